"""Design format, validation (JSON paths), keypoint resolution, mirroring and ease fields.

Resolution runs on the real default body (Anny). Ease fields are checked on a
cut made directly from body triangles (no cutting engine needed here).
"""

import json
import math

import numpy as np
import pytest
import scipy.sparse as sp

from core.cut.types import GarmentCut, Panel
from core.design import Resolver, apply_ease, load_design, resolve, save_design
from core.design.mirror import face_symmetry, mirror_surface_point
from core.design.naming import mirrored_name, swap_side
from core.design.templates import TEMPLATE_DIR, TEMPLATES, template
from core.errors import DesignError


@pytest.fixture(scope="module")
def body(anny):
    return anny


@pytest.fixture(scope="module")
def ref(body):
    return np.asarray(body.vertices(), dtype=float)


def shirt():
    return TEMPLATES["shirt_long_sleeve"]()


def error_of(obj):
    with pytest.raises(DesignError) as exc:
        load_design(obj)
    return exc.value


# ------------------------------------------------------------------ format


@pytest.mark.parametrize("name", list(TEMPLATES))
def test_template_round_trip(name, tmp_path):
    d = load_design(TEMPLATES[name]())
    again = load_design(d.to_json())
    assert again.to_json() == d.to_json()
    p = save_design(d, tmp_path / f"{name}.json")
    assert load_design(p).to_json() == d.to_json()
    assert load_design(p.read_text()).to_json() == d.to_json()


def test_template_files_are_current():
    for name, build in TEMPLATES.items():
        path = TEMPLATE_DIR / f"{name}.json"
        assert path.is_file(), f"{path} missing: run core.design.templates.write_templates()"
        on_disk = json.loads(path.read_text())
        assert on_disk == load_design(build()).to_json(), f"{path} is stale: rewrite with write_templates()"


def test_bad_ease_value_names_the_json_path():
    d = shirt()
    d["garments"][0]["panels"][2]["ease"] = {"value": 7}
    e = error_of(d)
    assert e.path == "garments[0].panels[2].ease.value"
    assert str(e) == "garments[0].panels[2].ease.value: panel 'sleeve_front_left': expected a number in 0.8..4.0, got 7"


@pytest.mark.parametrize(
    "ease, path",
    [
        ({"value": float("nan")}, "garments[0].panels[1].ease.value"),
        ({"value": 0.2}, "garments[0].panels[1].ease.value"),
        ({"value": "loose"}, "garments[0].panels[1].ease.value"),
        ({"from": 1.0, "to": 5.0, "axis": "z"}, "garments[0].panels[1].ease.to"),
        ({"from": 1.0, "to": 1.5}, "garments[0].panels[1].ease"),
        ({"from": 1.0, "to": 1.5, "axis": "w"}, "garments[0].panels[1].ease.axis"),
        ({"per_triangle": {"values": [1.0, 4.5]}}, "garments[0].panels[1].ease.per_triangle.values[1]"),
        (
            {"per_triangle": {"triangles": [1], "values": [1.0, 1.2]}},
            "garments[0].panels[1].ease.per_triangle.triangles",
        ),
        ({"per_triangle": {"values": [float("inf")]}}, "garments[0].panels[1].ease.per_triangle.values[0]"),
        ({"mystery": 1}, "garments[0].panels[1].ease"),
    ],
)
def test_bad_ease_fields(ease, path):
    d = shirt()
    d["garments"][0]["panels"][1]["ease"] = ease
    assert error_of(d).path == path


def _set(d, dotted, value):
    keys = dotted.split(".")
    node = d
    for k in keys[:-1]:
        node = node[int(k)] if isinstance(node, list) else node[k]
    last = keys[-1]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value


