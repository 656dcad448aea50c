"""The export stage: a pattern's cutting-room files (SVG, DXF, PDF, GLB, OBJ) with one allowance rule."""

from __future__ import annotations

from typing import List, Optional, Sequence, Tuple, Union

import numpy as np

from ..progress import Progress


def export_allowance(pattern, allowance: Optional[float] = None, hem: Optional[float] = None):
    """The seam/hem allowance table for an export: the design's (``materials.export.allowance``)
    with the caller's ``allowance`` (every seam) and ``hem`` over it; None when the caller sets
    neither (the exporter then reads the design's itself)."""
    if allowance is None and hem is None:
        return None
    from ..design.materials import ALLOWANCE, HEM

    base = ((pattern.materials or {}).get("export") or {}).get("allowance")
    if isinstance(base, dict):
        table = dict(base)
    elif isinstance(base, (int, float)) and not isinstance(base, bool):
        table = {"default": float(base)}
    else:
        table = {"default": ALLOWANCE, "hem": HEM}
    if allowance is not None:
        table["default"] = allowance
    if hem is not None:
        table["hem"] = hem
    return table


def export(
    pattern,
    out,
    formats: Union[str, Sequence[str]] = ("svg", "dxf", "pdf"),
    allowance=None,
    hem: Optional[float] = None,
    notch_spacing: Optional[float] = None,
    drape: Optional[Tuple[np.ndarray, Optional[np.ndarray]]] = None,
    strict: bool = True,
    warnings: Optional[List[str]] = None,
    up: str = "y",
    with_body: bool = False,
    progress: Optional[Progress] = None,
    print_all: bool = False,
    origin: str = "floor",
) -> list:
    """Cutting-room files (SVG, DXF, PDF) and the draped garment (GLB, OBJ) into ``out``, atomically.

    Parameters
    ----------
    pattern : core.pattern.Pattern
    formats : comma-separated string or names (see :func:`core.export.parse_formats`)
    allowance : float (m, every seam) or a table ``{"default": m, "hem": m, seam name: m}``, or None
    hem : float, m: the hem allowance over the table
    notch_spacing : float, m between notches along a seam (None: the design's, else the default)
    drape : (positions (N, 3) by global vertex id, faces or None) for GLB/OBJ
    strict : refuse pieces whose sew line crosses itself (False: export with a warning)
    warnings : list to receive the warnings
    up : ``"y"`` (default, OBJ readers' convention) or ``"z"`` (the body OBJs' frame): the up axis of
        ``garment.obj`` (``garment.glb`` is Y-up, as glTF requires)
    origin : ``"floor"`` (default: the body's lowest point at height 0) or ``"root"`` (the body's root):
        the origin of ``garment.glb`` and ``garment.obj``
    with_body : also write the pattern's body instance beside the draped garment, in the same frame
    print_all : print every piece whole on the tiled PDFs (default: each mirrored pair once, labelled cut 2;
        symmetric pieces as halves on the fold)

    Returns
    -------
    list of the written paths.
    """
    from ..export import export_pattern, parse_formats

    table = allowance if isinstance(allowance, dict) else export_allowance(pattern, allowance, hem)
    positions, faces = drape if drape is not None else (None, None)
    formats = parse_formats(formats)
    body = None
    if with_body and ("glb" in formats or "obj" in formats):
        from ..errors import ExportError
        from ._drape import pattern_body

        body = pattern_body(pattern, "--with-body", ExportError)  # the body the pattern was made on
    return export_pattern(
        pattern,
        out,
        formats=formats,
        allowance=table,
        drape_positions=positions,
        drape_faces=faces,
        notch_spacing=notch_spacing,
        strict=strict,
        warnings=warnings if warnings is not None else [],
        up=up,
        body=body,
        progress=progress,
        print_all=print_all,
        origin=origin,
    )
