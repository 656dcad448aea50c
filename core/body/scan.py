"""Bodies from scans: fit Anny's pose, shape and local changes to a 3D scan or point cloud.

As the EASE paper fitted SMPL to a scan for its manufacturing experiment, :func:`fit_scan`
fits the default body (Anny) to the points of a scan (``.obj`` vertices or ``.ply`` vertices,
ASCII or binary; faces, if any, are ignored): the body's placement (a rotation and a
translation), the rotations of the joints a standing person moves (:data:`POSE_JOINTS`), the
phenotypes and every local change of :data:`core.body.made_to_measure.LOCAL_FOR`.

The fit is an iterative closest point in Levenberg-Marquardt form:

- each round matches every scan point to the nearest body vertex and every body vertex to the
  nearest scan point (a match further than :data:`BODY_TO_SCAN_REACH` is a hole of the scan and
  left out), and takes point-to-plane distances along the body's normals, with a Huber weight
  beyond :data:`HUBER_MM`;
- a finite-difference Jacobian of the matched body points (one body per parameter) gives a
  damped Gauss-Newton step; local changes are pulled towards 0, phenotypes towards the average,
  joint rotations towards the A-pose (:data:`PULL_MM`), so holes do not let the body wander;
- it starts from the best of :data:`START_YAWS` turns about the vertical, each aligned by a
  rigid ICP (a scan may face any way).

:func:`scan_distance` gives the scan-to-body distance (each point to the nearest triangle of the
fitted body), :func:`scan_girths` the torso girths measured on the scan itself at the levels
the fitted body's tape measures use (docs/measurements.md). :func:`synthetic_scan` makes a
scan of a body of hidden shape and pose (points resampled on its triangles, noise, holes, no
soles) for tests and ``ease bench --only body``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Mapping, Optional

import numpy as np

from ..errors import BodyError
from ..geom.mesh import vertex_normals
from ..progress import Progress, report
from .made_to_measure import ADULT_AGE, LOCAL_FOR, PHENOTYPES
from .tape import LIMB_PLANES, TAPE_MEASURES, levels, limb_plane, plane_basis, tape_measures

# The fewest points a scan may have: fewer cannot pin down 60-odd parameters.
MIN_POINTS = 500
# Points the fit uses (an even sample of a larger scan); the distances are taken on all.
FIT_POINTS = 4000
# Joints a scanned person moves (their rotations on top of the A-pose are fitted).
POSE_JOINTS = (
    "spine03",
    "spine01",
    "neck01",
    "upperarm01.L",
    "upperarm01.R",
    "lowerarm01.L",
    "lowerarm01.R",
    "upperleg01.L",
    "upperleg01.R",
    "lowerleg01.L",
    "lowerleg01.R",
)
# Pulls (mm of mean distance per unit): local changes to 0, phenotypes to their start, joints to
# the A-pose (per radian).
PULL_MM = {"local": 0.6, "phenotype": 0.2, "pose": 0.3}
# A body vertex further than this from every scan point lies in a hole of the scan (m).
BODY_TO_SCAN_REACH = 0.03
# The weight of the body-to-scan distances beside the scan-to-body ones.
BODY_TO_SCAN_WEIGHT = 0.3
# Distances beyond this weigh linearly (Huber), not quadratically (mm).
HUBER_MM = 10.0
# Turns about the vertical tried at the start (radians).
START_YAWS = tuple(np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False))
# Finite-difference steps: shape parameters (units), joint and body rotations (rad), metres.
STEP = {"shape": 0.02, "pose": 0.02, "rotation": 0.01, "translation": 0.002}
# The fit stops when a round's cost (at fresh matches) is less than this share below the last's.
STOP_GAIN = 0.01
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


# -- reading --------------------------------------------------------------------------------------
def _read_obj(path: Path) -> np.ndarray:
    rows = []
    with open(path, "r", encoding="utf-8", errors="replace") as fh:
        for number, line in enumerate(fh, 1):
            if line.startswith("v ") or line.startswith("v\t"):
                parts = line.split()
                try:
                    rows.append([float(t) for t in parts[1:4]])
                except ValueError:
                    raise BodyError(f"{path}:{number}: vertex is not three numbers: {line.strip()[:60]!r}") from None
                if len(rows[-1]) != 3:
                    raise BodyError(f"{path}:{number}: vertex is not three numbers: {line.strip()[:60]!r}")
    return np.array(rows, dtype=float).reshape(-1, 3)


_PLY_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}


def _read_ply(path: Path) -> np.ndarray:
    data = path.read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise BodyError(f"{path}: not a PLY file (no 'ply' ... 'end_header' header)")
    nl = data.find(b"\n", end)
    header = data[:end].decode("ascii", errors="replace").splitlines()
    body = data[nl + 1 :] if nl >= 0 else b""
    fmt, elements = None, []
    for line in header:
        t = line.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1] if len(t) > 1 else None
        elif t[0] == "element" and len(t) == 3:
            try:
                elements.append([t[1], int(t[2]), []])
            except ValueError:
                raise BodyError(f"{path}: bad PLY element line {line!r}") from None
        elif t[0] == "property" and elements:
            elements[-1][2].append(t[1:])
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise BodyError(f"{path}: unknown PLY format {fmt!r}")
    if not elements or elements[0][0] != "vertex":
        raise BodyError(f"{path}: the PLY's first element must be 'vertex'")
    _, count, props = elements[0]
    names = [p[-1] for p in props]
    if any(p[0] == "list" for p in props) or not {"x", "y", "z"} <= set(names):
        raise BodyError(f"{path}: the PLY's vertices need x, y, z properties (and no lists)")
    if fmt == "ascii":
        lines = body.decode("ascii", errors="replace").splitlines()
        if len(lines) < count:
            raise BodyError(f"{path}: {count} vertices announced, {len(lines)} lines given")
        try:
            table = np.array([[float(s) for s in ln.split()[: len(names)]] for ln in lines[:count]], dtype=float)
        except ValueError:
            raise BodyError(f"{path}: a vertex line is not numbers") from None
        if table.shape != (count, len(names)):
            raise BodyError(f"{path}: a vertex line has fewer than {len(names)} values")
        cols = table.T
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        try:
            dtype = np.dtype([(n, order + _PLY_TYPES[p[0]]) for n, p in zip(names, props)])
        except KeyError as exc:
            raise BodyError(f"{path}: unknown PLY property type {exc.args[0]!r}") from None
        if len(body) < count * dtype.itemsize:
            raise BodyError(f"{path}: {count} vertices announced, the file is shorter")
        rec = np.frombuffer(body, dtype=dtype, count=count)
        cols = [rec[n].astype(float) for n in names]
    return np.stack([np.asarray(cols[names.index(a)], dtype=float) for a in "xyz"], axis=1)


def read_scan(path, up: str = "z", units: str = "auto") -> np.ndarray:
    """The points (N, 3) of a scan in metres, in the body's frame (+Z up).

    ``path``: an ``.obj`` (its ``v`` lines) or ``.ply`` (ASCII or binary; the vertex element's
    x, y, z). ``up``: the file's up axis, ``z`` or ``y`` (a Y-up file is turned Z-up, as a body
    OBJ). ``units``: ``m``, ``cm``, ``mm`` or ``auto`` (read from the scan's height: 0.5-2.5
    in the file's numbers is metres, 50-250 centimetres, 500-2500 millimetres).
    A BodyError naming the file for an unreadable file, non-finite values or fewer than
    :data:`MIN_POINTS` points."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in (".obj", ".ply"):
        raise BodyError(f"{p}: a scan must be .obj or .ply, got {suffix or 'no extension'!r}")
    if up not in ("z", "y"):
        raise BodyError(f"{p}: up must be 'z' or 'y', got {up!r}")
    if units not in ("auto", *UNITS):
        raise BodyError(f"{p}: units must be auto, m, cm or mm, got {units!r}")
    try:
        pts = _read_obj(p) if suffix == ".obj" else _read_ply(p)
    except OSError as exc:
        raise BodyError(f"{p}: cannot read the scan ({exc.strerror or exc})") from None
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        raise BodyError(f"{p}: point {int(np.argmax(bad)) + 1} of {len(pts)} is not finite (NaN or infinity)")
    if len(pts) < MIN_POINTS:
        raise BodyError(f"{p}: {len(pts)} points; a scan needs at least {MIN_POINTS}")
    if up == "y":
        pts = pts @ np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]).T
    height = float(np.ptp(pts[:, 2]))
    if units == "auto":
        scale = next((UNITS[u] for u, lo in (("m", 0.5), ("cm", 50.0), ("mm", 500.0)) if lo <= height <= 5 * lo), None)
        if scale is None:
            raise BodyError(
                f"{p}: the scan is {height:g} high along {up.upper()}: not a standing person in m, cm or mm "
                "(give the units, or the up axis)"
            )
    else:
        scale = UNITS[units]
    pts = pts * scale
    if not 0.5 <= float(np.ptp(pts[:, 2])) <= 2.5:
        raise BodyError(f"{p}: the scan is {np.ptp(pts[:, 2]):.3g} m high: not a standing person")
    return pts


