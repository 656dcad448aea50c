"""What the scene holds, read back: getters with no side effects on the scene.

The body object and its spec, the design (``scene.ease.design_json``), its
cut (rebuilt from the design on demand and cached, it is deterministic), the
stored pattern (``scene["ease_pattern_json"]``), the ease ramp range, the
draped garment's positions. Every operator and reaction reads the scene
through here; nothing here writes to it.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np

from . import convert, ramp, state
from .objects import objects_with_role

PATTERN_KEY = "ease_pattern_json"  # scene property holding pattern.json
VERTEX_ID = "ease_vertex_id"  # garment mesh layer: the pattern's vertex id of each vertex
MOTION_GARMENT = "EASE Motion Garment"  # the garment of Drape Animation (motion_ops), what Export Alembic writes


# ----------------------------------------------------------------------------- body


def body_object(context, required: bool = True):
    """The scene's body object; None (or AddonError when ``required``) if there is none."""
    obj = context.scene.ease.body
    if obj is None or obj.name not in context.scene.objects:
        if required:
            raise state.AddonError("no EASE body in the scene: add one in EASE > Body first")
        return None
    return obj


def body_spec(obj) -> dict:
    """``{"model", "shape", "pose"}`` stored on the body object."""
    return {
        "model": obj.get("ease_model", "anny"),
        "shape": convert.load_json(obj, "ease_shape", {}) or {},
        "pose": obj.get("ease_pose", "A"),
    }


def keypoint_positions(obj, verts) -> tuple:
    """(names, (K, 3) positions) of the keypoints stored on the body mesh, on vertices ``verts``."""
    from ..core.body.model import SurfacePoint

    kps = convert.read_keypoints(obj.data)
    faces = state.body_model(body_spec(obj)["model"]).faces  # (the body mesh keeps its model's triangles)
    pts = np.array([SurfacePoint(t, b).position(verts, faces) for t, b in kps.values()]).reshape(-1, 3)
    return list(kps), pts


def measurements(model, shape) -> dict:
    """Height and girths (cm) of ``model`` at ``shape`` in its reference pose."""
    from ..core.body.instance import body_instance
    from ..core.body.measure import measure

    return measure(model, body_instance(model, shape or None))


def format_measurements(m: dict) -> str:
    """One line: ``height 172.0 cm, chest 94.1 cm, ...``."""
    parts = []
    for k, v in (m or {}).items():
        parts.append(f"{k} {v:.1f} cm" if isinstance(v, (int, float)) else f"{k} {v}")
    return ", ".join(parts)


# ----------------------------------------------------------------------------- design and cut


def current_design(context):
    """The scene's design as a validated :class:`core.design.Design`."""
    from ..core.design import load_design

    text = context.scene.ease.design_json
    if not text:
        raise state.AddonError("no design loaded: load a template or a design file in EASE > Design")
    return load_design(text)


#: the Solver choice that leaves the configuration to the design (its ``"solver"`` field, else the core's default)
DESIGN_SOLVER = "design"


def solver_choice(scene):
    """The solver configuration the pattern operators pass to the core: the Solver choice, or None
    for the design's own (:func:`core.workflows.config_name` applies it)."""
    choice = scene.ease.solver_config
    return None if choice == DESIGN_SOLVER else choice


def drape_options(device: str, solver: str = "default", hold_pins: bool = False) -> dict:
    """The drape options of the Drape panel's *Device*, *Solver* (``DrapeOptions.solver``, or
    ``"default"``: none, the core's default) and *Hold Pins* (``DrapeOptions.hold_pins``), as Drape
    and Drape Animation pass them."""
    options = {"device": device}
    if solver and solver != "default":
        options["solver"] = solver
    if hold_pins:
        options["hold_pins"] = True
    return options


def design_solver(scene) -> str:
    """The configuration the scene's design names (its ``"solver"``), else the core's default: what
    the Solver choice *Design's* stands for."""
    return _design_head(scene)["solver"]


def design_chart(scene) -> str:
    """The size chart of the scene's design (its ``body.chart``, else the default chart): the chart
    of a bare size in *Transfer to Size*."""
    return _design_head(scene)["chart"]


def chart_sizes(chart: str) -> tuple:
    """The size names of ``chart`` in size order (the presets the panels offer on it)."""
    from ..core.body.sizes import chart_sizes as sizes

    return sizes(chart)


