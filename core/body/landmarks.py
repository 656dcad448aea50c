"""Landmarks, regions and the left/right symmetry of a body template.

Landmarks are :class:`SurfacePoint` s (triangle + barycentric weights), found once
on the reference body (default shape, A-pose) by deterministic geometric rules
anchored on the rig's joints: rays cast from a joint in an anatomical direction,
extremes of horizontal slices, apices of the gaps under the arms and between
the legs. Being on the template they then hold for every shape and pose.

Rules (frame: metres, +Z up, the body faces -Y, +X = the body's left):

- ``neck_*``: neck base (the ``neck01`` joint height, the root of the neck):
  rays from the neck axis to the front (-Y), back (+Y) and sides (+/-X);
- ``shoulder_*``: acromion, the surface straight above the shoulder joint;
- ``armpit_*``: apex of the gap between arm and torso, in the frontal plane of
  the shoulder joint (highest first hit of upward rays from outside the body);
- ``bust_*``: most anterior chest point on each side between armpit and waist;
- ``shoulder_blade_*``: most posterior point of the upper back on each side, within
  10 cm below to 6 cm above the armpits and inside 60 % of the shoulder's half width
  (the prominence of the scapula a back pattern must cover);
- ``seat_*``: most posterior point of each buttock between crotch and waist
  (the seat prominence);
- ``gluteal_cleft``: the midline of the back at the seat level (ray from behind at x = 0);
- ``waist_*``: natural waist, the narrowest horizontal torso girth between the
  crotch and the armpits, then front/back/sides of that slice;
- ``hip_*``: the sides of the widest horizontal girth between crotch and waist;
- ``crotch``: the lowest midline point of the trunk (upward rays at x = 0);
- ``navel``: the deepest dent of the front midline profile between crotch and waist;
- ``elbow_*``: the back of the elbow (olecranon), ray from the elbow joint
  backwards, square to the forearm;
- ``wrist_*``: the back/little-finger side of the wrist (ulnar styloid), ray from
  the wrist joint likewise;
- ``knee_*``: the front of the knee (patella), ray from the knee joint forwards;
- ``ankle_*``: the outer ankle bone (lateral malleolus), ray from the ankle joint
  outwards.
"""

from __future__ import annotations

from typing import Dict

import numpy as np

from ..errors import BodyError
from .model import SurfacePoint

# -------------------------------------------------------------------------------------------
# Geometry helpers


def symmetry_map(vertices: np.ndarray, tol: float = 1e-4) -> np.ndarray:
    """Left<->right vertex map (V,) of a mesh symmetric about the plane x = 0.

    Each vertex maps to the vertex nearest its mirror image; the map must be an
    involution with every mirror match closer than ``tol`` metres.
    """
    from scipy.spatial import cKDTree

    v = np.asarray(vertices, dtype=float)
    dist, idx = cKDTree(v).query(v * np.array([-1.0, 1.0, 1.0]))
    if dist.max() > tol or np.any(idx[idx] != np.arange(v.shape[0])):
        raise BodyError(
            f"template is not left/right symmetric (worst mirror mismatch "
            f"{dist.max() * 1000:.2f} mm); cannot build a symmetry map"
        )
    return idx.astype(np.int64)


class _RayMesh:
    """Per-triangle data of one mesh, kept across the many rays cast at it."""

    def __init__(self, vertices: np.ndarray, faces: np.ndarray):
        self.vertices, self.faces = vertices, faces
        self.a = vertices[faces[:, 0]]
        self.e1 = vertices[faces[:, 1]] - self.a
        self.e2 = vertices[faces[:, 2]] - self.a
        self.centre = self.a + (self.e1 + self.e2) / 3.0
        corners = np.stack([self.a, self.a + self.e1, self.a + self.e2], axis=1)
        self.radius = np.linalg.norm(corners - self.centre[:, None], axis=2).max(axis=1) + 1e-9
        eps = 1e-9
        self.lo = corners.min(axis=1) - eps
        self.hi = corners.max(axis=1) + eps


_RAY_MESH = {}


