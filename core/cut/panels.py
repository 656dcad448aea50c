"""Panels, seams and hems from the labelled faces of a cut garment mesh.

The cut lines split the mesh into panels (face labels, from the engine's
flood fill); here each panel gets its own vertices (corners joined across
uncut edges), its boundary loops and its grain, and each line its seams
(panel pairs along it) and hems (open edges), as :class:`core.cut.types.Panel`
and :class:`core.cut.types.Seam`.
"""

from __future__ import annotations

from typing import List

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import CutError
from .grain import warp_directions
from .types import Panel, Seam


def halfedges(F: np.ndarray, n: int):
    """Directed half-edge keys (3f,), their undirected keys, and the twin index (-1 if none)."""
    a = F.reshape(-1)
    b = np.roll(F, -1, axis=1).reshape(-1)
    key = a * n + b
    rkey = b * n + a
    order = np.argsort(key, kind="stable")
    pos = np.clip(np.searchsorted(key[order], rkey), 0, len(key) - 1)
    twin = np.where(key[order][pos] == rkey, order[pos], -1)
    ukey = np.minimum(a, b) * n + np.maximum(a, b)
    return key, ukey, twin, order


def build_panels(spec, gpanels, X, F, lab, lines, lines_li, axes, offset, clock):
    """Panels, seams and hems of one garment's labelled faces.

    Parameters
    ----------
    spec : CutSpec; gpanels : the garment's PanelSpecs (label i = gpanels[i]).
    X : (n, 3) float, garment mesh vertices (m); F : (f, 3) int, its faces.
    lab : (f,) int, panel label of each face.
    lines, lines_li : the vertex runs of each cut line and the line's index in ``spec.lines``.
    axes : {(body_part, side): (3,) axis}, the grain axes; offset : first garment vertex id.
    clock : has ``lap(stage)``, adds the wall time of ``panels_seams`` and ``grain``.

    Returns
    -------
    dict ``panels`` (list of Panel), ``seams`` (list of Seam), ``hems`` ({panel: [vertex runs]}),
    ``vertex_of_global`` (garment vertex -> mesh vertex).
    """
    n = len(X)
    key, ukey, twin, order = halfedges(F, n)
    # cut edges: every edge on a cut line
    cut, sewn = [], []
    for runs, li in zip(lines, lines_li):
        for s in runs:
            k = np.minimum(s[:-1], s[1:]) * n + np.maximum(s[:-1], s[1:])
            cut.append(k)
            if spec.lines[li].role == "seam":
                sewn.append(k)
    cut = np.unique(np.concatenate(cut)) if cut else np.zeros(0, np.int64)
    sewn = np.unique(np.concatenate(sewn)) if sewn else np.zeros(0, np.int64)
    i = np.arange(len(key))
    on_cut = np.isin(ukey, cut)
    join = (twin >= 0) & ~on_cut
    join &= lab[i // 3] == lab[np.maximum(twin, 0) // 3]
    # corner (f, k) ~ twin's corners: half-edge i = corner i -> corner next(i)
    nxt = lambda h: (h // 3) * 3 + (h % 3 + 1) % 3

    def corner_components(joined):
        a = np.nonzero(joined)[0]
        b = twin[a]
        ca = np.concatenate([a, nxt(a)])
        cb = np.concatenate([nxt(b), b])
        C = sp.coo_matrix((np.ones(len(ca)), (ca, cb)), shape=(3 * len(F), 3 * len(F)))
        return connected_components(C, directed=False)[1]

    # panel-local vertices: corners joined across uncut edges inside a panel
    corner_vert = corner_components(join)
    # global garment vertices: corners joined across uncut edges and across seams, never
    # across an opening - the two sides of an opening between panels (a jacket's front)
    # get their own vertices, so no later stage sews them together
    gv_all = F.reshape(-1)
    open_inside = (twin >= 0) & on_cut
    if len(sewn):
        open_inside &= ~np.isin(ukey, sewn)
    if open_inside.any():
        corner_global = corner_components((twin >= 0) & ~open_inside)
        ncg = np.int64(corner_global.max()) + 1
        # deterministic numbering by (mesh vertex, component): the mesh vertex order where
        # nothing is split
        ug, ginv = np.unique(gv_all * ncg + corner_global, return_inverse=True)
        global_of_corner = ginv.reshape(-1)
        vertex_of_global = ug // ncg
    else:  # no opening runs between faces: one garment vertex per mesh vertex (all used)
        global_of_corner = gv_all
        vertex_of_global = np.arange(n, dtype=np.int64)
    # deterministic local vertex numbering: by (panel, global vertex, component)
    panels = []
    local_of_corner = np.full(3 * len(F), -1, dtype=np.int64)
    gv_of_corner = F.reshape(-1)
    panel_names = [p.name for p in gpanels]
    for pi, p in enumerate(gpanels):
        fids = np.nonzero(lab == pi)[0]
        if len(fids) == 0:
            raise CutError(f"panel {p.name!r} has no faces")
        corners = (fids[:, None] * 3 + np.arange(3)[None]).reshape(-1)
        cv = corner_vert[corners]
        gv = gv_of_corner[corners]
        # order local vertices by global id then component id
        ncv = np.int64(corner_vert.max()) + 1
        uk, first, inv = np.unique(gv * ncv + cv, return_index=True, return_inverse=True)
        inv = inv.reshape(-1)
        local_of_corner[corners] = inv
        faces = inv.reshape(-1, 3)
        ugv = uk // ncv
        vids = global_of_corner[corners[first]] + offset
        Xl = X[ugv]
        side = "left" if Xl[:, 0].mean() >= 0 else "right"
        axis = axes[(p.body_part, "left" if p.body_part == "torso" else side)]
        clock.lap("panels_seams")
        warp = warp_directions(Xl, faces, axis)
        clock.lap("grain")
        # boundary half-edges: those not joined to a twin in the same panel
        hb = corners[~join[corners]]
        boundary = _boundary_loops(local_of_corner[hb], local_of_corner[nxt(hb)], p.name)
        panels.append(
            Panel(
                name=p.name,
                garment=p.garment,
                vertex_ids=vids.astype(np.int64),
                faces=faces.astype(np.int64),
                warp_dir=warp,
                ease=np.ones(len(faces)),
                boundary=boundary,
                body_part=p.body_part,
                mirror_of=p.mirror_of,
            )
        )
    # seams and hems along the lines: faces left/right of each line edge
    hkey_order = order
    skey = key[hkey_order]

    def halfedge(a, b):
        k = a * n + b
        pos = np.clip(np.searchsorted(skey, k), 0, len(skey) - 1)
        return np.where(skey[pos] == k, hkey_order[pos], -1)

    seams, hems = [], {}
    for runs, li in zip(lines, lines_li):
        line = spec.lines[li]
        stretches = []
        for s in runs:
            a, b = s[:-1], s[1:]
            hl = halfedge(a, b)  # left face has a -> b
            hr = halfedge(b, a)
            pl = np.where(hl >= 0, lab[np.maximum(hl, 0) // 3], -1)
            pr = np.where(hr >= 0, lab[np.maximum(hr, 0) // 3], -1)
            la0 = np.where(hl >= 0, local_of_corner[np.maximum(hl, 0)], -1)
            la1 = np.where(hl >= 0, local_of_corner[nxt(np.maximum(hl, 0))], -1)
            lb0 = np.where(hr >= 0, local_of_corner[nxt(np.maximum(hr, 0))], -1)
            lb1 = np.where(hr >= 0, local_of_corner[np.maximum(hr, 0)], -1)
            closed_run = len(s) > 2 and s[0] == s[-1]
            if line.role == "seam":
                both = (pl >= 0) & (pr >= 0)
                key = np.where(both, pl * (len(gpanels) + 1) + pr, -1)
                for sel in _joined(_joined(_stretches(key, closed_run), la0, la1), lb0, lb1):
                    if key[sel[0]] >= 0:
                        stretches.append(
                            (
                                int(pl[sel[0]]),
                                int(pr[sel[0]]),
                                np.append(la0[sel], la1[sel[-1]]),
                                np.append(lb0[sel], lb1[sel[-1]]),
                            )
                        )
                one_l = np.where(~both, pl, -1)
                one_r = np.where(~both, pr, -1)
            else:
                one_l, one_r = pl, pr
            # open edges: hems per side
            for side, l0, l1 in ((one_l, la0, la1), (one_r, lb0, lb1)):
                for sel in _joined(_stretches(side, closed_run), l0, l1):
                    if side[sel[0]] >= 0:
                        verts = np.append(l0[sel], l1[sel[-1]])
                        if side is one_r:
                            verts = verts[::-1]  # keep the panel on the left of the polyline
                        hems.setdefault(panel_names[int(side[sel[0]])], []).append(verts.astype(np.int64))
        for k, (pa, pb, va, vb) in enumerate(stretches):
            nm = line.name if len(stretches) == 1 else f"{line.name}#{k}"
            seams.append(
                Seam(
                    name=nm,
                    panel_a=panel_names[pa],
                    panel_b=panel_names[pb],
                    verts_a=np.asarray(va, np.int64),
                    verts_b=np.asarray(vb, np.int64),
                )
            )
    clock.lap("panels_seams")
    return {"panels": panels, "seams": seams, "hems": hems, "vertex_of_global": vertex_of_global}


def _stretches(key: np.ndarray, closed: bool) -> List[np.ndarray]:
    """Edge index runs of constant ``key`` along a line run (wrapping if closed)."""
    m = len(key)
    if m == 0:
        return []
    start = 0
    if closed:
        change = np.nonzero(key != np.roll(key, 1))[0]
        if len(change) == 0:
            return [np.arange(m)]
        start = int(change[0])
    idx = (np.arange(m) + start) % m if closed else np.arange(m)
    k_ = key[idx]
    cuts = np.nonzero(k_[1:] != k_[:-1])[0] + 1
    return np.split(idx, cuts)


def _joined(stretches: List[np.ndarray], l0: np.ndarray, l1: np.ndarray) -> List[np.ndarray]:
    """The stretches split where consecutive edges do not share their local vertex
    (``l1`` of one edge != ``l0`` of the next): where the line crosses the mouth of a
    dart, whose two legs split the vertex there in the panel."""
    out = []
    for sel in stretches:
        brk = np.nonzero(l1[sel[:-1]] != l0[sel[1:]])[0] + 1
        out += np.split(sel, brk) if len(brk) else [sel]
    return out


def _boundary_loops(a: np.ndarray, b: np.ndarray, name: str) -> List[np.ndarray]:
    """Closed boundary loops (local ids), longest first, from boundary half-edges a -> b."""
    nxt = {}
    for u, v in zip(a.tolist(), b.tolist()):
        if u in nxt:
            raise CutError(f"panel {name!r} is not a manifold surface (its boundary touches itself)")
        nxt[u] = v
    loops = []
    seen = set()
    for s in sorted(nxt):
        if s in seen:
            continue
        loop = [s]
        seen.add(s)
        v = nxt[s]
        while v != s:
            if v in seen or v not in nxt:
                raise CutError(f"panel {name!r}: its boundary does not form closed loops")
            loop.append(v)
            seen.add(v)
            v = nxt[v]
        loops.append(np.asarray(loop, dtype=np.int64))
    loops.sort(key=lambda l: -len(l))
    return loops