def write_points(path, points: np.ndarray) -> None:
    """Write points (N, 3, metres) as a binary little-endian PLY (``.ply``) or OBJ vertices."""
    p = Path(path)
    pts = np.asarray(points, dtype="<f4")
    if p.suffix.lower() == ".ply":
        head = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\n"
        head += "property float x\nproperty float y\nproperty float z\nend_header\n"
        p.write_bytes(head.encode("ascii") + pts.tobytes())
    else:
        p.write_text("".join(f"v {x:.5f} {y:.5f} {z:.5f}\n" for x, y, z in pts), encoding="utf-8")


# -- geometry -----------------------------------------------------------------------------------
def _rotation(rotvec) -> np.ndarray:
    from .lbs import rodrigues

    return rodrigues(np.asarray(rotvec, dtype=float)[None])[0]


def point_triangle_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance of each point ``p[i]`` to the triangle ``(a[i], b[i], c[i])``."""
    return np.linalg.norm(p - closest_on_triangle(p, a, b, c), axis=1)


def closest_on_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The point of the triangle ``(a[i], b[i], c[i])`` nearest ``p[i]`` (Ericson's regions)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = np.where(np.abs(va + vb + vc) > 1e-30, va + vb + vc, 1e-30)
    v, w = vb / denom, vc / denom
    q = a + ab * v[:, None] + ac * w[:, None]  # inside the face
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab = np.clip(d1 / (d1 - d3), 0, 1)
        t_ac = np.clip(d2 / (d2 - d6), 0, 1)
        t_bc = np.clip((d4 - d3) / ((d4 - d3) + (d5 - d6)), 0, 1)
    edge = {
        "ab": (vc <= 0) & (d1 >= 0) & (d3 <= 0),
        "ac": (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        "bc": (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),
    }
    q = np.where(edge["bc"][:, None], b + np.nan_to_num(t_bc)[:, None] * (c - b), q)
    q = np.where(edge["ac"][:, None], a + np.nan_to_num(t_ac)[:, None] * ac, q)
    q = np.where(edge["ab"][:, None], a + np.nan_to_num(t_ab)[:, None] * ab, q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
    return np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)


def nearest_on_mesh(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, candidates: int = 12):
    """For each point, the nearest triangle of the mesh (among the ``candidates`` whose centroids
    are nearest, exact within them): (triangle ids (N,), closest points (N, 3), distances (N,))."""
    from scipy.spatial import cKDTree

    tri = vertices[faces]
    _, idx = cKDTree(tri.mean(axis=1)).query(points, k=candidates)
    n, k = idx.shape
    t = tri[idx.ravel()]
    q = closest_on_triangle(np.repeat(points, k, axis=0), t[:, 0], t[:, 1], t[:, 2]).reshape(n, k, 3)
    d = np.linalg.norm(q - points[:, None], axis=2)
    best = d.argmin(axis=1)
    rows = np.arange(n)
    return idx[rows, best], q[rows, best], d[rows, best]


def scan_distance(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray, candidates: int = 12) -> np.ndarray:
    """Distance (m) of each scan point to the nearest triangle of the body (the ``candidates``
    triangles whose centroids are nearest, exact within them)."""
    return nearest_on_mesh(points, vertices, faces, candidates)[2]


def barycentric(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(N, 3) barycentric coordinates of points ``q`` of the triangles (a, b, c)."""
    v0, v1, v2 = b - a, c - a, q - a
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((v0, v0), (v0, v1), (v1, v1)))
    d20, d21 = np.einsum("ij,ij->i", v2, v0), np.einsum("ij,ij->i", v2, v1)
    den = np.where(np.abs(d00 * d11 - d01 * d01) > 1e-30, d00 * d11 - d01 * d01, 1e-30)
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    return np.stack([1.0 - v - w, v, w], axis=1)


