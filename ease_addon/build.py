"""Blender objects from the core's results, each written in one pass.

Everything is computed first, in plain Python by the core (the cut's seam
loops, the pattern's grain line and sheet layout); the functions here only
turn those arrays into meshes, curves and text objects. Objects are updated in
place: an object of the same name and role is reused (its data replaced, or its
vertices moved where the topology is the same), so names never pile up ``.001``
suffixes and what the designer set on an object (visibility, modifiers) stays.
Objects of the role that the new result no longer has are removed.
"""

from __future__ import annotations

import hashlib
import json

import bpy
import numpy as np

from . import convert, data, materials, ramp
from .objects import objects_with_role, remove_data, remove_object, remove_objects, role_object

SEAMLINES = "EASE Seamlines"
KEYPOINTS = "EASE Keypoints"
ACHIEVED = "achieved_ease"  # CORNER colour layer of the pattern panels (per triangle)
GAP = 0.08  # metres between laid-out panels
SHEET_WIDTH = 1.6  # metres: the pieces beside the body are laid out this wide
SHEET_TOP = 1.8  # metres: height of the pieces' top edge


#: datablocks made, swapped or removed here so far: what Live compares around a tick (a tick that
#: changed any pushes an undo step; Blender's memfile undo crashes on datablocks swapped outside one)
DATABLOCK_CHANGES = [0]


def put_object(scene, name: str, datablock, role: str, parent=None):
    """The object ``name`` of ``role`` holding ``datablock``: the existing one reused (its
    old data removed, the new data renamed to ``name``), else a new one."""
    DATABLOCK_CHANGES[0] += 1
    obj = bpy.data.objects.get(name)
    if (
        obj is None
        or obj.get("ease_role") != role
        or obj.name not in scene.objects
        or type(obj.data) is not type(datablock)
    ):
        if obj is not None and obj.get("ease_role") == role:
            remove_object(obj)  # same name, other kind of data: make way for the new one
        return role_object(scene, name, datablock, role, parent=parent)
    old = obj.data
    obj.data = datablock
    if old is not None and old != datablock:
        remove_data(old)
    datablock.name = name
    obj.parent = parent
    return obj


def _remove_others(scene, roles, kept) -> None:
    """Remove the objects of ``roles`` that are not in ``kept`` (children first)."""
    keep = {o.name for o in kept}
    old = [o for r in roles for o in objects_with_role(scene, r) if o.name not in keep]
    DATABLOCK_CHANGES[0] += len(old)
    remove_objects(sorted(old, key=lambda o: o.parent is None))


def body(scene, name: str, vertices: np.ndarray, faces: np.ndarray):
    """A body object (skin material, smooth shading) with ``vertices`` (V, 3) and ``faces`` (F, 3)."""
    me = convert.mesh_from_arrays(name, vertices, faces)
    me.materials.append(materials.skin())
    convert.smooth(me)
    return role_object(scene, name, me, "body")


def seam_loops(cut) -> list:
    """Global garment vertex ids of every panel boundary loop (closed polylines)."""
    loops = []
    for p in cut.panels:
        for b in p.boundary:
            loops.append(np.asarray(p.vertex_ids)[np.asarray(b)])
    return loops


def seamlines(scene, cut, verts, design: str = "") -> None:
    """The seamlines of ``cut`` on the body vertices ``verts`` (a wire object kept in front);
    ``design``: the fingerprint of the design they are drawn for (:func:`.data.design_digest`)."""
    pos = cut.positions(verts)
    loops = seam_loops(cut)
    v, e = convert.polyline_edges([pos[l] for l in loops], closed=True)
    obj = put_object(scene, SEAMLINES, convert.mesh_edges_from_arrays(SEAMLINES, v, e), "seamlines")
    obj["ease_ids"] = json.dumps([l.tolist() for l in loops])
    obj["ease_design"] = design
    obj.show_in_front = True
    obj.color = (1.0, 0.85, 0.1, 1.0)
    obj.hide_select = True
    _remove_others(scene, ["seamlines"], [obj])


def keypoint_markers(scene, names, pts) -> None:
    """Point markers at the keypoints ``pts`` (K, 3) named ``names``."""
    me = convert.mesh_edges_from_arrays(KEYPOINTS, pts, np.zeros((0, 2)))
    obj = put_object(scene, KEYPOINTS, me, "keypoints")
    obj["ease_names"] = json.dumps(names)
    obj.show_in_front = True
    obj.hide_select = True
    _remove_others(scene, ["keypoints"], [obj])


