"""Draping a sewing pattern on the body: our own Gauss-Seidel XPBD in Warp.

``drape(pattern, body_vertices, body_faces, material=None, options=None,
progress=None) -> DrapeResult`` (:mod:`.simulate`) runs a whole drape; for
frame-by-frame control, :class:`DrapeSolver` (:mod:`.xpbd`) precomputes once
and ``solver.step(state)`` advances a :class:`DrapeState` by one frame, with
:mod:`.schedule` deciding growth, settling and divergence. Warp is imported
lazily (on the first solver). :mod:`.textile` runs the textile tests (Cusick drape
coefficient, ASTM D1388 bending length) with the same solver.
"""

from .materials import PRESETS, Material, get_material
from .options import DrapeOptions
from .result import DrapeResult
from .simulate import drape
from .xpbd import DrapeSolver, DrapeState

__all__ = ["drape", "DrapeSolver", "DrapeState", "DrapeOptions", "DrapeResult", "Material", "PRESETS", "get_material"]
