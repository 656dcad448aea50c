"""The studio the add-on renders in: a set, a light rig, cameras, Cycles settings.

Everything here is made by name and reused, so running the preset again moves
the same objects (role ``studio``) instead of adding new ones:

- the set: a seamless cyclorama (a floor curving up into a round wall, 6 m
  radius, matte light grey) centred under the body, its floor at the body's
  feet, so every camera sees the same soft backdrop and the floor catches the
  body's contact shadow;
- the light rig: a large soft key (front left, high), a fill (front right), a
  rim (behind) and a top light, all area lights, plus a dim world;
- cameras (:data:`VIEWS`): front, three-quarter (front right) and back, each
  framing the body and garment with a margin, the feet's shadow on the floor
  in frame; the pattern view looks straight at the pattern pieces, with an
  orthographic camera;
- Cycles: adaptive sampling, OpenImageDenoise, capped bounces, a
  1080 x 1440 (portrait) frame at the Resolution % of the panel.

Objects that are not the add-on's and stand in the set (the startup file's
cube and light, say) are hidden from the render (``hide_render``; they stay
in the file and in the viewport): :func:`clear_set` returns their names for the
operator to report.
"""

from __future__ import annotations

import math

import bpy
import numpy as np

from . import convert, materials
from .objects import collection, world_bounds

STUDIO = "EASE Studio"
SET = STUDIO + " Set"
WIDTH, HEIGHT = 1080, 1440  # default frame, pixels (portrait)
SET_RADIUS = 6.0  # m: cyclorama floor + cove radius
COVE = 1.5  # m: radius of the curve from floor to wall
WALL = 5.0  # m: wall height above the floor
MARGIN = 1.08  # framing margin over the tightest fit
PITCH = math.radians(9.0)  # cameras look down this much
VIEWS = {  # view -> azimuth (degrees from the front, towards the body's left)
    "FRONT": 0.0,
    "THREE_QUARTER": 40.0,
    "BACK": 180.0,
}
PATTERN_VIEW = "PATTERN"
BODY_ROLES = ("body", "garment")
MOTION_ROLE = "motion"  # Drape Animation's body and garment (motion_ops)
PATTERN_ROLES = ("pattern_panel", "pattern_panel_part")
LIGHTS = (  # name, watts, size (m), azimuth (deg from front), elevation (deg), distance (m), colour
    ("Key", 190.0, 1.0, -25.0, 55.0, 3.2, (1.0, 0.96, 0.90)),
    ("Fill", 30.0, 2.5, 55.0, 15.0, 3.5, (0.92, 0.95, 1.0)),
    ("Rim", 160.0, 1.2, 160.0, 35.0, 3.0, (1.0, 1.0, 1.0)),
    ("Top", 170.0, 0.6, 0.0, 88.0, 2.2, (1.0, 1.0, 1.0)),
)


def camera_name(view: str) -> str:
    return f"{STUDIO} Camera {view.replace('_', ' ').title()}"


def _object(scene, name, datablock):
    obj = bpy.data.objects.get(name)
    if obj is None:
        obj = bpy.data.objects.new(name, datablock)
    elif obj.data != datablock:
        obj.data = datablock
    coll = collection(scene)
    if obj.name not in coll.objects:
        coll.objects.link(obj)
    obj["ease_role"] = "studio"
    return obj


def _role_objects(scene, roles):
    return [o for o in scene.objects if o.get("ease_role") in roles]


