"""Body benchmark: speed of shape and pose changes on the default body, and the size fits.

``run(out_dir)`` writes ``body.md`` and ``body.json``:

- shape change: wall time of ``body.vertices(new_shape, "A")`` with a shape
  never seen before (no cache), median of repeats, ms;
- pose change: ``body.vertices(same_shape, pose)`` cycling the five presets
  on an already evaluated shape, median, ms;
- size table: each chart size re-fitted with ``fit_measurements`` from the
  reference shape (parameters, achieved measurements, status, evaluations,
  seconds), and the stored chart shapes measured;
- charts: every size of the women's and men's charts, its stored Anny shape measured as a tailor
  measures (``core.body.tape``): each girth the chart gives and the height, with the error (cm;
  all within 1 cm), and the same body by the old chart definitions (``core.body.measure``);
- made-to-measure: ``made_to_measure`` sets of the 14 tape measures of hidden bodies of the
  population (``core.body.made_to_measure.sample_body``, seeded), each fitted with ``fit_tape``:
  the errors on girths and on lengths, how many land (girths 1 cm, lengths 1.5 cm), the fit time;
- scans: ``scans`` synthetic scans (``core.body.scan.synthetic_scan``: a hidden body of the
  population in a hidden pose, 20,000 points resampled on its triangles, 2 mm noise, four holes,
  no soles, turned and moved), each fitted by ``fit_scan``: the scan-to-body distance (mean, p95,
  max, mm), the fitted body's girth errors against the hidden body's, the scan's own girths'
  errors, the fit time.
"""

from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent


def _median_ms(fn, repeats):
    times = []
    for i in range(repeats):
        t0 = time.perf_counter()
        fn(i)
        times.append(1000.0 * (time.perf_counter() - t0))
    return float(np.median(times)), [round(t, 3) for t in times]


def charts_table(body) -> dict:
    """Every size of the published charts, its stored shape measured as a tailor measures
    (``core.body.tape``, the definitions the sizes are fitted by): {chart: {size: {measure:
    [target, measured, error, old]}}} (cm), ``old`` the same body's measure by the chart
    definitions the sizes were fitted by before (``core.body.measure``: girths at landmark heights)."""
    from core.body.charts import PUBLISHED
    from core.body.measure import measure
    from core.body.sizes import size_shape
    from core.body.tape import tape_measures

    out = {}
    for name, chart in PUBLISHED.items():
        out[name] = {}
        for size, targets in chart.sizes.items():
            shape = size_shape(body, size, chart=name)
            got = tape_measures(body, None, list(targets), shape=shape)
            old = measure(body, body.vertices(shape), list(targets))
            out[name][size] = {
                k: [v, round(got[k], 2), round(got[k] - v, 2), round(old[k], 2)] for k, v in targets.items()
            }
    return out


def made_to_measure(body, n: int, seed: int = 33) -> dict:
    """``n`` hidden bodies' tape measures fitted by ``fit_tape``: per set the errors (cm), time, evaluations."""
    from core.body.made_to_measure import LENGTHS, fit_tape, sample_body
    from core.body.tape import tape_measures

    rows = []
    for i in range(n):
        hidden = sample_body(np.random.default_rng([seed, i]))
        targets = tape_measures(body, shape=hidden)
        t = time.perf_counter()
        fit = fit_tape(body, {**targets, "gender": hidden["gender"]})
        rows.append(
            {
                "gender": hidden["gender"],
                "seconds": time.perf_counter() - t,
                "evaluations": fit.evaluations,
                "ok": fit.ok,
                "collisions": fit.collisions,
                "errors_cm": {k: round(e, 3) for k, e in fit.errors().items()},
            }
        )
    girth = [abs(e) for r in rows for k, e in r["errors_cm"].items() if k not in LENGTHS]
    length = [abs(e) for r in rows for k, e in r["errors_cm"].items() if k in LENGTHS]
    secs = [r["seconds"] for r in rows]
    return {
        "n": n,
        "seed": seed,
        "landed": sum(r["ok"] for r in rows),
        "girth_error_cm": {
            "mean": float(np.mean(girth)),
            "p95": float(np.percentile(girth, 95)),
            "max": float(np.max(girth)),
        },
        "length_error_cm": {
            "mean": float(np.mean(length)),
            "p95": float(np.percentile(length, 95)),
            "max": float(np.max(length)),
        },
        "fit_seconds": {"median": float(np.median(secs)), "max": float(np.max(secs))},
        "evaluations_median": float(np.median([r["evaluations"] for r in rows])),
        "rows": rows,
    }


