"""Drape Animation and Export Alembic (ease_addon.motion_ops): the garment through A -> P1 on the
moving body, shape-keyed per frame, written with Blender's Alembic exporter and read back by its
importer with the same vertices at every frame."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.drape.options import DrapeOptions

DESIGN = "top_sleeveless.json"  # cheapest template: two panels
BETWEEN = 2  # A, 2 in-betweens, P1: 4 frames


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    blender.reset(body=True, design=DESIGN, pattern=True)
    s = blender.scene.ease
    s.motion_poses, s.motion_between = "A, P1", BETWEEN
    assert blender.bpy.ops.ease.drape_animation() == {"FINISHED"}
    return blender


def _world(obj, depsgraph) -> np.ndarray:
    ev = obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    co = np.empty(len(me.vertices) * 3, dtype=np.float64)
    me.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    m = np.array(obj.matrix_world)
    return co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]


def test_motion_objects_play_the_frames(scene, bpy_session):
    bpy = scene.bpy
    sc = bpy.context.scene
    body, garment = bpy.data.objects["EASE Motion Body"], bpy.data.objects["EASE Motion Garment"]
    n = BETWEEN + 2
    assert (sc.frame_start, sc.frame_end) == (1, n)
    for o in (body, garment):
        assert [k.name for k in o.data.shape_keys.key_blocks][1:] == [f"frame {k:04d}" for k in range(1, n + 1)]
    rep = json.loads(sc["ease_motion_json"])
    assert rep["poses"] == ["A", "P1"] and rep["frames"] == n and len(rep["penetration_pct"]) == n
    assert sc.ease.drape_solver == "default" and rep["solver"] == DrapeOptions().solver  # the core's default
    assert max(rep["penetration_pct"]) <= 0.5
    assert "worst penetration" in sc.ease.motion_status
    # the timeline shows each frame's shape; the body really moves (arms forward in P1)
    first_body = None
    for f in (1, n):
        sc.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        key = np.empty(len(garment.data.vertices) * 3, dtype=np.float32)
        garment.data.shape_keys.key_blocks[f"frame {f:04d}"].data.foreach_get("co", key)
        assert np.allclose(_world(garment, dg), key.reshape(-1, 3), atol=1e-5)
        if first_body is None:
            first_body = _world(body, dg)
    assert np.abs(_world(body, dg) - first_body).max() > 0.2
    # the static body and garment are out of the way in the viewport
    assert all(o.hide_get() for o in scene.objects("body"))


def test_alembic_written_and_read_back(scene, bpy_session):
    bpy = scene.bpy
    sc = bpy.context.scene
    s = sc.ease
    s.motion_path = str(scene.tmp / "motion.abc")
    s.motion_with_body = True
    assert bpy.ops.ease.export_alembic() == {"FINISHED"}
    garment = bpy.data.objects["EASE Motion Garment"]
    n = sc.frame_end
    want = {}
    for f in range(1, n + 1):
        key = np.empty(len(garment.data.vertices) * 3, dtype=np.float32)
        garment.data.shape_keys.key_blocks[f"frame {f:04d}"].data.foreach_get("co", key)
        want[f] = key.reshape(-1, 3)
    before = set(bpy.data.objects)
    assert bpy.ops.wm.alembic_import(filepath=s.motion_path, as_background_job=False) == {"FINISHED"}
    new = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    assert len(new) == 2  # the garment and the body
    back = next(o for o in new if len(o.data.vertices) == len(garment.data.vertices))
    for f in range(1, n + 1):
        sc.frame_set(f)
        got = _world(back, bpy.context.evaluated_depsgraph_get())
        assert got.shape == want[f].shape
        assert np.abs(got - want[f]).max() < 1e-6, f
    for o in new:
        bpy.data.objects.remove(o)


def test_poses_field_is_checked(scene, bpy_session):
    bpy = scene.bpy
    s = bpy.context.scene.ease
    old = s.motion_poses
    try:
        for text, words in (("A, Q9", "'Q9' is not a pose"), ("A", "two poses"), ("P1, P3", "own pose A")):
            s.motion_poses = text
            r = scene.run(bpy.ops.ease.drape_animation)
            assert "ERROR" in r and words in r["ERROR"] and "Poses" in r["ERROR"], (text, r)
    finally:
        s.motion_poses = old


def test_point_cache_plays_in_blender(scene, bpy_session):
    """``ease drape --animation``'s garment_motion.obj + .pc2 (core.drape.animate.write_motion), read
    by Blender's OBJ importer (default axes: the files are Y-up) and its Mesh Cache modifier: every frame's
    vertices back in Blender's frame where they were draped."""
    from drape_synth import revolution_body, tube_skirt

    from core.drape.animate import drape_motion, write_motion

    bpy = scene.bpy
    sc = bpy.context.scene
    bv, bf = revolution_body(48, 60)
    frames = [bv + [0.03 * k, 0.0, 0.01 * k] for k in range(4)]
    r = drape_motion(tube_skirt(), frames, bf, options={"max_frames": 40})
    out = scene.tmp / "pc2"
    write_motion(out, r, frames, bf, ["A", "T"], 2)
    before = set(bpy.data.objects)
    # Y-up by default (OBJ readers' convention): Blender's importer with its default axes, the cache alike
    assert bpy.ops.wm.obj_import(filepath=str(out / "garment_motion.obj")) == {"FINISHED"}
    obj = next(o for o in bpy.data.objects if o not in before)
    mod = obj.modifiers.new("cache", "MESH_CACHE")
    mod.cache_format, mod.filepath = "PC2", str(out / "garment_motion.pc2")
    mod.frame_start = 1.0
    want = r.positions[:, r.used]
    try:
        for f in range(1, len(frames) + 1):
            sc.frame_set(f)
            got = _world(obj, bpy.context.evaluated_depsgraph_get())
            assert got.shape == want[f - 1].shape
            assert np.abs(got - want[f - 1]).max() < 1e-5, f
    finally:
        bpy.data.objects.remove(obj)


