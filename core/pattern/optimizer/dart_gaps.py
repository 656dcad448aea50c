"""A dart's legs keep a positive gap from the mouth to the apex: the solver's correction step.

A dart's legs are sewn to equal length (:data:`core.pattern.optimizer.seams.DART_LENGTH_WEIGHT`), but
nothing in the local-global energy keeps them apart, and the initial flattening does not either:
a conformal map (LSCM) closes a slit at its apex, where the surface is smooth, so a dart starts
with its legs tangent there, and where several darts share one bust's wedge they cross (the
four-dart blouse's front: 6 crossings in its LSCM start, 4 after the fitted solve, issue 30).
The piece then overlaps itself while every triangle keeps its orientation.

This is the dart's share of a global-injectivity constraint (cf. Smith & Schaefer 2015,
bijective parameterisation with free boundaries, whose barrier keeps boundary edges apart).
Over the matched vertices ``a_i`` / ``b_i`` of a dart's two legs (the apex left out), the gap
``u_a,i - u_b,i`` across the dart (along the left normal of the dart's local axis, the direction
from the pair before to the one after, towards the apex) must be at least ``min_gap_i``: the
legs' distance from the apex times :data:`MIN_OPENING` (a wedge of that angle). After each
global step, where a pair is under it (:meth:`GapCorrection.correct`), the step is corrected by
the smallest change ``d`` in the system matrix's norm that brings those pairs to their bound:

    (A + w D^T D) d = w D^T (t - D U)

with ``D`` the pairs' differences, ``t`` each pair's gap with its component across the dart
raised to the bound (the other pairs' gaps kept), and ``w`` :data:`STIFFNESS` times the mean
diagonal of ``A``. An iteration whose pairs are all apart is untouched, so a pattern whose darts
never close is the same bits as without the step. Both solver backends share this code (the
factorisation is :class:`.factor.SymmetricFactor`, qdldl's bits on both).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np
import scipy.sparse as sp

#: the narrowest wedge (radians, ~1.1 deg) a dart's legs may make: the gap across the dart at a
#: distance ``d`` from the apex is held at least ``MIN_OPENING * d``
MIN_OPENING = 0.02
#: the correction's weight on the pairs' gaps, times the mean diagonal of the system matrix
STIFFNESS = 100.0
#: the most a pair's gap is raised in one correction, times the legs' mean edge length (a deep crossing
#: opens over a few iterations: uncapped, the four-dart blouse transferred to women:XL with the warp
#: lengths kept diverged). On the charts refitted to their tape measures (2026-12-07) the four-dart
#: blouse's reference on women:M was refused at 1.0 (1099 flipped: the correction outran the flip guard
#: at the bust darts' tips) and at 0.3 or 0.15 (2 crossings per bust dart left open); 0.5 solves it
#: (0 crossings, weft 0.61 %) and every size transferred from it.
STEP_CAP = 0.5


@dataclass(frozen=True)
class DartLegs:
    """The matched leg vertices of every dart (global unknown ids, (P,) each): ``a``, ``b`` the pair;
    ``prev_a``/``prev_b`` and ``next_a``/``next_b`` the pairs before it (towards the mouth; the mouth's
    own pair at the mouth) and after it (towards the apex; the apex twice at the last pair), which
    give the local axis; ``min_gap`` (P,) metres."""

    a: np.ndarray
    b: np.ndarray
    prev_a: np.ndarray
    prev_b: np.ndarray
    next_a: np.ndarray
    next_b: np.ndarray
    min_gap: np.ndarray
    #: m, the mean length of the legs' edges in the initial flattening
    edge: float = 0.0
    #: ``(panel, dart)`` of each dart kept, in the order of their pairs (what a refusal names)
    names: tuple = ()


def dart_legs(sides: Sequence, pairs: Sequence, darts: Sequence[int], names: Optional[Sequence] = None) -> DartLegs:
    """The legs of the seams ``darts`` (indices into ``pairs``) from their ``sides``
    (:class:`core.pattern.optimizer.seams.SeamSide`: ``gids`` mouth to apex, ``rest_lengths``);
    ``names``: ``(panel, dart)`` of each of ``darts``."""
    cols = [[] for _ in range(7)]
    rest = []
    kept = []
    for n, si in enumerate(darts):
        A, B = sides[pairs[si][0]], sides[pairs[si][1]]
        ga, gb = np.asarray(A.gids, int), np.asarray(B.gids, int)
        k = len(ga) - 1  # pairs before the apex
        if k < 1 or len(gb) != len(ga):
            continue
        kept.append(("", f"dart {n + 1}") if names is None else tuple(names[n]))
        # distance to the apex along the legs (their mean), at each pair
        la = np.r_[np.cumsum(np.asarray(A.rest_lengths)[::-1])[::-1], 0.0]
        lb = np.r_[np.cumsum(np.asarray(B.rest_lengths)[::-1])[::-1], 0.0]
        dist = 0.5 * (la + lb)
        rest += [np.asarray(A.rest_lengths), np.asarray(B.rest_lengths)]
        i = np.arange(k)
        prev, nxt = np.maximum(i - 1, 0), i + 1
        for col, v in zip(cols, (ga[i], gb[i], ga[prev], gb[prev], ga[nxt], gb[nxt], MIN_OPENING * dist[i])):
            col.append(v)
    a, b, pa, pb, na, nb, g = (np.concatenate(c) if c else np.zeros(0) for c in cols)
    edge = float(np.mean(np.concatenate(rest))) if rest else 0.0
    return DartLegs(*(x.astype(int) for x in (a, b, pa, pb, na, nb)), g.astype(float), edge, tuple(kept))


def _legs_matrix(legs: DartLegs, weight: float, n: int) -> sp.csr_matrix:
    """(n, n) the term's part of the fixed system matrix: ``weight`` on ``(e_a - e_b)(e_a - e_b)^T``."""
    c = np.full(len(legs.a), float(weight))
    A, B = legs.a, legs.b
    return sp.coo_matrix(
        (np.concatenate([c, c, -c, -c]), (np.concatenate([A, B, A, B]), np.concatenate([A, B, B, A]))), shape=(n, n)
    ).tocsr()


