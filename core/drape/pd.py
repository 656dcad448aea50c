"""The drape's implicit step by projective dynamics: a global solve, so the fabric's stiffness holds.

Each substep minimises the implicit-Euler incremental potential

    G(x) = sum_i m_i / (2 dt^2) |x_i - y_i|^2 + E(x),   y = x + dt v + dt^2 g,

with E the energy the XPBD constraints stand for, in the preset's physical units
(:mod:`core.drape.vbd` lists it: weft / warp springs along the grain, shear, the
dihedral bending with weight |e|^2 / (A_a + A_b), the edge springs), by the
iteration

    x <- x - A^-1 grad G(x),

where A is a constant matrix, prefactored once (Bouaziz et al., "Projective
Dynamics", ACM TOG 33(4), 2014; Liu, Bouaziz, Kavan, "Quasi-Newton methods for
real-time simulation of hyperelastic materials", ACM TOG 36(3), 2017): the
masses over dt^2, the projective-dynamics matrices of the grain springs
(k A G^T G, for which the step is exactly the local-global iteration and never
increases G), and the flat-hinge Gauss-Newton matrix of the bending. One solve
moves the whole cloth, so a stretch or a hoop compression is corrected across
the sheet in one iteration, where a Gauss-Seidel pass (XPBD, VBD) moves it one
ring of triangles: the delivered stiffness is the preset's, not 1 / (1/k + dt^2
sum w |grad C|^2). Iterations stop when no particle moved more than
``tolerance`` (a residual-based stop) or after ``iterations``.

The matrix couples only the three coordinates' scalar pattern (A = L (x) I3), so
one sparse LU of the free particles' L serves x, y and z. Body contact (the
closest-point planes of :func:`core.drape.kernels.closest_contact`) is a
projection after every iteration; friction, tethers, self-collision and the
velocities are the Warp kernels the other solvers use. Plain numpy / scipy on
the host (float64).
"""

from __future__ import annotations

import numpy as np

from .mesh import Cloth


