"""core.export.pdf: 1:1 scale (test square, form geometry), tiling page count, plotter sheet."""
import base64
import math
import re
import zlib

import numpy as np
import pytest

from export_synth import make_pattern

pytest.importorskip("reportlab")

from core.export import pdf
from core.export.pieces import build_pieces
from core.geom.layout import layout_pieces

MM = 72.0 / 25.4  # PDF points per millimetre


def parse_pdf(data: bytes):
    """Objects of an (uncrypted, non-xref-stream) PDF: {num: (dict bytes, decoded stream or None)}."""
    objs = {}
    for m in re.finditer(rb"(\d+) 0 obj\s*(.*?)endobj", data, re.S):
        body = m.group(2)
        sm = re.search(rb"stream\r?\n", body)
        stream = None
        head = body
        if sm:
            head = body[:sm.start()]
            length = int(re.search(rb"/Length (\d+)", head).group(1))
            raw = body[sm.end():sm.end() + length]
            if b"ASCII85Decode" in head:
                raw = base64.a85decode(raw.strip().removesuffix(b"~>"), adobe=False)
            if b"FlateDecode" in head:
                raw = zlib.decompress(raw)
            stream = raw
        objs[int(m.group(1))] = (head, stream)
    return objs


def pages(objs):
    """Page objects in document order: list of (dict bytes, content stream)."""
    tree = next(h for h, _ in objs.values() if re.search(rb"/Type /Pages\b", h))
    kids = [int(k) for k in re.findall(rb"(\d+) 0 R", re.search(rb"/Kids \[(.*?)\]", tree, re.S).group(1))]
    out = []
    for k in kids:
        head = objs[k][0]
        c = int(re.search(rb"/Contents (\d+) 0 R", head).group(1))
        out.append((head, objs[c][1]))
    return out


def mediabox(head):
    return [float(v) for v in re.search(rb"/MediaBox \[(.*?)\]", head).group(1).split()]


@pytest.fixture(scope="module")
def made():
    pat = make_pattern()
    pieces = build_pieces(pat)
    lay = layout_pieces([p.bbox for p in pieces], 0.88, 0.02, reserve=pdf.TEST_RESERVE)
    return pat, pieces, lay


