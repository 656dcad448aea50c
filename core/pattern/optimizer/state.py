"""The state of a pattern solve between iterations: a value passed to the solver, never kept on it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, List, Optional

import numpy as np

from ..config import SolverConfig
from .seams import SeamPlan


@dataclass
class SolveState:
    """Where a solve stands between calls of :meth:`PatternSolver.iterate` (a value; the solver keeps none).

    Attributes
    ----------
    K : (f, 2, 2) intrinsic offsets of the targets; c_weft, c_warp : (f,) target scales.
    plan : SeamPlan sewn; config : SolverConfig of the solve; poses : adaptation demands or None.
    positions : (N, 3) m, the body the result is reported on.
    planned : iterations a one-shot :meth:`PatternSolver.solve` of this configuration runs.
    U : (n, 2) m, the current iterate; M : its Jacobians (4 arrays (f,)).
    corr_w, corr_g : (f,) the feedback's accumulated target corrections.
    guard : (f,) the collapse guard's stiffening gains (:func:`.steps.collapse_guard`; 0 = not guarded);
    guard_solve : the back-substitution of the matrix with the gains ``guard_held`` (the gains when it was
    last factorised, :func:`~core.pattern.optimizer.guard.renew_guard`; None: the shared matrix is solved), or None.
    gap_held : the gap step's own corrected factorisation (:meth:`.dart_gaps.GapCorrection.correct`'s ``holder``).
    integral : (E,) the seam length term's integral action; tg : the current rest targets.
    s_cur : (f,) signed areas of ``U`` or None; local_state : the local step's memory.
    iteration : iterations run so far (a resumed solve carries the earlier one's on); started : ``iteration``
    when this solve began (0, or the resumed solve's count); energies : energy per iteration; backtracks :
    flip-guard halvings.
    step : RMS vertex move of the last iteration over the mean edge length (inf before the first);
    max_move : the largest vertex move of the last iteration over the mean edge length.
    seconds : wall time spent in :meth:`~PatternSolver.begin` and :meth:`~PatternSolver.iterate` (a
    transfer's retry adds the first try's).
    """

    K: np.ndarray
    c_weft: np.ndarray
    c_warp: np.ndarray
    plan: SeamPlan
    config: SolverConfig
    poses: Optional[dict]
    positions: np.ndarray
    planned: int
    U: np.ndarray
    M: list
    corr_w: np.ndarray
    corr_g: np.ndarray
    guard: np.ndarray
    integral: np.ndarray
    tg: dict
    s_cur: Optional[np.ndarray] = None
    guard_solve: Optional[Callable] = None
    guard_held: Optional[np.ndarray] = None
    gap_held: dict = field(default_factory=dict)
    local_state: dict = field(default_factory=dict)
    iteration: int = 0
    started: int = 0
    energies: List[float] = field(default_factory=list)
    backtracks: int = 0
    step: float = float("inf")
    max_move: float = float("inf")
    seconds: float = 0.0
    #: a transfer solved again with its targets' folds bridged further (:data:`.folds.RETRY_FLOORS`): that
    #: floor; None: the solve's own targets
    fold_floor: Optional[float] = None
