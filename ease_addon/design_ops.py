"""Design stage: load a template or a design file, edit its parameters with a
live re-cut, place keypoints on the body (on a selected vertex, or where a
click meets the surface).

The design lives in the scene as JSON (``scene.ease.design_json``, read by
:func:`.data.current_design`); the cut is rebuilt from it on demand and
cached. Keypoints live on the body mesh as attribute layers (see
:func:`.convert.write_keypoints`); :func:`.sync.set_design` redraws the
seamlines and keypoint markers.
"""

from __future__ import annotations

import bpy

from . import convert, data, jobs, state, sync
from .operators_base import EaseOperator, poll_needs


def load_design_into_scene(context, source) -> str:
    """Load a design (path or dict) onto the body, shaping the body as the design says.

    The design is validated and cut on the body it asks for before anything
    in the scene changes, so a bad design leaves the scene as it was. The Body
    panel then says what the body is (the design's chart size, its sliders and
    measurements). Returns what happened to the body, for the report ("" when
    it kept its shape).
    """
    return _place_design(context, _load_design(source, *_body_now(context)))


def _body_now(context) -> tuple:
    """(body model name or None, its shape, its pose) of the scene body: what a design is loaded onto."""
    obj = data.body_object(context, required=False)
    if obj is None:
        return None, {}, "A"
    spec = data.body_spec(obj)
    return spec["model"], spec["shape"], spec["pose"]


def _load_design(source, model_name, before, pose) -> tuple:
    """The heavy half of a load, no Blender data touched (a worker may run it): the design read,
    validated and cut (cached) on the body it asks for, the body's vertices at that shape (in
    ``pose``) and the design's keypoints on them. ``(design, model name, its shape name or dict,
    the body's full shape, pose, vertices, keypoints)``; raises (DesignError/CutError) on a bad
    design."""
    import numpy as np

    from ..core.body.instance import instance_shape
    from ..core.design import load_design

    design = load_design(source)
    model_name = model_name or design.body.get("model", "anny")
    model = state.body_model(model_name)
    named = design.body.get("shape")
    shape = instance_shape(model, named)
    full = dict(model.default_shape())
    full.update({k: float(v) for k, v in (shape or before).items()})
    data.cut_on(design, model_name, full)  # raises before any change
    verts = sync.body_vertices({"model": model_name, "shape": full, "pose": pose})
    # the keypoints on the vertices as the mesh will hold them (float32), as set_design resolves them
    mesh = np.asarray(verts, dtype=np.float32).astype(np.float64)
    kps = data.resolved_keypoints(design, model, mesh)
    report = sync.measurements_report({"model": model_name, "shape": full}) if shape else None
    return design, model_name, named, full, pose, verts, kps, report


def _place_design(context, loaded) -> str:
    """The scene's half of a load (main thread, one pass): the body shaped, the design set."""
    from ..core.body.instance import instance_shape

    design, model_name, named, full, pose, verts, kps, report = loaded
    obj = data.body_object(context, required=False)
    spec = data.body_spec(obj) if obj is not None else {"model": model_name, "pose": "A"}
    if spec["model"] != model_name or spec["pose"] != pose:
        raise state.AddonError("the body changed while the design was loading: load it again")
    model = state.body_model(model_name)
    shape = instance_shape(model, named)
    before = data.body_spec(obj)["shape"] if obj is not None else {}
    # -- the scene changes from here on
    if obj is None:
        obj = sync.new_body(context, model_name, shape=full)
        reshaped = False
    else:
        reshaped = data.full_shape(model, before) != full
        sync.update_body(context, obj, shape=full, verts=verts)
        sync.fill_shape_props(context.scene, model, full)
    if shape:
        sync.show_size(context.scene, obj, named if isinstance(named, str) else None, report)
    sync.set_design(context, design, keypoints=kps)
    sync.fill_design_props(context.scene, design)  # its gathering, tolerance, allowance and notches
    try:
        sync.ease_from_design(context)
    except state.USER_ERRORS as exc:  # (as the operator it was: said, the load kept)
        context.scene.ease.design_status = f"Ease from Design: {exc}"
    if not reshaped:
        return ""
    return (
        f"the body takes the design's size {named}" if isinstance(named, str) else "the body takes the design's shape"
    )


def _design_file(op, context, missing: str) -> str:
    """The design file of operator ``op`` (its ``filepath``, else the panel's), absolute;
    AddonError ``missing`` when neither is set."""
    path = bpy.path.abspath(op.filepath or context.scene.ease.design_file)
    if not path:
        raise state.AddonError(missing)
    return path


def start_load(path: str, shown: str, body_now: tuple, label: str, sync=None) -> tuple:
    """Load the design file ``path`` (the report's ``shown``) onto the body ``body_now``
    (:func:`_body_now`) as the job ``"design"``: read, validated and cut in a worker (``sync``:
    :func:`.jobs.start`'s), placed in one pass when it lands (then, threaded, the panel says
    "loaded ..." and it is one undo step named ``label``). ``(job, said)``: ``said`` holds the
    report once placed (at once when in line)."""
    said = []
    threaded = not jobs.in_line(sync)

    def place(loaded):
        body = _place_design(bpy.context, loaded)
        said.append(f"loaded {shown}" + (f"; {body}" if body else ""))
        if threaded:  # it landed after the operator returned: say so, and make it one undo step
            bpy.context.scene.ease.job_status = said[-1]
            state.changed(bpy.context.scene)
            jobs.undo_push(f"EASE: {label}")

    job = jobs.start(
        "design",
        f"loading {shown}",
        lambda progress: _load_design(path, *body_now),
        place,
        fail=lambda exc: setattr(bpy.context.scene.ease, "design_status", f"{shown}: {exc}"),
        sync=sync,
    )
    return job, said


