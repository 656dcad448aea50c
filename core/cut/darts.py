"""The darts of a cut: each dart line's seam checked to be one seam of its panel with
itself, and the record the pattern and export stages read (:attr:`GarmentCut.darts`).

A dart line runs from its mouth (on a seam or hem line) to its sewn point inside
the panel; :func:`core.cut.panels.build_panels` makes it a seam whose two sides are
the dart's legs, sharing the apex vertex (:func:`core.cut.types.seam_kind`).
"""

from __future__ import annotations

from typing import Dict, List

import numpy as np

from ..errors import DesignError
from .types import Seam, seam_kind


def dart_records(spec, seams: List[Seam], body_vertices: np.ndarray, body_faces: np.ndarray) -> Dict[str, dict]:
    """``{dart seam name: record}`` for every dart line of ``spec`` (see :attr:`GarmentCut.darts`).

    Raises
    ------
    DesignError, at the dart's JSON path, when its line does not give one dart seam in its
    own panel: it leaves the panel (crosses another cut line, or its apex lies in another
    panel) or its mouth is not on the panel's boundary.
    """
    out = {}
    for line in spec.lines:
        d = getattr(line, "dart", None)
        if d is None:
            continue
        mine = [s for s in seams if s.name == line.name or s.name.startswith(line.name + "#")]
        panels = sorted({p for s in mine for p in (s.panel_a, s.panel_b)})
        if len(mine) != 1 or panels != [d.panel] or seam_kind(mine[0]) != "dart":
            where = (
                f"it runs through panels {', '.join(panels)}"
                if panels and panels != [d.panel]
                else f"it gives {len(mine)} stretches"
                if len(mine) != 1
                else f"its mouth is not on the edge of panel {d.panel!r} (line {d.host!r})"
            )
            raise DesignError(
                d.path,
                f"dart {d.name!r} is off its panel {d.panel!r}: {where}; a dart runs from "
                "a seam or hem of its panel to an apex inside it, crossing no other line",
            )
        out[line.name] = {
            "panel": d.panel,
            "intake": d.intake,
            "apex_offset": float(d.apex_offset),
            "apex": np.asarray(d.apex.position(body_vertices, body_faces), float),
            "line": d.host,
        }
    return out
