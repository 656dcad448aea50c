"""Sheets: the pieces laid out for the SVG/DXF sheet, the plotter roll and the tiled home-printer PDFs.

The packing itself is :func:`core.geom.layout.layout_pieces` (one definition
for the export, the pattern plot and the add-on); this module holds the
export's sheet sizes and the choice of sheet width for tiled pages.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..geom.layout import Layout, layout_pieces
from . import pdf

SHEET_WIDTH = 0.88      # m: with the PDF margins the plotter sheet is 900 mm, inside a 914 mm roll
LAYOUT_MARGIN = 0.02    # m between pieces

__all__ = ["Layout", "layout_pieces", "fewest_pages", "SHEET_WIDTH", "LAYOUT_MARGIN"]


def fewest_pages(boxes: Sequence[np.ndarray], paper: str) -> Layout:
    """The layout, a whole number of pages wide, that needs the fewest pages of ``paper``.

    Parameters
    ----------
    boxes : n (2, 2) float arrays, min/max corners of each piece (piece frame, m).
    paper : a key of :data:`core.export.pdf.PAPERS` (``"a4"``, ``"letter"``).

    Returns
    -------
    :class:`core.geom.layout.Layout` with the PDF test square reserved; of
    1 to 8 page columns, the first with the fewest pages.
    """
    tile_w = pdf.PAPERS[paper][0] - 2 * pdf.PAGE_MARGIN
    widest = max([float(b[1, 0] - b[0, 0]) for b in boxes] + [pdf.TEST_RESERVE[0]]) + 2 * LAYOUT_MARGIN
    best = None
    for cols in range(max(1, int(np.ceil(widest / tile_w - 1e-9))), 9):
        lay = layout_pieces(boxes, cols * tile_w, LAYOUT_MARGIN, reserve=pdf.TEST_RESERVE)
        rows, ncols, _ = pdf.tile_grid(lay.size, paper)
        if best is None or rows * ncols < best[0]:
            best = (rows * ncols, lay)
    return best[1]
