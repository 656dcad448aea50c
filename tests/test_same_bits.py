"""tests/helpers/same_bits.py: how the suite compares two code paths of one computation."""

import numpy as np
import pytest
import same_bits
from same_bits import assert_same


@pytest.fixture(params=["bits", "close"])
def mode(request, monkeypatch):
    monkeypatch.setitem(same_bits.MODE, "value", request.param)
    return request.param


def _nan(payload: int, sign: int = 0) -> float:
    return np.array([(sign << 63) | (0x7FF8 << 48) | payload], np.uint64).view(np.float64)[0]


def test_any_nan_is_the_same_nan(mode):
    a = np.array([1.0, _nan(3), 2.0])
    b = np.array([1.0, _nan(0, sign=1), 2.0])
    assert a.view(np.uint64)[1] != b.view(np.uint64)[1]
    assert_same(a, b)
    assert_same([a, (b,)], [b, (a,)])


def test_a_nan_against_a_number_differs(mode):
    with pytest.raises(AssertionError):
        assert_same(np.array([np.nan, 1.0]), np.array([0.0, 1.0]))


def test_one_ulp_differs_in_bits_only(monkeypatch):
    a = np.array([1.0, 2.0])
    b = np.nextafter(a, 3.0)
    monkeypatch.setitem(same_bits.MODE, "value", "bits")
    with pytest.raises(AssertionError):
        assert_same(a, b)
    monkeypatch.setitem(same_bits.MODE, "value", "close")
    assert_same(a, b)
    with pytest.raises(AssertionError):
        assert_same(a, a * (1 + 1e-6))


def test_signed_zeros_and_integers_exact_in_both(mode):
    if mode == "bits":
        with pytest.raises(AssertionError):
            assert_same(np.array([0.0]), np.array([-0.0]))
    with pytest.raises(AssertionError):
        assert_same(np.array([1, 2]), np.array([1, 3]))
    with pytest.raises(AssertionError):
        assert_same(np.zeros(2), np.zeros(3))


def test_the_probe_answers_on_this_machine(monkeypatch):
    """The probe runs both paths (a result either way; the summary line names a cause where they differ)."""
    monkeypatch.setitem(same_bits.MODE, "value", "auto")
    monkeypatch.setattr(same_bits, "_probe", {})
    holds = same_bits.contract_holds()
    line = same_bits.probe_summary()
    assert ("bit for bit" in line) if holds else ("within tolerances" in line and "differ" in line)
