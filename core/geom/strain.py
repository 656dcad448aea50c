"""Per-triangle strain of a flat pattern on a body: Jacobians, weft/warp scales, shear.

A triangle with 2D pattern corners ``U`` (metres of cloth) and 3D corners
``X`` on a body instance (metres) has the affine 2D->3D map with Jacobian
``J = [x1-x0, x2-x0] [u1-u0, u2-u0]^-1`` (3x2). With the piece's grain ``g``
(unit 2D warp) and weft ``w = rot90(g)``: the achieved weft scale (cloth per
body length along the weft) is ``1/|J w|``, the warp scale ``1/|J g|``, the
shear ``|angle(J w, J g) - 90|`` degrees.

The optimizer works with the same quantities through per-triangle gradient
operators ``G`` (f, 3, 2) of a reference flattening: ``X_t^T G_t`` is the
Jacobian of any per-vertex map from that flattening (:func:`gradient_jacobians`),
:func:`intrinsic_offsets` gives the 3D weft/warp offsets in a 2D tangent frame,
and :func:`scales_of_offsets` the weft/warp scales of a pattern from both.
"""

from __future__ import annotations

from typing import List, Sequence, Tuple

import numpy as np

from .mesh import row_cross, row_dot, row_norm
from .svd2 import hypot


def weft_of(grain: np.ndarray) -> np.ndarray:
    """The 2D weft (2,): the grain (2,) turned by +90 degrees."""
    g = np.asarray(grain, float)
    return np.array([-g[1], g[0]])


def jacobians(uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Per-triangle 2D->3D Jacobians.

    Parameters
    ----------
    uv : (n, 2) float, pattern positions, metres.
    xyz : (n, 3) float, the same vertices on a body, metres.
    faces : (f, 3) int.

    Returns
    -------
    (f, 3, 2) float, dimensionless; NaN for degenerate 2D triangles.
    """
    uv = np.asarray(uv, float)
    xyz = np.asarray(xyz, float)
    F = np.asarray(faces, int)
    u0, x0 = uv[F[:, 0]], xyz[F[:, 0]]
    e1, e2 = uv[F[:, 1]] - u0, uv[F[:, 2]] - u0  # the 2D edges: D2's columns
    d1, d2 = xyz[F[:, 1]] - x0, xyz[F[:, 2]] - x0  # the 3D edges: D3's columns
    det = e1[:, 0] * e2[:, 1] - e2[:, 0] * e1[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        i00, i01, i10, i11 = e2[:, 1] / det, -e2[:, 0] / det, -e1[:, 1] / det, e1[:, 0] / det
    # D3 D2^-1 written out: numpy's matmul on (f, 3, 2) stacks calls BLAS once per triangle
    # (~10x slower) and its fused multiply-adds make the last bit depend on the CPU
    J = np.empty((len(F), 3, 2))
    J[:, :, 0] = d1 * i00[:, None] + d2 * i10[:, None]
    J[:, :, 1] = d1 * i01[:, None] + d2 * i11[:, None]
    return J


def scales(
    uv: np.ndarray, xyz: np.ndarray, faces: np.ndarray, grain: np.ndarray
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Achieved weft/warp scales and shear per triangle.

    Parameters
    ----------
    uv : (n, 2) float, pattern positions, metres.
    xyz : (n, 3) float, body positions, metres.
    faces : (f, 3) int.
    grain : (2,) float, the piece's warp direction in the pattern (normalised here).

    Returns
    -------
    rho_weft, rho_warp : (f,) float, ``1/|J w|`` and ``1/|J g|`` (cloth length per body length).
    shear_deg : (f,) float, ``|angle(J w, J g) - 90|`` in degrees.
    """
    J = jacobians(uv, xyz, faces)
    g = np.asarray(grain, float) / np.linalg.norm(grain)
    w = weft_of(g)
    jw = J[:, :, 0] * w[0] + J[:, :, 1] * w[1]  # J w and J g written out (see jacobians)
    jg = J[:, :, 0] * g[0] + J[:, :, 1] * g[1]
    lw, lg = row_norm(jw), row_norm(jg)
    with np.errstate(divide="ignore", invalid="ignore"):
        cosang = row_dot(jw, jg) / (lw * lg)
        shear = np.abs(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))) - 90.0)
        return 1.0 / lw, 1.0 / lg, shear


