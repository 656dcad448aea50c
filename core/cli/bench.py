"""``ease bench``: regenerate the benchmark reports (``benchmarks/results/``).

Each ``benchmarks/bench_<name>.py`` defines ``run(out_dir) -> dict`` and writes
Markdown + JSON (+ PNG) into ``out_dir``. Benchmarks live in a source
checkout only (neither the wheel nor the extension ships them), so they are
loaded from their files: ``--bench-dir``, else ``$EASE_BENCH_DIR``, else
``benchmarks/`` in the current directory.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import time
from pathlib import Path

from .common import print_files, subcommand

ORDER = ("body", "cut", "pattern", "drape", "fabric", "export")
ENV = "EASE_BENCH_DIR"


def bench_dir(given=None) -> Path:
    """The benchmarks folder: ``given``, else ``$EASE_BENCH_DIR``, else ``./benchmarks``."""
    from ..errors import EaseError

    path = Path(given or os.environ.get(ENV) or "benchmarks")
    if not path.is_dir():
        raise EaseError(
            f"no benchmarks folder at {path.resolve()}: `ease bench` runs in a source checkout "
            f"(cd to it, or pass --bench-dir / set {ENV})"
        )
    return path


def available(directory: Path) -> list:
    names = [p.stem[len("bench_") :] for p in sorted(directory.glob("bench_*.py"))]
    return sorted(names, key=lambda n: (ORDER.index(n) if n in ORDER else len(ORDER), n))


def _load(directory: Path, name: str):
    path = directory / f"bench_{name}.py"
    spec = importlib.util.spec_from_file_location(f"ease_bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _cmd(args) -> int:
    from ..errors import EaseError
    from ..fileio import write_json, write_text

    directory = bench_dir(args.bench_dir)
    names = available(directory)
    wanted = [n.strip() for n in args.only.split(",")] if args.only else names
    unknown = [n for n in wanted if n not in names]
    if unknown:
        raise EaseError(f"--only: unknown benchmark(s) {', '.join(unknown)}; available: {', '.join(names)}")
    out = Path(args.out) if args.out else directory / "results"
    out.mkdir(parents=True, exist_ok=True)
    times_path = out / "bench_times.json"
    times = json.loads(times_path.read_text()) if times_path.is_file() else {}
    for name in wanted:
        print(f"[ease bench] {name} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        module = _load(directory, name)
        kwargs = {"quick": True} if args.quick and "quick" in module.run.__code__.co_varnames else {}
        module.run(out, **kwargs)
        dt = time.perf_counter() - t0
        times[name] = {"seconds": round(dt, 1), "quick": bool(kwargs), "date": time.strftime("%Y-%m-%d", time.gmtime())}
        write_json(times_path, times)
        print(f"[ease bench] {name} done in {dt:.1f} s", file=sys.stderr, flush=True)
    # the index lists every report in the folder, also those of earlier partial runs
    rows = []
    for name in names:
        if (out / f"{name}.md").is_file():
            t = times.get(name, {})
            when = f"{t['seconds']:.1f} s on {t['date']}{' (quick)' if t.get('quick') else ''}" if t else "-"
            rows.append(f"| {name} | [{name}.md]({name}.md) | {when} |")
    index = [
        "# EASE benchmark results",
        "",
        "Regenerate with `./ease.sh bench` (all) or `./ease.sh bench --only NAME`; see the README. "
        "Metric definitions: shared SPEC.md. Times are wall seconds on the machine that ran them.",
        "",
        "| benchmark | report | last run |",
        "|---|---|---|",
        *rows,
        "",
    ]
    write_text(out / "README.md", "\n".join(index))
    print_files(sorted(out.iterdir()), prefix="  ")
    return 0


def add_parser(sub) -> None:
    p = subcommand(
        sub,
        "bench",
        _cmd,
        help="run the benchmarks and write reports to benchmarks/results/ (source checkout)",
        description="Run benchmarks/bench_*.py (speed and accuracy: the paper's tables on our body) "
        "and write Markdown + JSON + PNG reports. The benchmarks ship with the source checkout "
        "only: run from its root, or pass --bench-dir.",
    )
    p.add_argument("--out", default=None, help="report folder (default: BENCH_DIR/results)")
    p.add_argument("--only", default="", help="comma-separated subset, e.g. body,pattern")
    p.add_argument("--quick", action="store_true", help="smaller sweeps where a benchmark supports it")
    p.add_argument("--bench-dir", default=None, help=f"folder of bench_*.py (default: ${ENV}, else ./benchmarks)")
