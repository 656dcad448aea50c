"""Gathered seams sewn as gathers: the long side keeps its length and ruffles between stitches.

A gathered seam (:attr:`core.pattern.types.PatternSeam.gathered`) has a longer
side that is eased into a shorter one. The pattern pairs the two sides vertex
by vertex (shared vertex ids), and welding them so presses every long-side
vertex into the seam line: the long side's first row of fabric is squeezed
along the seam, and a membrane that resists compression as it resists stretch
pushes the short side open instead of buckling. Here instead the long side
gets its own vertices (:func:`unweld_gathers`; its two ends stay welded to the
short side's), is refined for the drape on its own rest lengths, and is sewn
to the short side at stitches (:func:`sew_gathers`): each short-side vertex is
sewn to the long side's point at the same fraction of the rest arc length, as
GarmentCode sews a ruffle at matching fractions of both edges. That point
becomes a vertex of the long side (its edge split there, the triangle behind
it fanned: rest shapes unchanged) and the stitch is a weld, so it holds
exactly (a distance-constraint stitch lets the long side's fabric pull it off
the seam by millimetres in a one-pass XPBD step). Between stitches the long
side keeps its own, free vertices: its extra length bunches there. The long
side keeps its rest length, lies along the short one, and ruffles.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..geom.polyline import cumulative_lengths

#: Points of a seam closer than this fraction of its side's arc length are one point.
SNAP_FRACTION = 1e-6


def long_side(pattern, seam) -> int:
    """0 when side a of ``seam`` is the longer in the pattern (rest) shape, else 1 (a tie: side a)."""
    ua, ub = pattern.seam_polylines(seam)
    return longer(cumulative_lengths(ua)[-1], cumulative_lengths(ub)[-1])


def longer(length_a: float, length_b: float) -> int:
    """0 when side a is the longer (a tie, up to rounding: side a), else 1."""
    return 0 if length_a >= length_b * (1.0 - 1e-9) else 1


def unweld_gathers(pattern):
    """A copy of ``pattern`` whose gathered seams' long sides have their own vertex ids.

    The interior vertices of each gathered seam's long side get new global ids
    (after every id in use); its two end vertices keep theirs, so the seam's
    ends stay sewn. A pinned id that is split stays pinned on both sides.
    Panels that no gathered seam touches are shared with ``pattern``, not copied.
    """
    gathered = [s for s in pattern.seams if getattr(s, "gathered", False)]
    if not gathered:
        return pattern
    panels = {p.name: p for p in pattern.panels}
    new_ids = {p.name: np.asarray(p.vertex_ids, np.int64).copy() for p in pattern.panels}
    next_id = max((int(np.max(p.vertex_ids)) + 1 for p in pattern.panels if len(p.vertex_ids)), default=0)
    pins = {g: np.asarray(v, np.int64).reshape(-1) for g, v in (pattern.pins or {}).items()}
    for s in gathered:
        side = long_side(pattern, s)
        name, verts = (s.panel_a, s.verts_a) if side == 0 else (s.panel_b, s.verts_b)
        inner = np.asarray(verts, np.int64)[1:-1]
        if name == (s.panel_b if side == 0 else s.panel_a):
            # both sides in one panel (not a dart: those are never gathered): keep the short side's ids
            other = set(np.asarray(s.verts_b if side == 0 else s.verts_a, np.int64).tolist())
            inner = np.array([v for v in inner.tolist() if v not in other], np.int64)
        old = new_ids[name][inner]
        fresh = np.arange(next_id, next_id + len(inner), dtype=np.int64)
        next_id += len(inner)
        new_ids[name][inner] = fresh
        for g, ids in pins.items():
            hit = np.isin(old, ids)
            if hit.any():
                pins[g] = np.concatenate([ids, fresh[hit]])
    out_panels = [
        replace(p, vertex_ids=new_ids[p.name]) if not np.array_equal(new_ids[p.name], p.vertex_ids) else p
        for p in panels.values()
    ]
    return replace(pattern, panels=out_panels, pins=pins)


def _fan(faces: np.ndarray, parent: np.ndarray, a: int, b: int, inner: list) -> tuple:
    """``faces`` with the triangle on edge (a, b) fanned through the points ``inner`` (in order from a to b),
    and ``parent`` (the original face of each face) carried along."""
    f = np.asarray(faces)
    for k in range(3):
        p, q = f[:, k], f[:, (k + 1) % 3]
        hit = np.nonzero(((p == a) & (q == b)) | ((p == b) & (q == a)))[0]
        if len(hit):
            t = int(hit[0])
            r = int(f[t, (k + 2) % 3])
            seq = [a, *inner, b] if f[t, k] == a else [b, *inner[::-1], a]
            new = np.array([[seq[i], seq[i + 1], r] for i in range(len(seq) - 1)], dtype=np.int64)
            kids = np.full(len(new), parent[t])
            return np.concatenate([f[:t], new, f[t + 1 :]]), np.concatenate([parent[:t], kids, parent[t + 1 :]])
    raise ValueError(f"no triangle on edge ({a}, {b})")


def _carry(panel, verts: np.ndarray, where: np.ndarray, next_id: int) -> tuple:
    """Give one side of a seam a vertex at each arc position of ``where``.

    ``where`` (ascending, metres along the side's rest arc, 0 and the side's length included):
    a position within ``SNAP_FRACTION`` of the seam of a vertex of the side is that vertex;
    any other becomes a new vertex on its segment (new global id from ``next_id``, 2D and 3D
    interpolated, the panel's triangle on that edge fanned through it).

    Returns
    -------
    panel (a copy when vertices were added), path (len(where),) int local vertex ids, next_id.
    """
    uv, xyz, ids = panel.uv, panel.xyz, panel.vertex_ids
    a_s = cumulative_lengths(uv[verts])
    tol = SNAP_FRACTION * a_s[-1]
    seg = np.clip(np.searchsorted(a_s, where, side="right") - 1, 0, len(a_s) - 2)
    new_uv, new_xyz, inner, path = [], [], {}, []
    for w, j in zip(where.tolist(), seg.tolist()):
        if abs(w - a_s[j]) <= tol:
            path.append(int(verts[j]))
        elif abs(a_s[j + 1] - w) <= tol:
            path.append(int(verts[j + 1]))
        else:
            t = (w - a_s[j]) / (a_s[j + 1] - a_s[j])
            a, b = verts[j], verts[j + 1]
            local = len(uv) + len(new_uv)
            new_uv.append((1 - t) * uv[a] + t * uv[b])
            new_xyz.append((1 - t) * xyz[a] + t * xyz[b])
            inner.setdefault(j, []).append(local)
            path.append(local)
    if not new_uv:
        return panel, np.asarray(path, np.int64), next_id
    faces = np.asarray(panel.faces, np.int64)
    parent = np.arange(len(faces))
    for j, pts in sorted(inner.items()):
        faces, parent = _fan(faces, parent, int(verts[j]), int(verts[j + 1]), pts)
    per_face = {
        name: np.asarray(getattr(panel, name))[parent]
        for name in ("target_weft", "target_warp", "achieved_weft", "achieved_warp")
        if getattr(panel, name) is not None and len(np.asarray(getattr(panel, name))) == len(panel.faces)
    }
    split = {(int(verts[j]), int(verts[j + 1])): pts for j, pts in inner.items()}
    fresh = np.arange(next_id, next_id + len(new_uv), dtype=np.int64)
    panel = replace(
        panel,
        uv=np.concatenate([uv, np.asarray(new_uv)]),
        xyz=np.concatenate([xyz, np.asarray(new_xyz)]),
        vertex_ids=np.concatenate([ids, fresh]),
        faces=faces,
        boundary=[insert_points(b, split, closed=True) for b in panel.boundary],
        hems=[insert_points(h, split, closed=False) for h in panel.hems],
        **per_face,
    )
    return panel, np.asarray(path, np.int64), next_id + len(new_uv)


#: A gather's long side is moved onto the short side's skintight positions; the rest of its panel
#: follows, the move fading to nothing this far from the seam (or 4x the largest move, if more), metres.
EASE_IN_REACH = 0.03


def seams_of(pattern, panel: str, exclude: str = "") -> list:
    """The seams of ``pattern`` with a side on ``panel`` (but the one named ``exclude``)."""
    return [s for s in pattern.seams if s.name != exclude and panel in (s.panel_a, s.panel_b)]


def _seam_vertices(seams, panel: str) -> np.ndarray:
    """Local ids of ``panel``'s vertices on any side of ``seams`` that lies on it."""
    ids = [
        np.asarray(v, np.int64)
        for s in seams
        for name, v in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b))
        if name == panel
    ]
    return np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)


