"""Files of a drape: OBJ (+ its MTL), PLY (strain and gap per vertex), NPZ, report, preview PNG.

``garment.obj`` is Y-up by default, the convention of OBJ readers (Blender's importer with its
defaults brings it in standing), ``up="z"`` keeps the core frame (:mod:`core.geom.frame`; the
header says which); its origin is the body's root. ``garment.ply`` and ``drape.npz`` hold the
core frame (+Z up), the one every reader of a drape (``ease export --drape``) takes.

Every writer returns bytes or writes through :mod:`core.fileio`, so a folder
is filled atomically by :func:`write_drape`. The fit measurements are the
caller's (:mod:`core.metrics.drape` comes after the stages): the writers take
the per-vertex gap and the JSON-ready figures as given.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..fileio import output_dir, write_bytes, write_json, write_text
from ..geom.frame import MTL_NAME, frame_text, mtl_text, to_frame

FILES = ("garment.obj", MTL_NAME, "garment.ply", "drape.npz", "drape_report.json", "preview.png")


def obj_text(result, up: str = "y") -> str:
    """Wavefront OBJ: vertex k is global garment vertex id k (1-based in the file); one group per garment.

    ``up``: ``"y"`` (default, OBJ readers' convention: ``(x, z, -y)``) or ``"z"`` (the core frame)."""
    out = io.StringIO()
    out.write("# EASE drape: vertex k = global garment vertex id k-1\n")
    n0 = int(getattr(result, "pattern_vertices", 0) or 0)
    if 0 < n0 < len(result.positions):
        out.write(f"# vertices 1..{n0}: the pattern's; after them the drape mesh's own (refinement, gathers)\n")
    out.write(f"# frame: {frame_text(up, 'root')}\n")
    out.write(f"mtllib {MTL_NAME}\n")
    np.savetxt(out, to_frame(result.positions, up), fmt="v %.6f %.6f %.6f")
    for g, name in enumerate(result.garment_names):
        out.write(f"g {name}\nusemtl fabric\n")
        np.savetxt(out, result.faces[np.asarray(result.face_garment) == g] + 1, fmt="f %d %d %d")
    return out.getvalue()


def ply_bytes(result, vertex_gap: np.ndarray) -> bytes:
    """Binary little-endian PLY with per-vertex ``strain_weft``, ``strain_warp`` (fractions) and ``gap`` (m)."""
    n = len(result.positions)
    vert = np.zeros(
        n,
        dtype=[
            ("x", "<f4"),
            ("y", "<f4"),
            ("z", "<f4"),
            ("strain_weft", "<f4"),
            ("strain_warp", "<f4"),
            ("gap", "<f4"),
        ],
    )
    vert["x"], vert["y"], vert["z"] = result.positions.T
    vert["strain_weft"] = result.strain_weft
    vert["strain_warp"] = result.strain_warp
    vert["gap"] = vertex_gap
    faces = np.zeros(len(result.faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    faces["n"] = 3
    faces["v"] = result.faces
    header = "\n".join(
        [
            "ply",
            "format binary_little_endian 1.0",
            "comment EASE drape: vertex k = global garment vertex id k; metres; strain = stretch vs pattern; "
            "gap = distance outside the body",
            f"element vertex {n}",
            "property float x",
            "property float y",
            "property float z",
            "property float strain_weft",
            "property float strain_warp",
            "property float gap",
            f"element face {len(result.faces)}",
            "property list uchar int vertex_indices",
            "end_header",
            "",
        ]
    )
    return header.encode("ascii") + vert.tobytes() + faces.tobytes()


def npz_bytes(result, vertex_gap: np.ndarray) -> bytes:
    """``drape.npz``: positions (N, 3) by global vertex id, faces (T, 3) and the per-vertex maps (gap (N,) m).

    ``faces`` are the draped (refined) triangles; ``pattern_faces`` the pattern's own, whose
    vertices are ids ``0 .. pattern_vertices - 1``."""
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        positions=result.positions,
        faces=result.faces,
        used=result.used,
        start_positions=result.start_positions,
        strain_weft=result.strain_weft,
        strain_warp=result.strain_warp,
        gap=vertex_gap,
        face_garment=result.face_garment,
        garment_names=np.asarray(result.garment_names),
        seam_pairs=result.seam_pairs,
        pattern_faces=_pattern_faces(result),
        pattern_vertices=np.int64(getattr(result, "pattern_vertices", 0) or len(result.positions)),
    )
    return buf.getvalue()


def _pattern_faces(result) -> np.ndarray:
    """The pattern's own triangles of a drape (its draped ones when it was not refined)."""
    f = getattr(result, "pattern_faces", None)
    return np.asarray(result.faces if f is None else f)


def report_dict(result, fit: dict, pattern=None) -> dict:
    """The JSON report: times, settling, material, and the fit figures.

    ``refinement``: the drape mesh's refinement (target edge, edge lengths in mm and
    triangle counts before and after), ``gathers``: each gathered seam's stitches.
    ``fit`` is the JSON-ready summary of the fit measurements
    (:func:`core.metrics.drape.summary`): ``"all"`` with ``gap_mm``,
    ``penetration_pct``, ``seam_gap_mm``, ``folds`` (mean dihedral angle, share of
    edges over 30 degrees, mean curvature), and per garment. ``stretch_limit``: where the fabric is
    stretched beyond its material's ``max_stretch``, for all, per garment and per piece (the share of
    its area along the weft and the warp, and the largest stretch of each;
    :func:`core.drape.result.stretch_limit_report`).
    """
    return {
        "style": getattr(pattern, "style", ""),
        "body": getattr(pattern, "body", {}),
        "garments": list(result.garment_names),
        "vertices": int(result.used.sum()),
        "triangles": int(len(result.faces)),
        "pattern_triangles": int(len(_pattern_faces(result))),
        "refinement": dict(getattr(result, "refinement", None) or {}),
        "gathers": dict(getattr(result, "gathers", None) or {}),
        "device": result.device,
        "material": result.material,
        "options": result.options,
        "frames": int(result.frames),
        "settled": bool(result.settled),
        "settle_reason": result.settle_reason,
        "settle_frame": int(result.frames) if result.settled else None,
        "timings": result.timings,
        "self_collision": bool(result.self_collision),
        "self_radius_m": float(getattr(result, "self_radius", 0.0)),
        "gap_mm": fit["all"]["gap_mm"],
        "penetration_pct": fit["all"]["penetration_pct"],
        "seam_gap_mm": fit["all"]["seam_gap_mm"],
        "folds": fit["all"].get("folds"),
        "stretch_limit": dict(getattr(result, "stretch_limit", None) or {}),
        "metrics": fit,
    }


def preview_png(result, body_vertices: np.ndarray, body_faces: np.ndarray, path, title: str = "") -> None:
    """Front and side views of the body (grey) and the garment coloured by weft strain."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    bv = np.asarray(body_vertices, float)
    bf = np.asarray(body_faces)
    gv = np.asarray(result.positions, float)
    gf = np.asarray(result.faces)
    strain = np.clip(result.face_strain_weft * 100.0, -10.0, 10.0)
    cmap = plt.get_cmap("coolwarm")
    fig, axes = plt.subplots(1, 2, figsize=(9, 7), dpi=110)
    light = np.array([0.3, -0.8, 0.5]) / np.linalg.norm([0.3, -0.8, 0.5])
    # (horizontal axis, depth axis, depth sign toward the viewer): front looks along +Y, side along -X
    for ax, (h, d, towards), name in ((axes[0], (0, 1, -1.0), "front"), (axes[1], (1, 0, 1.0), "left side")):
        polys, colours, depth = [], [], []
        for v, f, col in ((bv, bf, None), (gv, gf, strain)):
            tri = v[f]
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
            shade = 0.35 + 0.65 * np.abs(n @ light)
            if col is None:
                c = np.column_stack([shade * 0.8] * 3 + [np.ones(len(f))])
            else:
                c = cmap((col + 10.0) / 20.0)
                c[:, :3] *= shade[:, None]
            polys.append(tri[:, :, [h, 2]])
            colours.append(c)
            depth.append(tri[:, :, d].mean(axis=1) * towards)
        polys = np.concatenate(polys)
        colours = np.concatenate(colours)
        order = np.argsort(np.concatenate(depth), kind="stable")  # far first (painter's algorithm)
        ax.add_collection(PolyCollection(polys[order], facecolors=colours[order], edgecolors="none"))
        allv = np.concatenate([bv, gv[result.used]])
        ax.set_xlim(allv[:, h].min() - 0.05, allv[:, h].max() + 0.05)
        ax.set_ylim(allv[:, 2].min() - 0.05, allv[:, 2].max() + 0.05)
        ax.set_aspect("equal")
        ax.set_title(name)
        ax.set_xticks([])
        ax.set_yticks([])
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(-10, 10))
    fig.colorbar(sm, ax=axes, shrink=0.6, label="weft strain vs pattern (%)")
    fig.suptitle(title)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    write_bytes(path, buf.getvalue())


def write_drape(
    out,
    result,
    body_vertices,
    body_faces,
    *,
    fit: dict,
    vertex_gap: np.ndarray,
    pattern=None,
    preview: bool = True,
    up: str = "y",
) -> Path:
    """Write every drape file (:data:`FILES`) into ``out`` atomically.

    Parameters
    ----------
    out : folder, replaced as a whole.
    result : :class:`core.drape.DrapeResult`.
    body_vertices : (V, 3) float m, body_faces : (F, 3) int: the body draped on (for the preview).
    fit : dict, the JSON-ready fit figures for the report (:func:`core.metrics.drape.summary`).
    vertex_gap : (N,) float, m, per global vertex id, its distance outside the body (PLY and NPZ).
    pattern : the pattern draped (its style and body record go into the report).
    preview : write ``preview.png``.
    up : the up axis of ``garment.obj``: ``"y"`` (default) or ``"z"`` (:func:`obj_text`).

    Returns
    -------
    Path of the folder.
    """
    report = report_dict(result, fit, pattern)
    with output_dir(out) as tmp:
        write_text(tmp / "garment.obj", obj_text(result, up))
        write_text(tmp / MTL_NAME, mtl_text())
        write_bytes(tmp / "garment.ply", ply_bytes(result, vertex_gap))
        write_bytes(tmp / "drape.npz", npz_bytes(result, vertex_gap))
        write_json(tmp / "drape_report.json", report)
        if preview:
            title = f"{report['style']}: {result.material['name']}, {result.frames} frames ({result.settle_reason})"
            preview_png(result, body_vertices, body_faces, tmp / "preview.png", title)
    return Path(out)


def read_drape(path) -> tuple:
    """The draped garment of ``drape.npz`` (what :func:`write_drape` wrote), for the export.

    Parameters
    ----------
    path : a drape folder or the ``.npz`` file itself.

    Returns
    -------
    positions : (N, 3) float, metres, by global garment vertex id.
    faces : (F, 3) int or None: the pattern's own triangles (``pattern_faces``, a refined drape),
        else the draped ones.
    """
    from ..errors import ExportError

    path = Path(path)
    if path.is_dir():
        path = path / "drape.npz"
    if not path.is_file():
        raise ExportError(f"--drape: no draped garment at {path} (run `ease drape PATTERN_DIR --out DIR` first)")
    try:
        with np.load(path, allow_pickle=False) as data:
            key = "pattern_faces" if "pattern_faces" in data.files else "faces"
            faces = np.asarray(data[key]) if key in data.files else None
            for key in ("positions", "vertices", "x"):
                if key in data.files:
                    return np.asarray(data[key], float), faces
            keys = ", ".join(data.files)
    except (OSError, ValueError) as exc:
        raise ExportError(f"--drape: cannot read {path}: {exc}") from exc
    raise ExportError(f"--drape: {path} has no 'positions' array (it holds: {keys})")


def read_ply_vertices(path) -> dict:
    """Read back the vertex properties of a PLY written by :func:`ply_bytes` (for tests and tools)."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    n = int(next(line.split()[2] for line in header if line.startswith("element vertex")))
    names = []
    for line in header:
        if line.startswith("element face"):
            break
        if line.startswith("property float"):
            names.append(line.split()[2])
    arr = np.frombuffer(data[end : end + n * 4 * len(names)], dtype="<f4").reshape(n, len(names))
    return {k: arr[:, i] for i, k in enumerate(names)}


__all__ = [
    "FILES",
    "obj_text",
    "ply_bytes",
    "npz_bytes",
    "report_dict",
    "preview_png",
    "write_drape",
    "read_ply_vertices",
]
