"""The drape's own mesh (core.drape.refine): the pattern bisected where the cloth hangs free."""

import numpy as np
import pytest
from drape_synth import revolution_body, tube_skirt

from core.drape import drape
from core.drape.mesh import build_cloth
from core.drape.output import obj_text, report_dict
from core.drape.refine import edge_lengths, refine_pattern
from core.errors import DrapeError
from core.geom.frame import to_y_up
from core.metrics.drape import drape_metrics, summary


def signed_areas(uv, faces):
    a, b = uv[faces[:, 1]] - uv[faces[:, 0]], uv[faces[:, 2]] - uv[faces[:, 0]]
    return 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def polyline_length(uv, poly, closed=False):
    p = uv[np.r_[poly, poly[:1]] if closed else poly]
    return np.linalg.norm(np.diff(p, axis=0), axis=1).sum()


@pytest.fixture(scope="module")
def skirt():
    return tube_skirt(1.2, n_rows=4, n_cols=4)


@pytest.fixture(scope="module")
def refined(skirt):
    return refine_pattern(skirt, 0.03)


def test_rest_shape_is_the_flat_pattern_subdivided(skirt, refined):
    out, rep = refined
    for p0, p in zip(skirt.panels, out.panels):
        # the pattern's own vertices keep their place and ids; the new ones come after every old id
        n0 = len(p0.uv)
        assert np.array_equal(p.uv[:n0], p0.uv) and np.array_equal(p.vertex_ids[:n0], p0.vertex_ids)
        assert p.vertex_ids[n0:].min() > max(q.vertex_ids.max() for q in skirt.panels)
        # the rest triangles tile the pattern: same orientation, areas adding up exactly
        a0, a = signed_areas(p0.uv, p0.faces), signed_areas(p.uv, p.faces)
        assert np.all(np.sign(a) == np.sign(a0[0])) and a.sum() == pytest.approx(a0.sum(), rel=1e-12)
        # outlines and hems keep their rest lengths, through the new midpoints
        for b0, b in zip(p0.boundary, p.boundary):
            assert len(b) > len(b0) and polyline_length(p.uv, b, True) == pytest.approx(
                polyline_length(p0.uv, b0, True), rel=1e-12
            )
        for h0, h in zip(p0.hems, p.hems):
            assert polyline_length(p.uv, h) == pytest.approx(polyline_length(p0.uv, h0), rel=1e-12)
        # no edge longer than the target (all of this 1.2-ease skirt hangs free)
        assert edge_lengths(p.uv, p.faces).max() <= 0.03 + 1e-12
        assert len(p.target_weft) == len(p.faces)
    assert rep["triangles_before"] == sum(len(p.faces) for p in skirt.panels)
    assert rep["triangles_after"] == sum(len(p.faces) for p in out.panels) > 4 * rep["triangles_before"]
    assert rep["edge_mm_before"]["max"] > 30.0 >= rep["edge_mm_after"]["max"] and rep["free_pct"] == 100.0


def test_seams_stay_sewn(skirt, refined):
    out, _ = refined
    for s0, s in zip(skirt.seams, out.seams):
        assert len(s.verts_a) == len(s.verts_b) > len(s0.verts_a)  # same vertex count on both sides ...
        ga = out.panel(s.panel_a).vertex_ids[s.verts_a]
        gb = out.panel(s.panel_b).vertex_ids[s.verts_b]
        assert np.array_equal(ga, gb)  # ... one vertex each: the seam's new midpoints are shared
        la, lb = (polyline_length(out.panel(n).uv, v) for n, v in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b)))
        ua, ub = skirt.seam_polylines(s0)
        assert la == pytest.approx(polyline_length(ua, np.arange(len(ua))), rel=1e-12)
        assert lb == pytest.approx(polyline_length(ub, np.arange(len(ub))), rel=1e-12)
    cloth = build_cloth(out)
    assert cloth.n_particles == len(np.unique(np.concatenate([p.vertex_ids for p in out.panels])))
    # the waistband's new midpoints are pinned with it, on its line
    top = np.abs(cloth.x0[:, 2] - 0.95) < 1e-12
    assert np.array_equal(cloth.pinned, top)


def test_the_cloth_keeps_the_pattern_rest_areas(skirt):
    plain, fine = build_cloth(skirt), build_cloth(skirt, refine_edge=0.03)
    for k in range(len(skirt.panels)):
        assert fine.rest_area[fine.face_panel == k].sum() == pytest.approx(
            plain.rest_area[plain.face_panel == k].sum(), rel=1e-12
        )
    assert fine.n_pattern == plain.n_global and np.array_equal(fine.pattern_faces, plain.faces_global)
    assert fine.refinement["triangles_after"] == len(fine.faces)


def test_cloth_that_clings_keeps_the_pattern_mesh():
    # skintight: no room to fold (12 columns: the 3D chords are within 0.3 % of the pattern's arcs)
    tight = tube_skirt(1.0, n_rows=4, n_cols=12)
    out, rep = refine_pattern(tight, 0.03)
    assert rep["free_pct"] == 0.0 and rep["triangles_after"] == rep["triangles_before"] and rep["rounds"] == 0
    assert all(np.array_equal(p.faces, q.faces) for p, q in zip(tight.panels, out.panels))


