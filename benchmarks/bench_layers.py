"""Layers benchmark (issue 37): garments draped one over another, inner first.

``run(out_dir)`` writes ``layers.md`` and ``layers.json``. Outfits (templates on the default body,
size M, pose A): a long-sleeve shirt tucked into pants, the shirt worn over the pants, a short-sleeve
top over a skirt, a jacket over the shirt. Each garment is patterned on the body and draped
(:func:`core.workflows.drape_outfit`, the default solver on the CPU, :data:`DRAPE`) against the body plus the
layers under it. Per outfit, for the outer garment(s):

- inter-layer penetration: the share of the outer garment's vertices over the inner one (within
  5 cm of it, not past its open edges) that lie more than 2 mm inside it, the largest over every
  frame after the fabric's growth, the settled (still) frames among them (target <= 0.5 %);
- the gap between the layers over those vertices (signed distance to the inner garment along its
  normals, mm: mean, p95);
- wall time per frame of the layered drape beside the same garment draped alone on the body (the
  per-frame penetration measure left out);
- for a tucked shirt: its hem's vertices inside the pants (or less than 2 mm out).

Every outer garment is patterned over the inner one twice (:data:`OVERS`): over its skintight
surface (the default) and over its draped surface (``--over draped``), with its pattern's ease
compliance and, cut over the draped surface, the offset it moved out by.

Every garment is cut at :data:`EDGE` mean edge (``python benchmarks/bench_layers.py --edge 0.02``:
another). ``quick``: the tucked outfit only, skintight only.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

OUTFITS = {
    "shirt tucked in pants": [{"design": "shirt_long_sleeve", "tucked": True}, {"design": "pants"}],
    "shirt over pants": [{"design": "pants"}, {"design": "shirt_long_sleeve"}],
    "top over skirt": [{"design": "skirt"}, {"design": "top_short_sleeve"}],
    "jacket over shirt": [{"design": "shirt_long_sleeve"}, {"design": "jacket"}],
}
#: every garment's drape (the fabric has grown to its pattern size by frame 20)
DRAPE = {"max_frames": 90}
#: the garments' mean edge length (m): the templates' own 1 cm
EDGE = 0.01
#: the surfaces an outer garment's pattern is solved over (:func:`core.workflows.drape_outfit`'s ``over``)
OVERS = ("skintight", "draped")
TARGETS = {"penetration_pct": 0.5}


def _alone(lr, options) -> dict:
    """The layer's own pattern draped alone on the body: its wall time per frame."""
    from core import workflows

    run = workflows.drape(lr.pattern.pattern, options=options)
    r = run.result
    return {"frames": int(r.frames), "time_per_frame_s": float(r.timings["simulate"]) / max(int(r.frames), 1)}


def _case(name, layers, edge, over="skintight") -> dict:
    from core import workflows

    t0 = time.perf_counter()
    run = workflows.drape_outfit(
        {"format": "ease-outfit", "version": 1, "name": name, "layers": layers},
        options=DRAPE,
        refine_edge_length=edge,
        over=over,
    )
    wall = time.perf_counter() - t0
    rows = []
    for i, lr in enumerate(run.layers):
        r = lr.drape.result
        row = {
            "layer": lr.layer.name,
            "frames": int(r.frames),
            "settled": r.settle_reason,
            "triangles": int(len(r.faces)),
            "time_per_frame_s": lr.time_per_frame,
            "body_penetration_pct": float(lr.drape.metrics["all"]["penetration_pct"]),
        }
        if i:
            ((inner, m),) = list(lr.over.items())[-1:]
            settled = [p for (_, still, p) in lr.frame_penetration_pct if still > 0]
            row.update(
                over=inner,
                overlap_vertices=m["overlap"],
                penetration_pct_final=m["penetration_pct"],
                penetration_pct_max_after_growth=max((p for _, _, p in lr.frame_penetration_pct), default=0.0),
                penetration_pct_max_settled=max(settled) if settled else None,
                settled_frames=len(settled),
                gap_mm_mean=m["gap_mm"]["mean"],
                gap_mm_p95=m["gap_mm"]["p95"],
                measured_on=lr.measured_on,
                compliance_pct=float(lr.pattern.pattern.report["metrics"]["compliance"]["mean"]),
                alone=_alone(lr, DRAPE) if over == "skintight" else None,
            )
        if lr.tucked:
            row["tucked_hem"] = lr.tucked
        rows.append(row)
    return {"outfit": name, "over": over, "wall_s": wall, "layers": rows}


