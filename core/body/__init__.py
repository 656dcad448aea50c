"""Parametric body models behind one interface (:class:`core.body.model.BodyModel`)."""

from .model import POSE_PRESETS, REQUIRED_LANDMARKS, REQUIRED_REGIONS, BodyModel, SurfacePoint

__all__ = ["BodyModel", "SurfacePoint", "POSE_PRESETS", "REQUIRED_LANDMARKS", "REQUIRED_REGIONS", "load_body"]


def load_body(name: str = "anny", **kwargs) -> BodyModel:
    """Load a body model by name: ``"anny"`` (default, embedded), or a path to an
    SMPL/SMPL-X ``.npz``/``.pkl`` file, or a template ``.obj``.

    Implemented in :mod:`core.body.registry`.
    """
    from .registry import load_body as _load

    return _load(name, **kwargs)
