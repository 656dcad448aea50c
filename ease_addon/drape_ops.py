"""Drape stage: drape the pattern on the body as a modal operator (progress
bar, status text, Esc cancels; the core runs in a worker thread and only the
main thread touches Blender data). The result is a garment object with a
fabric material, two fit-map colour layers (strain, gap) and the pattern
vertex id of each vertex (``ease_vertex_id``, read back by the export); see
:func:`.build.garment`. The drape and its fit measurements are the core's
(:func:`core.workflows.drape`)."""

from __future__ import annotations

import json
import threading

import bpy

from . import build, data, state, sync
from .objects import window_progress
from .operators_base import EaseOperator

_JOBS: list = []  # worker jobs running (cancelled on unregister)


class WorkerJob:
    """A core computation in a worker thread; the main thread polls it (:func:`step_job`) and
    applies its result. The drape and Drape Animation (``motion_ops``) are two.

    ``progress`` state (fraction, message) is written by the worker and read by
    the modal operator; :meth:`cancel` makes the worker's next progress call
    raise ``Cancelled``, so the core stops and nothing is applied. A subclass
    gives :meth:`compute` (worker thread: no Blender data) and :meth:`apply`
    (main thread), ``label`` (what the status bar says) and ``status`` (the
    ``scene.ease`` property that shows the outcome).
    """

    label = "drape"
    status = "drape_status"

    def __init__(self, digest=None):
        self.fraction, self.message = 0.0, "starting"
        self.digest = digest  # the stored pattern's digest when the job started
        self.result = None
        self.error = None
        self._cancel = threading.Event()
        self._thread = threading.Thread(target=self._work, daemon=True)

    def compute(self, progress):  # pragma: no cover - overridden
        raise NotImplementedError

    def apply(self, context) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def _progress(self, fraction, message):
        from ..core.errors import Cancelled

        self.fraction, self.message = fraction, message
        if self._cancel.is_set():
            raise Cancelled(f"{self.label} cancelled")

    def _work(self):
        try:
            self.result = self.compute(self._progress)
        except BaseException as exc:  # handed to the main thread
            self.error = exc
        finally:
            if self in _JOBS:
                _JOBS.remove(self)

    def run_here(self, context) -> None:
        """Compute in this thread (scripts, tests: ``execute``) with the window's progress bar, then apply."""
        with window_progress(context) as progress:
            self.result = self.compute(progress)
        self.apply(context)

    def start(self) -> "WorkerJob":
        _JOBS.append(self)
        self._thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    @property
    def cancelled(self) -> bool:
        return self._cancel.is_set()

    def done(self) -> bool:
        return not self._thread.is_alive()

    def join(self, timeout=None) -> None:
        self._thread.join(timeout)


class DrapeJob(WorkerJob):
    """The core's drape of ``pattern`` on the body (V, F) for at most ``frames`` frames."""

    def __init__(self, pattern, body_v, body_f, frames: int, device: str = "cpu", digest=None):
        super().__init__(digest)
        self._args = (pattern, body_v, body_f, frames)
        self._device = device

    def compute(self, progress):
        return _compute(*self._args, progress, self._device)

    def apply(self, context) -> None:
        apply_drape(context, self.result, digest=self.digest)


def cancel_running() -> None:
    for job in list(_JOBS):
        job.cancel()
    for job in list(_JOBS):
        job.join(timeout=30)
    _JOBS.clear()


def _pattern_body(pattern):
    """(vertices, faces) of the body instance the pattern was solved on."""
    from ..core.body.instance import spec_instance

    spec = pattern.body or {}
    return spec_instance(spec, model=state.body_model(spec.get("model", "anny")))


def _compute(pattern, body_v, body_f, frames, progress, device="cpu"):
    """The core's drape of ``pattern`` on the body (V, F) and its fit measurements (a DrapeRun)."""
    from ..core import workflows as wf

    return wf.drape(
        pattern, options={"max_frames": int(frames), "device": device}, body=(body_v, body_f), progress=progress
    )


