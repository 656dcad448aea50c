"""Input checks of the pattern stage: a cut and a body instance, refused with the element named."""

from __future__ import annotations

import numpy as np

from ..errors import PatternError


def validate_cut(cut) -> None:
    """Raise :class:`PatternError` naming the first invalid element of a GarmentCut."""
    if not cut.panels:
        raise PatternError("cut has no panels")
    N = cut.n_vertices
    names = set()
    for p in cut.panels:
        if p.name in names:
            raise PatternError(f"panel {p.name!r}: duplicate name")
        names.add(p.name)
        F = np.asarray(p.faces)
        vids = np.asarray(p.vertex_ids)
        if F.ndim != 2 or F.shape[0] == 0 or F.shape[1] != 3:
            raise PatternError(
                f"panel {p.name!r}: empty panel (faces must be a non-empty (f, 3) array, got shape {F.shape})"
            )
        if vids.ndim != 1 or vids.size < 3:
            raise PatternError(f"panel {p.name!r}: vertex_ids must list >= 3 vertices")
        if F.min() < 0 or F.max() >= vids.size:
            raise PatternError(f"panel {p.name!r}: faces index outside [0, {vids.size})")
        if vids.min() < 0 or vids.max() >= N:
            raise PatternError(f"panel {p.name!r}: vertex_ids outside the embedding's {N} rows")
        ease = np.asarray(p.ease, float)
        if ease.shape != (F.shape[0],):
            raise PatternError(
                f"panel {p.name!r}: ease must have one value per triangle ({F.shape[0]}), got shape {ease.shape}"
            )
        bad = ~np.isfinite(ease) | (ease <= 0)
        if np.any(bad):
            t = int(np.argmax(bad))
            raise PatternError(f"panel {p.name!r}: ease of triangle {t} is {ease[t]}; expected a finite weft scale > 0")
        wd = np.asarray(p.warp_dir, float)
        if wd.shape != (F.shape[0], 3) or not np.all(np.isfinite(wd)):
            raise PatternError(f"panel {p.name!r}: warp_dir must be a finite (f, 3) array, got shape {wd.shape}")
    for s in cut.seams:
        for side in ("panel_a", "panel_b"):
            if getattr(s, side) not in names:
                raise PatternError(f"seam {s.name!r}: {side} {getattr(s, side)!r} is not a panel of the cut")
        va, vb = np.asarray(s.verts_a), np.asarray(s.verts_b)
        if va.ndim != 1 or va.shape != vb.shape or va.size < 2:
            raise PatternError(
                f"seam {s.name!r}: verts_a and verts_b must be equally long polylines of >= 2 "
                f"vertices, got {va.shape} and {vb.shape}"
            )
        for side, v in (("a", va), ("b", vb)):
            n = len(cut.panel(getattr(s, f"panel_{side}")).vertex_ids)
            if v.min() < 0 or v.max() >= n:
                raise PatternError(f"seam {s.name!r}: verts_{side} outside [0, {n})")


def body_positions(cut, body_vertices, what: str) -> np.ndarray:
    """The cut's vertex positions (N, 3) on the body instance ``body_vertices`` (V, 3), checked.

    ``what`` names the body in the error (``"reference body"``, ``"pose 2"``).
    """
    X = np.asarray(body_vertices, float)
    if X.ndim != 2 or X.shape[1] != 3 or not np.all(np.isfinite(X)):
        raise PatternError(f"{what}: expected finite body vertices (V, 3), got shape {X.shape}")
    if X.shape[0] != cut.embedding.shape[1]:
        raise PatternError(f"{what}: has {X.shape[0]} vertices, the cut's embedding expects {cut.embedding.shape[1]}")
    return cut.positions(X)
