"""Body operators (ease_addon.body_ops): the default body, sizes, poses, sliders,
measurements, a body file; a bad input leaves the scene as it was."""

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
    return blender.reset()


def test_add_body_and_shape_in_place(bpy_session, blender, anny):
    bpy = bpy_session["bpy"]
    model = anny
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}
    s = bpy.context.scene.ease
    obj = s.body
    assert obj is not None and len(obj.data.vertices) == model.n_vertices
    assert len(obj.data.polygons) == len(model.faces)
    layer = obj.data.color_attributes.get("ease")
    assert layer is not None and layer.domain == "POINT" and layer.data_type == "FLOAT_COLOR"
    assert {i.name for i in s.shape} == set(model.shape_parameters())
    assert np.allclose(blender.verts(obj), model.vertices(), atol=1e-5)
    # size preset: the vertices move in place, the ease layer stays
    assert bpy.ops.ease.set_size(size="XL") == {"FINISHED"}
    from core.body.sizes import size_shape

    assert np.allclose(blender.verts(obj), model.vertices(size_shape(model, "XL")), atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert "chest" in s.measurements_report
    # every pose preset, on the XL body
    for pose in ("T", "P1", "P2", "P3"):
        assert bpy.ops.ease.set_pose(pose=pose) == {"FINISHED"}
        assert np.allclose(blender.verts(obj), model.vertices(size_shape(model, "XL"), pose), atol=1e-5), pose
    assert bpy.ops.ease.set_pose(pose="A") == {"FINISHED"}
    # every size preset: girth grows from XS to XL
    girth = []
    for size in ("XS", "S", "M", "L", "XL"):
        assert bpy.ops.ease.set_size(size=size) == {"FINISHED"}
        assert np.allclose(blender.verts(obj), model.vertices(size_shape(model, size)), atol=1e-5), size
        girth.append(float(np.ptp(blender.verts(obj)[:, 1])))
    assert girth == sorted(girth)
    assert bpy.ops.ease.set_size(size="M") == {"FINISHED"}
    # sliders update the body live
    item = next(i for i in s.shape if i.name == "weight")
    v0 = blender.verts(obj).copy()
    item.value = 0.8
    assert np.abs(blender.verts(obj) - v0).max() > 1e-3
    item.value = 0.5
    assert np.allclose(blender.verts(obj), v0, atol=1e-5)


def test_size_and_pose_run_in_the_background(bpy_session, blender, anny):
    """Apply Size / Apply Pose pressed in Blender's UI (the buttons' job, as Drape's): the body's
    vertices are computed in a worker, the operator returns at once with the body as it was and
    the status saying "updating"; the result lands in one pass (the body, the Body panel); Esc
    (cancel) leaves the body as it was; a result landing on a body changed meanwhile is refused
    with the reason; from a script the operators run in line even where jobs are threaded."""
    from core.body.sizes import size_shape

    bpy = bpy_session["bpy"]
    jobs, body_ops = blender.mod("jobs"), blender.mod("body_ops")
    blender.reset(body=True)
    s = bpy.context.scene.ease
    obj = s.body
    v0 = blender.verts(obj).copy()
    jobs.SYNCHRONOUS = False
    try:
        job = body_ops.start_body(bpy.context, shape=size_shape(anny, "L"), size="L")
        assert job.thread is not None
        assert s.job_status.startswith("updating: the body in size L")
        jobs.wait()
        assert np.allclose(blender.verts(obj), anny.vertices(size_shape(anny, "L")), atol=1e-5)
        assert s.size == "L" and obj["ease_size"] == "L" and s.job_status.startswith("size L: ")
        assert "chest" in s.measurements_report
        v1 = blender.verts(obj).copy()
        # Esc: nothing applied
        job = body_ops.start_body(bpy.context, pose="P1")
        assert jobs.cancel() == 1
        job.thread.join(60)
        jobs.poll()
        assert np.array_equal(blender.verts(obj), v1) and obj["ease_pose"] == "A"
        assert "cancelled" in s.job_status and s.pose == "A"
        # the body changed while a pose was computed: refused, said, the newer body kept
        job = body_ops.start_body(bpy.context, pose="P2")
        job.thread.join(60)
        next(i for i in s.shape if i.name == "weight").value = 0.7  # a slider moves the body meanwhile
        v2 = blender.verts(obj).copy()
        jobs.wait()
        assert "changed" in s.job_status and obj["ease_pose"] == "A" and np.array_equal(blender.verts(obj), v2)
        # a script's call: in line (a job of the same name running meanwhile is replaced: the newer wins)
        job = body_ops.start_body(bpy.context, pose="P3")
        assert bpy.ops.ease.set_size(size="S") == {"FINISHED"} and s.size == "S"
        assert jobs.running() is None and job.cancelled
        assert np.allclose(blender.verts(obj), anny.vertices(size_shape(anny, "S")), atol=1e-5)
        assert bpy.ops.ease.set_pose(pose="T") == {"FINISHED"} and jobs.running() is None
        assert np.allclose(blender.verts(obj), anny.vertices(size_shape(anny, "S"), "T"), atol=1e-5)
        assert not blender.mod("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
        blender.reset(body=True)  # (the next tests start from the default body)
    assert not np.array_equal(v0, v1)


def test_bad_input_reports_and_leaves_scene(bpy_session, blender):
    bpy = bpy_session["bpy"]
    obj = bpy.context.scene.ease.body
    v0 = blender.verts(obj).copy()
    n_obj = len(bpy.data.objects)
    r = blender.run(bpy.ops.ease.set_size, size="XXL")
    assert "ERROR" in r and "XXL" in r["ERROR"] and "XS" in r["ERROR"]
    r = blender.run(bpy.ops.ease.set_pose, pose="Q9")
    assert "ERROR" in r
    r = blender.run(bpy.ops.ease.load_template, template="no_such_design.json")
    assert "ERROR" in r and "no_such_design" in r["ERROR"]
    # a design that fails to resolve on the body: the core's message, nothing changed
    bad = json.loads((ROOT / "examples" / "designs" / DESIGN).read_text())
    bad["body"]["shape"] = "XL"  # would reshape the body if it got that far
    bad["keypoints"]["chest_front"] = {"landmark": "nose_tip"}
    path = bpy_session["tmp"] / "bad_design.json"
    path.write_text(json.dumps(bad))
    r = blender.run(bpy.ops.ease.load_design_file, filepath=str(path))
    assert "ERROR" in r and "nose_tip" in r["ERROR"], r
    assert bpy.context.scene.ease.design_json == ""
    assert np.array_equal(blender.verts(obj), v0) and len(bpy.data.objects) == n_obj
    # every later stage, asked too early, says what is missing and changes nothing
    s = bpy.context.scene.ease
    s.export_dir = str(bpy_session["tmp"] / "too_early")
    for op, kw, words in (
        (bpy.ops.ease.optimize_pattern, {}, "design"),
        (bpy.ops.ease.ease_to_design, {}, "design"),
        (bpy.ops.ease.recut, {}, "design"),
        (bpy.ops.ease.transfer_size, {}, "design"),
        (bpy.ops.ease.adapt_poses, {}, "design"),
        (bpy.ops.ease.drape, {}, "pattern"),
        (bpy.ops.ease.export_pattern, {}, "pattern"),
        (bpy.ops.ease.fitmap, dict(mode="STRAIN"), "drape"),
    ):
        r = blender.run(op, **kw)
        assert "ERROR" in r and words in r["ERROR"].lower(), (op.idname(), r)
        assert np.array_equal(blender.verts(obj), v0) and len(bpy.data.objects) == n_obj, op.idname()
        assert s.design_json == "" and not s.pattern_json and not s.fit_json and not s.drape_json, op.idname()
    assert not (bpy_session["tmp"] / "too_early").exists()


def test_measurements_fit_and_manual_shape(bpy_session, blender, anny):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    assert bpy.ops.ease.measure() == {"FINISHED"}
    assert "height" in s.measurements_report and "hip" in s.measurements_report
    s.height_cm, s.chest_cm, s.waist_cm, s.hip_cm = 175.0, 98.0, 84.0, 102.0
    assert bpy.ops.ease.fit_measurements() == {"FINISHED"}
    from core.body.measure import measure

    model = anny
    got = measure(model, blender.verts(s.body).astype(np.float64))
    for k, want in (("height", 175.0), ("chest", 98.0), ("waist", 84.0), ("hip", 102.0)):
        if "not reachable" not in s.measurements_report.split(k, 1)[1].split(",", 1)[0]:
            assert abs(got[k] - want) <= 1.0 + 1e-6, (k, got[k])
    # sliders -> Apply Shape: the mesh is the model evaluated at the sliders
    for item in s.shape:
        if item.name == "muscle":
            item.value = 0.3
    assert bpy.ops.ease.apply_shape() == {"FINISHED"}
    shape = {i.name: i.value for i in s.shape}
    assert np.allclose(blender.verts(s.body), model.vertices(shape), atol=1e-5)


def test_body_from_a_file_the_user_owns(bpy_session, blender, anny):
    """From File: a template OBJ (no blend shapes) becomes the scene body, with its ease layer."""
    bpy = bpy_session["bpy"]
    model = anny
    v = model.vertices()
    path = bpy_session["tmp"] / "my_body.obj"
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in model.faces]
    path.write_text("\n".join(lines) + "\n")
    s = bpy.context.scene.ease
    s.body_file = str(path)
    assert bpy.ops.ease.add_body(source="FILE") == {"FINISHED"}
    obj = s.body
    assert obj["ease_model"] == str(path)
    assert len(obj.data.vertices) == len(v) and np.allclose(blender.verts(obj), v, atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert len([o for o in bpy.data.objects if o.get("ease_role") == "body"]) == 1
    s.body_file = str(bpy_session["tmp"] / "missing.npz")
    r = blender.run(bpy.ops.ease.add_body, source="FILE")
    assert "ERROR" in r and s.body == obj


def test_body_from_an_smpl_file(bpy_session, blender):
    """From File with an SMPL-format .npz the user owns: its betas become the shape sliders, poses apply."""
    bpy = bpy_session["bpy"]
    from smpl_synth import tube_model  # a small SMPL-format model (24 joints)

    from core.body import load_body

    path = bpy_session["tmp"] / "my_smpl.npz"
    np.savez(path, **tube_model(J=24, n_ring=12, n_rows=30))
    model = load_body(str(path))
    s = bpy.context.scene.ease
    s.body_file = str(path)
    assert bpy.ops.ease.add_body(source="FILE") == {"FINISHED"}
    obj = s.body
    assert obj["ease_model"] == str(path) and len(obj.data.vertices) == model.n_vertices
    assert {i.name for i in s.shape} == set(model.shape_parameters())
    assert np.allclose(blender.verts(obj), model.vertices(), atol=1e-5)
    next(i for i in s.shape if i.name == "beta1").value = 2.0  # a slider: the body follows
    assert np.allclose(blender.verts(obj), model.vertices({"beta1": 2.0}), atol=1e-5)
    assert bpy.ops.ease.set_pose(pose="P1") == {"FINISHED"}
    assert np.allclose(blender.verts(obj), model.vertices({"beta1": 2.0}, "P1"), atol=1e-5)
    assert obj.data.color_attributes.get("ease") is not None
    assert bpy.ops.ease.add_body(source="DEFAULT") == {"FINISHED"}


def test_add_body_and_fit_measurements_run_in_the_background(bpy_session, blender, anny):
    """Add Body and Fit Measurements pressed in Blender's UI (jobs, as Apply Size): the body model,
    its vertices, the design's cut and keypoints on it (Add Body) and the fit (Fit Measurements)
    are computed in a worker, the scene as it was until the result lands in one pass (no
    ``.001``); Esc (cancel) leaves the scene as it was."""
    bpy = bpy_session["bpy"]
    jobs, body_ops = blender.mod("jobs"), blender.mod("body_ops")
    blender.reset(body=True, design=DESIGN)
    s = bpy.context.scene.ease
    old = s.body
    names = sorted(o.name for o in bpy.data.objects)
    kps = bpy.context.scene.ease.body.data.attributes["ease_keypoint"]
    n_kp = int(np.count_nonzero([d.value for d in kps.data]))
    # targets the default body nearly has (a short fit: the long one is test_measurements_fit_and_manual_shape's)
    m = blender.mod("data").measurements(anny, None)
    s.height_cm, s.chest_cm, s.waist_cm, s.hip_cm = (round(m[k], 0) for k in ("height", "chest", "waist", "hip"))
    jobs.SYNCHRONOUS = False
    try:
        job, said = body_ops.start_add_body(bpy.context, "anny")
        assert job.thread is not None and not said and s.body == old
        assert s.job_status.startswith("updating: adding the body anny")
        jobs.wait()
        obj = s.body
        assert said[-1][1].startswith("added body anny") and s.job_status.endswith(said[-1][1])
        assert sorted(o.name for o in bpy.data.objects) == names and obj.name == "EASE Body"
        kps = obj.data.attributes["ease_keypoint"]
        assert int(np.count_nonzero([d.value for d in kps.data])) == n_kp  # the design's keypoints on it
        assert np.allclose(blender.verts(obj), anny.vertices(None), atol=1e-5)
        # Fit Measurements: the fit in the worker, then the body and the panel
        job = body_ops.start_fit(bpy.context)
        assert job.thread is not None and s.job_status.startswith("updating: the body in shape")
        before = s.measurements_report
        jobs.wait()
        threaded = blender.verts(obj).copy()
        report = s.measurements_report
        assert report != before and report.count("(within 1 cm)") == 4 and s.job_status == f"shape: {report}"
        # Esc: nothing applied
        s.height_cm = 160.0
        job = body_ops.start_fit(bpy.context)
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert np.array_equal(blender.verts(obj), threaded) and s.measurements_report == report
        assert "cancelled" in s.job_status
        assert not blender.mod("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
        blender.reset(body=True)  # (the next tests start from the default body)


def test_a_result_landing_in_a_timer_is_one_undo_step(bpy_session, blender):
    """A threaded job's result lands in a timer, whose context has no window: there
    ``ed.undo_push``'s poll fails, and the step was silently not pushed (Ctrl+Z then took back the
    designer's previous action with it). ``jobs.undo_push`` runs it in the scene's window."""
    bpy = bpy_session["bpy"]
    jobs, body_ops = blender.mod("jobs"), blender.mod("body_ops")
    blender.reset(body=True)
    pose = lambda: bpy.context.scene.ease.body["ease_pose"]  # noqa: E731  (undo rebuilds the data)
    assert pose() == "A"
    bpy.ops.ed.undo_push(message="before")
    jobs.SYNCHRONOUS = False
    try:
        body_ops.start_body(bpy.context, pose="P1")
        with bpy.context.temp_override(window=None):  # as Blender runs a timer (the jobs' poll)
            assert not bpy.ops.ed.undo_push.poll()
            jobs.wait()
    finally:
        jobs.SYNCHRONOUS = True
    assert pose() == "P1"
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert pose() == "A"
    assert bpy.ops.ed.redo() == {"FINISHED"}
    assert pose() == "P1"
