"""``ease body``: write a sized and posed body as OBJ, or all sizes and poses with a picture.

Examples::

    ease body --shape XL --pose P3 --out body.obj
    ease body --measure chest=96,waist=80,hip=100,height=175 --out me.obj
    ease body --shape height=0.7,weight=0.6 --out tall.obj
    ease body --model SMPL_NEUTRAL.npz --shape beta0=1.5 --pose T --out smpl.obj
    ease body --all --out bodies/
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..errors import BodyError
from .model import POSE_PRESETS

MODEL_SUFFIXES = (".npz", ".pkl", ".pickle", ".obj")


def load_model(name: str, blendshapes=None, landmarks=None, up: str = "z"):
    """Body model from ``--model``: ``anny`` (default body), or a path to an SMPL
    ``.npz``/``.pkl`` file or an OBJ template."""
    path = Path(name)
    suffix = path.suffix.lower()
    if suffix in (".npz", ".pkl", ".pickle"):
        from .smpl import load_smpl
        return load_smpl(path)
    if suffix == ".obj":
        from .obj_model import load_obj_body
        return load_obj_body(path, blendshapes=blendshapes, landmarks=landmarks, up=up)
    if suffix or "/" in name:
        raise BodyError(f"--model {name!r}: expected 'anny' or a path to a {', '.join(MODEL_SUFFIXES)} file")
    from . import load_body
    try:
        return load_body(name)
    except (ImportError, FileNotFoundError) as exc:
        raise BodyError(f"--model {name!r}: the body model is not available ({exc})") from None


def resolve_shape(body, text, progress=None):
    """``--shape`` value: a chart size (XS..XL) or ``name=value,...`` shape parameters."""
    from .sizes import SIZES, parse_assignments, size_shape
    from .smpl import check_shape
    if text is None:
        return dict(body.default_shape())
    if str(text).upper() in SIZES:
        return size_shape(body, text, progress=progress)
    if "=" not in str(text):
        params = ", ".join(body.shape_parameters()) or "none"
        raise BodyError(f"--shape {text!r}: expected a size ({', '.join(SIZES)}) or name=value pairs "
                        f"of the model's shape parameters ({params})")
    return check_shape(body.shape_parameters(), parse_assignments(text, "--shape"), f"--shape ({body.name})")


def write_obj(path, vertices: np.ndarray, faces: np.ndarray, comment: str = "") -> Path:
    """Write a triangle mesh as OBJ atomically (metres, Z up)."""
    from ..fileio import write_text
    lines = [f"# {line}" for line in comment.splitlines()] + ["# EASE body, metres, +Z up, facing -Y"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    return write_text(path, "\n".join(lines) + "\n")


def safe_measure(body, vertices):
    """Measurements where the model's landmarks allow them; height always."""
    from .measure import measure
    try:
        return measure(body, vertices)
    except BodyError:
        return measure(body, vertices, ["height"])


