"""SPEC pattern metrics on hand-made cases with known values."""

import numpy as np
import pytest

from core.metrics import pattern as M
from core.pattern.types import Pattern, PatternPanel, PatternSeam


def _square(nx=4, ny=3):
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    uv = np.c_[xs.ravel(), ys.ravel()]
    F = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i
            F += [(a, b, c), (a, c, d)]
    return uv, np.array(F)


def _panel(name, uv, xyz, F, target=1.0):
    f = len(F)
    rw, rg, _ = M.scales(uv, xyz, F, [0.0, 1.0])
    return PatternPanel(
        name=name,
        garment="g",
        uv=uv,
        faces=F,
        vertex_ids=np.arange(len(uv)),
        xyz=xyz,
        grain=np.array([0.0, 1.0]),
        target_weft=np.full(f, target),
        target_warp=np.ones(f),
        achieved_weft=rw,
        achieved_warp=rg,
    )


def test_scales_of_an_affine_map():
    uv, F = _square()
    # body = pattern shrunk by 1/1.25 along the weft (x), 1/1.1 along the warp, lifted into 3D
    xyz = np.c_[uv[:, 0] / 1.25, np.zeros(len(uv)), uv[:, 1] / 1.1]
    rw, rg, shear = M.scales(uv, xyz, F, [0.0, 1.0])
    assert np.allclose(rw, 1.25) and np.allclose(rg, 1.1) and np.allclose(shear, 0.0, atol=1e-6)
    r_weft, r_warp = M.required_stretch(uv, xyz, F, [0.0, 1.0])
    assert np.allclose(r_weft, 0.8)


def test_shear_angle():
    uv, F = _square()
    t = np.tan(np.radians(10.0))
    xyz = np.c_[uv[:, 0] + t * uv[:, 1], np.zeros(len(uv)), uv[:, 1]]
    _, _, shear = M.scales(uv, xyz, F, [0.0, 1.0])
    assert np.allclose(shear, 10.0, atol=1e-6)


def test_grain_rotation_is_respected():
    uv, F = _square()
    xyz = np.c_[uv[:, 0] / 1.5, np.zeros(len(uv)), uv[:, 1]]
    # grain along +x: the weft is then -y (scale 1), the warp x (scale 1.5)
    rw, rg, _ = M.scales(uv, xyz, F, [1.0, 0.0])
    assert np.allclose(rw, 1.0) and np.allclose(rg, 1.5)


def test_compliance_and_weighting():
    uv, F = _square()
    xyz = np.c_[uv[:, 0] / 1.2, np.zeros(len(uv)), uv[:, 1]]
    p = _panel("a", uv, xyz, F, target=1.0)
    pat = Pattern(style="s", body={}, garments={"g": "upper"}, panels=[p], seams=[])
    c = M.ease_compliance(pat)
    assert c["mean"] == pytest.approx(20.0) and c["std"] == pytest.approx(0.0, abs=1e-9)
    assert c["shear_p95"] == pytest.approx(0.0, abs=1e-6)
    s = M.weighted_stats(np.array([0.0, 10.0]), np.array([3.0, 1.0]))
    assert s["mean"] == pytest.approx(2.5) and s["std"] == pytest.approx(np.sqrt(18.75))


def test_compliance_of_a_panel_subset():
    uv, F = _square()
    loose = _panel("a", uv, np.c_[uv[:, 0] / 1.2, np.zeros(len(uv)), uv[:, 1]], F, target=1.0)
    exact = _panel("b", uv, np.c_[uv[:, 0], np.zeros(len(uv)), uv[:, 1]], F, target=1.0)
    pat = Pattern(style="s", body={}, garments={"g": "upper"}, panels=[loose, exact], seams=[])
    assert M.ease_compliance(pat)["mean"] == pytest.approx(20.0 / 2.2)  # weighted by 3D area (1/1.2 and 1)
    assert M.ease_compliance(pat, panels=["a"])["mean"] == pytest.approx(20.0)
    assert M.ease_compliance(pat, panels=["b"])["mean"] == pytest.approx(0.0, abs=1e-9)
    assert M.ease_compliance(pat, panels=[]) == {}


def test_seam_mismatch_percent_and_mm():
    uv, F = _square()
    xyz = np.c_[uv[:, 0], np.zeros(len(uv)), uv[:, 1]]
    a = _panel("a", uv, xyz, F)
    b = _panel("b", uv * np.array([1.0, 1.02]), xyz, F)  # b's left edge 2 % longer
    left = np.array([0, 4, 8])
    pat = Pattern(
        style="s", body={}, garments={"g": "upper"}, panels=[a, b], seams=[PatternSeam("side", "a", "b", left, left)]
    )
    sm = M.seam_mismatch(pat)
    assert sm["mean"] == pytest.approx(100 * 0.02 / 1.01)
    assert sm["max_mm"] == pytest.approx(20.0)
    assert sm["gathered"] == {}


def test_gathered_seams_are_listed_not_counted_as_mismatch():
    uv, F = _square()
    xyz = np.c_[uv[:, 0], np.zeros(len(uv)), uv[:, 1]]
    a = _panel("a", uv, xyz, F)
    b = _panel("b", uv * np.array([1.0, 1.5]), xyz, F)  # b's left edge half as long again: gathered into a's
    left, right = np.array([0, 4, 8]), np.array([2, 6, 10])
    pat = Pattern(
        style="s",
        body={},
        garments={"g": "upper"},
        panels=[a, b],
        seams=[PatternSeam("cap", "a", "b", left, left, gathered=True), PatternSeam("side", "a", "b", right, right)],
    )
    sm = M.seam_mismatch(pat)
    assert sm["n"] == 1 and set(sm["per_seam"]) == {"side"}
    assert sm["gathered"] == {"cap": pytest.approx(1.5)}


def test_residual_stretch_area_fraction():
    uv, F = _square(nx=3, ny=2)  # 4 equal triangles: two columns
    xyz = np.c_[uv[:, 0], np.zeros(len(uv)), uv[:, 1]].astype(float)
    p = _panel("a", uv, xyz, F)
    pat = Pattern(style="s", body={}, garments={"g": "upper"}, panels=[p], seams=[])
    posed = xyz.copy()
    posed[:, 0] = np.where(uv[:, 0] > 0.75, 0.5 + (uv[:, 0] - 0.5) * 1.3, uv[:, 0])  # right column 30 % wider
    # areas are measured on the posed body: 0.65 of 1.15
    assert M.residual_stretch(pat, {"a": posed}, 1.10) == pytest.approx(100 * 0.65 / 1.15)
    assert M.residual_stretch(pat, {"a": xyz}, 1.10) == 0.0
    # along the warp: the widened column has no warp stretch; a body 30 % longer along the grain has it everywhere
    assert M.residual_stretch(pat, {"a": posed}, 1.10, direction="warp") == 0.0
    longer = xyz.copy()
    longer[:, 2] *= 1.3
    assert M.residual_stretch(pat, {"a": longer}, 1.10, direction="warp") == pytest.approx(100.0)
    assert M.residual_stretch(pat, {"a": longer}, 1.10) == 0.0
    with pytest.raises(ValueError, match="direction"):
        M.residual_stretch(pat, {"a": xyz}, 1.10, direction="bias")


def test_flips():
    uv, F = _square()
    assert M.flipped_count(uv, F) == 0
    bad = uv.copy()
    bad[5] = [0.9, 0.9]  # drag an interior vertex across its neighbours
    assert M.flipped_count(bad, F) > 0
    assert M.flipped_count(uv, F[:, ::-1]) == 0  # the majority sets the orientation
