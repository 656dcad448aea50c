"""EASE as a Blender extension: the entry point Blender imports.

Installed, this directory is a package such as ``bl_ext.user_default.ease``
with the subpackages ``ease_addon`` (the Blender side) and ``core`` (pure
Python). Nothing Blender-specific is imported at module level, so tools that
walk the repository (pytest, linters) can import this file without bpy.
"""


def register():
    from .ease_addon import register as _register

    _register()


def unregister():
    from .ease_addon import unregister as _unregister

    _unregister()
