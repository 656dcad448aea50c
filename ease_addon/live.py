"""Live mode: the pattern follows the ease the designer paints.

While *Live* (Ease panel) is on, a ``depsgraph_update_post`` handler notices
updates of the body and wakes a ``bpy.app.timers`` tick. Each tick takes at
most one slice (:data:`SLICE_S`: solving, writing the objects, the final work):

- when the body's ``ease`` layer differs from what the pattern was solved for
  (a stroke), the new field goes to the core's :class:`core.live.LiveSession`
  (kept cut and factorisation), one warm slice (the iterations that fit beside
  showing their result) runs from the current pattern and the flat pattern objects are updated in place (vertex positions,
  boundary curves, grain arrows, achieved-ease colours: no new object, no new
  name), with the body's fit overlay (:data:`FIT_LAYER`);
- while the designer is idle, later ticks advance the session's cold solve of
  the painted field; when it is complete (converged: the pattern *Optimize
  Pattern* gives for this paint) the final work follows in units that each fit
  a slice (show the objects, measure, encode the stored pattern a piece at a
  time, store it with the key figures), and then the timer stops: no CPU is
  used until the next update of the body.

That is the loop in line (headless: :data:`.jobs.SYNCHRONOUS`), where a tick plans its work
with running estimates of each kind of work, so that it takes at most one slice, or one
indivisible unit (one iteration and the showing of its result, or the metrics) where that is
longer. In Blender's window the solve runs in a worker (:func:`_solve_in_worker`, the job
:data:`SOLVE_JOB`): a tick only reads the layer and, when it changed, hands the field to a new
job (the running one is dropped: the newer paint wins); the worker takes one iteration from
the current pattern and returns its pattern and overlay values (shown when the jobs' poll
lands it), then the next job runs the cold solve to its end and returns the converged pattern
measured and encoded, stored with its figures in one pass. The main thread never iterates.

A design whose topology changed (a keypoint moved, a parameter changed, a seam
added) gets a new session once (:func:`core.live.topology_key`). A session is built off the
main thread (:mod:`.jobs`: the cut, the flattening and the factorisation of the design's seam
plan): until it lands the ticks only say "updating: Live: preparing the solver n %" and the
pieces shown stay; the pieces of a new cut are made once, from its converged pattern.

Undo: one step per stroke, the stroke's own (Blender's paint stroke, or the
EASE operator that wrote the layer, pushes it); live mode pushes none, which
would double it, except after it rebuilt the pieces of a new cut (datablocks
replaced outside an undo step crash Blender's memfile undo).

Status: "converged" only once a tick has seen the scene as it is (an EASE
operator, a slider's re-cut, an update of the body or an undo set it to
"updating" first) and while the stored pattern is Live's own (Optimize,
Transfer or Adapt storing another one makes it say so). After an undo or redo the loop continues from the restored
layer and pattern and converges to the restored paint's cold solve, which is
the pattern the previous stroke had, bit for bit (the converged pattern does
not depend on the painting history).

A file saved with Live on opens with Live running (``load_post``); one saved
with it off opens with no handler and no timer of a previous file.
"""

from __future__ import annotations

import json
import threading
import time
import traceback
from collections import deque

import bpy
import numpy as np

from . import build, convert, data, jobs, pattern_ops, ramp, state, sync

JOB = "live"  # the name of the session's build in :mod:`.jobs`
SOLVE_JOB = "live-solve"  # the solve (warm slice, cold solve, the converged pattern's figures), in a worker
BUILD_TICK_S = 0.05  # seconds between ticks while a job works off the main thread
SLICE_S = 0.03  # seconds of work per tick: the longest the viewport waits for the pattern
IDLE_TICK_S = 0.005  # seconds between ticks while converging (the UI handles its events in between)
FIT_LAYER = "ease_fit"  # CORNER colour layer on the body: achieved / painted ease - 1
FIT_RANGE = 0.10  # +-10 %: the overlay's full blue / full red

