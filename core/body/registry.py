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
MODEL_SUFFIXES = SMPL_SUFFIXES + (".obj",)  # every model file a design, the CLI and the add-on accept
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
    raise BodyError(
        f"unknown body {key!r}; options: {', '.join(BUILTIN)}, or a path to an "
        f"SMPL/SMPL-X or template file ({', '.join(MODEL_SUFFIXES)})"
    )


#: Keys of a body record (a design's ``body``, a cut's or pattern's ``body``) naming an OBJ
#: template's own files and frame, passed to :func:`core.body.obj_model.load_obj_body`.
OBJ_OPTIONS = ("landmarks", "blendshapes", "up")
_FILE_KEYS = ("model", "landmarks", "blendshapes")


def resolve_body_files(spec, base_dir) -> dict:
    """A copy of the body record ``spec`` with its file paths (model, landmarks, blend shapes)
    made absolute against ``base_dir`` (the design file's folder); built-in names stay."""
    out = dict(spec)
    for key in _FILE_KEYS:
        value = out.get(key)
        if isinstance(value, str) and value.lower() not in BUILTIN and not os.path.isabs(value):
            out[key] = os.path.normpath(os.path.join(os.fspath(base_dir), value))
    return out


def load_spec(spec) -> BodyModel:
    """The body model of a body record ``{"model", ...}``: :func:`load_body` of its model, with
    an OBJ template's landmarks, blend shapes and up axis where the record names them."""
    name = spec.get("model") or "anny"
    options = {k: spec[k] for k in OBJ_OPTIONS if spec.get(k) is not None}
    if options and not os.fspath(name).lower().endswith(".obj"):
        raise BodyError(f"body {name!r}: {', '.join(options)} are options of an OBJ template only")
    return load_body(name, **options)
