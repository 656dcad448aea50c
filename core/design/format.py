"""The EASE design file (``"format": "ease-design", "version": 1``): parse, validate, write.

A design is plain JSON. Loading validates every element and raises
:class:`core.errors.DesignError` whose ``path`` is the JSON path of the
offending element (``garments[0].panels[2].ease.value: expected a number in
0.5..4.0, got 7``). Everything that depends on a body (landmark names, whether
a length fits on a limb) is checked when the design is resolved
(:func:`core.design.resolve.resolve`), with the same kind of path.

Fields (metres, the body frame of :mod:`core`: +Z up, body faces -Y, +X = body's left)

=====================  ==========================================================
``format``, ``version``  ``"ease-design"``, ``1``
``name``               non-empty string; ``description`` optional
``body``               ``{"model": "anny", "shape": "XS".."XL" | {param: value},
                       "pose": "A" | "T" | "P1".."P3" | {joint: [rx, ry, rz]}}``:
                       the reference instance the design is made on
``materials``          ``{"fabric": preset, "eps_weft": >= 1, "eps_warp": >= 1,
                       "gathered": bool | [seam line], "gather_above": fraction | null,
                       "export": {"allowance": m | {"default", "hem", "fold",
                       seam line: m}, "notch_spacing": m}}``; ``gathered``
                       seams are not sewn flat: the longer side is gathered into
                       the shorter (true: every seam); ``gather_above`` (default
                       0.2) gathers any seam whose sides' ease demands differ by
                       more than that fraction, null never; ``export``
                       (optional) sets the seam allowance (0..0.1 m; default 1 cm,
                       hems 2 cm, folds 0; a seam line by its name, in every
                       garment, or as ``garment.line``) and the notch spacing
                       (default 10 cm) of the pattern files
``mirror``             true: every ``*_left`` keypoint / line / panel gets its
                       ``*_right`` counterpart through the body's symmetry map
``skirt``              true: cut on the skirt topology (dresses, skirts)
``refine_edge_length`` target *mean* edge length of the cut panels (m, 0.002..0.1,
                       default 0.01): every edge longer than 1.5x it is split
                       (:mod:`core.cut.refine`); null keeps the body's resolution
``parameters``         ``{name: number | {"value", "kind": "placement" (0..1) |
                       "length" (m) | "number", "min", "max"}}``; used as
                       ``"$name"`` wherever a number is expected
``keypoints``          ``{name: keypoint}``; a keypoint is a landmark name,
                       ``{"landmark"}``, ``{"triangle", "bary"}`` (template surface
                       point), ``{"between": [a, b], "t"}`` (fraction t along the
                       geodesic a -> b) or ``{"trace": {"from", "along": "arm_left" |
                       "arm_right" | "leg_left" | "leg_right" | "torso_down" |
                       "torso_up", "length"}}`` (geodesic length down a body part)
                       or ``{"mirror_of": keypoint}`` (its mirror image)
``lines``              lines shared by all garments (e.g. the waist of shirt+pants)
``garments``           ``[{"name", "kind": "upper" | "lower" | "dress", "pin": line
                       name, "lines": [...], "panels": [...]}]``
line                   ``{"name", "role": "seam" | "opening" | "guide"}`` plus one of
                       ``"points": [keypoint, ...], "closed"`` (joined by geodesics);
                       ``"ring": {"through", "normal": axis | [a, b], "contains",
                       "points", "named": {name: fraction | axis}}`` (closed plane
                       section; ``contains``, optional: a second keypoint the
                       plane is tilted to hold, the normal turned least; names
                       points on itself: the extreme along an axis, or the
                       point at a fraction of its length); ``"section": {"from",
                       "to", "normal", "spacing"}`` (plane section between two
                       keypoints, e.g. a centre seam on the midline). A ``guide``
                       line is not cut; it only names points.
panel                  ``{"name", "seed": keypoint inside it, "body_part": "torso" |
                       "arm" | "leg", "ease": field}``
ease field             ``{"value"}`` | ``{"from", "to", "between": [a, b]}`` |
                       ``{"from", "to", "axis", "over": "panel" | "garment"}`` |
                       ``{"per_triangle": {"triangles",
                       "values", "default"}}`` (body template triangles) -- every
                       value finite and in 0.5..4.0 (see :mod:`core.design.ease`)
=====================  ==========================================================

Keypoint references are strings: the name of a design keypoint, of a point
named on a ring line, of a generated ``*_right`` mirror, or of a body landmark.
"""
from __future__ import annotations

import copy
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Optional, Union

from ..errors import DesignError

FORMAT = "ease-design"
VERSION = 1

EASE_MIN, EASE_MAX = 0.5, 4.0
SIZES = ("XS", "S", "M", "L", "XL")
POSES = ("A", "T", "P1", "P2", "P3")
GARMENT_KINDS = ("upper", "lower", "dress")
LINE_ROLES = ("seam", "opening", "guide")  # a guide line is not cut: it only names points
BODY_PARTS = ("torso", "arm", "leg")
TRACE_ALONG = ("arm_left", "arm_right", "leg_left", "leg_right", "torso_down", "torso_up")
PARAMETER_KINDS = ("placement", "length", "number")
AXES = ("x", "-x", "+x", "y", "-y", "+y", "z", "-z", "+z")
KEYPOINT_KINDS = ("landmark", "triangle", "between", "trace", "mirror_of")

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