# the session of the scene's design (one per add-on session: the timer serves the active scene)
_LIVE = {
    "key": None,
    "session": None,
    "colors": None,
    "mirror": None,
    "builds": 0,
    "restart": False,
    "inputs": None,
    "faces": None,
    "final": None,
    "stored": None,
    "failed": None,
    "landed": False,  # threaded: the converged pattern of the session's current field is in the scene
    "iterations": 0,  # threaded: iterations of the solve results applied since the last tick
    "shown": 0,  # threaded: solve results applied (the live bench's latency: a stroke until it grows)
    "pattern": None,  # threaded: the pattern of the last result applied (the pieces show it)
    "solve_failed": None,  # threaded: the solve's error, said by the next tick (which stops)
    "writing": None,  # threaded: the converged pattern of a new cut being written (_write_new_cut)
}
# the session is iterated by one worker at a time (a newer stroke's job waits for the dropped one to
# stop at its next iteration): the main thread never iterates it while jobs run threaded
_SOLVING = threading.Lock()
# running estimates, seconds per cut triangle of each kind of work (show, measure, encode, store)
_RATES = {}


# ----------------------------------------------------------------------------- the fit overlay


def fit_to_color(values) -> np.ndarray:
    """Diverging ramp of ``rho_hat / rho - 1`` (n,): blue below (the fabric gives less than painted),
    white at 0, red above, full colour at +-:data:`FIT_RANGE`; NaN (no garment) is grey.
    Returns (n, 4) float32 scene-linear RGBA."""
    v = np.asarray(values, dtype=np.float64)
    t = np.clip(np.nan_to_num(v, nan=0.0) / FIT_RANGE, -1.0, 1.0)
    rgba = np.ones(v.shape + (4,))
    rgba[..., 0] = np.where(t < 0, 1.0 + t, 1.0)
    rgba[..., 1] = 1.0 - np.abs(t)
    rgba[..., 2] = np.where(t > 0, 1.0 - t, 1.0)
    rgba[np.isnan(v), :3] = 0.5
    return rgba.astype(np.float32)


def fill_legend(scene) -> None:
    """The overlay's legend (percent, colour) in the Ease panel."""
    coll = scene.ease.live_legend
    if len(coll) == 5:
        return
    coll.clear()
    for v in np.linspace(-FIT_RANGE, FIT_RANGE, 5):
        item = coll.add()
        item.ease = float(100.0 * v)
        item.color = tuple(float(x) for x in fit_to_color(np.array([v]))[0])


def write_overlay(obj, pattern, session) -> None:
    """The body's :data:`FIT_LAYER` (per face, on its corners) from ``pattern``; the painting layer stays active."""
    from ..core.live import achieved_over_painted

    _write_fit(obj, achieved_over_painted(pattern, session.triangles, len(obj.data.polygons), session.areas))


def _write_fit(obj, ratio) -> None:
    """The body's :data:`FIT_LAYER` from per-face ``ratio`` (achieved / painted - 1, F_body,)."""
    me = obj.data
    attr = me.color_attributes.get(FIT_LAYER)
    if attr is None or attr.domain != "CORNER":
        active = me.color_attributes.active_color_name
        if attr is not None:
            me.color_attributes.remove(attr)
        attr = me.color_attributes.new(FIT_LAYER, "FLOAT_COLOR", "CORNER")
        if active in me.color_attributes:
            me.color_attributes.active_color = me.color_attributes[active]
    attr.data.foreach_set("color", np.repeat(fit_to_color(ratio), 3, axis=0).ravel())
    me.update()


# ----------------------------------------------------------------------------- the loop


def _colors(obj):
    attr = obj.data.color_attributes.get(convert.EASE_LAYER)
    if attr is None:
        return None
    c = np.empty(len(attr.data) * 4, dtype=np.float32)
    attr.data.foreach_get("color", c)
    return c


def _of_cut(pattern, cut) -> bool:
    """``pattern`` is a pattern of ``cut`` (its panels, their vertex counts): one to start from."""
    return (
        pattern is not None
        and [p.name for p in pattern.panels] == [p.name for p in cut.panels]
        and all(len(a.uv) == len(b.vertex_ids) for a, b in zip(pattern.panels, cut.panels))
    )


def _inputs(context) -> str:
    """What the session's inputs are read from (unchanged: nothing is re-read, a tick stays cheap)."""
    s = context.scene.ease
    obj = data.body_object(context)
    return json.dumps(
        [
            s.design_json,
            data.body_spec(obj),
            s.gather_auto,
            round(s.gather_above_pct, 6),
            s.solver_config,
            obj.name,
            len(obj.data.polygons),
        ],
        sort_keys=True,
    )


