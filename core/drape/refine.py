"""The drape's own mesh: the pattern's triangles bisected to a target edge length where the cloth hangs free.

The pattern solve's mesh is sized for the 2D solve (about 10 mm edges, up to
25 mm); folds need 5-10 mm. :func:`refine_pattern` splits the pattern's
triangles by longest-edge bisection (Rivara's 4T-LE: a triangle is split at
the midpoint of its longest edge, and at the midpoints of its other edges when
a neighbour splits them) until every edge of the free-hanging cloth is at most
the target length. It works on the flat pattern: a new vertex lies at the
midpoint of its edge in the panel's own 2D coordinates, so the refined
triangles tile each piece exactly (rest areas add up to the piece's, rest
edge lengths along outlines, seams and hems to the pattern's), and the sewn
garment realises the same ease. Before and after bisection the free cloth's
inner edges are flipped to the Delaunay diagonal where it is shorter
(:func:`delaunay_flips`): slivers of the pattern's mesh, which bisection
would only halve, become well-shaped triangles (the drape's bending leaves
thin triangles out). Its start position on the body is the midpoint of the
skintight embedding.

Seams stay sewn: an edge is identified by its two welded vertices (global ids
joined through the seams), so a seam edge splits on both sides at once, into a
vertex with one global id, and both sides of every seam keep the same vertex
count. A gathered seam whose long side was unwelded
(:func:`core.drape.gathers.unweld_gathers`) refines each side on its own
lengths. Pins carry over: the midpoint of a boundary edge between two pinned
vertices is pinned.

Where the cloth hangs free: a pattern triangle whose rest area is larger than
its skintight image on the body by more than ``free_ease`` (the cloth there has
room to fall and fold), or that touches a gathered seam. The long side of a
gather ruffles between the stitches (:func:`core.drape.gathers.sew_gathers`:
the short side's vertices, at most the target apart), so its triangles are
refined to :data:`GATHER_EDGE` times the target: it has vertices to bunch at
between two stitches. Where the pattern is no larger than the body, the
cloth clings and keeps the solve's mesh (unless a free neighbour's split runs
into it).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import DrapeError
from ..geom.mesh import signed_areas_2d, triangle_areas, unique_pairs
from ..geom.polygon import cross2
from ..geom.polyline import cumulative_lengths
from .gathers import insert_points, longer

#: A triangle whose pattern area exceeds its skintight area by at least this fraction hangs free.
FREE_EASE = 0.01
#: The long side of a gathered seam is refined to this fraction of the target edge.
GATHER_EDGE = 0.5
#: Bisection rounds at most (each halves the longest edges): 25 mm pattern edges reach 5 mm in three.
MAX_LEVELS = 12


def _weld_roots(pattern, n_ids: int) -> np.ndarray:
    """(n_ids,) the smallest global id welded to each id through the non-gathered seams."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = []
    for s in pattern.seams:
        if getattr(s, "gathered", False) and len(s.verts_a) != len(s.verts_b):
            continue
        ga = np.asarray(pattern.panel(s.panel_a).vertex_ids, np.int64)[np.asarray(s.verts_a, np.int64)]
        gb = np.asarray(pattern.panel(s.panel_b).vertex_ids, np.int64)[np.asarray(s.verts_b, np.int64)]
        if getattr(s, "gathered", False):
            ga, gb = ga[[0, -1]], gb[[0, -1]]  # an unwelded gather: only its ends are one vertex
        pairs.append(np.stack([ga, gb], 1))
    p = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    link = coo_matrix((np.ones(len(p)), (p[:, 0], p[:, 1])), shape=(n_ids, n_ids))
    _, label = connected_components(link, directed=False)
    first = np.full(label.max() + 1 if n_ids else 0, n_ids, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n_ids))
    return first[label]


def edge_lengths(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(T, 3) rest length of edge k = (corner k, corner k+1) of each triangle."""
    p = uv[faces]
    return np.linalg.norm(p[:, [1, 2, 0]] - p, axis=2)


def unique_edge_lengths(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Rest lengths of the distinct edges of a (local-index) mesh."""
    e, _ = unique_pairs(np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1))
    return np.linalg.norm(uv[e[:, 1]] - uv[e[:, 0]], axis=1)


