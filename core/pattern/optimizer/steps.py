"""The pieces of one local-global iteration, on the stacked panels (:class:`.panels.PanelBlocks`).

- :func:`local_step`: the regulariser's rest shapes (best rotation per triangle, closed form);
  :func:`regulariser_energy`: its energy (a diagnostic).
- :func:`rigid_align`: a step's rigid part removed per panel.
- :func:`flip_guard`: vertices of triangles that would flip step back locally.
- :func:`realign_grain`: every panel turned so its voted grain is +y.
- :func:`scaled_start`: the initial flattening stretched by each panel's mean targets.
- :func:`collapse_guard`: the stiffening of triangles near collapse raised until they open;
  :func:`opened_jacobians`: what they are pulled towards.

Jacobians ``M`` are 4 (f,) arrays m00, m01, m10, m11 (pattern coordinate
``i`` along initial axis ``j``); 2x2 targets likewise (:func:`core.geom.strain.components`).
"""

from __future__ import annotations

from typing import List, Optional, Tuple

import numpy as np

from ...geom.mesh import signed_areas_2d
from ...geom.svd2 import clamp_singular_values_below, hypot, signed_singular_values2
from ..accel import compiled
from ..config import CollapseGuard, SolverConfig
from .panels import PanelBlocks

#: Rounds of local step-halving before a panel takes a uniformly shortened step (flip guard).
GUARD_ROUNDS = 40
#: Halvings of that uniform step before the panel keeps its previous iterate.
GUARD_UNIFORM_ROUNDS = 30
#: Samples of the step fraction along which the guard looks for the first area below the floor.
GUARD_SAMPLES = 32


