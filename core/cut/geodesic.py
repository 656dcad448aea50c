"""Keypoints as mesh vertices and geodesic paths between them (potpourri3d).

Keypoints (:class:`core.body.model.SurfacePoint`, a body triangle and
barycentric weights) are first inserted into the :class:`~.split.CutMesh` as
vertices by splitting their triangle or edge; then one
``EdgeFlipGeodesicSolver`` is built on that mesh and every pair of
consecutive keypoints is joined by the exact (intrinsic edge-flip) geodesic
(:func:`core.design.geometry.edge_flip_solver`: kept per mesh, and in the
add-on's workers built in a helper process).
The returned 3D polyline crosses mesh edges; :meth:`CutMesh.trace` inserts it.
"""

from __future__ import annotations

from typing import Dict, List, Sequence, Tuple

import numpy as np

from ..design.geometry import edge_flip_solver
from ..errors import CutError
from .split import CutMesh


def surface_point_position(sp, body_faces: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Position (3,) of a SurfacePoint on vertices ``X`` (V, 3)."""
    return np.asarray(sp.bary, dtype=float) @ X[body_faces[sp.triangle]]


def check_surface_point(sp, n_faces: int, what: str) -> None:
    """Raise :class:`CutError` naming ``what`` unless ``sp`` is a valid point on the body."""
    try:
        tri = int(sp.triangle)
        bary = np.asarray(sp.bary, dtype=float).reshape(3)
    except Exception:
        raise CutError(f"{what}: keypoint must be a SurfacePoint (triangle, 3 barycentric weights), got {sp!r}")
    if not 0 <= tri < n_faces:
        raise CutError(f"{what}: keypoint triangle {tri} is off the body (the body has {n_faces} triangles)")
    if not np.all(np.isfinite(bary)) or bary.min() < -1e-6 or abs(bary.sum() - 1.0) > 1e-6:
        raise CutError(f"{what}: keypoint barycentric weights {tuple(bary)} must be >= 0 and sum to 1")


def insert_keypoints(mesh: CutMesh, points: Sequence, body_faces: np.ndarray, X: np.ndarray) -> List[int]:
    """Insert SurfacePoints as vertices of ``mesh``; returns their vertex ids.

    Equal points give the same vertex. A point whose body triangle is gone
    (removed by the skirt topology) goes to the closest point of the mesh.
    """
    out: List[int] = []
    cache: Dict[Tuple, int] = {}
    for sp in points:
        key = (int(sp.triangle), tuple(round(float(b), 12) for b in sp.bary))
        if key in cache:
            out.append(cache[key])
            continue
        pos = surface_point_position(sp, body_faces, X)
        try:
            f, bary = mesh.locate_in_parent(int(sp.triangle), pos)
        except KeyError:
            f, bary = closest_face(mesh, pos)
        v = mesh.insert_point(f, bary)
        cache[key] = v
        out.append(v)
    return out


def closest_face(mesh: CutMesh, pos: np.ndarray):
    """Face of ``mesh`` closest to ``pos`` and the barycentrics of the closest point."""
    import igl

    V, F = mesh.X, mesh.F
    _, fi, c = igl.point_mesh_squared_distance(pos[None].astype(float), V, F.astype(np.int64))
    f = int(np.atleast_1d(fi)[0])
    c = np.atleast_2d(c)[0]
    tri = V[F[f]]
    # barycentrics by least squares in the triangle plane
    M = np.stack([tri[1] - tri[0], tri[2] - tri[0]], axis=1)
    l12, *_ = np.linalg.lstsq(M, c - tri[0], rcond=None)
    return f, np.array([1.0 - l12.sum(), l12[0], l12[1]])


class GeodesicPaths:
    """Geodesics between vertices of one mesh (solver built once).

    Parameters
    ----------
    X : (V, 3) float, vertex positions.
    F : (F, 3) int, manifold triangles.
    """

    def __init__(self, X: np.ndarray, F: np.ndarray):
        # the solver wants every vertex referenced (the skirt topology leaves some unused)
        F = np.asarray(F, dtype=np.int64)
        used = np.unique(F)
        self.index = np.full(len(X), -1, dtype=np.int64)
        self.index[used] = np.arange(len(used))
        try:
            # kept per mesh (a re-cut of the same keypoints on the same body builds none); in
            # the add-on's workers, built in a helper process (its constructor holds the GIL)
            self.solver = edge_flip_solver(np.asarray(X, dtype=float)[used], self.index[F])
        except Exception as e:  # potpourri raises RuntimeError on non-manifold input
            raise CutError(f"the body mesh cannot be cut (geodesic solver: {e})")

    def path(self, i: int, j: int) -> np.ndarray:
        """Geodesic polyline (k, 3) from vertex i to vertex j (both ends included)."""
        a, b = int(self.index[i]), int(self.index[j])
        if a < 0 or b < 0:
            raise CutError(f"internal: keypoint vertex {i if a < 0 else j} is not on the surface")
        try:
            return self.solver.path(a, b)
        except RuntimeError as e:  # the helper process ended (out of process)
            raise CutError(f"the geodesic path could not be found: {e}")
