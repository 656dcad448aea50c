"""Design stage: load a template or a design file, edit its parameters with a
live re-cut, place keypoints on the body, draw the seamlines on the body.

The design lives in the scene as JSON (``scene.ease.design_json``); the cut
is rebuilt from it on demand (deterministic) and cached. Keypoints live on
the body mesh as attribute layers (see :func:`.convert.write_keypoints`).
"""
from __future__ import annotations

import json
from pathlib import Path

import bpy
import numpy as np

from . import convert, state
from .body_ops import body_object, body_spec
from .operators_base import EaseOperator

SEAMLINES = "EASE Seamlines"
KEYPOINTS = "EASE Keypoints"


def templates_dir() -> Path:
    """``examples/designs`` of the extension (shipped in the zip, or the checkout)."""
    return Path(__file__).resolve().parent.parent / "examples" / "designs"


_TEMPLATE_ITEMS = []


def template_items():
    # Blender keeps only references to the strings: hold them in a module list.
    d = templates_dir()
    files = sorted(p.name for p in d.glob("*.json")) if d.is_dir() else []
    _TEMPLATE_ITEMS[:] = [(f, f[:-5].replace("_", " "), f"template {f}") for f in files] or \
        [("NONE", "(no templates)", "examples/designs has no designs")]
    return _TEMPLATE_ITEMS


# ----------------------------------------------------------------------------- design <-> scene

def current_design(context):
    """The scene's design as a validated :class:`core.design.format.Design`."""
    from ..core.design.format import load_design
    text = context.scene.ease.design_json
    if not text:
        raise state.AddonError("no design loaded: load a template or a design file in EASE > Design")
    return load_design(text)


def cut_on(design, model_name: str, shape: dict):
    """The cut of ``design`` on body ``model_name`` with ``shape`` (its reference pose); cached."""
    from ..core.cut import cut_design
    key = json.dumps([design.to_json(), model_name, shape or {}], sort_keys=True)
    cached = state.CUTS.get(key)
    if cached is not None:
        return cached
    cut = cut_design(design, body=state.body_model(model_name), shape=dict(shape) if shape else None)
    state.CUTS.clear()        # one cut per session is plenty; keeps memory bounded
    state.CUTS[key] = cut
    return cut


def cut_for(design, obj):
    """Cut ``design`` on the scene body's shape (the pose is the design's reference pose)."""
    spec = body_spec(obj)
    return cut_on(design, spec["model"], spec["shape"])


def current_cut(context):
    return cut_for(current_design(context), body_object(context))


def _seam_ids(cut) -> list:
    """Global garment vertex ids of every panel boundary loop (closed polylines)."""
    loops = []
    for p in cut.panels:
        for b in p.boundary:
            loops.append(np.asarray(p.vertex_ids)[np.asarray(b)])
    return loops


def _draw_seamlines(context, cut, verts) -> None:
    scene = context.scene
    pos = cut.positions(verts)
    loops = _seam_ids(cut)
    v, e = convert.polyline_edges([pos[l] for l in loops], closed=True)
    me = convert.mesh_edges_from_arrays(SEAMLINES, v, e)
    old = [o for o in state.objects_with_role(scene, "seamlines")]
    obj = convert.new_object(SEAMLINES, me, state.collection(scene))
    obj["ease_role"] = "seamlines"
    obj["ease_ids"] = json.dumps([l.tolist() for l in loops])
    obj.show_in_front = True
    obj.color = (1.0, 0.85, 0.1, 1.0)
    obj.hide_select = True
    for o in old:
        state.remove_object(o)


def _keypoint_positions(obj, verts) -> tuple:
    kps = convert.read_keypoints(obj.data)
    faces = convert.get_triangles(obj.data)
    names = list(kps)
    pts = np.array([np.asarray(b) @ verts[faces[t]] for t, b in kps.values()]).reshape(-1, 3)
    return names, pts


def _draw_keypoints(context, obj, verts) -> None:
    scene = context.scene
    names, pts = _keypoint_positions(obj, verts)
    me = convert.mesh_edges_from_arrays(KEYPOINTS, pts, np.zeros((0, 2)))
    old = state.objects_with_role(scene, "keypoints")
    kobj = convert.new_object(KEYPOINTS, me, state.collection(scene))
    kobj["ease_role"] = "keypoints"
    kobj["ease_names"] = json.dumps(names)
    kobj.show_in_front = True
    kobj.hide_select = True
    for o in old:
        state.remove_object(o)


