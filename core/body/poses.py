"""Pose presets of the default body (Anny) and arbitrary joint rotations.

Presets follow the reference body set of ``SPEC.md``:

- ``A`` (reference): Anny's rest pose - arms about 45 degrees below the horizontal,
  elbows slightly bent, legs slightly apart. All joint rotations are identity.
- ``T``: upper arms horizontal (shoulder abduction 90 degrees), legs as in A.
- ``P1``: arms forward (shoulder flexion 90 degrees), legs spread (each thigh 20 degrees
  out from the vertical).
- ``P2``: arms up (shoulder abduction 160 degrees), scissored legs: left hip flexed 30
  degrees, right hip extended 30 degrees.
- ``P3``: sitting: hips flexed 90 degrees (thighs horizontal, forward), knees flexed 90
  degrees (shins vertical), upper arms down along the torso, elbows flexed 90 degrees
  with the forearms horizontal in front.

Presets aim limb segments (from one joint to the next) at target directions in the
body frame, computed on the rest skeleton of the shape being posed, so the stated
angles hold for every shape. A rotation of a bone turns it about its head and
carries all its descendants.

Arbitrary rotations: ``{joint name: axis-angle (3,)}`` in radians, axes of our frame
(+X body's left, +Y back, +Z up) as they stand at the reference pose and carried along
by the parent's rotation (Anny's ``local-ref`` parameterisation). They apply on top of
the A-pose. A dict may also name a preset under the key ``"preset"``; its rotations are
then applied after that preset's.
"""

from __future__ import annotations

from typing import Dict, Mapping

import numpy as np

from ..errors import BodyError
from .lbs import rodrigues
from .model import POSE_PRESETS, check_axis_angle


def rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (3, 3) taking direction ``a`` to direction ``b``."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis)
    c = float(np.dot(a, b))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        # Opposite directions: half-turn about any axis orthogonal to a.
        ortho = np.cross(a, [1.0, 0.0, 0.0])
        if np.linalg.norm(ortho) < 1e-6:
            ortho = np.cross(a, [0.0, 1.0, 0.0])
        return rodrigues(np.pi * ortho / np.linalg.norm(ortho))
    return rodrigues(axis / s * np.arctan2(s, c))


def _axis_angle(R: np.ndarray) -> np.ndarray:
    """Axis-angle (3,) of a rotation matrix with angle < pi."""
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = np.linalg.norm(w) / 2.0
    c = (np.trace(R) - 1.0) / 2.0
    angle = np.arctan2(s, c)
    return w / (2.0 * s) * angle if s > 1e-12 else np.zeros(3)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


# Share of an arm raise taken by the shoulder girdle (scapula/clavicle lift), the rest
# by the shoulder joint; roughly the scapulohumeral rhythm (1:2).
SHOULDER_GIRDLE_SHARE = 1.0 / 3.0


class _Aimer:
    """Accumulates world rotations of bones aimed down a chain (parents first)."""

    def __init__(self, names, parents, heads):
        self.names, self.parents, self.heads = names, parents, heads
        self.world = {}  # bone -> accumulated world rotation (relative to the reference pose)
        self.local = {}  # bone -> delta rotation (parent-carried reference axes)

    def _parent_world(self, bone):
        j = self.names.index(bone)
        p = self.parents[j]
        while p >= 0:
            if self.names[p] in self.world:
                return self.world[self.names[p]]
            p = self.parents[p]
        return np.eye(3)

    def aim(self, bone: str, child: str, target, share: float = 0.0, helper: str = None) -> None:
        """Rotate ``bone`` so that its segment to joint ``child`` points along ``target``.

        With ``helper`` (an ancestor of ``bone``), that bone first takes ``share`` of the
        rotation about the same axis - e.g. the shoulder girdle lifting with a raised
        arm, which spares the armpit the whole turn - and ``bone`` completes it.
        """
        if helper is not None and share > 0:
            Gh = self._parent_world(helper)
            seg = self.heads[self.names.index(child)] - self.heads[self.names.index(bone)]
            full = rotation_between(self._parent_world(bone) @ seg, target)
            axis_angle = _axis_angle(full)
            world_h = rodrigues(share * axis_angle) @ Gh
            self.local[helper] = Gh.T @ world_h
            self.world[helper] = world_h
        G = self._parent_world(bone)
        seg = self.heads[self.names.index(child)] - self.heads[self.names.index(bone)]
        cur = G @ seg
        world = rotation_between(cur, target) @ G
        # local-ref: world rotation of a bone = (parent's world rotation) @ delta.
        self.local[bone] = G.T @ world
        self.world[bone] = world


