"""Runtime state: the caches of what is expensive and deterministic to rebuild.

Body models, the current cut and parsed patterns are kept here for the
session; what must survive a save lives in the scene (see :mod:`.properties`
and :mod:`.data`). The pipeline itself is the core's (:mod:`core.workflows`).
"""

from __future__ import annotations

from ..core.errors import Cancelled, EaseError


class AddonError(EaseError):
    """A user error detected by the add-on itself (e.g. no body in the scene)."""


USER_ERRORS = (EaseError, Cancelled, KeyError, ValueError, OSError)

_MODELS: dict = {}
CUTS: dict = {}  # (design text, body model, shape json) -> GarmentCut (data.cut_on), the newest last
CUTS_KEPT = 3  # a design being replaced, the new one and Live's: a switch never cuts one twice
PATTERNS: dict = {}  # (scene name, key) -> (pattern json text, Pattern)
BUGS: list = []  # (operator, traceback) of every exception an operator caught that is no user error


#: callbacks ``f(scene)`` told that something the pattern follows may have changed (Live registers
#: its own: operators and sync reach it through :func:`changed` without importing it)
ON_CHANGE: list = []


def changed(scene) -> None:
    """Tell the :data:`ON_CHANGE` callbacks that ``scene`` may have changed."""
    for f in ON_CHANGE:
        f(scene)


def keep_cut(key, cut) -> None:
    """Keep ``cut`` under ``key`` in :data:`CUTS`, the oldest dropped beyond :data:`CUTS_KEPT`
    (memory stays bounded). Safe beside a reader on another thread (one dict operation each)."""
    CUTS.pop(key, None)
    CUTS[key] = cut
    while len(CUTS) > CUTS_KEPT:
        CUTS.pop(next(iter(list(CUTS))), None)


def clear() -> None:
    _MODELS.clear()
    CUTS.clear()
    PATTERNS.clear()


def body_model(name: str):
    """The body model ``name`` (``"anny"`` or a file path), loaded once."""
    if name not in _MODELS:
        from ..core.body import load_body

        _MODELS[name] = load_body(name)
    return _MODELS[name]
