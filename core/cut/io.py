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


def _decode(value):
    if isinstance(value, dict) and set(value) == {"dtype", "shape", "data"}:
        return np.asarray(value["data"], dtype=value["dtype"]).reshape(value["shape"])
    if isinstance(value, list) and value and all(isinstance(v, dict) and set(v) == {"dtype", "shape", "data"}
                                                 for v in value):
        return [_decode(v) for v in value]
    if isinstance(value, dict):
        return {k: _decode(v) for k, v in value.items()}
    return value


def cut_to_json(cut: GarmentCut) -> dict:
    """The JSON object of ``cut.json`` (without the embedding)."""
    panels = []
    for p in cut.panels:
        d = {
            "name": p.name, "garment": p.garment, "body_part": p.body_part, "mirror_of": p.mirror_of,
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
        d = {"name": s.name, "panel_a": s.panel_a, "panel_b": s.panel_b,
             "verts_a": np.asarray(s.verts_a, dtype=np.int64).tolist(),
             "verts_b": np.asarray(s.verts_b, dtype=np.int64).tolist()}
        known = {"name", "panel_a", "panel_b", "verts_a", "verts_b"}
        extra = {f.name: _encode(getattr(s, f.name)) for f in dataclasses.fields(s) if f.name not in known}
        if extra:
            d["extra"] = extra
        seams.append(d)
    out = {
        "format": FORMAT, "version": VERSION,
        "body": _encode(cut.body), "garments": dict(cut.garments), "materials": _encode(cut.materials),
        "n_vertices": cut.n_vertices, "n_body_vertices": int(cut.embedding.shape[1]),
        "pins": {k: np.asarray(v, dtype=np.int64).tolist() for k, v in cut.pins.items()},
        "panels": panels, "seams": seams,
    }
    known = {"body", "embedding", "panels", "seams", "garments", "pins", "hems", "materials"}
    extra = {f.name: _encode(getattr(cut, f.name)) for f in dataclasses.fields(cut) if f.name not in known}
    if extra:
        out["extra"] = extra
    return out


def embedding_bytes(embedding) -> bytes:
    E = sp.csr_matrix(embedding)
    buf = io.BytesIO()
    np.savez_compressed(buf, data=E.data.astype(np.float64), indices=E.indices.astype(np.int64),
                        indptr=E.indptr.astype(np.int64), shape=np.asarray(E.shape, dtype=np.int64))
    return buf.getvalue()


def save_cut(cut: GarmentCut, directory: Union[str, Path]) -> list:
    """Write ``cut.json`` and ``cut_embedding.npz`` into ``directory``; returns the paths."""
    directory = Path(directory)
    obj = cut_to_json(cut)
    return [write_text(directory / CUT_JSON, dumps_json(obj, indent=None) + "\n"),
            write_bytes(directory / EMBEDDING_NPZ, embedding_bytes(cut.embedding))]


def load_cut(directory: Union[str, Path]) -> GarmentCut:
    """Reload a cut written by :func:`save_cut`.

    Raises
    ------
    CutError : a missing or malformed file (named).
    """
    import json
    directory = Path(directory)
    jpath, npath = directory / CUT_JSON, directory / EMBEDDING_NPZ
    for p in (jpath, npath):
        if not p.is_file():
            raise CutError(f"{p}: missing (a cut directory holds {CUT_JSON} and {EMBEDDING_NPZ})")
    try:
        obj = json.loads(jpath.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise CutError(f"{jpath}: not valid JSON ({exc.msg}, line {exc.lineno})") from None
    if obj.get("format") != FORMAT or obj.get("version") != VERSION:
        raise CutError(f"{jpath}: expected format {FORMAT!r} version {VERSION}, "
                       f"got {obj.get('format')!r} version {obj.get('version')!r}")
    try:
        with np.load(npath) as z:
            E = sp.csr_matrix((z["data"], z["indices"], z["indptr"]), shape=tuple(int(x) for x in z["shape"]))
    except (KeyError, ValueError, OSError) as exc:
        raise CutError(f"{npath}: not a cut embedding ({exc})") from None
    try:
        panels, hems = [], {}
        for d in obj["panels"]:
            extra = _decode(d.get("extra", {}))
            p = Panel(name=d["name"], garment=d["garment"],
                      vertex_ids=np.asarray(d["vertex_ids"], dtype=np.int64),
                      faces=np.asarray(d["faces"], dtype=np.int64).reshape(-1, 3),
                      warp_dir=np.asarray(d["warp_dir"], dtype=np.float64).reshape(-1, 3),
                      ease=np.asarray(d["ease"], dtype=np.float64),
                      boundary=[np.asarray(b, dtype=np.int64) for b in d["boundary"]],
                      body_part=d.get("body_part", "torso"), mirror_of=d.get("mirror_of"),
                      **{k: v for k, v in extra.items() if k in {f.name for f in dataclasses.fields(Panel)}})
            panels.append(p)
            if d.get("hems"):
                hems[p.name] = [np.asarray(h, dtype=np.int64) for h in d["hems"]]
        seams = []
        for d in obj["seams"]:
            extra = _decode(d.get("extra", {}))
            seams.append(Seam(name=d["name"], panel_a=d["panel_a"], panel_b=d["panel_b"],
                              verts_a=np.asarray(d["verts_a"], dtype=np.int64),
                              verts_b=np.asarray(d["verts_b"], dtype=np.int64),
                              **{k: v for k, v in extra.items() if k in {f.name for f in dataclasses.fields(Seam)}}))
        extra = _decode(obj.get("extra", {}))
        cut = GarmentCut(body=_decode(obj["body"]), embedding=E, panels=panels, seams=seams,
                         garments=dict(obj["garments"]),
                         pins={k: np.asarray(v, dtype=np.int64) for k, v in obj["pins"].items()},
                         hems=hems, materials=_decode(obj.get("materials", {})),
                         **{k: v for k, v in extra.items() if k in {f.name for f in dataclasses.fields(GarmentCut)}})
    except (KeyError, TypeError, ValueError) as exc:
        raise CutError(f"{jpath}: malformed cut ({type(exc).__name__}: {exc})") from None
    if cut.n_vertices != obj.get("n_vertices", cut.n_vertices):
        raise CutError(f"{npath}: embedding has {cut.n_vertices} rows, {jpath.name} expects {obj['n_vertices']}")
    return cut
