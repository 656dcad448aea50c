"""Skirt topology: remove the surface between the legs, bridge the legs.

For dresses and skirts the body surface is changed before cutting (paper,
"Dresses and skirts"; like CLOTH3D): a band of the inner thighs from the
crotch down to the shins is removed, together with the crotch between them,
which leaves one hole. Its boundary runs from the front of the crotch down the
front-inner side of one leg, across, up the back-inner side, over the back of
the crotch and likewise around the other leg. The front-inner edges of both
legs are then zipped together by a strip of triangles (the front "curtain"),
and so are the back-inner edges; the two curtains meet at the bottom, which
closes the surface again. A horizontal cut above the bottom of the band then
goes around both legs as one loop: the lower body is one tube.

Everything is decided from the body's geometry on the given vertices, so it
works for any shape and pose: the band is the set of leg/crotch triangles
facing the other leg (angle around the leg axis), between the crotch
landmark and a point above the ankles. On a body with a left/right symmetry
map the band is made its own mirror image and each curtain is split on the
midline: its left half joins the left leg's edge to new midline vertices (the
midpoints of every edge vertex and its mirror, weights 1/2 and 1/2 on two
body vertices) and its right half is the reflection of the left, so the whole
surface is its own mirror and a mirrored garment on it is rebuilt as the exact
mirror of its left half (:mod:`.symmetric`). Without a symmetry map the legs'
edges are zipped directly (no new vertices). Either way every curtain vertex
is a fixed combination of body vertices, so the curtains follow any shape and
pose of the model.
"""

from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..design.mirror import face_symmetry
from ..errors import CutError
from .split import CutMesh

BAND_HALF_ANGLE = np.deg2rad(60.0)  # removed: within this angle of "towards the other leg"
CROTCH_MARGIN = 0.02  # metres above the crotch landmark included (the crotch itself)
BOTTOM = 0.15  # band bottom: this fraction of crotch->ankle above the ankles


def _landmark(body, name, X):
    try:
        sp_ = body.landmarks[name]
    except (KeyError, AttributeError, TypeError):
        raise CutError(f"skirt topology needs the body landmark {name!r}")
    return np.asarray(sp_.bary, float) @ X[np.asarray(body.faces)[sp_.triangle]]


def _leg_frame(body, X: np.ndarray):
    """The legs as the skirt topology sees them: (crotch, z_bot, z_top, legs, zc, centre).

    ``legs`` maps side -> the leg's vertex ids, ``centre`` side -> (x(zc), y(zc)): the leg's
    centre line, the centroids of horizontal slices between ``z_bot`` (the bottom of the
    band) and the crotch."""
    crotch = _landmark(body, "crotch", X)
    ankle = 0.5 * (_landmark(body, "ankle_left", X) + _landmark(body, "ankle_right", X))
    z_top = crotch[2] + CROTCH_MARGIN
    z_bot = ankle[2] + BOTTOM * (crotch[2] - ankle[2])
    regions = getattr(body, "regions", {}) or {}
    legs = {}
    for side, sign in (("left", 1.0), ("right", -1.0)):
        ids = np.asarray(regions.get(f"leg_{side}", []), dtype=np.int64)
        if len(ids) == 0:  # no leg regions: the body below the crotch on that side
            ids = np.nonzero((X[:, 2] < crotch[2]) & (sign * X[:, 0] > 0))[0]
        legs[side] = ids
    # leg centre lines: centroids of horizontal slices of each leg
    nb = 24
    edges = np.linspace(z_bot, crotch[2], nb + 1)
    zc = 0.5 * (edges[1:] + edges[:-1])
    centre = {}
    for side, ids in legs.items():
        P = X[ids]
        P = P[(P[:, 2] >= z_bot) & (P[:, 2] <= crotch[2])]
        if len(P) < 10:
            raise CutError(f"skirt topology: the body's {side} leg is not found below the crotch")
        k = np.clip(np.searchsorted(edges, P[:, 2]) - 1, 0, nb - 1)
        cx = np.bincount(k, P[:, 0], nb) / np.maximum(np.bincount(k, None, nb), 1)
        cy = np.bincount(k, P[:, 1], nb) / np.maximum(np.bincount(k, None, nb), 1)
        have = np.bincount(k, None, nb) > 0
        centre[side] = (np.interp(zc, zc[have], cx[have]), np.interp(zc, zc[have], cy[have]))
    return crotch, z_bot, z_top, legs, zc, centre


