"""Ease fields: the target weft scale rho per cut triangle (warp is 1.0 at design time).

Kinds (per panel, in the design's ``ease``):

- uniform ``{"value": 1.2}``;
- linear gradient between two keypoints ``{"from": 1.0, "to": 1.6, "between": [a, b]}``:
  rho = from at ``a``, to at ``b``, linear in the projection of each triangle's
  centroid on the segment a -> b, constant beyond its ends;
- linear gradient along an axis ``{"from": 1.0, "to": 1.6, "axis": "-z"}``:
  ramps over the panel's own extent along the axis (``from`` where the
  coordinate along the axis is smallest: ``"-z"`` runs top -> bottom); with
  ``"over": "garment"`` over the extent of the whole garment instead (a dress
  whose ease rises from the neckline to the hem across all its panels);
- per body-template triangle ``{"per_triangle": {"triangles": [...], "values":
  [...], "default": 1.0}}`` (or ``{"values": [...]}`` with one value per
  template triangle): each cut triangle takes the value of the template
  triangle it lies on, so the field survives re-cuts and parameter changes;
  triangles not listed take ``default``. This is what the Blender add-on's
  ease painting writes.

Gradients and triangle lookups are evaluated on the reference instance (the
one the design is cut on), so the same field transfers to every shape and pose.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..errors import DesignError
from .checks import EASE_MAX, EASE_MIN
from .mirror import mirror_ease
from .parser import load_design
from .resolve import AXIS_VECTORS, Resolver


def _centroids(cut, panel, vertices) -> np.ndarray:
    X = cut.panel_positions(panel, vertices)
    return X[panel.faces].mean(axis=1)


def _garment_extent(cut, garment, direction, vertices):
    proj = [(_centroids(cut, p, vertices) @ direction) for p in cut.panels if p.garment == garment]
    proj = np.concatenate(proj) if proj else np.zeros(0)
    return (float(proj.min()), float(proj.max())) if proj.size else (0.0, 0.0)


def panel_ease(cut, panel, ease: dict, resolver: Resolver, path: str) -> np.ndarray:
    """Target weft scale (f,) for the triangles of one cut ``panel``.

    Parameters
    ----------
    cut : GarmentCut
    panel : core.cut.types.Panel
    ease : dict, a validated ease field (see module docs)
    resolver : Resolver on the reference instance
    path : JSON path of the field, for errors
    """
    nf = len(panel.faces)
    if "value" in ease:
        rho = np.full(nf, float(ease["value"]))
    elif "from" in ease:
        c = _centroids(cut, panel, resolver.vertices)
        if "between" in ease:
            a = resolver.position(resolver.ref(ease["between"][0], f"{path}.between[0]"))
            b = resolver.position(resolver.ref(ease["between"][1], f"{path}.between[1]"))
            ab = b - a
            if ab @ ab < 1e-12:
                raise DesignError(f"{path}.between", "the two keypoints coincide")
            t = (c - a) @ ab / (ab @ ab)
        else:
            axis = np.asarray(AXIS_VECTORS[ease["axis"]], dtype=float)
            proj = c @ axis
            if ease.get("over") == "garment":
                lo, hi = _garment_extent(cut, panel.garment, axis, resolver.vertices)
            else:
                lo, hi = (float(proj.min()), float(proj.max())) if nf else (0.0, 0.0)
            t = (proj - lo) / (hi - lo) if hi > lo else np.zeros(nf)
        t = np.clip(t, 0.0, 1.0)
        rho = ease["from"] + t * (ease["to"] - ease["from"])
    elif "per_triangle" in ease:
        pt = ease["per_triangle"]
        nbody = len(resolver.faces)
        c = _centroids(cut, panel, resolver.vertices)
        _, tri, _ = resolver.locator.closest(c) if nf else (None, np.zeros(0, dtype=np.int64), None)
        if pt.get("mirrored"):
            # the field is painted for the *_left panel: read it at the mirror triangle
            tri = np.where(resolver.face_sym[tri] >= 0, resolver.face_sym[tri], tri)
        if "triangles" in pt:
            tris = np.asarray(pt["triangles"], dtype=np.int64)
            bad = np.flatnonzero(tris >= nbody)
            if bad.size:
                raise DesignError(
                    f"{path}.per_triangle.triangles[{bad[0]}]",
                    f"triangle {tris[bad[0]]} does not exist (the body has {nbody} triangles)",
                )
            table = np.full(nbody, float(pt.get("default", 1.0)))
            table[tris] = np.asarray(pt["values"], dtype=float)
        else:
            if len(pt["values"]) != nbody:
                raise DesignError(
                    f"{path}.per_triangle.values",
                    f"expected {nbody} values (one per body template triangle), got {len(pt['values'])}",
                )
            table = np.asarray(pt["values"], dtype=float)
        rho = table[tri]
    else:  # pragma: no cover - validated on load
        raise DesignError(path, "unknown ease field")
    rho = np.asarray(rho, dtype=np.float64)
    bad = ~np.isfinite(rho) | (rho < EASE_MIN - 1e-12) | (rho > EASE_MAX + 1e-12)
    if bad.any():
        raise DesignError(
            path, f"panel {panel.name!r}: ease must be finite and within {EASE_MIN}..{EASE_MAX}, got {rho[bad][0]}"
        )
    return rho


def apply_ease(cut, design, body, body_vertices: np.ndarray, resolver: Optional[Resolver] = None):
    """Fill ``Panel.ease`` of every panel of ``cut`` from the design's ease fields.

    Parameters
    ----------
    cut : GarmentCut, cut from ``design`` (panel names ``garment.panel``)
    design : Design | dict | path
    body : BodyModel
    body_vertices : (V, 3) float, the reference instance the design was cut on

    Returns
    -------
    cut : the same GarmentCut, with ``ease`` (f,) set on each panel.
    """
    design = load_design(design)
    if resolver is None:
        resolver = Resolver(design, body, body_vertices)
    for panel in cut.panels:
        ease, path, generated = _panel_field(design, panel.name)
        panel.ease = panel_ease(cut, panel, ease, resolver, path)
        if generated and "per_triangle" in ease:
            _check_right_side(cut, panel, ease["per_triangle"], resolver, path)
        if panel.mirror_of is not None and not generated and not _is_mirror_ease(cut, design, panel, resolver):
            # a right panel with ease of its own (painted without X-mirror) is a piece of
            # its own: the export must not cut it as the mirror of the left one
            panel.mirror_of = None
    return cut


def _panel_field(design, name: str) -> tuple:
    """``(ease field, JSON path, generated)`` of the cut panel ``name`` (a generated
    ``*_right`` panel reads its ``*_left`` source's field mirrored)."""
    g, p, i, mirrored = design.find_panel(name)
    gi = design.garments.index(g)
    return (mirror_ease(p.ease) if mirrored else p.ease), f"garments[{gi}].panels[{i}].ease", mirrored


def _is_mirror_ease(cut, design, panel, resolver) -> bool:
    """True when ``panel.ease`` (a design panel's own field) is its ``mirror_of`` source's
    field read mirrored (to the 6 decimals the add-on writes ease with)."""
    try:
        source, path, _ = _panel_field(design, panel.mirror_of)
    except DesignError:  # the source is not a design panel: nothing to compare with
        return True
    mirrored = panel_ease(cut, panel, mirror_ease(source), resolver, path)
    return bool(np.allclose(mirrored, panel.ease, rtol=0.0, atol=1e-6))


def _check_right_side(cut, panel, pt: dict, resolver, path: str) -> None:
    """Refuse a per-triangle field that a generated ``*_right`` panel would drop: one with values
    of its own on the body triangles under that panel (listed, as their mirror triangles are, and
    not under the ``*_left`` source panel) that differ from the mirror of the left side. The
    generated panel reads the field at the mirror triangles only (a mirror piece), so that paint
    would be lost without a word."""
    nbody = len(resolver.faces)
    if "triangles" in pt:
        listed = np.zeros(nbody, dtype=bool)
        listed[np.asarray(pt["triangles"], dtype=np.int64)] = True
        table = np.full(nbody, float(pt.get("default", 1.0)))
        table[np.asarray(pt["triangles"], dtype=np.int64)] = np.asarray(pt["values"], dtype=float)
    else:
        listed, table = np.ones(nbody, dtype=bool), np.asarray(pt["values"], dtype=float)

    def under(p) -> np.ndarray:
        if not len(p.faces):
            return np.zeros(0, dtype=np.int64)
        return np.asarray(resolver.locator.closest(_centroids(cut, p, resolver.vertices))[1], dtype=np.int64)

    try:
        source = cut.panel(panel.mirror_of) if panel.mirror_of else None
    except KeyError:
        source = None
    own = np.unique(under(panel))
    if source is not None:
        own = np.setdiff1d(own, under(source))
    mirror = resolver.face_sym[own]
    keep = (mirror >= 0) & listed[own] & listed[np.maximum(mirror, 0)]
    t, m = own[keep], mirror[keep]
    diff = np.abs(table[t] - table[m])
    bad = diff > 1e-6
    if bad.any():
        left = panel.mirror_of.partition(".")[2] if panel.mirror_of else "its *_left panel"
        right = panel.name.partition(".")[2]
        raise DesignError(
            f"{path}.per_triangle",
            f"the field differs on the right side ({int(bad.sum())} triangles under the generated panel "
            f"{right!r}, by up to {float(diff.max()):.3f}) from the mirror of {left!r}'s, which {right!r} "
            f"would take instead: make the field symmetric, or give {right!r} a panel and ease of its own",
        )
