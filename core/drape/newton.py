"""The drape's implicit step solved to a residual: the fabric's own stiffness, whatever the step.

Each substep minimises the implicit-Euler incremental potential

    G(x) = sum_i m_i / (2 dt^2) |x_i - y_i|^2 + E(x) + contact,   y = x + dt v + dt^2 g,

with E the energy the XPBD constraints stand for, in the preset's physical units
(:mod:`core.drape.vbd` lists it: weft / warp springs along the grain, shear, the
dihedral bending with weight |e|^2 / (A_a + A_b), the edge springs), and the body
contact a penalty k/2 d^2 below each particle's closest-point plane
(:func:`core.drape.kernels.closest_contact`). The minimiser is a Newton-type
method: the substep's Hessian (each element's block made positive
semi-definite) is assembled and factored once (a sparse LU), and L-BFGS updates
it over the iterations (the factored Hessian as its initial inverse: Liu,
Bouaziz, Kavan, "Quasi-Newton methods for real-time simulation of hyperelastic
materials", ACM TOG 36(3), 2017), with a backtracking line search on G. The
iterations stop when the residual force on every free particle is under
``tolerance`` times its weight, or after ``iterations``.

One factored solve moves the whole cloth, so a stretch or a hoop compression is
corrected across the sheet at once, where a Gauss-Seidel pass (XPBD, VBD) moves
it one ring of triangles a pass (a stress wave crosses a 50 cm cotton sheet in 3
ms; one pass a 1/600 s substep carries it 1 cm): the delivered stiffness is
the preset's, not 1 / (1/k + dt^2 sum w |grad C|^2), and a drape that no
longer moves is a static equilibrium of the fabric's energy. Plain numpy /
scipy on the host, in float64: float32 positions put a strain noise of ~1e-6
on a 1 cm edge, a force of ~30 % of a particle's weight in a 3000 N/m fabric.
Friction, tethers, self-collision and the velocities are the Warp kernels the
other solvers use.
"""

from __future__ import annotations

import numpy as np

from ..geom.mesh import row_cross
from .mesh import BEND_WEIGHT_CAP, Cloth


def _rows(n_rows: int, n_cols: int, cols: np.ndarray, vals: np.ndarray):
    """A sparse (n_rows, n_cols) CSR matrix with row r holding ``vals[r]`` at ``cols[r]``."""
    from scipy.sparse import csr_matrix

    k = cols.shape[1] if cols.ndim == 2 else 0
    return csr_matrix(
        (vals.reshape(-1), (np.repeat(np.arange(n_rows), k), cols.reshape(-1))),
        shape=(n_rows, n_cols),
    )


def hinge_gradients(x: np.ndarray, bends: np.ndarray, gradient: bool = True) -> tuple:
    """Signed dihedral angles (B,) and their gradients (B, 4, 3) at the stencils (a, b, e0, e1)
    (Bridson et al. 2003; the convention of :func:`core.drape.mesh.dihedral_angles`); zero where degenerate.
    ``gradient=False``: the angles and None."""
    x1, x2, x3, x4 = x[bends].transpose(1, 0, 2)
    n1 = row_cross(x3 - x1, x4 - x1)
    n2 = row_cross(x4 - x2, x3 - x2)
    e = x4 - x3
    l1 = np.einsum("ij,ij->i", n1, n1)
    l2 = np.einsum("ij,ij->i", n2, n2)
    le = np.linalg.norm(e, axis=1)
    ok = (l1 > 1e-20) & (l2 > 1e-20) & (le > 1e-10)
    l1, l2, le = np.where(ok, l1, 1.0), np.where(ok, l2, 1.0), np.where(ok, le, 1.0)
    eh = e / le[:, None]
    n1h, n2h = n1 / np.sqrt(l1)[:, None], n2 / np.sqrt(l2)[:, None]
    theta = np.arctan2(np.einsum("ij,ij->i", row_cross(n1h, n2h), eh), np.einsum("ij,ij->i", n1h, n2h))
    if not gradient:
        return np.where(ok, theta, 0.0), None
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


