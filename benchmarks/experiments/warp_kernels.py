"""Prototype (not used by core/): the pattern solver's per-triangle steps as Warp CPU kernels.

Each kernel is one launch over the triangles, float64, written with the same
operations in the same order as the numpy version in core/pattern/steps.py /
feedback.py / solver.py (Warp's CPU codegen emits one C++ statement per
operation, so clang does not contract them into FMAs and the bits can match).

- ``local_step_kernel``: :func:`core.pattern.steps.local_step`, unit column
  weights (``weights.warp_column`` 1, every preset), prestretch or not, with
  and without warp slack;
- ``feedback_kernel``: :func:`core.pattern.feedback.move_corrections` of a
  reference / transfer solve (no poses);
- ``guard_kernel``: :func:`core.pattern.steps.collapse_guard`'s relative
  singular values and gain update (the held indices are one numpy pass after);
- ``areas_kernel``: :func:`core.pattern.steps.flip_guard`'s first check (the
  signed areas of the step and the count under the floor; a step that needs
  halving goes on to the numpy guard);
- ``jacobians_kernel``: :meth:`PatternSolver.jacobians` (the CSR rows' order).

Launches are recorded once (``record_cmd``) and only the arguments that are
new objects are re-bound (a raw ``array_t`` on the numpy buffer, no copy):
wrapping ~20 numpy arrays as ``wp.array`` would cost ~8 us each a call.
"""
from __future__ import annotations

import ctypes
import os

import numpy as np

from core.geom.queries import wp  # the project's Warp set-up (kernel cache folder, log level)

if os.environ.get("EXP_WARP_CPU_FLAGS") is not None:
    # e.g. "" (a generic x86-64 target, SSE2): Warp's default is -march=native (the host's ISA)
    wp.config.cpu_compiler_flags = os.environ["EXP_WARP_CPU_FLAGS"]
from warp._src.types import array_t

f64 = wp.float64
A = wp.array(dtype=wp.float64)
A2 = wp.array2d(dtype=wp.float64)
I2 = wp.array2d(dtype=wp.int32)


@wp.func
def _jac(m0: A, m1: A, m2: A, m3: A, i: int):
    """Triangle ``i``'s Jacobian entries m00, m01, m10, m11."""
    return m0[i], m1[i], m2[i], m3[i]


@wp.func
def _clip(x: f64, lo: f64, hi: f64):
    # np.clip(x, lo, hi) = minimum(maximum(x, lo), hi)
    return wp.min(wp.max(x, lo), hi)


