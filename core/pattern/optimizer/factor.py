"""Sparse LDLᵀ factorisation of the pattern's system matrix, refactorisable on the same pattern.

The local-global solve factorises one symmetric positive definite matrix and
back-substitutes it once per iteration. The collapse guard stiffens a few
triangles of it, which changes values but never the sparsity pattern (a
triangle's terms already sit in the matrix). :class:`SymmetricFactor` keeps
the symbolic analysis (AMD ordering, elimination tree) of QDLDL and redoes only
the numeric factorisation for new values, a fraction of the cost of a new
(SuperLU) factorisation; its back-substitution of both pattern coordinates is
cheaper than SuperLU's too.
Where the solver's Warp kernels run (:func:`.accel.compiled.enabled`) with qdldl's
bits (:func:`.accel.ldl.matches_qdldl`), qdldl's factors go to an :class:`.accel.ldl.LDL`,
which refactorises only the rows of L a change of values reaches and solves
both coordinates in one pass, with qdldl's bits. Measured timings:
``benchmarks/results/pattern_kernels_history.md``.
"""

from __future__ import annotations

import numpy as np
import qdldl
import scipy.sparse as sp

from ...errors import PatternError
from ..accel import compiled


def _qdldl(upper: sp.csc_matrix) -> "qdldl.Solver":
    """qdldl-python's factorisation of ``upper``; a matrix it cannot factorise (a zero pivot: the
    solve's terms gave it no positive definite system) is the pattern's refusal in one line, on both
    solver paths, not a traceback."""
    try:
        return qdldl.Solver(upper, upper=True)
    except RuntimeError:
        raise PatternError(
            "the pattern's linear system has a zero pivot (not positive definite): the solve "
            "cannot go on; nothing written"
        ) from None


class SymmetricFactor:
    """LDLᵀ of a sparse symmetric positive definite matrix with a fixed sparsity pattern.

    Parameters
    ----------
    A : (n, n) sparse symmetric positive definite matrix (any scipy format).

    Attributes
    ----------
    matrix : (n, n) ``scipy.sparse.csc_matrix``, canonical (sorted, no duplicates), read-only data:
        the factorised matrix; :meth:`with_values` takes new values on its pattern.
    """

    def __init__(self, A, like: "SymmetricFactor | None" = None):
        A = sp.csc_matrix(A, dtype=float, copy=True)
        A.sum_duplicates()
        A.sort_indices()
        A.data.flags.writeable = False
        self.matrix = A
        self._qdldl = self._ldl = None
        if like is not None:
            # a factorisation of the same pattern (with_values): its symbolic analysis, and where the
            # kernels run its factors, refactorised for these values
            self._cols, self._upper = like._cols, like._upper
            if like._ldl is not None:
                ldl = like._ldl.copy()
                if _refactorised(ldl, A.data):
                    self._ldl = ldl
                    return
            self._qdldl = _qdldl(self._upper_matrix(A.data))
            return
        # QDLDL factorises the upper triangle: handed over directly, an update skips its own
        # extraction of it
        n = A.shape[0]
        #: (nnz,) the column of each stored entry
        self._cols = col = np.repeat(np.arange(n, dtype=np.int64), np.diff(A.indptr))
        keep = np.flatnonzero(A.indices <= col)
        self._upper = (
            keep,
            A.indices[keep],
            np.concatenate([[0], np.cumsum(np.bincount(col[keep], minlength=n))]).astype(A.indptr.dtype),
        )
        self._qdldl = _qdldl(self._upper_matrix(A.data))
        if compiled.enabled():
            from ..accel.ldl import LDL, matches_qdldl

            self._ldl = LDL.from_qdldl(self._qdldl, self._upper, A.data) if matches_qdldl() else None
            if self._ldl is not None:
                self._qdldl = None  # its factors are the LDL's now

    def _qdldl_solver(self):
        """qdldl-python's factorisation of the matrix (made again where the kernels gave up: the same bits)."""
        self._ldl = None
        if self._qdldl is None:
            self._qdldl = _qdldl(self._upper_matrix(self.matrix.data))
        return self._qdldl

    def _upper_matrix(self, data: np.ndarray) -> sp.csc_matrix:
        """The upper triangle (diagonal included) of the matrix of this pattern with values ``data``."""
        keep, rows, ptr = self._upper
        return sp.csc_matrix((data[keep], rows, ptr), shape=self.matrix.shape)

    @property
    def n(self) -> int:
        return self.matrix.shape[0]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """``A⁻¹ rhs`` for rhs (n,) or (n, k): each column back-substituted on its own (the LDL's
        kernel does two at once, each with its own operations)."""
        rhs = np.asarray(rhs, float)
        if self._ldl is not None:
            out = self._ldl.solve(rhs)
            if out is not None:
                return out
        solver = self._qdldl_solver()
        if rhs.ndim == 1:
            return solver.solve(rhs)
        out = np.empty_like(rhs)
        for j in range(rhs.shape[1]):
            out[:, j] = solver.solve(np.ascontiguousarray(rhs[:, j]))
        return out

    __call__ = solve

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Indices into ``matrix.data`` of entries (rows[i], cols[i]) (any equal shapes, int).

        Raises ValueError if an entry is not in the pattern.
        """
        A = self.matrix
        n = np.int64(self.n)
        keys = self._cols * n + A.indices.astype(np.int64)  # ascending: CSC sorted by column, then row
        want = np.asarray(cols, np.int64) * n + np.asarray(rows, np.int64)
        pos = np.searchsorted(keys, want)
        ok = (pos < len(keys)) & (keys[np.minimum(pos, len(keys) - 1)] == want)
        if not np.all(ok):
            raise ValueError("entry outside the factorised matrix's sparsity pattern")
        return pos

    def with_values(self, data: np.ndarray, reuse: "SymmetricFactor | None" = None) -> "SymmetricFactor":
        """The factorisation of the matrix with this pattern and values ``data`` (nnz,).

        ``reuse``: a factorisation of the same pattern made by this method
        earlier whose symbolic analysis is taken over (it is refactorised in
        place and returned); ``self`` is never changed.
        """
        data = np.asarray(data, float)
        if data.shape != self.matrix.data.shape:
            raise ValueError(f"expected {self.matrix.data.shape[0]} values, got {data.shape}")
        B = sp.csc_matrix((data, self.matrix.indices, self.matrix.indptr), shape=self.matrix.shape)
        if reuse is None or reuse is self:
            return SymmetricFactor(B, like=self)
        if not (
            np.array_equal(reuse.matrix.indptr, self.matrix.indptr)
            and np.array_equal(reuse.matrix.indices, self.matrix.indices)
        ):
            raise ValueError("reuse: a factorisation of another sparsity pattern")
        B.data.flags.writeable = False
        if reuse._ldl is None or not _refactorised(reuse._ldl, B.data):
            reuse._qdldl_solver().update(self._upper_matrix(data), upper=True)
        reuse.matrix = B
        return reuse


def _refactorised(ldl, data: np.ndarray) -> bool:
    """The kernels' refactorisation of ``ldl`` for ``data``; False where they gave up or met a zero pivot:
    the caller then takes qdldl's, as the numpy path does (its update of a matrix with a zero pivot
    does not raise, so both paths go on alike and end in the same figures or the same refusal)."""
    try:
        return ldl.refactorise(data)
    except ValueError:
        return False
