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
from ..fileio import write_json
from .types import Pattern, PatternPanel, PatternSeam

FORMAT = "ease.pattern"
VERSION = 1
FILENAME = "pattern.json"


def pattern_to_json(pattern: Pattern) -> dict:
    """The JSON-ready dict of ``pattern`` (numpy arrays become lists)."""
    panels = []
    for p in pattern.panels:
        panels.append({
            "name": p.name, "garment": p.garment,
            "uv": np.asarray(p.uv, float).tolist(),
            "faces": np.asarray(p.faces, int).tolist(),
            "vertex_ids": np.asarray(p.vertex_ids, int).tolist(),
            "xyz": np.asarray(p.xyz, float).tolist(),
            "grain": np.asarray(p.grain, float).tolist(),
            "target_weft": np.asarray(p.target_weft, float).tolist(),
            "target_warp": np.asarray(p.target_warp, float).tolist(),
            "achieved_weft": np.asarray(p.achieved_weft, float).tolist(),
            "achieved_warp": np.asarray(p.achieved_warp, float).tolist(),
            "boundary": [np.asarray(b, int).tolist() for b in p.boundary],
            "hems": [np.asarray(h, int).tolist() for h in p.hems],
            "mirror_of": p.mirror_of,
        })
    seams = [{"name": s.name, "panel_a": s.panel_a, "panel_b": s.panel_b,
              "verts_a": np.asarray(s.verts_a, int).tolist(),
              "verts_b": np.asarray(s.verts_b, int).tolist(), "gathered": bool(s.gathered)} for s in pattern.seams]
    return {
        "format": FORMAT, "version": VERSION, "unit": "m",
        "style": pattern.style, "body": pattern.body, "garments": pattern.garments,
        "mode": pattern.mode, "materials": pattern.materials, "report": pattern.report,
        "pins": {g: np.asarray(v, int).tolist() for g, v in pattern.pins.items()},
        "panels": panels, "seams": seams,
    }


#: Report entries that are wall-clock times: they differ run to run.
WALL_CLOCK = ("timings", "optimize_seconds", "init_seconds")


def save_pattern(pattern: Pattern, out_dir: Union[str, Path], filename: str = FILENAME) -> Path:
    """Write ``pattern`` to ``out_dir/pattern.json`` atomically; returns the file path.

    The pattern is validated first, so an invalid pattern never reaches disk.
    Wall-clock figures (:data:`WALL_CLOCK`) stay out of the file, so the same
    design gives the same bytes on every run and through every door (CLI,
    add-on, batch); ``report.json`` beside it keeps them.
    """
    obj = pattern_to_json(pattern)
    obj["report"] = {k: v for k, v in obj["report"].items() if k not in WALL_CLOCK}
    pattern_from_json(obj)  # validate before anything is written
    try:
        return write_json(Path(out_dir) / filename, obj, indent=None)
    except ValueError as exc:  # NaN/inf refused by allow_nan=False
        raise PatternError(f"pattern {pattern.style!r} holds non-finite numbers: {exc}") from exc


def load_pattern(path: Union[str, Path]) -> Pattern:
    """Read a pattern from ``pattern.json`` or from a directory holding one."""
    path = Path(path)
    if path.is_dir():
        path = path / FILENAME
    if not path.is_file():
        raise PatternError(f"{path}: no pattern file (expected {FILENAME} written by `ease pattern`)")
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise PatternError(f"{path}: not valid JSON ({exc})") from exc
    try:
        return pattern_from_json(obj)
    except PatternError as exc:
        raise PatternError(f"{path}: {exc}") from exc


