"""Warp CPU kernels of the solver's two sparse products per iteration: scipy's CSR bits in one pass each.

:mod:`.products` launches them. Each output is the sum scipy's ``csr_matvec``
makes (from 0.0, the row's stored entries in their order, ``sum += a * x``),
so the Jacobians and the right-hand side are scipy's bits
(tests/test_pattern_products.py). What is new is that one pass over the
matrices makes what took scipy four:

- :func:`jacobians`: ``Gx u, Gy u, Gx v, Gy v`` from the interleaved (n, 2)
  pattern coordinates (each corner gathered once for both coordinates);
- :func:`add_rhs`: ``rhs[:, 0] += Gxᵀ b0 + Gyᵀ b1`` and ``rhs[:, 1] += Gxᵀ b2 +
  Gyᵀ b3`` in place (numpy's order: the two products' sum, then the add).

Native C++ snippets, as in :mod:`.ldl_kernels` (Warp's kernel language made
such gather loops slower than scipy), built without floating-point
contraction.
"""

from __future__ import annotations

from ...geom.queries import wp  # Warp as the package sets it up (kernel cache folder, log level)

wp.set_module_options({"enable_backward": False, "fuse_fp": False})

Ints = wp.array(dtype=wp.int32)
Reals = wp.array(dtype=wp.float64)

_JACOBIANS = r"""
const int* xp = (const int*)Gx_ptr.data; const int* xi = (const int*)Gx_ind.data; const double* xd = (const double*)Gx_val.data;
const int* yp = (const int*)Gy_ptr.data; const int* yi = (const int*)Gy_ind.data; const double* yd = (const double*)Gy_val.data;
const double* uv = (const double*)U.data;
double* m00 = (double*)M00.data; double* m01 = (double*)M01.data;
double* m10 = (double*)M10.data; double* m11 = (double*)M11.data;
for (int t = 0; t < f; t++) {
    double a = 0.0, c = 0.0;
    for (int j = xp[t]; j < xp[t + 1]; j++) { double g = xd[j]; int k = 2 * xi[j]; a += g * uv[k]; c += g * uv[k + 1]; }
    double b = 0.0, d = 0.0;
    for (int j = yp[t]; j < yp[t + 1]; j++) { double g = yd[j]; int k = 2 * yi[j]; b += g * uv[k]; d += g * uv[k + 1]; }
    m00[t] = a; m01[t] = b; m10[t] = c; m11[t] = d;
}
"""


@wp.func_native(_JACOBIANS)
def _jacobians(
    f: int,
    Gx_ptr: Ints,
    Gx_ind: Ints,
    Gx_val: Reals,
    Gy_ptr: Ints,
    Gy_ind: Ints,
    Gy_val: Reals,
    U: Reals,
    M00: Reals,
    M01: Reals,
    M10: Reals,
    M11: Reals,
): ...


@wp.kernel
def jacobians(
    f: int,
    Gx_ptr: Ints,
    Gx_ind: Ints,
    Gx_val: Reals,
    Gy_ptr: Ints,
    Gy_ind: Ints,
    Gy_val: Reals,
    U: Reals,
    M00: Reals,
    M01: Reals,
    M10: Reals,
    M11: Reals,
):
    """``M00 = Gx u``, ``M01 = Gy u``, ``M10 = Gx v``, ``M11 = Gy v`` (f,) for ``U`` (n, 2 interleaved)."""
    _jacobians(f, Gx_ptr, Gx_ind, Gx_val, Gy_ptr, Gy_ind, Gy_val, U, M00, M01, M10, M11)


_ADD_RHS = r"""
const int* xp = (const int*)X_ptr.data; const int* xi = (const int*)X_ind.data; const double* xd = (const double*)X_val.data;
const int* yp = (const int*)Y_ptr.data; const int* yi = (const int*)Y_ind.data; const double* yd = (const double*)Y_val.data;
const double* b0 = (const double*)B0.data; const double* b1 = (const double*)B1.data;
const double* b2 = (const double*)B2.data; const double* b3 = (const double*)B3.data;
double* r = (double*)R.data;
for (int i = 0; i < n; i++) {
    double p0 = 0.0, p2 = 0.0;
    for (int j = xp[i]; j < xp[i + 1]; j++) { double g = xd[j]; int k = xi[j]; p0 += g * b0[k]; p2 += g * b2[k]; }
    double q1 = 0.0, q3 = 0.0;
    for (int j = yp[i]; j < yp[i + 1]; j++) { double g = yd[j]; int k = yi[j]; q1 += g * b1[k]; q3 += g * b3[k]; }
    r[2 * i] += p0 + q1;
    r[2 * i + 1] += p2 + q3;
}
"""


@wp.func_native(_ADD_RHS)
def _add_rhs(
    n: int,
    X_ptr: Ints,
    X_ind: Ints,
    X_val: Reals,
    Y_ptr: Ints,
    Y_ind: Ints,
    Y_val: Reals,
    B0: Reals,
    B1: Reals,
    B2: Reals,
    B3: Reals,
    R: Reals,
): ...


@wp.kernel
def add_rhs(
    n: int,
    X_ptr: Ints,
    X_ind: Ints,
    X_val: Reals,
    Y_ptr: Ints,
    Y_ind: Ints,
    Y_val: Reals,
    B0: Reals,
    B1: Reals,
    B2: Reals,
    B3: Reals,
    R: Reals,
):
    """``R`` (n, 2 interleaved) ``+= (X B0 + Y B1, X B2 + Y B3)`` for CSR ``X = Gxᵀ``, ``Y = Gyᵀ`` (n, f)."""
    _add_rhs(n, X_ptr, X_ind, X_val, Y_ptr, Y_ind, Y_val, B0, B1, B2, B3, R)