def session_for(context):
    """The live session of the scene's design on its body (built once per topology and solver
    configuration: Optimize Pattern's, so that a converged pattern is the one it gives); None
    while it is being built off the main thread (:mod:`.jobs`: the cut, the flattening and the
    factorisation; headless, in line)."""
    from ..core import workflows as wf
    from ..core.live import LiveSession, topology_key

    quick = _inputs(context)
    if quick == _LIVE.get("inputs") and _LIVE["session"] is not None:
        return _LIVE["session"]
    failed = _LIVE.get("failed")
    if failed is not None and failed[0] == quick:
        raise failed[1]  # the same inputs failed before: say it again, build nothing
    job = jobs.running(JOB)
    if job is not None and getattr(job, "inputs", None) == quick:
        return None  # being built
    # what the worker needs, read here (the worker touches no Blender data)
    scene = context.scene
    obj = data.body_object(context)
    spec = data.body_spec(obj)
    design = pattern_ops.gather_settings(scene, data.current_design(context))
    choice = data.solver_choice(scene)
    start = _stored_lazily(scene)
    faces = np.asarray(state.body_model(spec["model"]).faces)  # (the body mesh keeps its model's triangles)
    key_now, session_now = _LIVE["key"], _LIVE["session"]

    def compute(progress):
        prep = data.prepare(design, spec)
        config = wf.config_name(prep, choice)
        key = json.dumps([topology_key(prep.design, spec), config])
        if key == key_now and session_now is not None:
            return key, prep, None
        pattern = start()
        session = LiveSession(
            prep, config=config, pattern=pattern if _of_cut(pattern, prep.cut) else None, progress=progress
        )
        session.prime()
        return key, prep, session

    def apply(result):
        key, prep, session = result
        _LIVE.update(inputs=quick, faces=faces, failed=None)
        _LIVE["colors"] = None  # the design's ease may have changed: the field is taken again
        if session is not None:
            _LIVE.update(key=key, session=session, builds=_LIVE["builds"] + 1, final=None, landed=False)
        else:  # the same cut: the design's own ease may differ (Ease to Design)
            _LIVE["session"].set_design_ease(np.concatenate([np.asarray(p.ease, float) for p in prep.cut.panels]))
        wake()

    def fail(exc):
        _LIVE["failed"] = (quick, exc)
        wake()  # the next tick says it (and stops)

    try:
        job = jobs.start(JOB, "Live: preparing the solver", compute, apply, fail, cancelled=_cancelled)
    except state.USER_ERRORS as exc:
        _LIVE["failed"] = (quick, exc)
        raise
    job.inputs = quick
    return _LIVE["session"] if _LIVE.get("inputs") == quick else None


def _restart(session, restored) -> None:
    """After an undo: continue from the restored pattern (``restored()``, :func:`_stored_lazily`)
    when it is one of the session's cut (not one of another cut: a parameter undone)."""
    if restored is None:
        return
    pattern = restored()
    if _of_cut(pattern, session.prep.cut):
        session.restart_from(pattern)


def _stored_lazily(scene):
    """The scene's stored pattern as a call that returns it, for a worker: parsed there unless the
    add-on parsed this text already (the main thread only reads the text)."""
    from . import state as st

    text = scene.get(data.PATTERN_KEY)
    if not text:
        return lambda: None
    cached = st.PATTERNS.get((scene.name, data.PATTERN_KEY))
    if cached is not None and cached[0] == text:
        return lambda: cached[1]

    def parse():
        from ..core.pattern.io import pattern_from_json

        return pattern_from_json(json.loads(text))

    return parse


def _cancelled(what: str = "preparation") -> None:
    """The designer cancelled the session's build or its solve (Esc, Cancel): Live goes off."""
    scene = getattr(bpy.context, "scene", None)
    if scene is not None and scene.ease.live:
        scene.ease.live = False
        scene.ease.live_status = f"off: its {what} was cancelled"


def _per_triangle(obj, values) -> np.ndarray:
    """Per body triangle (F,) mean of per-element values of the ease layer (its vertices or corners)."""
    if obj.data.color_attributes[convert.EASE_LAYER].domain == "CORNER":
        return np.asarray(values, dtype=np.float64).reshape(-1, 3).mean(axis=1)
    faces = _LIVE.get("faces")
    if faces is None or len(faces) != len(obj.data.polygons):
        faces = convert.get_triangles(obj.data)
    return ramp.vertex_to_triangle(values, faces)


