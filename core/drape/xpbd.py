"""The drape: small-step Gauss-Seidel XPBD of a welded pattern on a static body.

``drape(pattern, body_vertices, body_faces)`` starts the garment on the body
(the skintight embedding), lets it relax to its pattern size under gravity,
pins and body contact (the rest shape grows from the skintight stretch to the
pattern's over the first ``grow_frames``, so loose fabric unfolds
quasi-statically and a looser pattern drapes like a continuation of a tighter
one), and stops once it has settled (its kinetic energy stays
under a threshold for some frames) or at a frame limit; the result says which.

Body contact has thickness and friction. Self-collision is optional
(``self_collision=True``): particle against particle, found with a hash grid
and resolved Jacobi-style, so it stays repeatable; off by default, when garment
layers and folds may pass through each other.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, fields
from typing import Mapping, Optional, Union

import numpy as np

from ..errors import DrapeError
from ..progress import Progress, report
from .materials import Material, get_material
from .mesh import Cloth, build_cloth, colour_order, rest_edges

# most self-collision candidates a particle keeps (a particle in a fold meets a few of the other layer)
SELF_PAIRS = 16


@dataclass
class DrapeOptions:
    """Simulation settings.

    Attributes
    ----------
    device : ``"cpu"`` (default, bitwise repeatable) or ``"cuda"`` / ``"cuda:0"``.
    fps : frames per second of simulated time; a frame is the unit of settling checks.
    substeps : XPBD substeps per frame (each projects every constraint once).
    max_frames : frame limit.
    min_frames : frames simulated before settling may be declared.
    settle_speed : m/s, the root-mean-square particle speed under which a frame counts as still.
    settle_trim : fraction of the fastest particles left out of that RMS: a few particles
        caught between body parts (armpit, crotch) chatter against the contact planes
        and would otherwise hold a visibly still drape from settling.
    settle_frames : consecutive still frames that mean settled.
    damping : 1/s, velocity decay rate (air drag and internal friction).
    gravity : m/s^2, along -Z.
    thickness, friction : override the material's collision offset (m) and friction.
    search_distance : m, how far from the body a particle looks for contact; a particle
        deeper inside the body than this is not pushed out.
    contact_interval : substeps between contact searches (in between, contact is
        resolved against the plane of the closest body triangle found).
    tether_slack : long-range attachments let a particle stray this fraction beyond its
        fabric distance from the nearest pin (0.01 = 1 %); None disables them.
    max_speed : m/s, an RMS speed above this is a diverged (exploding) simulation.
    max_extent : m, a garment bounding box larger than this is a diverged (runaway) one.
    max_strain : a triangle stretched more than this fraction (3 = 300 %) is a diverged drape.
    grow_frames : frames over which the fabric grows from its skintight start to its pattern size
        (the rest stretch of every triangle goes linearly from its start value to 1, substep by
        substep): a loose garment unfolds quasi-statically instead of springing off the body; 0: at once.
    self_collision : keep the garment's particles apart (folds and layers stack instead of
        passing through each other). Off by default: it is particle against particle only (a
        layer can still slip through another between vertices where the mesh is coarser than
        the radius), roughly doubles the time per frame, and a loose garment squeezed between
        body parts (armpits) may chatter and settle later.
    self_radius : m, particle radius of the self-collision (two particles stay twice this apart);
        None: 0.4 x the median pattern edge, so that a layer cannot slip between the vertices of another.
    self_exclude : particles that start (skintight) closer than this many self-collision
        diameters and lie within two mesh rings of each other are fabric neighbours and do
        not collide (nor do particles that start within half a radius of each other).
    self_interval : substeps between searches for self-collision candidates (a hash grid over
        the particles); every substep resolves the candidates found.
    """
    device: str = "cpu"
    fps: float = 30.0
    substeps: int = 20
    max_frames: int = 120
    min_frames: int = 10
    settle_speed: float = 0.01
    settle_frames: int = 5
    settle_trim: float = 0.02
    damping: float = 3.0
    gravity: float = 9.81
    thickness: Optional[float] = None
    friction: Optional[float] = None
    search_distance: float = 0.03
    tether_slack: Optional[float] = 0.01
    contact_interval: int = 10
    max_speed: float = 30.0
    max_extent: float = 6.0
    max_strain: float = 3.0
    grow_frames: int = 20
    self_collision: bool = False
    self_radius: Optional[float] = None
    self_exclude: float = 1.5
    self_interval: int = 5

    @staticmethod
    def coerce(options: Union[None, "DrapeOptions", Mapping]) -> "DrapeOptions":
        if options is None:
            return DrapeOptions()
        if isinstance(options, DrapeOptions):
            opts = options
        elif isinstance(options, Mapping):
            known = {f.name for f in fields(DrapeOptions)}
            unknown = sorted(set(options) - known)
            if unknown:
                raise DrapeError(f"unknown drape option(s) {', '.join(unknown)}; options: {', '.join(sorted(known))}")
            opts = DrapeOptions(**dict(options))
        else:
            raise DrapeError(f"options must be DrapeOptions or a dict, not {type(options).__name__}")
        opts.validate()
        return opts

    def validate(self) -> None:
        def positive(name, integer=False):
            value = getattr(self, name)
            ok = isinstance(value, (int, np.integer)) if integer else isinstance(value, (int, float, np.number))
            if not ok or not np.isfinite(value) or value <= 0:
                kind = "a positive integer" if integer else "a positive number"
                raise DrapeError(f"drape option {name} = {value!r}: expected {kind}")
        for name in ("fps", "settle_speed", "search_distance", "max_speed", "max_extent", "max_strain"):
            positive(name)
        for name in ("substeps", "max_frames", "settle_frames", "contact_interval", "self_interval"):
            positive(name, integer=True)
        if not (0.0 <= self.settle_trim < 0.5):
            raise DrapeError(f"drape option settle_trim = {self.settle_trim!r}: expected a fraction in [0, 0.5)")
        for name in ("damping", "gravity", "min_frames", "grow_frames"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0:
                raise DrapeError(f"drape option {name} = {value!r}: expected a number >= 0")
        if not isinstance(self.self_collision, (bool, np.bool_)):
            raise DrapeError(f"drape option self_collision = {self.self_collision!r}: expected true or false")
        if not np.isfinite(self.self_exclude) or self.self_exclude < 0:
            raise DrapeError(f"drape option self_exclude = {self.self_exclude!r}: expected a number >= 0")
        for name in ("thickness", "friction", "tether_slack", "self_radius"):
            value = getattr(self, name)
            if value is not None and (not np.isfinite(value) or value < 0):
                raise DrapeError(f"drape option {name} = {value!r}: expected a number >= 0 or None")


@dataclass
class DrapeResult:
    """A settled (or frame-limited) drape.

    Attributes
    ----------
    positions : (N, 3) float, draped position of every global garment vertex id, metres
        (ids no panel uses, if any, stay at 0; see ``used``).
    faces : (T, 3) int, triangles as global vertex ids (panel order).
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


