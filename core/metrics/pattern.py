"""Pattern metrics exactly as the shared SPEC defines them.

Per triangle with 3D vertices ``X`` on a body instance and 2D pattern vertices
``U``, the affine 2D->3D map has Jacobian ``J = [x1-x0, x2-x0] [u1-u0, u2-u0]^-1``
(3x2). With the panel's grain ``g`` (unit 2D warp) and weft ``w = rot90(g)``:
achieved weft scale ``1/|J w|``, warp scale ``1/|J g|``; required stretch
``|J w|`` on a target body; shear = angle(J w, J g) - 90 degrees. Means and
standard deviations are area-weighted (3D area on the measured body), in percent.
"""
from __future__ import annotations

from typing import Dict, Iterable, Optional, Sequence

import numpy as np


def weft_of(grain: np.ndarray) -> np.ndarray:
    """The 2D weft (2,): the grain turned by +90 degrees."""
    g = np.asarray(grain, float)
    return np.array([-g[1], g[0]])


def jacobians(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per-triangle 2D->3D Jacobians (f, 3, 2); NaN for degenerate 2D triangles."""
    uv = np.asarray(uv, float)
    xyz = np.asarray(xyz, float)
    F = np.asarray(faces, int)
    D2 = np.stack([uv[F[:, 1]] - uv[F[:, 0]], uv[F[:, 2]] - uv[F[:, 0]]], axis=2)  # (f,2,2)
    D3 = np.stack([xyz[F[:, 1]] - xyz[F[:, 0]], xyz[F[:, 2]] - xyz[F[:, 0]]], axis=2)  # (f,3,2)
    det = D2[:, 0, 0] * D2[:, 1, 1] - D2[:, 0, 1] * D2[:, 1, 0]
    inv = np.empty_like(D2)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv[:, 0, 0] = D2[:, 1, 1] / det
        inv[:, 1, 1] = D2[:, 0, 0] / det
        inv[:, 0, 1] = -D2[:, 0, 1] / det
        inv[:, 1, 0] = -D2[:, 1, 0] / det
    return D3 @ inv


def signed_areas_2d(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Signed 2D triangle areas (f,), positive counter-clockwise."""
    uv = np.asarray(uv, float)
    F = np.asarray(faces, int)
    a = uv[F[:, 1]] - uv[F[:, 0]]
    b = uv[F[:, 2]] - uv[F[:, 0]]
    return 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def areas_3d(xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Triangle areas (f,) in square metres."""
    xyz = np.asarray(xyz, float)
    F = np.asarray(faces, int)
    return 0.5 * np.linalg.norm(np.cross(xyz[F[:, 1]] - xyz[F[:, 0]], xyz[F[:, 2]] - xyz[F[:, 0]]), axis=1)


def flipped_count(uv: np.ndarray, faces: np.ndarray) -> int:
    """Triangles whose 2D orientation differs from the panel's majority (degenerate count as flipped)."""
    s = signed_areas_2d(uv, faces)
    major = 1.0 if np.sum(s > 0) >= np.sum(s < 0) else -1.0
    return int(np.sum(s * major <= 0))


def scales(uv, xyz, faces, grain):
    """Achieved weft/warp scales and shear per triangle.

    Returns
    -------
    rho_weft, rho_warp : (f,) float, ``1/|J w|`` and ``1/|J g|``.
    shear_deg : (f,) float, ``|angle(J w, J g) - 90|`` in degrees.
    """
    J = jacobians(uv, xyz, faces)
    g = np.asarray(grain, float) / np.linalg.norm(grain)
    jw = J @ weft_of(g)
    jg = J @ g
    lw = np.linalg.norm(jw, axis=1)
    lg = np.linalg.norm(jg, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cosang = np.sum(jw * jg, axis=1) / (lw * lg)
        shear = np.abs(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))) - 90.0)
        return 1.0 / lw, 1.0 / lg, shear


def required_stretch(uv, xyz_body, faces, grain):
    """SPEC required stretch on a body instance: ``r_weft = |J_B w|``, ``r_warp = |J_B g|`` (f,)."""
    rw, rg, _ = scales(uv, xyz_body, faces, grain)
    return 1.0 / rw, 1.0 / rg


def weighted_stats(values: np.ndarray, weights: np.ndarray) -> Dict[str, float]:
    """Area-weighted mean, std and 95th percentile of ``values``."""
    v = np.asarray(values, float)
    w = np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    v, w = v[ok], w[ok]
    if v.size == 0:
        return {"mean": float("nan"), "std": float("nan"), "p95": float("nan"), "max": float("nan")}
    mean = float(np.sum(w * v) / np.sum(w))
    std = float(np.sqrt(np.sum(w * (v - mean) ** 2) / np.sum(w)))
    order = np.argsort(v)
    cw = np.cumsum(w[order]) / np.sum(w)
    p95 = float(v[order][min(np.searchsorted(cw, 0.95), v.size - 1)])
    return {"mean": mean, "std": std, "p95": p95, "max": float(v.max())}


def compliance_per_triangle(achieved_weft: np.ndarray, target_weft: np.ndarray) -> np.ndarray:
    """SPEC item 1: ``|rho_hat - rho| / rho`` per triangle (fraction, not percent)."""
    t = np.asarray(target_weft, float)
    return np.abs(np.asarray(achieved_weft, float) - t) / t


def _panels(pattern, garment, names=None):
    return [p for p in pattern.panels
            if (garment is None or p.garment == garment) and (names is None or p.name in names)]


