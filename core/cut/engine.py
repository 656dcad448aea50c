"""The cutting engine: a :class:`CutSpec` on a body -> :class:`GarmentCut`.

Pipeline (paper, "Cutting the Body Surface"):

1. optional skirt topology (:mod:`.skirt`): inter-leg faces removed, legs bridged;
2. keypoints inserted as vertices, one edge-flip geodesic solver, geodesic
   paths between consecutive keypoints (:mod:`.geodesic`);
3. per garment, its cut lines inserted exactly by splitting edges/triangles
   (:mod:`.split`); panels by flood fill from their seeds, never across a cut;
4. optional refinement to a target edge length, then Delaunay edge flips
   inside panels for better triangles (:mod:`.refine`);
5. per-panel meshes (vertices duplicated where a cut runs inside a panel),
   boundary loops, seams, hems, pins and grain (:mod:`.grain`).

Every garment vertex is a fixed linear combination of body vertices (the
sparse ``embedding``), so the cut evaluates on any shape and pose. A cut line
applies to the garment named by :attr:`CutLine.garment`, or by its name's
prefix (``"shirt.side_left"`` -> garment ``"shirt"``), or to every garment;
garments are cut separately so overlapping garments do not cut each other.

Output conventions: global garment vertex ids are grouped per garment (in
the order of ``spec.garments``). Panels share a global id only where they are
sewn: along seams. The two sides of an opening line get their own ids, also
where the opening runs between two panels (a jacket's front) or inside one
(a slit), so later stages that weld by global id never close an opening. A
panel's ``vertex_ids`` may repeat a global id where a seam runs inside the
panel (sewn to itself, e.g. a one-piece sleeve). A seam is one stretch of a "seam" line with the same two panels on
its sides (``panel_a`` on the left of the line's direction; named
``line.name``, or ``line.name#k`` when the line has several stretches). Hems
are the open stretches (opening lines, and seam lines with no panel on one
side), each with its panel on the left. A stretch that goes all around a
closed line repeats its first vertex at the end. Pins are the garment's
vertices on its ``pin_line``, in line order. ``warp_dir`` points up the body
part (see :mod:`.grain`).
"""

from __future__ import annotations

import time
import weakref
from typing import Dict, List, Optional, Sequence

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..design.spec import CutLine, CutSpec, PanelSpec
from ..errors import CutError
from ..progress import report
from .darts import midline_guards
from .geodesic import GeodesicPaths, check_surface_point, insert_keypoints
from .grain import body_part_axis
from .panels import build_panels, halfedges
from .seeds import seed_face, seed_hint, seed_label
from .split import CutMesh
from .symmetric import body_face_sides, coded_labels, mirrored_mesh
from .types import GarmentCut, Panel, Seam

FORBIDDEN_REGIONS = ("head", "hands", "feet")
ERODE = 2  # rings of vertices a garment may overlap a forbidden region's border by


# --------------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------------
def _validate(spec: CutSpec, n_faces: int) -> None:
    if not spec.panels:
        raise CutError("the cut spec has no panels")
    garments = {g.name for g in spec.garments}
    names = set()
    for line in spec.lines:
        if line.name in names:
            raise CutError(f"cut line {line.name!r} is defined twice")
        names.add(line.name)
        if line.role not in ("seam", "opening"):
            raise CutError(f"cut line {line.name!r}: role must be 'seam' or 'opening', got {line.role!r}")
        need = 3 if line.closed else 2
        if len(line.points) < need:
            raise CutError(
                f"cut line {line.name!r}: needs at least {need} keypoints"
                f"{' (it is closed)' if line.closed else ''}, got {len(line.points)}"
            )
        for k, p in enumerate(line.points):
            check_surface_point(p, n_faces, f"cut line {line.name!r} point {k}")
        g = getattr(line, "garment", None)
        if g is not None and g not in garments:
            raise CutError(f"cut line {line.name!r}: unknown garment {g!r}")
    pnames = set()
    for p in spec.panels:
        if p.name in pnames:
            raise CutError(f"panel {p.name!r} is defined twice")
        pnames.add(p.name)
        if p.garment not in garments:
            raise CutError(f"panel {p.name!r}: unknown garment {p.garment!r}; garments: {', '.join(sorted(garments))}")
        if p.body_part not in ("torso", "arm", "leg"):
            raise CutError(f"panel {p.name!r}: body_part must be 'torso', 'arm' or 'leg', got {p.body_part!r}")
        check_surface_point(p.seed, n_faces, f"panel {p.name!r} seed")
    for g in spec.garments:
        if g.pin_line is not None and g.pin_line not in names:
            raise CutError(f"garment {g.name!r}: pin_line {g.pin_line!r} is not a cut line")
    if spec.refine_edge_length is not None and not (spec.refine_edge_length > 0):
        raise CutError(f"refine_edge_length must be > 0 metres or None, got {spec.refine_edge_length!r}")


