"""The solver keeps no state that changes a later call: the same call gives the same pattern bitwise."""

import numpy as np
from synthetic_pattern import two_panels

from core.pattern.solve import PatternSolver, SolverConfig, adapt_pattern, solve_pattern, transfer_pattern


def _same(a, b):
    assert [p.name for p in a.panels] == [p.name for p in b.panels]
    for pa, pb in zip(a.panels, b.panels):
        assert np.array_equal(pa.uv, pb.uv)
        assert np.array_equal(pa.target_weft, pb.target_weft) and np.array_equal(pa.target_warp, pb.target_warp)
    assert [s.gathered for s in a.seams] == [s.gathered for s in b.seams]


def _case():
    cut, body = two_panels(ease=(1.2, 1.6), bulge=0.2)
    return cut, body, body * np.array([1.1, 1.1, 1.0])


def test_transfer_does_not_depend_on_a_prior_reference_solve():
    cut, body, big = _case()
    fresh = transfer_pattern(cut, body, big, solver=PatternSolver(cut, body))
    solver = PatternSolver(cut, body)
    solve_pattern(cut, body, solver=solver)
    # an ease sweep on the same solver plans other seams and factorises another matrix
    K, cw, cg = solver.targets_reference(ease=2.5)
    solver.solve(K, cw, cg, config=SolverConfig.stretch())
    _same(fresh, transfer_pattern(cut, body, big, solver=solver))


def test_adaptation_does_not_depend_on_a_prior_solve_and_leaves_the_config():
    cut, body, big = _case()
    fresh = adapt_pattern(cut, body, [big], eps_weft=1.05, solver=PatternSolver(cut, body))
    solver = PatternSolver(cut, body)
    config = solver.config
    ref = solve_pattern(cut, body, solver=solver)
    transfer_pattern(cut, body, big, solver=solver, start=ref)
    _same(fresh, adapt_pattern(cut, body, [big], eps_weft=1.05, solver=solver))
    assert solver.config is config
    # and the reference solve after all that is the first one again
    _same(ref, solve_pattern(cut, body, solver=solver))


def test_a_call_config_equals_a_solver_built_with_it():
    cut, body, big = _case()
    shared = PatternSolver(cut, body)
    for name in ("paper", "stretch"):
        cfg = SolverConfig.named(name, iterations=8)
        own = PatternSolver(cut, body, cfg)
        _same(solve_pattern(cut, body, solver=own), solve_pattern(cut, body, cfg, solver=shared))
        _same(transfer_pattern(cut, body, big, solver=own), transfer_pattern(cut, body, big, cfg, solver=shared))