def ease_in(panel, moved: np.ndarray, target: np.ndarray, held: np.ndarray) -> np.ndarray:
    """(n, 3) start positions of ``panel`` with its vertices ``moved`` (local ids) put at ``target``
    (k, 3) and the rest of the panel following smoothly: the move is harmonic over the panel's mesh
    (each vertex's move the mean of its neighbours'), none at ``held`` (other seams' vertices, whose
    partners in other panels stay) and none farther than :data:`EASE_IN_REACH` (in the pattern's 2D)
    from the moved vertices. A move along the seam of a centimetre or two then shears the panel's
    first rows a little instead of folding them over."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.linalg import spsolve

    xyz = np.asarray(panel.xyz, dtype=float)
    moved = np.asarray(moved, np.int64)
    move = np.asarray(target, dtype=float) - xyz[moved]
    size = float(np.linalg.norm(move, axis=1).max()) if len(moved) else 0.0
    if size == 0.0:
        return xyz
    uv = np.asarray(panel.uv, dtype=float)
    n = len(uv)
    reach = max(EASE_IN_REACH, 4.0 * size)
    near = np.zeros(n, bool)
    for start in range(0, n, 2048):  # distance in 2D to the nearest moved vertex, bounded memory
        d = np.linalg.norm(uv[start : start + 2048, None] - uv[moved][None], axis=2).min(axis=1)
        near[start : start + 2048] = d < reach
    disp = np.zeros((n, 3))
    disp[moved] = move
    fixed = ~near
    fixed[np.asarray(held, np.int64)] = True
    fixed[moved] = True
    free = np.nonzero(~fixed)[0]
    if len(free):
        f = np.asarray(panel.faces, np.int64)
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        e = np.unique(np.sort(np.concatenate([e, e[:, ::-1]]), axis=1), axis=0)
        i, j = np.concatenate([e[:, 0], e[:, 1]]), np.concatenate([e[:, 1], e[:, 0]])
        adj = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n)).tocsr()
        deg = np.asarray(adj.sum(axis=1)).ravel()
        lap = (coo_matrix((deg, (np.arange(n), np.arange(n))), shape=(n, n)) - adj).tocsr()
        rhs = -(lap[free][:, np.nonzero(fixed)[0]] @ disp[fixed])
        sol = spsolve(lap[free][:, free].tocsc(), rhs)
        disp[free] = np.asarray(sol).reshape(len(free), 3)
    return xyz + disp


def sew_gathers(pattern) -> tuple:
    """Sew each gathered seam's long side to its short side at the short side's vertices.

    The stitches are the short side's vertices: each is sewn to the point of
    the long side (already unwelded, and refined on its own length) at the same
    fraction of the rest arc length (both sides run from index 0, where they
    meet); a long side with no vertex there gets one on its segment
    (:func:`_carry`: rest shapes unchanged). The sides then pair stitch for
    stitch and weld as any seam. Between two stitches the long side keeps its
    own vertices, free: its extra length bunches there (the ruffle) instead of
    being pressed into the seam line, where a membrane that resists
    compression as it resists stretch would push the short side open (sewing
    every long-side vertex to the seam stretches a yoke's lower edge 20-25 %,
    these stitches 1.5 %, as a flat seam). The long side starts on the short
    side's skintight positions at the stitches.

    Returns
    -------
    pattern : a copy with the gathered seams' long panels split at the stitches, the seams' sides of
        equal length (the stitches).
    report : dict, seam name -> ``{"ratio": long / short rest length, "long_vertices",
        "short_vertices"`` (each side's own), ``"stitches"``, ``"free_long_vertices"`` (long-side
        vertices between stitches)``}``.
    """
    if not any(getattr(s, "gathered", False) for s in pattern.seams):
        return pattern, {}
    panels = {p.name: p for p in pattern.panels}
    next_id = max((int(np.max(p.vertex_ids)) + 1 for p in pattern.panels if len(p.vertex_ids)), default=0)
    seams, report = [], {}
    for s in pattern.seams:
        va, vb = np.asarray(s.verts_a, np.int64), np.asarray(s.verts_b, np.int64)
        if not getattr(s, "gathered", False) or min(len(va), len(vb)) < 2:
            seams.append(s)
            continue
        aa, ab = cumulative_lengths(panels[s.panel_a].uv[va]), cumulative_lengths(panels[s.panel_b].uv[vb])
        if aa[-1] <= 0 or ab[-1] <= 0:
            seams.append(s)
            continue
        side = longer(aa[-1], ab[-1])
        # the stitches: at the short side's own vertices (their fractions), carried to the long side
        frac = np.unique(ab / ab[-1] if side == 0 else aa / aa[-1])
        keep = np.concatenate([[True], np.diff(frac) > SNAP_FRACTION])
        keep[-1] = True
        frac = frac[keep & np.concatenate([frac[:-1] < 1.0 - SNAP_FRACTION, [True]])]
        frac[0], frac[-1] = 0.0, 1.0
        pa, path_a, next_id = _carry(panels[s.panel_a], va, frac * aa[-1], next_id)
        panels[s.panel_a] = pa
        pb, path_b, next_id = _carry(panels[s.panel_b], vb, frac * ab[-1], next_id)
        panels[s.panel_b] = pb
        # the long side starts on the short side's skintight positions, each of its points at the
        # short side's point of the same rest fraction (stitches on their short-side vertex exactly)
        sides = ((s.panel_a, path_a, va, aa), (s.panel_b, path_b, vb, ab))
        (nl, pl, vl, al), (ns, ps, _, _) = sides[:: 1 if side == 0 else -1]
        on_long = np.concatenate([vl, pl])
        at = np.concatenate([al / al[-1], frac])
        short_xyz = np.asarray(panels[ns].xyz, dtype=float)[ps]
        target = np.stack([np.interp(at, frac, short_xyz[:, k]) for k in range(3)], axis=1)
        held = _seam_vertices(seams_of(pattern, nl, exclude=s.name), nl)
        panels[nl] = replace(panels[nl], xyz=ease_in(panels[nl], on_long, target, held))
        seams.append(replace(s, verts_a=path_a, verts_b=path_b))
        (vl, pl_), n_short = ((va, path_a), len(vb)) if side == 0 else ((vb, path_b), len(va))
        report[s.name] = {
            "ratio": round(float(max(aa[-1], ab[-1]) / min(aa[-1], ab[-1])), 4),
            "long_vertices": int(len(vl)),
            "short_vertices": int(n_short),
            "stitches": int(len(frac)),
            "free_long_vertices": len(set(vl.tolist()) - set(pl_.tolist())),
        }
    out = [panels[p.name] for p in pattern.panels]
    return replace(pattern, panels=out, seams=seams), report


def insert_points(poly, split: dict, closed: bool) -> np.ndarray:
    """A polyline of vertex ids with points inserted on its split edges.

    ``split`` maps an edge (a, b) to the points on it, in order from a to b (an
    edge walked from b to a takes them reversed); ``closed``: the polyline is a loop.
    """
    poly = [int(v) for v in np.asarray(poly).reshape(-1)]
    out = []
    n = len(poly)
    for k, v in enumerate(poly):
        out.append(v)
        if k + 1 < n or (closed and n > 1):
            w = poly[(k + 1) % n]
            if (v, w) in split:
                out.extend(split[(v, w)])
            elif (w, v) in split:
                out.extend(split[(w, v)][::-1])
    return np.asarray(out, np.int64)