def _across(legs: DartLegs, U: np.ndarray):
    """Each pair's gap ``u_a - u_b`` (P, 2), the unit left normal of the dart's local axis (P, 2) and the
    gap's component along it (P,): negative where the legs have crossed."""
    gap = U[legs.a] - U[legs.b]
    axis = 0.5 * (U[legs.next_a] + U[legs.next_b] - U[legs.prev_a] - U[legs.prev_b])
    # the pair next to the apex: the axis from its own midpoint to the apex, so its gap is the tip wedge's
    # orientation (the legs' last edges in order). Through the pair before, a pair that sits off the axis
    # close to the apex read apart with the legs swapped: skirt_darted's back darts on women:XL, their last
    # pair 0.6 mm from the apex and 33 deg off that axis, crossed the other leg with a positive gap.
    tip = legs.next_a == legs.next_b
    axis[tip] = U[legs.next_a[tip]] - 0.5 * (U[legs.a[tip]] + U[legs.b[tip]])
    across = np.stack([-axis[:, 1], axis[:, 0]], axis=1) / np.maximum(np.linalg.norm(axis, axis=1), 1e-300)[:, None]
    return gap, across, np.einsum("ij,ij->i", gap, across)


def leg_gaps(legs: DartLegs, U: np.ndarray) -> np.ndarray:
    """(P,) each pair's gap across the dart (m; negative where the legs have crossed)."""
    return _across(legs, U)[2]


def _entries(factor, B) -> np.ndarray:
    """Where the entries of ``B`` (canonical CSC) lie in ``factor``'s matrix's values."""
    return factor.positions(B.indices, np.repeat(np.arange(B.shape[1]), np.diff(B.indptr)))


