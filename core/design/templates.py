"""The garment templates, built in code and shipped as package data.

Each builder returns a design dict (the JSON format); the files in the
package's ``core/data/designs/`` (:func:`template_dir`; a source checkout's
``examples/designs`` links there) are written from them by
:func:`write_templates` (tests check they are current), so an installed
wheel or the Blender extension has them too.
The builders are in :mod:`.garments` (construction of each garment there) and
:mod:`.blouse_variants` (the four-dart blouse, and variants of the blouse that are not shipped).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Callable, Dict, List

from .blouse_variants import blouse_four_darts
from .garments import (
    blouse_fitted,
    dress,
    dress_gradient,
    jacket,
    pants,
    shirt_long_sleeve,
    shorts,
    skirt,
    skirt_darted,
    teaser_shirt_pants,
    top_short_sleeve,
    top_sleeveless,
)
from .pleated import shirt_box_pleat, skirt_box_pleats, skirt_knife_pleats


def template_dir() -> Path:
    """The folder of the template JSON files inside the installed package.

    The package is installed as files (a wheel, an editable install or the
    extension), so the package data is a real folder.
    """
    return Path(str(resources.files("core").joinpath("data", "designs")))


TEMPLATE_DIR = template_dir()


TEMPLATES: Dict[str, Callable[[], dict]] = {
    "shirt_long_sleeve": shirt_long_sleeve,
    "top_short_sleeve": top_short_sleeve,
    "top_sleeveless": top_sleeveless,
    "pants": pants,
    "shorts": shorts,
    "skirt": skirt,
    "dress": dress,
    "jacket": jacket,
    "teaser_shirt_pants": teaser_shirt_pants,
    "dress_gradient": dress_gradient,
    "blouse_fitted": blouse_fitted,
    "blouse_four_darts": blouse_four_darts,
    "skirt_darted": skirt_darted,
    "skirt_knife_pleats": skirt_knife_pleats,
    "skirt_box_pleats": skirt_box_pleats,
    "shirt_box_pleat": shirt_box_pleat,
}


def list_templates() -> List[str]:
    """Names of the shipped templates, in the order of :data:`TEMPLATES`."""
    return list(TEMPLATES)


def _check_name(name: str) -> None:
    if name not in TEMPLATES:
        from ..errors import DesignError

        raise DesignError("", f"unknown template {name!r}; templates: {', '.join(TEMPLATES)}")


def template_path(name: str) -> Path:
    """Path of the shipped template ``<name>.json`` (package data)."""
    _check_name(name)
    return template_dir() / f"{name}.json"


def template(name: str):
    """The template ``name`` as a validated :class:`core.design.Design` (built in code)."""
    from .parser import load_design

    _check_name(name)
    return load_design(TEMPLATES[name]())


def write_templates(directory=None) -> list:
    """(Re)write every template's JSON into ``directory`` (default :func:`template_dir`); returns the paths."""
    from .parser import load_design, save_design

    directory = Path(directory) if directory is not None else template_dir()
    out = []
    for name, build in TEMPLATES.items():
        out.append(save_design(load_design(build()), directory / f"{name}.json"))
    return out