def _centres_at(z: np.ndarray, zc: np.ndarray, centre) -> Tuple[np.ndarray, np.ndarray]:
    """(left, right) leg centres (n, 2) at heights ``z`` (held at the ends of the slices)."""
    z = np.clip(z, zc[0], zc[-1])
    cl = np.stack([np.interp(z, zc, centre["left"][0]), np.interp(z, zc, centre["left"][1])], 1)
    cr = np.stack([np.interp(z, zc, centre["right"][0]), np.interp(z, zc, centre["right"][1])], 1)
    return cl, cr


def inter_leg_faces(body, X: np.ndarray) -> np.ndarray:
    """(F,) bool: body triangles between the legs (the band removed for the skirt topology)."""
    F = np.asarray(body.faces, dtype=np.int64)
    crotch, z_bot, z_top, legs, zc, centre = _leg_frame(body, X)
    regions = getattr(body, "regions", {}) or {}
    # candidate vertices: the legs and the torso just above the crotch
    cand = np.zeros(len(X), dtype=bool)
    cand[legs["left"]] = True
    cand[legs["right"]] = True
    torso = np.asarray(regions.get("torso", []), dtype=np.int64)
    cand[torso] = True
    cand &= (X[:, 2] >= z_bot) & (X[:, 2] <= z_top)
    cl, cr = _centres_at(X[:, 2], zc, centre)
    left = X[:, 0] >= 0.5 * (cl[:, 0] + cr[:, 0])
    own = np.where(left[:, None], cl, cr)
    other = np.where(left[:, None], cr, cl)
    medial = other - own
    medial /= np.maximum(np.linalg.norm(medial, axis=1), 1e-12)[:, None]
    r = X[:, :2] - own
    r /= np.maximum(np.linalg.norm(r, axis=1), 1e-12)[:, None]
    inner = (r * medial).sum(1) >= np.cos(BAND_HALF_ANGLE)
    # between the two leg centres (the crotch surface) counts as inner too
    between = np.abs(X[:, 0] - 0.5 * (cl[:, 0] + cr[:, 0])) < 0.25 * np.abs(cl[:, 0] - cr[:, 0])
    mark = cand & (inner | (between & (X[:, 2] <= z_top)))
    return mark[F].all(1)


def span_candidates(body, X: np.ndarray) -> np.ndarray:
    """(V,) bool: body vertices the spanned skirt surface may lift off the body (:mod:`.span`).

    Between the two legs' centre lines (in x), from :data:`.span.SPAN_BOTTOM` of the way
    from the crotch down to the bottom of the bridge up to :data:`.span.SPAN_TOP` of the way
    from the crotch to the back waist: the crotch, the creases beside it, the top of the
    curtains, the gluteal folds and the gluteal cleft."""
    from .span import SPAN_BOTTOM, SPAN_TOP

    crotch, z_bot, _, _, zc, centre = _leg_frame(body, X)
    top = crotch[2] + SPAN_TOP * (_landmark(body, "waist_back", X)[2] - crotch[2])
    z_bot = crotch[2] - SPAN_BOTTOM * (crotch[2] - z_bot)
    cl, cr = _centres_at(X[:, 2], zc, centre)
    lo, hi = np.minimum(cl[:, 0], cr[:, 0]), np.maximum(cl[:, 0], cr[:, 0])
    return (X[:, 2] >= z_bot) & (X[:, 2] <= top) & (X[:, 0] > lo) & (X[:, 0] < hi)