def _stats_mm(lengths: np.ndarray) -> dict:
    if len(lengths) == 0:
        return {"median": 0.0, "p95": 0.0, "max": 0.0}
    return {
        "median": round(float(np.median(lengths)) * 1e3, 3),
        "p95": round(float(np.percentile(lengths, 95)) * 1e3, 3),
        "max": round(float(np.max(lengths)) * 1e3, 3),
    }


def delaunay_flips(uv: np.ndarray, faces: np.ndarray, free: np.ndarray, keep: np.ndarray) -> tuple:
    """Flip the inner edges of the free cloth that are not locally Delaunay in the pattern's 2D.

    An edge (a, b) between triangles (a, b, c) and (b, a, d) of one piece is flipped to (c, d) when
    the angles at c and d add up to more than 180 degrees (d inside the circumcircle of a, b, c)
    and (c, d) is the shorter diagonal: a sliver of the pattern's mesh (angles of a few degrees,
    which bisection halves but keeps) becomes two well-shaped triangles. The pieces' rest shape is
    unchanged (the same quadrilateral, tiled the other way) and so are its boundaries, seams and hems
    (they are never inner edges); only edges with a triangle that hangs free (``free``) flip (both
    triangles then hang free), no edge with both ends on a pleat line (``keep``, per vertex) does. The drape needs it: the cloth's bending
    leaves out the hinges of thin triangles (:data:`core.drape.mesh.BEND_QUALITY`), and the cloth
    folded flat (180 degrees) at them, the dark pinches of a render.

    Returns
    -------
    faces (T, 3) (a flipped triangle keeps its row, so its parent record), free (T,), flips: int.
    """
    faces = np.array(faces, np.int64, copy=True)
    free = np.array(free, bool, copy=True)
    n, flips = len(uv), 0

    def orient(p, q, r):  # twice the signed area of each (p, q, r)
        return cross2(uv[q] - uv[p], uv[r] - uv[p])

    def angle(p, q, r):  # at p, between p->q and p->r
        u, v = uv[q] - uv[p], uv[r] - uv[p]
        return np.arctan2(np.abs(cross2(u, v)), np.einsum("ij,ij->i", u, v))

    for _ in range(10 * MAX_LEVELS):
        he = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)  # edge k: corners k, k+1
        opp = faces[:, [2, 0, 1]].reshape(-1)  # the corner across edge k
        key = np.minimum(he[:, 0], he[:, 1]) * n + np.maximum(he[:, 0], he[:, 1])
        order = np.argsort(key, kind="stable")
        two = key[order][1:] == key[order][:-1]
        h1, h2 = order[:-1][two], order[1:][two]
        f1, f2 = h1 // 3, h2 // 3
        a, b, c, d = he[h1, 0], he[h1, 1], opp[h1], opp[h2]
        ok = (free[f1] | free[f2]) & ~(keep[a] & keep[b]) & (he[h2, 0] == b) & (he[h2, 1] == a)
        excess = angle(c, a, b) + angle(d, a, b) - np.pi
        side = np.sign(orient(a, b, c))
        ok &= (excess > 1e-9) & (np.linalg.norm(uv[d] - uv[c], axis=1) < np.linalg.norm(uv[b] - uv[a], axis=1))
        ok &= (np.sign(orient(a, d, c)) == side) & (np.sign(orient(d, b, c)) == side)
        cand = np.nonzero(ok)[0]
        if not len(cand):
            break
        used = np.zeros(len(faces), bool)
        chosen = []
        for i in cand[np.argsort(-excess[cand], kind="stable")].tolist():  # worst first, no face twice
            if not (used[f1[i]] or used[f2[i]]):
                used[f1[i]] = used[f2[i]] = True
                chosen.append(i)
        ch = np.asarray(chosen, np.int64)
        faces[f1[ch]] = np.stack([a[ch], d[ch], c[ch]], axis=1)
        faces[f2[ch]] = np.stack([d[ch], b[ch], c[ch]], axis=1)
        free[f1[ch]] = free[f2[ch]] = True
        flips += len(ch)
    return faces, free, flips


