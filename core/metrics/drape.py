"""Fit measurements of a drape (SPEC items 6 and 7, the seam gap, strain maps).

- post-drape gap: from every body vertex under the garment, a ray along the
  outward vertex normal; the gap is the distance to the first hit on the
  draped garment, 0 where nothing is hit (openings, penetration). "Under the
  garment" = body vertices within ``cover_tolerance`` of the skintight
  garment (the embedding the pattern was solved on).
- penetration: share of garment vertices more than 2 mm inside the body.
- seam gap: distance between the two sides of every sewn vertex pair after
  the drape (0 by construction when seams are welded; measured anyway).
- strain: per-vertex weft and warp stretch relative to the pattern.
- folds (:func:`fold_measures`): over the interior edges of the draped mesh,
  the mean dihedral angle (degrees, 0 flat), the share of edges bent over 30
  degrees, and the mean curvature sum|theta_e| |e| / (2 A) (1/m: the
  area-weighted mean of |H| = |k1 + k2| / 2 on a smooth surface; 1/(2R) on a
  cylinder of radius R).

Means and standard deviations of the gap are over body vertices (as the
paper's gap graph); strain statistics are area-weighted over triangles.
Lengths are metres in arrays, millimetres in the summary dicts. The distance
and ray queries are :mod:`core.geom.queries` (Warp, imported on first use).
"""

from __future__ import annotations

import numpy as np

from ..errors import DrapeError
from ..geom.mesh import triangle_areas, vertex_normals

PENETRATION_DEPTH = 0.002  # m (SPEC item 7)


def covered_body_vertices(
    body_vertices: np.ndarray, garment_xyz: np.ndarray, garment_faces: np.ndarray, cover_tolerance: float = 0.004
) -> np.ndarray:
    """Mask (V,) of body vertices the skintight garment covers.

    Parameters
    ----------
    body_vertices : (V, 3).
    garment_xyz : (N, 3) skintight garment positions (per global vertex id).
    garment_faces : (T, 3) global ids.
    cover_tolerance : m, how far a body vertex may be from the skintight garment
        surface (the embedding's triangles are chords of the body surface).
    """
    from ..geom.queries import distance_to_mesh

    d = distance_to_mesh(body_vertices, garment_xyz, garment_faces, signed=False, max_dist=2 * cover_tolerance)
    return d <= cover_tolerance


def post_drape_gap(
    body_vertices: np.ndarray,
    body_faces: np.ndarray,
    draped: np.ndarray,
    garment_faces: np.ndarray,
    skintight: np.ndarray,
    cover_tolerance: float = 0.004,
    max_gap: float = 0.5,
) -> tuple:
    """SPEC item 6: the body-garment air gap along outward body vertex normals.

    Parameters
    ----------
    body_vertices : (V, 3), body_faces : (F, 3) outward oriented.
    draped : (N, 3) draped garment positions per global vertex id.
    garment_faces : (T, 3) global ids (one garment, or all).
    skintight : (N, 3) the skintight embedding (start of the drape).

    Returns
    -------
    gap : (k,) float m, per covered body vertex; covered : (V,) bool mask.
    """
    from ..geom.queries import ray_hit_distance

    bv = np.asarray(body_vertices, dtype=float)
    covered = covered_body_vertices(bv, skintight, garment_faces, cover_tolerance)
    normals = vertex_normals(bv, body_faces)
    gap = ray_hit_distance(bv[covered], normals[covered], draped, garment_faces, max_gap)
    return gap, covered


def penetration(
    garment_vertices: np.ndarray, body_vertices: np.ndarray, body_faces: np.ndarray, depth: float = PENETRATION_DEPTH
) -> tuple:
    """SPEC item 7: share of garment vertices more than ``depth`` inside the body.

    Returns
    -------
    share : float in [0, 1]; signed_distance : (n,) m, negative inside.
    """
    from ..geom.queries import distance_to_mesh

    sd = distance_to_mesh(garment_vertices, body_vertices, body_faces, signed=True, max_dist=0.5)
    if len(sd) == 0:
        return 0.0, sd
    return float(np.mean(sd < -depth)), sd


def seam_gap(positions: np.ndarray, seam_pairs: np.ndarray) -> np.ndarray:
    """Distance (m) between the sewn sides of each seam vertex pair (S,)."""
    pairs = np.asarray(seam_pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return np.zeros(0)
    x = np.asarray(positions, dtype=float)
    return np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)


