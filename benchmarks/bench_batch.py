"""Batch benchmark: ``ease batch`` throughput, scaling and cluster equivalence on the shirt.

``run(out_dir, quick=False)`` writes ``batch.md`` and ``batch.json``:

- throughput: the long-sleeve shirt over sampled Anny bodies, pattern only
  (pattern.json + report.json + body.json per item, no preview), on 1 and on
  2 local workers, in :data:`PAIRS` pairs of runs taken in turn (1, 2, 1, 2
  workers: a slow minute of the shared host falls on one run, not on one
  worker count). The steady rate is items per second between the first and
  the last completed item (the cluster start and each worker's one-off cut
  of the design excluded; they are listed apart); per core = rate / workers.
  :data:`BODIES` bodies a run: the items vary 3x in time, and at a run's end
  one worker may wait for the other's last item, which 60 bodies let weigh
  up to ~5 % of a 2-worker run.
  Per-item split (median over items, ms): body (shape + girths), transfer
  (the solve), metrics (compliance, seams), write, and the worker's CPU time
  per item. The CPU-time rate (1 / median CPU seconds of an item, the items
  that paid for their worker's cut left out) is the throughput per core that
  does not depend on what else the machine runs; the load average is
  recorded beside it;
- speed-up: the 2-worker steady rate over the 1-worker one, pooled over the
  pairs (items over steady seconds), and each pair's own;
- simulated cluster: a ``dask scheduler`` and two ``dask worker`` processes
  started on localhost, the same bodies (same seed) through ``--scheduler``;
  its manifest is compared with the LocalCluster's, timings and worker ids
  left out;
- population (not with ``quick``): 1,000 sampled bodies on 2 workers, every
  failure listed with its reason.

The datasets are written to a temporary folder and removed.
"""

from __future__ import annotations

import os
import platform
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Optional

import numpy as np

REPO = Path(__file__).resolve().parent.parent

DESIGN = "shirt_long_sleeve"

#: core.batch.run.WORKER_CONFIG as a Dask config file for workers started by hand.
WORKER_YAML = (
    "distributed:\n  nanny:\n    pre-spawn-environ:\n      MALLOC_TRIM_THRESHOLD_: null\n"
    "  worker:\n    profile:\n      enabled: false\n    memory:\n      monitor-interval: 1s\n"
    "  admin:\n    tick:\n      interval: 1s\n    system-monitor:\n      interval: 5s\n"
)
SEED = 2024
#: bodies of each throughput run (quick: 16), and pairs of 1- and 2-worker runs (quick: 1)
BODIES = 150
PAIRS = 2


def _cpu_ticks() -> Optional[np.ndarray]:
    """The machine's CPU time so far by state (user, nice, system, idle, iowait, irq, softirq, steal; Linux's
    /proc/stat), or None elsewhere."""
    try:
        with open("/proc/stat") as f:
            return np.array([float(x) for x in f.readline().split()[1:9]])
    except (OSError, ValueError):
        return None


def _shares(a, b) -> dict:
    """Percent of the machine's CPU time from ticks ``a`` to ``b`` (:func:`_cpu_ticks`) spent busy, idle, waiting
    for the disk and stolen by the host: what a wall-clock rate cannot tell from the code's speed."""
    if a is None or b is None or len(a) < 8 or len(b) < 8 or not (b - a).sum() > 0:
        return {}
    d = b - a
    pct = 100.0 * d / d.sum()
    return {
        "busy_pct": round(float(pct[[0, 1, 2, 5, 6]].sum()), 1),
        "idle_pct": round(float(pct[3]), 1),
        "iowait_pct": round(float(pct[4]), 1),
        "steal_pct": round(float(pct[7]), 1),
    }


def _timed_batch(design, bodies, out, **kw):
    """run_batch with the completion times of its items (s since the start) and the machine's CPU shares
    between the first and the last completion (:func:`_shares`)."""
    from core.batch import run_batch

    t0 = time.perf_counter()
    stamps, ticks = [], []

    def progress(fraction, message):
        if "/" in message.split()[0] and not message.startswith("0/"):
            stamps.append(time.perf_counter() - t0)
            ticks[min(len(ticks), 1) :] = [_cpu_ticks()]  # the first completion's, then the latest's

    res = run_batch(design, bodies, out, progress=progress, **kw)
    shares = _shares(ticks[0], ticks[-1]) if len(ticks) == 2 else {}
    return res, stamps, time.perf_counter() - t0, shares


def _steady_rate(stamps) -> float:
    return (len(stamps) - 1) / (stamps[-1] - stamps[0]) if len(stamps) > 1 and stamps[-1] > stamps[0] else 0.0


def _split(rows) -> dict:
    ok = [r for r in rows if r["status"] == "ok"]
    out = {}
    for k in ("body", "transfer", "metrics", "write", "setup"):
        vals = [r[f"timings.{k}"] for r in ok if f"timings.{k}" in r]
        out[k] = round(1000.0 * float(np.median(vals)), 1) if vals else None
    cpu = _item_cpu(rows)
    out["cpu"] = round(1000.0 * float(np.median(cpu)), 1) if cpu else None
    return out


