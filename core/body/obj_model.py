"""Any fixed-topology OBJ template as a body model (a mannequin, a horse, ...).

Shape is a dict of blend-shape weights (from an optional ``.npz``), pose is
only the template's own pose (``None``/``"A"``) unless the ``.npz`` also
carries a skeleton (``weights``, ``joints``, ``parents``), in which case a
pose dict of joint -> axis-angle is skinned with :mod:`.lbs`.

Blend-shape ``.npz`` keys: ``names`` (K,), ``deltas`` (K, V, 3) in the OBJ's
units and frame; optional ``ranges`` (K, 2) (default [0, 1] per shape, as
Blender's shape keys), ``weights`` (V, J), ``joints`` (J, 3), ``parents`` (J,),
``joint_names`` (J,). Landmark JSON: ``{name: {"triangle": t, "bary": [..3]}}``
or ``{name: vertex_id}``, or ``{"landmarks": {...}, "regions": {name: [ids]}}``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Dict, Mapping, Optional

import numpy as np

from ..errors import BodyError
from .arrays import finite_array, index_array, read_npz
from .lbs import check_parents, forward_kinematics, rodrigues, skin
from .model import POSE_PRESETS, BodyModel, SurfacePoint, check_axis_angle, check_shape
from .smpl import SMPL_TO_OURS, _vertex_point, mirror_map

# An OBJ of a 1 M-vertex scan is ~60 MB; refuse files far beyond before reading them.
MAX_OBJ_BYTES = 1 << 30

# Frame conversions into ours (Z up, facing -Y, +X the body's left).
UP_AXES = {"z": np.eye(3), "y": SMPL_TO_OURS}


def read_obj(path) -> tuple:
    """Vertices (V, 3) and triangles (F, 3) of an OBJ file; polygons are fan-triangulated.

    Raises
    ------
    BodyError : unreadable file, no faces, or a face index out of range (line named).
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_OBJ_BYTES:
            raise BodyError(f"{path}: an OBJ template over {MAX_OBJ_BYTES >> 20} MiB; not a body this project reads")
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise BodyError(f"cannot read OBJ template {path}: {exc.strerror}") from None
    verts, faces = [], []
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            try:
                verts.append([float(c) for c in parts[1:4]])
            except ValueError:
                raise BodyError(f"{path}:{lineno}: bad vertex line {line.strip()[:60]!r}") from None
            if len(verts[-1]) != 3:
                raise BodyError(f"{path}:{lineno}: a vertex needs 3 coordinates")
            if not all(math.isfinite(c) for c in verts[-1]):
                raise BodyError(
                    f"{path}:{lineno}: vertex coordinates must be finite numbers, got {line.strip()[:60]!r}"
                )
        elif parts[0] == "f":
            try:
                ids = [int(p.split("/")[0]) for p in parts[1:]]
            except ValueError:
                raise BodyError(f"{path}:{lineno}: bad face line {line.strip()[:60]!r}") from None
            n = len(verts)
            ids = [i - 1 if i > 0 else n + i for i in ids]
            if len(ids) < 3 or min(ids) < 0 or max(ids) >= n:
                raise BodyError(
                    f"{path}:{lineno}: face refers to a vertex that does not exist (file has {n} vertices so far)"
                )
            faces.extend([ids[0], ids[k], ids[k + 1]] for k in range(1, len(ids) - 1))
    if not faces:
        raise BodyError(f"{path}: OBJ template has no faces")
    return np.array(verts, dtype=float), np.array(faces, dtype=np.int64)


def _landmarks_from_json(obj, faces: np.ndarray, V: int, where: str):
    if "landmarks" in obj and isinstance(obj["landmarks"], Mapping):
        marks, regions = obj["landmarks"], obj.get("regions", {})
    else:
        marks, regions = obj, {}
    out = {}
    for name, spec in marks.items():
        if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
            if not 0 <= spec < V:
                raise BodyError(f"{where}: landmark {name!r}: vertex {spec} out of range [0, {V})")
            try:
                out[name] = _vertex_point(faces, int(spec))
            except BodyError as exc:
                raise BodyError(f"{where}: landmark {name!r}: {exc}") from None
            continue
        if not isinstance(spec, Mapping) or "triangle" not in spec or "bary" not in spec:
            raise BodyError(
                f'{where}: landmark {name!r} must be a vertex id or {{"triangle": t, "bary": [b0, b1, b2]}}'
            )
        try:
            point = SurfacePoint.from_json(spec)
        except (TypeError, ValueError):
            raise BodyError(f"{where}: landmark {name!r}: triangle must be an integer, bary three numbers") from None
        if not 0 <= point.triangle < len(faces):
            raise BodyError(f"{where}: landmark {name!r}: triangle {point.triangle} out of range [0, {len(faces)})")
        if len(point.bary) != 3 or abs(sum(point.bary) - 1.0) > 1e-6 or min(point.bary) < -1e-9:
            raise BodyError(f"{where}: landmark {name!r}: bary must be 3 non-negative weights summing to 1")
        out[name] = point
    regs = {}
    if not isinstance(regions, Mapping):
        raise BodyError(f"{where}: 'regions' must be an object name -> [vertex ids]")
    for name, ids in regions.items():
        if not isinstance(ids, list) or not all(isinstance(i, int) and not isinstance(i, bool) for i in ids):
            raise BodyError(f"{where}: region {name!r} must be a list of vertex ids")
        ids = np.asarray(ids, dtype=np.int64).ravel() if ids else np.zeros(0, dtype=np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= V):
            raise BodyError(f"{where}: region {name!r} has vertex ids outside [0, {V})")
        regs[name] = ids
    return out, regs


