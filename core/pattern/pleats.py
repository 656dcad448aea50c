"""Pleats and tucks on the flat pattern: placed on the piece as worn, then opened.

A pleat is solved closed: the pattern is flattened as the garment is worn, with
the pleat's cloth folded away, so the ease compliance of ``report["metrics"]``
is the cloth as worn. The pleat is then a post-flattening insertion
(:func:`open_pattern`): the piece is cut along the placement line's image (a
straight chord of the flat piece, from the ``from`` point on a hem, opening or seam
to where the line leaves the piece) and a strip of ``intake`` = 2 x depth
(knife, tuck) or 4 x depth (box, inverted box) is inserted; the part of the
piece beyond the line moves across by the intake, rigidly, so the depth is
kept exactly. A box pleat is two knife folds, one depth either side of its
placement line, turned under towards it.

What each stage reads:

- the pattern: ``report["pleats"]`` (:func:`attach_pleats`), per pleat its site on the cut
  panel (valid on every size: the start as a hem edge and a fraction, the aim as a triangle
  and barycentric weights or a body axis), its settings and what the opened piece measures
  (intake, depth error, extra cloth);
- export and drape: :func:`open_pattern`, the pattern with every pleated piece opened; its
  ``report["opened_pleats"]`` holds per piece the fold, placement and stitch lines as local
  vertex ids and 2D end points (:class:`OpenedLine`).

A line that starts or ends on a seam to another piece is sewn into it closed
(:func:`split_seams`): the seam is split where the strip meets it and the other piece gets a
vertex there, so the pleat's visible fold and placement line are sewn to one point of it.

Refused with the pleat's JSON path (exit 2 through the CLI): a start that is not on a hem,
opening or seam of its panel, a line that leaves its panel or ends on a dart, on a seam of its
piece with itself or on a gathered seam, a depth larger than the panel can take (the folded
cloth must lie under the piece), pleats whose folds cross or overlap, a pleat over a dart.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from ..errors import DesignError
from ..geom.mesh import boundary_loops, signed_areas_2d, vertex_normals
from ..geom.polygon import points_in_polygon
from ..geom.polyline import cumulative_lengths

#: m, a ``from`` point this far from its panel's hems and openings is refused
START_TOL = 0.03
#: fraction of the mean edge length: a vertex this close to the placement line is moved onto it
SNAP = 0.2
#: m, the strip's columns are at most this far apart (the fold lines are columns)
STRIP_EDGE = 0.006
#: m, the drape's start lifts each layer of folded cloth this far off the one below it
LAYER_GAP = 0.003
#: m, a column of a pleat's folded layers this close to a vertex of the seam they are sewn into is
#: sewn to that vertex (no sliver beside it); farther, both get a vertex
SEAM_SNAP = 0.0006
#: m, over this width beyond the folded cloth the lift of the cloth above it falls to 0
LIFT_FALLOFF = 0.015
#: share of the line's length at each end left out of the room check (the hem may slant there)
END_MARGIN = 0.1
#: why a pleat may not start or end on a seam (one line, after the seam's name)
SEAM_REASON = (
    "a pleat runs between hems, openings and seams that sew its piece to another (its folds are sewn "
    "into the seam closed); a dart, a seam of a piece with itself or a gathered seam cannot take it"
)
#: the wearer's left on the body (Anny: +x)
LEFT = np.array([1.0, 0.0, 0.0])


# ----------------------------------------------------------------- sites (design -> cut panel)


def pleat_sites(prep) -> List[dict]:
    """Every pleat of ``prep.design`` placed on its cut panel (JSON-able dicts, see the module
    docs), checked against the panel: its start on a hem, opening or seam to another piece."""
    from ..design.checks import parameter_value
    from ..design.geometry import SurfaceLocator
    from ..design.pleats import KINDS, design_pleats
    from ..design.resolve import AXIS_VECTORS, Resolver

    design, cut = prep.design, prep.cut
    found = design_pleats(design)
    if not found:
        return []
    resolver = Resolver(design, prep.body, prep.reference)
    panels = {p.name: p for p in cut.panels}
    out = []
    for full, path, pleat in found:
        if full not in panels:
            raise DesignError(path, f"pleat {pleat.name!r}: panel {full!r} is not in the cut")
        panel = panels[full]
        xyz = np.asarray(cut.panel_positions(panel, prep.reference), float)
        faces = np.asarray(panel.faces, int)
        start = resolver.position(resolver.point(pleat.start, f"{path}.from"))
        edge, lam, dist = _nearest_hem_point(cut.hems.get(full, []), xyz, start)
        seam, s_edge, s_lam, s_dist = _nearest_seam(cut.seams, full, xyz, start)
        if seam is not None and s_dist <= START_TOL and s_dist < dist:  # from a seam: sewn through the folds
            if seam.panel_a == seam.panel_b or getattr(seam, "gathered", False):
                what = "sews its panel to itself" if seam.panel_a == seam.panel_b else "is gathered"
                raise DesignError(
                    f"{path}.from",
                    f"pleat {pleat.name!r}: {pleat.start!r} is on seam {seam.name!r}, which {what}; {SEAM_REASON}",
                )
            edge, lam, dist = s_edge, s_lam, s_dist
        if edge is None or dist > START_TOL:
            far = "" if edge is None else f" ({dist * 1000:.0f} mm away)"
            raise DesignError(
                f"{path}.from",
                f"pleat {pleat.name!r}: {pleat.start!r} is not on a hem, opening or seam of {full!r}{far}",
            )
        site = {
            "name": pleat.name,
            "panel": full,
            "path": path,
            "kind": pleat.kind,
            "depth": parameter_value(pleat.depth, design.parameters),
            "direction": pleat.direction,
            "pressed": bool(pleat.pressed),
            "stitched_length": parameter_value(pleat.stitched_length, design.parameters),
            "start": [int(edge[0]), int(edge[1]), float(lam)],
            "intake_per_depth": KINDS[pleat.kind],
        }
        if pleat.towards is not None:
            aim = resolver.position(resolver.point(pleat.towards, f"{path}.towards"))
            _, tri, bary = SurfaceLocator(xyz, faces).closest(aim[None])
            site["towards"] = [int(tri[0])] + [float(b) for b in bary[0]]
        else:
            site["along"] = list(AXIS_VECTORS[pleat.along])
        out.append(site)
    return out


def _nearest_seam(seams, panel, xyz, p):
    """The seam (not a dart) of ``panel`` nearest to the point ``p`` (3,): ``(seam, edge (u, w),
    fraction along it, distance m)``; ``(None, None, 0, inf)`` without seams."""
    best = (None, None, 0.0, np.inf)
    for s in seams:
        if s.kind == "dart":
            continue
        for name, verts in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b)):
            if name == panel and len(verts) > 1:
                e, lam, d = _nearest_hem_point([verts], xyz, p)
                if d < best[3]:
                    best = (s, e, lam, d)
    return best


def _nearest_hem_point(hems, xyz, p):
    """The hem edge ``(u, w)``, the fraction along it and the distance (m) of the point of the
    panel's hems and openings nearest to ``p`` (3,); ``(None, 0, inf)`` without hems."""
    best = (None, 0.0, np.inf)
    for h in hems:
        h = np.asarray(h, int)
        a, b = xyz[h[:-1]], xyz[h[1:]]
        ab = b - a
        lam = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0, 1)
        d = np.linalg.norm(a + lam[:, None] * ab - p, axis=1)
        k = int(np.argmin(d)) if len(d) else -1
        if k >= 0 and d[k] < best[2]:
            best = ((int(h[k]), int(h[k + 1])), float(lam[k]), float(d[k]))
    return best


# ----------------------------------------------------------------- chords on a flat piece


@dataclass
class Strip:
    """One strip of folded cloth inserted along a chord of the closed piece.

    a, b : (2,) the chord's ends in the closed piece's uv (a at the pleat's start);
    side : +1 or -1, the side of the chord (along its left normal) that keeps its place (``A``);
    the other side moves by ``width`` away from it. breaks : the strip's breakpoints sigma (m
    from side A's edge) with ``x`` (m, the worn offset from the chord along its left normal) and
    the layer of each segment between them (1: right under the top cloth); folds : the sigma of
    each fold line, placements : of each placement line; stitch : (sigma, sigma) welded over
    ``stitched`` m from the start (for the drape).
    """

    pleat: str
    path: str
    a: np.ndarray
    b: np.ndarray
    side: int
    width: float
    breaks: List[float]
    x: List[float]
    layers: List[int]
    folds: List[float]
    placements: List[float]
    stitch: tuple
    stitched: float
    lift_bands: List[tuple] = field(default_factory=list)  # (side, reach m) of the top cloth lifted


