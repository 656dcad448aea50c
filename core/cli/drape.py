"""``ease drape``: drape a pattern on its body with our XPBD and measure the fit.

Writes into ``--out`` atomically, through :mod:`core.workflows`:
``garment.obj`` (+ ``garment.mtl``; Y-up by default, ``--up z``: the core frame), ``garment.ply`` (per-vertex weft/warp strain and gap),
``drape.npz`` (positions by global vertex id, faces: what the export stage
reads), ``drape_report.json`` (times, settling, gap, penetration, seam gap)
and ``preview.png``. Warp is imported inside the command.
"""

from __future__ import annotations

from .common import add_quiet, console_progress, subcommand

#: m, ``--refine-edge``'s default: the drape mesh's longest edge where the cloth hangs free
#: (:attr:`core.drape.options.DrapeOptions.refine_edge`; the Python API's default is the pattern's mesh)
REFINE_EDGE = 0.01


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "drape",
        _cmd,
        help="drape a sewing pattern on its body (XPBD in Warp) and measure the fit",
        description="Drape the pattern in PATTERN_DIR (pattern.json from `ease pattern`) on the body it was "
        "solved for: the garment starts skintight on the body and relaxes to its pattern size under "
        "gravity, pins and body contact, until it settles or hits the frame limit. Writes "
        "garment.obj, garment.ply (strain and gap per vertex), drape.npz, drape_report.json "
        "(times, settle frame, gap mean +- std, penetration, seam gap) and preview.png.",
    )
    p.add_argument("pattern", metavar="PATTERN_DIR", help="folder with pattern.json (or the file itself)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument(
        "--material",
        default=None,
        help="fabric preset: cotton, jersey, denim, silk, wool (default: the design's materials.fabric, else cotton)",
    )
    p.add_argument("--device", default="cpu", help="cpu (default; bitwise repeatable) or cuda")
    p.add_argument("--frames", type=int, default=None, help="frame limit (default 120 at 30 fps)")
    p.add_argument(
        "--solver",
        default=None,
        choices=("xpbd", "pd", "newton", "vbd"),  # core.drape.options.SOLVERS (numpy-free parser)
        help="cloth solver: pd (default; projective dynamics: the fabric's own stiffness), xpbd (faster, softer)",
    )
    p.add_argument("--substeps", type=int, default=None, help="substeps per frame (default: pd 2, silk 3; xpbd 20)")
    p.add_argument(
        "--self-collision",
        action="store_true",
        help="keep the garment's own layers apart (particle self-collision; slower)",
    )
    p.add_argument(
        "--refine-edge",
        type=float,
        default=REFINE_EDGE,
        metavar="M",
        help="the drape's own mesh: where the cloth hangs free, bisect the pattern's triangles until no "
        f"edge is longer than M metres (default {REFINE_EDGE:g}; 0: drape the pattern's mesh as solved); "
        "gathered seams are sewn as gathers on it. --animation drapes the pattern's mesh",
    )
    p.add_argument(
        "--hold-pins",
        action="store_true",
        help="hold every pin for the whole drape (default: an upper garment's collar pins let go once it has "
        "grown to its pattern size, so a shirt hangs from its shoulders; a waistband stays held)",
    )
    p.add_argument("--no-preview", action="store_true", help="skip preview.png")
    p.add_argument(
        "--up",
        default="y",
        choices=("y", "z"),  # core.geom.frame.UP_AXES (numpy-free parser)
        help="up axis of the OBJ files (garment.obj, and the motion OBJs + .pc2 caches of --animation): y "
        "(default; OBJ readers' convention, Blender's OBJ import brings it in standing: (x, z, -y)) or z "
        "(the core frame, body facing -Y; import into Blender with Up: Z, Forward: Y). "
        "garment.ply and the .npz files keep the core frame",
    )
    p.add_argument(
        "--animation",
        metavar="POSES",
        default=None,
        help="drape through a pose sequence instead, e.g. 'A,P1,P3' (the first the pattern's own "
        "pose), or a .json file listing the poses (preset names or {joint: [rx, ry, rz]} rotations): writes motion.npz, motion_report.json (penetration, residual stretch, seconds "
        "per frame) and garment_motion / body_motion .obj + .pc2 point caches",
    )
    p.add_argument(
        "--between",
        type=int,
        default=10,
        help="with --animation: in-between frames from each pose to the next (default 10)",
    )
    p.add_argument(
        "--adapt",
        metavar="DESIGN",
        default=None,
        help="with --animation: first adapt the pattern to the motion's poses after the first (pose "
        "adaptation within DESIGN's stretch tolerances, PATTERN_DIR being DESIGN's reference pattern), "
        "then drape the adapted pattern; writes its pattern.json too, and the report has the residual "
        "stretch per pose before and after adaptation",
    )
    add_quiet(p)


