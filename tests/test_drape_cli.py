"""``ease drape`` end to end on the synthetic skirt (core.cli.drape, core.workflows.drape)."""

import json

import numpy as np
import pytest
from drape_synth import tube_skirt

from core.cli import main
from core.drape.output import FILES, read_ply_vertices
from core.geom.frame import from_frame, to_y_up
from core.pattern.io import save_pattern


@pytest.fixture(scope="module")
def pattern_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("pattern")
    save_pattern(tube_skirt(1.2, n_rows=8, n_cols=10), d)
    return d


@pytest.fixture(scope="module")
def drape_dir(pattern_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("drape") / "out"
    assert main(["drape", str(pattern_dir), "--out", str(out), "--quiet", "--frames", "60"]) == 0
    return out


def test_writes_every_file(drape_dir):
    for name in FILES:
        assert (drape_dir / name).is_file() and (drape_dir / name).stat().st_size > 0, name
    assert (drape_dir / "preview.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report(drape_dir):
    rep = json.loads((drape_dir / "drape_report.json").read_text())
    assert rep["settle_reason"] in ("settled", "frame limit")
    assert rep["settled"] == (rep["settle_reason"] == "settled")
    assert rep["material"]["name"] == "cotton"
    assert set(rep["timings"]) >= {"simulate", "total"}
    assert rep["gap_mm"]["mean"] > 0 and rep["gap_mm"]["std"] >= 0
    assert rep["penetration_pct"] == 0.0
    assert rep["seam_gap_mm"]["max"] < 1.0
    assert rep["self_collision"] is False
    # the fold measures of every drape (overall and per garment)
    assert rep["folds"] == rep["metrics"]["all"]["folds"]
    assert rep["folds"]["edges"] > 0 and 0 < rep["folds"]["mean_dihedral_deg"] < 90
    assert all("folds" in g for g in rep["metrics"]["garments"].values())


def test_npz_obj_ply_agree(drape_dir):
    npz = np.load(drape_dir / "drape.npz")
    x, f = npz["positions"], npz["faces"]
    assert x.shape[1] == 3 and f.shape[1] == 3 and f.max() < len(x)
    obj = (drape_dir / "garment.obj").read_text().splitlines()
    v = np.array([[float(t) for t in line.split()[1:]] for line in obj if line.startswith("v ")])
    faces = np.array([[int(t) for t in line.split()[1:]] for line in obj if line.startswith("f ")]) - 1
    # garment.obj is Y-up by default ((x, z, -y) of the drape's core frame), its header says so
    assert np.allclose(from_frame(v, "y"), x, atol=1e-6) and np.allclose(v, to_y_up(x), atol=1e-6)
    assert any(line.startswith("# frame:") and "+Y up" in line for line in obj[:4])
    assert np.array_equal(np.sort(faces, axis=0), np.sort(f, axis=0))
    # its materials beside it
    assert "mtllib garment.mtl" in obj and "usemtl fabric" in obj
    assert "newmtl fabric" in (drape_dir / "garment.mtl").read_text()
    ply = read_ply_vertices(drape_dir / "garment.ply")
    assert set(ply) == {"x", "y", "z", "strain_weft", "strain_warp", "gap"}
    assert np.allclose(ply["x"], x[:, 0], atol=1e-6)
    assert np.allclose(ply["strain_weft"], npz["strain_weft"], atol=1e-6)
    assert np.allclose(ply["gap"], npz["gap"], atol=1e-6)
    assert ply["gap"].max() > 0.005  # the 1.2-ease skirt stands off the hips


def test_bad_material_writes_nothing(pattern_dir, tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["drape", str(pattern_dir), "--out", str(out), "--quiet", "--material", "chainmail"]) == 2
    assert "unknown material" in capsys.readouterr().err
    assert not out.exists()


def test_bad_frames(pattern_dir, tmp_path):
    assert main(["drape", str(pattern_dir), "--out", str(tmp_path / "x"), "--frames", "0"]) == 2


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["drape", "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "--material" in text and "--device" in text and "--frames" in text and "--self-collision" in text


def test_self_collision_flag(pattern_dir, tmp_path):
    out = tmp_path / "sc"
    assert (
        main(
            [
                "drape",
                str(pattern_dir),
                "--out",
                str(out),
                "--quiet",
                "--frames",
                "15",
                "--no-preview",
                "--self-collision",
            ]
        )
        == 0
    )
    rep = json.loads((out / "drape_report.json").read_text())
    assert rep["self_collision"] is True and rep["options"]["self_collision"] is True
    assert rep["self_radius_m"] > 0


def test_hold_pins_flag(pattern_dir, drape_dir, tmp_path):
    # the default lets an upper garment's pins go once grown; --hold-pins keeps them all (the report says which)
    assert json.loads((drape_dir / "drape_report.json").read_text())["options"]["hold_pins"] is False
    out = tmp_path / "held"
    args = ["drape", str(pattern_dir), "--out", str(out), "--quiet", "--frames", "5", "--no-preview", "--hold-pins"]
    assert main(args) == 0
    assert json.loads((out / "drape_report.json").read_text())["options"]["hold_pins"] is True


def test_divergence_names_frame_and_cause_and_writes_nothing(tmp_path, capsys):
    # a pattern a fifth of the body's girth is torn apart on the first frame
    d = tmp_path / "pattern"
    save_pattern(tube_skirt(0.2, n_rows=6, n_cols=8), d)
    out = tmp_path / "never"
    assert main(["drape", str(d), "--out", str(out), "--quiet", "--frames", "20"]) == 2
    err = capsys.readouterr().err
    assert "diverged at frame 1" in err and "likely cause" in err
    assert not out.exists()


def test_absurd_time_step_writes_nothing(pattern_dir, tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["drape", str(pattern_dir), "--out", str(out), "--quiet", "--substeps", "1"]) == 2
    assert "time step" in capsys.readouterr().err
    assert not out.exists()


def test_up_z_keeps_the_core_frame(pattern_dir, drape_dir, tmp_path, capsys):
    """``--up z``: garment.obj in the drape's own frame (drape.npz's positions, vertex for vertex);
    any other axis is refused before any work."""
    out = tmp_path / "z"
    argv = ["drape", str(pattern_dir), "--out", str(out), "--quiet", "--frames", "2", "--no-preview"]
    assert main(argv + ["--up", "z"]) == 0
    obj = (out / "garment.obj").read_text().splitlines()
    v = np.array([line.split()[1:] for line in obj if line.startswith("v ")], float)
    assert np.allclose(v, np.load(out / "drape.npz")["positions"], atol=1e-6)
    assert any(line.startswith("# frame:") and "+Z up" in line for line in obj[:4])
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:  # argparse's choices: exit 2, one line naming --up
        main(argv[:3] + [str(tmp_path / "x"), "--up", "x"])
    assert exc.value.code == 2 and "--up" in capsys.readouterr().err and not (tmp_path / "x").exists()
