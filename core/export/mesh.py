"""The draped garment as glTF 2.0 binary (GLB) and Wavefront OBJ, written by hand.

Each pattern piece becomes one mesh (one node, named after the piece) with
positions from the drape, smooth normals, triangle indices and texture
coordinates from the pattern: the piece's uv in metres, turned so that the
grain points along +v (the frame of the 2D exports). A fabric texture of 1 m
repeat then follows the grain on every piece. Seam vertices appear once per
piece (their uv differ).

Frames, one convention for every 3D file of the project: metres, the garment
where it was draped (the drape's own coordinates, the body's frame: +Z up,
the body facing -Y, +X the body's left, as in Blender). Every mesh file says
its frame in its header (:mod:`core.geom.frame`, one helper for all writers). glTF
requires +Y up, so ``garment.glb`` is always written as ``(x, z, -y)``
(Blender's glTF importer turns it back); the exported ``garment.obj`` is
written that way too by default (``up="y"``: OBJ readers, Blender's importer
included, assume Y-up), ``up="z"`` keeps the core frame. The exported files'
origin is on the floor by default (:data:`ORIGINS`: the body's lowest point at
height 0, under its root), or at the body's root. Each file states its frame
and origin (OBJ header comment, glTF ``asset.extras``); the OBJ's materials
are in ``garment.mtl`` beside it. With ``body`` the body the pattern was made on (its shape
and pose) is written beside the garment in the same frame: node/object
``body``.

glTF texture coordinates have v pointing down from the image top, so
``TEXCOORD_0 = (u, 1 - v)``; importers (Blender included) flip it back to the
pattern's ``(u, v)``. OBJ ``vt`` is ``(u, v)``.
"""

from __future__ import annotations

import json
import struct
from typing import List, Optional, Sequence, Tuple

import numpy as np

from ..geom.frame import (  # noqa: F401 (re-exported: the frame helpers of every mesh file)
    BODY_RGB,
    FABRIC_RGB,
    FRAME_Y,
    MTL_NAME,
    ORIGIN_TEXT,
    ORIGINS,
    UP_AXES,
    frame_text,
    mtl_material,
    mtl_text,
    to_frame,
    to_y_up,
)
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


def body_mesh(vertices: np.ndarray, faces: np.ndarray):
    """The body as a mesh for :func:`glb_bytes` / :func:`obj_text`: ("body", positions, normals, faces), core frame."""
    v = np.asarray(vertices, float)
    f = np.asarray(faces, np.int64)
    return ("body", v, smooth_normals(v, f), f)


def piece_meshes(pattern: Pattern, positions: np.ndarray, rotations: Sequence[np.ndarray]):
    """Per piece: name, garment, positions (n, 3), normals (n, 3), uv (n, 2), faces (f, 3), core frame."""
    out = []
    for panel, rot in zip(pattern.panels, rotations):
        xyz = np.asarray(positions, float)[np.asarray(panel.vertex_ids, int)]
        faces = np.asarray(panel.faces, int)
        uv = np.asarray(panel.uv, float) @ np.asarray(rot, float).T
        out.append((panel.name, panel.garment, xyz, smooth_normals(xyz, faces), uv, faces))
    return out


def gltf_material(name: str, rgb, roughness: float = 0.9, double_sided: bool = True, extras=None) -> dict:
    """A glTF PBR material: base colour ``rgb`` (linear), not metallic; ``extras`` (a dict) when given."""
    mat = {"name": name}
    if double_sided:
        mat["doubleSided"] = True
    mat["pbrMetallicRoughness"] = {
        "baseColorFactor": [float(c) for c in rgb] + [1.0],
        "metallicFactor": 0.0,
        "roughnessFactor": float(roughness),
    }
    if extras:
        mat["extras"] = dict(extras)
    return mat


