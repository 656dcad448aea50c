"""Nesting outlines: a simpler polygon that holds a piece's cut line, for the nester.

The cut lines that come from mesh boundaries have a few hundred vertices; a
nester's collision checks cost by the edge, so each piece is nested as a
simpler polygon that lies entirely outside its cut line (never inside it:
whatever the nester keeps apart, the true cut lines are kept apart too).

Douglas–Peucker picks the vertices that keep the outline within ``tol`` of
the cut line; each simplified edge is then moved outward just as far as the
cut line bulges beyond it (most edges barely move: the cut line crosses its
chords), plus a small ``clearance``; consecutive moved edges meet at their
intersection. The result is checked (a simple polygon, every cut-line vertex
strictly inside, no edge of the cut line crossing it); where the check fails
the tolerance is halved, and at the end the cut line itself, grown by the
clearance, is used. The area added is the fabric the nester may not use:
about a third of what growing the whole simplified outline by ``tol`` adds.
"""

from __future__ import annotations

import numpy as np

from ..errors import ExportError
from ..geom.polygon import cross2, offset_loop, points_in_polygon, remove_loops, segments_cross, signed_area
from ..geom.polyline import simplify_indices as simplify_polyline

NEST_TOLERANCE = 0.0003  # m: simplified outlines stay within this of the cut line (plus CLEARANCE)
CLEARANCE = 0.00002  # m: every nesting outline lies at least this far outside its cut line
MITRE_REACH = 10.0  # a corner point may lie this many tolerances from its vertex, else the corner is bevelled
MIN_TOLERANCE = 0.00002  # m: below this the tolerance is not halved again (the grown cut line is used)


def simplify_indices(loop: np.ndarray, tol: float) -> np.ndarray:
    """Douglas–Peucker on a closed loop: the indices of the vertices that keep it within ``tol``.

    The loop is cut at its first vertex and the vertex farthest from it; each half is simplified as an open
    polyline (:func:`core.geom.polyline.simplify_indices`).

    Parameters
    ----------
    loop : (k, 2) float, m, closed polygon (last != first).
    tol : float, m, largest distance of a left-out vertex from its chord.

    Returns
    -------
    (m,) int, increasing indices into ``loop`` (m >= 2).
    """
    loop = np.asarray(loop, float)
    far = int(np.argmax(np.linalg.norm(loop - loop[0], axis=1)))
    first = simplify_polyline(loop[: far + 1], tol)
    second = far + simplify_polyline(np.vstack([loop[far:], loop[:1]]), tol)
    return np.concatenate([first, second[1:-1]])


def _outer_polygon(loop: np.ndarray, idx: np.ndarray, tol: float, clearance: float) -> np.ndarray:
    """The chords ``loop[idx[k]] -> loop[idx[k+1]]``, each moved out past the cut line it replaces."""
    n, m = len(loop), len(idx)
    normals = np.zeros((m, 2))
    widths = np.zeros(m)
    for k in range(m):
        a, b = int(idx[k]), int(idx[(k + 1) % m])
        span = loop[np.arange(a, b + (n if b <= a else 0) + 1) % n]
        d = loop[b] - loop[a]
        d = d / max(float(np.linalg.norm(d)), 1e-12)
        normals[k] = (d[1], -d[0])  # outward: the material is on the left of a counter-clockwise loop
        widths[k] = max(0.0, float(((span - loop[a]) @ normals[k]).max())) + clearance
    out = []
    for k in range(m):
        v = loop[idx[k]]
        j = k - 1  # the chord that ends at v
        p1, t1 = v + widths[j] * normals[j], np.array([-normals[j][1], normals[j][0]])
        p2, t2 = v + widths[k] * normals[k], np.array([-normals[k][1], normals[k][0]])
        den = float(cross2(t1, t2))
        if abs(den) > 1e-9:
            x = p1 + float(cross2(p2 - p1, t2)) / den * t1
            if np.linalg.norm(x - v) <= max(MITRE_REACH * tol, 4.0 * max(widths[j], widths[k])):
                out.append(x)
                continue
        out += [p1, p2]  # nearly parallel chords or a sharp corner: bevelled
    return np.array(out)


def edges_meet(a: np.ndarray, b: np.ndarray, touching: bool = True) -> bool:
    """Whether any edge of closed loop ``a`` meets an edge of closed loop ``b``.

    ``touching``: an end point on the other edge counts (else only proper crossings).
    """
    p, r = a, np.roll(a, -1, axis=0) - a
    q, s = b, np.roll(b, -1, axis=0) - b
    den = r[:, None, 0] * s[None, :, 1] - r[:, None, 1] * s[None, :, 0]
    qp = q[None, :, :] - p[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[..., 0] * s[None, :, 1] - qp[..., 1] * s[None, :, 0]) / den
        u = (qp[..., 0] * r[:, None, 1] - qp[..., 1] * r[:, None, 0]) / den
    if touching:
        hit = (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    else:
        hit = (t > 0) & (t < 1) & (u > 0) & (u < 1)
    return bool(np.any((np.abs(den) > 1e-15) & hit))


def holds(outer: np.ndarray, loop: np.ndarray) -> bool:
    """Whether the simple counter-clockwise polygon ``outer`` has all of ``loop`` strictly inside it."""
    return (
        len(outer) >= 3
        and signed_area(outer) > 0
        and segments_cross(outer) is None
        and bool(points_in_polygon(loop, outer).all())
        and not edges_meet(loop, outer)
    )


def nest_outline(outline: np.ndarray, tol: float = NEST_TOLERANCE, clearance: float = CLEARANCE) -> np.ndarray:
    """(m, 2) m: a simpler polygon that holds ``outline``, within ``tol`` + ``clearance`` of it.

    Parameters
    ----------
    outline : (k, 2) float, m, counter-clockwise cut line.
    tol : float, m, how far the simplified outline may stray from the cut line.
    clearance : float, m > 0, the least distance the outline keeps outside the cut line
        (so two nested pieces never share a point of their cut lines).

    Raises
    ------
    ExportError when not even the grown cut line holds it (a self-crossing cut line).
    """
    loop = np.asarray(outline, float)
    t = float(tol)
    while t >= MIN_TOLERANCE:
        outer = _outer_polygon(loop, simplify_indices(loop, t), t, clearance)
        if holds(outer, loop):
            return outer
        t /= 2.0
    outer = remove_loops(offset_loop(loop, np.full(len(loop), clearance)))
    if not holds(outer, loop):
        raise ExportError("marker: a cut line crosses itself; expected a simple outline to nest")
    return outer


__all__ = ["nest_outline", "simplify_indices", "holds", "edges_meet", "NEST_TOLERANCE", "CLEARANCE"]
