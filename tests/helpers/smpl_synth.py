"""Synthetic SMPL-format models (no tests here): a skinned tube and a 24-joint stick skeleton."""

import numpy as np
from meshes import ring_grid_faces

from core.body.smpl import SMPL_JOINT_NAMES


def tube_model(seed=0, n_ring=8, n_rows=6, J=4, n_betas=3):
    """A small SMPL-format model in SMPL's frame (Y up): a tube along Y, J joints."""
    rng = np.random.default_rng(seed)
    ang = np.linspace(0, 2 * np.pi, n_ring, endpoint=False)
    rows = np.linspace(0.0, 1.0, n_rows)
    v = np.array([[0.1 * np.cos(a), y, 0.1 * np.sin(a)] for y in rows for a in ang])
    faces = ring_grid_faces(n_rows, n_ring)
    V = len(v)
    parents = np.array([-1] + [max(0, j - 1 - (j % 2)) for j in range(1, J)])
    kintree = np.stack([np.where(parents < 0, 4294967295, parents), np.arange(J)]).astype(np.int64)
    weights = rng.random((V, J)) ** 4
    weights /= weights.sum(1, keepdims=True)
    jreg = rng.random((J, V)) * (rng.random((J, V)) < 0.3)
    jreg[:, 0] += 1e-3
    jreg /= jreg.sum(1, keepdims=True)
    return {
        "v_template": v,
        "f": np.array(faces, dtype=np.uint32),
        "weights": weights,
        "kintree_table": kintree,
        "J_regressor": jreg,
        "shapedirs": rng.normal(scale=0.01, size=(V, 3, n_betas)),
        "posedirs": rng.normal(scale=0.01, size=(V, 3, 9 * (J - 1))),
    }


def stick_smpl(n_betas=2):
    """An SMPL-layout skeleton (24 joints, SMPL frame, metres) with one vertex per bone."""
    J = {
        "pelvis": (0, 0.9, 0),
        "left_hip": (0.09, 0.82, 0),
        "right_hip": (-0.09, 0.82, 0),
        "spine1": (0, 1.0, 0),
        "left_knee": (0.1, 0.48, 0),
        "right_knee": (-0.1, 0.48, 0),
        "spine2": (0, 1.12, 0),
        "left_ankle": (0.1, 0.08, 0),
        "right_ankle": (-0.1, 0.08, 0),
        "spine3": (0, 1.2, 0),
        "left_foot": (0.1, 0.02, 0.1),
        "right_foot": (-0.1, 0.02, 0.1),
        "neck": (0, 1.45, 0),
        "left_collar": (0.08, 1.38, 0),
        "right_collar": (-0.08, 1.38, 0),
        "head": (0, 1.55, 0),
        "left_shoulder": (0.18, 1.4, 0),
        "right_shoulder": (-0.18, 1.4, 0),
        "left_elbow": (0.45, 1.4, 0),
        "right_elbow": (-0.45, 1.4, 0),
        "left_wrist": (0.7, 1.4, 0),
        "right_wrist": (-0.7, 1.4, 0),
        "left_hand": (0.78, 1.4, 0),
        "right_hand": (-0.78, 1.4, 0),
    }
    parents = [-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21]
    joints = np.array([J[n] for n in SMPL_JOINT_NAMES], dtype=float)
    # Vertices: each joint position itself, skinned to its parent (so it follows the bone).
    v = joints.copy()
    weights = np.zeros((24, 24))
    for j in range(24):
        weights[j, max(parents[j], 0)] = 1.0
    return {
        "v_template": v,
        "f": np.array([[0, 1, 2], [3, 4, 5]]),
        "weights": weights,
        "kintree_table": np.array([[4294967295] + parents[1:], list(range(24))], dtype=np.int64),
        "J_regressor": np.eye(24),
        "shapedirs": np.zeros((24, 3, n_betas)),
        "posedirs": np.zeros((24, 3, 207)),
    }
