"""core.progress: progress callbacks, sub-ranges, and the CLI progress line."""

import io

import pytest

from core.errors import Cancelled
from core.progress import ConsoleProgress, report, sub


def test_report_clamps_and_sub_maps_into_the_parent_range():
    seen = []
    cb = lambda f, m: seen.append((round(f, 6), m))
    report(cb, 1.5, "over")
    report(cb, -1, "under")
    inner = sub(cb, 0.2, 0.6)
    report(inner, 0.5, "half of the middle stage")
    assert seen == [(1.0, "over"), (0.0, "under"), (0.4, "half of the middle stage")]
    report(None, 0.5, "no callback is fine")
    assert sub(None, 0, 1) is None


def test_console_progress_line_and_throttle():
    s = io.StringIO()
    p = ConsoleProgress(stream=s, min_interval=3600)
    p(0.0, "cutting")
    p(0.5, "throttled away")
    p(1.0, "done")  # the final line always prints
    assert s.getvalue().splitlines() == ["[ease]   0% cutting", "[ease] 100% done"]


def test_a_callback_cancels_by_raising():
    def cb(f, m):
        if f > 0.3:
            raise Cancelled()

    with pytest.raises(Cancelled):
        for i in range(10):
            report(cb, i / 10, "step")