def scan_fits(body, n: int, seed: int = 33, points: int = 20000) -> dict:
    """``n`` synthetic scans of hidden bodies fitted by ``fit_scan``: distances (mm), girth errors (cm), time."""
    from core.body.made_to_measure import LENGTHS, sample_body
    from core.body.scan import fit_scan, hidden_pose, synthetic_scan
    from core.body.tape import tape_measures

    rows = []
    for i in range(n):
        rng = np.random.default_rng([seed, 1000 + i])
        shape, pose = sample_body(rng), hidden_pose(rng)
        scan = synthetic_scan(body, shape, pose, rng, points=points)
        t = time.perf_counter()
        fit = fit_scan(body, scan)
        seconds = time.perf_counter() - t
        hidden = tape_measures(body, shape=shape)
        girths = [k for k in hidden if k not in LENGTHS]
        rows.append(
            {
                "gender": shape["gender"],
                "points": int(len(scan)),
                "seconds": seconds,
                "rounds": fit.rounds,
                "evaluations": fit.evaluations,
                "distance_mm": {k: round(v, 3) for k, v in fit.distance_mm.items()},
                "body_girth_error_cm": {k: round(fit.body_cm[k] - hidden[k], 3) for k in girths},
                "length_error_cm": {k: round(fit.body_cm[k] - hidden[k], 3) for k in LENGTHS},
                "scan_girth_error_cm": {
                    k: round(v - hidden[k], 3) for k, v in fit.scan_cm.items() if v is not None and k in girths
                },
            }
        )

    def stats(values):
        values = [abs(v) for v in values]
        return {"mean": float(np.mean(values)), "p95": float(np.percentile(values, 95)), "max": float(np.max(values))}

    return {
        "n": n,
        "seed": seed,
        "points": points,
        "distance_mean_mm": stats([r["distance_mm"]["mean"] for r in rows]),
        "distance_p95_mm": stats([r["distance_mm"]["p95"] for r in rows]),
        "body_girth_error_cm": stats([e for r in rows for e in r["body_girth_error_cm"].values()]),
        "length_error_cm": stats([e for r in rows for e in r["length_error_cm"].values()]),
        "scan_girth_error_cm": stats([e for r in rows for e in r["scan_girth_error_cm"].values()] or [float("nan")]),
        "within_targets": sum(
            r["distance_mm"]["mean"] <= 5.0 and all(abs(e) <= 1.5 for e in r["body_girth_error_cm"].values())
            for r in rows
        ),
        "fit_seconds": {
            "median": float(np.median([r["seconds"] for r in rows])),
            "max": max(r["seconds"] for r in rows),
        },
        "rows": rows,
    }


