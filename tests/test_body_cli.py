"""``ease body``: argument handling, errors that list what is allowed, atomic outputs."""

import argparse
import json

import numpy as np
import pytest
from smpl_synth import stick_smpl
from test_body_obj import horse, write_obj

from core.body.output import render_bodies
from core.cli import body as body_cli
from core.errors import BodyError
from core.geom.frame import from_frame


def ease_body(argv):
    """Parse and run ``ease body ARGV`` as core.cli does (errors propagate as exceptions)."""
    parser = argparse.ArgumentParser(prog="ease")
    body_cli.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["body", *argv, "--quiet"])
    return args.func(args)


@pytest.fixture
def stick(tmp_path):
    path = tmp_path / "stick.npz"
    np.savez(path, **stick_smpl(n_betas=3))
    return path


@pytest.fixture
def horse_obj(tmp_path):
    v, quads, _ = horse()
    write_obj(tmp_path / "horse.obj", v, quads)
    return tmp_path / "horse.obj"


def read_obj_vertices(path):
    return np.array(
        [[float(c) for c in line.split()[1:4]] for line in path.read_text().splitlines() if line.startswith("v ")]
    )


def test_writes_posed_smpl_body(stick, tmp_path, capsys):
    out = tmp_path / "out" / "b.obj"
    assert ease_body(["--model", str(stick), "--shape", "beta0=0.5", "--pose", "P2", "--out", str(out)]) == 0
    from core.body.smpl import load_smpl

    body = load_smpl(stick)
    want = body.vertices({"beta0": 0.5}, "P2")
    # Y-up by default, (x, z, -y) of the core frame: the header says so
    np.testing.assert_allclose(from_frame(read_obj_vertices(out), "y"), want, atol=2e-6)
    assert "# frame: metres, +Y up" in out.read_text()
    text = capsys.readouterr().out
    assert "height" in text and f"wrote {out}" in text
    # --out-up z: the core frame, as computed
    assert (
        ease_body(["--model", str(stick), "--shape", "beta0=0.5", "--pose", "P2", "--out", str(out), "--out-up", "z"])
        == 0
    )
    np.testing.assert_allclose(read_obj_vertices(out), want, atol=2e-6)
    assert "# frame: metres, +Z up" in out.read_text()


def test_out_up_is_the_written_file_up_is_the_read_one(horse_obj, tmp_path, capsys):
    """``--up`` is the axis of the OBJ model read, ``--out-up`` that of the OBJ written: a Y-up
    template read with ``--up y`` and written Z-up is the Z-up template's body."""
    from core.body.obj_model import load_obj_body

    ref = load_obj_body(horse_obj).vertices(None, None)
    out = tmp_path / "z.obj"
    assert ease_body(["--model", str(horse_obj), "--out", str(out), "--out-up", "z"]) == 0
    np.testing.assert_allclose(read_obj_vertices(out), ref, atol=2e-6)
    # the default output (Y-up) read back as a Y-up model gives the same body
    y = tmp_path / "y.obj"
    assert ease_body(["--model", str(horse_obj), "--out", str(y)]) == 0
    back = tmp_path / "back.obj"
    assert ease_body(["--model", str(y), "--up", "y", "--out", str(back), "--out-up", "z"]) == 0
    np.testing.assert_allclose(read_obj_vertices(back), ref, atol=2e-5)
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        ease_body(["--model", str(horse_obj), "--out", str(out), "--out-up", "x"])
    assert exc.value.code == 2 and "--out-up" in capsys.readouterr().err


