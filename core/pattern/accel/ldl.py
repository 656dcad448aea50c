"""QDLDL's LDLᵀ of the system matrix, refactorised only where values changed, solved two columns at once.

:class:`.factor.SymmetricFactor` factorises with qdldl-python (AMD ordering,
elimination tree, numeric factors) and, where the solver's Warp kernels run
(:func:`.compiled.enabled`) and they give qdldl's bits on the machine
(:func:`matches_qdldl`: not where qdldl's build fuses multiply-adds, as its
macOS arm64 wheel does), hands the factors to an :class:`LDL`:

- :meth:`LDL.refactorise`: the collapse guard stiffens a few triangles, which
  changes a few columns of the matrix. Only the rows of L those columns reach
  (the columns and their ancestors in the elimination tree) can change; the
  others would be recomputed from the same inputs into the same bits. On the
  long-sleeved shirt a guard's refactorisation recomputes 2-10 % of the rows,
  27-73 % of the work (the top separators of a panel are on every path),
  instead of all of it;
- :meth:`LDL.solve`: both pattern coordinates in one pass over L.

The loops are QDLDL's (:mod:`.ldl_kernels`) on the matrix qdldl-python
factorises (its symmetric permutation, entries in its order), so factors and
solutions are qdldl's bits and a pattern is the same bytes either way
(tests/test_pattern_ldl.py). A launch Warp refuses turns the kernels off for
the process (:func:`.compiled.give_up`) and the factor goes back to qdldl
(factors made earlier keep their LDL until a launch of theirs fails: the same
bits either way). A zero pivot raises ValueError (qdldl-python's constructor
raises RuntimeError; its update ignores it and leaves stale factors).
"""

from __future__ import annotations

import logging
from typing import Optional

import numpy as np

from . import compiled

log = logging.getLogger(__name__)
_I32 = np.int32


class Plan:
    """The symbolic side of QDLDL's factorisation of one sparsity pattern (shared by every :class:`LDL` of it).

    Parameters
    ----------
    P : (n,) int, the AMD ordering qdldl chose (row ``i`` of the permuted matrix is row ``P[i]``).
    L : (n, n) ``scipy.sparse.csc_matrix``, its strictly lower factor (the pattern is used).
    upper : (keep, rows, indptr) of :class:`.factor.SymmetricFactor`: the upper triangle's entries
        (indices into the full matrix's values), their rows and column pointers.
    nnz : int, the number of stored values of the full matrix.
    """

    def __init__(self, P: np.ndarray, L, upper: tuple, nnz: int):
        from . import ldl_kernels as K

        keep, rows, ptr = upper
        n = len(P)
        self.n = n
        self.P = np.ascontiguousarray(P, _I32)
        self.Lp = np.ascontiguousarray(L.indptr, _I32)
        self.Li = np.ascontiguousarray(L.indices, _I32)
        pinv = np.empty(n, np.int64)
        pinv[P] = np.arange(n)
        # qdldl-python's symperm: the upper triangle's entries (in column order) scattered to column
        # max(pinv i, pinv j) of the permuted matrix, each column in scan order; the order of a column's
        # entries is the order QDLDL walks them in, which decides its sums' order
        cols = np.repeat(np.arange(n), np.diff(ptr))
        i2, j2 = pinv[rows], pinv[cols]
        target = np.maximum(i2, j2)
        order = np.argsort(target, kind="stable")
        self.Ap = np.concatenate([[0], np.cumsum(np.bincount(target, minlength=n))]).astype(_I32)
        self.Ai = np.minimum(i2, j2)[order].astype(_I32)
        #: (nnz_upper,) the full matrix's value index of each permuted entry
        self.src = np.asarray(keep, np.int64)[order]
        #: (nnz,) the permuted column a full-matrix value enters (-1: below the diagonal, not read)
        self.entry_column = np.full(nnz, -1, _I32)
        self.entry_column[keep] = target
        # elimination tree: a column's parent is its first row below the diagonal in L
        self.etree = np.full(n, -1, _I32)
        has = np.diff(self.Lp) > 0
        self.etree[has] = self.Li[self.Lp[:-1][has]]
        self.rowptr = np.concatenate([[0], np.cumsum(np.bincount(self.Li, minlength=n))]).astype(_I32)
        self.seq_c = np.zeros(len(self.Li), _I32)
        self.seq_slot = np.zeros(len(self.Li), _I32)
        K.wp.launch(
            K.ldl_plan,
            dim=1,
            device="cpu",
            inputs=[
                n,
                *_arrays(
                    self.Ap, self.Ai, self.etree, self.Lp, self.rowptr, self.seq_c, self.seq_slot, np.zeros(4 * n, _I32)
                ),
            ],
        )


