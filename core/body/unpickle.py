"""A restricted unpickler for body-model files that users bring (SMPL ``.pkl``).

A pickle can call any importable callable while it loads, so an SMPL file of
unknown origin must never go through :func:`pickle.load`. :class:`SafeUnpickler`
admits only what a model file needs: numpy arrays and dtypes, scipy.sparse
matrices (rebuilt from their arrays, never through scipy's own pickle hooks),
a few inert builtins, and a stand-in for chumpy objects (SMPL's py2-era files
store arrays inside ``chumpy.ch.Ch``). Anything else raises :class:`BodyError`
naming the refused callable, before it could run.
"""
from __future__ import annotations

import io
import pickle
from pathlib import Path

import numpy as np

from ..errors import BodyError


class ChumpyStandIn:
    """Stands in for any chumpy class; keeps the pickled ``__dict__`` only."""

    def __init__(self, *args, **kwargs):
        # chumpy.Ch(x) rebuilt by a REDUCE call: its first argument is the array.
        if args:
            self.x = args[0]
        elif "x" in kwargs:
            self.x = kwargs["x"]

    def __setstate__(self, state):
        if isinstance(state, tuple) and len(state) == 2:
            state = {**(state[0] or {}), **(state[1] or {})}
        if isinstance(state, dict):
            self.__dict__.update(state)

    def array(self) -> np.ndarray:
        """The array a terminal chumpy object holds (its ``x``)."""
        x = self.__dict__.get("x")
        if x is None:
            raise BodyError("a chumpy object in the pickle is a derived expression, not an array; "
                            "re-save the model with plain numpy arrays")
        return np.asarray(as_array(x))


class SparseStandIn:
    """Stands in for a scipy.sparse matrix; rebuilt by :meth:`to_scipy` from its arrays."""

    def __init__(self, fmt: str):
        self.fmt = fmt

    def __setstate__(self, state):
        if isinstance(state, dict):
            self.__dict__.update(state)

    def to_scipy(self):
        import scipy.sparse as sp
        d = self.__dict__
        shape = d.get("_shape", d.get("shape"))
        try:
            shape = tuple(int(s) for s in shape)
            if self.fmt in ("csc", "csr"):
                cls = sp.csc_matrix if self.fmt == "csc" else sp.csr_matrix
                return cls((np.asarray(d["data"]), np.asarray(d["indices"]), np.asarray(d["indptr"])),
                           shape=shape)
            if self.fmt == "coo":
                row = d.get("row", d.get("coords", [None, None])[0])
                col = d.get("col", d.get("coords", [None, None])[1])
                return sp.coo_matrix((np.asarray(d["data"]), (np.asarray(row), np.asarray(col))), shape=shape)
        except (KeyError, TypeError, ValueError) as exc:
            raise BodyError(f"a scipy.sparse {self.fmt} matrix in the pickle is malformed ({exc})") from None
        raise BodyError(f"scipy.sparse format {self.fmt!r} is not supported in model files")


def _reconstructor(cls, base, state):
    """Safe ``copyreg._reconstructor`` (protocol 0/1 objects): stand-ins only."""
    if base is object and isinstance(cls, type) and issubclass(cls, (ChumpyStandIn, SparseStandIn)):
        return cls.__new__(cls)
    raise BodyError(f"pickle refused: cannot rebuild {getattr(cls, '__name__', cls)!r} "
                    f"from base {getattr(base, '__name__', base)!r}")


def _codecs_encode(text, encoding="utf-8"):
    """Safe ``_codecs.encode``: py3 protocol<3 pickles store bytes as ``encode(str, 'latin1')``."""
    if not isinstance(text, str) or str(encoding).lower().replace("_", "-") not in (
            "latin1", "latin-1", "ascii", "utf-8", "utf8"):
        raise BodyError(f"pickle refused: _codecs.encode with encoding {encoding!r}")
    return text.encode(encoding)


def _sparse_factory(fmt):
    class _Sparse(SparseStandIn):
        def __init__(self, *args, **kwargs):
            super().__init__(fmt)

        def __new__(cls, *args, **kwargs):
            obj = object.__new__(cls)
            obj.fmt = fmt
            return obj
    _Sparse.__name__ = f"{fmt}_matrix"
    return _Sparse


