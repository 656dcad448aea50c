"""Graded nest: every size of a design in one file, the way pattern makers check grading.

Input: ``{size: Pattern}`` (the transfers of one design, e.g. XS..XL, made by
:mod:`core.workflows`; this module solves nothing). Each piece's sizes are
stacked on one another, aligned at the piece's reference point: the middle
of its grain line, with the grain lines on one line (every piece frame has
the grain along +y, :mod:`core.export.pieces`). The stacks are laid out on
one sheet.

Grade points: every size of a piece has the same notches and the same
corners (AAMA turn points), in the same order, as CAD grade rules work point
to point. They are the sample size's (the design's own size, else M, else
the middle one), which is drawn exactly as ``ease export`` draws it alone:
each seam's notches are those of the sample's seam, their distances from the
seam's ends scaled by the seam's length in each size
(:func:`core.export.notches.notch_positions` ``base``); each corner is the
same sew-line vertex (the sizes share one mesh), or for a corner of the cut
line the cut-line vertex nearest to where the sample's corner lies from its
nearest sew-line vertex.

Files:

======================= ======================================================
``graded_astm.dxf``      ASTM D6673 / AAMA (R2000, mm): one block per piece per
                         size, named ``<piece>_<size>``, with ``Size: <size>``
                         in each block; a piece's blocks are inserted at the
                         same place (the stack)
``graded.svg``           1:1 in mm, each size's cut line (solid) and sew line
                         (dashed) in its own colour, a legend
``graded.pdf``           the same on one sheet at 1:1
``graded.json``          sizes, pieces, per piece and size the sew-line length
======================= ======================================================
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Dict, List, Mapping, Optional
from xml.sax.saxutils import escape

import numpy as np

from ..errors import ExportError
from ..fileio import dumps_json, write_files
from ..geom.layout import Layout, layout_pieces
from ..geom.polyline import polyline_length
from ..pattern.types import Pattern
from ..progress import Progress, report, sub
from . import dxf as dxf_mod
from . import pdf as pdf_mod
from .dxf import piece_turn_points
from .layout import LAYOUT_MARGIN, SHEET_WIDTH
from .notches import seam_lengths
from .pieces import PieceDrawing, ascii_text, build_pieces
from .svg import STROKE_MM, svg_number, svg_path

# one colour per size, smallest to largest (colour-blind safe, Okabe–Ito)
SIZE_COLOURS = ("#0072b2", "#009e73", "#e69f00", "#d55e00", "#cc79a7", "#56b4e9", "#f0e442", "#000000")
LEGEND_H = 0.03  # m of sheet kept above the stacks for the legend


def _hex_rgb(colour: str):
    return tuple(int(colour[i : i + 2], 16) / 255.0 for i in (1, 3, 5))


def _shifted(piece: PieceDrawing, d: np.ndarray) -> PieceDrawing:
    """The drawing moved by ``d`` (m) in its own frame."""
    return dataclasses.replace(
        piece,
        sew=[l + d for l in piece.sew],
        cut=[l + d for l in piece.cut],
        fold=[f + d for f in piece.fold],
        notches=[dataclasses.replace(n, point=n.point + d, segment=n.segment + d) for n in piece.notches],
        grain=piece.grain + d,
        arrows=[a + d for a in piece.arrows],
        label_at=piece.label_at + d,
        bbox=piece.bbox + d,
        turn_points=None if piece.turn_points is None else piece.turn_points + d,
    )


def reference_point(piece: PieceDrawing) -> np.ndarray:
    """(2,) m: where a piece's sizes are aligned, the middle of its grain line."""
    return 0.5 * (piece.grain[0] + piece.grain[1])


