"""Page windows of a tiled print sheet and the lines that reach them.

The sheet of a tiled PDF is a grid of page windows (:class:`PageGrid`: the
printable area of the paper, neighbouring windows overlapping by the taping
strip). A piece lies on the sheet turned and shifted (:class:`PrintLayout`);
:func:`line_pages` tells which windows its cut and sew lines and dart legs
cross (Liang-Barsky clipping of their segments). Raster helpers shared by the
print packer (:mod:`.tiling`) and the label placement (:mod:`.print_labels`)
sample lines and fill polygons on a cell grid.

All lengths are metres, sheet frame y up, origin bottom-left.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from ..geom.layout import Layout


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

    def windows(self, which: np.ndarray) -> np.ndarray:
        """(k, 2, 2) float: :meth:`window` of each cell set in the (rows, cols) bool ``which``, in
        ``np.nonzero`` order (the same numbers, all at once)."""
        r, c = np.nonzero(which)
        sx, sy = self.step
        y1 = self.height - r * sy
        lo = np.stack([c * sx, y1 - self.tile[1]], axis=-1)
        hi = np.stack([c * sx + self.tile[0], y1], axis=-1)
        return np.stack([lo, hi], axis=1)

    def holding(self, which: np.ndarray, lo: np.ndarray, hi: np.ndarray, pad: float = 0.0) -> np.ndarray:
        """(m,) bool: whether the box ``lo[j]``..``hi[j]`` ((m, 2) each) lies within a window set in ``which``
        (each window widened by ``pad`` m on every side)."""
        w = self.windows(which)
        if pad:
            w = np.stack([w[:, 0] - pad, w[:, 1] + pad], axis=1)
        inside = (lo[:, None, :] >= w[None, :, 0, :]) & (hi[:, None, :] <= w[None, :, 1, :])
        return inside.all(axis=2).any(axis=1)


def grid_for(size: Sequence[float], tile: Sequence[float], overlap: float) -> PageGrid:
    """The fewest windows of ``tile`` (m, overlapping by ``overlap``) that cover a sheet of ``size`` (m)."""
    step = np.asarray(tile, float) - overlap
    cols = max(1, int(math.ceil((float(size[0]) - overlap) / step[0] - 1e-9)))
    rows = max(1, int(math.ceil((float(size[1]) - overlap) / step[1] - 1e-9)))
    return PageGrid(
        tile=(float(tile[0]), float(tile[1])), overlap=float(overlap), rows=rows, cols=cols, height=float(size[1])
    )


def piece_lines(piece) -> List[np.ndarray]:
    """The closed cut and sew loops of a piece, (k, 2) float each, piece frame: what makes a page worth printing."""
    return [np.asarray(l, float) for l in list(piece.cut) + list(piece.sew)]


def segments(loops, open_lines=()) -> Tuple[np.ndarray, np.ndarray]:
    """Segment ends (a, b), (k, 2) each, of closed loops and open polylines."""
    a = [np.asarray(l, float) for l in loops] + [np.asarray(l, float)[:-1] for l in open_lines]
    b = [np.roll(np.asarray(l, float), -1, axis=0) for l in loops] + [np.asarray(l, float)[1:] for l in open_lines]
    if not a:
        return np.zeros((0, 2)), np.zeros((0, 2))
    return np.concatenate(a), np.concatenate(b)


def _piece_segments(piece) -> Tuple[np.ndarray, np.ndarray]:
    """Piece-frame segments of the lines that make a page worth printing: cut and sew loops, dart legs."""
    return segments(piece_lines(piece), [leg for d in piece.darts for leg in d.legs])


def _hits_boxes(a: np.ndarray, b: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """(k,) bool: whether any segment a[i]-b[i] meets each closed box ``boxes`` (k, 2, 2) (Liang-Barsky clipping,
    vectorised over segments and boxes)."""
    d = b - a
    shape = (len(boxes), len(a))
    t0, t1, ok = np.zeros(shape), np.ones(shape), np.ones(shape, bool)
    for k in range(2):
        for p, q in (
            (-d[:, k], a[None, :, k] - boxes[:, None, 0, k]),
            (d[:, k], boxes[:, None, 1, k] - a[None, :, k]),
        ):
            par = np.abs(p) < 1e-15
            ok &= ~(par & (q < 0))
            r = q / np.where(par, 1.0, p)
            t0 = np.where(~par & (p < 0), np.maximum(t0, r), t0)
            t1 = np.where(~par & (p > 0), np.minimum(t1, r), t1)
    return np.any(ok & (t0 <= t1), axis=1)


def windows_hit(a: np.ndarray, b: np.ndarray, grid: PageGrid, out: np.ndarray) -> None:
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
    if r1 < r0 or c1 < c0:
        return
    todo = np.zeros(out.shape, bool)
    todo[r0 : r1 + 1, c0 : c1 + 1] = True
    todo &= ~out
    w = grid.windows(todo)
    near = np.flatnonzero(np.all(hi >= w[:, 0], axis=1) & np.all(lo <= w[:, 1], axis=1))
    if not len(near):
        return
    rows, cols = np.nonzero(todo)
    hit = near[_hits_boxes(a, b, w[near])]
    out[rows[hit], cols[hit]] = True


def line_pages(pieces, layout: Layout, grid: PageGrid) -> np.ndarray:
    """(rows, cols) bool: the windows that a cut or sew line or a dart leg crosses."""
    ink = np.zeros((grid.rows, grid.cols), bool)
    for i, p in enumerate(pieces):
        a, b = _piece_segments(p)
        windows_hit(place(layout, i, a), place(layout, i, b), grid, ink)
    return ink


def sample_open(line, spacing: float) -> np.ndarray:
    """Points along an open polyline, at most ``spacing`` apart, ends included, (m, 2)."""
    p = np.asarray(line, float)
    if len(p) < 2:
        return p.reshape(-1, 2)
    return np.concatenate(
        [
            a + np.linspace(0.0, 1.0, int(math.ceil(np.linalg.norm(b - a) / spacing)) + 2)[:, None] * (b - a)
            for a, b in zip(p[:-1], p[1:])
        ]
    )


def fill_cells(mask: np.ndarray, poly: np.ndarray, x0: float, y1: float, cell: float) -> None:
    """Set the cells of ``mask`` (row 0 at y1, column 0 at x0) whose centre lies inside ``poly`` (scanlines).

    All rows at once: the crossings of each row's centre line with the edges, sorted along the row, taken in
    pairs (even-odd rule); each pair fills the cells whose centres lie between them.
    """
    a, b = np.asarray(poly, float), np.roll(np.asarray(poly, float), -1, axis=0)
    h, w = mask.shape
    if not h or not len(a):
        return
    y = y1 - (np.arange(h) + 0.5) * cell
    cross = (a[None, :, 1] > y[:, None]) != (b[None, :, 1] > y[:, None])
    rows, edges = np.nonzero(cross)
    if not len(rows):
        return
    xs = np.full(cross.shape, np.inf)
    e0, e1 = a[edges], b[edges]
    xs[rows, edges] = e0[:, 0] + (y[rows] - e0[:, 1]) * (e1[:, 0] - e0[:, 0]) / (e1[:, 1] - e0[:, 1])
    xs = np.sort(xs, axis=1)[:, : 2 * (int(cross.sum(axis=1).max()) // 2)]
    xa, xb = xs[:, 0::2], xs[:, 1::2]
    ok = np.isfinite(xb)
    r = np.broadcast_to(np.arange(h)[:, None], xa.shape)[ok]
    j0 = np.maximum(np.ceil((xa[ok] - x0) / cell - 0.5), 0).astype(np.int64)
    j1 = np.minimum(np.floor((xb[ok] - x0) / cell - 0.5), w - 1).astype(np.int64)
    keep = j0 <= j1
    r, j0, j1 = r[keep], j0[keep], j1[keep]
    diff = np.zeros((h, w + 1), np.int64)
    np.add.at(diff, (r, j0), 1)
    np.add.at(diff, (r, j1 + 1), -1)
    mask |= np.cumsum(diff[:, :w], axis=1) > 0


def sample_loops(loops: Sequence[np.ndarray], spacing: float) -> np.ndarray:
    """Points along closed loops, at most ``spacing`` apart, (m, 2)."""
    out = []
    for l in loops:
        a, b = l, np.roll(l, -1, axis=0)
        n = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / spacing).astype(int))
        t = np.concatenate([np.arange(k) / k for k in n])
        rep = np.repeat(np.arange(len(l)), n)
        out.append(a[rep] + t[:, None] * (b - a)[rep])
    return np.concatenate(out)
