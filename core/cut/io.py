"""Save and reload a :class:`core.cut.types.GarmentCut`.

Files (in one directory):

- ``cut.json``: ``{"format": "ease-cut", "version": 1, "body", "garments",
  "materials", "pins", "panels": [{name, garment, vertex_ids, faces,
  warp_dir, ease, boundary, body_part, mirror_of, hems}], "seams": [{name,
  panel_a, panel_b, verts_a, verts_b}]}``. Optional fields other stages add to
  the data classes are stored too: arrays as ``{"dtype", "shape", "data"}``.
- ``cut_embedding.npz``: the sparse embedding (garment vertex = row @ body
  vertices) as CSR arrays ``data, indices, indptr, shape``.

Every file is written atomically (:mod:`core.fileio`).
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Union

import numpy as np
import scipy.sparse as sp

from ..body.arrays import check_csr, check_shape, dtype_from_code, read_npz
from ..errors import CutError
from ..fileio import dumps_json, write_bytes, write_text
from .types import GarmentCut, Panel, Seam

FORMAT = "ease-cut"
VERSION = 1
CUT_JSON = "cut.json"
EMBEDDING_NPZ = "cut_embedding.npz"

_PANEL_INT = ("vertex_ids", "faces")
_PANEL_FLOAT = ("warp_dir", "ease")


def _encode(value):
    if isinstance(value, np.ndarray):
        return {"dtype": str(value.dtype), "shape": list(value.shape), "data": value.ravel().tolist()}
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, np.ndarray) for v in value):
        return [_encode(v) for v in value]
    if isinstance(value, dict):
        return {k: _encode(v) for k, v in value.items()}
    return value


def _decode(value, where="extra"):
    if isinstance(value, dict) and set(value) == {"dtype", "shape", "data"}:
        dt = dtype_from_code(value["dtype"], f"{where}.dtype", CutError)
        shape = value["shape"]
        if not isinstance(shape, list) or not isinstance(value["data"], list):
            raise CutError(f"{where}: expected shape and data lists")
        count = check_shape(tuple(shape), dt.itemsize, where, CutError)
        try:
            arr = np.asarray(value["data"], dtype=dt)
        except (TypeError, ValueError, OverflowError) as exc:
            raise CutError(f"{where}.data: not {count} values of {dt.str} ({type(exc).__name__})") from None
        if arr.shape != (count,):
            raise CutError(f"{where}.data: expected {count} values (shape {shape}), got {arr.size}")
        return arr.reshape(shape)
    if (
        isinstance(value, list)
        and value
        and all(isinstance(v, dict) and set(v) == {"dtype", "shape", "data"} for v in value)
    ):
        return [_decode(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, dict):
        return {k: _decode(v, f"{where}.{k}") for k, v in value.items()}
    return value


def cut_to_json(cut: GarmentCut) -> dict:
    """The JSON object of ``cut.json`` (without the embedding)."""
    panels = []
    for p in cut.panels:
        d = {
            "name": p.name,
            "garment": p.garment,
            "body_part": p.body_part,
            "mirror_of": p.mirror_of,
            "vertex_ids": np.asarray(p.vertex_ids, dtype=np.int64).tolist(),
            "faces": np.asarray(p.faces, dtype=np.int64).tolist(),
            "warp_dir": np.asarray(p.warp_dir, dtype=np.float64).tolist(),
            "ease": np.asarray(p.ease, dtype=np.float64).tolist(),
            "boundary": [np.asarray(b, dtype=np.int64).tolist() for b in p.boundary],
            "hems": [np.asarray(h, dtype=np.int64).tolist() for h in cut.hems.get(p.name, [])],
        }
        known = {"name", "garment", "body_part", "mirror_of", "vertex_ids", "faces", "warp_dir", "ease", "boundary"}
        extra = {f.name: _encode(getattr(p, f.name)) for f in dataclasses.fields(p) if f.name not in known}
        if extra:
            d["extra"] = extra
        panels.append(d)
    seams = []
    for s in cut.seams:
        d = {
            "name": s.name,
            "panel_a": s.panel_a,
            "panel_b": s.panel_b,
            "verts_a": np.asarray(s.verts_a, dtype=np.int64).tolist(),
            "verts_b": np.asarray(s.verts_b, dtype=np.int64).tolist(),
        }
        known = {"name", "panel_a", "panel_b", "verts_a", "verts_b"}
        extra = {f.name: _encode(getattr(s, f.name)) for f in dataclasses.fields(s) if f.name not in known}
        if extra:
            d["extra"] = extra
        seams.append(d)
    out = {
        "format": FORMAT,
        "version": VERSION,
        "body": _encode(cut.body),
        "garments": dict(cut.garments),
        "materials": _encode(cut.materials),
        "n_vertices": cut.n_vertices,
        "n_body_vertices": int(cut.embedding.shape[1]),
        "pins": {k: np.asarray(v, dtype=np.int64).tolist() for k, v in cut.pins.items()},
        "panels": panels,
        "seams": seams,
    }
    known = {"body", "embedding", "panels", "seams", "garments", "pins", "hems", "materials"}
    # a cut without darts writes no darts record (its files stay as they were)
    extra = {
        f.name: _encode(getattr(cut, f.name))
        for f in dataclasses.fields(cut)
        if f.name not in known and not (f.name == "darts" and not cut.darts)
    }
    if extra:
        out["extra"] = extra
    return out


def embedding_bytes(embedding) -> bytes:
    E = sp.csr_matrix(embedding)
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        data=E.data.astype(np.float64),
        indices=E.indices.astype(np.int64),
        indptr=E.indptr.astype(np.int64),
        shape=np.asarray(E.shape, dtype=np.int64),
    )
    return buf.getvalue()


def save_cut(cut: GarmentCut, directory: Union[str, Path]) -> list:
    """Write ``cut.json`` and ``cut_embedding.npz`` into ``directory``; returns the paths."""
    directory = Path(directory)
    obj = cut_to_json(cut)
    return [
        write_text(directory / CUT_JSON, dumps_json(obj, indent=None) + "\n"),
        write_bytes(directory / EMBEDDING_NPZ, embedding_bytes(cut.embedding)),
    ]


# A cut.json of a dense shirt is a few MB; refuse files far beyond before reading them.
MAX_JSON_BYTES = 256 << 20


def _ids(value, where, bound, shape=None):
    """An int64 array of ids in [0, bound) from a JSON list (of lists), or CutError naming ``where``."""
    if not isinstance(value, list):
        raise CutError(f"{where}: expected a list of indices, got {type(value).__name__}")
    try:
        a = np.asarray(value) if value else np.zeros(0, dtype=np.int64)
    except (TypeError, ValueError, OverflowError):
        a = None
    if a is None or a.dtype.kind not in "iu":  # floats, booleans, text, ragged rows, beyond int64
        raise CutError(f"{where}: expected whole-number indices")
    a = a.astype(np.int64)
    if shape is not None:
        if a.size == 0:
            a = a.reshape(0, shape)
        if a.ndim != 2 or a.shape[1] != shape:
            raise CutError(f"{where}: expected rows of {shape} indices, got shape {a.shape}")
    elif a.ndim != 1:
        raise CutError(f"{where}: expected a flat list of indices, got shape {a.shape}")
    if a.size and (a.min() < 0 or a.max() >= bound):
        raise CutError(f"{where}: index {int(a.min() if a.min() < 0 else a.max())} outside [0, {bound})")
    return a


def _floats(value, where, shape):
    if not isinstance(value, list):
        raise CutError(f"{where}: expected a list of numbers, got {type(value).__name__}")
    try:
        a = np.asarray(value, dtype=np.float64).reshape(shape)
    except (TypeError, ValueError, OverflowError):
        raise CutError(f"{where}: expected numbers of shape {shape}") from None
    if not np.isfinite(a).all():
        raise CutError(f"{where}: holds NaN or infinite values")
    return a


def _field(obj, key, where, kind):
    at = f"{where}.{key}" if ": " in where else f"{where}: {key}"
    if not isinstance(obj, dict):
        raise CutError(f"{where}: expected an object, got {type(obj).__name__}")
    if key not in obj:
        raise CutError(f"{at}: missing")
    if not isinstance(obj[key], kind):
        raise CutError(f"{at}: expected {getattr(kind, '__name__', 'a value')}, got {type(obj[key]).__name__}")
    return obj[key]


def _read_embedding(npath: Path):
    z = read_npz(npath, ("data", "indices", "indptr", "shape"), error=CutError, what="cut embedding .npz")
    for k in ("data", "indices", "indptr", "shape"):
        if k not in z:
            raise CutError(f"{npath}: missing key {k!r} (the embedding is CSR arrays data, indices, indptr, shape)")
    shape = z["shape"]
    if shape.shape != (2,) or shape.dtype.kind not in "iu" or shape.min() < 0:
        raise CutError(f"{npath}: key 'shape' must be 2 sizes >= 0, got {shape.tolist()}")
    rows, cols = (int(x) for x in shape)
    data, indices, indptr = (z[k].ravel() for k in ("data", "indices", "indptr"))
    check_csr(data, indices, indptr, rows, cols, str(npath), CutError)
    return sp.csr_matrix(
        (data.astype(np.float64), indices.astype(np.int64), indptr.astype(np.int64)), shape=(rows, cols)
    )


def _read_panel(d, where, N, fields):
    name = _field(d, "name", where, str)
    vids = _ids(_field(d, "vertex_ids", where, list), f"{where}.vertex_ids", N)
    faces = _ids(_field(d, "faces", where, list), f"{where}.faces", len(vids), shape=3)
    F = len(faces)
    extra = _decode(d.get("extra", {}), f"{where}.extra")
    if not isinstance(extra, dict):
        raise CutError(f"{where}.extra: expected an object")
    body_part = d.get("body_part", "torso")
    mirror_of = d.get("mirror_of")
    if not isinstance(body_part, str) or not (mirror_of is None or isinstance(mirror_of, str)):
        raise CutError(f"{where}: body_part and mirror_of must be names")
    panel = Panel(
        name=name,
        garment=_field(d, "garment", where, str),
        vertex_ids=vids,
        faces=faces,
        warp_dir=_floats(_field(d, "warp_dir", where, list), f"{where}.warp_dir", (F, 3)),
        ease=_floats(_field(d, "ease", where, list), f"{where}.ease", (F,)),
        boundary=[
            _ids(b, f"{where}.boundary[{i}]", len(vids)) for i, b in enumerate(_field(d, "boundary", where, list))
        ],
        body_part=body_part,
        mirror_of=mirror_of,
        **{k: v for k, v in extra.items() if k in fields},
    )
    hems = [_ids(h, f"{where}.hems[{i}]", len(vids)) for i, h in enumerate(d.get("hems") or [])]
    return panel, hems


def _read_seam(d, where, sizes, fields):
    a, b = _field(d, "panel_a", where, str), _field(d, "panel_b", where, str)
    for k, p in (("panel_a", a), ("panel_b", b)):
        if p not in sizes:
            raise CutError(f"{where}.{k}: no panel {p!r} in the cut")
    va = _ids(_field(d, "verts_a", where, list), f"{where}.verts_a", sizes[a])
    vb = _ids(_field(d, "verts_b", where, list), f"{where}.verts_b", sizes[b])
    if len(va) != len(vb):
        raise CutError(f"{where}: verts_a has {len(va)} vertices, verts_b {len(vb)}; a seam pairs them one to one")
    extra = _decode(d.get("extra", {}), f"{where}.extra")
    if not isinstance(extra, dict):
        raise CutError(f"{where}.extra: expected an object")
    return Seam(
        name=_field(d, "name", where, str),
        panel_a=a,
        panel_b=b,
        verts_a=va,
        verts_b=vb,
        **{k: v for k, v in extra.items() if k in fields},
    )


def load_cut(directory: Union[str, Path]) -> GarmentCut:
    """Reload a cut written by :func:`save_cut`, every field and index checked.

    Raises
    ------
    CutError : a missing or malformed file, naming the file and the key
        (``cut.json: panels[2].faces: index 91 outside [0, 90)``): not JSON or
        not UTF-8, a field of the wrong type or shape, NaN or infinite numbers,
        an index outside its array, an embedding whose CSR arrays are
        inconsistent or refer outside the matrix, or files over the size limits.
    """
    import json

    directory = Path(directory)
    jpath, npath = directory / CUT_JSON, directory / EMBEDDING_NPZ
    for p in (jpath, npath):
        if not p.is_file():
            raise CutError(f"{p}: missing (a cut directory holds {CUT_JSON} and {EMBEDDING_NPZ})")
    try:
        if jpath.stat().st_size > MAX_JSON_BYTES:
            raise CutError(f"{jpath}: over {MAX_JSON_BYTES >> 20} MiB; not a cut this project wrote")
        obj = json.loads(jpath.read_bytes().decode("utf-8"))
    except OSError as exc:
        raise CutError(f"{jpath}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise CutError(f"{jpath}: not UTF-8 text (byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise CutError(f"{jpath}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    except (ValueError, RecursionError) as exc:
        raise CutError(f"{jpath}: not valid JSON ({type(exc).__name__})") from None
    if not isinstance(obj, dict):
        raise CutError(
            f"{jpath}: expected a JSON object {{format, version, panels, seams, ...}}, got a {type(obj).__name__}"
        )
    if obj.get("format") != FORMAT or obj.get("version") != VERSION:
        raise CutError(
            f"{jpath}: expected format {FORMAT!r} version {VERSION}, "
            f"got {str(obj.get('format'))[:40]!r} version {str(obj.get('version'))[:20]!r}"
        )
    E = _read_embedding(npath)
    N = E.shape[0]
    for key, size in (("n_vertices", N), ("n_body_vertices", E.shape[1])):
        if key in obj and obj[key] != size:
            raise CutError(
                f"{npath}: embedding has {size} {'rows' if key == 'n_vertices' else 'columns'}, "
                f"{jpath.name} key {key!r} expects {str(obj[key])[:20]}"
            )
    where = str(jpath)
    panel_fields = {f.name for f in dataclasses.fields(Panel)}
    seam_fields = {f.name for f in dataclasses.fields(Seam)}
    try:
        panels, hems, sizes = [], {}, {}
        for i, d in enumerate(_field(obj, "panels", where, list)):
            p, h = _read_panel(d, f"{where}: panels[{i}]", N, panel_fields)
            if p.name in sizes:
                raise CutError(f"{where}: panels[{i}].name: duplicate panel name {p.name!r}")
            panels.append(p)
            sizes[p.name] = len(p.vertex_ids)
            if h:
                hems[p.name] = h
        seams = [
            _read_seam(d, f"{where}: seams[{i}]", sizes, seam_fields)
            for i, d in enumerate(_field(obj, "seams", where, list))
        ]
        garments = _field(obj, "garments", where, dict)
        if not all(isinstance(v, str) for v in garments.values()):
            raise CutError(f"{where}: garments: expected an object garment name -> kind")
        pins = {k: _ids(v, f"{where}: pins.{k}", N) for k, v in _field(obj, "pins", where, dict).items()}
        extra = _decode(obj.get("extra", {}), f"{where}: extra")
        materials = _decode(obj.get("materials", {}), f"{where}: materials")
        body = _decode(_field(obj, "body", where, dict), f"{where}: body")
        if not isinstance(extra, dict) or not isinstance(materials, dict):
            raise CutError(f"{where}: extra and materials must be objects")
        cut = GarmentCut(
            body=body,
            embedding=E,
            panels=panels,
            seams=seams,
            garments=dict(garments),
            pins=pins,
            hems=hems,
            materials=materials,
            **{k: v for k, v in extra.items() if k in {f.name for f in dataclasses.fields(GarmentCut)}},
        )
    except CutError:
        raise
    except (KeyError, TypeError, ValueError) as exc:
        raise CutError(f"{jpath}: malformed cut ({type(exc).__name__}: {exc})") from None
    return cut