def sample_size(sizes, own: Optional[str] = None) -> str:
    """The graded nest's sample size (AAMA ``Sample Size``, the size the grade points come from): ``own``
    (the design's own size) when among ``sizes``, else M, else the middle size."""
    sizes = [str(s) for s in sizes]
    if own is not None and str(own) in sizes:
        return str(own)
    return "M" if "M" in sizes else sizes[len(sizes) // 2]


def _nearest(points: np.ndarray, to: np.ndarray) -> np.ndarray:
    """Index into ``points`` (n, 2) of the nearest point to each of ``to`` (t, 2)."""
    return np.argmin(np.linalg.norm(to[:, None, :] - points[None, :, :], axis=2), axis=1)


def graded_turn_points(sample: PieceDrawing, piece: PieceDrawing) -> np.ndarray:
    """(t, 2) m: the sample size's corners (:func:`core.export.dxf.piece_turn_points`) on another size's
    drawing ``piece`` of the same piece, in the sample's order.

    A corner on the sample's sew line is the same sew-line vertex (the sizes share the mesh); a corner
    of the cut line is the cut-line vertex of ``piece`` nearest to the point that lies from its nearest
    sew-line vertex as the sample's corner lies from it.
    """
    own = piece_turn_points(sample)
    if piece is sample or not len(own):
        return own
    if [len(i) for i in sample.sew_ids] != [len(i) for i in piece.sew_ids] or any(
        not np.array_equal(a, b) for a, b in zip(sample.sew_ids, piece.sew_ids)
    ):
        raise ExportError(
            f"piece {piece.name}: its sew line's vertices differ between sizes; expected the sizes of one design"
        )
    sew_s, sew_p = np.concatenate(sample.sew), np.concatenate(piece.sew)
    cut_p = np.concatenate(piece.cut)
    j = _nearest(sew_s, own)
    out = sew_p[j] + (own - sew_s[j])
    on_cut = np.linalg.norm(own - sew_s[j], axis=1) > 1e-9
    if on_cut.any():
        out[on_cut] = cut_p[_nearest(cut_p, out[on_cut])]
    return out


def graded_stacks(
    patterns: Mapping[str, Pattern],
    allowance=None,
    notch_spacing: Optional[float] = None,
    progress: Optional[Progress] = None,
    sample: Optional[str] = None,
) -> Dict[str, Dict[str, PieceDrawing]]:
    """Piece name -> {size: drawing}, each size moved so its reference point is at the origin.

    Every size has the sample size's grade points (module docstring): the same notches and turn points
    per piece, in the same order.

    Parameters
    ----------
    patterns : {size: Pattern}, in size order; every size must have the same pieces.
    allowance, notch_spacing : see :func:`core.export.pieces.build_pieces`.
    sample : the sample size (:func:`sample_size`), None: M, else the middle size.
    """
    if len(patterns) < 1:
        raise ExportError("sizes: expected at least one size to grade")
    sample = sample_size(patterns, sample)
    grade_from = seam_lengths(patterns[sample])
    order = [sample] + [s for s in patterns if str(s) != sample]
    drawn: Dict[str, list] = {}
    names = None
    for k, size in enumerate(order):
        pieces = build_pieces(
            patterns[size],
            allowance,
            notch_spacing,
            grade_from=grade_from,
            progress=sub(progress, k / len(patterns), (k + 1) / len(patterns)),
        )
        got = [p.name for p in pieces]
        if names is None:
            names = got
        elif got != names:
            raise ExportError(
                f"size {size}: pieces {', '.join(got)} differ from size {sample}'s "
                f"({', '.join(names)}); expected the sizes of one design"
            )
        drawn[str(size)] = pieces
    stacks: Dict[str, Dict[str, PieceDrawing]] = {}
    for size in patterns:
        for own, p in zip(drawn[sample], drawn[str(size)]):
            p = dataclasses.replace(p, turn_points=graded_turn_points(own, p))
            stacks.setdefault(p.name, {})[str(size)] = _shifted(p, -reference_point(p))
    return stacks


def _layout(stacks: Dict[str, Dict[str, PieceDrawing]]) -> Layout:
    boxes = [
        np.stack([np.min([d.bbox[0] for d in s.values()], axis=0), np.max([d.bbox[1] for d in s.values()], axis=0)])
        for s in stacks.values()
    ]
    return layout_pieces(boxes, SHEET_WIDTH, LAYOUT_MARGIN)


def graded_dxf(stacks, layout: Layout, style: str, sample: Optional[str] = None) -> str:
    """ASTM D6673 DXF (R2000, mm) with one block per piece per size, the size named in each block;
    ``sample``: the ``Sample Size`` (:func:`sample_size`)."""
    sizes = list(next(iter(stacks.values())))
    flat, offsets, owner = [], [], []
    for (name, stack), off in zip(stacks.items(), layout.offsets):
        for size, d in stack.items():
            flat.append(dataclasses.replace(d, name=f"{name}_{size}"))
            offsets.append(off)
            owner.append((name, size))
    lay = Layout(offsets=np.array(offsets), size=layout.size, reserved=None)
    sample = sample_size(sizes, sample)
    stream = io.StringIO()
    with dxf_mod._fixed_metadata():
        doc = dxf_mod.astm_document(flat, lay, style, sample, "R2000")
        # the exporter writes one size per file: name each block's piece and size (ASTM D6673 piece text)
        for blk_name, (piece, size) in zip(dxf_mod.block_names(flat), owner):
            for e in doc.blocks.get(blk_name):
                if e.dxftype() != "TEXT":
                    continue
                if e.dxf.text.startswith("Piece Name: "):
                    e.dxf.text = f"Piece Name: {ascii_text(piece)}"
                elif e.dxf.text.startswith("Size: "):
                    e.dxf.text = f"Size: {ascii_text(size)}"
        doc.modelspace().add_text(
            ascii_text(f"Sizes: {', '.join(sizes)}"),
            dxfattribs={"layer": dxf_mod.ASTM_LAYERS["annotation"], "height": 5.0, "insert": (0.0, -8.0)},
        )
        doc.classes.classes = dict(sorted(doc.classes.classes.items(), key=lambda kv: str(kv[0])))
        doc.write(stream)
    return stream.getvalue()


def graded_svg(stacks, layout: Layout, title: str) -> str:
    """SVG at 1:1 (mm): the stacked sizes, one colour each, and a legend at the top."""
    sizes = list(next(iter(stacks.values())))
    W = float(layout.size[0]) * 1000.0
    H = (float(layout.size[1]) + LEGEND_H) * 1000.0

    def mm(points, off):
        q = (np.asarray(points, float) + off) * 1000.0
        return np.column_stack([q[:, 0], H - q[:, 1]])

    line = f'fill="none" stroke-width="{STROKE_MM}" stroke-linejoin="round" stroke-linecap="round"'
    out = [
        '<?xml version="1.0" encoding="UTF-8" standalone="no"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{svg_number(W)}mm" height="{svg_number(H)}mm" '
        f'viewBox="0 0 {svg_number(W)} {svg_number(H)}">',
        f"<title>{escape(title)}</title>",
        "<desc>EASE graded nest at 1:1; 1 user unit = 1 mm. Each piece's sizes stacked at the middle of the "
        "grain line; solid: cut line, dashed: sew line, one colour per size (legend).</desc>",
        '<g id="legend">',
    ]
    for k, size in enumerate(sizes):
        x, y = 10.0 + 30.0 * k, 12.0
        c = SIZE_COLOURS[k % len(SIZE_COLOURS)]
        out.append(
            f'<path d="M{svg_number(x)},{svg_number(y)} L{svg_number(x + 10)},{svg_number(y)}" stroke="{c}" fill="none" '
            f'stroke-width="1"/>'
        )
        out.append(
            f'<text x="{svg_number(x + 12)}" y="{svg_number(y + 2)}" font-family="Helvetica, Arial, sans-serif" '
            f'font-size="6" fill="{c}">{escape(size)}</text>'
        )
    out.append("</g>")
    for (name, stack), off in zip(stacks.items(), layout.offsets):
        out.append(f'<g id="piece-{escape(name)}" data-piece="{escape(name)}">')
        for k, (size, d) in enumerate(stack.items()):
            c = SIZE_COLOURS[k % len(SIZE_COLOURS)]
            out.append(f'<g class="size" data-size="{escape(size)}">')
            for loop in d.cut:
                out.append(f'<path class="cut" d="{svg_path(mm(loop, off), True)}" stroke="{c}" {line}/>')
            for loop in d.sew:
                out.append(
                    f'<path class="sew" d="{svg_path(mm(loop, off), True)}" stroke="{c}" '
                    f'stroke-dasharray="4,2" {line}/>'
                )
            out.append("</g>")
        first = next(iter(stack.values()))
        d = " ".join([svg_path(mm(first.grain, off), False)] + [svg_path(mm(a, off), False) for a in first.arrows])
        out.append(f'<path class="grain" d="{d}" stroke="#000000" {line}/>')
        x, y = mm(np.zeros((1, 2)), off)[0]
        out.append(
            f'<path class="reference" d="M{svg_number(x - 3)},{svg_number(y)} L{svg_number(x + 3)},{svg_number(y)} '
            f'M{svg_number(x)},{svg_number(y - 3)} L{svg_number(x)},{svg_number(y + 3)}" stroke="#000000" {line}/>'
        )
        out.append(
            f'<text x="{svg_number(x + 4)}" y="{svg_number(y - 4)}" font-family="Helvetica, Arial, sans-serif" '
            f'font-size="5" fill="#000000">{escape(ascii_text(name))}</text>'
        )
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def graded_pdf(stacks, layout: Layout, title: str) -> bytes:
    """One PDF sheet at 1:1: the stacked sizes in their colours and the legend."""
    canvas = pdf_mod._reportlab()
    sizes = list(next(iter(stacks.values())))
    m, k = pdf_mod.PAGE_MARGIN, pdf_mod.PT_PER_M
    W, H = float(layout.size[0]), float(layout.size[1]) + LEGEND_H
    buf = io.BytesIO()
    c = canvas.Canvas(buf, pagesize=((W + 2 * m) * k, (H + 2 * m) * k), invariant=1, pageCompression=1)
    c.setTitle(ascii_text(title))
    c.setCreator("EASE")
    c.setLineWidth(pdf_mod.LINE_PT)
    c.setFont("Helvetica", 9)
    for i, size in enumerate(sizes):
        x, y = (m + 0.01 + 0.03 * i) * k, (m + H - 0.012) * k
        c.setStrokeColorRGB(*_hex_rgb(SIZE_COLOURS[i % len(SIZE_COLOURS)]))
        c.setFillColorRGB(*_hex_rgb(SIZE_COLOURS[i % len(SIZE_COLOURS)]))
        c.line(x, y, x + 0.01 * k, y)
        c.drawString(x + 0.012 * k, y - 3, ascii_text(size))
    for (name, stack), off in zip(stacks.items(), layout.offsets):
        o = off + m
        for i, d in enumerate(stack.values()):
            c.setStrokeColorRGB(*_hex_rgb(SIZE_COLOURS[i % len(SIZE_COLOURS)]))
            for loop in d.cut:
                pdf_mod._poly(c, loop + o, True)
            c.setDash([4 * 72 / 25.4, 2 * 72 / 25.4])
            for loop in d.sew:
                pdf_mod._poly(c, loop + o, True)
            c.setDash()
        first = next(iter(stack.values()))
        c.setStrokeColorRGB(0, 0, 0)
        pdf_mod._poly(c, first.grain + o, False)
        for a in first.arrows:
            pdf_mod._poly(c, a + o, False)
        c.setFillColorRGB(0, 0, 0)
        c.drawString((o[0] + 0.004) * k, (o[1] + 0.004) * k, ascii_text(name))
    c.drawString(m * k, (H + 1.3 * m) * k, ascii_text(f"{title} - graded nest {', '.join(sizes)}, 1:1, do not scale"))
    c.showPage()
    c.save()
    return buf.getvalue()


def export_graded(
    patterns: Mapping[str, Pattern],
    out_dir,
    allowance=None,
    notch_spacing: Optional[float] = None,
    title: Optional[str] = None,
    progress: Optional[Progress] = None,
    sample: Optional[str] = None,
) -> List[Path]:
    """Write the graded nest of ``{size: Pattern}`` (DXF-AAMA, SVG, PDF, graded.json) into ``out_dir`` atomically.

    ``sample``: the size the grade points come from (:func:`sample_size`; the design's own size). Returns
    the written paths.
    """
    sample = sample_size(patterns, sample)
    stacks = graded_stacks(patterns, allowance, notch_spacing, progress=sub(progress, 0.0, 0.6), sample=sample)
    first = next(iter(patterns.values()))
    title = title or f"{first.style or 'pattern'} graded"
    layout = _layout(stacks)
    report(progress, 0.6, "rendering the graded nest")
    summary = {
        "title": title,
        "unit": "mm",
        "sizes": list(patterns),
        "sample_size": sample,
        "reference_point": "middle of the grain line",
        "pieces": {
            name: {
                size: {
                    "sew_line_mm": round(sum(polyline_length(l, closed=True) for l in d.sew) * 1000, 2),
                    "cut_line_mm": round(sum(polyline_length(l, closed=True) for l in d.cut) * 1000, 2),
                    "notches": len(d.notches),
                    "turn_points": len(d.turn_points),
                }
                for size, d in stack.items()
            }
            for name, stack in stacks.items()
        },
        "sheet_mm": (np.asarray(layout.size) * 1000).round(1).tolist(),
    }
    files = {
        "graded_astm.dxf": graded_dxf(stacks, layout, title, sample).encode("ascii", "replace"),
        "graded.svg": graded_svg(stacks, layout, title).encode("utf-8"),
        "graded.pdf": graded_pdf(stacks, layout, title),
        "graded.json": (dumps_json(summary) + "\n").encode("utf-8"),
    }
    paths = write_files(out_dir, files)
    report(progress, 1.0, f"wrote the graded nest to {out_dir}")
    return paths


__all__ = [
    "graded_stacks",
    "reference_point",
    "sample_size",
    "graded_turn_points",
    "graded_dxf",
    "graded_svg",
    "graded_pdf",
    "export_graded",
    "SIZE_COLOURS",
]
