"""core.metrics.strains: one pass of per-triangle strains that every reference-body figure reads."""

import numpy as np

from core.metrics import pattern as M
from core.metrics.collapse import collapse
from core.metrics.regions import region_compliance
from core.metrics.strains import panel_strain, pattern_strains
from core.pattern.types import Pattern, PatternPanel


def _pattern():
    rng = np.random.default_rng(3)
    xs, ys = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 5))
    uv = np.c_[xs.ravel(), ys.ravel()]
    F = np.array(
        [(j * 6 + i, j * 6 + i + 1, (j + 1) * 6 + i + 1) for j in range(4) for i in range(5)]
        + [(j * 6 + i, (j + 1) * 6 + i + 1, (j + 1) * 6 + i) for j in range(4) for i in range(5)]
    )
    panels = []
    for k, g in enumerate(("a", "b")):
        xyz = np.c_[uv[:, 0] / 1.2, 0.05 * rng.standard_normal(len(uv)), uv[:, 1] / (1.0 + 0.1 * k)]
        f = len(F)
        panels.append(
            PatternPanel(
                name=f"{g}.p",
                garment=g,
                uv=uv + rng.normal(0, 0.01, uv.shape),
                faces=F,
                vertex_ids=np.arange(len(uv)),
                xyz=xyz,
                grain=np.array([0.0, 1.0]),
                target_weft=np.full(f, 1.2),
                target_warp=np.ones(f),
                achieved_weft=np.ones(f),
                achieved_warp=np.ones(f),
            )
        )
    return Pattern(style="s", body={}, garments={"a": "upper", "b": "lower"}, panels=panels, seams=[])


def test_panel_strain_is_the_scales_and_areas():
    p = _pattern().panels[0]
    s = panel_strain(p)
    rw, rg, sh = M.scales(p.uv, p.xyz, p.faces, p.grain)
    assert np.array_equal(s.weft, rw) and np.array_equal(s.warp, rg) and np.array_equal(s.shear, sh)
    assert np.array_equal(s.area, M.triangle_areas(p.xyz, p.faces)) and s.area.shape == (len(p.faces),)


def test_figures_read_from_strains_equal_the_recomputed_ones():
    pat = _pattern()
    strains = pattern_strains(pat)
    assert set(strains) == {"a.p", "b.p"}
    for g in (None, "a", "b"):
        assert M.ease_compliance(pat, g, strains=strains) == M.ease_compliance(pat, g)
    lm = {"bust_left": np.array([0.4, 0.0, 0.4])}
    assert region_compliance(pat, lm, strains=strains) == region_compliance(pat, lm)
    assert collapse(pat, lm, strains=strains) == collapse(pat, lm)
    # a body given explicitly is measured on it, not read from the strains of the panels' own xyz
    other = {p.name: p.xyz * 1.1 for p in pat.panels}
    assert M.ease_compliance(pat, xyz=other, strains=strains) == M.ease_compliance(pat, xyz=other)


def test_a_pieces_scales_are_computed_once_and_follow_its_edits():
    p = _pattern().panels[0]
    first = p.scales()
    memo = p._scales
    again = p.scales()
    assert p._scales is memo  # read back, not recomputed
    assert all(np.array_equal(a, b) for a, b in zip(first, again))
    again[0][:] = 0.0  # a caller's array is its own
    assert np.array_equal(p.scales()[0], first[0])
    p.uv[3] += 0.05  # an edit in place: recomputed
    moved = p.scales()
    assert all(np.array_equal(a, b) for a, b in zip(moved, M.scales(p.uv, p.xyz, p.faces, p.grain)))
    assert not np.array_equal(moved[0], first[0])
    assert np.array_equal(panel_strain(p).weft, moved[0])