class GapCorrection:
    """The correction step of a solver's darts (module rule).

    The corrected matrix ``A + w D^T D`` is factorised for each system matrix ``A`` a step solves: the
    solver's, or the collapse guard's stiffened one, which is refactorised whenever the guard renews
    its gains. Those matrices share one sparsity pattern, and so do their corrected ones: the first
    corrected factorisation of a pattern is kept (shared, never changed) for its symbolic analysis, and
    each solve refactorises one factorisation of its own in place for a new matrix (numeric only, the
    same values as a new factorisation's, so the same patterns bit for bit). The four-dart blouse's
    fitted reference on women:M at ease 1.1 and its transfer to women:XL made 59 corrected
    factorisations from scratch (11.8 ms of CPU each with the kernels, 7.5 with numpy); now 2, and 57
    refactorisations (3.1 / 3.4 ms): the two solves' CPU time 3.5-3.6 s -> 2.9-3.2 s (2-core VM,
    2026-12-07).
    """

    def __init__(self, legs: DartLegs):
        self.legs = legs
        self._held = None  # (the system matrix, the weight, the corrected one's factorisation) of calls with no holder
        self._shapes = []  # [(a corrected factorisation, never refactorised: its pattern's analysis)]
        self._lock = threading.Lock()
        #: corrected factorisations made from scratch (a new pattern, or a solve's first)
        self.factorised = 0

    def _shape_of(self, A):
        """``(the kept corrected factorisation whose pattern is A's plus the legs' term, where A's entries
        and then the legs' lie in its values)``, or None."""
        for fac, indptr, indices, pos_a, pos_l in self._shapes:
            if indptr.shape == A.indptr.shape and indices.shape == A.indices.shape:
                if np.array_equal(indptr, A.indptr) and np.array_equal(indices, A.indices):
                    return fac, pos_a, pos_l
        return None

    def _factor(self, base, holder: Optional[dict] = None):
        """``(w, the factorisation of base's matrix + w D^T D)``; ``holder`` (a solve's, see :meth:`correct`)
        keeps the solve's own factorisation, refactorised in place when ``base`` changes."""
        from .factor import SymmetricFactor

        A = base.matrix  # a guarded factorisation refactorised in place takes a new matrix
        held = self._held if holder is None else holder.get("held")
        if held is not None and held[0] is A:
            return held[1], held[2]
        w = STIFFNESS * float(A.diagonal().mean())
        L = _legs_matrix(self.legs, w, A.shape[0]).tocsc()
        L.sum_duplicates()
        with self._lock:
            shape = self._shape_of(A)
        if shape is None:
            fac = SymmetricFactor(A + L)
            self.factorised += 1
            entry = (fac, A.indptr.copy(), A.indices.copy(), _entries(fac, A), _entries(fac, L))
            with self._lock:
                if self._shape_of(A) is None:
                    self._shapes.append(entry)
        else:
            kept, pos_a, pos_l = shape
            # A's values and the legs' term on the kept pattern: the sums A + L makes, entry by entry
            data = np.zeros(kept.matrix.nnz)
            data[pos_a] = A.data
            data[pos_l] += L.data
            own = None if held is None or held[2] is kept else held[2]
            if own is not None and not (
                np.array_equal(own.matrix.indptr, kept.matrix.indptr)
                and np.array_equal(own.matrix.indices, kept.matrix.indices)
            ):
                own = None  # another pattern's (a call without a holder, another configuration before)
            fac = kept.with_values(data, reuse=own)
            self.factorised += own is None
        held = (A, w, fac)
        if holder is None:
            self._held = held
        else:
            holder["held"] = held
        return w, fac

    def correct(
        self, base, U: np.ndarray, prev: Optional[np.ndarray] = None, holder: Optional[dict] = None
    ) -> np.ndarray:
        """``U`` (n, 2), a global step's positions, corrected where a pair of legs is under its gap (a new array),
        or ``U`` itself where none is. ``base``: the :class:`.factor.SymmetricFactor` of the matrix the step
        solved: the solver's, or the collapse guard's stiffened one while it holds triangles (corrected with
        the solver's own matrix, the stiffened triangles at a bust dart's mouth were stretched instead: the
        four-dart blouse transferred to women:XL with the warp lengths kept, 200 iterations, had 2 triangles
        over 10 x their targets by iteration 30 and ran to 1e10 mm; with the stiffened one, none over 3 x).
        ``prev`` (n, 2): the iterate the step started from. A pair's gap is raised by at most
        :data:`STEP_CAP` legs' edges beyond the larger of its gap in ``U`` and in ``prev``: a deep crossing
        opens over a few iterations, and a pair the global step closes again is put back where the previous
        iterate held it (measured against the step alone, the cap let the step win: the four-dart blouse
        adapted to P1 kept its bust darts crossed by 7-14 mm over 300 iterations, and with the feedback
        running throughout the crossing deepened until the solve diverged). ``holder``: a dict one solve
        keeps (:attr:`.state.SolveState.gap_held`) for its corrected factorisation; without one the
        correction keeps its own (one solve at a time)."""
        legs = self.legs
        if not len(legs.a):
            return U
        gap, across, now = _across(legs, U)
        short = legs.min_gap - now
        if not np.any(short > 0):
            return U
        w, factor = self._factor(base, holder)
        # each pair's gap raised towards its bound, by at most the cap beyond the larger of its gap now and
        # in the previous iterate: t - D U, zero on the pairs apart
        opened = now if prev is None else np.maximum(now, _across(legs, prev)[2])
        raise_by = np.minimum(legs.min_gap, opened + STEP_CAP * legs.edge) - now
        r = np.clip(raise_by, 0.0, None)[:, None] * across
        rhs = np.zeros_like(U)
        np.add.at(rhs, legs.a, w * r)
        np.add.at(rhs, legs.b, -w * r)
        return U + factor.solve(rhs)

    def crossed(self, U: np.ndarray) -> bool:
        """Whether an edge of one leg of a dart touches or crosses an edge of its other leg in ``U`` (the
        two edges ending at the apex, which meet there, left out as a pair; each is checked against the
        other leg's other edges): the check a pattern is refused for
        (:func:`core.metrics.injectivity.crossings`), on the solver's iterate. A pair can be apart
        across the dart while a leg hooks past the apex (``blouse_fitted`` at one interior point of its
        parameter ranges: two crossings per waist dart after 20 iterations, none after 30;
        ``skirt_darted`` on women:XL: one leg's last edge across the other leg's edge before it)."""
        from ...geom.polygon import CONTACT, segment_gaps

        legs = self.legs
        if not len(legs.a):
            return False
        first = np.flatnonzero(legs.prev_a == legs.a)  # each dart's first pair (at the mouth)
        for lo, hi in zip(first, np.r_[first[1:], len(legs.a)]):
            # the pairs' edges towards the apex (the last ending at it)
            a0, a1 = legs.a[lo:hi], legs.next_a[lo:hi]
            b0, b1 = legs.b[lo:hi], legs.next_b[lo:hi]
            i, j = (x.ravel() for x in np.meshgrid(np.arange(len(a0)), np.arange(len(b0)), indexing="ij"))
            keep = (i < len(a0) - 1) | (j < len(b0) - 1)  # not the two edges that share the apex
            i, j = i[keep], j[keep]
            if len(i) and np.any(segment_gaps(U[a0[i]], U[a1[i]], U[b0[j]], U[b1[j]]) <= CONTACT):
                return True
        return False


