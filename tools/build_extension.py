#!/usr/bin/env python3
"""Build the EASE Blender extension zip(s) with the core's wheels bundled.

    python tools/build_extension.py --out ~/ease-dist                        # one zip per platform
    python tools/build_extension.py --platform linux-x64 --out ~/ease-dist   # Linux x64 only

Steps: download the binary wheels of the core's dependencies for each
platform (``pip download --only-binary=:all: --platform ... --python-version
3.11``; pins from ``requirements.txt``; cached in ``.cache/wheels``); drop
numpy (Blender ships its own); stage the extension (``__init__.py``,
``blender_manifest.toml``, ``ease_addon/``, ``core/`` with its package
data: the body model and the design templates in ``core/data/``) in
``build/extension`` with a generated manifest that lists the wheels and the
platforms, in a temporary folder; then ``blender_ext.py build`` into
``--out`` (``--split-platforms`` when building for several platforms: one zip
per platform, each with only its wheels, so a user downloads only theirs).
Nothing is written into the checkout (``--out`` must lie outside it; the wheel
cache defaults to the user's cache folder), and the repository's own manifest
is never rewritten.
"""

from __future__ import annotations

import argparse
import glob
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Blender platform -> pip --platform tags (newest first; pip accepts several).
PLATFORM_TAGS = {
    "linux-x64": [
        "manylinux_2_28_x86_64",
        "manylinux_2_27_x86_64",
        "manylinux_2_17_x86_64",
        "manylinux2014_x86_64",
        "manylinux1_x86_64",
        "linux_x86_64",
    ],
    "macos-arm64": [
        "macosx_14_0_arm64",
        "macosx_13_0_arm64",
        "macosx_12_0_arm64",
        "macosx_11_0_arm64",
        "macosx_10_9_universal2",
    ],
    "windows-x64": ["win_amd64"],
}
# Not bundled: Blender ships numpy; bpy is Blender itself; pytest, ruff and setuptools are for tests, lint and
# builds (ruff's wheel alone is 10.6 MB); dask/distributed run `ease batch` (command line only: the add-on has no
# batch).
NOT_BUNDLED = {"numpy", "bpy", "pytest", "pytest-xdist", "execnet", "ruff", "setuptools", "dask", "distributed"}
# examples/designs is a link to core/data/designs in the checkout: the templates ship once, as package data.
SOURCES = ("__init__.py", "blender_manifest.toml", "ease_addon", "core")
SKIP = shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo", ".DS_Store", "*.egg-info", "cli.py.orig")


def requirements(path: Path = ROOT / "requirements.txt") -> tuple:
    """(bundled requirement lines, numpy constraint line) from requirements.txt."""
    bundled, numpy = [], "numpy<2"
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        name = re.split(r"[<>=!~\[; ]", line, 1)[0].lower()
        if name == "numpy":
            numpy = line
        elif name not in NOT_BUNDLED:
            bundled.append(line)
    return bundled, numpy


def download_wheels(platform: str, reqs: list, numpy: str, cache: Path) -> list:
    """Wheels (paths) for ``platform``, numpy excluded; cached per platform."""
    dest = cache / platform
    dest.mkdir(parents=True, exist_ok=True)
    cmd = [
        sys.executable,
        "-m",
        "pip",
        "download",
        "--quiet",
        "--only-binary=:all:",
        "--python-version",
        "3.11",
        "--implementation",
        "cp",
        "--dest",
        str(dest),
    ]
    for tag in PLATFORM_TAGS[platform]:
        cmd += ["--platform", tag]
    # numpy resolves with the others (so they fit Blender's numpy) but is not bundled.
    cmd += reqs + [numpy]
    print(f"[build] downloading wheels for {platform} ...", file=sys.stderr, flush=True)
    if subprocess.run(cmd).returncode != 0:
        # offline: resolve from the cache alone
        print(f"[build] download failed; trying the cache {dest} only", file=sys.stderr, flush=True)
        subprocess.run(cmd + ["--no-index", "--find-links", str(dest)], check=True)
    wheels = sorted(dest.glob("*.whl"))
    keep = []
    for w in wheels:
        dist = w.name.split("-", 1)[0].lower().replace("_", "-")
        if dist in NOT_BUNDLED:
            continue
        keep.append(w)
    return _newest_per_dist(keep)


def _newest_per_dist(wheels: list) -> list:
    """One wheel per distribution (a cache may hold several versions): the last by name order
    of versions is not reliable, so prefer the one pip would pick again = the newest mtime."""
    by = {}
    for w in wheels:
        dist = w.name.split("-", 1)[0].lower()
        if dist not in by or w.stat().st_mtime > by[dist].stat().st_mtime:
            by[dist] = w
    return [by[k] for k in sorted(by)]