def buckling_stress(bending: float, area: np.ndarray) -> np.ndarray:
    """The compressive stress (N/m) at which a fabric strip of the element's size buckles: the Euler
    load of a pinned strip, pi^2 B / h^2 per unit width, with h = sqrt(4 A / sqrt(3)) the edge of the
    equilateral triangle of the element's rest area A (m^2) and B the bending stiffness (N*m)."""
    h2 = 4.0 * np.asarray(area, float) / np.sqrt(3.0)
    return np.pi**2 * float(bending) / np.maximum(h2, 1e-30)


def clamped_bend_weight(cloth: Cloth) -> np.ndarray:
    """The cloth's hinge weights |e|^2 / (A_a + A_b), with a pinned triangle's area left out.

    A hinge stands for the curvature of the strip of fabric its two triangles span, half of each. Where one
    of them is pinned (all three corners: a clamp), that half cannot bend: the curvature lies on the free
    side alone, so the hinge's weight is |e|^2 / A_free (twice the interior one on a regular mesh, as a
    mirrored ghost triangle gives). With |e|^2 / (A_a + A_b) the clamp's hinge turns twice what the moment
    there asks over half the length: a first-order error in the mesh size (the cantilever strip drooped
    46.0, 41.3 and 38.8 degrees at 10, 5 and 2.5 mm edges, 3.46 cm overhang, cotton; ``docs/drape.md``).
    """
    w = np.asarray(cloth.bend_weight, float).copy()
    bends = np.asarray(cloth.bends).reshape(-1, 4)
    pinned = np.asarray(cloth.pinned, bool)
    if not len(bends) or not pinned.any():
        return w
    side_pinned = pinned[bends[:, :2]] & (pinned[bends[:, 2]] & pinned[bends[:, 3]])[:, None]  # (B, 2): a, b
    one = side_pinned.sum(axis=1) == 1
    if not one.any():
        return w
    faces = np.asarray(cloth.faces)
    key = {tuple(sorted(f)): i for i, f in enumerate(faces.tolist())}
    area = np.asarray(cloth.rest_area, float)
    for i in np.nonzero(one)[0]:
        a, b, e0, e1 = bends[i]
        fa, fb = key.get(tuple(sorted((a, e0, e1)))), key.get(tuple(sorted((b, e0, e1))))
        if fa is None or fb is None:
            continue
        free = area[fb] if side_pinned[i, 0] else area[fa]
        w[i] *= (area[fa] + area[fb]) / max(free, 1e-16)
    return np.minimum(w, 2 * BEND_WEIGHT_CAP)  # mesh.py's sliver cap, doubled for the clamp


