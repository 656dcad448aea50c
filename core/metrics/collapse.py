"""Collapsed triangles: cloth squeezed to a sliver where the design asked for fabric.

A flip-free pattern can still hide triangles whose 2D area is a few percent of
what the targets ask for (achieved scale 0.002 where 1.56 was asked): the
flip guard keeps their orientation but not their size. A triangle ``t`` of a
panel, not flipped, is **collapsed** when

    A_2D(t) < 0.25 * A_3D(t) * c_weft(t) * c_warp(t)
    or  rho_weft(t) < 0.5 * c_weft(t)
    or  rho_warp(t) < 0.5 * c_warp(t)

with ``A_2D`` its pattern area, ``A_3D`` its area on the body it is measured
on, ``c_weft``, ``c_warp`` the solve's targets (``target_weft``,
``target_warp``: the 2D area the targets ask for is ``A_3D c_weft c_warp``)
and ``rho`` the achieved scales (:func:`core.geom.strain.scales`). Flipped
triangles are counted by :func:`core.metrics.pattern.flips`, not here, so the
two counts never overlap. Definitions: ``docs/metrics.md``.

Each panel's collapsed triangles are grouped into *sites* by the nearest named
body landmark of their 3D centroid, so a report (and a refusal) can say where
on the body the cloth collapsed.
"""

from __future__ import annotations

from typing import Dict, List, Mapping, Optional

import numpy as np

from ..geom.mesh import signed_areas_2d, triangle_areas
from ..geom.strain import scales

# the rule's two numbers live with the solver, which ends a solve by the same rule (its rescue
# iterations, core.pattern.optimizer.guard.refused_mask): a triangle keeping less than AREA_FRACTION of the
# 2D area its targets ask for is collapsed, or one whose weft or warp scale is under SCALE_FRACTION
# of its target
from ..pattern.optimizer.guard import REFUSED_AREA as AREA_FRACTION
from ..pattern.optimizer.guard import REFUSED_SCALE as SCALE_FRACTION


