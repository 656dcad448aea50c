"""Sewing patterns that realise the painted ease.

- :mod:`.types`: the plain-data :class:`Pattern` (pieces, seams, targets, achieved scales).
- :mod:`.solve`: the entry points :func:`solve_pattern`, :func:`transfer_pattern`,
  :func:`adapt_pattern` (and :func:`build_pattern`).
- :mod:`.config` (:class:`SolverConfig`, the presets), :mod:`.validate` (input checks),
  :mod:`.build` (a pattern assembled from a solve).
- :mod:`.optimizer`: the local-global solve. :mod:`.optimizer.solver`: :class:`PatternSolver`
  (LSCM start, ease optimizer, factorised once per cut); its parts: :mod:`.optimizer.panels`
  and :mod:`.optimizer.init` (the flattening), :mod:`.optimizer.targets`,
  :mod:`.optimizer.seams` (seam layout, :class:`SeamPlan`, seam terms),
  :mod:`.optimizer.steps` (local step, flip guard, grain re-alignment),
  :mod:`.optimizer.state` (a solve between iterations), :mod:`.optimizer.start` (a start from
  an earlier pattern), :mod:`.optimizer.dart_gaps`, :mod:`.optimizer.feedback`,
  :mod:`.optimizer.guard`, :mod:`.optimizer.factor`.
- :mod:`.accel`: the same steps compiled (Warp CPU kernels with numpy's bits), one seam.
- :mod:`.io`: :func:`save_pattern` / :func:`load_pattern` (``pattern.json``); :mod:`.plot`: the PNG.

Submodules import numpy/scipy/igl when used; this package import stays light.
"""

from .types import Pattern, PatternPanel, PatternSeam

_SOLVE = (
    "PatternSolver",
    "SolverConfig",
    "SeamPlan",
    "solve_pattern",
    "transfer_pattern",
    "adapt_pattern",
    "build_pattern",
)


def __getattr__(name):
    # lazy re-exports: ``from core.pattern import solve_pattern`` without importing scipy up front
    if name in _SOLVE:
        from . import solve

        return getattr(solve, name)
    if name in ("save_pattern", "load_pattern"):
        from . import io

        return getattr(io, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Pattern", "PatternPanel", "PatternSeam", *_SOLVE, "save_pattern", "load_pattern"]
