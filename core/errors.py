"""Errors raised by the core. Each names the element at fault and what is expected."""


class EaseError(ValueError):
    """Base class of every user-facing error of the core."""


class BodyError(EaseError):
    """A body model, shape, pose or measurement is invalid."""


class DesignError(EaseError):
    """A design file is invalid. ``path`` is the JSON path of the offending element."""

    def __init__(self, path: str, message: str):
        self.path = path
        self.message = message
        super().__init__(f"{path}: {message}" if path else message)


class CutError(EaseError):
    """Cutting the body surface failed for a named design element."""


class PatternError(EaseError):
    """Pattern optimization got invalid input or produced an invalid pattern."""


class DrapeError(EaseError):
    """The drape diverged or got invalid input."""


class ExportError(EaseError):
    """A pattern cannot be exported."""


class Cancelled(Exception):
    """Raised inside a long operation when its progress callback asks to stop."""