# -- synthetic scans -------------------------------------------------------------------------------
def hidden_pose(rng: np.random.Generator, amount: float = 1.0) -> Dict[str, list]:
    """A standing person's pose off the A-pose: each joint of :data:`POSE_JOINTS` turned by a
    random rotation (arms up to ~0.25 rad, elbows 0.3, hips 0.1, knees 0.15, spine and neck 0.08)."""
    scale = {"spine": 0.08, "neck": 0.08, "upperarm": 0.25, "lowerarm": 0.3, "upperleg": 0.1, "lowerleg": 0.15}
    out = {}
    for j in POSE_JOINTS:
        s = next(v for k, v in scale.items() if j.startswith(k))
        out[j] = [float(a) for a in rng.uniform(-s, s, 3) * amount]
    return out


def synthetic_scan(
    body,
    shape: Mapping[str, float],
    pose,
    rng: np.random.Generator,
    points: int = 4000,
    noise: float = 0.002,
    holes: int = 4,
    hole_radius=(0.04, 0.07),
    yaw: Optional[float] = None,
    shift=(0.3, 0.3, 0.05),
) -> np.ndarray:
    """A scan of ``body`` at ``shape`` and ``pose``: ``points`` points drawn uniformly over its
    surface (random points of its triangles, none at its vertices), Gaussian noise of s.d.
    ``noise`` (m) in every direction, ``holes`` round holes (all points within a radius drawn
    from ``hole_radius`` of a random surface point removed) and no soles (a scanner does not
    see the feet's undersides), then turned by ``yaw`` about the vertical (random by default)
    and moved by up to ``shift`` (m)."""
    v = body.vertices(shape, pose)
    tri = v[body.faces]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    n_draw = int(points * 1.6)
    pick = rng.choice(len(tri), size=n_draw, p=area / area.sum())
    r1, r2 = np.sqrt(rng.random(n_draw)), rng.random(n_draw)
    t = tri[pick]
    pts = (1 - r1)[:, None] * t[:, 0] + (r1 * (1 - r2))[:, None] * t[:, 1] + (r1 * r2)[:, None] * t[:, 2]
    keep = pts[:, 2] > v[:, 2].min() + 0.01  # no soles
    for _ in range(holes):
        centre = pts[rng.integers(len(pts))]
        keep &= np.linalg.norm(pts - centre, axis=1) > rng.uniform(*hole_radius)
    pts = pts[keep]
    pts = pts[rng.permutation(len(pts))[:points]]
    pts = pts + rng.normal(0.0, noise, pts.shape)
    yaw = rng.uniform(-np.pi, np.pi) if yaw is None else yaw
    R = _rotation([0.0, 0.0, yaw])
    return pts @ R.T + rng.uniform(-1, 1, 3) * np.asarray(shift, dtype=float)


