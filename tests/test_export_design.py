"""Seam allowance and notch spacing set in the design: design JSON -> cut -> pattern -> export files.

``materials.export`` of a design travels with the cut and the pattern
(``pattern.json``) to ``ease export``, which uses it when no ``--allowance`` is
given. The end-to-end test measures the allowance in the written SVG.
"""

import copy
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from core.design.parser import parse_design
from core.errors import DesignError, EaseError, ExportError
from core.export.allowance import resolve_allowance, seam_allowance
from core.export.boundary import piece_loops
from core.geom.polygon import ray_hit

REPO = Path(__file__).resolve().parent.parent
SHORTS = REPO / "examples" / "designs" / "shorts.json"
NS = {"svg": "http://www.w3.org/2000/svg"}
EXPORT = {
    "allowance": {"default": 0.012, "hem": 0.03, "side_right": 0.02, "shorts.inseam_left": 0.015},
    "notch_spacing": 0.08,
}


def _shorts(export=None, coarse=True):
    d = json.loads(SHORTS.read_text())
    if coarse:
        d["refine_edge_length"] = 0.03  # a coarse cut keeps the solve at a few seconds
    if export is not None:
        d["materials"]["export"] = copy.deepcopy(export)
    return d


def test_design_keeps_its_export_settings(tmp_path):
    d = _shorts(EXPORT)
    design = parse_design(d)
    assert design.materials["export"] == EXPORT
    # written and read back unchanged
    again = parse_design(json.loads(json.dumps(design.to_json())))
    assert again.materials["export"] == EXPORT
    # a design without it stays without it (templates round-trip byte for byte)
    assert "export" not in parse_design(_shorts()).materials
    # one number sets every seam
    d = _shorts({"allowance": 0.015})
    assert parse_design(d).materials["export"] == {"allowance": 0.015}


@pytest.mark.parametrize(
    "export,path",
    [
        ({"allowance": 0.5}, "materials.export.allowance"),
        ({"allowance": {"hem": -0.01}}, "materials.export.allowance.hem"),
        ({"allowance": {"hem": "2cm"}}, "materials.export.allowance.hem"),
        ({"allowance": {"sidee_left": 0.01}}, "materials.export.allowance.sidee_left"),
        ({"allowance": {"waist": 0.01}}, "materials.export.allowance.waist"),  # an opening, not a seam
        ({"allowance": [0.01]}, "materials.export.allowance"),
        ({"notch_spacing": -0.1}, "materials.export.notch_spacing"),
        ({"notches": 0.1}, "materials.export.notches"),
    ],
)
def test_bad_export_settings_name_their_path(export, path):
    with pytest.raises(DesignError) as e:
        parse_design(_shorts(export))
    assert e.value.path == path, str(e.value)


def test_seam_keys_pick_the_most_specific_entry():
    w = {"default": 0.01, "hem": 0.02, "side_left": 0.013, "shorts.side_left": 0.014, "shorts.side_left#1": 0.016}
    assert seam_allowance(w, "shorts.side_left#1") == 0.016
    assert seam_allowance(w, "shorts.side_left#0") == 0.014
    assert seam_allowance(w, "shorts.side_left") == 0.014
    assert seam_allowance(w, "pants.side_left") == 0.013
    assert seam_allowance(w, "side_left#2") == 0.013
    assert seam_allowance(w, "shorts.inseam") == 0.01


def _run(argv):
    from core.cli import build_parser

    args = build_parser().parse_args(argv)
    return args.func(args)


@pytest.fixture(scope="module")
def shorts_pattern(tmp_path_factory):
    from core.body import load_body

    try:
        load_body("anny")
    except EaseError as exc:
        pytest.skip(f"the default body (Anny) is not available: {exc}")
    root = tmp_path_factory.mktemp("design_export")
    (root / "shorts.json").write_text(json.dumps(_shorts(EXPORT)))
    assert _run(["pattern", str(root / "shorts.json"), "--out", str(root / "pattern"), "--quiet"]) == 0
    return root


def _paths(group, cls):
    out = []
    for el in group.findall(f"svg:path[@class='{cls}']", NS):
        for part in re.findall(r"M[^M]*", el.get("d")):
            out.append(np.array([[float(a), float(b)] for a, b in re.findall(r"(-?[\d.]+),(-?[\d.]+)", part)]))
    return out


