"""The darts of a cut: each dart line's seam checked to be one seam of its panel with
itself, and the record the pattern and export stages read (:attr:`GarmentCut.darts`).

A dart line runs from its mouth (on a seam or hem line) to its sewn point inside
the panel; :func:`core.cut.panels.build_panels` makes it a seam whose two sides are
the dart's legs, sharing the apex vertex (:func:`core.cut.types.seam_kind`).
"""

from __future__ import annotations

from typing import Dict, List

import numpy as np
from scipy.sparse import csr_matrix as sp_csr

from ..design.naming import swap_side
from ..errors import DesignError
from ..geom.polyline import cumulative_lengths
from .types import Seam, seam_kind


def dart_records(spec, seams: List[Seam], body_vertices: np.ndarray, body_faces: np.ndarray) -> Dict[str, dict]:
    """``{dart seam name: record}`` for every dart line of ``spec`` (see :attr:`GarmentCut.darts`).

    Raises
    ------
    DesignError, at the dart's JSON path, when its line does not give one dart seam in its
    own panel: it leaves the panel (crosses another cut line, or its apex lies in another
    panel) or its mouth is not on the panel's boundary.
    """
    out = {}
    for line in spec.lines:
        d = getattr(line, "dart", None)
        if d is None:
            continue
        mine = [s for s in seams if s.name == line.name or s.name.startswith(line.name + "#")]
        panels = sorted({p for s in mine for p in (s.panel_a, s.panel_b)})
        if len(mine) != 1 or panels != [d.panel] or seam_kind(mine[0]) != "dart":
            where = (
                f"it runs through panels {', '.join(panels)}"
                if panels and panels != [d.panel]
                else f"it gives {len(mine)} stretches"
                if len(mine) != 1
                else f"its mouth is not on the edge of panel {d.panel!r} (line {d.host!r})"
            )
            raise DesignError(
                d.path,
                f"dart {d.name!r} is off its panel {d.panel!r}: {where}; a dart runs from "
                "a seam or hem of its panel to an apex inside it, crossing no other line",
            )
        apex = np.asarray(d.apex.position(body_vertices, body_faces), float)
        out[line.name] = {
            "panel": d.panel,
            "intake": d.intake,
            "apex_offset": float(d.apex_offset),
            "apex": apex,
            "line": d.host,
            **_cup_record(getattr(d, "towards", None), apex, body_vertices, body_faces),
        }
    return out


def midline_guards(lines, mirror) -> Dict[int, frozenset]:
    """``{line index: body vertices}`` the tracer must not snap the line to: for every dart line of a
    mirrored cut with its mirror dart (``*_left`` / ``*_right``), the body's midline vertices (their own
    mirror images). The cut rebuilds a mirrored garment's right half as the reflection of its left
    (:mod:`.symmetric`), so a left dart through a midline vertex meets its mirror there and the line
    gives two stretches: on men:XXL the four-dart blouse's neckline darts, from one mouth at the centre
    front, passed 0.4-0.5 mm from the sternum's midline vertex 1.5 mm below it, within the tracer's
    sliver snap (:data:`core.cut.trace.SNAP_ABS`). Only such a snap is refused (a crossing still
    splits its edge there), so a cut where no dart snaps to the midline is unchanged.

    ``mirror``: ``(body symmetry (V,), body triangle sides)`` as the cut engine has it, or None."""
    if mirror is None:
        return {}
    S = np.asarray(mirror[0], dtype=np.int64)
    mid = frozenset(np.flatnonzero(S == np.arange(len(S))).tolist())
    names = {line.name for line in lines}
    out = {}
    for i, line in enumerate(lines):
        if getattr(line, "dart", None) is None:
            continue
        other = swap_side(line.name)
        if other != line.name and other in names:
            out[i] = mid
    return out


# ---------------------------------------------------------------- the apex follows the cup

