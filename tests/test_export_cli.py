"""core.cli.export: `ease export PATTERN_DIR --format ... --out DIR [--drape DIR]`."""

import argparse

import numpy as np
import pytest
from export_synth import ALL_EXPORT_FILES, drape_positions, make_pattern  # noqa: E402

from core.cli import export as cli  # noqa: E402
from core.errors import EaseError  # noqa: E402
from core.pattern.io import save_pattern  # noqa: E402


def run(argv):
    """Like core.cli.main, with only the export subcommand (the other stages are not needed)."""
    parser = argparse.ArgumentParser(prog="ease")
    cli.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except EaseError as exc:
        return str(exc)


@pytest.fixture()
def job(tmp_path):
    pat = make_pattern()
    save_pattern(pat, tmp_path / "pattern")
    return tmp_path, pat


def test_export_2d_formats(job, capsys):
    root, pat = job
    assert (
        run(
            [
                "export",
                str(root / "pattern"),
                "--format",
                "svg,dxf",
                "--out",
                str(root / "x"),
                "--allowance",
                "0.012",
                "--hem",
                "0.03",
                "--quiet",
            ]
        )
        == 0
    )
    names = sorted(p.name for p in (root / "x").iterdir())
    assert names == ["export.json", "pattern.svg", "pattern_astm.dxf", "pattern_astm_r12.dxf", "pattern_plain.dxf"]
    assert "pattern.svg" in capsys.readouterr().out
    import json

    s = json.loads((root / "x" / "export.json").read_text())
    assert s["allowance_mm"]["default"] == 12 and s["allowance_mm"]["hem"] == 30


def test_glb_needs_a_drape(job):
    root, pat = job
    msg = run(["export", str(root / "pattern"), "--format", "glb", "--out", str(root / "x"), "--quiet"])
    assert isinstance(msg, str) and "--drape" in msg
    assert not (root / "x").exists()


def test_drape_found_next_to_the_pattern(job):
    root, pat = job
    (root / "drape").mkdir()
    np.savez(root / "drape" / "drape.npz", positions=drape_positions(pat), faces=np.zeros((0, 3), int))
    # default formats: 2D files plus the garment, since a drape is there
    assert run(["export", str(root / "pattern"), "--out", str(root / "x"), "--quiet"]) == 0
    names = {p.name for p in (root / "x").iterdir()}
    assert {"garment.glb", "garment.obj", "pattern_a4.pdf", "pattern.svg", "pattern_astm.dxf"} <= names


ALL = ALL_EXPORT_FILES


@pytest.mark.parametrize("fmt", ["svg,dxf,pdf,glb,obj", "all", "SVG, dxf,pdf,glb,obj,svg"])
def test_every_format_by_list_or_all(job, tmp_path, fmt):
    root, pat = job
    d = tmp_path / "drape_elsewhere"
    d.mkdir()
    np.savez(d / "drape.npz", positions=drape_positions(pat))
    assert (
        run(["export", str(root / "pattern"), "--format", fmt, "--drape", str(d), "--out", str(root / "x"), "--quiet"])
        == 0
    )
    assert {p.name for p in (root / "x").iterdir()} == ALL


def test_ease_command_runs_export(job, tmp_path, capsys):
    """`ease export ...` through the real entry point (core.cli.main), drape found beside the pattern."""
    from core.cli import main

    root, pat = job
    (root / "drape").mkdir()
    np.savez(root / "drape" / "drape.npz", positions=drape_positions(pat))
    assert main(["export", str(root / "pattern"), "--format", "all", "--out", str(root / "x"), "--quiet"]) == 0
    assert {p.name for p in (root / "x").iterdir()} == ALL
    assert main(["export", str(root / "pattern"), "--format", "tiff", "--out", str(root / "y")]) != 0
    assert "tiff" in capsys.readouterr().err and not (root / "y").exists()


def test_drape_of_another_pattern_is_refused(job, tmp_path):
    root, pat = job
    d = tmp_path / "other"
    d.mkdir()
    faces = np.concatenate([p.vertex_ids[p.faces] for p in pat.panels])
    np.savez(d / "drape.npz", positions=drape_positions(pat), faces=faces[::2])
    msg = run(["export", str(root / "pattern"), "--format", "glb", "--drape", str(d), "--out", str(root / "x")])
    assert isinstance(msg, str) and "another pattern" in msg and not (root / "x").exists()
    np.savez(d / "drape.npz", positions=drape_positions(pat), faces=faces)
    assert (
        run(
            ["export", str(root / "pattern"), "--format", "glb", "--drape", str(d), "--out", str(root / "x"), "--quiet"]
        )
        == 0
    )


@pytest.mark.parametrize("fmt", ["all", "svg,obj"])
def test_3d_formats_without_a_drape_fail_clearly(job, fmt):
    root, pat = job
    msg = run(["export", str(root / "pattern"), "--format", fmt, "--out", str(root / "x"), "--quiet"])
    assert isinstance(msg, str) and "needs the draped garment" in msg and "--drape" in msg
    assert not (root / "x").exists()


def test_unknown_format_names_it(job):
    root, _ = job
    msg = run(["export", str(root / "pattern"), "--format", "svg,png", "--out", str(root / "x"), "--quiet"])
    assert isinstance(msg, str) and "'png'" in msg and "all" in msg
    assert not (root / "x").exists()