def all_sizes() -> list:
    """Every size name of every chart, in size order (the default chart's first, then what the
    others add: XS .. 4XL)."""
    from ..core.body.sizes import CHARTS

    return list(dict.fromkeys(z for c in CHARTS.values() for z in c.sizes))


def nearest_size(size: str, chart: str) -> str:
    """``size`` if ``chart`` has it, else the chart's size nearest to it in the size order of all
    charts (XS .. 4XL): the smaller one on a tie."""
    sizes = chart_sizes(chart)
    if size in sizes:
        return size
    order = all_sizes()
    at = order.index(size) if size in order else 0
    return min(sizes, key=lambda z: (abs(order.index(z) - at), order.index(z)))


def _design_head(scene) -> dict:
    """What the panels show of the scene's design on every redraw (its solver, its chart): the
    design JSON (megabytes with a painted field) is parsed once per text."""
    from ..core.body.sizes import DEFAULT_CHART
    from ..core.workflows import config_name

    text = scene.ease.design_json
    if _DESIGN_SEEN[0] != text:
        d = json.loads(text) if text else {}
        _DESIGN_SEEN[:] = [
            text,
            {"solver": config_name(d), "chart": (d.get("body") or {}).get("chart") or DEFAULT_CHART},
        ]
    return _DESIGN_SEEN[1]


_DESIGN_SEEN = [None, None]  # (design text, what _design_head read of it)


def cut_on(design, model_name: str, shape: dict):
    """The cut of ``design`` on body ``model_name`` with ``shape`` (its reference pose); cached.

    A body at the design's own shape is cut as the design says (the cut's
    ``body`` record then names the design's size, as a cut from the command
    line does), any other shape as the shape dict it is.
    """
    from ..core.body.instance import instance_shape
    from ..core.cut import cut_design

    key = (design_text(design), model_name, json.dumps(shape or {}, sort_keys=True))
    cached = state.CUTS.get(key)
    if cached is not None:
        return cached
    model = state.body_model(model_name)
    own = instance_shape(model, design.body.get("shape"))
    same = model_name == design.body.get("model", "anny") and full_shape(model, own) == full_shape(model, shape)
    cut = cut_design(design, body=model, shape=None if same else (dict(shape) if shape else None))
    state.keep_cut(key, cut)
    return cut


def design_text(design) -> str:
    """The text ``scene.ease.design_json`` holds for ``design`` (what :func:`.sync.set_design` stores)."""
    return json.dumps(design.to_json(), sort_keys=True)


_DIGESTS: list = []  # [(text, digest)] of the last design texts fingerprinted (the newest last)


def design_digest(text: str) -> str:
    """Fingerprint of a design text: which design the seamlines on the body were drawn for (the
    last few kept: a body update compares its text, megabytes, without hashing it again)."""
    text = text or ""
    for known, digest in reversed(_DIGESTS):
        if known == text:
            return digest
    digest = hashlib.sha1(text.encode("utf-8")).hexdigest()
    _DIGESTS[:] = _DIGESTS[-2:] + [(text, digest)]
    return digest


def cached_cut(text: str, model_name: str):
    """The cached cut of the design ``text`` (:func:`design_text`) on body model ``model_name``, on
    any shape (the cut's embedding holds for every shape and pose); None when there is none."""
    for (d, m, _shape), cut in list(state.CUTS.items()):  # (a snapshot: a worker may add one)
        if d == text and m == model_name:
            return cut
    return None


def full_shape(model, shape) -> dict:
    """Every shape parameter of ``model``: its defaults where ``shape`` has none."""
    full = {k: float(v) for k, v in model.default_shape().items()}
    full.update({k: float(v) for k, v in (shape or {}).items()})
    return full


def cut_for(design, obj):
    """Cut ``design`` on the scene body's shape (the pose is the design's reference pose)."""
    spec = body_spec(obj)
    return cut_on(design, spec["model"], spec["shape"])


def current_cut(context):
    return cut_for(current_design(context), body_object(context))


def resolved_keypoints(design, model, verts) -> dict:
    """``{name: (triangle, bary)}`` of every design keypoint (landmarks,
    surface points, placements, traced lengths, ring points) resolved on the
    body instance ``verts`` by the core's resolver."""
    from ..core.design.resolve import Resolver

    pts = Resolver(design, model, verts).all_keypoints()
    return {n: (int(sp.triangle), tuple(float(b) for b in sp.bary)) for n, sp in pts.items()}


def template_dir():
    """The folder of the design templates shipped with the core."""
    from ..core.design.templates import template_dir as _dir

    return _dir()