def refresh_attachments(context, obj, verts) -> None:
    """Move the seamlines and keypoint markers onto the body's current vertices."""
    scene = context.scene
    for o in state.objects_with_role(scene, "seamlines"):
        ids = json.loads(o.get("ease_ids", "[]"))
        if not scene.ease.design_json or not ids:
            continue
        # The cut's embedding holds for every shape and pose: move the lines with
        # the cached cut (no re-cut while a slider is dragged).
        cut = next(iter(state.CUTS.values()), None)
        if cut is None or cut.embedding.shape[1] != len(verts):
            # no cut yet, or one made on another body model (a body file replaced it)
            try:
                cut = current_cut(context)
            except state.USER_ERRORS:
                continue
            if cut.embedding.shape[1] != len(verts):
                continue
        pos = cut.positions(verts)
        v, _ = convert.polyline_edges([pos[np.asarray(l)] for l in ids], closed=True)
        if len(v) == len(o.data.vertices):
            convert.set_vertices(o.data, v)
    for o in state.objects_with_role(scene, "keypoints"):
        _, pts = _keypoint_positions(obj, verts)
        if len(pts) == len(o.data.vertices):
            convert.set_vertices(o.data, pts)


def resolved_keypoints(design, model, verts) -> dict:
    """``{name: (triangle, bary)}`` of every design keypoint (landmarks,
    surface points, placements, traced lengths, ring points) resolved on the
    body instance ``verts`` by the core's resolver."""
    from ..core.design.resolve import Resolver
    pts = Resolver(design, model, verts).all_keypoints()
    return {n: (int(sp.triangle), tuple(float(b) for b in sp.bary)) for n, sp in pts.items()}


def _fill_params(scene, design) -> None:
    global _SYNC
    _SYNC = True
    try:
        coll = scene.ease.design_params
        coll.clear()
        for name, p in design.parameters.items():
            item = coll.add()
            item.name = name
            item.kind = p.kind
            item.min = -1e9 if p.min is None else p.min
            item.max = 1e9 if p.max is None else p.max
            item.value = p.value
    finally:
        _SYNC = False


_SYNC = False


def set_design(context, design, recut: bool = True, fill_params: bool = True) -> None:
    """Make ``design`` the scene's design: cut it on the body (errors raise
    before anything changes), store its JSON, redraw seamlines and keypoints."""
    from ..core.design.format import load_design
    design = load_design(design.to_json() if hasattr(design, "to_json") else design)
    obj = body_object(context)
    cut = cut_for(design, obj) if recut else None
    model = state.body_model(body_spec(obj)["model"])
    verts = convert.get_vertices(obj.data)
    kps = resolved_keypoints(design, model, verts)
    # -- the scene changes from here on
    scene = context.scene
    scene.ease.design_json = json.dumps(design.to_json(), sort_keys=True)
    if fill_params:   # not from a parameter slider's own update: its collection must stay put
        _fill_params(scene, design)
    convert.write_keypoints(obj.data, kps)
    _draw_keypoints(context, obj, verts)
    if cut is not None:
        _draw_seamlines(context, cut, verts)
        names = [p.name for p in cut.panels]
        if scene.ease.ease_panel not in names:
            scene.ease.ease_panel = names[0] if names else ""


def load_design_into_scene(context, source) -> None:
    """Load a design (path or dict) onto the scene body, shaping the body as the design says.

    The design is validated and cut on the body it asks for before anything
    in the scene changes, so a bad design leaves the scene as it was.
    """
    from ..core.design.format import load_design
    design = load_design(source)
    obj = body_object(context, required=False)
    model_name = body_spec(obj)["model"] if obj is not None else design.body.get("model", "anny")
    model = state.body_model(model_name)
    shape = design.body.get("shape")
    if isinstance(shape, str):
        shape, _ = state.size_shape(model, shape)
    full = dict(model.default_shape())
    full.update({k: float(v) for k, v in (shape or (body_spec(obj)["shape"] if obj is not None else {})).items()})
    cut_on(design, model_name, full)          # raises (DesignError/CutError) before any change
    # -- the scene changes from here on
    from .body_ops import _fill_shape_props, create_body, update_body
    if obj is None:
        obj = create_body(context, model_name, shape=full)
    else:
        update_body(context, obj, shape=full)
        _fill_shape_props(context.scene, model, full)
    set_design(context, design)
    from .export_ops import fill_export_props
    from .pattern_ops import fill_gather_props
    fill_export_props(context.scene, design)    # the design's seam allowance and notch spacing
    fill_gather_props(context.scene, design)    # and its seam gathering
    bpy.ops.ease.ease_from_design()


