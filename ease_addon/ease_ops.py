"""Ease stage: the ease field is the colour layer "ease" on the body.

Blender's own brushes paint it (Vertex Paint, or Sculpt-mode paint); the
add-on sets the brush colour from the ease ramp (:mod:`.ramp`), sets uniform
or gradient ease per panel by writing the layer, and converts the layer to
per-triangle ease in the design. An ``ease`` layer the designer already has is
adopted whatever its type and domain, its values kept. On a mirrored design,
Blender's X-mirror paint setting decides the sides: with it the field is made
symmetric, without it each side keeps what was painted on it.
"""

from __future__ import annotations

import bpy
import numpy as np

from . import convert, data, ramp, state, sync
from .objects import select_only
from .operators_base import EaseOperator
from .sync import ease_from_design, write_vertex_ease


def panel_vertex_mask(context, panel: str) -> np.ndarray:
    """Body vertices (V,) bool inside ``panel`` of the current cut."""
    cut = data.current_cut(context)
    names = [p.name for p in cut.panels]
    if panel not in names:
        raise state.AddonError(f"no panel {panel!r}; panels: {', '.join(names)}")
    obj = data.body_object(context)
    single, cols = data.template_rows(cut, cut.panel(panel))
    mask = np.zeros(len(obj.data.vertices), dtype=bool)
    mask[cols] = True
    return mask


def design_with_triangle_ease(context, design, tri_ease: np.ndarray, mirror: bool = False):
    """A copy of ``design`` whose every panel has the per-triangle ease
    ``tri_ease`` (F,) on the body triangles it covers.

    ``mirror`` (X-mirror painting, ``tri_ease`` symmetric): the generated ``*_right``
    panels of a mirrored design stay generated (they read their ``*_left`` panel's field
    mirrored). Without it each side keeps what was painted on it: a ``*_right`` panel gets
    a field of its own (and is cut as a piece of its own where it differs)."""
    obj = data.body_object(context)
    cut = data.cut_for(design, obj)
    faces = convert.get_triangles(obj.data)
    d = design.copy()
    for p in cut.panels:
        if mirror and d.find_panel(p.name)[3]:
            continue
        cols = np.unique(cut.embedding[p.vertex_ids].tocsr().indices)
        inside = np.zeros(len(obj.data.vertices), dtype=bool)
        inside[cols] = True
        tris = np.flatnonzero(inside[faces].all(axis=1))
        if len(tris) == 0:
            continue
        d.set_ease(
            p.name,
            {
                "per_triangle": {
                    "triangles": [int(t) for t in tris],
                    "values": [round(float(x), 6) for x in tri_ease[tris]],
                    "default": round(float(np.median(tri_ease[tris])), 6),
                }
            },
        )
    return d


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
    needs = ("body",)

    def run(self, context):
        lo, hi = data.ramp_range(context.scene)
        e = context.scene.ease.ease_value
        if not lo <= e <= hi:
            raise state.AddonError(f"ease {e:.3f} is outside the ramp {lo:g} .. {hi:g}")
        obj = data.body_object(context)
        if tuple(data.layer_range(obj, context.scene)) != (lo, hi):
            # keep the painted field: re-encode the layer in the new range first
            write_vertex_ease(obj, context.scene, data.vertex_ease(obj, context.scene))
        set_brush_color(context, ramp.ease_to_color(e, lo, hi))
        self.report({"INFO"}, f"brush paints ease {e:.3f}")


class EASE_OT_paint_ease(EaseOperator):
    """Paint the ease layer with Blender's Vertex Paint brushes"""

    bl_idname = "ease.paint_ease"
    bl_label = "Paint Ease"
    needs = ("body",)

    def run(self, context):
        obj = data.body_object(context)
        if obj.data.color_attributes.get(convert.EASE_LAYER) is None:
            sync.init_ease_layer(context.scene, obj)
        else:
            # the designer's own painting is kept, whatever the layer's type and domain
            done = convert.adopt_ease_layer(obj.data)
            if done:
                self.report({"INFO"}, done)
            if obj.data.get("ease_ramp") is None:
                obj.data["ease_ramp"] = list(data.ramp_range(context.scene))
            sync.refresh_legend(context.scene)
        select_only(context, obj)
        bpy.ops.object.mode_set(mode="VERTEX_PAINT")
        bpy.ops.ease.brush_ease()


