"""Bodies from scans (``core.body.scan``, ``ease body --scan``): reading OBJ/PLY point clouds,
the point-to-triangle distance, and fits to synthetic scans of hidden bodies (shape, local
changes and pose hidden; points resampled off the vertices, noise, holes, turned and moved)."""

import numpy as np
import pytest
from conftest import sample

from core.body.made_to_measure import sample_body
from core.body.scan import (
    MIN_POINTS,
    fit_scan,
    hidden_pose,
    point_triangle_distance,
    read_scan,
    scan_distance,
    scan_girths,
    synthetic_scan,
    write_points,
)
from core.body.tape import LENGTHS, TAPE_MEASURES, tape_measures
from core.errors import BodyError
from core.geom.frame import from_frame

GIRTHS = [m for m in TAPE_MEASURES if m not in LENGTHS]


def test_point_triangle_distance_regions():
    """Each of Ericson's regions: over the face, beyond each edge, beyond each vertex."""
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    cases = [
        ((0.2, 0.2, 0.5), 0.5),  # over the face
        ((0.5, -1.0, 0.0), 1.0),  # beyond edge ab
        ((-2.0, 0.5, 0.0), 2.0),  # beyond edge ac
        ((1.0, 1.0, 0.0), np.sqrt(0.5)),  # beyond edge bc
        ((-1.0, -1.0, 0.0), np.sqrt(2.0)),  # beyond a
        ((2.0, -1.0, 1.0), np.sqrt(3.0)),  # beyond b
        ((0.0, 3.0, 0.0), 2.0),  # beyond c
    ]
    p = np.array([q for q, _ in cases])
    n = len(p)
    got = point_triangle_distance(p, np.tile(a, (n, 1)), np.tile(b, (n, 1)), np.tile(c, (n, 1)))
    np.testing.assert_allclose(got, [d for _, d in cases], atol=1e-12)


def test_scan_distance_of_points_on_and_off_the_body(anny, anny_reference):
    v = anny_reference[0]
    tri = v[anny.faces[::50]]
    on = tri.mean(axis=1)  # centroids: on the surface, at no vertex
    np.testing.assert_allclose(scan_distance(on, v, anny.faces), 0.0, atol=1e-9)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    # 1 mm off along the face normal: 1 mm away (a nearer face elsewhere can only make it less)
    d = scan_distance(on + 0.001 * n, v, anny.faces)
    assert np.all(d <= 0.001 + 1e-9) and np.median(d) > 0.00099


@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_read_scan_files_units_and_up(tmp_path, suffix):
    rng = np.random.default_rng(1)
    pts = rng.uniform([-0.3, -0.2, 0.0], [0.3, 0.2, 1.7], (MIN_POINTS, 3))
    write_points(tmp_path / f"s{suffix}", pts)
    np.testing.assert_allclose(read_scan(tmp_path / f"s{suffix}"), pts, atol=1e-5)
    # millimetres, Y up: read back as metres, Z up
    yup = np.stack([pts[:, 0], pts[:, 2], -pts[:, 1]], axis=1) * 1000.0
    write_points(tmp_path / f"mm{suffix}", yup)
    np.testing.assert_allclose(read_scan(tmp_path / f"mm{suffix}", up="y"), pts, atol=1e-5)
    np.testing.assert_allclose(read_scan(tmp_path / f"mm{suffix}", up="y", units="mm"), pts, atol=1e-5)