def span_surface(mesh: CutMesh, body, X: np.ndarray) -> Optional[sp.csr_matrix]:
    """Lift the skirt topology's surface off the body's concavities between the legs, in place.

    ``mesh`` is the body mesh after :func:`make_skirt`. Its vertices move onto the membrane of
    :func:`.span.spanning_operator` (bridge vertices follow their body weights), and every
    parent triangle is re-made from the moved corners, so the cut proceeds on the spanned
    surface.

    Returns
    -------
    (V, V) csr operator ``B``: the spanned body vertices are ``B @ X`` on any shape and pose
    (the cut's embedding is composed with it), or None when nothing lifts off.
    """
    from .span import spanning_operator

    S = _symmetry(body, X)
    B = spanning_operator(mesh, X, span_candidates(body, X), S)
    if B is None:
        return None
    # the body's triangles and each bridge triangle (its own parent) re-made on the moved corners
    mesh.move_body(np.asarray(B @ X), np.asarray(body.faces, dtype=np.int64))
    return B


def _clean(F: np.ndarray, H: np.ndarray, nv: int) -> np.ndarray:
    """Make the removed set one disk: its largest component, holes in it filled, no pinches."""

    def comps(sel):
        idx = np.nonzero(sel)[0]
        sub = F[idx]
        a = sub.reshape(-1)
        b = np.roll(sub, -1, 1).reshape(-1)
        ukey = np.minimum(a, b) * nv + np.maximum(a, b)
        order = np.argsort(ukey, kind="stable")
        same = ukey[order][1:] == ukey[order][:-1]
        i = order[:-1][same] // 3
        j = order[1:][same] // 3
        A = sp.coo_matrix((np.ones(len(i)), (i, j)), shape=(len(idx), len(idx)))
        return idx, connected_components(A, directed=False)[1]

    for _ in range(20):
        idx, lab = comps(H)
        if len(idx) == 0:
            raise CutError("skirt topology: no surface found between the legs")
        big = np.argmax(np.bincount(lab))
        H = np.zeros(len(F), dtype=bool)
        H[idx[lab == big]] = True
        idx, lab = comps(~H)
        big = np.argmax(np.bincount(lab))
        H[idx[lab != big]] = True
        # pinched boundary vertices (more than two boundary edges): remove their faces too
        keep = F[~H]
        a = keep.reshape(-1)
        b = np.roll(keep, -1, 1).reshape(-1)
        key = a * nv + b
        bnd = ~np.isin(key, b * nv + a)
        deg = np.bincount(a[bnd], minlength=nv)
        pinch = np.nonzero(deg > 1)[0]
        if len(pinch) == 0:
            return H
        H |= np.isin(F, pinch).any(1)
    raise CutError("skirt topology: the surface between the legs does not form one hole")


def _boundary_loop(F: np.ndarray, nv: int) -> List[int]:
    a = F.reshape(-1)
    b = np.roll(F, -1, 1).reshape(-1)
    bnd = ~np.isin(a * nv + b, b * nv + a)
    nxt = dict(zip(a[bnd].tolist(), b[bnd].tolist()))
    if not nxt:
        raise CutError("skirt topology: no boundary after removing the inter-leg surface")
    start = min(nxt)
    loop = [start]
    v = nxt[start]
    while v != start:
        loop.append(v)
        v = nxt[v]
        if len(loop) > len(nxt):
            raise CutError("skirt topology: the inter-leg boundary is not a simple loop")
    if len(loop) != len(nxt):
        raise CutError("skirt topology: the inter-leg hole has more than one boundary loop")
    return loop


def _zip(A: List[int], B: List[int], X: np.ndarray) -> List[Tuple[int, int, int, int, int]]:
    """Triangle strip between chains A and B (same start region), by normalised arc length.

    Returns triples (x, y, z): chain edge x -> y and the opposite corner z."""

    def arc(C):
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(X[C], axis=0), axis=1))])
        return s / max(s[-1], 1e-12)

    sa, sb = arc(A), arc(B)
    i = j = 0
    out = []
    if A[0] == B[0]:
        # common apex: the first triangle takes the first edge of both chains
        out.append((A[0], A[1], B[1]))
        i = j = 1
    while i < len(A) - 1 or j < len(B) - 1:
        if j == len(B) - 1 or (i < len(A) - 1 and sa[i + 1] <= sb[j + 1]):
            out.append((A[i], A[i + 1], B[j]))
            i += 1
        else:
            out.append((B[j], B[j + 1], A[i]))
            j += 1
    return out


