"""DXF: ASTM D6673 / AAMA pattern exchange files and a plain DXF for general CAD.

ASTM D6673 (the AAMA DXF) stores one BLOCK per piece and gives each layer a
meaning; this module writes

====== ==========================================================
layer  content
====== ==========================================================
1      piece boundary = the cut line; piece and style system text
2      turn points (POINT at the corners of the cut and sew lines)
4      notches (slit notches, LINE from the boundary inward)
6      mirror line (a fold edge)
7      grain line (LINE, pointing along the warp)
8      internal lines: a dart's legs and its fold arrow; a pleat's fold and placement lines
13     drill holes (POINT: a dart's drill hole, where a tuck's stitching ends)
14     sew line
15     annotation (text: cut on fold, mirror, allowance, units; the grain line's arrow heads)
====== ==========================================================

(layers 8 and 13 only in a pattern with darts or pleats, so files without them stay as they were)

in millimetres; the grain line is one LINE, alone on layer 7; its arrow heads
are two open polylines on the annotation layer 15. :func:`astm_document` is DXF R2000 with
``$INSUNITS = 4`` (mm); the same content as DXF R12 (:func:`astm_r12_text`)
suits Gerber and other strict R12 readers, which take the units from the style
system text ``Units: METRIC`` and, where they read it, ``$MEASUREMENT`` = 1.
:func:`plain_document` has named layers (CUT, SEW, NOTCH, GRAIN, FOLD, LABEL; DART with darts)
and no blocks. Every variant sets its extents and limits (``$EXTMIN``,
``$EXTMAX``, ``$LIMMIN``, ``$LIMMAX``) from the drawing.
ezdxf is imported here only, so the rest of the core loads without it.
"""

from __future__ import annotations

import contextlib
import io
import logging
import re
from typing import List, Sequence

import numpy as np

from ..errors import ExportError
from ..geom.layout import Layout
from ..geom.polygon import turn_points
from .darts import DRILL_DIAMETER
from .pieces import PieceDrawing, ascii_text

ASTM_LAYERS = {"boundary": "1", "turn": "2", "notch": "4", "mirror": "6", "grain": "7", "sew": "14", "annotation": "15"}
TURN_DEG = 20.0  # a polyline vertex turning more than this is a corner (turn point), else a curve point
PLAIN_LAYERS = {"CUT": 1, "SEW": 5, "NOTCH": 3, "GRAIN": 7, "FOLD": 6, "LABEL": 7}  # ACI colours
INSUNITS_MM = 4
DART_LAYERS = {"internal": "8", "drill": "13"}


def _layers(pieces) -> dict:
    """The ASTM layers a drawing uses: the dart layers only where a piece has a dart."""
    return {**ASTM_LAYERS, **DART_LAYERS} if any(p.darts or p.pleats for p in pieces) else dict(ASTM_LAYERS)


def _ezdxf():
    try:
        import ezdxf
    except ImportError as exc:  # e.g. a Blender install without the bundled wheel
        raise ExportError(
            f"DXF export needs the ezdxf package ({exc}); install it or leave dxf out of the formats"
        ) from None
    return ezdxf


def _mm(points, offset=None) -> List[tuple]:
    q = np.asarray(points, float)
    if offset is not None:
        q = q + offset
    return [(float(x) * 1000.0, float(y) * 1000.0) for x, y in q]


#: longest block name per DXF version (R12: 31 characters; later versions: 255)
BLOCK_NAME_MAX = {"R12": 31, "R2000": 255, "R2010": 255}


def _fit_name(name: str, limit: int) -> str:
    """``name`` cut to ``limit`` characters, a short hash of the whole name at the end where it was cut."""
    if len(name) <= limit:
        return name
    import hashlib

    tag = hashlib.sha1(name.encode("utf-8")).hexdigest()[:6]
    return f"{name[: limit - len(tag) - 1]}_{tag}"


def block_names(pieces: Sequence[PieceDrawing], dxfversion: str = "R2000") -> List[str]:
    """ASCII block names, one per piece, unique (DXF R12 allows letters, digits, ``_-$``), at most
    :data:`BLOCK_NAME_MAX` characters for ``dxfversion`` (a longer name is cut, with a hash of the whole)."""
    limit = BLOCK_NAME_MAX.get(dxfversion, 31)
    names, seen = [], set()
    for p in pieces:
        base = re.sub(r"[^A-Za-z0-9_\-$]", "_", ascii_text(p.name)) or "PIECE"
        name, k = _fit_name(base, limit), 2
        while name.upper() in seen:
            suffix = f"_{k}"
            name, k = _fit_name(base, limit - len(suffix)) + suffix, k + 1
        seen.add(name.upper())
        names.append(name)
    return names


