"""Comparing two code paths of one computation: numpy and the solver's Warp kernels, qdldl and the
kernels' LDL, scipy and the kernels' products.

The contract (docs/architecture.md, "Two code paths, one result"): on one machine and one build the two
paths give the same bits, NaN payloads aside; across CPUs they need not (a compiler may fuse multiply-adds
or pick other vector widths on another CPU, and where two NaNs meet x86 keeps either operand's payload).

Tests that rely on the contract carry ``@pytest.mark.same_bits`` and compare with :func:`assert_same`:

- bit for bit, every NaN taken as the same NaN, where the contract holds on this machine
  (:func:`contract_holds`: a probe runs each pair of paths once on fixed inputs) or
  ``pytest --same-bits=bits`` insists on it;
- otherwise within tolerances (``rtol``/``atol``), NaNs in the same places, integers and booleans exact:
  the suite still checks that both paths compute the same thing, and the run's summary says which
  comparison was made.
"""

from __future__ import annotations

import numpy as np

#: "auto" (the probe decides), "bits" or "close": ``pytest --same-bits=...``
MODE = {"value": "auto"}
_probe: dict = {}


def _canonical(a: np.ndarray) -> np.ndarray:
    """``a`` with every NaN the same quiet NaN (payload and sign dropped)."""
    a = np.array(a, copy=True)
    if a.dtype.kind in "fc":
        a[np.isnan(a)] = np.nan
    return a


def _bits_equal(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per element: do ``a`` and ``b`` hold the same bits (NaNs canonicalised)? Shape of ``a``."""
    a, b = _canonical(a), _canonical(b)
    if a.size == 0:
        return np.ones(a.shape, bool)
    differ = a.view(np.uint8).reshape(a.size, a.itemsize) != b.view(np.uint8).reshape(b.size, b.itemsize)
    return ~differ.any(axis=1).reshape(a.shape)


def contract_holds() -> bool:
    """Do the two paths give the same bits on this machine? Probed once a session on fixed inputs.

    The probe runs a local step (numpy against the kernels) and the gradient products (scipy against the
    kernels) and compares their bits, NaNs canonicalised. (The LDL's own probe,
    :func:`core.pattern.accel.ldl.matches_qdldl`, decides whether the kernels factorise at all: where qdldl's
    build has other bits, qdldl keeps the factors and tests/test_pattern_ldl.py skips.)
    """
    if MODE["value"] != "auto":
        return MODE["value"] == "bits"
    if "holds" not in _probe:
        _probe["holds"], _probe["why"] = _run_probe()
    return _probe["holds"]


def probe_summary() -> str:
    """One line for the test run's summary: which comparison the ``same_bits`` tests made, and why."""
    if MODE["value"] == "bits":
        return "same_bits tests: bit for bit (--same-bits=bits)"
    if MODE["value"] == "close":
        return "same_bits tests: within tolerances (--same-bits=close)"
    if "holds" not in _probe:
        return ""
    if _probe["holds"]:
        return "same_bits tests: bit for bit (the two code paths give the same bits on this machine)"
    return f"same_bits tests: within tolerances; this machine's paths differ in bits ({_probe['why']})"


def _run_probe():
    import scipy.sparse as sp

    from core.pattern.accel import compiled

    if not compiled.load():
        return False, "the Warp kernels did not load"
    from core.pattern.accel.products import GradientProducts
    from core.pattern.config import SolverConfig
    from core.pattern.optimizer.steps import local_step
    from core.pattern.optimizer.targets import rest_targets

    # inputs shaped as a solver's: per-triangle 2x2 reference gradients (m^-1 scale), Jacobians near a
    # rotation with stretch, ease factors across and along the grain
    rng = np.random.default_rng(20261207)
    f = 83
    K = rng.normal(0, 0.01, (f, 2, 2)) + np.array([[0.01, 0.0], [0.0, 0.012]])
    Kc = [np.ascontiguousarray(K[:, i, j]) for i in range(2) for j in range(2)]
    M = [rng.normal(m, 0.3, f) for m in (1.1, 0.0, 0.0, 0.9)]
    cw, cg = rng.uniform(0.9, 1.6, f), rng.uniform(0.95, 1.2, f)
    cfg = SolverConfig.named("improved")
    tg = rest_targets(Kc, cw, cg, cfg.rest_shape.model)
    forced = compiled._state["forced"]
    try:
        compiled.use(False)
        ref = local_step(cfg, M, tg, np.ones(2), {})
        compiled.use(True)
        got = local_step(cfg, M, tg, np.ones(2), {})
        if not _bits_equal_all(ref, got):
            return False, "local step: numpy and the Warp kernels"
        n = 60
        cols = np.concatenate([rng.choice(n, 3, replace=False) for _ in range(f)])
        vals = rng.standard_normal((2, 3 * f))
        Gx = sp.csr_matrix((vals[0], cols, np.arange(0, 3 * f + 1, 3)), shape=(f, n))
        Gy = sp.csr_matrix((vals[1], cols, np.arange(0, 3 * f + 1, 3)), shape=(f, n))
        U = rng.standard_normal((n, 2))
        got = GradientProducts(Gx, Gy, Gx.T.tocsr(), Gy.T.tocsr()).jacobians(U)
        ref = [Gx @ U[:, 0].copy(), Gy @ U[:, 0].copy(), Gx @ U[:, 1].copy(), Gy @ U[:, 1].copy()]
        if not _bits_equal_all(ref, list(got)):
            return False, "gradient products: scipy and the Warp kernels"
    finally:
        compiled.use(forced)
    return True, ""


def assert_same(a, b, rtol: float = 1e-9, atol: float = 1e-12) -> None:
    """``a`` and ``b`` (nested lists / tuples of arrays and scalars) are one result of two code paths.

    Bit for bit with NaNs canonicalised where :func:`contract_holds`; otherwise floating-point arrays
    agree within ``rtol`` / ``atol`` with NaNs in the same places, and everything else exactly.
    """
    _compare(a, b, contract_holds(), rtol, atol)


def assert_same_floats(a, b) -> None:
    """:func:`assert_same` of two array-likes read as contiguous float64 arrays (a list is one too)."""
    assert_same(np.ascontiguousarray(a, float), np.ascontiguousarray(b, float))


def _bits_equal_all(a, b) -> bool:
    """The probe's test: bit for bit, NaNs canonicalised."""
    try:
        _compare(a, b, True, 0.0, 0.0)
    except AssertionError:
        return False
    return True


def _compare(a, b, strict: bool, rtol: float, atol: float) -> None:
    if isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), (type(b), len(a), len(b))
        for x, y in zip(a, b):
            _compare(x, y, strict, rtol, atol)
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape, (a.dtype, b.dtype)
        if strict or a.dtype.kind not in "fc":
            same = _bits_equal(a, b)
            assert same.all(), (np.flatnonzero(~same)[:10], a[~same][:5], b[~same][:5])
        else:
            np.testing.assert_allclose(b, a, rtol=rtol, atol=atol, equal_nan=True)
    elif isinstance(a, float) and not strict:
        np.testing.assert_allclose(b, a, rtol=rtol, atol=atol, equal_nan=True)
    else:
        assert a == b or (a != a and b != b), (a, b)
