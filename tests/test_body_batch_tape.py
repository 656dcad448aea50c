"""Tape-measure rows of ``ease batch --bodies``: a made-to-measure table (any tape measure beyond
height/chest/waist/hip, or gender) is read as such, and each row is fitted on the worker by the
fit of ``ease body --measurements`` (core.body.made_to_measure.fit_tape)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.batch import BodySourceError, make_items, read_measurements
from core.body.made_to_measure import fit_tape, sample_body, tolerance
from core.body.tape import tape_measures

GIVEN = ("height", "neck", "waist", "hip", "inseam")


def _csv(tmp_path, text, name="bodies.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_tape_table_rows(tmp_path):
    p = _csv(tmp_path, "name,height,bust,waist,inside_leg,gender,size\nann,170,92,74,78,1,\nbo,,,80,,,\nc,,,,,,L\n")
    bodies = read_measurements(p)
    assert [b.kind for b in bodies] == ["tape", "tape", "size"]
    assert bodies[0].value == {"height": 170, "chest": 92, "waist": 74, "inseam": 78, "gender": 1}
    assert bodies[1].value == {"waist": 80} and bodies[1].origin == "bodies.csv row 2"
    # a table of the chart measures alone stays a chart-fit table
    assert read_measurements(_csv(tmp_path, "height,waist\n170,80\n"))[0].kind == "measurements"


@pytest.mark.parametrize(
    "text, words",
    [
        ("height,neck\n170,380\n", ["row 1", "'neck'", "25..65 cm", "got 380"]),
        ("waist,gender\n80,2\n", ["row 1", "'gender'", "0..1,"]),
        ("waist,gender\n,1\n", ["row 1", "no measurement and no size"]),
        ("inseam,inside_leg\n80,80\n", ["one tape measure twice"]),
        ("neck,size\n40,M\n", ["row 1", "not both"]),
    ],
)
def test_bad_tape_tables(tmp_path, text, words):
    with pytest.raises(BodySourceError) as exc:
        read_measurements(_csv(tmp_path, text))
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_tape_rows_fitted_on_the_worker_as_the_cli(tmp_path, anny):
    """A batch item of a tape row: the body is the core's made-to-measure fit of the row (its shape in
    the row), each tape measure reached in a ``tape.<name>_cm`` column within its tolerance; an
    unreachable row fails alone, saying which measure and the closest value."""
    from core.batch.worker import run_items
    from core.design.templates import template_path

    hidden = sample_body(np.random.default_rng([33, 11]))
    want = {k: round(v, 1) for k, v in tape_measures(anny, shape=hidden, which=GIVEN).items()}
    head = "name," + ",".join(GIVEN) + ",gender\n"
    row = "me," + ",".join(f"{want[k]:g}" for k in GIVEN) + f",{hidden['gender']:g}\n"
    bodies = read_measurements(_csv(tmp_path, head + row + "tall,230,,,,60,1\n"))
    design = json.loads(template_path("top_sleeveless").read_text())
    ok, bad = run_items(make_items(design, bodies), tmp_path / "set")
    assert ok["status"] == "ok", ok["error"]
    core = fit_tape(anny, {**want, "gender": hidden["gender"]})
    shape = {k[len("shape.") :]: v for k, v in ok.items() if k.startswith("shape.")}
    assert shape == pytest.approx(core.shape, abs=1e-9)
    for k in GIVEN:
        assert ok[f"targets.{k}"] == want[k]
        assert ok[f"tape.{k}_cm"] == pytest.approx(core.achieved[k], abs=1e-6)
        assert abs(ok[f"tape.{k}_cm"] - want[k]) <= tolerance(k), k
    assert bad["status"] == "error" and "bodies.csv row 2: not reachable by this model: height" in bad["error"]
    assert bad["targets.height"] == 230
