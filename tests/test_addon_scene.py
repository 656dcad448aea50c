"""The scene as a whole: undo of every operator restores it, and a save and reopen keeps
everything the add-on needs (nothing lives only in memory)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, piecewise_ease=True, pattern=True, drape_frames=6)


def _fingerprint(bpy, blender, ease_ops, convert):
    """What an operator may change: objects, body vertices, ease layer, design, pattern, studio."""
    sc = bpy.context.scene
    s = sc.ease
    fp = {
        "objects": sorted(o.name for o in bpy.data.objects),
        "design": s.design_json,
        "pattern": sc.get("ease_pattern_json", ""),
        "engine": sc.render.engine,
        "camera": sc.camera.name if sc.camera else None,
        "reports": [s.pattern_json, s.fit_json, s.drape_json, s.measurements_report],
        "params": [(i.name, round(i.value, 6)) for i in s.design_params],
        "brush": [round(c, 6) for c in sc.tool_settings.vertex_paint.unified_paint_settings.color],
        "ramp": (round(s.ease_min, 6), round(s.ease_max, 6)),
        "mode": bpy.context.object.mode if bpy.context.object else None,
    }
    for g in (o for o in bpy.data.objects if o.get("ease_role") == "garment"):
        fp["garment"] = (
            float(np.round(blender.verts(g).astype(np.float64).sum(), 5)),
            g.data.materials[0].name if g.data.materials else None,
        )
    if s.body is not None:
        fp["verts"] = float(np.round(blender.verts(s.body).astype(np.float64).sum(), 5))
        fp["ease"] = float(np.round(blender.mod("data").vertex_ease(s.body, sc).sum(), 5))
        fp["kp"] = json.dumps(convert.read_keypoints(s.body.data), sort_keys=True)
        layer = s.body.data.color_attributes.get("ease")
        raw = np.empty(len(layer.data) * 4, dtype=np.float32)
        layer.data.foreach_get("color", raw)
        fp["layer"] = (float(np.round(raw.astype(np.float64).sum(), 4)), list(s.body.data.get("ease_ramp", [])))
    return fp


def test_undo_restores_the_scene(bpy_session, blender, addon):
    """Every operator's changes live in Blender data, so undo brings the scene back.

    Headless, operators called from Python push no undo step of their own; the
    test pushes the steps the UI would push around each call, then undoes.
    """
    bpy = bpy_session["bpy"]
    ease_ops, convert = addon("ease_ops"), addon("convert")
    names = [p.name for p in addon("data").current_cut(bpy.context).panels]
    bpy.context.scene.render.engine = (
        "BLENDER_EEVEE"
        if "BLENDER_EEVEE" in [i.identifier for i in bpy.context.scene.render.bl_rna.properties["engine"].enum_items]
        else "BLENDER_WORKBENCH"
    )
    # after an undo Blender rebuilds its data: Python references taken before it dangle,
    # so every step fetches the scene afresh (E() below)
    E = lambda: bpy.context.scene.ease  # noqa: E731
    param_name = E().design_params[0].name
    design_file = bpy_session["tmp"] / "undo_design.json"
    other = json.loads((ROOT / "examples" / "designs" / DESIGN).read_text())
    other["materials"]["eps_weft"] = 1.2
    design_file.write_text(json.dumps(other))
    E().export_dir = str(bpy_session["tmp"] / "export_undo")
    E().export_svg, E().export_dxf, E().export_pdf, E().export_glb, E().export_obj = True, False, False, False, False

    def param():
        return E().design_params[param_name]

    def slider_without_live_update():
        sync = addon("sync")
        sync.SYNCING = True  # as if the slider moved with live update off
        try:
            E().shape["weight"].value = 0.7
        finally:
            sync.SYNCING = False

    def nudge_param():
        E().live_recut = False
        param().value = 0.5 * (param().value + param().max)

    ops = bpy.ops.ease
    # (operator, arguments, what to set first); every operator that changes the scene
    calls = [
        (ops.ease_uniform, lambda: dict(whole_body=True, ease=1.9), None),
        (ops.ease_gradient, lambda: dict(panel=names[0]), None),
        # a field the design does not have yet (the same field again changes nothing)
        (ops.ease_to_design, dict, lambda: ops.ease_uniform(whole_body=True, ease=1.6)),
        (ops.ease_from_design, dict, lambda: ops.ease_uniform(whole_body=True, ease=1.7)),
        # a new ramp range: the brush re-encodes the painted layer in it
        (ops.brush_ease, dict, lambda: setattr(E(), "ease_min", 0.8) or setattr(E(), "ease_value", 1.45)),
        (ops.set_size, lambda: dict(size="S"), None),
        (ops.set_pose, lambda: dict(pose="P3"), None),
        (ops.apply_shape, dict, slider_without_live_update),
        (ops.fit_measurements, dict, lambda: setattr(E(), "waist_cm", 90.0)),
        (ops.measure, dict, lambda: setattr(E(), "measurements_report", "")),
        (ops.assign_keypoint, lambda: dict(name="undo_point", vertex=100), None),
        (ops.set_parameter, lambda: dict(name=param_name, value=0.5 * (param().value + param().min)), None),
        (ops.recut, dict, nudge_param),
        (ops.load_design_file, lambda: dict(filepath=str(design_file)), None),
        (ops.load_template, lambda: dict(template=DESIGN), None),
        (ops.optimize_pattern, dict, None),
        (ops.transfer_size, dict, lambda: setattr(E(), "fit_size", "S")),
        (ops.adapt_poses, dict, None),
        # fewer frames than the module's drape: a garment that differs from the one shown
        (ops.drape, dict, lambda: setattr(E(), "drape_frames", 4)),
        (ops.fitmap, lambda: dict(mode="GAP"), None),
        (ops.export_pattern, dict, lambda: setattr(E(), "export_hem_cm", 2.5)),
        (ops.paint_ease, dict, None),
        (ops.add_body, lambda: dict(source="DEFAULT"), None),
        (ops.studio_setup, dict, None),
    ]
    for op, kw, prepare in calls:
        if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        if prepare is not None:
            prepare()
        bpy.ops.ed.undo_push(message="before")
        before = _fingerprint(bpy, blender, ease_ops, convert)
        assert op(**kw()) == {"FINISHED"}, op
        bpy.ops.ed.undo_push(message=op.idname())
        assert _fingerprint(bpy, blender, ease_ops, convert) != before, f"{op.idname()} changed nothing"
        assert bpy.ops.ed.undo() == {"FINISHED"}
        after = _fingerprint(bpy, blender, ease_ops, convert)
        if op.idname() == "EASE_OT_brush_ease":
            # Blender keeps the paint colour out of its undo history (its own colour
            # picker is not undone either); the layer it re-encoded is restored
            assert after["brush"] != before["brush"]
            after["brush"] = before["brush"]
        assert after == before, (
            op.idname(),
            {k: (before.get(k), after.get(k)) for k in before if before.get(k) != after.get(k)},
        )
        E().live_recut = True
    # the operators that change no Blender data (files only; the modal picker is a
    # click in the viewport): nothing to undo, and the scene stays as it was
    assert ops.export_pattern() == {"FINISHED"}  # the design takes the panel's export settings
    before = _fingerprint(bpy, blender, ease_ops, convert)
    assert ops.save_design(filepath=str(bpy_session["tmp"] / "undo_saved.json")) == {"FINISHED"}
    assert ops.export_pattern() == {"FINISHED"}
    assert _fingerprint(bpy, blender, ease_ops, convert) == before


def test_save_reopen_round_trip(bpy_session, addon):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    addon("ease_ops")
    convert = addon("convert")
    design = s.design_json
    ease_v = addon("data").vertex_ease(s.body, bpy.context.scene).copy()
    kps = convert.read_keypoints(s.body.data)
    path = str(bpy_session["tmp"] / "scene.blend")
    assert bpy.ops.wm.save_as_mainfile(filepath=path) == {"FINISHED"}
    bpy.ops.wm.read_homefile(use_empty=True)
    assert not bpy.context.scene.ease.design_json
    assert bpy.ops.wm.open_mainfile(filepath=path) == {"FINISHED"}
    s = bpy.context.scene.ease
    assert s.design_json == design
    assert np.allclose(addon("data").vertex_ease(s.body, bpy.context.scene), ease_v, atol=1e-7)
    assert convert.read_keypoints(s.body.data) == kps
    data = addon("data")
    assert data.stored_pattern(bpy.context.scene) is not None
    # the draped garment exports from the reopened file (nothing kept only in memory)
    s.export_dir = str(bpy_session["tmp"] / "export_reopened")
    s.export_svg, s.export_dxf, s.export_pdf, s.export_glb, s.export_obj = False, False, False, True, False
    assert bpy.ops.ease.export_pattern() == {"FINISHED"}
    assert (bpy_session["tmp"] / "export_reopened" / "garment.glb").stat().st_size > 1000
    s.export_svg, s.export_dxf = True, True
    # the scene keeps working after reopening: ease back into the design, re-cut from the JSON
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
