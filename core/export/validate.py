"""Checks a pattern (and a drape) before anything is exported.

Every failure is an :class:`core.errors.ExportError` that names the piece or
seam and the field at fault, raised before a single file is written.
"""

from __future__ import annotations

from typing import List, Optional

import numpy as np

from ..errors import ExportError
from ..geom.polygon import remove_loops, segments_cross, signed_area
from ..pattern.types import Pattern
from .boundary import edge_table, piece_loops

MIN_AREA = 1e-6  # m^2 (1 cm^2): smaller pieces are degenerate for a cutting room
# A sew line that crosses itself is an error however small its loops (issue 30: a 1 cm^2 or 0.5 %
# threshold let 8.2 cm^2 of real loops through on a men's XS blouse); ``strict=False`` exports it
# with a warning.
MAX_COORDINATE = 1000.0  # m: a draped vertex farther than this from the origin is a diverged drape (and 1e308
# would be infinite in the GLB's float32)


def _ids(a, n: int, where: str) -> np.ndarray:
    try:
        a = np.asarray(a)
    except Exception:  # pragma: no cover - numpy accepts almost anything
        raise ExportError(f"{where}: expected vertex ids") from None
    if a.size and a.dtype.kind not in "iu":
        if a.dtype.kind == "f" and np.all(np.isfinite(a)) and np.all(a == np.round(a)):
            a = a.astype(np.int64)
        else:
            raise ExportError(f"{where}: expected integer vertex ids, got {a.dtype}")
    a = a.reshape(-1).astype(np.int64)
    if a.size and (a.min() < 0 or a.max() >= n):
        raise ExportError(f"{where}: vertex ids must lie in [0, {n}), got [{a.min()}, {a.max()}]")
    return a


#: characters a piece name may have: it is printed on the piece's label and names its DXF block
MAX_NAME = 100


