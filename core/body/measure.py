"""Body measurements as a tailor takes them, on any :class:`BodyModel` instance.

Height is the top of the head to the floor (the lowest vertex). A girth is
the length of a tape measure laid around the torso in a horizontal plane:
the perimeter of the convex hull of the torso's cross-section, with the arms
and hands left out (a tape passes between arm and torso) using the model's
``arm_left``/``arm_right``/``hands`` regions. Planes are at landmark heights:

- chest (bust): mean height of ``bust_left``/``bust_right``;
- waist: mean height of the waist landmarks (front, back, left, right);
- hip: mean height of ``hip_left``/``hip_right``.

All results are in centimetres.
"""

from __future__ import annotations

from typing import Dict, Iterable, Optional

import numpy as np

from ..errors import BodyError

MEASUREMENTS = ("height", "chest", "waist", "hip")

GIRTH_LANDMARKS = {
    "chest": ("bust_left", "bust_right"),
    "waist": ("waist_front", "waist_back", "waist_left", "waist_right"),
    "hip": ("hip_left", "hip_right"),
}

# Regions a horizontal tape passes outside of.
EXCLUDED_REGIONS = ("arm_left", "arm_right", "hands")


def mesh_edges(faces: np.ndarray) -> np.ndarray:
    """Unique undirected edges (E, 2) of triangles (F, 3)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return np.unique(np.sort(edges, axis=1), axis=0)


def plane_crossings(vertices: np.ndarray, faces: np.ndarray, height: float, edges=None) -> np.ndarray:
    """Points where the mesh edges cross the plane ``z = height``.

    Parameters
    ----------
    vertices : (V, 3) metres.
    faces : (F, 3) triangles (only their edges are used).
    height : float, metres.
    edges : optional (E, 2) precomputed :func:`mesh_edges` of ``faces``.

    Returns
    -------
    (n, 3) crossing points (each edge once).
    """
    if edges is None:
        edges = mesh_edges(faces)
    d = vertices[:, 2] - height
    da, db = d[edges[:, 0]], d[edges[:, 1]]
    cross = (da * db < 0) | ((da == 0) & (db != 0))
    a, b = edges[cross, 0], edges[cross, 1]
    t = (da[cross] / (da[cross] - db[cross]))[:, None]
    return vertices[a] + t * (vertices[b] - vertices[a])


def hull_perimeter(points_2d: np.ndarray) -> float:
    """Perimeter of the convex hull of (n, 2) points (0 for fewer than 3)."""
    if len(points_2d) < 3:
        return 0.0
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(points_2d)
    except QhullError:
        return 0.0
    ring = points_2d[hull.vertices]
    return float(np.linalg.norm(ring - np.roll(ring, 1, axis=0), axis=1).sum())


def torso_edges(body) -> np.ndarray:
    """Edges (E, 2) of the triangles of ``body`` that touch none of :data:`EXCLUDED_REGIONS`."""
    cached = getattr(body, "_ease_torso_edges", None)
    if cached is not None:
        return cached
    excluded = np.zeros(body.n_vertices, dtype=bool)
    for name in EXCLUDED_REGIONS:
        ids = body.regions.get(name)
        if ids is not None:
            excluded[np.asarray(ids, dtype=np.int64)] = True
    edges = mesh_edges(body.faces[~excluded[body.faces].any(axis=1)])
    try:  # the topology is fixed: compute once per model
        body._ease_torso_edges = edges
    except AttributeError:  # pragma: no cover - frozen model objects
        pass
    return edges


def girth_at(vertices: np.ndarray, faces: np.ndarray, height: float, edges=None) -> float:
    """Tape-measure girth (metres) of the mesh ``faces`` in the plane ``z = height``."""
    pts = plane_crossings(vertices, faces, height, edges)
    return hull_perimeter(pts[:, :2])


def landmark_height(body, vertices: np.ndarray, names: Iterable[str]) -> float:
    """Mean z (metres) of the named landmarks on ``vertices``."""
    return float(np.mean([body.landmark_position(n, vertices)[2] for n in names]))


def measure(body, vertices: Optional[np.ndarray] = None, which: Iterable[str] = MEASUREMENTS) -> Dict[str, float]:
    """Height and chest/waist/hip girths of a standing body instance, in cm.

    Parameters
    ----------
    body : BodyModel (needs the girth landmarks of :data:`GIRTH_LANDMARKS`).
    vertices : (V, 3) an instance of ``body`` (standing, e.g. the A-pose);
        default the reference shape.
    which : subset of :data:`MEASUREMENTS`.

    Returns
    -------
    dict name -> centimetres.
    """
    v = body.vertices() if vertices is None else np.asarray(vertices, dtype=float)
    if v.shape != (body.n_vertices, 3):
        raise BodyError(f"measure: vertices have shape {v.shape}, expected ({body.n_vertices}, 3)")
    out = {}
    edges = None
    for name in which:
        if name == "height":
            out[name] = 100.0 * float(v[:, 2].max() - v[:, 2].min())
        elif name in GIRTH_LANDMARKS:
            edges = torso_edges(body) if edges is None else edges
            h = landmark_height(body, v, GIRTH_LANDMARKS[name])
            out[name] = 100.0 * girth_at(v, None, h, edges)
        else:
            raise BodyError(f"unknown measurement {name!r}; allowed: {', '.join(MEASUREMENTS)}")
    return out
