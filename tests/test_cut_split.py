"""core.cut.split: edge/triangle splitting, weights, and exact segment tracing."""

import numpy as np
import pytest

from core.cut.split import SNAP, CutMesh
from core.errors import CutError


def grid(n=6, size=1.0):
    """A flat n x n grid of triangles in the z = 0 plane."""
    xs = np.linspace(0, size, n + 1)
    X = np.array([[x, y, 0.0] for y in xs for x in xs])
    F = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            F += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return X, np.array(F)


def check_mesh(m):
    """Oriented manifold: no repeated half-edge; every face counter-clockwise (+z)."""
    F = m.F
    key = F.reshape(-1) * m.nv + np.roll(F, -1, 1).reshape(-1)
    assert len(np.unique(key)) == len(key)
    X = m.X
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    assert (n[:, 2] > 0).all()


def embedding_positions(m, X0):
    out = []
    for v in range(m.nv):
        c, w = m.vertex_weights(v)
        out.append(w @ X0[c])
    return np.array(out)


def test_split_edge_and_face_keep_ids_and_weights():
    X, F = grid(2)
    m = CutMesh(X, F)
    area = 1.0
    v = m.split_edge(0, 1, 0.25)
    np.testing.assert_allclose(m.X[v], [0.125, 0, 0])
    c, w = m.vertex_weights(v)
    assert list(c) == [0, 1] and np.allclose(w, [0.75, 0.25])
    m.split_face(0, (0.2, 0.3, 0.5))
    check_mesh(m)
    np.testing.assert_allclose(embedding_positions(m, X), m.X)
    A = 0.5 * np.abs(np.cross(m.X[m.F[:, 1]] - m.X[m.F[:, 0]], m.X[m.F[:, 2]] - m.X[m.F[:, 0]])[:, 2]).sum()
    np.testing.assert_allclose(A, area)
    np.testing.assert_array_equal(m.X[: len(X)], X)  # original ids unchanged


def test_insert_point_snaps_near_vertices_and_edges():
    X, F = grid(2)
    m = CutMesh(X, F)
    tri = m.F[0].tolist()
    assert m.insert_point(0, (1 - SNAP / 10, SNAP / 20, SNAP / 20)) == tri[0]
    nv = m.nv
    v = m.insert_point(0, (0.5, 0.5 - SNAP / 10, SNAP / 10))  # on an edge: 1 vertex, 2 faces each side
    assert m.nv == nv + 1 and v == nv
    check_mesh(m)


def trace_geodesic(m, a, b, line, names=None):
    """Insert the geodesic a -> b (a straight segment on a flat mesh), point by point
    (each step of :meth:`CutMesh.trace` stays inside one parent triangle)."""
    from core.cut.geodesic import GeodesicPaths

    pts = GeodesicPaths(m.X, m.F).path(a, b)
    out, cur = [], a
    for q in pts[1:-1]:
        got = m.trace(cur, q, line, {a, b}, names=names)
        out += got
        cur = got[-1] if got else cur
    return out + m.trace(cur, m.X[b].copy(), line, {a, b}, target_vertex=b, names=names)


def test_trace_is_exact_straight_segment():
    X, F = grid(8)
    m = CutMesh(X, F)
    a = m.split_face(3, (0.3, 0.3, 0.4))
    b = m.split_face(100, (0.2, 0.5, 0.3))
    pa, pb = m.X[a].copy(), m.X[b].copy()
    path = [a] + trace_geodesic(m, a, b, 0)
    assert path[-1] == b
    P = m.X[path]
    # every vertex on the segment, in order, and the polyline is exactly as long as the segment
    d = pb - pa
    t = (P - pa) @ d / (d @ d)
    assert np.all(np.diff(t) > 0)
    off = np.linalg.norm(P - pa - t[:, None] * d, axis=1)
    assert off.max() < SNAP * 0.2  # a snap moves a crossing by < SNAP x edge length
    np.testing.assert_allclose(np.linalg.norm(np.diff(P, axis=0), axis=1).sum(), np.linalg.norm(d), rtol=1e-4)
    # consecutive path vertices are joined by edges marked as cut
    for u, w in zip(path[:-1], path[1:]):
        assert (min(u, w), max(u, w)) in m.cut
    check_mesh(m)
    np.testing.assert_allclose(embedding_positions(m, X), m.X, atol=1e-12)


def test_crossing_lines_raise():
    X, F = grid(8)
    m = CutMesh(X, F)
    a, b = m.split_face(2, (0.3, 0.3, 0.4)), m.split_face(125, (0.3, 0.3, 0.4))
    c, d = m.split_face(14, (0.3, 0.3, 0.4)), m.split_face(113, (0.3, 0.3, 0.4))
    names = ["one", "two"]
    trace_geodesic(m, a, b, 0, names)
    with pytest.raises(CutError, match="'two' and 'one' (cross|overlap)"):
        trace_geodesic(m, c, d, 1, names)


def test_copy_is_independent():
    X, F = grid(3)
    m = CutMesh(X, F)
    k = m.copy()
    k.split_edge(0, 1, 0.5)
    assert m.nv == len(X) and k.nv == len(X) + 1
    assert len(m.F) == len(F)


def test_move_body_remakes_vertices_and_parents():
    """CutMesh.move_body (the skirt's spanned surface): the body vertices move, a vertex off the body
    follows its weights, and every face lies in its parent on the moved corners (body parents by
    their body triangle, a replaced face's own parent by its face)."""
    X, F = grid(3)
    m = CutMesh(X, F)
    # two faces replaced by one new triangle each (their own parents), as the skirt bridge is added
    new = F[[0, 1]]
    m.replace_faces(np.array([0, 1]), new, X[new])
    v = m.split_edge(5, 6, 0.25)  # a vertex off the body: weights over 5 and 6
    Y = X + np.stack([0 * X[:, 0], 0 * X[:, 0], np.sin(3 * X[:, 0]) * X[:, 1]], 1)  # curved: parents move
    m.move_body(Y, F)
    assert np.allclose(m.X[: len(X)], Y)
    assert np.allclose(m.X[v], 0.75 * Y[5] + 0.25 * Y[6])
    for f in range(m.nf):
        q = m.X[m.F[f]].mean(axis=0)
        assert m.parent_contains(np.array([m.parent[f]]), q)[0], f
    # the body parents of the removed faces are re-made too (unused, as before the move)
    assert np.allclose(m._parent_corners()[: len(F)], Y[F])
