"""core.live: the live re-solve of painted ease (no Blender), and the solver's resumable iterations."""

from __future__ import annotations

import numpy as np
import pytest

import core.live as live_mod
from core import workflows as wf
from core.design.templates import template_dir
from core.errors import PatternError
from core.live import LiveSession, PatternText, achieved_over_painted, body_triangles, topology_key
from core.pattern.build import build_pattern
from core.pattern.optimizer.solver import PatternSolver

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module")
def prep(anny):
    return wf.prepare(str(template_dir() / DESIGN), body=anny)


@pytest.fixture(scope="module")
def session(prep):
    return LiveSession(prep)


def _stroke(prep, session, field, ease, seed):
    """``field`` with a brush-sized patch (6 cm around a garment triangle) painted ``ease``."""
    faces = np.asarray(prep.body.faces)
    cent = prep.reference[faces].mean(axis=1)
    rng = np.random.default_rng(seed)
    c = cent[rng.choice(np.unique(session.triangles))]
    out = np.array(field, dtype=float)
    patch = np.linalg.norm(cent - c, axis=1) < 0.06
    out[patch] = ease
    return out, patch


def _converge(session, budget=0.05, limit=1000):
    calls = 0
    while not session.converged:
        session.run(budget)
        calls += 1
        assert calls < limit
    return calls


def _uv(pattern):
    return np.concatenate([p.uv for p in pattern.panels])


def test_resumed_iterations_equal_one_solve(prep):
    """begin + iterate(k) + iterate(n - k) is the one-shot solve, bit for bit: the state is the value passed."""
    solver = wf.make_solver(prep)
    K, cw, cg = solver.targets_reference()
    one = solver.solve(K, cw, cg)
    st = solver.begin(K, cw, cg)
    solver.iterate(st, 7)
    solver.iterate(st, st.planned - 7)
    two = solver.result(st)
    for name in one.uv:
        assert np.array_equal(one.uv[name], two.uv[name])
    assert two.iterations == one.iterations and two.energy == one.energy


