"""Nesting outlines (core.marker.outline) hold the true cut line, and a marker of curved, concave
pieces keeps the true cut lines apart, inside the fabric, grain kept."""

from __future__ import annotations

import numpy as np
import pytest
from marker_synth import overlap, wavy_pattern

from core.geom.polygon import distance_to_polyline, offset_loop, points_in_polygon, remove_loops, signed_area
from core.marker.outline import CLEARANCE, NEST_TOLERANCE, holds, nest_outline, simplify_indices


def _blob(seed: int, n: int = 400) -> np.ndarray:
    """A concave, wiggly closed loop (counter-clockwise), about 0.3 m across."""
    rng = np.random.default_rng(seed)
    th = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    r = 0.15 * (
        1
        + 0.25 * np.sin(rng.integers(3, 7) * th + rng.uniform(0, 6))
        + 0.01 * np.sin(rng.integers(30, 60) * th)
        + 0.002 * rng.standard_normal(n)
    )
    return np.column_stack([r * np.cos(th), r * np.sin(th)])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("tol", [NEST_TOLERANCE, 0.001])
def test_nest_outline_holds_the_cut_line(seed, tol):
    """Every cut-line vertex lies strictly inside, at least the clearance from the outline; fewer vertices;
    less area added than growing the simplified outline by the tolerance (the old way)."""
    loop = _blob(seed)
    outer = nest_outline(loop, tol)
    assert holds(outer, loop)
    assert bool(points_in_polygon(loop, outer).all())
    assert distance_to_polyline(loop, outer).min() >= CLEARANCE * (1 - 1e-6)
    assert len(outer) < len(loop)
    simple = loop[simplify_indices(loop, tol)]
    grown = remove_loops(offset_loop(simple, np.full(len(simple), tol)))
    assert 0 < signed_area(outer) - signed_area(loop) < signed_area(grown) - signed_area(loop)
    # every outline vertex stays near the cut line (a mitred corner reaches at most 10 tolerances)
    assert distance_to_polyline(outer, loop).max() <= 10 * tol + CLEARANCE


def test_holds_can_fail():
    """The containment check rejects an outline that cuts a corner off or lies inside the cut line."""
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert holds(square * 1.1 - 0.05, square)
    assert not holds(square * 0.9 + 0.05, square)
    corner_cut = np.array([[-0.1, -0.1], [1.1, -0.1], [1.1, 0.85], [0.85, 1.1], [-0.1, 1.1]])
    assert not holds(corner_cut, square)
    notch = np.array([[-0.1, -0.1], [0.4, -0.1], [0.5, 0.2], [0.6, -0.1], [1.1, -0.1], [1.1, 1.1], [-0.1, 1.1]])
    assert not holds(notch, square)  # every square vertex inside, yet the notch reaches into the square
    assert not holds(square[::-1] * 1.1 - 0.05, square)  # clockwise


def test_marker_curved_pieces_true_cut_lines_apart():
    """Curved, concave pieces with wavy sides (six copies) nested: the true cut lines do not overlap, lie on
    the fabric, touch-close (so the check bites), and every piece is turned 0 or 180 degrees only."""
    from core.marker.nesting import marker_items, nest, placed_outline

    pytest.importorskip("spyrrow")
    width = 0.6
    items = marker_items([("M", wavy_pattern(3), 2)])
    m = nest(items, width, seconds=3, seed=0, early_stop=True)  # packed against each other from the first marker
    loops = [placed_outline(m, p) for p in m.placements]
    assert len(loops) == 6
    closest = np.inf
    for i, a in enumerate(loops):
        assert a[:, 1].min() >= -1e-6 and a[:, 1].max() <= width + 1e-6 and a[:, 0].min() >= -1e-6
        for b in loops[i + 1 :]:
            assert not overlap(a, b)
            closest = min(closest, float(distance_to_polyline(a, b).min()))
    assert closest < 0.002  # the nester packed pieces against each other
    for p in m.placements:
        assert min(abs(p.angle - a) for a in (0.0, 180.0, -180.0)) < 1e-6
    assert m.efficiency == pytest.approx(sum(signed_area(a) for a in loops) / (width * m.length), rel=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_one_douglas_peucker_for_open_and_closed_outlines(seed):
    """core.geom.polyline.simplify_indices (the GarmentCode panels') keeps both ends and every left-out point
    within the tolerance; the nesting outline's closed loop is its two halves."""
    from core.geom.polyline import simplify_indices as simplify_polyline

    loop, tol = _blob(seed), 0.0005
    half = loop[: len(loop) // 2 + 1]
    idx = simplify_polyline(half, tol)
    assert idx[0] == 0 and idx[-1] == len(half) - 1 and np.all(np.diff(idx) > 0) and len(idx) < len(half) / 2
    assert distance_to_polyline(half, half[idx], closed=False).max() <= tol + 1e-12
    # a chord of no length (the polyline comes back to its start): the farthest point is kept
    back = np.vstack([half, half[:1]])
    assert len(simplify_polyline(back, tol)) > 2
    closed = simplify_indices(loop, tol)
    assert closed[0] == 0 and distance_to_polyline(loop, loop[closed]).max() <= tol + 1e-12
