"""Drape stage: drape the pattern on the body as a modal operator (progress
bar, status text, Esc cancels; the core runs in a worker thread and only the
main thread touches Blender data). The result is a garment object with a
fabric material, two fit-map colour layers (strain, gap) and the pattern
vertex id of each vertex (``ease_vertex_id``, read back by the export)."""
from __future__ import annotations

import json
import threading

import bpy
import numpy as np

from . import convert, ramp, state
from .export_ops import VERTEX_ID, pattern_digest
from .operators_base import EaseOperator
from .pattern_ops import PATTERN_KEY

GARMENT = "EASE Garment"
STRAIN_LAYER = "fit_strain"
GAP_LAYER = "fit_gap"
STRAIN_RANGE = (0.0, 0.10)    # weft strain 0 .. 10 % mapped blue .. red
GAP_RANGE = (0.0, 0.05)       # gap 0 .. 5 cm mapped blue .. red

_JOBS: list = []              # drape jobs running (cancelled on unregister)


class DrapeJob:
    """The core's drape in a worker thread; the main thread polls it.

    ``progress`` state (fraction, message) is written by the worker and read by
    the modal operator; :meth:`cancel` makes the worker's next progress call
    raise ``Cancelled``, so the core stops and nothing is applied.
    """

    def __init__(self, pattern, body_v, body_f, frames: int, device: str = "cpu", digest=None):
        self.fraction, self.message = 0.0, "starting"
        self.digest = digest          # the stored pattern's digest when the drape started
        self.result = None
        self.error = None
        self._cancel = threading.Event()
        self._args = (pattern, body_v, body_f, frames)
        self._device = device
        self._thread = threading.Thread(target=self._work, daemon=True)

    def _progress(self, fraction, message):
        from ..core.errors import Cancelled
        self.fraction, self.message = fraction, message
        if self._cancel.is_set():
            raise Cancelled("drape cancelled")

    def _work(self):
        try:
            self.result = _compute(*self._args, self._progress, self._device)
        except BaseException as exc:  # handed to the main thread
            self.error = exc
        finally:
            if self in _JOBS:
                _JOBS.remove(self)

    def start(self) -> "DrapeJob":
        _JOBS.append(self)
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def done(self) -> bool:
        return not self._thread.is_alive()

    def join(self, timeout=None) -> None:
        self._thread.join(timeout)


def cancel_running() -> None:
    for job in list(_JOBS):
        job.cancel()
    for job in list(_JOBS):
        job.join(timeout=30)
    _JOBS.clear()


def _pattern_body(pattern):
    """(vertices, faces) of the body instance the pattern was solved on."""
    spec = pattern.body or {}
    model = state.body_model(spec.get("model", "anny"))
    shape = spec.get("shape")
    if isinstance(shape, str):
        shape, _ = state.size_shape(model, shape)
    pose = spec.get("pose")
    if pose == "A":
        pose = None
    return model.vertices(shape or None, pose), model.faces


def _map_colors(values, lo, hi) -> np.ndarray:
    # Same ramp as ease (blue = low, red = high) so the legend reads the same way.
    return ramp.ease_to_color(np.clip(values, lo, hi) + 1.0, lo + 1.0, hi + 1.0)


def _fabric_material():
    mat = bpy.data.materials.get("EASE Fabric")
    if mat is None:
        mat = bpy.data.materials.new("EASE Fabric")
        convert.ensure_nodes(mat)
        bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (0.18, 0.32, 0.55, 1.0)
            bsdf.inputs["Roughness"].default_value = 0.9
            for name in ("Sheen Weight", "Sheen"):
                if name in bsdf.inputs:
                    bsdf.inputs[name].default_value = 0.5
                    break
        mat.diffuse_color = (0.18, 0.32, 0.55, 1.0)
    return mat


def _fitmap_material(layer: str):
    from .pattern_ops import _ease_material
    return _ease_material(f"EASE Fit Map {layer}", layer)