_TEMPLATE_ITEMS = []


def template_items():
    """Enum items of the template files (Blender keeps only references to the strings:
    they are held in a module list)."""
    d = template_dir()
    files = sorted(p.name for p in d.glob("*.json")) if d.is_dir() else []
    _TEMPLATE_ITEMS[:] = [(f, f[:-5].replace("_", " "), f"template {f}") for f in files] or [
        ("NONE", "(no templates)", f"{d} has no designs")
    ]
    return _TEMPLATE_ITEMS


# ----------------------------------------------------------------------------- values


def as_typed(value) -> float:
    """The value of a single-precision Blender float property as the user typed it: the
    shortest decimal that reads back as the same float32 (0.9, not 0.8999999761581421)."""
    return float(str(np.float32(value)))


# ----------------------------------------------------------------------------- files


def output_path(path: str, setting: str) -> str:
    """The absolute file or folder ``path`` of the panel setting ``setting`` ("Render to",
    "Export to"); AddonError when it is empty, or relative to the .blend (``//``) while the
    .blend is not saved (Blender would resolve it against the current directory)."""
    import bpy

    if not path:
        raise state.AddonError(f"set {setting} first (EASE > Render & Export)")
    if path.startswith("//") and not bpy.data.filepath:
        raise state.AddonError(
            f"{setting} {path} is relative to the .blend file, which is not saved: "
            f"save the file first or set an absolute path (EASE > Render & Export)"
        )
    return bpy.path.abspath(path)


# ----------------------------------------------------------------------------- ease ramp


def ramp_range(scene) -> tuple:
    """(lo, hi) of the scene's ease ramp; AddonError when it is not a valid range."""
    s = scene.ease
    # the properties are single precision: 0.9 reads 0.8999999761581421; the user set 0.9
    lo, hi = as_typed(s.ease_min), as_typed(s.ease_max)
    try:
        ramp.check_range(lo, hi)
    except ValueError as exc:
        raise state.AddonError(str(exc)) from None
    return lo, hi


# ----------------------------------------------------------------------------- pattern and garment


def required_pattern(scene, to: str):
    """The scene's pattern, or AddonError saying what it is needed ``to`` do (``"to export"``)."""
    pattern = stored_pattern(scene)
    if pattern is None:
        raise state.AddonError(f"no pattern {to}: optimize the pattern first (EASE > Pattern)")
    return pattern


def stored_pattern(scene, key: str = PATTERN_KEY):
    """The pattern kept in the scene (None if there is none); parsed once per text."""
    from ..core.pattern.io import pattern_from_json

    text = scene.get(key)
    if not text:
        return None
    cached = state.PATTERNS.get((scene.name, key))
    if cached is not None and cached[0] == text:
        return cached[1]
    p = pattern_from_json(json.loads(text))
    state.PATTERNS[(scene.name, key)] = (text, p)
    return p


def pattern_digest(text: str) -> str:
    """Fingerprint of a stored pattern (which pattern a garment was draped from)."""
    return hashlib.sha1(text.encode("utf-8")).hexdigest()


def key_figures(pattern) -> dict:
    """The report's key figures (SPEC metrics) for the Pattern panel."""
    out = {"pieces": len(pattern.panels), "seams": len(pattern.seams), "mode": pattern.mode}
    rep = pattern.report or {}
    m = rep.get("metrics") or {}
    c, sm = m.get("compliance") or {}, m.get("seams") or {}
    for label, d, k in (
        ("ease compliance mean %", c, "mean"),
        ("ease compliance std %", c, "std"),
        ("warp deviation mean %", c, "warp_mean"),
        ("warp deviation signed %", c, "warp_signed"),
        ("shear p95 deg", c, "shear_p95"),
        ("seam mismatch mean %", sm, "mean"),
        ("seam mismatch max mm", sm, "max_mm"),
    ):
        if isinstance(d.get(k), (int, float)):
            out[label] = round(float(d[k]), 3)
    if sm.get("gathered"):
        out["gathered seams"] = len(sm["gathered"])
    if "flipped_triangles" in m:
        out["flipped triangles"] = int(m["flipped_triangles"])
    if "collapsed_triangles" in m:
        out["collapsed triangles"] = int(m["collapsed_triangles"])
    if "crossings" in m:
        out["crossings"] = int(m["crossings"])
    for name, r in sorted((m.get("regions") or {}).items()):
        # compliance near a landmark (weft / warp %), where fit fails first
        out[f"{name.replace('_', ' ')} % (weft / warp)"] = f"{float(r['mean']):.2f} / {float(r['warp_mean']):.2f}"
    if isinstance(rep.get("optimize_seconds"), (int, float)):
        out["optimize s"] = round(float(rep["optimize_seconds"]), 2)
    return out


