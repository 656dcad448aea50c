"""core.geom.mesh: triangle areas, signed 2D areas, face and vertex normals, boundary loops (one test each)."""

import numpy as np
import pytest

from core.geom.mesh import boundary_loops, face_normals, signed_areas_2d, triangle_areas, vertex_normals

# a unit square in the z = 0 plane, two ccw triangles, and a tetrahedron (closed, outward)
SQ_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
SQ_F = np.array([[0, 1, 2], [0, 2, 3]])
TET_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _grid_with_hole(n=6):
    idx = np.arange(n * n).reshape(n, n)
    faces = []
    for i in range(n - 1):
        for j in range(n - 1):
            if i == 2 and j == 2:
                continue
            a, b, c, d = idx[i, j], idx[i, j + 1], idx[i + 1, j + 1], idx[i + 1, j]
            faces += [[a, b, c], [a, c, d]]
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    return np.column_stack([x.ravel(), y.ravel()]), np.array(faces)


def test_triangle_areas():
    np.testing.assert_allclose(triangle_areas(SQ_V, SQ_F), [0.5, 0.5])
    np.testing.assert_allclose(triangle_areas(2 * TET_V, TET_F)[-1], 2 * np.sqrt(3), rtol=1e-12)


def test_signed_areas_2d_follow_orientation():
    uv = SQ_V[:, :2]
    np.testing.assert_allclose(signed_areas_2d(uv, SQ_F), [0.5, 0.5])
    np.testing.assert_allclose(signed_areas_2d(uv, SQ_F[:, ::-1]), [-0.5, -0.5])


def test_face_normals_unit_and_area_weighted():
    np.testing.assert_allclose(face_normals(SQ_V, SQ_F), [[0, 0, 1], [0, 0, 1]])
    np.testing.assert_allclose(face_normals(SQ_V, SQ_F, unit=False), [[0, 0, 1], [0, 0, 1]])
    np.testing.assert_allclose(face_normals(2 * SQ_V, SQ_F, unit=False), [[0, 0, 4], [0, 0, 4]])
    # a degenerate face gets a zero unit normal
    np.testing.assert_array_equal(face_normals(SQ_V, np.array([[0, 1, 1]])), [[0, 0, 0]])


def test_vertex_normals_point_outward_and_isolated_vertices_get_zero():
    n = vertex_normals(TET_V, TET_F)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0)
    centre = TET_V.mean(0)
    assert np.all(np.sum(n * (TET_V - centre), axis=1) > 0)
    np.testing.assert_allclose(n[0], -np.ones(3) / np.sqrt(3), atol=1e-12)
    v = np.vstack([SQ_V, [[5.0, 5.0, 5.0]]])
    n = vertex_normals(v, SQ_F)
    np.testing.assert_allclose(n[:4], np.tile([0.0, 0.0, 1.0], (4, 1)))
    np.testing.assert_array_equal(n[4], [0.0, 0.0, 0.0])


def test_boundary_loops_longest_first_oriented_like_the_faces():
    uv, faces = _grid_with_hole()
    loops = boundary_loops(faces)
    assert [len(b) for b in loops] == [20, 4]
    for b in loops:
        # each consecutive pair is a boundary edge walked as the faces walk it
        half = {tuple(e) for f in faces for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
        for u, v in zip(b, np.roll(b, -1)):
            assert (int(u), int(v)) in half and (int(v), int(u)) not in half
    area = [0.5 * np.sum(uv[b, 0] * np.roll(uv[b, 1], -1) - np.roll(uv[b, 0], -1) * uv[b, 1]) for b in loops]
    assert area[0] == pytest.approx(25.0) and area[1] == pytest.approx(-1.0)
    assert boundary_loops(TET_F) == []
    assert boundary_loops(np.zeros((0, 3), int)) == []


def test_compact_vertices_drops_unused_and_renumbers_faces():
    from core.geom.mesh import compact_vertices

    # vertices 0, 3, 5 in no face (of 7): the kept ones in order, the faces on them
    v = np.arange(21, dtype=float).reshape(7, 3)
    f = np.array([[1, 2, 4], [4, 2, 6]])
    ids, g = compact_vertices(f)
    assert ids.tolist() == [1, 2, 4, 6] and g.tolist() == [[0, 1, 2], [2, 1, 3]]
    assert np.array_equal(v[ids][g], v[f])  # the same triangles
    # a mask keeps what it says, also a vertex in no face
    used = np.zeros(7, bool)
    used[[0, 1, 2, 4, 6]] = True
    ids, g = compact_vertices(f, used)
    assert ids.tolist() == [0, 1, 2, 4, 6] and np.array_equal(v[ids][g], v[f])
    # a face on a dropped vertex, or an id outside the mask: an error, never a face on -1
    used[6] = False
    with pytest.raises(ValueError, match=r"face 1 \[4, 2, 6\]"):
        compact_vertices(f, used)
    with pytest.raises(ValueError, match="outside"):
        compact_vertices(f, used[:5])
    ids, g = compact_vertices(np.zeros((0, 3), int))
    assert len(ids) == 0 and g.shape == (0, 3)
