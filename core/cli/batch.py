"""``ease batch``: a design over many bodies (a population or a dataset) on Dask distributed.

Writes ``OUT/items/<id>/`` per item (pattern.json, report.json, body.json and
the optional adapt/, drape/, export/ and specification.json) and
``OUT/manifest.jsonl`` (``manifest.parquet`` too where pyarrow is installed).
A rerun of the same command skips the items already complete. The work is
done by :mod:`core.batch` through :mod:`core.workflows`.
"""

from __future__ import annotations

import sys

from ..choices import SOLVER_CONFIGS as CONFIGS
from .common import add_quiet, console_progress, subcommand


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "batch",
        _cmd,
        help="grade a design over many bodies (measurements, a sample, SMPL betas) on Dask",
        description="Every design x body item through shape transfer (the design is cut once per worker, "
        "each body costs one transfer), optional pose adaptation, drape and export, each in its "
        "own folder, with one manifest row per item (body, girths, metrics, timings, status). "
        "Resumable: a rerun skips items already complete. Runs on a local Dask cluster "
        "(--workers) or an existing one (--scheduler).",
    )
    p.add_argument("design", help="design JSON file (the shipped ones: `ease templates`)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument(
        "--bodies",
        metavar="CSV",
        help="measurement table: a header (height, chest or bust, waist, hip in cm; size; name) and one row per body",
    )
    src.add_argument(
        "--sample",
        type=int,
        metavar="N",
        help="N bodies sampled from Anny's phenotype space (uniform; adult ages), see --seed",
    )
    src.add_argument(
        "--smpl-betas",
        metavar="FILE",
        help="SMPL betas (N, B) as .npy, .npz (array 'betas') or CSV, for the model --model",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of --sample (default 0)")
    p.add_argument(
        "--model", default=None, help="body model file (SMPL .npz/.pkl) for --smpl-betas; default the design's model"
    )
    p.add_argument(
        "--poses",
        default=None,
        metavar="P1,P3",
        help="also adapt each item's pattern to these poses (a cut on the item's body per item)",
    )
    p.add_argument("--drape", action="store_true", help="drape each item's pattern on its body (Warp XPBD)")
    p.add_argument(
        "--export",
        default=None,
        metavar="svg,dxf",
        help="cutting-room formats per item (svg, dxf, pdf; glb, obj with --drape)",
    )
    p.add_argument(
        "--garmentcode",
        action="store_true",
        help="also write each item as a GarmentCode pattern specification (specification.json)",
    )
    p.add_argument(
        "--marker",
        type=float,
        default=None,
        metavar="WIDTH_MM",
        help="also nest each item's pieces on a fabric WIDTH_MM wide into marker/ (as `ease marker`, the "
        "export's allowance rule; one nester per worker)",
    )
    p.add_argument(
        "--marker-seconds",
        type=int,
        default=10,
        help="the nester's budget per item with --marker (default 10 s; 1 to 86400)",
    )
    p.add_argument(
        "--spread",
        default="single",
        metavar="single|pairs",
        help="with --marker: single (one ply, default) or pairs (two plies face to face, as `ease marker --spread`)",
    )
    p.add_argument("--preview", action="store_true", help="write pattern.png per item (slower than the solve)")
    p.add_argument(
        "--config",
        choices=CONFIGS,
        default=None,
        help='solver configuration (default: the design\'s "solver", else improved)',
    )
    p.add_argument("--out", required=True, help="dataset folder (created; reused to resume)")
    p.add_argument("--workers", type=int, default=None, help="local workers (default: the CPU count)")
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="tcp://HOST:PORT",
        help="use a running Dask scheduler instead of a local cluster",
    )
    p.add_argument(
        "--item-timeout",
        type=float,
        default=None,
        metavar="SECONDS",
        help="time limit per item (recorded as status timeout)",
    )
    add_quiet(p, "no progress line (items done, failures, time left)")


def _bodies(args, design: dict):
    from ..batch import bodies as src
    from ..body import load_body

    if args.bodies:
        return src.read_measurements(args.bodies)
    if args.sample is not None:
        return src.sample_anny(args.sample, args.seed, load_body(_model(args, design)).shape_parameters())
    if not args.model:
        from ..batch import BatchError

        raise BatchError("--smpl-betas needs --model FILE: the SMPL model file the betas are for")
    return src.read_betas(args.smpl_betas, load_body(args.model).shape_parameters())


def _model(args, design: dict) -> str:
    return args.model or (design.get("body") or {}).get("model") or "anny"


def _marker_options(args):
    """``--marker`` in m (None: no marker), its budget and spread checked before any work (one line each)."""
    from ..batch import BatchError
    from ..errors import EaseError
    from ..marker import SPREADS, check_options

    if args.spread not in SPREADS:
        raise BatchError(f"--spread: expected {' or '.join(SPREADS)}, got {args.spread!r}")
    if args.marker is None:
        return None
    try:
        width, *_ = check_options(args.marker / 1000.0, args.marker_seconds, 0, 1, 1, prefix="--")
    except EaseError as exc:
        raise BatchError(str(exc).replace("--width", "--marker").replace("--seconds", "--marker-seconds")) from None
    return width


def _cmd(args) -> int:
    from ..batch import Options, run_batch
    from ..batch.run import read_design
    from ..body import POSE_PRESETS
    from ..export import parse_formats

    design = read_design(args.design)
    bodies = _bodies(args, design)
    poses = tuple(p.strip() for p in (args.poses or "").split(",") if p.strip())
    unknown = [p for p in poses if p not in POSE_PRESETS]
    if unknown:
        from ..batch import BatchError

        raise BatchError(f"--poses: unknown pose {unknown[0]!r}; allowed: {', '.join(POSE_PRESETS)}")
    marker_width = _marker_options(args)
    # config None: make_items takes the design's own "solver" (else improved)
    options = Options(
        config=args.config,
        poses=poses,
        drape=args.drape,
        export=tuple(parse_formats(args.export)) if args.export else (),
        garmentcode=args.garmentcode,
        preview=args.preview,
        marker_width=marker_width,
        marker_seconds=args.marker_seconds,
        marker_spread=args.spread,
    )
    result = run_batch(
        design,
        bodies,
        args.out,
        model=_model(args, design),
        options=options,
        workers=args.workers,
        scheduler=args.scheduler,
        item_timeout=args.item_timeout,
        progress=console_progress(args),
    )
    print(result.summary())
    for row in result.own_rows():  # this command's items: the folder may hold other options' too
        if row.get("status") != "ok":
            print(f"{row['label']}: {row['status']}: {row.get('error', '')}")
    if result.interrupted:
        print(
            "ease batch: stopped; the manifest holds the complete items; rerun the same command to resume",
            file=sys.stderr,
        )
        return 130
    return 0 if result.failed == 0 else 1