def garment_positions(scene):
    """``(positions, None)`` of the draped garment by pattern vertex id, or ``(None, why)``."""
    garments = objects_with_role(scene, "garment")
    if not garments:
        return None, "no draped garment: drape first (EASE > Drape)"
    obj = garments[0]
    if obj.get("ease_pattern") != pattern_digest(scene.get(PATTERN_KEY, "")):
        return None, "the draped garment is from another pattern: drape the current pattern again"
    layer = obj.data.attributes.get(VERTEX_ID)
    if layer is None or layer.domain != "POINT" or len(obj.data.vertices) == 0:
        return None, "the garment object has no pattern vertex ids: drape again"
    ids = np.empty(len(obj.data.vertices), dtype=np.int32)
    layer.data.foreach_get("value", ids)
    co = convert.get_vertices(obj.data)
    m = np.array(obj.matrix_world, dtype=np.float64)
    co = co @ m[:3, :3].T + m[:3, 3]
    pos = np.full((int(ids.max()) + 1, 3), np.nan)
    pos[ids] = co
    return pos, None


def design_with_materials(design, **edits):
    """``design`` with its materials edited as the panels say (see
    :meth:`core.design.materials.Materials.edit`: validated, written only where
    they differ from what the design does now); ``design`` itself when nothing changes."""
    from ..core.design import load_design
    from ..core.design.materials import Materials

    materials = Materials.edit(design.materials, **edits)
    if materials == design.materials:
        return design
    d = design.to_json()
    d["materials"] = materials
    return load_design(d)  # DesignError names the field of an invalid value


def prepared(context, edit=None):
    """The scene's design (``edit(design)`` if given: the panels' settings) cut on the
    scene body, ready for the core's pattern workflows (:class:`core.workflows.Prepared`)."""
    return prepare(*preparing(context, edit))


def preparing(context, edit=None) -> tuple:
    """The main thread's half of :func:`prepared`: what it reads from the scene, ``(design, body
    spec)``; :func:`prepare` (no ``bpy``: a worker may run it) cuts and prepares it."""
    design = current_design(context)
    return (design if edit is None else edit(design)), body_spec(body_object(context))


def prepare(design, spec: dict):
    """``design`` cut on the body ``spec`` (cached) and prepared for the core's pattern workflows
    (:class:`core.workflows.Prepared`); no ``bpy``."""
    from ..core import workflows as wf

    return wf.prepare(design, body=state.body_model(spec["model"]), cut=cut_on(design, spec["model"], spec["shape"]))


# ----------------------------------------------------------------------------- the painted ease field


def layer_range(obj, scene) -> tuple:
    """The ramp range the layer was painted with (stored on the mesh); the
    scene's range for a layer that has none yet."""
    r = obj.data.get("ease_ramp")
    if r is not None and len(r) == 2:
        return float(r[0]), float(r[1])
    return ramp_range(scene)


def vertex_ease(obj, scene) -> np.ndarray:
    """Per-vertex ease (V,) decoded from the layer (corner layers are averaged per vertex)."""
    lo, hi = layer_range(obj, scene)
    me = obj.data
    colors, domain = convert.read_colors(me, convert.EASE_LAYER)
    e = ramp.color_to_ease(colors, lo, hi)
    if domain == "CORNER":
        vi = np.empty(len(me.loops), dtype=np.int32)
        me.loops.foreach_get("vertex_index", vi)
        acc = np.bincount(vi, weights=e, minlength=len(me.vertices))
        cnt = np.bincount(vi, minlength=len(me.vertices))
        e = np.where(cnt > 0, acc / np.maximum(cnt, 1), 1.0)
    return e


def triangle_ease(obj, scene) -> np.ndarray:
    """Per-triangle ease (F,) of the body from its layer: the mean of the
    triangle's vertex (or corner) values, so a uniformly painted area reads
    back exactly the value the brush used."""
    lo, hi = layer_range(obj, scene)
    me = obj.data
    colors, domain = convert.read_colors(me, convert.EASE_LAYER)
    e = ramp.color_to_ease(colors, lo, hi)
    if domain == "CORNER":
        return e.reshape(-1, 3).mean(axis=1)
    return ramp.vertex_to_triangle(e, convert.get_triangles(me))


