"""Warp CPU kernels of the solver's per-triangle steps: numpy's bits in fewer passes.

Each kernel is the numpy step it replaces (:mod:`.steps`, :mod:`.feedback`)
written with the same floating-point operations in the same order, so its
results are the same bits and a pattern is the same bytes with or without it
(:mod:`.compiled` launches them and falls back to numpy). What makes that hold:

- Warp's code generator makes one C++ statement of each operation and the
  module is built without floating-point contraction (``fuse_fp`` off), so
  nothing becomes a fused multiply-add, and IEEE ``+ - * / sqrt`` give
  numpy's bits, on any x86 or ARM target;
- no libm call: numpy's ``power`` is its own SIMD routine, so the feedback's
  power stays in numpy (:func:`ratios8` stops before it);
- Warp's ``min`` / ``max`` ignore a NaN where numpy's propagate it: every
  kernel counts the lanes where that could matter in ``flags`` and the caller
  then takes the numpy path for the whole call;
- a NaN is a NaN either way, but where two NaNs of different sign meet, x86
  keeps one operand's, and clang and numpy may order a commutative
  operation's operands differently: a NaN's sign and payload bits may differ
  (no pattern holds a NaN; tests/test_pattern_kernels.py checks the rest).

Speed: 8 triangles a task, as 8-vectors of float64 (the (f,) arrays viewed as
(f // 8,) vectors): LLVM's SLP vectoriser turns Warp's component loops into
packed AVX-512 / AVX2 / NEON code, 4x numpy's passes on the local step.
A branch inside a lane loop stops the vectoriser (5x slower), so per-lane
choices are ``wp.where``. The f % 8 last triangles: the caller launches the
kernel once more on the 8 last triangles (every kernel is pure: it writes
outputs only, so the overlap writes the same values twice).
"""

from __future__ import annotations

from ...geom.queries import wp  # Warp as the package sets it up (kernel cache folder, log level)

# forward only: no gradients are taken here, and the adjoints would double the compile time; no fused
# multiply-add even where clang's front end would form one (Warp's default lets the backend fuse those)
wp.set_module_options({"enable_backward": False, "fuse_fp": False})

f64 = wp.float64
v8 = wp.types.vector(length=8, dtype=wp.float64)
V = wp.array(dtype=v8)
Flags = wp.array(dtype=wp.int32)


@wp.func
def vsqrt(x: v8):
    s = v8()
    for j in range(8):
        s[j] = wp.sqrt(x[j])
    return s


@wp.func
def vpos(c: v8, a: v8, b: v8):
    """``a`` where ``c > 0``, else ``b``, lane by lane (numpy's ``where(c > 0, a, b)``)."""
    s = v8()
    for j in range(8):
        s[j] = wp.where(c[j] > f64(0.0), a[j], b[j])
    return s


@wp.func
def vclip(x: v8, lo: f64, hi: f64):
    """numpy's ``clip`` for lanes that are not NaN (``minimum(maximum(x, lo), hi)``)."""
    s = v8()
    for j in range(8):
        s[j] = wp.min(wp.max(x[j], lo), hi)
    return s


@wp.func
def vfloor(x: v8, lo: f64):
    """numpy's ``maximum(x, lo)`` for lanes that are not NaN."""
    s = v8()
    for j in range(8):
        s[j] = wp.max(x[j], lo)
    return s


@wp.func
def nans(x: v8):
    """How many lanes of ``x`` are NaN."""
    n = int(0)
    for j in range(8):
        n += wp.where(x[j] != x[j], 1, 0)
    return n


@wp.func
def flag(flags: Flags, slot: int, n: int):
    """Add ``n`` to ``flags[slot]`` (a branch outside the lane loops: most tasks add nothing)."""
    if n != 0:
        wp.atomic_add(flags, slot, n)


@wp.func
def four(a: V, b: V, c: V, d: V, i: int):
    """Task ``i``'s 8 lanes of four arrays (a 2 x 2 matrix's entries: Jacobians, offsets)."""
    return a[i], b[i], c[i], d[i]