def _left(d):
    return np.array([-d[1], d[0]])


def _mean_direction(uv, xyz, faces, d3):
    """The 2D direction on the piece of the body axis ``d3``: each triangle's image of it (unit),
    averaged over the piece weighted by area (a straight line across the piece, not the local
    direction at its start)."""
    e2a, e2b = uv[faces[:, 1]] - uv[faces[:, 0]], uv[faces[:, 2]] - uv[faces[:, 0]]
    e3a, e3b = xyz[faces[:, 1]] - xyz[faces[:, 0]], xyz[faces[:, 2]] - xyz[faces[:, 0]]
    # least squares coefficients of d3 in the triangle's 3D edge basis, then the same combination in 2D
    g = np.stack([np.einsum("ij,ij->i", e3a, e3a), np.einsum("ij,ij->i", e3a, e3b), np.einsum("ij,ij->i", e3b, e3b)], 1)
    r = np.stack([e3a @ d3, e3b @ d3], 1)
    det = g[:, 0] * g[:, 2] - g[:, 1] ** 2
    ok = det > 1e-30
    c0 = np.where(ok, (g[:, 2] * r[:, 0] - g[:, 1] * r[:, 1]) / np.where(ok, det, 1), 0)
    c1 = np.where(ok, (g[:, 0] * r[:, 1] - g[:, 1] * r[:, 0]) / np.where(ok, det, 1), 0)
    v = c0[:, None] * e2a + c1[:, None] * e2b
    v /= np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-300)
    area = 0.5 * np.abs(e2a[:, 0] * e2b[:, 1] - e2a[:, 1] * e2b[:, 0])
    return (area[:, None] * v).sum(axis=0)


def _push_3d(uv, xyz, faces, tri, d2):
    """The 3D image of the 2D direction ``d2`` at triangle ``tri``."""
    f = faces[tri]
    E2 = np.stack([uv[f[1]] - uv[f[0]], uv[f[2]] - uv[f[0]]], axis=1)
    E3 = np.stack([xyz[f[1]] - xyz[f[0]], xyz[f[2]] - xyz[f[0]]], axis=1)
    return E3 @ np.linalg.solve(E2, d2)


class FlatLocator:
    """Point location in a flat triangle mesh: the triangle holding each 2D point, among the
    :data:`CANDIDATES` triangles whose centroids are nearest to it (a k-d tree, built once)."""

    CANDIDATES = 16

    def __init__(self, uv, faces):
        from scipy.spatial import cKDTree

        self.uv, self.faces = np.asarray(uv, float), np.asarray(faces, int)
        self.tree = cKDTree(self.uv[self.faces].mean(axis=1))

    def locate(self, q):
        """Triangle and barycentric weights (k,), (k, 3) of points ``q`` (k, 2) (the best candidate,
        weights clipped, for a point just outside the mesh)."""
        q = np.atleast_2d(np.asarray(q, float))
        k = min(self.CANDIDATES, len(self.faces))
        _, cand = self.tree.query(q, k=k)
        cand = np.asarray(cand).reshape(len(q), k)
        T = self.uv[self.faces[cand]]  # (m, k, 3, 2)
        v0, v1 = T[:, :, 1] - T[:, :, 0], T[:, :, 2] - T[:, :, 0]
        w = q[:, None, :] - T[:, :, 0]
        den = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
        den = np.where(np.abs(den) > 1e-300, den, 1e-300)
        l1 = (w[..., 0] * v1[..., 1] - w[..., 1] * v1[..., 0]) / den
        l2 = (v0[..., 0] * w[..., 1] - v0[..., 1] * w[..., 0]) / den
        lam = np.stack([1 - l1 - l2, l1, l2], axis=-1)
        best = np.argmax(lam.min(axis=-1), axis=1)
        r = np.arange(len(q))
        b = np.clip(lam[r, best], 0, None)
        return cand[r, best], b / b.sum(axis=1, keepdims=True)


def locate_2d(uv, faces, q):
    """Triangle and barycentric weights (k,), (k, 3) of 2D points ``q`` (k, 2) in a flat mesh
    (:class:`FlatLocator`, for one query)."""
    return FlatLocator(uv, faces).locate(q)


def _inside(loop_xy, pts):
    return points_in_polygon(np.atleast_2d(np.asarray(pts, float)), loop_xy)


def _chord(uv, loops, p, d):
    """The chord of the piece on the line ``p + t d``: the inside stretch of the line that holds
    ``p`` (or starts nearest to it), as ``((point, hem edge key), (point, edge key))``, start
    first; None when the line misses the piece."""
    hits = []
    for loop in loops:
        a, b = uv[loop], uv[np.roll(loop, -1)]
        e = b - a
        den = d[0] * e[:, 1] - d[1] * e[:, 0]
        w = a - p
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (w[:, 0] * e[:, 1] - w[:, 1] * e[:, 0]) / den
            s = (w[:, 0] * d[1] - w[:, 1] * d[0]) / den
        for k in np.flatnonzero((np.abs(den) > 1e-14) & (s >= 0) & (s <= 1)):
            hits.append((float(t[k]), frozenset((int(loop[k]), int(loop[(k + 1) % len(loop)])))))
    hits.sort(key=lambda h: h[0])
    best = None
    for (t0, e0), (t1, e1) in zip(hits[:-1], hits[1:]):
        if t1 - t0 < 1e-9 or not _inside(uv[loops[0]], [p + 0.5 * (t0 + t1) * d])[0]:
            continue
        gap = 0.0 if t0 <= 1e-6 <= t1 else min(abs(t0), abs(t1))
        if best is None or gap < best[0]:
            best = (gap, ((p + t0 * d, e0), (p + t1 * d, e1)))
    return None if best is None else best[1]


def _hem_edges(hems) -> set:
    out = set()
    for h in hems:
        h = [int(v) for v in h]
        out.update(frozenset(e) for e in zip(h[:-1], h[1:]))
    return out


