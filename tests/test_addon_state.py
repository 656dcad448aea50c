"""State that never lies (driving the add-on headless through bpy as a designer would):
buttons that cannot run are greyed out with a tooltip saying what is missing, a render
of nothing is refused, objects are updated in place (no ``.001`` names), reports print
what the user set (no float32 noise), and the body shown agrees with the Body panel."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels

# what each operator needs, by the empty scene's tooltip
NEEDS_BODY = (
    "set_size",
    "fit_measurements",
    "measure",
    "set_pose",
    "apply_shape",
    "brush_ease",
    "paint_ease",
    "ease_uniform",
    "ease_gradient",
)
NEEDS_DESIGN = (
    "save_design",
    "set_parameter",
    "recut",
    "assign_keypoint",
    "pick_keypoint",
    "ease_to_design",
    "ease_from_design",
    "optimize_pattern",
    "transfer_size",
    "adapt_poses",
)
NEEDS_PATTERN = ("drape", "export_pattern", "marker")
RUN_ANYWHERE = ("add_body", "load_template", "load_design_file", "studio_setup", "tape_load", "layer_add")


@pytest.fixture
def empty(blender):
    return blender.reset()


def _refusal(op) -> str:
    """The message a greyed-out operator gives when called anyway."""
    try:
        op()
    except RuntimeError as exc:
        return str(exc)
    raise AssertionError(f"{op.idname()} ran although it cannot")


def test_every_operator_says_what_it_needs(bpy_session, blender, empty):
    """Empty scene: everything but adding a body or a design is greyed out, the tooltip
    names what is missing; then step by step (body, design) the next ones come alive."""
    bpy = bpy_session["bpy"]
    names = [n for n in dir(bpy.ops.ease) if not n.startswith("_")]
    assert set(NEEDS_BODY + NEEDS_DESIGN + NEEDS_PATTERN + RUN_ANYWHERE) <= set(names)
    for name in names:
        op = getattr(bpy.ops.ease, name)
        if name in RUN_ANYWHERE:
            assert op.poll(), name
            continue
        assert not op.poll(), f"ease.{name} can be pressed in an empty scene"
        msg = _refusal(op)
        # operators of other stages (not named here) say at least where to go
        want = {
            "save_design": "design",
            "drape": "pattern",
            "export_pattern": "pattern",
            "marker": "pattern",
            "fitmap": "garment",
            "render": "render",
            "drape_all": "layers",
            "layer_remove": "layers",
            "layer_move": "layers",
        }.get(name, "body" if name in NEEDS_BODY + NEEDS_DESIGN else "")
        assert want in msg.lower() and "EASE >" in msg, (name, msg)
    blender.reset(body=True)
    for name in NEEDS_BODY:
        assert getattr(bpy.ops.ease, name).poll(), name
    # Render on an unsaved file whose "Render to" is relative to it: greyed out, saying why; pressable
    # once the path is absolute
    s = bpy.context.scene.ease
    assert not bpy.data.filepath and s.render_path.startswith("//")
    assert "not saved" in _refusal(bpy.ops.ease.render) and "Render to" in _refusal(bpy.ops.ease.render)
    s.render_path = str(Path(bpy_session["tmp"]) / "render.png")
    assert bpy.ops.ease.render.poll()
    for name in NEEDS_DESIGN:
        assert "design" in _refusal(getattr(bpy.ops.ease, name)), name
    blender.reset(body=True, design=DESIGN)
    for name in NEEDS_DESIGN:
        assert getattr(bpy.ops.ease, name).poll(), name
    for name in NEEDS_PATTERN:
        assert "Optimize Pattern" in _refusal(getattr(bpy.ops.ease, name)), name
    assert "Drape" in _refusal(bpy.ops.ease.fitmap)


def test_render_of_an_empty_unsaved_scene_is_refused(bpy_session, blender, empty, tmp_path, monkeypatch):
    bpy = bpy_session["bpy"]
    monkeypatch.chdir(tmp_path)
    assert not bpy.ops.ease.render.poll()
    r = blender.run(bpy.ops.ease.render)
    assert "ERROR" in r and "body" in r["ERROR"]
    assert list(tmp_path.iterdir()) == []
    # with a body but an unsaved file, the relative default path is refused too
    blender.reset(body=True)
    s = bpy.context.scene.ease
    s.render_samples, s.render_resolution = 1, 5
    assert s.render_path.startswith("//")
    r = blender.run(bpy.ops.ease.render)
    assert "ERROR" in r and "save" in r["ERROR"], r
    assert list(tmp_path.iterdir()) == []


def _names(blender):
    out = []
    for role in ("pattern_panel", "pattern_panel_part", "keypoints", "seamlines", "garment"):
        for o in blender.objects(role):
            out.append(o.name)
            if o.data is not None:
                out.append(o.data.name)
    return sorted(out)


def test_reoptimizing_and_transferring_update_objects_in_place(bpy_session, blender):
    bpy = bpy_session["bpy"]
    blender.reset(body=True, design=DESIGN, pattern=True)
    names = _names(blender)
    assert names and not [n for n in names if re.search(r"\.\d{3}$", n)], names
    pieces = {o.name: o.session_uid for o in blender.objects("pattern_panel")}
    markers = {o.name: o.session_uid for o in blender.objects("keypoints")}
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    bpy.context.scene.ease.fit_size = "L"
    assert bpy.ops.ease.transfer_size() == {"FINISHED"}
    assert bpy.ops.ease.recut() == {"FINISHED"}
    assert _names(blender) == names
    assert {o.name: o.session_uid for o in blender.objects("pattern_panel")} == pieces
    assert {o.name: o.session_uid for o in blender.objects("keypoints")} == markers
    assert not [d.name for d in list(bpy.data.meshes) + list(bpy.data.curves) if re.search(r"\.\d{3}$", d.name)]


def test_drape_after_transfer_body_panel_follows(bpy_session, blender, anny):
    """The drape of a transferred pattern shows the body of the transfer size; the Body
    panel (size, phenotype sliders, measurements) follows it."""
    from core.body.instance import body_instance
    from core.body.measure import measure

    bpy = bpy_session["bpy"]
    blender.reset(body=True, design=DESIGN)
    s = bpy.context.scene.ease
    s.size = "M"
    s.fit_size = "XL"
    assert bpy.ops.ease.transfer_size() == {"FINISHED"}
    s.drape_frames, s.drape_device = 3, "cpu"
    assert bpy.ops.ease.drape() == {"FINISHED"}
    X = body_instance(anny, "XL")
    assert np.allclose(blender.verts(s.body), X, atol=1e-5)
    assert s.size == "XL"
    shape = {i.name: i.value for i in s.shape}
    assert shape == pytest.approx(json.loads(s.body["ease_shape"]), abs=1e-6)
    height = measure(anny, X)["height"]
    assert f"height {height:.1f} cm" in s.measurements_report


def test_reports_print_what_the_user_set(bpy_session, blender):
    bpy = bpy_session["bpy"]
    blender.reset(body=True, design=DESIGN)
    s = bpy.context.scene.ease
    s.ease_min, s.ease_max = 0.9, 2.0
    names = [p.name for p in blender.mod("data").current_cut(bpy.context).panels]
    for op, kw in ((bpy.ops.ease.ease_uniform, dict(panel=names[0], ease=3.5)), (bpy.ops.ease.brush_ease, {})):
        s.ease_value = 3.1
        r = blender.run(op, **kw)
        assert "ERROR" in r, r
        assert "0.9 .. 2" in r["ERROR"] and not re.search(r"\d\.\d{7,}", r["ERROR"]), r["ERROR"]


def test_parameters_keep_the_value_the_user_typed(bpy_session, blender):
    """Blender's float properties are single precision: 0.3 reads 0.30000001192092896. The
    design keeps 0.3, and a refused value is quoted as typed."""
    bpy = bpy_session["bpy"]
    blender.reset(body=True, design=DESIGN)
    s = bpy.context.scene.ease
    item = s.design_params[0]
    lo, hi = item.min, item.max
    value = round(0.5 * (lo + hi), 2) + 0.01
    item.value = value  # the slider, live re-cut
    assert json.loads(s.design_json)["parameters"][item.name]["value"] == value
    assert bpy.ops.ease.set_parameter(name=item.name, value=0.3 if lo <= 0.3 <= hi else value) == {"FINISHED"}
    got = json.loads(s.design_json)["parameters"][item.name]["value"]
    assert got == (0.3 if lo <= 0.3 <= hi else value)
    r = blender.run(bpy.ops.ease.set_parameter, name=item.name, value=hi + 1.1)
    assert "ERROR" in r and not re.search(r"\d\.\d{7,}", r["ERROR"]), r["ERROR"]
