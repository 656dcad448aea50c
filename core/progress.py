"""Progress reporting and cancellation for long operations.

A long operation takes ``progress: Progress | None``. It calls
``progress(fraction, message)`` now and then; the callback may raise
:class:`core.errors.Cancelled` to stop the operation, which then leaves no
partial output behind. The CLI prints a progress line; the add-on drives
Blender's progress bar and status text.
"""

from __future__ import annotations

import sys
import time
from typing import Callable, Optional

Progress = Callable[[float, str], None]


def report(progress: Optional[Progress], fraction: float, message: str) -> None:
    """Call ``progress`` if given; fraction is clamped to [0, 1]."""
    if progress is not None:
        progress(min(max(float(fraction), 0.0), 1.0), message)


def sub(progress: Optional[Progress], start: float, stop: float) -> Optional[Progress]:
    """A progress callback mapping [0, 1] into [start, stop] of ``progress``."""
    if progress is None:
        return None

    def inner(fraction: float, message: str) -> None:
        progress(start + (stop - start) * fraction, message)

    return inner


class ConsoleProgress:
    """Progress line on stderr: ``[ease] 42% cutting panel front``."""

    def __init__(self, stream=None, min_interval: float = 0.2):
        self.stream = stream or sys.stderr
        self.min_interval = min_interval
        self._last = float("-inf")  # the first line always prints
        self._tty = hasattr(self.stream, "isatty") and self.stream.isatty()

    def __call__(self, fraction: float, message: str) -> None:
        now = time.monotonic()
        if fraction < 1.0 and now - self._last < self.min_interval:
            return
        self._last = now
        line = f"[ease] {fraction * 100:3.0f}% {message}"
        if self._tty:
            self.stream.write("\r\033[K" + line + ("\n" if fraction >= 1.0 else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
