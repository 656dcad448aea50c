"""Design operators (ease_addon.design_ops): a template on the body with its seamlines and
keypoints, keypoints placed on a vertex or by a click, parameters with a live re-cut."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True)


def test_load_template_draws_seamlines_and_keypoints(bpy_session, blender, addon):
    bpy = bpy_session["bpy"]
    from core.design import load_design

    assert bpy.ops.ease.load_template(template=DESIGN) == {"FINISHED"}
    s = bpy.context.scene.ease
    design = load_design(json.loads(s.design_json))
    want = load_design(ROOT / "examples" / "designs" / DESIGN)
    assert design.panel_names() == want.panel_names()
    seams = [o for o in bpy.data.objects if o.get("ease_role") == "seamlines"]
    assert len(seams) == 1 and len(seams[0].data.edges) > 20
    convert = addon("convert")
    kps = convert.read_keypoints(s.body.data)
    assert kps, "the design's surface keypoints are stored on the body"
    # seamline vertices lie on the body surface (they are cut-embedded points)
    body_v = blender.verts(s.body)
    seam_v = blender.verts(seams[0])
    from scipy.spatial import cKDTree

    d, _ = cKDTree(body_v).query(seam_v)
    assert d.max() < 0.03
    # the seamlines stay attached when the body is posed (moved in place)
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    seams = [o for o in bpy.data.objects if o.get("ease_role") == "seamlines"]
    d, _ = cKDTree(blender.verts(s.body)).query(blender.verts(seams[0]))
    assert d.max() < 0.03 and np.abs(blender.verts(seams[0]) - seam_v).max() > 0.05
    assert bpy.ops.ease.set_pose(pose="A") == {"FINISHED"}
    # the cut panels match the design's panels
    cut = addon("data").current_cut(bpy.context)
    assert sorted(p.name for p in cut.panels) == sorted(want.panel_names())


def test_keypoint_on_selected_vertex(bpy_session, addon, anny):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    obj = s.body
    model = anny
    vid = int(model.faces[1234, 1])
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[vid] = True
    obj.data.vertices.foreach_set("select", sel)
    assert bpy.ops.ease.assign_keypoint(name="test_point") == {"FINISHED"}
    design = json.loads(s.design_json)
    kp = design["keypoints"]["test_point"]
    tri, bary = kp["triangle"], kp["bary"]
    assert vid in model.faces[tri] and np.isclose(max(bary), 1.0)
    assert np.allclose(np.asarray(bary) @ model.vertices()[model.faces[tri]], model.vertices()[vid])
    convert = addon("convert")
    assert convert.read_keypoints(obj.data)["test_point"][0] == tri


def test_keypoint_on_a_vertex_selected_in_edit_mode(bpy_session, blender):
    """The designer's way: Edit Mode, select one vertex, Keypoint at Selected Vertex; stays in Edit Mode."""
    bpy = bpy_session["bpy"]
    import bmesh

    s = bpy.context.scene.ease
    obj = s.body
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bm = bmesh.from_edit_mesh(obj.data)
    for v in bm.verts:
        v.select = False
    bm.verts.ensure_lookup_table()
    vid = 4321
    bm.verts[vid].select = True
    bmesh.update_edit_mesh(obj.data)
    assert bpy.ops.ease.assign_keypoint(name="edit_point") == {"FINISHED"}
    assert obj.mode == "EDIT"
    bpy.ops.object.mode_set(mode="OBJECT")
    kp = json.loads(s.design_json)["keypoints"]["edit_point"]
    faces = np.array([p.vertices[:] for p in obj.data.polygons])
    assert vid in faces[kp["triangle"]]
    assert np.allclose(
        np.asarray(kp["bary"]) @ blender.verts(obj)[faces[kp["triangle"]]], blender.verts(obj)[vid], atol=1e-6
    )
    # two selected: the add-on says what is wrong, the design unchanged
    before = s.design_json
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[[10, 20]] = True
    obj.data.vertices.foreach_set("select", sel)
    r = blender.run(bpy.ops.ease.assign_keypoint, name="two_points")
    assert "ERROR" in r and "exactly one" in r["ERROR"] and s.design_json == before


def test_keypoint_clicked_on_the_surface(bpy_session, blender, addon):
    """Pick Keypoint: the ray under the mouse meets the body; the keypoint is that surface point.
    Headless there is no viewport to click in: the test casts the ray the click would."""
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    design_ops = addon("design_ops")
    v = blender.verts(s.body).astype(np.float64)
    chest_z = v[:, 2].min() + 0.72 * np.ptp(v[:, 2])
    origin, direction = (0.03, -3.0, chest_z), (0.0, 1.0, 0.0)  # from in front (the body faces -Y)
    tri = design_ops.pick_on_surface(bpy.context, "clicked_point", origin, direction)
    kp = json.loads(s.design_json)["keypoints"]["clicked_point"]
    assert kp["triangle"] == tri and sum(kp["bary"]) == pytest.approx(1.0)
    faces = np.array([p.vertices[:] for p in s.body.data.polygons])
    hit = np.asarray(kp["bary"]) @ v[faces[tri]]
    # on the ray, and on the front of the body: nothing of the body lies between
    assert abs(hit[0] - 0.03) < 1e-5 and abs(hit[2] - chest_z) < 1e-5
    near = v[(np.abs(v[:, 0] - 0.03) < 0.01) & (np.abs(v[:, 2] - chest_z) < 0.01)]
    assert hit[1] <= near[:, 1].min() + 0.01
    convert = addon("convert")
    assert convert.read_keypoints(s.body.data)["clicked_point"][0] == tri
    # a click beside the body: the add-on's message, the design unchanged
    before = s.design_json
    with pytest.raises(Exception, match="no body under the mouse"):
        design_ops.pick_on_surface(bpy.context, "missed", (3.0, -3.0, chest_z), direction)
    with pytest.raises(Exception, match="name"):
        design_ops.pick_on_surface(bpy.context, "", origin, direction)
    assert s.design_json == before


