"""What a drape returns: :class:`DrapeResult`, collected from the solver's final state."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Optional

import numpy as np

from .mesh import Cloth
from .strain import face_strains, vertex_average


@dataclass
class DrapeResult:
    """A settled (or frame-limited) drape.

    Attributes
    ----------
    positions : (N, 3) float, draped position of every global garment vertex id, metres
        (ids no panel uses, if any, stay at 0; see ``used``). The pattern's own ids come
        first (``0 .. pattern_vertices - 1``, the pattern's vertices as draped); the ids after
        them are the drape mesh's own vertices (refinement midpoints, a gathered seam's long side).
    faces : (T, 3) int, the draped (refined) triangles as global vertex ids (panel order).
    pattern_vertices : int, the pattern's own global ids (N when the mesh was not refined).
    pattern_faces : (T0, 3) int, the pattern's own triangles (what an export of the pattern checks).
    mesh_pattern : the pattern as draped (:attr:`core.drape.mesh.Cloth.mesh_pattern`): its panels'
        triangles are ``faces``, for laying the pattern's per-corner data (fabric UVs) on the drape mesh.
    refinement : dict, the drape mesh's refinement (:func:`core.drape.refine.refine_pattern`'s
        report: target edge, edge lengths and triangle counts before and after); empty if not refined.
    gathers : dict, seam name -> ``{"ratio", "long_vertices", "short_vertices", "stitch_points"}``,
        each gathered seam sewn as a gather (:func:`core.drape.gathers.sew_gathers`): long / short
        rest length, the long side's vertices, the short side's before and the points added to it.
    used : (N,) bool, ids that some panel uses.
    strain_weft, strain_warp : (N,) float, per-vertex stretch relative to the pattern
        (0 = pattern size, 0.02 = 2 % longer, negative = compressed), area-weighted from the faces.
    face_strain_weft, face_strain_warp, face_shear : (T,) float, per-triangle |F w| - 1,
        |F g| - 1 and the shear angle (degrees) between the weft and warp images minus 90.
    face_garment : (T,) int index into ``garment_names``.
    garment_names : list of str.
    start_positions : (N, 3) float, the skintight embedding the drape started from.
    seam_pairs : (S, 2) int, global ids sewn together.
    frames : int, frames simulated.
    settled : bool; settle_reason : ``"settled"`` or ``"frame limit"``.
    speed_history : (frames,) float, RMS particle speed per frame (m/s), fastest
        ``options.settle_trim`` share left out.
    timings : dict of seconds: ``prepare``, ``compile``, ``simulate``, ``total``.
    material : dict, the material used; options : dict, the options used; device : str.
    self_collision : bool, whether particle self-collision was on; self_radius : float, its radius (m).
    speed : (N,) float, m/s, each vertex's speed at the last frame (where it still moves).
    face_valid : (T,) bool, False for pattern slivers (held by edge constraints; their
        strain is not meaningful and reads 0).
    stretch_limit : dict, where the fabric is stretched beyond its material's ``max_stretch``
        (:func:`stretch_limit_report`): for all, per garment and per piece, the share of fabric area
        past the limit along the weft and the warp and the largest stretch of each.
    """

    positions: np.ndarray
    faces: np.ndarray
    used: np.ndarray
    strain_weft: np.ndarray
    strain_warp: np.ndarray
    face_strain_weft: np.ndarray
    face_strain_warp: np.ndarray
    face_shear: np.ndarray
    face_garment: np.ndarray
    garment_names: list
    start_positions: np.ndarray
    seam_pairs: np.ndarray
    frames: int
    settled: bool
    settle_reason: str
    speed_history: np.ndarray
    timings: dict
    material: dict
    options: dict
    device: str
    self_collision: bool = False
    self_radius: float = 0.0
    face_valid: Optional[np.ndarray] = None
    speed: Optional[np.ndarray] = None
    pattern_vertices: int = 0
    pattern_faces: Optional[np.ndarray] = None
    refinement: dict = field(default_factory=dict)
    mesh_pattern: object = None
    gathers: dict = field(default_factory=dict)
    stretch_limit: dict = field(default_factory=dict)


def _over(weft: np.ndarray, warp: np.ndarray, area: np.ndarray, limit: float) -> dict:
    """The share (%) of ``area`` whose weft (warp) stretch is beyond ``limit``, and the largest stretches (%)."""
    total = float(area.sum())

    def share(strain):
        return 100.0 * float(area[strain > limit].sum()) / total if total > 0.0 else 0.0

    def largest(strain):
        return 100.0 * float(strain.max()) if len(strain) else 0.0

    return {
        "weft_over_pct": share(weft),
        "warp_over_pct": share(warp),
        "weft_max_pct": largest(weft),
        "warp_max_pct": largest(warp),
    }


def stretch_limit_report(
    cloth: Cloth, weft: np.ndarray, warp: np.ndarray, valid: np.ndarray, max_stretch: float
) -> dict:
    """Where a drape asks the fabric for more stretch than it gives.

    Parameters
    ----------
    cloth : the welded cloth (its faces' pattern areas, panels and garments).
    weft, warp : (T,) float, each triangle's stretch relative to the pattern (fractions).
    valid : (T,) bool, the triangles measured (not pattern slivers).
    max_stretch : the material's ``max_stretch`` (fraction).

    Returns
    -------
    dict: ``max_stretch_pct``; ``all`` and, per garment name, ``garments[name]`` with ``pieces[panel]``:
    ``weft_over_pct`` / ``warp_over_pct`` (the share of the fabric's area, the pattern's, stretched
    beyond ``max_stretch`` along that grain), ``weft_max_pct`` / ``warp_max_pct`` (the largest stretch,
    %). With pd's strain limit (:attr:`DrapeOptions.strain_limit`) a grain held at its limit sits just
    past it (by the penalty's excess), so it counts: the share is the fabric at or past its limit.
    """
    area = cloth.rest_area
    limit = float(max_stretch)
    out = {"max_stretch_pct": 100.0 * limit, "all": _over(weft[valid], warp[valid], area[valid], limit), "garments": {}}
    for g, name in enumerate(cloth.garment_names):
        sel = valid & (cloth.face_garment == g)
        entry = _over(weft[sel], warp[sel], area[sel], limit)
        entry["pieces"] = {}
        for k in np.unique(cloth.face_panel[sel]):
            piece = sel & (cloth.face_panel == k)
            entry["pieces"][cloth.panel_names[int(k)]] = _over(weft[piece], warp[piece], area[piece], limit)
        out["garments"][name] = entry
    return out


def collect(
    cloth: Cloth,
    x: np.ndarray,
    v: np.ndarray,
    settling,
    timings: dict,
    material,
    options,
    device: str,
    self_radius: float,
) -> DrapeResult:
    """The result of a drape from its final particle state.

    Parameters
    ----------
    cloth : the welded cloth that was draped.
    x, v : (P, 3) float, final particle positions (m) and velocities (m/s).
    settling : :class:`core.drape.schedule.Settling`, how the drape ended.
    timings : dict of seconds.
    material : :class:`Material`; options : :class:`DrapeOptions`; device : its name.
    self_radius : m, the self-collision radius, 0 when self-collision was off.
    """
    n = cloth.n_particles
    xp = np.asarray(x).astype(float)
    vp = np.linalg.norm(np.asarray(v).astype(float), axis=1)
    valid = ~cloth.sliver if len(cloth.sliver) else np.ones(len(cloth.faces), bool)
    fw, fg, fs = (np.where(valid, a, 0.0) for a in face_strains(xp, cloth))
    weight = cloth.rest_area * valid
    sw = vertex_average(fw, cloth.faces, weight, n)
    sg = vertex_average(fg, cloth.faces, weight, n)
    used = cloth.particle_of >= 0
    src = np.where(used, cloth.particle_of, 0)
    return DrapeResult(
        positions=np.where(used[:, None], xp[src], 0.0),
        faces=cloth.faces_global.copy(),
        used=used,
        strain_weft=np.where(used, sw[src], 0.0),
        strain_warp=np.where(used, sg[src], 0.0),
        face_strain_weft=fw,
        face_strain_warp=fg,
        face_shear=fs,
        face_valid=valid,
        speed=np.where(used, vp[src], 0.0),
        face_garment=cloth.face_garment.copy(),
        garment_names=list(cloth.garment_names),
        start_positions=np.where(used[:, None], cloth.x0[src], 0.0),
        seam_pairs=cloth.seam_pairs.copy(),
        frames=settling.frames,
        settled=settling.settled,
        settle_reason=settling.reason,
        speed_history=settling.speeds,
        timings=timings,
        material=material.to_json(),
        options=asdict(options),
        device=device,
        self_collision=self_radius > 0.0,
        self_radius=self_radius,
        pattern_vertices=int(cloth.n_pattern or cloth.n_global),
        pattern_faces=(cloth.pattern_faces if len(cloth.pattern_faces) else cloth.faces_global).copy(),
        refinement=dict(cloth.refinement),
        mesh_pattern=cloth.mesh_pattern,
        gathers=dict(cloth.gathers),
        stretch_limit=stretch_limit_report(cloth, fw, fg, valid, getattr(material, "max_stretch", np.inf)),
    )
