"""``seam_rhs`` on the seam vertices alone gives the bytes of the sum over every vertex.

The reference below is ``core.pattern.optimizer.seams.seam_rhs`` as it was before it was
rewritten for speed (bincounts per coordinate over all ``n`` vertices, the
rigid fit on (V, 2) arrays), frozen here; the helpers the rewrite left as they
were (the length and intake weights, the dart mouths' targets) are imported. Both run on real layouts (the
long-sleeve shirt, the blouse with set dart intakes, the synthetic two panels)
at several iterates, integral states, configurations and seam plans, and on
every call of a solve; the right-hand sides and the updated integrals must be
equal byte for byte (signed zeros included), so that patterns stay the same.
"""

import numpy as np
import pytest
from synthetic_pattern import two_panels

import core.pattern.optimizer.solver as solver_module

# unchanged by the rewrite, so shared with it: the weights and the dart mouths' targets
from core.pattern.optimizer.seams import _intake_weight, _length_weight, _mouth_targets, seam_rhs
from core.pattern.solve import PatternSolver, SolverConfig

# ----------------------------------------------------------------------------- the frozen reference


def _ref_fitted_partner(layout, U, d2):
    k = len(layout.sides)
    side = layout.vertex_side
    P = U[layout.vertex_ids]
    Q = P[layout.vertex_partner]
    cnt = layout.side_vertex_count
    Pm = np.stack([np.bincount(side, P[:, d], minlength=k) for d in range(2)], axis=1) / cnt[:, None]
    Qm = np.stack([np.bincount(side, Q[:, d], minlength=k) for d in range(2)], axis=1) / cnt[:, None]
    Pc, Qc = P - Pm[side], Q - Qm[side]
    h = {(i, j): np.bincount(side, Qc[:, i] * Pc[:, j], minlength=k) for i in range(2) for j in range(2)}
    th = np.arctan2(h[(0, 1)] - h[(1, 0)], h[(0, 0)] + h[(1, 1)])
    c_, s_ = np.cos(th)[layout.row_side], np.sin(th)[layout.row_side]
    do = d2[layout.row_partner]
    return np.stack([c_ * do[:, 0] - s_ * do[:, 1], s_ * do[:, 0] + c_ * do[:, 1]], axis=1)


def _ref_seam_rhs(layout, U, config, plan, integral):
    w, s = config.weights, config.seams
    n = len(U)
    rhs = np.zeros((n, 2))
    if not layout.sides:
        return rhs
    E0, E1, Eo = layout.edge_start, layout.edge_end, layout.edge_partner
    cur = U[E1] - U[E0]
    cur_len = np.sqrt(cur[:, 0] ** 2 + cur[:, 1] ** 2)
    if w.seam_length > 0:
        lbar = 0.5 * (cur_len + cur_len[Eo])
        if s.length_integral > 0:
            integral -= s.length_integral * 0.5 * (cur_len - cur_len[Eo])
            cap = s.length_integral_cap * lbar
            np.clip(integral, -cap, cap, out=integral)
            lbar = lbar + integral
        scale = np.maximum(cur_len, 1e-300)
        cl = _length_weight(layout, config, plan) * lbar
        for d in range(2):
            tgt = cl * (cur[:, d] / scale)
            rhs[:, d] += np.bincount(E1, tgt, minlength=n) - np.bincount(E0, tgt, minlength=n)
    if len(layout.mouth_a) and w.seam_length > 0:
        tgt = _intake_weight(layout, config) * _mouth_targets(layout, U)
        np.add.at(rhs, layout.mouth_a, tgt)
        np.add.at(rhs, layout.mouth_b, -tgt)
    if layout.second_diff is None:
        return rhs
    d2 = layout.second_diff @ U
    acc = np.zeros_like(d2)
    if w.seam_straight > 0 and s.straight_target == "smooth":
        sm = d2.copy()
        i = np.flatnonzero(layout.row_smooth)
        sm[i] = 0.5 * (d2[i - 1] + d2[i + 1])
        ws = w.seam_straight * layout.row_band * layout.row_straight
        acc[:, 0] += ws * sm[:, 0]
        acc[:, 1] += ws * sm[:, 1]
    if w.seam_curve > 0:
        wc = w.seam_curve * layout.row_band * plan.sewn_rows
        mean = 0.5 * (d2 + _ref_fitted_partner(layout, U, d2))
        acc[:, 0] += wc * mean[:, 0]
        acc[:, 1] += wc * mean[:, 1]
    rhs += layout.second_diff_T @ acc
    return rhs


