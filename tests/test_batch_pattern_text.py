"""pattern.json's bulk number formatting (core.pattern.jsonnum): exact, deterministic, JSON.

The batch writes a pattern.json per item; its numbers are formatted in bulk
with 17 significant digits. These tests check that every double reads back
bit for bit, that the text is the JSON the old writer made (up to float
digits), and that files written by the old writer (shortest repr) still read
to the same pattern and re-save to the new bytes.
"""

import json

import numpy as np
import pytest
from synthetic_pattern import two_panels

from core.errors import PatternError
from core.fileio import dumps_json
from core.pattern.io import WALL_CLOCK, load_pattern, pattern_text, pattern_to_json, save_pattern
from core.pattern.jsonnum import array_text, arrays_text
from core.pattern.solve import solve_pattern


def _bits(a):
    return np.asarray(a, np.float64).view(np.int64)


def _hard_floats():
    """Doubles of every magnitude, the neighbours of powers of ten, ties and odd values."""
    rng = np.random.default_rng(7)
    p10 = 10.0 ** np.arange(-12, 20)
    near = np.concatenate([p10, np.nextafter(p10, 0), np.nextafter(p10, np.inf), np.nextafter(np.nextafter(p10, 0), 0)])
    spread = 10.0 ** rng.uniform(-8, 18, 20000) * rng.choice([-1.0, 1.0], 20000)
    odd = np.array(
        [
            0.0,
            -0.0,
            0.1,
            0.2,
            0.3,
            1 / 3,
            2 / 3,
            1.2,
            5e-324,
            2.2250738585072014e-308,
            1.7976931348623157e308,
            -1e-300,
            0.30000000000000004,
            9.999999999999999e-6,
            999999999999999.9,
            1e15,
            123456789012345.67,
            2.0**-30,
            1 - 2.0**-53,
        ]
    )
    bits = rng.integers(0, 2**63 - 2**52, 5000, dtype=np.int64).view(np.float64)  # any finite double
    return np.concatenate([near, spread, odd, bits[np.isfinite(bits)], rng.standard_normal(5000) * 0.3])


def test_every_double_reads_back_bit_for_bit():
    x = _hard_floats()
    back = np.array(json.loads(array_text(x)), np.float64)
    assert np.array_equal(_bits(back), _bits(x))


def test_text_is_json_dumps_up_to_float_digits():
    rng = np.random.default_rng(3)
    arrays = [
        rng.standard_normal((7, 2)),
        rng.integers(-(10**12), 10**12, (5, 3)),
        np.zeros(0),
        np.zeros((3, 0)),
        np.arange(12).reshape(2, 3, 2),
        rng.standard_normal(4),
        np.array([-7, 0, 12]),
        np.array([[1.5, -2.0]]),
        np.array([2**63 - 1, -(2**63) + 1]),
    ]
    texts = arrays_text(arrays)
    for a, t in zip(arrays, texts):
        assert json.loads(t) == a.tolist()
        if a.dtype.kind != "f":
            assert t == json.dumps(a.tolist())  # integers: the very same text
        else:
            assert len(t) >= 2 and t.count(", ") == json.dumps(a.tolist()).count(", ")


def test_kept_texts_are_the_formatted_ones_and_follow_the_values():
    # large arrays' texts are kept by content: the same text alone, among others and from the
    # store; an array changed in place is formatted again
    from core.pattern import jsonnum

    rng = np.random.default_rng(11)
    big = [
        rng.standard_normal((jsonnum.CACHE_MIN, 2)),
        rng.integers(0, 10**6, (jsonnum.CACHE_MIN, 3)),
        rng.standard_normal(jsonnum.CACHE_MIN).astype(np.float32),
    ]
    small = [rng.standard_normal(5), np.arange(4)]
    alone = [jsonnum._format([a])[0] for a in big]
    first = arrays_text(big + small)
    again = arrays_text(small + big)
    assert first[:3] == alone and again[2:] == alone and first[3:] == again[:2]
    for a in big:
        a[3] = a[3] + 1
    changed = [arrays_text([a])[0] for a in big]
    assert changed == [jsonnum._format([a])[0] for a in big]
    assert all(t != o for t, o in zip(changed, alone))


def test_refusals():
    with pytest.raises(ValueError, match="JSON"):
        array_text(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="JSON"):
        array_text(np.array([np.inf]))
    with pytest.raises(TypeError):
        array_text(np.array(["a"]))


@pytest.fixture(scope="module")
def pattern():
    cut, body = two_panels(n_half=8, n_up=7)
    return solve_pattern(cut, body, style="two")


def _old_writer_text(pattern) -> str:
    """pattern.json as the writer before the bulk formatting made it (json's shortest repr)."""
    obj = pattern_to_json(pattern)
    obj["report"] = {k: v for k, v in obj["report"].items() if k not in WALL_CLOCK}
    return dumps_json(obj, indent=None) + "\n"


def test_same_document_as_the_old_writer_and_same_bytes_each_time(pattern):
    text = pattern_text(pattern)
    assert json.loads(text) == json.loads(_old_writer_text(pattern))
    assert pattern_text(pattern) == text


def test_old_files_read_to_the_same_pattern_and_resave_to_the_new_bytes(tmp_path, pattern):
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "pattern.json").write_text(_old_writer_text(pattern))
    old = load_pattern(tmp_path / "old")
    new = load_pattern(save_pattern(pattern, tmp_path / "new"))
    for a, b, c in zip(pattern.panels, old.panels, new.panels):
        for key in ("uv", "xyz", "grain", "target_weft", "target_warp", "achieved_weft", "achieved_warp"):
            assert np.array_equal(_bits(getattr(a, key)), _bits(getattr(b, key))), key
            assert np.array_equal(_bits(getattr(a, key)), _bits(getattr(c, key))), key
        for key in ("faces", "vertex_ids"):
            assert np.array_equal(getattr(a, key), getattr(c, key)) and getattr(c, key).dtype.kind == "i"
    save_pattern(old, tmp_path / "again")
    assert (tmp_path / "again" / "pattern.json").read_bytes() == (tmp_path / "new" / "pattern.json").read_bytes()


def test_names_with_nul_characters_take_the_plain_path(tmp_path, pattern):
    """A string holding the slot marker cannot be mistaken for an array."""
    pattern.report["note"] = "\x000 \x001"
    try:
        text = pattern_text(pattern)
    finally:
        pattern.report.pop("note")
    obj = json.loads(text)
    assert obj["report"]["note"] == "\x000 \x001"
    assert obj["panels"][0]["uv"] == np.asarray(pattern.panels[0].uv).tolist()


def test_a_non_finite_pattern_is_refused_before_writing(tmp_path, pattern):
    uv = pattern.panels[0].uv
    keep = uv[1, 0]
    uv[1, 0] = np.nan
    try:
        with pytest.raises(PatternError, match="NaN"):
            save_pattern(pattern, tmp_path)
    finally:
        uv[1, 0] = keep
    assert not (tmp_path / "pattern.json").exists()