def test_studio_renders_the_motion_while_it_is_shown(scene, bpy_session):
    bpy = scene.bpy
    sc = bpy.context.scene
    mats, studio = scene.mod("materials"), scene.mod("render_studio")
    garment = bpy.data.objects["EASE Motion Garment"]
    motion = [garment, bpy.data.objects["EASE Motion Body"]]
    static = scene.objects("body") + scene.objects("garment")
    assert all(o.hide_render for o in static)  # F12 shows the motion alone too
    sc.ease.render_view = "FRONT"
    assert bpy.ops.ease.studio_setup() == {"FINISHED"}
    # the motion garment wears the fabric with its layers, as the static one does
    assert garment.data.uv_layers.get(mats.FABRIC_UV) is not None
    assert garment.data.attributes.get(mats.SEAM_DIST) is not None
    assert garment.data.materials[0].name == "EASE Fabric cotton"
    assert not any(o.hide_render for o in motion) and all(o.hide_render for o in static)
    # hidden in the viewport: the static body and garment render again
    for o in motion:
        o.hide_set(True)
    try:
        studio.show_for(sc, "FRONT")
        assert all(o.hide_render for o in motion) and not any(o.hide_render for o in static)
    finally:
        for o in motion:
            o.hide_set(False)
        studio.show_for(sc, "FRONT")


def test_drape_animation_reports_frames_and_esc_cancels(scene, bpy_session):
    """The interactive Drape Animation runs as a job of :mod:`ease_addon.jobs` (the one job
    mechanism, as Drape): the worker reports each motion frame in the status line, the result
    lands on the main thread's poll; Esc (cancel) leaves the motion as it was. Headless jobs run
    in line: the test switches them to worker threads as in Blender's window."""
    bpy = scene.bpy
    sc = bpy.context.scene
    s = sc.ease
    motion_ops, jobs = scene.mod("motion_ops"), scene.mod("jobs")
    old = s.motion_poses, s.motion_between, jobs.SYNCHRONOUS, s.drape_solver
    real = motion_ops.Motion.compute
    seen = []  # every progress report of the worker, as the status line shows it

    def recording(self, progress):
        def shown(fraction, message):
            progress(fraction, message)
            seen.append(jobs.running(motion_ops.JOB).status())

        return real(self, shown)

    try:
        s.motion_poses, s.motion_between = "A, P1", 1
        jobs.SYNCHRONOUS = False
        # the button's job (headless bpy has no window to invoke in): back at once, the job
        # running; Esc: nothing is applied
        garment = bpy.data.objects["EASE Motion Garment"]
        keys, before = len(garment.data.shape_keys.key_blocks), sc["ease_motion_json"]
        job = motion_ops.start_motion(bpy.context)
        assert jobs.running(motion_ops.JOB) is job and job.thread.is_alive()
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert job.cancelled and job.result is None
        assert s.motion_status.startswith("drape animation cancelled")
        garment = bpy.data.objects["EASE Motion Garment"]
        assert len(garment.data.shape_keys.key_blocks) == keys and sc["ease_motion_json"] == before
        assert jobs.running() is None
        # a run to the end: one progress report a motion frame, applied on the main thread's poll;
        # the Drape panel's Solver reaches the motion's drape too
        motion_ops.Motion.compute = recording
        s.drape_solver = "xpbd"
        job = motion_ops.start_motion(bpy.context)
        job.thread.join(300)
        motion_ops.Motion.compute = real
        assert job.error is None and job.fraction == pytest.approx(1.0)
        frames = [t.split(",")[0] for t in seen if "motion: frame" in t]
        assert all(f.startswith("updating: drape animation") for f in frames), seen
        assert {f.split("(")[1] for f in frames} >= {"motion: frame 1/2", "motion: frame 2/2"}, seen
        assert json.loads(sc["ease_motion_json"]) == json.loads(before)  # not yet: the poll applies it
        jobs.poll()
        assert json.loads(sc["ease_motion_json"])["frames"] == 3
        assert json.loads(sc["ease_motion_json"])["solver"] == "xpbd"
        assert len(bpy.data.objects["EASE Motion Garment"].data.shape_keys.key_blocks) == 4
    finally:
        motion_ops.Motion.compute = real
        jobs.cancel()
        s.motion_poses, s.motion_between, jobs.SYNCHRONOUS, s.drape_solver = old


