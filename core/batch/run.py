"""Run a batch on Dask distributed: a LocalCluster by default, or an existing scheduler.

The driver (this process) reads the manifest, submits every item not yet
done, a few items a task (:func:`task_sizes`), and appends each returned row to
the journal; workers make the items (:func:`core.batch.worker.run_item`) and
write their folders. Only the driver
writes the manifest, and only after a worker has returned, that is after the
item's folder is complete, so an interruption at any moment leaves complete
rows of complete items, and a rerun of the same command makes exactly the
items without an ``ok`` row.
"""

from __future__ import annotations

import json
import logging
import os
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Sequence

from ..errors import EaseError
from ..fileio import recover_folder
from ..progress import Progress, report
from ..signals import signals_held
from .bodies import BodySource
from .items import Item, Options, make_items
from .manifest import Journal, compact, completed, read_rows
from .worker import item_row, one_line, run_items

#: Dask settings for the local workers. Distributed's nannies start workers with
#: MALLOC_TRIM_THRESHOLD_=65536, which turns off glibc's adaptive mmap threshold: every
#: array the solver allocates per iteration is then mmapped and unmapped, and a transfer
#: takes 1.5x as long (shirt: 180 vs 117 ms). None unsets it; BLAS stays at one thread.
#: The workers' statistical profiler (a thread walking the task's Python stack every 10 ms,
#: for the dashboard's profile page) costs ~8 % of an item's CPU (shirt: 332 vs 308 ms at
#: the same load): off. The event loop's health tick (every 20 ms) and the system monitor's
#: samples (every 500 ms), diagnostics for the dashboard and the "unresponsive" warnings, cost the
#: worker ~4 ms of CPU an item beside the task's own thread (shirt: 7.2 -> 3.5 ms): 1 s and 5 s.
#: The memory monitor (every 100 ms, in each worker and in its nanny, which lives in the driver's
#: process) cost 41 ms of CPU a second on an idle 2-worker cluster, 2 % of this 2-core machine, taken
#: from the workers: 12 ms at 1 s. A worker over its memory limit is then paused or stopped within 1 s.
WORKER_CONFIG = {
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.memory.monitor-interval": "1s",
}


class BatchError(EaseError):
    """A batch cannot start (bad design, no bodies, no scheduler)."""


@dataclass
class BatchResult:
    """What a run did.

    Attributes
    ----------
    total : items of the batch; skipped : already complete before this run;
    made : completed ok in this run; failed : rows with status error/timeout in
    this run; interrupted : stopped by Ctrl-C (or a progress callback raising
    KeyboardInterrupt); seconds : wall time of this run; workers : number of
    workers used; rows : the compacted manifest (all runs, whatever their options);
    ids : the ids of this batch's items (made now or before), in the bodies' order.
    """

    total: int
    skipped: int
    made: int = 0
    failed: int = 0
    interrupted: bool = False
    seconds: float = 0.0
    workers: int = 0
    rows: List[dict] = field(default_factory=list)
    ids: List[str] = field(default_factory=list)

    def own_rows(self) -> List[dict]:
        """The manifest's rows of this batch's items (a folder may also hold another option set's)."""
        ids = set(self.ids)
        return [row for row in self.rows if row.get("id") in ids]

    def summary(self) -> str:
        state = "interrupted" if self.interrupted else "done"
        where = (
            f"on {self.workers} worker{'s' * (self.workers != 1)}"
            if self.made + self.failed or self.workers
            else "(nothing left to make)"
        )
        return (
            f"batch {state}: {self.made} made, {self.failed} failed, {self.skipped} already complete, "
            f"{self.total} item{'s' * (self.total != 1)}, {self.seconds:.1f} s {where}"
        )


def read_design(design) -> dict:
    """The design as a JSON dict, checked (a bad design stops the batch before any worker starts)."""
    from ..design import load_design

    if isinstance(design, dict):
        obj = design
    else:
        path = Path(design)
        try:
            obj = json.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise BatchError(f"{path}: cannot read the design ({exc.strerror or exc})") from None
        except json.JSONDecodeError as exc:
            raise BatchError(f"{path}: not JSON ({exc})") from None
    try:
        load_design(json.loads(json.dumps(obj)))
    except EaseError as exc:
        if isinstance(design, dict):
            raise
        raise BatchError(f"{design}: {exc}") from None
    return obj


#: Seconds a --scheduler address has to answer as a Dask scheduler.
SCHEDULER_PROBE_S = 20.0


