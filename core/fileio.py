"""Atomic file output: nothing already made is lost or half-written.

Write every output through these helpers. A file appears under its final
name only once it is complete; an output directory is filled in a sibling
temporary directory and moved into place at the end, so a failure or a
cancellation leaves the previous contents untouched.
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Iterator, Union

import numpy as np

PathLike = Union[str, os.PathLike]


def _umask() -> int:
    # /proc gives the umask without changing it (os.umask is process-wide and racy
    # while a worker thread, e.g. the add-on's drape job, creates files)
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_bytes(path: PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temp file in the same dir + rename).

    The file gets the permissions a plain ``open(path, "w")`` would give
    (0666 minus the umask): ``mkstemp`` makes it owner-only, which would hide
    pattern files from the rest of a cutting room's group.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def write_text(path: PathLike, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def dumps_json(obj, indent: int | None = 1) -> str:
    return json.dumps(obj, indent=indent, default=_json_default, allow_nan=False)


def write_json(path: PathLike, obj, indent: int | None = 1) -> Path:
    return write_text(path, dumps_json(obj, indent=indent) + "\n")


@contextlib.contextmanager
def output_dir(path: PathLike) -> Iterator[Path]:
    """Fill a fresh directory and move it to ``path`` only on success.

    Files already in ``path`` that the operation does not write are kept;
    files it writes replace the old ones. On any exception nothing in
    ``path`` changes.
    """
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".tmp", dir=final.parent))
    try:
        yield tmp
        mask = _umask()
        final.mkdir(parents=True, exist_ok=True)
        for src in sorted(tmp.rglob("*")):
            rel = src.relative_to(tmp)
            dst = final / rel
            if src.is_dir():
                dst.mkdir(parents=True, exist_ok=True)
            else:
                # writers that bypass write_bytes (matplotlib, ezdxf, reportlab) already follow
                # the umask; only owner-only files (mkstemp's) need fixing
                if (src.stat().st_mode & 0o777) == 0o600:
                    os.chmod(src, 0o666 & ~mask)
                dst.parent.mkdir(parents=True, exist_ok=True)
                os.replace(src, dst)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
