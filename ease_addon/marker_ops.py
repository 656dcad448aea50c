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

from . import data, jobs, objects, state
from .operators_base import EaseOperator

ROLE = "marker"
IMAGE = "EASE Marker"


def _patterns(pattern, wanted, inputs, config, progress=None):
    """(size, pattern, garments) per wanted size: the scene's pattern for its own size, transfers
    for the rest (of the design and body spec ``inputs``, :func:`.data.preparing`, None without a
    design); no ``bpy`` (a worker runs it)."""
    from ..core import workflows as wf
    from ..core.marker import size_label

    here = size_label(pattern)
    runs, prep, solver = [], None, None
    for size, garments in wanted.items():
        if size == here:
            runs.append((size, pattern, garments))
            continue
        if prep is None:
            if inputs is None:
                raise state.AddonError(f"marker: size {size} needs the design to transfer from; load a design")
            prep = data.prepare(*inputs)
            solver = wf.make_solver(prep, config)
        if progress is not None:
            progress(0.0, f"transferring to {size}")
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


JOB = "marker"  # the job of Marker (a newer one replaces a running one)


def start_marker(context, sync=None) -> tuple:
    """*Marker*'s job (:mod:`.jobs`, ``sync`` its ``sync``): the transfers, the nesting and the
    files in a worker (the marker folder is written at once: it holds all the old files or all
    the new ones, also when cancelled), then the picture shown behind the body and the status.
    ``(job, said)``: ``said`` holds the report once done."""
    from ..core import workflows as wf
    from ..core.marker import parse_quantities, size_label

    scene = context.scene
    s = scene.ease
    pattern = data.required_pattern(scene, "to nest")
    out = Path(data.output_path(s.export_dir, "Export to")) / "marker"
    wanted = parse_quantities(s.marker_sizes, "Sizes") if s.marker_sizes.strip() else {size_label(pattern): 1}
    others = any(size != size_label(pattern) for size in wanted)  # sizes transferred from the design
    inputs = data.preparing(context) if s.design_json and others else None
    config = data.solver_choice(scene)  # as Transfer to Size: the design's or the chosen
    width, seconds = s.marker_width_mm / 1000.0, s.marker_seconds
    allowance, hem = round(s.export_allowance_cm / 100.0, 6), round(s.export_hem_cm / 100.0, 6)
    one_way, spread = s.marker_one_way, s.marker_spread.lower()  # (as `ease marker --spread single|pairs`)
    title = f"{pattern.style or 'pattern'} marker"
    said, writing = [], []
    threaded = not jobs.in_line(sync)

    def compute(progress):
        runs = _patterns(pattern, wanted, inputs, config, progress)
        marker = wf.marker(
            runs,
            width,
            allowance=allowance,
            hem=hem,
            seconds=seconds,
            seed=0,
            one_way=one_way,
            spread=spread,
            progress=progress,
        )
        progress(0.99, "writing the marker")
        writing.append(out)  # (rendered and written at once: no cancel after)
        return marker, wf.write_marker(out, marker, title)

    def apply(result):
        marker, files = result
        ctx = bpy.context
        show_marker(ctx, marker, next(f for f in files if f.name == "marker.png"))
        ctx.scene.ease.marker_status = (
            f"{marker.width * 1000:.0f} x {marker.length * 1000:.0f} mm, efficiency {marker.efficiency * 100:.1f} %"
        )
        said.append(f"marker {ctx.scene.ease.marker_status} in {out}")
        if threaded:
            ctx.scene.ease.job_status = said[-1]

    job = jobs.start_writing(JOB, "Marker", compute, apply, out, writing, sync)
    return job, said


class EASE_OT_marker(jobs.Background, EaseOperator):
    """Nest the pattern's pieces on the fabric width (a cutting-room marker), write it to the export folder and show it (in the background: Esc cancels)"""

    bl_idname = "ease.marker"
    bl_label = "Marker"
    needs = ("pattern", "export_dir")

    def run(self, context):
        job, said = start_marker(context, sync=self.job_sync())
        self.report({"INFO"}, said[-1] if said else "nesting the marker in the background (Esc cancels)")


CLASSES = (EASE_OT_marker,)
