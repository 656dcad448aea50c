"""The Blender side of EASE: thin adapters from the UI to the core.

Modules, one per concern: :mod:`.properties` (scene data), :mod:`.convert`
(Blender data <-> numpy), :mod:`.ramp` (the ease colour ramp, pure numpy),
one ``*_ops`` module per workflow stage (body, design, ease, pattern, fit,
drape, render, export) and :mod:`.panels` (the "EASE" sidebar tab). No
geometry algorithm lives here: every computation is a call into the core,
reached with relative imports (``from ..core.body import load_body``).
"""
from __future__ import annotations

import bpy

from . import (body_ops, design_ops, drape_ops, ease_ops, export_ops, fit_ops, panels, pattern_ops,
               properties, render_ops, state)

CLASSES = (properties.CLASSES + body_ops.CLASSES + design_ops.CLASSES + ease_ops.CLASSES
           + pattern_ops.CLASSES + fit_ops.CLASSES + drape_ops.CLASSES + render_ops.CLASSES
           + export_ops.CLASSES
           + panels.CLASSES)

_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    properties.register_props()


def unregister():
    drape_ops.cancel_running()
    properties.unregister_props()
    _unregister_classes()
    state.clear()
