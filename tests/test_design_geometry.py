"""Surface geometry of keypoint resolution, checked on analytic meshes (a closed cylinder)."""

import numpy as np
import pytest
from meshes import ring_grid_faces

from core.body.model import SurfacePoint
from core.design.geometry import (
    Geodesics,
    SectionLoop,
    SurfaceLocator,
    nearest_segment,
    plane_section_loop,
    segment_point,
    surface_tools,
    turned_normal,
    vertical_walk,
)
from core.design.mirror import face_symmetry, mirror_surface_point
from core.geom.polyline import point_at_length, polyline_length


def capped_cylinder(r=0.1, h=0.6, n=48, m=30):
    """Closed cylinder around +Z (radius r, height h), outward triangles, symmetric in x."""
    th = 2 * np.pi * (np.arange(n) + 0.5) / n  # no vertex on x = 0: a clean mirror in x
    z = np.linspace(0, h, m)
    V = [[r * np.cos(t), r * np.sin(t), zz] for zz in z for t in th]
    F = ring_grid_faces(m, n).tolist()
    bottom, top = len(V), len(V) + 1
    V += [[0, 0, 0], [0, 0, h]]
    for j in range(n):
        F.append([bottom, (j + 1) % n, j])
        F.append([top, (m - 1) * n + j, (m - 1) * n + (j + 1) % n])
    return np.array(V, float), np.array(F, np.int64)


def test_plane_section_of_a_cylinder_is_its_circle():
    V, F = capped_cylinder()
    p = np.array([0.1, 0.0, 0.31])
    loc = SurfaceLocator(V, F)
    sp = loc.locate(p[None])[0]
    poly, pts, segf = plane_section_loop(V, F, p, np.array([0, 0, 1.0]), sp.triangle)
    assert np.allclose(poly[:, 2], 0.31)
    per = np.linalg.norm(np.diff(np.vstack([poly, poly[:1]]), axis=0), axis=1).sum()
    n = 48
    assert abs(per - 2 * n * 0.1 * np.sin(np.pi / n)) < 1e-9  # the inscribed 48-gon
    # counter-clockwise about +Z; clockwise when asked
    c = np.cross(poly[0], poly[1])[2]
    assert c > 0
    poly_cw, _, _ = plane_section_loop(V, F, p, np.array([0, 0, 1.0]), sp.triangle, handed=-1)
    assert np.cross(poly_cw[0], poly_cw[1])[2] < 0
    # every point is a surface point on its face, at the polyline position
    for q, s, f in zip(poly, pts, segf):
        assert np.allclose(s.position(V, F), q)
        assert s.triangle == f
    j = nearest_segment(poly, p)
    assert segf[j] == sp.triangle or np.linalg.norm(poly[j] - p) < 0.02


def test_plane_section_that_runs_into_a_boundary_is_refused():
    V, F = capped_cylinder()
    keep = ~np.isin(F, [len(V) - 1]).any(axis=1)  # open the top
    Fo = F[keep]
    p = np.array([0.1, 0.0, 0.3])
    sp = SurfaceLocator(V, Fo).locate(p[None])[0]
    with pytest.raises(ValueError, match="boundary|close"):
        plane_section_loop(V, Fo, p, np.array([0, 1.0, 0]), sp.triangle)


def test_locator_and_segment_points():
    V, F = capped_cylinder()
    loc = SurfaceLocator(V, F)
    q = np.array([[0.1 * np.cos(0.3), 0.1 * np.sin(0.3), 0.2]])
    sp = loc.locate(q)[0]
    assert np.linalg.norm(sp.position(V, F) - q[0]) < 2e-3  # chord sag only
    assert abs(sum(sp.bary) - 1) < 1e-12 and min(sp.bary) >= 0
    c = V[F[7]].mean(axis=0)
    s2 = segment_point(V, F, 7, c)
    assert np.allclose(s2.bary, 1 / 3) and np.allclose(s2.position(V, F), c)


