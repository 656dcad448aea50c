"""Plain data produced by cutting the body surface (the input of the pattern stage).

Garment vertices are shared between panels along seams, and only there: a seam
vertex has one global id and appears in both panels' ``vertex_ids``, while the
two sides of an opening (e.g. a jacket's front, between two panels) have
distinct ids at the same place on the body. Every garment vertex is a
fixed linear combination of body vertices (``GarmentCut.embedding``), so the
same cut gives the panels' 3D positions on any shape and pose of the model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np
import scipy.sparse as sp


def seam_names(seam: str) -> List[str]:
    """The names that designate the cut seam ``seam``, most specific first.

    The cut names a seam ``garment.line`` (``line`` for a line shared by
    garments) and ``garment.line#k`` when the line has several stretches:
    ``"shorts.side_left#1"`` answers to that name, to ``"shorts.side_left"``
    and to ``"side_left"`` (that line in every garment). Export allowances and
    gathered seams are looked up by these names.
    """
    names = [seam]
    line = seam.partition("#")[0]
    for k in (line, line.partition(".")[2] if "." in line else ""):
        if k and k not in names:
            names.append(k)
    return names


@dataclass
class Panel:
    """One garment panel embedded on the body.

    Attributes
    ----------
    name : str, unique in the cut (e.g. ``"shirt.front"``).
    garment : str, the garment it belongs to (``"shirt"``); its kind is in
        :attr:`GarmentCut.garments`.
    vertex_ids : (n,) int, global garment vertex ids (rows of the embedding).
    faces : (f, 3) int, local indices into ``vertex_ids``, oriented outward.
    warp_dir : (f, 3) float, unit warp (lengthwise grain) per triangle on the
        reference body, tangent to the triangle; weft = normal x warp.
    ease : (f,) float, target weft scale rho_weft per triangle (warp is 1.0).
    boundary : list of (k,) int arrays, closed boundary loops (local ids).
    body_part : str, ``"torso"``, ``"arm"`` or ``"leg"``.
    mirror_of : name of the panel this one mirrors, or None.
    """

    name: str
    garment: str
    vertex_ids: np.ndarray
    faces: np.ndarray
    warp_dir: np.ndarray
    ease: np.ndarray
    boundary: List[np.ndarray] = field(default_factory=list)
    body_part: str = "torso"
    mirror_of: Optional[str] = None


@dataclass
class Seam:
    """Two corresponding boundary polylines to be sewn together.

    ``verts_a[i]`` (local to ``panel_a``) is sewn to ``verts_b[i]`` (local to
    ``panel_b``); both map to the same global garment vertex.

    A *dart* is a seam of a panel with itself whose two sides (the legs) run
    from the mouth to one shared vertex, the apex (:func:`seam_kind`).
    """

    name: str
    panel_a: str
    panel_b: str
    verts_a: np.ndarray
    verts_b: np.ndarray

    @property
    def kind(self) -> str:
        """``"dart"`` or ``"seam"`` (:func:`seam_kind`)."""
        return seam_kind(self)

    @property
    def apex(self) -> Optional[int]:
        """The local vertex id of a dart's apex (both legs end there), None for a seam."""
        return int(self.verts_a[-1]) if seam_kind(self) == "dart" else None


def seam_kind(seam) -> str:
    """``"dart"`` for a seam of one panel with itself whose sides end at one vertex (the
    legs of a dart meeting at its apex), else ``"seam"``. Read from the seam's vertices
    alone, so a cut or a pattern reloaded from its files knows its darts. Works on any
    object with ``panel_a``, ``panel_b``, ``verts_a``, ``verts_b``."""
    va, vb = seam.verts_a, seam.verts_b
    if seam.panel_a == seam.panel_b and len(va) >= 2 and int(va[-1]) == int(vb[-1]) and int(va[0]) != int(vb[0]):
        return "dart"
    return "seam"


@dataclass
class GarmentCut:
    """The output of ``core.cut``.

    Attributes
    ----------
    body : dict, the body spec the cut was made on: ``{"model", "shape", "pose"}``.
    embedding : (N, V) scipy.sparse.csr_matrix, garment vertex = row @ body vertices.
    panels : list[Panel]
    seams : list[Seam]
    garments : dict garment name -> kind (``"upper"``, ``"lower"``, ``"dress"``).
    pins : dict garment name -> (k,) int global vertex ids pinned while draping
        (collar for tops, waistband for lower garments and dresses).
    hems : dict panel name -> list of (k,) local-id polylines that are open
        edges (hems, cuffs, necklines), not seams.
    materials : dict, e.g. ``{"eps_weft": 1.1, "eps_warp": 1.1, "fabric": "cotton"}``.
    darts : dict dart seam name -> ``{"panel", "intake" (m, or None for auto), "apex_offset" (m),
        "apex" ((3,) float, the true apex on the reference body, m), "line" (the line of its mouth)}``.
    """

    body: dict
    embedding: sp.csr_matrix
    panels: List[Panel]
    seams: List[Seam]
    garments: Dict[str, str] = field(default_factory=dict)
    pins: Dict[str, np.ndarray] = field(default_factory=dict)
    hems: Dict[str, List[np.ndarray]] = field(default_factory=dict)
    materials: dict = field(default_factory=dict)
    darts: Dict[str, dict] = field(default_factory=dict)

    @property
    def n_vertices(self) -> int:
        return int(self.embedding.shape[0])

    def positions(self, body_vertices: np.ndarray) -> np.ndarray:
        """Global garment vertex positions (N, 3) on a body instance (V, 3)."""
        return np.asarray(self.embedding @ body_vertices)

    def panel(self, name: str) -> Panel:
        for p in self.panels:
            if p.name == name:
                return p
        raise KeyError(f"no panel {name!r}; panels: {', '.join(p.name for p in self.panels)}")

    def panel_positions(self, panel: Panel, body_vertices: np.ndarray) -> np.ndarray:
        """Local vertex positions (n, 3) of ``panel`` on a body instance."""
        return np.asarray(self.embedding[panel.vertex_ids] @ body_vertices)
