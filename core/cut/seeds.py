"""Panel seeds on the cut mesh, and what to tell the user when one is misplaced.

A panel is the region of the cut surface around its seed (flood fill in
:mod:`.engine`). A seed that lies on, or within a millimetre or so of, one of
its panel's seamlines may fall on the neighbour's side of the traced line (the
line snaps up to :data:`core.cut.split.SNAP_ABS` off the exact geodesic, and a
``between`` keypoint is placed on the design's own geodesic). The flood fill
then finds two seeds in one region; :func:`seed_hint` names the seed and the
line it is too close to, so the error says what to move.
"""

from __future__ import annotations

from typing import Dict, Optional, Sequence, Tuple

import numpy as np

from ..errors import CutError
from .geodesic import surface_point_position
from .split import CutMesh

# A seed closer than this to a cut line is named as the likely cause of a flood fill
# that merges two panels (or leaks out of the garment): metres (a few times the line's
# snap distance, SNAP_ABS = 0.5 mm).
SEED_CLEARANCE = 0.003


def seed_face(mesh: CutMesh, p, BF, X, seed_names: Optional[Dict[str, str]] = None) -> int:
    """The cut-mesh face (F index) that holds panel ``p``'s seed."""
    pos = surface_point_position(p.seed, BF, X)
    try:
        f, _ = mesh.locate_in_parent(int(p.seed.triangle), pos)
    except KeyError:
        raise CutError(
            f"panel {p.name!r}: its seed{seed_label(p.name, seed_names)} lies on a removed part "
            f"of the body (between the legs, removed for the skirt topology)"
        ) from None
    return f


def seed_label(panel: str, seed_names: Optional[Dict[str, str]]) -> str:
    """`` (keypoint 'chest_front')``: the seed as the design names it, or ``""``."""
    name = (seed_names or {}).get(panel)
    return f" ({name})" if name else ""


def nearest_line(mesh: CutMesh, pos: np.ndarray, lines: Sequence[int]) -> Tuple[float, int]:
    """(distance m, line index) of the cut line among ``lines`` nearest to ``pos`` (3,).

    ``(inf, -1)`` when none of them is in the mesh."""
    keys = [(k, li) for k, li in mesh.cut.items() if li in set(lines)]
    if not keys:
        return float("inf"), -1
    E = np.array([k for k, _ in keys], dtype=np.int64)
    A, B = mesh.X[E[:, 0]], mesh.X[E[:, 1]]
    AB = B - A
    t = np.clip(((pos - A) * AB).sum(1) / np.maximum((AB * AB).sum(1), 1e-300), 0.0, 1.0)
    d = np.linalg.norm(A + t[:, None] * AB - pos, axis=1)
    i = int(np.argmin(d))
    return float(d[i]), int(keys[i][1])


def seed_hint(
    mesh: CutMesh,
    panels,
    lines: Sequence[int],
    names: Sequence[str],
    BF,
    X,
    seed_names: Optional[Dict[str, str]] = None,
) -> str:
    """Text naming the seeds of ``panels`` that lie within :data:`SEED_CLEARANCE` of
    one of the cut lines ``lines`` (indices into ``names``), nearest first, ending in
    ``"; otherwise "``; ``""`` if none."""
    near = []
    for p in panels:
        d, li = nearest_line(mesh, surface_point_position(p.seed, BF, X), lines)
        if d < SEED_CLEARANCE:
            near.append((d, p.name, li))
    if not near:
        return ""
    return (
        "; ".join(
            f"the seed of panel {name!r}{seed_label(name, seed_names)} lies {1000 * d:.1f} mm "
            f"from cut line {names[li]!r}, maybe on its other side: move it into its panel"
            for d, name, li in sorted(near)
        )
        + "; otherwise "
    )