@pytest.mark.parametrize(
    "where, value, path",
    [
        ("format", "ease-pattern", "format"),
        ("version", 2, "version"),
        ("name", "", "name"),
        ("body.shape", "XXL", "body.shape"),
        ("body.pose", "P9", "body.pose"),
        ("materials.eps_weft", 0.9, "materials.eps_weft"),
        ("materials.eps_warp", "stiff", "materials.eps_warp"),
        ("materials.gathered", "armhole_left", "materials.gathered"),
        ("materials.gathered", ["armhole_lfet"], "materials.gathered[0]"),
        ("materials.gathered", ["arm hole"], "materials.gathered[0]"),
        ("materials.gather_above", 0.0, "materials.gather_above"),
        ("materials.gather_above", "often", "materials.gather_above"),
        ("parameters.sleeve_length", {"value": -0.1, "kind": "length"}, "parameters.sleeve_length.value"),
        ("parameters.sleeve_length", {"value": 0.5, "kind": "length", "max": 0.45}, "parameters.sleeve_length.value"),
        ("parameters.armhole_drop", {"value": 0.03, "kind": "wobble"}, "parameters.armhole_drop.kind"),
        ("keypoints.chest_front", {"between": ["neck_front", "waist_front"], "t": 1.5}, "keypoints.chest_front.t"),
        ("keypoints.chest_front", {"between": ["neck_front"], "t": 0.5}, "keypoints.chest_front.between"),
        ("keypoints.chest_front", {"between": ["neck_front", "waist_front"], "t": "$nope"}, "keypoints.chest_front.t"),
        (
            "keypoints.chest_front",
            {"between": ["neck_front", "waist_front"], "t": "$sleeve_length"},
            "keypoints.chest_front.t",
        ),
        ("keypoints.chest_front", {"triangle": 3, "bary": [0.5, 0.6, 0.2]}, "keypoints.chest_front.bary"),
        ("keypoints.chest_front", {"triangle": -1, "bary": [1, 0, 0]}, "keypoints.chest_front.triangle"),
        ("keypoints.chest_front", {"landmark": "neck_front", "triangle": 1}, "keypoints.chest_front"),
        (
            "keypoints.armhole_under_left",
            {"trace": {"from": "armpit_left", "along": "tail", "length": 0.1}},
            "keypoints.armhole_under_left.trace.along",
        ),
        (
            "keypoints.armhole_under_left",
            {"trace": {"from": "armpit_left", "along": "arm_left"}},
            "keypoints.armhole_under_left.trace.length",
        ),
        ("garments.0.kind", "hat", "garments[0].kind"),
        ("garments.0.pin", "collar", "garments[0].pin"),
        ("garments.0.lines.0.role", "glue", "garments[0].lines[0].role"),
        ("garments.0.lines.0.points", ["neck_front", "neck_back"], "garments[0].lines[0].points"),
        ("garments.0.lines.0.points", ["neck_front", 3, "neck_back"], "garments[0].lines[0].points[1]"),
        ("garments.0.lines.2.ring.points", 2, "garments[0].lines[2].ring.points"),
        ("garments.0.lines.2.ring.normal", "sideways", "garments[0].lines[2].ring.normal"),
        ("garments.0.lines.1.name", "neckline", "garments[0].lines[1].name"),
        ("garments.0.panels.1.name", "front", "garments[0].panels[1].name"),
        ("garments.0.panels.1.body_part", "wing", "garments[0].panels[1].body_part"),
        ("garments.0.panels", [], "garments[0].panels"),
        ("garments", [], "garments"),
        ("refine_edge_length", 0.0, "refine_edge_length"),
        ("mirror", "yes", "mirror"),
    ],
)
def test_validation_errors_name_the_path(where, value, path):
    d = shirt()
    _set(d, where, value)
    assert error_of(d).path == path


def test_unknown_top_level_field_and_bad_json(tmp_path):
    d = shirt()
    d["colour"] = "red"
    assert error_of(d).path == "colour"
    p = tmp_path / "broken.json"
    p.write_text('{"format": "ease-design", "version": 1,')
    e = error_of(str(p))
    assert "not valid JSON" in str(e) and "line 1" in str(e)
    e = error_of(str(tmp_path / "missing.json"))
    assert "not found" in str(e)


def test_save_refuses_invalid_design(tmp_path):
    d = load_design(shirt())
    d.garments[0].panels[0].ease = {"value": 9.0}
    with pytest.raises(DesignError):
        save_design(d, tmp_path / "x.json")
    assert not (tmp_path / "x.json").exists()


