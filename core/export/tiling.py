"""Print layout: the pieces nested for home-printer pages, and which pages carry a line.

A tiled PDF costs one sheet of paper per page that the printer feeds, so the
pieces are placed to touch as few pages as possible, not to make the
shortest strip. The sheet is a grid of page windows (the printable area of
the paper); neighbouring windows overlap by ``overlap`` for taping. Pieces
are rasterised (cut line filled, the label, plus half the paper gap between
pieces on every side) and placed one by one, largest first, turned by a
quarter turn and tilted by up to ``max(TILTS)`` degrees (paper may be turned
any way: the grain line is drawn on the piece, and the fabric is laid by it).
Of the positions where a piece fits (the first free cell after every occupied
run, per column, and the positions whose lines start just past a page line
or end just before one, across and down), the one whose cut and sew lines
reach the fewest pages no earlier piece reached wins, then the shallowest,
then the leftmost. Several sheet widths (whole numbers of pages) and orders
are tried; the layout with the fewest printed pages wins (ties: the one tried
first). Every step is deterministic.

A page is printed when a cut or sew line (or a dart leg) crosses its window
(:func:`inked_pages`); a page that lies wholly inside a piece or between
pieces is left out. So that no piece loses its name on a page left out, each
label is moved, within its piece, to the place nearest its own whose pages
are printed anyway (:func:`place_labels`); a label that finds none keeps its
place and its pages are printed. Likewise a grain line that would show less
than ``GRAIN_SHOWN`` on the printed pages slides across the grain to where it
does (:func:`place_grains`), or else gets its pages printed. The top-left page
(test square and page map) is always printed.

All lengths are metres, sheet frame y up, origin bottom-left.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from ..geom.layout import Layout

CELL = 0.0075           # m, raster cell of the packer (5 mm packs no tighter on the teaser, at twice the time)
GAP = 0.010             # m, paper between two pieces (room for the scissors)
SAMPLE = 0.008          # m, spacing of the cut-line samples that count a piece's pages while packing
EXTRA_COLUMNS = 4       # sheet widths tried: the narrowest that holds the widest piece, and this many more
TURNS = (0, 1, 2, 3)    # quarter turns tried per piece
TILTS = (0.0, -5.0, 5.0, -10.0, 10.0)  # degrees added to each quarter turn (teaser A4: 61 pages with 0 only, 58)
ALIGN_EPS = 0.0015      # m, how far past a page line an aligned position puts the piece's lines
LABEL_STEP = 0.004      # m, spacing of the places tried for a label
GRAIN_SHOWN = 0.10      # m of grain line that must be printed (all of it when shorter): enough to lay a ruler on


@dataclass
class PrintLayout(Layout):
    """A :class:`core.geom.layout.Layout` whose pieces may be turned: sheet = R(angles[i]) @ p + offsets[i].

    ``angles`` are degrees counter-clockwise (None: all 0); ``labels`` (n, 2)
    piece-frame top-left corners of the labels where the print layout moved
    them (None: each piece's own ``label_at``); ``grains`` (n, 2) piece-frame
    shifts of the grain lines (and their arrows) across the grain (None: 0).
    """
    angles: Optional[np.ndarray] = None
    labels: Optional[np.ndarray] = None
    grains: Optional[np.ndarray] = None

    def matrix(self, i: int) -> np.ndarray:
        """(2, 2) float, the rotation of piece ``i`` (piece frame -> sheet)."""
        return rotation(0.0 if self.angles is None else float(self.angles[i]))

    def place(self, i: int, points) -> np.ndarray:
        """(m, 2) piece-frame points of piece ``i`` on the sheet."""
        return np.asarray(points, float) @ self.matrix(i).T + self.offsets[i]


def rotation(degrees: float) -> np.ndarray:
    """(2, 2) rotation by ``degrees`` counter-clockwise; exact integers for quarter turns."""
    k, rest = divmod(float(degrees), 90.0)
    if rest == 0.0:
        c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][int(k) % 4]
        return np.array([[c, -s], [s, c]], float)
    a = math.radians(float(degrees))
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


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


def place(layout: Layout, i: int, points) -> np.ndarray:
    """Piece ``i``'s points on the sheet of any layout (turned when it is a :class:`PrintLayout`)."""
    if isinstance(layout, PrintLayout):
        return layout.place(i, points)
    return np.asarray(points, float) + layout.offsets[i]


@dataclass(frozen=True)
class PageGrid:
    """The page windows of a tiled sheet.

    Attributes
    ----------
    tile : (w, h) float, window size (printable area of one page), m.
    overlap : float, m shared by neighbouring windows (the taping strip).
    rows, cols : int, windows down and across.
    height : float, sheet height (m); row 0 hangs from the top edge.
    """
    tile: Tuple[float, float]
    overlap: float
    rows: int
    cols: int
    height: float

    @property
    def step(self) -> np.ndarray:
        """(2,) float, m from one window's corner to the next one's."""
        return np.asarray(self.tile, float) - self.overlap

    def window(self, r: int, c: int) -> np.ndarray:
        """(2, 2) float, min/max corner of window (row ``r`` from the top, column ``c``) on the sheet."""
        sx, sy = self.step
        y1 = self.height - r * sy
        return np.array([[c * sx, y1 - self.tile[1]], [c * sx + self.tile[0], y1]])


def grid_for(size: Sequence[float], tile: Sequence[float], overlap: float) -> PageGrid:
    """The fewest windows of ``tile`` (m, overlapping by ``overlap``) that cover a sheet of ``size`` (m)."""
    step = np.asarray(tile, float) - overlap
    cols = max(1, int(math.ceil((float(size[0]) - overlap) / step[0] - 1e-9)))
    rows = max(1, int(math.ceil((float(size[1]) - overlap) / step[1] - 1e-9)))
    return PageGrid(tile=(float(tile[0]), float(tile[1])), overlap=float(overlap), rows=rows, cols=cols,
                    height=float(size[1]))


def piece_lines(piece) -> List[np.ndarray]:
    """The closed cut and sew loops of a piece, (k, 2) float each, piece frame: what makes a page worth printing."""
    return [np.asarray(l, float) for l in list(piece.cut) + list(piece.sew)]


def _segments(loops, open_lines=()) -> Tuple[np.ndarray, np.ndarray]:
    """Segment ends (a, b), (k, 2) each, of closed loops and open polylines."""
    a = [np.asarray(l, float) for l in loops] + [np.asarray(l, float)[:-1] for l in open_lines]
    b = [np.roll(np.asarray(l, float), -1, axis=0) for l in loops] + [np.asarray(l, float)[1:] for l in open_lines]
    if not a:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.concatenate(a), np.concatenate(b)


def _piece_segments(piece) -> Tuple[np.ndarray, np.ndarray]:
    """Piece-frame segments of the lines that make a page worth printing: cut and sew loops, dart legs."""
    return _segments(piece_lines(piece), [leg for d in piece.darts for leg in d.legs])


def _hits_box(a: np.ndarray, b: np.ndarray, box: np.ndarray) -> bool:
    """Whether any segment a[i]-b[i] meets the closed box (Liang-Barsky clipping, vectorised)."""
    d = b - a
    t0 = np.zeros(len(a))
    t1 = np.ones(len(a))
    ok = np.ones(len(a), bool)
    for k in range(2):
        for p, q in ((-d[:, k], a[:, k] - box[0, k]), (d[:, k], box[1, k] - a[:, k])):
            par = np.abs(p) < 1e-15
            ok &= ~(par & (q < 0))
            r = q / np.where(par, 1.0, p)
            t0 = np.where(~par & (p < 0), np.maximum(t0, r), t0)
            t1 = np.where(~par & (p > 0), np.minimum(t1, r), t1)
    return bool(np.any(ok & (t0 <= t1)))


def _windows_hit(a: np.ndarray, b: np.ndarray, grid: PageGrid, out: np.ndarray) -> None:
    """Set ``out[r, c]`` for every window that a segment a[i]-b[i] (sheet m) meets."""
    if not len(a):
        return
    lo, hi = np.minimum(a, b).min(0), np.maximum(a, b).max(0)
    sx, sy = grid.step
    # only the windows that meet the segments' bounding box: column c spans [c sx, c sx + w], row r hangs r sy
    # below the top edge
    c0 = max(0, int(math.ceil((lo[0] - grid.tile[0]) / sx)) - 1)
    c1 = min(grid.cols - 1, int(math.floor(hi[0] / sx)) + 1)
    r0 = max(0, int(math.ceil((grid.height - hi[1] - grid.tile[1]) / sy)) - 1)
    r1 = min(grid.rows - 1, int(math.floor((grid.height - lo[1]) / sy)) + 1)
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            if out[r, c]:
                continue
            w = grid.window(r, c)
            out[r, c] = bool(np.all(hi >= w[0]) and np.all(lo <= w[1]) and _hits_box(a, b, w))


def line_pages(pieces, layout: Layout, grid: PageGrid) -> np.ndarray:
    """(rows, cols) bool: the windows that a cut or sew line or a dart leg crosses."""
    ink = np.zeros((grid.rows, grid.cols), bool)
    for i, p in enumerate(pieces):
        a, b = _piece_segments(p)
        _windows_hit(place(layout, i, a), place(layout, i, b), grid, ink)
    return ink


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
            a, b = _segments([place(layout, i, box)])
            _windows_hit(a, b, grid, here)
            if np.any(here & ~ink):
                extra |= here
        g = place(layout, i, p.grain + grain_shift(layout, i))
        length = float(np.linalg.norm(g[1] - g[0]))
        if _shown(g, grid, ink) < min(GRAIN_SHOWN, length) - 1e-9:
            _windows_hit(g[:1], g[1:], grid, extra)
    return ink | extra


def _shown(seg: np.ndarray, grid: PageGrid, ink: np.ndarray, spacing: float = 0.002) -> float:
    """Length (m, to ``spacing``) of the segment ``seg`` (2, 2) that lies on printed windows."""
    n = max(2, int(math.ceil(np.linalg.norm(seg[1] - seg[0]) / spacing)) + 1)
    q = seg[0] + np.linspace(0.0, 1.0, n)[:, None] * (seg[1] - seg[0])
    seen = np.zeros(n, bool)
    for r, c in zip(*np.nonzero(ink)):
        w = grid.window(r, c)
        seen |= np.all((q >= w[0]) & (q <= w[1]), axis=1)
    return float(seen.mean() * np.linalg.norm(seg[1] - seg[0]))


def place_labels(pieces, layout: "PrintLayout", grid: PageGrid, ink: np.ndarray) -> np.ndarray:
    """(n, 2) piece-frame top-left corners for the labels, each on pages printed anyway.

    A label keeps its place when its pages are printed; otherwise it moves to
    the nearest place (on a ``LABEL_STEP`` lattice, nearest first) where it
    lies inside the sew line, clear of every line, notch, dart and the grain
    line (2 mm), and every page it reaches is printed (``ink``). A label that
    finds none keeps its place (its pages are then printed, :func:`inked_pages`).
    """
    out = np.array([np.asarray(p.label_at, float) for p in pieces]).reshape(-1, 2)
    for i, p in enumerate(pieces):
        box = label_box(p, p.label_at)
        if not len(box) or _label_on(box, layout, i, grid, ink):
            continue
        found = _label_place(p, box, layout, i, grid, ink)
        if found is not None:
            out[i] = found
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
            q = _sample_open(g + [dx, 0.0], 0.004)
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


def _label_on(box: np.ndarray, layout: Layout, i: int, grid: PageGrid, ink: np.ndarray) -> bool:
    """Whether every window that the piece-frame ``box`` of piece ``i`` reaches is printed."""
    here = np.zeros_like(ink)
    a, b = _segments([place(layout, i, box)])
    _windows_hit(a, b, grid, here)
    return not np.any(here & ~ink)


def _label_place(piece, box: np.ndarray, layout: Layout, i: int, grid: PageGrid, ink: np.ndarray):
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
    _fill(free, outline, lo[0], hi[1], cell)
    for hole in piece.sew[1:]:
        inner = np.zeros((h, w), bool)
        _fill(inner, np.asarray(hole, float), lo[0], hi[1], cell)
        free &= ~inner
    drawn = list(piece.cut) + list(piece.sew)
    opened = [piece.grain] + [leg for d in piece.darts for leg in d.legs] + [d.fold for d in piece.darts] \
        + [n.segment for n in piece.notches] + list(piece.fold)
    q = np.concatenate([_sample(drawn, cell / 2)] + [_sample_open(l, cell / 2) for l in opened])
    line = np.zeros((h, w), bool)
    rr, cc = np.floor((hi[1] - q[:, 1]) / cell).astype(int), np.floor((q[:, 0] - lo[0]) / cell).astype(int)
    keep = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
    line[rr[keep], cc[keep]] = True
    k = 1 + int(math.ceil(0.002 / cell))
    free &= ~binary_dilation(line, structure=np.ones((2 * k + 1, 2 * k + 1), bool))
    # cell centres on the sheet, off every page left out (its window widened by a cell)
    yc, xc = hi[1] - (np.arange(h) + 0.5) * cell, lo[0] + (np.arange(w) + 0.5) * cell
    centres = place(layout, i, np.stack(np.meshgrid(xc, yc), axis=-1).reshape(-1, 2))
    off = np.zeros(len(centres), bool)
    for r, c in zip(*np.nonzero(~ink)):
        win = grid.window(r, c)
        off |= np.all((centres >= win[0] - cell) & (centres <= win[1] + cell), axis=1)
    free &= ~off.reshape(h, w)
    # label top-left at cell corner (r, c): cells r .. r + nh - 1, c .. c + nw - 1 all free
    sat = np.zeros((h + 1, w + 1), int)
    sat[1:, 1:] = np.cumsum(np.cumsum(free, axis=0), axis=1)
    bad = sat[nh:, nw:] - sat[:-nh, nw:] - sat[nh:, :-nw] + sat[:-nh, :-nw] < nh * nw
    r, c = np.nonzero(~bad)
    if not len(r):
        return None
    at = np.stack([lo[0] + c * cell, hi[1] - r * cell], axis=1)
    for j in np.argsort(np.linalg.norm(at - piece.label_at, axis=1), kind="stable")[:20]:
        if _label_on(label_box(piece, at[j]), layout, i, grid, ink):
            return at[j]
    return None


def _sample_open(line, spacing: float) -> np.ndarray:
    """Points along an open polyline, at most ``spacing`` apart, ends included, (m, 2)."""
    p = np.asarray(line, float)
    if len(p) < 2:
        return p.reshape(-1, 2)
    return np.concatenate([a + np.linspace(0.0, 1.0, int(math.ceil(np.linalg.norm(b - a) / spacing)) + 2)[:, None]
                           * (b - a) for a, b in zip(p[:-1], p[1:])])


def _fill(mask: np.ndarray, poly: np.ndarray, x0: float, y1: float, cell: float) -> None:
    """Set the cells of ``mask`` (row 0 at y1, column 0 at x0) whose centre lies inside ``poly`` (scanlines)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    for i in range(mask.shape[0]):
        y = y1 - (i + 0.5) * cell
        s = (a[:, 1] > y) != (b[:, 1] > y)
        if not s.any():
            continue
        xs = np.sort(a[s, 0] + (y - a[s, 1]) * (b[s, 0] - a[s, 0]) / (b[s, 1] - a[s, 1]))
        for xa, xb in zip(xs[0::2], xs[1::2]):
            j0 = max(int(math.ceil((xa - x0) / cell - 0.5)), 0)
            j1 = min(int(math.floor((xb - x0) / cell - 0.5)), mask.shape[1] - 1)
            mask[i, j0:j1 + 1] = True


def _sample(loops: Sequence[np.ndarray], spacing: float) -> np.ndarray:
    """Points along closed loops, at most ``spacing`` apart, (m, 2)."""
    out = []
    for l in loops:
        a, b = l, np.roll(l, -1, axis=0)
        n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(int))
        t = np.concatenate([np.arange(k) / k for k in n])
        rep = np.repeat(np.arange(len(l)), n)
        out.append(a[rep] + t[:, None] * (b - a)[rep])
    return np.concatenate(out)


@dataclass
class _Shape:
    """One piece turned by ``angle`` (degrees): its occupied cells and line samples, from the raster's top-left."""
    angle: float
    mask: np.ndarray        # (h, w) bool, row 0 at the top
    corner: np.ndarray      # (2,) m, turned-frame position of the mask's top-left corner
    lines: np.ndarray       # (m, 2) m, line samples relative to ``corner`` (y <= 0)


def _shape(piece, angle: float, gap: float, cell: float) -> _Shape:
    from scipy.ndimage import binary_dilation

    R = rotation(angle)
    pad = gap / 2.0
    outline = np.asarray(piece.cut[0], float) @ R.T
    label = label_box(piece, piece.label_at) @ R.T
    corners = np.array([[piece.bbox[i, 0], piece.bbox[j, 1]] for i in (0, 1) for j in (0, 1)]) @ R.T
    lo, hi = corners.min(0) - pad, corners.max(0) + pad
    w = int(math.ceil((hi[0] - lo[0]) / cell))
    h = int(math.ceil((hi[1] - lo[1]) / cell))
    mask = np.zeros((h, w), bool)
    _fill(mask, outline, lo[0], hi[1], cell)
    if len(label):
        _fill(mask, label, lo[0], hi[1], cell)
    # the outline's own cells: a thin piece may have no cell centre inside
    edge = _sample([outline], cell / 2)
    mask[np.clip(((hi[1] - edge[:, 1]) / cell).astype(int), 0, h - 1),
         np.clip(((edge[:, 0] - lo[0]) / cell).astype(int), 0, w - 1)] = True
    k = int(math.ceil(pad / cell))
    if k:
        mask = binary_dilation(mask, structure=np.ones((2 * k + 1, 2 * k + 1), bool))
    corner = np.array([lo[0], hi[1]])
    lines = _sample([outline], SAMPLE) - corner
    return _Shape(float(angle), mask, corner, lines)


def _page_ids(points: np.ndarray, step: np.ndarray, tile: np.ndarray, cols: int) -> List[np.ndarray]:
    """For points (..., 2) (x right, depth down from the top edge, m): window ids (row * cols + col), -1 if none.

    A point lies in window c when c * step <= x <= c * step + tile: the last
    such c, and in the overlap strip also the one before; so 4 candidates.
    """
    out = []
    fx = np.floor(points[..., 0] / step[0])
    fy = np.floor(points[..., 1] / step[1])
    for cx in (fx, fx - 1):
        okx = (cx >= 0) & (cx < cols) & (points[..., 0] <= cx * step[0] + tile[0])
        for ry in (fy, fy - 1):
            ok = okx & (ry >= 0) & (points[..., 1] <= ry * step[1] + tile[1])
            out.append(np.where(ok, ry * cols + cx, -1).astype(np.int64))
    return out


def _candidates(free: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the free positions that start a free run (top of the column or below a blocked one)."""
    start = free.copy()
    start[1:] &= ~free[:-1]
    r, c = np.nonzero(start)
    return r, c


def _aligned(s: _Shape, hit: np.ndarray, step: np.ndarray, tile: np.ndarray, cell: float):
    """Free positions (rows, columns of ``hit``) where the piece's lines start just past a page line or end just
    before one, across and down: where a piece reaches no further page than it must."""
    x0, x1 = s.lines[:, 0].min(), s.lines[:, 0].max()
    d0, d1 = -s.lines[:, 1].max(), -s.lines[:, 1].min()   # depth of the lines below the raster's corner
    ov = tile - step
    rows, cols = hit.shape

    def lattice(lo, hi, k_max, st, tl, ov_, size):
        ks = np.arange(k_max + 2)
        first = np.ceil((ks * st + ov_ + ALIGN_EPS - lo) / cell)   # lines begin past window k - 1's end
        last = np.floor((ks * st + tl - ALIGN_EPS - hi) / cell)    # lines end before window k's end
        v = np.unique(np.concatenate([first, last]).astype(int))
        return v[(v >= 0) & (v < size)]

    rs = lattice(d0, d1, int(rows * cell / step[1]), step[1], tile[1], ov[1], rows)
    cs = lattice(x0, x1, int(cols * cell / step[0]), step[0], tile[0], ov[0], cols)
    R, C = np.meshgrid(rs, cs, indexing="ij")
    R, C = R.ravel(), C.ravel()
    ok = ~hit[R, C]
    return R[ok], C[ok]


def _overlaps(occ: np.ndarray, masks, below: int, spectra: dict, block: int = 64):
    """Per mask: (rows, cols) bool, where its top-left cell may go on ``occ`` without covering an occupied cell.

    The positions down to ``below`` rows past a mask's own height (as
    ``fftconvolve(occ[:top], mask[::-1, ::-1], "valid") > 0.5`` with
    ``top = below + h``), None where the mask is wider than ``occ``. One
    transform of the sheet serves all masks; the sheet is padded to a multiple
    of ``block`` rows so that a mask's transform (kept in ``spectra``) serves
    the next pieces too.
    """
    from scipy import fft as sfft
    wc = occ.shape[1]
    fit = [m for m in masks if m.shape[1] <= wc]
    if not fit:
        return [None] * len(masks)
    hmax = max(m.shape[0] for m in fit)
    wmax = max(m.shape[1] for m in fit)
    top = min(below + hmax, len(occ))
    rows = sfft.next_fast_len(int(math.ceil((top + hmax) / block)) * block, real=True)
    cols = sfft.next_fast_len(wc + wmax, real=True)
    sheet = sfft.rfft2(occ[:top], s=(rows, cols))
    out = []
    for m in masks:
        h, w = m.shape
        if w > wc:
            out.append(None)
            continue
        key = (id(m), rows, cols)
        if key not in spectra:
            spectra[key] = (m, sfft.rfft2(m[::-1, ::-1].astype(float), s=(rows, cols)))
        full = sfft.irfft2(sheet * spectra[key][1], s=(rows, cols))
        # the "valid" part for this mask's own depth: rows h - 1 .. top_m - 1, columns w - 1 .. wc - 1
        top_m = min(below + h, len(occ))
        out.append(full[h - 1:top_m, w - 1:wc] > 0.5)
    return out


def _choose(new, bottom, col):
    return np.lexsort((col, bottom, new))[0]


def _pack(shapes, order, width: float, tile: np.ndarray, overlap: float, reserve, gap: float, cell: float):
    """Place every piece (``shapes[i]``: its turned variants) in ``order`` on a sheet ``width`` wide.

    Returns per piece (shape, x, depth of its raster's top-left) in m with the
    sheet's top edge at depth 0, the sheet depth used, and the pages touched.
    """
    step = tile - overlap
    wc = int(math.floor(width / cell))
    cols = max(1, int(math.ceil((width - overlap) / step[0] - 1e-9)))
    depth_cells = sum(max(max(s.mask.shape) for s in v) for v in shapes) + 2 * int(math.ceil(tile[1] / cell)) + 2
    occ = np.zeros((depth_cells, wc))
    depth = 0.0
    if reserve is not None:  # the test square and page map, top-left, half a gap from the edges
        rh, rw = int(math.ceil((reserve[1] + gap) / cell)), int(math.ceil((reserve[0] + gap) / cell))
        occ[:rh, :rw] = 1.0
        depth = rh * cell
    rows_max = int(math.ceil(depth_cells * cell / step[1])) + 2
    used = np.zeros(rows_max * cols + 1, bool)
    used[0] = True
    placed = {}
    spectra = {}
    for i in order:
        best = None
        hits = _overlaps(occ, [s.mask for s in shapes[i]], int(math.ceil(depth / cell)) + 1
                         + int(math.ceil(tile[1] / cell)), spectra)
        for s, hit in zip(shapes[i], hits):
            h, w = s.mask.shape
            if hit is None:
                continue
            r, c = _candidates(~hit)
            ra, ca = _aligned(s, hit, step, tile, cell)
            r, c = np.concatenate([r, ra]), np.concatenate([c, ca])
            if not len(r):
                continue
            # line samples of every candidate: x right, depth down
            pts = np.empty((len(r), len(s.lines), 2))
            pts[..., 0] = c[:, None] * cell + s.lines[None, :, 0]
            pts[..., 1] = r[:, None] * cell - s.lines[None, :, 1]
            touched = np.zeros((len(r), len(used)), bool)
            rows_idx = np.broadcast_to(np.arange(len(r))[:, None], pts.shape[:2])
            for ids in _page_ids(pts, step, tile, cols):
                ok = ids >= 0
                touched[rows_idx[ok], ids[ok]] = True
            new = (touched & ~used).sum(axis=1)
            key = _choose(new, r + h, c)
            cand = (int(new[key]), int(r[key] + h), int(c[key]))
            if best is None or cand < best[0]:
                best = (cand, s, int(r[key]), int(c[key]), touched[key])
        if best is None:
            raise ValueError("a piece does not fit the sheet")
        _, s, r, c, touched = best
        h, w = s.mask.shape
        occ[r:r + h, c:c + w] += s.mask
        used |= touched
        placed[i] = (s, c * cell, r * cell)
        depth = max(depth, (r + h) * cell)
    return placed, depth, int(used.sum())


def print_layout(pieces, tile: Sequence[float], overlap: float, reserve: Optional[Tuple[float, float]] = None,
                 gap: float = GAP, cell: float = CELL) -> Tuple[PrintLayout, PageGrid]:
    """Pieces nested onto the page grid of a tiled PDF so that the fewest pages carry a line.

    Parameters
    ----------
    pieces : :class:`core.export.pieces.PieceDrawing` list (``bbox``, ``cut``, ``sew``, label).
    tile : (w, h) m, the printable window of one page.
    overlap : m shared by neighbouring windows.
    reserve : (w, h) m kept free at the top-left (test square and page map), or None.
    gap : m of paper between pieces.
    cell : m, raster resolution.

    Returns
    -------
    layout : :class:`PrintLayout` (sheet width a whole number of windows); ``reserved`` is the reserve's box.
    grid : :class:`PageGrid` covering it.
    """
    tile = np.asarray(tile, float)
    step = tile - overlap
    angles = [90.0 * k + t for t in TILTS for k in TURNS]
    shapes = [[_shape(p, a, gap, cell) for a in angles] for p in pieces]
    # quarter turns alone, then tilted too: a greedy packer with more choices is not always better
    sets = [[v[:len(TURNS)] for v in shapes], shapes] if len(TILTS) > 1 else [shapes]
    # a piece must fit in some turn: the narrowest turn of the widest piece sets the first width tried
    need = max([min(s.mask.shape[1] for s in v) * cell for v in shapes] + [(reserve[0] + gap) if reserve else 0.0])
    cols0 = max(1, int(math.ceil((need + cell - overlap) / step[0] - 1e-9)))
    area = [-int(np.count_nonzero(v[0].mask)) for v in shapes]
    tall = [-max(v[0].mask.shape) for v in shapes]
    n = len(pieces)
    orders = [sorted(range(n), key=lambda i: (area[i], i)), sorted(range(n), key=lambda i: (tall[i], area[i], i))]
    best = None
    for cols, order, shown in itertools.product(range(cols0, cols0 + EXTRA_COLUMNS + 1), orders, sets):
        width = cols * step[0] + overlap
        placed, depth, _ = _pack(shown, order, width, tile, overlap, reserve, gap, cell)
        height = max(depth, float(tile[1]))
        turned = np.array([placed[i][0].angle for i in range(n)], float)
        # piece frame -> sheet: R p + offset, with the raster's corner at (x, height - depth)
        offsets = np.array([[placed[i][1], height - placed[i][2]] - placed[i][0].corner for i in range(n)])
        reserved = None if reserve is None else np.array(
            [[gap / 2, height - gap / 2 - reserve[1]], [gap / 2 + reserve[0], height - gap / 2]])
        lay = PrintLayout(offsets=offsets, size=np.array([width, height]), reserved=reserved, angles=turned)
        grid = grid_for(lay.size, tile, overlap)
        ink = line_pages(pieces, lay, grid)
        ink[0, 0] = True
        lay.labels = place_labels(pieces, lay, grid, ink)
        lay.grains = place_grains(pieces, lay, grid, ink)
        pages = int(inked_pages(pieces, lay, grid).sum())
        if best is None or pages < best[0]:
            best = (pages, lay, grid)
    return best[1], best[2]


__all__ = ["PrintLayout", "PageGrid", "rotation", "place", "grid_for", "line_pages", "inked_pages", "place_labels",
           "label_at", "label_box", "grain_shift", "place_grains", "print_layout", "piece_lines", "CELL", "GAP"]
