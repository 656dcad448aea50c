"""Export stage: write the scene's pattern with the core's exporters
(SVG, DXF, tiled PDF; GLB and OBJ of the draped garment).

The seam allowance, hem allowance and notch spacing shown in the Render &
Export panel live in the design (``materials.export``, next to per-seam
widths a design file may set): Export Pattern writes them there, so a saved
design carries them, and hands the design's settings to the exporters. The
draped garment is read from the garment object itself (its ``ease_vertex_id``
layer maps its vertices to the pattern's), so it exports after a save and
reopen, and undo of a drape or of a new pattern cannot mix the two up.
"""

from __future__ import annotations

import json

import bpy

from . import data, jobs, state
from .operators_base import EaseOperator

FORMATS = ("svg", "dxf", "pdf", "glb", "obj")


def export_settings(scene, design):
    """The design with ``materials.export`` set from the panel's allowance, hem and notch values
    (per-seam widths it already has are kept), and the ``(allowance table, notch_spacing)`` to
    export with."""
    from ..core.design.materials import Materials

    s = scene.ease
    allowance, hem = round(s.export_allowance_cm / 100.0, 6), round(s.export_hem_cm / 100.0, 6)
    notch = round(s.export_notch_cm / 100.0, 6)
    design = data.design_with_materials(design, allowance=allowance, hem=hem, notch_spacing=notch)
    return design, dict(Materials.of(design).allowances, default=allowance, hem=hem), notch


JOB = "export"  # the job of Export Pattern (a newer one replaces a running one)
WRITING = 0.95  # the core's export reports this when it writes the files (in one go: no cancel after)


def start_export(context, directory: str = "", sync=None) -> tuple:
    """*Export Pattern*'s job (:mod:`.jobs`, ``sync`` its ``sync``): the files rendered and written
    in a worker (the core writes the folder at once: it holds all the old files or all the new
    ones, also when cancelled), then the design keeps the settings it was exported with.
    ``(job, said)``: ``said`` holds the report lines once done."""
    from ..core import workflows as wf

    scene = context.scene
    s = scene.ease
    pattern = data.required_pattern(scene, "to export")
    formats = [f for f in FORMATS if getattr(s, f"export_{f}")]
    if not formats:
        raise state.AddonError("choose at least one export format")
    out = data.output_path(directory or s.export_dir, "Export to")
    design = data.current_design(context) if s.design_json else None
    if design is not None:
        design, allowance, notch = export_settings(scene, design)
    else:
        allowance, notch = None, None
    positions, skipped = None, None
    if "glb" in formats or "obj" in formats:
        positions, why = data.garment_positions(scene)
        if positions is None:
            flat = [f for f in formats if f not in ("glb", "obj")]
            if not flat:
                raise state.AddonError(f"GLB/OBJ export: {why}")
            skipped = f"{'/'.join(f.upper() for f in formats if f in ('glb', 'obj'))} skipped: {why}"
            formats = flat
    print_all = s.export_print_all
    said, writing = [], []
    threaded = not jobs.in_line(sync)

    def reported(progress, fraction, message):
        """The core's progress, cancellable until the files are being written (then all are)."""
        if fraction < 1.0:
            progress(fraction, message)
        if fraction >= WRITING:
            writing.append(fraction)

    def compute(progress):
        # the 3D files in the scene's own frame (Z up, the body's root at the origin), as the garment
        # object lies: imported back they land on the scene's body
        return wf.export(
            pattern,
            out,
            formats,
            allowance=allowance,
            notch_spacing=notch,
            drape=None if positions is None else (positions, None),
            print_all=print_all,
            up="z",
            origin="root",
            progress=lambda f, m: reported(progress, f, m),
        )

    def apply(files):
        # -- the scene changes from here on: the design keeps the settings it was exported with
        if design is not None:
            text = json.dumps(design.to_json(), sort_keys=True)
            if text != s.design_json:
                bpy.context.scene.ease.design_json = text
        said.append(f"exported {len(files)} files to {out}")
        if skipped:
            said.append(skipped)
        if threaded:
            bpy.context.scene.ease.job_status = "; ".join(said)

    job = jobs.start_writing(JOB, "Export Pattern", compute, apply, out, writing, sync)
    return job, said


class EASE_OT_export_pattern(jobs.Background, EaseOperator):
    """Export the pattern (SVG, DXF, PDF) and the draped garment (GLB, OBJ) to the export folder (in the background: Esc cancels)"""

    bl_idname = "ease.export_pattern"
    bl_label = "Export Pattern"
    needs = ("pattern", "export_dir")  # greyed out, saying why, on an unsaved file with a "//" folder

    directory: bpy.props.StringProperty(subtype="DIR_PATH", default="")

    def run(self, context):
        job, said = start_export(context, self.directory, sync=self.job_sync())
        if not said:
            self.report({"INFO"}, "exporting in the background (Esc cancels)")
            return
        self.report({"INFO"}, said[0])
        if len(said) > 1:
            self.report({"WARNING"}, said[1])


CLASSES = (EASE_OT_export_pattern,)
