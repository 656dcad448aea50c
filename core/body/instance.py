"""One body instance from a body spec: model, shape (a chart size or a shape dict), pose.

Every stage that needs "the body this design, pattern or drape is on" goes
through :func:`body_instance` (or :func:`spec_instance` for a stored
``{"model", "shape", "pose"}`` record), so a size name, a JSON pose and the
reference pose are read the same way everywhere: the CLI, the add-on, the
drape and the benchmarks.
"""

from __future__ import annotations

from typing import Mapping, Optional, Tuple, Union

import numpy as np

from .model import REFERENCE_POSE

Shape = Union[None, str, Mapping[str, float]]
Pose = Union[None, str, Mapping[str, object]]


def instance_shape(model, shape: Shape) -> Optional[dict]:
    """The shape dict of ``shape``: a chart size name (``"M"``, ``"women:M"``) is fitted on ``model``.

    Parameters
    ----------
    model : BodyModel
    shape : None, str or mapping
        ``None`` (the model's reference shape), a size name, or a shape dict.

    Returns
    -------
    dict or None
        ``None`` stands for the reference shape.
    """
    if isinstance(shape, str):
        from .sizes import size_shape

        return size_shape(model, shape)
    return dict(shape) if shape else None


def instance_pose(pose: Pose):
    """The pose argument of :meth:`BodyModel.vertices` for ``pose``.

    One spelling per pose, so every caller gets the same instance: the
    reference preset ``"A"`` and ``None`` are both the reference pose (None);
    another preset name stays a name; a JSON pose ``{joint: [rx, ry, rz]}``
    (radians, see :mod:`core.body.poses`) becomes arrays; the preset a JSON pose
    starts from (``"preset": "P1"``) stays a name.
    """
    if isinstance(pose, Mapping):
        return {k: v if k == "preset" else np.asarray(v, dtype=float) for k, v in pose.items()}
    return None if pose == REFERENCE_POSE else pose


def body_instance(model, shape: Shape = None, pose: Pose = None) -> np.ndarray:
    """Vertices of one body instance.

    Parameters
    ----------
    model : BodyModel
    shape : None, str or mapping
        Chart size name or shape dict (see :func:`instance_shape`).
    pose : None, str or mapping
        Pose preset name (``"A"``, ``"T"``, ``"P1"`` ...) or JSON pose.

    Returns
    -------
    (V, 3) float64 array, metres, Z up.
    """
    return np.asarray(model.vertices(instance_shape(model, shape), instance_pose(pose)), dtype=np.float64)


def spec_instance(spec: Mapping, model=None) -> Tuple[np.ndarray, np.ndarray]:
    """(vertices (V, 3) float64 m, faces (F, 3) int64) of a stored body record.

    ``spec`` is the ``body`` record of a design, cut or pattern:
    ``{"model": "anny" | file, "shape": size name | dict, "pose": ...}``. The
    model is loaded through :func:`core.body.registry.load_spec` unless given (an OBJ
    template with the landmarks, blend shapes and up axis its record names).
    """
    if model is None:
        from .registry import load_spec

        model = load_spec(spec)
    V = body_instance(model, spec.get("shape"), spec.get("pose"))
    return V, np.asarray(model.faces, dtype=np.int64)
