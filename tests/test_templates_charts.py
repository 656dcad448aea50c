"""Templates fit every body of every chart: each template cuts on each size of the women's and
men's charts and solves into its reference pattern there (each a seeded sample in CI, all with
``--full``; the default chart's sizes are tests/test_templates.py's), and the lengths a template
means relative to the body are so: the long sleeve ends short of the wrist and the pants' legs
short of the ankle on every size."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import sample
from test_template_ranges import _check_pattern as check_pattern

from core import workflows
from core.body.sizes import chart_sizes, size_shape
from core.cut import cut_design
from core.design import load_design
from core.design.resolve import Resolver
from core.design.templates import TEMPLATES
from core.errors import CutError, DesignError, PatternError

SIZES = [f"{chart}:{s}" for chart in ("women", "men") for s in chart_sizes(chart)]
CASES = [(name, size) for name in TEMPLATES for size in SIZES]

# Cases the cut refuses today, each with its reason (strict: a fix makes the test say so). Since the chart
# sizes are fitted by the tape measures (docs/bodies.md) every template cuts on every size: the four-dart
# blouse's neckline and shoulder darts crossed on women:L, XXL and 3XL until its neckline dart stopped
# 7.5 mm short of the bust point (core.design.blouse_variants.NECK_DART_APEX_OFFSET); on men's XXL that
# dart's line then gave two stretches until a mirrored dart no longer snapped to the body's midline
# (core.cut.darts.midline_guards).
KNOWN_REFUSED = {}

# Cases the solve (the reference pattern on the size's own body) refuses today besides those the cut
# refuses, each with its reason (a --full run). The women's 3XL and 4XL are fitted with their thighs
# apart (3XL 0.97 cm, 4XL 0.68 cm) and the average cup (core.body.sizes.CHART_THIGH_GAP_CM, CHART_EXTRA_LOCAL): before, the
# pants' back legs collapsed at 3XL's crotch (thighs 1.8 mm apart) and the side seams of every top
# were 3.4-6.4 mm apart on 4XL (cup 0.75); the pleated skirts' back centre is the waist ring's. The
# four-dart blouse on men:XL (5081 flipped triangles) solves since the solver's start is polished
# where it is squeezed (core.pattern.optimizer.init).
KNOWN_UNSOLVED = {
    **KNOWN_REFUSED,
    # refused in one line since a61d262 (bisected, fifth session of 2026-12-07). The runaway is mid-leg in the
    # front's left shoulder dart (nearly no intake on a men's chest): the global step crosses its legs there and
    # the gap correction reopens them each iteration, while the legs slide past each other along the dart (4-13
    # mm; uneven leg edges 0.5-12.5 mm) until a triangle beside leg b collapses. The case is unstable either way:
    # with a61d262's tip axis or without it, 5 of 9 small changes of the gap settings solve. A fix keeps the
    # legs from sliding along each other where they are held apart (or measures a leg vertex against the other
    # leg's nearby edges, not its fixed partner).
    ("blouse_four_darts", "men:XL"): "the shoulder dart's legs slide past each other mid-leg and the solve diverges",
}
UNSOLVED_RAISES = (CutError, PatternError, DesignError, AssertionError)


def _known(cases, known=None, raises=(CutError, DesignError)):
    """``cases`` (as :func:`conftest.sample` gives them) with the ``known`` ones marked."""
    known = KNOWN_REFUSED if known is None else known
    out = []
    for c in cases:
        marks, value = (list(c.marks), c.values[0]) if hasattr(c, "marks") else ([], c)
        if value in known:
            marks.append(pytest.mark.xfail(raises=raises, strict=True, reason=known[value]))
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


@pytest.mark.parametrize("case", _known(sample(CASES, 3, seed=34), KNOWN_UNSOLVED, UNSOLVED_RAISES))
def test_template_solves_on_every_chart_size(case, anny):
    """Each template, its body set to a chart size, is cut and solved into its reference pattern on
    that body (core.workflows.prepare, reference): no flipped triangle, seams that sew and ease met
    as tests/test_template_ranges.py asks of every template."""
    name, size = case
    d = TEMPLATES[name]()
    chart, bare = size.split(":")
    d["body"] = {**d.get("body", {}), "chart": chart, "shape": bare}  # a women's template on men's sizes too
    prep = workflows.prepare(d, body=anny)
    assert prep.cut.body["shape"] == size
    run = workflows.reference(prep)  # raises on a flipped triangle
    assert len(run.pattern.panels) == len(prep.cut.panels) > 0
    check_pattern(run)


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
