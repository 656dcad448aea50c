"""Garment over garment: the inner layers as a collider, the outer's start outside them, and the
measure of one layer against another.

A layered drape (:func:`core.workflows.drape_outfit`) drapes the garments inner first; each outer
garment drapes against the body plus the inner garments' draped surfaces, each offset outward by
its fabric thickness (:func:`layer_collider`), with the outer fabric's contact thickness and
friction on top (friction between layers is the outer fabric's Coulomb friction, as against the
body). The outer garment starts from its skintight embedding pushed out over the inner surfaces
(:func:`push_outside`), so contact, which pushes a particle out along the nearest surface's
normal, starts on the right side of every layer.

:func:`layer_distance` is the measure: the signed distance of points to a draped garment along its
own (outward) face normals, counted only where the closest point lies inside the surface, not on
its open edges (a trouser leg below a shirt's hem is not "inside" the shirt).
"""

from __future__ import annotations

from typing import Sequence, Tuple

import numpy as np

from ..errors import DrapeError
from ..geom.mesh import face_normals, vertex_normals

#: An outer point more than this inside the inner surface is a penetration (issue 37: 2 mm).
PENETRATION_DEPTH = 0.002
#: Points farther than this from the inner surface (either side) do not overlap it (another body part).
OVERLAP_BAND = 0.05
#: m, a collider face whose outer side this far out is inside the collider is buried (left out)
BURIED_LIFT = 0.0005
#: How far inside an inner garment the body is still under it (a loose garment's hem hangs this far off).
COVER_BAND = 0.15


def open_edges(f: np.ndarray) -> np.ndarray:
    """(k, 2) int, the edges of the triangles ``f`` used by one triangle only (hems, necklines, cuffs)."""
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    key, count = np.unique(e, axis=0, return_counts=True)
    return key[count == 1]


class Skin(tuple):
    """(vertices, faces) of a closed skin (:func:`measure_skin`) that keeps the Warp mesh
    :func:`inside_skin` builds of it (a layered drape measures every frame over the same skin)."""

    def __new__(cls, vertices, faces):
        return super().__new__(cls, (np.asarray(vertices, np.float64), np.asarray(faces, np.int64)))

    def mesh(self):
        from ..geom.queries import warp_mesh

        if not hasattr(self, "_mesh"):
            self._mesh = warp_mesh(self[0], self[1], device="cpu")
        return self._mesh


def inside_skin(points, skin_v, skin_f, mesh=None) -> np.ndarray:
    """(n,) bool, the points inside the closed skin (skin_v, skin_f) (:func:`layer_collider`): its
    winding number over 1/2. Robust where the skin is not one clean closed surface (an inner
    garment's folds, its ramps sunk into the body), where the closest face's normal is not.
    ``mesh``: the skin's Warp mesh when already built (:class:`Skin`)."""
    from ..geom.queries import warp_mesh
    from .kernels import inside_winding, wp

    p = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    if not len(p):
        return np.zeros(0, bool)
    wp.init()
    if mesh is None:
        mesh = warp_mesh(skin_v, skin_f, device="cpu")
    out = wp.zeros(len(p), dtype=int, device="cpu")
    wp.launch(inside_winding, len(p), inputs=[wp.array(p, dtype=wp.vec3, device="cpu"), mesh.id, out], device="cpu")
    return out.numpy().astype(bool)


def layer_distance(points, v, f, skin=None) -> Tuple[np.ndarray, np.ndarray]:
    """Signed distance (m) of ``points`` to the surface (v, f), positive on its normals' side, and
    whether each point's closest point lies inside the surface (not on an open edge).

    The side is the closest face's normal's. With ``skin`` ((V, 3), (F, 3): the inner surface as a
    closed skin with the body, :func:`measure_skin`) it is the skin's (:func:`inside_skin`) for
    every point within :data:`OVERLAP_BAND` of the surface and every point that normal puts inside:
    past a fold's far side, or on a ridge where the closest point is on an edge and the face picked
    faces away, the normal says inside for a point centimetres outside; in a concave seam (the
    trousers' centre back) it says outside for a shirt's tail centimetres inside.

    Returns ``(distance (n,), over (n,) bool)``.
    """
    import igl

    p = np.ascontiguousarray(points, dtype=np.float64)
    v = np.ascontiguousarray(v, dtype=np.float64)
    f = np.ascontiguousarray(f, dtype=np.int64)
    sq, face, closest = igl.point_mesh_squared_distance(p, v, f)
    face = np.asarray(face, dtype=np.int64)
    d = p - closest
    sign = np.where(np.einsum("ij,ij->i", d, face_normals(v, f)[face]) < 0, -1.0, 1.0)
    if skin is not None:
        idx = np.flatnonzero((sign < 0) | (sq <= OVERLAP_BAND**2))
        mesh = skin.mesh() if isinstance(skin, Skin) else None
        sign[idx] = np.where(inside_skin(p[idx], *skin, mesh=mesh), -1.0, 1.0)
    dist = sign * np.sqrt(np.maximum(sq, 0.0))
    # barycentrics of the closest point: on a boundary edge (a ~ 0 opposite it) the point is off the edge
    a, b, c = v[f[face, 0]], v[f[face, 1]], v[f[face, 2]]
    v0, v1, v2 = b - a, c - a, closest - a
    d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
    d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
    den = np.where(np.abs(d00 * d11 - d01 * d01) > 1e-30, d00 * d11 - d01 * d01, 1e-30)
    bb = (d11 * d20 - d01 * d21) / den
    bc = (d00 * d21 - d01 * d20) / den
    bary = np.stack([1.0 - bb - bc, bb, bc], axis=1)
    boundary = {tuple(k) for k in open_edges(f)}
    over = np.ones(len(p), dtype=bool)
    tol = 1e-6
    for k, (i, j) in enumerate(((1, 2), (2, 0), (0, 1))):  # edge opposite corner k
        on_edge = bary[:, k] < tol
        if not on_edge.any():
            continue
        idx = np.nonzero(on_edge)[0]
        ends = np.sort(np.stack([f[face[idx], i], f[face[idx], j]], axis=1), axis=1)
        hit = np.array([tuple(e) in boundary for e in ends], dtype=bool)
        over[idx[hit]] = False
    return dist, over


