"""``ease export DESIGN --sizes XS,S,M,L,XL``: the graded nest of a design (all sizes in one file).

The transfers to each size run through :mod:`core.workflows` (one cut, one
solver, the reference pattern as the start of every transfer; the design's
own size is the reference pattern itself, as ``ease pattern`` writes it); the
files are written by :func:`core.export.graded.export_graded`, with the
design's own size as the sample size the grade points come from.
"""

from __future__ import annotations

from typing import List


def parse_sizes(text: str, check=None) -> List[str]:
    """``"XS,S,M"`` (or ``"women:S,women:M"``) as size names, each once (``--sizes``).

    ``check`` maps a name to its canonical chart size (raising for an unknown one); the
    default checks against the default chart.
    """
    from ..body.sizes import check_size
    from ..errors import EaseError, ExportError

    check = check or check_size
    names = [s.strip() for s in str(text).split(",") if s.strip()]
    try:
        sizes = [check(s) for s in names]
    except EaseError as exc:
        raise ExportError(f"--sizes: {getattr(exc, 'message', exc)}") from None
    if not sizes or len(set(sizes)) != len(sizes):
        raise ExportError(f"--sizes: expected chart sizes (e.g. XS,S,M,L,XL), each once, got {text!r}")
    return sizes


def run_graded(args) -> int:
    """The ``--sizes`` form of ``ease export``: ``args.pattern_dir`` is the design file."""
    from pathlib import Path

    from .. import workflows as wf
    from ..body.sizes import size_of
    from ..design import load_design
    from ..errors import ExportError
    from ..export.graded import export_graded
    from ..progress import sub
    from .common import console_progress, print_files

    design = Path(args.pattern_dir)
    if not design.is_file():
        raise ExportError(
            f"{design}: --sizes grades a design: expected the design JSON file (the shipped ones: `ease templates`)"
        )
    progress = console_progress(args)
    # Bare size names are of the design's own chart (body.chart), as in ``ease transfer``;
    # checked before the (slow) preparation.
    chart = load_design(design).body.get("chart")
    sizes = parse_sizes(args.sizes, lambda s: size_of(s, chart))
    prep = wf.prepare(design, progress=sub(progress, 0.0, 0.2))
    solver = wf.make_solver(prep)
    ref = wf.reference(prep, solver=solver, progress=sub(progress, 0.2, 0.3)).pattern
    patterns = {}
    for k, size in enumerate(sizes):
        span = sub(progress, 0.3 + 0.6 * k / len(sizes), 0.3 + 0.6 * (k + 1) / len(sizes))
        patterns[size] = wf.transfer(prep, size, solver=solver, start=ref, progress=span).pattern
    allowance = wf.export_allowance(ref, args.allowance, args.hem)
    own = next((s for s in sizes if wf.is_own_size(prep, s)), None)
    files = export_graded(
        patterns,
        args.out,
        allowance=allowance,
        notch_spacing=args.notch_spacing,
        progress=sub(progress, 0.9, 1.0),
        sample=own,
    )
    print_files(files)
    return 0
