"""Runtime state and the add-on's doors into the core.

Caches hold what is expensive and deterministic to rebuild (body models,
cuts, patterns); what must survive a save lives in the scene (see
:mod:`.properties`). Nothing here changes the scene except the small
helpers at the end.
"""
from __future__ import annotations

import bpy

from ..core.errors import Cancelled, EaseError


class AddonError(EaseError):
    """A user error detected by the add-on itself (e.g. no body in the scene)."""


USER_ERRORS = (EaseError, Cancelled, KeyError, ValueError, OSError)

_MODELS: dict = {}
CUTS: dict = {}       # scene name -> (design json, body spec json, GarmentCut)
PATTERNS: dict = {}   # scene name -> Pattern


def clear() -> None:
    _MODELS.clear()
    CUTS.clear()
    PATTERNS.clear()


def body_model(name: str):
    """The body model ``name`` (``"anny"`` or a file path), loaded once."""
    if name not in _MODELS:
        from ..core.body import load_body
        _MODELS[name] = load_body(name)
    return _MODELS[name]


def size_shape(model, size: str):
    """(shape, achieved measurements in cm) of chart size ``size`` on ``model``."""
    from ..core.body import sizes
    from ..core.body.measure import measure as _measure
    shape = sizes.size_shape(model, size)
    return shape, _measure(model, model.vertices(shape))


def fit_measurements(model, targets: dict):
    """(shape, achieved, status) of a fit to ``targets`` (cm)."""
    from ..core.body import sizes
    res = sizes.fit_measurements(model, targets)
    return res.shape, {k: f"{v:.1f} cm" + (f" ({res.status[k]})" if k in res.status else "")
                       for k, v in res.achieved.items()}


def measure(model, shape: dict) -> dict:
    from ..core.body.measure import measure as _measure
    return _measure(model, model.vertices(shape or None))


def collection(scene):
    """The scene's "EASE" collection (created on first use)."""
    coll = bpy.data.collections.get("EASE")
    if coll is None:
        coll = bpy.data.collections.new("EASE")
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def remove_object(obj) -> None:
    data = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    if data is not None and data.users == 0:
        for coll in (bpy.data.meshes, bpy.data.curves):
            if data.name in coll and coll[data.name] == data:
                coll.remove(data)
                break


def objects_with_role(scene, role: str):
    return [o for o in scene.objects if o.get("ease_role") == role]


def remove_role(scene, role: str) -> None:
    for o in objects_with_role(scene, role):
        remove_object(o)


# ----------------------------------------------------------------------------- later stages

def body_instance(model, spec: dict):
    """Vertices (V, 3) of a body spec ``{"model", "shape", "pose"}`` (shape may be a size name)."""
    shape = spec.get("shape")
    if isinstance(shape, str):
        shape, _ = size_shape(model, shape)
    pose = spec.get("pose")
    return model.vertices(shape or None, None if pose in (None, "A") else pose)


def _ref_vertices(cut):
    """Vertices of the body instance ``cut`` was made on (its ``body`` record)."""
    model = body_model(cut.body.get("model", "anny"))
    return model, body_instance(model, cut.body)


def _with_metrics(pattern):
    from ..core.metrics.pattern import pattern_report
    from ..core.errors import PatternError
    metrics = pattern_report(pattern)
    if metrics.get("flipped_triangles"):
        raise PatternError(f"{metrics['flipped_triangles']} flipped triangles in the pattern")
    pattern.report["metrics"] = metrics
    return pattern


def optimize_pattern(design, cut, body_obj, progress=None):
    """The reference pattern of ``design`` cut as ``cut`` (on the scene body's shape)."""
    from ..core.pattern.solve import solve_pattern
    _, ref = _ref_vertices(cut)
    return _with_metrics(solve_pattern(cut, ref, style=design.name, progress=progress))


