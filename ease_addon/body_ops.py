"""Body stage: add the default body (or an SMPL/OBJ file), shape it by
phenotype sliders, measurements or size presets, pose it. Shape and pose
changes move the vertices in place (:func:`.sync.update_body`), so the ease
layer, the keypoint layers and everything attached to the body stay. *Apply Size*
and *Apply Pose* are jobs (:mod:`.jobs`, as Drape): the body's vertices are computed in a
worker (progress in the status bar, Esc cancels) and written in one pass when they land."""

from __future__ import annotations

import bpy

from . import data, jobs, state, sync
from .operators_base import EaseOperator

JOB = "body"  # the job of Apply Size / Apply Pose (a newer one replaces a running one)


def start_body(context, shape=None, pose=None, size=None, sync_=None, fit=None) -> jobs.Job:
    """Reshape (``shape``, with its chart ``size`` or None) and/or repose (``pose``) the scene's
    body as the job :data:`JOB`: its vertices computed off the main thread (``sync_``:
    :func:`.jobs.start`'s ``sync``), then the body, its attachments and the Body panel updated
    in one pass. ``fit(progress)``: the shape is computed in the worker too, ``(shape, the
    measurements line or None)`` (a size of a body that is not Anny's, Fit Measurements). Landing
    on a body that changed meanwhile (removed, another model, another shape or pose than the one
    it was computed from) it says so and changes nothing."""
    obj = data.body_object(context)
    spec = data.body_spec(obj)
    model_name, base = spec["model"], dict(spec)
    want = dict(spec)
    if shape is not None:
        want["shape"] = {k: float(v) for k, v in shape.items()}
    if pose is not None:
        want["pose"] = pose
    reshape = shape is not None or fit is not None
    what = (f"size {size}" if size else "shape") if reshape else f"pose {pose}"
    threaded = not jobs.in_line(sync_)

    def compute(progress):
        report = None
        if fit is not None:
            progress(0.0, f"fitting the body's {what}")
            got, report = fit(progress)
            want["shape"] = {k: float(v) for k, v in got.items()}
        progress(0.0, f"the body in {what}")
        verts = sync.body_vertices(want)
        if not reshape or report is not None:
            return verts, report
        progress(0.5, "measuring the body")
        return verts, sync.measurements_report(want)

    def apply(result):
        verts, report = result
        ctx = bpy.context
        body = data.body_object(ctx)
        now = data.body_spec(body)
        if now["model"] != model_name or now["shape"] != base["shape"] or now["pose"] != base["pose"]:
            raise state.AddonError(f"the body changed while its {what} was computed: apply it again")
        sync.update_body(ctx, body, shape=want["shape"] if reshape else None, pose=pose, verts=verts)
        s = ctx.scene.ease
        if reshape:
            model = state.body_model(model_name)
            sync.fill_shape_props(ctx.scene, model, want["shape"])
            sync.show_size(ctx.scene, body, size, report)
        if pose is not None:
            s.pose = pose  # the panel shows the body's pose
        if threaded:  # it landed after the operator returned: the panel says what changed
            s.job_status = what + (f": {s.measurements_report}" if reshape else "")

    return jobs.start_step(JOB, f"the body in {what}", compute, apply, "job_status", f"Apply {what}", sync=sync_)


def start_add_body(context, name: str, sync_=None) -> tuple:
    """*Add Body*'s job: the body model ``name`` ("anny" or a file) loaded, its vertices in the
    panel's pose and, with a design, the design's cut and keypoints on it computed in a worker;
    then the body replaces the scene's (no ``.001``) with the design on it, in one pass.
    ``(job, said)``: ``said`` holds ``(level, report)`` lines once done."""
    import numpy as np

    s = context.scene.ease
    pose = s.pose
    design = data.current_design(context) if s.design_json else None
    said = []
    threaded = not jobs.in_line(sync_)

    def compute(progress):
        progress(0.0, f"loading the body {name}")
        model = state.body_model(name)
        shape = dict(model.default_shape())
        verts = sync.body_vertices({"model": name, "shape": shape, "pose": pose})
        # Anny's default shape is the chart's M: the Body panel's measurements line, measured
        # here (the first measure of a model finds its torso's edges: 100 ms on the main thread)
        report = sync.measurements_report({"model": name, "shape": shape}) if name == "anny" else None
        if design is None:
            return verts, report, None, None
        progress(0.6, "the design on the new body")
        try:
            data.cut_on(design, name, shape)  # (kept: the placing pass cuts nothing)
            mesh = np.asarray(verts, dtype=np.float32).astype(np.float64)  # as the mesh will hold them
            return verts, report, data.resolved_keypoints(design, model, mesh), None
        except state.USER_ERRORS as exc:
            return verts, report, None, exc

    def apply(result):
        verts, report, kps, refused = result
        ctx = bpy.context
        old = data.body_object(ctx, required=False)
        obj = sync.new_body(ctx, name, pose=pose, replaces=old, verts=verts, report=report)
        if design is not None and refused is None:
            # the design's keypoints, seamlines and ease on the new body, as after loading it
            try:
                sync.set_design(ctx, data.current_design(ctx), keypoints=kps)
            except state.USER_ERRORS as exc:
                refused = exc
            else:
                sync.ease_from_design(ctx)
        if refused is not None:
            said.append(("WARNING", f"the design does not fit the new body, load it again: {refused}"))
        said.append(("INFO", f"added body {name} ({len(obj.data.vertices)} vertices)"))
        if threaded:
            ctx.scene.ease.job_status = "; ".join(text for _, text in said)

    job = jobs.start_step(JOB, f"adding the body {name}", compute, apply, "job_status", "Add Body", sync=sync_)
    return job, said


