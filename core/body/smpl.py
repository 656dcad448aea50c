"""SMPL and SMPL-X bodies from model files the user owns (``.npz`` or ``.pkl``).

Own numpy loader and linear blend skinning; pickles go through the restricted
:mod:`.unpickle`, never through :func:`pickle.load`.

SMPL's frame is Y up, the body facing +Z, +X the body's left. Ours is Z up,
facing -Y, +X left: a +90 deg rotation about X, ``ours = (x, -z, y)``. The
template, the shape and pose blend shapes are converted once at load; joint
rotations are given in our frame and turned back into SMPL's frame only for
the pose-corrective feature, which SMPL learnt in its own frame.

Landmarks of the real SMPL topology (6890 vertices) come from the vertex ids
commonly used in SMPL anthropometry (Boja et al., *SMPL-Anthropometry*):
nipples 3042/6489, belly button 3501, back of the belly button 3022, crotch
1210, wrists 2241/5559, shoulder tips 3011/6470, left ankle 3325, front of the
neck (Adam's apple) 3050, top of the head 412. The rest are found once on the
template by rules stated in :func:`_smpl_landmarks` (extremes of thin slices
at joint heights), and right-side points mirror left-side ones. For other
topologies (SMPL-X, custom files) the landmarks are unknown and asking for one
raises :class:`BodyError`; regions still come from the skinning weights where
the joints carry SMPL names.
"""

from __future__ import annotations

from pathlib import Path
from typing import Dict, Mapping, Optional

import numpy as np

from ..errors import BodyError
from .lbs import check_parents, forward_kinematics, pose_feature, rodrigues, skin
from .model import POSE_PRESETS, BodyModel, SurfacePoint, check_axis_angle, check_shape

SMPL_JOINT_NAMES = (
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hand",
    "right_hand",
)

_FINGERS = tuple(
    f"{side}_{finger}{k}"
    for side in ("left", "right")
    for finger in ("index", "middle", "pinky", "ring", "thumb")
    for k in (1, 2, 3)
)
SMPLX_JOINT_NAMES = SMPL_JOINT_NAMES[:22] + ("jaw", "left_eye_smplhf", "right_eye_smplhf") + _FINGERS
SMPLH_JOINT_NAMES = SMPL_JOINT_NAMES[:22] + _FINGERS

REQUIRED_KEYS = ("v_template", "shapedirs", "posedirs", "J_regressor", "weights", "kintree_table", "f")

# SMPL (Y up, facing +Z) -> ours (Z up, facing -Y): ours = C @ smpl.
SMPL_TO_OURS = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

BETA_RANGE = (-5.0, 5.0)

# Vertex ids of the SMPL topology (6890 vertices), SMPL-Anthropometry.
SMPL_VERTEX_IDS = {
    "bust_left": 3042,
    "bust_right": 6489,
    "navel": 3501,
    "waist_back": 3022,
    "crotch": 1210,
    "wrist_left": 2241,
    "wrist_right": 5559,
    "shoulder_left": 3011,
    "shoulder_right": 6470,
    "ankle_left": 3325,
    "neck_front": 3050,
    "head_top": 412,
}
SMPL_N_VERTICES = 6890

_DEG = np.pi / 180.0


def _preset_rotations(name: str) -> Dict[str, np.ndarray]:
    """Axis-angle (our frame) per SMPL joint for a pose preset; SMPL's zero pose is a T-pose.

    Rotations about +Y lower the left arm (+X) and raise the right; about X
    swing a leg forward (negative) or back; about Z swing the left arm forward
    (negative). Angles follow SPEC.md's pose set.
    """
    y = lambda deg: np.array([0.0, deg * _DEG, 0.0])
    x = lambda deg: np.array([deg * _DEG, 0.0, 0.0])
    z = lambda deg: np.array([0.0, 0.0, deg * _DEG])
    legs_a = {"left_hip": y(-5), "right_hip": y(5)}
    if name == "A":  # arms ~45 deg below horizontal, legs slightly apart
        return {"left_shoulder": y(45), "right_shoulder": y(-45), **legs_a}
    if name == "T":
        return dict(legs_a)
    if name == "P1":  # shoulder flexion 90 deg, legs spread
        return {"left_shoulder": z(-90), "right_shoulder": z(90), "left_hip": y(-20), "right_hip": y(20)}
    if name == "P2":  # shoulder abduction 160 deg, scissored legs
        return {"left_shoulder": y(-70), "right_shoulder": y(70), "left_hip": x(-30), "right_hip": x(30)}
    if name == "P3":  # sitting, elbows bent 90 deg with forearms in front
        return {
            "left_hip": x(-90),
            "right_hip": x(-90),
            "left_knee": x(90),
            "right_knee": x(90),
            "left_shoulder": y(80),
            "right_shoulder": y(-80),
            "left_elbow": z(-90),
            "right_elbow": z(90),
        }
    raise BodyError(f"unknown pose preset {name!r}; allowed: {', '.join(POSE_PRESETS)} or a dict joint -> axis-angle")


