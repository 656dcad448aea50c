"""Fabric presets (core.drape.materials)."""

import pytest

from core.drape.materials import PRESETS, Material, get_material, names
from core.errors import DrapeError


def test_presets_are_valid_and_physical():
    assert set(names()) >= {"cotton", "jersey", "denim", "silk", "wool"}
    for name in names():
        m = get_material(name)
        assert m.name == name and m.density > 0 and m.thickness > 0
    cotton, jersey = get_material("cotton"), get_material("jersey")
    assert cotton.max_stretch < 0.05 + 1e-12 and jersey.max_stretch > cotton.max_stretch
    assert jersey.stretch_weft < cotton.stretch_weft / 10  # knit stretches across the courses
    assert jersey.stretch_weft < jersey.stretch_warp


def test_default_and_resolution():
    assert get_material() == PRESETS["cotton"]
    assert get_material(" Jersey ").name == "jersey"
    m = get_material({"fabric": "silk", "friction": 0.1})
    assert m.friction == 0.1 and m.density == PRESETS["silk"].density
    assert isinstance(get_material(PRESETS["denim"]), Material)


def test_bad_materials():
    with pytest.raises(DrapeError, match="unknown material"):
        get_material("velvet-ish")
    with pytest.raises(DrapeError, match="unknown material field"):
        get_material({"fabric": "cotton", "stiffness": 3})
    with pytest.raises(DrapeError, match="density"):
        get_material({"fabric": "cotton", "density": 0})
    with pytest.raises(DrapeError, match="bending"):
        get_material({"fabric": "cotton", "bending": float("nan")})
    with pytest.raises(DrapeError):
        get_material(42)


def test_wool_is_a_suiting():
    # worsted suiting: heavier than shirting and than silk, bending between shirting and denim, and a
    # published drape range to meet (core.drape.materials.TARGETS)
    from core.drape.materials import TARGETS

    wool, cotton, denim = get_material("wool"), get_material("cotton"), get_material("denim")
    assert cotton.density < wool.density < denim.density
    assert cotton.bending < wool.bending < denim.bending
    assert wool.stretch_weft < cotton.stretch_weft  # wool gives more in the grain than poplin
    assert TARGETS["wool"]["dc_pct"] == (55.0, 65.0)
