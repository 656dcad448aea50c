"""Arrays from files users bring (model ``.npz``, blend shapes, cut embeddings), checked before use.

Every array is checked against what it claims and what the file holds before
any memory is taken for it: its dtype must be a plain one (booleans, integers,
floats, fixed-width text: :func:`check_dtype`, never Python objects, records
or sub-arrays), its element count and byte size must stay under the limits
below, and the bytes it declares must be present in the file. A ``.npz`` is
read member by member from its zip directory (:func:`read_npz`): the ``.npy``
header of each member is parsed and checked first, then exactly that many
bytes are read into a fresh array, so an archive declaring 10^12 elements,
a truncated or empty archive, or an ``.npy`` renamed ``.npz`` ends in one
error line naming the file and the key.

Limits. The largest file the project reads is an SMPL-X model: v_template
10475 x 3, shapedirs 10475 x 3 x 400 (12.6 M elements, 100 MB as float64),
posedirs 10475 x 3 x 486 (15.3 M elements, 122 MB), about 0.3 GB in all. One
array may hold :data:`MAX_ARRAY_ELEMENTS` = 2^27 elements (134 M: 1 GiB once
converted to float64), a file :data:`MAX_TOTAL_BYTES` = 2 GiB of array data,
which leaves a real SMPL-X file a factor of 6 below every limit.
"""

from __future__ import annotations

import re
import zipfile
import zlib
from pathlib import Path
from typing import Dict, Iterable, Optional, Type

import numpy as np

from ..errors import BodyError, EaseError

MAX_ARRAY_ELEMENTS = 1 << 27  # elements in one array (1 GiB as float64)
MAX_ARRAY_BYTES = 1 << 30  # bytes of one array as stored
MAX_TOTAL_BYTES = 2 << 30  # bytes of array data in one file
MAX_NDIM = 8  # no model array has more than 3 dimensions

# dtype kinds a model file may hold: bool, signed and unsigned integers, floats,
# fixed-width bytes and text (names). Never objects (references), records, voids.
ALLOWED_KINDS = "biufSU"

_DTYPE_CODE = re.compile(
    r"^[<>|=]?(\?|b1|[bBhHiIlLqQefdg]|[iu][1248]|f(2|4|8|16)|[SU]\d{0,6}"
    r"|bool|u?int(8|16|32|64)|float(16|32|64))$"
)


def check_dtype(dtype, where: str, error: Type[EaseError] = BodyError) -> np.dtype:
    """The dtype if it is a plain one (:data:`ALLOWED_KINDS`, no fields, no sub-array), else ``error``."""
    dt = np.dtype(dtype) if not isinstance(dtype, np.dtype) else dtype
    if (
        dt.hasobject
        or dt.fields is not None
        or dt.subdtype is not None
        or dt.kind not in ALLOWED_KINDS
        or (dt.itemsize == 0 and dt.kind not in "SU")
    ):
        raise error(
            f"{where}: dtype {dt.str!r} is not allowed; expected numbers or text "
            "(bool, int, float, fixed-width strings), never Python objects or records"
        )
    return dt


def dtype_from_code(code, where: str, error: Type[EaseError] = BodyError) -> np.dtype:
    """A dtype from a short type code (``'<f8'``, ``'u4'``, ``'U12'``) after matching it against the allow-list."""
    if not isinstance(code, str) or not _DTYPE_CODE.match(code):
        raise error(f"{where}: dtype {code!r} is not allowed; expected a plain numeric or text type code")
    return check_dtype(np.dtype(code), where, error)


def check_shape(shape, itemsize: int, where: str, error: Type[EaseError] = BodyError) -> int:
    """Element count of ``shape`` (a tuple of Python ints) if it and its byte size are within the limits."""
    if (
        not isinstance(shape, tuple)
        or len(shape) > MAX_NDIM
        or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in shape)
    ):
        raise error(f"{where}: array shape {shape!r} is not a tuple of at most {MAX_NDIM} sizes >= 0")
    count = 1
    for s in shape:
        count *= s  # exact Python ints: no overflow
    if count > MAX_ARRAY_ELEMENTS or count * itemsize > MAX_ARRAY_BYTES:
        raise error(
            f"{where}: array of shape {shape} ({count:.3g} elements, {count * itemsize / 2**30:.3g} GiB) "
            f"is over the limit of {MAX_ARRAY_ELEMENTS:.3g} elements / {MAX_ARRAY_BYTES / 2**30:g} GiB "
            "per array"
        )
    return count


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, where: str, error) -> np.ndarray:
    fmt = np.lib.format
    with zf.open(info) as f:
        try:
            version = fmt.read_magic(f)
            if version == (1, 0):
                shape, fortran, dtype = fmt.read_array_header_1_0(f)
            elif version == (2, 0):
                shape, fortran, dtype = fmt.read_array_header_2_0(f)
            else:
                raise ValueError(f"unsupported .npy version {version}")
        except ValueError as exc:
            raise error(f"{where}: not a readable .npy member ({exc})") from None
        header = f.tell()
        dt = check_dtype(dtype, where, error)
        count = check_shape(tuple(int(s) for s in shape), dt.itemsize, where, error)
        nbytes = count * dt.itemsize
        if info.file_size < header + nbytes:
            raise error(
                f"{where}: the header declares {nbytes} bytes of data, the file holds "
                f"{max(0, info.file_size - header)} (truncated)"
            )
        out = np.empty(count, dtype=dt)
        view = memoryview(out).cast("B") if nbytes else None
        done = 0
        while done < nbytes:
            n = f.readinto(view[done:])
            if not n:
                raise error(f"{where}: the data ends after {done} of {nbytes} bytes (truncated)")
            done += n
    return out.reshape(shape, order="F" if fortran else "C")


