"""Drape Animation: the garment carried through the body's motion
(:func:`core.drape.animate.drape_motion`), the body's rig, and the Alembic export.

*Drape Animation* (Drape panel, Animation box) takes the motion from *Motion*:

- *Poses*: the presets named in *Poses* (``A, P1, P3``; the first the pattern's
  own pose) with *In-betweens* frames from each to the next;
- *Rig Action*: the body rig's bones (*Add Rig*: an armature whose bones are the
  body's joints, deforming the body through an Armature modifier with the model's
  own skinning weights) over the scene's frame range, as an artist keyframed
  them: each frame's bone rotations (and the root bone's move) become an EASE
  pose (:func:`core.drape.animate.pose_from_bone_rotations`) that the model
  skins. The garment settles on the pattern's own pose first, then moves to the
  first frame (split into small steps) and through the others.

With *Adapt to Poses* the pattern is first adapted to the motion's poses (the
presets after the first, or the rig's keyframed poses) within the design's
stretch tolerances (:func:`core.workflows.adapt`); that pattern replaces the
pieces beside the body and is the one draped.

The drape runs as the static one does, as a background job (:mod:`.jobs`): in a
worker thread, its progress per frame in the status bar, Esc cancels (nothing is
applied); in line from a script or headless. The result is two
objects, ``EASE Motion Body`` and ``EASE Motion Garment`` (role ``motion``): one
shape key a frame, keyed so the timeline plays the motion. The static body and
garment are hidden in the viewport and the render; the studio renders the motion
objects while they are shown in the viewport (hide them to render the static ones).
The figures per frame (penetration, residual stretch, seconds) are kept in the
scene (``ease_motion_json``) and the worst frame is shown in the panel.

*Export Alembic* writes the motion objects (the garment, and the body when *With
body* is on) with Blender's own Alembic exporter over the motion's frames: an
``.abc`` other DCC tools read.
"""

from __future__ import annotations

import json
import os

import bpy
import numpy as np

from . import build, convert, data, jobs, materials, state, sync
from .objects import objects_with_role, remove_object, role_object, select_only
from .operators_base import EaseOperator

MOTION_BODY = "EASE Motion Body"
MOTION_GARMENT = data.MOTION_GARMENT
MOTION_KEY = "ease_motion_json"
RIG = "EASE Body Rig"
RIG_MODIFIER = "EASE Rig"
FRAME_START = "ease_frame_start"  # on a motion object: the timeline frame of its first shape key


def motion_object(scene, name: str, frames: np.ndarray, faces: np.ndarray, material, start: int = 1):
    """The object ``name`` (role ``motion``) with a shape key per frame of ``frames`` (K, V, 3),
    keyed so that frame ``start + k`` of the timeline shows ``frames[k]``."""
    me = convert.mesh_from_arrays(name, frames[0], faces)
    me.materials.append(material)
    convert.smooth(me)
    obj = build.put_object(scene, name, me, "motion")
    obj[FRAME_START] = int(start)
    obj.shape_key_add(name="Basis", from_mix=False)
    keys = []
    for k, f in enumerate(frames):
        key = obj.shape_key_add(name=f"frame {start + k:04d}", from_mix=False)
        key.data.foreach_set("co", np.ascontiguousarray(f, dtype=np.float32).ravel())
        keys.append(key)
    for k, key in enumerate(keys):
        for i in (k - 1, k, k + 1):
            if 0 <= i < len(keys):
                key.value = 1.0 if i == k else 0.0
                key.keyframe_insert("value", frame=start + i)
    action = obj.data.shape_keys.animation_data.action if obj.data.shape_keys.animation_data else None
    for fc in _fcurves(action):
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
    return obj


def _fcurves(action) -> list:
    """The F-curves of ``action`` (Blender 5's layered actions and the older flat ones)."""
    if action is None:
        return []
    if hasattr(action, "fcurves") and len(action.fcurves):
        return list(action.fcurves)
    out = []
    for layer in getattr(action, "layers", []):
        for strip in layer.strips:
            for bag in getattr(strip, "channelbags", []):
                out += list(bag.fcurves)
    return out


