"""Former home of the design format, kept for importers outside the design stage:
the types are in :mod:`core.design.types`, the parser in :mod:`core.design.parser`."""
from .parser import load_design, parse_design, save_design  # noqa: F401
from .types import Design  # noqa: F401
