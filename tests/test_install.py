"""The installed wheel works outside a source checkout.

Builds the wheel of the working tree offline, installs it into a fresh
virtual environment (no editable install: the checkout's dependencies are
borrowed through a ``.pth`` to its site-packages, whose own ``.pth`` files,
the editable finder among them, are not read), and runs ``ease`` from a
folder outside the checkout: the templates and the body model come from
package data, nothing written or listed points into the checkout, and the
Warp kernel cache goes to the user's cache folder.
"""

import os
import shutil
import site
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _can_build_wheels() -> bool:
    # setuptools >= 70.1 builds wheels by itself; older ones need the `wheel` package
    try:
        import setuptools
    except ImportError:
        return False
    major, minor = (int(x) for x in setuptools.__version__.split(".")[:2])
    if (major, minor) >= (70, 1):
        return True
    try:
        import wheel  # noqa: F401

        return True
    except ImportError:
        return False


pytestmark = pytest.mark.skipif(not _can_build_wheels(), reason="setuptools >= 70.1 (or wheel) needed offline")


def _run(cmd, cwd, env, timeout=300):
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, f"{cmd} failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-4000:]}"
    return r.stdout


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(ease executable, venv python, environment, working folder outside the checkout)."""
    tmp = tmp_path_factory.mktemp("install")
    src = tmp / "src"
    src.mkdir()
    shutil.copy2(ROOT / "pyproject.toml", src)
    shutil.copytree(ROOT / "core", src / "core", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "WARP_CACHE_PATH", "EASE_BENCH_DIR")}
    env["XDG_CACHE_HOME"] = str(tmp / "xdg")
    _run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "-q",
            "-w",
            str(tmp / "dist"),
            str(src),
        ],
        tmp,
        env,
    )
    wheel = next((tmp / "dist").glob("ease_garments-*.whl"))

    venv = tmp / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp, env)
    py = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    purelib = Path(_run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], tmp, env).strip())
    # the checkout's dependencies (numpy, scipy, warp ...), not its editable install of core
    deps = [p for p in site.getsitepackages() + [sysconfig.get_paths()["purelib"]] if Path(p).is_dir()]
    (purelib / "ease_checkout_deps.pth").write_text("\n".join(dict.fromkeys(deps)) + "\n")
    _run(
        [sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index", "-q", str(wheel)],
        tmp,
        env,
    )
    ease = venv / ("Scripts/ease.exe" if os.name == "nt" else "bin/ease")
    work = tmp / "work"
    work.mkdir()
    return ease, py, env, work, purelib


def _outside_checkout(text: str) -> None:
    assert str(ROOT) not in text, f"a path into the checkout {ROOT}: {text[:2000]}"


def test_core_is_the_installed_one(installed):
    ease, py, env, work, purelib = installed
    where = _run([str(py), "-c", "import core; print(core.__file__)"], work, env).strip()
    assert Path(where).is_relative_to(purelib), where


def test_help_and_templates_from_package_data(installed):
    ease, py, env, work, purelib = installed
    assert "templates" in _run([str(ease), "--help"], work, env)
    listing = _run([str(ease), "templates"], work, env)
    _outside_checkout(listing)
    paths = [Path(line.split()[1]) for line in listing.splitlines()]
    assert len(paths) >= 10 and all(p.is_file() and p.is_relative_to(purelib) for p in paths)


def test_pattern_of_a_template_outside_the_checkout(installed):
    ease, py, env, work, purelib = installed
    design = _run(
        [str(py), "-c", "from core.design.templates import template_path; print(template_path('top_sleeveless'))"],
        work,
        env,
    ).strip()
    out = _run([str(ease), "pattern", design, "--out", "pattern", "--quiet"], work, env)
    assert out.startswith("reference:")
    for name in ("pattern.json", "report.json", "pattern.png"):
        assert (work / "pattern" / name).is_file()
    _outside_checkout((work / "pattern" / "pattern.json").read_text())
    _outside_checkout((work / "pattern" / "report.json").read_text())


def test_bench_needs_a_checkout(installed):
    ease, py, env, work, purelib = installed
    r = subprocess.run([str(ease), "bench"], cwd=work, env=env, capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.startswith("ease bench: error:") and r.stderr.count("\n") == 1


def test_warp_cache_in_the_user_cache(installed):
    ease, py, env, work, purelib = installed
    code = (
        "import os; from core.paths import default_warp_cache; default_warp_cache(); "
        "import core.drape.kernels; print(os.environ['WARP_CACHE_PATH'])"
    )
    cache = Path(_run([str(py), "-c", code], work, env).strip().splitlines()[-1])
    assert cache == Path(env["XDG_CACHE_HOME"]) / "ease" / "warp"
    code = "import os, core.drape.kernels; print(os.environ['WARP_CACHE_PATH'])"
    cache = Path(_run([str(py), "-c", code], work, env).strip().splitlines()[-1])
    assert (
        not cache.is_relative_to(purelib.parent.parent.parent)
        and cache == Path(env["XDG_CACHE_HOME"]) / "ease" / "warp"
    )
