"""Pattern operators (ease_addon.pattern_ops): the optimized pattern's pieces beside the body
match pattern.json; the gathering setting reaches the design and the pattern."""

from __future__ import annotations

import json

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, piecewise_ease=True)


def test_pattern_objects_match_pattern_json(bpy_session, tmp_path, blender, addon):
    ramp = addon("ramp")
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    data = addon("data")
    from core.pattern.io import load_pattern

    text = bpy.context.scene[data.PATTERN_KEY]
    (tmp_path / "pattern.json").write_text(text)
    pattern = load_pattern(tmp_path / "pattern.json")
    pieces = {o["ease_panel"]: o for o in bpy.data.objects if o.get("ease_role") == "pattern_panel"}
    body_lo, body_hi = blender.world_box(s.body)
    assert sorted(pieces) == sorted(p.name for p in pattern.panels)
    for p in pattern.panels:
        o = pieces[p.name]
        ext = np.ptp(p.uv, axis=0)
        assert o.dimensions.x == pytest.approx(ext[0], abs=1e-4)
        assert o.dimensions.z == pytest.approx(ext[1], abs=1e-4)
        assert o.dimensions.y == pytest.approx(0.0, abs=1e-6)
        assert len(o.data.polygons) == len(p.faces)
        # coloured by achieved ease: the colours decode (ramp range on the mesh) to the pattern's weft scales
        col = o.data.color_attributes.get("achieved_ease")
        assert col is not None and col.domain == "CORNER"
        rgba = np.empty(len(col.data) * 4, dtype=np.float32)
        col.data.foreach_get("color", rgba)
        lo_r, hi_r = o.data["ease_ramp"]
        got = ramp.color_to_ease(rgba.reshape(-1, 4), lo_r, hi_r).reshape(-1, 3)[:, 0]
        assert np.allclose(got, np.clip(p.achieved_weft, lo_r, hi_r), atol=1e-4)
        assert np.mean((p.achieved_weft >= lo_r) & (p.achieved_weft <= hi_r)) > 0.95
        kids = {c.type for c in o.children}
        assert {"CURVE", "MESH", "FONT"} <= kids  # outline, grain arrow, name
        # laid out beside the body, not through it
        lo, hi = blender.world_box(o)
        assert hi[0] < body_lo[0] or lo[0] > body_hi[0] or hi[1] < body_lo[1] or lo[1] > body_hi[1], p.name
    figures = json.loads(s.pattern_json)
    assert figures["pieces"] == len(pattern.panels)
    assert figures["flipped triangles"] == 0
    assert figures["ease compliance mean %"] == pytest.approx(pattern.report["metrics"]["compliance"]["mean"], abs=1e-3)
    assert "seam mismatch max mm" in figures
    # piecewise ease realised: the 1.4 piece is wider per unit body than the 1.2 one
    first = pattern.panels[0] if pattern.panels[0].name == sorted(pieces)[0] else pattern.panel(sorted(pieces)[0])
    assert np.median(first.achieved_weft) > 1.0


def test_gathering_setting_reaches_the_design_and_the_pattern(bpy_session, addon):
    """The Pattern panel's gathering threshold is kept in the design and decides which seams are gathered."""
    bpy = bpy_session["bpy"]
    scene = bpy.context.scene
    s = scene.ease
    data = addon("data")

    def gathered():
        return [x["name"] for x in json.loads(scene[data.PATTERN_KEY])["seams"] if x.get("gathered")]

    try:
        s.gather_auto = False
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(s.design_json)["materials"]["gather_above"] is None
        assert gathered() == []
        # a 1 % threshold gathers seams whose sides differ a little (ease 1.2 against 1.4 across a seam)
        s.gather_auto, s.gather_above_pct = True, 1.0
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(s.design_json)["materials"]["gather_above"] == pytest.approx(0.01)
        assert gathered()
        assert json.loads(s.pattern_json)["gathered seams"] == len(gathered())
    finally:
        s.gather_auto, s.gather_above_pct = True, 20.0
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    assert json.loads(s.design_json)["materials"]["gather_above"] == pytest.approx(0.2)
    assert "gathered seams" not in json.loads(s.pattern_json) or gathered()


