"""The solver's per-iteration products with its gradient operators (:class:`GradientProducts`), scipy's bits.

Every local-global iteration takes the pattern's Jacobians ``Gx u, Gy u,
Gx v, Gy v`` and adds ``Gxᵀ b + Gyᵀ b'`` to both columns of the right-hand
side: eight scipy CSR products over every triangle of the pattern. Where the
solver's Warp kernels run (:func:`.compiled.enabled`) two kernels
(:mod:`.sparse_kernels`) make them in one pass each, instead of eight scipy
calls, with scipy's operations in scipy's order, so the bits are the same;
else, or for arguments they do not take, scipy does. Measured timings:
``benchmarks/results/pattern_kernels_history.md``.
"""

from __future__ import annotations

from typing import List

import numpy as np
import scipy.sparse as sp

from . import compiled

_F64 = np.dtype(np.float64)


def _csr(M: sp.csr_matrix) -> tuple:
    """(indptr, indices) as int32 and the values as float64, each contiguous (a kernel's CSR arguments)."""
    return (
        np.ascontiguousarray(M.indptr, np.int32),
        np.ascontiguousarray(M.indices, np.int32),
        np.ascontiguousarray(M.data, np.float64),
    )


def _takes(a, shape: tuple) -> bool:
    """Whether ``a`` is what the kernels read: an aligned, C-contiguous, native float64 array of ``shape``
    (a dtype equal to native float64 is native)."""
    return type(a) is np.ndarray and a.shape == shape and a.dtype == _F64 and a.flags.c_contiguous and a.flags.aligned


class GradientProducts(compiled.PerThread):
    """Products with a solver's gradient operators.

    Parameters
    ----------
    Gx, Gy : (f, n) ``scipy.sparse.csr_matrix``, d/dx and d/dy of a per-vertex field on each triangle
        (1 / m); GxT, GyT : their transposes as CSR (n, f).

    Keeps per thread the kernels' recorded launches (their argument structs);
    no result depends on them.
    """

    def __init__(self, Gx: sp.csr_matrix, Gy: sp.csr_matrix, GxT: sp.csr_matrix, GyT: sp.csr_matrix):
        self.Gx, self.Gy, self.GxT, self.GyT = Gx, Gy, GxT, GyT
        self.f, self.n = Gx.shape
        self._g = _csr(Gx) + _csr(Gy)
        self._gt = _csr(GxT) + _csr(GyT)
        # the kernels index with int32 (the interleaved coordinates at 2 n + 1): larger operators stay scipy's
        self._fits = max(Gx.nnz, Gy.nnz, GxT.nnz, GyT.nnz, 2 * self.n + 2, self.f + 1) <= np.iinfo(np.int32).max
        super().__init__()

    def _run(self, name: str, fixed: tuple, moving: list) -> bool:
        """Kernel ``name`` on ``fixed`` (the CSR arrays, first) and ``moving`` (rebound every call);
        False where it failed (the kernels are off then)."""
        launches = getattr(self._local, "launches", None)
        if launches is None:
            launches = self._local.launches = {}
        try:
            launch = launches.get(name)
            if launch is None:
                from . import sparse_kernels as K

                # recorded on 1-D views (the kernels' arrays); runs it once
                launches[name] = compiled.native(getattr(K, name), list(fixed) + [a.reshape(-1) for a in moving])
                return True
            first = len(fixed)
            for j, a in enumerate(moving):
                launch.bind(first + j, a, compiled.address(a))
            launch()
            return True
        except Exception as exc:  # noqa: BLE001 - a launch Warp refuses leaves scipy, the same bits
            compiled.give_up("launching " + name, exc)
            return False

    def jacobians(self, U: np.ndarray) -> List[np.ndarray]:
        """``[Gx u, Gy u, Gx v, Gy v]`` (4 new contiguous (f,) arrays) of ``U`` (n, 2)."""
        if self.f and self._fits and _takes(U, (self.n, 2)) and compiled.enabled():
            out = np.empty((4, self.f))
            if self._run("jacobians", (self.f,) + self._g, [U, *out]):
                return list(out)
        u, v = np.ascontiguousarray(U[:, 0]), np.ascontiguousarray(U[:, 1])
        return [self.Gx @ u, self.Gy @ u, self.Gx @ v, self.Gy @ v]

    def add_rhs(self, rhs: np.ndarray, B: list) -> None:
        """``rhs[:, 0] += Gxᵀ B[0] + Gyᵀ B[1]``, ``rhs[:, 1] += Gxᵀ B[2] + Gyᵀ B[3]`` in place (rhs (n, 2),
        B four (f,) arrays)."""
        if (
            self.n
            and self._fits
            and _takes(rhs, (self.n, 2))
            and all(_takes(b, (self.f,)) for b in B)
            and compiled.enabled()
        ):
            if self._run("add_rhs", (self.n,) + self._gt, [*B, rhs]):
                return
        rhs[:, 0] += self.GxT @ B[0] + self.GyT @ B[1]
        rhs[:, 1] += self.GxT @ B[2] + self.GyT @ B[3]
