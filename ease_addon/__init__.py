"""The Blender side of EASE: thin adapters from the UI to the core.

Modules, one per concern:

- :mod:`.properties`: the scene properties (what a save keeps);
- :mod:`.data`: the scene read back (body, design, cut, pattern: getters, no side effects);
- :mod:`.sync`: the after-change reactions (body moves, design redraws, panels filled,
  property update callbacks);
- :mod:`.build`: Blender objects from the core's results, written in one pass;
- :mod:`.materials`, :mod:`.objects` (collection, roles, removal, progress bar),
  :mod:`.convert` (Blender data <-> numpy), :mod:`.ramp` (the ease colour ramp, pure
  numpy), :mod:`.state` (session caches, the add-on's errors), :mod:`.jobs` (heavy work
  off the main thread);
- one ``*_ops`` module per workflow stage (body, design, ease, pattern, fit, drape,
  render, export), none importing another: what they share lives in the modules above;
- :mod:`.panels`: the "EASE" sidebar tab.

No geometry algorithm lives here and no pipeline step: a surface point from a
click, the grain line and the piece layout come from ``core.body.surface`` and
``core.geom.layout``, the pattern, drape and export from :mod:`core.workflows`,
reached with relative imports (``from ..core import workflows``).
"""

from __future__ import annotations

import bpy

from ..core.design import geometry
from . import (
    body_ops,
    design_ops,
    drape_ops,
    ease_ops,
    export_ops,
    fit_ops,
    jobs,
    layers_ops,
    live,
    marker_ops,
    measure_ops,
    motion_ops,
    panels,
    pattern_ops,
    properties,
    render_ops,
    state,
)

CLASSES = (
    properties.CLASSES
    + body_ops.CLASSES
    + design_ops.CLASSES
    + ease_ops.CLASSES
    + pattern_ops.CLASSES
    + fit_ops.CLASSES
    + drape_ops.CLASSES
    + motion_ops.CLASSES
    + render_ops.CLASSES
    + export_ops.CLASSES
    + marker_ops.CLASSES
    + measure_ops.CLASSES
    + jobs.CLASSES
    + panels.CLASSES
    + measure_ops.PANELS
    + layers_ops.CLASSES
    + layers_ops.PANELS
)

_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    properties.register_props()
    measure_ops.register_props()
    layers_ops.register_props()
    if live.on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(live.on_load)
    # a file already open (the add-on enabled after it was read): Live follows its toggle once
    # the context is the file's (register runs with a restricted one)
    bpy.app.timers.register(live.resume, first_interval=0.0)
    # the edge-flip geodesic solvers of the workers' cuts are built in a helper process (their
    # constructor holds the GIL: 45-120 ms the viewport would wait, issue 32)
    geometry.OUT_OF_PROCESS = True
    # the modules and data loaded so far live as long as the add-on: out of the collector's
    # sight, a full collection on the main thread (the first heavy operator's) stays short
    jobs.settle_heap()


def unregister():
    jobs.unregister()
    geometry.OUT_OF_PROCESS = False
    geometry.stop_helper()
    while live.on_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(live.on_load)
    if bpy.app.timers.is_registered(live.resume):
        bpy.app.timers.unregister(live.resume)
    live.stop()
    layers_ops.unregister_props()
    measure_ops.unregister_props()
    properties.unregister_props()
    _unregister_classes()
    state.clear()
