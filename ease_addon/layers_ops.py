"""Layers: an outfit of garments worn one over another, listed in the Design panel (inner first).

*Add Layer* adds the Design panel's template (or a design file) as the next, outer layer; each
layer says whether it is tucked into a lower garment listed after it; *Drape All* patterns every
layer on its body and drapes them inner first, each over the ones under it (as a background job:
:func:`core.workflows.drape_outfit`). Each garment becomes its own object (role
:data:`ROLE`) with its own material; the report (inter-layer penetration, gap, tucked hem) is kept
in the scene (:data:`REPORT_KEY`). The outfit's format and its checks are the core's
(:mod:`core.design.outfit`); docs/layers.md.
"""

from __future__ import annotations

from pathlib import Path

import bpy
from bpy.props import BoolProperty, CollectionProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import convert, data, jobs, materials, objects, state
from .operators_base import EaseOperator

JOB = "outfit"
ROLE = "outfit_garment"
REPORT_KEY = "ease_outfit_report"


class EASE_PG_layer(bpy.types.PropertyGroup):
    design: StringProperty(name="Design", description="A template's name (shirt_long_sleeve) or a design file (.json)")
    tucked: BoolProperty(
        name="Tucked", description="Tucked into a lower garment (trousers, skirt) listed after it", default=False
    )


class EASE_PG_layers(bpy.types.PropertyGroup):
    items: CollectionProperty(type=EASE_PG_layer)
    index: IntProperty(name="Layer", default=0, min=0)
    edge_mm: FloatProperty(
        name="Edge (mm)",
        description="Cut every garment at this mean edge length (0: each design's own; 20 mm drapes ~4x faster)",
        default=0.0,
        min=0.0,
        max=100.0,
    )
    over: EnumProperty(
        name="Cut over",
        description="The surface an outer garment's pattern is solved and its ease measured on",
        items=[
            ("skintight", "Skintight", "The inner garments' skintight surface: the body out by their thickness"),
            ("draped", "Draped", "The inner garments as draped, with their folds"),
            ("body", "Body", "The body, as if each garment were worn alone"),
        ],
        default="skintight",
    )


def outfit_of(scene) -> dict:
    """The scene's layers as an outfit (:func:`core.design.outfit.load_outfit` checks it)."""
    layers = scene.ease_layers.items
    if not layers:
        raise state.AddonError("Layers: add a garment first (Add Layer)")
    return {
        "format": "ease-outfit",
        "version": 1,
        "layers": [{"design": ly.design, "tucked": bool(ly.tucked)} for ly in layers],
    }


def _design_name(value: str) -> str:
    """A template file of the Design panel (``shirt_long_sleeve.json``) as its template name."""
    if value and value.endswith(".json") and (data.template_dir() / value).is_file():
        return Path(value).stem
    return value


class EASE_OT_layer_add(EaseOperator):
    """Add the Design panel's template (or the given design) as the outermost layer"""

    bl_idname = "ease.layer_add"
    bl_label = "Add Layer"
    design: StringProperty(
        name="Design", description="Template name or design file; empty: the Design panel's template"
    )
    tucked: BoolProperty(name="Tucked", default=False)

    def run(self, context):
        from ..core.design.outfit import load_outfit
        from ..core.errors import DesignError

        scene = context.scene
        name = _design_name(self.design or scene.ease.template)
        if not name or name == "NONE":
            raise state.AddonError("Add Layer: choose a template in the Design panel")
        try:  # the design alone must load (the order is checked on Drape All)
            load_outfit({"format": "ease-outfit", "version": 1, "layers": [{"design": name}]})
        except DesignError as exc:
            raise state.AddonError(f"Add Layer: {exc}") from None
        item = scene.ease_layers.items.add()
        item.design, item.tucked = name, self.tucked
        scene.ease_layers.index = len(scene.ease_layers.items) - 1


class EASE_OT_layer_remove(EaseOperator):
    """Remove the selected layer"""

    bl_idname = "ease.layer_remove"
    bl_label = "Remove Layer"
    needs = ("layers",)

    def run(self, context):
        layers = context.scene.ease_layers
        if not layers.items:
            raise state.AddonError("Remove Layer: there is no layer")
        layers.items.remove(min(layers.index, len(layers.items) - 1))
        layers.index = max(0, min(layers.index, len(layers.items) - 1))


class EASE_OT_layer_move(EaseOperator):
    """Move the selected layer inward (up) or outward (down)"""

    bl_idname = "ease.layer_move"
    bl_label = "Move Layer"
    needs = ("layers",)
    direction: EnumProperty(
        items=(("UP", "Inward", "one layer further in"), ("DOWN", "Outward", "one layer further out"))
    )

    def run(self, context):
        layers = context.scene.ease_layers
        i = layers.index
        j = i - 1 if self.direction == "UP" else i + 1
        if not (0 <= i < len(layers.items) and 0 <= j < len(layers.items)):
            raise state.AddonError("Move Layer: no layer further that way")
        layers.items.move(i, j)
        layers.index = j


