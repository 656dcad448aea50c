"""Ease stage: the ease field is the colour layer "ease" on the body.

Blender's own brushes paint it (Vertex Paint, or Sculpt-mode paint); the
add-on sets the brush colour from the ease ramp (:mod:`.ramp`), sets uniform
or gradient ease per panel by writing the layer, and converts the layer to
per-triangle ease in the design.
"""
from __future__ import annotations


import bpy
import numpy as np

from . import convert, ramp, state
from .body_ops import body_object
from .operators_base import EaseOperator


def ramp_range(scene) -> tuple:
    s = scene.ease
    lo, hi = float(s.ease_min), float(s.ease_max)
    try:
        ramp.check_range(lo, hi)
    except ValueError as exc:
        raise state.AddonError(str(exc)) from None
    return lo, hi


def refresh_legend(scene) -> None:
    s = scene.ease
    s.legend.clear()
    lo, hi = float(s.ease_min), float(s.ease_max)
    if not lo < hi:
        return
    for e, rgba in ramp.legend(lo, hi, 5):
        item = s.legend.add()
        item.ease = e
        item.color = rgba


def init_ease_layer(scene, obj, ease: float = 1.0) -> None:
    """Create the "ease" layer on a body (uniform ``ease``) unless it has one."""
    lo, hi = ramp_range(scene)
    if obj.data.color_attributes.get(convert.EASE_LAYER) is None:
        convert.ensure_color_layer(obj.data, fill=ramp.ease_to_color(ease, lo, hi))
    else:
        convert.ensure_color_layer(obj.data)
    obj.data["ease_ramp"] = [lo, hi]
    refresh_legend(scene)


def layer_range(obj, scene) -> tuple:
    """The ramp range the layer was painted with (stored on the mesh); the
    scene's range for a layer that has none yet."""
    r = obj.data.get("ease_ramp")
    if r is not None and len(r) == 2:
        return float(r[0]), float(r[1])
    return ramp_range(scene)


def vertex_ease(obj, scene) -> np.ndarray:
    """Per-vertex ease (V,) decoded from the layer (corner layers are averaged per vertex)."""
    lo, hi = layer_range(obj, scene)
    me = obj.data
    colors, domain = convert.read_colors(me, convert.EASE_LAYER)
    e = ramp.color_to_ease(colors, lo, hi)
    if domain == "CORNER":
        vi = np.empty(len(me.loops), dtype=np.int32)
        me.loops.foreach_get("vertex_index", vi)
        acc = np.bincount(vi, weights=e, minlength=len(me.vertices))
        cnt = np.bincount(vi, minlength=len(me.vertices))
        e = np.where(cnt > 0, acc / np.maximum(cnt, 1), 1.0)
    return e


def triangle_ease(obj, scene) -> np.ndarray:
    """Per-triangle ease (F,) of the body from its layer: the mean of the
    triangle's vertex (or corner) values, so a uniformly painted area reads
    back exactly the value the brush used."""
    lo, hi = layer_range(obj, scene)
    me = obj.data
    colors, domain = convert.read_colors(me, convert.EASE_LAYER)
    e = ramp.color_to_ease(colors, lo, hi)
    if domain == "CORNER":
        return e.reshape(-1, 3).mean(axis=1)
    return ramp.vertex_to_triangle(e, convert.get_triangles(me))


def write_vertex_ease(obj, scene, ease: np.ndarray, mask=None) -> None:
    """Write ease (V,) into the layer (only where ``mask``), re-encoding the
    rest if the scene's ramp range changed since the layer was painted."""
    lo, hi = ramp_range(scene)
    old = vertex_ease(obj, scene) if obj.data.color_attributes.get(convert.EASE_LAYER) else np.ones(len(obj.data.vertices))
    new = old.copy()
    if mask is None:
        new[:] = ease
    else:
        new[mask] = np.asarray(ease)[mask] if np.ndim(ease) else ease
    if new.min() < lo - 1e-9 or new.max() > hi + 1e-9:
        raise state.AddonError(f"ease {new.min():.3f} .. {new.max():.3f} is outside the ramp "
                               f"{lo} .. {hi}: widen the ramp range first")
    convert.ensure_color_layer(obj.data)
    convert.write_colors(obj.data, ramp.ease_to_color(new, lo, hi))
    obj.data["ease_ramp"] = [lo, hi]


def panel_vertex_mask(context, panel: str) -> np.ndarray:
    """Body vertices (V,) bool inside ``panel`` of the current cut."""
    from . import design_ops
    cut = design_ops.current_cut(context)
    names = [p.name for p in cut.panels]
    if panel not in names:
        raise state.AddonError(f"no panel {panel!r}; panels: {', '.join(names)}")
    obj = body_object(context)
    p = cut.panel(panel)
    emb = cut.embedding[p.vertex_ids].tocsr()
    # Rows with a single weight are template vertices inside (or on the seam of) the panel.
    single = np.diff(emb.indptr) == 1
    cols = emb.indices[emb.indptr[:-1][single]]
    mask = np.zeros(len(obj.data.vertices), dtype=bool)
    mask[cols] = True
    return mask