def _preset(name: str, names, parents, heads) -> Dict[str, np.ndarray]:
    a = _Aimer(names, parents, heads)
    if name == "A":
        return {}
    for sx, s in ((1.0, ".L"), (-1.0, ".R")):
        if name == "T":
            a.aim(
                "upperarm01" + s, "lowerarm01" + s, (sx, 0.0, 0.0), share=SHOULDER_GIRDLE_SHARE, helper="shoulder01" + s
            )
        elif name == "P1":
            a.aim(
                "upperarm01" + s,
                "lowerarm01" + s,
                (0.0, -1.0, 0.0),
                share=SHOULDER_GIRDLE_SHARE,
                helper="shoulder01" + s,
            )
            a.aim("upperleg01" + s, "lowerleg01" + s, (sx * np.sin(np.radians(20)), 0.0, -np.cos(np.radians(20))))
        elif name == "P2":
            t = np.radians(160)
            a.aim(
                "upperarm01" + s,
                "lowerarm01" + s,
                (sx * np.sin(t), 0.0, -np.cos(t)),
                share=SHOULDER_GIRDLE_SHARE,
                helper="shoulder01" + s,
            )
            h = np.radians(30) * (1.0 if s == ".L" else -1.0)  # left flexed, right extended
            spread = np.radians(5)
            a.aim("upperleg01" + s, "lowerleg01" + s, _unit((sx * np.sin(spread), -np.sin(h), -np.cos(h))))
        elif name == "P3":
            a.aim("upperarm01" + s, "lowerarm01" + s, _unit((sx * 0.15, 0.0, -1.0)))
            a.aim("lowerarm01" + s, "wrist" + s, (0.0, -1.0, 0.0))
            a.aim("upperleg01" + s, "lowerleg01" + s, _unit((sx * 0.08, -1.0, 0.0)))
            a.aim("lowerleg01" + s, "foot" + s, (0.0, 0.0, -1.0))
        else:
            raise BodyError(f"unknown pose preset {name!r}; allowed: {', '.join(POSE_PRESETS)}")
    return a.local


def pose_rotations(body, pose, heads: np.ndarray, to_native: np.ndarray = None) -> np.ndarray:
    """Per-bone delta rotations (J, 3, 3) for ``pose`` on a body with rest heads ``heads``.

    Parameters
    ----------
    body : a body with ``joint_names`` and ``data.parents`` (Anny).
    pose : None / preset name / dict joint -> axis-angle (see module docstring).
    heads : (J, 3) rest joint positions of the shape being posed, in our frame.
    to_native : (3, 3) rotation from our frame to the model's native frame (identity for Anny).
    """
    names = list(body.joint_names)
    parents = np.asarray(body.data.parents)
    J = len(names)
    D = np.broadcast_to(np.eye(3), (J, 3, 3)).copy()
    if pose is None:
        return D
    preset, extra = None, {}
    if isinstance(pose, str):
        preset = pose
    elif isinstance(pose, Mapping):
        extra = dict(pose)
        preset = extra.pop("preset", None)
    else:
        raise BodyError(
            f"pose must be a preset name ({', '.join(POSE_PRESETS)}), a dict "
            f"joint -> axis-angle, or None; got {type(pose).__name__}"
        )
    if preset is not None:
        if preset not in POSE_PRESETS:
            raise BodyError(f"unknown pose preset {preset!r}; allowed: {', '.join(POSE_PRESETS)}")
        for bone, R in _preset(preset, names, parents, heads).items():
            D[names.index(bone)] = R
    for bone, aa in extra.items():
        aa = check_axis_angle(aa, bone, names, getattr(body, "name", ""))
        j = names.index(bone)
        D[j] = rodrigues(aa) @ D[j]
    if to_native is not None:
        D = to_native @ D @ to_native.T
    return D