def _field(obj, scene) -> np.ndarray:
    """The painted field per body triangle (F,) as *Ease to Design* reads it (symmetrised with X-mirror)."""
    tri = _per_triangle(obj, data.layer_ease(obj, scene))
    return data.symmetrised(obj, tri) if data.x_mirror(obj) else tri


def targets(obj, scene) -> tuple:
    """``(field, painted)``: what Live solves for (:meth:`core.live.LiveSession.cut_ease`): the
    painted field (:func:`_field`) and the body triangles painted since the design's ease was
    written into the layer or taken from it (the others keep the design's own ease, so that Live
    switched on over an optimized pattern keeps it); ``painted`` None (all painted) without a
    record of the design's ease (:func:`.sync.design_record`)."""
    field = _field(obj, scene)
    base = sync.design_record(obj)
    if base is None:
        return field, None
    base = _per_triangle(obj, base)
    if data.x_mirror(obj):
        base = data.symmetrised(obj, base)
    return field, np.abs(field - base) > sync.MIRROR_TOL


def _estimate(kind: str, size: int):
    """Expected seconds of a unit of work of ``kind`` and ``size``; None before one was timed."""
    rate = _RATES.get(kind)
    return None if rate is None else rate * size


def _timed(kind: str, size: int, work):
    """Run ``work()``, keep a running estimate of its kind's seconds per size; its result."""
    t = time.perf_counter()
    out = work()
    rate = (time.perf_counter() - t) / max(size, 1)
    old = _RATES.get(kind)
    _RATES[kind] = rate if old is None else 0.7 * old + 0.3 * rate
    return out


def _show(context, session) -> None:
    """Write the session's (warm) pattern into the scene: objects in place, the overlay. The
    pieces of a new cut (a parameter or keypoint changed, no pieces yet) are not shown warm: they
    are made once, from the converged pattern, in the final work's last unit."""
    pattern = session.pattern(figures=False)
    if build.same_pieces(context.scene, pattern):
        sync.show_pieces(context, pattern)
        write_overlay(data.body_object(context), pattern, session)


def _store_final(context, pattern, text: str, same: bool, plan=None, made=None, range_=None) -> None:
    """Store Live's converged ``pattern`` (its stored ``text``): into the pieces shown where they
    are the same pieces (``same``), with the key figures; else the pieces of a new cut are made
    (from ``plan``, its :class:`.build.PatternPlan` when a worker made it, and ``made``, the new
    meshes made in earlier ticks: :func:`_write_new_cut`, coloured on ``range_``), stored and
    figured at once."""
    scene = context.scene
    if same:
        sync.store_pattern(scene, pattern, text=text)
        scene.ease.pattern_json = json.dumps(data.key_figures(pattern))
    else:
        sync.show_pattern(context, pattern, text=text, plan=plan, made=made, range_=range_)


def _final_units(context, session) -> deque:
    """The work after the cold solve completed, as a queue of ``(kind, size, work)`` units each
    well within a slice: show the pattern (objects in place, overlay), measure it, encode it a
    piece at a time, then store it with its key figures (together: the panel never shows
    figures of another pattern than the stored one). The pieces of a new cut are made in the
    store unit, in one pass (they then replace the old cut's pieces, with the new figures)."""
    from ..core import workflows as wf

    scene = context.scene
    n = len(session.triangles)
    queue = deque()
    box = {}

    def show():
        box["pattern"] = pattern = session.pattern(figures=False)
        box["same"] = build.same_pieces(scene, pattern)
        if box["same"]:
            sync.show_pieces(context, pattern)
            write_overlay(data.body_object(context), pattern, session)
        queue.append(("measure", n, measure))

    def measure():
        wf.measure_pattern(box["pattern"])
        units = session.text.units(box["pattern"])
        queue.extend(("encode", size, work) for size, work in units[:-1])
        queue.append(("store", units[-1][0], lambda: store(units[-1][1])))

    def store(join):
        pattern = box["pattern"]
        _store_final(context, pattern, join(), box["same"])
        if not box["same"]:
            write_overlay(data.body_object(context), pattern, session)
        _LIVE.update(stored=scene.get(data.PATTERN_KEY), landed=True)

    queue.append(("show", n, show))
    return queue


