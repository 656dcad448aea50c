"""Per-panel strains of a pattern on its own body, computed once for every figure that reads them.

The reference-body report (:func:`core.metrics.pattern.pattern_report`) measures
compliance per garment and overall, collapse and the regions: all from the same
per-triangle scales. Computing them once per panel keeps a report at one pass
(what a batch item and a live tick pay).
"""

from __future__ import annotations

from typing import Dict, NamedTuple

import numpy as np

from ..geom.mesh import triangle_areas
from ..geom.strain import scales
from ..pattern.types import PatternPanel


class PanelStrain(NamedTuple):
    """One panel's per-triangle strains on its ``xyz``: achieved weft and warp scales (f,),
    shear (f,) in degrees, 3D triangle areas (f,) in m^2."""

    weft: np.ndarray
    warp: np.ndarray
    shear: np.ndarray
    area: np.ndarray


def panel_strain(panel) -> PanelStrain:
    """The :class:`PanelStrain` of ``panel`` (a pattern panel: ``uv``, ``xyz``, ``faces``, ``grain``)."""
    X, F = np.asarray(panel.xyz, float), np.asarray(panel.faces)
    if isinstance(panel, PatternPanel):  # the scales its assembly computed, while they are still its own
        rw, rg, sh = panel.scales()
    else:
        with np.errstate(divide="ignore", invalid="ignore"):  # a degenerate triangle reads as inf/nan
            rw, rg, sh = scales(panel.uv, X, F, panel.grain)
    return PanelStrain(rw, rg, sh, triangle_areas(X, F))


def pattern_strains(pattern) -> Dict[str, PanelStrain]:
    """Panel name -> :func:`panel_strain`, for every panel of ``pattern``."""
    return {p.name: panel_strain(p) for p in pattern.panels}