def test_geodesic_path_and_arc_length():
    V, F = capped_cylinder()
    loc = SurfaceLocator(V, F)
    a, b = loc.locate(np.array([[0.1, 0.0, 0.05], [0.1, 0.0, 0.55]]))
    path = Geodesics(V, F).path(a, b)
    L = polyline_length(path)
    # a straight generator of the cylinder; the ends join it sideways (the solver runs
    # between vertices, here half a column spacing, 6.5 mm, off), never backwards
    assert 0.5 - 1e-9 <= L < 0.5 + 2 * 0.0066
    assert np.all(np.diff(path[:, 2]) >= -1e-12)
    p, _, t = point_at_length(path, L / 2)
    assert abs(p[2] - 0.3) < 0.01 and abs(abs(t[2]) - 1) < 1e-3
    p0, _, _ = point_at_length(path, -1.0)
    assert np.allclose(p0, path[0])


def test_mirror_through_the_symmetry_map():
    V, F = capped_cylinder()
    # symmetry x -> -x: the vertex at angle pi - theta
    n, m = 48, 30
    sym = np.empty(len(V), np.int64)
    for i in range(m):
        for j in range(n):
            sym[i * n + j] = i * n + (n // 2 - 1 - j) % n
    sym[-2:] = [len(V) - 2, len(V) - 1]
    assert np.allclose(V[sym] * [-1, 1, 1], V)
    fs = face_symmetry(F, sym)
    # the caps are triangulated symmetrically, the side quads are not (their diagonals flip)
    caps = np.isin(F, [len(V) - 2, len(V) - 1]).any(axis=1)
    assert (fs[caps] >= 0).all() and np.array_equal(fs[fs[caps]], np.flatnonzero(caps))
    assert (fs[~caps] == -1).all()
    cap_face = int(np.flatnonzero(caps)[5])
    sp = SurfacePoint(cap_face, (0.2, 0.3, 0.5))
    m_ = mirror_surface_point(sp, F, sym, fs)
    assert np.allclose(m_.position(V, F), sp.position(V, F) * [-1, 1, 1])
    back = mirror_surface_point(m_, F, sym, fs)
    assert back.triangle == sp.triangle and np.allclose(back.bary, sp.bary)
    # where the template has no mirror triangle, the reflected position is located
    side = SurfacePoint(100, (0.2, 0.3, 0.5))
    with pytest.raises(Exception):
        mirror_surface_point(side, F, sym, fs)
    m2 = mirror_surface_point(side, F, sym, fs, SurfaceLocator(V, F))
    assert np.allclose(m2.position(V, F), side.position(V, F) * [-1, 1, 1], atol=1e-9)


def test_surface_tools_are_reused_per_instance():
    V, F = capped_cylinder()
    t1 = surface_tools(V, F)
    assert surface_tools(V.copy(), F) is t1
    assert surface_tools(V * 1.01, F) is not t1
    e, fe = t1.edges
    assert len(e) == 3 * len(F) // 2 and fe.shape == F.shape  # closed surface: E = 3F/2


def test_turned_normal_holds_the_point():
    n, cos_turn = turned_normal(np.array([0.0, 0.0, 1.0]), np.zeros(3), np.array([1.0, 0.0, 1.0]))
    assert abs(n @ np.array([1.0, 0.0, 1.0])) < 1e-12 and cos_turn == pytest.approx(np.sqrt(0.5))
    assert turned_normal(np.array([0.0, 0.0, 1.0]), np.zeros(3), np.zeros(3)) == (None, None)
    assert turned_normal(np.array([0.0, 0.0, 1.0]), np.zeros(3), np.array([0.0, 0.0, 2.0])) == (None, 0.0)


def test_section_loop_from_its_start():
    V, F = capped_cylinder()
    loc = SurfaceLocator(V, F)
    start = loc.locate(np.array([[0.1, 0.0, 0.3]]))[0]
    p0 = start.position(V, F)
    poly, pts, segf = plane_section_loop(V, F, p0, np.array([0.0, 0.0, 1.0]), start.triangle)
    loop = SectionLoop(V, F, poly, pts, segf, p0, start)
    assert loop.S[0] == start and np.allclose(loop.closed[0], loop.closed[-1])
    assert loop.total == pytest.approx(polyline_length(poly, closed=True))
    assert loop.at(0.0) == start and loop.at(loop.total) == start  # modulo the loop length
    q = loop.at(loop.total / 4).position(V, F)
    assert abs(q[2] - 0.3) < 1e-9 and np.linalg.norm(q[:2]) == pytest.approx(0.1, abs=1e-3)
    s, dist = loop.arc_position(q)
    assert s == pytest.approx(loop.total / 4, abs=1e-9) and dist < 1e-9


def test_vertical_walk_goes_down_the_side():
    V, F = capped_cylinder()
    start = SurfaceLocator(V, F).locate(np.array([[0.1, 0.0, 0.5]]))[0]
    walked, end = vertical_walk(V, F, start, 0.2, down=True)
    assert polyline_length(walked) == pytest.approx(0.2, abs=1e-9)
    assert end.position(V, F)[2] == pytest.approx(start.position(V, F)[2] - 0.2, abs=1e-6)
    up, _ = vertical_walk(V, F, start, 0.05, down=False)
    assert up[-1, 2] > up[0, 2]


def _in_worker(fn):
    """``fn()`` run in a worker thread (its value, or its exception raised here)."""
    import threading

    out = {}

    def run():
        try:
            out["value"] = fn()
        except BaseException as exc:
            out["error"] = exc

    t = threading.Thread(target=run)
    t.start()
    t.join()
    if "error" in out:
        raise out["error"]
    return out["value"]


def test_edge_flip_solvers_are_kept_per_mesh_and_built_out_of_process(monkeypatch):
    """A re-cut on the same mesh builds no solver; in a worker with OUT_OF_PROCESS the solver is
    the helper process's (its constructor holds the GIL: issue 32), with the same paths; a
    non-manifold mesh is refused there as here; a helper that ended is restarted."""
    from core.design import geometry

    V, F = capped_cylinder()
    s1 = geometry.edge_flip_solver(V, F)
    assert geometry.edge_flip_solver(V.copy(), F.copy()) is s1  # the same mesh: the same solver
    moved = V.copy()
    moved[0, 2] += 1e-3
    assert geometry.edge_flip_solver(moved, F) is not s1
    pairs = [(0, 700), (5, 1300), (1441, 1440), (700, 0)]
    here = [s1.path(a, b) for a, b in pairs]
    # a cached solver answers as a fresh one, whatever it answered before (here: in the other order)
    for k in reversed(range(len(pairs))):
        fresh = geometry._LocalSolver(np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int64))
        np.testing.assert_allclose(fresh.path(*pairs[k]), here[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(s1.path(*pairs[k]), here[k], rtol=0, atol=1e-12)
    monkeypatch.setattr(geometry, "OUT_OF_PROCESS", True)
    try:
        remote = _in_worker(lambda: geometry.edge_flip_solver(V, F))
        assert isinstance(remote, geometry._RemoteSolver)
        assert geometry._Helper.proc is not None and geometry._Helper.proc.poll() is None
        for (a, b), p in zip(pairs, here):
            np.testing.assert_allclose(_in_worker(lambda: remote.path(a, b)), p, rtol=0, atol=1e-12)
        geometry.stop_helper()  # (the helper ends: the next path starts one and rebuilds there)
        np.testing.assert_allclose(_in_worker(lambda: remote.path(*pairs[1])), here[1], rtol=0, atol=1e-12)
        # the main thread builds its own (a pause there is its own, no other thread's)
        assert isinstance(geometry.edge_flip_solver(V, F), geometry._LocalSolver)
        bad = np.vstack([F, [[0, 1, 2], [0, 1, 2]]])  # an edge of four triangles
        with pytest.raises(RuntimeError):
            _in_worker(lambda: geometry.edge_flip_solver(V, bad))
        with pytest.raises(RuntimeError):
            geometry.edge_flip_solver(V, bad)
        # no helper can start (an executable that is not Python): built here, as without one
        geometry.stop_helper()
        monkeypatch.setattr(geometry._Helper, "unavailable", None)
        monkeypatch.setattr("sys.executable", "/nonexistent/python")
        assert isinstance(_in_worker(lambda: geometry.edge_flip_solver(moved, F)), geometry._LocalSolver)
        assert geometry._Helper.unavailable
    finally:
        geometry.stop_helper()
    assert geometry._Helper.proc is None
