"""Pleats in the drape: the opened pattern's strips start folded, pressed creases held.

:func:`core.drape.simulate.drape` drapes the opened pattern
(:func:`core.pattern.pleats.open_pattern` with its stitching): the strip of each pleat
starts folded under the cloth it lies beneath, each layer lifted :data:`LAYER_GAP
<core.pattern.pleats.LAYER_GAP>` off the one below (so nothing starts inside the body or
inside another layer), a pleat's two edges are welded at its start (a tuck's over its
stitched length). :func:`fold_rest` gives the bending stencils along a pressed pleat's fold
lines the rest angle :data:`CREASE_MAX`, folded the way the strip starts, and
:data:`PRESSED_STIFFNESS` times the cloth's bending: the crease is held as pressed. An
open pleat (``"pressed": false``) keeps the flat rest angle of any cloth and falls into
soft folds.

:func:`draped_cloth` is the one way a pattern becomes the cloth that is draped (the static drape,
the drape through a motion, the add-on's fabric UVs on a draped garment all read it): pleats
opened and stitched, the mesh refined and gathers sewn where asked, pressed creases held.
"""

from __future__ import annotations

import numpy as np

#: m, a bending stencil's edge whose ends both lie this close to a fold line (at the start) is on it
ON_FOLD = 0.0002
#: a pressed crease bends this many times stiffer than the cloth around it (pressing sets the fold)
PRESSED_STIFFNESS = 50.0
#: rad, the rest angle of a pressed crease (172 degrees), turned the way the strip starts folded: held at
#: 180 degrees the angle would flip sign with any motion; at 149 degrees (2.6) the knife-pleated skirt's
#: folds stood 12.5 mm off their placement lines after 40 frames (median), at 172 degrees 9 mm
CREASE_MAX = 3.0
#: m, a pressed pleat's visible fold is tied this far from its placement line (one layer of the drape's
#: start, :data:`LAYER_GAP <core.pattern.pleats.LAYER_GAP>`; less where it starts closer)
TIE_REST = 0.003
#: rad, a stencil on a fold line is a crease where it starts folded by more than this
FOLDED = 1.0


