"""Sizes from measurements: fit a body's shape parameters to tailor's targets.

:data:`SIZE_CHART` defines XS..XL (cm) around the default body (Anny's
reference shape is M); :func:`fit_measurements` fits any model's shape
parameters to target height/chest/waist/hip with bounded least squares and
says, per target, whether it landed within :data:`TOLERANCE_CM` or is not
reachable by this model. :func:`size_shape` returns the shape of a chart size
for a body: the stored fit for the default body (:data:`FITTED_SHAPES`, made
by :func:`fit_measurements` and checked by the tests), otherwise a fit made
once per process.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Mapping, Optional, Sequence

import numpy as np

from ..errors import BodyError
from ..progress import Progress, report, sub
from .charts import ADULT_AGE, LOCAL_GIRTHS, PUBLISHED, SizeChart
from .measure import MEASUREMENTS, measure

TOLERANCE_CM = 1.0

# Strength of the pull towards the start shape in fit_measurements, cm per full parameter range.
REGULARIZATION_CM = 0.5

# Weight (per cm) that holds a measurement without a target at the start body's value in
# fit_measurements, relative to 1 for a target.
HOLD_WEIGHT = 0.3

SIZES = ("XS", "S", "M", "L", "XL")

# Size chart in cm. M is the default Anny body (its reference phenotypes:
# gender 0.5, young adult age 0.7, the rest 0.5) as measured by
# core.body.measure; the other sizes are measured Anny bodies of increasing
# girth at similar height, rounded to 0.5 cm: XS weight 0, muscle 1, height
# 0.48; S weight 0.2, muscle 0.85, height 0.49; L weight 0.75, muscle 0.55,
# height 0.51; XL weight 1, muscle 0.6, height 0.52 (others at the reference).
# Girths step 1.5-6 cm per size (Anny's weight range bounds the small end).
SIZE_CHART: Dict[str, Dict[str, float]] = {
    "XS": {"height": 181.0, "chest": 88.5, "waist": 73.0, "hip": 91.5},
    "S": {"height": 182.5, "chest": 92.0, "waist": 74.5, "hip": 94.0},
    "M": {"height": 183.5, "chest": 95.6, "waist": 78.3, "hip": 99.8},
    "L": {"height": 184.5, "chest": 99.0, "waist": 82.5, "hip": 103.0},
    "XL": {"height": 186.0, "chest": 103.5, "waist": 86.5, "hip": 105.5},
}

# Shape parameters per size, fitted with fit_measurements to SIZE_CHART on the
# model named by the key, stored so the CLI and the add-on need not re-fit
# (tests/test_body_sizes.py re-fits and checks both land within 1 cm). M is
# the reference shape itself. Parameters not listed keep their reference value.
FITTED_SHAPES: Dict[str, Dict[str, Dict[str, float]]] = {
    "anny": {
        "XS": {"height": 0.4792, "weight": 0.0082, "muscle": 0.9788, "proportions": 0.5058},
        "S": {"height": 0.4921, "weight": 0.21, "muscle": 0.8769, "proportions": 0.483},
        "M": {},
        "L": {"height": 0.5074, "weight": 0.5935, "muscle": 0.3827, "proportions": 0.3121},
        "XL": {"height": 0.5186, "weight": 0.7571, "muscle": 0.3839, "proportions": 0.1331},
    },
}

# Plausible target ranges (cm): anything outside is a typo, not a body.
TARGET_RANGES = {"height": (50.0, 250.0), "chest": (40.0, 200.0), "waist": (30.0, 200.0), "hip": (40.0, 200.0)}

# Shape parameters that change size (not gender, age, ethnicity) where the model has them.
PREFERRED_FIT_PARAMETERS = ("height", "weight", "muscle", "proportions")

# Pull of a local change towards 0 (the population's body for the phenotypes), cm per unit of the
# change: stronger than the phenotypes' REGULARIZATION_CM, so a fit uses a local change only as far
# as the phenotypes cannot reach a girth.
LOCAL_REGULARIZATION_CM = 2.0


@dataclass
class FitResult:
    """Outcome of :func:`fit_measurements`.

    Attributes
    ----------
    shape : full shape dict of the fitted body.
    targets : the targets (cm).
    achieved : the measurements of the fitted body (cm), all of :data:`MEASUREMENTS`.
    status : target name -> ``"within 1 cm"`` or ``"not reachable by this model"``.
    evaluations : number of body evaluations the fit used.
    """

    shape: Dict[str, float]
    targets: Dict[str, float]
    achieved: Dict[str, float]
    status: Dict[str, str]
    evaluations: int = 0
    parameters: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return all(s == "within 1 cm" for s in self.status.values())

    def summary(self) -> str:
        """One line per measurement: target, achieved, status."""
        lines = []
        for name in MEASUREMENTS:
            got = self.achieved.get(name)
            if name in self.targets:
                lines.append(f"{name:>6}: {got:6.1f} cm (target {self.targets[name]:.1f}: {self.status[name]})")
            elif got is not None:
                lines.append(f"{name:>6}: {got:6.1f} cm")
        return "\n".join(lines)


def check_targets(targets: Mapping[str, float]) -> Dict[str, float]:
    """Validate measurement targets (cm); ``bust`` is accepted for ``chest``."""
    if not targets:
        raise BodyError(f"no measurement targets given; allowed: {', '.join(MEASUREMENTS)}")
    out = {}
    for key, value in targets.items():
        name = "chest" if key == "bust" else key
        if name not in MEASUREMENTS:
            raise BodyError(f"unknown measurement {key!r}; allowed: {', '.join(MEASUREMENTS)} (cm)")
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise BodyError(f"measurement {key!r} must be a number of cm, got {value!r}") from None
        if name in out:
            raise BodyError(f"measurement {name!r} is given twice (chest and bust are the same girth)")
        lo, hi = TARGET_RANGES[name]
        if not (lo <= value <= hi):
            raise BodyError(f"measurement {key}={value:g} cm is out of range [{lo:g}, {hi:g}] cm")
        out[name] = value
    return out


def local_parameters(body) -> Dict[str, tuple]:
    """The model's local changes a shape may carry besides its shape parameters (Anny's), else {}."""
    own = getattr(body, "local_change_parameters", None)
    return dict(own()) if callable(own) else {}


def fit_parameters(body) -> list:
    """Shape parameters a size fit moves: the size-related ones where the model has
    them (Anny: height, weight, muscle, proportions), else its first ten (SMPL betas)."""
    own = getattr(body, "fit_parameters", None)
    names = list(body.shape_parameters())
    if own:
        return list(own() if callable(own) else own)
    preferred = [n for n in PREFERRED_FIT_PARAMETERS if n in names]
    return preferred if len(preferred) >= 2 else names[:10]


def fit_measurements(
    body,
    targets: Mapping[str, float],
    progress: Optional[Progress] = None,
    parameters: Optional[Sequence[str]] = None,
    start: Optional[Mapping[str, float]] = None,
    bounds: Optional[Mapping[str, Sequence[float]]] = None,
) -> FitResult:
    """Fit ``body``'s shape to target measurements (cm) by bounded least squares.

    Parameters
    ----------
    body : BodyModel.
    targets : subset of {height, chest (or bust), waist, hip} -> cm.
    progress : optional callback; may raise Cancelled.
    parameters : shape parameters to move (default :func:`fit_parameters`);
        the others stay at ``start`` (default the model's reference shape).
    start : initial shape.
    bounds : optional name -> (lo, hi) narrowing a parameter's range (a chart's adult ages).

    Returns
    -------
    FitResult. A target that the model cannot reach within 1 cm is reported as
    ``"not reachable by this model"`` with its achieved value; that is not an error.
    Measurements without a target stay near the start body's (weakly held).

    With the default ``parameters``, a fit that misses is made again from where it stopped with
    :data:`FALLBACK_PARAMETERS` (gender, adult age, cup size) and the local change of each girth
    given (:data:`LOCAL_OF_GIRTH`, Anny's) moving too; the better of the two is returned. A fit
    that lands the first time is the same as without this second pass.
    """
    first = _fit_measurements(
        body, targets, progress if parameters is not None else sub(progress, 0.0, 0.5), parameters, start, bounds
    )
    local = local_parameters(body)
    if first.ok or parameters is not None or not local:
        report(progress, 1.0, "fit done")
        return first
    # The default parameters miss: again from where they stopped, with gender, adult age, the cup
    # and the local change of each girth given moving too (a made-to-measure row the phenotypes
    # around the average body cannot reach: a women's XL, a man's belly).
    own = body.shape_parameters()
    more = [n for n in FALLBACK_PARAMETERS if n in own and n not in first.parameters]
    more += [LOCAL_OF_GIRTH[k] for k in sorted(check_targets(targets)) if LOCAL_OF_GIRTH.get(k) in local]
    narrow = {**({"age": ADULT_AGE} if "age" in own else {}), **dict(bounds or {})}
    second = _fit_measurements(body, targets, sub(progress, 0.5, 1.0), first.parameters + more, first.shape, narrow)
    second.evaluations += first.evaluations
    report(progress, 1.0, "fit done")
    return second if second.ok or _worst_miss(second) < _worst_miss(first) else first


def _worst_miss(fit: "FitResult") -> float:
    return max(abs(fit.achieved[k] - v) for k, v in fit.targets.items())


def _fit_measurements(body, targets, progress, parameters, start, bounds) -> FitResult:
    """One bounded least-squares fit (:func:`fit_measurements` without its fallback)."""
    from scipy.optimize import least_squares

    targets = check_targets(targets)
    local = local_parameters(body)
    allowed = {**body.shape_parameters(), **local}
    names = list(parameters) if parameters is not None else fit_parameters(body)
    for n in names:
        if n not in allowed:
            raise BodyError(
                f"cannot fit unknown shape parameter {n!r}; allowed: {', '.join(body.shape_parameters())}"
                + (" and Anny's local changes" if local else "")
            )
    base = dict(body.default_shape())
    base.update({n: float(allowed[n][2]) for n in names if n in local})
    if start:
        base.update({k: float(v) for k, v in start.items()})
    narrow = dict(bounds or {})
    lo = np.array([max(allowed[n][0], narrow.get(n, allowed[n][:2])[0]) for n in names], dtype=float)
    hi = np.array([min(allowed[n][1], narrow.get(n, allowed[n][:2])[1]) for n in names], dtype=float)
    span = np.where(hi > lo, hi - lo, 1.0)
    keys = sorted(targets)
    want = np.array([targets[k] for k in keys])
    count = [0]

    def shape_of(u):
        s = dict(base)
        s.update({n: float(np.clip(lo[i] + u[i] * span[i], lo[i], hi[i])) for i, n in enumerate(names)})
        return s

    u0 = np.clip((np.array([base[n] for n in names], dtype=float) - lo) / span, 0.0, 1.0)
    # The pull of each parameter towards its start, cm per unit of u (a local change's range is 2).
    pull = np.array(
        [LOCAL_REGULARIZATION_CM * span[i] if n in local else REGULARIZATION_CM for i, n in enumerate(names)]
    )
    # Measurements without a target are held near the start body's (a tailor giving only a
    # chest girth means "this body, bigger chest", not a taller one), where the model can
    # measure them (girths need its landmarks).
    free = [k for k in MEASUREMENTS if k not in targets]
    try:
        held = measure(body, body.vertices(base), free) if free else {}
    except BodyError:
        held = measure(body, body.vertices(base), ["height"]) if "height" in free else {}
    hold_keys = sorted(held)
    hold = np.array([held[k] for k in hold_keys])

    def residual(u):
        count[0] += 1
        if count[0] % 5 == 1:
            report(progress, min(0.95, count[0] / 150.0), f"fitting {', '.join(keys)} ({count[0]} evaluations)")
        got = measure(body, body.vertices(shape_of(u)), keys + hold_keys)
        # A weak pull to the start shape (cm per parameter range) makes the answer unique where
        # the targets leave directions free (fewer targets than parameters, or near-parallel
        # parameters); against girth slopes of 10-30 cm per range it moves a fit by < 0.05 cm.
        # The held measurements pull harder, but still far below the targets' weight.
        return np.concatenate(
            [
                np.array([got[k] for k in keys]) - want,
                HOLD_WEIGHT * (np.array([got[k] for k in hold_keys]) - hold),
                pull * (u - u0),
            ]
        )

    # Finite differences of 1e-3 of the range: the slices' polygon noise stays below it.
    sol = least_squares(
        residual,
        u0,
        bounds=(0.0, 1.0),
        diff_step=1e-3,
        x_scale=1.0,
        ftol=1e-8,
        xtol=1e-8,
        gtol=1e-10,
        max_nfev=200 * max(1, len(names)) // 4 + 40,
    )
    shape = {k: v for k, v in shape_of(sol.x).items() if k not in local or v != 0.0}
    achieved = measure(body, body.vertices(shape))
    status = {
        k: ("within 1 cm" if abs(achieved[k] - targets[k]) <= TOLERANCE_CM else "not reachable by this model")
        for k in keys
    }
    report(progress, 1.0, "fit pass done")
    return FitResult(
        shape=shape, targets=targets, achieved=achieved, status=status, evaluations=count[0], parameters=names
    )


# What fit_measurements moves besides its default parameters where they miss (see there), and the
# local change of each girth target: Anny's measurement modifiers (-1 .. 1, 0 = the phenotype's own
# body), each moving its own girth by 10-18 cm over its range and the others by < 1 cm, all of them
# symmetric (no ``l-``/``r-`` twin), so the body stays left/right symmetric.
FALLBACK_PARAMETERS = ("gender", "age", "cupsize")
LOCAL_OF_GIRTH = dict(zip(("chest", "waist", "hip"), LOCAL_GIRTHS))


_CACHE: Dict[tuple, Dict[str, float]] = {}

DEFAULT_CHART = "default"


def _charts() -> Dict[str, SizeChart]:
    """Every chart by name: the default one (:data:`SIZE_CHART`) first, then the published ones."""
    default = SizeChart(
        name=DEFAULT_CHART, title="Anny's bodies around the reference shape (M)", sizes=SIZE_CHART, fitted=FITTED_SHAPES
    )
    return {DEFAULT_CHART: default, **PUBLISHED}


CHARTS: Dict[str, SizeChart] = _charts()
CHART_NAMES = tuple(CHARTS)


def check_chart(chart: Optional[str], what: str = "chart") -> SizeChart:
    """The chart named ``chart`` (None: the default); a BodyError naming ``what`` and the choices."""
    key = DEFAULT_CHART if chart is None else str(chart).strip().lower()
    if key not in CHARTS:
        raise BodyError(f"{what}: unknown size chart {chart!r}; allowed: {', '.join(CHART_NAMES)}")
    return CHARTS[key]


def chart_sizes(chart: Optional[str] = None) -> tuple:
    """Size names of ``chart`` in size order."""
    return tuple(check_chart(chart).sizes)


def split_size(size: str, chart: Optional[str] = None) -> tuple:
    """(chart, size) of a size name: ``"M"`` (of ``chart``, default the default chart) or
    ``"women:M"``; a BodyError listing the choices for an unknown chart or size."""
    text = str(size).strip()
    if ":" in text:
        named, text = (t.strip() for t in text.split(":", 1))
        if chart is not None and check_chart(named).name != check_chart(chart).name:
            raise BodyError(f"size {size!r} is of chart {named!r}, not of chart {chart!r}")
        chart = named
    c = check_chart(chart)
    key = text.upper()
    if key not in c.sizes:
        where = "" if c.name == DEFAULT_CHART else f" of chart {c.name!r}"
        raise BodyError(f"unknown size {size!r}{where}; allowed: {', '.join(c.sizes)}")
    return c, key


def check_size(size: str, chart: Optional[str] = None) -> str:
    """The canonical name of a chart size: ``"M"`` on the default chart, ``"women:M"`` on another."""
    c, key = split_size(size, chart)
    return key if c.name == DEFAULT_CHART else f"{c.name}:{key}"


def size_of(size: str, chart: Optional[str] = None) -> str:
    """:func:`check_size` of ``size`` where ``chart`` names the chart of a bare size only: ``"L"``
    is ``chart``'s L, ``"men:L"`` stays of its own chart (a design's chart, a ``--chart`` option,
    the add-on's chart selector: defaults that a qualified name overrides)."""
    return check_size(size, None if ":" in str(size) else chart)


def size_targets(size: str, chart: Optional[str] = None) -> Dict[str, float]:
    """The chart's target measurements (cm) of ``size``."""
    c, key = split_size(size, chart)
    return dict(c.sizes[key])


def chart_fit(body, size: str, chart: Optional[str] = None, progress: Optional[Progress] = None) -> FitResult:
    """Fit ``body`` to a chart size as the chart says: from its start phenotype (the
    gender), moving its parameters within its bounds, where the model has them.

    A fit that misses a target is made again from each of the chart's ``restarts`` in
    turn (the start phenotype kept) until one lands; then, where the chart has ``assist``
    parameters, the same again with them moving too. The first fit that lands is
    returned, else the one with the smallest largest miss.
    """
    c, key = split_size(size, chart)
    params = body.shape_parameters()
    names = [n for n in c.parameters if n in params]
    helpers = [n for n in c.assist if n in params and n not in names]
    start = {k: v for k, v in c.start.items() if k in params}
    local = [n for n in c.local if n in local_parameters(body)]
    stages = [names] + ([names + helpers] if helpers else []) + ([names + helpers + local] if local else [])
    attempts = []
    for moving in stages:
        for extra in ({},) + tuple(c.restarts):
            moved = {k: v for k, v in extra.items() if k in moving}
            if extra and not moved:
                continue  # a restart of parameters this model does not have
            attempts.append((moving, moved))
    best, best_miss = None, np.inf
    for i, (moving, moved) in enumerate(attempts):
        # Each attempt owns a slice of one bar, so a size that needs restarts shows one
        # rising bar ("fit 3 of 18") instead of a bar that falls back to 0 per restart.
        step = sub(progress, i / len(attempts), (i + 1) / len(attempts))
        labelled = (
            None
            if step is None
            else (lambda f, m, i=i, step=step: step(f, f"{m} (fit {i + 1} of {len(attempts)} for {size})"))
        )
        fit = fit_measurements(
            body,
            c.sizes[key],
            progress=labelled,
            start={**start, **moved} or None,
            parameters=moving if len(moving) >= 2 else None,
            bounds={k: v for k, v in c.bounds.items() if k in params},
        )
        if fit.ok:
            report(progress, 1.0, f"fit of {size} done")
            return fit
        miss = max(abs(fit.achieved[k] - v) for k, v in fit.targets.items())
        if miss < best_miss:
            best, best_miss = fit, miss
    report(progress, 1.0, f"fit of {size} done (closest of {len(attempts)})")
    return best


# The local changes a chart fit moves besides those of the girths the chart gives: the thighs' girth,
# so that a plus size's thighs are kept apart (fit_tape's thigh penalty) by slimmer thighs rather
# than by a narrower hip; and the underbust girth, so that a plus size's bust may come from a wider
# ribcage rather than a larger cup (the assist). The cup drives the side seams of the tops: on
# women:4XL at Anny's cup 0.75 (its bust local at +1) they sewed 3.4-6.4 mm apart, on the same body
# at cup 0.5 1.0-1.1 mm; the 4XL refitted with the underbust at cup 0.5: 0.4-1.7 mm.
CHART_EXTRA_LOCAL = ("measure-thigh-circ-incr", "measure-underbust-circ-incr")

# The gap (cm) a chart fit keeps between the inner thighs (fit_tape's ``gap``): thighs 2 mm apart
# leave a crease under the crotch the pants' back panels collapse in (women:3XL at 0.18 cm: 24 and
# 78 collapsed triangles; refitted 0.6-1.0 cm apart the pants, shorts and teaser solve). A fit with
# its thighs apart at all has landed, so a stored fit refitted from itself stays as it is.
CHART_THIGH_GAP_CM = 0.7


def chart_tape_fit(
    body,
    size: str,
    chart: Optional[str] = None,
    progress: Optional[Progress] = None,
    start: Optional[Mapping[str, float]] = None,
):
    """Fit ``body`` (Anny) to a chart size measured as a tailor measures (:mod:`core.body.tape`,
    ISO 8559-1: the bust at the bust points, the natural waist, the hip at the buttocks), by
    :func:`core.body.made_to_measure.fit_tape`: the chart's gender held, its parameters moving
    (adult ages; its ``assist`` too where they miss), with the local change of each girth the chart gives and
    :data:`CHART_EXTRA_LOCAL`, pulled towards the population; the thighs kept apart
    (:data:`CHART_THIGH_GAP_CM`).

    ``start`` defaults to the stored fit of the size (else the chart's start phenotype). Returns
    the :class:`~core.body.made_to_measure.TapeFit` (its ``ok``: every target within 1 cm, no
    self-intersection); these fits are the chart's stored ``fitted`` shapes for Anny.
    """
    from .made_to_measure import fit_tape

    c, key = split_size(size, chart)
    own = body.shape_parameters()
    targets = {**c.sizes[key], **{k: v for k, v in c.start.items() if k == "gender"}}
    params = [n for n in c.parameters if n in own]
    extra = [n for n in CHART_EXTRA_LOCAL if n in local_parameters(body)]
    helpers = [n for n in c.assist if n in own and n not in params]
    if start is None:
        start = c.fitted.get(getattr(body, "name", ""), {}).get(key, c.start)
    # The assist parameters (the women's cup) move only where the fit without them misses, so the
    # chart's bodies differ by the girths it gives (the four-dart blouse's darts follow the cup).
    gap = CHART_THIGH_GAP_CM
    fit = fit_tape(body, targets, progress=progress, start=start, parameters=params + extra, gap=gap)
    if fit.ok or not helpers:
        return fit
    return fit_tape(body, targets, progress=progress, start=fit.shape, parameters=params + helpers + extra, gap=gap)


def size_shape(body, size: str, progress: Optional[Progress] = None, chart: Optional[str] = None) -> Dict[str, float]:
    """Shape dict of chart size ``size`` (``"M"``, or ``"women:M"``; ``chart`` names the
    chart of an unqualified name, default the default chart) for ``body``.

    Anny's sizes are stored (each chart's ``fitted``, :data:`FITTED_SHAPES` for the
    default chart); other models are fitted to the chart once per process.
    """
    c, key = split_size(size, chart)
    params = body.shape_parameters()
    stored = c.fitted.get(getattr(body, "name", ""), {}).get(key)
    if stored is not None and all(k in params or k in local_parameters(body) for k in stored):
        shape = dict(body.default_shape())
        shape.update(stored)
        return shape
    _check_girth_landmarks(body, f"{c.name}:{key}")
    cache_key = (getattr(body, "name", ""), body.n_vertices, c.name, key)
    if cache_key not in _CACHE:
        _CACHE[cache_key] = chart_fit(body, key, c.name, progress=progress).shape
    return dict(_CACHE[cache_key])


def _check_girth_landmarks(body, size: str) -> None:
    """A size is fitted by its girths: say so when the model lacks the landmarks they are taken at
    (an OBJ template without a landmark file) instead of failing inside the measurement."""
    from .measure import GIRTH_LANDMARKS

    have = getattr(body, "landmarks", None) or {}
    missing = sorted({n for names in GIRTH_LANDMARKS.values() for n in names} - set(have))
    if missing:
        raise BodyError(
            f"size {size}: body {getattr(body, 'name', '?')!r} has no {', '.join(missing)} landmarks, "
            "which a chart size is fitted by; give the model's landmark file (a design's "
            "body.landmarks, --landmarks) or a shape of its own parameters instead of a size"
        )


def parse_assignments(text: str, what: str) -> Dict[str, float]:
    """``"a=1,b=2.5"`` -> ``{"a": 1.0, "b": 2.5}``; a clear error naming ``what`` otherwise."""
    out = {}
    for item in str(text).split(","):
        item = item.strip()
        if not item:
            continue
        if "=" not in item:
            raise BodyError(f"{what}: expected name=value pairs separated by commas, got {item!r}")
        k, v = (x.strip() for x in item.split("=", 1))
        if not k:
            raise BodyError(f"{what}: a name is missing before '=' in {item!r}")
        if k in out:
            raise BodyError(f"{what}: {k!r} is given twice; give each name once")
        try:
            out[k] = float(v)
        except ValueError:
            raise BodyError(f"{what}: value of {k!r} must be a number, got {v!r}") from None
        if not np.isfinite(out[k]):
            raise BodyError(f"{what}: value of {k!r} must be a finite number, got {v!r}")
    if not out:
        raise BodyError(f"{what}: no name=value pairs given")
    return out