def design_with_triangle_ease(context, design, tri_ease: np.ndarray):
    """A copy of ``design`` whose every panel has the per-triangle ease
    ``tri_ease`` (F,) on the body triangles it covers."""
    obj = body_object(context)
    cut = cut_for(design, obj)
    faces = convert.get_triangles(obj.data)
    d = design.copy()
    for p in cut.panels:
        emb = cut.embedding[p.vertex_ids].tocsr()
        cols = np.unique(emb.indices)
        inside = np.zeros(len(obj.data.vertices), dtype=bool)
        inside[cols] = True
        tris = np.flatnonzero(inside[faces].all(axis=1))
        if len(tris) == 0:
            continue
        d.set_ease(p.name, {"per_triangle": {"triangles": [int(t) for t in tris],
                                             "values": [round(float(x), 6) for x in tri_ease[tris]],
                                             "default": round(float(np.median(tri_ease[tris])), 6)}})
    return d


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
        emb = cut.embedding[p.vertex_ids].tocsr()
        single = np.flatnonzero(np.diff(emb.indptr) == 1)
        cols = emb.indices[emb.indptr[single]]
        np.add.at(acc, cols, ev[single] / np.maximum(cv[single], 1))
        np.add.at(cnt, cols, 1.0)
    return np.where(cnt > 0, acc / np.maximum(cnt, 1), 1.0)


# ----------------------------------------------------------------------------- operators

class EASE_OT_load_template(EaseOperator):
    """Load a design template from examples/designs onto the body"""
    bl_idname = "ease.load_template"
    bl_label = "Load Template"

    template: bpy.props.StringProperty(default="", description="file name in examples/designs")

    def run(self, context):
        name = self.template or context.scene.ease.template
        path = templates_dir() / name
        if not name or name == "NONE" or not path.is_file():
            raise state.AddonError(f"no design template {name!r} in {templates_dir()}")
        load_design_into_scene(context, str(path))
        self.report({"INFO"}, f"loaded {name}")


class EASE_OT_load_design_file(EaseOperator):
    """Load a design file (JSON) onto the body"""
    bl_idname = "ease.load_design_file"
    bl_label = "Load File"

    filepath: bpy.props.StringProperty(subtype="FILE_PATH", default="")

    def run(self, context):
        path = bpy.path.abspath(self.filepath or context.scene.ease.design_file)
        if not path:
            raise state.AddonError("set a design file first")
        load_design_into_scene(context, path)
        self.report({"INFO"}, f"loaded {path}")


class EASE_OT_save_design(EaseOperator):
    """Write the current design (with its ease) to the design file"""
    bl_idname = "ease.save_design"
    bl_label = "Save Design"

    filepath: bpy.props.StringProperty(subtype="FILE_PATH", default="")

    def run(self, context):
        from ..core.design.format import save_design
        path = bpy.path.abspath(self.filepath or context.scene.ease.design_file)
        if not path:
            raise state.AddonError("set a design file to save to")
        save_design(current_design(context), path)
        self.report({"INFO"}, f"saved {path}")


class EASE_OT_set_parameter(EaseOperator):
    """Set a design parameter (placement 0..1 or length in metres) and re-cut"""
    bl_idname = "ease.set_parameter"
    bl_label = "Set Parameter"

    name: bpy.props.StringProperty()
    value: bpy.props.FloatProperty()

    def run(self, context):
        d = current_design(context)
        d.set_parameter(self.name, self.value)
        set_design(context, d)


class EASE_OT_recut(EaseOperator):
    """Apply the parameter values to the design and re-cut it"""
    bl_idname = "ease.recut"
    bl_label = "Re-cut"

    def run(self, context):
        d = current_design(context)
        for item in context.scene.ease.design_params:
            if d.parameters[item.name].value != item.value:
                d.set_parameter(item.name, item.value)
        set_design(context, d)


def param_update(item, context) -> None:
    """Live re-cut when a parameter slider moves (errors go to the status text)."""
    if _SYNC or not context.scene.ease.live_recut:
        return
    try:
        d = current_design(context)
        d.set_parameter(item.name, item.value)
        set_design(context, d, fill_params=False)
    except state.USER_ERRORS as exc:
        context.scene.ease.drape_status = f"re-cut failed: {exc}"
        print(f"[ease] re-cut failed: {exc}")


