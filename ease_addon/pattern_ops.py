"""Pattern stage: optimize the pattern of the current design (the core's
reference workflow) and lay it out beside the body as flat panel objects
(mesh coloured by achieved ease, boundary curve, grain-line arrow, piece
name; see :func:`.build.update_pattern_objects`). The whole pattern is kept in a
scene property (pattern.json) so it survives a save. *Optimize Pattern* (and the Fit
stage's Transfer and Adapt, :func:`.pattern_job.start_pattern`) are jobs (:mod:`.jobs`, as Drape):
the cut and the solve run in a worker (progress in the status bar, Esc cancels) and the
pattern is shown in one pass when it lands."""

from __future__ import annotations

import json

from . import data, jobs, sync
from .operators_base import EaseOperator
from .pattern_job import start_pattern


def gather_settings(scene, design):
    """The design with ``materials.gather_above`` set from the Pattern panel (None when gathering is
    off); unchanged when the panel shows what the design already does."""
    s = scene.ease
    want = round(s.gather_above_pct / 100.0, 6) if s.gather_auto else None
    return data.design_with_materials(design, gather_above=want)


class EASE_OT_optimize_pattern(jobs.Background, EaseOperator):
    """Optimize the sewing pattern of the design and lay it out beside the body (in the background: Esc cancels)"""

    bl_idname = "ease.optimize_pattern"
    bl_label = "Optimize Pattern"
    needs = ("body", "design")

    def run(self, context):
        job, said = start_optimize(context, sync_=self.job_sync())
        self.report({"INFO"}, said[-1] if said else "optimizing in the background (Esc cancels)")


def start_optimize(context, sync_=None) -> tuple:
    """*Optimize Pattern*'s job (:func:`start_pattern`): the reference workflow with the
    panel's solver and gathering. ``(job, said)``: ``said`` holds the report once shown."""
    from ..core import workflows as wf

    config = data.solver_choice(context.scene)
    said = []

    def show(ctx, prep, run, shown):
        # the design keeps the gathering it was solved with
        text = json.dumps(prep.design.to_json(), sort_keys=True)
        if text != ctx.scene.ease.design_json:
            ctx.scene.ease.design_json = text
        sync.show_pattern(ctx, run.pattern, **shown)
        said.append(f"pattern: {len(run.pattern.panels)} pieces")

    job = start_pattern(
        context,
        "Optimize Pattern",
        lambda prep, progress: wf.reference(prep, config=config, progress=progress),
        show,
        edit=lambda design: gather_settings(context.scene, design),
        sync_=sync_,
    )
    return job, said


CLASSES = (EASE_OT_optimize_pattern,)
