"""Closest-point, distance and ray queries on a mesh (core.geom.queries), on a unit cube."""

import numpy as np
import pytest

from core.geom import queries as Q

wp = Q.wp


def _cube():
    """The unit cube [0, 1]^3, outward-oriented triangles."""
    v = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = []
    for a, b, c, d in quads:
        f += [[a, b, c], [a, c, d]]
    return v, np.array(f)


def test_cube_is_outward():
    from core.geom.mesh import face_normals

    v, f = _cube()
    centre = v[f].mean(axis=1) - 0.5
    assert np.all(np.einsum("ij,ij->i", face_normals(v, f), centre) > 0)


def test_warp_mesh_keeps_its_arrays():
    v, f = _cube()
    wp.init()
    mesh = Q.warp_mesh(v, f)
    assert np.array_equal(mesh.points.numpy(), v.astype(np.float32))
    assert np.array_equal(mesh.indices.numpy().reshape(-1, 3), f)


def test_unsigned_distance():
    v, f = _cube()
    p = np.array([[0.5, 0.5, 1.25], [0.5, 0.5, 0.9], [2.0, 0.5, 0.5], [5.0, 5.0, 5.0]])
    d = Q.distance_to_mesh(p, v, f, max_dist=2.0)
    assert d.dtype == np.float64 and d.shape == (4,)
    assert np.allclose(d, [0.25, 0.1, 1.0, 2.0], atol=1e-6)  # the last one is beyond max_dist
    assert Q.distance_to_mesh(np.zeros((0, 3)), v, f).shape == (0,)


def test_signed_distance_is_negative_inside():
    v, f = _cube()
    p = np.array([[0.5, 0.5, 1.25], [0.5, 0.5, 0.9], [0.5, 0.2, 0.5]])
    d = Q.distance_to_mesh(p, v, f, signed=True, max_dist=2.0)
    assert np.allclose(d, [0.25, -0.1, -0.2], atol=1e-6)


def test_ray_hit_distance():
    v, f = _cube()
    o = np.array([[0.5, 0.5, 2.0], [0.5, 0.5, 0.5], [0.5, 0.5, 2.0], [3.0, 0.5, 0.5]])
    d = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    t = Q.ray_hit_distance(o, d, v, f, max_t=1.5)
    # down onto the top face; out through the side from inside; away from the cube; too far
    assert np.allclose(t, [1.0, 0.5, 0.0, 0.0], atol=1e-6)
    assert Q.ray_hit_distance(np.zeros((0, 3)), np.zeros((0, 3)), v, f).shape == (0,)


def test_closest_plane():
    v, f = _cube()
    wp.init()
    mesh = Q.warp_mesh(v, f)
    pts = np.array([[0.5, 0.5, 1.02], [0.3, -0.01, 0.4], [0.5, 0.5, 1.5], [0.5, 0.5, 1.01]], np.float32)
    weight = np.array([1.0, 1.0, 1.0, 0.0], np.float32)  # the last one is pinned: never in contact
    n = len(pts)
    point = wp.zeros(n, dtype=wp.vec3, device="cpu")
    normal = wp.zeros(n, dtype=wp.vec3, device="cpu")
    hit = wp.zeros(n, dtype=int, device="cpu")
    wp.launch(
        Q.closest_plane,
        n,
        inputs=[
            wp.array(pts, dtype=wp.vec3, device="cpu"),
            wp.array(weight, dtype=float, device="cpu"),
            mesh.id,
            0.1,
            point,
            normal,
            hit,
        ],
        device="cpu",
    )
    assert hit.numpy().tolist() == [1, 1, 0, 0]  # the third is farther than 0.1 m
    assert np.allclose(point.numpy()[:2], [[0.5, 0.5, 1.0], [0.3, 0.0, 0.4]], atol=1e-6)
    assert np.allclose(normal.numpy()[:2], [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]], atol=1e-6)


@pytest.mark.parametrize("signed", [False, True])
def test_distance_is_float32_exact(signed):
    # the mesh is float32 on the device: a point on a face is at distance 0 exactly
    v, f = _cube()
    d = Q.distance_to_mesh(np.array([[0.25, 0.75, 1.0]]), v, f, signed=signed)
    assert abs(d[0]) == 0.0