# ---------------------------------------------------------------- the legs sewn equal at the end of a solve

#: m, the most a dart's two legs may differ in length at the end of a solve: a larger difference is
#: projected away by :func:`equal_legs` (issue 30: legs sewn equal within 0.1 mm)
LEG_TOLERANCE = 5e-5
#: m, the most a dart's two legs may differ in a pattern that is written (issue 30: legs sewn equal within
#: 0.1 mm): a solve that ends over it after :func:`equal_legs` had its go is refused (:func:`unequal_legs`)
LEGS_REFUSED = 1e-4
#: m, what :func:`equal_legs` aims to leave of each difference
LEG_TARGET = 5e-6
#: the projection's Newton steps at most (the legs' lengths are nearly linear in so small a move: 2 do)
LEG_STEPS = 4


def _dart_pairs(legs: DartLegs):
    """``[(lo, hi)]``: each dart's pairs ``lo:hi`` in ``legs`` (mouth to apex)."""
    first = np.flatnonzero(legs.prev_a == legs.a)  # each dart's first pair (at the mouth)
    return list(zip(first.tolist(), np.r_[first[1:], len(legs.a)].tolist()))


def leg_differences(legs: DartLegs, U: np.ndarray) -> np.ndarray:
    """(m,) each dart's leg ``a`` minus leg ``b`` (m), mouth to apex, in ``U`` (n, 2)."""
    la = np.linalg.norm(U[legs.next_a] - U[legs.a], axis=1)
    lb = np.linalg.norm(U[legs.next_b] - U[legs.b], axis=1)
    return np.array([la[lo:hi].sum() - lb[lo:hi].sum() for lo, hi in _dart_pairs(legs)])


