"""Synthetic patterns for the marker tests: curved, concave pieces whose cut lines have many vertices."""

from __future__ import annotations

import numpy as np
from export_synth import _panel, grid_piece

from core.geom.polygon import points_in_polygon
from core.marker.outline import edges_meet
from core.pattern.types import Pattern


def wavy_shape(k: int):
    """A map of the unit square: a trouser-leg-like piece, wavy sides, a concave top, sized by ``k``."""
    width, height, waves = 0.22 + 0.03 * k, 0.45 + 0.05 * k, 3 + k

    def shape(s, t):
        half = 0.5 * width * (1.0 + 0.3 * t)
        x = (s - 0.5) * 2 * half + 0.004 * np.sin(2 * np.pi * waves * t) * (2 * s - 1)
        y = t * height - 0.05 * t**2 * np.sin(np.pi * s) ** 2 + 0.02 * s * t
        return x, y

    return shape


def wavy_pattern(pieces: int = 3) -> Pattern:
    """``pieces`` unsewn panels of :func:`wavy_shape`, hems at the bottom (about 130 boundary vertices each)."""
    panels, n0 = [], 0
    for k in range(pieces):
        uv, faces, loop, sides = grid_piece(25, 40, wavy_shape(k))
        panels.append(_panel(f"leg{k}", uv, faces, loop, [0.0, 1.0], hems=[sides["bottom"]], id0=n0))
        n0 += len(uv)
    return Pattern(
        style="wavy",
        body={"model": "anny", "shape": "M", "pose": "A", "size": "M"},
        garments={"shirt": "shirt"},
        panels=panels,
        seams=[],
    )


def overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two closed loops overlap: an edge crossing, or a vertex of one strictly inside the other."""
    return (
        edges_meet(a, b, touching=False) or bool(points_in_polygon(a, b).any()) or bool(points_in_polygon(b, a).any())
    )
