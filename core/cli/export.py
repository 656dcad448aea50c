"""``ease export``: cutting-room files (SVG, DXF, PDF) and the draped garment (GLB, OBJ)."""

from __future__ import annotations

import sys
from pathlib import Path

from .common import add_quiet, console_progress, print_files, subcommand

FORMATS_HELP = "svg,dxf,pdf,glb,obj or all"


# widths in metres an option may take (the range resolve_allowance accepts for the design's fields)
ALLOWANCE_RANGE = (0.0, 0.1)


def allowance_options(args) -> None:
    """``--allowance`` and ``--hem`` as metres, each checked against :data:`ALLOWANCE_RANGE` before any work
    (one-line ExportError); ``ease export`` and ``ease marker`` alike."""
    from ..errors import ExportError

    for name in ("allowance", "hem"):
        text = getattr(args, name)
        if text is None:
            continue
        try:
            v = float(text)
        except ValueError:
            v = None
        lo, hi = ALLOWANCE_RANGE
        if v is None or not lo <= v <= hi:
            raise ExportError(f"--{name}: expected a width in metres in [{lo:g}, {hi:g}] (e.g. 0.01), got {text!r}")
        setattr(args, name, v)


def _options(args) -> None:
    """Numeric options as numbers, each checked against its range before any work (one-line ExportError)."""
    from ..errors import ExportError
    from ..export.notches import check_notch_spacing

    allowance_options(args)
    if args.notch_spacing is not None:
        args.notch_spacing = check_notch_spacing(args.notch_spacing, "--notch-spacing")
    if args.up not in ("y", "z"):
        raise ExportError(f"--up: expected y or z, got {args.up!r}")
    if args.origin not in ("floor", "root"):
        raise ExportError(f"--origin: expected floor or root, got {args.origin!r}")


def _run(args) -> int:
    _options(args)
    if args.sizes is not None:  # the graded nest of a design: all sizes in one file
        from .graded import run_graded

        return run_graded(args)
    from .. import workflows as wf
    from ..drape.output import read_drape
    from ..errors import ExportError
    from ..export import parse_formats
    from ..pattern.io import load_pattern

    guess = Path(args.pattern_dir).resolve()
    guess = (guess.parent if guess.is_file() else guess).parent / "drape"
    if args.format is None:
        # the 2D files always; the draped garment when there is a drape to export
        have_drape = args.drape is not None or (guess / "drape.npz").is_file()
        args.format = "svg,dxf,pdf" + (",glb,obj" if have_drape else "")
    formats = parse_formats(args.format)
    pattern = load_pattern(args.pattern_dir)
    drape = None
    if "glb" in formats or "obj" in formats:
        drape_dir = Path(args.drape) if args.drape else None
        if drape_dir is None:
            if not (guess / "drape.npz").is_file():
                raise ExportError(
                    f"GLB/OBJ export needs the draped garment: pass --drape DIR (no {guess}/drape.npz); "
                    f"or leave glb/obj out of --format"
                )
            drape_dir = guess
        drape = read_drape(drape_dir)
    warnings: list = []
    files = wf.export(
        pattern,
        args.out,
        formats=formats,
        allowance=args.allowance,
        hem=args.hem,
        notch_spacing=args.notch_spacing,
        drape=drape,
        strict=not args.lenient,
        warnings=warnings,
        up=args.up,
        with_body=args.with_body,
        progress=console_progress(args),
        print_all=args.print_all,
        origin=args.origin,
    )
    for w in warnings:
        print(f"ease export: warning: {w}", file=sys.stderr)
    print_files(files)
    return 0


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "export",
        _run,
        help="write cutting-room files (SVG, DXF ASTM/AAMA, 1:1 PDF) and the draped garment (GLB, OBJ)",
        description="Export a pattern written by `ease pattern` as files a cutting room can use: SVG at 1:1 "
        "in mm; DXF in ASTM D6673/AAMA layers (one block per piece; R2000 and R12) and plain DXF; "
        "PDF at 1:1 tiled on A4 and US Letter (join marks, page grid, 10 cm test square) and one "
        "plotter sheet (914 mm roll); the draped garment as GLB and OBJ with the pattern uv. Every "
        "piece has its cut line (seam allowance), sew line, notches, grain line and label.",
    )
    p.add_argument("pattern_dir", metavar="PATTERN_DIR", help="folder holding pattern.json (or the file itself)")
    p.add_argument(
        "--format",
        default=None,
        help=f"comma-separated formats: {FORMATS_HELP} (default: svg,dxf,pdf, plus glb,obj when a "
        f"drape is given or found)",
    )
    p.add_argument("--out", required=True, help="output folder (filled atomically)")
    p.add_argument(
        "--allowance", default=None, help="seam allowance in metres for every seam (default: the design's, else 0.01)"
    )
    p.add_argument("--hem", default=None, help="hem allowance in metres (default: the design's, else 0.02)")
    p.add_argument(
        "--notch-spacing",
        default=None,
        help="metres between notches along a seam, besides the seam ends (default 0.10; 0: the seam "
        "ends only; else 0.005 to 10)",
    )
    p.add_argument(
        "--up",
        default="y",
        metavar="y|z",
        help="up axis of garment.obj: y (default; OBJ readers' convention, Blender's OBJ import "
        "included; written with garment.mtl) or z (the frame of the body OBJs and "
        "drape/garment.obj, body facing -Y); garment.glb is always +Y up, as glTF requires",
    )
    p.add_argument(
        "--origin",
        default="floor",
        metavar="floor|root",
        help="origin of garment.glb and garment.obj: floor (default; the body stands on it: its lowest "
        "point at height 0, under its root) or root (the body's root, the pelvis, as draped)",
    )
    p.add_argument(
        "--with-body",
        action="store_true",
        help="write the body the pattern was made on (its shape and pose) beside the garment in "
        "garment.glb and garment.obj, in the same frame",
    )
    p.add_argument(
        "--drape",
        default=None,
        help="folder with drape.npz from `ease drape` (default: PATTERN_DIR/../drape when present); needed for glb/obj",
    )
    p.add_argument(
        "--print-all",
        action="store_true",
        help="print every piece whole on the tiled A4/Letter PDFs; by default each mirrored pair (left "
        "and right sides mirror images within 0.5 mm) is printed once, labelled cut 2 (1 as "
        "printed + 1 mirrored), and a piece symmetric about a line along its grain as its half, "
        "to cut on the fold; SVG, DXF and the plotter PDF always hold every piece whole",
    )
    p.add_argument(
        "--lenient",
        action="store_true",
        help="export pieces whose sew line crosses itself or whose allowance does not fit, with a "
        "warning (listed in export.json) instead of failing",
    )
    p.add_argument(
        "--sizes",
        default=None,
        help="graded nest: PATTERN_DIR is then a design file, transferred to these sizes (e.g. "
        "XS,S,M,L,XL) and written as graded_astm.dxf (one AAMA block per piece per size), "
        "graded.svg and graded.pdf (each piece's sizes stacked at the middle of the grain line)",
    )
    add_quiet(p)
