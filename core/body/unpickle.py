"""A restricted unpickler for body-model files that users bring (SMPL ``.pkl``).

A pickle can call any importable callable while it loads, so an SMPL file of
unknown origin must never go through :func:`pickle.load`. :class:`SafeUnpickler`
admits only what a model file needs, and none of it is the real numpy or
scipy machinery: every callable the pickle may name is a stand-in here that
checks its arguments and builds arrays only from validated data.

- Arrays (``numpy.core.multiarray._reconstruct`` + state, ``scalar``,
  ``_frombuffer``): the dtype from an allow-list (:func:`core.body.arrays.check_dtype`:
  numbers and text, never objects, records or dtype flags that make numpy read
  references), the shape and byte size within :mod:`core.body.arrays`' limits
  and equal to the bytes actually present, copied into a fresh array. Nothing
  in the pickle can hand numpy a raw address (``__array_interface__``,
  ``__array_struct__``, buffers): the stand-ins keep their state in slots,
  never in an instance ``__dict__`` numpy would look into, and are never
  passed to numpy.
- scipy.sparse matrices are rebuilt from their arrays after checking
  ``indptr``/``indices`` against the shape (never through scipy's own pickle
  hooks, never densified over the size limit).
- chumpy objects (SMPL's py2-era files store arrays inside ``chumpy.ch.Ch``)
  keep their ``x``; a chumpy object that refers to itself is refused.
- A few inert builtins (``bytes``, ``bytearray``, ``set``, ...) that refuse
  sizes: ``bytearray(3_000_000_000)`` from a 62-byte pickle is not a model file.

Anything else raises :class:`BodyError` naming the refused callable, before it could run.
"""

from __future__ import annotations

import io
import pickle
from pathlib import Path

import numpy as np

from ..errors import BodyError
from .arrays import MAX_ARRAY_ELEMENTS, MAX_TOTAL_BYTES, check_csr, check_dtype, check_shape, dtype_from_code, numbers

# A model pickle is its arrays plus a little: refuse files far larger before reading them.
MAX_PICKLE_BYTES = MAX_TOTAL_BYTES + (256 << 20)
# Chumpy objects nest (an array inside a Ch inside a Ch); real files go 2-3 deep.
MAX_NESTING = 32

_DTYPE_FLAGS_REFUSED = 0x01 | 0x02 | 0x04 | 0x10 | 0x20 | 0x40  # refcount/list-pickle/pointer/pyapi/getitem/setitem


def _refuse(what: str):
    raise BodyError(f"pickle refused: {what}")


class _Marker:
    """A class the pickle names only as an argument (``numpy.ndarray``, ``object``); calling it is refused."""

    __slots__ = ("name",)

    def __init__(self, name):
        self.name = name

    def __call__(self, *args, **kwargs):
        _refuse(f"it calls {self.name} directly; model files only rebuild arrays")


_NDARRAY = _Marker("numpy.ndarray")


class ScalarType(_Marker):
    """A numpy scalar type named in the pickle (a dtype argument): callable on one plain number only."""

    __slots__ = ()

    def __call__(self, *args, **kwargs):
        if (
            kwargs
            or len(args) > 1
            or (
                args and not (isinstance(args[0], (bool, float)) or (isinstance(args[0], int) and abs(args[0]) < 2**64))
            )
        ):
            _refuse(
                f"numpy.{self.name} called with {len(args)} arguments of types "
                f"{', '.join(type(a).__name__ for a in args)}; expected one number"
            )
        return getattr(np, self.name)(*args)


_SCALAR_TYPES = (
    "bool_",
    "float64",
    "float32",
    "float16",
    "int64",
    "int32",
    "int16",
    "int8",
    "uint64",
    "uint32",
    "uint16",
    "uint8",
)


