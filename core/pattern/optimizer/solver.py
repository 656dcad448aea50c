"""The local-global ease optimizer over all panels of a cut, factorised once (:class:`PatternSolver`).

Unknowns: the 2D positions of every panel vertex (seam vertices duplicated,
one copy per panel, :mod:`.panels`), one sparse least-squares system for all.
Everything is expressed on the panel's initial flattening ``U0`` (LSCM,
area-matched, grain along +y) through per-triangle gradient operators ``G_t``:
the pattern's Jacobian w.r.t. ``U0`` is ``M_t = U_t^T G_t`` (its columns the
paper's ``sigma_2D``), the body's 3D offsets ``X_t^T G_t`` with intrinsic
2D coordinates ``K_t`` (:func:`core.geom.strain.intrinsic_offsets`).

Energy, every term a relative strain squared integrated over area and
divided by the garment's total area ``A`` (dimensionless, independent of the
mesh resolution and the garment's size)::

    E = lambda_ease sum_t a_t |(M_t - T_t) W|^2          (ease: towards the targets, .targets)
      + lambda_reg  sum_t a_t |(M_t - D_t R_t K'_t) W|^2 (ARAP, R_t from the local step, .steps)
      + seam terms (length, straightness, matched curvature; .seams)

with ``a_t = area_t / A`` (at least ``weights.sliver`` times the mean) and
``W = diag(1, weights.warp_column)``. The matrix never changes for a
configuration's weights and a seam plan: it is factorised once and reused by
the reference, transfer and adaptation solves; only the right-hand side
changes. One soft pin per panel fixes the translation gauge; rotation is
fixed by the ease term's axes and the grain re-alignment after every
iteration. No triangle ever flips (:func:`.steps.flip_guard`).

The solver keeps only what it precomputed from the cut and the reference
body, a cache of factorisations keyed by the weights and the seam plan, and
spare guarded factorisations (:class:`.guard.GuardedFactors`: symbolic
analysis reused only); every call takes its configuration (default: the
solver's) and seam plan, so no call changes a later one's result.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from typing import Dict, Optional, Sequence, Tuple

import numpy as np
import scipy.sparse as sp

from ...errors import PatternError
from ...geom.strain import components, intrinsic_offsets
from ...progress import Progress, report
from .. import accel
from ..accel import compiled
from ..accel.products import GradientProducts
from ..build import SolveResult, solve_result
from ..config import SolverConfig, check_tolerance
from ..validate import body_positions, validate_cut
from .dart_gaps import LEGS_REFUSED, GapCorrection, dart_legs, equal_legs, unequal_legs
from .factor import SymmetricFactor
from .feedback import feedback_gains, move_corrections
from .folds import RETRY_FLOORS, bridge_folds
from .guard import (
    COLLAPSE_ROUNDS,
    DIVERGED_SCALE,
    RESCUE_ITERATIONS,
    GuardedFactors,
    refused,
    renew_guard,
    rescuing,
    round_guard,
    runaway,
)
from .panels import flatten_panels
from .seams import SeamPlan, plan_seams, seam_layout, seam_matrix, seam_rhs
from .start import pattern_start
from .state import SolveState
from .steps import (
    any_collapsed,
    collapse_guard,
    face_neighbourhood,
    flip_guard,
    inverse_offsets,
    local_step,
    opened_jacobians,
    realign_grain,
    regulariser_energy,
    rhs_terms,
    rigid_align,
    scaled_start,
)
from .targets import adaptation_scales, reference_ease, rest_targets


def _with_solvers_choice(method):
    """``method`` runs its steps compiled or not as the solver chose when it was built (``self.kernels``)."""

    @functools.wraps(method)
    def run(self, *args, **kwargs):
        with compiled.chosen(self.kernels):
            return method(self, *args, **kwargs)

    return run


#: Weight of each panel's translation pin, relative to its mean diagonal entry.
PIN_WEIGHT = 1e-6


class PatternSolver:
    """Local-global ease optimizer over all panels of a cut, factorised once.

    Parameters
    ----------
    cut : GarmentCut
    body_vertices : (V, 3) the reference body instance the cut was made on, metres.
    config : SolverConfig, the default of every call (:meth:`SolverConfig.improved`).
    progress : optional progress callback of the flattening.
    flatten_on : (N, 3) the cut's positions on another body to flatten the pieces (and so factorise the
        system) on, or None for the reference body's: a transfer's solver made on its target body
        (:attr:`~core.pattern.config.Convergence.transfer_solver`). The reference body stays the one the
        cut's shape, the design's targets and the folds are measured from (``ref_positions``,
        ``ref_offsets``, here in the target's frames).
    """

    def __init__(
        self,
        cut,
        body_vertices: np.ndarray,
        config: Optional[SolverConfig] = None,
        progress: Optional[Progress] = None,
        flatten_on: Optional[np.ndarray] = None,
    ):
        validate_cut(cut)
        self.cut = cut
        self.config = config or SolverConfig.improved()
        self.config.check()
        t0 = time.perf_counter()
        self.ref_positions = self.positions(body_vertices, "reference body")
        if flatten_on is not None:
            flatten_on = np.asarray(flatten_on, float)
            if flatten_on.shape != self.ref_positions.shape or not np.all(np.isfinite(flatten_on)):
                raise PatternError(
                    f"flatten_on: expected finite positions {self.ref_positions.shape}, got shape {flatten_on.shape}"
                )
        self.blocks = flatten_panels(cut, self.ref_positions if flatten_on is None else flatten_on, progress)
        b = self.blocks
        self.panels = b.panels
        self.n = b.n
        self.gfaces = b.faces
        self.uv0 = b.uv0
        self.total_area = float(b.area0.sum())
        #: each triangle's share of the garment's area (before the sliver floor of :meth:`area_weights`)
        self.area_fraction = b.area0 / self.total_area
        el = np.linalg.norm(self.uv0[self.gfaces[:, [1, 2, 0]]] - self.uv0[self.gfaces], axis=2)
        self.mean_edge = float(np.mean(el))
        self.design_ease = np.concatenate([pd.ease for pd in self.panels])
        self.seams = seam_layout(cut, self.panels, self.uv0, self.n, self.mean_edge, self.total_area)
        self.gaps = GapCorrection(self.seams.legs or dart_legs([], [], []))
        # gradient operators as sparse (f, n) matrices: (Gx @ U)[t] = M_t[:, 0], (Gy @ U)[t] = M_t[:, 1]
        f, cols = len(self.gfaces), self.gfaces.ravel()
        rows = np.repeat(np.arange(f), 3)
        self._Gx = sp.csr_matrix((b.G[:, :, 0].ravel(), (rows, cols)), shape=(f, self.n))
        self._Gy = sp.csr_matrix((b.G[:, :, 1].ravel(), (rows, cols)), shape=(f, self.n))
        self._GxT, self._GyT = self._Gx.T.tocsr(), self._Gy.T.tocsr()
        self._products = GradientProducts(self._Gx, self._Gy, self._GxT, self._GyT)
        self._factors: Dict[tuple, Tuple[SymmetricFactor, np.ndarray]] = {}
        # the collapse guard's stiffened factorisations and the spare ones finished solves gave back
        self._guarded = GuardedFactors(self.gfaces, b.G)
        self._neighbourhood: Optional[sp.csr_matrix] = None
        self._design_plans: Dict[SolverConfig, SeamPlan] = {}
        self.n_factorisations = 0
        # the reference body's offsets serve every reference target, adaptation and seam plan:
        # computed once, read-only (a solve never changes them)
        self.ref_offsets = tuple(a.copy() for a in self.offsets(self.ref_positions))
        for a in self.ref_offsets:
            a.flags.writeable = False
        #: whether the steps run as Warp kernels (:mod:`.accel`; compiled on a machine's first run)
        self.kernels = accel.choose(progress)
        self.timings = {"init": time.perf_counter() - t0}
        report(progress, 1.0, "flattened")

    # ------------------------------------------------------------------ bodies and targets
    def positions(self, body_vertices, what: str) -> np.ndarray:
        """The cut's positions (N, 3) on a body instance (V, 3), checked (``what`` names it in errors)."""
        return body_positions(self.cut, body_vertices, what)

    def offsets(self, positions: np.ndarray):
        """Intrinsic offsets ``K`` (f, 2, 2) and the 3D weft/warp offset lengths (f,) on ``positions``."""
        return intrinsic_offsets(positions[self.blocks.corners], self.blocks.G)

    def targets_reference(self, positions: Optional[np.ndarray] = None, ease=None, offsets=None):
        """Targets of Eq. ref-scale (or transfer-scale on other ``positions``): (K, c_weft, c_warp).

        ``c = (rho_weft, 1)``; ``ease``: optional override of the cut's weft
        ease, a scalar or one value per triangle of all panels in order
        (benchmarks sweep it). ``offsets``: :meth:`offsets` of ``positions``
        when the caller has them. On another body a triangle's ``K`` is its
        reference-body shape stretched by at least :data:`.folds.FOLD_FLOOR`
        in every direction (:func:`.folds.bridge_folds`: the cloth bridges a
        fold of the skin).
        """
        if positions is None:
            offsets = self.ref_offsets
        elif offsets is None:
            offsets = self.offsets(positions)
        K = offsets[0] if positions is None else bridge_folds(offsets[0], self.ref_offsets[0])
        ease = reference_ease(self.design_ease, ease)
        return K, ease.copy(), np.ones_like(ease)

    def targets_adapt(
        self,
        pose_positions: Sequence[np.ndarray],
        eps_weft: float,
        eps_warp: float,
        config: Optional[SolverConfig] = None,
    ):
        """Targets of Eq. material-scale: per direction max(rho sigma_ref, max_i sigma_i / eps)."""
        cfg = config or self.config
        eps_weft = check_tolerance("eps_weft", eps_weft)
        eps_warp = check_tolerance("eps_warp", eps_warp)
        K, lw, lg = self.ref_offsets
        poses = [self.offsets(P)[1:] for P in pose_positions]
        ad = cfg.adaptation
        cap_w, cap_g = (np.inf if c is None else c for c in (ad.cap_weft, ad.cap_warp))
        cw, cg = adaptation_scales(self.design_ease, lw, lg, poses, eps_weft, eps_warp, ad.margin, cap_w, cap_g)
        if ad.spread:
            # a pose's demand is a sharp local peak (the armpit with the arm raised): raised cloth around it
            # (the running maximum of the neighbours' mean, across seams too) asks for a compatible flat shape
            S = self.neighbourhood()
            for _ in range(ad.spread):
                cw = np.maximum(cw, S @ cw)
                cg = np.maximum(cg, S @ cg)
        return K, cw, cg

    def pose_demands(
        self,
        pose_positions: Sequence[np.ndarray],
        eps_weft: float,
        eps_warp: float,
        config: Optional[SolverConfig] = None,
    ) -> dict:
        """What adaptation solves feed back on (see :meth:`solve`): the poses' intrinsic offsets and tolerances."""
        cfg = config or self.config
        return {
            "offsets": [components(self.offsets(P)[0]) for P in pose_positions],
            "ease_weft": self.design_ease.copy(),
            "ease_warp": np.ones(len(self.gfaces)),
            "eps_weft": check_tolerance("eps_weft", eps_weft),
            "eps_warp": check_tolerance("eps_warp", eps_warp),
            "margin": 1.0 + cfg.adaptation.margin,
        }

    # ------------------------------------------------------------------ seam plan
    def plan_seams(
        self, K: np.ndarray, c_weft: np.ndarray, c_warp: np.ndarray, config: Optional[SolverConfig] = None
    ) -> SeamPlan:
        """The seam plan of targets ``diag(c) K`` (:func:`core.pattern.optimizer.seams.plan_seams`)."""
        return plan_seams(self.cut, self.seams, self.uv0, K, c_weft, c_warp, config or self.config)

    def design_plan(self, config: Optional[SolverConfig] = None) -> SeamPlan:
        """The seam plan of the design's own ease on the reference body: what transfer and adaptation
        solves sew (the reference pattern's plan). Planned once per configuration (every item of a batch
        sews it), read-only."""
        cfg = config or self.config
        plan = self._design_plans.get(cfg)
        if plan is None:
            plan = self.plan_seams(self.ref_offsets[0], self.design_ease, np.ones_like(self.design_ease), cfg)
            for a in (plan.sewn_edges, plan.sewn_rows):
                a.flags.writeable = False
            self._design_plans[cfg] = plan
        return plan

    # ------------------------------------------------------------------ the system
    def area_weights(self, config: Optional[SolverConfig] = None) -> np.ndarray:
        """Per-triangle weights ``a_t`` (f,): area fractions, at least ``weights.sliver`` times the mean.

        Slivers (cut boundaries meet the body mesh at grazing angles) would
        weigh almost nothing and fold freely.
        """
        a = self.area_fraction
        return np.maximum(a, (config or self.config).weights.sliver * float(np.mean(a)))

    @_with_solvers_choice
    def factorisation(self, config: Optional[SolverConfig], plan: SeamPlan) -> Tuple[SymmetricFactor, np.ndarray]:
        """(factorisation of the fixed system matrix (:class:`.factor.SymmetricFactor`; called on a
        right-hand side ``(n, 2)`` it back-substitutes), gauge pins (n, 2)) of ``config``'s weights and
        ``plan``; factorised on first use and kept."""
        cfg = config or self.config
        key = self._factor_key(cfg, plan)
        if key not in self._factors:
            t0 = time.perf_counter()
            A, pin = self._matrix(cfg, plan)
            self._factors[key] = (SymmetricFactor(A), pin)
            self.timings["factorise"] = time.perf_counter() - t0
            self.n_factorisations += 1
        return self._factors[key]

    @staticmethod
    def _factor_key(cfg: SolverConfig, plan: SeamPlan) -> tuple:
        w = cfg.weights
        return (
            w.ease,
            w.regulariser,
            w.seam_length,
            w.seam_straight,
            w.seam_curve,
            w.warp_column,
            w.sliver,
            plan.gathered,
        )

    @_with_solvers_choice
    def guarded_factorisation(
        self, config: Optional[SolverConfig], plan: SeamPlan, gain: np.ndarray, reuse: Optional[SymmetricFactor] = None
    ) -> SymmetricFactor:
        """The factorisation of the system matrix with the collapse guard's triangles stiffened.

        ``gain`` (f,): triangle ``t``'s ease + regulariser weight is multiplied
        by ``1 + gain[t]`` (:func:`.steps.collapse_guard`). The stiffening only
        changes values on the shared matrix's sparsity pattern (a triangle's
        terms are already in it), so only the numeric factorisation is redone:
        ``reuse``, an earlier guarded factorisation of the same solve, is
        refactorised in place. While a solve runs it lives in its :class:`SolveState`,
        not on the solver; the shared factorisation (:meth:`factorisation`)
        is untouched, and a solve where no triangle nears collapse never builds one.
        Without ``reuse``, a factorisation a finished solve gave back
        (:meth:`release`) is refactorised if there is one: its symbolic analysis
        (AMD ordering, elimination tree) is a function of the sparsity pattern
        alone, so the values are the same bits as a new factorisation's, for
        ~12 ms less (the shirt) per solve.
        """
        cfg = config or self.config
        base, _ = self.factorisation(cfg, plan)
        return self._guarded.factorise(
            self._factor_key(cfg, plan), base, cfg.weights, self.area_weights(cfg), gain, reuse=reuse
        )

    def release(self, state: "SolveState") -> None:
        """Give ``state``'s guarded factorisation to the next solve of the same matrix
        (:meth:`guarded_factorisation`). ``state`` may still :meth:`iterate`: its next guarded step
        refactorises again."""
        fac, state.guard_solve, state.guard_held = state.guard_solve, None, None
        self._guarded.give_back(self._factor_key(state.config, state.plan), fac)

    def _matrix(self, cfg: SolverConfig, plan: SeamPlan):
        """The fixed system matrix (both pattern coordinates): ease + regulariser (one operator), the seam
        terms, and the gauge pins (returned apart, (n, 2): they also enter every right-hand side)."""
        w = cfg.weights
        W2 = np.array([1.0, w.warp_column**2])
        a = (w.ease + w.regulariser) * self.area_weights(cfg)
        L = (self._GxT @ sp.diags(a * W2[0]) @ self._Gx + self._GyT @ sp.diags(a * W2[1]) @ self._Gy).tocsr()
        L = seam_matrix(self.seams, cfg, plan, L)
        # translation gauge: one soft pin per panel, tiny against the diagonal
        d = L.diagonal()
        off = self.blocks.vertex_offsets
        pin = np.zeros(self.n)
        pin[off] = PIN_WEIGHT * np.add.reduceat(d, off) / self.blocks.vertex_counts
        return (L + sp.diags(pin)).tocsc(), np.stack([pin, pin], axis=1)

    @_with_solvers_choice
    def jacobians(self, U: np.ndarray) -> list:
        """Jacobians of ``U`` (n, 2) w.r.t. the initial flattening as 4 contiguous (f,) arrays m00, m01, m10, m11.

        ``m_ij``: derivative of pattern coordinate ``i`` (u, v) along initial axis ``j`` (x, y).
        """
        return self._products.jacobians(U)

    def start_from(self, pattern, offsets=None) -> np.ndarray:
        """The unknowns (n, 2) of a flip-free ``pattern`` of this cut, each piece re-centred on its initial
        position and, given ``offsets`` (:meth:`offsets` of the body the solve is on, a transfer's target),
        stretched to that body's weft and warp lengths (:func:`.start.pattern_start`)."""
        uv = [pattern.panel(pd.name).uv for pd in self.panels]
        own = None if offsets is None else self._own_offsets(pattern)
        return pattern_start(self.blocks, uv, self.uv0, offsets, own)

    def flattening_start(self, c_weft: np.ndarray, c_warp: np.ndarray, offsets) -> np.ndarray:
        """The unknowns (n, 2) a reference solve of targets ``c_weft``, ``c_warp`` starts from (the
        flattening stretched by them, :func:`.steps.scaled_start`), each piece stretched further to the
        body of ``offsets`` (:meth:`offsets`) as :meth:`start_from` stretches a pattern: a transfer
        started here runs the reference's own course on its body."""
        U = scaled_start(self.blocks, c_weft, c_warp)
        uv = [U[self.blocks.panel_slices(pd)[0]] for pd in self.blocks.panels]
        return pattern_start(self.blocks, uv, self.uv0, offsets, self.ref_offsets)

    def _own_offsets(self, pattern):
        """:meth:`offsets` of the body ``pattern`` lies on (its pieces' ``xyz``): the reference's when it is it."""
        xyz = [np.asarray(pattern.panel(pd.name).xyz, float) for pd in self.panels]
        if all(np.array_equal(x, self.ref_positions[pd.vertex_ids]) for x, pd in zip(xyz, self.panels)):
            return self.ref_offsets
        return intrinsic_offsets(np.concatenate([x[pd.faces] for x, pd in zip(xyz, self.panels)]), self.blocks.G)

    # ------------------------------------------------------------------ iterations
    def solve(
        self,
        K: np.ndarray,
        c_weft: np.ndarray,
        c_warp: np.ndarray,
        start: Optional[np.ndarray] = None,
        positions: Optional[np.ndarray] = None,
        progress: Optional[Progress] = None,
        poses: Optional[dict] = None,
        plan: Optional[SeamPlan] = None,
        config: Optional[SolverConfig] = None,
    ) -> SolveResult:
        """Run the local-global iterations towards targets ``diag(c_weft, c_warp) K`` (module docstring).

        Per iteration: the local step (closed-form rotations, all triangles at
        once), one right-hand side, one back-substitution of the factorised
        matrix for both coordinates, the per-panel rigid fit, the flip guard
        and the grain re-alignment; the Jacobians of the next iterate are
        carried through the re-alignment's rotation, so only two sparse
        products per iteration touch the triangles. The configuration's
        ``iterations`` (adaptation: at least ``adaptation.min_iterations``) of
        :meth:`iterate` from :meth:`begin`. A transfer (``positions`` given, no ``poses``) that
        :meth:`refusal` refuses is solved again from the same start with the folds of its targets bridged at
        each of :data:`.folds.RETRY_FLOORS` in turn, while it would be refused and the floor changes a target:
        the last try is the result (refused by :meth:`result` if it still is).

        Parameters
        ----------
        K : (f, 2, 2) intrinsic offsets of the targets; c_weft, c_warp : (f,) target scales.
        start : (n, 2) first iterate (default: the flattening stretched by the targets).
        positions : (N, 3) the body the result is reported on (default: the reference).
        poses : adaptation (from :meth:`pose_demands`): the feedback then aims, per
            triangle, at the larger of the design ease and what every pose demands
            along the pattern's *current* weft/warp directions (Eq. material-scale
            evaluated where the metric measures it), with the :class:`~.config.Adaptation`
            gain, iterations and bounds.
        plan : the seam plan (default: :meth:`plan_seams` of these targets).
        config : this call's configuration (default: the solver's).
        """
        args = dict(start=start, positions=positions, poses=poses, plan=plan, config=config)
        state = self._run(K, c_weft, c_warp, progress, **args)
        sewn = None  # the state's legs sewn equal, when its refusal was weighed: the result's (the same bits)
        if positions is not None and poses is None:
            # a transfer that would be refused: solved again with the skin's folds bridged further (.folds)
            for floor in RETRY_FLOORS:
                K_up = bridge_folds(K, self.ref_offsets[0], floor)
                if K_up is K:
                    continue  # no triangle squeezed under this floor (a higher one may squeeze some)
                refuse, sewn = self.refusal(state)
                if not refuse:
                    break
                spent = state.seconds
                state, sewn = self._run(K_up, c_weft, c_warp, None, **args), None
                state.seconds += spent
                state.fold_floor = floor
        report(progress, 1.0, "pattern optimized")
        return self.result(state, sewn)

    def _run(self, K, c_weft, c_warp, progress, **args) -> "SolveState":
        """One solve to its end by :meth:`extra_iterations` (arguments as :meth:`solve`), its guarded
        factorisation given back (:meth:`release`)."""
        state = self.begin(K, c_weft, c_warp, **args)
        self.iterate(state, state.planned, progress)
        while True:
            more = self.extra_iterations(state)
            if not more:
                break
            self.iterate(state, more)
        self.release(state)
        return state

    @_with_solvers_choice
    def refusal(self, state: "SolveState") -> Tuple[bool, Optional["SolveState"]]:
        """(whether :meth:`result` would refuse ``state`` (diverged, or a dart's legs not sewn equal) or its
        darts' legs cross (:meth:`.dart_gaps.GapCorrection.crossed`: the pipeline refuses the pattern),
        ``state`` with its legs sewn equal (:meth:`legs_sewn_equal`), or None when it diverged): the sewn
        state serves :meth:`result` too, so a solve sews its legs once."""
        if np.any(runaway(state)):
            return True, None
        sewn = self.legs_sewn_equal(state)
        return bool(unequal_legs(self.gaps.legs, sewn.U)) or self.gaps.crossed(sewn.U), sewn

    @_with_solvers_choice
    def begin(
        self,
        K: np.ndarray,
        c_weft: np.ndarray,
        c_warp: np.ndarray,
        start: Optional[np.ndarray] = None,
        positions: Optional[np.ndarray] = None,
        poses: Optional[dict] = None,
        plan: Optional[SeamPlan] = None,
        config: Optional[SolverConfig] = None,
        resume: Optional["SolveState"] = None,
    ) -> "SolveState":
        """The state of a solve before its first iteration (arguments as :meth:`solve`).

        ``resume``: a state of an earlier solve of this solver to continue from
        with new targets (a warm re-solve, e.g. after the designer painted): its
        iterate (unless ``start`` is given), the feedback's accumulated target
        corrections, the seam length integral, the local step's memory and the
        iteration count carry over, so the feedback stays on and the pattern
        moves only as far as the new targets ask. Nothing is kept on the solver.
        """
        cfg = config or self.config
        if config is not None:
            cfg.check()
        plan = plan if plan is not None else self.plan_seams(K, c_weft, c_warp, cfg)
        t0 = time.perf_counter()
        self.factorisation(cfg, plan)
        nf = len(self.gfaces)
        if start is not None:
            U = start.copy()
        elif resume is not None:
            U = resume.U.copy()
        else:
            U = scaled_start(self.blocks, c_weft, c_warp)
        adapting = poses is not None
        ad = cfg.adaptation
        state = SolveState(
            K=K,
            c_weft=c_weft,
            c_warp=c_warp,
            plan=plan,
            config=cfg,
            poses=poses,
            positions=self.ref_positions if positions is None else positions,
            planned=max(int(cfg.iterations), int(ad.min_iterations)) if adapting else int(cfg.iterations),
            U=U,
            M=self.jacobians(U),
            corr_w=np.ones(nf),
            corr_g=np.ones(nf),
            guard=np.zeros(nf),
            integral=np.zeros(len(self.seams.edge_start)),
            tg=rest_targets(K, c_weft, c_warp, cfg.rest_shape.model),
        )
        if resume is not None:
            state.corr_w, state.corr_g = resume.corr_w.copy(), resume.corr_g.copy()
            state.guard = resume.guard.copy()
            state.integral = resume.integral.copy()
            state.local_state = dict(resume.local_state)
            state.iteration = state.started = resume.iteration
            if start is None:
                state.s_cur = resume.s_cur
        state.seconds = time.perf_counter() - t0
        return state

    @_with_solvers_choice
    def iterate(self, state: "SolveState", iterations: int, progress: Optional[Progress] = None) -> "SolveState":
        """Run ``iterations`` more local-global iterations on ``state`` (updated in place and returned).

        ``state.step`` is then the RMS vertex move of the last iteration over
        the mean edge length (dimensionless; how far from a fixed point).
        """
        cfg = state.config
        fb, ad = cfg.feedback, cfg.adaptation
        t0 = time.perf_counter()
        lu, pin = self.factorisation(cfg, state.plan)
        a = self.area_weights(cfg)
        W2 = np.array([1.0, cfg.weights.warp_column**2])
        poses = state.poses
        adapting = poses is not None
        gain_w, gain_g, _, _, _ = feedback_gains(cfg, adapting)
        model = cfg.rest_shape.model
        K, c_weft, c_warp = state.K, state.c_weft, state.c_warp
        corr_w, corr_g, integral = state.corr_w, state.corr_g, state.integral
        U, M, s_cur, tg = state.U, state.M, state.s_cur, state.tg
        Kc = components(K)
        guarding = cfg.guard.guard_scale > 0
        Kinv = inverse_offsets(Kc) if guarding else None
        aw = (a * W2[0], a * W2[1])
        # a product by 1.0 is its operand: skipped where the weights are 1 (the same bits, fewer passes)
        unit_columns = W2[0] == 1.0 and W2[1] == 1.0
        # a reference or transfer solve aims the feedback at its own targets: their finiteness once
        targets_finite = None if adapting else np.isfinite(c_weft) & np.isfinite(c_warp)
        lam_ease, lam_reg = cfg.weights.ease, cfg.weights.regulariser
        pinned = np.flatnonzero(pin[:, 0])
        warp_from = None  # the last rest targets while their warp products hold (rest_targets' warp_from)
        n_it = int(iterations)
        for k in range(n_it):
            it = state.iteration
            extra = it - state.started - state.planned
            report(progress, k / max(n_it, 1), f"optimizing pattern: iteration {k + 1}/{n_it}")
            # targets held still: an adaptation's settling iterations (seams close, shear settles), rescue ones
            settling = adapting and ad.holds(it, state.planned) or rescuing(extra, state.planned)
            if (gain_w > 0 or gain_g > 0) and it >= fb.from_iteration and not settling:
                # move the targets by the achieved/target ratio: the linear solve then
                # lands on the wanted rho-hat wherever curvature allows it
                move_corrections(cfg, M, Kc, c_weft, c_warp, corr_w, corr_g, poses, targets_finite)
                cg = c_warp * corr_g if warp_from is None else None
                tg = rest_targets(Kc, c_weft * corr_w, cg, model, warp_from)
                # no warp gain: the feedback only bounds the warp corrections, so after its first move they hold
                warp_from = None if gain_g > 0 else tg
            RT, Te = local_step(cfg, M, tg, W2, state.local_state)
            state.energies.append(regulariser_energy(a, M, RT, W2))
            B = rhs_terms(RT, Te, lam_reg, lam_ease)  # lambda_reg R T + lambda_ease T (RT's arrays may be reused)
            solve_k, aw_k = lu, aw
            if guarding:
                # triangles near collapse: stiffened and pulled towards their opened shape
                q, guarded = collapse_guard(
                    round_guard(cfg.guard, extra, state.planned), M, Kc, c_weft, c_warp, state.guard, Kinv
                )
                held = state.guard_held
                if not guarded.size:
                    held = None  # the shared factorisation again, at no cost
                elif (
                    state.guard_solve is None
                    or held is None
                    or renew_guard(*(x[np.union1d(guarded, np.flatnonzero(held > 0))] for x in (state.guard, held)))
                ):
                    state.guard_solve = self.guarded_factorisation(
                        cfg, state.plan, state.guard, reuse=state.guard_solve
                    )
                    held = state.guard.copy()
                state.guard_held = held
                if held is not None:
                    gidx = np.flatnonzero(held > 0)
                    Z = opened_jacobians(cfg.guard.guard_open, q, gidx, Kc, c_weft, c_warp)
                    solve_k = state.guard_solve
                    g = held[gidx]
                    for j in range(4):
                        B[j][gidx] = (B[j][gidx] + (lam_ease + lam_reg) * g * Z[j]) / (1.0 + g)
                    stiff = 1.0 + held
                    aw_k = (aw[0] * stiff,) * 2 if unit_columns else (aw[0] * stiff, aw[1] * stiff)
            # the seams' part (a new array) plus the triangles' (x + y is y + x); the pins only where they are
            rhs = seam_rhs(self.seams, U, cfg, state.plan, integral)
            for j in range(4):  # the weighted right-hand side, in B's arrays
                np.multiply(aw_k[j % 2], B[j], out=B[j])
            self._products.add_rhs(rhs, B)  # rhs[:, 0] += GxT B0 + GyT B1, rhs[:, 1] += GxT B2 + GyT B3
            rhs[pinned] += pin[pinned] * U[pinned]
            # darts' legs kept apart, on the step's matrix
            U_new = self.gaps.correct(solve_k, solve_k(rhs), U, state.gap_held)
            # the step's rigid part per panel carries no strain: remove it so that the flip
            # guard only ever pulls back the local part of the step
            U_new = rigid_align(self.blocks, U_new, U)
            U_prev = U
            U, nb, s_cur = flip_guard(self.blocks, U, U_new, s_cur)
            state.backtracks += nb
            M = self.jacobians(U)
            if cfg.realign_grain:
                U, M = realign_grain(self.blocks, U, M)
            d = (U - U_prev).ravel()
            state.step = float(np.sqrt(np.einsum("i,i->", d, d) / len(U))) / self.mean_edge  # not BLAS: steps.py
            state.max_move = float(np.sqrt(np.max(d[0::2] * d[0::2] + d[1::2] * d[1::2]))) / self.mean_edge
            state.iteration += 1
        state.U, state.M, state.s_cur, state.tg = U, M, s_cur, tg
        state.seconds += time.perf_counter() - t0
        return state

    def neighbourhood(self) -> sp.csr_matrix:
        """:func:`.steps.face_neighbourhood` of the panels (built on first use)."""
        if self._neighbourhood is None:
            self._neighbourhood = face_neighbourhood(self.panels, self.blocks.area0)
        return self._neighbourhood

    def extra_iterations(self, state: "SolveState") -> int:
        """Iterations to add to ``state`` now that it has run its planned ones (0: the solve is done).

        A solve far from its start (high ease, a strong pose) may still hold a triangle the collapse
        guard is opening: :data:`COLLAPSE_ROUNDS` more at a time, as many again as planned, then up to
        :data:`RESCUE_ITERATIONS` rescue iterations while it would be refused (:func:`.guard.rescuing`).
        A solve whose darts' legs still cross (:meth:`.dart_gaps.GapCorrection.crossed`) runs the same
        rounds, as many again as planned at most; one run to :class:`~core.pattern.config.Convergence`
        does its rounds first.
        A diverged solve (:func:`.guard.runaway`) ends at once (:meth:`result` refuses it).
        Every driver of a solve (:meth:`solve`, the live loop) ends it by this rule: the same pattern.
        """
        if np.any(runaway(state)):
            return 0  # diverged, refused by :meth:`result`: no round brings it back
        extra = state.iteration - state.planned
        if extra < 0:
            return -extra
        if extra == 0 and self.converging(state):
            # not yet converged (config.Convergence): a round more, counted as planned
            more = min(state.config.convergence.window, state.config.convergence.cap - state.planned)
            state.planned += more
            return more
        if rescuing(extra, state.planned):
            return COLLAPSE_ROUNDS if extra < state.planned + RESCUE_ITERATIONS and refused(state) else 0
        if self.collapsing(state):
            return COLLAPSE_ROUNDS
        # a dart's legs still crossed (a pattern refused for it): rounds more, as many again as planned at most
        return COLLAPSE_ROUNDS if extra < state.planned and self.gaps.crossed(state.U) else 0

    @staticmethod
    def converging(state: "SolveState") -> bool:
        """Whether ``state``, at the end of its planned iterations, runs a round more to converge
        (:class:`~core.pattern.config.Convergence`: the rule on, a reference or transfer solve, under
        its cap, not :func:`converged`)."""
        cv = state.config.convergence
        return cv.energy_rtol > 0 and state.poses is None and state.planned < cv.cap and not converged(state)

    def collapsing(self, state: "SolveState") -> bool:
        """Whether ``state``'s iterate has a collapsed triangle (:func:`.steps.any_collapsed`) while its
        configuration guards against collapse."""
        return state.config.guard.guard_scale > 0 and any_collapsed(
            state.M, components(state.K), state.c_weft, state.c_warp
        )

    @_with_solvers_choice
    def result(self, state: "SolveState", sewn: Optional["SolveState"] = None) -> SolveResult:
        """The :class:`SolveResult` of ``state``'s current iterate (:func:`.build.solve_result`); a diverged
        one (:func:`.guard.runaway`) is refused with one line (PatternError) naming the piece that ran away.
        ``sewn``: ``state`` with its legs sewn equal when the caller has it (:meth:`refusal`), else sewn here."""
        over = runaway(state)
        if np.any(over):
            per_piece = np.add.reduceat(over, self.blocks.face_offsets)
            k = int(np.argmax(per_piece))
            raise PatternError(
                f"panel {self.panels[k].name!r}: the solve diverged after {state.iteration} iterations "
                f"({int(per_piece[k])} triangles stretched over {DIVERGED_SCALE:g} x their targets)"
            )
        done = self.legs_sewn_equal(state) if sewn is None else sewn
        if done.iteration >= done.started + done.planned:
            # a finished solve (not a live preview on its way): its darts' legs sewn equal, or refused
            over = unequal_legs(self.gaps.legs, done.U)
            if over:
                panel, dart, d = over[0]
                raise PatternError(
                    f"panel {panel!r}: the legs of dart {dart!r} differ by {1000 * d:.2f} mm after "
                    f"{state.iteration} iterations (sewn equal within {1000 * LEGS_REFUSED:g} mm); nothing written"
                )
        return solve_result(self.panels, done)

    def legs_sewn_equal(self, state: "SolveState") -> "SolveState":
        """``state`` with its darts' legs made equal in length (:func:`.dart_gaps.equal_legs`, on the solver's
        matrix; a copy), or ``state`` itself where they are within :data:`.dart_gaps.LEG_TOLERANCE` or the
        move would flip a triangle or cross a dart's legs (then the iterate is kept as it is). The state's
        iterate is not changed: a solve that goes on goes on from it."""
        lu, _ = self.factorisation(state.config, state.plan)
        U = equal_legs(self.gaps.legs, lu, state.U)
        if U is state.U:
            return state
        s_old = state.s_cur if state.s_cur is not None else None
        kept, cut, _ = flip_guard(self.blocks, state.U, U, s_old)
        if cut or self.gaps.crossed(kept):
            return state
        return dataclasses.replace(state, U=kept)


def converged(state: "SolveState") -> bool:
    """Whether ``state`` has converged by its configuration's :class:`~core.pattern.config.Convergence`:
    over the last ``window`` iterations the regulariser energy changed by under ``energy_rtol`` of
    itself per iteration, and the last iteration moved no vertex more than ``max_move`` mean edges."""
    cv = state.config.convergence
    E = state.energies
    if len(E) <= cv.window:
        return False
    now, before = E[-1], E[-1 - cv.window]
    rate = abs(now - before) / (cv.window * max(abs(now), 1e-300))
    return rate < cv.energy_rtol and state.max_move < cv.max_move