def gradient_jacobians(corners: np.ndarray, G: np.ndarray) -> np.ndarray:
    """``corners[t]^T G[t]`` per triangle: the Jacobian of a per-vertex map w.r.t. the domain of ``G``.

    Parameters
    ----------
    corners : (f, 3, d) float, the map's values at each triangle's corners (3D body
        positions, or 2D pattern positions).
    G : (f, 3, 2) float, gradient operators of the reference flattening (per
        unit step along its x and y).

    Returns
    -------
    (f, d, 2) float; column 0 is the image of a unit weft step, column 1 of a warp step.
    """
    # explicit sums, one (f,) column at a time: several times faster than einsum/matmul on (f, 3, d) stacks,
    # and 4x faster than the same sums broadcast over the short (d, 2) axes (the same bits)
    out = np.empty((len(G), corners.shape[2], 2))
    for d in range(corners.shape[2]):
        for j in range(2):
            out[:, d, j] = corners[:, 0, d] * G[:, 0, j] + corners[:, 1, d] * G[:, 1, j] + corners[:, 2, d] * G[:, 2, j]
    return out


def intrinsic_offsets(corners: np.ndarray, G: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """3D weft/warp offsets of a unit step in the flattening, and their intrinsic 2D coordinates.

    Parameters
    ----------
    corners : (f, 3, 3) float, triangle vertex positions on a body instance, metres.
    G : (f, 3, 2) float, gradient operators of the flattening.

    Returns
    -------
    K : (f, 2, 2) float, columns: the weft and warp offsets in an orthonormal tangent
        frame whose second axis is the warp offset (lower-triangular), metres per metre.
    len_weft, len_warp : (f,) float, the offsets' 3D lengths |sigma_3D|.
    """
    S = gradient_jacobians(corners, G)  # (f, 3, 2)
    sw, sg = S[:, :, 0], S[:, :, 1]
    lw, lg = row_norm(sw), row_norm(sg)
    safe = np.where(lg > 0, lg, 1.0)
    along = row_dot(sw, sg) / safe
    across = row_norm(row_cross(sw, sg)) / safe
    K = np.zeros((len(G), 2, 2))
    K[:, 0, 0] = across
    K[:, 1, 0] = along
    K[:, 1, 1] = lg
    return K, lw, lg


def components(A: np.ndarray) -> List[np.ndarray]:
    """A (f, 2, 2) as 4 contiguous (f,) arrays a00, a01, a10, a11 (fast element-wise 2x2 algebra)."""
    return [np.ascontiguousarray(A[:, i, j]) for i in range(2) for j in range(2)]


def scales_of_offsets(M: Sequence[np.ndarray], K: Sequence[np.ndarray]) -> Tuple[np.ndarray, np.ndarray]:
    """Weft and warp scales of pattern Jacobians ``M`` on a body with intrinsic offsets ``K``.

    Parameters
    ----------
    M : 4 (f,) arrays m00, m01, m10, m11, the pattern's Jacobian w.r.t. the flattening
        (pattern axis ``i`` along flattening axis ``j``).
    K : 4 (f,) arrays, :func:`intrinsic_offsets`' ``K`` as :func:`components`.

    Returns
    -------
    rho_weft, rho_warp : (f,) float, as :func:`scales` with grain +y: the 2D->3D map is
        ``J = Q K M^-1`` (Q orthonormal), so ``|J w| = |K M^-1 e_x|`` and ``|J g| = |K M^-1 e_y|``.
    """
    # each difference formed in its own new array, the temporaries reused (out=): the same operations
    t = M[1] * M[2]
    det = M[0] * M[3]
    det -= t
    np.abs(det, out=det)
    # det M^-1 e_x = (m11, -m10), det M^-1 e_y = (-m01, m00); the signs folded into the sums (a + (-b) is a - b)
    out = []
    with np.errstate(divide="ignore", invalid="ignore"):
        # weft: |(k0 m11 - k1 m10, k2 m11 - k3 m10)|; warp: |(k1 m00 - k0 m01, k3 m00 - k2 m01)|
        for (ka, kb, kc, kd), (m, n) in (((0, 1, 2, 3), (3, 2)), ((1, 0, 3, 2), (0, 1))):
            x = K[ka] * M[m]
            x -= np.multiply(K[kb], M[n], out=t)
            y = K[kc] * M[m]
            y -= np.multiply(K[kd], M[n], out=t)
            out.append(np.divide(det, hypot(x, y), out=x))
    return out[0], out[1]
