"""The draped garment dressed for a render: what the fabric shader reads, and thickness.

:func:`dress_garment` writes on each garment mesh, from the scene's pattern
(the garment's faces are the pattern's, panel after panel):

- the UV map :data:`.materials.FABRIC_UV`: each corner's 2D pattern position in
  metres, turned so that V runs along the piece's grain line (warp) and U across
  it (weft), so the weave is laid on the cloth as it would be cut;
- the corner attributes :data:`.materials.SEAM_DIST` and :data:`.materials.HEM_DIST`:
  the distance in the piece (metres) from the nearest sewn edge and the
  nearest hem (exact where the edge is straight: a distance to a line is linear
  over a triangle);
- the colour attribute :data:`.materials.FABRIC_COLOR`: the design's colour of
  the garment each face belongs to (``materials.color`` in the design: one
  colour or one per garment, ``"#rrggbb"`` or ``[r, g, b]`` in 0..1, sRGB),
  else the preset's colour, a darker shade of it for a second garment;

and a Solidify modifier :data:`THICKNESS` at the fabric preset's thickness
(``core.drape.materials.PRESETS[...].thickness``, centred on the drape's
surface), and the preset's fabric material when no fit map is shown.
"""

from __future__ import annotations

import itertools

import numpy as np

from . import build, data, materials
from .objects import objects_with_role