def subject_points(scene) -> np.ndarray:
    """(n, 3) world points the body cameras frame: the body's and the garment's vertices
    (subsampled; a Drape Animation's at its first frame too), the bounds' corners when there
    are no meshes."""
    pts = []
    for o in _role_objects(scene, BODY_ROLES + (MOTION_ROLE,)):
        if o.type != "MESH" or not len(o.data.vertices):
            continue
        co = np.empty(len(o.data.vertices) * 3, dtype=np.float64)
        o.data.vertices.foreach_get("co", co)
        co = co.reshape(-1, 3)[:: max(1, len(o.data.vertices) // 4000)]
        m = np.array(o.matrix_world, dtype=np.float64)
        pts.append(co @ m[:3, :3].T + m[:3, 3])
    if not pts:
        return np.array([[x, y, z] for x in (-0.3, 0.3) for y in (-0.2, 0.2) for z in (0.0, 1.75)])
    return np.vstack(pts)


def _look(direction: np.ndarray) -> tuple:
    """Euler XYZ of a camera looking along ``direction`` (unit), its up towards +Z."""
    from mathutils import Vector

    return tuple(Vector(direction).to_track_quat("-Z", "Y").to_euler())


def frame_distance(points: np.ndarray, target: np.ndarray, forward: np.ndarray, tan_h: float, tan_v: float) -> float:
    """Distance from ``target`` back along ``forward`` at which a perspective camera of half-angle
    tangents ``tan_h``, ``tan_v`` sees every one of ``points``."""
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = points - target
    x, y, z = rel @ right, rel @ up, rel @ forward
    return float(max((np.abs(x) / tan_h - z).max(), (np.abs(y) / tan_v - z).max(), 0.5))


def place_camera(scene, view: str, points: np.ndarray, floor_z: float):
    """The camera of ``view`` (:data:`VIEWS`) framing ``points`` from its azimuth."""
    res_x, res_y = scene.render.resolution_x, scene.render.resolution_y
    name = camera_name(view)
    cd = bpy.data.cameras.get(name) or bpy.data.cameras.new(name)
    cd.type, cd.lens, cd.sensor_fit, cd.sensor_width = "PERSP", 70.0, "AUTO", 36.0
    cd.clip_start, cd.clip_end = 0.05, 100.0
    cam = _object(scene, name, cd)
    big = 0.5 * cd.sensor_width / cd.lens
    aspect = res_x / res_y
    tan_h, tan_v = (big, big / aspect) if aspect >= 1 else (big * aspect, big)
    lo, hi = points.min(axis=0), points.max(axis=0)
    # the floor around the feet is in frame too: its contact shadow is the body's footing
    feet = np.array([[lo[0] - 0.15, 0.5 * (lo[1] + hi[1]), floor_z], [hi[0] + 0.15, 0.5 * (lo[1] + hi[1]), floor_z]])
    pts = np.vstack([points, feet])
    target = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    az = math.radians(VIEWS[view])
    forward = np.array([-math.sin(az) * math.cos(PITCH), math.cos(az) * math.cos(PITCH), -math.sin(PITCH)])
    dist = frame_distance(pts, target, forward, tan_h / MARGIN, tan_v / MARGIN)
    # centre the content: shift the target to the middle of what the camera sees
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    eye = target - forward * dist
    rel = pts - eye
    depth = rel @ forward
    sx, sy = (rel @ right) / depth, (rel @ up) / depth
    target = target + right * 0.5 * (sx.max() + sx.min()) * dist + up * 0.5 * (sy.max() + sy.min()) * dist
    dist = frame_distance(pts, target, forward, tan_h / MARGIN, tan_v / MARGIN)
    cam.location = tuple(target - forward * dist)
    cam.rotation_euler = _look(forward)
    cam["ease_view"] = view
    return cam


def place_pattern_camera(scene):
    """An orthographic camera straight at the pattern pieces (None when there are none)."""
    pieces = [o for o in _role_objects(scene, PATTERN_ROLES)]
    if not pieces:
        return None
    lo, hi = world_bounds(pieces)
    res_x, res_y = scene.render.resolution_x, scene.render.resolution_y
    name = camera_name(PATTERN_VIEW)
    cd = bpy.data.cameras.get(name) or bpy.data.cameras.new(name)
    cd.type, cd.sensor_fit = "ORTHO", "AUTO"
    w, h = float(hi[0] - lo[0]), float(hi[2] - lo[2])
    cd.ortho_scale = MARGIN * max(w, h * res_x / res_y) if res_x >= res_y else MARGIN * max(h, w * res_y / res_x)
    cd.clip_start, cd.clip_end = 0.05, 100.0
    cam = _object(scene, name, cd)
    cam.location = (0.5 * float(lo[0] + hi[0]), float(lo[1]) - 3.0, 0.5 * float(lo[2] + hi[2]))
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    cam["ease_view"] = PATTERN_VIEW
    return cam


def _cyclorama(name: str, radius: float, cove: float, wall: float, segments: int = 96):
    """A mesh: a round floor of ``radius`` curving up (quarter circle of ``cove``) into a wall of ``wall``."""
    prof = [(0.0, 0.0), (0.5 * (radius - cove), 0.0)]
    for t in np.linspace(0.0, 0.5 * math.pi, 9):
        prof.append((radius - cove + cove * math.sin(t), cove * (1 - math.cos(t))))
    prof.append((radius, wall))
    prof = np.array(prof[1:])  # ring 0 is the centre point
    ang = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    rings = np.stack(
        [
            np.outer(prof[:, 0], np.cos(ang)),
            np.outer(prof[:, 0], np.sin(ang)),
            np.repeat(prof[:, 1:2], segments, axis=1),
        ],
        axis=2,
    ).reshape(-1, 3)
    verts = np.vstack([[0.0, 0.0, 0.0], rings])
    faces = []
    for j in range(segments):
        faces.append((0, 1 + j, 1 + (j + 1) % segments))
    for i in range(len(prof) - 1):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            k = (j + 1) % segments
            faces.append((a + j, b + j, b + k, a + k))
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts.tolist(), [], faces)
    convert.smooth(me)
    me.update()
    return me


def build_set(scene, centre: np.ndarray, floor_z: float):
    """The cyclorama under ``centre`` (x, y) with its floor at ``floor_z``."""
    me = bpy.data.meshes.get(SET)
    if me is None:
        me = _cyclorama(SET, SET_RADIUS, COVE, WALL)
    if not me.materials:
        me.materials.append(materials.floor())
    elif me.materials[0] is None:
        me.materials[0] = materials.floor()
    obj = _object(scene, SET, me)
    obj.location = (float(centre[0]), float(centre[1]), float(floor_z))
    return obj


def build_lights(scene, centre: np.ndarray, height: float) -> list:
    """The area-light rig around ``centre``, aimed at the body's chest (70 % of ``height``)."""
    out = []
    aim = np.array([centre[0], centre[1], centre[2] + 0.2 * height])
    for name, watts, size, az, el, dist, colour in LIGHTS:
        full = f"{STUDIO} {name}"
        ld = bpy.data.lights.get(full) or bpy.data.lights.new(full, "AREA")
        ld.type, ld.energy, ld.color = "AREA", watts, colour
        ld.shape, ld.size = "DISK", size
        obj = _object(scene, full, ld)
        a, e = math.radians(az), math.radians(el)
        pos = aim + dist * np.array([-math.sin(a) * math.cos(e), -math.cos(a) * math.cos(e), math.sin(e)])
        obj.location = tuple(pos)
        obj.rotation_euler = _look((aim - pos) / np.linalg.norm(aim - pos))
        out.append(obj)
    return out


def build_world(scene) -> None:
    from .objects import ensure_nodes

    world = scene.world or bpy.data.worlds.new(STUDIO + " World")
    scene.world = world
    ensure_nodes(world)
    bg = next((n for n in world.node_tree.nodes if n.type == "BACKGROUND"), None)
    if bg is not None:
        bg.inputs["Color"].default_value = (0.55, 0.56, 0.58, 1.0)
        bg.inputs["Strength"].default_value = 0.05


def clear_set(scene, centre: np.ndarray, radius: float = SET_RADIUS) -> list:
    """Hide from the render the objects that are not the add-on's and stand in the set (within
    ``radius`` of ``centre`` across the floor) or light it; returns their names, sorted."""
    hidden = []
    for o in scene.objects:
        if o.get("ease_role") or (o.parent is not None and o.parent.get("ease_role")) or o.hide_render:
            continue
        if o.type in ("CAMERA", "EMPTY", "SPEAKER", "LIGHT_PROBE", "ARMATURE"):
            continue
        if o.type != "LIGHT":
            lo, hi = world_bounds(o)
            near = np.clip(centre[:2], lo[:2], hi[:2])
            if np.linalg.norm(near - centre[:2]) > radius:
                continue
        o.hide_render = True
        hidden.append(o.name)
    return sorted(hidden)


def gpu_name():
    """The name of the GPU Cycles' preferences enable (CUDA, OptiX, HIP, Metal, oneAPI), else None."""
    addon = bpy.context.preferences.addons.get("cycles")
    prefs = getattr(addon, "preferences", None)
    if prefs is None or getattr(prefs, "compute_device_type", "NONE") in ("NONE", ""):
        return None
    used = [d for d in getattr(prefs, "devices", []) if d.use and d.type != "CPU"]
    return used[0].name if used else None


def render_settings(scene, samples: int, resolution_pct: int) -> None:
    """Cycles on the GPU that Blender's preferences enable, else the CPU; adaptive sampling,
    denoising, capped bounces, the 1080 x 1440 frame at ``resolution_pct``, AgX."""
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "GPU" if gpu_name() else "CPU"
    cy.samples = int(samples)
    cy.use_adaptive_sampling = True
    cy.adaptive_threshold = 0.02
    cy.adaptive_min_samples = 0
    cy.use_denoising = True
    cy.denoiser = "OPENIMAGEDENOISE"
    cy.max_bounces, cy.diffuse_bounces, cy.glossy_bounces = 6, 3, 2
    cy.transmission_bounces, cy.volume_bounces, cy.transparent_max_bounces = 2, 0, 4
    cy.caustics_reflective = cy.caustics_refractive = False
    cy.sample_clamp_indirect = 5.0
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = int(resolution_pct)
    scene.render.image_settings.file_format = "PNG"
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "AgX"
    scene.view_settings.look = "AgX - Medium High Contrast"


def show_for(scene, view: str) -> None:
    """Render visibility for ``view``: the pattern pieces only in the pattern view (in the body
    views they would stand beside the body); the body, the garment and the set in the others
    (the pattern view shows the pieces flat on the plain world)."""
    flat = view == PATTERN_VIEW
    for o in _role_objects(scene, PATTERN_ROLES):
        o.hide_render = not flat
    # a Drape Animation's body and garment stand where the static ones do: while they are shown in
    # the viewport they render instead (hide them, the eye in the Outliner, to render the static ones)
    motion = _role_objects(scene, (MOTION_ROLE,))
    shown = [o for o in motion if o.visible_get()]
    for o in _role_objects(scene, BODY_ROLES):
        o.hide_render = flat or bool(shown)
    for o in motion:
        o.hide_render = flat or o not in shown
    if SET in scene.objects:
        scene.objects[SET].hide_render = flat


def setup(scene, samples: int, resolution_pct: int, view: str = "FRONT") -> list:
    """The whole studio for the scene's content; ``view`` becomes the scene camera. Returns the
    names of the foreign objects hidden from the render (:func:`clear_set`)."""
    render_settings(scene, samples, resolution_pct)
    pts = subject_points(scene)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    floor_z = float(lo[2])
    build_set(scene, centre, floor_z - 0.002)
    build_lights(scene, centre, float(hi[2] - lo[2]))
    build_world(scene)
    for v in VIEWS:
        place_camera(scene, v, pts, floor_z)
    place_pattern_camera(scene)
    hidden = clear_set(scene, centre)
    use_view(scene, view)
    return hidden


def use_view(scene, view: str):
    """Make the studio camera of ``view`` the scene camera (and set what it shows)."""
    cam = bpy.data.objects.get(camera_name(view))
    if cam is None or cam.name not in scene.objects:
        raise KeyError(view)
    scene.camera = cam
    show_for(scene, view)
    return cam


def turntable_camera(scene, angle_deg: float):
    """The turntable camera at ``angle_deg`` around the body (0: the front camera's place)."""
    front = bpy.data.objects[camera_name("FRONT")]
    name = camera_name("TURNTABLE")
    cam = _object(scene, name, front.data)
    pts = subject_points(scene)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    axis = 0.5 * (lo + hi)
    rel = np.array(front.location) - axis
    a = math.radians(angle_deg)
    rot = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
    cam.location = tuple(axis + rot @ rel)
    cam.rotation_euler = front.rotation_euler.copy()
    cam.rotation_euler[2] += a
    scene.camera = cam
    show_for(scene, "TURNTABLE")
    return cam
