"""Heavy work off the main thread: the viewport keeps drawing while the core computes.

A :class:`Job` runs its ``compute(progress)`` (the core's work: a cut, a flattening and
factorisation, a body fit; no ``bpy``) in a Python thread (numpy, scipy's factorisations and
Warp release the GIL in their heavy parts), and its ``apply(result)`` on the main thread, from a
``bpy.app.timers`` poll, in one short pass that writes the result into Blender's data. Meanwhile
the panel (``scene.ease.job_status``) and, with a window, the status bar say "updating: ..."
with the core's progress; *Cancel* (or Esc while :class:`EASE_OT_watch_jobs` runs) stops it: the
core's progress callback raises :class:`core.errors.Cancelled` at its next report, and a result
that still arrives is dropped.

A job of a name replaces a running one of the same name (the newer request wins; the older
result is dropped). Headless runs (``bpy.app.background``: tests, scripts, the CLI's Blender
runs) compute in line (:data:`SYNCHRONOUS`), so their results are deterministic and there when
the call returns; a test of the threaded path sets it to False and calls :func:`wait`.
"""

from __future__ import annotations

import gc
import threading
import time
import traceback

import bpy

from ..core.errors import Cancelled
from . import state

#: compute in line (headless); False: in a worker thread
SYNCHRONOUS = bool(bpy.app.background)
POLL_S = 0.01  # seconds between the main thread's looks at the running jobs

_JOBS: dict = {}  # name -> Job (running)


class Job:
    """One piece of heavy work: ``compute(progress)`` in a thread, ``apply(result)`` on the main thread.

    Attributes
    ----------
    name, label : the job's key and what the status says it does
    fraction, message : the core's last progress report
    cancelled : set by :func:`cancel`; the next progress report raises Cancelled
    result, error : what ``compute`` returned or raised (``error``: the exception, ``trace``: its text)
    seconds : the compute's wall time; cpu_seconds: its thread's CPU time
    """

    def __init__(self, name: str, label: str, compute, apply, fail=None, cancelled=None):
        self.name, self.label = name, label
        self.compute, self.apply, self.fail, self.on_cancel = compute, apply, fail, cancelled
        self.fraction, self.message = 0.0, label
        self.cancelled = False
        self.done = threading.Event()
        self.result = self.error = self.trace = None
        self.seconds = self.cpu_seconds = 0.0
        self.thread = None  # the worker (None: computed in line)

    def progress(self, fraction: float, message: str) -> None:
        """The core's Progress callback (in the worker): records, or raises Cancelled."""
        if self.cancelled:
            raise Cancelled(f"{self.label}: cancelled")
        self.fraction, self.message = float(fraction), str(message)

    def run(self) -> None:
        t0, c0 = time.perf_counter(), time.thread_time()
        try:
            self.result = self.compute(self.progress)
        except BaseException as exc:  # kept for the main thread, which reports it
            self.error, self.trace = exc, traceback.format_exc()
        finally:
            self.seconds, self.cpu_seconds = time.perf_counter() - t0, time.thread_time() - c0
            self.done.set()

    def status(self) -> str:
        return f"updating: {self.label} {100 * self.fraction:.0f} % ({self.message})"


def in_line(sync=None) -> bool:
    """Whether a job computes in line: ``sync`` when given, else :data:`SYNCHRONOUS` (read at call
    time, so a test may switch it)."""
    return SYNCHRONOUS if sync is None else bool(sync)


def start(name: str, label: str, compute, apply, fail=None, sync=None, cancelled=None) -> Job:
    """Run ``compute(progress)`` off the main thread, then ``apply(result)`` on it.

    ``fail(exc)`` (main thread) is told of an error of ``compute`` (default: the status says
    it); ``cancelled()`` (main thread) is told when the designer cancels it (not when a newer job
    of its name replaces it); ``sync``: compute in line (default :data:`SYNCHRONOUS`; an error then raises here, as
    the work would without a job). Returns the job (done already when in line).
    """
    drop(name)
    job = Job(name, label, compute, apply, fail, cancelled)
    if in_line(sync):
        job.run()
        if job.error is not None:  # in line: the caller meets the error as it would without a job
            raise job.error
        job.apply(job.result)
        return job
    _JOBS[name] = job
    settle_heap()
    job.thread = threading.Thread(target=job.run, name=f"ease-{name}", daemon=True)
    job.thread.start()
    if not bpy.app.timers.is_registered(poll):
        bpy.app.timers.register(poll, first_interval=POLL_S)
    _show_status()
    _watch()
    return job


def settle_heap() -> None:
    """Keep Python's full garbage collections short while a worker runs (issue 32).

    A collection of the oldest generation walks every tracked object of the process (Blender's,
    numpy's, scipy's, Warp's modules and the add-on's: about 180k, 60-70 ms) holding the GIL; in a
    worker it stalls the main thread as long, a viewport tick over 50 ms with no CPU of its own.
    Here, on the main thread as the add-on registers, as a job starts and once jobs' results
    landed: a young collection (a few ms: what just died in a cycle is freed) and
    :func:`gc.freeze`, which moves every object alive now out of the collector's sight, so later
    full collections walk only what was made since (a few ms). Objects frozen are still freed
    when their last reference goes; only a reference cycle that dies after its freeze waits for
    :func:`thaw_heap` (a designer walk of 200 steps left 2,056 such objects of 200k frozen).
    """
    gc.collect(1)
    gc.freeze()


