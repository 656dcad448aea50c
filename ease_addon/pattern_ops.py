"""Pattern stage: optimize the pattern of the current design (the core's
reference workflow) and lay it out beside the body as flat panel objects
(mesh coloured by achieved ease, boundary curve, grain-line arrow, piece
name; see :func:`.build.update_pattern_objects`). The whole pattern is kept in a
scene property (pattern.json) so it survives a save."""

from __future__ import annotations

import json

from . import data, sync
from .objects import window_progress
from .operators_base import EaseOperator


def gather_settings(scene, design):
    """The design with ``materials.gather_above`` set from the Pattern panel (None when gathering is
    off); unchanged when the panel shows what the design already does."""
    s = scene.ease
    want = round(s.gather_above_pct / 100.0, 6) if s.gather_auto else None
    return data.design_with_materials(design, gather_above=want)


class EASE_OT_optimize_pattern(EaseOperator):
    """Optimize the sewing pattern of the design and lay it out beside the body"""

    bl_idname = "ease.optimize_pattern"
    bl_label = "Optimize Pattern"
    needs = ("body", "design")

    def run(self, context):
        from ..core import workflows as wf

        prep = data.prepared(context, lambda design: gather_settings(context.scene, design))
        with window_progress(context) as progress:
            pattern = wf.reference(prep, config=data.solver_choice(context.scene), progress=progress).pattern
        # -- the scene changes from here on: the design keeps the gathering it was solved with
        text = json.dumps(prep.design.to_json(), sort_keys=True)
        if text != context.scene.ease.design_json:
            context.scene.ease.design_json = text
        sync.show_pattern(context, pattern)
        self.report({"INFO"}, f"pattern: {len(pattern.panels)} pieces")


CLASSES = (EASE_OT_optimize_pattern,)
