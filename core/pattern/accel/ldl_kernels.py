"""Warp CPU kernels of the system matrix's LDLᵀ: QDLDL's loops, row by row, and a two-column solve.

:mod:`.ldl` launches them. The loops are QDLDL's (``QDLDL_factor``,
``QDLDL_solve``; github.com/osqp/qdldl, Apache-2.0, Goulart, Stellato,
Banjac and the OSQP developers) on the same permuted matrix, with the same
operations in the same order, so the factors and the solutions are QDLDL's
bits (tests/test_pattern_ldl.py compares them with qdldl-python's). What is
new is what they skip:

- :func:`ldl_rows` recomputes only the rows of L a change of values reaches
  (the changed columns and their elimination-tree ancestors); every other
  row would be computed from the same inputs into the same bits;
- :func:`ldl_solve2` back-substitutes both pattern coordinates in one pass
  over L (each column's operations are QDLDL's for that column alone).

They are native C++ snippets (``wp.func_native``) because Warp's kernel
language made these scalar loops 2.5x slower than QDLDL's C (its ranges and
array accessors stop clang's loop optimisations); the module is built
without floating-point contraction, as :mod:`.kernels` is, so no product and
difference become a fused multiply-add.
"""

from __future__ import annotations

from ...geom.queries import wp  # Warp as the package sets it up (kernel cache folder, log level)

wp.set_module_options({"enable_backward": False, "fuse_fp": False})

Ints = wp.array(dtype=wp.int32)
Reals = wp.array(dtype=wp.float64)

_PLAN = r"""
const int* ap = (const int*)Ap.data; const int* ai = (const int*)Ai.data; const int* et = (const int*)etree.data;
const int* lp = (const int*)Lp.data; const int* rp = (const int*)rowptr.data;
int* sc = (int*)seq_c.data; int* ss = (int*)seq_slot.data; int* marks = (int*)work.data;
int* elim = marks + n; int* yidx = marks + 2 * n; int* next_space = marks + 3 * n;
for (int i = 0; i < n; i++) { next_space[i] = lp[i]; marks[i] = 0; }
for (int k = 1; k < n; k++) {
    /* QDLDL_factor's first loop: the columns of row k's reach, in its order */
    int nnz_y = 0;
    for (int p = ap[k]; p < ap[k + 1]; p++) {
        int b = ai[p];
        if (b == k || marks[b]) continue;
        marks[b] = 1;
        elim[0] = b;
        int ne = 1;
        int nxt = et[b];
        while (nxt != -1 && nxt < k) {
            if (marks[nxt]) break;
            marks[nxt] = 1;
            elim[ne++] = nxt;
            nxt = et[nxt];
        }
        while (ne) yidx[nnz_y++] = elim[--ne];
    }
    /* its second loop's order (last found first) and the slot of each entry L[k, c] */
    int s = rp[k];
    for (int i = nnz_y - 1; i >= 0; i--, s++) {
        int c = yidx[i];
        sc[s] = c;
        ss[s] = next_space[c]++;
        marks[c] = 0;
    }
}
"""


@wp.func_native(_PLAN)
def _plan(n: int, Ap: Ints, Ai: Ints, etree: Ints, Lp: Ints, rowptr: Ints, seq_c: Ints, seq_slot: Ints, work: Ints): ...


@wp.kernel
def ldl_plan(n: int, Ap: Ints, Ai: Ints, etree: Ints, Lp: Ints, rowptr: Ints, seq_c: Ints, seq_slot: Ints, work: Ints):
    """Row k's entries of L in QDLDL's order: ``seq_c[rowptr[k]:rowptr[k+1]]`` their columns,
    ``seq_slot`` their places in ``Lx`` (``work``: 4 n scratch)."""
    _plan(n, Ap, Ai, etree, Lp, rowptr, seq_c, seq_slot, work)


