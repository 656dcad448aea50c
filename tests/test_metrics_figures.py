"""The drape's one-line summary shows the warp strain beside the weft's."""

from types import SimpleNamespace

from core import workflows as wf


def test_drape_summary_shows_warp_beside_weft():
    stats = lambda m: {"mean": m, "std": 0.0, "p95": m, "max": m}
    result = SimpleNamespace(
        material={"name": "cotton"}, frames=120, settle_reason="settled", timings={"simulate": 3.2}
    )
    metrics = {
        "all": {
            "gap_mm": {"mean": 4.0, "std": 1.0},
            "penetration_pct": 0.1,
            "seam_gap_mm": {"max": 0.5},
            "strain_weft_pct": stats(1.25),
            "strain_warp_pct": stats(-0.5),
        }
    }
    run = SimpleNamespace(result=result, metrics=metrics)
    line = wf.drape_summary(run, SimpleNamespace(style="shirt"))
    assert line.endswith("seam gap max 0.50 mm; strain weft 1.25 % / warp -0.50 % (mean)")