# ----------------------------------------------------------------------------- the body's rig


def rig_object(context, required: bool = False):
    """The body's rig (the armature its Armature modifier names), else None (or AddonError)."""
    body = data.body_object(context, required=required)
    mod = body.modifiers.get(RIG_MODIFIER) if body is not None else None
    rig = mod.object if mod is not None else None
    if rig is None or rig.name not in context.scene.objects:
        if required:
            raise state.AddonError("Motion: Rig Action needs the body's rig: press Add Rig (EASE > Drape, Animation)")
        return None
    return rig


def build_rig(context, body):
    """The armature of ``body`` (an EASE body of the default model in pose A): a bone per joint at
    the model's joints, and on the body an Armature modifier with the model's skinning weights
    (a vertex group per joint). Replaces the body's earlier rig."""
    from ..core.body.instance import instance_shape
    from ..core.body.lbs import bone_tails

    spec = data.body_spec(body)
    model = state.body_model(spec["model"])
    if not hasattr(model, "joint_names") or not hasattr(model, "data"):
        raise state.AddonError(f"Add Rig: the body model {spec['model']} has no skeleton (the default body, Anny, has)")
    if spec["pose"] not in ("A", None):
        raise state.AddonError(
            f"Add Rig: the rig is built on the body's rest pose A, the body stands in {spec['pose']}: "
            "set Pose to A first (EASE > Body)"
        )
    names = list(model.joint_names)
    parents = np.asarray(model.data.parents)
    heads = np.asarray(model.joints(instance_shape(model, spec["shape"]), None), dtype=float)
    tails = bone_tails(heads, parents)
    weights = model.data.sparse_weights.tocsc()
    scene = context.scene
    old = rig_object(context)
    if old is not None:
        arm = old.data
        remove_object(old)
        if arm is not None and arm.users == 0:
            bpy.data.armatures.remove(arm)
    arm = bpy.data.armatures.new(RIG)
    rig = role_object(scene, RIG, arm, "rig")
    rig.matrix_world = body.matrix_world.copy()
    rig.show_in_front = True
    arm.display_type = "STICK"
    view = context.view_layer
    active, mode_before = view.objects.active, None
    view.objects.active = rig
    try:
        mode_before = rig.mode
        bpy.ops.object.mode_set(mode="EDIT")
        bones = []
        for j, name in enumerate(names):
            eb = arm.edit_bones.new(name)
            eb.head, eb.tail = heads[j].tolist(), tails[j].tolist()
            bones.append(eb)
        for j, p in enumerate(parents):
            if p >= 0:
                bones[j].parent = bones[p]
                bones[j].use_connect = False
        bpy.ops.object.mode_set(mode=mode_before or "OBJECT")
    finally:
        view.objects.active = active
    for pb in rig.pose.bones:
        pb.rotation_mode = "QUATERNION"
    for name in names:
        vg = body.vertex_groups.get(name)
        if vg is not None:
            body.vertex_groups.remove(vg)
    for j, name in enumerate(names):
        vg = body.vertex_groups.new(name=name)
        lo, hi = weights.indptr[j], weights.indptr[j + 1]
        for v, w in zip(weights.indices[lo:hi].tolist(), weights.data[lo:hi].tolist()):
            if w > 0:
                vg.add([v], w, "REPLACE")
    mod = body.modifiers.get(RIG_MODIFIER) or body.modifiers.new(RIG_MODIFIER, "ARMATURE")
    mod.object = rig
    mod.use_vertex_groups, mod.use_bone_envelopes = True, False
    mod.use_deform_preserve_volume = False  # linear blend skinning: the model's own
    return rig


