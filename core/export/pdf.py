"""PDF at 1:1: tiled on A4 or US Letter for home printers, or one sheet for plotters.

Every piece is drawn once as a form XObject in its own frame (1 PDF point =
1/72 inch, so lengths are exact) and placed on each page it touches by one
matrix: a rotation (a quarter turn, exact integers, and a tilt on tiled
pages where :data:`.tiling.TILTS` adds tilts) and a translation, never a scale.

Tiled pages: the pieces are nested for the page grid (:mod:`.tiling`: the
fewest pages that carry a cut or sew line; pages with no line are left out,
and each label is moved within its piece onto a printed page).
Each page prints a window of the sheet (the paper less a 10 mm margin);
neighbouring windows share a 10 mm strip, marked on both pages by a dashed
line where the neighbour begins and a join diamond (labelled with the
neighbour's page) at the same place on both: lay one page over the other up
to the dashed line, diamonds on diamonds, and tape. Each page has its frame,
its name (row letter, column number) and its number among the printed pages;
page 1 also has a 10 x 10 cm test square to check the printer's scale and the
page map (the page grid, the pieces, the pages left out crossed).

The plotter PDF is one page, as wide as a 914 mm roll (or the widest piece)
and as long as the layout.
"""

from __future__ import annotations

import io
import math
import string
from typing import List, Sequence, Tuple

import numpy as np

from ..errors import ExportError
from ..geom.layout import Layout
from .darts import DRILL_DIAMETER
from .pieces import PieceDrawing, ascii_text
from .tiling import PageGrid, PrintLayout, grid_for, inked_pages, place, print_layout

PT_PER_M = 72.0 / 0.0254
PAPERS = {"a4": (0.210, 0.297), "letter": (0.2159, 0.2794), "a0": (0.841, 1.189)}
PAGE_MARGIN = 0.010  # m of white border around the page window (what home printers leave unprinted)
OVERLAP = 0.010  # m of the sheet printed on both neighbouring pages: the strip that is taped over
TEST_SQUARE = 0.100  # m
MAP_SIZE = 0.100  # m, largest side of the assembly map under the test square
TEST_RESERVE = (0.110, 0.232)  # m, layout box kept free for the test square and the assembly map
COLOURS = {
    "cut": (1, 0, 0),
    "sew": (0, 0, 1),
    "notch": (0, 0.63, 0),
    "grain": (0, 0, 0),
    "fold": (1, 0, 1),
    "text": (0, 0, 0),
    "mark": (0.45, 0.45, 0.45),
}
LINE_PT = 0.25e-3 * PT_PER_M


def _reportlab():
    try:
        from reportlab.pdfgen import canvas
    except ImportError as exc:  # e.g. a Blender install without the bundled wheel
        raise ExportError(
            f"PDF export needs the reportlab package ({exc}); install it or leave pdf out of the formats"
        ) from None
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


def tile_size(paper: str) -> np.ndarray:
    """(2,) float, m: the printable window of one portrait page of ``paper`` (the page less its margins)."""
    if paper not in PAPERS:
        raise ExportError(f"paper {paper!r}: expected one of {', '.join(PAPERS)}")
    pw, ph = PAPERS[paper]
    return np.array([pw - 2 * PAGE_MARGIN, ph - 2 * PAGE_MARGIN])


def print_sheet(pieces: Sequence[PieceDrawing], paper: str) -> PrintLayout:
    """The pieces nested for tiled pages of ``paper`` (:func:`core.export.tiling.print_layout`), test square kept free."""
    return print_layout(pieces, tile_size(paper), OVERLAP, reserve=TEST_RESERVE)[0]


def sheet_pages(pieces: Sequence[PieceDrawing], layout: Layout, paper: str) -> Tuple[PageGrid, np.ndarray]:
    """The page grid of a tiled sheet and which pages are printed ((rows, cols) bool, :func:`inked_pages`)."""
    grid = grid_for(layout.size, tile_size(paper), OVERLAP)
    return grid, inked_pages(pieces, layout, grid)


def page_name(r: int, c: int) -> str:
    """A page's name: row letter(s) and column number, ``B3``."""
    return f"{row_name(r)}{c + 1}"


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