def _compute(outfit: dict, frames: int, device: str, edge_m, progress, over: str = "skintight"):
    from ..core import workflows as wf

    options = {"max_frames": int(frames), "min_frames": min(10, int(frames)), "device": device}
    return wf.drape_outfit(outfit, options=options, refine_edge_length=edge_m, over=over, progress=progress)


def apply_outfit(context, run) -> None:
    """One object per draped garment (replacing the last Drape All's), each with its own material;
    the report in the scene; the status line."""
    import numpy as np

    from ..core.export.outfit import LAYER_COLOURS  # the exported outfit's colours: one palette
    from ..core.geom.mesh import compact_vertices

    scene = context.scene
    objects.remove_objects(objects.objects_with_role(scene, ROLE))
    for k, lr in enumerate(run.layers):
        r = lr.drape.result
        used, faces = compact_vertices(r.faces)
        me = convert.mesh_from_arrays(f"EASE {lr.layer.name}", np.asarray(r.positions)[used], faces)
        obj = objects.role_object(scene, f"EASE {lr.layer.name}", me, ROLE)
        obj["ease_layer"] = k
        rgb = LAYER_COLOURS[k % len(LAYER_COLOURS)]
        me.materials.append(materials.surface(f"EASE layer {k + 1}", (*rgb, 1.0), 0.9))
    report = run.report()
    convert.store_json(scene, REPORT_KEY, report)
    worst = max((lr.settled_penetration_pct for lr in run.layers), default=0.0)
    scene.ease.drape_status = (
        f"outfit draped: {len(run.layers)} layers, inter-layer penetration {worst:.2f} % (settled max)"
    )


class EASE_OT_drape_all(jobs.Background, EaseOperator):
    """Drape every layer, inner first, each over the ones under it (in the background: Esc cancels)"""

    bl_idname = "ease.drape_all"
    bl_label = "Drape All"
    needs = ("layers",)

    def run(self, context):
        from ..core.design.outfit import load_outfit
        from ..core.errors import DesignError

        s, layers = context.scene.ease, context.scene.ease_layers
        outfit = outfit_of(context.scene)
        try:
            checked = load_outfit(outfit)  # refused here, in one line, before the job starts
        except DesignError as exc:
            raise state.AddonError(f"Drape All: {exc}") from None
        edge = layers.edge_mm / 1000.0 if layers.edge_mm else None
        if edge is not None and not 0.005 <= edge <= 0.1:
            raise state.AddonError(f"Drape All: Edge (mm) = {layers.edge_mm:g}: expected 0 or 5 to 100 mm")
        frames, device, over = s.drape_frames, s.drape_device, layers.over
        jobs.start_step(
            JOB,
            "drape all",
            lambda progress: _compute(checked, frames, device, edge, progress, over),
            lambda run: apply_outfit(bpy.context, run),
            "drape_status",
            "Drape All",
            sync=self.job_sync(),
        )


class EASE_UL_layers(bpy.types.UIList):
    def draw_item(self, context, layout, data_, item, icon, active_data, active_propname, index=0):
        row = layout.row(align=True)
        row.label(text=f"{index + 1}. {item.design}")
        row.prop(item, "tucked", text="Tucked")


class EASE_PT_layers(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "EASE"
    bl_label = "Layers"
    bl_idname = "EASE_PT_layers"
    bl_parent_id = "EASE_PT_design"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout, layers = self.layout, context.scene.ease_layers
        layout.label(text="Garments, inner first")
        row = layout.row()
        row.template_list("EASE_UL_layers", "", layers, "items", layers, "index", rows=3)
        col = row.column(align=True)
        col.operator("ease.layer_add", icon="ADD", text="")
        col.operator("ease.layer_remove", icon="REMOVE", text="")
        col.operator("ease.layer_move", icon="TRIA_UP", text="").direction = "UP"
        col.operator("ease.layer_move", icon="TRIA_DOWN", text="").direction = "DOWN"
        layout.prop(layers, "edge_mm")
        layout.prop(layers, "over")
        layout.operator("ease.drape_all")
        report = convert.load_json(context.scene, REPORT_KEY)
        for ly in (report or {}).get("layers", [])[1:]:
            for inner, m in ly.get("over", {}).items():
                layout.label(
                    text=f"{ly['name']} over {inner}: {m['penetration_pct']:.2f} %, gap {m['gap_mm']['mean']:.1f} mm"
                )


CLASSES = (
    EASE_PG_layer,
    EASE_PG_layers,
    EASE_OT_layer_add,
    EASE_OT_layer_remove,
    EASE_OT_layer_move,
    EASE_OT_drape_all,
    EASE_UL_layers,
)
PANELS = (EASE_PT_layers,)


def register_props():
    bpy.types.Scene.ease_layers = bpy.props.PointerProperty(type=EASE_PG_layers)


def unregister_props():
    if hasattr(bpy.types.Scene, "ease_layers"):
        del bpy.types.Scene.ease_layers


__all__ = ["CLASSES", "PANELS", "apply_outfit", "outfit_of", "register_props", "unregister_props"]
