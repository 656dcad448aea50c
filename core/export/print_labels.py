"""Labels and grain lines on the printed pages of a tiled PDF, and which pages are printed.

Pages that lie wholly inside a piece or between pieces are left out
(:func:`inked_pages`). So that no piece loses its name on a page left out,
each label is moved, within its piece, to the place nearest its own whose
pages are printed anyway (:func:`place_labels`); a label that finds none keeps
its place and its pages are printed. Likewise a grain line that would show
less than ``GRAIN_SHOWN`` on the printed pages slides across the grain to
where it does (:func:`place_grains`), or else gets its pages printed. The
top-left page (test square and page map) is always printed.

All lengths are metres, piece frame unless said, sheet frame y up.
"""

from __future__ import annotations

import math

import numpy as np

from ..geom.layout import Layout
from .pages import (
    PageGrid,
    PrintLayout,
    fill_cells,
    line_pages,
    place,
    sample_loops,
    sample_open,
    segments,
    windows_hit,
)

LABEL_STEP = 0.004  # m, spacing of the places tried for a label
GRAIN_SHOWN = 0.10  # m of grain line that must be printed (all of it when shorter): enough to lay a ruler on
LABEL_TRIES = 100  # nearest free places checked exactly for a label (on printed pages, whole on one)


def label_at(layout: Layout, i: int, piece) -> np.ndarray:
    """(2,) piece-frame top-left of piece ``i``'s label in ``layout`` (moved by :func:`place_labels` or its own)."""
    labels = getattr(layout, "labels", None)
    return np.asarray(piece.label_at if labels is None else labels[i], float)


def grain_shift(layout: Layout, i: int) -> np.ndarray:
    """(2,) piece-frame shift of piece ``i``'s grain line and arrows in ``layout`` (:func:`place_grains`)."""
    grains = getattr(layout, "grains", None)
    return np.zeros(2) if grains is None else np.asarray(grains[i], float)


def label_box(piece, at) -> np.ndarray:
    """(4, 2) piece-frame corners of the label block with its top-left at ``at`` (empty when no label)."""
    from .pieces import CHAR_WIDTH

    if not piece.label:
        return np.zeros((0, 2))
    th = len(piece.label) * 1.5 * piece.text_height
    tw = max(len(s) for s in piece.label) * CHAR_WIDTH * piece.text_height
    x, y = at
    return np.array([[x, y - th], [x + tw, y - th], [x + tw, y], [x, y]])


def inked_pages(pieces, layout: Layout, grid: PageGrid) -> np.ndarray:
    """(rows, cols) bool: the pages printed.

    The windows a cut or sew line or a dart leg crosses, the top-left page
    (test square, map), the windows of a label that lies on none of those, and
    the grain line's windows when less than ``GRAIN_SHOWN`` of it would show.
    """
    ink = line_pages(pieces, layout, grid)
    ink[0, 0] = True
    extra = np.zeros_like(ink)
    for i, p in enumerate(pieces):
        box = label_box(p, label_at(layout, i, p))
        if len(box):
            here = np.zeros_like(ink)
            a, b = segments([place(layout, i, box)])
            windows_hit(a, b, grid, here)
            if np.any(here & ~ink):
                extra |= here
        g = place(layout, i, p.grain + grain_shift(layout, i))
        length = float(np.linalg.norm(g[1] - g[0]))
        if _shown(g, grid, ink) < min(GRAIN_SHOWN, length) - 1e-9:
            windows_hit(g[:1], g[1:], grid, extra)
    return ink | extra


def _shown(seg: np.ndarray, grid: PageGrid, ink: np.ndarray, spacing: float = 0.002) -> float:
    """Length (m, to ``spacing``) of the segment ``seg`` (2, 2) that lies on printed windows."""
    n = max(2, int(math.ceil(np.linalg.norm(seg[1] - seg[0]) / spacing)) + 1)
    q = seg[0] + np.linspace(0.0, 1.0, n)[:, None] * (seg[1] - seg[0])
    seen = grid.holding(ink, q, q)
    return float(seen.mean() * np.linalg.norm(seg[1] - seg[0]))


