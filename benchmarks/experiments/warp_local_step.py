"""Experiment: the pattern solver's per-triangle steps as Warp CPU kernels, against numpy, on the shirt.

Usage (repository root)::

    .venv/bin/python benchmarks/experiments/warp_local_step.py calls      # per call, real iteration-10 inputs
    .venv/bin/python benchmarks/experiments/warp_local_step.py items N    # N batch items, numpy / Warp alternating
    .venv/bin/python benchmarks/experiments/warp_local_step.py compile    # cold compile / cached load (subprocesses)

The solver state is built as ``core/batch/worker.py`` does (the shirt's
context, sampled Anny bodies of ``bench --only batch``'s seed). ``patch(True)``
swaps the solver module's steps for the drop-ins below (nothing in core/ is
edited); ``patch(False)`` restores them. Results: warp_local_step.md.
"""
from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
sys.path[:0] = [str(REPO), str(HERE)]

import core.pattern.solver as S  # noqa: E402
from core.pattern import steps as ST  # noqa: E402
from core.pattern import feedback as FB  # noqa: E402

SEED = 2024
ORIG = {"realign_grain": S.realign_grain, "local_step": S.local_step, "move_corrections": S.move_corrections, "collapse_guard": S.collapse_guard,
        "flip_guard": S.flip_guard, "jacobians": S.PatternSolver.jacobians}


# ---------------------------------------------------------------------------------------------- drop-ins
def _bufs(n, f, k=1):
    return [[np.empty(f) for _ in range(k)] for _ in range(n)]


_W = {}   # per kernel and size: launches (8 lanes, scalar tail) and output buffers per parity, call count


