"""Moved to ``tests/helpers/synthetic_pattern.py`` (test fixtures are not shipped code).

Loaded from the checkout for ``benchmarks/bench_export.py`` until it imports
``synthetic_pattern`` itself; then this module goes.
"""
import importlib.util as _util
from pathlib import Path as _Path

_spec = _util.spec_from_file_location(
    "synthetic_pattern", _Path(__file__).resolve().parents[2] / "tests" / "helpers" / "synthetic_pattern.py")
_module = _util.module_from_spec(_spec)
_spec.loader.exec_module(_module)
tube, two_panels = _module.tube, _module.two_panels
