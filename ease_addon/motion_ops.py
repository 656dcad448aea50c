"""Drape Animation: the garment carried through a pose sequence on the moving body
(:func:`core.drape.animate.drape_motion`), and its Alembic export.

*Drape Animation* (Drape panel, Animation box) takes the poses named in *Poses*
(``A, P1, P3``: presets; the first is the pattern's own pose) with *In-betweens*
frames from each to the next, drapes the scene's pattern on the first and carries
it through the others, and keeps the result as two objects, ``EASE Motion Body``
and ``EASE Motion Garment`` (role ``motion``): one shape key a frame, keyed so the
timeline (frames 1..K, set on the scene) plays the motion. The static body and
garment are hidden in the viewport and the render; the studio renders the motion
objects while they are shown in the viewport (hide them to render the static ones).
The figures per frame (penetration, seconds) are kept in the scene
(``ease_motion_json``) and the worst frame is shown in the panel.

*Export Alembic* writes the motion objects (the garment, and the body when *With
body* is on) with Blender's own Alembic exporter over frames 1..K: an ``.abc``
other DCC tools read.
"""

from __future__ import annotations

import json
import os

import bpy
import numpy as np

from . import build, convert, data, materials, state
from .objects import objects_with_role, select_only, window_progress
from .operators_base import EaseOperator

MOTION_BODY = "EASE Motion Body"
MOTION_GARMENT = data.MOTION_GARMENT
MOTION_KEY = "ease_motion_json"


def motion_object(scene, name: str, frames: np.ndarray, faces: np.ndarray, material):
    """The object ``name`` (role ``motion``) with a shape key per frame of ``frames`` (K, V, 3),
    keyed so that frame k (1-based) of the timeline shows ``frames[k - 1]``."""
    me = convert.mesh_from_arrays(name, frames[0], faces)
    me.materials.append(material)
    for poly in me.polygons:
        poly.use_smooth = True
    obj = build.put_object(scene, name, me, "motion")
    obj.shape_key_add(name="Basis", from_mix=False)
    keys = []
    for k, f in enumerate(frames):
        key = obj.shape_key_add(name=f"frame {k + 1:04d}", from_mix=False)
        key.data.foreach_set("co", np.ascontiguousarray(f, dtype=np.float32).ravel())
        keys.append(key)
    for k, key in enumerate(keys):
        for frame in (k, k + 1, k + 2):
            if 1 <= frame <= len(keys):
                key.value = 1.0 if frame == k + 1 else 0.0
                key.keyframe_insert("value", frame=frame)
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


def _motion(context):
    """(body frames (K, V, 3), body faces, MotionResult, poses) of the scene's pattern through the Poses."""
    from ..core.body import load_body
    from ..core.body.instance import spec_instance
    from ..core.drape.animate import drape_motion, parse_poses, pose_frames

    scene, s = context.scene, context.scene.ease
    poses = parse_poses(s.motion_poses, "Poses")
    pattern = data.required_pattern(scene, "to animate")
    spec = dict(pattern.body or {})
    own = spec.get("pose") or "A"
    if poses[0] != own:
        raise state.AddonError(
            f"Poses: the sequence starts at the pattern's own pose {own} (its garment was cut there), not {poses[0]}"
        )
    model = load_body(spec.get("model", "anny"))
    frames = pose_frames(model, spec.get("shape"), poses, int(s.motion_between))
    _, faces = spec_instance(spec, model)
    with window_progress(context) as progress:
        result = drape_motion(pattern, frames, faces, options={"device": s.drape_device}, progress=progress)
    return np.stack(frames), faces, result, poses


class EASE_OT_drape_animation(EaseOperator):
    """Drape the garment through the pose sequence (Poses, In-betweens): shape-keyed motion objects"""

    bl_idname = "ease.drape_animation"
    bl_label = "Drape Animation"
    needs = ("pattern",)

    def run(self, context):
        from ..core.drape.animate import motion_report

        scene, s = context.scene, context.scene.ease
        frames, faces, r, poses = _motion(context)
        used = np.asarray(r.used, dtype=bool)
        remap = -np.ones(len(used), dtype=np.int64)
        remap[used] = np.arange(int(used.sum()))
        body = motion_object(scene, MOTION_BODY, frames, faces, materials.skin())
        garment = motion_object(
            scene, MOTION_GARMENT, r.positions[:, used], remap[np.asarray(r.faces)], materials.fabric()
        )
        # the pattern vertex of each vertex: the studio dresses it in its fabric as the static garment
        vid = garment.data.attributes.new(data.VERTEX_ID, "INT", "POINT")
        vid.data.foreach_set("value", np.flatnonzero(used).astype(np.int32))
        scene.frame_start, scene.frame_end = 1, len(frames)
        scene.frame_set(1)
        for o in objects_with_role(scene, "body") + objects_with_role(scene, "garment"):
            o.hide_set(True)
            o.hide_render = True
        report = motion_report(r, poses, int(s.motion_between))
        scene[MOTION_KEY] = json.dumps(report)
        worst = report["worst_penetration_pct"]
        s.motion_status = (
            f"{len(frames)} frames ({' -> '.join(poses)}), worst penetration {worst:.2f} %, "
            f"stretch p95 up to {max(report['stretch_p95_pct']):.1f} %, "
            f"{np.mean(r.frame_seconds) if len(r.frame_seconds) else 0:.2f} s a frame"
        )
        self.report(
            {"INFO"},
            f"{body.name}, {garment.name}: {s.motion_status}; the static body and garment are hidden in the viewport",
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
        end = len(keys.key_blocks) - 1 if keys else 1
        before = [o for o in context.view_layer.objects if o.select_get()]
        active = context.view_layer.objects.active
        try:
            select_only(context, objs[0])
            for o in objs[1:]:
                o.select_set(True)
            r = bpy.ops.wm.alembic_export(
                filepath=path,
                start=1,
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
        self.report({"INFO"}, f"wrote {path}: {', '.join(o.name for o in objs)}, frames 1-{end}")


CLASSES = (EASE_OT_drape_animation, EASE_OT_export_alembic)
