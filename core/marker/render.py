"""Marker files: plotter DXF, SVG and a single-sheet PDF at 1:1 in millimetres, plus ``marker.json``.

The marker frame (:mod:`core.marker.nesting`): x along the fabric, y across
it, the fabric from y = 0 to the width. Every file shows the fabric edges
(selvages and the marker ends), each piece's cut line, notches, grain line
with arrows and a label (piece, size). A piece cut on a fold is drawn whole:
the half and its mirror image.

Only the files' lines and texts depend on the marker: the same marker gives
the same bytes (``marker.json`` also holds the wall time spent).
"""

from __future__ import annotations

import dataclasses
import io
import math
from pathlib import Path
from typing import List, Optional
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..export import dxf as dxf_mod
from ..export import pdf as pdf_mod
from ..export.pieces import CHAR_WIDTH, _place_label, ascii_text
from ..export.svg import COLOURS, STROKE_MM, svg_number, svg_path
from ..fileio import dumps_json, write_files
from ..progress import Progress, report
from .nesting import Marker, Placement, marker_report

FILES = ("marker.dxf", "marker.svg", "marker.pdf", "marker.png", "marker.json")
LABEL_MAX = 0.012  # m, the label's height where the piece has room
LABEL_MIN = 0.006  # m, never smaller: legible on the cutting table
DXF_LAYERS = {"CUT": 1, "NOTCH": 3, "GRAIN": 7, "FOLD": 6, "LABEL": 7, "FABRIC": 8}  # ACI colours
FABRIC_COLOUR = "#808080"


def _label(marker: Marker, p: Placement) -> List[str]:
    it = marker.items[p.item]
    if it.plies == 2:  # face to face: the second ply cuts the mirror image
        return [
            ascii_text(it.piece.name + (f" + {it.pair}" if it.pair else " x2")),
            ascii_text(f"size {it.size}, 2 plies face to face"),
        ]
    return [ascii_text(it.piece.name), ascii_text(f"size {it.size}")]


def _halves(marker: Marker, p: Placement):
    """(matrix (2, 2), translation (2,), draw label) for the piece and, when cut on a fold, its mirror half."""
    it = marker.items[p.item]
    out = [(p.rotation, p.translation, True)]
    if it.mirror is not None:
        p0, d = it.mirror
        refl = 2.0 * np.outer(d, d) - np.eye(2)  # mirror about the fold line through p0
        out.append((p.rotation @ refl, p.rotation @ (p0 - refl @ p0) + p.translation, False))
    return out


def _lines(marker: Marker, p: Placement):
    """(layer, (k, 2) m points in the marker frame, closed) of one placed copy."""
    it = marker.items[p.item]
    piece = it.piece
    place = lambda q: np.asarray(q, float) @ p.rotation.T + p.translation  # noqa: E731
    out = [("CUT", place(it.outline), True)]
    for M, t, _ in _halves(marker, p):
        move = lambda q: np.asarray(q, float) @ M.T + t  # noqa: E731
        out += [("NOTCH", move(n.segment), False) for n in piece.notches]
    out += [("GRAIN", place(piece.grain), False)] + [("GRAIN", place(a), False) for a in piece.arrows]
    out += [("FOLD", place(f), False) for f in piece.fold]
    return out


def _text_place(marker: Marker, p: Placement):
    """(baseline points (n, 2) m, angle degrees, height m) of a placed copy's label lines.

    The two lines (piece, size) are placed inside the piece's sew line at up to :data:`LABEL_MAX` high
    (:func:`core.export.pieces._place_label`), never under :data:`LABEL_MIN`, and read upright on the marker
    whichever way the piece lies (a piece turned 180 degrees gets its label turned back, at the same place).
    """
    piece = marker.items[p.item].piece
    lines = _label(marker, p)
    at, h = _place_label(piece.sew, piece.grain, lines, LABEL_MAX)
    h = max(float(h), LABEL_MIN)
    w, th = max(len(t) for t in lines) * CHAR_WIDTH * h, len(lines) * 1.5 * h
    block = np.array([[at[0], at[1]], [at[0] + w, at[1]], [at[0], at[1] - th], [at[0] + w, at[1] - th]])
    corners = block @ p.rotation.T + p.translation
    d = p.rotation @ np.array([1.0, 0.0])
    angle = round(math.degrees(math.atan2(d[1], d[0])), 9)
    if not -90.0 < angle <= 90.0:  # upside down on the marker: turn the text back
        angle = angle - 180.0 if angle > 90.0 else angle + 180.0
    up = np.array(
        [
            [math.cos(math.radians(angle)), -math.sin(math.radians(angle))],
            [math.sin(math.radians(angle)), math.cos(math.radians(angle))],
        ]
    )
    u = corners @ up  # the block in the upright text frame
    x0, top = float(u[:, 0].min()), float(u[:, 1].max())
    base = np.array([[x0, top - (k + 1) * 1.5 * h + 0.5 * h] for k in range(len(lines))])
    return base @ up.T, angle, h


