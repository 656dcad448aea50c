"""Global injectivity of a pattern piece: crossings of its sew line and of its darts' legs.

A piece with no flipped triangle is locally injective, but it can still overlap itself: a
dart's legs that cross on their way to the apex, a side seam folded over a hem. A locally
injective (orientation-preserving) map of a disk whose boundary is a simple closed curve is
globally injective, so with the flip count at zero, a piece is globally injective exactly when
its boundary loops are simple and do not touch one another. This module counts the
**crossings**: pairs of boundary edges of one piece that do not share a vertex and cross or come
within :data:`CONTACT` of each other (a dart's two legs must keep a positive gap from the mouth
to the apex and meet only at the apex). Each crossing is told by the stretches of the sew line
it joins (a dart's legs, a seam's side, a hem) and where on the body it lies, so a refusal can
name them. Definitions: ``docs/metrics.md`` ("Crossings").
"""

from __future__ import annotations

from typing import Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..geom.mesh import boundary_loops
from ..geom.polygon import CONTACT, segment_gaps


def piece_edges(panel) -> np.ndarray:
    """The boundary edges (k, 2) of a piece (local vertex ids), from ``panel.boundary`` or, when it lists
    none, its faces' boundary."""
    loops = [np.asarray(b, int).reshape(-1) for b in (panel.boundary or [])] or boundary_loops(panel.faces)
    out = []
    for b in loops:
        if len(b) > 1 and b[0] == b[-1]:
            b = b[:-1]
        if len(b) >= 2:
            out.append(np.stack([b, np.roll(b, -1)], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2), int)


def _candidates(a: np.ndarray, b: np.ndarray, pad: float) -> Tuple[np.ndarray, np.ndarray]:
    """Pairs (i, j), i != j, of segments a->b whose bounding boxes grown by ``pad`` overlap (sweep along x)."""
    lo, hi = np.minimum(a, b) - pad, np.maximum(a, b) + pad
    order = np.argsort(lo[:, 0], kind="stable")
    los = lo[order, 0]
    m = len(order)
    end = np.searchsorted(los, hi[order, 0], side="right")
    start = np.arange(1, m + 1)
    counts = np.maximum(end - start, 0)
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, int), np.zeros(0, int)
    first = np.repeat(start - np.cumsum(counts) + counts, counts)
    si = np.repeat(np.arange(m), counts)
    sj = np.arange(total) + first
    i, j = order[si], order[sj]
    keep = (lo[j, 1] <= hi[i, 1]) & (hi[j, 1] >= lo[i, 1])
    return i[keep], j[keep]


def crossing_pairs(uv: np.ndarray, edges: np.ndarray, contact: float = CONTACT) -> np.ndarray:
    """Pairs (k, 2) of rows of ``edges`` that share no vertex and cross or come within ``contact``."""
    uv = np.asarray(uv, float)
    edges = np.asarray(edges, int)
    if len(edges) < 2:
        return np.zeros((0, 2), int)
    a, b = uv[edges[:, 0]], uv[edges[:, 1]]
    i, j = _candidates(a, b, contact)
    e, f = edges[i], edges[j]
    apart = (e[:, 0] != f[:, 0]) & (e[:, 0] != f[:, 1]) & (e[:, 1] != f[:, 0]) & (e[:, 1] != f[:, 1])
    i, j = i[apart], j[apart]
    hit = segment_gaps(a[i], b[i], a[j], b[j]) <= contact
    pairs = np.stack([np.minimum(i[hit], j[hit]), np.maximum(i[hit], j[hit])], axis=1)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))] if len(pairs) else pairs


