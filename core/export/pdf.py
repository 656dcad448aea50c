"""PDF at 1:1: tiled on A4 or US Letter for home printers, or one sheet for plotters.

Every piece is drawn once as a form XObject in its own frame (1 PDF point =
1/72 inch, so lengths are exact) and placed on each page it touches with a
pure translation. Tiled pages carry a frame (the trim line), join marks on
every edge shared with a neighbour (half diamonds that make a whole one when
the pages are butted, labelled with the neighbour's page), the page's row
letter and column number; page 1 also has a 10 x 10 cm test square to check
the printer's scale and an assembly map (the page grid with the pieces). The plotter PDF is one page, as wide as a 914 mm roll (or
the widest piece) and as long as the layout.
"""
from __future__ import annotations

import io
import math
import string
from typing import List, Sequence, Tuple

import numpy as np

from ..errors import ExportError
from ..geom.layout import Layout
from .pieces import PieceDrawing, ascii_text

PT_PER_M = 72.0 / 0.0254
PAPERS = {"a4": (0.210, 0.297), "letter": (0.2159, 0.2794), "a0": (0.841, 1.189)}
PAGE_MARGIN = 0.010           # m of white border around the tile frame
TEST_SQUARE = 0.100           # m
MAP_SIZE = 0.100              # m, largest side of the assembly map under the test square
TEST_RESERVE = (0.110, 0.232)  # m, layout box kept free for the test square and the assembly map
COLOURS = {"cut": (1, 0, 0), "sew": (0, 0, 1), "notch": (0, 0.63, 0), "grain": (0, 0, 0),
           "fold": (1, 0, 1), "text": (0, 0, 0), "mark": (0.45, 0.45, 0.45)}
LINE_PT = 0.25e-3 * PT_PER_M


def _reportlab():
    try:
        from reportlab.pdfgen import canvas
    except ImportError as exc:  # e.g. a Blender install without the bundled wheel
        raise ExportError(f"PDF export needs the reportlab package ({exc}); install it or leave pdf out of the "
                          f"formats") from None
    return canvas


def row_name(r: int) -> str:
    """Row label: A..Z, then AA, AB, ..."""
    letters = string.ascii_uppercase
    s = ""
    r += 1
    while r:
        r, k = divmod(r - 1, 26)
        s = letters[k] + s
    return s


def tile_grid(sheet: Sequence[float], paper: str) -> Tuple[int, int, np.ndarray]:
    """Rows, columns and tile size (m) covering a sheet with pages of ``paper`` (portrait)."""
    pw, ph = PAPERS[paper]
    tile = np.array([pw - 2 * PAGE_MARGIN, ph - 2 * PAGE_MARGIN])
    cols = max(1, int(math.ceil(sheet[0] / tile[0] - 1e-9)))
    rows = max(1, int(math.ceil(sheet[1] / tile[1] - 1e-9)))
    return rows, cols, tile


def _pt(points) -> List[Tuple[float, float]]:
    return [(float(x) * PT_PER_M, float(y) * PT_PER_M) for x, y in np.asarray(points, float)]


def _poly(c, points, closed: bool) -> None:
    p = c.beginPath()
    pts = _pt(points)
    p.moveTo(*pts[0])
    for q in pts[1:]:
        p.lineTo(*q)
    if closed:
        p.close()
    c.drawPath(p, stroke=1, fill=0)


def _define_forms(c, pieces: Sequence[PieceDrawing]) -> List[str]:
    names = []
    for k, piece in enumerate(pieces):
        name = f"piece{k}"
        lo, hi = piece.bbox * PT_PER_M
        c.beginForm(name, lowerx=lo[0] - 2, lowery=lo[1] - 2, upperx=hi[0] + 2, uppery=hi[1] + 2)
        c.setLineWidth(LINE_PT)
        c.setLineJoin(1)
        c.setStrokeColorRGB(*COLOURS["cut"])
        for loop in piece.cut:
            _poly(c, loop, True)
        c.setStrokeColorRGB(*COLOURS["sew"])
        c.setDash([4 * 72 / 25.4, 2 * 72 / 25.4])
        for loop in piece.sew:
            _poly(c, loop, True)
        c.setStrokeColorRGB(*COLOURS["fold"])
        for f in piece.fold:
            _poly(c, f, False)
        c.setDash()
        c.setStrokeColorRGB(*COLOURS["notch"])
        for n in piece.notches:
            _poly(c, n.segment, False)
        c.setStrokeColorRGB(*COLOURS["grain"])
        _poly(c, piece.grain, False)
        for a in piece.arrows:
            _poly(c, a, False)
        h = piece.text_height * PT_PER_M
        c.setFillColorRGB(*COLOURS["text"])
        c.setFont("Helvetica", h)
        x, y = _pt(piece.label_at[None])[0]
        for i, text in enumerate(piece.label):
            c.drawString(x, y - (i + 1) * 1.5 * h + 0.5 * h, ascii_text(text))
        c.endForm()
        names.append(name)
    return names


