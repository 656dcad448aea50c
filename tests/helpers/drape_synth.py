"""A body of revolution and a two-panel tube skirt sewn for it.

Small, exact test data for the drape and its metrics. The body's hips are a
cylinder (z in [0.6, 0.95] m, radius 0.165 m), so the skirt that covers them
unrolls without distortion: its pattern is the cylinder cut at both sides and
scaled by ``ease`` in the weft, its achieved weft scale is ``ease`` everywhere
(up to the chord of one column) and its seams match exactly.

The skirt's body record names :func:`revolution_obj`, an OBJ copy of the
default :func:`revolution_body`, so a saved skirt pattern resolves its body
through the ordinary body loader (the CLI and the workflows) with no test
hook in the shipped code.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
from meshes import ring_grid_faces

from core.pattern.types import Pattern, PatternPanel, PatternSeam

# (z, radius) in metres: legs column, cylindrical hips, waist at 1.05 m, chest.
# Equal neighbours make the monotone cubic exactly flat between them.
PROFILE = np.array(
    [[0.20, 0.10], [0.45, 0.13], [0.60, 0.165], [0.75, 0.165], [0.95, 0.165], [1.05, 0.14], [1.20, 0.16], [1.40, 0.12]]
)
HIP_RADIUS = 0.165


def radius(z) -> np.ndarray:
    """Body radius (m) at height z (m), smooth (cubic through PROFILE)."""
    from scipy.interpolate import PchipInterpolator

    return PchipInterpolator(PROFILE[:, 0], PROFILE[:, 1])(np.asarray(z, dtype=float))


def revolution_body(n_around: int = 48, n_rings: int = 60) -> tuple:
    """A closed body of revolution about the Z axis.

    Returns
    -------
    vertices : (V, 3) float, faces : (F, 3) int, outward oriented.
    """
    z = np.linspace(PROFILE[0, 0], PROFILE[-1, 0], n_rings)
    r = radius(z)
    th = 2 * np.pi * np.arange(n_around) / n_around
    ring = np.stack([np.cos(th), np.sin(th)], axis=1)
    verts = [np.column_stack([r[i] * ring, np.full(n_around, z[i])]) for i in range(n_rings)]
    verts.append([[0.0, 0.0, z[0] - 0.02]])
    verts.append([[0.0, 0.0, z[-1] + 0.02]])
    v = np.vstack(verts)
    bottom, top = len(v) - 2, len(v) - 1
    faces = ring_grid_faces(n_rings, n_around).tolist()
    for j in range(n_around):
        faces.append([bottom, (j + 1) % n_around, j])
        t0 = (n_rings - 1) * n_around
        faces.append([top, t0 + j, t0 + (j + 1) % n_around])
    return v, np.asarray(faces, dtype=np.int64)


def revolution_obj(n_around: int = 48, n_rings: int = 60) -> str:
    """Path of an OBJ file of :func:`revolution_body` (written once, in the temp folder).

    Coordinates are written with ``repr`` precision, so the body loaded back
    from it is bitwise the same array.
    """
    path = Path(tempfile.gettempdir()) / f"ease_test_revolution_{n_around}x{n_rings}.obj"
    if not path.is_file():
        v, f = revolution_body(n_around, n_rings)
        lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f.tolist()]
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text("\n".join(lines) + "\n")
        os.replace(tmp, path)  # concurrent test runs never read a half-written file
    return str(path)


def tube_skirt(
    ease: float = 1.2,
    n_rows: int = 12,
    n_cols: int = 12,
    top: float = 0.95,
    bottom: float = 0.62,
    fabric: str = "cotton",
) -> Pattern:
    """A front and a back panel sewn at both sides, pinned at the waist.

    Parameters
    ----------
    ease : uniform weft scale (1 = skintight).
    n_rows, n_cols : grid resolution of each panel (rows down, columns across).
    top, bottom : waistband and hem heights, metres, within the cylindrical hips.

    Returns
    -------
    Pattern with panels ``back`` (theta in [0, pi]) and ``front`` (theta in [pi, 2 pi]).
    """
    z = np.linspace(top, bottom, n_rows + 1)
    r = radius(z)
    s = top - z  # distance down the cylinder: the warp (grain) coordinate
    n_around = 2 * n_cols
    panels = []
    for name, k0 in (("back", 0), ("front", n_cols)):
        th = np.pi * (k0 + np.arange(n_cols + 1)) / n_cols
        ii, jj = np.meshgrid(np.arange(n_rows + 1), np.arange(n_cols + 1), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        xyz = np.column_stack([r[ii] * np.cos(th[jj]), r[ii] * np.sin(th[jj]), z[ii]])
        # unrolled: weft is grain turned +90 deg = -u, so u runs against theta
        mid = th[n_cols // 2] if n_cols % 2 == 0 else 0.5 * (th[0] + th[-1])
        uv = np.column_stack([-ease * r[ii] * (th[jj] - mid), -s[ii]])
        ids = ii * n_around + (k0 + jj) % n_around
        faces = []
        for i in range(n_rows):
            for j in range(n_cols):
                a = i * (n_cols + 1) + j
                b, c, d = a + 1, a + n_cols + 1, a + n_cols + 2
                faces += [[a, c, b], [b, c, d]] if (i + j) % 2 else [[a, c, d], [a, d, b]]
        faces = np.asarray(faces, dtype=np.int64)
        nf = len(faces)
        local = lambda i, j: i * (n_cols + 1) + j  # noqa: E731
        loop = (
            [local(0, j) for j in range(n_cols + 1)]
            + [local(i, n_cols) for i in range(1, n_rows + 1)]
            + [local(n_rows, j) for j in range(n_cols - 1, -1, -1)]
            + [local(i, 0) for i in range(n_rows - 1, 0, -1)]
        )
        panels.append(
            PatternPanel(
                name=name,
                garment="skirt",
                uv=uv,
                faces=faces,
                vertex_ids=ids.astype(np.int64),
                xyz=xyz,
                grain=np.array([0.0, 1.0]),
                target_weft=np.full(nf, ease),
                target_warp=np.ones(nf),
                achieved_weft=np.full(nf, ease),
                achieved_warp=np.ones(nf),
                boundary=[np.asarray(loop)],
                hems=[
                    np.array([local(0, j) for j in range(n_cols + 1)]),
                    np.array([local(n_rows, j) for j in range(n_cols + 1)]),
                ],
            )
        )
    rows = np.arange(n_rows + 1) * (n_cols + 1)
    seams = [
        PatternSeam("side_left", "back", "front", rows + n_cols, rows.copy()),
        PatternSeam("side_right", "front", "back", rows + n_cols, rows.copy()),
    ]
    pins = {"skirt": np.arange(n_around, dtype=np.int64)}
    return Pattern(
        style=f"tube_skirt_{ease:g}",
        body={"model": revolution_obj(), "shape": {}, "pose": None},
        garments={"skirt": "skirt"},
        panels=panels,
        seams=seams,
        pins=pins,
        materials={"fabric": fabric},
    )
