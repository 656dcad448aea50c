"""The extension itself, headless with the bpy module: its manifest, enabling and disabling,
the ease ramp (pure numpy) and the sidebar panels naming real properties and operators."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene: a body with a design, so every panel draws in full."""
    return blender.reset(body=True, design=DESIGN)


def test_manifest_validates(blender):
    script = next(
        ROOT.glob(".venv/lib/python3.11/site-packages/bpy/*/scripts/addons_core/bl_pkg/cli/blender_ext.py"), None
    )
    if script is None:
        import bpy  # noqa: F401  (the venv without the usual layout: find it from the module)

        script = next(Path(sys.modules["bpy"].__file__).parent.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    r = subprocess.run([sys.executable, str(script), "validate", str(ROOT)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    text = (ROOT / "blender_manifest.toml").read_text()
    for key in (
        'id = "ease"',
        'type = "add-on"',
        'blender_version_min = "4.2.0"',
        '"SPDX:GPL-3.0-or-later"',
        "[permissions]",
        "files = ",
    ):
        assert key in text


def test_enable_disable_twice_leaves_nothing(bpy_session):
    bpy, module = bpy_session["bpy"], bpy_session["module"]
    base_ops = set(dir(bpy.ops.ease))
    assert "add_body" in base_ops and hasattr(bpy.types.Scene, "ease")
    handlers = {
        k: len(getattr(bpy.app.handlers, k))
        for k in dir(bpy.app.handlers)
        if isinstance(getattr(bpy.app.handlers, k), list)
    }
    for _ in range(2):
        bpy.ops.preferences.addon_disable(module=module)
        assert not hasattr(bpy.types.Scene, "ease")
        assert not hasattr(bpy.types, "EASE_PT_body")
        assert not hasattr(bpy.types, "EASE_OT_add_body")
        assert not [c for c in dir(bpy.types) if c.startswith("EASE_")]
        assert bpy.ops.preferences.addon_enable(module=module) == {"FINISHED"}
        assert hasattr(bpy.types.Scene, "ease") and hasattr(bpy.types, "EASE_PT_ease")
    assert set(dir(bpy.ops.ease)) == base_ops
    # no handler added by enabling twice
    assert {k: len(getattr(bpy.app.handlers, k)) for k in handlers} == handlers
    panels = [c for c in dir(bpy.types) if c.startswith("EASE_PT_")]
    assert {getattr(bpy.types, p).bl_category for p in panels} == {"EASE"}


def test_ramp_blends_decode_to_in_between_ease(addon):
    ramp = addon("ramp")
    lo, hi = 0.9, 2.0
    e = np.array([0.9, 1.0, 1.3, 1.75, 2.0])
    c = ramp.ease_to_color(e, lo, hi)
    assert np.allclose(ramp.color_to_ease(c, lo, hi), e, atol=1e-6)
    a = np.linspace(0, 1, 7)[:, None]
    c0, c1 = ramp.ease_to_color(1.1, lo, hi), ramp.ease_to_color(1.8, lo, hi)
    blend = (1 - a) * c0 + a * c1  # what a soft brush edge leaves in a float layer
    assert np.allclose(ramp.color_to_ease(blend, lo, hi), 1.1 + a[:, 0] * 0.7, atol=1e-6)
    # brush strength scaling the colour does not change the decoded ease
    assert np.allclose(ramp.color_to_ease(0.6 * c0, lo, hi), 1.1, atol=1e-6)
    with pytest.raises(ValueError):
        ramp.ease_to_color(1.0, 2.0, 1.0)
    assert np.allclose(ramp.srgb_to_linear(ramp.linear_to_srgb([0.0, 0.002, 0.3, 1.0])), [0.0, 0.002, 0.3, 1.0])


FILE_ONLY = ("save_design",)  # operators that write a file and change no Blender data: no undo step


class _Recorder:
    """A stand-in for ``UILayout`` that checks every property and operator the panels name."""

    def __init__(self, bpy, seen):
        self.bpy, self.seen = bpy, seen

    def _sub(self, *a, **k):
        return self

    row = column = box = split = _sub

    def label(self, **k):
        self.seen.append(("label", k.get("text")))

    def separator(self, **k):
        pass

    def prop(self, data, name, **k):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
        self.seen.append(("prop", name))

    def template_list(self, list_type, list_id, data, name, active_data, active_name, **k):
        assert hasattr(self.bpy.types, list_type), f"no UIList {list_type}"
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
        assert active_name in active_data.bl_rna.properties, f"{type(active_data).__name__} has no {active_name!r}"
        self.seen.append(("prop", name))

    def prop_enum(self, data, name, value, **k):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"
        items = {i.identifier for i in data.bl_rna.properties[name].enum_items}
        assert value in items, f"{type(data).__name__}.{name} has no item {value!r}"
        self.seen.append(("prop", name))

    def operator(self, idname, **k):
        mod, name = idname.split(".")
        assert hasattr(getattr(self.bpy.ops, mod), name), f"no operator {idname}"
        self.seen.append(("op", idname))

        class _Props:
            def __setattr__(s, key, value):
                pass

        return _Props()


def test_sidebar_panels_name_real_properties_and_operators(bpy_session):
    bpy = bpy_session["bpy"]
    seen = []
    for cls_name in [c for c in dir(bpy.types) if c.startswith("EASE_PT_")]:
        cls = getattr(bpy.types, cls_name)
        assert cls.bl_space_type == "VIEW_3D" and cls.bl_region_type == "UI" and cls.bl_category == "EASE"
        fake = type("P", (), {"layout": _Recorder(bpy, seen)})()
        cls.draw(fake, bpy.context)
    ops = {n for k, n in seen if k == "op"}
    for op in (
        "ease.add_body",
        "ease.set_size",
        "ease.fit_measurements",
        "ease.set_pose",
        "ease.load_template",
        "ease.assign_keypoint",
        "ease.paint_ease",
        "ease.brush_ease",
        "ease.ease_uniform",
        "ease.ease_gradient",
        "ease.ease_to_design",
        "ease.optimize_pattern",
        "ease.transfer_size",
        "ease.adapt_poses",
        "ease.drape",
        "ease.studio_setup",
        "ease.render",
        "ease.export_pattern",
    ):
        assert op in ops, f"{op} is not in the sidebar"
    # every operator that changes Blender data supports undo; Save Design writes a file only
    names = [n for n in dir(bpy.ops.ease) if not n.startswith("_")]
    assert len(names) >= 25
    for name in names:
        cls = getattr(bpy.types, "EASE_OT_" + name)
        if "INTERNAL" in cls.bl_options:  # the job watcher and Cancel: they change no Blender data
            assert not {"UNDO"} & set(cls.bl_options), name
            continue
        if name in FILE_ONLY:
            assert set(cls.bl_options) == {"REGISTER"}, name
        else:
            assert {"REGISTER", "UNDO"} <= set(cls.bl_options), name