def _vertex_point(faces: np.ndarray, vid: int) -> SurfacePoint:
    hits = np.nonzero((faces == vid).any(axis=1))[0]
    if not hits.size:
        raise BodyError(f"vertex {vid} (a landmark) is on no triangle of 'f'")
    tri = int(hits[0])
    bary = tuple(1.0 if faces[tri, k] == vid else 0.0 for k in range(3))
    return SurfacePoint(tri, bary)


def mirror_map(vertices: np.ndarray) -> np.ndarray:
    """Left<->right vertex map: nearest neighbour of every x-reflected vertex, (V,) int."""
    from scipy.spatial import cKDTree

    reflected = vertices * np.array([-1.0, 1.0, 1.0])
    _, idx = cKDTree(vertices).query(reflected)
    return idx.astype(np.int64)


def _regions_from_weights(weights: np.ndarray, joint_names) -> Dict[str, np.ndarray]:
    """Body-part regions from the dominant skinning joint of every vertex."""
    names = list(joint_names)
    if "pelvis" not in names or "left_wrist" not in names:
        return {}
    owner = np.asarray(weights.argmax(axis=1)).ravel()
    idx = {n: i for i, n in enumerate(names)}

    def of(*joints):
        ids = [idx[j] for j in joints if j in idx]
        return np.nonzero(np.isin(owner, ids))[0].astype(np.int64)

    fingers_l = [n for n in names if n.startswith("left_") and n[5:-1] in ("index", "middle", "pinky", "ring", "thumb")]
    fingers_r = [
        n for n in names if n.startswith("right_") and n[6:-1] in ("index", "middle", "pinky", "ring", "thumb")
    ]
    return {
        "head": of("head", "jaw", "left_eye_smplhf", "right_eye_smplhf"),
        "hands": of("left_wrist", "right_wrist", "left_hand", "right_hand", *fingers_l, *fingers_r),
        "feet": of("left_ankle", "right_ankle", "left_foot", "right_foot"),
        "neck": of("neck"),
        "torso": of("pelvis", "spine1", "spine2", "spine3", "left_collar", "right_collar"),
        "arm_left": of("left_shoulder", "left_elbow"),
        "arm_right": of("right_shoulder", "right_elbow"),
        "leg_left": of("left_hip", "left_knee"),
        "leg_right": of("right_hip", "right_knee"),
    }