class NewtonStep:
    """The host-side implicit step of one cloth: its element arrays, energy, Hessian and solve.

    Parameters
    ----------
    cloth : the welded cloth.
    material : its :class:`core.drape.materials.Material`.
    dt : the substep (s).
    mass : (P,) particle masses (kg).
    start_stretch : (T, 2) the skintight start's weft / warp stretch of every triangle (the rest
        stretch grows from it to 1); edge_start : (E,) the start lengths of the edges.
    buckling : cap each grain spring's compressive stress at the element's Euler load
        (:func:`buckling_stress`; Choi and Ko, "Stable but responsive cloth", ACM TOG 21(3), 2002,
        treat compression as buckling the same way). On by default: a fabric buckles at a tiny
        compressive stress, and folds finer than the mesh cannot form, so without it the disc's hoops
        lock (silk read 50.4 % at 10 mm and 48.3 % at 5 mm against 20-40 %); with it and the clamped
        hinges (:func:`clamped_bend_weight`) silk (1e-6 N*m) reads 26.5 / 27.5 % and cotton 66.0 /
        71.0 % at 10 / 5 mm (``docs/drape.md``). The cap grows as 1 / h^2, so it fades as the mesh is
        refined: the continuum's answer is the same.
    """

    def __init__(
        self, cloth: Cloth, material, dt: float, mass: np.ndarray, start_stretch, edge_start, buckling: bool = True
    ):
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
        self.tri, self.ca, self.cb = tri, ca, cb
        self.wa, self.wb = material.stretch_weft * area, material.stretch_warp * area
        # sub-element buckling: the compressive strain past which a grain spring's stress stays at the
        # element's Euler load (a fabric buckles at a tiny compressive stress; below the mesh size the
        # folds are not resolved, so the element gives way as the strip it stands for would)
        sigma = buckling_stress(material.bending, area) if buckling else np.full(len(area), np.inf)
        self.cap_a, self.cap_b = sigma / material.stretch_weft, sigma / material.stretch_warp
        self.ws = material.shear * area
        e = cloth.edges.reshape(-1, 2)
        self.edges = e
        self.Ge = _rows(len(e), n, e, np.tile([-1.0, 1.0], (len(e), 1)))
        self.we = 0.5 * (material.stretch_weft + material.stretch_warp)
        self.edge_rest = np.asarray(cloth.edge_rest, float)
        self.edge_start = np.asarray(edge_start, float)
        self.bends = cloth.bends.reshape(-1, 4)
        self.kb = material.bending * clamped_bend_weight(cloth)
        self.bend_rest = np.asarray(cloth.bend_rest, float)
        # scatter of the hinges' four gradients onto their particles
        nb = len(self.bends)
        self.S = _rows(4 * nb, n, self.bends.reshape(-1, 1), np.ones((4 * nb, 1))).T.tocsr()
        self.inertia = mass / (dt * dt)
        # the contact penalty's stiffness (N/m): each particle's own, the diagonal of the membrane's
        # rest Hessian plus its mass term
        diag = (self.Ga.multiply(self.Ga)).T @ (self.wa + self.ws) + (self.Gb.multiply(self.Gb)).T @ (self.wb + self.ws)
        self.contact_k = np.asarray(diag).ravel() + self.inertia
        self.contact = None
        self.free_idx = np.nonzero(self.free)[0]
        self._bending = bool(len(self.bends) and np.any(self.kb > 0))
        self._pattern = None  # the free Hessian's fixed sparsity pattern (free_hessian)
        self._ldl = None  # its factorisation (factor)

    def energy(self, x: np.ndarray, y: np.ndarray, grow: float, gradient: bool = True) -> tuple:
        """G and grad G (P, 3) at ``x``, in float64 (float32 positions put a strain noise of ~1e-6 on a
        1 cm edge, a force of ~30 % of a particle's weight in a 3000 N/m fabric): inertia, grain
        springs, shear, edge springs, bending. The gradient is None unless asked for."""
        d = x - y
        energy = 0.5 * float(np.sum(self.inertia * np.einsum("ij,ij->i", d, d)))
        g = self.inertia[:, None] * d if gradient else None
        back = 1.0 - grow
        ra = 1.0 + (self.stretch0[:, 0] - 1.0) * back
        rb = 1.0 + (self.stretch0[:, 1] - 1.0) * back
        fa, fb = self.Ga @ x, self.Gb @ x
        la = np.maximum(np.sqrt(np.einsum("ij,ij->i", fa, fa)), 1e-12)
        lb = np.maximum(np.sqrt(np.einsum("ij,ij->i", fb, fb)), 1e-12)
        s = np.einsum("ij,ij->i", fa, fb)
        # grain springs w psi(e), e = l - rest: psi = e^2 / 2, and past the buckling strain -c linear
        # (the stress capped): with q = max(e, -c), psi = q e - q^2 / 2 and dpsi/de = q
        ea, eb = la - ra, lb - rb
        qa, qb = np.maximum(ea, -self.cap_a), np.maximum(eb, -self.cap_b)
        energy += float(np.sum(self.wa * qa * (ea - 0.5 * qa) + self.wb * qb * (eb - 0.5 * qb)))
        energy += 0.5 * float(np.sum(self.ws * s * s))
        if gradient:
            s = self.ws * s
            ta = (self.wa * qa / la)[:, None] * fa + s[:, None] * fb
            tb = (self.wb * qb / lb)[:, None] * fb + s[:, None] * fa
            g += self.Ga.T @ ta + self.Gb.T @ tb
        if self.Ge.shape[0]:
            de = self.Ge @ x
            le = np.maximum(np.sqrt(np.einsum("ij,ij->i", de, de)), 1e-12)
            rest = self.edge_rest + (self.edge_start - self.edge_rest) * back
            energy += 0.5 * self.we * float(np.sum((le - rest) ** 2))
            if gradient:
                g += self.Ge.T @ ((self.we * (1.0 - rest / le))[:, None] * de)
        if self.contact is not None:
            idx, point, normal, thickness = self.contact
            depth = np.maximum(thickness - np.einsum("ij,ij->i", x[idx] - point, normal), 0.0)
            k = self.contact_k[idx]
            energy += 0.5 * float(np.sum(k * depth * depth))
            if gradient:
                g[idx] -= (k * depth)[:, None] * normal
        if self._bending:
            theta, gh = hinge_gradients(x, self.bends, gradient)
            c = np.mod(theta - self.bend_rest + np.pi, 2.0 * np.pi) - np.pi
            energy += 0.5 * float(np.sum(self.kb * c * c))
            if gradient:
                gh *= (self.kb * c)[:, None, None]
                g += self.S @ gh.reshape(-1, 3)
        return energy, g

    def _blocks(self, x: np.ndarray, grow: float) -> list:
        """The Hessian's element blocks at ``x``, each made positive semi-definite, as (particles (m, k),
        blocks (m, 3k, 3k)) in a fixed order (triangles, edges, hinges, each particle's own 3 x 3: its
        mass term plus the contact penalty k n n^T where it is below its contact offset), so that the
        sparsity pattern does not change between substeps. A compressed spring keeps only its
        stiffness along itself; shear and bending are Gauss-Newton."""
        n = self.n
        back = 1.0 - grow
        eye = np.eye(3)
        out = []

        def spring(f, rest, w, cap=None):  # (m, 3, 3) Hessian of w/2 (|f| - rest)^2 in f
            l = np.maximum(np.sqrt(np.einsum("mi,mi->m", f, f)), 1e-12)
            fh = f / l[:, None]
            t = np.maximum(1.0 - rest / l, 0.0)[:, None, None]
            if cap is not None:  # buckled (the stress capped): no stiffness along, none across (projected)
                w = np.where(l - rest < -cap, 0.0, w)
            return w[:, None, None] * (fh[:, :, None] * fh[:, None, :] * (1.0 - t) + eye * t)

        ra = 1.0 + (self.stretch0[:, 0] - 1.0) * back
        rb = 1.0 + (self.stretch0[:, 1] - 1.0) * back
        fa, fb = self.Ga @ x, self.Gb @ x
        m = len(self.tri)
        ka, kb = spring(fa, ra, self.wa, self.cap_a), spring(fb, rb, self.wb, self.cap_b)
        h = (self.ca[:, :, None] * self.ca[:, None, :])[:, :, None, :, None] * ka[:, None, :, None, :]
        h += (self.cb[:, :, None] * self.cb[:, None, :])[:, :, None, :, None] * kb[:, None, :, None, :]
        u = (self.ca[:, :, None] * fb[:, None, :] + self.cb[:, :, None] * fa[:, None, :]).reshape(m, 9)
        out.append((self.tri, h.reshape(m, 9, 9) + self.ws[:, None, None] * (u[:, :, None] * u[:, None, :])))
        if self.Ge.shape[0]:
            e = self.edges
            rest = self.edge_rest + (self.edge_start - self.edge_rest) * back
            k = spring(x[e[:, 1]] - x[e[:, 0]], rest, np.full(len(e), self.we))
            c = np.array([-1.0, 1.0])
            out.append(
                (e, ((c[:, None] * c[None, :])[None, :, None, :, None] * k[:, None, :, None, :]).reshape(-1, 6, 6))
            )
        if self._bending:
            _, gh = hinge_gradients(x, self.bends)
            gh = gh.reshape(len(gh), 12)
            out.append((self.bends, self.kb[:, None, None] * (gh[:, :, None] * gh[:, None, :])))
        own = self.inertia[:, None, None] * eye
        if self.contact is not None:
            idx, point, normal, thickness = self.contact
            below = thickness - np.einsum("ij,ij->i", x[idx] - point, normal) > 0
            if np.any(below):
                nrm, at = normal[below], idx[below]
                own[at] += self.contact_k[at][:, None, None] * (nrm[:, :, None] * nrm[:, None, :])
        out.append((np.arange(n)[:, None], own))
        return out

    def hessian(self, x: np.ndarray, grow: float):
        """The Hessian of G at ``x``, (3P, 3P) sparse CSR, each element's block made positive
        semi-definite (:meth:`_blocks`)."""
        from scipy.sparse import coo_matrix

        rows, cols, vals = [], [], []
        for dofs, blocks in self._blocks(x, grow):
            d = (3 * dofs[:, :, None] + np.arange(3)).reshape(len(dofs), -1)
            k = d.shape[1]
            rows.append(np.repeat(d, k, axis=1).ravel())
            cols.append(np.tile(d, (1, k)).ravel())
            vals.append(blocks.ravel())
        n3 = 3 * self.n
        return coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n3, n3)).tocsr()

    def free_hessian(self, x: np.ndarray, grow: float):
        """The Hessian's free rows and columns (the particles that are not pinned), their upper triangle as
        a CSC matrix whose sparsity pattern is the same at every call (what :meth:`factor` needs)."""
        from scipy.sparse import csc_matrix

        blocks = self._blocks(x, grow)
        if self._pattern is None:
            nf3 = 3 * len(self.free_idx)
            fmap = np.full(3 * self.n, -1, np.int64)
            fmap[(3 * self.free_idx[:, None] + np.arange(3)).ravel()] = np.arange(nf3)
            rows, cols = [], []
            for dofs, _ in blocks:
                d = fmap[(3 * dofs[:, :, None] + np.arange(3)).reshape(len(dofs), -1)]
                k = d.shape[1]
                rows.append(np.repeat(d, k, axis=1).ravel())
                cols.append(np.tile(d, (1, k)).ravel())
            r, c = np.concatenate(rows), np.concatenate(cols)
            keep = (r >= 0) & (c >= 0) & (r <= c)
            key, slot = np.unique(c[keep] * nf3 + r[keep], return_inverse=True)  # column-major order
            indptr = np.concatenate([[0], np.cumsum(np.bincount(key // nf3, minlength=nf3))])
            self._pattern = (keep, slot.ravel(), (key % nf3).astype(np.int32), indptr.astype(np.int32), nf3)
        keep, slot, indices, indptr, nf3 = self._pattern
        vals = np.concatenate([b.ravel() for _, b in blocks])[keep]
        data = np.bincount(slot, weights=vals, minlength=len(indices))
        return csc_matrix((data, indices, indptr), shape=(nf3, nf3))

    def factor(self, x: np.ndarray, grow: float):
        """The free Hessian at ``x`` factored (LDL^T, qdldl with its AMD ordering; the symbolic
        factorisation is kept and only the values refactored after the first call): ``solve(b)``."""
        import qdldl

        a = self.free_hessian(x, grow)
        if self._ldl is None:
            self._ldl = qdldl.Solver(a, upper=True)
        else:
            self._ldl.update(a, upper=True)
        return self._ldl

    def set_contact(self, point: np.ndarray, normal: np.ndarray, active: np.ndarray, thickness: float) -> None:
        """Body contact for the next solves: a penalty k/2 d^2 on each active free particle whose depth d
        below its contact plane's offset ``thickness`` is positive (k: the particle's diagonal of A)."""
        idx = np.nonzero((np.asarray(active) != 0) & self.free)[0]
        self.contact = (
            (idx, point[idx].astype(float), normal[idx].astype(float), float(thickness)) if len(idx) else None
        )

    def solve(
        self,
        x,
        y,
        grow: float,
        iterations: int,
        tolerance: float,
        weight: np.ndarray,
        history: int = 8,
        previous=None,
    ):
        """Minimise G from ``x`` (in place, (P, 3) float64) by L-BFGS with the factored Hessian at ``x`` as
        its initial inverse (without history, a Newton step) and a backtracking (Armijo) line search.
        Stops when every free particle's residual force |grad G| is under ``tolerance`` times its
        ``weight`` (N, (P,)) (at least one iteration), or after ``iterations``, or when the line search
        finds no decrease; particles within twice the contact offset of the body are left out of that
        test (the friction applied after the solve holds them where G alone would not).

        ``previous``: the substep's start positions x_n. Where G is lower there than at the guess
        ``x``, the solve starts from x_n, so that it ends no higher in G than x_n, the condition for a
        stable implicit step (Gast, Schroeder, Stomakhin, Jiang, Teran, "Optimization integrator for
        large time steps", IEEE TVCG 21(10), 2015). From the inertial guess, a solve stopped at its
        iteration limit can end with the stiff grain springs still stretched, energy the next steps
        turn into motion: the silk Cusick disc flapped 4-10 mm a frame at its rim for 400 frames;
        starting from the lower of the two it settles in about 40 (``docs/drape.md``).

        Returns (iterations done, the largest residual over weight at the end).
        """
        fi = self.free_idx
        if len(fi) == 0:
            return 0, 0.0
        if previous is not None:
            e_guess = self.energy(x, y, grow, gradient=False)[0]
            if self.energy(previous, y, grow, gradient=False)[0] < e_guess:
                x[...] = previous
        # the stop test leaves out the particles on the body: friction (applied after the solve) holds them
        w = np.maximum(weight[fi], 1e-30).copy()
        if self.contact is not None:
            idx, point, normal, thickness = self.contact
            near = idx[np.einsum("ij,ij->i", x[idx] - point, normal) < 2.0 * thickness]
            w[np.searchsorted(fi, near)] = np.inf
        e, g = self.energy(x, y, grow)
        g = g[fi]
        lu = self.factor(x, grow)
        nf = len(fi)

        def h0(v):  # the substep's Hessian, factored once, as L-BFGS's initial inverse
            return lu.solve(np.ascontiguousarray(v.reshape(-1))).reshape(nf, 3)

        hist_s, hist_y = [], []
        it, res = 0, float(np.max(np.linalg.norm(g, axis=1) / w, initial=0.0))
        while it < iterations and (it == 0 or res >= tolerance):
            it += 1
            q = g.copy()
            alphas = []
            for sv, yv in zip(reversed(hist_s), reversed(hist_y)):
                a = np.sum(sv * q) / np.sum(yv * sv)
                alphas.append(a)
                q -= a * yv
            r = h0(q)
            for (sv, yv), a in zip(zip(hist_s, hist_y), reversed(alphas)):
                r += sv * (a - np.sum(yv * r) / np.sum(yv * sv))
            step = -r
            slope = float(np.sum(g * step))
            if slope >= 0.0:  # not a descent direction: drop the history, take the plain step
                hist_s, hist_y = [], []
                step = -h0(g)
                slope = float(np.sum(g * step))
            x0f = x[fi].copy()
            alpha, ok = 1.0, False
            for trial in range(20):
                x[fi] = x0f + alpha * step
                # the full step (most often taken) with its gradient, to be kept; the shorter ones without
                e1, g1 = self.energy(x, y, grow, gradient=trial == 0)
                if e1 <= e + 1e-4 * alpha * slope:
                    ok = True
                    break
                alpha *= 0.5
            if not ok:  # no decrease along the step: keep the last iterate
                x[fi] = x0f
                if not hist_s:
                    break
                hist_s, hist_y = [], []
                continue
            if g1 is None:
                e1, g1 = self.energy(x, y, grow)
            g1 = g1[fi]
            sv, yv = x[fi] - x0f, g1 - g
            if np.sum(sv * yv) > 1e-8 * np.sqrt(np.sum(sv * sv) * np.sum(yv * yv)):  # curvature safeguard
                hist_s.append(sv)
                hist_y.append(yv)
                if len(hist_s) > history:
                    hist_s.pop(0)
                    hist_y.pop(0)
            e, g = e1, g1
            res = float(np.max(np.linalg.norm(g, axis=1) / w, initial=0.0))
        return it, res
