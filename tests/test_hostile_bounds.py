"""Bounds before allocation (issue 15): hostile pattern.json fields and out-of-range options.

* Hundreds of generated pattern.json mutations (every index and number field of
  a real pattern set to an out-of-range id, a huge or non-finite number, a
  wrong type) loaded in one child process whose address space is capped: each
  is refused with a :class:`PatternError` naming the field, or loads; none
  crashes or runs out of memory. The issue's case (one ``vertex_ids`` entry of
  10**9, which made the drape grow to 23.5 GB) is refused by ``ease drape``
  under the same cap.
* Every drape option and the solver's iterations at, inside and outside their
  ranges; the CLI refuses ``--frames``, ``--substeps``, ``--iterations`` out of
  range before any work, in one line naming the option.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import sample

from core.drape.options import RANGES, DrapeOptions
from core.errors import DrapeError, PatternError
from core.pattern.config import MAX_ITERATIONS, SolverConfig

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
CAP = 2 * 2**30  # address space of the children, bytes: far below what the old drape grew to


@pytest.fixture(scope="module")
def pattern_obj():
    from drape_synth import tube_skirt

    from core.pattern.io import pattern_to_json

    return json.loads(json.dumps(pattern_to_json(tube_skirt(1.2, n_rows=6, n_cols=8))))


# ----------------------------------------------------------------------------- pattern.json mutations

INDEX_FIELDS = ("faces", "vertex_ids", "boundary", "hems")
NUMBER_FIELDS = ("uv", "xyz", "grain", "target_weft", "target_warp", "achieved_weft", "achieved_warp")
BAD_INDEX = (10**9, -1, 2**70, 1.5, "3", None, [1, 2], float("nan"))
BAD_NUMBER = (1e9, 1e308, float("nan"), float("inf"), -float("inf"), "0.5", None, [0.1, 0.2])


def _leaf_paths(value, path=()):
    """Paths of the first and last leaf of a nested list (the places a mutation goes)."""
    if isinstance(value, list) and value:
        yield from _leaf_paths(value[0], path + (0,))
        if len(value) > 1:
            yield from _leaf_paths(value[-1], path + (len(value) - 1,))
    elif not isinstance(value, list):
        yield path


def _cases(obj):
    """(label, field name expected in the error or None when it may load, path, value)."""
    cases = []
    for k, panel in enumerate(obj["panels"]):
        for field in INDEX_FIELDS + NUMBER_FIELDS:
            bad = BAD_INDEX if field in INDEX_FIELDS else BAD_NUMBER
            for leaf in sorted(set(_leaf_paths(panel[field]))):
                for v in bad:
                    # a coordinate or an achieved scale may be any modest number: only
                    # the huge, non-finite and non-numbers must be refused
                    cases.append((f"panels[{k}].{field}{list(leaf)}={v!r}", field, ("panels", k, field) + leaf, v))
            cases.append((f"panels[{k}].{field}=whole {{}}", field, ("panels", k, field), {}))
    for k, _ in enumerate(obj["seams"]):
        for side in ("verts_a", "verts_b"):
            for v in BAD_INDEX:
                cases.append((f"seams[{k}].{side}[0]={v!r}", side, ("seams", k, side, 0), v))
    for g in obj["pins"]:
        for v in BAD_INDEX:
            cases.append((f"pins.{g}[0]={v!r}", "pins", ("pins", g, 0), v))
    for key, v in (
        ("pins", [1, 2]),
        ("seams", {"a": 1}),
        ("report", [1]),
        ("materials", "cotton"),
        ("garments", 3),
        ("style", {"x": 1}),
        ("panels", {"a": 1}),
        ("body", [1]),
    ):
        cases.append((f"{key}={v!r}", key, (key,), v))
    return cases


def _mutate(obj, path, value):
    o = json.loads(json.dumps(obj))
    target = o
    for step in path[:-1]:
        target = target[step]
    target[path[-1]] = value
    return o


LOADER = r"""
import json, resource, sys
resource.setrlimit(resource.RLIMIT_AS, ({cap}, {cap}))
from core.errors import PatternError
from core.pattern.io import load_pattern
out = []
for path in json.load(open(sys.argv[1])):
    try:
        load_pattern(path)
        out.append(["ok", ""])
    except PatternError as exc:
        out.append(["refused", str(exc)])
    except BaseException as exc:
        out.append(["crash", f"{{type(exc).__name__}}: {{exc}}"])
