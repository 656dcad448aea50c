"""``pattern.json``: a self-contained, validated serialisation of a :class:`Pattern`.

Layout (format ``"ease.pattern"``, version 1)::

    {"format": "ease.pattern", "version": 1, "unit": "m",
     "style", "body", "garments", "mode", "materials", "report",
     "pins": {garment: [ids]},
     "panels": [{"name", "garment", "uv": [[x, y]], "faces": [[i, j, k]],
                 "vertex_ids", "xyz", "grain": [gx, gy],
                 "target_weft", "target_warp", "achieved_weft", "achieved_warp",
                 "boundary": [[ids]], "hems": [[ids]], "mirror_of"}],
     "seams": [{"name", "panel_a", "panel_b", "verts_a", "verts_b", "gathered"}]}

Arrays are plain JSON lists. :func:`load_pattern` checks every field and raises
:class:`core.errors.PatternError` naming the offending one.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Union

import numpy as np

from ..errors import PatternError
from ..fileio import dumps_json, write_text
from .jsonnum import arrays_text
from .types import Pattern, PatternPanel, PatternSeam

FORMAT = "ease.pattern"
VERSION = 1
FILENAME = "pattern.json"


def _pattern_dict(pattern: Pattern) -> dict:
    """The file's layout with the numbers still numpy arrays (float64 / int64)."""

    def f(a):
        return np.asarray(a, float)

    def i(a):
        return np.asarray(a, np.int64)

    panels = [
        {
            "name": p.name,
            "garment": p.garment,
            "uv": f(p.uv),
            "faces": i(p.faces),
            "vertex_ids": i(p.vertex_ids),
            "xyz": f(p.xyz),
            "grain": f(p.grain),
            "target_weft": f(p.target_weft),
            "target_warp": f(p.target_warp),
            "achieved_weft": f(p.achieved_weft),
            "achieved_warp": f(p.achieved_warp),
            "boundary": [i(b) for b in p.boundary],
            "hems": [i(h) for h in p.hems],
            "mirror_of": p.mirror_of,
        }
        for p in pattern.panels
    ]
    seams = [
        {
            "name": s.name,
            "panel_a": s.panel_a,
            "panel_b": s.panel_b,
            "verts_a": i(s.verts_a),
            "verts_b": i(s.verts_b),
            "gathered": bool(s.gathered),
        }
        for s in pattern.seams
    ]
    return {
        "format": FORMAT,
        "version": VERSION,
        "unit": "m",
        "style": pattern.style,
        "body": pattern.body,
        "garments": pattern.garments,
        "mode": pattern.mode,
        "materials": pattern.materials,
        "report": pattern.report,
        "pins": {g: i(v) for g, v in pattern.pins.items()},
        "panels": panels,
        "seams": seams,
    }


def _map_arrays(obj, fn):
    """``obj`` with every numpy array replaced by ``fn(array)`` (dicts and lists copied, the rest shared)."""
    if isinstance(obj, np.ndarray):
        return fn(obj)
    if isinstance(obj, dict):
        return {k: _map_arrays(v, fn) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_map_arrays(v, fn) for v in obj]
    return obj


def pattern_to_json(pattern: Pattern) -> dict:
    """The JSON-ready dict of ``pattern`` (numpy arrays become lists)."""
    return _map_arrays(_pattern_dict(pattern), lambda a: a.tolist())


#: Report entries that are wall-clock times: they differ run to run.
WALL_CLOCK = ("timings", "optimize_seconds", "init_seconds")

#: Stand-in for an array in the text written by :func:`pattern_text` (json escapes a NUL as ``\u0000``).
_SLOT = "\\u0000"