_SPARSE = {f"{fmt}_matrix": _sparse_factory(fmt) for fmt in ("csc", "csr", "coo")}
_SPARSE.update({f"{fmt}_array": _SPARSE[f"{fmt}_matrix"] for fmt in ("csc", "csr", "coo")})


def _numpy_allowed():
    # numpy>=2 (as bundled with some Blender versions) moved numpy.core to numpy._core.
    try:
        from numpy._core import multiarray, numeric
    except ImportError:
        from numpy.core import multiarray, numeric
    table = {
        ("numpy.core.multiarray", "_reconstruct"): multiarray._reconstruct,
        ("numpy.core.multiarray", "scalar"): multiarray.scalar,
        ("numpy", "ndarray"): np.ndarray,
        ("numpy", "dtype"): np.dtype,
    }
    if hasattr(numeric, "_frombuffer"):
        table[("numpy.core.numeric", "_frombuffer")] = numeric._frombuffer
    # py2-era and numpy<2 pickles name numpy.core, numpy>=2 pickles numpy._core.
    for (mod, name), fn in list(table.items()):
        if mod.startswith("numpy.core"):
            table[(mod.replace("numpy.core", "numpy._core"), name)] = fn
    return table


_BUILTINS = {"set": set, "frozenset": frozenset, "slice": slice, "complex": complex,
             "object": object, "list": list, "dict": dict, "tuple": tuple, "bytearray": bytearray}


class SafeUnpickler(pickle.Unpickler):
    """Unpickler admitting only numpy/scipy.sparse data and chumpy stand-ins."""

    _numpy = None

    def find_class(self, module: str, name: str):
        if SafeUnpickler._numpy is None:
            SafeUnpickler._numpy = _numpy_allowed()
        fn = SafeUnpickler._numpy.get((module, name))
        if fn is not None:
            return fn
        if module in ("builtins", "__builtin__") and name in _BUILTINS:
            return _BUILTINS[name]
        if module in ("copyreg", "copy_reg") and name == "_reconstructor":
            return _reconstructor
        if module == "_codecs" and name == "encode":
            return _codecs_encode
        if module.startswith("scipy.sparse") and name in _SPARSE:
            return _SPARSE[name]
        if module == "chumpy" or module.startswith("chumpy."):
            return ChumpyStandIn
        if module == "numpy" and name in ("bool_", "float64", "float32", "int64", "int32", "uint32", "uint8"):
            # numpy scalar types appear as dtype arguments in some pickles.
            return getattr(np, name)
        raise BodyError(f"pickle refused: it calls {module}.{name}, which is not a numpy/scipy data type; "
                        "a model file must only contain arrays (the file may be malicious)")

    def persistent_load(self, pid):
        raise BodyError("pickle refused: it uses persistent ids, which model files never do")


def safe_load(data_or_path) -> object:
    """Load a pickle through :class:`SafeUnpickler`.

    Parameters
    ----------
    data_or_path : bytes or path. Python-2 era pickles are decoded as latin1.

    Raises
    ------
    BodyError : the pickle calls anything outside the admitted types, or is corrupt.
    """
    if isinstance(data_or_path, (bytes, bytearray)):
        data, where = bytes(data_or_path), "model data"
    else:
        path = Path(data_or_path)
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise BodyError(f"cannot read {path}: {exc.strerror}") from None
        where = str(path)
    try:
        return SafeUnpickler(io.BytesIO(data), encoding="latin1").load()
    except BodyError as exc:
        raise BodyError(f"{where}: {exc}") from None
    except (pickle.UnpicklingError, EOFError, AttributeError, TypeError, ValueError, IndexError) as exc:
        raise BodyError(f"{where}: not a readable model pickle ({type(exc).__name__}: {exc})") from None


def as_array(obj) -> np.ndarray:
    """Plain array from what a model pickle holds: ndarray, chumpy stand-in, sparse stand-in."""
    if isinstance(obj, ChumpyStandIn):
        return obj.array()
    if isinstance(obj, SparseStandIn):
        return obj.to_scipy().toarray()
    return np.asarray(obj)
