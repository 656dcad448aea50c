"""The base of every EASE operator: what it needs, undo support and error reporting.

``needs`` names what the scene must hold before the operator can run (a body, a
design, a pattern, a draped garment, something to render); ``poll`` greys the
button out while one is missing and its tooltip says which, and what to do.
``run(context)`` does the work; it computes everything first and only then
changes the scene, so an error from the core (an ``EaseError`` naming the
element at fault) is reported in the status bar and the scene is left as it
was.
"""

from __future__ import annotations

import traceback

import bpy

from . import data, state
from .objects import objects_with_role


def _has_body(context) -> bool:
    return data.body_object(context, required=False) is not None


def _has_garment(context) -> bool:
    return bool(objects_with_role(context.scene, "garment"))


def _has_content(context) -> bool:
    return any(objects_with_role(context.scene, r) for r in ("body", "garment", "pattern_panel"))


def _size_on_chart(context) -> bool:
    s = context.scene.ease
    return s.size in data.chart_sizes(s.chart)


def _fit_size_on_chart(context) -> bool:
    return context.scene.ease.fit_size in data.chart_sizes(data.design_chart(context.scene))


def _output_problem(path: str, setting: str) -> str:
    """Why the panel's output ``path`` ("Export to", "Render to") cannot be written now ("" when it can):
    empty, or relative to a .blend that is not saved."""
    try:
        data.output_path(path, setting)
    except state.AddonError as exc:
        return str(exc)
    return ""


def _sizes_text(chart: str) -> str:
    return f"the {chart} chart has sizes {', '.join(data.chart_sizes(chart))}"


# requirement -> (test on the context, what the tooltip says is missing: text, or a function of the context)
REQUIREMENTS = {
    "body": (_has_body, "needs an EASE body: add one in EASE > Body"),
    "design": (
        lambda c: bool(c.scene.ease.design_json),
        "needs a design: load a template or a design file in EASE > Design",
    ),
    "pattern": (
        lambda c: bool(c.scene.get(data.PATTERN_KEY)),
        "needs a pattern: press Optimize Pattern in EASE > Pattern",
    ),
    "garment": (_has_garment, "needs a draped garment: press Drape in EASE > Drape"),
    "content": (_has_content, "nothing to render: add a body in EASE > Body"),
    # an output folder or file the button can write to (an unsaved file has no folder for "//" paths)
    "export_dir": (
        lambda c: not _output_problem(c.scene.ease.export_dir, "Export to"),
        lambda c: _output_problem(c.scene.ease.export_dir, "Export to"),
    ),
    "render_path": (
        lambda c: not _output_problem(c.scene.ease.render_path, "Render to"),
        lambda c: _output_problem(c.scene.ease.render_path, "Render to"),
    ),
    # Drape All's outfit: the Layers list holds a garment (the scene property exists once the add-on registered)
    "layers": (
        lambda c: bool(getattr(c.scene, "ease_layers", None) and c.scene.ease_layers.items),
        "needs layers: add a garment in EASE > Design > Layers",
    ),
    "motion": (
        lambda c: bpy.data.objects.get(data.MOTION_GARMENT) is not None,
        "needs a motion: press Drape Animation in EASE > Drape",
    ),
    "motion_path": (
        lambda c: not _output_problem(c.scene.ease.motion_path, "Alembic to"),
        lambda c: _output_problem(c.scene.ease.motion_path, "Alembic to"),
    ),
    "size": (
        _size_on_chart,
        lambda c: f"size {c.scene.ease.size} is not on the chosen chart: {_sizes_text(c.scene.ease.chart)}",
    ),
    "fit_size": (
        _fit_size_on_chart,
        lambda c: (
            f"target size {c.scene.ease.fit_size} is not on the design's "
            f"chart: {_sizes_text(data.design_chart(c.scene))}"
        ),
    ),
}


def missing(context, needs) -> str:
    """What the first unmet requirement of ``needs`` says ("" when all are met)."""
    for need in needs:
        test, message = REQUIREMENTS[need]
        if not test(context):
            return message(context) if callable(message) else message
    return ""


def poll_needs(cls, context) -> bool:
    """``poll`` of an operator class with ``needs``: False (and the tooltip) while one is missing."""
    why = missing(context, getattr(cls, "needs", ()))
    if why:
        cls.poll_message_set(why)
        return False
    return True


class EaseOperator(bpy.types.Operator):
    bl_options = {"REGISTER", "UNDO"}
    needs = ()  # names in REQUIREMENTS (no annotation: Blender reads annotations as properties)

    @classmethod
    def poll(cls, context):
        return poll_needs(cls, context)

    def run(self, context):  # pragma: no cover - overridden
        raise NotImplementedError

    def execute(self, context):
        try:
            result = self.run(context)
        except state.USER_ERRORS as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        except Exception as exc:  # a bug: still no traceback dialog, but keep the trace in the console
            traceback.print_exc()
            state.BUGS.append((self.bl_idname, traceback.format_exc()))
            self.report({"ERROR"}, f"{type(exc).__name__}: {exc}")
            return {"CANCELLED"}
        state.changed(context.scene)  # Live says "converged" again once a tick has seen the change
        return result or {"FINISHED"}