# ---------------------------------------------------------------- data classes

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
    """A panel: the region of the cut surface around ``seed``, with its ease field."""
    name: str
    seed: Any
    body_part: str = "torso"
    ease: dict = field(default_factory=lambda: {"value": 1.0})

    def to_json(self):
        return {"name": self.name, "seed": copy.deepcopy(self.seed),
                "body_part": self.body_part, "ease": copy.deepcopy(self.ease)}


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
    """A validated design. Build with :func:`load_design`; write with :func:`save_design`.

    Attributes
    ----------
    name : str
    body : dict ``{"model": str, "shape": size name | dict, "pose": preset | dict | None}``
    materials : dict ``{"fabric": str, "eps_weft": float >= 1, "eps_warp": float >= 1}``
    parameters : dict name -> :class:`Parameter`
    keypoints : dict name -> keypoint definition (dict, see module docs)
    lines : list[:class:`Line`], lines shared by garments (e.g. the waist of a shirt+pants)
    garments : list[:class:`Garment`]
    mirror : bool, generate the ``*_right`` counterpart of every ``*_left`` element
    skirt : bool, cut on the skirt topology (dresses, skirts)
    refine_edge_length : float metres or None, the target mean edge length of the refined
        panels (edges longer than 1.5x are split, see :mod:`core.cut.refine`); None: no refinement
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

    # -- serialisation
    def to_json(self) -> dict:
        out = {
            "format": FORMAT,
            "version": VERSION,
            "name": self.name,
        }
        if self.description:
            out["description"] = self.description
        out.update({
            "body": copy.deepcopy(self.body),
            "materials": copy.deepcopy(self.materials),
            "mirror": self.mirror,
            "skirt": self.skirt,
            "refine_edge_length": self.refine_edge_length,
            "parameters": {k: p.to_json() for k, p in self.parameters.items()},
            "keypoints": copy.deepcopy(self.keypoints),
        })
        if self.lines:
            out["lines"] = [l.to_json() for l in self.lines]
        out["garments"] = [g.to_json() for g in self.garments]
        return out

    def copy(self) -> "Design":
        return load_design(self.to_json())

    # -- lookups
    def garment(self, name: str) -> Garment:
        for g in self.garments:
            if g.name == name:
                return g
        raise DesignError("garments", f"no garment {name!r}; garments: {', '.join(g.name for g in self.garments)}")

    def panel_names(self, mirrored: bool = True) -> List[str]:
        """Full panel names ``garment.panel`` as the cut will name them."""
        from .mirror import mirrored_name
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
        from .mirror import mirrored_name
        gname, _, pname = full_name.partition(".")
        g = self.garment(gname)
        for i, p in enumerate(g.panels):
            if p.name == pname:
                return g, p, i, False
        if self.mirror:
            for i, p in enumerate(g.panels):
                if mirrored_name(p.name) == pname:
                    return g, p, i, True
        raise DesignError(f"garments[{self.garments.index(g)}].panels",
                          f"no panel {pname!r} in garment {gname!r}")

    # -- edits (the add-on uses these; each re-validates what it changes)
    def set_parameter(self, name: str, value: float) -> None:
        if name not in self.parameters:
            raise DesignError("parameters", f"no parameter {name!r}; parameters: {', '.join(self.parameters) or 'none'}")
        p = self.parameters[name]
        _check_parameter_value(f"parameters.{name}", p.kind, value, p.min, p.max)
        p.value = float(value)

    def set_keypoint(self, name: str, definition) -> None:
        """Set or add a keypoint; ``definition`` is a keypoint dict or a SurfacePoint."""
        if hasattr(definition, "to_json"):
            definition = definition.to_json()
        path = f"keypoints.{name}"
        _check_name(path, name)
        self.keypoints[name] = _parse_keypoint(path, definition, self.parameters)

    def set_ease(self, panel: str, ease: dict) -> None:
        """Set the ease field of panel ``garment.panel`` (a ``*_right`` mirror
        panel that has no definition of its own becomes an explicit panel)."""
        g, p, i, mirrored = self.find_panel(panel)
        gi = self.garments.index(g)
        if mirrored:
            from .mirror import mirror_panel
            p = mirror_panel(p)
            g.panels.append(p)
            i = len(g.panels) - 1
        p.ease = _parse_ease(f"garments[{gi}].panels[{i}].ease", ease, self.parameters)


# ---------------------------------------------------------------- validation helpers

def _fmt(value) -> str:
    try:
        s = json.dumps(value)
    except (TypeError, ValueError):
        s = repr(value)
    return s if len(s) <= 60 else s[:57] + "..."


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _expect_dict(path, obj, what="an object"):
    if not isinstance(obj, dict):
        raise DesignError(path, f"expected {what}, got {_fmt(obj)}")
    return obj


def _expect_keys(path, obj, allowed):
    extra = sorted(set(obj) - set(allowed))
    if extra:
        raise DesignError(f"{path}.{extra[0]}" if path else extra[0],
                          f"unknown field; expected one of: {', '.join(sorted(allowed))}")


def _check_name(path, name):
    if not isinstance(name, str) or not _NAME.match(name):
        raise DesignError(path, f"expected a name of letters, digits and '_', got {_fmt(name)}")


def _number(path, x, lo=None, hi=None, lo_open=False, what=None):
    if not _is_number(x) or not math.isfinite(x):
        rng = f" in {lo}..{hi}" if lo is not None and hi is not None else ""
        raise DesignError(path, f"expected {what or 'a finite number'}{rng}, got {_fmt(x)}")
    if (lo is not None and (x < lo or (lo_open and x <= lo))) or (hi is not None and x > hi):
        if lo is not None and hi is not None:
            rng = f"in {lo}..{hi}"
        elif lo is not None:
            rng = f"> {lo}" if lo_open else f">= {lo}"
        else:
            rng = f"<= {hi}"
        raise DesignError(path, f"expected {what or 'a number'} {rng}, got {_fmt(x)}")
    return float(x)


def _check_parameter_value(path, kind, value, lo=None, hi=None):
    if kind == "placement":
        _number(path, value, 0.0, 1.0, what="a placement")
    elif kind == "length":
        _number(path, value, 0.0, 3.0, lo_open=True, what="a length in metres")
    else:
        _number(path, value)
    if lo is not None and value < lo or hi is not None and value > hi:
        raise DesignError(path, f"expected a value in {lo}..{hi} (the parameter's range), got {_fmt(value)}")


def _param_or_number(path, x, params, kind, lo=None, hi=None, lo_open=False, what=None):
    """A number, or ``"$name"`` naming a parameter of a compatible kind."""
    if isinstance(x, str):
        if not x.startswith("$"):
            raise DesignError(path, f"expected a number or \"$parameter\", got {_fmt(x)}")
        name = x[1:]
        if name not in params:
            raise DesignError(path, f"unknown parameter {name!r}; parameters: {', '.join(params) or 'none'}")
        p = params[name]
        if kind and p.kind not in (kind, "number"):
            raise DesignError(path, f"parameter {name!r} is a {p.kind}, expected a {kind}")
        return x
    return _number(path, x, lo, hi, lo_open=lo_open, what=what)


def parameter_value(x, params: Dict[str, Parameter]) -> float:
    """The number a validated ``number | "$param"`` field stands for."""
    if isinstance(x, str):
        return float(params[x[1:]].value)
    return float(x)


def _ref(path, x, params, allow_inline=True):
    """A keypoint reference: a name, or (when allowed) an inline keypoint."""
    if isinstance(x, str):
        _check_name(path, x)
        return x
    if allow_inline and isinstance(x, dict):
        return _parse_keypoint(path, x, params)
    raise DesignError(path, f"expected a keypoint name{' or a keypoint object' if allow_inline else ''}, got {_fmt(x)}")


def _parse_keypoint(path, obj, params):
    if isinstance(obj, str):
        return {"landmark": obj}
    _expect_dict(path, obj, "a keypoint object {landmark | triangle+bary | between+t | trace}")
    kinds = [k for k in KEYPOINT_KINDS if k in obj]
    if len(kinds) != 1:
        raise DesignError(path, f"expected exactly one of {', '.join(KEYPOINT_KINDS)}, got {_fmt(sorted(obj))}")
    kind = kinds[0]
    if kind == "landmark":
        _expect_keys(path, obj, ("landmark",))
        _check_name(f"{path}.landmark", obj["landmark"])
        return {"landmark": obj["landmark"]}
    if kind == "triangle":
        _expect_keys(path, obj, ("triangle", "bary"))
        tri = obj["triangle"]
        if not isinstance(tri, int) or isinstance(tri, bool) or tri < 0:
            raise DesignError(f"{path}.triangle", f"expected a triangle index >= 0, got {_fmt(tri)}")
        bary = obj.get("bary")
        if not isinstance(bary, (list, tuple)) or len(bary) != 3:
            raise DesignError(f"{path}.bary", f"expected 3 barycentric weights, got {_fmt(bary)}")
        b = [_number(f"{path}.bary[{i}]", v, -1e-6, 1 + 1e-6, what="a barycentric weight")
             for i, v in enumerate(bary)]
        if abs(sum(b) - 1.0) > 1e-4:
            raise DesignError(f"{path}.bary", f"expected weights summing to 1, got sum {sum(b):.6f}")
        return {"triangle": int(tri), "bary": b}
    if kind == "between":
        _expect_keys(path, obj, ("between", "t"))
        pair = obj["between"]
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise DesignError(f"{path}.between", f"expected [keypoint_a, keypoint_b], got {_fmt(pair)}")
        refs = [_ref(f"{path}.between[{i}]", r, params) for i, r in enumerate(pair)]
        if "t" not in obj:
            raise DesignError(f"{path}.t", "missing; expected a placement 0..1 or \"$parameter\"")
        t = _param_or_number(f"{path}.t", obj["t"], params, "placement", 0.0, 1.0, what="a placement")
        return {"between": refs, "t": t}
    if kind == "mirror_of":
        # the mirror image (through the body's symmetry map) of another keypoint
        _expect_keys(path, obj, ("mirror_of",))
        return {"mirror_of": _ref(f"{path}.mirror_of", obj["mirror_of"], params)}
    # trace
    _expect_keys(path, obj, ("trace",))
    tr = _expect_dict(f"{path}.trace", obj["trace"], "{from, along, length}")
    _expect_keys(f"{path}.trace", tr, ("from", "along", "length"))
    for k in ("from", "along", "length"):
        if k not in tr:
            raise DesignError(f"{path}.trace.{k}", "missing")
    start = _ref(f"{path}.trace.from", tr["from"], params)
    if tr["along"] not in TRACE_ALONG:
        raise DesignError(f"{path}.trace.along", f"expected one of {', '.join(TRACE_ALONG)}, got {_fmt(tr['along'])}")
    length = _param_or_number(f"{path}.trace.length", tr["length"], params, "length", 0.0, 3.0,
                              lo_open=True, what="a length in metres")
    return {"trace": {"from": start, "along": tr["along"], "length": length}}


def _parse_axis_or_pair(path, x, params):
    if isinstance(x, str):
        if x not in AXES:
            raise DesignError(path, f"expected an axis ({', '.join(AXES)}) or [keypoint_a, keypoint_b], got {_fmt(x)}")
        return x
    if isinstance(x, (list, tuple)) and len(x) == 2:
        return [_ref(f"{path}[{i}]", r, params) for i, r in enumerate(x)]
    raise DesignError(path, f"expected an axis ({', '.join(AXES)}) or [keypoint_a, keypoint_b], got {_fmt(x)}")


def _parse_ring(path, ring, params):
    _expect_dict(path, ring, "a ring {through, normal, points, named}")
    _expect_keys(path, ring, ("through", "normal", "points", "named", "offset", "contains"))
    if "through" not in ring:
        raise DesignError(f"{path}.through", "missing; expected a keypoint the ring passes through")
    out = {"through": _ref(f"{path}.through", ring["through"], params)}
    if "normal" not in ring:
        raise DesignError(f"{path}.normal", "missing; expected an axis or [keypoint_a, keypoint_b]")
    out["normal"] = _parse_axis_or_pair(f"{path}.normal", ring["normal"], params)
    if "contains" in ring:
        out["contains"] = _ref(f"{path}.contains", ring["contains"], params)
    n = ring.get("points", 12)
    if not isinstance(n, int) or isinstance(n, bool) or not 4 <= n <= 64:
        raise DesignError(f"{path}.points", f"expected an integer in 4..64, got {_fmt(n)}")
    out["points"] = n
    out["offset"] = _param_or_number(f"{path}.offset", ring.get("offset", 0.0), params, "length",
                                     -0.2, 0.2, what="an offset in metres")
    named = ring.get("named", {})
    _expect_dict(f"{path}.named", named, "an object name -> fraction 0..1 or axis")
    out_named = {}
    for k, v in named.items():
        _check_name(f"{path}.named.{k}", k)
        if isinstance(v, str):
            if v not in AXES:
                raise DesignError(f"{path}.named.{k}", f"expected a fraction 0..1 or an axis ({', '.join(AXES)}), got {_fmt(v)}")
            out_named[k] = v
        else:
            out_named[k] = _number(f"{path}.named.{k}", v, 0.0, 1.0, what="a fraction of the ring")
    out["named"] = out_named
    return out


def _parse_section(path, sec, params):
    _expect_dict(path, sec, "a section {from, to, normal, spacing}")
    _expect_keys(path, sec, ("from", "to", "normal", "spacing"))
    for k in ("from", "to", "normal"):
        if k not in sec:
            raise DesignError(f"{path}.{k}", "missing")
    out = {"from": _ref(f"{path}.from", sec["from"], params), "to": _ref(f"{path}.to", sec["to"], params),
           "normal": _parse_axis_or_pair(f"{path}.normal", sec["normal"], params)}
    out["spacing"] = _number(f"{path}.spacing", sec.get("spacing", 0.03), 0.005, 0.2,
                             what="a point spacing in metres")
    return out


def _parse_line(path, obj, params) -> Line:
    _expect_dict(path, obj, "a line {name, points | ring | section, closed, role}")
    _expect_keys(path, obj, ("name", "points", "closed", "role", "ring", "section"))
    if "name" not in obj:
        raise DesignError(f"{path}.name", "missing")
    _check_name(f"{path}.name", obj["name"])
    role = obj.get("role", "seam")
    if role not in LINE_ROLES:
        raise DesignError(f"{path}.role", f"expected one of {', '.join(LINE_ROLES)}, got {_fmt(role)}")
    if sum(k in obj for k in ("ring", "points", "section")) != 1:
        raise DesignError(path, "expected exactly one of points (a keypoint list), ring (a closed plane "
                                "section) or section (a plane section between two keypoints)")
    if "section" in obj:
        if obj.get("closed", False) is not False:
            raise DesignError(f"{path}.closed", "a section is always open")
        return Line(obj["name"], [], False, role, None, _parse_section(f"{path}.section", obj["section"], params))
    if "ring" in obj:
        if obj.get("closed", True) is not True:
            raise DesignError(f"{path}.closed", "a ring is always closed")
        return Line(obj["name"], [], True, role, _parse_ring(f"{path}.ring", obj["ring"], params))
    closed = obj.get("closed", False)
    if not isinstance(closed, bool):
        raise DesignError(f"{path}.closed", f"expected true or false, got {_fmt(closed)}")
    pts = obj["points"]
    need = 3 if closed else 2
    if not isinstance(pts, list) or len(pts) < need:
        raise DesignError(f"{path}.points", f"expected a list of at least {need} keypoints"
                          f"{' (a closed line)' if closed else ''}, got {_fmt(pts)}")
    refs = [_ref(f"{path}.points[{i}]", r, params) for i, r in enumerate(pts)]
    return Line(obj["name"], refs, closed, role, None)


def _parse_ease_value(path, x):
    return _number(path, x, EASE_MIN, EASE_MAX, what="a number")


def _parse_ease(path, obj, params) -> dict:
    """Validate an ease field. Every value must be finite and in 0.5..4.0."""
    if _is_number(obj):
        return {"value": _parse_ease_value(path, obj)}
    _expect_dict(path, obj, "an ease field {value} | {from, to, between|axis} | {per_triangle}")
    if "value" in obj:
        _expect_keys(path, obj, ("value",))
        return {"value": _parse_ease_value(f"{path}.value", obj["value"])}
    if "per_triangle" in obj:
        _expect_keys(path, obj, ("per_triangle",))
        pt = _expect_dict(f"{path}.per_triangle", obj["per_triangle"], "{triangles, values, default}")
        _expect_keys(f"{path}.per_triangle", pt, ("triangles", "values", "default"))
        vals = pt.get("values")
        if not isinstance(vals, list) or not vals:
            raise DesignError(f"{path}.per_triangle.values", f"expected a non-empty list of ease values, got {_fmt(vals)}")
        out_vals = [_parse_ease_value(f"{path}.per_triangle.values[{i}]", v) for i, v in enumerate(vals)]
        out = {"values": out_vals}
        if "triangles" in pt:
            tris = pt["triangles"]
            if not isinstance(tris, list) or len(tris) != len(vals):
                raise DesignError(f"{path}.per_triangle.triangles",
                                  f"expected a list of {len(vals)} body triangle ids (one per value), got {_fmt(tris)}")
            for i, t in enumerate(tris):
                if not isinstance(t, int) or isinstance(t, bool) or t < 0:
                    raise DesignError(f"{path}.per_triangle.triangles[{i}]", f"expected a triangle index >= 0, got {_fmt(t)}")
            out["triangles"] = [int(t) for t in tris]
        out["default"] = _parse_ease_value(f"{path}.per_triangle.default", pt.get("default", 1.0))
        return {"per_triangle": out}
    if "from" in obj or "to" in obj:
        _expect_keys(path, obj, ("from", "to", "between", "axis", "over"))
        for k in ("from", "to"):
            if k not in obj:
                raise DesignError(f"{path}.{k}", "missing; a gradient needs from and to")
        out = {"from": _parse_ease_value(f"{path}.from", obj["from"]),
               "to": _parse_ease_value(f"{path}.to", obj["to"])}
        if ("between" in obj) == ("axis" in obj):
            raise DesignError(path, "a gradient needs exactly one of between [keypoint_a, keypoint_b] or axis")
        if "between" in obj:
            pair = obj["between"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise DesignError(f"{path}.between", f"expected [keypoint_a, keypoint_b], got {_fmt(pair)}")
            out["between"] = [_ref(f"{path}.between[{i}]", r, params) for i, r in enumerate(pair)]
        else:
            if obj["axis"] not in AXES:
                raise DesignError(f"{path}.axis", f"expected one of {', '.join(AXES)}, got {_fmt(obj['axis'])}")
            out["axis"] = obj["axis"]
            over = obj.get("over", "panel")
            if over not in ("panel", "garment"):
                raise DesignError(f"{path}.over", f"expected \"panel\" or \"garment\", got {_fmt(over)}")
            if over != "panel":
                out["over"] = over
        return out
    raise DesignError(path, f"expected an ease field {{value}} | {{from, to, between|axis}} | {{per_triangle}}, got {_fmt(obj)}")


def _parse_panel(path, obj, params) -> Panel:
    _expect_dict(path, obj, "a panel {name, seed, body_part, ease}")
    _expect_keys(path, obj, ("name", "seed", "body_part", "ease"))
    for k in ("name", "seed"):
        if k not in obj:
            raise DesignError(f"{path}.{k}", "missing")
    _check_name(f"{path}.name", obj["name"])
    seed = _ref(f"{path}.seed", obj["seed"], params)
    part = obj.get("body_part", "torso")
    if part not in BODY_PARTS:
        raise DesignError(f"{path}.body_part", f"expected one of {', '.join(BODY_PARTS)}, got {_fmt(part)}")
    try:
        ease = _parse_ease(f"{path}.ease", obj.get("ease", {"value": 1.0}), params)
    except DesignError as exc:
        # name the panel, not only its JSON path
        raise DesignError(exc.path, f"panel {obj['name']!r}: {exc.message}") from None
    return Panel(obj["name"], seed, part, ease)


def _parse_garment(path, obj, params, shared_lines) -> Garment:
    _expect_dict(path, obj, "a garment {name, kind, pin, lines, panels}")
    _expect_keys(path, obj, ("name", "kind", "pin", "lines", "panels"))
    if "name" not in obj:
        raise DesignError(f"{path}.name", "missing")
    _check_name(f"{path}.name", obj["name"])
    kind = obj.get("kind")
    if kind not in GARMENT_KINDS:
        raise DesignError(f"{path}.kind", f"expected one of {', '.join(GARMENT_KINDS)}, got {_fmt(kind)}")
    lines_raw = obj.get("lines", [])
    if not isinstance(lines_raw, list):
        raise DesignError(f"{path}.lines", f"expected a list of lines, got {_fmt(lines_raw)}")
    lines = []
    for i, l in enumerate(lines_raw):
        line = _parse_line(f"{path}.lines[{i}]", l, params)
        if any(x.name == line.name for x in lines):
            raise DesignError(f"{path}.lines[{i}].name", f"duplicate line name {line.name!r}")
        lines.append(line)
    panels_raw = obj.get("panels")
    if not isinstance(panels_raw, list) or not panels_raw:
        raise DesignError(f"{path}.panels", f"expected a non-empty list of panels, got {_fmt(panels_raw)}")
    panels = []
    for i, p in enumerate(panels_raw):
        panel = _parse_panel(f"{path}.panels[{i}]", p, params)
        if any(x.name == panel.name for x in panels):
            raise DesignError(f"{path}.panels[{i}].name", f"duplicate panel name {panel.name!r}")
        panels.append(panel)
    pin = obj.get("pin")
    if pin is not None:
        names = [l.name for l in lines] + [l.name for l in shared_lines]
        if not isinstance(pin, str) or pin not in names:
            raise DesignError(f"{path}.pin", f"expected the name of one of the garment's (or shared) lines "
                                             f"({', '.join(names) or 'none'}), got {_fmt(pin)}")
    return Garment(obj["name"], kind, pin, lines, panels)


def _parse_body(path, obj):
    _expect_dict(path, obj, "a body {model, shape, pose}")
    _expect_keys(path, obj, ("model", "shape", "pose"))
    model = obj.get("model", "anny")
    if not isinstance(model, str) or not model:
        raise DesignError(f"{path}.model", f"expected a body model name or file path, got {_fmt(model)}")
    shape = obj.get("shape", "M")
    if isinstance(shape, str):
        if shape not in SIZES:
            raise DesignError(f"{path}.shape", f"expected a size ({', '.join(SIZES)}) or an object of shape parameters, got {_fmt(shape)}")
    elif isinstance(shape, dict):
        for k, v in shape.items():
            _number(f"{path}.shape.{k}", v)
        shape = {k: float(v) for k, v in shape.items()}
    elif shape is not None:
        raise DesignError(f"{path}.shape", f"expected a size ({', '.join(SIZES)}) or an object of shape parameters, got {_fmt(shape)}")
    pose = obj.get("pose", "A")
    if isinstance(pose, str):
        if pose not in POSES:
            raise DesignError(f"{path}.pose", f"expected a pose preset ({', '.join(POSES)}) or an object joint -> [rx, ry, rz], got {_fmt(pose)}")
    elif isinstance(pose, dict):
        for k, v in pose.items():
            if not isinstance(v, list) or len(v) != 3:
                raise DesignError(f"{path}.pose.{k}", f"expected an axis-angle [rx, ry, rz] in radians, got {_fmt(v)}")
            for i, x in enumerate(v):
                _number(f"{path}.pose.{k}[{i}]", x)
        pose = {k: [float(x) for x in v] for k, v in pose.items()}
    elif pose is not None:
        raise DesignError(f"{path}.pose", f"expected a pose preset ({', '.join(POSES)}) or an object joint -> [rx, ry, rz], got {_fmt(pose)}")
    return {"model": model, "shape": shape, "pose": pose}


def _parse_materials(path, obj):
    _expect_dict(path, obj, "materials {fabric, eps_weft, eps_warp, export, gathered, gather_above}")
    _expect_keys(path, obj, ("fabric", "eps_weft", "eps_warp", "export", "gathered", "gather_above"))
    fabric = obj.get("fabric", "cotton")
    if not isinstance(fabric, str) or not fabric:
        raise DesignError(f"{path}.fabric", f"expected a fabric preset name, got {_fmt(fabric)}")
    out = {"fabric": fabric}
    for k in ("eps_weft", "eps_warp"):
        out[k] = _number(f"{path}.{k}", obj.get(k, 1.1), 1.0, 4.0, what="a tolerance")
    if "export" in obj:
        out["export"] = _parse_export(f"{path}.export", obj["export"])
    if "gathered" in obj:
        g = obj["gathered"]
        if isinstance(g, bool):
            out["gathered"] = g
        elif isinstance(g, list) and all(isinstance(x, str) for x in g):
            for k, x in enumerate(g):
                for part in x.partition("#")[0].split("."):
                    _check_name(f"{path}.gathered[{k}]", part)
            out["gathered"] = list(g)
        else:
            raise DesignError(f"{path}.gathered", f"expected true, false or a list of seam line names, got {_fmt(g)}")
    if "gather_above" in obj:
        a = obj["gather_above"]
        out["gather_above"] = None if a is None else _number(
            f"{path}.gather_above", a, 0.01, 10.0,
            what="a fraction (0.25: gather a seam whose sides' ease demands differ by more than 25 %) or null")
    return out


def _parse_export(path, obj):
    """``materials.export``: seam allowance (m, a number or per seam) and notch spacing (m)."""
    _expect_dict(path, obj, "an object {allowance, notch_spacing}")
    _expect_keys(path, obj, ("allowance", "notch_spacing"))
    out = {}
    if "allowance" in obj:
        a = obj["allowance"]
        if _is_number(a):
            out["allowance"] = _number(f"{path}.allowance", a, 0.0, 0.1, what="a seam allowance in metres")
        else:
            _expect_dict(f"{path}.allowance", a, 'a width in metres or {"default", "hem", "fold", <seam line>: m}')
            widths = {}
            for k, v in a.items():
                if k not in EXPORT_ALLOWANCE_KEYS:
                    for part in str(k).partition("#")[0].split("."):
                        _check_name(f"{path}.allowance.{k}", part)
                widths[k] = _number(f"{path}.allowance.{k}", v, 0.0, 0.1, what="a seam allowance in metres")
            out["allowance"] = widths
    if "notch_spacing" in obj:
        out["notch_spacing"] = _number(f"{path}.notch_spacing", obj["notch_spacing"], 0.0, 1.0,
                                       what="a notch spacing in metres (0: seam ends only)")
    return out


EXPORT_ALLOWANCE_KEYS = ("default", "hem", "fold")


def _seam_line_names(design: "Design") -> set:
    """Every name a seam line answers to: its own, its mirror's, and both as ``garment.line``."""
    from .mirror import mirrored_name
    seams = set()
    for gname, lines in [(None, design.lines)] + [(g.name, g.lines) for g in design.garments]:
        for line in lines:
            if line.role != "seam":
                continue
            m = mirrored_name(line.name) if design.mirror else None
            for n in (line.name, m):
                if n:
                    seams.add(n)
                    if gname:
                        seams.add(f"{gname}.{n}")
    return seams


