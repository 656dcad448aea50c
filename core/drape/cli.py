"""``ease drape``: drape a pattern on its body with our XPBD and measure the fit.

Writes into ``--out`` atomically: ``garment.obj``, ``garment.ply`` (per-vertex
weft/warp strain and gap), ``drape.npz`` (positions by global vertex id, faces:
what the export stage reads), ``drape_report.json`` (times, settling, gap,
penetration, seam gap) and ``preview.png``. Warp is imported inside the command.
"""
from __future__ import annotations


def add_parser(sub) -> None:
    p = sub.add_parser(
        "drape", help="drape a sewing pattern on its body (XPBD in Warp) and measure the fit",
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
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=_cmd)


def _cmd(args) -> int:
    from ..errors import DrapeError
    from ..metrics.drape import drape_metrics
    from ..pattern.io import load_pattern
    from ..progress import ConsoleProgress, sub
    from . import drape
    from .output import body_of_pattern, write_drape

    for name in ("frames", "substeps"):
        value = getattr(args, name)
        if value is not None and value < 1:
            raise DrapeError(f"--{name}: expected a positive integer, got {value}")
    prog = None if args.quiet else ConsoleProgress()
    pattern = load_pattern(args.pattern)
    body_v, body_f = body_of_pattern(pattern)
    options = {"device": args.device}
    if args.frames is not None:
        options["max_frames"] = args.frames
        options["min_frames"] = min(10, args.frames)
    if args.substeps is not None:
        options["substeps"] = args.substeps
    if args.self_collision:
        options["self_collision"] = True
    result = drape(pattern, body_v, body_f, material=args.material, options=options,
                   progress=sub(prog, 0.0, 0.9))
    metrics = drape_metrics(result, body_v, body_f, pattern=pattern)
    if prog:
        prog(0.95, "drape: writing")
    write_drape(args.out, result, metrics, body_v, body_f, pattern=pattern, preview=not args.no_preview)
    if prog:
        prog(1.0, "drape: done")
    a = metrics["all"]
    print(f"drape {pattern.style}: {result.material['name']}, {result.frames} frames ({result.settle_reason}), "
          f"simulate {result.timings['simulate']:.1f} s; gap {a['gap_mm']['mean']:.1f} ± {a['gap_mm']['std']:.1f} mm, "
          f"penetration {a['penetration_pct']:.2f} %, seam gap max {a['seam_gap_mm']['max']:.2f} mm -> {args.out}")
    return 0