def template_rows(cut, panel) -> tuple:
    """(rows, template vertex ids): the panel's vertices that are template vertices of the body
    (rows of the embedding with a single weight: inside the panel or on its seam)."""
    emb = cut.embedding[panel.vertex_ids].tocsr()
    single = np.flatnonzero(np.diff(emb.indptr) == 1)
    return single, emb.indices[emb.indptr[single]]


def x_mirror(obj) -> bool:
    """Blender's own X-mirror setting of the paint modes: the body mesh's ``use_mirror_x``
    (the X toggle of Vertex Paint's and Sculpt's Symmetry popover; the tool settings'
    ``use_symmetry_x`` are legacy and not what the header shows)."""
    return bool(getattr(obj.data, "use_mirror_x", False))


def symmetrised(obj, tri_ease: np.ndarray) -> np.ndarray:
    """``tri_ease`` (F,) averaged with its mirror image through the body's symmetry map
    (triangles without a mirror triangle keep their value)."""
    from ..core.design.mirror import face_symmetry

    model = state.body_model(body_spec(obj)["model"])
    fs = face_symmetry(convert.get_triangles(obj.data), np.asarray(model.symmetry))
    out = np.asarray(tri_ease, dtype=np.float64).copy()
    has = fs >= 0
    out[has] = 0.5 * (out[has] + out[fs[has]])
    return out


def design_vertex_ease(context) -> np.ndarray:
    """Per body vertex ease (V,) of the design's cut (mean of the cut triangles'
    ease around each template vertex; 1.0 off the garment)."""
    obj = body_object(context)
    cut = current_cut(context)
    V = len(obj.data.vertices)
    acc = np.zeros(V)
    cnt = np.zeros(V)
    for p in cut.panels:
        f = np.asarray(p.faces)
        ev = np.zeros(len(p.vertex_ids))
        cv = np.zeros(len(p.vertex_ids))
        np.add.at(ev, f.ravel(), np.repeat(np.asarray(p.ease, dtype=float), 3))
        np.add.at(cv, f.ravel(), 1.0)
        single, cols = template_rows(cut, p)
        np.add.at(acc, cols, ev[single] / np.maximum(cv[single], 1))
        np.add.at(cnt, cols, 1.0)
    return np.where(cnt > 0, acc / np.maximum(cnt, 1), 1.0)


def element_mirror(me, symmetry) -> np.ndarray:
    """The mirror element of every element of the ease layer (V,) or (3F,) through the body's
    vertex symmetry map: a vertex's mirror vertex; a face corner's corner of the mirror face at
    the mirror vertex (-1 where the face has no mirror face)."""
    from ..core.design.mirror import face_symmetry

    sym = np.asarray(symmetry)
    if me.color_attributes[convert.EASE_LAYER].domain == "POINT":
        return sym
    faces = convert.get_triangles(me)
    fs = face_symmetry(faces, sym)
    target = sym[faces]  # (F, 3) the mirror vertex of each corner
    other = faces[np.maximum(fs, 0)]  # (F, 3) the mirror face's corners
    j = np.argmax(target[:, :, None] == other[:, None, :], axis=2)
    out = 3 * np.maximum(fs, 0)[:, None] + j
    out[fs < 0] = -1
    return out.ravel()


SEEN_LAYER = "ease_seen"  # FLOAT layer beside "ease": its values when the add-on last read or wrote it


def seen_ease(obj):
    """The ease layer's values (per element) when the add-on last took them (Ease to Design, Ease
    from Design, a Live tick: :func:`.sync.remember_layer`); None when there is no such record of
    this layer's shape. What changed since is a stroke (X-mirror mirrors one-sided strokes)."""
    me = obj.data
    seen, layer = me.attributes.get(SEEN_LAYER), me.color_attributes.get(convert.EASE_LAYER)
    if seen is None or layer is None or seen.domain != layer.domain or seen.data_type != "FLOAT":
        return None
    v = np.empty(len(seen.data), dtype=np.float32)
    seen.data.foreach_get("value", v)
    return v.astype(np.float64)


def layer_ease(obj, scene) -> np.ndarray:
    """The ease layer's values per element (a vertex or a face corner, as the layer is)."""
    colors, _domain = convert.read_colors(obj.data, convert.EASE_LAYER)
    return ramp.color_to_ease(colors, *layer_range(obj, scene))
