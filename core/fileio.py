"""Atomic file output: a file or an output folder is all-old or all-new.

Write every output through these helpers.

* :func:`write_bytes` (and the text/JSON forms) writes a temporary file beside
  the target and renames it over the target: a reader sees the old file or
  the new one, never a part.
* :func:`output_dir` fills a new folder beside the target and exchanges the
  two with one rename (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two
  renames, the old folder kept under a recognisable name until the new one is
  in place). A failure, an exception or Ctrl-C before that rename leaves the
  old folder untouched; after it the folder is the new one. Files of the old
  folder that the run does not write are carried into the new folder (hard
  links) before the exchange, so they are kept.
* A target that cannot be renamed (a mount point, or a folder whose parent is
  read-only) is filled in a staging folder inside it and its entries are
  swapped one rename each, with SIGINT/SIGTERM held off; if the process is
  killed during those renames, the next run writing that folder completes the
  swap first.

Temporary names are ``.NAME.ease-tmp-PID-XXXX`` (``ease-old``/``ease-new``
while swapping): a run that was killed leaves one behind, and the next write
of ``NAME`` removes it once process PID no longer exists. Durability against
a power cut is the filesystem's (files are fsync'ed, folders are not).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import hashlib
import os
import re
import secrets
import shutil
import threading
from pathlib import Path
from typing import Iterator, List, Tuple, Union

from .errors import EaseError
from .jsontext import dumps_json
from .signals import signals_held

PathLike = Union[str, os.PathLike]

_TEMP = re.compile(r"^\.(?P<name>.*)\.ease-(?P<kind>tmp|old|new)-(?P<pid>\d+)-(?P<tag>[0-9a-f]+)$")
_NAME_MAX = 200  # bytes of the target's name inside a temporary name (filesystems allow 255)
_committed: List[Path] = []
_lock = threading.Lock()


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


def _short(name: str) -> str:
    """``name`` as its temporaries carry it: under :data:`_NAME_MAX` bytes as it is, else its first
    whole characters, ``~`` and a hash of the whole, exactly :data:`_NAME_MAX` bytes (so a shortened
    name is known by its length), and names alike in their first bytes never take each other's
    leftovers (a killed run's old folder put back under another name)."""
    raw = os.fsencode(name)
    if len(raw) < _NAME_MAX:
        return name
    head = raw[: _NAME_MAX - 9].decode("utf-8", "ignore")  # a character cut in two dropped
    tildes = "~" * (_NAME_MAX - 8 - len(head.encode("utf-8")))
    return f"{head}{tildes}{hashlib.blake2b(raw, digest_size=4).hexdigest()}"


def _temp_name(name: str, kind: str, tag: str) -> str:
    return f".{_short(name)}.ease-{kind}-{tag}"


def _new_tag() -> str:
    return f"{os.getpid()}-{secrets.token_hex(4)}"


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # another user's process, or no way to tell: leave its files alone
    return True


def _stale(folder: Path, name: str) -> List[Tuple[str, str, Path]]:
    """``(kind, tag, path)`` of the temporary entries for ``name`` in ``folder``
    whose process is gone."""
    out = []
    try:
        entries = os.listdir(folder)
    except OSError:
        return out
    # a batch lists its items folder once per item: the cheap prefix test first, the
    # regex and the sort on the few entries that pass it
    short = _short(name)
    prefix = f".{short}.ease-"
    for entry in sorted(e for e in entries if e.startswith(prefix)):
        m = _TEMP.match(entry)
        if m and m["name"] == short and not _alive(int(m["pid"])):
            out.append((m["kind"], f"{m['pid']}-{m['tag']}", folder / entry))
    return out


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(path)


def _refuse(path: Path, exc: OSError, what: str) -> EaseError:
    reason = exc.strerror or str(exc)
    return EaseError(f"{path}: cannot write {what} ({reason})")


def _check_target(path: Path, folder: bool) -> bool:
    """One clear error for a target that cannot be written (checked before any work).

    Returns whether ``path``'s folder exists (then no folder above it can be a file: one stat
    instead of two per level, which a batch pays for every file of every item).
    """
    there = path.parent.is_dir()
    for parent in () if there else reversed(path.parents):
        if parent.exists() and not parent.is_dir():
            raise EaseError(f"{path}: cannot write here: {parent} is a file, not a folder")
    if folder and path.exists() and not path.is_dir():
        raise EaseError(f"{path}: is a file; expected an output folder")
    if not folder and path.is_dir():
        raise EaseError(f"{path}: is a folder; expected a file name")
    return there


def check_output(path: PathLike, folder: bool = True) -> None:
    """Refuse, before any work, an output that cannot be written.

    ``folder``: ``path`` is an output folder (else a file). Raises
    :class:`EaseError` (one line naming ``path``) when it is a file where a
    folder is expected or the reverse, lies under a file, or is read-only.
    """
    path = Path(os.path.realpath(path))
    try:
        _check_target(path, folder)
        probe = path if folder and path.is_dir() else next((p for p in path.parents if p.is_dir()), None)
    except OSError as exc:  # a folder on the way that cannot be searched: one line, not a traceback
        raise _refuse(path, exc, "the output") from None
    if probe is not None and not os.access(probe, os.W_OK | os.X_OK):
        raise EaseError(f"{path}: cannot write here: {probe} is read-only")


def write_bytes(path: PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary file beside it, fsync, rename).

    The file gets the permissions a plain ``open(path, "w")`` would give
    (0666 minus the umask), so pattern files stay readable by a cutting room's
    group. Temporary files of an earlier, killed write of the same name are
    removed.

    Raises
    ------
    EaseError when ``path`` is a folder, lies under a file or cannot be
    written (read-only folder or filesystem, no permission).
    """
    path = Path(path)
    try:
        if not _check_target(path, folder=False):
            path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _refuse(path.parent, exc, "a folder") from None
    for _, _, old in _stale(path.parent, path.name):
        _remove(old)
    tmp = path.parent / _temp_name(path.name, "tmp", _new_tag())
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # 0666 minus the umask
    except OSError as exc:
        raise _refuse(path, exc, "the file") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
            _uncache(f.fileno(), len(data))
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _refuse(path, exc, "the file") from None
        raise
    return path


#: Files at least this large (bytes) leave the page cache once on disk (:func:`_uncache`).
UNCACHE_BYTES = 1 << 18


def _uncache(fd: int, size: int) -> None:
    """Drop a written, fsync'ed file's pages from the page cache (Linux; elsewhere nothing).

    Nothing reads them back soon: a batch writes a ~3 MB ``pattern.json`` an item and never
    reads it. Kept, every file takes fresh page-cache pages; on a virtual machine that gives
    free memory back to its host (this project's CI and benchmark machines) those cost ~30 us
    a page of kernel time, ~20 ms an item, 10 % of a shirt item's CPU. Dropped, the next
    file reuses the same pages: 2.8 MB then cost 1.3-1.5 ms of kernel time instead of 19-20.
    A later reader gets the file from disk.
    """
    if size >= UNCACHE_BYTES and hasattr(os, "posix_fadvise"):
        with contextlib.suppress(OSError):  # advice only: a filesystem may not take it
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)


def write_text(path: PathLike, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: PathLike, obj, indent: int | None = 1) -> Path:
    return write_text(path, dumps_json(obj, indent=indent) + "\n")


def write_files(out_dir: PathLike, files: dict) -> List[Path]:
    """Write ``{relative name: bytes}`` into the folder ``out_dir`` at once (:func:`output_dir`);
    returns the final paths."""
    out_dir = Path(out_dir)
    with output_dir(out_dir) as tmp:
        for name, data in files.items():
            write_bytes(tmp / name, data)
    return [out_dir / name for name in files]


def committed_outputs() -> Tuple[Path, ...]:
    """Every output folder :func:`output_dir` has put in place in this process, in order.

    The CLI compares it before and after a command to say truthfully what an
    interrupted command did write.
    """
    with _lock:
        return tuple(_committed)


# ----------------------------------------------------------------------------- output folders


def _exchange(a: Path, b: Path) -> bool:
    """Swap the folders ``a`` and ``b`` with one rename; False where the system cannot."""
    func = getattr(_libc(), "renameat2", None) if os.name == "posix" else None
    if func is None:
        return False
    at_fdcwd, rename_exchange = -100, 2
    if func(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
        return False  # a filesystem without RENAME_EXCHANGE: the two-rename fallback
    raise OSError(err, os.strerror(err), str(b))


_LIBC = []


def _libc():
    if not _LIBC:
        try:
            _LIBC.append(ctypes.CDLL(None, use_errno=True))
        except OSError:
            _LIBC.append(None)
    return _LIBC[0]


def _carry_over(old: Path, new: Path, top: bool = True) -> None:
    """Hard-link (else copy) every entry of ``old`` that ``new`` lacks into ``new``.

    The run's own files win: an old entry whose path ``new`` already holds (as
    a file or a folder) is not carried, nor anything under it when ``new``
    holds a file there. Temporary entries of EASE are never carried.
    """
    for entry in sorted(os.scandir(old), key=lambda e: e.name):
        if top and _TEMP.match(entry.name):
            continue
        dst = new / entry.name
        if entry.is_dir(follow_symlinks=False):
            if not os.path.lexists(dst):
                os.mkdir(dst)
                _carry_over(Path(entry.path), dst, top=False)
                shutil.copystat(entry.path, dst)
            elif dst.is_dir() and not dst.is_symlink():
                _carry_over(Path(entry.path), dst, top=False)
        elif not os.path.lexists(dst):
            if entry.is_symlink():
                os.symlink(os.readlink(entry.path), dst)
                continue
            try:
                os.link(entry.path, dst, follow_symlinks=False)
            except OSError:
                if entry.is_file(follow_symlinks=False):
                    shutil.copy2(entry.path, dst)
                # a socket or FIFO that cannot be linked is not output: not carried


def _fix_modes(tmp: Path) -> None:
    # writers that bypass write_bytes (matplotlib, ezdxf, reportlab) follow the
    # umask; only owner-only files (mkstemp's) need fixing (the umask read only then)
    mask = None
    for src in tmp.rglob("*"):
        if not src.is_symlink() and src.is_file() and (src.stat().st_mode & 0o777) == 0o600:
            mask = _umask() if mask is None else mask
            os.chmod(src, 0o666 & ~mask)


def _put_back(final: Path, stale) -> None:
    """Undo what killed runs left beside ``final``: ``stale``, its entries from :func:`_stale`."""
    # what is moved below is gone when removed, and _remove ignores a path that is gone
    for kind, tag, path in stale:
        if kind == "old" and not os.path.lexists(final):
            os.rename(path, final)  # killed between the two renames: the old folder back
    for kind, tag, path in stale:
        _remove(path)


def recover_folder(folder: PathLike) -> None:
    """What killed runs left beside every entry of ``folder``, finished or undone with one listing
    (:func:`output_dir` with ``recover=False`` then skips its own listing of ``folder``).

    A batch writes thousands of item folders into one folder: listing it once per
    item made writing an item cost time in proportion to the items already there.
    A temporary whose name was shortened (a target name of 200 bytes or more) is left
    to :func:`output_dir`'s own recovery, which knows the full name.
    """
    folder = Path(folder)
    try:
        entries = sorted(os.listdir(folder))
    except OSError:
        return
    stale = {}
    for entry in entries:
        m = _TEMP.match(entry)
        if m and len(os.fsencode(m["name"])) < _NAME_MAX and not _alive(int(m["pid"])):
            stale.setdefault(m["name"], []).append((m["kind"], f"{m['pid']}-{m['tag']}", folder / entry))
    for name, found in stale.items():
        _put_back(folder / name, found)


def _recover(final: Path, beside: bool = True) -> None:
    """Finish or undo what a killed run left for ``final`` (beside it, unless ``beside`` is False:
    the caller ran :func:`recover_folder` on its folder, and inside it)."""
    # one listing each: what is moved or swapped below is gone when removed
    if beside:
        _put_back(final, _stale(final.parent, final.name))
    if final.is_dir():
        inside = _stale(final, final.name)
        for kind, tag, path in inside:
            if kind == "new":
                _swap_entries(path, final, final / _temp_name(final.name, "old", tag))
        for kind, tag, path in inside:
            _remove(path)


def _swap_entries(new: Path, final: Path, old: Path) -> None:
    """Move every entry of ``new`` into ``final``, the one it replaces into ``old``.

    Resumable: an entry already moved is not in ``new`` any more, and one whose
    old version was moved aside but the new one not yet in is just moved in.
    """
    done: List[str] = []
    with signals_held():
        try:
            os.makedirs(old, exist_ok=True)
            for name in sorted(os.listdir(new)):
                dst = final / name
                if os.path.lexists(dst):
                    os.rename(dst, old / name)
                os.rename(new / name, dst)
                done.append(name)
        except OSError:
            # back to the old folder; if even that fails, both stay for the next run to finish
            _undo_swap(done, new, final, old)
            _remove(old)
            _remove(new)
            raise
    _remove(old)
    _remove(new)


def _undo_swap(done: List[str], new: Path, final: Path, old: Path) -> None:
    """Put back the entries :func:`_swap_entries` moved before it failed (the old folder again)."""
    for name in done:
        os.rename(final / name, new / name)
    for name in os.listdir(old) if old.is_dir() else ():
        os.rename(old / name, final / name)


def _in_place(final: Path) -> bool:
    """True when ``final`` is a folder that cannot itself be renamed."""
    if not final.is_dir():
        return False
    try:
        cwd = Path(os.getcwd())
    except OSError:
        cwd = None
    # renaming the folder that holds the working directory would leave the
    # process (and a caller's relative paths) in the deleted old folder
    inside = cwd is not None and (cwd == final or final in cwd.parents)
    return inside or os.path.ismount(final) or not os.access(final.parent, os.W_OK | os.X_OK)


@contextlib.contextmanager
def output_dir(path: PathLike, recover: bool = True) -> Iterator[Path]:
    """Fill a new folder and make it ``path`` only on success, all at once.

    Yields the folder to write into. Files already in ``path`` that the
    operation does not write are kept (carried into the new folder); files it
    writes replace the old ones. On any exception, Ctrl-C included, ``path``
    is unchanged. The new folder gets the old one's permissions (else 0777
    minus the umask); its owner and ACLs are the writing user's.
    ``recover`` False: the caller ran :func:`recover_folder` on ``path``'s folder
    (a batch, once for all its items), so what killed runs left beside ``path`` is
    not looked for again (but for a name of 200 bytes or more, which
    :func:`recover_folder` leaves).

    Raises
    ------
    EaseError when ``path`` is a file, lies under a file, or is read-only.
    """
    final = Path(os.path.realpath(path))  # a symlink to a folder: replace the folder, keep the link
    try:
        _check_target(final, folder=True)
        final.parent.mkdir(parents=True, exist_ok=True)
        # a shortened name's leftovers are left by recover_folder (whose they are is not known there)
        _recover(final, beside=recover or _short(final.name) != final.name)
    except OSError as exc:
        raise _refuse(final, exc, "the output folder") from None
    if final.is_dir() and not os.access(final, os.W_OK | os.X_OK):
        raise EaseError(f"{path}: the output folder is read-only")
    in_place = _in_place(final)
    tag = _new_tag()
    tmp = (final if in_place else final.parent) / _temp_name(final.name, "tmp", tag)
    try:
        os.mkdir(tmp, 0o700)
    except OSError as exc:
        raise _refuse(final, exc, "the output folder") from None
    try:
        yield tmp  # the writers' own errors pass through unchanged
        try:
            _fix_modes(tmp)
            (_commit_in_place if in_place else _commit)(tmp, final, tag)
        except OSError as exc:
            raise _refuse(final, exc, "the output folder") from None
    finally:
        _remove(tmp)


def _commit(tmp: Path, final: Path, tag: str) -> None:
    old_mode = final.stat().st_mode & 0o7777 if final.is_dir() else 0o777 & ~_umask()
    if final.is_dir():
        _carry_over(final, tmp)
    os.chmod(tmp, old_mode)
    aside = None
    with signals_held():
        if not final.is_dir():
            os.rename(tmp, final)
        elif not _exchange(tmp, final):
            aside = final.parent / _temp_name(final.name, "old", tag)
            os.rename(final, aside)  # the next run puts it back if killed right here
            try:
                os.rename(tmp, final)
            except OSError:
                os.rename(aside, final)
                raise
        with _lock:
            _committed.append(final)
    # the old folder is at tmp (exchanged) or aside (two renames): removed here or by
    # the caller's finally, else by the next run when this process is killed first
    if aside is not None:
        _remove(aside)


def _commit_in_place(tmp: Path, final: Path, tag: str) -> None:
    for entry in os.scandir(tmp):
        dst = final / entry.name
        if entry.is_dir(follow_symlinks=False) and dst.is_dir() and not dst.is_symlink():
            _carry_over(dst, Path(entry.path), top=False)
    new = final / _temp_name(final.name, "new", tag)
    with signals_held():
        os.rename(tmp, new)  # the commit point: from here on the next run completes the swap
        _swap_entries(new, final, final / _temp_name(final.name, "old", tag))
        with _lock:
            _committed.append(final)
