"""The "EASE" tab of the 3D view sidebar: one panel per workflow stage."""

from __future__ import annotations

import json

import bpy

from . import data


class _EasePanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "EASE"


def _props(layout, s, *names, **kw):
    """One aligned row of the properties ``names`` of ``s``."""
    row = layout.row(align=True)
    for name in names:
        row.prop(s, name, **kw)
    return row


def _ops(layout, *ops):
    """One aligned row of operators: ``idname`` or ``(idname, icon)``."""
    row = layout.row(align=True)
    for op in ops:
        idname, icon = (op, "NONE") if isinstance(op, str) else op
        row.operator(idname, icon=icon)
    return row


def _sizes(layout, s, prop: str, chart: str):
    """One aligned row of the size presets of ``chart`` for the enum ``prop``: only the chart's
    (the enum holds every chart's sizes)."""
    row = layout.row(align=True)
    for size in data.chart_sizes(chart):
        row.prop_enum(s, prop, size)
    return row


def _figures(layout, text: str) -> None:
    """Key figures of a JSON report as label rows."""
    if not text:
        return
    try:
        data = json.loads(text)
    except ValueError:
        layout.label(text=text)
        return
    col = layout.column(align=True)
    for k, v in data.items():
        if isinstance(v, float):
            v = f"{v:.4g}"
        col.label(text=f"{k}: {v}")


def _job_row(layout, s) -> None:
    """The background work's "updating: ..." line with its Cancel button (Esc cancels too)."""
    if s.job_status:
        row = layout.row(align=True)
        row.label(text=s.job_status, icon="TIME" if s.job_status.startswith("updating") else "INFO")
        if s.job_status.startswith("updating"):
            row.operator("ease.cancel_jobs", text="", icon="CANCEL")


class EASE_PT_body(_EasePanel, bpy.types.Panel):
    bl_label = "Body"
    bl_idname = "EASE_PT_body"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        _job_row(layout, s)
        row = layout.row(align=True)
        row.operator("ease.add_body", text="Default Body", icon="OUTLINER_OB_ARMATURE").source = "DEFAULT"
        row.operator("ease.add_body", text="From File", icon="FILE").source = "FILE"
        layout.prop(s, "body_file")
        layout.prop(s, "body")
        if s.body is None:
            return
        box = layout.box()
        box.label(text="Phenotype")
        for item in s.shape:
            box.prop(item, "value", text=item.name, slider=False)
        size = s.body.get("ease_size")
        layout.label(text=f"Body size: {size}" if size else "Body size: a shape of its own (no chart size)")
        layout.prop(s, "chart")
        _sizes(layout, s, "size", s.chart)
        layout.operator("ease.set_size")
        box = layout.box()
        box.label(text="Measurements (cm)")
        for name in ("height_cm", "chest_cm", "waist_cm", "hip_cm"):
            box.prop(s, name)
        _ops(box, "ease.fit_measurements", "ease.measure")
        if s.measurements_report:
            for part in s.measurements_report.split(", "):
                box.label(text=part)
        _props(layout, s, "pose", expand=True)
        layout.operator("ease.set_pose")


class EASE_PT_design(_EasePanel, bpy.types.Panel):
    bl_label = "Design"
    bl_idname = "EASE_PT_design"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        layout.prop(s, "template")
        layout.operator("ease.load_template")
        layout.prop(s, "design_file")
        _ops(layout, "ease.load_design_file", "ease.save_design")
        if not s.design_json:
            return
        box = layout.box()
        box.label(text="Parameters")
        box.prop(s, "live_recut")
        for item in s.design_params:
            box.prop(item, "value", text=item.name)
        if s.design_status:
            box.label(text=s.design_status, icon="ERROR")
        box.operator("ease.recut")
        box = layout.box()
        box.label(text="Keypoints")
        box.prop(s, "keypoint_name")
        _ops(box, ("ease.assign_keypoint", "VERTEXSEL"), ("ease.pick_keypoint", "RESTRICT_SELECT_OFF"))


class EASE_PT_ease(_EasePanel, bpy.types.Panel):
    bl_label = "Ease"
    bl_idname = "EASE_PT_ease"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        _props(layout, s, "ease_min", "ease_max")
        legend = layout.row(align=True)
        for item in s.legend:
            col = legend.column(align=True)
            col.prop(item, "color", text="")
            col.label(text=f"{item.ease:.2f}")
        layout.prop(s, "ease_value")
        _ops(layout, ("ease.paint_ease", "BRUSH_DATA"), "ease.brush_ease")
        box = layout.box()
        box.prop(s, "ease_panel")
        box.operator("ease.ease_uniform")
        _props(box, s, "ease_from", "ease_to")
        box.prop(s, "gradient_axis")
        box.operator("ease.ease_gradient")
        _ops(layout, "ease.ease_to_design", "ease.ease_from_design")
        box = layout.box()
        row = box.row(align=True)
        row.prop(s, "live", toggle=True, icon="PLAY" if not s.live else "PAUSE")
        if s.live_status:
            row.label(text=s.live_status)
        _job_row(box, s)
        if s.live:
            box.label(text="ease_fit layer: achieved / painted - 1 (%)")
            legend = box.row(align=True)
            for item in s.live_legend:
                col = legend.column(align=True)
                col.prop(item, "color", text="")
                col.label(text=f"{item.ease:+.0f}")
            _figures(box, s.pattern_json)


