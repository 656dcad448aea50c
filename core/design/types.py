"""The data classes of a design: :class:`Design`, :class:`Garment`, :class:`Line`,
:class:`Panel`, :class:`Parameter`.

They hold validated values only: :func:`core.design.parser.parse_design`
builds them from the design JSON and :meth:`Design.to_json` writes it back;
the edits (:meth:`Design.set_parameter`, :meth:`Design.set_keypoint`,
:meth:`Design.set_ease`, used by the add-on) validate what they change with
:mod:`core.design.checks`, so a design stays valid.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

from ..errors import DesignError
from .checks import check_ease, check_keypoint, check_name, check_parameter_value
from .darts import Dart, mirror_dart
from .mirror import mirror_panel
from .naming import mirrored_name
from .pleats import Pleat, mirror_pleat

FORMAT = "ease-design"
VERSION = 1


@dataclass
class Parameter:
    """A named design parameter: ``placement`` (0..1 along a geodesic),
    ``length`` (metres, traced on the body) or a plain ``number``."""

    name: str
    value: float
    kind: str = "number"
    min: Optional[float] = None
    max: Optional[float] = None

    def to_json(self):
        out = {"value": self.value, "kind": self.kind}
        if self.min is not None:
            out["min"] = self.min
        if self.max is not None:
            out["max"] = self.max
        return out


@dataclass
class Line:
    """A cut line of a garment (or shared by garments).

    One of ``points`` (keypoint references or inline keypoints, joined by
    geodesics), ``ring`` (a closed plane section of a limb or the torso) or
    ``section`` (the plane section from one keypoint to another, e.g. a centre
    seam along the body's midline); see :mod:`core.design.resolve`.
    """

    name: str
    points: List[Any] = field(default_factory=list)
    closed: bool = False
    role: str = "seam"
    ring: Optional[dict] = None
    section: Optional[dict] = None

    def to_json(self):
        out: Dict[str, Any] = {"name": self.name}
        if self.ring is not None:
            out["ring"] = copy.deepcopy(self.ring)
        elif self.section is not None:
            out["section"] = copy.deepcopy(self.section)
        else:
            out["points"] = copy.deepcopy(self.points)
            out["closed"] = self.closed
        out["role"] = self.role
        return out


@dataclass
class Panel:
    """A panel: the region of the cut surface around ``seed``, with its ease field and its
    darts (:class:`core.design.darts.Dart`, written only when there are some), or a request for
    automatic darts (``auto_darts``: ``{"max_count", "max_intake"}``, :mod:`core.cut.auto_darts`)."""

    name: str
    seed: Any
    body_part: str = "torso"
    ease: dict = field(default_factory=lambda: {"value": 1.0})
    darts: List[Dart] = field(default_factory=list)
    auto_darts: Optional[dict] = None
    pleats: List[Pleat] = field(default_factory=list)

    def to_json(self):
        out = {
            "name": self.name,
            "seed": copy.deepcopy(self.seed),
            "body_part": self.body_part,
            "ease": copy.deepcopy(self.ease),
        }
        if self.auto_darts:
            out["darts"] = {"auto": copy.deepcopy(self.auto_darts)}
        elif self.darts:
            out["darts"] = [d.to_json() for d in self.darts]
        if self.pleats:
            out["pleats"] = [p.to_json() for p in self.pleats]
        return out


@dataclass
class Garment:
    name: str
    kind: str
    pin: Optional[str] = None
    lines: List[Line] = field(default_factory=list)
    panels: List[Panel] = field(default_factory=list)

    def to_json(self):
        out = {"name": self.name, "kind": self.kind}
        if self.pin is not None:
            out["pin"] = self.pin
        out["lines"] = [l.to_json() for l in self.lines]
        out["panels"] = [p.to_json() for p in self.panels]
        return out


@dataclass
class Design:
    """A validated design. Build with :func:`core.design.parser.load_design`; write with
    :func:`core.design.parser.save_design`.

    Attributes
    ----------
    name : str
    body : dict ``{"model": str, "shape": size name | dict, "pose": preset | dict | None}``
    materials : dict, the file's ``materials`` object (see :mod:`core.design.materials`;
        :meth:`core.design.materials.Materials.of` gives it with every default)
    parameters : dict name -> :class:`Parameter`
    keypoints : dict name -> keypoint definition (dict, see module docs)
    lines : list[:class:`Line`], lines shared by garments (e.g. the waist of a shirt+pants)
    garments : list[:class:`Garment`]
    mirror : bool, generate the ``*_right`` counterpart of every ``*_left`` element
    skirt : bool, cut on the skirt topology (dresses, skirts)
    refine_edge_length : float metres or None, the target mean edge length of the refined
        panels (edges longer than 1.5x are split, see :mod:`core.cut.refine`); None: no refinement
    solver : str or None, the solver configuration the design is made for (one of
        :data:`core.design.checks.SOLVER_CONFIGS`); None: the default. A user's explicit choice
        overrides it (:func:`core.workflows.config_name`).
    transfer_solver : str or None, the body a transfer to another size makes its flattening and
        factorisation on (``"reference"`` | ``"target"``, :data:`core.choices.TRANSFER_SOLVERS`); None:
        the configuration's (``"reference"``). A user's explicit choice overrides it.
    """

    name: str
    body: dict
    materials: dict
    parameters: Dict[str, Parameter]
    keypoints: Dict[str, dict]
    lines: List[Line]
    garments: List[Garment]
    mirror: bool = False
    skirt: bool = False
    refine_edge_length: Optional[float] = 0.01
    description: str = ""
    solver: Optional[str] = None
    transfer_solver: Optional[str] = None

    # -- serialisation
    def to_json(self) -> dict:
        out = {
            "format": FORMAT,
            "version": VERSION,
            "name": self.name,
        }
        if self.description:
            out["description"] = self.description
        out.update(
            {
                "body": copy.deepcopy(self.body),
                "materials": copy.deepcopy(self.materials),
                "mirror": self.mirror,
                "skirt": self.skirt,
                "refine_edge_length": self.refine_edge_length,
                **({"solver": self.solver} if self.solver is not None else {}),
                **({"transfer_solver": self.transfer_solver} if self.transfer_solver is not None else {}),
                "parameters": {k: p.to_json() for k, p in self.parameters.items()},
                "keypoints": copy.deepcopy(self.keypoints),
            }
        )
        if self.lines:
            out["lines"] = [l.to_json() for l in self.lines]
        out["garments"] = [g.to_json() for g in self.garments]
        return out

    def copy(self) -> "Design":
        """An independent copy (a validated design stays valid: nothing to check again)."""
        return copy.deepcopy(self)

    # -- lookups
    def garment(self, name: str) -> Garment:
        for g in self.garments:
            if g.name == name:
                return g
        raise DesignError("garments", f"no garment {name!r}; garments: {', '.join(g.name for g in self.garments)}")

    def panel_names(self, mirrored: bool = True) -> List[str]:
        """Full panel names ``garment.panel`` as the cut will name them."""
        names = []
        for g in self.garments:
            own = {p.name for p in g.panels}
            for p in g.panels:
                names.append(f"{g.name}.{p.name}")
                m = mirrored_name(p.name) if (mirrored and self.mirror) else None
                if m and m not in own:
                    names.append(f"{g.name}.{m}")
        return names

    def find_panel(self, full_name: str):
        """``(garment, panel, index, mirrored)`` for a full panel name; a
        mirrored (generated) panel returns its ``*_left`` source and ``mirrored=True``."""
        gname, _, pname = full_name.partition(".")
        g = self.garment(gname)
        for i, p in enumerate(g.panels):
            if p.name == pname:
                return g, p, i, False
        if self.mirror:
            for i, p in enumerate(g.panels):
                if mirrored_name(p.name) == pname:
                    return g, p, i, True
        raise DesignError(f"garments[{self.garments.index(g)}].panels", f"no panel {pname!r} in garment {gname!r}")

    # -- edits (the add-on uses these; each re-validates what it changes)
    def set_parameter(self, name: str, value: float) -> None:
        if name not in self.parameters:
            raise DesignError(
                "parameters", f"no parameter {name!r}; parameters: {', '.join(self.parameters) or 'none'}"
            )
        p = self.parameters[name]
        check_parameter_value(f"parameters.{name}", p.kind, value, p.min, p.max)
        p.value = float(value)

    def set_keypoint(self, name: str, definition) -> None:
        """Set or add a keypoint; ``definition`` is a keypoint dict or a SurfacePoint."""
        if hasattr(definition, "to_json"):
            definition = definition.to_json()
        path = f"keypoints.{name}"
        check_name(path, name)
        self.keypoints[name] = check_keypoint(path, definition, self.parameters)

    def set_ease(self, panel: str, ease: dict) -> None:
        """Set the ease field of panel ``garment.panel`` (a ``*_right`` mirror
        panel that has no definition of its own becomes an explicit panel)."""
        g, p, i, mirrored = self.find_panel(panel)
        gi = self.garments.index(g)
        if mirrored:
            p = mirror_panel(p)
            p.darts = [mirror_dart(d) for d in p.darts]
            p.pleats = [mirror_pleat(x) for x in p.pleats]
            g.panels.append(p)
            i = len(g.panels) - 1
        p.ease = check_ease(f"garments[{gi}].panels[{i}].ease", ease, self.parameters)
