"""Live mode (ease_addon.live): a painted change of the ease layer re-solves the pattern with the kept
factorisation and updates the pattern objects in place; the loop converges to the cold solve of the
painted field; a topology change rebuilds once; undo after a live update restores the previous pattern.

Headless, strokes are written as attribute data (a paint stroke segfaults without a window) and the
timer's tick (:func:`ease_addon.live.step`) is called directly, as the timer would call it.
"""

from __future__ import annotations

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene: a body, the design with piecewise ease, its pattern, Live on."""
    blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
    blender.scene.ease.live = True
    yield blender
    blender.scene.ease.live = False


def _stroke(blender, ease: float, seed: int):
    """Paint ``ease`` on a brush-sized patch (6 cm) around a random vertex of the garment."""
    bpy = blender.bpy
    ease_ops, data = blender.mod("ease_ops"), blender.mod("data")
    obj = bpy.context.scene.ease.body
    cut = data.current_cut(bpy.context)
    on = np.unique(cut.embedding.tocsr().indices)
    verts = blender.verts(obj).astype(np.float64)
    c = verts[np.random.default_rng(seed).choice(on)]
    mask = np.linalg.norm(verts - c, axis=1) < 0.06
    ease_ops.write_vertex_ease(obj, bpy.context.scene, ease, mask)
    return mask


def _converge(blender, limit=500):
    live, jobs = blender.mod("live"), blender.mod("jobs")
    for _ in range(limit):
        if live.step(blender.bpy.context)["converged"]:
            return
        jobs.wait()  # (threaded: the work a tick started off the main thread lands)
    raise AssertionError("live mode did not converge")


def _pieces(blender):
    return {o.name: blender.verts(o).copy() for o in blender.objects("pattern_panel")}


def _names(bpy):
    return (
        sorted(o.name for o in bpy.data.objects),
        sorted(m.name for m in bpy.data.meshes),
        sorted(c.name for c in bpy.data.curves),
    )


def _stored_uv(blender):
    p = blender.mod("data").stored_pattern(blender.bpy.context.scene)
    return {q.name: np.asarray(q.uv) for q in p.panels}


def test_live_update_in_place_and_convergence_to_the_cold_solve(blender):
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)  # adopt the layer as it is
    before, names = _pieces(blender), _names(bpy)
    _stroke(blender, 1.75, seed=3)
    out = live.step(bpy.context)
    assert out["changed"] and out["iterations"] >= 1 and not out["converged"]
    after = _pieces(blender)
    assert _names(bpy) == names  # no new object, mesh or curve, no new name
    assert sorted(after) == sorted(before)
    assert any(not np.array_equal(before[k], after[k]) for k in before)  # the pieces moved
    _converge(blender)
    assert _names(bpy) == names
    # converged: the stored pattern is the cold solve of the painted field (bitwise: the same solver
    # with the same targets from the same start) and the piece objects show it
    session = live.session_for(bpy.context)
    cold = session.cold_pattern(*live.targets(bpy.context.scene.ease.body, bpy.context.scene))
    stored = _stored_uv(blender)
    for p in cold.panels:
        assert np.allclose(stored[p.name], p.uv, rtol=0, atol=1e-12)
        o = next(o for o in blender.objects("pattern_panel") if o["ease_panel"] == p.name)
        assert np.allclose(blender.verts(o)[:, [0, 2]], p.uv, atol=1e-6)  # float32 mesh
    import json

    figures = json.loads(bpy.context.scene.ease.pattern_json)
    assert figures["ease compliance mean %"] == pytest.approx(cold.report["metrics"]["compliance"]["mean"], abs=1e-3)
    # the fit overlay: per face on its corners, finite colours, grey off the garment
    me = bpy.context.scene.ease.body.data
    fit = me.color_attributes.get(live.FIT_LAYER)
    assert fit is not None and fit.domain == "CORNER"
    assert me.color_attributes.active_color_name == "ease"  # painting still paints the ease layer
    rgba = np.empty(len(fit.data) * 4, dtype=np.float32)
    fit.data.foreach_get("color", rgba)
    rgba = rgba.reshape(-1, 3, 4)[:, 0]
    tri = np.unique(session.triangles)
    assert not np.allclose(rgba[tri, :3], 0.5) and np.allclose(np.delete(rgba, tri, axis=0)[:, :3], 0.5)
    assert len(bpy.context.scene.ease.live_legend) == 5
    # converged: a tick without a change does no work
    assert live.step(bpy.context)["iterations"] == 0


def test_topology_change_rebuilds_once(blender):
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    builds = live._LIVE["builds"]
    s = bpy.context.scene.ease
    name = s.design_params[0].name
    p = s.design_params[0]
    assert bpy.ops.ease.set_parameter(name=name, value=0.5 * (p.value + p.max)) == {"FINISHED"}
    live.step(bpy.context)
    assert live._LIVE["builds"] == builds + 1
    _converge(blender)
    _stroke(blender, 1.3, seed=5)
    _converge(blender)
    assert live._LIVE["builds"] == builds + 1
    assert blender.objects("pattern_panel")


def _cold_uv(blender):
    live = blender.mod("live")
    bpy = blender.bpy
    session = live.session_for(bpy.context)
    cold = session.cold_pattern(*live.targets(bpy.context.scene.ease.body, bpy.context.scene))
    return {p.name: p.uv for p in cold.panels}


def _stored(blender):
    """The stored pattern.json and the key figures, wall-clock times left out (they differ run to run),
    and the live record's iteration count (how many warm iterations fitted the time slices before the
    cold solve: a matter of the clock, not of the pattern)."""
    import json

    from core.pattern.io import WALL_CLOCK

    scene = blender.bpy.context.scene
    d = json.loads(scene["ease_pattern_json"])
    d["report"] = {k: v for k, v in d["report"].items() if k not in WALL_CLOCK}
    d["report"].get("live", {}).pop("iterations", None)
    figures = {k: v for k, v in json.loads(scene.ease.pattern_json).items() if not k.endswith(" s")}
    return d, figures


def test_final_work_in_bounded_units(blender):
    """After the cold solve, the final work (show, measure, encode, store) comes in units: with a
    zero slice every tick does exactly one unit of work (one iteration, with the showing of a warm
    state, or one final unit), one encoding unit per piece; what is stored is what a one-shot
    store writes, byte for byte."""
    from core.fileio import dumps_json
    from core.pattern.io import pattern_to_json

    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    _stroke(blender, 1.45, seed=21)
    ticks = []
    for _ in range(500):
        ticks.append(live.step(bpy.context, budget_s=0.0))
        if ticks[-1]["converged"]:
            break
    assert ticks[-1]["converged"] and ticks[0]["changed"]
    assert all(t["iterations"] + len(t["units"]) == 1 for t in ticks)
    stored = blender.mod("data").stored_pattern(bpy.context.scene)
    assert [u for t in ticks for u in t["units"]] == ["show", "measure"] + ["encode"] * len(stored.panels) + ["store"]
    assert bpy.context.scene["ease_pattern_json"] == dumps_json(pattern_to_json(stored), indent=None)
    cold = _cold_uv(blender)
    assert all(np.array_equal(p.uv, cold[p.name]) for p in stored.panels)
    # a slice that holds it all: the same work in one tick after the solve
    _stroke(blender, 1.25, seed=22)
    while not live.step(bpy.context, budget_s=0.0)["iterations"] or not live.session_for(bpy.context).converged:
        pass
    out = live.step(bpy.context, budget_s=60.0)
    assert out["converged"] and out["units"] == ["show", "measure"] + ["encode"] * len(stored.panels) + ["store"]


def test_undo_restores_the_previous_pattern(blender):
    """One undo step per stroke, the stroke's own (headless, the test pushes it as a paint stroke
    does): live mode adds none, so one undo goes back one stroke, and the loop converges to the
    previous stroke's pattern again, bit for bit; redo comes back to the last one's."""
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    _stroke(blender, 1.6, seed=7)
    bpy.ops.ed.undo_push(message="stroke A")  # what the paint stroke pushes at its end
    _converge(blender)
    first, first_uv = _stored(blender), _stored_uv(blender)
    layer = live._colors(bpy.context.scene.ease.body)
    _stroke(blender, 1.05, seed=8)
    bpy.ops.ed.undo_push(message="stroke B")
    assert live.step(bpy.context)["changed"]  # a live update
    _converge(blender)
    second, second_text = _stored_uv(blender), _stored(blender)
    assert any(not np.array_equal(second[k], first_uv[k]) for k in first_uv)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    # one step back: the paint before the last stroke; the loop takes it up and converges to
    # its pattern again (stored, shown, figured)
    assert np.array_equal(live._colors(bpy.context.scene.ease.body), layer)
    _converge(blender)
    assert _stored(blender) == first
    for o in blender.objects("pattern_panel"):
        assert np.allclose(blender.verts(o)[:, [0, 2]], first_uv[o["ease_panel"]], atol=1e-6)
    assert bpy.ops.ed.redo() == {"FINISHED"}
    _converge(blender)
    assert _stored(blender) == second_text


def test_strokes_faster_than_convergence_keep_one_step_each(blender):
    """A stroke that comes before the previous one converged: undo still goes back one stroke
    (its paint), and the loop converges to its pattern."""
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    _stroke(blender, 1.5, seed=11)
    bpy.ops.ed.undo_push(message="stroke A")
    assert live.step(bpy.context)["changed"]
    layer_a = live._colors(bpy.context.scene.ease.body)
    _stroke(blender, 1.15, seed=12)
    bpy.ops.ed.undo_push(message="stroke B")
    assert live.step(bpy.context)["changed"]
    _converge(blender)
    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert np.array_equal(live._colors(bpy.context.scene.ease.body), layer_a)
    _converge(blender)
    cold = _cold_uv(blender)
    stored = _stored_uv(blender)
    assert all(np.array_equal(stored[k], cold[k]) for k in cold)


def test_live_follows_the_file_it_opens(blender, bpy_session):
    """A file saved with Live on opens with the loop running (it converges and follows a stroke);
    one saved with it off opens with no handler, timer or session of the previous file."""
    bpy = blender.bpy
    live = blender.mod("live")
    _converge(blender)
    on, off = str(bpy_session["tmp"] / "live_on.blend"), str(bpy_session["tmp"] / "live_off.blend")
    assert bpy.ops.wm.save_as_mainfile(filepath=on, copy=True) == {"FINISHED"}
    bpy.context.scene.ease.live = False
    assert bpy.ops.wm.save_as_mainfile(filepath=off, copy=True) == {"FINISHED"}
    bpy.context.scene.ease.live = True
    _converge(blender)
    assert live._LIVE["session"] is not None
    assert bpy.ops.wm.open_mainfile(filepath=off) == {"FINISHED"}
    assert not bpy.context.scene.ease.live
    assert live._on_depsgraph not in bpy.app.handlers.depsgraph_update_post
    assert not bpy.app.timers.is_registered(live._tick) and live._LIVE["session"] is None
    assert bpy.ops.wm.open_mainfile(filepath=on) == {"FINISHED"}
    assert bpy.context.scene.ease.live
    assert live._on_depsgraph in bpy.app.handlers.depsgraph_update_post
    assert bpy.app.timers.is_registered(live._tick)
    _converge(blender)
    before = _pieces(blender)
    _stroke(blender, 1.7, seed=31)
    bpy.context.view_layer.update()  # what a stroke's redraw does: the handler wakes the timer
    assert live.step(bpy.context)["changed"]
    assert any(not np.array_equal(before[k], v) for k, v in _pieces(blender).items())
    _converge(blender)


def _figures_and_uv(blender):
    import json

    s = blender.bpy.context.scene
    figures = {k: v for k, v in json.loads(s.ease.pattern_json).items() if not k.endswith(" s")}
    return figures, _stored_uv(blender)


@pytest.mark.parametrize(
    "piecewise, solver", [(False, "design"), (True, "design"), (False, "stretch")]
)  # the template's own ease, Ease to Design's, a Solver chosen over the design's
def test_live_on_keeps_the_optimized_pattern(blender, piecewise, solver):
    """Switching Live on with no new paint keeps the pattern Optimize Pattern made, bit for bit
    (it re-read the template's ease through the vertex layer, mixed with the body's 1.0 where the
    cut crosses the body's triangles: compliance 1.068 -> 1.112 %, the front's area changed; and
    it solved with "improved" where the Solver choice or the design names another configuration);
    a stroke then changes the pattern only through what it painted."""
    bpy = blender.bpy
    live = blender.mod("live")
    s = bpy.context.scene.ease
    s.live = False
    try:
        blender.reset(body=True, design=DESIGN, piecewise_ease=piecewise)
        bpy.context.scene.ease.solver_config = solver
        assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
        figures, uv = _figures_and_uv(blender)
        s = bpy.context.scene.ease
        s.live = True
        _converge(blender)
        assert s.live_status.startswith("converged")
        after, uv_after = _figures_and_uv(blender)
        assert after == figures
        assert all(np.array_equal(uv[k], uv_after[k]) for k in uv)
        mask = _stroke(blender, 1.6, seed=41)
        _converge(blender)
        field, painted = live.targets(s.body, bpy.context.scene)
        tri = blender.mod("convert").get_triangles(s.body.data)
        assert painted is not None and painted.any() and np.all(mask[tri[painted]].any(axis=1))
        assert any(not np.array_equal(uv[k], v) for k, v in _stored_uv(blender).items())
    finally:
        bpy.context.scene.ease.live = False
        blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
        bpy.context.scene.ease.solver_config = "design"
        bpy.context.scene.ease.live = True


def _threaded(blender):
    """The jobs' threaded path, as in Blender's UI (headless runs compute in line)."""
    jobs = blender.mod("jobs")

    class _On:
        def __enter__(self):
            jobs.SYNCHRONOUS = False

        def __exit__(self, *exc):
            jobs.wait()
            jobs.SYNCHRONOUS = True

    return _On()


@pytest.mark.parametrize("pattern", [True, False])
def test_live_builds_its_session_off_the_main_thread(blender, pattern):
    """Live switched on (over a pattern, or with none yet): the tick that finds no session starts
    its build (cut, flattening, factorisation) in a worker thread and returns at once, with no
    iteration; the panel says "updating" and the pieces stay as they are until the build lands;
    then the loop converges to what it converges to in line (the optimized pattern kept; with no
    pattern, pieces made once from the converged pattern); a stroke's converged pattern, measured
    and encoded in a worker, is stored as in line."""
    from core.fileio import dumps_json
    from core.pattern.io import pattern_to_json

    bpy = blender.bpy
    live, jobs = blender.mod("live"), blender.mod("jobs")
    bpy.context.scene.ease.live = False
    try:
        blender.reset(body=True, design=DESIGN, pattern=pattern)
        s = bpy.context.scene.ease
        before = _figures_and_uv(blender) if pattern else None
        names = _names(bpy)
        with _threaded(blender):
            s.live = True
            out = live.step(bpy.context)
            assert out["iterations"] == 0 and not out["changed"] and not out["converged"]
            assert s.live_status.startswith("updating: Live: preparing the solver")
            assert s.job_status.startswith("updating") and jobs.running(live.JOB) is not None
            assert _names(bpy) == names  # nothing shown before the build lands
            jobs.wait()
            assert jobs.running() is None and s.job_status == ""
            _converge(blender)  # (the measuring and encoding of the converged pattern: off the main thread too)
            _converge(blender)  # (the tick after the body's overlay update: nothing to do)
            assert s.live_status.startswith("converged")
            if pattern:
                assert _figures_and_uv(blender)[0] == before[0]
                assert all(np.array_equal(before[1][k], v) for k, v in _stored_uv(blender).items())
                # a stroke: the stored pattern (measured and encoded in a worker) is the cold solve
                _stroke(blender, 1.65, seed=51)
                _converge(blender)
                cold = _cold_uv(blender)
                stored = blender.mod("data").stored_pattern(bpy.context.scene)
                assert all(np.array_equal(p.uv, cold[p.name]) for p in stored.panels)
                assert bpy.context.scene["ease_pattern_json"] == dumps_json(pattern_to_json(stored), indent=None)
        if not pattern:
            assert len(blender.objects("pattern_panel")) == 2
            cold = _cold_uv(blender)
            assert all(np.array_equal(v, cold[k]) for k, v in _stored_uv(blender).items())
    finally:
        bpy.context.scene.ease.live = False
        blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
        bpy.context.scene.ease.live = True


def test_cancelling_the_build_turns_live_off(blender):
    """Cancel (the panel's button; Esc does the same) while Live prepares: the build's result is
    dropped, Live goes off and says why; nothing is left running."""
    bpy = blender.bpy
    live, jobs = blender.mod("live"), blender.mod("jobs")
    s = bpy.context.scene.ease
    s.live = False
    live.stop()
    try:
        with _threaded(blender):
            s.live = True
            live.step(bpy.context)
            assert jobs.running(live.JOB) is not None
            assert bpy.ops.ease.cancel_jobs() == {"FINISHED"}
            assert not s.live and "cancelled" in s.live_status
            assert jobs.running() is None and not bpy.ops.ease.cancel_jobs.poll()
        assert live._LIVE["session"] is None and not bpy.app.timers.is_registered(live._tick)
    finally:
        s.live = True


def test_threaded_ticks_never_iterate(blender):
    """In Blender's window the solve runs in a worker (issue 32: no tick may block the viewport
    for the solve): every iteration of the session's solver runs off the main thread; a stroke's
    tick only hands the field over (the pieces stay until its warm slice lands, then move in
    place); a stroke while the previous one's solve runs drops it (the newer paint wins); the
    loop converges to the cold solve of the last paint, stored with its text; Cancel (Esc) while
    it solves turns Live off and says so."""
    import threading

    from core.fileio import dumps_json
    from core.pattern.io import pattern_to_json

    bpy = blender.bpy
    live, jobs = blender.mod("live"), blender.mod("jobs")
    s = bpy.context.scene.ease
    _converge(blender)
    session = live.session_for(bpy.context)
    threads = []
    real = session.solver.iterate

    def iterate(*a, **k):
        threads.append(threading.current_thread() is threading.main_thread())
        return real(*a, **k)

    session.solver.iterate = iterate
    try:
        with _threaded(blender):
            before, names = _pieces(blender), _names(bpy)
            _stroke(blender, 1.7, seed=61)
            out = live.step(bpy.context)
            assert out["changed"] and out["iterations"] == 0 and not out["converged"]
            job = jobs.running(live.SOLVE_JOB)
            assert job is not None and s.live_status.startswith("converging")
            shown = live._LIVE["shown"]
            jobs.wait()  # the warm slice lands: the pieces move in place, no new datablock
            assert live._LIVE["shown"] == shown + 1 and _names(bpy) == names
            assert any(not np.array_equal(before[k], v) for k, v in _pieces(blender).items())
            assert live.step(bpy.context)["iterations"] > 0 and jobs.running(live.SOLVE_JOB) is not None
            # a new stroke while the cold solve runs: that job is dropped, the new field solved
            _stroke(blender, 1.3, seed=62)
            assert live.step(bpy.context)["changed"]
            assert job.cancelled or job is not jobs.running(live.SOLVE_JOB)
            _converge(blender)
            assert s.live_status.startswith("converged")
            assert threads and not any(threads), "an iteration ran on the main thread"
            stored = blender.mod("data").stored_pattern(bpy.context.scene)
            cold = _cold_uv(blender)  # (the test's cold solve: on the main thread)
            assert all(np.array_equal(p.uv, cold[p.name]) for p in stored.panels)
            assert bpy.context.scene["ease_pattern_json"] == dumps_json(pattern_to_json(stored), indent=None)
            # Esc while it solves: Live off, nothing applied
            _stroke(blender, 1.5, seed=63)
            live.step(bpy.context)
            assert jobs.running(live.SOLVE_JOB) is not None
            assert bpy.ops.ease.cancel_jobs() == {"FINISHED"}
            assert not s.live and "solve was cancelled" in s.live_status
    finally:
        session.solver.iterate = real
        s.live = False
        blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
        bpy.context.scene.ease.live = True


def test_an_undo_over_pending_final_work_stores_the_converged_pattern(blender):
    """Seed 16 of the --full walk: a template loaded with Live on converges (its cold solve
    complete) while its final work (show, measure, store) is still pending; an undo that keeps
    that design drops the pending work. Live must store the converged pattern before it says
    "converged" (it said "converged" over the previous design's stored pattern, of another cut)."""
    bpy = blender.bpy
    live, data = blender.mod("live"), blender.mod("data")
    try:
        _converge(blender)
        assert bpy.ops.ease.load_template(template="blouse_fitted.json") == {"FINISHED"}
        for _ in range(2000):
            live.step(bpy.context, budget_s=0.0)  # (one iteration a tick: no final unit beside it)
            if live.session_for(bpy.context).converged:
                break
        assert live._LIVE["final"]  # converged, the final work pending: the old design's pattern stored
        cut = [p.name for p in live.session_for(bpy.context).prep.cut.panels]
        assert [p.name for p in data.stored_pattern(bpy.context.scene).panels] != cut
        bpy.ops.ed.undo_push(message="pending")
        assert bpy.ops.ease.measure("EXEC_DEFAULT", True) == {"FINISHED"}  # another undo step
        bpy.ops.ed.undo()  # back to the pending state: same design, same paint
        _converge(blender)
        _converge(blender)  # (the tick after the new pieces' update: nothing to do)
        assert bpy.context.scene.ease.live_status.startswith("converged")
        stored, cold = data.stored_pattern(bpy.context.scene), _cold_uv(blender)
        assert [p.name for p in stored.panels] == cut
        assert all(np.array_equal(p.uv, cold[p.name]) for p in stored.panels)
    finally:
        bpy.context.scene.ease.live = False
        blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
        bpy.context.scene.ease.live = True


def test_a_new_cuts_pieces_are_written_over_several_ticks(blender):
    """Issue 32 (no tick over 50 ms): with the solve in a worker, the converged pattern of a new
    cut (Live on before any pattern) lands as arrays made in the worker; the ticks after it make
    the pieces' meshes a few at a time (no object changes, the panel says "updating: Live: writing
    the pieces k/n"), then one tick puts them in place with the stored pattern, its figures and one
    undo step. An undo while they are written drops them (no mesh left behind, no ``.001``) and
    Live converges again to the cold solve."""
    bpy = blender.bpy
    live, jobs, data = blender.mod("live"), blender.mod("jobs"), blender.mod("data")
    bpy.context.scene.ease.live = False
    write_s = live.WRITE_S
    try:
        for undo in (False, True):
            blender.reset(body=True, design=DESIGN, pattern=False)
            s = bpy.context.scene.ease
            names = _names(bpy)
            live.WRITE_S = 0.0  # one mesh a tick
            with _threaded(blender):
                bpy.ops.ed.undo_push(message="Live off")
                s.live = True
                bpy.ops.ed.undo_push(message="Live on")
                for _ in range(500):
                    live.step(bpy.context)
                    jobs.wait()
                    if live._LIVE["writing"] is not None:
                        break
                assert live._LIVE["writing"] is not None and _names(bpy) == names
                n = len(live._LIVE["writing"]["todo"])
                assert n == 2
                live.step(bpy.context)  # the first mesh made: no object yet
                assert s.live_status == f"updating: Live: writing the pieces 1/{n}"
                assert _names(bpy)[0] == names[0] and not live._LIVE["landed"]
                if undo:  # Ctrl+Z: back to the step before Live on
                    bpy.ops.ed.undo()
                    s = bpy.context.scene.ease
                    assert live._LIVE["writing"] is None and not s.live
                    assert not [m for m in bpy.data.meshes if m.name.startswith("EASE piece")]
                    s.live = True
                _converge(blender)
                _converge(blender)
            assert s.live_status.startswith("converged")
            meshes = [m.name for m in bpy.data.meshes if m.name.startswith("EASE piece")]
            assert sorted(meshes) == sorted(o.data.name for o in blender.objects("pattern_panel"))
            assert not any(n.endswith(".001") for group in _names(bpy) for n in group)
            stored, cold = data.stored_pattern(bpy.context.scene), _cold_uv(blender)
            assert all(np.array_equal(p.uv, cold[p.name]) for p in stored.panels)
            s.live = False
    finally:
        live.WRITE_S = write_s
        bpy.context.scene.ease.live = False
        blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True)
        bpy.context.scene.ease.live = True


