"""Outputs are all-old or all-new (issue 15): faults at every step, SIGINT and SIGKILL at random times.

Three kinds of generated cases:

* in-process: :func:`core.fileio.output_dir` with a failure injected at every
  system call it makes (and at every file of the writer), for each swap mode
  (one-rename exchange, the two-rename fallback, the in-place swap of a mount
  point) and each kind of old folder;
* a child process committing version after version through ``output_dir``,
  killed (SIGKILL) or interrupted (SIGINT) at seeded random times;
* the real commands (``ease export``, ``ease drape``, ``ease pattern``) killed
  or interrupted at seeded random times around their writing phase.

Each checks that the folder holds exactly the old set of files or exactly the
new one (by content hash) and that no temporary entry is left after the next
run. ``pytest --full`` runs every case; CI a seeded sample.
"""

import hashlib
import itertools
import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import sample

import core.fileio as F
from core.errors import EaseError
from core.fileio import output_dir, write_text

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable


#: Report entries that are wall-clock times (they differ run to run).
WALL_CLOCK = {"timings", "optimize_seconds", "init_seconds", "seconds"}


def _content(p: Path) -> bytes:
    """The bytes that identify a run's file: JSON without wall-clock times; a DXF as the
    multiset of its lines (ezdxf's plain DXF orders two objects differently run to run)."""
    data = p.read_bytes()
    if p.suffix == ".json":

        def strip(o):
            if isinstance(o, dict):
                return {k: strip(v) for k, v in o.items() if k not in WALL_CLOCK}
            return [strip(v) for v in o] if isinstance(o, list) else o

        return json.dumps(strip(json.loads(data)), sort_keys=True).encode()
    if p.suffix == ".dxf":
        return b"\n".join(sorted(data.splitlines()))
    return data