@wp.kernel
def local_step_kernel(m0: A, m1: A, m2: A, m3: A, d0a: A, d1a: A, k0a: A, k1a: A, k2a: A, k3a: A,
                      Cdiff: A, C01: A, t2a: A, t3a: A, sw_in: A, has_sw: int, om: f64, free: int,
                      lo: f64, hi: f64, newton: int,
                      rt0: A, rt1: A, rt2: A, rt3: A, te2: A, te3: A, sw_out: A, off: int):
    i = wp.tid() + off
    M0, M1, M2, M3 = _jac(m0, m1, m2, m3, i)
    d0 = d0a[i]
    d1 = d1a[i]
    k0 = k0a[i]
    k1 = k1a[i]
    k2 = k2a[i]
    k3 = k3a[i]
    dw = d1
    if has_sw != 0:
        dw = d1 * sw_in[i]
    omdw = om * dw
    x = d0 * (M0 * k0 + M1 * k1)
    x = x + omdw * (M2 * k2 + M3 * k3)
    y = M2 * k0 + M3 * k1
    y = y * omdw
    y = y - d0 * (M0 * k2 + M1 * k3)
    r = wp.sqrt(x * x + y * y)
    c = f64(1.0)
    sn = f64(0.0)
    if r > f64(0.0):
        c = x / r
        sn = y / r
    if newton != 0:
        delta = d0 * d0
        delta = delta - omdw * dw
        delta = delta * f64(0.5)
        p = delta * Cdiff[i]
        q = (f64(-2.0) * delta) * C01[i]
        c2 = c * c - sn * sn
        s2 = (f64(2.0) * c) * sn
        g1 = x * sn
        g1 = g1 - y * c
        g1 = g1 * f64(2.0)
        g1 = g1 - (f64(2.0) * p) * s2
        g1 = g1 + (f64(2.0) * q) * c2
        g2 = f64(2.0) * r
        g2 = g2 - (f64(4.0) * p) * c2
        g2 = g2 - (f64(4.0) * q) * s2
        step = f64(0.0)
        if g2 > f64(0.0):
            step = (-g1) / g2
        nrm = wp.sqrt(step * step + f64(1.0))
        c_new = (c - sn * step) / nrm
        sn_new = (c * step + sn) / nrm
        c = c_new
        sn = sn_new
    r0 = c * k0 - sn * k2
    r1 = c * k1 - sn * k3
    r2 = sn * k0 + c * k2
    r3 = sn * k1 + c * k3
    T2 = t2a[i]
    T3 = t3a[i]
    if free != 0:
        p0 = d1 * r2
        p1 = d1 * r3
        num = M2 * p0 + M3 * p1
        den = p0 * p0 + p1 * p1
        sw = _clip(num / wp.max(den, f64(1e-300)), lo, hi)
        sw_out[i] = sw
        d1sw = d1 * sw
        rt0[i] = d0 * r0
        rt1[i] = d0 * r1
        rt2[i] = d1sw * r2
        rt3[i] = d1sw * r3
        num = M2 * T2 + M3 * T3
        tden = wp.max(T2 * T2 + T3 * T3, f64(1e-300))
        se = _clip(num / tden, lo, hi)
        te2[i] = T2 * se
        te3[i] = T3 * se
    else:
        rt0[i] = d0 * r0
        rt1[i] = d0 * r1
        rt2[i] = d1 * r2
        rt3[i] = d1 * r3
        te2[i] = T2
        te3[i] = T3


@wp.func
def _scale(det: f64, ka: f64, kb: f64, kc: f64, kd: f64, m: f64, n: f64):
    x = ka * m - kb * n
    y = kc * m - kd * n
    return det / wp.sqrt(x * x + y * y)


@wp.kernel
def feedback_kernel(m0: A, m1: A, m2: A, m3: A, k0a: A, k1a: A, k2a: A, k3a: A, cw: A, cg: A,
                    gain_w: f64, gain_g: f64, lower: f64, upper: f64, floor: f64, ceil: f64,
                    corr_w: A, corr_g: A, off: int):
    i = wp.tid() + off
    M0, M1, M2, M3 = _jac(m0, m1, m2, m3, i)
    k0 = k0a[i]
    k1 = k1a[i]
    k2 = k2a[i]
    k3 = k3a[i]
    det = wp.abs(M0 * M3 - M1 * M2)
    rw = _scale(det, k0, k1, k2, k3, M3, M2)
    rg = _scale(det, k1, k0, k3, k2, M0, M1)
    a = corr_w[i]
    b = corr_g[i]
    gw = cw[i]
    gg = cg[i]
    ok = wp.isfinite(rw) and wp.isfinite(rg) and rw > f64(0.0) and rg > f64(0.0) and wp.isfinite(gw) and wp.isfinite(gg)
    if ok:
        if gain_w > f64(0.0):
            a = a * _clip(wp.pow(gw / rw, gain_w), lower, upper)
        if gain_g > f64(0.0):
            b = b * _clip(wp.pow(gg / rg, gain_g), lower, upper)
    corr_w[i] = _clip(a, floor, ceil)
    corr_g[i] = _clip(b, floor, ceil)