def astm_document(pieces: Sequence[PieceDrawing], layout: Layout, style: str, size: str, dxfversion: str = "R2000"):
    """An ezdxf document with ASTM D6673 content: one block per piece, inserted at its layout place.

    Parameters
    ----------
    pieces, layout : the drawings and their placement (metres; written in mm).
    style, size : the style system text.
    dxfversion : ``"R2000"`` (carries ``$INSUNITS``) or ``"R12"``.
    """
    ezdxf = _ezdxf()
    if dxfversion == "R12":
        # R12 has no $INSUNITS (its readers take the units from "Units: METRIC");
        # ezdxf.new sets units anyway and warns, which would only confuse users
        log = logging.getLogger("ezdxf")
        level = log.level
        log.setLevel(logging.ERROR)
        try:
            doc = ezdxf.new(dxfversion, units=0)
        finally:
            log.setLevel(level)
    else:
        doc = ezdxf.new(dxfversion, units=INSUNITS_MM)
    if dxfversion != "R12":
        doc.header["$MEASUREMENT"] = 1

    # R12 knows only POLYLINE; in R2000 the compact LWPOLYLINE is ~10x faster
    # to write and read for the same vertices
    def add_poly(layout, points, close, dxfattribs):
        if dxfversion == "R12":
            return layout.add_polyline2d(points, close=close, dxfattribs=dxfattribs)
        return layout.add_lwpolyline(points, close=close, dxfattribs=dxfattribs)

    L = _layers(pieces)
    for name in L.values():
        if name not in doc.layers:
            doc.layers.add(name)
    msp = doc.modelspace()
    h_style = 5.0
    style_text = [
        f"Style Name: {ascii_text(style)}",
        f"Sample Size: {ascii_text(size)}",
        "Grading Rule Table: none",
        "Units: METRIC",
        "Author: EASE",
    ]
    top = float(layout.size[1]) * 1000.0
    for k, text in enumerate(style_text):
        msp.add_text(
            text,
            dxfattribs={
                "layer": L["boundary"],
                "height": h_style,
                "insert": (0.0, top + (len(style_text) - k) * 1.5 * h_style),
            },
        )
    for piece, name, off in zip(pieces, block_names(pieces, dxfversion), layout.offsets):
        blk = doc.blocks.new(name=name)
        for loop in piece.cut:
            add_poly(blk, _mm(loop), close=True, dxfattribs={"layer": L["boundary"]})
        for loop in piece.sew:
            add_poly(blk, _mm(loop), close=True, dxfattribs={"layer": L["sew"]})
        # turn points tell pattern CAD which vertices are corners (the rest are curve points)
        for q in _mm(piece_turn_points(piece)):
            blk.add_point(q, dxfattribs={"layer": L["turn"]})
        for n in piece.notches:
            a, b = _mm(n.segment)
            blk.add_line(a, b, dxfattribs={"layer": L["notch"]})
        for f in piece.fold:
            add_poly(blk, _mm(f), close=False, dxfattribs={"layer": L["mirror"]})
        for dart in piece.darts:
            for line in dart.legs + [dart.fold, dart.fold_head]:
                add_poly(blk, _mm(line), close=False, dxfattribs={"layer": L["internal"]})
            blk.add_point(_mm(dart.drill[None])[0], dxfattribs={"layer": L["drill"]})
        for pleat in piece.pleats:  # fold and placement lines are internal lines, a tuck's stitch end a drill hole
            for line in pleat.lines():
                add_poly(blk, _mm(line), close=False, dxfattribs={"layer": L["internal"]})
            for q in pleat.stitch_ends:
                blk.add_point(_mm(q[None])[0], dxfattribs={"layer": L["drill"]})
        g0, g1 = _mm(piece.grain)
        blk.add_line(g0, g1, dxfattribs={"layer": L["grain"]})
        # the arrow heads as open polylines (barb, tip, barb) on the annotation layer: the grain layer holds
        # the grain line alone, as the standard expects (one grain line per piece)
        for a in piece.arrows:
            add_poly(blk, _mm(a), close=False, dxfattribs={"layer": L["annotation"]})
        h = piece.text_height * 1000.0
        x, y = _mm(piece.label_at[None])[0]
        system = [
            f"Piece Name: {ascii_text(piece.name)}",
            f"Size: {ascii_text(size)}",
            f"Quantity: {piece.quantity}",
            f"Category: {ascii_text(piece.garment)}",
        ]
        notes = [t for t in piece.label[3:]]
        for k, text in enumerate(system + notes):
            layer = L["boundary"] if k < len(system) else L["annotation"]
            blk.add_text(text, dxfattribs={"layer": layer, "height": h, "insert": (x, y - (k + 1) * 1.5 * h)})
        msp.add_blockref(name, (float(off[0]) * 1000.0, float(off[1]) * 1000.0), dxfattribs={"layer": L["boundary"]})
    set_extents(doc)
    return doc


