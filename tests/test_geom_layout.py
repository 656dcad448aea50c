"""core.geom.layout: grain frame, interior point, grain line, arrow heads, sheet layout (one test each)."""

import math

import numpy as np
import pytest

from core.geom.layout import grain_arrows, grain_line, grain_rotation, interior_point, layout_pieces


def _grid(nx, ny, w, h):
    """A w x h rectangle triangulated on an nx x ny grid: uv, faces, boundary loop (ccw)."""
    x, y = np.meshgrid(np.linspace(0, w, nx), np.linspace(0, h, ny))
    uv = np.column_stack([x.ravel(), y.ravel()])
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    loop = np.concatenate([idx[0, :], idx[1:, -1], idx[-1, -2::-1], idx[-2:0:-1, 0]])
    return uv, faces, loop


def test_grain_rotation_turns_the_grain_to_plus_y():
    for g in ([1.0, 0.0], [0.3, -2.0], [-1.0, 1.0]):
        rot = grain_rotation(np.array(g))
        np.testing.assert_allclose(rot @ rot.T, np.eye(2), atol=1e-15)
        np.testing.assert_allclose(rot @ np.array(g) / np.linalg.norm(g), [0.0, 1.0], atol=1e-15)
    np.testing.assert_array_equal(grain_rotation(np.array([0.0, 1.0])), np.eye(2))


def test_interior_point_lies_inside_a_concave_piece():
    # an L shape: its area centroid is near the inner corner; the point returned is a triangle centroid inside
    uv = np.array([[0, 0], [1, 0], [1, 0.2], [0.2, 0.2], [0.2, 1], [0, 1]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
    c = interior_point(uv, faces)
    assert any(np.allclose(c, uv[f].mean(0)) for f in faces)
    assert (c[0] < 0.2) or (c[1] < 0.2)


def test_grain_line_spans_70_percent_of_the_chord_along_the_grain():
    uv, faces, loop = _grid(5, 9, 0.4, 0.8)
    start, end = grain_line(uv, faces, [loop], np.array([0.0, 1.0]))
    assert start[0] == pytest.approx(end[0])
    np.testing.assert_allclose([start[1], end[1]], [0.4 - 0.28, 0.4 + 0.28], atol=1e-12)
    # along the other axis, and any fraction
    start, end = grain_line(uv, faces, [loop], np.array([1.0, 0.0]), length_fraction=0.5)
    np.testing.assert_allclose(end - start, [0.2, 0.0], atol=1e-12)
    # a turned grain: the same line as drawing in the piece frame and turning back
    g = np.array([math.cos(0.4), math.sin(0.4)])
    rot = grain_rotation(g)
    s0, e0 = grain_line(uv @ rot.T, faces, [loop], np.array([0.0, 1.0]))
    s1, e1 = grain_line(uv, faces, [loop], g)
    np.testing.assert_allclose([s1, e1], [rot.T @ s0, rot.T @ e0], atol=1e-12)
    assert np.dot(e1 - s1, g) > 0


def test_grain_arrows_point_out_at_both_ends():
    start, end = np.array([0.0, 0.0]), np.array([0.0, 0.2])
    top, bottom = grain_arrows(start, end)
    np.testing.assert_array_equal(top[1], end)
    np.testing.assert_array_equal(bottom[1], start)
    dx = 0.015 * math.tan(math.radians(25))
    np.testing.assert_allclose(top[[0, 2]], [[-dx, 0.185], [dx, 0.185]], atol=1e-15)
    np.testing.assert_allclose(bottom[[0, 2]], [[-dx, 0.015], [dx, 0.015]], atol=1e-15)
    # a short line gets heads a quarter of its length
    top, _ = grain_arrows(np.array([0.0, 0.0]), np.array([0.02, 0.0]))
    assert np.linalg.norm(top[1] - 0.5 * (top[0] + top[2])) == pytest.approx(0.005)


def test_layout_has_no_overlaps_and_reserves_the_corner():
    rng = np.random.default_rng(0)
    boxes = []
    for _ in range(12):
        lo = rng.uniform(-1, 1, 2)
        boxes.append(np.stack([lo, lo + rng.uniform(0.05, 0.6, 2)]))
    lay = layout_pieces(boxes, width=0.9, margin=0.02, reserve=(0.11, 0.12))
    placed = [b + off for b, off in zip(boxes, lay.offsets)] + [lay.reserved]
    for i, a in enumerate(placed):
        assert a[0, 0] >= 0.02 - 1e-12 and a[0, 1] >= 0.02 - 1e-12
        assert a[1, 0] <= lay.size[0] - 0.02 + 1e-12 and a[1, 1] <= lay.size[1] - 0.02 + 1e-12
        for b in placed[i + 1 :]:
            sep = (
                a[1, 0] + 0.02 <= b[0, 0] + 1e-12
                or b[1, 0] + 0.02 <= a[0, 0] + 1e-12
                or a[1, 1] + 0.02 <= b[0, 1] + 1e-12
                or b[1, 1] + 0.02 <= a[0, 1] + 1e-12
            )
            assert sep
    # the reserved box is at the top-left corner
    assert lay.reserved[0, 0] == pytest.approx(0.02) and lay.reserved[1, 1] == pytest.approx(lay.size[1] - 0.02)
    # a piece wider than the sheet widens it
    wide = layout_pieces([np.array([[0, 0], [1.5, 0.2]])], width=0.9, margin=0.02)
    assert wide.size[0] == pytest.approx(1.54)


def test_layout_fills_beside_tall_pieces():
    tall = np.array([[0, 0], [0.4, 0.8]])
    small = [np.array([[0, 0], [0.4, 0.17]])] * 4
    lay = layout_pieces([tall] + small, width=0.86, margin=0.02)
    # the four small pieces stack beside the tall one: one tall piece deep
    assert lay.size[1] == pytest.approx(0.84)
    lay = layout_pieces([np.array([[0, 0], [0.4, 0.4]])] * 4, width=0.86, margin=0.02)
    np.testing.assert_allclose(lay.size, [0.86, 0.86])
