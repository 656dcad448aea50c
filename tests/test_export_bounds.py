"""Bounds before work in `ease export` (issue 15): every numeric option and design field checked against its range,
drape positions that would make an invalid file, unknown --format entries. Each case runs the CLI in-process
(core.cli.main) and must end with exit status 2, one stderr line naming the option or field, no traceback, and
no output folder."""

import json
import math

import numpy as np
import pytest
from conftest import sample
from export_synth import drape_positions, make_pattern

import core.cli
from core.pattern.io import save_pattern

# generated: a log grid below the 5 mm minimum and above the 10 m maximum, negatives, non-numbers
BAD_NOTCH = (
    [f"{v:.3g}" for v in np.logspace(-300, math.log10(0.00499), 60)]
    + [f"{-v:.3g}" for v in np.logspace(-9, 3, 20)]
    + [f"{v:.4g}" for v in np.logspace(math.log10(10.5), 308, 20)]
    + ["nan", "inf", "-inf", "abc", "", "0x10", "5e-3j", "1,5", "0.1m"]
)
BAD_WIDTH = (
    [f"{v:.4g}" for v in np.logspace(-1 + 1e-3, 308, 25)]
    + [f"{-v:.3g}" for v in np.logspace(-9, 2, 15)]
    + ["nan", "inf", "-inf", "abc", "", "1e-9j", "1cm"]
)
GOOD_NOTCH = ["0", "0.005", "0.05", "0.1", "10"]
FORMATS_BAD = ["all,bogus", "bogus,all", "svg,pdff", "SVG,xyz", "glb,,dxf2", "all,all,none", "pdf;svg", ",", " "]
BAD_POSITIONS = [1e308, -1e308, 1e300, 1e4, -2e3, np.inf, -np.inf, np.nan]
FIELD_BAD = [1e-9, 1e-6, -1.0, 11.0, "x", None, [0.1], {"a": 1}, True, 1e308]


@pytest.fixture(scope="module")
def pattern_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("bounds")
    pat = make_pattern()
    save_pattern(pat, root / "pattern")
    return root, pat


def _refused(capsys, argv, out, *names):
    code = core.cli.main(argv)
    err = capsys.readouterr().err
    lines = [l for l in err.splitlines() if l.strip()]
    assert code == 2, (argv, err)
    assert len(lines) == 1 and "Traceback" not in err, err
    assert all(n in lines[0] for n in names), lines[0]
    assert not out.exists()
    return lines[0]


@pytest.mark.parametrize("value", BAD_NOTCH)
def test_notch_spacing_out_of_range_is_refused(pattern_dir, capsys, value, tmp_path):
    root, _ = pattern_dir
    _refused(
        capsys,
        ["export", str(root / "pattern"), "--format", "svg", "--out", str(tmp_path / "o"), f"--notch-spacing={value}"],
        tmp_path / "o",
        "--notch-spacing",
    )


@pytest.mark.parametrize("option", ["--allowance", "--hem"])
@pytest.mark.parametrize("value", BAD_WIDTH)
def test_allowance_out_of_range_is_refused(pattern_dir, capsys, option, value, tmp_path):
    root, _ = pattern_dir
    _refused(
        capsys,
        ["export", str(root / "pattern"), "--format", "svg", "--out", str(tmp_path / "o"), f"{option}={value}"],
        tmp_path / "o",
        option,
    )


@pytest.mark.parametrize("value", FORMATS_BAD)
def test_unknown_format_entries_are_refused(pattern_dir, capsys, value, tmp_path):
    root, _ = pattern_dir
    _refused(
        capsys,
        ["export", str(root / "pattern"), "--format", value, "--out", str(tmp_path / "o")],
        tmp_path / "o",
        "format",
    )


@pytest.mark.parametrize("value", ["x", "Y", "up", "", "-z"])
def test_up_axis_is_checked(pattern_dir, capsys, value, tmp_path):
    root, _ = pattern_dir
    _refused(
        capsys,
        ["export", str(root / "pattern"), "--format", "svg", "--out", str(tmp_path / "o"), f"--up={value}"],
        tmp_path / "o",
        "--up",
    )


@pytest.mark.parametrize("value", sample(FIELD_BAD, 4), ids=repr)
def test_design_notch_spacing_field_is_checked(capsys, value, tmp_path):
    pat = make_pattern()
    pat.materials = {"export": {"notch_spacing": value}}
    save_pattern(pat, tmp_path / "pattern")
    # the field as it reads back (save_pattern may normalise it): still out of range, refused by its name
    if json.loads((tmp_path / "pattern" / "pattern.json").read_text()).get("materials", {}).get("export", {}).get(
        "notch_spacing", 0.1
    ) in (0.1, None):
        pytest.skip("the pattern file does not keep this value")
    _refused(
        capsys,
        ["export", str(tmp_path / "pattern"), "--format", "svg", "--out", str(tmp_path / "o")],
        tmp_path / "o",
        "notch_spacing",
    )


@pytest.mark.parametrize("case", sample([(v, w) for v in BAD_POSITIONS for w in ("first", "last", "all")], 6), ids=repr)
def test_absurd_drape_positions_never_write_a_file(pattern_dir, capsys, case, tmp_path):
    value, where = case
    root, pat = pattern_dir
    pos = drape_positions(pat)
    k = {"first": [0], "last": [len(pos) - 1], "all": slice(None)}[where]
    pos[k, 2] = value
    drape = tmp_path / "drape"
    drape.mkdir()
    np.savez(drape / "drape.npz", positions=pos)
    line = _refused(
        capsys,
        ["export", str(root / "pattern"), "--format", "glb,obj", "--drape", str(drape), "--out", str(tmp_path / "o")],
        tmp_path / "o",
        "drape.positions",
    )
    assert "vertex" in line


@pytest.mark.parametrize("value", sample(GOOD_NOTCH, 3))
def test_notch_spacing_in_range_exports(pattern_dir, capsys, value, tmp_path):
    root, _ = pattern_dir
    assert (
        core.cli.main(
            [
                "export",
                str(root / "pattern"),
                "--format",
                "svg",
                "--out",
                str(tmp_path / "o"),
                "--notch-spacing",
                value,
                "--quiet",
            ]
        )
        == 0
    )
    summary = json.loads((tmp_path / "o" / "export.json").read_text())
    counts = [sum(len(v) for v in p["notches_mm"].values()) for p in summary["pieces"]]
    v = float(value)
    # bounded: the seam ends plus at most one notch per spacing along the longest seam (0.6 m sides)
    assert all(c <= 2 * (2 + (0 if v == 0 else math.ceil(0.7 / v))) for c in counts)


def test_glb_writer_refuses_non_finite_json():
    from core.export import mesh
    from core.export.pieces import build_pieces

    pat = make_pattern()
    pos = drape_positions(pat)
    pos[0] = 1e308  # float32 overflow: inf in the accessor min/max
    with np.errstate(all="ignore"):
        meshes = mesh.piece_meshes(pat, pos, [p.rotation for p in build_pieces(pat)])
        with pytest.raises(ValueError):
            mesh.glb_bytes(meshes)
