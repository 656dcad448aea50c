"""The solver's Warp kernels (core/pattern/kernels.py via compiled.py) give numpy's bits, step by step and
for whole patterns, and numpy takes over wherever they do not apply."""

import numpy as np
import pytest
from same_bits import assert_same
from synthetic_pattern import two_panels

from core.pattern.accel import compiled
from core.pattern.config import SolverConfig
from core.pattern.optimizer.feedback import move_corrections
from core.pattern.optimizer.steps import collapse_guard, inverse_offsets, local_step, realign_grain
from core.pattern.optimizer.targets import rest_targets
from core.pattern.solve import PatternSolver, transfer_pattern

# every tail length f % 8, a size under one block of 8, and one of several blocks
SIZES = [5, 8, 9, 10, 11, 12, 13, 14, 15, 83]


@pytest.fixture
def both():
    """Run a step with numpy and with the kernels: ``both(fn)`` -> (numpy's result, the kernels')."""
    assert compiled.load(), "Warp kernels failed to load (see the log's warning)"

    def run(fn):
        try:
            compiled.use(False)
            ref = fn()
            compiled.use(True)
            return ref, fn()
        finally:
            compiled.use(None)

    return run


@pytest.fixture
def kernels_on(monkeypatch):
    """The kernels on for the test, whatever EASE_SOLVER_KERNELS says."""
    assert compiled.load(), "Warp kernels failed to load (see the log's warning)"
    monkeypatch.setitem(compiled._state, "forced", True)


@pytest.fixture
def ran(monkeypatch):
    """How many calls of each of :mod:`core.pattern.accel.compiled`'s steps the kernels did (gave a result) in
    the test: a comparison with numpy only tests the kernels where they ran."""
    counts = {}
    for name in (
        "local_step",
        "ratios",
        "collapse_guard",
        "grain_votes",
        "turned",
        "flip_check",
        "corrections",
        "rhs_terms",
    ):

        def spy(*args, _step=getattr(compiled, name), _name=name):
            got = _step(*args)
            counts[_name] = counts.get(_name, 0) + (got is not None and got is not False)
            return got

        monkeypatch.setattr(compiled, name, spy)
    return counts


