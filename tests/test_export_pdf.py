"""core.export.pdf and tiling: 1:1 scale (test square, form geometry), nested pages with lines only, overlap joins,
wide pieces, plotter sheet."""

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
            head = body[: sm.start()]
            length = int(re.search(rb"/Length (\d+)", head).group(1))
            raw = body[sm.end() : sm.end() + length]
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


@pytest.fixture(scope="module")
def nested(made):
    pat, pieces, _ = made
    return {paper: pdf.print_sheet(pieces, paper) for paper in ("a4", "letter")}


@pytest.fixture(scope="module")
def printed_pages(made, nested):
    """Per paper: the layout, its grid and printed pages, and the printed (row, col) beside their PDF pages."""
    pat, pieces, _ = made
    out = {}
    for paper, lay in nested.items():
        pg = pages(parse_pdf(pdf.tiled_pdf(pieces, lay, paper, pat.style)))
        grid, ink = pdf.sheet_pages(pieces, lay, paper)
        printed = [(r, c) for r in range(grid.rows) for c in range(grid.cols) if ink[r, c]]
        out[paper] = (lay, grid, ink, list(zip(printed, pg)))
    return out


def _segments_in(box, loops):
    """Whether any segment of the closed loops (sheet m) meets the box (dense sampling, independent of tiling.py)."""
    for loop in loops:
        a, b = loop, np.roll(loop, -1, axis=0)
        t = np.linspace(0, 1, 41)[:, None, None]
        q = (a[None] + t * (b - a)[None]).reshape(-1, 2)
        if np.any(np.all((q >= box[0] - 1e-9) & (q <= box[1] + 1e-9), axis=1)):
            return True
    return False


@pytest.mark.parametrize("paper,size_mm", [("a4", (210, 297)), ("letter", (215.9, 279.4))])
def test_tiled_pdf_pages_scale_and_test_square(made, nested, paper, size_mm):
    pat, pieces, _ = made
    lay = nested[paper]
    objs = parse_pdf(pdf.tiled_pdf(pieces, lay, paper, pat.style))
    pg = pages(objs)
    # windows: the paper less 10 mm margins, overlapping by 10 mm; one page per window with a line
    tile = (size_mm[0] - 20) / 1000, (size_mm[1] - 20) / 1000
    grid, ink = pdf.sheet_pages(pieces, lay, paper)
    step = np.array(tile) - pdf.OVERLAP
    assert grid.cols == math.ceil((lay.size[0] - pdf.OVERLAP) / step[0] - 1e-9)
    assert grid.rows == math.ceil((lay.size[1] - pdf.OVERLAP) / step[1] - 1e-9)
    assert len(pg) == int(ink.sum()) and ink[0, 0]
    for head, _ in pg:
        assert mediabox(head) == pytest.approx([0, 0, size_mm[0] * MM, size_mm[1] * MM], abs=1e-3)
    # the 10 cm test square is on page 1 (and only there)
    squares = [re.findall(rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) re", c) for _, c in pg]
    hits = [
        [s for s in page if abs(float(s[2]) - 100 * MM) < 0.01 and abs(float(s[3]) - 100 * MM) < 0.01]
        for page in squares
    ]
    assert len(hits[0]) == 1 and not any(hits[1:])
    x, y = float(hits[0][0][0]), float(hits[0][0][1])
    assert 0 < x and x + 100 * MM < size_mm[0] * MM and 0 < y and y + 100 * MM < size_mm[1] * MM
    # pieces are placed by a rotation and a translation: nothing on a page is scaled or mirrored
    for _, c in pg:
        for a, b, cc, d in re.findall(rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) -?[\d.]+ -?[\d.]+ cm", c):
            m = np.array([[float(a), float(cc)], [float(b), float(d)]])
            np.testing.assert_allclose(m @ m.T, np.eye(2), atol=1e-5)
            assert np.linalg.det(m) == pytest.approx(1.0, abs=1e-5)
    # page 1 carries the page map: the names of the printed pages in its grid, and no others
    assert b"page map" in pg[0][1]
    for r in range(grid.rows):
        for col in range(grid.cols):
            assert (f"({pdf.page_name(r, col)}) Tj".encode() in pg[0][1]) == bool(ink[r, col])
    # page labels: row letter + column number, numbered among the printed pages
    text = b"".join(c for _, c in pg)
    assert b"page A1" in text and f"1 of {len(pg)}".encode() in text


@pytest.mark.parametrize("paper", ["a4", "letter"])
def test_every_page_has_a_line_and_every_line_is_printed(made, printed_pages, paper):
    pieces = made[1]
    lay, grid, ink, printed = printed_pages[paper]
    loops = [lay.place(i, l) for i, p in enumerate(pieces) for l in list(p.cut) + list(p.sew)]
    m = pdf.PAGE_MARGIN
    for (r, c), (_, content) in printed:
        win = grid.window(r, c)
        # a printed page is page 1 or holds a line; a left-out page holds none
        assert (r, c) == (0, 0) or _segments_in(win, loops)
        drawn = {
            int(k): (np.array([[float(a), float(cc)], [float(b), float(d)]]), (float(x), float(y)))
            for a, b, cc, d, x, y, k in re.findall(
                rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) cm\s*/FormXob\.piece(\d+) Do",
                content,
            )
        }
        for k, piece in enumerate(pieces):
            corners = np.array([[piece.bbox[i, 0], piece.bbox[j, 1]] for i in (0, 1) for j in (0, 1)])
            q = lay.place(k, corners)
            covers = not (
                q[:, 0].max() < win[0, 0]
                or q[:, 0].min() > win[1, 0]
                or q[:, 1].max() < win[0, 1]
                or q[:, 1].min() > win[1, 1]
            )
            assert (k in drawn) == covers
            if covers:  # piece frame -> page: turn, + layout offset - window corner + margin, in points
                R, t = drawn[k]
                np.testing.assert_allclose(R, lay.matrix(k), atol=1e-5)
                np.testing.assert_allclose(t, (np.array([m, m]) - win[0] + lay.offsets[k]) * 1000 * MM, atol=0.01)
    for r in range(grid.rows):
        for c in range(grid.cols):
            if not ink[r, c]:
                assert not _segments_in(grid.window(r, c), loops)
    # the pieces do not overlap on the sheet and stay on it
    from core.geom.polygon import points_in_polygon

    outlines = [lay.place(i, p.cut[0]) for i, p in enumerate(pieces)]
    for i, a in enumerate(outlines):
        assert a.min() >= 0 and np.all(a <= lay.size + 1e-9)
        for b in outlines[i + 1 :]:
            assert not points_in_polygon(a, b).any() and not points_in_polygon(b, a).any()


