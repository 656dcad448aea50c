"""The seam plan is a value: gathered seams, demands, sewn masks; the seam layout pairs both sides."""

import numpy as np
from synthetic_pattern import two_panels

from core.pattern.optimizer.seams import seam_is_gathered
from core.pattern.solve import PatternSolver, SolverConfig


def test_layout_pairs_both_sides():
    cut, body = two_panels()
    lay = PatternSolver(cut, body).seams
    assert len(lay.sides) == 2 * len(cut.seams)
    # sewn edges are each other's partners, about as long in the flattenings (LSCM distorts a little)
    assert np.array_equal(lay.edge_partner[lay.edge_partner], np.arange(len(lay.edge_partner)))
    assert np.allclose(lay.edge_rest, lay.edge_rest[lay.edge_partner], rtol=0.05)


def test_plan_gathers_by_demand_and_by_name():
    cut, body = two_panels(ease=(1.0, 1.0))
    solver = PatternSolver(cut, body)
    K, cw, cg = solver.targets_reference()
    flat = solver.plan_seams(K, cw, cg)
    assert flat.gathered == () and np.all(flat.sewn_edges == 1.0) and max(flat.demand.values()) < 0.01
    # the side seams run along the warp: one panel 50 % longer there, both seams' sides differ
    cg = np.concatenate([np.full(len(p.faces), e) for p, e in zip(cut.panels, (1.0, 1.5))])
    loose = solver.plan_seams(K, cw, cg)
    assert loose.gathered == tuple(sorted(s.name for s in cut.seams))
    assert np.all(loose.sewn_edges == 0.0) and all(r > 0.2 for r in loose.demand.values())
    off = solver.plan_seams(K, cw, cg, SolverConfig.improved(gather_above=None))
    assert off.gathered == ()
    named = solver.plan_seams(K, cw, cg, SolverConfig.improved(gather_above=None, gathered=(cut.seams[0].name,)))
    assert named.gathered == (cut.seams[0].name,)
    assert set(np.unique(named.sewn_edges)) == {0.0, 1.0}
    # a plan is a value: planning again gives the same, whatever was planned in between
    again = solver.plan_seams(*solver.targets_reference())
    assert again.gathered == flat.gathered and again.demand == flat.demand


def test_seam_names_for_gathering():
    assert seam_is_gathered("shirt.armhole_left#1", ("armhole_left",))
    assert not seam_is_gathered("shirt.armhole_left#1", ("armhole",))
