"""Shared fixtures: the Anny body (one load per session) and the headless bpy session.

Fixtures that are expensive and read-only live here, session-scoped, so each
test module asks for them by name instead of loading its own copy. Synthetic
test geometry (capsules, tube models, hand-made patterns) lives in
``tests/helpers/`` (on ``sys.path`` through ``pythonpath`` in pyproject.toml),
never in the shipped packages.

Slow generated cases carry ``@pytest.mark.slow``: CI runs a fixed, seeded
sample of them (see :func:`sample`); ``pytest --full`` runs them all.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def pytest_addoption(parser):
    parser.addoption("--full", action="store_true", default=False,
                     help="run every generated case, not only the seeded CI sample")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a generated case outside the seeded CI sample")
    # Warp compiles its kernels once into this cache; tests share the project's cache.
    os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".cache" / "warp"))


def pytest_collection_modifyitems(config, items):
    if config.getoption("--full"):
        return
    skip = pytest.mark.skip(reason="slow generated case outside the CI sample (run with --full)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def sample(cases, k: int, seed: int = 0, full: bool = False):
    """A fixed, seeded sample of ``k`` of ``cases`` (all of them with ``full``).

    Use at collection time: ``pytest.mark.parametrize("case", sample(CASES, 20))``;
    the rest are generated with the ``slow`` mark so ``--full`` still reaches them.
    """
    import random
    cases = list(cases)
    if full or k >= len(cases):
        return cases
    chosen = set(random.Random(seed).sample(range(len(cases)), k))
    return [c if i in chosen else pytest.param(c, marks=pytest.mark.slow) for i, c in enumerate(cases)]


@pytest.fixture(scope="session")
def anny():
    """The baked Anny body model (part of the repository: a failure here is a real one)."""
    from core.body import load_body
    return load_body("anny")


@pytest.fixture(scope="session")
def anny_reference(anny):
    """(vertices (V, 3) m, joints (J, 3) m) of Anny's reference instance (shape M, A-pose)."""
    return anny.vertices_and_joints()


# ----------------------------------------------------------------------------- Blender

def _import_bpy(user_dir: str):
    if "bpy" not in sys.modules:
        # bpy reads its user folder once per process: set it before the first import
        os.environ["BLENDER_USER_RESOURCES"] = user_dir
    import bpy
    return bpy


@pytest.fixture(scope="session")
def bpy_session():
    """Headless bpy with the extension enabled from a temporary user extension repository.

    Yields ``{"bpy", "module", "tmp"}``: ``module`` is the extension's package
    (``bl_ext.ease_test.ease``), ``tmp`` a scratch folder for the session.
    """
    pytest.importorskip("bpy")
    tmp = tempfile.mkdtemp(prefix="ease_addon_test_")
    bpy = _import_bpy(os.path.join(tmp, "user"))
    repo_dir = os.path.join(tmp, "repo")
    os.makedirs(repo_dir)
    os.symlink(ROOT, os.path.join(repo_dir, "ease"))
    repo = bpy.context.preferences.extensions.repos.new(name="EASE test", module="ease_test",
                                                        custom_directory=repo_dir, source="USER")
    module = f"bl_ext.{repo.module}.ease"
    assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
    bpy.ops.wm.read_homefile(use_empty=True)
    yield {"bpy": bpy, "module": module, "tmp": Path(tmp)}
    import addon_utils
    if addon_utils.check(module)[1]:
        bpy.ops.preferences.addon_disable(module=module)
    elif module in sys.modules:  # preferences reloaded with a file: unregister directly
        sys.modules[module].unregister()
    for r in list(bpy.context.preferences.extensions.repos):
        if r.module == "ease_test":
            bpy.context.preferences.extensions.repos.remove(r)


@pytest.fixture
def addon(bpy_session):
    """``addon("state")`` -> the enabled extension's ``ease_addon.state`` module."""
    return lambda name: sys.modules[f"{bpy_session['module']}.ease_addon.{name}"]
