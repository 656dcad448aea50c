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

import copy
import hashlib
import json

import bpy
import numpy as np

from . import state
from .operators_base import EaseOperator

FORMATS = ("svg", "dxf", "pdf", "glb", "obj")
VERTEX_ID = "ease_vertex_id"     # garment mesh layer: the pattern's vertex id of each vertex


def pattern_digest(text: str) -> str:
    """Fingerprint of a stored pattern (which pattern a garment was draped from)."""
    return hashlib.sha1(text.encode("utf-8")).hexdigest()


def garment_positions(scene):
    """``(positions, None)`` of the draped garment by pattern vertex id, or ``(None, why)``."""
    from .convert import get_vertices
    from .pattern_ops import PATTERN_KEY
    garments = state.objects_with_role(scene, "garment")
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
    co = get_vertices(obj.data)
    m = np.array(obj.matrix_world, dtype=np.float64)
    co = co @ m[:3, :3].T + m[:3, 3]
    pos = np.full((int(ids.max()) + 1, 3), np.nan)
    pos[ids] = co
    return pos, None


def _widths(allowance) -> dict:
    """A design's ``materials.export.allowance`` (a number or a dict) as a dict."""
    if allowance is None:
        return {}
    return dict(allowance) if isinstance(allowance, dict) else {"default": float(allowance)}


def export_settings(scene, design):
    """The design with ``materials.export`` set from the panel's allowance, hem and notch values
    (per-seam widths it already has are kept), and the ``(allowance, notch_spacing)`` to export with."""
    from ..core.design.format import load_design
    from ..core.export.pieces import DEFAULT_ALLOWANCE, DEFAULT_HEM, DEFAULT_NOTCH_SPACING
    s = scene.ease
    data = design.to_json()
    exp = copy.deepcopy(data.get("materials", {}).get("export") or {})
    old = _widths(exp.get("allowance"))
    allowance = dict(old, default=round(s.export_allowance_cm / 100.0, 6), hem=round(s.export_hem_cm / 100.0, 6))
    notch = round(s.export_notch_cm / 100.0, 6)
    if (allowance["default"], allowance["hem"], notch) != (old.get("default", DEFAULT_ALLOWANCE),
                                                          old.get("hem", DEFAULT_HEM),
                                                          exp.get("notch_spacing", DEFAULT_NOTCH_SPACING)):
        exp["allowance"] = allowance
        exp["notch_spacing"] = notch
        data.setdefault("materials", {})["export"] = exp
        design = load_design(data)      # validates the new values (DesignError names the field)
    return design, allowance, notch


def fill_export_props(scene, design) -> None:
    """Show a design's export settings in the panel (on loading a design)."""
    from ..core.export.pieces import DEFAULT_ALLOWANCE, DEFAULT_HEM, DEFAULT_NOTCH_SPACING
    exp = design.materials.get("export") or {}
    a = _widths(exp.get("allowance"))
    s = scene.ease
    s.export_allowance_cm = 100.0 * a.get("default", DEFAULT_ALLOWANCE)
    s.export_hem_cm = 100.0 * a.get("hem", DEFAULT_HEM)
    s.export_notch_cm = 100.0 * exp.get("notch_spacing", DEFAULT_NOTCH_SPACING)


class EASE_OT_export_pattern(EaseOperator):
    """Export the pattern (SVG, DXF, PDF) and the draped garment (GLB, OBJ) to the export folder"""
    bl_idname = "ease.export_pattern"
    bl_label = "Export Pattern"

    directory: bpy.props.StringProperty(subtype="DIR_PATH", default="")

    def run(self, context):
        from .design_ops import current_design
        from .pattern_ops import stored_pattern
        scene = context.scene
        s = scene.ease
        pattern = stored_pattern(scene)
        if pattern is None:
            raise state.AddonError("no pattern to export: optimize the pattern first")
        formats = [f for f in FORMATS if getattr(s, f"export_{f}")]
        if not formats:
            raise state.AddonError("choose at least one export format")
        out = bpy.path.abspath(self.directory or s.export_dir)
        if not out:
            raise state.AddonError("set an export folder")
        design = current_design(context) if s.design_json else None
        if design is not None:
            design, allowance, notch = export_settings(scene, design)
        else:
            allowance, notch = None, None
        positions, skipped = None, None
        if "glb" in formats or "obj" in formats:
            positions, why = garment_positions(scene)
            if positions is None:
                flat = [f for f in formats if f not in ("glb", "obj")]
                if not flat:
                    raise state.AddonError(f"GLB/OBJ export: {why}")
                skipped = f"{'/'.join(f.upper() for f in formats if f in ('glb', 'obj'))} skipped: {why}"
                formats = flat
        files = state.export_pattern(pattern, out, formats, positions, allowance=allowance, notch_spacing=notch)
        # -- the scene changes from here on: the design keeps the settings it was exported with
        if design is not None:
            text = json.dumps(design.to_json(), sort_keys=True)
            if text != s.design_json:
                s.design_json = text
        self.report({"INFO"}, f"exported {len(files)} files to {out}")
        if skipped:
            self.report({"WARNING"}, skipped)


CLASSES = (EASE_OT_export_pattern,)