def turn(P: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Rows of ``P`` (n, 2) turned counter-clockwise by per-row angles with cosines ``c`` and sines ``s``."""
    out = np.empty_like(P)
    out[:, 0] = c * P[:, 0] - s * P[:, 1]
    out[:, 1] = s * P[:, 0] + c * P[:, 1]
    return out


def local_step(config: SolverConfig, M: list, tg: dict, W2: np.ndarray, state: dict) -> Tuple[list, list]:
    """Rest shapes ``D R K'`` of the regulariser (best 2x2 rotations, all triangles at once) and the ease target.

    ``tg``: :func:`core.pattern.optimizer.targets.rest_targets`. ``W2`` (2,): the column
    weights. With ``rest_shape.warp_slack`` the rest shape's warp row is also
    scaled by the best factor ``s`` within ``[1/(1+slack), 1+slack]`` (free
    warp stretch), and so is the ease target; ``s`` alternates with ``R``
    across iterations (kept in ``state``, one per solve, beside the products
    of ``K'`` that do not change while its targets move). Returns (RT, T) as
    component lists.

    The rotation minimises ``|Omega^1/2 (M - D R K') W^1/2|^2`` (``Omega =
    diag(1, warp_row)``): ``f(theta) = -2 (x cos + y sin) + p cos 2theta
    + q sin 2theta + const`` with ``x``, ``y`` the trace and skew parts of
    ``A = D Omega M W K'^T`` and ``p``, ``q`` from ``Delta = (d0^2 - omega d1^2) / 2``
    and ``C = K' W K'^T``. The polar angle of ``A`` is exact when ``Delta`` or
    the anisotropy of ``C`` vanishes; one Newton step refines it otherwise.
    """
    # written as the formula reads; the Warp kernel (accel.kernels.local_step8) computes the same
    # expressions in the same order, so both paths give the same bits
    rest = config.rest_shape
    d0, d1, k = tg["reg"]
    T = tg["T"]
    kp = state.get("_kprod")
    if kp is None or kp[0] is not k or not np.array_equal(kp[1], W2):
        kp = (
            k,
            W2.copy(),
            W2[0] * k[0] ** 2 + W2[1] * k[1] ** 2 - W2[0] * k[2] ** 2 - W2[1] * k[3] ** 2,
            W2[0] * k[0] * k[2] + W2[1] * k[1] * k[3],
        )
        state["_kprod"] = kp
    Cdiff, C01 = kp[2], kp[3]
    free = rest.warp_slack > 0
    sw = state.get("sw") if free else None
    lo, hi = (1.0 / (1.0 + rest.warp_slack), 1.0 + rest.warp_slack) if free else (1.0, 1.0)
    if W2[0] == 1.0 and W2[1] == 1.0:
        done = compiled.local_step(M, d0, d1, k, (Cdiff, C01), T, sw, rest.warp_row, free, lo, hi)
        if done is not None:
            if free:
                state["sw"] = done[2]
            return done[0], done[1]
    dw = d1 if sw is None else d1 * sw
    om = rest.warp_row
    m0, m1, m2, m3 = M if (W2[0] == 1.0 and W2[1] == 1.0) else (W2[0] * M[0], W2[1] * M[1], W2[0] * M[2], W2[1] * M[3])
    omdw = om * dw
    # x, y: the trace and skew parts of A = D Omega M W K'^T; the best angle without anisotropy
    x = d0 * (m0 * k[0] + m1 * k[1]) + omdw * (m2 * k[2] + m3 * k[3])
    y = (m2 * k[0] + m3 * k[1]) * omdw - d0 * (m0 * k[2] + m1 * k[3])
    r = hypot(x, y)
    ok = r > 0
    if ok.all():
        c, sn = x / r, y / r
    else:  # A = 0: no rotation to find (the identity)
        rs = np.where(ok, r, 1.0)
        c, sn = np.where(ok, x / rs, 1.0), np.where(ok, y / rs, 0.0)
    delta = (d0 * d0 - omdw * dw) * 0.5
    if delta.any():
        # one Newton step on f(theta) from the polar angle: f' = g1, f'' = g2 at theta
        p = delta * Cdiff
        q = -2.0 * delta * C01
        c2 = c * c - sn * sn  # cos 2 theta
        s2 = 2.0 * c * sn  # sin 2 theta
        g1 = (x * sn - y * c) * 2.0 - 2.0 * p * s2 + 2.0 * q * c2
        g2 = 2.0 * r - 4.0 * p * c2 - 4.0 * q * s2
        pos = g2 > 0
        step = -g1 / g2 if pos.all() else np.where(pos, -g1 / np.where(pos, g2, 1.0), 0.0)
        nrm = np.sqrt(step * step + 1.0)  # the angle's tangent step, back on the circle
        c, sn = (c - sn * step) / nrm, (c * step + sn) / nrm
    rk = [c * k[0] - sn * k[2], c * k[1] - sn * k[3], sn * k[0] + c * k[2], sn * k[1] + c * k[3]]  # R K'
    if free:
        p0, p1 = d1 * rk[2], d1 * rk[3]
        num = m2 * p0
        num += m3 * p1
        unit = W2[0] == 1.0 and W2[1] == 1.0  # products by 1 skipped: the same values
        den = p0 * p0 if unit else W2[0] * p0 * p0
        den += p1 * p1 if unit else W2[1] * p1 * p1
        sw = np.clip(num / np.maximum(den, 1e-300, out=den), lo, hi, out=num)
        state["sw"] = sw
        d1sw = d1 * sw
        RT = [d0 * rk[0], d0 * rk[1], np.multiply(d1sw, rk[2], out=rk[2]), np.multiply(d1sw, rk[3], out=rk[3])]
        num = m2 * T[2]
        num += m3 * T[3]
        # the ease target's warp row changes only with the warp targets: its weighted square, kept while it stays
        tden = state.get("_tden")
        if tden is None or tden[0] is not T[2] or tden[1] is not T[3] or not np.array_equal(tden[2], W2):
            den = T[2] ** 2 if unit else W2[0] * T[2] ** 2
            den += T[3] ** 2 if unit else W2[1] * T[3] ** 2
            tden = state["_tden"] = (T[2], T[3], W2.copy(), np.maximum(den, 1e-300, out=den))
        se = np.clip(num / tden[3], lo, hi, out=num)
        return RT, [T[0], T[1], T[2] * se, T[3] * se]
    return [d0 * rk[0], d0 * rk[1], d1 * rk[2], d1 * rk[3]], T


def rhs_terms(RT: list, T: list, lam_reg: float, lam_ease: float) -> list:
    """The triangles' right-hand side terms ``B = lambda_reg R T + lambda_ease T`` (4 (f,) arrays; one
    right-hand side for the regulariser and the ease term, which have the same weights) of the rest
    shapes ``RT`` and the ease targets ``T`` (4 (f,) each; ``RT``'s arrays may be reused)."""
    B = compiled.rhs_terms(RT, T, lam_reg, lam_ease)
    if B is not None:
        return B
    B = [RT[j] if lam_reg == 1.0 else np.multiply(lam_reg, RT[j], out=RT[j]) for j in range(4)]
    for j in range(4):
        B[j] += lam_ease * T[j]  # x + y is y + x: the same sums
    return B


def regulariser_energy(a: np.ndarray, M: list, RT: list, W2: np.ndarray) -> float:
    """The regulariser's energy (a diagnostic): ``sum_t a_t |(M_t - R_t T_t) W|^2`` of the Jacobians ``M``
    and the rest shapes ``RT`` (4 (f,) arrays each), area weights ``a`` (f,) and column weights ``W2``
    (2,); one dot product per entry."""
    energy = 0.0
    for j in range(4):
        r = M[j] - RT[j]
        # einsum's own loop, not BLAS: OpenBLAS splits a dot of > 10k values over threads that
        # then spin ~0.1 s each (in a plain process ~90 ms of CPU a shirt transfer, no time saved)
        energy += W2[j % 2] * float(np.einsum("i,i->", a, np.multiply(r, r, out=r)))
    return energy


def rigid_align(blocks: PanelBlocks, U_new: np.ndarray, U_old: np.ndarray) -> np.ndarray:
    """``U_new`` (n, 2) moved rigidly per panel onto ``U_old`` (area-free Kabsch, all panels at once)."""
    off, cnt = blocks.vertex_offsets, blocks.vertex_counts[:, None]
    co, cn = np.add.reduceat(U_old, off) / cnt, np.add.reduceat(U_new, off) / cnt
    rep = blocks.per_vertex
    Pc, Qc = U_old - rep(co), U_new - rep(cn)
    # H = Qc^T Pc per panel, entries (q0 p0, q0 p1, q1 p0, q1 p1): one outer product per vertex, written a
    # column at a time (the same products; broadcast over the 2 x 2 axes they cost ~2x the whole fit)
    outer = np.empty((len(Qc), 4))
    for j in range(4):
        np.multiply(Qc[:, j // 2], Pc[:, j % 2], out=outer[:, j])
    h = np.add.reduceat(outer, off)
    th = np.arctan2(h[:, 1] - h[:, 2], h[:, 0] + h[:, 3])
    return turn(Qc, rep(np.cos(th)), rep(np.sin(th))) + rep(co)


def face_areas(blocks: PanelBlocks, U: np.ndarray, faces: Optional[np.ndarray] = None) -> np.ndarray:
    """Signed 2D areas of all triangles (or of ``faces``), as :func:`core.geom.mesh.signed_areas_2d`,
    on the cached face columns."""
    F0, F1, F2 = blocks.face_columns if faces is None else (c[faces] for c in blocks.face_columns)
    u, v = U[:, 0], U[:, 1]
    u0, v0 = u[F0], v[F0]
    # 0.5 (ax by - ay bx) with ax = u[F1] - u0 etc., each product into its gathered operand (the same operations)
    ax, ay, bx, by = u[F1], v[F1], u[F2], v[F2]
    ax -= u0
    ay -= v0
    bx -= u0
    by -= v0
    ax *= by
    ay *= bx
    ax -= ay
    ax *= 0.5
    return ax


def flip_guard(blocks: PanelBlocks, U_old: np.ndarray, U_new: np.ndarray, s_old: Optional[np.ndarray] = None):
    """Keep the step flip-free: vertices of triangles that would flip step back locally.

    Every vertex starts with the full step; the step of the vertices of
    each triangle that would flip (or lose more than half its area when
    already near-degenerate) is cut, and only the triangles around the
    moved vertices are checked again. As a vertex's step goes to 0 it
    returns to the previous, flip-free iterate, so this terminates; a
    panel not fixed in :data:`GUARD_ROUNDS` rounds takes a uniformly
    shortened step instead (or keeps its previous iterate).
    ``s_old``: the signed areas of ``U_old`` when known (they survive
    rigid motions, so each iteration passes on its own).
    Returns (U, number of halvings, signed areas of U or None).
    """
    F = blocks.faces
    n = blocks.n
    checked = None if s_old is None else compiled.flip_check(blocks, U_new, s_old)
    if checked is not None and checked[1] == 0:
        return U_new.copy(), 0, checked[0]
    if s_old is None:
        s_old = face_areas(blocks, U_old)
    floor = np.minimum(blocks.area_floor, 0.5 * s_old)
    # most iterations cut nothing: their areas are checked once (the kernel's, the same bits, when it ran),
    # and the step's differences and the halving state are made only when a triangle needs them
    s_all = face_areas(blocks, U_new) if checked is None else checked[0]
    bad = np.flatnonzero(s_all <= floor)
    if bad.size == 0:
        return U_new.copy(), 0, s_all
    alpha = np.ones(n)
    U = U_new.copy()
    halvings = 0
    faces = None
    D = U_new - U_old
    for _ in range(GUARD_ROUNDS):
        if faces is not None:  # the first round's bad triangles are those found above
            s = face_areas(blocks, U, faces)
            bad = faces[s <= floor[faces]]
            if bad.size == 0:
                return U, halvings, None
        # largest common step fraction t of the bad triangle's vertices (their current
        # fractions scaled by t) keeping its area above the floor: a quadratic in t
        Fb = F[bad]
        P0 = U_old[Fb]
        Dd = alpha[Fb][:, :, None] * D[Fb]
        e1, e2 = P0[:, 1] - P0[:, 0], P0[:, 2] - P0[:, 0]
        f1, f2 = Dd[:, 1] - Dd[:, 0], Dd[:, 2] - Dd[:, 0]
        cr = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        a0 = 0.5 * cr(e1, e2) - floor[bad]
        a1 = 0.5 * (cr(e1, f2) + cr(f1, e2))
        a2 = 0.5 * cr(f1, f2)
        t = np.full(len(bad), 0.5)
        ts = np.linspace(0.0, 1.0, GUARD_SAMPLES + 1)[1:]
        # first sample where the area would reach the floor; step back one sample (robust, vectorised)
        vals = a0[:, None] + a1[:, None] * ts[None, :] + a2[:, None] * ts[None, :] ** 2
        hit = np.argmax(vals <= 0, axis=1)
        has = np.any(vals <= 0, axis=1)
        t[has] = np.where(hit[has] > 0, ts[np.maximum(hit[has] - 1, 0)], 0.0) * 0.9
        verts_t = np.repeat(t, 3)
        vids = Fb.ravel()
        scale = np.ones(n)
        np.minimum.at(scale, vids, np.maximum(verts_t, 0.0))
        verts = np.unique(vids)
        # never stall: every vertex of a bad triangle at least halves its step
        alpha[verts] *= np.minimum(scale[verts], 0.5)
        halvings += 1
        U[verts] = U_old[verts] + alpha[verts, None] * D[verts]
        faces = np.unique(blocks.vertex_faces[verts].indices)
    s = signed_areas_2d(U, F)
    for pd in blocks.panels:
        sl, fs = blocks.panel_slices(pd)
        if not np.any(s[fs] <= floor[fs]):
            continue
        # fall back to a uniform step of the whole panel towards the locally shortened one
        beta, Ul = 0.5, U[sl].copy()
        U[sl] = U_old[sl]
        for _ in range(GUARD_UNIFORM_ROUNDS):
            cand = U_old[sl] + beta * (Ul - U_old[sl])
            halvings += 1
            if np.all(signed_areas_2d(cand, pd.faces) > floor[fs]):
                U[sl] = cand
                break
            beta *= 0.5
    return U, halvings, None


def scaled_start(blocks: PanelBlocks, c_weft: np.ndarray, c_warp: np.ndarray) -> np.ndarray:
    """The initial flattening stretched by each panel's area-weighted mean targets (n, 2).

    A flip-free affine image of a flip-free flattening, already close to a
    uniform-ease solution: the first global steps stay small, so the flip
    guard rarely has to act even at rho = 2.
    """
    U = blocks.uv0.copy()
    for pd in blocks.panels:
        sl, fs = blocks.panel_slices(pd)
        w = np.abs(pd.area0)
        sx = float(np.sum(w * c_weft[fs]) / np.sum(w))
        sy = float(np.sum(w * c_warp[fs]) / np.sum(w))
        c = U[sl].mean(axis=0)
        U[sl] = (U[sl] - c) * np.array([sx, sy]) + c
    return U


def realign_grain(blocks: PanelBlocks, U: np.ndarray, M: List[np.ndarray]):
    """Rotate every panel about its centroid so its area-weighted grain vote is +y.

    ``M``: the Jacobians of ``U``; returns the rotated ``U`` and its
    Jacobians (the same rotation applied to the rows).
    """
    # the temporaries are reused (out=): the same operations in their order, fewer new arrays
    wx, wy = blocks.warp_columns
    votes = compiled.grain_votes(M, wx, wy, blocks.warp_vote)
    if votes is None:
        t = M[1] * wy
        ix = M[0] * wx  # the current 2D image of the warp: M w
        ix += t
        iy = M[2] * wx
        iy += np.multiply(M[3], wy, out=t)
        nrm = hypot(ix, iy)
        # a triangle whose warp image vanished does not vote (every one usually votes: the where() is skipped)
        vote = blocks.warp_vote if (nrm > 0).all() else np.where(nrm > 0, blocks.warp_vote, 0.0)
        w = np.divide(vote, np.maximum(nrm, 1e-300, out=nrm), out=nrm)
        votes = np.multiply(w, ix, out=ix), np.multiply(w, iy, out=iy)
    vx = np.add.reduceat(votes[0], blocks.face_offsets)
    vy = np.add.reduceat(votes[1], blocks.face_offsets)
    theta = -np.where((vx == 0) & (vy == 0), 0.0, np.arctan2(-vx, vy))
    c, sn = np.cos(theta), np.sin(theta)
    rep = blocks.per_vertex
    ctr = rep(np.add.reduceat(U, blocks.vertex_offsets) / blocks.vertex_counts[:, None])
    U = turn(U - ctr, rep(c), rep(sn)) + ctr
    ct, st = np.repeat(c, blocks.face_counts), np.repeat(sn, blocks.face_counts)
    out = compiled.turned(M, ct, st)
    if out is not None:
        return U, out
    # [ct m0 - st m2, ct m1 - st m3, st m0 + ct m2, st m1 + ct m3]
    out, t = [], np.empty_like(ct)
    for x, y, sign in ((0, 2, -1), (1, 3, -1), (0, 2, 1), (1, 3, 1)):
        if sign < 0:
            r = ct * M[x]
            r -= np.multiply(st, M[y], out=t)
        else:
            r = st * M[x]
            r += np.multiply(ct, M[y], out=t)
        out.append(r)
    return U, out


def inverse_offsets(Kc: list):
    """(``K^-1`` as 4 (f,) arrays, the body triangles (f,) bool: ``det K > 0``) of intrinsic offsets
    ``Kc`` (4 (f,) arrays): what :func:`relative_singular_values` divides by, the same for every
    iteration of a solve."""
    det_k = Kc[0] * Kc[3] - Kc[1] * Kc[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = [Kc[3] / det_k, -Kc[1] / det_k, -Kc[2] / det_k, Kc[0] / det_k]
    return inv, det_k > 0


def relative_singular_values(M: list, Kc: list, c_weft: np.ndarray, c_warp: np.ndarray, inverse=None):
    """Singular values (s1 >= |s2|, s2 < 0 when flipped) (f,) of each triangle's Jacobian relative to its
    targets, ``Q = diag(c)^-1 M K^-1`` (1, 1: the targets met; the smaller bounds the weft and warp
    scales from below, as fractions of their targets), and ``Q`` as 4 (f,) arrays.
    ``inverse``: :func:`inverse_offsets` of ``Kc`` when the caller has it."""
    (i00, i01, i10, i11), _ = inverse if inverse is not None else inverse_offsets(Kc)
    q, t = [], np.empty_like(M[0])
    with np.errstate(divide="ignore", invalid="ignore"):
        # q_ij = (M_i0 inv_0j + M_i1 inv_1j) / c_i, each sum formed in its own new array (the same operations)
        for a, b, c in ((M[0], M[1], c_weft), (M[2], M[3], c_warp)):
            for ia, ib in ((i00, i10), (i01, i11)):
                x = a * ia
                x += np.multiply(b, ib, out=t)
                x /= c
                q.append(x)
    s1, s2 = signed_singular_values2(q)
    return s1, s2, q


#: Smallest relative singular value (:func:`relative_singular_values`) of an open triangle: above it
#: the weft and warp scales are at least half their targets and the area a quarter (SPEC collapse).
COLLAPSED_BELOW = 0.5


def any_collapsed(M: list, Kc: list, c_weft: np.ndarray, c_warp: np.ndarray) -> bool:
    """Whether a triangle's smaller relative singular value is under :data:`COLLAPSED_BELOW` (degenerate
    body triangles, with no shape to keep, left out)."""
    inverse = inverse_offsets(Kc)
    _, s2, _ = relative_singular_values(M, Kc, c_weft, c_warp, inverse)
    return bool(np.any(~(s2 >= COLLAPSED_BELOW) & inverse[1]))


def face_neighbourhood(panels, area0: np.ndarray):
    """Area-weighted mean over each triangle's neighbours (f, f) sparse: the triangles sharing a cut
    vertex with it (across seams too: a seam vertex is one cut vertex), rows summing to 1.
    ``panels``: the stacked :class:`~.panels.PanelData`; ``area0`` (f,) their flattening's areas."""
    import scipy.sparse as sp

    ids = np.concatenate([pd.vertex_ids[pd.faces] for pd in panels])
    f = len(ids)
    inc = sp.csr_matrix((np.ones(3 * f), (np.repeat(np.arange(f), 3), ids.ravel())), shape=(f, int(ids.max()) + 1))
    A = (inc @ inc.T).tocsr()
    A.data[:] = 1.0
    A = A @ sp.diags(np.abs(area0))
    return (sp.diags(1.0 / np.asarray(A.sum(axis=1)).ravel()) @ A).tocsr()


def collapse_guard(
    guard: CollapseGuard, M: list, Kc: list, c_weft: np.ndarray, c_warp: np.ndarray, gain: np.ndarray, inverse=None
) -> list:
    """The collapse guard's gains of one iteration (:class:`~core.pattern.config.CollapseGuard`).

    A triangle whose smaller relative singular value
    (:func:`relative_singular_values`) is under ``guard_scale`` has its
    stiffening ``gain`` (f, updated in place) raised by ``guard_grow`` (to at
    least 1, at most ``guard_limit``); one that is open again (at least
    ``guard_open``) gives it back by ``guard_release`` (0 under 1), so guarded
    triangles do not freeze their neighbourhood. Stiffened triangles are
    pulled towards their opened shape (:func:`opened_jacobians`).

    ``inverse``: :func:`inverse_offsets` of ``Kc`` when the caller has it.
    Returns (the relative Jacobians ``Q`` (4 (f,) arrays) the gains were set
    from, the guarded triangles (k,): ``gain > 0`` after the update).
    """
    inverse = inverse if inverse is not None else inverse_offsets(Kc)
    q = compiled.collapse_guard(guard, M, inverse, c_weft, c_warp, gain)
    if q is not None:
        return q, np.flatnonzero(gain > 0)
    s1, s2, q = relative_singular_values(M, Kc, c_weft, c_warp, inverse)
    # a degenerate body triangle has no shape to keep; a non-finite iterate is the flip guard's to refuse
    # (s1 = a + b and s2 = a - b of two hypotenuses: s1 finite makes s2 finite)
    valid = inverse[1] & np.isfinite(s1)
    np.multiply(gain, valid, out=gain)  # 0 where not valid (gains are finite, >= 0)
    low = np.flatnonzero(valid & (s2 < guard.guard_scale))
    if np.any(gain[low] < guard.guard_limit):
        gain[low] = np.minimum(np.maximum(gain[low] * guard.guard_grow, 1.0), guard.guard_limit)
    held = np.flatnonzero(gain > 0)
    free = held[s2[held] >= guard.guard_open]
    if free.size:
        gain[free] *= guard.guard_release
        gain[free[gain[free] < 1.0]] = 0.0
        held = held[gain[held] > 0]
    return q, held


def opened_jacobians(
    guard_open: float, q: list, idx: np.ndarray, Kc: list, c_weft: np.ndarray, c_warp: np.ndarray
) -> list:
    """The Jacobians (4 (k,) arrays) triangles ``idx`` are pulled towards: their relative Jacobians
    ``q`` (:func:`collapse_guard`) with the signed singular values clamped from below at
    ``guard_open`` (rotation and shear kept; a flipped one unfolded), back in pattern terms. A
    triangle already open enough is its own target, so the pull costs nothing there."""
    # closed form: numpy's svd on a few 2x2s costs ms through LAPACK; Z = diag(c) Q' K
    o = clamp_singular_values_below([x[idx] for x in q], guard_open)
    k = [x[idx] for x in Kc]
    cw, cg = c_weft[idx], c_warp[idx]
    return [
        cw * (o[0] * k[0] + o[1] * k[2]),
        cw * (o[0] * k[1] + o[1] * k[3]),
        cg * (o[2] * k[0] + o[3] * k[2]),
        cg * (o[2] * k[1] + o[3] * k[3]),
    ]
