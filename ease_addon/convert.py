"""Blender data <-> plain numpy arrays (the only place that touches mesh data in bulk).

Everything goes through ``foreach_get``/``foreach_set``: one call per array.
The body mesh keeps the template's topology: polygon ``i`` is template
triangle ``i`` and its corners ``3 i + j`` are the triangle's vertices ``j``,
so per-triangle and per-corner data map one to one onto the core's arrays.
"""

from __future__ import annotations

import json

import bpy
import numpy as np

EASE_LAYER = "ease"  # colour attribute (float colour, point or face corner): the ease field
KEYPOINT_LAYER = "ease_keypoint"  # FACE int: 1 + keypoint index on that triangle, 0 = none
KEYPOINT_BARY_LAYER = "ease_keypoint_bary"  # CORNER float: barycentric weight of the keypoint
KEYPOINT_NAMES = "ease_keypoint_names"  # mesh custom property: JSON list of keypoint names


# ----------------------------------------------------------------------------- meshes


def _mesh_with_vertices(name: str, vertices: np.ndarray) -> bpy.types.Mesh:
    vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(vertices))
    me.vertices.foreach_set("co", vertices.ravel())
    return me


def mesh_from_arrays(name: str, vertices: np.ndarray, faces: np.ndarray, checked: bool = False) -> bpy.types.Mesh:
    """A new mesh with ``vertices`` (V, 3) metres and triangles ``faces`` (F, 3); ``checked``: the
    caller checked the triangles (in range, three distinct vertices each), so Blender's
    ``validate`` pass is skipped."""
    faces = np.ascontiguousarray(faces, dtype=np.int32).reshape(-1, 3)
    me = _mesh_with_vertices(name, vertices)
    me.loops.add(faces.size)
    me.loops.foreach_set("vertex_index", faces.ravel())
    me.polygons.add(len(faces))
    me.polygons.foreach_set("loop_start", np.arange(0, faces.size, 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(len(faces), 3, dtype=np.int32))
    me.update(calc_edges=True)
    if not checked:
        me.validate(clean_customdata=False)
    return me


def smooth(me) -> None:
    """Smooth shading on every polygon of ``me`` (one array write: a loop over 26k polygons took
    60 ms of the main thread)."""
    me.polygons.foreach_set("use_smooth", np.ones(len(me.polygons), dtype=bool))


def mesh_edges_from_arrays(name: str, vertices: np.ndarray, edges: np.ndarray) -> bpy.types.Mesh:
    """A wire mesh (no faces): ``vertices`` (V, 3), ``edges`` (E, 2)."""
    edges = np.ascontiguousarray(edges, dtype=np.int32).reshape(-1, 2)
    me = _mesh_with_vertices(name, vertices)
    me.edges.add(len(edges))
    me.edges.foreach_set("vertices", edges.ravel())
    me.update()
    return me


def polyline_edges(polylines, closed: bool) -> tuple:
    """Stack polylines [(k, 3)] into (V, 3) vertices and (E, 2) edges."""
    verts, edges, base = [], [], 0
    for pl in polylines:
        pl = np.asarray(pl, dtype=np.float64).reshape(-1, 3)
        k = len(pl)
        if k < 2:
            continue
        idx = np.arange(k) + base
        e = np.stack([idx[:-1], idx[1:]], axis=1)
        if closed and k > 2:
            e = np.vstack([e, [[idx[-1], idx[0]]]])
        verts.append(pl)
        edges.append(e)
        base += k
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 2), dtype=np.int64)
    return np.vstack(verts), np.vstack(edges)