def step(context, budget_s: float = SLICE_S) -> dict:
    """One tick of the live loop (what the timer runs; tests call it directly).

    In line (headless: :data:`.jobs.SYNCHRONOUS`) the tick plans its work to fit ``budget_s``:
    iterations, the showing of a warm state, the units of the final work
    (:func:`_final_units`), each started only when its running estimate still fits; at least
    one unit of work is done, so a tick is longer than the slice only when that one unit is.
    Threaded (Blender's window) the tick only reads the painted field and hands it to the
    solve's job (:func:`_step_threaded`): the iterations run in a worker, whose results the
    jobs' poll writes into the scene in one pass.

    Returns ``{"changed": a new field was taken, "iterations": run (threaded: those whose
    results landed since the last tick), "units": the final units done (kinds), "converged":
    the pattern is the cold solve and stored, "seconds": wall time}``.
    """
    t0 = time.perf_counter()
    with _UndoIfRebuilt():
        return _step(context, budget_s, t0)


class _UndoIfRebuilt:
    """Around work that may make the pieces of a new cut: an undo step after it did (datablocks
    made, swapped or removed outside an undo step leave Blender's memfile undo restoring objects
    whose data it freed: the next Ctrl+Z crashed, a segfault)."""

    def __enter__(self):
        self.changes = build.DATABLOCK_CHANGES[0]

    def __exit__(self, *exc):
        if build.DATABLOCK_CHANGES[0] != self.changes:
            jobs.undo_push("EASE Live: pieces of the new cut")
        return False


def _take_field(context, session):
    """The painted field when it differs from the one taken last (a stroke, X-mirror toggled, an
    undo): ``(field, painted, restart)`` (:func:`targets`; ``restart``: after an undo, a call
    giving the restored pattern, :func:`_restart`; else None), the layer remembered; None when
    unchanged."""
    scene = context.scene
    obj = data.body_object(context)
    raw = _colors(obj)
    mirror = data.x_mirror(obj)
    if raw is None:
        return None
    if _LIVE["colors"] is not None and np.array_equal(raw, _LIVE["colors"]) and mirror == _LIVE["mirror"]:
        return None
    if sync.mirrored_paint(obj, scene):  # X-mirror: a one-sided stroke painted on both sides
        raw = _colors(obj)
    restart = None
    if _LIVE["restart"]:
        # after an undo/redo: continue from the restored pattern
        _LIVE["restart"] = False
        restart = _stored_lazily(scene)  # (parsed by the solve: a worker when threaded)
    field, painted = targets(obj, scene)
    sync.remember_layer(obj, scene)
    _LIVE["colors"], _LIVE["mirror"] = raw, mirror
    return field, painted, restart


def _step(context, budget_s: float, t0: float) -> dict:
    scene = context.scene
    session = session_for(context)
    if session is None:  # being built off the main thread: the panel says so, the tick returns
        job = jobs.running(JOB)
        scene.ease.live_status = job.status() if job is not None else "updating"
        return {"changed": False, "iterations": 0, "units": [], "converged": False, "seconds": time.perf_counter() - t0}
    if not jobs.SYNCHRONOUS:
        return _step_threaded(context, session, t0)
    changed = False
    taken = _take_field(context, session)
    if taken is not None:
        field, painted, restart = taken
        _restart(session, restart)
        changed = session.set_ease(field, painted)
        if changed:
            _LIVE.update(final=None, landed=False)  # the pattern it would have stored is superseded
    warm = session.warming
    n_tri = len(session.triangles)
    show_s = (_estimate("show", n_tri) or 0.0) if warm else 0.0
    n = session.run(max(budget_s - show_s, 0.0))
    if warm and n and not session.converged:
        _timed("show", n_tri, lambda: _show(context, session))  # the warm state moved: show it
        # one warm slice is shown per stroke: the next ticks go to the cold solve (another warm
        # slice would cost another showing, and converging is what the designer waits for)
        session.end_warm()
    if session.converged and not _LIVE["landed"] and not _LIVE["final"]:
        # the converged pattern is not stored yet (or no longer: an undo restored another one, or
        # dropped the final work under way): store it
        _LIVE["final"] = _final_units(context, session)
    final, units = _LIVE["final"], []
    while final:
        kind, size, work = final[0]
        est = _estimate(kind, size)
        if (n or units) and (est is None or time.perf_counter() - t0 + est > budget_s):
            break
        final.popleft()
        _timed(kind, size, work)
        units.append(kind)
    done = session.converged and not final and _LIVE["landed"]
    _say_status(scene, session, done)
    return {"changed": changed, "iterations": n, "units": units, "converged": done, "seconds": time.perf_counter() - t0}


