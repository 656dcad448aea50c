"""The weft / warp / shear frontier of the shirt and the pants: ``run(out_dir) -> dict``.

Issue 14 asks the shirt and pants tables to keep weft compliance <= 1.2 % while
the warp deviation comes down to <= 3 %, and, where both cannot hold at once,
the frontier with the configuration that reaches each point. The design's
warp scale is 1.0 (lengths are set by length parameters), so every point of
warp deviation the default buys back costs something: shear, seam mismatch or
weft. This benchmark solves both garments at uniform ease 1.0, 1.35 and 1.8
over a grid of the three settings that trade them (the local step's warp
slack, the weft and warp target feedback gains, and the iterations), measures
weft, warp, shear p95, the largest seam mismatch, flipped and collapsed
triangles (SPEC metrics, docs/metrics.md), and marks the configurations that
no other configuration beats on all four figures (the frontier) and those
that meet weft <= 1.2 % and warp <= 3 % together.

The configurations that meet both are then solved on every shipped template
at its design ease (reference M of its chart): the largest seam mismatch and
shear p95 there say what the default would cost the other garments.

One solver (flattening, factorisation) per garment serves every configuration:
only the configuration of each solve changes.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
DESIGNS = REPO / "examples" / "designs"
LEVELS = (1.0, 1.35, 1.8)
GARMENTS = {"shirt": "shirt_long_sleeve", "pants": "pants"}
WEFT_GOAL, WARP_GOAL = 1.2, 3.0
FIGURES = ("weft", "warp", "shear_p95", "seam_max_mm")


def configurations(quick: bool = False) -> dict:
    """label -> (preset, overrides): the default, the other presets, and a grid of warp slack x feedback."""
    grid = {
        "improved (default)": ("improved", {}),
        "lengths": ("lengths", {}),
        "stretch": ("stretch", {}),
        "fitted": ("fitted", {}),
    }
    slacks = (0.12, 0.0) if quick else (0.12, 0.05, 0.0)
    gains = (
        ((0.06, 0.0), (0.10, 0.05), (0.15, 0.08))
        if quick
        else ((0.06, 0.0), (0.06, 0.04), (0.10, 0.05), (0.12, 0.06), (0.15, 0.08))
    )
    for slack in slacks:
        for weft, warp in gains:
            for iterations in (20,) if quick else (20, 60):
                if (slack, weft, warp, iterations) == (0.12, 0.06, 0.0, 20):
                    continue  # the default itself
                label = f"warp slack {slack:g}, feedback {weft:g} / {warp:g}, {iterations} it."
                grid[label] = (
                    "improved",
                    {"iterations": iterations, "warp_slack": slack, "feedback": {"weft": weft, "warp": warp}},
                )
    return grid


def _figures(pattern) -> dict:
    from core.metrics.pattern import collapse, ease_compliance, flips, seam_mismatch

    c, s = ease_compliance(pattern), seam_mismatch(pattern)
    return {
        "weft": c["mean"],
        "warp": c["warp_mean"],
        "warp_signed": c["warp_signed"],
        "shear_p95": c["shear_p95"],
        "seam_max_mm": s["max_mm"],
        "flips": int(sum(flips(pattern).values())),
        "collapsed": int(sum(v["count"] for v in collapse(pattern).values())),
    }


def _solve(solver, cut, config, ease=None) -> tuple:
    from core.pattern.solve import build_pattern

    K, cw, cg = solver.targets_reference(ease=ease)
    t0 = time.process_time()
    res = solver.solve(K, cw, cg, config=config)
    return build_pattern(cut, res), time.process_time() - t0


def _prepare(name, body, coarse):
    from core import workflows as wf
    from core.design import load_design
    from core.pattern.solve import PatternSolver, SolverConfig

    design = load_design(DESIGNS / f"{name}.json")
    if coarse:
        design.refine_edge_length = coarse
    prep = wf.prepare(design, body=body)
    return prep.cut, PatternSolver(prep.cut, prep.reference, SolverConfig.improved())


def dominated(a: dict, b: dict) -> bool:
    """True when ``b`` is at least as good as ``a`` on every figure and better on one (all: lower is better)."""
    return all(b[k] <= a[k] for k in FIGURES) and any(b[k] < a[k] for k in FIGURES)


def run(out_dir, quick: bool = False) -> dict:
    from core.body import load_body
    from core.fileio import write_json, write_text
    from core.pattern.solve import SolverConfig

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    coarse = 0.02 if quick else None
    body = load_body("anny")
    configs = configurations(quick)
    rows = {}
    for garment, name in GARMENTS.items():
        cut, solver = _prepare(name, body, coarse)
        for label, (preset, overrides) in configs.items():
            config = SolverConfig.named(preset, **overrides)
            runs = []
            for rho in LEVELS:
                pattern, cpu = _solve(solver, cut, config, ease=rho)
                runs.append({**_figures(pattern), "rho": rho, "cpu_s": cpu})
            mean = {k: float(np.mean([r[k] for r in runs])) for k in FIGURES + ("warp_signed", "cpu_s")}
            mean.update(flips=int(sum(r["flips"] for r in runs)), collapsed=int(sum(r["collapsed"] for r in runs)))
            rows.setdefault(label, {"preset": preset, "overrides": overrides})[garment] = {"mean": mean, "levels": runs}
    # a configuration's point: the worse of the two garments on each figure (both tables must hold)
    for label, row in rows.items():
        row["point"] = {k: max(row[g]["mean"][k] for g in GARMENTS) for k in FIGURES}
        row["meets"] = bool(
            row["point"]["weft"] <= WEFT_GOAL
            and row["point"]["warp"] <= WARP_GOAL
            and all(row[g]["mean"]["flips"] == 0 and row[g]["mean"]["collapsed"] == 0 for g in GARMENTS)
        )
    for label, row in rows.items():
        row["frontier"] = not any(dominated(row["point"], other["point"]) for o, other in rows.items() if o != label)

    # what the configurations that meet both goals cost the other templates (design ease, M)
    meeting = [label for label, row in rows.items() if row["meets"] and row["frontier"]]
    meeting = ["improved (default)", "lengths"] + [
        l for l in sorted(meeting, key=lambda l: rows[l]["point"]["shear_p95"]) if l != "lengths"
    ][: 1 if quick else 2]
    templates = {}
    names = sorted(p.stem for p in DESIGNS.glob("*.json")) if not quick else ["skirt", "dress"]
    for name in names:
        try:
            cut, solver = _prepare(name, body, coarse)
        except Exception as exc:  # a template this body cannot make is listed, not fatal
            templates[name] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        for label in meeting:
            preset, overrides = configs[label]
            pattern, _ = _solve(solver, cut, SolverConfig.named(preset, **overrides))
            templates.setdefault(name, {})[label] = _figures(pattern)

    R = {
        "levels": list(LEVELS),
        "goals": {"weft": WEFT_GOAL, "warp": WARP_GOAL},
        "quick": quick,
        "configurations": rows,
        "templates": templates,
        "templates_configs": meeting,
        "wall_seconds": time.perf_counter() - t_start,
    }
    write_json(out / "frontier.json", R)
    write_text(out / "frontier.md", _markdown(R))
    _plot(R, out / "frontier.png")
    return R


def _markdown(R) -> str:
    rows = R["configurations"]
    L = [
        "# Weft / warp / shear frontier: shirt and pants",
        "",
        f"Body: `anny` (reference M, A-pose). Each garment at uniform ease {', '.join(f'{r:g}' for r in R['levels'])}; "
        "figures are means over the levels (SPEC metrics, docs/metrics.md: weft compliance %, mean |warp scale - 1| %, "
        "shear p95 deg, largest seam mismatch mm). 'feedback a / b': the weft / warp target feedback gains; 'warp slack': "
        "how far the local step may scale the rest shape's warp (0 keeps the design's lengths along the grain). "
        "A point is the worse garment on each figure; **frontier**: no other configuration is at least as good on all four "
        f"and better on one; **meets**: weft <= {R['goals']['weft']:g} % and warp <= {R['goals']['warp']:g} % on both, "
        "0 flipped, 0 collapsed. CPU s: mean per solve. Regenerate: `./ease.sh bench --only frontier`. "
        f"Wall time: {R['wall_seconds']:.0f} s.",
        "",
        "| configuration | shirt weft / warp (signed) / shear p95 / seam mm | pants weft / warp (signed) / shear p95 / seam mm "
        "| flips / collapsed | CPU s | frontier | meets |",
        "|---|---|---|---|---|---|---|",
    ]

    def cell(m):
        return (
            f"{m['weft']:.2f} / {m['warp']:.2f} ({m['warp_signed']:+.2f}) / {m['shear_p95']:.1f} / "
            f"{m['seam_max_mm']:.2f}"
        )

    order = sorted(rows, key=lambda l: (not rows[l]["meets"], not rows[l]["frontier"], rows[l]["point"]["shear_p95"]))
    for label in order:
        r = rows[label]
        s, p = r["shirt"]["mean"], r["pants"]["mean"]
        L.append(
            f"| {label} | {cell(s)} | {cell(p)} | {s['flips'] + p['flips']} / {s['collapsed'] + p['collapsed']} "
            f"| {(s['cpu_s'] + p['cpu_s']) / 2:.2f} | {'yes' if r['frontier'] else ''} | {'yes' if r['meets'] else ''} |"
        )
    L += [
        "",
        "## What the configurations cost the other templates (design ease, M)",
        "",
        "Weft % / warp % / shear p95 deg / largest seam mm; templates promise seams <= 3 mm.",
        "",
        "| template | " + " | ".join(R["templates_configs"]) + " |",
        "|---|" + "---|" * len(R["templates_configs"]),
    ]
    for name, t in sorted(R["templates"].items()):
        if "error" in t:
            L.append(f"| {name} | " + " | ".join([t["error"]] * len(R["templates_configs"])) + " |")
            continue
        L.append(
            f"| {name} | "
            + " | ".join(
                f"{t[c]['weft']:.2f} / {t[c]['warp']:.2f} / {t[c]['shear_p95']:.1f} / {t[c]['seam_max_mm']:.2f}"
                + (f" ({t[c]['flips']} flipped)" if t[c]["flips"] else "")
                + (f" ({t[c]['collapsed']} collapsed)" if t[c]["collapsed"] else "")
                for c in R["templates_configs"]
            )
            + " |"
        )
    return "\n".join(L) + "\n"


def _plot(R, path):
    import io

    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from core.fileio import write_bytes

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    rows = R["configurations"]
    pts = np.array([[r["point"]["weft"], r["point"]["warp"], r["point"]["shear_p95"]] for r in rows.values()])
    sc = ax.scatter(pts[:, 1], pts[:, 0], c=pts[:, 2], cmap="viridis", s=36)
    for (label, r), (w, wa, _) in zip(rows.items(), pts):
        if r["frontier"] and (r["meets"] or label == "improved (default)"):
            ax.annotate(label, (wa, w), fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.axhline(R["goals"]["weft"], color="grey", lw=0.8, ls="--")
    ax.axvline(R["goals"]["warp"], color="grey", lw=0.8, ls="--")
    ax.set_xlabel("warp deviation, worse garment (%)")
    ax.set_ylabel("weft compliance, worse garment (%)")
    fig.colorbar(sc, label="shear p95, worse garment (deg)")
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    write_bytes(path, buf.getvalue())


if __name__ == "__main__":
    import sys

    r = run(sys.argv[1] if len(sys.argv) > 1 else REPO / "benchmarks" / "results", quick="--quick" in sys.argv)
    print(json.dumps({k: v["point"] for k, v in r["configurations"].items()}, indent=1))