def _check_export_seams(design: "Design") -> None:
    """Per-seam allowance keys of ``materials.export`` and the ``materials.gathered`` list must name seam
    lines (or their mirrors)."""
    allowance = (design.materials.get("export") or {}).get("allowance")
    gathered = design.materials.get("gathered")
    if not isinstance(allowance, dict) and not isinstance(gathered, list):
        return
    seams = _seam_line_names(design)
    for k, name in enumerate(gathered if isinstance(gathered, list) else []):
        if name.partition("#")[0] not in seams:
            raise DesignError(f"materials.gathered[{k}]",
                              f"{name!r} is not a seam line of the design; expected one of: "
                              f"{', '.join(sorted(seams)) or '(no seam lines)'}")
    for k in (allowance if isinstance(allowance, dict) else {}):
        if k in EXPORT_ALLOWANCE_KEYS or k.partition("#")[0] in seams:
            continue
        raise DesignError(f"materials.export.allowance.{k}",
                          f"not a seam line of the design; expected 'default', 'hem', 'fold' or one of: "
                          f"{', '.join(sorted(seams)) or '(no seam lines)'}")


def _parse_parameters(path, obj) -> Dict[str, Parameter]:
    _expect_dict(path, obj, "an object name -> number | {value, kind, min, max}")
    out = {}
    for name, v in obj.items():
        p = f"{path}.{name}"
        _check_name(p, name)
        if _is_number(v):
            v = {"value": v}
        _expect_dict(p, v, "a number or {value, kind, min, max}")
        _expect_keys(p, v, ("value", "kind", "min", "max"))
        kind = v.get("kind", "number")
        if kind not in PARAMETER_KINDS:
            raise DesignError(f"{p}.kind", f"expected one of {', '.join(PARAMETER_KINDS)}, got {_fmt(kind)}")
        lo = _number(f"{p}.min", v["min"]) if "min" in v else None
        hi = _number(f"{p}.max", v["max"]) if "max" in v else None
        if "value" not in v:
            raise DesignError(f"{p}.value", "missing")
        _check_parameter_value(f"{p}.value", kind, v["value"], lo, hi)
        out[name] = Parameter(name, float(v["value"]), kind, lo, hi)
    return out