def _arrays(*arrays) -> list:
    from .ldl_kernels import wp

    return [wp.array(a, device="cpu", copy=False) for a in arrays]


class LDL(compiled.PerThread):
    """The numeric factors ``L``, ``D``, ``1 / D`` of the matrix with values ``data`` on :class:`Plan` ``plan``.

    Parameters
    ----------
    plan : :class:`Plan`.
    Lx : (nnz_L,) float, L's values in QDLDL's layout; D, Dinv : (n,) float.
    data : (nnz,) float, the full matrix's values they factorise (held by reference, never written).
    """

    def __init__(
        self,
        plan: Plan,
        Lx: np.ndarray,
        D: np.ndarray,
        Dinv: np.ndarray,
        data: np.ndarray,
        Ax: Optional[np.ndarray] = None,
    ):
        self.plan = plan
        self.Lx, self.D, self.Dinv = Lx, D, Dinv
        self.data = data
        self.Ax = np.take(data, plan.src) if Ax is None else Ax  # the permuted upper triangle's values
        super().__init__()  # per thread: recorded launches and their buffers (no shared scratch space)

    @classmethod
    def from_qdldl(cls, solver, upper: tuple, data: np.ndarray) -> Optional["LDL"]:
        """The factors of qdldl-python ``solver``, which factorised the upper triangle ``upper`` of ``data``;
        None where they stay qdldl's: indices past the kernels' int32 (qdldl's are 64-bit), or the plan's
        launch failed (the kernels are off now)."""
        L, D, P = solver.factors()
        if max(int(L.indptr[-1]), len(data), 2 * len(P)) > np.iinfo(_I32).max:
            return None
        try:
            plan = Plan(P, L, upper, len(data))
        except Exception as exc:  # noqa: BLE001 - as refactorise
            compiled.give_up("launching ldl_plan", exc)
            return None
        D = np.array(D, float)
        return cls(plan, np.array(L.data, float), D, 1 / D, data)

    def copy(self) -> "LDL":
        """An independent copy (its own values, the same plan)."""
        return LDL(self.plan, self.Lx.copy(), self.D.copy(), self.Dinv.copy(), self.data, self.Ax.copy())

    def _record(self, name: str, make):
        rec = getattr(self._local, name, None)
        if rec is None:
            rec = make()
            setattr(self._local, name, rec)
        return rec

    def _rows_record(self):
        from . import ldl_kernels as K

        p = self.plan
        mark, y, failed = np.zeros(p.n, _I32), np.zeros(p.n), np.zeros(1, _I32)
        cmd = K.wp.launch(
            K.ldl_rows,
            dim=1,
            device="cpu",
            record_cmd=True,
            inputs=[
                p.n,
                *_arrays(
                    mark,
                    p.Ap,
                    p.Ai,
                    self.Ax,
                    p.etree,
                    p.rowptr,
                    p.seq_c,
                    p.seq_slot,
                    p.Lp,
                    p.Li,
                    self.Lx,
                    self.D,
                    self.Dinv,
                    y,
                    failed,
                ),
            ],
        )
        return cmd, mark, failed

    def _solve_record(self):
        from . import ldl_kernels as K

        p = self.plan
        b, work, x = np.zeros((p.n, 2)), np.zeros(2 * p.n), np.zeros((p.n, 2))
        cmd = K.wp.launch(
            K.ldl_solve2,
            dim=1,
            device="cpu",
            record_cmd=True,
            inputs=[p.n, *_arrays(p.P, p.Lp, p.Li, self.Lx, self.Dinv, b.reshape(-1), work, x.reshape(-1))],
        )
        return cmd, b, x

    def refactorise(self, data: np.ndarray) -> bool:
        """Factorise the matrix with values ``data`` (nnz,) in place, recomputing the rows that differ
        from the held values' (compared bit for bit). False: the kernels failed (they are off now).
        ValueError: a zero pivot (what is held then is the factorisation of ``data``, zero pivot and all)."""
        data = np.asarray(data, float)
        changed = np.flatnonzero(data.view(np.int64) != self.data.view(np.int64))
        columns = self.plan.entry_column[changed]
        columns = columns[columns >= 0]
        if len(columns):
            try:
                cmd, mark, failed = self._record("rows", self._rows_record)
                np.take(data, self.plan.src, out=self.Ax)
                mark[columns] = 1
                cmd.launch()
            except Exception as exc:  # noqa: BLE001 - a launch Warp refuses leaves qdldl, the same bits
                compiled.give_up("launching ldl_rows", exc)
                return False
            if failed[0]:
                failed[0] = 0
                # the factors are those of ``data`` (every reached row was recomputed): held as such, a
                # later refactorisation recomputes what differs from it
                self.data = data
                raise ValueError("matrix is not quasi-definite: a zero pivot in its LDL^T factorisation")
        self.data = data
        return True

    def solve(self, rhs: np.ndarray) -> Optional[np.ndarray]:
        """``A⁻¹ rhs`` for rhs (n,) or (n, k), or None where the kernels failed (they are off now)."""
        rhs = np.asarray(rhs, float)
        cols = rhs[:, None] if rhs.ndim == 1 else rhs
        if cols.ndim != 2 or len(cols) != self.plan.n:
            # the caller's error, raised as qdldl does, not a failed launch that turns the kernels off
            raise ValueError(f"expected a right-hand side of {self.plan.n} rows, got shape {rhs.shape}")
        k = cols.shape[1]
        out = np.empty(cols.shape)
        try:
            cmd, b, x = self._record("solve", self._solve_record)
            for j in range(0, k, 2):
                # a lone last column is solved beside zeros: each column's operations are its own
                m = min(2, k - j)
                b[:, :m] = cols[:, j : j + m]
                b[:, m:] = 0.0
                cmd.launch()
                out[:, j : j + m] = x[:, :m]
        except Exception as exc:  # noqa: BLE001 - as refactorise
            compiled.give_up("launching ldl_solve2", exc)
            return None
        return out[:, 0] if rhs.ndim == 1 else out


