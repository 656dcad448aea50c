"""The cutting engine on the real default body (Anny): a 6-panel long-sleeve shirt."""

import time

import numpy as np
import pytest
from cut_anny_shirt import shirt_spec
from cut_synth import surface_distance, triangle_areas

from core.cut.engine import cut_surface
from core.cut.refine import SPLIT_RATIO
from core.geom.polyline import polyline_length


@pytest.fixture(scope="module")
def shirt(anny, anny_reference):
    body, (X, J) = anny, anny_reference
    spec = shirt_spec(body, X, J, refine=0.01)
    t = time.perf_counter()
    cut = cut_surface(body, X, spec)
    print(f"\n6-panel shirt on Anny: cut in {time.perf_counter() - t:.2f} s, {cut.n_vertices} vertices")
    return spec, cut


def test_six_panels_and_seams(shirt, anny, anny_reference):
    _body, (X, _) = anny, anny_reference
    spec, cut = shirt
    names = [p.name for p in cut.panels]
    assert names == [
        "shirt.front",
        "shirt.back",
        "shirt.sleeve_front_left",
        "shirt.sleeve_back_left",
        "shirt.sleeve_front_right",
        "shirt.sleeve_back_right",
    ]
    G = cut.positions(X)
    pairs = {frozenset((s.panel_a, s.panel_b)) for s in cut.seams}
    assert frozenset(("shirt.front", "shirt.back")) in pairs
    assert frozenset(("shirt.front", "shirt.sleeve_front_left")) in pairs
    assert frozenset(("shirt.sleeve_front_left", "shirt.sleeve_back_left")) in pairs
    for s in cut.seams:
        a, b = cut.panel(s.panel_a), cut.panel(s.panel_b)
        np.testing.assert_array_equal(a.vertex_ids[s.verts_a], b.vertex_ids[s.verts_b])
        la = polyline_length(cut.panel_positions(a, X)[s.verts_a])
        lb = polyline_length(cut.panel_positions(b, X)[s.verts_b])
        assert la > 0.02
        assert abs(la - lb) < 1e-12
    for p in cut.panels:
        assert len(p.boundary) == 1, p.name  # every panel is a disk
        P = G[p.vertex_ids]
        e = np.linalg.norm(P[p.faces] - P[np.roll(p.faces, -1, 1)], axis=2)
        assert e.max() <= SPLIT_RATIO * 0.01 + 1e-12
    # openings: neck and hem on front/back, a cuff on every sleeve panel
    for n in ("shirt.sleeve_front_left", "shirt.sleeve_back_right"):
        assert len(cut.hems[n]) == 1
    assert len(cut.pins["shirt"]) > 20


def test_panels_partition_the_garment_region(shirt, anny, anny_reference):
    body, (X, _) = anny, anny_reference
    _, cut = shirt
    G = cut.positions(X)
    tris = np.concatenate([np.sort(p.vertex_ids[p.faces], axis=1) for p in cut.panels])
    assert len(np.unique(tris, axis=0)) == len(tris)
    # refinement keeps the area (up to Delaunay flips between nearly coplanar triangles)
    spec = shirt_spec(body, X, anny_reference[1], refine=None)
    coarse = cut_surface(body, X, spec)
    Gc = coarse.positions(X)
    for p, q in zip(cut.panels, coarse.panels):
        np.testing.assert_allclose(
            triangle_areas(G[p.vertex_ids], p.faces).sum(), triangle_areas(Gc[q.vertex_ids], q.faces).sum(), rtol=1e-4
        )  # < one 1 cm^2 triangle
    # the unrefined panels are made of whole or split body triangles: their area plus the
    # area of the rest of the body (the other flood-fill regions) is the body's area
    area = sum(triangle_areas(Gc[q.vertex_ids], q.faces).sum() for q in coarse.panels)
    assert 0.15 < area / triangle_areas(X, body.faces).sum() < 0.6
    # the garment sits on the body
    assert surface_distance(Gc, X, body.faces).max() < 1e-9


def test_outward_orientation(shirt, anny, anny_reference):
    body, (X, _) = anny, anny_reference
    _, cut = shirt
    import igl

    G = cut.positions(X)
    Fb = np.asarray(body.faces, dtype=np.int64)
    nb = np.cross(X[Fb[:, 1]] - X[Fb[:, 0]], X[Fb[:, 2]] - X[Fb[:, 0]])
    for p in cut.panels:
        P = G[p.vertex_ids]
        n = np.cross(P[p.faces[:, 1]] - P[p.faces[:, 0]], P[p.faces[:, 2]] - P[p.faces[:, 0]])
        _, fi, _ = igl.point_mesh_squared_distance(P[p.faces].mean(1), X, Fb)
        assert np.mean((n * nb[fi]).sum(1) > 0) > 0.99, p.name


