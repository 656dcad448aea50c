"""Settings of a drape, with their units, validated at the door."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Mapping, Optional, Union

import numpy as np

from ..errors import DrapeError


@dataclass
class DrapeOptions:
    """Simulation settings.

    Time: a frame lasts ``1 / fps`` seconds and is the unit of the settle test
    and of the rest-shape growth; each frame takes ``substeps`` substeps of
    ``1 / (fps * substeps)`` seconds.

    Attributes
    ----------
    device : str
        ``"cpu"`` (default, bitwise repeatable) or ``"cuda"`` / ``"cuda:0"``.
    solver : str
        ``"xpbd"`` (one XPBD pass per iteration over the constraints; its
        stiffness is set by the step and the mesh) or ``"vbd"`` (Vertex Block
        Descent, :mod:`core.drape.vbd`: per-vertex Newton steps on the implicit
        step's potential; a settled drape is the fabric's own equilibrium)
        or ``"newton"`` (:mod:`core.drape.newton`: the same potential
        minimised to a residual with the substep's factored Hessian and L-BFGS,
        float64 on the host; the fabric's stiffness at any step) or ``"pd"``
        (:mod:`core.drape.pd`: projective dynamics, the same energy to second
        order minimised by local projections and one back-substitution of a
        matrix factored once per cloth, float64 on the host; the default: it
        delivers the fabric's stiffness, where XPBD's is set by the step and
        the mesh; ``docs/drape.md``).
    fps : float, 1/s
        Frames per second of simulated time.
    substeps : int, per frame, or None
        Substeps per frame (XPBD: each projects every constraint once). None:
        the solver's default (:data:`SUBSTEPS`: 20; pd the fewest, at least 2,
        that keep gravity's fall in one substep within the fabric's contact
        thickness, :func:`default_substeps`: 2 for cotton, jersey, wool and
        denim at 30 fps, 3 for silk), set when the drape solver is made.
    iterations : int, per substep, or None
        XPBD: passes over the stretch, sliver-edge and bending constraints in
        each substep (the bending multipliers accumulate over them); VBD:
        Gauss-Seidel sweeps over the vertices; newton, pd: the most iterations
        (fewer once ``tolerance`` is met). None: the
        solver's default (:data:`ITERATIONS`).
    tolerance : float, fraction of a particle's weight
        ``solver="newton"`` or ``"pd"``: a substep's iterations stop once the residual force on
        every free particle (the gradient of the step's potential) is under this
        fraction of its weight (``iterations`` is then the most it takes).
    vbd_damping : float, s
        ``solver="vbd"``: stiffness-proportional (Rayleigh) damping k_d, the
        elastic forces' response to the substep's motion times k_d / dt.
    max_frames : int, frames
        Frame limit.
    min_frames : int, frames
        Frames simulated before settling may be declared.
    settle_speed : float, m/s
        The root-mean-square particle speed under which a frame counts as still.
    settle_frames : int, frames
        Consecutive still frames that mean settled.
    settle_trim : float, fraction in [0, 0.5)
        Share of the fastest particles left out of that RMS: a few particles
        caught between body parts (armpit, crotch) chatter against the contact
        planes and would otherwise hold a visibly still drape from settling.
    damping : float, 1/s
        Velocity decay rate (air drag and internal friction).
    gravity : float, m/s^2
        Along -Z.
    thickness : float, m, or None
        Collision offset from the body; None: the material's.
    friction : float (Coulomb coefficient, no unit) or None
        Friction against the body; None: the material's.
    search_distance : float, m
        How far from the body a particle looks for contact; a particle deeper
        inside the body than this is not pushed out.
    tether_slack : float, fraction, or None
        Long-range attachments let a particle stray this fraction beyond its
        fabric distance from the nearest pin (0.01 = 1 %); None disables them.
    hold_pins : bool
        Every pin holds for the whole drape. False (the default): an upper
        garment's pins (its collar) let go once it has grown to its pattern
        size (:attr:`core.drape.mesh.Cloth.pin_lets_go`), so a worn shirt
        hangs from its shoulders; a lower garment's waistband stays held.
        With the collar held at the skintight neck a loose shirt hangs from
        it as from a drawstring: its torso stands out like a bell and its
        hem rises with the ease (benchmarks/results/drape_gap.md). True
        holds them all, as Blender's and Newton's cloth do in the
        side-by-side comparison (``bench_drape``).
    contact_interval : int, substeps
        Substeps between contact searches (in between, contact is resolved
        against the plane found: through the particle's closest point on the
        body, facing the particle, so it follows the surface round convex edges).
    max_speed : float, m/s
        An RMS speed above this is a diverged (exploding) simulation.
    max_extent : float, m
        A garment bounding box larger than this is a diverged (runaway) one.
    max_strain : float, fraction
        A triangle stretched more than this (3 = 300 %) is a diverged drape.
    grow_frames : int, frames
        Frames over which the fabric grows from its skintight start to its
        pattern size (the rest stretch of every triangle goes linearly from its
        start value to 1, substep by substep): a loose garment unfolds
        quasi-statically instead of springing off the body; 0: at once.
    onset_frames : int, frames, or None
        ``solver="pd"`` or ``"newton"``: the first this many frames take
        ``onset_factor`` times ``iterations`` a substep. A cloth released at
        its rest shape falls free and picks its fold count in its first
        frames, from the error of those frames' solves: on the Cusick disc
        (10 mm, pd, 8 specimens) 5 frames at 8x give wool 63.1 % and cotton
        71.5 % with 8 nodes, within 2.2 points at 4x the iterations and at
        5 mm, where none read 55.0 % (4 nodes; +7.4 at 4x) and 68.1 % (6).
        None (the default): :data:`ONSET_FRAMES` for a cloth that starts at
        its rest shape or grows to it at once (``grow_frames`` 0: a specimen,
        a sheet), 0 for one that grows from a skintight start over
        ``grow_frames`` (a garment: it buckles as it grows, and 5 frames at
        8x change the 1.5 cm shirt's mean dihedral angle 13.3 -> 13.8 deg
        for 63 % more CPU; benchmarks/results/drape_pd.md, session 8 p1).
    onset_factor : int
        The iterations' multiple over the first ``onset_frames`` frames.
    self_collision : bool
        Keep the garment's particles apart (folds and layers stack instead of
        passing through each other). Off by default: it is particle against
        particle only (a layer can still slip through another between vertices
        where the mesh is coarser than the radius), roughly doubles the time
        per frame, and a loose garment squeezed between body parts (armpits)
        may chatter and settle later.
    self_radius : float, m, or None
        Particle radius of the self-collision (two particles stay twice this
        apart); None: 0.4 x the median pattern edge, so that a layer cannot slip
        between the vertices of another.
    self_exclude : float, self-collision diameters
        Particles that start (skintight) closer than this many diameters and lie
        within two mesh rings of each other are fabric neighbours and do not
        collide (nor do particles that start within half a radius of each other).
    self_interval : int, substeps, or None
        Substeps between searches for self-collision candidates (a hash grid
        over the particles); every substep resolves the candidates found.
        None: the solver's :data:`SELF_INTERVAL` (5 XPBD substeps, 8 ms at
        30 fps; every pd substep, 17 ms: at 5 pd substeps a sheet falling 3 cm
        onto another passed through it between two searches).
    refine_edge : float, m, or None
        The drape's own mesh: where the cloth hangs free (its pattern triangle
        larger than its skintight image), the pattern's triangles are bisected
        until no edge is longer than this (:mod:`core.drape.refine`; the rest
        shape is the flat pattern's, subdivided, and seams stay sewn); None
        (the default here) drapes the pattern solve's mesh as it is. ``ease
        drape`` refines to 0.01 m unless told otherwise (``--refine-edge``).
    strain_limit : float, multiples of a grain spring's weight (no unit)
        ``solver="pd"``: each triangle's weft (warp) image stretched past the material's ``max_stretch``
        at the end of a substep's solve is pulled back in the next ones by a penalty on the excess,
        ``w / 2 (|f| - (1 + max_stretch) rest)^2``, ``w`` this many times that grain spring's weight
        (:attr:`core.drape.pd.ProjectiveStep.limit_weight`; 30 holds a soft hanging sheet that stretches
        12.1 % at 5.23 %, 100 at 5.07 %); a drape whose fabric stays within its limit is unchanged bit for
        bit. 0 (the default): no limit. Off by default because on a garment cut smaller than the body it
        does not help: the body's contact keeps the cloth outside the body and the limit cannot shorten
        what wraps it (the pants at ease 0.9 in cotton at 30: weft stretch 18.4 % (p95) against 18.1 %
        without, settled in 42 frames against 29; at 100 unsettled after 250;
        benchmarks/results/drape_strain_limit.md). The drape report's ``stretch_limit`` says where the
        fabric is past its ``max_stretch`` either way.
        The other solvers ignore it.
    """

    device: str = "cpu"
    solver: str = "pd"
    fps: float = 30.0  # 1/s
    substeps: Optional[int] = None  # per frame; None: SUBSTEPS[solver]
    iterations: Optional[int] = None  # per substep; None: ITERATIONS[solver]
    tolerance: float = 0.01  # of a particle's weight
    vbd_damping: float = 3.0e-5  # s
    max_frames: int = 120  # frames
    min_frames: int = 10  # frames
    settle_speed: float = 0.01  # m/s
    settle_frames: int = 5  # frames
    settle_trim: float = 0.02  # fraction of the particles
    damping: float = 3.0  # 1/s
    gravity: float = 9.81  # m/s^2
    thickness: Optional[float] = None  # m
    friction: Optional[float] = None  # Coulomb coefficient
    search_distance: float = 0.03  # m
    tether_slack: Optional[float] = 0.01  # fraction of the fabric distance
    hold_pins: bool = False
    contact_interval: int = 10  # substeps
    max_speed: float = 30.0  # m/s
    max_extent: float = 6.0  # m
    max_strain: float = 3.0  # fraction
    grow_frames: int = 20  # frames
    onset_frames: Optional[int] = None  # frames; None: ONSET_FRAMES for a cloth released at rest, else 0
    onset_factor: int = 8  # x iterations
    self_collision: bool = False
    self_radius: Optional[float] = None  # m
    self_exclude: float = 1.5  # self-collision diameters
    self_interval: Optional[int] = None  # substeps; None: SELF_INTERVAL[solver]
    refine_edge: Optional[float] = None  # m
    strain_limit: float = 0.0  # x the grain spring's weight; 0: off

    def __post_init__(self):
        if self.iterations is None:
            self.iterations = ITERATIONS.get(self.solver, 1)
        if self.substeps is None and self.solver != "pd":  # pd's depends on the fabric: default_substeps
            self.substeps = SUBSTEPS.get(self.solver, 20)
        if self.self_interval is None:
            self.self_interval = SELF_INTERVAL.get(self.solver, 5)

    @staticmethod
    def coerce(options: Union[None, "DrapeOptions", Mapping]) -> "DrapeOptions":
        """Validated options from None (the defaults), DrapeOptions or a dict of its fields."""
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
        """Raise DrapeError naming the first field out of its range (:data:`RANGES`)."""
        for name in RANGES:
            check_option(name, getattr(self, name))
        if not isinstance(self.device, str):
            raise DrapeError(f"drape option device = {self.device!r}: expected 'cpu' or 'cuda'")
        if self.solver not in SOLVERS:
            raise DrapeError(f"drape option solver = {self.solver!r}: expected one of {', '.join(SOLVERS)}")
        for name in ("self_collision", "hold_pins"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise DrapeError(f"drape option {name} = {getattr(self, name)!r}: expected true or false")


#: frames of ``onset_factor`` x the iterations for a cloth released at its rest shape
#: (:attr:`DrapeOptions.onset_frames` None): the Cusick disc's fold count is picked in its first
#: 3-5 frames (2 at 8x: wool 63.1 % with 8 nodes but cotton 68.2 % with 5-6; 5: 71.1 % with 8)
ONSET_FRAMES = 5
#: the drape solvers (:attr:`DrapeOptions.solver`)
SOLVERS = ("xpbd", "vbd", "newton", "pd")
#: each solver's iterations per substep when none are given
ITERATIONS = {"xpbd": 1, "vbd": 2, "newton": 30, "pd": 10}
#: each solver's substeps per frame when none are given; pd's is the least of :func:`default_substeps`:
#: projective dynamics is an implicit step (stable at any step), and 2 substeps keep gravity's fall per
#: substep (2.7 mm at 30 fps) inside a 3 mm contact thickness (one substep a frame tore the shirt's cuffs)
SUBSTEPS = {"xpbd": 20, "vbd": 20, "newton": 20, "pd": 2}
#: each solver's substeps between self-collision searches when none are given (the search radius's margin
#: covers about one contact radius of motion until the next search: pd's substep is 10x XPBD's)
SELF_INTERVAL = {"xpbd": 5, "vbd": 5, "newton": 5, "pd": 1}


def default_substeps(options: "DrapeOptions", thickness: float) -> int:
    """Substeps per frame where ``options.substeps`` is None: the solver's :data:`SUBSTEPS`; for pd the
    fewest, at least ``SUBSTEPS["pd"]``, whose substep lets gravity move a particle no further than the
    contact ``thickness`` (m), the drape solver's limit (``gravity / (fps n)^2 <= thickness``)."""
    if options.substeps is not None:
        return int(options.substeps)
    n = SUBSTEPS.get(options.solver, 20)
    if options.solver == "pd":
        while n < RANGES["substeps"][3] and float(options.gravity) / (float(options.fps) * n) ** 2 > thickness:
            n += 1
    return n


#: name -> (kind, low, low included, high, None allowed) of every numeric option.
#: The upper bounds are far beyond any useful drape; they exist so a typo
#: (frames 10**9, thickness 1e6) is refused before any work instead of running
#: for days or allocating without end.
RANGES = {
    "fps": (float, 0.0, False, 1000.0, False),
    "substeps": (int, 1, True, 1000, True),
    "iterations": (int, 1, True, 1000, True),
    "tolerance": (float, 0.0, True, 100.0, False),
    "vbd_damping": (float, 0.0, True, 1.0, False),
    "max_frames": (int, 1, True, 10000, False),
    "min_frames": (int, 0, True, 10000, False),
    "settle_speed": (float, 0.0, False, 10.0, False),
    "settle_frames": (int, 1, True, 10000, False),
    "settle_trim": (float, 0.0, True, 0.5, False),
    "damping": (float, 0.0, True, 1000.0, False),
    "gravity": (float, 0.0, True, 100.0, False),
    "thickness": (float, 0.0, True, 0.05, True),
    "friction": (float, 0.0, True, 10.0, True),
    "search_distance": (float, 0.0, False, 1.0, False),
    "tether_slack": (float, 0.0, True, 10.0, True),
    "contact_interval": (int, 1, True, 1000, False),
    "max_speed": (float, 0.0, False, 1e4, False),
    "max_extent": (float, 0.0, False, 1e3, False),
    "max_strain": (float, 0.0, False, 1e3, False),
    "grow_frames": (int, 0, True, 10000, False),
    "onset_frames": (int, 0, True, 10000, True),
    "onset_factor": (int, 1, True, 100, False),
    "self_radius": (float, 0.0, True, 0.05, True),
    "self_exclude": (float, 0.0, True, 100.0, False),
    "self_interval": (int, 1, True, 1000, True),
    "refine_edge": (float, 0.001, True, 0.1, True),
    "strain_limit": (float, 0.0, True, 1e6, False),
}


def check_option(name: str, value, label: Optional[str] = None) -> None:
    """Raise DrapeError unless ``value`` lies in the range of option ``name``.

    ``label`` names the option in the message (a CLI flag such as
    ``--frames``); default ``drape option NAME``. ``settle_trim`` excludes its
    upper bound (a fraction below one half); every other bound is included.
    """
    kind, low, low_in, high, none_ok = RANGES[name]
    label = label or f"drape option {name}"
    if value is None and none_ok:
        return
    is_int = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    is_num = is_int or (isinstance(value, (float, np.floating)) and kind is float)
    high_in = name != "settle_trim"
    ok = (
        is_num
        and np.isfinite(value)
        and (value >= low if low_in else value > low)
        and (value <= high if high_in else value < high)
    )
    if not ok:
        what = "an integer" if kind is int else "a number"
        span = f"{'[' if low_in else '('}{low:g}, {high:g}{']' if high_in else ')'}"
        raise DrapeError(f"{label} = {value!r}: expected {what} in {span}{' or None' if none_ok else ''}")