def _ray_mesh(vertices, faces) -> _RayMesh:
    key = (id(vertices), id(faces))
    rm = _RAY_MESH.get(key)
    if rm is None or rm.vertices is not vertices or rm.faces is not faces:
        _RAY_MESH.clear()
        rm = _RAY_MESH[key] = _RayMesh(vertices, faces)
    return rm


def mirror_surface_point(point: SurfacePoint, faces: np.ndarray, symmetry: np.ndarray) -> SurfacePoint:
    """The mirror image of a surface point through the left/right ``symmetry`` map (V,).

    The mirrored triangle is the face on the mirrored vertices (its winding is
    reversed by the mirror); the barycentric weights follow their vertices.
    """
    tri = faces[point.triangle]
    image = symmetry[tri]
    target = set(image.tolist())
    cand = np.nonzero(np.isin(faces, image).all(axis=1))[0]
    for c in cand:
        if set(faces[c].tolist()) == target:
            bary = [point.bary[int(np.nonzero(image == vid)[0][0])] for vid in faces[c]]
            return SurfacePoint(int(c), tuple(float(b) for b in bary))
    raise BodyError(f"triangle {point.triangle} has no mirror triangle; the symmetry map does not match the faces")


def ray_cast(vertices: np.ndarray, faces: np.ndarray, origin, direction, all_hits: bool = False):
    """Intersections of a ray with a triangle mesh (Moller-Trumbore, vectorised).

    Returns
    -------
    If ``all_hits``: (t (k,), triangle (k,), bary (k, 3)) sorted by distance t > 0.
    Else the first hit as (t, triangle, bary) or None.
    """
    rm = _ray_mesh(vertices, faces)
    o = np.asarray(origin, dtype=float)
    dvec = np.asarray(direction, dtype=float)
    dvec = dvec / np.linalg.norm(dvec)
    axis = np.nonzero(np.abs(dvec) > 1.0 - 1e-12)[0]
    if axis.size == 1:
        # Axis-aligned ray: only triangles whose bounding box spans it across can be hit.
        a0, a1 = [k for k in range(3) if k != axis[0]]
        ok = (rm.lo[:, a0] <= o[a0]) & (rm.hi[:, a0] >= o[a0]) & (rm.lo[:, a1] <= o[a1]) & (rm.hi[:, a1] >= o[a1])
        cand = np.nonzero(ok)[0]
    else:
        # Only triangles whose bounding sphere meets the ray can be hit.
        rel = rm.centre - o
        along = rel @ dvec
        perp = np.linalg.norm(rel - along[:, None] * dvec, axis=1)
        cand = np.nonzero((perp <= rm.radius) & (along >= -rm.radius))[0]
    a, e1, e2 = rm.a[cand], rm.e1[cand], rm.e2[cand]
    p = np.cross(dvec, e2)
    det = np.einsum("ij,ij->i", e1, p)
    ok = np.abs(det) > 1e-14
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o - a
    u = np.einsum("ij,ij->i", s, p) * inv
    q = np.cross(s, e1)
    w = (q @ dvec) * inv
    t = np.einsum("ij,ij->i", e2, q) * inv
    hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 1e-9)
    sub = np.nonzero(hit)[0]
    sub = sub[np.argsort(t[sub], kind="stable")]
    ids = cand[sub]
    bary = np.stack([1 - u[sub] - w[sub], u[sub], w[sub]], axis=1)
    if all_hits:
        return t[sub], ids, bary
    if ids.size == 0:
        return None
    return float(t[sub[0]]), int(ids[0]), bary[0]


def _surface_point(tri: int, bary) -> SurfacePoint:
    b = np.clip(np.asarray(bary, dtype=float), 0.0, 1.0)
    b = b / b.sum()
    return SurfacePoint(int(tri), tuple(float(x) for x in b))


def vertex_point(faces: np.ndarray, vid: int) -> SurfacePoint:
    """A SurfacePoint sitting exactly on vertex ``vid``."""
    tri = int(np.nonzero((faces == vid).any(axis=1))[0][0])
    bary = [1.0 if faces[tri, k] == vid else 0.0 for k in range(3)]
    return SurfacePoint(tri, tuple(bary))