def piece_strips(piece, sites: List[dict], darts=(), seams=()) -> List[Strip]:
    """The strips of the pleats ``sites`` on the closed ``piece`` (a PatternPanel), checked:
    each chord inside the piece and ending on a hem, opening or seam to another piece (``seams``: the pattern's seams,
    to name one a line ends on), room for the folded cloth under the piece, no two pleats' cloth
    overlapping, no pleat over a dart (``darts``: the piece's dart seams)."""
    uv, xyz, faces = np.asarray(piece.uv, float), np.asarray(piece.xyz, float), np.asarray(piece.faces, int)
    loops = [np.asarray(b, int) for b in boundary_loops(faces)]
    hem_edges = _hem_edges(piece.hems)
    seam_of = {}  # boundary edge -> the seam along it
    for sm in seams:
        for name, verts in ((sm.panel_a, sm.verts_a), (sm.panel_b, sm.verts_b)):
            if name == piece.name:
                seam_of.update({e: sm for e in _hem_edges([verts])})
    out, bands = [], []
    for site in sites:
        path, name = site["path"], site["name"]
        u, w, lam = site["start"]
        a = (1 - lam) * uv[u] + lam * uv[w]
        if "towards" in site:
            t = site["towards"]
            aim = np.asarray(t[1:]) @ uv[faces[t[0]]]
            d = aim - a
            if np.linalg.norm(d) < 1e-4:
                raise DesignError(f"{path}.towards", f"pleat {name!r}: its towards point is its start")
        else:
            d = _mean_direction(uv, xyz, faces, np.asarray(site["along"], float))
        d = d / max(np.linalg.norm(d), 1e-300)
        if not _inside(uv[loops[0]], [a + 1e-4 * d])[0]:
            raise DesignError(f"{path}.from", f"pleat {name!r}: its line runs out of its panel {site['panel']!r}")
        n = _left(d)
        depth = float(site["depth"])
        # the wearer's side of the line's left normal: which way the folded cloth lies
        mid_t, _ = locate_2d(uv, faces, [a + 0.05 * d])
        toward_left = float(_push_3d(uv, xyz, faces, int(mid_t[0]), n) @ LEFT) > 0
        s_dir = 1 if toward_left == (site["direction"] == "left") else -1
        kind = site["kind"]
        if kind == "box":
            lines = [(a + depth * n, -1), (a - depth * n, +1)]  # two knife folds turned under towards the line
        else:
            lines = [(a, s_dir)]
        fixed = site.get("ends") if len(site.get("ends") or ()) == len(lines) else None
        found = []
        for k, (p0, side) in enumerate(lines):
            ends = _fixed_ends(uv, fixed[k]) if fixed else _chord(uv, loops, p0, d)
            if ends is None:
                raise DesignError(f"{path}.from", f"pleat {name!r}: its line does not cross {site['panel']!r}")
            (pa, edge_a), (pb, edge_b) = ends
            found.append([_edge_point(uv, pa, edge_a), _edge_point(uv, pb, edge_b)])
            for edge, field_ in ((edge_a, "from"), (edge_b, "towards" if "towards" in site else "along")):
                if edge not in hem_edges and not _sewn_through(seam_of.get(edge)):
                    seam = f"seam {seam_of[edge].name!r}" if edge in seam_of else "a dart or seam"
                    raise DesignError(
                        f"{path}.{field_}", f"pleat {name!r}: its line meets {seam} of {site['panel']!r}; {SEAM_REASON}"
                    )
            L = float(np.linalg.norm(pb - pa))
            ts = np.linspace(0.0, 1.0, 41)
            if not _inside(uv[loops[0]], pa + np.outer(ts[1:-1], pb - pa)).all() or any(
                _inside(uv[h], pa + np.outer(ts[1:-1], pb - pa)).any() for h in loops[1:]
            ):
                raise DesignError(f"{path}.from", f"pleat {name!r}: its line leaves its panel {site['panel']!r}")
            strip = _strip(name, path, kind, pa, pb, side, depth, float(site["stitched_length"]))
            # room: the folded cloth lies under the piece on each band's side
            inner = ts[(ts >= END_MARGIN) & (ts <= 1 - END_MARGIN)]
            for bside, reach in strip.lift_bands:
                q = pa + np.outer(inner, pb - pa) + bside * reach * _left((pb - pa) / L)
                if not _inside(uv[loops[0]], q).all():
                    raise DesignError(
                        f"{path}.depth",
                        f"pleat {name!r}: depth {depth * 1000:.1f} mm is more than panel {site['panel']!r} can take "
                        f"(the folded cloth would reach past its edge)",
                    )
                band = np.array(
                    [pa, pb, pb + bside * reach * _left((pb - pa) / L), pa + bside * reach * _left((pb - pa) / L)]
                )
                for other_name, other in bands:
                    if other_name != name and _overlap(band, other):
                        raise DesignError(
                            f"{path}.depth", f"pleat {name!r}: its folds cross or overlap pleat {other_name!r}"
                        )
                for s in darts:
                    legs = np.concatenate([uv[np.asarray(s.verts_a, int)], uv[np.asarray(s.verts_b, int)]])
                    if _inside(band, legs).any() or _segments_cross(pa, pb, legs):
                        raise DesignError(f"{path}.from", f"pleat {name!r} lies on dart {s.name!r}")
                bands.append((name, band))
            out.append(strip)
        site["ends"] = fixed or found  # the same hem points on every size (graded files share their outlines)
    return out


def _sewn_through(seam) -> bool:
    """A pleat's line may end on ``seam`` (a PatternSeam or None): one that sews two pieces, not
    gathered (the pleat is folded closed and the seam sewn through its layers, :func:`split_seams`)."""
    return seam is not None and seam.panel_a != seam.panel_b and not getattr(seam, "gathered", False)


def _edge_point(uv, p, edge) -> list:
    """``[u, w, fraction]`` of the point ``p`` on the edge ``{u, w}`` (u < w)."""
    u, w = sorted(int(v) for v in edge)
    e = uv[w] - uv[u]
    return [u, w, float(np.clip((p - uv[u]) @ e / max(e @ e, 1e-300), 0.0, 1.0))]


def _fixed_ends(uv, ends):
    """The chord between two recorded hem points ``[[u, w, fraction], [u, w, fraction]]``."""
    return tuple(((1 - f) * uv[u] + f * uv[w], frozenset((u, w))) for u, w, f in ends)


def _overlap(p, q) -> bool:
    """Two convex quadrilaterals (4, 2) overlap (more than touching along an edge)."""
    shrink = lambda r: r.mean(0) + 0.999 * (r - r.mean(0))  # noqa: E731
    p, q = shrink(p), shrink(q)
    for poly in (p, q):
        for i in range(4):
            e = poly[(i + 1) % 4] - poly[i]
            nrm = _left(e)
            pp, qq = p @ nrm, q @ nrm
            if pp.max() <= qq.min() or qq.max() <= pp.min():
                return False
    return True


def _segments_cross(a, b, pts) -> bool:
    """The segment a-b crosses the polyline ``pts`` (k, 2) anywhere."""
    n = _left(b - a)
    s = (pts - a) @ n
    d = b - a
    t = (pts - a) @ d / max(d @ d, 1e-300)
    sign = np.sign(s)
    for i in range(len(pts) - 1):
        if sign[i] * sign[i + 1] < 0:
            lam = s[i] / (s[i] - s[i + 1])
            tt = t[i] + lam * (t[i + 1] - t[i])
            if 0 <= tt <= 1:
                return True
    return False


def _strip(name, path, kind, a, b, side, depth, stitched) -> Strip:
    """The strip of one fold set (see :class:`Strip`): a knife fold (knife, tuck, each half of a
    box pleat) or an inverted box pleat (two knife folds meeting on the line)."""
    d = depth
    if kind == "inverted_box":
        s = side
        return Strip(
            name,
            path,
            a,
            b,
            s,
            4 * d,
            [0, d, 2 * d, 3 * d, 4 * d],
            [0, s * d, 0, -s * d, 0],
            [1, 2, 2, 1],
            [0, d, 3 * d, 4 * d],
            [2 * d],
            (0, 4 * d),
            stitched,
            [(s, d), (-s, d)],
        )
    return Strip(
        name,
        path,
        a,
        b,
        side,
        2 * d,
        [0, d, 2 * d],
        [0, side * d, 0],
        [1, 2],
        [0, d],
        [2 * d],
        (0, 2 * d),
        stitched,
        [(side, d)],
    )


# ----------------------------------------------------------------- opening a piece


@dataclass
class OpenedLine:
    """A line drawn on an opened piece: ``kind`` ``"fold"`` or ``"placement"``, its vertices
    (local ids, start to end) and the pleat's name."""

    pleat: str
    kind: str
    ids: List[int]
    strip: int = 0


