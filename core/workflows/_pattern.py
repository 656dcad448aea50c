"""The pattern stage: the reference pattern, transfer to other bodies, adaptation to poses, and their
files and figures."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Dict, Mapping, Optional, Sequence, Tuple

from ..choices import SOLVER_CONFIGS
from ..progress import Progress, report, sub
from ._prepare import Prepared, size_name

#: Solver configurations a user (``--config``) or a design (``"solver"``) can name; see :mod:`core.pattern`.
CONFIGS = SOLVER_CONFIGS
#: The configuration of a design that names none, when the user names none either.
DEFAULT_CONFIG = "improved"


@dataclass
class PatternRun:
    """A solved pattern and what a user reads of it.

    Attributes
    ----------
    pattern : core.pattern.Pattern; ``pattern.report`` holds the mode's records
        (``config``, ``transfer_deviation``, ``residual_stretch`` ...) and
        ``metrics`` (:func:`core.metrics.pattern.pattern_report`).
    figures : dict, label -> value: the key figures of this run, rounded for
        display (CLI summary, add-on panel).
    timings : dict, wall seconds (``optimize`` plus the preparation's).
    """

    pattern: object
    figures: Dict[str, object] = field(default_factory=dict)
    timings: Dict[str, float] = field(default_factory=dict)


def config_name(design, config: Optional[str] = None) -> str:
    """The solver configuration a run of ``design`` uses: ``config`` when the caller names one (the
    user's explicit choice), else the design's ``solver``, else :data:`DEFAULT_CONFIG`.

    Parameters
    ----------
    design : :class:`Prepared`, core.design.Design or a design dict (JSON)
    config : one of :data:`CONFIGS`, or None
    """
    if config is not None:
        return config
    design = getattr(design, "design", design)
    own = design.get("solver") if isinstance(design, Mapping) else getattr(design, "solver", None)
    return own or DEFAULT_CONFIG


def solver_config(name: str = DEFAULT_CONFIG, iterations: Optional[int] = None, gather_all: bool = False):
    """The solver configuration ``name`` with the user's overrides.

    Parameters
    ----------
    name : one of :data:`CONFIGS`
    iterations : local-global iterations, None for the configuration's
    gather_all : every seam gathered (the seam-length term off everywhere:
        the paper's switch for gathered designs)
    """
    from ..pattern.solve import SolverConfig

    overrides = {}
    if iterations is not None:
        overrides["iterations"] = iterations
    if gather_all:
        overrides["gathered"] = ("*",)
    return SolverConfig.named(name, **overrides)


def make_solver(
    prep: Prepared,
    config: Optional[str] = None,
    iterations: Optional[int] = None,
    gather_all: bool = False,
    progress: Optional[Progress] = None,
):
    """The pattern solver of ``prep``: one flattening and factorisation, shared by
    :func:`reference`, :func:`transfer` and :func:`adapt` (and by every body of a batch).
    ``config``: the configuration's name, None for the design's (:func:`config_name`)."""
    from ..pattern.solve import PatternSolver

    return PatternSolver(
        prep.cut, prep.reference, solver_config(config_name(prep, config), iterations, gather_all), progress=progress
    )


def _checked_metrics(pattern, checks: Optional[Sequence[str]] = None, vertices=None) -> dict:
    """The metrics of ``pattern`` (:func:`core.metrics.pattern.pattern_report`, with the region
    report and the collapse sites on the pattern's body landmarks); a pattern failing one of
    ``checks`` (default :func:`core.metrics.checks.checks_for` the pattern: flipped and collapsed;
    a live preview still converging only flipped) is an error naming the panel and where on the
    body, not a figure. ``vertices``: the pattern's body instance when the caller has it."""
    from ..metrics.checks import check_pattern, checks_for
    from ..metrics.pattern import pattern_report
    from ..metrics.regions import body_landmarks

    metrics = pattern_report(pattern, body_landmarks(pattern, vertices=vertices))
    check_pattern(metrics, checks_for(pattern) if checks is None else checks)
    return metrics


def measure_pattern(pattern, checks: Optional[Sequence[str]] = None) -> dict:
    """Measure ``pattern`` into its report (``report["metrics"]``) and return the metrics;
    a pattern failing one of ``checks`` (see :func:`_checked_metrics`) is an error, not a figure."""
    pattern.report["metrics"] = metrics = _checked_metrics(pattern, checks)
    return metrics


def _attach_pleats(pattern, prep) -> None:
    """The design's pleats placed on the pattern solved closed, measured opened (``report["pleats"]``,
    :func:`core.pattern.pleats.attach_pleats`)."""
    from ..pattern.pleats import attach_pleats

    attach_pleats(pattern, prep)


def pattern_figures(pattern) -> Dict[str, object]:
    """The key figures of a measured pattern (label -> rounded value), for the CLI and the add-on:
    weft compliance with the warp deviation and shear beside it, flipped and collapsed counts
    (:func:`core.metrics.figures.key_figures`)."""
    from ..metrics.figures import key_figures

    return key_figures(pattern)


def _solve_reference(prep, solver, progress):
    from ..pattern.solve import solve_pattern

    return solve_pattern(prep.cut, prep.reference, solver=solver, style=prep.design.name, progress=progress)


def reference(
    prep: Prepared,
    config: Optional[str] = None,
    iterations: Optional[int] = None,
    gather_all: bool = False,
    solver=None,
    progress: Optional[Progress] = None,
) -> PatternRun:
    """The design's pattern on its own (reference) body.

    Parameters
    ----------
    prep : :class:`Prepared`
    config, iterations, gather_all : see :func:`solver_config`; ``config`` None: the design's
        (:func:`config_name`). Ignored when ``solver`` is given, except ``config`` as the name
        recorded in the report.
    solver : PatternSolver of ``prep`` to reuse, or None
    """
    config = config_name(prep, config)
    t0 = time.perf_counter()
    if solver is None:
        solver = make_solver(prep, config, iterations, gather_all, progress=sub(progress, 0.0, 0.2))
    pattern = _solve_reference(prep, solver, sub(progress, 0.2, 1.0))
    optimize = time.perf_counter() - t0
    pattern.report["config"] = config
    measure_pattern(pattern)
    _attach_pleats(pattern, prep)
    return PatternRun(pattern, pattern_figures(pattern), {**prep.timings, "optimize": optimize})


def transfer(
    prep: Prepared,
    size,
    config: Optional[str] = None,
    iterations: Optional[int] = None,
    gather_all: bool = False,
    solver=None,
    start=None,
    progress: Optional[Progress] = None,
    vertices=None,
    transfer_solver: Optional[str] = None,
) -> PatternRun:
    """Shape transfer (paper Eq. transfer-scale): the same cut and ease field on another body shape.

    Parameters
    ----------
    size : str or mapping
        A chart size name (fitted on the model): ``"M"`` of the design's chart
        (``body.chart``, default the default chart) or ``"women:M"``; or a shape
        dict of the model's parameters (a measured or sampled body).

    The reference pattern is solved first (or ``start`` is taken as it) and
    seeds the transfer solve; the report records the transfer deviation (the
    ease compliance on the target body) beside the reference's own compliance.
    ``vertices``: the target body's instance in the cut's pose when the caller
    has made it (a batch item measured it), so it is not evaluated again.
    ``transfer_solver``: ``"reference"``, ``"target"`` or ``"cup"``, the body the transfer's flattening and
    factorisation are made on (:attr:`core.pattern.config.Convergence.transfer_solver`); None: the
    design's own ``transfer_solver``, else the configuration's (``"reference"``).

    The design's own size (the chart size its body is, ``body.shape``) is the
    reference pattern itself, not a re-solve on the same body: one size, one
    pattern, whichever door (``ease pattern``, ``ease transfer``, a graded
    nest, a batch item) it comes through.
    """
    import copy

    from ..body.instance import body_instance, instance_shape
    from ..metrics.pattern import ease_compliance
    from ..pattern.solve import transfer_pattern

    config = config_name(prep, config)
    if isinstance(size, str):
        size = size_name(prep, size)
    elif not isinstance(size, Mapping):
        from ..errors import PatternError

        raise PatternError(f"transfer: expected a size name or a shape dict, got {type(size).__name__}")
    t0 = time.perf_counter()
    if solver is None:
        solver = make_solver(prep, config, iterations, gather_all, progress=sub(progress, 0.0, 0.15))
    if transfer_solver is None:  # the design's own choice, where it makes one
        transfer_solver = getattr(getattr(prep, "design", None), "transfer_solver", None)
    chosen = None if transfer_solver is None else with_transfer_solver(solver.config, transfer_solver)
    ref_pat = start if start is not None else _solve_reference(prep, solver, sub(progress, 0.15, 0.5))
    pose = prep.cut.body.get("pose")
    shape = instance_shape(prep.body, size)
    body = {
        "model": prep.cut.body.get("model", prep.body.name),
        "shape": shape,
        "pose": pose,
        **({"size": size} if isinstance(size, str) else {}),
    }
    if is_own_size(prep, size):
        pattern = copy.deepcopy(ref_pat)
        pattern.body, pattern.mode = body, "transfer"
        report(progress, 1.0, f"{size} is the design's own size: its reference pattern")
        target = prep.reference if vertices is None else vertices
    else:
        target = vertices if vertices is not None else body_instance(prep.body, shape, pose)
        pattern = transfer_pattern(
            prep.cut,
            prep.reference,
            target,
            config=chosen,
            solver=solver,
            start=ref_pat,
            style=prep.design.name,
            body=body,
            progress=sub(progress, 0.5, 1.0),
        )
    optimize = time.perf_counter() - t0
    metrics = _checked_metrics(pattern, vertices=target)
    dev = metrics["compliance"]  # the transfer deviation is the compliance on the target
    refc = (ref_pat.report.get("metrics") or {}).get("compliance") or ease_compliance(ref_pat)
    label = size if isinstance(size, str) else "custom"
    pattern.report.update({"config": config, "size": label, "transfer_deviation": dev, "reference_compliance": refc})
    # the body the transfer's solver was made on (config.Convergence.transfer_solver)
    pattern.report["transfer_solver"] = (chosen or solver.config).convergence.transfer_solver
    pattern.report["metrics"] = metrics
    _attach_pleats(pattern, prep)
    figures = {
        "size": label,
        **pattern_figures(pattern),
        "transfer deviation mean %": round(float(dev["mean"]), 3),
        "transfer deviation std %": round(float(dev["std"]), 3),
        "reference compliance mean %": round(float(refc["mean"]), 3),
    }
    return PatternRun(pattern, figures, {**prep.timings, "optimize": optimize})


def with_transfer_solver(config, transfer_solver: str):
    """``config`` (a SolverConfig) with its transfers solved on ``transfer_solver``'s body (one of
    :data:`core.choices.TRANSFER_SOLVERS`, :attr:`core.pattern.config.Convergence.transfer_solver`), checked."""
    import dataclasses

    cfg = dataclasses.replace(
        config, convergence=dataclasses.replace(config.convergence, transfer_solver=transfer_solver)
    )
    cfg.check()
    return cfg


def is_own_size(prep: Prepared, size) -> bool:
    """Whether ``size`` (a name, canonical or bare) is the chart size the design's body is (``body.shape``)."""
    own = prep.cut.body.get("shape")
    return isinstance(size, str) and isinstance(own, str) and size_name(prep, size) == size_name(prep, own)


def tolerances(
    prep: Prepared, eps_weft: Optional[float] = None, eps_warp: Optional[float] = None
) -> Tuple[float, float]:
    """(eps_weft, eps_warp): the caller's, else the design's materials, else the default.

    A caller's weft tolerance also stands for the warp unless a warp tolerance
    is given (one ``--tolerance`` means "this much stretch either way").
    """
    from ..pattern.config import tolerances as resolve

    return resolve(prep.cut.materials, eps_weft, eps_warp)


def adapt(
    prep: Prepared,
    poses: Sequence,
    eps_weft: Optional[float] = None,
    eps_warp: Optional[float] = None,
    config: Optional[str] = None,
    iterations: Optional[int] = None,
    gather_all: bool = False,
    solver=None,
    start=None,
    progress: Optional[Progress] = None,
) -> PatternRun:
    """Pose adaptation (paper Eqs. adapt-scale, material-scale): the pattern grows
    where a target pose needs more fabric than the stretch tolerance allows.

    Parameters
    ----------
    poses : pose preset names (``"P1"`` ...) or JSON poses, on the reference shape
    eps_weft, eps_warp : stretch tolerances >= 1 (see :func:`tolerances`)

    The report records, per pose and garment, the residual stretch (percent
    of area stretched beyond the tolerance) before and after adaptation.
    """
    from ..body.instance import body_instance
    from ..metrics.pattern import residual_stretch
    from ..pattern.solve import adapt_pattern

    config = config_name(prep, config)
    eps_w, eps_g = tolerances(prep, eps_weft, eps_warp)
    names = [p if isinstance(p, str) else f"pose{i + 1}" for i, p in enumerate(poses)]
    t0 = time.perf_counter()
    shape = prep.cut.body.get("shape")
    pose_vertices = [body_instance(prep.body, shape, p) for p in poses]
    if solver is None:
        solver = make_solver(prep, config, iterations, gather_all, progress=sub(progress, 0.0, 0.15))
    ref_pat = start if start is not None else _solve_reference(prep, solver, sub(progress, 0.15, 0.5))
    pattern = adapt_pattern(
        prep.cut,
        prep.reference,
        pose_vertices,
        eps_weft=eps_w,
        eps_warp=eps_g,
        solver=solver,
        start=ref_pat,
        style=prep.design.name,
        progress=sub(progress, 0.5, 1.0),
    )
    optimize = time.perf_counter() - t0
    stretch: Dict[str, dict] = {}
    figures: Dict[str, object] = {"tolerance": round(eps_w, 4), "tolerance warp": round(eps_g, 4)}
    for name, P in zip(names, pose_vertices):
        X = prep.cut.positions(P)
        xyz = {p.name: X[p.vertex_ids] for p in prep.cut.panels}
        stretch[name] = {}
        for g in sorted(prep.cut.garments) or [None]:
            before = residual_stretch(ref_pat, xyz, eps_w, g)
            after = residual_stretch(pattern, xyz, eps_w, g)
            stretch[name][g or "all"] = {"before": before, "after": after}
            figures[f"{name} {g or 'all'} stretched % before/after"] = f"{before:.1f} / {after:.1f}"
    pattern.report.update(
        {"config": config, "poses": names, "eps_weft": eps_w, "eps_warp": eps_g, "residual_stretch": stretch}
    )
    measure_pattern(pattern)
    _attach_pleats(pattern, prep)
    figures.update(pattern_figures(pattern))
    return PatternRun(pattern, figures, {**prep.timings, "optimize": optimize})


def write_pattern(out, run: PatternRun, preview: bool = True) -> None:
    """``pattern.json``, ``report.json`` (records, metrics, timings) and ``pattern.png``
    (unless ``preview`` is false) into ``out``, atomically."""
    from ..fileio import output_dir, write_json
    from ..pattern.io import save_pattern
    from ..pattern.plot import render_png

    pattern = run.pattern
    pattern.report["timings"] = dict(run.timings)
    with output_dir(out) as tmp:
        save_pattern(pattern, tmp)
        write_json(tmp / "report.json", pattern.report)
        if preview:
            render_png(pattern, tmp / "pattern.png")


def summary(run: PatternRun) -> str:
    """The one-line summary the CLI prints after a pattern run (:func:`core.metrics.figures.summary_line`)."""
    from ..metrics.figures import summary_line

    return summary_line(run.pattern, run.timings.get("optimize", 0.0))
