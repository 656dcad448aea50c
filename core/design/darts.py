"""Darts in the design file: parsing, mirroring and resolving them on a body.

A dart is a wedge of cloth sewn away so a flat piece takes a doubly curved
shape (the bust, the shoulder blade, the hollow above the hip). In a design
it is a line in one panel, from its *mouth* on one of the panel's seam or
hem lines to its *apex*, the point of the body it shapes::

    "darts": [{"name": "bust_dart_left", "line": "side_left", "apex": "bust_left",
               "intake": "auto", "apex_offset": 0.02, "at": "bust_left"}]

- ``line``: the seam or hem line (of the panel's garment, or shared) the
  mouth lies on; the mouth is the point of that line nearest to ``at``
  (a keypoint, default the apex), inserted into the line so both meet there;
- ``apex``: a keypoint reference (a design keypoint or a body landmark);
- ``intake``: the dart's width at the mouth in the flat pattern (m, > 0), or
  ``"auto"`` (the default): as wide as the flattening opens it;
- ``apex_offset``: how far short of the true apex the sewn point stops (m,
  default :data:`APEX_OFFSET`), as a tailor ends a bust dart before the
  bust point so the point does not show.

On the cut the dart is a seam line from the mouth to the shortened apex
(:class:`core.design.spec.CutLine` with its :class:`DartSpec`): the cut slits
the panel along it and sews the two legs together, a seam of the panel with
itself. ``*_left`` darts of a mirrored design get their ``*_right``
counterparts (in the same panel when it spans both sides, in the mirrored
panel otherwise).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, replace
from typing import List, Optional

import numpy as np

from ..body.model import SurfacePoint
from ..errors import DesignError
from ..geom.polyline import point_at_length, polyline_length
from .checks import check_name, check_number, expect_dict, expect_keys, fmt, keypoint_ref
from .dart_tips import spread_tip
from .naming import mirrored_name, side_of, swap_side

#: m, default distance the sewn dart point stops short of the true apex
APEX_OFFSET = 0.02
#: m, bounds of the apex offset and of a numeric intake
APEX_OFFSET_MAX = 0.1
INTAKE_MAX = 0.2
#: m, the shortest dart (mouth to sewn point) the cut accepts
MIN_DART_LENGTH = 0.02
#: m, a mouth this close to a point of its line is that point
SNAP = 0.005


@dataclass
class Dart:
    """A dart of a panel (see the module docs); ``intake`` None means ``"auto"``."""

    name: str
    line: str
    apex: object
    intake: Optional[float] = None
    apex_offset: float = APEX_OFFSET
    at: Optional[object] = None

    def to_json(self) -> dict:
        out = {
            "name": self.name,
            "line": self.line,
            "apex": copy.deepcopy(self.apex),
            "intake": "auto" if self.intake is None else self.intake,
            "apex_offset": self.apex_offset,
        }
        if self.at is not None:
            out["at"] = copy.deepcopy(self.at)
        return out


@dataclass
class DartSpec:
    """What the cut needs of a dart (on :class:`core.design.spec.CutLine`).

    name : the dart's full name (``"blouse.bust_dart_left"``), also its cut line's and seam's;
    panel : the full name of the panel it lies in; path : its JSON path (for errors);
    apex : the true apex on the body (SurfacePoint); the line ends ``apex_offset`` m short of it;
    intake : m at the mouth in the pattern, or None (``"auto"``); host : the full name of the line
    the mouth lies on; towards : the name the design gives the apex (a keypoint or landmark), or None.
    """

    name: str
    panel: str
    path: str
    apex: SurfacePoint
    intake: Optional[float]
    apex_offset: float
    host: str
    towards: Optional[str] = None


#: what ``"darts": "auto"`` asks for: at most this many darts, at most this intake (m) each
AUTO_DEFAULTS = {"max_count": 2, "max_intake": 0.06}


def parse_auto(path: str, obj) -> Optional[dict]:
    """``"auto"`` or ``{"auto": true | {"max_count", "max_intake"}}`` as the request dict, else None."""
    if obj == "auto":
        return dict(AUTO_DEFAULTS)
    if not (isinstance(obj, dict) and "auto" in obj):
        return None
    expect_keys(path, obj, ("auto",))
    req = obj["auto"]
    if req is True:
        return dict(AUTO_DEFAULTS)
    expect_dict(f"{path}.auto", req, 'true or {"max_count", "max_intake"}')
    expect_keys(f"{path}.auto", req, tuple(AUTO_DEFAULTS))
    count = req.get("max_count", AUTO_DEFAULTS["max_count"])
    if not isinstance(count, int) or isinstance(count, bool) or not 1 <= count <= 8:
        raise DesignError(f"{path}.auto.max_count", f"expected a whole number of darts in 1..8, got {fmt(count)}")
    intake = check_number(
        f"{path}.auto.max_intake",
        req.get("max_intake", AUTO_DEFAULTS["max_intake"]),
        0.0,
        INTAKE_MAX,
        lo_open=True,
        what="the widest intake in metres",
    )
    return {"max_count": count, "max_intake": intake}


def parse_darts(path: str, obj, params) -> List[Dart]:
    """The ``darts`` list of a panel, validated (names unique, intake > 0 or ``"auto"``)."""
    if not isinstance(obj, list):
        raise DesignError(
            path, f"expected a list of darts {{name, line, apex, intake, apex_offset, at}}, got {fmt(obj)}"
        )
    out: List[Dart] = []
    for i, d in enumerate(obj):
        p = f"{path}[{i}]"
        expect_dict(p, d, "a dart {name, line, apex, intake, apex_offset, at}")
        expect_keys(p, d, ("name", "line", "apex", "intake", "apex_offset", "at"))
        for k in ("name", "line", "apex"):
            if k not in d:
                raise DesignError(f"{p}.{k}", "missing")
        check_name(f"{p}.name", d["name"])
        check_name(f"{p}.line", d["line"])
        apex = keypoint_ref(f"{p}.apex", d["apex"], params, allow_inline=False)
        at = keypoint_ref(f"{p}.at", d["at"], params, allow_inline=False) if d.get("at") is not None else None
        intake = d.get("intake", "auto")
        if intake != "auto":
            intake = check_number(
                f"{p}.intake", intake, 0.0, INTAKE_MAX, lo_open=True, what='"auto" or the width at the mouth in metres'
            )
        else:
            intake = None
        off = check_number(
            f"{p}.apex_offset",
            d.get("apex_offset", APEX_OFFSET),
            0.0,
            APEX_OFFSET_MAX,
            what="the distance in metres the dart stops short of its apex",
        )
        if any(x.name == d["name"] for x in out):
            raise DesignError(f"{p}.name", f"duplicate dart name {d['name']!r}")
        out.append(Dart(d["name"], d["line"], apex, intake, off, at))
    return out


def mirror_dart(d: Dart) -> Dart:
    """The counterpart on the other side of the body (names and references swapped)."""
    return replace(
        d,
        name=mirrored_name(d.name) or swap_side(d.name),
        line=swap_side(d.line),
        apex=swap_side(d.apex),
        at=None if d.at is None else swap_side(d.at),
    )


def panel_darts(panel, mirrored: bool, design_mirror: bool) -> List[Dart]:
    """The darts a panel of the cut gets: its own (mirrored for a generated ``*_right``
    panel) and, in a mirrored design, the ``*_right`` counterpart of every ``*_left`` dart
    the panel does not define itself, when the panel spans both sides (a front; a sided panel,
    ``sleeve_back_left``, has its mirror panel for the counterparts)."""
    own = [mirror_dart(d) for d in panel.darts] if mirrored else list(panel.darts)
    if not design_mirror or side_of(panel.name) is not None:
        return own
    names = {d.name for d in own}
    extra = [mirror_dart(d) for d in own if mirrored_name(d.name) and mirrored_name(d.name) not in names]
    return own + extra


def resolve_darts(resolver, design, lines: list, panels) -> list:
    """Cut lines of every dart, with their mouths inserted into their host lines.

    Parameters
    ----------
    resolver : :class:`core.design.resolve.Resolver` on the body instance.
    design : the Design.
    lines : list of :class:`core.design.spec.CutLine`, the design's cut lines (host lines are
        changed in place: the mouth becomes one of their points).
    panels : ``(garment, path, panel, mirrored)`` of every panel, mirrors included (``mirrored``: the
        panel is another's mirror image).

    Returns
    -------
    list of CutLine (role ``"seam"``, ``dart`` set), mouth first.
    """
    from .spec import CutLine

    by_name = {l.name: l for l in lines}
    taken = set(by_name)
    out = []
    done = {}  # full dart name -> (mouth, sewn point): a mirrored dart mirrors its source's points
    placed = {}  # full panel name -> positions of the sewn points placed so far (room between tips)
    for g, path, panel, mirrored in panels:
        own = {d.name for d in panel.darts} if not mirrored else set()
        for k, d in enumerate(panel_darts(panel, mirrored, design.mirror)):
            dp = f"{path}.darts[{k}]" if k < len(panel.darts) else f"{path}.darts (mirror of {swap_side(d.name)})"
            full = f"{g.name}.{d.name}"
            if full in taken:
                raise DesignError(f"{dp}.name", f"dart {d.name!r}: the name is taken by a line of garment {g.name!r}")
            taken.add(full)
            host = by_name.get(f"{g.name}.{d.line}") or by_name.get(d.line)
            if host is None:
                names = sorted(n.partition(".")[2] or n for n in by_name if n.startswith(f"{g.name}.") or "." not in n)
                raise DesignError(
                    f"{dp}.line",
                    f"dart {d.name!r}: no seam or hem line {d.line!r} in garment "
                    f"{g.name!r}; lines: {', '.join(names) or 'none'}",
                )
            apex = resolver.ref(d.apex, f"{dp}.apex")
            source = f"{g.name}.{swap_side(d.name)}"
            if (mirrored or d.name not in own) and source in done and design.mirror:
                # the mirror image of the source dart's points, so both sides are cut alike
                mouth, end = (resolver.mirror(x) for x in done[source])
                mouth = _insert_mouth(resolver, host, mouth, f"{dp}.line", d.name, exact=True)
            else:
                at = apex if d.at is None else resolver.ref(d.at, f"{dp}.at")
                mouth = _insert_mouth(resolver, host, at, f"{dp}.line", d.name)
                poly = resolver.geodesics.path(mouth, apex)
                length = polyline_length(poly)
                if length - d.apex_offset < MIN_DART_LENGTH:
                    raise DesignError(
                        f"{dp}.apex",
                        f"dart {d.name!r}: its apex is {length * 1000:.0f} mm from the "
                        f"{d.line!r} line; a dart needs {MIN_DART_LENGTH * 1000:.0f} mm "
                        f"after the apex offset of {d.apex_offset * 1000:.0f} mm",
                    )
                p, _, _ = point_at_length(poly, length - d.apex_offset)
                end = resolver.locator.locate(p[None])[0]
                end = spread_tip(resolver, apex, end, placed.get(f"{g.name}.{panel.name}", []), f"{dp}.apex", d.name)
            done[full] = (mouth, end)
            placed.setdefault(f"{g.name}.{panel.name}", []).append(resolver.position(end))
            towards = d.apex if isinstance(d.apex, str) else None
            spec = DartSpec(full, f"{g.name}.{panel.name}", dp, apex, d.intake, d.apex_offset, host.name, towards)
            out.append(CutLine(full, [mouth, end], closed=False, role="seam", dart=spec))
    return out


def _insert_mouth(resolver, host, at: SurfacePoint, path: str, name: str, exact: bool = False) -> SurfacePoint:
    """The point of cut line ``host`` nearest to ``at`` (``exact``: ``at`` itself, a point on
    the line), made one of its points (so the dart and the line meet at one cut vertex).

    The candidates are the points of the resolver's geodesics between the line's points. Each
    geodesic runs between the nearest body vertices of its ends and is joined to each end by a
    chord (:class:`core.design.geometry.Geodesics`), while the cut traces the line exactly
    between its points: the joint, the geodesic's second or last-but-one point, is off that line
    by up to half a body edge. A mouth nearest to a joint is the line's point beyond it: on the
    darted skirt at ``back_dart_place`` 0.60 the joint lay 5.3 mm above the back waist ring
    point, the waist seam dropped from the mouth there to the ring point the way the dart leaves
    it, and the cut found the two lines crossing.
    """
    pts = host.points
    target = resolver.position(at)
    best = None
    nseg = len(pts) if host.closed else len(pts) - 1
    for i in range(nseg):
        poly = resolver.geodesics.path(pts[i], pts[(i + 1) % len(pts)])
        dist = np.linalg.norm(poly - target, axis=1)
        j = int(np.argmin(dist))
        if best is None or dist[j] < best[0]:
            best = (float(dist[j]), i, j, len(poly), poly[j])
    _, i, j, m, q = best
    ends = (pts[i], pts[(i + 1) % len(pts)])
    if exact:
        q = target
    elif m > 2 and j in (1, m - 2):
        # the joint's own end (of a three-point geodesic, whose one joint joins both, the nearer)
        side = [0] if m > 3 and j == 1 else [1] if m > 3 else [0, 1]
        return min((ends[k] for k in side), key=lambda e: np.linalg.norm(resolver.position(e) - target))
    # a mouth within SNAP of a point of the line is that point (no sliver segment)
    for end in ends:
        if np.linalg.norm(resolver.position(end) - q) < SNAP:
            return end
    mouth = at if exact else resolver.locator.locate(q[None])[0]
    host.points.insert(i + 1, mouth)
    return mouth