def line_garments(line: CutLine, garments: Sequence[str]) -> List[str]:
    """Garments a cut line cuts: its ``garment`` field, its name prefix, or all."""
    g = getattr(line, "garment", None)
    if g is not None:
        return [g]
    prefix = line.name.split(".", 1)[0] if "." in line.name else None
    if prefix in garments:
        return [prefix]
    return list(garments)


_FORBIDDEN_CACHE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def forbidden_body_faces(body, n_faces: int) -> np.ndarray:
    """:func:`_forbidden_body_faces`, cached per body model (its regions are fixed)."""
    try:
        hit = _FORBIDDEN_CACHE.get(body)
    except TypeError:  # not weak-referenceable: no cache
        return _forbidden_body_faces(body, n_faces)
    if hit is None or len(hit) != n_faces:
        hit = _forbidden_body_faces(body, n_faces)
        hit.flags.writeable = False
        _FORBIDDEN_CACHE[body] = hit
    return hit


def _forbidden_body_faces(body, n_faces: int) -> np.ndarray:
    """(F,) int: per body triangle, 1 + index into FORBIDDEN_REGIONS of the region it lies
    in, or 0. The regions are eroded by ``ERODE`` rings of vertices first: a garment may
    run along (or slightly over) a region's border, e.g. a neckline at the neck landmarks,
    while a panel whose seamline does not close floods the whole region anyway."""
    faces = np.asarray(body.faces)
    nv = int(faces.max()) + 1
    out = np.zeros(len(faces), dtype=np.int64)
    for k, r in enumerate(FORBIDDEN_REGIONS):
        mark = np.zeros(nv, dtype=bool)
        ids = np.asarray(body.regions.get(r, []), dtype=np.int64)
        mark[ids[(ids >= 0) & (ids < nv)]] = True
        for _ in range(ERODE):
            mark[faces[~mark[faces].all(1)].reshape(-1)] = False
        out[(out == 0) & mark[faces].all(1)] = k + 1
    return out


# --------------------------------------------------------------------------------------------
# main entry
# --------------------------------------------------------------------------------------------
class _Clock:
    """Accumulates wall seconds per stage into ``timings`` (a dict), if one is given."""

    def __init__(self, timings: Optional[dict]):
        self.timings = timings
        self.t = time.perf_counter()

    def lap(self, stage: str) -> None:
        if self.timings is None:
            return
        now = time.perf_counter()
        self.timings[stage] = self.timings.get(stage, 0.0) + now - self.t
        self.t = now