def _split_along(uv, attrs, faces, a, b, tol):
    """Split the triangles of a flat mesh crossed by the chord a-b (its ends on the boundary).

    ``attrs``: per-vertex arrays (n, k) interpolated like ``uv`` at each new vertex. Returns uv,
    attrs, faces, the parent (closed) face of each face, the signed distance of every vertex
    from the chord (0 on it), its fraction along the chord, and the split edges
    ``{(p, q): new vertex}``."""
    d = b - a
    L = float(np.linalg.norm(d))
    e, n = d / L, _left(d / L)
    s = (uv - a) @ n
    t = (uv - a) @ e / L
    faces = np.asarray(faces, int)
    # the outline keeps its vertices: the line always meets it at a new vertex (the same on every size)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    key, count = np.unique(edges[:, 0] * len(uv) + edges[:, 1], return_counts=True)
    outline = np.zeros(len(uv), bool)
    outline[np.concatenate([key[count == 1] // len(uv), key[count == 1] % len(uv)])] = True
    near = (np.abs(s) < tol) & (t > -1e-9) & (t < 1 + 1e-9) & ~outline
    area0 = signed_areas_2d(uv, faces)
    for _ in range(3):  # a triangle the snap would flatten or turn over keeps its vertices where they were
        moved = uv - np.where(near, s, 0.0)[:, None] * n
        bad = near[faces].any(axis=1) & (signed_areas_2d(moved, faces) <= 0.05 * area0)
        if not bad.any():
            break
        near[faces[bad].ravel()] = False
    uv = uv - np.where(near, s, 0.0)[:, None] * n
    s = np.where(near, 0.0, s)
    uv_l, s_l, t_l = list(uv), list(s), list(t)
    at_l = [list(x) for x in attrs]
    cache: Dict[tuple, int] = {}

    def cross(p, q):
        key = (min(p, q), max(p, q))
        if key not in cache:
            lam = s_l[p] / (s_l[p] - s_l[q])
            x = uv_l[p] + lam * (uv_l[q] - uv_l[p])
            x = x - ((x - a) @ n) * n
            uv_l.append(x)
            for arr in at_l:
                arr.append(arr[p] + lam * (arr[q] - arr[p]))
            s_l.append(0.0)
            t_l.append(float((x - a) @ e / L))
            cache[key] = len(uv_l) - 1
        return cache[key]

    def crossing_t(p, q):
        lam = s_l[p] / (s_l[p] - s_l[q])
        return t_l[p] + lam * (t_l[q] - t_l[p])

    sgn = np.sign(np.asarray(s_l)[faces])
    crossed = (sgn > 0).any(axis=1) & (sgn < 0).any(axis=1)
    out, parent = [faces[~crossed]], [np.flatnonzero(~crossed)]
    for fi in np.flatnonzero(crossed):
        f, sg = [int(v) for v in faces[fi]], sgn[fi]
        new = [f]
        if (sg == 0).any():
            k = int(np.flatnonzero(sg == 0)[0])
            v0, v1, v2 = f[k], f[(k + 1) % 3], f[(k + 2) % 3]
            if -1e-6 <= crossing_t(v1, v2) <= 1 + 1e-6:
                q = cross(v1, v2)
                new = [[v0, v1, q], [v0, q, v2]]
        else:
            k = [i for i in range(3) if sg[i] != sg[(i + 1) % 3] and sg[i] != sg[(i + 2) % 3]][0]
            v0, v1, v2 = f[k], f[(k + 1) % 3], f[(k + 2) % 3]
            if -1e-6 <= crossing_t(v0, v1) <= 1 + 1e-6:
                q1, q2 = cross(v0, v1), cross(v0, v2)
                new = [[v0, q1, q2], [q1, v1, v2], [q1, v2, q2]]
        out.append(np.asarray(new, int))
        parent.append(np.full(len(new), fi))
    attrs = [np.array(x) for x in at_l]
    uv, faces, parent = np.array(uv_l), np.concatenate(out), np.concatenate(parent)
    s, t = np.array(s_l), np.array(t_l)
    rim = {m for (p, q), m in cache.items() if outline[p] and outline[q]}  # where the line meets the outline
    gone = _merge_close(uv, faces, s, t, L, tol, n_in=len(outline), keep=rim)
    if gone:
        alive = np.ones(len(uv), bool)
        alive[list(gone)] = False
        into = np.arange(len(uv))
        for v, w in gone.items():
            into[v] = w
        while np.any(into[into] != into):  # a vertex merged into one merged later
            into = into[into]
        new_id = np.cumsum(alive) - 1
        faces = new_id[into[faces]]
        ok = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 2] != faces[:, 0])
        faces, parent = faces[ok], parent[ok]
        uv, s, t, attrs = uv[alive], s[alive], t[alive], [a[alive] for a in attrs]
        cache = {k: int(new_id[into[m]]) for k, m in cache.items()}
    return uv, attrs, faces, parent, s, t, cache


def _merge_close(uv, faces, s, t, length, gap, n_in, keep) -> Dict[int, int]:
    """The new vertices on the line (s == 0, made by the split, not in ``keep``: where it meets the
    outline) closer than ``gap`` (m) to the line vertex before them, merged into it where no
    triangle turns over: ``{merged: kept}``. A row of the strip then never lies a sliver's width
    from the next (at 5 mm edges 14 % of the rows were under 1 mm apart, down to 4 um: their
    triangles tore at the drape's first frame)."""
    on = np.flatnonzero((s == 0) & (t > -1e-9) & (t < 1 + 1e-9))
    on = on[np.argsort(t[on], kind="stable")]
    faces = faces.copy()
    area0 = signed_areas_2d(uv, faces)
    gone: Dict[int, int] = {}
    prev = int(on[0]) if len(on) else -1
    for v in on[1:].tolist():
        if (t[v] - t[prev]) * length >= gap:
            prev = v
            continue
        for drop, stay in ((v, prev), (prev, v)):
            if drop < n_in or drop in keep:
                continue
            hit = np.flatnonzero((faces == drop).any(axis=1))
            moved = np.where(faces[hit] == drop, stay, faces[hit])
            live = (moved != np.roll(moved, 1, axis=1)).all(axis=1)
            if (signed_areas_2d(uv, moved[live]) <= 0.05 * area0[hit][live]).any():
                continue
            faces[hit] = moved
            gone[drop] = stay
            break
        prev = prev if prev not in gone else gone[prev]
        if v not in gone:
            prev = v
    return gone


def _columns(strip: Strip) -> np.ndarray:
    """The strip's column positions sigma (m): its breakpoints, each segment split into columns at
    most :data:`STRIP_EDGE` apart."""
    cols = [0.0]
    for lo, hi in zip(strip.breaks[:-1], strip.breaks[1:]):
        k = max(int(np.ceil((hi - lo) / STRIP_EDGE - 1e-9)), 1)
        cols += list(np.linspace(lo, hi, k + 1)[1:])
    return np.asarray(cols)


def _layer_lift(strip: Strip, sigma: float) -> float:
    """The drape's start lift (m) of the strip's column at ``sigma``: the layer under the top
    cloth highest; a fold between two layers half way."""
    lifts = [(2 - k) * LAYER_GAP for k in strip.layers]
    for i, (lo, hi) in enumerate(zip(strip.breaks[:-1], strip.breaks[1:])):
        if abs(sigma - lo) < 1e-12 and i > 0:
            return 0.5 * (lifts[i - 1] + lifts[i])
        if lo - 1e-12 <= sigma <= hi + 1e-12:
            return lifts[i]
    return 0.0


def open_piece(piece, strips: List[Strip], next_id: int, inside: np.ndarray, ends: list = None):
    """The piece opened along every strip (see the module docs): a copy of the PatternPanel with the
    strips' vertices and faces, its hems carried through the strips, and the lines drawn on it.

    ``next_id``: the first free global vertex id; ``inside``: a point inside the garment (the xyz of
    the opened piece is its drape start: the folded layers lifted off one another, away from it).
    Returns ``(piece, lines, stitches, next_id)``: lines a list of :class:`OpenedLine`, stitches
    ``(pleat, ids_a, ids_b)`` welded by the drape. ``ends`` (a list, optional) gets one
    ``(pleat, p, q, lam, at_p, at_q, cols)`` per end of a line on an edge ``p``-``q`` of the closed
    outline (local ids): the line met it ``lam`` of the way from ``p``, and the opened piece's
    outline runs ``p``, ``at_p``, the strip's row, ``at_q``, ``q`` (:func:`split_seams`); ``cols``
    lists that row's vertices from side A's copy to side B's vertex as ``(id, offset, breakpoint)``:
    where each lies along the outline as worn (the pleat closed: m from the line, positive towards
    ``p``) and whether it is one of the strip's breakpoints (a fold or placement line)."""
    closed_uv = np.asarray(piece.uv, float)
    closed_xyz = np.asarray(piece.xyz, float)
    closed_faces = np.asarray(piece.faces, int)
    normals = vertex_normals(closed_xyz, closed_faces)
    if np.mean(np.einsum("ij,ij->i", normals, closed_xyz - inside)) < 0:
        normals = -normals
    mean_edge = float(np.mean(np.linalg.norm(closed_uv[closed_faces[:, 1]] - closed_uv[closed_faces[:, 0]], axis=1)))
    closed_locator = FlatLocator(closed_uv, closed_faces)
    uv, faces = closed_uv.copy(), closed_faces.copy()
    # per vertex: body position, closed-piece position, normal, global id (-1: new), drape lift
    xyz, cl, nrm = closed_xyz.copy(), closed_uv.copy(), normals.copy()
    vids = np.asarray(piece.vertex_ids, int).copy()
    parent = np.arange(len(faces))
    hems = [list(map(int, h)) for h in piece.hems]
    lines: List[OpenedLine] = []
    stitches = []
    lifts = []  # (vertex ids, lift) of the cloth above folded layers, applied at the end (max)
    strip_lift = {}  # strip vertex -> lift
    canon = []  # per strip the new vertices on the outline, in a fixed order
    end_rec = []  # the lines' ends on the closed outline (see ``ends``)
    for n_strip, strip in enumerate(strips):
        # the chord in the current (partly opened) piece: the closed chord moved with its side
        flat = faces[parent >= 0]  # the strips' faces lie folded in the closed frame: not those
        a_cur, b_cur = _moved_point(strip.a, cl, uv, flat), _moved_point(strip.b, cl, uv, flat)
        n0 = len(uv)
        uv, (xyz, cl, nrm, vf), faces, par, s, t, cut = _split_along(
            uv, [xyz, cl, nrm, vids[:, None].astype(float)], faces, a_cur, b_cur, SNAP * mean_edge
        )
        parent = parent[par]
        vids = np.r_[vids, -np.ones(len(uv) - n0, int)]
        for (p, q), m in cut.items():  # a hem edge split by the line gets the new vertex
            for h in hems:
                for i in range(len(h) - 1):
                    if {h[i], h[i + 1]} == {p, q}:
                        h.insert(i + 1, m)
                        break
        on_line = np.flatnonzero((s == 0) & (t > -1e-3) & (t < 1 + 1e-3))
        on_line = on_line[np.argsort(t[on_line])]
        if len(on_line) < 2 or t[on_line[0]] > 1e-3 or t[on_line[-1]] < 1 - 1e-3:
            raise DesignError(strip.path, f"pleat {strip.pleat!r}: its line does not cross its piece")
        a_faces = np.sign(s[faces].sum(axis=1)) == strip.side
        b_set = set(np.unique(faces[~a_faces]).tolist())
        # side A keeps its place and gets copies of the line's vertices
        copy_of = {int(v): len(uv) + k for k, v in enumerate(on_line)}
        uv, xyz, cl, nrm = (np.vstack([x, x[on_line]]) for x in (uv, xyz, cl, nrm))
        vids = np.r_[vids, -np.ones(len(on_line), int)]
        fa = faces[a_faces]
        remap = np.arange(len(uv))
        for v, c in copy_of.items():
            remap[v] = c
        faces = faces.copy()
        faces[a_faces] = remap[fa]
        a_set = set(np.unique(faces[a_faces]).tolist())
        if a_set & b_set:
            raise DesignError(
                strip.path, f"pleat {strip.pleat!r}: its line leaves its piece (the piece is not cut in two)"
            )
        # side B moves across by the strip's width
        cn = _left((b_cur - a_cur) / np.linalg.norm(b_cur - a_cur))
        uv[sorted(b_set)] += -strip.side * strip.width * cn
        # the strip: rows along the line, columns across it
        sig = _columns(strip)
        grid = np.empty((len(on_line), len(sig)), int)
        grid[:, 0] = [copy_of[int(v)] for v in on_line]
        grid[:, -1] = on_line
        ccn = _left((strip.b - strip.a) / np.linalg.norm(strip.b - strip.a))
        for j in range(1, len(sig) - 1):
            grid[:, j] = np.arange(len(uv), len(uv) + len(on_line))
            q = strip.a + np.outer(t[on_line], strip.b - strip.a) + np.interp(sig[j], strip.breaks, strip.x) * ccn
            tri, bary = closed_locator.locate(q)
            uv = np.vstack([uv, uv[grid[:, 0]] - strip.side * sig[j] * cn])
            xyz = np.vstack([xyz, np.einsum("ij,ijk->ik", bary, closed_xyz[closed_faces[tri]])])
            nrm = np.vstack([nrm, np.einsum("ij,ijk->ik", bary, normals[closed_faces[tri]])])
            cl = np.vstack([cl, q])
            vids = np.r_[vids, -np.ones(len(on_line), int)]
            strip_lift.update({int(v): _layer_lift(strip, sig[j]) for v in grid[:, j]})
        new_faces = []
        for i in range(len(on_line) - 1):
            for j in range(len(sig) - 1):
                p, q, r, w = grid[i, j], grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1]
                for tri in ([p, q, r], [p, r, w]):
                    e1, e2 = uv[tri[1]] - uv[tri[0]], uv[tri[2]] - uv[tri[0]]
                    new_faces.append(tri if e1[0] * e2[1] - e1[1] * e2[0] > 0 else [tri[0], tri[2], tri[1]])
        faces = np.vstack([faces, np.asarray(new_faces, int)])
        parent = np.r_[parent, -np.ones(len(new_faces), int)]
        # the cloth over the folded layers (within reach of the line, on the band's side) is lifted
        for bside, reach in strip.lift_bands:
            verts = np.asarray(sorted(a_set if bside == strip.side else b_set), int)
            dd = (cl[verts] - strip.a) @ ccn * bside
            w = np.clip((reach + LIFT_FALLOFF - dd) / LIFT_FALLOFF, 0, 1) * (dd >= -1e-9)
            lifts.append((verts, 2 * LAYER_GAP * w))
        # hems crossing the line run through the strip's columns
        row = {int(v): i for i, v in enumerate(on_line)}
        hems = [_through_strip(h, grid, row, a_set) for h in hems]
        for j, sg in enumerate(sig):
            if _on(sg, strip.folds):
                lines.append(OpenedLine(strip.pleat, "fold", [int(v) for v in grid[:, j]], n_strip))
            elif _on(sg, strip.placements):
                lines.append(OpenedLine(strip.pleat, "placement", [int(v) for v in grid[:, j]], n_strip))
        # the line's ends on the closed outline: which side each of the split edge's ends lies on
        for (p, q), m in cut.items():
            r = row.get(int(m))
            if p < len(closed_uv) and q < len(closed_uv) and r in (0, len(on_line) - 1):
                lam = float(np.linalg.norm(cl[m] - cl[p]) / max(np.linalg.norm(cl[q] - cl[p]), 1e-300))
                at = (int(grid[r, 0]), int(grid[r, -1]))  # side A's copy, side B's vertex
                p_on_a = int(p) in a_set
                # each column's worn offset along the outline from the line, positive towards p
                to_p = strip.side if p_on_a else -strip.side
                cols = [
                    (int(grid[r, j]), to_p * float(np.interp(sg, strip.breaks, strip.x)), _on(sg, strip.breaks))
                    for j, sg in enumerate(sig)
                ]
                end_rec.append((strip.pleat, int(p), int(q), lam, at[0 if p_on_a else 1], at[1 if p_on_a else 0], cols))
        j0, j1 = (int(np.argmin(np.abs(sig - x))) for x in strip.stitch)
        arc = cumulative_lengths(uv[grid[:, 0]])
        held = max(int(np.searchsorted(arc, strip.stitched + 1e-9, side="right")), 1)
        stitches.append((strip.pleat, [int(v) for v in grid[:held, j0]], [int(v) for v in grid[:held, j1]]))
        canon.append([grid[0, -1], grid[-1, -1], grid[0, 0], grid[-1, 0], *grid[0, 1:-1], *grid[-1, 1:-1]])
    lift = np.zeros(len(uv))
    for verts, w in lifts:
        lift[verts] = np.maximum(lift[verts], w)
    for v, w in strip_lift.items():
        lift[v] = w
    # new vertices numbered outline first, strip by strip: the outline's ids are the same on every size
    order = list(range(len(closed_uv)))
    seen = set(order)
    for v in [int(x) for c in canon for x in c] + list(range(len(closed_uv), len(uv))):
        if v not in seen:
            seen.add(v)
            order.append(v)
    order = np.asarray(order)
    index = np.empty(len(order), int)
    index[order] = np.arange(len(order))
    uv, xyz, nrm, vids, lift = uv[order], xyz[order], nrm[order], vids[order], lift[order]
    faces = index[faces]
    hems = [[int(index[v]) for v in h] for h in hems]
    lines = [OpenedLine(x.pleat, x.kind, [int(index[v]) for v in x.ids], x.strip) for x in lines]
    stitches = [(n, [int(index[v]) for v in a], [int(index[v]) for v in b]) for n, a, b in stitches]
    if ends is not None:
        ends += [
            (n, p, q, lam, int(index[x]), int(index[y]), [(int(index[c]), o, b) for c, o, b in cols])
            for n, p, q, lam, x, y, cols in end_rec
        ]
    new = vids < 0
    vids[new] = np.arange(next_id, next_id + int(new.sum()))
    nrm = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    opened = copy.copy(piece)
    opened.uv, opened.faces, opened.vertex_ids = uv, faces, vids
    opened.xyz = xyz + lift[:, None] * nrm
    opened.hems = [np.asarray(h, int) for h in hems]
    opened.boundary = [_rotated(np.asarray(x, int), piece.boundary) for x in boundary_loops(faces)]
    tw, tg = np.asarray(piece.target_weft, float), np.asarray(piece.target_warp, float)
    inherit = np.where(parent >= 0, parent, 0)
    opened.target_weft = np.where(parent >= 0, tw[inherit], 1.0)
    opened.target_warp = np.where(parent >= 0, tg[inherit], 1.0)
    opened._scales = None
    opened.achieved_weft, opened.achieved_warp, _ = opened.scales()
    return opened, lines, stitches, next_id + int(new.sum())