@pytest.mark.parametrize("paper", ["a4", "letter"])
def test_labels_and_grain_lines_are_on_printed_pages(made, printed_pages, paper):
    """Pages inside a piece are left out, so each label moves onto pages printed for their lines (inside the sew
    line, clear of the lines) and each grain line shows at least GRAIN_SHOWN; the forms draw them there."""
    from core.export import print_labels, tiling
    from core.geom.polygon import points_in_polygon

    pieces = made[1]
    lay, grid, ink, printed = printed_pages[paper]
    lines = tiling.line_pages(pieces, lay, grid)
    lines[0, 0] = True
    assert np.array_equal(ink, lines)  # no page is printed for a label or a grain line alone
    objs = parse_pdf(pdf.tiled_pdf(pieces, lay, paper, "t"))
    forms = [objs[k][1] for k in sorted(objs) if b"/Subtype /Form" in objs[k][0]]
    flips = pdf.upside_down(lay, len(pieces))
    moved = 0
    for i, p in enumerate(pieces):
        at = tiling.label_at(lay, i, p)
        moved += not np.allclose(at, p.label_at)
        box = tiling.label_box(p, at)
        t = np.linspace(0.0, 1.0, 25)
        inner = box[0] + (box[2] - box[0]) * np.stack(np.meshgrid(t, t), axis=-1).reshape(-1, 2)
        assert points_in_polygon(inner, p.sew[0]).all()
        q = lay.place(i, inner)
        for r, c in zip(*np.nonzero(~ink)):
            w = grid.window(r, c)
            assert not np.any(np.all((q >= w[0]) & (q <= w[1]), axis=1))
        # the form writes the label's first line at the moved place (points, piece frame); a label that would
        # read upside down on the page is turned by 180 degrees about the centre of its own box
        if flips[i]:
            cm = re.search(rb"-1 0 0 -1 (-?[\d.]+) (-?[\d.]+) cm", forms[i])
            centre = (box[0] + box[2]) / 2 * 1000 * MM
            assert float(cm.group(1)) == pytest.approx(centre[0], abs=0.01)
            assert float(cm.group(2)) == pytest.approx(centre[1], abs=0.01)
        else:
            xy = re.search(rb"1 0 0 1 (-?[\d.]+) (-?[\d.]+) Tm", forms[i])
            assert float(xy.group(1)) == pytest.approx(at[0] * 1000 * MM, abs=0.01)
        # upright on the page: the label's reading direction turned by at most 90 degrees
        d = pdf._turn(lay, i) @ np.array([1.0, 0.0]) * (-1.0 if flips[i] else 1.0)
        assert d[0] > 1e-9 or (abs(d[0]) <= 1e-9 and d[1] > 0)
        g = lay.place(i, p.grain + tiling.grain_shift(lay, i))
        length = np.linalg.norm(g[1] - g[0])
        s = g[0] + np.linspace(0.0, 1.0, 401)[:, None] * (g[1] - g[0])
        on = np.zeros(len(s), bool)
        for r, c in zip(*np.nonzero(ink)):
            w = grid.window(r, c)
            on |= np.all((s >= w[0]) & (s <= w[1]), axis=1)
        assert on.mean() * length >= min(print_labels.GRAIN_SHOWN, length) - 0.002
    assert moved  # the tube's labels sit in the middle of its pieces, on pages left out


