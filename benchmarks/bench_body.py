"""Body benchmark: speed of shape and pose changes on the default body, and the size fits.

``run(out_dir)`` writes ``body.md`` and ``body.json``:

- shape change: wall time of ``body.vertices(new_shape, "A")`` with a shape
  never seen before (no cache), median of repeats, ms;
- pose change: ``body.vertices(same_shape, pose)`` cycling the five presets
  on an already evaluated shape, median, ms;
- size table: each chart size re-fitted with ``fit_measurements`` from the
  reference shape (parameters, achieved measurements, status, evaluations,
  seconds), and the stored chart shapes measured.
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
            "fit": {"shape": {k: round(v, 4) for k, v in fit.shape.items()}, "achieved_cm": fit.achieved,
                    "status": fit.status, "evaluations": fit.evaluations, "seconds": fit_s,
                    "parameters": fit.parameters},
            "stored_shape": stored,
            "stored_measured_cm": measure(body, body.vertices(stored)),
        }
        if quick and size == "S":
            break

    result = {
        "model": body.name, "n_vertices": body.n_vertices, "n_faces": int(len(body.faces)),
        "load_s": load_s, "shape_change_ms": shape_ms, "pose_change_ms": pose_ms, "measure_ms": measure_ms,
        "shape_change_samples_ms": shape_all, "pose_change_samples_ms": pose_all,
        "reference_measurements_cm": ref, "sizes": sizes,
        "machine": {"python": platform.python_version(), "cpu": platform.processor() or platform.machine()},
    }
    lines = [
        "# Body benchmark", "",
        f"Default body `{body.name}`: {body.n_vertices} vertices, {len(body.faces)} triangles. "
        f"Median of {repeats} runs on {platform.machine()}, Python {platform.python_version()}.", "",
        "| operation | time |", "|---|---|",
        f"| load model | {load_s * 1000:.0f} ms |",
        f"| shape change (new shape, A-pose) | {shape_ms:.1f} ms |",
        f"| pose change (same shape, preset) | {pose_ms:.1f} ms |",
        f"| measure height/chest/waist/hip | {measure_ms:.1f} ms |", "",
        "## Sizes", "",
        "Chart (cm) and the re-fit of each size from the reference shape "
        "(`fit_measurements`, bounded least squares on " + ", ".join(
            next(iter(sizes.values()))["fit"]["parameters"]) + "). Status: within 1 cm of the target, "
        "or not reachable by this model.", "",
        "| size | " + " | ".join(f"{m} chart / fit" for m in MEASUREMENTS) + " | status | evals | fit s | shape |",
        "|---|" + "---|" * (len(MEASUREMENTS) + 4),
    ]
    for size, rec in sizes.items():
        f = rec["fit"]
        ok = "all within 1 cm" if all(s == "within 1 cm" for s in f["status"].values()) else \
            "; ".join(f"{k}: {s}" for k, s in f["status"].items() if s != "within 1 cm")
        cells = [f"{rec['chart_cm'][m]:.1f} / {f['achieved_cm'][m]:.1f}" for m in MEASUREMENTS]
        shape = ", ".join(f"{k}={v:.3f}" for k, v in rec["stored_shape"].items() if k in f["parameters"])
        lines.append(f"| {size} | " + " | ".join(cells) + f" | {ok} | {f['evaluations']} | {f['seconds']:.1f} | {shape} |")
    lines += ["", "Reference (default shape) measured: " +
              ", ".join(f"{k} {v:.1f} cm" for k, v in ref.items()), ""]
    write_text(out / "body.md", "\n".join(lines))
    write_json(out / "body.json", result)
    return result


if __name__ == "__main__":
    import json
    res = run(Path(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results"))
    print(json.dumps({k: res[k] for k in ("shape_change_ms", "pose_change_ms", "measure_ms")}, indent=1))
