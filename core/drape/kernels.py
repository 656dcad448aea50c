"""Warp kernels of the drape (one module: one compile; the body-contact search is :mod:`core.geom.queries`).

XPBD (Macklin et al. 2016) with small steps (Macklin et al. 2019): each
substep predicts positions, projects every constraint once, Gauss-Seidel
style, colour by colour (no two constraints of a colour share a particle, so
a colour runs in parallel without atomics and a run is bitwise repeatable),
resolves body contact, and derives velocities from the position change.

Constraints on a triangle with pattern (rest) edge matrix D_m in its grain
frame and current edges D_s = [x1-x0, x2-x0]: F = D_s D_m^-1 (3x2), whose
columns are the images of the unit weft and warp. Weft and warp stretch are
C = |F_i| - 1, shear is C = F_0 . F_1; each has compliance 1/(k A).
Bending is the dihedral angle of two triangles (rest: flat inside a panel, the
sewn fold across a seam), with the
weight |e|^2/(A_a+A_b): compliance 1/(bending * weight) stores bending * kappa^2 / 2 per area
on a smoothly bent isotropic mesh (:class:`core.drape.mesh.Cloth`).
"""

from __future__ import annotations

from ..geom.queries import wp  # Warp, set up once for the package (kernel cache, log level)

#: rad, the most one bending pass turns a hinge (its linearised angle change): where both triangles are
#: millimetres across (a refined mesh's pieces along pleat lines and seams) the hinge is as good as rigid
#: against their tiny masses, and the full Gauss-Seidel step against body contact overshoots and tears the
#: cloth (the knife-pleated skirt at 5 mm: 0.6 % of its area stretched past 300 % at frame 1)
BEND_REACH = wp.constant(0.5)


@wp.kernel
def predict(
    x: wp.array(dtype=wp.vec3),
    v: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    gravity: wp.vec3,
    dt: float,
    keep: float,
):
    i = wp.tid()
    x_prev[i] = x[i]
    if inv_mass[i] == 0.0:
        v[i] = wp.vec3(0.0, 0.0, 0.0)
        return
    vel = (v[i] + gravity * dt) * keep
    v[i] = vel
    x[i] = x[i] + vel * dt


@wp.func
def _project(
    x: wp.array(dtype=wp.vec3),
    i: int,
    j: int,
    k: int,
    wi: float,
    wj: float,
    wk: float,
    c: float,
    gj: wp.vec3,
    gk: wp.vec3,
    alpha: float,
):
    gi = -(gj + gk)
    denom = wi * wp.dot(gi, gi) + wj * wp.dot(gj, gj) + wk * wp.dot(gk, gk) + alpha
    if denom > 0.0:
        dl = -c / denom
        x[i] = x[i] + gi * (wi * dl)
        x[j] = x[j] + gj * (wj * dl)
        x[k] = x[k] + gk * (wk * dl)


@wp.func
def _project_axis(
    x: wp.array(dtype=wp.vec3),
    i: int,
    j: int,
    k: int,
    wi: float,
    wj: float,
    wk: float,
    d0: float,
    d1: float,
    rest: float,
    alpha: float,
):
    """Stretch along one grain direction, C = |F c| - rest, where c = (d0, d1) is its rest_inv column."""
    e1 = x[j] - x[i]
    e2 = x[k] - x[i]
    f = e1 * d0 + e2 * d1
    l = wp.length(f)
    if l > 1.0e-12:
        n = f / l
        _project(x, i, j, k, wi, wj, wk, l - rest, n * d0, n * d1, alpha)


@wp.kernel
def solve_stretch(
    x: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    tri: wp.array2d(dtype=int),
    rest_inv: wp.array(dtype=wp.mat22),
    area: wp.array(dtype=float),
    k_weft: float,
    k_warp: float,
    k_shear: float,
    inv_dt2: float,
    offset: int,
    start: wp.array(dtype=wp.vec2),
    grow: wp.array(dtype=float),
):
    t = wp.tid() + offset
    # rest stretch: from the start's (skintight) stretch to the pattern's (1) as grow goes 0 -> 1
    s0 = start[t]
    g = grow[0]
    rest_a = 1.0 + (s0[0] - 1.0) * (1.0 - g)
    rest_b = 1.0 + (s0[1] - 1.0) * (1.0 - g)
    i = tri[t, 0]
    j = tri[t, 1]
    k = tri[t, 2]
    wi = inv_mass[i]
    wj = inv_mass[j]
    wk = inv_mass[k]
    d = rest_inv[t]
    a = area[t]
    _project_axis(x, i, j, k, wi, wj, wk, d[0, 0], d[1, 0], rest_a, inv_dt2 / (k_weft * a))  # weft
    _project_axis(x, i, j, k, wi, wj, wk, d[0, 1], d[1, 1], rest_b, inv_dt2 / (k_warp * a))  # warp
    # shear: weft and warp images stay orthogonal
    e1 = x[j] - x[i]
    e2 = x[k] - x[i]
    fa = e1 * d[0, 0] + e2 * d[1, 0]
    fb = e1 * d[0, 1] + e2 * d[1, 1]
    _project(
        x,
        i,
        j,
        k,
        wi,
        wj,
        wk,
        wp.dot(fa, fb),
        fb * d[0, 0] + fa * d[0, 1],
        fb * d[1, 0] + fa * d[1, 1],
        inv_dt2 / (k_shear * a),
    )


