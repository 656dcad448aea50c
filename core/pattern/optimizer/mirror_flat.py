"""A panel that is its own mirror image (a front across the body) flattened mirror-symmetrically.

LSCM fixes two far boundary vertices, and its result depends on which: on a
front panel the far pair is a hem corner and the opposite shoulder, so the
initial flattening leans to one side by centimetres (2.2 cm between the two
side seams of the long-sleeve shirt) although the panel's mesh, the body and the
ease are symmetric, and the local-global iterations do not remove it (15 mm
left after 60). Here the flattening is averaged with its own reflection
through the panel's vertex mirror map: the result is exactly symmetric, and
close to the original where that was nearly so. A panel whose mesh is not its
own mirror image keeps its flattening.

A panel across the body whose mesh is not its own mirror image (the skirt
topology's front and back on a body without a symmetry map, where the leg
bridge is zipped across the midline; with one, :mod:`core.cut.skirt` splits
it on the midline and the panel is its own mirror) is
averaged with its reflection all the same, through an approximate mirror:
each vertex's reflection is located in the panel's own triangles and the
flattening interpolated there (:func:`approximate_mirror`). The result is
not exactly symmetric, but the centimetres of LSCM lean go (skirt side seams
24.6 mm apart left to right, 1.2 mm after).
"""

from __future__ import annotations

from typing import Optional

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from ...design.mirror import face_symmetry
from ...geom.mesh import triangle_areas
from . import init as _init

#: a vertex and the reflection (x -> -x) of its mirror vertex lie within this (m) on the
#: reference body; the body's own asymmetry is 0.1 mm on Anny, a mesh vertex spacing ~1 cm
MATCH_TOLERANCE = 5e-4


def _across_midline(xyz: np.ndarray, faces: np.ndarray):
    """``(xyz, faces, keys)`` of a panel that crosses the body's midplane x = 0 (None otherwise, or
    when a vertex is on no face): ``keys`` every vertex pulled half way towards the mean centroid
    of its faces, so the two copies of a vertex on a dart's legs (one position) are told apart by
    the side their faces lie on; the pull commutes with the mirror."""
    xyz = np.asarray(xyz, float)
    F = np.asarray(faces, np.int64)
    if len(xyz) < 3 or xyz[:, 0].min() >= 0 or xyz[:, 0].max() <= 0:
        return None
    centroid = xyz[F].mean(axis=1)
    pull = np.zeros_like(xyz)
    np.add.at(pull, F.reshape(-1), np.repeat(centroid, 3, axis=0))
    count = np.bincount(F.reshape(-1), minlength=len(xyz)).astype(float)
    if np.any(count == 0):
        return None
    return xyz, F, 0.5 * (xyz + pull / count[:, None])


def self_mirror_map(xyz: np.ndarray, faces: np.ndarray) -> Optional[np.ndarray]:
    """(n,) int, the mirror vertex (through the body's midplane x = 0) of every panel vertex,
    or None when the panel's mesh is not its own mirror image (vertices and faces).

    Parameters
    ----------
    xyz : (n, 3) float, the panel on the reference body (m); faces : (f, 3) int.
    """
    # matched by a point pulled towards the vertex's faces: the two copies of a vertex on a
    # dart's legs (one position) and a keypoint beside its mirror at the midline (0.02 mm apart)
    # are told apart by the side their faces lie on
    got = _across_midline(xyz, faces)
    if got is None:
        return None
    xyz, F, key = got
    d, m = cKDTree(key).query(key * [-1.0, 1.0, 1.0], k=2)
    if d[:, 0].max() > MATCH_TOLERANCE or np.any(d[:, 1] < 2.0 * d[:, 0] + 1e-12):
        return None  # not its own mirror image, or a match is not unique
    m = m[:, 0]
    if np.any(m[m] != np.arange(len(m))):
        return None
    if np.any(face_symmetry(F, m) < 0):  # a face whose mirror is not a face
        return None
    return m


