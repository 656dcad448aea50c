"""Ease operators (ease_addon.ease_ops): the brush colour, the painted layer read back,
uniform and gradient ease per panel, the layer into the design and back.

Paint strokes crash headless, so the ease layer is written as data the way a
brush leaves it (scene-linear colours, linear blends)."""

from __future__ import annotations

import json

import numpy as np
import pytest

DESIGN = "top_sleeveless.json"  # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN)


def test_brush_colour_and_painted_layer_read_back(bpy_session, addon):
    ramp = addon("ramp")
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.ease_min, s.ease_max = 0.9, 2.0
    s.ease_value = 1.3
    assert bpy.ops.ease.brush_ease() == {"FINISHED"}
    ups = bpy.context.scene.tool_settings.vertex_paint.unified_paint_settings
    want = ramp.ease_to_color(1.3, 0.9, 2.0)[:3]
    got = np.asarray(ups.color)
    if type(ups).bl_rna.properties["color"].subtype == "COLOR_GAMMA":
        got = ramp.srgb_to_linear(got)
    assert np.allclose(got, want, atol=1e-6)
    assert len(s.legend) == 5 and s.legend[0].ease == pytest.approx(0.9) and s.legend[-1].ease == pytest.approx(2.0)
    # "paint": the brush colour where the stroke was, a 50 % blend with 1.8 on its edge
    obj = s.body
    me = obj.data
    addon("ease_ops")
    c0, c1 = ramp.ease_to_color(1.3, 0.9, 2.0), ramp.ease_to_color(1.8, 0.9, 2.0)
    colors = np.tile(c1, (len(me.vertices), 1))
    faces = np.array([p.vertices[:] for p in me.polygons])
    stroke = faces[:500]
    colors[np.unique(stroke)] = np.asarray(got.tolist() + [1.0], dtype=np.float32)
    edge = faces[600:650]
    colors[np.unique(edge)] = 0.5 * c0 + 0.5 * c1
    me.color_attributes["ease"].data.foreach_set("color", colors.astype(np.float32).ravel())
    tri = addon("data").triangle_ease(obj, bpy.context.scene)
    inner = [i for i in range(500) if not np.isin(faces[i], np.unique(faces[500:])).any()]
    assert inner and np.allclose(tri[inner], 1.3, atol=1e-5)  # exact for the brush's value
    only_edge = [
        i
        for i in range(600, 650)
        if np.isin(faces[i], np.unique(edge)).all() and not np.isin(faces[i], np.unique(stroke)).any()
    ]
    assert only_edge and np.allclose(tri[only_edge], 1.55, atol=1e-5)  # in-between ease


def test_uniform_and_gradient_ease_per_panel(bpy_session, blender, addon):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    ease_ops = addon("ease_ops")
    cut = addon("data").current_cut(bpy.context)
    names = [p.name for p in cut.panels]
    assert bpy.ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
    assert bpy.ops.ease.ease_uniform(panel=names[0], ease=1.5) == {"FINISHED"}
    v = addon("data").vertex_ease(s.body, bpy.context.scene)
    mask = ease_ops.panel_vertex_mask(bpy.context, names[0])
    assert np.allclose(v[mask], 1.5, atol=1e-5) and np.allclose(v[~mask], 1.2, atol=1e-5)
    s.ease_from, s.ease_to, s.gradient_axis = 1.1, 1.7, "Z"
    assert bpy.ops.ease.ease_gradient(panel=names[-1]) == {"FINISHED"}
    v = addon("data").vertex_ease(s.body, bpy.context.scene)
    m2 = ease_ops.panel_vertex_mask(bpy.context, names[-1])
    z = blender.verts(s.body)[:, 2]
    top, bottom = m2 & (z >= np.percentile(z[m2], 95)), m2 & (z <= np.percentile(z[m2], 5))
    assert v[top].mean() < 1.2 < v[bottom].mean()
    assert v[m2].min() >= 1.1 - 1e-5 and v[m2].max() <= 1.7 + 1e-5
    # a value outside the ramp is refused, the layer unchanged
    r = blender.run(bpy.ops.ease.ease_uniform, panel=names[0], ease=3.5)
    assert "ERROR" in r
    assert np.allclose(addon("data").vertex_ease(s.body, bpy.context.scene), v)
    # back to the piecewise field the pattern test uses
    assert bpy.ops.ease.ease_uniform(whole_body=True, ease=1.2) == {"FINISHED"}
    assert bpy.ops.ease.ease_uniform(panel=names[0], ease=1.4) == {"FINISHED"}


def test_ease_layer_to_design(bpy_session, addon):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    ease_ops = addon("ease_ops")
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    design = json.loads(s.design_json)
    fields = [p["ease"] for g in design["garments"] for p in g["panels"]]
    assert all("per_triangle" in f for f in fields)
    cut = addon("data").current_cut(bpy.context)
    names = [p.name for p in cut.panels]
    first, other = cut.panel(names[0]), cut.panel(names[-1])
    # the cut's per-triangle targets are the painted values (seam triangles may blend)
    assert np.median(first.ease) == pytest.approx(1.4, abs=1e-4)
    assert np.median(other.ease) == pytest.approx(1.2, abs=1e-4)
    # and back: the design's field written into the layer reads back the same
    v_before = addon("data").vertex_ease(s.body, bpy.context.scene)
    assert bpy.ops.ease.ease_from_design() == {"FINISHED"}
    v_after = addon("data").vertex_ease(s.body, bpy.context.scene)
    inside = ease_ops.panel_vertex_mask(bpy.context, names[0])
    assert np.median(np.abs(v_after[inside] - v_before[inside])) < 1e-4
