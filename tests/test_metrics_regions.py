"""Region report: compliance near named landmarks, on a synthetic body with a known answer,
and the landmarks it uses on Anny; warp and collapse in the summary and the add-on's figures."""

import numpy as np
import pytest

from core import workflows as wf
from core.geom.mesh import row_norm
from core.metrics.pattern import pattern_report
from core.metrics.regions import REGION_LANDMARKS, body_landmarks, region_compliance
from core.pattern.types import Pattern, PatternPanel


def _sheet(n=41):
    """A 1 m x 1 m flat "body" (z = 0) whose pattern has weft scale 1.2 left of x = 0.5 and 1.0 right of
    it, warp scale 0.9 everywhere, against targets 1: compliance 20 % (signed +20) on the left, 0 on
    the right, warp deviation 10 % (signed -10) everywhere."""
    xs = np.linspace(0.0, 1.0, n)  # a grid line at x = 0.5: the scale is piecewise constant
    X, Y = np.meshgrid(xs, xs)
    xyz = np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]
    u = np.where(xyz[:, 0] < 0.5, 1.2 * xyz[:, 0], 0.6 + (xyz[:, 0] - 0.5))
    uv = np.c_[u, 0.9 * xyz[:, 1]]
    F = []
    for j in range(n - 1):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i
            F += [(a, b, c), (a, c, d)]
    F = np.array(F)
    f = len(F)
    p = PatternPanel(
        name="front",
        garment="top",
        uv=uv,
        faces=F,
        vertex_ids=np.arange(len(uv)),
        xyz=xyz,
        grain=np.array([0.0, 1.0]),
        target_weft=np.ones(f),
        target_warp=np.ones(f),
        achieved_weft=np.ones(f),
        achieved_warp=np.ones(f),
    )
    return Pattern(style="sheet", body={}, garments={"top": "top"}, panels=[p], seams=[])


def test_region_compliance_known_answer():
    pat = _sheet()
    lm = {
        "bust_left": np.array([0.25, 0.5, 0.0]),
        "bust_right": np.array([0.75, 0.5, 0.0]),
        "seat_left": np.array([0.25, 0.5, 0.3]),  # 30 cm off the sheet: nothing within 6 cm
        "knee_left": np.array([0.5, 0.5, 0.0]),
    }  # not a region landmark: not reported by default
    r = region_compliance(pat, lm, radius=0.2)
    assert set(r) == {"bust_left", "bust_right"}
    left, right = r["bust_left"], r["bust_right"]
    assert left["mean"] == pytest.approx(20.0) and left["signed"] == pytest.approx(20.0)
    assert left["p95"] == pytest.approx(20.0)
    assert right["mean"] == pytest.approx(0.0, abs=1e-9)
    for v in (left, right):
        assert v["warp_mean"] == pytest.approx(10.0) and v["warp_signed"] == pytest.approx(-10.0)
        assert v["shear_p95"] == pytest.approx(0.0, abs=1e-6)
        assert v["area"] == pytest.approx(np.pi * 0.2**2, rel=0.05)  # the disc, to the mesh's resolution
    # straddling x = 0.5: half the disc at 20 %, half at 0 (the centre column of triangles split evenly)
    mid = region_compliance(pat, lm, radius=0.2, names=["knee_left"])["knee_left"]
    assert mid["mean"] == pytest.approx(10.0, abs=0.5)
    assert region_compliance(pat, lm, radius=0.2, garment="other") == {}


def test_pattern_report_carries_regions_per_garment():
    lm = {"bust_left": np.array([0.25, 0.5, 0.0])}
    m = pattern_report(_sheet(), lm)
    assert m["regions"]["bust_left"]["mean"] == pytest.approx(20.0)  # default radius 6 cm: inside the left half
    assert m["garments"]["top"]["regions"]["bust_left"] == m["regions"]["bust_left"]
    assert pattern_report(_sheet())["regions"] == {}  # no landmarks, no regions


def test_region_landmarks_on_anny(anny, anny_reference):
    V, _ = anny_reference
    P = {
        n: anny.landmark_position(n, V)
        for n in REGION_LANDMARKS + ("gluteal_cleft", "waist_back", "crotch", "armpit_left", "bust_left")
    }
    for side, sx in (("left", 1), ("right", -1)):
        blade, seat = P[f"shoulder_blade_{side}"], P[f"seat_{side}"]
        assert sx * blade[0] > 0.03 and sx * seat[0] > 0.02  # on its own side
        assert blade[1] > 0.05 and seat[1] > 0.05  # on the back (the body faces -Y)
        assert P["waist_back"][2] < blade[2] < P["armpit_left"][2] + 0.06
        assert P["crotch"][2] < seat[2] < P["waist_back"][2]
    # symmetric, and the cleft on the midline, in front of the seat prominences
    assert P["shoulder_blade_left"] == pytest.approx(P["shoulder_blade_right"] * [-1, 1, 1], abs=2e-3)
    assert P["seat_left"] == pytest.approx(P["seat_right"] * [-1, 1, 1], abs=2e-3)
    assert abs(P["gluteal_cleft"][0]) < 1e-3 and P["gluteal_cleft"][1] < P["seat_left"][1]


