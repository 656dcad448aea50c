"""core.pattern.accel.ldl: QDLDL's factors refactorised row by row and solved two columns at once, with qdldl's bits."""

import pickle

import numpy as np
import pytest
import qdldl
import scipy.sparse as sp
from same_bits import assert_same_floats

from core.pattern.accel import compiled
from core.pattern.optimizer.factor import SymmetricFactor


@pytest.fixture
def kernels_on(monkeypatch):
    assert compiled.load(), "Warp kernels failed to load (see the log's warning)"
    monkeypatch.setitem(compiled._state, "forced", True)
    from core.pattern.accel.ldl import matches_qdldl

    if not matches_qdldl():
        pytest.skip(
            "this machine's qdldl build has other bits than the kernels (fused multiply-adds): qdldl factorises"
        )


def _spd(n, seed, blocks=1, density=4):
    """A random SPD matrix (a weighted graph Laplacian plus a diagonal), ``blocks`` unconnected parts."""
    rng = np.random.default_rng(seed)
    parts = []
    for b in range(blocks):
        m = max(1, n // blocks)
        i, j = rng.integers(0, m, density * m), rng.integers(0, m, density * m)
        W = sp.coo_matrix((rng.random(density * m), (i, j)), shape=(m, m)).tocsc()
        W = W + W.T
        W.setdiag(0)
        parts.append(sp.diags(np.asarray(abs(W).sum(axis=1)).ravel()) - W + sp.diags(0.1 + rng.random(m)))
    A = sp.block_diag(parts).tocsc()
    A.eliminate_zeros()
    return A


def _bits(a):
    return np.ascontiguousarray(a, float).view(np.int64)


def _changed(f: SymmetricFactor, kind: str, seed: int) -> np.ndarray:
    """New values on ``f``'s pattern, still SPD: ``kind`` says which change."""
    rng = np.random.default_rng(seed)
    A = f.matrix
    data = A.data.copy()
    n = f.n
    diag = f.positions(np.arange(n), np.arange(n))
    if kind == "none":
        return data
    if kind == "one_diagonal":
        data[diag[rng.integers(n)]] *= 3.0
        return data
    if kind == "all":
        return data * (1.0 + 0.5 * rng.random()) + 0.0
    # a few symmetric off-diagonal pairs scaled, the diagonals raised to keep dominance
    rows, cols = A.indices, np.repeat(np.arange(n), np.diff(A.indptr))
    off = np.flatnonzero(rows < cols)
    if len(off) == 0:
        data[diag] *= 1.5
        return data
    pick = rng.choice(off, size=min(3, len(off)), replace=False)
    for e in pick:
        r, c = rows[e], cols[e]
        s = 1.0 + rng.random()
        data[e] *= s
        data[f.positions(np.array([c]), np.array([r]))] *= s
        data[diag[[r, c]]] += abs(data[e]) * s
    return data


MATRICES = [(1, 1), (2, 1), (5, 1), (60, 1), (300, 1), (300, 3), (40, 40)]


@pytest.mark.same_bits
@pytest.mark.parametrize("n, blocks", MATRICES)
@pytest.mark.parametrize("kind", ["none", "one_diagonal", "pairs", "all"])
def test_refactorised_factors_are_qdldls_bits(kernels_on, n, blocks, kind):
    f = SymmetricFactor(_spd(n, seed=n + blocks, blocks=blocks))
    assert f._ldl is not None
    data = _changed(f, kind, seed=7)
    g = f.with_values(data)  # a copy of f's factors, the changed rows recomputed
    h = f.with_values(_changed(f, "pairs", 3))
    h = f.with_values(data, reuse=h)  # refactorised in place from other values
    B = sp.csc_matrix((data, f.matrix.indices, f.matrix.indptr), shape=f.matrix.shape)
    ref = qdldl.Solver(sp.triu(B, format="csc"), upper=True)
    L, D, _ = ref.factors()
    for x in (g, h):
        assert_same_floats(x._ldl.Lx, L.data)
        assert_same_floats(x._ldl.D, D)
    rhs = np.random.default_rng(1).standard_normal((f.n, 3))
    want = np.stack([ref.solve(np.ascontiguousarray(rhs[:, j])) for j in range(3)], 1)
    for x in (g, h):
        assert_same_floats(x.solve(rhs), want)
        assert_same_floats(x.solve(rhs[:, :2]), want[:, :2])
        assert_same_floats(x.solve(rhs[:, 0]), want[:, 0])
        assert_same_floats(x.solve(rhs[:, 1:2]), want[:, 1:2])


def test_only_the_reached_rows_are_recomputed(kernels_on, monkeypatch):
    """A change in one column recomputes that row and its elimination-tree ancestors, no other."""
    f = SymmetricFactor(_spd(300, seed=5, blocks=3))
    plan = f._ldl.plan
    data = f.matrix.data.copy()
    k = 17
    data[f.positions(np.array([k]), np.array([k]))] *= 2.0
    g = f.with_values(data)
    col = int(plan.entry_column[f.positions(np.array([k]), np.array([k]))[0]])
    path = [col]
    while plan.etree[path[-1]] != -1:
        path.append(int(plan.etree[path[-1]]))
    moved = np.flatnonzero(_bits(g._ldl.D) != _bits(f._ldl.D))
    assert set(moved) <= set(path) and col in moved and len(path) < plan.n // 2
    rows_l = np.flatnonzero(_bits(g._ldl.Lx) != _bits(f._ldl.Lx))
    assert set(plan.Li[rows_l]) <= set(path)


def test_the_original_is_untouched(kernels_on):
    f = SymmetricFactor(_spd(60, seed=2))
    b = np.random.default_rng(2).random((f.n, 2))
    x0 = f.solve(b)
    g = f.with_values(_changed(f, "all", 4))
    g = f.with_values(_changed(f, "pairs", 5), reuse=g)
    assert not np.array_equal(g.solve(b), x0)
    assert np.array_equal(f.solve(b), x0)


@pytest.mark.same_bits
def test_kernels_and_qdldl_give_the_same_bits_on_a_solvers_guarded_matrices(kernels_on, monkeypatch):
    """The solver's own system matrix and the collapse guard's stiffenings of it, refactorised in turn."""
    from synthetic_pattern import two_panels

    from core.pattern.solve import PatternSolver

    cut, body = two_panels(ease=(1.2, 1.6), bulge=0.2)
    rng = np.random.default_rng(0)
    results = []
    for forced in (False, True):
        monkeypatch.setitem(compiled._state, "forced", forced)
        solver = PatternSolver(cut, body)
        K, cw, cg = solver.targets_reference()
        plan = solver.plan_seams(K, cw, cg)
        base, _ = solver.factorisation(None, plan)
        assert (base._ldl is not None) == forced
        rng = np.random.default_rng(0)
        rhs = rng.standard_normal((base.n, 2))
        out, fac = [base(rhs)], None
        for _ in range(4):
            gain = np.where(rng.random(len(solver.gfaces)) < 0.05, rng.random(len(solver.gfaces)) * 8, 0.0)
            fac = solver.guarded_factorisation(None, plan, gain, reuse=fac)
            out.append(fac(rhs))
        results.append(out)
    for a, b in zip(*results):
        assert_same_floats(a, b)


@pytest.mark.same_bits
def test_a_failed_launch_leaves_qdldl(kernels_on, monkeypatch, caplog):
    """A launch Warp refuses: qdldl's bits, one warning, and qdldl (and numpy) for the rest of the process."""
    from core.pattern.accel.ldl import LDL

    f = SymmetricFactor(_spd(60, seed=3))
    data = _changed(f, "pairs", 6)
    g_ref = f.with_values(data)
    b = np.random.default_rng(3).random((f.n, 2))
    want = g_ref.solve(b)

    def broken(self):
        raise RuntimeError("no launch")

    monkeypatch.setattr(LDL, "_rows_record", broken)
    monkeypatch.setattr(LDL, "_solve_record", broken)
    monkeypatch.setitem(compiled._state, "ready", True)
    g = f.with_values(data)
    assert g._ldl is None
    assert_same_floats(g.solve(b), want)
    assert caplog.text.count("using numpy") == 1
    assert not compiled.enabled()
    assert_same_floats(f.solve(b), SymmetricFactor(f.matrix).solve(b))


def test_a_zero_pivot_is_refused(kernels_on, monkeypatch):
    """A new factorisation with a zero pivot is the pattern's one-line refusal on both paths (issue 30:
    it was a ValueError traceback with the kernels, a RuntimeError from qdldl without them)."""
    from core.errors import PatternError

    for forced in (True, False):
        monkeypatch.setitem(compiled._state, "forced", forced)
        f = SymmetricFactor(sp.diags([2.0, 3.0, 4.0]).tocsc())
        with pytest.raises(PatternError, match="zero pivot"):
            f.with_values(np.array([2.0, 0.0, 4.0]))


@pytest.mark.same_bits
def test_a_pickled_factor_solves(kernels_on):
    f = SymmetricFactor(_spd(60, seed=4))
    b = np.random.default_rng(4).random((f.n, 2))
    x = f.solve(b)  # its launches are recorded now
    g = pickle.loads(pickle.dumps(f))
    assert_same_floats(g.solve(b), x)


@pytest.mark.same_bits
def test_a_refused_refactorisation_goes_on_as_qdldl_and_refactorises_to_qdldls_bits(kernels_on, monkeypatch):
    """A zero pivot in a reused factor's refactorisation is handed to qdldl's update, as without the
    kernels (which does not raise): both paths solve alike after it, and the next values are qdldl's
    bits, not the refused matrix's rows left beside them."""
    out = {}
    for forced in (True, False):
        monkeypatch.setitem(compiled._state, "forced", forced)
        f = SymmetricFactor(sp.diags([2.0, 3.0, 4.0]).tocsc())
        g = f.with_values(np.array([2.0, 3.0, 4.0]))
        g = f.with_values(np.array([2.0, 0.0, 4.0]), reuse=g)  # no traceback
        out[forced] = g.solve(np.ones(3))
        g = f.with_values(np.array([2.0, 3.0, 5.0]), reuse=g)
        assert_same_floats(g.solve(np.ones(3)), [1 / 2, 1 / 3, 1 / 5])
    assert_same_floats(out[True], out[False])


@pytest.mark.same_bits
def test_a_failed_plan_launch_leaves_qdldl(kernels_on, monkeypatch, caplog):
    """The symbolic plan's launch refused: the factor is qdldl's (not an error), one warning."""
    from core.pattern.accel import ldl

    def broken(self, *args):
        raise RuntimeError("no launch")

    A = _spd(60, seed=8)
    want = SymmetricFactor(A).solve(np.ones(60))
    monkeypatch.setattr(ldl.Plan, "__init__", broken)
    monkeypatch.setitem(compiled._state, "ready", True)
    f = SymmetricFactor(A)
    assert f._ldl is None and f._qdldl is not None and not compiled.enabled()
    assert_same_floats(f.solve(np.ones(60)), want)
    assert caplog.text.count("using numpy") == 1


def test_a_wrong_right_hand_side_raises_and_leaves_the_kernels_on(kernels_on, monkeypatch):
    """A caller's mistake is a ValueError, as qdldl's, not a failed launch turning the kernels off."""
    monkeypatch.setitem(compiled._state, "ready", True)
    f = SymmetricFactor(_spd(60, seed=9))
    for rhs in (np.ones(61), np.ones((59, 2)), np.ones((60, 2, 1))):
        with pytest.raises(ValueError):
            f.solve(rhs)
    assert compiled.enabled() and f._ldl is not None


def test_factors_past_int32_indices_stay_qdldls():
    """qdldl's indices are 64-bit, the kernels' int32: an L with 2**31 entries is left to qdldl."""
    from types import SimpleNamespace

    from core.pattern.accel.ldl import LDL

    L = SimpleNamespace(indptr=np.array([0, 2**31], np.int64), indices=np.zeros(0, np.int32), data=np.zeros(0))
    solver = SimpleNamespace(factors=lambda: (L, np.ones(1), np.zeros(1, np.int64)))
    upper = (np.array([0]), np.array([0], np.int32), np.array([0, 1], np.int32))
    assert LDL.from_qdldl(solver, upper, np.ones(1)) is None


def _edge(kind: str):
    """(matrix, values to refactorise to in turn) for the cases where QDLDL's bits are easiest to miss."""
    if kind == "no_diagonal":  # quasi-definite: D starts at 0 where a diagonal is missing
        A = sp.csc_matrix(np.array([[1.0, 1.0, 0], [1.0, 0, 2.0], [0, 2.0, 3.0]]))
        return A, [A.data * 2, A.data + 1, A.data]
    A = _spd(60, seed=11)
    f = SymmetricFactor(A)
    rows, cols, d = f.matrix.indices, f._cols, f.matrix.data
    if kind == "signed_zeros":  # -0.0 and 0.0 are other bits: both refactorised
        e = np.flatnonzero(rows < cols)[:4]
        zero = np.concatenate([e, f.positions(cols[e], rows[e])])
        A = f.matrix.copy()
        A.data[zero] = 0.0  # explicit zeros, on the pattern
        neg = A.data.copy()
        neg[zero] = -0.0
        return A, [neg, A.data.copy(), neg]
    if kind == "nonfinite":
        out = []
        for e, v in ((5, np.nan), (9, np.inf), (9, -np.inf), (12, -np.nan)):
            x = d.copy()
            x[e] = v
            out += [x, d.copy()]
        return A, out
    low = d.copy()  # lower triangle only: qdldl reads the upper one
    low[np.flatnonzero(rows > cols)[:5]] *= 7.0
    return A, [low, d.copy(), low]


@pytest.mark.same_bits
@pytest.mark.parametrize("kind", ["no_diagonal", "signed_zeros", "nonfinite", "lower_only"])
def test_edge_values_are_qdldls_bits(kernels_on, kind):
    A, values = _edge(kind)
    f = SymmetricFactor(A)
    assert f._ldl is not None
    rhs = np.random.default_rng(2).standard_normal((f.n, 2))
    g = None
    for data in values:
        g = f.with_values(data, reuse=g)
        B = sp.csc_matrix((data, f.matrix.indices, f.matrix.indptr), shape=f.matrix.shape)
        ref = qdldl.Solver(sp.triu(B, format="csc"), upper=True)
        L, D, _ = ref.factors()
        want = np.stack([ref.solve(np.ascontiguousarray(rhs[:, j])) for j in range(2)], 1)
        for x in (g, f.with_values(data)):
            assert_same_floats(x._ldl.Lx, L.data)
            assert_same_floats(x._ldl.D, D)
            assert_same_floats(x.solve(rhs), want)


@pytest.mark.same_bits
def test_where_qdldl_has_other_bits_it_keeps_the_factors(kernels_on, monkeypatch):
    """qdldl's macOS arm64 wheel fuses ``y -= l * x`` (fmsub), the kernels do not: where the probe finds
    other bits (simulated here by qdldl factors one ulp off), every factor stays qdldl's."""
    from core.pattern.accel import ldl

    class Fused(qdldl.Solver):
        def factors(self):
            L, D, P = super().factors()
            L.data = np.nextafter(L.data, np.inf)
            return L, D, P

    monkeypatch.setattr(qdldl, "Solver", Fused)
    monkeypatch.setattr(ldl, "_MATCH", {})
    A = _spd(60, seed=12)
    f = SymmetricFactor(A)
    assert f._ldl is None and not ldl.matches_qdldl()
    g = f.with_values(_changed(f, "pairs", 1))
    assert g._ldl is None
    b = np.ones(60)
    assert_same_floats(f.solve(b), Fused(sp.triu(A, format="csc"), upper=True).solve(b))