def test_explicit_drape_dir_and_bad_npz(job, tmp_path):
    root, pat = job
    d = tmp_path / "elsewhere"
    d.mkdir()
    np.savez(d / "drape.npz", wrong=np.zeros(3))
    msg = run(["export", str(root / "pattern"), "--format", "obj", "--drape", str(d), "--out", str(root / "x")])
    assert isinstance(msg, str) and "positions" in msg
    np.savez(d / "drape.npz", positions=drape_positions(pat))
    assert (
        run(
            ["export", str(root / "pattern"), "--format", "obj", "--drape", str(d), "--out", str(root / "x"), "--quiet"]
        )
        == 0
    )
    assert (root / "x" / "garment.obj").is_file()


def test_missing_pattern_and_help(tmp_path, capsys):
    msg = run(["export", str(tmp_path / "nothing"), "--out", str(tmp_path / "x")])
    assert isinstance(msg, str) and "pattern" in msg
    with pytest.raises(SystemExit):
        run(["export", "--help"])
    assert "ASTM" in capsys.readouterr().out


def test_with_body_and_up_axis(job, anny):
    """--with-body writes the pattern's body (Anny, size M, A-pose) beside the garment; --up picks the OBJ frame."""
    from core.body.instance import spec_instance

    root, pat = job
    drape = root / "drape"
    drape.mkdir()
    np.savez(drape / "drape.npz", positions=drape_positions(pat))
    V, F = spec_instance(pat.body, anny)
    for up in ("z", "y"):
        out = root / f"x_{up}"
        assert (
            run(
                [
                    "export",
                    str(root / "pattern"),
                    "--format",
                    "obj,glb",
                    "--drape",
                    str(drape),
                    "--out",
                    str(out),
                    "--with-body",
                    "--up",
                    up,
                    "--origin",
                    "root",
                    "--quiet",
                ]
            )
            == 0
        )
        text = (out / "garment.obj").read_text()
        assert ("+Z up" in text.splitlines()[1]) == (up == "z")
        body = text.split("o body\n", 1)[1].splitlines()
        v = np.array([[float(t) for t in l.split()[1:]] for l in body if l.startswith("v ")])
        want = V if up == "z" else np.column_stack([V[:, 0], V[:, 2], -V[:, 1]])
        np.testing.assert_allclose(v, want, atol=2e-6)
        assert sum(1 for l in body if l.startswith("f ")) == len(F)
        from core.export.mesh import read_glb

        doc, _ = read_glb((out / "garment.glb").read_bytes())
        assert "body" in [n["name"] for n in doc["nodes"]] and "+Y up" in doc["asset"]["extras"]["frame"]
    # the defaults: Y-up OBJ with its garment.mtl, and the body standing on the floor (its lowest point at 0)
    out = root / "x_default"
    assert (
        run(
            [
                "export",
                str(root / "pattern"),
                "--format",
                "obj,glb",
                "--drape",
                str(drape),
                "--out",
                str(out),
                "--with-body",
                "--quiet",
            ]
        )
        == 0
    )
    text = (out / "garment.obj").read_text()
    assert "+Y up" in text.splitlines()[1] and "origin on the floor" in text.splitlines()[1]
    assert "mtllib garment.mtl" in text and "usemtl fabric" in text and "usemtl body" in text
    mtl = (out / "garment.mtl").read_text()
    assert "newmtl fabric" in mtl and "newmtl body" in mtl
    body = text.split("o body\n", 1)[1].splitlines()
    v = np.array([[float(t) for t in l.split()[1:]] for l in body if l.startswith("v ")])
    np.testing.assert_allclose(v, np.column_stack([V[:, 0], V[:, 2] - V[:, 2].min(), -V[:, 1]]), atol=2e-6)
    assert v[:, 1].min() == pytest.approx(0.0, abs=1e-6)
    from core.export.mesh import glb_accessor

    doc, binary = read_glb((out / "garment.glb").read_bytes())
    node = next(n for n in doc["nodes"] if n["name"] == "body")
    pos = glb_accessor(doc, binary, doc["meshes"][node["mesh"]]["primitives"][0]["attributes"]["POSITION"])
    assert pos[:, 1].min() == pytest.approx(0.0, abs=1e-5) and "origin on the floor" in doc["asset"]["extras"]["frame"]
    import json

    assert json.loads((out / "export.json").read_text())["frame"]["origin"] == "floor"


def test_print_all_prints_every_piece_on_the_tiled_pdfs(tmp_path):
    """Default: a mirrored pair is printed once (cut 2); --print-all prints both pieces."""
    import json

    from export_synth import mirrored_pattern

    save_pattern(mirrored_pattern(), tmp_path / "pattern")
    for flag, want in (([], [("front_left", 2)]), (["--print-all"], [("front_left", 1), ("front_right", 1)])):
        out = tmp_path / ("x" + "".join(flag))
        assert run(["export", str(tmp_path / "pattern"), "--format", "pdf", "--out", str(out), "--quiet"] + flag) == 0
        s = json.loads((out / "export.json").read_text())
        assert [(p["piece"], p["quantity"]) for p in s["pdf"]["a4"]["pieces"]] == want