def thaw_heap() -> None:
    """Give the frozen objects back to the collector (the add-on unregistered: a later full
    collection frees a cycle that died while frozen)."""
    gc.unfreeze()


def running(name: str = None):
    """The running job ``name`` (any job: the first), or None."""
    if name is None:
        return next(iter(_JOBS.values()), None)
    return _JOBS.get(name)


def drop(name: str):
    """Stop the running job ``name`` quietly (a newer one replaces it); the job, or None."""
    job = _JOBS.pop(name, None)
    if job is not None:
        job.cancelled = True
    return job


def cancel(name: str = None) -> int:
    """Cancel the running job ``name`` (None: all): its result is dropped, its ``cancelled``
    callback told. How many were cancelled."""
    n = 0
    for k in [name] if name is not None else list(_JOBS):
        job = drop(k)
        if job is not None:
            n += 1
            if job.on_cancel is not None:
                job.on_cancel()
    if n:
        _show_status()
    return n


def _finish(job: Job) -> None:
    """The main thread's part of a finished job: apply its result, or say its error."""
    if job.cancelled:
        return
    if job.error is not None:
        if isinstance(job.error, state.USER_ERRORS):
            if job.fail is not None:
                job.fail(job.error)
            else:
                _say(f"{job.label}: {job.error}")
            return
        state.BUGS.append((f"job {job.name}", job.trace))
        print(job.trace)
        if job.fail is not None:
            job.fail(job.error)
        else:
            _say(f"{job.label}: {type(job.error).__name__}: {job.error}")
        return
    try:
        job.apply(job.result)
    except state.USER_ERRORS as exc:  # the scene changed under it (the body removed, ...): say it
        if job.fail is not None:
            job.fail(exc)
        else:
            _say(f"{job.label}: {exc}")


def poll():
    """Timer: finished jobs are applied (in the order they started); the status follows. Returns
    the next interval, or None when nothing runs."""
    landed = False
    for name, job in list(_JOBS.items()):
        if job.done.is_set() and _JOBS.get(name) is job:
            del _JOBS[name]
            landed = True
            try:
                _finish(job)
            except Exception:  # a bug in an apply: never a traceback from a timer
                state.BUGS.append((f"job {name}", traceback.format_exc()))
                traceback.print_exc()
    if landed:  # what the worker made (the modules it imported first: 90k objects) out of sight
        settle_heap()
    _show_status()
    return POLL_S if _JOBS else None


def wait(timeout: float = 600.0) -> None:
    """Wait for every running job and apply it (tests and scripts of the threaded path)."""
    end = time.perf_counter() + timeout
    while _JOBS and time.perf_counter() < end:
        for job in list(_JOBS.values()):
            job.done.wait(max(0.0, end - time.perf_counter()))
        poll()


def _say(text: str) -> None:
    scene = getattr(bpy.context, "scene", None)
    if scene is not None and hasattr(scene, "ease"):
        scene.ease.job_status = text


def _show_status() -> None:
    """The panel's and the status bar's "updating" line (cleared when nothing runs)."""
    job = running()
    text = job.status() if job is not None else ""
    scene = getattr(bpy.context, "scene", None)
    if scene is not None and hasattr(scene, "ease") and scene.ease.job_status != text:
        if text or scene.ease.job_status.startswith("updating"):
            scene.ease.job_status = text
    ws = getattr(bpy.context, "workspace", None)
    if ws is not None and getattr(bpy.context, "window", None) is not None:
        try:
            ws.status_text_set(text or None)
        except (AttributeError, RuntimeError, TypeError):
            pass


def _watch() -> None:
    """With a window: the modal watcher that cancels on Esc."""
    if bpy.app.background or getattr(bpy.context, "window", None) is None or EASE_OT_watch_jobs.active:
        return
    try:
        bpy.ops.ease.watch_jobs("INVOKE_DEFAULT")
    except RuntimeError:  # no window to run a modal operator in
        pass


def _busy(cls) -> bool:
    """``poll`` of the job operators: something runs (else greyed out, saying where work starts)."""
    if not _JOBS:
        cls.poll_message_set("nothing is running in the background (EASE > Ease > Live prepares there)")
        return False
    return True


