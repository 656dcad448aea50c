"""Left/right mirroring of design elements and of surface points.

Names follow :mod:`core.design.naming` (``*_left`` <-> ``*_right``).
Definitions of lines and panels are mirrored by substituting names (so that a
mirrored line meets the other lines at exactly the same keypoints); keypoints
are mirrored geometrically through the body's symmetry map.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from typing import Optional

import numpy as np

from ..body.model import SurfacePoint
from ..errors import DesignError
from .naming import mirror_axis, mirrored_name, swap_side


def _mirror_ref(ref):
    """A keypoint reference (name or inline keypoint dict) on the other side."""
    if isinstance(ref, str):
        return swap_side(ref)
    ref = copy.deepcopy(ref)
    if "landmark" in ref:
        ref["landmark"] = swap_side(ref["landmark"])
    elif "between" in ref:
        ref["between"] = [_mirror_ref(r) for r in ref["between"]]
    elif "trace" in ref:
        ref["trace"]["from"] = _mirror_ref(ref["trace"]["from"])
        ref["trace"]["along"] = swap_side(ref["trace"]["along"])
    elif "triangle" in ref:
        # Inline surface points are mirrored geometrically at resolve time.
        ref = {"mirror_of": ref}
    return ref


def mirror_line(line):
    """The ``*_right`` counterpart of a ``*_left`` line definition."""
    if line.ring is not None:
        r = copy.deepcopy(line.ring)
        r["through"] = _mirror_ref(r["through"])
        r["normal"] = (
            mirror_axis(r["normal"]) if isinstance(r["normal"], str) else [_mirror_ref(x) for x in r["normal"]]
        )
        if "contains" in r:
            r["contains"] = _mirror_ref(r["contains"])
        r["named"] = {swap_side(k): (mirror_axis(v) if isinstance(v, str) else v) for k, v in r["named"].items()}
        # A reflection reverses the sense of rotation: fractions along the ring
        # then land on mirrored positions.
        r["handed"] = -int(r.get("handed", 1))
        return replace(line, name=mirrored_name(line.name), points=[], closed=True, ring=r, section=None)
    if line.section is not None:
        c = copy.deepcopy(line.section)
        c["from"], c["to"] = _mirror_ref(c["from"]), _mirror_ref(c["to"])
        c["normal"] = (
            mirror_axis(c["normal"]) if isinstance(c["normal"], str) else [_mirror_ref(x) for x in c["normal"]]
        )
        return replace(line, name=mirrored_name(line.name), points=[], closed=False, ring=None, section=c)
    return replace(
        line, name=mirrored_name(line.name), points=[_mirror_ref(p) for p in line.points], ring=None, section=None
    )


def mirror_ease(ease: dict) -> dict:
    ease = copy.deepcopy(ease)
    if "between" in ease:
        ease["between"] = [_mirror_ref(r) for r in ease["between"]]
    if "axis" in ease:
        ease["axis"] = mirror_axis(ease["axis"])
    if "per_triangle" in ease:
        ease["per_triangle"]["mirrored"] = True
    return ease


def mirror_panel(panel):
    """The ``*_right`` counterpart of a ``*_left`` panel definition."""
    return replace(panel, name=mirrored_name(panel.name), seed=_mirror_ref(panel.seed), ease=mirror_ease(panel.ease))


# ---------------------------------------------------------------- geometry


def face_symmetry(faces: np.ndarray, symmetry: np.ndarray) -> np.ndarray:
    """Mirror face of every face (F,), -1 where the template has none.

    Parameters
    ----------
    faces : (F, 3) int
    symmetry : (V,) int, mirror vertex of each vertex
    """
    faces = np.asarray(faces, dtype=np.int64)
    nv = int(symmetry.shape[0])
    key = np.sort(faces, axis=1)
    code = (key[:, 0] * nv + key[:, 1]) * nv + key[:, 2]
    mkey = np.sort(np.asarray(symmetry)[faces], axis=1)
    mcode = (mkey[:, 0] * nv + mkey[:, 1]) * nv + mkey[:, 2]
    order = np.argsort(code)
    pos = np.searchsorted(code[order], mcode)
    pos = np.clip(pos, 0, len(order) - 1)
    found = code[order][pos] == mcode
    return np.where(found, order[pos], -1)


def mirror_surface_point(
    sp: SurfacePoint, faces: np.ndarray, symmetry: np.ndarray, face_sym: Optional[np.ndarray] = None, locator=None
) -> SurfacePoint:
    """The mirror image of a surface point on a fixed-topology template.

    Maps the triangle's vertices through the symmetry map; when the template
    has no mirrored triangle there, falls back to locating the x-reflected
    position (``locator``: a :class:`core.design.geometry.SurfaceLocator` on
    the reference instance).
    """
    if face_sym is None:
        face_sym = face_symmetry(faces, symmetry)
    g = int(face_sym[sp.triangle])
    if g >= 0:
        src = np.asarray(symmetry)[faces[sp.triangle]]
        dst = list(faces[g])
        bary = [0.0, 0.0, 0.0]
        for v, b in zip(src, sp.bary):
            bary[dst.index(int(v))] = float(b)
        return SurfacePoint(g, tuple(bary))
    if locator is None:
        raise DesignError("mirror", f"triangle {sp.triangle} has no mirror triangle on the template")
    p = sp.position(locator.vertices, locator.faces).copy()
    p[0] = -p[0]
    return locator.locate(p[None])[0]
