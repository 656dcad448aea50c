"""Garment designs: the versioned JSON design format, keypoint resolution on a
body, mirroring, ease fields and the garment templates.

>>> design = load_design("examples/designs/shirt_long_sleeve.json")
>>> spec = resolve(design, body)            # -> core.design.spec.CutSpec
>>> cut = core.cut.cut_design(design)       # resolve + cut + ease

Heavy dependencies (igl, potpourri3d) are imported when a design is resolved,
not when this package is imported.
"""

from .checks import EASE_MAX, EASE_MIN
from .ease import apply_ease, panel_ease
from .materials import Materials
from .parser import load_design, parse_design, save_design
from .resolve import Resolver, instance_vertices, resolve
from .types import FORMAT, VERSION, Design, Garment, Line, Panel, Parameter

__all__ = [
    "Design",
    "Garment",
    "Line",
    "Panel",
    "Parameter",
    "Materials",
    "EASE_MIN",
    "EASE_MAX",
    "FORMAT",
    "VERSION",
    "load_design",
    "parse_design",
    "save_design",
    "Resolver",
    "instance_vertices",
    "resolve",
    "apply_ease",
    "panel_ease",
]
