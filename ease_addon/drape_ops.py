"""Drape stage: drape the pattern on the body as a modal operator (progress
bar, status text, Esc cancels; the core runs in a worker thread and only the
main thread touches Blender data). The result is a garment object with a
fabric material and two fit-map colour layers (strain, gap)."""
from __future__ import annotations

import json
import threading

import bpy
import numpy as np

from . import convert, ramp, state
from .operators_base import EaseOperator

GARMENT = "EASE Garment"
STRAIN_LAYER = "fit_strain"
GAP_LAYER = "fit_gap"
STRAIN_RANGE = (0.0, 0.10)    # weft strain 0 .. 10 % mapped blue .. red
GAP_RANGE = (0.0, 0.05)       # gap 0 .. 5 cm mapped blue .. red

_RUNNING: list = []           # the operators with a worker running (to cancel on unregister)


def cancel_running() -> None:
    for op in list(_RUNNING):
        op._cancel.set()
    for op in list(_RUNNING):
        if op._thread is not None:
            op._thread.join(timeout=30)
    _RUNNING.clear()


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


def garment_object(context, result, gap=None):
    """Build the garment object from a DrapeResult (replacing an earlier one)."""
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
    me.materials.append(_fabric_material())
    for poly in me.polygons:
        poly.use_smooth = True
    scene = context.scene
    old = state.objects_with_role(scene, "garment")
    obj = convert.new_object(GARMENT, me, state.collection(scene))
    obj["ease_role"] = "garment"
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

    _thread = None
    _timer = None

    def _prepare(self, context):
        from .pattern_ops import stored_pattern
        pattern = stored_pattern(context.scene)
        if pattern is None:
            raise state.AddonError("no pattern: optimize the pattern first (EASE > Pattern)")
        body_v, body_f = _pattern_body(pattern)
        return pattern, body_v, body_f

    def _finish(self, context, result, gap, metrics):
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
        garment_object(context, result, gap)
        state.DRAPES[context.scene.name] = result
        rep = drape_report(result, metrics)
        s = context.scene.ease
        s.drape_json = json.dumps(rep)
        s.drape_status = f"draped: {rep['frames']} frames, {rep['settled']}"

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
        self._finish(context, result, gap, metrics)
        self.report({"INFO"}, s.drape_status)

    # -- interactive: invoke + modal, the core in a worker thread
    def invoke(self, context, event):
        try:
            pattern, body_v, body_f = self._prepare(context)
        except state.USER_ERRORS as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        from ..core.errors import Cancelled
        self._cancel = threading.Event()
        self._state = {"fraction": 0.0, "message": "starting", "result": None, "error": None}
        frames = context.scene.ease.drape_frames
        device = context.scene.ease.drape_device

        def progress(fraction, message):
            self._state["fraction"], self._state["message"] = fraction, message
            if self._cancel.is_set():
                raise Cancelled("drape cancelled")

        def work():
            try:
                self._state["result"] = _compute(pattern, body_v, body_f, frames, progress, device)
            except BaseException as exc:  # handed to the main thread
                self._state["error"] = exc

        self._thread = threading.Thread(target=work, daemon=True)
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        _RUNNING.append(self)
        self._thread.start()
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        if self in _RUNNING:
            _RUNNING.remove(self)

    def modal(self, context, event):
        s = context.scene.ease
        if event.type == "ESC":
            self._cancel.set()
            s.drape_status = "cancelling..."
        if event.type != "TIMER":
            return {"RUNNING_MODAL"} if event.type == "ESC" else {"PASS_THROUGH"}
        st = self._state
        context.window_manager.progress_update(int(100 * st["fraction"]))
        if context.workspace is not None:
            context.workspace.status_text_set(f"EASE drape {100 * st['fraction']:.0f}%: {st['message']} (Esc cancels)")
        if self._thread.is_alive():
            return {"RUNNING_MODAL"}
        self._end(context)
        if st["error"] is not None:
            s.drape_status = f"drape stopped: {st['error']}"
            self.report({"ERROR" if not self._cancel.is_set() else "WARNING"}, s.drape_status)
            return {"CANCELLED"}
        self._finish(context, *st["result"])
        self.report({"INFO"}, s.drape_status)
        return {"FINISHED"}


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
