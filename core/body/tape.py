"""Tape measures as a tailor takes them (ISO 8559-1), on a standing body instance.

:mod:`core.body.measure` gives the four measures the size charts are fitted by (height and the
chest/waist/hip girths at landmark heights). This module gives the made-to-measure set of
:data:`TAPE_MEASURES`, each taken where ISO 8559-1 names it, on the body as it stands (the
levels are searched on each body, not carried from the reference body). docs/measurements.md
states every definition and compares them with the chart measures.

A girth is a tape around a section of the body: the perimeter of the convex hull of the
section (the tape bridges hollows), in the section's plane. Torso girths are horizontal and
leave the arms out; a limb's girth is the loop of that limb only, in a plane square to the
limb's bone. Lengths are straight between landmarks or along the surface, as named. All
results are in centimetres; the left side is measured (the fitted bodies are symmetric).
"""

from __future__ import annotations

from typing import Dict, Iterable, Mapping, Optional

import numpy as np

from ..errors import BodyError
from .measure import girth_at, hull_perimeter, torso_edges

TAPE_MEASURES = (
    "height",
    "neck",
    "shoulder_width",
    "chest",
    "underbust",
    "waist",
    "high_hip",
    "hip",
    "upper_arm",
    "wrist",
    "arm_length",
    "back_waist_length",
    "inseam",
    "thigh",
)

# The lengths among them (the rest are girths): a fit holds these to 1.5 cm, girths to 1 cm.
LENGTHS = ("height", "shoulder_width", "arm_length", "back_waist_length", "inseam")

# Other names a table may use.
ALIASES = {
    "bust": "chest",
    "shoulder": "shoulder_width",
    "upperarm": "upper_arm",
    "bicep": "upper_arm",
    "highhip": "high_hip",
    "back_waist": "back_waist_length",
    "inside_leg": "inseam",
}

# Joints and landmarks the measures need (Anny's rig names; a model without them cannot be taped).
_JOINTS = ("upperarm01.L", "lowerarm01.L", "wrist.L", "upperleg01.L")
_LANDMARKS = (
    "neck_front",
    "neck_back",
    "neck_left",
    "neck_right",
    "shoulder_left",
    "shoulder_right",
    "bust_left",
    "bust_right",
    "crotch",
    "elbow_left",
    "wrist_left",
)

# Thigh girth: this far below the crotch (the top of the thigh, under the gluteal fold), metres.
THIGH_BELOW_CROTCH = 0.03


def canonical(name: str) -> str:
    """A measure's name in :data:`TAPE_MEASURES` (``bust`` -> ``chest``); BodyError if unknown."""
    key = str(name).strip().lower().replace("-", "_").replace(" ", "_")
    key = ALIASES.get(key, key)
    if key not in TAPE_MEASURES:
        raise BodyError(f"unknown measurement {name!r}; allowed: {', '.join(TAPE_MEASURES)} (cm)")
    return key


# -- sections ---------------------------------------------------------------------------------
def plane_basis(normal):
    """``(n, u, w)``: the unit ``normal`` (3,) and two unit vectors (3,) spanning its plane, so that
    ``(u, w, n)`` is right-handed; ``u`` is taken across x (across y where the normal is near x)."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    return n, u, np.cross(n, u)


def section_loops(vertices: np.ndarray, faces: np.ndarray, point, normal) -> list:
    """The closed curves where the plane (``point``, ``normal``) cuts the triangles ``faces``.

    Returns a list of (k, 3) arrays, the crossing points of each connected curve (unordered).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = np.asarray(normal, dtype=float)
    d = (vertices - np.asarray(point, dtype=float)) @ n
    side = d[faces] > 0.0
    cut = faces[side.any(axis=1) & ~side.all(axis=1)]
    if len(cut) == 0:
        return []
    e = np.concatenate([cut[:, [0, 1]], cut[:, [1, 2]], cut[:, [2, 0]]])
    crosses = (d[e[:, 0]] > 0) != (d[e[:, 1]] > 0)
    key = np.sort(e, axis=1)
    ids, inverse = np.unique(key[:, 0] * len(vertices) + key[:, 1], return_inverse=True)
    inverse = inverse.ravel()
    # Each cut triangle joins the two of its edges the plane crosses.
    F = len(cut)
    edge_of = inverse.reshape(3, F).T
    hit = crosses.reshape(3, F).T
    two = hit.sum(axis=1) == 2
    pairs = edge_of[two][hit[two]].reshape(-1, 2)
    m = len(ids)
    if len(pairs) == 0:
        return []
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    count, label = connected_components(graph, directed=False)
    a, b = ids // len(vertices), ids % len(vertices)
    with np.errstate(divide="ignore", invalid="ignore"):  # edges the plane does not cross: unused
        t = (d[a] / (d[a] - d[b]))[:, None]
    pts = vertices[a] + t * (vertices[b] - vertices[a])
    used = np.zeros(m, dtype=bool)
    used[pairs.ravel()] = True
    return [pts[(label == c) & used] for c in range(count) if np.count_nonzero((label == c) & used) >= 3]


