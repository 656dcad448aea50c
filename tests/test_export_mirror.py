"""Mirror images in the cutting-room files: notches of mirrored seams, and the labels of declared pairs.

The dress's pieces span both sides of the body: its left and right seams
(``side_left`` / ``side_right``) lie on one piece and its waist seams run
across the centre line. Notches measured from one end of a seam made the
two halves of each piece differ by 37-62 mm (so no piece printed as a half on
the fold); the teaser's left and right pieces (declared pairs) must stay
mirror images too. Patterns are solved on coarse cuts (3 cm edges) to keep
the module at a few seconds.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from core.export.fold_half import fold_axis
from core.export.mirror_check import MIRROR_TOL, REFLECTIONS, mirror_gap, points_apart
from core.export.pieces import build_pieces
from core.export.print_set import print_set
from core.geom.polygon import centroid
from core.geom.polyline import polyline_length

REPO = Path(__file__).resolve().parent.parent
DESIGNS = ("dress", "teaser_shirt_pants")


@pytest.fixture(scope="module")
def patterns(anny, tmp_path_factory):
    from core.cli import build_parser
    from core.pattern.io import load_pattern

    root = tmp_path_factory.mktemp("mirror")
    out = {}
    for name in DESIGNS:
        d = json.loads((REPO / "examples" / "designs" / f"{name}.json").read_text())
        d["refine_edge_length"] = 0.03
        (root / f"{name}.json").write_text(json.dumps(d))
        args = build_parser().parse_args(["pattern", str(root / f"{name}.json"), "--out", str(root / name), "--quiet"])
        assert args.func(args) == 0
        out[name] = load_pattern(root / name)
    return out


def _notch_gap(left, right) -> float:
    """How far (m) the notch slits of ``right`` lie from the mirror image of ``left``'s (as :func:`mirror_gap`
    places it: reflected across or along the grain, centroids of the outlines met)."""
    best = np.inf
    for F in REFLECTIONS:
        shift = centroid(right.sew[0]) - centroid(left.sew[0] @ F)
        a = np.concatenate([n.segment for n in left.notches]) @ F + shift
        best = min(best, points_apart(a, np.concatenate([n.segment for n in right.notches])))
    return best


@pytest.mark.parametrize("name", DESIGNS)
def test_mirrored_seams_carry_mirrored_notches(patterns, name):
    """Every declared pair's notches are the mirror image of each other's, and every piece spanning both sides
    (the dress's four, the shirt's front and back) is its own mirror image, notches included: printed as a half
    on the fold. The pairs still print once."""
    pat = patterns[name]
    pieces = build_pieces(pat)
    by = {p.name: p for p in pieces}
    pairs = [(p.mirror_of, p.name) for p in pat.panels if p.mirror_of]
    assert len(pairs) == (4 if name == "teaser_shirt_pants" else 0)
    for left, right in pairs:
        assert len(by[left].notches) == len(by[right].notches) > 0
        assert _notch_gap(by[left], by[right]) <= MIRROR_TOL, (left, right)
        assert mirror_gap(by[left], by[right]) <= MIRROR_TOL
    paired = {n for pair in pairs for n in pair}
    halves = [p.name for p in pieces if p.name not in paired]
    assert len(halves) == (4 if name == "dress" else 2)
    for piece in (by[n] for n in halves):
        x0 = fold_axis(piece, MIRROR_TOL)
        assert x0 is not None, piece.name
        slits = np.concatenate([n.segment for n in piece.notches])
        assert points_apart(slits * [-1, 1] + [2 * x0, 0], slits) <= MIRROR_TOL
    _, plan = print_set(pat, pieces)
    assert sorted(e["piece"] for e in plan if e["cut"] == "on fold (half printed)") == sorted(halves)
    assert sorted(e["piece"] for e in plan if e["quantity"] == 2) == sorted(left for left, _ in pairs)


@pytest.mark.parametrize("name", DESIGNS)
def test_both_sides_of_every_seam_match(patterns, name):
    """Both sides of every seam carry as many notches, at equal arc lengths from the nearer end of the seam (at
    the same fractions of each side on a gathered seam, the dress's waist and the shirt's armholes)."""
    pat = patterns[name]
    pieces = {p.name: p for p in build_pieces(pat)}
    gathered = 0
    for seam in pat.seams:
        if seam.kind == "dart":
            continue
        na = [n.s for n in pieces[seam.panel_a].notches if n.seam == seam.name and n.side == "a"]
        nb = [n.s for n in pieces[seam.panel_b].notches if n.seam == seam.name and n.side == "b"]
        la = polyline_length(pat.panel(seam.panel_a).uv[seam.verts_a])
        lb = polyline_length(pat.panel(seam.panel_b).uv[seam.verts_b])
        sa, sb = np.array(na), np.array(nb)
        assert len(sa) == len(sb) >= 2, seam.name
        if seam.gathered:
            gathered += 1
            np.testing.assert_allclose(sa / la, sb / lb, atol=1e-9)
            continue
        half = len(sa) // 2
        np.testing.assert_allclose(sa[:half], sb[:half], atol=1e-9)
        np.testing.assert_allclose(la - sa[-half:], lb - sb[-half:], atol=1e-9)
        if len(sa) % 2:
            assert sa[half] == pytest.approx(la / 2) and sb[half] == pytest.approx(lb / 2)
    assert gathered == (2 if name == "dress" else 4)


def test_dress_prints_its_halves_on_the_fold(patterns, tmp_path):
    """The tiled PDFs print each of the dress's pieces once, as its half on the fold (export.json says how)."""
    from core.export import export_pattern

    export_pattern(patterns["dress"], tmp_path, formats="pdf")
    summary = json.loads((tmp_path / "export.json").read_text())
    for paper in ("a4", "letter"):
        plan = summary["pdf"][paper]["pieces"]
        assert [e["cut"] for e in plan] == ["on fold (half printed)"] * 4
        assert [e["pieces"] for e in plan] == [[p.name] for p in patterns["dress"].panels]