def _on(sigma: float, marks) -> bool:
    """The strip column at ``sigma`` is one of ``marks`` (a strip's breakpoints, folds or placements)."""
    return any(abs(sigma - f) < 1e-12 for f in marks)


def _rotated(loop, closed_loops):
    """``loop`` turned to start where the closed piece's outline starts (else at its smallest id)."""
    firsts = [int(b[0]) for b in closed_loops if len(b)]
    hit = [k for k, v in enumerate(loop) if int(v) in firsts]
    k = hit[0] if hit else int(np.argmin(loop))
    return np.roll(loop, -k)


def _moved_point(p, cl, uv, faces):
    """Where the closed-piece point ``p`` (2,) lies in the current (partly opened) piece: through the
    triangle of the closed positions ``cl`` that holds it."""
    tri, bary = locate_2d(cl, faces, [p])
    return bary[0] @ uv[faces[tri[0]]]


def _through_strip(h, grid, row, a_set) -> list:
    """A hem polyline with each vertex on the line replaced by the strip's row there, from the
    side the hem comes from to the side it goes to."""
    out = []
    for k, v in enumerate(h):
        if v not in row:
            out.append(v)
            continue
        chain = [int(x) for x in grid[row[v]]]  # side A's copy ... side B's vertex
        prev = h[k - 1] if k > 0 else None
        nxt = h[k + 1] if k + 1 < len(h) else None
        from_a = (prev in a_set) if prev is not None else (nxt not in a_set)
        out += chain if from_a else chain[::-1]
    return out