# The girths taken in a plane that is not horizontal: the neck's and the left arm's.
LIMB_PLANES = ("neck", "upper_arm", "wrist")


def limb_plane(name: str, lm: Mapping[str, np.ndarray], J: Mapping[str, np.ndarray]):
    """(point, normal, near) of the plane a girth of :data:`LIMB_PLANES` is taken in, from the
    landmarks ``lm`` and joints ``J`` of the instance: the neck's through its four base landmarks
    (their least-squares plane), the upper arm's square to the bone half way from shoulder to
    elbow, the wrist's square to the forearm through the wrist landmark (the loop nearest the
    wrist joint)."""
    if name == "neck":
        p = np.array([lm[k] for k in ("neck_front", "neck_back", "neck_left", "neck_right")])
        centre = p.mean(axis=0)
        normal = np.linalg.svd(p - centre)[2][2]
        return centre, (normal if normal[2] > 0 else -normal), centre
    if name == "upper_arm":
        a, b = J["upperarm01.L"], J["lowerarm01.L"]
        return 0.5 * (a + b), b - a, 0.5 * (a + b)
    if name == "wrist":
        a, b = J["lowerarm01.L"], J["wrist.L"]
        return lm["wrist_left"], b - a, b
    raise ValueError(f"limb_plane: {name!r} is not one of {LIMB_PLANES}")


def loop_girth(vertices: np.ndarray, faces: np.ndarray, point, normal, near=None) -> float:
    """Tape girth (metres) of the section loop of ``faces`` by the plane (``point``, ``normal``)
    nearest ``near`` (default ``point``): the perimeter of its convex hull in the plane."""
    loops = section_loops(vertices, faces, point, normal)
    if not loops:
        raise BodyError("tape: the plane misses the body part it should cut")
    c = np.asarray(point if near is None else near, dtype=float)
    loop = min(loops, key=lambda p: float(np.linalg.norm(p - c, axis=1).min() + np.linalg.norm(p.mean(0) - c)))
    _, u, w = plane_basis(normal)
    return hull_perimeter(np.stack([loop @ u, loop @ w], axis=1))


# -- the body's parts -------------------------------------------------------------------------
class _Parts:
    """Per model: the faces of each part a tape goes around (the topology is fixed)."""

    def __init__(self, body):
        regions = body.regions
        V = body.n_vertices
        F = body.faces

        def faces_of(*names, keep=None):
            mask = np.zeros(V, dtype=bool)
            for n in names:
                mask[np.asarray(regions.get(n, ()), dtype=np.int64)] = True
            sel = mask[F].all(axis=1) if keep is None else keep(mask[F])
            return F[sel]

        arms = np.zeros(V, dtype=bool)
        for n in ("arm_left", "arm_right", "hands"):
            arms[np.asarray(regions.get(n, ()), dtype=np.int64)] = True
        self.no_arms = F[~arms[F].any(axis=1)]  # torso, head, legs
        self.arm_left = faces_of("arm_left", "hands", keep=lambda m: m.any(axis=1))
        self.torso_edges = torso_edges(body)


def _parts(body) -> _Parts:
    cached = getattr(body, "_ease_tape_parts", None)
    if cached is None:
        cached = _Parts(body)
        try:
            body._ease_tape_parts = cached
        except AttributeError:  # pragma: no cover - frozen model objects
            pass
    return cached


def _check_model(body):
    have = set(getattr(body, "landmarks", {}) or {})
    missing = [n for n in _LANDMARKS if n not in have] + [j for j in _JOINTS if j not in body.joint_names]
    if missing:
        raise BodyError(
            f"tape measures: body {getattr(body, 'name', '?')!r} lacks {', '.join(missing)} "
            "(the tape measures need Anny's rig and landmarks)"
        )


def _torso_girth(v, parts, z) -> float:
    return girth_at(v, None, z, parts.torso_edges)


