"""The pipeline, once: prepare → reference → transfer / adapt → drape → export → marker.

The CLI (:mod:`core.cli`), the add-on (``ease_addon``), the benchmarks, batch
runs and the demo call these functions and nothing below them to run a
stage, so a design gives the same pattern, figures and files whichever door
it comes through. Each function returns its result together with the figures
a user reads (the report records and a flat ``figures`` dict); writing files
is separate (:func:`write_pattern`, :func:`write_drape`, :func:`export`).

Settings follow one precedence rule: the caller's value, else the design's
(its ``materials``), else the default (:class:`core.design.materials.Materials`).
The solver configuration too (:func:`config_name`): the caller's ``config``
(``--config`` given, the add-on's Solver set to a configuration), else the
design's ``"solver"``, else ``"improved"``; ``iterations`` and ``gather_all``
override that configuration's settings.

Progress: every function takes ``progress(fraction, message)`` for its own
span 0..1 (compose spans with :func:`core.progress.sub`); the callback may
raise :class:`core.errors.Cancelled` to stop.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from .design.checks import SOLVER_CONFIGS
from .progress import Progress, report, sub

#: Solver configurations a user (``--config``) or a design (``"solver"``) can name; see :mod:`core.pattern`.
CONFIGS = SOLVER_CONFIGS
#: The configuration of a design that names none, when the user names none either.
DEFAULT_CONFIG = "improved"


# ----------------------------------------------------------------------------- prepare

@dataclass
class Prepared:
    """A design cut on its body, ready for pattern solves.

    Attributes
    ----------
    design : core.design.Design
    body : BodyModel, the model the cut was made on.
    cut : core.cut.types.GarmentCut
    reference : (V, 3) float64, metres: the body instance the cut was made on
        (its ``cut.body`` record: shape and pose).
    timings : dict, wall seconds of ``load`` and ``cut`` (0 for what was given).
    """
    design: object
    body: object
    cut: object
    reference: np.ndarray
    timings: Dict[str, float] = field(default_factory=dict)


def prepare(design, body=None, cut=None, progress: Optional[Progress] = None) -> Prepared:
    """Load a design and its body and cut it (or adopt a cut already made).

    Parameters
    ----------
    design : path, JSON text, dict or core.design.Design
    body : BodyModel or None
        None loads the design's ``body.model`` (``"anny"`` by default).
    cut : GarmentCut or None
        A cut of this design made earlier (the add-on keeps one); None cuts now.
    progress : callback, optional
    """
    from .body.instance import spec_instance
    from .body.registry import load_spec
    from .design import load_design

    t0 = time.perf_counter()
    design = load_design(design)      # an OBJ template's files made absolute against the design file
    if body is None:
        body = load_spec(design.body)
    t1 = time.perf_counter()
    if cut is None:
        from .cut import cut_design
        cut = cut_design(design, body=body, progress=sub(progress, 0.0, 0.95))
    t2 = time.perf_counter()
    reference, _ = spec_instance(cut.body, model=body)
    report(progress, 1.0, f"cut {len(cut.panels)} panels")
    return Prepared(design, body, cut, reference, {"load": t1 - t0, "cut": t2 - t1})


def size_name(prep: Prepared, size: str) -> str:
    """The canonical chart size of ``size`` for ``prep``: a bare name (``"M"``) is of the
    design's chart (``body.chart``), a qualified one (``"women:M"``) of its own."""
    from .body.sizes import size_of
    return size_of(str(size), prep.design.body.get("chart"))


# ----------------------------------------------------------------------------- pattern

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
    from .pattern.solve import SolverConfig
    overrides = {}
    if iterations is not None:
        overrides["iterations"] = iterations
    if gather_all:
        overrides["gathered"] = ("*",)
    return SolverConfig.named(name, **overrides)


def make_solver(prep: Prepared, config: Optional[str] = None, iterations: Optional[int] = None,
                gather_all: bool = False, progress: Optional[Progress] = None):
    """The pattern solver of ``prep``: one flattening and factorisation, shared by
    :func:`reference`, :func:`transfer` and :func:`adapt` (and by every body of a batch).
    ``config``: the configuration's name, None for the design's (:func:`config_name`)."""
    from .pattern.solve import PatternSolver
    return PatternSolver(prep.cut, prep.reference,
                         solver_config(config_name(prep, config), iterations, gather_all), progress=progress)


