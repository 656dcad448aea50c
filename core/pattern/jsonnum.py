"""Numpy arrays as JSON number lists, formatted in bulk and exactly.

``pattern.json`` holds ~150k floats for a shirt; Python's ``json`` formats each
with ``float.__repr__`` (shortest round-trip digits, a few hundred ns a
number), which made writing the file most of the cost of a batch item. Here
the decimal digits of all the arrays of a file are computed at once with numpy:

- a float ``x`` is written with 17 significant digits, correctly rounded, and
  trailing zeros dropped. 17 digits always read back as the same double
  (IEEE 754-2008, 5.12.2), so a file read back holds the very arrays that were
  written: no precision is given up, not even the last bit;
- the rounding is exact: ``|x| * 10**p`` (``10**p`` exact for ``p <= 22``) is
  split into ``hi + lo`` without error (Dekker's product), ``hi`` is an integer
  (it is above ``2**53``) and ``lo`` at most 8 in magnitude, so
  ``int(hi) + rint(lo)`` is the nearest integer of the exact product;
- numbers outside ``1e-5 <= |x| < 1e15`` (not met in a pattern, whose
  coordinates are metres and scales ratios) keep ``repr``; zeros are ``0.0``.

Each number and what follows it (``", "``, brackets) get a row of 4-byte
columns whose place does not depend on the number's length: the sign first,
then the integer part and the point (or ``0.`` and the zeros of a number below
0.1) from a table, then 17 fraction digits four at a time from a table, then
the suffix. Leading and trailing zeros that are not written, and every unused
byte, are NUL; one pass that drops the NULs leaves the text. So the rows are
made with whole-column numpy operations (no per-exponent passes, no
per-number lengths) and the text with one compaction: a row is 28 bytes for
the numbers of a pattern (below 10**4, arrays of up to two dimensions), 44
with larger integer parts.

The digits depend only on the values (no platform ``printf``; the exponent is
checked against the digits, not taken from ``log10``), so the same arrays give
the same bytes. Integers are written in plain decimal. The text is what
:func:`json.dumps` writes for ``a.tolist()`` but for the digits of floats
(nested lists, ``", "`` between items).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from typing import List, Sequence

import numpy as np

_DIGITS = 17  # significant digits of a float
_LO, _HI = 10 ** (_DIGITS - 1), 10**_DIGITS  # the integer mantissa lies in [_LO, _HI)
_E_MIN, _E_MAX = -5, 14  # decimal exponents formatted in bulk (10**(16-e) exact)
_POW10 = 10.0 ** np.arange(0, 23)
_SPLIT = 134217729.0  # 2**27 + 1: Dekker's splitter for float64
_CHUNK = 1 << 15  # numbers per pass: bounds the temporaries of a huge array
_MINUS = np.uint8(ord("-"))


def _texts(texts, width: int, dtype) -> np.ndarray:
    """Each text NUL-padded to ``width`` bytes, as one ``dtype`` word (or ``width / itemsize`` words)."""
    return np.frombuffer(b"".join(t.encode("ascii").ljust(width, b"\0") for t in texts), dtype).copy()


#: Four digit characters per uint32 entry, four variants of 10**4 entries each (index: value + variant):
#: all four digits; trailing zeros NUL (a float's last fraction digits); leading zeros NUL, 0 all NUL
#: (an integer's upper digits); leading zeros NUL, 0 as "0" (an integer's last four digits)
_FULL, _TRAIL, _LEAD, _LAST = 0, 10_000, 20_000, 30_000
_QUAD = _texts(
    [f"{i:04d}" for i in range(10_000)]
    + [f"{i:04d}".rstrip("0") for i in range(10_000)]
    + [(str(i) if i else "").rjust(4, "\0") for i in range(10_000)]
    + [str(i).rjust(4, "\0") for i in range(10_000)],
    4,
    np.uint32,
)
_QUAD_FULL, _QUAD_TRAIL = _QUAD[_FULL:_TRAIL], _QUAD[_TRAIL:_LEAD]
#: The 8 bytes before a float's last 16 fraction digits (uint64; byte 0 left NUL for the sign, byte 7
#: for the first fraction digit, added as a multiple of :data:`_BYTE7`), by index: 5 + e for e < 0:
#: "0." and -1 - e zeros; 5 + w: "w." for an integer part w < 10**4; 10005 + w: "wwww." (w's last four
#: digits: a larger integer part, whose upper digits precede these bytes)
_WHOLE, _WHOLE4 = 5, 10_005
_PREFIX = _texts(
    [("0." + "0" * k).rjust(7, "\0") for k in range(4, -1, -1)]
    + [f"{w}.".rjust(7, "\0") for w in range(10_000)]
    + [f"{w:04d}.".rjust(7, "\0") for w in range(10_000)],
    8,
    np.uint64,
)
_BYTE7 = np.frombuffer(b"\0" * 7 + b"\1", np.uint64)[0]  # 1 in byte 7, in this machine's byte order
#: By e + 5 (-5 <= e <= 14): 10**p with p = 16 - max(e, -1) digits of q after the point (p = 17 below 1,
#: where the prefix holds "0." and the zeros), and 10**(17 - p), which left-aligns them in 17 digits
_E = np.arange(_E_MIN, _E_MAX + 1)
_SPLIT_AT = 10 ** (16 - np.maximum(_E, -1))
_ALIGN = 10 ** (1 + np.maximum(_E, -1))


def _suffixes(depth: int) -> np.ndarray:
    """(2 depth + 1, s) uint32: the text that follows a number, by code: c closing brackets,
    then (unless it ends its array) ", " and as many opening ones: code 2c (array end, c = ndim)
    or 2c + 1 (c < ndim): at most 2 depth characters, one quad for a pattern's arrays."""
    texts = ["]" * (c // 2) + ("" if c % 2 == 0 else ", " + "[" * (c // 2)) for c in range(2 * depth + 1)]
    quads = (max(map(len, texts)) + 3) // 4
    return _texts(texts, 4 * quads, np.uint32).reshape(len(texts), quads)


def _mantissa(a: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The nearest integer of ``a * 10**(16 - e)`` (int64), exactly: ``hi + lo`` is the exact
    product (Dekker), ``hi`` an integer above 2**53 and ``|lo| <= 8``."""
    b = _POW10[16 - e]
    bh = _SPLIT * b  # 10**p split as Dekker does (exact: 10**p = 5**p * 2**p
    bh -= bh - b  # has at most 49 significant bits for p <= 22)
    bl = b - bh
    hi = a * b
    ah = _SPLIT * a  # in place from here: fewer temporaries of n numbers
    ah -= ah - a
    al = a - ah
    b = al * bl  # the terms of ((ah * bh - hi) + ah * bl + al * bh) + al * bl
    bl *= ah
    ah *= bh
    ah -= hi
    ah += bl
    bh *= al
    ah += bh
    ah += b
    q = hi.astype(np.int64)
    q += np.rint(ah, out=ah).astype(np.int64)
    return q


def _decimal(a: np.ndarray):
    """(q, e, other) of the magnitudes ``a``: ``a`` is ``q * 10**(e - 16)`` rounded to the nearest,
    ``10**16 <= q < 10**17`` and ``-5 <= e <= 14``, but at the indices ``other`` (zeros and the
    magnitudes left to ``repr``), where q = e = 0."""
    fast = (a >= 10.0**_E_MIN) & (a < 10.0 ** (_E_MAX + 1))
    other = np.flatnonzero(~fast)  # few: a pattern's zeros and rounding dust
    af = a
    if other.size:
        af = a.copy()
        af[other] = 1.0
    e = np.floor(np.log10(af)).astype(np.int64)
    np.clip(e, _E_MIN, _E_MAX, out=e)
    q = _mantissa(af, e)
    for _ in range(2):  # log10 may be one off near a power of ten: the digits decide
        low, high = q < _LO, q >= _HI
        if not (low.any() or high.any()):
            break  # every q in range: what follows the loop would change nothing
        e = e - low + high
        fast &= (e >= _E_MIN) & (e <= _E_MAX)
        e = np.clip(e, _E_MIN, _E_MAX)
        q = _mantissa(np.where(fast, af, 1.0), e)
        other = np.flatnonzero(~fast)
    else:
        up = q >= _HI  # rounded up to 10**17: one decade more
        q, e = np.where(up, q // 10, q), e + up
        fast &= (q >= _LO) & (q < _HI) & (e <= _E_MAX)
        other = np.flatnonzero(~fast)
    q[other] = 0
    e[other] = 0
    return q, e, other


def _float_rows(x: np.ndarray, suffix: np.ndarray, words: np.ndarray, rows: np.ndarray) -> None:
    """Write the rows of the floats ``x`` followed by their suffixes (codes ``suffix`` into the
    ``words`` table) into ``rows`` ((n, 4 (h + 6 + s)) uint8, h = 4 when an integer part may exceed
    9999, else 0), in uint32 quads: [sign, upper integer digits (h)] [the 8 bytes of :data:`_PREFIX`
    with the first fraction digit (2)] [16 fraction digits (4)] [suffix (s)], NUL where nothing is."""
    n, s = x.size, words.shape[1]
    quads = rows.view(np.uint32)
    h = quads.shape[1] - 6 - s
    a = np.abs(x)
    q, e, other = _decimal(a)
    # |x| = q * 10**-p: the integer part, and the fraction's digits left-aligned in 17 digits
    ei = e - _E_MIN
    whole, frac = np.divmod(q, _SPLIT_AT[ei])
    frac *= _ALIGN[ei]
    prefix = np.minimum(e, 0, out=e)
    prefix += _WHOLE
    if h:
        upper = whole // 10_000  # < 10**11: three quads, zeros before the first digit NUL
        lead = np.ones(n, bool)
        quads[:, 0] = 0
        for j, u in enumerate((upper // 10**8, upper // 10_000 % 10_000, upper % 10_000)):
            quads[:, 1 + j] = _QUAD[u + _LEAD * lead]
            lead &= u == 0
        prefix += whole % 10_000 + (upper > 0) * (_WHOLE4 - _WHOLE)
    else:
        prefix += whole
    first = frac // 10**16  # always written: "x.0" when the fraction is 0
    word = _PREFIX[prefix]
    word += (first + ord("0")).view(np.uint64) * _BYTE7
    word = word.view(np.uint32).reshape(n, 2)
    quads[:, h] = word[:, 0]  # column by column: a 2D strided copy is slower
    quads[:, h + 1] = word[:, 1]
    frac -= first * 10**16
    hi8 = frac // 10**8
    lo8 = frac - hi8 * 10**8
    v0, v2 = hi8 // 10_000, lo8 // 10_000
    v1, v3 = hi8 - v0 * 10_000, lo8 - v2 * 10_000
    quads[:, h + 5] = _QUAD_TRAIL[v3]  # the trailing zeros of the last quad are NUL
    for j, v in enumerate((v0, v1, v2)):
        quads[:, h + 2 + j] = _QUAD_FULL[v]
    ends = np.flatnonzero(v3 == 0)  # rare: ends in 4 zeros, whose quads before may end it too
    if ends.size:
        trail = np.ones(ends.size, bool)
        for j, v in ((2, v2[ends]), (1, v1[ends]), (0, v0[ends])):
            quads[ends, h + 2 + j] = _QUAD[v + _TRAIL * trail]
            trail &= v == 0
    quads[:, h + 6 :] = words[suffix]
    rows[:, 0] = np.signbit(x).view(np.uint8) * _MINUS
    slow = other[a[other] != 0]
    if slow.size:  # tiny or huge magnitudes: Python's repr (also exact);
        width = rows.shape[1] - 4 * s  # at most 24 characters ("-2.2250738585072014e-308")
        text = b"".join(repr(float(v)).encode("ascii").ljust(width, b"\0") for v in x[slow])
        rows[slow, :width] = np.frombuffer(text, np.uint8).reshape(slow.size, width)


def _float_width(x: np.ndarray, suffix_quads: int) -> int:
    # conservative: a wider row only adds NULs
    big = np.any((np.abs(x) >= 9999.0) & (np.abs(x) < 10.0 ** (_E_MAX + 1)))
    return 4 * (4 * bool(big) + 6 + suffix_quads)


def _int_rows(v: np.ndarray, suffix: np.ndarray, words: np.ndarray, rows: np.ndarray) -> None:
    """Write the rows of the integers ``v``: [sign, NULs] [quads of digits, zeros before the first
    digit NUL] [suffix (s quads)]."""
    n, s = v.size, words.shape[1]
    quads = rows.view(np.uint32)
    nq = quads.shape[1] - s - 1
    mag = np.abs(v)
    parts = []
    for _ in range(nq):
        rest = mag // 10_000
        parts.append(mag - rest * 10_000)
        mag = rest
    quads[:, 0] = 0
    lead = np.ones(n, bool)
    for j, part in enumerate(reversed(parts)):
        quads[:, 1 + j] = _QUAD[part + np.where(lead, _LAST if j == nq - 1 else _LEAD, _FULL)]
        lead &= part == 0
    quads[:, nq + 1 :] = words[suffix]
    rows[:, 0] = (v < 0).view(np.uint8) * _MINUS


def _int_width(v: np.ndarray, suffix_quads: int) -> int:
    digits = len(str(int(np.abs(v).max()))) if v.size else 1
    return 4 * (1 + (digits + 3) // 4 + suffix_quads)


#: Arrays of at least this many numbers have their text kept by content (:func:`arrays_text`).
CACHE_MIN = 1024
#: Bytes kept, at most: the texts and the values they were made from (the least recently used go first).
CACHE_BYTES = 24_000_000
#: Values of an array that make its fingerprint (spread evenly over it, the last one included).
_PROBES = 256
_cache: "OrderedDict[tuple, tuple]" = OrderedDict()
_cache_bytes = 0
_cache_lock = threading.Lock()


def _content_key(a: np.ndarray) -> tuple:
    """dtype, shape and a fingerprint of ``a``: the bytes of :data:`_PROBES` of its values.

    Cheap (a batch's arrays are looked up every item, most of them to find
    that they changed); a key says where to look, :func:`_kept` compares all
    the values before it answers.
    """
    flat = a.reshape(-1)
    return a.dtype.str, a.shape, flat[:: max(1, flat.size // _PROBES)].tobytes() + flat[-1:].tobytes()


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    # bit for bit, as the text depends on them (0.0 and -0.0 differ)
    bits = np.dtype(f"u{a.dtype.itemsize}")
    return bool(np.array_equal(a.view(bits), b.view(bits)))


def _kept(key: tuple, a: np.ndarray):
    """The kept text of ``a`` (None if there is none for these very values)."""
    with _cache_lock:
        hit = _cache.get(key)
        if hit is None or not _same_bits(hit[0], a):
            return None
        _cache.move_to_end(key)
        return hit[1]


def _keep(key: tuple, a: np.ndarray, text: str) -> None:
    """Keep ``text`` for ``a``, the private copy it was made from (replacing another array of the same key)."""
    global _cache_bytes
    size = a.nbytes + len(text)
    with _cache_lock:
        if size > CACHE_BYTES:
            return
        old = _cache.pop(key, None)
        if old is not None:
            _cache_bytes -= old[0].nbytes + len(old[1])
        _cache[key] = (a, text)
        _cache_bytes += size
        while _cache_bytes > CACHE_BYTES:
            values, kept = _cache.popitem(last=False)[1]
            _cache_bytes -= values.nbytes + len(kept)


def arrays_text(arrays: Sequence) -> List[str]:
    """The JSON text of each numeric array, as ``json.dumps(a.tolist())`` up to float digits.

    Parameters
    ----------
    arrays : sequence of arrays (any shape; int or finite float)

    Returns
    -------
    list of str, one per array: nested lists, ``", "`` between items
    (``[]`` for an empty 1D array). One pass over all numbers of a kind: the
    cost is per number, not per array.

    An array's text is a function of its dtype, shape and values alone, so the
    texts of arrays of :data:`CACHE_MIN` numbers or more (of at most 8 bytes
    each) are kept with a copy of their values (:data:`CACHE_BYTES` at most):
    a batch writes the same faces, vertex ids, outlines and ease targets for
    every body of a design.
    A text is used again only for an array equal to the copy bit for bit
    (looked up by a fingerprint, compared in full), so the bytes are the same
    either way.
    """
    arrays = [np.asarray(a) for a in arrays]
    for a in arrays:
        if a.dtype.kind not in "iuf":
            raise TypeError(f"expected an int or float array, got {a.dtype.name}")
    out: List[str] = [""] * len(arrays)
    keys, todo = {}, []
    for i, a in enumerate(arrays):
        # bits compared as unsigned integers of the same width: none for a long double's 16 bytes
        # (6 of them padding, not its value), whose text is made every time
        if a.size >= CACHE_MIN and a.dtype.itemsize <= 8:
            keys[i] = _content_key(a)
            text = _kept(keys[i], a)
            if text is not None:
                out[i] = text
                continue
            # formatted from the copy that is kept: the caller may change the array meanwhile (another
            # thread), and a text kept with other values would be given to an array equal to those
            arrays[i] = a.copy()
        todo.append(i)
    for i, text in zip(todo, _format([arrays[i] for i in todo])):
        out[i] = text
        if i in keys:
            _keep(keys[i], arrays[i], text)
    return out


def _format(arrays: List[np.ndarray]) -> List[str]:
    """:func:`arrays_text` of checked arrays, every number formatted."""
    depth = max([a.ndim for a in arrays] + [1])
    words = _suffixes(depth)
    out: List[str] = [""] * len(arrays)
    for kind, rows_of, width_of in (("f", _float_rows, _float_width), ("iu", _int_rows, _int_width)):
        group = [(i, a) for i, a in enumerate(arrays) if a.dtype.kind in kind]
        for i, a in group:
            if not a.size:
                out[i] = _empty(a.shape)
        group = [(i, a) for i, a in group if a.size]
        if not group:
            continue
        if kind == "f":
            values = np.concatenate([a.ravel() for _, a in group]).astype(np.float64)
            if not np.all(np.isfinite(values)):
                raise ValueError("Out of range float values are not JSON compliant")
        else:
            # each array to int64 first: int64 and uint64 concatenated meet as float64 (53 bits)
            if any(a.dtype.kind == "u" and a.max() > np.iinfo(np.int64).max for _, a in group):
                raise ValueError("integer out of range for JSON text: 2**63 or more")
            values = np.concatenate([a.ravel().astype(np.int64, copy=False) for _, a in group])
            if values.min() == np.iinfo(np.int64).min:
                raise ValueError("integer out of range for JSON text: -2**63")
        # the suffix codes: ", " (1); 2 more for each dimension whose row a number ends; 2 ndim at the end
        suffix = np.ones(values.size, np.int64)
        spans, at = [], 0
        for i, a in group:
            step = 1
            for d in range(a.ndim - 1, 0, -1):
                step *= a.shape[d]
                suffix[at + step - 1 : at + a.size : step] += 2
            suffix[at + a.size - 1] = 2 * a.ndim
            spans.append((i, at, at + a.size, a.ndim))
            at += a.size
        rows = np.empty((values.size, width_of(values, words.shape[1])), np.uint8)
        for c in range(0, values.size, _CHUNK):
            rows_of(values[c : c + _CHUNK], suffix[c : c + _CHUNK], words, rows[c : c + _CHUNK])
        # the one compaction: bytes.translate's deletion (a C loop) is twice numpy's boolean indexing
        text = rows.tobytes().translate(None, b"\0").decode("ascii")
        end = 0
        for i, lo, hi, ndim in spans:
            start, end = end, end + int(np.count_nonzero(rows[lo:hi]))
            out[i] = "[" * ndim + text[start:end]
    return out


def _empty(shape) -> str:
    return "[" + ", ".join([_empty(shape[1:])] * shape[0]) + "]" if len(shape) > 1 else "[]"


def array_text(a) -> str:
    """The JSON text of one numeric array (:func:`arrays_text`)."""
    return arrays_text([a])[0]