def test_edits_validate():
    d = load_design(shirt())
    d.set_parameter("sleeve_end", 0.8)
    assert d.parameters["sleeve_end"].value == 0.8
    with pytest.raises(DesignError) as e:
        d.set_parameter("sleeve_end", 2.0)
    assert e.value.path == "parameters.sleeve_end"
    with pytest.raises(DesignError):
        d.set_parameter("collar_height", 0.1)
    # a generated mirror panel becomes explicit when its ease is edited
    d.set_ease("shirt.sleeve_front_right", {"value": 1.7})
    names = [p.name for p in d.garments[0].panels]
    assert "sleeve_front_right" in names
    with pytest.raises(DesignError) as e:
        d.set_ease("shirt.front", {"value": 4.5})
    assert e.value.path == "garments[0].panels[0].ease.value"
    assert d.panel_names().count("shirt.sleeve_front_right") == 1


def test_mirrored_names():
    assert mirrored_name("sleeve_front_left") == "sleeve_front_right"
    assert mirrored_name("front") is None
    assert swap_side("arm_right") == "arm_left" and swap_side("crotch") == "crotch"
    d = load_design(shirt())
    assert set(d.panel_names()) == {
        "shirt.front",
        "shirt.back",
        "shirt.sleeve_front_left",
        "shirt.sleeve_back_left",
        "shirt.sleeve_front_right",
        "shirt.sleeve_back_right",
    }


# ------------------------------------------------------------------ resolution on Anny


def test_shirt_resolves_to_a_cut_spec(body, ref):
    spec = resolve(shirt(), body, vertices=ref)
    names = {l.name for l in spec.lines}
    for n in (
        "shirt.neckline",
        "shirt.hem",
        "shirt.cuff_left",
        "shirt.cuff_right",
        "shirt.armhole_left",
        "shirt.armhole_right",
        "shirt.shoulder_left",
        "shirt.shoulder_right",
        "shirt.side_left",
        "shirt.side_right",
        "shirt.sleeve_top_left",
        "shirt.sleeve_under_right",
    ):
        assert n in names
    roles = {l.name: l.role for l in spec.lines}
    assert roles["shirt.neckline"] == roles["shirt.hem"] == roles["shirt.cuff_left"] == "opening"
    assert roles["shirt.side_left"] == roles["shirt.armhole_right"] == "seam"
    assert [p.name for p in spec.panels] == [
        "shirt.front",
        "shirt.back",
        "shirt.sleeve_front_left",
        "shirt.sleeve_back_left",
        "shirt.sleeve_front_right",
        "shirt.sleeve_back_right",
    ]
    assert spec.panels[4].mirror_of == "shirt.sleeve_front_left"
    assert spec.garments[0].pin_line == "shirt.neckline" and spec.garments[0].kind == "upper"
    assert spec.materials["eps_weft"] == 1.1 and spec.body["shape"] == "M"
    # lines meet exactly at shared keypoints
    lines = {l.name: l for l in spec.lines}
    assert lines["shirt.side_left"].points[-1] in lines["shirt.hem"].points
    assert lines["shirt.shoulder_left"].points[-1] in lines["shirt.armhole_left"].points
    assert lines["shirt.sleeve_under_right"].points[-1] in lines["shirt.cuff_right"].points
    assert lines["shirt.neckline"].points[0] == lines["shirt.neckline"].points[0]


def test_unknown_landmark(body, ref):
    d = shirt()
    d["garments"][0]["lines"][0]["points"][1] = "nek_left"
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert e.value.path == "garments[0].lines[0].points[1]"
    assert "nek_left" in str(e.value) and "neck_left" in str(e.value)


def test_length_leaving_the_body_part_names_the_parameter(body, ref):
    d = TEMPLATES["top_short_sleeve"]()  # its sleeve's length is traced (the long sleeve's is a share of the arm)
    d["parameters"]["sleeve_length"] = {"value": 0.9, "kind": "length"}
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert e.value.path == "parameters.sleeve_length"
    assert "leaves the body part" in str(e.value)
    d = shirt()
    d["parameters"]["hem_length"] = {"value": 0.6, "kind": "length"}
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert e.value.path == "parameters.hem_length"
    d = TEMPLATES["shorts"]()  # the pants' leg is a share of the way to the ankle
    d["parameters"]["leg_length"] = {"value": 1.5, "kind": "length"}
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert e.value.path == "parameters.leg_length"