def stretch_labels(pattern, panel, edges: np.ndarray) -> List[str]:
    """What each boundary edge of ``panel`` belongs to: ``"dart <name>"``, ``"seam <name>"``, ``"hem"`` or
    ``"boundary"`` (the first that lists both of its vertices consecutively)."""
    label: Dict[Tuple[int, int], str] = {}

    def mark(run, name):
        run = np.asarray(run, int).reshape(-1)
        for u, v in zip(run[:-1], run[1:]):
            label.setdefault((int(u), int(v)), name)
            label.setdefault((int(v), int(u)), name)

    for s in pattern.seams:
        kind = "dart" if s.kind == "dart" else "seam"
        if s.panel_a == panel.name:
            mark(s.verts_a, f"{kind} {s.name}")
        if s.panel_b == panel.name:
            mark(s.verts_b, f"{kind} {s.name}")
    for h in panel.hems or []:
        mark(h, "hem")
    return [label.get((int(u), int(v)), "boundary") for u, v in edges]


def _nearest(point: np.ndarray, landmarks: Optional[Mapping[str, np.ndarray]]) -> dict:
    site = {"near": None, "centroid": [round(float(x), 4) for x in point]}
    if landmarks:
        names = sorted(landmarks)
        d = [float(np.linalg.norm(point - np.asarray(landmarks[n], float))) for n in names]
        k = int(np.argmin(d))
        site.update(near=names[k], distance_mm=round(1000.0 * d[k], 1))
    return site


def panel_crossings(pattern, panel, landmarks: Optional[Mapping[str, np.ndarray]] = None) -> dict:
    """The crossings of one piece: ``{"count", "sites"}``, each site ``{"between": [stretch, stretch],
    "count", "near", "distance_mm", "centroid"}`` (the stretches of the sew line that cross, sorted; the
    mean 3D point of their crossing edges on the piece's body and its nearest landmark), largest first."""
    edges = piece_edges(panel)
    pairs = crossing_pairs(panel.uv, edges)
    if not len(pairs):
        return {"count": 0, "sites": []}
    labels = stretch_labels(pattern, panel, edges)
    X = np.asarray(panel.xyz, float)
    groups: Dict[Tuple[str, str], List[np.ndarray]] = {}
    for i, j in pairs:
        key = tuple(sorted((labels[i], labels[j])))
        groups.setdefault(key, []).append(X[np.concatenate([edges[i], edges[j]])].mean(axis=0))
    sites = [
        {"between": list(k), "count": len(v), **_nearest(np.mean(v, axis=0), landmarks)} for k, v in groups.items()
    ]
    return {"count": int(len(pairs)), "sites": sorted(sites, key=lambda s: (-s["count"], s["between"]))}


def crossings(pattern, landmarks: Optional[Mapping[str, np.ndarray]] = None) -> Dict[str, dict]:
    """:func:`panel_crossings` of every piece (panel name -> ``{"count", "sites"}``)."""
    return {p.name: panel_crossings(pattern, p, landmarks) for p in pattern.panels}


def dart_gaps(pattern) -> Dict[str, dict]:
    """Per dart: ``min_gap_mm``, the smallest distance between its two legs (mm; the two edges that end
    at the apex, which meet there, left out; 0 where the legs cross), and ``crossings``, the pairs of leg
    edges that cross or touch."""
    out = {}
    for s in pattern.seams:
        if s.kind != "dart":
            continue
        panel = pattern.panel(s.panel_a)
        la, lb = np.asarray(s.verts_a, int), np.asarray(s.verts_b, int)
        ea = np.stack([la[:-1], la[1:]], axis=1)
        eb = np.stack([lb[:-1], lb[1:]], axis=1)
        if len(ea) < 2 or len(eb) < 2:
            out[s.name] = {"min_gap_mm": None, "crossings": 0}
            continue
        uv = np.asarray(panel.uv, float)
        ea, eb = ea[:-1], eb[:-1]  # the edges ending at the apex share it
        ii, jj = np.meshgrid(np.arange(len(ea)), np.arange(len(eb)), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        g = segment_gaps(uv[ea[ii, 0]], uv[ea[ii, 1]], uv[eb[jj, 0]], uv[eb[jj, 1]])
        n = int(np.sum(g <= CONTACT))
        out[s.name] = {"min_gap_mm": round(1000.0 * float(g.min()), 3), "crossings": n}
    return out
