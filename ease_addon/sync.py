"""The after-change reactions: what follows in the scene when something changed.

A body's shape or pose moves its vertices in place and the objects attached
to it follow; a new design redraws the seamlines and keypoints; a loaded
design shows its settings in the panels; a new pattern replaces the pieces
beside the body; the property update callbacks (:mod:`.properties`) land
here too. Operators call these after computing everything they need, so the
scene changes only once nothing can fail any more.
"""
from __future__ import annotations

import json
from contextlib import contextmanager

import numpy as np

from . import build, convert, data, materials, ramp, state
from .objects import objects_with_role, select_only, world_bounds

SYNCING = False   # True while the add-on fills the sliders (their update callbacks must not fire)


@contextmanager
def filling():
    """While the add-on itself fills slider collections: their updates do nothing."""
    global SYNCING
    SYNCING = True
    try:
        yield
    finally:
        SYNCING = False


# ----------------------------------------------------------------------------- body

def fill_shape_props(scene, model, shape: dict) -> None:
    """Show ``model``'s shape parameters with the values of ``shape`` as the Phenotype sliders."""
    with filling():
        coll = scene.ease.shape
        coll.clear()
        for name, (lo, hi, default) in model.shape_parameters().items():
            item = coll.add()
            item.name = name
            item.min, item.max = float(lo), float(hi)
            item.value = float(shape.get(name, default))


def body_vertices(spec: dict) -> np.ndarray:
    """Vertices of the body spec ``{"model", "shape", "pose"}`` (the core's body instance)."""
    from ..core.body.instance import body_instance
    return body_instance(state.body_model(spec["model"]), spec["shape"] or None, spec["pose"])


def update_body(context, obj, shape=None, pose=None) -> None:
    """Set the body's shape and/or pose: vertices move in place, attached
    objects (seamlines, keypoint markers) follow. Computes first, so a bad
    shape/pose raises before the scene changes."""
    spec = data.body_spec(obj)
    if shape is not None:
        spec["shape"] = {k: float(v) for k, v in shape.items()}
    if pose is not None:
        spec["pose"] = pose
    verts = body_vertices(spec)
    convert.set_vertices(obj.data, verts)
    convert.store_json(obj, "ease_shape", spec["shape"])
    obj["ease_pose"] = spec["pose"]
    refresh_attachments(context, obj, verts)


def new_body(context, model_name: str, shape=None, pose: str = "A"):
    """Add a body object and make it the scene's body (shape sliders, ease layer, selection)."""
    model = state.body_model(model_name)
    shape = dict(model.default_shape() if shape is None else shape)
    verts = body_vertices({"model": model_name, "shape": shape, "pose": pose})
    scene = context.scene
    obj = build.body(scene, "EASE Body", verts, model.faces)
    obj["ease_model"] = model_name
    convert.store_json(obj, "ease_shape", shape)
    obj["ease_pose"] = pose
    scene.ease.body = obj
    fill_shape_props(scene, model, shape)
    init_ease_layer(scene, obj)
    select_only(context, obj)
    return obj


def shape_changed(item, context) -> None:
    """A Phenotype slider moved: the body follows live (errors go to the console, never a traceback)."""
    if SYNCING:
        return
    obj = data.body_object(context, required=False)
    if obj is None:
        return
    shape = {i.name: float(min(max(i.value, i.min), i.max)) for i in context.scene.ease.shape}
    try:
        update_body(context, obj, shape=shape)
    except Exception as exc:  # a slider must never leave a traceback in the UI
        print(f"[ease] shape update failed: {exc}")


def refresh_attachments(context, obj, verts) -> None:
    """Move the seamlines and keypoint markers onto the body's current vertices."""
    scene = context.scene
    for o in objects_with_role(scene, "seamlines"):
        ids = json.loads(o.get("ease_ids", "[]"))
        if not scene.ease.design_json or not ids:
            continue
        # The cut's embedding holds for every shape and pose: move the lines with
        # the cached cut (no re-cut while a slider is dragged).
        cut = next(iter(state.CUTS.values()), None)
        if cut is None or cut.embedding.shape[1] != len(verts):
            # no cut yet, or one made on another body model (a body file replaced it)
            try:
                cut = data.current_cut(context)
            except state.USER_ERRORS:
                continue
            if cut.embedding.shape[1] != len(verts):
                continue
        pos = cut.positions(verts)
        v, _ = convert.polyline_edges([pos[np.asarray(l)] for l in ids], closed=True)
        if len(v) == len(o.data.vertices):
            convert.set_vertices(o.data, v)
    for o in objects_with_role(scene, "keypoints"):
        _, pts = data.keypoint_positions(obj, verts)
        if len(pts) == len(o.data.vertices):
            convert.set_vertices(o.data, pts)


# ----------------------------------------------------------------------------- ease layer

def refresh_legend(scene) -> None:
    """The ease legend of the Ease panel, from the ramp range (update of Ramp min/max)."""
    s = scene.ease
    s.legend.clear()
    lo, hi = float(s.ease_min), float(s.ease_max)
    if not lo < hi:
        return
    for e, rgba in ramp.legend(lo, hi, 5):
        item = s.legend.add()
        item.ease = e
        item.color = rgba