def natural_waist_height(v, parts, lo: float, hi: float) -> float:
    """Height (m) of the narrowest horizontal torso section between ``lo`` and ``hi``: a grid
    of 1 cm, then 2 mm around its smallest."""
    band = _band(v, parts.torso_edges, lo, hi)
    zs = np.arange(lo + 0.01, hi - 0.005, 0.01)
    g = np.array([girth_at(v, None, z, band) for z in zs])
    z0 = zs[int(np.argmin(g))]
    fine = np.arange(z0 - 0.01, z0 + 0.0101, 0.002)
    return float(fine[int(np.argmin([girth_at(v, None, z, band) for z in fine]))])


def buttock_height(v, body, parts, crotch_z: float, waist_z: float) -> float:
    """Height (m) of the greatest buttock prominence: the most posterior (+y) point of the body,
    arms left out, between the crotch and the waist."""
    ids = np.unique(parts.no_arms)
    z = v[ids, 2]
    sel = ids[(z > crotch_z) & (z < waist_z)]
    return float(v[sel[np.argmax(v[sel, 1])], 2])


def underbust_height(v, parts, bust_x: float, bust_z: float, waist_z: float) -> float:
    """Height (m) of the fold under the breast, on the front profile through the bust points (the
    most anterior point within 2 cm of their |x|, every 5 mm from the bust point down through the
    upper 60 % of the way to the waist): the profile's inner corner, i.e. the heights weighted by
    the square of their depth behind the chord from the bust point to the band's foot, plus
    (3 mm)^2 each. A breast's fold (1-4 cm deep) decides; a flat chest (no corner) gives the
    band's middle, and the level moves smoothly with the shape (a fit's derivatives exist)."""
    foot = bust_z - 0.6 * (bust_z - waist_z)
    zs = np.linspace(bust_z, foot, max(3, int(np.ceil((bust_z - foot) / 0.005)) + 1))
    e = _band(v, parts.torso_edges, foot - 0.01, bust_z + 0.01)
    front = []
    for z in zs:
        p = _slice_points(v, e, z)
        near = np.abs(np.abs(p[:, 0]) - bust_x) < 0.02
        front.append(p[near, 1].min() if near.any() else np.nan)
    front = np.array(front)
    ok = np.isfinite(front)
    zs, front = zs[ok], front[ok]
    if len(zs) < 3:
        return float(0.5 * (bust_z + foot))
    chord = front[0] + (front[-1] - front[0]) * (zs - zs[0]) / (zs[-1] - zs[0])
    w = np.maximum(front - chord, 0.0) ** 2 + 0.003**2
    return float(np.sum(w * zs) / np.sum(w))


def _slice_points(v, edges, z):
    """Points (n, 3) where the ``edges`` cross the plane z."""
    d = v[:, 2] - z
    da, db = d[edges[:, 0]], d[edges[:, 1]]
    c = (da * db < 0) | ((da == 0) & (db != 0))  # an end on the plane counts once, as measure's
    t = (da[c] / (da[c] - db[c]))[:, None]
    return v[edges[c, 0]] + t * (v[edges[c, 1]] - v[edges[c, 0]])


def _band(v, edges, lo, hi):
    """The edges reaching into heights lo .. hi (a slice search scans only these)."""
    za, zb = v[edges[:, 0], 2], v[edges[:, 1], 2]
    return edges[(np.maximum(za, zb) >= lo) & (np.minimum(za, zb) <= hi)]


def back_profile(v, edges, top_z: float, bottom_z: float) -> np.ndarray:
    """The back's midline from ``bottom_z`` up to ``top_z``: (k, 2) points (y, z) (m), in horizontal
    slices 5 mm apart the most posterior point within 2 cm of the midline (where a tape laid down
    the spine lies)."""
    band = _band(v, edges, bottom_z, top_z)
    prof = []
    for z in np.linspace(bottom_z, top_z, max(2, int(np.ceil((top_z - bottom_z) / 0.005)) + 1)):
        p = _slice_points(v, band, z)
        p = p[np.abs(p[:, 0]) < 0.02]
        if len(p):
            prof.append((p[:, 1].max(), z))
    if len(prof) < 2:
        raise BodyError("tape: no back profile between the neck and the waist")
    return np.array(prof)


def back_profile_length(v, edges, top_z: float, bottom_z: float) -> float:
    """Length (m) down the back's midline from ``top_z`` to ``bottom_z``: the :func:`back_profile`
    points joined (a tape laid down the spine)."""
    return float(np.linalg.norm(np.diff(back_profile(v, edges, top_z, bottom_z), axis=0), axis=1).sum())


