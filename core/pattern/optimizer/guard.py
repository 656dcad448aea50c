"""The collapse guard's schedule and its stiffened factorisations (:class:`GuardedFactors`).

The guard (:func:`.steps.collapse_guard`) stiffens triangles near collapse;
a solve that guards solves a matrix of its own, the shared system matrix
with those triangles' terms scaled by ``1 + gain``. The stiffening only
changes values on the shared matrix's sparsity pattern, so a guarded
factorisation is a numeric refactorisation of the shared one
(:meth:`.factor.SymmetricFactor.with_values`). This module holds when a
solve refactorises (:func:`renew_guard`), how the guard hardens in a
solve's extra rounds (:func:`round_guard`) and in the rescue iterations of
a solve that would be refused after them (:func:`rescuing`, :func:`refused`),
and the per-solver pool of guarded factorisations that finished solves give back.
"""

from __future__ import annotations

import threading
from dataclasses import replace
from typing import Dict, Optional

import numpy as np

from ...geom.strain import components, scales_of_offsets
from .factor import SymmetricFactor

#: Iterations added at a time after the planned ones while a triangle is still collapsed.
COLLAPSE_ROUNDS = 5
#: Each round of extra iterations after the first multiplies the collapse guard's stiffening limit by this.
GUARD_ESCALATION = 4.0
#: Rounds of extra iterations that raise the collapse guard's limit at most: 4, the rounds a solve of the
#: default 20 iterations has (its extra iterations are at most as many as planned), so its limit reaches
#: 4^4 = 256 x. A longer solve raised it on, one level a round: the four-dart blouse transferred to women:XL
#: with 200 iterations (warp slack 0) reached gains of 1e13 in its extra rounds, the stiffened matrix lost
#: its conditioning and the solve ran away (refused as diverged after 280 iterations).
GUARD_LEVELS = 4
#: Rescue iterations at most (rounds of :data:`COLLAPSE_ROUNDS`) after a solve's extra ones, for a solve
#: that would be refused for collapse when they end (:func:`rescuing`, :func:`refused`).
RESCUE_ITERATIONS = 40
#: The collapse rule a pattern is refused for (docs/metrics.md; :mod:`core.metrics.collapse`, a later
#: stage, reads these two numbers as ``AREA_FRACTION`` and ``SCALE_FRACTION``): a triangle keeping
#: under this share of the 2D area its targets ask for ...
REFUSED_AREA = 0.25
#: ... or a weft or warp scale under this share of its target.
REFUSED_SCALE = 0.5
#: A solve has diverged when a triangle's weft or warp scale exceeds this multiple of its target (or a
#: position is not finite): no solve that converges stretches a triangle past 3 x (the feedback's and the
#: adaptation's ceilings are 1.25 and 2); the four-dart blouse transferred to women:XL with the warp lengths
#: kept (warp slack 0, 200 iterations) ran to 1e10 mm with every triangle keeping its orientation.
DIVERGED_SCALE = 10.0
#: Spare guarded factorisations kept per system matrix (one per thread solving at once is enough).
GUARD_POOL = 4
#: The collapse guard's stiffened matrix is refactorised when a triangle is guarded that it does not
#: stiffen, or when a triangle's weight factor ``1 + gain`` has moved by more than this factor from the
#: one it holds (gains double or halve per iteration: about every other change). In between the solve
#: keeps the gains it factorised, in the matrix and the right-hand side alike (one consistent energy).
#: Shirt transfers: a third fewer refactorisations (~4 ms each), the same patterns to a few 0.01 %.
GUARD_RENEW = 3.0


