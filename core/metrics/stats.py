"""Area-weighted statistics shared by the pattern metrics (``docs/metrics.md``, "Weighting")."""
from __future__ import annotations

from typing import Dict

import numpy as np


def weighted_stats(values: np.ndarray, weights: np.ndarray) -> Dict[str, float]:
    """Area-weighted mean, std and 95th percentile of ``values``."""
    v = np.asarray(values, float)
    w = np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    v, w = v[ok], w[ok]
    if v.size == 0:
        return {"mean": float("nan"), "std": float("nan"), "p95": float("nan"), "max": float("nan")}
    mean = float(np.sum(w * v) / np.sum(w))
    std = float(np.sqrt(np.sum(w * (v - mean) ** 2) / np.sum(w)))
    order = np.argsort(v)
    cw = np.cumsum(w[order]) / np.sum(w)
    p95 = float(v[order][min(np.searchsorted(cw, 0.95), v.size - 1)])
    return {"mean": mean, "std": std, "p95": p95, "max": float(v.max())}
