"""Pattern files a cutting room can use: SVG, DXF (ASTM D6673/AAMA), 1:1 PDF, and the draped garment.

:func:`export_pattern` validates the pattern, builds every piece (sew line,
cut line with seam allowance, notches, grain line, label), lays the pieces
out, renders each requested format in memory and only then writes the files,
all at once, through :func:`core.fileio.output_dir`; an invalid pattern or a
failure in any format leaves the output directory untouched.

Files (under ``out_dir``):

========= =====================================================================
format    files
========= =====================================================================
``svg``   ``pattern.svg`` (1:1, mm)
``dxf``   ``pattern_astm.dxf`` (ASTM D6673/AAMA, R2000, $INSUNITS mm),
          ``pattern_astm_r12.dxf`` (same, R12 for Gerber/CLO: $MEASUREMENT metric,
          LAYER table), ``pattern_plain.dxf``; extents set in all three
``pdf``   ``pattern_a4.pdf``, ``pattern_letter.pdf`` (tiled 1:1, nested for the
          fewest pages with a line, 10 mm overlaps; each mirrored pair printed
          once, labelled cut 2; symmetric pieces as halves on the fold),
          ``pattern_plotter.pdf`` (one sheet, 914 mm roll, every piece)
``glb``   ``garment.glb`` (needs the drape; +Y up as glTF requires)
``obj``   ``garment.obj`` (needs the drape; +Z up like every other 3D file, or ``up="y"``)
========= =====================================================================

plus ``export.json``: per piece sew-line length, allowance, notch count, the
page counts and pages left out, per paper the pieces printed and how many to
cut from each (``pdf.a4.pieces``: ``piece``, ``quantity``, ``cut``,
``pieces``), and the 3D files' frames. Which file suits
which tool: ``docs/export.md``.

Seam allowance and notch spacing are set in the design (``materials.export``:
``{"allowance": 0.01 | {"default", "hem", "fold", "<seam line>": m},
"notch_spacing": m}``), travel with the cut and the pattern (``pattern.json``
``materials``) and are used here unless the caller (``--allowance``,
``--hem``, ``--notch-spacing``) overrides them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, List, Optional, Union

import numpy as np

from ..errors import ExportError
from ..fileio import dumps_json, write_files
from ..geom.polyline import polyline_length
from ..pattern.types import Pattern
from ..progress import report, sub
from .allowance import DEFAULT_ALLOWANCE, DEFAULT_HEM, resolve_allowance
from .layout import LAYOUT_MARGIN, SHEET_WIDTH, layout_pieces
from .notches import DEFAULT_NOTCH_SPACING
from .pieces import PieceDrawing, body_summary, build_pieces, resolve_notch_spacing, size_label
from .validate import validate_body, validate_drape, validate_pattern

FORMATS = ("svg", "dxf", "pdf", "glb", "obj")

__all__ = [
    "export_pattern",
    "FORMATS",
    "validate_pattern",
    "build_pieces",
    "layout_pieces",
    "resolve_allowance",
    "DEFAULT_ALLOWANCE",
    "DEFAULT_HEM",
    "DEFAULT_NOTCH_SPACING",
]


def parse_formats(formats: Union[str, Iterable[str]]) -> List[str]:
    """Normalised, de-duplicated format list; ``"all"`` means every format.

    Every entry is checked, ``"all"`` included among others: an unknown one
    is an ExportError naming it.
    """
    if isinstance(formats, str):
        formats = formats.split(",")
    out = []
    for f in formats:
        f = str(f).strip().lower()
        if not f:
            continue
        if f != "all" and f not in FORMATS:
            raise ExportError(f"format {f!r}: expected some of {', '.join(FORMATS)} (or all)")
        for g in FORMATS if f == "all" else (f,):
            if g not in out:
                out.append(g)
    if not out:
        raise ExportError(f"formats: none given; expected some of {', '.join(FORMATS)}")
    return out


def export_pattern(
    pattern: Pattern,
    out_dir,
    formats=("svg", "dxf", "pdf", "glb"),
    allowance=None,
    drape_positions: Optional[np.ndarray] = None,
    progress=None,
    notch_spacing: Optional[float] = None,
    strict: bool = True,
    warnings: Optional[list] = None,
    drape_faces: Optional[np.ndarray] = None,
    up: str = "y",
    body: Optional[tuple] = None,
    print_all: bool = False,
    origin: str = "floor",
) -> List[Path]:
    """Write the pattern's cutting-room files and the draped garment.

    Parameters
    ----------
    pattern : :class:`core.pattern.types.Pattern`.
    out_dir : directory to write into (created; existing unrelated files kept).
    formats : iterable of ``"svg"``, ``"dxf"``, ``"pdf"``, ``"glb"``, ``"obj"``
        (or a comma-separated string).
    allowance : None, metres for every seam, or ``{"default": 0.01, "hem": 0.02,
        "<seam name>": ...}``; None takes ``pattern.materials["export"]["allowance"]``
        and falls back to 1 cm seams and 2 cm hems.
    drape_positions : (N, 3) float, draped garment positions by global vertex id
        (``drape.npz["positions"]``); needed for ``glb``/``obj``.
    progress : ``progress(fraction, message)`` callback, may raise Cancelled.
    notch_spacing : m between notches along a seam (default 10 cm, or
        ``materials["export"]["notch_spacing"]``).
    strict : bool. True (default): a piece whose sew line crosses itself, or
        whose seam allowance does not fit around it, is an error. False: such
        pieces are exported as they are and the problems are listed in
        ``export.json["warnings"]`` (and appended to ``warnings`` if given).

    drape_faces : (F, 3) int or None, the drape's triangles (``drape.npz["faces"]``):
        when given they must be the pattern's (a drape of another pattern is refused).
    up : ``"y"`` (default: OBJ readers' convention) or ``"z"`` (the core frame): the up axis of
        ``garment.obj`` (see :mod:`core.export.mesh`); ``garment.glb`` is always +Y up, as glTF requires.
    origin : ``"floor"`` (default) or ``"root"``: the origin of ``garment.glb`` / ``garment.obj``: on the
        floor (the lowest point of the body, ``body`` or else the pattern's own body instance, at height 0,
        under the root) or the body's root (the core frame).
    body : None or (vertices (V, 3) float m, faces (F, 3) int), the body in the
        drape's frame (:func:`core.body.instance.spec_instance` of ``pattern.body``),
        written beside the garment in the GLB and OBJ.
    print_all : bool. False (default): the tiled PDFs (A4, Letter) print each
        mirrored pair once, labelled to cut 2 (1 as printed + 1 mirrored), when
        its sides are mirror images within 0.5 mm, and a piece symmetric about
        a line along its grain within 0.5 mm as its half, to cut on the fold
        (:mod:`.print_set`); True: every piece whole. SVG, DXF and the plotter
        PDF always hold every piece whole.

    Returns
    -------
    list of Path, the files written (final locations).

    Raises
    ------
    ExportError before any file is written when the pattern, the allowance, the
    formats or the drape are invalid.
    """
    formats = parse_formats(formats)
    from .mesh import ORIGINS, UP_AXES

    if up not in UP_AXES:
        raise ExportError(f"up: expected 'y' or 'z', got {up!r}")
    if origin not in ORIGINS:
        raise ExportError(f"origin: expected floor or root, got {origin!r}")
    # the options and the design's export fields first: a bad value costs no work and no memory
    if not isinstance(pattern, Pattern):
        raise ExportError(f"pattern: expected a core.pattern.types.Pattern, got {type(pattern).__name__}")
    notch_spacing = resolve_notch_spacing(notch_spacing, pattern)
    widths = resolve_allowance(allowance, pattern)
    found = validate_pattern(pattern, strict=strict)
    positions = None
    if "glb" in formats or "obj" in formats:
        from ..pattern.pleats import open_pattern

        worn = open_pattern(pattern)  # a pleated pattern is draped opened (core.drape.simulate)
        positions = validate_drape(worn, drape_positions, drape_faces)
        if body is not None:
            body = validate_body(body)
        if origin == "floor":
            floor = float(np.min((body[0] if body is not None else _pattern_body(pattern))[:, 2]))
            positions = np.asarray(positions, float) - [0.0, 0.0, floor]
            if body is not None:
                body = (np.asarray(body[0], float) - [0.0, 0.0, floor], body[1])
    report(progress, 0.0, "building pattern pieces")
    pieces = build_pieces(
        pattern, widths, notch_spacing, progress=sub(progress, 0.0, 0.3), warnings=None if strict else found
    )
    if warnings is not None:
        warnings.extend(found)
    boxes = [p.bbox for p in pieces]
    title = pattern.style or "pattern"
    size = size_label(pattern)
    files = {}  # relative name -> bytes, rendered fully before anything is written
    summary = {
        "style": title,
        "size": size,
        "body": body_summary(pattern),
        "unit": "mm",
        "allowance_mm": {k: v * 1000 for k, v in widths.items()},
        "pieces": [_piece_summary(p, pattern) for p in pieces],
        "warnings": found,
    }
    if "glb" in formats or "obj" in formats:
        from . import mesh

        meshes = mesh.piece_meshes(worn, positions, [p.rotation for p in pieces])
        body_mesh = None if body is None else mesh.body_mesh(*body)
    steps = len(formats)
    for k, fmt in enumerate(formats):
        report(progress, 0.3 + 0.65 * k / steps, f"rendering {fmt.upper()}")
        if fmt == "svg":
            from .svg import svg_document

            lay = layout_pieces(boxes, SHEET_WIDTH, LAYOUT_MARGIN)
            files["pattern.svg"] = svg_document(pieces, lay, title).encode("utf-8")
            summary["sheet_mm"] = (lay.size * 1000).round(1).tolist()
        elif fmt == "dxf":
            from . import dxf

            lay = layout_pieces(boxes, SHEET_WIDTH, LAYOUT_MARGIN)
            files["pattern_astm.dxf"] = dxf.astm_text(pieces, lay, title, size).encode("ascii", "replace")
            files["pattern_astm_r12.dxf"] = dxf.astm_r12_text(pieces, lay, title, size).encode("ascii", "replace")
            files["pattern_plain.dxf"] = dxf.plain_text(pieces, lay, title).encode("utf-8")
        elif fmt == "pdf":
            from . import pdf
            from .print_set import print_set

            # home-printer pages: each mirrored pair printed once (cut 2), symmetric pieces as halves on the
            # fold, unless print_all
            printed, plan = print_set(pattern, pieces, print_all=print_all)
            pages = {}
            for paper in ("a4", "letter"):
                lay = pdf.print_sheet(printed, paper)
                grid, ink = pdf.sheet_pages(printed, lay, paper)
                files[f"pattern_{paper}.pdf"] = pdf.tiled_pdf(printed, lay, paper, title, pages=(grid, ink))
                pages[paper] = {
                    "rows": grid.rows,
                    "columns": grid.cols,
                    "pages": int(ink.sum()),
                    "left_out": [pdf.page_name(r, c) for r, c in zip(*np.nonzero(~ink))],
                    "overlap_mm": round(pdf.OVERLAP * 1000, 1),
                    "pieces": plan,
                }
            lay = layout_pieces(boxes, SHEET_WIDTH, LAYOUT_MARGIN, reserve=pdf.TEST_RESERVE)
            files["pattern_plotter.pdf"] = pdf.plotter_pdf(pieces, lay, title)
            pages["plotter_mm"] = ((lay.size + 2 * pdf.PAGE_MARGIN) * 1000).round(1).tolist()
            pages["plotter_pieces"] = [{"piece": p.name, "quantity": p.quantity} for p in pieces]
            summary["pdf"] = pages
        elif fmt in ("glb", "obj"):
            if fmt == "glb":
                files["garment.glb"] = mesh.glb_bytes(meshes, body=body_mesh, origin=origin)
            else:
                files["garment.obj"] = mesh.obj_text(meshes, title, up=up, body=body_mesh, origin=origin).encode(
                    "utf-8"
                )
                files[mesh.MTL_NAME] = mesh.mtl_text(meshes, body=body_mesh).encode("utf-8")
            summary["frame"] = {
                "garment.glb": mesh.frame_text("y", origin),
                "garment.obj": mesh.frame_text(up, origin),
                "origin": origin,
                "body": body is not None,
            }
    summary["files"] = sorted(files)
    files["export.json"] = (dumps_json(summary) + "\n").encode("utf-8")
    report(progress, 0.95, "writing files")
    paths = write_files(out_dir, files)
    report(progress, 1.0, f"wrote {len(files)} files to {out_dir}")
    return paths


def _pattern_body(pattern: Pattern) -> np.ndarray:
    """(V, 3) m: the body instance ``pattern`` was made on (its ``body`` record), for the floor of the mesh files."""
    from ..body.instance import spec_instance
    from ..errors import EaseError

    spec = pattern.body or {}
    if not spec.get("model") and spec.get("shape") is None:
        raise ExportError(
            "origin floor: the pattern names no body (pattern.json body) to stand on the floor; use origin root"
        )
    try:
        return np.asarray(spec_instance(spec)[0], float)
    except EaseError as exc:
        raise ExportError(f"origin floor: the pattern's body: {getattr(exc, 'message', exc)}") from None


def _piece_summary(piece: PieceDrawing, pattern: Pattern) -> dict:
    seams = {}
    for n in piece.notches:
        seams.setdefault(n.seam, []).append(round(n.s * 1000, 2))
    return {
        "name": piece.name,
        "garment": piece.garment,
        "quantity": piece.quantity,
        "sew_line_mm": round(sum(polyline_length(l, closed=True) for l in piece.sew) * 1000, 2),
        "cut_line_mm": round(sum(polyline_length(l, closed=True) for l in piece.cut) * 1000, 2),
        "allowance_mm": sorted({round(float(w) * 1000, 2) for e in piece.edge_allowance for w in e}),
        "notches_mm": seams,
        "size_mm": ((piece.bbox[1] - piece.bbox[0]) * 1000).round(1).tolist(),
    }