def transfer_pattern(design, cut, body_obj, size: str, progress=None):
    """(pattern on size ``size``, figures): shape transfer keeping the ease field."""
    from ..core.body.sizes import check_size
    from ..core.metrics.pattern import ease_compliance
    from ..core.pattern.solve import PatternSolver, solve_pattern, transfer_pattern as _transfer
    from ..core.progress import sub
    size = check_size(size)
    model, ref = _ref_vertices(cut)
    shape, _ = size_shape(model, size)
    pose = cut.body.get("pose")
    target = model.vertices(shape, None if pose in (None, "A") else pose)
    solver = PatternSolver(cut, ref, None, progress=sub(progress, 0.0, 0.3))
    ref_pat = solve_pattern(cut, ref, solver=solver, progress=sub(progress, 0.3, 0.6))
    pat = _transfer(cut, ref, target, solver=solver, start=ref_pat, style=design.name,
                    body={"model": cut.body.get("model", model.name), "shape": shape, "pose": pose, "size": size},
                    progress=sub(progress, 0.6, 1.0))
    dev, refc = ease_compliance(pat), ease_compliance(ref_pat)
    pat.report.update({"size": size, "transfer_deviation": dev, "reference_compliance": refc})
    _with_metrics(pat)
    figures = {"size": size,
               "transfer deviation mean %": round(float(dev["mean"]), 3),
               "transfer deviation std %": round(float(dev["std"]), 3),
               "reference compliance mean %": round(float(refc["mean"]), 3)}
    return pat, figures


def adapt_pattern(design, cut, body_obj, poses, tolerance: float, progress=None):
    """(pattern adapted to ``poses``, figures with before/after residual stretch %)."""
    from ..core.metrics.pattern import residual_stretch
    from ..core.pattern.solve import PatternSolver, adapt_pattern as _adapt, solve_pattern
    from ..core.progress import sub
    model, ref = _ref_vertices(cut)
    shape = cut.body.get("shape")
    if isinstance(shape, str):
        shape, _ = size_shape(model, shape)
    pose_v = [model.vertices(shape or None, p) for p in poses]
    solver = PatternSolver(cut, ref, None, progress=sub(progress, 0.0, 0.3))
    ref_pat = solve_pattern(cut, ref, solver=solver, progress=sub(progress, 0.3, 0.6))
    pat = _adapt(cut, ref, pose_v, eps_weft=float(tolerance), solver=solver, start=ref_pat,
                 style=design.name, progress=sub(progress, 0.6, 1.0))
    figures = {"tolerance": float(tolerance)}
    stretch = {}
    for name, P in zip(poses, pose_v):
        X = cut.positions(P)
        xyz = {p.name: X[p.vertex_ids] for p in cut.panels}
        stretch[name] = {}
        for g in sorted(cut.garments) or [None]:
            b = float(residual_stretch(ref_pat, xyz, tolerance, g))
            a = float(residual_stretch(pat, xyz, tolerance, g))
            stretch[name][g or "all"] = {"before": b, "after": a}
            figures[f"{name} {g or 'all'} stretched % before/after"] = f"{b:.1f} / {a:.1f}"
    pat.report.update({"poses": list(poses), "eps_weft": float(tolerance), "residual_stretch": stretch})
    _with_metrics(pat)
    return pat, figures


def garment_gap(result, pattern, body_vertices, body_faces):
    """(per garment vertex gap (N,) m, drape metrics summary dict)."""
    from ..core.metrics.drape import drape_metrics, summary
    m = drape_metrics(result, body_vertices, body_faces, pattern)
    return m["vertex_gap"], summary(m)


def export_pattern(pattern, out_dir: str, formats, drape_positions=None, allowance=None,
                   notch_spacing=None) -> list:
    """The core's exporter (:func:`core.export.export_pattern`); raises ExportError before writing."""
    from ..core.export import export_pattern as _export
    return _export(pattern, out_dir, formats=list(formats), drape_positions=drape_positions,
                   allowance=allowance, notch_spacing=notch_spacing)