def round_guard(guard, extra: int, planned: int):
    """The collapse guard of an iteration ``extra`` iterations past a solve's ``planned`` ones.

    A triangle can sit under the collapse bound with its stiffening at ``guard_limit`` while
    its neighbours' pull balances it (the skirt's gluteal cleft at the finest refinement, on
    an AMD EPYC: relative scale 0.47 from iteration 15 on, at gain 30; on an Intel Xeon the
    same solve ended just above 0.5). Each round of :data:`COLLAPSE_ROUNDS` extra iterations
    after the first raises the limit by :data:`GUARD_ESCALATION`, so such a triangle opens
    (0.60 five iterations later) instead of the pattern being refused; a solve that ends
    within its planned iterations or its first extra round never sees a higher limit, and none
    sees more than :data:`GUARD_LEVELS` raises.
    In rescue iterations (:func:`rescuing`) the guard keeps every gain it has raised
    (``guard_release`` 1) under the limit of the first rescue round, held there (raised on, the
    shirt's four sampled bodies that stay refused kept 2-37 collapsed triangles after 40 rescue
    iterations and 3-8,074 after 120; held, 2-28 and 5-21).
    """
    rescue = rescuing(extra, planned)
    # the rescue holds the limit of its first round: the cycle it breaks is not one held at the limit,
    # and a limit raised on (x4 a round: 1e18 after 120 rescue iterations) lets the solve run away
    level = min(extra, planned, GUARD_LEVELS * COLLAPSE_ROUNDS) // COLLAPSE_ROUNDS if extra > 0 else 0
    if level == 0 and not rescue:
        return guard
    return replace(
        guard, guard_limit=guard.guard_limit * GUARD_ESCALATION**level, **({"guard_release": 1.0} if rescue else {})
    )


def rescuing(extra: int, planned: int) -> bool:
    """Whether an iteration ``extra`` iterations past a solve's ``planned`` ones is a rescue iteration:
    one after the extra rounds (as many as planned), which only a solve the pipeline would refuse for
    collapse at their end runs (:func:`refused`).

    Such a solve is caught in a cycle, not held at a limit: the guard stiffens a triangle, it
    opens past ``guard_open``, the guard gives its gain back and a few iterations later it
    collapses again, or a neighbour does; escalating the limit does not reach triangles whose
    gains keep being given back. The long-sleeved shirt transferred to heavy, short sampled
    bodies: the body triangle at the armpit under ``sleeve_back_*`` is stretched along and
    squeezed across (sample 809 of seed 2024: 1.27x and 0.37x the reference, anisotropy 3.4
    where the panel's median is 1.3), the cloth triangles in it collapse in turn at gains of
    0-8 with the feedback's weft correction at its ceiling, 1-6 of them at any iteration
    through the 40th, and 40 more plain extra iterations end collapsed too. A rescue
    iteration breaks the cycle: the guard keeps its gains (:func:`round_guard`) and the
    targets stay where the feedback left them, as in an adaptation's settling iterations.
    A solve that ends earlier never runs one, so its pattern is what it was without them.
    """
    return extra >= planned


def refused(state) -> bool:
    """Whether a solve's iterate (:class:`.state.SolveState`) has a triangle collapsed by the rule a
    pattern is refused for (:func:`refused_mask`).

    Looser than :func:`.steps.any_collapsed` (the smaller relative singular value under 0.5), which a
    sheared triangle can fail with its weft, warp and area kept: the extra rounds run on that bound,
    the rescue iterations only for a pattern the pipeline would refuse (shirt on 1,000 sampled bodies:
    6 patterns end their extra rounds over the bound and pass the rule; they stay as they were).
    """
    return bool(np.any(refused_mask(state.M, components(state.K), state.c_weft, state.c_warp)))


def refused_mask(M: list, Kc: list, c_weft: np.ndarray, c_warp: np.ndarray) -> np.ndarray:
    """(f,) bool: the triangles collapsed by the rule a pattern is refused for (:data:`REFUSED_AREA`,
    :data:`REFUSED_SCALE`; flipped ones are the flip guard's), from the solve's own Jacobians: the
    pattern's area over the body's is ``det M / |det K|`` and its scales :func:`~core.geom.strain.scales_of_offsets`."""
    rw, rg = scales_of_offsets(M, Kc)
    det = M[0] * M[3] - M[1] * M[2]
    with np.errstate(invalid="ignore"):
        small = det < REFUSED_AREA * np.abs(Kc[0] * Kc[3] - Kc[1] * Kc[2]) * c_weft * c_warp
        thin = (rw < REFUSED_SCALE * c_weft) | (rg < REFUSED_SCALE * c_warp)
    return (det > 0) & (small | thin)


