"""``ease batch``: one design over many bodies on Dask distributed.

- :mod:`.bodies`: the bodies (a measurement table, a seeded Anny sample, SMPL betas);
- :mod:`.items`: design × body items named by a content hash, the run's options;
- :mod:`.worker`: one item on a worker (the design cut once per worker, one transfer per item);
- :mod:`.manifest`: the JSONL journal of rows (and Parquet where pyarrow is installed);
- :mod:`.run`: the Dask driver (LocalCluster or ``--scheduler``), resumable, interruptible;
- :mod:`.garmentcode`: each item's pattern as a GarmentCode specification.

The pipeline work goes through :mod:`core.workflows` only. See docs/batch.md.
"""

from .bodies import BodySource, BodySourceError, read_betas, read_measurements, sample_anny
from .items import Item, Options, make_items
from .run import BatchError, BatchResult, run_batch

__all__ = [
    "BodySource",
    "BodySourceError",
    "read_betas",
    "read_measurements",
    "sample_anny",
    "Item",
    "Options",
    "make_items",
    "BatchError",
    "BatchResult",
    "run_batch",
]
