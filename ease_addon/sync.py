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
from .objects import objects_with_role, remove_object, select_only, world_bounds

SYNCING = False  # True while the add-on fills the sliders (their update callbacks must not fire)


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


def show_size(scene, obj, size, report=None) -> None:
    """The Body panel and the body say which chart size the body has: ``size`` (``"M"``,
    ``"women:M"``) sets the chart selector, the size preset and the body's ``ease_size``;
    None (a shape of no chart size) clears the body's record. The measurements follow
    (``report``: their line, :func:`measurements_report`, when a worker measured them)."""
    from ..core.body.sizes import split_size

    s = scene.ease
    if size is None:
        if "ease_size" in obj:
            del obj["ease_size"]
    else:
        chart, key = split_size(size)
        s.chart = chart.name
        s.size = key
        obj["ease_size"] = size
    spec = data.body_spec(obj)
    s.measurements_report = measurements_report(spec) if report is None else report


def measurements_report(spec: dict) -> str:
    """The Body panel's measurements line of the body spec ``spec`` (no ``bpy``: a worker may
    measure)."""
    return data.format_measurements(data.measurements(state.body_model(spec["model"]), spec["shape"]))


def chart_changed(scene) -> None:
    """Update of the chart selector: the size preset stays one of the chart's (the nearest
    one where the chart has no such size)."""
    s = scene.ease
    s.size = data.nearest_size(s.size, s.chart)


def body_vertices(spec: dict) -> np.ndarray:
    """Vertices of the body spec ``{"model", "shape", "pose"}`` (the core's body instance)."""
    from ..core.body.instance import body_instance

    return body_instance(state.body_model(spec["model"]), spec["shape"] or None, spec["pose"])


def update_body(context, obj, shape=None, pose=None, verts=None) -> None:
    """Set the body's shape and/or pose: vertices move in place, attached
    objects (seamlines, keypoint markers) follow. Computes first, so a bad
    shape/pose raises before the scene changes (``verts``: the new spec's
    :func:`body_vertices` when the caller computed them, in a worker)."""
    spec = data.body_spec(obj)
    if shape is not None:
        spec["shape"] = {k: float(v) for k, v in shape.items()}
    if pose is not None:
        spec["pose"] = pose
    verts = body_vertices(spec) if verts is None else verts
    convert.set_vertices(obj.data, verts)
    convert.store_json(obj, "ease_shape", spec["shape"])
    obj["ease_pose"] = spec["pose"]
    state.changed(context.scene)  # (Live: a slider's update runs no operator)
    if shape is not None:
        # a shape of its own: no chart size, measurements not taken yet (a caller that knows says so after)
        if "ease_size" in obj:
            del obj["ease_size"]
        context.scene.ease.measurements_report = ""
    refresh_attachments(context, obj, verts)


def new_body(context, model_name: str, shape=None, pose: str = "A", replaces=None, verts=None, report=None):
    """Add a body object and make it the scene's body (shape sliders, ease layer, selection);
    ``replaces``: the body it replaces, removed once the new one is computed (so the new one
    takes its name, with no ``.001``); ``verts``, ``report``: its vertices and measurements line
    (:func:`measurements_report`) when a worker computed them."""
    model = state.body_model(model_name)
    shape = dict(model.default_shape() if shape is None else shape)
    verts = body_vertices({"model": model_name, "shape": shape, "pose": pose}) if verts is None else verts
    scene = context.scene
    if replaces is not None:
        remove_object(replaces)
    obj = build.body(scene, "EASE Body", verts, model.faces)
    obj["ease_model"] = model_name
    convert.store_json(obj, "ease_shape", shape)
    obj["ease_pose"] = pose
    scene.ease.body = obj
    fill_shape_props(scene, model, shape)
    if shape == dict(model.default_shape()) and model_name == "anny":
        show_size(scene, obj, "M", report)  # Anny's reference shape is the default chart's M
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
    # the local changes a made-to-measure fit gave (no slider of their own) stay
    shape = {**{k: v for k, v in data.body_spec(obj)["shape"].items() if k not in shape}, **shape}
    try:
        update_body(context, obj, shape=shape)
    except Exception as exc:  # a slider must never leave a traceback in the UI
        print(f"[ease] shape update failed: {exc}")


