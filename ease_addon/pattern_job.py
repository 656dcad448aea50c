"""The pattern job shared by *Optimize Pattern* (:mod:`.pattern_ops`) and the Fit stage's
*Transfer* and *Adapt* (:mod:`.fit_ops`): the design cut on the scene body and a
:mod:`core.workflows` pattern run, in a worker (:mod:`.jobs`), the result applied on the main
thread in one pass. Kept apart from the operator modules so that none imports another."""

from __future__ import annotations

import json

import bpy

from . import data, jobs, state, sync

PATTERN_JOB = "pattern"  # the job of Optimize Pattern, Transfer and Adapt (a newer one replaces a running one)


def start_pattern(context, label: str, workflow, apply, edit=None, sync_=None) -> jobs.Job:
    """Run ``workflow(prep, progress)`` (a :mod:`core.workflows` pattern run) on the scene's
    design (``edit(design)``: the panels' settings) cut on the scene body (:func:`.data.prepared`,
    its scene half here, its cut in the worker), as the job :data:`PATTERN_JOB`: the cut and the
    workflow in a worker (``sync_``: :func:`.jobs.start`'s ``sync``), then ``apply(context,
    prep, result, shown)`` on the main thread in one pass (``shown``: the keywords of
    :func:`.sync.show_pattern` for the result's pattern, made in the worker too). A result
    landing on a scene whose design or body changed meanwhile is refused with the reason."""
    design, spec = data.preparing(context, edit)
    before = (context.scene.ease.design_json, json.dumps(spec, sort_keys=True))
    ramp_range = data.ramp_range(context.scene)

    def compute(progress):
        progress(0.0, "cutting the design")
        prep = data.prepare(design, spec)
        run = workflow(prep, progress)
        progress(0.99, "preparing the pieces")
        return prep, run, sync.prepared_show(run.pattern, ramp_range)

    def landed(result):
        ctx = bpy.context
        body = data.body_object(ctx)
        if (ctx.scene.ease.design_json, json.dumps(data.body_spec(body), sort_keys=True)) != before:
            raise state.AddonError(f"the design or the body changed while {label} ran: run it again")
        apply(ctx, *result)

    return jobs.start_step(PATTERN_JOB, label, compute, landed, "job_status", label, sync=sync_)