def place_labels(pieces, layout: "PrintLayout", grid: PageGrid, ink: np.ndarray) -> np.ndarray:
    """(n, 2) piece-frame top-left corners for the labels, each on pages printed anyway.

    A label keeps its place when its pages are printed and it lies whole on one of
    them (read on one page, not split across two); otherwise it moves to the nearest
    place (on a ``LABEL_STEP`` lattice, nearest first) where it lies inside the sew
    line, clear of every line, notch, dart and the grain line (2 mm), every page it
    reaches is printed (``ink``) and it lies whole on one. Where no such place is,
    the same without the one page (a label split over printed pages rather than a
    page printed for it alone); a label that finds neither keeps its place (its
    pages are then printed, :func:`inked_pages`).
    """
    out = np.array([np.asarray(p.label_at, float) for p in pieces]).reshape(-1, 2)
    for i, p in enumerate(pieces):
        box = label_box(p, p.label_at)
        if not len(box):
            continue
        for whole in (True, False):
            if _label_on(box, layout, i, grid, ink, whole):
                break
            found = _label_place(p, box, layout, i, grid, ink, whole)
            if found is not None:
                out[i] = found
                break
    return out


def place_grains(pieces, layout: "PrintLayout", grid: PageGrid, ink: np.ndarray) -> np.ndarray:
    """(n, 2) piece-frame shifts of the grain lines, so that ``GRAIN_SHOWN`` of each shows on printed pages.

    A grain line that shows enough stays; otherwise it slides across the grain
    (nearest first, ``LABEL_STEP`` apart) to the first place inside the sew
    line, clear of the label (2 mm), where it does; a line that finds none
    stays (its pages are then printed, :func:`inked_pages`). Any line parallel
    to the grain serves to lay the piece on the fabric.
    """
    from ..geom.polygon import points_in_polygon

    out = np.zeros((len(pieces), 2))
    for i, p in enumerate(pieces):
        g = np.asarray(p.grain, float)
        length = float(np.linalg.norm(g[1] - g[0]))
        need = min(GRAIN_SHOWN, length) - 1e-9
        if _shown(place(layout, i, g), grid, ink) >= need:
            continue
        outline = np.asarray(p.sew[0], float)
        lo, hi = outline.min(0), outline.max(0)
        box = label_box(p, label_at(layout, i, p))
        shifts = np.arange(lo[0] - g[0, 0], hi[0] - g[0, 0], LABEL_STEP)
        for dx in shifts[np.argsort(np.abs(shifts), kind="stable")]:
            q = sample_open(g + [dx, 0.0], 0.004)
            if not np.all(points_in_polygon(q, outline)):
                continue
            if len(box) and np.any(np.all((q >= box[0] - 0.002) & (q <= box[2] + 0.002), axis=1)):
                continue
            if any(np.any(points_in_polygon(q, hole)) for hole in p.sew[1:]):
                continue
            if _shown(place(layout, i, g + [dx, 0.0]), grid, ink) >= need:
                out[i] = [dx, 0.0]
                break
    return out


def _label_on(box: np.ndarray, layout: Layout, i: int, grid: PageGrid, ink: np.ndarray, whole: bool = True) -> bool:
    """Whether every window that the piece-frame ``box`` of piece ``i`` reaches is printed, and (``whole``) the
    box lies whole within one of them (a label read on one page, not split across two)."""
    here = np.zeros_like(ink)
    placed = place(layout, i, box)
    a, b = segments([placed])
    windows_hit(a, b, grid, here)
    if np.any(here & ~ink):
        return False
    if not whole:
        return True
    return bool(grid.holding(here, placed.min(axis=0)[None], placed.max(axis=0)[None])[0])


