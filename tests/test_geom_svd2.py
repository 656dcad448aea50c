"""core.geom.svd2: the closed-form signed 2 x 2 SVD against numpy's."""

import numpy as np

from core.geom.svd2 import clamp_singular_values_below, compose2, signed_svd2


def _stack(n=500, seed=0):
    A = np.random.default_rng(seed).normal(size=(n, 2, 2))
    A[:5] = [[[1, 0], [0, 1]], [[2, 0], [0, 0.5]], [[0, 1], [1, 0]], [[1e-9, 0], [0, 1]], [[0, 0], [0, 0]]]
    return A, [A[:, 0, 0], A[:, 0, 1], A[:, 1, 0], A[:, 1, 1]]


def test_singular_values_match_numpy_with_the_sign_of_the_determinant():
    A, c = _stack()
    s1, s2, phi, theta = signed_svd2(c)
    S = np.linalg.svd(A, compute_uv=False)
    assert np.allclose(s1, S[:, 0], atol=1e-12)
    assert np.allclose(np.abs(s2), S[:, 1], atol=1e-12)
    det = np.linalg.det(A)
    clear = np.abs(det) > 1e-9
    assert np.array_equal(s2[clear] < 0, det[clear] < 0)
    out = compose2(s1, s2, phi, theta)
    B = np.stack([np.stack(out[:2], -1), np.stack(out[2:], -1)], -2)
    assert np.allclose(B, A, atol=1e-12)


def test_clamping_opens_small_singular_values_and_unfolds_reflections_only():
    A, c = _stack()
    out = clamp_singular_values_below(c, 0.7)
    B = np.stack([np.stack(out[:2], -1), np.stack(out[2:], -1)], -2)
    S = np.linalg.svd(B, compute_uv=False)
    assert np.all(S[:, 1] >= 0.7 - 1e-12)
    assert np.all(np.linalg.det(B) > 0)
    # matrices already open enough are unchanged
    open_ = np.all(np.linalg.svd(A, compute_uv=False) >= 0.7, axis=1) & (np.linalg.det(A) > 0)
    assert open_.sum() > 10
    assert np.allclose(B[open_], A[open_], atol=1e-12)
    # the reference answer: numpy's signed SVD clamped as the collapse guard did
    U, S0, Vt = np.linalg.svd(A)
    neg = np.linalg.det(U) * np.linalg.det(Vt) < 0
    U[neg, :, 1] *= -1.0
    S0[neg, 1] *= -1.0
    ref = (U * np.maximum(S0, 0.7)[:, None, :]) @ Vt
    distinct = np.abs(S0[:, 0] - np.abs(S0[:, 1])) > 1e-6
    assert np.allclose(B[distinct], ref[distinct], atol=1e-9)


def test_hypot_is_numpys_to_an_ulp_over_the_solvers_range():
    from core.geom.svd2 import hypot

    rng = np.random.default_rng(3)
    # Jacobian entries, scales and metre offsets: 1e-9 .. 1e3, either sign, exact zeros included
    x = rng.choice([-1.0, 1.0], 4000) * 10.0 ** rng.uniform(-9, 3, 4000)
    y = rng.choice([-1.0, 1.0], 4000) * 10.0 ** rng.uniform(-9, 3, 4000)
    x[:3], y[:3] = [0.0, 3.0, 0.0], [0.0, 4.0, -2.0]
    h, ref = hypot(x, y), np.hypot(x, y)
    assert np.array_equal(h[:3], [0.0, 5.0, 2.0])
    assert np.all(np.abs(h - ref) <= np.spacing(ref))
    assert np.isnan(hypot(np.array([np.nan]), np.array([1.0]))[0])
    assert np.isinf(hypot(np.array([np.inf]), np.array([1.0]))[0])
