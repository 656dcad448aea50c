"""Resolve a design on one body instance into a :class:`core.design.spec.CutSpec`.

Keypoints become :class:`core.body.model.SurfacePoint` s of the body template
(triangle + barycentric weights), so the cut made from them holds for every
shape and pose. Keypoint kinds:

- a landmark of the body, by name;
- ``{"triangle", "bary"}``, a surface point of the template;
- ``{"between": [a, b], "t"}``, the point at fraction t of the geodesic a -> b;
- ``{"trace": {"from", "along", "length"}}``, the point at a geodesic length
  from ``from`` down a body part: ``arm_*`` towards the wrist, ``leg_*``
  towards the ankle (pose-dependent: the geodesic follows the limb as posed),
  ``torso_down``/``torso_up`` straight down/up the torso. A length beyond the
  body part (past the wrist, ankle, crotch or neck) is a DesignError naming
  the parameter.

A line is either a list of keypoints joined by geodesics, or a *ring*: the
closed plane section of a limb or the torso through a keypoint, with the plane
normal given by an axis or by two keypoints (a limb's direction), optionally
tilted (turned least) so the plane also holds a second keypoint (``contains``:
an armhole through the armpit and over the shoulder tip, across the arm in any
pose), sampled at
``points`` positions; a ring can name points on itself (``"named": {"hem_left":
"+x", "cuff_under_left": 0.5}``: the extreme point along an axis, or the point
at a fraction of the ring's length from ``through``, counter-clockwise about
the normal) for other lines to end on.
"""

from __future__ import annotations

from typing import Dict, List, Optional, Tuple

import numpy as np

from ..body.instance import body_instance
from ..body.model import SurfacePoint
from ..body.registry import OBJ_OPTIONS
from ..errors import BodyError, DesignError
from ..geom.polyline import point_at_length, polyline_length
from .checks import parameter_value
from .geometry import SectionLoop, plane_section_loop, surface_tools, turned_normal, vertical_walk
from .mirror import face_symmetry, mirror_line, mirror_panel, mirror_surface_point
from .naming import mirrored_name, swap_side
from .parser import load_design
from .spec import CutLine, CutSpec, GarmentSpec, PanelSpec
from .types import Design, Line

AXIS_VECTORS = {
    "x": (1, 0, 0),
    "+x": (1, 0, 0),
    "-x": (-1, 0, 0),
    "y": (0, 1, 0),
    "+y": (0, 1, 0),
    "-y": (0, -1, 0),
    "z": (0, 0, 1),
    "+z": (0, 0, 1),
    "-z": (0, 0, -1),
}

# Where a trace along a body part heads (landmarks), and its limit.
TRACE_TARGET = {
    "arm_left": "wrist_left",
    "arm_right": "wrist_right",
    "leg_left": "ankle_left",
    "leg_right": "ankle_right",
}


def instance_vertices(design: Design, body, shape=None, pose=None) -> np.ndarray:
    """Vertices (V, 3) of the body instance a design is resolved on (``shape``/``pose`` override the design's).

    A shape parameter or pose joint the model does not know (an SMPL or OBJ
    model is only read here) is a design error at ``body``."""
    try:
        return body_instance(
            body,
            design.body.get("shape") if shape is None else shape,
            design.body.get("pose") if pose is None else pose,
        )
    except BodyError as exc:
        raise DesignError("body", str(exc)) from None


_FACE_SYM = {}


def _face_symmetry_cached(body, faces):
    key = id(body)
    hit = _FACE_SYM.get(key)
    if hit is None or hit[0] is not body:
        hit = (body, face_symmetry(faces, np.asarray(body.symmetry)))
        _FACE_SYM.clear()
        _FACE_SYM[key] = hit
    return hit[1]


