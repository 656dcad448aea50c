"""Hostile and broken body-model files (no tests here): crafted attacks and seeded byte mutations.

:func:`make_case` writes one case into a folder and returns its path;
:func:`check_model` is the worker-side check (see :mod:`hostile_runner`): every
loading path a user reaches — :func:`core.body.load_body` (the design, the cut,
the add-on's *Add Body*) and ``ease body --model`` through :func:`core.cli.main` —
must either work or refuse with one line naming the file.
"""

import contextlib
import copyreg
import io
import os
import pickle
import sys
import types
import zipfile
from pathlib import Path

import numpy as np
from smpl_synth import tube_model

try:
    from numpy.core import multiarray as _ma
except ImportError:  # numpy >= 2
    from numpy._core import multiarray as _ma


def small_model():
    """A 24-vertex, 3-joint SMPL-format tube (SMPL's frame)."""
    return tube_model(n_ring=6, n_rows=4, J=3, n_betas=2)


# ----------------------------------------------------------------------------- crafting helpers


@contextlib.contextmanager
def fake_chumpy():
    """A module ``chumpy.ch`` with a class ``Ch`` for pickling chumpy-looking objects."""
    pkg, mod = types.ModuleType("chumpy"), types.ModuleType("chumpy.ch")

    class Ch:
        pass

    Ch.__module__, Ch.__qualname__ = "chumpy.ch", "Ch"
    mod.Ch = Ch
    pkg.ch = mod
    saved = {k: sys.modules.get(k) for k in ("chumpy", "chumpy.ch")}
    sys.modules.update({"chumpy": pkg, "chumpy.ch": mod})
    try:
        yield Ch
    finally:
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v


def chumpy(Ch, **state):
    obj = Ch.__new__(Ch)
    obj.__dict__.update(state)
    return obj


class Reduce:
    """An object that pickles as ``func(*args)`` followed by BUILD ``state`` (when given)."""

    def __init__(self, func, args, state=None):
        self.r = (func, args) if state is None else (func, args, state)

    def __reduce__(self):
        return self.r


def _interface(address=16, n=1 << 20):
    return {"data": (address, False), "shape": (n,), "typestr": "<f8", "version": 3}


