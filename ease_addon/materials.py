"""The add-on's materials: made once by name, reused after (a saved file keeps them).

Three kinds: a plain Principled surface (the skin of the body, the studio
floor), the fabric of the draped garment (one procedural shader per fabric
preset, :func:`fabric`) and one that shows a colour attribute (achieved ease on
the pattern pieces, the fit maps on the garment), in the viewport and in Cycles.

The fabric shader reads what :mod:`.render_fabric` writes on the garment mesh:
the UV map :data:`FABRIC_UV` (the pattern's 2D metres, V along the grain), the
corner attributes :data:`SEAM_DIST` / :data:`HEM_DIST` (metres from the nearest
sewn edge / hem) and the colour attribute :data:`FABRIC_COLOR` (the design's
colour per garment). Without them (a garment not yet through the studio) it
shows the preset's colour with no weave.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import bpy

from .objects import ensure_nodes

SKIN = "EASE Skin"
FABRIC = "EASE Fabric"  # + " <preset>"
FLOOR = "EASE Studio Floor"
ACHIEVED_EASE = "EASE Achieved Ease"

FABRIC_UV = "ease_fabric_uv"  # UV map: pattern metres, U across the grain (weft), V along it (warp)
SEAM_DIST = "ease_seam_dist"  # FLOAT corner attribute: metres to the nearest sewn edge of the piece
HEM_DIST = "ease_hem_dist"  # FLOAT corner attribute: metres to the nearest hem of the piece
FABRIC_COLOR = "ease_fabric_color"  # FLOAT_COLOR corner attribute: the garment's colour (alpha 1)

STITCH_FROM_SEAM = 0.006  # m: top-stitch line this far from a sewn edge
STITCH_FROM_HEM = 0.015  # m: hem stitch line this far from the hem
STITCH_WIDTH = 0.0012  # m: half width of a stitch line
CREASE_WIDTH = 0.005  # m: the seam's crease (a groove on the sewn edge) this wide


@dataclass(frozen=True)
class FabricLook:
    """How a fabric preset renders.

    weave : "plain" | "twill" | "satin" | "knit".
    thread_mm : the weave's repeat across the threads (mm), wale width for a knit.
    color : linear RGB of the preset (the design may name its own).
    roughness, sheen : Principled BSDF inputs.
    bump : strength of the weave's relief.
    stitch : linear RGB of the stitching (None: a lighter shade of the fabric).
    """

    weave: str
    thread_mm: float
    color: tuple[float, float, float]
    roughness: float
    sheen: float
    bump: float
    stitch: tuple[float, float, float] | None = None


LOOKS = {
    "cotton": FabricLook("plain", 0.45, (0.32, 0.44, 0.64), 0.78, 0.35, 0.35),
    "jersey": FabricLook("knit", 1.1, (0.20, 0.21, 0.23), 0.85, 0.55, 0.45),
    "denim": FabricLook("twill", 0.9, (0.045, 0.075, 0.17), 0.88, 0.25, 0.55, stitch=(0.55, 0.30, 0.07)),
    "silk": FabricLook("satin", 0.25, (0.72, 0.52, 0.36), 0.32, 0.85, 0.15),
    "wool": FabricLook("twill", 0.7, (0.13, 0.13, 0.15), 0.9, 0.45, 0.4),
}
DEFAULT_FABRIC = "cotton"
LOOK_VERSION = 1  # raise when the fabric shader changes: a saved file's fabric is then rebuilt


def _new(name: str):
    """(material, its Principled BSDF node or None) of a new material ``name`` with a node tree."""
    mat = bpy.data.materials.new(name)
    ensure_nodes(mat)
    bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
    return mat, bsdf


def surface(name: str, color, roughness: float, sheen: float = 0.0):
    """The material ``name``: a Principled surface of ``color`` (RGBA, scene linear)."""
    mat = bpy.data.materials.get(name)
    if mat is not None:
        return mat
    mat, bsdf = _new(name)
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = color
        bsdf.inputs["Roughness"].default_value = roughness
        if sheen:
            for socket in ("Sheen Weight", "Sheen"):  # Blender 4+ / 3.x spelling
                if socket in bsdf.inputs:
                    bsdf.inputs[socket].default_value = sheen
                    break
    mat.diffuse_color = color
    return mat


def skin():
    return surface(SKIN, (0.60, 0.43, 0.34, 1.0), 0.6)


def floor():
    """The studio's floor and backdrop: a light matte grey."""
    return surface(FLOOR, (0.30, 0.30, 0.32, 1.0), 0.85)


