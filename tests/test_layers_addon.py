"""The add-on's Layers list (ease_addon.layers_ops, issue 37): add garments inner first, set tucked,
reorder, Drape All; each garment its own object and material, the report in the scene."""

from __future__ import annotations

import json

import pytest


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    return blender.reset()


def test_layers_list_and_drape_all(bpy_session, blender):
    bpy = bpy_session["bpy"]
    ops, sc = bpy.ops, bpy.context.scene
    layers = sc.ease_layers
    sc.ease.template = "shirt_long_sleeve.json"
    assert ops.ease.layer_add() == {"FINISHED"}  # the Design panel's template: the shirt
    assert ops.ease.layer_add(design="pants") == {"FINISHED"}
    assert [ly.design for ly in layers.items] == ["shirt_long_sleeve", "pants"]
    # the order and the tuck must agree: an untucked shirt under the pants is refused in one line
    err = blender.run(ops.ease.drape_all)
    assert "ERROR" in err and "layers[0].tucked" in err["ERROR"]
    # reordered: the pants inner, the shirt over them; then back, tucked
    layers.index = 1
    assert ops.ease.layer_move(direction="UP") == {"FINISHED"}
    assert [ly.design for ly in layers.items] == ["pants", "shirt_long_sleeve"] and layers.index == 0
    assert "ERROR" in blender.run(ops.ease.layer_move, direction="UP")
    assert ops.ease.layer_move(direction="DOWN") == {"FINISHED"}
    layers.items[0].tucked = True
    assert "ERROR" in blender.run(ops.ease.layer_add, design="no_such_garment")
    assert len(layers.items) == 2
    sc.ease.drape_frames, sc.ease.drape_device, layers.edge_mm = 12, "cpu", 40.0
    layers.over = "draped"  # the pants cut over the shirt as draped
    assert ops.ease.drape_all() == {"FINISHED"}
    objs = sorted(blender.objects("outfit_garment"), key=lambda o: o["ease_layer"])
    assert [o.name for o in objs] == ["EASE long-sleeve shirt", "EASE pants"]
    mats = [o.data.materials[0].name for o in objs]
    assert len(set(mats)) == 2
    rep = json.loads(sc["ease_outfit_report"])
    assert [ly["name"] for ly in rep["layers"]] == ["long-sleeve shirt", "pants"]
    assert rep["layers"][0]["tucked"] and "long-sleeve shirt" in rep["layers"][1]["over"]
    assert rep["layers"][1]["pattern_measured_on"]["surface"] == "draped over"
    assert "outfit draped: 2 layers" in sc.ease.drape_status
    # a second Drape All replaces the garments, nothing piles up
    assert ops.ease.layer_remove() == {"FINISHED"} and len(layers.items) == 1