def run(out_dir, quick: bool = False) -> dict:
    from core.body import POSE_PRESETS, load_body
    from core.body.measure import MEASUREMENTS, measure
    from core.body.sizes import SIZE_CHART, SIZES, fit_measurements, size_shape
    from core.fileio import write_json, write_text

    out = Path(out_dir)
    repeats = 5 if quick else 15
    t0 = time.perf_counter()
    body = load_body("anny")
    load_s = time.perf_counter() - t0
    body.vertices()  # warm up imports and caches of the reference

    base = body.default_shape()
    fit_names = [n for n in ("weight", "height", "muscle", "proportions") if n in base] or list(base)[:1]

    def shape_change(i):
        s = dict(base)
        s[fit_names[0]] = float(np.clip(base[fit_names[0]] + 0.01 * (i + 1) * (-1) ** i, 0.0, 1.0))
        body.vertices(s, "A")

    shape_ms, shape_all = _median_ms(shape_change, repeats)
    body.vertices(base, "A")

    def pose_change(i):
        body.vertices(base, POSE_PRESETS[(i + 1) % len(POSE_PRESETS)])

    pose_ms, pose_all = _median_ms(pose_change, repeats)
    measure(body, body.vertices())  # first call builds the torso edge list once per model
    mt = time.perf_counter()
    ref = measure(body, body.vertices())
    measure_ms = 1000.0 * (time.perf_counter() - mt)

    sizes = {}
    for size in SIZES:
        t = time.perf_counter()
        fit = fit_measurements(body, SIZE_CHART[size])
        fit_s = time.perf_counter() - t
        stored = size_shape(body, size)
        sizes[size] = {
            "chart_cm": SIZE_CHART[size],
            "fit": {
                "shape": {k: round(v, 4) for k, v in fit.shape.items()},
                "achieved_cm": fit.achieved,
                "status": fit.status,
                "evaluations": fit.evaluations,
                "seconds": fit_s,
                "parameters": fit.parameters,
            },
            "stored_shape": stored,
            "stored_measured_cm": measure(body, body.vertices(stored)),
        }
        if quick and size == "S":
            break

    charts = charts_table(body)
    mtm = made_to_measure(body, 5 if quick else 50)
    scans = scan_fits(body, 2 if quick else 10)

    result = {
        "charts": charts,
        "made_to_measure": mtm,
        "scans": scans,
        "model": body.name,
        "n_vertices": body.n_vertices,
        "n_faces": int(len(body.faces)),
        "load_s": load_s,
        "shape_change_ms": shape_ms,
        "pose_change_ms": pose_ms,
        "measure_ms": measure_ms,
        "shape_change_samples_ms": shape_all,
        "pose_change_samples_ms": pose_all,
        "reference_measurements_cm": ref,
        "sizes": sizes,
        "machine": {"python": platform.python_version(), "cpu": platform.processor() or platform.machine()},
    }
    lines = [
        "# Body benchmark",
        "",
        f"Default body `{body.name}`: {body.n_vertices} vertices, {len(body.faces)} triangles. "
        f"Median of {repeats} runs on {platform.machine()}, Python {platform.python_version()}.",
        "",
        "| operation | time |",
        "|---|---|",
        f"| load model | {load_s * 1000:.0f} ms |",
        f"| shape change (new shape, A-pose) | {shape_ms:.1f} ms |",
        f"| pose change (same shape, preset) | {pose_ms:.1f} ms |",
        f"| measure height/chest/waist/hip | {measure_ms:.1f} ms |",
        "",
        "## Sizes",
        "",
        "Chart (cm) and the re-fit of each size from the reference shape "
        "(`fit_measurements`, bounded least squares on "
        + ", ".join(next(iter(sizes.values()))["fit"]["parameters"])
        + "). Status: within 1 cm of the target, "
        "or not reachable by this model.",
        "",
        "| size | " + " | ".join(f"{m} chart / fit" for m in MEASUREMENTS) + " | status | evals | fit s | shape |",
        "|---|" + "---|" * (len(MEASUREMENTS) + 4),
    ]
    for size, rec in sizes.items():
        f = rec["fit"]
        ok = (
            "all within 1 cm"
            if all(s == "within 1 cm" for s in f["status"].values())
            else "; ".join(f"{k}: {s}" for k, s in f["status"].items() if s != "within 1 cm")
        )
        cells = [f"{rec['chart_cm'][m]:.1f} / {f['achieved_cm'][m]:.1f}" for m in MEASUREMENTS]
        shape = ", ".join(f"{k}={v:.3f}" for k, v in rec["stored_shape"].items() if k in f["parameters"])
        lines.append(
            f"| {size} | " + " | ".join(cells) + f" | {ok} | {f['evaluations']} | {f['seconds']:.1f} | {shape} |"
        )
    lines += ["", "Reference (default shape) measured: " + ", ".join(f"{k} {v:.1f} cm" for k, v in ref.items()), ""]
    lines += [
        "## Published charts",
        "",
        "Each size's stored Anny shape (fitted by `sizes.chart_tape_fit`) measured as a tailor measures "
        "(`core.body.tape`, ISO 8559-1: bust at the bust points, natural waist, hip at the buttocks): "
        "target / measured (error), cm; in brackets after it, where it differs by 0.5 cm or more, the same "
        "body by the old chart definitions (`core.body.measure`, girths at landmark heights).",
        "",
    ]
    for name, table in charts.items():
        keys = list(next(iter(table.values())))
        lines += [f"**{name}**", "", "| size | " + " | ".join(keys) + " | worst |", "|---|" + "---|" * (len(keys) + 1)]
        for size, rec in table.items():
            worst = max(abs(v[2]) for v in rec.values())
            cells = " | ".join(
                f"{rec[k][0]:g} / {rec[k][1]:.1f} ({rec[k][2]:+.1f})"
                + (f" [old {rec[k][3]:.1f}]" if len(rec[k]) > 3 and abs(rec[k][3] - rec[k][1]) >= 0.5 else "")
                for k in keys
            )
            lines.append(f"| {size} | {cells} | {worst:.2f} |")
        lines.append("")
    g, ln, fs = mtm["girth_error_cm"], mtm["length_error_cm"], mtm["fit_seconds"]
    lines += [
        "## Made-to-measure",
        "",
        f"{mtm['n']} tape-measure sets (14 measures each, `core.body.tape`) of hidden bodies of the population "
        f"(`made_to_measure.sample_body`, seed {mtm['seed']}), fitted by `fit_tape`: "
        f"{mtm['landed']} of {mtm['n']} land (girths within 1 cm, lengths within 1.5 cm, "
        "no self-intersection).",
        "",
        "| | mean | p95 | max |",
        "|---|---|---|---|",
        f"| girth error (cm) | {g['mean']:.2f} | {g['p95']:.2f} | {g['max']:.2f} |",
        f"| length error (cm) | {ln['mean']:.2f} | {ln['p95']:.2f} | {ln['max']:.2f} |",
        f"| fit time (s) | median {fs['median']:.1f} | | {fs['max']:.1f} |",
        "",
        f"Median {mtm['evaluations_median']:.0f} body evaluations per fit.",
        "",
    ]
    sd, sp = scans["distance_mean_mm"], scans["distance_p95_mm"]
    bg, sl, sg, st = (
        scans["body_girth_error_cm"],
        scans["length_error_cm"],
        scans["scan_girth_error_cm"],
        scans["fit_seconds"],
    )
    lines += [
        "## Bodies from scans",
        "",
        f"{scans['n']} synthetic scans (`core.body.scan.synthetic_scan`, seed {scans['seed']}): a hidden body of "
        f"the population (shape and local changes, `sample_body`) in a hidden pose, {scans['points']} points "
        "drawn on its triangles, 2 mm noise, four holes of 4-7 cm, no soles, turned and moved; each fitted by "
        f"`fit_scan` (pose, shape, local changes; the fit on 4,000 of the points). {scans['within_targets']} of "
        f"{scans['n']} meet the targets (mean distance <= 5 mm, every girth within 1.5 cm of the hidden body's).",
        "",
        "| | mean | p95 | max |",
        "|---|---|---|---|",
        f"| scan-to-body distance, mean per scan (mm) | {sd['mean']:.2f} | {sd['p95']:.2f} | {sd['max']:.2f} |",
        f"| scan-to-body distance, p95 per scan (mm) | {sp['mean']:.2f} | {sp['p95']:.2f} | {sp['max']:.2f} |",
        f"| fitted body's girths vs hidden (cm) | {bg['mean']:.2f} | {bg['p95']:.2f} | {bg['max']:.2f} |",
        f"| fitted body's lengths vs hidden (cm) | {sl['mean']:.2f} | {sl['p95']:.2f} | {sl['max']:.2f} |",
        f"| the scan's own girths vs hidden (cm) | {sg['mean']:.2f} | {sg['p95']:.2f} | {sg['max']:.2f} |",
        f"| fit time (s) | median {st['median']:.1f} | | {st['max']:.1f} |",
        "",
        "| scan | gender | distance mean / p95 / max (mm) | worst girth error (cm) | rounds | s |",
        "|---|---|---|---|---|---|",
    ]
    for i, r in enumerate(scans["rows"]):
        d = r["distance_mm"]
        worst = max(r["body_girth_error_cm"].items(), key=lambda kv: abs(kv[1]))
        lines.append(
            f"| {i} | {r['gender']:g} | {d['mean']:.2f} / {d['p95']:.2f} / {d['max']:.1f} | "
            f"{worst[1]:+.2f} ({worst[0]}) | {r['rounds']} | {r['seconds']:.1f} |"
        )
    lines.append("")
    write_text(out / "body.md", "\n".join(lines))
    write_json(out / "body.json", result)
    return result


if __name__ == "__main__":
    import json

    res = run(Path(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results"))
    print(json.dumps({k: res[k] for k in ("shape_change_ms", "pose_change_ms", "measure_ms")}, indent=1))