def test_obj_model_reference_pose(horse_obj, tmp_path):
    out = tmp_path / "h.obj"
    assert ease_body(["--model", str(horse_obj), "--out", str(out)]) == 0
    assert len(read_obj_vertices(out)) == 48


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--pose", "Q"], "unknown pose; allowed: A, T, P1, P2, P3"),
        (["--shape", "beta9=1"], "shape.beta9: unknown shape parameter; allowed: beta0, beta1, beta2"),
        (["--shape", "beta0=7"], r"beta0=7 is out of range \[-5, 5\]"),
        (["--shape", "huge"], r"expected a size \(XS, S, M, L, XL\) or name=value pairs"),
        (["--measure", "neck=40"], "unknown measurement 'neck'; allowed: height, chest, waist, hip"),
        (["--measure", "chest=960"], "out of range"),
        (["--shape", "XL", "--measure", "chest=90"], "either --shape or --measure"),
    ],
)
def test_errors_list_what_is_allowed(stick, tmp_path, argv, message):
    out = tmp_path / "never.obj"
    with pytest.raises(BodyError, match=message):
        ease_body(["--model", str(stick), *argv, "--out", str(out)])
    assert not out.exists()


def test_bad_model_paths(tmp_path):
    with pytest.raises(BodyError, match="expected 'anny' or a path"):
        ease_body(["--model", str(tmp_path / "x.fbx"), "--out", str(tmp_path / "o.obj")])
    with pytest.raises(BodyError, match="not found"):
        ease_body(["--model", str(tmp_path / "missing.npz"), "--out", str(tmp_path / "o.obj")])


def test_missing_landmarks_still_report_height(stick, tmp_path, capsys):
    # The stick model has no landmarks: girths are skipped, height is reported.
    ease_body(["--model", str(stick), "--out", str(tmp_path / "s.obj")])
    assert "measured (A-pose): height" in capsys.readouterr().out


def test_render_bodies_png(tmp_path):
    from core.body.obj_model import load_obj_body

    v, quads, _ = horse()
    write_obj(tmp_path / "horse.obj", v, quads)
    body = load_obj_body(tmp_path / "horse.obj")
    path = render_bodies([[("a", body.vertices()), ("b", body.vertices() * 1.2)]], body.faces, tmp_path / "pic.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ease_main_reports_errors_with_exit_code(stick, tmp_path, capsys):
    from core.cli import build_parser, main

    build_parser()
    rc = main(["body", "--model", str(stick), "--pose", "sideways", "--out", str(tmp_path / "x.obj")])
    assert rc == 2
    assert "allowed: A, T, P1, P2, P3" in capsys.readouterr().err


@pytest.fixture(scope="module")
def anny_available():
    from core.body import load_body

    return load_body("anny")  # the baked asset is committed: a failure here is a real one


def test_all_writes_sizes_poses_and_picture(anny_available, tmp_path):
    out = tmp_path / "bodies"
    assert ease_body(["--all", "--out", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        [f"size_{s}.obj" for s in ("XS", "S", "M", "L", "XL")]
        + [f"pose_{p}.obj" for p in ("A", "T", "P1", "P2", "P3")]
        + ["bodies.png", "bodies.json"]
    )
    summary = json.loads((out / "bodies.json").read_text())
    chest = [summary["sizes"][s]["measured_cm"]["chest"] for s in ("XS", "S", "M", "L", "XL")]
    assert chest == sorted(chest)
    # every OBJ Y-up (the default): standing along +Y, the body's front towards +Z
    v = read_obj_vertices(out / "pose_A.obj")
    assert "+Y up" in (out / "pose_A.obj").read_text() and np.ptp(v[:, 1]) > 1.4 and np.ptp(v[:, 2]) < 0.6
    np.testing.assert_allclose(
        from_frame(v, "y"), anny_available.vertices(summary["sizes"]["M"]["shape"], "A"), atol=2e-6
    )


def test_measure_fits_anny(anny_available, tmp_path, capsys):
    from core.body.measure import measure

    # Targets measured on a known Anny shape are reachable by construction.
    m = measure(anny_available, anny_available.vertices({"weight": 0.7, "height": 0.6}))
    arg = ",".join(f"{k}={v:.1f}" for k, v in m.items())
    out = tmp_path / "me.obj"
    assert ease_body(["--measure", arg, "--pose", "P3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.count("within 1 cm") == 4, text
    assert len(read_obj_vertices(out)) == anny_available.n_vertices
    assert ease_body(["--measure", "chest=150,height=160", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "chest" in text and "not reachable by this model" in text
