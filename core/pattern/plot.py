"""PNG of a pattern: pieces laid out, coloured by achieved weft ease, seams and grain lines drawn."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..fileio import write_bytes
from ..geom.layout import grain_line


def render_png(pattern, path, title: str = "", dpi: int = 110) -> Path:
    """Draw ``pattern`` to ``path`` (atomic). Colour = achieved weft scale rho-hat."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection

    allw = np.concatenate([p.achieved_weft for p in pattern.panels])
    allw = allw[np.isfinite(allw)]
    # robust colour range: a few slivers must not wash out the picture
    lo, hi = (float(np.percentile(allw, 1)), float(np.percentile(allw, 99))) if allw.size else (0.9, 1.1)
    if hi - lo < 0.05:
        lo, hi = lo - 0.025, hi + 0.025
    uv_all = np.concatenate([p.uv for p in pattern.panels])
    span = np.ptp(uv_all, axis=0)
    w = 12.0
    h = max(3.0, min(12.0, w * span[1] / max(span[0], 1e-9) + 1.2))
    fig, ax = plt.subplots(figsize=(w, h))
    coll = None
    for p in pattern.panels:
        tris = p.uv[p.faces]
        coll = PolyCollection(tris, array=np.nan_to_num(p.achieved_weft), cmap="viridis", edgecolors="none")
        coll.set_clim(lo, hi)
        ax.add_collection(coll)
        for b in p.boundary:
            loop = p.uv[np.r_[b, b[:1]]]
            ax.plot(loop[:, 0], loop[:, 1], color="k", lw=0.6)
        # the grain line as the export draws it (core.geom.layout.grain_line)
        start, end = grain_line(p.uv, p.faces, p.boundary, p.grain)
        ax.annotate("", xy=end, xytext=start, arrowprops=dict(arrowstyle="<->", color="white", lw=1.2))
        c = p.uv.mean(axis=0)
        label = p.name + (" (mirror)" if p.mirror_of else "")
        ax.text(c[0], c[1] - 0.42 * np.ptp(p.uv[:, 1]), label, ha="center", fontsize=7, color="white")
    cmap = plt.get_cmap("tab10")
    for k, s in enumerate(pattern.seams):
        a, b = pattern.seam_polylines(s)
        segs = [a, b]
        ax.add_collection(LineCollection(segs, colors=[cmap(k % 10)], linewidths=1.6))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("m")
    if coll is not None:
        fig.colorbar(coll, ax=ax, fraction=0.025, label="achieved weft scale (SPEC rho-hat)")
    ax.set_title(title or f"{pattern.style} ({pattern.mode})")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return write_bytes(path, buf.getvalue())
