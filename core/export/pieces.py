"""Cutting-room geometry of pattern pieces (pure numpy).

For every pattern piece this module derives what a printed or plotted pattern
shows: the sew line (the piece boundary), the cut line (the sew line offset
outward by the seam allowance of each edge, with mitred or squared corners),
notches on both sides of each seam at identical arc lengths, the grain line
with arrows and the piece label. :func:`layout_pieces` places the pieces on a
sheet without overlaps (shelf packing of bounding boxes).

Every piece is drawn in its own frame: the pattern uv (metres) rotated so that
the grain (warp) points along +y, the way pieces are laid on fabric with the
selvage vertical. Rotation keeps lengths, so sew-line lengths are the
pattern's.
"""
from __future__ import annotations

import math
import unicodedata
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from ..cut.types import seam_names
from ..errors import ExportError
from ..pattern.types import Pattern, PatternPanel

DEFAULT_ALLOWANCE = 0.01   # m, seams
DEFAULT_HEM = 0.02         # m, hems
DEFAULT_NOTCH_SPACING = 0.10  # m between notches along a seam
NOTCH_LENGTH = 0.006       # m, slit notch cut into the allowance
MITRE_LIMIT = 3.0          # corner point at most this many allowances from the sew corner


# --------------------------------------------------------------------------- #
# small geometry helpers on plain arrays
# --------------------------------------------------------------------------- #

