"""The items of a batch: design × body, each named by a content hash.

An item's id hashes what determines its output: the design (its JSON,
canonicalised), the body model, the body (:meth:`BodySource.record`) and the
options that change files or figures (:meth:`Options.record`). Rerunning the
same command finds the same ids, so completed items are skipped; changing the
design, a body or an option makes new ones. The design's own hash keys the
worker's cache of prepared solvers (:mod:`core.batch.worker`).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field, replace
from typing import List, Optional, Sequence, Tuple

from .bodies import BodySource

#: Hex digits of the item id used in folder names (64 bits: collisions need ~4e9 items).
FOLDER_ID_DIGITS = 16


def content_hash(obj) -> str:
    """SHA-256 (hex) of ``obj`` as canonical JSON (sorted keys, no spaces)."""
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


@dataclass(frozen=True)
class Options:
    """What every item of a batch does besides the transfer.

    Attributes
    ----------
    config : solver configuration name (:data:`core.workflows.CONFIGS`), or None for the
        design's own (its ``solver``, else improved: :func:`core.workflows.config_name`),
        resolved when the items are made, so an item's record always names one
    poses : pose presets to adapt each item's pattern to (empty: none)
    drape : drape each item's pattern on its body (Warp XPBD)
    export : cutting-room formats written per item (``("svg", "dxf")``)
    garmentcode : also write the GarmentCode pattern specification
    preview : write ``pattern.png`` per item (costs more than the solve)
    marker_width : m of fabric: nest each item's pieces into ``marker/`` (:func:`core.workflows.marker`,
        the export's allowance rule); None: no marker
    marker_seconds : the nester's budget per item (s); marker_spread : ``"single"`` or ``"pairs"``
    """

    config: Optional[str] = None
    poses: Tuple[str, ...] = ()
    drape: bool = False
    export: Tuple[str, ...] = ()
    garmentcode: bool = False
    preview: bool = False
    marker_width: Optional[float] = None
    marker_seconds: int = 10
    marker_spread: str = "single"

    def record(self) -> dict:
        out = {
            "config": self.config,
            "poses": list(self.poses),
            "drape": self.drape,
            "export": list(self.export),
            "garmentcode": self.garmentcode,
            "preview": self.preview,
        }
        if self.marker_width is not None:  # only then: the ids of batches without a marker stay as they were
            out["marker"] = {"width": self.marker_width, "seconds": self.marker_seconds, "spread": self.marker_spread}
        return out


@dataclass(frozen=True)
class Item:
    """One unit of work: a body of the batch with everything a worker needs to make it.

    Attributes
    ----------
    id : str, the content hash (hex, 64 digits)
    index : position in the body list (the progress line and the seed order)
    body : BodySource
    design_key : content hash of the design (the worker's cache key)
    design : dict, the design JSON
    model : body model name or file (``"anny"``, an SMPL file)
    options : Options
    folder : the item's folder name under the dataset's ``items/``
    """

    id: str
    index: int
    body: BodySource
    design_key: str
    design: dict = field(compare=False, repr=False)
    model: str = "anny"
    options: Options = Options()

    @property
    def folder(self) -> str:
        return self.id[:FOLDER_ID_DIGITS]


def make_items(
    design: dict, bodies: Sequence[BodySource], model: str = "anny", options: Optional[Options] = None
) -> List[Item]:
    """Design × bodies as :class:`Item` (one per body, in the bodies' order).

    Two bodies with the same record make the same item; the duplicate is kept
    once (the first).
    """
    from ..workflows import config_name

    options = options or Options()
    # the design's own configuration made explicit: the id (and a rerun's skip) is the same
    # whether the caller named it or left it to the design
    options = replace(options, config=config_name(design, options.config))
    design_key = content_hash({"design": design, "model": model})
    seen, out = set(), []
    for i, body in enumerate(bodies):
        item_id = content_hash({"design": design_key, "body": body.record(), "options": options.record()})
        if item_id in seen:
            continue
        seen.add(item_id)
        out.append(Item(item_id, i, body, design_key, design, model, options))
    return out
