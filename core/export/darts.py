"""Darts on a pattern piece, as the cutting room marks them.

A dart (:func:`core.cut.types.seam_kind`) is a wedge of the piece's boundary:
from the mouth of one leg up to the apex and back down the other leg. The
sew line and the cut line bridge its mouth (:func:`bridge_darts`; the cloth
in the wedge is folded away, not cut out), and the dart is drawn inside the
piece (:class:`DartDrawing`): both legs, the fold (which way the intake is
pressed: towards the body's centre for an upright dart, down for a level one,
the tailor's rule), the drill hole just inside the sewn point, and a notch at
each leg's mouth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List

import numpy as np

from ..pattern.types import Pattern, PatternPanel

#: m, the drill hole sits this far inside the dart's sewn point, on its centre line
DRILL_INSET = 0.01
#: m, the drill hole's diameter as drawn
DRILL_DIAMETER = 0.003
#: m, the fold arrow's head
FOLD_HEAD = 0.006


@dataclass
class DartDrawing:
    """One dart, in the piece frame (metres).

    Attributes
    ----------
    name : the dart's seam name.
    legs : (2,) list of (k, 2) polylines, mouth to apex (sewn together).
    apex : (2,) the sewn point; drill : (2,) the drill hole's centre.
    fold : (2, 2) from the mouth of the leg folded over to the mouth of the leg it is pressed onto;
    fold_head : (3, 2) the arrow head at ``fold[1]``.
    """

    name: str
    legs: List[np.ndarray]
    apex: np.ndarray
    drill: np.ndarray
    fold: np.ndarray
    fold_head: np.ndarray


def piece_darts(pattern: Pattern, panel: PatternPanel):
    """The dart seams lying on ``panel``, in pattern order."""
    return [s for s in pattern.seams if s.kind == "dart" and s.panel_a == panel.name]


def bridge_darts(loops: List[np.ndarray], darts) -> List[np.ndarray]:
    """The boundary loops with each dart's wedge (legs and apex) replaced by its mouth.

    Parameters
    ----------
    loops : list of (k,) int, local ids (:func:`core.export.boundary.piece_loops`).
    darts : the piece's dart seams (``verts_a``/``verts_b`` mouth to apex).

    Returns
    -------
    list of (k',) int: where a loop runs mouth -> leg -> apex -> leg -> mouth, only the two mouths stay.
    """
    out = []
    for b in loops:
        drop = np.zeros(len(b), bool)
        for s in darts:
            inner = set(np.asarray(s.verts_a[1:], int).tolist()) | set(np.asarray(s.verts_b[1:], int).tolist())
            drop |= np.isin(b, list(inner))
        out.append(b[~drop] if drop.any() and (~drop).sum() >= 3 else b)
    return out


def dart_drawing(panel: PatternPanel, seam, xy: np.ndarray) -> DartDrawing:
    """The drawing of dart ``seam`` of ``panel`` (``xy`` (n, 2): the piece frame)."""
    a, b = xy[np.asarray(seam.verts_a, int)], xy[np.asarray(seam.verts_b, int)]
    apex = a[-1]
    mid = 0.5 * (a[0] + b[0])
    axis = mid - apex
    drill = apex + DRILL_INSET * axis / max(np.linalg.norm(axis), 1e-12)
    # pressed towards the body's centre (upright darts) or down (level darts), decided on the body
    # by the side each leg's cloth lies on (the legs themselves coincide there)
    P = np.asarray(panel.xyz, float)
    ia = int(seam.verts_a[0])
    d3 = P[int(seam.verts_a[-1])] - P[ia]
    upright = abs(d3[2]) >= np.hypot(d3[0], d3[1])
    ca, cb = (_side_centroid(panel, v[:-1], P) for v in (seam.verts_a, seam.verts_b))
    onto_a = abs(ca[0]) < abs(cb[0]) if upright else ca[2] < cb[2]
    src, dst = (b[0], a[0]) if onto_a else (a[0], b[0])
    fold = np.stack([src, dst])
    d = dst - src
    n = np.linalg.norm(d)
    u = d / max(n, 1e-12)
    w = np.array([-u[1], u[0]])
    h = min(FOLD_HEAD, 0.4 * n)
    head = np.stack([dst - h * u + 0.5 * h * w, dst, dst - h * u - 0.5 * h * w])
    return DartDrawing(name=seam.name, legs=[a, b], apex=apex, drill=drill, fold=fold, fold_head=head)


def _side_centroid(panel: PatternPanel, ids, P: np.ndarray) -> np.ndarray:
    """(3,) the body centroid of the triangles touching the leg vertices ``ids`` (one side of a dart)."""
    faces = np.asarray(panel.faces, int)
    touch = np.isin(faces, np.asarray(ids, int)).any(axis=1)
    return P[faces[touch]].mean(axis=(0, 1))