def _checked_metrics(pattern, checks: Optional[Sequence[str]] = None, vertices=None) -> dict:
    """The metrics of ``pattern`` (:func:`core.metrics.pattern.pattern_report`, with the region
    report and the collapse sites on the pattern's body landmarks); a pattern failing one of
    ``checks`` (default :func:`core.metrics.checks.checks_for` the pattern: flipped and collapsed;
    a live preview still converging only flipped) is an error naming the panel and where on the
    body, not a figure. ``vertices``: the pattern's body instance when the caller has it."""
    from .metrics.checks import check_pattern, checks_for
    from .metrics.pattern import pattern_report
    from .metrics.regions import body_landmarks
    metrics = pattern_report(pattern, body_landmarks(pattern, vertices=vertices))
    check_pattern(metrics, checks_for(pattern) if checks is None else checks)
    return metrics


def measure_pattern(pattern, checks: Optional[Sequence[str]] = None) -> dict:
    """Measure ``pattern`` into its report (``report["metrics"]``) and return the metrics;
    a pattern failing one of ``checks`` (see :func:`_checked_metrics`) is an error, not a figure."""
    pattern.report["metrics"] = metrics = _checked_metrics(pattern, checks)
    return metrics


def pattern_figures(pattern) -> Dict[str, object]:
    """The key figures of a measured pattern (label -> rounded value), for the CLI and the add-on:
    weft compliance with the warp deviation and shear beside it, flipped and collapsed counts
    (:func:`core.metrics.figures.key_figures`)."""
    from .metrics.figures import key_figures
    return key_figures(pattern)


def _solve_reference(prep, solver, progress):
    from .pattern.solve import solve_pattern
    return solve_pattern(prep.cut, prep.reference, solver=solver, style=prep.design.name, progress=progress)


def reference(prep: Prepared, config: Optional[str] = None, iterations: Optional[int] = None,
              gather_all: bool = False, solver=None, progress: Optional[Progress] = None) -> PatternRun:
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
    return PatternRun(pattern, pattern_figures(pattern), {**prep.timings, "optimize": optimize})


def transfer(prep: Prepared, size, config: Optional[str] = None, iterations: Optional[int] = None,
             gather_all: bool = False, solver=None, start=None, progress: Optional[Progress] = None,
             vertices=None) -> PatternRun:
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

    The design's own size (the chart size its body is, ``body.shape``) is the
    reference pattern itself, not a re-solve on the same body: one size, one
    pattern, whichever door (``ease pattern``, ``ease transfer``, a graded
    nest, a batch item) it comes through.
    """
    import copy

    from .body.instance import body_instance, instance_shape
    from .metrics.pattern import ease_compliance
    from .pattern.solve import transfer_pattern

    config = config_name(prep, config)
    if isinstance(size, str):
        size = size_name(prep, size)
    elif not isinstance(size, Mapping):
        from .errors import PatternError
        raise PatternError(f"transfer: expected a size name or a shape dict, got {type(size).__name__}")
    t0 = time.perf_counter()
    if solver is None:
        solver = make_solver(prep, config, iterations, gather_all, progress=sub(progress, 0.0, 0.15))
    ref_pat = start if start is not None else _solve_reference(prep, solver, sub(progress, 0.15, 0.5))
    pose = prep.cut.body.get("pose")
    shape = instance_shape(prep.body, size)
    body = {"model": prep.cut.body.get("model", prep.body.name), "shape": shape, "pose": pose,
            **({"size": size} if isinstance(size, str) else {})}
    if is_own_size(prep, size):
        pattern = copy.deepcopy(ref_pat)
        pattern.body, pattern.mode = body, "transfer"
        report(progress, 1.0, f"{size} is the design's own size: its reference pattern")
        target = prep.reference if vertices is None else vertices
    else:
        target = vertices if vertices is not None else body_instance(prep.body, shape, pose)
        pattern = transfer_pattern(prep.cut, prep.reference, target, solver=solver, start=ref_pat,
                                   style=prep.design.name, body=body, progress=sub(progress, 0.5, 1.0))
    optimize = time.perf_counter() - t0
    metrics = _checked_metrics(pattern, vertices=target)
    dev = metrics["compliance"]                       # the transfer deviation is the compliance on the target
    refc = (ref_pat.report.get("metrics") or {}).get("compliance") or ease_compliance(ref_pat)
    label = size if isinstance(size, str) else "custom"
    pattern.report.update({"config": config, "size": label, "transfer_deviation": dev,
                           "reference_compliance": refc})
    pattern.report["metrics"] = metrics
    figures = {"size": label, **pattern_figures(pattern),
               "transfer deviation mean %": round(float(dev["mean"]), 3),
               "transfer deviation std %": round(float(dev["std"]), 3),
               "reference compliance mean %": round(float(refc["mean"]), 3)}
    return PatternRun(pattern, figures, {**prep.timings, "optimize": optimize})


def is_own_size(prep: Prepared, size) -> bool:
    """Whether ``size`` (a name, canonical or bare) is the chart size the design's body is (``body.shape``)."""
    own = prep.cut.body.get("shape")
    return isinstance(size, str) and isinstance(own, str) and size_name(prep, size) == size_name(prep, own)