def garment_object(context, result, gap=None, digest=None):
    """Build the garment object from a DrapeResult (replacing an earlier one).
    ``digest``: the pattern it was draped from (default: the scene's pattern now)."""
    used = np.asarray(result.used, dtype=bool)
    ids = np.flatnonzero(used)
    remap = -np.ones(len(used), dtype=np.int64)
    remap[ids] = np.arange(len(ids))
    faces = remap[np.asarray(result.faces)]
    me = convert.mesh_from_arrays(GARMENT, np.asarray(result.positions)[ids], faces)
    for layer, values, (lo, hi) in ((STRAIN_LAYER, np.asarray(result.strain_weft)[ids], STRAIN_RANGE),
                                    (GAP_LAYER, None if gap is None else np.asarray(gap)[ids], GAP_RANGE)):
        if values is None:
            continue
        attr = me.color_attributes.new(layer, "FLOAT_COLOR", "POINT")
        attr.data.foreach_set("color", _map_colors(values, lo, hi).ravel())
        me.attributes.new(layer + "_value", "FLOAT", "POINT").data.foreach_set(
            "value", np.asarray(values, dtype=np.float32))
    # which pattern vertex each garment vertex is: the export reads the garment back by it
    me.attributes.new(VERTEX_ID, "INT", "POINT").data.foreach_set("value", ids.astype(np.int32))
    me.materials.append(_fabric_material())
    for poly in me.polygons:
        poly.use_smooth = True
    scene = context.scene
    old = state.objects_with_role(scene, "garment")
    obj = convert.new_object(GARMENT, me, state.collection(scene))
    obj["ease_role"] = "garment"
    obj["ease_pattern"] = digest or pattern_digest(scene.get(PATTERN_KEY, ""))   # draped from this pattern
    for o in old:
        state.remove_object(o)
    apply_fitmap(scene)
    return obj


def apply_fitmap(scene) -> None:
    """Colour the garment by the chosen fit map (or the plain fabric)."""
    mode = scene.ease.fitmap
    for obj in state.objects_with_role(scene, "garment"):
        me = obj.data
        layer = {"STRAIN": STRAIN_LAYER, "GAP": GAP_LAYER}.get(mode)
        if layer is not None and me.color_attributes.get(layer) is not None:
            mat = _fitmap_material(layer)
            me.color_attributes.active_color = me.color_attributes[layer]
        else:
            mat = _fabric_material()
        if me.materials:
            me.materials[0] = mat
        else:
            me.materials.append(mat)


def drape_report(result, metrics=None) -> dict:
    """Key figures of a drape (and its fit metrics) for the panel."""
    out = {"frames": int(result.frames), "settled": result.settle_reason,
           "time s": round(float(result.timings.get("total", 0.0)), 2),
           "mean weft strain %": round(100 * float(np.mean(np.asarray(result.strain_weft)[result.used])), 2),
           "device": result.device}
    a = (metrics or {}).get("all") or {}
    if a:
        out["mean gap mm"] = round(float(a["gap_mm"]["mean"]), 1)
        out["penetration %"] = round(float(a["penetration_pct"]), 2)
        out["seam gap max mm"] = round(float(a["seam_gap_mm"]["max"]), 2)
    return out


def _compute(pattern, body_v, body_f, frames, progress, device="cpu"):
    from ..core.drape import drape
    from ..core.progress import sub
    result = drape(pattern, body_v, body_f, options={"max_frames": int(frames), "device": device},
                   progress=sub(progress, 0.0, 0.9))
    if progress is not None:
        progress(0.92, "measuring the fit (gap, strain)")
    gap, metrics = state.garment_gap(result, pattern, body_v, body_f)
    return result, gap, metrics


