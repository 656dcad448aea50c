"""Fit measurements after the drape (core.metrics.drape), on exact synthetic geometry."""

import numpy as np
import pytest
from drape_synth import HIP_RADIUS, radius, revolution_body, tube_skirt

from core.drape import drape
from core.drape.mesh import build_cloth
from core.geom.mesh import vertex_normals
from core.metrics.drape import (
    covered_body_vertices,
    drape_metrics,
    penetration,
    post_drape_gap,
    seam_gap,
    seam_side_distance,
    summary,
)


@pytest.fixture(scope="module")
def body():
    return revolution_body(48, 60)


def _offset_skirt(skirt, delta):
    """Skintight positions per global id, and the same pushed out radially by ``delta`` m."""
    cloth = build_cloth(skirt)
    x0 = cloth.x0[cloth.particle_of]
    r = np.hypot(x0[:, 0], x0[:, 1])
    out = x0.copy()
    out[:, :2] *= ((r + delta) / r)[:, None]
    return x0, out, cloth.faces_global


def test_vertex_normals_point_outward(body):
    # the directions of the gap rays
    v, f = body
    n = vertex_normals(v, f)
    side = (v[:, 2] > 0.3) & (v[:, 2] < 1.3)
    radial = v[side, :2] / np.linalg.norm(v[side, :2], axis=1, keepdims=True)
    assert np.all(np.einsum("ij,ij->i", n[side, :2], radial) > 0.9)
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0)


def test_gap_of_an_offset_garment_is_the_offset(body):
    skirt = tube_skirt(1.0, n_rows=12, n_cols=24)
    x0, out, faces = _offset_skirt(skirt, 0.02)
    gap, covered = post_drape_gap(*body, out, faces, x0)
    v = body[0]
    # covered: the body vertices on the hips between hem and waistband
    assert covered.sum() > 0
    assert np.all((v[covered, 2] > 0.6) & (v[covered, 2] < 0.96))
    inner = (v[covered, 2] > 0.64) & (v[covered, 2] < 0.93)
    assert np.allclose(gap[inner], 0.02, atol=1e-3)


def test_gap_is_zero_where_the_ray_misses(body):
    skirt = tube_skirt(1.0, n_rows=6, n_cols=12)
    x0, out, faces = _offset_skirt(skirt, 0.02)
    out[:, 2] += 5.0  # the garment flew away: nothing is hit
    gap, covered = post_drape_gap(*body, out, faces, x0)
    assert covered.any() and np.all(gap == 0.0)


def test_covered_vertices_follow_the_skintight_garment(body):
    skirt = tube_skirt(1.0, n_rows=6, n_cols=12, top=0.9, bottom=0.7)
    x0, _, faces = _offset_skirt(skirt, 0.0)
    covered = covered_body_vertices(body[0], x0, faces)
    z = body[0][:, 2]
    assert np.all((z[covered] > 0.69) & (z[covered] < 0.91))
    ring = (z > 0.72) & (z < 0.88)
    assert covered[ring].all()


def test_penetration_share(body):
    skirt = tube_skirt(1.0, n_rows=6, n_cols=12)
    x0, out, _ = _offset_skirt(skirt, 0.01)
    share, sd = penetration(out, *body)
    assert share == 0.0 and sd.min() > 0.005
    inside = x0.copy()  # on the body surface
    half = np.arange(len(inside)) % 2 == 0
    r = np.hypot(inside[:, 0], inside[:, 1])
    inside[half, :2] *= ((r[half] - 0.005) / r[half])[:, None]  # 5 mm inside, beyond the 2 mm allowed
    share, sd = penetration(inside, *body)
    assert share == pytest.approx(half.mean(), abs=0.01)
    shallow = x0.copy()
    shallow[:, :2] *= ((r - 0.001) / r)[:, None]  # 1 mm inside: within tolerance
    assert penetration(shallow, *body)[0] == 0.0


