"""core.cut.engine.cut_surface on a synthetic tube body (and on Anny, see test_cut_anny)."""

import numpy as np
import pytest
from cut_synth import LEFT, R, SynthBody, capsule, surface_distance, triangle_areas, tube_spec

from core.cut.engine import cut_surface
from core.cut.geodesic import GeodesicPaths, insert_keypoints
from core.cut.refine import SPLIT_RATIO
from core.cut.split import CutMesh
from core.design.spec import CutLine, PanelSpec
from core.errors import CutError
from core.geom.polyline import polyline_length


@pytest.fixture(scope="module")
def body():
    return SynthBody()


@pytest.fixture(scope="module")
def cut(body):
    return cut_surface(body, body.V, tube_spec(body))


def test_panels_seams_hems(cut):
    assert [p.name for p in cut.panels] == ["shirt.front", "shirt.back"]
    assert {s.name for s in cut.seams} == {"shirt.side_left", "shirt.side_right"}
    for s in cut.seams:
        a, b = cut.panel(s.panel_a), cut.panel(s.panel_b)
        assert {s.panel_a, s.panel_b} == {"shirt.front", "shirt.back"}
        assert len(s.verts_a) == len(s.verts_b) > 5
        # both sides are the same global vertices, hence the same 3D length
        np.testing.assert_array_equal(a.vertex_ids[s.verts_a], b.vertex_ids[s.verts_b])
    for p in cut.panels:
        assert len(p.boundary) == 1  # a disk
        assert len(cut.hems[p.name]) == 2  # neck and hem stretches
        assert p.warp_dir.shape == (len(p.faces), 3)
        np.testing.assert_allclose(np.linalg.norm(p.warp_dir, axis=1), 1.0)
        np.testing.assert_array_equal(p.ease, 1.0)
    assert set(cut.pins) == {"shirt"}
    assert len(np.unique(cut.pins["shirt"])) == len(cut.pins["shirt"]) > 10


def test_faces_outward_and_on_body(body, cut):
    X = cut.positions(body.V)
    for p in cut.panels:
        P = X[p.vertex_ids]
        n = np.cross(P[p.faces[:, 1]] - P[p.faces[:, 0]], P[p.faces[:, 2]] - P[p.faces[:, 0]])
        c = P[p.faces].mean(1)
        radial = c * [1, 1, 0]
        assert np.all((n * radial).sum(1) > 0)
    assert surface_distance(X, body.V, body.faces).max() < 1e-9


def test_panel_grain_torso_vertical(cut, body):
    for p in cut.panels:
        # the tube's torso axis (no joints, no landmarks) is +Z; the tube walls are vertical
        np.testing.assert_allclose(p.warp_dir[:, 2], 1.0, atol=1e-3)


def test_partition_covers_closed_surface():
    """With panels on both caps too, the panels tile the whole closed surface once."""
    body = SynthBody(forbidden=False)
    cut = cut_surface(body, body.V, tube_spec(body, extra_panels=True))
    X = cut.positions(body.V)
    area = sum(triangle_areas(X[p.vertex_ids], p.faces).sum() for p in cut.panels)
    np.testing.assert_allclose(area, triangle_areas(body.V, body.faces).sum(), rtol=1e-10)
    tris = np.concatenate([np.sort(p.vertex_ids[p.faces], axis=1) for p in cut.panels])
    assert len(np.unique(tris, axis=0)) == len(tris)  # no face doubled
    # neck and hem are openings: hems on both sides; the caps are panels of their own
    assert len(cut.hems["shirt.cap_top"]) == 1


def test_cut_lines_are_geodesics(body, cut):
    spec = tube_spec(body)
    mesh = CutMesh(body.V, body.faces)
    flat = [p for l in spec.lines for p in l.points]
    kv = insert_keypoints(mesh, flat, body.faces, body.V)
    geo = GeodesicPaths(mesh.X, mesh.F)
    hem = kv[4:8]
    ref = sum(polyline_length(geo.path(a, b)) for a, b in zip(hem, hem[1:] + hem[:1]))
    X = cut.positions(body.V)
    got = 0.0
    for name in ("shirt.front", "shirt.back"):
        p = cut.panel(name)
        for h in cut.hems[name]:
            P = X[p.vertex_ids[h]]
            if P[:, 2].mean() < 0.5:
                got += polyline_length(P)
    np.testing.assert_allclose(got, ref, rtol=1e-6)
    # the hem of a tube is (close to) a horizontal circle of the polygonal tube
    assert abs(ref - 2 * np.pi * R) < 0.01 * 2 * np.pi * R


def test_embedding_transfers_to_other_instances(body, cut):
    for kw in ({"twist": 0.8}, {"scale": 1.3}):
        V2, F2 = capsule(**kw)
        X2 = cut.positions(V2)
        assert np.all(np.isfinite(X2))
        assert surface_distance(X2, V2, F2).max() < 1e-9
    assert cut.embedding.shape == (cut.n_vertices, len(body.V))
    np.testing.assert_allclose(np.asarray(cut.embedding.sum(1)).ravel(), 1.0)


