"""``ease body``: write a sized and posed body as OBJ, or all sizes and poses with a picture.

Examples::

    ease body --shape XL --pose P3 --out body.obj
    ease body --chart women --size M --out woman_m.obj
    ease body --size men:L --pose T --out man_l.obj
    ease body --measure chest=96,waist=80,hip=100,height=175 --out me.obj
    ease body --measurements me.json --out me.obj      # tape measures, made-to-measure
    ease body --scan scan.ply --out me.obj             # fit pose, shape and local changes to a scan
    ease body --shape height=0.7,weight=0.6 --out tall.obj
    ease body --model SMPL_NEUTRAL.npz --shape beta0=1.5 --pose T --out smpl.obj
    ease body --all --out bodies/
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..choices import POSE_PRESETS
from ..errors import BodyError
from .common import add_quiet, console_progress, print_files, subcommand


def load_model(name: str, blendshapes=None, landmarks=None, up: str = "z"):
    """Body model from ``--model``: ``anny`` (default body), or a path to an SMPL
    ``.npz``/``.pkl``/``.pickle`` file or an OBJ template (the suffixes a design's
    ``body.model`` takes, :data:`core.body.registry.MODEL_SUFFIXES`)."""
    from ..body.registry import MODEL_SUFFIXES, load_body

    suffix = Path(name).suffix.lower()
    if suffix == ".obj":
        return load_body(name, blendshapes=blendshapes, landmarks=landmarks, up=up)
    if suffix in MODEL_SUFFIXES:
        return load_body(name)
    if suffix or "/" in name:
        raise BodyError(f"--model {name!r}: expected 'anny' or a path to a {', '.join(MODEL_SUFFIXES)} file")
    try:
        return load_body(name)
    except (ImportError, FileNotFoundError) as exc:
        raise BodyError(f"--model {name!r}: the body model is not available ({exc})") from None


def resolve_shape(body, text, progress=None, chart=None):
    """``--shape`` value: a chart size (``M`` of ``chart``, or ``women:M``) or ``name=value,...``
    shape parameters."""
    from ..body.sizes import chart_sizes, parse_assignments, size_of, size_shape
    from ..body.smpl import check_shape

    if text is None:
        return dict(body.default_shape())
    if "=" not in str(text):
        if ":" in str(text) or str(text).upper() in chart_sizes(chart):
            return size_shape(body, size_of(text, chart), progress=progress)
        params = ", ".join(body.shape_parameters()) or "none"
        raise BodyError(
            f"--shape {text!r}: expected a size ({', '.join(chart_sizes(chart))}) or name=value pairs "
            f"of the model's shape parameters ({params}), or chart:size"
        )
    return check_shape(body.shape_parameters(), parse_assignments(text, "--shape"), f"--shape ({body.name})")


def _write_all(body, out: Path, progress, up: str) -> int:
    from ..body.output import measures_text, write_all_bodies

    summary = write_all_bodies(body, out, progress, up)
    for size, rec in summary["sizes"].items():
        print(f"size {size:>2}: {measures_text(rec['measured_cm'])}")
    print_files((p for p in sorted(out.iterdir()) if p.name.startswith(("size_", "pose_", "bodies."))), prefix="wrote ")
    return 0


def run(args) -> int:
    from ..body.output import measures_text, safe_measure, write_obj
    from ..body.sizes import check_chart, check_targets, fit_measurements, parse_assignments, size_of

    progress = console_progress(args)
    if args.chart is not None:
        check_chart(args.chart, "--chart")
    if args.size is not None:
        if args.shape is not None:
            raise BodyError("give either --size or --shape, not both")
        try:
            args.shape = size_of(args.size, args.chart)
        except BodyError as exc:
            raise BodyError(f"--size: {exc}") from None
    if args.pose not in (None,) and args.pose not in POSE_PRESETS:
        raise BodyError(f"--pose {args.pose!r}: unknown pose; allowed: {', '.join(POSE_PRESETS)}")
    if args.shape is not None and args.measure is not None:
        raise BodyError("give either --shape or --measure, not both")
    if args.measurements is not None and (args.shape is not None or args.measure is not None or args.all):
        raise BodyError(
            "--measurements fits the body to a table of tape measures; it takes no --shape, --size, --measure or --all"
        )
    if args.scan is not None and (
        args.shape is not None or args.measure is not None or args.measurements is not None or args.all
    ):
        raise BodyError(
            "--scan fits the body to a scan; it takes no --shape, --size, --measure, --measurements or --all"
        )
    if args.all and (args.shape is not None or args.measure is not None or args.pose is not None):
        raise BodyError("--all writes every size and pose; it takes no --shape, --measure or --pose")
    if args.measure is not None:
        targets = check_targets(parse_assignments(args.measure, "--measure"))
    body = load_model(args.model, args.blendshapes, args.landmarks, args.up)
    out = Path(args.out)
    if args.all:
        return _write_all(body, out, progress, args.out_up)
    if args.scan is not None:
        return _fit_scan(args, body, out, progress)
    if args.measurements is not None:
        from ..body.made_to_measure import fit_tape, read_tape_file

        fit = fit_tape(body, read_tape_file(args.measurements), progress=progress)
        shape = fit.shape
        print(fit.summary())
        args.measure = f"measurements of {args.measurements}"
    elif args.measure is not None:
        fit = fit_measurements(body, targets, progress=progress)
        shape = fit.shape
        print(fit.summary())
    else:
        shape = resolve_shape(body, args.shape, progress, args.chart)
    pose = args.pose or "A"
    v = body.vertices(shape, pose)
    m_std = safe_measure(body, body.vertices(shape, None))
    label = args.shape or args.measure or "reference"
    write_obj(out, v, body.faces, f"model {body.name}, shape {label}, pose {pose}\n{measures_text(m_std)}", args.out_up)
    if args.measure is None:
        print(f"measured (A-pose): {measures_text(m_std)}")
    print("shape: " + ", ".join(f"{k}={val:.4g}" for k, val in shape.items()))
    print(f"wrote {out}")
    return 0


def _fit_scan(args, body, out: Path, progress) -> int:
    import json

    from ..body.output import write_obj
    from ..body.scan import fit_scan, read_scan

    points = read_scan(args.scan, up=args.up, units=args.scan_units)
    fit = fit_scan(body, points, progress=progress)
    print(fit.summary())
    if args.pose is None:  # the body as scanned: its pose, placed on the scan
        v = body.vertices(fit.shape, fit.pose) @ fit.rotation.T + fit.translation
        label = "the scan's pose, placed on the scan"
    else:
        v = body.vertices(fit.shape, args.pose)
        label = f"pose {args.pose}"
    d = fit.distance_mm
    write_obj(
        out,
        v,
        body.faces,
        f"model {body.name} fitted to {args.scan} ({label}); scan to body mean {d['mean']:.1f} mm, p95 {d['p95']:.1f} mm",
        args.out_up,
    )
    rounded = {k: round(val, 4) for k, val in fit.shape.items()}
    pose = {j: [round(a, 4) for a in r] for j, r in fit.pose.items()}
    print('design body: {"shape": ' + json.dumps(rounded) + ', "pose": ' + json.dumps(pose) + "}")
    print(f"wrote {out}")
    return 0


def _chart_text() -> str:
    from ..body.sizes import CHARTS

    return "\n".join(
        f"  {c.name}: " + "; ".join(f"{k} " + "/".join(f"{v:g}" for v in row.values()) for k, row in c.sizes.items())
        for c in CHARTS.values()
    )


class _ChartsHelp(argparse.RawDescriptionHelpFormatter):
    """``ease body --help``'s epilog with the size charts, read only when the help is shown: the charts
    need numpy, which ``ease --help`` and every other command's parser do without."""

    def add_text(self, text):
        if text and _CHARTS in text:
            text = text.replace(_CHARTS, _chart_text())
        super().add_text(text)