def scene_fabric(scene=None) -> str:
    """The fabric preset of the scene's pattern (else its design), ``cotton`` when it has neither."""
    from . import data

    scene = scene or bpy.context.scene
    name = None
    try:
        pattern = data.stored_pattern(scene)
        if pattern is not None:
            name = (pattern.materials or {}).get("fabric")
        if name is None and scene.ease.design_json:
            import json

            name = (json.loads(scene.ease.design_json).get("materials") or {}).get("fabric")
    except (ValueError, TypeError, AttributeError):  # an unreadable design: the design panel reports it
        name = None
    name = str(name or DEFAULT_FABRIC).strip().lower()
    return name if name in LOOKS else DEFAULT_FABRIC


class _Graph:
    """Small helper to wire shader nodes: each method adds a node and returns its output socket."""

    def __init__(self, nt):
        self.nt, self.x = nt, -1400

    def node(self, kind, **props):
        n = self.nt.nodes.new(kind)
        for k, v in props.items():
            setattr(n, k, v)
        n.location = (self.x, 0)
        self.x += 40
        return n

    def _in(self, sock, value):
        if hasattr(value, "is_output"):
            self.nt.links.new(value, sock)
        else:
            sock.default_value = value

    def math(self, op, a, b=0.0, c=0.0):
        n = self.node("ShaderNodeMath", operation=op)
        for sock, value in zip(n.inputs, (a, b, c)):
            self._in(sock, value)
        return n.outputs[0]

    def map_range(self, value, lo, hi, to_lo=0.0, to_hi=1.0, smooth=True):
        n = self.node("ShaderNodeMapRange", interpolation_type="SMOOTHSTEP" if smooth else "LINEAR", clamp=True)
        self._in(n.inputs["Value"], value)
        for i, v in zip((1, 2, 3, 4), (lo, hi, to_lo, to_hi)):
            n.inputs[i].default_value = v
        return n.outputs[0]

    def mix_rgb(self, fac, a, b):
        n = self.node("ShaderNodeMix", data_type="RGBA")
        self._in(n.inputs[0], fac)
        self._in(n.inputs[6], a)
        self._in(n.inputs[7], b)
        return n.outputs[2]

    def attribute(self, name):
        n = self.node("ShaderNodeAttribute", attribute_name=name)
        return n.outputs

    def sin01(self, x, period):
        """0.5 + 0.5 sin(2 pi x / period)."""
        return self.math("MULTIPLY_ADD", self.math("SINE", self.math("MULTIPLY", x, 2 * math.pi / period)), 0.5, 0.5)


def _weave_height(g: _Graph, u, v, look: FabricLook):
    """Height 0..1 of the weave at pattern coordinates ``u`` (weft), ``v`` (warp) in metres."""
    p = look.thread_mm / 1000.0
    if look.weave == "plain":  # over-under: a checker of thread crossings
        h = g.math(
            "MULTIPLY",
            g.math("SINE", g.math("MULTIPLY", u, math.pi / p)),
            g.math("SINE", g.math("MULTIPLY", v, math.pi / p)),
        )
        return g.math("MULTIPLY_ADD", h, 0.5, 0.5)
    if look.weave == "twill":  # diagonal wales (3/1 twill) over fine warp threads
        wale = g.sin01(g.math("ADD", u, v), p)
        return g.math("MULTIPLY_ADD", g.sin01(u, p / 3.0), 0.25, g.math("MULTIPLY", wale, 0.75))
    if look.weave == "satin":  # long floats along the warp: a faint, fine rib
        return g.sin01(g.math("ADD", u, g.math("MULTIPLY", v, 0.2)), p)
    # knit: columns of V-shaped loops (wales along the warp, courses across)
    across = g.math("FRACT", g.math("DIVIDE", u, p))  # 0..1 across a wale
    chevron = g.math("ABSOLUTE", g.math("SUBTRACT", across, 0.5))  # 0.5 at the edges, 0 mid
    course = g.sin01(g.math("ADD", g.math("DIVIDE", v, 0.8 * p), chevron), 1.0)
    loop = g.math("SINE", g.math("MULTIPLY", across, math.pi))  # each loop rounded across
    return g.math("MULTIPLY", course, loop)


