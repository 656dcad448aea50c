"""core.cut.panels (half-edges, boundary loops, line stretches) and core.cut.incidence."""

import numpy as np
import pytest

from core.cut.incidence import VertexFaces, bary2, bary2_scalar
from core.cut.panels import _boundary_loops, _stretches, halfedges
from core.errors import CutError

F = np.array([[0, 1, 2], [1, 3, 2]])


def test_halfedges_and_twins():
    key, ukey, twin, _ = halfedges(F, 4)
    assert key.tolist() == [1, 6, 8, 7, 14, 9]
    # the shared edge 1-2 (half-edge 1 of face 0) and 2-1 (half-edge 2 of face 1) are twins
    assert twin.tolist() == [-1, 5, -1, -1, -1, 1] and ukey[1] == ukey[5]


def test_boundary_loops_start_at_the_smallest_vertex():
    a, b = np.array([3, 1, 0, 2]), np.array([2, 3, 1, 0])
    loops = _boundary_loops(np.append(a, [7, 8, 9]), np.append(b, [8, 9, 7]), "p")
    assert [l.tolist() for l in loops] == [[0, 1, 3, 2], [7, 8, 9]]
    with pytest.raises(CutError, match="'p'"):
        _boundary_loops(np.array([0, 0]), np.array([1, 2]), "p")


def test_stretches_wrap_on_closed_runs():
    key = np.array([1, 1, 2, 2, 1])
    assert [s.tolist() for s in _stretches(key, False)] == [[0, 1], [2, 3], [4]]
    assert [s.tolist() for s in _stretches(key, True)] == [[2, 3], [4, 0, 1]]


def test_incidence_and_barycentrics():
    vf = VertexFaces(F, 4)
    assert vf[1] == {0, 1} and vf[0] == {0} and vf[5] == set()
    other = vf.copy()
    other[1].add(7)
    assert vf[1] == {0, 1}
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    q = np.array([[0.25, 0.5]])
    assert np.allclose(bary2(q, tri[None]), [[0.25, 0.25, 0.5]])
    assert bary2_scalar(0.25, 0.5, *tri) == pytest.approx((0.25, 0.25, 0.5))
