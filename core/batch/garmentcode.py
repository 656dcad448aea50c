"""An EASE pattern as a GarmentCode pattern specification (``specification.json``).

GarmentCode (Korosteleva & Sorkine-Hornung 2023) and GarmentCodeData store a
pattern as ``{"pattern": {"panels": {...}, "stitches": [...], "panel_order":
[...]}, "properties": {...}, "parameters": {}, "parameter_order": []}``; a
panel has 2D ``vertices`` (cm), ``edges`` (``{"endpoints": [i, j]}``, a
closed loop) and a 3D placement ``translation`` (cm) / ``rotation`` (Euler
XYZ, degrees); a stitch is a pair ``[{"panel", "edge"}, {"panel", "edge"}]``.

Mapping (see docs/batch.md for its limits):

- a piece's outline (:func:`core.export.boundary.piece_loops`, the first loop,
  counter-clockwise) becomes the panel: every outline vertex a vertex, every
  outline segment a straight edge, so the shape is the solved one exactly;
  holes are left out (GarmentCode panels have none);
- a seam of ``k`` segments becomes ``k`` stitches, segment ``i`` of side a
  with segment ``i`` of side b (EASE's seam correspondence);
- the placement is the rigid motion that best carries the flat piece onto its
  position on the body (Kabsch), in GarmentCode's frame: Y up, the body
  facing +Z, centimetres (ours: Z up, facing -Y, metres).
"""
from __future__ import annotations

from typing import Dict, List, Tuple

import numpy as np

#: Our frame (x, y, z) -> GarmentCode's (x, z, -y): a rotation (Z up -> Y up, front -Y -> +Z).
TO_GARMENTCODE = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

CM = 100.0


def placement(uv: np.ndarray, xyz: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Rigid motion (R (3, 3), t (3,)) with ``xyz ≈ R @ [uv, 0] + t`` in the least-squares sense.

    Parameters
    ----------
    uv : (n, 2) piece-local 2D positions; xyz : (n, 3) the same vertices in 3D.
    """
    P = np.column_stack([uv, np.zeros(len(uv))])
    cp, cq = P.mean(axis=0), xyz.mean(axis=0)
    U, _, Vt = np.linalg.svd((P - cp).T @ (xyz - cq))
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return R, cq - R @ cp


def _panel(panel) -> Tuple[dict, Dict[Tuple[int, int], int]]:
    from scipy.spatial.transform import Rotation

    from ..export.boundary import piece_loops
    loop = piece_loops(panel)[0]
    uv = np.asarray(panel.uv, float)
    origin = uv[loop].min(axis=0)  # GarmentCode panels sit in their own frame, here from the lower left
    local = (uv - origin) * CM
    R, t = placement(local[loop], np.asarray(panel.xyz, float)[loop] * CM @ TO_GARMENTCODE.T)
    n = len(loop)
    edges = {}
    for e in range(n):
        u, v = int(loop[e]), int(loop[(e + 1) % n])
        edges[(u, v)] = edges[(v, u)] = e
    spec = {"vertices": [[round(float(x), 4), round(float(y), 4)] for x, y in local[loop]],
            "edges": [{"endpoints": [e, (e + 1) % n]} for e in range(n)],
            "translation": [round(float(x), 4) for x in t],
            "rotation": [round(float(a), 4) for a in Rotation.from_matrix(R).as_euler("XYZ", degrees=True)]}
    return spec, edges


def specification(pattern) -> dict:
    """The GarmentCode pattern specification of ``pattern`` (a JSON-ready dict)."""
    panels, edge_of = {}, {}
    for p in pattern.panels:
        panels[p.name], edge_of[p.name] = _panel(p)
    stitches: List[list] = []
    for s in pattern.seams:
        a, b = np.asarray(s.verts_a, int), np.asarray(s.verts_b, int)
        for i in range(len(a) - 1):
            ea = edge_of[s.panel_a].get((int(a[i]), int(a[i + 1])))
            eb = edge_of[s.panel_b].get((int(b[i]), int(b[i + 1])))
            if ea is not None and eb is not None:  # both segments on the outlines (holes are left out)
                stitches.append([{"panel": s.panel_a, "edge": ea}, {"panel": s.panel_b, "edge": eb}])
    return {"pattern": {"panels": panels, "stitches": stitches, "panel_order": [p.name for p in pattern.panels]},
            "parameters": {}, "parameter_order": [],
            "properties": {"curvature_coords": "relative", "normalize_panel_translation": False,
                           "units_in_meter": 100, "normalized_edge_loops": True,
                           "source": "EASE", "style": pattern.style}}