class EASE_OT_drape(EaseOperator):
    """Drape the pattern on the body (Esc cancels)"""
    bl_idname = "ease.drape"
    bl_label = "Drape"

    _job = None
    _timer = None

    def _prepare(self, context):
        from .pattern_ops import stored_pattern
        pattern = stored_pattern(context.scene)
        if pattern is None:
            raise state.AddonError("no pattern: optimize the pattern first (EASE > Pattern)")
        body_v, body_f = _pattern_body(pattern)
        return pattern, body_v, body_f

    # -- synchronous (scripts, tests): execute
    def run(self, context):
        pattern, body_v, body_f = self._prepare(context)
        wm = context.window_manager
        s = context.scene.ease
        wm.progress_begin(0, 100)

        def progress(fraction, message):
            wm.progress_update(int(100 * fraction))
        try:
            result, gap, metrics = _compute(pattern, body_v, body_f, s.drape_frames, progress, s.drape_device)
        finally:
            wm.progress_end()
        apply_drape(context, result, gap, metrics)
        self.report({"INFO"}, s.drape_status)

    # -- interactive: invoke + modal, the core in a worker thread
    def invoke(self, context, event):
        try:
            pattern, body_v, body_f = self._prepare(context)
        except state.USER_ERRORS as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        s = context.scene.ease
        # the pattern may change while the drape runs: the garment records the one it was draped from
        digest = pattern_digest(context.scene.get(PATTERN_KEY, ""))
        self._job = DrapeJob(pattern, body_v, body_f, s.drape_frames, s.drape_device, digest).start()
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        status = step_job(context, self._job, event.type)
        if status == "RUNNING":
            return {"RUNNING_MODAL"} if event.type in ("ESC", "TIMER") else {"PASS_THROUGH"}
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        s = context.scene.ease
        if status == "FINISHED":
            self.report({"INFO"}, s.drape_status)
            return {"FINISHED"}
        self.report({"WARNING" if self._job.cancelled else "ERROR"}, s.drape_status)
        return {"CANCELLED"}


def apply_drape(context, result, gap, metrics, digest=None) -> None:
    """Show a finished drape: garment object, fit maps, report (main thread)."""
    from .body_ops import body_object, body_spec, update_body
    from .pattern_ops import stored_pattern
    # show the garment on the body it was draped on
    obj = body_object(context, required=False)
    pspec = stored_pattern(context.scene).body or {}
    if obj is not None:
        spec = body_spec(obj)
        shape = pspec.get("shape")
        if isinstance(shape, str):
            shape, _ = state.size_shape(state.body_model(spec["model"]), shape)
        pose = pspec.get("pose") or "A"
        if (shape and dict(shape) != spec["shape"]) or (isinstance(pose, str) and pose != spec["pose"]):
            update_body(context, obj, shape=dict(shape) if shape else None,
                        pose=pose if isinstance(pose, str) else None)
    garment_object(context, result, gap, digest)
    rep = drape_report(result, metrics)
    s = context.scene.ease
    s.drape_json = json.dumps(rep)
    s.drape_status = f"draped: {rep['frames']} frames, {rep['settled']}"


def step_job(context, job: DrapeJob, event_type: str) -> str:
    """One modal step for ``event_type``: Esc cancels; a timer tick shows the
    progress and, once the worker is done, applies the result (main thread).
    Returns ``"RUNNING"``, ``"FINISHED"`` or ``"CANCELLED"``."""
    s = context.scene.ease
    if event_type == "ESC":
        job.cancel()
        s.drape_status = "cancelling..."
    if event_type != "TIMER":
        return "RUNNING"
    try:
        context.window_manager.progress_update(int(100 * job.fraction))
    except Exception:
        pass
    if context.workspace is not None:
        context.workspace.status_text_set(f"EASE drape {100 * job.fraction:.0f}%: {job.message} (Esc cancels)")
    if not job.done():
        return "RUNNING"
    if job.error is not None:
        s.drape_status = f"drape {'cancelled' if job.cancelled else 'stopped'}: {job.error}"
        return "CANCELLED"
    apply_drape(context, *job.result, digest=job.digest)
    return "FINISHED"


class EASE_OT_fitmap(EaseOperator):
    """Colour the garment by strain, gap or plain fabric"""
    bl_idname = "ease.fitmap"
    bl_label = "Fit Map"

    mode: bpy.props.EnumProperty(items=[("NONE", "Fabric", ""), ("STRAIN", "Strain", ""), ("GAP", "Gap", "")])

    def run(self, context):
        if not state.objects_with_role(context.scene, "garment"):
            raise state.AddonError("no draped garment: drape first")
        context.scene.ease.fitmap = self.mode   # its update applies the map


CLASSES = (EASE_OT_drape, EASE_OT_fitmap)