def ray_point(vertices, faces, origin, direction, name: str) -> SurfacePoint:
    """The last exit of a ray from inside the body (the outer surface in that direction)."""
    t, tri, bary = ray_cast(vertices, faces, origin, direction, all_hits=True)
    if t.size == 0:
        raise BodyError(
            f"landmark {name}: ray from {np.round(origin, 3)} along {np.round(direction, 3)} misses the body"
        )
    # First exit: rays start inside a limb, so the first surface crossed is the limb's skin.
    return _surface_point(tri[0], bary[0])


def _upward_apex(vertices, faces, xs, ys, z0, name):
    """Highest first hit of upward rays started outside the body at (x, y, z0)."""
    best = None
    for x, y in zip(xs, ys):
        t, tri, bary = ray_cast(vertices, faces, (x, y, z0), (0.0, 0.0, 1.0), all_hits=True)
        if t.size == 0:
            continue
        # An even number of crossings ahead means the start lies outside the body.
        if t.size % 2 == 1:
            continue
        z = z0 + t[0]
        if best is None or z > best[0]:
            best = (z, tri[0], bary[0])
    if best is None:
        raise BodyError(f"landmark {name}: no gap found below it")
    return best


def _lowest_apex(vertices, faces, xs, ys, z0, name):
    """Lowest first hit of upward rays (outside starts) - the bottom of a profile."""
    best = None
    for x, y in zip(xs, ys):
        t, tri, bary = ray_cast(vertices, faces, (x, y, z0), (0.0, 0.0, 1.0), all_hits=True)
        if t.size == 0 or t.size % 2 == 1:
            continue
        z = z0 + t[0]
        if best is None or z < best[0]:
            best = (z, tri[0], bary[0])
    if best is None:
        raise BodyError(f"landmark {name}: no surface found")
    return best


def _hull_perimeter(points2d: np.ndarray) -> float:
    from scipy.spatial import ConvexHull

    if points2d.shape[0] < 3:
        return 0.0
    h = ConvexHull(points2d)
    ring = points2d[h.vertices]
    return float(np.linalg.norm(ring - np.roll(ring, 1, axis=0), axis=1).sum())


def _band_girths(vertices, mask, zs, half_band=0.004):
    """Convex-hull (tape measure) girth of the masked vertices in thin horizontal bands."""
    v = vertices[mask]
    out = []
    for z in zs:
        sel = np.abs(v[:, 2] - z) < half_band
        out.append(_hull_perimeter(v[sel, :2]) if sel.sum() >= 3 else np.nan)
    return np.array(out)


def _midline_centre_y(vertices, faces, z):
    """Mid-depth (y) of the body on the midline x = 0 at height ``z``."""
    front = ray_cast(vertices, faces, (0.0, -2.0, z), (0.0, 1.0, 0.0))
    back = ray_cast(vertices, faces, (0.0, 2.0, z), (0.0, -1.0, 0.0))
    if front is None or back is None:
        raise BodyError(f"no body on the midline at height {z:.3f} m")
    return 0.5 * ((-2.0 + front[0]) + (2.0 - back[0]))


def _orthogonal(direction, axis):
    """``direction`` with its component along ``axis`` removed, normalised."""
    axis = axis / np.linalg.norm(axis)
    d = np.asarray(direction, dtype=float) - np.dot(direction, axis) * axis
    return d / np.linalg.norm(d)


# -------------------------------------------------------------------------------------------
# Anny

# Rig bones -> body parts (each vertex goes to the part of its most-weighted bone).
_PART_OF_BONE_PREFIX = (
    ("head", ("neck", "head", "eye")),
    ("hands", ("wrist", "finger", "metacarpal")),
    ("feet", ("foot", "toe")),
    ("arm", ("shoulder01", "upperarm", "lowerarm")),
    ("leg", ("upperleg", "lowerleg")),
    ("torso", ("root", "pelvis", "spine", "clavicle", "breast")),
)


def _bone_part(label: str) -> str:
    for part, prefixes in _PART_OF_BONE_PREFIX:
        if label.startswith(prefixes):
            if part in ("arm", "leg"):
                return f"{part}_{'left' if label.endswith('.L') else 'right'}"
            return part
    raise BodyError(f"bone {label!r} has no body part")