def _say_status(scene, session, done: bool) -> None:
    if not done:
        status = "converging"
    elif scene.get(data.PATTERN_KEY) == _LIVE["stored"]:
        status = "converged"
    else:  # Optimize, Transfer or Adapt stored a pattern since: the pieces are not Live's
        status = "idle: the pieces show another pattern than Live's; paint to update them"
    scene.ease.live_status = (
        status if status.startswith("idle") else f"{status} ({session.iterations_since_change} iterations)"
    )


WRITE_S = 0.01  # seconds of a tick spent making the meshes of a new cut's pieces (at least one)


def _write_new_cut(context, session, t0: float) -> str:
    """One tick's share of writing the converged pattern of a new cut (:data:`_LIVE` ``writing``,
    left by the solve's result): the pieces' new meshes made, one or more per tick within
    :data:`WRITE_S` (datablocks no object holds yet), then, in a tick of its own, the pieces put
    in place with the stored pattern, its figures and the fit overlay (one undo step, pushed by
    :func:`step`). The tick's status line."""
    w = _LIVE["writing"]
    if w["session"] is not session:  # a new session replaced it meanwhile: its solve writes anew
        _discard_writing()
        return "updating"
    _, _, pattern, ratio, text, plan = w["out"]
    lo, hi = w["range"]
    n = len(plan.pieces)
    if w["todo"]:
        first = True
        while w["todo"] and (first or time.perf_counter() - t0 < WRITE_S):
            pp, first = w["todo"].pop(0), False
            w["made"][pp.name] = build.piece_mesh(f"EASE piece {pp.name}", pp, lo, hi)
        return f"updating: Live: writing the pieces {len(w['made'])}/{n}"
    _LIVE["writing"] = None
    try:
        made = {k: me for k, me in w["made"].items() if me.users == 0}
    except ReferenceError:  # an undo freed them (the undo handler drops the writing too)
        return "updating"
    _store_final(context, pattern, text, False, plan, made, (lo, hi))
    _forget(w["made"].values())
    _write_fit(data.body_object(context), ratio)
    _LIVE.update(stored=context.scene.get(data.PATTERN_KEY), landed=True, pattern=pattern)
    _LIVE["shown"] += 1
    return "updating"  # (the next tick says "converged" once it has seen the scene as it is)


def _forget(meshes) -> None:
    """Remove the meshes of ``meshes`` no object took (an unfinished writing of a new cut)."""
    for me in meshes:
        try:
            if me.users == 0:
                bpy.data.meshes.remove(me)
        except ReferenceError:  # freed already (an undo)
            pass


def _discard_writing() -> None:
    """Drop an unfinished writing of a new cut's pieces (its meshes made so far removed)."""
    w, _LIVE["writing"] = _LIVE.get("writing"), None
    if w is not None:
        _forget(w["made"].values())


def _step_threaded(context, session, t0: float) -> dict:
    """A tick with the solve in a worker (Blender's window): a new field (a stroke) starts the
    solve's job (a running one is dropped: the newer paint wins); with none, a solve that is not
    done yet (a warm slice shown, the cold solve not complete, or its pattern not in the scene)
    goes on in a new job. The tick reads the layer and hands it over; it never iterates."""
    scene = context.scene
    if _LIVE["writing"] is not None:  # a new cut's pieces being written: nothing else this tick
        scene.ease.live_status = _write_new_cut(context, session, t0)
        return {"changed": False, "iterations": 0, "units": [], "converged": False, "seconds": time.perf_counter() - t0}
    taken = _take_field(context, session)
    if taken is not None:
        _LIVE["solve_failed"] = None
        _solve_in_worker(context, session, *taken)
    elif _LIVE["solve_failed"] is not None:
        raise _LIVE["solve_failed"]  # said by the tick, which stops (a new stroke tries again)
    elif jobs.running(SOLVE_JOB) is None and not (session.converged and _LIVE["landed"]):
        _solve_in_worker(context, session)
    done = jobs.running(SOLVE_JOB) is None and session.converged and _LIVE["landed"]
    _say_status(scene, session, done)
    n, _LIVE["iterations"] = _LIVE["iterations"], 0
    return {
        "changed": taken is not None,
        "iterations": n,
        "units": [],
        "converged": done,
        "seconds": time.perf_counter() - t0,
    }