class DtypeStandIn:
    """``numpy.dtype(code, align, copy)`` + its state: a plain dtype from the allow-list, flags checked."""

    __slots__ = ("dtype",)

    def __init__(self, code=None, align=False, copy=True):
        if isinstance(code, ScalarType):
            code = np.dtype(getattr(np, code.name)).str
        elif isinstance(code, bytes):
            code = code.decode("latin1")
        self.dtype = dtype_from_code(code, "a dtype in the pickle")

    def __setstate__(self, state):
        if not isinstance(state, tuple) or len(state) not in (8, 9) or state[0] not in (3, 4):
            _refuse(
                f"a dtype state of {type(state).__name__} length "
                f"{len(state) if isinstance(state, tuple) else '-'}; expected numpy's (3 or 4, ...) tuple"
            )
        endian, sub, names, fields, elsize, _align, flags = state[1:8]
        if sub is not None or names is not None or fields is not None:
            _refuse("a dtype with fields or a sub-array; model arrays are plain numbers")
        if len(state) == 9 and state[8] is not None:
            _refuse("a dtype with metadata")
        if not isinstance(flags, int) or flags & _DTYPE_FLAGS_REFUSED:
            _refuse(f"dtype flags {flags!r} (object references); model arrays are plain numbers")
        if endian not in ("<", ">", "|", "="):
            _refuse(f"dtype byte order {endian!r}")
        if elsize not in (-1, self.dtype.itemsize) and not (
            self.dtype.kind in "SU" and isinstance(elsize, int) and 0 < elsize <= 1 << 20
        ):
            _refuse(f"dtype item size {elsize!r} for {self.dtype.str!r}")
        dt = self.dtype
        if dt.kind in "SU" and elsize not in (-1, dt.itemsize):
            dt = np.dtype(f"{dt.kind}{elsize // (4 if dt.kind == 'U' else 1)}")
        self.dtype = dt.newbyteorder(endian) if endian in "<>" and dt.kind not in "bS" else dt


def _as_dtype(dtype, where) -> np.dtype:
    if isinstance(dtype, DtypeStandIn):
        return dtype.dtype
    _refuse(f"{where}: expected a dtype, got {type(dtype).__name__}")


def _raw_bytes(raw, where) -> bytes:
    if isinstance(raw, (bytes, bytearray)):
        return bytes(raw)
    if isinstance(raw, str):  # a py2 str read as latin1
        try:
            return raw.encode("latin1")
        except UnicodeEncodeError:
            pass
    _refuse(f"{where}: array data of type {type(raw).__name__}; expected bytes")


class ArrayStandIn:
    """``_reconstruct(ndarray, shape, code)`` + ``__setstate__``: an array built from checked bytes.

    ``value`` is the array (None until the pickle sets the state).
    """

    __slots__ = ("value", "_budget")

    def __init__(self, budget):
        self.value = None
        self._budget = budget

    def __setstate__(self, state):
        if not isinstance(state, tuple) or len(state) not in (4, 5):
            _refuse("an array state that is not numpy's (version, shape, dtype, fortran, data) tuple")
        shape, dtype, fortran, raw = state[-4:]
        self.value = self._budget.build(shape, dtype, fortran, raw, "an array in the pickle")


class _Budget:
    """The bytes of array data one pickle has built so far, against :data:`MAX_TOTAL_BYTES`."""

    def __init__(self):
        self.total = 0

    def build(self, shape, dtype, fortran, raw, where) -> np.ndarray:
        if isinstance(shape, list):
            shape = tuple(shape)
        dt = check_dtype(_as_dtype(dtype, where), where)
        count = check_shape(shape, dt.itemsize, where)
        data = _raw_bytes(raw, where)
        if len(data) != count * dt.itemsize:
            _refuse(
                f"{where}: shape {shape} of {dt.str!r} needs {count * dt.itemsize} bytes, the pickle holds {len(data)}"
            )
        self.total += len(data)
        if self.total > MAX_TOTAL_BYTES:
            _refuse(f"more than {MAX_TOTAL_BYTES / 2**30:g} GiB of array data")
        flat = np.frombuffer(data, dtype=dt, count=count).copy() if count else np.empty(0, dtype=dt)
        return flat.reshape(shape, order="F" if fortran else "C")


class ChumpyStandIn:
    """Stands in for any chumpy class; keeps the pickled state (in a slot, never as attributes)."""

    __slots__ = ("state",)

    def __new__(cls, *args, **kwargs):
        # copyreg._reconstructor and NEWOBJ make the object without __init__
        obj = object.__new__(cls)
        obj.state = {}
        return obj

    def __init__(self, *args, **kwargs):
        # chumpy.Ch(x) rebuilt by a REDUCE call: its first argument is the array.
        if args:
            self.state["x"] = args[0]
        elif "x" in kwargs:
            self.state["x"] = kwargs["x"]

    def __setstate__(self, state):
        if isinstance(state, tuple) and len(state) == 2:
            a, b = state
            state = {**(a if isinstance(a, dict) else {}), **(b if isinstance(b, dict) else {})}
        if isinstance(state, dict):
            self.state.update({k: v for k, v in state.items() if isinstance(k, str)})

    def array(self, _seen=None) -> np.ndarray:
        """The array a terminal chumpy object holds (its ``x``)."""
        x = self.state.get("x")
        if x is None:
            raise BodyError(
                "a chumpy object in the pickle is a derived expression, not an array; "
                "re-save the model with plain numpy arrays"
            )
        return as_array(x, _seen=_seen)