class JobOperator(EaseOperator):
    """An operator whose work is a :class:`WorkerJob` (:meth:`make_job`): from a script or test
    (``execute``) it runs in the main thread; from the interface (``invoke``) it runs modal, the
    job in a worker thread, its progress in the status bar and the progress bar, Esc cancels."""

    _job = None
    _timer = None

    def make_job(self, context) -> WorkerJob:  # pragma: no cover - overridden
        """The job, not started (main thread: reads the scene; raises a user error to refuse)."""
        raise NotImplementedError

    def finished(self, context, job: WorkerJob) -> None:
        """Report a finished job (both paths)."""
        self.report({"INFO"}, getattr(context.scene.ease, job.status))

    # -- synchronous (scripts, tests): execute
    def run(self, context):
        job = self.make_job(context)
        job.run_here(context)
        self.finished(context, job)

    # -- interactive: invoke + modal, the core in a worker thread
    def invoke(self, context, event):
        try:
            self._job = self.make_job(context).start()
        except state.USER_ERRORS as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.2, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        status = step_job(context, self._job, event.type)
        if status == "RUNNING":
            return {"RUNNING_MODAL"} if event.type in ("ESC", "TIMER") else {"PASS_THROUGH"}
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        if status == "FINISHED":
            state.changed(context.scene)
            self.finished(context, self._job)
            return {"FINISHED"}
        self.report({"WARNING" if self._job.cancelled else "ERROR"}, getattr(context.scene.ease, self._job.status))
        return {"CANCELLED"}


class EASE_OT_drape(JobOperator):
    """Drape the pattern on the body (Esc cancels)"""

    bl_idname = "ease.drape"
    bl_label = "Drape"
    needs = ("pattern",)

    def make_job(self, context) -> DrapeJob:
        pattern = data.required_pattern(context.scene, "to drape")
        body_v, body_f = _pattern_body(pattern)
        s = context.scene.ease
        # the pattern may change while the drape runs: the garment records the one it was draped from
        digest = data.pattern_digest(context.scene.get(data.PATTERN_KEY, ""))
        return DrapeJob(pattern, body_v, body_f, s.drape_frames, s.drape_device, digest)


def apply_drape(context, run, digest=None) -> None:
    """Show a finished drape (a :class:`core.workflows.DrapeRun`): the body it was draped on,
    the garment object with its fit maps, the report (main thread). ``digest``: the pattern
    it was draped from (default: the scene's pattern now)."""
    from ..core.body.instance import instance_shape

    scene = context.scene
    obj = data.body_object(context, required=False)
    pspec = data.stored_pattern(scene).body or {}
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
    s.drape_json = json.dumps(run.figures)
    s.drape_status = f"draped: {run.figures['frames']} frames, {run.figures['settled']}" + (
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


def step_job(context, job: WorkerJob, event_type: str) -> str:
    """One modal step for ``event_type``: Esc cancels; a timer tick shows the
    progress and, once the worker is done, applies the result (main thread).
    Returns ``"RUNNING"``, ``"FINISHED"`` or ``"CANCELLED"``; the job's ``status``
    property says what happened."""
    s = context.scene.ease
    if event_type == "ESC":
        job.cancel()
        setattr(s, job.status, "cancelling...")
    if event_type != "TIMER":
        return "RUNNING"
    try:
        context.window_manager.progress_update(int(100 * job.fraction))
    except Exception:
        pass
    if context.workspace is not None:
        context.workspace.status_text_set(f"EASE {job.label} {100 * job.fraction:.0f}%: {job.message} (Esc cancels)")
    if not job.done():
        return "RUNNING"
    if job.error is not None:
        setattr(s, job.status, f"{job.label} {'cancelled' if job.cancelled else 'stopped'}: {job.error}")
        return "CANCELLED"
    job.apply(context)
    return "FINISHED"


class EASE_OT_fitmap(EaseOperator):
    """Colour the garment by strain, gap or plain fabric"""

    bl_idname = "ease.fitmap"
    bl_label = "Fit Map"
    needs = ("garment",)

    mode: bpy.props.EnumProperty(items=[("NONE", "Fabric", ""), ("STRAIN", "Strain", ""), ("GAP", "Gap", "")])

    def run(self, context):  # poll (needs garment) has made sure there is a draped garment
        context.scene.ease.fitmap = self.mode  # its update applies the map


CLASSES = (EASE_OT_drape, EASE_OT_fitmap)
