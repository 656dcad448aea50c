"""Geometry on plain numpy arrays, shared by every stage (imports nothing else of EASE).

One operation per module, as in gpytoolbox: import from the module that
names the job.

- :mod:`.mesh` -- triangle areas (3D and signed 2D), face and vertex normals,
  boundary loops.
- :mod:`.polyline` -- length, cumulative length, point at arc length.
- :mod:`.polygon` -- signed area, offset, self-crossing, point in polygon.
- :mod:`.layout` -- a piece's grain line and the row layout of pieces.
- :mod:`.strain` -- per-triangle Jacobians, weft/warp scales and shear.
- :mod:`.queries` -- Warp kernels for closest-point and ray queries on a mesh.
"""
