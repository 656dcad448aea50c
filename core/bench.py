"""``ease bench``: regenerate the benchmark reports in ``benchmarks/results/``.

Each ``benchmarks/bench_<name>.py`` defines ``run(out_dir) -> dict`` and writes
Markdown + JSON (+ PNG) into ``out_dir``. Benchmarks live in the source
checkout only (they are not part of the installed extension), so they are
loaded from their files.
"""
from __future__ import annotations

import importlib.util
import json
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
BENCH_DIR = REPO / "benchmarks"
ORDER = ("body", "cut", "pattern", "drape", "export")


def available() -> list:
    names = [p.stem[len("bench_"):] for p in sorted(BENCH_DIR.glob("bench_*.py"))]
    return sorted(names, key=lambda n: (ORDER.index(n) if n in ORDER else len(ORDER), n))


def _load(name: str):
    path = BENCH_DIR / f"bench_{name}.py"
    spec = importlib.util.spec_from_file_location(f"ease_bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _cmd(args) -> int:
    from .errors import EaseError
    from .fileio import write_json, write_text

    if not BENCH_DIR.is_dir():
        raise EaseError("benchmarks/ not found: `ease bench` runs from a source checkout")
    names = available()
    wanted = [n.strip() for n in args.only.split(",")] if args.only else names
    unknown = [n for n in wanted if n not in names]
    if unknown:
        raise EaseError(f"--only: unknown benchmark(s) {', '.join(unknown)}; available: {', '.join(names)}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    times_path = out / "bench_times.json"
    times = json.loads(times_path.read_text()) if times_path.is_file() else {}
    for name in wanted:
        print(f"[ease bench] {name} ...", file=sys.stderr, flush=True)
        t0 = time.perf_counter()
        module = _load(name)
        kwargs = {"quick": True} if args.quick and "quick" in module.run.__code__.co_varnames else {}
        module.run(out, **kwargs)
        dt = time.perf_counter() - t0
        times[name] = {"seconds": round(dt, 1), "quick": bool(kwargs),
                       "date": time.strftime("%Y-%m-%d", time.gmtime())}
        write_json(times_path, times)
        print(f"[ease bench] {name} done in {dt:.1f} s", file=sys.stderr, flush=True)
    # the index lists every report in the folder, also those of earlier partial runs
    rows = []
    for name in names:
        if (out / f"{name}.md").is_file():
            t = times.get(name, {})
            when = f"{t['seconds']:.1f} s on {t['date']}{' (quick)' if t.get('quick') else ''}" if t else "-"
            rows.append(f"| {name} | [{name}.md]({name}.md) | {when} |")
    index = ["# EASE benchmark results", "",
             "Regenerate with `./ease.sh bench` (all) or `./ease.sh bench --only NAME`; see the README. "
             "Metric definitions: shared SPEC.md. Times are wall seconds on the machine that ran them.", "",
             "| benchmark | report | last run |", "|---|---|---|", *rows, ""]
    write_text(out / "README.md", "\n".join(index))
    for p in sorted(out.iterdir()):
        print(f"  {p}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "bench",
        help="run the benchmarks and write reports to benchmarks/results/",
        description="Run benchmarks/bench_*.py (speed and accuracy: the paper's tables on our body) "
                    "and write Markdown + JSON + PNG reports.",
    )
    p.add_argument("--out", default=str(BENCH_DIR / "results"), help="report folder (default: benchmarks/results)")
    p.add_argument("--only", default="", help="comma-separated subset, e.g. body,pattern")
    p.add_argument("--quick", action="store_true", help="smaller sweeps where a benchmark supports it")
    p.set_defaults(func=_cmd)