class SparseStandIn:
    """Stands in for a scipy.sparse matrix; rebuilt by :meth:`to_scipy` from its checked arrays."""

    __slots__ = ("fmt", "state")

    def __init__(self, fmt: str):
        self.fmt = fmt
        self.state = {}

    def __setstate__(self, state):
        if isinstance(state, dict):
            self.state.update({k: v for k, v in state.items() if isinstance(k, str)})

    def to_scipy(self, _seen=None):
        import scipy.sparse as sp

        d = self.state
        try:
            shape = tuple(int(s) for s in d.get("_shape", d.get("shape")))
            if len(shape) != 2 or min(shape) < 0 or max(shape) > 1 << 40:
                raise ValueError(f"shape {shape}")
            data = as_array(d["data"], _seen=_seen).ravel()
            if self.fmt in ("csc", "csr"):
                indices = as_array(d["indices"], _seen=_seen).ravel()
                indptr = as_array(d["indptr"], _seen=_seen).ravel()
                major, minor = shape if self.fmt == "csr" else shape[::-1]
                check_csr(data, indices, indptr, major, minor, "")
                cls = sp.csc_matrix if self.fmt == "csc" else sp.csr_matrix
                return cls((data, indices, indptr), shape=shape)
            if self.fmt == "coo":
                coords = d.get("coords", (None, None))
                row = as_array(d.get("row", coords[0]), _seen=_seen).ravel()
                col = as_array(d.get("col", coords[1]), _seen=_seen).ravel()
                if not (len(row) == len(col) == len(data)) or row.dtype.kind not in "iu" or col.dtype.kind not in "iu":
                    raise ValueError("row, col and data differ in length or are not integers")
                if len(data) and (row.min() < 0 or row.max() >= shape[0] or col.min() < 0 or col.max() >= shape[1]):
                    raise ValueError(f"an entry lies outside the shape {shape}")
                return sp.coo_matrix((data, (row, col)), shape=shape)
        except (KeyError, TypeError, ValueError, OverflowError, IndexError) as exc:
            raise BodyError(f"a scipy.sparse {self.fmt} matrix in the pickle is malformed ({exc})") from None
        raise BodyError(f"scipy.sparse format {self.fmt!r} is not supported in model files")


def _reconstructor(cls, base, state):
    """Safe ``copyreg._reconstructor`` (protocol 0/1 objects): stand-ins only."""
    if base is _OBJECT and isinstance(cls, type) and issubclass(cls, (ChumpyStandIn, SparseStandIn)):
        return cls.__new__(cls)
    raise BodyError(
        f"pickle refused: cannot rebuild {getattr(cls, '__name__', cls)!r} from base {getattr(base, 'name', base)!r}"
    )


def _codecs_encode(text, encoding="utf-8"):
    """Safe ``_codecs.encode``: py3 protocol<3 pickles store bytes as ``encode(str, 'latin1')``."""
    if (
        not isinstance(text, str)
        or not isinstance(encoding, str)
        or encoding.lower().replace("_", "-") not in ("latin1", "latin-1", "ascii", "utf-8", "utf8")
    ):
        raise BodyError(f"pickle refused: _codecs.encode with encoding {encoding!r}")
    try:
        return text.encode(encoding)
    except UnicodeEncodeError:
        _refuse(f"_codecs.encode: text not representable in {encoding}")


def _sparse_factory(fmt):
    class _Sparse(SparseStandIn):
        __slots__ = ()

        def __new__(cls, *args, **kwargs):
            obj = object.__new__(cls)
            obj.fmt = fmt
            obj.state = {}
            return obj

        def __init__(self, *args, **kwargs):
            pass

    _Sparse.__name__ = f"{fmt}_matrix"
    return _Sparse


_SPARSE = {f"{fmt}_matrix": _sparse_factory(fmt) for fmt in ("csc", "csr", "coo")}
_SPARSE.update({f"{fmt}_array": _SPARSE[f"{fmt}_matrix"] for fmt in ("csc", "csr", "coo")})


