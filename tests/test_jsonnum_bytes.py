"""The bulk number formatter writes the very bytes of its frozen reference.

``tests/helpers/jsonnum_reference.py`` is the formatter as it was when
pattern.json's digits were settled (17 significant digits in fixed notation
for 1e-5 <= |x| < 1e15, ``repr`` outside, plain integers). The current one in
``core.pattern.jsonnum`` lays the characters out differently for speed; here
both format real pattern arrays and fuzzed ones (every magnitude, the
neighbours of powers of ten, roundings that carry, trailing zeros, negative
zeros, integers of every width, any shape, chunk edges) and must agree byte
for byte. The kept texts are used again only for arrays equal bit for bit.
"""

import jsonnum_reference as reference
import numpy as np
import pytest
from synthetic_pattern import two_panels

from core.pattern import jsonnum
from core.pattern.io import _map_arrays, _pattern_dict
from core.pattern.solve import solve_pattern


def _same(arrays):
    arrays = [np.asarray(a) for a in arrays]
    got, want = jsonnum._format(arrays), reference._format(arrays)
    for k, (g, w) in enumerate(zip(got, want)):
        if g != w:
            at = next((i for i, (c, d) in enumerate(zip(g, w)) if c != d), min(len(g), len(w)))
            raise AssertionError(
                f"array {k} ({arrays[k].dtype}, {arrays[k].shape}) differs at {at}: "
                f"{g[max(0, at - 40) : at + 40]!r} != {w[max(0, at - 40) : at + 40]!r}"
            )
    assert len(got) == len(want)


def _powers_and_neighbours():
    p10 = 10.0 ** np.arange(-9, 19)
    out = [p10, 0.5 * p10, 9.5 * p10]
    for _ in range(3):
        out += [np.nextafter(out[-3], 0), np.nextafter(out[-2], np.inf)]
    x = np.concatenate(out)
    # below 10**4 and above (the row gets upper integer digits), and roundings that carry into a new decade
    edges = np.array(
        [
            9999.0,
            9999.5,
            9999.999999999998,
            9999.999999999999,
            10000.0,
            10000.000000000002,
            0.99999999999999989,
            9.9999999999999982,
            99999999999999.98,
            999999999999999.9,
            999999999999999.8,
            1e15,
            9.999999999999999e-06,
            1e-05,
            1.0000000000000001e-05,
        ]
    )
    return np.concatenate([x, edges, np.nextafter(edges, 0), np.nextafter(edges, np.inf)])


def _fuzzed_floats(seed, n=20_000):
    rng = np.random.default_rng(seed)
    sign = rng.choice([-1.0, 1.0], n)
    spread = 10.0 ** rng.uniform(-8, 18, n) * sign  # the bulk range and outside
    bulk = 10.0 ** rng.uniform(-5, 15, n) * sign
    pattern_like = rng.uniform(-3, 3, n)
    # short decimals: trailing zeros in every quad of the fraction (k / 10**j)
    short = rng.integers(-(10**6), 10**6, n) / 10.0 ** rng.integers(0, 17, n)
    integral = rng.integers(-(10**9), 10**9, n).astype(float)
    bits = rng.integers(0, 2**63 - 2**52, n, dtype=np.int64).view(np.float64)  # any finite double
    return np.concatenate([spread, bulk, pattern_like, short, integral, bits[np.isfinite(bits)]])


def test_real_pattern_arrays():
    cut, body = two_panels(n_half=8, n_up=7)
    arrays = []
    _map_arrays(_pattern_dict(solve_pattern(cut, body, style="two")), lambda a: arrays.append(a))
    assert len(arrays) > 10 and any(a.dtype.kind == "f" and a.size > 50 for a in arrays)
    _same(arrays)
    for a in arrays:
        _same([a])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fuzzed_floats_of_every_magnitude(seed):
    x = _fuzzed_floats(seed)
    _same([x])
    _same([x[np.abs(x) < 9000]])  # the narrow rows alone
    _same([x.reshape(-1, 2), -x[:999]])


def test_powers_of_ten_their_neighbours_and_carries():
    x = _powers_and_neighbours()
    _same([x, -x, x.reshape(-1, 1)])
    _same([x[np.abs(x) < 9000]])


def test_zeros_negative_zeros_and_tiny_or_huge_values():
    x = np.array(
        [
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            2.2250738585072014e-308,
            -1.7976931348623157e308,
            1e-300,
            1e300,
            -0.0,
            1.5,
            -2.25,
            3.0,
            123.0,
            0.05,
            -1e-5,
            1e16,
            1.2345678901234567e-06,
            0.1,
            0.2,
            0.3,
        ]
    )
    _same([x])
    _same([np.zeros(7), -np.zeros((2, 3)), np.array([-0.0])])


def test_integers_of_every_width_and_type():
    rng = np.random.default_rng(5)
    digits = rng.integers(0, 19, 5000)
    v = (rng.random(5000) * 10.0**digits).astype(np.int64) * rng.choice([-1, 1], 5000)
    extremes = np.array([0, -1, 1, 9, -9, 10, 9999, 10000, -10000, 2**63 - 1, -(2**63) + 1, 10**18])
    _same([v, extremes, v.reshape(-1, 5)])
    _same(
        [
            np.arange(12).reshape(2, 3, 2),
            np.array([7], np.int32),
            np.arange(300, dtype=np.uint16),
            np.array([2**40], np.uint64),
            np.array([-3, 0, 3], np.int8),
        ]
    )
    _same([np.zeros(5, np.int64)])


