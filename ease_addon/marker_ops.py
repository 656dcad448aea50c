"""Marker: nest the pattern's pieces (one or more sizes) on the fabric width with the core's
marker stage (:func:`core.workflows.marker`, as ``ease marker``: the export's allowance rule, the
panel's allowance and hem over the design's table), write the marker files into the export
folder's ``marker`` subfolder, and show the marker picture on a flat object lying behind the body.

Sizes other than the scene pattern's are transferred from the current design first
(:func:`core.workflows.transfer`, the scene pattern as the start when it is the reference).
"""

from __future__ import annotations

from pathlib import Path

import bpy

from . import data, objects, state
from .objects import window_progress
from .operators_base import EaseOperator

ROLE = "marker"
IMAGE = "EASE Marker"


def _patterns(context, pattern, wanted):
    """(size, pattern, garments) per wanted size: the scene's pattern for its own size, transfers for the rest."""
    from ..core import workflows as wf
    from ..core.marker import size_label

    here = size_label(pattern)
    runs, prep, solver, config = [], None, None, None
    for size, garments in wanted.items():
        if size == here:
            runs.append((size, pattern, garments))
            continue
        if prep is None:
            if not context.scene.ease.design_json:
                raise state.AddonError(f"marker: size {size} needs the design to transfer from; load a design")
            prep = data.prepared(context)
            config = data.solver_choice(context.scene)  # as Transfer to Size: the design's or the chosen
            solver = wf.make_solver(prep, config)
        start = pattern if pattern.mode == "reference" else None
        runs.append((size, wf.transfer(prep, size, config=config, solver=solver, start=start).pattern, garments))
    return runs


def show_marker(context, marker, png: Path):
    """The marker picture as an image and a flat object (fabric length x width, metres) behind the body."""
    img = bpy.data.images.get(IMAGE)
    if img is None:
        img = bpy.data.images.load(str(png))
        img.name = IMAGE
    else:
        img.filepath = str(png)
        img.reload()
    scene = context.scene
    objects.remove_objects(objects.objects_with_role(scene, ROLE))
    L, W = float(marker.length), float(marker.width)
    mesh = bpy.data.meshes.new(IMAGE)
    mesh.from_pydata([(0, 0, 0), (L, 0, 0), (L, W, 0), (0, W, 0)], [], [(0, 1, 2, 3)])
    uv = mesh.uv_layers.new(name="UVMap")
    for loop, co in zip(uv.data, ((0, 0), (1, 0), (1, 1), (0, 1))):
        loop.uv = co
    mat = bpy.data.materials.get(IMAGE) or bpy.data.materials.new(IMAGE)
    objects.ensure_nodes(mat)
    nodes = mat.node_tree.nodes
    tex = nodes.get("Marker Image") or nodes.new("ShaderNodeTexImage")
    tex.name = "Marker Image"
    tex.image = img
    bsdf = next((n for n in nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is not None:
        mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    mesh.materials.append(mat)
    obj = objects.role_object(scene, IMAGE, mesh, ROLE)
    obj.location = (-0.5 * L, 0.6, 0.0)  # on the floor behind the body (the body faces -Y)
    return obj


class EASE_OT_marker(EaseOperator):
    """Nest the pattern's pieces on the fabric width (a cutting-room marker), write it to the export folder and show it"""

    bl_idname = "ease.marker"
    bl_label = "Marker"
    needs = ("pattern", "export_dir")

    def run(self, context):
        from ..core import workflows as wf
        from ..core.marker import parse_quantities, size_label

        scene = context.scene
        s = scene.ease
        pattern = data.required_pattern(scene, "to nest")
        out = data.output_path(s.export_dir, "Export to")
        wanted = parse_quantities(s.marker_sizes, "Sizes") if s.marker_sizes.strip() else {size_label(pattern): 1}
        runs = _patterns(context, pattern, wanted)
        with window_progress(context) as progress:
            marker = wf.marker(
                runs,
                s.marker_width_mm / 1000.0,
                allowance=round(s.export_allowance_cm / 100.0, 6),
                hem=round(s.export_hem_cm / 100.0, 6),
                seconds=s.marker_seconds,
                seed=0,
                one_way=s.marker_one_way,
                spread=s.marker_spread.lower(),  # as `ease marker --spread single|pairs`
                progress=progress,
            )
        title = f"{pattern.style or 'pattern'} marker"
        files = wf.write_marker(Path(out) / "marker", marker, title)
        show_marker(context, marker, next(f for f in files if f.name == "marker.png"))
        s.marker_status = (
            f"{marker.width * 1000:.0f} x {marker.length * 1000:.0f} mm, efficiency {marker.efficiency * 100:.1f} %"
        )
        self.report({"INFO"}, f"marker {s.marker_status} in {Path(out) / 'marker'}")


CLASSES = (EASE_OT_marker,)
