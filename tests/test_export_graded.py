"""Graded nest (core.export.graded, `ease export DESIGN --sizes ...`): one AAMA block per piece per size
with the size in the block, the sizes of a piece stacked at its reference point, one colour per size."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from core.cli import main
from core.export.graded import SIZE_COLOURS, export_graded, graded_stacks, reference_point
from core.geom.polyline import polyline_length
from export_synth import make_pattern

SCALES = {"S": 0.95, "M": 1.0, "L": 1.06}


def _sizes():
    out = {}
    for size, f in SCALES.items():
        p = make_pattern()
        for panel in p.panels:
            panel.uv = panel.uv * f
        p.body = dict(p.body, size=size)
        out[size] = p
    return out


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    out = tmp_path_factory.mktemp("graded")
    return out, export_graded(_sizes(), out, title="test graded")


def test_stacks_aligned_at_the_reference_point():
    stacks = graded_stacks(_sizes())
    assert list(stacks) == ["front", "back"]
    for stack in stacks.values():
        assert list(stack) == list(SCALES)
        for d in stack.values():
            assert np.allclose(reference_point(d), 0.0, atol=1e-12)
            assert np.allclose(d.grain[:, 0], 0.0, atol=1e-9)      # grain lines on one line
        # the sizes really differ: the sew line grows with the scale
        lengths = [polyline_length(d.sew[0], closed=True) for d in stack.values()]
        assert np.allclose(np.array(lengths) / lengths[1], list(SCALES.values()), rtol=1e-9)


def test_one_block_per_piece_per_size(graded):
    import ezdxf
    out, files = graded
    assert sorted(f.name for f in files) == ["graded.json", "graded.pdf", "graded.svg", "graded_astm.dxf"]
    doc = ezdxf.readfile(out / "graded_astm.dxf")
    assert not doc.audit().has_errors
    blocks = {b.name: b for b in doc.blocks if not b.name.startswith("*")}
    assert sorted(blocks) == sorted(f"{p}_{s}" for p in ("front", "back") for s in SCALES)
    inserts = {}
    for ins in doc.modelspace().query("INSERT"):
        inserts[ins.dxf.name] = tuple(round(v, 6) for v in ins.dxf.insert)
    for piece in ("front", "back"):
        places = {inserts[f"{piece}_{s}"] for s in SCALES}
        assert len(places) == 1                                   # stacked: one insertion point
        mids = []
        for s in SCALES:
            texts = [e.dxf.text for e in blocks[f"{piece}_{s}"] if e.dxftype() == "TEXT"]
            assert f"Size: {s}" in texts and f"Piece Name: {piece}" in texts
            grain = [e for e in blocks[f"{piece}_{s}"] if e.dxftype() == "LINE" and e.dxf.layer == "7"][0]
            mids.append((np.array(grain.dxf.start)[:2] + np.array(grain.dxf.end)[:2]) / 2)
        assert np.allclose(mids, 0.0, atol=1e-6)                  # aligned at the grain line's middle


def test_svg_colours_and_legend(graded):
    out, _ = graded
    root = ET.fromstring((out / "graded.svg").read_text())
    ns = {"svg": "http://www.w3.org/2000/svg"}
    legend = root.find("svg:g[@id='legend']", ns)
    assert [t.text for t in legend.findall("svg:text", ns)] == list(SCALES)
    for piece in ("front", "back"):
        g = root.find(f"svg:g[@id='piece-{piece}']", ns)
        groups = g.findall("svg:g[@class='size']", ns)
        assert [x.get("data-size") for x in groups] == list(SCALES)
        colours = [x.find("svg:path[@class='cut']", ns).get("stroke") for x in groups]
        assert colours == list(SIZE_COLOURS[:len(SCALES)])
    summary = json.loads((out / "graded.json").read_text())
    assert summary["sizes"] == list(SCALES) and set(summary["pieces"]) == {"front", "back"}
    assert (out / "graded.pdf").read_bytes().startswith(b"%PDF")


def test_graded_cli_errors(tmp_path, capsys):
    """Bad --sizes and a pattern folder instead of a design: exit 2 and one line, nothing written."""
    from core.design.templates import template_path
    design = template_path("top_sleeveless")
    for target, sizes, words in ((design, "XS,XXL", "--sizes"), (design, "M,M", "--sizes"),
                                 (design, "women:XL", "S, M, L"),
                                 (tmp_path, "XS,M", "design JSON")):
        rc = main(["export", str(target), "--sizes", sizes, "--out", str(tmp_path / "g"), "--quiet"])
        err = capsys.readouterr().err
        assert rc == 2 and words in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "g").exists()


@pytest.mark.slow
def test_graded_cli_design(tmp_path):
    """The whole door: a shipped design transferred to two sizes, one block per piece per size."""
    import ezdxf
    from core.design.templates import template_path
    rc = main(["export", str(template_path("top_sleeveless")), "--sizes", "XS,XL", "--out", str(tmp_path), "--quiet"])
    assert rc == 0
    summary = json.loads((tmp_path / "graded.json").read_text())
    doc = ezdxf.readfile(tmp_path / "graded_astm.dxf")
    names = [b.name for b in doc.blocks if not b.name.startswith("*")]
    assert len(names) == 2 * len(summary["pieces"]) and all(n.endswith(("_XS", "_XL")) for n in names)
    for piece in summary["pieces"].values():
        assert piece["XL"]["sew_line_mm"] > piece["XS"]["sew_line_mm"]
