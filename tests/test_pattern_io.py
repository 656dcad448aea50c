"""pattern.json round trip and validation."""

import json

import numpy as np
import pytest
from synthetic_pattern import two_panels

from core.errors import PatternError
from core.pattern.io import load_pattern, pattern_to_json, save_pattern
from core.pattern.solve import solve_pattern


@pytest.fixture(scope="module")
def pattern():
    cut, body = two_panels(n_half=8, n_up=7)
    return solve_pattern(cut, body, style="two")


def test_round_trip(tmp_path, pattern):
    path = save_pattern(pattern, tmp_path)
    assert path.name == "pattern.json"
    back = load_pattern(tmp_path)
    assert back.style == "two" and back.mode == "reference"
    assert [p.name for p in back.panels] == [p.name for p in pattern.panels]
    for a, b in zip(pattern.panels, back.panels):
        for key in ("uv", "faces", "vertex_ids", "xyz", "grain", "target_weft", "achieved_weft"):
            assert np.array_equal(getattr(a, key), getattr(b, key)), key
        assert len(a.boundary) == len(b.boundary)
    assert [s.name for s in back.seams] == [s.name for s in pattern.seams]
    assert np.array_equal(back.seams[0].verts_a, pattern.seams[0].verts_a)
    assert [s.gathered for s in back.seams] == [s.gathered for s in pattern.seams]
    assert load_pattern(path).panels[0].name == "front"


def test_gathered_flag_round_trips(tmp_path, pattern):
    pattern.seams[0].gathered = True
    save_pattern(pattern, tmp_path)
    assert [s.gathered for s in load_pattern(tmp_path).seams] == [True] + [False] * (len(pattern.seams) - 1)


def _write(tmp_path, obj):
    (tmp_path / "pattern.json").write_text(json.dumps(obj))
    return tmp_path


@pytest.mark.parametrize(
    "mutate, match",
    [
        (lambda o: o.update(format="other"), "format"),
        (lambda o: o.update(panels=[]), "panels"),
        (lambda o: o["panels"][0].update(uv=[[0, 0]]), r"panels\[0\] \(front\)\.uv"),
        (lambda o: o["panels"][0].update(faces=[]), "faces"),
        (lambda o: o["panels"][0]["faces"].__setitem__(0, [0, 1, 999]), "faces: vertex indices"),
        (lambda o: o["panels"][1]["target_weft"].__setitem__(0, 0.0), r"panels\[1\] \(back\)\.target_weft"),
        (lambda o: o["panels"][0].update(grain=[0.0, 2.0]), "grain"),
        (lambda o: o["panels"][0].pop("xyz"), "xyz: missing"),
        (lambda o: o["seams"][0].update(panel_b="nope"), r"seams\[0\]\.panel_b"),
        (lambda o: o["seams"][0].update(verts_b=[0]), r"seams\[0\]\.verts_a/verts_b"),
        (lambda o: o.update(mode="draft"), "mode"),
        (lambda o: o["seams"][0].update(gathered="yes"), r"seams\[0\]\.gathered"),
    ],
)
def test_validation_names_the_field(tmp_path, pattern, mutate, match):
    obj = json.loads(json.dumps(pattern_to_json(pattern)))
    mutate(obj)
    with pytest.raises(PatternError, match=match):
        load_pattern(_write(tmp_path, obj))


def test_nan_in_file_is_refused(tmp_path, pattern):
    obj = pattern_to_json(pattern)
    obj["panels"][0]["uv"][3][1] = float("nan")
    (tmp_path / "pattern.json").write_text(json.dumps(obj))  # Python writes the NaN token
    with pytest.raises(PatternError, match=r"panels\[0\] \(front\)\.uv: holds NaN"):
        load_pattern(tmp_path)


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(PatternError, match="no pattern file"):
        load_pattern(tmp_path)
    (tmp_path / "pattern.json").write_text("{not json")
    with pytest.raises(PatternError, match="not valid JSON"):
        load_pattern(tmp_path)


def test_invalid_pattern_is_never_written(tmp_path, pattern):
    import copy

    bad = copy.deepcopy(pattern)
    bad.panels[0].uv[0, 0] = np.nan
    with pytest.raises(PatternError):
        save_pattern(bad, tmp_path)
    assert not (tmp_path / "pattern.json").exists()