@wp.kernel
def solve_distance(
    x: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    edge: wp.array2d(dtype=int),
    rest: wp.array(dtype=float),
    k: float,
    inv_dt2: float,
    offset: int,
    start: wp.array(dtype=float),
    grow: wp.array(dtype=float),
):
    """Edge length constraints (the edges of pattern slivers), compliance 1/k; rest grows like the triangles'."""
    e = wp.tid() + offset
    i = edge[e, 0]
    j = edge[e, 1]
    d = x[j] - x[i]
    l = wp.length(d)
    wi = inv_mass[i]
    wj = inv_mass[j]
    denom = wi + wj + inv_dt2 / k
    if l < 1.0e-12 or denom <= 0.0:
        return
    n = d / l
    dl = -(l - (rest[e] + (start[e] - rest[e]) * (1.0 - grow[0]))) / denom
    x[i] = x[i] - n * (wi * dl)
    x[j] = x[j] + n * (wj * dl)


@wp.kernel
def advance_grow(grow: wp.array(dtype=float), step: float):
    grow[0] = wp.min(grow[0] + step, 1.0)


@wp.kernel
def zero(values: wp.array(dtype=float)):
    values[wp.tid()] = 0.0


@wp.func
def dihedral(x1: wp.vec3, x2: wp.vec3, x3: wp.vec3, x4: wp.vec3):
    """Signed dihedral angle of the stencil (a, b, e0, e1) = (x1, x2, x3, x4), with the pieces of its
    gradients: the face normals n1, n2 (unnormalised), their squared lengths, the edge length and
    direction; ``ok`` 0 where a face or the edge is degenerate (theta 0 then)."""
    n1 = wp.cross(x3 - x1, x4 - x1)
    n2 = wp.cross(x4 - x2, x3 - x2)
    e = x4 - x3
    l1 = wp.length_sq(n1)
    l2 = wp.length_sq(n2)
    le = wp.length(e)
    theta = float(0.0)
    eh = wp.vec3(0.0)
    ok = int(0)
    if l1 >= 1.0e-20 and l2 >= 1.0e-20 and le >= 1.0e-10:
        ok = 1
        eh = e / le
        n1h = n1 / wp.sqrt(l1)
        n2h = n2 / wp.sqrt(l2)
        theta = wp.atan2(wp.dot(wp.cross(n1h, n2h), eh), wp.dot(n1h, n2h))
    return theta, n1, n2, l1, l2, le, eh, ok


@wp.kernel
def solve_bending(
    x: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    bend: wp.array2d(dtype=int),
    weight: wp.array(dtype=float),
    rest: wp.array(dtype=float),
    k_bend: float,
    inv_dt2: float,
    offset: int,
    lam: wp.array(dtype=float),
):
    """Dihedral-angle bending, XPBD with its multiplier ``lam`` accumulated over the iterations of a
    substep (zeroed at the substep's start): iterated, it converges to the implicit step's bending force,
    which the one-pass update under-delivers where the compliance is not large against the mass term."""
    b = wp.tid() + offset
    i = bend[b, 0]
    j = bend[b, 1]
    k = bend[b, 2]
    l = bend[b, 3]
    x1 = x[i]
    x2 = x[j]
    x3 = x[k]
    x4 = x[l]
    theta, n1, n2, l1, l2, le, eh, ok = dihedral(x1, x2, x3, x4)
    if ok == 0:
        return
    # exact dihedral-angle gradients (Bridson et al. 2003), signed to match theta
    g1 = n1 * (-le / l1)
    g2 = n2 * (-le / l2)
    g3 = n1 * (wp.dot(x4 - x1, eh) / l1) + n2 * (wp.dot(x4 - x2, eh) / l2)
    g4 = n1 * (wp.dot(x1 - x3, eh) / l1) + n2 * (wp.dot(x2 - x3, eh) / l2)
    w1 = inv_mass[i]
    w2 = inv_mass[j]
    w3 = inv_mass[k]
    w4 = inv_mass[l]
    alpha = inv_dt2 / (k_bend * weight[b])
    denom = w1 * wp.dot(g1, g1) + w2 * wp.dot(g2, g2) + w3 * wp.dot(g3, g3) + w4 * wp.dot(g4, g4) + alpha
    if denom <= 0.0:
        return
    c = theta - rest[b]
    # the shorter way round: no jump when a fold passes through +-pi
    if c > wp.pi:
        c = c - 2.0 * wp.pi
    if c < -wp.pi:
        c = c + 2.0 * wp.pi
    dl = -(c + alpha * lam[b]) / denom
    # a trust region: one pass turns the hinge by at most BEND_REACH (linearised); the fixed point
    # (dl = 0) is the same, but a stiff hinge between millimetre triangles no longer overshoots
    lin = denom - alpha
    if lin > 0.0:
        reach = BEND_REACH / lin
        dl = wp.clamp(dl, -reach, reach)
    lam[b] = lam[b] + dl
    x[i] = x1 + g1 * (w1 * dl)
    x[j] = x2 + g2 * (w2 * dl)
    x[k] = x3 + g3 * (w3 * dl)
    x[l] = x4 + g4 * (w4 * dl)