@wp.kernel
def guard_kernel(m0: A, m1: A, m2: A, m3: A, i00a: A, i01a: A, i10a: A, i11a: A, body_ok: wp.array(dtype=wp.uint8),
                 cw: A, cg: A, scale: f64, opn: f64, grow: f64, limit: f64, release: f64,
                 gain: A, q0: A, q1: A, q2: A, q3: A, s2out: A, off: int):
    i = wp.tid() + off
    M0, M1, M2, M3 = _jac(m0, m1, m2, m3, i)
    i00 = i00a[i]
    i01 = i01a[i]
    i10 = i10a[i]
    i11 = i11a[i]
    a = cw[i]
    b = cg[i]
    x0 = (M0 * i00 + M1 * i10) / a
    x1 = (M0 * i01 + M1 * i11) / a
    x2 = (M2 * i00 + M3 * i10) / b
    x3 = (M2 * i01 + M3 * i11) / b
    q0[i] = x0
    q1[i] = x1
    q2[i] = x2
    q3[i] = x3
    e = (x0 + x3) * f64(0.5)
    f = (x0 - x3) * f64(0.5)
    g = (x2 + x1) * f64(0.5)
    h = (x2 - x1) * f64(0.5)
    qq = wp.sqrt(e * e + h * h)
    rr = wp.sqrt(f * f + g * g)
    s1 = qq + rr
    s2 = qq - rr
    s2out[i] = s2
    gn = gain[i]
    valid = body_ok[i] != wp.uint8(0) and wp.isfinite(s1)
    if not valid:
        gn = gn * f64(0.0)
    if valid and s2 < scale:
        gn = wp.min(wp.max(gn * grow, f64(1.0)), limit)
    if gn > f64(0.0) and s2 >= opn:
        gn = gn * release
        if gn < f64(1.0):
            gn = f64(0.0)
    gain[i] = gn


@wp.kernel
def areas_kernel(U: A2, F: I2, s_old: A, area_floor: A, s_out: A, nbad: wp.array(dtype=wp.int32)):
    i = wp.tid()
    a = F[i, 0]
    b = F[i, 1]
    c = F[i, 2]
    u0 = U[a, 0]
    v0 = U[a, 1]
    ax = U[b, 0] - u0
    ay = U[b, 1] - v0
    bx = U[c, 0] - u0
    by = U[c, 1] - v0
    s = (ax * by - ay * bx) * f64(0.5)
    s_out[i] = s
    if s <= wp.min(area_floor[i], f64(0.5) * s_old[i]):
        wp.atomic_add(nbad, 0, 1)


@wp.kernel
def jacobians_kernel(U: A2, cx: I2, gx: A2, cy: I2, gy: A2, m0: A, m1: A, m2: A, m3: A):
    # a CSR row product: 0 + sum of data * x over the row's (sorted) columns, in their order
    i = wp.tid()
    a = cx[i, 0]
    b = cx[i, 1]
    c = cx[i, 2]
    m0[i] = ((f64(0.0) + gx[i, 0] * U[a, 0]) + gx[i, 1] * U[b, 0]) + gx[i, 2] * U[c, 0]
    m2[i] = ((f64(0.0) + gx[i, 0] * U[a, 1]) + gx[i, 1] * U[b, 1]) + gx[i, 2] * U[c, 1]
    a = cy[i, 0]
    b = cy[i, 1]
    c = cy[i, 2]
    m1[i] = ((f64(0.0) + gy[i, 0] * U[a, 0]) + gy[i, 1] * U[b, 0]) + gy[i, 2] * U[c, 0]
    m3[i] = ((f64(0.0) + gy[i, 0] * U[a, 1]) + gy[i, 1] * U[b, 1]) + gy[i, 2] * U[c, 1]


# ---------------------------------------------------------------------------------------------- 8 lanes
# The scalar kernels above compile to scalar code (one triangle a task: ~35 ns a triangle for the local step,
# no faster than numpy's SIMD passes). The same algebra on 8 triangles a task, as 8-vectors of float64,
# compiles to AVX-512 / AVX2 packed instructions (LLVM's SLP vectoriser on Warp's component loops): the
# arrays are viewed as (f // 8,) vectors; the f % 8 last triangles run through the scalar kernel.
v8 = wp.types.vector(length=8, dtype=wp.float64)
V = wp.array(dtype=v8)