def _launch(name, k8, k1, f, nout, args, tail_args=None):
    """Run ``k8`` on the first f - f % 8 triangles and ``k1`` (scalar, offset) on the rest, with the
    arguments ``args`` followed by this call's output buffers (two sets, alternating, so that one call's
    results stay valid while the next call reads them); returns the outputs."""
    import warp_kernels as WK
    s = _W.get((name, f))
    if s is None:
        s = _W[(name, f)] = {"launch": [(WK.Launch(k8, f // 8, 8), WK.Launch(k1, f % 8)) for _ in range(2)],
                             "out": [[np.empty(f) for _ in range(nout)] for _ in range(2)], "n": 0}
    p = s["n"] % 2
    s["n"] += 1
    main, tail = s["launch"][p]
    out = s["out"][p]
    main(*args, *out)
    if f % 8:
        tail(*(tail_args or args), *out, f - f % 8)
    return out


def local_step_w(config, M, tg, W2, state):
    """:func:`core.pattern.steps.local_step` in one Warp launch (unit column weights; else numpy)."""
    import warp_kernels as WK
    if not (W2[0] == 1.0 and W2[1] == 1.0):
        return ORIG["local_step"](config, M, tg, W2, state)
    rest = config.rest_shape
    d0, d1, k = tg["reg"]
    T = tg["T"]
    kp = state.get("_kprod")
    if kp is None or kp[0] is not k or not np.array_equal(kp[1], W2):
        kp = (k, W2.copy(), W2[0] * k[0] ** 2 + W2[1] * k[1] ** 2 - W2[0] * k[2] ** 2 - W2[1] * k[3] ** 2,
              W2[0] * k[0] * k[2] + W2[1] * k[1] * k[3])
        state["_kprod"] = kp
    free = rest.warp_slack > 0
    sw = state.get("sw") if free else None
    f = len(d0)
    lo, hi = (1.0 / (1.0 + rest.warp_slack), 1.0 + rest.warp_slack) if free else (1.0, 1.0)
    # the first call has no sw yet: any array of the right size stands in (has_sw 0: not read)
    out = _launch("local", WK.local_step_kernel8, WK.local_step_kernel, f, 7,
                  (M[0], M[1], M[2], M[3], d0, d1, k[0], k[1], k[2], k[3], kp[2], kp[3], T[2], T[3],
                   sw if sw is not None else d1, int(sw is not None), float(rest.warp_row), int(free),
                   float(lo), float(hi), 1))
    if free:
        state["sw"] = out[6]
        return out[:4], [T[0], T[1], out[4], out[5]]
    return out[:4], T


def move_corrections_w(cfg, M, Kc, c_weft, c_warp, corr_w, corr_g, poses=None, targets_finite=None):
    """:func:`core.pattern.feedback.move_corrections` of a reference / transfer solve in one launch."""
    import warp_kernels as WK
    if poses is not None:
        return ORIG["move_corrections"](cfg, M, Kc, c_weft, c_warp, corr_w, corr_g, poses, targets_finite)
    gain_w, gain_g, lower, upper, hi = FB.feedback_gains(cfg, False)
    _launch("feedback", WK.feedback_kernel8, WK.feedback_kernel, len(corr_w), 0,
            (M[0], M[1], M[2], M[3], Kc[0], Kc[1], Kc[2], Kc[3], c_weft, c_warp, float(gain_w), float(gain_g),
             float(lower), float(upper), float(cfg.feedback.floor), float(hi), corr_w, corr_g))


_BODY = {}   # the body triangles' mask as float64 (8 lanes) and uint8 (scalar tail), per mask


def move_corrections_split(cfg, M, Kc, c_weft, c_warp, corr_w, corr_g, poses=None, targets_finite=None):
    """:func:`core.pattern.feedback.move_corrections`: the scales and ratios in one launch, the power
    (numpy's, so the same bits) and the clipping in numpy."""
    import warp_kernels as WK
    if poses is not None:
        return ORIG["move_corrections"](cfg, M, Kc, c_weft, c_warp, corr_w, corr_g, poses, targets_finite)
    gain_w, gain_g, lower, upper, hi = FB.feedback_gains(cfg, False)
    ratio_w, ratio_g = _launch("ratio", WK.ratio_kernel8, WK.ratio_kernel, len(corr_w), 2,
                               (M[0], M[1], M[2], M[3], Kc[0], Kc[1], Kc[2], Kc[3], c_weft, c_warp))
    # a ratio of 1 (a triangle the feedback leaves) gives the factor 1: the correction keeps its bits
    if gain_w > 0:
        corr_w *= np.clip(np.power(ratio_w, gain_w, out=ratio_w), lower, upper, out=ratio_w)
    if gain_g > 0:
        corr_g *= np.clip(np.power(ratio_g, gain_g, out=ratio_g), lower, upper, out=ratio_g)
    np.clip(corr_w, cfg.feedback.floor, hi, out=corr_w)
    np.clip(corr_g, cfg.feedback.floor, hi, out=corr_g)


def collapse_guard_w(guard, M, Kc, c_weft, c_warp, gain, inverse=None):
    """:func:`core.pattern.steps.collapse_guard` in one launch and one numpy pass (the held indices)."""
    import warp_kernels as WK
    inverse = inverse if inverse is not None else ST.inverse_offsets(Kc)
    (i00, i01, i10, i11), body = inverse
    bf = _BODY.get(id(body))
    if bf is None or bf[0] is not body:
        bf = _BODY[id(body)] = (body, body.astype(np.float64), body.view(np.uint8))
    rest = (c_weft, c_warp, float(guard.guard_scale), float(guard.guard_open), float(guard.guard_grow),
            float(guard.guard_limit), float(guard.guard_release), gain)
    out = _launch("guard", WK.guard_kernel8, WK.guard_kernel, len(gain), 5,
                  (M[0], M[1], M[2], M[3], i00, i01, i10, i11, bf[1]) + rest,
                  (M[0], M[1], M[2], M[3], i00, i01, i10, i11, bf[2]) + rest)
    return out[:4], np.flatnonzero(gain > 0)


def realign_grain_w(blocks, U, M):
    """:func:`core.pattern.steps.realign_grain`: the votes and the Jacobians' rotation in one launch each,
    the per-panel sums, angles and the vertices' rotation in numpy (as there)."""
    import warp_kernels as WK
    wx, wy = blocks.warp_columns
    f = len(M[0])
    wix, wiy = _launch("vote", WK.vote_kernel8, WK.vote_kernel, f, 2, (M[0], M[1], M[2], M[3], wx, wy,
                                                                        blocks.warp_vote))
    vx = np.add.reduceat(wix, blocks.face_offsets)
    vy = np.add.reduceat(wiy, blocks.face_offsets)
    theta = -np.where((vx == 0) & (vy == 0), 0.0, np.arctan2(-vx, vy))
    c, sn = np.cos(theta), np.sin(theta)
    rep = blocks.per_vertex
    ctr = rep(np.add.reduceat(U, blocks.vertex_offsets) / blocks.vertex_counts[:, None])
    U = ST.turn(U - ctr, rep(c), rep(sn)) + ctr
    ct, st = np.repeat(c, blocks.face_counts), np.repeat(sn, blocks.face_counts)
    out = [np.empty(f) for _ in range(4)]       # new arrays: the iterate's Jacobians outlive the call
    s = _W.get(("rotate", f))
    if s is None:
        s = _W[("rotate", f)] = (WK.Launch(WK.rotate_kernel8, f // 8, 8), WK.Launch(WK.rotate_kernel, f % 8))
    s[0](M[0], M[1], M[2], M[3], ct, st, *out)
    if f % 8:
        s[1](M[0], M[1], M[2], M[3], ct, st, *out, f - f % 8)
    return U, out


_NBAD = np.zeros(1, np.int32)


def flip_guard_w(blocks, U_old, U_new, s_old=None):
    """:func:`core.pattern.steps.flip_guard`: its first check (areas of the full step) in one launch; a step
    with a triangle under the floor goes on to the numpy guard."""
    import warp_kernels as WK
    if s_old is None:
        return ORIG["flip_guard"](blocks, U_old, U_new, s_old)
    F = blocks.__dict__.get("_faces32")
    if F is None:
        F = blocks.__dict__["_faces32"] = np.ascontiguousarray(blocks.faces, dtype=np.int32)
    s = _W.get(("areas", len(F)))
    if s is None:
        s = _W[("areas", len(F))] = {"launch": [WK.Launch(WK.areas_kernel, len(F)) for _ in range(2)],
                                     "out": [[np.empty(len(F))] for _ in range(2)], "n": 0}
    p = s["n"] % 2
    s["n"] += 1
    out = s["out"][p]
    _NBAD[0] = 0
    s["launch"][p](np.ascontiguousarray(U_new), F, s_old, blocks.area_floor, out[0], _NBAD)
    if _NBAD[0] == 0:
        return U_new.copy(), 0, out[0]
    return ORIG["flip_guard"](blocks, U_old, U_new, s_old)


def jacobians_w(self, U):
    """:meth:`PatternSolver.jacobians` in one launch (the CSR rows' columns and values, in their order)."""
    import warp_kernels as WK
    cols = self.__dict__.get("_jcols")
    if cols is None:
        f = self._Gx.shape[0]
        parts = []
        for G in (self._Gx, self._Gy):
            assert np.array_equal(G.indptr, 3 * np.arange(f + 1)) and G.has_sorted_indices
            parts += [np.ascontiguousarray(G.indices.reshape(f, 3), dtype=np.int32),
                      np.ascontiguousarray(G.data.reshape(f, 3))]
        cols = self.__dict__["_jcols"] = (parts, WK.Launch(WK.jacobians_kernel, f))
    parts, launch = cols
    out = [np.empty(len(parts[0])) for _ in range(4)]     # new arrays: a solve keeps its iterate's M
    launch(np.ascontiguousarray(U), *parts, *out)
    return out


WARP = {"local_step": local_step_w, "move_corrections": move_corrections_split, "collapse_guard": collapse_guard_w,
        "flip_guard": flip_guard_w, "realign_grain": realign_grain_w}


def patch(on: bool, which=("local_step", "move_corrections", "collapse_guard", "flip_guard", "realign_grain")):
    """Swap the solver module's steps for the Warp drop-ins (``on``) or back; the Jacobians (scipy's CSR
    product, faster than a gather kernel: ``calls``) only when named."""
    for name in which:
        fn = (jacobians_w if on else ORIG[name]) if name == "jacobians" else (WARP[name] if on else ORIG[name])
        if name == "jacobians":
            S.PatternSolver.jacobians = fn
        else:
            setattr(S, name, fn)


# ---------------------------------------------------------------------------------------------- set-up
def shirt_items(n):
    from core.batch import sample_anny
    from core.batch.items import make_items
    from core.batch.run import read_design
    from core.design.templates import template_path
    return make_items(read_design(template_path("shirt_long_sleeve")), sample_anny(n, seed=SEED))


def load():
    return "load %.2f %.2f %.2f" % os.getloadavg()


def capture(item, at=10):
    """The inputs of each step at iteration ``at`` of ``item``'s transfer (copies), run with numpy."""
    from core import workflows as wf
    from core.batch.worker import context
    from core.body.instance import body_instance
    ctx = context(item)
    got, count = {}, {}

    def spy(name, fn, snap):
        def inner(*a, **kw):
            count[name] = count.get(name, 0) + 1
            if count[name] == at:
                got[name] = snap(*a, **kw)
            return fn(*a, **kw)
        return inner

    cp = lambda x: [y.copy() for y in x]
    S.local_step = spy("local_step", ORIG["local_step"], lambda cfg, M, tg, W2, st: (
        cfg, cp(M), {"T": cp(tg["T"]), "reg": (tg["reg"][0].copy(), tg["reg"][1].copy(), cp(tg["reg"][2]))},
        W2.copy(), {"sw": st["sw"].copy()} if "sw" in st else {}))
    S.move_corrections = spy("move_corrections", ORIG["move_corrections"], lambda cfg, M, Kc, cw, cg, a, b, *r, **kw: (
        cfg, cp(M), cp(Kc), cw.copy(), cg.copy(), a.copy(), b.copy()))
    S.collapse_guard = spy("collapse_guard", ORIG["collapse_guard"], lambda g, M, Kc, cw, cg, gain, inv=None: (
        g, cp(M), cp(Kc), cw.copy(), cg.copy(), gain.copy(), inv))
    S.realign_grain = spy("realign_grain", ORIG["realign_grain"], lambda b, U, M: (b, U.copy(), cp(M)))
    S.flip_guard = spy("flip_guard", ORIG["flip_guard"], lambda b, Uo, Un, s=None: (b, Uo.copy(), Un.copy(), s.copy()))
    try:
        model = ctx.prep.body
        rest = body_instance(model, item.body.value)
        wf.transfer(ctx.prep, item.body.value, config=item.options.config, solver=ctx.solver, start=ctx.start,
                    vertices=rest)
    finally:
        patch(False)
    return ctx, got


def _cpu_us(fn, reps=50, rounds=9):
    best = []
    for _ in range(rounds):
        t = time.process_time_ns()
        for _ in range(reps):
            fn()
        best.append((time.process_time_ns() - t) / reps / 1000.0)
    return min(best)


def _diff(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    ad = float(np.max(np.abs(a - b))) if a.size else 0.0
    rel = float(np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-300))) if a.size else 0.0
    return {"max_abs": ad, "max_rel": rel, "identical": bool(np.array_equal(a, b))}


def calls():
    """Per call: numpy vs Warp on iteration-10 inputs of a sampled shirt body (CPU, min of rounds,
    the two alternating), and the differences of the results."""
    item = shirt_items(1)[0]
    ctx, got = capture(item)
    solver = ctx.solver
    rows = {}
    import warp_kernels as WK

    cfg, M, tg, W2, st = got["local_step"]
    print("config", cfg.rest_shape, "W2", W2, "f", len(M[0]), load())
    res = {}
    for name, fn in (("numpy", ORIG["local_step"]), ("warp", local_step_w)):
        s = dict(st)
        RT, Te = fn(cfg, M, tg, W2, s)
        res[name] = ([x.copy() for x in RT], [x.copy() for x in Te], s["sw"].copy() if "sw" in s else None)
    d = {f"RT{j}": _diff(res["numpy"][0][j], res["warp"][0][j]) for j in range(4)}
    d.update({f"Te{j}": _diff(res["numpy"][1][j], res["warp"][1][j]) for j in range(4)})
    d["sw"] = _diff(res["numpy"][2], res["warp"][2])
    rows["local_step"] = {"diff": d}

    cfg2, M2, Kc, cw, cg, a0, b0 = got["move_corrections"]
    outs = {}
    for name, fn in (("numpy", ORIG["move_corrections"]), ("warp", move_corrections_w)):
        a, b = a0.copy(), b0.copy()
        fn(cfg2, M2, Kc, cw, cg, a, b, None, np.isfinite(cw) & np.isfinite(cg))
        outs[name] = (a, b)
    rows["feedback"] = {"diff": {"corr_w": _diff(outs["numpy"][0], outs["warp"][0]),
                                 "corr_g": _diff(outs["numpy"][1], outs["warp"][1])}}

    g, M3, Kc3, cw3, cg3, gain0, inv = got["collapse_guard"]
    outs = {}
    for name, fn in (("numpy", ORIG["collapse_guard"]), ("warp", collapse_guard_w)):
        gain = gain0.copy()
        q, held = fn(g, M3, Kc3, cw3, cg3, gain, inv)
        outs[name] = ([x.copy() for x in q], held.copy(), gain)
    dd = {f"q{j}": _diff(outs["numpy"][0][j], outs["warp"][0][j]) for j in range(4)}
    dd["gain"] = _diff(outs["numpy"][2], outs["warp"][2])
    dd["held_same"] = bool(np.array_equal(outs["numpy"][1], outs["warp"][1]))
    dd["held"] = int(len(outs["numpy"][1]))
    rows["collapse_guard"] = {"diff": dd}

    blocks, Uo, Un, s_old = got["flip_guard"]
    outs = {name: fn(blocks, Uo, Un, s_old) for name, fn in (("numpy", ORIG["flip_guard"]), ("warp", flip_guard_w))}
    rows["flip_guard"] = {"diff": {"U": _diff(outs["numpy"][0], outs["warp"][0]),
                                   "areas": _diff(outs["numpy"][2], outs["warp"][2]),
                                   "halvings": [outs["numpy"][1], outs["warp"][1]]}}

    bl, Ug, Mg = got["realign_grain"]
    a_, b_ = ORIG["realign_grain"](bl, Ug, Mg), realign_grain_w(bl, Ug, Mg)
    rows["realign_grain"] = {"diff": {"U": _diff(a_[0], b_[0]), **{f"M{j}": _diff(a_[1][j], b_[1][j]) for j in range(4)}}}
    U = Un
    rows["jacobians"] = {"diff": {f"M{j}": _diff(a, b) for j, (a, b) in
                                  enumerate(zip(ORIG["jacobians"](solver, U), jacobians_w(solver, U)))}}

    # timing: the two versions alternate round by round; in-place inputs re-copied in both arms
    aa, bb, gg = a0.copy(), b0.copy(), gain0.copy()
    tf = np.isfinite(cw) & np.isfinite(cg)
    cases = {
        "local_step": (lambda: ORIG["local_step"](cfg, M, tg, W2, dict(st)),
                       lambda: local_step_w(cfg, M, tg, W2, st)),
        "feedback_all_in_warp": (lambda: (np.copyto(aa, a0), np.copyto(bb, b0),
                              ORIG["move_corrections"](cfg2, M2, Kc, cw, cg, aa, bb, None, tf)),
                     lambda: (np.copyto(aa, a0), np.copyto(bb, b0),
                              move_corrections_w(cfg2, M2, Kc, cw, cg, aa, bb, None, tf))),
        "feedback": (lambda: (np.copyto(aa, a0), np.copyto(bb, b0),
                              ORIG["move_corrections"](cfg2, M2, Kc, cw, cg, aa, bb, None, tf)),
                     lambda: (np.copyto(aa, a0), np.copyto(bb, b0),
                              move_corrections_split(cfg2, M2, Kc, cw, cg, aa, bb, None, tf))),
        "collapse_guard": (lambda: (np.copyto(gg, gain0), ORIG["collapse_guard"](g, M3, Kc3, cw3, cg3, gg, inv)),
                           lambda: (np.copyto(gg, gain0), collapse_guard_w(g, M3, Kc3, cw3, cg3, gg, inv))),
        "flip_guard": (lambda: ORIG["flip_guard"](blocks, Uo, Un, s_old),
                       lambda: flip_guard_w(blocks, Uo, Un, s_old)),
        "jacobians": (lambda: ORIG["jacobians"](solver, U), lambda: jacobians_w(solver, U)),
        "realign_grain": (lambda: ORIG["realign_grain"](bl, Ug, Mg), lambda: realign_grain_w(bl, Ug, Mg)),
    }
    st_w = dict(st)
    cases["local_step"] = (cases["local_step"][0], lambda: local_step_w(cfg, M, tg, W2, st_w))
    rows["feedback_all_in_warp"] = {}
    outs = {}
    for name, fn in (("numpy", ORIG["move_corrections"]), ("split", move_corrections_split)):
        a, b = a0.copy(), b0.copy()
        fn(cfg2, M2, Kc, cw, cg, a, b, None, np.isfinite(cw) & np.isfinite(cg))
        outs[name] = (a, b)
    rows["feedback"]["diff_split"] = {"corr_w": _diff(outs["numpy"][0], outs["split"][0]),
                                      "corr_g": _diff(outs["numpy"][1], outs["split"][1])}
    for name, (fn_np, fn_w) in cases.items():
        tn, tw = [], []
        for _ in range(5):
            tn.append(_cpu_us(fn_np, 40, 3))
            tw.append(_cpu_us(fn_w, 40, 3))
        rows[name].update(numpy_us=round(min(tn), 1), warp_us=round(min(tw), 1), speedup=round(min(tn) / min(tw), 2))
    # the launch alone: the local step's kernel on one triangle, its arguments bound
    one = WK.Launch(WK.local_step_kernel, 1)
    args = [M[0], M[1], M[2], M[3], tg["reg"][0], tg["reg"][1], *tg["reg"][2], M[0], M[1], tg["T"][2], tg["T"][3],
            M[0], 0, 0.5, 1, 0.9, 1.1, 1, *(np.empty(len(M[0])) for _ in range(7)), 0]
    one(*args)
    spare = [x.copy() for x in M]
    flip = [0]

    def rebind_all_m():       # the four Jacobians rebound (new arrays every iteration), then the launch
        flip[0] ^= 1
        one(*([spare[j] if flip[0] else M[j] for j in range(4)] + args[4:]))
    rows["launch_overhead_us"] = {
        "warp_recorded_launch_1_thread": round(_cpu_us(one.cmd.launch, 200, 5), 2),
        "direct_entry_1_thread": round(_cpu_us(lambda: one(*args), 200, 5), 2),
        "direct_entry_4_arrays_rebound": round(_cpu_us(rebind_all_m, 200, 5), 2),
        "warp_set_param_from_ctype_one_array": round(_cpu_us(
            lambda: one.cmd.set_param_at_index_from_ctype(0, WK._ctype(M[0])), 200, 5), 2)}
    rows["load"] = load()
    print(json.dumps(rows, indent=1))
    return rows


# ---------------------------------------------------------------------------------------------- whole items
def _digest(folder: Path) -> str:
    h = hashlib.sha256()
    for name in ("pattern.json", "report.json"):
        p = folder / name
        txt = p.read_bytes()
        if name == "report.json":      # timings differ run to run: hash the report without them
            rep = json.loads(txt)
            rep.pop("timings", None)
            rep.pop("optimize_seconds", None)
            txt = json.dumps(rep, sort_keys=True).encode()
        h.update(txt)
    return h.hexdigest()


def items(n, repeats=2):
    """``n`` batch items (the worker's run_item, pattern only) alternating numpy and Warp item by item,
    ``repeats`` times; per-item CPU, figures and file digests."""
    from core.batch.worker import context, run_item
    its = shirt_items(n)
    context(its[0])             # the cut: once, outside the measured items
    with tempfile.TemporaryDirectory(prefix="warp_exp_") as tmp:
        patch(True)
        run_item(its[0], Path(tmp) / "warmup")   # first-use kernel load outside the measurement
        patch(False)
        cpu = {"numpy": [], "warp": []}
        rows = {}
        digests = {}
        raw = []
        print(load())
        for r in range(repeats):
            for i, it in enumerate(its):
                order = ("numpy", "warp") if (i + r) % 2 == 0 else ("warp", "numpy")
                for mode in order:
                    patch(mode == "warp")
                    out = Path(tmp) / f"{mode}{r}"
                    row = run_item(it, out)
                    patch(False)
                    assert row["status"] == "ok", row["error"]
                    cpu[mode].append(row["timings.cpu"])
                    raw.append({"item": i, "round": r, "mode": mode, "first": mode == order[0],
                                "cpu": row["timings.cpu"], "transfer": row["timings.transfer"]})
                    rows.setdefault(mode, {}).setdefault(i, []).append(row)
                    digests.setdefault(mode, {}).setdefault(i, []).append(_digest(out / "items" / it.folder))
        print(load())
    keys = [k for k in rows["numpy"][0][0] if k.startswith("metrics.")]
    worst = {}
    for k in keys:
        worst[k] = max(abs(float(rows["numpy"][i][0][k]) - float(rows["warp"][i][0][k])) for i in rows["numpy"])
    same_np = all(len(set(v)) == 1 for v in digests["numpy"].values())
    same_w = all(len(set(v)) == 1 for v in digests["warp"].values())
    same_both = all(digests["numpy"][i][0] == digests["warp"][i][0] for i in digests["numpy"])
    med = {m: 1000 * float(np.median(v)) for m, v in cpu.items()}
    paired = [1000 * (b - a) for a, b in zip(cpu["numpy"], cpu["warp"])]
    out = {"items": n, "repeats": repeats, "cpu_ms_median": {m: round(v, 1) for m, v in med.items()},
           "items_per_cpu_s": {m: round(1000 / v, 2) for m, v in med.items()},
           "paired_diff_ms_median": round(float(np.median(paired)), 1),
           "transfer_ms_median": {m: round(1000 * float(np.median([r["timings.transfer"] for v in rows[m].values()
                                                                   for r in v])), 1) for m in rows},
           "figures_max_abs_diff": worst, "numpy_runs_same_bytes": same_np, "warp_runs_same_bytes": same_w,
           "numpy_vs_warp_same_bytes": same_both, "load": load()}
    # the pair's difference by which mode ran first (the host's state drifts between the two)
    for first in ("numpy", "warp"):
        d = [1000 * (b["cpu"] - a["cpu"]) for a, b in zip(raw[0::2], raw[1::2]) if a["mode"] == first]
        d = d if first == "numpy" else [-x for x in d]
        out[f"paired_warp_minus_numpy_ms_when_{first}_first"] = round(float(np.median(d)), 1) if d else None
    out["total_cpu_s"] = {m: round(sum(v), 3) for m, v in cpu.items()}
    Path("/tmp/warp_exp_items_raw.json").write_text(json.dumps(raw))
    print(json.dumps(out, indent=1))
    return out


# ---------------------------------------------------------------------------------------------- as the bench
def _worker_setup(repo, here, on):
    import sys as _s
    _s.path[:0] = [repo, here]
    import warp_local_step as X
    X.patch(on)
    return on


def batch(n=30, runs=4):
    """``bench --only batch``'s CPU rate (median CPU of an item, the item that paid for the cut left out)
    through a 1-worker LocalCluster with the bench's worker settings, numpy and Warp runs alternating;
    the Warp drop-ins are installed in the worker process (``Client.run``)."""
    import dask
    from distributed import Client, LocalCluster
    from core.batch import run_batch, sample_anny
    from core.batch.run import WORKER_CONFIG
    from core.design.templates import template_path
    bodies = sample_anny(n, seed=SEED)
    res = {"numpy": [], "warp": []}
    for r in range(runs):
        mode = ("numpy", "warp")[r % 2]
        with dask.config.set(WORKER_CONFIG):
            cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        try:
            client.run(_worker_setup, str(REPO), str(HERE), mode == "warp")
            with tempfile.TemporaryDirectory(prefix="warp_exp_batch_") as tmp:
                l0 = load()
                out = run_batch(template_path("shirt_long_sleeve"), bodies, Path(tmp) / "out",
                                scheduler=cluster.scheduler_address)
                cpu = [row["timings.cpu"] for row in out.rows if row["status"] == "ok" and "timings.setup" not in row]
                med = 1000 * float(np.median(cpu))
                res[mode].append(med)
                print(mode, "made", out.made, "failed", out.failed, "median CPU ms %.1f" % med,
                      "items/CPU-s %.2f" % (1000 / med), l0, "->", load(), flush=True)
        finally:
            client.close()
            cluster.close()
    print(json.dumps({m: [round(v, 1) for v in vals] for m, vals in res.items()}))
    return res


# ---------------------------------------------------------------------------------------------- compile
COMPILE_SNIPPET = r"""
import sys, time
t0 = time.perf_counter(); c0 = time.process_time()
sys.path[:0] = [{repo!r}, {here!r}]
import warp_kernels as WK
wp = WK.wp
wp.init()
t1 = time.perf_counter(); c1 = time.process_time()
wp.load_module(WK, device="cpu")
t2 = time.perf_counter(); c2 = time.process_time()
print("import+init %.3f s (cpu %.3f); module load %.3f s (cpu %.3f)" % (t1 - t0, c1 - c0, t2 - t1, c2 - c1))
"""


def compile_times():
    """First use (empty kernel cache) and cached load, each in a fresh process."""
    py = sys.executable
    code = COMPILE_SNIPPET.format(repo=str(REPO), here=str(HERE))
    with tempfile.TemporaryDirectory(prefix="warp_cache_") as cache:
        env = {**os.environ, "WARP_CACHE_PATH": cache}
        for label in ("cold (empty cache)", "cached", "cached"):
            t = time.perf_counter()
            r = subprocess.run([py, "-c", code], env=env, capture_output=True, text=True, cwd=str(REPO))
            print(label, r.stdout.strip(), "| process %.2f s" % (time.perf_counter() - t), load())
            if r.returncode:
                print(r.stderr[-2000:])
        print("cache size", sum(p.stat().st_size for p in Path(cache).rglob("*") if p.is_file()) // 1024, "kB")


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "calls"
    if what == "calls":
        calls()
    elif what == "items":
        items(int(sys.argv[2]) if len(sys.argv) > 2 else 8, int(sys.argv[3]) if len(sys.argv) > 3 else 2)
    elif what == "batch":
        batch(int(sys.argv[2]) if len(sys.argv) > 2 else 30, int(sys.argv[3]) if len(sys.argv) > 3 else 4)
    elif what == "compile":
        compile_times()
