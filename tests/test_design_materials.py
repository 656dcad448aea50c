"""core.design.materials: the one owner of the materials defaults and of the add-on's edits."""

from pathlib import Path

import pytest

from core.design import Materials, load_design
from core.design.materials import ALLOWANCE, EPS_WEFT, GATHER_ABOVE, HEM, NOTCH_SPACING, parse_materials
from core.errors import DesignError

SHIRT = Path(__file__).resolve().parents[1] / "examples" / "designs" / "shirt_long_sleeve.json"


def test_defaults():
    m = Materials.from_dict(None)
    assert (m.fabric, m.eps_weft, m.eps_warp, m.gathered, m.gather_above) == ("cotton", 1.1, 1.1, False, 0.2)
    assert m.allowances == {"default": 0.01, "hem": 0.02, "fold": 0.0} and m.notch_spacing == 0.10
    assert (EPS_WEFT, GATHER_ABOVE, ALLOWANCE, HEM, NOTCH_SPACING) == (1.1, 0.2, 0.01, 0.02, 0.10)
    assert Materials.from_dict({}) == m


def test_typed_view_of_a_file():
    m = Materials.from_dict(
        {
            "eps_weft": 1.3,
            "gathered": ["armhole_left"],
            "gather_above": None,
            "export": {"allowance": 0.015, "notch_spacing": 0.05},
        }
    )
    assert m.eps_warp == 1.3  # the warp tolerance follows the weft's
    assert m.gathered == ("armhole_left",) and m.gather_above is None
    assert m.allowances == {"default": 0.015, "hem": 0.02, "fold": 0.0} and m.notch_spacing == 0.05
    per_seam = Materials.from_dict({"export": {"allowance": {"hem": 0.03, "side_left": 0.012}}})
    assert per_seam.allowances == {"default": 0.01, "hem": 0.03, "fold": 0.0, "side_left": 0.012}


def test_parser_fills_tolerances():
    assert parse_materials("materials", {}) == {"fabric": "cotton", "eps_weft": 1.1, "eps_warp": 1.1}
    assert parse_materials("materials", {"fabric": "Wool"})["fabric"].lower() == "wool"  # a design may name wool
    assert parse_materials("materials", {"eps_weft": 1.2})["eps_warp"] == 1.2
    assert parse_materials("materials", {"eps_weft": 1.2, "eps_warp": 1.05})["eps_warp"] == 1.05


def test_of_a_design():
    d = load_design(SHIRT)
    assert Materials.of(d) == Materials.from_dict(d.materials)


def test_edit_writes_only_changes():
    d = load_design(SHIRT)
    assert Materials.edit(d.materials, gather_above=0.2, allowance=0.01, hem=0.02, notch_spacing=0.1) == d.materials
    off = Materials.edit(d.materials, gather_above=None)
    assert off["gather_above"] is None and "gather_above" not in d.materials  # the input is not changed
    exp = Materials.edit(d.materials, allowance=0.012, hem=0.02, notch_spacing=0.1)["export"]
    assert exp == {"allowance": {"default": 0.012, "hem": 0.02}, "notch_spacing": 0.1}  # the group is written
    kept = Materials.edit({"export": {"allowance": {"side_left": 0.005}}}, allowance=0.02)["export"]["allowance"]
    assert kept == {"side_left": 0.005, "default": 0.02}
    assert Materials.edit({"export": {"allowance": 0.015}}, hem=0.03)["export"]["allowance"] == {
        "default": 0.015,
        "hem": 0.03,
    }


@pytest.mark.parametrize(
    "change, path",
    [
        ({"notch_spacing": 3.0}, "materials.export.notch_spacing"),
        ({"allowance": -0.01}, "materials.export.allowance.default"),
        ({"hem": 0.5}, "materials.export.allowance.hem"),
        ({"gather_above": 0.0}, "materials.gather_above"),
        ({"eps_weft": 0.9}, "materials.eps_weft"),
        ({"eps_warp": "x"}, "materials.eps_warp"),
        ({"fabric": ""}, "materials.fabric"),
    ],
)
def test_edit_errors_name_the_field(change, path):
    with pytest.raises(DesignError) as e:
        Materials.edit({}, **change)
    assert e.value.path == path
