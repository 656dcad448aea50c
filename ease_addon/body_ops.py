"""Body stage: add the default body (or an SMPL/OBJ file), shape it by
phenotype sliders, measurements or size presets, pose it. Shape and pose
changes move the vertices in place, so the ease layer, the keypoint layers and
everything attached to the body stay."""
from __future__ import annotations

import bpy
import numpy as np

from . import convert, state
from .operators_base import EaseOperator

SYNCING = False   # True while the add-on fills the shape sliders (their update must not fire)


def body_object(context, required: bool = True):
    obj = context.scene.ease.body
    if obj is None or obj.name not in context.scene.objects:
        if required:
            raise state.AddonError("no EASE body in the scene: add one in EASE > Body first")
        return None
    return obj


def body_spec(obj) -> dict:
    """``{"model", "shape", "pose"}`` stored on the body object."""
    return {"model": obj.get("ease_model", "anny"),
            "shape": convert.load_json(obj, "ease_shape", {}) or {},
            "pose": obj.get("ease_pose", "A")}


def body_vertices(obj, spec=None) -> np.ndarray:
    spec = spec or body_spec(obj)
    model = state.body_model(spec["model"])
    return model.vertices(spec["shape"] or None, spec["pose"] if spec["pose"] != "A" else None)


def _fill_shape_props(scene, model, shape: dict) -> None:
    global SYNCING
    SYNCING = True
    try:
        coll = scene.ease.shape
        coll.clear()
        for name, (lo, hi, default) in model.shape_parameters().items():
            item = coll.add()
            item.name = name
            item.min, item.max = float(lo), float(hi)
            item.value = float(shape.get(name, default))
    finally:
        SYNCING = False


def update_body(context, obj, shape=None, pose=None) -> None:
    """Set the body's shape and/or pose: vertices move in place, attached
    objects (seamlines, keypoint markers) follow. Computes first, so a bad
    shape/pose raises before the scene changes."""
    spec = body_spec(obj)
    if shape is not None:
        spec["shape"] = {k: float(v) for k, v in shape.items()}
    if pose is not None:
        spec["pose"] = pose
    verts = body_vertices(obj, spec)
    convert.set_vertices(obj.data, verts)
    convert.store_json(obj, "ease_shape", spec["shape"])
    obj["ease_pose"] = spec["pose"]
    from . import design_ops
    design_ops.refresh_attachments(context, obj, verts)


def apply_shape_from_props(context, report=None) -> bool:
    obj = body_object(context, required=False)
    if obj is None:
        return False
    shape = {}
    for item in context.scene.ease.shape:
        shape[item.name] = float(min(max(item.value, item.min), item.max))
    try:
        update_body(context, obj, shape=shape)
    except Exception as exc:  # a slider must never leave a traceback in the UI
        if report:
            report({"ERROR"}, str(exc))
        return False
    return True


def _skin_material():
    mat = bpy.data.materials.get("EASE Skin")
    if mat is None:
        mat = bpy.data.materials.new("EASE Skin")
        convert.ensure_nodes(mat)
        bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (0.78, 0.62, 0.52, 1.0)
            bsdf.inputs["Roughness"].default_value = 0.6
        mat.diffuse_color = (0.78, 0.62, 0.52, 1.0)
    return mat


def create_body(context, model_name: str, shape=None, pose: str = "A"):
    """Add a body object (or replace the mesh of the current one) and make it the scene's body."""
    from . import ease_ops
    model = state.body_model(model_name)
    shape = dict(model.default_shape() if shape is None else shape)
    verts = model.vertices(shape, None if pose == "A" else pose)
    scene = context.scene
    me = convert.mesh_from_arrays("EASE Body", verts, model.faces)
    obj = convert.new_object("EASE Body", me, state.collection(scene))
    me.materials.append(_skin_material())
    for poly in me.polygons:
        poly.use_smooth = True
    obj["ease_model"] = model_name
    obj["ease_role"] = "body"
    convert.store_json(obj, "ease_shape", shape)
    obj["ease_pose"] = pose
    scene.ease.body = obj
    _fill_shape_props(scene, model, shape)
    ease_ops.init_ease_layer(scene, obj)
    for o in context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj


class EASE_OT_add_body(EaseOperator):
    """Add the default body (Anny) or a body file to the scene"""
    bl_idname = "ease.add_body"
    bl_label = "Add Body"

    source: bpy.props.EnumProperty(items=[("DEFAULT", "Default body", "Anny, embedded"),
                                          ("FILE", "Body file", "the SMPL/SMPL-X/OBJ file set in the panel")],
                                   default="DEFAULT")

    def run(self, context):
        s = context.scene.ease
        if self.source == "FILE":
            if not s.body_file:
                raise state.AddonError("set a body file (SMPL .npz/.pkl or .obj) first")
            name = bpy.path.abspath(s.body_file)
        else:
            name = "anny"
        old = body_object(context, required=False)
        obj = create_body(context, name, pose=s.pose)
        if old is not None and old != obj:
            state.remove_object(old)
        self.report({"INFO"}, f"added body {name} ({len(obj.data.vertices)} vertices)")


class EASE_OT_set_size(EaseOperator):
    """Shape the body to a size preset (XS..XL) of the size chart"""
    bl_idname = "ease.set_size"
    bl_label = "Apply Size"

    size: bpy.props.StringProperty(default="")

    def run(self, context):
        obj = body_object(context)
        s = context.scene.ease
        size = self.size or s.size
        model = state.body_model(body_spec(obj)["model"])
        shape, achieved = state.size_shape(model, size)
        update_body(context, obj, shape=shape)
        _fill_shape_props(context.scene, model, shape)
        obj["ease_size"] = size
        s.measurements_report = _format_measurements(achieved)
        self.report({"INFO"}, f"size {size}: {s.measurements_report}")


class EASE_OT_fit_measurements(EaseOperator):
    """Fit the body's shape to the target measurements (cm)"""
    bl_idname = "ease.fit_measurements"
    bl_label = "Fit Measurements"

    def run(self, context):
        obj = body_object(context)
        s = context.scene.ease
        model = state.body_model(body_spec(obj)["model"])
        targets = {"height": s.height_cm, "chest": s.chest_cm, "waist": s.waist_cm, "hip": s.hip_cm}
        shape, achieved = state.fit_measurements(model, targets)
        update_body(context, obj, shape=shape)
        _fill_shape_props(context.scene, model, shape)
        s.measurements_report = _format_measurements(achieved)
        self.report({"INFO"}, f"fitted: {s.measurements_report}")


class EASE_OT_measure(EaseOperator):
    """Measure the body (height, chest/bust, waist, hip circumferences in cm)"""
    bl_idname = "ease.measure"
    bl_label = "Measure"

    def run(self, context):
        obj = body_object(context)
        spec = body_spec(obj)
        model = state.body_model(spec["model"])
        achieved = state.measure(model, spec["shape"])
        context.scene.ease.measurements_report = _format_measurements(achieved)
        self.report({"INFO"}, context.scene.ease.measurements_report)


class EASE_OT_set_pose(EaseOperator):
    """Pose the body (A, T, P1-P3); the design stays attached"""
    bl_idname = "ease.set_pose"
    bl_label = "Apply Pose"

    pose: bpy.props.StringProperty(default="")

    def run(self, context):
        obj = body_object(context)
        pose = self.pose or context.scene.ease.pose
        update_body(context, obj, pose=pose)
        self.report({"INFO"}, f"pose {pose}")


class EASE_OT_apply_shape(EaseOperator):
    """Apply the phenotype sliders to the body"""
    bl_idname = "ease.apply_shape"
    bl_label = "Apply Shape"

    def run(self, context):
        obj = body_object(context)
        shape = {i.name: float(i.value) for i in context.scene.ease.shape}
        update_body(context, obj, shape=shape)


def _format_measurements(m: dict) -> str:
    """One line: ``height 172.0 cm, chest 94.1 cm, ...``."""
    parts = []
    for k, v in (m or {}).items():
        parts.append(f"{k} {v:.1f} cm" if isinstance(v, (int, float)) else f"{k} {v}")
    return ", ".join(parts)


CLASSES = (EASE_OT_add_body, EASE_OT_set_size, EASE_OT_fit_measurements, EASE_OT_measure,
           EASE_OT_set_pose, EASE_OT_apply_shape)