#: whether the kernels give qdldl-python's bits on this machine (:func:`matches_qdldl`), once probed
_MATCH: dict = {}


def matches_qdldl() -> bool:
    """Whether QDLDL's loops in :mod:`.ldl_kernels` give qdldl-python's bits here, probed once per process.

    The kernels are built without fused multiply-adds, as are qdldl's x86-64 wheels (Linux, Windows:
    baseline x86-64 has no FMA); its macOS arm64 wheel fuses ``y -= l * x`` (``fmsub`` in
    ``QDLDL_factor`` and ``QDLDL_solve``). There the kernels' rows would differ from qdldl's in the last
    bits, and a refactorised factor would mix both by the rows its history recomputed (a result
    depending on the guard's pool), so qdldl keeps the factors. The probe: a fixed SPD matrix (a chain
    with random couplings, n = 200) factorised and solved both ways, every row recomputed by the
    kernels (QDLDL's loops with ``y -= l * x`` fused give 1,722 of its 6,656 entries of L other bits).
    """
    if "qdldl" not in _MATCH:
        _MATCH["qdldl"] = _probe()
    return _MATCH["qdldl"]


def _probe() -> bool:
    import qdldl
    import scipy.sparse as sp

    n, rng = 200, np.random.default_rng(0)
    i = np.concatenate([np.arange(n - 1), rng.integers(0, n, 4 * n)])
    j = np.concatenate([np.arange(1, n), rng.integers(0, n, 4 * n)])
    W = sp.coo_matrix((rng.random(len(i)), (i, j)), shape=(n, n)).tocsc()
    W = W + W.T
    W.setdiag(0)
    A = sp.diags(np.asarray(W.sum(axis=1)).ravel() + rng.random(n)) - W
    U = sp.triu(A, format="csc")
    U.sort_indices()
    solver = qdldl.Solver(U, upper=True)
    # the upper triangle as the "full" matrix: its values are all kept
    ref = LDL.from_qdldl(solver, (np.arange(U.nnz), U.indices, U.indptr), U.data)
    if ref is None:
        return False
    mine = LDL(ref.plan, np.zeros_like(ref.Lx), np.zeros(n), np.zeros(n), np.full(U.nnz, np.nan))
    b = rng.standard_normal((n, 2))
    if not mine.refactorise(U.data):  # every value differs from the NaNs: every row recomputed
        return False
    x = mine.solve(b)
    if x is None:
        return False
    want = np.stack([solver.solve(np.ascontiguousarray(b[:, k])) for k in range(2)], 1)
    same = all(
        np.array_equal(a.view(np.int64), w.view(np.int64)) for a, w in ((mine.Lx, ref.Lx), (mine.D, ref.D), (x, want))
    )
    if not same:
        log.info(
            "pattern solver: the LDL kernels differ from qdldl's bits here (its build fuses "
            "multiply-adds); qdldl factorises"
        )
    return same