def _check_scheduler(address: str) -> None:
    """Stop in one line on an address that is not a Dask scheduler answering.

    ``Client()`` waits without end on a server that takes the connection and never
    answers (a web server, say the dashboard's port), and one that answers something
    else can make it read a frame length of exabytes: a probe in its own thread and
    event loop, bounded by :data:`SCHEDULER_PROBE_S`, asks for the scheduler's identity.
    """
    import asyncio
    import concurrent.futures

    from distributed.comm import connect
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        parse_host_port(parse_address(address)[1])
    except (ValueError, TypeError) as exc:
        raise BatchError(f"--scheduler {address}: expected tcp://HOST:PORT ({one_line(exc)})") from None

    async def identity():
        comm = await connect(address, timeout=SCHEDULER_PROBE_S)
        try:
            await comm.write({"op": "identity"})
            return await comm.read()
        finally:
            comm.abort()

    def probe():
        return asyncio.run(asyncio.wait_for(identity(), SCHEDULER_PROBE_S))

    with concurrent.futures.ThreadPoolExecutor(1) as pool:  # a caller may be running an event loop
        try:
            reply = pool.submit(probe).result()
        except (asyncio.TimeoutError, TimeoutError):
            raise BatchError(
                f"--scheduler {address}: no Dask scheduler answered within {SCHEDULER_PROBE_S:g} s"
            ) from None
        except Exception as exc:  # refused, reset, or bytes that are not Dask's protocol
            raise BatchError(f"--scheduler {address}: cannot connect to a Dask scheduler ({one_line(exc)})") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise BatchError(f"--scheduler {address}: not a Dask scheduler (it answered as {kind!r})")


def _client(workers: Optional[int], scheduler: Optional[str]):
    """(client, cluster or None, number of workers)."""
    try:
        import dask
        from distributed import Client, LocalCluster
    except ImportError:
        raise BatchError(
            "ease batch needs Dask: pip install 'ease-garments[batch]' (dask, distributed; ./ease.sh installs them)"
        ) from None
    if scheduler:
        _check_scheduler(scheduler)
        try:
            client = Client(scheduler, timeout="20s")
        except (OSError, TimeoutError) as exc:  # the probe above answered; the scheduler went since
            raise BatchError(f"--scheduler {scheduler}: cannot connect ({one_line(exc)})") from None
        return client, None, len(client.scheduler_info().get("workers", {}))
    n = int(os.cpu_count() or 1) if workers is None else int(workers)
    if n < 1:
        raise BatchError(f"--workers: expected >= 1, got {n}")
    # processes, one thread each: the solver is numpy/scipy-bound and holds the GIL between calls
    with dask.config.set(WORKER_CONFIG):
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
            preload=["core.batch.local_worker"],
            # no dashboard, but the scheduler's HTTP routes still take a port: any free
            # one, not 8787 with a warning when another cluster holds it
            scheduler_kwargs={"dashboard_address": ":0"},
        )
    return Client(cluster), cluster, n


def _eta(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}"


def run_batch(
    design,
    bodies: Sequence[BodySource],
    out,
    model: str = "anny",
    options: Optional[Options] = None,
    workers: Optional[int] = None,
    scheduler: Optional[str] = None,
    item_timeout: Optional[float] = None,
    progress: Optional[Progress] = None,
) -> BatchResult:
    """Make every design × body item not yet in ``out``'s manifest.

    Parameters
    ----------
    design : path or JSON dict of the design
    bodies : the batch's bodies (:mod:`core.batch.bodies`)
    out : the dataset folder: ``items/<id>/`` per item, ``manifest.jsonl`` (+ ``.parquet``)
    model : body model name or file the design is cut on and the bodies are of
    options : what each item makes besides the transfer (:class:`Options`)
    workers : LocalCluster workers (default: the CPU count); ignored with ``scheduler``
    scheduler : ``tcp://HOST:PORT`` of a running Dask scheduler
    item_timeout : seconds an item may take (its worker's one-off cut of the design excluded)
    progress : ``progress(fraction, message)``; the message reads
        ``"12/100 items, 1 failed, ETA 0:01:05"``. It may raise KeyboardInterrupt
        to stop as Ctrl-C would.

    Returns
    -------
    BatchResult; the manifest is compacted (sorted by id) even when interrupted.
    """
    if not bodies:
        raise BatchError("no bodies: give --bodies, --sample or --smpl-betas")
    if item_timeout is not None and not item_timeout > 0:
        raise BatchError(f"--item-timeout: expected seconds > 0, got {item_timeout}")
    meshes = [f for f in (options.export if options else ()) if f in ("glb", "obj")]
    if meshes and not options.drape:
        raise BatchError(
            f"--export {meshes[0]}: the garment's 3D file is of the draped garment; "
            f"add --drape, or export svg, dxf, pdf only"
        )
    obj = read_design(design)
    out = Path(out)
    items = make_items(obj, bodies, model=model, options=options)
    done = completed(read_rows(out / "manifest.jsonl"))
    pending: List[Item] = [it for it in items if it.id not in done]
    result = BatchResult(total=len(items), skipped=len(items) - len(pending), ids=[it.id for it in items])
    t0 = time.perf_counter()
    if pending:
        # what killed runs left in the items folder, cleared once here: the workers then write
        # an item without listing a folder that holds every item made so far
        recover_folder(out / "items")
        try:
            _submit(pending, out, workers, scheduler, item_timeout, progress, result)
        except KeyboardInterrupt:  # Ctrl-C again while the first one's clean-up ran
            result.interrupted = True
    try:
        with signals_held():  # the manifest is compacted whole whatever Ctrl-C does meanwhile
            result.rows = compact(out)
    except KeyboardInterrupt:  # arrived during the compaction, which is done: a stop like any
        result.interrupted = True
    result.seconds = time.perf_counter() - t0
    return result