class Resolver:
    """Resolves keypoints, lines and seeds of a design on one body instance.

    Parameters
    ----------
    design : Design
    body : BodyModel
    vertices : (V, 3) float, the body instance (metres)
    """

    def __init__(self, design: Design, body, vertices: np.ndarray):
        self.design = design
        self.body = body
        self.faces = np.asarray(body.faces, dtype=np.int64)
        self.vertices = np.asarray(vertices, dtype=np.float64)
        if self.vertices.ndim != 2 or self.vertices.shape[1] != 3 or len(self.vertices) <= self.faces.max():
            raise BodyError(
                f"body vertices {self.vertices.shape} do not match the template of "
                f"{getattr(body, 'name', 'the body')!r} ({int(self.faces.max()) + 1} vertices)"
            )
        if not np.all(np.isfinite(self.vertices)):
            raise BodyError("body vertices must be finite")
        self.tools = surface_tools(self.vertices, self.faces)
        self.geodesics = self.tools.geodesics
        self._face_sym = None
        self._points: Dict[str, SurfacePoint] = {}
        self._stack: List[str] = []
        self._rings: Dict[str, List[SurfacePoint]] = {}
        self._build_tables()

    # ------------------------------------------------------------ tables
    def _build_tables(self):
        d = self.design
        # lines: (full name, JSON path, Line, garment name or None), generated mirrors included
        self.lines: List[Tuple[str, str, Line, Optional[str]]] = []
        groups = [(None, "lines", d.lines)] + [
            (g.name, f"garments[{gi}].lines", g.lines) for gi, g in enumerate(d.garments)
        ]
        for gname, prefix, lines in groups:
            own = {l.name for l in lines}
            for li, line in enumerate(lines):
                full = f"{gname}.{line.name}" if gname else line.name
                self.lines.append((full, f"{prefix}[{li}]", line, gname))
            if d.mirror:
                for li, line in enumerate(lines):
                    m = mirrored_name(line.name)
                    if m and m not in own:
                        full = f"{gname}.{m}" if gname else m
                        self.lines.append((full, f"{prefix}[{li}] (mirrored)", mirror_line(line), gname))
        # names defined by the design: keypoints and ring-named points
        self.ring_named: Dict[str, int] = {}
        for i, (_, _, line, _) in enumerate(self.lines):
            if line.ring is not None:
                for k in line.ring["named"]:
                    if k not in d.keypoints and k not in self.ring_named:
                        self.ring_named[k] = i

    @property
    def locator(self):
        return self.tools.locator

    @property
    def face_sym(self) -> np.ndarray:
        if self._face_sym is None:
            self._face_sym = _face_symmetry_cached(self.body, self.faces)
        return self._face_sym

    def position(self, sp: SurfacePoint) -> np.ndarray:
        return sp.position(self.vertices, self.faces)

    def mirror(self, sp: SurfacePoint) -> SurfacePoint:
        return mirror_surface_point(sp, self.faces, np.asarray(self.body.symmetry), self.face_sym, self.locator)

    def defines(self, name: str) -> bool:
        return name in self.design.keypoints or name in self.ring_named

    # ------------------------------------------------------------ keypoints
    def point(self, name: str, path: str) -> SurfacePoint:
        """The surface point of a keypoint reference ``name`` (used at ``path``)."""
        if name in self._points:
            return self._points[name]
        if name in self._stack:
            raise DesignError(path, f"keypoint {name!r} depends on itself ({' -> '.join(self._stack + [name])})")
        self._stack.append(name)
        try:
            d = self.design
            if name in d.keypoints:
                sp = self.resolve_def(d.keypoints[name], f"keypoints.{name}")
            elif name in self.ring_named:
                self.ring_points(self.ring_named[name])
                sp = self._points[name]
            elif d.mirror and (name.endswith("_right") or "_right_" in name) and self.defines(swap_side(name)):
                sp = self.mirror(self.point(swap_side(name), path))
            else:
                sp = self.landmark(name, path)
        finally:
            self._stack.pop()
        self._points[name] = sp
        return sp

    def landmark(self, name: str, path: str) -> SurfacePoint:
        lm = self.body.landmarks
        if name not in lm:
            known = sorted(self.design.keypoints) + sorted(self.ring_named)
            raise DesignError(
                path,
                f"unknown keypoint or landmark {name!r}; design keypoints: "
                f"{', '.join(known) or 'none'}; landmarks of body {self.body.name!r}: "
                f"{', '.join(sorted(lm))}",
            )
        return lm[name]

    def ref(self, x, path: str) -> SurfacePoint:
        if isinstance(x, str):
            return self.point(x, path)
        return self.resolve_def(x, path)

    def resolve_def(self, kp: dict, path: str) -> SurfacePoint:
        if "landmark" in kp:
            return self.landmark(kp["landmark"], f"{path}.landmark" if not path.endswith(".landmark") else path)
        if "triangle" in kp:
            nf = len(self.faces)
            if kp["triangle"] >= nf:
                raise DesignError(
                    f"{path}.triangle",
                    f"keypoint off the body: triangle {kp['triangle']} does not "
                    f"exist (body {self.body.name!r} has {nf} triangles)",
                )
            return SurfacePoint(int(kp["triangle"]), tuple(float(b) for b in kp["bary"]))
        if "mirror_of" in kp:
            return self.mirror(self.ref(kp["mirror_of"], f"{path}.mirror_of"))
        if "between" in kp:
            a = self.ref(kp["between"][0], f"{path}.between[0]")
            b = self.ref(kp["between"][1], f"{path}.between[1]")
            t = parameter_value(kp["t"], self.design.parameters)
            poly = self.geodesics.path(a, b)
            p, _, _ = point_at_length(poly, t * polyline_length(poly))
            return self.locator.locate(p[None])[0]
        if "trace" in kp:
            return self._trace(kp["trace"], f"{path}.trace")
        raise DesignError(path, "unknown keypoint kind")  # pragma: no cover - validated on load

    def _trace(self, tr: dict, path: str) -> SurfacePoint:
        start = self.ref(tr["from"], f"{path}.from")
        length = parameter_value(tr["length"], self.design.parameters)
        lpath = f"parameters.{tr['length'][1:]}" if isinstance(tr["length"], str) else f"{path}.length"
        along = tr["along"]
        from_name = tr["from"] if isinstance(tr["from"], str) else "the start point"
        if along in TRACE_TARGET:
            target = self.landmark(TRACE_TARGET[along], f"{path}.along")
            poly = self.geodesics.path(start, target)
            avail = polyline_length(poly)
            if length > avail:
                raise DesignError(
                    lpath,
                    f"a length of {length:.3f} m from {from_name} along {along} leaves the "
                    f"body part: it is {avail:.3f} m from there to {TRACE_TARGET[along]}",
                )
            p, _, _ = point_at_length(poly, length)
            return self.locator.locate(p[None])[0]
        down = along == "torso_down"
        try:
            poly, end = vertical_walk(self.vertices, self.faces, start, length, down, self.tools.edges)
        except ValueError as exc:
            raise DesignError(path, str(exc)) from None
        got = polyline_length(poly)
        limit_name = "crotch" if down else "neck_back"
        limit = self.position(self.landmark(limit_name, f"{path}.along"))[2]
        if got < length - 1e-3 or (down and poly[:, 2].min() < limit) or (not down and poly[:, 2].max() > limit):
            raise DesignError(
                lpath,
                f"a length of {length:.3f} m from {from_name} along {along} leaves the "
                f"torso (past the {limit_name} level)",
            )
        return end

    # ------------------------------------------------------------ lines
    def line_points(self, index: int) -> List[SurfacePoint]:
        full, path, line, _ = self.lines[index]
        if line.ring is not None:
            return self.ring_points(index)
        if line.section is not None:
            return self.section_points(index)
        pts = [self.ref(r, f"{path}.points[{i}]") for i, r in enumerate(line.points)]
        for i in range(len(pts) - 1 + int(line.closed)):
            a, b = pts[i], pts[(i + 1) % len(pts)]
            if np.linalg.norm(self.position(a) - self.position(b)) < 1e-6:
                raise DesignError(
                    f"{path}.points[{(i + 1) % len(pts)}]", f"line {full!r}: consecutive keypoints coincide"
                )
        return pts

    def _axis(self, spec, path) -> np.ndarray:
        if isinstance(spec, str):
            return np.asarray(AXIS_VECTORS[spec], dtype=float)
        a = self.position(self.ref(spec[0], f"{path}[0]"))
        b = self.position(self.ref(spec[1], f"{path}[1]"))
        v = b - a
        n = np.linalg.norm(v)
        if n < 1e-6:
            raise DesignError(path, "the two keypoints coincide; they cannot give a direction")
        return v / n

    def _tilt_to_contain(self, n: np.ndarray, p0: np.ndarray, q: np.ndarray, ref, path: str, full: str) -> np.ndarray:
        """The normal ``n`` turned least so that the plane through ``p0`` holds the point
        ``q`` of keypoint ``ref`` too (a ring's ``contains``, then a vertex of the ring):
        e.g. an armhole through the armpit and the shoulder tip, otherwise across the arm
        whatever its pose."""
        m, cos_turn = turned_normal(n, p0, q)
        if cos_turn is None:
            raise DesignError(f"{path}.contains", f"line {full!r}: {ref!r} is the through point itself")
        if cos_turn < 0.2:
            raise DesignError(
                f"{path}.contains",
                f"line {full!r}: {ref!r} lies (nearly) along the normal "
                f"from the through point; no plane across it holds both",
            )
        return m

    def ring_points(self, index: int) -> List[SurfacePoint]:
        full, path, line, _ = self.lines[index]
        if full in self._rings:
            return self._rings[full]
        r = line.ring
        through = self.ref(r["through"], f"{path}.ring.through")
        p0 = self.position(through)
        n = self._axis(r["normal"], f"{path}.ring.normal")
        contains = None
        if r.get("contains") is not None:
            contains = self.ref(r["contains"], f"{path}.ring.contains")
            n = self._tilt_to_contain(n, p0, self.position(contains), r["contains"], f"{path}.ring", full)
        try:
            poly, pts, segf = plane_section_loop(
                self.vertices, self.faces, p0, n, through.triangle, int(r.get("handed", 1)), self.tools.edges
            )
        except ValueError as exc:
            raise DesignError(f"{path}.ring", f"line {full!r}: {exc}") from None
        loop = SectionLoop(self.vertices, self.faces, poly, pts, segf, p0, through)
        j, k = loop.start_segment, len(poly)
        if np.linalg.norm(poly[j] - p0) > 0.05 and np.linalg.norm(poly[(j + 1) % k] - p0) > 0.05:
            raise DesignError(f"{path}.ring", f"line {full!r}: the section misses its through point")
        P, S, cum, total, at = loop.P, loop.S, loop.cum, loop.total, loop.at
        entries = []  # (arc length, SurfacePoint, name or None)
        for name, v in r["named"].items():
            if isinstance(v, str):
                i = int(np.argmax(P @ np.asarray(AXIS_VECTORS[v], dtype=float)))
                entries.append((cum[i], S[i], name))
            else:
                s = v * total
                entries.append((s % total, at(s), name))
        if contains is not None:
            # the contained keypoint is a vertex of the ring (other lines may end on it)
            s_q, dist = loop.arc_position(self.position(contains))
            if dist > 5e-3:
                raise DesignError(
                    f"{path}.ring.contains",
                    f"line {full!r}: the section does not pass within 5 mm of {r['contains']!r}",
                )
            entries.append((s_q % total, contains, None))
        named_s = [e[0] for e in entries]
        N = int(r["points"])
        gap = 0.35 * total / N
        for i in range(N):
            s = i * total / N
            if i == 0 or all(min(abs(s - x), total - abs(s - x)) > gap for x in named_s):
                entries.append((s, at(s) if i else through, None))
        entries.sort(key=lambda e: (e[0], e[2] is None))
        out: List[SurfacePoint] = []
        last = None
        for s, sp, name in entries:
            if name is not None and name not in self.design.keypoints and self.ring_named.get(name) == index:
                self._points[name] = sp
            if last is not None and abs(s - last) < 1e-6:
                continue
            out.append(sp)
            last = s
        self._rings[full] = out
        return out

    def section_points(self, index: int) -> List[SurfacePoint]:
        """Points every ``spacing`` metres along the plane section from ``from`` to ``to``
        (the shorter way round); the plane passes through ``from`` with the given normal."""
        full, path, line, _ = self.lines[index]
        c = line.section
        a = self.ref(c["from"], f"{path}.section.from")
        b = self.ref(c["to"], f"{path}.section.to")
        pa, pb = self.position(a), self.position(b)
        n = self._axis(c["normal"], f"{path}.section.normal")
        # tilt the plane (slightly) so that it contains both ends
        n, cos_turn = turned_normal(n, pa, pb)
        if cos_turn is None:
            raise DesignError(f"{path}.section.to", f"line {full!r}: from and to coincide")
        if cos_turn < np.cos(np.radians(10.0)):
            raise DesignError(
                f"{path}.section.normal",
                f"line {full!r}: {c['to']!r} is more than 10 degrees off the section plane through {c['from']!r}",
            )
        try:
            poly, pts, segf = plane_section_loop(self.vertices, self.faces, pa, n, a.triangle, 1, self.tools.edges)
        except ValueError as exc:
            raise DesignError(f"{path}.section", f"line {full!r}: {exc}") from None
        loop = SectionLoop(self.vertices, self.faces, poly, pts, segf, pa, a)
        # where ``to`` sits on the loop: the nearest point of the section polyline
        sb, dist = loop.arc_position(pb)
        if dist > 5e-3:
            raise DesignError(
                f"{path}.section.to",
                f"line {full!r}: the section through {c['from']!r} does not pass within 5 mm of {c['to']!r}",
            )
        total = loop.total
        forward = sb <= total - sb
        length = sb if forward else total - sb
        count = max(1, int(round(length / c["spacing"])))
        out = [a]
        for i in range(1, count):
            s = i * length / count
            out.append(loop.at(s if forward else total - s))
        out.append(b)
        return out

    # ------------------------------------------------------------ everything
    def line_polylines(self) -> Dict[str, np.ndarray]:
        """Every cut line (guides excluded) as a 3D polyline (k, 3) on this
        instance: consecutive points joined by geodesics, closed lines
        repeating their first point. For drawing seamlines before cutting."""
        out = {}
        for i, (full, _, line, _) in enumerate(self.lines):
            if line.role == "guide":
                continue
            pts = self.line_points(i)
            seq = pts + ([pts[0]] if line.closed else [])
            parts = [self.geodesics.path(a, b) for a, b in zip(seq[:-1], seq[1:])]
            out[full] = np.vstack([parts[0]] + [p[1:] for p in parts[1:]])
        return out

    def all_keypoints(self) -> Dict[str, SurfacePoint]:
        """Every design keypoint and ring-named point (with mirrors), by name."""
        names = list(self.design.keypoints) + list(self.ring_named)
        if self.design.mirror:
            names += [mirrored_name(n) for n in names if mirrored_name(n)]
        out = {}
        for n in names:
            out[n] = self.point(n, f"keypoints.{n}")
        return out