@wp.func
def scale8(det: v8, ka: v8, kb: v8, kc: v8, kd: v8, m: v8, n: v8):
    """:func:`core.geom.strain.scales_of_offsets`' ``det / |(ka m - kb n, kc m - kd n)|``."""
    x = wp.cw_mul(ka, m) - wp.cw_mul(kb, n)
    y = wp.cw_mul(kc, m) - wp.cw_mul(kd, n)
    return wp.cw_div(det, vsqrt(wp.cw_mul(x, x) + wp.cw_mul(y, y)))


@wp.kernel
def local_step8(
    m0: V,
    m1: V,
    m2: V,
    m3: V,
    d0a: V,
    d1a: V,
    k0a: V,
    k1a: V,
    k2a: V,
    k3a: V,
    cdiff: V,
    c01: V,
    t2a: V,
    t3a: V,
    sw_in: V,
    has_sw: int,
    om: f64,
    free: int,
    lo: f64,
    hi: f64,
    newton: int,
    rt0: V,
    rt1: V,
    rt2: V,
    rt3: V,
    te2: V,
    te3: V,
    sw_out: V,
    flags: Flags,
):
    """:func:`.steps.local_step` with unit column weights. ``flags[0]``: lanes whose ``delta`` is not 0
    (numpy takes the Newton step only if one is); ``flags[1]``: lanes where a NaN meets a clip."""
    i = wp.tid()
    M0, M1, M2, M3 = four(m0, m1, m2, m3, i)
    d0 = d0a[i]
    d1 = d1a[i]
    k0, k1, k2, k3 = four(k0a, k1a, k2a, k3a, i)
    one = v8(f64(1.0))
    zero = v8(f64(0.0))
    dw = d1
    if has_sw != 0:
        dw = wp.cw_mul(d1, sw_in[i])
    omdw = dw * om
    x = wp.cw_mul(d0, wp.cw_mul(M0, k0) + wp.cw_mul(M1, k1))
    x = x + wp.cw_mul(omdw, wp.cw_mul(M2, k2) + wp.cw_mul(M3, k3))
    y = wp.cw_mul(M2, k0) + wp.cw_mul(M3, k1)
    y = wp.cw_mul(y, omdw)
    y = y - wp.cw_mul(d0, wp.cw_mul(M0, k2) + wp.cw_mul(M1, k3))
    r = vsqrt(wp.cw_mul(x, x) + wp.cw_mul(y, y))
    c = vpos(r, wp.cw_div(x, r), one)
    sn = vpos(r, wp.cw_div(y, r), zero)
    delta = wp.cw_mul(d0, d0) - wp.cw_mul(omdw, dw)
    delta = delta * f64(0.5)
    moving = int(0)
    for j in range(8):
        moving += wp.where(delta[j] != f64(0.0), 1, 0)
    flag(flags, 0, moving)
    if newton != 0:
        p = wp.cw_mul(delta, cdiff[i])
        q = wp.cw_mul(delta * f64(-2.0), c01[i])
        c2 = wp.cw_mul(c, c) - wp.cw_mul(sn, sn)
        s2 = wp.cw_mul(c * f64(2.0), sn)
        g1 = wp.cw_mul(x, sn) - wp.cw_mul(y, c)
        g1 = g1 * f64(2.0)
        g1 = g1 - wp.cw_mul(p * f64(2.0), s2)
        g1 = g1 + wp.cw_mul(q * f64(2.0), c2)
        g2 = r * f64(2.0)
        g2 = g2 - wp.cw_mul(p * f64(4.0), c2)
        g2 = g2 - wp.cw_mul(q * f64(4.0), s2)
        step = vpos(g2, wp.cw_div(-g1, g2), zero)
        nrm = vsqrt(wp.cw_mul(step, step) + one)
        c_new = wp.cw_div(c - wp.cw_mul(sn, step), nrm)
        sn_new = wp.cw_div(wp.cw_mul(c, step) + sn, nrm)
        c = c_new
        sn = sn_new
    r0 = wp.cw_mul(c, k0) - wp.cw_mul(sn, k2)
    r1 = wp.cw_mul(c, k1) - wp.cw_mul(sn, k3)
    r2 = wp.cw_mul(sn, k0) + wp.cw_mul(c, k2)
    r3 = wp.cw_mul(sn, k1) + wp.cw_mul(c, k3)
    t2 = t2a[i]
    t3 = t3a[i]
    rt0[i] = wp.cw_mul(d0, r0)
    rt1[i] = wp.cw_mul(d0, r1)
    if free != 0:
        # the warp row's best factor within [lo, hi] (the rest shape's), then the ease target's
        p0 = wp.cw_mul(d1, r2)
        p1 = wp.cw_mul(d1, r3)
        num = wp.cw_mul(M2, p0) + wp.cw_mul(M3, p1)
        den = wp.cw_mul(p0, p0) + wp.cw_mul(p1, p1)
        ratio = wp.cw_div(num, vfloor(den, f64(1e-300)))
        sw = vclip(ratio, lo, hi)
        sw_out[i] = sw
        d1sw = wp.cw_mul(d1, sw)
        rt2[i] = wp.cw_mul(d1sw, r2)
        rt3[i] = wp.cw_mul(d1sw, r3)
        num = wp.cw_mul(M2, t2) + wp.cw_mul(M3, t3)
        tden = wp.cw_mul(t2, t2) + wp.cw_mul(t3, t3)
        tratio = wp.cw_div(num, vfloor(tden, f64(1e-300)))
        se = vclip(tratio, lo, hi)
        te2[i] = wp.cw_mul(t2, se)
        te3[i] = wp.cw_mul(t3, se)
        flag(flags, 1, nans(den) + nans(ratio) + nans(tden) + nans(tratio))
    else:
        rt2[i] = wp.cw_mul(d1, r2)
        rt3[i] = wp.cw_mul(d1, r3)


