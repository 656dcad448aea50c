"""From a sewing pattern to the cloth the solver moves (plain numpy).

The particles are the garment vertices with seams welded: one particle per
global vertex id, and ids that a seam pairs are merged too (union-find), so a
pattern whose seam sides carry different ids still closes. Rest shapes come
from the 2D pattern in each panel's grain frame (weft, warp), start positions
from the skintight embedding ``xyz``. Optionally the pattern is first refined
for the drape (:mod:`core.drape.refine`) and its gathered seams sewn as gathers
(:mod:`core.drape.gathers`: the long side stitched along the short one).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Dict, List, Optional

import numpy as np

from ..errors import DrapeError
from ..geom.mesh import unique_pairs
from ..geom.strain import weft_of
from .gathers import sew_gathers, unweld_gathers


@dataclass
class Cloth:
    """The welded garment mesh and its rest state.

    Attributes
    ----------
    n_global : int, number of global vertex ids (max id + 1).
    particle_of : (n_global,) int, particle index of each global id (-1: unused id).
    x0 : (P, 3) float, start positions (skintight embedding), metres.
    faces : (T, 3) int, triangles as particle indices (panel order, then local order).
    faces_global : (T, 3) int, the same triangles as global vertex ids.
    face_panel : (T,) int, index of the panel in ``panel_names``.
    face_garment : (T,) int, index of the garment in ``garment_names``.
    panel_names, garment_names : list of str.
    rest_inv : (T, 2, 2) float, inverse of the rest edge matrix in the grain frame:
        ``F = [x1-x0, x2-x0] @ rest_inv`` has the weft image as column 0 and the
        warp image as column 1.
    rest_area : (T,) float, pattern triangle areas in m^2.
    mass_area : (P,) float, lumped rest area per particle in m^2 (times density = mass).
    pinned : (P,) bool.
    bends : (B, 4) int, particles (a, b, e0, e1) of each interior edge: a and b
        opposite, (e0, e1) the shared edge.
    bend_weight : (B,) float, |e|^2 / (A_a + A_b) (no unit): with it, sum(w theta^2 / 2) * bending
        is the bending energy of a smooth surface, bending * kappa^2 / 2 per area, within about 10 %
        on an isotropic mesh (the discrete-shell 3|e|^2/A stored 3.3 times that: bending was ~3x the preset).
    seam_pairs : (S, 2) int, global ids sewn together, for the seam-gap metric.
    garment_of_particle : (P,) int, index into ``garment_names``.
    tether_anchor : (P,) int, the nearest pinned particle along the fabric (-1: none, or pinned).
    tether_length : (P,) float, pattern (rest) distance to it along mesh edges, metres.
    pin_lets_go : (P,) bool, the pinned particles whose pin lets go once the garment has grown to its
        pattern size (:meth:`let_go`): an upper garment's (its collar held while it is put on, as a
        dresser's hands hold it; worn, a shirt hangs from its shoulders). A lower garment's waistband
        stays held, as a belt holds it.
    sliver : (T,) bool, pattern triangles too thin for a deformation-gradient constraint
        (quality below :data:`SLIVER_QUALITY`); their edges are kept as distance constraints.
    bend_rest : (B,) float, rest dihedral angle (radians): 0 inside a panel, the skintight angle across a seam.
    edges : (E, 2) int, the sliver edges (particles); edge_rest : (E,) float, their pattern lengths.
    gathers : dict, each gathered seam sewn as a gather (:func:`core.drape.gathers.sew_gathers`'s report).
    n_pattern : int, the pattern's own global ids (``0 .. n_pattern - 1``); ids from there on were
        made for the drape (a gathered long side's own vertices, refinement midpoints).
    pattern_faces : (T0, 3) int, the pattern's own triangles as its global ids (panel order).
    refinement : dict, :func:`core.drape.refine.refine_pattern`'s report; empty when not refined.
    mesh_pattern : the pattern as draped (refined, gathers sewn; the pattern itself when neither): its
        panels' triangles, as global ids in panel order, are ``faces_global``, so per-corner data of the
        pattern (fabric UVs, seam distances) can be laid on the drape mesh from it.
    """

    n_global: int
    particle_of: np.ndarray
    x0: np.ndarray
    faces: np.ndarray
    faces_global: np.ndarray
    face_panel: np.ndarray
    face_garment: np.ndarray
    panel_names: List[str]
    garment_names: List[str]
    rest_inv: np.ndarray
    rest_area: np.ndarray
    mass_area: np.ndarray
    pinned: np.ndarray
    bends: np.ndarray
    bend_weight: np.ndarray
    seam_pairs: np.ndarray
    garment_of_particle: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    tether_anchor: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    tether_length: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sliver: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    bend_rest: np.ndarray = field(default_factory=lambda: np.zeros(0))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), int))
    edge_rest: np.ndarray = field(default_factory=lambda: np.zeros(0))
    gathers: dict = field(default_factory=dict)
    n_pattern: int = 0
    pattern_faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), int))
    refinement: dict = field(default_factory=dict)
    mesh_pattern: object = None
    pin_lets_go: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))

    @property
    def n_particles(self) -> int:
        return int(self.x0.shape[0])

    def let_go(self) -> "Cloth":
        """The same cloth with the pins of :attr:`pin_lets_go` let go: those particles free, and every
        free particle's tether recomputed to its nearest pin that still holds (none where no pin is left
        on its piece of fabric)."""
        pinned = self.pinned & ~self.pin_lets_go
        bends, bend_faces = interior_edges(self.faces)
        anchor, length = tethers(self.faces, self.rest_inv, pinned, bends, bend_faces)
        return replace(
            self,
            pinned=pinned,
            pin_lets_go=np.zeros(self.n_particles, bool),
            tether_anchor=anchor,
            tether_length=length,
        )


# Triangle quality 4*sqrt(3)*A / sum(l^2): 1 equilateral, 0 degenerate. Below this the
# inverse rest matrix is so ill-conditioned that a tiny 3D error reads as a huge strain.
SLIVER_QUALITY = 0.05
# Bending needs better-shaped triangles still: the dihedral-angle gradient scales with 1/height.
BEND_QUALITY = 0.2


def inv22(m: np.ndarray) -> np.ndarray:
    """Inverse of a stack of 2x2 matrices (n, 2, 2) (closed form: numpy's batched inv is slow here)."""
    det = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
    out = np.empty_like(m)
    out[:, 0, 0] = m[:, 1, 1] / det
    out[:, 1, 1] = m[:, 0, 0] / det
    out[:, 0, 1] = -m[:, 0, 1] / det
    out[:, 1, 0] = -m[:, 1, 0] / det
    return out


def pattern_quality(rest_inv: np.ndarray, rest_area: np.ndarray) -> np.ndarray:
    """Shape quality (T,) of the pattern triangles, 1 for equilateral, 0 for degenerate."""
    if len(rest_inv) == 0:
        return np.zeros(0)
    dm = inv22(rest_inv)
    a, b = dm[:, :, 0], dm[:, :, 1]
    l2 = np.sum(a * a, axis=1) + np.sum(b * b, axis=1) + np.sum((b - a) ** 2, axis=1)
    return 4.0 * np.sqrt(3.0) * rest_area / np.maximum(l2, 1e-300)


def grain_frame(grain) -> np.ndarray:
    """(2, 2) rows: weft (grain turned +90 degrees) and warp (the grain), unit."""
    g = np.asarray(grain, dtype=float).reshape(2)
    n = np.linalg.norm(g)
    if not np.isfinite(n) or n < 1e-12:
        raise DrapeError(f"grain {g.tolist()} is not a direction")
    g = g / n
    return np.array([weft_of(g), g])


def rest_matrices(uv: np.ndarray, faces: np.ndarray, grain) -> tuple:
    """Inverse rest edge matrices and areas of pattern triangles in the grain frame.

    Parameters
    ----------
    uv : (n, 2) pattern coordinates, metres.
    faces : (f, 3) int.
    grain : (2,) warp direction.

    Returns
    -------
    rest_inv : (f, 2, 2), area : (f,) m^2, and the (f,) bool mask of degenerate triangles.
    """
    frame = grain_frame(grain)
    q = uv @ frame.T  # (n, 2): weft, warp coordinates
    e1 = q[faces[:, 1]] - q[faces[:, 0]]
    e2 = q[faces[:, 2]] - q[faces[:, 0]]
    dm = np.stack([e1, e2], axis=2)  # columns are the edges: (f, 2, 2)
    det = dm[:, 0, 0] * dm[:, 1, 1] - dm[:, 0, 1] * dm[:, 1, 0]
    scale = np.maximum(np.einsum("fij,fij->f", dm, dm), 1e-300)
    bad = ~np.isfinite(det) | (np.abs(det) < 1e-10 * scale)
    safe = np.where(bad, 1.0, det)
    inv = np.empty_like(dm)
    inv[:, 0, 0] = dm[:, 1, 1] / safe
    inv[:, 1, 1] = dm[:, 0, 0] / safe
    inv[:, 0, 1] = -dm[:, 0, 1] / safe
    inv[:, 1, 0] = -dm[:, 1, 0] / safe
    return inv, 0.5 * np.abs(det), bad


def greedy_colouring(elements: np.ndarray, n_vertices: int) -> np.ndarray:
    """Colour elements (rows of vertex ids) so that no two of a colour share a vertex.

    Deterministic greedy (smallest free colour, in element order).

    Returns
    -------
    (E,) int colours.
    """
    used = [0] * n_vertices  # bit c set: colour c touches this vertex
    colours = np.empty(len(elements), dtype=np.int64)
    for e, row in enumerate(elements.tolist()):
        mask = 0
        for v in row:
            mask |= used[v]
        c = (~mask & (mask + 1)).bit_length() - 1  # lowest zero bit
        colours[e] = c
        bit = 1 << c
        for v in row:
            used[v] |= bit
    return colours


def colour_order(elements: np.ndarray, n_vertices: int) -> tuple:
    """Sort elements by colour.

    Returns
    -------
    order : (E,) int permutation, offsets : (C+1,) int, elements[order][offsets[c]:offsets[c+1]] has colour c.
    """
    if len(elements) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(1, dtype=np.int64)
    colours = greedy_colouring(elements, n_vertices)
    order = np.argsort(colours, kind="stable")
    counts = np.bincount(colours)
    return order, np.concatenate([[0], np.cumsum(counts)])


def dihedral_angles(x: np.ndarray, bends: np.ndarray) -> np.ndarray:
    """Signed dihedral angle (B,) radians of each bending stencil (a, b, e0, e1), 0 when flat.

    The same convention as the solver's bending kernel.
    """
    if len(bends) == 0:
        return np.zeros(0)
    x1, x2, x3, x4 = (x[bends[:, k]] for k in range(4))
    n1 = np.cross(x3 - x1, x4 - x1)
    n2 = np.cross(x4 - x2, x3 - x2)
    e = x4 - x3
    eh = e / np.maximum(np.linalg.norm(e, axis=1, keepdims=True), 1e-30)
    n1 /= np.maximum(np.linalg.norm(n1, axis=1, keepdims=True), 1e-30)
    n2 /= np.maximum(np.linalg.norm(n2, axis=1, keepdims=True), 1e-30)
    return np.arctan2(np.einsum("ij,ij->i", np.cross(n1, n2), eh), np.einsum("ij,ij->i", n1, n2))


def interior_edges(faces: np.ndarray) -> tuple:
    """Edges shared by exactly two triangles, as bending stencils.

    Returns
    -------
    bends : (B, 4) int (a, b, e0, e1): a, b opposite vertices, (e0, e1) the edge.
    bend_faces : (B, 2) int, the two triangles (of a and of b).
    """
    f = np.asarray(faces)
    t = len(f)
    e = np.concatenate([f[:, [1, 2]], f[:, [2, 0]], f[:, [0, 1]]])
    opp = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    tri = np.tile(np.arange(t), 3)
    key = np.sort(e, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, e, opp, tri = key[order], e[order], opp[order], tri[order]
    same = np.all(key[1:] == key[:-1], axis=1)
    first = np.nonzero(same)[0]
    if len(first):
        # an edge met three or more times is a non-manifold seam: no bending there
        triple = np.zeros(len(key), bool)
        t3 = np.nonzero(same[1:] & same[:-1])[0]
        triple[t3] = triple[t3 + 1] = triple[t3 + 2] = True
        first = first[~triple[first] & ~triple[first + 1]]
    bends = np.stack([opp[first], opp[first + 1], e[first, 0], e[first, 1]], axis=1).reshape(-1, 4)
    pair = np.stack([tri[first], tri[first + 1]], axis=1).reshape(-1, 2)
    keep = bends[:, 0] != bends[:, 1]
    return bends[keep].astype(np.int64), pair[keep].astype(np.int64)


#: the discrete-shell weight of a hinge is capped at ten times the equilateral value (slivers have tiny areas)
BEND_WEIGHT_CAP = 10 * 2 / np.sqrt(3.0)


def build_cloth(pattern, refine_edge: Optional[float] = None, gathers: bool = False) -> Cloth:
    """Weld a :class:`core.pattern.types.Pattern` into a :class:`Cloth`.

    Parameters
    ----------
    pattern : the pattern.
    refine_edge : float, metres, or None: refine the free-hanging cloth to edges at most this long
        (:func:`core.drape.refine.refine_pattern`); None keeps the pattern's mesh.
    gathers : sew gathered seams as gathers (the long side, sampled on its own, sewn along the
        short one at matching arc-length fractions, :mod:`core.drape.gathers`) instead of welding
        them vertex by vertex as the pattern pairs them.

    Raises
    ------
    DrapeError for a pattern without panels, mismatched arrays, or degenerate
    pattern triangles (naming the panel and triangle).
    """
    n_pattern = _check_panels(pattern)
    pattern_faces = np.concatenate(
        [np.asarray(p.vertex_ids, np.int64)[np.asarray(p.faces, np.int64).reshape(-1, 3)] for p in pattern.panels]
    )
    refinement, sewn = {}, {}
    if gathers:
        pattern = unweld_gathers(pattern)
    if refine_edge is not None:
        from .refine import refine_pattern

        pattern, refinement = refine_pattern(pattern, refine_edge)
    if gathers:
        pattern, sewn = sew_gathers(pattern)
    panels = list(pattern.panels)
    n_global = max((int(np.max(p.vertex_ids)) + 1 for p in panels if len(p.vertex_ids)), default=0)
    cloth = _weld(pattern, panels, n_global)
    cloth.n_pattern, cloth.pattern_faces, cloth.refinement, cloth.gathers = n_pattern, pattern_faces, refinement, sewn
    cloth.mesh_pattern = pattern
    return cloth


def _check_panels(pattern) -> int:
    """Check the panels' arrays; the number of global ids (max id + 1)."""
    panels = list(pattern.panels)
    if not panels:
        raise DrapeError("pattern has no panels to drape")
    n_global = 0
    for p in panels:
        n = len(p.uv)
        for name, arr, shape in (("xyz", p.xyz, (n, 3)), ("vertex_ids", p.vertex_ids, (n,))):
            if np.shape(arr) != shape:
                raise DrapeError(f"panel {p.name!r}: {name} has shape {np.shape(arr)}, expected {shape}")
        faces = np.asarray(p.faces)
        if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and (faces.min() < 0 or faces.max() >= n)):
            raise DrapeError(f"panel {p.name!r}: faces must be (f, 3) indices into its {n} vertices")
        if not np.all(np.isfinite(p.uv)) or not np.all(np.isfinite(p.xyz)):
            raise DrapeError(f"panel {p.name!r}: uv or xyz holds NaN/inf")
        if n:
            n_global = max(n_global, int(np.max(p.vertex_ids)) + 1)
    if any(int(np.min(p.vertex_ids)) < 0 for p in panels if len(p.vertex_ids)):
        raise DrapeError("pattern: negative global vertex id")
    names = {p.name for p in panels}
    for s in pattern.seams:
        if s.panel_a not in names or s.panel_b not in names:
            raise DrapeError(f"seam {s.name!r}: unknown panel {s.panel_a!r} or {s.panel_b!r}")
        if np.shape(s.verts_a) != np.shape(s.verts_b) and not getattr(s, "gathered", False):
            raise DrapeError(f"seam {s.name!r}: sides have {len(s.verts_a)} and {len(s.verts_b)} vertices")
    return n_global


def _weld(pattern, panels: list, n_global: int) -> Cloth:
    """The cloth of checked panels, seams welded."""
    # Weld: one particle per global id, plus ids paired by a seam.
    by_name: Dict[str, object] = {p.name: p for p in panels}
    seam_pairs = []
    for s in pattern.seams:
        va, vb = np.asarray(s.verts_a), np.asarray(s.verts_b)
        if va.shape != vb.shape:
            raise DrapeError(f"seam {s.name!r}: sides have {len(va)} and {len(vb)} vertices")
        ga = np.asarray(by_name[s.panel_a].vertex_ids)[va]
        gb = np.asarray(by_name[s.panel_b].vertex_ids)[vb]
        seam_pairs.append(np.stack([ga, gb], axis=1))
    pairs = np.concatenate(seam_pairs) if seam_pairs else np.zeros((0, 2), np.int64)
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    link = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n_global, n_global))
    _, label = connected_components(link, directed=False)
    # the root of a welded group is its smallest id: deterministic particle order
    first = np.full(label.max() + 1 if n_global else 0, n_global, dtype=np.int64)
    np.minimum.at(first, label, np.arange(n_global))
    roots = first[label]
    used = np.zeros(n_global, bool)
    for p in panels:
        used[np.asarray(p.vertex_ids)] = True
    root_used = np.unique(roots[used])
    particle_of_root = -np.ones(n_global, dtype=np.int64)
    particle_of_root[root_used] = np.arange(len(root_used))
    particle_of = np.where(used, particle_of_root[roots], -1)
    n_part = len(root_used)

    garment_names = sorted({p.garment for p in panels})
    x_sum = np.zeros((n_part, 3))
    x_cnt = np.zeros(n_part)
    faces_l, faces_g, fpanel, fgarm, inv_l, area_l = [], [], [], [], [], []
    garment_of_particle = np.zeros(n_part, dtype=np.int64)
    for k, p in enumerate(panels):
        ids = np.asarray(p.vertex_ids, dtype=np.int64)
        part = particle_of[ids]
        np.add.at(x_sum, part, np.asarray(p.xyz, float))
        np.add.at(x_cnt, part, 1.0)
        faces = np.asarray(p.faces, dtype=np.int64)
        inv, area, bad = rest_matrices(np.asarray(p.uv, float), faces, p.grain)
        if np.any(bad):
            t = int(np.nonzero(bad)[0][0])
            raise DrapeError(f"panel {p.name!r}: pattern triangle {t} is degenerate (zero area); re-solve the pattern")
        faces_l.append(part[faces])
        faces_g.append(ids[faces])
        fpanel.append(np.full(len(faces), k))
        g = garment_names.index(p.garment)
        fgarm.append(np.full(len(faces), g))
        garment_of_particle[part] = g
        inv_l.append(inv)
        area_l.append(area)
    x0 = x_sum / np.maximum(x_cnt, 1)[:, None]
    faces = np.concatenate(faces_l)
    rest_area = np.concatenate(area_l)
    mass_area = np.zeros(n_part)
    np.add.at(mass_area, faces.ravel(), np.repeat(rest_area / 3.0, 3))
    # a vertex held only by slivers would weigh nothing and take every correction:
    # give it a floor of a tenth of the typical vertex mass
    if n_part:
        mass_area = np.maximum(mass_area, 0.1 * float(np.median(mass_area)))
    inv_all = np.concatenate(inv_l)
    bends, bend_faces = interior_edges(faces)
    sliver = pattern_quality(inv_all, rest_area) < SLIVER_QUALITY
    edges, edge_rest = (
        rest_edges(faces[sliver], inv_all[sliver]) if sliver.any() else (np.zeros((0, 2), np.int64), np.zeros(0))
    )

    pinned = np.zeros(n_part, bool)
    lets_go = np.zeros(n_part, bool)
    kinds = getattr(pattern, "garments", None) or {}
    for garment, ids in (pattern.pins or {}).items():
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        if ids.size and (ids.min() < 0 or ids.max() >= n_global or np.any(particle_of[ids] < 0)):
            raise DrapeError(f"pins[{garment!r}]: ids must be global vertex ids of the pattern")
        pinned[particle_of[ids]] = True
        lets_go[particle_of[ids]] = kinds.get(garment) == "upper"  # a particle is one garment's (its ids)

    dm = inv22(np.concatenate(inv_l))  # rest edges x1-x0, x2-x0 per triangle
    rest_xy = np.zeros((len(faces), 3, 2))
    rest_xy[:, 1], rest_xy[:, 2] = dm[:, :, 0], dm[:, :, 1]
    corner = lambda v, t: rest_xy[t, np.argmax(faces[t] == v[:, None], axis=1)]  # noqa: E731
    if len(bends):
        e = corner(bends[:, 3], bend_faces[:, 0]) - corner(bends[:, 2], bend_faces[:, 0])
        bend_weight = np.sum(e * e, axis=1) / np.maximum(rest_area[bend_faces].sum(axis=1), 1e-16)
        # slivers give huge weights (tiny areas): cap at ten times the equilateral value
        bend_weight = np.minimum(bend_weight, BEND_WEIGHT_CAP)
    else:
        bend_weight = np.zeros(0)

    anchor, length = tethers(faces, inv_all, pinned, bends, bend_faces)
    # the dihedral angle of a thin triangle is ill-defined (it flips with any tiny motion): no bending there
    thin = pattern_quality(inv_all, rest_area) < BEND_QUALITY
    flat_ok = ~thin[bend_faces].any(axis=1) if len(bends) else np.zeros(0, bool)
    bends, bend_weight, bend_faces = bends[flat_ok], bend_weight[flat_ok], bend_faces[flat_ok]
    # a seam holds the fold it is sewn with (the skintight angle); inside a panel the rest is flat
    panel_of_face = np.concatenate(fpanel)
    across = panel_of_face[bend_faces[:, 0]] != panel_of_face[bend_faces[:, 1]]
    bend_rest = np.where(across, dihedral_angles(x0, bends), 0.0)
    return Cloth(
        tether_anchor=anchor,
        tether_length=length,
        sliver=sliver,
        bend_rest=bend_rest,
        edges=edges,
        edge_rest=edge_rest,
        n_global=n_global,
        particle_of=particle_of,
        x0=x0,
        faces=faces,
        faces_global=np.concatenate(faces_g),
        face_panel=np.concatenate(fpanel),
        face_garment=np.concatenate(fgarm),
        panel_names=[p.name for p in panels],
        garment_names=garment_names,
        rest_inv=np.concatenate(inv_l),
        rest_area=rest_area,
        mass_area=mass_area,
        pinned=pinned,
        bends=bends,
        bend_weight=bend_weight,
        seam_pairs=pairs,
        garment_of_particle=garment_of_particle,
        pin_lets_go=lets_go,
    )