def tree(folder: Path) -> dict:
    """relative path -> sha256 of every file (``/`` for a folder) under ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        out[rel] = "/" if p.is_dir() and not p.is_symlink() else hashlib.sha256(_content(p)).hexdigest()
    return out


def temps(*folders: Path) -> list:
    """EASE temporary entries in ``folders`` (beside and inside an output)."""
    return sorted(str(f / n) for f in folders if f.is_dir() for n in os.listdir(f) if F._TEMP.match(n))


# ----------------------------------------------------------------------------- in-process faults

FILES = ("a.json", "b.png", "sub/c.txt", "d.bin")

OLD_STATES = {
    "none": {},
    "older": {"a.json": "old a", "b.png": "old b", "sub/c.txt": "old c", "keep.txt": "kept", "sub/old.txt": "o"},
    "png is a folder": {"a.json": "old a", "b.png/inner.txt": "in", "keep.txt": "kept"},
    "sub is a file": {"sub": "a file", "keep.txt": "kept"},
}


def _fill(folder: Path, files: dict) -> None:
    for rel, text in files.items():
        p = folder / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)


def _write_new(d: Path, fail_at=None) -> None:
    for i, rel in enumerate(FILES):
        if fail_at == i:
            raise RuntimeError(f"writer failed at file {i}")
        write_text(d / rel, f"new {rel}")


def _expected_new(old: dict) -> dict:
    """What a successful run leaves: its own files win, old ones it did not write are kept."""
    new = {rel: f"new {rel}" for rel in FILES}
    ours = list(new)
    for rel, text in old.items():
        if not any(n == rel or n.startswith(rel + "/") or rel.startswith(n + "/") for n in ours):
            new[rel] = text
    return new


def _texts(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_text() for p in folder.rglob("*") if p.is_file()}


class Faults:
    """Make the ``at``-th call (counting from 0) of the patched system calls raise OSError."""

    CALLS = ("rename", "replace", "link", "mkdir", "chmod", "open")

    def __init__(self, monkeypatch, at=None):
        self.n, self.at = 0, at
        for name in self.CALLS:
            monkeypatch.setattr(os, name, self._wrap(getattr(os, name)))
        real_exchange, real_remove = F._exchange, F._remove
        monkeypatch.setattr(F, "_exchange", lambda a, b: self._count() or real_exchange(a, b))
        # removing temporaries is not faulted here: a removal that fails leaves a temporary
        # for the next run (a later process) to remove, which the killed-child cases check
        monkeypatch.setattr(F, "_remove", lambda path: self._paused(real_remove, path))
        self.paused = False

    def _paused(self, func, *args):
        self.paused = True
        try:
            return func(*args)
        finally:
            self.paused = False

    def _count(self):
        if self.paused:
            return False
        self.n += 1
        if self.at is not None and self.n - 1 == self.at:
            raise OSError(5, "injected I/O error")
        return False

    def _wrap(self, func):
        def call(*args, **kwargs):
            self._count()
            return func(*args, **kwargs)

        return call


MODES = ("exchange", "two renames", "in place")


def _mode(monkeypatch, mode):
    if mode == "two renames":
        monkeypatch.setattr(F, "_exchange", lambda a, b: False)
    elif mode == "in place":
        monkeypatch.setattr(F, "_in_place", lambda final: final.is_dir())


def _run(tmp_path, monkeypatch, mode, state, at=None, writer_fail=None):
    out = tmp_path / "out"
    if OLD_STATES[state]:
        _fill(out, OLD_STATES[state])
    _mode(monkeypatch, mode)
    faults = Faults(monkeypatch, at)
    error = None
    try:
        with output_dir(out) as d:
            _write_new(d, writer_fail)
    except (EaseError, RuntimeError) as exc:
        error = exc
    monkeypatch.undo()
    return out, faults.n, error


def _count_calls(mode, state, tmp_path_factory):
    mp = pytest.MonkeyPatch()
    _, n, error = _run(tmp_path_factory.mktemp("count"), mp, mode, state)
    assert error is None
    return n


# every (mode, old folder, failing call) up to a generous bound; cases past a
# run's last call are the clean run
FAULT_CASES = [(m, s, k) for m in MODES for s in OLD_STATES for k in range(48)]


@pytest.mark.parametrize("case", sample(FAULT_CASES, 60, seed=15), ids=str)
def test_a_fault_at_any_step_leaves_the_old_folder(tmp_path, monkeypatch, case):
    mode, state, at = case
    out, calls, error = _run(tmp_path, monkeypatch, mode, state, at=at)
    old = OLD_STATES[state]
    if error is None:  # no fault reached, or one a caller may ignore (mkdir of an existing folder)
        assert _texts(out) == _expected_new(old)
    else:
        assert at < calls and isinstance(error, EaseError) and "injected I/O error" in str(error), error
        assert (_texts(out) if out.exists() else {}) == old
    assert temps(tmp_path, out) == []


WRITER_CASES = [(m, s, k) for m in MODES for s in OLD_STATES for k in range(len(FILES) + 1)]


@pytest.mark.parametrize("case", sample(WRITER_CASES, 20, seed=16), ids=str)
def test_a_failing_writer_leaves_the_old_folder(tmp_path, monkeypatch, case):
    mode, state, fail = case
    out, _, error = _run(tmp_path, monkeypatch, mode, state, writer_fail=fail)
    old = OLD_STATES[state]
    if fail == len(FILES):
        assert error is None and _texts(out) == _expected_new(old)
    else:
        assert isinstance(error, RuntimeError)  # the writer's own error, unchanged
        assert (_texts(out) if out.exists() else {}) == old
    assert temps(tmp_path, out) == []


def test_fault_cases_reach_every_call(tmp_path_factory):
    # the generated fault range covers each mode's whole run (else raise the bound above)
    for mode in MODES:
        for state in OLD_STATES:
            assert _count_calls(mode, state, tmp_path_factory) < 48, (mode, state)


# ----------------------------------------------------------------------------- recovery, naming, modes


def _dead_pid() -> int:
    p = subprocess.Popen([PY, "-c", "pass"])
    p.wait()
    return p.pid


def test_killed_runs_are_cleaned_and_the_two_rename_gap_recovered(tmp_path):
    out = tmp_path / "out"
    _fill(out, {"a.json": "old"})
    pid = _dead_pid()
    # killed between the two renames of the fallback: the folder is away under its old name
    os.rename(out, tmp_path / f".out.ease-old-{pid}-ab12")
    _fill(tmp_path / f".out.ease-tmp-{pid}-ab12", {"a.json": "half"})
    _fill(tmp_path / f".out.ease-tmp-{pid}-cd34", {"x": "stale"})
    live = tmp_path / f".out.ease-tmp-{os.getpid()}-ef56"  # a live run's: left alone
    live.mkdir()
    with output_dir(out) as d:
        write_text(d / "b.json", "new")
    assert _texts(out) == {"a.json": "old", "b.json": "new"}
    assert temps(tmp_path, out) == [str(live)]


def test_a_folders_leftovers_are_recovered_with_one_listing(tmp_path, monkeypatch):
    """recover_folder clears what killed runs left beside every entry (a batch's items folder, once);
    output_dir(recover=False) then writes without listing that folder again."""
    from core import fileio

    pid = _dead_pid()
    _fill(tmp_path / "a", {"x": "old a"})
    os.rename(tmp_path / "a", tmp_path / f".a.ease-old-{pid}-ab12")  # a's two-rename gap
    _fill(tmp_path / f".a.ease-tmp-{pid}-ab12", {"x": "half"})
    _fill(tmp_path / f".b.ease-tmp-{pid}-cd34", {"x": "half"})
    _fill(tmp_path / "c", {"x": "c"})
    live = tmp_path / f".d.ease-tmp-{os.getpid()}-ef56"  # a live run's: left alone
    live.mkdir()
    fileio.recover_folder(tmp_path)
    assert _texts(tmp_path / "a") == {"x": "old a"} and _texts(tmp_path / "c") == {"x": "c"}
    assert sorted(os.listdir(tmp_path)) == sorted(["a", "c", live.name])
    listed = []
    real = os.listdir
    monkeypatch.setattr(fileio.os, "listdir", lambda p=".": listed.append(Path(p)) or real(p))
    with output_dir(tmp_path / "e", recover=False) as d:
        write_text(d / "y", "e")
    assert _texts(tmp_path / "e") == {"y": "e"} and tmp_path not in listed
    with output_dir(tmp_path / "f") as d:  # by default it looks beside its target itself
        write_text(d / "y", "f")
    assert tmp_path in listed


def test_a_long_names_leftovers_are_recovered_without_recover_folder(tmp_path):
    """recover_folder leaves a temporary whose name was shortened (it cannot tell whose it is);
    output_dir(recover=False) of that name then looks beside its target itself."""
    from core import fileio

    pid, name = _dead_pid(), "n" * (F._NAME_MAX + 10)
    _fill(tmp_path / F._temp_name(name, "old", f"{pid}-ab12"), {"keep": "old"})  # its two-rename gap
    fileio.recover_folder(tmp_path)
    with output_dir(tmp_path / name, recover=False) as d:
        write_text(d / "y", "new")
    assert _texts(tmp_path / name) == {"keep": "old", "y": "new"} and temps(tmp_path) == []


def test_long_names_that_share_their_start_keep_their_own_leftovers(tmp_path):
    """Temporaries carry a long name shortened; two names alike in their first 200 characters must
    not take each other's: y's old folder (a two-rename gap) is put back for y, not for x."""
    pid = _dead_pid()
    x, y = "n" * F._NAME_MAX + "x", "n" * F._NAME_MAX + "y"
    with output_dir(tmp_path / y) as d:
        write_text(d / "a", "y")
    os.rename(tmp_path / y, tmp_path / F._temp_name(y, "old", f"{pid}-ab12"))
    with output_dir(tmp_path / x) as d:
        write_text(d / "b", "x")
    assert _texts(tmp_path / x) == {"b": "x"}
    with output_dir(tmp_path / y) as d:
        write_text(d / "c", "y")
    assert _texts(tmp_path / y) == {"a": "y", "c": "y"} and temps(tmp_path) == []


def test_a_name_long_in_bytes_is_written(tmp_path):
    """A name of 80 three-byte characters (240 bytes of the 255 a file name may have) is written:
    its temporaries' names are cut to bytes, not characters."""
    name = "\u00e9\u4e2d" * 48  # 96 characters, 240 bytes
    write_text(tmp_path / name, "a")
    with output_dir(tmp_path / (name + "d")) as d:
        write_text(d / name, "b")
    assert (tmp_path / name).read_text() == "a" and (tmp_path / (name + "d") / name).read_text() == "b"
    assert temps(tmp_path, tmp_path / (name + "d")) == []


def test_in_place_swap_killed_midway_is_completed_by_the_next_run(tmp_path):
    out = tmp_path / "out"
    _fill(out, {"a": "old a", "b": "old b", "keep": "k"})
    pid = _dead_pid()
    # killed after moving "a" in: "a" new, "b" old, the rest of the new folder still staged
    new, old = out / f".out.ease-new-{pid}-0a0a", out / f".out.ease-old-{pid}-0a0a"
    _fill(new, {"b": "new b"})
    _fill(old, {"a": "old a"})
    (out / "a").write_text("new a")
    with output_dir(out) as d:
        write_text(d / "c", "c")
    assert _texts(out) == {"a": "new a", "b": "new b", "c": "c", "keep": "k"}
    assert temps(tmp_path, out) == []


def test_single_file_temp_of_a_killed_write_is_removed(tmp_path):
    pid = _dead_pid()
    stale = tmp_path / f".body.obj.ease-tmp-{pid}-9f9f"
    stale.write_text("half a body")
    F.write_text(tmp_path / "body.obj", "v 0 0 0\n")
    assert sorted(os.listdir(tmp_path)) == ["body.obj"]


def test_symlinked_output_keeps_the_link_and_the_folder_mode(tmp_path):
    real = tmp_path / "real"
    _fill(real, {"a": "old"})
    os.chmod(real, 0o750)
    (tmp_path / "link").symlink_to(real)
    with output_dir(tmp_path / "link") as d:
        write_text(d / "a", "new")
    assert (tmp_path / "link").is_symlink() and _texts(real) == {"a": "new"}
    assert os.stat(real).st_mode & 0o777 == 0o750


def test_the_working_directory_is_swapped_in_place(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _fill(out, {"a": "old"})
    monkeypatch.chdir(out)
    with output_dir(".") as d:
        write_text(d / "a", "new")
    assert Path("a").read_text() == "new" and Path.cwd() == out


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda p: p.write_text("x"), "is a file; expected an output folder"),
        (lambda p: p.parent.joinpath("f").write_text("x") or None, "is a file, not a folder"),
    ],
)
def test_unwritable_targets_are_one_clear_error(tmp_path, make, match):
    target = tmp_path / "out"
    make(target)
    if not target.exists():
        target = tmp_path / "f" / "sub"
    with pytest.raises(EaseError, match=match):
        with output_dir(target):
            pass
    with pytest.raises(EaseError, match="is a folder; expected a file name"):
        F.write_text(tmp_path, "x")