#: The landmarks a dart's apex follows onto another body, with the direction their rule picks the
#: vertex along (core.body.landmarks: a bust point is the torso's most anterior vertex on its side,
#: a seat or shoulder blade the most posterior one; -y is the front).
CUP_AXES = {
    "bust_left": (0.0, -1.0, 0.0),
    "bust_right": (0.0, -1.0, 0.0),
    "seat_left": (0.0, 1.0, 0.0),
    "seat_right": (0.0, 1.0, 0.0),
    "shoulder_blade_left": (0.0, 1.0, 0.0),
    "shoulder_blade_right": (0.0, 1.0, 0.0),
}
#: m, the body region (on the reference) whose surface carries the move: the body faces within this
#: distance of the apex (measured on the four-dart blouse transferred to women:L: 0.07 / 0.10 / 0.14 /
#: 0.18 / 0.24 m read bust region 4.19 / 2.61 / 2.23 / 2.36 / 12.7 %)
CUP_REACH = 0.14
#: m, the landmark's rule re-applied within this distance of the apex carried onto the other body
CUP_SEARCH = 0.05


def _cup_record(towards, apex, X, BF) -> dict:
    """``{"cup_axis", "cup_disk"}`` of a dart towards a landmark of :data:`CUP_AXES`: the direction of
    its rule and the body faces (k, 3) within :data:`CUP_REACH` of the apex, one disk around it; ``{}``
    for any other dart (it stays where the cut's embedding carries it)."""
    if towards not in CUP_AXES:
        return {}
    F = np.asarray(BF)
    inside = np.flatnonzero(np.all(np.linalg.norm(X[F] - apex, axis=2) < CUP_REACH, axis=1))
    if not len(inside):
        return {}
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    # the faces around the apex joined through their vertices: the component of the apex's nearest face
    vids, local = np.unique(F[inside], return_inverse=True)
    local = local.reshape(-1, 3)
    rows = np.repeat(np.arange(len(inside)), 3)
    incidence = sp.csr_matrix((np.ones(rows.size), (rows, local.ravel())), shape=(len(inside), len(vids)))
    _, label = connected_components(incidence @ incidence.T, directed=False)
    near = int(np.argmin(np.linalg.norm(X[F[inside]].mean(axis=1) - apex, axis=1)))
    disk = F[inside[label == label[near]]]
    if _boundary_loop(disk) is None:  # not one disk (a hole, a pinch): no move
        return {}
    return {"cup_axis": np.asarray(CUP_AXES[towards], float), "cup_disk": disk}


def _boundary_loop(F: np.ndarray):
    """The boundary vertices of the triangle mesh ``F`` (k, 3) in order, when it is one loop; else None."""
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    _, inv, count = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True)
    half = e[count[inv.ravel()] == 1]
    nxt = dict(zip(half[:, 0].tolist(), half[:, 1].tolist()))
    if not len(half) or len(nxt) != len(half):
        return None
    loop = [int(half[0, 0])]
    while len(loop) <= len(half):
        v = nxt[loop[-1]]
        if v == loop[0]:
            break
        loop.append(v)
    return np.array(loop) if len(loop) == len(half) else None