@pytest.mark.parametrize("paper,size_mm", [("a4", (210, 297)), ("letter", (215.9, 279.4))])
def test_tiled_pdf_pages_scale_and_test_square(made, paper, size_mm):
    pat, pieces, lay = made
    objs = parse_pdf(pdf.tiled_pdf(pieces, lay, paper, pat.style))
    pg = pages(objs)
    # page count = the tiling of the layout by the printable area of the paper
    tile = (size_mm[0] - 20) / 1000, (size_mm[1] - 20) / 1000
    want = math.ceil(lay.size[0] / tile[0]) * math.ceil(lay.size[1] / tile[1])
    rows, cols, _ = pdf.tile_grid(lay.size, paper)
    assert len(pg) == want == rows * cols
    for head, _ in pg:
        assert mediabox(head) == pytest.approx([0, 0, size_mm[0] * MM, size_mm[1] * MM], abs=1e-3)
    # the 10 cm test square is on page 1 (and only there)
    squares = [re.findall(rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) re", c) for _, c in pg]
    hits = [[s for s in page if abs(float(s[2]) - 100 * MM) < 0.01 and abs(float(s[3]) - 100 * MM) < 0.01]
            for page in squares]
    assert len(hits[0]) == 1 and not any(hits[1:])
    x, y = float(hits[0][0][0]), float(hits[0][0][1])
    assert 0 < x and x + 100 * MM < size_mm[0] * MM and 0 < y and y + 100 * MM < size_mm[1] * MM
    # pieces are placed by pure translations: nothing on a page is scaled
    for _, c in pg:
        for a, b, cc, d in re.findall(rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) -?[\d.]+ -?[\d.]+ cm", c):
            assert (float(a), float(b), float(cc), float(d)) == (1, 0, 0, 1)
    # page 1 carries the assembly map: every page's name in its grid
    assert b"assembly map" in pg[0][1]
    for r in range(rows):
        for col in range(cols):
            assert f"({pdf.row_name(r)}{col + 1}) Tj".encode() in pg[0][1]
    # page labels: row letter + column number, and join marks naming the neighbour
    text = b"".join(c for _, c in pg)
    assert b"page A1" in text and b"join A2" in text and b"join B1" in text


@pytest.mark.parametrize("paper", ["a4", "letter"])
def test_every_piece_lands_on_the_pages_it_covers(made, paper):
    pat, pieces, lay = made
    pg = pages(parse_pdf(pdf.tiled_pdf(pieces, lay, paper, pat.style)))
    rows, cols, tile = pdf.tile_grid(lay.size, paper)
    m = pdf.PAGE_MARGIN
    for r in range(rows):
        for c in range(cols):
            content = pg[r * cols + c][1]
            drawn = {int(k): (float(x), float(y)) for x, y, k in
                     re.findall(rb"1 0 0 1 (-?[\d.]+) (-?[\d.]+) cm\s*/FormXob\.piece(\d+) Do", content)}
            x0, y0 = c * tile[0], lay.size[1] - (r + 1) * tile[1]  # the sheet window of this page
            for k, (piece, off) in enumerate(zip(pieces, lay.offsets)):
                box = piece.bbox + off
                covers = not (box[1, 0] < x0 or box[0, 0] > x0 + tile[0] or box[1, 1] < y0 or box[0, 1] > y0 + tile[1])
                assert (k in drawn) == covers
                if covers:  # piece frame -> page: + layout offset - window corner + margin, in points
                    want = (np.array([m - x0, m - y0]) + off) * 1000 * MM
                    np.testing.assert_allclose(drawn[k], want, atol=0.01)
    assert sum(len(re.findall(rb"Do", c)) for _, c in pg) >= len(pieces)


def test_piece_forms_are_drawn_at_one_to_one(made):
    pat, pieces, lay = made
    objs = parse_pdf(pdf.tiled_pdf(pieces, lay, "a4", pat.style))
    forms = [objs[k] for k in sorted(objs) if b"/Subtype /Form" in objs[k][0]]  # in piece order
    assert len(forms) == len(pieces)
    for head, _ in forms:
        assert re.search(rb"/Matrix \[ 1 0 0 1 0 0 \]", head)
    # the red (cut line) path of each form spans the piece's cut line, in points
    spans = []
    for _, stream in forms:
        red = stream.split(b"1 0 0 RG", 1)[1].split(b"RG", 1)[0]
        pts = np.array([[float(a), float(b)] for a, b in re.findall(rb"(-?[\d.]+) (-?[\d.]+) [ml]\b", red)])
        spans.append(tuple(np.ptp(pts, axis=0) / MM))
    want = [tuple(np.ptp(p.cut[0], axis=0) * 1000) for p in pieces]
    np.testing.assert_allclose(spans, want, atol=0.1)


def test_plotter_pdf_is_one_sheet_at_full_size(made):
    pat, pieces, lay = made
    pg = pages(parse_pdf(pdf.plotter_pdf(pieces, lay, pat.style)))
    assert len(pg) == 1
    w, h = mediabox(pg[0][0])[2:]
    assert w / MM == pytest.approx(lay.size[0] * 1000 + 20, abs=0.01) and w / MM <= 914
    assert h / MM == pytest.approx(lay.size[1] * 1000 + 20, abs=0.01)
    assert re.search(rb"283\.46\d* 283\.46\d* re", pg[0][1])


def test_row_names():
    assert [pdf.row_name(i) for i in (0, 1, 25, 26, 27)] == ["A", "B", "Z", "AA", "AB"]
