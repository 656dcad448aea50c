"""EASE core: parametric garment design with explicit, local ease control.

Pure Python (numpy, scipy, libigl, potpourri3d, warp-lang); never imports bpy.
Data flows one way: body -> design (cuts, ease field) -> panels -> pattern ->
drape -> export. Every stage takes and returns plain data classes.

Frame (fixed once, see ``core.body.model``): metres, +Z up, the body faces -Y,
+X is the body's left. This is Blender's frame, so the add-on needs no
conversion.
"""

__version__ = "0.1.0"
