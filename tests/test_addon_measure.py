"""The Measurements panel (ease_addon.measure_ops): tape measures in, the body fitted by the core's
made-to-measure fit (the one of ``ease body --measurements``), each value reached beside its target."""

from __future__ import annotations

import numpy as np
import pytest

from core.body.made_to_measure import fit_tape, sample_body, tolerance
from core.body.tape import TAPE_MEASURES, tape_measures

GIVEN = ("height", "chest", "waist", "hip", "inseam", "upper_arm")


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """A scene with the default body."""
    return blender.reset(body=True)


def test_panel_fits_the_body_as_the_core(bpy_session, blender, anny, tmp_path):
    bpy = bpy_session["bpy"]
    tape = bpy.context.scene.ease_tape
    obj = bpy.context.scene.ease.body
    # Measure: the reference body's tape measures, shown as reached; Use Body's copies them
    assert bpy.ops.ease.tape_measure() == {"FINISHED"}
    ref = tape_measures(anny)
    assert all(getattr(tape, f"reached_{n}") == pytest.approx(ref[n], abs=1e-3) for n in TAPE_MEASURES)
    assert bpy.ops.ease.tape_from_body() == {"FINISHED"}
    assert tape.waist == pytest.approx(round(ref["waist"], 1), abs=1e-3)
    # a hidden body's measures, loaded from a table as ease body --measurements reads it
    hidden = sample_body(np.random.default_rng([33, 7]))
    want = tape_measures(anny, shape=hidden, which=GIVEN)
    table = {k: round(v, 1) for k, v in want.items()}
    path = tmp_path / "me.csv"
    path.write_text("name,cm\n" + "".join(f"{k},{v}\n" for k, v in table.items()) + f"gender,{hidden['gender']:g}\n")
    tape.file = str(path)
    assert bpy.ops.ease.tape_load() == {"FINISHED"}
    assert [n for n in TAPE_MEASURES if getattr(tape, f"use_{n}")] == [n for n in TAPE_MEASURES if n in GIVEN]
    assert tape.give_gender and tape.gender == hidden["gender"]
    assert bpy.ops.ease.tape_fit() == {"FINISHED"}
    # the same fit as the core's, the body shaped in place, each value reached beside its target
    core = fit_tape(anny, {**table, "gender": hidden["gender"]})
    assert np.allclose(blender.verts(obj), anny.vertices(core.shape), atol=1e-5)
    for n in TAPE_MEASURES:
        assert getattr(tape, f"reached_{n}") == pytest.approx(core.achieved[n], abs=1e-3), n
        assert getattr(tape, f"status_{n}") == core.status.get(n, ""), n
    for n in GIVEN:
        assert abs(getattr(tape, f"reached_{n}") - table[n]) <= tolerance(n), n
    assert tape.report.startswith(f"{len(GIVEN)} of {len(GIVEN)} within tolerance"), tape.report
    # the phenotype sliders show the fitted phenotypes
    assert {i.name: round(i.value, 4) for i in bpy.context.scene.ease.shape} == {
        k: round(v, 4) for k, v in core.shape.items() if k in anny.shape_parameters()
    }


def test_panel_reports_bad_input_and_leaves_the_body(bpy_session, blender, tmp_path):
    bpy = bpy_session["bpy"]
    tape = bpy.context.scene.ease_tape
    obj = bpy.context.scene.ease.body
    v0 = blender.verts(obj).copy()
    (tmp_path / "bad.json").write_text('{"knee": 40}')
    tape.file = str(tmp_path / "bad.json")
    r = blender.run(bpy.ops.ease.tape_load)
    assert "ERROR" in r and "bad.json.knee: unknown measurement" in r["ERROR"], r
    for n in TAPE_MEASURES:
        setattr(tape, f"use_{n}", False)
    r = blender.run(bpy.ops.ease.tape_fit)
    assert "ERROR" in r and "tick at least one" in r["ERROR"], r
    tape.use_wrist, tape.wrist = True, 200.0  # out of range: the core's message
    r = blender.run(bpy.ops.ease.tape_fit)
    assert "ERROR" in r and "wrist=200 cm is out of range" in r["ERROR"], r
    assert np.array_equal(blender.verts(obj), v0)


