"""Shared Blender helpers: the "EASE" collection, object roles, object removal
and the window manager's progress bar.

Every object the add-on makes carries an ``ease_role`` custom property
("body", "seamlines", "keypoints", "pattern_panel", "garment", "studio", and
"<role>_part" for the children of a pattern piece) and lives in the scene's
"EASE" collection; replacing objects of a role goes through here.
"""

from __future__ import annotations

from contextlib import contextmanager

import bpy
import numpy as np


def collection(scene):
    """The scene's "EASE" collection (created on first use)."""
    coll = bpy.data.collections.get("EASE")
    if coll is None:
        coll = bpy.data.collections.new("EASE")
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def new_object(name: str, data, collection=None) -> bpy.types.Object:
    """A new object holding ``data``, linked into ``collection`` (default: the scene's root)."""
    obj = bpy.data.objects.new(name, data)
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def role_object(scene, name: str, data, role: str, parent=None) -> bpy.types.Object:
    """A new object of ``role`` in the EASE collection (a child of ``parent`` if given)."""
    obj = new_object(name, data, collection(scene))
    obj["ease_role"] = role
    if parent is not None:
        obj.parent = parent
    return obj


def objects_with_role(scene, role: str) -> list:
    return [o for o in scene.objects if o.get("ease_role") == role]


def remove_data(datablock) -> None:
    """Remove a mesh or curve datablock once nothing uses it."""
    if datablock is not None and datablock.users == 0:
        for coll in (bpy.data.meshes, bpy.data.curves):
            if datablock.name in coll and coll[datablock.name] == datablock:
                coll.remove(datablock)
                return


def remove_object(obj) -> None:
    """Remove ``obj`` and its mesh or curve data once nothing else uses it."""
    data = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    remove_data(data)


def remove_objects(objects) -> None:
    for o in objects:
        remove_object(o)


def world_bounds(objects) -> tuple:
    """(min (3,), max (3,)) world corners of the bounding boxes of ``objects`` (one object or several)."""
    objects = [objects] if isinstance(objects, bpy.types.Object) else list(objects)
    corners = []
    for o in objects:
        m = np.array(o.matrix_world, dtype=np.float64)
        corners.append(np.array([tuple(c) for c in o.bound_box], dtype=np.float64) @ m[:3, :3].T + m[:3, 3])
    c = np.vstack(corners)
    return c.min(axis=0), c.max(axis=0)


def select_only(context, obj) -> None:
    """Make ``obj`` the only selected object and the active one."""
    for o in context.view_layer.objects:
        if o is not None:  # (an object removed in this operator: the view layer lists None until updated)
            o.select_set(o == obj)
    context.view_layer.objects.active = obj


def ensure_nodes(idblock) -> None:
    """Give a material/world its node tree (always there in Blender 5; ``use_nodes`` before)."""
    if idblock.node_tree is None or bpy.app.version < (5, 0, 0):
        idblock.use_nodes = True


@contextmanager
def window_progress(context):
    """The window manager's progress bar for the duration of the block.

    Yields the core's ``progress(fraction, message)`` callback; the bar ends
    however the block ends.
    """
    wm = context.window_manager
    wm.progress_begin(0, 100)

    def progress(fraction, message):
        try:
            wm.progress_update(int(100 * fraction))
        except Exception:  # no window (a script run): the core's progress is only shown
            pass

    try:
        yield progress
    finally:
        wm.progress_end()