def test_keypoint_off_the_body_and_cycles(body, ref):
    d = shirt()
    d["keypoints"]["chest_front"] = {"triangle": 10**7, "bary": [1, 0, 0]}
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert e.value.path == "keypoints.chest_front.triangle" and "off the body" in str(e.value)
    d = shirt()
    d["keypoints"]["chest_front"] = {"between": ["chest_back", "neck_front"], "t": 0.5}
    d["keypoints"]["chest_back"] = {"between": ["chest_front", "neck_back"], "t": 0.5}
    with pytest.raises(DesignError) as e:
        resolve(d, body, vertices=ref)
    assert "depends on itself" in str(e.value)


def test_placement_and_trace_geometry(body, ref):
    d = shirt()
    d["keypoints"]["p0"] = {"between": ["neck_front", "waist_front"], "t": 0.0}
    d["keypoints"]["p1"] = {"between": ["neck_front", "waist_front"], "t": 1.0}
    d["keypoints"]["pm"] = {"between": ["neck_front", "waist_front"], "t": 0.5}
    d["keypoints"]["tr"] = {"trace": {"from": "shoulder_left", "along": "arm_left", "length": 0.2}}
    r = Resolver(load_design(d), body, ref)
    pos = lambda n: r.position(r.point(n, n))
    a, b = body.landmark_position("neck_front", ref), body.landmark_position("waist_front", ref)
    assert np.linalg.norm(pos("p0") - a) < 1e-6
    assert np.linalg.norm(pos("p1") - b) < 1e-6
    m = pos("pm")
    # half-way along the geodesic: about equally far from both ends, off the chord only a little
    assert abs(np.linalg.norm(m - a) - np.linalg.norm(m - b)) < 0.02
    s = body.landmark_position("shoulder_left", ref)
    w = body.landmark_position("wrist_left", ref)
    t = pos("tr")
    assert 0.15 < np.linalg.norm(t - s) <= 0.2 + 1e-6
    assert np.linalg.norm(t - w) < np.linalg.norm(s - w)  # it went towards the wrist


def test_ring_points_lie_on_their_plane(body, ref):
    r = Resolver(load_design(shirt()), body, ref)
    i = next(k for k, l in enumerate(r.lines) if l[0] == "shirt.hem")
    pts = r.line_points(i)
    z = np.array([r.position(p)[2] for p in pts])
    assert len(pts) >= 16 and np.ptp(z) < 1e-9
    left, right = r.position(r.point("hem_side_left", "")), r.position(r.point("hem_side_right", ""))
    P = np.array([r.position(p) for p in pts])
    assert left[0] >= P[:, 0].max() - 1e-9 and right[0] <= P[:, 0].min() + 1e-9
    assert r.point("hem_side_left", "") in pts
    # the loop is closed and goes round the torso: perimeter of a hip
    per = np.linalg.norm(np.diff(np.vstack([P, P[:1]]), axis=0), axis=1).sum()
    assert 0.6 < per < 1.6


def test_mirroring_surface_points(body, ref):
    faces = np.asarray(body.faces)
    sym = np.asarray(body.symmetry)
    fs = face_symmetry(faces, sym)
    assert (fs >= 0).mean() > 0.99
    r = Resolver(load_design(shirt()), body, ref)
    for name in ("armhole_under_left", "cuff_level_left", "neckline_side_left", "shoulder_left"):
        sp = r.point(name, name)
        m = mirror_surface_point(sp, faces, sym, fs, r.locator)
        p, q = r.position(sp), r.position(m)
        assert np.linalg.norm(q - p * [-1, 1, 1]) < 2e-3
        back = mirror_surface_point(m, faces, sym, fs, r.locator)
        assert back.triangle == sp.triangle and np.allclose(back.bary, sp.bary)
    # generated *_right keypoints are the mirror images of the *_left ones
    for name in ("armhole_under_left", "cuff_top_left", "armhole_top_left"):
        p = r.position(r.point(name, name))
        q = r.position(r.point(mirrored_name(name), name))
        assert np.linalg.norm(q - p * [-1, 1, 1]) < 2e-3


