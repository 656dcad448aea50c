"""An outfit's draped garments in one GLB / OBJ: every garment its own mesh with its own material.

Same frames as :mod:`core.export.mesh` (Y-up, origin on the floor: the body's lowest point at
height 0). Each garment is one mesh (its pieces joined; a seam vertex appears once per piece, its
uv differ), named after its layer, with the material ``<layer>`` (its fabric named in the glTF
material's ``extras`` and in the MTL comment); texture coordinates are the pattern's, grain along +v.
"""

from __future__ import annotations

from typing import Dict, Sequence

import numpy as np

from ..geom.layout import grain_rotation
from . import mesh

#: Base colours (RGB, linear) of the layers' materials, inner first (cycled): the files' and the add-on's.
LAYER_COLOURS = ((0.92, 0.92, 0.88), (0.20, 0.27, 0.42), (0.55, 0.35, 0.22), (0.35, 0.45, 0.30))
OUTFIT_MTL = "outfit.mtl"


def garment_mesh(name: str, pattern, positions: np.ndarray, floor: float):
    """One garment as a :func:`core.export.mesh.glb_bytes` mesh: its pieces joined, positions from the drape."""
    from ..pattern.pleats import open_pattern

    worn = open_pattern(pattern)
    pieces = mesh.piece_meshes(
        worn, np.asarray(positions, float) - [0.0, 0.0, floor], [grain_rotation(p.grain) for p in worn.panels]
    )
    xyz, nrm, uv, faces, base = [], [], [], [], 0
    for _, _, x, n, u, f in pieces:
        xyz.append(x)
        nrm.append(n)
        uv.append(u)
        faces.append(f + base)
        base += len(x)
    return (name, name, np.concatenate(xyz), np.concatenate(nrm), np.concatenate(uv), np.concatenate(faces))


def _layer_rgb(k: int):
    return LAYER_COLOURS[k % len(LAYER_COLOURS)]


def _mtl_name(name: str) -> str:
    return name.replace(" ", "_")


def outfit_glb(meshes, fabrics: Sequence[str]) -> bytes:
    """GLB of the garment meshes (:func:`garment_mesh`), mesh ``k`` with material ``k`` (its fabric in extras)."""
    materials = [
        mesh.gltf_material(m[0], _layer_rgb(k), extras={"fabric": f}) for k, (m, f) in enumerate(zip(meshes, fabrics))
    ]
    return mesh.glb_bytes(meshes, generator="EASE outfit", origin="floor", materials=materials, scene="outfit")


def outfit_obj(meshes, fabrics: Sequence[str], title: str) -> Dict[str, bytes]:
    """``outfit.obj`` and ``outfit.mtl``: one ``o`` per garment, each ``usemtl`` its own material."""
    names = [_mtl_name(m[0]) for m in meshes]
    text = mesh.obj_text(meshes, title, up="y", origin="floor", materials=names, mtllib=OUTFIT_MTL)
    mtl = ["# EASE materials for outfit.obj, one per garment"]
    for k, (name, fabric) in enumerate(zip(names, fabrics)):
        mtl += [""] + mesh.mtl_material(name, _layer_rgb(k), f"fabric: {fabric}")
    return {"outfit.obj": text.encode("utf-8"), OUTFIT_MTL: ("\n".join(mtl) + "\n").encode("utf-8")}


def outfit_files(garments, floor: float, formats=("glb", "obj"), title: str = "outfit") -> Dict[str, bytes]:
    """``{file name: bytes}`` of the outfit: ``garments`` is ``[(layer name, DrapeResult, Pattern)]``, inner first."""
    meshes = [garment_mesh(name, pattern, result.positions, floor) for name, result, pattern in garments]
    fabrics = [str(result.material.get("name", "")) for _, result, _ in garments]
    files: Dict[str, bytes] = {}
    if "glb" in formats:
        files["outfit.glb"] = outfit_glb(meshes, fabrics)
    if "obj" in formats:
        files.update(outfit_obj(meshes, fabrics, title))
    return files