@wp.func
def _jac8(m0: V, m1: V, m2: V, m3: V, i: int):
    """Task ``i``'s 8 Jacobians, entry by entry."""
    return m0[i], m1[i], m2[i], m3[i]


@wp.func
def vsqrt(x: v8):
    s = v8()
    for j in range(8):
        s[j] = wp.sqrt(x[j])
    return s


@wp.func
def vpos(c: v8, a: v8, b: v8):
    """a where c > 0 else b, lane by lane."""
    s = v8()
    for j in range(8):
        s[j] = wp.where(c[j] > f64(0.0), a[j], b[j])
    return s


@wp.func
def vclip(x: v8, lo: f64, hi: f64):
    s = v8()
    for j in range(8):
        s[j] = wp.min(wp.max(x[j], lo), hi)
    return s


@wp.func
def vabs(x: v8):
    s = v8()
    for j in range(8):
        s[j] = wp.abs(x[j])
    return s


@wp.func
def vfloor(x: v8, lo: f64):
    s = v8()
    for j in range(8):
        s[j] = wp.max(x[j], lo)
    return s


@wp.kernel
def local_step_kernel8(m0: V, m1: V, m2: V, m3: V, d0a: V, d1a: V, k0a: V, k1a: V, k2a: V, k3a: V,
                       Cdiff: V, C01: V, t2a: V, t3a: V, sw_in: V, has_sw: int, om: f64, free: int,
                       lo: f64, hi: f64, newton: int,
                       rt0: V, rt1: V, rt2: V, rt3: V, te2: V, te3: V, sw_out: V):
    i = wp.tid()
    M0, M1, M2, M3 = _jac8(m0, m1, m2, m3, i)
    d0 = d0a[i]
    d1 = d1a[i]
    k0 = k0a[i]
    k1 = k1a[i]
    k2 = k2a[i]
    k3 = k3a[i]
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
    if newton != 0:
        delta = wp.cw_mul(d0, d0) - wp.cw_mul(omdw, dw)
        delta = delta * f64(0.5)
        p = wp.cw_mul(delta, Cdiff[i])
        q = wp.cw_mul(delta * f64(-2.0), C01[i])
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
    T2 = t2a[i]
    T3 = t3a[i]
    if free != 0:
        p0 = wp.cw_mul(d1, r2)
        p1 = wp.cw_mul(d1, r3)
        num = wp.cw_mul(M2, p0) + wp.cw_mul(M3, p1)
        den = wp.cw_mul(p0, p0) + wp.cw_mul(p1, p1)
        sw = vclip(wp.cw_div(num, vfloor(den, f64(1e-300))), lo, hi)
        sw_out[i] = sw
        d1sw = wp.cw_mul(d1, sw)
        rt0[i] = wp.cw_mul(d0, r0)
        rt1[i] = wp.cw_mul(d0, r1)
        rt2[i] = wp.cw_mul(d1sw, r2)
        rt3[i] = wp.cw_mul(d1sw, r3)
        num = wp.cw_mul(M2, T2) + wp.cw_mul(M3, T3)
        tden = vfloor(wp.cw_mul(T2, T2) + wp.cw_mul(T3, T3), f64(1e-300))
        se = vclip(wp.cw_div(num, tden), lo, hi)
        te2[i] = wp.cw_mul(T2, se)
        te3[i] = wp.cw_mul(T3, se)
    else:
        rt0[i] = wp.cw_mul(d0, r0)
        rt1[i] = wp.cw_mul(d0, r1)
        rt2[i] = wp.cw_mul(d1, r2)
        rt3[i] = wp.cw_mul(d1, r3)
        te2[i] = T2
        te3[i] = T3


