"""The drape stage: a pattern draped on its body, its fit figures and files."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

import numpy as np

from ..progress import Progress, report, sub


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


def drape(
    pattern,
    material=None,
    options=None,
    body: Optional[Tuple[np.ndarray, np.ndarray]] = None,
    progress: Optional[Progress] = None,
) -> DrapeRun:
    """Drape ``pattern`` with the project's XPBD (Warp) and measure the fit.

    Parameters
    ----------
    pattern : core.pattern.Pattern
    material : fabric preset name, Material, mapping or None (the design's, else cotton)
    options : DrapeOptions or mapping (frames, substeps, device ...), see :class:`core.drape.DrapeOptions`
    body : (vertices (V, 3), faces (F, 3)) or None for the pattern's own body
        instance (its ``body`` record: model, size or shape, pose)
    """
    from ..drape import drape as _drape
    from ..metrics.drape import drape_metrics

    if body is None:
        body_v, body_f = pattern_body(pattern, "ease drape")
    else:
        body_v, body_f = np.asarray(body[0], dtype=np.float64), np.asarray(body[1], dtype=np.int64)
    result = _drape(pattern, body_v, body_f, material=material, options=options, progress=sub(progress, 0.0, 0.9))
    report(progress, 0.92, "drape: measuring the fit")
    metrics = drape_metrics(result, body_v, body_f, pattern=pattern)
    report(progress, 1.0, "drape: done")
    return DrapeRun(result, metrics, body_v, body_f, _drape_figures(result, metrics))


def pattern_body(pattern, needed_by: str, error=None) -> Tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the body ``pattern`` was made on (its ``body`` record: model, shape, pose).

    A pattern without a body record is refused (``error``, default :class:`core.errors.DrapeError`):
    no body is assumed for it, the one line names ``needed_by``.
    """
    from ..body.instance import spec_instance

    if not pattern.body:
        from ..errors import DrapeError

        raise (error or DrapeError)(
            f"pattern.json: body: missing; {needed_by} needs the body the pattern was made on "
            f"(model, shape, pose: as `ease pattern` writes it)"
        )
    return spec_instance(pattern.body)


def _drape_figures(result, metrics) -> Dict[str, object]:
    out = {
        "frames": int(result.frames),
        "settled": result.settle_reason,
        "time s": round(float(result.timings.get("total", 0.0)), 2),
        "mean weft strain %": round(100 * float(np.mean(np.asarray(result.strain_weft)[result.used])), 2),
        "device": result.device,
    }
    a = (metrics or {}).get("all") or {}
    if a:
        out["mean gap mm"] = round(float(a["gap_mm"]["mean"]), 1)
        out["penetration %"] = round(float(a["penetration_pct"]), 2)
        out["seam gap max mm"] = round(float(a["seam_gap_mm"]["max"]), 2)
    return out


def write_drape(out, run: DrapeRun, pattern=None, preview: bool = True, up: str = "y"):
    """Every drape file into ``out`` atomically (see :func:`core.drape.output.write_drape`); returns the folder.

    ``up``: the up axis of ``garment.obj``, ``"y"`` (default, OBJ readers' convention) or ``"z"``."""
    from ..drape.output import write_drape as _write
    from ..metrics.drape import summary as fit_summary

    return _write(
        out,
        run.result,
        run.body_vertices,
        run.body_faces,
        fit=fit_summary(run.metrics),
        vertex_gap=run.metrics["vertex_gap"],
        pattern=pattern,
        preview=preview,
        up=up,
    )


def drape_summary(run: DrapeRun, pattern) -> str:
    """The one-line summary the CLI prints after a drape."""
    r, a = run.result, run.metrics["all"]
    return (
        f"drape {pattern.style}: {r.material['name']}, {r.frames} frames ({r.settle_reason}), "
        f"simulate {r.timings['simulate']:.1f} s; gap {a['gap_mm']['mean']:.1f} ± {a['gap_mm']['std']:.1f} mm, "
        f"penetration {a['penetration_pct']:.2f} %, seam gap max {a['seam_gap_mm']['max']:.2f} mm; "
        f"strain weft {a['strain_weft_pct']['mean']:.2f} % / warp {a['strain_warp_pct']['mean']:.2f} % (mean)"
    )