def tolerances(prep: Prepared, eps_weft: Optional[float] = None,
               eps_warp: Optional[float] = None) -> Tuple[float, float]:
    """(eps_weft, eps_warp): the caller's, else the design's materials, else the default.

    A caller's weft tolerance also stands for the warp unless a warp tolerance
    is given (one ``--tolerance`` means "this much stretch either way").
    """
    from .pattern.config import tolerances as resolve
    return resolve(prep.cut.materials, eps_weft, eps_warp)


def adapt(prep: Prepared, poses: Sequence, eps_weft: Optional[float] = None, eps_warp: Optional[float] = None,
          config: Optional[str] = None, iterations: Optional[int] = None, gather_all: bool = False, solver=None,
          start=None, progress: Optional[Progress] = None) -> PatternRun:
    """Pose adaptation (paper Eqs. adapt-scale, material-scale): the pattern grows
    where a target pose needs more fabric than the stretch tolerance allows.

    Parameters
    ----------
    poses : pose preset names (``"P1"`` ...) or JSON poses, on the reference shape
    eps_weft, eps_warp : stretch tolerances >= 1 (see :func:`tolerances`)

    The report records, per pose and garment, the residual stretch (percent
    of area stretched beyond the tolerance) before and after adaptation.
    """
    from .body.instance import body_instance
    from .metrics.pattern import residual_stretch
    from .pattern.solve import adapt_pattern

    config = config_name(prep, config)
    eps_w, eps_g = tolerances(prep, eps_weft, eps_warp)
    names = [p if isinstance(p, str) else f"pose{i + 1}" for i, p in enumerate(poses)]
    t0 = time.perf_counter()
    shape = prep.cut.body.get("shape")
    pose_vertices = [body_instance(prep.body, shape, p) for p in poses]
    if solver is None:
        solver = make_solver(prep, config, iterations, gather_all, progress=sub(progress, 0.0, 0.15))
    ref_pat = start if start is not None else _solve_reference(prep, solver, sub(progress, 0.15, 0.5))
    pattern = adapt_pattern(prep.cut, prep.reference, pose_vertices, eps_weft=eps_w, eps_warp=eps_g,
                            solver=solver, start=ref_pat, style=prep.design.name, progress=sub(progress, 0.5, 1.0))
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
    pattern.report.update({"config": config, "poses": names, "eps_weft": eps_w, "eps_warp": eps_g,
                           "residual_stretch": stretch})
    measure_pattern(pattern)
    figures.update(pattern_figures(pattern))
    return PatternRun(pattern, figures, {**prep.timings, "optimize": optimize})


def write_pattern(out, run: PatternRun, preview: bool = True) -> None:
    """``pattern.json``, ``report.json`` (records, metrics, timings) and ``pattern.png``
    (unless ``preview`` is false) into ``out``, atomically."""
    from .fileio import output_dir, write_json
    from .pattern.io import save_pattern
    from .pattern.plot import render_png

    pattern = run.pattern
    pattern.report["timings"] = dict(run.timings)
    with output_dir(out) as tmp:
        save_pattern(pattern, tmp)
        write_json(tmp / "report.json", pattern.report)
        if preview:
            render_png(pattern, tmp / "pattern.png")


def summary(run: PatternRun) -> str:
    """The one-line summary the CLI prints after a pattern run (:func:`core.metrics.figures.summary_line`)."""
    from .metrics.figures import summary_line
    return summary_line(run.pattern, run.timings.get("optimize", 0.0))


# ----------------------------------------------------------------------------- drape

@dataclass
class DrapeRun:
    """A drape and its fit measurements.

    Attributes
    ----------
    result : core.drape.DrapeResult
    metrics : dict, :func:`core.metrics.drape.drape_metrics` (per-vertex
        arrays included: ``vertex_gap`` ...)
    body_vertices : (V, 3) float64 m, body_faces : (F, 3) int64: the body draped on.
    figures : dict, label -> value for display.
    """
    result: object
    metrics: dict
    body_vertices: np.ndarray
    body_faces: np.ndarray
    figures: Dict[str, object] = field(default_factory=dict)