def _inputs(f, seed, collapse=False):
    rng = np.random.default_rng(seed)
    K = rng.normal(0, 0.01, (f, 2, 2)) + np.array([[0.01, 0.0], [0.0, 0.012]])
    Kc = [np.ascontiguousarray(K[:, i, j]) for i in range(2) for j in range(2)]
    M = [rng.normal(m, 0.3, f) for m in (1.1, 0.0, 0.0, 0.9)]
    if collapse:
        M[0][: f // 3] *= 0.1  # some triangles near collapse, some flipped
        M[3][: f // 5] *= -0.5
    cw, cg = rng.uniform(0.9, 1.6, f), rng.uniform(0.95, 1.2, f)
    return rng, K, Kc, M, cw, cg


@pytest.mark.same_bits
@pytest.mark.parametrize("f", SIZES)
@pytest.mark.parametrize("name", ["improved", "paper", "lengths", "stretch"])
def test_local_step_same_bits(both, f, name):
    cfg = SolverConfig.named(name)
    _, K, Kc, M, cw, cg = _inputs(f, f)
    M[0][0] = M[1][0] = M[2][0] = M[3][0] = 0.0  # r = 0: no rotation to find
    tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
    W2 = np.ones(2)

    def run():
        state = {}
        first = local_step(cfg, M, tg, W2, state)
        second = local_step(cfg, M, tg, W2, state)  # with the first call's warp factors
        return first, second, state.get("sw")

    ref, got = both(run)
    assert_same(ref[:2], got[:2])
    if ref[2] is not None:
        assert_same(ref[2], got[2])


@pytest.mark.same_bits
def test_local_step_nan_lanes_fall_back_to_numpy(both):
    cfg = SolverConfig.named("improved")
    _, K, Kc, M, cw, cg = _inputs(83, 3)
    M[2][7] = np.nan  # the warp factor's clip meets a NaN
    tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
    ref, got = both(lambda: local_step(cfg, M, tg, np.ones(2), {}))
    assert_same(ref, got)
    assert np.isnan(got[0][2][7])  # numpy's NaN, not Warp's clipped value


# zeros of both signs, subnormals, values whose squares underflow or overflow, and the non-finite ones
FINITE = [
    0.0,
    -0.0,
    5e-324,
    -5e-324,
    1e-310,
    2.2250738585072014e-308,
    1e-160,
    -1e-160,
    1e-300,
    1.0,
    -1.0,
    1e154,
    -1e154,
    1e200,
]
NON_FINITE = FINITE + [np.inf, -np.inf, np.nan, -np.nan]


def _sprinkle(rng, arrays, values, share):
    """``share`` of each array's entries set to values drawn from ``values`` (in place)."""
    for a in arrays:
        at = rng.random(len(a)) < share
        a[at] = rng.choice(values, at.sum())


@pytest.mark.same_bits
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's overflow / invalid notes
@pytest.mark.parametrize("finite", [True, False])
@pytest.mark.parametrize("name", ["improved", "paper", "lengths", "stretch"])
def test_local_step_special_values_same_bits(both, ran, name, finite):
    cfg = SolverConfig.named(name)
    for seed in range(8):
        rng, K, Kc, M, cw, cg = _inputs(83, 300 + seed)
        tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
        tg = {
            "T": [t.copy() for t in tg["T"]],
            "reg": (tg["reg"][0].copy(), tg["reg"][1].copy(), [x.copy() for x in tg["reg"][2]]),
        }
        values = FINITE if finite else NON_FINITE
        _sprinkle(rng, M, values, 0.3)
        _sprinkle(rng, [*tg["T"], tg["reg"][0], tg["reg"][1], *tg["reg"][2]], values, 0.1)

        def run():
            state = {}
            return local_step(cfg, M, tg, np.ones(2), state), local_step(cfg, M, tg, np.ones(2), state)

        ref, got = both(run)
        assert_same(ref, got)
    if cfg.rest_shape.warp_slack == 0:  # no clip, so no NaN to meet one: the kernels always run
        assert ran["local_step"] == 16


@pytest.mark.same_bits
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's overflow / invalid notes
@pytest.mark.parametrize("gains", [(0.15, 0.0), (2.0, 0.5), (1.0, 1.0), (0.5, 2.0), (0.7, 0.3), (2, 1)])
def test_feedback_special_values_same_bits(both, ran, gains):
    """Subnormal and signed-zero shears, extreme targets, and the gains numpy's ``**`` computes
    otherwise (2: a square, 0.5: a square root, 1: a copy) keep numpy's bits."""
    cfg = SolverConfig.named("lengths", feedback={"weft": gains[0], "warp": gains[1]})
    for seed in range(8):
        rng, K, Kc, M, cw, cg = _inputs(83, 400 + seed)
        _sprinkle(rng, [M[1], M[2]], [0.0, -0.0, 5e-324, -5e-324, 1e-310, 1e-160, -1e-160], 0.3)
        _sprinkle(rng, [cw, cg], [1e-300, 5e-324, 1e300, 1e-10, 1e10, 1.0, 0.0, -0.0, -1.0], 0.2)

        def run():
            cw_corr, cg_corr = np.linspace(0.9, 1.1, 83), np.linspace(1.05, 0.95, 83)
            move_corrections(cfg, M, Kc, cw, cg, cw_corr, cg_corr)
            return cw_corr, cg_corr

        ref, got = both(run)
        assert_same(ref, got)
    assert ran["ratios"] == 8


@pytest.mark.same_bits
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's overflow / invalid notes
@pytest.mark.parametrize("finite", [True, False])
def test_collapse_guard_special_values_same_bits(both, ran, finite):
    guard = SolverConfig.named("improved").guard
    # gains: signed zeros, a subnormal, one raised to exactly 1, one released to exactly 1, the limit
    gains = [0.0, -0.0, 5e-324, 1.0 / guard.guard_grow, 1.0, 1.0 / guard.guard_release, 3.0, guard.guard_limit]
    for seed in range(8):
        rng, K, Kc, M, cw, cg = _inputs(83, 500 + seed, collapse=True)
        _sprinkle(rng, M, FINITE if finite else NON_FINITE, 0.2)
        _sprinkle(rng, Kc, FINITE, 0.05)
        start = rng.choice(gains, 83)

        def run():
            gain = start.copy()
            q, held = collapse_guard(guard, M, Kc, cw, cg, gain, inverse_offsets(Kc))
            return q, held, gain

        ref, got = both(run)
        assert_same(ref, got)
    assert ran["collapse_guard"] == 8


@pytest.mark.same_bits
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy's overflow / invalid notes
@pytest.mark.parametrize("finite", [True, False])
def test_realign_grain_special_values_same_bits(both, ran, tube, finite):
    _, _, solver = tube
    for seed in range(8):
        rng = np.random.default_rng(600 + seed)
        U = solver.uv0 + rng.normal(0, 1e-3, solver.uv0.shape)
        M = solver.jacobians(U)
        _sprinkle(rng, M, FINITE if finite else NON_FINITE, 0.05)
        ref, got = both(lambda: realign_grain(solver.blocks, U, M))
        assert_same(ref, got)
    assert ran["turned"] == 8


@pytest.mark.same_bits
@pytest.mark.parametrize("f", SIZES)
@pytest.mark.parametrize("poison", [None, "target", "jacobian"])
def test_feedback_same_bits(both, f, poison):
    cfg = SolverConfig.named("lengths")
    _, K, Kc, M, cw, cg = _inputs(f, 100 + f)
    if poison == "target":
        cw[f // 2] = np.inf  # the feedback leaves that triangle
    elif poison == "jacobian":
        M[0][1] = M[1][1] = 0.0  # a degenerate triangle: rho infinite or NaN
        M[2][1] = M[3][1] = 0.0

    def run():
        cw_corr, cg_corr = np.linspace(0.9, 1.1, f), np.linspace(1.05, 0.95, f)
        move_corrections(cfg, M, Kc, cw, cg, cw_corr, cg_corr)
        return cw_corr, cg_corr

    ref, got = both(run)
    assert_same(ref, got)


@pytest.mark.same_bits
@pytest.mark.parametrize("name", ["improved", "lengths", "paper", "stretch"])
@pytest.mark.parametrize("poison", [None, "nan_correction", "far"])
def test_feedback_corrections_same_bits(both, ran, name, poison):
    """The feedback's clips and products after numpy's power, in the kernel: one gain, both, none; a NaN
    correction (numpy's clip keeps it: numpy's path) and ratios far off (the per-step bound and the
    ceiling bite)."""
    cfg = SolverConfig.named(name)
    _, K, Kc, M, cw, cg = _inputs(83, 7)
    if poison == "far":
        cw = cw * 40.0
    start_w, start_g = np.linspace(0.9, 1.1, 83), np.linspace(1.05, 0.95, 83)
    if poison == "nan_correction":
        start_w[4] = np.nan

    def run():
        a, b = start_w.copy(), start_g.copy()
        move_corrections(cfg, M, Kc, cw, cg, a, b)
        return a, b

    ref, got = both(run)
    assert_same(ref, got)
    assert ran.get("corrections", 0) == (0 if poison == "nan_correction" else 1)


@pytest.mark.same_bits
@pytest.mark.parametrize("lam", [(1.0, 1.0), (2.0, 1.0), (1.0, 0.5), (0.0, 3.0)])
def test_rhs_terms_same_bits(both, ran, lam):
    """The right-hand side's terms lambda_reg R T + lambda_ease T in the kernel, unit weights included."""
    from core.pattern.optimizer.steps import rhs_terms

    rng = np.random.default_rng(9)
    RT0, T = [rng.normal(0, 1, 83) for _ in range(4)], [rng.normal(0, 1, 83) for _ in range(4)]
    RT0[0][:3] = [-0.0, 0.0, np.inf]

    def run():
        with np.errstate(invalid="ignore"):  # 0 x inf where lambda_reg is 0: NaN in both
            return rhs_terms([x.copy() for x in RT0], T, *lam)

    ref, got = both(run)
    assert_same(ref, got)
    assert ran.get("rhs_terms") == 1


@pytest.mark.same_bits
@pytest.mark.parametrize("f", SIZES)
def test_collapse_guard_same_bits(both, f):
    guard = SolverConfig.named("improved").guard
    rng, K, Kc, M, cw, cg = _inputs(f, 200 + f, collapse=True)
    Kc[0][-1] = Kc[1][-1] = 0.0  # a degenerate body triangle: det K = 0
    M[1][f // 2] = np.nan  # a non-finite iterate
    start = rng.choice([0.0, 1.0, 1.5, guard.guard_limit, 2.0 / guard.guard_release], f)

    def run():
        gain = start.copy()
        q, held = collapse_guard(guard, M, Kc, cw, cg, gain, inverse_offsets(Kc))
        return q, held, gain

    ref, got = both(run)
    assert_same(ref, got)
    if f == SIZES[-1]:  # the cases the update distinguishes all occur
        gain = ref[2]
        assert ref[1].size and (gain > start).any() and ((start > 0) & (gain < start)).any() and (gain == 0).any()


@pytest.mark.same_bits
@pytest.mark.parametrize("grow, over", [(2.0, True), (2.0, False), (0.9, False)])
def test_collapse_guard_gains_at_or_over_the_limit(both, ran, grow, over):
    """numpy raises the low triangles' gains only if one is under the limit: where all are at it (or over
    it, as a resumed solve's gains after an escalated limit) it leaves them, and so must the kernel."""
    from dataclasses import replace

    from core.pattern.optimizer.steps import relative_singular_values

    guard = replace(SolverConfig.named("improved").guard, guard_grow=grow)
    f = 83
    rng, K, Kc, M, cw, cg = _inputs(f, 5, collapse=True)
    inverse = inverse_offsets(Kc)
    _, s2, _ = relative_singular_values(M, Kc, cw, cg, inverse)
    low = inverse[1] & (s2 < guard.guard_scale)
    start = np.where(low, guard.guard_limit, rng.choice([0.0, 1.0, 4.0], f))
    if over:
        start[np.flatnonzero(low)[::2]] *= 3.0

    def run():
        gain = start.copy()
        q, held = collapse_guard(guard, M, Kc, cw, cg, gain, inverse)
        return q, held, gain

    ref, got = both(run)
    assert_same(ref, got)
    assert low.sum() > 3 and np.array_equal(ref[2][low], start[low])  # numpy left them
    assert ran.get("collapse_guard", 0) == (0 if over or grow < 1 else 1)


def _unaligned(x):
    buf = np.zeros(x.nbytes + 1, np.uint8)
    out = np.frombuffer(buf.data, np.float64, len(x), offset=1)
    out.flags.writeable = True
    out[:] = x
    return out


class _Sub(np.ndarray):
    pass


UNSUITABLE = {
    "float32": lambda x: x.astype(np.float32),
    "int32": lambda x: (x * 100).astype(np.int32),  # an int32 array in a float64 slot: read past its end
    "int64": lambda x: (x * 100).astype(np.int64),
    "big-endian": lambda x: x.astype(">f8"),
    "strided": lambda x: np.repeat(x, 2)[::2],
    "longer": lambda x: np.append(x, 1.0),
    "2-d": lambda x: x[:, None],
    "unaligned": _unaligned,
    "subclass": lambda x: x.view(_Sub),
    "list": lambda x: list(x),
}


@pytest.mark.same_bits
@pytest.mark.parametrize("kind", sorted(UNSUITABLE))
def test_unsuitable_arrays_go_to_numpy(both, ran, kind):
    """An argument the kernels cannot read as a float64 (f,) array: numpy takes the call, and the
    launches' arguments rebound before it was met stay consistent (the next calls give numpy's bits)."""
    cfg = SolverConfig.named("lengths")
    f = 83
    _, K, Kc, M, cw, cg = _inputs(f, 21)
    bad = UNSUITABLE[kind](cg)

    def run():
        out = []
        for M_, c_warp in ((M, cg), ([m * 1.01 for m in M], bad), (M, cg)):
            if c_warp is bad:  # M_ is rebound before c_warp is met
                out.append(compiled.ratios(M_, Kc, cw, bad))
                continue
            a, b = np.linspace(0.9, 1.1, f), np.linspace(1.05, 0.95, f)
            move_corrections(cfg, M_, Kc, cw, c_warp, a, b)
            out += [a, b]
        return out

    ref, got = both(run)
    assert got[2] is None
    assert_same(ref[:2] + ref[3:], got[:2] + got[3:])
    assert ran["ratios"] == 2
    assert compiled.turned(M, bad, cw) is None  # no flags there: the launcher alone refuses it


@pytest.mark.same_bits
def test_equal_float64_dtypes_and_read_only_arrays_run(both, ran):
    """Arrays that came through pickle (a Dask worker's: an equal float64 dtype, another object) and
    read-only ones are the kernels' too."""
    import pickle

    cfg = SolverConfig.named("improved")
    _, K, Kc, M, cw, cg = _inputs(83, 31)
    M = pickle.loads(pickle.dumps(M))
    assert M[0].dtype is not np.dtype(np.float64)
    for x in Kc:
        x.flags.writeable = False
    tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
    ref, got = both(lambda: local_step(cfg, M, tg, np.ones(2), {}))
    assert_same(ref, got)
    assert ran["local_step"] == 1


def test_launches_keep_no_arrays_and_few_sizes(kernels_on, monkeypatch):
    """The kept launches hold no array past its call (a solve's memory goes with it), and a thread keeps
    launches for a few sizes only (a batch over many designs meets a new size with every design)."""
    import weakref

    monkeypatch.setattr(compiled._local, "launches", {}, raising=False)
    rng = np.random.default_rng(0)
    for f in range(8, 8 + 2 * compiled._KEPT):
        for _ in range(2):  # recorded, then rebound
            M = [rng.normal(size=f) for _ in range(4)]
            ct, st = rng.normal(size=f), rng.normal(size=f)
            out = compiled.turned(M, ct, st)
            assert out is not None
            arrays = [weakref.ref(x) for x in (*M, ct, st, out[0].base)]
            del M, ct, st, out
            assert not any(r() is not None for r in arrays)
    assert len(compiled._local.launches) == compiled._KEPT


@pytest.fixture(scope="module")
def tube():
    cut, body = two_panels(ease=(1.2, 1.6), bulge=0.2)
    return cut, body, PatternSolver(cut, body)


@pytest.mark.same_bits
@pytest.mark.parametrize("case", ["small", "flipping", "nan_old", "nan_step"])
def test_flip_guard_same_bits(both, ran, tube, case):
    """The flip guard's first check in the kernel: a step that cuts nothing is the kernel's alone; one
    with a triangle at its floor, or a NaN where Warp's min and numpy's part, is numpy's."""
    from core.pattern.optimizer.steps import face_areas, flip_guard

    _, _, solver = tube
    rng = np.random.default_rng(3)
    U_old = solver.uv0 * 1.02
    s_old = face_areas(solver.blocks, U_old)
    U_new = U_old + rng.normal(0, 1e-4 if case != "flipping" else 2e-2, U_old.shape)
    if case == "nan_old":
        s_old = s_old.copy()
        s_old[5] = np.nan
    elif case == "nan_step":
        U_new[7] = np.nan
    ref, got = both(lambda: flip_guard(solver.blocks, U_old, U_new, s_old))
    assert_same(ref, got)
    # the check ran but for the NaN floor; a step with a triangle at its floor went on to numpy's halving
    assert ran.get("flip_check", 0) == (0 if case == "nan_old" else 1)
    assert (ref[1] > 0) == (case == "flipping")


@pytest.mark.same_bits
def test_realign_grain_same_bits(both, tube):
    _, _, solver = tube
    rng = np.random.default_rng(7)
    U = solver.uv0 + rng.normal(0, 1e-3, solver.uv0.shape)
    M = solver.jacobians(U)
    ref, got = both(lambda: realign_grain(solver.blocks, U, M))
    assert_same(ref, got)
    M[0][3] = np.nan  # a NaN image: numpy's path (its NaN vote)
    ref, got = both(lambda: realign_grain(solver.blocks, U, M))
    assert_same(ref, got)


@pytest.mark.same_bits
@pytest.mark.parametrize("name", ["improved", "paper", "lengths"])
def test_transfer_same_bits(both, tube, name):
    cut, body, _ = tube
    big = body * np.array([1.1, 1.05, 1.0])

    def run():
        p = transfer_pattern(cut, body, big, config=SolverConfig.named(name), solver=PatternSolver(cut, body))
        return [x for pn in p.panels for x in (pn.uv, pn.target_weft, pn.target_warp)]

    ref, got = both(run)
    assert_same(ref, got)


@pytest.mark.same_bits
def test_threads_same_bits(tube, ran):
    """Solves in several threads at once (Dask workers' threads, the add-on's background solve): each
    thread binds its own launches, and every pattern is numpy's."""
    from concurrent.futures import ThreadPoolExecutor

    cut, body, _ = tube
    sizes = [body * np.array([1.0 + 0.03 * i, 1.05, 1.0]) for i in range(4)]

    def run(solver, big):
        p = transfer_pattern(cut, body, big, config=SolverConfig.named("improved"), solver=solver)
        return [x for pn in p.panels for x in (pn.uv, pn.target_weft, pn.target_warp)]

    assert compiled.load()
    compiled.use(False)
    try:
        numpy_solver = PatternSolver(cut, body)  # a solver chooses its path when built
        compiled.use(True)
        solvers = [PatternSolver(cut, body) for _ in sizes]  # a solver is one thread's
        compiled.use(None)
        assert not numpy_solver.kernels and all(s.kernels for s in solvers)
        ref = [run(numpy_solver, big) for big in sizes]
        with ThreadPoolExecutor(len(sizes)) as pool:
            got = list(pool.map(run, solvers, sizes))
    finally:
        compiled.use(None)
    assert_same(ref, got, rtol=1e-6, atol=1e-9)
    assert ran["local_step"] > 0


def test_only_warps_public_api():
    """The launches use Warp's public API only (recorded launches, ``set_param_at_index*``, ``__ctype__``):
    nothing of ``warp._src`` and no private attribute of a Warp object, so another warp-lang release
    either runs them or refuses a launch (then numpy, one warning)."""
    import re
    from pathlib import Path

    for name in ("compiled", "ldl", "products"):
        src = (Path(compiled.__file__).parent / f"{name}.py").read_text()
        assert "_src" not in src and "_invoke_cache" not in src and ".hooks" not in src, name
        assert not re.search(r"\b(wp|cmd|kernel)\._[a-z]", src), name


def test_a_solver_keeps_the_path_it_chose_when_built(tube, ran, monkeypatch):
    """The choice is made once, when a solver is built: switching the environment afterwards changes
    nothing for that solver's solves (and a solver built after the switch follows it)."""
    cut, body, _ = tube
    big = body * np.array([1.1, 1.05, 1.0])
    monkeypatch.setenv(compiled.ENV, "warp")
    kept = PatternSolver(cut, body)
    monkeypatch.setenv(compiled.ENV, "numpy")
    transfer_pattern(cut, body, big, solver=kept)
    assert kept.kernels and ran["local_step"] > 0
    ran.clear()
    fresh = PatternSolver(cut, body)
    transfer_pattern(cut, body, big, solver=fresh)
    assert not fresh.kernels and ran.get("local_step", 0) == 0


def test_switches(monkeypatch):
    monkeypatch.setenv(compiled.ENV, "numpy")
    assert not compiled.enabled()
    monkeypatch.setenv(compiled.ENV, "warp")
    assert compiled.enabled()
    monkeypatch.setenv(compiled.ENV, "off")  # not a value: numpy (the reference), with a warning
    assert not compiled.enabled()
    compiled.use(False)
    try:
        assert not compiled.enabled()
    finally:
        compiled.use(None)


def test_numpy_asked_for_loads_no_kernels(monkeypatch, tube):
    """``EASE_SOLVER_KERNELS=numpy``: a solver's set-up neither imports nor compiles the kernels."""
    cut, body, _ = tube
    monkeypatch.setenv(compiled.ENV, "numpy")
    monkeypatch.setitem(compiled._state, "ready", None)
    PatternSolver(cut, body)
    assert compiled._state["ready"] is None


def test_a_failed_load_leaves_numpy(monkeypatch, caplog):
    import core.geom.queries as Q

    def broken():
        raise RuntimeError("no compiler")

    monkeypatch.setattr(Q, "init_cpu", broken)
    monkeypatch.setitem(compiled._state, "ready", None)
    assert not compiled.load()
    assert "using numpy" in caplog.text
    assert not compiled.enabled()


@pytest.mark.same_bits
def test_a_failed_launch_leaves_numpy(both, monkeypatch, caplog):
    """A launch Warp refuses: numpy's result, one warning, and numpy for the rest of the process."""

    def broken(*args):
        raise RuntimeError("no launch")

    cfg = SolverConfig.named("improved")
    _, K, Kc, M, cw, cg = _inputs(83, 41)
    tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
    monkeypatch.setattr(compiled._Launch, "__init__", broken)
    monkeypatch.setattr(compiled._local, "launches", {}, raising=False)
    monkeypatch.setitem(compiled._state, "ready", True)
    ref, got = both(lambda: [local_step(cfg, M, tg, np.ones(2), {}) for _ in range(2)])
    assert_same(ref, got)
    assert caplog.text.count("using numpy") == 1
    assert not compiled.enabled()


def test_a_scalar_rebound_when_only_its_sign_of_zero_changes(kernels_on, monkeypatch):
    """0.0 == -0.0, but the kernel must see the one it is given (the recorded launch's parameter)."""
    import math

    monkeypatch.setattr(compiled._local, "launches", {}, raising=False)
    _, K, Kc, M, cw, cg = _inputs(16, 51)
    for om in (0.0, -0.0):
        assert compiled.local_step(M, cw, cg, Kc, (cw, cg), Kc, None, om, False, 1.0, 1.0) is not None
    (pair,) = compiled._local.launches.values()
    for launch in pair.launches:
        om = [a.label for a in launch.cmd.kernel.adj.args].index("om")
        assert math.copysign(1.0, launch.cmd.params[1 + om].value) == -1.0
