"""The ease colour ramp: ease value <-> colour of the body's "ease" layer.

Pure numpy, no bpy, so it is tested without Blender.

The ramp is linear in scene-linear RGB: ``t = (ease - lo) / (hi - lo)`` goes
into red, ``1 - t`` into blue, green is a constant. Blender's brushes mix
colours linearly in the layer (a float colour attribute holds scene-linear
values), so a blended stroke edge ``(1 - a) c0 + a c1`` still has
``R + B = 1`` and decodes to the in-between ease ``(1 - a) e0 + a e1``.
Decoding uses ``t = R / (R + B)``, which is also immune to a brush strength
that darkens or brightens the colour uniformly.
"""

from __future__ import annotations

import numpy as np

from ..core.design.checks import EASE_MAX, EASE_MIN

GREEN = 0.08  # constant green of the ramp (keeps the mid tones purple, not grey)
EASE_LIMITS = (EASE_MIN, EASE_MAX)  # the range the design format accepts


def check_range(lo: float, hi: float) -> None:
    """Raise ValueError unless ``EASE_LIMITS[0] <= lo < hi <= EASE_LIMITS[1]``."""
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ValueError(f"ease ramp range must have min < max, got {lo} .. {hi}")
    if lo < EASE_LIMITS[0] or hi > EASE_LIMITS[1]:
        raise ValueError(f"ease ramp range {lo} .. {hi} must lie within {EASE_LIMITS[0]} .. {EASE_LIMITS[1]}")


def ease_to_color(ease, lo: float, hi: float) -> np.ndarray:
    """Scene-linear RGBA colours of ease values.

    Parameters
    ----------
    ease : (n,) or scalar float, weft scale; clamped to [lo, hi].
    lo, hi : float, the ramp's range (ease at pure blue and at pure red).

    Returns
    -------
    (n, 4) float32 (or (4,) for a scalar) RGBA in [0, 1], alpha 1.
    """
    check_range(lo, hi)
    e = np.asarray(ease, dtype=np.float64)
    t = np.clip((e - lo) / (hi - lo), 0.0, 1.0)
    rgba = np.empty(t.shape + (4,), dtype=np.float64)
    rgba[..., 0] = t
    rgba[..., 1] = GREEN
    rgba[..., 2] = 1.0 - t
    rgba[..., 3] = 1.0
    return rgba.astype(np.float32)


def color_to_ease(rgba, lo: float, hi: float, default: float = 1.0) -> np.ndarray:
    """Ease values of scene-linear colours written with :func:`ease_to_color`
    (or blended from such colours by a brush).

    Parameters
    ----------
    rgba : (n, 3) or (n, 4) float, scene-linear colours.
    lo, hi : float, the ramp's range.
    default : float, ease where the colour carries no ramp information
        (``R + B`` about 0, e.g. a black layer).

    Returns
    -------
    (n,) float64 ease.
    """
    check_range(lo, hi)
    c = np.asarray(rgba, dtype=np.float64)
    s = c[..., 0] + c[..., 2]
    ok = s > 1e-6
    t = np.where(ok, c[..., 0] / np.where(ok, s, 1.0), 0.0)
    return np.where(ok, lo + np.clip(t, 0.0, 1.0) * (hi - lo), default)


def linear_to_srgb(c) -> np.ndarray:
    """sRGB transfer function (for Blender versions whose brush colour is
    display-referred, ``COLOR_GAMMA``; Blender 5 uses scene-linear)."""
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)


def srgb_to_linear(c) -> np.ndarray:
    c = np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, np.power((c + 0.055) / 1.055, 2.4))


def vertex_to_triangle(values: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per-triangle mean of per-vertex values: (V,) -> (F,) for faces (F, 3)."""
    return np.asarray(values, dtype=np.float64)[np.asarray(faces)].mean(axis=1)


def legend(lo: float, hi: float, n: int = 5):
    """``n`` evenly spaced (ease, rgba) pairs for a legend."""
    vals = np.linspace(lo, hi, n)
    return [(float(v), tuple(float(x) for x in ease_to_color(v, lo, hi))) for v in vals]
