"""core.pattern.optimizer.factor: LDL^T of the system matrix and its same-pattern refactorisation."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from core.pattern.optimizer.factor import SymmetricFactor


def _laplacian(n=60, seed=0):
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n, 4 * n)
    j = rng.integers(0, n, 4 * n)
    w = rng.random(4 * n)
    W = sp.coo_matrix((w, (i, j)), shape=(n, n)).tocsc()
    W = W + W.T
    L = sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W
    return (L + 1e-2 * sp.eye(n)).tocsc()


def test_solve_matches_a_direct_solve_for_one_and_two_columns():
    A = _laplacian()
    f = SymmetricFactor(A)
    b = np.random.default_rng(1).random((A.shape[0], 2))
    x = f(b)
    assert x.shape == b.shape
    assert np.allclose(x, np.stack([spsolve(A, b[:, 0]), spsolve(A, b[:, 1])], 1), rtol=1e-9, atol=1e-10)
    assert np.allclose(f.solve(b[:, 0]), x[:, 0])


def test_with_values_refactorises_without_touching_the_original():
    A = _laplacian()
    f = SymmetricFactor(A)
    b = np.random.default_rng(2).random(A.shape[0])
    x0 = f.solve(b)
    # stiffen the diagonal: same pattern, new values
    d = f.positions(np.arange(A.shape[0]), np.arange(A.shape[0]))
    data = f.matrix.data.copy()
    data[d] *= 3.0
    g = f.with_values(data)
    B = sp.csc_matrix((data, f.matrix.indices, f.matrix.indptr), shape=A.shape)
    assert np.allclose(g.solve(b), spsolve(B, b), rtol=1e-9, atol=1e-10)
    # refactorised in place on the second factorisation's symbolic analysis
    data2 = data.copy()
    data2[d] *= 2.0
    h = f.with_values(data2, reuse=g)
    assert h is g
    B2 = sp.csc_matrix((data2, f.matrix.indices, f.matrix.indptr), shape=A.shape)
    assert np.allclose(h.solve(b), spsolve(B2, b), rtol=1e-9, atol=1e-10)
    # the shared factorisation still solves its own matrix
    assert np.array_equal(f.solve(b), x0)


def test_positions_refuse_entries_outside_the_pattern():
    A = sp.diags([2.0, 2.0, 2.0]).tocsc()
    f = SymmetricFactor(A)
    assert list(f.positions(np.array([0, 2]), np.array([0, 2]))) == [0, 2]
    with pytest.raises(ValueError, match="sparsity pattern"):
        f.positions(np.array([0]), np.array([1]))
    with pytest.raises(ValueError, match="expected 3 values"):
        f.with_values(np.ones(4))