class EASE_OT_add_body(jobs.Background, EaseOperator):
    """Add the default body (Anny) or a body file to the scene (in the background: Esc cancels)"""

    bl_idname = "ease.add_body"
    bl_label = "Add Body"

    source: bpy.props.EnumProperty(
        items=[
            ("DEFAULT", "Default body", "Anny, embedded"),
            ("FILE", "Body file", "the SMPL/SMPL-X/OBJ file set in the panel"),
        ],
        default="DEFAULT",
    )

    def run(self, context):
        s = context.scene.ease
        if self.source == "FILE":
            if not s.body_file:
                raise state.AddonError("set a body file (SMPL .npz/.pkl or .obj) first")
            name = bpy.path.abspath(s.body_file)
        else:
            name = "anny"
        job, said = start_add_body(context, name, sync_=self.job_sync())
        if not said:
            self.report({"INFO"}, f"adding the body {name} in the background (Esc cancels)")
        for level, text in said:
            self.report({level}, text)


class EASE_OT_set_size(jobs.Background, EaseOperator):
    """Shape the body to a size preset of the chosen size chart (default XS..XL, women's, men's; in the background: Esc cancels)"""

    bl_idname = "ease.set_size"
    bl_label = "Apply Size"
    needs = ("body", "size")

    size: bpy.props.StringProperty(default="")

    def run(self, context):
        from ..core.body.sizes import size_of, size_shape

        obj = data.body_object(context)
        s = context.scene.ease
        size = self.size or s.size
        size = size_of(size, s.chart)  # "women:M" on the women's chart
        model = state.body_model(data.body_spec(obj)["model"])
        # (a body that is not Anny's is fitted to the size's measurements: in the worker too)
        job = start_body(
            context, size=size, sync_=self.job_sync(), fit=lambda progress: (size_shape(model, size), None)
        )
        self.report(
            {"INFO"},
            f"size {size}: {s.measurements_report}"
            if job.thread is None
            else f"size {size} in the background (Esc cancels)",
        )


def start_fit(context, sync_=None) -> jobs.Job:
    """*Fit Measurements*' job: the body's shape fitted to the Body panel's targets (cm), its
    vertices and the achieved measurements computed in a worker (:func:`start_body`)."""
    from ..core.body.sizes import fit_measurements

    s = context.scene.ease
    model = state.body_model(data.body_spec(data.body_object(context))["model"])
    targets = {"height": s.height_cm, "chest": s.chest_cm, "waist": s.waist_cm, "hip": s.hip_cm}

    def fit(progress):
        res = fit_measurements(model, targets, progress=progress)
        achieved = {
            k: f"{v:.1f} cm" + (f" ({res.status[k]})" if k in res.status else "") for k, v in res.achieved.items()
        }
        return res.shape, data.format_measurements(achieved)

    return start_body(context, sync_=sync_, fit=fit)


class EASE_OT_fit_measurements(jobs.Background, EaseOperator):
    """Fit the body's shape to the target measurements (cm) (in the background: Esc cancels)"""

    bl_idname = "ease.fit_measurements"
    bl_label = "Fit Measurements"
    needs = ("body",)

    def run(self, context):
        job = start_fit(context, sync_=self.job_sync())
        s = context.scene.ease
        self.report(
            {"INFO"},
            f"fitted: {s.measurements_report}" if job.thread is None else "fitting in the background (Esc cancels)",
        )


class EASE_OT_measure(EaseOperator):
    """Measure the body (height, chest/bust, waist, hip circumferences in cm)"""

    bl_idname = "ease.measure"
    bl_label = "Measure"
    needs = ("body",)

    def run(self, context):
        spec = data.body_spec(data.body_object(context))
        achieved = data.measurements(state.body_model(spec["model"]), spec["shape"])
        context.scene.ease.measurements_report = data.format_measurements(achieved)
        self.report({"INFO"}, context.scene.ease.measurements_report)


class EASE_OT_set_pose(jobs.Background, EaseOperator):
    """Pose the body (A, T, P1-P3); the design stays attached (in the background: Esc cancels)"""

    bl_idname = "ease.set_pose"
    bl_label = "Apply Pose"
    needs = ("body",)

    pose: bpy.props.StringProperty(default="")

    def run(self, context):
        pose = self.pose or context.scene.ease.pose
        job = start_body(context, pose=pose, sync_=self.job_sync())
        self.report({"INFO"}, f"pose {pose}" if job.thread is None else f"pose {pose} in the background (Esc cancels)")


class EASE_OT_apply_shape(EaseOperator):
    """Apply the phenotype sliders to the body"""

    bl_idname = "ease.apply_shape"
    bl_label = "Apply Shape"
    needs = ("body",)

    def run(self, context):
        obj = data.body_object(context)
        shape = {i.name: float(i.value) for i in context.scene.ease.shape}
        sync.update_body(context, obj, shape=shape)


CLASSES = (
    EASE_OT_add_body,
    EASE_OT_set_size,
    EASE_OT_fit_measurements,
    EASE_OT_measure,
    EASE_OT_set_pose,
    EASE_OT_apply_shape,
)
