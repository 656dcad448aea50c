"""A template's declared parameter range is a promise: every value in it cuts and flattens.

Every parameter of every shipped template is set to its declared minimum and its
maximum (the others at their defaults), and seeded random combinations draw every
parameter inside its range at once. Each case is cut on the template's body and
solved into its reference pattern (:func:`core.workflows.prepare`,
:func:`core.workflows.reference`): no error, no flipped triangle, seams that sew
(mismatch at most :data:`SEAM_MM`) and ease met about as well as the defaults do
(mean compliance error at most :data:`COMPLIANCE_PCT`). CI runs a seeded sample
(``conftest.sample``); ``pytest --full`` runs every case.

The design format's own floors hold too: every template drapes (a short, 30-frame
drape) with every panel at the lowest ease a design may ask for (``EASE_MIN``), and
cut at the finest refinement (``REFINE_EDGE_MIN``) it solves into a pattern that sews
and drapes; one step below each is refused at load.

Also here: a panel seed next to its seamline is named in the cut's error.
"""

import random

import pytest
from conftest import sample

from core import workflows
from core.design import EASE_MIN, load_design
from core.design.checks import REFINE_EDGE_MIN
from core.design.templates import TEMPLATES
from core.errors import CutError, DesignError, PatternError

SEAM_MM = 3.0  # the defaults give <= 2 mm; a torn solve gives centimetres (12 mm and up)
COMPLIANCE_PCT = 5.0  # the defaults give 0.8 .. 2.4 %; the shortest skirt 3.5 %
INTERIOR = 8  # random interior combinations per template
CI_CASES = 30  # cases run in CI (about 0.5 to 3 s each)
SHORT_DRAPE = {"max_frames": 30}  # the fabric has grown to its pattern size by frame 20


def _cases():
    out = []
    for name, build in TEMPLATES.items():
        params = build()["parameters"]
        for p, spec in params.items():
            for end in ("min", "max"):
                out.append((name, f"{p}={end}", {p: spec[end]}))
        rng = random.Random(f"template-ranges-{name}")
        for i in range(INTERIOR):
            out.append(
                (name, f"interior{i}", {p: round(rng.uniform(s["min"], s["max"]), 4) for p, s in params.items()})
            )
    return out


CASES = _cases()

#: Cases refused today where the range promises a pattern: each a real defect, kept visible (strict xfail:
#: a fix makes the run say so). blouse_fitted-interior5 (a waist dart's leg hooking past the apex after 20
#: iterations) solves since a solve whose dart legs still cross runs extra rounds
#: (PatternSolver.extra_iterations); blouse_four_darts-refine (222 flipped at 5 mm edges) since its front's
#: LSCM start is polished by SLIM (core.pattern.optimizer.init.COLLAPSED_START).
KNOWN_REFUSED: dict = {}


def _known(cases, key):
    """``cases`` (as :func:`conftest.sample` gives them) with the :data:`KNOWN_REFUSED` ones marked."""
    out = []
    for c in cases:
        marks, value = (list(c.marks), c.values[0]) if hasattr(c, "marks") else ([], c)
        reason = KNOWN_REFUSED.get(key(value))
        if reason:
            marks.append(pytest.mark.xfail(raises=PatternError, strict=True, reason=reason))
        out.append(pytest.param(value, marks=marks))
    return out


def _design(name, values):
    d = TEMPLATES[name]()
    for p, v in values.items():
        d["parameters"][p]["value"] = v
    return load_design(d)


def test_every_parameter_declares_its_range():
    """The sweep covers every parameter: each has a min and a max around its default."""
    for name, build in TEMPLATES.items():
        for p, spec in build()["parameters"].items():
            assert spec["min"] < spec["max"], (name, p)
            assert spec["min"] <= spec["value"] <= spec["max"], (name, p)
    assert len(CASES) == sum(2 * len(b()["parameters"]) + INTERIOR for b in TEMPLATES.values())


@pytest.mark.parametrize(
    "case", _known(sample(CASES, CI_CASES, seed=15), lambda c: f"{c[0]}-{c[1]}"), ids=lambda c: f"{c[0]}-{c[1]}"
)
def test_declared_value_cuts_and_flattens(case, anny):
    name, _, values = case
    prep = workflows.prepare(_design(name, values), body=anny)
    run = workflows.reference(prep)  # raises on a flipped triangle
    assert len(run.pattern.panels) == len(prep.cut.panels) > 0
    _check_pattern(run)