def _solve_in_worker(context, session, field=None, painted=None, restart=None) -> None:
    """The solve as the job :data:`SOLVE_JOB`: in a worker, the new field ``field`` (F_body,)
    with ``painted`` (:func:`targets`; None: the one set) taken (from ``restart`` after an undo),
    then either one warm slice from the current pattern (after a change: its pattern and fit
    overlay, shown when it lands) or the cold solve to its end with the converged pattern's
    figures and stored text (stored with its figures when it lands). Everything that costs
    (iterations, building, measuring and encoding the pattern, the overlay's values, the pieces'
    arrays: :class:`.build.PatternPlan`) is the worker's; the main thread writes the result into
    the objects in one pass."""
    from ..core import workflows as wf
    from ..core.live import achieved_over_painted

    n_body = len(data.body_object(context).data.polygons)
    landed = _LIVE["landed"]
    # the ramp ranges the pieces will be coloured with (the pieces shown, or a new cut's)
    shown, ramp_range = sync.shown_range(context.scene), data.ramp_range(context.scene)
    new_range = []  # the worker's: a new cut's range (:func:`.sync.pattern_range`)

    def overlay(pattern):
        return achieved_over_painted(pattern, session.triangles, n_body, session.areas)

    def compute(progress):
        with _SOLVING:  # (a dropped job of this session stops at its next iteration)
            _restart(session, restart)
            changed = session.set_ease(field, painted) if field is not None else False
            if field is not None and not changed and session.converged and landed:
                return "same", 0, None, None, None, None  # (X-mirror toggled on a symmetric field, ...)
            if session.state is None:
                session.set_ease(None)
            n = 0
            if session.warming:
                n = session.run(0.0)  # one iteration: the stroke's first result, shown at once
                if not session.converged:
                    session.end_warm()  # one warm slice shown per stroke, then the cold solve
                    pattern = session.pattern(figures=False)
                    return "warm", n, pattern, overlay(pattern), None, build.PatternPlan(pattern).colored(shown)
            while not session.converged:
                progress(0.5, f"converging ({session.iterations_since_change} iterations)")
                n += session.run(SLICE_S)
            progress(0.9, "measuring the pattern")
            pattern = session.pattern(figures=False)
            wf.measure_pattern(pattern)
            new_range[:] = sync.pattern_range(ramp_range, pattern)
            plan = build.PatternPlan(pattern).colored(shown, new_range)
            return "final", n, pattern, overlay(pattern), session.text.text(pattern), plan

    def apply(out):
        kind, n, pattern, ratio, text, plan = out
        if _LIVE["session"] is not session:  # a new session replaced it meanwhile
            return
        _LIVE["iterations"] += n
        ctx = bpy.context
        scene, obj = ctx.scene, data.body_object(ctx, required=False)
        if kind != "same" and obj is not None:
            same = build.same_pieces(scene, pattern)
            if kind == "final" and not same:  # the pieces of a new cut: written over the next ticks
                lo_hi = tuple(new_range) if data.ramp_range(scene) == ramp_range else None
                lo_hi = lo_hi or sync.pattern_range(data.ramp_range(scene), pattern)
                todo = build.pieces_to_make(scene, plan)
                _LIVE["writing"] = {"session": session, "out": out, "range": lo_hi, "todo": todo, "made": {}}
                _LIVE.update(landed=False, pattern=None)
                wake()
                return
            with _UndoIfRebuilt():
                if same:
                    sync.show_pieces(ctx, pattern, plan)
                if kind == "final":
                    _store_final(ctx, pattern, text, same, plan)
                    _LIVE["stored"] = scene.get(data.PATTERN_KEY)
                if same or kind == "final":
                    _write_fit(obj, ratio)
        if kind != "same":
            _LIVE["landed"] = kind == "final"
            _LIVE["pattern"] = pattern
        _LIVE["shown"] += 1
        wake()

    def fail(exc):
        _LIVE["solve_failed"] = exc
        wake()  # the next tick says it (and stops)

    jobs.start(SOLVE_JOB, "Live: solving", compute, apply, fail, sync=False, cancelled=lambda: _cancelled("solve"))


