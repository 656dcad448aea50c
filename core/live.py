"""Live ease painting: the pattern follows the painted field, a time slice at a time.

A :class:`LiveSession` keeps what is expensive and fixed for one design on one
body: the cut (:class:`core.workflows.Prepared`), the pattern solver's
flattening and factorisation (:func:`core.workflows.make_solver`) and the map
from every cut triangle to the body template triangle it lies on. A new
painted field (one ease value per body template triangle, what the add-on
reads from the body's ``ease`` layer) becomes the targets of a warm re-solve
that starts from the current pattern (:meth:`core.pattern.optimizer.solver.PatternSolver.begin`
with ``resume``: the iterate, the feedback's corrections and the seam
integral carry over). :meth:`LiveSession.run` runs as many local-global
iterations as fit a time slice and says whether the pattern has converged;
the caller (the add-on's timer) calls it again while the designer is idle and
stops calling once it has. A change of topology (a keypoint moved, a
parameter changed, a seam added: anything but the ease in the design) needs
a new session, made once (:func:`topology_key` tells when).

The solver itself stays stateless: the solve's state is a value held here.
"""

from __future__ import annotations

import dataclasses
import json
import time
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np

from . import workflows as wf
from .errors import PatternError


def topology_key(design, body_spec: Optional[dict] = None) -> str:
    """What a live session depends on: the design without its ease fields, and the body it is cut on.

    Parameters
    ----------
    design : core.design.Design or its JSON dict
    body_spec : ``{"model", "shape", "pose"}`` of the body the cut is made on, or None

    Returns
    -------
    str, equal for two designs that differ only in their panels' ease.
    """
    d = json.loads(json.dumps(design.to_json() if hasattr(design, "to_json") else design))
    for g in d.get("garments") or []:
        for p in g.get("panels") or []:
            if isinstance(p, dict):
                p.pop("ease", None)
    return json.dumps([d, body_spec or {}], sort_keys=True)


def body_triangles(prep) -> np.ndarray:
    """The body template triangle (int64) under each cut triangle, in the solver's order (all panels).

    A cut triangle reads the painted field where it lies, on both sides of a
    mirrored design (the centroid's closest template triangle on the reference
    instance, as the design's ``per_triangle`` ease fields are read).
    """
    from .design.resolve import Resolver

    loc = Resolver(prep.design, prep.body, prep.reference).locator
    out = []
    for panel in prep.cut.panels:
        if not len(panel.faces):
            out.append(np.zeros(0, dtype=np.int64))
            continue
        c = prep.cut.panel_positions(panel, prep.reference)[panel.faces].mean(axis=1)
        out.append(np.asarray(loc.closest(c)[1], dtype=np.int64))
    return np.concatenate(out)