def _crafted_values(Ch):
    """name -> value put at ``v_template`` (or the whole pickle, for a name starting with '!')."""
    big = (10**12,)
    d8 = np.dtype("f8")
    self_ch = chumpy(Ch)
    self_ch.__dict__["x"] = self_ch
    deep = np.zeros((24, 3))
    for _ in range(60):
        deep = chumpy(Ch, x=deep)
    a, b = chumpy(Ch), chumpy(Ch)
    a.__dict__["x"], b.__dict__["x"] = b, a
    loop = []
    loop.append(loop)
    return {
        "array_interface_inner": chumpy(Ch, x=chumpy(Ch, __array_interface__=_interface())),
        "array_interface_outer": chumpy(
            Ch, __array_interface__=_interface(), x=chumpy(Ch, __array_interface__=_interface(0))
        ),
        "array_interface_in_list": chumpy(Ch, x=[chumpy(Ch, __array_interface__=_interface())]),
        "array_attribute": chumpy(Ch, __array__=np.ndarray, __array_priority__=1e9),
        "self_referencing_chumpy": self_ch,
        "mutual_chumpy": a,
        "deep_chumpy": deep,
        "self_containing_list": loop,
        "object_dtype": np.array([1, 2, None], dtype=object),
        "dtype_object_flags": Reduce(
            _ma._reconstruct,
            (np.ndarray, (0,), b"b"),
            (
                1,
                (3,),
                Reduce(np.dtype, ("f8", False, True), (3, "<", None, None, None, -1, -1, 0x3F)),
                False,
                b"\0" * 24,
            ),
        ),
        "dtype_void_refs": Reduce(
            _ma._reconstruct,
            (np.ndarray, (0,), b"b"),
            (1, (3,), Reduce(np.dtype, ("V8", False, True), (3, "|", None, None, None, 8, 1, 0x01)), False, b"\1" * 24),
        ),
        "dtype_fields": Reduce(np.dtype, ("f8", False, True), (3, "<", None, ("a",), {"a": (d8, 0)}, -1, -1, 0)),
        "dtype_O": Reduce(np.dtype, ("O", False, True), (3, "|", None, None, None, -1, -1, 63)),
        "reconstruct_huge": Reduce(_ma._reconstruct, (np.ndarray, big, b"b")),
        "setstate_huge": Reduce(_ma._reconstruct, (np.ndarray, (0,), b"b"), (1, big, d8, False, b"")),
        "setstate_short_data": Reduce(_ma._reconstruct, (np.ndarray, (0,), b"b"), (1, (24, 3), d8, False, b"\0" * 8)),
        "setstate_negative_shape": Reduce(_ma._reconstruct, (np.ndarray, (0,), b"b"), (1, (-1, 3), d8, False, b"")),
        "setstate_list_data": Reduce(_ma._reconstruct, (np.ndarray, (0,), b"b"), (1, (2,), d8, False, [1.0, 2.0])),
        "setstate_text": Reduce(_ma._reconstruct, (np.ndarray, (0,), b"b"), "not a state"),
        "ndarray_call": Reduce(np.ndarray, (big,)),
        "ndarray_buffer": Reduce(np.ndarray, ((3,), d8, b"\0" * 8, 10**6)),
        "scalar_object": Reduce(_ma.scalar, (np.dtype("O"), "x")),
        "scalar_short": Reduce(_ma.scalar, (d8, b"\0")),
        "float64_list": Reduce(np.float64, ([1.0] * 10,)),
        "bytearray_bomb": Reduce(bytearray, (3 * 10**9,)),
        "bytes_bomb": Reduce(bytes, (3 * 10**9,)),
        "list_of_bytes": Reduce(list, (b"\0" * 1000,)),
        "sparse_huge_dense": Reduce(
            copyreg._reconstructor,
            (_Csc, object, None),
            {
                "_shape": (10**12, 2),
                "data": np.zeros(0),
                "indices": np.zeros(0, np.int32),
                "indptr": np.zeros(3, np.int32),
            },
        ),
        "sparse_bad_index": Reduce(
            copyreg._reconstructor,
            (_Csc, object, None),
            {
                "_shape": (24, 3),
                "data": np.ones(3),
                "indices": np.array([0, 5, 10**6], np.int32),
                "indptr": np.array([0, 1, 2, 3], np.int32),
            },
        ),
        "sparse_bad_indptr": Reduce(
            copyreg._reconstructor,
            (_Csc, object, None),
            {
                "_shape": (24, 3),
                "data": np.ones(3),
                "indices": np.zeros(3, np.int32),
                "indptr": np.array([0, 10**6, 2, 3], np.int32),
            },
        ),
        "string_v_template": "not vertices",
        "bytes_v_template": b"\0" * 72,
        "dict_v_template": {"a": 1},
        "nan_v_template": np.full((24, 3), np.nan),
        "inf_v_template": np.where(np.arange(72).reshape(24, 3) == 5, np.inf, 0.0),
        "huge_int_list": [10**30] * 72,
        "ragged_list": [[0.0, 1.0], [0.0]],
        "!top_level_list": [1, 2, 3],
        "!empty_pickle": None,
        "!persistent_id": None,
        "!os_system": None,
    }


class _CscFake:
    pass


def _register_csc():
    """Pickle a plain object as ``scipy.sparse._csc.csc_matrix`` (the name a real file gives)."""
    import scipy.sparse._csc as csc_mod

    return csc_mod


_Csc = _CscFake


_NAMES = []


def crafted_pkl_names():
    if not _NAMES:
        with fake_chumpy() as Ch:
            _NAMES.extend(sorted(_crafted_values(Ch)))
    return list(_NAMES)


