"""Area-weighted statistics shared by the pattern metrics (``docs/metrics.md``, "Weighting")."""

from __future__ import annotations

from typing import Dict

import numpy as np


def _finite(values, weights):
    v = np.asarray(values, float)
    w = np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    return v[ok], w[ok]


def weighted_mean(values: np.ndarray, weights: np.ndarray) -> float:
    """The area-weighted mean of ``values`` (``weighted_stats(values, weights)["mean"]``, the same
    float, without the sort that the percentile needs)."""
    v, w = _finite(values, weights)
    return float(np.sum(w * v) / np.sum(w)) if v.size else float("nan")


def weighted_stats(values: np.ndarray, weights: np.ndarray) -> Dict[str, float]:
    """Area-weighted mean, std and 95th percentile of ``values``."""
    v, w = _finite(values, weights)
    if v.size == 0:
        return {"mean": float("nan"), "std": float("nan"), "p95": float("nan"), "max": float("nan")}
    mean = float(np.sum(w * v) / np.sum(w))
    std = float(np.sqrt(np.sum(w * (v - mean) ** 2) / np.sum(w)))
    order = np.argsort(v)
    cw = np.cumsum(w[order]) / np.sum(w)
    p95 = float(v[order][min(np.searchsorted(cw, 0.95), v.size - 1)])
    return {"mean": mean, "std": std, "p95": p95, "max": float(v.max())}
