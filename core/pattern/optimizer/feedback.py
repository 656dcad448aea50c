"""The targets' feedback between local-global iterations (:func:`move_corrections`).

The linear solve lands short of a target where the body's curvature pulls
against it; multiplying the target by a correction that follows the
achieved/target ratio makes the next solve land on the wanted scale wherever
curvature allows it. A pose adaptation aims instead at the scales its poses
demand (paper Eq. adapt-scale) and only ever adds cloth.
"""

from __future__ import annotations

from typing import Optional, Tuple

import numpy as np

from ...geom.strain import scales_of_offsets
from ..accel import compiled


def feedback_gains(cfg, adapting: bool) -> Tuple[float, float, float, float, float]:
    """(weft gain, warp gain, lowest factor, highest factor per iteration, ceiling) of ``cfg``'s feedback.

    An adaptation uses the larger of the feedback's and the adaptation's gains, and lowers a
    correction by at most ``adaptation.lower`` of a step: a correction lowered where a triangle is
    already past its goal pulls it against its raised neighbours, which is shear.
    """
    fb, ad = cfg.feedback, cfg.adaptation
    gain_w = max(fb.weft, ad.gain) if adapting else fb.weft
    gain_g = max(fb.warp, ad.gain if ad.warp_gain is None else ad.warp_gain) if adapting else fb.warp
    step = ad.step if adapting else fb.step
    lower = 1 - ad.lower * step if adapting else 1 - step
    return gain_w, gain_g, lower, 1 + step, (ad.ceiling if adapting else fb.ceiling)


def move_corrections(
    cfg,
    M: list,
    Kc: list,
    c_weft: np.ndarray,
    c_warp: np.ndarray,
    corr_w: np.ndarray,
    corr_g: np.ndarray,
    poses: Optional[dict] = None,
    targets_finite: Optional[np.ndarray] = None,
) -> None:
    """Move the weft and warp corrections ``corr_w``, ``corr_g`` (f,) in place by the achieved/target ratio.

    Parameters
    ----------
    cfg : SolverConfig (its ``feedback`` and ``adaptation`` groups).
    M : the iterate's Jacobians, 4 (f,) arrays; Kc : the body's intrinsic offsets, 4 (f,) arrays.
    c_weft, c_warp : (f,) the solve's targets (a reference or transfer solve aims at them).
    poses : an adaptation's demands (``ease_weft``, ``ease_warp``, ``offsets`` per pose, ``margin``,
        ``eps_weft``, ``eps_warp``), or None.
    targets_finite : (f,) bool, ``isfinite(c_weft) & isfinite(c_warp)`` (without poses; computed once
        per solve by the caller).
    """
    fb = cfg.feedback
    adapting = poses is not None
    gain_w, gain_g, lower, upper, hi = feedback_gains(cfg, adapting)
    done = None if adapting else compiled.ratios(M, Kc, c_weft, c_warp)
    if done is not None:
        where = slice(None)  # the kernel's ratios: every triangle moves (else numpy's below)
        ratio_w, ratio_g = done
    else:
        where, ratio_w, ratio_g = _ratios(cfg, M, Kc, c_weft, c_warp, gain_w, gain_g, poses, targets_finite)
    # the power is numpy's (its own SIMD routine, not libm's); the clips and products the kernel's where the
    # whole arrays move, numpy's otherwise
    p_w = ratio_w**gain_w if gain_w > 0 else None
    p_g = ratio_g**gain_g if gain_g > 0 else None
    if isinstance(where, slice) and compiled.corrections(p_w, p_g, corr_w, corr_g, lower, upper, fb.floor, hi):
        return
    if p_w is not None:
        corr_w[where] *= np.clip(p_w, lower, upper)
    if p_g is not None:
        corr_g[where] *= np.clip(p_g, lower, upper)
    np.clip(corr_w, fb.floor, hi, out=corr_w)
    np.clip(corr_g, fb.floor, hi, out=corr_g)


def _ratios(cfg, M, Kc, c_weft, c_warp, gain_w, gain_g, poses, targets_finite):
    """numpy's (where, goal / rho weft, warp) of :func:`move_corrections`: ``where`` the triangles the
    feedback moves (a full slice when all do), the ratios on them (None for a gain of 0)."""
    ad = cfg.adaptation
    adapting = poses is not None
    rw, rg = scales_of_offsets(M, Kc)
    goal_w, goal_g = c_weft, c_warp
    if adapting:
        goal_w, goal_g = poses["ease_weft"].copy(), poses["ease_warp"].copy()
        for Kp in poses["offsets"]:
            # stretch of the pose along the current weft/warp: rho-hat on the reference over rho-hat on the pose
            pw, pg = scales_of_offsets(M, Kp)
            with np.errstate(divide="ignore", invalid="ignore"):
                goal_w = np.fmax(goal_w, poses["margin"] * rw / pw / poses["eps_weft"])
                goal_g = np.fmax(goal_g, poses["margin"] * rg / pg / poses["eps_warp"])
        goal_w = goal_w if ad.cap_weft is None else np.fmin(goal_w, ad.cap_weft * poses["ease_weft"])
        goal_g = goal_g if ad.cap_warp is None else np.fmin(goal_g, ad.cap_warp * poses["ease_warp"])
    if targets_finite is None and not adapting:
        targets_finite = np.isfinite(c_weft) & np.isfinite(c_warp)
    ok = (
        np.isfinite(rw)
        & np.isfinite(rg)
        & (rw > 0)
        & (rg > 0)
        & (targets_finite if not adapting else np.isfinite(goal_w) & np.isfinite(goal_g))
    )
    # every triangle is usually valid: the whole arrays then, the same values without the masked copies
    where = slice(None) if ok.all() else ok
    return (where, goal_w[where] / rw[where] if gain_w > 0 else None, goal_g[where] / rg[where] if gain_g > 0 else None)