def follow_cups(cut, ref_vertices: np.ndarray, target_vertices: np.ndarray, at_offsets: bool = False) -> np.ndarray:
    """The cut's positions (N, 3) on ``target_vertices`` with each dart's apex region moved to follow
    the cup: a dart towards a landmark of :data:`CUP_AXES` ends where that landmark's rule puts it on the
    target body (the most anterior vertex of the bust within :data:`CUP_SEARCH` of the carried apex),
    as it ends at the landmark on the reference. The embedding carries the landmark's mesh vertex, which
    on another body can lie off the cup (women:L: the carried bust point 30 mm medial of L's most
    anterior point; women:M, XS: on it). The move is smooth and stays on the body: the apex's disk
    (``cup_disk``) is mapped to the unit disk (harmonic, cotangent weights), the panel's vertices in it
    are shifted there by the apex's move times a weight falling from 1 at the apex to 0 (C1) before the
    panel's outer edges, and mapped back to the body. Both legs of a dart share their body points, so
    they move alike. Other darts, and the cut's other panels, keep the embedding's positions.

    ``at_offsets``: the darts re-drafted on the target's cup end at the design's apex offsets from its
    bust point (:func:`_sewn_at_offsets`), as the cut ends them from the reference's; the move alone
    leaves the sewn points short of where the cup moved (women:L: 7.7-12.7 mm from the cup, offsets
    5 and 7.5 mm). The cup rule's regrade (:func:`core.pattern.solve.transfer_pattern`) asks for it."""
    X0 = np.asarray(ref_vertices, float)
    X1 = np.asarray(target_vertices, float)
    pos = cut.positions(X1)
    done = set()
    for rec in (getattr(cut, "darts", None) or {}).values():
        if "cup_disk" not in rec:
            continue
        key = (rec["panel"], tuple(np.round(np.asarray(rec["apex"], float), 9)))
        if key in done:  # darts sharing an apex move together, once
            continue
        done.add(key)
        moved = _cup_move(cut, rec, X0, X1, at_offsets)
        if moved is not None:
            ids, P = moved
            pos[ids] = P
    return pos