def refresh_attachments(context, obj, verts) -> None:
    """Move the seamlines and keypoint markers onto the body's current vertices.

    Seamlines follow only when they were drawn for the scene's design (their ``ease_design``
    fingerprint): lines of another design (a design being replaced: :func:`set_design` redraws
    them next) or that do not fit the cut are left alone, never indexed with another cut's ids.
    """
    scene = context.scene
    text = scene.ease.design_json
    for o in objects_with_role(scene, "seamlines"):
        ids = json.loads(o.get("ease_ids", "[]"))
        digest = data.design_digest(text)
        if not text or not ids or o.get("ease_design", digest) != digest:  # (lines of older files: unstamped)
            continue
        # The cut's embedding holds for every shape and pose: move the lines with
        # the cached cut of this design (no re-cut while a slider is dragged).
        cut = data.cached_cut(text, data.body_spec(obj)["model"])
        if cut is None:
            try:
                cut = data.current_cut(context)
            except state.USER_ERRORS:
                continue
        if cut.embedding.shape[1] != len(verts):
            continue
        pos = cut.positions(verts)
        if max(max(l) for l in ids) >= len(pos):
            continue
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


MIRROR_TOL = 1e-4  # ease: a layer element differing from before by more was painted


def mirror_stroke(obj, scene, before) -> int:
    """X-mirror as Blender's own paint mirror does it: where the ease layer differs from ``before``
    (its values per element, :func:`.data.layer_ease`) on one side only, the stroke is painted on
    the mirror side too (the colours copied, so both sides hold what the brush put down, not an
    average with what was there). Where both sides changed (Blender's mirrored stroke) the layer
    is left as it is. Returns how many elements were written."""
    me = obj.data
    now = data.layer_ease(obj, scene)
    before = np.asarray(before, dtype=np.float64)
    if before.shape != now.shape:
        return 0
    mirror = data.element_mirror(me, state.body_model(data.body_spec(obj)["model"]).symmetry)
    changed = np.abs(now - before) > MIRROR_TOL
    has = mirror >= 0
    one = changed & has
    one[has] &= ~changed[mirror[has]]
    if not one.any():
        return 0
    attr = me.color_attributes[convert.EASE_LAYER]
    colors = np.empty(len(attr.data) * 4, dtype=np.float32)
    attr.data.foreach_get("color", colors)
    colors = colors.reshape(-1, 4)
    colors[mirror[one]] = colors[one]
    attr.data.foreach_set("color", colors.ravel())
    me.update()
    return int(one.sum())


DESIGN_LAYER = "ease_design"  # FLOAT layer beside "ease": its values when the design's ease was last
# written into it (Ease from Design, a template load) or taken from it (Ease to Design)


def remember_layer(obj, scene, design: bool = False) -> None:
    """Record the ease layer's values as taken now (:func:`.data.seen_ease`): strokes are what
    differs from them later. With ``design``, also as the design's ease (:func:`design_record`):
    what Live paints on is what differs from that."""
    me = obj.data
    e = data.layer_ease(obj, scene).astype(np.float32)
    layer = me.color_attributes[convert.EASE_LAYER]
    for name in (data.SEEN_LAYER, DESIGN_LAYER) if design else (data.SEEN_LAYER,):
        rec = me.attributes.get(name)
        if rec is None or rec.domain != layer.domain or rec.data_type != "FLOAT":
            if rec is not None:
                me.attributes.remove(rec)
            rec = me.attributes.new(name, "FLOAT", layer.domain)
        rec.data.foreach_set("value", e)


def design_record(obj):
    """The ease layer's values (per element, float64) when the design's ease was last written into
    it or taken from it (:func:`remember_layer` with ``design``); None without such a record of
    this layer's shape (a layer painted before the design, an older file)."""
    me = obj.data
    rec, layer = me.attributes.get(DESIGN_LAYER), me.color_attributes.get(convert.EASE_LAYER)
    if rec is None or layer is None or rec.domain != layer.domain or rec.data_type != "FLOAT":
        return None
    if len(rec.data) != len(layer.data):
        return None
    v = np.empty(len(rec.data), dtype=np.float32)
    rec.data.foreach_get("value", v)
    return v.astype(np.float64)


def mirrored_paint(obj, scene) -> int:
    """With X-mirror on: the strokes since the layer was last taken (:func:`.data.seen_ease`) that
    reached one side only are painted on the other side too (:func:`mirror_stroke`); 0 (nothing
    written) with X-mirror off or no record."""
    before = data.seen_ease(obj)
    if not data.x_mirror(obj) or before is None:
        return 0
    return mirror_stroke(obj, scene, before)


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


