"""pd's strain limit (``DrapeOptions.strain_limit``) on and off: ``python -m benchmarks.measure_strain_limit
STAGE [--limits 0,30] [--levels 0,1] [--out FILE.json]`` (benchmarks/results/drape_strain_limit.md).

* ``sheet``: hanging cotton (30 x 50 cm, 2 cm edges, no tethers, 3 substeps; the textile test's sheet)
  and the 1.5 cm shirt at ease 1.2 (``bench_drape``'s pattern, 60 frames): a hash of the final positions,
  the strains and the report's ``stretch_limit``; the shirt's largest move between the first and the last
  of ``--limits``. ``default`` in ``--limits`` passes no ``strain_limit`` (for a checkout without it).
* ``soft``: a cotton sheet made soft in its grain (2 N/m; 10 x 20 cm at 2 cm edges), which hangs 12 %
  stretched: its warp stretch with each limit.
* ``pants``: the pants at uniform ease ``LEVELS[i]`` (``--levels``) in cotton, ``bench_drape``'s gap-curve
  drape (1.5 cm, self-collision, settle speed 4 mm/s, 250 frames, growth over 20 frames): strain p95 and
  max, penetration, gap mean (SPEC items 6 and 7), frames, time, the report's ``stretch_limit``.
* ``cusick``: the Cusick cotton specimen (seed 0, 10 mm, pd): its drape coefficient.

Each row records the load average (1, 5, 15 min) before and after it.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time

import numpy as np


def _load() -> list:
    return list(os.getloadavg())


def _hash(x) -> str:
    return hashlib.sha256(np.ascontiguousarray(x, dtype=np.float64).tobytes()).hexdigest()[:16]


def _limit(options: dict, limit) -> dict:
    return options if limit == "default" else {**options, "strain_limit": limit}


def hanging(limit, width=0.3, height=0.5, edge=0.02, frames=40) -> tuple:
    """(final positions, figures) of hanging cotton, as :func:`core.drape.textile.hanging_sheet`."""
    from core.drape import textile as T
    from core.drape.materials import get_material
    from core.drape.mesh import build_cloth
    from core.drape.options import DrapeOptions
    from core.drape.strain import face_strains
    from core.drape.xpbd import DrapeSolver

    mat = get_material("cotton")
    opts = DrapeOptions.coerce(_limit({"solver": "pd", "substeps": 3, "tether_slack": None, "grow_frames": 0}, limit))
    uv, faces = T.strip_mesh([-height, 0.0], width, edge)
    uv = np.column_stack([uv[:, 1], uv[:, 0]])
    faces = faces[:, [0, 2, 1]]
    pattern = T.sheet_pattern(uv, faces, 0.0, uv[:, 1] >= -1e-9, mat.name)
    pattern.panels[0].xyz = np.column_stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]])
    cloth = build_cloth(pattern)
    bv, bf = T.box_body((-0.05, 0.5, -0.05), (0.05, 0.6, 0.05))
    solver = DrapeSolver(cloth, bv, bf, mat, opts)
    state = solver.state()
    st = T.settle(solver, state, frames)
    x = state.x64 if state.x64 is not None else state.x.numpy().astype(float)
    _, warp, _ = face_strains(x, cloth)
    return x, {
        "frames": st.frames,
        "settled": st.settled,
        "warp_p95_pct": float(np.percentile(warp, 95) * 100),
        "warp_max_pct": float(warp.max() * 100),
        "limited": getattr(solver._implicit, "limited", None),
        "refactors": solver._implicit.refactors,
    }


def sheet(limits) -> dict:
    from benchmarks.bench_drape import GAP_EDGE, load_cut, pattern_at
    from core.body import load_body
    from core.drape import drape

    rows = {"load": [_load()]}
    for lim in limits:
        x, info = hanging(lim)
        rows[f"sheet limit={lim}"] = {"hash": _hash(x), **info}
    body = load_body("anny")
    cut, ref = load_cut("shirt_long_sleeve", GAP_EDGE, body)
    pat = pattern_at(cut, ref, 1.2, "shirt")
    xs = {}
    for lim in limits:
        t0 = time.perf_counter()
        r = drape(pat, ref, body.faces, options=_limit({"max_frames": 60}, lim))
        xs[lim] = r.positions
        rows[f"shirt limit={lim}"] = {
            "hash": _hash(r.positions),
            "frames": r.frames,
            "settled": r.settled,
            "seconds": time.perf_counter() - t0,
            "weft_p95_pct": float(np.percentile(r.face_strain_weft, 95) * 100),
            "warp_p95_pct": float(np.percentile(r.face_strain_warp, 95) * 100),
            "weft_max_pct": float(r.face_strain_weft.max() * 100),
            "warp_max_pct": float(r.face_strain_warp.max() * 100),
            "stretch_limit": (getattr(r, "stretch_limit", None) or {}).get("all"),
        }
    if len(limits) > 1:
        rows["shirt_max_abs_dx_m"] = float(np.abs(xs[limits[0]] - xs[limits[-1]]).max())
    rows["load"].append(_load())
    return rows


def soft(limits) -> list:
    from core.drape import textile as T

    mat = {"fabric": "cotton", "stretch_weft": 2.0, "stretch_warp": 2.0}
    rows = []
    for lim in limits:
        load = _load()
        r = T.hanging_sheet(mat, width=0.1, height=0.2, edge=0.02, options=_limit({"solver": "pd"}, lim), max_frames=60)
        keys = ("warp_p50_pct", "warp_p95_pct", "warp_max_pct", "expected_pct", "frames", "settled")
        rows.append({"strain_limit": lim, **{k: r[k] for k in keys}, "load": [load, _load()]})
    return rows


def pants(levels, limits, grow: int = 20) -> list:
    from benchmarks.bench_drape import GAP_EDGE, GAP_MAX_FRAMES, LEVELS, load_cut, pattern_at
    from core.body import load_body
    from core.drape import drape
    from core.metrics.drape import drape_metrics, summary

    body = load_body("anny")
    cut, ref = load_cut("pants", GAP_EDGE, body)
    rows = []
    for i in levels:
        ease = float(LEVELS[i])
        pat = pattern_at(cut, ref, ease, "pants")
        for lim in limits:
            load, t0 = _load(), time.perf_counter()
            opts = {"max_frames": GAP_MAX_FRAMES, "settle_speed": 0.004, "self_collision": True, "grow_frames": grow}
            r = drape(pat, ref, body.faces, material="cotton", options=_limit(opts, lim))
            m = summary(drape_metrics(r, ref, body.faces, pattern=pat))["all"]
            rows.append(
                {
                    "ease": ease,
                    "strain_limit": lim,
                    "hash": _hash(r.positions),
                    "frames": r.frames,
                    "settled": r.settled,
                    "seconds": time.perf_counter() - t0,
                    "simulate_s": r.timings.get("simulate"),
                    "weft_p95_pct": m["strain_weft_pct"]["p95"],
                    "weft_max_pct": m["strain_weft_pct"]["max"],
                    "warp_p95_pct": m["strain_warp_pct"]["p95"],
                    "warp_max_pct": m["strain_warp_pct"]["max"],
                    "penetration_pct": m["penetration_pct"],
                    "gap_mean_mm": m["gap_mm"]["mean"],
                    "gap_std_mm": m["gap_mm"]["std"],
                    "seam_gap_max_mm": m["seam_gap_mm"]["max"],
                    "stretch_limit": (getattr(r, "stretch_limit", None) or {}).get("all"),
                    "load": [load, _load()],
                }
            )
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    return rows


def cusick(limits) -> list:
    from core.drape import textile as T

    rows = []
    for lim in limits:
        load = _load()
        c = T.cusick("cotton", 0.01, _limit({"solver": "pd"}, lim), 400, 0, True)
        keys = ("dc_pct", "nodes", "frames", "settled", "seconds")
        rows.append({"strain_limit": lim, **{k: c[k] for k in keys}, "load": [load, _load()]})
    return rows


def _limits(text: str) -> list:
    return [v if v == "default" else float(v) for v in text.split(",")]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("stage", choices=("sheet", "soft", "pants", "cusick"))
    ap.add_argument("--limits", default="0,30", help="strain_limit values (comma-separated; 'default': none passed)")
    ap.add_argument("--levels", default="0,1", help="pants: indices into bench_drape.LEVELS")
    ap.add_argument("--out", help="write the rows to this JSON file")
    a = ap.parse_args()
    limits = _limits(a.limits)
    if a.stage == "pants":
        res = pants([int(v) for v in a.levels.split(",")], limits)
    else:
        res = {"sheet": sheet, "soft": soft, "cusick": cusick}[a.stage](limits)
    text = json.dumps(res, indent=1)
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    else:
        print(text)
