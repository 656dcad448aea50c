"""Drape operators (ease_addon.drape_ops): the garment and its fit maps; the modal drape's
progress, Esc, a failing core, a pattern changed meanwhile, disabling mid-drape."""

from __future__ import annotations

import json

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


def test_drape_modal_progress_and_esc(bpy_session, blender, addon):
    """The interactive drape: a worker thread runs the core; the modal step
    shows progress, applies the result on the main thread when done, and Esc
    cancels leaving the scene as it was. Headless there is no event loop (an
    INVOKE call falls back to execute), so the test drives the modal step."""
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    drape_ops = addon("drape_ops")
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    g_name, g_verts = garment.data.name, blender.verts(garment).copy()
    pattern = addon("data").stored_pattern(bpy.context.scene)
    body_v, body_f = drape_ops._pattern_body(pattern)
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=400).start()
    assert drape_ops.step_job(bpy.context, job, "ESC") == "RUNNING"
    job.join(120)
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "CANCELLED"
    assert "cancelled" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    assert not drape_ops._JOBS
    # the core fails mid-drape: its message in the status, the garment as it was
    from core.errors import EaseError

    real = drape_ops._compute

    def failing(*a, **k):
        a[4](0.3, "frame 12")
        raise EaseError("drape diverged at frame 12 (time step too large?)")

    drape_ops._compute = failing
    try:
        job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=400).start()
        job.join(60)
        assert drape_ops.step_job(bpy.context, job, "TIMER") == "CANCELLED"
    finally:
        drape_ops._compute = real
    assert "diverged at frame 12" in s.drape_status and "stopped" in s.drape_status
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment.data.name == g_name and np.array_equal(blender.verts(garment), g_verts)
    # a run to the end
    data = addon("data")
    key = addon("data").PATTERN_KEY
    digest = data.pattern_digest(bpy.context.scene[key])
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=4, digest=digest).start()
    assert drape_ops.step_job(bpy.context, job, "MOUSEMOVE") == "RUNNING"
    job.join(120)
    assert job.fraction >= 0.9 and job.error is None
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "FINISHED"
    assert json.loads(s.drape_json)["frames"] <= 4
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest and data.garment_positions(bpy.context.scene)[0] is not None
    # the pattern changed while a drape ran: the garment says which pattern it fits, and
    # is not exported as the new one's
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=2, digest=digest).start()
    text = bpy.context.scene[key]
    bpy.context.scene[key] = json.dumps(dict(json.loads(text), style="re-optimized meanwhile"))
    job.join(120)
    assert drape_ops.step_job(bpy.context, job, "TIMER") == "FINISHED"
    garment = next(o for o in bpy.data.objects if o.get("ease_role") == "garment")
    assert garment["ease_pattern"] == digest
    pos, why = data.garment_positions(bpy.context.scene)
    assert pos is None and "another pattern" in why
    bpy.context.scene[key] = text
    assert data.garment_positions(bpy.context.scene)[0] is not None
    # disabling the add-on while a drape runs stops the worker (no thread left behind)
    module = bpy_session["module"]
    job = drape_ops.DrapeJob(pattern, body_v, body_f, frames=5000).start()
    assert job._thread.is_alive()
    bpy.ops.preferences.addon_disable(module=module)
    assert job.cancelled and not job._thread.is_alive() and job.result is None
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    assert bpy.context.scene.ease.drape_json  # the scene's EASE data is still there