def action_poses(context, rig, frames) -> tuple:
    """(JSON poses, root moves (K, 3)) of the rig at the timeline's ``frames``: each bone's
    posed orientation against its rest one (constraints and IK included), in the body's frame."""
    from ..core.drape.animate import pose_from_bone_rotations

    scene = context.scene
    names = [b.name for b in rig.data.bones]
    index = {n: i for i, n in enumerate(names)}
    parents = np.array([index[b.parent.name] if b.parent else -1 for b in rig.data.bones])
    rest = np.array([np.array(b.matrix_local) for b in rig.data.bones])
    root = int(np.flatnonzero(parents < 0)[0])
    before = scene.frame_current
    poses, moves = [], []
    try:
        for f in frames:
            scene.frame_set(int(f))
            posed = np.array([np.array(pb.matrix) for pb in (rig.pose.bones[n] for n in names)])
            world = posed[:, :3, :3] @ np.swapaxes(rest[:, :3, :3], 1, 2)
            poses.append(pose_from_bone_rotations(names, parents, world))
            moves.append(posed[root, :3, 3] - rest[root, :3, 3])
    finally:
        scene.frame_set(before)
    return poses, np.array(moves)


def _key_frames(rig, first: int, last: int) -> list:
    """The frames within first..last where the rig's action has a key (the poses an artist set)."""
    anim = rig.animation_data
    keys = {round(kp.co[0]) for fc in _fcurves(anim.action if anim else None) for kp in fc.keyframe_points}
    return sorted(f for f in keys if first <= f <= last)


class EASE_OT_add_rig(EaseOperator):
    """Give the body an armature (a bone per joint, the model's skinning weights) to keyframe"""

    bl_idname = "ease.add_rig"
    bl_label = "Add Rig"
    needs = ("body",)

    def run(self, context):
        body = data.body_object(context)
        rig = build_rig(context, body)
        context.scene.ease.motion_source = "ACTION"
        self.report(
            {"INFO"},
            f"{rig.name}: {len(rig.data.bones)} bones deform {body.name}; keyframe them in Pose Mode, "
            "then Drape Animation (Motion: Rig Action)",
        )


# ----------------------------------------------------------------------------- Drape Animation


JOB = "drape animation"  # the job's name (a new Drape Animation replaces a running one)