def test_deterministic(body, cut):
    again = cut_surface(body, body.V, tube_spec(body))
    assert (again.embedding != cut.embedding).nnz == 0
    for p, q in zip(cut.panels, again.panels):
        np.testing.assert_array_equal(p.faces, q.faces)
        np.testing.assert_array_equal(p.vertex_ids, q.vertex_ids)
        np.testing.assert_array_equal(p.warp_dir, q.warp_dir)


def test_refined_cut(body):
    h = 0.008
    cut = cut_surface(body, body.V, tube_spec(body, refine=h))
    X = cut.positions(body.V)
    coarse = cut_surface(body, body.V, tube_spec(body))
    Xc = coarse.positions(body.V)
    for p, q in zip(cut.panels, coarse.panels):
        P = X[p.vertex_ids]
        e = np.linalg.norm(P[p.faces] - P[np.roll(p.faces, -1, 1)], axis=2)
        assert e.max() <= SPLIT_RATIO * h + 1e-12
        a = triangle_areas(P, p.faces).sum()
        np.testing.assert_allclose(
            a, triangle_areas(Xc[q.vertex_ids], q.faces).sum(), rtol=1e-6
        )  # Delaunay flips: nearly coplanar
        assert len(p.boundary) == 1
    for s in cut.seams:
        a, b = cut.panel(s.panel_a), cut.panel(s.panel_b)
        np.testing.assert_array_equal(a.vertex_ids[s.verts_a], b.vertex_ids[s.verts_b])
        la = polyline_length(X[a.vertex_ids[s.verts_a]])
        sc = next(t for t in coarse.seams if t.name == s.name)
        lc = polyline_length(Xc[coarse.panel(sc.panel_a).vertex_ids[sc.verts_a]])
        np.testing.assert_allclose(la, lc, rtol=1e-9)
    assert surface_distance(X, body.V, body.faces).max() < 1e-9


# ---- errors ------------------------------------------------------------------------------------
def test_loop_that_does_not_close(body):
    with pytest.raises(CutError, match="shirt.back.*does not close"):
        cut_surface(body, body.V, tube_spec(body, close_top=False))


def test_missing_seam_merges_panels(body):
    spec = tube_spec(body)
    spec.lines = [l for l in spec.lines if l.name != "shirt.side_right"]
    with pytest.raises(CutError, match="shirt.front.*shirt.back"):
        cut_surface(body, body.V, spec)


def test_crossing_lines(body):
    spec = tube_spec(body)
    spec.lines.append(
        CutLine("shirt.belt", [body.point([R * np.cos(a), R * np.sin(a), 0.5]) for a in (LEFT - 0.5, LEFT + 0.5)])
    )
    with pytest.raises(CutError, match="shirt.belt.*shirt.side_left|shirt.side_left.*shirt.belt"):
        cut_surface(body, body.V, spec)


def test_seed_in_head_region(body):
    spec = tube_spec(body)
    spec.panels[1] = PanelSpec("shirt.back", "shirt", body.point([0, R, 0.95]))
    with pytest.raises(CutError, match="shirt.back.*head"):
        cut_surface(body, body.V, spec)


def test_bad_keypoint_and_names(body):
    from core.body.model import SurfacePoint

    spec = tube_spec(body)
    spec.lines[0].points[1] = SurfacePoint(10**7, (1.0, 0.0, 0.0))
    with pytest.raises(CutError, match="shirt.neck.*off the body"):
        cut_surface(body, body.V, spec)
    spec = tube_spec(body)
    spec.panels[0] = PanelSpec("shirt.front", "nope", spec.panels[0].seed)
    with pytest.raises(CutError, match="shirt.front.*unknown garment"):
        cut_surface(body, body.V, spec)


def test_self_seam_opens_a_tube_panel(body):
    """One panel around the tube with one seam: the panel is cut open (a disk) and sewn to itself."""
    spec = tube_spec(body, refine=0.01)
    spec.lines = [l for l in spec.lines if l.name != "shirt.side_right"]
    spec.panels = spec.panels[:1]
    cut = cut_surface(body, body.V, spec)
    (p,) = cut.panels
    assert len(p.boundary) == 1
    (s,) = cut.seams
    assert s.panel_a == s.panel_b == "shirt.front"
    np.testing.assert_array_equal(p.vertex_ids[s.verts_a], p.vertex_ids[s.verts_b])
    assert np.all(s.verts_a != s.verts_b)
    assert len(p.vertex_ids) - len(np.unique(p.vertex_ids)) == len(s.verts_a)


def test_progress_and_cancel(body):
    from core.errors import Cancelled

    seen = []
    cut_surface(body, body.V, tube_spec(body), progress=lambda f, m: seen.append((f, m)))
    fr = [f for f, _ in seen]
    assert fr[0] == 0.0 and fr[-1] == 1.0 and all(b >= a for a, b in zip(fr, fr[1:]))
    assert any("shirt.hem" in m for _, m in seen)

    def stop(f, m):
        if f > 0.3:
            raise Cancelled()

    with pytest.raises(Cancelled):
        cut_surface(body, body.V, tube_spec(body), progress=stop)
