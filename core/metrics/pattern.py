"""Pattern metrics exactly as the shared SPEC defines them.

Per triangle with 3D vertices ``X`` on a body instance and 2D pattern vertices
``U``, the affine 2D->3D map has Jacobian ``J = [x1-x0, x2-x0] [u1-u0, u2-u0]^-1``
(3x2). With the panel's grain ``g`` (unit 2D warp) and weft ``w = rot90(g)``:
achieved weft scale ``1/|J w|``, warp scale ``1/|J g|``; required stretch
``|J w|`` on a target body; shear = angle(J w, J g) - 90 degrees. Means and
standard deviations are area-weighted (3D area on the measured body), in percent.
The per-triangle geometry is :mod:`core.geom.strain` and :mod:`core.geom.mesh`
(``scales`` and ``signed_areas_2d`` are re-exported here).
"""

from __future__ import annotations

import copy
from typing import Dict, Iterable, Optional

import numpy as np

from ..geom.mesh import signed_areas_2d, triangle_areas
from ..geom.polyline import polyline_length
from ..geom.strain import scales
from .collapse import collapse, oriented_areas
from .injectivity import crossings, dart_gaps
from .regions import region_compliance
from .stats import weighted_mean, weighted_stats
from .strains import panel_strain, pattern_strains

__all__ = [
    "scales",
    "signed_areas_2d",
    "flipped_count",
    "required_stretch",
    "weighted_stats",
    "compliance_per_triangle",
    "ease_compliance",
    "seam_mismatch",
    "residual_stretch",
    "flips",
    "collapse",
    "region_compliance",
    "pattern_report",
]


def flipped_count(uv: np.ndarray, faces: np.ndarray) -> int:
    """Triangles whose 2D orientation differs from the panel's majority (degenerate count as flipped)."""
    return int(np.sum(oriented_areas(uv, faces) <= 0))


def required_stretch(uv, xyz_body, faces, grain):
    """SPEC required stretch on a body instance: ``r_weft = |J_B w|``, ``r_warp = |J_B g|`` (f,)."""
    rw, rg, _ = scales(uv, xyz_body, faces, grain)
    return 1.0 / rw, 1.0 / rg


def compliance_per_triangle(achieved_weft: np.ndarray, target_weft: np.ndarray) -> np.ndarray:
    """SPEC item 1: ``|rho_hat - rho| / rho`` per triangle (fraction, not percent)."""
    t = np.asarray(target_weft, float)
    return np.abs(np.asarray(achieved_weft, float) - t) / t


def _panels(pattern, garment, names=None):
    return [
        p for p in pattern.panels if (garment is None or p.garment == garment) and (names is None or p.name in names)
    ]


def ease_compliance(
    pattern,
    garment: Optional[str] = None,
    xyz: Optional[Dict[str, np.ndarray]] = None,
    target: Optional[Dict[str, np.ndarray]] = None,
    panels: Optional[Iterable[str]] = None,
    strains=None,
) -> Dict[str, float]:
    """Ease compliance (SPEC 1 and 3) with shear (SPEC 8), area-weighted, percent / degrees.

    Parameters
    ----------
    pattern : Pattern
    garment : restrict to one garment, or None for all panels.
    xyz : optional dict panel name -> (n, 3) positions of the body to measure on
        (default: each panel's own ``xyz``, the body it was solved for).
    target : optional dict panel name -> (f,) target weft scale (default ``target_weft``).
    panels : optional panel names to restrict to (e.g. the sleeves).
    strains : optional :func:`core.metrics.strains.pattern_strains` of ``pattern``
        (read instead of recomputed when ``xyz`` is None).

    Returns
    -------
    dict with ``mean``, ``std``, ``p95``, ``max`` (percent), ``shear_mean``,
    ``shear_p95`` (degrees), ``warp_mean`` (percent deviation of the warp
    scale from its target), ``warp_signed`` (its signed mean: near 0 when the
    garment's length is kept), ``warp_p95`` (its 95th percentile), ``area`` (m^2).
    """
    comp, shear, warp, area = [], [], [], []
    for p in _panels(pattern, garment, None if panels is None else set(panels)):
        if xyz is None:  # on the panel's own body: its strains, given or computed once here
            rw, rg, sh, a3 = strains[p.name] if strains is not None else panel_strain(p)
        else:
            rw, rg, sh = scales(p.uv, xyz[p.name], p.faces, p.grain)
            a3 = triangle_areas(xyz[p.name], p.faces)
        t = p.target_weft if target is None else target[p.name]
        comp.append(compliance_per_triangle(rw, t))
        warp.append((rg - p.target_warp) / p.target_warp)
        shear.append(sh)
        area.append(a3)
    if not comp:
        return {}
    a = np.concatenate(area)
    c = weighted_stats(100.0 * np.concatenate(comp), a)
    s = weighted_stats(np.concatenate(shear), a)
    warp = 100.0 * np.concatenate(warp)
    w = weighted_stats(np.abs(warp), a)
    return {
        "mean": c["mean"],
        "std": c["std"],
        "p95": c["p95"],
        "max": c["max"],
        "shear_mean": s["mean"],
        "shear_p95": s["p95"],
        "warp_mean": w["mean"],
        "warp_signed": weighted_mean(warp, a),
        "warp_p95": w["p95"],
        "area": float(a.sum()),
    }


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
        return {
            "mean": 0.0,
            "std": 0.0,
            "max_percent": 0.0,
            "max_mm": 0.0,
            "n": 0,
            "per_seam": {},
            "gathered": gathered,
        }
    return {
        "mean": float(np.mean(rel)),
        "std": float(np.std(rel)),
        "max_percent": float(np.max(rel)),
        "max_mm": float(np.max(diff)),
        "n": len(rel),
        "per_seam": per,
        "gathered": gathered,
    }


