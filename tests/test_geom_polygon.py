"""core.geom.polygon: one test per operation (signed area, centroid, offset, crossings, loops, inside, corners, distance, rays)."""

import numpy as np
import pytest

from core.errors import ExportError
from core.geom.polygon import (
    centroid,
    cross2,
    distance_to_polyline,
    line_intersection,
    offset_loop,
    points_in_polygon,
    ray_hit,
    remove_loops,
    segments_cross,
    signed_area,
    turn_points,
)

SQUARE = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)


def test_cross2_is_the_z_component():
    u = np.array([[1.0, 0.0], [0.0, 2.0]])
    v = np.array([[0.0, 3.0], [1.0, 0.0]])
    np.testing.assert_array_equal(cross2(u, v), [3.0, -2.0])


def test_signed_area_sign_follows_orientation():
    assert signed_area(SQUARE) == pytest.approx(1.0)
    assert signed_area(SQUARE[::-1]) == pytest.approx(-1.0)
    tri = np.array([[0, 0], [2, 0], [0, 3]], float)
    assert signed_area(tri) == pytest.approx(3.0)


def test_centroid_is_the_area_centroid_either_orientation():
    # an L of two unit squares and a 2x1 bar: the area centroid, not the vertex mean (which is pulled to the corner)
    ell = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    expected = np.array([2 * 1.0 + 1 * 0.5, 2 * 0.5 + 1 * 1.5]) / 3.0  # bar (area 2) and square (area 1)
    np.testing.assert_allclose(centroid(ell), expected, atol=1e-12)
    np.testing.assert_allclose(centroid(ell[::-1]), expected, atol=1e-12)
    assert not np.allclose(centroid(ell), ell.mean(axis=0))


def test_line_intersection_and_parallel_lines():
    x = line_intersection(np.array([0.0, 0.0]), np.array([1.0, 1.0]), np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    np.testing.assert_allclose(x, [1.0, 1.0])
    assert line_intersection(np.zeros(2), np.array([1.0, 0.0]), np.array([0.0, 1.0]), np.array([2.0, 0.0])) is None


def test_segments_cross_finds_the_first_proper_crossing():
    assert segments_cross(SQUARE) is None
    bowtie = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], float)
    assert segments_cross(bowtie) == (0, 2)
    # an open polyline: its first edge crossed by its fourth
    hook = np.array([[0, 0], [1, 0], [1, 1], [0.5, 1], [0.5, -1]], float)
    assert segments_cross(hook, closed=False) == (0, 3)
    assert segments_cross(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0, 0.5]], float), closed=False) is None
    # touching at a vertex is not a proper crossing
    assert segments_cross(np.array([[0, 0], [1, 0], [0.5, 0.5], [1, 1], [0, 1], [0.5, 0.5]], float)) is None


def test_offset_square_mitres_and_steps():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    cut = offset_loop(sq, np.full(4, 0.01))
    np.testing.assert_allclose(cut, [[-0.01, -0.01], [1.01, -0.01], [1.01, 1.01], [-0.01, 1.01]], atol=1e-12)
    # bottom edge a 2 cm hem: the mitre keeps each allowance to its own edge width
    cut = offset_loop(sq, np.array([0.02, 0.01, 0.01, 0.01]))
    np.testing.assert_allclose(cut[0], [-0.01, -0.02], atol=1e-12)
    np.testing.assert_allclose(cut[1], [1.01, -0.02], atol=1e-12)
    # collinear edges with different widths: a step joins them
    line = np.array([[0, 0], [0.5, 0], [1, 0], [1, 1], [0, 1]], float)
    cut = offset_loop(line, np.array([0.01, 0.02, 0.01, 0.01, 0.01]))
    assert any(np.allclose(q, [0.5, -0.01]) for q in cut) and any(np.allclose(q, [0.5, -0.02]) for q in cut)


