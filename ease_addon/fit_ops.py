"""Fit stage: transfer the design to a size, adapt it to poses within the
material tolerance (the core's transfer and adapt workflows); their figures
(transfer deviation, before/after residual stretch) show in the panel. The
transferred/adapted pattern replaces the pieces beside the body (and is what
Drape and Export use next)."""

from __future__ import annotations

import json

from . import data, jobs, pattern_job, state, sync
from .operators_base import EaseOperator


def _fit(context, label: str, workflow, sync_=None) -> jobs.Job:
    """Run ``workflow(prep, progress)`` (a :mod:`core.workflows` pattern run) on the scene's
    design as a job (:func:`.pattern_job.start_pattern`; ``sync_``: :func:`.jobs.start`'s); its
    pattern replaces the pieces beside the body, its figures show in the Fit panel."""

    def show(ctx, prep, run, shown):
        sync.show_pattern(ctx, run.pattern, **shown)
        ctx.scene.ease.fit_json = json.dumps(run.figures)

    return pattern_job.start_pattern(context, label, workflow, show, sync_=sync_)


def start_transfer(context, sync_=None) -> jobs.Job:
    """*Transfer to Size*'s job: the design transferred to the Fit panel's size with the panel's
    solver (pressed: in a worker)."""
    from ..core import workflows as wf

    size = context.scene.ease.fit_size
    config = data.solver_choice(context.scene)
    return _fit(
        context,
        "Transfer to Size",
        lambda prep, progress: wf.transfer(prep, size, config=config, progress=progress),
        sync_=sync_,
    )


def start_adapt(context, sync_=None) -> jobs.Job:
    """*Adapt to Poses*' job: the design adapted to the Fit panel's poses within its tolerance
    (pressed: in a worker); AddonError without a pose."""
    from ..core import workflows as wf

    s = context.scene.ease
    poses = [p for p in ("T", "P1", "P2", "P3") if getattr(s, f"adapt_{p}")]
    if not poses:
        raise state.AddonError("choose at least one pose to adapt to")
    tol = round(float(s.tolerance), 6)  # the property is single precision: 1.1 reads 1.10000002
    config = data.solver_choice(context.scene)

    def adapt(prep, progress):
        # the panel's tolerance is the caller's where it differs from the design's weft
        # tolerance; where it shows the design's, the design decides both (weft and warp)
        own = prep.cut.materials.get("eps_weft")
        mine = None if own is not None and abs(tol - float(own)) < 1e-6 else tol
        return wf.adapt(prep, poses, eps_weft=mine, config=config, progress=progress)

    job = _fit(context, "Adapt to Poses", adapt, sync_=sync_)
    job.poses = poses
    return job


class EASE_OT_transfer_size(jobs.Background, EaseOperator):
    """Transfer the design to the chosen size, preserving its ease (in the background: Esc cancels)"""

    bl_idname = "ease.transfer_size"
    bl_label = "Transfer to Size"
    needs = ("body", "design", "fit_size")

    def run(self, context):
        job = start_transfer(context, sync_=self.job_sync())
        size = context.scene.ease.fit_size
        self.report(
            {"INFO"},
            f"transferred to {size}" if job.thread is None else f"{self.bl_label} in the background (Esc cancels)",
        )


class EASE_OT_adapt_poses(jobs.Background, EaseOperator):
    """Adapt the design to the chosen poses within the stretch tolerance (in the background: Esc cancels)"""

    bl_idname = "ease.adapt_poses"
    bl_label = "Adapt to Poses"
    needs = ("body", "design")

    def run(self, context):
        job = start_adapt(context, sync_=self.job_sync())
        self.report(
            {"INFO"},
            f"adapted to {', '.join(job.poses)}"
            if job.thread is None
            else f"{self.bl_label} in the background (Esc cancels)",
        )


CLASSES = (EASE_OT_transfer_size, EASE_OT_adapt_poses)