def _difference_gradient(legs: DartLegs, U: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """(n, 2) the gradient of one dart's leg difference (pairs ``lo:hi``) with respect to ``U``."""
    g = np.zeros_like(U)
    for p, q, sign in ((legs.a, legs.next_a, 1.0), (legs.b, legs.next_b, -1.0)):
        e = U[q[lo:hi]] - U[p[lo:hi]]
        t = sign * e / np.maximum(np.linalg.norm(e, axis=1), 1e-300)[:, None]
        np.add.at(g, q[lo:hi], t)
        np.add.at(g, p[lo:hi], -t)
    return g


def equal_legs(legs: DartLegs, factor, U: np.ndarray) -> np.ndarray:
    """``U`` (n, 2) with every dart's legs of equal length (a new array), or ``U`` itself where each pair
    of legs already differs by at most :data:`LEG_TOLERANCE`.

    The legs are sewn to equal length by the seam term, but a solve ends with what its last iterations
    left: the four-dart blouse adapted to P1 (fitted) had its bust darts' legs 0.43 mm apart, its shoulder
    darts' 0.18 mm, while the pose's demands and the gap step pulled at them. The smallest change in the
    norm of the system matrix ``A`` (``factor``: its :class:`.factor.SymmetricFactor`) that makes every
    dart's difference ``c_k`` vanish, linearised (``J_k`` its gradient): ``d = sum_k l_k A^-1 J_k`` with
    ``(J A^-1 J^T) l = -c``, a few Newton steps. The move spreads over the piece as the solve's own
    energy allows (well under a millimetre); one back-substitution per dart and step."""
    pairs = _dart_pairs(legs) if len(legs.a) else []
    if not pairs:
        return U
    c = leg_differences(legs, U)
    if np.max(np.abs(c)) <= LEG_TOLERANCE:
        return U
    out = U.copy()
    for _ in range(LEG_STEPS):
        J = [_difference_gradient(legs, out, lo, hi) for lo, hi in pairs]
        Y = [factor.solve(j) for j in J]
        S = np.array([[np.vdot(j, y) for y in Y] for j in J])
        lam = np.linalg.lstsq(S, -c, rcond=None)[0]  # a degenerate dart (no gradient) gets no move
        for k, y in enumerate(Y):
            out += lam[k] * y
        c = leg_differences(legs, out)
        if not np.all(np.isfinite(out)):
            return U
        if np.max(np.abs(c)) <= LEG_TARGET:
            break
    return out


def unequal_legs(legs: DartLegs, U: np.ndarray, tolerance: float = LEGS_REFUSED) -> list:
    """``[(panel, dart, difference m)]``: the darts whose two legs differ in length by more than ``tolerance``
    in ``U`` (n, 2), the largest difference first (empty: every dart's legs sewn equal)."""
    if not len(legs.a):
        return []
    c = np.abs(leg_differences(legs, U))
    names = legs.names or tuple(("", f"dart {k + 1}") for k in range(len(c)))
    over = [(names[k][0], names[k][1], float(c[k])) for k in np.flatnonzero(~(c <= tolerance))]
    return sorted(over, key=lambda x: -x[2] if np.isfinite(x[2]) else -np.inf)
