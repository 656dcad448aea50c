"""core.geom.strain: Jacobians, weft/warp scales and shear of affine maps with known answers."""

import numpy as np
import pytest

from core.geom import strain as S


def _grid():
    xs, ys = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 3))
    uv = np.c_[xs.ravel(), ys.ravel()]
    F = []
    for j in range(2):
        for i in range(3):
            a, b, c, d = j * 4 + i, j * 4 + i + 1, (j + 1) * 4 + i + 1, (j + 1) * 4 + i
            F += [(a, b, c), (a, c, d)]
    return uv, np.array(F)


def _lift(uv, A):
    return np.c_[uv @ np.asarray(A, float).T, np.zeros(len(uv))]


def test_weft_is_the_grain_turned_left():
    assert np.allclose(S.weft_of([0.0, 1.0]), [-1.0, 0.0])


def test_jacobians_and_scales_of_an_affine_map():
    uv, F = _grid()
    A = [[0.8, 0.0], [0.0, 1 / 1.1]]
    J = S.jacobians(uv, _lift(uv, A), F)
    assert J.shape == (len(F), 3, 2)
    assert np.allclose(J[:, :2, :], A)
    rw, rg, shear = S.scales(uv, _lift(uv, A), F, [0.0, 2.0])
    assert np.allclose(rw, 1.25) and np.allclose(rg, 1.1) and np.allclose(shear, 0.0)


def test_shear_of_a_sheared_map():
    uv, F = _grid()
    t = np.tan(np.radians(10.0))
    _, _, shear = S.scales(uv, _lift(uv, [[1.0, t], [0.0, 1.0]]), F, [0.0, 1.0])
    assert np.allclose(shear, 10.0)


def test_degenerate_triangle_gives_nan():
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    with np.errstate(invalid="ignore"):
        J = S.jacobians(uv, np.c_[uv, np.zeros(3)], np.array([[0, 1, 2]]))
    assert np.all(np.isnan(J))


def test_gradient_jacobians_and_intrinsic_offsets():
    # gradient operators of the unit right triangle: corners (0,0), (1,0), (0,1)
    G = np.array([[[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]])
    X = np.array([[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 3.0, 0.0]]])
    M = S.gradient_jacobians(X, G)
    assert np.allclose(M[0], [[2.0, 0.5], [0.0, 3.0], [0.0, 0.0]])
    K, lw, lg = S.intrinsic_offsets(X, G)
    assert lw[0] == pytest.approx(2.0) and lg[0] == pytest.approx(np.hypot(0.5, 3.0))
    # K keeps the offsets' lengths and their angle
    assert np.linalg.norm(K[0, :, 0]) == pytest.approx(2.0) and K[0, 0, 1] == 0.0
    assert K[0, :, 0] @ K[0, :, 1] == pytest.approx(M[0, :, 0] @ M[0, :, 1])


def test_scales_of_offsets_match_scales():
    uv, F = _grid()
    A = [[0.8, 0.1], [0.0, 0.9]]
    xyz = _lift(uv, A)
    # pattern = the flattening (identity Jacobian): the scales are those of the body's offsets
    G = np.zeros((len(F), 3, 2))
    for t, f in enumerate(F):
        E = np.stack([uv[f[1]] - uv[f[0]], uv[f[2]] - uv[f[0]]], axis=1)
        inv = np.linalg.inv(E)
        G[t, 1], G[t, 2] = inv[0], inv[1]
        G[t, 0] = -inv[0] - inv[1]
    K, _, _ = S.intrinsic_offsets(xyz[F], G)
    one, zero = np.ones(len(F)), np.zeros(len(F))
    rw, rg = S.scales_of_offsets([one, zero, zero, one], S.components(K))
    rw2, rg2, _ = S.scales(uv, xyz, F, [0.0, 1.0])
    assert np.allclose(rw, rw2) and np.allclose(rg, rg2)
