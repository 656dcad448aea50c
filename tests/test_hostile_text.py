"""Hostile text and structure: design files, option strings and format lists never trace back.

Every design case (crafted: latin-1/UTF-16/UTF-32 files, nesting 100 to 100000
deep, 5000-digit integers, NaN literals, reversed parameter ranges, unknown
fabrics, models, shape parameters, joints and pose angles in degrees; and
seeded mutations of every template, element by element and byte by byte) is
loaded with :func:`core.design.load_design`: it loads or raises a
DesignError, nothing else. The refused ones also go through ``ease cut`` via
:func:`core.cli.main`: exit 2 and one line naming the file.
"""

import contextlib
import io

import pytest
from conftest import sample
from hostile_text import ASSIGNMENTS, crafted_designs, design_bytes, design_cases

from core.cli import main
from core.errors import BodyError, DesignError, EaseError

CASES = design_cases()
CRAFTED = crafted_designs()


def _ease(*argv):
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main([str(a) for a in argv])
    return rc, err.getvalue().strip()


def _load(path):
    from core.design import load_design

    try:
        load_design(path)
    except DesignError as exc:
        return str(exc)
    return None


@pytest.mark.parametrize("name", sorted(CRAFTED))
def test_crafted_design_is_refused_at_load_naming_the_field(name, tmp_path):
    data, expect = CRAFTED[name]
    path = tmp_path / "design.json"
    path.write_bytes(data)
    message = _load(path)
    assert message is not None, f"{name} was accepted"
    assert "\n" not in message and expect in message and str(path) in message, message


def test_refusals_through_ease_cut_are_one_line_naming_the_file(tmp_path):
    for name in (
        "encoding_latin-1",
        "nested_garments_100000",
        "fabric_unknown",
        "shape_unknown_param",
        "parameter_reversed",
        "pose_degrees",
    ):
        path = tmp_path / f"{name}.json"
        path.write_bytes(CRAFTED[name][0])
        rc, err = _ease("cut", path, "--out", tmp_path / "out", "--no-png", "--quiet")
        assert rc == 2 and "\n" not in err and str(path) in err and CRAFTED[name][1] in err, (name, err)
        assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "chunk",
    sample([tuple(CASES[i : i + 20]) for i in range(0, len(CASES), 20)], 8, seed=15),
    ids=lambda c: f"{c[0][0]}_{c[0][1]}",
)
def test_mutated_designs_load_or_are_refused(chunk, tmp_path):
    """No traceback for any mutation: a Design or a one-line DesignError naming the file."""
    for i, case in enumerate(chunk):
        path = tmp_path / f"d{i}.json"
        path.write_bytes(design_bytes(case))
        message = _load(path)
        if message is not None:
            assert "\n" not in message and str(path) in message, (case, message)


def test_an_accepted_model_suffix_is_one_set():
    """A design's body.model takes every suffix ``ease body --model`` takes (.pickle included)."""
    from core.body.registry import MODEL_SUFFIXES
    from core.design.parser import _parse_body

    for suffix in MODEL_SUFFIXES:
        assert _parse_body("body", {"model": f"my_model{suffix}"})["model"] == f"my_model{suffix}"
    with pytest.raises(BodyError, match="my_model.pickle"):  # then load_body reads it (here: missing)
        from core.body import load_body

        load_body("my_model.pickle")


@pytest.mark.parametrize("text, refused", ASSIGNMENTS)
def test_measure_strings(text, refused):
    from core.body.sizes import check_targets, parse_assignments

    try:
        check_targets(parse_assignments(text, "--measure"))
        got = False
    except BodyError as exc:
        assert "\n" not in str(exc)
        got = True
    assert got == refused


def test_duplicate_measure_is_refused_by_the_cli(tmp_path):
    rc, err = _ease("body", "--measure", "chest=96,chest=100", "--out", tmp_path / "b.obj", "--quiet")
    assert rc == 2 and "'chest' is given twice" in err and not (tmp_path / "b.obj").exists()


@pytest.mark.parametrize("formats", ["all,bogus", "svg,,bogus", "bogus,all", "SVG,dxf"])
def test_format_lists(formats):
    from core.export import parse_formats

    if "bogus" in formats:
        with pytest.raises(EaseError, match="'bogus'"):
            parse_formats(formats)
    else:
        assert parse_formats(formats) == ["svg", "dxf"]


def test_fabric_names_are_the_drape_presets():
    from core.design.materials import FABRICS
    from core.drape.materials import PRESETS

    assert sorted(FABRICS) == sorted(PRESETS)
