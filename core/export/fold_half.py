"""A piece symmetric about a line along its grain, drawn as the half to cut on the fold.

Home-sewing patterns print a symmetric piece (a shirt's front or back
without a centre seam) as its half, to be laid with its fold line on the
fold of fabric folded double: one cut gives the whole piece. The half is
the piece's own drawing clipped at the line of symmetry: the cut line and
sew line end on the fold (the cut line there is the fold of the fabric, no
allowance), notches, darts and holes on the far side are dropped, the fold
line is drawn where the cut line meets the axis, and the grain line, which
may lie on the axis, moves into the half, parallel to the fold.

A piece is drawn as a half only when its drawing is its own mirror image
across a line parallel to the grain within ``tol`` (sew and cut lines both
ways, every notch slit, dart leg, drill hole and fold arrow), the line
through the outline's centroid; when its outline and cut line cross that
line exactly twice (one fold edge); when it has no holes and is not already
cut on a fold; and when no dart reaches across the line.

All lengths are metres, piece frame (grain = +y).
"""

from __future__ import annotations

import dataclasses
from typing import Optional

import numpy as np

from ..geom.layout import grain_arrows
from ..geom.polygon import centroid, ray_hit
from .mirror_check import loops_apart, marks, points_apart
from .pieces import PieceDrawing

GRAIN_FRACTION = 0.6  # part of the half's chord through its centroid that the moved grain line spans
GRAIN_INSET = 0.4  # where across the half the moved grain line lies: 0 on the fold, 1 at the far side
SIDE_TOL = 1e-9  # m, a point this close to the axis counts as on it


def _crossings(loop: np.ndarray, x0: float) -> int:
    """How many times the closed loop crosses the vertical line x = x0."""
    side = np.sign(np.where(np.abs(loop[:, 0] - x0) <= SIDE_TOL, 0.0, loop[:, 0] - x0))
    side = side[side != 0]
    return int(np.count_nonzero(side != np.roll(side, -1))) if len(side) else 0


def fold_axis(piece: PieceDrawing, tol: float) -> Optional[float]:
    """x of the line (parallel to the grain) the piece is symmetric about within ``tol``, or None."""
    if piece.fold or len(piece.sew) != 1 or len(piece.cut) != 1:
        return None
    sew, cut = np.asarray(piece.sew[0], float), np.asarray(piece.cut[0], float)
    x0 = float(centroid(sew)[0])
    flip = lambda p: np.column_stack([2.0 * x0 - p[:, 0], p[:, 1]])  # noqa: E731
    m = marks(piece)
    if (
        max(loops_apart([flip(sew)], [sew]), loops_apart([flip(cut)], [cut]), points_apart(flip(m) if len(m) else m, m))
        > tol
    ):
        return None
    if _crossings(sew, x0) != 2 or _crossings(cut, x0) != 2:
        return None
    for d in piece.darts:  # a dart must lie wholly on one side of the fold
        x = np.concatenate([np.asarray(l, float)[:, 0] for l in d.legs])
        if x.min() < x0 - SIDE_TOL < x0 + SIDE_TOL < x.max():
            return None
    return x0


def _clip(loop: np.ndarray, x0: float):
    """The part of the closed loop with x >= x0, closed along the line (one crossing pair: one loop).

    Returns the clipped loop (k, 2); per output vertex the index of the input
    vertex it is (-1 for a point where the loop crosses the line); and the
    input edge its outgoing edge lies on (the edge along the line excepted).
    """
    out, ids, edge = [], [], []
    n = len(loop)
    for i in range(n):
        a, b = loop[i], loop[(i + 1) % n]
        ina, inb = a[0] >= x0, b[0] >= x0
        if ina:
            out.append(a)
            ids.append(i)
            edge.append(i)
        if ina != inb:
            t = (x0 - a[0]) / (b[0] - a[0])
            out.append(np.array([x0, a[1] + t * (b[1] - a[1])]))
            ids.append(-1)
            edge.append(i)
    return np.array(out), np.array(ids, int), np.array(edge, int)


def _grain(sew: np.ndarray, x0: float):
    """A grain line (2, 2) parallel to the fold inside the half ``sew``, and its arrows."""
    x = x0 + GRAIN_INSET * (sew[:, 0].max() - x0)
    y = float(centroid(sew)[1])
    up = ray_hit(np.array([x, y]), np.array([0.0, 1.0]), sew)
    down = ray_hit(np.array([x, y]), np.array([0.0, -1.0]), sew)
    up, down = (0.0 if up is None else up), (0.0 if down is None else down)
    mid, half = y + 0.5 * (up - down), 0.5 * GRAIN_FRACTION * (up + down)
    start, end = np.array([x, mid - half]), np.array([x, mid + half])
    return np.stack([start, end]), grain_arrows(start, end)


def half_pleat(pleat, keep):
    """A pleat's drawing with the lines ``keep`` (a test on points) keeps."""
    return dataclasses.replace(
        pleat,
        folds=[f for f in pleat.folds if keep(f)],
        placements=[f for f in pleat.placements if keep(f)],
        stitch_ends=np.asarray([q for q in pleat.stitch_ends if keep(q)]).reshape(-1, 2),
    )


def fold_half(piece: PieceDrawing, x0: float, tol: float) -> PieceDrawing:
    """The half of ``piece`` with x >= ``x0`` (from :func:`fold_axis`), to cut on the fold; the label is the piece's
    own (the caller says how to cut it, :func:`core.export.pieces.relabel`).

    The sew line's edges keep their allowance, the edge along the fold has
    none; ``sew_ids`` holds -1 for the points where the sew line meets the fold.
    Notches and darts within ``tol`` of the fold or beyond it on the kept side stay.
    """
    sew, ids, edge = _clip(np.asarray(piece.sew[0], float), x0)
    cut, _, _ = _clip(np.asarray(piece.cut[0], float), x0)
    width = np.asarray(piece.edge_allowance[0], float)
    src = np.asarray(piece.sew_ids[0])
    nxt = np.roll(sew, -1, axis=0)
    on_fold = (np.abs(sew[:, 0] - x0) <= SIDE_TOL) & (np.abs(nxt[:, 0] - x0) <= SIDE_TOL)
    w = np.where(on_fold, 0.0, width[edge])
    on_axis = np.abs(cut[:, 0] - x0) <= SIDE_TOL
    ys = cut[on_axis, 1]
    fold = np.array([[x0, ys.min()], [x0, ys.max()]])
    grain, arrows = _grain(sew, x0)
    keep = lambda pts: bool(np.all(np.asarray(pts, float)[..., 0] >= x0 - tol))  # noqa: E731
    return dataclasses.replace(
        piece,
        sew=[sew],
        sew_ids=[np.where(ids >= 0, src[np.maximum(ids, 0)], -1)],
        cut=[cut],
        edge_allowance=[w],
        fold=[fold],
        notches=[m for m in piece.notches if keep(m.point)],
        darts=[d for d in piece.darts if keep(np.concatenate([np.asarray(l, float) for l in d.legs]))],
        pleats=[half_pleat(p, keep) for p in piece.pleats],
        grain=grain,
        arrows=arrows,
    )
