"""core.workflows: the one pipeline the CLI, the add-on, the benchmarks and batch call."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core import workflows as wf
from core.design.templates import template_path
from core.errors import PatternError


@pytest.fixture(scope="module")
def prep(anny):
    return wf.prepare(template_path("top_sleeveless"), body=anny)


@pytest.fixture(scope="module")
def solver(prep):
    return wf.make_solver(prep)


def _pattern_json(pattern) -> str:
    from core.pattern.io import pattern_to_json

    return json.dumps(pattern_to_json(pattern)["panels"], sort_keys=True)


def test_prepare_reference_is_the_cut_body_instance(prep, anny):
    from core.body.instance import body_instance

    assert prep.cut.body["shape"] == "M" and prep.cut.body["pose"] == "A"
    np.testing.assert_array_equal(prep.reference, body_instance(anny, "M", "A"))
    assert set(prep.timings) == {"load", "cut"}


def test_prepare_adopts_a_given_cut(prep, anny):
    again = wf.prepare(prep.design, body=anny, cut=prep.cut)
    assert again.cut is prep.cut and again.timings["cut"] < 1.0
    np.testing.assert_array_equal(again.reference, prep.reference)


def test_reference_records_config_metrics_and_figures(prep, solver):
    run = wf.reference(prep, solver=solver)
    rep = run.pattern.report
    assert rep["config"] == "improved" and rep["metrics"]["flipped_triangles"] == 0
    assert run.figures["pieces"] == len(run.pattern.panels) == 2
    assert run.figures["compliance mean %"] == round(rep["metrics"]["compliance"]["mean"], 2)
    assert "optimize" in run.timings and "cut" in run.timings
    line = wf.summary(run)
    assert line.startswith("reference: 2 pieces, ease compliance") and "flipped 0" in line


def test_reference_is_the_same_with_a_shared_or_fresh_solver(prep, solver):
    shared = wf.reference(prep, solver=solver)
    fresh = wf.reference(prep)
    assert _pattern_json(shared.pattern) == _pattern_json(fresh.pattern)


def test_transfer_records_size_and_deviation(prep, solver):
    run = wf.transfer(prep, "L", solver=solver)
    rep = run.pattern.report
    assert rep["size"] == "L" and run.pattern.body["size"] == "L" and run.pattern.body["pose"] == "A"
    assert rep["transfer_deviation"]["mean"] == pytest.approx(rep["metrics"]["compliance"]["mean"], abs=1e-9)
    assert run.figures["transfer deviation mean %"] == round(rep["transfer_deviation"]["mean"], 3)
    assert "transfer deviation" in wf.summary(run)
    with pytest.raises(Exception, match="size"):
        wf.transfer(prep, "XXXL", solver=solver)


def test_adapt_records_residual_stretch_before_and_after(prep, solver):
    run = wf.adapt(prep, ["P1"], solver=solver)
    rep = run.pattern.report
    stretch = rep["residual_stretch"]["P1"]
    assert set(stretch) == set(sorted(prep.cut.garments) or ["all"])
    for v in stretch.values():
        assert v["after"] <= v["before"] + 1e-9
    assert rep["poses"] == ["P1"] and "residual stretch after adaptation" in wf.summary(run)


def test_tolerances_caller_over_design_over_default(prep):
    design_w = float(prep.cut.materials.get("eps_weft"))
    assert wf.tolerances(prep) == (design_w, float(prep.cut.materials.get("eps_warp", design_w)))
    assert wf.tolerances(prep, 1.3) == (1.3, 1.3)  # one tolerance: either way
    assert wf.tolerances(prep, 1.3, 1.05) == (1.3, 1.05)
    with pytest.raises(PatternError, match="tolerance"):
        wf.tolerances(prep, 0.9)


def test_solver_config_overrides():
    cfg = wf.solver_config("paper", iterations=3, gather_all=True)
    assert cfg.iterations == 3
    with pytest.raises(Exception):
        wf.solver_config("nonsense")


def test_transfer_to_a_shape_dict(prep, solver, anny):
    """A measured or sampled body (a shape dict, no chart size) transfers like a size."""
    from core.body.sizes import size_shape

    by_name = wf.transfer(prep, "L", solver=solver)
    by_shape = wf.transfer(prep, size_shape(anny, "L"), solver=solver)
    assert _pattern_json(by_shape.pattern) == _pattern_json(by_name.pattern)
    assert "size" not in by_shape.pattern.body and by_shape.pattern.report["size"] == "custom"
    with pytest.raises(PatternError, match="shape dict"):
        wf.transfer(prep, 42, solver=solver)


def test_write_pattern_without_preview(prep, solver, tmp_path):
    wf.write_pattern(tmp_path / "p", wf.reference(prep, solver=solver), preview=False)
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == ["pattern.json", "report.json"]
