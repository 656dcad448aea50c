"""A frozen copy of ``core.pattern.jsonnum._format`` as of commit 9eb061f (the reference formatter).

The tests compare the current formatter with this one byte for byte: the
text of pattern.json must not change when the formatter is made faster. Do
not edit it (it is the specification by example); only the cache and the
public wrappers were left out.
"""

from __future__ import annotations

from typing import List, Tuple

import numpy as np

_DIGITS = 17  # significant digits of a float
_LO, _HI = 10 ** (_DIGITS - 1), 10**_DIGITS  # the integer mantissa lies in [_LO, _HI)
_E_MIN, _E_MAX = -5, 14  # decimal exponents formatted in bulk (10**(16-e) exact)
_POW10 = 10.0 ** np.arange(0, 23)
_SPLIT = 134217729.0  # 2**27 + 1: Dekker's splitter for float64
#: 10**p split as Dekker does (exact: 10**p = 5**p * 2**p has at most 49 significant bits for p <= 22)
_POW10_HI = _SPLIT * _POW10 - (_SPLIT * _POW10 - _POW10)
_POW10_LO = _POW10 - _POW10_HI
#: "0000".."9999" as uint32: four digit characters per table entry
_QUADS = np.frombuffer("".join(f"{i:04d}" for i in range(10000)).encode("ascii"), np.uint32).copy()
#: float columns: sign and up to 15 integer digits in 0..15, the point at 16, 21 fraction
#: digits in 17..37, "0" in 38..39 (the words 16..39 find the last non-zero digit). Digits
#: are written four at a time (uint32 columns), so every group starts at a multiple of 4.
_POINT = 16
_FRAC = _DIGITS - 1 - _E_MIN  # 21 fraction columns
_FLOAT_COLS = 40
_CHUNK = 8192  # numbers per pass: a pass's tables stay in the cache
_ZERO_WORD = np.frombuffer(b"0" * 8, np.uint64)[0]


