"""Gathered seams sewn as gathers: the long side keeps its length and is stitched along the short one.

A gathered seam (:attr:`core.pattern.types.PatternSeam.gathered`) has a longer
side that is eased into a shorter one. Welding the two sides vertex by vertex
(what the pattern's shared vertex ids do) ties each long-side vertex to one
short-side vertex. Here instead, as GarmentCode sews ruffles, the long side
gets its own particles (:func:`unweld_gathers`; its two ends stay welded to the
short side's), is refined on its own rest lengths, and each of its vertices is
stitched to the point of the short side at the same fraction of the arc length
(:func:`stitches`): the long side keeps its rest length, lies along the short
one, and the cloth behind it has to fold (ruffle) to fit.

A stitch to the point at fraction ``t`` of the short segment (i, j) of rest
length ``s`` is a pair of distance constraints, to i at ``t s`` and to j at
``(1 - t) s``: both hold only on the segment, at ``t``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import List

import numpy as np

#: A long-side vertex closer than this fraction of a short segment to one of its ends is welded to that end.
WELD_FRACTION = 1e-6


@dataclass
class Stitches:
    """The stitches of the gathered seams, as particles.

    Attributes
    ----------
    long : (S,) int, the long-side particle of each stitch.
    short : (S, 2) int, the ends (i, j) of the short-side segment it is sewn to.
    t : (S,) float in (0, 1), the stitch point ``(1 - t) x_i + t x_j``.
    seg : (S,) float, rest length of that short segment, metres.
    seam : (S,) int, index of the gathered seam in ``names``.
    names : list of str, the gathered seams' names.
    ratio : list of float, each seam's long / short rest length.
    """

    long: np.ndarray
    short: np.ndarray
    t: np.ndarray
    seg: np.ndarray
    seam: np.ndarray
    names: List[str]
    ratio: List[float]

    @staticmethod
    def none() -> "Stitches":
        return Stitches(
            np.zeros(0, np.int64), np.zeros((0, 2), np.int64), np.zeros(0), np.zeros(0), np.zeros(0, np.int64), [], []
        )

    def __len__(self) -> int:
        return int(len(self.long))

    def edges(self) -> tuple:
        """The stitches as distance constraints: (2S, 2) int particle pairs and (2S,) rest lengths (m)."""
        e = np.concatenate([np.stack([self.long, self.short[:, 0]], 1), np.stack([self.long, self.short[:, 1]], 1)])
        r = np.concatenate([self.t * self.seg, (1.0 - self.t) * self.seg])
        return e.astype(np.int64).reshape(-1, 2), r

    def points(self, x: np.ndarray) -> np.ndarray:
        """(S, 3) the stitch points on the short side for particle positions ``x``."""
        return (1.0 - self.t)[:, None] * x[self.short[:, 0]] + self.t[:, None] * x[self.short[:, 1]]

    def gaps(self, x: np.ndarray) -> np.ndarray:
        """(S,) distance (m) of each long-side particle from its stitch point."""
        return np.linalg.norm(x[self.long] - self.points(x), axis=1)


def arc(uv: np.ndarray) -> np.ndarray:
    """Cumulative arc length (k,) of a polyline (k, 2), 0 at its start."""
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(uv, axis=0), axis=1))])


def long_side(pattern, seam) -> int:
    """0 when side a of ``seam`` is the longer in the pattern (rest) shape, else 1."""
    ua, ub = pattern.seam_polylines(seam)
    return 0 if arc(ua)[-1] >= arc(ub)[-1] else 1


def unweld_gathers(pattern):
    """A copy of ``pattern`` whose gathered seams' long sides have their own vertex ids.

    The interior vertices of each gathered seam's long side get new global ids
    (after every id in use); its two end vertices keep theirs, so the seam's
    ends stay sewn. A pinned id that is split stays pinned on both sides.
    Panels that no gathered seam touches are shared with ``pattern``, not copied.
    """
    gathered = [s for s in pattern.seams if getattr(s, "gathered", False)]
    if not gathered:
        return pattern
    panels = {p.name: p for p in pattern.panels}
    new_ids = {p.name: np.asarray(p.vertex_ids, np.int64).copy() for p in pattern.panels}
    next_id = max((int(np.max(p.vertex_ids)) + 1 for p in pattern.panels if len(p.vertex_ids)), default=0)
    pins = {g: np.asarray(v, np.int64).reshape(-1) for g, v in (pattern.pins or {}).items()}
    for s in gathered:
        side = long_side(pattern, s)
        name, verts = (s.panel_a, s.verts_a) if side == 0 else (s.panel_b, s.verts_b)
        inner = np.asarray(verts, np.int64)[1:-1]
        if name == (s.panel_b if side == 0 else s.panel_a):
            # both sides in one panel (not a dart: those are never gathered): keep the short side's ids
            other = set(np.asarray(s.verts_b if side == 0 else s.verts_a, np.int64).tolist())
            inner = np.array([v for v in inner.tolist() if v not in other], np.int64)
        old = new_ids[name][inner]
        fresh = np.arange(next_id, next_id + len(inner), dtype=np.int64)
        next_id += len(inner)
        new_ids[name][inner] = fresh
        for g, ids in pins.items():
            hit = np.isin(old, ids)
            if hit.any():
                pins[g] = np.concatenate([ids, fresh[hit]])
    out_panels = [
        replace(p, vertex_ids=new_ids[p.name]) if not np.array_equal(new_ids[p.name], p.vertex_ids) else p
        for p in panels.values()
    ]
    return replace(pattern, panels=out_panels, pins=pins)


def stitches(pattern) -> tuple:
    """Stitches of the gathered seams of ``pattern`` (already unwelded, possibly refined).

    Each long-side vertex is sewn to the point of the short side at the same
    fraction of the rest arc length (both sides run from index 0, where they
    meet). Vertices at a fraction that falls on a short-side vertex (the seam's
    ends, at least) are welded to it instead.

    Parameters
    ----------
    pattern : the pattern, whose gathered seams' sides may have different vertex counts.

    Returns
    -------
    :class:`Stitches` in global vertex ids (:func:`to_particles` maps them), and the (W, 2) int
    global id pairs to weld (the ends).
    """
    names, ratio, rows, welds = [], [], [], []
    for s in pattern.seams:
        if not getattr(s, "gathered", False):
            continue
        pa, pb = pattern.panel(s.panel_a), pattern.panel(s.panel_b)
        side = long_side(pattern, s)
        (pl, vl), (ps, vs) = ((pa, s.verts_a), (pb, s.verts_b)) if side == 0 else ((pb, s.verts_b), (pa, s.verts_a))
        vl, vs = np.asarray(vl, np.int64), np.asarray(vs, np.int64)
        al, as_ = arc(pl.uv[vl]), arc(ps.uv[vs])
        if al[-1] <= 0 or as_[-1] <= 0:
            continue
        k = len(names)
        names.append(s.name)
        ratio.append(float(al[-1] / as_[-1]))
        gl = np.asarray(pl.vertex_ids, np.int64)[vl]
        gs = np.asarray(ps.vertex_ids, np.int64)[vs]
        where = al / al[-1] * as_[-1]  # the arc position of each long vertex, carried to the short side
        seg = np.clip(np.searchsorted(as_, where, side="right") - 1, 0, len(as_) - 2)
        length = as_[seg + 1] - as_[seg]
        t = np.where(length > 0, (where - as_[seg]) / np.maximum(length, 1e-300), 0.0)
        for n in range(len(vl)):
            if t[n] <= WELD_FRACTION:
                welds.append((gl[n], gs[seg[n]]))
            elif t[n] >= 1.0 - WELD_FRACTION:
                welds.append((gl[n], gs[seg[n] + 1]))
            else:
                rows.append((gl[n], gs[seg[n]], gs[seg[n] + 1], t[n], length[n], k))
    welds = np.array(welds, np.int64).reshape(-1, 2)
    if not rows:
        return replace(Stitches.none(), names=names, ratio=ratio), welds
    r = np.array(rows, dtype=float)
    g = r[:, :3].astype(np.int64)
    return (
        Stitches(
            long=g[:, 0],
            short=g[:, 1:3],
            t=r[:, 3],
            seg=r[:, 4],
            seam=r[:, 5].astype(np.int64),
            names=names,
            ratio=ratio,
        ),
        welds,
    )


def to_particles(st: Stitches, particle_of: np.ndarray) -> Stitches:
    """The stitches with global ids mapped to particles (after welding)."""
    return replace(st, long=particle_of[st.long], short=particle_of[st.short].reshape(-1, 2))
