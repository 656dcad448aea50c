"""Collapsed triangles: a known count on hand-made triangles, their sites, and the refusal."""

import numpy as np
import pytest

from core import workflows as wf
from core.errors import PatternError
from core.metrics import checks
from core.metrics.collapse import collapse, collapse_message, collapsed_mask
from core.metrics.pattern import pattern_report
from core.pattern.types import Pattern, PatternPanel

#: One right triangle on the body (metres, z = 0 plane), legs along the weft (x) and warp (y).
TRI = np.array([[0.0, 0.0], [0.02, 0.0], [0.0, 0.02]])


def _soup(cases, origin=(0.0, 0.0, 0.0)):
    """A panel of disjoint triangles: case ``(weft scale, warp scale, target weft, target warp)``
    gives a triangle whose pattern is the body triangle scaled by those factors (a negative scale mirrors it)."""
    uv, xyz, F, tw, tg = [], [], [], [], []
    for k, (sw, sg, cw, cg) in enumerate(cases):
        off = np.array([0.05 * k, 0.0])
        uv.append(TRI * [sw, sg] + off * 3)
        xyz.append(np.c_[TRI + off, np.zeros(3)] + origin)
        F.append([3 * k, 3 * k + 1, 3 * k + 2])
        tw.append(cw)
        tg.append(cg)
    return np.concatenate(uv), np.concatenate(xyz), np.array(F), np.array(tw, float), np.array(tg, float)


CASES = [
    (1.0, 1.0, 1.0, 1.0),  # as asked
    (0.6, 0.6, 1.0, 1.0),  # area 36 % of the body's, both scales above half: kept
    (0.45, 1.0, 1.0, 1.0),  # weft under half: collapsed (scale rule)
    (1.0, 0.4, 1.0, 1.0),  # warp under half: collapsed (scale rule)
    (0.3, 0.3, 1.0, 1.0),  # area 9 %: collapsed (area rule, and the scale rule)
    (0.7, 1.0, 1.5, 1.0),  # 0.7 where 1.5 was asked: under half its target, collapsed
    (1.5, 1.0, 1.5, 1.0),  # the same target reached: kept
    (1.2, 1.15, 2.2, 2.2),  # area 1.38 of 4.84 asked (29 %), scales 55 % and 52 %: kept
    (1.1, 1.0, 2.2, 2.2),  # area 1.1 of 4.84 (23 %): collapsed (area rule, warp 45 %)
    (-1.0, 1.0, 1.0, 1.0),  # mirrored: a flip, counted by flips, not as collapsed
]
COLLAPSED = [2, 3, 4, 5, 8]


def _pattern(cases=CASES, name="skirt.back", origin=(0.0, 0.0, 0.0), body=None):
    uv, xyz, F, tw, tg = _soup(cases, origin)
    p = PatternPanel(
        name=name,
        garment="skirt",
        uv=uv,
        faces=F,
        vertex_ids=np.arange(len(uv)),
        xyz=xyz,
        grain=np.array([0.0, 1.0]),
        target_weft=tw,
        target_warp=tg,
        achieved_weft=np.ones(len(F)),
        achieved_warp=np.ones(len(F)),
    )
    return Pattern(style="test", body=body or {}, garments={"skirt": "skirt"}, panels=[p], seams=[])


def test_collapsed_mask_known_triangles():
    uv, xyz, F, tw, tg = _soup(CASES)
    assert np.nonzero(collapsed_mask(uv, xyz, F, np.array([0.0, 1.0]), tw, tg))[0].tolist() == COLLAPSED


def test_collapse_counts_by_rule_and_beside_flips():
    m = pattern_report(_pattern())
    assert m["flipped_triangles"] == 1  # the mirrored one, and only there
    assert m["collapsed_triangles"] == len(COLLAPSED)
    assert m["collapsed_per_panel"] == {"skirt.back": len(COLLAPSED)}
    per = collapse(_pattern())["skirt.back"]
    assert per["area"] == 2 and per["scale_only"] == 3  # cases 4 and 8 by area; 2, 3, 5 by a scale alone