def _item_cpu(rows) -> list:
    """The CPU seconds of the items made without their worker's one-off cut."""
    return [r["timings.cpu"] for r in rows if r["status"] == "ok" and "timings.cpu" in r and "timings.setup" not in r]


def _cpu_rate(split) -> float:
    """Items per CPU second of a worker (per core): 1 / the median CPU time of an item."""
    return round(1000.0 / split["cpu"], 2) if split.get("cpu") else 0.0


def _shares_text(shares) -> str:
    if not shares:
        return "n/a"
    return " / ".join(str(shares[k]) for k in ("busy_pct", "idle_pct", "iowait_pct", "steal_pct"))


def _load() -> list:
    return [round(v, 2) for v in os.getloadavg()] if hasattr(os, "getloadavg") else []


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _simulated_cluster(n_workers: int, config_dir: Path):
    """(address, processes): a scheduler and ``n_workers`` worker processes on localhost."""
    port = _free_port()
    # the workers get the LocalCluster's settings through a config file (docs/batch.md, Clusters)
    config_dir.mkdir(parents=True, exist_ok=True)
    (config_dir / "ease.yaml").write_text(WORKER_YAML)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
        "DASK_CONFIG": str(config_dir),
    }
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=str(REPO), env=env)
    address = f"tcp://127.0.0.1:{port}"
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "distributed.cli.dask_scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--no-dashboard",
            ],
            **quiet,
        )
    ]
    for _ in range(n_workers):
        procs.append(
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "distributed.cli.dask_worker",
                    address,
                    "--nthreads",
                    "1",
                    "--nworkers",
                    "1",
                    "--no-dashboard",
                ],
                **quiet,
            )
        )
    from distributed import Client

    deadline = time.monotonic() + 60
    while True:
        try:
            with Client(address, timeout="5s") as c:
                c.wait_for_workers(n_workers, timeout=60)
            return address, procs
        except (OSError, TimeoutError):
            if time.monotonic() > deadline:
                _stop(procs)
                raise


def _stop(procs) -> None:
    for p in reversed(procs):
        p.terminate()
    for p in procs:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()


