"""Vertex Block Descent (VBD) for the drape: the fabric's own stiffness, whatever the step.

Chen, A. H., Liu, Z., Yang, Y., Yuksel, C. "Vertex Block Descent", ACM TOG 43(4), 2024.
Each substep minimises the implicit-Euler incremental potential

    G(x) = sum_i m_i / (2 dt^2) |x_i - y_i|^2 + E(x),   y = x + dt v + dt^2 g,

by Gauss-Seidel over the vertices: each vertex in turn takes one Newton step
on G with its neighbours held (a 3x3 solve), vertex colour by colour (no two
vertices of a colour share an element, so a colour runs in parallel without
atomics and a CPU run is bitwise repeatable). E is the same energy the XPBD
solver's constraints stand for, in the preset's physical units:

* membrane, per triangle of rest area A with weft / warp images f_a, f_b of its
  deformation gradient: A/2 [k_weft (|f_a| - r_a)^2 + k_warp (|f_b| - r_b)^2
  + k_shear (f_a . f_b)^2] (r: the rest stretch, 1 once grown);
* bending, per interior edge: bending * w / 2 (theta - theta_0)^2 with the
  discrete-shell weight w = |e|^2 / (A_a + A_b) (:class:`core.drape.mesh.Cloth`);
* the sliver edges' springs: k/2 (l - l_0)^2.

Unlike one XPBD pass a substep, whose effective stiffness is
1 / (1/k + dt^2 sum w |grad C|^2) (set by the step and the mesh), a state that
VBD leaves unchanged is a true equilibrium of these forces: the settled drape
follows the fabric, not the substeps. Body contact is a half-space per vertex
(the closest-point plane of :func:`core.drape.kernels.closest_contact`), kept
inside the vertex solve; friction and the final projection are the XPBD
solver's (:func:`core.drape.kernels.collide_body`).
"""

from __future__ import annotations

import numpy as np

from ..geom.queries import wp
from .kernels import dihedral

# roles packed with the element index: element * 4 + role
ROLES = 4


