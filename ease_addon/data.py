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

PATTERN_KEY = "ease_pattern_json"   # scene property holding pattern.json
VERTEX_ID = "ease_vertex_id"        # garment mesh layer: the pattern's vertex id of each vertex


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
    return {"model": obj.get("ease_model", "anny"),
            "shape": convert.load_json(obj, "ease_shape", {}) or {},
            "pose": obj.get("ease_pose", "A")}


def keypoint_positions(obj, verts) -> tuple:
    """(names, (K, 3) positions) of the keypoints stored on the body mesh, on vertices ``verts``."""
    from ..core.body.model import SurfacePoint
    kps = convert.read_keypoints(obj.data)
    faces = convert.get_triangles(obj.data)
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


def design_solver(scene) -> str:
    """The configuration the scene's design names (its ``"solver"``), else the core's default: what
    the Solver choice *Design's* stands for. The panel asks on every redraw: the design JSON (megabytes
    with a painted field) is parsed once per text."""
    from ..core.workflows import config_name
    text = scene.ease.design_json
    if _SOLVER_SEEN[0] != text:
        _SOLVER_SEEN[:] = [text, config_name(json.loads(text) if text else {})]
    return _SOLVER_SEEN[1]


_SOLVER_SEEN = [None, None]     # (design text, its configuration) of the last design_solver call


def cut_on(design, model_name: str, shape: dict):
    """The cut of ``design`` on body ``model_name`` with ``shape`` (its reference pose); cached.

    A body at the design's own shape is cut as the design says (the cut's
    ``body`` record then names the design's size, as a cut from the command
    line does), any other shape as the shape dict it is.
    """
    from ..core.body.instance import instance_shape
    from ..core.cut import cut_design
    key = json.dumps([design.to_json(), model_name, shape or {}], sort_keys=True)
    cached = state.CUTS.get(key)
    if cached is not None:
        return cached
    model = state.body_model(model_name)
    own = instance_shape(model, design.body.get("shape"))
    same = model_name == design.body.get("model", "anny") and _full(model, own) == _full(model, shape)
    cut = cut_design(design, body=model, shape=None if same else (dict(shape) if shape else None))
    state.CUTS.clear()        # one cut per session is plenty; keeps memory bounded
    state.CUTS[key] = cut
    return cut


def _full(model, shape) -> dict:
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
    _TEMPLATE_ITEMS[:] = [(f, f[:-5].replace("_", " "), f"template {f}") for f in files] or \
        [("NONE", "(no templates)", f"{d} has no designs")]
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
        raise state.AddonError(f"{setting} {path} is relative to the .blend file, which is not saved: "
                               f"save the file first or set an absolute path (EASE > Render & Export)")
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
    for label, d, k in (("ease compliance mean %", c, "mean"), ("ease compliance std %", c, "std"),
                        ("warp deviation mean %", c, "warp_mean"), ("warp deviation signed %", c, "warp_signed"),
                        ("shear p95 deg", c, "shear_p95"), ("seam mismatch mean %", sm, "mean"),
                        ("seam mismatch max mm", sm, "max_mm")):
        if isinstance(d.get(k), (int, float)):
            out[label] = round(float(d[k]), 3)
    if sm.get("gathered"):
        out["gathered seams"] = len(sm["gathered"])
    if "flipped_triangles" in m:
        out["flipped triangles"] = int(m["flipped_triangles"])
    if "collapsed_triangles" in m:
        out["collapsed triangles"] = int(m["collapsed_triangles"])
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
    return load_design(d)       # DesignError names the field of an invalid value


def prepared(context, edit=None):
    """The scene's design (``edit(design)`` if given: the panels' settings) cut on the
    scene body, ready for the core's pattern workflows (:class:`core.workflows.Prepared`)."""
    from ..core import workflows as wf
    obj = body_object(context)
    design = current_design(context)
    if edit is not None:
        design = edit(design)
    return wf.prepare(design, body=state.body_model(body_spec(obj)["model"]), cut=cut_for(design, obj))