class EASE_OT_ease_uniform(EaseOperator):
    """Set a uniform ease on a panel (or the whole body) by writing the layer"""

    bl_idname = "ease.ease_uniform"
    bl_label = "Uniform Ease"
    needs = ("body",)

    panel: bpy.props.StringProperty(default="", description="panel name; empty: the panel field of the scene")
    ease: bpy.props.FloatProperty(default=0.0, description="ease; 0 takes the scene's ease value")
    whole_body: bpy.props.BoolProperty(default=False, description="set the whole body, not one panel")

    def run(self, context):
        s = context.scene.ease
        obj = data.body_object(context)
        panel = "" if self.whole_body else (self.panel or s.ease_panel)
        e = self.ease or s.ease_value
        mask = panel_vertex_mask(context, panel) if panel else None
        write_vertex_ease(obj, context.scene, float(e), mask)
        self.report({"INFO"}, f"ease {e:.3f} on {panel or 'the whole body'}")


class EASE_OT_ease_gradient(EaseOperator):
    """Set a linear ease gradient on a panel (from -> to along an axis) by writing the layer"""

    bl_idname = "ease.ease_gradient"
    bl_label = "Gradient Ease"
    needs = ("body",)

    panel: bpy.props.StringProperty(default="")
    whole_body: bpy.props.BoolProperty(default=False, description="set the whole body, not one panel")

    def run(self, context):
        s = context.scene.ease
        obj = data.body_object(context)
        panel = "" if self.whole_body else (self.panel or s.ease_panel)
        verts = convert.get_vertices(obj.data)
        mask = panel_vertex_mask(context, panel) if panel else np.ones(len(verts), dtype=bool)
        axis = "XYZ".index(s.gradient_axis)
        # "top to bottom" starts at the top (-Z); right to left (-X to +X) and front to back as they come
        x = -verts[:, axis] if axis == 2 else verts[:, axis]
        lo_x, hi_x = x[mask].min(), x[mask].max()
        t = (x - lo_x) / max(hi_x - lo_x, 1e-9)
        e = s.ease_from + np.clip(t, 0.0, 1.0) * (s.ease_to - s.ease_from)
        write_vertex_ease(obj, context.scene, e, mask)
        self.report({"INFO"}, f"ease {s.ease_from:.2f} -> {s.ease_to:.2f} on {panel or 'the whole body'}")


class EASE_OT_ease_to_design(EaseOperator):
    """Convert the painted ease layer to per-triangle ease and write it into the design"""

    bl_idname = "ease.ease_to_design"
    bl_label = "Ease to Design"
    needs = ("body", "design")

    def run(self, context):
        obj = data.body_object(context)
        design = data.current_design(context)
        mirror = data.x_mirror(obj)
        sync.mirrored_paint(obj, context.scene)  # X-mirror: a one-sided stroke painted on both sides
        tri = data.triangle_ease(obj, context.scene)
        if mirror:
            tri = data.symmetrised(obj, tri)
        sync.set_design(context, design_with_triangle_ease(context, design, tri, mirror), recut=True)
        sync.remember_layer(obj, context.scene, design=True)
        how = "X-mirror: symmetric" if mirror else "each side as painted"
        self.report({"INFO"}, f"ease {tri.min():.3f} .. {tri.max():.3f} written into the design ({how})")


class EASE_OT_ease_from_design(EaseOperator):
    """Write the design's ease field into the body's ease layer"""

    bl_idname = "ease.ease_from_design"
    bl_label = "Ease from Design"
    needs = ("body", "design")

    def run(self, context):
        ease_from_design(context)


CLASSES = (
    EASE_OT_brush_ease,
    EASE_OT_paint_ease,
    EASE_OT_ease_uniform,
    EASE_OT_ease_gradient,
    EASE_OT_ease_to_design,
    EASE_OT_ease_from_design,
)
