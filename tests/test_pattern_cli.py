"""`ease pattern`, `ease transfer`, `ease adapt`: arguments, outputs, errors."""

import argparse
import json

import numpy as np
import pytest

from core.cli import pattern as cli
from core.design.templates import template_path
from core.errors import PatternError
from core.pattern.io import load_pattern

SHORTS = template_path("shorts")


def _parser():
    p = argparse.ArgumentParser(prog="ease")
    sub = p.add_subparsers(dest="command")
    cli.add_parser(sub)
    return p


def _run(argv):
    args = _parser().parse_args(argv)
    return args.func(args)


@pytest.mark.parametrize("cmd", ["pattern", "transfer", "adapt"])
def test_help(cmd, capsys):
    with pytest.raises(SystemExit) as e:
        _parser().parse_args([cmd, "--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert "--out" in out and "--config" in out


def test_adapt_refuses_tolerance_below_one(tmp_path):
    with pytest.raises(PatternError, match="--tolerance.*>= 1"):
        _run(["adapt", str(SHORTS), "--pose", "P1", "--tolerance", "0.9", "--out", str(tmp_path / "o")])
    assert not (tmp_path / "o").exists()


def test_pattern_and_adapt_on_the_default_body(anny, tmp_path, capsys):
    out = tmp_path / "pattern"
    assert _run(["pattern", str(SHORTS), "--out", str(out), "--quiet"]) == 0
    pat = load_pattern(out)
    rep = json.loads((out / "report.json").read_text())
    assert rep["metrics"]["flipped_triangles"] == 0
    assert rep["timings"]["cut"] > 0 and rep["timings"]["optimize"] > 0
    assert rep["metrics"]["compliance"]["mean"] < 4.0
    assert rep["metrics"]["seams"]["mean"] < 0.5
    assert (out / "pattern.png").stat().st_size > 1000
    assert pat.mode == "reference" and len(pat.panels) == 4
    assert "ease compliance" in capsys.readouterr().out

    out2 = tmp_path / "adapt"
    assert _run(["adapt", str(SHORTS), "--pose", "P3", "--tolerance", "1.1", "--out", str(out2), "--quiet"]) == 0
    ad = load_pattern(out2)
    rep2 = json.loads((out2 / "report.json").read_text())
    assert ad.mode == "adapt" and rep2["metrics"]["flipped_triangles"] == 0

    out3 = tmp_path / "no_png"  # --no-png: the same pattern, no picture
    assert _run(["pattern", str(SHORTS), "--out", str(out3), "--quiet", "--no-png"]) == 0
    assert not (out3 / "pattern.png").exists()
    assert (out3 / "pattern.json").read_bytes() == (out / "pattern.json").read_bytes()
    rs = rep2["residual_stretch"]["P3"]
    for g, v in rs.items():
        assert v["after"] <= v["before"] + 1e-9
    # never smaller than the reference demand
    for pr, pa in zip(pat.panels, ad.panels):
        assert np.all(pa.target_weft >= pr.target_weft - 1e-9)