# -- the fit ---------------------------------------------------------------------------------------
@dataclass
class ScanFit:
    """Outcome of :func:`fit_scan`.

    shape : phenotypes and local changes; pose : joint -> axis-angle (radians) on the A-pose.
    rotation (3,3), translation (3,) : the body's placement onto the scan (scan = R v + t).
    distance_mm : mean, p95 and max of the scan-to-body distance (every scan point).
    body_cm : the fitted body's tape measures (A-pose); scan_cm : the scan's girths (torso, thigh,
    neck, upper arm, wrist) and height at the fitted body's levels and planes (None where the
    scan has too few points there).
    """

    shape: Dict[str, float]
    pose: Dict[str, list]
    rotation: np.ndarray
    translation: np.ndarray
    distance_mm: Dict[str, float]
    body_cm: Dict[str, float]
    scan_cm: Dict[str, Optional[float]] = field(default_factory=dict)
    evaluations: int = 0
    rounds: int = 0

    def summary(self) -> str:
        d = self.distance_mm
        lines = [
            f"scan to body: mean {d['mean']:.1f} mm, p95 {d['p95']:.1f} mm, max {d['max']:.1f} mm "
            f"({d['points']} points; {self.rounds} rounds, {self.evaluations} body evaluations)",
            f"{'measure':>17}  {'body':>6}  {'scan':>6}  (cm; scan: its points at the body's tape levels)",
        ]
        for name in TAPE_MEASURES:
            s = self.scan_cm.get(name)
            lines.append(f"{name:>17}: {self.body_cm[name]:6.1f}  {'-' if s is None else f'{s:6.1f}':>6}")
        return "\n".join(lines)


