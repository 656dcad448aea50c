"""Corrupted cut folders (no tests here): crafted damage and seeded mutations of a small valid cut.

:func:`make_case` writes one cut folder and returns its path; :func:`check_cut`
(worker side, :mod:`hostile_runner`) loads it with :func:`core.cut.io.load_cut`
and evaluates every garment position (the product that read outside memory
when an embedding index was out of range).
"""

import copy
import io
import json
import zipfile
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from hostile_models import mutate, npy_bytes

N_BODY = 20


def small_cut():
    """Two 4-vertex panels sharing a 2-vertex seam, embedded on a 20-vertex body."""
    from core.cut.types import GarmentCut, Panel, Seam

    rng = np.random.default_rng(3)
    E = sp.random(6, N_BODY, density=0.3, random_state=4, format="csr") + sp.eye(6, N_BODY, format="csr")
    E = sp.csr_matrix(E.multiply(1.0 / E.sum(axis=1)))
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    warp = np.tile([0.0, 0.0, 1.0], (2, 1))
    p1 = Panel("g.front", "g", np.array([0, 1, 2, 3]), faces, warp, np.array([1.1, 1.2]), [np.array([0, 1, 2, 3])])
    p2 = Panel(
        "g.back",
        "g",
        np.array([2, 3, 4, 5]),
        faces,
        warp,
        np.array([1.0, 1.3]),
        [np.array([0, 1, 2, 3])],
        mirror_of=None,
    )
    seam = Seam("g.side", "g.front", "g.back", np.array([2, 3]), np.array([0, 1]))
    return GarmentCut(
        body={"model": "anny", "shape": "M", "pose": "A"},
        embedding=E,
        panels=[p1, p2],
        seams=[seam],
        garments={"g": "upper"},
        pins={"g": np.array([0, 1])},
        hems={"g.front": [np.array([0, 3])]},
        materials={"fabric": "cotton", "eps_weft": 1.1, "extra_array": rng.random((2, 2))},
    )


def _files():
    from core.cut.io import cut_to_json, embedding_bytes

    cut = small_cut()
    return cut_to_json(cut), embedding_bytes(cut.embedding)


def _npz(**members):
    """The embedding npz with members replaced (name -> array, or raw ``.npy`` bytes)."""
    cut = small_cut()
    E = cut.embedding
    arrays = {
        "data": E.data,
        "indices": E.indices.astype(np.int64),
        "indptr": E.indptr.astype(np.int64),
        "shape": np.array(E.shape),
    }
    arrays.update({k: v for k, v in members.items() if v is not None})
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for k, v in arrays.items():
            if isinstance(v, bytes):
                z.writestr(k + ".npy", v)
            else:
                b = io.BytesIO()
                np.save(b, v)
                z.writestr(k + ".npy", b.getvalue())
    return buf.getvalue()


