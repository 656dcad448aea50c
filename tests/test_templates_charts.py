"""Templates fit every body of every chart: each template cuts on each size of the women's and
men's charts (a seeded sample in CI, all with ``--full``; the default chart's sizes are
tests/test_templates.py's), and the lengths a template means relative to the body are so: the
long sleeve ends short of the wrist and the pants' legs short of the ankle on every size."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import sample

from core.body.sizes import chart_sizes, size_shape
from core.cut import cut_design
from core.design import load_design
from core.design.resolve import Resolver
from core.design.templates import TEMPLATES
from core.errors import CutError

SIZES = [f"{chart}:{s}" for chart in ("women", "men") for s in chart_sizes(chart)]
CASES = [(name, size) for name in TEMPLATES for size in SIZES]

# Cases the cut refuses today, each with its reason (strict: a fix makes the test say so).
KNOWN_REFUSED = {
    ("blouse_four_darts", "women:4XL"): "the neckline and shoulder darts cross near the bust point on "
    "women:4XL (a mouth at 0.5-0.72 of the shoulder does not help; the dart tips' turn, core.design.dart_tips)",
}


def _known(cases):
    """``cases`` (as :func:`conftest.sample` gives them) with the :data:`KNOWN_REFUSED` ones marked."""
    out = []
    for c in cases:
        marks, value = (list(c.marks), c.values[0]) if hasattr(c, "marks") else ([], c)
        if value in KNOWN_REFUSED:
            marks.append(pytest.mark.xfail(raises=CutError, strict=True, reason=KNOWN_REFUSED[value]))
        out.append(pytest.param(value, marks=marks, id=f"{value[0]}-{value[1]}"))
    return out


@pytest.mark.parametrize("case", _known(sample(CASES, 6, seed=33)))
def test_template_cuts_on_every_chart_size(case, anny):
    name, size = case
    d = load_design(TEMPLATES[name]())
    d.refine_edge_length = None  # refinement is body-independent (tests/test_templates.py)
    cut = cut_design(d, body=anny, shape=size)
    assert cut.body["shape"] == size
    assert sorted(p.name for p in cut.panels) == sorted(d.panel_names())
    assert all(len(p.faces) > 0 for p in cut.panels)


@pytest.mark.parametrize("size", ["women:XS", "women:4XL", "men:XS", "men:XXL"])
def test_relative_lengths_end_short_of_wrist_and_ankle(size, anny):
    """The long sleeve's cuff lies between the elbow and the wrist, 3-9 cm from the wrist; the
    pants' hem between the knee and the ankle, 5-15 cm above the ankle; on short and tall, slim
    and heavy bodies alike (the design's own lengths were 0.52 and 0.98 m, past the wrist and
    the ankle on several of these)."""
    for name, end, joint, middle, low, high in (
        ("shirt_long_sleeve", "cuff_level_left", "wrist_left", "elbow_left", 0.03, 0.09),
        ("pants", "leg_hem_out_left", "ankle_left", "knee_left", 0.05, 0.15),
    ):
        d = load_design(TEMPLATES[name]())
        V = np.asarray(anny.vertices(size_shape(anny, size)), float)
        R = Resolver(d, anny, V)
        pos = lambda n: R.position(R.point(n, "test"))  # noqa: E731
        gap = np.linalg.norm(pos(end) - pos(joint))
        assert low < gap < high, (name, size, gap)
        assert pos(middle)[2] > pos(end)[2] > pos(joint)[2], (name, size)
