"""core.cut.geodesic: keypoints as vertices, geodesic paths (potpourri3d)."""

import numpy as np
import pytest
from cut_synth import R, SynthBody

from core.body.model import SurfacePoint
from core.cut.geodesic import GeodesicPaths, check_surface_point, insert_keypoints
from core.cut.split import CutMesh
from core.errors import CutError
from core.geom.polyline import polyline_length


def test_keypoints_inserted_at_their_positions():
    body = SynthBody()
    m = CutMesh(body.V, body.faces)
    pts = body.ring(0.5, [0.1, 1.0, 2.0]) + [SurfacePoint(5, (1.0, 0.0, 0.0)), SurfacePoint(7, (0.5, 0.5, 0.0))]
    pts.append(pts[0])  # a repeated point gives the same vertex
    ids = insert_keypoints(m, pts, body.faces, body.V)
    assert ids[-1] == ids[0]
    assert ids[3] == body.faces[5][0]  # a corner is the existing vertex
    # exact, or moved onto a nearby vertex/edge (< SNAP_ABS) to avoid sliver triangles
    from core.cut.split import SNAP_ABS

    for v, p in zip(ids, pts):
        assert np.linalg.norm(m.X[v] - p.position(body.V, body.faces)) <= SNAP_ABS
    far = body.ring(0.5, [0.1])[0]
    m2 = CutMesh(body.V, body.faces)
    (v,) = insert_keypoints(m2, [SurfacePoint(far.triangle, (0.3, 0.3, 0.4))], body.faces, body.V)
    np.testing.assert_allclose(
        m2.X[v], SurfacePoint(far.triangle, (0.3, 0.3, 0.4)).position(body.V, body.faces), atol=1e-15
    )


def test_geodesic_on_tube_is_the_helix_or_circle():
    body = SynthBody(nt=64, nz=60)
    m = CutMesh(body.V, body.faces)
    a, b = insert_keypoints(m, body.ring(0.3, [0.0]) + body.ring(0.7, [np.pi / 2]), body.faces, body.V)
    P = GeodesicPaths(m.X, m.F).path(a, b)
    # unrolled tube: straight line; length sqrt(dz^2 + (r * dtheta)^2) (polygon r slightly smaller)
    L = np.hypot(0.4, R * np.pi / 2)
    assert abs(polyline_length(P) - L) < 0.01 * L
    assert np.linalg.norm(P[0] - m.X[a]) < 1e-12 and np.linalg.norm(P[-1] - m.X[b]) < 1e-12


def test_bad_keypoints():
    with pytest.raises(CutError, match="line X.*off the body"):
        check_surface_point(SurfacePoint(99, (1, 0, 0)), 10, "line X")
    with pytest.raises(CutError, match="sum to 1"):
        check_surface_point(SurfacePoint(1, (0.5, 0.1, 0.1)), 10, "line X")