# ----------------------------------------------------------------- the pattern


def attach_pleats(pattern, prep) -> None:
    """Place the pleats of ``prep.design`` on ``pattern`` (solved closed, as worn) and record them in
    ``pattern.report["pleats"]``: per pleat its site, settings and what the opened piece measures
    (:func:`measure_pleats`). Raises DesignError (the pleat's JSON path) for a pleat the pattern
    cannot take. A design without pleats leaves the pattern as it is."""
    sites = pleat_sites(prep)
    if not sites:
        return
    # the hem points each line ends at, found on the first pattern of this preparation, are kept for
    # every other size (graded files need the same outline vertices)
    known = getattr(prep, "_pleat_ends", None)
    known = known if isinstance(known, dict) else {}
    for s in sites:  # with where the folds were sewn into a seam (split_seams)
        s.update(copy.deepcopy(known.get(_site_key(s), {})))
    pattern.report["pleats"] = sites
    measure_pleats(pattern)
    known.update({_site_key(s): copy.deepcopy({k: s[k] for k in ("ends", "sewn") if k in s}) for s in sites})
    try:
        prep._pleat_ends = known
    except AttributeError:  # a container without attributes: each size finds its own ends
        pass


def _site_key(site) -> str:
    import json

    fields = ("name", "panel", "kind", "depth", "direction", "start", "towards", "along")
    return json.dumps({k: site.get(k) for k in fields}, sort_keys=True)


def open_pattern(pattern, stitch: bool = False):
    """``pattern`` with every pleated piece opened (:func:`open_piece`); the pattern itself when it
    has no pleats. ``stitch``: add each pleat's stitching as a seam of the piece with itself (the
    drape welds it; export leaves it out). The copy's ``report["opened_pleats"]`` holds per piece
    the lines drawn on it: ``{"pleat", "kind", "ids"}``."""
    from ..pattern.types import Pattern, PatternSeam

    sites = pattern.report.get("pleats") or []
    if not sites:
        return pattern
    next_id = 1 + max(int(np.max(p.vertex_ids)) for p in pattern.panels if len(p.vertex_ids))
    panels, seams, drawn, ends = [], list(pattern.seams), {}, {}
    for piece in pattern.panels:
        mine = [s for s in sites if s["panel"] == piece.name]
        if not mine:
            panels.append(piece)
            continue
        darts = [s for s in pattern.seams if s.kind == "dart" and s.panel_a == piece.name]
        strips = piece_strips(piece, mine, darts, [s for s in pattern.seams if s.kind != "dart"])
        garment = np.concatenate([np.asarray(p.xyz) for p in pattern.panels if p.garment == piece.garment])
        ends[piece.name] = []
        opened, lines, stitches, next_id = open_piece(piece, strips, next_id, garment.mean(axis=0), ends[piece.name])
        panels.append(opened)
        gids = np.asarray(opened.vertex_ids, int)
        drawn[piece.name] = [
            {"pleat": x.pleat, "kind": x.kind, "ids": x.ids, "gids": gids[x.ids].tolist(), "strip": x.strip}
            for x in lines
        ]
        if stitch:
            for k, (name, ia, ib) in enumerate(stitches):
                seams.append(PatternSeam(f"{name}#stitch{k}", piece.name, piece.name, np.asarray(ia), np.asarray(ib)))
    panels, seams, next_id = split_seams(panels, seams, ends, next_id, sites=sites, drawn=drawn)
    report = dict(pattern.report)
    report["opened_pleats"] = drawn
    return Pattern(
        style=pattern.style,
        body=pattern.body,
        garments=pattern.garments,
        panels=panels,
        seams=seams,
        pins=pattern.pins,
        materials=pattern.materials,
        mode=pattern.mode,
        report=report,
    )


