"""The marker stage: every piece of one or more sizes nested on a fabric width (a cutting-room marker).

After export in the pipeline (its pieces are the exporter's drawings,
:func:`core.export.pieces.build_pieces`, with the export's allowance rule):

- :mod:`.nesting`: the items to nest, the option checks, the nester run (spyrrow in
  its own process), the :class:`Marker` and its report;
- :mod:`.outline`: the simpler polygon each cut line is nested as, holding it;
- :mod:`.render`: ``marker.dxf``, ``.svg``, ``.pdf``, ``.png`` and ``marker.json``;
- :mod:`.worker`: the nesting process (standalone: imports no EASE module).

The CLI (``ease marker``), the add-on and batch runs reach it through
:func:`core.workflows.marker`.
"""

from __future__ import annotations

from .nesting import (
    MAX_GARMENTS,
    MAX_SECONDS,
    MAX_WIDTH,
    SPREADS,
    Marker,
    MarkerItem,
    Placement,
    check_options,
    default_split,
    default_tries,
    marker_items,
    marker_report,
    nest,
    orientations,
    parse_quantities,
    placed_outline,
    size_label,
)
from .render import write_marker

__all__ = [
    "Marker",
    "MarkerItem",
    "Placement",
    "marker_items",
    "nest",
    "check_options",
    "default_split",
    "default_tries",
    "orientations",
    "parse_quantities",
    "size_label",
    "placed_outline",
    "marker_report",
    "write_marker",
    "MAX_WIDTH",
    "MAX_SECONDS",
    "MAX_GARMENTS",
    "SPREADS",
]