def test_tilted_piece_is_drawn_turned_not_scaled(made):
    """A piece tilted by a few degrees is placed by that rotation on every page (cos, sin in the matrix)."""
    from core.export import tiling

    pat, pieces, _ = made
    lay = pdf.print_sheet(pieces, "a4")
    angles = np.array(lay.angles, float)
    angles[0] += 5.0
    tilted = tiling.PrintLayout(offsets=lay.offsets, size=lay.size, reserved=lay.reserved, angles=angles)
    R = tiling.rotation(angles[0])
    assert R @ R.T == pytest.approx(np.eye(2)) and np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_array_equal(tiling.rotation(270.0), [[0, 1], [-1, 0]])
    found = 0
    for _, c in pages(parse_pdf(pdf.tiled_pdf(pieces, tilted, "a4", pat.style))):
        for a, b, cc, d in re.findall(
            rb"(-?[\d.]+) (-?[\d.]+) (-?[\d.]+) (-?[\d.]+) -?[\d.]+ -?[\d.]+ cm\s*/FormXob"
            rb"\.piece0 Do",
            c,
        ):
            np.testing.assert_allclose([[float(a), float(cc)], [float(b), float(d)]], R, atol=1e-5)
            found += 1
    assert found


def test_tiled_pdf_is_deterministic(made):
    pat, pieces, _ = made
    a = pdf.tiled_pdf(pieces, pdf.print_sheet(pieces, "a4"), "a4", pat.style)
    assert a == pdf.tiled_pdf(pieces, pdf.print_sheet(pieces, "a4"), "a4", pat.style)


@pytest.mark.parametrize("paper", ["a4", "letter"])
def test_join_marks_name_printed_neighbours(printed_pages, paper):
    lay, grid, ink, printed = printed_pages[paper]
    for (r, c), (_, content) in printed:
        joins = set(re.findall(rb"\(join (\w+)\) Tj", content))
        want = {
            pdf.page_name(rr, cc).encode()
            for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1))
            if 0 <= rr < grid.rows and 0 <= cc < grid.cols and ink[rr, cc]
        }
        assert joins == want


def test_wide_piece_tiles(made):
    """A piece wider than any page grid tried before (1.6 m) still tiles, on as many columns as it needs."""
    from export_synth import wide_pattern

    pieces = build_pieces(wide_pattern(1.6))
    for paper in ("a4", "letter"):
        lay = pdf.print_sheet(pieces, paper)
        grid, ink = pdf.sheet_pages(pieces, lay, paper)
        q = lay.place(0, pieces[0].cut[0])
        assert np.ptp(q[:, 0]) >= 0.5 and q.min() >= 0  # the 0.5 m side across at the least: turned, or tiled
        assert grid.cols * grid.step[0] + grid.overlap >= q[:, 0].max()
        data = pdf.tiled_pdf(pieces, lay, paper, "wide")
        assert len(pages(parse_pdf(data))) == int(ink.sum())


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


def _forms(data: bytes):
    """The content streams of a PDF's form XObjects (one per piece drawn), in piece order."""
    objs = parse_pdf(data)
    return [objs[k][1] for k in sorted(objs) if b"/Subtype /Form" in objs[k][0]]


def _export(pat, out, **kw):
    import json

    from core.export import export_pattern

    export_pattern(pat, out, formats="svg,dxf,pdf", **kw)
    return json.loads((out / "export.json").read_text())