def split_seams(panels, seams, ends: Dict[str, list], next_id: int, sites=None, drawn=None):
    """Sew a pleat into the seam it starts or ends on: the pleat folded closed, the seam sewn through it.

    ``ends``: per opened piece the ends of its pleats' lines on the closed outline (``ends`` of
    :func:`open_piece`). Where one lies on a seam to another piece, the opened piece's side of the
    seam runs ``p``, ``at_p`` and goes on from ``at_q``, ``q``. The seam is split there into parts
    (named ``<seam>#p0``, ``#p1``, ... along it), and the other piece gets a vertex on its edge at the
    same fraction, which ends both parts: the pleat's visible fold and its placement line (welded
    by the pleat's stitching at its start) are sewn to that one point, as a pattern maker folds the
    pleat, pins it and sews the seam through it; each part's two sides keep their closed lengths
    (notches match), and the seam's ends there are both pieces' notches.

    The folded layers are in the seam too (:func:`_sew_layers`): each layer of the strip's edge
    (from the line out to an inner fold, or back) is sewn to the other piece's edge over the
    stretch of the seam it lies under when the pleat is closed, by a seam ``<seam>#layer<k>``
    from the line's point outwards, so the seam runs through every layer of the closed pleat. The
    stretch gets a vertex on both pieces at each of the layers' columns and each layer one at
    each vertex of the stretch (a column within :data:`SEAM_SNAP` of one is sewn to it), and the
    seam part beside the line takes them: the top cloth, every layer and the other piece are one
    point at each. ``sites`` (the pattern's ``report["pleats"]``, optional) keeps under each
    pleat's ``"sewn"`` where the stretch's points were placed, and the next call (another size)
    places them the same way, so every size has the same outline vertices.

    The vertices added to a piece are numbered after its last outline vertex (:func:`_outline_first`);
    ``drawn`` (optional, ``report["opened_pleats"]``) gets its lines' ids renumbered with them.
    A site's ``path`` (its pleat's JSON path) names the pleat in the error of a seam that cannot take it.
    Returns ``(panels, seams, next_id)``.
    """
    from dataclasses import replace

    if not any(ends.values()):
        return panels, seams, next_id
    before = [len(p.uv) for p in panels]
    by_name = {p.name: k for k, p in enumerate(panels)}
    site_of = {x["name"]: x for x in sites or ()}
    paths = {x["name"]: x["path"] for x in sites or () if "path" in x}
    panels = list(panels)
    out = []
    for seam in seams:
        cuts = []  # (index along the seam, side, pleat, p, q, lam, at_p, at_q, cols)
        for side, name, verts in (("a", seam.panel_a, seam.verts_a), ("b", seam.panel_b, seam.verts_b)):
            if seam.kind == "dart" or name not in ends:
                continue
            v = [int(x) for x in verts]
            pos = {frozenset((v[i], v[i + 1])): i for i in range(len(v) - 1)}
            for pleat, p, q, lam, at_p, at_q, *cols in ends[name]:
                i = pos.get(frozenset((p, q)))
                if i is not None:
                    cuts.append((i, side, pleat, p, q, lam, at_p, at_q, cols[0] if cols else []))
        if not cuts:
            out.append(seam)
            continue
        if seam.panel_a == seam.panel_b or seam.gathered or len({c[0] for c in cuts}) < len(cuts):
            where = paths.get(cuts[0][2], "")
            raise DesignError(
                f"{where}.from" if where else "",
                f"pleat {cuts[0][2]!r} cannot be sewn into seam {seam.name!r}; {SEAM_REASON}",
            )
        va, vb = [int(x) for x in seam.verts_a], [int(x) for x in seam.verts_b]
        at_edge = {c[0]: c for c in cuts}
        parts, cur, sewn = [], ([], []), []
        for k in range(len(va)):
            cur[0].append(va[k])
            cur[1].append(vb[k])
            if k not in at_edge:
                continue
            _, side, pleat, p, q, lam, at_p, at_q, cols = at_edge[k]
            mine, other = (va, vb) if side == "a" else (vb, va)
            oname = seam.panel_b if side == "a" else seam.panel_a
            # the other piece's vertex at the same fraction of its edge
            y_p, y_q = (other[k], other[k + 1]) if mine[k] == p else (other[k + 1], other[k])
            panels[by_name[oname]], m = _split_edge(panels[by_name[oname]], y_p, y_q, lam, next_id)
            next_id += 1
            first, second = (at_p, at_q) if mine[k] == p else (at_q, at_p)
            ends_here, starts_next = ((first, m), (second, m)) if side == "a" else ((m, first), (m, second))
            cur[0].append(ends_here[0])
            cur[1].append(ends_here[1])
            parts.append(cur)
            cur = ([starts_next[0]], [starts_next[1]])
            # the columns' offsets along the seam's direction after the line (before it: negated)
            after = [(c, -o if mine[k] == p else o, br) for c, o, br in cols]
            sewn.append((len(parts) - 1, side, pleat, f"{seam.name}|{p}|{q}", after))
        parts.append(cur)
        layers = []
        for n_part, side, pleat, key, after in sewn:
            mi = by_name[seam.panel_a if side == "a" else seam.panel_b]
            oi = by_name[seam.panel_b if side == "a" else seam.panel_a]
            record = site_of.get(pleat, {}).setdefault("sewn", {}) if pleat in site_of else {}
            for way, n, sign in (("before", n_part, -1), ("after", n_part + 1, 1)):
                chains = _layer_chains(after, sign)
                if not chains:
                    continue
                part = parts[n]
                ms, os_ = (0, 1) if side == "a" else (1, 0)
                flip = (lambda x: x[::-1]) if way == "before" else (lambda x: x)  # noqa: E731
                chain_m, chain_o = flip(part[ms]), flip(part[os_])
                where = paths.get(pleat, "")
                panels, chain_m, chain_o, sewn_layers, next_id, record[f"{key}|{way}"] = _sew_layers(
                    panels, mi, oi, chain_m, chain_o, chains, next_id, record.get(f"{key}|{way}"), where, seam.name
                )
                part[ms][:], part[os_][:] = flip(chain_m), flip(chain_o)
                for ids_m, ids_o in sewn_layers:
                    layers.append((ids_m, ids_o) if side == "a" else (ids_o, ids_m))
        parts_a, parts_b = [x[0] for x in parts], [x[1] for x in parts]
        for k, (a, b) in enumerate(zip(parts_a, parts_b)):
            out.append(replace(seam, name=f"{seam.name}#p{k}", verts_a=np.asarray(a, int), verts_b=np.asarray(b, int)))
        for k, (a, b) in enumerate(layers):
            out.append(
                replace(seam, name=f"{seam.name}#layer{k}", verts_a=np.asarray(a, int), verts_b=np.asarray(b, int))
            )
    for k, n0 in enumerate(before):
        if len(panels[k].uv) > n0:
            panels[k], out, order = _outline_first(panels[k], n0, out)
            if drawn is not None and panels[k].name in drawn:
                for line in drawn[panels[k].name]:
                    line["ids"] = [int(order[v]) for v in line["ids"]]
    return panels, out, next_id


def _outline_first(piece, n0: int, seams):
    """``piece`` with the vertices added to its outline (local ids from ``n0``) numbered right after
    its last outline vertex before them (an opened piece's strips' inner vertices, whose number
    changes from size to size, after them): every size has the same outline ids (a graded nest).
    Returns the piece, ``seams`` renumbered and the new id of each old one."""
    from dataclasses import replace

    n = len(piece.uv)
    faces = np.asarray(piece.faces, int)
    on = set(int(v) for loop in boundary_loops(faces) for v in loop if v < n0)
    pos = 1 + max(on)
    old = np.r_[np.arange(pos), np.arange(n0, n), np.arange(pos, n0)]
    new_id = np.empty(n, int)
    new_id[old] = np.arange(n)
    out = copy.copy(piece)
    out.uv, out.xyz = np.asarray(piece.uv)[old], np.asarray(piece.xyz)[old]
    out.vertex_ids = np.asarray(piece.vertex_ids)[old]
    out.faces = new_id[faces]
    out.hems = [new_id[np.asarray(h, int)] for h in piece.hems]
    out.boundary = [new_id[np.asarray(b, int)] for b in piece.boundary]
    out._scales = None
    out.achieved_weft, out.achieved_warp, _ = out.scales()

    def side(name, verts):
        return new_id[np.asarray(verts, int)] if name == piece.name else verts

    seams = [replace(x, verts_a=side(x.panel_a, x.verts_a), verts_b=side(x.panel_b, x.verts_b)) for x in seams]
    return out, seams, new_id


def _layer_chains(cols, sign) -> list:
    """The layers of a strip's edge on a seam that lie along it in the direction ``sign`` (+1: the
    offsets of ``cols`` as given, -1: negated) when the pleat is closed: per stretch of the edge
    between two of its breakpoints (fold or placement lines), its vertices and their offsets, from
    the line (offset 0) outwards."""
    brk = [j for j, c in enumerate(cols) if c[2]]
    out = []
    for j0, j1 in zip(brk[:-1], brk[1:]):
        seg = [(c[0], sign * c[1]) for c in cols[j0 : j1 + 1]]
        if max(o for _, o in seg) <= 1e-9:
            continue
        if seg[0][1] > seg[-1][1]:
            seg = seg[::-1]
        out.append(([c for c, _ in seg], [o for _, o in seg]))
    return out


