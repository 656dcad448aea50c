"""Darts placed automatically where a panel's flattening error concentrates.

A panel with ``"darts": {"auto": {"max_count": 2, "max_intake": 0.06}}`` (or
``"darts": "auto"``) gets its darts here, before it is cut
(:func:`place_darts`). The error a flat piece cannot avoid is the surface's
Gaussian curvature: a piece laid flat over a bump of integrated curvature
``theta`` (radians) must take a wedge of angle ``theta`` out somewhere, and a
dart takes it where it lies. So:

1. the design is cut without its automatic darts, and each such panel's
   integrated curvature (angle defect, :func:`angle_defect`) is summed within
   :data:`REACH` of every vertex;
2. the peaks of that sum above :data:`MIN_THETA` (up to ``max_count``,
   :data:`SPACING` apart, :data:`INSIDE` the panel, on the ``*_left`` side of a
   mirrored design) become apexes: the nearest body landmark among the tailor's
   (:data:`APEX_LANDMARKS`: bust points, shoulder blades, seat) when within
   :data:`SNAP_LANDMARK`, else the peak itself as a surface point;
3. the mouth goes on the nearest seam or hem line of the panel (a bust dart
   from the side seam, a back dart from the waist or hem, as a tailor would);
4. the intake is ``"auto"`` (the flattening opens it), or ``max_intake`` where
   the wedge ``2 L sin(theta / 2)`` of a dart ``L`` long would be wider.

The darts are written into the design (:func:`place_darts` returns it, the
designer can edit it and save it with :func:`core.design.save_design`); a
mirrored design mirrors them as any dart.
"""

from __future__ import annotations

from typing import List

import numpy as np

from ..design.darts import APEX_OFFSET, MIN_DART_LENGTH, Dart
from ..design.naming import side_of
from ..errors import DesignError

#: m, the radius the curvature is summed over (a bust is about 6 cm round)
REACH = 0.06
#: rad, the least integrated curvature worth a dart (about 3 degrees of wedge)
MIN_THETA = 0.05
#: m, the least distance between two automatic darts' apexes
SPACING = 0.1
#: the landmarks a tailor points a dart at
APEX_LANDMARKS = ("bust_left", "bust_right", "shoulder_blade_left", "shoulder_blade_right", "seat_left", "seat_right")
#: m, a peak this near one of them points at the landmark
SNAP_LANDMARK = 0.06
#: m, an apex at least this far inside the panel (a dart needs room to open)
INSIDE = 0.06
#: m, how far left of the midline (+x) a mirrored design's automatic apexes lie
MIDLINE = 0.03
#: m, a line point this near the panel's boundary runs along it
ON_LINE = 0.004
#: m, the least length of an automatic dart after its apex offset: the cut's least
#: (:data:`core.design.darts.MIN_DART_LENGTH`) with 1 cm to spare, as the mouth is placed on the
#: line's geodesics, not at the nearest of its points measured here
MIN_LENGTH = MIN_DART_LENGTH + 0.01


