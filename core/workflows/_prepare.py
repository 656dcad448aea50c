"""The prepare stage: a design loaded, its body and its cut (:func:`prepare`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np

from ..progress import Progress, report, sub


@dataclass
class Prepared:
    """A design cut on its body, ready for pattern solves.

    Attributes
    ----------
    design : core.design.Design
    body : BodyModel, the model the cut was made on.
    cut : core.cut.types.GarmentCut
    reference : (V, 3) float64, metres: the body instance the cut was made on
        (its ``cut.body`` record: shape and pose).
    timings : dict, wall seconds of ``load`` and ``cut`` (0 for what was given).
    """

    design: object
    body: object
    cut: object
    reference: np.ndarray
    timings: Dict[str, float] = field(default_factory=dict)


def prepare(design, body=None, cut=None, progress: Optional[Progress] = None) -> Prepared:
    """Load a design and its body and cut it (or adopt a cut already made).

    Parameters
    ----------
    design : path, JSON text, dict or core.design.Design
    body : BodyModel or None
        None loads the design's ``body.model`` (``"anny"`` by default).
    cut : GarmentCut or None
        A cut of this design made earlier (the add-on keeps one); None cuts now.
    progress : callback, optional
    """
    from ..body.instance import spec_instance
    from ..body.registry import load_spec
    from ..design import load_design

    t0 = time.perf_counter()
    design = load_design(design)  # an OBJ template's files made absolute against the design file
    if body is None:
        body = load_spec(design.body)
    t1 = time.perf_counter()
    if cut is None:
        from ..cut import cut_design

        cut = cut_design(design, body=body, progress=sub(progress, 0.0, 0.95))
    t2 = time.perf_counter()
    reference, _ = spec_instance(cut.body, model=body)
    report(progress, 1.0, f"cut {len(cut.panels)} panels")
    return Prepared(design, body, cut, reference, {"load": t1 - t0, "cut": t2 - t1})


def size_name(prep: Prepared, size: str) -> str:
    """The canonical chart size of ``size`` for ``prep``: a bare name (``"M"``) is of the
    design's chart (``body.chart``), a qualified one (``"women:M"``) of its own."""
    from ..body.sizes import size_of

    return size_of(str(size), prep.design.body.get("chart"))
