"""Fabric grain on the cut: a unit warp direction per triangle.

The warp (lengthwise grain) follows the long axis of the body part a panel
covers (SPEC "Frames and grain"): the torso axis (pelvis -> neck), the arm
(wrist -> shoulder) or the leg (ankle -> hip) of the panel's side. All axes
are oriented to point *up* the body part (towards the neck / the shoulder /
the hip), so the grain of every panel points to the garment's top. Per
triangle the axis is projected into the triangle plane and normalised.

Without a skeleton, regions or landmarks (an OBJ template) the torso's axis is
found from the body's surface: where its principal axis lies nearer the
horizontal than the vertical (a quadruped: long along its spine) the torso
axis is the horizontal principal direction (the spine in plan view; the head
and legs tilt the full 3D axis), pointing to the head end, so the warp runs
along the barrel, not around it. A standing body keeps the vertical.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

_JOINTS = {
    # (lower, upper) candidates; "{s}" is the side tag
    "torso": (("pelvis", "root", "spine05", "hips", "hip"), ("neck01", "neck", "neck_01", "spine3")),
    "arm": (
        ("wrist.{S}", "{side}_wrist", "{s}_wrist", "wrist_{s}", "lowerarm02.{S}"),
        ("upperarm01.{S}", "{side}_shoulder", "{s}_shoulder", "shoulder_{s}", "shoulder01.{S}"),
    ),
    "leg": (
        ("foot.{S}", "{side}_ankle", "{s}_ankle", "ankle_{s}", "lowerleg02.{S}"),
        ("upperleg01.{S}", "{side}_hip", "{s}_hip", "hip_{s}", "pelvis.{S}"),
    ),
}
_LANDMARKS = {
    "torso": (("waist_front", "waist_back"), ("neck_front", "neck_back")),
    "arm": (("wrist_{side}",), ("shoulder_{side}",)),
    "leg": (("ankle_{side}",), ("hip_{side}",)),
}


def _find_joint(names: Sequence[str], candidates, side: str) -> Optional[int]:
    low = {n.lower(): i for i, n in enumerate(names)}
    for c in candidates:
        key = c.format(S="L" if side == "left" else "R", side=side, s=side[0]).lower()
        if key in low:
            return low[key]
    return None


def body_part_axis(
    part: str, side: str, joint_names=None, joints=None, landmarks=None, faces=None, X=None, region_points=None
) -> np.ndarray:
    """Unit long axis (3,) of a body part, pointing up the part.

    Parameters
    ----------
    part : "torso", "arm" or "leg".
    side : "left" or "right" (ignored for the torso).
    joint_names, joints : the model's joint names and positions (J, 3) on the
        reference body, used when the names are recognised.
    region_points : (k, 3) vertices of the part's region: fallback, their
        principal axis (the long axis of a limb or the torso).
    landmarks, faces, X : last fallback: SurfacePoint landmarks on vertices X.
    """
    axis = None
    if joints is not None and joint_names is not None and part in _JOINTS:
        lo = _find_joint(joint_names, _JOINTS[part][0], side)
        hi = _find_joint(joint_names, _JOINTS[part][1], side)
        if lo is not None and hi is not None:
            axis = np.asarray(joints[hi], float) - np.asarray(joints[lo], float)
    if axis is None and region_points is not None and len(region_points) >= 10:
        P = np.asarray(region_points, float)
        _, _, vt = np.linalg.svd(P - P.mean(0), full_matrices=False)
        axis = vt[0]
    if axis is None and landmarks is not None and part in _LANDMARKS:
        try:
            pts = []
            for group in _LANDMARKS[part]:
                names = [n.format(side=side) for n in group]
                pts.append(
                    np.mean(
                        [np.asarray(landmarks[n].bary, float) @ X[faces[landmarks[n].triangle]] for n in names], axis=0
                    )
                )
            axis = pts[1] - pts[0]
        except KeyError:
            axis = None
    if axis is None and part == "torso" and X is not None and faces is not None:
        lying = surface_long_axis(np.asarray(X, float), np.asarray(faces))
        if lying is not None and abs(lying[2]) < np.sqrt(0.5):
            flat = surface_long_axis(np.asarray(X, float), np.asarray(faces), horizontal=True)
            if flat is not None:
                return flat if flat @ lying >= 0 else -flat
    if axis is None or np.linalg.norm(axis) < 1e-9:
        axis = np.array([0.0, 0.0, 1.0])
    if axis[2] < 0:
        axis = -axis
    return axis / np.linalg.norm(axis)


def surface_long_axis(X: np.ndarray, F: np.ndarray, horizontal: bool = False) -> Optional[np.ndarray]:
    """Unit principal axis (3,) of a mesh's surface, pointing to its higher end; None if degenerate.
    ``horizontal``: the principal direction of the surface seen from above (z = 0).

    The second moment is integrated exactly over each triangle (area/12 of the corners' outer
    products plus the sum's), so the answer does not depend on how finely the mesh is cut.
    The end whose outermost tenth of the surface (along the axis) stands higher is "up":
    a quadruped's head and neck, a person's head.

    Parameters
    ----------
    X : (V, 3) vertices, metres.  F : (F, 3) triangles.
    """
    if len(F) == 0:
        return None
    a, b, c = X[F[:, 0]], X[F[:, 1]], X[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    total = area.sum()
    if total <= 0:
        return None
    centroid = (area[:, None] * (a + b + c) / 3.0).sum(0) / total
    a, b, c = a - centroid, b - centroid, c - centroid
    s = a + b + c
    M = (
        np.einsum("f,fi,fj->ij", area / 12.0, a, a)
        + np.einsum("f,fi,fj->ij", area / 12.0, b, b)
        + np.einsum("f,fi,fj->ij", area / 12.0, c, c)
        + np.einsum("f,fi,fj->ij", area / 12.0, s, s)
    )
    if horizontal:
        M[2, :] = 0.0
        M[:, 2] = 0.0
    w, v = np.linalg.eigh(M)
    if w[-1] <= 0 or w[-1] - w[-2] < 1e-6 * w[-1]:
        return None
    axis = v[:, -1]
    mid = (a + b + c) / 3.0 + centroid
    t = (mid - centroid) @ axis
    lo, hi = np.quantile(t, [0.1, 0.9])
    if mid[t >= hi, 2].mean() < mid[t <= lo, 2].mean():
        axis = -axis
    return axis / np.linalg.norm(axis)


def warp_directions(X: np.ndarray, F: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Per-triangle unit warp (f, 3): ``axis`` projected into each triangle's plane.

    Where the axis is (nearly) normal to a triangle the projection is
    meaningless; there the body's horizontal ``+X`` turned into the plane,
    rotated a quarter turn about the normal, is used (a fixed tangent).
    """
    e1 = X[F[:, 1]] - X[F[:, 0]]
    e2 = X[F[:, 2]] - X[F[:, 0]]
    n = np.cross(e1, e2)
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    w = axis[None] - (n @ axis)[:, None] * n
    norm = np.linalg.norm(w, axis=1)
    bad = norm < 0.05
    if bad.any():
        ref = np.array([1.0, 0.0, 0.0])
        t = ref[None] - (n[bad] @ ref)[:, None] * n[bad]
        alt = np.cross(n[bad], t)
        small = np.linalg.norm(alt, axis=1) < 1e-6
        alt[small] = np.cross(n[bad][small], np.array([0.0, 1.0, 0.0]))
        w[bad] = alt
        norm = np.linalg.norm(w, axis=1)
    return w / np.maximum(norm, 1e-300)[:, None]
