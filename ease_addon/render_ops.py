"""Render stage: a studio preset (camera framing the body, three-point
lights, Cycles on the CPU with few samples) and a PNG render."""
from __future__ import annotations

import math
import os

import bpy
import numpy as np

from . import data, state
from .objects import collection, ensure_nodes, world_bounds
from .operators_base import EaseOperator

STUDIO = "EASE Studio"


def scene_bounds(scene) -> tuple:
    """(min, max) world corners of the visible EASE meshes (body, garment, pattern)."""
    shown = [o for o in scene.objects if o.type == "MESH" and not o.hide_render
             and o.get("ease_role") in ("body", "garment", "pattern_panel")]
    if not shown:
        return np.array([-0.5, -0.3, 0.0]), np.array([0.5, 0.3, 1.8])
    return world_bounds(shown)


def _studio_object(scene, name, data):
    coll = collection(scene)
    obj = bpy.data.objects.get(name)
    if obj is None:
        obj = bpy.data.objects.new(name, data)
        coll.objects.link(obj)
    obj["ease_role"] = "studio"
    return obj


def setup_studio(scene, samples: int = 16, resolution_pct: int = 50) -> None:
    """Camera in front of the body (-Y) framing the body, garment and pattern
    pieces, key/fill/rim lights, grey world, Cycles CPU with ``samples``
    samples at ``resolution_pct`` % of a 1200-pixel-high frame."""
    lo, hi = scene_bounds(scene)
    centre = (lo + hi) / 2
    w, h = float(max(hi[0] - lo[0], 0.3)), float(max(hi[2] - lo[2], 0.3))
    # frame aspect follows the content (portrait for a body, landscape with the pattern beside it)
    aspect = min(max(w / h, 0.8), 1.8)
    res_y = 1200
    res_x = int(round(res_y * aspect / 2) * 2)
    cam_data = bpy.data.cameras.get(STUDIO + " Camera") or bpy.data.cameras.new(STUDIO + " Camera")
    cam_data.lens = 50.0
    cam_data.sensor_fit = "AUTO"      # the 36 mm sensor spans the larger image side
    cam = _studio_object(scene, STUDIO + " Camera", cam_data)
    big = 0.5 * 36.0 / 50.0
    tan_h = big if res_x >= res_y else big * res_x / res_y
    tan_v = big if res_y >= res_x else big * res_y / res_x
    dist = 1.08 * max(0.5 * w / tan_h, 0.5 * h / tan_v)
    cam.location = (float(centre[0]), float(lo[1] - dist), float(centre[2]))
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.camera = cam
    for name, energy, loc, rot in (("Key", 250.0, (-1.5, -2.5, 2.6), (math.radians(55), 0, math.radians(-30))),
                                   ("Fill", 90.0, (2.0, -2.0, 1.6), (math.radians(65), 0, math.radians(45))),
                                   ("Rim", 180.0, (0.5, 2.5, 2.4), (math.radians(-55), 0, math.radians(170)))):
        ld = bpy.data.lights.get(f"{STUDIO} {name}") or bpy.data.lights.new(f"{STUDIO} {name}", "AREA")
        ld.energy = energy
        ld.size = 1.5
        lo_obj = _studio_object(scene, f"{STUDIO} {name}", ld)
        lo_obj.location = (centre[0] + loc[0], centre[1] + loc[1], loc[2])
        lo_obj.rotation_euler = rot
    world = scene.world or bpy.data.worlds.new(STUDIO + " World")
    scene.world = world
    ensure_nodes(world)
    bg = world.node_tree.nodes.get("Background")
    if bg is not None:
        bg.inputs["Color"].default_value = (0.6, 0.6, 0.62, 1.0)
        bg.inputs["Strength"].default_value = 0.45
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(samples)
    scene.cycles.use_denoising = False
    if hasattr(scene.cycles, "use_adaptive_sampling"):
        scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x = res_x
    scene.render.resolution_y = res_y
    scene.render.resolution_percentage = int(resolution_pct)
    scene.render.image_settings.file_format = "PNG"
    scene.render.film_transparent = False


def render_png(scene, path: str) -> str:
    """Render the scene's camera to ``path`` (PNG, absolute or relative to a saved .blend);
    the file appears only when complete."""
    path = data.output_path(path, "Render to")
    if not path.lower().endswith(".png"):
        path += ".png"
    os.makedirs(os.path.dirname(os.path.abspath(path)) or ".", exist_ok=True)
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)), ".ease_render_tmp.png")
    old = scene.render.filepath
    scene.render.filepath = tmp
    try:
        bpy.ops.render.render(write_still=True, scene=scene.name)
    finally:
        scene.render.filepath = old
    if not os.path.exists(tmp):
        raise state.AddonError(f"render wrote no image to {path}")
    os.replace(tmp, path)
    return path


class EASE_OT_studio_setup(EaseOperator):
    """Set up the studio: camera framing the body, lights, Cycles CPU with few samples"""
    bl_idname = "ease.studio_setup"
    bl_label = "Studio Preset"

    def run(self, context):
        s = context.scene.ease
        setup_studio(context.scene, s.render_samples, s.render_resolution)


class EASE_OT_render(EaseOperator):
    """Render the studio camera to a PNG file"""
    bl_idname = "ease.render"
    bl_label = "Render PNG"
    needs = ('content',)

    def run(self, context):
        s = context.scene.ease
        data.output_path(s.render_path, "Render to")      # before the studio changes the scene
        if context.scene.camera is None or STUDIO not in context.scene.camera.name:
            setup_studio(context.scene, s.render_samples, s.render_resolution)
        path = render_png(context.scene, s.render_path)
        self.report({"INFO"}, f"rendered {path}")


CLASSES = (EASE_OT_studio_setup, EASE_OT_render)