def _texts(out: Path):
    """The label texts of every file written: SVG (per piece group), AAMA DXF (per block), plain DXF (all)."""
    import xml.etree.ElementTree as ET

    import ezdxf

    ns = {"svg": "http://www.w3.org/2000/svg"}
    root = ET.parse(out / "pattern.svg").getroot()
    svg = {
        g.get("data-piece"): [t.text for t in g.findall("svg:text", ns)]
        for g in root.iter(f"{{{ns['svg']}}}g")
        if g.get("data-piece")
    }
    aama = {}
    for b in ezdxf.readfile(out / "pattern_astm.dxf").blocks:
        if not b.name.startswith("*"):
            aama[b.name] = [e.dxf.text for e in b if e.dxftype() == "TEXT"]
    plain = [e.dxf.text for e in ezdxf.readfile(out / "pattern_plain.dxf").modelspace() if e.dxftype() == "TEXT"]
    return svg, aama, plain


@pytest.mark.parametrize("bulge,mirrored", [(0.0, True), (0.0003, True), (0.004, False)])
def test_svg_and_dxf_labels_follow_the_mirror_check(tmp_path, bulge, mirrored):
    """A declared pair is labelled ``mirror of`` / ``mirrored by`` in the SVG and DXF only when the tiled PDF's
    check finds it a mirror image (within 0.5 mm: the 0.3 mm bulge is); ease painted on one side (a 4 mm bulge)
    makes both labels say ``not the mirror of X: N mm off``, the figure the PDF's plan gives."""
    pytest.importorskip("ezdxf")
    from export_synth import mirrored_pattern

    from core.export import export_pattern

    export_pattern(mirrored_pattern(bulge), tmp_path, formats="svg,dxf,pdf")
    summary = json.loads((tmp_path / "export.json").read_text())
    plan = summary["pdf"]["a4"]["pieces"]
    if mirrored:
        want = {"front_left": "cut 1, mirrored by front_right", "front_right": "cut 1, mirror of front_left"}
        assert [e["quantity"] for e in plan] == [2]
    else:
        mm = plan[0]["not_mirrored_mm"]
        assert mm == plan[1]["not_mirrored_mm"] > 0.5
        want = {
            "front_left": f"cut 1, not the mirror of front_right: {mm:g} mm off",
            "front_right": f"cut 1, not the mirror of front_left: {mm:g} mm off",
        }
    svg, aama, plain = _texts(tmp_path)
    for piece, line in want.items():
        assert line in svg[piece], svg[piece]
        block = next(texts for name, texts in aama.items() if piece in name)
        assert any(line in t for t in block), block
        assert line in plain
    cut_lines = [t for texts in [*svg.values(), *aama.values(), plain] for t in texts if t.startswith("cut ")]
    assert len(cut_lines) == 6 and all(("not the mirror" in t) != mirrored for t in cut_lines)
