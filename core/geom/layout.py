"""How pattern pieces are shown: the grain frame, the grain line and the sheet layout.

One definition used by the export, the pattern plot and the add-on.

- :func:`grain_rotation` turns pattern uv into the piece frame, where the
  grain (warp) points along +y, the way pieces are laid on fabric with the
  selvage vertical.
- :func:`grain_line` is the grain line of a piece: parallel to the grain,
  through a point inside the piece near its area centroid, across the middle
  70 % of the piece's chord there.
- :func:`grain_arrows` are the arrow heads drawn at both of its ends.
- :func:`layout_pieces` places the pieces' bounding boxes on a sheet without
  overlaps (skyline packing).

All lengths are metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .mesh import signed_areas_2d
from .polygon import ray_hit

GRAIN_FRACTION = 0.7  # the grain line spans this fraction of the chord through the piece
GRAIN_MISS = 0.05  # m, half-chord assumed on a side where the ray leaves no loop
ARROW_HEAD = 0.015  # m, arrow-head length (at most a quarter of the grain line)
ARROW_ANGLE = 25.0  # degrees, half opening of an arrow head


def grain_rotation(grain: np.ndarray) -> np.ndarray:
    """Rotation from pattern uv to the piece frame, where the grain points along +y.

    Parameters
    ----------
    grain : (2,) float, the grain direction in uv (any length > 0).

    Returns
    -------
    (2, 2) float, ``frame = rotation @ uv``; ``uv = rotation.T @ frame``.
    """
    g = np.asarray(grain, float)
    ang = math.pi / 2 - math.atan2(g[1], g[0])
    c, s = math.cos(ang), math.sin(ang)
    return np.array([[c, -s], [s, c]])


def interior_point(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """A point inside a piece near its area centroid.

    The centroid itself can lie outside a concave piece; the centroid of the
    triangle closest to it lies inside.

    Parameters
    ----------
    uv : (n, 2) float, metres.
    faces : (F, 3) int.

    Returns
    -------
    (2,) float, metres.
    """
    tri = uv[faces]
    cen = tri.mean(axis=1)
    area = np.abs(signed_areas_2d(uv, faces))
    c = (cen * area[:, None]).sum(0) / max(area.sum(), 1e-300)
    return cen[np.argmin(np.linalg.norm(cen - c, axis=1))]


def grain_line(
    uv: np.ndarray,
    faces: np.ndarray,
    loops: Sequence[np.ndarray],
    grain: np.ndarray,
    length_fraction: float = GRAIN_FRACTION,
) -> Tuple[np.ndarray, np.ndarray]:
    """The grain line of a piece.

    From :func:`interior_point`, rays along the grain and against it meet the
    piece's boundary; the grain line is centred on that chord and spans
    ``length_fraction`` of it (a side whose ray meets nothing counts
    ``GRAIN_MISS``).

    Parameters
    ----------
    uv : (n, 2) float, vertex positions, metres.
    faces : (F, 3) int, the piece's triangles.
    loops : list of (k,) int, the boundary loops (vertex ids into ``uv``).
    grain : (2,) float, grain direction in ``uv`` (any length > 0).
    length_fraction : float, part of the chord covered.

    Returns
    -------
    start, end : (2,) float, the end points in ``uv`` (``end`` lies along the grain from ``start``).
    """
    rot = grain_rotation(grain)
    xy = np.asarray(uv, float) @ rot.T
    c = interior_point(xy, np.asarray(faces, int))
    sew = [xy[np.asarray(b, int)] for b in loops]
    up = np.array([0.0, 1.0])
    hits_up = [h for h in (ray_hit(c, up, loop) for loop in sew) if h is not None]
    hits_dn = [h for h in (ray_hit(c, -up, loop) for loop in sew) if h is not None]
    t_up = min(hits_up) if hits_up else GRAIN_MISS
    t_dn = min(hits_dn) if hits_dn else GRAIN_MISS
    lo, hi = c[1] - t_dn, c[1] + t_up
    mid, half = 0.5 * (lo + hi), (0.5 * length_fraction) * (hi - lo)
    p0, p1 = np.array([c[0], mid - half]), np.array([c[0], mid + half])
    return rot.T @ p0, rot.T @ p1


def grain_arrows(
    start: np.ndarray, end: np.ndarray, head: float = ARROW_HEAD, angle: float = ARROW_ANGLE
) -> List[np.ndarray]:
    """Arrow heads at both ends of a grain line.

    Parameters
    ----------
    start, end : (2,) float, the grain line, metres.
    head : float, arrow-head length (m), at most a quarter of the line.
    angle : float, half opening in degrees.

    Returns
    -------
    list of two (3, 2) float polylines (barb, tip, barb): at ``end``, then at ``start``.
    """
    p0, p1 = np.asarray(start, float), np.asarray(end, float)
    d = p1 - p0
    length = float(np.linalg.norm(d))
    u = d / max(length, 1e-300)
    n = np.array([u[1], -u[0]])  # to the right of the line
    h = min(head, 0.25 * length)
    dx = h * math.tan(math.radians(angle))
    return [
        np.array([p1 - h * u - dx * n, p1, p1 - h * u + dx * n]),
        np.array([p0 + h * u - dx * n, p0, p0 + h * u + dx * n]),
    ]


@dataclass
class Layout:
    """Placement of pieces on one sheet (metres, y up, origin bottom-left).

    Attributes
    ----------
    offsets : (n, 2) float, sheet position = piece position + offset.
    size : (2,) float, sheet width and height.
    reserved : (2, 2) float or None, min/max corner of the reserved box (test square).
    """

    offsets: np.ndarray
    size: np.ndarray
    reserved: Optional[np.ndarray] = None


def layout_pieces(
    boxes: Sequence[np.ndarray], width: float = 0.9, margin: float = 0.02, reserve: Optional[Tuple[float, float]] = None
) -> Layout:
    """Skyline packing of bounding boxes: tallest first, each where it reaches least far down, then leftmost.

    Parameters
    ----------
    boxes : n (2, 2) float arrays, min/max corners of each piece, metres.
    width : float, sheet width (m); a piece wider than that widens the sheet.
    margin : float, gap between pieces and around the sheet (m).
    reserve : (w, h) of a box kept free at the top-left (the PDF test square), m.

    Returns
    -------
    :class:`Layout`.
    """
    boxes = [np.asarray(b, float) for b in boxes]
    sizes = np.array([b[1] - b[0] for b in boxes]).reshape(-1, 2)
    items = [(-sizes[i, 1], -sizes[i, 0], i) for i in range(len(boxes))]
    items.sort()
    order = [i for _, _, i in items]
    entries = ([("reserve", np.asarray(reserve, float))] if reserve is not None else []) + [
        (i, sizes[i]) for i in order
    ]
    sheet_w = max([width] + [s[0] + 2 * margin for _, s in entries])
    # skyline packing, y measured downward from the top edge: the skyline is
    # the fill depth of each x interval; a box goes where its top would be
    # shallowest (then leftmost), spanning the intervals it covers
    xs = [margin, sheet_w - margin]  # interval boundaries
    depth = [margin]  # fill depth of each interval
    pos = {}
    for key, s in entries:
        w = float(s[0])
        best = None
        for k in range(len(depth)):
            x = xs[k]
            if x + w > sheet_w - margin + 1e-12:
                break
            end = x + w
            top = max(d for d, x0 in zip(depth, xs) if x0 < end - 1e-12 and x0 >= x - 1e-12)
            if best is None or top < best[0] - 1e-12:
                best = (top, x)
        top, x = best
        pos[key] = (x, top)
        # raise the skyline under the box (plus a margin below it)
        new_depth = top + float(s[1]) + margin
        x1 = min(x + w + margin, sheet_w - margin)
        bounds = sorted(set(xs + [x, x1]))
        fill = []
        for x0, x_end in zip(bounds[:-1], bounds[1:]):
            k = max(i for i in range(len(depth)) if xs[i] <= x0 + 1e-12)
            fill.append(new_depth if (x0 >= x - 1e-12 and x_end <= x1 + 1e-12) else depth[k])
        # merge equal neighbours so the skyline stays short
        xs, depth = [bounds[0]], [fill[0]]
        for x0, d in zip(bounds[1:-1], fill[1:]):
            if abs(d - depth[-1]) > 1e-12:
                xs.append(x0)
                depth.append(d)
        xs.append(bounds[-1])
    sheet_h = max(py + float(s[1]) for (key, s), (px, py) in zip(entries, [pos[k] for k, _ in entries])) + margin
    offsets = np.zeros((len(boxes), 2))
    for i in range(len(boxes)):
        px, py = pos[i]
        offsets[i] = [px - boxes[i][0, 0], sheet_h - py - sizes[i, 1] - boxes[i][0, 1]]
    reserved = None
    if reserve is not None:
        px, py = pos["reserve"]
        reserved = np.array([[px, sheet_h - py - reserve[1]], [px + reserve[0], sheet_h - py]])
    return Layout(offsets=offsets, size=np.array([sheet_w, sheet_h]), reserved=reserved)
