"""Drape operators (ease_addon.drape_ops): the garment and its fit maps; the modal drape's
progress, Esc, a failing core, a pattern changed meanwhile, disabling mid-drape."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, pattern=True)


def test_drape_garment_and_fit_map(bpy_session, blender):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.drape_frames = 15
    s.drape_device = "cuda"
    r = blender.run(bpy.ops.ease.drape)
    if "ERROR" in r:  # no GPU here: the core's message, and no garment made
        assert "cuda" in r["ERROR"].lower()
        assert not [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    s.drape_device = "cpu"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    garments = [o for o in bpy.data.objects if o.get("ease_role") == "garment"]
    assert len(garments) == 1
    g = garments[0]
    assert len(g.data.polygons) > 100
    assert g.data.materials[0].name == "EASE Fabric cotton"  # the design's fabric preset
    assert g.data.color_attributes.get("fit_strain") is not None
    rep = json.loads(s.drape_json)
    assert rep["frames"] >= 1
    assert bpy.ops.ease.fitmap(mode="STRAIN") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fit Map fit_strain"
    assert g.data.color_attributes.active_color.name == "fit_strain"
    assert bpy.ops.ease.fitmap(mode="GAP") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fit Map fit_gap"
    assert g.data.color_attributes.active_color.name == "fit_gap"
    gap = np.empty(len(g.data.vertices), dtype=np.float32)
    g.data.attributes["fit_gap_value"].data.foreach_get("value", gap)
    assert np.all(gap >= 0) and gap.max() > 0.0
    # the two maps colour differently: they show different fields
    cols = {}
    for layer in ("fit_strain", "fit_gap"):
        c = np.empty(len(g.data.vertices) * 4, dtype=np.float32)
        g.data.color_attributes[layer].data.foreach_get("color", c)
        cols[layer] = c
    assert not np.allclose(cols["fit_strain"], cols["fit_gap"])
    assert bpy.ops.ease.fitmap(mode="NONE") == {"FINISHED"}
    assert g.data.materials[0].name == "EASE Fabric cotton"  # the design's fabric preset


@pytest.fixture
def threaded(addon):
    """The add-on's jobs in worker threads, as in Blender's window (headless they run in line)."""
    jobs = addon("jobs")
    before, jobs.SYNCHRONOUS = jobs.SYNCHRONOUS, False
    try:
        yield jobs
    finally:
        jobs.cancel()
        jobs.SYNCHRONOUS = before


def _landed(jobs, job) -> None:
    """Wait for ``job``'s worker, then the main thread's poll (what Blender's timer does)."""
    job.thread.join(120)
    assert not job.thread.is_alive()
    jobs.poll()


def test_drape_in_the_background_progress_and_esc(bpy_session, blender, addon, threaded):
    """The interactive drape (one job mechanism, :mod:`ease_addon.jobs`): the core runs in a
    worker thread, its progress per frame is the status line, the result lands on the main
    thread's poll, and Esc (cancel) leaves the scene as it was; a failing core, a pattern
    changed meanwhile and disabling the add-on mid-drape too."""
    bpy = bpy_session["bpy"]
    jobs = threaded
    s = bpy.context.scene.ease
    drape_ops = addon("drape_ops")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    g_name, g_verts = garment.data.name, blender.verts(garment).copy()
    pattern = addon("data").stored_pattern(bpy.context.scene)
    body_v, body_f = drape_ops._pattern_body(pattern)
    # the Drape button's job (headless bpy has no window to invoke in): back at once, the job running
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=400)
    assert jobs.running(drape_ops.JOB) is job and job.thread.is_alive()
    jobs.poll()
    assert s.job_status.startswith("updating: drape")
    # Esc (the watcher's cancel): the worker stops at its next progress report, nothing is applied
    assert jobs.cancel() == 1
    _landed(jobs, job)
    assert job.cancelled and job.result is None and "cancelled" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    assert jobs.running() is None
    # the core fails mid-drape: its message in the status, the garment as it was
    from core.errors import EaseError

    real = drape_ops._compute

    def failing(*a, **k):
        a[4](0.3, "frame 12")
        raise EaseError("drape diverged at frame 12 (time step too large?)")

    drape_ops._compute = failing
    try:
        job = drape_ops.start_drape(pattern, body_v, body_f, frames=400)
        _landed(jobs, job)
    finally:
        drape_ops._compute = real
    assert "diverged at frame 12" in s.drape_status and "stopped" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    # a run to the end: a progress report per frame, shown in the status line, applied on the poll
    data = addon("data")
    key = addon("data").PATTERN_KEY
    digest = data.pattern_digest(bpy.context.scene[key])
    seen = []  # every progress report of the worker, as the status line shows it

    def recording(*a, **k):
        shown = a[4]

        def progress(fraction, message):
            shown(fraction, message)
            seen.append(jobs.running(drape_ops.JOB).status())

        return real(*a[:4], progress, *a[5:], **k)

    drape_ops._compute = recording
    try:
        job = drape_ops.start_drape(pattern, body_v, body_f, frames=4, digest=digest)
        job.thread.join(120)
    finally:
        drape_ops._compute = real
    frames = [re.match(r"updating: drape (\d+) % \(drape: frame (\d+),", t) for t in seen]
    frames = [(int(m[1]), int(m[2])) for m in frames if m]
    assert [k for _, k in frames] == [1, 2, 3, 4] and [f for f, _ in frames] == sorted({f for f, _ in frames}), seen
    assert job.fraction >= 0.9 and job.error is None
    jobs.poll()
    assert json.loads(s.drape_json)["frames"] <= 4 and s.drape_status.startswith("draped")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest and data.garment_positions(bpy.context.scene)[0] is not None
    # the pattern changed while a drape ran: the garment says which pattern it fits, and
    # is not exported as the new one's
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=2, digest=digest)
    text = bpy.context.scene[key]
    bpy.context.scene[key] = json.dumps(dict(json.loads(text), style="re-optimized meanwhile"))
    _landed(jobs, job)
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest
    pos, why = data.garment_positions(bpy.context.scene)
    assert pos is None and "another pattern" in why
    bpy.context.scene[key] = text
    assert data.garment_positions(bpy.context.scene)[0] is not None
    # disabling the add-on while a drape runs stops the worker (no thread left behind)
    module = bpy_session["module"]
    job = drape_ops.start_drape(pattern, body_v, body_f, frames=5000)
    assert job.thread.is_alive()
    bpy.ops.preferences.addon_disable(module=module)
    assert job.cancelled and not job.thread.is_alive() and job.result is None
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    assert bpy.context.scene.ease.drape_json  # the scene's EASE data is still there
