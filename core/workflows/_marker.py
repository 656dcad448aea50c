"""The marker stage: pieces of one or several patterns nested on the fabric's width, and its files."""

from __future__ import annotations

from typing import Optional, Sequence, Tuple

from ..progress import Progress
from ._export import export_allowance


def marker(
    runs: Sequence[Tuple[str, object, int]],
    width: float,
    allowance=None,
    hem: Optional[float] = None,
    notch_spacing: Optional[float] = None,
    seconds: int = 60,
    seed: int = 0,
    one_way: bool = False,
    tilt: float = 0.0,
    threads: Optional[int] = None,
    tries: Optional[int] = None,
    progress: Optional[Progress] = None,
    early_stop: bool = False,
    spread: str = "single",
):
    """A cutting-room marker: the pieces of ``runs`` nested on a fabric ``width`` m wide (:mod:`core.marker`).

    Parameters
    ----------
    runs : (size label, core.pattern.Pattern, garments) per size
    allowance, hem : as :func:`export`: the export's rule, one for every output (each pattern's table,
        :func:`export_allowance`, with ``allowance`` on every seam and ``hem`` over it; a table as such),
        so the marker nests the cut lines ``ease export`` draws
    notch_spacing, seconds, seed, one_way, tilt, threads, tries, early_stop : see :func:`core.marker.nest`;
        the numbers are checked before any work (:func:`core.marker.check_options`); ``threads`` and ``tries``
        None: one nester with a worker thread a core (:func:`core.marker.default_split`); ``tries`` alone None:
        as many nesters (seeds ``seed``, ``seed + 1``, ...) as the machine's cores hold ``threads`` each, in the
        same wall time
    spread : ``"single"`` (one ply) or ``"pairs"`` (two plies face to face, :func:`core.marker.marker_items`)

    Returns
    -------
    core.marker.Marker
    """
    from ..marker import check_options, default_split, marker_items, nest

    threads, tries = default_split(threads, tries)
    check_options(width, seconds, seed, threads, tries)
    items = []
    for size, pattern, garments in runs:
        table = allowance if isinstance(allowance, dict) else export_allowance(pattern, allowance, hem)
        items += marker_items([(size, pattern, garments)], allowance=table, notch_spacing=notch_spacing, spread=spread)
    return nest(
        items,
        width,
        seconds=seconds,
        seed=seed,
        one_way=one_way,
        tilt=tilt,
        threads=threads,
        tries=tries,
        progress=progress,
        early_stop=early_stop,
    )


def write_marker(
    out, marker, title: str = "marker", extra: Optional[dict] = None, progress: Optional[Progress] = None
) -> list:
    """The marker's files (DXF, SVG, PDF, PNG, ``marker.json`` with ``extra`` merged) into ``out``, atomically;
    returns the written paths."""
    from ..marker import write_marker as _write

    return _write(marker, out, title, progress=progress, extra=extra)