def _symmetric_band(F: np.ndarray, H: np.ndarray, S: np.ndarray, nv: int) -> Optional[np.ndarray]:
    """The removed band made its own mirror image (its union with its reflection, cleaned), or
    None when that is not possible (the body mesh is not its own mirror)."""
    mf = face_symmetry(F, S)
    if np.any(mf < 0):
        return None
    H = _clean(F, H | H[mf], nv)
    return H if np.array_equal(H, H[mf]) else None


def _mirrored_bridge(mesh: CutMesh, loop: List[int], X: np.ndarray, S: np.ndarray):
    """The bridge as a left half and its mirror image, split on the midline.

    The hole's boundary is the mirror image of itself: from the front midline vertex down the
    left leg and up to the back midline vertex, and the reflection of that arc. Each curtain
    (front and back) is built between the left arc and a chain of new midline vertices, the
    midpoints of every arc vertex and its mirror (body weights ½ and ½, so they follow any
    shape and pose), and reflected through ``S``; both curtains end at the midpoint of the
    arc's lowest vertex and its mirror. Every bridge triangle then lies on one side of the
    midline, and the whole surface is its own mirror image, so a mirrored garment cut on it
    can be rebuilt as the exact mirror of its left half (:mod:`.symmetric`).

    Returns
    -------
    (tris (k, 3) int, sides (k,) int8: 1 on the left, 0 on the right), or None when the
    boundary is not its own mirror image (then the caller zips the legs as before).
    """
    L = np.asarray(loop)
    n = len(L)
    on_mid = np.nonzero(S[L] == L)[0]
    if len(on_mid) != 2:
        return None
    kf, kb = sorted(on_mid.tolist(), key=lambda k: X[L[k], 1])  # front (smaller y), back
    arc1 = [loop[(kf + i) % n] for i in range((kb - kf) % n + 1)]
    arc2 = [loop[(kb + i) % n] for i in range((kf - kb) % n + 1)]
    left, right = (arc1, arc2) if X[arc1[1:-1], 0].mean() > X[arc2[1:-1], 0].mean() else (arc2, arc1)
    if (
        len(left) < 3
        or left[0] != right[-1]
        or not np.array_equal(S[left], right[::-1])
        or np.any(X[left[1:-1], 0] <= 0)
    ):
        return None
    inner = np.asarray(left[1:-1])
    e = 1 + int(np.argmin(X[inner, 2]))  # the left leg's lowest hole vertex
    mid = {left[0]: left[0], left[-1]: left[-1]}
    for v in inner.tolist():
        w = int(S[v])
        cols = np.array(sorted((v, w)), dtype=np.int64)
        mid[v] = mesh._add_vertex(0.5 * (X[v] + X[w]), cols, np.array([0.5, 0.5]))
    bnd = set(zip(loop, loop[1:] + loop[:1]))
    tris = []
    for chain in (left[: e + 1], left[e:][::-1]):  # the two curtains, each from the midline down
        for a, b in zip(chain[:-1], chain[1:]):
            ma, mb = mid[a], mid[b]
            # the quad b, a, ma, mb in the orientation that holds the boundary edge reversed
            quad = [b, a, ma, mb] if (a, b) in bnd else [a, b, mb, ma]
            if ma == a:  # at the midline vertex: a triangle
                quad.remove(ma)
                tris.append(quad)
                continue
            p0, p1, p2, p3 = quad
            # the shorter diagonal
            if np.linalg.norm(mesh.X[p0] - mesh.X[p2]) <= np.linalg.norm(mesh.X[p1] - mesh.X[p3]):
                tris += [[p0, p1, p2], [p0, p2, p3]]
            else:
                tris += [[p0, p1, p3], [p1, p2, p3]]
    T = np.asarray(tris, dtype=np.int64)
    m = np.arange(mesh.nv, dtype=np.int64)
    m[: len(S)] = S
    T = np.concatenate([T, m[T][:, ::-1]])
    sides = np.repeat(np.array([1, 0], dtype=np.int8), len(tris))
    return T, sides


