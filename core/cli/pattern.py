"""``ease pattern``, ``ease transfer``, ``ease adapt``: sewing patterns from a design.

Each writes ``pattern.json`` (:mod:`core.pattern.io`), ``report.json``
(SPEC metrics and stage timings) and ``pattern.png`` (not with ``--no-png``) into ``--out``
atomically, through :mod:`core.workflows`. Heavy imports happen inside the
commands.
"""

from __future__ import annotations

from ..choices import SOLVER_CONFIGS as CONFIGS
from ..choices import TRANSFER_SOLVERS
from .common import add_quiet, console_progress, subcommand


def _common(p) -> None:
    p.add_argument("design", help="design JSON file (the shipped ones: `ease templates`)")
    p.add_argument("--out", required=True, help="output folder (pattern.json, report.json, pattern.png)")
    p.add_argument(
        "--config",
        choices=CONFIGS,
        default=None,
        help='solver configuration (default: the one the design names in its "solver" field, else '
        "improved; given, it overrides the design's): improved (pre-stretched ARAP), paper (the "
        "paper's weights taken literally), stretch (compliance bought with shear), fitted (darted, "
        "close-fitting garments: 300 iterations, warp lengths nearly kept), lengths (the "
        "design's lengths kept along the grain: warp within 3 %% for about twice the shear)",
    )
    p.add_argument(
        "--iterations",
        type=int,
        default=None,
        help="local-global iterations (default: the configuration's, 20; fitted 300)",
    )
    p.add_argument(
        "--no-seam-length",
        action="store_true",
        help="gather every seam: the seam-length term off (the paper's switch for gathered designs)",
    )
    p.add_argument(
        "--no-png", action="store_true", help="skip pattern.png (its drawing is ~half the wall time of a small pattern)"
    )
    add_quiet(p)


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "pattern",
        _cmd_pattern,
        help="optimize the sewing pattern of a design on its reference body",
        description="Cut the design on its body and optimize the 2D pattern so the achieved "
        "weft/warp scales follow the painted ease. Writes pattern.json, report.json "
        "(metrics: weft compliance with the warp deviation and shear beside it, flipped and "
        "collapsed triangles, compliance near the bust points, shoulder blades and seat; "
        "timings) and pattern.png. A pattern with a flipped triangle is refused.",
    )
    _common(p)

    p = subcommand(
        sub,
        "transfer",
        _cmd_transfer,
        help="transfer a design's ease to another body size and re-solve",
        description="Shape transfer (paper Eq. transfer-scale): the same cut and ease field on "
        "the body of size --size; the pattern is re-solved on that body.",
    )
    _common(p)
    p.add_argument("--size", required=True, help="target size: XS, S, M, L or XL")
    p.add_argument(
        "--transfer-solver",
        choices=TRANSFER_SOLVERS,
        default=None,
        help="the body the transfer's flattening and factorisation are made on: reference (the design's body, "
        "the default) or target (the --size body; docs/darts.md)",
    )

    p = subcommand(
        sub,
        "adapt",
        _cmd_adapt,
        help="adapt a design's pattern to target poses",
        description="Pose adaptation (paper Eqs. adapt-scale, material-scale): the pattern grows "
        "where any --pose needs more fabric than the tolerance allows.",
    )
    _common(p)
    p.add_argument(
        "--pose", action="append", required=True, help="target pose preset (P1, P2, P3, T); repeat for several poses"
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=None,
        help="weft stretch tolerance eps_weft >= 1 (default: the design's materials, else 1.1)",
    )
    p.add_argument(
        "--tolerance-warp", type=float, default=None, help="warp stretch tolerance eps_warp >= 1 (default: --tolerance)"
    )


def _solver_options(args) -> dict:
    from ..pattern.config import check_iterations

    if args.iterations is not None:
        check_iterations("--iterations", args.iterations)
    return {"config": args.config, "iterations": args.iterations, "gather_all": args.no_seam_length}


def _prepare(args, prog):
    from .. import workflows as wf
    from ..progress import sub

    return wf.prepare(args.design, progress=sub(prog, 0.0, 0.4))


def _write(args, run) -> int:
    from .. import workflows as wf

    wf.write_pattern(args.out, run, preview=not args.no_png)
    print(wf.summary(run))
    return 0


def _cmd_pattern(args) -> int:
    from .. import workflows as wf
    from ..progress import sub

    options = _solver_options(args)
    prog = console_progress(args)
    prep = _prepare(args, prog)
    return _write(args, wf.reference(prep, **options, progress=sub(prog, 0.4, 0.95)))


def _cmd_transfer(args) -> int:
    from .. import workflows as wf
    from ..body.sizes import check_size
    from ..progress import sub

    size = check_size(args.size)
    options = _solver_options(args)
    prog = console_progress(args)
    prep = _prepare(args, prog)
    options["transfer_solver"] = args.transfer_solver
    return _write(args, wf.transfer(prep, size, **options, progress=sub(prog, 0.4, 0.95)))


def _cmd_adapt(args) -> int:
    from .. import workflows as wf
    from ..pattern.config import check_tolerance
    from ..progress import sub

    for name, v in (("--tolerance", args.tolerance), ("--tolerance-warp", args.tolerance_warp)):
        if v is not None:
            check_tolerance(name, v)  # refused before the cut
    options = _solver_options(args)
    prog = console_progress(args)
    prep = _prepare(args, prog)
    return _write(
        args,
        wf.adapt(
            prep,
            args.pose,
            eps_weft=args.tolerance,
            eps_warp=args.tolerance_warp,
            **options,
            progress=sub(prog, 0.4, 0.95),
        ),
    )
