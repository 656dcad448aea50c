"""Export stage: write the scene's pattern with the core's exporters
(SVG, DXF, tiled PDF, GLB of the draped garment)."""
from __future__ import annotations

import bpy

from . import state
from .operators_base import EaseOperator


class EASE_OT_export_pattern(EaseOperator):
    """Export the pattern (SVG, DXF, PDF, GLB) to the export folder"""
    bl_idname = "ease.export_pattern"
    bl_label = "Export Pattern"

    directory: bpy.props.StringProperty(subtype="DIR_PATH", default="")

    def run(self, context):
        from .pattern_ops import stored_pattern
        s = context.scene.ease
        pattern = stored_pattern(context.scene)
        if pattern is None:
            raise state.AddonError("no pattern to export: optimize the pattern first")
        formats = [f for f in ("svg", "dxf", "pdf", "glb") if getattr(s, f"export_{f}")]
        if not formats:
            raise state.AddonError("choose at least one export format")
        out = bpy.path.abspath(self.directory or s.export_dir)
        if not out:
            raise state.AddonError("set an export folder")
        files = state.export_pattern(pattern, out, formats, state.DRAPES.get(context.scene.name))
        self.report({"INFO"}, f"exported {len(files)} files to {out}")


CLASSES = (EASE_OT_export_pattern,)
