"""Small mesh builders shared by the synthetic test bodies and patterns (no tests here)."""

import numpy as np


def ring_grid_faces(n_rings: int, n_around: int) -> np.ndarray:
    """Triangles (2 (n_rings - 1) n_around, 3) joining ``n_rings`` rings of ``n_around`` vertices.

    Vertex ``r * n_around + k`` is point ``k`` of ring ``r``; each quad between
    rings ``r`` and ``r + 1`` becomes two triangles, ring ``r`` wrapping around.
    """
    faces = []
    for r in range(n_rings - 1):
        for k in range(n_around):
            a, b = r * n_around + k, r * n_around + (k + 1) % n_around
            c, d = a + n_around, b + n_around
            faces += [[a, b, d], [a, d, c]]
    return np.asarray(faces, dtype=np.int64)