def vertex_colouring(n: int, groups) -> np.ndarray:
    """Colours (n,) of the particles: no two particles that share an element (a row of any of ``groups``)
    have one colour. Deterministic greedy (smallest free colour, vertex order)."""
    from scipy.sparse import coo_matrix

    rows, cols = [], []
    for g in groups:
        g = np.asarray(g, dtype=np.int64)
        if g.size == 0:
            continue
        k = g.shape[1]
        for a in range(k):
            for b in range(k):
                if a != b:
                    rows.append(g[:, a])
                    cols.append(g[:, b])
    colours = np.zeros(n, dtype=np.int64)
    if not rows:
        return colours
    adj = coo_matrix((np.ones(sum(len(r) for r in rows)), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    adj = adj.tocsr()
    indptr, indices = adj.indptr, adj.indices
    colours[:] = -1
    for v in range(n):
        used = {int(c) for c in colours[indices[indptr[v] : indptr[v + 1]]] if c >= 0}
        c = 0
        while c in used:
            c += 1
        colours[v] = c
    return colours


def incidence(n: int, elements: np.ndarray) -> tuple:
    """CSR lists of the elements of each particle: (starts (n+1,), packed element * 4 + role)."""
    e = np.asarray(elements, dtype=np.int64)
    if e.size == 0:
        return np.zeros(n + 1, np.int64), np.zeros(1, np.int64)
    k = e.shape[1]
    owner = e.reshape(-1)
    packed = (np.repeat(np.arange(len(e)), k) * ROLES + np.tile(np.arange(k), len(e))).astype(np.int64)
    order = np.argsort(owner, kind="stable")
    counts = np.bincount(owner, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return starts, packed[order] if len(packed) else np.zeros(1, np.int64)


@wp.kernel
def predict(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    y: wp.array(dtype=wp.vec3),
    acc: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    gravity: wp.vec3,
    dt: float,
    keep: float,
):
    """The inertial target y = x + dt v' + dt^2 g (v' the damped velocity) and the start guess:
    x + dt v' plus the part of gravity the vertex accelerated with last substep (VBD's adaptive
    initialisation: a resting vertex starts where it rests, a falling one where it falls)."""
    i = wp.tid()
    xi = x[i]
    x_prev[i] = xi
    if inv_mass[i] == 0.0:
        v[i] = wp.vec3(0.0, 0.0, 0.0)
        y[i] = xi
        return
    vel = v[i] * keep
    y[i] = xi + (vel + gravity * dt) * dt
    g2 = wp.dot(gravity, gravity)
    s = float(0.0)
    if g2 > 0.0:
        s = wp.clamp(wp.dot(acc[i], gravity) / g2, 0.0, 1.0)
    x[i] = xi + (vel + gravity * (s * dt)) * dt


@wp.func
def _axis_terms(f: wp.vec3, rest: float, k: float, c: float):
    """Gradient factor and Hessian of k/2 (|f| - rest)^2 for a vertex whose f-coefficient is c."""
    l = wp.length(f)
    h = wp.mat33(0.0)
    g = wp.vec3(0.0)
    if l > 1.0e-12:
        kk = k
        n = f / l
        g = n * (kk * (l - rest) * c)
        nn = wp.outer(n, n)
        t = wp.max(1.0 - rest / l, 0.0)
        h = (nn + (wp.identity(n=3, dtype=float) - nn) * t) * (kk * c * c)
    return g, h


@wp.func
def _dihedral(x1: wp.vec3, x2: wp.vec3, x3: wp.vec3, x4: wp.vec3, role: int):
    """Signed dihedral angle of the stencil (a, b, e0, e1) and its gradient at the vertex ``role``."""
    theta, n1, n2, l1, l2, le, eh, ok = dihedral(x1, x2, x3, x4)
    g = wp.vec3(0.0)
    if ok == 1:
        if role == 0:
            g = n1 * (-le / l1)
        elif role == 1:
            g = n2 * (-le / l2)
        elif role == 2:
            g = n1 * (wp.dot(x4 - x1, eh) / l1) + n2 * (wp.dot(x4 - x2, eh) / l2)
        else:
            g = n1 * (wp.dot(x1 - x3, eh) / l1) + n2 * (wp.dot(x2 - x3, eh) / l2)
    return theta, g, ok


@wp.kernel
def solve_vertices(
    x: wp.array(dtype=wp.vec3),
    y: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    mass: wp.array(dtype=float),
    inv_mass: wp.array(dtype=float),
    order: wp.array(dtype=int),
    offset: int,
    inv_dt2: float,
    damp: float,
    tri: wp.array2d(dtype=int),
    rest_inv: wp.array(dtype=wp.mat22),
    area: wp.array(dtype=float),
    tri_start: wp.array(dtype=wp.vec2),
    tri_of_start: wp.array(dtype=int),
    tri_of: wp.array(dtype=int),
    k_weft: float,
    k_warp: float,
    k_shear: float,
    bend: wp.array2d(dtype=int),
    bend_w: wp.array(dtype=float),
    bend_rest: wp.array(dtype=float),
    bend_of_start: wp.array(dtype=int),
    bend_of: wp.array(dtype=int),
    k_bend: float,
    edge: wp.array2d(dtype=int),
    edge_rest: wp.array(dtype=float),
    edge_start: wp.array(dtype=float),
    edge_of_start: wp.array(dtype=int),
    edge_of: wp.array(dtype=int),
    k_edge: float,
    grow: wp.array(dtype=float),
    contact_point: wp.array(dtype=wp.vec3),
    contact_normal: wp.array(dtype=wp.vec3),
    contact_active: wp.array(dtype=int),
    thickness: float,
):
    """One Newton step of each vertex of one colour on the incremental potential, neighbours held;
    ``damp`` = k_d / dt, the stiffness-proportional (Rayleigh) damping over the substep's motion."""
    v = order[wp.tid() + offset]
    if inv_mass[v] == 0.0:
        return
    xv = x[v]
    m = mass[v] * inv_dt2
    g = grow[0]
    # the elastic force on v (minus the gradient of E) and its 3x3 Hessian block, positive
    # semi-definite: compressed springs lose their negative transverse part, bending is Gauss-Newton
    f = wp.vec3(0.0)
    h = wp.mat33(0.0)
    # membrane
    for q in range(tri_of_start[v], tri_of_start[v + 1]):
        p = tri_of[q]
        t = p // 4
        r = p - t * 4
        i = tri[t, 0]
        j = tri[t, 1]
        k = tri[t, 2]
        d = rest_inv[t]
        a = area[t]
        s0 = tri_start[t]
        ra = 1.0 + (s0[0] - 1.0) * (1.0 - g)
        rb = 1.0 + (s0[1] - 1.0) * (1.0 - g)
        e1 = x[j] - x[i]
        e2 = x[k] - x[i]
        fa = e1 * d[0, 0] + e2 * d[1, 0]
        fb = e1 * d[0, 1] + e2 * d[1, 1]
        ca = -(d[0, 0] + d[1, 0])
        cb = -(d[0, 1] + d[1, 1])
        if r == 1:
            ca = d[0, 0]
            cb = d[0, 1]
        elif r == 2:
            ca = d[1, 0]
            cb = d[1, 1]
        ga, ha = _axis_terms(fa, ra, k_weft * a, ca)
        gb, hb = _axis_terms(fb, rb, k_warp * a, cb)
        s = wp.dot(fa, fb)
        gs = fb * ca + fa * cb
        f = f - ga - gb - gs * (k_shear * a * s)
        h = (
            h
            + ha
            + hb
            + wp.outer(gs, gs) * (k_shear * a)
            + wp.identity(n=3, dtype=float) * (k_shear * a * wp.max(2.0 * s * ca * cb, 0.0))
        )
    # bending (Gauss-Newton Hessian)
    if k_bend > 0.0:
        for q in range(bend_of_start[v], bend_of_start[v + 1]):
            p = bend_of[q]
            b = p // 4
            r = p - b * 4
            theta, gr, ok = _dihedral(x[bend[b, 0]], x[bend[b, 1]], x[bend[b, 2]], x[bend[b, 3]], r)
            if ok == 1:
                c = theta - bend_rest[b]
                if c > wp.pi:
                    c = c - 2.0 * wp.pi
                if c < -wp.pi:
                    c = c + 2.0 * wp.pi
                kb = k_bend * bend_w[b]
                f = f - gr * (kb * c)
                h = h + wp.outer(gr, gr) * kb
    # edge springs
    for q in range(edge_of_start[v], edge_of_start[v + 1]):
        p = edge_of[q]
        e = p // 4
        r = p - e * 4
        rest = edge_rest[e] + (edge_start[e] - edge_rest[e]) * (1.0 - g)
        dv = x[edge[e, 1]] - x[edge[e, 0]]
        sign = float(1.0)
        if r == 0:
            sign = -1.0
        ge, he = _axis_terms(dv, rest, k_edge, sign)
        f = f - ge
        h = h + he
    f = f - h * (xv - x_prev[v]) * damp + (y[v] - xv) * m
    h = h * (1.0 + damp) + wp.identity(n=3, dtype=float) * m
    det = wp.determinant(h)
    if wp.abs(det) > 1.0e-20 * m * m * m:
        xv = xv + wp.inverse(h) * f
    # body contact: stay thickness outside the vertex's contact plane
    if contact_active[v] != 0:
        n = contact_normal[v]
        depth = thickness - wp.dot(xv - contact_point[v], n)
        if depth > 0.0:
            xv = xv + n * depth
    x[v] = xv


@wp.kernel
def update_velocity(
    x: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    acc: wp.array(dtype=wp.vec3),
    inv_dt: float,
):
    """Velocities from the position change, and the acceleration for the next start guess."""
    i = wp.tid()
    vn = (x[i] - x_prev[i]) * inv_dt
    acc[i] = (vn - v[i]) * inv_dt
    v[i] = vn
