"""core.fileio: atomic writes and output folders that never leave half-written files."""

import os
import stat

import numpy as np
import pytest

from core.fileio import dumps_json, output_dir, write_bytes, write_json, write_text


def _mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def test_write_replaces_whole_file_and_leaves_no_temp(tmp_path):
    p = tmp_path / "sub" / "a.txt"
    write_text(p, "first")
    write_text(p, "second")
    assert p.read_text() == "second"
    assert sorted(x.name for x in p.parent.iterdir()) == ["a.txt"]


def test_written_files_follow_the_umask_not_owner_only(tmp_path, umask_022):
    p = write_bytes(tmp_path / "piece.svg", b"<svg/>")
    assert _mode(p) == 0o644
    with output_dir(tmp_path / "out") as d:
        write_text(d / "x.json", "{}")
        fd = os.open(d / "private.bin", os.O_CREAT | os.O_WRONLY, 0o600)  # e.g. a mkstemp'd file
        os.close(fd)
    assert _mode(tmp_path / "out" / "x.json") == 0o644
    assert _mode(tmp_path / "out" / "private.bin") == 0o644


def test_failed_write_keeps_the_old_file(tmp_path):
    p = tmp_path / "report.json"
    write_json(p, {"ok": 1})
    with pytest.raises(ValueError):
        write_json(p, {"bad": float("nan")})  # NaN is not JSON: nothing written
    assert p.read_text().strip() == '{\n "ok": 1\n}'
    assert [x.name for x in tmp_path.iterdir()] == ["report.json"]


def test_output_dir_is_all_or_nothing(tmp_path):
    out = tmp_path / "pattern"
    with output_dir(out) as d:
        write_text(d / "pattern.json", "v1")
        write_text(d / "keep.txt", "kept")
    with pytest.raises(RuntimeError):
        with output_dir(out) as d:
            write_text(d / "pattern.json", "v2")
            raise RuntimeError("solver failed")
    assert (out / "pattern.json").read_text() == "v1"
    with output_dir(out) as d:
        (d / "plots").mkdir()
        write_text(d / "plots" / "p.txt", "p")
        write_text(d / "pattern.json", "v3")
    assert (out / "pattern.json").read_text() == "v3"
    assert (out / "keep.txt").read_text() == "kept"  # files the run did not write stay
    assert (out / "plots" / "p.txt").read_text() == "p"
    assert not [x for x in tmp_path.iterdir() if x.name.endswith(".tmp")]


def test_json_of_numpy_values():
    s = dumps_json({"a": np.arange(3), "b": np.float32(0.5), "c": np.int64(2), "d": np.bool_(True)}, indent=None)
    assert s == '{"a": [0, 1, 2], "b": 0.5, "c": 2, "d": true}'
    with pytest.raises(TypeError, match="not JSON serialisable: object"):
        dumps_json({"x": object()})


def test_only_the_temporaries_of_the_name_written_are_removed(tmp_path):
    # the listing is filtered by the name's prefix before the pattern: names that share a prefix
    # with the one written (".out2", ".out.x"), or a dead run's temporary inside another name's, stay
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    dead = child.pid
    mine = [f".out.ease-tmp-{dead}-ab12", f".out.ease-old-{dead}-cd34"]
    others = [
        f".out2.ease-tmp-{dead}-ab12",
        f".out.x.ease-tmp-{dead}-ab12",
        f".o.ease-tmp-{dead}-ab12",
        f".out.ease-tmp-{dead}-ab12.ease-tmp-{dead}-ef56",
        "out.ease-tmp-1-ab12",
    ]
    for name in mine + others:
        (tmp_path / name).mkdir()
    with output_dir(tmp_path / "out") as d:
        write_text(d / "a.json", "{}")
    assert sorted(os.listdir(tmp_path)) == sorted(others + ["out"])


def test_a_file_under_a_file_is_one_clear_error(tmp_path):
    from core.errors import EaseError

    (tmp_path / "f").write_text("x")
    for target in (tmp_path / "f" / "a.json", tmp_path / "f" / "sub" / "a.json"):
        with pytest.raises(EaseError, match="f is a file, not a folder"):
            write_text(target, "{}")
    write_text(tmp_path / "new" / "sub" / "a.json", "{}")  # missing folders are made
    assert (tmp_path / "new" / "sub" / "a.json").read_text() == "{}"


def test_large_files_leave_the_page_cache_once_on_disk(tmp_path, monkeypatch):
    """A written file of UNCACHE_BYTES or more is fsync'ed, then its cached pages dropped (the next
    file reuses them); a small one keeps them. Both read back whole."""
    import os

    from core import fileio

    if not hasattr(os, "posix_fadvise"):
        pytest.skip("no posix_fadvise on this platform")
    calls = []
    real = os.posix_fadvise
    monkeypatch.setattr(
        fileio.os, "posix_fadvise", lambda fd, off, n, advice: calls.append(advice) or real(fd, off, n, advice)
    )
    big, small = b"x" * fileio.UNCACHE_BYTES, b"y" * 100
    write_bytes(tmp_path / "big.bin", big)
    assert calls == [os.POSIX_FADV_DONTNEED]
    write_bytes(tmp_path / "small.bin", small)
    assert calls == [os.POSIX_FADV_DONTNEED]
    assert (tmp_path / "big.bin").read_bytes() == big and (tmp_path / "small.bin").read_bytes() == small


def test_a_folder_that_cannot_be_searched_is_one_clear_error(tmp_path, monkeypatch):
    """A PermissionError while checking the target (a folder on the way without search permission; root
    cannot make one, so the check is made to meet it) is an EaseError naming the path, not a traceback."""
    from pathlib import Path

    from core.errors import EaseError
    from core.fileio import check_output

    real = Path.is_dir

    def refusing(self):
        if self.name == "locked":
            raise PermissionError(13, "Permission denied", str(self))
        return real(self)

    monkeypatch.setattr(Path, "is_dir", refusing)
    for make in (lambda p: check_output(p), lambda p: output_dir(p).__enter__()):
        with pytest.raises(EaseError, match="locked.*Permission denied"):
            make(tmp_path / "locked" / "out")