def _xz(points2d: np.ndarray, y: float = 0.0) -> np.ndarray:
    """2D pattern points (n, 2) in the XZ plane (facing the camera, -Y) at depth ``y``."""
    p = np.asarray(points2d, dtype=np.float64).reshape(-1, 2)
    return np.stack([p[:, 0], np.full(len(p), y), p[:, 1]], axis=1)


def _faces_digest(faces: np.ndarray) -> str:
    return hashlib.sha1(np.ascontiguousarray(faces, dtype=np.int32).tobytes()).hexdigest()


def _same_topology(me, n_vertices: int, faces: np.ndarray, digest: str) -> bool:
    """``me`` has ``n_vertices`` vertices and the triangles ``faces`` (their ``digest``, kept on
    the mesh: no read-back of its loops on every live update)."""
    if len(me.vertices) != n_vertices or len(me.polygons) != len(faces):
        return False
    if me.get("ease_faces") is not None:
        return me["ease_faces"] == digest
    vi = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", vi)
    return bool(np.array_equal(vi, np.asarray(faces, dtype=np.int32).ravel()))


def _piece_object(scene, name: str, plan, role: str):
    """The existing piece object ``name`` that can take the planned piece ``plan`` in place (its
    topology), or None."""
    obj = bpy.data.objects.get(name)
    if (
        obj is not None
        and obj.get("ease_role") == role
        and obj.name in scene.objects
        and isinstance(obj.data, bpy.types.Mesh)
        and _same_topology(obj.data, plan.n_vertices, plan.faces, plan.digest)
    ):
        return obj
    return None


def _piece_mesh(scene, name: str, plan, lo: float, hi: float, role: str, made=None):
    """The piece object ``name`` of the planned piece ``plan`` (:class:`PiecePlan`): its vertices
    moved and its colours rewritten in place where the topology is the one it has, else a new
    mesh (``made``: :func:`piece_mesh` made already, in an earlier tick)."""
    obj = _piece_object(scene, name, plan, role)
    if obj is not None:
        obj.data.vertices.foreach_set("co", plan.co)  # (updated below, once)
        _color_piece(obj.data, plan, lo, hi)
        return obj
    return put_object(scene, name, made if made is not None else piece_mesh(name, plan, lo, hi), role)


def piece_mesh(name: str, plan, lo: float, hi: float):
    """A new mesh of the planned piece ``plan``, coloured on the ramp ``lo`` .. ``hi`` (no object
    holds it yet: :func:`update_pattern_objects` puts it in place)."""
    me = convert.mesh_from_arrays(name, plan.co, plan.faces, checked=plan.checked)
    me.color_attributes.new(ACHIEVED, "FLOAT_COLOR", "CORNER")
    me.attributes.new("achieved_weft", "FLOAT", "FACE")
    me.materials.append(materials.attribute("EASE Achieved Ease", ACHIEVED))
    _color_piece(me, plan, lo, hi)
    return me


def _color_piece(me, plan, lo: float, hi: float) -> None:
    me["ease_faces"] = plan.digest
    # colour layers live on points or corners: every corner of a triangle gets its achieved ease
    me.color_attributes[ACHIEVED].data.foreach_set("color", plan.corner_colors(lo, hi))
    me.attributes["achieved_weft"].data.foreach_set("value", plan.achieved)
    me["ease_ramp"] = (float(lo), float(hi))  # the colours' ramp range (legend, read-back)
    me.update()


def pieces_to_make(scene, plan, role: str = "pattern_panel") -> list:
    """The planned pieces (:class:`PiecePlan`) whose object cannot take them in place (a new
    topology, or no object yet): those :func:`update_pattern_objects` makes a new mesh for."""
    return [pp for pp in plan.pieces if _piece_object(scene, f"EASE piece {pp.name}", pp, role) is None]


def same_pieces(scene, pattern, role: str = "pattern_panel") -> bool:
    """The scene's piece objects are ``pattern``'s pieces (the same panels, vertex and triangle
    counts, outline loops): :func:`update_pattern_objects` then only moves what is there (a
    re-solve of the same cut: a live update, a transfer)."""
    pieces = {o.get("ease_panel"): o for o in objects_with_role(scene, role)}
    if sorted(pieces) != sorted(p.name for p in pattern.panels):
        return False
    for p in pattern.panels:
        o, outline = pieces[p.name], _part(f"EASE outline {p.name}", role + "_part")
        if (
            len(o.data.vertices) != len(p.uv)
            or len(o.data.polygons) != len(p.faces)
            or outline is None
            or [len(sp.points) for sp in outline.data.splines] != [len(b) for b in p.boundary]
        ):
            return False
    return True