class LiveSession:
    """The live re-solve of one design on one body (module docstring).

    Parameters
    ----------
    prep : core.workflows.Prepared
    config : solver configuration name (:data:`core.workflows.CONFIGS`)
    pattern : a pattern of this cut to start from (the scene's), or None for a cold start
    progress : progress callback of the flattening and factorisation
    warm_iterations : warm iterations after a change (shown as they come) before the cold solve starts

    Attributes
    ----------
    solver : core.pattern.optimizer.solver.PatternSolver, factorised once for the session
    triangles : (f,) int64, :func:`body_triangles`
    ease : (f,) float, the weft ease per cut triangle the current state aims at
    state : core.pattern.optimizer.state.SolveState or None (before the first field)
    converged : bool, ``state`` is the cold solve of the current field (see :meth:`run`)
    iterations_since_change : int, warm and cold iterations since the last :meth:`set_ease`
    seconds_per_iteration : running estimate of one iteration's wall time (what fits a slice)
    """

    def __init__(self, prep, config: str = "improved", pattern=None, progress=None, warm_iterations: int = 4):
        self.prep = prep
        self.config = config
        self.solver = wf.make_solver(prep, config, progress=progress)
        self.triangles = body_triangles(prep)
        from .geom.mesh import triangle_areas

        pos = self.solver.ref_positions
        #: (f,) m^2, the cut triangles' areas on the reference body
        self.areas = np.concatenate([triangle_areas(pos[p.vertex_ids], p.faces) for p in prep.cut.panels])
        self.warm_iterations = int(warm_iterations)
        # Warm slices are previews (shown with their collapse count, never stored): they run without
        # the collapse guard, whose factorisation of a stiffened matrix (tens of ms) would block the
        # viewport beyond a slice after every stroke; the cold solve that converges keeps it.
        cfg = self.solver.config
        self.preview_config = dataclasses.replace(cfg, guard=dataclasses.replace(cfg.guard, guard_scale=0.0))
        self.K = self.solver.ref_offsets[0]
        #: (f,) the design's own weft ease per cut triangle: the target wherever the field is not painted
        self.design_ease = self.solver.design_ease.copy()
        self.ease = self.design_ease.copy()
        self._start = None if pattern is None else self.solver.start_from(pattern)
        self.state = None
        self._cold = None
        self._cold_upto = 0  # the cold solve runs to here (planned, then collapse rounds)
        self._warm = False
        self.converged = False
        self.iterations_since_change = 0
        self.seconds_per_iteration = None
        #: the stored pattern's text, made a piece at a time (:class:`PatternText`)
        self.text = PatternText()

    def prime(self) -> None:
        """Factorise the system of the design's own seam plan now (what the first :meth:`set_ease`
        of an unpainted field needs): a caller that builds the session off the main thread does
        the heavy part there."""
        ones = np.ones_like(self.design_ease)
        self.solver.factorisation(self.preview_config, self.solver.plan_seams(self.K, self.design_ease, ones))

    @property
    def warming(self) -> bool:
        """The next :meth:`run` iterates the warm (shown) state, not the cold solve."""
        return self._warm

    @property
    def n_body_triangles(self) -> int:
        return len(self.prep.body.faces)

    def cut_ease(self, body_ease=None, painted=None) -> np.ndarray:
        """The per-cut-triangle ease (f,) of a painted field ``body_ease`` (F_body,), checked.

        ``painted`` (F_body,) bool: the body triangles whose paint differs from what the design's
        ease was made from or written to (a stroke since); the cut triangles on the others keep
        the design's own ease (:attr:`design_ease`), so a field nobody painted gives the design's
        pattern exactly (a vertex layer cannot hold a per-panel ease where the cut crosses the
        body's triangles). None: every triangle reads the field. ``body_ease`` None: the design's.
        """
        from .design.checks import EASE_MAX, EASE_MIN

        if body_ease is None:
            return self.design_ease.copy()
        e = np.asarray(body_ease, dtype=np.float64).reshape(-1)
        if len(e) != self.n_body_triangles:
            raise PatternError(
                f"live ease: expected {self.n_body_triangles} values (one per body template triangle), got {len(e)}"
            )
        bad = ~np.isfinite(e) | (e < EASE_MIN - 1e-12) | (e > EASE_MAX + 1e-12)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise PatternError(f"live ease: triangle {i}: expected an ease in {EASE_MIN}..{EASE_MAX}, got {e[i]}")
        if painted is None:
            return e[self.triangles]
        painted = np.asarray(painted, dtype=bool).reshape(-1)
        if len(painted) != self.n_body_triangles:
            raise PatternError(
                f"live ease: expected {self.n_body_triangles} painted flags (one per body triangle), got {len(painted)}"
            )
        return np.where(painted[self.triangles], e[self.triangles], self.design_ease)

    def set_design_ease(self, design_ease) -> None:
        """The design's own ease (f,) changed (*Ease to Design*), its cut did not: the unpainted
        triangles aim at it from the next :meth:`set_ease`."""
        ease = np.asarray(design_ease, dtype=np.float64).reshape(-1)
        if ease.shape != self.design_ease.shape:
            raise PatternError(f"live ease: expected {len(self.design_ease)} design values, got {len(ease)}")
        self.design_ease = ease.copy()

    def set_ease(self, body_ease=None, painted=None) -> bool:
        """Aim at a new painted field (F_body,) (:meth:`cut_ease`: ``painted``, None for the
        design's own); False (nothing to do) when the garment's ease is unchanged.

        The next :meth:`run` then takes one warm slice from the current
        pattern. The seam plan follows the new targets; a plan not met before
        costs one factorisation (cached by the solver for the session).
        """
        ease = self.cut_ease(body_ease, painted)
        if self.state is not None and np.array_equal(ease, self.ease):
            return False
        ones = np.ones_like(ease)
        plan = self.solver.plan_seams(self.K, ease, ones)
        start = self._start if self.state is None else None
        self.state = self.solver.begin(
            self.K, ease, ones, start=start, plan=plan, resume=self.state, config=self.preview_config
        )
        self.ease = ease
        self._cold = None
        self._warm = True
        self.converged = False
        self.iterations_since_change = 0
        return True

    def end_warm(self) -> None:
        """Go on with the cold solve from the next :meth:`run` (the warm state shown is enough: a
        caller that shows each warm slice at a cost ends the warm phase after the first one)."""
        self._warm = False

    def restart_from(self, pattern) -> None:
        """Continue from ``pattern`` of this cut (the scene's after an undo): the next field's warm
        slice starts there, with fresh feedback corrections."""
        self._start = self.solver.start_from(pattern)
        self.state = None
        self._cold = None
        self.converged = False

    def run(self, budget_s: float, min_iterations: int = 1) -> int:
        """Work for about ``budget_s`` seconds (at least ``min_iterations`` iterations); the iterations run.

        The first calls after :meth:`set_ease` iterate the warm state (the
        pattern the designer sees moves towards the new paint at once), up to
        ``warm_iterations`` in all (at least one); later calls advance a cold solve of the same field (the configuration's
        iterations from the stretched flattening, exactly what *Optimize
        Pattern* computes), which replaces the warm state when it is complete:
        the session has then converged, and the pattern no longer depends on
        the order the field was painted in. An iteration is started only when
        its expected time still fits the slice.
        """
        if self.state is None:
            self.set_ease(None)
        if self.converged:
            return 0
        if self._warm:
            done = self._iterate(
                self.state,
                budget_s,
                min_iterations,
                self.state.iteration + max(self.warm_iterations - self.iterations_since_change, 0),
            )
            self._warm = self.iterations_since_change < self.warm_iterations
            return done
        if self._cold is None:
            ones = np.ones_like(self.ease)
            self._cold = self.solver.begin(self.K, self.ease, ones, plan=self.state.plan)
            self._cold_upto = self._cold.planned
        done = self._iterate(self._cold, budget_s, min_iterations, self._cold_upto)
        if self._cold.iteration >= self._cold_upto:
            # ended by the solver's own rule (collapse rounds after the planned iterations), so the
            # pattern is the one Optimize Pattern gives
            more = self.solver.extra_iterations(self._cold)
            if more:
                self._cold_upto += more
            else:
                self.state, self._cold = self._cold, None
                self.converged = True
        return done

    def _iterate(self, state, budget_s: float, min_iterations: int, upto: Optional[int]) -> int:
        done = 0
        t0 = time.perf_counter()
        while upto is None or state.iteration < upto:
            per = self.seconds_per_iteration or 0.0
            if done >= min_iterations and time.perf_counter() - t0 + per > budget_s:
                break
            t1 = time.perf_counter()
            self.solver.iterate(state, 1)
            dt = time.perf_counter() - t1
            # running estimate of one iteration's cost: what decides whether the next one fits
            self.seconds_per_iteration = dt if per == 0.0 else 0.7 * per + 0.3 * dt
            done += 1
            self.iterations_since_change += 1
        return done

    def pattern(self, figures: bool = True):
        """The current pattern (core.pattern.Pattern, mode ``reference``); with ``figures``, its
        metrics in ``report["metrics"]``; ``report["live"]``: iterations since the change, converged;
        converged (or with ``figures``), the design's pleats in ``report["pleats"]``."""
        if self.state is None:
            self.run(0.0)
        # a warm preview is shown, never stored: the pleats (half a second to open and measure on a
        # pleated skirt) are attached to the converged pattern, the one the add-on stores
        pat = self._reference(self.solver.result(self.state), pleats=self.converged or figures)
        pat.report["config"] = self.config
        pat.report["live"] = {"iterations": int(self.iterations_since_change), "converged": bool(self.converged)}
        if figures:
            wf.measure_pattern(pat)
        return pat

    def figures(self, pattern) -> Dict[str, object]:
        """The key figures of a measured ``pattern`` of this session (as the workflows give them)."""
        return wf.pattern_figures(pattern)

    def cold_pattern(self, body_ease=None, painted=None):
        """A cold solve (the configuration's iterations from the stretched flattening) of the
        field ``body_ease`` (F_body,) on this session's solver (``painted``: :meth:`cut_ease`):
        what live mode converges towards."""
        ease = self.cut_ease(body_ease, painted)
        ones = np.ones_like(ease)
        pat = self._reference(self.solver.solve(self.K, ease, ones, plan=self.solver.plan_seams(self.K, ease, ones)))
        wf.measure_pattern(pat)
        return pat

    def _reference(self, result, pleats: bool = True):
        """The reference pattern of a solve ``result`` of this session; with ``pleats`` the design's
        pleats attached as every workflow attaches them (:func:`core.pattern.pleats.attach_pleats`):
        what Live stores over Optimize's pattern keeps ``report["pleats"]``, so drape, export and
        marker open them."""
        from .pattern.build import build_pattern
        from .pattern.pleats import attach_pleats

        pat = build_pattern(self.prep.cut, result, style=self.prep.design.name, mode="reference")
        if pleats:
            attach_pleats(pat, self.prep)
        return pat


