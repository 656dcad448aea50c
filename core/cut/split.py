"""A mutable triangle mesh that cut lines are inserted into by splitting.

:class:`CutMesh` starts as the body mesh (optionally with the skirt bridge)
and only ever grows: edges are split at a parameter ``t`` and triangles at a
barycentric point, so original vertex ids stay valid. Every vertex keeps its
weights over body vertices (the row of the cut's embedding), and every face
keeps its *parent*: the body triangle (or skirt bridge triangle) it lies in.
All sub-faces of a parent are coplanar with it at the reference shape, which
makes tracing a straight segment across them a planar problem.

Tolerances are relative: a crossing within :data:`SNAP` of an edge end (as a
fraction of the edge) is snapped to that vertex, which avoids zero-length
edges. To avoid sliver triangles a crossing is also snapped to a vertex that is
no more than :data:`SNAP_SLIVER` of the edge and :data:`SNAP_ABS` metres away,
unless that vertex lies on another cut line; the line then passes through the
vertex, off the exact geodesic by at most ``SNAP_ABS`` (not a zig-zag: it still
crosses the triangles, it does not follow mesh edges). The walk itself, and these
tolerances, are in :mod:`core.cut.trace` (a mixin of :class:`CutMesh`).
"""

from __future__ import annotations

from typing import Dict, Sequence, Tuple

import numpy as np

from ..errors import CutError
from .incidence import VertexFaces, bary2
from .trace import SNAP, SNAP_ABS, SNAP_SLIVER, LineTracer


