"""Pattern stage: optimize the pattern of the current design and lay it out
beside the body as flat panel objects (mesh coloured by achieved ease,
boundary curve, grain-line arrow, piece name). The whole pattern is kept in a
text block ("EASE pattern.json") so it survives a save."""
from __future__ import annotations

import json

import bpy
import numpy as np

from . import convert, ramp, state
from .body_ops import body_object
from .operators_base import EaseOperator

PATTERN_KEY = "ease_pattern_json"   # scene property holding pattern.json
ACHIEVED = "achieved_ease"     # CORNER colour layer of the pattern panels (per triangle)
GAP = 0.08                     # metres between laid-out panels


# ----------------------------------------------------------------------------- pattern <-> scene

def store_pattern(scene, pattern, key: str = PATTERN_KEY) -> None:
    """Keep the whole pattern (pattern.json) in a scene property (saved in the .blend)."""
    from ..core.pattern.io import pattern_to_json
    from ..core.fileio import dumps_json
    text = dumps_json(pattern_to_json(pattern), indent=None)
    scene[key] = text
    state.PATTERNS[(scene.name, key)] = (text, pattern)


def stored_pattern(scene, key: str = PATTERN_KEY):
    """The pattern kept in the scene (None if there is none)."""
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


def key_figures(pattern) -> dict:
    """The report's key figures (SPEC metrics) for the Pattern panel."""
    out = {"pieces": len(pattern.panels), "seams": len(pattern.seams), "mode": pattern.mode}
    rep = pattern.report or {}
    m = rep.get("metrics") or {}
    c, sm = m.get("compliance") or {}, m.get("seams") or {}
    for label, d, k in (("ease compliance mean %", c, "mean"), ("ease compliance std %", c, "std"),
                        ("shear p95 deg", c, "shear_p95"), ("seam mismatch mean %", sm, "mean"),
                        ("seam mismatch max mm", sm, "max_mm")):
        if isinstance(d.get(k), (int, float)):
            out[label] = round(float(d[k]), 3)
    if sm.get("gathered"):
        out["gathered seams"] = len(sm["gathered"])
    if "flipped_triangles" in m:
        out["flipped triangles"] = int(m["flipped_triangles"])
    if isinstance(rep.get("optimize_seconds"), (int, float)):
        out["optimize s"] = round(float(rep["optimize_seconds"]), 2)
    return out


def _ease_material(name: str, layer: str):
    """A material showing the colour attribute ``layer`` (viewport and Cycles)."""
    mat = bpy.data.materials.get(name)
    if mat is not None:
        return mat
    mat = bpy.data.materials.new(name)
    convert.ensure_nodes(mat)
    nt = mat.node_tree
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    attr = nt.nodes.new("ShaderNodeAttribute")
    attr.attribute_name = layer
    attr.location = (-300, 200)
    if bsdf is not None:
        nt.links.new(attr.outputs["Color"], bsdf.inputs["Base Color"])
        bsdf.inputs["Roughness"].default_value = 0.8
    return mat


def _layout(pattern, x0: float, z_top: float) -> list:
    """Offsets (ox, oz) placing each piece's bounding box in rows beside the body."""
    offs = []
    x, z, row_h = x0, z_top, 0.0
    width = 1.6
    for p in pattern.panels:
        lo, hi = p.uv.min(axis=0), p.uv.max(axis=0)
        w, h = hi - lo
        if x > x0 and x + w > x0 + width:
            x, z, row_h = x0, z - row_h - GAP, 0.0
        offs.append((x - lo[0], z - hi[1]))
        x += w + GAP
        row_h = max(row_h, h)
    return offs