def _text(obj: dict, end: str = "") -> str:
    """The JSON text of a :func:`_pattern_dict` (one line, ``", "`` / ``": "`` separators), then ``end``.

    The arrays' numbers are formatted in one pass (:func:`core.pattern.jsonnum.arrays_text`):
    floats with 17 significant digits, which read back as the very same doubles.
    The rest goes through :func:`core.fileio.dumps_json` with a NUL-named slot for
    each array; a file whose own strings hold NULs takes the plain path.
    """
    arrays: list = []

    def slot(a):
        arrays.append(a)
        return "\x00" + str(len(arrays) - 1)

    skeleton = dumps_json(_map_arrays(obj, slot), indent=None)
    parts = skeleton.split(f'"{_SLOT}')
    if len(parts) - 1 != len(arrays) or skeleton.count(_SLOT) != len(arrays):
        return dumps_json(_map_arrays(obj, lambda a: a.tolist()), indent=None) + end
    texts = arrays_text(arrays)
    out = [parts[0]]
    for k, part in enumerate(parts[1:]):
        index, rest = part.split('"', 1)
        if index != str(k):
            return dumps_json(_map_arrays(obj, lambda a: a.tolist()), indent=None) + end
        out += [texts[k], rest]
    return "".join(out + [end])  # one copy of the megabytes, not two


def pattern_text(pattern: Pattern) -> str:
    """The text of ``pattern.json`` for ``pattern`` (validated; wall-clock report entries left out).

    Raises :class:`PatternError` for an invalid pattern or a non-finite number.
    """
    obj = _pattern_dict(pattern)
    obj["report"] = {k: v for k, v in obj["report"].items() if k not in WALL_CLOCK}
    pattern_from_json(obj)  # validate before anything is written
    try:
        return _text(obj, "\n")
    except ValueError as exc:  # NaN/inf refused by allow_nan=False
        raise PatternError(f"pattern {pattern.style!r} holds non-finite numbers: {exc}") from exc


def save_pattern(pattern: Pattern, out_dir: Union[str, Path], filename: str = FILENAME) -> Path:
    """Write ``pattern`` to ``out_dir/pattern.json`` atomically; returns the file path.

    The pattern is validated first, so an invalid pattern never reaches disk.
    Wall-clock figures (:data:`WALL_CLOCK`) stay out of the file, so the same
    design gives the same bytes on every run and through every door (CLI,
    add-on, batch); ``report.json`` beside it keeps them. Floats are written
    with 17 significant digits (:mod:`core.pattern.jsonnum`): reading the file
    gives back the very arrays written.
    """
    return write_text(Path(out_dir) / filename, pattern_text(pattern))


#: Largest pattern.json read (bytes): a real one is a few MB; the JSON parser
#: needs about ten times the file size in memory.
MAX_FILE_BYTES = 256 * 2**20
#: Largest coordinate (m) of a pattern vertex, flat (``uv``) or on the body (``xyz``).
MAX_COORD = 100.0
#: Largest ease scale (``target_*``, ``achieved_*``): 100 = a hundred times the body.
MAX_SCALE = 100.0