@pytest.mark.parametrize("size", ["XS", "XL"])
def test_templates_resolve_on_other_sizes(body, size):
    from core.design.resolve import instance_vertices

    d = load_design(shirt())
    V = instance_vertices(d, body, shape=size)
    spec = resolve(d, body, vertices=V, shape=size)
    assert spec.body["shape"] == size and len(spec.panels) == 6


# ------------------------------------------------------------------ ease fields


def _body_cut(body, ref, regions):
    """A cut whose panels are whole body regions (identity embedding)."""
    faces = np.asarray(body.faces)
    panels = []
    for name, verts in regions.items():
        mask = np.isin(faces, verts).all(axis=1)
        F = faces[mask]
        vid = np.unique(F)
        remap = {v: i for i, v in enumerate(vid)}
        local = np.vectorize(remap.get)(F)
        panels.append(
            Panel(
                name=name,
                garment="shirt",
                vertex_ids=vid,
                faces=local,
                warp_dir=np.tile([0, 0, 1.0], (len(F), 1)),
                ease=np.ones(len(F)),
            )
        )
    n = len(ref)
    return GarmentCut(body={}, embedding=sp.identity(n, format="csr"), panels=panels, seams=[])


def test_ease_fields(body, ref):
    regions = {
        "shirt.front": body.regions["torso"],
        "shirt.sleeve_front_left": body.regions["arm_left"],
        "shirt.sleeve_front_right": body.regions["arm_right"],
    }
    d = shirt()
    panels = d["garments"][0]["panels"]
    panels[0]["ease"] = {"from": 1.0, "to": 2.0, "axis": "-z"}
    ftri = np.flatnonzero(np.isin(np.asarray(body.faces), body.regions["arm_left"]).all(axis=1))
    chosen = ftri[::3]
    panels[2]["ease"] = {"per_triangle": {"triangles": chosen.tolist(), "values": [2.5] * len(chosen), "default": 1.1}}
    cut = apply_ease(_body_cut(body, ref, regions), d, body, ref)
    front = cut.panel("shirt.front")
    c = cut.panel_positions(front, ref)[front.faces].mean(axis=1)
    top, bottom = np.argmax(c[:, 2]), np.argmin(c[:, 2])
    assert math.isclose(front.ease[top], 1.0) and math.isclose(front.ease[bottom], 2.0)
    assert np.all(np.diff(front.ease[np.argsort(-c[:, 2])]) >= -1e-12)  # rises towards the hem
    left = cut.panel("shirt.sleeve_front_left")
    assert set(np.round(left.ease, 6)) == {1.1, 2.5}
    assert math.isclose((left.ease == 2.5).sum(), len(chosen), rel_tol=0.01)
    # the mirrored panel reads the painted field at the mirror triangles
    right = cut.panel("shirt.sleeve_front_right")
    assert (right.ease == 2.5).sum() == (left.ease == 2.5).sum()


