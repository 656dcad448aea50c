"""Sheets: the pieces laid out for the SVG/DXF sheet and the plotter roll.

The packing itself is :func:`core.geom.layout.layout_pieces` (one definition
for the export, the pattern plot and the add-on); this module holds the
export's sheet sizes. The tiled home-printer PDFs nest the pieces for their
page grid instead (:mod:`core.export.tiling`).
"""

from __future__ import annotations

from ..geom.layout import Layout, layout_pieces

SHEET_WIDTH = 0.88  # m: with the PDF margins the plotter sheet is 900 mm, inside a 914 mm roll
LAYOUT_MARGIN = 0.02  # m between pieces

__all__ = ["Layout", "layout_pieces", "SHEET_WIDTH", "LAYOUT_MARGIN"]
