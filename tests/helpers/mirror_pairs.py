"""Left/right agreement of a mirrored pattern: seam lengths per stretch and panel outlines.

For tests and measurements of issue 14 ("mirrored designs stay symmetric").
"""

from __future__ import annotations

from typing import Dict

import numpy as np

from core.design.naming import swap_side


def _length(uv: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(uv, axis=0), axis=1).sum())


def seam_side_lengths(pattern) -> Dict[tuple, float]:
    """(seam name, panel) -> 2D length (m) of that panel's side of the seam."""
    out = {}
    for s in pattern.seams:
        for pn, verts in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b)):
            out[(s.name, pn)] = _length(pattern.panel(pn).uv[np.asarray(verts)])
    return out


def _mirror_key(key):
    name, panel = key
    base, hash_, part = name.partition("#")
    return swap_side(base) + hash_ + part, swap_side(panel)


def seam_asymmetry(pattern) -> Dict[str, float]:
    """Largest |length(side) - length(mirror side)| (m) per seam side that has a mirror, keyed
    ``"seam @ panel"``; a seam side whose mirror is itself (a centre seam) is left out."""
    lengths = seam_side_lengths(pattern)
    out = {}
    for key, L in lengths.items():
        m = _mirror_key(key)
        if m == key or m not in lengths or key > m:
            continue
        out[f"{key[0]} @ {key[1]}"] = abs(L - lengths[m])
    return out


def outline_asymmetry(pattern) -> Dict[str, float]:
    """Per mirror pair of panels (or a panel that is its own mirror): the largest distance (m)
    between a boundary vertex of one and the other's boundary polyline reflected (x -> -x) and
    aligned, both ways (symmetric Hausdorff distance of vertices to outlines: two outlines of
    one shape sampled by different vertices, as on the skirt topology, are 0 apart)."""
    out = {}
    names = [p.name for p in pattern.panels]
    for p in pattern.panels:
        m = swap_side(p.name)
        if m not in names or (m != p.name and p.name > m):
            continue
        q = pattern.panel(m)
        a = _outline(p)
        b = _outline(q) * [-1.0, 1.0]
        out[p.name] = _aligned_hausdorff(a, b)
    return out


def _outline(panel) -> np.ndarray:
    loop = max(panel.boundary, key=len)
    return np.asarray(panel.uv[np.asarray(loop)], float)


def _to_loop(P: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """(k,) distance of every point of ``P`` to the closed polyline ``loop``."""
    A, AB = loop, np.roll(loop, -1, axis=0) - loop
    t = np.einsum("pkd,kd->pk", P[:, None] - A[None], AB) / np.maximum(np.einsum("kd,kd->k", AB, AB), 1e-30)
    C = A[None] + np.clip(t, 0.0, 1.0)[..., None] * AB[None]
    return np.linalg.norm(P[:, None] - C, axis=2).min(axis=1)


def _aligned_hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    """Rigidly align ``b`` onto ``a`` (best rotation by nearest-point iterations) and return the
    symmetric Hausdorff distance of each outline's vertices to the other outline."""
    from scipy.spatial import cKDTree

    b = b - b.mean(0) + a.mean(0)
    ta = cKDTree(a)
    for _ in range(30):
        _, j = ta.query(b)
        P, Q = b - b.mean(0), a[j] - a[j].mean(0)
        U, _, Vt = np.linalg.svd(P.T @ Q)
        R = U @ Vt
        if np.linalg.det(R) < 0:
            U[:, -1] *= -1
            R = U @ Vt
        b = P @ R + a[j].mean(0)
    return float(max(_to_loop(b, a).max(), _to_loop(a, b).max()))
