"""core.export.svg: 1:1 millimetres, one group per piece, distinct colours."""

import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from export_synth import make_pattern

from core.export.pieces import build_pieces
from core.export.svg import COLOURS, svg_document
from core.geom.layout import layout_pieces
from core.geom.polyline import polyline_length

NS = {"svg": "http://www.w3.org/2000/svg"}


def _points(d: str) -> list:
    """Polylines of an SVG path made of M/L/Z commands."""
    out = []
    for part in re.findall(r"M[^M]*", d):
        closed = part.rstrip().endswith("Z")
        pts = np.array([[float(a), float(b)] for a, b in re.findall(r"(-?[\d.]+),(-?[\d.]+)", part)])
        out.append((pts, closed))
    return out


@pytest.fixture(scope="module")
def svg():
    pat = make_pattern(rotate_back_deg=30.0)
    pieces = build_pieces(pat)
    lay = layout_pieces([p.bbox for p in pieces], 0.88, 0.02)
    return pat, pieces, lay, ET.fromstring(svg_document(pieces, lay, pat.style))


def test_document_is_in_millimetres(svg):
    pat, pieces, lay, root = svg
    w, h = lay.size * 1000
    assert root.get("width").endswith("mm") and root.get("height").endswith("mm")
    assert float(root.get("width")[:-2]) == pytest.approx(w, abs=1e-3)
    assert float(root.get("height")[:-2]) == pytest.approx(h, abs=1e-3)
    vb = [float(v) for v in root.get("viewBox").split()]
    assert vb == pytest.approx([0, 0, w, h], abs=1e-3)


def test_one_group_per_piece_with_all_lines(svg):
    pat, pieces, lay, root = svg
    groups = root.findall("svg:g", NS)
    assert [g.get("data-piece") for g in groups] == [p.name for p in pat.panels]
    for g in groups:
        kinds = {p.get("class"): p.get("stroke") for p in g.findall("svg:path", NS)}
        assert set(kinds) >= {"cut", "sew", "notch", "grain"}
        assert len(set(kinds.values())) == len(kinds)  # one colour per kind of line
        assert kinds["cut"] == COLOURS["cut"]
        texts = [t.text for t in g.findall("svg:text", NS)]
        assert "test shirt" in texts and "size: M" in texts


def test_piece_sizes_in_mm_equal_the_pattern(svg):
    pat, pieces, lay, root = svg
    for g, piece in zip(root.findall("svg:g", NS), pieces):
        panel = pat.panel(g.get("data-piece"))
        ((sew, closed),) = _points(g.find("svg:path[@class='sew']", NS).get("d"))
        assert closed
        # the pattern's own numbers: uv (m) in the grain-up frame
        loop = panel.boundary[0]
        xy = panel.uv[loop] @ piece.rotation.T * 1000.0
        np.testing.assert_allclose(np.ptp(sew, axis=0), np.ptp(xy, axis=0), atol=0.1)
        assert polyline_length(sew, closed=True) == pytest.approx(polyline_length(xy, closed=True), abs=0.1)
        # shape, not just size: same point set up to a translation (and the y flip of SVG)
        flipped = np.column_stack([sew[:, 0], -sew[:, 1]])
        np.testing.assert_allclose(flipped - flipped.mean(0), xy - xy.mean(0), atol=0.01)


def test_notch_count_matches_pieces(svg):
    pat, pieces, lay, root = svg
    for g, piece in zip(root.findall("svg:g", NS), pieces):
        segs = _points(g.find("svg:path[@class='notch']", NS).get("d"))
        assert len(segs) == len(piece.notches)
        for (pts, _), n in zip(segs, piece.notches):
            assert np.linalg.norm(pts[1] - pts[0]) == pytest.approx(
                np.linalg.norm(n.segment[1] - n.segment[0]) * 1000, abs=0.01
            )