def _check_pattern(run):
    m = run.pattern.report["metrics"]
    assert m["seams"]["max_mm"] <= SEAM_MM, m["seams"]["max_mm"]
    assert m["compliance"]["mean"] <= COMPLIANCE_PCT, m["compliance"]["mean"]


@pytest.mark.parametrize("name", sample(list(TEMPLATES), 1, seed=15))
def test_the_lowest_ease_drapes(name, anny):
    """Every panel at EASE_MIN: a pattern that sews, and a drape that does not diverge
    (at a uniform 0.7 the long-sleeve shirt's diverges at frame 1)."""
    d = TEMPLATES[name]()
    for g in d["garments"]:
        for p in g["panels"]:
            p["ease"] = {"value": EASE_MIN}
    run = workflows.reference(workflows.prepare(d, body=anny))
    _check_pattern(run)
    drape = workflows.drape(run.pattern, options=SHORT_DRAPE)  # raises DrapeError when it diverges
    assert drape.result.frames > 0 and drape.figures["penetration %"] < 1.0


@pytest.mark.parametrize("name", _known(sample(list(TEMPLATES), 1, seed=16), lambda n: f"{n}-refine"))
def test_the_finest_refinement_solves_and_drapes(name, anny):
    """refine_edge_length at REFINE_EDGE_MIN: the pattern sews and the drape does not
    diverge (at 4 mm the skirt's drape diverges at frame 1 and dress_gradient's side
    seams mismatch by 95 mm; at 2 mm the skirt's by 43 mm)."""
    d = TEMPLATES[name]()
    d["refine_edge_length"] = REFINE_EDGE_MIN
    run = workflows.reference(workflows.prepare(d, body=anny))
    _check_pattern(run)
    drape = workflows.drape(run.pattern, options=SHORT_DRAPE)
    assert drape.result.frames > 0


@pytest.mark.parametrize(
    "field, value, path",
    [
        ("ease", round(EASE_MIN - 0.01, 2), "garments[0].panels[0].ease.value"),
        ("refine_edge_length", REFINE_EDGE_MIN - 0.001, "refine_edge_length"),
    ],
)
def test_below_the_floors_is_refused(field, value, path):
    d = TEMPLATES["skirt"]()
    if field == "ease":
        d["garments"][0]["panels"][0]["ease"] = {"value": value}
    else:
        d["refine_edge_length"] = value
    with pytest.raises(DesignError) as err:
        load_design(d)
    assert err.value.path == path


# ----------------------------------------------------------------------------- seeds


def _seed_on_side_seam():
    """The long-sleeve shirt with its front's seed half way down the left side seam
    (a geodesic point of that seam's own keypoints: under a millimetre off the cut line)."""
    d = TEMPLATES["shirt_long_sleeve"]()
    d["keypoints"]["side_mid"] = {"between": ["armhole_under_left", "hem_side_left"], "t": 0.5}
    d["garments"][0]["panels"][0]["seed"] = "side_mid"
    return d


def test_a_seed_on_its_seam_is_named(anny):
    with pytest.raises(CutError) as err:
        workflows.prepare(_seed_on_side_seam(), body=anny)
    msg = str(err.value)
    assert "panel 'shirt.front' (keypoint 'side_mid') lies" in msg
    assert "mm from cut line 'shirt.side_left'" in msg
    mm = float(msg.split("(keypoint 'side_mid') lies ")[1].split(" mm")[0])
    assert 0.0 <= mm < 3.0
    assert "missing or does not close" in msg  # the other possible cause stays named


def test_an_inline_seed_is_named_by_its_path(anny):
    d = _seed_on_side_seam()
    d["garments"][0]["panels"][0]["seed"] = d["keypoints"].pop("side_mid")
    with pytest.raises(CutError, match=r"panel 'shirt.front' \(seed garments\[0\].panels\[0\].seed\) lies"):
        workflows.prepare(d, body=anny)


def test_a_missing_seam_still_names_both_seeds(anny):
    d = TEMPLATES["top_sleeveless"]()
    g = d["garments"][0]
    g["lines"] = [l for l in g["lines"] if l["name"] != "side_left"]
    with pytest.raises(CutError) as err:
        workflows.prepare(d, body=anny)
    msg = str(err.value)
    assert "'top.front' (keypoint 'chest_front') and 'top.back' (keypoint 'chest_back')" in msg
    assert "lies" not in msg and "missing or does not close" in msg
