"""A Dask worker preload for the batch tests: the item of the body labelled ``sample 2`` ends its
worker process at once, as a crash or the kernel's out-of-memory killer would."""

import os

from core.batch import worker

KILL = "sample 2"
# Dask may run a preload more than once in one process (re-executing this module's globals):
# keep the first original, or the wrapper would end up calling itself.
_run_item = worker.__dict__.setdefault("_unpatched_run_item", worker.run_item)


def run_item(item, *args, **kwargs):
    if item.body.label == KILL:
        os._exit(3)
    return _run_item(item, *args, **kwargs)


worker.run_item = run_item