def _part(name: str, part: str):
    """The existing child object ``name`` of a piece (its role ``part``: "pattern_panel_part"), or None."""
    obj = bpy.data.objects.get(name)
    return obj if obj is not None and obj.get("ease_role") == part else None


def _outline(scene, name: str, loops, parent, part: str):
    """The piece's boundary curve(s) (``loops``: (k, 4) float32 curve points each, just in front of
    its mesh): the points moved where the curve has these loops' point counts, a new curve
    otherwise."""
    obj = _part(name, part)
    if (
        obj is not None
        and obj.name in scene.objects
        and isinstance(obj.data, bpy.types.Curve)
        and [len(sp.points) for sp in obj.data.splines] == [len(l) for l in loops]
    ):
        for sp, pts in zip(obj.data.splines, loops):
            sp.points.foreach_set("co", pts.ravel())
        obj.data.update_tag()
        obj.parent = parent
        return obj
    cd = bpy.data.curves.new(name, "CURVE")
    cd.dimensions = "3D"
    for pts in loops:
        sp = cd.splines.new("POLY")
        sp.points.add(len(pts) - 1)
        sp.points.foreach_set("co", pts.ravel())
        sp.use_cyclic_u = True
    cd.bevel_depth = 0.002
    return put_object(scene, name, cd, part, parent=parent)


def _grain(scene, name: str, v, e, parent, part: str):
    """The grain line with its arrow heads (a wire mesh of vertices ``v``, edges ``e``): moved in
    place where it is one."""
    obj = _part(name, part)
    if (
        obj is not None
        and obj.name in scene.objects
        and isinstance(obj.data, bpy.types.Mesh)
        and len(obj.data.vertices) == len(v)
    ):
        convert.set_vertices(obj.data, v)
        obj.parent = parent
        return obj
    return put_object(scene, name, convert.mesh_edges_from_arrays(name, v, e), part, parent=parent)


def _label(scene, name: str, text: str, at, parent, part: str):
    """The piece's name at ``at`` (x, z: above the grain line's middle; the text object kept where
    it is one)."""
    obj = _part(name, part)
    if obj is None or obj.name not in scene.objects or not isinstance(obj.data, bpy.types.TextCurve):
        fd = bpy.data.curves.new(name, "FONT")
        fd.size = 0.045
        fd.align_x = "CENTER"
        obj = put_object(scene, name, fd, part, parent=parent)
        obj.rotation_euler = (np.pi / 2, 0.0, 0.0)
    if obj.data.body != text:
        obj.data.body = text
    obj.parent = parent
    obj.location = (float(at[0]), -0.003, float(at[1]) + 0.03)
    return obj


class PiecePlan:
    """What the objects of one pattern piece are made of, computed off the main thread (no
    ``bpy``: :class:`PatternPlan`); :func:`update_pattern_objects` only writes it.

    Attributes
    ----------
    name : the panel's name; label: the text beside its grain line
    co : (V * 3,) float32 mesh vertices (the pattern's 2D metres in the XZ plane); n_vertices: V
    faces : (F, 3) int32 triangles; digest: their hash; checked: in range, three distinct vertices
        each (Blender's validation of a new mesh is then skipped)
    achieved : (F,) float32 achieved weft ease (the colours: the ramp range is the writer's)
    offset : (2,) the piece's place on the sheet from its bottom-left corner (x, z)
    outline : (k, 4) float32 curve points of each boundary loop
    grain : (vertices (n, 3), edges (m, 2)) of the grain line and its arrow heads
    label_at : (2,) where the label goes (x, z)
    """

    def __init__(self, p, offset):
        from ..core.geom.layout import grain_arrows, grain_line

        uv = np.asarray(p.uv, dtype=np.float64)
        faces = np.ascontiguousarray(p.faces, dtype=np.int32).reshape(-1, 3)
        self.checked = not faces.size or not (
            faces.min() < 0
            or faces.max() >= len(uv)
            or ((faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 0] == faces[:, 2])).any()
        )
        self.name = p.name
        self.n_vertices = len(uv)
        self.co = _xz(uv).astype(np.float32).ravel()
        self.faces, self.digest = faces, _faces_digest(faces)
        self.achieved = np.asarray(p.achieved_weft, dtype=np.float32)
        self.offset = np.asarray(offset, dtype=np.float64)
        self.outline = [
            np.hstack([pts, np.ones((len(pts), 1))]).astype(np.float32)
            for pts in (_xz(uv[np.asarray(loop)], -0.001) for loop in p.boundary)
        ]
        start, end = grain_line(uv, p.faces, p.boundary, p.grain)
        self.grain = convert.polyline_edges(
            [_xz(l, -0.002) for l in [np.array([start, end])] + grain_arrows(start, end)], closed=False
        )
        self.label = p.name.split(".", 1)[-1] + (" (mirror)" if p.mirror_of else "")
        self.label_at = 0.5 * (start + end)
        self._colors = {}

    def corner_colors(self, lo: float, hi: float) -> np.ndarray:
        """(3 F * 4,) float32 colours of the triangles' corners, achieved ease on the ramp
        ``lo`` .. ``hi`` (kept: a worker makes those of the range it expects)."""
        key = (float(lo), float(hi))
        if key not in self._colors:
            rgba = ramp.ease_to_color(np.clip(self.achieved, lo, hi), lo, hi)
            self._colors[key] = np.repeat(rgba, 3, axis=0).ravel()
        return self._colors[key]


