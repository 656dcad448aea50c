"""One batch item on a worker: body, transfer, optional adaptation / drape / export, files, manifest row.

A worker process cuts each design once: the first item of a design builds a
:class:`Context` (:func:`core.workflows.prepare`, the solver's factorisation
and the reference pattern that every transfer starts from) and keeps it in
this process; later items of the design cost one transfer. The context is a
pure function of the design, so every worker builds the same one and an
item's result does not depend on which worker made it.

Errors never leave :func:`run_item`: an item that fails returns a row with
status ``"error"`` (or ``"timeout"``) and a one-line message, and its folder
is not written.
"""

from __future__ import annotations

import copy
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

from ..errors import Cancelled, EaseError
from .items import Item

# design key, config -> Context, per worker process (threads share it under the lock)
_CONTEXTS: Dict[Tuple[str, str], "Context"] = {}
_LOCK = threading.Lock()


class ItemTimeout(Cancelled):
    """An item ran past the batch's per-item time limit."""


@dataclass
class Context:
    """What a worker keeps per design: the preparation, its solver and the reference pattern."""

    prep: object
    solver: object
    start: object
    seconds: float


def context(item: Item) -> Context:
    """The worker's :class:`Context` of ``item``'s design, built on first use."""
    from .. import workflows as wf
    from ..body import load_body

    key = (item.design_key, item.options.config)
    with _LOCK:
        ctx = _CONTEXTS.get(key)
        if ctx is None:
            t0 = time.perf_counter()
            prep = wf.prepare(copy.deepcopy(item.design), body=load_body(item.model))
            solver = wf.make_solver(prep, config=item.options.config)
            start = wf.reference(prep, config=item.options.config, solver=solver).pattern
            ctx = _CONTEXTS[key] = Context(prep, solver, start, time.perf_counter() - t0)
    return ctx


def deadline(seconds: Optional[float]):
    """A progress callback raising :class:`ItemTimeout` once ``seconds`` have passed (None: no limit).

    The stages call it at each solver iteration, fit evaluation and drape
    frame, so an item stops within one of those steps of its limit.
    """
    if not seconds:
        return None
    end = time.monotonic() + float(seconds)

    def check(fraction: float, message: str) -> None:
        if time.monotonic() > end:
            raise ItemTimeout(f"over the item time limit of {seconds:g} s (at: {message})")

    return check


def _target(ctx: Context, item: Item, check) -> Tuple[object, Dict[str, object]]:
    """The transfer target of ``item``'s body (a size name or a shape dict) and its row entries."""
    from .. import workflows as wf
    from ..body.sizes import fit_measurements

    body = item.body
    if body.kind == "size":
        # a bare size is of the design's chart (as the transfer reads it): named so here, or the
        # item's body instance, girths and shape would be the default chart's size
        return wf.size_name(ctx.prep, body.value), {}
    if body.kind == "tape":  # made-to-measure, the fit of ease body --measurements
        from ..body.made_to_measure import fit_tape

        fit = fit_tape(ctx.prep.body, body.value, progress=check)
        missed = [
            f"{k} {fit.achieved[k]:.1f} cm for {fit.targets[k]:g}" for k, s in fit.status.items() if s[:6] != "within"
        ]
        if missed or fit.collisions:
            why = f"not reachable by this model: {'; '.join(missed)}" if missed else "the fitted body cuts into itself"
            raise EaseError(f"{body.origin}: {why}" + (f" ({', '.join(fit.collisions)})" if fit.collisions else ""))
        return fit.shape, {f"tape.{k}_cm": fit.achieved[k] for k in fit.targets}
    if body.kind != "measurements":
        return body.value, {}
    fit = fit_measurements(ctx.prep.body, body.value, progress=check)
    missed = [
        f"{k} {fit.achieved[k]:.1f} cm for {fit.targets[k]:g}" for k, s in fit.status.items() if s != "within 1 cm"
    ]
    if missed:
        raise EaseError(f"{body.origin}: not reachable by this model: {'; '.join(missed)}")
    return fit.shape, {f"targets.{k}": v for k, v in fit.targets.items()}


def _pattern_row(pattern, prefix: str = "metrics.") -> dict:
    m = pattern.report["metrics"]
    c, s = m["compliance"], m["seams"]
    return {
        f"{prefix}weft_mean_pct": c["mean"],
        f"{prefix}weft_std_pct": c["std"],
        f"{prefix}warp_mean_pct": c["warp_mean"],
        f"{prefix}warp_signed_pct": c["warp_signed"],
        f"{prefix}shear_p95_deg": c["shear_p95"],
        f"{prefix}flipped": m["flipped_triangles"],
        f"{prefix}collapsed": m.get("collapsed_triangles", 0),
        f"{prefix}crossings": m.get("crossings", 0),
        f"{prefix}seam_mismatch_mean_pct": s["mean"],
        f"{prefix}seam_mismatch_max_mm": s["max_mm"],
    }