def test_slider_keeps_the_fitted_local_changes(bpy_session, blender, anny):
    """After a fit, a Phenotype slider moves the phenotype and keeps the fit's local changes."""
    import json

    bpy = bpy_session["bpy"]
    tape = bpy.context.scene.ease_tape
    for n in TAPE_MEASURES:
        setattr(tape, f"use_{n}", n in ("height", "waist"))
    tape.height, tape.waist, tape.give_gender, tape.gender = 170.0, 90.0, True, 0.0
    assert bpy.ops.ease.tape_fit() == {"FINISHED"}
    obj = bpy.context.scene.ease.body
    fitted = json.loads(obj["ease_shape"])
    local = {k: v for k, v in fitted.items() if k in anny.local_change_parameters()}
    assert local, fitted
    item = next(i for i in bpy.context.scene.ease.shape if i.name == "muscle")
    item.value = 0.9
    shape = {**fitted, "muscle": 0.9}
    assert np.allclose(blender.verts(obj), anny.vertices(shape), atol=1e-5)


def test_fit_in_the_background_progress_and_esc(bpy_session, blender, addon, anny):
    """Fit Body pressed in the interface (:mod:`ease_addon.jobs`, as the Drape): the core's fit runs
    in a worker thread, its progress is the status line, Esc (cancel) leaves the body as it was, a
    failing fit says why, and a fit run to the end lands on the main thread's poll."""
    import time

    bpy = bpy_session["bpy"]
    jobs, measure_ops = addon("jobs"), addon("measure_ops")
    assert issubclass(measure_ops.EASE_OT_tape_fit, jobs.Background)  # pressed: in the background
    s, tape = bpy.context.scene.ease, bpy.context.scene.ease_tape
    obj = s.body
    v0 = blender.verts(obj).copy()
    model = measure_ops._anny(obj)
    table = {"waist": 80.0, "gender": 1.0}
    before, jobs.SYNCHRONOUS = jobs.SYNCHRONOUS, False
    try:
        # back at once, the job running; Esc: the worker stops at its next report, nothing applied
        job = measure_ops.start_fit(model, table)
        assert jobs.running(measure_ops.JOB) is job and job.thread.is_alive()
        jobs.poll()
        assert s.job_status.startswith("updating: fit body")
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert job.cancelled and job.result is None and type(job.error).__name__ == "Cancelled"
        assert s.job_status == "fit body cancelled: the scene is as it was"
        assert np.array_equal(blender.verts(obj), v0) and jobs.running() is None
        # the core fails in the worker: its message in the status line, the body as it was
        job = measure_ops.start_fit(type("Plain", (), {"name": "plain"})(), table)
        job.thread.join(120)
        jobs.poll()
        assert s.job_status.startswith("fit body stopped: made-to-measure: body 'plain' has no local changes")
        assert np.array_equal(blender.verts(obj), v0)
        # a fit to the end: the status line follows the core's progress, the poll shapes the body
        job = measure_ops.start_fit(model, table)
        seen = set()
        while job.thread.is_alive():
            seen.add(job.status())
            time.sleep(0.01)
        assert any("fitting 1 measures (" in t and t.startswith("updating: fit body") for t in seen), seen
        assert job.error is None and job.fraction == 1.0
        assert np.array_equal(blender.verts(obj), v0)  # not yet: the poll applies it
        jobs.poll()
        fit = job.result
        assert np.allclose(blender.verts(obj), anny.vertices(fit.shape), atol=1e-5)
        assert tape.reached_waist == pytest.approx(fit.achieved["waist"], abs=1e-3)
        assert abs(fit.achieved["waist"] - 80.0) <= tolerance("waist")
        assert tape.status_waist == fit.status["waist"] and tape.report.startswith("1 of 1 within tolerance")
    finally:
        jobs.cancel()
        jobs.SYNCHRONOUS = before
