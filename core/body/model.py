"""The body-model interface every parametric body implements.

Frame (fixed for the whole project): metres, +Z up, the body faces -Y, +X is
the body's left. Models convert their native frame once, at this boundary.

Shape is a ``dict[str, float]`` of named parameters (Anny phenotypes, SMPL
``beta0..``), pose is a preset name (``"A"``, ``"T"``, ``"P1"``, ``"P2"``,
``"P3"``) or a ``dict[str, array(3)]`` of joint name -> axis-angle rotation,
or None for the reference A-pose.

Joint rotations (radians) are applied on top of the reference pose, about axes
of the project frame (+X body's left, +Y back, +Z up) as they stand at the
reference pose, carried along by the parent's rotation: a bone's rotation
relative to the reference pose is ``G_bone = G_parent @ R(axis_angle)``. So a
joint whose ancestors are not rotated turns about the world axes of the
reference pose (``{"lowerarm01.L": [0, 0, 1.2]}`` swings the forearm 1.2 rad
about +Z), and a joint below a rotated one turns about those axes rotated with
its parent. The axes are not the bone's own local (bone-aligned) frame. Every
model uses this convention (Anny: its ``local-ref`` parameterisation; SMPL and
skinned OBJ templates: their rest joint frames are the world axes).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Dict, Mapping, Optional, Union

import numpy as np

from ..choices import POSE_PRESETS, REFERENCE_POSE  # noqa: F401  (re-exported: the model's interface)
from ..geom.frame import FRAME  # noqa: F401  (re-exported: the core frame, core.geom.frame)

Shape = Mapping[str, float]
Pose = Union[str, Mapping[str, np.ndarray], None]


REQUIRED_LANDMARKS = (
    "neck_front",
    "neck_back",
    "neck_left",
    "neck_right",
    "shoulder_left",
    "shoulder_right",
    "armpit_left",
    "armpit_right",
    "bust_left",
    "bust_right",
    "waist_front",
    "waist_back",
    "waist_left",
    "waist_right",
    "hip_left",
    "hip_right",
    "crotch",
    "navel",
    "elbow_left",
    "elbow_right",
    "wrist_left",
    "wrist_right",
    "knee_left",
    "knee_right",
    "ankle_left",
    "ankle_right",
)

REQUIRED_REGIONS = ("head", "hands", "feet")

# Longest joint rotation a pose may give (radians): every rotation has an axis-angle of at most pi;
# up to a full turn is accepted, anything longer is a unit mistake (degrees).
POSE_ANGLE_MAX = 2.0 * np.pi


def listed(names, limit: int = 12) -> str:
    """``a, b, c, ... (N in all)``: the first names of a long list, for one error line."""
    names = list(names)
    return ", ".join(names[:limit]) + (f", ... ({len(names)} in all)" if len(names) > limit else "")


def check_axis_angle(value, joint: str, joints, model: str = "") -> np.ndarray:
    """The (3,) axis-angle (radians) of ``pose[joint]``, checked: a known joint, three finite numbers,
    at most :data:`POSE_ANGLE_MAX` long.

    Raises
    ------
    BodyError naming the pose field (``pose.left_elbow``).
    """
    from ..errors import BodyError

    pre = f"{model}: " if model else ""
    if joint not in joints:
        raise BodyError(f"{pre}pose.{joint}: unknown joint; joints: {', '.join(joints)}")
    try:
        aa = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        aa = None
    if aa is None or aa.shape != (3,) or not np.all(np.isfinite(aa)):
        raise BodyError(
            f"{pre}pose.{joint}: expected a finite axis-angle [rx, ry, rz] in radians, got {str(value)[:60]}"
        )
    if float(np.linalg.norm(aa)) > POSE_ANGLE_MAX:
        raise BodyError(
            f"{pre}pose.{joint}: a rotation of {np.linalg.norm(aa):.4g} rad is more than a full "
            f"turn ({POSE_ANGLE_MAX:.4g} rad); pose angles are radians, not degrees"
        )
    return aa


@dataclass(frozen=True)
class SurfacePoint:
    """A point on the template surface: a triangle id and barycentric weights.

    Holds for every shape and pose of the model, since the topology is fixed.
    """

    triangle: int
    bary: tuple  # (3,) floats summing to 1

    def position(self, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
        """3D position (3,) on a body instance ``vertices`` (V, 3)."""
        tri = faces[self.triangle]
        return np.asarray(self.bary, dtype=float) @ vertices[tri]

    def to_json(self) -> dict:
        return {"triangle": int(self.triangle), "bary": [float(b) for b in self.bary]}

    @staticmethod
    def from_json(obj: Mapping) -> "SurfacePoint":
        return SurfacePoint(int(obj["triangle"]), tuple(float(b) for b in obj["bary"]))


class BodyModel(ABC):
    """A fixed-topology parametric body.

    Attributes
    ----------
    name : str
    faces : (F, 3) int array, triangles of the template (consistently oriented, outward).
    joint_names : list[str]
    symmetry : (V,) int array, the left<->right mirror of every vertex.
    landmarks : dict[str, SurfacePoint], at least :data:`REQUIRED_LANDMARKS`.
    regions : dict[str, (k,) int array of vertex ids], at least :data:`REQUIRED_REGIONS`
        (never covered by a garment), plus body parts used for grain
        (``"torso"``, ``"arm_left"``, ``"arm_right"``, ``"leg_left"``, ``"leg_right"``)
        where the model knows them.
    """

    name: str
    faces: np.ndarray
    joint_names: list
    symmetry: np.ndarray
    landmarks: Dict[str, SurfacePoint]
    regions: Dict[str, np.ndarray]

    @abstractmethod
    def default_shape(self) -> Dict[str, float]:
        """The reference shape (size M for the default body)."""

    @abstractmethod
    def shape_parameters(self) -> Dict[str, tuple]:
        """Allowed shape parameters: name -> (min, max, default)."""

    @abstractmethod
    def vertices(self, shape: Optional[Shape] = None, pose: Pose = None) -> np.ndarray:
        """Posed vertices (V, 3) in metres. ``None`` means reference shape / A-pose."""

    @abstractmethod
    def joints(self, shape: Optional[Shape] = None, pose: Pose = None) -> np.ndarray:
        """Posed joint positions (J, 3) in metres, ordered as :attr:`joint_names`."""

    @property
    def n_vertices(self) -> int:
        return int(self.symmetry.shape[0])

    def landmark_position(self, name: str, vertices: np.ndarray) -> np.ndarray:
        from ..errors import BodyError

        if name not in self.landmarks:
            raise BodyError(f"unknown landmark {name!r}; known: {', '.join(sorted(self.landmarks))}")
        return self.landmarks[name].position(vertices, self.faces)


def check_shape(allowed: Mapping[str, tuple], shape: Optional[Mapping[str, float]], model: str) -> Dict[str, float]:
    """Complete and validate a shape dict against ``allowed`` (name -> (min, max, default)).

    Every model (Anny, SMPL, OBJ) checks shapes here: an unknown parameter, a
    non-number or a value out of its range is a BodyError naming ``shape.<name>``."""
    from ..errors import BodyError

    out = {k: float(v[2]) for k, v in allowed.items()}
    if shape is None:
        return out
    for key, value in shape.items():
        if key not in allowed:
            raise BodyError(f"{model}: shape.{key}: unknown shape parameter; allowed: {listed(allowed)}")
        lo, hi, _ = allowed[key]
        try:
            value = float(value)
        except (TypeError, ValueError, OverflowError):
            raise BodyError(f"{model}: shape.{key}: must be a number, got {str(value)[:60]!r}") from None
        if not (lo <= value <= hi) or not np.isfinite(value):
            raise BodyError(f"{model}: shape.{key}={value:g} is out of range [{lo:g}, {hi:g}]")
        out[key] = value
    return out