def _cup_move(cut, rec: dict, X0: np.ndarray, X1: np.ndarray, at_offsets: bool = False):
    """``(global vertex ids, (k, 3) positions)`` of the panel's vertices :func:`follow_cups` moves for the
    apex of ``rec``, or None when the cup is where the embedding carries the apex (``at_offsets``: the
    sewn points then put at their apex offsets from the cup, :func:`_sewn_at_offsets`)."""
    import igl

    from ..design.geometry import SurfaceLocator

    F = np.asarray(rec["cup_disk"], dtype=np.int64)  # lists when the cut was read from its file
    vids, local = np.unique(F, return_inverse=True)
    local = local.reshape(-1, 3)
    axis, apex = np.asarray(rec["cup_axis"], float), np.asarray(rec["apex"], float)
    # the landmark's rule on each body, near the apex (on the target: near the vertex nearest it on the reference)
    near0 = np.flatnonzero(np.linalg.norm(X0[vids] - apex, axis=1) < CUP_SEARCH)
    if not len(near0):
        return None
    at = X1[vids[near0[np.argmin(np.linalg.norm(X0[vids[near0]] - apex, axis=1))]]]
    near1 = np.flatnonzero(np.linalg.norm(X1[vids] - at, axis=1) < CUP_SEARCH)
    cup0 = int(near0[np.argmax(X0[vids[near0]] @ axis)])
    cup1 = int(near1[np.argmax(X1[vids[near1]] @ axis)])
    if cup0 == cup1:
        return None
    loop = _boundary_loop(local)
    arc = cumulative_lengths(X1[vids[loop]], closed=True)  # back at the first point: the loop's length last
    t = 2 * np.pi * arc[:-1] / arc[-1]
    U = igl.harmonic(
        np.ascontiguousarray(X1[vids]),
        np.ascontiguousarray(local, dtype=np.int64),
        np.ascontiguousarray(loop, dtype=np.int64),
        np.ascontiguousarray(np.c_[np.cos(t), np.sin(t)]),
        1,
    )
    c0, shift = U[cup0], U[cup1] - U[cup0]
    panel = cut.panel(rec["panel"])
    ids = np.asarray(panel.vertex_ids)
    # the panel's vertices in the disk, at their images there (rows of the embedding inside the disk)
    to_disk = np.full(X1.shape[0], -1)
    to_disk[vids] = np.arange(len(vids))
    E = cut.embedding[ids].tocsr()
    row = np.repeat(np.arange(len(ids)), np.diff(E.indptr))
    inside = (np.bincount(row, to_disk[E.indices] < 0, minlength=len(ids)) == 0) & (np.diff(E.indptr) > 0)
    if not inside.any():
        return None
    D = E[inside]
    img = np.asarray(sp_csr((D.data, to_disk[D.indices], D.indptr), shape=(D.shape[0], len(vids))) @ U)
    # the weight falls to 0 before the panel's edges other than its darts' legs (they stay where they are)
    legs = {int(v) for s in cut.seams if s.kind == "dart" and s.panel_a == panel.name for v in (*s.verts_a, *s.verts_b)}
    edge = np.array([v for v in np.unique(np.concatenate(panel.boundary)) if int(v) not in legs], int)
    pos_in = np.full(len(ids), -1)
    pos_in[np.flatnonzero(inside)] = np.arange(int(inside.sum()))
    edge_img = img[pos_in[edge[pos_in[edge] >= 0]]] if len(edge) else np.zeros((0, 2))
    rho = 0.9 * min(
        1.0 - float(np.linalg.norm(c0)), float(np.min(np.linalg.norm(edge_img - c0, axis=1))) if len(edge_img) else 1.0
    )
    if rho <= 0:
        return None
    # a shift under rho / 1.5 keeps the map one-to-one (|grad w| <= 1.5 / rho): at most 0.8 of that
    size = float(np.linalg.norm(shift))
    shift = shift * min(1.0, 0.8 * rho / (1.5 * size))
    s = np.linalg.norm(img - c0, axis=1) / rho
    w = np.where(s < 1.0, (1.0 - s) ** 2 * (1.0 + 2.0 * s), 0.0)
    Z, move = img + w[:, None] * shift, w > 0
    locator = SurfaceLocator(np.c_[U, np.zeros(len(U))], local)

    def on_body(Q):  # disk images -> body points
        _, tri, bary = locator.closest(np.c_[Q, np.zeros(len(Q))])
        return np.einsum("ij,ijk->ik", bary, X1[vids[local[tri]]])

    if at_offsets:
        tips, offsets = _sewn_points(cut, panel.name, np.asarray(rec["apex"], float))
        tips = pos_in[tips]
        if len(tips) and (tips >= 0).all():
            # the scaling stays short of the disk's rim and of the panel's edges other than its darts' legs
            free = edge[pos_in[edge] >= 0] if len(edge) else edge
            reach = 1.0 - float(np.linalg.norm(U[cup1]))
            if len(free):
                reach = min(reach, float(np.min(np.linalg.norm(Z[pos_in[free]] - U[cup1], axis=1))))
            Z, within = _sewn_at_offsets(Z, U[cup1], X1[vids[cup1]], tips, offsets, on_body, 0.9 * reach)
            move |= within
    if not move.any():
        return None
    return ids[np.flatnonzero(inside)[move]], on_body(Z[move])


def _sewn_points(cut, panel: str, apex: np.ndarray):
    """``(panel-local vertex ids, apex offsets m)`` of the sewn points of ``panel``'s darts towards ``apex``."""
    tips, offsets = [], []
    for seam in cut.seams:
        rec = (cut.darts or {}).get(seam.name)
        if seam.kind == "dart" and seam.panel_a == panel and rec is not None and np.allclose(rec["apex"], apex):
            tips.append(int(seam.verts_a[-1]))
            offsets.append(float(rec["apex_offset"]))
    return np.asarray(tips, dtype=np.int64), np.asarray(offsets, float)


#: the rounds of :func:`_sewn_at_offsets` (the disk map is not an isometry: each round measures again on the body)
OFFSET_ROUNDS = 3
#: the radial scaling of :func:`_sewn_at_offsets` fades out at this many times the sewn points' farthest image
#: radius (women:L, bust region: 3 / 4 / 6 read 1.64 / 1.60 / 1.73 %, docs/darts.md "Graded to L")
OFFSET_FADE = 4.0