def test_collapse_sites_name_the_nearest_landmark():
    # the soup lies along x from 0 to 0.47 m; two landmarks split it
    landmarks = {"seat_left": np.array([0.0, 0.0, 0.0]), "hip_left": np.array([0.5, 0.0, 0.0])}
    per = collapse(_pattern(), landmarks)["skirt.back"]
    near = {s["near"]: s["count"] for s in per["sites"]}
    # triangle k's centroid is at x = 0.05 k + 0.0067: 2, 3, 4 are nearer the seat, 5, 8 the hip
    assert near == {"seat_left": 3, "hip_left": 2}
    seat = next(s for s in per["sites"] if s["near"] == "seat_left")
    assert seat["centroid"] == pytest.approx([0.15 + 0.02 / 3, 0.02 / 3, 0.0], abs=1e-4)
    assert seat["distance_mm"] == pytest.approx(1000 * np.hypot(0.15 + 0.02 / 3, 0.02 / 3), abs=0.1)


def test_collapsed_pattern_is_refused_naming_panel_and_place():
    landmarks = {"gluteal_cleft": np.array([0.0, 0.08, -0.09])}
    m = pattern_report(_pattern(origin=(0.0, 0.08, -0.09)), landmarks)
    with pytest.raises(PatternError) as e:
        checks.check_pattern(m, ("collapsed",))
    msg = str(e.value)
    assert msg.startswith("panel skirt.back: 5 collapsed triangles near gluteal_cleft (")
    assert " m)" in msg and "nothing written" in msg
    checks.check_pattern(pattern_report(_pattern(CASES[:2])), ("flipped", "collapsed"))  # a clean one passes


def test_the_workflow_check_refuses_a_collapse():
    pat = _pattern([c for c in CASES if c[0] > 0])  # no flip: only the collapse can refuse it
    with pytest.raises(PatternError, match=r"panel skirt.back: 5 collapsed triangles at \("):
        wf.measure_pattern(pat, checks=("flipped", "collapsed"))
    assert "metrics" not in pat.report  # nothing recorded on refusal
    m = wf.measure_pattern(pat, checks=("flipped",))
    assert m["collapsed_triangles"] == 5 and pat.report["metrics"] is m


def test_the_pipeline_refuses_a_collapse_by_default_but_not_a_preview_in_between():
    assert checks.REFUSED == ("flipped", "collapsed", "crossings")
    pat = _pattern([c for c in CASES if c[0] > 0])
    with pytest.raises(PatternError, match="5 collapsed triangles"):
        wf.measure_pattern(pat)
    pat.report["live"] = {"iterations": 3, "converged": False}  # a live preview still converging: shown
    assert wf.measure_pattern(pat)["collapsed_triangles"] == 5
    pat.report["live"]["converged"] = True  # converged: a pattern like any other
    with pytest.raises(PatternError, match="5 collapsed triangles"):
        wf.measure_pattern(pat)


def test_flips_are_refused_with_the_panel_named():
    with pytest.raises(PatternError, match=r"1 flipped triangles \(skirt.back \(1\)\)"):
        checks.check_pattern(pattern_report(_pattern()), ("flipped",))


def test_unknown_check_name():
    with pytest.raises(ValueError, match="unknown pattern checks"):
        checks.check_pattern(pattern_report(_pattern(CASES[:1])), ("wrinkled",))


def test_collapse_message_lists_every_site():
    per = {
        "a": {
            "count": 3,
            "sites": [
                {"near": "bust_left", "count": 2, "centroid": [0.1, -0.14, 0.36]},
                {"near": "bust_right", "count": 1, "centroid": [-0.1, -0.14, 0.36]},
            ],
        },
        "b": {"count": 0, "sites": []},
    }
    assert collapse_message(per) == (
        "panel a: 3 collapsed triangles (2 near bust_left (0.100, -0.140, 0.360 m); "
        "1 near bust_right (-0.100, -0.140, 0.360 m))"
    )
