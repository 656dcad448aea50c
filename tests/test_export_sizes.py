"""A pattern's size as every file names it (core.export.pieces.size_label): a chart size, else a batch body's
readable name (``sample-0017``), never a Python dict of shape parameters; the body's shape and girths in their
own fields of export.json."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import pytest

from core.export.pieces import readable_name, size_label
from core.pattern.types import Pattern


@pytest.mark.parametrize(
    "label, name",
    [
        ("sample 17", "sample-0017"),
        ("row 3", "row-0003"),
        ("betas 12345", "betas-12345"),
        ("Anna B.", "Anna B."),
        ("  ", "custom"),
        ("Zoë", "Zoe"),
    ],
)
def test_readable_name(label, name):
    assert readable_name(label) == name


@pytest.mark.parametrize(
    "body, size",
    [
        ({"shape": "M"}, "M"),
        ({"shape": {"age": 0.9}, "size": "women:L"}, "women:L"),
        ({"shape": {"age": 0.9}, "name": "sample-0003"}, "sample-0003"),
        ({"shape": {"age": 0.9}}, "custom"),
        ({}, "-"),
    ],
)
def test_size_label(body, size):
    assert size_label(Pattern(style="s", body=body, garments={}, panels=[], seams=[])) == size


def test_batch_item_files_name_the_sampled_body(tmp_path):
    """A sampled body's item: AAMA Size / Sample Size, the SVG labels and export.json say sample-0000 (its label: sample 0); its
    shape parameters and girths are export.json's body fields and pattern.json's body record."""
    import ezdxf

    from core.batch import Options, make_items, sample_anny
    from core.batch.worker import run_items
    from core.design.templates import template_path

    design = json.loads(template_path("top_sleeveless").read_text())
    items = make_items(design, sample_anny(1, seed=3), options=Options(export=("svg", "dxf")))
    [row] = run_items(items, tmp_path)
    assert row["status"] == "ok", row["error"]
    assert row["label"] == "sample 0"
    folder = tmp_path / "items" / row["folder"]
    summary = json.loads((folder / "export" / "export.json").read_text())
    assert summary["size"] == "sample-0000" and summary["body"]["size"] == "sample-0000"
    shape = {k[len("shape.") :]: v for k, v in row.items() if k.startswith("shape.")}
    assert summary["body"]["shape"] == pytest.approx(shape)
    girths = {k[len("body.") : -len("_cm")]: v for k, v in row.items() if k.startswith("body.") and k.endswith("_cm")}
    assert girths and summary["body"]["measurements_cm"] == pytest.approx(girths)
    pattern = json.loads((folder / "pattern.json").read_text())
    assert pattern["body"]["name"] == "sample-0000" and pattern["body"]["measurements_cm"] == pytest.approx(girths)
    doc = ezdxf.readfile(folder / "export" / "pattern_astm.dxf")
    texts = [e.dxf.text for e in doc.modelspace() if e.dxftype() == "TEXT"]
    texts += [e.dxf.text for b in doc.blocks if not b.name.startswith("*") for e in b if e.dxftype() == "TEXT"]
    assert "Sample Size: sample-0000" in texts and "Size: sample-0000" in texts
    assert not any("{" in t for t in texts)
    svg = ET.fromstring((folder / "export" / "pattern.svg").read_text())
    words = " ".join(t.text or "" for t in svg.iter() if t.tag.endswith("text") or t.tag.endswith("tspan"))
    assert "size: sample-0000" in words and "{" not in words
