"""``ease export DESIGN --sizes XS,S,M,L,XL``: the graded nest of a design (all sizes in one file).

The transfers to each size run through :mod:`core.workflows` (one cut, one
solver, the reference pattern as the start of every transfer); the files are
written by :func:`core.export.graded.export_graded`.
"""
from __future__ import annotations

from typing import List


def parse_sizes(text: str) -> List[str]:
    """``"XS,S,M"`` as chart size names, each once (``--sizes``)."""
    from ..body.sizes import SIZES
    from ..errors import ExportError
    sizes = [s.strip() for s in str(text).split(",") if s.strip()]
    bad = [s for s in sizes if s not in SIZES]
    if not sizes or bad or len(set(sizes)) != len(sizes):
        raise ExportError(f"--sizes: expected chart sizes from {','.join(SIZES)}, each once, got {text!r}")
    return sizes


def run_graded(args) -> int:
    """The ``--sizes`` form of ``ease export``: ``args.pattern_dir`` is the design file."""
    from pathlib import Path

    from .. import workflows as wf
    from ..errors import ExportError
    from ..export.graded import export_graded
    from ..progress import sub
    from .common import console_progress, print_files

    sizes = parse_sizes(args.sizes)
    design = Path(args.pattern_dir)
    if not design.is_file():
        raise ExportError(f"{design}: --sizes grades a design: expected the design JSON file "
                          f"(the shipped ones: `ease templates`)")
    progress = console_progress(args)
    prep = wf.prepare(design, progress=sub(progress, 0.0, 0.2))
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver, progress=sub(progress, 0.2, 0.3)).pattern
    patterns = {}
    for k, size in enumerate(sizes):
        span = sub(progress, 0.3 + 0.6 * k / len(sizes), 0.3 + 0.6 * (k + 1) / len(sizes))
        patterns[size] = wf.transfer(prep, size, solver=solver, start=ref, progress=span).pattern
    allowance = wf.export_allowance(ref, args.allowance, args.hem)
    files = export_graded(patterns, args.out, allowance=allowance, notch_spacing=args.notch_spacing,
                          progress=sub(progress, 0.9, 1.0))
    print_files(files)
    return 0