def face_deformation(x: np.ndarray, faces: np.ndarray, rest_inv: np.ndarray) -> np.ndarray:
    """Deformation gradients F = [x1-x0, x2-x0] rest_inv, (T, 3, 2): columns weft, warp images."""
    ds = np.stack([x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]]], axis=2)
    return ds @ rest_inv


def face_strains(x: np.ndarray, cloth: Cloth) -> tuple:
    """Per-face weft strain, warp strain (fractions) and shear angle (degrees) of positions ``x`` (P, 3)."""
    f = face_deformation(x, cloth.faces, cloth.rest_inv)
    a, b = f[:, :, 0], f[:, :, 1]
    la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(la * lb, 1e-30)
    shear = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) - 90.0
    return la - 1.0, lb - 1.0, shear


def vertex_average(values: np.ndarray, faces: np.ndarray, area: np.ndarray, n: int) -> np.ndarray:
    """Area-weighted average of per-face ``values`` (T,) at the n vertices."""
    num = np.zeros(n)
    den = np.zeros(n)
    np.add.at(num, faces.ravel(), np.repeat(values * area, 3))
    np.add.at(den, faces.ravel(), np.repeat(area, 3))
    return num / np.maximum(den, 1e-30)


def _check_body(body_vertices, body_faces) -> tuple:
    v = np.asarray(body_vertices, dtype=float)
    f = np.asarray(body_faces)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.all(np.isfinite(v)):
        raise DrapeError(f"body vertices must be a finite (V, 3) array, got shape {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3 or len(f) == 0 or not np.issubdtype(f.dtype, np.integer) \
            or f.min() < 0 or f.max() >= len(v):
        raise DrapeError(f"body faces must be (F, 3) integer indices into the {len(v)} body vertices")
    return v, f.astype(np.int32)


def _device(wp, name: str):
    try:
        dev = wp.get_device(name)
    except Exception:
        dev = None
    if dev is None or (dev.is_cuda and not wp.is_cuda_available()):
        have = ", ".join(str(d) for d in wp.get_devices())
        raise DrapeError(f"drape device {name!r} is not available; available: {have}")
    return dev


def drape(pattern, body_vertices, body_faces, material: Union[None, str, Material, Mapping] = None,
          options: Union[None, DrapeOptions, Mapping] = None,
          progress: Optional[Progress] = None) -> DrapeResult:
    """Drape a sewing pattern on a body with XPBD.

    Parameters
    ----------
    pattern : :class:`core.pattern.types.Pattern`, with the skintight embedding ``xyz``
        of every panel on this body.
    body_vertices : (V, 3) float, metres, +Z up.
    body_faces : (F, 3) int, outward-oriented triangles.
    material : preset name, :class:`Material` or dict; default: the pattern's
        ``materials["fabric"]``, else cotton.
    options : :class:`DrapeOptions` or a dict of its fields.
    progress : optional ``progress(fraction, message)``; may raise Cancelled.

    Returns
    -------
    DrapeResult

    Raises
    ------
    DrapeError on invalid input, an unavailable device, or divergence (naming
    the frame and the likely cause).
    """
    t_start = time.perf_counter()
    opts = DrapeOptions.coerce(options)
    if material is None:
        material = (getattr(pattern, "materials", None) or {}).get("fabric")
    mat = get_material(material)
    thickness = mat.thickness if opts.thickness is None else float(opts.thickness)
    friction = mat.friction if opts.friction is None else float(opts.friction)
    body_v, body_f = _check_body(body_vertices, body_faces)
    report(progress, 0.0, "drape: welding the pattern")
    cloth = build_cloth(pattern)

    from . import kernels as K
    wp = K.wp
    wp.init()
    dev = _device(wp, opts.device)

    # Constraint order: colour by colour (Gauss-Seidel without write conflicts).
    good = np.nonzero(~cloth.sliver)[0] if len(cloth.sliver) else np.arange(len(cloth.faces))
    tri_order, tri_off = colour_order(cloth.faces[good], cloth.n_particles)
    tri_order = good[tri_order]
    bend_order, bend_off = colour_order(cloth.bends, cloth.n_particles)
    edge_order, edge_off = colour_order(cloth.edges, cloth.n_particles)
    mass = mat.density * cloth.mass_area
    if np.any(mass <= 0):
        raise DrapeError("pattern has a vertex that belongs to no triangle (zero mass)")
    inv_mass = np.where(cloth.pinned, 0.0, 1.0 / mass)
    t_prep = time.perf_counter()

    f32 = np.float32
    x = wp.array(cloth.x0.astype(f32), dtype=wp.vec3, device=dev)
    v = wp.zeros(cloth.n_particles, dtype=wp.vec3, device=dev)
    x_prev = wp.zeros(cloth.n_particles, dtype=wp.vec3, device=dev)
    w = wp.array(inv_mass.astype(f32), dtype=float, device=dev)
    tri = wp.array(cloth.faces[tri_order].astype(np.int32), dtype=int, device=dev)
    rest_inv = wp.array(cloth.rest_inv[tri_order].astype(f32), dtype=wp.mat22, device=dev)
    area = wp.array(cloth.rest_area[tri_order].astype(f32), dtype=float, device=dev)
    bends = wp.array(cloth.bends[bend_order].astype(np.int32).reshape(-1, 4), dtype=int, device=dev)
    edges = wp.array(cloth.edges[edge_order].astype(np.int32).reshape(-1, 2), dtype=int, device=dev)
    edge_rest = wp.array(cloth.edge_rest[edge_order].astype(f32), dtype=float, device=dev)
    bend_w = wp.array(cloth.bend_weight[bend_order].astype(f32), dtype=float, device=dev)
    bend_rest = wp.array(cloth.bend_rest[bend_order].astype(f32), dtype=float, device=dev)
    anchor = wp.array(cloth.tether_anchor.astype(np.int32), dtype=int, device=dev)
    tether_len = wp.array(cloth.tether_length.astype(f32), dtype=float, device=dev)
    fw0, fg0, _ = face_strains(cloth.x0, cloth)
    start_stretch = np.clip(np.stack([fw0, fg0], axis=1) + 1.0, 0.2, 5.0)  # the skintight start's stretch
    tri_start = wp.array(start_stretch[tri_order].astype(f32), dtype=wp.vec2, device=dev)
    e_sorted = cloth.edges[edge_order]
    edge_start = wp.array(np.linalg.norm(cloth.x0[e_sorted[:, 1]] - cloth.x0[e_sorted[:, 0]], axis=1).astype(f32)
                          if len(e_sorted) else np.zeros(0, f32), dtype=float, device=dev)
    grow = wp.array([0.0 if opts.grow_frames > 0 else 1.0], dtype=float, device=dev)
    c_point = wp.zeros(cloth.n_particles, dtype=wp.vec3, device=dev)
    c_normal = wp.zeros(cloth.n_particles, dtype=wp.vec3, device=dev)
    c_active = wp.zeros(cloth.n_particles, dtype=int, device=dev)
    body_points = wp.array(body_v.astype(f32), dtype=wp.vec3, device=dev)
    body_idx = wp.array(body_f.reshape(-1), dtype=wp.int32, device=dev)
    body = wp.Mesh(points=body_points, indices=body_idx)
    wp.load_module(K, device=dev)
    t_compile = time.perf_counter()

    self_on = bool(opts.self_collision)
    if opts.self_radius is not None:
        self_radius = float(opts.self_radius)
    else:
        _, edge_len = rest_edges(cloth.faces, cloth.rest_inv)
        self_radius = 0.4 * float(np.median(edge_len)) if len(edge_len) else 0.0
    self_on = self_on and self_radius > 0.0

    dt = 1.0 / (opts.fps * opts.substeps)
    fall = float(opts.gravity) * dt * dt
    if fall > thickness:
        # XPBD stays bounded at any step, but a step this long lets the cloth pass
        # through the body between contact checks and stalls its constraints: refuse it.
        raise DrapeError(f"time step {dt * 1e3:.3g} ms ({opts.substeps} substeps at {opts.fps:g} fps) is too "
                         f"large: gravity alone moves a particle {fall * 1e3:.2f} mm per substep, more than the "
                         f"{thickness * 1e3:.1f} mm contact thickness; use more substeps or a higher fps")
    inv_dt2 = 1.0 / (dt * dt)
    keep = float(np.exp(-opts.damping * dt))
    gravity = wp.vec3(0.0, 0.0, -float(opts.gravity))
    n = cloth.n_particles
    cmds = [wp.launch(K.predict, n, inputs=[x, v, x_prev, w, gravity, dt, keep], device=dev, record_cmd=True)]
    if opts.grow_frames > 0:
        cmds.append(wp.launch(K.advance_grow, 1, inputs=[grow, 1.0 / (opts.grow_frames * opts.substeps)],
                              device=dev, record_cmd=True))
    for c in range(len(tri_off) - 1):
        cmds.append(wp.launch(K.solve_stretch, int(tri_off[c + 1] - tri_off[c]),
                              inputs=[x, w, tri, rest_inv, area, mat.stretch_weft, mat.stretch_warp,
                                      mat.shear, inv_dt2, int(tri_off[c]), tri_start, grow], device=dev,
                              record_cmd=True))
    k_edge = 0.5 * (mat.stretch_weft + mat.stretch_warp)
    for c in range(len(edge_off) - 1):
        cmds.append(wp.launch(K.solve_distance, int(edge_off[c + 1] - edge_off[c]),
                              inputs=[x, w, edges, edge_rest, k_edge, inv_dt2, int(edge_off[c]), edge_start, grow],
                              device=dev, record_cmd=True))
    if mat.bending > 0:
        for c in range(len(bend_off) - 1):
            cmds.append(wp.launch(K.solve_bending, int(bend_off[c + 1] - bend_off[c]),
                                  inputs=[x, w, bends, bend_w, bend_rest, mat.bending, inv_dt2,
                                          int(bend_off[c])],
                                  device=dev, record_cmd=True))
    if opts.tether_slack is not None and np.any(cloth.tether_anchor >= 0):
        cmds.append(wp.launch(K.solve_tethers, n, inputs=[x, anchor, tether_len, 1.0 + float(opts.tether_slack)],
                              device=dev, record_cmd=True))
    pre = cmds
    cmds = []
    cmds.append(wp.launch(K.collide_body, n, inputs=[x, x_prev, c_point, c_normal, c_active, thickness,
                                                     friction], device=dev, record_cmd=True))
    cmds.append(wp.launch(K.update_velocity, n, inputs=[x, x_prev, v, 1.0 / dt], device=dev, record_cmd=True))
    contacts = wp.launch(K.find_contacts, n, inputs=[x, w, body.id, opts.search_distance, c_point, c_normal,
                                                     c_active], device=dev, record_cmd=True)

    free = inv_mass > 0
    speeds = []
    still = 0
    settled = False
    frame = 0
    if self_on:
        grid = wp.HashGrid(48, 48, 48, device=dev)
        self_dx = wp.zeros(n, dtype=wp.vec3, device=dev)
        partner = wp.zeros((n, SELF_PAIRS), dtype=int, device=dev)
        n_partner = wp.zeros(n, dtype=int, device=dev)
        x_start = wp.array(cloth.x0.astype(f32), dtype=wp.vec3, device=dev)
        r_start, r_idx = two_rings(cloth.faces, n)
        ring_start = wp.array(r_start.astype(np.int32), dtype=int, device=dev)
        ring_idx = wp.array(r_idx.astype(np.int32), dtype=int, device=dev)
        search = 3.0 * self_radius  # the contact distance plus a margin for the motion until the next search
        find_pairs = wp.launch(K.find_self_pairs, n, inputs=[x, w, x_start, grid.id, search,
                                                             opts.self_exclude * 2.0 * self_radius, SELF_PAIRS,
                                                             partner, n_partner, ring_start, ring_idx,
                                                             0.5 * self_radius], device=dev, record_cmd=True)
        self_cmds = [wp.launch(K.self_collide, n, inputs=[x, w, partner, n_partner, self_radius, self_dx],
                               device=dev, record_cmd=True),
                     wp.launch(K.apply_delta, n, inputs=[x, self_dx], device=dev, record_cmd=True)]
    step = 0
    for frame in range(1, opts.max_frames + 1):
        for sub in range(opts.substeps):
            if sub % opts.contact_interval == 0:
                contacts.launch()
            for cmd in pre:
                cmd.launch()
            if self_on:
                if step % opts.self_interval == 0:
                    grid.build(x, search)
                    find_pairs.launch()
                for cmd in self_cmds:
                    cmd.launch()
            step += 1
            for cmd in cmds:
                cmd.launch()
        xs = x.numpy()
        vs = v.numpy()
        _check_divergence(frame, xs, vs[free], opts, mat, dt, cloth)
        rms = settle_speed(vs[free], opts.settle_trim)
        speeds.append(rms)
        still = still + 1 if (rms < opts.settle_speed and frame > opts.grow_frames) else 0
        report(progress, frame / opts.max_frames, f"drape: frame {frame}, rms speed {rms * 1000:.1f} mm/s")
        if frame >= max(opts.min_frames, opts.grow_frames) and still >= opts.settle_frames:
            settled = True
            break
    wp.synchronize_device(dev)
    t_sim = time.perf_counter()

    xp = x.numpy().astype(float)
    vp = np.linalg.norm(v.numpy().astype(float), axis=1)
    valid = ~cloth.sliver if len(cloth.sliver) else np.ones(len(cloth.faces), bool)
    fw, fg, fs = (np.where(valid, a, 0.0) for a in face_strains(xp, cloth))
    weight = cloth.rest_area * valid
    sw = vertex_average(fw, cloth.faces, weight, n)
    sg = vertex_average(fg, cloth.faces, weight, n)
    used = cloth.particle_of >= 0
    src = np.where(used, cloth.particle_of, 0)
    positions = np.where(used[:, None], xp[src], 0.0)
    start = np.where(used[:, None], cloth.x0[src], 0.0)
    report(progress, 1.0, "drape: settled" if settled else "drape: frame limit reached")
    t_end = time.perf_counter()
    return DrapeResult(
        positions=positions, faces=cloth.faces_global.copy(), used=used,
        strain_weft=np.where(used, sw[src], 0.0), strain_warp=np.where(used, sg[src], 0.0),
        face_strain_weft=fw, face_strain_warp=fg, face_shear=fs, face_valid=valid,
        speed=np.where(used, vp[src], 0.0),
        face_garment=cloth.face_garment.copy(), garment_names=list(cloth.garment_names),
        start_positions=start, seam_pairs=cloth.seam_pairs.copy(), frames=frame, settled=settled,
        settle_reason="settled" if settled else "frame limit", speed_history=np.asarray(speeds),
        timings={"prepare": t_prep - t_start, "compile": t_compile - t_prep, "simulate": t_sim - t_compile,
                 "total": t_end - t_start},
        material=mat.to_json(), options=asdict(opts), device=str(dev),
        self_collision=self_on, self_radius=self_radius if self_on else 0.0,
    )


def two_rings(faces: np.ndarray, n: int) -> tuple:
    """CSR lists of the particles within two mesh rings of each particle: (starts (n+1,), indices)."""
    from scipy.sparse import coo_matrix
    f = np.asarray(faces, dtype=np.int64)
    rows = np.concatenate([f[:, 0], f[:, 1], f[:, 2], f[:, 1], f[:, 2], f[:, 0]])
    cols = np.concatenate([f[:, 1], f[:, 2], f[:, 0], f[:, 0], f[:, 1], f[:, 2]])
    a = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n)).tocsr()
    a.data[:] = 1.0
    r = (a + a @ a).tocsr()
    r.sort_indices()
    return r.indptr.astype(np.int64), r.indices.astype(np.int64)


