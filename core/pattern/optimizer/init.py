"""Per-panel initialisation: LSCM flattening, orientation, grain alignment.

Small functions on plain arrays. A panel's 3D positions ``xyz`` (n, 3) and
faces (f, 3) (oriented outward) give a 2D ``uv`` (n, 2), counter-clockwise as
seen from outside the body, scaled to the 3D area and rotated so that the
panel's grain (the 3D warp field mapped to 2D) is +y.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...errors import PatternError
from ...geom.mesh import boundary_loops, signed_areas_2d, triangle_areas

#: Edges or triangle images shorter than this (relative to the panel's mean
#: edge length) are treated as degenerate and skip the grain vote.
DEGENERATE = 1e-8
#: A flattening with a triangle whose area scale (2D over 3D area) is under this fraction of the
#: panel's median is polished by SLIM (:func:`open_collapsed`). 0.25 (was 0.1): the four-dart blouse's
#: front, eight slits converging on the bust points, reads 0.155 at its 10 mm edges and 0.197 at the
#: finest refinement (5 mm); from that LSCM start the first iteration at 5 mm held 4316 of its 19486
#: triangles in the collapse guard and the solve flipped (814 and more), polished it converges (0 guarded
#: after 40 iterations). Every other template's pieces read 0.39 or more (blouse_fitted's front 0.39,
#: the rest 0.5-0.9) or under 0.03 (the skirt topology's fronts, polished at 0.1 already).
COLLAPSED_START = 0.25
#: SLIM iterations of that polish.
SLIM_ITERATIONS = 20


def _far_pair(xyz: np.ndarray, candidates: np.ndarray) -> tuple:
    """Two candidate vertices roughly farthest apart (two sweeps)."""
    p = candidates[0]
    a = candidates[np.argmax(np.linalg.norm(xyz[candidates] - xyz[p], axis=1))]
    b = candidates[np.argmax(np.linalg.norm(xyz[candidates] - xyz[a], axis=1))]
    return int(a), int(b)


def lscm(xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """LSCM flattening (n, 2) of a disk-like panel, two far boundary vertices fixed.

    The result is scaled so its area equals the 3D area and made
    counter-clockwise (positive majority of signed areas).
    """
    import igl

    xyz = np.ascontiguousarray(xyz, dtype=np.float64)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    loops = boundary_loops(F)
    cand = loops[0] if loops else np.arange(len(xyz))
    a, b = _far_pair(xyz, cand)
    d = float(np.linalg.norm(xyz[a] - xyz[b]))
    out = igl.lscm(xyz, F, np.array([a, b], dtype=np.int64), np.array([[0.0, 0.0], [d, 0.0]]))
    uv = np.asarray(out[0] if isinstance(out, tuple) else out, dtype=np.float64)
    return normalise_orientation_and_scale(uv, xyz, F)


def tutte(xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Tutte-style harmonic flattening onto a circle: flip-free for disk panels."""
    xyz = np.ascontiguousarray(xyz, dtype=np.float64)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    loops = boundary_loops(F)
    if len(loops) != 1:
        raise PatternError(f"a flip-free fallback flattening needs a disk-like panel, got {len(loops)} boundary loops")
    bnd = loops[0]
    seg = np.linalg.norm(np.diff(xyz[np.r_[bnd, bnd[:1]]], axis=0), axis=1)
    t = 2 * np.pi * np.r_[0.0, np.cumsum(seg)[:-1]] / seg.sum()
    bc = np.c_[np.cos(t), np.sin(t)]
    # uniform (Tutte) weights guarantee an embedding for convex boundaries
    n = len(xyz)
    E = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    A = sp.coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n)).tocsr()
    A = ((A + A.T) > 0).astype(float)
    L = sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A
    free = np.setdiff1d(np.arange(n), bnd)
    uv = np.zeros((n, 2))
    uv[bnd] = bc
    if free.size:
        Lff = L[free][:, free].tocsc()
        rhs = -L[free][:, bnd] @ bc
        from scipy.sparse.linalg import splu

        uv[free] = splu(Lff).solve(np.asarray(rhs))
    return normalise_orientation_and_scale(uv, xyz, F)


