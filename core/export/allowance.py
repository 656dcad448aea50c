"""Seam allowance: the width outside each sew edge and the cut line around it.

Widths come from the caller, else the design (``materials.export.allowance``),
else the defaults of :mod:`core.design.materials` (1 cm seams, 2 cm hems,
nothing on a fold). Each sew edge
of a piece gets one width: hems, then seams (a seam wins where an edge is
listed twice), then the fold. The cut line is the sew line offset outward by
those widths (:func:`core.geom.polygon.offset_loop`), loops removed and
checked.
"""

from __future__ import annotations

import math
from typing import Dict, List, Mapping, Optional, Tuple, Union

import numpy as np

from ..cut.types import seam_names
from ..design.materials import ALLOWANCE as DEFAULT_ALLOWANCE
from ..design.materials import FOLD as DEFAULT_FOLD
from ..design.materials import HEM as DEFAULT_HEM
from ..errors import ExportError
from ..geom.polygon import MITRE_LIMIT, offset_loop, points_in_polygon, remove_loops, segments_cross
from ..pattern.types import Pattern, PatternPanel
from .boundary import seam_sides


def resolve_allowance(allowance: Union[None, float, Mapping], pattern: Pattern) -> Dict[str, float]:
    """Seam allowance per seam name, with ``"default"`` and ``"hem"`` entries.

    Parameters
    ----------
    allowance : None, a number (every seam) or a dict ``{"default": 0.01,
        "hem": 0.02, "fold": 0, "<seam>": ...}`` in metres; a seam is named
        as the cut names it (``garment.line``, ``garment.line#k`` for one
        stretch of a split line) or by its line (``line``: in every garment).
        None takes
        ``pattern.materials["export"]["allowance"]`` when the design has one.

    Raises
    ------
    ExportError naming the key when a value is not a finite number in
    [0, 0.1] m or a key is neither a seam name nor default/hem/fold.
    """
    if allowance is None:
        allowance = ((pattern.materials or {}).get("export") or {}).get("allowance")
    out = {"default": DEFAULT_ALLOWANCE, "hem": DEFAULT_HEM, "fold": DEFAULT_FOLD}
    if allowance is None:
        return out
    if isinstance(allowance, (int, float)) and not isinstance(allowance, bool):
        allowance = {"default": float(allowance)}
    if not isinstance(allowance, Mapping):
        raise ExportError(
            f"allowance: expected a number or a dict like "
            f"{{'default': 0.01, 'hem': 0.02, '<seam>': ...}}, got {type(allowance).__name__}"
        )
    seams = {s.name for s in pattern.seams}
    lines = {k for n in seams for k in seam_names(n)}
    for key, value in allowance.items():
        if key not in out and key not in lines:
            raise ExportError(
                f"allowance[{key!r}]: not a seam of the pattern; expected 'default', 'hem', "
                f"'fold' or one of: {', '.join(sorted(lines)) or '(no seams)'}"
            )
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ExportError(f"allowance[{key!r}]: expected a width in metres, got {value!r}") from None
        if not math.isfinite(v) or v < 0 or v > 0.1:
            raise ExportError(f"allowance[{key!r}]: expected a width in [0, 0.1] m, got {value!r}")
        out[key] = v
    return out


def seam_allowance(widths: Mapping[str, float], seam: str) -> float:
    """Allowance (m) of seam ``seam`` from :func:`resolve_allowance`'s table:
    the most specific key naming it (see :func:`core.cut.types.seam_names`), else the default."""
    for k in seam_names(seam):
        if k in widths:
            return float(widths[k])
    return float(widths["default"])


def fold_ids(panel: PatternPanel) -> Optional[np.ndarray]:
    """(k,) int local vertex ids of the piece's fold line, or None when it is not cut on a fold."""
    ids = getattr(panel, "fold", None)
    if ids is None or not len(ids):
        return None
    return np.asarray(ids, int)