def settle_speed(velocities: np.ndarray, trim: float = 0.0) -> float:
    """RMS speed (m/s) of the particles, leaving out the fastest ``trim`` fraction."""
    if len(velocities) == 0:
        return 0.0
    sq = np.sum(np.asarray(velocities, dtype=float) ** 2, axis=1)
    keep = len(sq) - int(np.floor(trim * len(sq)))
    if keep < len(sq):
        sq = np.partition(sq, keep - 1)[:keep]
    return float(np.sqrt(np.mean(sq)))


def _check_divergence(frame: int, xs: np.ndarray, vs: np.ndarray, opts: DrapeOptions, mat: Material,
                      dt: float, cloth: Optional[Cloth] = None) -> None:
    """Raise DrapeError naming the frame and the likely cause when the state blew up."""
    step = f"time step {dt * 1e3:.3g} ms ({opts.substeps} substeps at {opts.fps:g} fps)"
    if not np.all(np.isfinite(xs)) or not np.all(np.isfinite(vs)):
        raise DrapeError(f"drape diverged at frame {frame}: positions became NaN/inf; likely cause: "
                         f"{step} too large for the stiffness of {mat.name!r}, or a degenerate pattern triangle")
    extent = float(np.linalg.norm(xs.max(axis=0) - xs.min(axis=0)))
    if extent > opts.max_extent:
        raise DrapeError(f"drape diverged at frame {frame}: the garment's bounding box grew to {extent:.1f} m "
                         f"(limit {opts.max_extent:g} m); likely cause: {step} too large, or stiffness "
                         f"of {mat.name!r} out of range")
    if len(vs):
        rms = float(np.sqrt(np.mean(np.sum(vs.astype(float) ** 2, axis=1))))
        if rms > opts.max_speed:
            raise DrapeError(f"drape diverged at frame {frame}: kinetic energy exploded (RMS speed "
                             f"{rms:.1f} m/s > {opts.max_speed:g} m/s); likely cause: {step} too large "
                             f"for the stiffness of {mat.name!r}")
    if cloth is not None and len(cloth.faces):
        fw, fg, _ = face_strains(xs.astype(float), cloth)
        worst = np.maximum(np.abs(fw), np.abs(fg))
        area = cloth.rest_area * (~cloth.sliver if len(cloth.sliver) else 1.0)
        torn = float(area[worst > opts.max_strain].sum() / max(area.sum(), 1e-30))
        if torn > 0.005:  # a few bad triangles are input defects; half a percent of the cloth is a blow-up
            raise DrapeError(f"drape diverged at frame {frame}: {torn * 100:.1f} % of the fabric is stretched "
                             f"beyond {opts.max_strain * 100:.0f} % (up to {worst.max() * 100:.0f} %); likely "
                             f"cause: {step} too large, a pattern far too small for the body, or pins far "
                             f"from their pattern places")
