"""Measurements panel: made-to-measure from a tape measure, in the add-on.

Each of the tape measures (docs/measurements.md) has a tick (give it), a target (cm) and, beside
it, the value the body reaches with its status once fitted or measured. **Fit Body** runs the
same core fit as ``ease body --measurements`` and a design's ``"body": {"measurements": ...}``
(:func:`core.body.made_to_measure.fit_tape`) and shapes the body in place; pressed in the
interface it runs in the background (:mod:`.jobs`: a worker thread, its progress in the status
bar, Esc or Cancel stops it and leaves the body as it was; in line from a script). **Measure** takes the
body's tape measures; **Use Body's** copies them into the targets; **Load** reads a table
(JSON or CSV, as ``--measurements``).
"""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, PointerProperty, StringProperty

from ..core.body.tape import TAPE_MEASURES
from . import data, jobs, state, sync
from .operators_base import EaseOperator


def _label(name: str) -> str:
    return name.replace("_", " ").capitalize()


def _tape_annotations() -> dict:
    ann = {
        "give_gender": BoolProperty(name="Gender", description="hold the body's gender (else the fit moves it)"),
        "gender": FloatProperty(name="Gender", min=0.0, max=1.0, default=1.0, description="0 male .. 1 female"),
        "file": StringProperty(name="Table", subtype="FILE_PATH", description="a .json or .csv of tape measures (cm)"),
        "report": StringProperty(name="Fit report"),
    }
    for name in TAPE_MEASURES:
        ann[f"use_{name}"] = BoolProperty(name=_label(name), description=f"fit the body's {_label(name).lower()}")
        ann[name] = FloatProperty(name=_label(name), min=0.0, max=250.0, precision=1, description="target (cm)")
        ann[f"reached_{name}"] = FloatProperty(name="reached", precision=1)
        ann[f"status_{name}"] = StringProperty()
    return ann


EASE_PG_tape = type(
    "EASE_PG_tape",
    (bpy.types.PropertyGroup,),
    {"__annotations__": _tape_annotations(), "__doc__": "The Measurements panel: targets and values reached (cm)."},
)


def targets(tape) -> dict:
    """The table of tape measures the panel gives: the ticked measures (and gender if held)."""
    out = {n: float(getattr(tape, n)) for n in TAPE_MEASURES if getattr(tape, f"use_{n}")}
    if tape.give_gender:
        out["gender"] = float(tape.gender)
    return out


def _anny(obj):
    model = state.body_model(data.body_spec(obj)["model"])
    if not callable(getattr(model, "local_change_parameters", None)):
        raise state.AddonError("made-to-measure needs the default body (Anny): add it first")
    return model


def _show(tape, achieved: dict, status: dict) -> None:
    for n in TAPE_MEASURES:
        setattr(tape, f"reached_{n}", float(achieved.get(n, 0.0)))
        setattr(tape, f"status_{n}", status.get(n, ""))


JOB = "tape_fit"  # the job's name (a new Fit Body replaces a running one)


def start_fit(model, table: dict, sync=None):
    """The core's fit of ``model`` (Anny) to the tape measures ``table`` as the job :data:`JOB`
    (``sync``: :func:`.jobs.start`'s); the body is shaped when it lands (:func:`apply_fit`)."""
    from ..core.body.made_to_measure import fit_tape

    return jobs.start_step(
        JOB,
        "fit body",
        lambda progress: fit_tape(model, table, progress=progress),
        lambda fit: apply_fit(bpy.context, fit),
        "job_status",
        "Fit Body",
        sync=sync,
    )


def _missed(fit) -> list:
    """The measures a fit does not bring within tolerance."""
    return [k for k, s in fit.status.items() if not s.startswith("within")]


def apply_fit(context, fit) -> None:
    """Shape the scene's body as the fit (a :class:`core.body.made_to_measure.TapeFit`) says, show
    each value reached beside its target and the fit's report (main thread)."""
    obj = data.body_object(context)
    model = _anny(obj)  # the body may have changed while the fit ran: still Anny
    tape = context.scene.ease_tape
    sync.update_body(context, obj, shape=fit.shape)
    sync.fill_shape_props(context.scene, model, fit.shape)
    _show(tape, fit.achieved, fit.status)
    missed = _missed(fit)
    parts = [f"{len(fit.status) - len(missed)} of {len(fit.status)} within tolerance"]
    parts += [f"{k}: {fit.status[k]}" for k in missed]
    if fit.collisions:
        parts.append(f"the body cuts into itself: {', '.join(fit.collisions)}")
    tape.report = "; ".join(parts)


