"""Plane polygons: signed area, outward offset, self-crossings, point in polygon, corners, rays.

A polygon is a ``(k, 2)`` float array of points in metres, closed implicitly
(the last point joins the first; it is not repeated). Counter-clockwise
polygons have positive area; an outline is counter-clockwise and a hole
clockwise, so the material is always on the left of the walk.
"""

from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np

from ..errors import ExportError

MITRE_LIMIT = 3.0  # a mitred corner lies at most this many offset widths from the polygon corner


def cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z component of the cross product of 2D vectors.

    Parameters
    ----------
    u, v : (..., 2) float, broadcast against each other.

    Returns
    -------
    (...) float, ``u_x v_y - u_y v_x`` (> 0 when v turns left of u).
    """
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def signed_area(loop: np.ndarray) -> float:
    """Signed area of a closed polygon (shoelace formula).

    Parameters
    ----------
    loop : (k, 2) float, metres.

    Returns
    -------
    float, square metres; > 0 when counter-clockwise.
    """
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def centroid(loop: np.ndarray) -> np.ndarray:
    """Area centroid of a closed polygon.

    Parameters
    ----------
    loop : (k, 2) float, any length unit; either orientation.

    Returns
    -------
    (2,) float, in the loop's unit.
    """
    x, y = loop[:, 0], loop[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    c = x * y1 - x1 * y
    return np.array([((x + x1) * c).sum(), ((y + y1) * c).sum()]) / (3.0 * c.sum())


def line_intersection(a0: np.ndarray, t0: np.ndarray, a1: np.ndarray, t1: np.ndarray) -> Optional[np.ndarray]:
    """Intersection of the lines ``a0 + s t0`` and ``a1 + u t1``.

    Parameters
    ----------
    a0, t0, a1, t1 : (2,) float, a point and a direction of each line.

    Returns
    -------
    (2,) float, or None when the lines are parallel (``|t0 x t1| < 1e-9``).
    """
    den = cross2(t0, t1)
    if abs(den) < 1e-9:
        return None
    s = cross2(a1 - a0, t1) / den
    return a0 + s * t0


def segments_cross(loop: np.ndarray, closed: bool = True, tol: float = 1e-12) -> Optional[Tuple[int, int]]:
    """First pair of non-adjacent edges of a polygon that properly cross.

    Parameters
    ----------
    loop : (k, 2) float, metres.
    closed : bool, the polygon closes from the last point to the first.
    tol : float, the orientation products must be below ``-tol`` (touching
        edges do not count).

    Returns
    -------
    (i, j) with i < j, the edges ``loop[i] -> loop[i+1]`` and
    ``loop[j] -> loop[j+1]`` (the smallest i, then j), or None.
    """
    p = np.asarray(loop, float)
    a = p
    b = np.roll(p, -1, axis=0) if closed else p[1:]
    if not closed:
        a = p[:-1]
    m = len(a)
    if m < 4:
        return None
    d = b - a
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    jj = np.arange(m)
    # blocks of rows keep the pair arrays small while staying vectorised
    for i0 in range(0, m - 2, 128):
        ii = np.arange(i0, min(i0 + 128, m - 2))[:, None]
        cand = jj[None, :] >= ii + 2
        if closed:
            cand &= ~((ii == 0) & (jj[None, :] == m - 1))
        cand &= (
            (lo[None, :, 0] <= hi[ii, 0])
            & (hi[None, :, 0] >= lo[ii, 0])
            & (lo[None, :, 1] <= hi[ii, 1])
            & (hi[None, :, 1] >= lo[ii, 1])
        )
        ci, cj = np.nonzero(cand)
        if ci.size == 0:
            continue
        i, j = ci + i0, cj
        c1 = cross2(d[i], a[j] - a[i])
        c2 = cross2(d[i], b[j] - a[i])
        c3 = cross2(d[j], a[i] - a[j])
        c4 = cross2(d[j], b[i] - a[j])
        hit = np.flatnonzero((c1 * c2 < -tol) & (c3 * c4 < -tol))
        if hit.size:
            k = hit[0]  # np.nonzero is row-major: the smallest i, then j
            return int(i[k]), int(j[k])
    return None


def offset_loop(loop: np.ndarray, widths: np.ndarray, mitre_limit: float = MITRE_LIMIT) -> np.ndarray:
    """Offset a closed polygon outward by a width per edge.

    Each edge is moved along its outward normal by its width; consecutive
    offset lines are intersected (a mitred corner, so both allowances of a
    sewn corner reach the same point); a convex corner whose mitre would lie
    farther than ``mitre_limit`` times the larger width from the corner is
    squared off; where two collinear edges have different widths a step joins
    them. Offset edges that turn over (short edges in concave stretches) are
    removed and their neighbours intersected instead, so the result has no
    local loops (wider overlaps are left to :func:`remove_loops`).

    Parameters
    ----------
    loop : (k, 2) float, counter-clockwise polygon (material on the left), metres.
    widths : (k,) float >= 0, width of edge ``loop[i] -> loop[i+1]``, metres.
    mitre_limit : float, see above.

    Returns
    -------
    (m, 2) float, the offset polygon, counter-clockwise, not closed (last != first).

    Raises
    ------
    ExportError when fewer than 3 distinct points remain (the offset is the
    cut line of a pattern piece).
    """
    p = np.asarray(loop, float)
    w = np.asarray(widths, float)
    # drop zero-length edges: they have no direction
    seg = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    keep = seg > 1e-10
    p, w = p[keep], w[keep]
    n = len(p)
    if n < 3:
        raise ExportError("cannot offset a polygon with fewer than 3 distinct points")
    d = np.roll(p, -1, axis=0) - p
    t = d / np.linalg.norm(d, axis=1)[:, None]
    nrm = np.stack([t[:, 1], -t[:, 0]], axis=1)  # right normal = outward for ccw
    base = p + w[:, None] * nrm  # a point on each offset line

    def corner(e0: int, e1: int) -> List[np.ndarray]:
        # the polygon corner: end of e0 (== start of e1 while they are neighbours)
        v = p[(e0 + 1) % n]
        c = cross2(t[e0], t[e1])
        dot = float(np.dot(t[e0], t[e1]))
        if abs(c) < 1e-9 and dot > 0:  # collinear, same way
            a, b = v + w[e0] * nrm[e0], p[e1] + w[e1] * nrm[e1]
            return [a] if np.linalg.norm(a - b) < 1e-12 else [a, b]
        m = line_intersection(base[e0], t[e0], base[e1], t[e1])
        limit = mitre_limit * max(w[e0], w[e1])
        if m is not None and (c < 0 or np.linalg.norm(m - v) <= limit + 1e-15):
            return [m]
        # sharp convex corner (or a hairpin): square it off at distance `limit`
        bis = nrm[e0] + nrm[e1]
        bl = np.linalg.norm(bis)
        bis = bis / bl if bl > 1e-9 else t[e0]
        limit = max(limit, 1e-6)
        pts = []
        for e in (e0, e1):
            den = float(np.dot(t[e], bis))
            if abs(den) < 1e-12:
                pts.append(v + w[e] * nrm[e])
            else:
                s = (limit - float(np.dot(base[e] - v, bis))) / den
                pts.append(base[e] + s * t[e])
        return pts

    # doubly linked ring of the edges still on the offset; corners[e] are
    # the points where the offset of e starts (shared with its predecessor)
    prev = np.roll(np.arange(n), 1)
    nxt = np.roll(np.arange(n), -1)
    corners = [corner(int(prev[e]), e) for e in range(n)]

    def proj(e: int) -> float:
        # signed length of the offset segment of e along e: < 0 when it turned over
        return float(np.dot(corners[nxt[e]][0] - corners[e][-1], t[e]))

    length = np.array([proj(e) for e in range(n)])
    alive = n
    while alive > 3:
        e = int(np.argmin(length))
        if length[e] >= -1e-12:
            break
        p_, n_ = int(prev[e]), int(nxt[e])
        nxt[p_], prev[n_] = n_, p_
        length[e] = np.inf
        alive -= 1
        corners[n_] = corner(p_, n_)
        length[p_], length[n_] = proj(p_), proj(n_)
    start = int(np.argmin(np.where(np.isfinite(length), np.arange(n), n)))
    out, e = [], start
    for _ in range(alive):
        out.extend(corners[e])
        e = int(nxt[e])
    return np.asarray(out, float)


def remove_loops(poly: np.ndarray, orientation: float = 1.0, max_iter: int = 1000, return_removed: bool = False):
    """Cut the loops out of a self-crossing closed polygon.

    At each crossing the polygon splits in two closed parts; the one with the
    larger signed area times ``orientation`` (+1: keep the counter-clockwise
    outline, -1: a clockwise hole) is kept. Offsetting a curve whose parts come
    closer than twice the offset makes such loops.

    Parameters
    ----------
    poly : (k, 2) float closed polygon (last != first), metres.
    orientation : float, +1 or -1, see above.
    max_iter : int, at most this many crossings are resolved.
    return_removed : bool, also return the area cut away.

    Returns
    -------
    (m, 2) float, a polygon without crossings (m <= k + number of crossings);
    with ``return_removed`` also the total unsigned area (m^2) of the parts cut away.
    """
    p = np.asarray(poly, float)
    removed = 0.0
    for _ in range(max_iter):
        hit = segments_cross(p)
        if hit is None:
            break
        i, j = hit
        a0, a1 = p[i], p[(i + 1) % len(p)]
        b0, b1 = p[j], p[(j + 1) % len(p)]
        x = line_intersection(a0, a1 - a0, b0, b1 - b0)
        if x is None:  # pragma: no cover - segments_cross found a proper crossing
            break
        outer = np.vstack([p[: i + 1], x[None], p[j + 1 :]])
        inner = np.vstack([x[None], p[i + 1 : j + 1]])
        if orientation * signed_area(outer) >= orientation * signed_area(inner):
            p, cut_away = outer, inner
        else:
            p, cut_away = inner, outer
        removed += abs(signed_area(cut_away))
    return (p, removed) if return_removed else p


def points_in_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Which points lie strictly inside a closed polygon (crossing number).

    Parameters
    ----------
    points : (m, 2) float, metres.
    poly : (k, 2) float, any orientation.

    Returns
    -------
    (m,) bool.
    """
    q = np.asarray(points, float)
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    x, y = q[:, 0:1], q[:, 1:2]
    straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return (np.sum(straddle & (x < xc), axis=1) % 2) == 1