#: Rows of a list encoded per ``json`` call: its C encoder holds the GIL for the whole call, so a
#: worker encoding a large panel's field in one call stalls the main thread as long (issue 32:
#: up to ~40 ms on the 45.7k-triangle teaser); between calls the threads switch.
ENCODE_ROWS = 1024


def _dumps_rows(value) -> str:
    """``dumps_json(value, indent=None)``, byte for byte, a list encoded :data:`ENCODE_ROWS` rows
    per call."""
    from .fileio import dumps_json

    if not isinstance(value, list) or len(value) <= ENCODE_ROWS:
        return dumps_json(value, indent=None)
    chunks = (dumps_json(value[i : i + ENCODE_ROWS], indent=None)[1:-1] for i in range(0, len(value), ENCODE_ROWS))
    return "[" + ", ".join(chunks) + "]"


class PatternText:
    """The compact ``pattern.json`` text of a session's patterns, made a piece at a time.

    What :func:`core.fileio.dumps_json` of :func:`core.pattern.io.pattern_to_json`
    gives with ``indent=None``, byte for byte, but as a list of units (one per
    pattern piece, then one that joins them), so that a caller with a time
    budget (the add-on's timer) can spread the encoding over several slices.
    The text of an array field that did not change since the last pattern of
    this cut (faces, vertex ids, body positions, unpainted targets) is kept and
    reused: a stroke re-encodes the 2D positions and the scales, not the cut.
    """

    def __init__(self):
        self._fields: Dict[Tuple[str, str], Tuple[np.ndarray, str]] = {}

    def units(self, pattern) -> List[Tuple[int, Callable[[], Optional[str]]]]:
        """``[(size, work)]``: call each ``work()`` in order; the last one returns the text.

        ``size`` is the unit's share of the encoding (the piece's triangles;
        the join counts all of them), what a caller's time estimate scales with.
        """
        pieces: List[str] = []
        units = [(len(p.faces), lambda p=p: pieces.append(self._panel(pattern, p))) for p in pattern.panels]
        units.append((sum(len(p.faces) for p in pattern.panels), lambda: self._join(pattern, pieces)))
        return units

    def text(self, pattern) -> str:
        """The whole text at once (the units run in a row)."""
        out = None
        for _, work in self.units(pattern):
            out = work()
        return out

    def _panel(self, pattern, panel) -> str:
        from .pattern.io import pattern_to_json

        arrays = {
            f.name: getattr(panel, f.name)
            for f in dataclasses.fields(panel)
            if isinstance(getattr(panel, f.name), np.ndarray)
        }
        kept = {}
        for name, value in arrays.items():
            hit = self._fields.get((panel.name, name))
            if hit is not None and hit[0].dtype == value.dtype and np.array_equal(hit[0], value):
                kept[name] = hit[1]
        # the kept fields are converted empty (their lists are what costs), their text is reused
        one = dataclasses.replace(
            pattern, panels=[dataclasses.replace(panel, **{k: arrays[k][:0] for k in kept})], seams=[], pins={}
        )
        d = pattern_to_json(one)["panels"][0]
        if set(kept) - set(d):  # a field stored under another name: convert it in full
            d = pattern_to_json(dataclasses.replace(one, panels=[panel]))["panels"][0]
            kept = {}
        parts = []
        for key, value in d.items():
            text = kept.get(key)
            if text is None:
                text = _dumps_rows(value)
                if key in arrays:
                    self._fields[(panel.name, key)] = (np.array(arrays[key]), text)
            parts.append(f"{json.dumps(key)}: {text}")
        return "{" + ", ".join(parts) + "}"

    @staticmethod
    def _join(pattern, pieces: List[str]) -> str:
        from .pattern.io import pattern_to_json

        top = pattern_to_json(dataclasses.replace(pattern, panels=[]))
        parts = [
            f"{json.dumps(k)}: " + ("[" + ", ".join(pieces) + "]" if k == "panels" else _dumps_rows(v))
            for k, v in top.items()
        ]
        return "{" + ", ".join(parts) + "}"


