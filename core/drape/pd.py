"""Projective dynamics: the drape's implicit step with one factored matrix per cloth.

Each substep minimises the implicit-Euler incremental potential

    G(x) = sum_i m_i / (2 dt^2) |x_i - y_i|^2 + sum_c w_c / 2 |A_c x - p_c(x)|^2,   y = x + dt v + dt^2 g,

by local-global iterations (Bouaziz, Martin, Liu, Kavan, Pauly, "Projective
Dynamics: Fusing Constraint Projections for Fast Simulation", ACM TOG 33(4),
2014; the scheme of Style3D and of Newton's ``SolverStyle3D``). Every term of
the fabric's energy is a squared distance from a linear image of the positions
(``A_c x``) to a constraint set, ``p_c(x)`` the closest point of that set:

* weft / warp grain springs: the triangle's weft (warp) image ``f = G x`` onto
  the sphere of the rest stretch, weight ``k_weft A`` (``k_warp A``);
* shear: the pair (weft, warp image) onto the nearest orthogonal pair (closed
  form), weight ``2 k_shear A``: ``k_shear A (f_a . f_b)^2 / 2`` for small shear;
* the sliver edges' springs: the edge vector onto the sphere of its rest length;
* bending: the hinge vector ``v = sum_i alpha_i x_i`` (``alpha_i`` the flat
  rest hinge's dihedral-angle gradients, so ``|v| = 2 sin(theta / 2)`` for an
  isometric bend) onto ``2 sin(theta_0 / 2)`` along the hinge normal, weight
  ``bending * |e|^2 / (A_a + A_b)``: the discrete-shell energy of
  :mod:`core.drape.newton` to second order in the angle (flat hinges: a
  constant quadratic form, Bergou et al. 2006).

So, to second order in strain and angle, it is the energy :mod:`core.drape.newton`
minimises (the preset's physical stiffness), and the system matrix
``M / dt^2 + sum_c w_c A_c^T A_c`` does not change: it is factored once per
cloth (a sparse LU on the free particles, the same matrix for x, y and z) and
each iteration is the projections (numpy, vectorised) plus one back-substitution
(the global step). Body contact is a projection onto each active particle's
contact plane after every global step (off the matrix); friction, tethers and
self-collision are the Warp kernels the other solvers use after the solve.

Each iteration lowers G; the iterations stop when every free particle off the
body has a residual force ``|grad G|`` under ``tolerance`` times its weight, or
after ``iterations``. A fixed point is the implicit step's solution, so a drape
that stops moving is a static equilibrium of this energy whatever the iteration
count: the stiffness is the fabric's, not the solver's.
"""

from __future__ import annotations

import numpy as np

from ..geom.mesh import row_cross
from .mesh import Cloth, inv22
from .newton import NewtonStep, _rows


def hinge_coefficients(cloth: Cloth) -> np.ndarray:
    """(B, 4) the flat rest hinge's dihedral-angle gradients along its normal, per stencil particle
    (a, b, e0, e1): ``theta ~ n . sum_i alpha_i x_i`` near the rest shape (Bridson et al. 2003's gradients
    on the hinge unfolded flat from its two pattern triangles); zero where a triangle is degenerate."""
    bends = cloth.bends.reshape(-1, 4)
    out = np.zeros((len(bends), 4))
    if len(bends) == 0:
        return out
    dm = inv22(cloth.rest_inv)  # rest edges x1-x0, x2-x0 per triangle
    corners = np.zeros((len(cloth.faces), 3, 2))
    corners[:, 1], corners[:, 2] = dm[:, :, 0], dm[:, :, 1]

    # the triangle of each side, (a, e0, e1) and (b, e0, e1), looked up by its sorted corners
    def code(tri):
        k = np.sort(tri, axis=1).astype(np.int64)
        return (k[:, 0] << 42) + (k[:, 1] << 21) + k[:, 2]

    face_code = code(cloth.faces)
    order = np.argsort(face_code, kind="stable")
    sorted_code = face_code[order]

    def face_of(tri):
        want = code(tri)
        pos = np.clip(np.searchsorted(sorted_code, want), 0, len(sorted_code) - 1)
        return order[pos], sorted_code[pos] == want

    a, b, e0, e1 = bends.T
    ta, oka = face_of(np.stack([a, e0, e1], axis=1))
    tb, okb = face_of(np.stack([b, e0, e1], axis=1))

    def local(v, t):
        return corners[t, np.argmax(cloth.faces[t] == v[:, None], axis=1)]

    def side(p, t):  # along-edge position from e0, height, edge length of one side
        q0, q1, q = local(e0, t), local(e1, t), local(p, t)
        e = q1 - q0
        le = np.maximum(np.linalg.norm(e, axis=1), 1e-30)
        u = e / le[:, None]
        along = np.einsum("ij,ij->i", q - q0, u)
        height = np.abs(u[:, 0] * (q - q0)[:, 1] - u[:, 1] * (q - q0)[:, 0])
        return along, height, le

    xa, ya, la = side(a, ta)
    xb, yb, lb = side(b, tb)
    ok = oka & okb & (ya > 1e-12 * la) & (yb > 1e-12 * lb)
    ya, yb = np.where(ok, ya, 1.0), np.where(ok, yb, 1.0)
    out[:, 0] = -1.0 / ya
    out[:, 1] = -1.0 / yb
    out[:, 2] = (la - xa) / (la * ya) + (lb - xb) / (lb * yb)
    out[:, 3] = xa / (la * ya) + xb / (lb * yb)
    out[~ok] = 0.0
    return out


