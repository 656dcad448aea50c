"""Left/right names of design elements: ``*_left`` <-> ``*_right``.

A name is mirrored by its side suffix (``sleeve_left``) or an inner side word
(``arm_left_front``); midline names (``front``, ``neck_back``) have no side.
Plain strings only, so the design types, the checks and the resolver share
one rule.
"""

from __future__ import annotations

from typing import Optional


def mirrored_name(name: str) -> Optional[str]:
    """``"sleeve_left"`` -> ``"sleeve_right"``; None when the name has no ``_left``."""
    if name.endswith("_left"):
        return name[: -len("_left")] + "_right"
    if "_left_" in name:
        return name.replace("_left_", "_right_", 1)
    return None


def swap_side(name: str) -> str:
    """Swap ``_left``/``_right`` in a reference name (midline names are kept)."""
    if name.endswith("_left"):
        return name[:-5] + "_right"
    if name.endswith("_right"):
        return name[:-6] + "_left"
    if "_left_" in name:
        return name.replace("_left_", "_right_", 1)
    if "_right_" in name:
        return name.replace("_right_", "_left_", 1)
    return name


def side_of(name: str) -> Optional[str]:
    """``"left"`` or ``"right"``: the side a name is on by :func:`swap_side`'s rule (suffix first,
    then an inner side word); None for a midline name."""
    for side in ("left", "right"):
        if name.endswith("_" + side):
            return side
    for side in ("left", "right"):
        if f"_{side}_" in name:
            return side
    return None


_AXIS_FLIP = {"x": "-x", "+x": "-x", "-x": "x"}


def mirror_axis(axis: str) -> str:
    """An axis name reflected through the body's symmetry plane (x -> -x; y, z kept)."""
    return _AXIS_FLIP.get(axis, axis)