def glb_bytes(
    meshes,
    generator: str = "EASE",
    body=None,
    origin: str = "root",
    materials: Optional[Sequence[dict]] = None,
    scene: str = "garment",
) -> bytes:
    """A GLB file from :func:`piece_meshes` output (+Y up, as glTF requires).

    One node + mesh + primitive per piece, grouped under one node per garment;
    float32 attributes, uint32 indices, one buffer. ``body``: :func:`body_mesh`
    output or None; written as the node ``body`` with its own material.
    ``materials``: glTF materials (:func:`gltf_material`), one per mesh, mesh ``k`` with
    ``materials[k]``; None: every mesh the one material ``fabric``. ``scene``: the scene's name.
    """
    own = list(materials) if materials is not None else [gltf_material("fabric", FABRIC_RGB)]
    if materials is not None and len(own) != len(meshes):
        raise ValueError(f"glb_bytes: expected one material per mesh ({len(meshes)}), got {len(own)}")
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
        acc = {
            "bufferView": add_view(data.tobytes(), target),
            "componentType": ctype,
            "count": int(data.shape[0]),
            "type": kind,
        }
        if minmax:
            acc["min"] = data.min(axis=0).astype(float).tolist()
            acc["max"] = data.max(axis=0).astype(float).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    for k, (name, garment, xyz, nrm, uv, faces) in enumerate(meshes):
        pos = to_y_up(xyz).astype(np.float32)
        attrs = {
            "POSITION": add_accessor(pos, "VEC3", 34962, minmax=True),
            "NORMAL": add_accessor(to_y_up(nrm).astype(np.float32), "VEC3", 34962),
            "TEXCOORD_0": add_accessor(np.column_stack([uv[:, 0], 1.0 - uv[:, 1]]).astype(np.float32), "VEC2", 34962),
        }
        idx = add_accessor(faces.reshape(-1).astype(np.uint32), "SCALAR", 34963)
        gl_meshes.append(
            {
                "name": name,
                "primitives": [
                    {"attributes": attrs, "indices": idx, "mode": 4, "material": k if materials is not None else 0}
                ],
            }
        )
        nodes.append({"name": name, "mesh": len(gl_meshes) - 1})
        garments.setdefault(garment or "garment", []).append(len(nodes) - 1)
    roots = []
    for garment, children in garments.items():
        nodes.append({"name": garment, "children": children})
        roots.append(len(nodes) - 1)
    if body is not None:
        name, xyz, nrm, faces = body
        attrs = {
            "POSITION": add_accessor(to_y_up(xyz).astype(np.float32), "VEC3", 34962, minmax=True),
            "NORMAL": add_accessor(to_y_up(nrm).astype(np.float32), "VEC3", 34962),
        }
        idx = add_accessor(faces.reshape(-1).astype(np.uint32), "SCALAR", 34963)
        gl_meshes.append(
            {"name": name, "primitives": [{"attributes": attrs, "indices": idx, "mode": 4, "material": len(own)}]}
        )
        nodes.append({"name": name, "mesh": len(gl_meshes) - 1})
        roots.append(len(nodes) - 1)
    while len(blob) % 4:
        blob.append(0)
    doc = {
        "asset": {"version": "2.0", "generator": generator, "extras": {"frame": frame_text("y", origin)}},
        "scene": 0,
        "scenes": [{"name": scene, "nodes": roots}],
        "nodes": nodes,
        "meshes": gl_meshes,
        "materials": own + ([gltf_material("body", BODY_RGB, 0.8, double_sided=False)] if body is not None else []),
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    # glTF JSON has no Infinity or NaN: refuse rather than write an invalid file
    js = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8")
    js += b" " * ((4 - len(js) % 4) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    return (
        struct.pack("<III", GLB_MAGIC, 2, total)
        + struct.pack("<II", len(js), CHUNK_JSON)
        + js
        + struct.pack("<II", len(blob), CHUNK_BIN)
        + bytes(blob)
    )


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
    doc = json.loads(data[20 : 20 + jlen].decode("utf-8"))
    off = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, off)
    if btype != CHUNK_BIN:
        raise ValueError("GLB: second chunk is not BIN")
    return doc, data[off + 8 : off + 8 + blen]


def glb_accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    """The array of accessor ``index`` (float32 or uint32)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
    dtype = {5126: np.float32, 5125: np.uint32}[acc["componentType"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    arr = np.frombuffer(binary, dtype=dtype, count=acc["count"] * comps, offset=start)
    return arr.reshape(acc["count"], comps) if comps > 1 else arr


def obj_text(
    meshes,
    style: str = "garment",
    up: str = "y",
    body=None,
    origin: str = "root",
    materials: Optional[Sequence[str]] = None,
    mtllib: str = MTL_NAME,
) -> str:
    """Wavefront OBJ (metres, ``up`` = ``"y"``: the OBJ readers' convention, or ``"z"``: the core frame) with
    ``vt`` from the pattern and ``vn``; one ``o`` per piece, and ``o body`` (no ``vt``) when ``body``
    (:func:`body_mesh` output) is given; materials from the library ``mtllib`` (:data:`MTL_NAME`:
    :func:`mtl_text`), ``materials`` the ``usemtl`` name of each mesh (None: ``fabric`` for every one).
    ``origin`` is only stated (the positions are given in it)."""
    if materials is not None and len(materials) != len(meshes):
        raise ValueError(f"obj_text: expected one material per mesh ({len(meshes)}), got {len(materials)}")
    lines: List[str] = [
        f"# EASE draped garment: {style}",
        f"# frame: {frame_text(up, origin)}",
        "# vt = pattern uv in metres, grain along +v",
        f"mtllib {mtllib}",
    ]
    base = 1
    for k, (name, garment, xyz, nrm, uv, faces) in enumerate(meshes):
        lines.append(f"o {name.replace(' ', '_')}")
        lines.append(f"usemtl {materials[k] if materials is not None else 'fabric'}")
        lines.extend(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_frame(xyz, up))
        lines.extend(f"vt {u:.6f} {v:.6f}" for u, v in uv)
        lines.extend(f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_frame(nrm, up))
        f = faces + base
        lines.extend(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}" for a, b, c in f)
        base += len(xyz)
    if body is not None:
        name, xyz, nrm, faces = body
        lines.append(f"o {name}")
        lines.append("usemtl body")
        lines.extend(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_frame(xyz, up))
        lines.extend(f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in to_frame(nrm, up))
        f = faces + base
        lines.extend(f"f {a}//{a} {b}//{b} {c}//{c}" for a, b, c in f)
    return "\n".join(lines) + "\n"