def set_design(context, design, recut: bool = True, fill_params_too: bool = True, keypoints=None) -> None:
    """Make ``design`` the scene's design: cut it on the body (errors raise
    before anything changes), store its JSON, redraw seamlines and keypoints
    (``keypoints``: :func:`.data.resolved_keypoints` on the body as it is, when
    the caller resolved them, in a worker)."""
    from ..core.design import load_design

    design = load_design(design.to_json() if hasattr(design, "to_json") else design)
    obj = data.body_object(context)
    cut = data.cut_for(design, obj) if recut else None
    model = state.body_model(data.body_spec(obj)["model"])
    verts = convert.get_vertices(obj.data)
    kps = data.resolved_keypoints(design, model, verts) if keypoints is None else keypoints
    # -- the scene changes from here on
    scene = context.scene
    scene.ease.design_json = data.design_text(design)
    state.changed(scene)
    if fill_params_too:  # not from a parameter slider's own update: its collection must stay put
        fill_params(scene, design)
    # the Fit panel offers the design's chart's sizes: the target is one of them
    scene.ease.fit_size = data.nearest_size(scene.ease.fit_size, data.design_chart(scene))
    convert.write_keypoints(obj.data, kps)
    build.keypoint_markers(scene, *data.keypoint_positions(obj, verts))
    if cut is not None:
        build.seamlines(scene, cut, verts, data.design_digest(scene.ease.design_json))
        names = [p.name for p in cut.panels]
        if scene.ease.ease_panel not in names:
            scene.ease.ease_panel = names[0] if names else ""


def param_changed(item, context) -> None:
    """Live re-cut when a parameter slider moves. A value the design refuses (out of range, a cut
    that fails) is not kept: the slider goes back to the design's value and the error shows under
    the Parameters, naming the parameter."""
    s = context.scene.ease
    if SYNCING or not s.live_recut:
        return
    try:
        d = data.current_design(context)
        d.set_parameter(item.name, data.as_typed(item.value))
        set_design(context, d, fill_params_too=False)
    except state.USER_ERRORS as exc:
        refuse_param(context, item.name, exc)
        print(f"[ease] re-cut failed: {exc}")
    else:
        s.design_status = ""


def refuse_param(context, name, exc) -> None:
    """A parameter value was refused with ``exc`` (``name``: the parameter's, None for a cut of
    several that failed): the sliders show the design's values again (in place: this may run in
    a slider's own update) and the Design panel says why, naming the parameter and the value tried."""
    s = context.scene.ease
    item = s.design_params.get(name) if name else None
    tried = None if item is None else data.as_typed(item.value)
    try:
        params = data.current_design(context).parameters
    except state.USER_ERRORS:
        params = {}
    with filling():
        for i in s.design_params:
            if i.name in params and data.as_typed(i.value) != params[i.name].value:
                i.value = params[i.name].value
    s.design_status = f"{name} = {tried:g} refused: {exc}" if tried is not None else str(exc)


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


PIECES_GAP = 0.35  # metres between the body's right side and the pieces' sheet
PIECES_X0 = 0.45  # the sheet's left edge with no body


def pieces_x0(scene) -> float:
    """Where the pieces' sheet starts (x, metres): beside the body, else at :data:`PIECES_X0`."""
    body = scene.ease.body
    return float(world_bounds(body)[1][0]) + PIECES_GAP if body is not None else PIECES_X0


def shown_range(scene) -> tuple:
    """The ramp range ``(lo, hi)`` the scene's pieces are coloured with (the panel's without pieces)."""
    pieces = objects_with_role(scene, "pattern_panel")
    shown = pieces[0].data.get("ease_ramp") if pieces else None
    return (float(shown[0]), float(shown[1])) if shown is not None and len(shown) == 2 else data.ramp_range(scene)


def show_pieces(context, pattern, plan=None) -> None:
    """Move the scene's piece objects onto ``pattern`` (a re-solve of their cut: a live update),
    coloured in the range they were shown with; the stored pattern and its figures stay (``plan``:
    its :class:`.build.PatternPlan`, when a worker made it)."""
    lo, hi = shown_range(context.scene)
    build.update_pattern_objects(context.scene, pattern, lo, hi, pieces_x0(context.scene), plan=plan)


