"""Pleats and tucks in the design file: parsing and mirroring them.

A pleat is cloth folded under along a line of a panel: the panel is worn with
the pleat closed, and the flat piece carries the folded cloth as a strip
inserted along the line (:mod:`core.pattern.pleats`). In a design it is an
entry of a panel's ``pleats`` list::

    "pleats": [{"name": "pleat_1_left", "kind": "knife", "from": "waist_pleat_1_left",
                "towards": "hem_pleat_1_left", "depth": 0.02, "direction": "left",
                "pressed": true}]

- ``kind``: ``"knife"`` (one fold, pressed one way: intake 2 x depth), ``"box"`` (two folds
  turned under towards the placement line: intake 4 x depth), ``"inverted_box"`` (two folds
  meeting on the placement line: intake 4 x depth) or ``"tuck"`` (a knife fold stitched
  through its layers over ``stitched_length`` from its start);
- ``from``: a keypoint on a hem, opening or seam line of the panel where the placement line starts
  (a seam to another piece is sewn through the pleat folded closed);
- ``towards``: a keypoint the line runs towards, or ``along``: an axis (``"-z"``: down); the
  line runs straight across the flat piece until it leaves it (on a hem, opening or seam);
- ``depth``: the cloth folded under on each fold (m, 0 < depth <= :data:`DEPTH_MAX`, or a
  ``"$parameter"``);
- ``direction``: ``"left"`` or ``"right"``, the wearer's side of the placement line the folded
  cloth of a knife pleat or tuck lies under (a box pleat's lies on both sides);
- ``pressed``: true (default) for a pressed crease, false for a pleat left open (the drape
  holds a pressed crease, an open one falls into soft folds);
- ``stitched_length``: m the fold's layers are stitched together from the start (a tuck's
  stitching; required > 0 for a tuck, default 0 for a pleat, which is held closed at its start).

``*_left`` pleats of a mirrored design get their ``*_right`` counterparts (names, keypoints and
direction swapped), in the same panel when it spans both sides, as darts do.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import List, Optional

from ..errors import DesignError
from .checks import check_axis, check_name, check_number, expect_dict, expect_keys, fmt, keypoint_ref, param_or_number
from .naming import mirrored_name, swap_side

#: the kinds of pleat, and the cloth each takes in per unit of depth (the strip's width / depth)
KINDS = {"knife": 2, "box": 4, "inverted_box": 4, "tuck": 2}
#: m, the largest depth of one fold
DEPTH_MAX = 0.1
#: m, the longest stitching of a tuck
STITCHED_MAX = 2.0
DIRECTIONS = ("left", "right")
FIELDS = ("name", "kind", "from", "towards", "along", "depth", "direction", "pressed", "stitched_length")
_WHAT = "a pleat {name, kind, from, towards | along, depth, direction, pressed, stitched_length}"


@dataclass
class Pleat:
    """A pleat or tuck of a panel (see the module docs). ``depth`` and ``stitched_length`` are
    numbers or ``"$parameter"`` references; ``towards`` a keypoint reference or None (then
    ``along`` is an axis)."""

    name: str
    kind: str
    start: str
    depth: object
    towards: Optional[str] = None
    along: Optional[str] = None
    direction: str = "left"
    pressed: bool = True
    stitched_length: object = 0.0

    def to_json(self) -> dict:
        out = {"name": self.name, "kind": self.kind, "from": self.start}
        if self.towards is not None:
            out["towards"] = self.towards
        else:
            out["along"] = self.along
        out.update(
            {
                "depth": copy.deepcopy(self.depth),
                "direction": self.direction,
                "pressed": self.pressed,
                "stitched_length": copy.deepcopy(self.stitched_length),
            }
        )
        return out


def parse_pleats(path: str, obj, params) -> List[Pleat]:
    """The ``pleats`` list of a panel, validated field by field (names unique)."""
    if not isinstance(obj, list):
        raise DesignError(path, f"expected a list of pleats {{{', '.join(FIELDS)}}}, got {fmt(obj)}")
    out: List[Pleat] = []
    for i, d in enumerate(obj):
        out.append(parse_pleat(f"{path}[{i}]", d, params))
        if any(x.name == out[-1].name for x in out[:-1]):
            raise DesignError(f"{path}[{i}].name", f"duplicate pleat name {out[-1].name!r}")
    return out


def parse_pleat(p: str, d, params) -> Pleat:
    """One pleat object at JSON path ``p``."""
    expect_dict(p, d, _WHAT)
    expect_keys(p, d, FIELDS)
    for k in ("name", "from", "depth"):
        if k not in d:
            raise DesignError(f"{p}.{k}", "missing")
    check_name(f"{p}.name", d["name"])
    kind = d.get("kind", "knife")
    if kind not in KINDS:
        raise DesignError(f"{p}.kind", f"expected one of {', '.join(KINDS)}, got {fmt(kind)}")
    start = keypoint_ref(f"{p}.from", d["from"], params, allow_inline=False)
    if ("towards" in d) == ("along" in d):
        raise DesignError(
            f"{p}.towards", "expected either towards (a keypoint) or along (an axis), not both or neither"
        )
    towards = keypoint_ref(f"{p}.towards", d["towards"], params, allow_inline=False) if "towards" in d else None
    along = None
    if "along" in d:
        along = check_axis(f"{p}.along", d["along"], params)
        if not isinstance(along, str):
            raise DesignError(f"{p}.along", f"expected an axis (x, -x, y, -y, z, -z), got {fmt(d['along'])}")
    what = "the depth folded under, in metres"
    depth = param_or_number(f"{p}.depth", d["depth"], params, "length", 0.0, DEPTH_MAX, lo_open=True, what=what)
    if not isinstance(depth, str):
        check_number(f"{p}.depth", depth, 0.0, DEPTH_MAX, lo_open=True, what=what)
    direction = d.get("direction", "left")
    if direction not in DIRECTIONS:
        raise DesignError(f"{p}.direction", f"expected left or right, got {fmt(direction)}")
    pressed = d.get("pressed", True)
    if not isinstance(pressed, bool):
        raise DesignError(f"{p}.pressed", f"expected true or false, got {fmt(pressed)}")
    what = "the stitched length in metres"
    stitched = param_or_number(
        f"{p}.stitched_length", d.get("stitched_length", 0.0), params, "length", 0.0, STITCHED_MAX, what=what
    )
    if kind == "tuck" and not isinstance(stitched, str) and stitched <= 0:
        raise DesignError(
            f"{p}.stitched_length", f"a tuck is stitched: expected a length > 0 in metres, got {fmt(stitched)}"
        )
    return Pleat(d["name"], kind, start, depth, towards, along, direction, pressed, stitched)


_AXIS_MIRROR = {"x": "-x", "+x": "-x", "-x": "x"}


def mirror_pleat(p: Pleat) -> Pleat:
    """The counterpart on the other side of the body: names, keypoints and direction swapped, an
    ``along`` axis mirrored across the body's midline (x)."""
    return replace(
        p,
        name=mirrored_name(p.name) or swap_side(p.name),
        start=swap_side(p.start),
        towards=None if p.towards is None else swap_side(p.towards),
        along=None if p.along is None else _AXIS_MIRROR.get(p.along, p.along),
        direction="right" if p.direction == "left" else "left",
    )


