"""Body models by name: ``load_body("anny")`` (the default, embedded) or a path.

- ``"anny"``: :class:`core.body.anny.AnnyBody`, built once and cached.
- ``*.npz`` / ``*.pkl`` / ``*.pickle``: an SMPL / SMPL-X model file the user owns
  (:func:`core.body.smpl.load_smpl`).
- ``*.obj``: a fixed-topology template mesh (:func:`core.body.obj_model.load_obj_body`).
"""
from __future__ import annotations

import os
import threading

from ..errors import BodyError
from .model import BodyModel

BUILTIN = ("anny",)
SMPL_SUFFIXES = (".npz", ".pkl", ".pickle")
MODEL_SUFFIXES = SMPL_SUFFIXES + (".obj",)   # every model file a design, the CLI and the add-on accept
_CACHE = {}
_LOCK = threading.Lock()


def load_body(name: str = "anny", **kwargs) -> BodyModel:
    """Load a body model by name or file path (see module docstring).

    Raises
    ------
    BodyError
        For an unknown name, or a path with an unsupported extension.
    """
    if not isinstance(name, (str, os.PathLike)):
        raise BodyError(f"body name must be a string, got {type(name).__name__}")
    key = os.fspath(name)
    low = key.lower()
    if low == "anny":
        if kwargs:
            from .anny import AnnyBody
            return AnnyBody(**kwargs)
        with _LOCK:
            if "anny" not in _CACHE:
                from .anny import AnnyBody
                _CACHE["anny"] = AnnyBody()
            return _CACHE["anny"]
    if low.endswith(SMPL_SUFFIXES):
        from .smpl import load_smpl
        return load_smpl(key, **kwargs)
    if low.endswith(".obj"):
        from .obj_model import load_obj_body
        return load_obj_body(key, **kwargs)
    raise BodyError(f"unknown body {key!r}; options: {', '.join(BUILTIN)}, or a path to an "
                    f"SMPL/SMPL-X or template file ({', '.join(MODEL_SUFFIXES)})")