_ROWS = r"""
const int* ap = (const int*)Ap.data; const int* ai = (const int*)Ai.data; const double* ax = (const double*)Ax.data;
const int* et = (const int*)etree.data; const int* rp = (const int*)rowptr.data;
const int* sc = (const int*)seq_c.data; const int* ss = (const int*)seq_slot.data;
const int* lp = (const int*)Lp.data; const int* li = (const int*)Li.data;
double* lx = (double*)Lx.data; double* d = (double*)D.data; double* dinv = (double*)Dinv.data;
double* yv = (double*)y.data; int* todo = (int*)mark.data;
int failed = 0;
for (int k = 0; k < n; k++) {
    if (!todo[k]) continue;
    todo[k] = 0;
    /* a row recomputed changes its ancestors' rows (they read it): they are later rows */
    if (et[k] != -1) todo[et[k]] = 1;
    double dk = 0.0;
    for (int p = ap[k]; p < ap[k + 1]; p++) {
        int b = ai[p];
        if (b == k) dk = ax[p]; else yv[b] = ax[p];
    }
    for (int s = rp[k]; s < rp[k + 1]; s++) {
        int c = sc[s];
        int slot = ss[s];
        double yc = yv[c];
        for (int j = lp[c]; j < slot; j++) yv[li[j]] -= lx[j] * yc;
        double l = yc * dinv[c];
        lx[slot] = l;
        dk -= yc * l;
        yv[c] = 0.0;
    }
    d[k] = dk;
    if (dk == 0.0) failed = 1;
    dinv[k] = 1 / dk;
}
return failed;
"""


@wp.func_native(_ROWS)
def _rows(
    n: int,
    mark: Ints,
    Ap: Ints,
    Ai: Ints,
    Ax: Reals,
    etree: Ints,
    rowptr: Ints,
    seq_c: Ints,
    seq_slot: Ints,
    Lp: Ints,
    Li: Ints,
    Lx: Reals,
    D: Reals,
    Dinv: Reals,
    y: Reals,
) -> int: ...


@wp.kernel
def ldl_rows(
    n: int,
    mark: Ints,
    Ap: Ints,
    Ai: Ints,
    Ax: Reals,
    etree: Ints,
    rowptr: Ints,
    seq_c: Ints,
    seq_slot: Ints,
    Lp: Ints,
    Li: Ints,
    Lx: Reals,
    D: Reals,
    Dinv: Reals,
    y: Reals,
    failed: Ints,
):
    """Rows ``k`` of L, D and 1 / D where ``mark[k]`` and their ancestors' (``mark`` is zero after;
    ``y``: n zeros, zeros after; ``failed[0]`` 1 where a pivot is 0)."""
    failed[0] = _rows(n, mark, Ap, Ai, Ax, etree, rowptr, seq_c, seq_slot, Lp, Li, Lx, D, Dinv, y)


_SOLVE = r"""
const int* pp = (const int*)P.data; const int* lp = (const int*)Lp.data; const int* li = (const int*)Li.data;
const double* lx = (const double*)Lx.data; const double* dinv = (const double*)Dinv.data;
const double* bb = (const double*)b.data; double* w = (double*)work.data; double* xx = (double*)x.data;
for (int i = 0; i < n; i++) { w[2 * i] = bb[2 * pp[i]]; w[2 * i + 1] = bb[2 * pp[i] + 1]; }
for (int i = 0; i < n; i++) {
    double v0 = w[2 * i], v1 = w[2 * i + 1];
    for (int j = lp[i]; j < lp[i + 1]; j++) {
        int r = li[j];
        double l = lx[j];
        w[2 * r] -= l * v0;
        w[2 * r + 1] -= l * v1;
    }
}
for (int i = 0; i < n; i++) { w[2 * i] *= dinv[i]; w[2 * i + 1] *= dinv[i]; }
for (int i = n - 1; i >= 0; i--) {
    double v0 = w[2 * i], v1 = w[2 * i + 1];
    for (int j = lp[i]; j < lp[i + 1]; j++) {
        int r = li[j];
        double l = lx[j];
        v0 -= l * w[2 * r];
        v1 -= l * w[2 * r + 1];
    }
    w[2 * i] = v0;
    w[2 * i + 1] = v1;
}
for (int i = 0; i < n; i++) { xx[2 * pp[i]] = w[2 * i]; xx[2 * pp[i] + 1] = w[2 * i + 1]; }
"""


@wp.func_native(_SOLVE)
def _solve(n: int, P: Ints, Lp: Ints, Li: Ints, Lx: Reals, Dinv: Reals, b: Reals, work: Reals, x: Reals): ...


@wp.kernel
def ldl_solve2(n: int, P: Ints, Lp: Ints, Li: Ints, Lx: Reals, Dinv: Reals, b: Reals, work: Reals, x: Reals):
    """``x`` (n, 2 interleaved) = A⁻¹ ``b`` (n, 2 interleaved) from A's LDLᵀ (``work``: 2 n scratch)."""
    _solve(n, P, Lp, Li, Lx, Dinv, b, work, x)