def rest_edges(faces: np.ndarray, rest_inv: np.ndarray) -> tuple:
    """Unique mesh edges and their pattern (rest) lengths.

    Returns
    -------
    edges : (E, 2) int sorted pairs, length : (E,) float metres (mean over the
    triangles that share the edge: seam copies agree up to the seam mismatch).
    """
    dm = inv22(rest_inv)  # columns: rest edges x1-x0, x2-x0
    e01 = np.linalg.norm(dm[:, :, 0], axis=1)
    e02 = np.linalg.norm(dm[:, :, 1], axis=1)
    e12 = np.linalg.norm(dm[:, :, 1] - dm[:, :, 0], axis=1)
    pairs = np.concatenate([faces[:, [0, 1]], faces[:, [0, 2]], faces[:, [1, 2]]])
    lens = np.concatenate([e01, e02, e12])
    edges, inverse = unique_pairs(np.sort(pairs, axis=1))
    total = np.bincount(inverse, weights=lens, minlength=len(edges))
    count = np.bincount(inverse, minlength=len(edges))
    return edges, total / count


def _rest_corners(faces: np.ndarray, rest_inv: np.ndarray) -> np.ndarray:
    """(T, 3, 2) pattern corner positions of each triangle in its grain frame (corner 0 at the origin)."""
    dm = inv22(rest_inv)
    out = np.zeros((len(faces), 3, 2))
    out[:, 1], out[:, 2] = dm[:, :, 0], dm[:, :, 1]
    return out