class EASE_OT_assign_keypoint(EaseOperator):
    """Place the named keypoint on the selected body vertex (Edit Mode selection)"""
    bl_idname = "ease.assign_keypoint"
    bl_label = "Keypoint at Selected Vertex"

    name: bpy.props.StringProperty(default="")
    vertex: bpy.props.IntProperty(default=-1, description="vertex index; -1 uses the selection")

    def run(self, context):
        obj = body_object(context)
        name = self.name or context.scene.ease.keypoint_name
        if not name:
            raise state.AddonError("type the keypoint's name first")
        was_edit = obj.mode == "EDIT"
        if was_edit:
            obj.update_from_editmode()
        if self.vertex >= 0:
            vid = self.vertex
        else:
            sel = convert.selected_vertices(obj.data)
            if len(sel) != 1:
                raise state.AddonError(f"select exactly one body vertex in Edit Mode (selected: {len(sel)})")
            vid = int(sel[0])
        tri, bary = convert.vertex_surface_point(convert.get_triangles(obj.data), vid)
        place_keypoint(context, name, tri, bary, was_edit)
        self.report({"INFO"}, f"keypoint {name} at vertex {vid}")


def place_keypoint(context, name, tri, bary, was_edit=False):
    from ..core.body.model import SurfacePoint
    d = current_design(context)
    d.set_keypoint(name, SurfacePoint(int(tri), tuple(float(b) for b in bary)))
    if was_edit:
        bpy.ops.object.mode_set(mode="OBJECT")
    set_design(context, d)
    if was_edit:
        bpy.ops.object.mode_set(mode="EDIT")


class EASE_OT_pick_keypoint(bpy.types.Operator):
    """Click on the body surface to place the named keypoint there"""
    bl_idname = "ease.pick_keypoint"
    bl_label = "Pick Keypoint on Surface"
    bl_options = {"REGISTER", "UNDO"}

    def invoke(self, context, event):
        if context.area is None or context.area.type != "VIEW_3D":
            self.report({"ERROR"}, "run this from the 3D view")
            return {"CANCELLED"}
        context.window_manager.modal_handler_add(self)
        context.workspace.status_text_set("EASE: click on the body to place the keypoint, Esc to cancel")
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type in {"ESC", "RIGHTMOUSE"}:
            context.workspace.status_text_set(None)
            return {"CANCELLED"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS":
            context.workspace.status_text_set(None)
            try:
                self._pick(context, event)
            except state.USER_ERRORS as exc:
                self.report({"ERROR"}, str(exc))
                return {"CANCELLED"}
            return {"FINISHED"}
        return {"PASS_THROUGH"} if event.type.startswith(("WHEEL", "MIDDLEMOUSE")) else {"RUNNING_MODAL"}

    def _pick(self, context, event):
        from bpy_extras import view3d_utils
        region, rv3d = context.region, context.region_data
        co = (event.mouse_region_x, event.mouse_region_y)
        origin = view3d_utils.region_2d_to_origin_3d(region, rv3d, co)
        direction = view3d_utils.region_2d_to_vector_3d(region, rv3d, co)
        pick_on_surface(context, context.scene.ease.keypoint_name, origin, direction)


def pick_on_surface(context, name, origin, direction):
    """Place keypoint ``name`` where the ray ``origin + t * direction`` (world space) first
    meets the body: the clicked surface point as (triangle, barycentric weights).
    Returns the triangle index."""
    from mathutils import Vector
    obj = body_object(context)
    if not name:
        raise state.AddonError("type the keypoint's name first")
    inv = obj.matrix_world.inverted()
    hit, loc, _n, face = obj.ray_cast(inv @ Vector(origin), inv.to_3x3() @ Vector(direction))
    if not hit:
        raise state.AddonError("no body under the mouse")
    faces = convert.get_triangles(obj.data)
    verts = convert.get_vertices(obj.data)
    a, b, c = verts[faces[face]]
    p = np.asarray(loc)
    m = np.stack([b - a, c - a], axis=1)
    uv, *_ = np.linalg.lstsq(m, p - a, rcond=None)
    bary = (1 - uv.sum(), uv[0], uv[1])
    place_keypoint(context, name, face, bary)
    return int(face)


CLASSES = (EASE_OT_load_template, EASE_OT_load_design_file, EASE_OT_save_design, EASE_OT_set_parameter,
           EASE_OT_recut, EASE_OT_assign_keypoint, EASE_OT_pick_keypoint)
