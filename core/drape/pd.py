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
  rest hinge's dihedral-angle gradients, so ``v = 2 sin(theta / 2) n`` for an
  isometric bend, n the hinge normal; Bergou et al. 2006's quadratic bending)
  with its normal component projected onto ``2 sin(theta_0 / 2)`` and its
  in-plane part (a non-isometric stretch of the hinge, large where the rest
  shape grows from the skintight start, not a bend) left free, weight
  ``bending * |e|^2 / (A_a + A_b)``: the discrete-shell energy of
  :mod:`core.drape.newton` to second order in the angle.

So, to second order in strain and angle, it is the energy :mod:`core.drape.newton`
minimises (the preset's physical stiffness), and the system matrix
``M / dt^2 + sum_c w_c A_c^T A_c`` does not change: it is factored once per
cloth (a sparse LU on the free particles, the same matrix for x, y and z) and
each iteration is the projections (numpy, vectorised) plus one back-substitution
(the global step). Body contact stays off the matrix: after each substep's
solve, as with the other solvers, the Warp kernels keep the particles on their
contact planes' offset with friction (a projection inside the iterations fought
the stiff membrane where neighbouring contact planes diverge, at the armpits, and
tore the shirt), then tethers and self-collision.

Each iteration lowers G; the iterations stop when every free particle off the
body has a residual force ``|grad G|`` under ``tolerance`` times its weight, or
after ``iterations``. A fixed point is the implicit step's solution, so a drape
that stops moving is a static equilibrium of this energy whatever the iteration
count: the stiffness is the fabric's, not the solver's.
"""

from __future__ import annotations

import numpy as np

from ..geom.mesh import row_cross
from ..geom.queries import wp  # Warp, set up once for the package (kernel cache, log level)
from .mesh import Cloth, inv22
from .newton import NewtonStep, _rows

F64 = wp.float64
V64 = wp.vec3d


@wp.kernel
def project_triangles(
    fa: wp.array(dtype=V64),
    fb: wp.array(dtype=V64),
    ra: wp.array(dtype=F64),
    rb: wp.array(dtype=F64),
    wa: wp.array(dtype=F64),
    wb: wp.array(dtype=F64),
    ws: wp.array(dtype=F64),
    ta: wp.array(dtype=V64),
    tb: wp.array(dtype=V64),
    energy: wp.array(dtype=F64),
):
    """Each triangle's weft / warp images onto their rest stretch's sphere and, as a pair, onto the
    nearest orthogonal pair (:func:`orthogonal_pair`): the weighted targets and the energy (float64)."""
    i = wp.tid()
    zero = F64(0.0)
    tiny = F64(1.0e-15)
    a = fa[i]
    b = fb[i]
    la = wp.length(a)
    lb = wp.length(b)
    sa = V64(ra[i], zero, zero)
    sb = V64(rb[i], zero, zero)
    if la > tiny:
        sa = a * (ra[i] / la)
    if lb > tiny:
        sb = b * (rb[i] / lb)
    s = wp.dot(a, b)
    t = la * la + lb * lb
    disc = wp.sqrt(wp.max(t * t - F64(4.0) * s * s, zero))
    mu = zero
    if t > zero:
        mu = F64(2.0) * s / (t + disc)
    den = F64(1.0) - mu * mu
    if wp.abs(den) < F64(1.0e-12):
        den = F64(1.0e-12)
    p = (a - b * mu) / den
    q = (b - a * mu) / den
    ta[i] = sa * wa[i] + p * ws[i]
    tb[i] = sb * wb[i] + q * ws[i]
    e = wa[i] * wp.length_sq(a - sa) + wb[i] * wp.length_sq(b - sb)
    energy[i] = F64(0.5) * (e + ws[i] * (wp.length_sq(a - p) + wp.length_sq(b - q)))


@wp.kernel
def project_hinges(
    x: wp.array(dtype=V64),
    bends: wp.array(dtype=int, ndim=2),
    v: wp.array(dtype=V64),
    kb: wp.array(dtype=F64),
    rest_len: wp.array(dtype=F64),
    target: wp.array(dtype=V64),
    energy: wp.array(dtype=F64),
):
    """Each hinge vector's normal component onto its rest value (:func:`hinge_normals`): the weighted
    target and the energy (float64)."""
    i = wp.tid()
    tiny = F64(1.0e-30)
    x1 = x[bends[i, 0]]
    x2 = x[bends[i, 1]]
    x3 = x[bends[i, 2]]
    x4 = x[bends[i, 3]]
    n1 = wp.cross(x3 - x1, x4 - x1)
    n2 = wp.cross(x4 - x2, x3 - x2)
    n = n1 / wp.max(wp.length(n1), tiny) + n2 / wp.max(wp.length(n2), tiny)
    n = n / wp.max(wp.length(n), tiny)
    h = v[i]
    c = wp.dot(h, n) - rest_len[i]
    target[i] = (h - n * c) * kb[i]
    energy[i] = F64(0.5) * kb[i] * c * c


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


def _vec(a: np.ndarray):
    """A Warp view (no copy) of a contiguous (n, 3) float64 array on the host."""
    return wp.array(np.ascontiguousarray(a), dtype=V64, device="cpu", copy=False)


def _num(a: np.ndarray):
    """A Warp view (no copy) of a contiguous (n,) float64 array on the host."""
    return wp.array(np.ascontiguousarray(a), dtype=F64, device="cpu", copy=False)


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
    history : the acceleration's depth (0: plain local-global iterations).

    Attributes
    ----------
    elements : the :class:`core.drape.newton.NewtonStep` of the same cloth, whose element operators
        (grain images, edges, hinges, rest shapes) this step projects.
    matrix : (P, P) sparse, ``M / dt^2 + sum_c w_c A_c^T A_c`` (the same for x, y and z).
    method : ``"anderson"`` (default: Anderson-accelerated local-global iterations), ``"lbfgs"``
        (L-BFGS with the factored matrix as its initial inverse Hessian) or ``"newton"`` (Gauss-Newton
        steps by conjugate gradients preconditioned with the factored matrix, :meth:`_newton`; an
        experiment: 4x fewer back-substitutions than Anderson on a clamped creased strip, but on the
        Cusick disc it does not settle, and at 5 mm edges the specimen falls off the support, so the
        drape's options do not offer it; benchmarks/results/drape_pd.md).
    """

    def __init__(
        self, cloth: Cloth, material, dt: float, mass: np.ndarray, start_stretch, edge_start, history: int = 5
    ):
        from scipy.sparse import diags, vstack
        from scipy.sparse.linalg import splu

        el = NewtonStep(cloth, material, dt, mass, start_stretch, edge_start)
        self.elements, self.n, self.history = el, el.n, int(history)
        self.free, self.free_idx = el.free, el.free_idx
        self.inertia = el.inertia
        self.ws = 2.0 * el.ws  # the orthogonal pair's distance^2 is (f_a . f_b)^2 / 2
        bends = el.bends
        self.Gh = _rows(len(bends), self.n, bends, hinge_coefficients(cloth))
        # each hinge vector's normal component at rest: 2 sin(theta_0 / 2) (0 inside a panel)
        self.rest_len = 2.0 * np.sin(0.5 * el.bend_rest)

        def gram(g, w):
            return (g.T @ diags(w) @ g) if g.shape[0] else 0.0

        A = diags(self.inertia) + gram(el.Ga, el.wa + self.ws) + gram(el.Gb, el.wb + self.ws)
        A = A + gram(el.Ge, np.full(el.Ge.shape[0], el.we)) + gram(self.Gh, el.kb)
        self.matrix = A.tocsr()
        fi = self.free_idx
        # SPD: no pivoting, a symmetric ordering (about 3x faster back-substitutions than a pivoted LU)
        opts = {"SymmetricMode": True}
        self.lu = (
            splu(self.matrix[fi][:, fi].tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=opts)
            if len(fi)
            else None
        )
        # every linear image at once: weft, warp, sliver edges, hinges (rows in that order), and its transpose
        self.D = vstack([el.Ga, el.Gb, el.Ge, self.Gh]).tocsr()
        self.DT = self.D.T.tocsr()
        t, e = len(el.tri), el.Ge.shape[0]
        self._blocks = np.cumsum([0, t, t, e, len(bends)])
        # the local step's constant inputs, for its Warp kernels (on the host, float64)
        # (the float64 arrays kept here, since the Warp views share their memory)
        self._host = [np.ascontiguousarray(a, dtype=float) for a in (el.wa, el.wb, self.ws, el.kb, self.rest_len)]
        self._wa, self._wb, self._ws, self._kb, self._rest_len = (_num(a) for a in self._host)
        self._bends = wp.array(bends.astype(np.int32).reshape(-1, 4), dtype=int, device="cpu")
        # each image row's weight W (D^T W D + M is the matrix): the gradient is M (x - y) + D^T (W D x - target)
        self._row_w = np.concatenate([el.wa + self.ws, el.wb + self.ws, np.full(e, el.we), el.kb])[:, None]
        # the local step's buffers and their Warp views, made once (the images, targets, energies)
        self._images = np.zeros((self.D.shape[0], 3))
        self._target = np.zeros_like(self._images)
        self._part = np.zeros(self.D.shape[0])
        o = self._blocks
        self._views = [
            (_vec(b[o[k] : o[k + 1]]) if b.ndim == 2 else _num(b[o[k] : o[k + 1]]))
            for b in (self._images, self._target, self._part)
            for k in range(4)
        ]
        self._grow = None
        self.contact = None
        self.friction = 0.0  # the Coulomb coefficient the stop test allows on the body (the drape's)
        self.method = "anderson"

    def set_contact(self, point: np.ndarray, normal: np.ndarray, active: np.ndarray, thickness: float) -> None:
        """Body contact for the next solves' stop test: on an active free particle within twice
        ``thickness`` of its contact plane (through ``point``, facing along ``normal``), the part of the
        residual force that presses it into the body, and up to :attr:`friction` times that along the
        body, is the body's to hold (the contact and friction are applied after the solve)."""
        idx = np.nonzero((np.asarray(active) != 0) & self.free)[0]
        self.contact = (
            (idx, point[idx].astype(float), normal[idx].astype(float), float(thickness)) if len(idx) else None
        )

    def local(self, x: np.ndarray, y: np.ndarray, grow: float) -> tuple:
        """The local step at ``x``: (the elastic part of ``grad G``, ``sum_c w_c A_c^T (A_c x - p_c(x))``
        (P, 3), G(x)), G the step's potential; ``grad G`` is ``M (x - y) / dt^2`` plus it."""
        el = self.elements
        sq = lambda u: np.einsum("ij,ij->i", u, u)  # noqa: E731
        d = x - y
        energy = 0.5 * float(np.sum(self.inertia * sq(d)))
        if self._grow != grow:  # the rest stretch, growing from the skintight start's
            back = 1.0 - grow
            self._rest = [1.0 + (el.stretch0[:, k] - 1.0) * back for k in (0, 1)]  # kept: the views share them
            self._ra, self._rb = (_num(r) for r in self._rest)
            self._edge_len = el.edge_rest + (el.edge_start - el.edge_rest) * back
            self._grow = grow
        o, v = self._blocks, self._views
        images, target, part = self._images, self._target, self._part  # views v[0:4], v[4:8], v[8:12]
        images[:] = self.D @ x
        wp.launch(
            project_triangles,
            int(o[1] - o[0]),
            inputs=[v[0], v[1], self._ra, self._rb, self._wa, self._wb, self._ws, v[4], v[5], v[8]],
            device="cpu",
        )
        if o[3] > o[2]:
            de = images[o[2] : o[3]]
            se = _onto_sphere(de, self._edge_len)
            part[o[2] : o[3]] = 0.5 * el.we * sq(de - se)
            target[o[2] : o[3]] = el.we * se
        if o[4] > o[3]:
            # the hinge vector's normal component onto 2 sin(theta_0 / 2); its in-plane part (a
            # non-isometric stretch of the hinge, not a bend) is left where it is
            wp.launch(
                project_hinges,
                int(o[4] - o[3]),
                inputs=[_vec(x), self._bends, v[3], self._kb, self._rest_len, v[7], v[11]],
                device="cpu",
            )
        energy += float(part.sum())
        return self.DT @ (self._row_w * images - target), energy

    def energy(self, x: np.ndarray, y: np.ndarray, grow: float) -> float:
        """G at ``x`` (float64): inertia plus every constraint's weighted squared distance, halved."""
        return self.local(x, y, grow)[1]

    def solve(self, x, y, grow: float, iterations: int, tolerance: float, weight: np.ndarray):
        """Local-global iterations from ``x`` (in place, (P, 3) float64) towards the minimiser of G.

        Each iteration: the projections at ``x``, the residual ``grad G = A x - M y / dt^2 -
        sum_c w_c A_c^T p_c(x)`` (stop once every free particle off the body has it under ``tolerance``
        times its ``weight``, N (P,), less what the body holds: :meth:`set_contact`) and the global step (one back-substitution of the factored
        matrix). With ``history`` > 0 the iterates are Anderson-accelerated (Peng,
        Deng, Zhang, Liu, "Anderson acceleration for geometry optimization and physics simulation", ACM
        TOG 37(4), 2018): the next iterate mixes the last ``history`` steps, and is kept only where it
        lowers G (else the plain step is taken and the history dropped). With :attr:`method`
        ``"lbfgs"`` they are L-BFGS steps instead (:meth:`_lbfgs`).

        Returns (iterations done, the largest residual over weight at the last test).
        """
        fi = self.free_idx
        if len(fi) == 0:
            return 0, 0.0
        w2 = np.maximum(weight[fi], 1e-30) ** 2
        near, nrm = np.zeros(0, int), np.zeros((0, 3))
        if self.contact is not None:
            # on the body (within twice the contact offset) the body's reaction and friction take the part
            # of the force that presses the particle into the body and up to mu times that along it
            idx, point, normal, thickness = self.contact
            on = np.einsum("ij,ij->i", x[idx] - point, normal) < 2.0 * thickness
            near, nrm = np.searchsorted(fi, idx[on]), normal[on]
        if self.method == "lbfgs":
            return self._lbfgs(x, y, grow, iterations, tolerance, fi, near, nrm, w2)
        if self.method == "newton":
            return self._newton(x, y, grow, iterations, tolerance, fi, near, nrm, w2)
        m = max(self.history, 0)
        # Anderson's history, rows in a ring: the plain steps G(x_k) and their increments G(x_k) - x_k
        ring_g = np.empty((m + 1, 3 * len(fi)))
        ring_f = np.empty_like(ring_g)
        count = 0
        e, grad = self._gradient(x, y, grow)
        it, res = 0, np.inf
        while True:
            res = self._residual(grad, near, nrm, w2)
            if res < tolerance or it >= iterations:
                break
            it += 1
            xf = x[fi].reshape(-1)
            # the global step: A x' = rhs on the free particles, written as x' = x - A^-1 grad G
            g = xf - self._back(grad).reshape(-1)
            k = count % (m + 1)
            ring_g[k], ring_f[k] = g, g - xf
            count += 1
            x[fi] = g.reshape(-1, 3)
            if m and count > 1:
                order = [(count - 1 - j) % (m + 1) for j in range(min(count, m + 1))]  # newest first
                df = ring_f[order[:-1]] - ring_f[order[1:]]
                dg = ring_g[order[:-1]] - ring_g[order[1:]]
                # (einsum, not BLAS: a threaded BLAS on these thin products costs more than the step on a
                # loaded machine)
                gram = np.einsum("ik,jk->ij", df, df)
                gram.flat[:: len(gram) + 1] += 1e-12 * max(float(np.trace(gram)), 1e-300)
                theta = np.linalg.solve(gram, np.einsum("ik,k->i", df, ring_f[order[0]]))
                x[fi] = (g - np.einsum("i,ik->k", theta, dg)).reshape(-1, 3)
                e_a, grad_a = self._gradient(x, y, grow)
                if np.isfinite(e_a) and e_a < e:
                    e, grad = e_a, grad_a
                    continue
                x[fi] = g.reshape(-1, 3)  # the mix did not lower G: the plain step, a fresh history
                ring_g[0], ring_f[0] = g, ring_f[k]
                count = 1
            e, grad = self._gradient(x, y, grow)
        return it, res

    def _gradient(self, x, y, grow) -> tuple:
        """(G(x), grad G on the free particles (F, 3))."""
        elastic, e = self.local(x, y, grow)
        fi = self.free_idx
        return e, self.inertia[fi, None] * (x[fi] - y[fi]) + elastic[fi]

    def _back(self, v: np.ndarray) -> np.ndarray:
        """A^-1 v on the free particles ((F, 3)): one back-substitution of the factored matrix."""
        return self.lu.solve(np.asfortranarray(v.reshape(-1, 3)))

    def _stiffness(self, x: np.ndarray):
        """The Gauss-Newton Hessian of G at ``x`` (whose images the last :meth:`local` left in the buffer),
        as a product: each spring's stiffness along itself and ``max(0, 1 - rest / length)`` across (a
        compressed spring's negative transverse curvature clamped to 0), the shear's ``(f_a . f_b)^2 / t``
        as ``2 w / t J J^T`` (J = (f_b, f_a), t = |f_a|^2 + |f_b|^2) and the hinge's ``k n n^T``, so the
        product is symmetric positive definite and below the PD matrix in every direction."""
        el, o, img = self.elements, self._blocks, self._images.copy()
        ra, rb = self._rest
        fa, fb = img[o[0] : o[1]], img[o[1] : o[2]]

        def spring(f, rest, w):
            length = np.maximum(np.sqrt(np.einsum("ij,ij->i", f, f)), 1e-15)
            across = np.maximum(1.0 - rest / length, 0.0)
            return f / length[:, None], w * across, w * (1.0 - across)

        ua, ca, cna = spring(fa, ra, el.wa)
        ub, cb, cnb = spring(fb, rb, el.wb)
        t = np.einsum("ij,ij->i", fa, fa) + np.einsum("ij,ij->i", fb, fb)
        cs = 2.0 * el.ws / np.maximum(t, 1e-30)
        parts = []
        if o[3] > o[2]:
            parts.append(spring(img[o[2] : o[3]], self._edge_len, np.full(o[3] - o[2], el.we)))
        nh = hinge_normals(x, self.elements.bends.reshape(-1, 4)) if o[4] > o[3] else None
        inertia = self.inertia[:, None]

        def product(u: np.ndarray) -> np.ndarray:
            v = self.D @ u
            out = np.empty_like(v)
            va, vb = v[o[0] : o[1]], v[o[1] : o[2]]
            s = cs * (np.einsum("ij,ij->i", fb, va) + np.einsum("ij,ij->i", fa, vb))
            out[o[0] : o[1]] = ca[:, None] * va + (cna * np.einsum("ij,ij->i", ua, va))[:, None] * ua + s[:, None] * fb
            out[o[1] : o[2]] = cb[:, None] * vb + (cnb * np.einsum("ij,ij->i", ub, vb))[:, None] * ub + s[:, None] * fa
            if parts:
                ue, ce, cne = parts[0]
                ve = v[o[2] : o[3]]
                out[o[2] : o[3]] = ce[:, None] * ve + (cne * np.einsum("ij,ij->i", ue, ve))[:, None] * ue
            if nh is not None:
                vh = v[o[3] : o[4]]
                out[o[3] : o[4]] = (el.kb * np.einsum("ij,ij->i", nh, vh))[:, None] * nh
            return inertia * u + self.DT @ out

        return product

    def _newton(self, x, y, grow, iterations, tolerance, fi, near, nrm, w2):
        """Gauss-Newton steps on G, each solved by conjugate gradients preconditioned with the factored PD
        matrix (whose first iterate is the local-global step): the Hessian of :meth:`_stiffness` keeps the
        soft modes soft (a stretched spring's transverse stiffness near 0, where the PD matrix holds its
        full stiffness), so CG resolves them in a few back-substitutions where the local-global iterations
        crawl. An Armijo line search keeps G falling. ``iterations`` bounds the back-substitutions.

        Returns (back-substitutions done, the largest residual over weight at the last test)."""
        e, grad = self._gradient(x, y, grow)
        it, res = 0, self._residual(grad, near, nrm, w2)
        u = np.zeros_like(x)

        def held(v):  # the body holds the particles on it along its normal: no motion there (filtered CG)
            if len(near):
                v[near] -= np.einsum("ij,ij->i", v[near], nrm)[:, None] * nrm
            return v

        while it < iterations and res >= tolerance:
            hess = self._stiffness(x)
            # PCG on H d = -grad, stopped once the weighted residual of the linear system is a tenth of
            # the gradient's (or at the budget)
            r = held(-grad)
            z = held(self._back(r))
            p, d = z.copy(), np.zeros_like(r)
            rz = float(np.einsum("ij,ij->", r, z))
            goal = 0.1 * max(res, tolerance)
            while True:
                it += 1
                u[fi] = p
                hp = held(hess(u)[fi])
                php = float(np.einsum("ij,ij->", p, hp))
                if not php > 0.0:
                    break
                alpha = rz / php
                d += alpha * p
                r -= alpha * hp
                if it >= iterations or np.sqrt(np.max(np.einsum("ij,ij->i", r, r) / w2)) < goal:
                    break
                z = held(self._back(r))
                rz_new = float(np.einsum("ij,ij->", r, z))
                p = z + (rz_new / rz) * p
                rz = rz_new
            if not np.any(d):
                break
            slope = float(np.einsum("ij,ij->", grad, d))
            x0 = x[fi].copy()
            step, ok = 1.0, False
            for _ in range(8):
                x[fi] = x0 + step * d
                e1, g1 = self._gradient(x, y, grow)
                if np.isfinite(e1) and e1 <= e + 1e-4 * step * slope:
                    ok = True
                    break
                step *= 0.5
            if not ok:
                x[fi] = x0
                break
            e, grad = e1, g1
            res = self._residual(grad, near, nrm, w2)
        return it, res

    def _residual(self, grad, near, nrm, w2) -> float:
        """The largest residual force over weight, less what the body holds (:meth:`set_contact`)."""
        left = np.einsum("ij,ij->i", grad, grad)
        if len(near):
            press = np.einsum("ij,ij->i", grad[near], nrm)  # > 0: the net force presses into the body
            slide = np.maximum(left[near] - press * press, 0.0)
            held = np.maximum(np.sqrt(slide) - self.friction * np.maximum(press, 0.0), 0.0) ** 2
            left[near] = np.where(press > 0.0, held, left[near])
        return float(np.sqrt(np.max(left / w2, initial=0.0)))

    def _lbfgs(self, x, y, grow, iterations, tolerance, fi, near, nrm, w2):
        """L-BFGS on G with the factored matrix as its initial inverse Hessian (Liu, Bouaziz, Kavan,
        "Quasi-Newton methods for real-time simulation of hyperelastic materials", ACM TOG 36(3), 2017):
        without history its step is the local-global one; an Armijo line search keeps G falling."""
        nf = len(fi)

        def h0(v):
            return self._back(v.reshape(nf, 3)).reshape(-1)

        def evaluate(xx):
            return self._gradient(xx, y, grow)

        e, grad = evaluate(x)
        g = grad.reshape(-1)
        hist_s, hist_y = [], []
        it, res = 0, self._residual(grad, near, nrm, w2)
        while it < iterations and res >= tolerance:
            it += 1
            q = g.copy()
            alphas = []
            for sv, yv in zip(reversed(hist_s), reversed(hist_y)):
                a = float(sv @ q) / float(yv @ sv)
                alphas.append(a)
                q -= a * yv
            r = h0(q)
            for (sv, yv), a in zip(zip(hist_s, hist_y), reversed(alphas)):
                r += sv * (a - float(yv @ r) / float(yv @ sv))
            step = -r
            slope = float(g @ step)
            if slope >= 0.0:  # not a descent direction: the plain step, a fresh history
                hist_s, hist_y = [], []
                step = -h0(g)
                slope = float(g @ step)
            x0 = x[fi].reshape(-1).copy()
            alpha, ok = 1.0, False
            for _ in range(8):
                x[fi] = (x0 + alpha * step).reshape(-1, 3)
                e1, grad1 = evaluate(x)
                if e1 <= e + 1e-4 * alpha * slope:
                    ok = True
                    break
                alpha *= 0.5
            if not ok:  # no decrease along the step: keep the last iterate
                x[fi] = x0.reshape(-1, 3)
                if not hist_s:
                    break
                hist_s, hist_y = [], []
                continue
            g1 = grad1.reshape(-1)
            sv, yv = alpha * step, g1 - g
            if float(sv @ yv) > 1e-10 * np.sqrt(float(sv @ sv) * float(yv @ yv)):  # curvature safeguard
                hist_s.append(sv)
                hist_y.append(yv)
                if len(hist_s) > self.history:
                    hist_s.pop(0)
                    hist_y.pop(0)
            e, g = e1, g1
            res = self._residual(grad1, near, nrm, w2)
        return it, res