class _Problem:
    """The parameter vector of a scan fit: [rotation (3), translation (3), joints, shape]."""

    def __init__(self, body, local: bool):
        allowed = {**body.shape_parameters(), **body.local_change_parameters()}
        self.body = body
        self.shape_names = list(PHENOTYPES) + ["gender"]
        if local:
            self.shape_names += [c for v in LOCAL_FOR.values() for c in v if c in allowed]
        self.local = set(body.local_change_parameters())
        base = body.default_shape()
        lo = [-np.inf] * 6 + [-1.0] * (3 * len(POSE_JOINTS))
        hi = [np.inf] * 6 + [1.0] * (3 * len(POSE_JOINTS))
        for n in self.shape_names:
            a, b, _ = allowed[n]
            if n == "age":
                a, b = ADULT_AGE
            lo.append(a)
            hi.append(b)
        self.lo, self.hi = np.array(lo), np.array(hi)
        self.n_pose = 3 * len(POSE_JOINTS)
        self.start_shape = np.array([base.get(n, 0.0) if n != "age" else 0.7 for n in self.shape_names])
        steps = [STEP["rotation"]] * 3 + [STEP["translation"]] * 3 + [STEP["pose"]] * self.n_pose
        self.steps = np.array(steps + [STEP["shape"]] * len(self.shape_names))
        pulls = [0.0] * 6 + [PULL_MM["pose"]] * self.n_pose
        pulls += [PULL_MM["local"] if n in self.local else PULL_MM["phenotype"] for n in self.shape_names]
        self.pull = np.array(pulls)
        self.prior = np.zeros(6 + self.n_pose + len(self.shape_names))
        self.prior[6 + self.n_pose :] = [
            0.0 if n in self.local else s for n, s in zip(self.shape_names, self.start_shape)
        ]
        self.evaluations = 0
        self._memo = {}

    def x0(self, yaw: float, translation) -> np.ndarray:
        return np.concatenate([[0.0, 0.0, yaw], translation, np.zeros(self.n_pose), self.start_shape])

    def shape(self, x) -> Dict[str, float]:
        s = dict(self.body.default_shape())
        for n, val in zip(self.shape_names, x[6 + self.n_pose :]):
            if n in self.local and val == 0.0:
                continue
            s[n] = float(val)
        return s

    def pose(self, x) -> Dict[str, list]:
        p = x[6 : 6 + self.n_pose].reshape(-1, 3)
        return {j: [float(a) for a in r] for j, r in zip(POSE_JOINTS, p)}

    def local_vertices(self, x) -> np.ndarray:
        """The body at x before its placement (the body's own frame)."""
        key = x[6:].tobytes()
        hit = self._memo.get(key)
        if hit is None:
            self.evaluations += 1
            hit = self.body.vertices(self.shape(x), self.pose(x))
            if len(self._memo) > 4:
                self._memo.clear()
            self._memo[key] = hit
        return hit

    def world(self, x) -> np.ndarray:
        return self.local_vertices(x) @ _rotation(x[:3]).T + x[3:6]