@wp.func
def _vscale(det: v8, ka: v8, kb: v8, kc: v8, kd: v8, m: v8, n: v8):
    x = wp.cw_mul(ka, m) - wp.cw_mul(kb, n)
    y = wp.cw_mul(kc, m) - wp.cw_mul(kd, n)
    return wp.cw_div(det, vsqrt(wp.cw_mul(x, x) + wp.cw_mul(y, y)))


@wp.kernel
def feedback_kernel8(m0: V, m1: V, m2: V, m3: V, k0a: V, k1a: V, k2a: V, k3a: V, cw: V, cg: V,
                     gain_w: f64, gain_g: f64, lower: f64, upper: f64, floor: f64, ceil: f64,
                     corr_w: V, corr_g: V):
    i = wp.tid()
    M0, M1, M2, M3 = _jac8(m0, m1, m2, m3, i)
    k0 = k0a[i]
    k1 = k1a[i]
    k2 = k2a[i]
    k3 = k3a[i]
    dt = wp.cw_mul(M0, M3) - wp.cw_mul(M1, M2)
    det = v8()
    for j in range(8):
        det[j] = wp.abs(dt[j])
    rw = _vscale(det, k0, k1, k2, k3, M3, M2)
    rg = _vscale(det, k1, k0, k3, k2, M0, M1)
    a = corr_w[i]
    b = corr_g[i]
    gw = cw[i]
    gg = cg[i]
    for j in range(8):
        ok = wp.isfinite(rw[j]) and wp.isfinite(rg[j]) and rw[j] > f64(0.0) and rg[j] > f64(0.0) and wp.isfinite(gw[j]) and wp.isfinite(gg[j])
        if ok:
            if gain_w > f64(0.0):
                a[j] = a[j] * wp.min(wp.max(wp.pow(gw[j] / rw[j], gain_w), lower), upper)
            if gain_g > f64(0.0):
                b[j] = b[j] * wp.min(wp.max(wp.pow(gg[j] / rg[j], gain_g), lower), upper)
    corr_w[i] = vclip(a, floor, ceil)
    corr_g[i] = vclip(b, floor, ceil)


@wp.kernel
def guard_kernel8(m0: V, m1: V, m2: V, m3: V, i00a: V, i01a: V, i10a: V, i11a: V, body_ok: V,
                  cw: V, cg: V, scale: f64, opn: f64, grow: f64, limit: f64, release: f64,
                  gain: V, q0: V, q1: V, q2: V, q3: V, s2out: V):
    i = wp.tid()
    M0, M1, M2, M3 = _jac8(m0, m1, m2, m3, i)
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
    s2out[i] = s2
    gn = gain[i]
    bo = body_ok[i]
    fin = s1 - s1       # 0 where s1 is finite
    # branch-free lanes (the same rules as the scalar kernel: a branch in a lane loop stops LLVM's SLP
    # vectoriser, ~5x slower)
    for j in range(8):
        v = wp.where(bo[j] > f64(0.0), wp.where(fin[j] == f64(0.0), 1, 0), 0)
        x = wp.where(v != 0, gn[j], gn[j] * f64(0.0))
        x = wp.where(v != 0, wp.where(s2[j] < scale, wp.min(wp.max(x * grow, f64(1.0)), limit), x), x)
        xr = x * release
        xr = wp.where(xr < f64(1.0), f64(0.0), xr)
        gn[j] = wp.where(x > f64(0.0), wp.where(s2[j] >= opn, xr, x), x)
    gain[i] = gn


