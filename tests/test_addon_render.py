"""Render operators (ease_addon.render_ops): the studio preset and a Cycles render."""
from __future__ import annotations


import numpy as np
import pytest

DESIGN = "top_sleeveless.json"     # cheapest template: two panels


@pytest.fixture(scope="module", autouse=True)
def scene(blender):
    """This module's starting scene."""
    return blender.reset(body=True, design=DESIGN, pattern=True)


def test_cycles_render_is_not_empty(bpy_session):
    bpy = bpy_session["bpy"]
    s = bpy.context.scene.ease
    s.render_samples, s.render_resolution = 2, 8
    s.render_path = str(bpy_session["tmp"] / "render.png")
    assert bpy.ops.ease.studio_setup() == {"FINISHED"}
    assert bpy.context.scene.render.engine == "CYCLES" and bpy.context.scene.cycles.device == "CPU"
    assert bpy.ops.ease.render() == {"FINISHED"}
    img = bpy.data.images.load(s.render_path)
    px = np.empty(img.size[0] * img.size[1] * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    rgb = px.reshape(-1, 4)[:, :3]
    assert img.size[0] > 10 and rgb.std() > 0.01, "the render is a flat image"
    bpy.data.images.remove(img)
