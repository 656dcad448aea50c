"""``ease batch --marker``: each item's marker made by :func:`core.workflows.marker` (the entry the CLI and the
add-on call), with the export's allowance rule; its options checked before any work."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from core.batch import Options, make_items, read_measurements, run_batch
from core.batch.manifest import read_rows
from core.design.templates import template_path

DESIGN = template_path("top_sleeveless")
NO_DASHBOARD = {"dashboard_address": None, "scheduler_kwargs": {"dashboard_address": ":0"}}


def test_each_item_gets_the_marker_of_workflows_marker_with_the_exports_allowances(tmp_path, monkeypatch):
    from core import workflows as wf

    pytest.importorskip("spyrrow")
    (tmp_path / "bodies.csv").write_text("name,size\nmedium,M\n")
    bodies = read_measurements(tmp_path / "bodies.csv")
    out = tmp_path / "set"
    opts = Options(export=("svg",), marker_width=1.5, marker_seconds=1)
    res = run_batch(DESIGN, bodies, out, options=opts, workers=1)
    assert (res.made, res.failed) == (1, 0), res.own_rows()
    (row,) = read_rows(out / "manifest.jsonl")
    folder = out / "items" / row["folder"]
    marker = json.loads((folder / "marker" / "marker.json").read_text())
    export = json.loads((folder / "export" / "export.json").read_text())
    assert {"marker.dxf", "marker.svg", "marker.pdf", "marker.png"} <= {p.name for p in (folder / "marker").iterdir()}
    # one allowance rule: the marker nests the cut lines the export draws (the design's table)
    assert marker["allowance_mm"] == {p["name"]: p["allowance_mm"] for p in export["pieces"]}
    assert marker["sizes"] and list(marker["sizes"]) == ["M"] and marker["garments"] == 1
    assert marker["pieces"] == row["marker.pieces"] == len(export["pieces"])
    assert row["marker.efficiency_pct"] == pytest.approx(marker["efficiency_pct"], abs=1e-3)
    assert 30 < row["marker.efficiency_pct"] < 100 and row["marker.length_mm"] == pytest.approx(marker["length_mm"])
    assert marker["threads"] == 1 and marker["tries"] == 1 and row["timings.marker"] > 0
    # the batch's marker is the workflows' entry, the function the CLI and the add-on call
    from core.batch.worker import _marker
    from core.pattern.io import load_pattern

    seen = []
    real = wf.marker
    monkeypatch.setattr(wf, "marker", lambda *a, **k: seen.append((a, k)) or real(*a, **k))
    (item,) = make_items(json.loads(DESIGN.read_text()), bodies, options=opts)
    pattern = load_pattern(folder)
    _marker(item, SimpleNamespace(pattern=pattern), None)
    ((runs, width), kw) = seen[0]
    assert runs == [("M", pattern, 1)] and width == 1.5 and kw["seconds"] == 1 and kw["spread"] == "single"
    assert "allowance" not in kw and "hem" not in kw  # the design's own table, as the batch's export


def test_marker_options_change_the_ids_only_when_given():
    design = json.loads(DESIGN.read_text())
    bodies = read_measurements_text("name,size\na,M\n")
    plain = [it.id for it in make_items(design, bodies)]
    assert "marker" not in Options().record()
    assert plain != [it.id for it in make_items(design, bodies, options=Options(marker_width=1.5))]
    assert [it.id for it in make_items(design, bodies, options=Options(marker_seconds=30))] == plain


def read_measurements_text(text):
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "b.csv").write_text(text)
        return read_measurements(Path(tmp) / "b.csv")


@pytest.mark.parametrize(
    "argv, said",
    [
        (["--marker", "0"], "--marker: expected a fabric width in mm in (0, 10000], got 0"),
        (["--marker", "1e308"], "--marker: expected a fabric width in mm"),
        (["--marker", "1500", "--marker-seconds", "0"], "--marker-seconds: expected a time budget of 1 to"),
        (["--marker", "1500", "--spread", "three"], "--spread: expected single or pairs, got 'three'"),
    ],
)
def test_bad_marker_options_stop_before_any_work_with_one_line(tmp_path, capsys, argv, said):
    from core.cli import main

    code = main(["batch", str(DESIGN), "--sample", "2", "--out", str(tmp_path / "o")] + argv)
    err = capsys.readouterr().err.strip()
    assert code == 2 and said in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "o").exists()