def pattern_range(ramp_range, pattern) -> tuple:
    """The ramp range a new pattern's pieces are coloured with: the panel's ``ramp_range``
    widened to the achieved scales (robust percentiles; degenerate slivers aside). No ``bpy``."""
    lo, hi = ramp_range
    w = np.concatenate([np.asarray(p.achieved_weft, dtype=float) for p in pattern.panels])
    lo = max(ramp.EASE_LIMITS[0], min(lo, float(np.percentile(w, 1))))
    hi = min(ramp.EASE_LIMITS[1], max(hi, float(np.percentile(w, 99))))
    return lo, hi


def prepared_show(pattern, ramp_range) -> dict:
    """What :func:`show_pattern` makes of ``pattern`` before writing Blender's data, made ahead
    (no ``bpy``: in the worker that solved it; the main thread's tick then only writes arrays):
    its stored text (encoded a few rows per call: the worker lets the main thread run between),
    its :class:`.build.PatternPlan` and its ramp range for the panel's ``ramp_range``.
    :func:`show_pattern`'s keywords."""
    from ..core.live import PatternText

    range_ = pattern_range(ramp_range, pattern)
    return {
        "text": PatternText().text(pattern),
        "plan": build.PatternPlan(pattern).colored(range_),
        "range_": range_,
        "ramp_range": tuple(ramp_range),
    }


def show_pattern(
    context,
    pattern,
    store_as: str = data.PATTERN_KEY,
    text=None,
    plan=None,
    made=None,
    range_=None,
    ramp_range=None,
) -> None:
    """Make ``pattern`` the scene's pattern: its pieces beside the body, its key figures
    (``text``: its stored text, ``plan``: its :class:`.build.PatternPlan`, ``range_``: its
    :func:`pattern_range`, when the caller made them already, in a worker: :func:`prepared_show`;
    ``ramp_range``: the panel's range ``range_`` was made for (another now: made again);
    ``made``: new piece meshes made in earlier ticks, :func:`.build.update_pattern_objects`)."""
    if ramp_range is not None and tuple(ramp_range) != tuple(data.ramp_range(context.scene)):
        range_ = None
    lo, hi = pattern_range(data.ramp_range(context.scene), pattern) if range_ is None else range_
    build.update_pattern_objects(context.scene, pattern, lo, hi, pieces_x0(context.scene), plan=plan, made=made)
    store_pattern(context.scene, pattern, store_as, text=text)
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


def write_vertex_ease(obj, scene, ease: np.ndarray, mask=None) -> None:
    """Write ease (V,) into the layer (only where ``mask``), re-encoding the
    rest if the scene's ramp range changed since the layer was painted. A
    face-corner layer stays one: the corners outside ``mask`` keep their own values."""
    lo, hi = data.ramp_range(scene)
    me = obj.data
    if me.color_attributes.get(convert.EASE_LAYER) is None:
        convert.ensure_color_layer(me, fill=ramp.ease_to_color(1.0, lo, hi))
    else:
        convert.adopt_ease_layer(me)
    colors, domain = convert.read_colors(me, convert.EASE_LAYER)
    vi = convert.element_vertices(me, domain)
    new = ramp.color_to_ease(colors, *data.layer_range(obj, scene))
    ease = np.broadcast_to(np.asarray(ease, dtype=np.float64), (len(me.vertices),))
    where = np.ones(len(vi), dtype=bool) if mask is None else np.asarray(mask)[vi]
    new[where] = ease[vi][where]
    if new.min() < lo - 1e-9 or new.max() > hi + 1e-9:
        raise state.AddonError(
            f"ease {new.min():.3f} .. {new.max():.3f} is outside the ramp {lo:g} .. {hi:g}: widen the ramp range first"
        )
    me.color_attributes[convert.EASE_LAYER].data.foreach_set(
        "color", ramp.ease_to_color(new, lo, hi).astype(np.float32).ravel()
    )
    me.update()
    me["ease_ramp"] = [lo, hi]


def ease_from_design(context) -> None:
    """*Ease from Design*'s work (a load calls it in its own pass: no operator call, no view-layer
    update inside a timer's call)."""
    obj = data.body_object(context)
    v = data.design_vertex_ease(context)
    lo, hi = data.ramp_range(context.scene)
    if v.min() < lo or v.max() > hi:
        s = context.scene.ease
        s.ease_min, s.ease_max = min(lo, float(v.min())), max(hi, float(v.max()))
    write_vertex_ease(obj, context.scene, v)
    remember_layer(obj, context.scene, design=True)
