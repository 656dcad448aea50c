"""Pose adaptation without the bias cost (issue 14): the settling phase, the raising-only feedback, the
warp cap, and the adapted shirt's shear and seams, on a coarse shirt."""

import numpy as np
import pytest

from core.errors import PatternError
from core.pattern.solve import PatternSolver, SolverConfig, adapt_pattern, solve_pattern


@pytest.fixture(scope="module")
def shirt(anny):
    from core import workflows as wf
    from core.design import load_design
    from core.design.templates import TEMPLATE_DIR

    design = load_design(TEMPLATE_DIR / "shirt_long_sleeve.json")
    design.refine_edge_length = 0.02
    prep = wf.prepare(design, body=anny)
    solver = PatternSolver(prep.cut, prep.reference)
    ref = solve_pattern(prep.cut, prep.reference, solver=solver)
    return prep, solver, ref


def _pose(prep, anny, name="P1"):
    from core.body.instance import body_instance

    return body_instance(anny, prep.cut.body.get("shape"), name)


def _adapt_state(prep, solver, ref, pose, cfg):
    poses = [solver.positions(pose, "pose")]
    K, cw, cg = solver.targets_adapt(poses, 1.1, 1.1, cfg)
    demands = solver.pose_demands(poses, 1.1, 1.1, cfg)
    return (
        solver.begin(K, cw, cg, start=solver.start_from(ref), poses=demands, plan=solver.design_plan(cfg), config=cfg),
        cw,
        cg,
    )


def test_settling_iterations_freeze_the_feedback(shirt, anny):
    prep, solver, ref = shirt
    cfg = SolverConfig.improved()
    settle = cfg.adaptation.settle
    assert 0 < settle < cfg.adaptation.min_iterations
    state, _, _ = _adapt_state(prep, solver, ref, _pose(prep, anny), cfg)
    solver.iterate(state, state.planned - settle)
    cw, cg = state.corr_w.copy(), state.corr_g.copy()
    assert not np.allclose(cw, 1.0)  # the feedback did move the targets before
    solver.iterate(state, settle)
    assert np.array_equal(cw, state.corr_w) and np.array_equal(cg, state.corr_g)


def test_without_settling_the_feedback_runs_to_the_end(shirt, anny):
    prep, solver, ref = shirt
    state, _, _ = _adapt_state(prep, solver, ref, _pose(prep, anny), SolverConfig.improved(settle=0))
    solver.iterate(state, state.planned - 1)
    cw = state.corr_w.copy()
    solver.iterate(state, 1)
    assert not np.array_equal(cw, state.corr_w)


def test_settling_and_warp_cap_leave_reference_solves_alone(shirt):
    prep, solver, _ = shirt
    a = solve_pattern(prep.cut, prep.reference, SolverConfig.improved(settle=0, cap_warp=None), solver=solver)
    b = solve_pattern(prep.cut, prep.reference, SolverConfig.improved(settle=15, cap_warp=1.2), solver=solver)
    for p, q in zip(a.panels, b.panels):
        assert np.array_equal(p.uv, q.uv)


def test_warp_targets_are_capped(shirt, anny):
    prep, solver, ref = shirt
    cfg = SolverConfig.improved()
    _, cw, cg = _adapt_state(prep, solver, ref, _pose(prep, anny), cfg)
    assert cfg.adaptation.cap_warp == 2.0 and cg.max() <= 2.0 + 1e-12
    _, _, free = _adapt_state(prep, solver, ref, _pose(prep, anny), SolverConfig.improved(cap_warp=None))
    assert free.max() > 2.0  # the armpit asks for more than a flat cloth gives