class EASE_OT_watch_jobs(bpy.types.Operator):
    """Watch the running EASE jobs: Esc cancels them"""

    bl_idname = "ease.watch_jobs"
    bl_label = "Watch EASE Jobs"
    bl_options = {"INTERNAL"}
    active = False  # class-wide: one watcher at a time

    @classmethod
    def poll(cls, context):
        return _busy(cls)

    def invoke(self, context, event):
        type(self).active = True
        self._timer = context.window_manager.event_timer_add(0.1, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _end(self, context):
        type(self).active = False
        context.window_manager.event_timer_remove(self._timer)

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS" and _JOBS:
            cancel()
            self._end(context)
            return {"CANCELLED"}
        if not _JOBS:
            self._end(context)
            return {"FINISHED"}
        return {"PASS_THROUGH"}


class EASE_OT_cancel_jobs(bpy.types.Operator):
    """Cancel the EASE work running in the background (Esc does too)"""

    bl_idname = "ease.cancel_jobs"
    bl_label = "Cancel"
    bl_options = {"INTERNAL"}

    @classmethod
    def poll(cls, context):
        return _busy(cls)

    def execute(self, context):
        n = cancel()
        context.scene.ease.job_status = "cancelled"
        self.report({"INFO"}, f"cancelled {n} job(s)")
        return {"FINISHED"}


def undo_push(message: str) -> bool:
    """Push an undo step named ``message`` from a timer (a job's result written, Live's pieces of a
    new cut), through Blender's public ``bpy.ops.ed.undo_push``. A timer runs with no window in its
    context, where the operator's poll fails (and nothing was pushed, silently): the call runs in
    the scene's window (:func:`_window`), as a button press would. ``bpy.ops`` evaluates the view
    layer around the call: what Blender does before its next redraw anyway. Whether a step was
    pushed (False: no window, or the undo system is off)."""
    ctx = bpy.context
    override = {}
    if ctx.window is None:
        win = _window(ctx)
        if win is None:
            return False
        override = {"window": win, "screen": win.screen}
    with ctx.temp_override(**override):
        if not bpy.ops.ed.undo_push.poll():
            return False
        bpy.ops.ed.undo_push(message=message)
    return True


def _window(ctx):
    """The window showing the context's scene (else the first), or None."""
    wins = list(getattr(ctx.window_manager, "windows", None) or [])
    return next((w for w in wins if w.scene == ctx.scene), wins[0] if wins else None)


def start_step(name: str, label: str, compute, apply, status: str, undo: str, sync=None, cancelled=None) -> Job:
    """:func:`start` for an operator's work whose outcome the ``scene.ease`` property ``status``
    says: "*label* stopped: *error*", or "*label* cancelled: the scene is as it was" (nothing
    applied; ``cancelled()``: what follows "cancelled: " instead, for work that writes files).
    A result that lands after the operator returned (computed in a worker) is one undo step of
    its own, named ``undo``, and Live sees the change."""
    threaded = not in_line(sync)

    def apply_step(result):
        apply(result)
        if threaded:
            state.changed(bpy.context.scene)
            undo_push(f"EASE: {undo}")

    def say(text: str) -> None:
        setattr(bpy.context.scene.ease, status, text)

    return start(
        name,
        label,
        compute,
        apply_step,
        fail=lambda exc: say(f"{label} stopped: {exc}"),
        sync=sync,
        cancelled=lambda: say(f"{label} cancelled: " + (cancelled() if cancelled else "the scene is as it was")),
    )


def folder_cancelled(out, writing: list):
    """The ``cancelled`` text of :func:`start_step` for work that writes the folder ``out`` at once
    (the core's output folders: all the old files or all the new ones): ``writing`` is not empty
    once the worker has begun writing (no cancel after)."""
    return lambda: (
        f"too late: {out} was being written, it holds the new files"
        if writing
        else f"nothing written ({out} as it was)"
    )


def start_writing(name: str, label: str, compute, apply, out, writing: list, sync=None) -> Job:
    """:func:`start_step` for an operator's work that writes the folder ``out`` (Export, Marker):
    its outcome in ``job_status``, its result one undo step named ``label``, and a cancel that says
    whether ``out`` was already being written (``writing``: :func:`folder_cancelled`)."""
    return start_step(name, label, compute, apply, "job_status", label, sync, folder_cancelled(out, writing))


class Background:
    """Mixin of an operator whose work is a job (list it before the operator's base class).

    Pressed in the interface (``invoke``) the job runs in the background (in line headless, see
    :data:`SYNCHRONOUS`): progress in the status bar, Esc cancels; run from a script
    (``execute``) it runs in line, its result there when the call returns. ``run`` passes
    :meth:`job_sync` as :func:`start`'s ``sync``."""

    def invoke(self, context, event):
        self.ease_background = True
        return self.execute(context)

    def job_sync(self):
        return None if getattr(self, "ease_background", False) else True


def unregister(join_s: float = 10.0) -> None:
    """The add-on goes: every job dropped, the poll stopped; the workers are given ``join_s``
    seconds in all to stop (at their next progress report), so none is left behind."""
    dropped = [drop(name) for name in list(_JOBS)]
    if bpy.app.timers.is_registered(poll):
        bpy.app.timers.unregister(poll)
    end = time.perf_counter() + join_s
    for job in dropped:
        if job.thread is not None:
            job.thread.join(max(0.0, end - time.perf_counter()))
    thaw_heap()


CLASSES = (EASE_OT_watch_jobs, EASE_OT_cancel_jobs)