def _smpl_landmarks(
    v: np.ndarray, faces: np.ndarray, joints: np.ndarray, names, sym: np.ndarray, regions: Mapping[str, np.ndarray]
) -> Dict[str, SurfacePoint]:
    """Landmarks of the SMPL topology on its T-pose template ``v`` (our frame).

    Literature vertex ids (:data:`SMPL_VERTEX_IDS`) where they exist; otherwise:
    waist sides = outermost torso vertex within 1 cm of the navel height; hip
    sides = outermost torso/thigh vertex within 1 cm of the hip-joint height;
    neck back/sides = back-most / outermost vertex of the neck region within
    1.5 cm of the neck-joint height; armpit = lowest vertex skinned to the
    shoulder that is no further out than the shoulder joint; elbow = vertex
    nearest a point 10 cm behind the elbow joint; knee = nearest a point 10 cm
    in front of the knee joint; right side = mirror of the left.
    """
    j = {n: joints[i] for i, n in enumerate(names)}
    vid = dict(SMPL_VERTEX_IDS)
    empty = [r for r in ("torso", "neck", "arm_left", "leg_left", "leg_right") if not regions.get(r, ()).size]
    if empty:
        raise BodyError(
            f"key 'weights': no vertex is skinned mostly to the {empty[0]} joints; the SMPL "
            "landmarks need every body part"
        )
    torso = regions["torso"]
    nearest = lambda p, among: int(among[np.argmin(np.linalg.norm(v[among] - p, axis=1))])

    def slice_extreme(among, z, tol, key):
        if not among.size:
            raise BodyError(
                "key 'v_template': no vertex near the body's midline at the neck; the SMPL "
                "landmarks need an SMPL-like body"
            )
        sel = among[np.abs(v[among, 2] - z) < tol]
        if sel.size == 0:
            sel = among
        return int(sel[np.argmax(key(v[sel]))])

    vid["waist_left"] = slice_extreme(torso, v[vid["navel"], 2], 0.01, lambda p: p[:, 0])
    hips = np.concatenate([torso, regions["leg_left"], regions["leg_right"]])
    vid["hip_left"] = slice_extreme(hips, j["left_hip"][2], 0.01, lambda p: p[:, 0])
    neck = np.concatenate([regions["neck"], torso])
    neck = neck[np.abs(v[neck, 0]) < 0.1]
    vid["neck_back"] = slice_extreme(neck, j["neck"][2], 0.015, lambda p: p[:, 1] - 10 * np.abs(p[:, 0]))
    vid["neck_left"] = slice_extreme(regions["neck"], j["neck"][2], 0.015, lambda p: p[:, 0])
    arm = regions["arm_left"]
    under = arm[v[arm, 0] <= j["left_shoulder"][0]]
    vid["armpit_left"] = int(under[np.argmin(v[under, 2])]) if under.size else nearest(j["left_shoulder"], arm)
    vid["elbow_left"] = nearest(j["left_elbow"] + [0.0, 0.1, 0.0], np.arange(len(v)))
    vid["knee_left"] = nearest(j["left_knee"] + [0.0, -0.1, 0.0], np.arange(len(v)))
    for name in ("waist", "hip", "neck", "armpit", "elbow", "knee", "ankle"):
        vid[f"{name}_right"] = int(sym[vid[f"{name}_left"]])
    vid["waist_front"] = vid["navel"]
    vid.pop("head_top")
    return {name: _vertex_point(faces, i) for name, i in vid.items()}