def read_npz(
    path, keys: Optional[Iterable[str]] = None, error: Type[EaseError] = BodyError, what: str = "a .npz file"
) -> Dict[str, np.ndarray]:
    """The arrays of a ``.npz`` archive, each checked before it is read (see the module doc).

    Parameters
    ----------
    path : the ``.npz`` file.
    keys : names of the arrays to read (others are skipped unread); None: all.
    error : the :class:`core.errors.EaseError` subclass to raise.
    what : what the file should be, for the messages ("an SMPL model .npz").

    Returns
    -------
    dict key -> array (only keys the archive has).

    Raises
    ------
    ``error`` naming the file (and the key) for an unreadable, truncated or
    non-zip file, a member that is not a plain ``.npy`` array, or an array over
    the limits.
    """
    path = Path(path)
    wanted = None if keys is None else set(keys)
    out = {}
    total = 0
    try:
        with zipfile.ZipFile(path) as zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy"):
                    continue
                key = info.filename[:-4]
                if wanted is not None and key not in wanted:
                    continue
                arr = _read_member(zf, info, f"{path}: key {key!r}", error)
                total += arr.nbytes
                if total > MAX_TOTAL_BYTES:
                    raise error(
                        f"{path}: more than {MAX_TOTAL_BYTES / 2**30:g} GiB of array data "
                        f"(at key {key!r}); not a model file this project reads"
                    )
                out[key] = arr
    except EaseError:
        raise
    except (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, zlib.error) as exc:
        raise error(f"{path}: not {what} (a truncated, empty or non-zip file: {exc})") from None
    except (OSError, ValueError, NotImplementedError, RuntimeError) as exc:
        raise error(f"{path}: not a readable {what} ({type(exc).__name__}: {exc})") from None
    return out


def numbers(value, where: str, error: Type[EaseError] = BodyError) -> np.ndarray:
    """``value`` as an array whose dtype is numeric (bool, int, float), else ``error`` naming ``where``."""
    try:
        a = np.asarray(value)
    except (TypeError, ValueError, OverflowError, RecursionError) as exc:
        raise error(f"{where}: expected an array of numbers ({type(exc).__name__})") from None
    if a.dtype.kind not in "biuf":
        raise error(f"{where}: expected an array of numbers, got dtype {a.dtype.str!r}")
    return a


def finite_array(value, where: str, dtype=float, error: Type[EaseError] = BodyError) -> np.ndarray:
    """``value`` as an array of numbers of ``dtype``, every entry finite, else ``error`` naming ``where``."""
    a = numbers(value, where, error).astype(dtype)
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        raise error(f"{where}: holds NaN or infinite values")
    return a


def index_array(value, where: str, error: Type[EaseError] = BodyError) -> np.ndarray:
    """``value`` as an int64 array of whole numbers (integer dtype, or floats that are integers)."""
    a = finite_array(value, where, dtype=np.float64 if np.asarray(value).dtype.kind == "f" else np.int64, error=error)
    if a.dtype.kind == "f":
        if a.size and (np.any(a != np.round(a)) or np.abs(a).max() > 2.0**62):
            raise error(f"{where}: expected whole-number indices")
        a = a.astype(np.int64)
    return a


def check_csr(data, indices, indptr, major: int, minor: int, where: str, error=BodyError) -> None:
    """Compressed-sparse arrays consistent with a (major, minor) shape, every index in range.

    scipy's own constructor does not check index bounds, and a product with an
    index outside the matrix reads outside its memory.
    """
    pre = f"{where}: " if where else ""
    if indices.dtype.kind not in "iu" or indptr.dtype.kind not in "iu" or data.dtype.kind not in "biuf":
        raise error(f"{pre}indices and indptr must be integers and data numbers")
    if indptr.size != major + 1:
        raise error(f"{pre}'indptr' has {indptr.size} entries, expected {major + 1} (rows + 1)")
    if indptr[0] != 0 or np.any(np.diff(indptr.astype(np.int64)) < 0) or int(indptr[-1]) != indices.size:
        raise error(f"{pre}'indptr' must rise from 0 to the number of entries ({indices.size})")
    if data.size != indices.size:
        raise error(f"{pre}'data' has {data.size} entries, 'indices' {indices.size}")
    if indices.size and (indices.min() < 0 or int(indices.max()) >= minor):
        raise error(f"{pre}'indices' has entries outside [0, {minor})")
    if data.dtype.kind == "f" and not np.isfinite(data).all():
        raise error(f"{pre}'data' holds NaN or infinite values")
