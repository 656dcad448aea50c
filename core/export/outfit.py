"""An outfit's draped garments in one GLB / OBJ: every garment its own mesh with its own material.

Same frames as :mod:`core.export.mesh` (Y-up, origin on the floor: the body's lowest point at
height 0). Each garment is one mesh (its pieces joined; a seam vertex appears once per piece, its
uv differ), named after its layer, with the material ``<layer>`` (its fabric named in the glTF
material's ``extras`` and in the MTL comment); texture coordinates are the pattern's, grain along +v.
"""

from __future__ import annotations

import json
import struct
from typing import Dict, List, Sequence, Tuple

import numpy as np

from ..geom.layout import grain_rotation
from . import mesh

#: Base colours of the layers' materials, inner first (cycled).
LAYER_COLOURS = ((0.92, 0.92, 0.88), (0.20, 0.27, 0.42), (0.55, 0.35, 0.22), (0.35, 0.45, 0.30))


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


def _materials(garments: Sequence[Tuple[str, str]]) -> List[dict]:
    out = []
    for k, (name, fabric) in enumerate(garments):
        r, g, b = LAYER_COLOURS[k % len(LAYER_COLOURS)]
        out.append(
            {
                "name": name,
                "doubleSided": True,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [r, g, b, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.9,
                },
                "extras": {"fabric": fabric},
            }
        )
    return out


def outfit_glb(meshes, fabrics: Sequence[str]) -> bytes:
    """GLB of the garment meshes (:func:`garment_mesh`), mesh ``k`` with material ``k`` (its fabric in extras)."""
    doc, blob = mesh.read_glb(mesh.glb_bytes(meshes, generator="EASE outfit", origin="floor"))
    doc["materials"] = _materials([(m[0], f) for m, f in zip(meshes, fabrics)])
    for k, m in enumerate(doc["meshes"]):
        for prim in m["primitives"]:
            prim["material"] = k
    doc["scenes"][0]["name"] = "outfit"
    js = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
    js += b" " * ((4 - len(js) % 4) % 4)
    blob = bytes(blob) + b"\0" * ((4 - len(blob) % 4) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    return (
        struct.pack("<III", mesh.GLB_MAGIC, 2, total)
        + struct.pack("<II", len(js), mesh.CHUNK_JSON)
        + js
        + struct.pack("<II", len(blob), mesh.CHUNK_BIN)
        + blob
    )


def outfit_obj(meshes, fabrics: Sequence[str], title: str) -> Dict[str, bytes]:
    """``outfit.obj`` and ``outfit.mtl``: one ``o`` per garment, each ``usemtl`` its own material."""
    text = mesh.obj_text(meshes, title, up="y", origin="floor").replace(f"mtllib {mesh.MTL_NAME}", "mtllib outfit.mtl")
    lines, k = [], 0
    for line in text.split("\n"):
        if line == "usemtl fabric":
            line = f"usemtl {meshes[k][0].replace(' ', '_')}"
            k += 1
        lines.append(line)
    mtl = ["# EASE materials for outfit.obj, one per garment"]
    for j, (m, fabric) in enumerate(zip(meshes, fabrics)):
        r, g, b = LAYER_COLOURS[j % len(LAYER_COLOURS)]
        mtl += ["", f"# fabric: {fabric}", f"newmtl {m[0].replace(' ', '_')}", f"Kd {r:.3f} {g:.3f} {b:.3f}"]
        mtl += ["Ka 0 0 0", "Ks 0 0 0", "Ns 10", "d 1", "illum 1"]
    return {"outfit.obj": "\n".join(lines).encode("utf-8"), "outfit.mtl": ("\n".join(mtl) + "\n").encode("utf-8")}


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