def _pickle_with_fake_csc(obj, protocol):
    """Pickle ``obj`` with :class:`_CscFake` named ``scipy.sparse._csc.csc_matrix``."""
    import scipy.sparse._csc as csc_mod

    real = csc_mod.csc_matrix
    _CscFake.__module__, _CscFake.__qualname__ = "scipy.sparse._csc", "csc_matrix"
    csc_mod.csc_matrix = _CscFake
    try:
        return pickle.dumps(obj, protocol=protocol)
    finally:
        csc_mod.csc_matrix = real
        _CscFake.__module__, _CscFake.__qualname__ = __name__, "_CscFake"


def crafted_pkl(name: str, protocol: int = 2) -> bytes:
    """The bytes of crafted pickle ``name``."""
    if name == "!empty_pickle":
        return b""
    if name == "!persistent_id":
        return b"\x80\x02P0\n."
    if name == "!os_system":
        return pickle.dumps({"v_template": Reduce(os.system, ("true",))}, protocol=protocol)
    with fake_chumpy() as Ch:
        value = _crafted_values(Ch)[name]
        if name.startswith("!"):
            return _pickle_with_fake_csc(value, protocol)
        m = small_model()
        m["v_template"] = value
        return _pickle_with_fake_csc(m, protocol)


def npy_bytes(header: dict, data: bytes) -> bytes:
    """An ``.npy`` file with a header as given (shape, descr, fortran_order) and raw ``data``."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    return buf.getvalue() + data


def npz_bytes(members: dict, compressed: bool = False) -> bytes:
    """A zip of ``name.npy`` members (raw ``.npy`` bytes each)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED if compressed else zipfile.ZIP_STORED) as z:
        for name, data in members.items():
            z.writestr(name + ".npy", data)
    return buf.getvalue()


def model_npz_bytes(m=None, compressed=False) -> bytes:
    buf = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buf, **(small_model() if m is None else m))
    return buf.getvalue()


def _model_members(**replace):
    """The small model as raw ``.npy`` members, with some replaced (name -> bytes)."""
    out = {}
    for k, v in small_model().items():
        b = io.BytesIO()
        np.save(b, v)
        out[k] = b.getvalue()
    out.update(replace)
    return out


CRAFTED_NPZ = {
    "declares_1e12_elements": lambda: npz_bytes(
        _model_members(v_template=npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (10**12,)}, b"\0" * 64))
    ),
    "declares_1e12_compressed": lambda: npz_bytes(
        _model_members(shapedirs=npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (10**6, 10**6)}, b"")),
        True,
    ),
    "object_member": lambda: npz_bytes(
        _model_members(v_template=npy_bytes({"descr": "|O", "fortran_order": False, "shape": (3,)}, b"\0" * 24))
    ),
    "record_member": lambda: npz_bytes(
        _model_members(
            v_template=npy_bytes({"descr": [("a", "<f8")], "fortran_order": False, "shape": (3,)}, b"\0" * 24)
        )
    ),
    "short_data": lambda: npz_bytes(
        _model_members(v_template=npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (24, 3)}, b"\0" * 100))
    ),
    "string_v_template": lambda: model_npz_bytes({**small_model(), "v_template": np.array("abc")}),
    "nan_v_template": lambda: model_npz_bytes({**small_model(), "v_template": np.full((24, 3), np.nan)}),
    "inf_shapedirs": lambda: model_npz_bytes({**small_model(), "shapedirs": np.full((24, 3, 2), np.inf)}),
    "float_faces": lambda: model_npz_bytes({**small_model(), "f": small_model()["f"] + 0.5}),
    "faces_out_of_range": lambda: model_npz_bytes({**small_model(), "f": small_model()["f"] * 1000}),
    "kintree_cycle": lambda: model_npz_bytes({**small_model(), "kintree_table": np.array([[1, 2, 0], [0, 1, 2]])}),
    "no_joints": lambda: model_npz_bytes(
        {
            **small_model(),
            "weights": np.zeros((24, 0)),
            "kintree_table": np.zeros((2, 0), int),
            "J_regressor": np.zeros((0, 24)),
            "posedirs": np.zeros((24, 3, 0)),
        }
    ),
    "smpl_topology_one_joint": lambda: _smpl_topology_one_joint(),
    "missing_key": lambda: model_npz_bytes({k: v for k, v in small_model().items() if k != "weights"}),
    "npy_renamed": lambda: _model_members()["v_template"],
    "empty_file": lambda: b"",
    "truncated_half": lambda: model_npz_bytes()[: len(model_npz_bytes()) // 2],
    "truncated_compressed": lambda: model_npz_bytes(compressed=True)[:-40],
    "zip_without_arrays": lambda: npz_bytes({}),
    "text_file": lambda: b"v_template = [1, 2, 3]\n",
}