class EASE_OT_tape_fit(jobs.Background, EaseOperator):
    """Fit the body to the ticked tape measures (Anny's phenotypes and local changes, the fit of
    ease body --measurements), in the background (Esc cancels); each value reached is shown
    beside its target"""

    bl_idname = "ease.tape_fit"
    bl_label = "Fit Body"
    needs = ("body",)

    def run(self, context):
        from ..core.body.made_to_measure import check_tape_targets

        obj = data.body_object(context)
        tape = context.scene.ease_tape
        table = targets(tape)
        if not set(table) - {"gender"}:
            raise state.AddonError("tick at least one measurement to fit")
        model = _anny(obj)
        check_tape_targets(table)  # bad input is said at once, not from the worker
        job = start_fit(model, table, sync=self.job_sync())
        if job.thread is not None:
            self.report({"INFO"}, "fitting the body in the background (Esc cancels)")
            return
        fit = job.result
        self.report({"WARNING"} if _missed(fit) or fit.collisions else {"INFO"}, tape.report)


class EASE_OT_tape_measure(EaseOperator):
    """Take the body's tape measures (standing, cm) and show them as the values reached"""

    bl_idname = "ease.tape_measure"
    bl_label = "Measure"
    needs = ("body",)

    def run(self, context):
        from ..core.body.tape import tape_measures

        obj = data.body_object(context)
        shape = data.body_spec(obj)["shape"] or None
        tape = context.scene.ease_tape
        _show(tape, tape_measures(_anny(obj), shape=shape), {})
        tape.report = "measured"


class EASE_OT_tape_from_body(EaseOperator):
    """Copy the body's tape measures into the targets (a start to edit)"""

    bl_idname = "ease.tape_from_body"
    bl_label = "Use Body's"
    needs = ("body",)

    def run(self, context):
        from ..core.body.tape import tape_measures

        obj = data.body_object(context)
        tape = context.scene.ease_tape
        got = tape_measures(_anny(obj), shape=data.body_spec(obj)["shape"] or None)
        for n, v in got.items():
            setattr(tape, n, round(v, 1))
        _show(tape, got, {})


class EASE_OT_tape_load(EaseOperator):
    """Read the targets from a table of tape measures (.json or .csv, cm), as ease body --measurements"""

    bl_idname = "ease.tape_load"
    bl_label = "Load"

    def run(self, context):
        from ..core.body.made_to_measure import read_tape_file

        tape = context.scene.ease_tape
        if not tape.file:
            raise state.AddonError("set the table file (.json or .csv) first")
        table = read_tape_file(bpy.path.abspath(tape.file))
        for n in TAPE_MEASURES:
            setattr(tape, f"use_{n}", n in table)
            if n in table:
                setattr(tape, n, table[n])
        tape.give_gender = "gender" in table
        if "gender" in table:
            tape.gender = table["gender"]
        tape.report = f"{len(table)} values read"


class EASE_PT_measurements(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "EASE"
    bl_label = "Measurements"
    bl_idname = "EASE_PT_measurements"
    bl_parent_id = "EASE_PT_body"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout, tape = self.layout, context.scene.ease_tape
        row = layout.row(align=True)
        row.prop(tape, "file", text="")
        row.operator("ease.tape_load", text="", icon="FILEBROWSER")
        col = layout.column(align=True)
        head = col.row()
        head.label(text="tape measure (cm)")
        head.label(text="reached")
        for n in TAPE_MEASURES:
            row = col.row(align=True)
            row.prop(tape, f"use_{n}", text="")
            sub = row.row(align=True)
            sub.active = getattr(tape, f"use_{n}")
            sub.prop(tape, n)
            reached = getattr(tape, f"reached_{n}")
            status = getattr(tape, f"status_{n}")
            icon = "NONE" if not status else ("CHECKMARK" if status.startswith("within") else "ERROR")
            row.label(text=f"{reached:.1f}" if reached else "-", icon=icon)
        row = layout.row(align=True)
        row.prop(tape, "give_gender", text="")
        sub = row.row()
        sub.active = tape.give_gender
        sub.prop(tape, "gender", slider=True)
        row = layout.row(align=True)
        row.operator("ease.tape_fit", icon="MOD_ARMATURE")
        row.operator("ease.tape_measure")
        row.operator("ease.tape_from_body")
        if tape.report:
            for part in tape.report.split("; "):
                layout.label(text=part)


# Registered after the Body panel (this panel is its child).
CLASSES = (EASE_PG_tape, EASE_OT_tape_fit, EASE_OT_tape_measure, EASE_OT_tape_from_body, EASE_OT_tape_load)
PANELS = (EASE_PT_measurements,)


def register_props():
    bpy.types.Scene.ease_tape = PointerProperty(type=EASE_PG_tape)


def unregister_props():
    if hasattr(bpy.types.Scene, "ease_tape"):
        del bpy.types.Scene.ease_tape