def set_brush_color(context, rgba) -> None:
    """Give the Vertex Paint and Sculpt paint brushes the colour ``rgba``
    (scene linear). Blender 5 brush colours are scene linear; 4.x ones are
    display referred (``COLOR_GAMMA``) and get the sRGB transfer."""
    ts = context.scene.tool_settings
    targets = []
    for mode in ("vertex_paint", "sculpt"):
        paint = getattr(ts, mode, None)
        if paint is None:
            continue
        ups = getattr(paint, "unified_paint_settings", None) or getattr(ts, "unified_paint_settings", None)
        if ups is not None:
            if hasattr(ups, "use_unified_color"):
                ups.use_unified_color = True
            targets.append(ups)
        if getattr(paint, "brush", None) is not None:
            targets.append(paint.brush)
    for t in targets:
        subtype = type(t).bl_rna.properties["color"].subtype
        c = np.asarray(rgba[:3], dtype=np.float64)
        if subtype == "COLOR_GAMMA":
            c = ramp.linear_to_srgb(c)
        t.color = tuple(float(x) for x in c)


class EASE_OT_brush_ease(EaseOperator):
    """Set the paint brush colour to the chosen ease (from the ease ramp)"""
    bl_idname = "ease.brush_ease"
    bl_label = "Set Brush Ease"

    def run(self, context):
        lo, hi = ramp_range(context.scene)
        e = context.scene.ease.ease_value
        if not lo <= e <= hi:
            raise state.AddonError(f"ease {e:.3f} is outside the ramp {lo} .. {hi}")
        obj = body_object(context)
        if tuple(layer_range(obj, context.scene)) != (lo, hi):
            # keep the painted field: re-encode the layer in the new range first
            write_vertex_ease(obj, context.scene, vertex_ease(obj, context.scene))
        set_brush_color(context, ramp.ease_to_color(e, lo, hi))
        self.report({"INFO"}, f"brush paints ease {e:.3f}")


class EASE_OT_paint_ease(EaseOperator):
    """Paint the ease layer with Blender's Vertex Paint brushes"""
    bl_idname = "ease.paint_ease"
    bl_label = "Paint Ease"

    def run(self, context):
        obj = body_object(context)
        init_ease_layer(context.scene, obj)
        for o in context.view_layer.objects:
            o.select_set(o == obj)
        context.view_layer.objects.active = obj
        bpy.ops.object.mode_set(mode="VERTEX_PAINT")
        bpy.ops.ease.brush_ease()


class EASE_OT_ease_uniform(EaseOperator):
    """Set a uniform ease on a panel (or the whole body) by writing the layer"""
    bl_idname = "ease.ease_uniform"
    bl_label = "Uniform Ease"

    panel: bpy.props.StringProperty(default="", description="panel name; empty: the panel field of the scene")
    ease: bpy.props.FloatProperty(default=0.0, description="ease; 0 takes the scene's ease value")
    whole_body: bpy.props.BoolProperty(default=False, description="set the whole body, not one panel")

    def run(self, context):
        s = context.scene.ease
        obj = body_object(context)
        panel = "" if self.whole_body else (self.panel or s.ease_panel)
        e = self.ease or s.ease_value
        mask = panel_vertex_mask(context, panel) if panel else None
        write_vertex_ease(obj, context.scene, float(e), mask)
        self.report({"INFO"}, f"ease {e:.3f} on {panel or 'the whole body'}")


class EASE_OT_ease_gradient(EaseOperator):
    """Set a linear ease gradient on a panel (from -> to along an axis) by writing the layer"""
    bl_idname = "ease.ease_gradient"
    bl_label = "Gradient Ease"

    panel: bpy.props.StringProperty(default="")
    whole_body: bpy.props.BoolProperty(default=False, description="set the whole body, not one panel")

    def run(self, context):
        s = context.scene.ease
        obj = body_object(context)
        panel = "" if self.whole_body else (self.panel or s.ease_panel)
        verts = convert.get_vertices(obj.data)
        mask = panel_vertex_mask(context, panel) if panel else np.ones(len(verts), dtype=bool)
        axis = "XYZ".index(s.gradient_axis)
        x = verts[:, axis]
        if axis == 2:
            x = -x        # "top to bottom": from at the top
        elif axis == 0:
            x = x          # right (-X) to left (+X)
        lo_x, hi_x = x[mask].min(), x[mask].max()
        t = (x - lo_x) / max(hi_x - lo_x, 1e-9)
        e = s.ease_from + np.clip(t, 0.0, 1.0) * (s.ease_to - s.ease_from)
        write_vertex_ease(obj, context.scene, e, mask)
        self.report({"INFO"}, f"ease {s.ease_from:.2f} -> {s.ease_to:.2f} on {panel or 'the whole body'}")


class EASE_OT_ease_to_design(EaseOperator):
    """Convert the painted ease layer to per-triangle ease and write it into the design"""
    bl_idname = "ease.ease_to_design"
    bl_label = "Ease to Design"

    def run(self, context):
        from . import design_ops
        obj = body_object(context)
        design = design_ops.current_design(context)
        tri = triangle_ease(obj, context.scene)
        new = design_ops.design_with_triangle_ease(context, design, tri)
        design_ops.set_design(context, new, recut=True)
        self.report({"INFO"}, f"ease {tri.min():.3f} .. {tri.max():.3f} written into the design")


class EASE_OT_ease_from_design(EaseOperator):
    """Write the design's ease field into the body's ease layer"""
    bl_idname = "ease.ease_from_design"
    bl_label = "Ease from Design"

    def run(self, context):
        from . import design_ops
        obj = body_object(context)
        v = design_ops.design_vertex_ease(context)
        lo, hi = ramp_range(context.scene)
        if v.min() < lo or v.max() > hi:
            s = context.scene.ease
            s.ease_min, s.ease_max = min(lo, float(v.min())), max(hi, float(v.max()))
        write_vertex_ease(obj, context.scene, v)


CLASSES = (EASE_OT_brush_ease, EASE_OT_paint_ease, EASE_OT_ease_uniform, EASE_OT_ease_gradient,
           EASE_OT_ease_to_design, EASE_OT_ease_from_design)