def marker_svg(marker: Marker, title: str = "marker") -> str:
    """The SVG text of the marker, 1:1 in mm (fabric along x, selvages at the top and bottom)."""
    L, W = marker.length * 1000.0, marker.width * 1000.0

    def mm(points):
        q = np.asarray(points, float) * 1000.0
        return np.column_stack([q[:, 0], W - q[:, 1]])

    line = f'fill="none" stroke-width="{STROKE_MM}" stroke-linejoin="round" stroke-linecap="round"'
    colour = {"CUT": COLOURS["cut"], "NOTCH": COLOURS["notch"], "GRAIN": COLOURS["grain"], "FOLD": COLOURS["fold"]}
    rep = marker_report(marker, title)
    out = [
        '<?xml version="1.0" encoding="UTF-8" standalone="no"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{svg_number(L)}mm" height="{svg_number(W)}mm" '
        f'viewBox="0 0 {svg_number(L)} {svg_number(W)}">',
        f"<title>{escape(title)}</title>",
        f"<desc>EASE marker at 1:1; 1 user unit = 1 mm. Fabric {svg_number(W)} mm wide (grey: selvages and marker "
        f"ends), length {svg_number(L)} mm, efficiency {rep['efficiency_pct']:.2f} %. Grain along the length. Red: cut "
        f"line; green: notches; black: grain line and labels; magenta: fold line.</desc>",
        f'<rect class="fabric" x="0" y="0" width="{svg_number(L)}" height="{svg_number(W)}" stroke="{FABRIC_COLOUR}" {line}/>',
    ]
    for p in marker.placements:
        it = marker.items[p.item]
        out.append(
            f"<g id={quoteattr(f'piece-{it.size}-{it.piece.name}-{p.translation[0]:.4f}')} "
            f"data-piece={quoteattr(it.piece.name)} data-size={quoteattr(it.size)} "
            f'data-angle="{svg_number(p.angle)}">'
        )
        for layer, pts, closed in _lines(marker, p):
            out.append(
                f'<path class="{layer.lower()}" d="{svg_path(mm(pts), closed)}" stroke="{colour[layer]}" {line}/>'
            )
        base, angle, h = _text_place(marker, p)
        for (x, y), text in zip(mm(base), _label(marker, p)):
            out.append(
                f'<text class="label" transform="translate({svg_number(x)},{svg_number(y)}) rotate({svg_number(-angle)})" '
                f'font-family="Helvetica, Arial, sans-serif" font-size="{svg_number(h * 1000)}" '
                f'fill="{COLOURS["text"]}">{escape(text)}</text>'
            )
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def marker_dxf(marker: Marker, title: str = "marker") -> str:
    """A plotter DXF (R2010, mm, no blocks): fabric edges, cut lines, notches, grain lines, labels."""
    ezdxf = dxf_mod._ezdxf()
    with dxf_mod._fixed_metadata():  # ezdxf stamps the creation time when the document is made
        doc = ezdxf.new("R2010", units=dxf_mod.INSUNITS_MM)
    doc.header["$MEASUREMENT"] = 1
    L, W = marker.length * 1000.0, marker.width * 1000.0
    for name, colour in DXF_LAYERS.items():
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    msp.add_lwpolyline([(0.0, 0.0), (L, 0.0), (L, W), (0.0, W)], close=True, dxfattribs={"layer": "FABRIC"})
    msp.add_text(
        ascii_text(f"{title}: {W:.0f} mm fabric, {L:.0f} mm, grain along x"),
        dxfattribs={"layer": "FABRIC", "height": 8.0, "insert": (0.0, W + 6.0)},
    )
    for p in marker.placements:
        for layer, pts, closed in _lines(marker, p):
            msp.add_lwpolyline(
                [(float(x), float(y)) for x, y in pts * 1000.0], close=closed, dxfattribs={"layer": layer}
            )
        base, angle, h = _text_place(marker, p)
        for (x, y), text in zip(base * 1000.0, _label(marker, p)):
            msp.add_text(
                text,
                dxfattribs={"layer": "LABEL", "height": h * 1000.0, "rotation": angle, "insert": (float(x), float(y))},
            )
    # the extents of what is drawn (left unset, ezdxf writes the modelspace's +-1e20 over the header's)
    dxf_mod.set_extents(doc)
    stream = io.StringIO()
    with dxf_mod._fixed_metadata():
        # ezdxf lists the CLASSES section in registration order, which varies between runs
        doc.classes.classes = dict(sorted(doc.classes.classes.items(), key=lambda kv: str(kv[0])))
        doc.write(stream)
    return stream.getvalue()