class PatternPlan:
    """The objects of a whole pattern's pieces (:class:`PiecePlan` each) and the sheet's height
    (no ``bpy``: a worker may make it)."""

    def __init__(self, pattern):
        from ..core.geom.layout import layout_pieces

        layout = layout_pieces(
            [np.array([p.uv.min(axis=0), p.uv.max(axis=0)]) for p in pattern.panels], width=SHEET_WIDTH, margin=GAP
        )
        self.height = float(layout.size[1])
        self.pieces = [PiecePlan(p, off) for p, off in zip(pattern.panels, layout.offsets)]

    def colored(self, *ranges) -> PatternPlan:
        """The pieces' colours made for each ramp range ``(lo, hi)`` of ``ranges`` (those the
        writer is expected to use); the plan."""
        for lo, hi in ranges:
            for pp in self.pieces:
                pp.corner_colors(lo, hi)
        return self


def update_pattern_objects(
    scene, pattern, lo: float, hi: float, x0: float, role: str = "pattern_panel", plan=None, made=None
) -> list:
    """The pattern's pieces beside the body, updated in place (objects reused by name;
    pieces the pattern no longer has are removed). Returns the piece objects.

    Each piece is a mesh in the XZ plane: local coordinates are the pattern's
    2D metres, so its dimensions are the piece's. Children: the boundary
    curve(s), the grain-line arrow and the piece's name. The pieces are laid
    out by the core's sheet layout, its top-left corner at (``x0``, 1.8 m).
    Where a piece's topology is unchanged (a re-solve of the same cut: transfer,
    adaptation, a live update) its mesh, outline, grain line and label are the
    ones it had, their points moved: no datablock is made or removed. ``plan``:
    :class:`PatternPlan` of ``pattern`` when a worker made it (else it is made here); what
    is left here is writing arrays into Blender's data. ``made``: piece name -> a new mesh
    (:func:`piece_mesh`, made in earlier ticks) for the pieces of a new topology.
    """
    plan = PatternPlan(pattern) if plan is None else plan
    corner = np.array([x0 - GAP, SHEET_TOP + GAP - plan.height])  # the sheet's bottom-left
    kept, parts = [], []
    part = role + "_part"
    for pp in plan.pieces:
        obj = _piece_mesh(scene, f"EASE piece {pp.name}", pp, lo, hi, role, (made or {}).get(pp.name))
        ox, oz = corner + pp.offset
        obj.location = (float(ox), 0.0, float(oz))
        obj["ease_panel"] = pp.name
        obj["ease_mean_achieved_weft"] = float(np.mean(pp.achieved))
        kept.append(obj)
        parts.append(_outline(scene, f"EASE outline {pp.name}", pp.outline, obj, part))
        parts.append(_grain(scene, f"EASE grain {pp.name}", *pp.grain, obj, part))
        parts.append(_label(scene, f"EASE label {pp.name}", pp.label, pp.label_at, obj, part))
    _remove_others(scene, [part, role], kept + parts)
    return kept


# ----------------------------------------------------------------------------- draped garment

