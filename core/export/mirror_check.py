"""Whether two piece drawings are mirror images of each other, and how far apart they are.

The tiled PDFs print a declared left/right pair (``mirror_of``) once only
when the right piece's drawn geometry is the left one's mirror image within
``MIRROR_TOL`` (:mod:`.print_set`); every file's labels say ``mirror of X``
by the same measure, or how far apart the two are (:mod:`.pieces`). A piece
that is its own mirror image across a line along its grain prints as its
half on the fold (:mod:`.fold_half`), measured with the same helpers.

Pieces are :class:`core.export.pieces.PieceDrawing` (not imported here:
:mod:`.pieces` measures its pairs with this module). All lengths are metres,
piece frame (grain = +y).
"""

from __future__ import annotations

import numpy as np

from ..geom.polygon import centroid, distance_to_polyline

MIRROR_TOL = 0.0005  # m: a pair further apart than this prints both pieces
# the reflections of the piece frame that keep the grain's axis: across the grain, and along it (the same up to a
# half turn, which a grain line with arrows at both ends does not tell apart)
REFLECTIONS = (np.diag([-1.0, 1.0]), np.diag([1.0, -1.0]))


def declared_pairs(pattern, pieces) -> list:
    """``(left, right)`` indices into ``pieces`` (built from ``pattern``, in pattern order) of every
    declared pair: a panel whose ``mirror_of`` names another piece is the right of that left one."""
    by_name = {p.name: k for k, p in enumerate(pieces)}
    out = []
    for k, panel in enumerate(pattern.panels[: len(pieces)]):
        j = by_name.get(panel.mirror_of) if panel.mirror_of else None
        if j is not None and j != k:
            out.append((j, k))
    return out


def mirror_gap(left, right) -> float:
    """How far (m) ``right`` lies from the mirror image of ``left``: inf when their drawings differ in kind.

    ``left`` is reflected across its grain (or along it), moved so that the
    centroids of the outlines meet, and compared line by line: sew and cut
    loops (each vertex to the other loop, both ways) and the notches', darts'
    and fold lines' points (each to the nearest of the other piece's). The
    smaller of the two reflections' largest distances is returned.
    """
    kinds = lambda p: (len(p.sew), len(p.cut), len(p.notches), len(p.darts), len(p.fold))  # noqa: E731
    if kinds(left) != kinds(right):
        return float("inf")
    best = float("inf")
    for F in REFLECTIONS:
        shift = centroid(np.asarray(right.sew[0], float)) - centroid(np.asarray(left.sew[0], float) @ F)
        move = lambda loops: [np.asarray(l, float) @ F + shift for l in loops]  # noqa: E731
        gap = max(
            loops_apart(move(left.sew), right.sew),
            loops_apart(move(left.cut), right.cut),
            points_apart(marks(left) @ F + shift, marks(right)),
        )
        best = min(best, gap)
    return float(best)


def marks(piece) -> np.ndarray:
    """(m, 2) points of the piece's small marks: notch slits, dart legs, drill holes, fold arrows, fold lines."""
    pts = [np.asarray(n.segment, float) for n in piece.notches]
    for d in piece.darts:
        pts += [np.asarray(l, float) for l in d.legs] + [np.asarray(d.drill, float)[None], np.asarray(d.fold, float)]
    pts += [np.asarray(f, float) for f in piece.fold]
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def loops_apart(a, b) -> float:
    """Largest distance between the closed loops ``a[k]`` and ``b[k]`` (each vertex to the other loop, both ways)."""
    return max(
        (max(distance_to_polyline(p, q).max(), distance_to_polyline(q, p).max()) for p, q in zip(a, b)), default=0.0
    )


def points_apart(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a point of either set to the nearest point of the other (0 when both are empty)."""
    if not len(a) and not len(b):
        return 0.0
    if not len(a) or not len(b):
        return float("inf")
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))