def marker_pdf(marker: Marker, title: str = "marker") -> bytes:
    """One PDF page holding the marker at 1:1 (for a roll plotter), each piece drawn as the export draws it."""
    canvas = pdf_mod._reportlab()
    m, k = pdf_mod.PAGE_MARGIN, pdf_mod.PT_PER_M
    L, W = marker.length, marker.width
    buf = io.BytesIO()
    c = canvas.Canvas(buf, pagesize=((L + 2 * m) * k, (W + 3 * m) * k), invariant=1, pageCompression=1)
    c.setTitle(ascii_text(title))
    c.setCreator("EASE")
    used = sorted({p.item for p in marker.placements})
    # the pieces' lines as forms, their labels drawn upright apart (as in the SVG and DXF)
    forms = dict(
        zip(used, pdf_mod._define_forms(c, [dataclasses.replace(marker.items[i].piece, label=[]) for i in used]))
    )
    c.setLineWidth(pdf_mod.LINE_PT)
    c.setStrokeColorRGB(*pdf_mod.COLOURS["mark"])
    c.rect(m * k, m * k, L * k, W * k, stroke=1, fill=0)
    for p in marker.placements:
        for M, t, labelled in _halves(marker, p):
            c.saveState()
            c.transform(M[0, 0], M[1, 0], M[0, 1], M[1, 1], (t[0] + m) * k, (t[1] + m) * k)
            c.doForm(forms[p.item])
            c.restoreState()
        base, angle, h = _text_place(marker, p)
        c.setFillColorRGB(*pdf_mod.COLOURS["text"])
        c.setFont("Helvetica", h * k)
        for (x, y), text in zip(base, _label(marker, p)):
            c.saveState()
            c.translate((x + m) * k, (y + m) * k)
            c.rotate(angle)
            c.drawString(0, 0, text)
            c.restoreState()
    rep = marker_report(marker, title)
    c.setFont("Helvetica", 9)
    c.setFillColorRGB(0, 0, 0)
    c.drawString(
        m * k,
        (W + 1.6 * m) * k,
        ascii_text(
            f"{title} - marker {W * 1000:.0f} x {L * 1000:.0f} mm at 1:1, grain along the length, "
            f"efficiency {rep['efficiency_pct']:.2f} % - do not scale"
        ),
    )
    c.showPage()
    c.save()
    return buf.getvalue()


def marker_png(marker: Marker, title: str = "marker", dpi: int = 60) -> bytes:
    """A preview picture of the marker (PNG; the add-on shows it): fabric, cut lines, one colour per size."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon, Rectangle

    sizes = sorted({it.size for it in marker.items})
    L, W = marker.length, marker.width
    fig = Figure(figsize=(min(max(L / W * 4.0, 4.0), 24.0) + 0.5, 4.6), dpi=dpi)
    ax = fig.add_axes((0.02, 0.02, 0.96, 0.86))
    ax.add_patch(Rectangle((0, 0), L, W, fill=False, edgecolor=FABRIC_COLOUR, linewidth=1.0))
    cmap = matplotlib.colormaps["tab10"]
    for p in marker.placements:
        it = marker.items[p.item]
        c = cmap(sizes.index(it.size) % 10)
        ax.add_patch(
            Polygon(
                it.outline @ p.rotation.T + p.translation,
                closed=True,
                facecolor=(*c[:3], 0.35),
                edgecolor="#d00000",
                linewidth=0.6,
            )
        )
    ax.set_xlim(-0.01 * L, 1.01 * L)
    ax.set_ylim(-0.02 * W, 1.02 * W)
    ax.set_aspect("equal")
    ax.axis("off")
    rep = marker_report(marker, title)
    fig.suptitle(
        ascii_text(
            f"{title}: {W * 1000:.0f} mm x {L * 1000:.0f} mm, efficiency {rep['efficiency_pct']:.1f} %"
            f" ({', '.join(sizes)})"
        ),
        fontsize=9,
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    return buf.getvalue()


def write_marker(
    marker: Marker, out_dir, title: str = "marker", progress: Optional[Progress] = None, extra: Optional[dict] = None
) -> List[Path]:
    """Render the marker (DXF, SVG, PDF, PNG preview, ``marker.json``) in memory, then write the folder atomically.

    ``extra`` is merged into ``marker.json`` (the caller's inputs: pattern folders, sizes).
    Returns the written paths.
    """
    report(progress, 0.0, "rendering the marker")
    summary = marker_report(marker, title)
    summary.update(extra or {})
    summary["seconds"] = round(marker.seconds, 2)
    summary["history"] = [{"seconds": t, "efficiency_pct": round(e * 100, 3)} for t, e in marker.history]
    files = {
        "marker.dxf": marker_dxf(marker, title).encode("ascii", "replace"),
        "marker.svg": marker_svg(marker, title).encode("utf-8"),
        "marker.pdf": marker_pdf(marker, title),
        "marker.png": marker_png(marker, title),
        "marker.json": (dumps_json(summary) + "\n").encode("utf-8"),
    }
    paths = write_files(out_dir, files)
    report(progress, 1.0, f"wrote the marker to {out_dir}")
    return paths


__all__ = ["marker_svg", "marker_dxf", "marker_pdf", "marker_png", "write_marker", "FILES"]