class _LoadDesign(jobs.Background, EaseOperator):
    """Load the design :meth:`source` names onto the body (pressed: in the background, Esc
    cancels; from a script: in line, as Drape)."""

    def source(self, context) -> tuple:  # pragma: no cover - overridden
        """(path of the design file, how the report names it)."""
        raise NotImplementedError

    def run(self, context):
        path, shown = self.source(context)
        _, said = start_load(path, shown, _body_now(context), self.bl_label, sync=self.job_sync())
        if said:  # in line: done
            self.report({"INFO"}, said[-1])
        else:
            self.report({"INFO"}, f"loading {shown} in the background")


class EASE_OT_load_template(_LoadDesign):
    """Load a design template onto the body"""

    bl_idname = "ease.load_template"
    bl_label = "Load Template"

    template: bpy.props.StringProperty(default="", description="file name of a design template")

    def source(self, context):
        name = self.template or context.scene.ease.template
        path = data.template_dir() / name
        if not name or name == "NONE" or not path.is_file():
            raise state.AddonError(f"no design template {name!r} in {data.template_dir()}")
        return str(path), name


class EASE_OT_load_design_file(_LoadDesign):
    """Load a design file (JSON) onto the body"""

    bl_idname = "ease.load_design_file"
    bl_label = "Load File"

    filepath: bpy.props.StringProperty(subtype="FILE_PATH", default="")

    def source(self, context):
        path = _design_file(self, context, "set a design file first")
        return path, path


class EASE_OT_save_design(EaseOperator):
    """Write the current design (with its ease) to the design file"""

    bl_idname = "ease.save_design"
    bl_label = "Save Design"
    bl_options = {"REGISTER"}  # writes a file, changes no Blender data: no undo step
    needs = ("design",)

    filepath: bpy.props.StringProperty(subtype="FILE_PATH", default="")

    def run(self, context):
        from ..core.design import save_design

        path = _design_file(self, context, "set a design file to save to")
        save_design(data.current_design(context), path)
        self.report({"INFO"}, f"saved {path}")


class EASE_OT_set_parameter(EaseOperator):
    """Set a design parameter (placement 0..1 or length in metres) and re-cut"""

    bl_idname = "ease.set_parameter"
    bl_label = "Set Parameter"
    needs = ("body", "design")

    name: bpy.props.StringProperty()
    value: bpy.props.FloatProperty()

    def run(self, context):
        d = data.current_design(context)
        try:
            d.set_parameter(self.name, data.as_typed(self.value))
            sync.set_design(context, d)
        except state.USER_ERRORS as exc:
            sync.refuse_param(context, self.name, exc)
            raise
        context.scene.ease.design_status = ""


class EASE_OT_recut(EaseOperator):
    """Apply the parameter values to the design and re-cut it"""

    bl_idname = "ease.recut"
    bl_label = "Re-cut"
    needs = ("body", "design")

    def run(self, context):
        d = data.current_design(context)
        name = None
        try:
            for item in context.scene.ease.design_params:
                value = data.as_typed(item.value)
                if d.parameters[item.name].value != value:
                    name = item.name
                    d.set_parameter(item.name, value)
            name = None  # the values are the design's: a cut that fails is no one slider's
            sync.set_design(context, d)
        except state.USER_ERRORS as exc:
            sync.refuse_param(context, name, exc)
            raise
        context.scene.ease.design_status = ""


class EASE_OT_assign_keypoint(EaseOperator):
    """Place the named keypoint on the selected body vertex (Edit Mode selection)"""

    bl_idname = "ease.assign_keypoint"
    bl_label = "Keypoint at Selected Vertex"
    needs = ("body", "design")

    name: bpy.props.StringProperty(default="")
    vertex: bpy.props.IntProperty(default=-1, description="vertex index; -1 uses the selection")

    def run(self, context):
        obj = data.body_object(context)
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

    d = data.current_design(context)
    d.set_keypoint(name, SurfacePoint(int(tri), tuple(float(b) for b in bary)))
    if was_edit:
        bpy.ops.object.mode_set(mode="OBJECT")
    sync.set_design(context, d)
    if was_edit:
        bpy.ops.object.mode_set(mode="EDIT")


class EASE_OT_pick_keypoint(bpy.types.Operator):
    """Click on the body surface to place the named keypoint there"""

    bl_idname = "ease.pick_keypoint"
    bl_label = "Pick Keypoint on Surface"
    bl_options = {"REGISTER", "UNDO"}
    needs = ("body", "design")
    poll = classmethod(poll_needs)

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

    from ..core.body.surface import surface_point_at

    obj = data.body_object(context)
    if not name:
        raise state.AddonError("type the keypoint's name first")
    inv = obj.matrix_world.inverted()
    hit, loc, _n, face = obj.ray_cast(inv @ Vector(origin), inv.to_3x3() @ Vector(direction))
    if not hit:
        raise state.AddonError("no body under the mouse")
    sp = surface_point_at(convert.get_vertices(obj.data), convert.get_triangles(obj.data), face, tuple(loc))
    place_keypoint(context, name, sp.triangle, sp.bary)
    return int(sp.triangle)


CLASSES = (
    EASE_OT_load_template,
    EASE_OT_load_design_file,
    EASE_OT_save_design,
    EASE_OT_set_parameter,
    EASE_OT_recut,
    EASE_OT_assign_keypoint,
    EASE_OT_pick_keypoint,
)
