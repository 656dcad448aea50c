"""Linear blend skinning on plain numpy arrays.

Shared by every skinned body model (SMPL/SMPL-X, skinned OBJ templates, Anny).
A skeleton is a ``parents`` array (J,) with ``parents[0] == -1`` and every
parent listed before its children; rotations are local (relative to the
parent), as axis-angle vectors or 3x3 matrices.
"""

from __future__ import annotations

import numpy as np

from ..errors import BodyError


def rodrigues(axis_angle: np.ndarray) -> np.ndarray:
    """Rotation matrices from axis-angle vectors.

    Parameters
    ----------
    axis_angle : (..., 3) float, rotation axis times angle in radians.

    Returns
    -------
    (..., 3, 3) float rotation matrices.
    """
    aa = np.asarray(axis_angle, dtype=float)
    theta = np.linalg.norm(aa, axis=-1, keepdims=True)
    # Small angles: the axis is ill-defined but R -> I + [aa]x, so any axis works.
    safe = np.where(theta < 1e-12, 1.0, theta)
    k = aa / safe
    kx, ky, kz = k[..., 0], k[..., 1], k[..., 2]
    zero = np.zeros_like(kx)
    K = np.stack([zero, -kz, ky, kz, zero, -kx, -ky, kx, zero], axis=-1).reshape(aa.shape[:-1] + (3, 3))
    s = np.sin(theta)[..., None]
    c = np.cos(theta)[..., None]
    eye = np.broadcast_to(np.eye(3), K.shape)
    return eye + s * K + (1.0 - c) * (K @ K)


def check_parents(parents: np.ndarray) -> np.ndarray:
    """Validate a kinematic tree: (J,) int, root -1, parents before children."""
    parents = np.asarray(parents).astype(np.int64)
    if parents.ndim != 1 or parents.size == 0:
        raise BodyError(f"skeleton parents must be a non-empty (J,) array, got shape {parents.shape}")
    if parents[0] != -1:
        raise BodyError(f"skeleton root (joint 0) must have parent -1, got {parents[0]}")
    idx = np.arange(parents.size)
    bad = np.nonzero((parents[1:] < 0) | (parents[1:] >= idx[1:]))[0]
    if bad.size:
        j = int(bad[0]) + 1
        raise BodyError(f"skeleton joint {j} has parent {int(parents[j])}; every parent must be a lower-numbered joint")
    return parents


def forward_kinematics(rotations: np.ndarray, rest_joints: np.ndarray, parents: np.ndarray):
    """Pose a skeleton.

    Parameters
    ----------
    rotations : (J, 3, 3) local joint rotations.
    rest_joints : (J, 3) joint positions in the rest pose, metres.
    parents : (J,) int, ``-1`` for the root; parents precede children.

    Returns
    -------
    posed_joints : (J, 3) posed joint positions.
    skinning : (J, 4, 4) transforms taking a rest-pose point to its posed
        position if rigidly attached to each joint (world transform with the
        rest joint position removed), for :func:`skin`.
    """
    R = np.asarray(rotations, dtype=float)
    t = np.asarray(rest_joints, dtype=float)
    J = t.shape[0]
    world = np.zeros((J, 4, 4))
    for j in range(J):
        local = np.eye(4)
        local[:3, :3] = R[j]
        p = parents[j]
        local[:3, 3] = t[j] - (t[p] if p >= 0 else 0.0)
        world[j] = local if p < 0 else world[p] @ local
    posed = world[:, :3, 3].copy()
    skinning = world.copy()
    # Remove the rest position: G_j = W_j * T(-t_j).
    skinning[:, :3, 3] -= np.einsum("jab,jb->ja", world[:, :3, :3], t)
    return posed, skinning


def skin(vertices: np.ndarray, weights: np.ndarray, skinning: np.ndarray) -> np.ndarray:
    """Linear blend skinning.

    Parameters
    ----------
    vertices : (V, 3) rest-pose vertices (after shape and pose correctives).
    weights : (V, J) skinning weights, rows summing to 1; dense or scipy.sparse.
    skinning : (J, 4, 4) transforms from :func:`forward_kinematics`.

    Returns
    -------
    (V, 3) skinned vertices.
    """
    G = skinning.reshape(skinning.shape[0], 16)
    T = (weights @ G).reshape(-1, 4, 4)
    v = np.asarray(vertices, dtype=float)
    return np.einsum("vab,vb->va", T[:, :3, :3], v) + T[:, :3, 3]


def pose_feature(rotations: np.ndarray) -> np.ndarray:
    """SMPL pose-corrective feature: flattened ``R_j - I`` of every non-root joint.

    Parameters
    ----------
    rotations : (J, 3, 3) local rotations.

    Returns
    -------
    (9 * (J - 1),) float.
    """
    R = np.asarray(rotations, dtype=float)
    return (R[1:] - np.eye(3)).reshape(-1)


def bone_tails(heads: np.ndarray, parents: np.ndarray, min_length: float = 0.005, stub: float = 0.03) -> np.ndarray:
    """A bone's tail per joint, for a rig drawn from joint positions (a bone's head is its joint).

    Parameters
    ----------
    heads : (J, 3) float, the joints' positions (metres).
    parents : (J,) int, the kinematic tree (root -1, parents before children; see :func:`check_parents`).
    min_length : a child closer than this (metres) to its joint does not give the bone its direction.
    stub : the length (metres) of a bone with no such child.

    Returns
    -------
    (J, 3) float: a joint's tail is its first child's joint farther than ``min_length`` (the
    limb's direction); else (an end joint) ``stub`` along its parent's bone, the root's (or a
    joint on its parent) ``stub`` up +z.
    """
    heads = np.asarray(heads, dtype=float)
    parents = check_parents(parents)
    if heads.shape != (len(parents), 3):
        raise BodyError(f"bone_tails: heads has shape {heads.shape}, expected ({len(parents)}, 3)")
    up = np.array([0.0, 0.0, 1.0])
    tails = np.empty_like(heads)
    children: dict = {}
    for j, p in enumerate(parents):
        if p >= 0:
            children.setdefault(int(p), []).append(j)
    for j in range(len(heads)):
        kids = [c for c in children.get(j, []) if np.linalg.norm(heads[c] - heads[j]) > min_length]
        if kids:
            tails[j] = heads[kids[0]]
            continue
        p = parents[j]
        d = heads[j] - heads[p] if p >= 0 else up
        n = np.linalg.norm(d)
        tails[j] = heads[j] + stub * (d / n if n > 1e-6 else up)
    return tails