def turn_points(loop: np.ndarray, degrees: float) -> np.ndarray:
    """The corners of a closed polyline: the vertices where it turns by more than ``degrees``.

    Parameters
    ----------
    loop : (k, 2) float, metres.
    degrees : float, the smallest turn (between the incoming and the outgoing
        edge's directions) that makes a corner rather than a curve point.

    Returns
    -------
    (c,) int, vertex indices in increasing order.
    """
    p = np.asarray(loop, float)
    a = p - np.roll(p, 1, axis=0)
    b = np.roll(p, -1, axis=0) - p
    cos = np.sum(a * b, axis=1) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
    return np.flatnonzero(cos < np.cos(np.radians(degrees)))


def distance_to_polyline(points: np.ndarray, poly: np.ndarray, closed: bool = True) -> np.ndarray:
    """Distance from each point to the nearest point of a polyline.

    Parameters
    ----------
    points : (m, 2) float, metres.
    poly : (k, 2) float.
    closed : bool, include the edge from the last point back to the first.

    Returns
    -------
    (m,) float, metres.
    """
    q = np.asarray(points, float)[:, None, :]
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0) if closed else a[1:]
    if not closed:
        a = a[:-1]
    d = b - a
    dd = np.maximum((d * d).sum(1), 1e-300)
    t = np.clip(((q - a) * d).sum(2) / dd, 0.0, 1.0)
    c = a + t[..., None] * d
    return np.linalg.norm(q - c, axis=2).min(axis=1)