class SMPLBody(BodyModel):
    """An SMPL-family body (SMPL, SMPL+H, SMPL-X body part) behind :class:`BodyModel`.

    Shape is ``{"beta0": b0, ...}`` (range :data:`BETA_RANGE`), pose a preset
    name or ``{joint_name: axis-angle (3,)}`` (optionally with ``"preset"``)
    applied on top of the A-pose (or the preset) about our frame's axes at the
    reference pose, carried by the parent's rotation (:mod:`core.body.model`).
    """

    def __init__(self, arrays: Mapping[str, np.ndarray], name: str = "smpl", source: str = ""):
        self.name = name
        self.source = source or name
        C = SMPL_TO_OURS
        import scipy.sparse as sp

        from .arrays import finite_array, index_array

        num = lambda key: finite_array(arrays[key], f"{self.source}: key {key!r}")
        v_template = num("v_template")
        V = v_template.shape[0] if v_template.ndim == 2 else -1
        self._check(
            v_template.ndim == 2 and v_template.shape[1] == 3 and V > 0, "v_template", "(V, 3)", v_template.shape
        )
        faces = index_array(arrays["f"], f"{self.source}: key 'f'")
        self._check(
            faces.ndim == 2 and faces.shape[1] == 3 and faces.size and faces.min() >= 0 and faces.max() < V,
            "f",
            f"(F, 3) vertex ids below {V}",
            faces.shape,
        )
        weights = num("weights")
        self._check(
            weights.ndim == 2 and weights.shape[0] == V and weights.shape[1] > 0, "weights", f"({V}, J)", weights.shape
        )
        J = weights.shape[1]
        kintree = index_array(arrays["kintree_table"], f"{self.source}: key 'kintree_table'")
        self._check(kintree.ndim == 2 and kintree.shape == (2, J), "kintree_table", f"(2, {J})", kintree.shape)
        jreg = arrays["J_regressor"]
        jreg = jreg.tocsr() if sp.issparse(jreg) else num("J_regressor")
        self._check(jreg.shape == (J, V), "J_regressor", f"({J}, {V})", jreg.shape)
        shapedirs = num("shapedirs")
        self._check(shapedirs.ndim == 3 and shapedirs.shape[:2] == (V, 3), "shapedirs", f"({V}, 3, B)", shapedirs.shape)
        posedirs = num("posedirs")
        P = 9 * (J - 1)
        self._check(posedirs.shape == (V, 3, P), "posedirs", f"({V}, 3, {P})", posedirs.shape)

        # Parents: first kintree row, as indices; the root's parent is -1 (or uint32 max).
        ids = {int(k): i for i, k in enumerate(kintree[1])}
        parents = np.array([-1] + [ids.get(int(p), -2) for p in kintree[0, 1:]], dtype=np.int64)
        try:
            self.parents = check_parents(parents)
        except BodyError as exc:
            raise BodyError(f"{self.source}: key 'kintree_table': {exc}") from None

        n_betas = shapedirs.shape[2]
        if J == 55 and "expr_dirs" not in arrays:
            # SMPL-X stores shape and expression directions together (300+100 or 10+10).
            n_betas = 300 if n_betas >= 400 else min(n_betas, 10)
        shapedirs = shapedirs[:, :, :n_betas]

        self.v_template = v_template @ C.T
        self.shapedirs = np.einsum("ab,vbk->vak", C, shapedirs)
        self.posedirs = np.einsum("ab,vbk->vak", C, posedirs).reshape(V * 3, P)
        self._shapedirs_flat = self.shapedirs.reshape(V * 3, n_betas)
        self.weights = weights
        self.faces = faces
        self.J_regressor = jreg
        self._j_template = np.asarray(jreg @ self.v_template)
        self._j_dirs = np.asarray(jreg @ self.shapedirs.reshape(V, 3 * n_betas)).reshape(J, 3, n_betas)
        self.n_betas = n_betas

        if J == 24:
            self.joint_names = list(SMPL_JOINT_NAMES)
        elif J == 55:
            self.joint_names = list(SMPLX_JOINT_NAMES)
        elif J == 52:
            self.joint_names = list(SMPLH_JOINT_NAMES)
        else:
            self.joint_names = [f"joint{i}" for i in range(J)]
        self._joint_index = {n: i for i, n in enumerate(self.joint_names)}
        self.symmetry = mirror_map(self.v_template)
        self.regions = _regions_from_weights(weights, self.joint_names)
        self.landmarks = {}
        if V == SMPL_N_VERTICES and J == 24:
            try:
                self.landmarks = _smpl_landmarks(
                    self.v_template, faces, self._j_template, self.joint_names, self.symmetry, self.regions
                )
            except BodyError as exc:
                raise BodyError(f"{self.source}: {exc}") from None
        self._params = {f"beta{i}": (BETA_RANGE[0], BETA_RANGE[1], 0.0) for i in range(n_betas)}

    def _check(self, ok, key, expected, got):
        if not ok:
            raise BodyError(f"{self.source}: key {key!r} has shape {tuple(got)}, expected {expected}")

    # -- BodyModel -----------------------------------------------------
    def default_shape(self) -> Dict[str, float]:
        return {k: 0.0 for k in self._params}

    def shape_parameters(self) -> Dict[str, tuple]:
        return dict(self._params)

    def betas(self, shape) -> np.ndarray:
        """(B,) beta vector of a shape dict (validated)."""
        full = check_shape(self._params, shape, self.name)
        return np.array([full[f"beta{i}"] for i in range(self.n_betas)])

    def rotations(self, pose) -> np.ndarray:
        """(J, 3, 3) local rotations (our frame) of a pose preset / dict / None (A-pose)."""
        J = len(self.joint_names)
        aa = np.zeros((J, 3))
        if pose is None or isinstance(pose, str):
            preset = _preset_rotations("A" if pose is None else pose)
            for name, r in preset.items():
                if name in self._joint_index:
                    aa[self._joint_index[name]] = r
            return rodrigues(aa)
        if not isinstance(pose, Mapping):
            raise BodyError(
                f"pose must be a preset name ({', '.join(POSE_PRESETS)}), a dict "
                f"joint -> axis-angle, or None; got {type(pose).__name__}"
            )
        pose = dict(pose)
        preset = pose.pop("preset", None)
        if preset is not None and preset not in POSE_PRESETS:
            raise BodyError(f"unknown pose preset {preset!r}; allowed: {', '.join(POSE_PRESETS)}")
        R = self.rotations(preset)
        # The axes are those of the reference (A) pose, carried by the parent's rotation
        # (see core.body.model): R_j <- (W_p^T r W_p) R_j with W_p the parent's world
        # rotation at the reference pose, so that G_j = G_parent @ r relative to it.
        RA = self.rotations(None)
        WA = np.empty_like(RA)
        for j, p in enumerate(self.parents):
            WA[j] = RA[j] if p < 0 else WA[p] @ RA[j]
        for name, r in pose.items():
            r = check_axis_angle(r, name, self._joint_index, self.source)
            j = self._joint_index[name]
            p = self.parents[j]
            Wp = WA[p] if p >= 0 else np.eye(3)
            R[j] = Wp.T @ rodrigues(r) @ Wp @ R[j]
        return R

    def rest_joints(self, betas: np.ndarray) -> np.ndarray:
        """(J, 3) joint positions of a shape in the zero (T) pose."""
        return self._j_template + self._j_dirs @ betas

    def shaped(self, betas: np.ndarray) -> np.ndarray:
        """(V, 3) zero-pose vertices of a shape."""
        return self.v_template + (self._shapedirs_flat @ betas).reshape(-1, 3)

    def _pose(self, shape, pose):
        b = self.betas(shape)
        R = self.rotations(pose)
        v = self.shaped(b)
        C = SMPL_TO_OURS
        feat = pose_feature(np.einsum("ba,jbc,cd->jad", C, R, C))  # C^T R C: back to SMPL's frame
        v = v + (self.posedirs @ feat).reshape(-1, 3)
        joints, G = forward_kinematics(R, self.rest_joints(b), self.parents)
        return v, joints, G

    def vertices(self, shape=None, pose=None) -> np.ndarray:
        v, _, G = self._pose(shape, pose)
        return skin(v, self.weights, G)

    def joints(self, shape=None, pose=None) -> np.ndarray:
        b = self.betas(shape)
        joints, _ = forward_kinematics(self.rotations(pose), self.rest_joints(b), self.parents)
        return joints

    def landmark_position(self, name: str, vertices: np.ndarray) -> np.ndarray:
        if not self.landmarks:
            raise BodyError(
                f"{self.name}: landmarks are not known for this topology "
                f"({self.n_vertices} vertices, {len(self.joint_names)} joints); they are defined "
                f"for the SMPL topology ({SMPL_N_VERTICES} vertices, 24 joints) only"
            )
        return super().landmark_position(name, vertices)


