"""Values a solve keeps instead of recomputing are the values it would recompute: the rest targets' warp
products, the local step's warp-row weights, the design's seam plan (the region report's rows:
tests/test_metrics_regions.py)."""

import numpy as np
import pytest
from synthetic_pattern import two_panels

from core.pattern.config import RestShape, SolverConfig
from core.pattern.optimizer.steps import local_step
from core.pattern.optimizer.targets import rest_targets
from core.pattern.solve import PatternSolver


def _same(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert np.array_equal(np.asarray(x), np.asarray(y))


def _components(rng, f):
    return [rng.uniform(0.5, 1.5, f), rng.uniform(-0.3, 0.3, f), rng.uniform(-0.3, 0.3, f), rng.uniform(0.5, 1.5, f)]


@pytest.mark.parametrize("model", ["prestretch", "isometric"])
def test_rest_targets_take_over_the_warp_products(model):
    rng = np.random.default_rng(3)
    f = 500
    k = _components(rng, f)
    cg = rng.uniform(0.9, 1.1, f)
    first = rest_targets(k, rng.uniform(1.0, 1.3, f), cg, model)
    cw = rng.uniform(1.0, 1.3, f)
    kept = rest_targets(k, cw, None, model, warp_from=first)
    fresh = rest_targets(k, cw, cg.copy(), model)
    _same(kept["T"], fresh["T"])
    _same(kept["reg"][:2], fresh["reg"][:2])
    assert kept["reg"][2] is k


def test_local_step_with_its_kept_warp_row_is_a_fresh_one(numpy_steps):
    rng = np.random.default_rng(4)
    f = 800
    cfg = SolverConfig.improved()
    k = _components(rng, f)
    cg = rng.uniform(0.95, 1.05, f)
    W2 = np.array([1.0, 1.0])
    state = {}
    tg = rest_targets(k, rng.uniform(1.0, 1.3, f), cg, "prestretch")
    local_step(cfg, _components(rng, f), tg, W2, state)
    assert "_tden" in state
    # the next iteration: weft targets moved, the warp's taken over (the solver's path), a new iterate
    tg = rest_targets(k, rng.uniform(1.0, 1.3, f), None, "prestretch", warp_from=tg)
    M = _components(rng, f)
    fresh = {"sw": state["sw"].copy(), "_kprod": state["_kprod"]}
    RT, T = local_step(cfg, M, tg, W2, state)
    RT0, T0 = local_step(cfg, M, tg, W2, fresh)
    _same(RT, RT0)
    _same(T, T0)
    # other column weights or another warp row: recomputed, not read from the kept one
    W2b = np.array([1.0, 0.8])
    _, Tb = local_step(SolverConfig.improved(rest_shape=RestShape(warp_slack=0.12)), M, tg, W2b, state)
    _, Tb0 = local_step(cfg, M, tg, W2b, {"sw": state["sw"].copy()})
    _same(Tb, Tb0)


def test_the_design_plan_is_planned_once_per_configuration_and_read_only():
    cut, body = two_panels(ease=(1.1, 1.4), bulge=0.2)
    solver = PatternSolver(cut, body)
    plan = solver.design_plan()
    assert solver.design_plan(SolverConfig.improved()) is plan
    K = solver.ref_offsets[0]
    again = solver.plan_seams(K, solver.design_ease, np.ones_like(solver.design_ease))
    assert again.gathered == plan.gathered and again.demand == plan.demand
    _same((again.sewn_edges, again.sewn_rows), (plan.sewn_edges, plan.sewn_rows))
    with pytest.raises(ValueError):
        plan.sewn_edges[0] = 0.0
    other = SolverConfig.stretch()
    assert solver.design_plan(other) is not plan and solver.design_plan(other) is solver.design_plan(other)