def _array(obj, key, where, dtype, shape):
    if key not in obj:
        raise PatternError(f"{where}.{key}: missing")
    try:
        a = np.asarray(obj[key], dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise PatternError(f"{where}.{key}: expected numbers of shape {shape} ({exc})") from exc
    if a.size == 0 and len(shape) > 1:
        a = a.reshape((0,) + tuple(s if isinstance(s, int) else 0 for s in shape[1:]))
    if a.ndim != len(shape) or any(isinstance(s, int) and a.shape[i] != s for i, s in enumerate(shape)):
        raise PatternError(f"{where}.{key}: expected shape {shape}, got {a.shape}")
    if dtype is float and not np.all(np.isfinite(a)):
        raise PatternError(f"{where}.{key}: holds NaN or infinite values")
    return a


def _id_lists(obj, key, where, n):
    out = []
    for i, seq in enumerate(obj.get(key, []) or []):
        a = np.asarray(seq, dtype=np.int64).reshape(-1)
        if a.size and (a.min() < 0 or a.max() >= n):
            raise PatternError(f"{where}.{key}[{i}]: vertex ids must lie in [0, {n})")
        out.append(a)
    return out


def pattern_from_json(obj: dict) -> Pattern:
    """Build and validate a :class:`Pattern` from its JSON dict."""
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
    panels = []
    names = set()
    for k, po in enumerate(panels_obj):
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
        uv = _array(po, "uv", where, float, ("n", 2))
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
        xyz = _array(po, "xyz", where, float, (n, 3))
        grain = _array(po, "grain", where, float, (2,))
        if abs(np.linalg.norm(grain) - 1.0) > 1e-6:
            raise PatternError(f"{where}.grain: expected a unit 2D vector, got {grain.tolist()}")
        per_tri = {key: _array(po, key, where, float, (f,))
                   for key in ("target_weft", "target_warp", "achieved_weft", "achieved_warp")}
        for key in ("target_weft", "target_warp"):
            if np.any(per_tri[key] <= 0):
                raise PatternError(f"{where}.{key}: scales must be > 0")
        mirror = po.get("mirror_of")
        if mirror is not None and not isinstance(mirror, str):
            raise PatternError(f"{where}.mirror_of: expected a panel name or null")
        panels.append(PatternPanel(
            name=name, garment=str(po.get("garment", "")), uv=uv, faces=faces, vertex_ids=vids,
            xyz=xyz, grain=grain, boundary=_id_lists(po, "boundary", where, n),
            hems=_id_lists(po, "hems", where, n), mirror_of=mirror, **per_tri))
    by_name = {p.name: p for p in panels}
    seams = []
    for k, so in enumerate(obj.get("seams", []) or []):
        where = f"seams[{k}]"
        if not isinstance(so, dict):
            raise PatternError(f"{where}: expected an object")
        for side in ("panel_a", "panel_b"):
            if so.get(side) not in by_name:
                raise PatternError(f"{where}.{side}: unknown panel {so.get(side)!r}")
        va = np.asarray(so.get("verts_a", []), dtype=np.int64).reshape(-1)
        vb = np.asarray(so.get("verts_b", []), dtype=np.int64).reshape(-1)
        if va.size < 2 or va.size != vb.size:
            raise PatternError(f"{where}.verts_a/verts_b: expected two equally long polylines of >= 2 "
                               f"vertices, got {va.size} and {vb.size}")
        for side, v in (("a", va), ("b", vb)):
            n = by_name[so[f"panel_{side}"]].uv.shape[0]
            if v.min() < 0 or v.max() >= n:
                raise PatternError(f"{where}.verts_{side}: vertex ids must lie in [0, {n})")
        gathered = so.get("gathered", False)
        if not isinstance(gathered, bool):
            raise PatternError(f"{where}.gathered: expected true or false, got {gathered!r}")
        seams.append(PatternSeam(name=str(so.get("name", f"seam{k}")), panel_a=so["panel_a"],
                                 panel_b=so["panel_b"], verts_a=va, verts_b=vb, gathered=gathered))
    pins = {}
    for g, ids in (obj.get("pins") or {}).items():
        pins[str(g)] = np.asarray(ids, dtype=np.int64).reshape(-1)
    mode = obj.get("mode", "reference")
    if mode not in ("reference", "transfer", "adapt"):
        raise PatternError(f"mode: expected 'reference', 'transfer' or 'adapt', got {mode!r}")
    body = obj.get("body") or {}
    if not isinstance(body, dict):
        raise PatternError("body: expected an object {model, shape, pose, size}")
    return Pattern(style=str(obj.get("style", "")), body=body, garments=dict(obj.get("garments") or {}),
                   panels=panels, seams=seams, pins=pins, materials=dict(obj.get("materials") or {}),
                   mode=mode, report=dict(obj.get("report") or {}))
