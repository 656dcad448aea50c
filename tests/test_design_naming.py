"""core.design.naming (left/right names) and the name-substituting mirror of core.design.mirror."""

from core.design.mirror import mirror_line, mirror_panel
from core.design.naming import mirror_axis, mirrored_name, side_of, swap_side
from core.design.types import Line, Panel


def test_mirrored_name():
    assert mirrored_name("sleeve_left") == "sleeve_right"
    assert mirrored_name("arm_left_front") == "arm_right_front"
    assert mirrored_name("front") is None and mirrored_name("sleeve_right") is None


def test_swap_side_both_ways():
    for a, b in (("wrist_left", "wrist_right"), ("arm_left_up", "arm_right_up")):
        assert swap_side(a) == b and swap_side(b) == a
    assert swap_side("neck_back") == "neck_back"


def test_side_of_follows_the_swap_rule():
    cases = {
        "sleeve_left": "left",
        "side_right": "right",
        "arm_left_front": "left",
        "arm_right_up": "right",
        "front": None,
        "neck_back": None,
        "left": None,
        "hem_left_right": "right",
    }
    for name, side in cases.items():
        assert side_of(name) == side, name
        # a name with a side swaps to the other side's name, a midline name to itself
        assert (swap_side(name) == name) == (side is None), name


def test_mirror_axis():
    assert [mirror_axis(a) for a in ("x", "+x", "-x", "y", "-z")] == ["-x", "-x", "x", "y", "-z"]


def test_mirror_line_and_panel_keep_their_type():
    line = Line("side_left", ["armpit_left", {"between": ["waist_left", "hip_left"], "t": 0.5}], role="seam")
    m = mirror_line(line)
    assert isinstance(m, Line) and m.name == "side_right" and m.role == "seam" and not m.closed
    assert m.points == ["armpit_right", {"between": ["waist_right", "hip_right"], "t": 0.5}]
    ring = Line(
        "cuff_left",
        [],
        True,
        "opening",
        {"through": "wrist_left", "normal": "x", "points": 12, "offset": 0.0, "named": {"cuff_under_left": 0.5}},
    )
    r = mirror_line(ring)
    assert r.ring["normal"] == "-x" and r.ring["handed"] == -1 and "cuff_under_right" in r.ring["named"]
    assert line.points[0] == "armpit_left"  # the source is not changed
    p = mirror_panel(Panel("sleeve_left", "elbow_left", "arm", {"axis": "x", "from": 1.0, "to": 1.2}))
    assert isinstance(p, Panel) and p.name == "sleeve_right" and p.seed == "elbow_right"
    assert p.ease["axis"] == "-x" and p.body_part == "arm"