def run(out_dir, quick: bool = False) -> dict:
    from core.batch import sample_anny
    from core.batch.manifest import comparable
    from core.design.templates import template_path
    from core.fileio import write_json, write_text

    out = Path(out_dir)
    design = template_path(DESIGN)
    n, pairs = (16, 1) if quick else (BODIES, PAIRS)
    bodies = sample_anny(n, seed=SEED)
    result = {
        "design": DESIGN,
        "bodies": n,
        "seed": SEED,
        "pairs": pairs,
        "cpu_count": os.cpu_count(),
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs (shared)",
        "runs": {},
    }
    with tempfile.TemporaryDirectory(prefix="ease_bench_batch_") as tmp:
        tmp = Path(tmp)
        steady = {1: [0, 0.0], 2: [0, 0.0]}  # workers -> [items, seconds] between first and last completions
        cpus = {1: [], 2: []}  # workers -> the items' CPU seconds (those that paid no cut)
        for k in range(1, pairs + 1):
            for w in (1, 2):
                load = _load()
                res, stamps, wall, shares = _timed_batch(design, bodies, tmp / f"local{w}_{k}", workers=w)
                rate = _steady_rate(stamps)
                if rate:
                    steady[w][0] += len(stamps) - 1
                    steady[w][1] += stamps[-1] - stamps[0]
                split = _split(res.rows)
                cpus[w] += _item_cpu(res.rows)
                result["runs"][f"local_{w}" + (f"_{k}" if k > 1 else "")] = {
                    "workers": w,
                    "made": res.made,
                    "failed": res.failed,
                    "wall_s": round(wall, 2),
                    "first_item_s": round(stamps[0], 2) if stamps else None,
                    "steady_items_per_s": round(rate, 2),
                    "items_per_s_per_core": round(rate / w, 2),
                    "cpu_items_per_s_per_core": _cpu_rate(split),
                    "load_before": load,
                    "load_after": _load(),
                    "machine_cpu": shares,
                    "split_ms": split,
                }
                if w == 2 and k == 1:
                    local_rows = res.rows
        pooled = {w: steady[w][0] / steady[w][1] if steady[w][1] else 0.0 for w in steady}
        result["steady_items_per_s_pooled"] = {str(w): round(v, 2) for w, v in pooled.items()}
        result["speedup_2_vs_1"] = round(pooled[2] / pooled[1], 2) if pooled[1] else None
        result["cpu_items_per_s_per_core_pooled"] = {
            str(w): round(1.0 / float(np.median(v)), 2) if v else 0.0 for w, v in cpus.items()
        }
        result["speedup_per_pair"] = [
            round(
                result["runs"][f"local_2{s}"]["steady_items_per_s"]
                / result["runs"][f"local_1{s}"]["steady_items_per_s"],
                2,
            )
            if result["runs"][f"local_1{s}"]["steady_items_per_s"]
            else None
            for s in [""] + [f"_{k}" for k in range(2, pairs + 1)]
        ]

        address, procs = _simulated_cluster(2, tmp / "dask_config")
        try:
            res, stamps, wall, _ = _timed_batch(design, bodies, tmp / "cluster", scheduler=address)
        finally:
            _stop(procs)
        same = comparable(res.rows) == comparable(local_rows)
        result["runs"]["simulated_cluster"] = {
            "workers": res.workers,
            "made": res.made,
            "failed": res.failed,
            "wall_s": round(wall, 2),
            "steady_items_per_s": round(_steady_rate(stamps), 2),
            "same_manifest": same,
        }

        if not quick:
            many = sample_anny(1000, seed=SEED)
            res, stamps, wall, _ = _timed_batch(design, many, tmp / "population", workers=2)
            fails = [
                {"label": r["label"], "status": r["status"], "error": r["error"]}
                for r in res.rows
                if r["status"] != "ok"
            ]
            result["population"] = {
                "bodies": 1000,
                "made": res.made,
                "failed": res.failed,
                "crashed": False,
                "wall_s": round(wall, 1),
                "steady_items_per_s": round(_steady_rate(stamps), 2),
                "failures": fails,
                "split_ms": _split(res.rows),
            }

    lines = [
        "# Batch: `ease batch` on Dask",
        "",
        f"Design: {DESIGN} (Anny), {n} bodies sampled with seed {SEED} (uniform phenotypes, adult ages) "
        f"a run, 1 and 2 workers in turn, {pairs} pair(s) of runs, "
        f"pattern only (pattern.json, report.json, body.json per item; no preview). "
        f"Machine: {result['machine']}.",
        "",
        "Steady rate: items per second between the first and the last completed item (cluster start and "
        "each worker's one-off cut of the design excluded: `first item` is the wall time to the first "
        "completed item). CPU rate: 1 / the median CPU seconds a worker spends on an item (per core, "
        "whatever else runs; load: the 1-minute load average before / after the run; machine: the whole "
        "machine's CPU time between the first and the last completed item, busy (any process), idle, "
        "waiting for the disk, stolen by the host). "
        "Split: median per item, ms.",
        "",
        "| run | workers | items ok / failed | wall s | first item s | items/s | items/s/core | "
        "items/CPU-s (per core) | load | machine busy / idle / disk wait / steal % | body ms | transfer ms | "
        "metrics ms | write ms | CPU ms | setup (cut) ms |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name in result["runs"]:
        if not name.startswith("local_"):
            continue
        r, s = result["runs"][name], result["runs"][name]["split_ms"]
        load = f"{r['load_before'][0]} / {r['load_after'][0]}" if r["load_before"] else "n/a"
        pair = name.split("_")[2] if name.count("_") == 2 else "1"
        lines.append(
            f"| LocalCluster (pair {pair}) | {r['workers']} | {r['made']} / {r['failed']} | {r['wall_s']} | "
            f"{r['first_item_s']} | {r['steady_items_per_s']} | {r['items_per_s_per_core']} | "
            f"{r['cpu_items_per_s_per_core']} | {load} | {_shares_text(r.get('machine_cpu'))} | "
            f"{s['body']} | {s['transfer']} | "
            f"{s['metrics']} | {s['write']} | {s['cpu']} | {s['setup']} |"
        )
    c = result["runs"]["simulated_cluster"]
    pooled, cpu_pooled = result["steady_items_per_s_pooled"], result["cpu_items_per_s_per_core_pooled"]
    lines += [
        "",
        f"Speed-up, 2 workers over 1 (steady rate, {pairs} pair(s) of runs taken in turn, pooled: "
        f"{pooled['2']} / {pooled['1']} items/s): **{result['speedup_2_vs_1']}x** "
        f"(each pair: {', '.join(f'{v}x' for v in result['speedup_per_pair'])}). "
        f"Items per CPU-second per core, the median item of the runs pooled: 1 worker {cpu_pooled['1']}, "
        f"2 workers {cpu_pooled['2']}.",
        "",
        f"Simulated cluster (a `dask scheduler` and {c['workers']} `dask worker` processes on localhost, "
        f"`--scheduler`): {c['made']} ok / {c['failed']} failed in {c['wall_s']} s "
        f"({c['steady_items_per_s']} items/s); manifest equal to the 2-worker LocalCluster's "
        f"(timings and worker ids aside): **{'yes' if c['same_manifest'] else 'NO'}**.",
        "",
    ]
    if "population" in result:
        p = result["population"]
        lines += [
            f"Population: 1,000 sampled bodies on 2 workers: {p['made']} ok, {p['failed']} failed, "
            f"no crash, {p['wall_s']} s ({p['steady_items_per_s']} items/s steady).",
            "",
        ]
        if p["failures"]:
            lines += ["| body | status | reason |", "|---|---|---|"]
            lines += [f"| {f['label']} | {f['status']} | {f['error']} |" for f in p["failures"]]
            lines.append("")
    else:
        lines += ["Population (1,000 bodies): not run in quick mode.", ""]
    write_text(out / "batch.md", "\n".join(lines))
    write_json(out / "batch.json", result)
    return result
