"""Triangle-mesh basics: areas, normals, boundary loops.

Vertices are ``(V, 3)`` (or ``(V, 2)`` for pattern coordinates) float arrays
in metres, faces ``(F, 3)`` integer arrays of vertex ids.
"""

from __future__ import annotations

from typing import List

import numpy as np


def row_dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products (F,) of (F, 3) arrays: ``numpy.sum(a * b, axis=1)`` term by term in its
    order (the same bits), without numpy's reduction over a short strided axis (several times slower)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def row_norm(a: np.ndarray) -> np.ndarray:
    """Row-wise lengths (F,) of an (F, 3) array: ``numpy.linalg.norm(a, axis=1)``, the same bits."""
    return np.sqrt(row_dot(a, a))


def row_cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross products (F, 3) of (F, 3) arrays: ``numpy.cross(a, b)``, the same bits."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def unique_pairs(pairs: np.ndarray) -> tuple:
    """``np.unique(pairs, axis=0, return_inverse=True)`` for (k, 2) non-negative int pairs, through one
    int64 key per pair (the same lexicographic order, several times faster than the axis form)."""
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    n = int(pairs.max()) + 1 if len(pairs) else 1
    keys, inverse = np.unique(pairs[:, 0] * n + pairs[:, 1], return_inverse=True)
    return np.stack([keys // n, keys % n], axis=1), inverse.reshape(-1)


def triangle_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unsigned triangle areas.

    Parameters
    ----------
    vertices : (V, 3) float, metres.
    faces : (F, 3) int.

    Returns
    -------
    (F,) float, square metres.
    """
    v = np.asarray(vertices, float)
    f = np.asarray(faces, int)
    return 0.5 * row_norm(row_cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]))


def signed_areas_2d(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Signed areas of 2D triangles, positive when counter-clockwise.

    Parameters
    ----------
    uv : (V, 2) float, metres.
    faces : (F, 3) int.

    Returns
    -------
    (F,) float, square metres.
    """
    uv = np.asarray(uv, float)
    f = np.asarray(faces, int)
    a = uv[f[:, 1]] - uv[f[:, 0]]
    b = uv[f[:, 2]] - uv[f[:, 0]]
    return 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def face_normals(vertices: np.ndarray, faces: np.ndarray, unit: bool = True) -> np.ndarray:
    """Face normals by the right-hand rule of each face's corner order.

    Parameters
    ----------
    vertices : (V, 3) float.
    faces : (F, 3) int.
    unit : bool
        Unit length (degenerate faces get zero); otherwise the length is twice
        the face's area.

    Returns
    -------
    (F, 3) float.
    """
    v = np.asarray(vertices, float)
    f = np.asarray(faces, int)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    if not unit:
        return n
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals of an outward-oriented mesh.

    Parameters
    ----------
    vertices : (V, 3) float.
    faces : (F, 3) int.

    Returns
    -------
    (V, 3) float; a vertex in no face (or only in degenerate ones) gets (0, 0, 0).
    """
    v = np.asarray(vertices, float)
    f = np.asarray(faces, int)
    fn = face_normals(v, f, unit=False)  # length = 2 * area: the area weighting
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.maximum(length, 1e-30)


def boundary_loops(faces: np.ndarray) -> List[np.ndarray]:
    """Closed boundary loops of a triangle mesh (libigl), longest first.

    Each loop follows the faces' orientation (the mesh lies to its left in
    a counter-clockwise flattening).

    Parameters
    ----------
    faces : (F, 3) int.

    Returns
    -------
    list of (k,) int64 arrays of vertex ids, each loop listed once, not closed
    (the last vertex joins the first); empty for a closed mesh.
    """
    import igl

    f = np.ascontiguousarray(faces, dtype=np.int64)
    if len(f) == 0:
        return []
    loops = igl.boundary_loop_all(f) if hasattr(igl, "boundary_loop_all") else [igl.boundary_loop(f)]
    loops = [np.asarray(loop, dtype=np.int64) for loop in loops if len(loop) > 0]
    return sorted(loops, key=len, reverse=True)


def compact_vertices(faces: np.ndarray, used=None) -> tuple:
    """Drop the vertices a mesh does not keep and renumber its faces onto the ones it does.

    Parameters
    ----------
    faces : (F, 3) int, vertex ids.
    used : (V,) bool, the vertices kept; default: those some face uses.

    Returns
    -------
    ids : (K,) int64, the kept vertices' old ids in ascending order (new id ``k`` is old
        ``ids[k]``: ``vertices[ids]`` are the compacted vertices).
    faces : (F, 3) int64, the faces on the new ids.

    Raises
    ------
    ValueError
        A face uses a vertex that ``used`` drops (or an id outside it).
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if used is None:
        ids = np.unique(f)
        n = int(ids[-1]) + 1 if len(ids) else 0
    else:
        used = np.asarray(used, dtype=bool).reshape(-1)
        ids, n = np.flatnonzero(used), len(used)
    if len(f) and (f.min() < 0 or f.max() >= n):
        raise ValueError(f"compact_vertices: face vertex ids {f.min()}..{f.max()} outside 0..{n - 1}")
    remap = np.full(n, -1, dtype=np.int64)
    remap[ids] = np.arange(len(ids))
    out = remap[f]
    dropped = np.flatnonzero((out < 0).any(axis=1))
    if len(dropped):
        i = int(dropped[0])
        raise ValueError(f"compact_vertices: face {i} {f[i].tolist()} uses a vertex that is not kept")
    return ids, out