def _sewn_at_offsets(Z, centre, cup, tips, offsets, on_body, limit: float):
    """The disk images ``Z`` (k, 2) scaled radially about the cup's image ``centre`` so that the sewn points
    (rows ``tips``) end at their apex ``offsets`` (m) from the body point ``cup``: a pattern maker ends a
    re-drafted dart its offset from the new bust point. One factor for the apex (the mean of offset over
    distance, measured on the body through ``on_body``), :data:`OFFSET_ROUNDS` rounds; the factor fades to 1
    (C1, monotone in the radius, so the map stays one-to-one for a factor under 2.5) at
    :data:`OFFSET_FADE` times the sewn points' farthest radius, at most ``limit`` (short of the panel's edges
    other than its darts' legs). Returns ``(Z, the rows moved)``."""
    moved = np.zeros(len(Z), bool)
    for _ in range(OFFSET_ROUNDS):
        k = float(np.mean(offsets / np.linalg.norm(on_body(Z[tips]) - cup, axis=1)))
        r = np.linalg.norm(Z - centre, axis=1)
        fade = min(OFFSET_FADE * float(r[tips].max()), limit)
        if not 0.0 < k < 2.5 or fade <= 0.0:
            break
        t = np.clip(r / fade, 0.0, 1.0)
        Z = centre + (Z - centre) * (k + (1.0 - k) * t * t * (3.0 - 2.0 * t))[:, None]
        moved |= r < fade
    return Z, moved


# ---------------------------------------------------------------- a bigger cup: the darts re-derived

#: m, a cup's size: the angle defect (integrated Gaussian curvature) of the body within this distance of the
#: apex the embedding carries, inside the dart's cup disk. Measured on the women's chart (the four-dart
#: blouse's bust, rad): XS 0.26, S 0.45, M 0.56, L 1.58, XL 1.14 (within 6 cm S 0.79 read over M's 0.77)
CUP_SIZE_RADIUS = 0.10


def _cup_defect(rec: dict, X0: np.ndarray, X: np.ndarray) -> float:
    """The angle defect (rad) of body ``X`` over the interior vertices of ``rec``'s cup disk within
    :data:`CUP_SIZE_RADIUS` of the disk vertex nearest the dart's apex on the reference body ``X0``."""
    from .auto_darts import angle_defect

    F = np.asarray(rec["cup_disk"], dtype=np.int64)
    vids, local = np.unique(F, return_inverse=True)
    P = X[vids]
    defect = angle_defect(P, local.reshape(-1, 3))  # 0 on the disk's boundary
    centre = P[int(np.argmin(np.linalg.norm(X0[vids] - np.asarray(rec["apex"], float), axis=1)))]
    return float(defect[np.linalg.norm(P - centre, axis=1) < CUP_SIZE_RADIUS].sum())


def bigger_cups(cut, ref_vertices: np.ndarray, target_vertices: np.ndarray) -> bool:
    """Whether the target body's cups are bigger than the reference's: the angle defect near the apexes of
    the cut's darts towards a landmark of :data:`CUP_AXES` (each apex once, :func:`_cup_defect`), summed,
    exceeds the reference body's. False for a cut with no such dart."""
    X0, X1 = np.asarray(ref_vertices, float), np.asarray(target_vertices, float)
    seen, ref, tgt = set(), 0.0, 0.0
    for rec in (getattr(cut, "darts", None) or {}).values():
        key = tuple(np.round(np.asarray(rec["apex"], float), 9))
        if "cup_disk" not in rec or key in seen:
            continue
        seen.add(key)
        ref += _cup_defect(rec, X0, X0)
        tgt += _cup_defect(rec, X0, X1)
    return bool(seen) and tgt > ref


def with_auto_intakes(cut):
    """A shallow copy of ``cut`` whose darts all open as the flattening opens them (every intake ``"auto"``:
    no set intake held at the mouth); the cut itself is unchanged."""
    import copy

    out = copy.copy(cut)
    out.darts = {k: {**v, "intake": None} for k, v in (cut.darts or {}).items()}
    return out