def test_solver_configuration_reaches_the_pattern(bpy_session, addon):
    """The Pattern panel's solver choice is the configuration Optimize Pattern solves with; every
    configuration of the core is offered, after the design's own choice (the default)."""
    from core.workflows import CONFIGS

    bpy = bpy_session["bpy"]
    scene = bpy.context.scene
    s = scene.ease
    data = addon("data")
    props = addon("properties")
    assert [k for k, _, _ in props.SOLVER_CONFIGS][0] == data.DESIGN_SOLVER == s.solver_config
    assert sorted(k for k, _, _ in props.SOLVER_CONFIGS[1:]) == sorted(CONFIGS)
    try:
        s.solver_config = "fitted"
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        fitted = json.loads(scene[data.PATTERN_KEY])
        assert fitted["report"]["config"] == "fitted"
    finally:
        s.solver_config = data.DESIGN_SOLVER
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    plain = json.loads(scene[data.PATTERN_KEY])
    assert plain["report"]["config"] == "improved"  # the top names none: the core's default
    # a different solve, not the same pattern relabelled
    assert (
        fitted["report"]["metrics"]["compliance"]["warp_mean"] != plain["report"]["metrics"]["compliance"]["warp_mean"]
    )


def test_the_designs_solver_is_the_default_and_a_choice_overrides_it(bpy_session, addon):
    """A design naming its configuration ("solver") is solved with it under the Solver choice
    *Design's*, which the panel spells out; a configuration chosen in the panel wins over it."""
    bpy = bpy_session["bpy"]
    scene = bpy.context.scene
    s = scene.ease
    data = addon("data")
    before = s.design_json
    try:
        s.design_json = json.dumps({**json.loads(before), "solver": "stretch"}, sort_keys=True)
        assert data.design_solver(scene) == "stretch"
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(scene[data.PATTERN_KEY])["report"]["config"] == "stretch"
        assert json.loads(s.design_json)["solver"] == "stretch"  # kept in the design
        s.solver_config = "improved"
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        assert json.loads(scene[data.PATTERN_KEY])["report"]["config"] == "improved"
        assert json.loads(s.design_json)["solver"] == "stretch"  # the choice does not edit it
    finally:
        s.solver_config = data.DESIGN_SOLVER
        s.design_json = before
    assert data.design_solver(scene) == "improved"


def test_optimize_runs_in_the_background(bpy_session, blender, addon):
    """Optimize Pattern pressed in Blender's UI (its job, as Drape's): the cut and the solve run in
    a worker, the operator returns with the scene as it was and the status "updating" (the
    Pattern panel shows it with Cancel); the pattern lands in one pass, the same pattern as in
    line; Esc leaves the scene as it was; a result landing on a design changed meanwhile is
    refused with the reason; from a script it runs in line even where jobs are threaded."""
    bpy = bpy_session["bpy"]
    jobs, pattern_ops, data = addon("jobs"), addon("pattern_ops"), addon("data")
    blender.reset(body=True, design=DESIGN, piecewise_ease=True)
    s = bpy.context.scene.ease
    jobs.SYNCHRONOUS = False
    try:
        job, said = pattern_ops.start_optimize(bpy.context)
        assert job.thread is not None and not said and not blender.objects("pattern_panel")
        assert s.job_status.startswith("updating: Optimize Pattern")
        from test_addon_honest import _draw  # the Pattern panel shows the line and its Cancel button

        log = _draw(blender, "EASE_PT_pattern")
        assert any(t.startswith("updating: Optimize") for t in log["labels"]) and "ease.cancel_jobs" in log["operators"]
        jobs.wait()
        got = {p.name: p.uv for p in data.stored_pattern(bpy.context.scene).panels}
        assert said and blender.objects("pattern_panel")
        # a script's call: in line, the same pattern (its wall clock aside)
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"} and jobs.running() is None
        want = data.stored_pattern(bpy.context.scene)
        assert sorted(got) == sorted(p.name for p in want.panels)
        assert all(np.array_equal(p.uv, got[p.name]) for p in want.panels)
        text = bpy.context.scene[data.PATTERN_KEY]
        # Esc: nothing applied
        job, said = pattern_ops.start_optimize(bpy.context)
        assert jobs.cancel() == 1
        job.thread.join(120)
        jobs.poll()
        assert not said and bpy.context.scene[data.PATTERN_KEY] == text and "cancelled" in s.job_status
        # the design changed while it ran: refused, said
        job, said = pattern_ops.start_optimize(bpy.context)
        job.thread.join(120)
        assert bpy.ops.ease.set_parameter(name=s.design_params[0].name, value=s.design_params[0].value * 1.01) == {
            "FINISHED"
        }
        jobs.wait()
        assert not said and "changed" in s.job_status and bpy.context.scene[data.PATTERN_KEY] == text
        assert not addon("state").BUGS
    finally:
        jobs.wait()
        jobs.SYNCHRONOUS = True