def test_body_landmarks_of_a_pattern(anny):
    pat = _sheet()
    assert body_landmarks(pat) == {}  # a synthetic pattern names no body
    pat.body = {"model": "anny", "shape": None, "pose": None}
    lm = body_landmarks(pat, anny)
    assert set(REGION_LANDMARKS) <= set(lm)
    assert lm["bust_left"] == pytest.approx(anny.landmark_position("bust_left", anny.vertices(None, None)))
    pat.body = {"model": "/nonexistent/body.obj"}
    assert body_landmarks(pat) == {}


def test_summary_and_figures_show_warp_and_collapse():
    pat = _sheet()
    wf.measure_pattern(pat)
    run = wf.PatternRun(pat, wf.pattern_figures(pat), {"optimize": 0.1})
    line = wf.summary(run)
    assert "ease compliance 10.00" in line  # half the sheet at 20 %
    assert "(warp 10.00 %, signed -10.00 %; shear p95 0.0°)" in line
    assert "flipped 0, collapsed 0" in line
    assert run.figures["warp deviation mean %"] == 10.0 and run.figures["warp deviation signed %"] == -10.0
    assert run.figures["collapsed"] == 0
    pat.report["metrics"]["regions"] = region_compliance(pat, {"bust_left": np.array([0.25, 0.5, 0.0])})
    assert "worst region bust_left 20.00 % (signed +20.00 %, warp 10.00 %" in wf.summary(run)


def test_addon_key_figures_show_warp_collapse_and_regions(addon):
    pat = _sheet()
    pat.report["metrics"] = pattern_report(pat, {"bust_left": np.array([0.25, 0.5, 0.0])})
    fig = addon("data").key_figures(pat)
    assert fig["warp deviation mean %"] == pytest.approx(10.0)
    assert fig["warp deviation signed %"] == pytest.approx(-10.0)
    assert fig["collapsed triangles"] == 0 and fig["flipped triangles"] == 0
    assert fig["bust left % (weft / warp)"] == "20.00 / 10.00"


def _tilted():
    """The sheet tilted out of the xy plane (z = y), a quarter of it: distances to a landmark depend on z."""
    pat = _sheet(31)
    p = pat.panels[0]
    p.xyz = 0.5 * np.c_[p.xyz[:, 0], p.xyz[:, 1], p.xyz[:, 1]]
    return pat


def test_region_rows_are_the_rows_within_the_radius():
    # the report measures only the rows within the radius along z: the same rows as the whole distance test
    pat = _tilted()
    p = pat.panels[0]
    cen = (p.xyz[p.faces[:, 0]] + p.xyz[p.faces[:, 1]] + p.xyz[p.faces[:, 2]]) / 3.0
    rng = np.random.default_rng(5)
    c = cen[200]
    # landmarks whose radius passes through a centroid, along z and across it
    lms = {
        "bust_left": np.array([0.25, 0.25, 0.25]),
        "bust_right": c + np.array([0.0, 0.0, 0.05]),
        "seat_left": c + np.array([0.03, 0.04, 0.0]),
    }
    lms.update({f"extra_{i}": rng.uniform(0.0, 0.5, 3) for i in range(3)})
    for radius in (0.05, 0.06, 0.1):
        got = region_compliance(pat, lms, radius=radius, names=None)
        for name, lm in lms.items():
            n = int(np.sum(row_norm(cen - lm) <= radius))
            assert got.get(name, {"n": 0})["n"] == n, (name, radius)


def test_one_garment_report_copies_its_overall_figures():
    pat = _tilted()
    m = pattern_report(pat, {"bust_left": np.array([0.25, 0.25, 0.25])})
    g = m["garments"]["top"]
    assert g == {"compliance": m["compliance"], "seams": m["seams"], "regions": m["regions"]}
    assert g["regions"] is not m["regions"] and g["regions"]["bust_left"] is not m["regions"]["bust_left"]
    g["regions"]["bust_left"]["mean"] = -1.0
    assert m["regions"]["bust_left"]["mean"] != -1.0
