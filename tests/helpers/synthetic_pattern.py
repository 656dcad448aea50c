"""Synthetic cuts with known answers, for tests and benchmarks of the pattern stage (test helper).

Each builder returns ``(cut, body_vertices)``: a :class:`GarmentCut` whose
embedding is the identity onto a small "body" mesh made for the purpose.
Frame as everywhere: metres, +Z up.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from core.cut.types import GarmentCut, Panel, Seam


def _grid_faces(nu: int, nv: int, closed_u: bool = False) -> np.ndarray:
    """Triangles of an nu x nv vertex grid (index = j * nu + i), counter-clockwise in (u, v)."""
    F = []
    iu = nu if closed_u else nu - 1
    for j in range(nv - 1):
        for i in range(iu):
            a = j * nu + i
            b = j * nu + (i + 1) % nu
            c = (j + 1) * nu + (i + 1) % nu
            d = (j + 1) * nu + i
            F.append((a, b, c))
            F.append((a, c, d))
    return np.array(F, dtype=np.int64)


def tube(
    radius: float = 0.15, height: float = 0.5, n_around: int = 48, n_up: int = 21, ease: float = 1.2, bulge: float = 0.0
):
    """A vertical tube cut open by one seam (sewn to itself), warp along +Z.

    The panel is the tube unrolled: its vertex column ``n_around`` duplicates
    column 0 (same global id), and the seam joins the two. ``bulge`` > 0
    makes the radius vary with height (a doubly curved, non-developable tube).
    Faces are oriented outward.
    """
    th = 2 * np.pi * np.arange(n_around) / n_around
    z = np.linspace(0.0, height, n_up)
    r = radius * (1.0 + bulge * np.sin(np.pi * z / height))
    body = np.array([(rr * np.cos(t), rr * np.sin(t), zz) for zz, rr in zip(z, r) for t in th])
    nu = n_around + 1  # panel columns incl. the duplicated seam column
    vids = np.array([j * n_around + (i % n_around) for j in range(n_up) for i in range(nu)])
    F = _grid_faces(nu, n_up)
    # (theta, z) counter-clockwise seen from outside: theta grows to the right when looking at the tube
    warp = np.tile([0.0, 0.0, 1.0], (len(F), 1))
    X = body[vids]
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    warp = warp - np.sum(warp * n, axis=1, keepdims=True) * n / np.sum(n * n, axis=1, keepdims=True)
    warp /= np.linalg.norm(warp, axis=1, keepdims=True)
    left = np.array([j * nu for j in range(n_up)])
    right = np.array([j * nu + n_around for j in range(n_up)])
    panel = Panel(
        name="tube",
        garment="tube",
        vertex_ids=vids,
        faces=F,
        warp_dir=warp,
        ease=np.full(len(F), float(ease)),
        body_part="arm",
    )
    emb = sp.identity(len(body), format="csr")
    cut = GarmentCut(
        body={"model": "synthetic", "shape": {}, "pose": None},
        embedding=emb,
        panels=[panel],
        seams=[Seam("tube.seam", "tube", "tube", right, left)],
        garments={"tube": "upper"},
        hems={"tube": [np.arange(nu), np.arange(nu) + (n_up - 1) * nu]},
        materials={"eps_weft": 1.1, "eps_warp": 1.1},
    )
    return cut, body


def two_panels(
    radius: float = 0.15, height: float = 0.5, n_half: int = 24, n_up: int = 21, ease=(1.2, 1.2), bulge: float = 0.3
):
    """A bulging tube cut into a front and a back half, sewn on two side seams.

    ``ease`` gives each half its uniform weft scale.
    """
    n_around = 2 * n_half
    th = 2 * np.pi * np.arange(n_around) / n_around
    z = np.linspace(0.0, height, n_up)
    r = radius * (1.0 + bulge * np.sin(np.pi * z / height))
    body = np.array([(rr * np.cos(t), rr * np.sin(t), zz) for zz, rr in zip(z, r) for t in th])
    nu = n_half + 1
    panels = []
    for k, name in enumerate(("front", "back")):
        cols = [(k * n_half + i) % n_around for i in range(nu)]
        vids = np.array([j * n_around + c for j in range(n_up) for c in cols])
        F = _grid_faces(nu, n_up)
        X = body[vids]
        n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
        w = np.tile([0.0, 0.0, 1.0], (len(F), 1))
        w = w - np.sum(w * n, axis=1, keepdims=True) * n / np.sum(n * n, axis=1, keepdims=True)
        w /= np.linalg.norm(w, axis=1, keepdims=True)
        panels.append(
            Panel(
                name=name,
                garment="top",
                vertex_ids=vids,
                faces=F,
                warp_dir=w,
                ease=np.full(len(F), float(ease[k])),
                body_part="torso",
            )
        )
    col = lambda i: np.array([j * nu + i for j in range(n_up)])
    seams = [Seam("side_a", "front", "back", col(n_half), col(0)), Seam("side_b", "back", "front", col(n_half), col(0))]
    cut = GarmentCut(
        body={"model": "synthetic", "shape": {}, "pose": None},
        embedding=sp.identity(len(body), format="csr"),
        panels=panels,
        seams=seams,
        garments={"top": "upper"},
        materials={"eps_weft": 1.1, "eps_warp": 1.1},
    )
    return cut, body
