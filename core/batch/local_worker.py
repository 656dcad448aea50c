"""A Dask preload for the local cluster's workers: Ctrl-C is the driver's to handle.

A terminal's Ctrl-C goes to every process of its group, the LocalCluster's
worker processes too; each then died printing a ~35-line traceback before the
driver's own clean stop, and the nanny logged the death. The driver stops the
workers itself (cancelling their tasks, closing the cluster), so its workers
ignore SIGINT. Only the local cluster loads this (:func:`core.batch.run._client`);
the workers of a cluster started by hand keep their own handling.
"""

from __future__ import annotations

import signal
import threading


def dask_setup(service) -> None:
    """Ignore SIGINT in a worker process (Dask calls this for each preload's service)."""
    from distributed import Worker

    if isinstance(service, Worker) and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