def seam_side_distance(pattern, positions: np.ndarray) -> dict:
    """Per seam of the pattern: the largest distance (m) between its sewn sides after the drape.

    Measured on the seam polylines: for each side vertex, the distance to the
    other side's polyline (so it also holds where a seam is not welded
    vertex-to-vertex).
    """
    x = np.asarray(positions, dtype=float)
    out = {}
    for s in pattern.seams:
        a = x[np.asarray(pattern.panel(s.panel_a).vertex_ids)[np.asarray(s.verts_a)]]
        b = x[np.asarray(pattern.panel(s.panel_b).vertex_ids)[np.asarray(s.verts_b)]]
        out[s.name] = max(_point_polyline(a, b).max(initial=0.0), _point_polyline(b, a).max(initial=0.0))
    return out


def _point_polyline(p: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Distance of points (n, 3) to a polyline (k, 3)."""
    if len(line) == 1:
        return np.linalg.norm(p - line[0], axis=1)
    a, b = line[:-1], line[1:]
    ab = b - a
    t = np.einsum("nkj,kj->nk", p[:, None, :] - a[None], ab) / np.maximum(np.sum(ab * ab, axis=1), 1e-30)
    t = np.clip(t, 0.0, 1.0)
    closest = a[None] + t[..., None] * ab[None]
    return np.min(np.linalg.norm(p[:, None, :] - closest, axis=2), axis=1)


def _stats_mm(values: np.ndarray) -> dict:
    v = np.asarray(values, dtype=float) * 1000.0
    if len(v) == 0:
        return {"mean": 0.0, "std": 0.0, "max": 0.0, "n": 0}
    return {"mean": float(v.mean()), "std": float(v.std()), "max": float(v.max()), "n": int(len(v))}


def _area_stats_pct(values: np.ndarray, area: np.ndarray) -> dict:
    w = np.asarray(area, dtype=float)
    v = np.asarray(values, dtype=float) * 100.0
    if len(v) == 0 or w.sum() <= 0:
        return {"mean": 0.0, "std": 0.0, "p95": 0.0, "max": 0.0}
    mean = float(np.sum(v * w) / w.sum())
    std = float(np.sqrt(np.sum(w * (v - mean) ** 2) / w.sum()))
    order = np.argsort(v)
    cdf = np.cumsum(w[order]) / w.sum()
    p95 = float(v[order][min(np.searchsorted(cdf, 0.95), len(v) - 1)])
    return {"mean": mean, "std": std, "p95": p95, "max": float(v.max())}


FOLD_ANGLE = 30.0  # degrees: an edge bent more than this counts as folded


def fold_measures(positions: np.ndarray, faces: np.ndarray) -> dict:
    """How folded a draped mesh is (see the module notes).

    Parameters
    ----------
    positions : (N, 3) float, m. faces : (T, 3) int (slivers and all). Edges count where two
        triangles share both vertex ids: in a drape result, seams whose sides keep their own ids
        are left out.

    Returns
    -------
    dict: ``mean_dihedral_deg``, ``edges_over_30_pct``, ``mean_curvature_per_m``, ``edges`` (the count).
    """
    from ..drape.mesh import dihedral_angles, interior_edges

    x = np.asarray(positions, dtype=float)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    bends, _ = interior_edges(f) if len(f) else (np.zeros((0, 4), np.int64), None)
    area = float(triangle_areas(x, f).sum()) if len(f) else 0.0
    if len(bends) == 0 or area <= 0:
        return {"mean_dihedral_deg": 0.0, "edges_over_30_pct": 0.0, "mean_curvature_per_m": 0.0, "edges": 0}
    theta = np.abs(dihedral_angles(x, bends))
    length = np.linalg.norm(x[bends[:, 3]] - x[bends[:, 2]], axis=1)
    deg = np.degrees(theta)
    return {
        "mean_dihedral_deg": float(deg.mean()),
        "edges_over_30_pct": 100.0 * float(np.mean(deg > FOLD_ANGLE)),
        "mean_curvature_per_m": float(np.sum(theta * length) / (2.0 * area)),
        "edges": int(len(bends)),
    }


def drape_metrics(
    result, body_vertices: np.ndarray, body_faces: np.ndarray, pattern=None, cover_tolerance: float = 0.004
) -> dict:
    """All fit measurements of a :class:`core.drape.DrapeResult`, per garment and overall.

    Returns
    -------
    dict with, per garment (``"garments"``) and for all (``"all"``): ``gap_mm``
    (mean, std, max, n body vertices), ``penetration_pct``, ``seam_gap_mm`` (max,
    mean), ``strain_weft_pct`` / ``strain_warp_pct`` (area-weighted mean, std, p95,
    max), ``folds`` (:func:`fold_measures`). Arrays for maps: ``vertex_gap`` (N,) m (per garment vertex: its distance
    outside the body, 0 inside), ``body_gap`` (V,) m (0 where not covered).
    """
    bv = np.asarray(body_vertices, dtype=float)
    bf = np.asarray(body_faces)
    if bv.ndim != 2 or bv.shape[1] != 3:
        raise DrapeError(f"body vertices must be (V, 3), got {bv.shape}")
    x = np.asarray(result.positions, dtype=float)
    faces = np.asarray(result.faces)
    used = np.asarray(result.used, bool)
    _, sd = penetration(x, bv, bf)
    sd_used = sd[used]
    vertex_gap = np.where(used, np.clip(sd, 0.0, None), 0.0)
    body_gap = np.zeros(len(bv))
    area = _face_areas(result)
    out = {"garments": {}, "penetration_depth_mm": PENETRATION_DEPTH * 1000.0}
    all_gaps = []
    for g, name in enumerate(result.garment_names):
        sel = np.asarray(result.face_garment) == g
        gf = faces[sel]
        gap, covered = post_drape_gap(bv, bf, x, gf, result.start_positions, cover_tolerance)
        body_gap[covered] = np.maximum(body_gap[covered], gap)
        all_gaps.append(gap)
        verts = np.unique(gf)
        sg = seam_gap(x, _pairs_of(result.seam_pairs, verts))
        out["garments"][name] = {
            "gap_mm": _stats_mm(gap),
            "penetration_pct": 100.0 * float(np.mean(sd[verts] < -PENETRATION_DEPTH)),
            "seam_gap_mm": {
                "max": float(sg.max(initial=0.0) * 1000),
                "mean": float(sg.mean() * 1000) if len(sg) else 0.0,
            },
            "strain_weft_pct": _area_stats_pct(result.face_strain_weft[sel], area[sel]),
            "strain_warp_pct": _area_stats_pct(result.face_strain_warp[sel], area[sel]),
            "folds": fold_measures(x, gf),
        }
    sg = seam_gap(x, result.seam_pairs)
    out["all"] = {
        "gap_mm": _stats_mm(np.concatenate(all_gaps) if all_gaps else np.zeros(0)),
        "penetration_pct": 100.0 * (float(np.mean(sd_used < -PENETRATION_DEPTH)) if len(sd_used) else 0.0),
        "seam_gap_mm": {"max": float(sg.max(initial=0.0) * 1000), "mean": float(sg.mean() * 1000) if len(sg) else 0.0},
        "strain_weft_pct": _area_stats_pct(result.face_strain_weft, area),
        "strain_warp_pct": _area_stats_pct(result.face_strain_warp, area),
        "folds": fold_measures(x, faces),
    }
    if pattern is not None:
        sides = seam_side_distance(pattern, x)
        out["seam_side_mm"] = {k: v * 1000.0 for k, v in sides.items()}
        out["all"]["seam_gap_mm"]["max_side"] = max(sides.values(), default=0.0) * 1000.0
    out["vertex_gap"] = vertex_gap
    out["body_gap"] = body_gap
    return out


def _pairs_of(pairs: np.ndarray, verts: np.ndarray) -> np.ndarray:
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        return pairs
    return pairs[np.isin(pairs[:, 0], verts)]


def _face_areas(result) -> np.ndarray:
    """Areas (m^2) of the draped triangles, the weights of the strain statistics (0 for slivers)."""
    area = triangle_areas(np.asarray(result.positions, dtype=float), result.faces)
    valid = getattr(result, "face_valid", None)
    return area if valid is None else area * np.asarray(valid, bool)


def summary(metrics: dict) -> dict:
    """The metrics without per-vertex arrays (JSON-ready)."""
    return {k: v for k, v in metrics.items() if not isinstance(v, np.ndarray)}


__all__ = [
    "covered_body_vertices",
    "post_drape_gap",
    "fold_measures",
    "FOLD_ANGLE",
    "penetration",
    "seam_gap",
    "seam_side_distance",
    "drape_metrics",
    "summary",
    "PENETRATION_DEPTH",
]
