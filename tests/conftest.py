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
    parser.addoption(
        "--full", action="store_true", default=False, help="run every generated case, not only the seeded CI sample"
    )
    parser.addoption(
        "--same-bits",
        choices=("auto", "bits", "close"),
        default="auto",
        dest="same_bits",
        help="how same_bits tests compare two code paths: as this machine's probe says (auto), "
        "bit for bit whatever it says (bits), or within tolerances (close); "
        "tests/helpers/same_bits.py",
    )


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a generated case outside the seeded CI sample")
    config.addinivalue_line(
        "markers",
        "same_bits: compares two code paths of one computation, bit for bit "
        "where this machine keeps the contract, else within tolerances "
        "(tests/helpers/same_bits.py, docs/architecture.md)",
    )
    import same_bits

    same_bits.MODE["value"] = config.getoption("same_bits")
    # Warp compiles its kernels once into this cache; tests share the project's cache.
    os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".cache" / "warp"))


def pytest_collection_modifyitems(config, items):
    if config.getoption("--full"):
        return
    skip = pytest.mark.skip(reason="slow generated case outside the CI sample (run with --full)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def pytest_terminal_summary(terminalreporter):
    import same_bits

    line = same_bits.probe_summary()
    if line:
        terminalreporter.write_line(line)


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


@pytest.fixture
def numpy_steps():
    """The solver's per-triangle steps in numpy for the test (the Warp kernels off: tests of numpy's own
    memos; :mod:`core.pattern.accel.compiled` gives the same bits either way)."""
    from core.pattern.accel import compiled

    compiled.use(False)
    yield
    compiled.use(None)


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
    repo = bpy.context.preferences.extensions.repos.new(
        name="EASE test", module="ease_test", custom_directory=repo_dir, source="USER"
    )
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


class AddonScene:
    """The add-on tests' handle on the session's bpy: the scene a test module starts from and
    the read-backs every module uses.

    Each add-on test module builds the scene it needs with :meth:`reset` in a module fixture
    (an empty scene, then the designer's steps up to the stage it tests), so no module depends
    on another having run first.
    """

    def __init__(self, session: dict):
        self.bpy, self.module, self.tmp = session["bpy"], session["module"], session["tmp"]

    def mod(self, name: str):
        """The enabled extension's ``ease_addon.<name>`` module."""
        return sys.modules[f"{self.module}.ease_addon.{name}"]

    @property
    def scene(self):
        return self.bpy.context.scene

    def reset(
        self,
        body: bool = False,
        design: str = None,
        piecewise_ease: bool = False,
        pattern: bool = False,
        drape_frames: int = 0,
    ):
        """An empty scene, then (each step needs the ones before it): the default body, the
        template ``design``, a piecewise ease field painted into the design (1.2 on the
        body, 1.4 on the first panel), the optimized pattern, a drape of ``drape_frames``."""
        ops = self.bpy.ops
        if self.bpy.context.object is not None and self.bpy.context.object.mode != "OBJECT":
            ops.object.mode_set(mode="OBJECT")
        ops.wm.read_homefile(use_empty=True)
        steps = []
        if body:
            steps.append((ops.ease.add_body, dict(source="DEFAULT")))
        if design:
            steps.append((ops.ease.load_template, dict(template=design)))
        for op, kw in steps:
            assert op(**kw) == {"FINISHED"}, op.idname()
        if piecewise_ease:
            first = self.mod("data").current_cut(self.bpy.context).panels[0].name
            assert ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
            assert ops.ease.ease_uniform(panel=first, ease=1.4) == {"FINISHED"}
            assert ops.ease.ease_to_design() == {"FINISHED"}
        if pattern:
            assert ops.ease.optimize_pattern() == {"FINISHED"}
        if drape_frames:
            self.scene.ease.drape_frames, self.scene.ease.drape_device = drape_frames, "cpu"
            assert ops.ease.drape() == {"FINISHED"}
        return self

    def objects(self, role: str) -> list:
        return [o for o in self.bpy.data.objects if o.get("ease_role") == role]

    @staticmethod
    def verts(obj):
        """(V, 3) float32 object-space vertex positions of a mesh object."""
        import numpy as np

        co = np.empty(len(obj.data.vertices) * 3, dtype=np.float32)
        obj.data.vertices.foreach_get("co", co)
        return co.reshape(-1, 3)

    @staticmethod
    def world_box(obj):
        """Min and max corner of an object's world-space bounding box."""
        import numpy as np

        m = np.array(obj.matrix_world)
        c = np.array([list(v) for v in obj.bound_box]) @ m[:3, :3].T + m[:3, 3]
        return c.min(0), c.max(0)

    @staticmethod
    def run(op, **kw):
        """Call an operator; its result set, or ``{"ERROR": message}`` when it reported an error."""
        try:
            return op(**kw)
        except RuntimeError as exc:
            return {"ERROR": str(exc)}


@pytest.fixture(scope="session")
def blender(bpy_session):
    """:class:`AddonScene` on the session's bpy."""
    return AddonScene(bpy_session)