def _label_place(piece, box: np.ndarray, layout: Layout, i: int, grid: PageGrid, ink: np.ndarray, whole: bool = True):
    """The nearest top-left corner (piece frame) where the label fits inside the piece on printed pages, or None.

    On a ``LABEL_STEP`` lattice over the sew line's box, a cell is free when its
    centre is inside the sew line (not in a hole), no line, notch, dart or the
    grain line passes within a cell and 2 mm of it, and it lies on no page left
    out (windows widened by a cell); the label fits where all the cells it
    covers are free (summed-area table). The nearest fits are checked exactly.
    """
    from scipy.ndimage import binary_dilation

    cell = LABEL_STEP
    size = box[2] - box[0]
    outline = np.asarray(piece.sew[0], float)
    lo, hi = outline.min(0), outline.max(0)
    h, w = int(math.ceil((hi[1] - lo[1]) / cell)), int(math.ceil((hi[0] - lo[0]) / cell))
    nh, nw = int(math.ceil(size[1] / cell)) + 1, int(math.ceil(size[0] / cell)) + 1
    if nh > h or nw > w:
        return None
    free = np.zeros((h, w), bool)
    fill_cells(free, outline, lo[0], hi[1], cell)
    for hole in piece.sew[1:]:
        inner = np.zeros((h, w), bool)
        fill_cells(inner, np.asarray(hole, float), lo[0], hi[1], cell)
        free &= ~inner
    drawn = list(piece.cut) + list(piece.sew)
    opened = (
        [piece.grain]
        + [leg for d in piece.darts for leg in d.legs]
        + [d.fold for d in piece.darts]
        + [n.segment for n in piece.notches]
        + list(piece.fold)
    )
    q = np.concatenate([sample_loops(drawn, cell / 2)] + [sample_open(l, cell / 2) for l in opened])
    line = np.zeros((h, w), bool)
    rr, cc = np.floor((hi[1] - q[:, 1]) / cell).astype(int), np.floor((q[:, 0] - lo[0]) / cell).astype(int)
    keep = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
    line[rr[keep], cc[keep]] = True
    k = 1 + int(math.ceil(0.002 / cell))
    free &= ~binary_dilation(line, structure=np.ones((2 * k + 1, 2 * k + 1), bool))
    # cell centres on the sheet, off every page left out (its window widened by a cell)
    yc, xc = hi[1] - (np.arange(h) + 0.5) * cell, lo[0] + (np.arange(w) + 0.5) * cell
    centres = place(layout, i, np.stack(np.meshgrid(xc, yc), axis=-1).reshape(-1, 2))
    off = grid.holding(~ink, centres, centres, pad=cell)  # a centre within a window left out, widened by a cell
    free &= ~off.reshape(h, w)
    # label top-left at cell corner (r, c): cells r .. r + nh - 1, c .. c + nw - 1 all free
    sat = np.zeros((h + 1, w + 1), int)
    sat[1:, 1:] = np.cumsum(np.cumsum(free, axis=0), axis=1)
    bad = sat[nh:, nw:] - sat[:-nh, nw:] - sat[nh:, :-nw] + sat[:-nh, :-nw] < nh * nw
    r, c = np.nonzero(~bad)
    if not len(r):
        return None
    at = np.stack([lo[0] + c * cell, hi[1] - r * cell], axis=1)
    nearest = np.argsort(np.linalg.norm(at - piece.label_at, axis=1), kind="stable")[:LABEL_TRIES]
    if whole:  # the exact check only where the label can lie whole on a printed page
        boxes = at[nearest][:, None, :] + label_box(piece, (0.0, 0.0))[None]
        nearest = nearest[_within_a_printed_window(place(layout, i, boxes.reshape(-1, 2)).reshape(-1, 4, 2), grid, ink)]
    for j in nearest:
        if _label_on(label_box(piece, at[j]), layout, i, grid, ink, whole):
            return at[j]
    return None


def _within_a_printed_window(corners: np.ndarray, grid: PageGrid, ink: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """(m,) bool: whether each box (``corners`` (m, 4, 2), sheet m) lies within a printed window (``tol`` m
    to spare): what :func:`_label_on` with ``whole`` needs (the window holding the box is one it reaches, so
    one printed), checked for many boxes at once."""
    return grid.holding(ink, corners.min(axis=1) + tol, corners.max(axis=1) - tol)