def _matches(prob, x, scan, tree_scan):
    """Matches at x: each scan point to its nearest point of the body's surface (a triangle and
    barycentric weights, the face's normal), each body vertex to the nearest scan point within
    :data:`BODY_TO_SCAN_REACH` (further: a hole of the scan; its vertex normal)."""
    W = prob.world(x)
    F = prob.body.faces
    tri, q, _ = nearest_on_mesh(scan, W, F)
    t = W[F[tri]]
    bary = barycentric(q, t[:, 0], t[:, 1], t[:, 2])
    n_face = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    n_face /= np.maximum(np.linalg.norm(n_face, axis=1, keepdims=True), 1e-12)
    d, idx = tree_scan.query(W, distance_upper_bound=BODY_TO_SCAN_REACH)
    verts = np.flatnonzero(np.isfinite(d))
    N = vertex_normals(W, F)  # core.geom.mesh
    return F[tri], bary, n_face, verts, N[verts], scan[idx[verts]]


def _residuals(prob, x, scan, m):
    """Point-to-plane distances (mm) of the matches ``m`` at x: scan -> body, body -> scan."""
    corners, bary, n_sb, verts, n_bs, targets = m
    W = prob.world(x)
    on_body = np.einsum("ijk,ij->ik", W[corners], bary)
    a = np.einsum("ij,ij->i", on_body - scan, n_sb) * 1000.0
    b = np.einsum("ij,ij->i", W[verts] - targets, n_bs) * 1000.0
    return a, b


def _cost_vector(prob, x, scan, m, weights):
    a, b = _residuals(prob, x, scan, m)
    wa, wb = weights
    return np.concatenate([wa * a, wb * b, prob.pull * (x - prob.prior)])


def _huber_weights(a, b):
    def w(r, count):
        h = np.where(np.abs(r) <= HUBER_MM, 1.0, np.sqrt(HUBER_MM / np.maximum(np.abs(r), 1e-9)))
        return h / np.sqrt(max(count, 1))

    return w(a, len(a)), BODY_TO_SCAN_WEIGHT * w(b, len(b))


