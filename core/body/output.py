"""Files of a body: the posed mesh as OBJ and a picture of bodies side by side.

Both write through :mod:`core.fileio` (atomic).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import BodyError
from ..fileio import write_bytes, write_text
from ..geom.frame import frame_text, to_frame
from ..geom.mesh import face_normals


def write_obj(path, vertices: np.ndarray, faces: np.ndarray, comment: str = "", up: str = "y") -> Path:
    """Write a triangle mesh as OBJ atomically.

    Parameters
    ----------
    vertices : (V, 3) float, metres, the core frame (+Z up, the body facing -Y).
    faces : (F, 3) int.
    comment : lines written as ``#`` comments at the top.
    up : the file's up axis: ``"y"`` (default, OBJ readers' convention: ``(x, z, -y)``) or ``"z"``
        (the core frame); the header says which (:mod:`core.geom.frame`).
    """
    lines = [f"# {line}" for line in comment.splitlines()] + [
        "# EASE body",
        f"# frame: {frame_text(up, 'root', 'the body')}",
    ]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_frame(vertices, up)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    return write_text(path, "\n".join(lines) + "\n")


def safe_measure(body, vertices: np.ndarray) -> dict:
    """Measurements (cm) where the model's landmarks allow them; height always."""
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
            n = face_normals(v, faces)
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
    fig, axes = plt.subplots(
        len(rows), 1, figsize=(fig_w, fig_h), squeeze=False, gridspec_kw={"height_ratios": heights}
    )
    for ax, (polys, colors, depth, labels, (x0, x1, z0, z1)) in zip(axes[:, 0], laid):
        order = np.argsort(-depth)  # painter's algorithm: far (large y) first
        ax.add_collection(PolyCollection(polys[order], facecolors=colors[order], edgecolors="none", antialiased=False))
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


def measures_text(m: dict) -> str:
    """``chest 96.0 cm, waist 80.0 cm, ...`` of a measurement dict (cm)."""
    return ", ".join(f"{k} {v:.1f} cm" for k, v in m.items())


def write_all_bodies(body, out, progress=None, up: str = "y") -> dict:
    """Every chart size (A pose) and every pose preset (size M) as OBJ (up axis ``up``,
    :func:`write_obj`), with ``bodies.png`` and ``bodies.json``, into the folder ``out`` atomically.

    Returns
    -------
    dict
        The ``bodies.json`` record: ``model``, ``sizes`` {size: shape,
        measured_cm, chart_cm}, ``poses`` {pose: file}.
    """
    from ..fileio import output_dir, write_json
    from ..progress import report, sub
    from .model import POSE_PRESETS
    from .sizes import SIZE_CHART, SIZES, size_shape

    summary = {"model": body.name, "sizes": {}, "poses": {}}
    sizes, poses = [], []
    with output_dir(out) as tmp:
        for i, size in enumerate(SIZES):
            report(progress, 0.6 * i / len(SIZES), f"size {size}")
            shape = size_shape(body, size, progress=sub(progress, 0.6 * i / 5, 0.6 * (i + 1) / 5))
            v = body.vertices(shape, None)
            m = safe_measure(body, v)
            write_obj(tmp / f"size_{size}.obj", v, body.faces, f"size {size}, A-pose\n{measures_text(m)}", up)
            summary["sizes"][size] = {"shape": shape, "measured_cm": m, "chart_cm": SIZE_CHART[size]}
            girths = "/".join(f"{m[k]:.0f}" for k in ("chest", "waist", "hip") if k in m)
            sizes.append((f"{size}\n{girths}" if girths else size, v))
        shape_m = size_shape(body, "M")
        for i, pose in enumerate(POSE_PRESETS):
            report(progress, 0.6 + 0.2 * i / len(POSE_PRESETS), f"pose {pose}")
            v = body.vertices(shape_m, pose)
            write_obj(tmp / f"pose_{pose}.obj", v, body.faces, f"size M, pose {pose}", up)
            summary["poses"][pose] = {"file": f"pose_{pose}.obj"}
            poses.append((pose, v))
        report(progress, 0.85, "rendering bodies.png")
        render_bodies(
            [sizes, poses],
            body.faces,
            tmp / "bodies.png",
            title=f"{body.name}: sizes XS-XL in A-pose (chest/waist/hip cm); poses A, T, P1, P2, P3 at size M",
        )
        write_json(tmp / "bodies.json", summary)
    report(progress, 1.0, "done")
    return summary


__all__ = ["write_obj", "safe_measure", "render_bodies", "measures_text", "write_all_bodies"]
