"""``ease pattern``, ``ease transfer``, ``ease adapt``: sewing patterns from a design.

Each writes ``pattern.json`` (:mod:`core.pattern.io`), ``report.json``
(SPEC metrics and stage timings) and ``pattern.png`` into ``--out``
atomically. Heavy imports happen inside the commands.
"""
from __future__ import annotations

import argparse

CONFIGS = ("improved", "paper", "stretch")


def _common(p) -> None:
    p.add_argument("design", help="design JSON file (see examples/designs/)")
    p.add_argument("--out", required=True, help="output folder (pattern.json, report.json, pattern.png)")
    p.add_argument("--config", choices=CONFIGS, default="improved",
                   help="solver configuration: improved (default; pre-stretched ARAP), paper (the paper's "
                        "weights taken literally), stretch (compliance bought with shear)")
    p.add_argument("--iterations", type=int, default=None, help="local-global iterations (default 20)")
    p.add_argument("--no-seam-length", action="store_true",
                   help="gather every seam: the seam-length term off (the paper's switch for gathered designs)")
    p.add_argument("--quiet", action="store_true", help="no progress line")


def add_parser(sub) -> None:
    p = sub.add_parser("pattern", help="optimize the sewing pattern of a design on its reference body",
                       description="Cut the design on its body and optimize the 2D pattern so the achieved "
                                   "weft/warp scales follow the painted ease. Writes pattern.json, report.json "
                                   "(metrics, timings) and pattern.png.")
    _common(p)
    p.set_defaults(func=_cmd_pattern)

    p = sub.add_parser("transfer", help="transfer a design's ease to another body size and re-solve",
                       description="Shape transfer (paper Eq. transfer-scale): the same cut and ease field on "
                                   "the body of size --size; the pattern is re-solved on that body.")
    _common(p)
    p.add_argument("--size", required=True, help="target size: XS, S, M, L or XL")
    p.set_defaults(func=_cmd_transfer)

    p = sub.add_parser("adapt", help="adapt a design's pattern to target poses",
                       description="Pose adaptation (paper Eqs. adapt-scale, material-scale): the pattern grows "
                                   "where any --pose needs more fabric than the tolerance allows.")
    _common(p)
    p.add_argument("--pose", action="append", required=True,
                   help="target pose preset (P1, P2, P3, T); repeat for several poses")
    p.add_argument("--tolerance", type=float, default=None,
                   help="weft stretch tolerance eps_weft >= 1 (default: the design's materials, else 1.1)")
    p.add_argument("--tolerance-warp", type=float, default=None,
                   help="warp stretch tolerance eps_warp >= 1 (default: --tolerance)")
    p.set_defaults(func=_cmd_adapt)


def _progress(args):
    from ..progress import ConsoleProgress
    return None if args.quiet else ConsoleProgress()


def _config(args, cut):
    from .solve import SolverConfig
    kw = {}
    if args.iterations is not None:
        kw["iterations"] = args.iterations
    if args.no_seam_length:
        kw["gathered"] = ("*",)
    return SolverConfig.named(args.config, **kw)


def prepare(design_path, progress=None):
    """Load a design, its body and cut it. Returns (design, body, cut, ref_vertices, timings)."""
    import time
    from ..body import load_body
    from ..design import load_design
    from ..design.resolve import instance_vertices
    from ..cut import cut_design
    from ..progress import sub

    t0 = time.perf_counter()
    design = load_design(design_path)
    body = load_body(design.body.get("model", "anny") or "anny")
    t1 = time.perf_counter()
    cut = cut_design(design, body=body, progress=sub(progress, 0.0, 0.4))
    t2 = time.perf_counter()
    ref = instance_vertices(design, body)
    return design, body, cut, ref, {"load": t1 - t0, "cut": t2 - t1}


def write_outputs(out, pattern, extra: dict = None) -> None:
    """pattern.json + report.json + pattern.png into ``out`` atomically."""
    from ..fileio import output_dir, write_json
    from ..metrics.pattern import pattern_report
    from .io import save_pattern
    from .plot import render_png

    metrics = pattern_report(pattern)
    if metrics["flipped_triangles"]:
        from ..errors import PatternError
        raise PatternError(f"{metrics['flipped_triangles']} flipped triangles; nothing written")
    pattern.report.update({"metrics": metrics, **(extra or {})})
    with output_dir(out) as tmp:
        save_pattern(pattern, tmp)
        write_json(tmp / "report.json", pattern.report)
        render_png(pattern, tmp / "pattern.png")


def _summary(pattern) -> str:
    m = pattern.report["metrics"]
    c, s = m["compliance"], m["seams"]
    return (f"{pattern.mode}: {len(pattern.panels)} pieces, ease compliance {c['mean']:.2f} ± {c['std']:.2f} % "
            f"(shear p95 {c['shear_p95']:.1f}°), seam mismatch {s['mean']:.2f} % (max {s['max_mm']:.1f} mm), "
            f"flipped {m['flipped_triangles']}, optimize {pattern.report['timings']['optimize']:.2f} s"
            + (f"; gathered: {', '.join(sorted(s['gathered']))}" if s.get("gathered") else ""))