def _tick():
    context = bpy.context
    scene = getattr(context, "scene", None)
    if scene is None or not scene.ease.live:
        return None
    try:
        out = step(context)
    except state.USER_ERRORS as exc:  # the design does not cut on this body, ...: say it, and stop
        scene.ease.live_status = f"live: {exc}"
        return None
    except Exception as exc:  # a bug: a timer must never leave a traceback; the console keeps it
        traceback.print_exc()
        state.BUGS.append(("live", traceback.format_exc()))
        scene.ease.live_status = f"live: {type(exc).__name__}: {exc}"
        return None
    if out["converged"] and not out["changed"]:
        return None
    waiting = jobs.running(JOB) is not None or jobs.running(SOLVE_JOB) is not None
    return BUILD_TICK_S if waiting else IDLE_TICK_S


def touched(scene) -> None:
    """Something Live follows may have changed (an EASE operator ran, the body was updated): the
    status no longer says "converged" until a tick has seen the scene as it is now."""
    s = getattr(scene, "ease", None)
    if s is None or not s.live:
        return
    if not s.live_status.startswith("updating"):
        s.live_status = "updating"
    wake()


state.ON_CHANGE[:] = [touched]  # operators and sync tell Live through state.changed


def wake() -> None:
    """Make sure a tick runs soon (idempotent)."""
    if not bpy.app.timers.is_registered(_tick):
        bpy.app.timers.register(_tick, first_interval=0.0)


@bpy.app.handlers.persistent
def _on_depsgraph(scene, depsgraph) -> None:
    s = getattr(scene, "ease", None)
    if s is None or not s.live or s.body is None:
        return
    body = s.body
    for u in depsgraph.updates:
        if getattr(u.id, "original", u.id) in (body, body.data):
            touched(scene)
            return


@bpy.app.handlers.persistent
def _on_undo(scene, *_args) -> None:
    # the restored scene holds the pattern stored when its step was pushed: the loop stores the
    # converged pattern of the restored paint again before it says "converged" (a pending final
    # work dropped here, over a session already converged, left another cut's pattern "converged")
    _LIVE.update(colors=None, restart=True, final=None, landed=False)
    _discard_writing()
    jobs.drop(SOLVE_JOB)
    touched(scene)  # the restored status is the pushed one: not "converged" until a tick has seen it


def _handlers():
    h = bpy.app.handlers
    return ((h.depsgraph_update_post, _on_depsgraph), (h.undo_post, _on_undo), (h.redo_post, _on_undo))


def start(context) -> None:
    """Live on: handlers installed, the legend filled, a first tick queued."""
    for lst, fn in _handlers():
        if fn not in lst:
            lst.append(fn)
    fill_legend(context.scene)
    _LIVE.update(colors=None, final=None)
    wake()


def stop() -> None:
    """Live off (or the add-on unregistered): no handler, no timer, the session dropped."""
    for lst, fn in _handlers():
        while fn in lst:
            lst.remove(fn)
    if bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)
    jobs.drop(JOB)
    jobs.drop(SOLVE_JOB)
    _discard_writing()
    _LIVE.update(
        failed=None,
        key=None,
        session=None,
        colors=None,
        mirror=None,
        restart=False,
        inputs=None,
        faces=None,
        final=None,
        stored=None,
        landed=False,
        iterations=0,
        solve_failed=None,
        pattern=None,
    )


def resume(*_args) -> None:
    """Make the loop agree with the active scene's *Live* toggle: running when it is on, nothing of
    another file's loop left (the handlers, the timer, the session) when it is off. Returns None
    (also a one-shot timer)."""
    stop()
    context = bpy.context
    s = getattr(getattr(context, "scene", None), "ease", None)
    if s is not None and s.live:
        start(context)
    return None


@bpy.app.handlers.persistent
def on_load(*_args) -> None:
    """``load_post``: a file was opened (or the start-up file read); Live follows its toggle."""
    resume()


def toggled(scene, context) -> None:
    """Update of the *Live* toggle."""
    if scene.ease.live:
        start(context)
    else:
        stop()
        scene.ease.live_status = ""
