"""The nesting worker of :mod:`core.marker.nesting`, run as its own process.

It reads one JSON request on stdin (strip height, items, exploration and
compression seconds, whether the search may end early, seed, threads), runs
spyrrow (the sparrow / jagua-rs strip packer) and writes one JSON line on
stdout for every feasible solution shorter than the last one, then
``{"done": true}``. The nester cannot be stopped from outside once it
runs, so the marker runs it in this separate process: a cancel or Ctrl-C
kills the process and keeps the best solution already received.

Standalone on purpose: it imports no EASE module, so it runs under any
``sys.executable`` (a venv, Blender's Python) with the caller's ``sys.path``.
"""

import json
import signal
import sys
import threading
import time


def main() -> int:
    # Ctrl-C in a terminal reaches the whole process group: the parent decides
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import spyrrow
    except ImportError as exc:
        sys.stderr.write(f"spyrrow is not installed ({exc})\n")
        return 3
    req = json.load(sys.stdin)
    items = [
        spyrrow.Item(str(k), [tuple(p) for p in it["shape"]], int(it["demand"]), list(it["orientations"]))
        for k, it in enumerate(req["items"])
    ]
    instance = spyrrow.StripPackingInstance("marker", float(req["strip"]), items)
    # the phases' times set here, not left to spyrrow's split of a total (80 % exploration, 20 % compression)
    config = spyrrow.StripPackingConfig(
        early_termination=bool(req.get("early_termination", False)),
        total_computation_time=None,
        exploration_time=int(req["exploration"]),
        compression_time=int(req["compression"]),
        seed=int(req["seed"]),
        num_workers=int(req["threads"]),
    )
    queue = spyrrow.ProgressQueue()
    result = {}

    def solve():
        result["solution"] = instance.solve(config, progress=queue)

    thread = threading.Thread(target=solve, daemon=True)
    thread.start()
    best = [float("inf")]

    def emit(solution, phase):
        if solution.width < best[0] - 1e-9:
            best[0] = solution.width
            placed = [
                [int(p.id), float(p.rotation), float(p.translation[0]), float(p.translation[1])]
                for p in solution.placed_items
            ]
            sys.stdout.write(json.dumps({"length": float(solution.width), "phase": phase, "placed": placed}) + "\n")
            sys.stdout.flush()

    def drain():
        for kind, solution in queue.drain():
            if kind.phase_name() != "exploring" or kind == spyrrow.ReportType.ExplFeas:
                emit(solution, kind.phase_name())

    while thread.is_alive():
        time.sleep(0.05)
        drain()
    thread.join()
    drain()
    if "solution" in result:
        emit(result["solution"], "final")
    sys.stdout.write(json.dumps({"done": True}) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
