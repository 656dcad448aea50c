"""Batch speed work on the metrics (core.metrics, figures byte-identical): the one-garment report
reads its overall figures once, and the means that need no percentile skip the sort."""

import numpy as np
from test_metrics_strains import _pattern

from core.metrics import pattern as M
from core.metrics.regions import region_compliance
from core.pattern.types import Pattern


def test_weighted_mean_is_the_mean_of_weighted_stats():
    from core.metrics.stats import weighted_mean, weighted_stats

    rng = np.random.default_rng(5)
    v, w = rng.normal(size=200), rng.uniform(0, 1, 200)
    v[3], w[7] = np.nan, 0.0  # left out by both
    assert weighted_mean(v, w) == weighted_stats(v, w)["mean"]
    assert np.isnan(weighted_mean([np.nan], [1.0])) and np.isnan(weighted_stats([np.nan], [1.0])["mean"])


def test_one_garment_report_lists_the_overall_figures_as_its_own():
    """A one-garment pattern's garment entry is the overall figures (a copy); two garments each their own."""
    pat = _pattern()
    lm = {"bust_left": np.array([0.4, 0.0, 0.4])}
    two = M.pattern_report(pat, lm)
    for g in ("a", "b"):
        assert two["garments"][g]["compliance"] == M.ease_compliance(pat, g)
        assert two["garments"][g]["regions"] == region_compliance(pat, lm, garment=g)
    assert two["garments"]["a"]["compliance"] != two["compliance"]
    one = Pattern(style="s", body={}, garments={"a": "upper"}, panels=[pat.panels[0]], seams=[])
    rep = M.pattern_report(one, lm)
    g = rep["garments"]["a"]
    assert g["compliance"] == M.ease_compliance(one, "a") == rep["compliance"]
    assert g["seams"] == M.seam_mismatch(one, "a") == rep["seams"]
    assert g["regions"] == region_compliance(one, lm, garment="a") == rep["regions"]
    assert g["compliance"] is not rep["compliance"] and g["regions"] is not rep["regions"]
    assert list(rep) == [
        "garments",
        "compliance",
        "seams",
        "flipped_triangles",
        "flipped_per_panel",
        "collapsed_triangles",
        "collapsed_per_panel",
        "collapse_sites",
        "regions",
        "crossings",
        "crossings_per_panel",
        "crossing_sites",
        "darts",
        "pieces",
    ]