def test_adapted_shirt_keeps_stretch_low_with_less_shear_and_closed_seams(shirt, anny):
    from core.metrics.pattern import ease_compliance, residual_stretch, seam_mismatch

    prep, solver, ref = shirt
    pose = _pose(prep, anny)
    X = prep.cut.positions(pose)
    xyz = {p.name: X[p.vertex_ids] for p in prep.cut.panels}
    old = SolverConfig.improved(
        adaptation=dict(margin=0.06, gain=0.2, warp_gain=0.08, cap_warp=None, settle=0, lower=1.0)
    )
    before = adapt_pattern(prep.cut, prep.reference, [pose], eps_weft=1.1, solver=solver, start=ref, config=old)
    after = adapt_pattern(prep.cut, prep.reference, [pose], eps_weft=1.1, solver=solver, start=ref)
    assert residual_stretch(after, xyz, 1.1) <= 1.0
    assert ease_compliance(after)["shear_p95"] < ease_compliance(before)["shear_p95"]
    assert seam_mismatch(after)["max_mm"] < seam_mismatch(before)["max_mm"]


def test_the_feedback_only_raises_unless_told_to_lower(shirt, anny):
    prep, solver, ref = shirt
    pose = _pose(prep, anny)
    state, _, _ = _adapt_state(prep, solver, ref, pose, SolverConfig.improved())
    solver.iterate(state, state.planned)
    assert state.corr_w.min() >= 1.0 and state.corr_g.min() >= 1.0
    both, _, _ = _adapt_state(prep, solver, ref, pose, SolverConfig.improved(lower=1.0))
    solver.iterate(both, both.planned)
    assert min(both.corr_w.min(), both.corr_g.min()) < 1.0  # somewhere a triangle is past its goal


def test_reference_feedback_still_lowers(shirt):
    # the raising-only rule is the adaptation's: a reference solve's feedback corrects both ways
    prep, solver, _ = shirt
    K, cw, cg = solver.targets_reference()
    state = solver.begin(K, cw, cg, config=SolverConfig.improved())
    solver.iterate(state, state.planned)
    assert state.corr_w.min() < 1.0 < state.corr_w.max()


@pytest.mark.parametrize(
    "override, where",
    [
        ({"settle": -1}, "adaptation.settle"),
        ({"lower": -0.5}, "adaptation.lower"),
        ({"settle": 60}, "adaptation.settle"),
        ({"settle": 1.5}, "adaptation.settle"),
        ({"feedback_until": -1}, "adaptation.feedback_until"),
        ({"feedback_until": 2.5}, "adaptation.feedback_until"),
        ({"feedback_until": True}, "adaptation.feedback_until"),
    ],
)
def test_bad_settle_is_refused(override, where):
    with pytest.raises(PatternError, match=where):
        SolverConfig.improved(**override).check()


def test_the_feedback_holds_from_feedback_until_however_long_the_solve(shirt, anny):
    prep, solver, ref = shirt
    ad = SolverConfig.improved().adaptation
    assert ad.feedback_until is None  # by default only the last ``settle`` hold the feedback
    assert [ad.holds(it, 60) for it in (0, 29, 30, 59)] == [False, False, True, True]
    cfg = SolverConfig.improved(iterations=100, feedback_until=12)
    assert [cfg.adaptation.holds(it, 100) for it in (11, 12, 69, 70)] == [False, True, True, True]
    state, _, _ = _adapt_state(prep, solver, ref, _pose(prep, anny), cfg)
    solver.iterate(state, 12)
    cw, cg = state.corr_w.copy(), state.corr_g.copy()
    assert not np.allclose(cw, 1.0)
    solver.iterate(state, 40)  # long before the last 30: held all the same
    assert np.array_equal(cw, state.corr_w) and np.array_equal(cg, state.corr_g)


def test_fitted_adapts_in_improved_window_and_takes_other_iteration_counts():
    fitted, improved = SolverConfig.fitted(), SolverConfig.improved()
    planned = max(fitted.iterations, fitted.adaptation.min_iterations)
    moving = [it for it in range(planned) if not fitted.adaptation.holds(it, planned)]
    assert moving == [it for it in range(60) if not improved.adaptation.holds(it, 60)] == list(range(30))
    for n in (1, 20, 100, 1000):  # --iterations overrides it: still a valid configuration
        SolverConfig.fitted(iterations=n).check()