# -- the measures -----------------------------------------------------------------------------
def waist_band(crotch_z: float, bust_z: float):
    """(lo, hi), the heights (m) the natural waist is searched between: from a point 35 % of the way
    from the crotch to the bust (below it the section widens into the hips) to 3 cm under the bust."""
    return crotch_z + 0.35 * (bust_z - crotch_z), bust_z - 0.03


def levels(body, v: np.ndarray) -> Dict[str, float]:
    """The heights (m) the torso girths are taken at, searched on this body: bust, underbust,
    waist, high hip, hip, thigh."""
    parts = _parts(body)
    lm = {n: body.landmark_position(n, v) for n in _LANDMARKS}
    bust_z = 0.5 * (lm["bust_left"][2] + lm["bust_right"][2])
    bust_x = 0.5 * (abs(lm["bust_left"][0]) + abs(lm["bust_right"][0]))
    crotch_z = float(lm["crotch"][2])
    waist_z = natural_waist_height(v, parts, *waist_band(crotch_z, bust_z))
    hip_z = buttock_height(v, body, parts, crotch_z, waist_z)
    return {
        "bust": float(bust_z),
        "underbust": underbust_height(v, parts, bust_x, bust_z, waist_z),
        "waist": waist_z,
        "high_hip": 0.5 * (waist_z + hip_z),
        "hip": hip_z,
        "thigh": crotch_z - THIGH_BELOW_CROTCH,
        "crotch": crotch_z,
    }


def tape_measures(
    body, vertices: Optional[np.ndarray] = None, which: Iterable[str] = TAPE_MEASURES, shape=None, joints=None
) -> Dict[str, float]:
    """The tape measures (cm) of a standing instance of ``body`` (default its reference shape).

    Parameters
    ----------
    body : an Anny-rigged BodyModel (landmarks and joints of :data:`_LANDMARKS`, :data:`_JOINTS`).
    vertices : (V, 3) the instance (A-pose); default ``body.vertices(shape)``.
    which : names of :data:`TAPE_MEASURES` (aliases accepted).
    shape : the instance's shape, for its joints (default the reference shape).
    joints : the instance's joints where the caller has them with ``vertices`` (else from ``shape``).
    """
    _check_model(body)
    names = [canonical(n) for n in which]
    if vertices is None:
        v, joints = (
            body.vertices_and_joints(shape)
            if hasattr(body, "vertices_and_joints")
            else (body.vertices(shape), body.joints(shape))
        )
    else:
        v = np.asarray(vertices, dtype=float)
        joints = body.joints(shape) if joints is None else np.asarray(joints, dtype=float)
    if v.shape != (body.n_vertices, 3):
        raise BodyError(f"tape measures: vertices have shape {v.shape}, expected ({body.n_vertices}, 3)")
    parts = _parts(body)
    J = dict(zip(body.joint_names, joints))
    lm = {n: body.landmark_position(n, v) for n in _LANDMARKS}
    need_levels = {"chest", "underbust", "waist", "high_hip", "hip", "thigh", "back_waist_length"} & set(names)
    lv = levels(body, v) if need_levels else {}
    out = {}
    for name in names:
        if name == "height":
            m = float(v[:, 2].max() - v[:, 2].min())
        elif name in ("chest", "underbust", "waist", "high_hip", "hip"):
            m = _torso_girth(v, parts, lv["bust" if name == "chest" else name])
        elif name in LIMB_PLANES:
            point, normal, near = limb_plane(name, lm, J)
            m = loop_girth(v, parts.no_arms if name == "neck" else parts.arm_left, point, normal, near=near)
        elif name == "shoulder_width":
            m = float(np.linalg.norm(lm["shoulder_left"] - lm["shoulder_right"]))
        elif name == "arm_length":
            m = float(
                np.linalg.norm(lm["elbow_left"] - lm["shoulder_left"])
                + np.linalg.norm(lm["wrist_left"] - lm["elbow_left"])
            )
        elif name == "back_waist_length":
            m = back_profile_length(v, parts.torso_edges, float(lm["neck_back"][2]), lv["waist"])
        elif name == "inseam":
            m = float(lm["crotch"][2] - v[:, 2].min())
        elif name == "thigh":
            hip_joint = J["upperleg01.L"]
            m = loop_girth(v, parts.no_arms, (hip_joint[0], hip_joint[1], lv["thigh"]), (0.0, 0.0, 1.0))
        out[name] = 100.0 * float(m)
    return out