def test_refined_drape_reports_its_mesh_and_folds(skirt):
    body = revolution_body(48, 60)
    r = drape(skirt, *body, options={"refine_edge": 0.04, "max_frames": 8, "min_frames": 1})
    rep = r.refinement
    assert rep["target_edge_m"] == 0.04 and rep["triangles_after"] == len(r.faces) > rep["triangles_before"]
    n0 = r.pattern_vertices
    assert n0 == max(p.vertex_ids.max() for p in skirt.panels) + 1 and len(r.positions) > n0
    assert r.used.all() and np.array_equal(
        r.pattern_faces, np.concatenate([p.vertex_ids[p.faces] for p in skirt.panels])
    )
    fit = drape_metrics(r, *body, pattern=skirt)
    # the fold measures are taken on the draped (refined) mesh: one per interior edge of it
    from core.drape.mesh import interior_edges

    assert fit["all"]["folds"]["edges"] == len(interior_edges(r.faces)[0]) > 3 * len(r.pattern_faces)
    report = report_dict(r, summary(fit), skirt)
    assert report["triangles"] == len(r.faces) and report["pattern_triangles"] == len(r.pattern_faces)
    assert report["refinement"]["edge_mm_after"]["max"] <= 40.0 and report["folds"]["edges"] > 0
    # the pattern as draped: its panels' triangles are the draped ones, corner for corner
    mesh = r.mesh_pattern
    assert np.array_equal(np.concatenate([p.vertex_ids[p.faces] for p in mesh.panels]), r.faces)
    assert sum(len(p.faces) for p in mesh.panels) == rep["triangles_after"]
    obj = obj_text(r)
    assert f"# vertices 1..{n0}: the pattern's" in obj and obj.count("\nv ") == len(r.positions)
    # Y-up by default; up="z" keeps the core frame, vertex for vertex
    for up, want in (("y", to_y_up(r.positions)), ("z", r.positions)):
        v = np.array([line.split()[1:] for line in obj_text(r, up).splitlines() if line.startswith("v ")], float)
        assert np.allclose(v, want, atol=1e-6), up


def min_angles(uv, faces):
    """(T,) each triangle's smallest angle, degrees."""
    t = uv[faces]
    out = []
    for k in range(3):
        u, v = t[:, (k + 1) % 3] - t[:, k], t[:, (k + 2) % 3] - t[:, k]
        out.append(np.degrees(np.arctan2(np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]), np.einsum("ij,ij->i", u, v))))
    return np.min(out, axis=0)


def test_a_sliver_is_flipped_not_bisected(skirt):
    """A sliver of the pattern's mesh (one vertex almost on the opposite edge: 4.5 degrees) in the
    free cloth: bisected, its children were slivers again (the old mesh: 4.5 degrees), and the
    drape's bending leaves thin triangles out, where the cloth then folded flat. Flipped to the
    quadrilateral's other diagonal first, every refined triangle is well shaped; the rest shape
    (areas, outlines) is still the pattern's."""
    from dataclasses import replace

    p = skirt.panels[0]
    uv = p.uv.copy()
    a, b, c = 1 * 5 + 2, 1 * 5 + 3, 2 * 5 + 2  # a cell's corner, pushed almost onto its diagonal b-c
    uv[a] += 0.45 * ((uv[b] - uv[a]) + (uv[c] - uv[a]))
    slivered = replace(skirt, panels=[replace(p, uv=uv), *skirt.panels[1:]])
    assert min_angles(uv, p.faces).min() < 5.0
    out, rep = refine_pattern(slivered, 0.03)
    assert rep["flips"] > 0
    for p0, q in zip(slivered.panels, out.panels):
        assert min_angles(q.uv, q.faces).min() > 20.0
        a0, a1 = signed_areas(p0.uv, p0.faces), signed_areas(q.uv, q.faces)
        assert np.all(np.sign(a1) == np.sign(a0[0])) and a1.sum() == pytest.approx(a0.sum(), rel=1e-12)
        assert edge_lengths(q.uv, q.faces).max() <= 0.03 + 1e-12
        for b0, b1 in zip(p0.boundary, q.boundary):
            assert polyline_length(q.uv, b1, True) == pytest.approx(polyline_length(p0.uv, b0, True), rel=1e-12)


@pytest.mark.parametrize("edge", [0.0, -0.01, float("nan"), 1.0])
def test_refine_edge_is_a_length(skirt, edge):
    body = revolution_body(12, 10)
    with pytest.raises(DrapeError, match="refine_edge"):
        drape(skirt, *body, options={"refine_edge": edge})


def test_cli_refuses_a_bad_refine_edge(tmp_path, capsys):
    from core.cli import main

    assert main(["drape", str(tmp_path / "none"), "--out", str(tmp_path / "o"), "--refine-edge", "-1"]) == 2
    assert "--refine-edge" in capsys.readouterr().err
