"""The base of every EASE operator: undo support and error reporting.

``run(context)`` does the work; it computes everything first and only then
changes the scene, so an error from the core (an ``EaseError`` naming the
element at fault) is reported in the status bar and the scene is left as it
was.
"""
from __future__ import annotations

import traceback

import bpy

from . import state


class EaseOperator(bpy.types.Operator):
    bl_options = {"REGISTER", "UNDO"}

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
            self.report({"ERROR"}, f"{type(exc).__name__}: {exc}")
            return {"CANCELLED"}
        return result or {"FINISHED"}