def drape(pattern, material=None, options=None, body: Optional[Tuple[np.ndarray, np.ndarray]] = None,
          progress: Optional[Progress] = None) -> DrapeRun:
    """Drape ``pattern`` with the project's XPBD (Warp) and measure the fit.

    Parameters
    ----------
    pattern : core.pattern.Pattern
    material : fabric preset name, Material, mapping or None (the design's, else cotton)
    options : DrapeOptions or mapping (frames, substeps, device ...), see :class:`core.drape.DrapeOptions`
    body : (vertices (V, 3), faces (F, 3)) or None for the pattern's own body
        instance (its ``body`` record: model, size or shape, pose)
    """
    from .body.instance import spec_instance
    from .drape import drape as _drape
    from .metrics.drape import drape_metrics

    if body is None:
        body_v, body_f = spec_instance(pattern.body or {})
    else:
        body_v, body_f = np.asarray(body[0], dtype=np.float64), np.asarray(body[1], dtype=np.int64)
    result = _drape(pattern, body_v, body_f, material=material, options=options, progress=sub(progress, 0.0, 0.9))
    report(progress, 0.92, "drape: measuring the fit")
    metrics = drape_metrics(result, body_v, body_f, pattern=pattern)
    report(progress, 1.0, "drape: done")
    return DrapeRun(result, metrics, body_v, body_f, _drape_figures(result, metrics))


def _drape_figures(result, metrics) -> Dict[str, object]:
    out = {"frames": int(result.frames), "settled": result.settle_reason,
           "time s": round(float(result.timings.get("total", 0.0)), 2),
           "mean weft strain %": round(100 * float(np.mean(np.asarray(result.strain_weft)[result.used])), 2),
           "device": result.device}
    a = (metrics or {}).get("all") or {}
    if a:
        out["mean gap mm"] = round(float(a["gap_mm"]["mean"]), 1)
        out["penetration %"] = round(float(a["penetration_pct"]), 2)
        out["seam gap max mm"] = round(float(a["seam_gap_mm"]["max"]), 2)
    return out


def write_drape(out, run: DrapeRun, pattern=None, preview: bool = True):
    """Every drape file into ``out`` atomically (see :func:`core.drape.output.write_drape`); returns the folder."""
    from .drape.output import write_drape as _write
    from .metrics.drape import summary as fit_summary
    return _write(out, run.result, run.body_vertices, run.body_faces, fit=fit_summary(run.metrics),
                  vertex_gap=run.metrics["vertex_gap"], pattern=pattern, preview=preview)


def drape_summary(run: DrapeRun, pattern) -> str:
    """The one-line summary the CLI prints after a drape."""
    r, a = run.result, run.metrics["all"]
    return (f"drape {pattern.style}: {r.material['name']}, {r.frames} frames ({r.settle_reason}), "
            f"simulate {r.timings['simulate']:.1f} s; gap {a['gap_mm']['mean']:.1f} ± {a['gap_mm']['std']:.1f} mm, "
            f"penetration {a['penetration_pct']:.2f} %, seam gap max {a['seam_gap_mm']['max']:.2f} mm; "
            f"strain weft {a['strain_weft_pct']['mean']:.2f} % / warp {a['strain_warp_pct']['mean']:.2f} % (mean)")


# ----------------------------------------------------------------------------- export

def export_allowance(pattern, allowance: Optional[float] = None, hem: Optional[float] = None):
    """The seam/hem allowance table for an export: the design's (``materials.export.allowance``)
    with the caller's ``allowance`` (every seam) and ``hem`` over it; None when the caller sets
    neither (the exporter then reads the design's itself)."""
    if allowance is None and hem is None:
        return None
    from .design.materials import ALLOWANCE, HEM
    base = ((pattern.materials or {}).get("export") or {}).get("allowance")
    if isinstance(base, dict):
        table = dict(base)
    elif isinstance(base, (int, float)) and not isinstance(base, bool):
        table = {"default": float(base)}
    else:
        table = {"default": ALLOWANCE, "hem": HEM}
    if allowance is not None:
        table["default"] = allowance
    if hem is not None:
        table["hem"] = hem
    return table