#: largest distance (m) from a panel vertex's reflection to the panel for :func:`approximate_mirror`
#: (the skirt's bridges differ left and right by under a millimetre; a panel off the midline by more)
APPROX_TOLERANCE = 5e-3


def approximate_mirror(xyz: np.ndarray, faces: np.ndarray) -> Optional[sp.csr_matrix]:
    """(n, n) sparse interpolation: row ``i`` gives a per-vertex field at the reflection (through
    the body's midplane x = 0) of vertex ``i``, barycentric in the panel triangle nearest to it;
    None when the panel does not cross the midplane or a reflection is off the panel.

    For a panel across the body whose mesh is not its own mirror image (:func:`self_mirror_map`
    None).

    Parameters
    ----------
    xyz : (n, 3) float, the panel on the reference body (m); faces : (f, 3) int.
    """
    from ...design.geometry import SurfaceLocator

    got = _across_midline(xyz, faces)
    if got is None:
        return None
    xyz, F, key = got
    R = np.array([-1.0, 1.0, 1.0])
    q = xyz * R
    locator = SurfaceLocator(xyz, F)
    d2, _, _ = locator.closest(q)
    if np.sqrt(d2.max()) > APPROX_TOLERANCE:
        return None
    # the triangle nearest to the reflected pulled vertex: on a dart's leg, the leg's own side
    _, tri, _ = locator.closest(key * R)
    A = xyz[F[tri]]
    e1, e2, r = A[:, 1] - A[:, 0], A[:, 2] - A[:, 0], q - A[:, 0]
    d11, d12, d22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    r1, r2 = (r * e1).sum(1), (r * e2).sum(1)
    den = d11 * d22 - d12 * d12
    if np.any(den <= 0):
        return None
    b1, b2 = (d22 * r1 - d12 * r2) / den, (d11 * r2 - d12 * r1) / den
    bary = np.stack([1.0 - b1 - b2, b1, b2], axis=1)
    n = len(xyz)
    return sp.csr_matrix((bary.reshape(-1), (np.repeat(np.arange(n), 3), F[tri].reshape(-1))), shape=(n, n))


def symmetric_flattening(fl: dict, xyz: np.ndarray, faces: np.ndarray, warp_dir: np.ndarray, mirror) -> dict:
    """:func:`core.pattern.optimizer.init.flatten_panel`'s result ``fl`` made mirror-symmetric.

    ``uv`` -> ``(uv + T(uv[mirror])) / 2`` with ``T`` the reflection best aligning the
    mirrored layout onto ``uv`` (as ``T`` is an involution, the average is its own
    reflection), then rotated to the grain again. ``mirror``: the vertex mirror map of
    :func:`self_mirror_map`, or the interpolation of :func:`approximate_mirror` (then
    ``mirror @ uv``: nearly symmetric). ``fl`` is returned unchanged when the average would
    turn a triangle over.
    """
    uv = np.asarray(fl["uv"], float)
    F = np.asarray(faces, np.int64)
    c = uv.mean(axis=0)
    A = uv - c
    B = (mirror @ uv if sp.issparse(mirror) else uv[mirror]) - c
    U, _, Vt = np.linalg.svd(B.T @ A)
    R = U @ Vt
    if np.linalg.det(R) > 0:  # a reflection is wanted: the mirror map reverses orientation
        U[:, -1] *= -1
        R = U @ Vt
    sym = 0.5 * (A + B @ R) + c
    sym = _init.align_grain(sym, xyz, F, warp_dir)
    G, area = _init.gradient_operators(sym, F)
    if np.any(area <= 0):
        return fl
    img, ok = _init.pulled_back_warp(xyz, F, G, warp_dir)
    w = np.where(ok & (area != 0), triangle_areas(xyz, F), 0.0)
    return {"uv": sym, "G": G, "area": area, "warp": img, "warp_weight": w}
