"""The frames of the project's mesh files: one helper for every writer.

Inside the code the frame is fixed: metres, +Z up, the body facing -Y, +X the
body's left (Blender's frame). OBJ and glTF readers assume +Y up, so every mesh
file is written Y-up by default, as ``(x, z, -y)`` (:func:`to_y_up`); ``up="z"``
keeps the core frame. Each file says its frame in its header (:func:`frame_text`).
"""

from __future__ import annotations

import numpy as np

#: the frame of the core (every array in the code): Blender's
FRAME = "metres, +Z up, the body facing -Y, +X the body's left (EASE/Blender frame)"
#: a mesh file's up axis: ``"y"`` (the default of OBJ and glTF readers) or ``"z"`` (the core frame)
UP_AXES = ("y", "z")
FRAME_Y = "metres, +Y up, the body facing +Z, +X the body's left (glTF frame: EASE (x, y, z) -> (x, z, -y))"
#: where a mesh file's origin is: ``"floor"`` (under the body's root, at the height of the body's lowest
#: point, so the body stands on the floor as glTF/OBJ viewers expect) or ``"root"`` (the body's root, the core frame)
ORIGINS = ("floor", "root")
ORIGIN_TEXT = {
    "floor": "origin on the floor: under the body's root, at the body's lowest point",
    "root": "origin at the body's root (the pelvis)",
}


#: the OBJ's material library, written beside it
MTL_NAME = "garment.mtl"


#: base colours (RGB, linear) of the garment's material ``fabric`` and the body's ``body``, in every mesh file
FABRIC_RGB = (0.8, 0.8, 0.8)
BODY_RGB = (0.93, 0.78, 0.66)


def mtl_material(name: str, rgb, comment: str = "") -> list:
    """The lines of one ``newmtl`` of an OBJ material library (diffuse ``rgb``), after a ``# comment``."""
    r, g, b = rgb
    head = [f"# {comment}"] if comment else []
    return head + [f"newmtl {name}", f"Kd {r:.3f} {g:.3f} {b:.3f}", "Ka 0 0 0", "Ks 0 0 0", "Ns 10", "d 1", "illum 1"]


def mtl_text(meshes=None, body=None) -> str:
    """The OBJ's material library: ``fabric`` (the garment, its uv the pattern's) and ``body``, as in the GLB."""
    lines = ["# EASE materials for garment.obj"] + mtl_material("fabric", FABRIC_RGB)
    if body is not None:
        lines += [""] + mtl_material("body", BODY_RGB)
    return "\n".join(lines) + "\n"


def frame_text(up: str, origin: str = "root", what: str = "as draped") -> str:
    """What a mesh file says about its frame: axes (``up``), ``what`` the positions are, and the origin."""
    axes = FRAME_Y if up == "y" else FRAME
    return f"{axes}, {what}; {ORIGIN_TEXT[origin]}" if what else f"{axes}; {ORIGIN_TEXT[origin]}"


def check_up(up: str, field: str = "--up") -> str:
    """``up`` if it is one of :data:`UP_AXES`, else ValueError naming ``field``."""
    if up not in UP_AXES:
        raise ValueError(f"{field}: expected {' or '.join(UP_AXES)}, got {up!r}")
    return up


def to_y_up(v: np.ndarray) -> np.ndarray:
    """(..., 3) points or normals in the core's Z-up frame -> (x, z, -y) in glTF/OBJ Y-up."""
    v = np.asarray(v, float)
    return np.stack([v[..., 0], v[..., 2], -v[..., 1]], axis=-1)


def to_frame(v: np.ndarray, up: str) -> np.ndarray:
    """Core-frame points or normals (..., 3) in the file frame ``up`` (``"z"``: unchanged, ``"y"``: :func:`to_y_up`)."""
    return to_y_up(v) if check_up(up, "up") == "y" else np.asarray(v, float)


def from_frame(v: np.ndarray, up: str) -> np.ndarray:
    """Points (..., 3) read from a file in frame ``up`` back in the core frame (the inverse of :func:`to_frame`)."""
    v = np.asarray(v, float)
    if check_up(up, "up") == "z":
        return v
    return np.stack([v[..., 0], -v[..., 2], v[..., 1]], axis=-1)


__all__ = [
    "FRAME",
    "UP_AXES",
    "FRAME_Y",
    "ORIGINS",
    "ORIGIN_TEXT",
    "frame_text",
    "check_up",
    "to_y_up",
    "to_frame",
    "from_frame",
    "MTL_NAME",
    "mtl_text",
    "mtl_material",
    "FABRIC_RGB",
    "BODY_RGB",
]
