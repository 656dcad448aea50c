"""Compliance near named body landmarks: where fit fails first.

The garment-wide compliance averages the bust, the shoulder blades and the
seat in with the flat side seams. The region report measures, for each named
landmark, the triangles whose 3D centroid lies within ``radius`` (straight-line
distance, m) of the landmark on the body the pattern is measured on: ease
compliance (weft), warp deviation and shear, exactly as
:func:`core.metrics.pattern.ease_compliance` defines them, plus the signed weft
mean (negative: the region gets less ease than painted). Definitions:
``docs/metrics.md``.
"""

from __future__ import annotations

from typing import Dict, Iterable, Mapping, Optional

import numpy as np

from ..geom.mesh import row_norm
from .stats import weighted_mean, weighted_stats
from .strains import panel_strain

#: The landmarks of the region report (those a body lacks are left out).
REGION_LANDMARKS = ("bust_left", "bust_right", "shoulder_blade_left", "shoulder_blade_right", "seat_left", "seat_right")
#: Default region radius, m (the issue's "within 6 cm of the bust points").
REGION_RADIUS = 0.06


def body_landmarks(pattern, model=None, vertices=None) -> Dict[str, np.ndarray]:
    """Every landmark of the pattern's body (its ``body`` record), name -> (3,) position in m.

    The body is the instance the pattern's panels were solved on (the target
    shape of a transfer, the reference of a reference or adapted pattern);
    ``vertices`` (V, 3): that instance when the caller has made it (a transfer
    has), so it is not evaluated again.
    Returns an empty dict when the record names no model, or one that cannot be
    loaded (a synthetic pattern, a moved OBJ file).
    """
    from ..body.instance import spec_instance
    from ..body.registry import load_spec
    from ..errors import EaseError

    spec = getattr(pattern, "body", None) or {}
    if not spec.get("model"):
        return {}
    try:
        model = model if model is not None else load_spec(spec)  # an OBJ template with its landmarks file
        V = vertices if vertices is not None else spec_instance(spec, model=model)[0]
    except (EaseError, OSError):
        return {}
    return {n: np.asarray(model.landmark_position(n, V), float) for n in sorted(model.landmarks)}


def region_compliance(
    pattern,
    landmarks: Mapping[str, np.ndarray],
    radius: float = REGION_RADIUS,
    names: Optional[Iterable[str]] = REGION_LANDMARKS,
    garment: Optional[str] = None,
    strains=None,
) -> Dict[str, dict]:
    """Compliance within ``radius`` of each named landmark.

    Parameters
    ----------
    pattern : Pattern; each panel measured on its own ``xyz`` against its own targets.
    landmarks : name -> (3,) position, m, on the same body.
    radius : float, m.
    names : landmarks to report (default :data:`REGION_LANDMARKS`; None: every
        landmark given); names missing from ``landmarks`` are skipped.
    garment : restrict to one garment.
    strains : optional :func:`core.metrics.strains.pattern_strains` of ``pattern`` (read, not recomputed).

    Returns
    -------
    dict name -> ``{"mean", "std", "p95", "signed"}`` (weft compliance, %),
    ``warp_mean``, ``warp_p95``, ``warp_signed`` (%), ``shear_mean``, ``shear_p95`` (deg),
    ``area`` (m^2) and ``n`` (triangles); a landmark the garment does not
    cover within ``radius`` is left out.
    """
    keys = sorted(landmarks) if names is None else [n for n in names if n in landmarks]
    if not keys:
        return {}
    weft, warp, shear, area, cen = [], [], [], [], []
    for p in pattern.panels:
        if garment is not None and p.garment != garment:
            continue
        X, F = np.asarray(p.xyz, float), np.asarray(p.faces)
        rw, rg, sh, a3 = strains[p.name] if strains is not None else panel_strain(p)
        weft.append((rw - p.target_weft) / p.target_weft)
        warp.append((rg - p.target_warp) / p.target_warp)
        shear.append(sh)
        area.append(a3)
        # X[F].mean(axis=1) term by term in its order (the same bits, without the strided reduction)
        cen.append((X[F[:, 0]] + X[F[:, 1]] + X[F[:, 2]]) / 3.0)
    if not cen:
        return {}
    weft, warp = 100.0 * np.concatenate(weft), 100.0 * np.concatenate(warp)
    shear, area, cen = np.concatenate(shear), np.concatenate(area), np.concatenate(cen)
    cz = np.ascontiguousarray(cen[:, 2])
    out = {}
    for name in keys:
        lm = np.asarray(landmarks[name], float)
        # the computed length is at least |dz| (sqrt(fl(dz^2)) is |dz| and the sum of squares only grows), so
        # a centroid within the radius is within it along z: only those rows are measured (the same set)
        near = np.flatnonzero(np.abs(cz - lm[2]) <= radius)
        inside = near[row_norm(cen[near] - lm) <= radius]
        if not inside.size:
            continue
        a = area[inside]
        c = weighted_stats(np.abs(weft[inside]), a)
        s = weighted_stats(shear[inside], a)
        w = weighted_stats(np.abs(warp[inside]), a)
        out[name] = {
            "mean": c["mean"],
            "std": c["std"],
            "p95": c["p95"],
            "signed": weighted_mean(weft[inside], a),
            "warp_mean": w["mean"],
            "warp_p95": w["p95"],
            "warp_signed": weighted_mean(warp[inside], a),
            "shear_mean": s["mean"],
            "shear_p95": s["p95"],
            "area": float(a.sum()),
            "n": int(inside.size),
        }
    return out