def cut_surface(
    body,
    body_vertices: np.ndarray,
    spec: CutSpec,
    progress=None,
    timings: Optional[dict] = None,
    seed_names: Optional[Dict[str, str]] = None,
) -> GarmentCut:
    """Cut the body surface into garment panels.

    Parameters
    ----------
    body : BodyModel (faces, regions, landmarks, joint_names, joints()).
    body_vertices : (V, 3) float, the reference body the design is made on (metres).
    spec : CutSpec, lines, panels and garments (see :mod:`core.design.spec`).
    progress : optional ``progress(fraction, message)`` callback.
    timings : optional dict, filled with wall seconds per stage (``prepare``, ``skirt``,
        ``keypoints``, ``geodesics``, ``splitting``, ``flood_fill``, ``embedding``,
        ``refine``, ``delaunay_flips``, ``axes``, ``grain``, ``panels_seams``), for benchmarks.
    seed_names : optional dict, panel name -> its seed as the design names it
        (``"keypoint 'chest_front'"``), for error messages.

    Returns
    -------
    GarmentCut with ``ease`` = 1 everywhere (filled by the design stage).
    """
    X = np.asarray(body_vertices, dtype=float)
    BF = np.asarray(body.faces, dtype=np.int64)
    if X.ndim != 2 or X.shape[1] != 3 or not np.all(np.isfinite(X)):
        raise CutError("body vertices must be a finite (V, 3) array")
    if BF.max() >= len(X):
        raise CutError(f"body vertices ({len(X)}) do not match the body's faces")
    clock = _Clock(timings)
    _validate(spec, len(BF))
    report(progress, 0.0, "cutting: preparing the body mesh")
    mesh = CutMesh(X, BF)
    forbidden = forbidden_body_faces(body, len(BF))
    clock.lap("prepare")
    bridge_sides = span = None
    if spec.skirt:
        from .skirt import make_skirt, span_surface

        bridge_sides = make_skirt(mesh, body, X)
        # the skirt lies on a membrane over the concavities between the legs, not in the
        # creases: the cut works on that surface, and its embedding is composed with it below
        span = span_surface(mesh, body, X)
        if span is not None:
            X = np.asarray(span @ X)
        forbidden = np.concatenate([forbidden, np.zeros(mesh._ptri_count() - len(BF), dtype=np.int64)])
        clock.lap("skirt")

    # keypoints of every line as vertices; one geodesic solver on that mesh
    report(progress, 0.1, "cutting: inserting keypoints")
    flat = [p for line in spec.lines for p in line.points]
    kv = insert_keypoints(mesh, flat, BF, X)
    line_kv, k = [], 0
    for line in spec.lines:
        line_kv.append(kv[k : k + len(line.points)])
        k += len(line.points)
    clock.lap("keypoints")
    report(progress, 0.2, "cutting: geodesic paths")
    geo = GeodesicPaths(mesh.X, mesh.F)
    paths: List[List[np.ndarray]] = []
    for line, ids in zip(spec.lines, line_kv):
        seq = list(ids) + ([ids[0]] if line.closed else [])
        segs = []
        for a, b in zip(seq[:-1], seq[1:]):
            if a == b:
                continue
            segs.append(geo.path(a, b))
        if not segs:
            raise CutError(f"cut line {line.name!r}: all its keypoints coincide")
        paths.append(segs)
    clock.lap("geodesics")

    axes = _axes(body, X, spec)
    sides = body_face_sides(body, X)
    if sides is not None and spec.skirt:
        # the bridge's triangles are parents after the body's: their sides follow (None: the
        # bridge lies across the midline, no mirrored rebuild)
        sides = None if bridge_sides is None else np.concatenate([sides, bridge_sides])
    mirror = None if sides is None else (np.asarray(body.symmetry, dtype=np.int64), sides)
    guards = midline_guards(spec.lines, mirror)
    clock.lap("axes")
    gnames = [g.name for g in spec.garments]
    garment_lines = {g: [i for i, l in enumerate(spec.lines) if g in line_garments(l, gnames)] for g in gnames}
    panels: List[Panel] = []
    seams: List[Seam] = []
    hems: Dict[str, List[np.ndarray]] = {}
    pins: Dict[str, np.ndarray] = {}
    rows: List[sp.csr_matrix] = []
    offset = 0
    names = [l.name for l in spec.lines]
    for gi, g in enumerate(spec.garments):
        gpanels = [p for p in spec.panels if p.garment == g.name]
        if not gpanels:
            continue
        base = 0.3 + 0.65 * gi / len(spec.garments)
        report(progress, base, f"cutting garment {g.name}: inserting cut lines")
        gm = mesh.copy() if len(spec.garments) > 1 else mesh
        seqs = {}
        todo = garment_lines[g.name]
        for k, li in enumerate(todo):
            report(
                progress,
                base + 0.2 * k / max(len(todo), 1) / len(spec.garments),
                f"cutting garment {g.name}: line {names[li]}",
            )
            gm.avoid = guards.get(li, frozenset())  # vertices the line may not snap to
            seqs[li] = _insert_line(gm, li, line_kv[li], paths[li], spec.lines[li].closed, names)
            gm.avoid = frozenset()
        clock.lap("splitting")
        report(progress, base + 0.2 / len(spec.garments), f"cutting garment {g.name}: panels")
        out = _garment_panels(gm, spec, g, gpanels, seqs, forbidden, BF, X, axes, offset, clock, seed_names, mirror)
        panels += out["panels"]
        seams += out["seams"]
        hems.update(out["hems"])
        if out["pins"] is not None:
            pins[g.name] = out["pins"]
        rows.append(out["W"])
        offset += out["W"].shape[0]
    W = sp.vstack(rows).tocsr() if rows else sp.csr_matrix((0, len(X)))
    if span is not None:
        W = (W @ span).tocsr()
    W.sort_indices()
    darts = {}
    if any(getattr(l, "dart", None) is not None for l in spec.lines):
        from .darts import dart_records

        darts = dart_records(spec, seams, X, BF)
    report(progress, 1.0, "cutting: done")
    return GarmentCut(
        body=dict(spec.body),
        embedding=W,
        panels=panels,
        seams=seams,
        garments={g.name: g.kind for g in spec.garments},
        pins=pins,
        hems=hems,
        materials=dict(spec.materials),
        darts=darts,
    )