# ----------------------------------------------------------------------------- killed child processes

CHILD = r"""
import os, sys, time
import core.fileio as F
mode, delay, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]
if mode == "two renames":
    F._exchange = lambda a, b: False
elif mode == "in place":
    F._in_place = lambda final: final.is_dir()
for name in ("rename", "link", "mkdir", "replace"):
    def slow(*a, _f=getattr(os, name), **k):
        time.sleep(delay)
        return _f(*a, **k)
    setattr(os, name, slow)
print("ready", flush=True)
try:
    for version in range(1, 10**6):
        with F.output_dir(out) as d:
            for i in range(6):
                F.write_text(os.path.join(d, f"f{{i}}.txt" if i < 4 else f"s/f{{i}}.txt"), f"v{{version}} f{{i}}")
except KeyboardInterrupt:
    sys.exit(130)
"""

KILL_CASES = [(m, sig, seed) for m in MODES for sig in ("KILL", "INT") for seed in range(40)]


@pytest.mark.parametrize("case", sample(KILL_CASES, 12, seed=17), ids=str)
def test_killed_while_committing_version_after_version(tmp_path, case):
    mode, sig, seed = case
    out = tmp_path / "out"
    _fill(out, {"keep.txt": "kept"})
    script = tmp_path / "child.py"
    script.write_text(CHILD.format())
    child = subprocess.Popen([PY, str(script), mode, "0.001", str(out)], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "ready"
    time.sleep(random.Random(seed).uniform(0.05, 0.4))
    child.send_signal(getattr(signal, f"SIG{sig}"))
    child.wait(timeout=60)
    # a SIGKILL between the steps of a swap that is not one rename leaves it for the next run to finish:
    # in place (a mount point) inside the per-entry swap, with two renames between them (the old folder
    # moved aside, the new one not yet in)
    later = mode in ("in place", "two renames") and sig == "KILL"
    if not later:
        _one_version(out)
    before = tree(out)
    with output_dir(out):  # the next run
        pass
    assert (tree(out) == before or later) and temps(tmp_path, out) == []
    _one_version(out)


def _one_version(out: Path) -> None:
    files = _texts(out)
    assert files.pop("keep.txt") == "kept"
    versions = {text.split()[0] for text in files.values()}
    assert len(versions) <= 1, files  # never a mix of two versions
    if versions:
        v = versions.pop()
        assert files == {f"{'s/' if i >= 4 else ''}f{i}.txt": f"{v} f{i}" for i in range(6)}


# ----------------------------------------------------------------------------- real commands

CLI_CHILD = r"""
import contextlib, os, sys, time
import core.fileio as F
delay = float(os.environ["EASE_TEST_DELAY"])
for name in ("rename", "link", "mkdir", "replace"):
    def slow(*a, _f=getattr(os, name), **k):
        time.sleep(delay)
        return _f(*a, **k)
    setattr(os, name, slow)
_output_dir = F.output_dir
@contextlib.contextmanager
def marked(path):
    with _output_dir(path) as d:
        print("writing", flush=True)
        yield d
F.output_dir = marked
from core.cli import main
sys.exit(main(sys.argv[1:]))
"""


class Commands:
    """The synthetic pattern, its drape, the child script and, made on first use, the two
    known outputs (old, new) of each command."""

    def __init__(self, base: Path):
        from drape_synth import tube_skirt

        from core.cli import main
        from core.pattern.io import save_pattern

        self.base = base
        save_pattern(tube_skirt(1.2, n_rows=8, n_cols=10), base / "pattern")
        self.script = base / "child.py"
        self.script.write_text(CLI_CHILD.format())
        assert (
            main(
                [
                    "drape",
                    str(base / "pattern"),
                    "--out",
                    str(base / "drape"),
                    "--quiet",
                    "--frames",
                    "2",
                    "--no-preview",
                ]
            )
            == 0
        )
        shirt = ROOT / "core" / "data" / "designs" / "top_sleeveless.json"
        self.commands = {
            "export": (
                ["export", str(base / "pattern"), "--quiet", "--format", "all", "--drape", str(base / "drape")],
                ["--allowance", "0.01"],
                ["--allowance", "0.015"],
            ),
            "drape": (
                ["drape", str(base / "pattern"), "--quiet", "--no-preview"],
                ["--frames", "2"],
                ["--frames", "3"],
            ),
            "pattern": (["pattern", str(shirt), "--quiet"], ["--iterations", "2"], ["--iterations", "3"]),
        }
        self.known = {}

    def get(self, name):
        """(argv, old options, new options, old folder, new folder, write-phase seconds)."""
        if name not in self.known:
            argv, a, b = self.commands[name]
            refs, took = [], 0.0
            for opt in (a, b):
                ref = self.base / f"ref_{name}_{opt[-1]}"
                rc, t = _child(self.script, argv + opt + ["--out", str(ref)], self.base, wait_for_exit=True)
                assert rc == 0
                refs.append(ref)
                took = max(took, t)
            assert tree(refs[0]) != tree(refs[1]) and set(tree(refs[0])) == set(tree(refs[1]))
            self.known[name] = (argv, a, b, refs[0], refs[1], took)
        return self.known[name]


@pytest.fixture(scope="module")
def commands(tmp_path_factory):
    return Commands(tmp_path_factory.mktemp("cli"))


def _child(script, argv, cwd, wait_for_exit=False, signal_after=None, sig=None):
    env = dict(os.environ, EASE_TEST_DELAY="0.004", PYTHONPATH=str(ROOT / "tests" / "helpers"))
    p = subprocess.Popen(
        [PY, str(script), *argv], cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    line = p.stdout.readline()
    t0 = time.perf_counter()
    if signal_after is not None and line.strip() == "writing":
        time.sleep(signal_after)
        p.send_signal(sig)
    out, err = p.communicate(timeout=600)
    took = time.perf_counter() - t0
    if wait_for_exit:
        return p.returncode, took
    return p.returncode, err


CLI_CASES = [(c, sig, seed) for c in ("export", "drape", "pattern") for sig in ("INT", "KILL") for seed in range(30)]
#: CI cases per (command, signal): export by both signals, drape by Ctrl-C (a kill is the same commit as
#: export's); pattern (a real cut and solve) and the rest: --full only
CLI_CI = {("export", "INT"): 1, ("export", "KILL"): 1, ("drape", "INT"): 1}


def _cli_sample():
    picked = []
    for k, (c, sig) in enumerate(itertools.product(("export", "drape", "pattern"), ("INT", "KILL"))):
        # a seed of its own per group: the strikes fall at other moments of the write
        picked += sample([x for x in CLI_CASES if x[:2] == (c, sig)], CLI_CI.get((c, sig), 0), seed=18 + k)
    return picked


@pytest.mark.parametrize("case", _cli_sample(), ids=str)
def test_interrupted_command_leaves_all_old_or_all_new(commands, tmp_path, case):
    command, sig, seed = case
    import shutil

    argv, old_opt, new_opt, old_ref, new_ref, window = commands.get(command)
    old_tree, new_tree = tree(old_ref), tree(new_ref)
    out = tmp_path / "out"
    shutil.copytree(old_ref, out)  # what the old run wrote
    # the write phase (marker -> exit) of this command takes `window` seconds: strike anywhere in it
    after = random.Random(seed).uniform(0.0, 1.2 * window)
    rc, err = _child(
        commands.script,
        argv + new_opt + ["--out", str(out)],
        commands.base,
        signal_after=after,
        sig=getattr(signal, f"SIG{sig}"),
    )
    now = tree(out)
    assert now in (old_tree, new_tree), (
        rc,
        err,
        {k: (v == old_tree.get(k), v == new_tree.get(k)) for k, v in now.items() if v != new_tree.get(k)},
    )
    said = [line for line in err.splitlines() if line.startswith("ease ")]
    if rc == 0:
        assert now == new_tree and "Traceback" not in err, err
    elif rc == 130:
        assert len(said) == 1 and "Traceback" not in err, err
        assert ("nothing was written" in said[0]) == (now == old_tree), err
    elif rc == -signal.SIGINT:
        # Ctrl-C after the command had returned (interpreter shutdown): it had written everything
        assert now == new_tree and not said, err
    else:
        assert sig == "KILL" and rc == -signal.SIGKILL, (rc, err)
    with output_dir(out):  # the next run
        pass
    assert tree(out) == now and temps(tmp_path, out) == []


# ----------------------------------------------------------------------------- mount points, read-only


def _in_mount_namespace(cmd: str, tmp_path):
    """Run ``cmd`` (sh) in a private mount namespace; skip where that is not allowed."""
    probe = subprocess.run(["unshare", "-m", "true"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("no private mount namespace here (needs unshare -m: root or user namespaces)")
    env = dict(os.environ, PYTHONPATH=f"{ROOT}:{ROOT / 'tests' / 'helpers'}")
    return subprocess.run(
        ["unshare", "-m", "sh", "-c", cmd], capture_output=True, text=True, cwd=tmp_path, env=env, timeout=300
    )


def test_out_on_a_mount_point_and_on_a_read_only_folder(commands, tmp_path):
    argv, old_opt, new_opt, _, new_ref, _ = commands.get("export")
    mnt, ro, copy = tmp_path / "mnt", tmp_path / "ro", tmp_path / "copy"
    mnt.mkdir(), ro.mkdir()
    cli, args = f"{PY} -m core.cli", " ".join(argv)
    script = (
        f"mount -t tmpfs none {mnt} && mount -t tmpfs -o ro none {ro} && "
        f"{cli} {args} {' '.join(old_opt)} --out {mnt} && echo kept > {mnt}/keep.txt && "
        f"{cli} {args} {' '.join(new_opt)} --out {mnt} && cp -a {mnt} {copy} && "
        f"{cli} {args} --out {ro}; echo rc=$?"
    )
    res = _in_mount_namespace(script, tmp_path)
    assert res.stdout.strip().endswith("rc=2"), res.stdout + res.stderr
    err = [line for line in res.stderr.splitlines() if line.startswith("ease ")]
    assert len(err) == 1 and "read-only" in err[0] and "Traceback" not in res.stderr, res.stderr
    now = tree(copy)
    assert now.pop("keep.txt") and now == tree(new_ref) and temps(copy) == []


@pytest.mark.parametrize(
    "argv, match",
    [
        (["export", "PATTERN", "--out", "FILE"], "is a file; expected an output folder"),
        (["drape", "PATTERN", "--out", "FILE/sub"], "is a file, not a folder"),
        (["pattern", "DESIGN", "--out", "FILE"], "is a file; expected an output folder"),
        (["body", "--out", "DIR"], "is a folder; expected a file name"),
        (["body", "--all", "--out", "FILE"], "is a file; expected an output folder"),
    ],
)
def test_bad_out_is_one_line_before_any_work(commands, tmp_path, argv, match):
    base = commands.base
    (tmp_path / "FILE").write_text("x")
    (tmp_path / "DIR").mkdir()
    subst = {"PATTERN": str(base / "pattern"), "DESIGN": str(ROOT / "core/data/designs/skirt.json")}
    argv = [subst.get(a, str(tmp_path / a) if a in ("FILE", "FILE/sub", "DIR") else a) for a in argv]
    res = subprocess.run([PY, "-m", "core.cli", *argv], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and match in res.stderr, res.stderr