def test_parameter_recut(bpy_session, blender):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    if not len(s.design_params):
        pytest.skip("template has no parameters")
    item = max(s.design_params, key=lambda i: min(i.max, 10.0) - max(i.min, -10.0))
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    v0 = blender.verts(seams).copy()
    old = item.value
    lo, hi = item.min, item.max
    new = old + 0.5 * (hi - old) if hi - old > old - lo else old - 0.5 * (old - lo)
    assert lo <= new <= hi
    assert bpy.ops.ease.set_parameter(name=item.name, value=new) == {"FINISHED"}
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(new)
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    v1 = blender.verts(seams)
    assert v1.shape != v0.shape or np.abs(v1 - v0).max() > 1e-4
    assert bpy.ops.ease.set_parameter(name=item.name, value=old) == {"FINISHED"}
    # live re-cut from the slider itself
    s.live_recut = True
    item = next(i for i in s.design_params if i.name == item.name)
    item.value = new
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(new)
    seams = next(o for o in bpy.data.objects if o.get("ease_role") == "seamlines")
    assert np.abs(blender.verts(seams) - v1).max() < 1e-6 if blender.verts(seams).shape == v1.shape else False
    item.value = old
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == pytest.approx(old)


def test_a_design_that_would_drop_right_side_paint_is_refused(bpy_session, blender, anny, tmp_path):
    """Load File of a mirrored design whose per-triangle ease differs on the right side from the
    mirror of the left: refused in one line naming the field (the generated right panels would
    drop that paint without a word), the scene left as it was."""
    from test_mirror_ease import PATH, mirrored_sleeve_design

    bpy = bpy_session["bpy"]
    assert bpy.ops.ease.load_template(template=DESIGN) == {"FINISHED"}
    s = bpy.context.scene.ease
    before = s.design_json
    bad = tmp_path / "asym.json"
    bad.write_text(json.dumps(mirrored_sleeve_design(anny, 1.8)))
    out = blender.run(bpy.ops.ease.load_design_file, filepath=str(bad))
    assert "ERROR" in out and PATH in out["ERROR"] and "sleeve_front_right" in out["ERROR"], out
    assert "\n" not in out["ERROR"].strip()
    assert s.design_json == before
    ok = tmp_path / "sym.json"
    ok.write_text(json.dumps(mirrored_sleeve_design(anny, 1.5)))
    assert bpy.ops.ease.load_design_file(filepath=str(ok)) == {"FINISHED"}


def test_loading_runs_off_the_main_thread(bpy_session, blender, anny, tmp_path):
    """In Blender's UI a design is read and cut in a worker (the button's job, as Drape's): Load
    returns at once with the scene as it was ("updating: loading ..."), and the design lands in
    one pass on the main thread, the same as in line; a refused design says why under the Design
    panel and changes nothing. From a script (``execute``) a load runs in line even where jobs
    are threaded (Blender's UI), as Drape does: its result is there when the call returns."""
    from test_mirror_ease import PATH, mirrored_sleeve_design

    bpy = bpy_session["bpy"]
    jobs, design_ops = blender.mod("jobs"), blender.mod("design_ops")
    blender.reset(body=True)
    assert bpy.ops.ease.load_template(template=DESIGN) == {"FINISHED"}
    want = bpy.context.scene.ease.design_json
    template = str(blender.mod("data").template_dir() / DESIGN)
    blender.reset(body=True)
    s = bpy.context.scene.ease
    blender.mod("state").BUGS.clear()
    jobs.SYNCHRONOUS = False
    try:
        # the button (invoke): the job in a worker
        job, said = design_ops.start_load(template, DESIGN, design_ops._body_now(bpy.context), "Load Template")
        assert job.thread is not None and not said
        assert s.design_json == "" and s.job_status.startswith("updating: loading")
        assert not blender.objects("seamlines")
        jobs.wait()
        assert not blender.mod("state").BUGS
        assert s.design_json == want and s.job_status.startswith(f"loaded {DESIGN}") and said
        assert blender.objects("seamlines") and convert_keypoints(blender)
        bad = tmp_path / "asym.json"
        bad.write_text(json.dumps(mirrored_sleeve_design(anny, 1.8)))
        design_ops.start_load(str(bad), str(bad), design_ops._body_now(bpy.context), "Load File")
        jobs.wait()
        assert s.design_json == want and PATH in s.design_status
        # a script's call: in line, no job left running, the design there on return
        blender.reset(body=True)
        s = bpy.context.scene.ease  # (a new scene)
        assert bpy.ops.ease.load_template(template=DESIGN) == {"FINISHED"}
        assert jobs.running() is None and s.design_json == want
        out = blender.run(bpy.ops.ease.load_design_file, filepath=str(bad))
        assert PATH in out["ERROR"]
        assert jobs.running() is None and s.design_json == want
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True


def convert_keypoints(blender):
    return blender.mod("convert").read_keypoints(blender.scene.ease.body.data)