def layer_measure(points, v, f, depth: float = PENETRATION_DEPTH, band: float = OVERLAP_BAND, skin=None) -> dict:
    """Penetration and gap of an outer layer's ``points`` over an inner layer's surface (v, f).

    Only points over the inner surface and within ``band`` of it count (``overlap`` of them): the
    penetration share is of those more than ``depth`` inside it; the gap is their signed distance.
    ``skin``: the inner surface closed with the body (:func:`measure_skin`), which decides inside
    where the closest face's normal says so (:func:`layer_distance`).
    """
    dist, over = layer_distance(points, v, f, skin=skin)
    near = over & (np.abs(dist) <= band)
    n = int(near.sum())
    inside = near & (dist < -depth)
    gap = dist[near] * 1000.0
    return {
        "overlap": n,
        "points": int(len(dist)),
        "penetrating": int(inside.sum()),
        "penetration_pct": 100.0 * float(inside.sum()) / n if n else 0.0,
        "gap_mm": {
            "mean": float(gap.mean()) if n else 0.0,
            "p95": float(np.percentile(gap, 95)) if n else 0.0,
            "min": float(gap.min()) if n else 0.0,
        },
    }


def _directed_open_edges(f: np.ndarray) -> np.ndarray:
    """(k, 2) the open edges as their one triangle runs them (a -> b)."""
    d = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key, inv, count = np.unique(np.sort(d, axis=1), axis=0, return_inverse=True, return_counts=True)
    return d[count[inv.ravel()] == 1]


def hem_strips(v, f, body_v, body_f, sink: float = 0.002, ramp: float = 2.0) -> Tuple[np.ndarray, np.ndarray]:
    """The open edges of the surface (v, f) joined to the body by a strip of triangles, oriented as
    the surface (its normals turn with it towards the body). Each open-edge vertex goes to the body
    point closest to it carried on past the edge, in the surface's direction, by ``ramp`` times its
    distance to the body (a ramp, not a step, for the outer layer to slide over), ``sink`` into the
    body. Returns (new vertices (k, 3), triangles (2e, 3) indexing ``v`` then the new vertices). A
    collider with these strips has no free edge under which an outer layer could be caught (contact
    past an open edge would push it round the edge)."""
    import igl

    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    body_v = np.asarray(body_v, np.float64)
    body_f = np.asarray(body_f, np.int64)
    edges = _directed_open_edges(f)
    if not len(edges):
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    # each open edge's direction away from the surface, in its triangle's plane
    tri_normal = face_normals(v, f)
    d = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    owner = np.tile(np.arange(len(f)), 3)
    key = {tuple(e): k for k, e in enumerate(d.tolist())}
    tri = owner[[key[tuple(e)] for e in edges.tolist()]]
    along = v[edges[:, 1]] - v[edges[:, 0]]
    away = np.cross(along, tri_normal[tri])  # a -> b runs counter-clockwise: along x n points out
    away /= np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-12)
    out = np.zeros_like(v)
    np.add.at(out, edges[:, 0], away)
    np.add.at(out, edges[:, 1], away)
    ring = np.unique(edges)
    out = out[ring] / np.maximum(np.linalg.norm(out[ring], axis=1, keepdims=True), 1e-12)
    gap, _, _ = igl.point_mesh_squared_distance(v[ring], body_v, body_f)
    _, _, foot = igl.point_mesh_squared_distance(v[ring] + out * ramp * np.sqrt(gap)[:, None], body_v, body_f)
    inward = foot - v[ring]
    length = np.linalg.norm(inward, axis=1, keepdims=True)
    foot = foot + inward / np.where(length > 0, length, 1.0) * sink
    new_id = np.full(len(v), -1, np.int64)
    new_id[ring] = len(v) + np.arange(len(ring))
    a, b = edges[:, 0], edges[:, 1]
    tris = np.concatenate([np.column_stack([b, a, new_id[a]]), np.column_stack([b, new_id[a], new_id[b]])])
    return foot, tris


