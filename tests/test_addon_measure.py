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