def _template_adapted(anny, name, pose_name, solver=None, **kw):
    """(prep, solver, reference pattern, pose, adapted pattern) of template ``name`` adapted to ``pose_name``
    (``solver``: the design's configuration when None; ``kw`` for :func:`adapt_pattern`)."""
    from core import workflows as wf
    from core.design.templates import TEMPLATE_DIR

    prep = wf.prepare(TEMPLATE_DIR / f"{name}.json", body=anny)
    solver = solver(prep) if solver else wf.make_solver(prep)
    ref = solve_pattern(prep.cut, prep.reference, solver=solver)
    pose = _pose(prep, anny, pose_name)
    return prep, solver, ref, pose, adapt_pattern(prep.cut, prep.reference, [pose], solver=solver, start=ref, **kw)


def _assert_adaptation_targets(prep, ref, pose, ap, stretched):
    """Issue 14's adaptation targets: residual stretch <= 1 % weft and warp (the reference's weft residual
    over ``stretched``: the pose does stretch it), shear p95 <= 8 deg, every seam <= 2 mm, 0 flipped and
    0 collapsed."""
    from core.metrics.pattern import collapse, ease_compliance, flips, residual_stretch, seam_mismatch

    X = prep.cut.positions(pose)
    xyz = {p.name: X[p.vertex_ids] for p in prep.cut.panels}
    assert residual_stretch(ref, xyz, 1.1) > stretched
    assert residual_stretch(ap, xyz, 1.1) <= 1.0
    assert residual_stretch(ap, xyz, 1.1, direction="warp") <= 1.0
    assert ease_compliance(ap)["shear_p95"] <= 8.0
    assert seam_mismatch(ap)["max_mm"] <= 2.0
    assert sum(flips(ap).values()) == 0 and sum(v["count"] for v in collapse(ap).values()) == 0


def test_adapted_four_dart_blouse_meets_the_targets(anny):
    """Issue 14's adaptation targets on the four-dart blouse in P1 with the fitted configuration it names,
    a piece that can be cut (issue 30: no crossing, every dart's legs apart and sewn equal; on the tape-fitted women:M its
    bust darts stayed crossed by 7-14 mm while the gap step's cap was measured against the global step
    alone); with its feedback running through all 300 iterations (feedback_until None) the raising-only
    corrections ratchet up around the waist and the armpits and the shear p95 reads over 8 deg (that solve
    diverged before: 5206 flipped)."""
    from core.metrics.injectivity import crossings, dart_gaps
    from core.metrics.pattern import ease_compliance

    prep, solver, ref, pose, ap = _template_adapted(anny, "blouse_four_darts", "P1")
    assert solver.config == SolverConfig.fitted()
    _assert_adaptation_targets(prep, ref, pose, ap, stretched=10.0)
    assert sum(c["count"] for c in crossings(ap).values()) == 0
    assert all(g["crossings"] == 0 and g["min_gap_mm"] > 0 for g in dart_gaps(ap).values())
    # legs sewn equal (issue 30: 0.1 mm; the bust darts' were 0.43 mm apart before the solve ended with
    # core.pattern.optimizer.dart_gaps.equal_legs)
    assert all(r["leg_difference_mm"] <= 0.1 for r in ap.report["darts"].values())
    ratchet = adapt_pattern(
        prep.cut, prep.reference, [pose], solver=solver, start=ref, config=SolverConfig.fitted(feedback_until=None)
    )
    assert ease_compliance(ratchet)["shear_p95"] > 8.0


def test_adapted_pants_meet_the_targets_in_the_widest_pose(anny):
    # issue 14's targets in Table 4's hardest lower-body case (P3, eps 1.1): residual stretch <= 1 %,
    # shear p95 <= 8 deg, every seam <= 2 mm (2.20 mm with 10 settling iterations of 40), warp beside
    improved = lambda prep: PatternSolver(prep.cut, prep.reference)
    prep, _, ref, pose, ap = _template_adapted(anny, "pants", "P3", improved, eps_weft=1.1, eps_warp=1.1)
    _assert_adaptation_targets(prep, ref, pose, ap, stretched=2.0)