def parse_design(obj: dict) -> Design:
    """Validate a design object (parsed JSON) and build a :class:`Design`."""
    _expect_dict("", obj, "a design object")
    top = ("format", "version", "name", "description", "body", "materials", "mirror", "skirt",
           "refine_edge_length", "parameters", "keypoints", "lines", "garments")
    _expect_keys("", obj, top)
    if obj.get("format") != FORMAT:
        raise DesignError("format", f"expected {FORMAT!r}, got {_fmt(obj.get('format'))}")
    if obj.get("version") != VERSION:
        raise DesignError("version", f"expected {VERSION} (this version of EASE reads design version {VERSION}), got {_fmt(obj.get('version'))}")
    name = obj.get("name")
    if not isinstance(name, str) or not name.strip():
        raise DesignError("name", f"expected a non-empty string, got {_fmt(name)}")
    desc = obj.get("description", "")
    if not isinstance(desc, str):
        raise DesignError("description", f"expected a string, got {_fmt(desc)}")
    body = _parse_body("body", obj.get("body", {}))
    materials = _parse_materials("materials", obj.get("materials", {}))
    for k in ("mirror", "skirt"):
        if not isinstance(obj.get(k, False), bool):
            raise DesignError(k, f"expected true or false, got {_fmt(obj.get(k))}")
    rel = obj.get("refine_edge_length", 0.01)
    if rel is not None:
        rel = _number("refine_edge_length", rel, 0.002, 0.1, what="an edge length in metres (or null)")
    params = _parse_parameters("parameters", obj.get("parameters", {}))
    kps_raw = _expect_dict("keypoints", obj.get("keypoints", {}), "an object name -> keypoint")
    keypoints = {}
    for k, v in kps_raw.items():
        _check_name(f"keypoints.{k}", k)
        keypoints[k] = _parse_keypoint(f"keypoints.{k}", v, params)
    shared_raw = obj.get("lines", [])
    if not isinstance(shared_raw, list):
        raise DesignError("lines", f"expected a list of lines, got {_fmt(shared_raw)}")
    shared = []
    for i, l in enumerate(shared_raw):
        line = _parse_line(f"lines[{i}]", l, params)
        if any(x.name == line.name for x in shared):
            raise DesignError(f"lines[{i}].name", f"duplicate line name {line.name!r}")
        shared.append(line)
    graw = obj.get("garments")
    if not isinstance(graw, list) or not graw:
        raise DesignError("garments", f"expected a non-empty list of garments, got {_fmt(graw)}")
    garments = []
    for i, g in enumerate(graw):
        garment = _parse_garment(f"garments[{i}]", g, params, shared)
        if any(x.name == garment.name for x in garments):
            raise DesignError(f"garments[{i}].name", f"duplicate garment name {garment.name!r}")
        garments.append(garment)
    skirt = bool(obj.get("skirt", False))
    design = Design(name=name, body=body, materials=materials, parameters=params, keypoints=keypoints,
                    lines=shared, garments=garments, mirror=bool(obj.get("mirror", False)), skirt=skirt,
                    refine_edge_length=rel, description=desc)
    _check_names_unique(design)
    _check_export_seams(design)
    return design


