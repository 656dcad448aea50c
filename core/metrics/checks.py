"""The checks a measured pattern must pass before anything is written.

SPEC requires zero flipped triangles in every reported pattern, issue 14
adds zero collapsed triangles (:mod:`core.metrics.collapse`) and issue 30 zero
crossings (:mod:`core.metrics.injectivity`: a piece's sew line is a simple closed
curve, its darts' legs apart from mouth to apex). Each check is
named, so the pipeline (:func:`core.workflows.measure_pattern`, used by the
CLI, the add-on, batch runs and the benchmarks' workflow calls) applies one
list, :data:`REFUSED`, and a caller can name the checks it applies.
"""

from __future__ import annotations

from typing import Iterable, Mapping, Optional

from ..errors import PatternError
from .collapse import collapse_message, site_where

#: Every check a pattern can be refused by.
CHECKS = ("flipped", "collapsed", "crossings")
#: The checks the pipeline applies: zero collapsed is required like zero flipped
#: (issue 14; the solver's collapse guard prevents it on every shipped template), and zero
#: crossings: a piece that overlaps itself cannot be cut (issue 30).
REFUSED = ("flipped", "collapsed", "crossings")
#: The checks of a live preview still converging (``report["live"]["converged"]`` false): a
#: state in between is shown with its collapse and crossing counts, not refused; once converged
#: it is a pattern like any other.
PREVIEW_REFUSED = ("flipped",)


def checks_for(pattern) -> tuple:
    """The checks the pipeline applies to ``pattern``: :data:`PREVIEW_REFUSED` for a live preview
    that has not converged yet, else :data:`REFUSED`."""
    live = (getattr(pattern, "report", None) or {}).get("live")
    if isinstance(live, dict) and not live.get("converged", True):
        return PREVIEW_REFUSED
    return REFUSED


def check_pattern(metrics: Mapping, checks: Optional[Iterable[str]] = None) -> None:
    """Raise :class:`PatternError` when the measured ``metrics`` fail one of ``checks``.

    Parameters
    ----------
    metrics : dict of :func:`core.metrics.pattern.pattern_report`.
    checks : names from :data:`CHECKS`; None applies :data:`REFUSED` (the pipeline passes
        :func:`checks_for` of the pattern).

    The message names each failing panel, and for collapse and crossings where on the body
    (nearest landmark, 3D centroid in m); for crossings also the dart or the stretches of the
    sew line that cross.
    """
    checks = tuple(REFUSED if checks is None else checks)
    unknown = [c for c in checks if c not in CHECKS]
    if unknown:
        raise ValueError(f"unknown pattern checks {unknown}; known: {', '.join(CHECKS)}")
    if "flipped" in checks and metrics["flipped_triangles"]:
        panels = ", ".join(f"{k} ({v})" for k, v in metrics["flipped_per_panel"].items() if v)
        raise PatternError(f"{metrics['flipped_triangles']} flipped triangles ({panels}); nothing written")
    if "collapsed" in checks and metrics.get("collapsed_triangles"):
        per = {
            k: {"count": n, "sites": metrics["collapse_sites"].get(k, [])}
            for k, n in metrics["collapsed_per_panel"].items()
        }
        raise PatternError(
            f"{collapse_message(per)}; nothing written (a collapsed triangle keeps under half "
            "the weft or warp its ease asks for)"
        )
    if "crossings" in checks and metrics.get("crossings"):
        raise PatternError(
            f"{crossing_message(metrics['crossing_sites'])}; nothing written (a piece that "
            "overlaps itself cannot be cut)"
        )


def _stretches(between) -> str:
    a, b = between
    if a == b:
        kind, _, name = a.partition(" ")
        return (
            f"the legs of {a} cross"
            if kind == "dart"
            else (f"the sew line crosses itself along {a}" if kind != "boundary" else "the sew line crosses itself")
        )
    return f"{a} crosses {b}"


def crossing_message(sites) -> str:
    """One line naming every piece whose sew line crosses itself, what crosses and where on the body:
    ``panel blouse.front: the legs of dart blouse.bust_dart_left cross (1 crossing) near bust_left
    (0.082, -0.105, 1.243 m)``; ``sites``: ``pattern_report(...)["crossing_sites"]``."""
    parts = []
    for name, ss in sites.items():
        for s in ss:
            n = s["count"]
            parts.append(
                f"panel {name}: {_stretches(s['between'])} ({n} crossing{'s' if n != 1 else ''}) {site_where(s)}"
            )
    return "; ".join(parts)
