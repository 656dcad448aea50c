"""The gap-curve benchmark's choices (benchmarks/bench_drape.py; SPEC item 6): no drape is run here."""

import importlib.util
from pathlib import Path

import numpy as np

from core.drape.materials import get_material


def _bench():
    path = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_drape.py"
    spec = importlib.util.spec_from_file_location("bench_drape_for_tests", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_negative_ease_levels_need_the_stretch_fabric():
    # the tightest level's pattern is this much smaller than the body: the woven gap fabric cannot take
    # it within its own limit, the second curve's stretch fabric can
    bd = _bench()
    deficit = 1.0 / float(np.min(bd.LEVELS)) - 1.0
    assert np.min(bd.LEVELS) < 1.0 and len(bd.LEVELS) == 17
    assert get_material(bd.GAP_FABRIC).max_stretch < deficit < get_material(bd.STRETCH_FABRIC).max_stretch


def test_the_second_curve_takes_the_stretch_rows_below_ease_1_only():
    bd = _bench()
    cotton = [{"ease": e, "gap_mean_mm": g} for e, g in ((0.9, 4.0), (0.994, 3.3), (1.087, 5.3), (1.181, 8.4))]
    jersey = [{"ease": e, "gap_mean_mm": g} for e, g in ((0.9, 2.8), (0.994, 3.1))]
    both = bd.combined(cotton, jersey)
    assert [(r["ease"], r["gap_mean_mm"]) for r in both] == [(0.9, 2.8), (0.994, 3.1), (1.087, 5.3), (1.181, 8.4)]
    assert bd.monotonic([r["gap_mean_mm"] for r in both])
    assert not bd.monotonic([r["gap_mean_mm"] for r in cotton])
    assert bd._worst_step(cotton).startswith(" (smallest step -0.70 mm, at ease 0.994")
