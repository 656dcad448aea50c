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
  ``bending * |e|^2 / (A_a + A_b) / cos^2(theta_0 / 2)``: the discrete-shell
  energy of :mod:`core.drape.newton` to second order in the angle. A hinge
  resting folded past 90 degrees (a pressed crease) takes the difference of its
  two sides instead, ``2 cos(theta / 2)`` along the difference of the normals,
  weight ``/ sin^2(theta_0 / 2)``: the same stiffness at any rest angle.

So, to second order in strain and angle, it is the energy :mod:`core.drape.newton`
minimises (the preset's physical stiffness), and the system matrix
``M / dt^2 + sum_c w_c A_c^T A_c`` does not change: it is factored once per
cloth (an LDL^T on the free particles, qdldl's AMD ordering: the same n x n
matrix for x, y and z, back-substituted for the three at once, :class:`Factor3`)
and each iteration is one pass of a native kernel on the host (the images, the
projections, the gradient and the energy, :func:`pd_gradient`) plus one
back-substitution (the global step). Body contact enters the solve as a penalty
on the particles at their contact plane's offset (chosen at each contact search,
its weight in the matrix's diagonal, refactored when that set changes:
:attr:`ProjectiveStep.contact_weight`); after each substep's solve, as with the
other solvers, the Warp kernels keep every particle on its contact plane's offset
with friction, then tethers and self-collision. (A projection onto the planes
inside the iterations fought the stiff membrane where neighbouring planes diverge,
at the armpits, and tore the shirt; contact after the solve alone tore most of
the coarse shirt's gap-curve drapes.)

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

wp.set_module_options({"enable_backward": False})

#: body contact inside the solve: the penalty's weight in units of the median diagonal entry of the step's
#: matrix (:attr:`ProjectiveStep.contact_weight`); 0: contact only after each substep's solve, which tore
#: 8 of the 15 drapes of the 3 cm shirt's gap curve (the stiff membrane's solve pulls the cloth through
#: the body, the contact pushes it back apart); with it all 30 of shirt and pants settle or run out their
#: frames whole, for about 18 % more time a frame (a refactorisation per contact search;
#: benchmarks/results/drape_pd.md)
CONTACT_WEIGHT = 1.0
#: the contact penalty holds the particles whose height over their contact plane is under this many offsets
HELD_HEIGHT = 1.05
#: cap each grain spring's compressive stress at its element's Euler load, as :class:`NewtonStep` does
#: (:func:`core.drape.newton.buckling_stress`; :attr:`ProjectiveStep.buckling`). Off: with it the Cusick
#: disc converges in the iterations (cotton 64.4 / 63.9 / 64.4 % at 10 / 40 / 160 at 10 mm, 72.2 / 70.7 % at
#: 5 mm; silk 33.1 %, inside 20-40, where pd reads 44.8 % without it) but not in the mesh (cotton 64 % at 10
#: mm, 71-72 % at 5 mm: the cap grows as 1 / h^2 and the disc's DC follows it), and a garment's compressed
#: fabric gives way instead of folding: the tube skirt's fabric below its gathered waistband sits 15 % (p95)
#: off its pattern lengths, against under 1 % without it (benchmarks/results/drape_pd.md, session 6 p10)
BUCKLING = False
#: the iterations' method (:attr:`ProjectiveStep.method`): Anderson-accelerated local-global steps, or
#: "lbfgs" (L-BFGS with the factored matrix as its initial inverse Hessian). A frontier, measured (session 7,
#: benchmarks/results/drape_pd.md): on the Cusick disc (10 mm with the clamp band, mean of 4 specimens)
#: Anderson's fold count follows the iteration count for wool (55.1 % at 10 iterations, 62.1 % at 40) where
#: L-BFGS reads 61.2 / 62.5 %, but L-BFGS moves silk -3.3 points at 4x the iterations (8 specimens; Anderson
#: -2.9 with 4), and on the garments L-BFGS leaves the loose drapes unsettled: the full gap curve (1.5 cm,
#: self-collision, 17 levels x 3 growths) settled 47 of 51 shirt and 51 of 51 pants drapes with Anderson,
#: 29 and 41 with L-BFGS, with one step down of 0.4 mm (shirt, ease 2.119 -> 2.212) against four of up to
#: 2.9 mm. The garment is what a user drapes, so Anderson is the default.
METHOD = "anderson"
#: self-collision inside the solve: each candidate pair closer than its diameter along the pair's direction
#: at the substep's start is pushed apart by the penalty ``self_weight / 2 * (diameter - separation)^2``,
#: this many median diagonal entries of the step's matrix (as the body's, :data:`CONTACT_WEIGHT`); 0:
#: self-collision only after each substep's solve, whose projections the stiff membrane's next solve
#: undoes: on the 1.5 cm shirt at ease 1.93 a thousand particles were pushed about 1 mm every substep, the
#: drape never settled and the fabric stretched 6 % (p95). The penalty is not in the matrix (its pairs
#: change every substep, and its diagonal there, in x, y and z alike, held stacked layers from sliding over
#: each other: the loose shirts crept for 150 frames), so a plain step that raises G is halved, at most
#: :data:`SELF_BACKTRACK` times (benchmarks/results/drape_pd.md, session 7 p1)
SELF_WEIGHT = 1.0
SELF_BACKTRACK = 6
#: Coulomb friction against the body inside the solve (:attr:`ProjectiveStep.anchor`, set each substep by
#: the drape where this is on). Without it pd has no Coulomb friction: the contact penalty's weight sits
#: in every direction of the matrix's diagonal, so at the default 10 iterations a held particle barely
#: moves along the body from its start guess (a sheet on a 20 degree plane sticks at mu 0.2, 0.4 mm in
#: 1 s where XPBD slides 19 cm), converged it slides at any mu (the kernels' friction after the solve
#: scales with a depth the penalty already removed), and on a moving body the garment stays behind
#: (the rig-action test: 4.8 of 6.0 cm). With it the sheet sticks at mu 0.5 and slides 19.9 cm at mu 0.2
#: (XPBD 19.1) and the rig test passes, but the 1.5 cm shirt at ease 1.2 ends its 60 frames unsettled,
#: stretched 5.1 / 14.8 % (weft / warp p95) against 0.46 / 0.70 % without: the normal force it bounds
#: friction with is the inertial target's depth only (a tight garment's is its tension), so where the
#: inertial motion carries a particle past the stop the solve cannot pull it back (adding the fabric's
#: push into the body to F_n: 1.7 / 6.6 %, but the sheet on the plane lifts and slides 7.8 cm). Off until
#: that is resolved (session 7 p7; the shirt: benchmarks.bench_drape's pattern, drape(max_frames=60))
FRICTION = False

#: the strain limit's weight where :class:`ProjectiveStep` is given none (:attr:`ProjectiveStep.limit_weight`;
#: :attr:`DrapeOptions.strain_limit`, 0 by default: off): each grain image (weft, warp) of a triangle longer
#: than ``1 + max_stretch`` (the material's) times its rest length is pulled back by the penalty
#: ``w / 2 (|f| - L_max)^2`` on the excess only, ``w`` this many times the grain spring's own weight. Measured
#: (benchmarks/results/drape_strain_limit.md, eighth session p1): a soft sheet that hangs 12.1 % stretched
#: (warp p95) hangs at 5.64 / 5.23 / 5.07 % with 10 / 30 / 100 (1000: unsettled after 60 frames); but the
#: body's contact after each solve keeps a garment outside the body, so the limit cannot shorten fabric that
#: wraps a body larger than its pattern: at 30 the pants at ease 0.9 / 0.994 in cotton (1.5 cm) read weft
#: p95 18.4 / 7.0 % against 18.1 / 6.7 % without and settle in 42 / 68 frames against 29 / 48 (at 100 they
#: did not settle in 250), so it is off by default
STRAIN_LIMIT = 0.0
#: the strain limit on a triangle the body's contact penalty holds (a particle of it on the body): off. The
#: contact after each solve keeps the cloth outside the body, so a limit there cannot shorten fabric that
#: wraps a body larger than its pattern: it pulls the cloth into the body's concave creases, where the
#: contact puts it back on the surface, longer; on the pants at ease 0.9 in cotton (1.5 cm) the weft
#: stretch rose from 18.1 to 22.8 % (p95) with it (benchmarks/results/drape_strain_limit.md)
LIMIT_ON_BODY = False

F64 = wp.float64


_GRADIENT = r"""
const int* ip = (const int*)Dp.data; const int* ci = (const int*)Di.data; const double* dv = (const double*)Dx.data;
const double* xx = (const double*)x.data; const double* yy = (const double*)y.data;
const double* m = (const double*)inertia.data; const double* rw = (const double*)row_w.data;
double* img = (double*)images.data; double* tg = (double*)target.data; double* o = (double*)out.data;
const double* ra = (const double*)rest_a.data; const double* rb = (const double*)rest_b.data;
const double* wa = (const double*)w_a.data; const double* wb = (const double*)w_b.data;
const double* wsh = (const double*)w_s.data; const double* el = (const double*)edge_len.data;
const int* bd = (const int*)bends.data; const double* kb = (const double*)k_bend.data;
const double* hr = (const double*)hinge_rest.data; double* en = (double*)energy.data;
const double* hs = (const double*)hinge_side.data;
const int* bl = (const int*)blocks.data;
const double* cpa = (const double*)cap_a.data; const double* cpb = (const double*)cap_b.data;
const int o1 = bl[1], o2 = bl[2], o3 = bl[3], o4 = bl[4];
/* every linear image: D x */
for (int r = 0; r < o4; r++) {
    double a0 = 0.0, a1 = 0.0, a2 = 0.0;
    for (int j = ip[r]; j < ip[r + 1]; j++) {
        const double* p = xx + 3 * ci[j];
        double c = dv[j];
        a0 += c * p[0]; a1 += c * p[1]; a2 += c * p[2];
    }
    img[3 * r] = a0; img[3 * r + 1] = a1; img[3 * r + 2] = a2;
}
double e_el = 0.0;
/* triangles: the weft / warp images onto their rest stretch's sphere and, as a pair, onto the nearest
   orthogonal pair */
for (int i = 0; i < o1; i++) {
    const double* a = img + 3 * i; const double* b = img + 3 * (o1 + i);
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    /* the sphere's radius: the rest stretch, or, compressed past the buckling strain c, the length + c
       (the stress capped at the element's Euler load: w psi(e) = min over t <= rest of
       w / 2 (l - t)^2 + w c (rest - t), psi quadratic down to e = -c and linear past it) */
    double ta_len = ra[i], tb_len = rb[i];
    if (la + cpa[i] < ta_len) ta_len = la + cpa[i];
    if (lb + cpb[i] < tb_len) tb_len = lb + cpb[i];
    double sa[3] = {ta_len, 0.0, 0.0}, sb[3] = {tb_len, 0.0, 0.0};
    if (la > 1.0e-15) { double f = ta_len / la; sa[0] = a[0] * f; sa[1] = a[1] * f; sa[2] = a[2] * f; }
    if (lb > 1.0e-15) { double f = tb_len / lb; sb[0] = b[0] * f; sb[1] = b[1] * f; sb[2] = b[2] * f; }
    if (ta_len < ra[i]) e_el += wa[i] * cpa[i] * (ra[i] - ta_len);
    if (tb_len < rb[i]) e_el += wb[i] * cpb[i] * (rb[i] - tb_len);
    double s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double t = la * la + lb * lb;
    double q4 = t * t - 4.0 * s * s;
    double disc = sqrt(q4 > 0.0 ? q4 : 0.0);
    double mu = t > 0.0 ? 2.0 * s / (t + disc) : 0.0;
    double den = 1.0 - mu * mu;
    if (fabs(den) < 1.0e-12) den = 1.0e-12;
    double e = 0.0, es = 0.0;
    double* ta = tg + 3 * i; double* tb = tg + 3 * (o1 + i);
    for (int k = 0; k < 3; k++) {
        double p = (a[k] - b[k] * mu) / den, q = (b[k] - a[k] * mu) / den;
        ta[k] = sa[k] * wa[i] + p * wsh[i];
        tb[k] = sb[k] * wb[i] + q * wsh[i];
        e += wa[i] * (a[k] - sa[k]) * (a[k] - sa[k]) + wb[i] * (b[k] - sb[k]) * (b[k] - sb[k]);
        es += (a[k] - p) * (a[k] - p) + (b[k] - q) * (b[k] - q);
    }
    e_el += 0.5 * (e + wsh[i] * es);
}
/* sliver edges onto the sphere of their rest length */
for (int r = o2; r < o3; r++) {
    const double* a = img + 3 * r; double* t = tg + 3 * r;
    double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double s[3] = {el[r - o2], 0.0, 0.0};
    if (la > 1.0e-15) { double f = el[r - o2] / la; s[0] = a[0] * f; s[1] = a[1] * f; s[2] = a[2] * f; }
    double e = 0.0;
    for (int k = 0; k < 3; k++) { t[k] = s[k] * we; e += (a[k] - s[k]) * (a[k] - s[k]); }
    e_el += 0.5 * we * e;
}
/* hinges: the hinge vector's normal component onto its rest value */
for (int r = o3; r < o4; r++) {
    const int* q = bd + 4 * (r - o3);
    const double* x1 = xx + 3 * q[0]; const double* x2 = xx + 3 * q[1];
    const double* x3 = xx + 3 * q[2]; const double* x4 = xx + 3 * q[3];
    double u[3], v[3], n1[3], n2[3], nn[3];
    for (int k = 0; k < 3; k++) { u[k] = x3[k] - x1[k]; v[k] = x4[k] - x1[k]; }
    n1[0] = u[1] * v[2] - u[2] * v[1]; n1[1] = u[2] * v[0] - u[0] * v[2]; n1[2] = u[0] * v[1] - u[1] * v[0];
    for (int k = 0; k < 3; k++) { u[k] = x4[k] - x2[k]; v[k] = x3[k] - x2[k]; }
    n2[0] = u[1] * v[2] - u[2] * v[1]; n2[1] = u[2] * v[0] - u[0] * v[2]; n2[2] = u[0] * v[1] - u[1] * v[0];
    double l1 = sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
    double l2 = sqrt(n2[0] * n2[0] + n2[1] * n2[1] + n2[2] * n2[2]);
    l1 = l1 > 1.0e-30 ? l1 : 1.0e-30; l2 = l2 > 1.0e-30 ? l2 : 1.0e-30;
    for (int k = 0; k < 3; k++) nn[k] = n1[k] / l1 + hs[r - o3] * n2[k] / l2;
    double ln = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    ln = ln > 1.0e-30 ? ln : 1.0e-30;
    for (int k = 0; k < 3; k++) nn[k] /= ln;
    const double* h = img + 3 * r; double* t = tg + 3 * r;
    double c = h[0] * nn[0] + h[1] * nn[1] + h[2] * nn[2] - hr[r - o3];
    for (int k = 0; k < 3; k++) t[k] = (h[k] - nn[k] * c) * kb[r - o3];
    e_el += 0.5 * kb[r - o3] * c * c;
}
/* the gradient: inertia (x - y) + D^T (W D x - target), scattered row by row */
double e_in = 0.0;
for (int i = 0; i < 3 * n; i++) { double d = xx[i] - yy[i]; o[i] = m[i / 3] * d; e_in += m[i / 3] * d * d; }
for (int r = 0; r < o4; r++) {
    double w = rw[r];
    double u0 = w * img[3 * r] - tg[3 * r], u1 = w * img[3 * r + 1] - tg[3 * r + 1], u2 = w * img[3 * r + 2] - tg[3 * r + 2];
    for (int j = ip[r]; j < ip[r + 1]; j++) {
        double* t = o + 3 * ci[j];
        double c = dv[j];
        t[0] += c * u0; t[1] += c * u1; t[2] += c * u2;
    }
}
en[0] = 0.5 * e_in;
en[1] = e_el;
"""


@wp.func_native(_GRADIENT)
def _gradient_native(
    n: int,
    blocks: wp.array(dtype=wp.int32),
    Dp: wp.array(dtype=wp.int32),
    Di: wp.array(dtype=wp.int32),
    Dx: wp.array(dtype=F64),
    x: wp.array(dtype=F64),
    y: wp.array(dtype=F64),
    inertia: wp.array(dtype=F64),
    row_w: wp.array(dtype=F64),
    rest_a: wp.array(dtype=F64),
    rest_b: wp.array(dtype=F64),
    cap_a: wp.array(dtype=F64),
    cap_b: wp.array(dtype=F64),
    w_a: wp.array(dtype=F64),
    w_b: wp.array(dtype=F64),
    w_s: wp.array(dtype=F64),
    edge_len: wp.array(dtype=F64),
    we: F64,
    bends: wp.array(dtype=wp.int32),
    k_bend: wp.array(dtype=F64),
    hinge_rest: wp.array(dtype=F64),
    hinge_side: wp.array(dtype=F64),
    images: wp.array(dtype=F64),
    target: wp.array(dtype=F64),
    out: wp.array(dtype=F64),
    energy: wp.array(dtype=F64),
): ...


@wp.kernel
def pd_gradient(
    n: int,
    blocks: wp.array(dtype=wp.int32),
    Dp: wp.array(dtype=wp.int32),
    Di: wp.array(dtype=wp.int32),
    Dx: wp.array(dtype=F64),
    x: wp.array(dtype=F64),
    y: wp.array(dtype=F64),
    inertia: wp.array(dtype=F64),
    row_w: wp.array(dtype=F64),
    rest_a: wp.array(dtype=F64),
    rest_b: wp.array(dtype=F64),
    cap_a: wp.array(dtype=F64),
    cap_b: wp.array(dtype=F64),
    w_a: wp.array(dtype=F64),
    w_b: wp.array(dtype=F64),
    w_s: wp.array(dtype=F64),
    edge_len: wp.array(dtype=F64),
    we: F64,
    bends: wp.array(dtype=wp.int32),
    k_bend: wp.array(dtype=F64),
    hinge_rest: wp.array(dtype=F64),
    hinge_side: wp.array(dtype=F64),
    images: wp.array(dtype=F64),
    target: wp.array(dtype=F64),
    out: wp.array(dtype=F64),
    energy: wp.array(dtype=F64),
):
    """The local step and the gradient of the step's potential G in one pass (float64, on the host; all
    vectors (., 3) interleaved, ``n`` particles):

    * ``images = D x``: every linear image, rows in blocks ``blocks`` (weft, warp, sliver edges, hinges);
    * the projections (their weighted targets into ``target``): each triangle's weft / warp images onto
      their rest stretch's sphere (``rest_a``, ``rest_b``; weights ``w_a``, ``w_b``), or, compressed past
      the buckling strain (``cap_a``, ``cap_b``; inf: none), onto the sphere ``length + cap`` (the
      stress capped, :attr:`ProjectiveStep.buckling`), and, as a pair, onto
      the nearest orthogonal pair (:func:`orthogonal_pair`, weight ``w_s``); each sliver edge onto the
      sphere of its rest length (``edge_len``, weight ``we``); each hinge vector's normal component
      (:func:`hinge_normals`, from the stencil ``bends`` (B, 4); ``hinge_side`` -1 where it is folded,
      :func:`folded_hinges`) onto ``hinge_rest`` (weight ``k_bend``);
    * ``out = inertia (x - y) + D^T (W images - target)``, W = ``row_w``, scattered row by row;
    * ``energy[0]`` the inertial part of G, ``energy[1]`` the constraints' (each weighted squared
      distance, halved).

    One thread, everything in a fixed order: the same bits on every run."""
    _gradient_native(
        n,
        blocks,
        Dp,
        Di,
        Dx,
        x,
        y,
        inertia,
        row_w,
        rest_a,
        rest_b,
        cap_a,
        cap_b,
        w_a,
        w_b,
        w_s,
        edge_len,
        we,
        bends,
        k_bend,
        hinge_rest,
        hinge_side,
        images,
        target,
        out,
        energy,
    )


_SOLVE3 = r"""
const int* pp = (const int*)P.data; const int* lp = (const int*)Lp.data; const int* li = (const int*)Li.data;
const double* lx = (const double*)Lx.data; const double* dinv = (const double*)Dinv.data;
const double* bb = (const double*)b.data; double* w = (double*)work.data; double* xx = (double*)x.data;
for (int i = 0; i < n; i++) { const double* s = bb + 3 * pp[i]; w[3 * i] = s[0]; w[3 * i + 1] = s[1]; w[3 * i + 2] = s[2]; }
for (int i = 0; i < n; i++) {
    double v0 = w[3 * i], v1 = w[3 * i + 1], v2 = w[3 * i + 2];
    for (int j = lp[i]; j < lp[i + 1]; j++) {
        double* t = w + 3 * li[j];
        double l = lx[j];
        t[0] -= l * v0; t[1] -= l * v1; t[2] -= l * v2;
    }
}
for (int i = 0; i < n; i++) { double d = dinv[i]; w[3 * i] *= d; w[3 * i + 1] *= d; w[3 * i + 2] *= d; }
for (int i = n - 1; i >= 0; i--) {
    double v0 = w[3 * i], v1 = w[3 * i + 1], v2 = w[3 * i + 2];
    for (int j = lp[i]; j < lp[i + 1]; j++) {
        const double* t = w + 3 * li[j];
        double l = lx[j];
        v0 -= l * t[0]; v1 -= l * t[1]; v2 -= l * t[2];
    }
    w[3 * i] = v0; w[3 * i + 1] = v1; w[3 * i + 2] = v2;
}
for (int i = 0; i < n; i++) { double* t = xx + 3 * pp[i]; t[0] = w[3 * i]; t[1] = w[3 * i + 1]; t[2] = w[3 * i + 2]; }
"""


@wp.func_native(_SOLVE3)
def _solve3(
    n: int,
    P: wp.array(dtype=wp.int32),
    Lp: wp.array(dtype=wp.int32),
    Li: wp.array(dtype=wp.int32),
    Lx: wp.array(dtype=F64),
    Dinv: wp.array(dtype=F64),
    b: wp.array(dtype=F64),
    work: wp.array(dtype=F64),
    x: wp.array(dtype=F64),
): ...


@wp.kernel
def ldl_solve3(
    n: int,
    P: wp.array(dtype=wp.int32),
    Lp: wp.array(dtype=wp.int32),
    Li: wp.array(dtype=wp.int32),
    Lx: wp.array(dtype=F64),
    Dinv: wp.array(dtype=F64),
    b: wp.array(dtype=F64),
    work: wp.array(dtype=F64),
    x: wp.array(dtype=F64),
):
    """``x`` (n, 3 interleaved) = A^-1 ``b`` (n, 3 interleaved) from A's LDL^T (QDLDL's factors: ``P`` the
    ordering, L strictly lower in CSC, 1 / D): x, y and z back-substituted in one pass over L (``work``:
    3 n scratch)."""
    _solve3(n, P, Lp, Li, Lx, Dinv, b, work, x)


class Factor3:
    """The LDL^T of the free particles' matrix (qdldl's AMD ordering and factors), solved for x, y and z
    at once by :func:`ldl_solve3`: one pass over L for three right-hand sides (SuperLU solves them
    column by column; measured on the 1.5 cm shirt's 5401 x 5401 matrix, 0.68 ms against 1.47 ms, its
    L 214 382 non-zeros against SuperLU's 462 750 in L + U).

    ``A``: canonical CSC (sorted indices, no duplicates). :meth:`refactor` takes new values on its pattern:
    where the pattern solver's kernels run (:mod:`core.pattern.accel.ldl`), only the rows of L the changed
    columns reach are recomputed (on the shirt, a contact set's diagonal: about 6 ms against qdldl's 10 ms
    for the whole numeric factorisation and its factors' copy), else qdldl refactors it all."""

    def __init__(self, A):
        import qdldl
        from scipy.sparse import csc_matrix

        n = A.shape[0]
        cols = np.repeat(np.arange(n), np.diff(A.indptr))
        keep = np.flatnonzero(A.indices <= cols)
        ptr = np.concatenate([[0], np.cumsum(np.bincount(cols[keep], minlength=n))]).astype(A.indptr.dtype)
        self._upper = (keep, A.indices[keep], ptr)
        self._qdldl = qdldl.Solver(csc_matrix((A.data[keep], A.indices[keep], ptr), shape=A.shape), upper=True)
        self._ldl = self._rows_factor(A)
        self.n = n
        i32 = np.int32
        if self._ldl is not None:
            plan = self._ldl.plan
            self._host = [plan.P, plan.Lp, plan.Li, self._ldl.Lx, self._ldl.Dinv]  # refactored in place
        else:
            L, D, P = self._qdldl.factors()
            self._host = [
                np.ascontiguousarray(P, i32),
                np.ascontiguousarray(L.indptr, i32),
                np.ascontiguousarray(L.indices, i32),
                np.ascontiguousarray(L.data, float),
                1.0 / np.asarray(D, float),
            ]
        self.b, self.x, work = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros(3 * n)
        arrays = [*self._host, self.b.reshape(-1), work, self.x.reshape(-1)]
        self._work = work
        self._cmd = wp.launch(
            ldl_solve3,
            dim=1,
            device="cpu",
            record_cmd=True,
            inputs=[n, *(wp.array(a, device="cpu", copy=False) for a in arrays)],
        )

    def _rows_factor(self, A):
        """The pattern solver's row-wise LDL of qdldl's factors (None where its kernels do not run)."""
        from ..pattern.accel import compiled

        if not compiled.enabled():
            return None
        from ..pattern.accel.ldl import LDL

        return LDL.from_qdldl(self._qdldl, self._upper, np.array(A.data, float))

    def refactor(self, A) -> None:
        """Factorise ``A`` (the same sparsity pattern, new values) in place."""
        from scipy.sparse import csc_matrix

        if self._ldl is not None:
            try:
                if self._ldl.refactorise(np.array(A.data, float)):
                    return
            except ValueError:
                pass
            self._ldl = None  # the kernels gave up, or a zero pivot: qdldl from here on
        keep, rows, ptr = self._upper
        self._qdldl.update(csc_matrix((A.data[keep], rows, ptr), shape=A.shape), upper=True)
        L, D, _ = self._qdldl.factors()
        self._host[3][:] = L.data
        self._host[4][:] = 1.0 / np.asarray(D, float)

    def solve(self, v: np.ndarray) -> np.ndarray:
        """A^-1 v, v (n, 3): a new (n, 3) array."""
        self.b[:] = v
        self._cmd.launch()
        return self.x.copy()


def _tangential(v: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(k, 3) ``v`` less its component along the unit ``normal`` (k, 3): its part along the body."""
    return v - np.einsum("ij,ij->i", v, normal)[:, None] * normal


def hinge_coefficients(cloth: Cloth) -> np.ndarray:
    """(B, 4) the flat rest hinge's dihedral-angle gradients along its normal, per stencil particle
    (a, b, e0, e1): ``theta ~ n . sum_i alpha_i x_i`` near the rest shape (Bridson et al. 2003's gradients
    on the hinge unfolded flat from its two pattern triangles); zero where a triangle is degenerate. A
    folded hinge (:func:`folded_hinges`) takes side b's away instead of adding it."""
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
    sb = np.where(folded_hinges(cloth.bend_rest), -1.0, 1.0)  # a folded hinge: side b's vector taken away
    out[:, 0] = -1.0 / ya
    out[:, 1] = -sb / yb
    out[:, 2] = (la - xa) / (la * ya) + sb * (lb - xb) / (lb * yb)
    out[:, 3] = xa / (la * ya) + sb * xb / (lb * yb)
    out[~ok] = 0.0
    return out


def folded_hinges(bend_rest: np.ndarray) -> np.ndarray:
    """(B,) bool: the hinges resting folded past 90 degrees, whose hinge vector is the difference of its two
    sides' (:func:`hinge_coefficients`, :func:`hinge_normals`)."""
    return np.abs(np.asarray(bend_rest, float)) > 0.5 * np.pi


def hinge_normals(x: np.ndarray, bends: np.ndarray, folded=None) -> np.ndarray:
    """(B, 3) unit normal of each hinge (a, b, e0, e1): the mean of its two triangles' unit normals. The
    hinge vector of :func:`hinge_coefficients` is ``2 sin(theta / 2)`` times it for an isometric bend.
    ``folded`` (B,) bool (:func:`folded_hinges`): there the difference of the two unit normals, along
    which a folded hinge's vector is ``2 cos(theta / 2)`` (signed: through 180 degrees it turns over)."""
    x1, x2, x3, x4 = (x[bends[:, k]] for k in range(4))
    n1 = row_cross(x3 - x1, x4 - x1)
    n2 = row_cross(x4 - x2, x3 - x2)
    nrm = n1 / np.maximum(np.linalg.norm(n1, axis=1), 1e-30)[:, None]
    sb = 1.0 if folded is None else np.where(folded, -1.0, 1.0)[:, None]
    nrm += sb * n2 / np.maximum(np.linalg.norm(n2, axis=1), 1e-30)[:, None]
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


def _flat(a: np.ndarray):
    """A flat Warp view (no copy) of a contiguous float64 or int32 array on the host."""
    assert a.flags.c_contiguous
    return wp.array(a.reshape(-1), device="cpu", copy=False)


class ProjectiveStep:
    """The host-side projective-dynamics step of one cloth: its constraints, the factored matrix, the solve.

    Parameters
    ----------
    cloth, material, dt, mass, start_stretch, edge_start : as :class:`core.drape.newton.NewtonStep`'s.
    history : the acceleration's depth (0: plain local-global iterations).
    buckling : None (:data:`BUCKLING`) or bool: cap each grain spring's compressive stress at its element's
        Euler load (NewtonStep's ``cap_a``, ``cap_b``): a grain image compressed past that strain c is
        projected onto the sphere of its length + c instead of its rest stretch, so its force stays at the
        cap, and the potential gains ``w c (rest - target)``: the energy NewtonStep minimises.
    strain_limit : None (:data:`STRAIN_LIMIT`) or float >= 0: :attr:`limit_weight` in multiples of each grain
        spring's weight (0: no limit).

    Attributes
    ----------
    elements : the :class:`core.drape.newton.NewtonStep` of the same cloth, whose element operators
        (grain images, edges, hinges, rest shapes) this step projects.
    matrix : (P, P) sparse, ``M / dt^2 + sum_c w_c A_c^T A_c`` (the same for x, y and z).
    method : ``"anderson"`` (default, :data:`METHOD`: Anderson-accelerated local-global iterations),
        ``"lbfgs"`` (L-BFGS with the factored matrix as its initial inverse Hessian) or ``"newton"`` (Gauss-Newton
        steps by conjugate gradients preconditioned with the factored matrix, :meth:`_newton`; an
        experiment: 4x fewer back-substitutions than Anderson on a clamped creased strip, but on the
        Cusick disc it does not settle, and at 5 mm edges the specimen falls off the support, so the
        drape's options do not offer it; benchmarks/results/drape_pd.md).
    contact_weight : N/m, the body-contact penalty inside the solve (:data:`CONTACT_WEIGHT` times the
        matrix's median diagonal entry; 0: none, contact only after the solve). Where positive, each
        contact search's particles on the body (within :data:`HELD_HEIGHT` times the contact offset of
        their plane) are held by ``contact_weight / 2 * depth^2`` (depth below the offset), its weight in
        the matrix's diagonal (refactored when that set changes), and the stop test counts the normal
        force and allows friction up to ``friction`` times the penalty's force.
    refactors : int, the refactorisations the contact penalty's and the strain limit's set changes asked for.
    limit_weight : the strain limit's weight, in multiples of each grain spring's (:data:`STRAIN_LIMIT`; 0:
        none), and ``max_stretch`` the material's. The limit's set is the grains (a triangle's weft or warp
        image) that ended the last solve longer than ``L_max = (1 + max_stretch)`` times their rest length,
        but for a triangle the contact penalty holds on the body (:data:`LIMIT_ON_BODY`): in the next solve
        each is a projective constraint onto the ball of radius ``L_max`` (energy ``w / 2 (|f| - L_max)^2``
        past it, none inside), its weight ``w`` in the matrix (refactored when the set changes, on a garment
        at its contact searches only), so the local-global step still lowers G. The set is taken from the end
        of a solve, not from its start guess: the inertial guess and the unconverged solves of the first
        frames of growth stretch thousands of the shirt's grains past 5 % for a substep, and a grain in the set
        but inside its ball is held where it is by the matrix's weight (such a set, kept until a grain fell
        under half its limit, held the 1.5 cm shirt's fabric at 4.7 % (weft p95) where it settles at 0.7 %).
        An empty set (no grain ever ends a solve past its limit) leaves the matrix, the iterations and the
        drape as they are without the limit, bit for bit.
    limited : int, the grains in the limit's set at the last solve.
    """

    def __init__(
        self,
        cloth: Cloth,
        material,
        dt: float,
        mass: np.ndarray,
        start_stretch,
        edge_start,
        history: int = 5,
        buckling=None,
        strain_limit=None,
    ):
        from scipy.sparse import diags, vstack

        el = NewtonStep(cloth, material, dt, mass, start_stretch, edge_start)
        self.elements, self.n, self.history = el, el.n, int(history)
        self.buckling = BUCKLING if buckling is None else bool(buckling)
        self.free, self.free_idx = el.free, el.free_idx
        self.inertia = el.inertia
        self.ws = 2.0 * el.ws  # the orthogonal pair's distance^2 is (f_a . f_b)^2 / 2
        bends = el.bends
        self.Gh = _rows(len(bends), self.n, bends, hinge_coefficients(cloth))
        # each hinge vector's normal component at rest: 2 sin(theta_0 / 2) (0 inside a panel); a hinge resting
        # folded past 90 degrees (a pressed crease, a seam sewn folded) measures 2 cos(theta / 2) instead, along
        # the normals' difference (:func:`folded_hinges`): 2 sin(theta / 2) stops turning towards 180 degrees
        # (a pressed crease's 172: slope cos(86 deg) = 0.07), 2 cos(theta / 2) turns on through it
        half = 0.5 * el.bend_rest
        self.folded = folded_hinges(el.bend_rest)
        self.rest_len = np.where(self.folded, -np.sign(half) * 2.0 * np.cos(half), 2.0 * np.sin(half))
        # its weight: w / 2 (f(theta) - f(theta_0))^2 turns by w f'(theta_0)^2 per rad^2 at the rest angle, so
        # w = k / f'(theta_0)^2 (cos^2 or sin^2 of theta_0 / 2, at least 1/2) holds the preset's stiffness k
        # (NewtonStep's) at any rest angle; a flat hinge's k exactly (cos 0 = 1)
        slope = np.where(self.folded, np.sin(half), np.cos(half))
        self.kb = el.kb / (slope * slope)

        def gram(g, w):
            return (g.T @ diags(w) @ g) if g.shape[0] else 0.0

        A = diags(self.inertia) + gram(el.Ga, el.wa + self.ws) + gram(el.Gb, el.wb + self.ws)
        A = A + gram(el.Ge, np.full(el.Ge.shape[0], el.we)) + gram(self.Gh, self.kb)
        self.matrix = A.tocsr()
        fi = self.free_idx
        # SPD: an LDL^T with qdldl's AMD ordering, x, y and z back-substituted in one pass
        free_matrix = self.matrix[fi][:, fi].tocsc()
        free_matrix.sort_indices()
        self.lu = Factor3(free_matrix) if len(fi) else None
        # body contact in the solve: a penalty on the particles held on their contact plane, whose weight
        # enters the matrix's diagonal (refactored when that set changes, at most once per contact search)
        self._free_matrix, self._base_values = free_matrix, free_matrix.data.copy()
        cols = np.repeat(np.arange(len(fi)), np.diff(free_matrix.indptr))
        self._diag_pos = np.zeros(len(fi), dtype=np.int64)
        on_diag = free_matrix.indices == cols
        self._diag_pos[cols[on_diag]] = np.nonzero(on_diag)[0]
        diag = free_matrix.diagonal()
        self.contact_weight = CONTACT_WEIGHT * float(np.median(diag)) if len(fi) else 0.0
        self._held = None  # (rows into the free particles, normals, plane points, offset) of the penalty
        self._row_of = np.full(self.n, -1, dtype=np.int64)
        self._row_of[fi] = np.arange(len(fi))
        self._self = None  # (particle i, particle j, their direction, diameter): pairs the penalty keeps apart
        self.self_weight = SELF_WEIGHT * float(np.median(diag)) if len(fi) else 0.0
        self._held_key = b""
        self._searched = True
        # friction in the solve: each particle's anchor (the substep's start, :attr:`anchor`; None: no
        # friction in the solve) and the held particles' friction bound (N, set at each solve)
        self.anchor = None
        self._cap = None
        # a moving body: how far it carries each particle over the substep beyond the particle's own velocity,
        # at its contact point ((P, 3), set by the drape where the body moved; None: a still body); the held
        # particles' start guess and inertial target move by it along the body
        self.carry = None
        self.refactors = 0
        # every linear image at once: weft, warp, sliver edges, hinges (rows in that order), and its transpose
        self.D = vstack([el.Ga, el.Gb, el.Ge, self.Gh]).tocsr()
        self.DT = self.D.T.tocsr()
        t, e = len(el.tri), el.Ge.shape[0]
        self._blocks = np.cumsum([0, t, t, e, len(bends)])
        # each image row's weight W (D^T W D + M is the matrix): the gradient is M (x - y) + D^T (W D x - target)
        self._row_w = np.concatenate([el.wa + self.ws, el.wb + self.ws, np.full(e, el.we), self.kb])
        # the local step's buffers (positions and target in, images, targets, gradient and energy out) and
        # the rest lengths that grow (updated in place), all float64 on the host, and the kernel's launch
        # on them, recorded once
        n_rows = self.D.shape[0]
        self._x, self._y, self._all = np.zeros((self.n, 3)), np.zeros((self.n, 3)), np.zeros((self.n, 3))
        self._images, self._target = np.zeros((n_rows, 3)), np.zeros((n_rows, 3))
        self._energy = np.zeros(2)
        self._rest = [np.ones(t), np.ones(t)]
        self._edge_len = np.zeros(e)
        i32 = np.int32
        self._host = [
            np.ascontiguousarray(a, dtype=dtype)
            for a, dtype in (
                (self._blocks, i32),
                (self.D.indptr, i32),
                (self.D.indices, i32),
                (self.D.data, float),
                (self.inertia, float),
                (self._row_w, float),
                (el.wa, float),
                (el.wb, float),
                (self.ws, float),
                (bends.reshape(-1), i32),
                (self.kb, float),
                (self.rest_len, float),
                (np.where(self.folded, -1.0, 1.0), float),
                (el.cap_a if self.buckling else np.full(t, np.inf), float),
                (el.cap_b if self.buckling else np.full(t, np.inf), float),
            )
        ]
        blocks, Dp, Di, Dx, inertia, row_w, wa, wb, ws, bd, kb, hr, hs, cap_a, cap_b = (_flat(a) for a in self._host)
        self._launch = wp.launch(
            pd_gradient,
            dim=1,
            device="cpu",
            record_cmd=True,
            inputs=[
                self.n,
                blocks,
                Dp,
                Di,
                Dx,
                _flat(self._x),
                _flat(self._y),
                inertia,
                row_w,
                _flat(self._rest[0]),
                _flat(self._rest[1]),
                cap_a,
                cap_b,
                wa,
                wb,
                ws,
                _flat(self._edge_len),
                float(el.we),
                bd,
                kb,
                hr,
                hs,
                _flat(self._images),
                _flat(self._target),
                _flat(self._all),
                _flat(self._energy),
            ],
        )
        self._grow = None
        self.stalls = 0  # solves stopped where no halved step lowered G (self-collision, :meth:`solve`)
        self.contact = None
        self.friction = 0.0  # the Coulomb coefficient the stop test allows on the body (the drape's)
        self.method = METHOD
        # the strain limit: its weights per grain row (weft rows, then warp rows), its set (None: empty) and
        # the free matrix's entries in column-major order, to lay the set's A^T W A on its pattern
        self.limit_weight = STRAIN_LIMIT if strain_limit is None else float(strain_limit)
        self.max_stretch = float(getattr(material, "max_stretch", np.inf))
        self._limit_w = self.limit_weight * np.concatenate([el.wa, el.wb])
        self._limit = None  # (rows into D, their weights, D's rows transposed (P, k)) of the set
        self._limit_in = np.zeros(2 * t, bool)
        self._limit_want = None  # the grains past their limit at the end of the last solve
        self._limit_pos = self._limit_coef = None  # each grain row's matrix entries (:meth:`_limit_entries`)
        self._limit_values = None  # the set's A^T W A on the free matrix's entries
        self._limit_dirty = False
        self.limited = 0
        nf = len(fi)
        self._entry_key = cols.astype(np.int64) * max(nf, 1) + free_matrix.indices

    def set_contact(self, point: np.ndarray, normal: np.ndarray, active: np.ndarray, thickness: float) -> None:
        """Body contact for the next solves' stop test: on an active free particle within twice
        ``thickness`` of its contact plane (through ``point``, facing along ``normal``), the part of the
        residual force that presses it into the body, and up to :attr:`friction` times that along the
        body, is the body's to hold (the contact and friction are applied after the solve)."""
        idx = np.nonzero((np.asarray(active) != 0) & self.free)[0]
        prev = self.contact
        # the planes move only at a contact search: the penalty's set is chosen again after one
        self._searched = (
            prev is None
            or not np.array_equal(prev[0], idx)
            or not np.array_equal(prev[1], point[idx])
            or not np.array_equal(prev[2], normal[idx])
        )
        self.contact = (
            (idx, point[idx].astype(float), normal[idx].astype(float), float(thickness)) if len(idx) else None
        )

    def _evaluate(self, x: np.ndarray, y: np.ndarray, grow: float) -> float:
        """The local step and the gradient at ``x`` (:func:`pd_gradient`): the images, targets and
        ``grad G`` (every particle's) in the buffers; returns G(x)."""
        self._grow_rest(grow)
        self._x[:] = x
        self._y[:] = y
        self._launch.launch()
        if self._limit is None:
            return float(self._energy[0] + self._energy[1])
        # the strain limit's set: each grain image onto the ball of radius L_max, its weighted distance in
        # the gradient (the kernel's buffer) and the energy
        rows, w, dt_rows = self._limit
        img = self._images[rows]
        length = np.sqrt(np.einsum("ij,ij->i", img, img))
        excess = np.maximum(length - (1.0 + self.max_stretch) * np.concatenate(self._rest)[rows], 0.0)
        self._all += dt_rows @ ((w * excess / np.maximum(length, 1e-300))[:, None] * img)
        return float(self._energy[0] + self._energy[1]) + 0.5 * float(np.sum(w * excess * excess))

    def _grow_rest(self, grow: float) -> None:
        """The rest stretch (:attr:`_rest`, weft and warp) and sliver-edge lengths at ``grow``, growing from
        the skintight start's (updated in place where ``grow`` changed)."""
        if self._grow != grow:
            el, back = self.elements, 1.0 - grow
            for k in (0, 1):
                self._rest[k][:] = 1.0 + (el.stretch0[:, k] - 1.0) * back
            self._edge_len[:] = el.edge_rest + (el.edge_start - el.edge_rest) * back
            self._grow = grow

    def local(self, x: np.ndarray, y: np.ndarray, grow: float) -> tuple:
        """The local step at ``x``: (the elastic part of ``grad G``, ``sum_c w_c A_c^T (A_c x - p_c(x))``
        (P, 3), G(x)), G the step's potential; ``grad G`` is ``M (x - y) / dt^2`` plus it."""
        energy = self._evaluate(x, y, grow)
        return self._all - self.inertia[:, None] * (self._x - self._y), energy

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
        ``"lbfgs"`` (not the default, :data:`METHOD`) they are L-BFGS steps instead (:meth:`_lbfgs`). The strain
        limit's set (:attr:`limit_weight`) is the grains the last solve ended past their limit.

        Returns (iterations done, the largest residual over weight at the last test).
        """
        out = self._solve(x, y, grow, iterations, tolerance, weight)
        self._limit_mark(x, grow)
        return out

    def _solve(self, x, y, grow: float, iterations: int, tolerance: float, weight: np.ndarray):
        """:meth:`solve`'s iterations (the strain limit's set chosen from the last solve's end)."""
        fi = self.free_idx
        if len(fi) == 0:
            return 0, 0.0
        w2 = np.maximum(weight[fi], 1e-30) ** 2
        self._limit_set()
        near, nrm = np.zeros(0, int), np.zeros((0, 3))
        if self.contact is not None:
            # on the body (within twice the contact offset) the body's reaction and friction take the part
            # of the force that presses the particle into the body and up to mu times that along it
            idx, point, normal, thickness = self.contact
            height = np.einsum("ij,ij->i", x[idx] - point, normal)
            on = height < 2.0 * thickness
            near, nrm = np.searchsorted(fi, idx[on]), normal[on]
            if self.contact_weight > 0.0:
                if self._searched or self._held is None:
                    # held: the particles on the body (at its offset, where the last contact put them, or
                    # below); one above it stays free to fall (its matrix term would hold it back)
                    touch = height < HELD_HEIGHT * thickness
                    self._hold((np.searchsorted(fi, idx[touch]), normal[touch], point[touch], thickness))
                if self._held is not None:
                    near, nrm = self._held[0], self._held[1]
        elif self._held is not None:
            self._hold(None)
        if self._limit_dirty:
            self._refactor()
        if self._held is not None and self.carry is not None:
            # a moving body carries the particles it holds: their start guess and inertial target move
            # with the body's surface along it (the penalty's weight in every direction of the matrix
            # keeps a held particle near its start guess; at its place in the world the body slid under
            # the cloth and left it behind). Along the normal the penalty keeps them on the body.
            p, nrm = self._held_particles, self._held[1]
            d = self.carry[p]
            d = _tangential(d, nrm)
            x[p] += d
            y[p] += d
        if self._held is not None and self._solve_friction:
            # Coulomb's choice for the held particles' start guess: stuck at the anchor where the net force
            # along the body there (inertia, gravity, the fabric's) is within mu F_n, F_n the force that
            # stops the inertial target's depth inside the offset over the substep; elsewhere the given
            # guess (sliding, against mu F_n in the solve). The penalty's weight in every direction of the
            # matrix makes the motion along the body the slowest to converge: from a wrong guess a
            # particle would crawl, stuck where it should slide or sliding where it should stick.
            _, nrm, point, offset = self._held
            p, rows = self._held_particles, self._held[0]
            self._cap = (
                self.friction * self.inertia[p] * np.maximum(offset - np.einsum("ij,ij->i", y[p] - point, nrm), 0.0)
            )
            guess = x[p].copy()
            t = guess - self.anchor[p]
            x[p] -= _tangential(t, nrm)
            cap, self._cap = self._cap, None  # the force along the body without friction
            grad = self._gradient(x, y, grow)[1][rows]
            self._cap = cap
            along = _tangential(grad, nrm)
            slide = np.einsum("ij,ij->i", along, along) > cap * cap
            x[p[slide]] = guess[slide]
            # a slide the inertial target carries past friction's stop: that motion less the stop (the
            # fabric's pull is left to the solve)
            d = y[p] - self.anchor[p]
            d = _tangential(d, nrm)
            length = np.sqrt(np.einsum("ij,ij->i", d, d))
            stop = cap / self.inertia[p]
            carry = slide & (length > stop)
            keep = 1.0 - stop[carry] / length[carry]
            t = guess[carry] - self.anchor[p[carry]]
            x[p[carry]] = guess[carry] - _tangential(t, nrm[carry]) + keep[:, None] * d[carry]
        if self.method == "lbfgs":
            return self._lbfgs(x, y, grow, iterations, tolerance, fi, near, nrm, w2)
        if self.method == "newton":
            return self._newton(x, y, grow, iterations, tolerance, fi, near, nrm, w2)
        m = max(self.history, 0)
        # Anderson's history: the last m differences of successive plain steps G(x_k) and of their
        # increments G(x_k) - x_k, in a ring, with the increments' Gram matrix updated a row at a time
        d_g = np.empty((m, 3 * len(fi)))
        d_f = np.empty_like(d_g)
        gram = np.zeros((m, m))
        held, slot, last = 0, 0, None
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
            f = g - xf
            x[fi] = g.reshape(-1, 3)
            if m and last is not None:
                np.subtract(g, last[0], out=d_g[slot])
                np.subtract(f, last[1], out=d_f[slot])
                held = min(held + 1, m)
                # (einsum, not BLAS: a threaded BLAS on these thin products costs more than the step on a
                # loaded machine)
                row = np.einsum("ik,k->i", d_f[:held], d_f[slot])
                gram[slot, :held] = row
                gram[:held, slot] = row
                slot = (slot + 1) % m
                reg = gram[:held, :held].copy()
                reg.flat[:: held + 1] += 1e-12 * max(float(np.trace(reg)), 1e-300)
                theta = np.linalg.solve(reg, np.einsum("ik,k->i", d_f[:held], f))
                last = (g, f)
                x[fi] = (g - np.einsum("i,ik->k", theta, d_g[:held])).reshape(-1, 3)
                e_a, grad_a = self._gradient(x, y, grow)
                if np.isfinite(e_a) and e_a < e:
                    e, grad = e_a, grad_a
                    continue
                x[fi] = g.reshape(-1, 3)  # the mix did not lower G: the plain step, a fresh history
                held, slot = 0, 0
            last = (g, f)
            e_old = e
            e, grad = self._gradient(x, y, grow)
            if self._self is not None and not (np.isfinite(e) and e <= e_old):
                # the self-collision penalty is not in the matrix, so the plain step may raise G where
                # it acts: halve the step until G falls (the local-global step alone always lowers it),
                # and start a fresh history
                for _ in range(SELF_BACKTRACK):
                    g = 0.5 * (g + xf)
                    x[fi] = g.reshape(-1, 3)
                    e, grad = self._gradient(x, y, grow)
                    if np.isfinite(e) and e <= e_old:
                        break
                else:
                    # no step along this one lowers G: stay where it was lowest and stop (iterating on from
                    # a raised G let the penalty's overshoot grow until the cloth blew up at 80 iterations);
                    # res is that point's, from this iteration's test
                    self.stalls += 1
                    x[fi] = xf.reshape(-1, 3)
                    break
                held, slot, last = 0, 0, None
        return it, res

    def _hold(self, held) -> None:
        """Hold ``held`` (rows into the free particles, their normals, plane points, the offset; or None)
        on the body by the contact penalty: the matrix's diagonal gains its weight there (refactored where
        the rows differ from the last set's)."""
        self._searched = False
        key = held[0].tobytes() if held is not None and len(held[0]) else b""
        self._held = held if key else None
        self._held_particles = self.free_idx[held[0]] if key else None
        if key == self._held_key and not self._limit_dirty:
            return
        self._held_key = key
        self._refactor()

    def _refactor(self) -> None:
        """Factorise the matrix with the strain limit's set and the contact penalty's held particles."""
        values = self._base_values.copy()
        if self._limit_values is not None:
            values += self._limit_values
        if self._held is not None:
            values[self._diag_pos[self._held[0]]] += self.contact_weight
        self._free_matrix.data[:] = values
        self.lu.refactor(self._free_matrix)
        self._limit_dirty = False
        self.refactors += 1

    def _limit_mark(self, x: np.ndarray, grow: float) -> None:
        """The grains past their limit at the end of a solve (``x``): the strain limit's next set."""
        if self.limit_weight <= 0.0 or not np.isfinite(self.max_stretch) or self.lu is None:
            return
        el = self.elements
        self._grow_rest(grow)
        rest = np.concatenate(self._rest)
        f = np.concatenate([el.Ga @ x, el.Gb @ x])
        want = np.sqrt(np.einsum("ij,ij->i", f, f)) > (1.0 + self.max_stretch) * rest
        if not LIMIT_ON_BODY and self._held is not None and np.any(want):
            on = np.zeros(self.n, bool)
            on[self._held_particles] = True
            held = on[el.tri].any(axis=1)
            want &= ~np.concatenate([held, held])
        self._limit_want = want

    def _limit_set(self) -> None:
        """The strain limit's set for the next solve (:attr:`limit_weight`, :meth:`_limit_mark`); where it
        changed, its matrix entries are laid out anew (refactored by the solve)."""
        now = self._limit_want
        if now is None or np.array_equal(now, self._limit_in):
            return
        if self._held is not None and not self._searched:
            # on the body the set changes at a contact search only, where the contact's refactorisation serves
            # both (the pants at ease 0.9, 100 frames: 128 refactorisations in 200 substeps, not one a substep)
            return
        self._limit_in = now
        self._limit_dirty = True
        rows = np.nonzero(now)[0]
        self.limited = len(rows)
        if not len(rows):
            self._limit, self._limit_values = None, None
            return
        d_rows = self.D[rows]  # weft rows 0..t-1, warp rows t..2t-1: D's first two blocks
        w = self._limit_w[rows]
        self._limit = (rows, w, d_rows.T.tocsr())
        # the set's A^T W A: each grain row's 3 x 3 block (its coefficients' products) on the free matrix's entries
        pos, coef = self._limit_entries()
        block = w[:, None] * (coef[rows][:, :, None] * coef[rows][:, None, :]).reshape(len(rows), 9)
        keep = pos[rows] >= 0
        values = np.zeros(len(self._entry_key))
        np.add.at(values, pos[rows][keep], block[keep])
        self._limit_values = values

    def _limit_entries(self) -> tuple:
        """Each grain row's (weft rows, then warp rows) 3 x 3 block: its entries' positions in the free
        matrix's values ((2T, 9), -1 where a particle is pinned) and the row's coefficients ((2T, 3))."""
        if self._limit_pos is None:
            el = self.elements
            tri = np.concatenate([el.tri, el.tri])
            coef = np.concatenate([el.ca, el.cb])
            r = self._row_of[tri]  # (2T, 3) rows of the free particles, -1 pinned
            ri, rj = np.repeat(r, 3, axis=1), np.tile(r, (1, 3))
            key = rj.astype(np.int64) * max(len(self.free_idx), 1) + ri
            pos = np.minimum(np.searchsorted(self._entry_key, key), len(self._entry_key) - 1)
            free = (ri >= 0) & (rj >= 0)
            if not np.all(self._entry_key[pos][free] == key[free]):
                raise RuntimeError("strain limit: a grain's entry outside the matrix's pattern")
            self._limit_pos, self._limit_coef = np.where(free, pos, -1), coef
        return self._limit_pos, self._limit_coef

    @property
    def _solve_friction(self) -> bool:
        """Coulomb friction against the body inside the solve (:data:`FRICTION`: an anchor set, a coefficient)."""
        return self.anchor is not None and self.friction > 0.0

    def set_self(self, i: np.ndarray, j: np.ndarray, diameter: float, x: np.ndarray) -> None:
        """Self-collision candidates for the next solves: particle pairs (``i``, ``j``) kept ``diameter``
        apart along their direction at ``x`` (the substep's start, (P, 3)) by the penalty
        ``self_weight / 2 * (diameter - separation)^2`` (a plane through the partner, as the body's: a
        particle the solve carries past its partner is pushed back, not on through; None or empty: none)."""
        if i is None or len(i) == 0 or self.self_weight <= 0.0:
            self._self = None
            return
        i, j = np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64)
        d = x[i] - x[j]
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        ok = length > 1e-12
        self._self = (i[ok], j[ok], d[ok] / length[ok][:, None], float(diameter)) if np.any(ok) else None

    def _gradient(self, x, y, grow) -> tuple:
        """(G(x), grad G on the free particles (F, 3)); with the contact penalty
        ``contact_weight / 2 * depth^2`` on the held particles, depth = how far inside its plane's offset."""
        energy = self._evaluate(x, y, grow)
        grad = self._all[self.free_idx]
        self._pressure = None
        if self._self is not None:
            pi, pj, nrm, dia = self._self
            depth = np.maximum(dia - np.einsum("ij,ij->i", x[pi] - x[pj], nrm), 0.0)
            on = depth > 0.0
            if np.any(on):
                f = (self.self_weight * depth[on])[:, None] * nrm[on]
                ri, rj = self._row_of[pi[on]], self._row_of[pj[on]]
                ki, kj = ri >= 0, rj >= 0
                np.add.at(grad, ri[ki], -f[ki])
                np.add.at(grad, rj[kj], f[kj])
                energy += 0.5 * self.self_weight * float(depth[on] @ depth[on])
        if self._held is not None:
            rows, nrm, point, offset = self._held
            depth = np.maximum(offset - np.einsum("ij,ij->i", x[self._held_particles] - point, nrm), 0.0)
            grad[rows] -= (self.contact_weight * depth)[:, None] * nrm
            energy += 0.5 * self.contact_weight * float(depth @ depth)
            self._pressure = self.contact_weight * depth
            if self._solve_friction and self._cap is not None:
                # Coulomb friction as the penalty's tangential part (the matrix's diagonal already holds
                # its weight in every direction): a spring of the same weight to the particle's anchor
                # along the body, its force capped at mu F_n (a Huber energy: it sticks below the cap
                # and slides against mu F_n above it)
                p = self._held_particles
                t = x[p] - self.anchor[p]
                t = _tangential(t, nrm)
                slide = np.sqrt(np.einsum("ij,ij->i", t, t))
                cap = self._cap
                k = np.minimum(self.contact_weight, cap / np.maximum(slide, 1e-300))
                grad[rows] += k[:, None] * t
                stick = self.contact_weight * slide <= cap
                energy += 0.5 * self.contact_weight * float(slide[stick] @ slide[stick])
                energy += float(np.sum(cap[~stick] * slide[~stick] - 0.5 * cap[~stick] ** 2 / self.contact_weight))
        return energy, grad

    def _back(self, v: np.ndarray) -> np.ndarray:
        """A^-1 v on the free particles ((F, 3)): one back-substitution of the factored matrix."""
        return self.lu.solve(v.reshape(-1, 3))

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
        nh = hinge_normals(x, self.elements.bends.reshape(-1, 4), self.folded) if o[4] > o[3] else None
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
                out[o[3] : o[4]] = (self.kb * np.einsum("ij,ij->i", nh, vh))[:, None] * nh
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
                v[near] = _tangential(v[near], nrm)
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
        # with friction in the solve (:attr:`_solve_friction`) the penalty and its friction are both in the
        # gradient: all of it counts
        if self._held is not None and len(near) and not self._solve_friction:
            # the penalty is in the gradient: the normal part counts, friction holds up to mu times the
            # penalty's force along the body
            normal = np.einsum("ij,ij->i", grad[near], nrm)
            slide = np.sqrt(np.maximum(left[near] - normal * normal, 0.0))
            left[near] = normal * normal + np.maximum(slide - self.friction * self._pressure, 0.0) ** 2
        elif self._held is None and len(near):
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