def export(pattern, out, formats: Union[str, Sequence[str]] = ("svg", "dxf", "pdf"), allowance=None,
           hem: Optional[float] = None, notch_spacing: Optional[float] = None,
           drape: Optional[Tuple[np.ndarray, Optional[np.ndarray]]] = None, strict: bool = True,
           warnings: Optional[List[str]] = None, up: str = "y", with_body: bool = False,
           progress: Optional[Progress] = None, print_all: bool = False, origin: str = "floor") -> list:
    """Cutting-room files (SVG, DXF, PDF) and the draped garment (GLB, OBJ) into ``out``, atomically.

    Parameters
    ----------
    pattern : core.pattern.Pattern
    formats : comma-separated string or names (see :func:`core.export.parse_formats`)
    allowance : float (m, every seam) or a table ``{"default": m, "hem": m, seam name: m}``, or None
    hem : float, m: the hem allowance over the table
    notch_spacing : float, m between notches along a seam (None: the design's, else the default)
    drape : (positions (N, 3) by global vertex id, faces or None) for GLB/OBJ
    strict : refuse pieces whose sew line crosses itself (False: export with a warning)
    warnings : list to receive the warnings
    up : ``"y"`` (default, OBJ readers' convention) or ``"z"`` (the body OBJs' frame): the up axis of
        ``garment.obj`` (``garment.glb`` is Y-up, as glTF requires)
    origin : ``"floor"`` (default: the body's lowest point at height 0) or ``"root"`` (the body's root):
        the origin of ``garment.glb`` and ``garment.obj``
    with_body : also write the pattern's body instance beside the draped garment, in the same frame
    print_all : print every piece whole on the tiled PDFs (default: each mirrored pair once, labelled cut 2;
        symmetric pieces as halves on the fold)

    Returns
    -------
    list of the written paths.
    """
    from .export import export_pattern, parse_formats
    table = allowance if isinstance(allowance, dict) else export_allowance(pattern, allowance, hem)
    positions, faces = drape if drape is not None else (None, None)
    formats = parse_formats(formats)
    body = None
    if with_body and ("glb" in formats or "obj" in formats):
        from .body.instance import spec_instance
        body = spec_instance(pattern.body or {})      # the body the pattern was made on
    return export_pattern(pattern, out, formats=formats, allowance=table,
                          drape_positions=positions, drape_faces=faces, notch_spacing=notch_spacing,
                          strict=strict, warnings=warnings if warnings is not None else [], up=up, body=body,
                          progress=progress, print_all=print_all, origin=origin)


# ----------------------------------------------------------------------------- marker

def marker(runs: Sequence[Tuple[str, object, int]], width: float, allowance=None, hem: Optional[float] = None,
           notch_spacing: Optional[float] = None, seconds: int = 60, seed: int = 0, one_way: bool = False,
           tilt: float = 0.0, threads: int = 1, tries: Optional[int] = None, progress: Optional[Progress] = None,
           early_stop: bool = False):
    """A cutting-room marker: the pieces of ``runs`` nested on a fabric ``width`` m wide (:mod:`core.marker`).

    Parameters
    ----------
    runs : (size label, core.pattern.Pattern, garments) per size
    allowance, hem : as :func:`export`: the export's rule, one for every output (each pattern's table,
        :func:`export_allowance`, with ``allowance`` on every seam and ``hem`` over it; a table as such),
        so the marker nests the cut lines ``ease export`` draws
    notch_spacing, seconds, seed, one_way, tilt, threads, tries, early_stop : see :func:`core.marker.nest`;
        the numbers are checked before any work (:func:`core.marker.check_options`); ``tries`` None: as many
        nesters (seeds ``seed``, ``seed + 1``, ...) as the machine's cores hold ``threads`` each, in the same
        wall time

    Returns
    -------
    core.marker.Marker
    """
    from .marker import check_options, default_tries, marker_items, nest
    if tries is None:
        tries = default_tries(threads)
    check_options(width, seconds, seed, threads, tries)
    items = []
    for size, pattern, garments in runs:
        table = allowance if isinstance(allowance, dict) else export_allowance(pattern, allowance, hem)
        items += marker_items([(size, pattern, garments)], allowance=table, notch_spacing=notch_spacing)
    return nest(items, width, seconds=seconds, seed=seed, one_way=one_way, tilt=tilt, threads=threads, tries=tries,
                progress=progress, early_stop=early_stop)


def write_marker(out, marker, title: str = "marker", extra: Optional[dict] = None,
                 progress: Optional[Progress] = None) -> list:
    """The marker's files (DXF, SVG, PDF, PNG, ``marker.json`` with ``extra`` merged) into ``out``, atomically;
    returns the written paths."""
    from .marker import write_marker as _write
    return _write(marker, out, title, progress=progress, extra=extra)


__all__ = ["CONFIGS", "DEFAULT_CONFIG", "Prepared", "PatternRun", "DrapeRun", "prepare", "config_name",
           "solver_config", "make_solver",
           "reference", "transfer", "is_own_size", "adapt", "tolerances", "measure_pattern", "pattern_figures",
           "write_pattern",
           "summary", "drape", "write_drape", "drape_summary", "export_allowance", "export", "marker",
           "write_marker"]
