"""Sewing patterns that realise the painted ease.

- :mod:`.types`: the plain-data :class:`Pattern` (pieces, seams, targets, achieved scales).
- :mod:`.solve`: :class:`PatternSolver` (LSCM start, local-global ease optimizer, factorised
  once per cut) and :func:`solve_pattern`, :func:`transfer_pattern`, :func:`adapt_pattern`.
- :mod:`.io`: :func:`save_pattern` / :func:`load_pattern` (``pattern.json``).
- :mod:`.cli`: ``ease pattern``, ``ease transfer``, ``ease adapt``; :mod:`.plot`: the PNG.

Submodules import numpy/scipy/igl when used; this package import stays light.
"""
from .types import Pattern, PatternPanel, PatternSeam


def __getattr__(name):
    # lazy re-exports: ``from core.pattern import solve_pattern`` without importing scipy up front
    if name in ("PatternSolver", "SolverConfig", "solve_pattern", "transfer_pattern", "adapt_pattern",
                "build_pattern"):
        from . import solve
        return getattr(solve, name)
    if name in ("save_pattern", "load_pattern"):
        from . import io
        return getattr(io, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Pattern", "PatternPanel", "PatternSeam", "PatternSolver", "SolverConfig", "solve_pattern",
           "transfer_pattern", "adapt_pattern", "build_pattern", "save_pattern", "load_pattern"]