def pattern_objects(context, pattern, lo: float, hi: float, role: str = "pattern_panel",
                    x0=None) -> list:
    """Create the pattern's panel objects (replacing earlier ones of ``role``).

    Each panel is a mesh in the XZ plane (facing the camera, -Y): local
    coordinates are the pattern's 2D metres, so its dimensions are the piece's.
    """
    scene = context.scene
    coll = state.collection(scene)
    body = scene.ease.body
    if x0 is None:
        x0 = 0.45
        if body is not None:
            xs = [(body.matrix_world @ __import__("mathutils").Vector(c)).x for c in body.bound_box]
            x0 = max(xs) + 0.35
    z_top = 1.8
    old = state.objects_with_role(scene, role) + state.objects_with_role(scene, role + "_part")
    mat = _ease_material("EASE Achieved Ease", ACHIEVED)
    made = []
    for p, (ox, oz) in zip(pattern.panels, _layout(pattern, x0, z_top)):
        uv = np.asarray(p.uv, dtype=np.float64)
        v3 = np.stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]], axis=1)
        me = convert.mesh_from_arrays(f"EASE piece {p.name}", v3, p.faces)
        # colour layers live on points or corners: every corner of a triangle gets its achieved ease
        col = me.color_attributes.new(ACHIEVED, "FLOAT_COLOR", "CORNER")
        rgba = ramp.ease_to_color(np.clip(p.achieved_weft, lo, hi), lo, hi)
        col.data.foreach_set("color", np.repeat(rgba, 3, axis=0).ravel())
        me.attributes.new("achieved_weft", "FLOAT", "FACE").data.foreach_set(
            "value", np.asarray(p.achieved_weft, dtype=np.float32))
        me["ease_ramp"] = (float(lo), float(hi))     # the colours' ramp range (legend, read-back)
        me.materials.append(mat)
        obj = convert.new_object(f"EASE piece {p.name}", me, coll)
        obj.location = (ox, 0.0, oz)
        obj["ease_role"] = role
        obj["ease_panel"] = p.name
        obj["ease_mean_achieved_weft"] = float(np.mean(p.achieved_weft))
        made.append(obj)
        # boundary curve(s)
        cd = bpy.data.curves.new(f"EASE outline {p.name}", "CURVE")
        cd.dimensions = "3D"
        for loop in p.boundary:
            loop = np.asarray(loop)
            sp = cd.splines.new("POLY")
            sp.points.add(len(loop) - 1)
            pts = np.hstack([v3[loop], np.ones((len(loop), 1))]).astype(np.float32)
            pts[:, 1] = -0.001   # just in front of the mesh
            sp.points.foreach_set("co", pts.ravel())
            sp.use_cyclic_u = True
        cd.bevel_depth = 0.002
        _child(coll, f"EASE outline {p.name}", cd, obj, role)
        # grain-line arrow through the centroid
        c = uv.mean(axis=0)
        g = np.asarray(p.grain, dtype=np.float64)
        g = g / max(np.linalg.norm(g), 1e-12)
        n = np.array([-g[1], g[0]])
        half = 0.35 * float(np.ptp(uv @ g))
        a, b = c - half * g, c + half * g
        head = 0.04 * max(half, 0.05) / 0.35
        pts2 = np.array([a, b, b - head * g + 0.5 * head * n, b - head * g - 0.5 * head * n,
                         a + head * g + 0.5 * head * n, a + head * g - 0.5 * head * n])
        pts3 = np.stack([pts2[:, 0], np.full(len(pts2), -0.002), pts2[:, 1]], axis=1)
        gm = convert.mesh_edges_from_arrays(f"EASE grain {p.name}", pts3, [[0, 1], [1, 2], [1, 3], [0, 4], [0, 5]])
        _child(coll, f"EASE grain {p.name}", gm, obj, role)
        # piece name
        fd = bpy.data.curves.new(f"EASE label {p.name}", "FONT")
        fd.body = p.name.split(".", 1)[-1] + (" (mirror)" if p.mirror_of else "")
        fd.size = 0.045
        fd.align_x = "CENTER"
        label = _child(coll, f"EASE label {p.name}", fd, obj, role)
        label.location = (float(c[0]), -0.003, float(c[1]) + 0.03)
        label.rotation_euler = (np.pi / 2, 0.0, 0.0)
    for o in old:
        state.remove_object(o)
    return made


def _child(coll, name, data, parent, role):
    obj = bpy.data.objects.new(name, data)
    coll.objects.link(obj)
    obj.parent = parent
    obj["ease_role"] = role + "_part"
    return obj


def _progress_for(context):
    wm = context.window_manager

    def progress(fraction, message):
        try:
            wm.progress_update(int(100 * fraction))
        except Exception:
            pass
    return progress


def show_pattern(context, pattern, store_as: str = PATTERN_KEY) -> None:
    from .ease_ops import ramp_range
    lo, hi = ramp_range(context.scene)
    # widen the display range to the achieved scales (robust percentiles; degenerate slivers aside)
    w = np.concatenate([np.asarray(p.achieved_weft, dtype=float) for p in pattern.panels])
    lo = max(ramp.EASE_LIMITS[0], min(lo, float(np.percentile(w, 1))))
    hi = min(ramp.EASE_LIMITS[1], max(hi, float(np.percentile(w, 99))))
    pattern_objects(context, pattern, lo, hi)
    store_pattern(context.scene, pattern, store_as)
    context.scene.ease.pattern_json = json.dumps(key_figures(pattern))


def gather_settings(scene, design):
    """The design with ``materials.gather_above`` set from the Pattern panel (None when gathering is
    off); unchanged when the panel shows what the design already does."""
    from ..core.design.format import load_design
    from ..core.pattern.solve import SolverConfig
    s = scene.ease
    want = round(s.gather_above_pct / 100.0, 6) if s.gather_auto else None
    have = design.materials.get("gather_above", SolverConfig().gather_above)
    if want == have:
        return design
    data = design.to_json()
    data.setdefault("materials", {})["gather_above"] = want
    return load_design(data)        # validates the value (DesignError names the field)


def fill_gather_props(scene, design) -> None:
    """Show a design's gathering threshold in the Pattern panel (on loading a design)."""
    from ..core.pattern.solve import SolverConfig
    above = design.materials.get("gather_above", SolverConfig().gather_above)
    scene.ease.gather_auto = above is not None
    if above is not None:
        scene.ease.gather_above_pct = 100.0 * float(above)


class EASE_OT_optimize_pattern(EaseOperator):
    """Optimize the sewing pattern of the design and lay it out beside the body"""
    bl_idname = "ease.optimize_pattern"
    bl_label = "Optimize Pattern"

    def run(self, context):
        from . import design_ops
        obj = body_object(context)
        design = gather_settings(context.scene, design_ops.current_design(context))
        cut = design_ops.cut_for(design, obj)
        wm = context.window_manager
        wm.progress_begin(0, 100)
        try:
            pattern = state.optimize_pattern(design, cut, obj, progress=_progress_for(context))
        finally:
            wm.progress_end()
        # -- the scene changes from here on: the design keeps the gathering it was solved with
        text = json.dumps(design.to_json(), sort_keys=True)
        if text != context.scene.ease.design_json:
            context.scene.ease.design_json = text
        show_pattern(context, pattern)
        self.report({"INFO"}, f"pattern: {len(pattern.panels)} pieces")


CLASSES = (EASE_OT_optimize_pattern,)