def upside_down(layout: Layout, n: int) -> List[bool]:
    """Per piece of ``layout``: whether its label, written along the piece frame's +x, would read upside down
    on the sheet (turned by more than 90 degrees); such a label is turned back within its own box."""
    out = []
    for i in range(n):
        d = _turn(layout, i) @ np.array([1.0, 0.0])
        angle = round(math.degrees(math.atan2(d[1], d[0])), 9)
        out.append(not -90.0 < angle <= 90.0)
    return out


def _define_forms(c, pieces: Sequence[PieceDrawing], labels=None, grains=None, flips=None) -> List[str]:
    """One form XObject per piece; ``labels`` (n, 2): piece-frame top-left of each label (None: ``label_at``),
    ``grains`` (n, 2): piece-frame shift of each grain line and its arrows (None: none), ``flips`` (n,) bool:
    labels turned by 180 degrees within their box, to read upright on a piece printed upside down."""
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
        for dart in piece.darts:
            c.setStrokeColorRGB(*COLOURS["sew"])
            for leg in dart.legs:
                _poly(c, leg, False)
            c.setStrokeColorRGB(*COLOURS["mark"])
            _poly(c, dart.fold, False)
            _poly(c, dart.fold_head, False)
            x, y = _pt(dart.drill[None])[0]
            c.circle(x, y, 0.5 * DRILL_DIAMETER * PT_PER_M, stroke=1, fill=0)
        for pleat in piece.pleats:
            c.setStrokeColorRGB(*COLOURS["mark"])
            for lines, dash in ((pleat.folds, [6, 2]), (pleat.placements, [2, 2])):
                c.setDash([x * 72 / 25.4 for x in dash])
                for x in lines:
                    _poly(c, x, False)
            c.setDash()
            for x, y in _pt(pleat.stitch_ends) if len(pleat.stitch_ends) else []:
                c.circle(x, y, 0.5 * DRILL_DIAMETER * PT_PER_M, stroke=1, fill=0)
        c.setStrokeColorRGB(*COLOURS["notch"])
        for n in piece.notches:
            _poly(c, n.segment, False)
        c.setStrokeColorRGB(*COLOURS["grain"])
        shift = np.zeros(2) if grains is None else np.asarray(grains[k], float)
        _poly(c, piece.grain + shift, False)
        for a in piece.arrows:
            _poly(c, a + shift, False)
        h = piece.text_height * PT_PER_M
        c.setFillColorRGB(*COLOURS["text"])
        c.setFont("Helvetica", h)
        x, y = _pt(np.asarray(piece.label_at if labels is None else labels[k], float)[None])[0]
        if flips is not None and flips[k] and piece.label:
            from .pieces import CHAR_WIDTH

            tw, th = max(len(t) for t in piece.label) * CHAR_WIDTH * h, len(piece.label) * 1.5 * h
            c.saveState()
            c.translate(x + 0.5 * tw, y - 0.5 * th)  # the box's centre: turned about it, the box stays
            c.rotate(180)
            x, y = -0.5 * tw, 0.5 * th
        for i, text in enumerate(piece.label):
            c.drawString(x, y - (i + 1) * 1.5 * h + 0.5 * h, ascii_text(text))
        if flips is not None and flips[k] and piece.label:
            c.restoreState()
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


