"""An EASE pattern as a GarmentCode pattern specification (``specification.json``).

GarmentCode (Korosteleva & Sorkine-Hornung 2023) and GarmentCodeData store a
pattern as ``{"pattern": {"panels": {...}, "stitches": [...], "panel_order":
[...]}, "properties": {...}, "parameters": {}, "parameter_order": []}``; a
panel has 2D ``vertices`` (cm), ``edges`` (``{"endpoints": [i, j]}``, a
closed loop) and a 3D placement ``translation`` (cm) / ``rotation`` (Euler
angles, degrees); a stitch is a pair ``[{"panel", "edge"}, {"panel", "edge"}]``.

GarmentCode's conventions, as its code has them (``pygarment``):

- rotation: ``rotation.euler_xyz_to_R`` composes ``Rz @ Ry @ Rx`` (Maya's XYZ
  order), which the simulator's mesher (``BoxMesh``) applies to each panel:
  scipy's *extrinsic* ``"xyz"``, not the intrinsic ``"XYZ"``;
- units: centimetres (``units_in_meter: 100``);
- origin: its bodies stand on ``y = 0``, Y up, facing +Z;
- loops: ``normalized_edge_loops: true`` means each edge loop starts at the
  vertex nearest to the lower-left corner of the panel's bounding box
  (``_vert_at_left_corner``) and runs counter-clockwise.

Mapping (see docs/batch.md for its limits):

- a piece's outline (:func:`core.export.boundary.piece_loops`, the first loop,
  counter-clockwise) becomes the panel, simplified to within
  :data:`TOLERANCE` (Douglas-Peucker between kept vertices): the ends of
  every seam, the corners (a turn over :data:`CORNER_DEG`) and the vertex
  nearest to each notch (:func:`core.export.notches.notch_positions`) are
  kept, and a vertex kept on one side of a seam keeps its partner on the
  other, so each stitch still pairs corresponding stretches; kept corners and
  notches closer than :data:`MIN_EDGE` to a vertex kept before them are
  dropped (GarmentCode's mesher refuses the degenerate triangles that edges of
  a few hundredths of a millimetre make); holes are left out (GarmentCode
  panels have none);
- a seam of ``k`` simplified segments becomes ``k`` stitches, segment ``i`` of
  side a with segment ``i`` of side b (EASE's seam correspondence);
- the placement is the rigid motion that best carries the flat piece onto its
  position on the body (Kabsch), in GarmentCode's frame: Y up, the body
  facing +Z, centimetres, the floor (the body's lowest point) at ``y = 0``
  (ours: Z up, facing -Y, metres, the origin at the body's root).
"""

from __future__ import annotations

from typing import Dict, List, Optional, Tuple

import numpy as np

#: Our frame (x, y, z) -> GarmentCode's (x, z, -y): a rotation (Z up -> Y up, front -Y -> +Z).
TO_GARMENTCODE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

CM = 100.0
#: m: the simplified outline stays this close to the solved one.
TOLERANCE = 0.0005
#: m: a corner or notch vertex this close to a vertex kept before it is left out.
MIN_EDGE = 0.002
#: degrees: an outline vertex turning more than this is a corner (kept).
CORNER_DEG = 20.0


def euler_to_matrix(angles_deg) -> np.ndarray:
    """(3, 3) GarmentCode's rotation of Euler ``angles_deg`` (x, y, z): ``Rz @ Ry @ Rx``."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("xyz", np.asarray(angles_deg, float), degrees=True).as_matrix()


def matrix_to_euler(R: np.ndarray) -> np.ndarray:
    """(3,) degrees: the Euler angles GarmentCode reads as ``R`` (:func:`euler_to_matrix`)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(R).as_euler("xyz", degrees=True)