def _key_rotation(pb, frame: int, axis, degrees: float) -> None:
    from mathutils import Quaternion

    pb.rotation_mode = "QUATERNION"
    pb.rotation_quaternion = Quaternion(axis, np.radians(degrees))
    pb.keyframe_insert("rotation_quaternion", frame=frame)


def test_rig_action_drives_the_motion(scene, bpy_session):
    """Add Rig gives the body an armature of its joints; two bones' rotations and the root's move,
    keyframed, are what Drape Animation (Motion: Rig Action) moves the body through: its frames
    are the rig's deformation of the body, and the garment follows without tunnelling."""
    from mathutils import Vector

    bpy = scene.bpy
    sc = bpy.context.scene
    s = sc.ease
    body = scene.objects("body")[0]
    n_garment = len(bpy.data.objects["EASE Motion Garment"].data.vertices)
    assert bpy.ops.ease.add_rig() == {"FINISHED"}
    rig = bpy.data.objects["EASE Body Rig"]
    model = scene.mod("state").body_model("anny")
    assert [b.name for b in rig.data.bones] == list(model.joint_names)
    assert body.modifiers["EASE Rig"].object == rig and s.motion_source == "ACTION"
    # Add Rig again (after a change of shape): the rig is replaced, nothing piles up
    assert bpy.ops.ease.add_rig() == {"FINISHED"}
    rig = bpy.data.objects["EASE Body Rig"]
    assert len(scene.objects("rig")) == 1 and len(bpy.data.armatures) == 1
    assert [m.type for m in body.modifiers].count("ARMATURE") == 1 and body.modifiers["EASE Rig"].object == rig
    assert len(body.vertex_groups) == len(model.joint_names)
    # the bones are the core's (core.body.lbs.bone_tails): heads at the joints, tails toward the limbs
    from core.body.instance import instance_shape
    from core.body.lbs import bone_tails

    shape = instance_shape(model, scene.mod("data").body_spec(body)["shape"])
    heads = np.asarray(model.joints(shape, None), dtype=float)
    tails = bone_tails(heads, model.data.parents)
    got = np.array([[*b.head_local, *b.tail_local] for b in rig.data.bones])
    assert np.allclose(got, np.hstack([heads, tails]), atol=1e-5)
    try:
        sc.frame_start, sc.frame_end = 1, 7  # moves over frames 1-4, then holds
        root = rig.pose.bones["root"]
        rest = rig.data.bones["root"].matrix_local.to_3x3()
        move = Vector((0.06, 0.0, 0.0))  # 6 cm to the body's left over 3 frames
        for f, m in ((1, 0.0), (4, 1.0)):
            root.location = rest.transposed() @ (move * m)
            root.keyframe_insert("location", frame=f)
            _key_rotation(rig.pose.bones["upperarm01.L"], f, (0.0, 0.0, 1.0), 35 * m)
            _key_rotation(rig.pose.bones["lowerarm01.L"], f, (1.0, 0.0, 0.0), 40 * m)
        # what the rig does to the body in the viewport (Armature modifier, the model's weights)
        deformed = {}
        for f in range(1, 8):
            sc.frame_set(f)
            deformed[f] = _world(body, bpy.context.evaluated_depsgraph_get())
        assert np.abs(deformed[4] - deformed[1]).max() > 0.1  # the arm swings
        assert bpy.ops.ease.drape_animation() == {"FINISHED"}
        rep = json.loads(sc["ease_motion_json"])
        assert rep["source"] == "rig action" and rep["frames"] == 7 and rep["first_frame"] == 1
        assert max(rep["penetration_pct"]) <= 0.5
        mbody, garment = bpy.data.objects["EASE Motion Body"], bpy.data.objects["EASE Motion Garment"]
        assert len(garment.data.vertices) == n_garment
        assert [k.name for k in garment.data.shape_keys.key_blocks][1:] == [f"frame {k:04d}" for k in range(1, 8)]
        assert rig.hide_get() and body.hide_get()
        first = None
        for f in range(1, 8):
            sc.frame_set(f)
            dg = bpy.context.evaluated_depsgraph_get()
            # the motion's body is the model posed by the rig's rotations: the rig's own skinning of it
            assert np.abs(_world(mbody, dg) - deformed[f]).max() < 0.005, f
            g = _world(garment, dg)
            first = g if first is None else first
        # the garment came along with the body (6 cm to the left): each
        # vertex moved as the body under it did, none of it left behind
        from scipy.spatial import cKDTree

        under = cKDTree(deformed[1]).query(first)[1]
        carried = deformed[7][under] - deformed[1][under]
        assert np.linalg.norm(carried.mean(axis=0)) > 0.05
        assert (g - first).mean(axis=0) == pytest.approx(carried.mean(axis=0), abs=0.01)
        assert np.median(np.linalg.norm(g - first - carried, axis=1)) < 0.025
        # none of it left behind (that would be 6 cm off): as close to the body once it holds still as
        # at the first frame, but for the hem still swinging a little (median, 99th percentile)
        gap = [np.percentile(cKDTree(deformed[f]).query(x)[0], [50, 99]) for f, x in ((1, first), (7, g))]
        assert gap[1][0] < gap[0][0] + 0.005 and gap[1][1] < gap[0][1] + 0.015, gap
    finally:
        s.motion_source = "POSES"
        sc.frame_start, sc.frame_end = 1, BETWEEN + 2


