"""``ease outfit``: garments worn one over another, patterned on one body and draped inner first.

Through :func:`core.workflows.drape_outfit` and :func:`core.workflows.write_outfit`; the outfit
file's format is :mod:`core.design.outfit` (docs/layers.md).
"""

from __future__ import annotations

from .common import add_quiet, console_progress, subcommand


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "outfit",
        _cmd,
        help="pattern and drape layered garments (a shirt tucked in trousers, a jacket over a shirt)",
        description="Read OUTFIT.json (layers inner first, each a design or template, an upper garment "
        "\"tucked\" into a lower one listed after it), solve every garment's pattern on the outfit's body "
        "and drape them inner first, each against the body and the layers under it. Writes per garment "
        "<name>/pattern, <name>/drape and <name>/export (its own pattern files), outfit.glb / outfit.obj "
        "(every garment its own mesh and material) and outfit_report.json (inter-layer penetration at "
        "every settled frame, gap between layers, time per frame).",
    )
    p.add_argument("outfit", metavar="OUTFIT.json", help="the outfit file (format ease-outfit)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--frames", type=int, default=None, help="frame limit of each garment's drape (default 120)")
    p.add_argument(
        "--edge",
        type=float,
        default=None,
        metavar="M",
        help="cut every garment at this mean edge length (m, 0.005..0.1; default each design's): coarser is faster",
    )
    p.add_argument(
        "--over",
        choices=("skintight", "draped", "body"),
        default="skintight",
        help="the surface an outer garment's pattern is solved and its ease measured on: the inner garments' "
        "skintight surface (default), their draped surface (with its folds), or the body",
    )
    p.add_argument("--device", default="cpu", help="cpu (default; bitwise repeatable) or cuda")
    p.add_argument(
        "--formats",
        default="svg,dxf,pdf,glb,obj",
        help="files per garment and for the outfit (default svg,dxf,pdf,glb,obj)",
    )
    p.add_argument("--no-preview", action="store_true", help="skip the PNG previews")
    add_quiet(p)


def _cmd(args) -> int:
    from ..design.outfit import load_outfit
    from ..drape.options import check_option
    from ..errors import DesignError
    from ..export import parse_formats
    from ..workflows import drape_outfit, outfit_summary, write_outfit

    options = {"device": args.device}
    if args.frames is not None:
        check_option("max_frames", args.frames, "--frames")
        options["max_frames"] = args.frames
        options["min_frames"] = min(10, args.frames)
    if args.edge is not None and not (isinstance(args.edge, float) and 0.005 <= args.edge <= 0.1):
        raise DesignError("--edge", f"expected a mean edge length in 0.005..0.1 m, got {args.edge}")
    formats = parse_formats(args.formats)
    outfit = load_outfit(args.outfit)
    run = drape_outfit(
        outfit, options=options, refine_edge_length=args.edge, over=args.over, progress=console_progress(args)
    )
    write_outfit(args.out, run, formats=formats, preview=not args.no_preview)
    print(outfit_summary(run))
    print(f"wrote {args.out}")
    return 0