def _mantissa(a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The nearest integer of ``a * 10**(16 - e)`` (int64), exactly: ``hi + lo`` is the exact
    product (Dekker), ``hi`` an integer above 2**53 and ``|lo| <= 8``."""
    p = 16 - e
    bh, bl = _POW10_HI[p], _POW10_LO[p]
    hi = a * _POW10[p]
    ca = _SPLIT * a
    ah = ca - (ca - a)
    al = a - ah
    lo = ((ah * bh - hi) + ah * bl + al * bh) + al * bl
    return hi.astype(np.int64) + np.rint(lo).astype(np.int64)


def _put_digits(words: np.ndarray, q: np.ndarray) -> None:
    """Write the decimal digit characters of ``q`` (int64, 0 <= q < 10**(4 * k), zero-padded, most
    significant first) into ``words`` ((n, k) uint32 columns of a character table)."""
    for col in range(words.shape[1] - 1, -1, -1):
        rest = q // 10000  # by a constant: numpy's fast division; % is not
        words[:, col] = _QUADS[q - rest * 10000]
        q = rest


def _mask_table(width: int) -> np.ndarray:
    """(width + 1, width + 1, width) bool: row [s, e] keeps the columns s..e-1."""
    col = np.arange(width)
    return (col[None, None, :] >= np.arange(width + 1)[:, None, None]) & (
        col[None, None, :] < np.arange(width + 1)[None, :, None]
    )


def _round8(n: int) -> int:
    return (n + 7) // 8 * 8


class _Floats:
    """The per-number fields of a flat finite float array, computed on the whole array (1D work)."""

    def __init__(self, x: np.ndarray):
        n = x.size
        a = np.abs(x)
        zero = a == 0
        fast = (a >= 10.0**_E_MIN) & (a < 10.0 ** (_E_MAX + 1))
        af = np.where(fast, a, 1.0)
        e = np.clip(np.floor(np.log10(af)).astype(np.int64), _E_MIN, _E_MAX)
        q = _mantissa(af, e)
        for _ in range(2):  # log10 may be one off near a power of ten: the digits decide
            low, high = q < _LO, q >= _HI
            if not (low.any() or high.any()):
                break
            e = e - low + high
            fast &= (e >= _E_MIN) & (e <= _E_MAX)
            e = np.clip(e, _E_MIN, _E_MAX)
            q = _mantissa(np.where(fast, af, 1.0), e)
        up = q >= _HI  # rounded up to 10**17: one decade more
        q, e = np.where(up, q // 10, q), e + up
        fast &= (q >= _LO) & (q < _HI) & (e <= _E_MAX)
        q = np.where(fast, q, 0)  # zeros (and the slow ones, redone): "0.0"
        e = np.where(fast, e, 0)
        # x = q * 10**-p (p = 16 - e): integer part q // 10**p, then the fraction's p digits
        # left-aligned in 21 columns as two integers of 11 and 10 digits (21 overflow int64)
        whole, hi, lo = np.zeros(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
        for ev in np.flatnonzero(np.bincount(e - _E_MIN, minlength=_E_MAX - _E_MIN + 1)) + _E_MIN:
            # one exponent at a time: division by a constant is numpy's fast one
            rows = np.flatnonzero(e == ev)
            qv = q[rows]
            p = 16 - int(ev)
            if p <= 16:
                w = qv // 10**p
                whole[rows] = w
                qv = qv - w * 10**p
            t = _FRAC - p
            if t >= 10:
                hi[rows], lo[rows] = qv * 10 ** (t - 10), 0
            else:
                h = qv // 10 ** (10 - t)
                hi[rows], lo[rows] = h, (qv - h * 10 ** (10 - t)) * 10**t
        self.whole, self.hi, self.lo = whole, hi, lo
        self.start = _POINT - np.maximum(e + 1, 1) - np.signbit(x)
        self.sign = np.signbit(x)
        self.slow = np.flatnonzero(~fast & ~zero)
        self.slow_text = [repr(float(v)).encode("ascii") for v in x[self.slow]]
        top = int(whole.max()) if n else 0
        self.whole_quads = max(1, (len(str(top)) + 3) // 4)

    def chunk(self, lo_i: int, hi_i: int, width: int):
        """(chars (m, width) uint8, start (m,), end (m,)) of the numbers ``lo_i..hi_i - 1``."""
        m = hi_i - lo_i
        chars = np.empty((m, width), np.uint8)
        quads = chars.view(np.uint32)
        wq = self.whole_quads
        _put_digits(quads[:, _POINT // 4 - wq : _POINT // 4], self.whole[lo_i:hi_i])
        _put_digits(quads[:, _POINT // 4 : _POINT // 4 + 3], self.hi[lo_i:hi_i])  # col 16 dummy, 17..27
        _put_digits(quads[:, _POINT // 4 + 3 : _FLOAT_COLS // 4], self.lo[lo_i:hi_i] * 100)  # 28..37, "00"
        chars[:, _POINT] = ord(".")
        # the last non-zero fraction digit: the highest byte of (word xor "00000000") that is not 0,
        # from the float exponent of the word (exact enough: no byte of it exceeds 9)
        words = chars.view(np.uint64)[:, _POINT // 8 : _FLOAT_COLS // 8] ^ _ZERO_WORD
        byte = (np.frexp(words.astype(np.float64))[1] - 1) >> 3
        last = np.where(
            words[:, 2] != 0,
            _POINT + 16 + byte[:, 2],
            np.where(words[:, 1] != 0, _POINT + 8 + byte[:, 1], _POINT + byte[:, 0]),
        )
        end = np.maximum(last, _POINT + 1) + 1
        start = self.start[lo_i:hi_i].copy()
        sign = np.flatnonzero(self.sign[lo_i:hi_i])
        chars.reshape(-1)[sign * width + start[sign]] = ord("-")
        at = np.searchsorted(self.slow, [lo_i, hi_i])
        for i in range(at[0], at[1]):  # tiny or huge magnitudes: Python's repr (also exact)
            r, text = self.slow[i] - lo_i, self.slow_text[i]
            chars[r, : len(text)] = np.frombuffer(text, np.uint8)
            start[r], end[r] = 0, len(text)
        return chars, start, end


class _Ints:
    """The per-number fields of a flat integer array."""

    def __init__(self, v: np.ndarray):
        v = v.astype(np.int64)
        if v.size and v.min() == np.iinfo(np.int64).min:
            raise ValueError("integer out of range for JSON text: -2**63")
        self.neg = v < 0
        self.mag = np.abs(v)
        digits = max(1, len(str(int(self.mag.max())))) if v.size else 1
        self.quads = (digits + 3) // 4
        nd = np.ones(v.size, np.int64)
        for i in range(1, digits):
            nd += self.mag >= 10**i
        self.cols = 4 + 4 * self.quads  # sign in 0..3, digits from column 4
        self.start = self.cols - nd - self.neg

    def chunk(self, lo_i: int, hi_i: int, width: int):
        chars = np.empty((hi_i - lo_i, width), np.uint8)
        _put_digits(chars.view(np.uint32)[:, 1 : 1 + self.quads], self.mag[lo_i:hi_i])
        start = self.start[lo_i:hi_i]
        neg = np.flatnonzero(self.neg[lo_i:hi_i])
        chars.reshape(-1)[neg * width + start[neg]] = ord("-")
        return chars, start, np.full(hi_i - lo_i, self.cols, np.int64)


def _joined(chars, start, end, suffix, suffixes, masks) -> Tuple[bytes, np.ndarray]:
    """(text, end offsets (n,)): each token followed by its ``suffixes[suffix[i]]``."""
    width = chars.shape[1]
    flat = chars.reshape(-1)
    end = end.copy()
    for code, text in enumerate(suffixes):
        sel = np.flatnonzero(suffix == code)
        if not sel.size:
            continue
        at = sel * width + end[sel]
        for j, ch in enumerate(text.encode("ascii")):
            flat[at + j] = ch
        end[sel] += len(text)
    return chars[masks[start, end]].tobytes(), np.cumsum(end - start)


def _format(arrays: List[np.ndarray]) -> List[str]:
    """:func:`arrays_text` of checked arrays, every number formatted."""
    depth = max([a.ndim for a in arrays] + [1])
    # what follows a number: c closing brackets, then (unless it ends its array) ", " and as
    # many opening ones: code 2c (array end) or 2c + 1
    suffixes = ["]" * (c // 2) + ("" if c % 2 == 0 else ", " + "[" * (c // 2)) for c in range(2 * depth + 2)]
    out: List[str] = [""] * len(arrays)
    for kind, fields, cols in (("f", _Floats, _FLOAT_COLS), ("iu", _Ints, None)):
        group = [(i, a) for i, a in enumerate(arrays) if a.dtype.kind in kind]
        for i, a in group:
            if not a.size:
                out[i] = _empty(a.shape)
        group = [(i, a) for i, a in group if a.size]
        if not group:
            continue
        values = np.concatenate([a.ravel() for _, a in group])
        if kind == "f":
            values = values.astype(np.float64)
            if not np.all(np.isfinite(values)):
                raise ValueError("Out of range float values are not JSON compliant")
        closes = np.zeros(values.size, np.int64)
        opens = np.zeros(values.size, np.int64)
        spans, at = [], 0
        for i, a in group:
            step = 1
            for d in range(a.ndim - 1, -1, -1):  # the numbers that end a row of each dimension
                step *= a.shape[d]
                closes[at + step - 1 : at + a.size : step] += 1
                opens[at + step - 1 : at + a.size - 1 : step] += 1
            spans.append((i, at, at + a.size, a.ndim))
            at += a.size
        last = np.zeros(values.size, bool)
        last[[hi - 1 for _, _, hi, _ in spans]] = True
        suffix = np.where(last, 2 * closes, 2 * opens + 1)
        f = fields(values)
        width = _round8((cols or f.cols) + 2 * depth)
        masks = _mask_table(width)
        pieces, ends, done = [], [], 0
        for c in range(0, values.size, _CHUNK):
            hi_c = min(c + _CHUNK, values.size)
            piece, piece_ends = _joined(*f.chunk(c, hi_c, width), suffix[c:hi_c], suffixes, masks)
            pieces.append(piece)
            ends.append(piece_ends + done)
            done += len(piece)
        text, ends = b"".join(pieces), np.concatenate(ends)
        for i, lo, hi, ndim in spans:
            out[i] = "[" * ndim + text[(ends[lo - 1] if lo else 0) : ends[hi - 1]].decode("ascii")
    return out


def _empty(shape) -> str:
    return "[" + ", ".join([_empty(shape[1:])] * shape[0]) + "]" if len(shape) > 1 else "[]"