@wp.kernel
def ratio_kernel8(m0: V, m1: V, m2: V, m3: V, k0a: V, k1a: V, k2a: V, k3a: V, cw: V, cg: V,
                  ratio_w: V, ratio_g: V):
    """The feedback's achieved/target ratios goal / rho (1 where the feedback does not move a triangle):
    numpy then raises them to the gains (its pow, SIMD, not libm's)."""
    i = wp.tid()
    M0, M1, M2, M3 = _jac8(m0, m1, m2, m3, i)
    k0 = k0a[i]
    k1 = k1a[i]
    k2 = k2a[i]
    k3 = k3a[i]
    det = vabs(wp.cw_mul(M0, M3) - wp.cw_mul(M1, M2))
    rw = _vscale(det, k0, k1, k2, k3, M3, M2)
    rg = _vscale(det, k1, k0, k3, k2, M0, M1)
    gw = cw[i]
    gg = cg[i]
    a = wp.cw_div(gw, rw)
    b = wp.cw_div(gg, rg)
    # branch-free lanes (the same test): x - x is 0 for a finite x, NaN otherwise
    fin = (rw - rw) + (rg - rg) + (gw - gw) + (gg - gg)
    for j in range(8):
        a[j] = wp.where(fin[j] == f64(0.0), wp.where(rw[j] > f64(0.0), wp.where(rg[j] > f64(0.0), a[j], f64(1.0)), f64(1.0)), f64(1.0))
        b[j] = wp.where(fin[j] == f64(0.0), wp.where(rw[j] > f64(0.0), wp.where(rg[j] > f64(0.0), b[j], f64(1.0)), f64(1.0)), f64(1.0))
    ratio_w[i] = a
    ratio_g[i] = b


@wp.kernel
def ratio_kernel(m0: A, m1: A, m2: A, m3: A, k0a: A, k1a: A, k2a: A, k3a: A, cw: A, cg: A,
                 ratio_w: A, ratio_g: A, off: int):
    i = wp.tid() + off
    M0, M1, M2, M3 = _jac(m0, m1, m2, m3, i)
    det = wp.abs(M0 * M3 - M1 * M2)
    rw = _scale(det, k0a[i], k1a[i], k2a[i], k3a[i], M3, M2)
    rg = _scale(det, k1a[i], k0a[i], k3a[i], k2a[i], M0, M1)
    gw = cw[i]
    gg = cg[i]
    ok = wp.isfinite(rw) and wp.isfinite(rg) and rw > f64(0.0) and rg > f64(0.0) and wp.isfinite(gw) and wp.isfinite(gg)
    if ok:
        ratio_w[i] = gw / rw
        ratio_g[i] = gg / rg
    else:
        ratio_w[i] = f64(1.0)
        ratio_g[i] = f64(1.0)


@wp.kernel
def vote_kernel8(m0: V, m1: V, m2: V, m3: V, wxa: V, wya: V, vote: V, wix: V, wiy: V):
    """:func:`core.pattern.steps.realign_grain`'s per-triangle votes (w ix, w iy): the warp's image and
    its weight; numpy sums them per panel."""
    i = wp.tid()
    wx = wxa[i]
    wy = wya[i]
    ix = wp.cw_mul(m0[i], wx) + wp.cw_mul(m1[i], wy)
    iy = wp.cw_mul(m2[i], wx) + wp.cw_mul(m3[i], wy)
    nrm = vsqrt(wp.cw_mul(ix, ix) + wp.cw_mul(iy, iy))
    w = wp.cw_div(vpos(nrm, vote[i], v8(f64(0.0))), vfloor(nrm, f64(1e-300)))
    wix[i] = wp.cw_mul(w, ix)
    wiy[i] = wp.cw_mul(w, iy)


@wp.kernel
def vote_kernel(m0: A, m1: A, m2: A, m3: A, wxa: A, wya: A, vote: A, wix: A, wiy: A, off: int):
    i = wp.tid() + off
    wx = wxa[i]
    wy = wya[i]
    ix = m0[i] * wx + m1[i] * wy
    iy = m2[i] * wx + m3[i] * wy
    nrm = wp.sqrt(ix * ix + iy * iy)
    v = f64(0.0)
    if nrm > f64(0.0):
        v = vote[i]
    w = v / wp.max(nrm, f64(1e-300))
    wix[i] = w * ix
    wiy[i] = w * iy