def oriented_areas(uv: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Signed 2D areas (f,) in m^2, positive in the orientation most triangles of the panel share."""
    s = signed_areas_2d(uv, faces)
    return s if np.sum(s > 0) >= np.sum(s < 0) else -s


def _criteria(uv, xyz, faces, grain, target_weft, target_warp, strain=None, a2=None):
    """(kept, small, thin) (f,) bool each: not flipped; area rule; scale rule (module rule).
    ``strain``: the panel's :class:`core.metrics.strains.PanelStrain` on ``xyz`` if known; ``a2``: its
    :func:`oriented_areas` if known."""
    a2 = oriented_areas(uv, faces) if a2 is None else a2
    tw = np.asarray(target_weft, float)
    tg = np.asarray(target_warp, float)
    if strain is not None:
        rw, rg, _, a3 = strain
    else:
        a3 = triangle_areas(xyz, faces)
        with np.errstate(divide="ignore", invalid="ignore"):
            rw, rg, _ = scales(uv, xyz, faces, grain)
    small = a2 < AREA_FRACTION * a3 * tw * tg
    thin = (rw < SCALE_FRACTION * tw) | (rg < SCALE_FRACTION * tg)
    return a2 > 0, small, thin


def collapsed_mask(
    uv: np.ndarray,
    xyz: np.ndarray,
    faces: np.ndarray,
    grain: np.ndarray,
    target_weft: np.ndarray,
    target_warp: np.ndarray,
) -> np.ndarray:
    """Which triangles of one panel are collapsed (see the module rule).

    Parameters
    ----------
    uv : (n, 2) float, m: pattern positions.
    xyz : (n, 3) float, m: positions on the body measured on.
    faces : (f, 3) int.
    grain : (2,) unit warp direction in the pattern.
    target_weft, target_warp : (f,) float: the solve's target scales.

    Returns
    -------
    (f,) bool. Flipped and zero-area triangles are False (they are flips).
    """
    kept, small, thin = _criteria(uv, xyz, faces, grain, target_weft, target_warp)
    return kept & (small | thin)


def _sites(centroids: np.ndarray, landmarks: Optional[Mapping[str, np.ndarray]]) -> List[dict]:
    """Group collapsed triangles' centroids (k, 3) by their nearest landmark."""
    if not landmarks:
        c = centroids.mean(axis=0)
        return [{"near": None, "count": int(len(centroids)), "centroid": [round(float(x), 4) for x in c]}]
    names = sorted(landmarks)
    P = np.array([np.asarray(landmarks[n], float) for n in names])
    d = np.linalg.norm(centroids[:, None, :] - P[None, :, :], axis=2)
    near = np.argmin(d, axis=1)
    out = []
    for k in np.unique(near):  # sorted by landmark name: deterministic
        c = centroids[near == k].mean(axis=0)
        out.append(
            {
                "near": names[k],
                "count": int(np.sum(near == k)),
                "distance_mm": round(1000.0 * float(np.linalg.norm(c - P[k])), 1),
                "centroid": [round(float(x), 4) for x in c],
            }
        )
    return sorted(out, key=lambda s: (-s["count"], s["near"]))


def collapse(
    pattern,
    landmarks: Optional[Mapping[str, np.ndarray]] = None,
    strains=None,
    oriented: Optional[Mapping[str, np.ndarray]] = None,
) -> Dict[str, dict]:
    """Collapsed triangles per panel, measured on each panel's own ``xyz`` against its targets.

    Parameters
    ----------
    pattern : Pattern
    landmarks : optional name -> (3,) position (m) on the same body, to say
        where on the body each group of collapsed triangles lies.
    strains : optional :func:`core.metrics.strains.pattern_strains` of ``pattern`` (read, not recomputed).
    oriented : optional panel name -> :func:`oriented_areas` of its piece (read, not recomputed).

    Returns
    -------
    dict panel name -> ``{"count", "area", "scale_only", "sites"}``: ``count``
    collapsed triangles, ``area`` of them by the area rule, ``scale_only`` by
    the scale rule alone (a scale under half its target with the area kept:
    typically a raised adaptation target the solve could not reach). Each site is
    ``{"near": landmark name or None, "count", "distance_mm", "centroid": [x, y, z] m}``
    (the mean 3D centroid of its triangles), the largest site first. Panels
    with no collapsed triangle have ``count`` 0 and no sites.
    """
    out = {}
    for p in pattern.panels:
        X = np.asarray(p.xyz, float)
        F = np.asarray(p.faces)
        kept, small, thin = _criteria(
            p.uv,
            X,
            F,
            p.grain,
            p.target_weft,
            p.target_warp,
            None if strains is None else strains[p.name],
            None if oriented is None else oriented[p.name],
        )
        m = kept & (small | thin)
        n = int(m.sum())
        out[p.name] = {
            "count": n,
            "area": int(np.sum(kept & small)),
            "scale_only": int(np.sum(m & ~small)),
            "sites": _sites(X[F[m]].mean(axis=1), landmarks) if n else [],
        }
    return out


def site_where(site: dict) -> str:
    xyz = ", ".join(f"{v:.3f}" for v in site["centroid"])
    if site.get("near"):
        return f"near {site['near']} ({xyz} m)"
    return f"at ({xyz} m)"


def collapse_message(per_panel: Mapping[str, dict]) -> str:
    """One line naming every panel with collapsed triangles and where on the body they lie.

    e.g. ``panel skirt_back: 20 collapsed triangles near gluteal_cleft (0.000, 0.081, 0.812 m)``.
    """
    parts = []
    for name, v in per_panel.items():
        if not v["count"]:
            continue
        where = "; ".join(f"{s['count']} {site_where(s)}" for s in v["sites"])
        parts.append(
            f"panel {name}: {v['count']} collapsed triangles ({where})"
            if len(v["sites"]) > 1
            else f"panel {name}: {v['count']} collapsed triangles {site_where(v['sites'][0])}"
        )
    return "; ".join(parts)