# ----------------------------------------------------------------------------- comparisons


def _same(layout, U, config, plan, integral):
    """Both implementations from copies of ``integral``: equal bytes of the right-hand side and of the
    updated integral (returned, for the next iterate)."""
    mine, ref = integral.copy(), integral.copy()
    got, want = seam_rhs(layout, U, config, plan, mine), _ref_seam_rhs(layout, U, config, plan, ref)
    assert got.shape == want.shape and got.dtype == want.dtype
    assert got.tobytes() == want.tobytes(), np.max(np.abs(got - want))
    assert mine.tobytes() == ref.tobytes()
    return mine


CONFIGS = {
    "improved": SolverConfig.improved(),
    "paper": SolverConfig.paper(),
    "lengths": SolverConfig.lengths(),
    "no_curve": SolverConfig.improved(weights={"seam_curve": 0.0}),
    "no_straight": SolverConfig.improved(weights={"seam_straight": 0.0}),
    "no_length": SolverConfig.improved(weights={"seam_length": 0.0}),
    "shape_off": SolverConfig.improved(weights={"seam_curve": 0.0, "seam_straight": 0.0}),
    "all_gathered": SolverConfig.improved(gathered=("*",)),
    "tight_cap": SolverConfig.improved(seams={"length_integral_cap": 1e-4}),
}


def _check_layout(solver, seed):
    """Every configuration at the start, perturbed starts and a degenerate seam edge, the integral carried
    from call to call; the configurations alternate on one layout, so its kept weights must follow."""
    rng = np.random.default_rng(seed)
    layout = solver.seams
    U0 = solver.uv0
    iterates = [U0] + [U0 + rng.normal(scale=s * solver.mean_edge, size=U0.shape) for s in (0.01, 0.3, 1.0)]
    collapsed = U0.copy()
    collapsed[layout.edge_end[3]] = collapsed[layout.edge_start[3]]  # a zero-length seam edge
    iterates.append(collapsed)
    integrals = {name: np.zeros(len(layout.edge_start)) for name in CONFIGS}
    plans = {name: solver.design_plan(cfg) for name, cfg in CONFIGS.items()}
    for U in iterates:
        for name, cfg in CONFIGS.items():
            integrals[name] = _same(layout, U, cfg, plans[name], integrals[name])
            # a fresh plan object of the same configuration, and a non-contiguous iterate
            again = solver.plan_seams(solver.ref_offsets[0], solver.design_ease, np.ones_like(solver.design_ease), cfg)
            _same(layout, np.asfortranarray(U), cfg, again, integrals[name])
    # a random integral state, within and beyond the caps
    for name, cfg in CONFIGS.items():
        _same(layout, iterates[2], cfg, plans[name], rng.normal(scale=0.05, size=len(layout.edge_start)))


def _check_solve(solver, monkeypatch, **solve):
    """Every call of a solve's iterations, on the solve's own iterates and integral."""
    calls = []

    def spy(layout, U, config, plan, integral):
        before = integral.copy()
        got = seam_rhs(layout, U, config, plan, integral)
        calls.append(1)
        want = _ref_seam_rhs(layout, U, config, plan, before)
        assert got.tobytes() == want.tobytes() and integral.tobytes() == before.tobytes()
        return got

    monkeypatch.setattr(solver_module, "seam_rhs", spy)
    solver.solve(*solver.targets_reference(), **solve)
    assert len(calls) >= 10


def test_two_panels(monkeypatch):
    cut, body = two_panels(ease=(1.0, 1.4))  # one side seam demand over the gathering threshold
    solver = PatternSolver(cut, body)
    _check_layout(solver, 0)
    _check_solve(solver, monkeypatch)


def _real_solver(name, body):
    from core.cut import cut_design
    from core.design import load_design
    from core.design.resolve import instance_vertices
    from core.design.templates import template_path

    design = load_design(template_path(name))
    design.refine_edge_length = 0.02  # coarser than the default 1 cm: keeps the test short
    return PatternSolver(cut_design(design, body=body), instance_vertices(design, body))


@pytest.mark.parametrize("name", ["shirt_long_sleeve", "blouse_fitted"])
def test_templates(name, anny, monkeypatch):
    solver = _real_solver(name, anny)
    if name == "blouse_fitted":
        assert len(solver.seams.mouth_a)  # the set dart intakes' mouth term is exercised
    _check_layout(solver, 1)
    _check_solve(solver, monkeypatch)
