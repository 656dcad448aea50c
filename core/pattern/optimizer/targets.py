"""Per-triangle targets of the optimizer (paper Eqs. ref-scale, transfer-scale, adapt-scale, material-scale).

With ``K`` (f, 2, 2) the intrinsic 2D coordinates of a body's 3D weft/warp
offsets (:func:`core.geom.strain.intrinsic_offsets`) and target scales
``c = |sigma*_2D| / |sigma_3D|``, ``D = diag(c_weft, c_warp)``:

- reference / transfer: ``c = (rho_weft, 1)`` on the reference or the target body;
- adaptation: per direction ``max(rho sigma_ref, max_i (1 + margin) sigma_i / eps)`` over the poses.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from ...errors import PatternError
from ...geom.strain import components


def rest_targets(
    K, c_weft: np.ndarray, c_warp: Optional[np.ndarray], model: str, warp_from: Optional[dict] = None
) -> dict:
    """Ease target ``T`` and the regulariser's rest shape ``diag(D) R K'``, as component arrays.

    ``K``: the intrinsic offsets (f, 2, 2), or their 4 components (f,)
    (:func:`core.geom.strain.components`; the iterations pass the ones they
    already have). ``model == "prestretch"`` (improved): ``T = diag(c) K``, the
    scales act along the pattern's weft/warp axes after the rotation (``J = Q
    R^T diag(1/c)``: exact weft scale and no shear for any local rotation
    ``R``), and the rest shape is the pre-stretched ``diag(c) R K``.
    ``"isometric"`` (paper, literal): ``T = K diag(c)``, the scales act on the
    initial flattening's barycentric offsets, so a local rotation of a
    stretched triangle turns its stretch off the weft (shear and compliance
    error that grow with rho); the rest shape is the isometric ``R K``.
    Returns ``{"T": 4 (f,) arrays t00, t01, t10, t11, "reg": (d_weft (f,), d_warp (f,), K' as 4 (f,)
    arrays)}``: one product per entry, the same values as the (f, 2, 2) products.

    ``warp_from``: an earlier result of the same ``K`` and ``model`` whose warp scales equal
    ``c_warp`` (then None): its products by them are taken over, not recomputed (the same
    arrays: the feedback moves the weft targets every iteration, the warp's only with a warp gain).
    """
    # the caller's component list itself: the local step keeps its K-only products while it is the same list
    k = components(K) if isinstance(K, np.ndarray) else K
    cw = np.asarray(c_weft, float)
    if warp_from is not None:
        T = warp_from["T"]
        if model == "prestretch":
            return {"T": [cw * k[0], cw * k[1], T[2], T[3]], "reg": (cw, warp_from["reg"][1], k)}
        return {"T": [k[0] * cw, T[1], k[2] * cw, T[3]], "reg": warp_from["reg"]}
    cg = np.asarray(c_warp, float)
    if model == "prestretch":
        return {"T": [cw * k[0], cw * k[1], cg * k[2], cg * k[3]], "reg": (cw, cg, k)}
    one = np.ones_like(cw)
    return {"T": [k[0] * cw, k[1] * cg, k[2] * cw, k[3] * cg], "reg": (one, one, k)}


def reference_ease(design_ease: np.ndarray, ease=None) -> np.ndarray:
    """The weft targets (f,) of a reference or transfer solve: the design's ``design_ease`` (f,), or
    ``ease`` (a scalar or (f,): benchmarks sweep it) when given."""
    if ease is None:
        return design_ease.copy()
    ease = np.broadcast_to(np.asarray(ease, float), design_ease.shape).copy()
    if not np.all(np.isfinite(ease) & (ease > 0)):
        raise PatternError("ease override: expected finite weft scales > 0")
    return ease


def adaptation_scales(
    ease: np.ndarray,
    len_weft: np.ndarray,
    len_warp: np.ndarray,
    pose_lengths: Sequence[tuple],
    eps_weft: float,
    eps_warp: float,
    margin: float,
    cap_weft: float = np.inf,
    cap_warp: float = np.inf,
):
    """Target scales (c_weft, c_warp) (f,) of Eq. material-scale.

    Parameters
    ----------
    ease : (f,) the design's weft ease.
    len_weft, len_warp : (f,) the reference body's offset lengths |sigma_ref|.
    pose_lengths : per pose the pair (len_weft, len_warp) (f,) on that pose.
    eps_weft, eps_warp : the stretch tolerances (>= 1).
    margin : fraction the pose demands are raised by before the tolerance applies.
    cap_weft, cap_warp : most a target may be raised, as a multiple of the design's (ease, 1): where a
        pose stretches the skin by several times (the armpit with the arm raised) no flat cloth follows.
    """
    want_w = ease * len_weft
    want_g = 1.0 * len_warp
    m = 1.0 + margin
    for lwi, lgi in pose_lengths:
        want_w = np.maximum(want_w, m * lwi / eps_weft)
        want_g = np.maximum(want_g, m * lgi / eps_warp)
    with np.errstate(divide="ignore", invalid="ignore"):
        cw = np.where(len_weft > 0, want_w / len_weft, ease)
        cg = np.where(len_warp > 0, want_g / len_warp, 1.0)
    return np.minimum(cw, cap_weft * ease), np.minimum(cg, cap_warp)