class EASE_PT_pattern(_EasePanel, bpy.types.Panel):
    bl_label = "Pattern"
    bl_idname = "EASE_PT_pattern"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        row = _props(layout, s, "gather_auto")
        sub = row.row(align=True)
        sub.enabled = s.gather_auto
        sub.prop(s, "gather_above_pct")
        layout.prop(s, "solver_config")
        if s.solver_config == data.DESIGN_SOLVER and s.design_json:
            layout.label(text=f"Design's solver: {data.design_solver(context.scene).capitalize()}")
        layout.operator("ease.optimize_pattern", icon="MESH_GRID")
        if "Optimize Pattern" in s.job_status:  # running in the background (or stopped): Cancel beside it
            _job_row(layout, s)
        _figures(layout, s.pattern_json)


class EASE_PT_fit(_EasePanel, bpy.types.Panel):
    bl_label = "Fit"
    bl_idname = "EASE_PT_fit"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        chart = data.design_chart(context.scene)
        if chart != "default":
            layout.label(text=f"Sizes of the design's chart: {chart}")
        _sizes(layout, s, "fit_size", chart)
        layout.operator("ease.transfer_size")
        _props(layout, s, *(f"adapt_{p}" for p in ("T", "P1", "P2", "P3")), toggle=True)
        layout.prop(s, "tolerance")
        layout.operator("ease.adapt_poses")
        if "Transfer to Size" in s.job_status or "Adapt to Poses" in s.job_status:
            _job_row(layout, s)
        _figures(layout, s.fit_json)


class EASE_PT_drape(_EasePanel, bpy.types.Panel):
    bl_label = "Drape"
    bl_idname = "EASE_PT_drape"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        row = _props(layout, s, "drape_frames")
        row.prop(s, "drape_device", text="")
        layout.prop(s, "drape_solver")
        layout.prop(s, "drape_hold_pins")
        layout.prop(s, "drape_refine_mm")
        layout.operator("ease.drape", icon="MOD_CLOTH")
        if s.job_status.startswith("updating: drape"):  # a Drape or Drape Animation running: Cancel beside it
            _job_row(layout, s)
        if s.drape_status:
            layout.label(text=s.drape_status)
        _props(layout, s, "fitmap", expand=True)
        _figures(layout, s.drape_json)
        box = layout.box()
        box.label(text="Animation")
        box.prop(s, "motion_source", expand=True)
        if s.motion_source == "POSES":
            box.prop(s, "motion_poses")
            box.prop(s, "motion_between")
        box.operator("ease.add_rig", icon="ARMATURE_DATA")
        box.prop(s, "motion_adapt")
        box.operator("ease.drape_animation", icon="MOD_CLOTH")
        if s.motion_status:
            box.label(text=s.motion_status)
        box.prop(s, "motion_path")
        row = box.row(align=True)
        row.prop(s, "motion_with_body", toggle=True)
        row.operator("ease.export_alembic", icon="EXPORT")


class EASE_PT_render(_EasePanel, bpy.types.Panel):
    bl_label = "Render & Export"
    bl_idname = "EASE_PT_render"

    def draw(self, context):
        layout, s = self.layout, context.scene.ease
        layout.operator("ease.studio_setup", icon="LIGHT_AREA")
        _props(layout, s, "render_samples", "render_resolution")
        layout.prop(s, "render_view", expand=True)
        layout.prop(s, "render_path")
        layout.operator("ease.render", icon="RENDER_STILL")
        row = layout.row(align=True)
        row.prop(s, "render_turntable_frames")
        row.operator("ease.render_turntable", icon="RENDER_ANIMATION")
        layout.separator()
        layout.prop(s, "export_dir")
        _props(layout, s, *(f"export_{f}" for f in ("svg", "dxf", "pdf", "glb", "obj")), toggle=True)
        col = layout.column(align=True)
        for name in ("export_allowance_cm", "export_hem_cm", "export_notch_cm"):
            col.prop(s, name)
        row = layout.row()
        row.enabled = s.export_pdf
        row.prop(s, "export_print_all")
        layout.operator("ease.export_pattern", icon="EXPORT")
        layout.separator()
        col = layout.column(align=True)
        for name in ("marker_width_mm", "marker_sizes", "marker_seconds", "marker_one_way", "marker_spread"):
            col.prop(s, name)
        layout.operator("ease.marker", icon="MOD_UVPROJECT")
        if s.marker_status:
            layout.label(text=s.marker_status)


CLASSES = (EASE_PT_body, EASE_PT_design, EASE_PT_ease, EASE_PT_pattern, EASE_PT_fit, EASE_PT_drape, EASE_PT_render)
