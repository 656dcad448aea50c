"""SIGINT and SIGTERM held off while a block runs (:func:`signals_held`).

:mod:`core.fileio` swaps an output folder's entries one rename each where the
folder itself cannot be renamed; Ctrl-C in the middle would leave it half
swapped until the next run, so the swap runs with the signals held.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import List


@contextlib.contextmanager
def signals_held():
    """SIGINT/SIGTERM wait until the block is done (main thread, where Python allows it).

    Blocking the signals is not enough on its own: a signal that arrived just
    before the block has already tripped Python's handler, which would raise
    at the next bytecode, inside the block. So the handlers are also swapped
    for one that only records the signal; it is delivered after the block."""
    held = (signal.SIGINT, signal.SIGTERM)
    if not (hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread()):
        yield
        return
    pending: List[int] = []
    handlers = {s: signal.signal(s, lambda signum, frame: pending.append(signum)) for s in held}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # a blocked signal arrives now: recorded
        for s, handler in handlers.items():
            signal.signal(s, handler)
        for s in dict.fromkeys(pending):  # delivered as if it came now
            handler = handlers[s]
            if callable(handler):
                handler(s, None)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(s)