def _axes(body, X, spec):
    """Long axes of torso, arms and legs on the reference body ``X``.

    Joints are used when the model can evaluate them for the spec's shape and
    pose and its vertices there are ``X`` (checked); otherwise the principal
    axis of the body-part region, then landmarks, then the vertical."""
    joints = None
    jn = getattr(body, "joint_names", None)
    if jn:
        try:
            shape, pose = spec.body.get("shape"), spec.body.get("pose")
            if hasattr(body, "vertices_and_joints"):
                V, J = body.vertices_and_joints(shape, pose)
            else:
                V, J = body.vertices(shape, pose), body.joints(shape, pose)
            V, J = np.asarray(V, float), np.asarray(J, float)
            if V.shape == X.shape and np.abs(V - X).max() < 1e-6 and J.shape == (len(jn), 3):
                joints = J
        except Exception:  # e.g. a size name the model does not evaluate directly
            joints = None
    lm = getattr(body, "landmarks", None)
    regions = getattr(body, "regions", None) or {}
    out = {}
    for part in ("torso", "arm", "leg"):
        for side in ("left", "right"):
            name = "torso" if part == "torso" else f"{part}_{side}"
            ids = np.asarray(regions.get(name, []), dtype=np.int64)
            pts = X[ids] if len(ids) >= 10 else None
            out[(part, side)] = body_part_axis(part, side, jn, joints, lm, np.asarray(body.faces), X, region_points=pts)
    return out


def _insert_line(mesh: CutMesh, li: int, kv: List[int], segs: List[np.ndarray], closed: bool, names) -> np.ndarray:
    """Trace a line's geodesic segments into the mesh; its ordered vertex sequence."""
    allowed = set(kv)
    seq_k = list(kv) + ([kv[0]] if closed else [])
    seq_k = [a for i, a in enumerate(seq_k) if i == 0 or a != seq_k[i - 1]]
    out = [seq_k[0]]
    for s, (a, b) in enumerate(zip(seq_k[:-1], seq_k[1:])):
        pts = segs[s]
        cur = a
        for q in pts[1:-1]:
            got = mesh.trace(cur, q, li, allowed, names=names)
            out += got
            if got:
                cur = got[-1]
        got = mesh.trace(cur, mesh.X[b].copy(), li, allowed, target_vertex=b, names=names)
        out += got
        if out[-1] != b:
            raise CutError(f"cut line {names[li]!r}: could not reach keypoint {s + 1}")
    return np.asarray(out, dtype=np.int64)