def _cmd_pattern(args) -> int:
    import time
    from ..progress import sub
    from .solve import solve_pattern

    prog = _progress(args)
    design, body, cut, ref, timings = prepare(args.design, prog)
    t0 = time.perf_counter()
    pat = solve_pattern(cut, ref, _config(args, cut), style=design.name, progress=sub(prog, 0.4, 0.95))
    timings["optimize"] = time.perf_counter() - t0
    pat.report["config"] = args.config
    write_outputs(args.out, pat, {"timings": timings})
    print(_summary(pat))
    return 0


def _reference_shape_pose(design, body):
    from ..design.resolve import instance_pose, instance_shape
    return instance_shape(design, body), instance_pose(design)


def _cmd_transfer(args) -> int:
    import time
    from ..body.sizes import check_size, size_shape
    from ..progress import sub
    from .solve import PatternSolver, solve_pattern, transfer_pattern

    size = check_size(args.size)
    prog = _progress(args)
    design, body, cut, ref, timings = prepare(args.design, prog)
    shape_ref, pose = _reference_shape_pose(design, body)
    shape = size_shape(body, size)
    target = body.vertices(shape, pose)
    t0 = time.perf_counter()
    solver = PatternSolver(cut, ref, _config(args, cut), progress=sub(prog, 0.4, 0.5))
    ref_pat = solve_pattern(cut, ref, solver=solver, progress=sub(prog, 0.5, 0.7))
    pat = transfer_pattern(cut, ref, target, solver=solver, start=ref_pat, style=design.name,
                           body={"model": cut.body.get("model", body.name), "shape": shape, "pose": cut.body.get("pose"),
                                 "size": size}, progress=sub(prog, 0.7, 0.95))
    timings["optimize"] = time.perf_counter() - t0
    from ..metrics.pattern import ease_compliance
    pat.report.update({"config": args.config, "size": size,
                       "transfer_deviation": ease_compliance(pat),
                       "reference_compliance": ease_compliance(ref_pat)})
    write_outputs(args.out, pat, {"timings": timings})
    print(_summary(pat) + f"; transfer deviation {pat.report['transfer_deviation']['mean']:.2f} %")
    return 0


def _cmd_adapt(args) -> int:
    import time
    from ..errors import PatternError
    from ..metrics.pattern import residual_stretch
    from ..progress import sub
    from .solve import PatternSolver, adapt_pattern, solve_pattern

    for name, v in (("--tolerance", args.tolerance), ("--tolerance-warp", args.tolerance_warp)):
        if v is not None and not v >= 1.0:
            raise PatternError(f"{name}: a stretch tolerance must be >= 1 (1.1 = 10 % stretch), got {v}")
    prog = _progress(args)
    design, body, cut, ref, timings = prepare(args.design, prog)
    eps_w = args.tolerance if args.tolerance is not None else float(cut.materials.get("eps_weft", 1.1))
    eps_g = args.tolerance_warp if args.tolerance_warp is not None else (
        args.tolerance if args.tolerance is not None else float(cut.materials.get("eps_warp", eps_w)))
    for name, v in (("--tolerance", eps_w), ("--tolerance-warp", eps_g)):
        if not v >= 1.0:
            raise PatternError(f"{name}: a stretch tolerance must be >= 1 (1.1 = 10 % stretch), got {v}")
    shape, _ = _reference_shape_pose(design, body)
    poses = [body.vertices(shape, p) for p in args.pose]
    t0 = time.perf_counter()
    solver = PatternSolver(cut, ref, _config(args, cut), progress=sub(prog, 0.4, 0.5))
    ref_pat = solve_pattern(cut, ref, solver=solver, progress=sub(prog, 0.5, 0.7))
    pat = adapt_pattern(cut, ref, poses, eps_weft=eps_w, eps_warp=eps_g, solver=solver, start=ref_pat,
                        style=design.name, progress=sub(prog, 0.7, 0.95))
    timings["optimize"] = time.perf_counter() - t0
    stretch = {}
    for name, P in zip(args.pose, poses):
        X = cut.positions(P)
        xyz = {p.name: X[p.vertex_ids] for p in cut.panels}
        stretch[name] = {}
        for g in sorted(cut.garments) or [None]:
            stretch[name][g or "all"] = {"before": residual_stretch(ref_pat, xyz, eps_w, g),
                                         "after": residual_stretch(pat, xyz, eps_w, g)}
    pat.report.update({"config": args.config, "poses": list(args.pose), "eps_weft": eps_w, "eps_warp": eps_g,
                       "residual_stretch": stretch})
    write_outputs(args.out, pat, {"timings": timings})
    worst = max((v["after"] for d in stretch.values() for v in d.values()), default=0.0)
    print(_summary(pat) + f"; residual stretch after adaptation <= {worst:.2f} %")
    return 0