def _container(kind):
    """``set``, ``frozenset``, ``list``, ``tuple``, ``dict`` on a container the pickle already holds
    (same size), never on bytes or text (a list of a 1 GB bytes object is 28 GB)."""

    def build(*args):
        if len(args) > 1 or (args and not isinstance(args[0], (list, tuple, dict, set, frozenset))):
            _refuse(f"{kind.__name__}() of {', '.join(type(a).__name__ for a in args)}")
        return kind(*args)

    return build


def _byte_string(kind):
    """``bytes`` / ``bytearray`` of bytes or of text and an encoding (protocol 2 writes ``bytes()`` for
    b''); never of a size."""

    def build(*args):
        if not args:
            return kind()
        if len(args) == 1 and isinstance(args[0], (bytes, bytearray)):
            return kind(args[0])
        if len(args) == 2 and isinstance(args[0], str) and isinstance(args[1], str):
            return kind(_codecs_encode(args[0], args[1]))
        _refuse(f"{kind.__name__}() of {', '.join(type(a).__name__ for a in args)}; expected bytes")

    return build


def _safe_complex(*args):
    if not all(isinstance(a, (int, float)) for a in args) or len(args) > 2:
        _refuse("complex() of non-numbers")
    return complex(*args)


def _safe_slice(*args):
    if len(args) > 3 or not all(a is None or isinstance(a, int) for a in args):
        _refuse("slice() of non-integers")
    return slice(*args)


_OBJECT = _Marker("object")
_BUILTINS = {
    "set": _container(set),
    "frozenset": _container(frozenset),
    "list": _container(list),
    "tuple": _container(tuple),
    "dict": _container(dict),
    "slice": _safe_slice,
    "complex": _safe_complex,
    "object": _OBJECT,
    "bytes": _byte_string(bytes),
    "bytearray": _byte_string(bytearray),
}


class SafeUnpickler(pickle.Unpickler):
    """Unpickler admitting only numpy/scipy.sparse data (rebuilt here) and chumpy stand-ins."""

    def __init__(self, file, **kwargs):
        super().__init__(file, **kwargs)
        self._budget = _Budget()
        budget = self._budget

        def reconstruct(cls, shape=(0,), code=b"b"):
            if cls is not _NDARRAY:
                _refuse(f"_reconstruct of {getattr(cls, 'name', type(cls).__name__)}; only numpy.ndarray")
            return ArrayStandIn(budget)

        def scalar(dtype, data=b""):
            dt = check_dtype(_as_dtype(dtype, "a numpy scalar"), "a numpy scalar")
            raw = _raw_bytes(data, "a numpy scalar")
            if len(raw) != dt.itemsize:
                _refuse(f"a numpy scalar of {dt.str!r} needs {dt.itemsize} bytes, got {len(raw)}")
            return np.frombuffer(raw, dtype=dt)[0]

        def frombuffer(buf, dtype, shape, order="C"):
            return budget.build(
                tuple(shape) if isinstance(shape, list) else shape, dtype, order == "F", buf, "an array in the pickle"
            )

        numpy_names = {"_reconstruct": reconstruct, "scalar": scalar, "_frombuffer": frombuffer}
        self._numpy = {}
        # py2-era and numpy<2 pickles name numpy.core, numpy>=2 pickles numpy._core.
        for core in ("numpy.core", "numpy._core"):
            for mod in ("multiarray", "numeric"):
                for name, fn in numpy_names.items():
                    self._numpy[(f"{core}.{mod}", name)] = fn
        self._numpy[("numpy", "ndarray")] = _NDARRAY
        self._numpy[("numpy", "dtype")] = DtypeStandIn
        for name in _SCALAR_TYPES:
            self._numpy[("numpy", name)] = ScalarType(name)

    def find_class(self, module: str, name: str):
        fn = self._numpy.get((module, name))
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
        raise BodyError(
            f"pickle refused: it calls {module}.{name}, which is not a numpy/scipy data type; "
            "a model file must only contain arrays (the file may be malicious)"
        )

    def persistent_load(self, pid):
        raise BodyError("pickle refused: it uses persistent ids, which model files never do")


