"""Print layout: the pieces nested for home-printer pages, and which pages carry a line.

A tiled PDF costs one sheet of paper per page that the printer feeds, so the
pieces are placed to touch as few pages as possible, not to make the
shortest strip. The sheet is a grid of page windows (the printable area of
the paper); neighbouring windows overlap by ``overlap`` for taping. Pieces
are rasterised (cut line filled, the label, plus half the paper gap between
pieces on every side) and placed one by one, largest first, turned by a
multiple of 90 degrees (paper may be turned: the grain line is drawn on
it): of the positions where a piece fits (the first free cell after every
occupied run, per column), the one whose cut and sew lines reach the fewest
pages no earlier piece reached wins, then the shallowest, then the leftmost.
Several sheet widths (whole numbers of pages) and orders are tried; the layout
with the fewest printed pages wins (ties: the one tried first). Every step is
deterministic.

A page is printed when a cut or sew line crosses its window
(:func:`inked_pages`); a page that lies wholly inside a piece or between
pieces is left out. The top-left page (test square and page map) is always
printed.

All lengths are metres, sheet frame y up, origin bottom-left.
"""
from __future__ import annotations

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


@dataclass
class PrintLayout(Layout):
    """A :class:`core.geom.layout.Layout` whose pieces may be turned: sheet = R(90° · turns[i]) @ p + offsets[i]."""
    turns: Optional[np.ndarray] = None

    def matrix(self, i: int) -> np.ndarray:
        """(2, 2) float, the rotation of piece ``i`` (piece frame -> sheet)."""
        return quarter_turn(0 if self.turns is None else int(self.turns[i]))

    def place(self, i: int, points) -> np.ndarray:
        """(m, 2) piece-frame points of piece ``i`` on the sheet."""
        return np.asarray(points, float) @ self.matrix(i).T + self.offsets[i]


def quarter_turn(k: int) -> np.ndarray:
    """(2, 2) rotation by ``k`` x 90 degrees counter-clockwise (exact integers)."""
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][k % 4]
    return np.array([[c, -s], [s, c]], float)


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


def inked_pages(pieces, layout: Layout, grid: PageGrid) -> np.ndarray:
    """(rows, cols) bool: the windows a cut or sew line crosses, and the top-left page (test square, map)."""
    segs = []
    for i, p in enumerate(pieces):
        loops = [place(layout, i, l) for l in piece_lines(p)]
        a = np.concatenate(loops)
        b = np.concatenate([np.roll(l, -1, axis=0) for l in loops])
        segs.append((a, b, np.minimum(a, b).min(0), np.maximum(a, b).max(0)))
    ink = np.zeros((grid.rows, grid.cols), bool)
    for r in range(grid.rows):
        for c in range(grid.cols):
            w = grid.window(r, c)
            ink[r, c] = any(np.all(hi >= w[0]) and np.all(lo <= w[1]) and _hits_box(a, b, w)
                            for a, b, lo, hi in segs)
    ink[0, 0] = True
    return ink


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
    """One piece turned by ``turn``: its occupied cells, its line samples, both relative to the raster's top-left."""
    turn: int
    mask: np.ndarray        # (h, w) bool, row 0 at the top
    corner: np.ndarray      # (2,) m, turned-frame position of the mask's top-left corner
    lines: np.ndarray       # (m, 2) m, line samples relative to ``corner`` (y <= 0)


def _shape(piece, turn: int, gap: float, cell: float) -> _Shape:
    from scipy.ndimage import binary_dilation
    from .pieces import CHAR_WIDTH

    R = quarter_turn(turn)
    pad = gap / 2.0
    outline = np.asarray(piece.cut[0], float) @ R.T
    label = np.zeros((0, 2))
    if piece.label:
        th = len(piece.label) * 1.5 * piece.text_height
        tw = max(len(s) for s in piece.label) * CHAR_WIDTH * piece.text_height
        x, y = piece.label_at
        label = np.array([[x, y - th], [x + tw, y - th], [x + tw, y], [x, y]]) @ R.T
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
    return _Shape(turn, mask, corner, lines)


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


def _choose(new, bottom, col):
    return np.lexsort((col, bottom, new))[0]


def _pack(shapes, order, width: float, tile: np.ndarray, overlap: float, reserve, gap: float, cell: float):
    """Place every piece (``shapes[i]``: its turned variants) in ``order`` on a sheet ``width`` wide.

    Returns per piece (turn, x, depth of its raster's top-left) in m with the
    sheet's top edge at depth 0, the sheet depth used, and the pages touched.
    """
    from scipy.signal import fftconvolve

    step = tile - overlap
    wc = int(math.floor(width / cell))
    cols = max(1, int(math.ceil((width - overlap) / step[0] - 1e-9)))
    depth_cells = sum(max(s.mask.shape) for v in shapes for s in v[:1]) + int(math.ceil(tile[1] / cell)) + 2
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
    for i in order:
        best = None
        for s in shapes[i]:
            h, w = s.mask.shape
            if w > wc:
                continue
            # only the filled part of the sheet and one piece height below it can hold the piece
            top = min(int(math.ceil(depth / cell)) + h + 1, len(occ))
            hit = fftconvolve(occ[:top], s.mask[::-1, ::-1].astype(float), mode="valid") > 0.5
            r, c = _candidates(~hit)
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
    shapes = [[_shape(p, t, gap, cell) for t in TURNS] for p in pieces]
    # a piece must fit in some turn: the narrowest turn of the widest piece sets the first width tried
    need = max([min(s.mask.shape[1] for s in v) * cell for v in shapes] + [(reserve[0] + gap) if reserve else 0.0])
    cols0 = max(1, int(math.ceil((need + cell - overlap) / step[0] - 1e-9)))
    area = [-int(np.count_nonzero(v[0].mask)) for v in shapes]
    tall = [-max(v[0].mask.shape) for v in shapes]
    n = len(pieces)
    orders = [sorted(range(n), key=lambda i: (area[i], i)), sorted(range(n), key=lambda i: (tall[i], area[i], i))]
    best = None
    for cols in range(cols0, cols0 + EXTRA_COLUMNS + 1):
        width = cols * step[0] + overlap
        for order in orders:
            placed, depth, _ = _pack(shapes, order, width, tile, overlap, reserve, gap, cell)
            height = max(depth, float(tile[1]))
            turns = np.array([placed[i][0].turn for i in range(n)], int)
            # piece frame -> sheet: R p + offset, with the raster's corner at (x, height - depth)
            offsets = np.array([[placed[i][1], height - placed[i][2]] - placed[i][0].corner for i in range(n)])
            reserved = None if reserve is None else np.array(
                [[gap / 2, height - gap / 2 - reserve[1]], [gap / 2 + reserve[0], height - gap / 2]])
            lay = PrintLayout(offsets=offsets, size=np.array([width, height]), reserved=reserved, turns=turns)
            grid = grid_for(lay.size, tile, overlap)
            pages = int(inked_pages(pieces, lay, grid).sum())
            if best is None or pages < best[0]:
                best = (pages, lay, grid)
    return best[1], best[2]


__all__ = ["PrintLayout", "PageGrid", "quarter_turn", "place", "grid_for", "inked_pages", "print_layout",
           "piece_lines", "CELL", "GAP"]