def init_ease_layer(scene, obj, ease: float = 1.0) -> None:
    """Create the "ease" layer on a body (uniform ``ease``) unless it has one."""
    lo, hi = data.ramp_range(scene)
    if obj.data.color_attributes.get(convert.EASE_LAYER) is None:
        convert.ensure_color_layer(obj.data, fill=ramp.ease_to_color(ease, lo, hi))
    else:
        convert.ensure_color_layer(obj.data)
    obj.data["ease_ramp"] = [lo, hi]
    refresh_legend(scene)


# ----------------------------------------------------------------------------- design

def fill_params(scene, design) -> None:
    """Show the design's parameters as the Parameters sliders."""
    with filling():
        coll = scene.ease.design_params
        coll.clear()
        for name, p in design.parameters.items():
            item = coll.add()
            item.name = name
            item.kind = p.kind
            item.min = -1e9 if p.min is None else p.min
            item.max = 1e9 if p.max is None else p.max
            item.value = p.value


def set_design(context, design, recut: bool = True, fill_params_too: bool = True) -> None:
    """Make ``design`` the scene's design: cut it on the body (errors raise
    before anything changes), store its JSON, redraw seamlines and keypoints."""
    from ..core.design import load_design
    design = load_design(design.to_json() if hasattr(design, "to_json") else design)
    obj = data.body_object(context)
    cut = data.cut_for(design, obj) if recut else None
    model = state.body_model(data.body_spec(obj)["model"])
    verts = convert.get_vertices(obj.data)
    kps = data.resolved_keypoints(design, model, verts)
    # -- the scene changes from here on
    scene = context.scene
    scene.ease.design_json = json.dumps(design.to_json(), sort_keys=True)
    if fill_params_too:   # not from a parameter slider's own update: its collection must stay put
        fill_params(scene, design)
    convert.write_keypoints(obj.data, kps)
    build.keypoint_markers(scene, *data.keypoint_positions(obj, verts))
    if cut is not None:
        build.seamlines(scene, cut, verts)
        names = [p.name for p in cut.panels]
        if scene.ease.ease_panel not in names:
            scene.ease.ease_panel = names[0] if names else ""


def param_changed(item, context) -> None:
    """Live re-cut when a parameter slider moves (errors go to the status text)."""
    if SYNCING or not context.scene.ease.live_recut:
        return
    try:
        d = data.current_design(context)
        d.set_parameter(item.name, data.as_typed(item.value))
        set_design(context, d, fill_params_too=False)
    except state.USER_ERRORS as exc:
        context.scene.ease.drape_status = f"re-cut failed: {exc}"
        print(f"[ease] re-cut failed: {exc}")


def fill_design_props(scene, design) -> None:
    """Show a loaded design's settings in the panels: seam gathering (Pattern), stretch
    tolerance (Fit), seam allowance, hem and notch spacing (Render & Export)."""
    from ..core.design.materials import Materials
    m = Materials.of(design)
    s = scene.ease
    s.gather_auto = m.gather_above is not None
    if m.gather_above is not None:
        s.gather_above_pct = 100.0 * float(m.gather_above)
    s.tolerance = m.eps_weft
    s.export_allowance_cm = 100.0 * m.allowances["default"]
    s.export_hem_cm = 100.0 * m.allowances["hem"]
    s.export_notch_cm = 100.0 * m.notch_spacing


# ----------------------------------------------------------------------------- pattern and garment

def store_pattern(scene, pattern, key: str = data.PATTERN_KEY, text=None) -> None:
    """Keep the whole pattern (pattern.json) in a scene property (saved in the .blend).

    ``text``: the pattern's stored text when the caller has it already (the live loop
    encodes it a piece at a time); otherwise it is encoded here.
    """
    if text is None:
        from ..core.fileio import dumps_json
        from ..core.pattern.io import pattern_to_json
        text = dumps_json(pattern_to_json(pattern), indent=None)
    scene[key] = text
    state.PATTERNS[(scene.name, key)] = (text, pattern)


def show_pattern(context, pattern, store_as: str = data.PATTERN_KEY) -> None:
    """Make ``pattern`` the scene's pattern: its pieces beside the body, its key figures."""
    lo, hi = data.ramp_range(context.scene)
    # widen the display range to the achieved scales (robust percentiles; degenerate slivers aside)
    w = np.concatenate([np.asarray(p.achieved_weft, dtype=float) for p in pattern.panels])
    lo = max(ramp.EASE_LIMITS[0], min(lo, float(np.percentile(w, 1))))
    hi = min(ramp.EASE_LIMITS[1], max(hi, float(np.percentile(w, 99))))
    body = context.scene.ease.body
    x0 = 0.45
    if body is not None:
        x0 = float(world_bounds(body)[1][0]) + 0.35
    build.update_pattern_objects(context.scene, pattern, lo, hi, x0)
    store_pattern(context.scene, pattern, store_as)
    context.scene.ease.pattern_json = json.dumps(data.key_figures(pattern))


def apply_fitmap(scene) -> None:
    """Colour the garment by the chosen fit map (or the plain fabric): update of Fit map."""
    layer = build.FIT_MAPS.get(scene.ease.fitmap)
    for obj in objects_with_role(scene, "garment"):
        me = obj.data
        if layer is not None and me.color_attributes.get(layer) is not None:
            mat = materials.attribute(f"EASE Fit Map {layer}", layer)
            me.color_attributes.active_color = me.color_attributes[layer]
        else:
            mat = materials.fabric()
        if me.materials:
            me.materials[0] = mat
        else:
            me.materials.append(mat)