class Motion:
    """The body's frames, the pattern (adapted to the motion's poses when asked) and its drape
    through them (:meth:`compute`, in the worker); the motion objects from them (:meth:`apply`,
    on the main thread)."""

    def __init__(
        self,
        pattern,
        model,
        shape,
        motion: dict,
        device: str,
        prep=None,
        adapt_to=(),
        solver="default",
        hold_pins=False,
    ):
        self.pattern, self.model, self.shape, self.motion = pattern, model, shape, motion
        self.device, self.prep, self.adapt_to, self.solver = device, prep, list(adapt_to), solver
        self.hold_pins = bool(hold_pins)

    def compute(self, progress):
        from ..core import workflows as wf
        from ..core.drape.animate import drape_motion, pose_frames, posed_frames
        from ..core.progress import sub

        m = self.motion
        if m["source"] == "POSES":
            frames = pose_frames(self.model, self.shape, m["poses"], m["between"])
        else:  # the pattern's own pose, then the rig's frames (bones the model lacks, e.g. IK targets, left out)
            joints = set(self.model.joint_names)
            poses = [{k: v for k, v in pose.items() if k in joints} for pose in m["poses"]]
            frames = posed_frames(self.model, self.shape, [m["own"]] + poses, [np.zeros(3)] + list(m["moves"]))
        pattern, adapted = self.pattern, None
        if self.adapt_to:
            adapted = wf.adapt(self.prep, self.adapt_to, start=self.pattern, progress=sub(progress, 0.0, 0.1))
            pattern = adapted.pattern
        faces = self.model.faces
        result = drape_motion(
            pattern,
            frames,
            faces,
            options=data.drape_options(self.device, self.solver, self.hold_pins),
            progress=sub(progress, 0.1 if adapted else 0.0, 1.0),
        )
        if m["source"] == "ACTION":
            frames, result = frames[1:], _without_first(result)
        return np.stack(frames), faces, result, adapted

    def apply(self, result) -> None:
        from ..core.drape.animate import motion_report
        from ..core.geom.mesh import compact_vertices

        scene, s = bpy.context.scene, bpy.context.scene.ease
        frames, faces, r, adapted = result
        m = self.motion
        if adapted is not None:  # the adapted pattern is the scene's pattern now, beside the body
            sync.show_pattern(bpy.context, adapted.pattern)
            s.fit_json = json.dumps(adapted.figures)
        ids, gfaces = compact_vertices(r.faces, r.used)
        start = m["start"]
        motion_object(scene, MOTION_BODY, frames, faces, materials.skin(), start)
        garment = motion_object(scene, MOTION_GARMENT, r.positions[:, ids], gfaces, materials.fabric(), start)
        # the pattern vertex of each vertex: the studio dresses it in its fabric as the static garment
        vid = garment.data.attributes.new(data.VERTEX_ID, "INT", "POINT")
        vid.data.foreach_set("value", ids.astype(np.int32))
        scene.frame_start, scene.frame_end = start, start + len(frames) - 1
        scene.frame_set(start)
        hide = objects_with_role(scene, "body") + objects_with_role(scene, "garment")
        rig = bpy.data.objects.get(RIG)
        if rig is not None and rig.get("ease_role") == "rig":
            hide.append(rig)
        for o in hide:
            o.hide_set(True)
            o.hide_render = True
        pattern = adapted.pattern if adapted is not None else self.pattern
        report = motion_report(r, m["label"], m["between"], pattern)
        report["source"] = "rig action" if m["source"] == "ACTION" else "poses"
        report["first_frame"] = start
        scene[MOTION_KEY] = json.dumps(report)
        worst = report["worst_penetration_pct"]
        s.motion_status = (
            f"{len(frames)} frames ({m['title']}, {report['pattern']}), worst penetration {worst:.2f} %, "
            f"stretch p95 up to {max(report['stretch_p95_pct']):.1f} %, "
            f"{np.mean(r.frame_seconds) if len(r.frame_seconds) else 0:.2f} s a frame"
        )


def _without_first(result):
    """``result`` without its first frame (the settle on the pattern's own pose before a rig's frames)."""
    import dataclasses

    return dataclasses.replace(
        result,
        positions=result.positions[1:],
        penetration=result.penetration[1:],
        stretch=result.stretch[1:],
        frame_seconds=result.frame_seconds[1:],
    )


def motion_input(context) -> dict:
    """What Drape Animation moves the body through (main thread: reads the scene), checked:
    ``source``, ``poses`` (names, or JSON poses of the rig's frames), ``between``, the timeline
    ``start``, ``label`` (for the report), ``title`` (for the status) and ``adapt_to``."""
    from ..core.drape.animate import parse_poses

    scene, s = context.scene, context.scene.ease
    pattern = data.required_pattern(scene, "to animate")
    own = (pattern.body or {}).get("pose") or "A"
    if s.motion_source == "POSES":
        poses = parse_poses(s.motion_poses, "Poses")
        if poses[0] != own:
            raise state.AddonError(
                f"Poses: the sequence starts at the pattern's own pose {own} (its garment was cut there), "
                f"not {poses[0]}"
            )
        return {
            "source": "POSES",
            "poses": poses,
            "between": int(s.motion_between),
            "start": 1,
            "label": poses,
            "title": " -> ".join(poses),
            "adapt_to": [p for p in dict.fromkeys(poses[1:]) if p != own],
        }
    rig = rig_object(context, required=True)
    first, last = int(scene.frame_start), int(scene.frame_end)
    if last <= first:
        raise state.AddonError(f"Motion: the scene's frame range {first}-{last} has one frame; set End after Start")
    frames = list(range(first, last + 1))
    poses, moves = action_poses(context, rig, frames)
    keyed = [frames.index(f) for f in _key_frames(rig, first, last)]
    adapt_to = [poses[i] for i in keyed if poses[i]]
    return {
        "source": "ACTION",
        "own": own,
        "poses": poses,
        "moves": moves,
        "between": 0,
        "start": first,
        "label": [f"frame {f}" for f in (first, last)],
        "title": f"{rig.name} frames {first}-{last}",
        "adapt_to": adapt_to,
    }