def angle_defect(xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(n,) float, radians: 2 pi minus the triangle angles around each vertex (the integrated
    Gaussian curvature there), 0 on the boundary. ``xyz`` (n, 3) m, ``faces`` (f, 3)."""
    P = xyz[faces]
    total = np.zeros(len(xyz))
    for k in range(3):
        a, b, c = P[:, k], P[:, (k + 1) % 3], P[:, (k + 2) % 3]
        u, v = b - a, c - a
        cos = np.sum(u * v, 1) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1), 1e-300)
        np.add.at(total, faces[:, k], np.arccos(np.clip(cos, -1.0, 1.0)))
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(e, axis=0, return_counts=True)
    on_boundary = np.zeros(len(xyz), bool)
    on_boundary[uniq[count == 1].ravel()] = True
    return np.where(on_boundary, 0.0, 2 * np.pi - total)


def curvature_peaks(xyz: np.ndarray, faces: np.ndarray, count: int, keep=None) -> List[tuple]:
    """Up to ``count`` ``(vertex, theta)``: the local maxima of the angle defect summed within
    :data:`REACH`, above :data:`MIN_THETA`, :data:`SPACING` apart, largest first; ``keep`` (n,) bool
    limits the candidates (e.g. one side of a mirrored design)."""
    from scipy.spatial import cKDTree

    k = angle_defect(xyz, faces)
    tree = cKDTree(xyz)
    near = tree.query_ball_point(xyz, REACH)
    theta = np.array([k[i].sum() for i in near])
    order = np.argsort(-theta, kind="stable")
    out = []
    for i in order.tolist():
        if len(out) >= count or theta[i] < MIN_THETA:
            break
        if keep is not None and not keep[i]:
            continue
        if all(np.linalg.norm(xyz[i] - xyz[j]) >= SPACING for j, _ in out):
            out.append((int(i), float(theta[i])))
    return out


def has_auto(design) -> bool:
    return any(getattr(p, "auto_darts", None) for g in design.garments for p in g.panels)


def place_darts(design, body=None, vertices=None, progress=None):
    """A copy of ``design`` whose automatic-dart panels hold explicit darts (see the module docs).

    Parameters
    ----------
    design : Design with some panel's ``auto_darts`` set.
    body : BodyModel or None (the design's); vertices : (V, 3) the reference instance or None.

    Returns
    -------
    Design: the automatic requests replaced by the placed darts and their apex keypoints
    (``auto_dart_<k>_apex``, where no landmark is near).
    """
    from ..design.resolve import Resolver, instance_vertices
    from . import cut_design

    out = design.copy()
    if not has_auto(out):
        return out
    if body is None:
        from ..body import load_body

        body = load_body(design.body.get("model", "anny"))
    if vertices is None:
        vertices = instance_vertices(design, body)
    plain = design.copy()
    for g in plain.garments:
        for p in g.panels:
            p.auto_darts = None
    cut = cut_design(plain, body=body, progress=progress)
    resolver = Resolver(plain, body, vertices)
    X = cut.positions(vertices)
    lm = body.landmarks
    BF = np.asarray(body.faces)
    n_kp = 0
    for gi, g in enumerate(out.garments):
        for pi, p in enumerate(g.panels):
            req = getattr(p, "auto_darts", None)
            if not req:
                continue
            path = f"garments[{gi}].panels[{pi}].darts"
            panel = cut.panel(f"{g.name}.{p.name}")
            xyz = X[panel.vertex_ids]
            from scipy.spatial import cKDTree

            inner = cKDTree(xyz[np.unique(np.concatenate(panel.boundary))]).query(xyz)[0] >= INSIDE
            # a mirrored design places its *_left darts (the mirror makes the others): no midline dart
            keep = inner & (xyz[:, 0] >= MIDLINE) if out.mirror else inner
            lines = _mouth_lines(resolver, plain, panel, xyz, g.name)
            if not lines:
                raise DesignError(path, f"panel {p.name!r}: no seam or hem line to open a dart on")
            darts: List[Dart] = list(p.darts)
            n_own = len(darts)
            for i, theta in curvature_peaks(xyz, panel.faces, int(req["max_count"]), keep):
                q = xyz[i]
                names = [n for n in APEX_LANDMARKS if n in lm and (n.endswith("_left") or not out.mirror)]
                dist = [np.linalg.norm(lm[n].position(vertices, BF) - q) for n in names]
                if dist and min(dist) <= SNAP_LANDMARK:
                    apex = names[int(np.argmin(dist))]
                    q = lm[apex].position(vertices, BF)
                found = _mouth_line(lines, q)
                if found is None:  # every line too near: the flattening takes this curvature
                    continue
                line, length = found
                if not dist or min(dist) > SNAP_LANDMARK:
                    n_kp += 1
                    # a mirrored design's *_left keypoint: its *_right mirror image is the mirrored dart's apex
                    apex = f"auto_dart_{n_kp}_apex" + ("_left" if out.mirror else "")
                    sp = resolver.locator.locate(q[None])[0]
                    out.set_keypoint(apex, {"triangle": int(sp.triangle), "bary": [float(b) for b in sp.bary]})
                wedge = 2 * length * np.sin(theta / 2)
                intake = float(req["max_intake"]) if wedge > req["max_intake"] else None
                darts.append(
                    Dart(_dart_name(p.name, len(darts) + 1 - n_own, out.mirror), line, apex, intake, APEX_OFFSET)
                )
            p.darts = darts
            p.auto_darts = None
    return out


def _mouth_line(lines: list, q: np.ndarray):
    """``(line name, dart length in m after the apex offset)``: the line of ``lines`` (see
    :func:`_mouth_lines`) nearest to the apex ``q`` whose nearest point, where the cut puts the
    mouth (:func:`core.design.darts.resolve_darts`: the whole line is searched), runs along the
    panel and leaves the dart at least :data:`MIN_LENGTH` long (the cut refuses a shorter one, or
    one whose mouth is off its panel); None when no line does."""
    near = []
    for name, poly, along in lines:
        d = np.linalg.norm(poly - q, axis=1)
        j = int(np.argmin(d))
        if along[j] and d[j] - APEX_OFFSET >= MIN_LENGTH:
            near.append((float(d[j]), name))
    if not near:
        return None
    d, name = min(near)
    return name, d - APEX_OFFSET


def _dart_name(panel: str, k: int, mirror: bool) -> str:
    """The ``k``-th automatic dart's name in ``panel``. In a mirrored design a panel spanning both
    sides names it ``*_left`` (its ``*_right`` counterpart is cut in the same panel); a sided panel
    (``sleeve_back_left``) carries the side in its own name, which the mirror panel's dart swaps
    (``sleeve_back_right_auto_dart_1``)."""
    if mirror and side_of(panel) is None:
        return f"{panel}_auto_dart_{k}_left"
    return f"{panel}_auto_dart_{k}"


def _mouth_lines(resolver, design, panel, xyz, garment: str) -> list:
    """``(line name as the design names it, (k, 3) its points, (k,) bool: the points along the
    panel's boundary, :data:`ON_LINE`)`` for every seam and hem line of ``garment`` (or shared)
    running along the panel; in a mirrored design its ``*_left`` and midline lines only."""
    from scipy.spatial import cKDTree

    edge = np.unique(np.concatenate(panel.boundary)) if panel.boundary else np.arange(len(xyz))
    tree = cKDTree(xyz[edge])
    out = []
    for full, poly in resolver.line_polylines().items():
        gname, _, name = full.rpartition(".")
        if gname not in ("", garment) or (design.mirror and name.endswith("_right")):
            continue
        d, _ = tree.query(poly)
        if np.count_nonzero(d < ON_LINE) >= 3:
            out.append((name, poly, d < ON_LINE))
    return out