def _options(args) -> dict:
    from ..drape.options import check_option

    # refused before the pattern is read or Warp is loaded
    for flag, name in (("frames", "max_frames"), ("substeps", "substeps")):
        if getattr(args, flag) is not None:
            check_option(name, getattr(args, flag), f"--{flag}")
    refine = getattr(args, "refine_edge", None)
    if refine is not None and refine != 0:
        check_option("refine_edge", refine, "--refine-edge")
    options = {"device": args.device, "refine_edge": refine or None}
    if args.frames is not None:
        options["max_frames"] = args.frames
        options["min_frames"] = min(10, args.frames)
    if args.substeps is not None:
        options["substeps"] = args.substeps
    if getattr(args, "solver", None):
        options["solver"] = args.solver
    if args.self_collision:
        options["self_collision"] = True
    if getattr(args, "hold_pins", False):
        options["hold_pins"] = True
    return options


def _motion(args, options, pattern, prog) -> int:
    """``--animation``: the drape through the poses (:mod:`core.drape.animate`), its files."""
    from ..body import load_body
    from ..body.instance import spec_instance
    from ..drape.animate import (
        check_poses,
        distinct_poses,
        drape_motion,
        motion_report,
        pose_frames,
        pose_label,
        write_motion,
    )
    from ..errors import DrapeError
    from ..progress import report, sub

    poses = args.poses
    spec = dict(pattern.body or {})
    own = spec.get("pose") or "A"
    if poses[0] != own:
        raise DrapeError(
            f"--animation: the sequence starts at the pattern's own pose {own} "
            f"(its garment was cut there), not {pose_label(poses[0], 0)}"
        )
    model = load_body(spec.get("model", "anny"))
    check_poses(model, poses, f"--animation: {args.animation}")
    start = 0.0
    if args.adapt is not None:
        pattern = _adapted(args.adapt, pattern, distinct_poses(poses[1:], own), prog)
        start = 0.2
    frames = pose_frames(model, spec.get("shape"), poses, args.between)
    _, faces = spec_instance(spec, model)
    result = drape_motion(
        pattern, frames, faces, material=args.material, options=options, progress=sub(prog, start, 0.95)
    )
    write_motion(args.out, result, frames, faces, poses, args.between, pattern=pattern, up=args.up)
    report(prog, 1.0, "drape: done")
    rep = motion_report(result, poses, args.between, pattern)
    for pose, garments in (rep.get("adaptation_residual_stretch_pct") or {}).items():
        for g, v in garments.items():
            print(f"adapted to {pose}, {g}: residual stretch {v['before']:.1f} % before, {v['after']:.1f} % after")
    print(
        f"motion {' -> '.join(pose_label(p, i) for i, p in enumerate(poses))} ({rep['pattern']}): "
        f"{rep['frames']} frames, "
        f"worst penetration {rep['worst_penetration_pct']:.2f} %, "
        f"residual stretch p95 up to {max(rep['stretch_p95_pct']):.1f} %, "
        f"{sum(rep['frame_seconds']) / max(len(rep['frame_seconds']), 1):.2f} s a frame -> {args.out}"
    )
    return 0


def _adapted(design, pattern, poses, prog):
    """``--adapt``: ``pattern`` (the reference pattern of ``design``) adapted to ``poses``."""
    from .. import workflows as wf
    from ..errors import DrapeError
    from ..progress import sub

    if not poses:
        raise DrapeError("--adapt: the motion has no pose but the pattern's own to adapt to")
    prep = wf.prepare(design, progress=sub(prog, 0.0, 0.1))
    if pattern.style != prep.design.name:
        raise DrapeError(f"--adapt: PATTERN_DIR is a pattern of the design {pattern.style!r}, not of {design}")
    if (pattern.body or {}).get("shape") != prep.cut.body.get("shape"):
        raise DrapeError(
            f"--adapt: PATTERN_DIR was solved on another body ({(pattern.body or {}).get('shape')!r}) "
            f"than {design}'s reference ({prep.cut.body.get('shape')!r}); adapt the design's reference pattern"
        )
    return wf.adapt(prep, poses, start=pattern, progress=sub(prog, 0.1, 0.2)).pattern


def _cmd(args) -> int:
    from .. import workflows as wf
    from ..pattern.io import load_pattern
    from ..progress import report, sub

    options = _options(args)
    if args.animation is not None:  # refused before the pattern is read
        from ..drape.animate import load_poses, parse_poses
        from ..errors import DrapeError

        if args.animation.strip().lower().endswith(".json"):
            args.poses = load_poses(args.animation.strip(), "--animation")
        else:
            args.poses = parse_poses(args.animation, "--animation")
        if args.between < 0:
            raise DrapeError(f"--between: expected 0 or more in-between frames, got {args.between}")
    if args.adapt is not None:
        from pathlib import Path

        from ..errors import DrapeError

        if args.animation is None:
            raise DrapeError("--adapt: adapts the pattern to the poses of --animation; give --animation too")
        if not Path(args.adapt).is_file():
            raise DrapeError(f"--adapt: no design file {args.adapt}")
    prog = console_progress(args)
    pattern = load_pattern(args.pattern)
    if args.animation is not None:
        return _motion(args, options, pattern, prog)
    run = wf.drape(pattern, material=args.material, options=options, progress=sub(prog, 0.0, 0.9))
    report(prog, 0.95, "drape: writing")
    wf.write_drape(args.out, run, pattern=pattern, preview=not args.no_preview, up=args.up)
    report(prog, 1.0, "drape: done")
    print(f"{wf.drape_summary(run, pattern)} -> {args.out}")
    return 0