def _panels(design: Design):
    """``(garment, path, Panel, mirror_of full name or None)`` incl. generated mirrors."""
    for gi, g in enumerate(design.garments):
        own = {p.name for p in g.panels}
        for pi, p in enumerate(g.panels):
            left = swap_side(p.name) if p.name.endswith("_right") else None
            mirror_of = f"{g.name}.{left}" if left and left in own else None
            yield g, f"garments[{gi}].panels[{pi}]", p, mirror_of
        if design.mirror:
            for pi, p in enumerate(g.panels):
                m = mirrored_name(p.name)
                if m and m not in own:
                    yield g, f"garments[{gi}].panels[{pi}] (mirrored)", mirror_panel(p), f"{g.name}.{p.name}"


def resolve(
    design, body, shape=None, pose=None, vertices: Optional[np.ndarray] = None, resolver: Optional[Resolver] = None
):
    """Resolve ``design`` on a body instance into a :class:`core.design.spec.CutSpec`.

    Parameters
    ----------
    design : Design | dict | path
    body : BodyModel
    shape, pose : override the design's body shape (size name or dict) and pose.
    vertices : (V, 3) float, the instance itself (skips evaluating the body).

    Raises
    ------
    DesignError : naming the JSON path of the element that cannot be resolved.
    """
    design = load_design(design)
    if resolver is None:
        if vertices is None:
            vertices = instance_vertices(design, body, shape, pose)
        resolver = Resolver(design, body, vertices)
    lines = []
    for i, (full, path, line, gname) in enumerate(resolver.lines):
        pts = resolver.line_points(i)
        if line.role == "guide":
            continue
        lines.append(CutLine(full, list(pts), closed=line.closed, role=line.role))
    if any(p.darts for g in design.garments for p in g.panels):
        from .darts import resolve_darts

        lines += resolve_darts(
            resolver, design, lines, [(g, path, p, path.endswith("(mirrored)")) for g, path, p, _ in _panels(design)]
        )
    names = {l.name for l in lines}
    panels = []
    for g, path, p, mirror_of in _panels(design):
        seed = resolver.ref(p.seed, f"{path}.seed")
        panels.append(PanelSpec(f"{g.name}.{p.name}", g.name, seed, p.body_part, mirror_of))
    garments = []
    for gi, g in enumerate(design.garments):
        pin = None
        if g.pin is not None:
            pin = f"{g.name}.{g.pin}" if f"{g.name}.{g.pin}" in names else g.pin
        garments.append(GarmentSpec(g.name, g.kind, pin))
    shape_used = design.body.get("shape") if shape is None else shape
    pose_used = design.body.get("pose") if pose is None else pose
    if isinstance(pose_used, dict):
        pose_used = {k: [float(x) for x in np.asarray(v).ravel()] for k, v in pose_used.items()}
    return CutSpec(
        lines=lines,
        panels=panels,
        garments=garments,
        skirt=bool(design.skirt),
        refine_edge_length=design.refine_edge_length,
        materials=dict(design.materials),
        body={
            "model": design.body.get("model", "anny"),
            "shape": shape_used,
            "pose": pose_used,
            # an OBJ template's own files travel with the cut (pattern, drape reload it)
            **{k: design.body[k] for k in OBJ_OPTIONS if design.body.get(k) is not None},
        },
    )