def open_collapsed(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``uv`` (n, 2), or where it squeezes a triangle to a sliver, the same panel polished by SLIM.

    Conformal maps (LSCM) shrink the cloth towards a cone of excess angle
    (the skirt topology's bridge between the legs: angle sums 1.4 x 2 pi) by
    orders of magnitude; the optimizer's flip guard would then hold those
    triangles collapsed. SLIM's symmetric Dirichlet energy (a barrier against
    collapse and flips, libigl) spreads the squeeze; its result is taken only
    when it is flip-free. Panels without such a triangle are returned as they
    are (unchanged patterns).
    """
    import igl

    F = np.asarray(faces, np.int64)
    ratio = signed_areas_2d(uv, F) / np.maximum(triangle_areas(xyz, F), 1e-300)
    if not (np.all(ratio > 0) and ratio.min() < COLLAPSED_START * np.median(ratio)):
        return uv
    data = igl.slim_precompute(
        np.asfortranarray(xyz, dtype=np.float64),
        np.asfortranarray(F, dtype=np.int32),
        np.asfortranarray(uv, dtype=np.float64),
        igl.MappingEnergyType.SYMMETRIC_DIRICHLET,
        np.zeros(0, np.int32),
        np.zeros((0, 2)),
        0.0,
    )
    out = np.asarray(igl.slim_solve(data, SLIM_ITERATIONS), dtype=np.float64)[:, :2]
    if not (np.all(np.isfinite(out)) and np.all(signed_areas_2d(out, F) > 0)):
        return uv
    return normalise_orientation_and_scale(out, xyz, F)


def normalise_orientation_and_scale(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Mirror ``uv`` if clockwise, then scale it to the 3D area (about its centroid)."""
    s = signed_areas_2d(uv, faces)
    if np.sum(s > 0) < np.sum(s < 0):
        uv = uv * np.array([-1.0, 1.0])
        s = -s
    a2 = float(np.sum(np.abs(s)))
    a3 = float(triangle_areas(xyz, faces).sum())
    if not (a2 > 0 and a3 > 0):
        raise PatternError("panel has zero area")
    c = uv.mean(axis=0)
    return (uv - c) * np.sqrt(a3 / a2)


def gradient_operators(uv: np.ndarray, faces: np.ndarray) -> tuple:
    """Per-triangle gradient operators of the 2D domain ``uv``.

    Returns
    -------
    G : (f, 3, 2) float, for a per-vertex function with values ``v`` (3,) on a
        triangle, ``v @ G[t]`` is its constant 2D gradient; ``X_t.T @ G[t]``
        (3x2) is the Jacobian of the 2D->3D map. ``G[t][:, 0]`` are the
        barycentric offsets of a unit step along +x from the centroid.
    area : (f,) float, 2D triangle areas (0 and ``G = 0`` for degenerate ones).
    """
    F = np.asarray(faces, int)
    e1 = uv[F[:, 1]] - uv[F[:, 0]]
    e2 = uv[F[:, 2]] - uv[F[:, 0]]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    area = 0.5 * det
    scale = np.mean(np.abs(det)) if det.size else 0.0
    ok = np.abs(det) > DEGENERATE * scale
    inv = np.zeros((len(F), 2, 2))
    inv[ok, 0, 0] = e2[ok, 1] / det[ok]
    inv[ok, 0, 1] = -e2[ok, 0] / det[ok]
    inv[ok, 1, 0] = -e1[ok, 1] / det[ok]
    inv[ok, 1, 1] = e1[ok, 0] / det[ok]
    # value(u) = v0 + [v1-v0, v2-v0] . inv @ (u - u0): rows of B map (v0,v1,v2) to d/dx, d/dy
    G = np.zeros((len(F), 3, 2))
    G[:, 1, :] = inv[:, 0, :]
    G[:, 2, :] = inv[:, 1, :]
    G[:, 0, :] = -inv[:, 0, :] - inv[:, 1, :]
    area = np.where(ok, area, 0.0)
    return G, area


def grain_angle(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray, warp_dir: np.ndarray) -> float:
    """Area-weighted vote (radians) of the angle from +y to the 2D image of the 3D warp.

    Per triangle the 3D warp direction is mapped to 2D through the inverse of
    the triangle's 2D->3D Jacobian (:func:`pulled_back_warp`); its angle from +y
    is voted with weight equal to the 3D area (as a unit vector, so angles
    average on the circle). Degenerate triangles (tiny 2D or 3D extent) do not vote.
    """
    G, area = gradient_operators(uv, faces)
    img, ok = pulled_back_warp(xyz, faces, G, warp_dir)
    return _vote_angle(img, np.where(ok & (area != 0), triangle_areas(xyz, faces), 0.0))


def _vote_angle(unit: np.ndarray, weight: np.ndarray) -> float:
    """Angle from +y (counter-clockwise, ``atan2(-x, y)``) of the weighted sum of ``unit``
    (f, 2); 0 when nothing votes (keep the flattening's own orientation)."""
    if not np.any(weight > 0):
        return 0.0
    v = np.sum(weight[:, None] * unit, axis=0)
    return float(np.arctan2(-v[0], v[1]))


def rotation(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def align_grain(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray, warp_dir: np.ndarray) -> np.ndarray:
    """Rotate ``uv`` about its centroid so the voted grain is +y."""
    theta = grain_angle(uv, xyz, faces, warp_dir)
    c = uv.mean(axis=0)
    return (uv - c) @ rotation(-theta).T + c


def pulled_back_warp(xyz: np.ndarray, faces: np.ndarray, G: np.ndarray, warp_dir: np.ndarray) -> tuple:
    """Per triangle the 3D warp direction pulled back to the 2D domain of ``G`` (least-squares preimage).

    Returns (unit (f, 2), ok (f,) bool); degenerate triangles (tiny 2D or
    3D extent) are not ok and get 0.
    """
    F = np.asarray(faces, int)
    X = [xyz[F[:, k]] for k in range(3)]
    Jx = X[0] * G[:, 0, 0, None] + X[1] * G[:, 1, 0, None] + X[2] * G[:, 2, 0, None]  # (f, 3): 2D x -> 3D
    Jy = X[0] * G[:, 0, 1, None] + X[1] * G[:, 1, 1, None] + X[2] * G[:, 2, 1, None]
    a, b, c = np.sum(Jx * Jx, axis=1), np.sum(Jx * Jy, axis=1), np.sum(Jy * Jy, axis=1)
    rx, ry = np.sum(Jx * warp_dir, axis=1), np.sum(Jy * warp_dir, axis=1)
    det = a * c - b * b
    ok = np.abs(det) > DEGENERATE * max(float(np.mean(np.abs(det))), 1e-300)
    sd = np.where(ok, det, 1.0)
    v = np.where(ok[:, None], np.stack([(c * rx - b * ry) / sd, (a * ry - b * rx) / sd], axis=1), 0.0)
    nrm = np.hypot(v[:, 0], v[:, 1])
    ok &= nrm > DEGENERATE * max(float(np.mean(nrm)), 1e-300)
    return np.where(ok[:, None], v / np.maximum(nrm, 1e-300)[:, None], 0.0), ok


def flatten_panel(xyz: np.ndarray, faces: np.ndarray, warp_dir: np.ndarray) -> dict:
    """The initial flattening and what the optimizer derives from it, in one pass.

    LSCM (Tutte where LSCM folds; polished by SLIM where it squeezes a triangle to a sliver,
    :func:`open_collapsed`), counter-clockwise, area-matched, rotated
    so the area-weighted vote of the pulled-back 3D warp is +y.

    Returns a dict: ``uv`` (n, 2); ``G``, ``area`` as :func:`gradient_operators`
    of ``uv``; ``warp`` (f, 2) the unit warp pulled back to ``uv`` (0 where
    degenerate); ``warp_weight`` (f,) its vote weight (3D area, 0 where degenerate).
    """
    F = np.asarray(faces, np.int64)
    warp_dir = np.asarray(warp_dir, float)
    uv = lscm(xyz, F)
    s = signed_areas_2d(uv, F)
    if np.any(s <= DEGENERATE * np.mean(np.abs(s))):
        uv = tutte(xyz, F)
    uv = open_collapsed(uv, xyz, F)
    G, area = gradient_operators(uv, F)
    img, ok = pulled_back_warp(xyz, F, G, warp_dir)
    w = np.where(ok & (area != 0), triangle_areas(xyz, F), 0.0)
    R = rotation(-_vote_angle(img, w))
    c = uv.mean(axis=0)
    # rotating the domain rotates gradients and pulled-back directions alike
    return {"uv": (uv - c) @ R.T + c, "G": G @ R.T, "area": area, "warp": img @ R.T, "warp_weight": w}