def across_lengths(faces: np.ndarray, rest_inv: np.ndarray, bends: np.ndarray, bend_faces: np.ndarray) -> np.ndarray:
    """Shortest pattern distance between the two opposite vertices of each interior edge.

    The two triangles are unfolded about their shared edge; the straight line
    between the opposite vertices counts where it crosses the edge, else the
    path bends at the nearer edge end. Added to the edge graph, these
    shortcuts bring shortest paths close to true fabric geodesics.
    """
    if len(bends) == 0:
        return np.zeros(0)
    corners = _rest_corners(faces, rest_inv)

    def local(v, t):
        return corners[t, np.argmax(faces[t] == v[:, None], axis=1)]

    a, b, e0, e1 = bends.T
    ta, tb = bend_faces[:, 0], bend_faces[:, 1]
    # edge frame per side: origin at e0, x along the edge; opposite vertex height |y|
    pa0, pa1, pa = local(e0, ta), local(e1, ta), local(a, ta)
    pb0, pb1, pb = local(e0, tb), local(e1, tb), local(b, tb)
    ea, eb = pa1 - pa0, pb1 - pb0
    la = np.maximum(np.linalg.norm(ea, axis=1), 1e-30)
    lb = np.maximum(np.linalg.norm(eb, axis=1), 1e-30)
    ua, ub = ea / la[:, None], eb / lb[:, None]
    cross = lambda u, w: u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]  # noqa: E731
    xa = np.einsum("ij,ij->i", pa - pa0, ua)
    ya = np.abs(cross(ua, pa - pa0))
    xb = np.einsum("ij,ij->i", pb - pb0, ub)
    yb = np.abs(cross(ub, pb - pb0))
    length = 0.5 * (la + lb)
    straight = np.hypot(xa - xb, ya + yb)
    t = xa + (xb - xa) * ya / np.maximum(ya + yb, 1e-30)
    via0 = np.hypot(xa, ya) + np.hypot(xb, yb)
    via1 = np.hypot(xa - length, ya) + np.hypot(xb - length, yb)
    inside = (t >= 0) & (t <= length)
    return np.where(inside, straight, np.minimum(via0, via1))


