"""Pleats benchmark (issue 37): every pleated template at sizes XS..XL, solved closed, opened, draped.

``run(out_dir)`` writes ``pleats.md`` and ``pleats.json``. Per template (``skirt_knife_pleats``,
``skirt_box_pleats``, ``shirt_box_pleat``) and size (the reference on M, transferred to the
others with the template's own solver configuration):

- the pleats' depth as opened: the largest difference from the set depth over every fold and
  placement line (mm; target <= 0.1);
- the closed pattern (the cloth as worn): flipped, collapsed, crossings (target 0 each) and the
  ease compliance, mean % (target <= 1.2);
- the pleats' cloth: intake and area beside the pattern's (m^2);
- the drape of the opened pattern (pre-folded, pressed creases held, :data:`DRAPE` frames, CPU):
  body penetration % (target 0), whether it settled, wall seconds, and how closed the pleats
  stay: the distance between each pleat's visible fold and its placement line after the drape
  (mm, median and p95 over the line's vertices; 0 is a pleat lying closed as pressed, 2 x depth
  one opened flat).

``quick``: size M only.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

TEMPLATES = ("skirt_knife_pleats", "skirt_box_pleats", "shirt_box_pleat")
SIZES = ("XS", "S", "M", "L", "XL")
#: the drape's options: the fabric has grown to its pattern size by frame 20 (grow_frames)
DRAPE = {"max_frames": 90}  # the pleated skirts settle at 50-51 frames (measured with 90)
TARGETS = {"depth_error_mm": 0.1, "compliance_pct": 1.2, "penetration_pct": 0.0}


def pleat_closure(pattern, positions) -> dict:
    """Per pleat of ``pattern``: the distances (m) after a drape between its visible fold (its first
    fold line) and its placement line, vertex by vertex along them; ``positions`` by global id."""
    from core.pattern.pleats import open_pattern

    opened = open_pattern(pattern)
    out = {}
    for lines in opened.report["opened_pleats"].values():
        by_strip = {}
        for x in lines:
            by_strip.setdefault((x["pleat"], x["strip"]), []).append(x)
        for (name, _), xs in by_strip.items():
            fold = next(x for x in xs if x["kind"] == "fold")
            place = next(x for x in xs if x["kind"] == "placement")
            d = np.linalg.norm(positions[fold["gids"]] - positions[place["gids"]], axis=1)
            out.setdefault(name, []).extend(d.tolist())
    return out


def _case(workflows, prep, solver, ref, size):
    t0 = time.perf_counter()
    run = workflows.reference(prep, solver=solver) if size == "M" else None
    if run is None:
        run = workflows.transfer(prep, size, solver=solver, start=ref)
    pattern = run.pattern
    solve_s = time.perf_counter() - t0
    m = pattern.report["metrics"]
    pleats = pattern.report["pleats"]
    row = {
        "size": size,
        "solve_s": round(solve_s, 2),
        "pleats": len(pleats),
        "depth_mm": sorted({p["depth_mm"] for p in pleats}),
        "depth_error_mm": max(p["depth_error_mm"] for p in pleats),
        "intake_mm": sum(p["intake_mm"] for p in pleats),
        "extra_cloth_m2": round(sum(p["extra_cloth_m2"] for p in pleats), 5),
        "flipped": int(run.figures.get("flipped", 0)),
        "collapsed": int(run.figures.get("collapsed", 0)),
        "crossings": int(run.figures.get("crossings", 0)),
        "compliance_pct": round(float(m["compliance"]["mean"]), 3),
    }
    t0 = time.perf_counter()
    d = workflows.drape(pattern, options=DRAPE)
    row["drape_s"] = round(time.perf_counter() - t0, 1)
    row["penetration_pct"] = float(d.figures.get("penetration %", np.nan))
    row["settled"] = str(d.figures.get("settled"))
    row["solver"] = str((getattr(d.result, "options", None) or {}).get("solver", ""))
    closure = np.concatenate([np.asarray(v) for v in pleat_closure(pattern, np.asarray(d.result.positions)).values()])
    row["closure_median_mm"] = round(1000 * float(np.median(closure)), 2)
    row["closure_p95_mm"] = round(1000 * float(np.percentile(closure, 95)), 2)
    return row, pattern


def run(out_dir, quick: bool = False) -> dict:
    from core import workflows
    from core.design.templates import template_path
    from core.fileio import write_json, write_text

    out_dir = Path(out_dir)
    sizes = ("M",) if quick else SIZES
    load = [os.getloadavg()[0]]
    results = {"drape": DRAPE, "targets": TARGETS, "templates": {}}
    for name in TEMPLATES:
        prep = workflows.prepare(template_path(name))
        solver = workflows.make_solver(prep)
        ref = workflows.reference(prep, solver=solver).pattern
        rows = []
        for size in sizes:
            row, _ = _case(workflows, prep, solver, ref, size)
            rows.append(row)
            print(f"[pleats] {name} {size}: {row}", flush=True)
        results["templates"][name] = {"config": workflows.config_name(prep), "rows": rows}
    load.append(os.getloadavg()[0])
    results["load_average_1min"] = {"before": load[0], "after": load[1], "cores": os.cpu_count()}

    solvers = ", ".join(sorted({r["solver"] for rec in results["templates"].values() for r in rec["rows"]}))
    md = [
        "# Pleats: every pleated template at XS..XL",
        "",
        "`ease bench --only pleats` (`benchmarks/bench_pleats.py`, issue 37). The pattern is solved closed "
        "(the cloth as worn), each pleat opened as a strip of 2 x depth (knife) or 4 x depth (box) along its "
        "line; the drape is of the opened pattern, pre-folded, pressed creases held, "
        f"{DRAPE['max_frames']} frames on the CPU (solver {solvers}). Targets: depth within {TARGETS['depth_error_mm']} mm, "
        f"0 flipped / collapsed / crossings, closed compliance <= {TARGETS['compliance_pct']} %, "
        "0 % body penetration. Closure: the distance between each pleat's visible fold and its placement "
        "line after the drape (0: closed as pressed; 2 x depth: opened flat).",
        "",
        f"Load average (1 min) {load[0]:.1f} before, {load[1]:.1f} after, on {os.cpu_count()} cores: "
        "wall times are of a shared machine.",
        "",
    ]
    for name, rec in results["templates"].items():
        md += [
            f"## {name} (solver `{rec['config']}`)",
            "",
            "| size | pleats | depth mm | depth error mm | intake mm | extra cloth m^2 | flipped | collapsed "
            "| crossings | compliance % | penetration % | settled | closure median / p95 mm | solve s | drape s |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in rec["rows"]:
            md.append(
                f"| {r['size']} | {r['pleats']} | {', '.join(f'{x:g}' for x in r['depth_mm'])} | "
                f"{r['depth_error_mm']:g} | {r['intake_mm']:g} | {r['extra_cloth_m2']:g} | {r['flipped']} | "
                f"{r['collapsed']} | {r['crossings']} | {r['compliance_pct']:.2f} | {r['penetration_pct']:g} | "
                f"{r['settled']} | {r['closure_median_mm']:g} / {r['closure_p95_mm']:g} | {r['solve_s']:g} | "
                f"{r['drape_s']:g} |"
            )
        md.append("")
    write_text(out_dir / "pleats.md", "\n".join(md))
    write_json(out_dir / "pleats.json", results)
    return results