@wp.kernel
def rotate_kernel8(m0: V, m1: V, m2: V, m3: V, cta: V, sta: V, o0: V, o1: V, o2: V, o3: V):
    """The Jacobians turned with their panel: [ct m0 - st m2, ct m1 - st m3, st m0 + ct m2, st m1 + ct m3]."""
    i = wp.tid()
    ct = cta[i]
    st = sta[i]
    M0, M1, M2, M3 = _jac8(m0, m1, m2, m3, i)
    o0[i] = wp.cw_mul(ct, M0) - wp.cw_mul(st, M2)
    o1[i] = wp.cw_mul(ct, M1) - wp.cw_mul(st, M3)
    o2[i] = wp.cw_mul(st, M0) + wp.cw_mul(ct, M2)
    o3[i] = wp.cw_mul(st, M1) + wp.cw_mul(ct, M3)


@wp.kernel
def rotate_kernel(m0: A, m1: A, m2: A, m3: A, cta: A, sta: A, o0: A, o1: A, o2: A, o3: A, off: int):
    i = wp.tid() + off
    ct = cta[i]
    st = sta[i]
    o0[i] = ct * m0[i] - st * m2[i]
    o1[i] = ct * m1[i] - st * m3[i]
    o2[i] = st * m0[i] + ct * m2[i]
    o3[i] = st * m1[i] + ct * m3[i]


def _ctype(a: np.ndarray) -> array_t:
    return array_t(a.__array_interface__["data"][0], 0, a.ndim, a.shape, a.strides)


def _wrap(a, lanes: int = 1, stop=None):
    if isinstance(a, np.ndarray):
        dt = {np.dtype(np.float64): wp.float64, np.dtype(np.int32): wp.int32, np.dtype(np.uint8): wp.uint8}[a.dtype]
        assert a.flags.c_contiguous
        if lanes > 1 and a.ndim == 1:
            return wp.array(a[:stop].reshape(-1, lanes), dtype=v8, device="cpu", copy=False)
        return wp.array(a, dtype=dt, device="cpu", copy=False)
    return a


class Launch:
    """A CPU launch of ``kernel`` over ``dim`` threads whose arguments are set in place in one prebuilt
    argument struct, and only those that are another object than last time (an array's data pointer; the
    arrays are kept alive while bound). ``lanes`` 8: (f,) arrays are bound as (f // 8,) 8-vectors.

    Calls Warp's CPU entry point (``hooks.forward``) directly: ``Launch.launch`` rebuilds the whole
    struct (~0.3 us an argument) each call."""

    def __init__(self, kernel, dim: int, lanes: int = 1):
        self.kernel, self.dim, self.lanes, self.args = kernel, dim, lanes, None

    def __call__(self, *args):
        if self.args is None:
            stop = self.dim * self.lanes if self.lanes > 1 else None
            cmd = wp.launch(self.kernel, dim=self.dim, inputs=[_wrap(a, self.lanes, stop) for a in args],
                            device="cpu", record_cmd=True)
            cmd.launch()        # builds Warp's argument struct type
            params = cmd.params
            ArgsStruct, fields = self.kernel._invoke_cache[(tuple(type(p) for p in params[1:]), False)]
            self.struct = ArgsStruct()
            for j, field in enumerate(fields):
                setattr(self.struct, field[0], params[1 + j])
            self.names = [f[0] for f in fields]
            self.bounds, self.hooks, self.cmd = params[0], cmd.hooks, cmd
            self.args = list(args)
            self.ref = ctypes.byref(self.bounds), ctypes.byref(self.struct)
            return
        last, st = self.args, self.struct
        for j, a in enumerate(args):
            if a is last[j]:
                continue
            if isinstance(a, np.ndarray):
                getattr(st, self.names[j]).data = a.__array_interface__["data"][0]
            else:
                if a == last[j]:
                    continue
                setattr(st, self.names[j], a)
            last[j] = a
        self.hooks.forward(*self.ref)