@wp.kernel
def solve_tethers(x: wp.array(dtype=wp.vec3), anchor: wp.array(dtype=int), length: wp.array(dtype=float), slack: float):
    """Long-range attachments: a particle stays within its fabric distance of its pin.

    The anchor is pinned (never moves), so particles are independent: no colouring.
    """
    i = wp.tid()
    a = anchor[i]
    if a < 0:
        return
    d = x[i] - x[a]
    l = wp.length(d)
    lmax = length[i] * slack
    if l > lmax:
        x[i] = x[a] + d * (lmax / l)


@wp.kernel
def find_self_pairs(
    x: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    x0: wp.array(dtype=wp.vec3),
    grid: wp.uint64,
    search: float,
    exclude: float,
    max_pairs: int,
    partner: wp.array2d(dtype=int),
    count: wp.array(dtype=int),
    ring_start: wp.array(dtype=int),
    ring: wp.array(dtype=int),
    touching: float,
):
    """Self-collision candidates of each particle: the others within ``search`` (at most ``max_pairs``).

    Fabric neighbours are left out: pairs that started closer than ``exclude``
    (skintight) and lie within two mesh rings of each other (``ring[ring_start[i]:
    ring_start[i + 1]]``), and pairs that started closer than ``touching`` (no room
    between them on the body). Pairs that start close but are far apart in the
    fabric (sleeve and side under the arm, the two legs at the crotch) do collide.
    The hash grid lists points in a fixed order (a radix sort), so the lists, and
    a CPU run, are repeatable.
    """
    i = wp.tid()
    count[i] = 0
    if inv_mass[i] == 0.0:
        return
    p = x[i]
    p0 = x0[i]
    c = int(0)
    query = wp.hash_grid_query(grid, p, search)
    j = int(0)
    while wp.hash_grid_query_next(query, j):
        if j != i and c < max_pairs:
            if wp.length(p - x[j]) < search:
                d0 = wp.length(p0 - x0[j])
                ok = int(1)
                if d0 <= touching:
                    ok = 0
                elif d0 <= exclude:
                    for k in range(ring_start[i], ring_start[i + 1]):
                        if ring[k] == j:
                            ok = 0
                if ok == 1:
                    partner[i, c] = j
                    c += 1
    count[i] = c


@wp.kernel
def self_collide(
    x: wp.array(dtype=wp.vec3),
    inv_mass: wp.array(dtype=float),
    partner: wp.array2d(dtype=int),
    count: wp.array(dtype=int),
    radius: float,
    dx: wp.array(dtype=wp.vec3),
):
    """Self-collision, particle against particle: keep the candidates ``2 radius`` apart.

    Jacobi style: each thread only writes its own correction (the average over
    its contacts, its inverse-mass share of each overlap), so the result does not
    depend on the thread order; :func:`apply_delta` adds it.
    """
    i = wp.tid()
    dx[i] = wp.vec3(0.0, 0.0, 0.0)
    c = count[i]
    if c == 0:
        return
    wi = inv_mass[i]
    p = x[i]
    d = 2.0 * radius
    corr = wp.vec3(0.0, 0.0, 0.0)
    hits = int(0)
    for k in range(c):
        j = partner[i, k]
        diff = p - x[j]
        l = wp.length(diff)
        if l < d and l > 1.0e-9:
            corr = corr + diff * ((d - l) / l * wi / (wi + inv_mass[j]))
            hits += 1
    if hits > 0:
        dx[i] = corr / float(hits)


@wp.kernel
def apply_delta(x: wp.array(dtype=wp.vec3), dx: wp.array(dtype=wp.vec3)):
    i = wp.tid()
    x[i] = x[i] + dx[i]


