"""The live bench's main-thread probe (benchmarks/bench_live.py ``_Gaps``, issue 32): a worker
that holds the GIL in one C call stalls the main thread's waits as long, and the probe sees it
between the ticks, where no tick measures it."""

import importlib.util
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _bench():
    spec = importlib.util.spec_from_file_location("bench_live_probe", ROOT / "benchmarks" / "bench_live.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_probe_sees_a_worker_holding_the_gil():
    import random

    bench = _bench()
    rng = random.Random(0)
    values = [rng.random() for _ in range(300_000)]
    held = {}

    def worker():
        t0 = time.perf_counter()
        sorted(values)  # one C call: the GIL is held throughout
        held["s"] = time.perf_counter() - t0

    gaps = bench._Gaps()
    t = threading.Thread(target=worker)
    t.start()
    gaps.nap(0.02)  # the worker takes the GIL as the main thread sleeps
    t.join()
    assert held["s"] > 4 * bench.NAP_S
    # the main thread waited for (most of) the sort, between its ticks
    assert gaps.longest_s >= 0.5 * held["s"], (gaps.longest_s, held["s"])
    assert gaps.what == "between ticks"