def _distance_to_polyline(x: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Distance (n,) of points ``x`` (n, 3) to the polyline ``poly`` (k, 3)."""
    a, b = poly[:-1], poly[1:]
    ab = b - a
    L2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    best = np.full(len(x), np.inf)
    for k in range(len(a)):
        t = np.clip((x - a[k]) @ ab[k] / L2[k], 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(x - (a[k] + t[:, None] * ab[k]), axis=1))
    return best


def fold_edges(cloth, pattern) -> np.ndarray:
    """(B,) bool: the cloth's bending stencils whose shared edge lies on a pressed pleat's fold line
    (the opened pattern's ``report["opened_pleats"]``; found by position at the start, so a
    refined drape mesh's split fold edges count too)."""
    drawn = (getattr(pattern, "report", None) or {}).get("opened_pleats") or {}
    on = np.zeros(len(cloth.bends), bool)
    if not drawn or not len(cloth.bends):
        return on
    pressed = {s["name"]: bool(s.get("pressed", True)) for s in pattern.report.get("pleats") or []}
    e0, e1 = cloth.x0[cloth.bends[:, 2]], cloth.x0[cloth.bends[:, 3]]
    for lines in drawn.values():
        for line in lines:
            if line["kind"] != "fold" or not pressed.get(line["pleat"], True):
                continue
            part = cloth.particle_of[np.asarray(line["gids"], np.int64)]
            poly = cloth.x0[part[part >= 0]]
            if len(poly) < 2:
                continue
            # only the stencils whose edge lies in the line's box (grown by ON_FOLD) can be on it
            lo, hi = poly.min(axis=0) - ON_FOLD, poly.max(axis=0) + ON_FOLD
            near = np.flatnonzero(np.all((e0 >= lo) & (e0 <= hi) & (e1 >= lo) & (e1 <= hi), axis=1))
            near = near[_distance_to_polyline(e0[near], poly) < ON_FOLD]
            on[near[_distance_to_polyline(e1[near], poly) < ON_FOLD]] = True
    return on


def fold_rest(cloth, pattern) -> None:
    """Pressed pleats hold their crease: every bending stencil on a pressed fold line (:func:`fold_edges`)
    rests at :data:`CREASE_MAX`, folded the way the pre-folded strip starts, and bends
    :data:`PRESSED_STIFFNESS` times stiffer."""
    from .mesh import dihedral_angles

    on = np.flatnonzero(fold_edges(cloth, pattern))
    start = dihedral_angles(cloth.x0, cloth.bends[on])
    on, start = on[np.abs(start) > FOLDED], start[np.abs(start) > FOLDED]  # a stencil along a fold lying flat: cloth
    if len(on):
        cloth.bend_rest = np.asarray(cloth.bend_rest, float).copy()
        cloth.bend_rest[on] = np.sign(start) * CREASE_MAX
        cloth.bend_weight = np.asarray(cloth.bend_weight, float).copy()
        cloth.bend_weight[on] *= PRESSED_STIFFNESS


def fold_ties(cloth, pattern) -> int:
    """Pressed pleats stay closed: each visible fold of a pressed pleat (a strip's first line, and its
    last where that is a fold: an inverted box pleat's second visible fold) is tied, row by row, to
    the strip's placement line by a distance constraint (the cloth's stretch stiffness, like a sliver
    edge: ``cloth.edges``) at its start distance, at most :data:`TIE_REST`. Rows already welded (the
    stitching at the start) or starting on the placement line are left out. Returns the number of
    ties added."""
    drawn = (getattr(pattern, "report", None) or {}).get("opened_pleats") or {}
    pressed = {s["name"]: bool(s.get("pressed", True)) for s in pattern.report.get("pleats") or []}
    pairs = []
    for lines in drawn.values():
        by_strip = {}
        for line in lines:
            if pressed.get(line["pleat"], True):
                by_strip.setdefault((line["pleat"], line["strip"]), []).append(line)
        for strip in by_strip.values():  # lines in their order across the strip
            place = [x for x in strip if x["kind"] == "placement"]
            if not place:
                continue
            visible = [strip[0]] + ([strip[-1]] if strip[-1]["kind"] == "fold" and len(strip) > 1 else [])
            for fold in visible:
                a = cloth.particle_of[np.asarray(fold["gids"], np.int64)]
                b = cloth.particle_of[np.asarray(place[0]["gids"], np.int64)]
                ok = (a >= 0) & (b >= 0) & (a != b)
                pairs.append(np.stack([a[ok], b[ok]], axis=1))
    pairs = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    start = np.linalg.norm(cloth.x0[pairs[:, 1]] - cloth.x0[pairs[:, 0]], axis=1)
    pairs, start = pairs[start > 1e-6], start[start > 1e-6]  # a row starting on its placement: no direction to hold
    if len(pairs):
        cloth.edges = np.concatenate([np.asarray(cloth.edges, np.int64).reshape(-1, 2), pairs])
        cloth.edge_rest = np.concatenate([np.asarray(cloth.edge_rest, float), np.minimum(start, TIE_REST)])
    return len(pairs)


def draped_cloth(pattern, refine_edge=None):
    """The :class:`core.drape.mesh.Cloth` a drape of ``pattern`` simulates: its pleats opened with
    their stitching (:func:`core.pattern.pleats.open_pattern`), welded by
    :func:`core.drape.mesh.build_cloth` (``refine_edge``, m or None: the free-hanging cloth
    refined to that edge, gathered seams sewn as gathers; None: the pattern's mesh, gathers
    welded as paired), pressed creases at rest on their fold (:func:`fold_rest`). Its
    ``mesh_pattern`` is the pattern as draped: its panels' triangles are the drape's faces."""
    from ..pattern.pleats import open_pattern
    from .mesh import build_cloth

    opened = open_pattern(pattern, stitch=True)
    cloth = build_cloth(opened, refine_edge=refine_edge, gathers=refine_edge is not None)
    fold_rest(cloth, opened)
    fold_ties(cloth, opened)
    return cloth