class OBJBody(BodyModel):
    """A template mesh with optional blend shapes and skeleton; see the module doc."""

    def __init__(
        self,
        vertices,
        faces,
        name="obj",
        blend_names=(),
        deltas=None,
        ranges=None,
        weights=None,
        joints=None,
        parents=None,
        joint_names=None,
        landmarks=None,
        regions=None,
        source="",
        skeleton_source=None,
    ):
        self.name = name
        self.source = source or name
        self.template = np.asarray(vertices, dtype=float)
        self.faces = np.asarray(faces, dtype=np.int64)
        V = len(self.template)
        K = len(blend_names)
        self.blend_names = [str(n) for n in blend_names]
        self.deltas = np.zeros((0, V, 3)) if deltas is None else np.asarray(deltas, dtype=float)
        if self.deltas.shape != (K, V, 3):
            raise BodyError(
                f"{self.source}: blend shape 'deltas' has shape {self.deltas.shape}, "
                f"expected ({K}, {V}, 3) for {K} names and {V} template vertices"
            )
        rng = np.tile([0.0, 1.0], (K, 1)) if ranges is None else np.asarray(ranges, dtype=float)
        if rng.shape != (K, 2) or np.any(rng[:, 0] > 0) or np.any(rng[:, 1] < 0):
            raise BodyError(f"{self.source}: blend shape 'ranges' must be (K, 2) [min, max] around 0")
        self._params = {n: (float(lo), float(hi), 0.0) for n, (lo, hi) in zip(self.blend_names, rng)}
        self._deltas_flat = self.deltas.reshape(K, V * 3).T
        self.weights = None
        if weights is not None:
            self.weights = np.asarray(weights, dtype=float)
            self.rest_joints = np.asarray(joints, dtype=float)
            try:
                self.parents = check_parents(parents)
            except BodyError as exc:
                raise BodyError(f"{skeleton_source or self.source}: {exc}") from None
            J = len(self.parents)
            if self.weights.shape != (V, J) or self.rest_joints.shape != (J, 3):
                raise BodyError(
                    f"{self.source}: skeleton needs weights ({V}, {J}) and joints ({J}, 3), "
                    f"got {self.weights.shape} and {self.rest_joints.shape}"
                )
            self.joint_names = (
                [str(n) for n in np.asarray(joint_names).ravel()]
                if joint_names is not None
                else [f"joint{j}" for j in range(J)]
            )
            if len(self.joint_names) != J:
                raise BodyError(f"{self.source}: skeleton has {J} joints but {len(self.joint_names)} joint_names")
        else:
            self.rest_joints = np.zeros((0, 3))
            self.parents = np.zeros(0, dtype=np.int64)
            self.joint_names = []
        self._joint_index = {n: i for i, n in enumerate(self.joint_names)}
        self.symmetry = mirror_map(self.template)
        self.landmarks = dict(landmarks or {})
        self.regions = dict(regions or {})

    def default_shape(self) -> Dict[str, float]:
        return {k: 0.0 for k in self._params}

    def shape_parameters(self) -> Dict[str, tuple]:
        return dict(self._params)

    def _shaped(self, shape) -> np.ndarray:
        full = check_shape(self._params, shape, self.name)
        w = np.array([full[n] for n in self.blend_names])
        if not w.size:
            return self.template.copy()
        return self.template + (self._deltas_flat @ w).reshape(-1, 3)

    def _rotations(self, pose) -> Optional[np.ndarray]:
        if pose is None or (isinstance(pose, str) and pose == "A"):
            return None
        if isinstance(pose, str):
            if pose not in POSE_PRESETS:
                raise BodyError(f"unknown pose preset {pose!r}; allowed: {', '.join(POSE_PRESETS)}")
            raise BodyError(
                f"{self.name}: pose preset {pose!r} needs a skeleton with known joints; this "
                "template has only its own pose (A/None), or give a dict joint -> axis-angle"
            )
        if not isinstance(pose, Mapping):
            raise BodyError(
                f"pose must be a preset name, a dict joint -> axis-angle or None; got {type(pose).__name__}"
            )
        if self.weights is None and pose:
            raise BodyError(
                f"{self.name}: this template has no skeleton (add weights, joints and parents "
                "to its .npz); only the template pose (A/None) is available"
            )
        aa = np.zeros((len(self.joint_names), 3))
        for name, r in pose.items():
            aa[self._joint_index[name]] = check_axis_angle(r, name, self._joint_index, self.source)
        return rodrigues(aa)

    def vertices(self, shape=None, pose=None) -> np.ndarray:
        v = self._shaped(shape)
        R = self._rotations(pose)
        if R is None:
            return v
        _, G = forward_kinematics(R, self.rest_joints, self.parents)
        return skin(v, self.weights, G)

    def joints(self, shape=None, pose=None) -> np.ndarray:
        check_shape(self._params, shape, self.name)
        R = self._rotations(pose)
        if R is None:
            return self.rest_joints.copy()
        return forward_kinematics(R, self.rest_joints, self.parents)[0]

    def landmark_position(self, name: str, vertices: np.ndarray) -> np.ndarray:
        if name not in self.landmarks:
            known = ", ".join(sorted(self.landmarks)) or "none (pass a landmark JSON)"
            raise BodyError(f"{self.name}: landmark {name!r} is not defined for this template; known: {known}")
        return self.landmarks[name].position(vertices, self.faces)


