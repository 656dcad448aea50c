"""Surface points from 3D positions: a click on a face, or the closest point to a position.

A :class:`core.body.model.SurfacePoint` (template triangle + barycentric
weights) holds for every shape and pose, so a point picked on one body
instance (the add-on's click, a test's probe) is stored this way. The add-on
gets the hit face and location from Blender's ray cast and hands them here;
it computes no geometry itself.
"""

from __future__ import annotations

import numpy as np

from .model import SurfacePoint


def barycentric(corners: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Barycentric weights of ``p`` on the triangle ``corners``, clipped to it.

    Parameters
    ----------
    corners : (3, 3) float, the triangle's corners (metres).
    p : (3,) float, a point on (or near) the triangle's plane.

    Returns
    -------
    (3,) float, weights >= 0 summing to 1: ``p`` projected on the plane by
    least squares, then clipped to the triangle (a hit a rounding error off
    an edge lands on it).
    """
    corners = np.asarray(corners, dtype=float)
    m = np.stack([corners[1] - corners[0], corners[2] - corners[0]], axis=1)
    uv, *_ = np.linalg.lstsq(m, np.asarray(p, dtype=float) - corners[0], rcond=None)
    b = np.clip(np.array([1 - uv.sum(), uv[0], uv[1]]), 0, None)
    return b / b.sum()


def surface_point_at(vertices: np.ndarray, faces: np.ndarray, face_index: int, location) -> SurfacePoint:
    """The surface point of a hit ``location`` on face ``face_index``.

    Parameters
    ----------
    vertices : (V, 3) float, the body instance (metres).
    faces : (F, 3) int, the template triangles.
    face_index : int, the face that was hit.
    location : (3,) float, the hit position (metres, the body's frame).
    """
    f = int(face_index)
    corners = np.asarray(vertices, dtype=float)[np.asarray(faces)[f]]
    return SurfacePoint(f, tuple(float(x) for x in barycentric(corners, location)))


def closest_surface_point(vertices: np.ndarray, faces: np.ndarray, p) -> SurfacePoint:
    """The surface point of the body instance closest to the position ``p`` (3,), metres.

    Parameters
    ----------
    vertices : (V, 3) float.
    faces : (F, 3) int.
    p : (3,) float.
    """
    import igl

    V = np.asarray(vertices, dtype=float)
    F = np.asarray(faces, dtype=np.int64)
    _, fi, c = igl.point_mesh_squared_distance(np.asarray(p, float)[None], V, F)
    return surface_point_at(V, F, int(np.atleast_1d(fi)[0]), np.atleast_2d(c)[0])
