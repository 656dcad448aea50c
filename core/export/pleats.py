"""Pleats and tucks on a pattern piece, as the cutting room marks them.

The export draws the opened piece (:func:`core.pattern.pleats.open_pattern`: the pleat's
cloth inserted as a strip, so the outline, the cut line and the marker include it) and
on it, per pleat (:class:`PleatDrawing`): its fold lines (fold the cloth here), its
placement line (bring the fold to this line), the end of a tuck's stitching, and a notch
at both ends of every fold and placement line, where they meet the sew line. In the
DXF-AAMA they are internal lines (layer 8), the stitching's end a drill hole (layer 13),
the notches on the notch layer (4), as the standard has it for darts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List

import numpy as np

from ..geom.polyline import point_at_length
from ..pattern.types import Pattern, PatternPanel
from .notches import Notch, slit


@dataclass
class PleatDrawing:
    """One pleat of a piece, in the piece frame (metres).

    Attributes
    ----------
    name : the pleat's name.
    kind : knife, box, inverted_box or tuck.
    folds, placements : lists of (k, 2) polylines, start (the pleat's ``from``) to end.
    stitch_ends : (m, 2) where a tuck's stitching ends (drill holes), empty for a pleat.
    """

    name: str
    kind: str
    folds: List[np.ndarray] = field(default_factory=list)
    placements: List[np.ndarray] = field(default_factory=list)
    stitch_ends: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def lines(self) -> List[np.ndarray]:
        """Every line drawn for the pleat (folds, then placements)."""
        return list(self.folds) + list(self.placements)


def _site(pattern: Pattern, name: str) -> dict:
    return next(s for s in pattern.report.get("pleats") or [] if s["name"] == name)


def piece_pleats(pattern: Pattern, panel: PatternPanel, xy: np.ndarray) -> List[PleatDrawing]:
    """The pleats drawn on ``panel`` of an opened pattern (``report["opened_pleats"]``), in the
    piece frame ``xy`` (the piece's uv rotated to the grain)."""
    drawn = (pattern.report.get("opened_pleats") or {}).get(panel.name) or []
    out: List[PleatDrawing] = []
    for line in drawn:
        if not out or out[-1].name != line["pleat"]:
            out.append(PleatDrawing(line["pleat"], _site(pattern, line["pleat"])["kind"]))
        poly = xy[np.asarray(line["ids"], int)]
        (out[-1].folds if line["kind"] == "fold" else out[-1].placements).append(poly)
    for p in out:
        site = _site(pattern, p.name)
        stitched = float(site.get("stitched_length") or 0.0)
        if stitched > 0 and p.folds:
            ends = [
                point_at_length(f, stitched)[0] for f in (p.folds[0], p.placements[-1] if p.placements else p.folds[-1])
            ]
            p.stitch_ends = np.asarray(ends)
    return out


def pleat_notches(pattern: Pattern, panel: PatternPanel, xy, loops, cut, edge_w) -> List[Notch]:
    """A notch at both ends of every fold and placement line of ``panel``'s pleats, on the sew line
    (``loops``: the sew line's loops as local ids, ``cut``: the cut line's, ``edge_w``: the
    allowance of each sew edge)."""
    drawn = (pattern.report.get("opened_pleats") or {}).get(panel.name) or []
    where = {int(v): (li, k) for li, loop in enumerate(loops) for k, v in enumerate(loop)}
    out = []
    for line in drawn:
        for side, v in (("a", line["ids"][0]), ("b", line["ids"][-1])):
            if int(v) not in where:
                continue
            li, k = where[int(v)]
            loop = loops[li]
            d = xy[loop[(k + 1) % len(loop)]] - xy[loop[k - 1]]
            nrm = np.array([d[1], -d[0]]) / max(np.linalg.norm(d), 1e-300)
            q = xy[int(v)]
            width = max(edge_w[li][k - 1], edge_w[li][k])
            out.append(
                Notch(seam=line["pleat"], side=side, s=0.0, point=q, normal=nrm, segment=slit(q, nrm, cut[li], width))
            )
    return out