_CHARTS = "<size charts>"


def add_parser(subparsers) -> None:
    p = subcommand(
        subparsers,
        "body",
        run,
        help="write a body of a given size/measurements and pose as OBJ",
        description="Write a posed body as OBJ (metres, +Y up by default, facing +Z; --out-up z: +Z up, "
        "facing -Y) and print its measurements "
        "(height, chest, waist, hip in cm). --all writes sizes XS..XL and poses A, T, P1, P2, P3 "
        "and a PNG of them side by side.",
        formatter_class=_ChartsHelp,
        epilog="examples:"
        + __doc__.split("Examples::", 1)[1].rstrip()
        + "\n\nsize charts (cm, height/chest/waist[/hip]):\n"
        + _CHARTS,
    )
    p.add_argument(
        "--model",
        default="anny",
        help="body model: 'anny' (default body) or a path to an SMPL/SMPL-X .npz/.pkl or an OBJ template",
    )
    p.add_argument(
        "--shape", default=None, help="a chart size XS, S, M, L, XL (M = reference) or name=value,... shape parameters"
    )
    p.add_argument(
        "--chart",
        default=None,
        help="size chart of --size/--shape sizes: default (Anny's XS..XL), women or men (EN 13402-3)",
    )
    p.add_argument(
        "--size", default=None, help="a size of --chart (e.g. M) or chart:size (women:M); the same as --shape SIZE"
    )
    p.add_argument(
        "--measure",
        default=None,
        metavar="chest=96,waist=80,hip=100,height=175",
        help="fit the shape to these measurements in cm (any of height, chest/bust, waist, hip)",
    )
    p.add_argument(
        "--measurements",
        default=None,
        metavar="FILE.json|FILE.csv",
        help="made-to-measure: fit Anny's phenotypes and local changes to a table of tape measures "
        "in cm (height, neck, shoulder_width, chest/bust, underbust, waist, high_hip, hip, "
        "upper_arm, wrist, arm_length, back_waist_length, inseam, thigh; optional gender 0..1; "
        "docs/measurements.md)",
    )
    p.add_argument(
        "--scan",
        default=None,
        metavar="SCAN.obj|SCAN.ply",
        help="fit Anny's pose, shape and local changes to a 3D scan or point cloud (OBJ or PLY vertices); "
        "prints the scan-to-body distance and the tape measures of both; writes the body as scanned "
        "(or in --pose)",
    )
    p.add_argument(
        "--scan-units",
        default="auto",
        choices=("auto", "m", "cm", "mm"),
        help="units of --scan (default: read from the scan's height)",
    )
    p.add_argument("--pose", default=None, help=f"pose preset: {', '.join(POSE_PRESETS)} (default A)")
    p.add_argument(
        "--all", action="store_true", help="write all five sizes and all five poses and bodies.png to --out DIR"
    )
    p.add_argument("--out", required=True, help="output .obj file (or directory with --all)")
    p.add_argument(
        "--blendshapes", default=None, help="OBJ models: .npz of blend shapes (names, deltas, optional skeleton)"
    )
    p.add_argument("--landmarks", default=None, help="OBJ models: landmark JSON")
    p.add_argument(
        "--up", default="z", choices=("z", "y"), help="OBJ models and --scan: up axis of the file read (default z)"
    )
    p.add_argument(
        "--out-up",
        default="y",
        choices=("y", "z"),
        help="up axis of the OBJ written: y (default; OBJ readers' convention, Blender's OBJ import brings the body "
        "in standing: (x, z, -y)) or z (the core frame, body facing -Y; import into Blender with Up: Z, Forward: Y)",
    )
    add_quiet(p, "no progress lines")
