"""A transfer's targets bridge the folds of the target body's skin (:func:`bridge_folds`).

A heavier body's skin folds where a curve overhangs it: under women:XL's bust (the inframammary
crease) the cut triangles that are the cloth's shape on the reference body (women:M) lie squeezed
to 6-9 % of their height there (the smaller stretch from their M shape: 0.085, 0.057 with the
darts' apexes following the cup; 3XL 0.094, 4XL 0.053; XS..L at least 0.29; every other template
on its chart's XS..XL at least 0.448). Cloth does not follow skin into such a fold: it bridges it,
as the skirt's membrane spans the gluteal cleft
(:mod:`core.cut.span`). Taken literally, those targets ask the pattern to shorten a band under the
bust by up to 16 x: the four-dart blouse transferred to women:XL at ease 1.3 with ``improved`` at
200 iterations (and with warp slack 0) started with 10 triangles over 10 x their targets there and
was refused as diverged after 215 iterations: the band pulls the cloth below the bust dart up into
it, the gap step holds the dart's legs apart, and the collapse guard, holding the cloth squeezed
between them (300-400 triangles), pushes the squeeze on into triangles it does not hold, until some
of them are stretched past 10 x (with the guard and the weft feedback both off it settled at
1.5 x). An exact projection of the gap step (only the pairs under
their bound, only across the dart) ran away the same way.

So the solve's target of a triangle on another body is its reference-body shape stretched by at
least :data:`FOLD_FLOOR` in every direction: ``K' = F' K_ref`` with ``F = K K_ref^-1`` and ``F'``
its singular values floored. Nothing else changes: the measured figures stay those of the skin
(:mod:`core.metrics`, from the target body's positions), and a transfer with no triangle squeezed
that far (every template's XS..XL but the blouses' women:L and XL, the reference solve, every
adaptation) is the same bits.

A transfer that would still be refused (diverged, a dart's legs crossed or not sewn equal: the women:M
reference at ease 1.3 transferred to women:3XL and 4XL) is solved again with the floor raised to each of
:data:`RETRY_FLOORS` in turn (:meth:`.solver.PatternSolver.solve`); a floor of 0.5 for every transfer would
move women:XS and L, which solve at 0.3 (docs/patterns.md).
"""

from __future__ import annotations

import numpy as np

#: the least stretch (a singular value of the map from a triangle's reference-body shape to its
#: target-body shape) a transfer's solve asks of a triangle (the module). At 0.25 the four-dart blouse
#: transferred to women:XL at ease 1.1 with warp slack 0 still ran away in its extra rounds (a triangle
#: at 0.28, held by the collapse guard at its top gain); at 0.3 every XL case solves (docs/patterns.md)
#: and women:L has 2 triangles floored (0.293)
FOLD_FLOOR = 0.3
#: the floors a transfer's solve is tried again with, in turn, while it would be refused (diverged, or a
#: dart's legs crossed or not sewn equal) and the floor changes a target (:meth:`.solver.PatternSolver.solve`):
#: a solve that is not refused is never tried again, so every size that solves at :data:`FOLD_FLOOR` keeps its bits.
#: The four-dart blouse's women:M reference (fitted) transferred to women:3XL (ease 1.1, 1.3) and 4XL (1.1) diverged
#: at 0.3 and 4XL @ 1.3 ended with its legs 9.8 mm apart; all four solve at 0.5. 0.7 is for a cut 0.5 does not
#: bridge: with the cut's bust work in progress (2026-12-07), 3XL @ 1.3 diverged at 0.5 and 0.6 and solved at 0.7
RETRY_FLOORS = (0.5, 0.7)


def smaller_stretch(F: np.ndarray) -> np.ndarray:
    """(f,) the smaller singular value of each 2 x 2 map ``F`` (f, 2, 2) (closed form)."""
    a, b, c, d = F[:, 0, 0], F[:, 0, 1], F[:, 1, 0], F[:, 1, 1]
    frob = a * a + b * b + c * c + d * d
    det = a * d - b * c
    disc = np.sqrt(np.maximum(frob * frob - 4.0 * det * det, 0.0))
    return np.sqrt(np.maximum(0.5 * (frob - disc), 0.0))


def bridge_folds(K: np.ndarray, K_ref: np.ndarray, floor: float = FOLD_FLOOR) -> np.ndarray:
    """``K`` (f, 2, 2), a body's intrinsic offsets, with each triangle stretched from its reference-body shape
    ``K_ref`` (f, 2, 2) by at least ``floor`` in every direction (a new array), or ``K`` itself where
    every triangle is (the module)."""
    det = K_ref[:, 0, 0] * K_ref[:, 1, 1] - K_ref[:, 0, 1] * K_ref[:, 1, 0]
    ok = np.abs(det) > 0
    if not np.all(ok):  # a degenerate reference triangle has no shape to stretch: its target kept
        det = np.where(ok, det, 1.0)
    inv = np.empty_like(K_ref)
    inv[:, 0, 0], inv[:, 0, 1] = K_ref[:, 1, 1] / det, -K_ref[:, 0, 1] / det
    inv[:, 1, 0], inv[:, 1, 1] = -K_ref[:, 1, 0] / det, K_ref[:, 0, 0] / det
    F = K @ inv
    low = np.flatnonzero(ok & (smaller_stretch(F) < floor))
    if not len(low):
        return K
    u, s, vt = np.linalg.svd(F[low])
    out = K.copy()
    out[low] = ((u * np.maximum(s, floor)[:, None, :]) @ vt) @ K_ref[low]
    return out