def test_gradient_between_keypoints_and_over_the_garment(body, ref):
    d = shirt()
    d["garments"][0]["panels"][0]["ease"] = {"from": 1.0, "to": 1.8, "between": ["neck_front", "waist_front"]}
    regions = {"shirt.front": body.regions["torso"]}
    cut = apply_ease(_body_cut(body, ref, regions), d, body, ref)
    e = cut.panels[0].ease
    assert e.min() == 1.0 and e.max() == 1.8  # clamped beyond both ends
    c = cut.panel_positions(cut.panels[0], ref)[cut.panels[0].faces].mean(axis=1)
    zn, zw = body.landmark_position("neck_front", ref)[2], body.landmark_position("waist_front", ref)[2]
    mid = np.abs(c[:, 2] - (zn + zw) / 2) < 0.01
    assert np.all(np.abs(e[mid] - 1.4) < 0.1)
    # over the garment: one ramp across both panels, not one per panel
    d = shirt()
    for p in d["garments"][0]["panels"]:
        p["ease"] = {"from": 1.0, "to": 2.0, "axis": "-z", "over": "garment"}
    regions = {"shirt.front": body.regions["torso"], "shirt.sleeve_front_left": body.regions["arm_left"]}
    cut = apply_ease(_body_cut(body, ref, regions), d, body, ref)
    torso, arm = cut.panel("shirt.front"), cut.panel("shirt.sleeve_front_left")
    assert torso.ease.min() == 1.0 and torso.ease.max() == 2.0  # the torso spans the garment's height
    assert arm.ease.min() > 1.0 and arm.ease.max() < 2.0
    d["garments"][0]["panels"][0]["ease"]["over"] = "body"
    assert error_of(d).path == "garments[0].panels[0].ease.over"
    nf = len(body.faces)
    d = shirt()
    d["garments"][0]["panels"][0]["ease"] = {"per_triangle": {"values": [1.3] * (nf - 1)}}
    with pytest.raises(DesignError) as exc:
        apply_ease(_body_cut(body, ref, {"shirt.front": body.regions["torso"]}), d, body, ref)
    assert exc.value.path == "garments[0].panels[0].ease.per_triangle.values"
    d["garments"][0]["panels"][0]["ease"] = {"per_triangle": {"values": [1.3] * nf}}
    cut = apply_ease(_body_cut(body, ref, {"shirt.front": body.regions["torso"]}), d, body, ref)
    assert np.allclose(cut.panels[0].ease, 1.3)


def test_template_lookup():
    assert template("pants").name == "pants"
    with pytest.raises(DesignError):
        template("kilt")


def test_mirror_of_keypoints_and_explicit_mirror_panels(body, ref):
    d = shirt()
    d["keypoints"]["spot_left"] = {"triangle": 5000, "bary": [0.2, 0.3, 0.5]}
    d["keypoints"]["spot_mirror"] = {"mirror_of": "spot_left"}
    d["garments"][0]["panels"][2]["seed"] = {"between": ["armhole_front_left", "cuff_front_left"], "t": 0.5}
    design = load_design(d)
    design.set_ease("shirt.sleeve_front_right", {"value": 1.5})  # the mirrored seed becomes explicit
    again = load_design(design.to_json())
    r = Resolver(again, body, ref)
    p, q = r.position(r.point("spot_left", "")), r.position(r.point("spot_mirror", ""))
    assert np.linalg.norm(q - p * [-1, 1, 1]) < 2e-3
    spec = resolve(again, body, vertices=ref)
    seeds = {s.name: r.position(s.seed) for s in spec.panels}
    assert np.linalg.norm(seeds["shirt.sleeve_front_right"] - seeds["shirt.sleeve_front_left"] * [-1, 1, 1]) < 2e-3


def test_ring_fractions_mirror_with_the_ring(body, ref):
    d = shirt()
    cuff = next(l for l in d["garments"][0]["lines"] if l["name"] == "cuff_left")
    cuff["ring"]["named"]["cuff_quarter_left"] = 0.25
    cuff["ring"]["named"]["cuff_half_left"] = 0.5
    r = Resolver(load_design(d), body, ref)
    i = next(k for k, l in enumerate(r.lines) if l[0] == "shirt.cuff_left")
    pts = r.line_points(i)
    P = np.array([r.position(p) for p in pts])
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(np.vstack([P, P[:1]]), axis=0), axis=1))])
    k = pts.index(r.point("cuff_half_left", ""))
    assert abs(arc[k] / arc[-1] - 0.5) < 0.02
    # the mirrored ring turns the other way round, so fractions land on mirrored points
    for name in ("cuff_quarter_left", "cuff_half_left"):
        p = r.position(r.point(name, ""))
        q = r.position(r.point(name.replace("_left", "_right"), ""))
        assert np.linalg.norm(q - p * [-1, 1, 1]) < 2e-3


