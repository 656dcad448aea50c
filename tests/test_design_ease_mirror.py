"""A ``*_right`` panel is cut as the mirror of its ``*_left`` panel only while its ease is
the left one's read mirrored (core.design.ease.apply_ease): a right side with ease of its
own is a piece of its own, and the export does not mark it "mirror"."""

from __future__ import annotations

import numpy as np
import pytest

from core.cut import cut_design
from core.design import load_design
from core.design.templates import template_dir


@pytest.fixture(scope="module")
def design():
    return load_design(str(template_dir() / "top_short_sleeve.json"))


def _explicit_right(design, ease_left, ease_right):
    d = design.copy()
    d.set_ease("top.sleeve_front_left", ease_left)
    d.set_ease("top.sleeve_front_right", ease_right)
    return d


def test_generated_right_panel_stays_a_mirror(design, anny):
    cut = cut_design(design, body=anny)
    assert cut.panel("top.sleeve_front_right").mirror_of == "top.sleeve_front_left"


@pytest.mark.parametrize("right, mirror", [(1.25, True), (1.4, False)])
def test_explicit_right_panel_is_a_mirror_only_with_the_same_ease(design, anny, right, mirror):
    cut = cut_design(_explicit_right(design, 1.25, right), body=anny)
    p = cut.panel("top.sleeve_front_right")
    assert np.allclose(p.ease, right)
    assert (p.mirror_of == "top.sleeve_front_left") is mirror
    # the other sleeve panel keeps its mirror
    assert cut.panel("top.sleeve_back_right").mirror_of == "top.sleeve_back_left"