def test_mirrored_pair_prints_once_labelled_cut_2(tmp_path):
    """A declared pair whose sides are mirror images is one piece on the tiled PDFs, labelled to cut 2 (1 + 1
    mirrored) naming both; the SVG, DXF and plotter sheet keep both pieces, each cut once."""
    from export_synth import mirrored_pattern

    s = _export(mirrored_pattern(), tmp_path / "o")
    for paper in ("a4", "letter"):
        assert s["pdf"][paper]["pieces"] == [
            {
                "piece": "front_left",
                "quantity": 2,
                "cut": "1 as printed + 1 mirrored",
                "pieces": ["front_left", "front_right"],
            }
        ]
        forms = _forms((tmp_path / "o" / f"pattern_{paper}.pdf").read_bytes())
        assert len(forms) == 1
        assert b"(cut 2: front_left) Tj" in forms[0] and b"(+ mirrored \\(front_right\\)) Tj" in forms[0]
    assert len(_forms((tmp_path / "o" / "pattern_plotter.pdf").read_bytes())) == 2
    assert [(p["name"], p["quantity"]) for p in s["pieces"]] == [("front_left", 1), ("front_right", 1)]
    assert s["pdf"]["plotter_pieces"] == [
        {"piece": "front_left", "quantity": 1},
        {"piece": "front_right", "quantity": 1},
    ]
    svg = (tmp_path / "o" / "pattern.svg").read_text()
    assert svg.count('data-quantity="1"') == 2 and "front_right" in svg
    # print_all: both pieces on the tiled pages, as built
    s = _export(mirrored_pattern(), tmp_path / "all", print_all=True)
    assert [p["piece"] for p in s["pdf"]["a4"]["pieces"]] == ["front_left", "front_right"]
    forms = _forms((tmp_path / "all" / "pattern_a4.pdf").read_bytes())
    assert len(forms) == 2 and not any(b"cut 2" in f for f in forms)


def test_pair_that_is_not_a_mirror_prints_twice(tmp_path):
    """A right piece 4 mm wider on its outer side (ease painted on one side), or one that is a copy rather than
    a mirror image of the left, prints both pieces, each labelled as not the other's mirror."""
    from export_synth import mirrored_pattern

    from core.export.print_set import MIRROR_TOL, mirror_gap

    s = _export(mirrored_pattern(bulge=0.004), tmp_path / "o")
    plan = s["pdf"]["a4"]["pieces"]
    assert [(p["piece"], p["quantity"]) for p in plan] == [("front_left", 1), ("front_right", 1)]
    assert all(p["not_mirrored_mm"] > MIRROR_TOL * 1000 for p in plan)
    forms = _forms((tmp_path / "o" / "pattern_a4.pdf").read_bytes())
    assert len(forms) == 2
    assert b"(not the mirror of front_right" in forms[0] and b"(not the mirror of front_left" in forms[1]
    # the geometric test itself: an exact mirror is 0 apart; a translated copy of a lopsided piece is no mirror
    pieces = build_pieces(mirrored_pattern())
    assert mirror_gap(pieces[0], pieces[1]) < 1e-9
    copy = build_pieces(mirrored_pattern())[0]
    assert mirror_gap(pieces[0], copy) > 0.005
    # a gap just under the tolerance still collapses (0.3 mm bulge)
    pieces = build_pieces(mirrored_pattern(bulge=0.0003))
    assert 0 < mirror_gap(pieces[0], pieces[1]) <= MIRROR_TOL