def _rows(n_rows: int, n_cols: int, cols: np.ndarray, vals: np.ndarray):
    """A sparse (n_rows, n_cols) CSR matrix with row r holding ``vals[r]`` at ``cols[r]``."""
    from scipy.sparse import csr_matrix

    k = cols.shape[1] if cols.ndim == 2 else 0
    return csr_matrix(
        (vals.reshape(-1), (np.repeat(np.arange(n_rows), k), cols.reshape(-1))),
        shape=(n_rows, n_cols),
    )


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product (n, 3) (np.cross is several times slower on small rows)."""
    out = np.empty_like(a)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def hinge_gradients(x: np.ndarray, bends: np.ndarray) -> tuple:
    """Signed dihedral angles (B,) and their gradients (B, 4, 3) at the stencils (a, b, e0, e1)
    (Bridson et al. 2003; the convention of :func:`core.drape.mesh.dihedral_angles`); zero where degenerate."""
    x1, x2, x3, x4 = (x[bends[:, k]] for k in range(4))
    n1 = _cross(x3 - x1, x4 - x1)
    n2 = _cross(x4 - x2, x3 - x2)
    e = x4 - x3
    l1 = np.einsum("ij,ij->i", n1, n1)
    l2 = np.einsum("ij,ij->i", n2, n2)
    le = np.linalg.norm(e, axis=1)
    ok = (l1 > 1e-20) & (l2 > 1e-20) & (le > 1e-10)
    l1, l2, le = np.where(ok, l1, 1.0), np.where(ok, l2, 1.0), np.where(ok, le, 1.0)
    eh = e / le[:, None]
    n1h, n2h = n1 / np.sqrt(l1)[:, None], n2 / np.sqrt(l2)[:, None]
    theta = np.arctan2(np.einsum("ij,ij->i", _cross(n1h, n2h), eh), np.einsum("ij,ij->i", n1h, n2h))
    a1, a2 = n1 / l1[:, None], n2 / l2[:, None]
    g = np.stack(
        [
            -a1 * le[:, None],
            -a2 * le[:, None],
            a1 * np.einsum("ij,ij->i", x4 - x1, eh)[:, None] + a2 * np.einsum("ij,ij->i", x4 - x2, eh)[:, None],
            a1 * np.einsum("ij,ij->i", x1 - x3, eh)[:, None] + a2 * np.einsum("ij,ij->i", x2 - x3, eh)[:, None],
        ],
        axis=1,
    )
    g[~ok] = 0.0
    return np.where(ok, theta, 0.0), g


class ProjectiveStep:
    """The host-side implicit step of one cloth: constant matrices, the prefactored solve.

    Parameters
    ----------
    cloth : the welded cloth.
    material : its :class:`core.drape.materials.Material`.
    dt : the substep (s).
    mass : (P,) particle masses (kg).
    start_stretch : (T, 2) the skintight start's weft / warp stretch of every triangle (the rest
        stretch grows from it to 1); edge_start : (E,) the start lengths of the edges.
    """

    def __init__(self, cloth: Cloth, material, dt: float, mass: np.ndarray, start_stretch, edge_start):
        from scipy.sparse import diags
        from scipy.sparse.linalg import splu

        n = cloth.n_particles
        self.n = n
        self.free = ~np.asarray(cloth.pinned, bool)
        good = ~cloth.sliver if len(cloth.sliver) else np.ones(len(cloth.faces), bool)
        tri, d = cloth.faces[good], cloth.rest_inv[good]
        area = cloth.rest_area[good]
        self.stretch0 = np.asarray(start_stretch, float)[good]
        ca = np.stack([-(d[:, 0, 0] + d[:, 1, 0]), d[:, 0, 0], d[:, 1, 0]], axis=1)
        cb = np.stack([-(d[:, 0, 1] + d[:, 1, 1]), d[:, 0, 1], d[:, 1, 1]], axis=1)
        t = len(tri)
        self.Ga, self.Gb = _rows(t, n, tri, ca), _rows(t, n, tri, cb)
        self.wa, self.wb = material.stretch_weft * area, material.stretch_warp * area
        self.ws = material.shear * area
        e = cloth.edges.reshape(-1, 2)
        self.Ge = _rows(len(e), n, e, np.tile([-1.0, 1.0], (len(e), 1)))
        self.we = 0.5 * (material.stretch_weft + material.stretch_warp)
        self.edge_rest = np.asarray(cloth.edge_rest, float)
        self.edge_start = np.asarray(edge_start, float)
        self.bends = cloth.bends.reshape(-1, 4)
        self.kb = material.bending * cloth.bend_weight
        self.bend_rest = np.asarray(cloth.bend_rest, float)
        # scatter of the hinges' four gradients onto their particles
        nb = len(self.bends)
        self.S = _rows(4 * nb, n, self.bends.reshape(-1, 1), np.ones((4 * nb, 1))).T.tocsr()
        self.inertia = mass / (dt * dt)
        # the flat-hinge Gauss-Newton matrix: each gradient's component along the hinge's mean normal
        if len(self.bends) and material.bending > 0:
            _, g0 = hinge_gradients(cloth.x0, self.bends)
            x1, x2, x3, x4 = (cloth.x0[self.bends[:, k]] for k in range(4))
            nrm = _cross(x3 - x1, x4 - x1) + _cross(x4 - x2, x3 - x2)
            nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-30)
            c = np.einsum("bkj,bj->bk", g0, nrm)
            B = _rows(len(self.bends), n, self.bends, c)
            bend_m = B.T @ diags(self.kb) @ B
        else:
            bend_m = 0.0
        L = (
            diags(self.inertia)
            + self.Ga.T @ diags(self.wa + self.ws) @ self.Ga
            + self.Gb.T @ diags(self.wb + self.ws) @ self.Gb
            + self.we * (self.Ge.T @ self.Ge)
            + bend_m
        )
        fi = np.nonzero(self.free)[0]
        self.free_idx = fi
        self.lu = splu(L.tocsc()[fi][:, fi].tocsc(), permc_spec="MMD_AT_PLUS_A") if len(fi) else None

    def gradient(self, x: np.ndarray, y: np.ndarray, grow: float) -> np.ndarray:
        """grad G (P, 3) at ``x`` in float64 (float32 positions put a strain noise of ~1e-6 on a 1 cm
        edge, a force of ~30 % of a particle's weight in a 3000 N/m fabric): inertia, grain springs,
        shear, edge springs, bending."""
        g = self.inertia[:, None] * (x - y)
        back = 1.0 - grow
        ra = 1.0 + (self.stretch0[:, 0] - 1.0) * back
        rb = 1.0 + (self.stretch0[:, 1] - 1.0) * back
        fa, fb = self.Ga @ x, self.Gb @ x
        la = np.maximum(np.sqrt(np.einsum("ij,ij->i", fa, fa)), 1e-12)
        lb = np.maximum(np.sqrt(np.einsum("ij,ij->i", fb, fb)), 1e-12)
        s = self.ws * np.einsum("ij,ij->i", fa, fb)
        ta = (self.wa * (1.0 - ra / la))[:, None] * fa + s[:, None] * fb
        tb = (self.wb * (1.0 - rb / lb))[:, None] * fb + s[:, None] * fa
        g += self.Ga.T @ ta + self.Gb.T @ tb
        if self.Ge.shape[0]:
            de = self.Ge @ x
            le = np.maximum(np.sqrt(np.einsum("ij,ij->i", de, de)), 1e-12)
            rest = self.edge_rest + (self.edge_start - self.edge_rest) * back
            g += self.Ge.T @ ((self.we * (1.0 - rest / le))[:, None] * de)
        if len(self.bends) and np.any(self.kb > 0):
            theta, gh = hinge_gradients(x, self.bends)
            c = np.mod(theta - self.bend_rest + np.pi, 2.0 * np.pi) - np.pi
            gh *= (self.kb * c)[:, None, None]
            g += self.S @ gh.reshape(-1, 3)
        return g

    def solve(self, x, y, grow: float, contact, thickness: float, iterations: int, tolerance: float) -> tuple:
        """Iterate x <- x - A^-1 grad G(x) (in place on the (P, 3) float64 ``x``), then project onto the
        contact half-spaces ``contact = (point, normal, active)``; stop when no particle moved more than
        ``tolerance`` (m) or after ``iterations``. Returns (iterations done, last largest move in m)."""
        if self.lu is None:
            return 0, 0.0
        fi = self.free_idx
        point, normal, active = contact
        on = np.nonzero(active[fi] != 0)[0]
        cp, cn = point[fi[on]].astype(float), normal[fi[on]].astype(float)
        move, it = np.inf, 0
        for it in range(1, iterations + 1):
            g = self.gradient(x, y, grow)[fi]
            xf = x[fi] - self.lu.solve(np.ascontiguousarray(g))
            if len(on):
                xo = xf[on]
                depth = thickness - np.einsum("ij,ij->i", xo - cp, cn)
                push = depth > 0
                xo[push] += cn[push] * depth[push, None]
                xf[on] = xo
            step = xf - x[fi]
            move = float(np.sqrt(np.max(np.einsum("ij,ij->i", step, step), initial=0.0)))
            x[fi] = xf
            if move < tolerance:
                break
        return it, move