def anny_regions(body, ref_vertices: np.ndarray) -> Dict[str, np.ndarray]:
    """Vertex regions of Anny from skinning weights, the head cut at the neck base.

    ``head``, ``hands``, ``feet`` are never covered by a garment; ``torso``,
    ``arm_left/right``, ``leg_left/right`` serve grain directions.
    """
    data = body.data
    labels = data.bone_labels
    dominant = np.argmax(data.weights, axis=1)
    part = np.array([_bone_part(labels[b]) for b in range(len(labels))])[dominant]
    joints = body.joints(None, "A")
    neck_base = joints[labels.index("neck01")]
    # The neck bones also weigh on the top of the shoulders/collar; the head region (never
    # covered) stops at the neck base, so neck skin below it belongs to the torso.
    low_neck = (part == "head") & (ref_vertices[:, 2] < neck_base[2])
    part[low_neck] = "torso"
    names = ("head", "hands", "feet", "torso", "arm_left", "arm_right", "leg_left", "leg_right")
    return {n: np.nonzero(part == n)[0].astype(np.int64) for n in names}


def anny_landmarks(body, ref_vertices: np.ndarray, ref_joints: np.ndarray) -> Dict[str, SurfacePoint]:
    """All :data:`REQUIRED_LANDMARKS` of Anny on the reference body (see module rules)."""
    v, f = ref_vertices, body.faces
    J = {n: ref_joints[i] for i, n in enumerate(body.joint_names)}
    lm: Dict[str, SurfacePoint] = {}
    X, Y, Z = np.eye(3)

    # Neck base, on the neck axis at the neck01 joint.
    neck = J["neck01"]
    lm["neck_front"] = ray_point(v, f, neck, -Y, "neck_front")
    lm["neck_back"] = ray_point(v, f, neck, Y, "neck_back")
    lm["neck_left"] = ray_point(v, f, neck, X, "neck_left")
    lm["neck_right"] = ray_point(v, f, neck, -X, "neck_right")

    torso = np.zeros(v.shape[0], dtype=bool)
    torso[body.regions["torso"]] = True

    for side, sx, s in (("left", 1.0, ".L"), ("right", -1.0, ".R")):
        sh = J["upperarm01" + s]
        lm[f"shoulder_{side}"] = ray_point(v, f, sh, Z, f"shoulder_{side}")
        # Armpit: scan the frontal plane of the shoulder joint inwards of it.
        xs = sx * np.linspace(abs(sh[0]) - 0.12, abs(sh[0]) + 0.04, 81)
        z, tri, bary = _upward_apex(v, f, xs, np.full(xs.shape, sh[1]), sh[2] - 0.35, f"armpit_{side}")
        lm[f"armpit_{side}"] = _surface_point(tri, bary)

        elbow, wrist = J["lowerarm01" + s], J["wrist" + s]
        forearm = wrist - elbow
        lm[f"elbow_{side}"] = ray_point(v, f, elbow, _orthogonal(Y, forearm), f"elbow_{side}")
        hand_dir = J["finger3-1" + s] - wrist
        lm[f"wrist_{side}"] = ray_point(v, f, wrist, _orthogonal(Y, hand_dir), f"wrist_{side}")
        knee = J["lowerleg01" + s]
        lm[f"knee_{side}"] = ray_point(v, f, knee, -Y, f"knee_{side}")
        ankle = J["foot" + s]
        lm[f"ankle_{side}"] = ray_point(v, f, ankle, sx * X, f"ankle_{side}")

    armpit_z = 0.5 * (lm["armpit_left"].position(v, f)[2] + lm["armpit_right"].position(v, f)[2])

    # Crotch: lowest point of the trunk on the midline, between the hip joints' depths.
    hips = 0.5 * (J["upperleg01.L"] + J["upperleg01.R"])
    ys = np.linspace(hips[1] - 0.08, hips[1] + 0.08, 81)
    z, tri, bary = _lowest_apex(v, f, np.zeros_like(ys), ys, J["lowerleg01.L"][2], "crotch")
    # Rays in front of / behind the body hit nothing (or the chin, higher up), so the
    # lowest first hit is the underside of the trunk between the legs.
    lm["crotch"] = _surface_point(tri, bary)
    crotch_z = z

    # Waist: narrowest torso girth between crotch and armpits (middle part of that span).
    zs = np.linspace(crotch_z + 0.35 * (armpit_z - crotch_z), crotch_z + 0.8 * (armpit_z - crotch_z), 60)
    g = _band_girths(v, torso, zs)
    zw = float(zs[np.nanargmin(g)])
    cy = _midline_centre_y(v, f, zw)
    centre = np.array([0.0, cy, zw])
    lm["waist_front"] = ray_point(v, f, centre, -Y, "waist_front")
    lm["waist_back"] = ray_point(v, f, centre, Y, "waist_back")
    lm["waist_left"] = ray_point(v, f, centre, X, "waist_left")
    lm["waist_right"] = ray_point(v, f, centre, -X, "waist_right")

    # Hips: level of the greatest buttock prominence (ISO 8559 hip girth) between crotch
    # and waist, then the sides of the body at that level.
    trunk = torso.copy()
    trunk[body.regions["leg_left"]] = True
    trunk[body.regions["leg_right"]] = True
    sel = (
        trunk
        & (np.abs(v[:, 0]) > 0.02)
        & (np.abs(v[:, 0]) < 0.5 * abs(lm["waist_left"].position(v, f)[0] - lm["waist_right"].position(v, f)[0]))
    )
    sel &= (v[:, 2] > crotch_z) & (v[:, 2] < zw)
    ids = np.nonzero(sel)[0]
    zh = float(v[ids[np.argmax(v[ids, 1])], 2])
    cy = _midline_centre_y(v, f, zh)
    lm["hip_left"] = ray_point(v, f, (0.0, cy, zh), X, "hip_left")
    lm["hip_right"] = ray_point(v, f, (0.0, cy, zh), -X, "hip_right")
    # Seat: each buttock's most posterior vertex; the cleft between them on the midline.
    for side, sx in (("left", 1.0), ("right", -1.0)):
        side_ids = ids[sx * v[ids, 0] > 0]
        lm[f"seat_{side}"] = vertex_point(f, int(side_ids[np.argmax(v[side_ids, 1])]))
    lm["gluteal_cleft"] = ray_point(v, f, (0.0, 2.0, zh), -Y, "gluteal_cleft")

    # Bust points: most anterior torso vertex on each side between waist and armpits.
    for side, sx in (("left", 1.0), ("right", -1.0)):
        sel = torso & (v[:, 2] > zw + 0.05) & (v[:, 2] < armpit_z) & (sx * v[:, 0] > 0.03)
        ids = np.nonzero(sel)[0]
        lm[f"bust_{side}"] = vertex_point(f, int(ids[np.argmin(v[ids, 1])]))
        # Shoulder blade: most posterior upper-back vertex, inside the shoulder (off the arm).
        half = 0.6 * abs(J["upperarm01" + (".L" if sx > 0 else ".R")][0])
        sel = (
            torso
            & (v[:, 2] > armpit_z - 0.10)
            & (v[:, 2] < armpit_z + 0.06)
            & (sx * v[:, 0] > 0.03)
            & (sx * v[:, 0] < half)
        )
        ids = np.nonzero(sel)[0]
        lm[f"shoulder_blade_{side}"] = vertex_point(f, int(ids[np.argmax(v[ids, 1])]))

    # Navel: deepest dent of the front midline profile between crotch and waist.
    zs = np.linspace(crotch_z + 0.08, zw + 0.03, 90)
    prof = []
    for z in zs:
        hit = ray_cast(v, f, (0.0, -1.0, z), Y)
        prof.append((hit[0] - 1.0) if hit is not None else np.nan)
    prof = np.array(prof)  # front surface y(z)
    k = 8  # ~2.5 cm each side: the navel is a dent on that scale
    depth = np.full(zs.shape, -np.inf)
    for i in range(k, zs.size - k):
        depth[i] = prof[i] - 0.5 * (prof[i - k] + prof[i + k])
    i = int(np.argmax(depth))
    hit = ray_cast(v, f, (0.0, -1.0, zs[i]), Y)
    lm["navel"] = _surface_point(hit[1], hit[2])
    return lm