@pytest.mark.parametrize("pose", ["A", "T"])
def test_traced_length_follows_the_limb_in_the_design_pose(body, pose):
    """A length is traced down the body part in the design's reference pose: from the
    shoulder tip along the arm it drops steeply in the A-pose and runs out level in the T-pose."""
    from core.design.resolve import instance_vertices

    d = shirt()
    d["body"]["pose"] = pose
    d["keypoints"]["tr"] = {"trace": {"from": "shoulder_left", "along": "arm_left", "length": 0.25}}
    design = load_design(d)
    V = instance_vertices(design, body)
    r = Resolver(design, body, V)
    t = r.position(r.point("tr", "tr"))
    s = body.landmark_position("shoulder_left", V)
    e = body.landmark_position("elbow_left", V)
    drop = np.degrees(np.arctan2(s[2] - t[2], t[0] - s[0]))  # below the horizontal, degrees
    arm = np.degrees(np.arctan2(s[2] - e[2], e[0] - s[0]))
    assert abs(drop - arm) < 12, (drop, arm)
    assert (drop > 30) if pose == "A" else (abs(drop) < 15)
    assert 0.2 < np.linalg.norm(t - s) <= 0.25 + 1e-6


def test_ring_tilted_to_contain_a_keypoint(body, ref):
    """``ring.contains``: the plane through ``through`` is turned least from its normal so
    that it also holds a second keypoint (the templates' armholes: armpit + shoulder tip);
    it is mirrored with the ring, and checked (saving: the template round trips)."""
    d = shirt()
    arm = next(l for l in d["garments"][0]["lines"] if l["name"] == "armhole_left")
    assert arm["ring"]["contains"] == "armhole_top_left"
    assert d["keypoints"]["armhole_top_left"] == "shoulder_left"
    r = Resolver(load_design(d), body, ref)
    for side in ("left", "right"):
        i = next(k for k, l in enumerate(r.lines) if l[0] == f"shirt.armhole_{side}")
        P = np.array([r.position(p) for p in r.line_points(i)])
        c = P.mean(0)
        n = np.linalg.svd(P - c)[2][-1]
        assert np.abs((P - c) @ n).max() < 1e-6
        assert abs((r.position(r.point(f"shoulder_{side}", "")) - c) @ n) < 1e-6
        assert r.point(f"armhole_top_{side}", "") in r.line_points(i)  # a vertex of the ring
        assert abs(n[0]) > 0.99  # the A-pose armhole: (nearly) the sagittal plane
    # without ``contains`` the plane is across the arm's axis and misses the shoulder tip
    del arm["ring"]["contains"]
    r = Resolver(load_design(d), body, ref)
    i = next(k for k, l in enumerate(r.lines) if l[0] == "shirt.armhole_left")
    P = np.array([r.position(p) for p in r.line_points(i)])
    assert np.linalg.norm(P - r.position(r.point("shoulder_left", "")), axis=1).min() > 0.01
    # bad values name their JSON path
    arm["ring"]["contains"] = 3
    assert error_of(d).path == "garments[0].lines[2].ring.contains"
    arm["ring"]["contains"] = "armhole_under_left"  # the through point itself
    with pytest.raises(DesignError) as exc:
        resolve(load_design(d), body, vertices=ref)
    assert exc.value.path == "garments[0].lines[2].ring.contains"


def test_gathered_seams_in_materials():
    obj = json.loads(json.dumps(load_design(TEMPLATES["shirt_long_sleeve"]()).to_json()))
    obj["materials"].update(gathered=["armhole_left", "shirt.armhole_right"], gather_above=0.3)
    d = load_design(obj)
    assert d.materials["gathered"] == ["armhole_left", "shirt.armhole_right"]
    assert d.materials["gather_above"] == 0.3
    assert load_design(d.to_json()).materials == d.materials
    obj["materials"].update(gathered=True, gather_above=None)
    d = load_design(obj)
    assert d.materials["gathered"] is True and d.materials["gather_above"] is None


def test_a_body_error_at_resolve_names_the_design_body():
    """A shape parameter or joint only a file model knows is checked when the instance is made:
    the error then points at the design's body, not at a bare parameter name."""
    from core.design.resolve import instance_vertices
    from core.errors import BodyError

    class FileModel:
        def vertices(self, shape=None, pose=None):
            raise BodyError("shape.beta99: unknown shape parameter; known: beta0..beta9")

    d = load_design(shirt())
    with pytest.raises(DesignError) as e:
        instance_vertices(d, FileModel(), shape={"beta99": 1.0})
    assert e.value.path == "body" and "beta99" in str(e.value)