def _test_square(c, corner: np.ndarray) -> None:
    """10 x 10 cm square with its caption; ``corner`` = its bottom-left in page metres."""
    x, y = corner * PT_PER_M
    side = TEST_SQUARE * PT_PER_M
    c.setStrokeColorRGB(0, 0, 0)
    c.setLineWidth(LINE_PT)
    c.rect(x, y, side, side, stroke=1, fill=0)
    c.setFont("Helvetica", 9)
    c.setFillColorRGB(0, 0, 0)
    c.drawCentredString(x + side / 2, y + side / 2 + 4, "10 cm x 10 cm")
    c.drawCentredString(x + side / 2, y + side / 2 - 8, "print at 100% / actual size")


def _assembly_map(c, top_left: np.ndarray, pieces, layout: Layout, rows: int, cols: int, tile: np.ndarray) -> None:
    """A small map of the whole sheet: the page grid with its labels and the pieces' cut lines.

    ``top_left`` is the map's top-left corner in page metres; the map fits in
    ``MAP_SIZE`` x ``MAP_SIZE``.
    """
    H = float(layout.size[1])
    grid_w, grid_h = cols * tile[0], rows * tile[1]
    scale = MAP_SIZE / max(grid_w, grid_h)
    x0, y0 = float(top_left[0]), float(top_left[1]) - grid_h * scale   # bottom-left of the map

    def to_page(pts):  # sheet metres (y up, top edge at H) -> page points
        q = np.asarray(pts, float)
        return [((x0 + x * scale) * PT_PER_M, (y0 + (y - (H - grid_h)) * scale) * PT_PER_M) for x, y in q]

    c.setFillColorRGB(0, 0, 0)
    c.setFont("Helvetica", 7)
    c.drawString(x0 * PT_PER_M, (top_left[1] + 0.002) * PT_PER_M, "assembly map: pages by row and column")
    c.setLineWidth(0.3)
    c.setStrokeColorRGB(*COLOURS["cut"])
    for piece, off in zip(pieces, layout.offsets):
        loop = piece.cut[0] + off
        step = max(1, len(loop) // 200)  # a map needs no more detail than this
        pts = to_page(loop[::step])
        p = c.beginPath()
        p.moveTo(*pts[0])
        for q in pts[1:]:
            p.lineTo(*q)
        p.close()
        c.drawPath(p, stroke=1, fill=0)
    c.setStrokeColorRGB(*COLOURS["mark"])
    c.setFillColorRGB(*COLOURS["mark"])
    size = max(3.0, min(7.0, 0.35 * tile[1] * scale * PT_PER_M))
    c.setFont("Helvetica", size)
    top = H  # the grid hangs from the sheet's top edge
    for k in range(cols + 1):
        (xa, ya), (xb, yb) = to_page([[k * tile[0], top], [k * tile[0], top - grid_h]])
        c.line(xa, ya, xb, yb)
    for k in range(rows + 1):
        (xa, ya), (xb, yb) = to_page([[0, top - k * tile[1]], [grid_w, top - k * tile[1]]])
        c.line(xa, ya, xb, yb)
    for r in range(rows):
        for col in range(cols):
            (x, y), = to_page([[(col + 0.5) * tile[0], top - (r + 0.5) * tile[1]]])
            c.drawCentredString(x, y - size / 3, f"{row_name(r)}{col + 1}")


def _piece_boxes(pieces, layout) -> np.ndarray:
    return np.array([p.bbox + off for p, off in zip(pieces, layout.offsets)]).reshape(-1, 2, 2)


def tiled_pdf(pieces: Sequence[PieceDrawing], layout: Layout, paper: str = "a4", title: str = "pattern") -> bytes:
    """1:1 pattern tiled on ``paper`` pages (``"a4"`` or ``"letter"``), rows top to bottom.

    ``layout`` should keep ``TEST_RESERVE`` free at its top-left (see
    :func:`core.geom.layout.layout_pieces`); the test square is drawn there.

    Returns
    -------
    bytes, the PDF; ``rows * cols`` pages (see :func:`tile_grid`).
    """
    rl_canvas = _reportlab()

    pw, ph = PAPERS[paper]
    rows, cols, tile = tile_grid(layout.size, paper)
    buf = io.BytesIO()
    c = rl_canvas.Canvas(buf, pagesize=(pw * PT_PER_M, ph * PT_PER_M), invariant=1, pageCompression=1)
    c.setTitle(ascii_text(title))
    c.setCreator("EASE")
    forms = _define_forms(c, pieces)
    boxes = _piece_boxes(pieces, layout)
    H = float(layout.size[1])
    m = PAGE_MARGIN
    for r in range(rows):
        for col in range(cols):
            x0, y0 = col * tile[0], H - (r + 1) * tile[1]   # sheet window, bottom-left
            x1, y1 = x0 + tile[0], y0 + tile[1]
            c.saveState()
            p = c.beginPath()
            p.rect(m * PT_PER_M, m * PT_PER_M, tile[0] * PT_PER_M, tile[1] * PT_PER_M)
            c.clipPath(p, stroke=0, fill=0)
            for name, box, off in zip(forms, boxes, layout.offsets):
                if box[1, 0] < x0 or box[0, 0] > x1 or box[1, 1] < y0 or box[0, 1] > y1:
                    continue
                c.saveState()
                c.translate((m - x0 + off[0]) * PT_PER_M, (m - y0 + off[1]) * PT_PER_M)
                c.doForm(name)
                c.restoreState()
            if r == 0 and col == 0 and layout.reserved is not None:
                corner = np.array([layout.reserved[0, 0] - x0 + m, layout.reserved[1, 1] - y0 + m - TEST_SQUARE])
                _test_square(c, corner)
                _assembly_map(c, corner - np.array([0.0, 0.012]), pieces, layout, rows, cols, tile)
            c.restoreState()
            _page_marks(c, r, col, rows, cols, tile, title, paper)
            c.showPage()
    c.save()
    return buf.getvalue()


def _page_marks(c, r, col, rows, cols, tile, title, paper) -> None:
    m = PAGE_MARGIN * PT_PER_M
    tw, th = tile * PT_PER_M
    c.setStrokeColorRGB(*COLOURS["mark"])
    c.setFillColorRGB(*COLOURS["mark"])
    c.setLineWidth(0.5)
    c.rect(m, m, tw, th, stroke=1, fill=0)
    name = f"{row_name(r)}{col + 1}"
    c.setFont("Helvetica", 8)
    c.drawString(m, m + th + 0.35 * m, ascii_text(
        f"{title} - page {name} (row {row_name(r)}, column {col + 1}; {r * cols + col + 1} of {rows * cols}) - "
        f"{paper.upper()} at 1:1, do not scale"))
    # join marks: a half diamond on each shared edge, pointing into the page
    s = 6.0 * 72 / 25.4
    marks = []
    if r > 0:
        marks.append(((m + tw / 2, m + th), (0, -1), f"{row_name(r - 1)}{col + 1}"))
    if r < rows - 1:
        marks.append(((m + tw / 2, m), (0, 1), f"{row_name(r + 1)}{col + 1}"))
    if col > 0:
        marks.append(((m, m + th / 2), (1, 0), f"{row_name(r)}{col}"))
    if col < cols - 1:
        marks.append(((m + tw, m + th / 2), (-1, 0), f"{row_name(r)}{col + 2}"))
    c.setFont("Helvetica", 7)
    for (x, y), (dx, dy), other in marks:
        p = c.beginPath()
        p.moveTo(x - dy * s, y + dx * s)
        p.lineTo(x + dx * s, y + dy * s)
        p.lineTo(x + dy * s, y - dx * s)
        p.close()
        c.drawPath(p, stroke=1, fill=1)
        c.drawCentredString(x + dx * 2.2 * s, y + dy * 2.2 * s - 2.5, f"join {other}")
    # corner crosses on the frame corners for alignment
    for x in (m, m + tw):
        for y in (m, m + th):
            c.line(x - 3 * 72 / 25.4, y, x + 3 * 72 / 25.4, y)
            c.line(x, y - 3 * 72 / 25.4, x, y + 3 * 72 / 25.4)
    c.setFont("Helvetica-Bold", 10)
    c.drawRightString(m + tw, m + th + 0.35 * m, name)


def plotter_pdf(pieces: Sequence[PieceDrawing], layout: Layout, title: str = "pattern") -> bytes:
    """One page holding the whole layout at 1:1 (for A0 or roll plotters), test square included."""
    rl_canvas = _reportlab()

    m = PAGE_MARGIN
    W, H = float(layout.size[0]), float(layout.size[1])
    buf = io.BytesIO()
    c = rl_canvas.Canvas(buf, pagesize=((W + 2 * m) * PT_PER_M, (H + 2 * m) * PT_PER_M),
                         invariant=1, pageCompression=1)
    c.setTitle(ascii_text(title))
    c.setCreator("EASE")
    forms = _define_forms(c, pieces)
    for name, off in zip(forms, layout.offsets):
        c.saveState()
        c.translate((off[0] + m) * PT_PER_M, (off[1] + m) * PT_PER_M)
        c.doForm(name)
        c.restoreState()
    if layout.reserved is not None:
        _test_square(c, np.array([layout.reserved[0, 0] + m, layout.reserved[1, 1] + m - TEST_SQUARE]))
    c.setFont("Helvetica", 9)
    c.setFillColorRGB(0, 0, 0)
    c.drawString(m * PT_PER_M, (H + 1.3 * m) * PT_PER_M,
                 ascii_text(f"{title} - {W * 1000:.0f} x {H * 1000:.0f} mm at 1:1, do not scale"))
    c.showPage()
    c.save()
    return buf.getvalue()