def test_a_worker_start_freezes_the_heap(blender):
    """Issue 32: a full garbage collection walks every tracked object (60-70 ms of the GIL at
    Blender's size), and one in a worker stalls the viewport as long. A job started in a worker
    first frees the young garbage (a reference cycle that just died is collected, not frozen),
    then freezes what is alive: later full collections walk only what was made since; so does a
    result's landing; the add-on's unregister gives the frozen objects back to the collector."""
    import gc
    import threading
    import weakref

    jobs = blender.mod("jobs")

    class Node:
        pass

    was_enabled = gc.isenabled()
    gc.disable()  # (no automatic collection: the cycle below dies only by the job's start)
    jobs.thaw_heap()
    kept = [Node()]  # alive as the job starts
    a, b = Node(), Node()
    a.other, b.other = b, a
    dead = weakref.ref(a)
    del a, b
    assert dead() is not None and any(o is kept for o in gc.get_objects())
    release = threading.Event()
    landed = []

    def compute(progress):
        release.wait(30.0)
        return [Node()]  # made in the worker, after the freeze

    try:
        with _threaded(blender):
            jobs.start("test-freeze", "test", compute, landed.append)
            assert dead() is None, "the dead cycle was frozen, not freed"
            assert gc.get_freeze_count() > 0
            assert not any(o is kept for o in gc.get_objects()), "an object alive at the start is still walked"
            release.set()
            jobs.wait()
            # what the worker made is frozen too once its result landed (its first imports: 90k)
            assert landed and not any(o is landed[0] for o in gc.get_objects())
    finally:
        release.set()
        jobs.wait()
        jobs.thaw_heap()
        if was_enabled:
            gc.enable()
    assert gc.get_freeze_count() == 0 and any(o is kept for o in gc.get_objects())