def test_body_triangles_lie_under_the_cut(prep, session):
    tri = body_triangles(prep)
    assert tri.shape == (sum(len(p.faces) for p in prep.cut.panels),)
    assert tri.min() >= 0 and tri.max() < len(prep.body.faces)
    # the design's own ease, and a field painted nowhere: the cut's ease exactly
    assert np.array_equal(session.cut_ease(None), session.solver.design_ease)
    field = np.full(len(prep.body.faces), 1.05)
    none = np.zeros(len(prep.body.faces), dtype=bool)
    assert np.array_equal(session.cut_ease(field, none), session.solver.design_ease)
    # painted somewhere: the field there, the design's ease elsewhere
    some = none.copy()
    some[tri[: len(tri) // 2]] = True
    mixed = session.cut_ease(field, some)
    on = some[tri]
    assert np.all(mixed[on] == 1.05) and np.array_equal(mixed[~on], session.solver.design_ease[~on])


def test_unpainted_live_keeps_the_optimized_pattern(prep):
    """Switching Live on with no new paint: the converged pattern is Optimize Pattern's, bit for bit
    (it read the design's ease back through a vertex layer, whose triangles mix the garment's ease
    with the body's around the cut's edges: compliance 1.068 -> 1.112 %)."""
    ref = wf.reference(prep).pattern
    s = LiveSession(prep, pattern=ref)
    field = np.full(len(prep.body.faces), 1.0)
    field[s.triangles] = 1.2  # the layer as the design wrote it: mixed on the cut's edges
    field[np.unique(s.triangles)[::7]] = 1.1
    assert s.set_ease(field, np.zeros(len(field), dtype=bool))
    _converge(s)
    assert np.array_equal(_uv(s.pattern()), _uv(ref))


def test_live_converges_to_the_cold_solve_whatever_the_painting_order(prep, session):
    """After any sequence of strokes, the converged live pattern is a cold solve of the last field
    on a fresh solver, bit for bit (the warm slices shape only what is shown meanwhile)."""
    field = np.full(len(prep.body.faces), 1.2)
    assert session.set_ease(field)
    _converge(session)
    before = session.pattern()
    field2, patch = _stroke(prep, session, field, 1.7, seed=1)
    assert session.set_ease(field2)
    assert not session.set_ease(field2)  # the same paint again: nothing to do
    assert session.run(0.0) == 1  # one warm iteration fits a zero slice
    warm = session.pattern(figures=False)
    assert not session.converged
    # the warm slice already moves the painted patch towards its new ease
    on = np.isin(session.triangles, np.flatnonzero(patch))
    rw = lambda p: np.concatenate([q.achieved_weft for q in p.panels])  # noqa: E731
    assert on.any() and np.mean(rw(warm)[on]) > np.mean(rw(before)[on])
    field3, _ = _stroke(prep, session, field2, 1.05, seed=2)
    session.set_ease(field3)
    _converge(session)
    live = session.pattern()
    fresh = PatternSolver(prep.cut, prep.reference, wf.solver_config())
    K, cw, cg = fresh.targets_reference(ease=field3[body_triangles(prep)])
    cold = build_pattern(prep.cut, fresh.solve(K, cw, cg), style=prep.design.name)
    assert np.array_equal(_uv(live), _uv(cold))
    assert live.report["metrics"]["flipped_triangles"] == 0
    assert live.report["live"]["converged"]
    figs = session.figures(live)
    assert figs["compliance mean %"] == round(live.report["metrics"]["compliance"]["mean"], 2)


def test_no_work_once_converged(session):
    _converge(session)
    assert session.run(1.0) == 0


def test_achieved_over_painted(prep, session):
    _converge(session)
    pat = session.pattern(figures=False)
    ratio = achieved_over_painted(pat, session.triangles, len(prep.body.faces))
    on = np.zeros(len(prep.body.faces), bool)
    on[session.triangles] = True
    assert np.isnan(ratio[~on]).all() and np.isfinite(ratio[on]).all()
    # the pattern realises its painted ease to about its compliance (percent): the mean ratio is near 0
    comp = (
        pat.report.get("metrics", {}).get("compliance", {}).get("mean") or wf.measure_pattern(pat)["compliance"]["mean"]
    )
    assert abs(np.nanmean(ratio)) < 3 * comp / 100


def test_pattern_text_is_the_stored_text_a_piece_at_a_time(prep, session):
    """The units' text is what a one-shot ``dumps_json(pattern_to_json(...))`` writes, byte for byte,
    after a change too (the kept text of unchanged fields reused, the changed ones re-encoded);
    one unit per piece and one join."""
    from core.fileio import dumps_json
    from core.pattern.io import pattern_to_json

    text = PatternText()
    field = np.full(len(prep.body.faces), 1.2)
    session.set_ease(field)
    _converge(session)
    first = session.pattern()
    assert text.text(first) == dumps_json(pattern_to_json(first), indent=None)
    name = first.panels[0].name
    faces_text, uv_text = text._fields[(name, "faces")][1], text._fields[(name, "uv")][1]
    session.set_ease(_stroke(prep, session, field, 1.6, seed=4)[0])
    _converge(session)
    second = session.pattern()
    units = text.units(second)
    assert [size for size, _ in units] == [len(p.faces) for p in second.panels] + [len(session.triangles)]
    out = [work() for _, work in units][-1]
    assert out == dumps_json(pattern_to_json(second), indent=None)
    assert text._fields[(name, "faces")][1] is faces_text  # the cut's text kept
    assert text._fields[(name, "uv")][1] != uv_text  # the moved positions re-encoded
    assert max(len(p.faces) for p in second.panels) > live_mod.ENCODE_ROWS  # (the rows' path taken)


def test_pattern_text_encodes_a_few_rows_per_call(monkeypatch):
    """Issue 32: json's C encoder holds the GIL for a whole call, so a worker encoding a large
    field in one call stalls the viewport: a list is encoded ENCODE_ROWS rows per call, and the
    text is the one-shot text, byte for byte."""
    import core.fileio

    real, rows = core.fileio.dumps_json, []

    def counting(obj, indent=1):
        rows.append(len(obj) if isinstance(obj, list) else 0)
        return real(obj, indent=indent)

    monkeypatch.setattr(core.fileio, "dumps_json", counting)
    monkeypatch.setattr(live_mod, "ENCODE_ROWS", 3)
    rng = np.random.default_rng(5)
    for value in ([], [1.5], [[1, 2, 3]] * 3, rng.normal(size=(10, 3)).tolist(), [{"a": [0.1, 2]}] * 7, "text", 4):
        rows.clear()
        assert live_mod._dumps_rows(value) == real(value, indent=None)
        assert max(rows) <= 3 and len(rows) == max(1, -(-len(value) // 3) if isinstance(value, list) else 1)


def test_topology_key(prep):
    d = prep.design.to_json()
    painted = prep.design.copy()
    painted.set_ease(prep.cut.panels[0].name, {"value": 1.5})
    assert topology_key(painted, {"model": "anny"}) == topology_key(d, {"model": "anny"})
    assert topology_key(d, {"model": "anny", "shape": {"height": 1}}) != topology_key(d, {"model": "anny"})
    moved = prep.design.copy()
    name = next(iter(moved.parameters))
    p = moved.parameters[name]
    moved.set_parameter(name, p.value * 0.9 if p.value else 0.1)
    assert topology_key(moved) != topology_key(d)


@pytest.mark.parametrize("bad, expect", [(np.ones(5), "expected"), ("nan", "triangle 0"), (9.0, "triangle 0")])
def test_bad_fields_are_refused(prep, session, bad, expect):
    if isinstance(bad, str) or np.ndim(bad) == 0:
        bad = np.full(len(prep.body.faces), np.nan if bad == "nan" else bad)
    with pytest.raises(PatternError, match=expect):
        session.set_ease(bad)


def test_the_cold_solve_ends_by_the_solvers_rule(prep, monkeypatch):
    """The live cold solve ends where PatternSolver.solve ends (collapse rounds after the planned
    iterations included), so the converged pattern is Optimize Pattern's: here the solver is told a
    triangle is still collapsing after the planned iterations, once; both then run one more round."""
    from core.pattern.optimizer import solver as S

    calls = {"solve": 0, "live": 0}

    def once(key):
        def collapsing(self, state):
            calls[key] += 1
            return calls[key] == 1

        return collapsing

    solver = wf.make_solver(prep)
    K, cw, cg = solver.targets_reference()
    monkeypatch.setattr(S.PatternSolver, "collapsing", once("solve"))
    one = solver.solve(K, cw, cg)
    assert one.iterations == solver.config.iterations + S.COLLAPSE_ROUNDS
    session = LiveSession(prep)
    monkeypatch.setattr(S.PatternSolver, "collapsing", once("live"))
    session.set_ease(np.full(session.n_body_triangles, 1.1))
    session.end_warm()
    _converge(session)
    assert session.state.iteration == one.iterations and calls["live"] == 2
