"""Body benchmark: speed of shape and pose changes on the default body, and the size fits.

``run(out_dir)`` writes ``body.md`` and ``body.json``:

- shape change: wall time of ``body.vertices(new_shape, "A")`` with a shape
  never seen before (no cache), median of repeats, ms;
- pose change: ``body.vertices(same_shape, pose)`` cycling the five presets
  on an already evaluated shape, median, ms;
- size table: each chart size re-fitted with ``fit_measurements`` from the
  reference shape (parameters, achieved measurements, status, evaluations,
  seconds), and the stored chart shapes measured;
- charts: every size of the women's and men's charts, its stored Anny shape measured: each
  girth the chart gives and the height, with the error (cm; all within 1 cm);
- made-to-measure: ``made_to_measure`` sets of the 14 tape measures of hidden bodies of the
  population (``core.body.made_to_measure.sample_body``, seeded), each fitted with ``fit_tape``:
  the errors on girths and on lengths, how many land (girths 1 cm, lengths 1.5 cm), the fit time.
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
    """Every size of the published charts, its stored shape measured: {chart: {size: {measure:
    [target, measured, error]}}} (cm)."""
    from core.body.charts import PUBLISHED
    from core.body.measure import measure
    from core.body.sizes import size_shape

    out = {}
    for name, chart in PUBLISHED.items():
        out[name] = {}
        for size, targets in chart.sizes.items():
            got = measure(body, body.vertices(size_shape(body, size, chart=name)))
            out[name][size] = {k: [v, round(got[k], 2), round(got[k] - v, 2)] for k, v in targets.items()}
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

    result = {
        "charts": charts,
        "made_to_measure": mtm,
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
        "Each size's stored Anny shape measured (chart measures, `core.body.measure`): target / "
        "measured (error), cm. Sizes beyond the phenotypes' reach carry Anny's local changes.",
        "",
    ]
    for name, table in charts.items():
        keys = list(next(iter(table.values())))
        lines += [f"**{name}**", "", "| size | " + " | ".join(keys) + " | worst |", "|---|" + "---|" * (len(keys) + 1)]
        for size, rec in table.items():
            worst = max(abs(v[2]) for v in rec.values())
            cells = " | ".join(f"{rec[k][0]:g} / {rec[k][1]:.1f} ({rec[k][2]:+.1f})" for k in keys)
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
    write_text(out / "body.md", "\n".join(lines))
    write_json(out / "body.json", result)
    return result


if __name__ == "__main__":
    import json

    res = run(Path(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results"))
    print(json.dumps({k: res[k] for k in ("shape_change_ms", "pose_change_ms", "measure_ms")}, indent=1))
