"""SVG at 1:1 in millimetres, written by hand.

``width``/``height`` carry the ``mm`` unit and the ``viewBox`` is in
millimetres, so one user unit is one millimetre in every viewer, printer and
laser cutter. One ``<g>`` per piece; lines are told apart by stroke colour
(laser cutters map colours to operations): cut line red, sew line blue,
notches green, grain line black, fold (mirror) line magenta, text black;
a dart's legs blue (class ``dart``), its fold arrow and drill hole grey.
"""

from __future__ import annotations

from typing import List, Sequence
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..geom.layout import Layout
from .darts import DRILL_DIAMETER
from .pieces import PieceDrawing

COLOURS = {
    "cut": "#ff0000",
    "sew": "#0000ff",
    "notch": "#00a000",
    "grain": "#000000",
    "fold": "#ff00ff",
    "text": "#000000",
    "mark": "#808080",
}
STROKE_MM = 0.25


def svg_number(v: float) -> str:
    """``v`` (mm) as SVG text: at most 3 decimals (a micrometre), no trailing zeros, never ``-0``."""
    s = f"{v:.3f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def svg_path(points_mm: np.ndarray, closed: bool) -> str:
    """The ``d`` attribute of a polyline through ``points_mm`` (n, 2), closed with ``Z`` if ``closed``."""
    p = points_mm
    d = "M" + " L".join(f"{svg_number(x)},{svg_number(y)}" for x, y in p)
    return d + (" Z" if closed else "")


def svg_document(pieces: Sequence[PieceDrawing], layout: Layout, title: str = "pattern") -> str:
    """The SVG text of the laid-out pieces.

    Parameters
    ----------
    pieces : the drawings, in the order of ``layout.offsets``.
    layout : :class:`core.geom.layout.Layout` (metres).
    title : str, document title.
    """
    W, H = layout.size * 1000.0

    def mm(points: np.ndarray, offset: np.ndarray) -> np.ndarray:
        q = (np.asarray(points, float) + offset) * 1000.0
        return np.column_stack([q[:, 0], H - q[:, 1]])

    out: List[str] = [
        '<?xml version="1.0" encoding="UTF-8" standalone="no"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{svg_number(W)}mm" height="{svg_number(H)}mm" '
        f'viewBox="0 0 {svg_number(W)} {svg_number(H)}">',
        f"<title>{escape(title)}</title>",
        "<desc>EASE sewing pattern at 1:1; 1 user unit = 1 mm. Red: cut line (seam allowance included); "
        "blue: sew line; green: notches; black: grain line and labels; magenta: fold line.</desc>",
    ]
    line = f'fill="none" stroke-width="{STROKE_MM}" stroke-linejoin="round" stroke-linecap="round"'
    for piece, off in zip(pieces, layout.offsets):
        out.append(
            f"<g id={quoteattr('piece-' + piece.name)} data-piece={quoteattr(piece.name)} "
            f'data-quantity="{piece.quantity}">'
        )
        for loop in piece.cut:
            out.append(f'<path class="cut" d="{svg_path(mm(loop, off), True)}" stroke="{COLOURS["cut"]}" {line}/>')
        for loop in piece.sew:
            out.append(
                f'<path class="sew" d="{svg_path(mm(loop, off), True)}" stroke="{COLOURS["sew"]}" '
                f'stroke-dasharray="4,2" {line}/>'
            )
        for f in piece.fold:
            out.append(
                f'<path class="fold" d="{svg_path(mm(f, off), False)}" stroke="{COLOURS["fold"]}" '
                f'stroke-dasharray="8,2,1,2" {line}/>'
            )
        for dart in piece.darts:
            d = " ".join(svg_path(mm(leg, off), False) for leg in dart.legs)
            out.append(
                f'<path class="dart" data-dart={quoteattr(dart.name)} d="{d}" stroke="{COLOURS["sew"]}" {line}/>'
            )
            d = " ".join(svg_path(mm(x, off), False) for x in (dart.fold, dart.fold_head))
            out.append(f'<path class="dart-fold" d="{d}" stroke="{COLOURS["mark"]}" {line}/>')
            x, y = mm(dart.drill[None], off)[0]
            out.append(
                f'<circle class="drill" cx="{svg_number(x)}" cy="{svg_number(y)}" r="{svg_number(500 * DRILL_DIAMETER)}" '
                f'stroke="{COLOURS["mark"]}" {line}/>'
            )
        for pleat in piece.pleats:
            for kind, lines in (("pleat-fold", pleat.folds), ("pleat-placement", pleat.placements)):
                d = " ".join(svg_path(mm(x, off), False) for x in lines)
                dash = "6,2" if kind == "pleat-fold" else "2,2"
                out.append(
                    f'<path class="{kind}" data-pleat={quoteattr(pleat.name)} d="{d}" stroke="{COLOURS["mark"]}" '
                    f'stroke-dasharray="{dash}" {line}/>'
                )
            for x, y in mm(pleat.stitch_ends, off) if len(pleat.stitch_ends) else []:
                out.append(
                    f'<circle class="drill" cx="{svg_number(x)}" cy="{svg_number(y)}" r="{svg_number(500 * DRILL_DIAMETER)}" '
                    f'stroke="{COLOURS["mark"]}" {line}/>'
                )
        if piece.notches:
            d = " ".join(svg_path(mm(n.segment, off), False) for n in piece.notches)
            out.append(f'<path class="notch" d="{d}" stroke="{COLOURS["notch"]}" {line}/>')
        d = " ".join([svg_path(mm(piece.grain, off), False)] + [svg_path(mm(a, off), False) for a in piece.arrows])
        out.append(f'<path class="grain" d="{d}" stroke="{COLOURS["grain"]}" {line}/>')
        h = piece.text_height * 1000.0
        x, y = mm(piece.label_at[None], off)[0]
        for k, text in enumerate(piece.label):
            out.append(
                f'<text class="label" x="{svg_number(x)}" y="{svg_number(y + (k + 1) * 1.5 * h - 0.5 * h)}" '
                f'font-family="Helvetica, Arial, sans-serif" font-size="{svg_number(h)}" '
                f'fill="{COLOURS["text"]}">{escape(text)}</text>'
            )
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"
