"""The pipeline, once: prepare → reference → transfer / adapt → drape → export → marker.

The CLI (:mod:`core.cli`), the add-on (``ease_addon``), the benchmarks, batch
runs and the demo call these functions and nothing below them to run a
stage, so a design gives the same pattern, figures and files whichever door
it comes through. Each function returns its result together with the figures
a user reads (the report records and a flat ``figures`` dict); writing files
is separate (:func:`write_pattern`, :func:`write_drape`, :func:`export`).

Settings follow one precedence rule: the caller's value, else the design's
(its ``materials``), else the default (:class:`core.design.materials.Materials`).
The solver configuration too (:func:`config_name`): the caller's ``config``
(``--config`` given, the add-on's Solver set to a configuration), else the
design's ``"solver"``, else ``"improved"``; ``iterations`` and ``gather_all``
override that configuration's settings.

Progress: every function takes ``progress(fraction, message)`` for its own
span 0..1 (compose spans with :func:`core.progress.sub`); the callback may
raise :class:`core.errors.Cancelled` to stop.

One module a stage (``_prepare``, ``_pattern``, ``_drape``, ``_export``, ``_marker``; ``_outfit``:
layered garments draped inner first); this
package is their public interface.
"""

from ._drape import DrapeRun, drape, drape_summary, write_drape
from ._export import export, export_allowance
from ._marker import marker, write_marker
from ._outfit import LayerRun, OutfitRun, drape_outfit, outfit_summary, write_outfit
from ._pattern import (
    CONFIGS,
    DEFAULT_CONFIG,
    PatternRun,
    adapt,
    config_name,
    is_own_size,
    make_solver,
    measure_pattern,
    pattern_figures,
    reference,
    solver_config,
    summary,
    tolerances,
    transfer,
    with_transfer_solver,
    write_pattern,
)
from ._prepare import Prepared, prepare, size_name

__all__ = [
    "CONFIGS",
    "DEFAULT_CONFIG",
    "Prepared",
    "PatternRun",
    "DrapeRun",
    "prepare",
    "size_name",
    "config_name",
    "solver_config",
    "make_solver",
    "reference",
    "transfer",
    "with_transfer_solver",
    "is_own_size",
    "adapt",
    "tolerances",
    "measure_pattern",
    "pattern_figures",
    "write_pattern",
    "summary",
    "drape",
    "write_drape",
    "drape_summary",
    "export_allowance",
    "export",
    "marker",
    "write_marker",
    "LayerRun",
    "OutfitRun",
    "drape_outfit",
    "outfit_summary",
    "write_outfit",
]