def achieved_over_painted(
    pattern, triangles: np.ndarray, n_body: int, areas: Optional[np.ndarray] = None
) -> np.ndarray:
    """Per body template triangle ``rho_hat / rho - 1`` (F_body,): the achieved weft scale over the
    painted one, area-weighted over the cut triangles on it (NaN where no garment lies).

    Parameters
    ----------
    pattern : core.pattern.Pattern of the session's cut (panels in the cut's order)
    triangles : (f,) :func:`body_triangles`
    n_body : number of body template triangles
    areas : (f,) m^2, the cut triangles' areas on the pattern's body (computed when None)
    """
    from .geom.mesh import triangle_areas

    ratio = (
        np.concatenate([np.asarray(p.achieved_weft, float) / np.asarray(p.target_weft, float) for p in pattern.panels])
        - 1.0
    )
    area = areas if areas is not None else np.concatenate([triangle_areas(p.xyz, p.faces) for p in pattern.panels])
    ok = np.isfinite(ratio)
    w = np.bincount(triangles[ok], weights=area[ok], minlength=n_body)
    s = np.bincount(triangles[ok], weights=(area * ratio)[ok], minlength=n_body)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(w > 0, s / np.where(w > 0, w, 1.0), np.nan)


__all__ = ["LiveSession", "PatternText", "topology_key", "body_triangles", "achieved_over_painted"]