# --------------------------------------------------------------------------------------------
# panels: flood fill between the cut lines (their vertices, seams and hems: core.cut.panels)
# --------------------------------------------------------------------------------------------
def face_components(F: np.ndarray, n: int, cut_ukeys: np.ndarray):
    """Connected components of faces across edges that are not cut."""
    key, ukey, twin, _ = halfedges(F, n)
    ok = (twin >= 0) & ~np.isin(ukey, cut_ukeys)
    i = np.nonzero(ok)[0]
    A = sp.coo_matrix((np.ones(len(i)), (i // 3, twin[i] // 3)), shape=(len(F), len(F)))
    return connected_components(A, directed=False)[1]


def _garment_panels(
    mesh: CutMesh,
    spec: CutSpec,
    g,
    gpanels: List[PanelSpec],
    seqs: Dict[int, np.ndarray],
    forbidden: np.ndarray,
    BF,
    X,
    axes,
    offset: int,
    clock: Optional[_Clock] = None,
    seed_names: Optional[Dict[str, str]] = None,
    mirror=None,
):
    """One garment's panels; ``mirror``: ``(body symmetry, body triangle sides)`` to make a
    mirrored garment's right half the exact mirror of its left (:mod:`.symmetric`), or None."""
    clock = clock or _Clock(None)
    F = mesh.F.copy()
    n = mesh.nv
    cut_ukeys = np.array(sorted(a * n + b for (a, b) in mesh.cut), dtype=np.int64)
    comp = face_components(F, n, cut_ukeys)
    fb = forbidden[mesh.parent]
    bad_comp = np.zeros(comp.max() + 1, dtype=np.int64)
    bad_comp[comp[fb > 0]] = fb[fb > 0]
    label = np.full(len(F), -1, dtype=np.int64)
    owner: Dict[int, str] = {}
    by_name = {p.name: p for p in gpanels}
    for pi, p in enumerate(gpanels):
        c = comp[seed_face(mesh, p, BF, X, seed_names)]
        if c in owner:
            # a seed on (or a millimetre from) a seamline is the likely cause: named first
            hint = seed_hint(mesh, [by_name[owner[c]], p], list(seqs), [l.name for l in spec.lines], BF, X, seed_names)
            raise CutError(
                f"panels {owner[c]!r}{seed_label(owner[c], seed_names)} and {p.name!r}"
                f"{seed_label(p.name, seed_names)} are in one region, so panel {p.name!r} has no faces "
                f"of its own: {hint}a seamline between them is missing or does not close"
                + _open_ends(mesh, spec, seqs, comp, c)
            )
        if bad_comp[c]:
            hint = seed_hint(mesh, [p], list(seqs), [l.name for l in spec.lines], BF, X, seed_names)
            raise CutError(
                f"panel {p.name!r}{seed_label(p.name, seed_names)} reaches the "
                f"{FORBIDDEN_REGIONS[bad_comp[c] - 1]} region: {hint}a seamline around it does not "
                f"close{_open_ends(mesh, spec, seqs, comp, c)}"
            )
        owner[c] = p.name
        label[comp == c] = pi
    keep = label >= 0
    if not keep.any():
        raise CutError(f"garment {g.name!r}: no panel has faces")
    # compact the garment's vertices
    clock.lap("flood_fill")
    Fg = F[keep]
    lab = label[keep]
    used = np.unique(Fg)
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    Fg = remap[Fg]
    Xg = mesh.X[used]
    W = _weights(mesh, used, len(X))
    clock.lap("embedding")
    lines_li = sorted(seqs)
    lines = [remap[seqs[li]] for li in lines_li]
    plan, lab = coded_labels(
        mirror, [p.name for p in gpanels], [spec.lines[li].name for li in lines_li], mesh.parent[keep], lab
    )
    if spec.refine_edge_length is not None:
        from .refine import delaunay_flips, refine

        # lines may leave the garment (-1 ids): refine only their in-garment stretches
        pieces, owners = [], []
        for k, l in enumerate(lines):
            for s in _runs(l):
                pieces.append(s)
                owners.append(k)
        Xg, Fg, lab, W, pieces = refine(Xg, Fg, lab, W, pieces, spec.refine_edge_length)
        clock.lap("refine")
        ng = np.int64(len(Xg))
        fixed = [np.minimum(q[:-1], q[1:]) * ng + np.maximum(q[:-1], q[1:]) for q in pieces]
        Fg = delaunay_flips(
            Xg, Fg, lab, np.concatenate(fixed) if fixed else np.zeros(0, np.int64), max_length=spec.refine_edge_length
        )
        clock.lap("delaunay_flips")
        lines = [[pieces[j] for j in range(len(pieces)) if owners[j] == k] for k in range(len(lines))]
    else:
        lines = [_runs(l) for l in lines]
    if plan is not None:
        Xg, Fg, lab, W, lines = mirrored_mesh(mirror, plan, Xg, Fg, lab, W, lines, X)
        clock.lap("mirror")
    out = build_panels(spec, gpanels, Xg, Fg, lab, lines, lines_li, axes, offset, clock)
    vog = out.pop("vertex_of_global")
    pins = None
    if g.pin_line is not None:
        li = [l.name for l in spec.lines].index(g.pin_line)
        if li in lines_li:
            runs = lines[lines_li.index(li)]
            if runs:
                seq = np.concatenate(runs)
                _, first = np.unique(seq, return_index=True)
                seq = seq[np.sort(first)]
                # every garment vertex of each pinned mesh vertex (two where an opening splits it)
                rank = np.full(len(Xg), -1, dtype=np.int64)
                rank[seq] = np.arange(len(seq))
                gids = np.nonzero(rank[vog] >= 0)[0]
                pins = gids[np.argsort(rank[vog[gids]], kind="stable")] + offset
        if pins is None or len(pins) == 0:
            raise CutError(f"garment {g.name!r}: its pin line {g.pin_line!r} does not touch its panels")
    out["pins"] = pins
    out["W"] = W[vog] if len(vog) != W.shape[0] or np.any(vog != np.arange(len(vog))) else W
    return out


def _open_ends(mesh: CutMesh, spec: CutSpec, seqs: Dict[int, np.ndarray], comp: np.ndarray, c: int) -> str:
    """Text naming the open lines whose loose end (a point on no other cut line) touches
    region ``c``: where a region leaks through a seamline that does not close."""
    out = []
    for li in sorted(seqs):
        line = spec.lines[li]
        seq = seqs[li]
        if line.closed or len(seq) < 2:
            continue
        for end, v in (("first", int(seq[0])), ("last", int(seq[-1]))):
            if mesh.cut_verts.get(v, set()) - {li}:
                continue  # it meets another line there
            if any(comp[f] == c for f in mesh.vf[v]):
                out.append(f"{line.name!r} ({end} keypoint)")
    if not out:
        return ""
    if len(out) == 1:
        return f"; the open end of cut line {out[0]} meets no other line"
    return "; the open ends of cut lines " + ", ".join(out) + " meet no other line"


def _runs(seq: np.ndarray) -> List[np.ndarray]:
    """Maximal stretches of a vertex sequence with valid (>= 0) ids, length >= 2."""
    ok = seq >= 0
    out, start = [], None
    for i, v in enumerate(ok.tolist() + [False]):
        if v and start is None:
            start = i
        elif not v and start is not None:
            if i - start >= 2:
                out.append(seq[start:i])
            start = None
    return out


def _weights(mesh: CutMesh, used: np.ndarray, V: int) -> sp.csr_matrix:
    """Embedding rows of mesh vertices ``used``: identity rows for body vertices, the
    stored body weights for vertices the cut added."""
    used = np.asarray(used, dtype=np.int64)
    body = used < mesh.n_body
    rows, cols, vals = [np.nonzero(body)[0]], [used[body]], [np.ones(int(body.sum()))]
    for r in np.nonzero(~body)[0].tolist():
        c, w = mesh.vertex_weights(int(used[r]))
        rows.append(np.full(len(c), r))
        cols.append(c)
        vals.append(w)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(len(used), V))