def validate_pattern(pattern: Pattern, strict: bool = True) -> List[str]:
    """Raise :class:`ExportError` unless ``pattern`` can be exported.

    A sew line that crosses itself raises, whatever area its loops enclose, or
    with ``strict=False`` is reported in the returned warnings. Everything
    else always raises.

    Checks: at least one piece; unique piece names of at most :data:`MAX_NAME` characters; per piece finite uv (n, 2)
    with n >= 3, faces (f, 3) indexing uv, non-negative vertex ids, a finite
    non-zero grain, boundary loops and hems indexing uv, an outline of area
    >= 1 cm^2 whose sew line does not cross itself, ``mirror_of`` naming a
    piece; per seam existing pieces, two equally long polylines of >= 2
    vertices that run along the pieces' boundaries.
    """
    if not isinstance(pattern, Pattern):
        raise ExportError(f"pattern: expected a core.pattern.types.Pattern, got {type(pattern).__name__}")
    if not pattern.panels:
        raise ExportError("pattern.panels: the pattern has no pieces")
    warnings: List[str] = []
    names = [p.name for p in pattern.panels]
    for k, name in enumerate(names):
        if not isinstance(name, str) or not name:
            raise ExportError(f"pattern.panels: piece names must be non-empty strings, got {name!r}")
        if len(name) > MAX_NAME:
            raise ExportError(
                f"pattern.panels[{k}].name: expected at most {MAX_NAME} characters (it names the piece "
                f"on its label and in every file), got {len(name)}: {name[:24]!r}..."
            )
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ExportError(f"pattern.panels: duplicate piece names {dup}")
    tables = {}
    for panel in pattern.panels:
        where = f"piece {panel.name!r}"
        uv = np.asarray(panel.uv)
        if uv.ndim != 2 or uv.shape[1] != 2 or uv.shape[0] < 3 or uv.dtype.kind not in "fiu":
            raise ExportError(f"{where}.uv: expected (n, 2) numbers with n >= 3, got shape {uv.shape}")
        if not np.all(np.isfinite(uv)):
            bad = int(np.argmax(~np.all(np.isfinite(uv), axis=1)))
            raise ExportError(f"{where}.uv: vertex {bad} is not finite ({uv[bad].tolist()})")
        n = uv.shape[0]
        faces = np.asarray(panel.faces)
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.shape[0] == 0:
            raise ExportError(f"{where}.faces: expected (f, 3) vertex ids with f >= 1, got shape {faces.shape}")
        _ids(faces, n, f"{where}.faces")
        vids = np.asarray(panel.vertex_ids)
        if vids.shape != (n,):
            raise ExportError(f"{where}.vertex_ids: expected {n} ids (one per uv vertex), got shape {vids.shape}")
        _ids(vids, np.iinfo(np.int64).max, f"{where}.vertex_ids")
        grain = np.asarray(panel.grain, float).reshape(-1)
        if grain.shape != (2,) or not np.all(np.isfinite(grain)) or np.linalg.norm(grain) < 1e-9:
            raise ExportError(f"{where}.grain: expected a finite non-zero 2D direction, got {grain.tolist()}")
        for k, b in enumerate(panel.boundary):
            ids = _ids(b, n, f"{where}.boundary[{k}]")
            if len(np.unique(ids)) < 3:
                raise ExportError(f"{where}.boundary[{k}]: a loop needs at least 3 distinct vertices")
        for k, h in enumerate(panel.hems):
            if len(_ids(h, n, f"{where}.hems[{k}]")) < 2:
                raise ExportError(f"{where}.hems[{k}]: a hem needs at least 2 vertices")
        if panel.mirror_of is not None and panel.mirror_of not in names:
            raise ExportError(f"{where}.mirror_of: no piece {panel.mirror_of!r} in the pattern")
        loops = piece_loops(panel)
        if not loops:
            raise ExportError(f"{where}.boundary: the piece has no boundary loop")
        outline = uv[loops[0]].astype(float)
        area = abs(signed_area(outline))
        if area < MIN_AREA:
            raise ExportError(f"{where}: degenerate piece, outline area {area * 1e4:.3g} cm^2 (expected >= 1 cm^2)")
        for k, loop in enumerate(loops):
            hit = segments_cross(uv[loop].astype(float))
            if hit is not None:
                q = uv[loop][hit[0]] * 1000
                _, loops_area = remove_loops(uv[loop].astype(float), 1.0 if k == 0 else -1.0, return_removed=True)
                msg = (
                    f"{where}.uv: the sew line crosses itself near ({q[0]:.0f}, {q[1]:.0f}) mm, "
                    f"enclosing {loops_area * 1e4:.2g} cm^2 in loops"
                )
                if strict:
                    raise ExportError(msg + " (a folded-over or tangled piece)")
                else:
                    warnings.append(msg + " (a folded-over or tangled piece, exported as it is)")
        tables[panel.name] = edge_table(loops)
    for k, seam in enumerate(pattern.seams):
        where = f"seam {seam.name!r}"
        for side in ("a", "b"):
            pname = getattr(seam, f"panel_{side}")
            if pname not in tables:
                raise ExportError(f"{where}.panel_{side}: no piece {pname!r}; pieces: {', '.join(names)}")
        va = np.asarray(seam.verts_a).reshape(-1)
        vb = np.asarray(seam.verts_b).reshape(-1)
        if va.size < 2 or va.size != vb.size:
            raise ExportError(
                f"{where}.verts_a/verts_b: expected two equally long polylines of >= 2 vertices, "
                f"got {va.size} and {vb.size}"
            )
        for side, v in (("a", va), ("b", vb)):
            pname = getattr(seam, f"panel_{side}")
            panel = pattern.panel(pname)
            ids = _ids(v, len(panel.uv), f"{where}.verts_{side}")
            for u, w in zip(ids[:-1], ids[1:]):
                if (int(u), int(w)) not in tables[pname]:
                    raise ExportError(
                        f"{where}.verts_{side}: vertices {u} -> {w} of piece {pname!r} are not "
                        f"consecutive boundary vertices (a seam must run along the piece outline)"
                    )
    return warnings


