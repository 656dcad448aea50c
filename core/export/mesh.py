"""The draped garment as glTF 2.0 binary (GLB) and Wavefront OBJ, written by hand.

Each pattern piece becomes one mesh (one node, named after the piece) with
positions from the drape, smooth normals, triangle indices and texture
coordinates from the pattern: the piece's uv in metres, turned so that the
grain points along +v (the frame of the 2D exports). A fabric texture of 1 m
repeat then follows the grain on every piece. Seam vertices appear once per
piece (their uv differ).

Frames: the core is +Z up, -Y forward (Blender); glTF is +Y up, +Z forward,
so positions and normals are written as ``(x, z, -y)`` (Blender's glTF and
OBJ importers turn them back). glTF texture coordinates have v pointing down
from the image top, so ``TEXCOORD_0 = (u, 1 - v)``; importers (Blender
included) flip it back to the pattern's ``(u, v)``. OBJ ``vt`` is ``(u, v)``.
"""
from __future__ import annotations

import json
import struct
from typing import List, Sequence, Tuple

import numpy as np

from ..geom.mesh import vertex_normals
from ..pattern.types import Pattern

GLB_MAGIC = 0x46546C67  # "glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942


def smooth_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals for the files (:func:`core.geom.mesh.vertex_normals`).

    Parameters
    ----------
    positions : (n, 3) float. faces : (f, 3) int.

    Returns
    -------
    (n, 3) float; a vertex in no face (or only in degenerate ones) gets
    (0, 0, 1), since glTF requires unit normals.
    """
    vn = vertex_normals(positions, faces)
    vn[np.linalg.norm(vn, axis=1) < 0.5] = (0.0, 0.0, 1.0)
    return vn


def to_y_up(v: np.ndarray) -> np.ndarray:
    """(x, y, z) in the core's Z-up frame -> (x, z, -y) in glTF/OBJ Y-up."""
    v = np.asarray(v, float)
    return np.column_stack([v[:, 0], v[:, 2], -v[:, 1]])


def piece_meshes(pattern: Pattern, positions: np.ndarray, rotations: Sequence[np.ndarray]):
    """Per piece: name, garment, positions (n, 3), normals (n, 3), uv (n, 2), faces (f, 3), core frame."""
    out = []
    for panel, rot in zip(pattern.panels, rotations):
        xyz = np.asarray(positions, float)[np.asarray(panel.vertex_ids, int)]
        faces = np.asarray(panel.faces, int)
        uv = np.asarray(panel.uv, float) @ np.asarray(rot, float).T
        out.append((panel.name, panel.garment, xyz, smooth_normals(xyz, faces), uv, faces))
    return out


def glb_bytes(meshes, generator: str = "EASE") -> bytes:
    """A GLB file from :func:`piece_meshes` output.

    One node + mesh + primitive per piece, grouped under one node per garment;
    float32 attributes, uint32 indices, one buffer.
    """
    blob = bytearray()
    views, accessors, gl_meshes, nodes = [], [], [], []
    garments = {}

    def add_view(data: bytes, target: int) -> int:
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        blob.extend(data)
        return len(views) - 1

    def add_accessor(arr: np.ndarray, kind: str, target: int, minmax: bool = False) -> int:
        if arr.dtype.kind == "f":
            data, ctype = np.ascontiguousarray(arr, np.float32), 5126
        else:
            data, ctype = np.ascontiguousarray(arr, np.uint32), 5125
        acc = {"bufferView": add_view(data.tobytes(), target), "componentType": ctype,
               "count": int(data.shape[0]), "type": kind}
        if minmax:
            acc["min"] = data.min(axis=0).astype(float).tolist()
            acc["max"] = data.max(axis=0).astype(float).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    for name, garment, xyz, nrm, uv, faces in meshes:
        pos = to_y_up(xyz).astype(np.float32)
        attrs = {"POSITION": add_accessor(pos, "VEC3", 34962, minmax=True),
                 "NORMAL": add_accessor(to_y_up(nrm).astype(np.float32), "VEC3", 34962),
                 "TEXCOORD_0": add_accessor(np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float32),
                                            "VEC2", 34962)}
        idx = add_accessor(faces.reshape(-1).astype(np.uint32), "SCALAR", 34963)
        gl_meshes.append({"name": name, "primitives": [{"attributes": attrs, "indices": idx, "mode": 4,
                                                        "material": 0}]})
        nodes.append({"name": name, "mesh": len(gl_meshes) - 1})
        garments.setdefault(garment or "garment", []).append(len(nodes) - 1)
    roots = []
    for garment, children in garments.items():
        nodes.append({"name": garment, "children": children})
        roots.append(len(nodes) - 1)
    while len(blob) % 4:
        blob.append(0)
    doc = {"asset": {"version": "2.0", "generator": generator},
           "scene": 0, "scenes": [{"name": "garment", "nodes": roots}], "nodes": nodes, "meshes": gl_meshes,
           "materials": [{"name": "fabric", "doubleSided": True,
                          "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                                   "metallicFactor": 0.0, "roughnessFactor": 0.9}}],
           "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
    js = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    js += b" " * ((4 - len(js) % 4) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    return (struct.pack("<III", GLB_MAGIC, 2, total) + struct.pack("<II", len(js), CHUNK_JSON) + js
            + struct.pack("<II", len(blob), CHUNK_BIN) + bytes(blob))


def read_glb(data: bytes) -> Tuple[dict, bytes]:
    """Parse a GLB into its JSON document and binary chunk (checks the header)."""
    if len(data) < 20:
        raise ValueError("GLB: file too short")
    magic, version, total = struct.unpack_from("<III", data, 0)
    if magic != GLB_MAGIC or version != 2 or total != len(data):
        raise ValueError("GLB: bad header")
    jlen, jtype = struct.unpack_from("<II", data, 12)
    if jtype != CHUNK_JSON:
        raise ValueError("GLB: first chunk is not JSON")
    doc = json.loads(data[20:20 + jlen].decode("utf-8"))
    off = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, off)
    if btype != CHUNK_BIN:
        raise ValueError("GLB: second chunk is not BIN")
    return doc, data[off + 8:off + 8 + blen]


def glb_accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    """The array of accessor ``index`` (float32 or uint32)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
    dtype = {5126: np.float32, 5125: np.uint32}[acc["componentType"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    arr = np.frombuffer(binary, dtype=dtype, count=acc["count"] * comps, offset=start)
    return arr.reshape(acc["count"], comps) if comps > 1 else arr


def obj_text(meshes, style: str = "garment") -> str:
    """Wavefront OBJ (Y-up, metres) with ``vt`` from the pattern and ``vn``; one ``o`` per piece."""
    lines: List[str] = [f"# EASE draped garment: {style}", "# units: metres, +Y up; vt = pattern uv in metres"]
    base = 1
    for name, garment, xyz, nrm, uv, faces in meshes:
        lines.append(f"o {name.replace(' ', '_')}")
        lines.extend(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_y_up(xyz))
        lines.extend(f"vt {u:.6f} {v:.6f}" for u, v in uv)
        lines.extend(f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_y_up(nrm))
        f = faces + base
        lines.extend(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}" for a, b, c in f)
        base += len(xyz)
    return "\n".join(lines) + "\n"