def hinge_normals(x: np.ndarray, bends: np.ndarray) -> np.ndarray:
    """(B, 3) unit normal of each hinge (a, b, e0, e1): the mean of its two triangles' unit normals. The
    hinge vector of :func:`hinge_coefficients` is ``2 sin(theta / 2)`` times it for an isometric bend."""
    x1, x2, x3, x4 = (x[bends[:, k]] for k in range(4))
    n1 = row_cross(x3 - x1, x4 - x1)
    n2 = row_cross(x4 - x2, x3 - x2)
    nrm = n1 / np.maximum(np.linalg.norm(n1, axis=1), 1e-30)[:, None]
    nrm += n2 / np.maximum(np.linalg.norm(n2, axis=1), 1e-30)[:, None]
    return nrm / np.maximum(np.linalg.norm(nrm, axis=1), 1e-30)[:, None]


def orthogonal_pair(a: np.ndarray, b: np.ndarray) -> tuple:
    """The nearest pair (p, q) with p . q = 0 to the rows of (a, b): minimises |p - a|^2 + |q - b|^2.

    p = (a - mu b) / (1 - mu^2), q = (b - mu a) / (1 - mu^2) with mu the root of
    s mu^2 - (|a|^2 + |b|^2) mu + s = 0 (s = a . b) of smallest size."""
    s = np.einsum("ij,ij->i", a, b)
    t = np.einsum("ij,ij->i", a, a) + np.einsum("ij,ij->i", b, b)
    disc = np.sqrt(np.maximum(t * t - 4.0 * s * s, 0.0))
    # mu = (t - disc) / (2 s), written without cancellation
    mu = np.where(t > 0.0, 2.0 * s / np.maximum(t + disc, 1e-300), 0.0)
    den = 1.0 - mu * mu
    den = np.where(np.abs(den) > 1e-12, den, 1e-12)
    return (a - mu[:, None] * b) / den[:, None], (b - mu[:, None] * a) / den[:, None]


