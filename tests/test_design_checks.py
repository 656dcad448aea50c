"""core.design.checks and core.design.parser: field checks return normalised values, errors name the field."""

import pytest

from core.body.model import POSE_PRESETS, SurfacePoint
from core.body.sizes import SIZES
from core.design.checks import (
    check_ease,
    check_keypoint,
    check_name,
    check_number,
    check_parameter_value,
    parameter_value,
)
from core.design.parser import parse_design
from core.design.spec import CutLine, CutSpec, GarmentSpec, PanelSpec
from core.design.types import Parameter
from core.errors import DesignError


def _path(fn, *args):
    with pytest.raises(DesignError) as e:
        fn(*args)
    return e.value.path


def test_field_checks():
    assert check_number("a", 3) == 3.0 and isinstance(check_number("a", 3), float)
    assert _path(check_number, "x.y", float("nan")) == "x.y"
    assert _path(check_name, "keypoints.1a", "1a") == "keypoints.1a"
    assert _path(check_parameter_value, "parameters.t", "placement", 1.5) == "parameters.t"
    params = {"t": Parameter("t", 0.25, "placement")}
    kp = check_keypoint("keypoints.k", {"between": ["a", "b"], "t": "$t"}, params)
    assert kp == {"between": ["a", "b"], "t": "$t"} and parameter_value(kp["t"], params) == 0.25
    assert check_keypoint("keypoints.k", "neck_front", params) == {"landmark": "neck_front"}
    assert _path(check_keypoint, "keypoints.k", {"between": ["a", "b"], "t": "$u"}, params) == "keypoints.k.t"
    assert check_ease("e", 1.5, {}) == {"value": 1.5}
    assert _path(check_ease, "panels[0].ease", {"from": 1.0, "to": 9.0, "axis": "z"}, {}) == "panels[0].ease.to"


def _design(**body):
    return {
        "format": "ease-design",
        "version": 1,
        "name": "t",
        "body": body,
        "garments": [{"name": "g", "kind": "upper", "panels": [{"name": "p", "seed": "navel"}]}],
    }


def test_body_sizes_and_poses_come_from_the_body_stage():
    for s in SIZES:
        assert parse_design(_design(shape=s)).body["shape"] == s
    for p in POSE_PRESETS:
        assert parse_design(_design(pose=p)).body["pose"] == p
    assert _path(parse_design, _design(shape="XXL")) == "body.shape"
    assert _path(parse_design, _design(pose="Q")) == "body.pose"


def test_cut_spec_is_plain_data():
    sp = SurfacePoint(3, (1.0, 0.0, 0.0))
    spec = CutSpec(
        lines=[CutLine("g.hem", [sp, sp, sp], closed=True, role="opening")],
        panels=[PanelSpec("g.p", "g", sp)],
        garments=[GarmentSpec("g", "upper", "g.hem")],
    )
    assert spec.refine_edge_length == 0.01 and not spec.skirt and spec.materials == {} and spec.body == {}
    assert spec.panels[0].body_part == "torso" and spec.lines[0].garment is None


def test_named_lists():
    d = _design()
    d["garments"].append(dict(d["garments"][0]))
    assert _path(parse_design, d) == "garments[1].name"
    d = _design()
    d["garments"][0]["panels"] = []
    with pytest.raises(DesignError, match="expected a non-empty list of panels"):
        parse_design(d)
    d = _design()
    d["lines"] = {"a": 1}
    with pytest.raises(DesignError, match="^lines: expected a list of lines"):
        parse_design(d)
