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
(:mod:`.pages`); a page that lies wholly inside a piece or between pieces is
left out, and labels and grain lines are moved onto printed pages
(:mod:`.print_labels`).

All lengths are metres, sheet frame y up, origin bottom-left.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .pages import PageGrid, PrintLayout, fill_cells, grid_for, line_pages, piece_lines, place, rotation, sample_loops
from .print_labels import grain_shift, inked_pages, label_at, label_box, place_grains, place_labels

CELL = 0.0075  # m, raster cell of the packer (5 mm packs no tighter on the teaser, at twice the time)
GAP = 0.010  # m, paper between two pieces (room for the scissors)
SAMPLE = 0.008  # m, spacing of the cut-line samples that count a piece's pages while packing
EXTRA_COLUMNS = 4  # sheet widths tried: the narrowest that holds the widest piece, and this many more
TURNS = (0, 1, 2, 3)  # quarter turns tried per piece
# degrees added to each quarter turn: (0, -5, 5, -10, 10) prints the teaser on 58 A4 pages instead of 61 (Letter 62
# either way) for 4.5x the layout time (~10 s CPU a paper instead of ~2 s), so no tilt by default
TILTS = (0.0,)  # the first is 0: print_layout tries the quarter turns alone first
ALIGN_EPS = 0.0015  # m, how far past a page line an aligned position puts the piece's lines


@dataclass
class _Shape:
    """One piece turned by ``angle`` (degrees): its occupied cells and line samples, from the raster's top-left."""

    angle: float
    mask: np.ndarray  # (h, w) bool, row 0 at the top
    corner: np.ndarray  # (2,) m, turned-frame position of the mask's top-left corner
    lines: np.ndarray  # (m, 2) m, line samples relative to ``corner`` (y <= 0)


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
    fill_cells(mask, outline, lo[0], hi[1], cell)
    if len(label):
        fill_cells(mask, label, lo[0], hi[1], cell)
    # the outline's own cells: a thin piece may have no cell centre inside
    edge = sample_loops([outline], cell / 2)
    mask[
        np.clip(((hi[1] - edge[:, 1]) / cell).astype(int), 0, h - 1),
        np.clip(((edge[:, 0] - lo[0]) / cell).astype(int), 0, w - 1),
    ] = True
    k = int(math.ceil(pad / cell))
    if k:
        mask = binary_dilation(mask, structure=np.ones((2 * k + 1, 2 * k + 1), bool))
    corner = np.array([lo[0], hi[1]])
    lines = sample_loops([outline], SAMPLE) - corner
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
    d0, d1 = -s.lines[:, 1].max(), -s.lines[:, 1].min()  # depth of the lines below the raster's corner
    ov = tile - step
    rows, cols = hit.shape

    def lattice(lo, hi, k_max, st, tl, ov_, size):
        ks = np.arange(k_max + 2)
        first = np.ceil((ks * st + ov_ + ALIGN_EPS - lo) / cell)  # lines begin past window k - 1's end
        last = np.floor((ks * st + tl - ALIGN_EPS - hi) / cell)  # lines end before window k's end
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
        out.append(full[h - 1 : top_m, w - 1 : wc] > 0.5)
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
        hits = _overlaps(
            occ, [s.mask for s in shapes[i]], int(math.ceil(depth / cell)) + 1 + int(math.ceil(tile[1] / cell)), spectra
        )
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
        occ[r : r + h, c : c + w] += s.mask
        used |= touched
        placed[i] = (s, c * cell, r * cell)
        depth = max(depth, (r + h) * cell)
    return placed, depth, int(used.sum())


def print_layout(
    pieces,
    tile: Sequence[float],
    overlap: float,
    reserve: Optional[Tuple[float, float]] = None,
    gap: float = GAP,
    cell: float = CELL,
) -> Tuple[PrintLayout, PageGrid]:
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
    sets = [[v[: len(TURNS)] for v in shapes], shapes] if len(TILTS) > 1 else [shapes]
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
        reserved = (
            None
            if reserve is None
            else np.array([[gap / 2, height - gap / 2 - reserve[1]], [gap / 2 + reserve[0], height - gap / 2]])
        )
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


__all__ = [
    "PrintLayout",
    "PageGrid",
    "rotation",
    "place",
    "grid_for",
    "line_pages",
    "inked_pages",
    "place_labels",
    "label_at",
    "label_box",
    "grain_shift",
    "place_grains",
    "print_layout",
    "piece_lines",
    "CELL",
    "GAP",
]