def load_pattern(path: Union[str, Path]) -> Pattern:
    """Read a pattern from ``pattern.json`` or from a directory holding one.

    Every field is checked before anything is built (index ranges, numbers,
    sizes), so a broken or hostile file is one :class:`PatternError` naming the
    file and the field, never a crash or a runaway allocation later.
    """
    path = Path(path)
    if path.is_dir():
        path = path / FILENAME
    if not path.is_file():
        raise PatternError(f"{path}: no pattern file (expected {FILENAME} written by `ease pattern`)")
    size = path.stat().st_size
    if size > MAX_FILE_BYTES:
        raise PatternError(
            f"{path}: {size / 2**20:.0f} MB is larger than a pattern file can be ({MAX_FILE_BYTES // 2**20} MB)"
        )
    try:
        obj = json.loads(path.read_bytes().decode("utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise PatternError(f"{path}: not valid JSON ({exc})") from exc
    except RecursionError:
        raise PatternError(f"{path}: not a pattern file (nested too deeply)") from None
    try:
        return pattern_from_json(obj)
    except PatternError as exc:
        raise PatternError(f"{path}: {exc}") from exc


def _numbers(value, where, kind):
    """``value`` as a numpy array of JSON numbers (``kind`` "int" or "float"), nothing else."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError, OverflowError) as exc:  # ragged lists, huge integers
        raise PatternError(f"{where}: expected {kind}s ({exc})") from None
    if a.size == 0:
        return a.astype(np.int64 if kind == "int" else float)
    if a.dtype.kind not in ("iu" if kind == "int" else "iuf"):
        raise PatternError(f"{where}: expected {kind}s, got {a.dtype.name} values")
    if kind == "int":
        return a.astype(np.int64, copy=False)  # no copy of an int64 array (pattern_text checks its own)
    a = a.astype(float, copy=False)
    if not np.all(np.isfinite(a)):
        raise PatternError(f"{where}: holds NaN or infinite values")
    return a


def _array(obj, key, where, dtype, shape, bound=None):
    """``obj[key]`` of ``shape`` (ints or names of free sizes); floats finite and, with ``bound``,
    within ``[-bound, bound]``."""
    if key not in obj:
        raise PatternError(f"{where}.{key}: missing")
    a = _numbers(obj[key], f"{where}.{key}", "float" if dtype is float else "int")
    if a.size == 0 and len(shape) > 1:
        a = a.reshape((0,) + tuple(s if isinstance(s, int) else 0 for s in shape[1:]))
    if a.ndim != len(shape) or any(isinstance(s, int) and a.shape[i] != s for i, s in enumerate(shape)):
        raise PatternError(f"{where}.{key}: expected shape {shape}, got {a.shape}")
    if bound is not None and a.size and np.abs(a).max() > bound:
        raise PatternError(f"{where}.{key}: expected values within +-{bound:g}, got {np.abs(a).max():.6g}")
    return a


def _ids(value, where, n, what="vertex ids"):
    """A flat id array with every id in ``[0, n)``."""
    a = _numbers(value, where, "int").reshape(-1)
    if a.size and (a.min() < 0 or a.max() >= n):
        raise PatternError(f"{where}: {what} must lie in [0, {n}), got {int(a.min())}..{int(a.max())}")
    return a


def _id_lists(obj, key, where, n):
    seqs = obj.get(key)
    seqs = [] if seqs is None else seqs
    if not isinstance(seqs, list):
        raise PatternError(f"{where}.{key}: expected a list of vertex id lists")
    return [_ids(seq, f"{where}.{key}[{i}]", n) for i, seq in enumerate(seqs)]


def _mapping(obj, key):
    value = obj.get(key)
    value = {} if value is None else value
    if not isinstance(value, dict):
        raise PatternError(f"{key}: expected an object, got {type(value).__name__}")
    return value


def _panel(k, po, names):
    where = f"panels[{k}]"
    if not isinstance(po, dict):
        raise PatternError(f"{where}: expected an object")
    name = po.get("name")
    if not isinstance(name, str) or not name:
        raise PatternError(f"{where}.name: expected a non-empty string")
    if name in names:
        raise PatternError(f"{where}.name: duplicate panel name {name!r}")
    names.add(name)
    where = f"panels[{k}] ({name})"
    uv = _array(po, "uv", where, float, ("n", 2), MAX_COORD)
    n = uv.shape[0]
    if n < 3:
        raise PatternError(f"{where}.uv: a panel needs at least 3 vertices, got {n}")
    faces = _array(po, "faces", where, np.int64, ("f", 3))
    if faces.shape[0] == 0:
        raise PatternError(f"{where}.faces: empty panel")
    if faces.min() < 0 or faces.max() >= n:
        raise PatternError(f"{where}.faces: vertex indices must lie in [0, {n})")
    f = faces.shape[0]
    vids = _array(po, "vertex_ids", where, np.int64, (n,))
    xyz = _array(po, "xyz", where, float, (n, 3), MAX_COORD)
    grain = _array(po, "grain", where, float, (2,))
    if abs(np.linalg.norm(grain) - 1.0) > 1e-6:
        raise PatternError(f"{where}.grain: expected a unit 2D vector, got {grain.tolist()}")
    per_tri = {
        key: _array(po, key, where, float, (f,), MAX_SCALE)
        for key in ("target_weft", "target_warp", "achieved_weft", "achieved_warp")
    }
    for key in ("target_weft", "target_warp"):
        if np.any(per_tri[key] <= 0):
            raise PatternError(f"{where}.{key}: scales must be > 0")
    mirror = po.get("mirror_of")
    if mirror is not None and not isinstance(mirror, str):
        raise PatternError(f"{where}.mirror_of: expected a panel name or null")
    garment = po.get("garment", "")
    if not isinstance(garment, str):
        raise PatternError(f"{where}.garment: expected a garment name")
    return PatternPanel(
        name=name,
        garment=garment,
        uv=uv,
        faces=faces,
        vertex_ids=vids,
        xyz=xyz,
        grain=grain,
        boundary=_id_lists(po, "boundary", where, n),
        hems=_id_lists(po, "hems", where, n),
        mirror_of=mirror,
        **per_tri,
    )


def _seam(k, so, by_name):
    where = f"seams[{k}]"
    if not isinstance(so, dict):
        raise PatternError(f"{where}: expected an object")
    for side in ("panel_a", "panel_b"):
        if not isinstance(so.get(side), str) or so.get(side) not in by_name:
            raise PatternError(f"{where}.{side}: unknown panel {so.get(side)!r}")
    va = _ids(so.get("verts_a", []), f"{where}.verts_a", by_name[so["panel_a"]].uv.shape[0])
    vb = _ids(so.get("verts_b", []), f"{where}.verts_b", by_name[so["panel_b"]].uv.shape[0])
    if va.size < 2 or va.size != vb.size:
        raise PatternError(
            f"{where}.verts_a/verts_b: expected two equally long polylines of >= 2 "
            f"vertices, got {va.size} and {vb.size}"
        )
    gathered = so.get("gathered", False)
    if not isinstance(gathered, bool):
        raise PatternError(f"{where}.gathered: expected true or false, got {gathered!r}")
    return PatternSeam(
        name=str(so.get("name", f"seam{k}")),
        panel_a=so["panel_a"],
        panel_b=so["panel_b"],
        verts_a=va,
        verts_b=vb,
        gathered=gathered,
    )


def pattern_from_json(obj: dict) -> Pattern:
    """Build and validate a :class:`Pattern` from its JSON dict.

    Global vertex ids (``vertex_ids``, ``pins``) must lie below the number of
    panel vertices in the file: every garment vertex belongs to a panel, so a
    larger id cannot be real (and would make the drape allocate for it).
    """
    if not isinstance(obj, dict):
        raise PatternError("pattern: expected a JSON object")
    if obj.get("format") != FORMAT:
        raise PatternError(f"format: expected {FORMAT!r}, got {obj.get('format')!r}")
    if obj.get("version") != VERSION:
        raise PatternError(f"version: expected {VERSION}, got {obj.get('version')!r}")
    if obj.get("unit", "m") != "m":
        raise PatternError(f"unit: expected 'm', got {obj.get('unit')!r}")
    panels_obj = obj.get("panels")
    if not isinstance(panels_obj, list) or not panels_obj:
        raise PatternError("panels: expected a non-empty list")
    names: set = set()
    panels = [_panel(k, po, names) for k, po in enumerate(panels_obj)]
    n_garment = sum(p.uv.shape[0] for p in panels)
    for k, p in enumerate(panels):
        _ids(
            p.vertex_ids,
            f"panels[{k}] ({p.name}).vertex_ids",
            n_garment,
            "global vertex ids (at most one per panel vertex of the file)",
        )
    by_name = {p.name: p for p in panels}
    seams_obj = obj.get("seams")
    seams_obj = [] if seams_obj is None else seams_obj
    if not isinstance(seams_obj, list):
        raise PatternError("seams: expected a list")
    seams = [_seam(k, so, by_name) for k, so in enumerate(seams_obj)]
    used = np.zeros(n_garment, bool)  # the ids of the panels' vertices (all in [0, n_garment))
    for p in panels:
        used[p.vertex_ids] = True
    pins = {}
    for g, ids in _mapping(obj, "pins").items():
        a = _ids(ids, f"pins.{g}", n_garment, "global vertex ids")
        if not np.all(used[a]):
            raise PatternError(f"pins.{g}: vertex {int(a[~used[a]][0])} is in no panel")
        pins[str(g)] = a
    mode = obj.get("mode", "reference")
    if mode not in ("reference", "transfer", "adapt"):
        raise PatternError(f"mode: expected 'reference', 'transfer' or 'adapt', got {mode!r}")
    body = obj.get("body") or {}
    if not isinstance(body, dict):
        raise PatternError("body: expected an object {model, shape, pose, size}")
    style = obj.get("style", "")
    if not isinstance(style, str):
        raise PatternError(f"style: expected a name, got {style!r}")
    return Pattern(
        style=style,
        body=body,
        garments=dict(_mapping(obj, "garments")),
        panels=panels,
        seams=seams,
        pins=pins,
        materials=dict(_mapping(obj, "materials")),
        mode=mode,
        report=dict(_mapping(obj, "report")),
    )