@wp.kernel
def ratios8(
    m0: V, m1: V, m2: V, m3: V, k0a: V, k1a: V, k2a: V, k3a: V, cw: V, cg: V, ratio_w: V, ratio_g: V, flags: Flags
):
    """:func:`.feedback.move_corrections`' achieved/target ratios ``goal / rho`` (weft, warp) of a
    reference or transfer solve; numpy raises them to the gains. ``flags[0]``: triangles the feedback
    leaves (a scale not finite or not positive, a target not finite): numpy then takes the call."""
    i = wp.tid()
    M0, M1, M2, M3 = four(m0, m1, m2, m3, i)
    k0, k1, k2, k3 = four(k0a, k1a, k2a, k3a, i)
    dt = wp.cw_mul(M0, M3) - wp.cw_mul(M1, M2)
    det = v8()
    for j in range(8):
        det[j] = wp.abs(dt[j])
    rw = scale8(det, k0, k1, k2, k3, M3, M2)
    rg = scale8(det, k1, k0, k3, k2, M0, M1)
    gw = cw[i]
    gg = cg[i]
    ratio_w[i] = wp.cw_div(gw, rw)
    ratio_g[i] = wp.cw_div(gg, rg)
    # x - x is 0 for a finite x and NaN otherwise
    fin = (rw - rw) + (rg - rg) + (gw - gw) + (gg - gg)
    left = int(0)
    for j in range(8):
        left += wp.where(fin[j] == f64(0.0), wp.where(rw[j] > f64(0.0), wp.where(rg[j] > f64(0.0), 0, 1), 1), 1)
    flag(flags, 0, left)


