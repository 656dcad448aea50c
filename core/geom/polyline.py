"""Polylines: length, cumulative length, point at arc length, simplification.

A polyline is a ``(k, d)`` float array of points (d = 2 or 3, metres), open
unless ``closed=True`` adds the edge from the last point back to the first.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np


def _points(points: np.ndarray, closed: bool) -> np.ndarray:
    p = np.asarray(points, float)
    return np.vstack([p, p[:1]]) if closed and len(p) > 1 else p


def polyline_length(points: np.ndarray, closed: bool = False) -> float:
    """Length of a polyline.

    Parameters
    ----------
    points : (k, d) float, metres.
    closed : bool
        Include the closing edge.

    Returns
    -------
    float, metres (0 for fewer than two points).
    """
    p = _points(points, closed)
    if len(p) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def cumulative_lengths(points: np.ndarray, closed: bool = False) -> np.ndarray:
    """Arc length at each point, starting at 0.

    Returns
    -------
    (k,) float, metres; ``k + 1`` entries when ``closed`` (the last is the
    total length, back at the first point).
    """
    p = _points(points, closed)
    if len(p) < 2:
        return np.zeros(len(p))
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


def point_at_length(points: np.ndarray, s) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points at arc lengths ``s`` along an open polyline, clamped to its ends.

    Parameters
    ----------
    points : (k, d) float, k >= 2.
    s : float or (m,) float, metres from the first point.

    Returns
    -------
    xy : (m, d) float (or (d,) for a scalar ``s``), the points.
    edge : (m,) int (or int), the edge each point lies on.
    tangent : (m, d) float (or (d,)), the unit direction of that edge
        (zero for a zero-length edge).
    """
    p = np.asarray(points, float)
    seg = np.diff(p, axis=0)
    length = np.linalg.norm(seg, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(length)])
    scalar = np.ndim(s) == 0
    s = np.clip(np.atleast_1d(np.asarray(s, float)), 0.0, cum[-1])
    edge = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(length) - 1)
    le = length[edge]
    t = np.where(le > 0, (s - cum[edge]) / np.where(le > 0, le, 1.0), 0.0)
    xy = p[edge] + t[:, None] * seg[edge]
    tangent = seg[edge] / np.maximum(le, 1e-12)[:, None]
    if scalar:
        return xy[0], int(edge[0]), tangent[0]
    return xy, edge, tangent


def simplify_indices(points: np.ndarray, tol: float) -> np.ndarray:
    """Douglas-Peucker on an open polyline: the indices of the points that keep it within ``tol``.

    Parameters
    ----------
    points : (k, 2) float, metres, k >= 1.
    tol : float, metres, the largest distance of a left-out point from the chord that replaces it
        (from the chord's end where the chord has no length).

    Returns
    -------
    (m,) int, increasing; the first and the last point always kept.
    """
    p = np.asarray(points, float)
    keep = np.zeros(len(p), bool)
    keep[[0, -1]] = True
    stack = [(0, len(p) - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        d, q = p[b] - p[a], p[a + 1 : b] - p[a]
        n = float(np.linalg.norm(d))
        dist = np.abs(d[0] * q[:, 1] - d[1] * q[:, 0]) / n if n > 1e-15 else np.linalg.norm(q, axis=1)
        k = int(np.argmax(dist))
        if dist[k] > tol:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return np.flatnonzero(keep)
