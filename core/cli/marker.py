"""``ease marker``: nest the pieces of one or more sizes on a fabric width (a cutting-room marker).

The marker is made by :func:`core.workflows.marker` (as in the add-on), with the export's allowance
rule: ``--allowance`` and ``--hem`` over the design's table, as ``ease export`` draws the cut lines.
"""

from __future__ import annotations

from pathlib import Path

from .common import add_quiet, console_progress, print_files, subcommand


def _run(args) -> int:
    from .. import workflows as wf
    from ..errors import ExportError
    from ..marker import SPREADS, check_options, default_split, parse_quantities, size_label
    from ..pattern.io import load_pattern
    from .export import allowance_options

    allowance_options(args)
    if args.spread not in SPREADS:
        raise ExportError(f"--spread: expected {' or '.join(SPREADS)}, got {args.spread!r}")
    if args.width is None:
        raise ExportError("--width: expected the fabric width in mm (e.g. 1500)")
    args.threads, args.tries = default_split(args.threads, args.tries)
    check_options(args.width / 1000.0, args.seconds, args.seed, args.threads, args.tries, prefix="--")
    wanted = parse_quantities(args.sizes, "--sizes") if args.sizes is not None else None
    found = {}
    for folder in args.pattern_dirs:
        pattern = load_pattern(folder)
        size = size_label(pattern, folder)
        if size in found:
            raise ExportError(
                f"{folder}: a second pattern of size {size} (the first is {found[size][0]}); "
                f"expected one folder per size"
            )
        found[size] = (folder, pattern)
    if wanted is not None:
        missing = [s for s in wanted if s not in found]
        if missing:
            raise ExportError(
                f"--sizes: no pattern folder of size {', '.join(missing)}; the folders given are "
                f"sizes {', '.join(found)}"
            )
        runs = [(s, found[s][1], n) for s, n in wanted.items()]
    else:
        runs = [(s, p, 1) for s, (_, p) in found.items()]
    marker = wf.marker(
        runs,
        args.width / 1000.0,
        allowance=args.allowance,
        hem=args.hem,
        seconds=args.seconds,
        seed=args.seed,
        one_way=args.one_way,
        tilt=args.tilt,
        threads=args.threads,
        tries=args.tries,
        progress=console_progress(args),
        early_stop=args.early_stop,
        spread=args.spread,
    )
    title = f"{runs[0][1].style or 'marker'} marker"
    extra = {
        "patterns": {s: str(Path(found[s][0])) for s, _, _ in runs},
        "left_out": sorted(set(found) - {s for s, _, _ in runs}),
    }
    files = wf.write_marker(args.out, marker, title, extra=extra)
    print(
        f"marker {marker.width * 1000:.0f} x {marker.length * 1000:.0f} mm, efficiency "
        f"{marker.efficiency * 100:.1f} %, {len(marker.placements)} pieces, {marker.seconds:.0f} s ({marker.stopped})"
    )
    print_files(files)
    return 0


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "marker",
        _run,
        help="nest the pieces of one or more sizes on a fabric width (a cutting-room marker)",
        description="Nest the cut lines (seam allowance included) of every piece of the given pattern folders "
        "(one per size) on a fabric of --width mm, grain parallel to the selvage (pieces turned 0 or "
        "180 degrees; 0 only with --one-way), with spyrrow (sparrow / jagua-rs). Writes marker.dxf "
        "(plotter DXF, mm), marker.svg, marker.pdf (one sheet at 1:1), marker.png and marker.json "
        "(length, efficiency, fabric per garment and per size, time, seed). Ctrl-C stops the search "
        "and writes the best marker found so far.",
    )
    p.add_argument(
        "pattern_dirs",
        nargs="+",
        metavar="PATTERN_DIR",
        help="folders holding pattern.json (from `ease pattern` / `ease transfer`), one per size",
    )
    p.add_argument(
        "--width", type=float, default=None, required=True, help="usable fabric width in mm (e.g. 1500; at most 10000)"
    )
    p.add_argument(
        "--sizes",
        default=None,
        help="garments per size, e.g. XS:1,M:2,L:1 (1 to 100 each; default: one garment of every "
        "folder's size); folders of other sizes are left out",
    )
    p.add_argument(
        "--seconds",
        type=int,
        default=60,
        help="time budget in seconds (default 60; 80 %% exploring, 20 %% compressing): the command "
        "returns within it plus 5 s, with the best marker found",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="nester seed, 0 to 2**32-1 (default 0): with --early-stop, --threads 1 and --tries 1, a marker "
        "that converges in time is repeatable",
    )
    p.add_argument(
        "--early-stop",
        action="store_true",
        help="let the nester stop when its search stops improving (repeatable, usually a longer "
        "marker); by default it uses the whole budget",
    )
    p.add_argument(
        "--threads",
        type=int,
        default=None,
        help="worker threads of each nester (default: one a core, with one nester; they search side by side "
        "and share the best marker; at most the machine's cores)",
    )
    p.add_argument(
        "--tries",
        type=int,
        default=None,
        help="nesters run side by side in the same time, seeds SEED, SEED+1, ... (default 1; with --threads: "
        "as many as the machine's cores hold THREADS each); the shortest marker is kept; THREADS x TRIES "
        "cores, at most the machine's",
    )
    p.add_argument(
        "--one-way",
        action="store_true",
        help="one-way fabric (nap, pile, directional print): every piece the same way up (0 degrees)",
    )
    p.add_argument(
        "--spread",
        default="single",
        metavar="single|pairs",
        help="single: one ply, every piece nested (default); pairs: two plies face to face, as cutting "
        "rooms lay mirrored pieces: one piece of each mirrored pair (the second ply cuts its mirror "
        "image), a piece that is its own mirror image half as often",
    )
    p.add_argument(
        "--tilt", type=float, default=0.0, help="allowed tilt off the grain in degrees (default 0, at most 10)"
    )
    p.add_argument(
        "--allowance",
        default=None,
        help="seam allowance in metres for every seam (default: the design's, else 0.01); the design's "
        "hem allowance stays unless --hem is given, as in `ease export`",
    )
    p.add_argument("--hem", default=None, help="hem allowance in metres (default: the design's, else 0.02)")
    p.add_argument("--out", required=True, help="output folder (filled atomically)")
    add_quiet(p)
