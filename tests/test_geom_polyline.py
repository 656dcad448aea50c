"""core.geom.polyline: length, cumulative length, point at arc length (one test each)."""

import numpy as np
import pytest

from core.geom.polyline import cumulative_lengths, point_at_length, polyline_length

L_SHAPE = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]])


def test_polyline_length_open_closed_and_degenerate():
    assert polyline_length(L_SHAPE) == pytest.approx(7.0)
    assert polyline_length(L_SHAPE, closed=True) == pytest.approx(12.0)
    assert polyline_length(np.array([[1.0, 2.0, 3.0], [1.0, 2.0, 5.0]])) == pytest.approx(2.0)
    assert polyline_length(L_SHAPE[:1]) == 0.0
    assert polyline_length(L_SHAPE[:1], closed=True) == 0.0


def test_cumulative_lengths():
    np.testing.assert_allclose(cumulative_lengths(L_SHAPE), [0.0, 3.0, 7.0])
    np.testing.assert_allclose(cumulative_lengths(L_SHAPE, closed=True), [0.0, 3.0, 7.0, 12.0])
    np.testing.assert_array_equal(cumulative_lengths(L_SHAPE[:1]), [0.0])


def test_point_at_length_points_edges_tangents_clamped():
    xy, edge, tangent = point_at_length(L_SHAPE, [0.0, 1.5, 3.0, 5.0, 9.0, -1.0])
    np.testing.assert_allclose(xy, [[0, 0], [1.5, 0], [3, 0], [3, 2], [3, 4], [0, 0]])
    np.testing.assert_array_equal(edge, [0, 0, 1, 1, 1, 0])
    np.testing.assert_allclose(tangent, [[1, 0], [1, 0], [0, 1], [0, 1], [0, 1], [1, 0]])
    # a scalar arc length gives one point; a zero-length edge has a zero tangent
    q, e, t = point_at_length(L_SHAPE, 1.0)
    np.testing.assert_allclose(q, [1.0, 0.0])
    assert e == 0 and np.allclose(t, [1.0, 0.0])
    dup = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]])
    q, e, t = point_at_length(dup, 0.0)
    np.testing.assert_allclose(q, [0.0, 0.0])
    assert e == 1 and np.allclose(t, [1.0, 0.0])