def _read_pkl(path: Path) -> dict:
    from .unpickle import SparseStandIn, as_array, safe_load

    obj = safe_load(path)
    if not isinstance(obj, dict):
        raise BodyError(f"{path}: expected a dict of arrays in the pickle, got {type(obj).__name__}")
    out = {}
    try:
        for key in REQUIRED_KEYS + ("expr_dirs",):
            if key not in obj:
                continue
            val = obj[key]
            if key == "J_regressor" and isinstance(val, SparseStandIn):
                out[key] = val.to_scipy()
            else:
                out[key] = as_array(val, key)
    except BodyError as exc:
        raise BodyError(f"{path}: {exc}") from None
    return out


def load_smpl(path, name: Optional[str] = None) -> SMPLBody:
    """Load an SMPL / SMPL+H / SMPL-X model file (``.npz`` or ``.pkl``) as a body.

    Parameters
    ----------
    path : path to the model file (keys v_template, shapedirs, posedirs,
        J_regressor, weights, kintree_table, f).
    name : model name; default the file stem.

    Raises
    ------
    BodyError : unreadable file, a refused pickle, a missing key (named) or a
        badly shaped array.
    """
    path = Path(path)
    if not path.is_file():
        raise BodyError(f"SMPL model file not found: {path}")
    suffix = path.suffix.lower()
    if suffix == ".npz":
        from .arrays import read_npz

        arrays = read_npz(path, REQUIRED_KEYS + ("expr_dirs",), what="SMPL model .npz")
    elif suffix in (".pkl", ".pickle"):
        arrays = _read_pkl(path)
    else:
        raise BodyError(f"{path}: SMPL model files must be .npz or .pkl, got {suffix or 'no suffix'!r}")
    for key in REQUIRED_KEYS:
        if key not in arrays:
            raise BodyError(f"{path}: missing key {key!r} (an SMPL model file needs {', '.join(REQUIRED_KEYS)})")
    return SMPLBody(arrays, name=name or path.stem, source=str(path))