def test_shapes_depths_and_mixed_calls():
    rng = np.random.default_rng(9)
    arrays = [
        rng.standard_normal((4, 3, 2)),
        rng.standard_normal((2, 2, 2, 2)),
        np.zeros(0),
        np.zeros((3, 0)),
        np.zeros((0, 2)),
        np.zeros((2, 0, 3)),
        np.array([1.25]),
        np.arange(6).reshape(1, 6),
        rng.integers(-50, 50, (3, 1, 2)),
        rng.standard_normal((5, 2)).T,
        rng.standard_normal(9)[::2],
        rng.standard_normal(7).astype(np.float32),
        np.array([[1e6, -2.5e11], [3.0, 4e-6]]),
    ]
    _same(arrays)
    for a in arrays:
        _same([a])


def test_chunk_edges():
    n = 2 * jsonnum._CHUNK + 37
    x = np.random.default_rng(4).uniform(-2, 2, n)
    x[[jsonnum._CHUNK - 1, jsonnum._CHUNK, 2 * jsonnum._CHUNK]] = [1e-9, 3e20, -0.0]  # repr and "-0.0" at the edges
    _same([x[:5], x.reshape(-1, 1), x])
    _same([np.arange(n) - n // 2])


def test_kept_text_only_for_the_very_same_values():
    # the key holds a fingerprint of some values: arrays that differ elsewhere, or by a zero's sign,
    # get their own text
    rng = np.random.default_rng(2)
    a = rng.standard_normal((4 * jsonnum.CACHE_MIN, 2))
    b = a.copy()
    b[1, 1] = np.nextafter(b[1, 1], 0)  # not among the probed values
    c = a.copy()
    c[2, 0], a[2, 0] = -0.0, 0.0
    assert jsonnum._content_key(a) == jsonnum._content_key(b)
    for arr in (a, b, c, a):
        assert jsonnum.arrays_text([arr])[0] == reference._format([arr])[0]
    assert len({jsonnum.arrays_text([arr])[0] for arr in (a, b, c)}) == 3


def test_kept_texts_stay_within_their_budget(monkeypatch):
    monkeypatch.setattr(jsonnum, "_cache", type(jsonnum._cache)())
    monkeypatch.setattr(jsonnum, "_cache_bytes", 0)
    rng = np.random.default_rng(8)
    arrays = [rng.standard_normal(jsonnum.CACHE_MIN) for _ in range(6)]
    one = arrays[0].nbytes + len(jsonnum._format([arrays[0]])[0])
    monkeypatch.setattr(jsonnum, "CACHE_BYTES", int(2.5 * one))
    for a in arrays:
        assert jsonnum.arrays_text([a])[0] == reference._format([a])[0]
    assert len(jsonnum._cache) == 2 and jsonnum._cache_bytes <= jsonnum.CACHE_BYTES
    assert jsonnum.arrays_text([arrays[-1]])[0] == reference._format([arrays[-1]])[0]


def test_a_text_kept_belongs_to_the_values_it_was_made_from(monkeypatch):
    # another thread (the add-on writes in the background) may change an array while its text is
    # formatted: the values kept with the text must be the ones it was made from, else a later
    # array equal to the changed values would get the old values' text
    monkeypatch.setattr(jsonnum, "_cache", type(jsonnum._cache)())
    monkeypatch.setattr(jsonnum, "_cache_bytes", 0)
    a = np.random.default_rng(3).standard_normal(4 * jsonnum.CACHE_MIN)
    before = jsonnum._content_key(a)
    real = jsonnum._format

    def format_then_change(arrays):
        out = real(arrays)
        a[1] += 1.0  # not among the probed values: the key stays
        return out

    monkeypatch.setattr(jsonnum, "_format", format_then_change)
    jsonnum.arrays_text([a])
    monkeypatch.setattr(jsonnum, "_format", real)
    assert jsonnum._content_key(a) == before
    assert jsonnum.arrays_text([a])[0] == reference._format([a])[0]


def test_wide_floats_written_twice():
    # a long double has no unsigned integer of its width to compare bits with (and padding bytes
    # that are not its value): its text is made every time, as the reference does
    a = np.arange(2 * jsonnum.CACHE_MIN, dtype=np.longdouble) / 3
    for _ in range(2):
        assert jsonnum.arrays_text([a])[0] == reference._format([a])[0]


def test_int64_and_uint64_together_and_uint64_out_of_range():
    # concatenated as they are, int64 and uint64 arrays meet as float64 (53 bits) and a uint64 of
    # 2**63 or more wraps in int64: the text must be json's, or an error
    import json

    arrays = [np.array([2**60 + 1, -(2**62) - 3], np.int64), np.array([1, 2**63 - 1], np.uint64)]
    assert jsonnum.arrays_text(arrays) == [json.dumps(a.tolist()) for a in arrays]
    with pytest.raises(ValueError, match="out of range"):
        jsonnum.arrays_text([np.array([2**63], np.uint64)])