class CutMesh(LineTracer):
    """Growing triangle mesh with per-vertex body weights and per-face parents.

    Parameters
    ----------
    X : (V, 3) float, reference vertex positions (metres).
    F : (F, 3) int, triangles.
    parent_tris : (P, 3, 3) float, corner positions of every parent triangle;
        ``parent[f]`` indexes it. Defaults to the faces themselves.
    parent : (F,) int, parent triangle of each face (default ``arange(F)``).
    weights : dict vertex id -> (cols, vals) body weights for vertices that are
        not body vertices (ids ``>= n_body``).
    n_body : int, number of body vertices (identity rows).
    """

    def __init__(self, X, F, parent_tris=None, parent=None, weights=None, n_body=None):
        X = np.asarray(X, dtype=float)
        F = np.asarray(F, dtype=np.int64)
        self.n_body = int(X.shape[0] if n_body is None else n_body)
        self._X = np.zeros((max(2 * len(X), 16), 3))
        self._X[: len(X)] = X
        self.nv = len(X)
        self._F = np.zeros((max(2 * len(F), 16), 3), dtype=np.int64)
        self._F[: len(F)] = F
        self.nf = len(F)
        self._parent = np.zeros(self._F.shape[0], dtype=np.int64)
        self._parent[: len(F)] = np.arange(len(F)) if parent is None else parent
        if parent_tris is None:
            parent_tris = X[F]
        self._set_parents(np.asarray(parent_tris, dtype=float))
        self.weights: Dict[int, Tuple[np.ndarray, np.ndarray]] = dict(weights or {})
        self._rebuild_adjacency()
        self.cut: Dict[Tuple[int, int], int] = {}  # undirected edge -> line index
        self.cut_verts: Dict[int, set] = {}  # vertex -> line indices through it

    # -- storage ---------------------------------------------------------------------------
    def _set_parents(self, tris: np.ndarray) -> None:
        self._ptris = tris
        p0 = tris[:, 0]
        e1 = tris[:, 1] - p0
        n = np.cross(e1, tris[:, 2] - p0)
        nn = np.linalg.norm(n, axis=1)
        e1 /= np.maximum(np.linalg.norm(e1, axis=1), 1e-300)[:, None]
        n /= np.maximum(nn, 1e-300)[:, None]
        self._p0, self._e1, self._n = p0, e1, n
        self._e2 = np.cross(n, e1)
        self._scale = np.sqrt(np.maximum(nn, 1e-300))  # ~ edge length of the parent
        self._ptri2 = np.stack([self._to2d_all(tris[:, k]) for k in range(3)], axis=1)
        self._frames = {}

    def _to2d_all(self, q: np.ndarray) -> np.ndarray:
        d = q - self._p0
        return np.stack([(d * self._e1).sum(1), (d * self._e2).sum(1)], axis=1)

    def copy(self) -> "CutMesh":
        other = object.__new__(CutMesh)
        other.__dict__.update(self.__dict__)
        other._X = self._X.copy()
        other._F = self._F.copy()
        other._parent = self._parent.copy()
        other.weights = dict(self.weights)
        other.he = dict(self.he)
        other.vf = self.vf.copy()
        other.cut = dict(self.cut)
        other.cut_verts = {k: set(v) for k, v in self.cut_verts.items()}
        return other

    @property
    def X(self) -> np.ndarray:
        return self._X[: self.nv]

    @property
    def F(self) -> np.ndarray:
        return self._F[: self.nf]

    @property
    def parent(self) -> np.ndarray:
        return self._parent[: self.nf]

    def _add_vertex(self, pos: np.ndarray, cols: np.ndarray, vals: np.ndarray) -> int:
        if self.nv == self._X.shape[0]:
            self._X = np.concatenate([self._X, np.zeros_like(self._X)])
        v = self.nv
        self._X[v] = pos
        self.nv += 1
        self.weights[v] = (cols, vals)
        self.vf.append(set())
        return v

    def _add_face(self, tri, parent: int) -> int:
        if self.nf == self._F.shape[0]:
            self._F = np.concatenate([self._F, np.zeros_like(self._F)])
            self._parent = np.concatenate([self._parent, np.zeros_like(self._parent)])
        f = self.nf
        self._F[f] = tri
        self._parent[f] = parent
        self.nf += 1
        return f

    def vertex_weights(self, v: int) -> Tuple[np.ndarray, np.ndarray]:
        """Body weights (cols, vals) of vertex ``v``."""
        if v < self.n_body:
            return np.array([v]), np.array([1.0])
        return self.weights[v]

    def _combine(self, verts: Sequence[int], coef: Sequence[float]):
        acc: Dict[int, float] = {}
        for v, c in zip(verts, coef):
            cv, vv = self.vertex_weights(v)
            for j, w in zip(cv.tolist(), vv.tolist()):
                acc[j] = acc.get(j, 0.0) + w * float(c)
        keys = sorted(k for k, w in acc.items() if abs(w) > 1e-15)
        return np.array(keys, dtype=np.int64), np.array([acc[k] for k in keys])

    # -- topology edits ---------------------------------------------------------------------
    def _set_face(self, f: int, tri) -> None:
        self._F[f] = tri
        a, b, c = tri
        self.he[(a << 32) | b] = f
        self.he[(b << 32) | c] = f
        self.he[(c << 32) | a] = f

    def split_edge(self, a: int, b: int, t: float) -> int:
        """Split edge (a, b) at ``(1-t) a + t b``; returns the new vertex id."""
        f1 = self.he.get((a << 32) | b)
        f2 = self.he.get((b << 32) | a)
        if f1 is None and f2 is None:
            raise CutError(f"internal: edge ({a}, {b}) is not in the mesh")
        pos = (1.0 - t) * self._X[a] + t * self._X[b]
        m = self._add_vertex(pos, *self._combine((a, b), (1.0 - t, t)))
        for f, (p, q) in ((f1, (a, b)), (f2, (b, a))):
            if f is None:
                continue
            tri = self._F[f].tolist()
            k = tri.index(p)
            c = tri[(k + 2) % 3]
            assert tri[(k + 1) % 3] == q
            par = int(self._parent[f])
            del self.he[(p << 32) | q]
            self._set_face(f, (p, m, c))
            g = self._add_face((m, q, c), par)
            self._set_face(g, (m, q, c))
            self.vf[q].discard(f)
            self.vf[q].add(g)
            self.vf[c].add(g)
            self.vf[m].update((f, g))
        key = (a, b) if a < b else (b, a)
        line = self.cut.pop(key, None)
        if line is not None:
            self.cut[(min(a, m), max(a, m))] = line
            self.cut[(min(b, m), max(b, m))] = line
            self.cut_verts.setdefault(m, set()).add(line)
        return m

    def split_face(self, f: int, bary) -> int:
        """Split triangle ``f`` at barycentric ``bary`` into three; returns the new vertex."""
        a, b, c = self._F[f].tolist()
        bary = np.asarray(bary, dtype=float)
        pos = bary @ self._X[[a, b, c]]
        p = self._add_vertex(pos, *self._combine((a, b, c), bary))
        par = int(self._parent[f])
        self._set_face(f, (a, b, p))
        g1 = self._add_face((b, c, p), par)
        self._set_face(g1, (b, c, p))
        g2 = self._add_face((c, a, p), par)
        self._set_face(g2, (c, a, p))
        self.vf[c].discard(f)
        self.vf[a].add(g2)
        self.vf[b].add(g1)
        self.vf[c].update((g1, g2))
        self.vf[p].update((f, g1, g2))
        return p

    def replace_faces(self, remove: np.ndarray, F_new: np.ndarray, parent_tris: np.ndarray) -> None:
        """Delete faces ``remove`` and append faces ``F_new``, each its own new parent
        triangle with corner positions ``parent_tris`` (k, 3, 3). Face ids are compacted;
        vertex ids are unchanged."""
        keep = np.ones(self.nf, dtype=bool)
        keep[np.asarray(remove, dtype=np.int64)] = False
        F_new = np.asarray(F_new, dtype=np.int64).reshape(-1, 3)
        base = self._ptri_count()
        F = np.concatenate([self.F[keep], F_new])
        par = np.concatenate([self.parent[keep], base + np.arange(len(F_new))])
        tris = np.concatenate([self._parent_corners(), np.asarray(parent_tris, float).reshape(-1, 3, 3)])
        if len(F) > self._F.shape[0]:
            self._F = np.zeros((2 * len(F), 3), dtype=np.int64)
            self._parent = np.zeros(2 * len(F), dtype=np.int64)
        self._F[: len(F)] = F
        self._parent[: len(F)] = par
        self.nf = len(F)
        self._set_parents(tris)
        self._rebuild_adjacency()

    def move_body(self, Y: np.ndarray, body_faces: np.ndarray) -> None:
        """Move the body vertices to ``Y`` and re-make the parent triangles on the moved corners.

        For a mesh whose faces have not been split yet (the body mesh, the skirt bridge added by
        :meth:`replace_faces`): every other vertex follows its body weights, parent ``p`` of the
        body's triangles is ``body_faces[p]`` on ``Y``, and every later parent (a bridge triangle,
        its own face's parent) is its face on the moved vertices.

        Parameters
        ----------
        Y : (n_body, 3) float, the body vertices' new positions (metres).
        body_faces : (Fb, 3) int, the body's triangles (parents ``0 .. Fb - 1``).
        """
        Xn = self._X
        Xn[: self.n_body] = Y
        for v in range(self.n_body, self.nv):
            c, w = self.vertex_weights(v)
            Xn[v] = w @ Y[c]
        tris = self._parent_corners().copy()
        tris[: len(body_faces)] = Y[body_faces]
        own = self.parent >= len(body_faces)
        tris[self.parent[own]] = self.X[self.F[own]]
        self._set_parents(tris)

    def _ptri_count(self) -> int:
        return int(self._p0.shape[0])

    def _parent_corners(self) -> np.ndarray:
        return self._ptris

    def _rebuild_adjacency(self) -> None:
        # half-edge key (a << 32 | b) -> face, and vertex -> incident faces
        F = self.F
        he = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
        fid = np.repeat(np.arange(len(F)), 3)
        self.he: Dict[int, int] = dict(zip(((he[:, 0] << 32) | he[:, 1]).tolist(), fid.tolist()))
        self.vf = VertexFaces(F, self.nv)

    # -- geometry ---------------------------------------------------------------------------
    def _to2d(self, P: np.ndarray, q: np.ndarray) -> np.ndarray:
        """2D coords of points q (k, 3) in the frames of parents P (k,)."""
        d = q - self._p0[P]
        return np.stack([(d * self._e1[P]).sum(-1), (d * self._e2[P]).sum(-1)], axis=-1)

    def parent_contains(self, P: np.ndarray, q: np.ndarray, tol: float = 1e-6) -> np.ndarray:
        """Whether point ``q`` (3,) lies on each parent triangle P (k,) (relative tol)."""
        P = np.asarray(P)
        d = q[None] - self._p0[P]
        off = np.abs((d * self._n[P]).sum(-1)) <= tol * self._scale[P]
        b = bary2(self._to2d(P, np.broadcast_to(q, (len(P), 3))), self._ptri2[P])
        return off & (b.min(axis=1) >= -tol)

    def locate_in_parent(self, P: int, q: np.ndarray) -> Tuple[int, np.ndarray]:
        """The face (child of parent ``P``) containing point ``q`` and its barycentrics."""
        faces = np.nonzero(self.parent == P)[0]
        if len(faces) == 0:
            raise KeyError(P)
        tri = self.F[faces]
        Pv = np.full(len(faces), P)
        c2 = np.stack([self._to2d(Pv, self._X[tri[:, k]]) for k in range(3)], axis=1)
        b = bary2(self._to2d(Pv, np.broadcast_to(q, (len(faces), 3))), c2)
        k = int(np.argmax(b.min(axis=1)))
        return int(faces[k]), b[k]

    def insert_point(self, f: int, bary: np.ndarray) -> int:
        """Make the point ``bary`` of face ``f`` a vertex (snap, split an edge or the face)."""
        bary = np.clip(np.asarray(bary, dtype=float), 0.0, None)
        bary = bary / bary.sum()
        tri = self._F[f].tolist()
        k = int(np.argmax(bary))
        if bary[k] >= 1.0 - SNAP:
            return tri[k]
        near = self._near_corner(tri, bary, set())
        if near is not None:
            return near
        # distance to each edge (opposite corner j) = bary_j x height_j
        P = self._X[tri]
        el = np.linalg.norm(np.roll(P, -1, axis=0) - np.roll(P, 1, axis=0), axis=1)  # edge opposite j
        area2 = np.linalg.norm(np.cross(P[1] - P[0], P[2] - P[0]))
        dist = bary * area2 / np.maximum(el, 1e-300)
        lim = np.minimum(SNAP_SLIVER * el, SNAP_ABS)
        small = (bary < SNAP) | (dist < lim)
        if small.sum() >= 1:
            j = int(np.argmin(np.where(small, dist, np.inf)))
            a, b = tri[(j + 1) % 3], tri[(j + 2) % 3]
            wa, wb = bary[(j + 1) % 3], bary[(j + 2) % 3]
            return self.split_edge(a, b, wb / (wa + wb))
        return self.split_face(f, bary)