def ease_compliance(pattern, garment: Optional[str] = None, xyz: Optional[Dict[str, np.ndarray]] = None,
                    target: Optional[Dict[str, np.ndarray]] = None,
                    panels: Optional[Iterable[str]] = None) -> Dict[str, float]:
    """Ease compliance (SPEC 1 and 3) with shear (SPEC 8), area-weighted, percent / degrees.

    Parameters
    ----------
    pattern : Pattern
    garment : restrict to one garment, or None for all panels.
    xyz : optional dict panel name -> (n, 3) positions of the body to measure on
        (default: each panel's own ``xyz``, the body it was solved for).
    target : optional dict panel name -> (f,) target weft scale (default ``target_weft``).
    panels : optional panel names to restrict to (e.g. the sleeves).

    Returns
    -------
    dict with ``mean``, ``std``, ``p95``, ``max`` (percent), ``shear_mean``,
    ``shear_p95`` (degrees), ``warp_mean`` (percent deviation of the warp
    scale from its target), ``warp_signed`` (its signed mean: near 0 when the
    garment's length is kept), ``area`` (m^2).
    """
    comp, shear, warp, area = [], [], [], []
    for p in _panels(pattern, garment, None if panels is None else set(panels)):
        X = p.xyz if xyz is None else xyz[p.name]
        rw, rg, sh = scales(p.uv, X, p.faces, p.grain)
        t = p.target_weft if target is None else target[p.name]
        comp.append(compliance_per_triangle(rw, t))
        warp.append((rg - p.target_warp) / p.target_warp)
        shear.append(sh)
        area.append(areas_3d(X, p.faces))
    if not comp:
        return {}
    a = np.concatenate(area)
    c = weighted_stats(100.0 * np.concatenate(comp), a)
    s = weighted_stats(np.concatenate(shear), a)
    warp = 100.0 * np.concatenate(warp)
    return {"mean": c["mean"], "std": c["std"], "p95": c["p95"], "max": c["max"],
            "shear_mean": s["mean"], "shear_p95": s["p95"], "warp_mean": weighted_stats(np.abs(warp), a)["mean"],
            "warp_signed": weighted_stats(warp, a)["mean"], "area": float(a.sum())}


def polyline_length(points: np.ndarray) -> float:
    """Length of a polyline (k, d)."""
    return float(np.sum(np.linalg.norm(np.diff(np.asarray(points, float), axis=0), axis=1)))


def seam_mismatch(pattern, garment: Optional[str] = None) -> Dict[str, object]:
    """Seam mismatch (SPEC 2): per seam ``|Lp - Lq| / ((Lp + Lq)/2)``.

    Returns ``mean``, ``std`` (percent over seams), ``max_mm`` (largest absolute
    difference, millimetres) and ``per_seam`` (name -> {percent, mm}). A seam
    belongs to a garment when its first panel does. Gathered seams are
    meant to differ: they are left out of the statistics and listed in
    ``gathered`` (name -> gather ratio, longer side / shorter side).
    """
    names = {p.name for p in _panels(pattern, garment)}
    per, rel, diff, gathered = {}, [], [], {}
    for s in pattern.seams:
        if s.panel_a not in names:
            continue
        pa, pb = pattern.seam_polylines(s)
        la, lb = polyline_length(pa), polyline_length(pb)
        if getattr(s, "gathered", False):
            gathered[s.name] = max(la, lb) / max(min(la, lb), 1e-12)
            continue
        r = abs(la - lb) / max((la + lb) / 2.0, 1e-12)
        per[s.name] = {"percent": 100.0 * r, "mm": 1000.0 * abs(la - lb)}
        rel.append(100.0 * r)
        diff.append(1000.0 * abs(la - lb))
    if not rel:
        return {"mean": 0.0, "std": 0.0, "max_percent": 0.0, "max_mm": 0.0, "n": 0, "per_seam": {},
                "gathered": gathered}
    return {"mean": float(np.mean(rel)), "std": float(np.std(rel)), "max_percent": float(np.max(rel)),
            "max_mm": float(np.max(diff)), "n": len(rel), "per_seam": per, "gathered": gathered}


def residual_stretch(pattern, body_xyz: Dict[str, np.ndarray], eps_weft: float = 1.10,
                     garment: Optional[str] = None) -> float:
    """Residual stretch (SPEC 4): percent of garment area (on the posed body) with ``r_weft > eps_weft``.

    ``body_xyz`` maps panel name -> (n, 3) panel positions on the target pose.
    """
    over, total = 0.0, 0.0
    for p in _panels(pattern, garment):
        X = body_xyz[p.name]
        r_weft, _ = required_stretch(p.uv, X, p.faces, p.grain)
        a = areas_3d(X, p.faces)
        over += float(np.sum(a[r_weft > eps_weft]))
        total += float(np.sum(a))
    return 100.0 * over / total if total > 0 else 0.0


def flips(pattern) -> Dict[str, int]:
    """Flipped-triangle count per panel (SPEC "Per-triangle scales")."""
    return {p.name: flipped_count(p.uv, p.faces) for p in pattern.panels}


def pattern_report(pattern) -> Dict[str, object]:
    """All reference-body metrics of a pattern, per garment and overall."""
    out = {"garments": {}}
    for g in sorted({p.garment for p in pattern.panels}):
        out["garments"][g] = {"compliance": ease_compliance(pattern, g), "seams": seam_mismatch(pattern, g)}
    out["compliance"] = ease_compliance(pattern)
    seams = seam_mismatch(pattern)
    out["seams"] = seams
    fl = flips(pattern)
    out["flipped_triangles"] = int(sum(fl.values()))
    out["flipped_per_panel"] = fl
    return out
