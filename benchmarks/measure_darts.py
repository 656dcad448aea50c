"""Women's fitted blouse (women's chart, size M) without darts, with the template's bust darts
and with automatic darts, at uniform ease 1.1 and 1.3: weft compliance, warp deviation, shear
p95, the bust region (within 6 cm of the bust points), flipped/collapsed, and each dart's intake
and leg difference. ``python -m benchmarks.measure_darts``. :func:`blouse_case` is the case for
the pattern bench's women's-wear table."""
import json
import sys

from core import workflows as wf
from core.design.templates import TEMPLATES

VARIANTS = ("none", "bust", "auto")


def blouse_case(ease: float, darts: str = "bust") -> dict:
    """The blouse design at uniform ``ease``: ``darts`` ``"none"`` (removed), ``"bust"`` (the
    template's side-seam bust darts) or ``"auto"`` (one automatic dart per side, intake <= 8 cm)."""
    d = TEMPLATES["blouse_fitted"]()
    for p in d["garments"][0]["panels"]:
        p["ease"] = {"value": ease}
        if darts == "none":
            p.pop("darts", None)
        elif darts == "auto" and p["name"] == "front":
            p["darts"] = {"auto": {"max_count": 1, "max_intake": 0.08}}
    return d


def row(ease: float, darts: str) -> dict:
    """The figures of one case (percent, degrees, mm)."""
    run = wf.reference(wf.prepare(blouse_case(ease, darts)))
    f, regions = run.figures, run.pattern.report["metrics"].get("regions", {})
    bust = [regions[k]["mean"] for k in ("bust_left", "bust_right") if k in regions]
    return {"ease": ease, "darts": darts, "weft %": f["compliance mean %"],
            "warp %": f.get("warp deviation mean %"), "shear p95 deg": f["shear p95 deg"],
            "bust region %": round(max(bust), 2) if bust else None, "flipped": f["flipped"],
            "collapsed": f.get("collapsed"),
            "darts_mm": {k: [v["intake_mm"], v["leg_difference_mm"]]
                         for k, v in run.pattern.report.get("darts", {}).items()}}


def main() -> int:
    for ease in (1.1, 1.3):
        for darts in VARIANTS:
            print(json.dumps(row(ease, darts)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