def test_printing_pairs_once_saves_pages_without_empty_ones(tmp_path):
    """The tube with a mirrored pair beside it (a small teaser): fewer pages with the pair printed once, every
    printed page crossed by a line; the same input gives the same bytes."""
    from export_synth import mirrored_pattern

    from core.export.print_set import print_set

    pat = make_pattern()
    pair = mirrored_pattern()
    for p in pair.panels:
        p.vertex_ids = p.vertex_ids + 10_000
    pat.panels += pair.panels
    pat.seams += pair.seams
    pieces = build_pieces(pat)
    counts = {}
    for print_all in (False, True):
        printed, plan = print_set(pat, pieces, print_all=print_all)
        assert len(printed) == (4 if print_all else 3)
        lay = pdf.print_sheet(printed, "a4")
        grid, ink = pdf.sheet_pages(printed, lay, "a4")
        loops = [lay.place(i, l) for i, p in enumerate(printed) for l in list(p.cut) + list(p.sew)]
        for r, c in zip(*np.nonzero(ink)):
            assert (r, c) == (0, 0) or _segments_in(grid.window(r, c), loops)
        counts[print_all] = int(ink.sum())
    assert counts[False] < counts[True]
    a = _export(pat, tmp_path / "a")
    _export(pat, tmp_path / "b")
    assert a["pdf"]["a4"]["pages"] == counts[False]
    for name in ("pattern_a4.pdf", "pattern_letter.pdf"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_symmetric_piece_prints_as_a_half_on_the_fold(tmp_path):
    """The tube's front and back are symmetric about their centre lines: the tiled PDFs print their halves, cut
    line and sew line clipped at the axis, the fold line drawn there, notches of the kept side, grain line inside,
    labelled to cut on the fold; a front 5 mm wider on one side prints whole."""
    from core.export.print_set import print_set
    from core.geom.polygon import distance_to_polyline, points_in_polygon, signed_area

    pat = make_pattern()
    pieces = build_pieces(pat)
    printed, plan = print_set(pat, pieces)
    assert [e["cut"] for e in plan] == ["on fold (half printed)"] * 2
    for whole, half in zip(pieces, printed):
        cut, full = half.cut[0], whole.cut[0]
        x0 = half.fold[0][0, 0]
        assert np.allclose(half.fold[0][:, 0], x0) and np.all(cut[:, 0] >= x0 - 1e-12)
        # every point of the half's cut line is on the whole piece's cut line or on the fold line
        off = distance_to_polyline(cut, full)
        assert np.all((off < 1e-9) | (np.abs(cut[:, 0] - x0) < 1e-12))
        assert abs(signed_area(cut)) == pytest.approx(0.5 * abs(signed_area(full)), rel=2e-3)
        # the fold line spans the cut line's edge on the axis
        on = cut[np.abs(cut[:, 0] - x0) < 1e-12, 1]
        assert half.fold[0][:, 1].tolist() == pytest.approx([on.min(), on.max()])
        assert len(half.notches) == sum(n.point[0] >= x0 - 5e-4 for n in whole.notches) < len(whole.notches)
        assert points_in_polygon(half.grain, half.sew[0]).all() and np.ptp(half.grain[:, 0]) == 0
        assert half.label[3:5] == [f"cut 1 on fold: {whole.name}", "(half printed: fold line on the fabric fold)"]
        assert len(half.edge_allowance[0]) == len(half.sew[0]) and 0.0 in half.edge_allowance[0]
    # the label placed inside the half
    from core.export import tiling

    for half in printed:
        assert points_in_polygon(tiling.label_box(half, half.label_at), half.sew[0]).all()
    # one side of the front pushed out by 5 mm: not symmetric, printed whole; the back still folds
    pat.panels[0].uv = pat.panels[0].uv * np.where(pat.panels[0].uv[:, :1] > 0, [1.02, 1.0], [1.0, 1.0])
    printed, plan = print_set(pat, build_pieces(pat))
    assert [e["cut"] for e in plan] == ["as printed", "on fold (half printed)"]
    assert not printed[0].fold and printed[0].label == build_pieces(pat)[0].label
    # print_all and fold=False print the whole pieces
    assert [e["cut"] for e in print_set(make_pattern(), pieces, fold=False)[1]] == ["as printed"] * 2
    assert [e["cut"] for e in print_set(make_pattern(), pieces, print_all=True)[1]] == ["as printed"] * 2


def test_a_label_is_placed_whole_on_one_page(printed_pages):
    """A label lies whole on one printed page where it can (read there, not split across two): a box across
    the edge between two printed pages does not count as placed, one inside a page does."""
    from core.export import print_labels

    lay, grid, ink, _ = printed_pages["a4"]
    ink = np.ones_like(ink)
    (x0, y0), (x1, y1) = grid.window(0, 0)
    # boxes in sheet metres, taken back to piece 0's frame
    R, off = pdf._turn(lay, 0), lay.offsets[0]

    def local(box):
        return (np.asarray(box, float) - off) @ R  # the inverse of the piece's quarter turn and place

    inside = local([[x0 + 0.02, y1 - 0.05], [x0 + 0.08, y1 - 0.05], [x0 + 0.08, y1 - 0.02], [x0 + 0.02, y1 - 0.02]])
    across = local([[x1 - 0.03, y1 - 0.05], [x1 + 0.03, y1 - 0.05], [x1 + 0.03, y1 - 0.02], [x1 - 0.03, y1 - 0.02]])
    assert print_labels._label_on(inside, lay, 0, grid, ink)
    assert print_labels._label_on(across, lay, 0, grid, ink, whole=False)
    assert not print_labels._label_on(across, lay, 0, grid, ink)