def _smpl_topology_one_joint():
    """SMPL's 6890 vertices and 24 joints with every vertex skinned to the pelvis: no body part to
    place the landmarks on (was "argmax of an empty sequence")."""
    from smpl_synth import stick_smpl

    m = stick_smpl()
    V = 6890
    rng = np.random.default_rng(5)
    return model_npz_bytes(
        {
            **m,
            "v_template": rng.random((V, 3)),
            "f": np.arange(V - 2)[:, None] + np.arange(3),
            "weights": np.eye(24)[np.zeros(V, int)],
            "J_regressor": np.eye(24, V),
            "shapedirs": np.zeros((V, 3, 2)),
            "posedirs": np.zeros((V, 3, 207)),
        },
        compressed=True,
    )


CRAFTED_OBJ = {
    "nan_vertex": "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
    "inf_vertex": "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n",
    "overflow_vertex": "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n",
    "two_coordinates": "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "text_coordinate": "v 0 0 x\nf 1 1 1\n",
    "face_out_of_range": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    "face_zero": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    "face_negative_far": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -9\n",
    "face_huge_index": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 " + "9" * 5000 + "\n",
    "no_faces": "v 0 0 0\nv 1 0 0\n",
    "empty": "",
    "binary": "\0\x01\x02\xff" * 50,
    "one_point": "v 0 0 0\nf 1 1 1\n",
}


def small_obj_text() -> str:
    m = small_model()
    v = m["v_template"]
    return "".join(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in m["f"]
    )


# ----------------------------------------------------------------------------- byte mutations


def mutate(data: bytes, seed: int) -> bytes:
    """A seeded damage of ``data``: flipped/zeroed/inserted bytes, a truncation, or digits made huge."""
    rng = np.random.default_rng(seed)
    b = bytearray(data)
    op = seed % 6
    if op == 0 and b:  # flip a few bytes
        for i in rng.integers(0, len(b), size=int(rng.integers(1, 8))):
            b[i] ^= int(rng.integers(1, 256))
    elif op == 1:  # truncate
        b = b[: int(rng.integers(0, max(1, len(b))))]
    elif op == 2 and b:  # insert random bytes
        i = int(rng.integers(0, len(b)))
        b[i:i] = bytes(rng.integers(0, 256, size=int(rng.integers(1, 16)), dtype=np.uint8))
    elif op == 3 and b:  # zero a range
        i = int(rng.integers(0, len(b)))
        b[i : i + int(rng.integers(1, 64))] = b"\0" * len(b[i : i + 64][: int(rng.integers(1, 64))])
    elif op == 4:  # make a run of digits huge (shapes in .npy headers, OBJ numbers)
        digits = [i for i, c in enumerate(b) if 48 <= c <= 57]
        if digits:
            i = digits[int(rng.integers(0, len(digits)))]
            b[i : i + 1] = b"9" * int(rng.integers(2, 14))
    else:  # swap two chunks
        if len(b) > 8:
            i, j = sorted(rng.integers(0, len(b), size=2))
            b = b[:i] + b[j:] + b[i:j]
    return bytes(b)


