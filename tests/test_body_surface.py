"""core.body.surface: surface points from a face hit and from the closest point."""

import numpy as np
import pytest

from core.body.surface import barycentric, closest_surface_point, surface_point_at

V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]])
F = np.array([[0, 1, 2], [1, 3, 2]])


def test_barycentric_inside_and_clipped():
    assert np.allclose(barycentric(V[F[0]], [0.25, 0.25, 0.0]), [0.5, 0.25, 0.25])
    b = barycentric(V[F[0]], [0.6, 0.6, 0.0])  # past the hypotenuse: clipped onto it
    assert b.min() >= 0 and b.sum() == pytest.approx(1.0) and b[0] == 0.0


def test_surface_point_at_a_hit():
    sp = surface_point_at(V, F, 1, np.array([0.75, 0.75, 1e-9]))
    assert sp.triangle == 1 and sum(sp.bary) == pytest.approx(1.0)
    assert np.allclose(sp.position(V, F), [0.75, 0.75, 0.0])
    assert all(isinstance(b, float) for b in sp.bary)


def test_closest_surface_point():
    sp = closest_surface_point(V, F, [0.2, 0.3, 0.5])
    assert sp.triangle == 0 and np.allclose(sp.position(V, F), [0.2, 0.3, 0.0])
    corner = closest_surface_point(V, F, [2.0, 2.0, 0.0])
    assert np.allclose(corner.position(V, F), [1.0, 1.0, 0.0])