#: Items one Dask task makes at most. Whatever it does, a task costs the driver (scheduler
#: transitions, the client's bookkeeping and its fetch of the result) ~4 ms of CPU on this 2-core
#: machine, and its worker ~1.4 ms: at ~150 ms a shirt item, 3.6 % of the CPU the items need, taken
#: from the workers once they fill the machine. Four items a task: 1.2 and 0.5 ms an item (200
#: 60 ms tasks on 2 workers: driver 4.0 -> 1.2 ms, workers 1.4 -> 0.5 ms an item).
ITEMS_PER_TASK = 4


def task_sizes(n: int, workers: int, largest: int = ITEMS_PER_TASK) -> List[int]:
    """How many items each task of a batch of ``n`` items makes, in submission order.

    The first task of each worker makes one item, so each worker's first row (which
    pays for its cut of the design) comes as soon as it can; after that a task takes a
    quarter of an even share of what is left, at most ``largest``, so the tasks
    shrink to one item towards the end and no worker waits there for another's long
    task (guided self-scheduling). Dask runs the tasks in submission order.
    """
    workers = max(int(workers), 1)
    sizes = [1] * min(n, workers)
    left = n - len(sizes)
    while left > 0:
        size = max(1, min(largest, -(-left // (4 * workers))))
        sizes.append(size)
        left -= size
    return sizes


def _error_row(item: Item, exc: BaseException) -> dict:
    # Dask's KilledWorker text names the task's key (which carries the run's token) and a worker
    # address: neither means anything to the user, and the manifest would differ run to run
    if type(exc).__name__ == "KilledWorker":
        error = (
            f"KilledWorker: the worker process died {1 + getattr(exc, 'allowed_failures', 0)} time(s) "
            "while this item was on it (out of memory, or a crash; a rerun tries it again)"
        )
    else:
        error = one_line(exc)
    return item_row(item, "error", error)


def _submit(pending, out, workers, scheduler, item_timeout, progress, result: BatchResult) -> None:
    from distributed import as_completed

    # the cluster first: a --scheduler that does not answer leaves no manifest behind
    client, cluster, result.workers = _client(workers, scheduler)
    journal, futures, groups = None, [], {}
    # the keys are this run's: a scheduler shares a key's task (and its result) between its clients,
    # so another run of the same items at once (into another folder, or with other task sizes) would
    # return rows of items made elsewhere, or of other items than the task's
    token = uuid.uuid4().hex[:12]

    def submit(tasks, prefix):
        new = client.map(
            run_items,
            tasks,
            out_root=str(out.resolve()),
            time_limit=item_timeout,
            key=[f"{prefix}-{group[0].id}-{token}" for group in tasks],
            pure=False,
        )
        futures.extend(new)
        groups.update((f.key, group) for f, group in zip(new, tasks))
        return new

    try:
        journal = Journal(out)
        tasks, i = [], 0
        for size in task_sizes(len(pending), result.workers):
            tasks.append(pending[i : i + size])
            i += size
        queue = as_completed(submit(tasks, "ease-items"), with_results=True, raise_errors=False)
        t0, n, k = time.perf_counter(), len(pending), 0
        report(progress, 0.0, f"0/{n} items, 0 failed, {result.workers} workers starting")
        for future, value in queue:
            group = groups[future.key]
            if future.status == "finished":
                rows = value
            elif len(group) > 1:
                # the worker process died (memory, a crash) under a task of several items: each
                # again in a task of its own, so only the item that kills its worker gets the error
                queue.update(submit([[item] for item in group], "ease-item"))
                continue
            else:
                exc = value[1] if isinstance(value, tuple) else value
                rows = [_error_row(group[0], exc)]
            failed = result.failed
            ok = sum(row["status"] == "ok" for row in rows)
            with signals_held():  # a task's rows go into the journal and the counts together
                journal.extend(rows)
                result.made, result.failed = result.made + ok, result.failed + len(rows) - ok
            for row in rows:  # counted first: a progress callback may stop the batch here
                k, failed = k + 1, failed + (row["status"] != "ok")
                rate = (time.perf_counter() - t0) / k
                report(progress, k / n, f"{k}/{n} items, {failed} failed, ETA {_eta(rate * (n - k))}")
    except KeyboardInterrupt:
        result.interrupted = True
    finally:
        with signals_held():  # Ctrl-C again: delivered once the workers are stopped and released
            if journal is not None:
                journal.close()
            if futures:
                client.cancel(futures)
            client.close()
            if cluster is not None:
                cluster.close()