def polyline_length(points: np.ndarray, closed: bool = False) -> float:
    """Length of a 2D polyline.

    Parameters
    ----------
    points : (k, 2) float, metres.
    closed : bool, include the edge from the last point back to the first.
    """
    p = np.asarray(points, float)
    if closed:
        p = np.vstack([p, p[:1]])
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def signed_area(loop: np.ndarray) -> float:
    """Signed area (m^2) of a closed polygon (k, 2); > 0 when counter-clockwise."""
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def point_at_arclength(points: np.ndarray, s: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Points at arc lengths ``s`` along an open polyline.

    Returns
    -------
    xy : (m, 2) float, the points.
    edge : (m,) int, the edge index each point lies on.
    """
    p = np.asarray(points, float)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.clip(np.asarray(s, float), 0.0, cum[-1])
    edge = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
    t = np.where(seg[edge] > 0, (s - cum[edge]) / np.where(seg[edge] > 0, seg[edge], 1.0), 0.0)
    xy = p[edge] + t[:, None] * (p[edge + 1] - p[edge])
    return xy, edge


def segments_cross(loop: np.ndarray, closed: bool = True, tol: float = 1e-12) -> Optional[Tuple[int, int]]:
    """First pair of non-adjacent edges of a polygon that properly cross, or None.

    Parameters
    ----------
    loop : (k, 2) float.
    closed : bool, the polygon closes from the last point to the first.
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
        cand = (jj[None, :] >= ii + 2)
        if closed:
            cand &= ~((ii == 0) & (jj[None, :] == m - 1))
        cand &= ((lo[None, :, 0] <= hi[ii, 0]) & (hi[None, :, 0] >= lo[ii, 0]) &
                 (lo[None, :, 1] <= hi[ii, 1]) & (hi[None, :, 1] >= lo[ii, 1]))
        ci, cj = np.nonzero(cand)
        if ci.size == 0:
            continue
        i, j = ci + i0, cj
        c1 = _cross(d[i], a[j] - a[i])
        c2 = _cross(d[i], b[j] - a[i])
        c3 = _cross(d[j], a[i] - a[j])
        c4 = _cross(d[j], b[i] - a[j])
        hit = np.flatnonzero((c1 * c2 < -tol) & (c3 * c4 < -tol))
        if hit.size:
            k = hit[0]  # np.nonzero is row-major: the smallest i, then j
            return int(i[k]), int(j[k])
    return None


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _line_intersection(a0, t0, a1, t1):
    """Intersection of lines a0 + s t0 and a1 + u t1 (None when parallel)."""
    den = _cross(t0, t1)
    if abs(den) < 1e-9:
        return None
    s = _cross(a1 - a0, t1) / den
    return a0 + s * t0


def offset_loop(loop: np.ndarray, widths: np.ndarray, mitre_limit: float = MITRE_LIMIT) -> np.ndarray:
    """Offset a closed polygon outward by a width per edge (the cut line of a piece).

    Each edge is moved along its outward normal by its width; consecutive
    offset lines are intersected (a mitred corner, so both allowances of a
    sewn corner reach the same point); a convex corner whose mitre would lie
    farther than ``mitre_limit`` times the larger width from the sew corner is
    squared off; where two collinear edges have different widths a step joins
    them. Offset edges that turn over (short edges in concave stretches) are
    removed and their neighbours intersected instead, so the cut line has no
    local loops.

    Parameters
    ----------
    loop : (k, 2) float, counter-clockwise polygon (material on the left), metres.
    widths : (k,) float >= 0, width of edge ``loop[i] -> loop[i+1]``, metres.
    mitre_limit : float, see above.

    Returns
    -------
    (m, 2) float, the offset polygon, counter-clockwise, not closed (last != first).
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
    base = p + w[:, None] * nrm                  # a point on each offset line

    def corner(e0: int, e1: int) -> List[np.ndarray]:
        # the sew corner: end of e0 (== start of e1 while they are neighbours)
        v = p[(e0 + 1) % n]
        c = _cross(t[e0], t[e1])
        dot = float(np.dot(t[e0], t[e1]))
        if abs(c) < 1e-9 and dot > 0:  # collinear, same way
            a, b = v + w[e0] * nrm[e0], p[e1] + w[e1] * nrm[e1]
            return [a] if np.linalg.norm(a - b) < 1e-12 else [a, b]
        m = _line_intersection(base[e0], t[e0], base[e1], t[e1])
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

    # doubly linked ring of the edges still on the cut line; corners[e] are
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


def remove_loops(poly: np.ndarray, orientation: float = 1.0, max_iter: int = 1000,
                 return_removed: bool = False):
    """Cut the loops out of a self-crossing closed polygon.

    At each crossing the polygon splits in two closed parts; the one with the
    larger signed area times ``orientation`` (+1: keep the counter-clockwise
    outline, -1: a clockwise hole) is kept. Offsetting a curve whose parts come
    closer than twice the offset makes such loops.

    Parameters
    ----------
    poly : (k, 2) float closed polygon (last != first).

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
        x = _line_intersection(a0, a1 - a0, b0, b1 - b0)
        if x is None:  # pragma: no cover - segments_cross found a proper crossing
            break
        outer = np.vstack([p[:i + 1], x[None], p[j + 1:]])
        inner = np.vstack([x[None], p[i + 1:j + 1]])
        if orientation * signed_area(outer) >= orientation * signed_area(inner):
            p, cut_away = outer, inner
        else:
            p, cut_away = inner, outer
        removed += abs(signed_area(cut_away))
    return (p, removed) if return_removed else p


def points_in_polygon(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """(m,) bool: each point (m, 2) strictly inside the closed polygon (k, 2), by crossing number."""
    q = np.asarray(points, float)
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    x, y = q[:, 0:1], q[:, 1:2]
    straddle = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return (np.sum(straddle & (x < xc), axis=1) % 2) == 1


def cut_line(sew: np.ndarray, widths: np.ndarray, mitre_limit: float = MITRE_LIMIT,
             hole: bool = False, warnings: Optional[List[str]] = None) -> np.ndarray:
    """The cut line around one sew-line loop: :func:`offset_loop`, loops removed, checked.

    Parameters
    ----------
    sew : (k, 2) float, the loop with the material on its left (outline ccw, hole cw).
    widths : (k,) float, allowance of each edge (m).
    hole : bool, the loop is a hole of the piece.
    warnings : list or None; when given, a cut line that fails the checks is
        returned anyway and the problem appended here instead of raised.

    Raises
    ------
    ExportError when the allowance cannot go around the loop (two parts of the
    outline closer than the sum of their allowances, e.g. a narrow slit).
    """
    c = remove_loops(offset_loop(sew, widths, mitre_limit), -1.0 if hole else 1.0)
    # every sew vertex with allowance on both sides must lie inside the cut line
    # (outside it for a hole); vertices on a fold lie on it and are skipped
    w = np.asarray(widths, float)
    keep = (w > 0) & (np.roll(w, 1) > 0)
    inside = points_in_polygon(sew[keep], c)
    bad = inside if hole else ~inside
    if np.any(bad) or segments_cross(c) is not None:
        q = (sew[keep][np.argmax(bad)] if np.any(bad) else c[0]) * 1000
        msg = (f"the seam allowance does not fit around the sew line near ({q[0]:.0f}, {q[1]:.0f}) mm "
               f"(parts of the outline closer than twice the allowance); lower the allowance there")
        if warnings is None:
            raise ExportError(msg)
        warnings.append(msg)
    return c


def distance_to_polyline(points: np.ndarray, poly: np.ndarray, closed: bool = True) -> np.ndarray:
    """Distance (m) from each point (m, 2) to a polyline (k, 2)."""
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
    """Smallest t >= 0 where origin + t * direction meets the closed polygon ``loop``."""
    a = np.asarray(loop, float)
    b = np.roll(a, -1, axis=0)
    e = b - a
    den = _cross(direction, e)
    ok = np.abs(den) > 1e-14
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(a - origin, e) / den
        u = _cross(a - origin, direction) / den
    hit = ok & (t >= -1e-12) & (u >= -1e-9) & (u <= 1 + 1e-9)
    if not np.any(hit):
        return None
    return float(t[hit].min())


# --------------------------------------------------------------------------- #
# pieces
# --------------------------------------------------------------------------- #

@dataclass
class Notch:
    """A slit notch on one side of a seam.

    Attributes
    ----------
    seam : str, the seam name.
    side : ``"a"`` or ``"b"``.
    s : float, arc length (m) along this side of the seam from its first vertex.
    point : (2,) float, the notch position on the sew line (piece frame, m).
    normal : (2,) float, unit outward normal of the sew line there.
    segment : (2, 2) float, the slit: from the cut line inward, ``NOTCH_LENGTH`` long.
    """
    seam: str
    side: str
    s: float
    point: np.ndarray
    normal: np.ndarray
    segment: np.ndarray


@dataclass
class PieceDrawing:
    """Everything drawn for one pattern piece, in the piece frame (metres, grain = +y).

    Attributes
    ----------
    name, garment : str.
    rotation : (2, 2) float, piece frame = ``rotation @ uv``.
    sew : list of (k, 2) closed loops, the sew line; ``sew[0]`` is the outline
        (counter-clockwise), the others are holes (clockwise).
    sew_ids : list of (k,) int, local vertex ids of ``sew``.
    cut : list of (m, 2) closed loops, the cut line (allowance included).
    edge_allowance : list of (k,) float, allowance of each sew edge (m).
    fold : list of (j, 2) polylines on the fold (layer "mirror line").
    notches : list of :class:`Notch`.
    grain : (2, 2) float, grain line end points (bottom, top).
    arrows : list of (3, 2) polylines, arrow heads at both grain ends.
    label : list of str, label lines (ASCII).
    label_at : (2,) float, top-left of the label block.
    text_height : float, m.
    quantity : int, how many to cut.
    bbox : (2, 2) float, min and max corner of everything drawn.
    """
    name: str
    garment: str
    rotation: np.ndarray
    sew: List[np.ndarray]
    sew_ids: List[np.ndarray]
    cut: List[np.ndarray]
    edge_allowance: List[np.ndarray]
    fold: List[np.ndarray]
    notches: List[Notch]
    grain: np.ndarray
    arrows: List[np.ndarray]
    label: List[str]
    label_at: np.ndarray
    text_height: float
    quantity: int
    bbox: np.ndarray = field(default_factory=lambda: np.zeros((2, 2)))


def ascii_text(text: str) -> str:
    """7-bit ASCII rendering of a label (DXF AAMA and the PDF base fonts need it)."""
    s = unicodedata.normalize("NFKD", str(text)).encode("ascii", "ignore").decode("ascii")
    return "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in s)


def resolve_allowance(allowance: Union[None, float, Mapping], pattern: Pattern) -> Dict[str, float]:
    """Seam allowance per seam name, with ``"default"`` and ``"hem"`` entries.

    Parameters
    ----------
    allowance : None, a number (every seam) or a dict ``{"default": 0.01,
        "hem": 0.02, "fold": 0, "<seam>": ...}`` in metres; a seam is named
        as the cut names it (``garment.line``, ``garment.line#k`` for one
        stretch of a split line) or by its line (``line``: in every garment).
        None takes
        ``pattern.materials["export"]["allowance"]`` when the design has one.

    Raises
    ------
    ExportError naming the key when a value is not a finite number in
    [0, 0.1] m or a key is neither a seam name nor default/hem/fold.
    """
    if allowance is None:
        allowance = ((pattern.materials or {}).get("export") or {}).get("allowance")
    out = {"default": DEFAULT_ALLOWANCE, "hem": DEFAULT_HEM, "fold": 0.0}
    if allowance is None:
        return out
    if isinstance(allowance, (int, float)) and not isinstance(allowance, bool):
        allowance = {"default": float(allowance)}
    if not isinstance(allowance, Mapping):
        raise ExportError(f"allowance: expected a number or a dict like "
                          f"{{'default': 0.01, 'hem': 0.02, '<seam>': ...}}, got {type(allowance).__name__}")
    seams = {s.name for s in pattern.seams}
    lines = {k for n in seams for k in seam_names(n)}
    for key, value in allowance.items():
        if key not in out and key not in lines:
            raise ExportError(f"allowance[{key!r}]: not a seam of the pattern; expected 'default', 'hem', "
                              f"'fold' or one of: {', '.join(sorted(lines)) or '(no seams)'}")
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ExportError(f"allowance[{key!r}]: expected a width in metres, got {value!r}") from None
        if not math.isfinite(v) or v < 0 or v > 0.1:
            raise ExportError(f"allowance[{key!r}]: expected a width in [0, 0.1] m, got {value!r}")
        out[key] = v
    return out


def seam_allowance(widths: Mapping[str, float], seam: str) -> float:
    """Allowance (m) of seam ``seam`` from :func:`resolve_allowance`'s table:
    the most specific key naming it (see :func:`core.cut.types.seam_names`), else the default."""
    for k in seam_names(seam):
        if k in widths:
            return float(widths[k])
    return float(widths["default"])


def boundary_loops_from_faces(faces: np.ndarray) -> List[np.ndarray]:
    """Closed boundary loops (local ids) of a triangle mesh, oriented like its faces."""
    f = np.asarray(faces, int)
    half = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = {tuple(e) for e in half.tolist()}
    nxt = {}
    for a, b in half.tolist():
        if (b, a) not in key:
            nxt[a] = b
    loops, seen = [], set()
    for start in sorted(nxt):
        if start in seen:
            continue
        loop, v = [], start
        while v not in seen and v in nxt:
            seen.add(v)
            loop.append(v)
            v = nxt[v]
        if len(loop) >= 3:
            loops.append(np.asarray(loop, int))
    return loops


def piece_loops(panel: PatternPanel) -> List[np.ndarray]:
    """Boundary loops of a piece, outline first (ccw in uv), holes after (cw)."""
    loops = [np.asarray(b, int).reshape(-1) for b in panel.boundary] or boundary_loops_from_faces(panel.faces)
    loops = [b[:-1] if len(b) > 1 and b[0] == b[-1] else b for b in loops]
    uv = np.asarray(panel.uv, float)
    areas = [signed_area(uv[b]) for b in loops]
    order = np.argsort([-abs(a) for a in areas], kind="stable")
    out = []
    for rank, i in enumerate(order):
        b, a = loops[i], areas[i]
        if (rank == 0) != (a > 0):
            b = b[::-1]
        out.append(b)
    return out


def _edge_table(loops: List[np.ndarray]) -> Dict[Tuple[int, int], Tuple[int, int]]:
    """(u, v) and (v, u) -> (loop index, edge index) for every boundary edge."""
    table = {}
    for li, b in enumerate(loops):
        for ei in range(len(b)):
            u, v = int(b[ei]), int(b[(ei + 1) % len(b)])
            table[(u, v)] = (li, ei)
            table[(v, u)] = (li, ei)
    return table


def seam_sides(pattern: Pattern, panel_name: str):
    """(seam, side, local vertex ids) of every seam side lying on ``panel_name``."""
    for s in pattern.seams:
        if s.panel_a == panel_name:
            yield s, "a", np.asarray(s.verts_a, int)
        if s.panel_b == panel_name:
            yield s, "b", np.asarray(s.verts_b, int)


def notch_positions(length_a: float, length_b: float, spacing: float = DEFAULT_NOTCH_SPACING,
                    gathered: bool = False) -> Tuple[np.ndarray, np.ndarray]:
    """Arc lengths of the notches on the two sides of a seam.

    Both sides get the seam ends and the same interior positions
    ``spacing, 2 spacing, ...`` measured from the seam's first vertex, skipping
    those closer than ``spacing / 4`` to the shorter side's end. On a
    ``gathered`` seam the interior notches sit at the same *fractions* of each
    side (spaced ``spacing`` on the shorter one), so each stretch of the
    longer side is gathered into its own stretch of the shorter.

    Returns
    -------
    s_a, s_b : (k,) float arrays of equal length, metres.
    """
    lmin = min(length_a, length_b)
    interior = []
    if spacing > 0:
        k = 1
        while k * spacing <= lmin - 0.25 * spacing:
            interior.append(k * spacing)
            k += 1
    if gathered and lmin > 0:
        f = np.array(interior) / lmin
        return (np.concatenate([[0.0], f * length_a, [length_a]]),
                np.concatenate([[0.0], f * length_b, [length_b]]))
    s_a = np.array([0.0] + interior + [length_a])
    s_b = np.array([0.0] + interior + [length_b])
    return s_a, s_b


def _rotation_to_y(grain: np.ndarray) -> np.ndarray:
    g = np.asarray(grain, float)
    ang = math.pi / 2 - math.atan2(g[1], g[0])
    c, s = math.cos(ang), math.sin(ang)
    return np.array([[c, -s], [s, c]])


def _interior_point(xy: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """A point inside the piece near its area centroid (a triangle centroid)."""
    tri = xy[faces]
    cen = tri.mean(axis=1)
    area = np.abs(_cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])) * 0.5
    c = (cen * area[:, None]).sum(0) / max(area.sum(), 1e-300)
    return cen[np.argmin(np.linalg.norm(cen - c, axis=1))]


def _grain_line(xy: np.ndarray, faces: np.ndarray, sew: List[np.ndarray]) -> Tuple[np.ndarray, List[np.ndarray]]:
    """Grain line (+y in the piece frame) across the middle 70% of the chord through the piece."""
    c = _interior_point(xy, faces)
    up = np.array([0.0, 1.0])
    hits_up = [h for h in (ray_hit(c, up, loop) for loop in sew) if h is not None]
    hits_dn = [h for h in (ray_hit(c, -up, loop) for loop in sew) if h is not None]
    t_up = min(hits_up) if hits_up else 0.05
    t_dn = min(hits_dn) if hits_dn else 0.05
    lo, hi = c[1] - t_dn, c[1] + t_up
    mid, half = 0.5 * (lo + hi), 0.35 * (hi - lo)
    p0, p1 = np.array([c[0], mid - half]), np.array([c[0], mid + half])
    head = min(0.015, 0.25 * (p1[1] - p0[1]))
    dx = head * math.tan(math.radians(25))
    arrows = [np.array([[p1[0] - dx, p1[1] - head], p1, [p1[0] + dx, p1[1] - head]]),
              np.array([[p0[0] - dx, p0[1] + head], p0, [p0[0] + dx, p0[1] + head]])]
    return np.stack([p0, p1]), arrows


def _allowance_text(edge_w: List[np.ndarray]) -> str:
    vals = sorted({round(float(v) * 1000, 1) for w in edge_w for v in w if v > 0})
    if not vals:
        return "no seam allowance"
    return "allowance " + "/".join(f"{v:g}" for v in vals) + " incl."


CHAR_WIDTH = 0.6   # Helvetica's mean advance is ~0.55 em: a safe width estimate per character
TEXT_MIN = 0.0025  # m, smallest label text


def _room(sew: List[np.ndarray], y: np.ndarray, x: float, direction: float) -> float:
    """Smallest distance (m) from (x, y_k) along +-x to the sew line, over the rows y_k."""
    d = np.array([direction, 0.0])
    hits = []
    for yk in y:
        h = [t for t in (ray_hit(np.array([x, yk]), d, loop) for loop in sew) if t is not None]
        hits.append(min(h) if h else 0.0)
    return float(min(hits))


def _place_label(sew: List[np.ndarray], grain: np.ndarray, label: List[str], text_h: float):
    """Top-left corner and text height of the label, kept inside the sew line.

    Beside the grain line (1 cm to its right) where the piece is wide enough,
    else centred across it with smaller text (down to ``TEXT_MIN``).
    """
    gx = float(grain[0, 0])
    mid = 0.5 * float(grain[0, 1] + grain[1, 1])
    chars = max(len(s) for s in label)

    def rows(h):
        top = mid + 0.5 * len(label) * 1.5 * h
        return np.linspace(top, top - len(label) * 1.5 * h, 4)

    right = _room(sew, rows(text_h), gx + 0.01, 1.0)
    h = min(text_h, 0.9 * right / (CHAR_WIDTH * chars))
    if h >= 0.7 * text_h or h >= TEXT_MIN * 1.6:
        h = max(h, TEXT_MIN)
        return np.array([gx + 0.01, mid + 0.5 * len(label) * 1.5 * h]), float(h)
    left = _room(sew, rows(text_h), gx, -1.0)
    right = _room(sew, rows(text_h), gx, 1.0)
    h = float(np.clip(0.9 * (left + right) / (CHAR_WIDTH * chars), TEXT_MIN, text_h))
    width = CHAR_WIDTH * chars * h
    x0 = gx - left + 0.5 * max(left + right - width, 0.0)
    return np.array([x0, mid + 0.5 * len(label) * 1.5 * h]), h


def build_piece(pattern: Pattern, panel: PatternPanel, widths: Dict[str, float],
                notch_spacing: float = DEFAULT_NOTCH_SPACING,
                mitre_limit: float = MITRE_LIMIT, warnings: Optional[List[str]] = None) -> PieceDrawing:
    """The drawing of one piece: sew and cut lines, notches, grain line, label.

    Parameters
    ----------
    pattern : the pattern (seams, style, body size).
    panel : the piece.
    widths : from :func:`resolve_allowance`.
    notch_spacing : float, m between interior notches along a seam (0: ends only).
    warnings : list or None; when given, a cut line that does not fit is drawn
        anyway and the problem appended here (see :func:`cut_line`).
    """
    rot = _rotation_to_y(panel.grain)
    xy = np.asarray(panel.uv, float) @ rot.T
    loops = piece_loops(panel)
    table = _edge_table(loops)
    edge_w = [np.full(len(b), widths["default"]) for b in loops]
    # hems, then seams (a seam wins if an edge is listed twice), then folds
    for h in panel.hems:
        h = np.asarray(h, int)
        for u, v in zip(h[:-1], h[1:]):
            if (int(u), int(v)) in table:
                li, ei = table[(int(u), int(v))]
                edge_w[li][ei] = widths["hem"]
    for seam, side, ids in seam_sides(pattern, panel.name):
        w = seam_allowance(widths, seam.name)
        for u, v in zip(ids[:-1], ids[1:]):
            li, ei = table[(int(u), int(v))]
            edge_w[li][ei] = w
    fold_ids = getattr(panel, "fold", None)
    folds = []
    if fold_ids is not None and len(fold_ids):
        fold_ids = np.asarray(fold_ids, int)
        for u, v in zip(fold_ids[:-1], fold_ids[1:]):
            if (int(u), int(v)) in table:
                li, ei = table[(int(u), int(v))]
                edge_w[li][ei] = widths["fold"]
        folds.append(xy[fold_ids])
    sew = [xy[b] for b in loops]
    cut = []
    for li in range(len(loops)):
        # the outline is ccw and holes cw, so the material is always on the
        # left and offsetting to the right puts the allowance outside it
        found: List[str] = []
        try:
            c = cut_line(sew[li], edge_w[li], mitre_limit, hole=li > 0,
                         warnings=None if warnings is None else found)
        except ExportError as exc:
            raise ExportError(f"piece {panel.name!r}: {exc}") from None
        if warnings is not None:
            warnings.extend(f"piece {panel.name!r}: {m}" for m in found)
        cut.append(c)

    # outward normal of every boundary edge, for the notches
    notches: List[Notch] = []
    for seam, side, ids in seam_sides(pattern, panel.name):
        other = pattern.panel(seam.panel_b if side == "a" else seam.panel_a)
        other_ids = np.asarray(seam.verts_b if side == "a" else seam.verts_a, int)
        la = polyline_length(xy[ids])
        lb = polyline_length(np.asarray(other.uv, float)[other_ids])
        s_here, _ = notch_positions(la, lb, notch_spacing, gathered=bool(getattr(seam, "gathered", False)))
        pts, edges = point_at_arclength(xy[ids], s_here)
        for s, q, e in zip(s_here, pts, edges):
            li, ei = table[(int(ids[e]), int(ids[e + 1]))]
            b = loops[li]
            # the edge's outward normal; a zero-length edge borrows its neighbour's
            for k in (0, 1, -1, 2, -2):
                d = xy[b[(ei + k + 1) % len(b)]] - xy[b[(ei + k) % len(b)]]
                if np.linalg.norm(d) > 1e-12:
                    break
            nrm = np.array([d[1], -d[0]]) / max(np.linalg.norm(d), 1e-300)
            t_cut = ray_hit(q, nrm, cut[li])
            t_cut = edge_w[li][ei] if t_cut is None else t_cut
            a0 = q + t_cut * nrm
            seg = np.stack([a0, a0 - min(NOTCH_LENGTH, max(t_cut, 1e-4) * 0.9 + 1e-4) * nrm]) \
                if t_cut > 0 else np.stack([q + 0.5 * NOTCH_LENGTH * nrm, q - 0.5 * NOTCH_LENGTH * nrm])
            notches.append(Notch(seam=seam.name, side=side, s=float(s), point=q, normal=nrm, segment=seg))

    grain, arrows = _grain_line(xy, np.asarray(panel.faces, int), sew)

    size = (pattern.body or {}).get("size") or (pattern.body or {}).get("shape") or "-"
    quantity = 1
    notes = []
    if folds:
        notes.append("cut on fold")
    if panel.mirror_of:
        notes.append(f"mirror of {panel.mirror_of}")
    twins = [p.name for p in pattern.panels if p.mirror_of == panel.name]
    if twins:
        notes.append(f"mirrored by {', '.join(twins)}")
    label = [ascii_text(pattern.style or "pattern"),
             ascii_text(f"piece: {panel.name}" + (f" ({panel.garment})" if panel.garment and
                                                  not panel.name.startswith(panel.garment) else "")),
             ascii_text(f"size: {size}"),
             ascii_text(f"cut {quantity}" + ("".join(f", {n}" for n in notes))),
             ascii_text(f"units: mm, {_allowance_text(edge_w)}")]
    lo = np.min([c.min(0) for c in cut], axis=0)
    hi = np.max([c.max(0) for c in cut], axis=0)
    extent = hi - lo
    text_h = float(np.clip(min(extent) / (len(label) * 3.0), 0.003, 0.008))
    label_at, text_h = _place_label(sew, grain, label, text_h)
    piece = PieceDrawing(name=panel.name, garment=panel.garment, rotation=rot, sew=sew, sew_ids=loops,
                         cut=cut, edge_allowance=edge_w, fold=folds, notches=notches, grain=grain,
                         arrows=arrows, label=label, label_at=label_at, text_height=text_h,
                         quantity=quantity)
    tw = max(len(s) for s in label) * CHAR_WIDTH * text_h
    th = len(label) * 1.5 * text_h
    lo = np.minimum(lo, [label_at[0], label_at[1] - th])
    hi = np.maximum(hi, [label_at[0] + tw, label_at[1]])
    piece.bbox = np.stack([lo, hi])
    return piece


def build_pieces(pattern: Pattern, allowance=None, notch_spacing: Optional[float] = None,
                 progress=None, warnings: Optional[List[str]] = None) -> List[PieceDrawing]:
    """:func:`build_piece` for every piece of a validated pattern, in pattern order.

    ``warnings``: None raises on a cut line that does not fit; a list collects
    the problems instead (lenient export).
    """
    from ..progress import report
    widths = resolve_allowance(allowance, pattern)
    if notch_spacing is None:
        notch_spacing = ((pattern.materials or {}).get("export") or {}).get("notch_spacing", DEFAULT_NOTCH_SPACING)
    try:
        notch_spacing = float(notch_spacing)
    except (TypeError, ValueError):
        raise ExportError(f"notch_spacing: expected metres, got {notch_spacing!r}") from None
    if not math.isfinite(notch_spacing) or notch_spacing < 0:
        raise ExportError(f"notch_spacing: expected a distance >= 0 m, got {notch_spacing!r}")
    out = []
    for i, panel in enumerate(pattern.panels):
        report(progress, i / max(len(pattern.panels), 1), f"piece {panel.name}")
        out.append(build_piece(pattern, panel, widths, notch_spacing, warnings=warnings))
    return out


# --------------------------------------------------------------------------- #
# layout
# --------------------------------------------------------------------------- #

@dataclass
class Layout:
    """Placement of pieces on one sheet (metres, y up, origin bottom-left).

    Attributes
    ----------
    offsets : (n, 2) float, sheet position = piece-frame position + offset.
    size : (2,) float, sheet width and height.
    reserved : (2, 2) float or None, min/max corner of the reserved box (test square).
    """
    offsets: np.ndarray
    size: np.ndarray
    reserved: Optional[np.ndarray] = None


def layout_pieces(boxes: Sequence[np.ndarray], width: float = 0.9, margin: float = 0.02,
                  reserve: Optional[Tuple[float, float]] = None) -> Layout:
    """Skyline packing of bounding boxes: tallest first, each where it reaches least far down, then leftmost.

    Parameters
    ----------
    boxes : n (2, 2) arrays, min/max corners of each piece (piece frame, m).
    width : float, sheet width (m); a piece wider than that widens the sheet.
    margin : float, gap between pieces and around the sheet (m).
    reserve : (w, h) of a box kept free at the top-left (the PDF test square).

    Returns
    -------
    :class:`Layout`.
    """
    boxes = [np.asarray(b, float) for b in boxes]
    sizes = np.array([b[1] - b[0] for b in boxes]).reshape(-1, 2)
    items = [(-sizes[i, 1], -sizes[i, 0], i) for i in range(len(boxes))]
    items.sort()
    order = [i for _, _, i in items]
    entries = ([("reserve", np.asarray(reserve, float))] if reserve is not None else []) + \
              [(i, sizes[i]) for i in order]
    sheet_w = max([width] + [s[0] + 2 * margin for _, s in entries])
    # skyline packing, y measured downward from the top edge: the skyline is
    # the fill depth of each x interval; a box goes where its top would be
    # shallowest (then leftmost), spanning the intervals it covers
    xs = [margin, sheet_w - margin]          # interval boundaries
    depth = [margin]                          # fill depth of each interval
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