def piece_turn_points(piece) -> np.ndarray:
    """(t, 2) m: the corners a piece's AAMA block marks (layer 2): its own ``turn_points`` where set (a graded
    nest's, shared by every size), else the cut lines' and then the sew lines' vertices turning by more than
    :data:`TURN_DEG`, loop by loop."""
    if piece.turn_points is not None:
        return np.asarray(piece.turn_points, float).reshape(-1, 2)
    found = [loop[turn_points(loop, TURN_DEG)] for loop in piece.cut + piece.sew]
    return np.concatenate(found) if found else np.zeros((0, 2))


def set_extents(doc) -> tuple:
    """Set ``$EXTMIN``/``$EXTMAX`` and ``$LIMMIN``/``$LIMMAX`` from what the modelspace draws (mm).

    Left unset they read +-1e20, and readers that scale "automatically" to
    the extents (Inkscape) put every coordinate near 1e20.

    Returns
    -------
    (lo, hi), two (x, y) tuples in mm.
    """
    from ezdxf import bbox

    ext = bbox.extents(doc.modelspace(), fast=True)
    lo, hi = (0.0, 0.0), (1.0, 1.0)
    if ext.has_data:
        lo = (round(float(ext.extmin.x), 6), round(float(ext.extmin.y), 6))
        hi = (round(float(ext.extmax.x), 6), round(float(ext.extmax.y), 6))
    # ezdxf copies the modelspace layout's extents and limits into the header when it writes
    msp = doc.modelspace()
    msp.reset_extents((lo[0], lo[1], 0.0), (hi[0], hi[1], 0.0))
    msp.reset_limits(lo, hi)
    doc.header["$EXTMIN"] = (lo[0], lo[1], 0.0)
    doc.header["$EXTMAX"] = (hi[0], hi[1], 0.0)
    doc.header["$LIMMIN"] = lo
    doc.header["$LIMMAX"] = hi
    return lo, hi


@contextlib.contextmanager
def _fixed_metadata():
    # ezdxf stamps creation time and random GUIDs into every file; its fixed
    # metadata mode keeps the output a function of the pattern alone
    ezdxf = _ezdxf()

    before = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = before


def astm_text(pieces, layout, style, size) -> str:
    """ASTM D6673 DXF (R2000, ``$INSUNITS`` = mm) as text."""
    stream = io.StringIO()
    with _fixed_metadata():
        astm_document(pieces, layout, style, size, "R2000").write(stream)
    return stream.getvalue()