def _adapt(ctx: Context, item: Item, target, check):
    """The design cut on the item's body and adapted to the batch's poses (a cut per item:
    adaptation is defined on the body a cut was made on)."""
    from .. import workflows as wf

    design = copy.deepcopy(item.design)
    design["body"] = {**design.get("body", {}), "shape": target}
    prep = wf.prepare(design, body=ctx.prep.body, progress=check)
    run = wf.adapt(prep, list(item.options.poses), config=item.options.config, progress=check)
    stretch = run.pattern.report["residual_stretch"]
    row = {
        f"adapt.residual_stretch_before_pct.{pose}": max(v["before"] for v in g.values()) for pose, g in stretch.items()
    }
    row.update(
        {f"adapt.residual_stretch_after_pct.{pose}": max(v["after"] for v in g.values()) for pose, g in stretch.items()}
    )
    row.update(_pattern_row(run.pattern, "adapt."))
    return run, row


def _drape(ctx: Context, item: Item, run, vertices, check):
    from .. import workflows as wf

    drun = wf.drape(run.pattern, body=(vertices, ctx.prep.body.faces), progress=check)
    a = drun.metrics["all"]
    return drun, {
        "drape.gap_mean_mm": a["gap_mm"]["mean"],
        "drape.penetration_pct": a["penetration_pct"],
        "drape.seam_gap_max_mm": a["seam_gap_mm"]["max"],
        "drape.frames": int(drun.result.frames),
        "drape.settled": drun.result.settle_reason,
    }


def _marker(item: Item, run, check):
    """The item's pieces nested on the batch's fabric width (:func:`core.workflows.marker`, one garment, one
    nester on this worker's core; the export's allowance rule: the design's table) and its row entries.

    The nester ends its search when it stops improving (``early_stop``), so an item's marker does not depend on
    how much time a loaded worker gave it within ``marker_seconds``."""
    from .. import workflows as wf
    from ..marker import size_label

    opts = item.options
    marker = wf.marker(
        [(size_label(run.pattern), run.pattern, 1)],
        opts.marker_width,
        seconds=opts.marker_seconds,
        threads=1,
        tries=1,
        spread=opts.marker_spread,
        early_stop=True,
        progress=check,
    )
    return marker, {
        "marker.efficiency_pct": 100.0 * marker.efficiency,
        "marker.length_mm": 1000.0 * marker.length,
        "marker.pieces": len(marker.placements),
    }


def _write(folder: Path, item: Item, run, arun, drun, preview: bool, marker=None) -> None:
    from .. import workflows as wf
    from ..fileio import output_dir, write_json
    from .garmentcode import specification

    opts = item.options
    # the items folder's leftovers of killed runs were cleared when the batch started (run_batch)
    with output_dir(folder, recover=False) as tmp:
        wf.write_pattern(tmp, run, preview=preview)
        if arun is not None:
            wf.write_pattern(tmp / "adapt", arun, preview=preview)
        if drun is not None:
            wf.write_drape(tmp / "drape", drun, pattern=run.pattern, preview=preview)
        if opts.export:
            wf.export(
                run.pattern,
                tmp / "export",
                opts.export,
                drape=(drun.result.positions, drun.result.pattern_faces) if drun is not None else None,
            )
        if marker is not None:
            wf.write_marker(tmp / "marker", marker, f"{run.pattern.style or 'pattern'} marker")
        if opts.garmentcode:
            write_json(tmp / "specification.json", specification(run.pattern))
        write_json(
            tmp / "body.json",
            {
                "id": item.id,
                **item.body.record(),
                "origin": item.body.origin,
                "model": item.model,
                "shape": run.pattern.body.get("shape"),
            },
        )


def item_row(item: Item, status: str = "ok", error: str = "") -> dict:
    """The manifest row's first keys: the item, its body's kind, its status and error."""
    return {
        "id": item.id,
        "label": item.body.label,
        "index": item.index,
        "folder": item.folder,
        "body.kind": item.body.kind,
        "status": status,
        "error": error,
    }


