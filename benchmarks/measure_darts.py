"""Women's fitted blouse with and without its bust darts at uniform ease 1.1 and 1.3 (women's
chart size M): weft compliance, warp deviation, shear p95, flipped/collapsed and the darts'
intakes and leg differences. ``python -m benchmarks.measure_darts``; a case for the
pattern bench's women's-wear table (:func:`blouse_case`)."""
import copy
import json
import sys

from core import workflows as wf
from core.design.templates import TEMPLATES


def blouse_case(ease: float, darts: bool) -> dict:
    """The blouse design at uniform ``ease``, with its darts or without them."""
    d = TEMPLATES["blouse_fitted"]()
    for p in d["garments"][0]["panels"]:
        p["ease"] = {"value": ease}
        if not darts:
            p.pop("darts", None)
    return d


def main() -> int:
    for ease in (1.1, 1.3):
        for darts in (True, False):
            run = wf.reference(wf.prepare(blouse_case(ease, darts)))
            print(json.dumps({"ease": ease, "darts": darts, **run.figures,
                              "dart_records": run.pattern.report.get("darts", {})}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
