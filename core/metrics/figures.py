"""What a user reads of a measured pattern: the key figures and the one-line summary.

Both read ``pattern.report["metrics"]`` (:func:`core.metrics.pattern.pattern_report`)
and show the warp deviation and shear beside the weft compliance, and the
collapsed and crossing counts beside the flipped one (``docs/metrics.md``).
:func:`core.workflows.pattern_figures` and :func:`core.workflows.summary` are
these, for the CLI, the add-on and batch runs.
"""

from __future__ import annotations

from typing import Dict


def key_figures(pattern) -> Dict[str, object]:
    """The key figures of a measured pattern (label -> rounded value)."""
    m = pattern.report["metrics"]
    c, s = m["compliance"], m["seams"]
    return {
        "pieces": len(pattern.panels),
        "compliance mean %": round(float(c["mean"]), 2),
        "compliance std %": round(float(c["std"]), 2),
        "warp deviation mean %": round(float(c["warp_mean"]), 2),
        "warp deviation signed %": round(float(c["warp_signed"]), 2),
        "shear p95 deg": round(float(c["shear_p95"]), 1),
        "seam mismatch mean %": round(float(s["mean"]), 2),
        "seam mismatch max mm": round(float(s["max_mm"]), 1),
        "flipped": int(m["flipped_triangles"]),
        "collapsed": int(m.get("collapsed_triangles", 0)),
        "crossings": int(m.get("crossings", 0)),
        "gathered seams": len(s.get("gathered") or {}),
    }


def summary_line(pattern, optimize_seconds: float = 0.0) -> str:
    """One line: compliance (warp, shear), seams, flipped, collapsed, crossings, the worst region, the mode's
    records."""
    m = pattern.report["metrics"]
    c, s = m["compliance"], m["seams"]
    line = (
        f"{pattern.mode}: {len(pattern.panels)} pieces, ease compliance {c['mean']:.2f} ± {c['std']:.2f} % "
        f"(warp {c['warp_mean']:.2f} %, signed {c['warp_signed']:+.2f} %; shear p95 {c['shear_p95']:.1f}°), "
        f"seam mismatch {s['mean']:.2f} % (max {s['max_mm']:.1f} mm), "
        f"flipped {m['flipped_triangles']}, collapsed {m.get('collapsed_triangles', 0)}, "
        f"crossings {m.get('crossings', 0)}, "
        f"optimize {optimize_seconds:.2f} s"
        + (f"; gathered: {', '.join(sorted(s['gathered']))}" if s.get("gathered") else "")
    )
    regions = m.get("regions") or {}
    if regions:
        name = max(sorted(regions), key=lambda k: regions[k]["mean"])
        r = regions[name]
        line += (
            f"; worst region {name} {r['mean']:.2f} % (signed {r['signed']:+.2f} %, warp {r['warp_mean']:.2f} %, "
            f"shear p95 {r['shear_p95']:.1f}°)"
        )
    if "transfer_deviation" in pattern.report:
        line += f"; transfer deviation {pattern.report['transfer_deviation']['mean']:.2f} %"
    if "residual_stretch" in pattern.report:
        worst = max((v["after"] for d in pattern.report["residual_stretch"].values() for v in d.values()), default=0.0)
        line += f"; residual stretch after adaptation <= {worst:.2f} %"
    return line
