"""Settings of the pattern optimizer, grouped by what they act on, with the three presets.

Every energy term is normalised to be dimensionless and independent of the
mesh resolution and the garment's size (:mod:`.solve`), so the weights are
plain numbers. Groups:

- :class:`Weights` -- the terms' weights (paper Eqs. ease, ARAP, seam length / straightness / curvature);
- :class:`RestShape` -- the regulariser's rest shape and the local step;
- :class:`SeamOptions` -- the seam terms' targets and which seams are sewn gathered;
- :class:`Feedback` -- the per-iteration correction of the targets by the achieved scales;
- :class:`Adaptation` -- what pose adaptation solves do differently;
- :class:`CollapseGuard` -- the targets of triangles near collapse raised until they open;
- :class:`Convergence` -- when a solve stops (its iterations, or until converged).

Precedence, for every setting the design can also give (``materials``): the
caller's value over the design's over the default. Only the gathering
threshold is such a setting here (the design's gathered seams add to the
caller's); the stretch tolerances are the adaptation's arguments
(:func:`core.pattern.solve.adapt_pattern`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field, fields, replace
from typing import Mapping, Optional, Tuple

import numpy as np

from ..choices import TRANSFER_SOLVERS  # the bodies a transfer's solver can be made on
from ..design.materials import EPS_WEFT, GATHER_ABOVE
from ..errors import PatternError

#: A gathering threshold left to the design: its ``materials.gather_above``, else the
#: :class:`core.design.materials.Materials` default (0.2).
FROM_DESIGN = "design"


@dataclass(frozen=True)
class Weights:
    """Weights of the energy terms (dimensionless: each term is a relative strain squared over the area).

    ``ease``: the ease term (lambda_ease: the pattern's Jacobian towards the
    targets). ``regulariser``: the ARAP term (lambda_reg: towards the rotated
    rest shape). ``seam_length``, ``seam_straight``, ``seam_curve``: the seam
    terms (lambda_len, lambda_straight, lambda_curve); 0 removes a term from
    every seam (to sew one seam without its length term, gather it:
    :attr:`SeamOptions.gathered`). ``warp_column``: relative weight of the
    warp column in the ease and regulariser terms (< 1 lets warp give way to
    the weft target). ``sliver``: every triangle weighs at least this
    fraction of the mean triangle weight, so slivers do not fold for free.
    """

    ease: float = 0.1
    regulariser: float = 1.0
    seam_length: float = 15.0
    seam_straight: float = 0.1
    seam_curve: float = 0.1
    warp_column: float = 1.0
    sliver: float = 0.5


@dataclass(frozen=True)
class RestShape:
    """The regulariser's rest shape and how the local step fits it.

    ``model``: ``"prestretch"`` (ours: targets ``diag(c) K``, the scales act
    along the pattern's own weft/warp after the local rotation, and the ARAP
    rest shape is the pre-stretched ``diag(c) R K``) or ``"isometric"`` (the
    paper literally: targets ``K diag(c)``, the initial flattening's
    barycentric offsets scaled, and the ARAP rest shape the isometric ``R K``).
    ``warp_slack``: the local step may scale the rest shape's warp by a factor
    within ``[1/(1+slack), 1+slack]`` (0 = off: the design's lengths kept
    along the grain, mean warp deviation ~3 % instead of 6-8 % at 0.12, for
    seam mismatch up to 4.5 mm or, with a stronger seam length term, weft
    compliance 1.4 %; see docs: the warp frontier).
    ``warp_row``: weight of the pattern's
    warp (v) row against the weft (u) row when the local step fits each
    triangle's rotation (< 1: the rest shape turns to the current weft first).
    """

    model: str = "prestretch"
    warp_slack: float = 0.12
    warp_row: float = 0.5


@dataclass(frozen=True)
class SeamOptions:
    """Targets of the seam terms and the gathered seams.

    ``straight_target``: ``"smooth"`` (second differences of each seam towards
    the mean of their neighbours: damps oscillations, keeps crotch and
    armhole curves) or ``"zero"`` (the paper: towards 0, which straightens
    seams that must be curved). ``length_integral``: gain of the integral
    action on seam-edge length mismatch (0 = the paper's proximal
    linearisation only); ``length_integral_cap``: its bound, as a fraction of
    the edge's length. ``gathered``: seams sewn gathered (cut seam names,
    seam lines, or lines in every garment; ``"*"`` for all): their length and
    matched-curvature terms are off, the longer side is gathered into the
    shorter. The design's ``materials.gathered`` adds to them.
    ``gather_above``: a seam whose two sides' ease demands differ by more
    than this fraction is gathered too; None never gathers on its own;
    :data:`FROM_DESIGN` takes the design's ``materials.gather_above``, else
    the
    :class:`core.design.materials.Materials` default (0.2).
    """

    straight_target: str = "smooth"
    length_integral: float = 1.0
    length_integral_cap: float = 1.0
    gathered: Tuple[str, ...] = ()
    gather_above: object = FROM_DESIGN

    def __post_init__(self):
        # a list of names (a caller's, a JSON's) kept as a tuple: a configuration is hashable, as the
        # solver's per-configuration seam plans need (PatternSolver.design_plan)
        if isinstance(self.gathered, list):
            object.__setattr__(self, "gathered", tuple(self.gathered))


@dataclass(frozen=True)
class Feedback:
    """Per-iteration correction of the targets by the ratio target / achieved scale (SPEC rho-hat).

    ``weft``, ``warp``: the gains (exponents of the ratio; 0 = off, the
    paper): compliance bought with shear. ``from_iteration``: the first
    iteration (0-based) that corrects. ``step``: bound of one iteration's
    correction factor, ``1 +- step``. ``floor``, ``ceiling``: bounds of the
    accumulated correction factor (adaptation solves use their own ceiling
    and step, :class:`Adaptation`).
    """

    weft: float = 0.06
    warp: float = 0.0
    from_iteration: int = 2
    step: float = 0.03
    floor: float = 0.8
    ceiling: float = 1.25


@dataclass(frozen=True)
class Adaptation:
    """What pose adaptation solves do differently (paper Eqs. adapt-scale, material-scale).

    ``margin``: pose demands are raised by this fraction before the tolerance
    applies, so that the optimizer's own compliance error (~1-2 %) does not
    leave triangles just above the tolerance (the paper aims exactly at it:
    0). ``gain``: the weft and warp feedback gain of adaptation solves (at
    least the :class:`Feedback` gains; pose demands are local, hence
    incompatible in 2D without shear): it aims at the poses' demands along the
    pattern's current weft and warp (0 = no feedback, the paper).
    ``warp_gain``: the warp feedback gain of adaptation solves instead
    (None: ``gain``; a strong warp feedback chases the poses' local warp
    demands, up to 4-7 x at the armpit, with shear and seam mismatch).
    ``min_iterations``: adaptation solves run at least this many iterations.
    ``ceiling``, ``step``: bounds of the feedback's accumulated and
    per-iteration correction factors (the poses' local demands are far from
    uniform). ``spread``: passes of the running maximum of the neighbours'
    mean over the raised targets (0 = none): the cloth around a sharp demand
    is raised too, so the raised region has a flat shape with less shear.
    ``cap_weft``, ``cap_warp``: most a target may be raised, as a multiple of
    the design's (None: no cap; the warp capped at 2: the poses ask up to 4-7 x
    at the armpit, which no flat cloth follows without shearing its neighbours).
    ``settle``: the last iterations of an adaptation solve run with the
    feedback frozen (0 = none): the targets stop moving, so the seams' length
    integral closes the seams and the shear the moving targets drive settles
    (30 of 60: the pants in pose P3 keep 2.2 mm on a seam after 10 of 40, 2.0
    after 20 of 50, 1.8 after 30 of 60; the shirt and pants' other figures move
    by under 0.2 point, at 1.5 x the adaptation's iterations).
    ``lower``: how far one iteration may lower a target's correction, as a
    fraction of ``step`` (0: the feedback only raises: an adaptation adds
    cloth where a pose needs it, and lowering it where a triangle is past its
    goal pulls that triangle against its raised neighbours, which is shear,
    for less cloth; 1: both ways alike).
    ``feedback_until``: the iteration (0-based) from which the feedback holds
    still at the latest, however many iterations the solve runs (None: only
    the last ``settle`` hold it). A solve run long for another reason (the
    fitted preset's 300, for its darts to open) would otherwise chase the
    poses' demands all the way: the raising-only feedback ratchets up the
    corrections of the few triangles still short of a demand the curvature
    does not allow, each raise against its neighbours bought with shear
    (four-dart blouse in P1: after iteration 30 the corrections of 6 % (weft)
    and 10 % (warp) of the area kept rising, up to 1.8 / 2.0 x, around the
    waist and the armpits; the back's shear p95 10.4 deg, the garment's 8.3
    after 268 moving iterations, 6.1 after 28).
    """

    margin: float = 0.12
    gain: float = 0.1
    min_iterations: int = 60
    ceiling: float = 2.0
    step: float = 0.06
    warp_gain: Optional[float] = 0.04
    spread: int = 30
    cap_weft: Optional[float] = None
    cap_warp: Optional[float] = 2.0
    settle: int = 30
    lower: float = 0.0
    feedback_until: Optional[int] = None

    def holds(self, iteration: int, planned: int) -> bool:
        """Whether an adaptation's feedback holds still in ``iteration`` (0-based) of a solve of ``planned``
        iterations: in the last ``settle`` and from ``feedback_until`` on."""
        return (
            self.settle > 0
            and iteration >= planned - self.settle
            or self.feedback_until is not None
            and iteration >= self.feedback_until
        )


@dataclass(frozen=True)
class CollapseGuard:
    """Keeps every triangle open (no collapse: no triangle squeezed to a sliver without flipping).

    Where the body is far from developable (the skirt topology's bridge
    between the legs: cones of angle sum 1.4 x 2 pi next to 0.6 x 2 pi) the
    cheapest flat map squeezes a few triangles to slivers rather than spread
    the squeeze over their neighbours, and the flip guard holds them there.
    With ``Q`` a triangle's Jacobian relative to its targets (singular values
    1: the targets met; the smaller bounds its weft and warp scales from
    below as fractions of their targets), a triangle whose smaller singular
    value falls under ``guard_scale`` is stiffened: its ease and regulariser
    weight times ``1 + gain``, the gain raised by ``guard_grow`` per iteration
    while it stays under (from 1, at most ``guard_limit``), and pulled towards
    ``Q`` with its singular values clamped from below at ``guard_open``
    (rotation and shear kept). A solve where no triangle nears collapse is
    unchanged; one that guards factorises its own stiffened matrix (kept in
    the solve's state; the solver's shared factorisation is untouched).
    Targets reported and measured stay the design's. ``guard_scale`` 0 turns
    it off (the paper preset).
    """

    guard_scale: float = 0.6
    guard_open: float = 0.7
    guard_grow: float = 2.0
    guard_limit: float = 30.0
    guard_release: float = 0.5


@dataclass(frozen=True)
class Convergence:
    """When a reference or transfer solve has converged: it runs its ``iterations``, then rounds of
    ``window`` more while it has not, up to ``cap`` iterations in all.

    Converged: over the last ``window`` iterations the regulariser energy (the local step's ARAP
    residual, :func:`~core.pattern.optimizer.steps.regulariser_energy`) changed by under
    ``energy_rtol`` of itself per iteration, and the last iteration moved no vertex by more than
    ``max_move`` mean edge lengths. ``energy_rtol`` 0 turns the rule off: the solve runs its
    ``iterations`` (with the collapse guard's extra rounds). A solve with a fixed iteration count
    stops short by however far its start was (a transfer starts from the reference pattern, so it
    converges further in the same count than the reference itself: the teaser's front sleeve on
    women:L sewed 0.4 mm shorter than on M); the rule stops every size equally converged.
    Adaptation solves with a feedback on the poses' demands (``Adaptation.gain`` > 0) keep their own
    schedule (:class:`Adaptation`).

    ``transfer_from``: where a transfer starts. ``"reference"``: the reference pattern stretched to the
    target body (it has run the reference's iterations already, so the transfer ends further converged
    than the reference itself). ``"flattening"``: the reference solve's own start (the flattening
    stretched by the targets) stretched to the target body, so that with the same iterations every
    size, the design's own included, is solved alike and the grade follows the bodies (the teaser's
    front sleeve XS..XL 1290 < 1316 < 1351 < 1364 < 1381 mm, where from the reference L's 1350.6 was
    under M's 1350.6). Measured in docs/darts.md ("Convergence").

    ``transfer_solver``: which body a transfer's flattening and factorisation are made on.
    ``"reference"``: the reference solver's (the design's body), shared by every size. ``"target"``: the
    target body's (the same cut, its darts' apexes following the cups; flattened and factorised again
    for each size, 0.1-0.7 s of CPU), so that a transfer's local-global steps measure strain in the target's
    own frames, as the reference solve does on its body. Its targets, seam plan and folds are the
    reference's, as with ``"reference"``. Measured in docs/darts.md ("A solver made on the target body").
    ``"cup"``: ``"target"`` started from its flattening with every dart's intake re-derived on a target
    whose cups are bigger than the reference's, ``"reference"`` on any other (docs/darts.md, "Graded to L").

    """

    energy_rtol: float = 0.0
    max_move: float = 0.002
    window: int = 10
    cap: int = 300
    transfer_from: str = "reference"
    transfer_solver: str = "reference"


_GROUPS = {
    "weights": Weights,
    "rest_shape": RestShape,
    "seams": SeamOptions,
    "feedback": Feedback,
    "adaptation": Adaptation,
    "guard": CollapseGuard,
    "convergence": Convergence,
}


@dataclass(frozen=True)
class SolverConfig:
    """All settings of one solve: ``iterations`` (local-global iterations), ``realign_grain`` (turn every
    piece so its voted grain is +y after each iteration) and the groups (module docstring).

    Build one from a preset with overrides: ``SolverConfig.named("improved", iterations=5,
    gathered=("*",))``. An override is a top-level field, a group (an instance, or a dict of the
    fields to change), or a field of exactly one group by its own name.
    """

    iterations: int = 20
    realign_grain: bool = True
    weights: Weights = field(default_factory=Weights)
    rest_shape: RestShape = field(default_factory=RestShape)
    seams: SeamOptions = field(default_factory=SeamOptions)
    feedback: Feedback = field(default_factory=Feedback)
    adaptation: Adaptation = field(default_factory=Adaptation)
    guard: CollapseGuard = field(default_factory=CollapseGuard)
    convergence: Convergence = field(default_factory=Convergence)

    @classmethod
    def paper(cls, **overrides) -> "SolverConfig":
        """The paper's weights taken literally (isometric ARAP regulariser, no feedback, no gathering),
        with the collapse guard (not a term of the paper's energy: without it the shirt and pants
        keep 27-35 collapsed triangles, which every pattern is refused for; with it the figures
        move by under 0.1 point)."""
        base = cls(
            weights=Weights(seam_length=100.0, seam_straight=5.0, seam_curve=10.0),
            rest_shape=RestShape(model="isometric", warp_slack=0.0, warp_row=1.0),
            seams=SeamOptions(straight_target="zero", length_integral=0.0, gather_above=None),
            feedback=Feedback(weft=0.0, warp=0.0),
            adaptation=Adaptation(margin=0.0, gain=0.0, warp_gain=None, spread=0, cap_warp=None, settle=0, lower=1.0),
        )
        return base.with_overrides(**overrides)

    @classmethod
    def improved(cls, **overrides) -> "SolverConfig":
        """Our default: pre-stretched ARAP rest shape, lighter seam-shape terms, free warp length within 12 %,
        light weft feedback (gain 0.06), seams gathered where their sides' demands differ by
        > 20 %, the collapse guard; adaptation: margin 12 %, feedback 0.1 (warp 0.04), raising only, on targets
        spread over 30 passes, warp targets capped at 2, 60 iterations of which the last 30 with the feedback
        frozen."""
        return cls().with_overrides(**overrides)

    @classmethod
    def stretch(cls, **overrides) -> "SolverConfig":
        """Improved, with a stronger weft target feedback (gain 0.15), warp slack 0.1 and both rows weighted
        alike: compliance bought with shear and local warp length."""
        base = cls(rest_shape=RestShape(warp_slack=0.1, warp_row=1.0), feedback=Feedback(weft=0.15))
        return base.with_overrides(**overrides)

    @classmethod
    def fitted(cls, **overrides) -> "SolverConfig":
        """Improved, solved to convergence for darted, close-fitting garments: 300 iterations (the darts
        open over the iterations, ~60-90 % of the way after 20), the design's warp lengths nearly kept
        (warp slack 0.01), a weak weft feedback (gain 0.01, its accumulated correction at most 1.2) and
        the regulariser at 2 (it holds the shear the feedback would buy). On the four-dart blouse,
        women:M at ease 1.1 (weft %, warp %, shear p95 deg, bust region %): 0.60 / 2.87 / 4.9 / 1.36,
        against improved at 200 iterations 0.38 / 8.73 / 5.2 / 1.06 and at 20 1.36 / 8.64 / 5.9 / 3.03
        (benchmarks/results/pattern.md, women's wear). About 15x the iterations of improved. Its adaptations
        move the targets in the first 30 iterations only, as improved's 60 do (``feedback_until``), and settle
        in the other 270: after adaptation to P1, shear p95 6.1 deg instead of 8.3, residual stretch weft /
        warp 0.07 / 0.55 % (0.16 / 0.45), seams 0.17 mm (0.70), 2 % less cloth."""
        base = cls(
            iterations=300,
            weights=Weights(regulariser=2.0),
            rest_shape=RestShape(warp_slack=0.01),
            feedback=Feedback(weft=0.01, ceiling=1.2),
            adaptation=Adaptation(feedback_until=Adaptation.min_iterations - Adaptation.settle),
        )
        return base.with_overrides(**overrides)

    @classmethod
    def lengths(cls, **overrides) -> "SolverConfig":
        """Improved with the design's lengths kept along the grain: warp slack 0 and a weft and warp target
        feedback (gains 0.13 / 0.07) that buy the weft and warp scales back with shear. On the shirt and
        the pants at every uniform ease 0.9-2.0: weft <= 1.15 %, warp <= 2.94 %, for shear p95 7.7-9.4 deg
        (improved: 4.1-4.8 deg, warp 6.4-7.8 %) and seams <= 2.8 mm; on the skirt topology seams reach
        3.1-4.7 mm, over the 3 mm templates promise (benchmarks/results/frontier.md: the frontier this
        point lies on)."""
        base = cls(rest_shape=RestShape(warp_slack=0.0), feedback=Feedback(weft=0.13, warp=0.07))
        return base.with_overrides(**overrides)

    @classmethod
    def named(cls, name: str, **overrides) -> "SolverConfig":
        """The preset ``name`` (``paper``, ``improved``, ``stretch``, ``fitted``, ``lengths``) with ``overrides``."""
        table = {
            "paper": cls.paper,
            "improved": cls.improved,
            "stretch": cls.stretch,
            "fitted": cls.fitted,
            "lengths": cls.lengths,
        }
        if name not in table:
            raise PatternError(f"solver configuration: expected one of {', '.join(table)}, got {name!r}")
        return table[name](**overrides)

    def with_overrides(self, **overrides) -> "SolverConfig":
        """This configuration with ``overrides`` (class docstring); unknown or ambiguous names are refused."""
        top, changes = {}, {}
        for key, value in overrides.items():
            if key in _GROUPS:
                if isinstance(value, _GROUPS[key]):
                    top[key] = value
                elif isinstance(value, Mapping):
                    changes.setdefault(key, {}).update(value)
                else:
                    raise PatternError(
                        f"solver configuration {key}: expected a {_GROUPS[key].__name__} or a dict "
                        f"of its fields, got {value!r}"
                    )
            elif key in ("iterations", "realign_grain"):
                top[key] = value
            else:
                owners = [g for g, kind in _GROUPS.items() if key in {f.name for f in fields(kind)}]
                if len(owners) != 1:
                    why = f"in {' and '.join(owners)}: name the group" if owners else "no such setting"
                    raise PatternError(f"solver configuration {key}: {why}")
                changes.setdefault(owners[0], {})[key] = value
        for group, change in changes.items():
            known = {f.name for f in fields(_GROUPS[group])}
            for key in change:
                if key not in known:
                    raise PatternError(f"solver configuration {group}.{key}: no such setting")
            top[group] = replace(top.get(group, getattr(self, group)), **change)
        return replace(self, **top)

    @property
    def gather_above(self) -> Optional[float]:
        """The gathering threshold of a design that gives none (for callers showing the default)."""
        return gather_threshold(self, None)

    def to_dict(self) -> dict:
        """Plain nested dict of every setting (JSON-ready)."""
        return dataclasses.asdict(self)

    def check(self) -> None:
        """Raise :class:`PatternError` naming the first invalid setting."""
        w, r, s, fb, ad, gd = self.weights, self.rest_shape, self.seams, self.feedback, self.adaptation, self.guard
        nonneg = [
            ("guard", gd, ("guard_scale",)),
            ("weights", w, ("ease", "regulariser", "seam_length", "seam_straight", "seam_curve", "sliver")),
            ("rest_shape", r, ("warp_slack",)),
            ("seams", s, ("length_integral", "length_integral_cap")),
            ("feedback", fb, ("weft", "warp", "step")),
            ("adaptation", ad, ("margin", "gain", "step", "lower")),
        ]
        for group, obj, names in nonneg:
            for k in names:
                _finite(f"{group}.{k}", getattr(obj, k), 0.0, ">=")
        if w.ease + w.regulariser <= 0:
            raise PatternError("solver configuration weights: ease + regulariser must be > 0")
        _finite("weights.warp_column", w.warp_column, 0.0, ">")
        _finite("rest_shape.warp_row", r.warp_row, 0.0, ">")
        _finite("feedback.floor", fb.floor, 0.0, ">")
        if fb.floor > 1:
            raise PatternError(f"solver configuration feedback.floor: expected <= 1, got {fb.floor}")
        _finite("feedback.ceiling", fb.ceiling, 1.0, ">=")
        _finite("adaptation.ceiling", ad.ceiling, 1.0, ">=")
        _finite("guard.guard_open", gd.guard_open, gd.guard_scale, ">=")
        _finite("guard.guard_grow", gd.guard_grow, 1.0, ">")
        _finite("guard.guard_limit", gd.guard_limit, 1.0, ">=")
        _finite("guard.guard_release", gd.guard_release, 0.0, ">=")
        if gd.guard_release > 1:
            raise PatternError(f"solver configuration guard.guard_release: expected <= 1, got {gd.guard_release}")
        for name, v in (("iterations", self.iterations), ("adaptation.min_iterations", ad.min_iterations)):
            check_iterations(f"solver configuration {name}", v)
        check_iterations("solver configuration adaptation.spread", ad.spread, low=0)
        check_iterations("solver configuration adaptation.settle", ad.settle, low=0)
        if ad.feedback_until is not None:
            check_iterations("solver configuration adaptation.feedback_until", ad.feedback_until, low=0)
        if ad.settle >= max(self.iterations, ad.min_iterations):
            raise PatternError(
                f"solver configuration adaptation.settle: expected fewer than the adaptation's "
                f"{max(self.iterations, ad.min_iterations)} iterations, got {ad.settle}"
            )
        if ad.warp_gain is not None:
            _finite("adaptation.warp_gain", ad.warp_gain, 0.0, ">=")
        for k in ("cap_weft", "cap_warp"):
            if getattr(ad, k) is not None:
                _finite(f"adaptation.{k}", getattr(ad, k), 1.0, ">=")
        check_iterations("solver configuration feedback.from_iteration", fb.from_iteration, low=0)
        cv = self.convergence
        _finite("convergence.energy_rtol", cv.energy_rtol, 0.0, ">=")
        _finite("convergence.max_move", cv.max_move, 0.0, ">")
        check_iterations("solver configuration convergence.window", cv.window)
        check_iterations("solver configuration convergence.cap", cv.cap)
        if cv.transfer_from not in ("reference", "flattening"):
            raise PatternError(
                "solver configuration convergence.transfer_from: expected 'reference' or 'flattening', "
                f"got {cv.transfer_from!r}"
            )
        if cv.transfer_solver not in TRANSFER_SOLVERS:
            raise PatternError(
                "solver configuration convergence.transfer_solver: expected "
                f"{' or '.join(repr(t) for t in TRANSFER_SOLVERS)}, got {cv.transfer_solver!r}"
            )
        if s.straight_target not in ("zero", "smooth"):
            raise PatternError(
                f"solver configuration seams.straight_target: expected 'zero' or 'smooth', got {s.straight_target!r}"
            )
        if r.model not in ("prestretch", "isometric"):
            raise PatternError(
                f"solver configuration rest_shape.model: expected 'prestretch' or 'isometric', got {r.model!r}"
            )
        a = s.gather_above
        if a != FROM_DESIGN and a is not None and (isinstance(a, str) or not np.isfinite(a) or a <= 0):
            raise PatternError(
                f"solver configuration seams.gather_above: expected a fraction > 0, None or {FROM_DESIGN!r}, got {a!r}"
            )
        if isinstance(s.gathered, str) or not all(isinstance(g, str) for g in s.gathered):
            raise PatternError(
                f"solver configuration seams.gathered: expected a tuple of seam names, got {s.gathered!r}"
            )


#: Most local-global iterations of one solve (default 20; an adaptation at least
#: 40): far beyond convergence, so a typo cannot run for hours.
MAX_ITERATIONS = 1000


def check_iterations(label: str, value, low: int = 1) -> int:
    """``value`` as an int; :class:`PatternError` naming ``label`` unless it is an integer
    in ``[low, MAX_ITERATIONS]``."""
    ok = (
        isinstance(value, (int, np.integer))
        and not isinstance(value, (bool, np.bool_))
        and (low <= value <= MAX_ITERATIONS)
    )
    if not ok:
        raise PatternError(f"{label}: expected an integer in {low}..{MAX_ITERATIONS}, got {value!r}")
    return int(value)


def _finite(name: str, value, bound: float, op: str) -> None:
    ok = (
        isinstance(value, (int, float, np.number))
        and not isinstance(value, bool)
        and np.isfinite(value)
        and (value >= bound if op == ">=" else value > bound)
    )
    if not ok:
        raise PatternError(f"solver configuration {name}: expected a finite value {op} {bound:g}, got {value!r}")


def gather_threshold(config: SolverConfig, materials: Optional[Mapping]) -> Optional[float]:
    """The gathering threshold of a solve: the caller's, else the design's ``materials.gather_above``,
    else the :class:`core.design.materials.Materials` default (None: no seam is gathered on its own)."""
    a = config.seams.gather_above
    if a == FROM_DESIGN:
        a = (materials or {}).get("gather_above", GATHER_ABOVE)
    return None if a is None else float(a)


def tolerances(
    materials: Optional[Mapping], eps_weft: Optional[float] = None, eps_warp: Optional[float] = None
) -> Tuple[float, float]:
    """Stretch tolerances (weft, warp) of an adaptation, each >= 1.

    Weft: the caller's ``eps_weft``, else the design's ``materials.eps_weft``,
    else the :class:`core.design.materials.Materials` default (1.1). Warp: the caller's ``eps_warp``, else the
    caller's ``eps_weft``, else the design's ``materials.eps_warp``, else the weft's.
    """
    m = materials or {}
    weft = eps_weft if eps_weft is not None else m.get("eps_weft", EPS_WEFT)
    warp = eps_warp if eps_warp is not None else eps_weft if eps_weft is not None else m.get("eps_warp", weft)
    return check_tolerance("eps_weft", weft), check_tolerance("eps_warp", warp)


def check_tolerance(name: str, eps) -> float:
    """``eps`` as a float; :class:`PatternError` naming ``name`` unless it is a finite value >= 1."""
    eps = float(eps)
    if not np.isfinite(eps) or eps < 1.0:
        raise PatternError(f"{name}: a stretch tolerance must be >= 1 (1.1 = 10 % stretch), got {eps}")
    return eps