def test_read_scan_ascii_ply_with_extra_properties_and_faces(tmp_path):
    rng = np.random.default_rng(2)
    pts = rng.uniform([-0.3, -0.2, 0.0], [0.3, 0.2, 1.7], (MIN_POINTS, 3))
    head = f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\nproperty float nx\nproperty float x\n"
    head += "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
    rows = "".join(f"0.5 {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in pts) + "3 0 1 2\n"
    (tmp_path / "a.ply").write_text(head + rows)
    np.testing.assert_allclose(read_scan(tmp_path / "a.ply"), pts, atol=1e-6)


def test_bad_scans_exit_2_with_one_line(tmp_path, capsys):
    from core.cli import main

    rng = np.random.default_rng(3)
    pts = rng.uniform([-0.3, -0.2, 0.0], [0.3, 0.2, 1.7], (MIN_POINTS, 3))
    write_points(tmp_path / "few.ply", pts[:100])
    nan = pts.copy()
    nan[7, 1] = np.nan
    write_points(tmp_path / "nan.obj", nan)
    (tmp_path / "junk.ply").write_bytes(b"\x00\x01 not a ply")
    (tmp_path / "words.obj").write_text("v 1 2 three\n")
    write_points(tmp_path / "flat.ply", pts * np.array([1.0, 1.0, 0.0]))
    (tmp_path / "scan.stl").write_text("solid x\n")
    for name, words in (
        ("missing.ply", "missing.ply: cannot read the scan"),
        ("few.ply", f"few.ply: 100 points; a scan needs at least {MIN_POINTS}"),
        ("nan.obj", f"nan.obj: point 8 of {MIN_POINTS} is not finite"),
        ("junk.ply", "junk.ply: not a PLY file"),
        ("words.obj", "words.obj:1: vertex is not three numbers"),
        ("flat.ply", "flat.ply: the scan is 0 high along Z"),
        ("scan.stl", "a scan must be .obj or .ply"),
    ):
        rc = main(["body", "--scan", str(tmp_path / name), "--out", str(tmp_path / "x.obj"), "--quiet"])
        err = capsys.readouterr().err
        assert rc == 2 and words in err and len(err.strip().splitlines()) == 1, (name, err)
    with pytest.raises(BodyError, match="expected at least"):
        fit_scan(None, pts[:10])


def _check_fit(anny, seed, points, fit_points, rounds):
    rng = np.random.default_rng([33, seed])
    shape, pose = sample_body(rng), hidden_pose(rng)
    scan = synthetic_scan(anny, shape, pose, rng, points=points)
    fit = fit_scan(anny, scan, fit_points=fit_points, rounds=rounds)
    hidden = tape_measures(anny, shape=shape)
    errors = {m: fit.body_cm[m] - hidden[m] for m in GIRTHS}
    assert fit.distance_mm["mean"] <= 5.0, fit.summary()
    assert all(abs(e) <= 1.5 for e in errors.values()), errors
    return fit, scan


def test_fit_synthetic_scan_ci(anny, tmp_path, capsys):
    """``ease body --scan`` on a small scan (2,500 points in millimetres, 2 mm noise, four holes,
    no soles, turned and moved) of a hidden body: mean distance <= 5 mm, every girth of the body
    it prints within 1.5 cm of the hidden body's, and the body written where the scan is."""
    import json

    from core.cli import main

    rng = np.random.default_rng([33, 0])
    shape, pose = sample_body(rng), hidden_pose(rng)
    scan = synthetic_scan(anny, shape, pose, rng, points=2500)
    write_points(tmp_path / "scan.ply", scan * 1000.0)  # millimetres, read back by the height
    rc = main(["body", "--scan", str(tmp_path / "scan.ply"), "--out", str(tmp_path / "me.obj"), "--quiet"])
    out = capsys.readouterr().out
    assert rc == 0 and "scan to body: mean" in out, out
    mean = float(out.split("scan to body: mean ", 1)[1].split(" mm", 1)[0])
    fitted = json.loads(out.split("design body: ", 1)[1].splitlines()[0])
    hidden, got = tape_measures(anny, shape=shape), tape_measures(anny, shape=fitted["shape"])
    errors = {m: got[m] - hidden[m] for m in GIRTHS}
    assert mean <= 5.0 and all(abs(e) <= 1.5 for e in errors.values()), (mean, errors)
    written = np.array(
        [[float(c) for c in ln.split()[1:4]] for ln in (tmp_path / "me.obj").read_text().splitlines() if ln[:2] == "v "]
    )
    written = from_frame(written, "y")  # the OBJ is Y-up by default (ease body --out-up)
    assert np.mean(scan_distance(scan, written, anny.faces)) * 1000 == pytest.approx(mean, abs=0.06)


@pytest.mark.parametrize("seed", sample(range(1, 7), 0))
def test_fit_synthetic_scan_larger(anny, seed):
    """Larger scans (20,000 points, the fit on 4,000): the targets, and the scan's own girths,
    taken on its points at the fitted body's levels, within 2 cm of the hidden body's."""
    fit, _ = _check_fit(anny, seed, 20000, 4000, 30)
    rng = np.random.default_rng([33, seed])
    hidden = tape_measures(anny, shape=sample_body(rng))
    taken = {m: v for m, v in fit.scan_cm.items() if v is not None and m != "height"}
    assert len(taken) >= 4, fit.scan_cm
    assert all(abs(v - hidden[m]) <= 2.0 for m, v in taken.items()), (taken, hidden)


def test_scan_neck_and_arm_girths_need_a_dense_scan(anny):
    """The scan's own neck, upper-arm and wrist girths, each in its tilted plane on the body in the
    scan's pose (core.body.tape.limb_plane): on a scan of 100,000 points (2 mm noise, holes) within
    1 cm of the hidden body's own; on 4,000 points too few lie within 6 mm of those small loops and
    none is taken (printed "-"), never a girth of a few points."""
    rng = np.random.default_rng(2)
    shape, pose = sample_body(rng), hidden_pose(rng)
    v, joints = anny.vertices_and_joints(shape, pose)
    limbs = ("neck", "upper_arm", "wrist")
    hidden = tape_measures(anny, v, limbs, shape=shape, joints=joints)
    dense = scan_girths(anny, shape, pose, synthetic_scan(anny, shape, pose, rng, points=100000, yaw=0.0, shift=0))
    assert all(dense[m] is not None and abs(dense[m] - hidden[m]) <= 1.0 for m in limbs), (dense, hidden)
    sparse = scan_girths(anny, shape, pose, synthetic_scan(anny, shape, pose, rng, points=4000, yaw=0.0, shift=0))
    assert all(sparse[m] is None for m in limbs), sparse
