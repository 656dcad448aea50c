"""Cutting the body surface into garment panels.

:func:`cut_design` is the entry point: design -> keypoints resolved on the
reference body instance -> :func:`core.cut.engine.cut_surface` -> ease fields.
The result (:class:`core.cut.types.GarmentCut`) gives the panels' 3D vertices
on any shape and pose through its embedding. Imports stay light here; the
engine and its dependencies load when a cut is made.
"""

from __future__ import annotations

import time
from typing import Optional

from ..progress import Progress, report, sub


def cut_design(
    design, body=None, shape=None, pose=None, progress: Optional[Progress] = None, timings: Optional[dict] = None
):
    """Cut ``design`` on a body instance.

    Parameters
    ----------
    design : core.design.Design | dict | path of a design JSON
    body : BodyModel, or None to load ``design.body["model"]``
    shape : size name (``"XS"``..``"XL"``) or shape dict; None: the design's
    pose : pose preset or dict; None: the design's (the reference pose)
    progress : callback ``progress(fraction, message)``, may raise Cancelled
    timings : optional dict, filled with wall seconds per stage: ``resolve`` (keypoints,
        rings and traced lengths on the body), the engine's stages (see
        :func:`core.cut.engine.cut_surface`) and ``ease`` (for benchmarks)

    Returns
    -------
    GarmentCut with ``Panel.ease`` filled from the design's ease fields and
    ``materials`` from the design.

    Raises
    ------
    DesignError : an invalid design element (named by its JSON path)
    CutError : the engine cannot cut a named line or panel
    """
    from ..design import apply_ease, load_design
    from ..design.resolve import Resolver, instance_vertices, resolve
    from .engine import cut_surface

    design = load_design(design)
    report(progress, 0.0, f"resolving design {design.name!r}")
    if body is None:
        from ..body.registry import load_spec

        body = load_spec(design.body)
    t0 = time.perf_counter()
    vertices = instance_vertices(design, body, shape, pose)
    from .auto_darts import has_auto, place_darts

    if has_auto(design):
        # automatic darts placed first, on this instance (core.cut.auto_darts)
        design = place_darts(design, body, vertices, progress=sub(progress, 0.0, 0.1))
    t1 = time.perf_counter()
    resolver = Resolver(design, body, vertices)
    spec = resolve(design, body, shape=shape, pose=pose, resolver=resolver)
    t2 = time.perf_counter()
    report(progress, 0.15, "cutting the body surface")
    cut = cut_surface(
        body, vertices, spec, progress=sub(progress, 0.15, 0.95), timings=timings, seed_names=seed_names(design)
    )
    report(progress, 0.95, "applying ease fields")
    t3 = time.perf_counter()
    apply_ease(cut, design, body, vertices, resolver=resolver)
    if timings is not None:
        timings["body_instance"] = timings.get("body_instance", 0.0) + t1 - t0
        timings["resolve"] = timings.get("resolve", 0.0) + t2 - t1
        timings["ease"] = timings.get("ease", 0.0) + time.perf_counter() - t3
    cut.materials = {**dict(cut.materials or {}), **design.materials}
    if not cut.body:
        cut.body = dict(spec.body)
    report(progress, 1.0, f"cut {len(cut.panels)} panels")
    return cut


def seed_names(design) -> dict:
    """Panel name -> its seed as the design names it, for the engine's errors:
    ``"keypoint 'chest_front'"``, or the JSON path of an inline seed."""
    from ..design.resolve import _panels as design_panels  # (garment, path, panel, mirror_of), mirrors included

    return {
        f"{g.name}.{p.name}": f"keypoint {p.seed!r}" if isinstance(p.seed, str) else f"seed {path}.seed"
        for g, path, p, _ in design_panels(design)
    }


__all__ = ["cut_design"]
