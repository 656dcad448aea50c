"""Waist and shoulder darts beside the bust darts (:func:`core.design.blouse_variants.blouse_waist_darts`):
on a converged solve every dart closes (its legs sew to equal length within 0.1 mm), a set intake is
realised, and the mirrored darts open alike."""

import numpy as np
import pytest

from core.design.blouse_variants import blouse_waist_darts


@pytest.fixture(scope="module")
def waist_run(anny):
    from core import workflows as wf

    prep = wf.prepare(blouse_waist_darts(), body=anny)
    # the darts open over the iterations (docs/darts.md, "Limits"): a converged solve
    return prep, wf.reference(prep, iterations=200)


def test_variant_has_front_waist_and_shoulder_darts_mirrored(waist_run):
    prep, _ = waist_run
    names = sorted(prep.cut.darts)
    assert names == sorted(
        f"blouse.{k}_{s}" for k in ("bust_dart", "waist_dart", "shoulder_dart") for s in ("left", "right")
    )
    hosts = {k.split(".")[1]: v["line"].split(".")[-1] for k, v in prep.cut.darts.items()}
    assert hosts["waist_dart_left"] == "hem" and hosts["shoulder_dart_right"] == "shoulder_right"


def test_waist_darts_close_and_realise_their_intake(waist_run):
    _, run = waist_run
    darts = run.pattern.report["darts"]
    assert run.figures["flipped"] == 0 and run.figures.get("collapsed") == 0
    for name, rec in darts.items():
        assert rec["leg_difference_mm"] <= 0.1, (name, rec)
        assert rec["intake_mm"] > 0, (name, rec)  # none crossed
        if "waist" in name or "shoulder" in name:
            assert rec["intake_set_mm"] == 20.0
            assert abs(rec["intake_mm"] - 20.0) <= 1.5, (name, rec)  # a soft term: 94-102 % held
    for k in ("waist_dart", "shoulder_dart"):
        assert abs(darts[f"blouse.{k}_left"]["intake_mm"] - darts[f"blouse.{k}_right"]["intake_mm"]) <= 1.0


def test_back_waist_dart_points_at_the_shoulder_blade(anny):
    from core import workflows as wf

    prep = wf.prepare(blouse_waist_darts(waist=None, shoulder=None, back=0.015), body=anny)
    for side in ("left", "right"):
        rec = prep.cut.darts[f"blouse.back_waist_dart_{side}"]
        assert rec["panel"] == "blouse.back" and rec["intake"] == pytest.approx(0.015)
        assert rec["line"].split(".")[-1] == "hem"
        blade = anny.landmark_position(f"shoulder_blade_{side}", prep.reference)
        assert np.linalg.norm(rec["apex"] - blade) < 1e-6


def test_four_darts_close_and_fit_the_bust_better_than_three(anny, waist_run):
    """The neckline dart beside the bust, waist and shoulder darts, each 5 mm from the bust point:
    converged, every dart closes and the bust region (within 6 cm of the bust points) is nearer its
    ease than with three darts ending 2 cm short (1.3 % against 2.3 % on women:M at ease 1.1)."""
    from core import workflows as wf
    from core.design.blouse_variants import NECK_DART_APEX_OFFSET, NECK_DART_INTAKE, blouse_four_darts

    prep = wf.prepare(blouse_four_darts(), body=anny)
    assert sorted(k.split(".")[1] for k in prep.cut.darts) == sorted(
        f"{k}_{s}" for k in ("bust_dart", "waist_dart", "shoulder_dart", "neck_dart") for s in ("left", "right")
    )
    run = wf.reference(prep, "improved", iterations=200)  # not the template's fitted: as waist_run
    assert run.figures["flipped"] == 0 and run.figures.get("collapsed") == 0
    darts = run.pattern.report["darts"]
    for name, rec in darts.items():
        assert rec["leg_difference_mm"] <= 0.1, (name, rec)
        assert rec["intake_mm"] > 0, (name, rec)
    assert darts["blouse.neck_dart_left"]["intake_set_mm"] == pytest.approx(NECK_DART_INTAKE * 1000)
    for side in ("left", "right"):
        rec = prep.cut.darts[f"blouse.neck_dart_{side}"]
        bust = anny.landmark_position(f"bust_{side}", prep.reference)
        assert np.linalg.norm(rec["apex"] - bust) < 1e-6 and rec["apex_offset"] == NECK_DART_APEX_OFFSET

    def bust(r):
        regions = r.pattern.report["metrics"]["regions"]
        return max(regions[f"bust_{s}"]["mean"] for s in ("left", "right"))

    assert bust(run) < 0.75 * bust(waist_run[1])


def test_fitted_configuration_keeps_warp_and_shear_on_the_four_dart_blouse(anny):
    """The template ``blouse_four_darts`` names ``fitted`` (converged, warp lengths nearly kept, weak
    weft feedback, regulariser 2) and is solved with it: warp near its design length and shear low
    where improved's 200 iterations buy weft with warp (women:M, ease 1.1: 3.19 % / 5.9 deg against
    8.73 % / 5.2 deg), the bust region within 2 % (1.30 %), every dart closed. With the solver's gap step
    between dart legs (issue 30: before it the piece crossed itself at 2.89 % / 4.9 deg) the warp and shear
    are what a cuttable piece costs."""
    from core import workflows as wf
    from core.design.templates import template_path

    prep = wf.prepare(template_path("blouse_four_darts"), body=anny)
    run = wf.reference(prep)
    assert run.pattern.report["config"] == "fitted"
    f = run.figures
    assert f["flipped"] == 0 and f.get("collapsed") == 0
    assert f["warp deviation mean %"] < 3.5 and f["shear p95 deg"] < 6.2 and f["compliance mean %"] < 1.0, f
    assert f["crossings"] == 0, f
    regions = run.pattern.report["metrics"]["regions"]
    assert max(regions[f"bust_{s}"]["mean"] for s in ("left", "right")) < 2.0
    assert all(rec["leg_difference_mm"] <= 0.1 for rec in run.pattern.report["darts"].values())