def validate_drape(pattern: Pattern, positions: Optional[np.ndarray], faces: Optional[np.ndarray] = None) -> np.ndarray:
    """The drape positions as a float (N, 3) array covering every garment vertex id, or ExportError.

    ``faces`` (optional, (F, 3) garment vertex ids, ``drape.npz["faces"]``): the
    drape's triangles, which must be the pattern's, so that a drape of another
    pattern (another design, size or pose) is refused instead of exported."""
    if positions is None:
        raise ExportError("drape: GLB/OBJ export needs the draped garment (drape_positions / --drape DIR)")
    p = np.asarray(positions)
    if p.ndim != 2 or p.shape[1] != 3 or p.dtype.kind not in "fiu":
        raise ExportError(f"drape.positions: expected (N, 3) numbers, got shape {p.shape}")
    need = max(int(np.max(panel.vertex_ids)) for panel in pattern.panels) + 1
    if p.shape[0] < need:
        raise ExportError(
            f"drape.positions: {p.shape[0]} vertices, but the pattern uses garment vertex ids "
            f"up to {need - 1} (was it draped from this pattern?)"
        )
    if faces is not None and np.size(faces):
        f = np.asarray(faces)
        if f.ndim != 2 or f.shape[1] != 3 or f.dtype.kind not in "iu":
            raise ExportError(f"drape.faces: expected (F, 3) vertex ids, got shape {f.shape}")
        mine = np.sort(
            np.concatenate(
                [np.asarray(panel.vertex_ids, int)[np.asarray(panel.faces, int)] for panel in pattern.panels]
            ),
            axis=1,
        )
        theirs = np.sort(f.astype(np.int64), axis=1)
        if len(mine) != len(theirs) or not np.array_equal(np.unique(mine, axis=0), np.unique(theirs, axis=0)):
            raise ExportError(
                f"drape: its {len(theirs)} triangles are not this pattern's {len(mine)} "
                f"(was it draped from another pattern? drape this one again)"
            )
    used = np.concatenate([np.asarray(panel.vertex_ids, int) for panel in pattern.panels])
    q = p[used].astype(float)
    if not np.all(np.isfinite(q)):
        bad = int(used[np.argmax(~np.all(np.isfinite(q), axis=1))])
        raise ExportError(
            f"drape.positions: vertex {bad} holds NaN or infinite values "
            f"({p[bad].tolist()}); the drape diverged? "
            f"drape the pattern again"
        )
    far = np.abs(q).max(axis=1)
    if far.max() > MAX_COORDINATE:
        bad = int(used[np.argmax(far)])
        raise ExportError(
            f"drape.positions: vertex {bad} lies {far.max():.3g} m from the origin (expected within "
            f"{MAX_COORDINATE:g} m: a body is about 2 m tall; the drape diverged?)"
        )
    return p.astype(float)


def validate_body(body) -> tuple:
    """The body to export beside the garment: (vertices (V, 3) float m, faces (F, 3) int64), or ExportError."""
    try:
        v, f = body
        v = np.asarray(v, float)
        f = np.asarray(f)
    except (TypeError, ValueError):
        raise ExportError("body: expected (vertices (V, 3), faces (F, 3))") from None
    if v.ndim != 2 or v.shape[1] != 3 or not len(v) or not np.all(np.isfinite(v)) or np.abs(v).max() > MAX_COORDINATE:
        raise ExportError(
            f"body.vertices: expected (V, 3) finite metres within {MAX_COORDINATE:g} m, got shape {v.shape}"
        )
    if f.ndim != 2 or f.shape[1] != 3 or f.dtype.kind not in "iu" or (f.size and (f.min() < 0 or f.max() >= len(v))):
        raise ExportError(f"body.faces: expected (F, 3) vertex ids in [0, {len(v)}), got shape {f.shape}")
    return v, f.astype(np.int64)
