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
crosses the triangles, it does not follow mesh edges).
"""
from __future__ import annotations

from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..errors import CutError
from .incidence import VertexFaces, bary2, bary2_scalar

SNAP = 1e-3          # relative snap distance on an edge / in a triangle (always)
SNAP_SLIVER = 0.05   # a crossing this close to a free vertex (relative to the edge) snaps to it...
SNAP_ABS = 5e-4      # ...if it is also within this many metres: no sliver triangles
_INSIDE = 1e-9       # barycentric slack for "point lies in this triangle"
_MAX_STEPS = 100000  # guard against a walk that does not progress


class CutMesh:
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
        self.cut: Dict[Tuple[int, int], int] = {}     # undirected edge -> line index
        self.cut_verts: Dict[int, set] = {}            # vertex -> line indices through it

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
        self._scale = np.sqrt(np.maximum(nn, 1e-300))   # ~ edge length of the parent
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
        el = np.linalg.norm(np.roll(P, -1, axis=0) - np.roll(P, 1, axis=0), axis=1)   # edge opposite j
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

    # -- tracing ----------------------------------------------------------------------------
    def _frame(self, P: int):
        fr = self._frames.get(P)
        if fr is None:
            fr = (self._p0[P].tolist(), self._e1[P].tolist(), self._e2[P].tolist(), self._n[P].tolist(),
                  float(self._scale[P]), self._ptri2[P].tolist())
            self._frames[P] = fr
        return fr

    def _best_wedge(self, cur: int, target: np.ndarray):
        """The face around ``cur`` (in a parent that holds ``target``) whose wedge at
        ``cur`` contains the direction to ``target``: (face, u, w, bA, bu, bw) with the
        barycentrics of ``target`` in (cur, u, w), or None. Plain floats: it runs per step."""
        tx, ty, tz = target.tolist()
        X = self._X
        par = self._parent
        Fa = self._F
        pq = {}
        best = None
        for f in sorted(self.vf[cur]):
            P = int(par[f])
            q = pq.get(P)
            if q is None:
                (ox, oy, oz), (ax, ay, az), (bx, by, bz), (nx, ny, nz), sc, T = self._frame(P)
                dx, dy, dz = tx - ox, ty - oy, tz - oz
                qx = dx * ax + dy * ay + dz * az
                qy = dx * bx + dy * by + dz * bz
                ok = abs(dx * nx + dy * ny + dz * nz) <= 1e-6 * sc
                if ok:
                    b = bary2_scalar(qx, qy, T[0], T[1], T[2])
                    ok = min(b) >= -1e-6
                q = (qx, qy, ok)
                pq[P] = q
            if not q[2]:
                continue
            a, b_, c = Fa[f].tolist()
            if a == cur:
                u, w = b_, c
            elif b_ == cur:
                u, w = c, a
            else:
                u, w = a, b_
            (ox, oy, oz), (ax, ay, az), (bx, by, bz), _, _, _ = self._frame(P)
            pts = []
            for v in (cur, u, w):
                x, y, z = X[v].tolist()
                dx, dy, dz = x - ox, y - oy, z - oz
                pts.append((dx * ax + dy * ay + dz * az, dx * bx + dy * by + dz * bz))
            bA, bu, bw = bary2_scalar(q[0], q[1], *pts)
            score = min(bu, bw)
            if best is None or score > best[0]:
                best = (score, f, u, w, bA, bu, bw)
        return None if best is None else best[1:]

    def _wedges(self, cur: int, faces: np.ndarray, target: np.ndarray):
        """Faces around ``cur`` whose parent holds ``target``, rotated to start at ``cur``,
        and the barycentrics (k, 3) of ``target`` in each (in the parent's plane)."""
        P = self._parent[faces]
        p0, e1, e2 = self._p0[P], self._e1[P], self._e2[P]
        d = target[None] - p0
        q = np.stack([np.einsum("ij,ij->i", d, e1), np.einsum("ij,ij->i", d, e2)], axis=1)
        off = np.abs(np.einsum("ij,ij->i", d, self._n[P])) <= 1e-6 * self._scale[P]
        inside = bary2(q, self._ptri2[P]).min(axis=1) >= -1e-6
        ok = off & inside
        faces, P, q, p0, e1, e2 = faces[ok], P[ok], q[ok], p0[ok], e1[ok], e2[ok]
        tri = self._F[faces]
        k = np.argmax(tri == cur, axis=1)
        idx = (k[:, None] + np.arange(3)[None]) % 3
        tri = np.take_along_axis(tri, idx, axis=1)
        D = self._X[tri] - p0[:, None, :]
        c2 = np.stack([np.einsum("ijk,ik->ij", D, e1), np.einsum("ijk,ik->ij", D, e2)], axis=2)
        return faces, tri, bary2(q, c2)

    def trace(self, A: int, target: np.ndarray, line: int, allowed: set,
              target_vertex: Optional[int] = None, names=None) -> List[int]:
        """Insert the straight (in-parent) segment from vertex ``A`` to point ``target``.

        Edges crossed are split (or the crossing snapped to a nearby vertex);
        the segment's vertices are returned (without ``A``), and its edges are
        marked as cut by ``line``. ``allowed``: vertices where the line may
        meet other lines (its keypoints). Raises :class:`CutError` where the
        line meets another line (or itself) elsewhere.
        """
        out: List[int] = []
        cur = A
        for _ in range(_MAX_STEPS):
            if target_vertex is not None and (cur == target_vertex):
                return out
            if target_vertex is not None and (((cur << 32) | target_vertex) in self.he or ((target_vertex << 32) | cur) in self.he):
                self._mark(cur, target_vertex, line, allowed, names)
                out.append(target_vertex)
                return out
            if not self.vf[cur]:
                raise CutError(f"internal: vertex {cur} has no faces")
            best = self._best_wedge(cur, target)
            if best is None:
                raise CutError(f"{_name(names, line)}: could not trace the geodesic across the mesh")
            f, u, w, bA, bu, bw = best
            if bA >= -_INSIDE:
                # target is in this triangle's closure: finish here
                nxt = self._finish(f, cur, u, w, np.array([bA, bu, bw]), line, allowed, names)
                if nxt != cur:
                    self._mark(cur, nxt, line, allowed, names)
                    out.append(nxt)
                    if target_vertex is not None and nxt != target_vertex:
                        cur = nxt
                        continue
                return out
            s = 1.0 / (1.0 - bA)
            t = float(np.clip(s * bw, 0.0, 1.0))
            tol = self._snap_tol(u, w)
            if t < SNAP or (t < tol and self._free(u, allowed)):
                nxt = u
            elif t > 1.0 - SNAP or (t > 1.0 - tol and self._free(w, allowed)):
                nxt = w
            else:
                key = (u, w) if u < w else (w, u)
                if key in self.cut:
                    raise CutError(f"cut lines {_name(names, line)} and {_name(names, self.cut[key])} cross")
                nxt = self.split_edge(u, w, t)
            self._mark(cur, nxt, line, allowed, names)
            out.append(nxt)
            cur = nxt
        raise CutError(f"{_name(names, line)}: tracing the geodesic did not terminate")

    def _snap_tol(self, u: int, w: int) -> float:
        """Edge-parameter distance within which a crossing of edge (u, w) snaps to its end:
        :data:`SNAP_SLIVER` of the edge, at most :data:`SNAP_ABS` metres."""
        L = float(np.linalg.norm(self._X[u] - self._X[w]))
        return min(SNAP_SLIVER, SNAP_ABS / max(L, 1e-300))

    def _near_corner(self, tri, b, allowed, first_free=False):
        """A corner of triangle ``tri`` within the sliver snap distance of the point with
        barycentrics ``b`` (and free to snap to), or None."""
        P = self._X[list(tri)]
        pos = np.asarray(b) @ P
        L = np.linalg.norm(P - np.roll(P, 1, axis=0), axis=1).max()
        lim = min(SNAP_SLIVER * L, SNAP_ABS)
        d = np.linalg.norm(P - pos, axis=1)
        for k in np.argsort(d, kind="stable").tolist():
            if d[k] >= lim:
                break
            if (first_free and k == 0) or self._free(tri[k], allowed):
                return tri[k]
        return None

    def _free(self, v: int, allowed: set) -> bool:
        """A vertex a line may snap to: not on another cut line (unless a keypoint of this one)."""
        return v in allowed or not self.cut_verts.get(v)

    def _finish(self, f, cur, u, w, b, line, allowed, names) -> int:
        b = np.clip(b, 0.0, None)
        b = b / b.sum()
        bA, bu, bw = b
        if bA >= 1.0 - SNAP:
            return cur
        if bu >= 1.0 - SNAP:
            return u
        if bw >= 1.0 - SNAP:
            return w
        if bA < SNAP:
            a0, a1, t = u, w, bw / (bu + bw)
        elif bu < SNAP:
            a0, a1, t = cur, w, bw / (bA + bw)
        elif bw < SNAP:
            a0, a1, t = cur, u, bu / (bA + bu)
        else:
            tri = self._F[f].tolist()
            k = tri.index(cur)
            order = [cur, u, w]
            bb = np.zeros(3)
            for j in range(3):
                bb[(k + j) % 3] = b[j]
            assert [tri[(k + j) % 3] for j in range(3)] == order
            return self.split_face(f, bb)
        # a point very close to an end of its edge snaps to it (no sliver); only ends of the
        # same edge, so the snapped vertex still lies on both triangles of the body edge
        tol = self._snap_tol(a0, a1)
        if t < tol and (a0 == cur or self._free(a0, allowed)):
            return a0
        if t > 1.0 - tol and (a1 == cur or self._free(a1, allowed)):
            return a1
        key = (a0, a1) if a0 < a1 else (a1, a0)
        if key in self.cut:
            raise CutError(f"cut lines {_name(names, line)} and {_name(names, self.cut[key])} cross")
        return self.split_edge(a0, a1, t)

    def _mark(self, a: int, b: int, line: int, allowed: set, names) -> None:
        key = (a, b) if a < b else (b, a)
        prev = self.cut.get(key)
        if prev is not None:
            raise CutError(f"cut lines {_name(names, line)} and {_name(names, prev)} overlap")
        others = self.cut_verts.get(b)
        if others and b not in allowed:
            if line in others:
                raise CutError(f"cut line {_name(names, line)} crosses itself")
            raise CutError(f"cut lines {_name(names, line)} and {_name(names, min(others))} cross")
        self.cut[key] = line
        self.cut_verts.setdefault(a, set()).add(line)
        self.cut_verts.setdefault(b, set()).add(line)


def _name(names, line) -> str:
    if names is None:
        return f"#{line}"
    return repr(names[line])