def case_list():
    """Every model case as ``(kind, name_or_seed)``: crafted pickles (protocols 0-5), crafted npz and
    OBJ files, and seeded mutations of a valid pickle, npz (plain, compressed) and OBJ."""
    cases = [("pkl", f"{n}@{p}") for n in crafted_pkl_names() for p in (0, 2, 4)]
    cases += [("npz", n) for n in CRAFTED_NPZ] + [("obj", n) for n in CRAFTED_OBJ]
    cases += [("valid", f"{k}@{p}") for k in ("pkl", "pickle") for p in range(6)]
    cases += [("valid", "empty_extra_array@2"), ("valid", "npz"), ("valid", "npz_compressed"), ("valid", "obj")]
    cases += [("mut_pkl", s) for s in range(150)] + [("mut_npz", s) for s in range(150)]
    cases += [("mut_npzc", s) for s in range(60)] + [("mut_obj", s) for s in range(90)]
    return cases


def make_case(case, folder) -> str:
    """Write ``case`` (from :func:`case_list`) into ``folder``; its path."""
    kind, key = case
    folder = Path(folder)
    if kind == "pkl":
        name, proto = key.split("@")
        path = folder / f"{name.strip('!')}_p{proto}.pkl"
        path.write_bytes(crafted_pkl(name, int(proto)))
    elif kind == "npz":
        path = folder / f"{key}.npz"
        path.write_bytes(CRAFTED_NPZ[key]())
    elif kind == "obj":
        path = folder / f"{key}.obj"
        path.write_text(CRAFTED_OBJ[key], encoding="latin-1" if key == "binary" else "utf-8")
    elif kind == "valid":
        name, _, proto = key.partition("@")
        if name in ("pkl", "pickle"):
            path = folder / f"model_p{proto}.{name}"
            path.write_bytes(pickle.dumps(small_model(), protocol=int(proto)))
        elif name == "empty_extra_array":
            path = folder / "empty_extra.pkl"
            path.write_bytes(pickle.dumps({**small_model(), "extra": np.zeros(0), "bs_style": "lbs"}, protocol=2))
        elif name.startswith("npz"):
            path = folder / f"{name}.npz"
            path.write_bytes(model_npz_bytes(compressed=name.endswith("compressed")))
        else:
            path = folder / "model.obj"
            path.write_text(small_obj_text())
    else:
        seed = int(key)
        base = {
            "mut_pkl": lambda: pickle.dumps(small_model(), protocol=seed % 6),
            "mut_npz": model_npz_bytes,
            "mut_npzc": lambda: model_npz_bytes(compressed=True),
            "mut_obj": lambda: small_obj_text().encode(),
        }[kind]()
        suffix = {"mut_pkl": ".pkl", "mut_npz": ".npz", "mut_npzc": ".npz", "mut_obj": ".obj"}[kind]
        path = folder / f"{kind}_{seed}{suffix}"
        path.write_bytes(mutate(base, seed))
    return str(path)


def check_model(path: str) -> None:
    """Worker-side: the CLI must exit 0 or 2 (one line naming the file), then :func:`load_body` and a
    posed instance must work or raise an EaseError (the runner records which)."""
    from core.body import load_body
    from core.cli import main

    err = io.StringIO()
    out = Path(path).with_suffix(".out.obj")
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(["body", "--model", path, "--out", str(out), "--quiet"])
    if rc not in (0, 2):
        raise AssertionError(f"ease body exited {rc}")
    if rc == 2:
        line = err.getvalue().strip()
        if "\n" in line or Path(path).name not in line:
            raise AssertionError(f"ease body refusal is not one line naming the file: {line!r}")
    body = load_body(path)
    v = body.vertices()
    if not np.isfinite(v).all():
        raise AssertionError("non-finite vertices from an accepted model")
    if rc != 0:
        raise AssertionError("load_body accepted a model that ease body refused")
