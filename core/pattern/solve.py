"""The pattern stage's entry points (paper: "Parameterization -- Optimizing Ease").

- :func:`solve_pattern`: the reference pattern (Eq. ref-scale) on the body the cut was made on;
- :func:`transfer_pattern`: the ease field kept on another body (Eq. transfer-scale);
- :func:`adapt_pattern`: the pattern grown where target poses need more cloth than the
  stretch tolerances allow (Eqs. adapt-scale, material-scale).

Each takes an optional :class:`~core.pattern.optimizer.solver.PatternSolver` (the
flattening and factorisation, shared by all solves of one cut) and an
optional :class:`~core.pattern.config.SolverConfig` for this call (default:
the solver's). Transfer and adaptation sew the reference pattern's seam plan
(the design's ease on the reference body), whatever ran on the solver before.
The optimizer itself: :mod:`.solver` (system, iterations), :mod:`.targets`,
:mod:`.seams`, :mod:`.steps` (local step, flip guard), :mod:`.build`
(assembly), :mod:`.config` (settings and presets).
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from ..errors import PatternError
from ..progress import Progress, sub
from .build import SolveResult, build_pattern
from .config import SolverConfig, tolerances
from .optimizer.seams import SeamPlan, seam_is_gathered
from .optimizer.solver import PatternSolver
from .types import Pattern
from .validate import validate_cut

__all__ = [
    "PatternSolver",
    "SolverConfig",
    "SolveResult",
    "SeamPlan",
    "solve_pattern",
    "transfer_pattern",
    "target_solver",
    "adapt_pattern",
    "build_pattern",
    "seam_is_gathered",
    "validate_cut",
]


def _solver(
    cut, ref_vertices, solver: Optional[PatternSolver], config: Optional[SolverConfig], progress: Optional[Progress]
) -> PatternSolver:
    return solver or PatternSolver(cut, ref_vertices, config, progress=sub(progress, 0.0, 0.3))


def solve_pattern(
    cut,
    body_vertices,
    config: Optional[SolverConfig] = None,
    style: str = "",
    progress: Optional[Progress] = None,
    solver: Optional[PatternSolver] = None,
) -> Pattern:
    """Reference pattern (paper Eq. ref-scale) of ``cut`` on the body instance ``body_vertices`` (V, 3)
    it was cut on."""
    solver = _solver(cut, body_vertices, solver, config, progress)
    K, cw, cg = solver.targets_reference()
    res = solver.solve(K, cw, cg, progress=sub(progress, 0.3, 1.0), config=config)
    pat = build_pattern(cut, res, style=style, mode="reference")
    pat.report["init_seconds"] = solver.timings.get("init", 0.0)
    return pat


def transfer_pattern(
    cut,
    ref_vertices,
    target_vertices,
    config: Optional[SolverConfig] = None,
    style: str = "",
    body: Optional[dict] = None,
    progress: Optional[Progress] = None,
    solver: Optional[PatternSolver] = None,
    start: Optional[Pattern] = None,
    ease=None,
) -> Pattern:
    """Shape transfer (paper Eq. transfer-scale): the ease field kept on the target body (V, 3).

    With the configuration's ``convergence.transfer_solver`` ``"reference"`` the reference flattening
    and factorisation (``solver``) are reused; with ``"target"`` a solver of the same cut is made on the
    target body (:func:`target_solver`: flattened and factorised on the target's positions) and the
    transfer solved on it, sewing the reference's seam plan. The solve starts
    from the reference pattern when ``start`` is given, each piece stretched
    to the target body (:meth:`PatternSolver.start_from`), or, with the
    configuration's ``convergence.transfer_from`` ``"flattening"``, from the
    reference solve's own start so stretched (:meth:`PatternSolver.flattening_start`;
    ``start`` unused; on a target solver: the target's own flattening).
    ``body``: the target body's spec, recorded in the pattern. ``ease``: an override of the cut's weft
    ease (:meth:`PatternSolver.targets_reference`; benchmarks sweep it).

    Darts follow the body: the apex of a dart towards a bust point, seat or shoulder blade is moved,
    with the cloth around it, to where that landmark's rule puts it on the target body
    (:func:`core.cut.darts.follow_cups`); its intake is re-derived (``"auto"``) or held (a set one) by
    the transfer's own solve (docs/darts.md). With ``convergence.transfer_solver`` ``"cup"``, a target
    body whose cups are bigger than the reference's (:func:`core.cut.darts.bigger_cups`) is solved as
    with ``"target"`` from its own flattening, every dart's intake re-derived there (a set one too:
    the design's darts drafted again on the bigger cup, their sewn points at the design's apex offsets from
    the target's bust points: ``follow_cups(..., at_offsets=True)``); any other target as with ``"reference"``, and so
    is a bigger cup where the re-drafted darts are refused (``darts_regrade_refused`` in the report says
    why: men:XL's chest diverges). The pattern's report records ``darts_regraded``.
    """
    solver = _solver(cut, ref_vertices, solver, config, progress)
    cv = (config or solver.config).convergence
    tgt = solver.positions(target_vertices, "target body")
    if any("cup_disk" in r for r in (getattr(cut, "darts", None) or {}).values()):
        from ..cut.darts import follow_cups

        # a dart towards a bust point, seat or shoulder blade ends where that point is on the target body
        tgt = follow_cups(cut, ref_vertices, target_vertices)
    plan = solver.design_plan(config)  # the reference pattern's seams, whichever solver sews them

    def solve_on(solver, cut, start_from, tgt=tgt):
        offsets = solver.offsets(tgt)
        K, cw, cg = solver.targets_reference(tgt, ease=ease, offsets=offsets)
        # the reference pattern stretched by how much longer the target body is under each piece, or the
        # reference solve's own start so stretched (config.Convergence.transfer_from: every size solved alike)
        if start_from == "flattening":
            U0 = solver.flattening_start(cw, cg, offsets)
        else:
            U0 = None if start is None else solver.start_from(start, offsets)
        res = solver.solve(
            K, cw, cg, start=U0, positions=tgt, progress=sub(progress, 0.3, 1.0), plan=plan, config=config
        )
        return build_pattern(cut, res, style=style, body=body, mode="transfer")

    if cv.transfer_solver == "cup":
        from ..cut.darts import bigger_cups, follow_cups, with_auto_intakes

        # on a bigger cup the darts are drafted again: every intake opened by the target's flattening
        if bigger_cups(cut, ref_vertices, target_vertices):
            again = with_auto_intakes(cut)
            # the re-drafted darts end at the design's apex offsets from the target's bust points
            drafted = follow_cups(cut, ref_vertices, target_vertices, at_offsets=True)
            try:
                regraded = target_solver(solver, ref_vertices, drafted, sub(progress, 0.0, 0.3), cut=again)
                pattern = solve_on(regraded, again, "flattening", drafted)
                pattern.report["darts_regraded"] = True
                return pattern
            except PatternError as err:
                # the re-drafted darts do not solve on this body (men:XL's chest): the design's own darts,
                # graded as "reference" grades them, and the report says why
                refused = str(err)
        else:
            refused = None
        pattern = solve_on(solver, cut, cv.transfer_from)
        pattern.report["darts_regraded"] = False
        if refused:
            pattern.report["darts_regrade_refused"] = refused
        return pattern
    if cv.transfer_solver == "target":
        solver = target_solver(solver, ref_vertices, tgt, progress=sub(progress, 0.0, 0.3))
    return solve_on(solver, cut, cv.transfer_from)


def target_solver(
    solver: PatternSolver,
    ref_vertices,
    target_positions: np.ndarray,
    progress: Optional[Progress] = None,
    cut=None,
) -> PatternSolver:
    """A solver of ``solver``'s cut and configuration made on a transfer's target body: the pieces flattened
    and the system factorised on ``target_positions`` (N, 3) (the cut's positions there, its darts' apexes
    following the cups), the reference body (``ref_vertices``, (V, 3), the one ``solver`` was made on) kept
    as the one the targets and folds are measured from (``convergence.transfer_solver`` ``"target"``).
    ``cut``: another cut of the same mesh in its place (``"cup"``: the darts drafted again)."""
    return PatternSolver(
        solver.cut if cut is None else cut, ref_vertices, solver.config, progress=progress, flatten_on=target_positions
    )


def adapt_pattern(
    cut,
    ref_vertices,
    pose_vertices: Sequence[np.ndarray],
    eps_weft: Optional[float] = None,
    eps_warp: Optional[float] = None,
    config: Optional[SolverConfig] = None,
    style: str = "",
    body: Optional[dict] = None,
    progress: Optional[Progress] = None,
    solver: Optional[PatternSolver] = None,
    start: Optional[Pattern] = None,
) -> Pattern:
    """Pose adaptation (paper Eqs. adapt-scale, material-scale) for one or more target poses (V, 3).

    The pattern is solved for the reference body with targets raised to what
    every pose demands, divided by the stretch tolerances ``eps_weft`` and
    ``eps_warp``, each >= 1 (:func:`core.pattern.config.tolerances`: the
    caller's, else the design's ``materials``, else 1.1; the warp's default
    is the caller's weft tolerance).
    """
    eps_weft, eps_warp = tolerances(cut.materials, eps_weft, eps_warp)
    if not len(pose_vertices):
        raise PatternError("adaptation needs at least one target pose")
    solver = _solver(cut, ref_vertices, solver, config, progress)
    cfg = config or solver.config
    poses = [solver.positions(P, f"pose {i + 1}") for i, P in enumerate(pose_vertices)]
    K, cw, cg = solver.targets_adapt(poses, eps_weft, eps_warp, cfg)
    # feedback on the poses' demands only moves right-hand sides: the factorisation is kept
    demands = solver.pose_demands(poses, eps_weft, eps_warp, cfg) if cfg.adaptation.gain > 0 else None
    res = solver.solve(
        K,
        cw,
        cg,
        start=None if start is None else solver.start_from(start),
        progress=sub(progress, 0.3, 1.0),
        poses=demands,
        plan=solver.design_plan(cfg),
        config=cfg,
    )
    mats = dict(cut.materials)
    mats.update({"eps_weft": eps_weft, "eps_warp": eps_warp})
    return build_pattern(cut, res, style=style, body=body, mode="adapt", materials=mats)