THICKNESS = "EASE Thickness"


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) distance of each of ``points`` (n, 2) to the nearest segment a[i]-b[i] (m, 2); inf when m is 0."""
    if len(a) == 0:
        return np.full(len(points), np.inf)
    out = np.full(len(points), np.inf)
    d = b - a
    dd = np.maximum((d * d).sum(axis=1), 1e-30)
    for start in range(0, len(points), 2048):  # bounded memory: 2048 x m at a time
        p = points[start : start + 2048, None, :]
        t = np.clip(((p - a) * d).sum(axis=2) / dd, 0.0, 1.0)
        q = a + t[..., None] * d
        out[start : start + 2048] = np.sqrt(((p - q) ** 2).sum(axis=2)).min(axis=1)
    return out


def edge_distances(panel) -> tuple:
    """(seam, hem): (n,) distance of each vertex of ``panel`` to its nearest sewn boundary
    edge and to its nearest hem edge (metres, in the pattern's 2D)."""
    uv = np.asarray(panel.uv, dtype=np.float64)
    hem_edges = set()
    for h in panel.hems:
        h = [int(i) for i in h]
        hem_edges.update(frozenset(e) for e in itertools.pairwise(h))
    sewn, hem = [], []
    for loop in panel.boundary:
        loop = [int(i) for i in loop]
        for e in zip(loop, loop[1:] + loop[:1]):
            (hem if frozenset(e) in hem_edges else sewn).append(e)
    out = []
    for edges in (sewn, hem):
        e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        out.append(_segment_distance(uv, uv[e[:, 0]], uv[e[:, 1]]))
    return out[0], out[1]


def srgb_to_linear(c):
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _parse_color(value):
    """Linear RGB of a design colour (``"#rrggbb"`` or [r, g, b] in 0..1, sRGB); None when unreadable."""
    try:
        if isinstance(value, str):
            h = value.strip().lstrip("#")
            if len(h) != 6:
                return None
            rgb = [int(h[i : i + 2], 16) / 255.0 for i in (0, 2, 4)]
        else:
            rgb = [float(x) for x in value]
            if len(rgb) != 3 or not all(0.0 <= x <= 1.0 for x in rgb):
                return None
    except (TypeError, ValueError):
        return None
    return tuple(float(x) for x in srgb_to_linear(rgb))


def garment_colors(pattern, preset: str) -> dict:
    """garment name -> linear RGB: the design's ``materials.color`` where it names one, else the
    preset's colour (the first garment) and darker shades of it (the others)."""
    look = materials.LOOKS[preset]
    given = (pattern.materials or {}).get("color")
    out = {}
    for i, name in enumerate(pattern.garments):
        value = given.get(name) if isinstance(given, dict) else given
        rgb = _parse_color(value) if value is not None else None
        if rgb is None:
            rgb = tuple(c * (0.3**i) for c in look.color)
        out[name] = rgb
    return out


def _corner_layers(pattern, preset: str) -> dict:
    """Per corner of the garment's faces (panel order): global vertex id, UV, seam and hem distance, colour."""
    colors = garment_colors(pattern, preset)
    ids, uvs, seam, hem, rgba = [], [], [], [], []
    for p in pattern.panels:
        faces = np.asarray(p.faces, dtype=np.int64)
        uv = np.asarray(p.uv, dtype=np.float64)
        g = np.asarray(p.grain, dtype=np.float64)
        g = g / max(np.linalg.norm(g), 1e-12)
        turned = np.stack([uv @ np.array([g[1], -g[0]]), uv @ g], axis=1)  # U weft, V warp
        ds, dh = edge_distances(p)
        c = faces.ravel()
        ids.append(np.asarray(p.vertex_ids)[c])
        uvs.append(turned[c])
        seam.append(ds[c])
        hem.append(dh[c])
        rgba.append(np.tile([*colors[p.garment], 1.0], (len(c), 1)))
    return {
        "ids": np.concatenate(ids),
        "uv": np.concatenate(uvs),
        "seam": np.concatenate(seam),
        "hem": np.concatenate(hem),
        "rgba": np.concatenate(rgba),
    }


def _set_corner(me, name: str, kind: str, values: np.ndarray, key: str) -> None:
    attr = me.attributes.get(name)
    if attr is not None and (attr.domain != "CORNER" or attr.data_type != kind):
        me.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = me.attributes.new(name, kind, "CORNER")
    attr.data.foreach_set(key, np.ascontiguousarray(values, dtype=np.float32).ravel())


def thicken(obj, thickness: float):
    """The Solidify modifier :data:`THICKNESS` on ``obj`` (made once, then reused): ``thickness``
    metres, centred on the drape's surface, every vertex moved by half of it along its normal.

    No *Even Thickness*: it divides a vertex's offset by the cosine between its normal and its
    faces' normals, which is near 0 where the cloth folds flat on itself (a pressed fold, a
    gather's pleat: neighbouring triangles at 170-180 degrees), and turned such folds into
    spikes tens of centimetres long."""
    mod = obj.modifiers.get(THICKNESS)
    if mod is None:
        mod = obj.modifiers.new(THICKNESS, "SOLIDIFY")
    mod.solidify_mode = "EXTRUDE"
    mod.thickness = float(thickness)
    mod.offset = 0.0  # centred: the drape keeps the surface this far off the body
    mod.use_even_offset = False
    mod.use_rim = True
    return mod


def dress_garment(scene, obj, pattern=None) -> bool:
    """Write the fabric's layers on the garment ``obj``, its Solidify, its preset material.

    Returns False (layers left as they are) when the garment's faces are not the pattern's
    (a garment draped from another pattern)."""
    from ..core.drape.materials import PRESETS

    pattern = pattern if pattern is not None else data.stored_pattern(scene)
    preset = materials.scene_fabric(scene)
    me = obj.data
    thicken(obj, float(PRESETS[preset].thickness if preset in PRESETS else 0.003))
    if scene.ease.fitmap == "NONE" or not me.materials:
        mat = materials.fabric(preset)
        if me.materials:
            me.materials[0] = mat
        else:
            me.materials.append(mat)
    pattern = build.drape_pattern(obj, pattern)  # a refined drape mesh's: the pattern as draped
    if pattern is None:
        return False
    layers = _corner_layers(pattern, preset)
    vid = me.attributes.get(data.VERTEX_ID)
    if vid is None or len(me.loops) != len(layers["ids"]):
        return False
    per_vertex = np.empty(len(me.vertices), dtype=np.int32)
    vid.data.foreach_get("value", per_vertex)
    loop_vertex = np.empty(len(me.loops), dtype=np.int32)
    me.loops.foreach_get("vertex_index", loop_vertex)
    if not np.array_equal(per_vertex[loop_vertex], layers["ids"]):
        return False
    uv = me.uv_layers.get(materials.FABRIC_UV) or me.uv_layers.new(name=materials.FABRIC_UV)
    uv.data.foreach_set("uv", layers["uv"].astype(np.float32).ravel())
    _set_corner(me, materials.SEAM_DIST, "FLOAT", np.minimum(layers["seam"], 1.0), "value")
    _set_corner(me, materials.HEM_DIST, "FLOAT", np.minimum(layers["hem"], 1.0), "value")
    _set_corner(me, materials.FABRIC_COLOR, "FLOAT_COLOR", layers["rgba"], "color")
    me.update()
    return True


def dress_garments(scene) -> int:
    """:func:`dress_garment` on every garment of the scene (a Drape Animation's too); how many got
    the pattern's layers."""
    pattern = data.stored_pattern(scene)
    garments = objects_with_role(scene, "garment") + [
        o for o in objects_with_role(scene, "motion") if o.data.attributes.get(data.VERTEX_ID) is not None
    ]
    return sum(dress_garment(scene, o, pattern) for o in garments)
