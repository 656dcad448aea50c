"""The boundary of a pattern piece as the cutting room walks it.

A piece's sew line is its boundary loops: the outline first (counter-clockwise
in uv) and holes after (clockwise), so the material is always on the left and
an allowance offset to the right lies outside the piece. Each boundary edge is
found again by its two vertex ids through :func:`edge_table`; seams name the
vertex runs they sew (:func:`seam_sides`).
"""

from __future__ import annotations

from typing import Dict, Iterator, List, Tuple

import numpy as np

from ..geom.mesh import boundary_loops
from ..geom.polygon import signed_area
from ..pattern.types import Pattern, PatternPanel, PatternSeam


def face_loops(faces: np.ndarray) -> List[np.ndarray]:
    """Boundary loops of a piece's triangles, for a piece that lists none.

    Parameters
    ----------
    faces : (F, 3) int, local vertex ids.

    Returns
    -------
    list of (k,) int, k >= 3, oriented like the faces; each loop starts at its
    smallest vertex id and the loops are ordered by it (a stable order for
    the output files, independent of the mesh library's).
    """
    loops = [np.roll(b, -int(np.argmin(b))) for b in boundary_loops(faces) if len(b) >= 3]
    return sorted(loops, key=lambda b: int(b[0]))


def piece_loops(panel: PatternPanel) -> List[np.ndarray]:
    """Boundary loops of a piece, outline first (ccw in uv), holes after (cw).

    Parameters
    ----------
    panel : the piece; ``panel.boundary`` (or, when empty, its faces' boundary).

    Returns
    -------
    list of (k,) int, local vertex ids, not closed (last != first); the loop
    of largest area first.
    """
    loops = [np.asarray(b, int).reshape(-1) for b in panel.boundary] or face_loops(panel.faces)
    loops = [b[:-1] if len(b) > 1 and b[0] == b[-1] else b for b in loops]
    uv = np.asarray(panel.uv, float)
    areas = [signed_area(uv[b]) for b in loops]
    order = np.argsort([-abs(a) for a in areas], kind="stable")
    out = []
    for rank, i in enumerate(order):
        b, a = loops[i], areas[i]
        if (rank == 0) != (a > 0):
            b = b[::-1]
        out.append(b)
    return out


def edge_table(loops: List[np.ndarray]) -> Dict[Tuple[int, int], Tuple[int, int]]:
    """Where each boundary edge lies in the loops.

    Parameters
    ----------
    loops : list of (k,) int, from :func:`piece_loops`.

    Returns
    -------
    dict ``(u, v)`` and ``(v, u)`` -> ``(loop index, edge index)``, edge ``i``
    of a loop running from its vertex ``i`` to vertex ``i + 1``.
    """
    table = {}
    for li, b in enumerate(loops):
        for ei in range(len(b)):
            u, v = int(b[ei]), int(b[(ei + 1) % len(b)])
            table[(u, v)] = (li, ei)
            table[(v, u)] = (li, ei)
    return table


def seam_sides(pattern: Pattern, panel_name: str) -> Iterator[Tuple[PatternSeam, str, np.ndarray]]:
    """Every seam side lying on one piece.

    Yields
    ------
    (seam, side, ids): the :class:`core.pattern.types.PatternSeam`, ``"a"`` or
    ``"b"``, and that side's (k,) int local vertex ids, in pattern order.
    Darts are not among them: their legs lie inside the piece's drawn outline
    (:mod:`core.export.darts`).
    """
    for s in pattern.seams:
        if s.kind == "dart":
            continue
        if s.panel_a == panel_name:
            yield s, "a", np.asarray(s.verts_a, int)
        if s.panel_b == panel_name:
            yield s, "b", np.asarray(s.verts_b, int)
