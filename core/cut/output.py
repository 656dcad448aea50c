"""Files of a cut: the panels on the body as OBJ and a front/back picture of them.

Both are written through :mod:`core.fileio` (atomic) by the caller
(:func:`obj_text`) or here (:func:`render_png`).
"""

from __future__ import annotations

import numpy as np

from ..fileio import write_bytes
from ..geom.mesh import face_normals


def obj_text(cut, positions: np.ndarray) -> str:
    """Wavefront OBJ of all panels: shared garment vertices, one ``g`` per panel."""
    lines = ["# EASE cut: garment panels embedded on the body (metres, +Z up, body faces -Y)"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in positions]
    for p in cut.panels:
        lines.append(f"g {p.name.replace(' ', '_')}")
        F = np.asarray(p.vertex_ids)[np.asarray(p.faces)] + 1
        lines += [f"f {a} {b} {c}" for a, b, c in F]
    return "\n".join(lines) + "\n"


def _view_polys(X, F, view):
    """2D polygons, depth and shading of triangles facing the viewer.

    view : +1 looks at the front (from -Y), -1 at the back (from +Y).
    """
    T = X[F]
    facing = -view * face_normals(X, F)[:, 1]  # cosine to the view direction
    keep = facing > 0
    xs = T[:, :, 0] * view  # mirror the back view so left/right read naturally
    poly = np.stack([xs, T[:, :, 2]], axis=2)
    depth = view * T[:, :, 1].mean(axis=1)  # larger = farther from the viewer
    return poly[keep], depth[keep], facing[keep], keep


def render_png(cut, body_faces, body_vertices, path, title=""):
    """Front and back views of the body (grey) with its panels coloured (top row)
    and with the panels' target ease (bottom row, colour bar)."""
    import matplotlib

    matplotlib.use("Agg")
    import io

    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    from ..design.geometry import SurfaceLocator

    X = cut.positions(body_vertices)
    cmap = plt.get_cmap("tab10" if len(cut.panels) <= 10 else "tab20")
    ncol = 10 if len(cut.panels) <= 10 else 20
    body_faces = np.asarray(body_faces)
    covered = np.zeros(len(body_faces), dtype=bool)
    if cut.panels:
        loc = SurfaceLocator(body_vertices, body_faces)
        C = np.concatenate([X[np.asarray(p.vertex_ids)[np.asarray(p.faces)]].mean(axis=1) for p in cut.panels])
        _, tri, _ = loc.closest(C)
        covered[tri] = True
    ease_all = np.concatenate([np.asarray(p.ease, dtype=float) for p in cut.panels]) if cut.panels else np.ones(1)
    lo, hi = float(ease_all.min()), float(ease_all.max())
    if hi - lo < 1e-6:
        lo, hi = lo - 0.1, hi + 0.1
    ease_cmap = plt.get_cmap("viridis")
    fig, axes = plt.subplots(2, 2, figsize=(10, 15), dpi=100)
    for row, mode in enumerate(("panels", "ease")):
        for ax, view, label in zip(axes[row], (1, -1), ("front", "back")):
            polys, depths, shades, colors = [], [], [], []
            for part, push in ((~covered, 0.0), (covered, 8e-3)):
                # body triangles under a panel are pushed back: they only show where the panel ends
                bp, bd, bs, _ = _view_polys(body_vertices, body_faces[part], view)
                polys.append(bp)
                depths.append(bd + push)
                shades.append(bs)
                colors.append(np.tile([0.78, 0.78, 0.78], (len(bp), 1)))
            for i, p in enumerate(cut.panels):
                F = np.asarray(p.vertex_ids)[np.asarray(p.faces)]
                pp, pd, ps, keep = _view_polys(X, F, view)
                polys.append(pp)
                depths.append(pd - 3e-3)
                shades.append(ps)  # in front of the body it lies on
                if mode == "panels":
                    colors.append(np.tile(cmap(i % ncol)[:3], (len(pp), 1)))
                else:
                    colors.append(ease_cmap((np.asarray(p.ease)[keep] - lo) / (hi - lo))[:, :3])
            P = np.concatenate(polys)
            D = np.concatenate(depths)
            S = np.concatenate(shades)
            C = np.concatenate(colors)
            order = np.argsort(-D, kind="stable")
            C = C * (0.35 + 0.65 * S)[:, None]
            ax.add_collection(PolyCollection(P[order], facecolors=C[order], edgecolors="none", antialiased=False))
            ax.autoscale_view()
            ax.set_aspect("equal")
            ax.set_axis_off()
            ax.set_title(f"{label}: {'panels' if mode == 'panels' else 'ease (weft scale)'}")
    handles = [plt.Rectangle((0, 0), 1, 1, color=cmap(i % ncol)) for i in range(len(cut.panels))]
    fig.legend(
        handles,
        [p.name for p in cut.panels],
        loc="center",
        bbox_to_anchor=(0.5, 0.515),
        ncol=4,
        fontsize=8,
        frameon=False,
    )
    sm = plt.cm.ScalarMappable(cmap=ease_cmap, norm=plt.Normalize(lo, hi))
    cax = fig.add_axes([0.25, 0.03, 0.5, 0.012])
    fig.colorbar(sm, cax=cax, orientation="horizontal", label="target weft ease rho")
    if title:
        fig.suptitle(title)
    fig.subplots_adjust(left=0.02, right=0.98, top=0.95, bottom=0.07, wspace=0.02, hspace=0.16)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return write_bytes(path, buf.getvalue())


__all__ = ["obj_text", "render_png"]