def astm_r12_text(pieces, layout, style, size) -> str:
    """ASTM D6673 DXF R12 in the strict form Gerber readers accept.

    The sections Gerber's parser takes (ezdxf's ``gerber_D6673`` add-on: no
    handles, only the pieces' BLOCK definitions, no ``$MODEL_SPACE`` or
    ``$PAPER_SPACE`` blocks), plus what other readers need to open it at the
    right size: a HEADER with ``$ACADVER`` AC1009, ``$MEASUREMENT`` = 1
    (metric: R12 has no ``$INSUNITS``; Inkscape's "read units from file" and
    LibreCAD read ``$MEASUREMENT``, R12 readers skip header variables they do not
    know), ``$LUNITS`` = 2 (decimal), the extents and limits; and a TABLES section
    with the LTYPE ``CONTINUOUS`` and one LAYER entry per ASTM layer.
    """
    ezdxf = _ezdxf()
    from ezdxf.lldxf.tagwriter import TagWriter

    doc = astm_document(pieces, layout, style, size, "R12")
    lo, hi = doc.header["$EXTMIN"], doc.header["$EXTMAX"]
    stream = io.StringIO()
    with _fixed_metadata():
        w = TagWriter(stream, write_handles=False, dxfversion=ezdxf.const.DXF12)
        w.write_str("  0\nSECTION\n  2\nHEADER\n")
        w.write_tag2(9, "$ACADVER")
        w.write_tag2(1, "AC1009")
        w.write_tag2(9, "$MEASUREMENT")
        w.write_tag2(70, 1)
        w.write_tag2(9, "$LUNITS")
        w.write_tag2(70, 2)
        for name, (x, y) in (("$EXTMIN", lo[:2]), ("$EXTMAX", hi[:2]), ("$LIMMIN", lo[:2]), ("$LIMMAX", hi[:2])):
            w.write_tag2(9, name)
            w.write_tag2(10, float(x))
            w.write_tag2(20, float(y))
            if name.startswith("$EXT"):
                w.write_tag2(30, 0.0)
        w.write_tag2(0, "ENDSEC")
        w.write_str("  0\nSECTION\n  2\nTABLES\n")
        w.write_str("  0\nTABLE\n  2\nLTYPE\n 70\n1\n")
        w.write_str("  0\nLTYPE\n  2\nCONTINUOUS\n 70\n0\n  3\nSolid line\n 72\n65\n 73\n0\n 40\n0.0\n")
        w.write_tag2(0, "ENDTAB")
        layers = ["0"] + sorted(_layers(pieces).values(), key=int)
        w.write_str(f"  0\nTABLE\n  2\nLAYER\n 70\n{len(layers)}\n")
        for name in layers:
            w.write_str(f"  0\nLAYER\n  2\n{name}\n 70\n0\n 62\n7\n  6\nCONTINUOUS\n")
        w.write_tag2(0, "ENDTAB")
        w.write_tag2(0, "ENDSEC")
        # the pieces' blocks only (Gerber refuses the layout blocks), then the entities
        w.write_str("  0\nSECTION\n  2\nBLOCKS\n")
        for record in doc.block_records:
            if record.is_block_layout:
                record.export_block_definition(w)
        w.write_tag2(0, "ENDSEC")
        w.write_str("  0\nSECTION\n  2\nENTITIES\n")
        doc.modelspace().entity_space.export_dxf(w)
        w.write_tag2(0, "ENDSEC")
        w.write_tag2(0, "EOF")
    return stream.getvalue()


def plain_document(pieces: Sequence[PieceDrawing], layout: Layout, style: str):
    """A plain DXF (R2010, mm): the laid-out pieces as polylines on named layers."""
    ezdxf = _ezdxf()
    doc = ezdxf.new("R2010", units=INSUNITS_MM)
    doc.header["$MEASUREMENT"] = 1
    plain = {**PLAIN_LAYERS, "DART": 4} if any(p.darts for p in pieces) else dict(PLAIN_LAYERS)
    if any(p.pleats for p in pieces):
        plain["PLEAT"] = 4
    for name, colour in plain.items():
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    for piece, off in zip(pieces, layout.offsets):
        for loop in piece.cut:
            msp.add_lwpolyline(_mm(loop, off), close=True, dxfattribs={"layer": "CUT"})
        for loop in piece.sew:
            msp.add_lwpolyline(_mm(loop, off), close=True, dxfattribs={"layer": "SEW"})
        for n in piece.notches:
            a, b = _mm(n.segment, off)
            msp.add_line(a, b, dxfattribs={"layer": "NOTCH"})
        for f in piece.fold:
            msp.add_lwpolyline(_mm(f, off), dxfattribs={"layer": "FOLD"})
        for dart in piece.darts:
            for line in dart.legs + [dart.fold, dart.fold_head]:
                msp.add_lwpolyline(_mm(line, off), dxfattribs={"layer": "DART"})
            msp.add_circle(_mm(dart.drill[None], off)[0], 0.5 * DRILL_DIAMETER * 1000.0, dxfattribs={"layer": "DART"})
        for pleat in piece.pleats:
            for line in pleat.lines():
                msp.add_lwpolyline(_mm(line, off), dxfattribs={"layer": "PLEAT"})
            for q in pleat.stitch_ends:
                msp.add_circle(_mm(q[None], off)[0], 0.5 * DRILL_DIAMETER * 1000.0, dxfattribs={"layer": "PLEAT"})
        msp.add_lwpolyline(_mm(piece.grain, off), dxfattribs={"layer": "GRAIN"})
        for a in piece.arrows:
            msp.add_lwpolyline(_mm(a, off), dxfattribs={"layer": "GRAIN"})
        h = piece.text_height * 1000.0
        x, y = _mm(piece.label_at[None], off)[0]
        for k, text in enumerate(piece.label):
            msp.add_text(text, dxfattribs={"layer": "LABEL", "height": h, "insert": (x, y - (k + 1) * 1.5 * h)})
    set_extents(doc)
    return doc


def plain_text(pieces, layout, style) -> str:
    stream = io.StringIO()
    with _fixed_metadata():
        plain_document(pieces, layout, style).write(stream)
    return stream.getvalue()