def _indices(value):
    E = small_cut().embedding
    idx = E.indices.astype(np.int64).copy()
    idx[len(idx) // 2] = value
    return idx


def _json_edit(fn):
    def edit(obj):
        obj = copy.deepcopy(obj)
        fn(obj)
        return obj

    return edit


def _deep(depth):
    v = 0
    for _ in range(depth):
        v = [v]
    return v


CRAFTED_NPZ = {
    "index_out_of_range": lambda: _npz(indices=_indices(10**6)),
    "index_just_out": lambda: _npz(indices=_indices(N_BODY)),
    "index_negative": lambda: _npz(indices=_indices(-5)),
    "nan_weight": lambda: _npz(data=np.where(np.arange(len(small_cut().embedding.data)) == 2, np.nan, 0.5)),
    "inf_weight": lambda: _npz(data=np.full(len(small_cut().embedding.data), np.inf)),
    "indptr_decreasing": lambda: _npz(indptr=small_cut().embedding.indptr[::-1].copy()),
    "indptr_short": lambda: _npz(indptr=small_cut().embedding.indptr[:-2].copy()),
    "indptr_beyond": lambda: _npz(indptr=small_cut().embedding.indptr * 1000),
    "shape_three": lambda: _npz(shape=np.array([6, N_BODY, 1])),
    "shape_float": lambda: _npz(shape=np.array([6.0, 20.0])),
    "shape_negative": lambda: _npz(shape=np.array([-6, N_BODY])),
    "shape_huge_rows": lambda: _npz(shape=np.array([10**12, N_BODY])),
    "shape_other_columns": lambda: _npz(shape=np.array([6, 10**9])),
    "data_short": lambda: _npz(data=np.ones(3)),
    "data_text": lambda: _npz(data=np.array(["a"] * len(small_cut().embedding.data))),
    "data_object": lambda: _npz(data=npy_bytes({"descr": "|O", "fortran_order": False, "shape": (3,)}, b"\0" * 24)),
    "data_declares_1e12": lambda: _npz(
        data=npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (10**12,)}, b"\0" * 64)
    ),
    "missing_indptr": lambda: _npz_without("indptr"),
    "empty_file": lambda: b"",
    "npy_renamed": lambda: npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (2,)}, b"\0" * 16),
    "truncated": lambda: _files()[1][:-30],
    "text": lambda: b"not an npz",
}


def _npz_without(key):
    data = _npz()
    src = zipfile.ZipFile(io.BytesIO(data))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for info in src.infolist():
            if info.filename != key + ".npy":
                z.writestr(info.filename, src.read(info))
    return buf.getvalue()


def _set(path, value):
    def fn(obj):
        o = obj
        for k in path[:-1]:
            o = o[k]
        o[path[-1]] = value

    return _json_edit(fn)


CRAFTED_JSON = {
    "top_level_list": lambda obj: [obj],
    "top_level_string": lambda obj: "cut",
    "panels_not_list": _set(["panels"], {"a": 1}),
    "panel_not_object": _set(["panels", 0], 7),
    "faces_two_columns": _set(["panels", 0, "faces"], [[0, 1], [1, 2]]),
    "faces_out_of_range": _set(["panels", 0, "faces"], [[0, 1, 9], [0, 2, 3]]),
    "faces_negative": _set(["panels", 0, "faces"], [[0, 1, -1], [0, 2, 3]]),
    "vertex_id_out_of_range": _set(["panels", 0, "vertex_ids"], [0, 1, 2, 10**9]),
    "vertex_id_float": _set(["panels", 0, "vertex_ids"], [0, 1, 2.5, 3]),
    "vertex_id_text": _set(["panels", 0, "vertex_ids"], ["a", 1, 2, 3]),
    "warp_two_columns": _set(["panels", 0, "warp_dir"], [[0, 1], [1, 0]]),
    "warp_nan": _set(["panels", 0, "warp_dir"], [[0, 0, float("nan")], [0, 0, 1]]),
    "ease_short": _set(["panels", 0, "ease"], [1.1]),
    "ease_nan": _set(["panels", 1, "ease"], [float("nan"), 1.0]),
    "boundary_out_of_range": _set(["panels", 0, "boundary"], [[0, 1, 99]]),
    "hem_out_of_range": _set(["panels", 0, "hems"], [[0, 99]]),
    "seam_unknown_panel": _set(["seams", 0, "panel_b"], "g.sleeve"),
    "seam_lengths_differ": _set(["seams", 0, "verts_b"], [0]),
    "seam_out_of_range": _set(["seams", 0, "verts_a"], [2, 40]),
    "pins_out_of_range": _set(["pins", "g"], [0, 10**6]),
    "pins_not_list": _set(["pins", "g"], 3),
    "garments_list": _set(["garments"], ["g"]),
    "name_number": _set(["panels", 0, "name"], 5),
    "duplicate_panel": lambda obj: _set(["panels", 1, "name"], obj["panels"][0]["name"])(obj),
    "n_vertices_wrong": _set(["n_vertices"], 7),
    "n_body_vertices_wrong": _set(["n_body_vertices"], 19),
    "extra_object_dtype": _set(["materials", "extra_array"], {"dtype": "O", "shape": [2], "data": [1, 2]}),
    "extra_huge_shape": _set(["materials", "extra_array"], {"dtype": "<f8", "shape": [10**6, 10**6], "data": []}),
    "extra_shape_mismatch": _set(["materials", "extra_array"], {"dtype": "<f8", "shape": [3, 3], "data": [1.0]}),
    "extra_dtype_list": _set(["materials", "extra_array"], {"dtype": ["a"], "shape": [1], "data": [1]}),
    "deep_nesting": _set(["materials", "deep"], _deep(100000)),
    "missing_seams": lambda obj: {k: v for k, v in obj.items() if k != "seams"},
    "version_2": _set(["version"], 2),
}