def blender_ext_script() -> Path:
    """``blender_ext.py`` shipped inside the bpy wheel."""
    spec = importlib.util.find_spec("bpy")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("bpy is not installed in this Python: run ./ease.sh once (it builds .venv)")
    for loc in spec.submodule_search_locations:
        hits = sorted(glob.glob(os.path.join(loc, "*", "scripts", "addons_core", "bl_pkg", "cli", "blender_ext.py")))
        if hits:
            return Path(hits[-1])
    raise SystemExit("blender_ext.py not found in the bpy package")


def generated_manifest(platforms: list, wheel_names: list) -> str:
    """The repo manifest with ``platforms`` and ``wheels`` filled in (build copy only)."""
    text = (ROOT / "blender_manifest.toml").read_text()
    plat = "platforms = [" + ", ".join(f'"{p}"' for p in platforms) + "]"
    text, n = re.subn(r"(?m)^platforms\s*=.*$", plat, text)
    if n != 1:
        raise SystemExit("blender_manifest.toml: expected one top-level 'platforms = [...]' line")
    if wheel_names:
        wl = "wheels = [\n" + "".join(f'  "./wheels/{w}",\n' for w in wheel_names) + "]"
        text = text.replace(plat, plat + "\n\n" + wl, 1)
    return text


def stage(build: Path, platforms: list, wheels: list) -> Path:
    src = build / "extension"
    if src.exists():
        shutil.rmtree(src)
    src.mkdir(parents=True)
    for rel in SOURCES:
        p = ROOT / rel
        if p.is_dir():
            shutil.copytree(p, src / rel, ignore=SKIP)
        elif p.is_file():
            (src / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(p, src / rel)
    if wheels:
        (src / "wheels").mkdir()
        for w in wheels:
            shutil.copy2(w, src / "wheels" / w.name)
    (src / "blender_manifest.toml").write_text(generated_manifest(platforms, [w.name for w in wheels]))
    return src


def build(platforms: list, out: Path, cache: Path, with_wheels: bool = True, build_dir: Path = None) -> list:
    """Build the zip(s); returns their paths."""
    for p in platforms:
        if p not in PLATFORM_TAGS:
            raise SystemExit(f"unknown platform {p!r}; known: {', '.join(PLATFORM_TAGS)}")
    wheels = []
    if with_wheels:
        reqs, numpy = requirements()
        seen = set()
        for p in platforms:
            for w in download_wheels(p, reqs, numpy, cache):
                if w.name not in seen:  # pure-Python wheels are the same file for every platform
                    seen.add(w.name)
                    wheels.append(w)
    if build_dir is None:  # staged outside the checkout, removed afterwards
        with tempfile.TemporaryDirectory(prefix="ease-extension-") as tmp:
            return _build_zips(stage(Path(tmp), platforms, wheels), platforms, out)
    return _build_zips(stage(build_dir, platforms, wheels), platforms, out)


def _build_zips(src: Path, platforms: list, out: Path) -> list:
    """``blender_ext.py`` validate and build of the staged ``src`` into ``out``; the zips written."""
    script = blender_ext_script()
    out.mkdir(parents=True, exist_ok=True)
    before = set(out.glob("*.zip"))
    subprocess.run([sys.executable, str(script), "validate", str(src)], check=True)
    cmd = [sys.executable, str(script), "build", "--source-dir", str(src), "--output-dir", str(out)]
    if len(platforms) > 1:
        cmd.append("--split-platforms")
    subprocess.run(cmd, check=True)
    return sorted(z for z in out.glob("*.zip") if z not in before or z.stat().st_mtime >= src.stat().st_mtime)


def user_cache() -> Path:
    """The wheel cache: ``$XDG_CACHE_HOME/ease/wheels`` (default ``~/.cache/ease/wheels``)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "ease" / "wheels"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--platform",
        action="append",
        choices=sorted(PLATFORM_TAGS),
        help="platform to build for (repeat; default: all three)",
    )
    ap.add_argument(
        "--out", required=True, help="output folder for the zip(s), outside the checkout (e.g. ~/ease-dist)"
    )
    ap.add_argument("--cache", default=None, help=f"wheel download cache (default {user_cache()})")
    ap.add_argument(
        "--no-wheels",
        action="store_true",
        help="build without bundled wheels (for a Python that already has the dependencies)",
    )
    args = ap.parse_args(argv)
    platforms = args.platform or list(PLATFORM_TAGS)
    out = Path(args.out).expanduser().resolve()
    if out == ROOT or ROOT in out.parents:
        raise SystemExit(f"--out: {out} is inside the checkout {ROOT}; give a folder outside it (e.g. ~/ease-dist)")
    cache = Path(args.cache).expanduser() if args.cache else user_cache()
    zips = build(platforms, out, cache, with_wheels=not args.no_wheels)
    for z in zips:
        print(f"{z}  ({z.stat().st_size / 2**20:.1f} MiB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
