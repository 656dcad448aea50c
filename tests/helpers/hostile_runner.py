"""Run hostile-input cases in a worker process that may crash (no tests here).

``run_cases("hostile_models:check_model", [path, ...])`` starts one Python
process with its address space capped (``RLIMIT_AS``), calls the check on
each case in turn and reads one JSON line per case: ``ok`` (the input was
accepted and worked), ``refused`` (an :class:`core.errors.EaseError`, with its
message), or ``traceback`` (any other exception, MemoryError included). A
worker killed by a signal (a segfault: return code < 0) is recorded as
``crash`` for the case it was on, and a new worker goes on with the next.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HELPERS = Path(__file__).resolve().parent

# Python + numpy + scipy + the core take ~0.2 GiB of address space; a memory bomb that
# is not refused before allocating (3 GB, 8 TB) fails under this cap instead of taking the machine.
MEMORY_CAP = 3 << 29  # 1.5 GiB

_WORKER = r"""
import json, os, resource, sys
cap = int(sys.argv[2])
resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
sys.path[:0] = [sys.argv[3], sys.argv[4]]
import importlib
mod, func = sys.argv[1].split(":")
check = getattr(importlib.import_module(mod), func)
from core.errors import EaseError
cases = json.loads(sys.stdin.read())
for i, case in enumerate(cases):
    try:
        check(case)
        out = ["ok", ""]
    except EaseError as exc:
        out = ["refused", str(exc)]
    except BaseException as exc:
        out = ["traceback", f"{type(exc).__name__}: {str(exc)[:300]}"]
    print(json.dumps([i] + out), flush=True)
"""


def run_cases(check: str, cases: list, cap: int = MEMORY_CAP, timeout: float = 300.0) -> list:
    """``[(case, status, message), ...]`` for every case, status ``ok|refused|traceback|crash``."""
    results = []
    todo = list(cases)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", PYTHONFAULTHANDLER="")
    while todo:
        proc = subprocess.run(
            [sys.executable, "-c", _WORKER, check, str(cap), str(ROOT), str(HELPERS)],
            input=json.dumps(todo),
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
            cwd=str(ROOT),
        )
        done = [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("[")]
        for i, status, message in done:
            results.append((todo[i], status, message))
        if len(done) == len(todo):
            break
        # the worker died on case len(done): a crash (signal) or an exit without a word
        why = f"return code {proc.returncode}: {proc.stderr.strip()[-300:]}"
        results.append((todo[len(done)], "crash" if proc.returncode < 0 else "traceback", why))
        todo = todo[len(done) + 1 :]
    return results


def failures(results) -> list:
    """The results that are a crash or a traceback (none is allowed)."""
    return [r for r in results if r[1] in ("crash", "traceback")]


def check_message(message: str, *names) -> None:
    """A refusal is one line that names the file (any of ``names``)."""
    assert "\n" not in message.strip(), f"refusal over several lines: {message!r}"
    assert any(str(n) in message for n in names), f"refusal does not name {names}: {message!r}"


def split_cases(cases: list, chunk: int) -> tuple:
    """(crafted cases, seeded mutations in tuples of ``chunk``): a generator's cases whose name
    starts with ``mut`` are mutations, run as a sample of chunks in CI."""
    crafted = [c for c in cases if not c[0].startswith("mut")]
    mutated = [c for c in cases if c[0].startswith("mut")]
    return crafted, [tuple(mutated[i : i + chunk]) for i in range(0, len(mutated), chunk)]


def run_checked(check: str, cases: list, inputs: list, names_of) -> dict:
    """Run ``inputs`` (one per case) through ``check``; no crash or traceback is allowed, and
    every refusal is one line naming a file of ``names_of(input)``. Returns case -> (status, message)."""
    results = run_cases(check, inputs)
    assert len(results) == len(cases)
    bad = failures(results)
    assert not bad, f"{len(bad)} of {len(cases)} crashed or traced back: {bad[:5]}"
    for item, status, message in results:
        if status == "refused":
            check_message(message, *names_of(item))
    return {case: (status, message) for case, (_, status, message) in zip(cases, results)}