def covered_faces(body_v, body_f, v, f, band: float = COVER_BAND) -> np.ndarray:
    """(F,) bool, the body triangles under the garment surface (v, f): their centre inside it, over
    it (not past its open edges), within ``band`` of it, and the garment met by the ray out along
    the triangle's normal within ``band`` (the body between the legs, below a tucked shirt's tails,
    is inside and near the shirt but faces away from it: it is kept, or the trousers' crotch would
    find no body there)."""
    from ..geom.queries import ray_hit_distance

    body_v = np.asarray(body_v, np.float64)
    body_f = np.asarray(body_f, np.int64)
    centre = body_v[body_f].mean(axis=1)
    dist, over = layer_distance(centre, v, f)
    out = over & (dist < 0) & (dist > -band)
    if out.any():
        idx = np.flatnonzero(out)
        out[idx] = ray_hit_distance(centre[idx], face_normals(body_v, body_f[idx]), v, f, max_t=band) > 0
    return out


def layer_collider(
    body_v, body_f, inner: Sequence[Tuple[np.ndarray, np.ndarray, float]], strips: bool = True, buried: bool = False
):
    """One collider mesh: the body plus every inner garment's surface (vertices, faces, offset m),
    each moved outward along its vertex normals by its offset (the inner fabric's thickness).

    With ``strips`` each inner garment's open edges are joined to the body (:func:`hem_strips`) and
    the body under it is left out (:func:`covered_faces`): the collider is one closed skin, so an
    outer particle pressed through an inner garment finds that garment, not the body under it, as
    its closest surface and is pushed back out (with the body there it would stay caught between).
    With ``buried`` (the layered drape's contact) the inner garments' faces buried in that skin are
    left out (:func:`_unburied`): where an inner garment passes through itself (a sleeve into the
    side under the arm) an outer particle would find one the closest, be pushed out of its plane
    still inside the other sheet, and chatter.
    """
    body_v = np.asarray(body_v, dtype=np.float64)
    body_f = np.asarray(body_f, dtype=np.int64)
    keep = np.ones(len(body_f), bool)
    vs, fs, base = [body_v], [], len(body_v)
    for v, f, offset in inner:
        v = np.asarray(v, dtype=np.float64)
        f = np.asarray(f, dtype=np.int64)
        if not np.all(np.isfinite(v)):
            raise DrapeError("an inner layer's draped surface holds NaN/inf")
        v = v + vertex_normals(v, f) * float(offset)
        if strips:
            keep &= ~covered_faces(body_v, body_f, v, f)
            foot, tris = hem_strips(v, f, body_v, body_f)
            v, f = np.concatenate([v, foot]), np.concatenate([f, tris])
        vs.append(v)
        fs.append(f + base)
        base += len(v)
    v, f = np.concatenate(vs), np.concatenate([body_f[keep], *fs])
    if strips and buried:
        nb = int(keep.sum())  # the body's faces come first
        f = np.concatenate([f[:nb], _unburied(v, f, f[nb:])])
    return v, f


def _unburied(v, all_f, faces, lift: float = BURIED_LIFT) -> np.ndarray:
    """``faces`` of the collider (v, all_f) less those buried in it: their outer side (the centre
    moved ``lift`` out along the face's normal) inside the collider (:func:`inside_skin`)."""
    centre = v[faces].mean(axis=1) + face_normals(v, faces) * lift
    return faces[~inside_skin(centre, v, all_f)]


def measure_skin(body_v, body_f, v, f) -> Skin:
    """The inner surface (v, f) as it lies, closed with the body (:func:`layer_collider` at offset 0):
    the skin :func:`layer_measure` tells inside from outside by."""
    return Skin(*layer_collider(body_v, body_f, [(v, f, 0.0)]))


def push_outside(points, v, f, clearance: float, band: float = OVERLAP_BAND, movable=None) -> Tuple[np.ndarray, int]:
    """``points`` moved out of the surface (v, f) to ``clearance`` outside it where they lie over it,
    within ``band``, closer than ``clearance``; returns (moved points, how many moved).

    ``movable`` ((F,) bool) instead: (v, f) is a closed skin (:func:`layer_collider`) and a point moves
    where its closest triangle is a movable one (an inner garment's or a strip's, not the body's)."""
    import igl

    p = np.array(points, dtype=np.float64)
    v = np.asarray(v, np.float64)
    f = np.asarray(f, np.int64)
    if movable is None:
        dist, over = layer_distance(p, v, f)
        face = closest = None
    else:
        sq, face, closest = igl.point_mesh_squared_distance(p, v, f)
        face = np.asarray(face, np.int64)
        normal = face_normals(v, f)[face]
        dist = np.where(np.einsum("ij,ij->i", p - closest, normal) < 0, -1.0, 1.0) * np.sqrt(np.maximum(sq, 0))
        over = np.asarray(movable, bool)[face]
    move = over & (dist < clearance) & (dist > -band)
    if move.any():
        if face is None:
            _, face, closest = igl.point_mesh_squared_distance(p, v, f)
            face = np.asarray(face, np.int64)
        p[move] = closest[move] + face_normals(v, f)[face[move]] * clearance
    return p, int(move.sum())