def get_vertices(me: bpy.types.Mesh) -> np.ndarray:
    """Vertex positions (V, 3) float64 in object space."""
    co = np.empty(len(me.vertices) * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    return co.reshape(-1, 3).astype(np.float64)


def set_vertices(me: bpy.types.Mesh, vertices: np.ndarray) -> None:
    """Move the vertices in place (topology, attributes and layers are kept)."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
    if len(vertices) != len(me.vertices):
        raise ValueError(f"mesh {me.name!r} has {len(me.vertices)} vertices, got {len(vertices)}")
    me.vertices.foreach_set("co", vertices.ravel())
    me.update()


def get_triangles(me: bpy.types.Mesh) -> np.ndarray:
    """Triangles (F, 3) of an all-triangle mesh."""
    n = len(me.polygons)
    tot = np.empty(n, dtype=np.int32)
    me.polygons.foreach_get("loop_total", tot)
    if n and (tot != 3).any():
        raise ValueError(f"mesh {me.name!r} is not all triangles")
    vi = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", vi)
    return vi.reshape(-1, 3).astype(np.int64)


# ----------------------------------------------------------------------------- ease colour layer


def ensure_color_layer(me: bpy.types.Mesh, name: str = EASE_LAYER, fill=None):
    """The FLOAT_COLOR attribute ``name`` (a POINT one created if missing), made active
    for painting and display; ``fill`` (4,) sets every vertex of a new one. An existing
    ``ease`` layer is adopted (:func:`adopt_ease_layer`), never replaced."""
    attr = me.color_attributes.get(name)
    if attr is not None and name == EASE_LAYER:
        adopt_ease_layer(me)  # the designer's painting is kept, whatever its type
    elif attr is not None and (attr.domain != "POINT" or attr.data_type != "FLOAT_COLOR"):
        me.color_attributes.remove(attr)  # a display layer of ours: remade
        attr = None
    if attr is None:
        attr = me.color_attributes.new(name=name, type="FLOAT_COLOR", domain="POINT")
        if fill is not None:
            write_colors(me, np.tile(np.asarray(fill, dtype=np.float32), (len(me.vertices), 1)), name)
    me.color_attributes.active_color = me.color_attributes[name]
    try:
        me.color_attributes.render_color_index = me.color_attributes.active_color_index
    except AttributeError:  # older API spelling
        pass
    return me.color_attributes[name]


def element_vertices(me, domain: str) -> np.ndarray:
    """The vertex of each element (n,) of a colour layer on ``domain`` (POINT or CORNER)."""
    if domain == "POINT":
        return np.arange(len(me.vertices))
    vi = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", vi)
    return vi


def adopt_ease_layer(me) -> str:
    """Make the mesh's existing ``ease`` layer the one EASE paints, whatever its type and
    domain, keeping every value: byte colours become float colours (the same scene-linear
    colours), a face-corner layer whose corners agree on each vertex becomes a point layer,
    one whose corners differ stays a float face-corner layer. Returns what was done (empty
    when the layer was already a float point layer)."""
    attr = me.color_attributes[EASE_LAYER]
    colors, domain = read_colors(me, EASE_LAYER)
    was = f"{attr.data_type.replace('_', ' ').lower()}, {domain.lower()}"
    target = domain
    if domain == "CORNER":
        vi = element_vertices(me, domain)
        first = np.zeros((len(me.vertices), 4))
        first[vi[::-1]] = colors[::-1]  # one corner's colour per vertex
        if np.array_equal(first[vi], colors):
            target, colors = "POINT", first
    if attr.data_type != "FLOAT_COLOR" or target != domain:
        me.color_attributes.remove(attr)
        attr = me.color_attributes.new(EASE_LAYER, "FLOAT_COLOR", target)
        attr.data.foreach_set("color", colors.astype(np.float32).ravel())
        me.update()
        done = f"adopted the ease layer ({was}) as float colour, {target.lower()}"
    else:
        done = ""
    me.color_attributes.active_color = me.color_attributes[EASE_LAYER]
    try:
        me.color_attributes.render_color_index = me.color_attributes.active_color_index
    except AttributeError:  # older API spelling
        pass
    return done


def write_colors(me: bpy.types.Mesh, rgba: np.ndarray, name: str = EASE_LAYER) -> None:
    """Write per-vertex scene-linear RGBA (V, 4) into colour layer ``name``,
    exactly as a brush stroke would leave it."""
    attr = me.color_attributes[name]
    rgba = np.ascontiguousarray(rgba, dtype=np.float32).reshape(-1, 4)
    if attr.domain == "POINT":
        attr.data.foreach_set("color", rgba.ravel())
    else:  # CORNER: every corner of a vertex gets its colour
        vi = np.empty(len(me.loops), dtype=np.int32)
        me.loops.foreach_get("vertex_index", vi)
        attr.data.foreach_set("color", rgba[vi].ravel())
    me.update()


def read_colors(me: bpy.types.Mesh, name: str = EASE_LAYER) -> tuple:
    """(colours, domain): scene-linear RGBA (n, 4) per vertex or per corner."""
    attr = me.color_attributes.get(name)
    if attr is None:
        raise KeyError(f"mesh {me.name!r} has no colour layer {name!r}")
    c = np.empty(len(attr.data) * 4, dtype=np.float32)
    attr.data.foreach_get("color", c)
    return c.reshape(-1, 4).astype(np.float64), attr.domain


# ----------------------------------------------------------------------------- keypoints


def write_keypoints(me: bpy.types.Mesh, keypoints: dict) -> None:
    """Store keypoints ``{name: (triangle, (b0, b1, b2))}`` as attribute layers.

    A FACE int layer says which keypoint sits on a triangle, a CORNER float
    layer holds its barycentric weights: both survive shape and pose changes
    (the topology is fixed) and a save.
    """
    nf = len(me.polygons)
    kp = np.zeros(nf, dtype=np.int32)
    bary = np.zeros(len(me.loops), dtype=np.float32)
    names = []
    for name, (tri, b) in keypoints.items():
        tri = int(tri)
        if not 0 <= tri < nf:
            raise ValueError(f"keypoint {name!r}: triangle {tri} is not on the body (0..{nf - 1})")
        if kp[tri]:
            # one keypoint per triangle (about 1 cm^2): the first one keeps it
            print(
                f"[ease] keypoints {names[kp[tri] - 1]!r} and {name!r} share triangle {tri}; "
                f"the layer keeps {names[kp[tri] - 1]!r}"
            )
            continue
        names.append(name)
        kp[tri] = len(names)
        bary[3 * tri : 3 * tri + 3] = np.asarray(b, dtype=np.float32)
    for lname, dom, typ in ((KEYPOINT_LAYER, "FACE", "INT"), (KEYPOINT_BARY_LAYER, "CORNER", "FLOAT")):
        if me.attributes.get(lname) is None:
            me.attributes.new(lname, typ, dom)
    me.attributes[KEYPOINT_LAYER].data.foreach_set("value", kp)
    me.attributes[KEYPOINT_BARY_LAYER].data.foreach_set("value", bary)
    me[KEYPOINT_NAMES] = json.dumps(names)


def read_keypoints(me: bpy.types.Mesh) -> dict:
    """Keypoints stored by :func:`write_keypoints`: ``{name: (triangle, (b0, b1, b2))}``."""
    if me.attributes.get(KEYPOINT_LAYER) is None or KEYPOINT_NAMES not in me:
        return {}
    names = json.loads(me[KEYPOINT_NAMES])
    kp = np.empty(len(me.polygons), dtype=np.int32)
    me.attributes[KEYPOINT_LAYER].data.foreach_get("value", kp)
    bary = np.empty(len(me.loops), dtype=np.float32)
    me.attributes[KEYPOINT_BARY_LAYER].data.foreach_get("value", bary)
    out = {}
    for tri in np.flatnonzero(kp):
        k = int(kp[tri]) - 1
        if 0 <= k < len(names):
            out[names[k]] = (int(tri), tuple(float(x) for x in bary[3 * tri : 3 * tri + 3]))
    return dict(sorted(out.items(), key=lambda kv: names.index(kv[0])))


def selected_vertices(me: bpy.types.Mesh) -> np.ndarray:
    """Indices of selected vertices (object mode data; call after leaving Edit Mode)."""
    sel = np.empty(len(me.vertices), dtype=bool)
    me.vertices.foreach_get("select", sel)
    return np.flatnonzero(sel)


def vertex_surface_point(faces: np.ndarray, vertex: int) -> tuple:
    """A (triangle, bary) surface point exactly at template vertex ``vertex``."""
    rows, cols = np.nonzero(np.asarray(faces) == int(vertex))
    if len(rows) == 0:
        raise ValueError(f"vertex {vertex} is in no triangle")
    b = [0.0, 0.0, 0.0]
    b[int(cols[0])] = 1.0
    return int(rows[0]), tuple(b)


# ----------------------------------------------------------------------------- scene data


def store_json(idblock, key: str, obj) -> None:
    """Keep a JSON-able value as a string custom property (saved in the .blend)."""
    idblock[key] = json.dumps(obj, sort_keys=True)


def load_json(idblock, key: str, default=None):
    s = idblock.get(key)
    return default if s in (None, "") else json.loads(s)