def _rigid_icp(prob, x, scan, tree_scan, rounds: int = 8) -> np.ndarray:
    """Align the body at x to the scan by rotation and translation only (Kabsch on matched pairs
    both ways); returns x with the placement updated."""
    from scipy.spatial import cKDTree
    from scipy.spatial.transform import Rotation

    V = prob.local_vertices(x)
    sub = V[:: max(1, len(V) // 3000)]
    x = x.copy()
    for _ in range(rounds):
        R = _rotation(x[:3])
        W = sub @ R.T + x[3:6]
        _, i = cKDTree(W).query(scan)
        _, j = tree_scan.query(W)
        P = np.concatenate([sub[i], sub])  # body points (own frame)
        Q = np.concatenate([scan, scan[j]])  # their matches
        pc, qc = P.mean(0), Q.mean(0)
        U, _, Vt = np.linalg.svd((P - pc).T @ (Q - qc))
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        R = Vt.T @ D @ U.T
        x[:3] = Rotation.from_matrix(R).as_rotvec()
        x[3:6] = qc - R @ pc
    return x


def _mean_distance(prob, x, scan, tree_scan) -> float:
    from scipy.spatial import cKDTree

    W = prob.world(x)
    a = cKDTree(W).query(scan)[0]
    b = tree_scan.query(W[:: max(1, len(W) // 3000)], distance_upper_bound=BODY_TO_SCAN_REACH)[0]
    return float(a.mean() + 0.5 * np.where(np.isfinite(b), b, BODY_TO_SCAN_REACH).mean())


def fit_scan(
    body,
    points: np.ndarray,
    progress: Optional[Progress] = None,
    rounds: int = 30,
    fit_points: int = FIT_POINTS,
    local: bool = True,
    seed: int = 0,
) -> ScanFit:
    """Fit ``body`` (Anny) to a scan's ``points`` (N, 3, metres, +Z up): placement, the joints of
    :data:`POSE_JOINTS`, phenotypes and (``local``) the local changes. ``rounds``: rounds of
    matching and damped Gauss-Newton at most; ``fit_points``: scan points the fit uses."""
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < MIN_POINTS:
        raise BodyError(f"scan: expected at least {MIN_POINTS} points (N, 3), got an array of shape {pts.shape}")
    if not np.isfinite(pts).all():
        raise BodyError("scan: the points are not all finite (NaN or infinity)")
    if not callable(getattr(body, "local_change_parameters", None)):
        raise BodyError(f"scan fit: body {getattr(body, 'name', '?')!r} is not Anny (no local changes)")
    rng = np.random.default_rng(seed)
    scan = pts if len(pts) <= fit_points else pts[rng.choice(len(pts), fit_points, replace=False)]
    tree_scan = cKDTree(scan)
    prob = _Problem(body, local)

    # Start: the reference body standing on the scan's floor at its centre, the best of several turns.
    V0 = prob.local_vertices(prob.x0(0.0, np.zeros(3)))
    centre = np.array([*(0.5 * (scan[:, :2].min(0) + scan[:, :2].max(0))), scan[:, 2].min()])
    own = np.array([*(0.5 * (V0[:, :2].min(0) + V0[:, :2].max(0))), V0[:, 2].min()])
    best = None
    for k, yaw in enumerate(START_YAWS):
        report(progress, 0.05 * k / len(START_YAWS), "placing the body on the scan")
        R = _rotation([0.0, 0.0, yaw])
        x = _rigid_icp(prob, prob.x0(yaw, centre - R @ own), scan, tree_scan)
        d = _mean_distance(prob, x, scan, tree_scan)
        if best is None or d < best[0]:
            best = (d, x)
    x = best[1]

    lam = 1e-3
    done_rounds = 0
    previous = None
    for it in range(rounds):
        done_rounds = it + 1
        report(progress, 0.05 + 0.9 * it / rounds, f"fitting the body to the scan (round {it + 1})")
        m = _matches(prob, x, scan, tree_scan)
        weights = _huber_weights(*_residuals(prob, x, scan, m))
        r = _cost_vector(prob, x, scan, m, weights)
        cost = r @ r
        J = np.empty((r.size, x.size))
        for i in range(x.size):
            h = prob.steps[i] if x[i] + prob.steps[i] <= prob.hi[i] else -prob.steps[i]
            xi = x.copy()
            xi[i] += h
            J[:, i] = (_cost_vector(prob, xi, scan, m, weights) - r) / h
        A, g = J.T @ J, J.T @ r
        for _ in range(6):
            dx = -np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-6), g)
            xn = np.clip(x + dx, prob.lo, prob.hi)
            rn = _cost_vector(prob, xn, scan, m, weights)
            if rn @ rn < cost:
                x = xn
                lam = max(lam / 3.0, 1e-7)
                break
            lam *= 5.0
        if previous is not None and cost > (1.0 - STOP_GAIN) * previous:
            break
        previous = cost

    report(progress, 0.97, "measuring the body and the scan")
    shape, pose = prob.shape(x), prob.pose(x)
    R, t = _rotation(x[:3]), x[3:6].copy()
    W = prob.world(x)
    dist = scan_distance(pts, W, body.faces) * 1000.0
    body_cm = tape_measures(body, None, TAPE_MEASURES, shape=shape)
    scan_cm = scan_girths(body, shape, pose, (pts - t) @ R)
    report(progress, 1.0, "scan fit done")
    return ScanFit(
        shape=shape,
        pose=pose,
        rotation=R,
        translation=t,
        distance_mm={
            "mean": float(dist.mean()),
            "p95": float(np.percentile(dist, 95)),
            "max": float(dist.max()),
            "points": int(len(pts)),
        },
        body_cm=body_cm,
        scan_cm=scan_cm,
        evaluations=prob.evaluations,
        rounds=done_rounds,
    )


# -- measuring the scan ----------------------------------------------------------------------------
SCAN_SLAB = 0.006  # half the height of the band of scan points a girth is taken from (m)
SCAN_BINS = 36  # angular bins around the section's centre (the median radius of each)
SCAN_COVER = 0.75  # the share of bins that must hold points for a girth to be taken


def _scan_loop_girth(points_2d: np.ndarray) -> Optional[float]:
    """Hull perimeter of a noisy ring of points: the median radius of each angular bin (noise
    would push a hull outwards), bins without points bridged by the hull."""
    from .measure import hull_perimeter

    if len(points_2d) < SCAN_BINS:
        return None
    c = 0.5 * (points_2d.min(0) + points_2d.max(0))
    d = points_2d - c
    ang = np.arctan2(d[:, 1], d[:, 0])
    rad = np.linalg.norm(d, axis=1)
    b = ((ang + np.pi) / (2 * np.pi) * SCAN_BINS).astype(int) % SCAN_BINS
    ring = []
    for k in range(SCAN_BINS):
        sel = b == k
        if sel.any():
            a = np.median(ang[sel])
            ring.append(c + np.median(rad[sel]) * np.array([np.cos(a), np.sin(a)]))
    if len(ring) < SCAN_COVER * SCAN_BINS:
        return None
    return 100.0 * hull_perimeter(np.array(ring))


def scan_girths(body, shape, pose, points: np.ndarray) -> Dict[str, Optional[float]]:
    """The scan's own girths and height (cm): its points within :data:`SCAN_SLAB` of each
    level the tape measures use on the fitted body (found on it in the scan's pose), those the
    fitted body's torso and legs are nearest (arms left out; the thigh: the left leg's), as a
    tape around them; the neck, upper arm and wrist in their tilted planes
    (:func:`core.body.tape.limb_plane`), the points within :data:`LIMB_REACH` of the plane's
    centre that the neck (no arm) or the left arm is nearest. ``points`` are in the fitted body's
    frame. None where too few points (:func:`_scan_loop_girth`: 27 of 36 angular bins; the small
    neck and arm loops need a scan of some 50,000 points)."""
    from scipy.spatial import cKDTree

    v = body.vertices(shape, pose)
    lv = levels(body, v)
    owner = cKDTree(v).query(points)[1]
    regions = body.regions
    arm = np.zeros(len(v), dtype=bool)
    for n in ("arm_left", "arm_right", "hands"):
        arm[np.asarray(regions.get(n, ()), dtype=np.int64)] = True
    left_leg = np.zeros(len(v), dtype=bool)
    left_leg[np.asarray(regions.get("leg_left", ()), dtype=np.int64)] = True
    arm_left = np.zeros(len(v), dtype=bool)
    for n in ("arm_left", "hands"):
        arm_left[np.asarray(regions.get(n, ()), dtype=np.int64)] = True
    out: Dict[str, Optional[float]] = {n: None for n in TAPE_MEASURES}
    out["height"] = 100.0 * float(np.ptp(points[:, 2]))
    for name, level in (("chest", "bust"), ("underbust", "underbust"), ("waist", "waist")):
        out[name] = _girth_near(points, ~arm[owner], lv[level])
    for name in ("high_hip", "hip"):
        out[name] = _girth_near(points, ~arm[owner] & (points[:, 2] > lv["crotch"]), lv[name])
    out["thigh"] = _girth_near(points, left_leg[owner], lv["thigh"])
    # The neck and the left arm, each in its tilted plane (tape.limb_plane) on the posed body: the
    # points within SCAN_SLAB of it, near its centre, owned by the part the tape goes around.
    J = dict(zip(body.joint_names, body.joints(shape, pose)))
    lm = {n: body.landmark_position(n, v) for n in body.landmarks}
    for name in LIMB_PLANES:
        point, normal, near = limb_plane(name, lm, J)
        part = ~arm[owner] if name == "neck" else arm_left[owner]
        close = np.linalg.norm(points - near, axis=1) <= LIMB_REACH[name]
        out[name] = _girth_in_plane(points, part & close, point, normal)
    return out


# How far from a limb plane's centre its scan points are taken (m): past a neck's or arm's radius,
# short of the shoulders, the chest or the hand.
LIMB_REACH = {"neck": 0.1, "upper_arm": 0.08, "wrist": 0.05}


def _girth_in_plane(points, mask, point, normal) -> Optional[float]:
    """:func:`_scan_loop_girth` of the ``mask`` points within :data:`SCAN_SLAB` of the plane
    (``point``, ``normal``), in the plane's own coordinates."""
    n, u, w = plane_basis(normal)
    d = points - np.asarray(point, dtype=float)
    sel = mask & (np.abs(d @ n) <= SCAN_SLAB)
    return _scan_loop_girth(np.stack([d[sel] @ u, d[sel] @ w], axis=1))


def _girth_near(points, mask, z) -> Optional[float]:
    sel = mask & (np.abs(points[:, 2] - z) <= SCAN_SLAB)
    return _scan_loop_girth(points[sel, :2])