def _check_names_unique(design: Design) -> None:
    """Ring-named points must not shadow keypoints or each other."""
    seen = dict.fromkeys(design.keypoints, "keypoints")
    groups = [("lines", design.lines)] + [(f"garments[{gi}].lines", g.lines) for gi, g in enumerate(design.garments)]
    for prefix, lines in groups:
        for li, line in enumerate(lines):
            if line.ring is None:
                continue
            for k in line.ring["named"]:
                if k in seen:
                    raise DesignError(f"{prefix}[{li}].ring.named.{k}", f"name {k!r} is already defined ({seen[k]})")
                seen[k] = f"{prefix}[{li}]"


def load_design(source: Union[str, Path, dict, Design]) -> Design:
    """Load and validate a design from a path, a JSON string, a dict or a Design.

    Raises
    ------
    DesignError : naming the JSON path of the first invalid element.
    """
    if isinstance(source, Design):
        return source
    if isinstance(source, dict):
        return parse_design(copy.deepcopy(source))
    if isinstance(source, str) and source.lstrip().startswith("{"):
        text = source
        where = "<string>"
    else:
        p = Path(source)
        if not p.is_file():
            raise DesignError("", f"design file not found: {p}")
        text = p.read_text(encoding="utf-8")
        where = str(p)
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DesignError("", f"{where}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    return parse_design(obj)


def save_design(design: Design, path: Union[str, Path]) -> Path:
    """Write ``design`` as JSON atomically (validated again first)."""
    from ..fileio import write_json
    obj = design.to_json()
    parse_design(copy.deepcopy(obj))
    return write_json(path, obj, indent=1)