def tethers(
    faces: np.ndarray, rest_inv: np.ndarray, pinned: np.ndarray, bends: np.ndarray = None, bend_faces: np.ndarray = None
) -> tuple:
    """Long-range attachments (Kim et al. 2012): each free particle's nearest pin.

    A particle may never be farther (in 3D) from its nearest pinned particle than
    the fabric distance between them in the pattern; that bound holds for any
    inextensible drape, and enforcing it lets a hanging garment carry its weight
    without the slow stretch of Gauss-Seidel on long chains. Fabric distance is
    the shortest path along rest mesh edges and the unfolded diagonals across
    them (never shorter than the geodesic, so the tether is never tighter than
    the true bound; a few percent longer on irregular meshes).

    Returns
    -------
    anchor : (P,) int (-1 where no pin is reachable or the particle is pinned), length : (P,) float.
    """
    n = len(pinned)
    anchor = -np.ones(n, dtype=np.int64)
    length = np.zeros(n)
    pins = np.nonzero(pinned)[0]
    if len(pins) == 0:
        return anchor, length
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    edges, lens = rest_edges(faces, rest_inv)
    if bends is not None and len(bends):
        edges = np.concatenate([edges, bends[:, :2]])
        lens = np.concatenate([lens, across_lengths(faces, rest_inv, bends, bend_faces)])
    keep = lens > 0
    edges, lens = np.sort(edges[keep], axis=1), lens[keep]
    # a link met twice (an across-edge shortcut that is also an edge) counts once, at its shorter length
    # (coo would add them)
    order = np.lexsort((lens, edges[:, 1], edges[:, 0]))
    edges, lens = edges[order], lens[order]
    first = np.ones(len(edges), bool)
    first[1:] = np.any(edges[1:] != edges[:-1], axis=1)
    graph = coo_matrix((lens[first], (edges[first, 0], edges[first, 1])), shape=(n, n)).tocsr()
    dist, _, source = dijkstra(graph, directed=False, indices=pins, min_only=True, return_predecessors=True)
    ok = np.isfinite(dist) & ~pinned & (source >= 0)
    anchor[ok] = source[ok]
    length[ok] = dist[ok]
    return anchor, length


def two_rings(faces: np.ndarray, n: int) -> tuple:
    """The particles within two mesh rings of each particle (the self-collision's fabric neighbours).

    Parameters
    ----------
    faces : (T, 3) int, particle triangles.
    n : number of particles.

    Returns
    -------
    starts : (n + 1,) int64, CSR row starts; indices : int64, the neighbours of
    particle i are ``indices[starts[i]:starts[i + 1]]`` (sorted, itself included).
    """
    from scipy.sparse import coo_matrix

    f = np.asarray(faces, dtype=np.int64)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    a = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)).tocsr()
    a.data[:] = 1.0
    r = (a + a @ a).tocsr()
    r.sort_indices()
    return r.indptr.astype(np.int64), r.indices.astype(np.int64)