def panel_pleats(panel, mirrored: bool, design_mirror: bool) -> List[Pleat]:
    """The pleats a panel of the cut gets: its own (mirrored for a generated ``*_right`` panel) and,
    in a mirrored design, the ``*_right`` counterpart of every ``*_left`` pleat the panel does not
    define itself (a front that spans both sides)."""
    pleats = getattr(panel, "pleats", None) or []
    own = [mirror_pleat(p) for p in pleats] if mirrored else list(pleats)
    if not design_mirror:
        return own
    names = {p.name for p in own}
    return own + [mirror_pleat(p) for p in own if mirrored_name(p.name) and mirrored_name(p.name) not in names]


def design_pleats(design):
    """``(full panel name, JSON path of the pleat, Pleat)`` for every pleat of ``design``, generated
    mirrors included (their path says ``(mirrored)``)."""
    out = []
    for gi, g in enumerate(design.garments):
        own = {p.name for p in g.panels}
        for pi, panel in enumerate(g.panels):
            base = f"garments[{gi}].panels[{pi}].pleats"
            names = [(f"{g.name}.{panel.name}", False)]
            m = mirrored_name(panel.name) if design.mirror else None
            if m and m not in own:
                names.append((f"{g.name}.{m}", True))
            for full, mirrored in names:
                source = {p.name: i for i, p in enumerate(getattr(panel, "pleats", None) or [])}
                for pleat in panel_pleats(panel, mirrored, design.mirror):
                    i = source.get(pleat.name)
                    if i is None:  # a generated mirror: the path of its source
                        i = source.get(swap_side(pleat.name), 0)
                        path = f"{base}[{i}] (mirrored)"
                    else:
                        path = f"{base}[{i}]"
                    out.append((full, path, pleat))
    return out
