"""Notches: slits cut into the allowance at matching arc lengths on both sides of a seam.

Both sides of a seam get a notch at each end and at the same interior arc
lengths, measured from the nearer end of the seam, so the sewer matches them
stretch by stretch; on a gathered seam the interior notches sit at the same
fractions of each side instead. Measuring from both ends makes the notches
independent of the direction a seam happens to run in: the seams of a
mirrored design (``side_left`` / ``side_right``) get mirror-image notches, and
a seam across the centre line gets notches symmetric about it, so a left and
right piece still print once and a symmetric piece as its half on the fold
(:mod:`.print_set`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..design.materials import NOTCH_SPACING as DEFAULT_NOTCH_SPACING
from ..geom.polygon import ray_hit
from ..geom.polyline import point_at_length, polyline_length
from ..pattern.types import Pattern, PatternPanel
from .boundary import seam_sides

NOTCH_LENGTH = 0.006  # m, slit notch cut into the allowance
# m, half the chord along the seam whose normal an interior slit follows: a notch on a mesh vertex would
# otherwise take one of the two edges' normals, and the mirror image of a piece is not meshed alike
NORMAL_SPAN = 0.01
# notch spacing bounds, m: 0 means notches at the seam ends only; below 5 mm notches would merge
# into one cut (and a seam of 1 m would need 10^9 of them at 1e-9); above 10 m no seam has one
MIN_NOTCH_SPACING = 0.005
MAX_NOTCH_SPACING = 10.0


def check_notch_spacing(value, where: str = "notch_spacing") -> float:
    """``value`` as metres between notches, or ExportError naming ``where``.

    Accepted: 0 (the seam ends only) or a finite number in
    [``MIN_NOTCH_SPACING``, ``MAX_NOTCH_SPACING``] m.
    """
    from ..errors import ExportError

    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ExportError(f"{where}: expected metres between notches, got {value!r}") from None
    if isinstance(value, bool) or not (v == 0 or MIN_NOTCH_SPACING <= v <= MAX_NOTCH_SPACING):
        raise ExportError(
            f"{where}: expected 0 (notches at the seam ends only) or {MIN_NOTCH_SPACING * 1000:g} mm "
            f"to {MAX_NOTCH_SPACING:g} m between notches, got {value!r}"
        )
    return v


@dataclass
class Notch:
    """A slit notch on one side of a seam.

    Attributes
    ----------
    seam : str, the seam name.
    side : ``"a"`` or ``"b"``.
    s : float, arc length (m) along this side of the seam from its first vertex (the notches of the
        seam's second half match those of the other side at equal arc lengths from the last vertex).
    point : (2,) float, the notch position on the sew line (piece frame, m).
    normal : (2,) float, unit outward normal of the sew line there.
    segment : (2, 2) float, the slit: from the cut line inward, ``NOTCH_LENGTH`` long.
    """

    seam: str
    side: str
    s: float
    point: np.ndarray
    normal: np.ndarray
    segment: np.ndarray


def notch_positions(
    length_a: float,
    length_b: float,
    spacing: float = DEFAULT_NOTCH_SPACING,
    gathered: bool = False,
    base: Optional[float] = None,
) -> Tuple[np.ndarray, np.ndarray]:
    """Arc lengths of the notches on the two sides of a seam.

    Both sides get the seam ends and interior notches ``spacing, 2 spacing,
    ...`` measured from *each* end towards the middle of the shorter side,
    stopping ``spacing / 8`` short of it (so no two notches are closer than
    ``spacing / 4``), plus one in the middle where the stretch left there is
    longer than ``1.25 spacing``. The first half's notches lie at the same
    arc lengths from the seam's first vertex on both sides, the second half's
    at the same arc lengths from its last vertex, the middle one at half of
    each side: the difference in length between the sides (the ease the
    sewer works in) falls in the middle stretch. The rule does not depend on
    which end a seam starts from, so a seam and its mirror image get mirrored
    notches whichever way each runs, and a seam that is its own mirror image
    (a waist seam across a front) gets notches symmetric about its middle.
    On a ``gathered`` seam the interior notches sit at the same *fractions*
    of each side (those of the shorter side), so each stretch of the longer
    side is gathered into its own stretch of the shorter.

    Parameters
    ----------
    length_a, length_b : float, the lengths of the two sides, metres.
    spacing : float, metres between interior notches (0: ends only).
    gathered : bool, see above.
    base : float or None, metres: grade from a seam of this length (the shorter side of the
        same seam in a graded nest's sample size): the notches are those of a seam ``base``
        long, their distances from the ends scaled by ``min(length_a, length_b) / base``, so
        every size of a graded nest has the same notches (grade points) in the same order
        and the sample size has exactly its own. None: this seam's own rule.

    Returns
    -------
    s_a, s_b : (k,) float arrays of equal length, metres from each side's first vertex.
    """
    lmin = min(length_a, length_b)
    rule = lmin if base is None else float(base)
    head, middle = [], []
    if spacing > 0:
        k = 1
        while k * spacing <= 0.5 * rule - 0.125 * spacing:
            head.append(k * spacing)
            k += 1
        if rule - 2 * len(head) * spacing > 1.25 * spacing:
            middle = [0.5]
    head = np.array(head)
    if base is not None and rule > 0:
        head = head * (lmin / rule)

    def side(length: float) -> np.ndarray:
        if gathered and lmin > 0:
            return np.concatenate(
                [[0.0], head / lmin * length, np.array(middle) * length, length - head[::-1] / lmin * length, [length]]
            )
        return np.concatenate([[0.0], head, np.array(middle) * length, length - head[::-1], [length]])

    return side(length_a), side(length_b)


def piece_notches(
    pattern: Pattern,
    panel: PatternPanel,
    xy: np.ndarray,
    loops: List[np.ndarray],
    table: Dict[Tuple[int, int], Tuple[int, int]],
    edge_w: List[np.ndarray],
    cut: List[np.ndarray],
    spacing: float = DEFAULT_NOTCH_SPACING,
    grade_from: Optional[Mapping[str, float]] = None,
) -> List[Notch]:
    """The notches of every seam side on one piece, in seam order.

    Each slit starts on the cut line straight out from the notch point and
    runs ``NOTCH_LENGTH`` inward (shorter where the allowance is narrower);
    on an edge without allowance it straddles the sew line.

    Parameters
    ----------
    pattern, panel : the pattern and the piece.
    xy : (n, 2) float, the piece's vertices in the piece frame, metres.
    loops, table : the piece's loops and edge table (:mod:`core.export.boundary`).
    edge_w : list of (k,) float, allowance per sew edge (m).
    cut : list of (m, 2) float, the cut line of each loop (piece frame, m).
    spacing : float, metres between interior notches (see :func:`notch_positions`).
    grade_from : seam name -> the sample size's seam length (:func:`seam_lengths`) in a graded
        nest: each seam's notches are graded from it (``base`` of :func:`notch_positions`).
    """
    notches: List[Notch] = []
    for seam, side, ids in seam_sides(pattern, panel.name):
        other = pattern.panel(seam.panel_b if side == "a" else seam.panel_a)
        other_ids = np.asarray(seam.verts_b if side == "a" else seam.verts_a, int)
        la = polyline_length(xy[ids])
        lb = polyline_length(np.asarray(other.uv, float)[other_ids])
        s_here, _ = notch_positions(
            la,
            lb,
            spacing,
            gathered=bool(getattr(seam, "gathered", False)),
            base=None if grade_from is None else grade_from.get(seam.name),
        )
        pts, edges, _ = point_at_length(xy[ids], s_here)
        for i, (s, q, e) in enumerate(zip(s_here, pts, edges)):
            li, ei = table[(int(ids[e]), int(ids[e + 1]))]
            b = loops[li]
            # the edge's outward normal; a zero-length edge borrows its neighbour's
            for k in (0, 1, -1, 2, -2):
                d = xy[b[(ei + k + 1) % len(b)]] - xy[b[(ei + k) % len(b)]]
                if np.linalg.norm(d) > 1e-12:
                    break
            nrm = np.array([d[1], -d[0]]) / max(np.linalg.norm(d), 1e-300)
            if 0 < i < len(s_here) - 1:
                nrm = _chord_normal(xy[ids], s, nrm)
            notches.append(
                Notch(
                    seam=seam.name,
                    side=side,
                    s=float(s),
                    point=q,
                    normal=nrm,
                    segment=slit(q, nrm, cut[li], edge_w[li][ei]),
                )
            )
    return notches


def seam_lengths(pattern: Pattern) -> Dict[str, float]:
    """Seam name -> the length (m) of its shorter side, the length :func:`notch_positions` places
    notches by (darts left out, as in :func:`core.export.boundary.seam_sides`)."""
    out = {}
    for seam in pattern.seams:
        if seam.kind == "dart":
            continue
        sides = [(seam.panel_a, seam.verts_a), (seam.panel_b, seam.verts_b)]
        out[seam.name] = min(
            polyline_length(np.asarray(pattern.panel(p).uv, float)[np.asarray(ids, int)]) for p, ids in sides
        )
    return out


def _chord_normal(side: np.ndarray, s: float, edge_normal: np.ndarray) -> np.ndarray:
    """(2,) unit normal of the chord of the seam side ``side`` (k, 2) from arc length ``s - NORMAL_SPAN`` to
    ``s + NORMAL_SPAN``, turned to the side of ``edge_normal`` (the outward normal of the edge at ``s``).

    An interior notch's slit follows it rather than the edge's normal, so that a
    notch at the middle of a symmetric seam points along the axis and a seam's
    mirror image (meshed differently) gets the mirrored slit.
    """
    (a, b), _, _ = point_at_length(side, [s - NORMAL_SPAN, s + NORMAL_SPAN])
    d = b - a
    length = float(np.linalg.norm(d))
    if length <= 1e-12:
        return edge_normal
    nrm = np.array([d[1], -d[0]]) / length
    return nrm if float(nrm @ edge_normal) >= 0 else -nrm


def slit(q: np.ndarray, nrm: np.ndarray, cut_loop: np.ndarray, width: float) -> np.ndarray:
    """(2, 2) the slit of a notch at sew-line point ``q`` (2,) with outward unit normal ``nrm``:
    from the cut line ``cut_loop`` (m, 2) straight out from ``q`` inward, ``NOTCH_LENGTH`` long
    (shorter where the allowance is narrower); on an edge without allowance it straddles the
    sew line. ``width``: the edge's allowance (m), where the ray misses the cut line."""
    t_cut = ray_hit(q, nrm, cut_loop)
    t_cut = width if t_cut is None else t_cut
    a0 = q + t_cut * nrm
    if t_cut > 0:
        return np.stack([a0, a0 - min(NOTCH_LENGTH, max(t_cut, 1e-4) * 0.9 + 1e-4) * nrm])
    return np.stack([q + 0.5 * NOTCH_LENGTH * nrm, q - 0.5 * NOTCH_LENGTH * nrm])