def motion_job(context) -> Motion:
    """Drape Animation's work, not started (main thread: reads the scene; refuses bad input)."""
    from ..core.body import load_body

    s = context.scene.ease
    pattern = data.required_pattern(context.scene, "to animate")
    motion = motion_input(context)
    spec = dict(pattern.body or {})
    model = load_body(spec.get("model", "anny"))
    prep, adapt_to = None, ()
    if s.motion_adapt:
        adapt_to = motion["adapt_to"]
        if not adapt_to:
            raise state.AddonError(
                "Adapt to Poses: the motion has no pose but the pattern's own to adapt to "
                "(name poses after the first, or keyframe the rig's bones)"
            )
        prep = data.prepared(context)
    return Motion(
        pattern, model, spec.get("shape"), motion, s.drape_device, prep, adapt_to, s.drape_solver, s.drape_hold_pins
    )


def start_motion(context, sync=None) -> jobs.Job:
    """Drape Animation as the job :data:`JOB` (``sync``: :func:`.jobs.start`'s); the motion
    objects are made when it lands."""
    work = motion_job(context)
    return jobs.start_step(
        JOB, "drape animation", work.compute, work.apply, "motion_status", "Drape Animation", sync=sync
    )


class EASE_OT_drape_animation(jobs.Background, EaseOperator):
    """Drape the garment through the motion (Poses, or the rig's action): shape-keyed motion objects (Esc cancels)"""

    bl_idname = "ease.drape_animation"
    bl_label = "Drape Animation"
    needs = ("pattern",)

    def run(self, context):
        job = start_motion(context, sync=self.job_sync())
        if job.thread is not None:
            self.report({"INFO"}, "Drape Animation runs in the background (Esc cancels)")
            return
        self.report(
            {"INFO"},
            f"{MOTION_BODY}, {MOTION_GARMENT}: {context.scene.ease.motion_status}; "
            "the static body and garment are hidden in the viewport",
        )


class EASE_OT_export_alembic(EaseOperator):
    """Write the motion (garment, and the body with With body) to an Alembic file (.abc)"""

    bl_idname = "ease.export_alembic"
    bl_label = "Export Alembic"
    needs = ("motion", "motion_path")

    def run(self, context):
        s = context.scene.ease
        path = data.output_path(s.motion_path, "Alembic to")
        if not path.lower().endswith(".abc"):
            path += ".abc"
        os.makedirs(os.path.dirname(os.path.abspath(path)) or ".", exist_ok=True)
        objs = [bpy.data.objects[MOTION_GARMENT]]
        if s.motion_with_body and bpy.data.objects.get(MOTION_BODY) is not None:
            objs.append(bpy.data.objects[MOTION_BODY])
        keys = objs[0].data.shape_keys
        start = int(objs[0].get(FRAME_START, 1))
        end = start + (len(keys.key_blocks) - 2 if keys else 0)
        before = [o for o in context.view_layer.objects if o.select_get()]
        active = context.view_layer.objects.active
        try:
            select_only(context, objs[0])
            for o in objs[1:]:
                o.select_set(True)
            r = bpy.ops.wm.alembic_export(
                filepath=path,
                start=start,
                end=end,
                selected=True,
                uvs=False,
                face_sets=False,
                export_hair=False,
                export_particles=False,
            )
        finally:
            for o in context.view_layer.objects:
                o.select_set(o in before)
            context.view_layer.objects.active = active
        if r != {"FINISHED"} or not os.path.exists(path):
            raise state.AddonError(f"Blender's Alembic exporter wrote nothing to {path}")
        self.report({"INFO"}, f"wrote {path}: {', '.join(o.name for o in objs)}, frames {start}-{end}")


CLASSES = (EASE_OT_add_rig, EASE_OT_drape_animation, EASE_OT_export_alembic)
