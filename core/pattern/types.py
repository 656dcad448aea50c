"""Plain data of a 2D sewing pattern (the output of ``core.pattern``).

A pattern is self-contained: with the body spec it carries, the drape and
export stages need nothing else. Lengths are metres; the grain line ``grain``
is the unit warp direction in 2D (the optimizer aligns it to +y), the weft is
``grain`` turned by +90 degrees (SPEC "Frames and grain").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from ..cut.types import seam_kind
from ..geom.strain import scales


@dataclass
class PatternPanel:
    """One 2D pattern piece.

    Attributes
    ----------
    name, garment : as in :class:`core.cut.types.Panel`.
    uv : (n, 2) float, 2D vertex positions in metres.
    faces : (f, 3) int, same local indexing as the cut panel.
    vertex_ids : (n,) int, global garment vertex ids (shared along seams).
    xyz : (n, 3) float, the panel embedded on the body instance it was solved for.
    grain : (2,) float, unit warp direction in 2D.
    target_weft, target_warp : (f,) float, the scales the solve aimed at.
    achieved_weft, achieved_warp : (f,) float, SPEC rho-hat on the solve's body.
    boundary : list of (k,) int closed loops (local ids), counter-clockwise.
    hems : list of (k,) int open polylines on the boundary that are not seams.
    mirror_of : name of the mirrored piece, or None (labels say "mirror").
    """

    name: str
    garment: str
    uv: np.ndarray
    faces: np.ndarray
    vertex_ids: np.ndarray
    xyz: np.ndarray
    grain: np.ndarray
    target_weft: np.ndarray
    target_warp: np.ndarray
    achieved_weft: np.ndarray
    achieved_warp: np.ndarray
    boundary: List[np.ndarray] = field(default_factory=list)
    hems: List[np.ndarray] = field(default_factory=list)
    mirror_of: Optional[str] = None
    #: (copies of the inputs, value) of the last :meth:`scales`
    _scales: Optional[tuple] = field(default=None, init=False, repr=False, compare=False)

    def scales(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The piece's achieved weft and warp scales and shear (degrees) on its own body, (f,) each:
        :func:`core.geom.strain.scales` of ``uv``, ``xyz``, ``faces``, ``grain`` (a degenerate
        triangle reads as inf / nan, without a warning).

        Computed once while those four hold the same values (the pattern's assembly sets
        ``achieved_weft`` / ``achieved_warp`` from it and its report reads it again: a shirt
        transfer paid ~7 ms twice); every call returns new arrays.
        """
        inputs = (self.uv, self.xyz, self.faces, self.grain)
        memo = self._scales
        if memo is None or not all(np.array_equal(a, b) for a, b in zip(memo[0], inputs)):
            with np.errstate(divide="ignore", invalid="ignore"):
                value = scales(*inputs)
            memo = self._scales = (tuple(np.array(a, copy=True) for a in inputs), value)
        return tuple(v.copy() for v in memo[1])


@dataclass
class PatternSeam:
    """Corresponding 2D polylines: ``panel_a.uv[verts_a[i]]`` sews to ``panel_b.uv[verts_b[i]]``.

    ``gathered``: the sides were not made equally long; the longer one is
    gathered into the shorter (notches at matching fractions of each side).
    """

    name: str
    panel_a: str
    panel_b: str
    verts_a: np.ndarray
    verts_b: np.ndarray
    gathered: bool = False

    @property
    def kind(self) -> str:
        """``"dart"`` (the legs of a dart, both ending at its apex) or ``"seam"``
        (:func:`core.cut.types.seam_kind`: read from the vertices, so a reloaded pattern knows it)."""
        return seam_kind(self)

    @property
    def apex(self) -> Optional[int]:
        """A dart's apex (local vertex id on ``panel_a``, where both legs end), None for a seam."""
        return int(self.verts_a[-1]) if seam_kind(self) == "dart" else None


@dataclass
class Pattern:
    """A sewing pattern.

    Attributes
    ----------
    style : str, the design's name.
    body : dict, ``{"model", "shape", "pose", "size"}`` of the body the pattern fits.
    garments : dict garment -> kind.
    panels, seams : the pieces and their seams.
    pins : dict garment -> (k,) global vertex ids pinned while draping.
    materials : dict, fabric and tolerances from the design.
    mode : ``"reference"``, ``"transfer"`` or ``"adapt"``.
    report : dict of metrics and timings (SPEC definitions).
    """

    style: str
    body: dict
    garments: Dict[str, str]
    panels: List[PatternPanel]
    seams: List[PatternSeam]
    pins: Dict[str, np.ndarray] = field(default_factory=dict)
    materials: dict = field(default_factory=dict)
    mode: str = "reference"
    report: dict = field(default_factory=dict)

    def panel(self, name: str) -> PatternPanel:
        for p in self.panels:
            if p.name == name:
                return p
        raise KeyError(f"no pattern piece {name!r}; pieces: {', '.join(p.name for p in self.panels)}")

    def seam_polylines(self, seam: PatternSeam):
        """The two 2D polylines (k, 2) of a seam."""
        return self.panel(seam.panel_a).uv[seam.verts_a], self.panel(seam.panel_b).uv[seam.verts_b]