def load_obj_body(path, blendshapes=None, landmarks=None, up: str = "z", name: Optional[str] = None) -> OBJBody:
    """Load an OBJ template as a body model.

    Parameters
    ----------
    path : OBJ file (fixed topology; polygons are triangulated).
    blendshapes : optional ``.npz`` with ``names`` and ``deltas`` (K, V, 3), and
        optionally ``ranges``, and a skeleton ``weights``/``joints``/``parents``.
    landmarks : optional JSON file of landmarks (and regions), see the module doc.
    up : ``"z"`` (already our frame) or ``"y"`` (Y up, facing +Z, as most DCC
        exports and SMPL): converted once into ours.
    """
    path = Path(path)
    key = str(up).lower().lstrip("+")
    if key not in UP_AXES:
        raise BodyError(f"up axis {up!r} not supported; allowed: {', '.join(UP_AXES)}")
    Cm = UP_AXES[key]
    if not path.is_file():
        raise BodyError(f"OBJ template not found: {path}")
    verts, faces = read_obj(path)
    V = len(verts)
    kw = {}
    if blendshapes is not None:
        bpath = Path(blendshapes)
        if not bpath.is_file():
            raise BodyError(f"blend-shape .npz not found: {bpath}")
        arrays = read_npz(bpath, what="blend-shape .npz")
        for k in ("names", "deltas"):
            if k not in arrays:
                raise BodyError(f"{bpath}: missing key {k!r} (blend shapes need names and deltas)")
        num = lambda k: finite_array(arrays[k], f"{bpath}: key {k!r}")
        deltas = num("deltas")
        if deltas.ndim != 3 or deltas.shape[1:] != (V, 3):
            raise BodyError(f"{bpath}: 'deltas' has shape {deltas.shape}, expected (K, {V}, 3)")
        names = arrays["names"]
        if names.ndim != 1 or len(names) != len(deltas) or names.dtype.kind not in "SU":
            raise BodyError(
                f"{bpath}: key 'names' must be {len(deltas)} texts (one per blend shape), got "
                f"shape {names.shape} of {names.dtype.str!r}"
            )
        kw.update(blend_names=list(names), deltas=deltas @ Cm.T, ranges=num("ranges") if "ranges" in arrays else None)
        skeleton = [k for k in ("weights", "joints", "parents") if k in arrays]
        if skeleton and len(skeleton) < 3:
            missing = sorted({"weights", "joints", "parents"} - set(skeleton))
            raise BodyError(f"{bpath}: skeleton is incomplete, missing key {missing[0]!r}")
        if skeleton:
            joints = num("joints")
            if joints.ndim != 2 or joints.shape[1] != 3:
                raise BodyError(f"{bpath}: key 'joints' has shape {joints.shape}, expected (J, 3)")
            kw.update(
                weights=num("weights"),
                joints=joints @ Cm.T,
                parents=index_array(arrays["parents"], f"{bpath}: key 'parents'"),
                joint_names=arrays.get("joint_names"),
                skeleton_source=f"{bpath}: key 'parents'",
            )
    if landmarks is not None:
        lpath = Path(landmarks)
        try:
            obj = json.loads(lpath.read_text(encoding="utf-8"))
        except RecursionError:
            raise BodyError(f"{lpath}: not a readable landmark JSON (nested too deeply)") from None
        except (OSError, ValueError) as exc:
            raise BodyError(f"{lpath}: not a readable landmark JSON ({exc})") from None
        if not isinstance(obj, Mapping):
            raise BodyError(f"{lpath}: landmark JSON must be an object name -> point")
        kw["landmarks"], kw["regions"] = _landmarks_from_json(obj, faces, V, str(lpath))
    return OBJBody(verts @ Cm.T, faces, name=name or path.stem, source=str(path), **kw)