def runaway(state) -> np.ndarray:
    """(f,) bool: the triangles of a solve's iterate (:class:`.state.SolveState`) that have diverged, a weft or
    warp scale over :data:`DIVERGED_SCALE` times its target or not finite."""
    rw, rg = scales_of_offsets(state.M, components(state.K))
    with np.errstate(invalid="ignore"):
        return ~((rw <= DIVERGED_SCALE * state.c_weft) & (rg <= DIVERGED_SCALE * state.c_warp))


def renew_guard(gain: np.ndarray, held: np.ndarray, ratio: Optional[float] = None) -> bool:
    """Whether the collapse guard's gains ``gain`` (f,) call for a new factorisation of the matrix that
    holds ``held`` (f,): a triangle guarded that it does not stiffen, or a weight factor ``1 + gain``
    off the held one by more than ``ratio`` either way (default :data:`GUARD_RENEW`)."""
    ratio = GUARD_RENEW if ratio is None else ratio
    if np.any((gain > 0) & (held == 0)):
        return True
    r = (1.0 + gain) / (1.0 + held)
    return bool(np.any(r > ratio) or np.any(r * ratio < 1.0))


class GuardedFactors:
    """Stiffened refactorisations of a solver's system matrices, and the spare ones finished solves gave back.

    Parameters
    ----------
    faces : (f, 3) int, the stacked panels' triangles (unknown indices).
    G : (f, 3, 2) float, their gradient operators on the initial flattening.

    Keyed by the system matrix (the solver's factorisation key). A spare
    factorisation is reused only for its symbolic analysis (AMD ordering,
    elimination tree: a function of the sparsity pattern alone); every
    refactorisation gives the factors of its own values (all of them with
    qdldl; with :class:`.ldl.LDL` the rows whose inputs differ from the ones
    the spare held, the others being the same bits), so no result depends on the pool.
    """

    def __init__(self, faces: np.ndarray, G: np.ndarray):
        self.faces = faces
        self.G = G
        self._slots: Dict[tuple, np.ndarray] = {}
        self._pool: Dict[tuple, list] = {}
        self._lock = threading.Lock()

    def factorise(
        self,
        key: tuple,
        base: SymmetricFactor,
        weights,
        area_weights: np.ndarray,
        gain: np.ndarray,
        reuse: Optional[SymmetricFactor] = None,
    ) -> SymmetricFactor:
        """The factorisation of ``base``'s matrix with triangle ``t``'s ease + regulariser terms times ``1 + gain[t]``.

        ``weights``: the configuration's :class:`~.config.Weights`; ``area_weights`` (f,) the
        solver's; ``reuse``: a guarded factorisation of the same matrix to refactorise in place
        (else a spare one from the pool, else a new one).
        """
        if key not in self._slots:
            # where each triangle's 3 x 3 block of terms sits in the matrix's values (once per matrix)
            F = self.faces
            self._slots[key] = base.positions(np.repeat(F, 3, axis=1), np.tile(F, (1, 3)))
        pos = self._slots[key]
        t = np.flatnonzero(gain > 0)
        a = (weights.ease + weights.regulariser) * area_weights[t] * gain[t]
        gx, gy = self.G[t, :, 0], self.G[t, :, 1]
        # a_t (gx_p gx_q + w^2 gy_p gy_q): the triangle's extra terms, entry (p, q) at slot 3 p + q
        extra = a[:, None, None] * (
            gx[:, :, None] * gx[:, None, :] + weights.warp_column**2 * gy[:, :, None] * gy[:, None, :]
        )
        data = base.matrix.data + np.bincount(
            pos[t].ravel(), weights=extra.reshape(len(t), 9).ravel(), minlength=base.matrix.nnz
        )
        if reuse is None:
            with self._lock:
                spare = self._pool.get(key)
                reuse = spare.pop() if spare else None
        return base.with_values(data, reuse=reuse)

    def give_back(self, key: tuple, factor: Optional[SymmetricFactor]) -> None:
        """Keep ``factor`` (a finished solve's) for the next solve of the same matrix, up to :data:`GUARD_POOL`."""
        if factor is None:
            return
        with self._lock:
            spare = self._pool.setdefault(key, [])
            if len(spare) < GUARD_POOL and all(f is not factor for f in spare):
                spare.append(factor)