def placement(uv: np.ndarray, xyz: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Rigid motion (R (3, 3), t (3,)) with ``xyz ≈ R @ [uv, 0] + t`` in the least-squares sense.

    Parameters
    ----------
    uv : (n, 2) piece-local 2D positions; xyz : (n, 3) the same vertices in 3D.
    """
    P = np.column_stack([uv, np.zeros(len(uv))])
    cp, cq = P.mean(axis=0), xyz.mean(axis=0)
    U, _, Vt = np.linalg.svd((P - cp).T @ (xyz - cq))
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return R, cq - R @ cp


def left_corner(vertices: np.ndarray) -> int:
    """GarmentCode's loop origin: the vertex nearest to the lower-left corner of the bounding box."""
    v = np.asarray(vertices, float)
    return int(np.argmin(np.linalg.norm(v - v.min(axis=0), axis=1)))


def _outlines(pattern) -> Dict[str, np.ndarray]:
    from ..export.boundary import piece_loops

    return {p.name: piece_loops(p)[0] for p in pattern.panels}


def _anchors(pattern, loops: Dict[str, np.ndarray]) -> Tuple[Dict[str, set], Dict[str, set]]:
    """Per panel, the local vertex ids that must stay (seam ends) and those kept where not too close to another
    (corners, the vertex nearest to each notch)."""
    from ..export.notches import notch_positions
    from ..export.pieces import resolve_notch_spacing
    from ..geom.polygon import turn_points
    from ..geom.polyline import cumulative_lengths, polyline_length

    spacing = resolve_notch_spacing(None, pattern)
    must = {name: set() for name in loops}
    soft = {
        name: {int(loop[i]) for i in turn_points(np.asarray(pattern.panel(name).uv, float)[loop], CORNER_DEG)}
        for name, loop in loops.items()
    }
    for s in pattern.seams:
        sides = [(s.panel_a, np.asarray(s.verts_a, int)), (s.panel_b, np.asarray(s.verts_b, int))]
        lengths = [polyline_length(np.asarray(pattern.panel(p).uv, float)[ids]) for p, ids in sides]
        arcs = notch_positions(lengths[0], lengths[1], spacing, gathered=bool(getattr(s, "gathered", False)))
        along = []
        for p, ids in sides:
            must[p] |= {int(ids[0]), int(ids[-1])}
            along.append(cumulative_lengths(np.asarray(pattern.panel(p).uv, float)[ids]))
        # one seam vertex pair per notch, nearest to it on both sides together: the nearest on each side alone
        # can be neighbours (a notch between two vertices), and with their partners kept too the outline got
        # stitched segments under a millimetre, where GarmentCode's mesher makes degenerate triangles
        for ta, tb in zip(*arcs):
            i = int(np.argmin(np.abs(along[0] - ta) + np.abs(along[1] - tb)))
            soft[sides[0][0]].add(int(sides[0][1][i]))
            soft[sides[1][0]].add(int(sides[1][1][i]))
    return must, soft


def simplified_outlines(pattern, tol: float = TOLERANCE, min_edge: float = MIN_EDGE) -> Dict[str, np.ndarray]:
    """Per panel, the outline's local vertex ids kept (in loop order, see the module docstring)."""
    from ..geom.polyline import simplify_indices

    loops = _outlines(pattern)
    must, soft = _anchors(pattern, loops)
    kept: Dict[str, set] = {}
    for name, loop in loops.items():
        uv = np.asarray(pattern.panel(name).uv, float)
        anchors = set(must[name]) or {int(loop[0])}
        for v in [int(x) for x in loop if int(x) in soft[name] and int(x) not in must[name]]:
            if all(np.linalg.norm(uv[v] - uv[a]) >= min_edge for a in anchors):
                anchors.add(v)
        pos = sorted(i for i, v in enumerate(loop) if int(v) in anchors)
        keep = set()
        for a, b in zip(pos, pos[1:] + [pos[0] + len(loop)]):
            run = [int(loop[i % len(loop)]) for i in range(a, b + 1)]
            keep |= {run[i] for i in simplify_indices(uv[run], tol)}
        kept[name] = keep
    # a vertex kept on one side of a seam keeps its partner on the other (same index along the seam)
    partners: Dict[Tuple[str, int], List[Tuple[str, int]]] = {}
    for s in pattern.seams:
        a, b = np.asarray(s.verts_a, int), np.asarray(s.verts_b, int)
        both = [i for i in range(len(a)) if int(a[i]) in kept[s.panel_a] or int(b[i]) in kept[s.panel_b]]
        kept[s.panel_a] |= {int(a[i]) for i in both}
        kept[s.panel_b] |= {int(b[i]) for i in both}
        for u, v in zip(a.tolist(), b.tolist()):
            partners.setdefault((s.panel_a, u), []).append((s.panel_b, v))
            partners.setdefault((s.panel_b, v), []).append((s.panel_a, u))
    _drop_close(pattern, loops, kept, must, partners, min_edge)
    return {name: np.array([int(v) for v in loop if int(v) in kept[name]]) for name, loop in loops.items()}


def _drop_close(pattern, loops, kept, must, partners, min_edge: float) -> None:
    """Leave out (in place) a kept vertex closer than ``min_edge`` to the kept vertex before it, with its seam
    partners: the simplified outlines of a seam's two sides keep the same seam indices, and neither has an edge
    under ``min_edge`` (Douglas-Peucker or a corner on one side and its partner kept for the other side can make
    neighbours a fraction of a millimetre apart, and GarmentCode's mesher makes degenerate triangles there).
    Seam ends stay."""
    uv = {p.name: np.asarray(p.uv, float) for p in pattern.panels}
    changed = True
    while changed:
        changed = False
        for name, loop in loops.items():
            ids = [int(v) for v in loop if int(v) in kept[name]]
            for u, v in zip(ids, ids[1:] + ids[:1]):
                if np.linalg.norm(uv[name][u] - uv[name][v]) >= min_edge:
                    continue
                victim = v if v not in must[name] else (u if u not in must[name] else None)
                if victim is None:
                    continue
                kept[name].discard(victim)
                for other, w in partners.get((name, victim), []):
                    kept[other].discard(w)
                changed = True
                break


def _floor(pattern) -> float:
    """m, our z of the lowest point of the body ``pattern`` was made on (its ``body`` record)."""
    from ..body.instance import spec_instance

    V, _ = spec_instance(pattern.body or {})
    return float(np.min(V[:, 2]))


def _panel(panel, ids: np.ndarray, floor: float) -> Tuple[dict, Dict[Tuple[int, int], int]]:
    uv = np.asarray(panel.uv, float)
    start = left_corner(uv[ids])
    ids = np.roll(ids, -start)  # the loop from GarmentCode's own origin vertex
    origin = uv[ids].min(axis=0)  # GarmentCode panels sit in their own frame, here from the lower left
    local = (uv - origin) * CM
    xyz = (np.asarray(panel.xyz, float)[ids] - [0.0, 0.0, floor]) * CM @ TO_GARMENTCODE.T
    R, t = placement(local[ids], xyz)
    n = len(ids)
    edges = {}
    for e in range(n):
        u, v = int(ids[e]), int(ids[(e + 1) % n])
        edges[(u, v)] = edges[(v, u)] = e
    spec = {
        "vertices": [[round(float(x), 4), round(float(y), 4)] for x, y in local[ids]],
        "edges": [{"endpoints": [e, (e + 1) % n]} for e in range(n)],
        "translation": [round(float(x), 4) for x in t],
        "rotation": [round(float(a), 4) for a in matrix_to_euler(R)],
    }
    return spec, edges


def specification(pattern, floor: Optional[float] = None) -> dict:
    """The GarmentCode pattern specification of ``pattern`` (a JSON-ready dict).

    ``floor``: our z (m) of the body's lowest point, the ``y = 0`` of GarmentCode's frame; None: from the
    pattern's body record (one body instance).
    """
    floor = _floor(pattern) if floor is None else float(floor)
    outlines = simplified_outlines(pattern)
    panels, edge_of = {}, {}
    for p in pattern.panels:
        panels[p.name], edge_of[p.name] = _panel(p, outlines[p.name], floor)
    stitches: List[list] = []
    for s in pattern.seams:
        a, b = np.asarray(s.verts_a, int), np.asarray(s.verts_b, int)
        kept_a, kept_b = set(outlines[s.panel_a].tolist()), set(outlines[s.panel_b].tolist())
        on = [i for i in range(len(a)) if int(a[i]) in kept_a and int(b[i]) in kept_b]
        for i, j in zip(on, on[1:]):
            ea = edge_of[s.panel_a].get((int(a[i]), int(a[j])))
            eb = edge_of[s.panel_b].get((int(b[i]), int(b[j])))
            if ea is not None and eb is not None:  # both segments on the outlines (holes are left out)
                stitches.append([{"panel": s.panel_a, "edge": ea}, {"panel": s.panel_b, "edge": eb}])
    return {
        "pattern": {"panels": panels, "stitches": stitches, "panel_order": [p.name for p in pattern.panels]},
        "parameters": {},
        "parameter_order": [],
        "properties": {
            "curvature_coords": "relative",
            "normalize_panel_translation": False,
            "units_in_meter": 100,
            "normalized_edge_loops": True,
            "source": "EASE",
            "style": pattern.style,
        },
    }