def safe_load(data_or_path) -> object:
    """Load a pickle through :class:`SafeUnpickler`.

    Parameters
    ----------
    data_or_path : bytes or path. Python-2 era pickles are decoded as latin1.

    Returns
    -------
    The unpickled object; arrays are plain numpy arrays where they are values of
    the top-level dict, :class:`ArrayStandIn` elsewhere (:func:`as_array` reads both).

    Raises
    ------
    BodyError : the pickle calls anything outside the admitted types, builds an
        array over the limits or from inconsistent data, or is corrupt.
    """
    if isinstance(data_or_path, (bytes, bytearray)):
        data, where = bytes(data_or_path), "model data"
    else:
        path = Path(data_or_path)
        try:
            size = path.stat().st_size
            if size > MAX_PICKLE_BYTES:
                raise BodyError(
                    f"{path}: {size / 2**30:.3g} GiB is over the {MAX_PICKLE_BYTES / 2**30:.3g} GiB a "
                    "model pickle may have"
                )
            data = path.read_bytes()
        except OSError as exc:
            raise BodyError(f"cannot read {path}: {exc.strerror}") from None
        where = str(path)
    try:
        obj = SafeUnpickler(io.BytesIO(data), encoding="latin1").load()
    except BodyError as exc:
        raise BodyError(f"{where}: {exc}") from None
    except RecursionError:
        raise BodyError(f"{where}: not a readable model pickle (nested too deeply)") from None
    except MemoryError:
        raise BodyError(f"{where}: not a readable model pickle (it asks for more memory than there is)") from None
    except (
        pickle.UnpicklingError,
        EOFError,
        AttributeError,
        TypeError,
        ValueError,
        IndexError,
        KeyError,
        OverflowError,
        UnicodeDecodeError,
        ImportError,
    ) as exc:
        raise BodyError(f"{where}: not a readable model pickle ({type(exc).__name__}: {exc})") from None
    if isinstance(obj, dict):
        obj = {k: (v.value if isinstance(v, ArrayStandIn) and v.value is not None else v) for k, v in obj.items()}
    return obj


def as_array(obj, key: str = "", _seen=None) -> np.ndarray:
    """Plain array from what a model pickle holds: an array, a chumpy or sparse stand-in, numbers.

    Raises
    ------
    BodyError : anything else (text, objects, a chumpy object that refers to
        itself, a sparse matrix whose dense form is over the size limit).
    """
    pre = f"key {key!r}: " if key else ""
    seen = set() if _seen is None else _seen
    if id(obj) in seen:
        raise BodyError(f"{pre}an object in the pickle refers to itself")
    if len(seen) > MAX_NESTING:
        raise BodyError(f"{pre}chumpy objects nested more than {MAX_NESTING} deep")
    if isinstance(obj, np.ndarray):
        check_dtype(obj.dtype, f"{pre}an array in the pickle".strip())
        return obj
    if isinstance(obj, ArrayStandIn):
        if obj.value is None:
            raise BodyError(f"{pre}an array in the pickle has no data")
        return obj.value
    if isinstance(obj, (ChumpyStandIn, SparseStandIn)):
        seen.add(id(obj))
        try:
            if isinstance(obj, ChumpyStandIn):
                return obj.array(_seen=seen)
            m = obj.to_scipy(_seen=seen)
        except BodyError as exc:
            raise BodyError(f"{pre}{exc}") from None
        finally:
            seen.discard(id(obj))
        if m.shape[0] * m.shape[1] > MAX_ARRAY_ELEMENTS:
            raise BodyError(
                f"{pre}a sparse matrix of shape {m.shape} is over the limit of "
                f"{MAX_ARRAY_ELEMENTS:.3g} elements as a dense array"
            )
        return m.toarray()
    if isinstance(obj, (bool, float, np.generic)) or (isinstance(obj, int) and abs(obj) < 2**63):
        return np.asarray(obj)
    if isinstance(obj, (list, tuple)):
        if any(isinstance(x, (ChumpyStandIn, SparseStandIn, ArrayStandIn, list, tuple)) for x in obj):
            seen.add(id(obj))
            parts = [as_array(x, key, _seen=seen) for x in obj]
            seen.discard(id(obj))
            if len({(p.shape, p.dtype.kind) for p in parts}) > 1:
                raise BodyError(f"{pre}a list in the pickle holds arrays of different shapes")
            return np.asarray(parts)
        return numbers(obj, f"{pre}a list in the pickle")
    raise BodyError(f"{pre}expected an array, got {type(obj).__name__}")
