"""The optimizer's unknowns: every panel flattened once, stacked as contiguous blocks.

Seam vertices are duplicated, one copy per panel; panel ``k``'s vertices are
the unknowns ``offset .. offset + n`` and its faces the rows
``face_offset .. face_offset + f`` of the stacked arrays, so per-panel sums
are ``np.add.reduceat``'s.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional

import numpy as np
import scipy.sparse as sp

from ...errors import PatternError
from ...geom.mesh import triangle_areas
from ...progress import Progress, report
from . import init as _init
from .mirror_flat import approximate_mirror, self_mirror_map, symmetric_flattening

#: Smallest 2D area a triangle may keep in a step, as a fraction of its initial area (flip guard).
AREA_FLOOR = 1e-6


@dataclass(frozen=True)
class PanelData:
    """One panel's block: ``offset``/``n`` (its unknowns), ``faces`` (f, 3) local and ``gfaces`` global
    ids, ``vertex_ids`` (n,) rows of the cut's embedding, ``warp_dir`` (f, 3), ``ease`` (f,), the initial
    flattening ``uv0`` (n, 2, metres), its gradient operators ``G`` (f, 3, 2), ``area0`` (f,) its signed
    areas (square metres) and ``face_offset``."""

    name: str
    offset: int
    n: int
    faces: np.ndarray
    gfaces: np.ndarray
    vertex_ids: np.ndarray
    warp_dir: np.ndarray
    ease: np.ndarray
    uv0: np.ndarray
    G: np.ndarray
    area0: np.ndarray
    face_offset: int


@dataclass(frozen=True)
class PanelBlocks:
    """All panels stacked (built by :func:`flatten_panels`).

    ``n`` unknowns and ``faces`` (f, 3) global ids (``face_columns``: its
    three columns, contiguous); ``vertex_faces`` (n, f) sparse incidence (the
    flip guard's local re-checks); ``vertex_offsets``/``vertex_counts`` and
    ``face_offsets``/``face_counts`` per panel; ``uv0`` (n, 2) the initial
    flattening, ``G`` (f, 3, 2) its gradient operators, ``area0`` (f,) its
    areas; ``area_floor`` (f,) the flip guard's smallest area; ``warp0``
    (f, 2) the 3D warp pulled back to ``uv0`` (a material direction; ``warp_columns``: its two
    columns, contiguous) and ``warp_vote`` (f,) its grain-vote weight (3D area, 0 where degenerate);
    ``corners`` (f, 3) each triangle's corners as rows of the cut's embedding (a body's positions
    ``P[corners]`` are the stacked panels' triangles in one gather).
    """

    panels: List[PanelData]
    n: int
    faces: np.ndarray
    face_columns: tuple
    vertex_faces: sp.csr_matrix
    vertex_offsets: np.ndarray
    vertex_counts: np.ndarray
    face_offsets: np.ndarray
    face_counts: np.ndarray
    uv0: np.ndarray
    G: np.ndarray
    area0: np.ndarray
    area_floor: np.ndarray
    warp0: np.ndarray
    warp_vote: np.ndarray
    warp_columns: tuple
    corners: np.ndarray

    def per_vertex(self, x: np.ndarray) -> np.ndarray:
        """Per-panel values (p, ...) repeated onto every unknown of the panel (n, ...)."""
        return np.repeat(x, self.vertex_counts.astype(int), axis=0)

    def panel_slices(self, pd: PanelData):
        """(vertex slice, face slice) of panel ``pd`` in the stacked arrays."""
        return slice(pd.offset, pd.offset + pd.n), slice(pd.face_offset, pd.face_offset + len(pd.faces))


def flatten_panels(cut, positions: np.ndarray, progress: Optional[Progress] = None) -> PanelBlocks:
    """Flatten every panel of ``cut`` at ``positions`` (N, 3) (:func:`core.pattern.optimizer.init.flatten_panel`) and stack them."""
    panels: List[PanelData] = []
    flat = []
    offset = face_offset = 0
    for k, p in enumerate(cut.panels):
        report(progress, 0.8 * k / len(cut.panels), f"flattening panel {p.name}")
        xyz = positions[np.asarray(p.vertex_ids, int)]
        F = np.asarray(p.faces, np.int64)
        if np.all(triangle_areas(xyz, F) <= 0):
            raise PatternError(f"panel {p.name!r}: all triangles are degenerate on the reference body")
        fl = _init.flatten_panel(xyz, F, np.asarray(p.warp_dir, float))
        mirror = None
        if p.mirror_of is None:  # a panel across the body: its flattening made symmetric too
            mirror = self_mirror_map(xyz, F)
            if mirror is None:  # its mesh not its own mirror image (the skirt topology)
                mirror = approximate_mirror(xyz, F)
        if mirror is not None:
            fl = symmetric_flattening(fl, xyz, F, np.asarray(p.warp_dir, float), mirror)
        flat.append(fl)
        panels.append(
            PanelData(
                p.name,
                offset,
                len(p.vertex_ids),
                F,
                F + offset,
                np.asarray(p.vertex_ids, int),
                np.asarray(p.warp_dir, float),
                np.asarray(p.ease, float),
                fl["uv"],
                fl["G"],
                fl["area"],
                face_offset,
            )
        )
        offset += len(p.vertex_ids)
        face_offset += len(F)
    gfaces = np.concatenate([pd.gfaces for pd in panels])
    area0 = np.concatenate([pd.area0 for pd in panels])
    nf = len(gfaces)
    warp0 = np.concatenate([fl["warp"] for fl in flat])
    return PanelBlocks(
        panels=panels,
        n=offset,
        faces=gfaces,
        face_columns=tuple(np.ascontiguousarray(gfaces[:, c]) for c in range(3)),
        vertex_faces=sp.csr_matrix(
            (np.ones(3 * nf), (gfaces.ravel(), np.repeat(np.arange(nf), 3))), shape=(offset, nf)
        ),
        vertex_offsets=np.array([pd.offset for pd in panels]),
        vertex_counts=np.array([pd.n for pd in panels], float),
        face_offsets=np.array([pd.face_offset for pd in panels]),
        face_counts=np.array([len(pd.faces) for pd in panels]),
        uv0=np.concatenate([pd.uv0 for pd in panels]),
        G=np.concatenate([pd.G for pd in panels]),
        area0=area0,
        area_floor=AREA_FLOOR * np.abs(area0),
        warp0=warp0,
        warp_vote=np.concatenate([fl["warp_weight"] for fl in flat]),
        # the iterations read them every time: strided column views cost twice a contiguous array's pass
        warp_columns=(np.ascontiguousarray(warp0[:, 0]), np.ascontiguousarray(warp0[:, 1])),
        corners=np.concatenate([pd.vertex_ids[pd.faces] for pd in panels]),
    )
