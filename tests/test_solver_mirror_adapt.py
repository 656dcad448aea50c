"""Mirrored seams gather together; pose adaptation keeps every triangle open (issue 14)."""

import numpy as np
import pytest
from test_solver_collapse import _collapsed

from core.design.naming import swap_side
from core.pattern.solve import PatternSolver, SolverConfig


@pytest.fixture(scope="module")
def shirt(anny):
    from core import workflows as wf
    from core.design import load_design
    from core.design.templates import TEMPLATE_DIR

    design = load_design(TEMPLATE_DIR / "shirt_long_sleeve.json")
    design.refine_edge_length = 0.02
    return wf.prepare(design, body=anny)


def test_mirrored_lines_gather_together(shirt):
    solver = PatternSolver(shirt.cut, shirt.reference)
    K = solver.ref_offsets[0]
    ones = np.ones(len(solver.gfaces))
    demand = solver.plan_seams(K, 3.5 * ones, ones).demand
    left, right = demand["shirt.side_left"], demand["shirt.side_right"]
    # a threshold between the two sides' demands (they differ by the flattening's asymmetry)
    above = 0.5 * (left + right) if left != right else 0.5 * left
    plan = solver.plan_seams(K, 3.5 * ones, ones, SolverConfig.improved(gather_above=above))
    sides = {n for n in plan.gathered if n.startswith("shirt.side")}
    assert sides == {"shirt.side_left", "shirt.side_right"}
    for name in plan.gathered:
        base, _, part = name.partition("#")
        assert swap_side(base) + (f"#{part}" if part else "") in plan.gathered, name


def test_adaptation_keeps_triangles_open_and_stretch_low(shirt):
    from core import workflows as wf

    run = wf.adapt(shirt, ["P1"], eps_weft=1.1, eps_warp=1.1)
    pat = run.pattern
    assert _collapsed(pat) == 0
    after = pat.report["residual_stretch"]["P1"]["shirt"]["after"]
    assert after <= 1.0, after