def fabric(preset: str | None = None):
    """The fabric material of ``preset`` (default: the current scene's, :func:`scene_fabric`):
    the weave or knit as bump (scaled in mm on the pattern's UV map), sheen, the design's
    colour (attribute :data:`FABRIC_COLOR`, else the preset's), a top-stitch line along the
    sewn edges and a crease on them, a stitch line along the hems."""
    preset = preset if preset in LOOKS else scene_fabric()
    name = f"{FABRIC} {preset}"
    mat = bpy.data.materials.get(name)
    if mat is not None and mat.get("ease_look") == LOOK_VERSION:
        return mat
    look = LOOKS[preset]
    if mat is None:
        mat, bsdf = _new(name)
    else:  # made by an earlier version of the add-on (a saved file): rebuilt in place, slots keep it
        ensure_nodes(mat)
        mat.node_tree.nodes.clear()
        out = mat.node_tree.nodes.new("ShaderNodeOutputMaterial")
        bsdf = mat.node_tree.nodes.new("ShaderNodeBsdfPrincipled")
        mat.node_tree.links.new(bsdf.outputs[0], out.inputs["Surface"])
        out.location = (400, 0)
    mat["ease_fabric"] = preset
    mat["ease_look"] = LOOK_VERSION
    g = _Graph(mat.node_tree)
    uv = g.node("ShaderNodeUVMap", uv_map=FABRIC_UV)
    sep = g.node("ShaderNodeSeparateXYZ")
    g.nt.links.new(uv.outputs["UV"], sep.inputs[0])
    u, v = sep.outputs[0], sep.outputs[1]
    weave = _weave_height(g, u, v, look)
    # fibre irregularity and slubs: noise at a few threads and a few cm
    fibre = g.node("ShaderNodeTexNoise", noise_dimensions="2D")
    g.nt.links.new(uv.outputs["UV"], fibre.inputs["Vector"])
    fibre.inputs["Scale"].default_value = 1000.0 / (4 * look.thread_mm)
    fibre.inputs["Detail"].default_value = 2.0
    slub = g.node("ShaderNodeTexNoise", noise_dimensions="2D")
    g.nt.links.new(uv.outputs["UV"], slub.inputs["Vector"])
    slub.inputs["Scale"].default_value = 25.0
    # seams: a stitch line at STITCH_FROM_SEAM from the sewn edge and a groove on it; hems: a stitch line
    seam_d = g.attribute(SEAM_DIST)[2]
    hem_d = g.attribute(HEM_DIST)[2]
    has_seams = g.attribute(FABRIC_COLOR)[3]  # alpha 1 where the studio wrote the garment's layers

    def line(dist, at):
        off = g.math("ABSOLUTE", g.math("SUBTRACT", dist, at))
        return g.map_range(off, STITCH_WIDTH, 0.5 * STITCH_WIDTH, 0.0, 1.0)

    stitch = g.math(
        "MULTIPLY", g.math("MAXIMUM", line(seam_d, STITCH_FROM_SEAM), line(hem_d, STITCH_FROM_HEM)), has_seams
    )
    # a stitch is dashed: the thread shows ~4 mm in 6 along the line (diagonal dashes read as stitches
    # in every direction of the seam)
    dash = g.map_range(g.sin01(g.math("ADD", u, v), 0.006), 0.2, 0.35)
    stitch = g.math("MULTIPLY", stitch, dash)
    crease = g.math("MULTIPLY", g.map_range(seam_d, CREASE_WIDTH, 0.0), has_seams)
    height = g.math("ADD", g.math("MULTIPLY", weave, 0.7), g.math("MULTIPLY", fibre.outputs["Fac"], 0.3))
    height = g.math("ADD", height, g.math("MULTIPLY", stitch, 0.8))  # the thread stands proud
    height = g.math("SUBTRACT", height, g.math("MULTIPLY", crease, 1.5))  # the seam sinks in
    bump = g.node("ShaderNodeBump")
    bump.inputs["Strength"].default_value = look.bump
    bump.inputs["Distance"].default_value = 0.3 * look.thread_mm / 1000.0
    g.nt.links.new(height, bump.inputs["Height"])
    # seam relief wider than a thread: a second bump on the first's normal
    seam_bump = g.node("ShaderNodeBump")
    seam_bump.inputs["Strength"].default_value = 0.6
    seam_bump.inputs["Distance"].default_value = 0.0006
    g.nt.links.new(g.math("SUBTRACT", 0.0, crease), seam_bump.inputs["Height"])
    g.nt.links.new(bump.outputs["Normal"], seam_bump.inputs["Normal"])
    # colour: the design's (attribute) or the preset's, shaded by the weave, the slubs, the crease
    rgb = (*look.color, 1.0)
    design = g.attribute(FABRIC_COLOR)
    base = g.mix_rgb(design[3], rgb, design[0])
    shade = g.math("ADD", g.math("MULTIPLY", weave, 0.16), 0.84)
    shade = g.math("MULTIPLY", shade, g.math("MULTIPLY_ADD", slub.outputs["Fac"], 0.12, 0.94))
    shade = g.math("MULTIPLY", shade, g.math("SUBTRACT", 1.0, g.math("MULTIPLY", crease, 0.7)))
    shaded = g.node("ShaderNodeMix", data_type="RGBA", blend_type="MULTIPLY")
    shaded.inputs[0].default_value = 1.0
    g.nt.links.new(base, shaded.inputs[6])
    comb = g.node("ShaderNodeCombineXYZ")
    for i in range(3):
        g.nt.links.new(shade, comb.inputs[i])
    g.nt.links.new(comb.outputs[0], shaded.inputs[7])
    thread = (*look.stitch, 1.0) if look.stitch else None
    if thread is None:  # a shade of the fabric that shows on it: darker on light cloth, lighter on dark
        light = sum(look.color) / 3 > 0.25
        shade_of = g.node("ShaderNodeMix", data_type="RGBA", blend_type="MULTIPLY" if light else "SCREEN")
        shade_of.inputs[0].default_value = 0.6
        g.nt.links.new(base, shade_of.inputs[6])
        shade_of.inputs[7].default_value = (0.2, 0.2, 0.2, 1.0) if light else (1.0, 1.0, 1.0, 1.0)
        thread = shade_of.outputs[2]
    color = g.mix_rgb(stitch, shaded.outputs[2], thread)
    if bsdf is not None:
        g.nt.links.new(color, bsdf.inputs["Base Color"])
        g.nt.links.new(seam_bump.outputs["Normal"], bsdf.inputs["Normal"])
        bsdf.inputs["Roughness"].default_value = look.roughness
        bsdf.inputs["Sheen Weight"].default_value = look.sheen
        bsdf.inputs["Sheen Roughness"].default_value = 0.35
        bsdf.inputs["Sheen Tint"].default_value = (1.0, 1.0, 1.0, 1.0)
        bsdf.location = (g.x + 200, 0)
    mat.diffuse_color = rgb
    mat.roughness = look.roughness
    return mat


def attribute(name: str, layer: str):
    """The material ``name`` showing the colour attribute ``layer`` as its base colour."""
    mat = bpy.data.materials.get(name)
    if mat is not None:
        return mat
    mat, bsdf = _new(name)
    nt = mat.node_tree
    attr = nt.nodes.new("ShaderNodeAttribute")
    attr.attribute_name = layer
    attr.location = (-300, 200)
    if bsdf is not None:
        nt.links.new(attr.outputs["Color"], bsdf.inputs["Base Color"])
        bsdf.inputs["Roughness"].default_value = 0.8
    return mat
