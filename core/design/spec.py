"""What the design stage hands to the cutting engine (plain data).

``core.design`` resolves a design file (landmarks, placement and length
parameters, mirroring) into a :class:`CutSpec` on one body model; the engine
(:func:`core.cut.engine.cut_surface`) turns it into a
:class:`core.cut.types.GarmentCut`. Ease is filled in afterwards by
``core.design`` from the design's ease fields, per cut triangle.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional

from ..body.model import SurfacePoint


@dataclass
class CutLine:
    """A seamline or opening: consecutive points joined by geodesics.

    name : unique, used in errors (e.g. ``"shirt.side_left"``).
    points : ordered keypoints on the body surface (>= 2).
    closed : True for a loop (neckline, cuff, hem, armhole).
    role : ``"seam"`` (two panels are sewn along it) or ``"opening"`` (the
        garment ends there: neckline, hem, cuff, waistband).
    garment : the garment this line cuts. None: the garment named by the
        line name's prefix (``"shirt.side_left"`` -> ``"shirt"``) if there is
        one, else every garment. Garments are cut separately, so the lines of
        one garment never cut another (overlapping shirt and pants).
    dart : the :class:`core.design.darts.DartSpec` of a dart line (a seam from
        the mouth, on another line, to the sewn point inside one panel), else None.
    """

    name: str
    points: List[SurfacePoint]
    closed: bool = False
    role: str = "seam"
    garment: Optional[str] = None
    dart: Optional[object] = None


@dataclass
class PanelSpec:
    """A panel: the region of the cut surface containing ``seed``."""

    name: str
    garment: str
    seed: SurfacePoint
    body_part: str = "torso"  # "torso" | "arm" | "leg" (grain follows its long axis)
    mirror_of: Optional[str] = None


@dataclass
class GarmentSpec:
    name: str
    kind: str  # "upper" | "lower" | "dress"
    pin_line: Optional[str] = None  # name of the opening CutLine pinned while draping


@dataclass
class CutSpec:
    """Everything the engine needs. ``skirt`` asks for the skirt topology
    (inter-leg faces removed, leg boundaries bridged) before cutting."""

    lines: List[CutLine]
    panels: List[PanelSpec]
    garments: List[GarmentSpec]
    skirt: bool = False
    refine_edge_length: Optional[float] = 0.01  # target mean edge, metres (split above 1.5x); None: no refinement
    materials: dict = field(default_factory=dict)
    body: dict = field(default_factory=dict)  # {"model", "shape", "pose"} for the record