def test_allowance_set_in_the_design_reaches_the_files(shorts_pattern):
    from core.pattern.io import load_pattern

    root = shorts_pattern
    pat = load_pattern(root / "pattern")
    # the design's settings travelled through the cut into pattern.json
    assert pat.materials["export"] == EXPORT
    seams = {s.name for s in pat.seams}
    assert {"shorts.side_right", "shorts.inseam_left", "shorts.inseam_right"} <= seams

    # no --allowance / --notch-spacing: the design's values are used
    assert _run(["export", str(root / "pattern"), "--format", "svg", "--out", str(root / "x"), "--quiet"]) == 0
    summary = json.loads((root / "x" / "export.json").read_text())
    assert summary["allowance_mm"]["default"] == 12 and summary["allowance_mm"]["hem"] == 30

    # expected width of every sew edge, from the pattern's seams and hems
    widths = resolve_allowance(None, pat)
    svg = ET.parse(root / "x" / "pattern.svg").getroot()
    groups = {g.get("data-piece"): g for g in svg.findall("svg:g", NS)}
    seen = set()
    for panel in pat.panels:
        loop = piece_loops(panel)[0]
        want = {}
        for h in panel.hems:
            for u, v in zip(h[:-1], h[1:]):
                want[frozenset((int(u), int(v)))] = widths["hem"]
        for s in pat.seams:
            for name, ids in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b)):
                if name == panel.name:
                    for u, v in zip(ids[:-1], ids[1:]):
                        want[frozenset((int(u), int(v)))] = seam_allowance(widths, s.name)
        expect = (
            np.array(
                [
                    want.get(frozenset((int(loop[i]), int(loop[(i + 1) % len(loop)]))), widths["default"])
                    for i in range(len(loop))
                ]
            )
            * 1000
        )
        (sew,), (cut,) = _paths(groups[panel.name], "sew"), _paths(groups[panel.name], "cut")
        # the allowance as a cutter measures it: from the middle of each sew edge, square
        # to the edge, out to the cut line (SVG y points down: the outward normal flips)
        d = np.roll(sew, -1, axis=0) - sew
        mid = sew + 0.5 * d
        nrm = np.column_stack([-d[:, 1], d[:, 0]]) / np.linalg.norm(d, axis=1)[:, None]
        measured = np.array([ray_hit(m, n, cut) for m, n in zip(mid, nrm)])
        assert len(mid) == len(expect)
        for w in np.unique(expect):
            sel = expect == w
            # measured in the file (mm, printed to 0.01 mm): each kind of edge at its requested
            # width, but for at most two edges next to a corner, where the ray from the middle
            # of a short edge meets the neighbour's (mitred or squared) allowance farther out
            off = np.abs(measured[sel] - w) > 0.05
            assert np.median(measured[sel]) == pytest.approx(w, abs=0.02), (panel.name, w)
            assert off.sum() <= 2, (panel.name, w, measured[sel][off])
            seen.add(float(w))
        # and nowhere is the allowance narrower than asked
        assert np.all(measured >= expect - 0.05), panel.name
    assert seen == {12.0, 15.0, 20.0, 30.0}
    # labels: the right pieces are declared mirrors of the left ones, but the design gives the right side seam
    # and the left inseam wider allowances: the cut lines are no mirror images, and every label says so
    for panel in pat.panels:
        texts = [t.text for t in groups[panel.name].findall("svg:text", NS)]
        assert panel.name.endswith("_right") == bool(panel.mirror_of)
        twin = panel.mirror_of or panel.name.replace("_left", "_right")
        line = next(t for t in texts if t.startswith("cut 1"))
        assert line.startswith(f"cut 1, not the mirror of {twin}: ") and line.endswith(" mm off"), texts
        assert float(line.split(": ")[1].split()[0]) > 3.0  # 3 mm more allowance on one side
        assert "units: mm, allowance" in " ".join(texts)

    # notches every 8 cm from the design, from either end of each seam: at equal arc lengths from the nearer
    # end on both sides (the middle one, where there is one, at half of each side)
    by_seam = {}
    for p in summary["pieces"]:
        for seam, s in p["notches_mm"].items():
            by_seam.setdefault(seam, []).append(np.array(s))
    assert set(by_seam) == seams
    for seam, (a, b) in by_seam.items():
        assert len(a) == len(b) >= 3, seam
        half = len(a) // 2
        step = 80.0 * np.arange(1, half)
        for side in (a, b):
            np.testing.assert_allclose(side[1:half], step, atol=0.01)
            np.testing.assert_allclose(side[-1] - side[-half:-1], step[::-1], atol=0.01)
            if len(side) % 2:
                assert side[half] == pytest.approx(side[-1] / 2, abs=0.01)
    assert max(len(a) for a, _ in by_seam.values()) >= 6


def test_command_line_overrides_the_design(shorts_pattern):
    root = shorts_pattern
    assert (
        _run(
            [
                "export",
                str(root / "pattern"),
                "--format",
                "svg",
                "--out",
                str(root / "y"),
                "--allowance",
                "0.005",
                "--notch-spacing",
                "0",
                "--quiet",
            ]
        )
        == 0
    )
    s = json.loads((root / "y" / "export.json").read_text())
    # --allowance replaces the default; the design's hem and per-seam widths stay
    assert s["allowance_mm"]["default"] == 5 and s["allowance_mm"]["hem"] == 30
    assert s["allowance_mm"]["side_right"] == 20
    assert all(len(v) == 2 for p in s["pieces"] for v in p["notches_mm"].values())  # seam ends only


def test_pattern_with_a_stale_seam_key_fails_before_writing(shorts_pattern, tmp_path):
    from core.export import export_pattern
    from core.pattern.io import load_pattern

    pat = load_pattern(shorts_pattern / "pattern")
    pat.materials = {"export": {"allowance": {"yoke": 0.01}}}
    with pytest.raises(ExportError, match="yoke.*side_right"):
        export_pattern(pat, tmp_path / "z", formats="svg")
    assert not (tmp_path / "z").exists()