def test_offset_sharp_corner_is_squared():
    tri = np.array([[0, 0], [1, 0], [0.5, 0.05]], float)  # two very sharp corners
    cut = offset_loop(tri, np.full(3, 0.01), mitre_limit=3.0)
    assert len(cut) > 3
    # an unlimited mitre would reach 0.01 / sin(2.9 deg) = 20 cm beyond the corner
    assert distance_to_polyline(cut, tri).max() <= 0.035
    assert distance_to_polyline(cut, tri).min() >= 0.01 - 1e-9


def test_offset_concave_noisy_curve_has_no_loops():
    # a star-ish outline with many short edges in concave stretches
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    r = 0.2 + 0.05 * np.cos(5 * t) + 0.0015 * np.sin(97 * t)
    loop = np.column_stack([r * np.cos(t), r * np.sin(t)])
    assert signed_area(loop) > 0 and segments_cross(loop) is None
    cut = offset_loop(loop, np.full(len(loop), 0.015))
    assert segments_cross(cut) is None
    assert distance_to_polyline(cut, loop).min() >= 0.015 - 1e-6


def test_remove_loops_keeps_the_outline():
    # a ccw square with a small cw "ear" loop at one corner (what offsetting a tight spot makes)
    poly = np.array([[0, 0], [1, 0], [1, 1.1], [1.1, 1.0], [0.9, 1.0], [0, 1]], float)
    assert segments_cross(poly) is not None
    out = remove_loops(poly)
    assert segments_cross(out) is None
    np.testing.assert_allclose(out, [[0, 0], [1, 0], [1, 1], [0.9, 1], [0, 1]], atol=1e-12)


def test_offset_of_too_few_points_is_refused():
    with pytest.raises(ExportError, match="fewer than 3"):
        offset_loop(np.array([[0, 0], [1, 0], [1, 0]], float), np.full(3, 0.01))


def test_remove_loops_reports_the_area_cut_away():
    poly = np.array([[0, 0], [1, 0], [1, 1.1], [1.1, 1.0], [0.9, 1.0], [0, 1]], float)
    out, removed = remove_loops(poly, return_removed=True)
    assert removed == pytest.approx(0.5 * 0.1 * 0.1, rel=1e-9)  # the ear (1, 1), (1, 1.1), (1.1, 1)
    # the hole orientation keeps the clockwise part
    hole, _ = remove_loops(poly[::-1], orientation=-1.0, return_removed=True)
    assert signed_area(hole) < 0 and segments_cross(hole) is None


def test_points_in_polygon_strictly_inside():
    q = np.array([[0.5, 0.5], [1.5, 0.5], [-0.1, 0.2], [0.99, 0.01]])
    np.testing.assert_array_equal(points_in_polygon(q, SQUARE), [True, False, False, True])
    np.testing.assert_array_equal(points_in_polygon(q, SQUARE[::-1]), [True, False, False, True])


def test_turn_points_find_corners_not_curve_points():
    t = np.linspace(0, np.pi / 2, 30)
    quarter = np.vstack([[0, 0], np.column_stack([np.cos(t), np.sin(t)])])  # a pie slice: 3 corners
    np.testing.assert_array_equal(turn_points(quarter, 20.0), [0, 1, 30])
    np.testing.assert_array_equal(turn_points(SQUARE, 89.0), [0, 1, 2, 3])


def test_distance_to_polyline_closed_and_open():
    q = np.array([[0.5, -0.2], [0.5, 0.5], [-0.3, 1.4]])
    np.testing.assert_allclose(distance_to_polyline(q, SQUARE), [0.2, 0.5, 0.5])
    # open: the closing edge (0, 1) -> (0, 0) is not part of it
    np.testing.assert_allclose(
        distance_to_polyline(np.array([[-0.1, 0.5]]), SQUARE, closed=False), [np.hypot(0.1, 0.5)]
    )


def test_ray_hit_first_crossing_or_none():
    assert ray_hit(np.array([0.5, 0.5]), np.array([1.0, 0.0]), SQUARE) == pytest.approx(0.5)
    assert ray_hit(np.array([0.5, 0.25]), np.array([0.0, -2.0]), SQUARE) == pytest.approx(0.125)
    assert ray_hit(np.array([2.0, 0.5]), np.array([1.0, 0.0]), SQUARE) is None