def edge_allowances(
    pattern: Pattern,
    panel: PatternPanel,
    widths: Mapping[str, float],
    loops: List[np.ndarray],
    table: Dict[Tuple[int, int], Tuple[int, int]],
) -> List[np.ndarray]:
    """The allowance of every sew edge of a piece.

    Parameters
    ----------
    pattern, panel : the pattern and the piece.
    widths : from :func:`resolve_allowance`.
    loops, table : the piece's loops and their edge table
        (:func:`core.export.boundary.piece_loops`, :func:`~core.export.boundary.edge_table`).

    Returns
    -------
    list of (k,) float, metres, per loop: the width of edge ``loop[i] -> loop[i+1]``.
    """
    edge_w = [np.full(len(b), widths["default"]) for b in loops]
    # hems, then seams (a seam wins if an edge is listed twice), then folds
    for h in panel.hems:
        h = np.asarray(h, int)
        for u, v in zip(h[:-1], h[1:]):
            if (int(u), int(v)) in table:
                li, ei = table[(int(u), int(v))]
                edge_w[li][ei] = widths["hem"]
    for seam, side, ids in seam_sides(pattern, panel.name):
        w = seam_allowance(widths, seam.name)
        for u, v in zip(ids[:-1], ids[1:]):
            li, ei = table[(int(u), int(v))]
            edge_w[li][ei] = w
    fold = fold_ids(panel)
    if fold is not None:
        for u, v in zip(fold[:-1], fold[1:]):
            if (int(u), int(v)) in table:
                li, ei = table[(int(u), int(v))]
                edge_w[li][ei] = widths["fold"]
    return edge_w


def cut_line(
    sew: np.ndarray,
    widths: np.ndarray,
    mitre_limit: float = MITRE_LIMIT,
    hole: bool = False,
    warnings: Optional[List[str]] = None,
) -> np.ndarray:
    """The cut line around one sew-line loop: :func:`offset_loop`, loops removed, checked.

    Parameters
    ----------
    sew : (k, 2) float, the loop with the material on its left (outline ccw, hole cw), metres.
    widths : (k,) float, allowance of each edge (m).
    hole : bool, the loop is a hole of the piece.
    warnings : list or None; when given, a cut line that fails the checks is
        returned anyway and the problem appended here instead of raised.

    Returns
    -------
    (m, 2) float, the cut line, closed implicitly.

    Raises
    ------
    ExportError when the allowance cannot go around the loop (two parts of the
    outline closer than the sum of their allowances, e.g. a narrow slit).
    """
    c = remove_loops(offset_loop(sew, widths, mitre_limit), -1.0 if hole else 1.0)
    # every sew vertex with allowance on both sides must lie inside the cut line
    # (outside it for a hole); vertices on a fold lie on it and are skipped
    w = np.asarray(widths, float)
    keep = (w > 0) & (np.roll(w, 1) > 0)
    inside = points_in_polygon(sew[keep], c)
    bad = inside if hole else ~inside
    if np.any(bad) or segments_cross(c) is not None:
        q = (sew[keep][np.argmax(bad)] if np.any(bad) else c[0]) * 1000
        msg = (
            f"the seam allowance does not fit around the sew line near ({q[0]:.0f}, {q[1]:.0f}) mm "
            f"(parts of the outline closer than twice the allowance); lower the allowance there"
        )
        if warnings is None:
            raise ExportError(msg)
        warnings.append(msg)
    return c


def piece_cut_lines(
    name: str,
    sew: List[np.ndarray],
    edge_w: List[np.ndarray],
    mitre_limit: float = MITRE_LIMIT,
    warnings: Optional[List[str]] = None,
) -> List[np.ndarray]:
    """:func:`cut_line` around every loop of one piece (outline, then holes).

    Parameters
    ----------
    name : str, the piece, named in errors and warnings.
    sew : list of (k, 2) float, the loops from :func:`core.export.boundary.piece_loops`, metres.
    edge_w : list of (k,) float, from :func:`edge_allowances`.
    warnings : list or None, see :func:`cut_line`.
    """
    cut = []
    for li in range(len(sew)):
        # the outline is ccw and holes cw, so the material is always on the
        # left and offsetting to the right puts the allowance outside it
        found: List[str] = []
        try:
            c = cut_line(sew[li], edge_w[li], mitre_limit, hole=li > 0, warnings=None if warnings is None else found)
        except ExportError as exc:
            raise ExportError(f"piece {name!r}: {exc}") from None
        if warnings is not None:
            warnings.extend(f"piece {name!r}: {m}" for m in found)
        cut.append(c)
    return cut


def allowance_text(edge_w: List[np.ndarray]) -> str:
    """The label's allowance note: every width in use (mm), e.g. ``"allowance 10/20 incl."``."""
    vals = sorted({round(float(v) * 1000, 1) for w in edge_w for v in w if v > 0})
    if not vals:
        return "no seam allowance"
    return "allowance " + "/".join(f"{v:g}" for v in vals) + " incl."
