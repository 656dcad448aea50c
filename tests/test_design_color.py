"""``materials.color`` of a design (the render's fabric colour): accepted forms, refusals naming the field."""

from __future__ import annotations

import pytest

from core.design.materials import parse_materials
from core.errors import DesignError


@pytest.mark.parametrize("color", ["#1a2B3c", [0.1, 0.2, 1.0], {"shirt": "#ffffff", "pants": [0, 0, 0]}])
def test_colour_forms_are_kept(color):
    assert parse_materials("materials", {"color": color})["color"] == color


@pytest.mark.parametrize(
    "color, field",
    [
        ("red", "materials.color"),
        ("#12345", "materials.color"),
        ([0.1, 0.2], "materials.color"),
        ([0, 0, 2], "materials.color"),
        ({"shirt": "#zzzzzz"}, "materials.color.shirt"),
        ({"a b": "#ffffff"}, "materials.color.a b"),
    ],
)
def test_bad_colours_name_the_field(color, field):
    with pytest.raises(DesignError) as e:
        parse_materials("materials", {"color": color})
    assert field in str(e.value)