print(json.dumps(out))
"""


def _run_capped(tmp_path, files):
    (tmp_path / "files.json").write_text(json.dumps([str(f) for f in files]))
    script = tmp_path / "loader.py"
    script.write_text(LOADER.format(cap=CAP))
    res = subprocess.run([PY, str(script), str(tmp_path / "files.json")], capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    return json.loads(res.stdout)


def test_hostile_pattern_fields_are_refused_naming_the_field(tmp_path, pattern_obj, request):
    cases = _cases(pattern_obj)
    full = request.config.getoption("--full")
    import random

    chosen = cases if full else random.Random(19).sample(cases, 150)
    files = []
    for i, (_, _, path, value) in enumerate(chosen):
        f = tmp_path / f"case{i:04d}.json"
        # json writes NaN/Infinity tokens, as a careless or hostile writer would
        f.write_text(json.dumps(_mutate(pattern_obj, path, value)))
        files.append(f)
    results = _run_capped(tmp_path, files)
    crashes = [(c[0], r) for c, r in zip(chosen, results) if r[0] == "crash"]
    assert crashes == []
    for (label, field, path, value), (kind, msg) in zip(chosen, results):
        may_load = (
            field in NUMBER_FIELDS
            and field not in ("grain",)
            and isinstance(value, float)
            and math.isfinite(value)
            and abs(value) <= 100
        )
        if kind == "ok":
            assert may_load, label
        else:
            assert field in msg and msg.startswith(str(tmp_path)) and "\n" not in msg, (label, msg)
    assert len(chosen) >= 150


def test_huge_vertex_id_is_refused_by_ease_drape_in_bounded_memory(tmp_path, pattern_obj):
    obj = _mutate(pattern_obj, ("panels", 0, "vertex_ids", 0), 10**9)
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "pattern.json").write_text(json.dumps(obj))
    code = (
        f"import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({CAP}, {CAP})); "
        f"from core.cli import main; "
        f"sys.exit(main(['drape', {str(tmp_path / 'p')!r}, '--out', {str(tmp_path / 'd')!r}, '--quiet']))"
    )
    res = subprocess.run([PY, "-c", code], capture_output=True, text=True, timeout=300)
    lines = [line for line in res.stderr.splitlines() if line.startswith("ease ")]
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "vertex_ids" in lines[0] and "global vertex ids" in lines[0] and not (tmp_path / "d").exists()


def test_a_huge_or_deeply_nested_file_is_refused(tmp_path, monkeypatch):
    from core.pattern import io

    (tmp_path / "pattern.json").write_text("[" * 100000 + "]" * 100000)
    with pytest.raises(PatternError, match="nested too deeply"):
        io.load_pattern(tmp_path)
    monkeypatch.setattr(io, "MAX_FILE_BYTES", 1000)
    (tmp_path / "pattern.json").write_text(" " * 2000)
    with pytest.raises(PatternError, match="larger than a pattern file can be"):
        io.load_pattern(tmp_path)


# ----------------------------------------------------------------------------- options


def _option_cases():
    cases = []
    for name, (kind, low, low_in, high, none_ok) in RANGES.items():
        span = high - low
        cases += [
            (name, high, True),
            (name, low if low_in else low + span * 1e-3, True),
            (name, low - 1 if low_in else low, False),
            (name, high * 10 + 1, False),
            (name, float("nan"), False),
            (name, float("inf"), False),
            (name, "3", False),
            (name, True, False),
            (name, None, none_ok),
        ]
        if kind is int:
            cases.append((name, 2.5, False))
    return [c for c in cases if not (c[0] == "settle_trim" and c[1] == 0.5 and c[2])] + [("settle_trim", 0.5, False)]


@pytest.mark.parametrize("case", sample(_option_cases(), 80, seed=20), ids=str)
def test_drape_options_in_and_out_of_range(case):
    name, value, ok = case
    if ok:
        DrapeOptions.coerce({name: value})
    else:
        with pytest.raises(DrapeError, match=f"drape option {name} = "):
            DrapeOptions.coerce({name: value})


@pytest.mark.parametrize(
    "value, ok",
    [
        (1, True),
        (MAX_ITERATIONS, True),
        (0, False),
        (MAX_ITERATIONS + 1, False),
        (10**9, False),
        (-3, False),
        (2.5, False),
        (True, False),
        ("20", False),
    ],
)
def test_solver_iterations_range(value, ok):
    if ok:
        SolverConfig.named("improved", iterations=value).check()
    else:
        with pytest.raises(PatternError, match="iterations: expected an integer in 1..1000"):
            SolverConfig.named("improved", iterations=value).check()


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["drape", "PATTERN", "--frames", "1000000000"], "--frames"),
        (["drape", "PATTERN", "--frames", "0"], "--frames"),
        (["drape", "PATTERN", "--substeps", "100000"], "--substeps"),
        (["pattern", "DESIGN", "--iterations", "1000000000"], "--iterations"),
        (["transfer", "DESIGN", "--size", "XL", "--iterations", "0"], "--iterations"),
        (["adapt", "DESIGN", "--pose", "P1", "--iterations", "-2"], "--iterations"),
    ],
)
def test_cli_refuses_out_of_range_options_before_work(tmp_path, argv, flag):
    (tmp_path / "PATTERN").mkdir()  # never read: the option is refused first
    subst = {"PATTERN": str(tmp_path / "PATTERN"), "DESIGN": str(ROOT / "core/data/designs/skirt.json")}
    argv = [subst.get(a, a) for a in argv] + ["--out", str(tmp_path / "out"), "--quiet"]
    res = subprocess.run([PY, "-m", "core.cli", *argv], capture_output=True, text=True, cwd=ROOT, timeout=120)
    lines = [line for line in res.stderr.splitlines() if line.startswith("ease ")]
    assert res.returncode == 2 and len(lines) == 1 and flag in lines[0], res.stderr
    assert not (tmp_path / "out").exists()