@wp.kernel
def contact_motion(
    points: wp.array(dtype=wp.vec3),
    active: wp.array(dtype=int),
    mesh: wp.uint64,
    max_dist: float,
    indices: wp.array(dtype=int),
    moved: wp.array(dtype=wp.vec3),
    carry: wp.array(dtype=wp.vec3),
):
    """A field ``moved`` (V, 3) on the body's vertices (their displacement over a substep) at each
    particle's closest point on the body (its contact search's: the same query from the same ``points``),
    interpolated on the face; 0 where the particle has no contact (``active[i]`` 0)."""
    i = wp.tid()
    carry[i] = wp.vec3(0.0, 0.0, 0.0)
    if active[i] == 0:
        return
    q = wp.mesh_query_point_no_sign(mesh, points[i], max_dist)
    if not q.result:
        return
    f = q.face
    carry[i] = (
        moved[indices[3 * f]] * q.u + moved[indices[3 * f + 1]] * q.v + moved[indices[3 * f + 2]] * (1.0 - q.u - q.v)
    )


@wp.kernel
def closest_contact(
    points: wp.array(dtype=wp.vec3),
    weight: wp.array(dtype=float),
    mesh: wp.uint64,
    max_dist: float,
    flat: float,
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec3),
    hit: wp.array(dtype=int),
):
    """The contact plane of each particle: through its closest point on the body, facing the particle.

    The normal is the direction from the closest point to the particle (away
    from it where the particle is inside): on a face it is the face normal, past
    a convex edge or corner it turns with the particle round the edge, so the
    cloth slides off the edge instead of resting on the extended plane of the
    last triangle. Within ``flat`` of the surface (where that direction is
    float noise) the face normal is taken. ``hit[i]`` is 0 where the body is
    farther than ``max_dist`` or the particle is pinned (``weight[i]`` 0).

    Inside or outside is the closest point's pseudo-normal's answer, and where that says inside,
    the mesh's winding number's (the mesh built with winding-number support,
    :func:`core.geom.queries.warp_mesh`). On a closed body the two agree. A layered collider
    (:func:`core.drape.layers.layer_collider`: an inner garment's offset surface with its folds,
    ramps sunk into the body) is not one closed surface, and there the pseudo-normal of a fold's
    far side says inside for a particle centimetres outside: contact threw it through the
    collider, and the jacket's sleeve ends over a shirt's cuffs never settled.
    """
    i = wp.tid()
    hit[i] = 0
    if weight[i] == 0.0:
        return
    p = points[i]
    q = wp.mesh_query_point_sign_normal(mesh, p, max_dist)
    if not q.result:
        return
    sign = q.sign
    if sign < 0.0:
        sign = wp.mesh_query_point_sign_winding_number(mesh, p, max_dist, 2.0, 0.5).sign
    c = wp.mesh_eval_position(mesh, q.face, q.u, q.v)
    n = wp.mesh_eval_face_normal(mesh, q.face)
    d = p - c
    dist = wp.length(d)
    if dist > flat:
        n = d * (sign / dist)
    point[i] = c
    normal[i] = n
    hit[i] = 1


@wp.kernel
def inside_winding(points: wp.array(dtype=wp.vec3), mesh: wp.uint64, inside: wp.array(dtype=int)):
    """``inside[i]`` 1 where the mesh's winding number at the point is over 1/2 (the mesh built with
    winding-number support, :func:`core.geom.queries.warp_mesh`), else 0."""
    i = wp.tid()
    inside[i] = 0
    q = wp.mesh_query_point_sign_winding_number(mesh, points[i], 1.0e6, 2.0, 0.5)
    if q.result and q.sign < 0.0:
        inside[i] = 1


@wp.kernel
def collide_body(
    x: wp.array(dtype=wp.vec3),
    x_prev: wp.array(dtype=wp.vec3),
    point: wp.array(dtype=wp.vec3),
    normal: wp.array(dtype=wp.vec3),
    active: wp.array(dtype=int),
    thickness: float,
    friction: float,
):
    """Keep particles ``thickness`` outside their contact plane (:func:`closest_contact`); Coulomb friction."""
    i = wp.tid()
    if active[i] == 0:
        return
    n = normal[i]
    p = x[i]
    depth = thickness - wp.dot(p - point[i], n)
    if depth <= 0.0:
        return
    p = p + n * depth
    # cancel the tangential motion of this substep up to mu * depth
    dx = p - x_prev[i]
    dt_ = dx - n * wp.dot(dx, n)
    lt = wp.length(dt_)
    if lt > 1.0e-12:
        p = p - dt_ * wp.min(friction * depth / lt, 1.0)
    x[i] = p


@wp.kernel
def update_velocity(
    x: wp.array(dtype=wp.vec3), x_prev: wp.array(dtype=wp.vec3), v: wp.array(dtype=wp.vec3), inv_dt: float
):
    i = wp.tid()
    v[i] = (x[i] - x_prev[i]) * inv_dt
