"""Render stage: the studio preset (:mod:`.render_studio`: set, light rig, front / 3/4 /
back cameras, Cycles with adaptive sampling and denoising), the garment dressed in its
fabric (:mod:`.render_fabric`), PNG renders of one view or all, and a turntable."""

from __future__ import annotations

import os

import bpy

from . import data, render_fabric, render_studio, state
from .objects import window_progress
from .operators_base import EaseOperator

VIEW_FILES = {"FRONT": "front", "THREE_QUARTER": "three_quarter", "BACK": "back"}


def setup_studio(scene, samples: int = 32, resolution_pct: int = 100, view: str = "FRONT") -> list:
    """The studio for the scene's content and the garment's fabric; the names of the objects
    not made by EASE that were hidden from the render (:func:`.render_studio.clear_set`)."""
    render_fabric.dress_garments(scene)
    return render_studio.setup(scene, samples, resolution_pct, view)


def _ready(scene, s) -> list:
    """Studio made (once), garment dressed, the panel's samples and size applied; hidden names."""
    if (
        bpy.data.objects.get(render_studio.camera_name("FRONT")) is None
        or render_studio.camera_name("FRONT") not in scene.objects
    ):
        return setup_studio(scene, s.render_samples, s.render_resolution)
    render_fabric.dress_garments(scene)
    scene.cycles.samples = int(s.render_samples)
    scene.render.resolution_percentage = int(s.render_resolution)
    lo_hi = render_studio.subject_points(scene)
    return render_studio.clear_set(scene, 0.5 * (lo_hi.min(axis=0) + lo_hi.max(axis=0)))


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


def view_paths(path: str, view: str) -> list:
    """[(view, file)] that a render of ``view`` writes: ``path`` itself for one view, and
    ``<stem>_front.png``, ``<stem>_three_quarter.png``, ``<stem>_back.png`` for ALL."""
    if view != "ALL":
        return [(view, path)]
    stem = path[:-4] if path.lower().endswith(".png") else path
    return [(v, f"{stem}_{name}.png") for v, name in VIEW_FILES.items()]


def _hidden_note(hidden: list) -> str:
    if not hidden:
        return ""
    return f"; hid from the render {len(hidden)} object(s) not made by EASE that stood in the studio: " + ", ".join(
        hidden
    )


class EASE_OT_studio_setup(EaseOperator):
    """Set up the studio: a floor and backdrop, soft area lights, front / 3/4 / back cameras framing
    the body and garment, the garment in its fabric, Cycles with adaptive sampling and denoising"""

    bl_idname = "ease.studio_setup"
    bl_label = "Studio Preset"

    def run(self, context):
        s = context.scene.ease
        view = s.render_view if s.render_view in render_studio.VIEWS or s.render_view == "PATTERN" else "FRONT"
        if (
            view == "PATTERN"
            and bpy.data.objects.get(render_studio.camera_name("PATTERN")) is None
            and not [o for o in context.scene.objects if o.get("ease_role") == "pattern_panel"]
        ):
            view = "FRONT"
        hidden = setup_studio(context.scene, s.render_samples, s.render_resolution, view)
        device = render_studio.gpu_name() or "CPU"
        self.report({"INFO"}, f"studio ready: front, 3/4, back cameras, Cycles on {device}" + _hidden_note(hidden))


def _use_view(scene, view: str) -> None:
    try:
        render_studio.use_view(scene, view)
    except KeyError:
        raise state.AddonError(
            f"no {view.lower()} camera: the scene has no pattern pieces (EASE > Pattern) to show"
        ) from None


def render_shots(context, shots) -> tuple:
    """Render ``shots`` [(message, place the camera: f(scene), path)] one after the other with the
    studio ready (:func:`_ready`) and the window's progress; the scene camera and what the render
    shows are put back after. Returns (paths written, names hidden from the render)."""
    s, scene = context.scene.ease, context.scene
    data.output_path(s.render_path, "Render to")  # before the studio changes the scene
    hidden = _ready(scene, s)
    old = scene.camera
    written = []
    with window_progress(context) as progress:
        try:
            for i, (message, place, path) in enumerate(shots):
                progress(i / len(shots), message)
                place(scene)
                written.append(render_png(scene, path))
        finally:
            if old is not None and old.name in scene.objects:
                scene.camera = old
                render_studio.show_for(scene, old.get("ease_view", "FRONT"))
    return written, hidden


class EASE_OT_render(EaseOperator):
    """Render the studio camera of the chosen view (or front, 3/4 and back) to PNG"""

    bl_idname = "ease.render"
    bl_label = "Render PNG"
    needs = ("content", "render_path")

    def run(self, context):
        s = context.scene.ease
        shots = [
            (f"rendering {view.lower()}", lambda scene, v=view: _use_view(scene, v), path)
            for view, path in view_paths(s.render_path, s.render_view)
        ]
        written, hidden = render_shots(context, shots)
        if s.render_view != "ALL":  # the view rendered stays the scene camera
            _use_view(context.scene, s.render_view)
        self.report({"INFO"}, "rendered " + ", ".join(written) + _hidden_note(hidden))


class EASE_OT_render_turntable(EaseOperator):
    """Render a full turn around the body: Turntable frames PNGs <Render to>_0001.png, ..."""

    bl_idname = "ease.render_turntable"
    bl_label = "Render Turntable"
    needs = ("content", "render_path")

    def run(self, context):
        s = context.scene.ease
        base = data.output_path(s.render_path, "Render to")
        stem = base[:-4] if base.lower().endswith(".png") else base
        n = int(s.render_turntable_frames)
        shots = [
            (
                f"turntable frame {i + 1}/{n}",
                lambda scene, a=360.0 * i / n: render_studio.turntable_camera(scene, a),
                f"{stem}_{i + 1:04d}.png",
            )
            for i in range(n)
        ]
        written, hidden = render_shots(context, shots)
        self.report({"INFO"}, f"rendered {len(written)} frames {written[0]} .. {written[-1]}" + _hidden_note(hidden))


CLASSES = (EASE_OT_studio_setup, EASE_OT_render, EASE_OT_render_turntable)
