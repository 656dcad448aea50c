"""Fit stage: transfer the design to a size, adapt it to poses within the
material tolerance; the before/after residual-stretch figures show in the
panel. The transferred/adapted pattern replaces the pieces beside the body
(and is what Drape and Export use next)."""
from __future__ import annotations

import json

from . import state
from .body_ops import body_object
from .operators_base import EaseOperator
from .pattern_ops import _progress_for, show_pattern


class EASE_OT_transfer_size(EaseOperator):
    """Transfer the design to the chosen size, preserving its ease"""
    bl_idname = "ease.transfer_size"
    bl_label = "Transfer to Size"

    def run(self, context):
        from . import design_ops
        s = context.scene.ease
        obj = body_object(context)
        design = design_ops.current_design(context)
        cut = design_ops.cut_for(design, obj)
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            pattern, figures = state.transfer_pattern(design, cut, obj, s.fit_size, _progress_for(context))
        finally:
            wm.progress_end()
        show_pattern(context, pattern)
        s.fit_json = json.dumps(figures)
        self.report({"INFO"}, f"transferred to {s.fit_size}")


class EASE_OT_adapt_poses(EaseOperator):
    """Adapt the design to the chosen poses within the stretch tolerance"""
    bl_idname = "ease.adapt_poses"
    bl_label = "Adapt to Poses"

    def run(self, context):
        from . import design_ops
        s = context.scene.ease
        poses = [p for p in ("T", "P1", "P2", "P3") if getattr(s, f"adapt_{p}")]
        if not poses:
            raise state.AddonError("choose at least one pose to adapt to")
        obj = body_object(context)
        design = design_ops.current_design(context)
        cut = design_ops.cut_for(design, obj)
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            pattern, figures = state.adapt_pattern(design, cut, obj, poses, s.tolerance, _progress_for(context))
        finally:
            wm.progress_end()
        show_pattern(context, pattern)
        s.fit_json = json.dumps(figures)
        self.report({"INFO"}, f"adapted to {', '.join(poses)}")


CLASSES = (EASE_OT_transfer_size, EASE_OT_adapt_poses)
