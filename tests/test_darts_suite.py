"""The generated dart suite (issue 30): every case is a valid pattern or a one-line refusal.

Cases: dart mouths along every seam and hem of the blouse's front and back and of the darted
skirt's pieces; apexes at the bust points, the shoulder blades, the seat, on a seam and off it;
intakes from 0 to beyond what a piece can take; two darts sharing a mouth, two darts crossing;
``"darts": "auto"`` on every template (placed darts are never refused).
Each is cut and solved on its design's body (the design's configuration). A valid pattern has 0
flipped, 0 collapsed and 0 crossing triangles or edges (the pipeline refuses every other one) and
its darts' legs sewn equal within 0.1 mm (:data:`LEGS_MM`); a refusal is an :class:`~core.errors.EaseError`
of one line. Never a traceback, never a tangled pattern. CI runs a seeded sample; ``pytest --full`` runs
every case.
"""

import pytest
from conftest import sample

from core import workflows as wf
from core.design.templates import TEMPLATES
from core.errors import EaseError

#: legs sewn equal within this (mm) on a valid pattern, a set intake's too (issue 30). A set intake, held
#: by the soft mouth term, left them up to 1.40 mm apart after the default 20 iterations where the
#: solver's gap step opened crossed legs (0.31 mm on a 20 mm neckline dart, 0.61 / 0.83 / 1.40 mm on
#: 20 mm side / shoulder / armhole darts) until every solve ended with its legs sewn equal
#: (core.pattern.optimizer.dart_gaps.equal_legs)
LEGS_MM = 0.1


def _blouse(panel, darts, keypoints=None):
    d = TEMPLATES["blouse_fitted"]()
    d["keypoints"].update(keypoints or {})
    for p in d["garments"][0]["panels"]:
        p["darts"] = darts if p["name"] == panel else []
    return d


def _skirt(panel, darts):
    d = TEMPLATES["skirt_darted"]()
    for p in d["garments"][0]["panels"]:
        p["darts"] = darts if p["name"] == panel else []
    return d


def _dart(name, line, apex, intake="auto", **kw):
    return {"name": name, "line": line, "apex": apex, "intake": intake, **kw}


#: the templates whose panels take darts: every template but the pleated ones (a dart may not cross a pleat's line)
AUTO_TEMPLATES = (
    "blouse_fitted",
    "blouse_four_darts",
    "dress",
    "dress_gradient",
    "jacket",
    "pants",
    "shirt_long_sleeve",
    "shorts",
    "skirt",
    "skirt_darted",
    "teaser_shirt_pants",
    "top_short_sleeve",
    "top_sleeveless",
)
SIDE_MID = {"side_mid_left": {"between": ["armhole_under_left", "hem_side_left"], "t": 0.5}}
CASES = (
    # the blouse front: a mouth on every line it touches, towards the bust point, intakes auto and set
    [
        (f"front {line} {intake}", "blouse", "front", [_dart("d_left", line, "bust_left", intake)], None)
        for line in ("side_left", "hem", "shoulder_left", "neckline", "armhole_left")
        for intake in ("auto", 0.02)
    ]
    # intakes from none to beyond what the piece can take (0 and 0.25 are refused by the design's check)
    + [
        (f"front side_left intake {w}", "blouse", "front", [_dart("d_left", "side_left", "bust_left", w)], None)
        for w in (0.0, 0.005, 0.08, 0.2, 0.25)
    ]
    # the back: towards the shoulder blade from the hem and the shoulder
    + [
        (f"back {line}", "blouse", "back", [_dart("d_left", line, "shoulder_blade_left", 0.015)], None)
        for line in ("hem", "shoulder_left")
    ]
    # an apex on a seam (the side seam's middle) from the hem, and a mouth at a seam's end
    + [
        (
            "front hem apex on the side seam",
            "blouse",
            "front",
            [_dart("d_left", "hem", "side_mid_left", 0.02)],
            SIDE_MID,
        ),
        (
            "front mouth at a seam end",
            "blouse",
            "front",
            [_dart("d_left", "side_left", "bust_left", at="armhole_under_left")],
            None,
        ),
    ]
    # two darts sharing a mouth, two darts crossing
    + [
        (
            "front two darts one mouth",
            "blouse",
            "front",
            [
                _dart("a_left", "hem", "bust_left", 0.02, at="hem_front"),
                _dart("b_left", "hem", "bust_left", 0.02, at="hem_front", apex_offset=0.04),
            ],
            None,
        ),
        (
            "front two darts crossing",
            "blouse",
            "front",
            [
                _dart("a_left", "side_left", "bust_left", 0.02, at="hem_side_left"),
                _dart("b_left", "hem", "armhole_under_left", 0.02, at="hem_front"),
            ],
            None,
        ),
    ]
    # the darted skirt: from the waist towards the seat, on the back and the front, and from the hem
    + [
        (f"skirt {panel} {line} {w}", "skirt", panel, [_dart("d_left", line, "seat_left", w)], None)
        for panel in ("back", "front")
        for line, w in (("waist", "auto"), ("waist", 0.02), ("hem", 0.02))
    ]
    # "darts": "auto" on every panel of templates that allow darts
    + [(f"auto darts {name}", "auto", name, [], None) for name in AUTO_TEMPLATES]
)


def _auto(name):
    """Template ``name`` with ``"darts": "auto"`` on every panel (core.cut.auto_darts places them)."""
    d = TEMPLATES[name]()
    for g in d["garments"]:
        for p in g["panels"]:
            p["darts"] = "auto"
    return d


def _design(case):
    _, kind, panel, darts, keypoints = case
    if kind == "auto":
        return _auto(panel)
    return _blouse(panel, darts, keypoints) if kind == "blouse" else _skirt(panel, darts)


@pytest.mark.parametrize("case", sample(CASES, 4, seed=30), ids=lambda c: c[0])
def test_a_dart_case_is_a_valid_pattern_or_a_one_line_refusal(case, anny):
    try:
        run = wf.reference(wf.prepare(_design(case), body=anny))
    except EaseError as exc:  # refused: one line, nothing else (anything else fails the test)
        # automatic darts are placed valid on every template (issue 30): never refused
        assert case[1] != "auto", (case[0], str(exc))
        msg = str(exc)
        assert msg and "\n" not in msg and "Traceback" not in msg, msg
        return
    m = run.pattern.report["metrics"]
    assert m["flipped_triangles"] == 0 and m["collapsed_triangles"] == 0 and m["crossings"] == 0, case[0]
    for name, rec in run.pattern.report.get("darts", {}).items():
        assert m["darts"][name]["crossings"] == 0 and m["darts"][name]["min_gap_mm"] > 0, (case[0], name)
        assert rec["leg_difference_mm"] <= LEGS_MM, (case[0], name, rec)


def test_the_suite_covers_what_the_issue_lists():
    names = [c[0] for c in CASES]
    lines = {"side_left", "hem", "shoulder_left", "neckline", "armhole_left"}
    assert lines <= {c[3][0]["line"] for c in CASES if c[1] == "blouse" and c[2] == "front"}
    assert {"shoulder_blade_left", "seat_left", "bust_left", "side_mid_left"} <= {
        d["apex"] for c in CASES for d in c[3]
    }
    assert sum(c[1] == "auto" for c in CASES) >= 5
    assert any("one mouth" in n for n in names) and any("crossing" in n for n in names)
    assert any(c[2] == "back" for c in CASES) and {0.0, 0.25} <= {d["intake"] for c in CASES for d in c[3]}
