"""Incidence and planar coordinates of the cut mesh (:mod:`core.cut.split`).

:class:`VertexFaces` keeps each vertex's incident faces while the mesh is
split; :func:`bary2` / :func:`bary2_scalar` give barycentric coordinates in a
parent triangle's plane, vectorised and for one point in plain floats (the
line tracer's inner loop).
"""

from __future__ import annotations

from typing import Dict

import numpy as np


class VertexFaces:
    """vertex -> set of incident faces, materialised per vertex on first use.

    Every change of a vertex's incidence goes through ``self[v]``, so a set made
    later from the initial arrays is still correct."""

    def __init__(self, F: np.ndarray, nv: int):
        flat = F.reshape(-1)
        order = np.argsort(flat, kind="stable")
        self._bounds = np.searchsorted(flat[order], np.arange(nv + 1))
        self._faces = order // 3
        self._n0 = nv
        self._sets: Dict[int, set] = {}

    def __getitem__(self, v: int) -> set:
        s = self._sets.get(v)
        if s is None:
            s = set(self._faces[self._bounds[v] : self._bounds[v + 1]].tolist()) if v < self._n0 else set()
            self._sets[v] = s
        return s

    def append(self, s: set) -> None:
        pass  # new vertices start empty (made on first use)

    def copy(self) -> "VertexFaces":
        other = object.__new__(VertexFaces)
        other.__dict__.update(self.__dict__)
        other._sets = {k: set(v) for k, v in self._sets.items()}
        return other


def bary2_scalar(qx, qy, a, b, c):
    """Barycentric coordinates of the 2D point (qx, qy) in triangle a, b, c (plain floats)."""
    v0x, v0y = b[0] - a[0], b[1] - a[1]
    v1x, v1y = c[0] - a[0], c[1] - a[1]
    v2x, v2y = qx - a[0], qy - a[1]
    den = v0x * v1y - v1x * v0y
    if abs(den) < 1e-300:
        den = 1e-300
    l1 = (v2x * v1y - v1x * v2y) / den
    l2 = (v0x * v2y - v2x * v0y) / den
    return 1.0 - l1 - l2, l1, l2


def bary2(q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Barycentric coordinates (k, 3) of 2D points q (k, 2) in triangles tri (k, 3, 2)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    v0 = b - a
    v1 = c - a
    v2 = q - a
    den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
    den = np.where(np.abs(den) < 1e-300, 1e-300, den)
    l1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
    l2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
    return np.stack([1.0 - l1 - l2, l1, l2], axis=1)