def _onto_sphere(f: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Rows of ``f`` scaled to length ``radius`` (a zero row: ``radius`` along x)."""
    length = np.sqrt(np.einsum("ij,ij->i", f, f))
    out = np.zeros_like(f)
    ok = length > 1e-15
    out[ok] = f[ok] * (radius[ok] / length[ok])[:, None]
    out[~ok, 0] = radius[~ok]
    return out


class ProjectiveStep:
    """The host-side projective-dynamics step of one cloth: its constraints, the factored matrix, the solve.

    Parameters
    ----------
    cloth, material, dt, mass, start_stretch, edge_start : as :class:`core.drape.newton.NewtonStep`'s.
    history : the Anderson acceleration's depth (0: plain local-global iterations).

    Attributes
    ----------
    elements : the :class:`core.drape.newton.NewtonStep` of the same cloth, whose element operators
        (grain images, edges, hinges, rest shapes) this step projects.
    matrix : (P, P) sparse, ``M / dt^2 + sum_c w_c A_c^T A_c`` (the same for x, y and z).
    """

    def __init__(
        self, cloth: Cloth, material, dt: float, mass: np.ndarray, start_stretch, edge_start, history: int = 5
    ):
        from scipy.sparse import diags
        from scipy.sparse.linalg import splu

        el = NewtonStep(cloth, material, dt, mass, start_stretch, edge_start)
        self.elements, self.n, self.history = el, el.n, int(history)
        self.free, self.free_idx = el.free, el.free_idx
        self.fixed_idx = np.nonzero(~el.free)[0]
        self.inertia = el.inertia
        self.GaT, self.GbT, self.GeT = el.Ga.T.tocsr(), el.Gb.T.tocsr(), el.Ge.T.tocsr()
        self.ws = 2.0 * el.ws  # the orthogonal pair's distance^2 is (f_a . f_b)^2 / 2
        bends = el.bends
        self.Gh = _rows(len(bends), self.n, bends, hinge_coefficients(cloth))
        self.GhT = self.Gh.T.tocsr()
        # the bent hinges (seams sewn at an angle) project onto 2 sin(theta_0 / 2) along their normal;
        # the flat ones onto 0, a constant quadratic term with no right-hand side
        self.bent = np.nonzero((np.abs(el.bend_rest) > 1e-9) & (el.kb > 0))[0]
        self.bent_len = 2.0 * np.sin(0.5 * el.bend_rest[self.bent])

        def gram(g, w):
            return (g.T @ diags(w) @ g) if g.shape[0] else 0.0

        A = diags(self.inertia) + gram(el.Ga, el.wa + self.ws) + gram(el.Gb, el.wb + self.ws)
        A = A + gram(el.Ge, np.full(el.Ge.shape[0], el.we)) + gram(self.Gh, el.kb)
        self.matrix = A.tocsr()
        fi = self.free_idx
        self.A_fp = self.matrix[fi][:, self.fixed_idx].tocsr()
        self.lu = splu(self.matrix[fi][:, fi].tocsc(), permc_spec="MMD_AT_PLUS_A") if len(fi) else None
        self.contact = None

    def set_contact(self, point: np.ndarray, normal: np.ndarray, active: np.ndarray, thickness: float) -> None:
        """Body contact for the next solves: each active free particle is kept at least ``thickness``
        above its contact plane (through ``point``, facing along ``normal``) after every global step."""
        idx = np.nonzero((np.asarray(active) != 0) & self.free)[0]
        self.contact = (
            (idx, point[idx].astype(float), normal[idx].astype(float), float(thickness)) if len(idx) else None
        )

    def local(self, x: np.ndarray, y: np.ndarray, grow: float) -> tuple:
        """The local step at ``x``: (``sum_c w_c A_c^T p_c(x)`` (P, 3), G(x)), G the step's potential."""
        el = self.elements
        sq = lambda u: np.einsum("ij,ij->i", u, u)  # noqa: E731
        d = x - y
        energy = 0.5 * float(np.sum(self.inertia * sq(d)))
        back = 1.0 - grow
        ra = 1.0 + (el.stretch0[:, 0] - 1.0) * back
        rb = 1.0 + (el.stretch0[:, 1] - 1.0) * back
        fa, fb = el.Ga @ x, el.Gb @ x
        sa, sb = _onto_sphere(fa, ra), _onto_sphere(fb, rb)
        pa, pb = orthogonal_pair(fa, fb)
        energy += 0.5 * float(np.sum(el.wa * sq(fa - sa) + el.wb * sq(fb - sb) + self.ws * (sq(fa - pa) + sq(fb - pb))))
        rhs = self.GaT @ (el.wa[:, None] * sa + self.ws[:, None] * pa)
        rhs += self.GbT @ (el.wb[:, None] * sb + self.ws[:, None] * pb)
        if el.Ge.shape[0]:
            de = el.Ge @ x
            se = _onto_sphere(de, el.edge_rest + (el.edge_start - el.edge_rest) * back)
            energy += 0.5 * el.we * float(np.sum(sq(de - se)))
            rhs += self.GeT @ (el.we * se)
        if len(el.bends):
            v = self.Gh @ x
            if len(self.bent):
                ph = np.zeros_like(v)
                ph[self.bent] = self.bent_len[:, None] * hinge_normals(x, el.bends[self.bent])
                v = v - ph
                rhs += self.GhT @ (el.kb[:, None] * ph)
            energy += 0.5 * float(np.sum(el.kb * sq(v)))
        return rhs, energy

    def energy(self, x: np.ndarray, y: np.ndarray, grow: float) -> float:
        """G at ``x`` (float64): inertia plus every constraint's weighted squared distance, halved."""
        return self.local(x, y, grow)[1]

    def _contact(self, x: np.ndarray) -> None:
        """Each active particle lifted onto its contact plane's offset where it lies below it (in place)."""
        if self.contact is None:
            return
        idx, point, normal, thickness = self.contact
        depth = thickness - np.einsum("ij,ij->i", x[idx] - point, normal)
        below = depth > 0.0
        x[idx[below]] += depth[below, None] * normal[below]

    def solve(self, x, y, grow: float, iterations: int, tolerance: float, weight: np.ndarray):
        """Local-global iterations from ``x`` (in place, (P, 3) float64) towards the minimiser of G.

        Each iteration: the projections at ``x``, the residual ``grad G = A x - M y / dt^2 -
        sum_c w_c A_c^T p_c(x)`` (stop once every free particle off the body has it under ``tolerance``
        times its ``weight``, N (P,)), the global step (one back-substitution of the factored matrix)
        and the contact projection. With ``history`` > 0 the iterates are Anderson-accelerated (Peng,
        Deng, Zhang, Liu, "Anderson acceleration for geometry optimization and physics simulation", ACM
        TOG 37(4), 2018): the next iterate mixes the last ``history`` steps, and is kept only where it
        lowers G (else the plain step is taken and the history dropped).

        Returns (iterations done, the largest residual over weight at the last test).
        """
        fi = self.free_idx
        if len(fi) == 0:
            return 0, 0.0
        w = np.maximum(weight[fi], 1e-30).copy()
        if self.contact is not None:
            # the stop test leaves out the particles on the body: friction (applied after the solve) holds them
            idx, point, normal, thickness = self.contact
            near = idx[np.einsum("ij,ij->i", x[idx] - point, normal) < 2.0 * thickness]
            w[np.searchsorted(fi, near)] = np.inf
        inert = self.inertia[:, None] * y
        fixed = self.A_fp @ x[self.fixed_idx] if len(self.fixed_idx) else 0.0
        hist_g, hist_f = [], []  # the plain steps G(x_k) and their increments G(x_k) - x_k (free dofs)
        rhs, e = self.local(x, y, grow)
        it, res = 0, np.inf
        while True:
            rhs = inert + rhs
            res = float(np.max(np.linalg.norm((self.matrix @ x - rhs)[fi], axis=1) / w, initial=0.0))
            if res < tolerance or it >= iterations:
                break
            it += 1
            xf = x[fi].reshape(-1)
            x[fi] = self.lu.solve(np.ascontiguousarray(rhs[fi] - fixed))
            self._contact(x)
            g = x[fi].reshape(-1)
            hist_g.append(g)
            hist_f.append(g - xf)
            if len(hist_g) > self.history + 1:
                hist_g.pop(0)
                hist_f.pop(0)
            if len(hist_g) > 1:
                df = np.stack([hist_f[k + 1] - hist_f[k] for k in range(len(hist_f) - 1)], axis=1)
                dg = np.stack([hist_g[k + 1] - hist_g[k] for k in range(len(hist_g) - 1)], axis=1)
                theta = np.linalg.lstsq(df, hist_f[-1], rcond=None)[0]
                x[fi] = (g - dg @ theta).reshape(-1, 3)
                self._contact(x)
                rhs_a, e_a = self.local(x, y, grow)
                if np.isfinite(e_a) and e_a < e:
                    rhs, e = rhs_a, e_a
                    continue
                x[fi] = g.reshape(-1, 3)  # the mix did not lower G: the plain step, a fresh history
                hist_g, hist_f = [g], [hist_f[-1]]
            rhs, e = self.local(x, y, grow)
        return it, res
