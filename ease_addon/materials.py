"""The add-on's materials: made once by name, reused after (a saved file keeps them).

Two kinds: a plain Principled surface (the skin of the body, the fabric of
the draped garment) and one that shows a colour attribute (achieved ease on
the pattern pieces, the fit maps on the garment), in the viewport and in Cycles.
"""
from __future__ import annotations

import bpy

from .objects import ensure_nodes

SKIN = "EASE Skin"
FABRIC = "EASE Fabric"
ACHIEVED_EASE = "EASE Achieved Ease"


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
            for socket in ("Sheen Weight", "Sheen"):    # Blender 4+ / 3.x spelling
                if socket in bsdf.inputs:
                    bsdf.inputs[socket].default_value = sheen
                    break
    mat.diffuse_color = color
    return mat


def skin():
    return surface(SKIN, (0.78, 0.62, 0.52, 1.0), 0.6)


def fabric():
    return surface(FABRIC, (0.18, 0.32, 0.55, 1.0), 0.9, sheen=0.5)


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