def render_bodies(rows, faces: np.ndarray, path, title: str = "") -> Path:
    """Front views of bodies side by side, Lambert-shaded, as PNG (atomic).

    Parameters
    ----------
    rows : list of rows, each a list of (label, vertices (V, 3)).
    faces : (F, 3) triangles shared by all bodies.
    """
    import io
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from ..fileio import write_bytes

    light = np.array([-0.4, -1.0, 0.6])
    light /= np.linalg.norm(light)
    laid = []  # per row: polygons (n, 3, 2), colours, depth, labels, (xmin, xmax, zmin, zmax)
    for row in rows:
        polys, colors, depth, labels = [], [], [], []
        x = 0.0
        for i, (label, v) in enumerate(row):
            width = v[:, 0].max() - v[:, 0].min()
            if i:
                x += 0.5 * width + 0.12
            v = v - [0.5 * (v[:, 0].max() + v[:, 0].min()) - x, 0.0, v[:, 2].min()]
            tri = v[faces]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.linalg.norm(n, axis=1, keepdims=True) + 1e-20
            front = n[:, 1] < 0  # facing the viewer at -Y
            shade = 0.25 + 0.75 * np.clip(n[front] @ light, 0.0, 1.0)
            polys.append(tri[front][:, :, [0, 2]])
            colors.append(np.outer(shade, [0.93, 0.78, 0.66]))
            depth.append(tri[front][:, :, 1].mean(axis=1))
            labels.append((x, label))
            x += 0.5 * width
        polys = np.concatenate(polys)
        bounds = (polys[..., 0].min(), polys[..., 0].max(), -0.25, polys[..., 1].max())
        laid.append((polys, np.concatenate(colors), np.concatenate(depth), labels, bounds))
    widths = [b[1] - b[0] for *_, b in laid]
    heights = [b[3] - b[2] for *_, b in laid]
    fig_w = min(16.0, 2.0 * max(len(r) for r in rows) + 1.0)
    fig_h = fig_w * sum(heights) / max(widths) + 0.6
    fig, axes = plt.subplots(len(rows), 1, figsize=(fig_w, fig_h), squeeze=False,
                             gridspec_kw={"height_ratios": heights})
    for ax, (polys, colors, depth, labels, (x0, x1, z0, z1)) in zip(axes[:, 0], laid):
        order = np.argsort(-depth)  # painter's algorithm: far (large y) first
        ax.add_collection(PolyCollection(polys[order], facecolors=colors[order], edgecolors="none",
                                         antialiased=False))
        for x, label in labels:
            ax.text(x, -0.03, label, ha="center", va="top", fontsize=9)
        ax.set_xlim(x0 - 0.05, x0 + max(widths) + 0.05)
        ax.set_ylim(z0, z1 + 0.05)
        ax.set_aspect("equal")
        ax.axis("off")
    if title:
        fig.suptitle(title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return write_bytes(path, buf.getvalue())


def _fmt(m) -> str:
    return ", ".join(f"{k} {v:.1f} cm" for k, v in m.items())


def _progress(args):
    from ..progress import ConsoleProgress
    return None if args.quiet else ConsoleProgress()


def _write_all(body, out: Path, progress) -> int:
    from ..fileio import output_dir, write_json
    from ..progress import report, sub
    from .sizes import SIZE_CHART, SIZES, size_shape

    summary = {"model": body.name, "sizes": {}, "poses": {}}
    sizes, poses = [], []
    with output_dir(out) as tmp:
        for i, size in enumerate(SIZES):
            report(progress, 0.6 * i / len(SIZES), f"size {size}")
            shape = size_shape(body, size, progress=sub(progress, 0.6 * i / 5, 0.6 * (i + 1) / 5))
            v = body.vertices(shape, None)
            m = safe_measure(body, v)
            write_obj(tmp / f"size_{size}.obj", v, body.faces, f"size {size}, A-pose\n{_fmt(m)}")
            summary["sizes"][size] = {"shape": shape, "measured_cm": m, "chart_cm": SIZE_CHART[size]}
            girths = "/".join(f"{m[k]:.0f}" for k in ("chest", "waist", "hip") if k in m)
            sizes.append((f"{size}\n{girths}" if girths else size, v))
            print(f"size {size:>2}: {_fmt(m)}")
        shape_m = size_shape(body, "M")
        for i, pose in enumerate(POSE_PRESETS):
            report(progress, 0.6 + 0.2 * i / len(POSE_PRESETS), f"pose {pose}")
            v = body.vertices(shape_m, pose)
            write_obj(tmp / f"pose_{pose}.obj", v, body.faces, f"size M, pose {pose}")
            summary["poses"][pose] = {"file": f"pose_{pose}.obj"}
            poses.append((pose, v))
        report(progress, 0.85, "rendering bodies.png")
        render_bodies([sizes, poses], body.faces, tmp / "bodies.png",
                      title=f"{body.name}: sizes XS-XL in A-pose (chest/waist/hip cm); poses A, T, P1, P2, P3 at size M")
        write_json(tmp / "bodies.json", summary)
    report(progress, 1.0, "done")
    for p in sorted(out.iterdir()):
        if p.name.startswith(("size_", "pose_", "bodies.")):
            print(f"wrote {p}")
    return 0


def run(args) -> int:
    from .sizes import check_targets, fit_measurements, parse_assignments

    progress = _progress(args)
    if args.pose not in (None,) and args.pose not in POSE_PRESETS:
        raise BodyError(f"--pose {args.pose!r}: unknown pose; allowed: {', '.join(POSE_PRESETS)}")
    if args.shape is not None and args.measure is not None:
        raise BodyError("give either --shape or --measure, not both")
    if args.all and (args.shape is not None or args.measure is not None or args.pose is not None):
        raise BodyError("--all writes every size and pose; it takes no --shape, --measure or --pose")
    if args.measure is not None:
        targets = check_targets(parse_assignments(args.measure, "--measure"))
    body = load_model(args.model, args.blendshapes, args.landmarks, args.up)
    out = Path(args.out)
    if args.all:
        return _write_all(body, out, progress)
    if args.measure is not None:
        fit = fit_measurements(body, targets, progress=progress)
        shape = fit.shape
        print(fit.summary())
    else:
        shape = resolve_shape(body, args.shape, progress)
    pose = args.pose or "A"
    v = body.vertices(shape, pose)
    m_std = safe_measure(body, body.vertices(shape, None))
    label = args.shape or args.measure or "reference"
    write_obj(out, v, body.faces, f"model {body.name}, shape {label}, pose {pose}\n{_fmt(m_std)}")
    if args.measure is None:
        print(f"measured (A-pose): {_fmt(m_std)}")
    print("shape: " + ", ".join(f"{k}={val:.4g}" for k, val in shape.items()))
    print(f"wrote {out}")
    return 0


def _chart_text() -> str:
    from .sizes import SIZE_CHART
    return "; ".join(f"{k} " + "/".join(f"{v:g}" for v in row.values()) for k, row in SIZE_CHART.items())


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "body",
        help="write a body of a given size/measurements and pose as OBJ",
        description="Write a posed body as OBJ (metres, +Z up, facing -Y) and print its measurements "
                    "(height, chest, waist, hip in cm). --all writes sizes XS..XL and poses A, T, P1, P2, P3 "
                    "and a PNG of them side by side.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:" + __doc__.split("Examples::", 1)[1].rstrip() + "\n\nsizes (cm, height/chest/waist/hip): " + _chart_text(),
    )
    p.add_argument("--model", default="anny",
                   help="body model: 'anny' (default body) or a path to an SMPL/SMPL-X .npz/.pkl or an OBJ template")
    p.add_argument("--shape", default=None,
                   help="a chart size XS, S, M, L, XL (M = reference) or name=value,... shape parameters")
    p.add_argument("--measure", default=None, metavar="chest=96,waist=80,hip=100,height=175",
                   help="fit the shape to these measurements in cm (any of height, chest/bust, waist, hip)")
    p.add_argument("--pose", default=None, help=f"pose preset: {', '.join(POSE_PRESETS)} (default A)")
    p.add_argument("--all", action="store_true", help="write all five sizes and all five poses and bodies.png to --out DIR")
    p.add_argument("--out", required=True, help="output .obj file (or directory with --all)")
    p.add_argument("--blendshapes", default=None, help="OBJ models: .npz of blend shapes (names, deltas, optional skeleton)")
    p.add_argument("--landmarks", default=None, help="OBJ models: landmark JSON")
    p.add_argument("--up", default="z", choices=("z", "y"), help="OBJ models: up axis of the file (default z)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run)