def _sew_layers(panels, mi, oi, chain_m, chain_o, layers, gid, record, where, seam_name):
    """Sew the folded layers ``layers`` (:func:`_layer_chains`) of piece ``panels[mi]`` into its seam
    with ``panels[oi]`` beside the pleat's line: ``chain_m`` / ``chain_o``, the seam part's two sides
    from the line's point (the top cloth's vertex there and the other piece's, which the layers'
    first vertices are already sewn to) outwards. The stretch of ``chain_m`` as long as the layers
    gets the points listed in ``record`` (made here when None): ``["v", k, x]``, the chain's ``k``-th
    vertex (sewn to the layers' column at offset ``x``, or None: each layer gets a vertex there)
    and ``["c", x]``, a new vertex at the column offset ``x`` (m) on both sides of the seam. Returns
    ``(panels, chain_m, chain_o, [(layer ids, other piece's ids)], gid, record)``."""
    panels = list(panels)
    uv = np.asarray(panels[mi].uv, float)
    s_top = cumulative_lengths(uv[chain_m])
    depth = max(max(o) for _, o in layers)
    if s_top[-1] < depth - SEAM_SNAP:
        raise DesignError(
            f"{where}.from" if where else "",
            f"seam {seam_name!r} ends {1000 * s_top[-1]:.1f} mm from the pleat's line, before its folded cloth "
            f"({1000 * depth:.1f} mm): the folds cannot be sewn into it",
        )
    if record is None:
        record = _seam_points(s_top, sorted({round(o, 12) for _, offs in layers for o in offs if o > 1e-12}))
    # the top cloth's side and the other piece's, point by point
    new_m, new_o = [chain_m[0]], [chain_o[0]]
    at_top = {}  # entry index -> offset on this size
    k_last, off_last = 0, 0.0
    for e, entry in enumerate(record):
        if entry[0] == "v":
            k = int(entry[1])
            new_m.append(chain_m[k])
            new_o.append(chain_o[k])
            k_last, off_last = k, float(s_top[k])
            at_top[e] = off_last
            continue
        nxt = min(k_last + 1, len(chain_m) - 1)
        x = _clamped(float(entry[1]), off_last, float(s_top[nxt]))
        lam = (x - off_last) / max(float(s_top[nxt]) - off_last, 1e-300)
        panels[mi], v_m = _split_edge(panels[mi], new_m[-1], chain_m[nxt], lam, gid)
        panels[oi], v_o = _split_edge(panels[oi], new_o[-1], chain_o[nxt], lam, gid + 1)
        gid += 2
        new_m.append(v_m)
        new_o.append(v_o)
        off_last = x
        at_top[e] = x
    last = record[-1]
    rest = int(last[1]) + 1 if last[0] == "v" else k_last + 1
    chain_m, stretch_o = new_m + list(chain_m[rest:]), new_o
    chain_o = new_o + list(chain_o[rest:])
    # each layer: its columns where they are claimed, a new vertex at every other point
    sewn = []
    for ids, offs in layers:
        col = {round(o, 9): c for c, o in zip(ids, offs)}
        lay = [ids[0]]
        off_l = 0.0
        for e, entry in enumerate(record):
            x = entry[2] if entry[0] == "v" else entry[1]
            if x is not None and round(float(x), 9) in col:
                lay.append(col[round(float(x), 9)])
                off_l = float(x)
                continue
            nxt_x = min((o for o in offs if o > off_l + 1e-12), default=None)
            if nxt_x is None:
                raise DesignError(f"{where}.from" if where else "", f"pleat seam {seam_name!r}: a layer ends early")
            w = col[round(nxt_x, 9)]
            x = _clamped(at_top[e], off_l, nxt_x)
            panels[mi], v = _split_edge(panels[mi], lay[-1], w, (x - off_l) / (nxt_x - off_l), gid)
            gid += 1
            lay.append(v)
            off_l = x
        sewn.append((lay, stretch_o))
    return panels, chain_m, chain_o, sewn, gid, record


def _seam_points(s_top, cols) -> list:
    """The points of a seam stretch beside a pleat's line (see :func:`_sew_layers`): ``s_top`` the
    arc length of each vertex of the top cloth's side from the line, ``cols`` the layers' column
    offsets (> 0, sorted; the last is the layers' reach). A column within :data:`SEAM_SNAP` of a
    vertex is sewn to it, the others get a vertex; the stretch ends at the layers' reach."""
    reach = cols[-1]
    cand = [k for k in range(1, len(s_top)) if s_top[k] < reach + SEAM_SNAP]
    claimed = {}
    for x in cols:
        near = [k for k in cand if abs(s_top[k] - x) <= SEAM_SNAP and k not in claimed]
        if near:
            claimed[min(near, key=lambda k: abs(s_top[k] - x))] = x
    end = next((k for k, x in claimed.items() if x == reach), None)
    keep = [k for k in cand if (k <= end if end is not None else s_top[k] < reach)]
    entries = [(float(s_top[k]), ["v", k, claimed.get(k)]) for k in keep]
    entries += [(x, ["c", x]) for x in cols if x not in claimed.values()]
    return [e for _, e in sorted(entries, key=lambda t: t[0])]


def _clamped(x: float, lo: float, hi: float) -> float:
    """``x`` kept strictly between ``lo`` and ``hi`` (a point placed on another size, where the
    stretch's vertices lie a little elsewhere), at least a tenth of the gap from each."""
    gap = hi - lo
    return min(max(x, lo + 0.1 * gap), hi - 0.1 * gap)


def _split_edge(piece, y_p: int, y_q: int, lam: float, gid: int):
    """A copy of ``piece`` with a vertex on its boundary edge ``y_p``-``y_q``, ``lam`` of the way from
    ``y_p`` (the edge's triangle split in two, targets kept), global id ``gid``; and its local id."""
    faces = np.asarray(piece.faces, int)
    has = (faces == y_p).any(axis=1) & (faces == y_q).any(axis=1)
    (f,) = np.flatnonzero(has)[:1] if has.sum() == 1 else (None,)
    if f is None:
        raise DesignError("", f"pleat seam: edge {y_p}-{y_q} of {piece.name!r} is not on its outline")
    m = len(piece.uv)
    a, b, c = (int(x) for x in faces[f])
    # the face's corners turned so that its edge between y_p and y_q runs a -> b
    while {a, b} != {y_p, y_q}:
        a, b, c = b, c, a
    new = copy.copy(piece)
    new.uv = np.vstack([piece.uv, (1 - lam) * np.asarray(piece.uv[y_p]) + lam * np.asarray(piece.uv[y_q])])
    new.xyz = np.vstack([piece.xyz, (1 - lam) * np.asarray(piece.xyz[y_p]) + lam * np.asarray(piece.xyz[y_q])])
    new.vertex_ids = np.r_[np.asarray(piece.vertex_ids, int), gid]
    new.faces = np.vstack([faces[:f], [[a, m, c], [m, b, c]], faces[f + 1 :]])
    for name in ("target_weft", "target_warp"):
        t = np.asarray(getattr(piece, name), float)
        setattr(new, name, np.r_[t[:f], t[f], t[f], t[f + 1 :]])
    new.hems = [np.asarray(h, int) for h in piece.hems]
    new.boundary = [_rotated(np.asarray(x, int), piece.boundary) for x in boundary_loops(new.faces)]
    new._scales = None
    new.achieved_weft, new.achieved_warp, _ = new.scales()
    return new, m


def measure_pleats(pattern) -> List[dict]:
    """Open ``pattern`` and measure each pleat on the opened piece into its ``report["pleats"]``
    entry: ``intake_mm`` (set), ``depth_mm`` (the mean width between its fold and placement lines
    as opened), ``depth_error_mm`` (their largest difference from the set depth, over the line),
    ``line_mm`` (the placement line's length), ``extra_cloth_m2`` (the strips' area: the pleat's
    cloth beside the pattern's own, which the ease figures leave out)."""
    opened = open_pattern(pattern)
    sites = pattern.report["pleats"]
    for site in sites:
        uv = np.asarray(opened.panel(site["panel"]).uv)
        lines = [x for x in opened.report["opened_pleats"][site["panel"]] if x["pleat"] == site["name"]]
        gaps, extra = [], 0.0
        for k in sorted({x["strip"] for x in lines}):
            cols = [uv[x["ids"]] for x in lines if x["strip"] == k]
            gaps += [np.linalg.norm(g - f, axis=1) for f, g in zip(cols[:-1], cols[1:])]
            extra += float(np.linalg.norm(cols[-1][0] - cols[0][0])) * float(np.linalg.norm(cols[0][-1] - cols[0][0]))
        g = np.concatenate(gaps)
        depth = float(site["depth"])
        first = uv[lines[0]["ids"]]
        site.update(
            {
                "intake_mm": round(1000 * site["intake_per_depth"] * depth, 3),
                "depth_mm": round(1000 * float(np.mean(g)), 4),
                "depth_error_mm": round(1000 * float(np.max(np.abs(g - depth))), 6),
                "line_mm": round(1000 * float(np.linalg.norm(first[-1] - first[0])), 2),
                "extra_cloth_m2": round(extra, 6),
            }
        )
    return sites