def refine_pattern(pattern, edge: float, free_ease: float = FREE_EASE, max_levels: int = MAX_LEVELS) -> tuple:
    """The pattern with its free-hanging triangles bisected until no edge there is longer than ``edge``.

    Parameters
    ----------
    pattern : :class:`core.pattern.types.Pattern` (gathered seams may be unwelded already).
    edge : float, metres, the target (longest) edge length of the free cloth.
    free_ease : fraction, the area ease above which a pattern triangle hangs free (:data:`FREE_EASE`).
    max_levels : int, bisection rounds at most.

    Returns
    -------
    refined : a Pattern: the same panels, seams, pins and materials, with new
        vertices (new global ids after every id of ``pattern``) and triangles.
    report : dict, JSON-ready: target, edge lengths before and after (mm), triangle and
        vertex counts before and after, the share of pattern triangles that hang free, rounds.
    """
    if not (isinstance(edge, (int, float, np.floating)) and np.isfinite(edge) and edge > 0):
        raise DrapeError(f"drape option refine_edge = {edge!r}: expected a length in metres > 0")
    panels = list(pattern.panels)
    sizes = [len(p.uv) for p in panels]
    off = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    uv = np.concatenate([np.asarray(p.uv, float).reshape(-1, 2) for p in panels])
    xyz = np.concatenate([np.asarray(p.xyz, float).reshape(-1, 3) for p in panels])
    gid = np.concatenate([np.asarray(p.vertex_ids, np.int64) for p in panels])
    pan = np.repeat(np.arange(len(panels)), sizes)
    faces = np.concatenate([np.asarray(p.faces, np.int64).reshape(-1, 3) + off[k] for k, p in enumerate(panels)])
    parent = np.concatenate([np.arange(len(p.faces)) for p in panels]).astype(np.int64)  # face index in its panel
    n_ids = int(gid.max()) + 1 if len(gid) else 0
    root = _weld_roots(pattern, n_ids)
    pinned = np.zeros(n_ids, bool)
    for ids in (pattern.pins or {}).values():
        ids = np.asarray(ids, np.int64).reshape(-1)
        pinned[ids[(ids >= 0) & (ids < n_ids)]] = True
    with np.errstate(divide="ignore", invalid="ignore"):
        ease = np.abs(signed_areas_2d(uv, faces)) / triangle_areas(xyz, faces) - 1.0
    free = np.nan_to_num(ease, nan=0.0, posinf=1.0) > free_ease
    # a gathered seam ruffles: the triangles on its sides hang free, its long side's refined to
    # GATHER_EDGE x the target, so that its extra length has vertices to bunch at between two
    # stitches (the short side's vertices, core.drape.gathers.sew_gathers)
    on_long, on_short = np.zeros(len(uv), bool), np.zeros(len(uv), bool)
    index = {p.name: k for k, p in enumerate(panels)}
    for s in pattern.seams:
        if getattr(s, "gathered", False):
            ua, ub = pattern.seam_polylines(s)
            sides = ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b))[
                :: 1 if longer(cumulative_lengths(ua)[-1], cumulative_lengths(ub)[-1]) == 0 else -1
            ]
            for mark, (name, verts) in zip((on_long, on_short), sides):
                mark[off[index[name]] + np.asarray(verts, np.int64)] = True
    gather = on_long[faces].any(axis=1)
    free |= gather | on_short[faces].any(axis=1)
    before = unique_edge_lengths(uv, faces)
    free_before = free.copy()
    tris_before, verts_before = len(faces), int(len(np.unique(root[gid])))
    # polylines (concatenated local ids) that must take the new midpoints: seam sides, boundaries, hems
    seams = [
        (off[pn[s.panel_a]] + np.asarray(s.verts_a, np.int64), off[pn[s.panel_b]] + np.asarray(s.verts_b, np.int64))
        for pn in [{p.name: k for k, p in enumerate(panels)}]
        for s in pattern.seams
    ]
    loops = [[off[k] + np.asarray(b, np.int64) for b in p.boundary] for k, p in enumerate(panels)]
    hems = [[off[k] + np.asarray(h, np.int64) for h in p.hems] for k, p in enumerate(panels)]

    # pleat lines (folds, placements, stitches) inside a piece: their edges stay edges (no flips)
    lines = {
        int(g) for ls in ((pattern.report or {}).get("opened_pleats") or {}).values() for x in ls for g in x["gids"]
    }
    on_line = np.isin(gid, np.fromiter(lines, np.int64, len(lines)))

    # slivers of the pattern's mesh flipped first: bisected, a sliver's children are slivers too
    faces, free, flips = delaunay_flips(uv, faces, free, on_line)
    gather = on_long[faces].any(axis=1)
    levels = 0
    for _ in range(max_levels):
        lens = edge_lengths(uv, faces)
        longest = np.argmax(lens, axis=1)
        need = free & (lens.max(axis=1) > np.where(gather, GATHER_EDGE, 1.0) * edge * (1.0 + 1e-9))
        if not need.any():
            break
        levels += 1
        la, lb = faces, np.roll(faces, -1, axis=1)
        ra, rb = root[gid[la]], root[gid[lb]]
        key = np.minimum(ra, rb) * len(root) + np.maximum(ra, rb)
        ukey, eid = np.unique(key.ravel(), return_inverse=True)
        eid = eid.reshape(-1, 3)
        t_all = np.arange(len(faces))
        marked = np.zeros(len(ukey), bool)
        marked[eid[need, longest[need]]] = True
        while True:  # closure: a triangle with a split edge splits its longest edge too
            fix = marked[eid].any(axis=1) & ~marked[eid[t_all, longest]]
            if not fix.any():
                break
            marked[eid[fix, longest[fix]]] = True
        # new global ids, one per split (welded) edge, in edge order
        gid_of_edge = -np.ones(len(ukey), np.int64)
        gid_of_edge[marked] = len(root) + np.arange(int(marked.sum()))
        # new local vertices, one per split local edge (two panels sharing a seam edge get one each)
        hit = marked[eid]
        lk = np.stack([np.minimum(la, lb)[hit], np.maximum(la, lb)[hit]], 1)
        lkeys, linv = unique_pairs(lk)
        first = np.full(len(lkeys), len(linv), np.int64)
        np.minimum.at(first, linv, np.arange(len(linv)))  # the first occurrence of each
        base = len(uv)
        mid = -np.ones(faces.shape, np.int64)
        mid[hit] = base + linv
        new_gid = gid_of_edge[eid[hit][first]]
        # a boundary edge (one triangle in its panel) between two pinned vertices has its midpoint pinned
        code = np.sort(np.minimum(la, lb) * base + np.maximum(la, lb), axis=None)
        want = lkeys[:, 0] * base + lkeys[:, 1]
        uses = np.searchsorted(code, want, side="right") - np.searchsorted(code, want, side="left")
        new_pin = pinned[gid[lkeys[:, 0]]] & pinned[gid[lkeys[:, 1]]] & (uses == 1)
        n_new_ids = int(marked.sum())
        root = np.concatenate([root, len(root) + np.arange(n_new_ids)])
        pin_ids = np.zeros(n_new_ids, bool)
        pin_ids[new_gid[new_pin] - (len(root) - n_new_ids)] = True
        pinned = np.concatenate([pinned, pin_ids])
        uv = np.concatenate([uv, 0.5 * (uv[lkeys[:, 0]] + uv[lkeys[:, 1]])])
        xyz = np.concatenate([xyz, 0.5 * (xyz[lkeys[:, 0]] + xyz[lkeys[:, 1]])])
        gid = np.concatenate([gid, new_gid])
        pan = np.concatenate([pan, pan[lkeys[:, 0]]])
        on_line = np.concatenate([on_line, on_line[lkeys[:, 0]] & on_line[lkeys[:, 1]]])
        # children, corners rotated so the longest edge is (a, b); orientation kept
        split = hit.any(axis=1)
        a, b, c = faces[t_all, longest], faces[t_all, (longest + 1) % 3], faces[t_all, (longest + 2) % 3]
        mab, mbc, mca = mid[t_all, longest], mid[t_all, (longest + 1) % 3], mid[t_all, (longest + 2) % 3]
        kinds = (
            (split & (mca < 0), (a, mab, c)),
            (split & (mca >= 0), (mab, c, mca)),
            (split & (mca >= 0), (mab, mca, a)),
            (split & (mbc < 0), (mab, b, c)),
            (split & (mbc >= 0), (mab, b, mbc)),
            (split & (mbc >= 0), (mab, mbc, c)),
        )
        src = np.concatenate([np.nonzero(~split)[0]] + [np.nonzero(m)[0] for m, _ in kinds])
        kids = np.concatenate([faces[~split]] + [np.stack([v[m] for v in corners], 1) for m, corners in kinds])
        # the children of a triangle stay together, in the parents' order (a repeatable layout)
        order = np.argsort(src, kind="stable")
        faces, parent, free, gather = kids[order], parent[src[order]], free[src[order]], gather[src[order]]
        mids = {(int(p), int(q)): [base + k] for k, (p, q) in enumerate(lkeys.tolist())}
        seams = [(insert_points(sa, mids, False), insert_points(sb, mids, False)) for sa, sb in seams]
        loops = [[insert_points(lp, mids, True) for lp in ls] for ls in loops]
        hems = [[insert_points(h, mids, False) for h in hs] for hs in hems]

    if levels:
        faces, free, more = delaunay_flips(uv, faces, free, on_line)
        flips += more
    after = unique_edge_lengths(uv, faces)
    # back to panels: each panel's old vertices first, then its new ones in the order they were made
    local = np.zeros(len(uv), np.int64)
    out_panels = []
    face_pan = pan[faces[:, 0]]
    for k, p in enumerate(panels):
        sel = np.nonzero(pan == k)[0]
        local[sel] = np.arange(len(sel))
        fk = face_pan == k
        per_face = {}
        nf = len(p.faces)
        for name in ("target_weft", "target_warp", "achieved_weft", "achieved_warp"):
            arr = getattr(p, name)
            per_face[name] = np.asarray(arr)[parent[fk]] if arr is not None and len(np.asarray(arr)) == nf else arr
        out_panels.append(
            replace(
                p,
                uv=uv[sel],
                xyz=xyz[sel],
                vertex_ids=gid[sel],
                faces=local[faces[fk]],
                boundary=[local[lp] for lp in loops[k]],
                hems=[local[h] for h in hems[k]],
                **per_face,
            )
        )
    out_seams = [replace(s, verts_a=local[sa], verts_b=local[sb]) for s, (sa, sb) in zip(pattern.seams, seams)]
    pins = {}
    for g, ids in (pattern.pins or {}).items():
        ids = np.asarray(ids, np.int64).reshape(-1)
        garment_ids = np.unique(
            np.concatenate([q.vertex_ids for q in out_panels if q.garment == g] or [np.zeros(0, int)])
        )
        extra = garment_ids[(garment_ids >= n_ids) & pinned[garment_ids]]
        pins[g] = np.concatenate([ids, extra])
    refined = replace(pattern, panels=out_panels, seams=out_seams, pins=pins)
    report = {
        "target_edge_m": float(edge),
        "free_ease": float(free_ease),
        "free_pct": round(100.0 * float(np.mean(free_before)) if tris_before else 0.0, 2),
        "rounds": levels,
        "flips": int(flips),
        "edge_mm_before": _stats_mm(before),
        "edge_mm_after": _stats_mm(after),
        "triangles_before": int(tris_before),
        "triangles_after": int(len(faces)),
        "vertices_before": verts_before,
        "vertices_after": int(len(np.unique(root[gid]))),
    }
    return refined, report
