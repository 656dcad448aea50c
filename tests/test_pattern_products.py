"""core.pattern.accel.products: the solver's Jacobians and right-hand side products in kernels, scipy's bits."""

import pickle
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import scipy.sparse as sp
from same_bits import assert_same, assert_same_floats

from core.pattern.accel import compiled
from core.pattern.accel.products import GradientProducts


@pytest.fixture
def kernels_on(monkeypatch):
    assert compiled.load(), "Warp kernels failed to load (see the log's warning)"
    monkeypatch.setitem(compiled._state, "forced", True)


@pytest.fixture(scope="module")
def tube():
    from synthetic_pattern import two_panels

    from core.pattern.solve import PatternSolver

    cut, body = two_panels(ease=(1.2, 1.6), bulge=0.2)
    return PatternSolver(cut, body)


def _random_operators(f, n, seed):
    """Gradient-like operators: 3 corners a triangle, the columns in random order within a row (scipy keeps
    a CSR row's stored order, so the kernels must too), some values exactly 0 or negative zero."""
    rng = np.random.default_rng(seed)
    cols = np.concatenate([rng.choice(n, 3, replace=False) for _ in range(f)])
    vals = rng.standard_normal((2, 3 * f))
    vals[0, ::7] = 0.0
    vals[1, ::11] = -0.0
    Gx = sp.csr_matrix((vals[0], cols, np.arange(0, 3 * f + 1, 3)), shape=(f, n))
    Gy = sp.csr_matrix((vals[1], cols, np.arange(0, 3 * f + 1, 3)), shape=(f, n))
    return Gx, Gy, Gx.T.tocsr(), Gy.T.tocsr()


def _scipy(P, U, B, rhs):
    u, v = np.ascontiguousarray(U[:, 0]), np.ascontiguousarray(U[:, 1])
    J = [P.Gx @ u, P.Gy @ u, P.Gx @ v, P.Gy @ v]
    r = rhs.copy()
    r[:, 0] += P.GxT @ B[0] + P.GyT @ B[1]
    r[:, 1] += P.GxT @ B[2] + P.GyT @ B[3]
    return J, r


@pytest.mark.same_bits
@pytest.mark.parametrize("f, n", [(1, 3), (7, 5), (40, 30), (500, 260)])
def test_same_bits_as_scipy(kernels_on, f, n):
    P = GradientProducts(*_random_operators(f, n, seed=f))
    rng = np.random.default_rng(f + 1)
    U = rng.standard_normal((n, 2))
    U[0, 1] = -0.0
    B = [rng.standard_normal(f) for _ in range(4)]
    rhs = rng.standard_normal((n, 2))
    J_ref, r_ref = _scipy(P, U, B, rhs)
    for _ in range(2):  # recorded on the first call, rebound on the second
        J = P.jacobians(U)
        r = rhs.copy()
        P.add_rhs(r, B)
        assert_same(list(J), list(J_ref))
        assert all(j.flags.c_contiguous and j.shape == (f,) for j in J)
        assert_same_floats(r, r_ref)
    # a new call's arrays are new: the last call's are left as they were
    J2 = P.jacobians(U * 2.0)
    assert_same(list(J), list(J_ref))
    assert not np.array_equal(J2[0], J[0]) or not np.any(J[0])


@pytest.mark.same_bits
def test_the_solvers_own_operators(kernels_on, tube):
    P = tube._products
    rng = np.random.default_rng(3)
    U = tube.uv0 + rng.normal(0, 1e-3, tube.uv0.shape)
    B = [rng.standard_normal(P.f) for _ in range(4)]
    rhs = rng.standard_normal((P.n, 2))
    J_ref, r_ref = _scipy(P, U, B, rhs)
    r = rhs.copy()
    P.add_rhs(r, B)
    assert_same(list(P.jacobians(U)), list(J_ref))
    assert_same_floats(r, r_ref)


@pytest.mark.same_bits
@pytest.mark.parametrize("kind", ["fortran", "float32", "strided", "shape"])
def test_arrays_the_kernels_do_not_take_go_to_scipy(kernels_on, kind):
    P = GradientProducts(*_random_operators(40, 30, seed=5))
    rng = np.random.default_rng(6)
    U = rng.standard_normal((30, 2))
    B = [rng.standard_normal(40) for _ in range(4)]
    rhs = rng.standard_normal((30, 2))
    J_ref, r_ref = _scipy(P, U, B, rhs)
    if kind == "fortran":
        U2, B2, r = np.asfortranarray(U), B, np.asfortranarray(rhs)
    elif kind == "float32":
        U2, B2, r = U.astype(np.float32), [b.astype(np.float32) for b in B], rhs.copy()
        J_ref, r_ref = _scipy(P, U2, B2, rhs)
    elif kind == "strided":
        U2 = np.repeat(U, 2, axis=0)[::2]
        B2 = [np.repeat(b, 2)[::2] for b in B]
        r = rhs.copy()
    else:
        with pytest.raises(ValueError):
            P.jacobians(rng.standard_normal((29, 2)))
        return
    got = P.jacobians(U2)
    P.add_rhs(r, B2)
    assert_same(list(got), list(J_ref))
    assert_same_floats(r, r_ref)
    assert compiled.enabled()


@pytest.mark.same_bits
def test_threads_and_pickle(kernels_on):
    P = GradientProducts(*_random_operators(300, 200, seed=8))
    rng = np.random.default_rng(9)
    Us = [rng.standard_normal((200, 2)) for _ in range(8)]
    ref = [
        _scipy(
            P,
            U,
            [U[:150, 0].repeat(2), U[:150, 1].repeat(2), U[:150, 0].repeat(2), U[:150, 1].repeat(2)],
            np.zeros((200, 2)),
        )[0]
        for U in Us
    ]
    with ThreadPoolExecutor(4) as pool:
        got = list(pool.map(P.jacobians, Us))
    for a, b in zip(got, ref):
        assert_same(list(a), list(b))
    Q = pickle.loads(pickle.dumps(P))
    assert_same(list(Q.jacobians(Us[0])), list(ref[0]))


@pytest.mark.same_bits
def test_a_failed_launch_leaves_scipy(kernels_on, monkeypatch, caplog):
    P = GradientProducts(*_random_operators(40, 30, seed=10))
    U = np.random.default_rng(11).standard_normal((30, 2))
    J_ref, _ = _scipy(P, U, [np.zeros(40)] * 4, np.zeros((30, 2)))

    def broken(*args):
        raise RuntimeError("no launch")

    monkeypatch.setattr(compiled, "native", broken)
    monkeypatch.setitem(compiled._state, "ready", True)
    assert_same(list(P.jacobians(U)), list(J_ref))
    assert caplog.text.count("using numpy") == 1
    assert not compiled.enabled()


@pytest.mark.same_bits
def test_kernels_off_is_scipy(monkeypatch):
    monkeypatch.setitem(compiled._state, "forced", False)
    P = GradientProducts(*_random_operators(40, 30, seed=12))
    U = np.random.default_rng(13).standard_normal((30, 2))
    J_ref, _ = _scipy(P, U, [np.zeros(40)] * 4, np.zeros((30, 2)))
    assert_same(list(P.jacobians(U)), list(J_ref))
    assert not getattr(P._local, "launches", None)
