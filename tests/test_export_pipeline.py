"""What a pipeline trips over (issue 34): a design path is a path, a pattern without a body is refused
where a body is needed, the extension's manifest and build."""

from __future__ import annotations

import dataclasses
import importlib.util
import shutil
from pathlib import Path

import pytest
from export_synth import drape_positions, make_pattern

from core import workflows as wf
from core.design import load_design
from core.errors import DesignError, DrapeError, ExportError

ROOT = Path(__file__).resolve().parent.parent


def test_a_design_path_starting_with_a_brace_is_a_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    shutil.copy(ROOT / "examples" / "designs" / "skirt.json", tmp_path / "{summer} skirt.json")
    design = load_design("{summer} skirt.json")  # relative, as typed on a command line
    assert design.garments
    with pytest.raises(DesignError) as err:
        load_design("{winter} skirt.json")
    assert str(err.value).endswith("design file not found: {winter} skirt.json")
    # JSON text is still JSON text, its errors still say so
    text = (tmp_path / "{summer} skirt.json").read_text()
    assert [g.name for g in load_design(text).garments] == [g.name for g in design.garments]
    with pytest.raises(DesignError, match="<string>: not valid JSON"):
        load_design('{"garments": ')


def test_a_pattern_without_a_body_is_refused_where_a_body_is_needed(tmp_path):
    pattern = dataclasses.replace(make_pattern(), body={})
    with pytest.raises(DrapeError) as err:
        wf.drape(pattern)
    assert str(err.value) == (
        "pattern.json: body: missing; ease drape needs the body the pattern was made on "
        "(model, shape, pose: as `ease pattern` writes it)"
    )
    with pytest.raises(ExportError, match=r"^pattern.json: body: missing; --with-body needs"):
        wf.export(pattern, tmp_path / "x", ("obj",), drape=(drape_positions(pattern), None), with_body=True)
    assert not (tmp_path / "x").exists()


def _build_module():
    spec = importlib.util.spec_from_file_location("ease_build_extension_p", ROOT / "tools" / "build_extension.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_manifest_names_a_maintainer():
    text = (ROOT / "blender_manifest.toml").read_text()
    line = next(ln for ln in text.splitlines() if ln.startswith("maintainer"))
    assert "example." not in line and "<" in line and "@" in line.split("<", 1)[1], line


def test_build_extension_needs_an_output_folder_outside_the_checkout(tmp_path, capsys):
    build = _build_module()
    with pytest.raises(SystemExit) as err:
        build.main(["--platform", "linux-x64", "--no-wheels"])
    assert err.value.code == 2 and "--out" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="--out: .* is inside the checkout"):
        build.main(["--platform", "linux-x64", "--no-wheels", "--out", str(ROOT / "dist")])


def test_the_extension_bundles_no_test_or_lint_tools():
    """The wheels bundled per platform are the add-on's runtime: not pytest (nor xdist), ruff, setuptools, nor dask."""
    build = _build_module()
    bundled, _ = build.requirements()
    names = {r.split("==")[0].split(">")[0].split("<")[0].strip().lower() for r in bundled}
    tools = {"pytest", "pytest-xdist", "execnet", "ruff", "setuptools", "dask", "distributed", "numpy", "bpy"}
    assert names and not names & tools
    assert {"scipy", "warp-lang", "spyrrow"} <= names
