"""``ease cut``: cut a design's panels out of the body surface and write them.

``--size`` re-cuts the design on that size (keypoints resolved on it);
``--pose`` shows the cut (made on the design's reference pose) on a pose.

Writes (atomically, all or nothing) into ``--out``:
``panels.obj`` (one ``g`` group per panel, on the instance cut), ``cut.json`` +
``cut_embedding.npz`` (reloadable with :func:`core.cut.io.load_cut`),
``design.json`` (the validated design) and ``cut.png`` (the body with its
panels coloured, front and back views).
"""

from __future__ import annotations

import time
from pathlib import Path

from ..choices import POSE_PRESETS
from ..errors import BodyError
from .common import add_quiet, console_progress, subcommand


def run_cut(design_path, out, size=None, pose=None, body_name=None, progress=None, png=True) -> dict:
    """Cut ``design_path`` and write the cut directory ``out``; returns a summary."""
    from ..body import load_body
    from ..body.instance import body_instance
    from ..body.registry import load_spec
    from ..cut import cut_design
    from ..cut.auto_darts import has_auto, place_darts
    from ..cut.io import save_cut
    from ..cut.output import obj_text, render_png
    from ..design import load_design
    from ..fileio import output_dir, write_json, write_text

    design = load_design(design_path)
    if size is not None:
        # A bare size is of the design's own chart (body.chart), as in ``ease transfer``.
        try:
            from ..body.sizes import size_of

            size = size_of(size, design.body.get("chart"))
        except BodyError as exc:
            raise BodyError(f"--size: {exc}") from None
    body = load_body(body_name) if body_name else load_spec(design.body)
    if has_auto(design):
        # automatic darts placed here, so design.json holds them as explicit darts to edit
        design = place_darts(design, body=body, progress=progress)
    t0 = time.perf_counter()
    # The design is defined (its lengths traced) on its reference pose; the cut is
    # pose-independent, so a requested pose only changes where the panels are shown.
    cut = cut_design(design, body=body, shape=size, progress=progress)
    seconds = time.perf_counter() - t0
    vertices = body_instance(body, size or design.body.get("shape"), pose or design.body.get("pose"))
    X = cut.positions(vertices)
    with output_dir(out) as tmp:
        write_text(tmp / "panels.obj", obj_text(cut, X))
        save_cut(cut, tmp)
        write_json(tmp / "design.json", design.to_json())
        if png:
            render_png(
                cut,
                body.faces,
                vertices,
                tmp / "cut.png",
                title=f"{design.name} on {body.name} ({size or design.body.get('shape')}, "
                f"pose {pose or design.body.get('pose')})",
            )
    return {
        "design": design.name,
        "panels": [p.name for p in cut.panels],
        "seams": len(cut.seams),
        "vertices": cut.n_vertices,
        "triangles": int(sum(len(p.faces) for p in cut.panels)),
        "seconds": seconds,
    }


def _cmd(args) -> int:
    summary = run_cut(
        args.design,
        args.out,
        size=args.size,
        pose=args.pose,
        body_name=args.body,
        progress=console_progress(args),
        png=not args.no_png,
    )
    print(
        f"cut {summary['design']!r}: {len(summary['panels'])} panels ({', '.join(summary['panels'])}), "
        f"{summary['seams']} seams, {summary['triangles']} triangles in {summary['seconds']:.2f} s"
    )
    print(
        f"wrote {Path(args.out) / 'panels.obj'}, cut.json, cut_embedding.npz, design.json"
        f"{'' if args.no_png else ', cut.png'}"
    )
    return 0


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "cut",
        _cmd,
        help="cut a design's panels out of the body surface",
        description="Resolve a design (a design JSON file, e.g. a template from `ease templates`) on the "
        "body, cut its seamlines into the body mesh and write the panels: panels.obj (one group "
        "per panel), cut.json + cut_embedding.npz (seams, grain, ease, pins; reloadable), "
        "design.json and cut.png (front/back views). Nothing is written if the design is invalid.",
    )
    p.add_argument("design", help="design JSON file")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument(
        "--size",
        default=None,
        help="cut on this size instead of the design's body shape: a size of the design's chart "
        "(e.g. M) or of a named one (women:M)",
    )
    p.add_argument(
        "--pose",
        choices=POSE_PRESETS,
        default=None,
        help="write the panels (OBJ, PNG) on this pose; the cut is made on the design's "
        "reference pose and holds for every pose",
    )
    p.add_argument("--body", default=None, help="body model (default: the design's, e.g. anny)")
    p.add_argument("--no-png", action="store_true", help="skip the PNG picture")
    add_quiet(p)