def residual_stretch(
    pattern,
    body_xyz: Dict[str, np.ndarray],
    eps_weft: float = 1.10,
    garment: Optional[str] = None,
    direction: str = "weft",
) -> float:
    """Residual stretch (SPEC 4): percent of garment area (on the posed body) with ``r_weft > eps_weft``.

    ``body_xyz`` maps panel name -> (n, 3) panel positions on the target pose.
    ``direction="warp"``: the same along the warp (``r_warp > eps_weft``), what a
    weft figure alone does not show.
    """
    if direction not in ("weft", "warp"):
        raise ValueError(f"direction: expected 'weft' or 'warp', got {direction!r}")
    over, total = 0.0, 0.0
    for p in _panels(pattern, garment):
        X = body_xyz[p.name]
        r = required_stretch(p.uv, X, p.faces, p.grain)[0 if direction == "weft" else 1]
        a = triangle_areas(X, p.faces)
        over += float(np.sum(a[r > eps_weft]))
        total += float(np.sum(a))
    return 100.0 * over / total if total > 0 else 0.0


def flips(pattern, oriented: Optional[Dict[str, np.ndarray]] = None) -> Dict[str, int]:
    """Flipped-triangle count per panel (SPEC "Per-triangle scales"). ``oriented``: panel name ->
    :func:`~core.metrics.collapse.oriented_areas` of its pieces when the caller has them."""
    if oriented is None:
        return {p.name: flipped_count(p.uv, p.faces) for p in pattern.panels}
    return {p.name: int(np.sum(oriented[p.name] <= 0)) for p in pattern.panels}


def _tree_copy(obj):
    """A copy of a report tree (dicts and lists of numbers, strings, None): what ``copy.deepcopy`` gives it,
    without its memo (a batch item's report copied at ~1/6 of the cost); immutable scalars shared, as
    ``deepcopy`` shares them."""
    if isinstance(obj, dict):
        return {k: _tree_copy(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_tree_copy(v) for v in obj]
    if isinstance(obj, (int, float, str, bool, type(None), np.generic)):
        return obj
    return copy.deepcopy(obj)


def pattern_report(pattern, landmarks: Optional[Dict[str, np.ndarray]] = None) -> Dict[str, object]:
    """All reference-body metrics of a pattern, per garment and overall.

    Parameters
    ----------
    pattern : Pattern
    landmarks : optional name -> (3,) position (m) on the pattern's body
        (:func:`core.metrics.regions.body_landmarks`): with them the report
        says where collapsed triangles lie and adds the region report.

    Returns
    -------
    dict: ``compliance`` and ``seams`` (all panels), ``garments[g]`` (the same
    per garment, with ``regions``), ``flipped_triangles`` /
    ``flipped_per_panel``, ``collapsed_triangles`` / ``collapsed_per_panel``
    / ``collapse_sites`` (panel -> sites, panels with collapsed triangles
    only), ``regions`` (landmark -> compliance within
    :data:`core.metrics.regions.REGION_RADIUS`; empty without landmarks),
    ``crossings`` / ``crossings_per_panel`` / ``crossing_sites`` (the sew line's
    crossings, :mod:`core.metrics.injectivity`; sites of panels with crossings
    only), ``darts`` (dart name -> its legs' ``min_gap_mm`` and ``crossings``)
    and ``pieces`` (panel name -> its own :func:`ease_compliance`).
    """
    out = {"garments": {}}
    strains = pattern_strains(pattern)  # every figure below reads the same per-triangle scales
    overall = {
        "compliance": ease_compliance(pattern, strains=strains),
        "seams": seam_mismatch(pattern),
        "regions": region_compliance(pattern, landmarks or {}, strains=strains),
    }
    garments = sorted({p.garment for p in pattern.panels})
    for g in garments:
        if len(garments) == 1:
            # one garment: its panels and seams are all of them, so its figures are the overall ones
            # (the same floats; a copy, so that a reader editing one entry leaves the other)
            out["garments"][g] = _tree_copy(overall)
            continue
        out["garments"][g] = {
            "compliance": ease_compliance(pattern, g, strains=strains),
            "seams": seam_mismatch(pattern, g),
            "regions": region_compliance(pattern, landmarks or {}, garment=g, strains=strains),
        }
    out["compliance"], out["seams"] = overall["compliance"], overall["seams"]
    # every piece's areas in its majority orientation: the flips and the collapse rule read the same ones
    oriented = {p.name: oriented_areas(p.uv, p.faces) for p in pattern.panels}
    fl = flips(pattern, oriented)
    out["flipped_triangles"] = int(sum(fl.values()))
    out["flipped_per_panel"] = fl
    col = collapse(pattern, landmarks, strains=strains, oriented=oriented)
    out["collapsed_triangles"] = int(sum(v["count"] for v in col.values()))
    out["collapsed_per_panel"] = {k: v["count"] for k, v in col.items()}
    out["collapse_sites"] = {k: v["sites"] for k, v in col.items() if v["count"]}
    out["regions"] = overall["regions"]
    cross = crossings(pattern, landmarks)
    out["crossings"] = int(sum(v["count"] for v in cross.values()))
    out["crossings_per_panel"] = {k: v["count"] for k, v in cross.items()}
    out["crossing_sites"] = {k: v["sites"] for k, v in cross.items() if v["count"]}
    out["darts"] = dart_gaps(pattern)
    out["pieces"] = {p.name: ease_compliance(pattern, panels=(p.name,), strains=strains) for p in pattern.panels}
    return out
