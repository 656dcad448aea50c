"""Paint is honoured where it is painted (ease_addon.ease_ops, core.design.ease): on a
mirrored design each side keeps what was painted on it unless Blender's X-mirror paint
setting is on, and *Paint Ease* adopts an ease layer of any domain and type without loss.

Paint strokes crash headless: the layer is written as data the way a brush leaves it."""

from __future__ import annotations

import numpy as np
import pytest

DESIGN = "top_short_sleeve.json"  # mirrored: sleeve_*_right are generated from sleeve_*_left


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene: the body and a mirrored design."""
    return blender.reset(body=True, design=DESIGN)


def _paint_random(bpy, addon, seed=0):
    """A random field (1.0 .. 1.8) written into the layer as a brush would; per-triangle ease (F,)."""
    ramp, _ease_ops = addon("ramp"), addon("ease_ops")
    s = bpy.context.scene.ease
    s.ease_min, s.ease_max = 0.9, 2.0
    me = s.body.data
    e = np.random.default_rng(seed).uniform(1.0, 1.8, len(me.vertices))
    me.color_attributes["ease"].data.foreach_set("color", ramp.ease_to_color(e, 0.9, 2.0).astype(np.float32).ravel())
    return addon("data").triangle_ease(s.body, bpy.context.scene)


def _own_share(bpy, addon, cut, tri_ease):
    """Per panel: the share of its triangles whose target ease is the painted ease where they lie."""
    from core.design.geometry import SurfaceLocator

    convert = addon("convert")
    obj = bpy.context.scene.ease.body
    X, F = convert.get_vertices(obj.data), convert.get_triangles(obj.data)
    loc = SurfaceLocator(X, F)
    out = {}
    for p in cut.panels:
        c = cut.panel_positions(p, X)[p.faces].mean(axis=1)
        _, tri, _ = loc.closest(c)
        out[p.name] = float(np.mean(np.abs(np.asarray(p.ease) - tri_ease[tri]) < 1e-4))
    return out


def _x_mirror(bpy, on: bool):
    me = bpy.context.scene.ease.body.data
    me.use_mirror_x = on


def test_right_side_paint_reaches_the_right_panels(bpy_session, addon):
    bpy = bpy_session["bpy"]
    _x_mirror(bpy, False)
    tri = _paint_random(bpy, addon, seed=1)
    assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    cut = addon("data").current_cut(bpy.context)
    share = _own_share(bpy, addon, cut, tri)
    right = [n for n in share if n.endswith("_right")]
    assert right
    for n in share:
        # seam triangles may blend; nearly every triangle reads its own painting
        assert share[n] > 0.9, (n, share[n])
    # the two sides differ: the right pieces are pieces of their own, not mirrors
    for p in cut.panels:
        if p.name.endswith("_right"):
            assert p.mirror_of is None, p.name
    assert bpy.ops.ease.optimize_pattern() == {"FINISHED"}
    pattern = addon("data").stored_pattern(bpy.context.scene)
    assert not [p.name for p in pattern.panels if p.mirror_of], "the export would mark them 'mirror'"
    labels = [o.data.body for o in bpy.data.objects if o.name.startswith("EASE label")]
    assert labels and not [t for t in labels if "mirror" in t]


def test_x_mirror_paint_symmetrises_the_field(bpy_session, addon):
    bpy = bpy_session["bpy"]
    _x_mirror(bpy, True)
    try:
        _paint_random(bpy, addon, seed=2)
        assert bpy.ops.ease.ease_to_design() == {"FINISHED"}
    finally:
        _x_mirror(bpy, False)
    cut = addon("data").current_cut(bpy.context)
    for p in cut.panels:
        if p.name.endswith("_right"):
            left = cut.panel(p.name.replace("_right", "_left"))
            assert p.mirror_of == left.name
            assert np.allclose(np.sort(p.ease), np.sort(left.ease), atol=1e-6)


@pytest.mark.parametrize("data_type", ["BYTE_COLOR", "FLOAT_COLOR"])
@pytest.mark.parametrize("domain", ["POINT", "CORNER"])
def test_paint_ease_adopts_any_ease_layer_without_loss(bpy_session, addon, data_type, domain):
    """A designer's ``ease`` layer of any type and domain (made in Blender's Color Attributes
    panel, or by another tool) is kept: Paint Ease converts it, the ease it reads is unchanged."""
    bpy = bpy_session["bpy"]
    ramp, ease_ops = addon("ramp"), addon("ease_ops")
    sc = bpy.context.scene
    sc.ease.ease_min, sc.ease.ease_max = 0.9, 2.0
    me = sc.ease.body.data
    me.color_attributes.remove(me.color_attributes["ease"])
    if "ease_ramp" in me:
        del me["ease_ramp"]
    layer = me.color_attributes.new("ease", data_type, domain)
    n = len(layer.data)
    e = np.random.default_rng(3).uniform(1.0, 1.8, n)  # corners of one vertex differ: no averaging allowed
    layer.data.foreach_set("color", ramp.ease_to_color(e, 0.9, 2.0).astype(np.float32).ravel())
    before = addon("data").triangle_ease(sc.ease.body, sc)
    assert before.std() > 0.05
    try:
        assert bpy.ops.ease.paint_ease() == {"FINISHED"}
    finally:
        bpy.ops.object.mode_set(mode="OBJECT")
    layer = me.color_attributes["ease"]
    assert layer.data_type == "FLOAT_COLOR" and me.color_attributes.active_color.name == "ease"
    after = addon("data").triangle_ease(sc.ease.body, sc)
    assert np.allclose(after, before, atol=1e-6)
    # the brush's uniform writes keep the corners they do not touch
    names = [p.name for p in addon("data").current_cut(bpy.context).panels]
    assert bpy.ops.ease.ease_uniform(panel=names[0], ease=1.3) == {"FINISHED"}
    mask = ease_ops.panel_vertex_mask(bpy.context, names[0])
    faces = addon("convert").get_triangles(me)
    outside = ~mask[faces].any(axis=1)
    assert np.allclose(addon("data").triangle_ease(sc.ease.body, sc)[outside], before[outside], atol=1e-6)