@wp.kernel
def guard8(
    m0: V,
    m1: V,
    m2: V,
    m3: V,
    i00a: V,
    i01a: V,
    i10a: V,
    i11a: V,
    body_ok: V,
    cw: V,
    cg: V,
    scale: f64,
    opn: f64,
    grow: f64,
    limit: f64,
    release: f64,
    gain_in: V,
    gain: V,
    q0: V,
    q1: V,
    q2: V,
    q3: V,
    flags: Flags,
):
    """:func:`.steps.collapse_guard`: the relative Jacobians ``q`` (:func:`.steps.relative_singular_values`)
    and the gains after the update (``gain``, from ``gain_in``); numpy lists the held triangles.
    ``flags[0]``: triangles under ``scale`` whose gain is over ``limit`` or NaN, or raised to NaN
    (numpy raises the gains only if one is under the limit, and its min / max propagate a NaN)."""
    i = wp.tid()
    M0, M1, M2, M3 = four(m0, m1, m2, m3, i)
    i00 = i00a[i]
    i01 = i01a[i]
    i10 = i10a[i]
    i11 = i11a[i]
    a = cw[i]
    b = cg[i]
    x0 = wp.cw_div(wp.cw_mul(M0, i00) + wp.cw_mul(M1, i10), a)
    x1 = wp.cw_div(wp.cw_mul(M0, i01) + wp.cw_mul(M1, i11), a)
    x2 = wp.cw_div(wp.cw_mul(M2, i00) + wp.cw_mul(M3, i10), b)
    x3 = wp.cw_div(wp.cw_mul(M2, i01) + wp.cw_mul(M3, i11), b)
    q0[i] = x0
    q1[i] = x1
    q2[i] = x2
    q3[i] = x3
    e = (x0 + x3) * f64(0.5)
    f = (x0 - x3) * f64(0.5)
    g = (x2 + x1) * f64(0.5)
    h = (x2 - x1) * f64(0.5)
    qq = vsqrt(wp.cw_mul(e, e) + wp.cw_mul(h, h))
    rr = vsqrt(wp.cw_mul(f, f) + wp.cw_mul(g, g))
    s1 = qq + rr
    s2 = qq - rr
    gn = gain_in[i]
    bo = body_ok[i]
    fin = s1 - s1
    over = int(0)
    # s2 is finite where the triangle is valid; where no raised gain is over the limit (or NaN) numpy's
    # "raise only if one is under the limit" is the raise itself (grow >= 1, limit >= 1: the caller's)
    for j in range(8):
        ok = wp.where(bo[j] > f64(0.0), wp.where(fin[j] == f64(0.0), 1, 0), 0)
        x = wp.where(ok != 0, gn[j], gn[j] * f64(0.0))
        low = wp.where(ok != 0, wp.where(s2[j] < scale, 1, 0), 0)
        up = x * grow
        over += wp.where(low != 0, wp.where(x <= limit, wp.where(up == up, 0, 1), 1), 0)
        x = wp.where(low != 0, wp.min(wp.max(up, f64(1.0)), limit), x)
        xr = x * release
        xr = wp.where(xr < f64(1.0), f64(0.0), xr)
        gn[j] = wp.where(x > f64(0.0), wp.where(s2[j] >= opn, xr, x), x)
    gain[i] = gn
    flag(flags, 0, over)


@wp.kernel
def votes8(m0: V, m1: V, m2: V, m3: V, wxa: V, wya: V, vote: V, wix: V, wiy: V, flags: Flags):
    """:func:`.steps.realign_grain`'s per-triangle votes ``w M g`` (the warp's image, weighted);
    numpy sums them per panel. ``flags[0]``: lanes whose image length is NaN."""
    i = wp.tid()
    wx = wxa[i]
    wy = wya[i]
    ix = wp.cw_mul(m0[i], wx) + wp.cw_mul(m1[i], wy)
    iy = wp.cw_mul(m2[i], wx) + wp.cw_mul(m3[i], wy)
    nrm = vsqrt(wp.cw_mul(ix, ix) + wp.cw_mul(iy, iy))
    w = wp.cw_div(vpos(nrm, vote[i], v8(f64(0.0))), vfloor(nrm, f64(1e-300)))
    wix[i] = wp.cw_mul(w, ix)
    wiy[i] = wp.cw_mul(w, iy)
    flag(flags, 0, nans(nrm))


