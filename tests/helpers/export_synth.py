"""Synthetic patterns for the export tests (built directly, no other stage needed)."""

from __future__ import annotations

import math

import numpy as np

from core.pattern.types import Pattern, PatternPanel, PatternSeam


def grid_piece(nx: int, ny: int, shape):
    """A triangulated piece from a map of the unit square.

    Returns uv (n, 2), faces (f, 3) ccw, the ccw boundary loop and a dict of
    its sides (bottom, right, top, left) as polylines in loop direction
    (left side and top run in loop order too).
    """
    ii, jj = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    s, t = ii.ravel() / (nx - 1), jj.ravel() / (ny - 1)
    uv = np.stack(shape(s, t), axis=1)
    vid = lambda i, j: j * nx + i  # noqa: E731
    faces = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            faces += [[a, b, c], [a, c, d]]
    bottom = [vid(i, 0) for i in range(nx)]
    right = [vid(nx - 1, j) for j in range(ny)]
    top = [vid(i, ny - 1) for i in range(nx - 1, -1, -1)]
    left = [vid(0, j) for j in range(ny - 1, -1, -1)]
    loop = bottom[:-1] + right[:-1] + top[:-1] + left[:-1]
    sides = {"bottom": np.array(bottom), "right": np.array(right), "top": np.array(top), "left": np.array(left)}
    return uv, np.array(faces), np.array(loop), sides


def _panel(name, uv, faces, loop, grain, hems=(), mirror_of=None, id0=0):
    n, f = len(uv), len(faces)
    return PatternPanel(
        name=name,
        garment="shirt",
        uv=uv,
        faces=faces,
        vertex_ids=np.arange(n) + id0,
        xyz=np.column_stack([uv, np.zeros(n)]),
        grain=np.asarray(grain, float),
        target_weft=np.ones(f),
        target_warp=np.ones(f),
        achieved_weft=np.ones(f),
        achieved_warp=np.ones(f),
        boundary=[loop],
        hems=[np.asarray(h) for h in hems],
        mirror_of=mirror_of,
    )


def trapezoid(s, t, bottom=0.50, top=0.40, height=0.60):
    half = 0.5 * (bottom + (top - bottom) * t)
    return (s - 0.5) * 2 * half, t * height


def curved_top(s, t):
    x, y = trapezoid(s, t)
    # a concave neckline dip on the top edge, 6 cm deep
    return x, y - 0.06 * t**3 * np.sin(np.pi * s) ** 2


def make_pattern(rotate_back_deg: float = 30.0, nx: int = 9, ny: int = 13) -> Pattern:
    """Front (trapezoid) and back (curved neckline, rotated uv) sewn on two side seams, hems at the bottom."""
    uv_f, faces, loop, sides_f = grid_piece(nx, ny, trapezoid)
    uv_b, faces_b, loop_b, sides_b = grid_piece(nx, ny, curved_top)
    a = math.radians(rotate_back_deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    uv_b = uv_b @ rot.T + np.array([1.0, 0.2])
    grain_b = rot @ np.array([0.0, 1.0])
    front = _panel("front", uv_f, faces, loop, [0.0, 1.0], hems=[sides_f["bottom"]])
    back = _panel("back", uv_b, faces_b, loop_b, grain_b, hems=[sides_b["bottom"]], mirror_of=None, id0=len(uv_f))
    # side seams: both run bottom -> top
    seams = [
        PatternSeam("side_left", "front", "back", sides_f["left"][::-1], sides_b["right"]),
        PatternSeam("side_right", "front", "back", sides_f["right"], sides_b["left"][::-1]),
    ]
    return Pattern(
        style="test shirt",
        body={"model": "anny", "shape": "M", "pose": "A", "size": "M"},
        garments={"shirt": "shirt"},
        panels=[front, back],
        seams=seams,
    )


def drape_positions(pattern: Pattern) -> np.ndarray:
    """(N, 3) positions by global vertex id: the pieces wrapped around a cylinder."""
    n = max(int(p.vertex_ids.max()) for p in pattern.panels) + 1
    pos = np.zeros((n, 3))
    for k, p in enumerate(pattern.panels):
        ang = p.uv[:, 0] / 0.2 + k * math.pi
        pos[p.vertex_ids] = np.column_stack([0.2 * np.sin(ang), -0.2 * np.cos(ang), 0.8 + p.uv[:, 1]])
    return pos


def wide_pattern(width: float = 1.6, height: float = 0.5) -> Pattern:
    """One rectangle ``width`` x ``height`` m (grain along its height), hem at the bottom: wider than a page grid.

    The ease-3.0 shirt front is 1.58 m wide; a tiled PDF must still print it.
    """
    uv, faces, loop, sides = grid_piece(17, 6, lambda s, t: ((s - 0.5) * width, t * height))
    return Pattern(
        style="wide",
        body={"model": "anny", "shape": "M", "pose": "A", "size": "M"},
        garments={"shirt": "shirt"},
        panels=[_panel("front", uv, faces, loop, [0.0, 1.0], hems=[sides["bottom"]])],
        seams=[],
    )


def mirrored_pattern(bulge: float = 0.0) -> Pattern:
    """A left piece and its declared mirror (``front_right``, ``mirror_of="front_left"``) sewn on a centre seam.

    The left piece is lopsided (slanted, its outer side curved), so its mirror
    image is a different shape. ``bulge`` (m) pushes the right piece's outer
    side out by up to that much: 0 gives an exact mirror, a few mm a pair whose
    sides differ (as ease painted on one side only would make it).
    """

    def lopsided(s, t):
        x = (s - 0.5) * (0.36 - 0.08 * t) + 0.06 * t - 0.03 * (1 - s) * np.sin(np.pi * t)
        return x, 0.5 * t

    uv, faces, loop, sides = grid_piece(7, 9, lopsided)
    left = _panel("front_left", uv, faces, loop, [0.0, 1.0], hems=[sides["bottom"]])
    ruv = uv * np.array([-1.0, 1.0]) + np.array([1.0, 0.0])
    outer = np.isin(np.arange(len(uv)), sides["left"])  # becomes the right piece's outer side
    ruv[outer, 0] += bulge * np.sin(np.pi * uv[outer, 1] / 0.5)
    right = _panel(
        "front_right",
        ruv,
        faces[:, ::-1],
        loop[::-1],
        [0.0, 1.0],
        hems=[sides["bottom"][::-1]],
        mirror_of="front_left",
        id0=len(uv),
    )
    seams = [PatternSeam("centre", "front_left", "front_right", sides["right"], sides["right"])]
    return Pattern(
        style="mirror test",
        body={"model": "anny", "shape": "M", "pose": "A", "size": "M"},
        garments={"shirt": "shirt"},
        panels=[left, right],
        seams=seams,
    )


#: Every file ``--format all`` writes (the draped garment included): what a user finds in the folder.
ALL_EXPORT_FILES = frozenset(
    {
        "pattern.svg",
        "pattern_astm.dxf",
        "pattern_astm_r12.dxf",
        "pattern_plain.dxf",
        "pattern_a4.pdf",
        "pattern_letter.pdf",
        "pattern_plotter.pdf",
        "garment.glb",
        "garment.obj",
        "garment.mtl",
        "export.json",
    }
)
