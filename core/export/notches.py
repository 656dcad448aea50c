"""Notches: slits cut into the allowance at matching arc lengths on both sides of a seam.

Both sides of a seam get a notch at each end and at the same interior arc
lengths, so the sewer matches them stretch by stretch; on a gathered seam the
interior notches sit at the same fractions of each side instead.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Tuple

import numpy as np

from ..design.materials import NOTCH_SPACING as DEFAULT_NOTCH_SPACING
from ..geom.polygon import ray_hit
from ..geom.polyline import point_at_length, polyline_length
from ..pattern.types import Pattern, PatternPanel
from .boundary import seam_sides

NOTCH_LENGTH = 0.006       # m, slit notch cut into the allowance
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
        raise ExportError(f"{where}: expected 0 (notches at the seam ends only) or {MIN_NOTCH_SPACING * 1000:g} mm "
                          f"to {MAX_NOTCH_SPACING:g} m between notches, got {value!r}")
    return v


@dataclass
class Notch:
    """A slit notch on one side of a seam.

    Attributes
    ----------
    seam : str, the seam name.
    side : ``"a"`` or ``"b"``.
    s : float, arc length (m) along this side of the seam from its first vertex.
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


def notch_positions(length_a: float, length_b: float, spacing: float = DEFAULT_NOTCH_SPACING,
                    gathered: bool = False) -> Tuple[np.ndarray, np.ndarray]:
    """Arc lengths of the notches on the two sides of a seam.

    Both sides get the seam ends and the same interior positions
    ``spacing, 2 spacing, ...`` measured from the seam's first vertex, skipping
    those closer than ``spacing / 4`` to the shorter side's end. On a
    ``gathered`` seam the interior notches sit at the same *fractions* of each
    side (spaced ``spacing`` on the shorter one), so each stretch of the
    longer side is gathered into its own stretch of the shorter.

    Parameters
    ----------
    length_a, length_b : float, the lengths of the two sides, metres.
    spacing : float, metres between interior notches (0: ends only).
    gathered : bool, see above.

    Returns
    -------
    s_a, s_b : (k,) float arrays of equal length, metres.
    """
    lmin = min(length_a, length_b)
    interior = []
    if spacing > 0:
        k = 1
        while k * spacing <= lmin - 0.25 * spacing:
            interior.append(k * spacing)
            k += 1
    if gathered and lmin > 0:
        f = np.array(interior) / lmin
        return (np.concatenate([[0.0], f * length_a, [length_a]]),
                np.concatenate([[0.0], f * length_b, [length_b]]))
    s_a = np.array([0.0] + interior + [length_a])
    s_b = np.array([0.0] + interior + [length_b])
    return s_a, s_b


def piece_notches(pattern: Pattern, panel: PatternPanel, xy: np.ndarray, loops: List[np.ndarray],
                  table: Dict[Tuple[int, int], Tuple[int, int]], edge_w: List[np.ndarray],
                  cut: List[np.ndarray], spacing: float = DEFAULT_NOTCH_SPACING) -> List[Notch]:
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
    """
    notches: List[Notch] = []
    for seam, side, ids in seam_sides(pattern, panel.name):
        other = pattern.panel(seam.panel_b if side == "a" else seam.panel_a)
        other_ids = np.asarray(seam.verts_b if side == "a" else seam.verts_a, int)
        la = polyline_length(xy[ids])
        lb = polyline_length(np.asarray(other.uv, float)[other_ids])
        s_here, _ = notch_positions(la, lb, spacing, gathered=bool(getattr(seam, "gathered", False)))
        pts, edges, _ = point_at_length(xy[ids], s_here)
        for s, q, e in zip(s_here, pts, edges):
            li, ei = table[(int(ids[e]), int(ids[e + 1]))]
            b = loops[li]
            # the edge's outward normal; a zero-length edge borrows its neighbour's
            for k in (0, 1, -1, 2, -2):
                d = xy[b[(ei + k + 1) % len(b)]] - xy[b[(ei + k) % len(b)]]
                if np.linalg.norm(d) > 1e-12:
                    break
            nrm = np.array([d[1], -d[0]]) / max(np.linalg.norm(d), 1e-300)
            notches.append(Notch(seam=seam.name, side=side, s=float(s), point=q, normal=nrm,
                                 segment=slit(q, nrm, cut[li], edge_w[li][ei])))
    return notches


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