def test_seam_gap_measures_sides():
    x = np.array([[0, 0, 0], [0, 0.003, 0], [1, 0, 0], [1, 0, 0.0]], float)
    assert np.allclose(seam_gap(x, np.array([[0, 1], [2, 3]])), [0.003, 0.0])
    skirt = tube_skirt(1.0, n_rows=4, n_cols=4)
    x0, _, _ = _offset_skirt(skirt, 0.0)
    assert max(seam_side_distance(skirt, x0).values()) < 1e-9
    # give the front's side of seam side_left its own ids, then move one of them 4 mm
    seam = skirt.seams[0]
    assert (seam.name, seam.panel_b) == ("side_left", "front")
    front = skirt.panel("front")
    old = front.vertex_ids[seam.verts_b].copy()
    new = len(x0) + np.arange(len(old))
    front.vertex_ids[seam.verts_b] = new
    x = np.concatenate([x0, x0[old]])
    assert seam_side_distance(skirt, x)["side_left"] < 1e-9
    x[new[2]] += [0.0, 0.0, 0.004]  # along the seam line: the polyline distance is smaller
    x[new[1]] += [0.004, 0.0, 0.0]  # off the seam line (the side is the plane x = -r)
    assert seam_side_distance(skirt, x)["side_left"] == pytest.approx(0.004, abs=1e-4)


def test_looser_pattern_has_larger_gap(body):
    gaps = []
    for ease in (1.05, 1.3):
        skirt = tube_skirt(ease, n_rows=8, n_cols=12)
        result = drape(skirt, *body, options={"max_frames": 60})
        m = drape_metrics(result, *body, pattern=skirt)
        gaps.append(m["all"]["gap_mm"]["mean"])
        assert m["all"]["penetration_pct"] == 0.0
        assert m["all"]["seam_gap_mm"]["max"] < 1.0 and m["all"]["seam_gap_mm"]["max_side"] < 1.0
        assert m["garments"]["skirt"]["gap_mm"]["n"] > 0
        assert m["vertex_gap"].shape == result.positions.shape[:1]
        assert m["body_gap"].shape == body[0].shape[:1]
        s = summary(m)
        assert "vertex_gap" not in s and "body_gap" not in s
    assert gaps[1] > gaps[0] + 5.0  # mm
    # the analytic lower bound: at least the contact thickness on the covered body
    assert gaps[0] > 1.0


def test_radius_profile_is_cylindrical_at_the_hips():
    z = np.linspace(0.6, 0.95, 20)
    assert np.allclose(radius(z), HIP_RADIUS)


def _sheet(n=24, size=0.2):
    g = np.linspace(0.0, size, n + 1)
    u, v = np.meshgrid(g, g, indexing="ij")
    faces = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, i * (n + 1) + j + 1
            faces += [[a, b, c], [a, c, d]]
    return u.ravel(), v.ravel(), np.asarray(faces)


def test_fold_measures_flat_cylinder_and_crease():
    from core.metrics.drape import fold_measures

    u, v, f = _sheet()
    flat = fold_measures(np.column_stack([u, v, np.zeros_like(u)]), f)
    assert flat["mean_dihedral_deg"] == pytest.approx(0.0, abs=1e-9) and flat["edges_over_30_pct"] == 0.0
    assert flat["mean_curvature_per_m"] == pytest.approx(0.0, abs=1e-9)
    # rolled round a cylinder of radius R: mean curvature 1 / (2 R), nothing folded
    R = 0.08
    cyl = np.column_stack([R * np.sin(u / R), v, R * (1 - np.cos(u / R))])
    m = fold_measures(cyl, f)
    assert m["mean_curvature_per_m"] == pytest.approx(1.0 / (2 * R), rel=0.05)
    assert m["edges_over_30_pct"] == 0.0 and 0.0 < m["mean_dihedral_deg"] < 10.0
    # folded sharply at u = 0.1 (90 degrees): the crease edges (one row of 24 of the 1680) are over 30
    crease = np.column_stack([np.minimum(u, 0.1), v, np.maximum(u - 0.1, 0.0)])
    c = fold_measures(crease, f)
    assert c["edges"] == 1680
    assert c["edges_over_30_pct"] == pytest.approx(100.0 * 24 / 1680)
    # the crease bends 90 degrees over 0.2 m of edge: sum |theta| |e| / (2 A) = (pi/2) 0.2 / (2 * 0.04)
    assert c["mean_curvature_per_m"] == pytest.approx(np.pi / 2 * 0.2 / 0.08, rel=1e-6)


def test_drape_report_has_fold_measures(body):
    skirt = tube_skirt(1.2, n_rows=8, n_cols=8)
    res = drape(skirt, *body, options={"max_frames": 15})
    m = summary(drape_metrics(res, *body, pattern=skirt))
    for scope in (m["all"], m["garments"]["skirt"]):
        assert set(scope["folds"]) == {"mean_dihedral_deg", "edges_over_30_pct", "mean_curvature_per_m", "edges"}
        assert scope["folds"]["edges"] > 0 and scope["folds"]["mean_curvature_per_m"] > 0
