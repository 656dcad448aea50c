"""Which pieces a home-printer PDF prints: each mirrored pair once, symmetric pieces as halves on the fold.

A left and right piece that are mirror images of each other are cut from one
paper piece: once as printed and once with the paper turned over (or from
fabric folded double). The tiled PDFs (A4, Letter) print such a pair once,
labelled ``cut 2: <left>`` / ``+ mirrored (<right>)``; every other format (SVG,
DXF, the plotter sheet, the marker) keeps every piece, since a cutting room
or a plotter lays each piece by itself.

A pair is printed once only when its drawn geometry really is mirrored:
the right piece's sew and cut lines, notches, dart legs, drill holes and
fold arrows must lie within ``MIRROR_TOL`` of the left piece's reflected
across the grain (either reflection that keeps the grain line's direction:
grain lines have arrows at both ends) and aligned by the outline's centroid,
with the same number of loops, notches and darts. A pair whose sides differ
(for example ease painted on one side only) prints both pieces, each
labelled as not the other's mirror.

A piece printed by itself that is its own mirror image across a line along
its grain within the same tolerance (a shirt front or back without a centre
seam) prints as its half, labelled ``cut 1 on fold: <piece>``, the fold line
drawn (:mod:`.fold_half`).

All lengths are metres, piece frame (grain = +y).
"""

from __future__ import annotations

import dataclasses
from typing import List, Sequence, Tuple

import numpy as np

from ..pattern.types import Pattern
from .fold_half import fold_axis, fold_half
from .mirror_check import MIRROR_TOL, declared_pairs, mirror_gap
from .pieces import PieceDrawing, not_mirror_note, relabel


def print_set(
    pattern: Pattern,
    pieces: Sequence[PieceDrawing],
    print_all: bool = False,
    tol: float = MIRROR_TOL,
    fold: bool = True,
) -> Tuple[List[PieceDrawing], List[dict]]:
    """The pieces a tiled PDF prints, and what each printed piece stands for.

    Parameters
    ----------
    pattern : the pattern the pieces were built from (``panel.mirror_of`` names the pairs).
    pieces : :func:`core.export.pieces.build_pieces` of it, in pattern order.
    print_all : True prints every piece as it is (quantity 1 each).
    tol : m, how far a right piece may lie from its left piece's mirror image to be printed once, and a piece
        from its own mirror image across a line along the grain to be printed as a half on the fold.
    fold : False prints symmetric pieces whole (pairs are still printed once).

    Returns
    -------
    printed : the drawings to print, in pattern order; a left piece printed for
        its pair has quantity 2 and the label lines ``cut 2: <left>``, ``+ mirrored (<right>)``;
        a symmetric piece is its half with the lines ``cut 1 on fold: <piece>``, ``(half printed: ...)``.
    plan : one dict per printed drawing: ``piece`` (its name), ``quantity``
        (how many to cut from it), ``cut`` (how: ``"as printed"``,
        ``"1 as printed + 1 mirrored"`` or ``"on fold (half printed)"``), ``pieces`` (the pattern pieces it
        stands for) and, for a declared pair printed twice, ``not_mirrored_mm``
        (how far apart its sides are, None when their drawings differ in kind);
        such a piece's label says it is not the other's mirror.
    """
    twin = {}  # left index -> right index, for pairs printed once
    apart = {}  # piece index -> (its declared mirror's index, m apart), for pairs printed twice
    for j, k in [] if print_all else declared_pairs(pattern, pieces):
        if j in twin:
            continue
        # build_pieces measured the pair already (for the labels of every file)
        gap = pieces[k].mirror_gaps.get(pieces[j].name)
        gap = mirror_gap(pieces[j], pieces[k]) if gap is None else gap
        if gap <= tol:
            twin[j] = k
        else:
            apart[j], apart[k] = (k, gap), (j, gap)
    skipped = set(twin.values())
    printed, plan = [], []
    for k, piece in enumerate(pieces):
        if k in skipped:
            continue
        if k in twin:
            other = pieces[twin[k]].name
            folded = ", on fold" if piece.fold else ""
            printed.append(relabel(piece, [f"cut 2: {piece.name}", f"+ mirrored ({other}){folded}"], 2))
            plan.append(
                {"piece": piece.name, "quantity": 2, "cut": "1 as printed + 1 mirrored", "pieces": [piece.name, other]}
            )
            continue
        entry = {"piece": piece.name, "quantity": piece.quantity, "cut": "as printed", "pieces": [piece.name]}
        if k in apart:
            # its label must not send the reader to flip the other piece's paper
            other, gap = apart[k]
            note = not_mirror_note(pieces[other].name, gap)
            printed.append(relabel(piece, [f"cut {piece.quantity} as printed", f"({note})"], piece.quantity))
            entry["not_mirrored_mm"] = round(gap * 1000, 1) if np.isfinite(gap) else None
        elif fold and not print_all and (x0 := fold_axis(piece, tol)) is not None:
            printed.append(
                relabel(
                    fold_half(piece, x0, tol),
                    [f"cut {piece.quantity} on fold: {piece.name}", "(half printed: fold line on the fabric fold)"],
                    piece.quantity,
                )
            )
            entry["cut"] = "on fold (half printed)"
        else:
            printed.append(dataclasses.replace(piece))
        plan.append(entry)
    return printed, plan
