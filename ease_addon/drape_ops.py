"""Drape stage: drape the pattern on the body as a background job (:mod:`.jobs`: the core in a
worker thread, its progress per frame in the status bar, Esc cancels and nothing is applied; in
line from a script or headless). The result is a garment object with a fabric material, two
fit-map colour layers (strain, gap) and the pattern vertex id of each vertex
(``ease_vertex_id``, read back by the export); see :func:`.build.garment`. The drape and its fit
measurements are the core's (:func:`core.workflows.drape`)."""

from __future__ import annotations

import json

import bpy

from . import build, data, jobs, state, sync
from .operators_base import EaseOperator

JOB = "drape"  # the job's name (a new Drape replaces a running one)


def _compute(
    pattern, body_v, body_f, frames, progress, device="cpu", refine_edge=None, solver="default", hold_pins=False
):
    """The core's drape of ``pattern`` on the body (V, F) and its fit measurements (a DrapeRun);
    ``refine_edge`` (m, or None): the drape mesh's longest edge where the cloth hangs free;
    ``solver``: ``DrapeOptions.solver``, or ``"default"`` for the core's default; ``hold_pins``:
    ``DrapeOptions.hold_pins``."""
    from ..core import workflows as wf

    options = {**data.drape_options(device, solver, hold_pins), "max_frames": int(frames), "refine_edge": refine_edge}
    return wf.drape(pattern, options=options, body=(body_v, body_f), progress=progress)


def refine_edge(mm: float):
    """The core's ``refine_edge`` (m, or None for 0) of the Drape panel's *Refine (mm)*, checked."""
    if not mm:
        return None
    if not 1.0 <= mm <= 100.0:
        raise state.AddonError(f"Refine (mm) = {mm:g}: expected 0 (the pattern's mesh) or 1 to 100 mm")
    return mm / 1000.0


def start_drape(
    pattern,
    body_v,
    body_f,
    frames: int,
    device: str = "cpu",
    digest=None,
    sync=None,
    refine=None,
    solver="default",
    hold_pins=False,
) -> jobs.Job:
    """The drape of ``pattern`` on the body (V, F) for at most ``frames`` frames as the job
    :data:`JOB` (``sync``: :func:`.jobs.start`'s); the garment is made when it lands.
    ``digest``: the pattern it drapes (the scene's may change meanwhile); ``refine``: the drape
    mesh's refinement edge (m, or None: the pattern's mesh); ``solver``, ``hold_pins``: :func:`_compute`'s. ``pattern``'s body record goes with
    the job: the body takes the draped pattern's size and pose when the garment lands, whatever
    pattern the scene holds by then (a Transfer landing meanwhile)."""
    body = dict(pattern.body or {})
    return jobs.start_step(
        JOB,
        "drape",
        lambda progress: _compute(pattern, body_v, body_f, frames, progress, device, refine, solver, hold_pins),
        lambda run: apply_drape(bpy.context, run, digest=digest, body=body),
        "drape_status",
        "Drape",
        sync=sync,
    )


class EASE_OT_drape(jobs.Background, EaseOperator):
    """Drape the pattern on the body (in the background: Esc cancels)"""

    bl_idname = "ease.drape"
    bl_label = "Drape"
    needs = ("pattern",)

    def run(self, context):
        from ..core.workflows._drape import pattern_body

        pattern = data.required_pattern(context.scene, "to drape")
        body_v, body_f = pattern_body(pattern, "Drape", state.AddonError)  # the body it was solved on
        s = context.scene.ease
        # the pattern may change while the drape runs: the garment records the one it was draped from
        digest = data.pattern_digest(context.scene.get(data.PATTERN_KEY, ""))
        refine = refine_edge(s.drape_refine_mm)
        job = start_drape(
            pattern,
            body_v,
            body_f,
            s.drape_frames,
            s.drape_device,
            digest,
            sync=self.job_sync(),
            refine=refine,
            solver=s.drape_solver,
            hold_pins=s.drape_hold_pins,
        )
        self.report({"INFO"}, s.drape_status if job.thread is None else "draping in the background (Esc cancels)")


def apply_drape(context, run, digest=None, body=None) -> None:
    """Show a finished drape (a :class:`core.workflows.DrapeRun`): the body it was draped on,
    the garment object with its fit maps, the report (main thread). ``digest``: the pattern
    it was draped from (default: the scene's pattern now); ``body``: that pattern's body
    record (default: the scene's pattern's now)."""
    from ..core.body.instance import instance_shape

    scene = context.scene
    obj = data.body_object(context, required=False)
    pspec = (body if body is not None else data.stored_pattern(scene).body) or {}
    moved = []  # what of the body changed: said in the status line
    if obj is not None:
        spec = data.body_spec(obj)
        model = state.body_model(spec["model"])
        shape = instance_shape(model, pspec.get("shape"))
        pose = pspec.get("pose") or "A"
        if shape and data.full_shape(model, shape) != data.full_shape(model, spec["shape"]):
            moved.append(f"size {pspec.get('size') or 'of the pattern'}")
        if isinstance(pose, str) and pose != spec["pose"]:
            moved.append(
                f"pose {pose} (it was {spec['pose']}; the pattern is solved in {pose}: "
                f"Adapt to Poses, then drape, for another pose)"
            )
        if moved:
            sync.update_body(
                context, obj, shape=dict(shape) if shape else None, pose=pose if isinstance(pose, str) else None
            )
            show_body(scene, obj, model, pspec)
    build.garment(
        scene, run.result, run.metrics["vertex_gap"], digest or data.pattern_digest(scene.get(data.PATTERN_KEY, ""))
    )
    sync.apply_fitmap(scene)
    s = scene.ease
    options = getattr(run.result, "options", None) or {}
    solver = options.get("solver")
    s.drape_json = json.dumps(
        {**run.figures, **({"solver": solver} if solver else {}), "hold_pins": bool(options.get("hold_pins"))}
    )
    ref = run.result.refinement or {}
    refined = (
        f", mesh refined to {1000 * ref['target_edge_m']:g} mm "
        f"({ref['triangles_before']} -> {len(run.result.faces)} triangles)"
        if ref
        else ""
    )
    s.drape_status = f"draped: {run.figures['frames']} frames, {run.figures['settled']}{refined}" + (
        f"; the body takes the pattern's {', '.join(moved)}" if moved else ""
    )


def show_body(scene, obj, model, pspec: dict) -> None:
    """The Body panel follows the body the garment was draped on (a transferred pattern's
    size, an adapted one's pose): phenotype sliders, chart and size, pose and measurements."""
    from ..core.body.sizes import check_size

    s = scene.ease
    spec = data.body_spec(obj)
    sync.fill_shape_props(scene, model, spec["shape"])
    size = pspec.get("size")
    try:
        size = check_size(size) if isinstance(size, str) else None
    except state.USER_ERRORS:
        size = None  # a shape of no chart size
    sync.show_size(scene, obj, size)
    if spec["pose"] in {i.identifier for i in s.bl_rna.properties["pose"].enum_items}:
        s.pose = spec["pose"]


class EASE_OT_fitmap(EaseOperator):
    """Colour the garment by strain, gap or plain fabric"""

    bl_idname = "ease.fitmap"
    bl_label = "Fit Map"
    needs = ("garment",)

    mode: bpy.props.EnumProperty(items=[("NONE", "Fabric", ""), ("STRAIN", "Strain", ""), ("GAP", "Gap", "")])

    def run(self, context):  # poll (needs garment) has made sure there is a draped garment
        context.scene.ease.fitmap = self.mode  # its update applies the map


CLASSES = (EASE_OT_drape, EASE_OT_fitmap)
