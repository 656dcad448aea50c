"""Closest-point, distance and ray queries on a triangle mesh (Warp's BVH).

The kernels are shared by the drape (its body-contact search launches
:func:`closest_plane` every few substeps) and by the fit measurements (gap
rays, penetration depth, coverage), so both query the body and the garment
the same way. The host functions take plain numpy arrays and run on the CPU.

This module is also where Warp is set up for the whole package (the drape's
kernels import ``wp`` from here): its kernel cache defaults to the user's
cache folder (:func:`core.paths.default_warp_cache`, overridable by
``WARP_CACHE_PATH``) and its info-level chatter is silenced.

Shapes: points and ray origins ``(n, 3)``, mesh vertices ``(V, 3)`` and faces
``(F, 3)``; lengths in metres. The mesh is converted to float32 (Warp's
``vec3``), so distances are float32-exact, returned as float64.
"""

from __future__ import annotations

import numpy as np

from ..paths import default_warp_cache

default_warp_cache()  # before Warp initialises: it reads the cache folder once

import warp as wp  # noqa: E402

# Keep the CLI output to our own lines: Warp's init banner and module-load notes are info-level.
if getattr(wp.config, "log_level", None) == getattr(wp, "LOG_INFO", 20):
    wp.config.log_level = getattr(wp, "LOG_WARNING", 30)


def init_cpu() -> None:
    """``wp.init()`` for CPU work, without the native library's notice that no CUDA driver was found.

    The notice is written straight to file descriptor 2 by Warp's C++ code
    (no Python setting silences it); the pattern solver's kernels run on the
    CPU, so on a machine without a GPU it would only add a line to every run's
    output. A drape that asks for a CUDA device on such a machine is refused
    with its own message (:func:`core.drape.xpbd._device`).
    """
    import os
    import sys

    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (AttributeError, OSError, ValueError):  # no file descriptor 2 (an embedding host)
        wp.init()
        return
    try:
        quiet = os.open(os.devnull, os.O_WRONLY)
        os.dup2(quiet, 2)
        os.close(quiet)
        wp.init()
    finally:
        os.dup2(saved, 2)
        os.close(saved)


@wp.kernel
def closest_plane(
    points: wp.array(dtype=wp.vec3),
    weight: wp.array(dtype=float),
    mesh: wp.uint64,
    max_dist: float,
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec3),
    hit: wp.array(dtype=int),
):
    """Closest mesh point and the normal of its triangle, for points within ``max_dist``.

    ``hit[i]`` is 1 where found, 0 where the mesh is farther or ``weight[i]`` is
    0 (the drape passes inverse masses: pinned particles never touch).
    """
    i = wp.tid()
    hit[i] = 0
    if weight[i] == 0.0:
        return
    q = wp.mesh_query_point_sign_normal(mesh, points[i], max_dist)
    if not q.result:
        return
    point[i] = wp.mesh_eval_position(mesh, q.face, q.u, q.v)
    normal[i] = wp.mesh_eval_face_normal(mesh, q.face)
    hit[i] = 1


@wp.func
def _distance(mesh: wp.uint64, p: wp.vec3, q: wp.MeshQueryPoint, sign: float, max_dist: float):
    if q.result:
        return wp.length(p - wp.mesh_eval_position(mesh, q.face, q.u, q.v)) * sign
    return max_dist


@wp.kernel
def signed_distance_kernel(
    points: wp.array(dtype=wp.vec3), mesh: wp.uint64, max_dist: float, out: wp.array(dtype=float)
):
    """Signed distance to ``mesh`` (negative inside), +max_dist when farther."""
    i = wp.tid()
    q = wp.mesh_query_point_sign_normal(mesh, points[i], max_dist)
    out[i] = _distance(mesh, points[i], q, q.sign, max_dist)


@wp.kernel
def unsigned_distance_kernel(
    points: wp.array(dtype=wp.vec3), mesh: wp.uint64, max_dist: float, out: wp.array(dtype=float)
):
    """Distance to ``mesh``, +max_dist when farther."""
    i = wp.tid()
    q = wp.mesh_query_point_no_sign(mesh, points[i], max_dist)
    out[i] = _distance(mesh, points[i], q, 1.0, max_dist)


