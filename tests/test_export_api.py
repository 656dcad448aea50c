"""core.export.export_pattern: all formats, atomic output, failures before any file is written."""

import json
import sys

import numpy as np
import pytest
from export_synth import ALL_EXPORT_FILES, drape_positions, make_pattern

from core.errors import Cancelled, ExportError
from core.export import FORMATS, export_pattern, parse_formats

ALL_FILES = ALL_EXPORT_FILES


def test_exports_every_format(tmp_path):
    pat = make_pattern()
    calls = []
    files = export_pattern(
        pat,
        tmp_path / "out",
        formats="all",
        drape_positions=drape_positions(pat),
        progress=lambda f, m: calls.append(f),
    )
    assert {f.name for f in files} == ALL_FILES
    assert {f.name for f in (tmp_path / "out").iterdir()} == ALL_FILES
    assert calls and calls[-1] == 1.0 and calls == sorted(calls)
    summary = json.loads((tmp_path / "out" / "export.json").read_text())
    assert [p["name"] for p in summary["pieces"]] == ["front", "back"]
    for paper in ("a4", "letter"):
        info = summary["pdf"][paper]
        assert info["pages"] + len(info["left_out"]) == info["rows"] * info["columns"]
    assert summary["pieces"][0]["notches_mm"]["side_left"] == summary["pieces"][1]["notches_mm"]["side_left"]


def test_same_input_same_bytes(tmp_path):
    pat = make_pattern()
    a = export_pattern(pat, tmp_path / "a", formats="svg,dxf,pdf")
    b = export_pattern(pat, tmp_path / "b", formats="svg,dxf,pdf")
    for fa, fb in zip(a, b):
        assert fa.read_bytes() == fb.read_bytes(), fa.name


def test_allowance_from_the_design_materials(tmp_path):
    pat = make_pattern()
    pat.materials = {"export": {"allowance": {"default": 0.015, "hem": 0.03}, "notch_spacing": 0.2}}
    export_pattern(pat, tmp_path, formats="svg")
    s = json.loads((tmp_path / "export.json").read_text())
    assert s["allowance_mm"]["default"] == 15 and s["pieces"][0]["allowance_mm"] == [15, 30]
    assert s["pieces"][0]["notches_mm"]["side_left"][1] == 200


@pytest.mark.parametrize(
    "kwargs,words",
    [
        ({"formats": "svg,tiff"}, "tiff"),
        ({"formats": "glb"}, "drape"),
        ({"allowance": {"sidee": 0.01}}, "sidee"),
        ({"allowance": {"hem": 1.0}}, "hem"),
    ],
)
def test_bad_arguments_fail_before_writing(tmp_path, kwargs, words):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("old")
    with pytest.raises(ExportError, match=words):
        export_pattern(make_pattern(), out, **kwargs)
    assert [f.name for f in out.iterdir()] == ["keep.txt"]


def test_invalid_pattern_writes_nothing(tmp_path):
    pat = make_pattern()
    pat.panel("front").uv[0, 0] = np.nan
    with pytest.raises(ExportError, match="front"):
        export_pattern(pat, tmp_path / "out", formats="all", drape_positions=drape_positions(make_pattern()))
    assert not (tmp_path / "out").exists()
    assert not list(tmp_path.iterdir())  # no temporary folder left either


def test_cancel_leaves_previous_output(tmp_path):
    pat = make_pattern()
    export_pattern(pat, tmp_path, formats="svg")
    before = (tmp_path / "pattern.svg").read_bytes()

    def stop(fraction, message):
        if "PDF" in message:
            raise Cancelled()

    pat.style = "changed"
    with pytest.raises(Cancelled):
        export_pattern(pat, tmp_path, formats="svg,pdf", progress=stop)
    assert (tmp_path / "pattern.svg").read_bytes() == before
    assert not (tmp_path / "pattern_a4.pdf").exists()


def test_parse_formats():
    assert parse_formats("SVG, dxf,svg") == ["svg", "dxf"]
    assert parse_formats("all") == list(FORMATS)
    with pytest.raises(ExportError):
        parse_formats("")


def test_lenient_export_of_a_tangled_piece_lists_warnings(tmp_path):
    pat = make_pattern()
    uv = pat.panel("front").uv
    loop = pat.panel("front").boundary[0]
    uv[loop[2]], uv[loop[20]] = uv[loop[20]].copy(), uv[loop[2]].copy()
    with pytest.raises(ExportError, match="crosses itself"):
        export_pattern(pat, tmp_path / "strict", formats="svg")
    assert not (tmp_path / "strict").exists()
    found = []
    files = export_pattern(pat, tmp_path / "lenient", formats="svg,dxf", strict=False, warnings=found)
    assert found and all("front" in w for w in found)
    summary = json.loads((tmp_path / "lenient" / "export.json").read_text())
    assert summary["warnings"] == found
    assert {f.name for f in files} >= {"pattern.svg", "pattern_astm.dxf"}


@pytest.mark.parametrize("fmt,module", [("dxf", "ezdxf"), ("pdf", "reportlab.pdfgen")])
def test_missing_writer_package_is_a_clear_error(tmp_path, monkeypatch, fmt, module):
    monkeypatch.setitem(sys.modules, module, None)  # import now fails, as in a bare Blender
    with pytest.raises(ExportError, match=module.split(".")[0]):
        export_pattern(make_pattern(), tmp_path / "out", formats=f"svg,{fmt}")
    assert not (tmp_path / "out").exists()


def test_a_piece_wider_than_the_page_grid_exports(tmp_path):
    """The ease-3.0 shirt front is 1.58 m wide: every format still exports it (it raised a TypeError in PDF)."""
    from export_synth import wide_pattern

    files = export_pattern(wide_pattern(1.6), tmp_path / "out", formats="svg,dxf,pdf")
    summary = json.loads((tmp_path / "out" / "export.json").read_text())
    assert summary["pdf"]["a4"]["pages"] >= 8 and "pattern_a4.pdf" in {f.name for f in files}