def test_drape_animation_adapts_the_pattern_to_the_poses(scene, bpy_session):
    """Adapt to Poses (Animation box): the pattern is adapted to the motion's poses after the
    first, becomes the scene's pattern, and is the one draped; the report says so and gives
    the adaptation's residual stretch before and after, and each frame's stretch."""
    bpy = scene.bpy
    sc = bpy.context.scene
    s = sc.ease
    data = scene.mod("data")
    assert data.stored_pattern(sc).mode == "reference"
    old = s.motion_poses, s.motion_between
    try:
        s.motion_poses, s.motion_between, s.motion_adapt = "A, P1", 1, True
        assert bpy.ops.ease.drape_animation() == {"FINISHED"}
        rep = json.loads(sc["ease_motion_json"])
        assert rep["pattern"] == "pattern adapted to P1" and "pattern adapted to P1" in s.motion_status
        stretch = rep["adaptation_residual_stretch_pct"]["P1"]["top"]
        assert stretch["after"] < stretch["before"]
        assert rep["frames"] == 3 and len(rep["stretch_p95_pct"]) == 3 and max(rep["penetration_pct"]) <= 0.5
        pattern = data.stored_pattern(sc)
        assert pattern.mode == "adapt" and pattern.report["poses"] == ["P1"]
        # nothing to adapt to: refused, naming the setting
        s.motion_poses = "A, A"
        r = scene.run(bpy.ops.ease.drape_animation)
        assert "ERROR" in r and "Adapt to Poses" in r["ERROR"], r
    finally:
        s.motion_poses, s.motion_between = old
        s.motion_adapt = False


def test_drape_animation_takes_the_drape_panels_hold_pins(scene, bpy_session):
    # the Drape panel's Hold Pins reaches the motion's drape options, as its Solver does
    bpy = scene.bpy
    s = bpy.context.scene.ease
    motion_ops, data = scene.mod("motion_ops"), scene.mod("data")
    old = s.motion_poses, s.drape_hold_pins
    try:
        s.motion_poses = "A, P1"
        for hold in (False, True):
            s.drape_hold_pins = hold
            job = motion_ops.motion_job(bpy.context)
            assert job.hold_pins is hold
            assert data.drape_options(job.device, job.solver, job.hold_pins).get("hold_pins", False) is hold
    finally:
        s.motion_poses, s.drape_hold_pins = old
