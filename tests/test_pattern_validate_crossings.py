"""Global injectivity (issue 30): a piece whose dart legs or sew line cross is counted and refused.

The pieces are built by hand: a 1 x 1 m sheet on the z = 0 plane with a dart slit from the
bottom edge up to (0.5, 0.5). Each side of the slit is moved by a shear of determinant 1 (no
triangle flips), so only the global check can see the legs cross.
"""

import numpy as np
import pytest

from core import workflows as wf
from core.errors import PatternError
from core.metrics import checks
from core.metrics.figures import key_figures, summary_line
from core.metrics.injectivity import crossing_pairs, dart_gaps, panel_crossings, segment_gaps
from core.metrics.pattern import pattern_report
from core.pattern.types import Pattern, PatternPanel, PatternSeam

N = 10  # grid cells per side; the slit runs along x = 0.5 from y = 0 to y = 0.5


def _sheet(cross: float = 0.0, intake: float = 0.1, name: str = "blouse.front"):
    """A sheet with a dart; ``cross`` (m): how far the right side's leg is pushed over the left one
    half way up the dart (0: a clean dart of ``intake`` at the mouth)."""
    g = np.linspace(0.0, 1.0, N + 1)
    X, Y = np.meshgrid(g, g, indexing="xy")
    xyz = np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]
    vid = np.arange(X.size).reshape(N + 1, N + 1)  # [row y, column x]
    mid, top = N // 2, N // 2  # the slit's column and the apex's row
    # the right side's copies of the slit's vertices below the apex
    copies = {int(vid[r, mid]): X.size + k for k, r in enumerate(range(top))}
    xyz = np.r_[xyz, xyz[list(copies)]]
    faces = []
    for r in range(N):
        for c in range(N):
            q = [vid[r, c], vid[r, c + 1], vid[r + 1, c + 1], vid[r + 1, c]]
            if c == mid and r < top:  # right of the slit: its copies
                q = [copies.get(int(v), int(v)) if k in (0, 3) else int(v) for k, v in enumerate(q)]
            faces += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    faces = np.array(faces, int)
    right = np.zeros(len(xyz), bool)
    right[X.size :] = True
    right[: X.size] = xyz[: X.size, 0] > 0.5 + 1e-9
    y = xyz[:, 1]
    w = intake * np.clip(1.0 - y / 0.5, 0.0, None)  # the wedge's width, 0 at and above the apex
    d = cross * np.where(y < 0.5, np.sin(np.pi * y / 0.5) ** 2, 0.0)
    uv = xyz[:, :2].copy()
    uv[:, 0] += np.where(right, 0.5 * w - d, -0.5 * w * (xyz[:, 0] <= 0.5 + 1e-9))
    leg_a = [int(vid[r, mid]) for r in range(top + 1)]  # left leg, mouth to apex
    leg_b = [copies[int(vid[r, mid])] for r in range(top)] + [int(vid[top, mid])]
    f = len(faces)
    panel = PatternPanel(
        name=name,
        garment="blouse",
        uv=uv,
        faces=faces,
        vertex_ids=np.arange(len(uv)),
        xyz=xyz,
        grain=np.array([0.0, 1.0]),
        target_weft=np.ones(f),
        target_warp=np.ones(f),
        achieved_weft=np.ones(f),
        achieved_warp=np.ones(f),
    )
    dart = PatternSeam("blouse.bust_dart_left", name, name, np.array(leg_b), np.array(leg_a))
    return Pattern(style="test", body={}, garments={"blouse": "upper"}, panels=[panel], seams=[dart])


def test_the_sheet_is_a_dart_and_flip_free():
    pat = _sheet(cross=0.12)
    assert pat.seams[0].kind == "dart"
    m = pattern_report(pat)
    assert m["flipped_triangles"] == 0 and m["collapsed_triangles"] == 0  # locally injective


def test_a_clean_dart_has_no_crossing_and_a_positive_gap():
    m = pattern_report(_sheet())
    assert m["crossings"] == 0 and m["crossing_sites"] == {}
    gap = m["darts"]["blouse.bust_dart_left"]
    assert gap["crossings"] == 0 and gap["min_gap_mm"] > 5.0
    checks.check_pattern(m)  # passes every check


