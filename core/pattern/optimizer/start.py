"""A solve's start from an earlier pattern of the same cut (:func:`pattern_start`)."""

from __future__ import annotations

from typing import Optional, Sequence, Tuple

import numpy as np


def pattern_start(
    blocks,
    uv: Sequence[np.ndarray],
    uv0: np.ndarray,
    offsets: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None,
    own: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None,
) -> np.ndarray:
    """The unknowns (n, 2) of a flip-free pattern, each piece re-centred on its initial position.

    Parameters
    ----------
    blocks : the solver's stacked panels (:class:`.panels.PanelBlocks`: ``panels``, ``panel_slices``).
    uv : per panel, in ``blocks.panels`` order, the pattern's (n_p, 2) piece coordinates, m.
    uv0 : (n, 2) float, the initial flattening the solve starts from otherwise, m.
    offsets : (K, weft lengths (f,), warp lengths (f,)) of the body the solve is on (a transfer's
        target, :meth:`.solver.PatternSolver.offsets`), or None.
    own : the same of the body the pattern lies on (needed with ``offsets``).

    With ``offsets``, each piece is also stretched along its weft (x) and its warp (y) by the
    ratio of the target body's weft and warp offset lengths under it to those of the pattern's
    own body (area-weighted means): an affine image of a flip-free piece, so flip-free, that
    starts the solve at the new body's lengths rather than the old one's. The planned
    iterations do not converge a transfer, so the start shows in the result: a lower warp
    deviation and fewer refactorisations of the collapse guard than from the unstretched
    pattern (measured: ``benchmarks/results/pattern_kernels_history.md``).
    """
    U = np.concatenate([np.asarray(x, float) for x in uv])
    out = U.copy()
    for pd in blocks.panels:
        sl, fs = blocks.panel_slices(pd)
        centre = U[sl].mean(axis=0)
        if offsets is None:
            out[sl] = U[sl] - centre + uv0[sl].mean(axis=0)
            continue
        (_, lw, lg), (_, lw0, lg0) = offsets, own
        w = np.abs(pd.area0)
        stretch = np.array([np.sum(w * lw[fs]) / np.sum(w * lw0[fs]), np.sum(w * lg[fs]) / np.sum(w * lg0[fs])])
        out[sl] = (U[sl] - centre) * stretch + uv0[sl].mean(axis=0)
    return out