ENCODINGS = ("latin-1", "utf-16", "utf-32")
HOSTILE_VALUES = (
    -1,
    10**9,
    10**30,
    1.5,
    float("nan"),
    float("inf"),
    "x",
    None,
    [],
    {},
    [[1, 2, 3]],
    {"dtype": "<f8", "shape": [2], "data": [1, 2]},
    True,
    [-1],
    [10**12],
    "\udcff",
)


def _leaves(obj, path=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, path + (k,))
    elif isinstance(obj, list) and obj:
        for i, v in enumerate(obj):
            yield from _leaves(v, path + (i,))
    if path:
        yield path


def json_mutation(obj, seed):
    """Replace a seeded element (a leaf, a list or an object) by a hostile value."""
    rng = np.random.default_rng(seed)
    paths = list(_leaves(obj))
    path = paths[int(rng.integers(0, len(paths)))]
    value = HOSTILE_VALUES[int(rng.integers(0, len(HOSTILE_VALUES)))]
    obj = copy.deepcopy(obj)
    o = obj
    for k in path[:-1]:
        o = o[k]
    o[path[-1]] = copy.deepcopy(value)
    return obj


def case_list():
    cases = [("npz", n) for n in CRAFTED_NPZ] + [("json", n) for n in CRAFTED_JSON]
    cases += [("encoding", e) for e in ENCODINGS] + [("valid", "")]
    cases += [("mut_json", s) for s in range(240)] + [("mut_npz", s) for s in range(120)]
    return cases


def make_case(case, folder) -> str:
    kind, key = case
    out = Path(folder) / f"{kind}_{key}"
    out.mkdir(parents=True, exist_ok=True)
    obj, npz = _files()
    text = None
    if kind == "npz":
        npz = CRAFTED_NPZ[key]()
    elif kind == "json":
        obj = CRAFTED_JSON[key](obj)
    elif kind == "mut_json":
        obj = json_mutation(obj, int(key))
    elif kind == "mut_npz":
        npz = mutate(npz, int(key))
    if kind == "encoding":
        obj["panels"][0]["name"] = "g.d\u00e9vant"
        text = json.dumps(obj, ensure_ascii=False).encode(key)
    else:
        try:
            text = json.dumps(obj, ensure_ascii=False).encode("utf-8", "surrogateescape")
        except RecursionError:
            text = b"[" * 100000 + b"]" * 100000
    (out / "cut.json").write_bytes(text)
    (out / "cut_embedding.npz").write_bytes(npz)
    return str(out)


def check_cut(folder: str) -> None:
    """Worker side: load the cut, then every garment and panel position on a body instance."""
    from core.cut.io import load_cut

    cut = load_cut(folder)
    V = np.random.default_rng(0).random((cut.embedding.shape[1], 3))
    X = cut.positions(V)
    if not np.isfinite(X).all():
        raise AssertionError("an accepted cut gives non-finite positions")
    for p in cut.panels:
        cut.panel_positions(p, V)
        X[p.vertex_ids][p.faces]
    for s in cut.seams:
        cut.panel(s.panel_a).vertex_ids[s.verts_a], cut.panel(s.panel_b).vertex_ids[s.verts_b]