def _md(results, edge) -> str:
    from core.drape import DrapeOptions

    lines = [
        "# Layers (issue 37): garments draped one over another",
        "",
        f"Templates on the default body (M, pose A), every garment cut at {edge * 100:g} cm mean edge, "
        f"the default drape solver ({DrapeOptions().solver}) on the CPU, frame limit {DRAPE['max_frames']}; inner garment draped first, the outer against "
        "the body + the inner garment's draped surface offset by its thickness. The outer garment's pattern "
        "is solved over the inner one's skintight surface (default) or its draped surface (`--over draped`; "
        "offset: how far its own vertices moved out, mean / p95, on the share of them that moved). "
        "Penetration: share of the outer garment's vertices over the inner one more than 2 mm inside it, "
        "inside told by the inner garment's skin closed with the body (target <= "
        f"{TARGETS['penetration_pct']} % at every settled frame). Compliance: the outer pattern's ease "
        "compliance (mean %). Regenerate: "
        + ("`ease bench --only layers`." if edge == EDGE else f"`python benchmarks/bench_layers.py --edge {edge:g}`."),
        "",
        "| outfit | cut over | outer | inner | frames (settled?) | penetration % settled max / final "
        "| gap mm mean / p95 | s/frame layered | s/frame alone | compliance % | offset mm | triangles |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for res in results:
        for row in res["layers"][1:]:
            sm = row["penetration_pct_max_settled"]
            on = row["measured_on"]
            offset = (
                f"{on['offset_mm']:.1f} / {on['offset_p95_mm']:.1f} on {on['covered_pct']:.0f} %"
                if "offset_p95_mm" in on
                else f"{on.get('offset_mm', 0.0):.0f}"
            )
            alone = f"{row['alone']['time_per_frame_s']:.3f}" if row["alone"] else "-"
            lines.append(
                f"| {res['outfit']} | {res['over']} | {row['layer']} | {row['over']} | {row['frames']} "
                f"({row['settled']}) | {'-' if sm is None else f'{sm:.2f}'} / {row['penetration_pct_final']:.2f} | "
                f"{row['gap_mm_mean']:.1f} / {row['gap_mm_p95']:.1f} | {row['time_per_frame_s']:.3f} | "
                f"{alone} | {row['compliance_pct']:.2f} | {offset} | {row['triangles']} |"
            )
    lines += ["", "Tucked hems (the shirt's longest open loop, over the pants):", ""]
    for res in results:
        for row in res["layers"]:
            h = row.get("tucked_hem")
            if h:
                lines.append(
                    f"- {res['outfit']} (cut over {res['over']}): {h['inside']} of {h['edge_vertices']} hem "
                    f"vertices inside {h['under']} ({h['inside_pct']:.1f} %), the farthest out "
                    f"{h['most_outside_mm']:.1f} mm; the hem's top {h['below_waistband_mm']:.0f} mm below the "
                    "pants' top"
                )
    lines += [
        "",
        "Inner garments (draped on the body alone): "
        + "; ".join(
            f"{res['layers'][0]['layer']} in {res['outfit']}: {res['layers'][0]['frames']} frames "
            f"({res['layers'][0]['settled']}), {res['layers'][0]['time_per_frame_s']:.3f} s/frame"
            for res in results
            if res["over"] == OVERS[0]
        ),
        "",
        f"CPU: {os.cpu_count()} cores, shared; wall seconds per outfit: "
        + ", ".join(f"{r['outfit']} ({r['over']}) {r['wall_s']:.0f}" for r in results),
        "",
    ]
    return "\n".join(lines)


def run(out_dir, quick: bool = False, edge: float = EDGE) -> dict:
    out = Path(out_dir)
    names = ["shirt tucked in pants"] if quick else list(OUTFITS)
    overs = OVERS[:1] if quick else OVERS
    results = [_case(n, OUTFITS[n], edge, over) for over in overs for n in names]
    (out / "layers.json").write_text(json.dumps({"edge": edge, "drape": DRAPE, "results": results}, indent=1))
    (out / "layers.md").write_text(_md(results, edge))
    return {"results": results}


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--edge", type=float, default=EDGE)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    a = ap.parse_args()
    run(Path(a.out), quick=a.quick, edge=a.edge)