def make_skirt(mesh: CutMesh, body, X: np.ndarray) -> Optional[np.ndarray]:
    """Apply the skirt topology to ``mesh`` (the unmodified body mesh) in place.

    Returns
    -------
    (k,) int8 per new (bridge) parent triangle, in order: 1 on the body's left, 0 on its
    right, when the body has a symmetry map and the bridge is built as a mirror image
    (:func:`_mirrored_bridge`); else None (the legs zipped directly, triangles across the
    midline).
    """
    F = mesh.F.copy()
    nv = mesh.nv
    H = _clean(F, inter_leg_faces(body, X), nv)
    S = _symmetry(body, X)
    if S is not None:
        Hs = _symmetric_band(F, H, S, nv)
        S, H = (None, H) if Hs is None else (S, Hs)
    keep = F[~H]
    loop = _boundary_loop(keep, nv)
    if S is not None:
        got = _mirrored_bridge(mesh, loop, X, S)
        if got is not None:
            tris, sides = got
            mesh.replace_faces(np.nonzero(H)[0], tris, mesh.X[tris])
            return sides
    _zip_legs(mesh, H, loop, X)
    return None


def _symmetry(body, X: np.ndarray) -> Optional[np.ndarray]:
    """The body's left/right vertex map when it is usable (an involution with a midline that
    no triangle crosses, :func:`.symmetric.body_face_sides`), else None."""
    from .symmetric import body_face_sides

    if body_face_sides(body, X) is None:
        return None
    return np.asarray(body.symmetry, dtype=np.int64)


def _zip_legs(mesh: CutMesh, H: np.ndarray, loop: List[int], X: np.ndarray) -> None:
    """The bridge without a symmetry map: the legs' edges zipped directly (by arc length)."""
    L = np.asarray(loop)
    P = X[L]
    n = len(L)
    # the loop crosses the body's midline twice: at the front and at the back of the crotch
    mid = 0.0
    sgn = P[:, 0] >= mid
    cross = np.nonzero(sgn != np.roll(sgn, -1))[0]  # edge k -> k+1 crosses
    if len(cross) != 2:
        raise CutError(f"skirt topology: the inter-leg hole crosses the midline {len(cross)} times, expected 2")
    ks = [k if abs(P[k, 0]) <= abs(P[(k + 1) % n, 0]) else (k + 1) % n for k in cross]
    ks.sort(key=lambda k: P[k, 1])
    kf, kb = ks  # front (smaller y), back
    # lowest loop vertex on each side
    left = np.nonzero(P[:, 0] > mid)[0]
    right = np.nonzero(P[:, 0] < mid)[0]
    kl = int(left[np.argmin(P[left, 2])])
    kr = int(right[np.argmin(P[right, 2])])

    def walk(a, b):
        out = [a]
        k = a
        while k != b:
            k = (k + 1) % n
            out.append(k)
        return out

    # loop order from the front point: first bottom reached is e1, then back, then e2
    d = lambda k: (k - kf) % n
    e1, e2 = (kl, kr) if d(kl) < d(kr) else (kr, kl)
    if not (d(e1) < d(kb) < d(e2)):
        raise CutError("skirt topology: unexpected shape of the inter-leg hole")
    c1 = [loop[k] for k in walk(kf, e1)]
    c2 = [loop[k] for k in walk(e1, kb)]
    c3 = [loop[k] for k in walk(kb, e2)]
    c4 = [loop[k] for k in walk(e2, kf)]
    strips = _zip(c1, c4[::-1], X) + _zip(c2[::-1], c3, X)
    bnd_he = set(zip(loop, loop[1:] + loop[:1]))
    tris = []
    for x, y, z in strips:
        # the new face holds the boundary edge reversed
        tris.append((y, x, z) if (x, y) in bnd_he else (x, y, z))
    tris = np.asarray(tris, dtype=np.int64)
    if np.any(tris[:, 0] == tris[:, 2]) or np.any(tris[:, 1] == tris[:, 2]):
        raise CutError("skirt topology: degenerate bridge between the legs")
    mesh.replace_faces(np.nonzero(H)[0], tris, X[tris])
