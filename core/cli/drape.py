"""``ease drape``: drape a pattern on its body with our XPBD and measure the fit.

Writes into ``--out`` atomically, through :mod:`core.workflows`:
``garment.obj``, ``garment.ply`` (per-vertex weft/warp strain and gap),
``drape.npz`` (positions by global vertex id, faces: what the export stage
reads), ``drape_report.json`` (times, settling, gap, penetration, seam gap)
and ``preview.png``. Warp is imported inside the command.
"""
from __future__ import annotations

from .common import add_quiet, console_progress, subcommand


def add_parser(sub) -> None:
    p = subcommand(
        sub, "drape", _cmd,
        help="drape a sewing pattern on its body (XPBD in Warp) and measure the fit",
        description="Drape the pattern in PATTERN_DIR (pattern.json from `ease pattern`) on the body it was "
                    "solved for: the garment starts skintight on the body and relaxes to its pattern size under "
                    "gravity, pins and body contact, until it settles or hits the frame limit. Writes "
                    "garment.obj, garment.ply (strain and gap per vertex), drape.npz, drape_report.json "
                    "(times, settle frame, gap mean +- std, penetration, seam gap) and preview.png.")
    p.add_argument("pattern", metavar="PATTERN_DIR", help="folder with pattern.json (or the file itself)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--material", default=None,
                   help="fabric preset: cotton, jersey, denim, silk (default: the design's materials.fabric, "
                        "else cotton)")
    p.add_argument("--device", default="cpu", help="cpu (default; bitwise repeatable) or cuda")
    p.add_argument("--frames", type=int, default=None, help="frame limit (default 120 at 30 fps)")
    p.add_argument("--substeps", type=int, default=None, help="XPBD substeps per frame (default 20)")
    p.add_argument("--self-collision", action="store_true",
                   help="keep the garment's own layers apart (particle self-collision; slower)")
    p.add_argument("--no-preview", action="store_true", help="skip preview.png")
    add_quiet(p)


def _options(args) -> dict:
    from ..drape.options import check_option
    # refused before the pattern is read or Warp is loaded
    for flag, name in (("frames", "max_frames"), ("substeps", "substeps")):
        if getattr(args, flag) is not None:
            check_option(name, getattr(args, flag), f"--{flag}")
    options = {"device": args.device}
    if args.frames is not None:
        options["max_frames"] = args.frames
        options["min_frames"] = min(10, args.frames)
    if args.substeps is not None:
        options["substeps"] = args.substeps
    if args.self_collision:
        options["self_collision"] = True
    return options


def _cmd(args) -> int:
    from .. import workflows as wf
    from ..pattern.io import load_pattern
    from ..progress import report, sub

    options = _options(args)
    prog = console_progress(args)
    pattern = load_pattern(args.pattern)
    run = wf.drape(pattern, material=args.material, options=options, progress=sub(prog, 0.0, 0.9))
    report(prog, 0.95, "drape: writing")
    wf.write_drape(args.out, run, pattern=pattern, preview=not args.no_preview)
    report(prog, 1.0, "drape: done")
    print(f"{wf.drape_summary(run, pattern)} -> {args.out}")
    return 0