GARMENT = "EASE Garment"
STRAIN_LAYER = "fit_strain"
GAP_LAYER = "fit_gap"
FIT_MAPS = {"STRAIN": STRAIN_LAYER, "GAP": GAP_LAYER}  # Fit map choice -> colour layer
STRAIN_RANGE = (0.0, 0.10)  # weft strain 0 .. 10 % mapped blue .. red
GAP_RANGE = (0.0, 0.05)  # gap 0 .. 5 cm mapped blue .. red


def _map_colors(values, lo, hi) -> np.ndarray:
    # Same ramp as ease (blue = low, red = high) so the legend reads the same way.
    return ramp.ease_to_color(np.clip(values, lo, hi) + 1.0, lo + 1.0, hi + 1.0)


REFINE_EDGE = "ease_refine_edge"  # on the garment: the drape mesh's refinement edge (m; 0: the pattern's mesh)
PATTERN_VERTICES = "ease_pattern_vertices"  # on the garment: ids below this are the pattern's own
_MESH_PATTERNS: dict = {}  # (pattern digest, refine edge) -> the pattern as draped (the last drape's)


def garment(scene, result, gap, digest: str):
    """The garment object of a DrapeResult (replacing an earlier one): fabric material, the
    fit-map colour layers (strain, gap) with their values, and the global vertex id of each
    vertex (layer :data:`.data.VERTEX_ID`); ``digest`` names the pattern it was draped from.

    On a refined drape mesh (``DrapeOptions.refine_edge``) the object is the drape's own mesh:
    its ids below :data:`PATTERN_VERTICES` are the pattern's vertices (what the export reads
    back), those above them the refinement's; the pattern as draped (``result.mesh_pattern``,
    whose panels' triangles are the object's faces) is kept for :func:`drape_pattern`."""
    from ..core.geom.mesh import compact_vertices

    ids, faces = compact_vertices(result.faces, result.used)
    me = convert.mesh_from_arrays(GARMENT, np.asarray(result.positions)[ids], faces)
    for layer, values, (lo, hi) in (
        (STRAIN_LAYER, np.asarray(result.strain_weft)[ids], STRAIN_RANGE),
        (GAP_LAYER, None if gap is None else np.asarray(gap)[ids], GAP_RANGE),
    ):
        if values is None:
            continue
        attr = me.color_attributes.new(layer, "FLOAT_COLOR", "POINT")
        attr.data.foreach_set("color", _map_colors(values, lo, hi).ravel())
        me.attributes.new(layer + "_value", "FLOAT", "POINT").data.foreach_set(
            "value", np.asarray(values, dtype=np.float32)
        )
    # which pattern vertex each garment vertex is: the export reads the garment back by it
    me.attributes.new(data.VERTEX_ID, "INT", "POINT").data.foreach_set("value", ids.astype(np.int32))
    me.materials.append(materials.fabric())
    convert.smooth(me)
    obj = put_object(scene, GARMENT, me, "garment")
    obj["ease_pattern"] = digest  # draped from this pattern
    edge = float((getattr(result, "options", None) or {}).get("refine_edge") or 0.0)
    obj[REFINE_EDGE] = edge
    obj[PATTERN_VERTICES] = int(getattr(result, "pattern_vertices", 0) or len(result.used))
    if edge and getattr(result, "mesh_pattern", None) is not None:
        _MESH_PATTERNS.clear()
        _MESH_PATTERNS[(digest, edge)] = result.mesh_pattern
    _remove_others(scene, ["garment"], [obj])
    return obj


def drape_pattern(obj, pattern):
    """The pattern whose panels' triangles are the faces of the garment ``obj`` draped from
    ``pattern``: ``pattern`` itself, or the pattern as draped where the drape's mesh is not the
    pattern's (pleats opened, a refined drape mesh): the core's own
    (:func:`core.drape.pleats.draped_cloth`: the same triangles; kept from the drape, else made
    again), with ``pattern``'s materials."""
    from dataclasses import replace

    edge = float(obj.get(REFINE_EDGE, 0.0) or 0.0)
    if pattern is None or not (edge or pattern.report.get("pleats")):
        return pattern
    mesh = _MESH_PATTERNS.get((obj.get("ease_pattern"), edge)) if edge else None
    if mesh is None:  # (a file opened again, a pleated pattern): the core builds it as the drape did
        from ..core.drape.pleats import draped_cloth

        mesh = draped_cloth(pattern, edge or None).mesh_pattern
    return replace(mesh, materials=pattern.materials)
