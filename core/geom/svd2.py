"""Closed-form signed SVD of stacks of 2 x 2 matrices, and its clamping of singular values.

``numpy.linalg.svd`` / ``inv`` on a stack of a few 2 x 2 matrices costs
milliseconds per call through LAPACK's dispatch (the collapse guard calls it
every iteration); the closed form is a handful of element-wise operations on
4 (k,) arrays, like the rest of the per-triangle algebra (``a00, a01, a10, a11``
as :func:`core.geom.strain.components` gives them).

A 2 x 2 matrix ``A = R(phi) diag(s1, s2) R(theta)`` with rotations ``R`` (det +1),
``s1 >= |s2|`` and ``s2 < 0`` exactly when ``A`` reflects (the *signed* SVD).
"""

from __future__ import annotations

from typing import List, Sequence, Tuple

import numpy as np


def hypot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``sqrt(x**2 + y**2)`` element-wise (a new array), within an ulp of ``numpy.hypot``.

    ``numpy.hypot`` calls libm's ``hypot`` once per element, which scales its
    operands against overflow: ~15 ns an element on this project's x86 hosts
    against ~2 ns for the three vectorised passes here (a solver iteration on
    the shirt's 21.6k triangles takes six of them: ~1.9 of its ~9 ms). The
    values it serves (2x2 Jacobian entries, scale factors, offsets in metres)
    lie many decades inside the range where the squares neither overflow nor
    underflow.
    """
    r = np.multiply(x, x)
    r += np.multiply(y, y)
    return np.sqrt(r, out=r)


def _halves(A: Sequence[np.ndarray]):
    """(e, f, g, h) of ``A``: its conformal part (e, h) and anti-conformal part (f, g)."""
    a00, a01, a10, a11 = (np.asarray(a, float) for a in A)
    out = [a00 + a11, a00 - a11, a10 + a01, a10 - a01]
    for x in out:
        x *= 0.5  # 0.5 (a + b), in the sum's own array
    return out


def signed_singular_values2(A: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
    """(s1, s2) (k,) of 2 x 2 matrices given as 4 (k,) arrays: ``s1 >= |s2|``, ``s2 < 0`` for a
    reflection (:func:`signed_svd2` without the rotations)."""
    e, f, g, h = _halves(A)
    q, r = hypot(e, h), hypot(f, g)
    s1 = q + r
    q -= r
    return s1, q


def signed_svd2(A: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The signed SVD of 2 x 2 matrices given as 4 (k,) arrays a00, a01, a10, a11.

    Returns
    -------
    s1, s2 : (k,) the singular values, ``s1 >= |s2|``, ``s2 < 0`` for a reflection.
    phi, theta : (k,) radians, ``A = R(phi) diag(s1, s2) R(theta)``.
    """
    e, f, g, h = _halves(A)
    q, r = hypot(e, h), hypot(f, g)
    a1, a2 = np.arctan2(g, f), np.arctan2(h, e)
    return q + r, q - r, 0.5 * (a2 + a1), 0.5 * (a2 - a1)


def compose2(s1: np.ndarray, s2: np.ndarray, phi: np.ndarray, theta: np.ndarray) -> List[np.ndarray]:
    """``R(phi) diag(s1, s2) R(theta)`` as 4 (k,) arrays a00, a01, a10, a11."""
    cp, sp_ = np.cos(phi), np.sin(phi)
    ct, st = np.cos(theta), np.sin(theta)
    # R(phi) diag(s) = [[cp s1, -sp s2], [sp s1, cp s2]]; times R(theta) = [[ct, -st], [st, ct]]
    return [
        cp * s1 * ct - sp_ * s2 * st,
        -cp * s1 * st - sp_ * s2 * ct,
        sp_ * s1 * ct + cp * s2 * st,
        -sp_ * s1 * st + cp * s2 * ct,
    ]


def clamp_singular_values_below(A: Sequence[np.ndarray], floor: float) -> List[np.ndarray]:
    """``A`` with both signed singular values raised to at least ``floor`` (> 0), rotations kept.

    A reflection (``s2 < 0``) is unfolded: its negative singular value becomes
    ``floor``. A matrix whose singular values are both at least ``floor`` comes back unchanged
    (to round-off).
    """
    s1, s2, phi, theta = signed_svd2(A)
    return compose2(np.maximum(s1, floor), np.maximum(s2, floor), phi, theta)


__all__ = ["hypot", "signed_singular_values2", "signed_svd2", "compose2", "clamp_singular_values_below"]