def test_grain(shirt, anny, anny_reference):
    body, (_X, J) = anny, anny_reference
    _, cut = shirt
    jn = body.joint_names
    arm = J[jn.index("upperarm01.L")] - J[jn.index("wrist.L")]
    arm /= np.linalg.norm(arm)
    for p in cut.panels:
        np.testing.assert_allclose(np.linalg.norm(p.warp_dir, axis=1), 1.0)
        if p.name == "shirt.front":
            assert np.median(p.warp_dir[:, 2]) > 0.9  # up the torso
        if p.name == "shirt.sleeve_front_left":
            assert np.median(p.warp_dir @ arm) > 0.8  # along the arm, towards the shoulder


def test_transfer_to_shapes_and_poses(shirt, anny, anny_reference):
    body, (_X, _) = anny, anny_reference
    _, cut = shirt
    Fb = np.asarray(body.faces, dtype=np.int64)
    instances = [
        ({"weight": 0.1, "height": 0.3}, None),
        ({"weight": 0.9, "height": 0.7, "muscle": 0.7}, None),
        (None, "P1"),
        (None, "P2"),
        (None, "P3"),
    ]
    for shape, pose in instances:
        V = body.vertices(shape, pose)
        G = cut.positions(V)
        assert np.all(np.isfinite(G))
        # refined vertices are midpoints of chords: within a few mm of the surface
        assert surface_distance(G, V, Fb).max() < 0.003, (shape, pose)
        for p in cut.panels:
            assert triangle_areas(G[p.vertex_ids], p.faces).min() > 0, (shape, pose, p.name)


def test_left_right_mirror(shirt, anny, anny_reference):
    _body, (X, _) = anny, anny_reference
    _, cut = shirt
    G = cut.positions(X)
    for a, b in (
        ("shirt.sleeve_front_left", "shirt.sleeve_front_right"),
        ("shirt.sleeve_back_left", "shirt.sleeve_back_right"),
    ):
        pa, pb = cut.panel(a), cut.panel(b)
        Aa = triangle_areas(G[pa.vertex_ids], pa.faces).sum()
        Ab = triangle_areas(G[pb.vertex_ids], pb.faces).sum()
        assert abs(Aa - Ab) < 0.01 * Aa
        # every vertex of the mirrored left panel is close to the right panel
        M = G[pa.vertex_ids] * [-1, 1, 1]
        assert surface_distance(M, G[pb.vertex_ids], pb.faces).max() < 0.002


def test_deterministic(shirt, anny, anny_reference):
    body, (X, J) = anny, anny_reference
    spec, cut = shirt
    again = cut_surface(body, X, shirt_spec(body, X, J, refine=0.01))
    assert (again.embedding != cut.embedding).nnz == 0
    for p, q in zip(cut.panels, again.panels):
        np.testing.assert_array_equal(p.faces, q.faces)
        np.testing.assert_array_equal(p.warp_dir, q.warp_dir)


def _distance_to_polyline(P, Q):
    """Distance (p,) of points P (p, 3) to the polyline Q (q, 3)."""
    a, b = Q[:-1], Q[1:]
    ab = b - a
    t = np.clip(np.einsum("pij,ij->pi", P[:, None] - a[None], ab) / np.maximum((ab * ab).sum(1), 1e-18), 0, 1)
    return np.linalg.norm(a[None] + t[..., None] * ab[None] - P[:, None], axis=2).min(axis=1)


def test_template_seams_are_the_exact_geodesics(anny, anny_reference):
    """The shirt template's seamlines, as cut, are potpourri3d's geodesics between their
    keypoints: every seam vertex within SNAP_ABS (0.5 mm) of the geodesic and the same
    length to 0.1 % - not snapped to mesh vertices, no zig-zag along mesh edges (which
    would be several % longer and up to half an edge, ~5 mm, off)."""
    from core.cut import cut_design
    from core.cut.geodesic import GeodesicPaths, insert_keypoints
    from core.cut.split import SNAP_ABS, CutMesh
    from core.design import load_design, resolve
    from core.design.templates import TEMPLATE_DIR

    body, (X, _) = anny, anny_reference
    BF = np.asarray(body.faces)
    d = load_design(TEMPLATE_DIR / "shirt_long_sleeve.json")
    spec = resolve(d, body, vertices=X)
    cut = cut_design(d, body=body)
    GX = cut.positions(X)
    checked = 0
    for line in spec.lines:
        seams = [s for s in cut.seams if s.name == line.name]
        if line.closed or len(seams) != 1:
            continue
        mesh = CutMesh(X, BF)
        kv = insert_keypoints(mesh, line.points, BF, X)
        geo = GeodesicPaths(mesh.X, mesh.F)
        G = np.vstack([geo.path(a, b) for a, b in zip(kv[:-1], kv[1:])])
        s = seams[0]
        P = GX[np.asarray(cut.panel(s.panel_a).vertex_ids)[s.verts_a]]
        assert len(P) > len(line.points)  # it crosses the mesh
        assert _distance_to_polyline(P, G).max() <= SNAP_ABS + 1e-9, line.name
        assert abs(polyline_length(P) - polyline_length(G)) < 1e-3 * polyline_length(G), line.name
        checked += 1
    assert checked >= 8  # shoulders, sides, sleeve tops and undersides
