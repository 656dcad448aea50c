"""The XPBD drape solver: small-step Gauss-Seidel XPBD of a welded cloth on a static body.

:class:`DrapeSolver` precomputes everything that does not move once (the
constraint colouring, masses, rest shapes, the body's BVH, the compiled
kernels); :meth:`DrapeSolver.state` makes a fresh :class:`DrapeState` (the
garment skintight on the body) and :meth:`DrapeSolver.step` advances a state
by one frame. The solver keeps nothing that a step changes, so two states
stepped by one solver are independent. The schedule around the steps (growth,
settling, divergence) is :mod:`core.drape.schedule`.

Body contact has thickness and friction; each particle's contact plane goes
through its closest point on the body and faces it (so the cloth slides off a
convex edge instead of resting on the extended plane of the last triangle).
Self-collision is optional (``self_collision=True``): particle against particle, found with a hash grid
and resolved Jacobi-style, so it stays repeatable; off by default, when garment
layers and folds may pass through each other.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, List, Mapping, Optional, Union

import numpy as np

from ..errors import DrapeError
from .materials import Material, get_material
from .mesh import Cloth, colour_order, rest_edges, two_rings
from .options import ONSET_FRAMES, DrapeOptions, default_substeps
from .schedule import growth_per_substep, initial_growth
from .strain import face_strains

# within this distance (m) of the body the contact normal is the face's (the direction to the
# closest point is float32 noise there); farther out it is that direction (see kernels.closest_contact)
CONTACT_FLAT = 1.0e-4
# most self-collision candidates a particle keeps (a particle in a fold meets a few of the other layer)
SELF_PAIRS = 16


def check_body(body_vertices, body_faces) -> tuple:
    """The body as (vertices (V, 3) float64, faces (F, 3) int32); DrapeError naming what is wrong."""
    v = np.asarray(body_vertices, dtype=float)
    f = np.asarray(body_faces)
    if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.all(np.isfinite(v)):
        raise DrapeError(f"body vertices must be a finite (V, 3) array, got shape {v.shape}")
    if (
        f.ndim != 2
        or f.shape[1] != 3
        or len(f) == 0
        or not np.issubdtype(f.dtype, np.integer)
        or f.min() < 0
        or f.max() >= len(v)
    ):
        raise DrapeError(f"body faces must be (F, 3) integer indices into the {len(v)} body vertices")
    return v, f.astype(np.int32)


def _start(cloth: Cloth) -> tuple:
    """The skintight start the rest shape grows from: (T, 2) weft / warp stretch of every triangle,
    (E,) the start lengths of the sliver edges."""
    fw0, fg0, _ = face_strains(cloth.x0, cloth)
    e = cloth.edges.reshape(-1, 2)
    edge_start = np.linalg.norm(cloth.x0[e[:, 1]] - cloth.x0[e[:, 0]], axis=1)
    return np.clip(np.stack([fw0, fg0], axis=1) + 1.0, 0.2, 5.0), edge_start


def _device(wp, name: str):
    try:
        dev = wp.get_device(name)
    except Exception:
        dev = None
    if dev is None or (dev.is_cuda and not wp.is_cuda_available()):
        have = ", ".join(str(d) for d in wp.get_devices())
        raise DrapeError(f"drape device {name!r} is not available; available: {have}")
    return dev


@dataclass
class DrapeState:
    """The moving part of one drape, on the solver's device.

    Attributes
    ----------
    x, v, x_prev : (P,) wp.vec3 arrays: positions (m), velocities (m/s), positions before the substep.
    grow : (1,) float array, the rest-shape growth from the skintight start (0) to the pattern (1).
    contact_point, contact_normal, contact_active : (P,) arrays, each particle's contact plane:
        through its closest point on the body, facing it (refreshed every ``contact_interval`` substeps,
        and sooner where the fastest particle could have come from beyond ``search_distance``).
    searched : int, the substep of the last contact search.
    bend_lambda : (B,) float array, the bending constraints' XPBD multipliers within a substep.
    substeps : int, substeps taken so far (times the self-collision search).
    frames : int, frames taken so far.
    self_grid, self_dx, self_partner, self_count : self-collision buffers (None when off).
    y, acc : (P,) wp.vec3 arrays, VBD's inertial target and last acceleration (None for XPBD).
    launches : the kernel launches recorded on these arrays (see :meth:`DrapeSolver.state`).
    """

    x: Any
    v: Any
    x_prev: Any
    grow: Any
    contact_point: Any
    contact_normal: Any
    contact_active: Any
    bend_lambda: Any = None
    substeps: int = 0
    frames: int = 0
    searched: int = 0
    self_grid: Any = None
    self_dx: Any = None
    self_partner: Any = None
    self_count: Any = None
    launches: Optional["_Launches"] = None
    y: Any = None
    acc: Any = None
    x64: Any = None
    # this state's pins: inverse masses (0: pinned), tethers, the free particles, and whether an upper
    # garment's pins have let go (:meth:`DrapeSolver.step`); its own, so a later state starts held
    w: Any = None
    anchor: Any = None
    tether_len: Any = None
    free: Any = None
    released: bool = False


@dataclass
class _Launches:
    """Recorded kernel launches of one state, in substep order."""

    contacts: Any  # the contact search, every contact_interval substeps
    constraints: List[Any]  # predict, growth, stretch, sliver edges, bending, tethers
    self_pairs: Any  # the self-collision candidate search (None when off)
    self_collide: List[Any]  # self-collision resolve and apply
    finish: List[Any]  # body contact and friction, velocity update
    tethers: List[Any] = None  # after the constraints (and the host step)
    host: Any = None  # the newton solver's host step, ``host(state)`` (None: all on the device)


class DrapeSolver:
    """XPBD drape of one welded cloth on one static body, precomputed once.

    XPBD (Macklin et al. 2016) with small steps (Macklin et al. 2019); the
    constraints and contact kernels are :mod:`core.drape.kernels`.

    Parameters
    ----------
    cloth : :class:`core.drape.mesh.Cloth`, the welded pattern.
    body_vertices : (V, 3) float, metres, +Z up.
    body_faces : (F, 3) int, outward-oriented triangles.
    material : preset name, :class:`Material` or dict (default cotton).
    options : :class:`DrapeOptions` or a dict of its fields.

    Attributes
    ----------
    cloth, material, options : as given (validated).
    device : the Warp device.
    dt : float, s, the substep, ``1 / (fps * substeps)``.
    thickness : float, m; friction : float; the body contact's (options over material).
    self_radius : float, m, the self-collision radius; 0 when self-collision is off.
    free : (P,) bool, particles that move at the start (not pinned); a state's own
        :attr:`DrapeState.free` adds those whose pins have let go.
    lets_go : bool, whether an upper garment's pins let go once the cloth has grown
        (:attr:`core.drape.mesh.Cloth.pin_lets_go`, unless ``options.hold_pins``).
    onset : int, frames, the first frames whose pd / newton solves take ``onset_factor`` x the
        iterations (:attr:`DrapeOptions.onset_frames`; where None, :data:`ONSET_FRAMES` for a cloth
        that starts at its rest shape or grows to it at once, else 0).
    timings : dict of seconds: ``prepare`` (colouring, masses) and ``compile`` (upload, kernels).

    Raises
    ------
    DrapeError on invalid input, an unavailable device, a particle without
    mass, or a substep so long that gravity alone moves a particle through the
    contact thickness.
    """

    def __init__(
        self,
        cloth: Cloth,
        body_vertices,
        body_faces,
        material: Union[None, str, Material, Mapping] = None,
        options: Union[None, DrapeOptions, Mapping] = None,
    ):
        t0 = time.perf_counter()
        opts = DrapeOptions.coerce(options)
        mat = get_material(material)
        body_v, body_f = check_body(body_vertices, body_faces)
        self.cloth, self.material, self.options = cloth, mat, opts
        self.thickness = mat.thickness if opts.thickness is None else float(opts.thickness)
        opts.substeps = default_substeps(opts, self.thickness)  # pd's default depends on the thickness
        self.friction = mat.friction if opts.friction is None else float(opts.friction)

        from ..geom import queries as Q
        from . import kernels as K

        wp = K.wp
        wp.init()
        self._K, self._Q, self._wp = K, Q, wp
        self.device = _device(wp, opts.device)

        # Constraint order: colour by colour (Gauss-Seidel without write conflicts).
        good = np.nonzero(~cloth.sliver)[0] if len(cloth.sliver) else np.arange(len(cloth.faces))
        tri_order, self._tri_off = colour_order(cloth.faces[good], cloth.n_particles)
        tri_order = good[tri_order]
        bend_order, self._bend_off = colour_order(cloth.bends, cloth.n_particles)
        edge_order, self._edge_off = colour_order(cloth.edges, cloth.n_particles)
        mass = mat.density * cloth.mass_area
        if np.any(mass <= 0):
            raise DrapeError("pattern has a vertex that belongs to no triangle (zero mass)")
        inv_mass = np.where(cloth.pinned, 0.0, 1.0 / mass)
        self.free = inv_mass > 0
        self.lets_go = not opts.hold_pins and bool(np.any(cloth.pin_lets_go))
        self._released = None  # the cloth with those pins let go, its masses and implicit step (built once)
        t_prep = time.perf_counter()

        self._upload(cloth, inv_mass, tri_order, bend_order, edge_order, body_v, body_f)
        wp.load_module(K, device=self.device)
        wp.load_module(Q, device=self.device)
        if opts.solver in ("vbd", "newton", "pd"):
            self._upload_vbd(cloth, mass, tri_order, bend_order, edge_order)
        if opts.solver in ("newton", "pd"):
            self._upload_newton(cloth, mass)
        t_compile = time.perf_counter()
        self.timings = {"prepare": t_prep - t0, "compile": t_compile - t_prep}

        if opts.self_radius is not None:
            radius = float(opts.self_radius)
        else:
            _, edge_len = rest_edges(cloth.faces, cloth.rest_inv)
            radius = 0.4 * float(np.median(edge_len)) if len(edge_len) else 0.0
        self.self_radius = radius if bool(opts.self_collision) and radius > 0.0 else 0.0
        # the self-collision search radius: the contact distance plus a margin for the motion until the next search
        self._self_search = 3.0 * self.self_radius
        if self.self_radius > 0.0:
            r_start, r_idx = two_rings(cloth.faces, cloth.n_particles)
            self._x_start = wp.array(cloth.x0.astype(np.float32), dtype=wp.vec3, device=self.device)
            self._ring_start = wp.array(r_start.astype(np.int32), dtype=int, device=self.device)
            self._ring_idx = wp.array(r_idx.astype(np.int32), dtype=int, device=self.device)

        self.dt = 1.0 / (opts.fps * opts.substeps)
        fall = float(opts.gravity) * self.dt * self.dt
        if fall > self.thickness:
            # XPBD stays bounded at any step, but a step this long lets the cloth pass
            # through the body between contact checks and stalls its constraints: refuse it.
            raise DrapeError(
                f"time step {self.dt * 1e3:.3g} ms ({opts.substeps} substeps at {opts.fps:g} fps) "
                f"is too large: gravity alone moves a particle {fall * 1e3:.2f} mm per substep, more "
                f"than the {self.thickness * 1e3:.1f} mm contact thickness; use more substeps or a "
                f"higher fps"
            )

    def _upload(self, cloth: Cloth, inv_mass, tri_order, bend_order, edge_order, body_v, body_f) -> None:
        """The constant device arrays: masses, constraints in colour order, their start lengths, the body BVH."""
        wp, dev, f32 = self._wp, self.device, np.float32
        self._w = wp.array(inv_mass.astype(f32), dtype=float, device=dev)
        self._tri = wp.array(cloth.faces[tri_order].astype(np.int32), dtype=int, device=dev)
        self._rest_inv = wp.array(cloth.rest_inv[tri_order].astype(f32), dtype=wp.mat22, device=dev)
        self._area = wp.array(cloth.rest_area[tri_order].astype(f32), dtype=float, device=dev)
        self._bends = wp.array(cloth.bends[bend_order].astype(np.int32).reshape(-1, 4), dtype=int, device=dev)
        self._edges = wp.array(cloth.edges[edge_order].astype(np.int32).reshape(-1, 2), dtype=int, device=dev)
        self._edge_rest = wp.array(cloth.edge_rest[edge_order].astype(f32), dtype=float, device=dev)
        self._bend_w = wp.array(cloth.bend_weight[bend_order].astype(f32), dtype=float, device=dev)
        self._bend_rest = wp.array(cloth.bend_rest[bend_order].astype(f32), dtype=float, device=dev)
        self._anchor = wp.array(cloth.tether_anchor.astype(np.int32), dtype=int, device=dev)
        self._tether_len = wp.array(cloth.tether_length.astype(f32), dtype=float, device=dev)
        # the skintight start's stretch, where the rest shape grows from
        fw0, fg0, _ = face_strains(cloth.x0, cloth)
        start_stretch = np.clip(np.stack([fw0, fg0], axis=1) + 1.0, 0.2, 5.0)
        # released at rest (a specimen, a sheet) it falls free and picks its folds in the first frames;
        # grown from a skintight start (a garment) it buckles as it grows
        opts = self.options
        at_rest = opts.grow_frames == 0 or float(np.max(np.abs(start_stretch - 1.0), initial=0.0)) < 1e-4
        self.onset = int(opts.onset_frames if opts.onset_frames is not None else ONSET_FRAMES * at_rest)
        self._tri_start = wp.array(start_stretch[tri_order].astype(f32), dtype=wp.vec2, device=dev)
        e_sorted = cloth.edges[edge_order]
        self._edge_start = wp.array(
            np.linalg.norm(cloth.x0[e_sorted[:, 1]] - cloth.x0[e_sorted[:, 0]], axis=1).astype(f32)
            if len(e_sorted)
            else np.zeros(0, f32),
            dtype=float,
            device=dev,
        )
        self._body = self._Q.warp_mesh(body_v, body_f, device=dev)
        # the body's displacement (V, 3) since the last substep (:meth:`move_body`), and over the last substep
        self._body_moved = self._body_last = None

    def _upload_vbd(self, cloth: Cloth, mass, tri_order, bend_order, edge_order) -> None:
        """VBD's arrays: particle masses, the vertex colouring, each particle's triangles, hinges and edges."""
        from . import vbd as V

        wp, dev, n = self._wp, self.device, cloth.n_particles
        tris = cloth.faces[tri_order]
        bends = cloth.bends[bend_order].reshape(-1, 4)
        edges = cloth.edges[edge_order].reshape(-1, 2)
        # the vertex colouring (VBD's Gauss-Seidel order; the newton solver does not need it)
        colours = V.vertex_colouring(n, [tris, bends, edges]) if self.options.solver == "vbd" else np.zeros(n, int)
        order = np.argsort(colours, kind="stable")
        self._vbd_off = np.concatenate([[0], np.cumsum(np.bincount(colours))])
        self._mass = wp.array(mass.astype(np.float32), dtype=float, device=dev)
        self._vbd_order = wp.array(order.astype(np.int32), dtype=int, device=dev)
        self._vbd_adj = [
            tuple(wp.array(a.astype(np.int32), dtype=int, device=dev) for a in V.incidence(n, els))
            for els in (tris, bends, edges)
        ]
        wp.load_module(V, device=dev)
        self._V = V

    def _newton_step(self, cloth: Cloth, mass):
        """The newton solver's host step (:class:`core.drape.newton.NewtonStep`) for this cloth: its energy
        and the substep's Hessian (the rest shape growing from the skintight start's stretch)."""
        from . import newton as N

        return N.NewtonStep(
            cloth, self.material, 1.0 / (self.options.fps * self.options.substeps), mass, *_start(cloth)
        )

    def _upload_newton(self, cloth: Cloth, mass) -> None:
        """The implicit solver's step on the host: :class:`core.drape.newton.NewtonStep` (the substep's
        Hessian factored once per substep) or, for ``solver="pd"``, :class:`core.drape.pd.ProjectiveStep`
        (its constant matrix factored once per cloth)."""
        if self.options.solver == "pd":
            self._implicit = self._projective_step(cloth, mass)
        else:
            self._newton = self._implicit = self._newton_step(cloth, mass)
        self._weight = mass * max(float(self.options.gravity), 1e-3)  # N (a floor without gravity)
        self._newton_iterations = []  # iterations per substep (the residual-based stop's record)
        self._newton_residuals = []  # the largest residual over weight at the end of each substep's solve

    def _projective_step(self, cloth: Cloth, mass):
        """pd's host step (:class:`core.drape.pd.ProjectiveStep`) for this cloth, with the drape's options."""
        from .pd import ProjectiveStep

        dt = 1.0 / (self.options.fps * self.options.substeps)  # (before self.dt is set, in __init__)
        step = ProjectiveStep(cloth, self.material, dt, mass, *_start(cloth), strain_limit=self.options.strain_limit)
        step.friction = self.friction
        return step

    @property
    def newton_residuals(self) -> np.ndarray:
        """(S,) the largest residual over weight each substep's implicit solve ended with so far
        (``solver="newton"`` or ``"pd"``; empty for the other solvers): above the tolerance, that solve stopped
        at its iteration limit."""
        return np.asarray(getattr(self, "_newton_residuals", []), float)

    def residual(self, state: DrapeState) -> float:
        """The largest net force (elastic + gravity) on a free particle off the body, over its weight:
        0 in a static equilibrium of the fabric's own energy (:mod:`core.drape.newton`), whatever the
        solver. Particles within twice the contact offset of the body are left out (friction holds them)."""
        cloth = self._released[0] if state.released else self.cloth
        attr = "_newton_released" if state.released else "_newton"
        if getattr(self, attr, None) is None:
            setattr(self, attr, self._newton_step(cloth, self.material.density * cloth.mass_area))
        step = getattr(self, attr)
        x = state.x64 if state.x64 is not None else state.x.numpy().astype(np.float64)
        y = x.copy()
        y[:, 2] -= float(self.options.gravity) * self.dt * self.dt
        step.contact = None
        _, g = step.energy(x, y, float(state.grow.numpy()[0]))
        keep = state.free.copy() if state.free is not None else self.free.copy()
        active = state.contact_active.numpy() != 0
        height = np.einsum("ij,ij->i", x - state.contact_point.numpy(), state.contact_normal.numpy())
        keep &= ~(active & (height < 2.0 * self.thickness))
        ratio = np.linalg.norm(g, axis=1)[keep] / np.maximum(self._weight[keep], 1e-30)
        return float(ratio.max(initial=0.0))

    def _newton_solve(self, s: DrapeState) -> None:
        """One implicit step on the host, in float64: x from the device, the iterations, x back."""
        # the substep's start in float64: the host's own positions where the device's float32 copy still
        # holds them (contact, tethers or self-collision may have moved some since), plus the device's
        # start guess and inertial target as increments on it
        prev = s.x_prev.numpy()
        base = prev.astype(np.float64)
        if s.x64 is not None:
            same = np.all(s.x64.astype(np.float32) == prev, axis=1)
            base[same] = s.x64[same]
        x = base + (s.x.numpy().astype(np.float64) - prev)
        y = base + (s.y.numpy().astype(np.float64) - prev)
        opts = self.options
        grow = float(s.grow.numpy()[0])
        implicit = self._released[2] if s.released else self._implicit
        implicit.set_contact(
            s.contact_point.numpy(), s.contact_normal.numpy(), s.contact_active.numpy(), self.thickness
        )
        if opts.solver == "pd" and self.self_radius > 0.0 and s.self_count is not None:
            # the self-collision candidates (the last search's) kept apart inside the solve too
            count = s.self_count.numpy()
            partner = s.self_partner.numpy()
            rows = np.repeat(np.arange(len(count)), count)
            cols = partner[np.arange(partner.shape[1])[None, :] < count[:, None]]
            pairs = np.unique(np.stack([np.minimum(rows, cols), np.maximum(rows, cols)], axis=1), axis=0)
            implicit.set_self(pairs[:, 0], pairs[:, 1], 2.0 * self.self_radius, base)
        start = {"previous": base} if opts.solver == "newton" else {}  # newton: from the lower G of x_n and x
        if opts.solver == "pd":
            from .pd import FRICTION

            # Coulomb friction in the solve (core.drape.pd.FRICTION): the body's particles held to where
            # the substep began
            implicit.carry, moved = self._carry(s, FRICTION)
            # (with friction, on a moving body: held where the body carried the substep's start)
            implicit.anchor = None if not FRICTION else base if moved is None else base + moved
        iterations = int(opts.iterations) * (int(opts.onset_factor) if s.frames < self.onset else 1)
        it, res = implicit.solve(x, y, grow, iterations, float(opts.tolerance), self._weight, **start)
        self._newton_iterations.append(it)
        self._newton_residuals.append(res)
        s.x64 = x
        s.x.assign(x.astype(np.float32))

    def _carry(self, s: DrapeState, friction: bool) -> tuple:
        """(carry, moved): how far the body carries each particle this substep beyond its own (damped)
        velocity, at its contact point ((P, 3) float64: the body's displacement this substep less the damped
        share of its last substep's, which the particle's velocity already holds where it moved with the
        body; :meth:`move_body`), and with ``friction`` (:data:`core.drape.pd.FRICTION`) the body's
        displacement this substep there; (None, None) where the body has not moved in either substep (a
        still body's drape is left as it was). With ``carry`` a held particle keeps its velocity relative
        to the body, as on a still body it keeps its own."""
        moved, last = self._body_moved, self._body_last
        self._body_moved, self._body_last = None, moved
        if moved is None and last is None:
            return None, None
        zero = np.zeros_like(moved if moved is not None else last)
        moved = zero if moved is None else moved
        keep = float(np.exp(-self.options.damping * self.dt))  # the predicted velocity's damping (_record)
        change = moved - keep * (zero if last is None else last)
        return self._at_contacts(s, change), self._at_contacts(s, moved) if friction else None

    def _at_contacts(self, s: DrapeState, per_vertex: np.ndarray) -> np.ndarray:
        """A body vertex field (V, 3) at each particle's contact point ((P, 3) float64; 0 off the body)."""
        wp, dev = self._wp, self.device
        n = self.cloth.n_particles
        out = wp.zeros(n, dtype=wp.vec3, device=dev)
        field = wp.array(np.asarray(per_vertex, dtype=np.float32), dtype=wp.vec3, device=dev)
        # from the contact search's points (the substep's start): the same closest face
        inputs = [s.x_prev, s.contact_active, self._body.id, self.options.search_distance, self._body.indices]
        wp.launch(self._K.contact_motion, dim=n, inputs=inputs + [field, out], device=dev)
        return out.numpy().astype(np.float64)

    def state(self) -> DrapeState:
        """A fresh state: the garment skintight on the body, at rest, its rest shape not yet grown."""
        wp, dev, n = self._wp, self.device, self.cloth.n_particles
        s = DrapeState(
            x=wp.array(self.cloth.x0.astype(np.float32), dtype=wp.vec3, device=dev),
            v=wp.zeros(n, dtype=wp.vec3, device=dev),
            x_prev=wp.zeros(n, dtype=wp.vec3, device=dev),
            grow=wp.array([initial_growth(self.options)], dtype=float, device=dev),
            contact_point=wp.zeros(n, dtype=wp.vec3, device=dev),
            contact_normal=wp.zeros(n, dtype=wp.vec3, device=dev),
            contact_active=wp.zeros(n, dtype=int, device=dev),
            bend_lambda=wp.zeros(max(len(self.cloth.bends), 1), dtype=float, device=dev),
            w=wp.clone(self._w),
            anchor=wp.clone(self._anchor),
            tether_len=wp.clone(self._tether_len),
            free=self.free.copy(),
        )
        if self.options.solver in ("vbd", "newton", "pd"):
            s.y = wp.zeros(n, dtype=wp.vec3, device=dev)
            s.acc = wp.zeros(n, dtype=wp.vec3, device=dev)
        if self.self_radius > 0.0:
            s.self_grid = wp.HashGrid(48, 48, 48, device=dev)
            s.self_dx = wp.zeros(n, dtype=wp.vec3, device=dev)
            s.self_partner = wp.zeros((n, SELF_PAIRS), dtype=int, device=dev)
            s.self_count = wp.zeros(n, dtype=int, device=dev)
        s.launches = self._record(s)
        return s

    def _launch(self, kernel, dim: int, inputs: list):
        return self._wp.launch(kernel, dim, inputs=inputs, device=self.device, record_cmd=True)

    def _record(self, s: DrapeState) -> _Launches:
        """Record every kernel launch of a substep on the arrays of ``s`` (launched again each substep)."""
        K, opts, mat, n = self._K, self.options, self.material, self.cloth.n_particles
        inv_dt2 = 1.0 / (self.dt * self.dt)
        keep = float(np.exp(-opts.damping * self.dt))
        gravity = self._wp.vec3(0.0, 0.0, -float(opts.gravity))
        vbd = opts.solver in ("vbd", "newton", "pd")  # all predict the inertial target y
        if vbd:
            predict = self._launch(self._V.predict, n, [s.x, s.v, s.x_prev, s.y, s.acc, s.w, gravity, self.dt, keep])
        else:
            predict = self._launch(K.predict, n, [s.x, s.v, s.x_prev, s.w, gravity, self.dt, keep])
        cmds = [predict]
        grow_step = growth_per_substep(opts)
        if grow_step is not None:
            cmds.append(self._launch(K.advance_grow, 1, [s.grow, grow_step]))
        if vbd:
            if opts.solver == "vbd":
                cmds.extend(self._vbd_sweeps(s) * int(opts.iterations))
            return self._finish_record(s, cmds, self._V.update_velocity, [s.x, s.x_prev, s.v, s.acc, 1.0 / self.dt])
        if mat.bending > 0 and len(self.cloth.bends):
            cmds.append(self._launch(K.zero, len(self.cloth.bends), [s.bend_lambda]))
        block = []  # the constraint block, projected opts.iterations times per substep
        off = self._tri_off
        for c in range(len(off) - 1):
            block.append(
                self._launch(
                    K.solve_stretch,
                    int(off[c + 1] - off[c]),
                    [
                        s.x,
                        s.w,
                        self._tri,
                        self._rest_inv,
                        self._area,
                        mat.stretch_weft,
                        mat.stretch_warp,
                        mat.shear,
                        inv_dt2,
                        int(off[c]),
                        self._tri_start,
                        s.grow,
                    ],
                )
            )
        k_edge = 0.5 * (mat.stretch_weft + mat.stretch_warp)
        off = self._edge_off
        for c in range(len(off) - 1):
            block.append(
                self._launch(
                    K.solve_distance,
                    int(off[c + 1] - off[c]),
                    [
                        s.x,
                        s.w,
                        self._edges,
                        self._edge_rest,
                        k_edge,
                        inv_dt2,
                        int(off[c]),
                        self._edge_start,
                        s.grow,
                    ],
                )
            )
        if mat.bending > 0:
            off = self._bend_off
            for c in range(len(off) - 1):
                block.append(
                    self._launch(
                        K.solve_bending,
                        int(off[c + 1] - off[c]),
                        [
                            s.x,
                            s.w,
                            self._bends,
                            self._bend_w,
                            self._bend_rest,
                            mat.bending,
                            inv_dt2,
                            int(off[c]),
                            s.bend_lambda,
                        ],
                    )
                )
        cmds.extend(block * int(opts.iterations))
        return self._finish_record(s, cmds, K.update_velocity, [s.x, s.x_prev, s.v, 1.0 / self.dt])

    def _element_args(self, s: DrapeState) -> list:
        """The arguments of :func:`core.drape.vbd.vertex_forces` after ``x``: elements, incidence, moduli."""
        mat = self.material
        (t0, t1), (b0, b1), (e0, e1) = self._vbd_adj
        return [
            self._tri,
            self._rest_inv,
            self._area,
            self._tri_start,
            t0,
            t1,
            mat.stretch_weft,
            mat.stretch_warp,
            mat.shear,
            self._bends,
            self._bend_w,
            self._bend_rest,
            b0,
            b1,
            mat.bending,
            self._edges,
            self._edge_rest,
            self._edge_start,
            e0,
            e1,
            0.5 * (mat.stretch_weft + mat.stretch_warp),
            s.grow,
        ]

    def _vbd_sweeps(self, s: DrapeState) -> list:
        """One VBD iteration: a Newton step of every free vertex, colour by colour."""
        off = self._vbd_off
        head = [s.x, s.y, s.x_prev, self._mass, s.w, self._vbd_order]
        inv_dt2 = 1.0 / (self.dt * self.dt)
        damp = float(self.options.vbd_damping) / self.dt
        tail = self._element_args(s) + [s.contact_point, s.contact_normal, s.contact_active, self.thickness]
        return [
            self._launch(self._V.solve_vertices, int(off[c + 1] - off[c]), head + [int(off[c]), inv_dt2, damp] + tail)
            for c in range(len(off) - 1)
        ]

    def _finish_record(self, s: DrapeState, cmds: list, update_velocity, velocity_inputs: list) -> _Launches:
        """The launches after the constraints (tethers, contact, self-collision, velocities), recorded."""
        K, opts, n = self._K, self.options, self.cloth.n_particles
        tethers = []
        if opts.tether_slack is not None and np.any(self.cloth.tether_anchor >= 0):
            tethers.append(
                self._launch(K.solve_tethers, n, [s.x, s.anchor, s.tether_len, 1.0 + float(opts.tether_slack)])
            )
        finish = [
            self._launch(
                K.collide_body,
                n,
                [s.x, s.x_prev, s.contact_point, s.contact_normal, s.contact_active, self.thickness, self.friction],
            ),
            self._launch(update_velocity, n, velocity_inputs),
        ]
        contacts = self._launch(
            K.closest_contact,
            n,
            [
                s.x,
                s.w,
                self._body.id,
                opts.search_distance,
                CONTACT_FLAT,
                s.contact_point,
                s.contact_normal,
                s.contact_active,
            ],
        )
        pairs, collide = None, []
        if self.self_radius > 0.0:
            r = self.self_radius
            pairs = self._launch(
                K.find_self_pairs,
                n,
                [
                    s.x,
                    s.w,
                    self._x_start,
                    s.self_grid.id,
                    self._self_search,
                    opts.self_exclude * 2.0 * r,
                    SELF_PAIRS,
                    s.self_partner,
                    s.self_count,
                    self._ring_start,
                    self._ring_idx,
                    0.5 * r,
                ],
            )
            collide = [
                self._launch(K.self_collide, n, [s.x, s.w, s.self_partner, s.self_count, r, s.self_dx]),
                self._launch(K.apply_delta, n, [s.x, s.self_dx]),
            ]
        host = self._newton_solve if opts.solver in ("newton", "pd") else None
        return _Launches(
            contacts=contacts,
            constraints=cmds,
            self_pairs=pairs,
            self_collide=collide,
            finish=finish,
            tethers=tethers,
            host=host,
        )

    def move_body(self, vertices) -> None:
        """Move the body to ``vertices`` (V, 3), same triangles (an animated body): its BVH refitted."""
        pts = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
        if pts.shape[0] != self._body.points.shape[0]:
            raise DrapeError(
                f"the moved body has {pts.shape[0]} vertices, the drape's body {self._body.points.shape[0]}"
            )
        # pd: its displacement since the last substep (the body carries the cloth it holds: _carry)
        if self.options.solver == "pd":
            moved = pts - self._body.points.numpy()
            self._body_moved = moved if self._body_moved is None else self._body_moved + moved
        self._body.points.assign(pts)
        self._body.refit()

    def _let_go(self, state: DrapeState) -> None:
        """Let go of the pins of :attr:`core.drape.mesh.Cloth.pin_lets_go` in ``state``: those particles
        take their masses, the tethers reach only the pins that still hold, and the implicit solvers
        (pd, newton) step the let-go cloth, its matrix factored once for the solver."""
        if self._released is None:
            cloth = self.cloth.let_go()
            mass = self.material.density * cloth.mass_area
            step = None
            if self.options.solver == "pd":
                step = self._projective_step(cloth, mass)
            elif self.options.solver == "newton":
                step = self._newton_step(cloth, mass)
            self._released = (cloth, np.where(cloth.pinned, 0.0, 1.0 / mass), step)
        cloth, inv_mass, _ = self._released
        state.w.assign(inv_mass.astype(np.float32))
        state.anchor.assign(cloth.tether_anchor.astype(np.int32))
        state.tether_len.assign(cloth.tether_length.astype(np.float32))
        state.free = inv_mass > 0
        state.released = True

    def _outruns_contacts(self, state: DrapeState) -> bool:
        """Whether the fastest particle may have moved half the ``search_distance`` since the last
        contact search (by the end of this substep): one that had no contact plane then (farther from
        the body than that) could reach it before the next search and pass through (pd's 2 substeps a
        frame: a falling jersey strip's tip swung 4 cm through the cantilever's platform in a frame)."""
        v = state.v.numpy()
        fastest = float(np.sqrt(np.max(np.einsum("ij,ij->i", v, v), initial=0.0)))
        return fastest * self.dt * (state.substeps - state.searched + 1) > 0.5 * self.options.search_distance

    def step(self, state: DrapeState, before_substep=None) -> None:
        """Advance ``state`` by one frame: ``options.substeps`` substeps of :attr:`dt` seconds.

        ``before_substep(i)``, when given, runs before substep ``i`` (it may :meth:`move_body`);
        the contacts are then searched every substep.

        Before the first frame past ``grow_frames`` an upper garment's pins let go (:attr:`lets_go`).
        Each substep: the contact search (every ``contact_interval`` substeps, and at any substep
        where the fastest particle could have travelled half the ``search_distance`` since the last
        one: :meth:`_outruns_contacts`),
        prediction, rest-shape growth, the constraints colour by colour
        (``iterations`` passes; stretch is projected afresh each pass, its compliance
        being small against the mass term for every preset, bending accumulates its
        XPBD multiplier over the passes), tethers, the
        self-collision (search every ``self_interval`` substeps), body contact
        with friction, and the velocities from the position change.
        """
        opts, L = self.options, state.launches
        if self.lets_go and not state.released and state.frames >= opts.grow_frames:
            # grown to its pattern size: the collar lets go and the garment settles on the body
            self._let_go(state)
        for sub in range(opts.substeps):
            if before_substep is not None:
                before_substep(sub)
            if before_substep is not None or sub % opts.contact_interval == 0 or self._outruns_contacts(state):
                L.contacts.launch()
                state.searched = state.substeps
            for cmd in L.constraints:
                cmd.launch()
            if L.host is not None:
                L.host(state)
            for cmd in L.tethers:
                cmd.launch()
            if L.self_pairs is not None:
                if state.substeps % opts.self_interval == 0:
                    state.self_grid.build(state.x, self._self_search)
                    L.self_pairs.launch()
                for cmd in L.self_collide:
                    cmd.launch()
            state.substeps += 1
            for cmd in L.finish:
                cmd.launch()
        state.frames += 1