def _assembly_map(c, top_left: np.ndarray, pieces, layout: Layout, grid: PageGrid, ink: np.ndarray) -> None:
    """A small map of the whole sheet: the page grid, the printed pages' names and the pieces' cut lines.

    ``top_left`` is the map's top-left corner in page metres; the map fits in
    ``MAP_SIZE`` x ``MAP_SIZE``. A page left out (nothing to cut on it) is
    drawn crossed, without a name.
    """
    H = grid.height
    step = grid.step
    grid_w = grid.cols * step[0] + grid.overlap
    grid_h = grid.rows * step[1] + grid.overlap
    scale = MAP_SIZE / max(grid_w, grid_h)
    x0, y0 = float(top_left[0]), float(top_left[1]) - grid_h * scale  # bottom-left of the map

    def to_page(pts):  # sheet metres (y up, top edge at H) -> page points
        q = np.asarray(pts, float)
        return [((x0 + x * scale) * PT_PER_M, (y0 + (y - (H - grid_h)) * scale) * PT_PER_M) for x, y in q]

    c.setFillColorRGB(0, 0, 0)
    c.setFont("Helvetica", 7)
    left_out = int(ink.size - ink.sum())
    c.drawString(
        x0 * PT_PER_M,
        (top_left[1] + 0.002) * PT_PER_M,
        "page map: rows A, B, ... columns 1, 2, ..."
        + (f"; {left_out} crossed pages are left out (no line on them)" if left_out else ""),
    )
    c.setLineWidth(0.3)
    c.setStrokeColorRGB(*COLOURS["cut"])
    for i, piece in enumerate(pieces):
        loop = place(layout, i, piece.cut[0])
        step_k = max(1, len(loop) // 200)  # a map needs no more detail than this
        pts = to_page(loop[::step_k])
        p = c.beginPath()
        p.moveTo(*pts[0])
        for q in pts[1:]:
            p.lineTo(*q)
        p.close()
        c.drawPath(p, stroke=1, fill=0)
    c.setStrokeColorRGB(*COLOURS["mark"])
    c.setFillColorRGB(*COLOURS["mark"])
    size = max(3.0, min(7.0, 0.35 * step[1] * scale * PT_PER_M))
    c.setFont("Helvetica", size)
    for r in range(grid.rows):
        for col in range(grid.cols):
            w = grid.window(r, col)
            # each page's own part of the sheet (the overlap strips go to its right and lower neighbours)
            (xa, ya), (xb, yb) = to_page([[w[0, 0], w[1, 1] - step[1]], [w[0, 0] + step[0], w[1, 1]]])
            c.rect(xa, ya, xb - xa, yb - ya, stroke=1, fill=0)
            if ink[r, col]:
                c.drawCentredString(0.5 * (xa + xb), 0.5 * (ya + yb) - size / 3, page_name(r, col))
            else:
                c.line(xa, ya, xb, yb)
                c.line(xa, yb, xb, ya)


def tiled_pdf(
    pieces: Sequence[PieceDrawing],
    layout: Layout = None,
    paper: str = "a4",
    title: str = "pattern",
    pages: Tuple[PageGrid, np.ndarray] = None,
) -> bytes:
    """1:1 pattern tiled on ``paper`` pages (``"a4"`` or ``"letter"``), rows top to bottom.

    Parameters
    ----------
    pieces : the drawings.
    layout : their placement on the sheet, None: :func:`print_sheet` (nested for
        the fewest pages). It should keep ``TEST_RESERVE`` free at its
        top-left; the test square and the page map are drawn there.
    paper, title : str.
    pages : (grid, printed) of :func:`sheet_pages` for this layout when the caller has them.

    Returns
    -------
    bytes, the PDF: one page per window of :func:`sheet_pages` that a cut or
    sew line crosses (and the top-left one), in row order. Neighbouring
    windows share ``OVERLAP`` of the sheet: each page marks, with a dashed
    line, where its neighbour's window begins and carries join diamonds in
    the middle of the shared strip, at the same place on both pages.
    """
    rl_canvas = _reportlab()
    if layout is None:
        layout = print_sheet(pieces, paper)
    pw, ph = PAPERS[paper]
    grid, ink = pages if pages is not None else sheet_pages(pieces, layout, paper)
    tile = np.asarray(grid.tile)
    buf = io.BytesIO()
    c = rl_canvas.Canvas(buf, pagesize=(pw * PT_PER_M, ph * PT_PER_M), invariant=1, pageCompression=1)
    c.setTitle(ascii_text(title))
    c.setCreator("EASE")
    forms = _define_forms(
        c, pieces, getattr(layout, "labels", None), getattr(layout, "grains", None), upside_down(layout, len(pieces))
    )
    boxes = [_placed_box(layout, i, p) for i, p in enumerate(pieces)]
    m = PAGE_MARGIN
    printed = [(r, col) for r in range(grid.rows) for col in range(grid.cols) if ink[r, col]]
    for k, (r, col) in enumerate(printed):
        (x0, y0), (x1, y1) = grid.window(r, col)
        c.saveState()
        p = c.beginPath()
        p.rect(m * PT_PER_M, m * PT_PER_M, tile[0] * PT_PER_M, tile[1] * PT_PER_M)
        c.clipPath(p, stroke=0, fill=0)
        for i, (name, box) in enumerate(zip(forms, boxes)):
            if box[1, 0] < x0 or box[0, 0] > x1 or box[1, 1] < y0 or box[0, 1] > y1:
                continue
            R = _turn(layout, i)
            off = layout.offsets[i]
            # one cm: the piece's rotation (exact integers for quarter turns) and its place; no scaling
            c.saveState()
            c.transform(R[0, 0], R[1, 0], R[0, 1], R[1, 1], (m - x0 + off[0]) * PT_PER_M, (m - y0 + off[1]) * PT_PER_M)
            c.doForm(name)
            c.restoreState()
        if (r, col) == (0, 0) and layout.reserved is not None:
            corner = np.array([layout.reserved[0, 0] - x0 + m, layout.reserved[1, 1] - y0 + m - TEST_SQUARE])
            _test_square(c, corner)
            _assembly_map(c, corner - np.array([0.0, 0.012]), pieces, layout, grid, ink)
        c.restoreState()
        _page_marks(c, r, col, grid, ink, (k + 1, len(printed)), title, paper)
        c.showPage()
    c.save()
    return buf.getvalue()


def _turn(layout: Layout, i: int) -> np.ndarray:
    return layout.matrix(i) if isinstance(layout, PrintLayout) else np.eye(2)


def _placed_box(layout: Layout, i: int, piece: PieceDrawing) -> np.ndarray:
    """(2, 2) min/max corner on the sheet of everything drawn for piece ``i``."""
    corners = np.array([[piece.bbox[a, 0], piece.bbox[b, 1]] for a in (0, 1) for b in (0, 1)])
    q = place(layout, i, corners)
    return np.stack([q.min(0), q.max(0)])


def _page_marks(c, r, col, grid: PageGrid, ink: np.ndarray, number, title, paper) -> None:
    m = PAGE_MARGIN * PT_PER_M
    tw, th = np.asarray(grid.tile) * PT_PER_M
    ov = grid.overlap * PT_PER_M
    c.setStrokeColorRGB(*COLOURS["mark"])
    c.setFillColorRGB(*COLOURS["mark"])
    c.setLineWidth(0.5)
    c.rect(m, m, tw, th, stroke=1, fill=0)
    name = page_name(r, col)
    c.setFont("Helvetica", 8)
    c.drawString(
        m,
        m + th + 0.35 * m,
        ascii_text(
            f"{title} - page {name} (row {row_name(r)}, column {col + 1}; {number[0]} of {number[1]}) - "
            f"{paper.upper()} at 1:1, do not scale; overlap the pages up to the dashed lines"
        ),
    )

    def printed(rr, cc):
        return 0 <= rr < grid.rows and 0 <= cc < grid.cols and bool(ink[rr, cc])

    # per printed neighbour: the dashed line where its window begins (or ends), and a join diamond in the
    # middle of the shared strip, which lies at the same sheet place on both pages
    s = 3.5 * 72 / 25.4
    # (neighbour, dashed line, diamond centre, direction into the page)
    sides = [
        ((r - 1, col), ((m, m + th - ov), (m + tw, m + th - ov)), (m + tw / 2, m + th - ov / 2), (0, -1)),
        ((r + 1, col), ((m, m + ov), (m + tw, m + ov)), (m + tw / 2, m + ov / 2), (0, 1)),
        ((r, col - 1), ((m + ov, m), (m + ov, m + th)), (m + ov / 2, m + th / 2), (1, 0)),
        ((r, col + 1), ((m + tw - ov, m), (m + tw - ov, m + th)), (m + tw - ov / 2, m + th / 2), (-1, 0)),
    ]
    c.setFont("Helvetica", 7)
    for (rr, cc), (a, b), (x, y), (dx, dy) in sides:
        if not printed(rr, cc):
            continue
        c.setDash([2, 2])
        c.line(a[0], a[1], b[0], b[1])
        c.setDash()
        p = c.beginPath()
        p.moveTo(x - s, y)
        p.lineTo(x, y + s)
        p.lineTo(x + s, y)
        p.lineTo(x, y - s)
        p.close()
        c.drawPath(p, stroke=1, fill=1)
        c.drawCentredString(x + dx * (ov + 4 * s), y + dy * (ov + 2 * s) - 2.5, f"join {page_name(rr, cc)}")
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
    c = rl_canvas.Canvas(buf, pagesize=((W + 2 * m) * PT_PER_M, (H + 2 * m) * PT_PER_M), invariant=1, pageCompression=1)
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
    c.drawString(
        m * PT_PER_M,
        (H + 1.3 * m) * PT_PER_M,
        ascii_text(f"{title} - {W * 1000:.0f} x {H * 1000:.0f} mm at 1:1, do not scale"),
    )
    c.showPage()
    c.save()
    return buf.getvalue()
