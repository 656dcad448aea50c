"""Stretch of the cloth relative to its pattern: per triangle and per vertex (plain numpy)."""

from __future__ import annotations

import numpy as np

from .mesh import Cloth


def face_deformation(x: np.ndarray, faces: np.ndarray, rest_inv: np.ndarray) -> np.ndarray:
    """Deformation gradients of the triangles.

    Parameters
    ----------
    x : (P, 3) float, positions, metres.
    faces : (T, 3) int.
    rest_inv : (T, 2, 2) float, inverse rest edge matrices in the grain frame (1/m).

    Returns
    -------
    (T, 3, 2) float, F = [x1-x0, x2-x0] rest_inv: columns the weft and warp images.
    """
    ds = np.stack([x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]]], axis=2)
    return ds @ rest_inv


def face_strains(x: np.ndarray, cloth: Cloth) -> tuple:
    """Weft strain, warp strain and shear angle of every cloth triangle.

    Parameters
    ----------
    x : (P, 3) float, particle positions, metres.
    cloth : the welded cloth (its faces and rest matrices).

    Returns
    -------
    weft, warp : (T,) float, |F w| - 1 and |F g| - 1 (fractions, 0 = pattern size).
    shear : (T,) float, degrees, the angle between the weft and warp images minus 90.
    """
    f = face_deformation(x, cloth.faces, cloth.rest_inv)
    a, b = f[:, :, 0], f[:, :, 1]
    la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(la * lb, 1e-30)
    shear = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) - 90.0
    return la - 1.0, lb - 1.0, shear


def vertex_average(values: np.ndarray, faces: np.ndarray, area: np.ndarray, n: int) -> np.ndarray:
    """Area-weighted average of per-face values at the vertices.

    Parameters
    ----------
    values : (T,) float.
    faces : (T, 3) int.
    area : (T,) float, the weights (m^2).
    n : number of vertices.

    Returns
    -------
    (n,) float; 0 at a vertex of no weighted face.
    """
    num = np.zeros(n)
    den = np.zeros(n)
    np.add.at(num, faces.ravel(), np.repeat(values * area, 3))
    np.add.at(den, faces.ravel(), np.repeat(area, 3))
    return num / np.maximum(den, 1e-30)
