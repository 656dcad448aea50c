"""Tracing a cut line across a :class:`core.cut.split.CutMesh`: the walk from one vertex
towards a target point, triangle by triangle, inserting the crossings as vertices.

A mixin of :class:`~core.cut.split.CutMesh` (it reads the mesh's parents, frames and
incidence, and splits through its public operations), kept apart because the walk is
its own operation. Tolerances are relative: a crossing within :data:`SNAP` of an edge
end (as a fraction of the edge) is snapped to that vertex, and one no more than
:data:`SNAP_SLIVER` of the edge and :data:`SNAP_ABS` metres from a free vertex snaps to
it too (no sliver triangles), unless that vertex lies on another cut line or is one the
line must avoid (:attr:`LineTracer.avoid`).
"""

from __future__ import annotations

from typing import List, Optional

import numpy as np

from ..errors import CutError
from .incidence import bary2, bary2_scalar

SNAP = 1e-3  # relative snap distance on an edge / in a triangle (always)
SNAP_SLIVER = 0.05  # a crossing this close to a free vertex (relative to the edge) snaps to it...
SNAP_ABS = 5e-4  # ...if it is also within this many metres: no sliver triangles
_INSIDE = 1e-9  # barycentric slack for "point lies in this triangle"
_MAX_STEPS = 100000  # guard against a walk that does not progress


class LineTracer:
    """The tracing half of :class:`~core.cut.split.CutMesh` (see the module docstring)."""

    #: vertices the line being traced may not snap to (a mirrored dart: the body's midline,
    #: :func:`core.cut.darts.midline_guards`); set by the cut engine per line
    avoid: frozenset = frozenset()

    def _frame(self, P: int):
        fr = self._frames.get(P)
        if fr is None:
            fr = (
                self._p0[P].tolist(),
                self._e1[P].tolist(),
                self._e2[P].tolist(),
                self._n[P].tolist(),
                float(self._scale[P]),
                self._ptri2[P].tolist(),
            )
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

    def trace(
        self, A: int, target: np.ndarray, line: int, allowed: set, target_vertex: Optional[int] = None, names=None
    ) -> List[int]:
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
            if target_vertex is not None and (
                ((cur << 32) | target_vertex) in self.he or ((target_vertex << 32) | cur) in self.he
            ):
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
        """A vertex a line may snap to: not on another cut line (unless a keypoint of this one) nor
        one of :attr:`avoid`."""
        return v in allowed or not (self.cut_verts.get(v) or v in self.avoid)

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