@wp.kernel
def ray_hit_kernel(
    origins: wp.array(dtype=wp.vec3),
    dirs: wp.array(dtype=wp.vec3),
    mesh: wp.uint64,
    max_t: float,
    t: wp.array(dtype=float),
):
    """Ray parameter of the first hit on ``mesh`` (the distance for unit directions), 0 when none."""
    i = wp.tid()
    q = wp.mesh_query_ray(mesh, origins[i], dirs[i], max_t)
    if q.result:
        t[i] = q.t
    else:
        t[i] = 0.0


def warp_mesh(vertices: np.ndarray, faces: np.ndarray, device="cpu") -> "wp.Mesh":
    """A Warp BVH mesh of a triangle mesh.

    Parameters
    ----------
    vertices : (V, 3) float, metres (stored as float32).
    faces : (F, 3) int.
    device : Warp device or its name.

    Returns
    -------
    wp.Mesh, its ``points`` and ``indices`` arrays attached (they must outlive it), built with
    winding-number support (``wp.mesh_query_point_sign_winding_number``: the drape's contact checks
    an "inside" answer with it on a layered collider that is not one closed surface).
    """
    points = wp.array(np.asarray(vertices, dtype=np.float32), dtype=wp.vec3, device=device)
    idx = wp.array(np.asarray(faces, dtype=np.int32).reshape(-1), dtype=wp.int32, device=device)
    return wp.Mesh(points=points, indices=idx, support_winding_number=True)


def _query(
    kernel, points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, limit: float, extra: tuple = ()
) -> np.ndarray:
    """Launch a per-point query kernel ``kernel(points, *extra, mesh, limit, out)`` on the CPU."""
    wp.init()
    pts = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    if len(pts) == 0:
        return np.zeros(0)
    mesh = warp_mesh(vertices, faces)
    out = wp.zeros(len(pts), dtype=float, device="cpu")
    inputs = [wp.array(pts, dtype=wp.vec3, device="cpu"), *extra, mesh.id, float(limit), out]
    wp.launch(kernel, len(pts), inputs=inputs, device="cpu")
    return out.numpy().astype(float)


def distance_to_mesh(
    points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, signed: bool = False, max_dist: float = 1.0
) -> np.ndarray:
    """Distance of each point to a triangle mesh.

    Parameters
    ----------
    points : (n, 3) float, metres.
    vertices : (V, 3) float, faces : (F, 3) int; outward oriented when ``signed``.
    signed : negative inside the mesh (by the normal of the closest triangle).
    max_dist : metres; points farther than this get ``max_dist``.

    Returns
    -------
    (n,) float, metres.
    """
    kernel = signed_distance_kernel if signed else unsigned_distance_kernel
    return _query(kernel, points, vertices, faces, max_dist)


def ray_hit_distance(
    origins: np.ndarray, directions: np.ndarray, vertices: np.ndarray, faces: np.ndarray, max_t: float = 0.5
) -> np.ndarray:
    """Distance along each ray to its first hit on a triangle mesh.

    Parameters
    ----------
    origins : (n, 3) float, metres.
    directions : (n, 3) float, unit vectors.
    vertices : (V, 3) float, faces : (F, 3) int.
    max_t : metres, the longest ray.

    Returns
    -------
    (n,) float, metres; 0 where nothing is hit within ``max_t``.
    """
    o = np.asarray(origins, dtype=np.float32).reshape(-1, 3)
    if len(o) == 0:
        return np.zeros(0)
    wp.init()
    dirs = wp.array(np.asarray(directions, dtype=np.float32).reshape(-1, 3), dtype=wp.vec3, device="cpu")
    return _query(ray_hit_kernel, o, vertices, faces, max_t, extra=(dirs,))


__all__ = [
    "closest_plane",
    "signed_distance_kernel",
    "unsigned_distance_kernel",
    "ray_hit_kernel",
    "warp_mesh",
    "distance_to_mesh",
    "ray_hit_distance",
]