def test_crossed_legs_are_counted_named_and_refused():
    """A crossing built on purpose: the right leg pushed 12 cm over the left one half way up."""
    pat = _sheet(cross=0.12)
    lm = {"bust_left": np.array([0.5, 0.3, 0.0]), "waist_left": np.array([0.5, -0.5, 0.0])}
    m = pattern_report(pat, lm)
    assert m["crossings"] == m["crossings_per_panel"]["blouse.front"] >= 1
    (site,) = m["crossing_sites"]["blouse.front"]
    assert site["between"] == ["dart blouse.bust_dart_left"] * 2 and site["near"] == "bust_left"
    assert m["darts"]["blouse.bust_dart_left"]["crossings"] >= 1
    assert m["darts"]["blouse.bust_dart_left"]["min_gap_mm"] == 0.0
    with pytest.raises(PatternError) as e:
        checks.check_pattern(m, checks.CHECKS)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("panel blouse.front: the legs of dart blouse.bust_dart_left cross")
    assert "near bust_left" in msg and "nothing written" in msg
    # the pipeline's measure refuses it and records nothing; a live preview in between shows the count
    with pytest.raises(PatternError, match="legs of dart"):
        wf.measure_pattern(pat, checks=checks.CHECKS)
    assert "metrics" not in pat.report
    pat.report["live"] = {"iterations": 3, "converged": False}
    assert wf.measure_pattern(pat, checks=checks.checks_for(pat))["crossings"] == m["crossings"]
    assert key_figures(pat)["crossings"] == m["crossings"]
    assert f"crossings {m['crossings']}," in summary_line(pat)


def test_legs_that_touch_count_as_a_crossing():
    """Pushed exactly onto each other half way up: a zero gap is not a positive one."""
    pat = _sheet(cross=0.05)  # the wedge is 5 cm wide half way up
    assert pattern_report(pat)["crossings"] >= 1


def test_a_sew_line_folded_over_another_stretch_is_named():
    """The sheet's right half pushed far over the left: the dart's leg crosses the sheet's own edge."""
    pat = _sheet(cross=0.9)
    sites = panel_crossings(pat, pat.panels[0])["sites"]
    assert any("boundary" in s["between"] and "dart blouse.bust_dart_left" in s["between"] for s in sites)
    with pytest.raises(PatternError, match="panel blouse.front: boundary crosses dart blouse.bust_dart_left"):
        checks.check_pattern(pattern_report(pat), ("crossings",))


def test_segment_gaps_and_pairs():
    a0, b0 = np.array([[0.0, 0.0]]), np.array([[1.0, 0.0]])
    assert segment_gaps(a0, b0, np.array([[0.5, -1.0]]), np.array([[0.5, 1.0]]))[0] == 0.0  # crossing
    assert segment_gaps(a0, b0, np.array([[2.0, 1.0]]), np.array([[2.0, 3.0]]))[0] == pytest.approx(np.sqrt(2))
    # a square's edges: adjacent ones share a vertex and never count; a figure eight crosses once
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    ring = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    assert len(crossing_pairs(sq, ring)) == 0
    eight = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float)
    assert crossing_pairs(eight, ring).tolist() == [[0, 2]]


def test_dart_gap_of_a_pattern_without_darts_is_empty():
    pat = _sheet()
    pat.seams = []
    assert dart_gaps(pat) == {}


def test_the_four_dart_blouse_is_cut_into_a_valid_piece_and_refused_without_the_gap_step(anny, tmp_path, monkeypatch):
    """On the real body (women:M): the template's bust and shoulder darts crossed (4 crossings, from the
    LSCM start on); the solver's gap step (core.pattern.optimizer.dart_gaps) keeps every dart's legs apart, and
    without it ``ease pattern`` refuses the piece in one line naming the darts and where on the body,
    and writes nothing."""
    from core.cli import main
    from core.design.templates import template_path

    prep = wf.prepare(template_path("blouse_four_darts"), body=anny)
    run = wf.reference(prep)
    m = run.pattern.report["metrics"]
    assert m["crossings"] == 0 and m["flipped_triangles"] == 0 and m["collapsed_triangles"] == 0
    assert all(g["min_gap_mm"] > 0 and g["crossings"] == 0 for g in m["darts"].values()), m["darts"]
    assert all(rec["leg_difference_mm"] <= 0.1 for rec in run.pattern.report["darts"].values())
    monkeypatch.setattr(
        "core.pattern.optimizer.dart_gaps.GapCorrection.correct", lambda self, base, U, prev=None, holder=None: U
    )
    out = tmp_path / "out"
    assert main(["pattern", str(template_path("blouse_four_darts")), "--out", str(out), "--quiet"]) == 2
    assert not out.exists()
    with pytest.raises(PatternError) as e:
        wf.reference(wf.prepare(template_path("blouse_four_darts"), body=anny))
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("panel blouse.front: the legs of dart blouse.")
    for dart in ("bust_dart_left", "bust_dart_right", "shoulder_dart_left", "shoulder_dart_right"):
        assert f"the legs of dart blouse.{dart} cross" in msg
    assert "near bust_left" in msg and "nothing written" in msg