def ray_hit(origin: np.ndarray, direction: np.ndarray, loop: np.ndarray) -> Optional[float]:
    """Where a ray first meets a closed polygon.

    Parameters
    ----------
    origin, direction : (2,) float; the ray is ``origin + t direction``, t >= 0.
    loop : (k, 2) float, closed polygon.

    Returns
    -------
    float, the smallest such t (in units of ``|direction|``), or None when the
    ray misses.
    """
    a = np.asarray(loop, float)
    b = np.roll(a, -1, axis=0)
    e = b - a
    den = cross2(direction, e)
    ok = np.abs(den) > 1e-14
    with np.errstate(divide="ignore", invalid="ignore"):
        t = cross2(a - origin, e) / den
        u = cross2(a - origin, direction) / den
    hit = ok & (t >= -1e-12) & (u >= -1e-9) & (u <= 1 + 1e-9)
    if not np.any(hit):
        return None
    return float(t[hit].min())


#: m: two boundary edges of a piece that share no vertex and come closer than this touch (1 um,
#: far below a cutter's line and far above the solver's rounding on a 2 m body)
CONTACT = 1e-6


def point_segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance (k,) from points p (k, 2) to segments a->b (k, 2), row by row (metres in, metres out)."""
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    q = a + t[:, None] * d - p
    return np.sqrt(np.einsum("ij,ij->i", q, q))


def segment_gaps(a0, b0, a1, b1) -> np.ndarray:
    """Distance (k,) between 2D segments a0->b0 and a1->b1 (each (k, 2), metres), row by row; 0 where they cross."""
    d0, d1 = b0 - a0, b1 - a1
    c1, c2 = cross2(d0, a1 - a0), cross2(d0, b1 - a0)
    c3, c4 = cross2(d1, a0 - a1), cross2(d1, b0 - a1)
    cross = (c1 * c2 < 0) & (c3 * c4 < 0)
    gap = np.minimum.reduce(
        [
            point_segment_distances(a0, a1, b1),
            point_segment_distances(b0, a1, b1),
            point_segment_distances(a1, a0, b0),
            point_segment_distances(b1, a0, b0),
        ]
    )
    return np.where(cross, 0.0, gap)
