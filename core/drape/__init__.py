"""Draping a sewing pattern on the body: our own Gauss-Seidel XPBD in Warp.

``drape(pattern, body_vertices, body_faces, material=None, options=None,
progress=None) -> DrapeResult``. Warp is imported lazily (on the first drape),
with its kernel cache in the project's ``.cache/warp``.
"""
from .materials import PRESETS, Material, get_material
from .xpbd import DrapeOptions, DrapeResult, drape

__all__ = ["drape", "DrapeOptions", "DrapeResult", "Material", "PRESETS", "get_material"]