@wp.kernel
def turn8(m0: V, m1: V, m2: V, m3: V, cta: V, sta: V, o0: V, o1: V, o2: V, o3: V):
    """The Jacobians turned with their panel: ``[ct m0 - st m2, ct m1 - st m3, st m0 + ct m2, st m1 + ct m3]``."""
    i = wp.tid()
    ct = cta[i]
    st = sta[i]
    M0, M1, M2, M3 = four(m0, m1, m2, m3, i)
    o0[i] = wp.cw_mul(ct, M0) - wp.cw_mul(st, M2)
    o1[i] = wp.cw_mul(ct, M1) - wp.cw_mul(st, M3)
    o2[i] = wp.cw_mul(st, M0) + wp.cw_mul(ct, M2)
    o3[i] = wp.cw_mul(st, M1) + wp.cw_mul(ct, M3)


@wp.kernel
def areas8(u0: V, v0: V, u1: V, v1: V, u2: V, v2: V, area_floor: V, s_old: V, s: V, flags: Flags):
    """:func:`.steps.flip_guard`'s first check: the signed areas ``s`` of a step's triangles from their
    corners' coordinates (gathered by numpy) and, in ``flags[0]``, how many are at or under their floor
    ``min(area_floor, s_old / 2)``; ``flags[1]``: lanes where ``s_old`` is NaN (numpy's floor is NaN there,
    Warp's min would not be)."""
    i = wp.tid()
    a = u0[i]
    b = v0[i]
    ax = u1[i] - a
    ay = v1[i] - b
    bx = u2[i] - a
    by = v2[i] - b
    area = (wp.cw_mul(ax, by) - wp.cw_mul(ay, bx)) * f64(0.5)
    s[i] = area
    old = s_old[i] * f64(0.5)
    fl = area_floor[i]
    low = int(0)
    for j in range(8):
        low += wp.where(area[j] <= wp.min(fl[j], old[j]), 1, 0)
    flag(flags, 0, low)
    flag(flags, 1, nans(old))


@wp.kernel
def corrections8(
    p_w: V,
    p_g: V,
    corr_w: V,
    corr_g: V,
    use_w: int,
    use_g: int,
    lower: f64,
    upper: f64,
    floor: f64,
    hi: f64,
    new_w: V,
    new_g: V,
    flags: Flags,
):
    """:func:`.feedback.move_corrections` after numpy's power of the ratios (``p_w``, ``p_g``: the ratios
    to the gains; read where ``use_w`` / ``use_g``): ``corr *= clip(p, lower, upper)``, then ``clip(corr,
    floor, hi)``, into ``new_w``, ``new_g``. ``flags[0]``: lanes with a NaN (numpy's clip keeps it)."""
    i = wp.tid()
    a = corr_w[i]
    b = corr_g[i]
    pw = p_w[i]
    pg = p_g[i]
    if use_w != 0:
        a = wp.cw_mul(a, vclip(pw, lower, upper))
    if use_g != 0:
        b = wp.cw_mul(b, vclip(pg, lower, upper))
    new_w[i] = vclip(a, floor, hi)
    new_g[i] = vclip(b, floor, hi)
    flag(flags, 0, nans(a) + nans(b) + nans(pw) + nans(pg))


@wp.kernel
def rhs_terms8(
    rt0: V,
    rt1: V,
    rt2: V,
    rt3: V,
    t0: V,
    t1: V,
    t2: V,
    t3: V,
    lam_reg: f64,
    scale_reg: int,
    lam_ease: f64,
    b0: V,
    b1: V,
    b2: V,
    b3: V,
):
    """:func:`.steps.rhs_terms`: ``B = lambda_reg R T + lambda_ease T`` entry by entry (``R T`` not
    scaled where ``scale_reg`` is 0: a weight of 1)."""
    i = wp.tid()
    r0, r1, r2, r3 = four(rt0, rt1, rt2, rt3, i)
    if scale_reg != 0:
        r0 = r0 * lam_reg
        r1 = r1 * lam_reg
        r2 = r2 * lam_reg
        r3 = r3 * lam_reg
    b0[i] = r0 + t0[i] * lam_ease
    b1[i] = r1 + t1[i] * lam_ease
    b2[i] = r2 + t2[i] * lam_ease
    b3[i] = r3 + t3[i] * lam_ease