def run_item(item: Item, out_root, time_limit: Optional[float] = None) -> dict:
    """Make ``item`` into ``out_root/items/<folder>`` and return its manifest row.

    Row keys: ``id``, ``label``, ``index``, ``folder``, ``status`` (``ok``,
    ``error``, ``timeout``), ``error`` (one line), ``body.kind``, ``shape.*``,
    ``targets.*`` (cm, measurement bodies), ``body.<measure>_cm`` (cm, measured on the
    body: :func:`core.body.measure.measure`), ``metrics.*`` (the transferred
    pattern on its body), ``adapt.*``, ``drape.*``, ``marker.*`` (efficiency %, length mm,
    pieces), ``timings.*`` (s: body, transfer, metrics, adapt, drape, marker, write, setup = this worker's cut of the
    design when this item paid for it; ``cpu`` = the CPU seconds of this
    worker's process for the item, the cut included when it paid for it:
    throughput on a shared machine), ``worker``.
    """
    from .. import workflows as wf
    from ..body.instance import body_instance, instance_pose, instance_shape
    from ..body.measure import measure
    from ..export.pieces import readable_name

    row = {**item_row(item), "worker": os.getpid()}
    timings: Dict[str, float] = {}
    cpu = time.process_time()
    try:
        built = (item.design_key, item.options.config) in _CONTEXTS
        t = time.perf_counter()
        ctx = context(item)
        if not built:
            timings["setup"] = time.perf_counter() - t
        check = deadline(time_limit)
        t = time.perf_counter()
        if item.body.kind in ("measurements", "tape"):  # what was asked, also on a row whose fit fails
            row.update({f"targets.{k}": v for k, v in item.body.value.items()})
        target, entries = _target(ctx, item, check)
        row.update(entries)
        if isinstance(target, str):
            row["body.size"] = target
        model = ctx.prep.body
        # the body's shape before anything can fail on it: a refused body's row says which body it is
        row.update({f"shape.{k}": v for k, v in sorted((instance_shape(model, target) or {}).items())})
        rest = body_instance(model, target)
        girths = measure(model, rest)
        row.update({f"body.{k}_cm": v for k, v in girths.items()})
        # the cut's pose: the reference pose ("A", or none) is the rest instance itself, which the transfer
        # then takes as its target instead of evaluating the body again; another pose is the transfer's to
        # make, and the drape's (the posed body, only then)
        at_rest = instance_pose(ctx.prep.cut.body.get("pose")) is None
        vertices = (
            (rest if at_rest else body_instance(model, target, ctx.prep.cut.body.get("pose")))
            if item.options.drape
            else None
        )
        timings["body"] = time.perf_counter() - t

        t = time.perf_counter()
        run = wf.transfer(
            ctx.prep,
            target,
            config=item.options.config,
            solver=ctx.solver,
            start=ctx.start,
            progress=check,
            vertices=rest if at_rest else None,
        )
        timings["transfer"] = run.timings["optimize"]
        # the body in its own fields of pattern.json and every export: a readable name where it has no chart
        # size (sample-0017, not its shape parameters), its girths
        run.pattern.body.update(
            {} if isinstance(target, str) else {"name": readable_name(item.body.label)}, measurements_cm=dict(girths)
        )
        row.update(_pattern_row(run.pattern))
        timings["metrics"] = time.perf_counter() - t - timings["transfer"]

        arun = drun = None
        if item.options.poses:
            t = time.perf_counter()
            arun, entries = _adapt(ctx, item, target, check)
            row.update(entries)
            timings["adapt"] = time.perf_counter() - t
        if item.options.drape:
            t = time.perf_counter()
            drun, entries = _drape(ctx, item, run, vertices, check)
            row.update(entries)
            timings["drape"] = time.perf_counter() - t

        marker = None
        if item.options.marker_width is not None:
            t = time.perf_counter()
            marker, entries = _marker(item, run, check)
            row.update(entries)
            timings["marker"] = time.perf_counter() - t

        t = time.perf_counter()
        _write(Path(out_root) / "items" / item.folder, item, run, arun, drun, item.options.preview, marker)
        timings["write"] = time.perf_counter() - t
    except ItemTimeout as exc:
        row.update(status="timeout", error=one_line(exc))
    except Exception as exc:  # one item's failure is recorded, never the batch's
        row.update(status="error", error=one_line(exc))
    timings["cpu"] = time.process_time() - cpu
    row.update({f"timings.{k}": v for k, v in timings.items()})
    return row


def run_items(items: Sequence[Item], out_root, time_limit: Optional[float] = None) -> List[dict]:
    """:func:`run_item` on each of ``items`` in turn (one Dask task of several items); their rows.

    Each item has its own time limit and its own error row, as it would in a task of its own.
    """
    return [run_item(item, out_root, time_limit=time_limit) for item in items]


def one_line(exc: BaseException) -> str:
    """``Type: first line of the message`` (EaseError: just the message, it names the element)."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
    if isinstance(exc, EaseError) and text:
        return text
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__
