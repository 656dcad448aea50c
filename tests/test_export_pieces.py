"""core.export.pieces, allowance, notches: cut lines, allowance widths, notches, grain, labels."""

import numpy as np
import pytest
from export_synth import make_pattern
from meshes import ring_grid_faces

from core.errors import ExportError
from core.export.allowance import cut_line, resolve_allowance
from core.export.notches import notch_positions
from core.export.pieces import build_pieces
from core.geom.polygon import distance_to_polyline, points_in_polygon, signed_area
from core.geom.polyline import point_at_length, polyline_length


def test_allowance_width_measured_on_every_edge():
    pat = make_pattern()
    pieces = build_pieces(pat, allowance={"default": 0.012, "hem": 0.025, "side_right": 0.015})
    for p in pieces:
        sew, cut, w = p.sew[0], p.cut[0], p.edge_allowance[0]
        mid = 0.5 * (sew + np.roll(sew, -1, axis=0))
        np.testing.assert_allclose(distance_to_polyline(mid, cut), w, atol=1e-9)
        # the cut line is nowhere nearer to the sew line than the smallest allowance
        assert distance_to_polyline(cut, sew).min() >= w.min() - 1e-9
        assert sorted(set(np.round(w, 6))) == [0.012, 0.015, 0.025]
        assert signed_area(cut) > signed_area(sew) > 0


def test_seam_and_hem_edges_get_their_widths():
    pat = make_pattern()
    p = build_pieces(pat, allowance={"side_left": 0.017})[0]
    loop = p.sew_ids[0]
    front = pat.panel("front")
    hem_edges = {frozenset(e) for e in zip(front.hems[0][:-1], front.hems[0][1:])}
    seam = pat.seams[0]
    seam_edges = {frozenset(e) for e in zip(seam.verts_a[:-1], seam.verts_a[1:])}
    for i in range(len(loop)):
        e = frozenset((loop[i], loop[(i + 1) % len(loop)]))
        want = 0.02 if e in hem_edges else 0.017 if e in seam_edges else 0.01
        assert p.edge_allowance[0][i] == pytest.approx(want)


def test_notches_match_on_both_sides_of_every_seam():
    pat = make_pattern()
    pieces = {p.name: p for p in build_pieces(pat)}
    for seam in pat.seams:
        na = [n for n in pieces[seam.panel_a].notches if n.seam == seam.name]
        nb = [n for n in pieces[seam.panel_b].notches if n.seam == seam.name]
        # ends + every 10 cm from either end + the middle (the stretch there is 20 cm) on a 60.2 cm seam
        assert len(na) == len(nb) == 7
        sa, sb = np.array([n.s for n in na]), np.array([n.s for n in nb])
        np.testing.assert_allclose(sa, sb, atol=1e-12)
        length = sa[-1]
        np.testing.assert_allclose(sa[1:-1], [0.1, 0.2, 0.5 * length, length - 0.2, length - 0.1])
        # each notch lies on its sew line at arc length s from the seam's first vertex
        for side, notches in (("a", na), ("b", nb)):
            piece = pieces[getattr(seam, f"panel_{side}")]
            ids = getattr(seam, f"verts_{side}")
            xy = pat.panel(piece.name).uv[ids] @ piece.rotation.T
            want, _, _ = point_at_length(xy, [n.s for n in notches])
            np.testing.assert_allclose([n.point for n in notches], want, atol=1e-12)
            for n in notches:  # the slit starts on the cut line and points inward
                assert distance_to_polyline(n.segment[:1], piece.cut[0])[0] < 1e-9
                assert np.dot(n.segment[1] - n.segment[0], n.normal) < 0


def test_notch_positions_rules():
    # every 10 cm from either end; the 12 cm left in the middle (<= 1.25 spacing) gets no notch
    sa, sb = notch_positions(0.32, 0.32, 0.1)
    np.testing.assert_allclose(sa, [0, 0.1, 0.22, 0.32])
    # 13 cm left in the middle: a notch halves it
    sa, _ = notch_positions(0.33, 0.33, 0.1)
    np.testing.assert_allclose(sa, [0, 0.1, 0.165, 0.23, 0.33])
    # 0.2 from both ends of a 0.45 seam would be 5 mm apart (< spacing / 4): one 0.1 from each end
    sa, _ = notch_positions(0.45, 0.45, 0.1)
    np.testing.assert_allclose(sa, [0, 0.1, 0.2, 0.25, 0.35, 0.45])
    # sides of different lengths: the first half matches from the start, the second from the end
    sa, sb = notch_positions(0.31, 0.312, 0.1)
    np.testing.assert_allclose(sa, [0, 0.1, 0.21, 0.31])
    np.testing.assert_allclose(sb, [0, 0.1, 0.212, 0.312])
    sa, sb = notch_positions(0.35, 0.352, 0.1)
    np.testing.assert_allclose(sa, [0, 0.1, 0.175, 0.25, 0.35])
    np.testing.assert_allclose(sb, [0, 0.1, 0.176, 0.252, 0.352])
    sa, _ = notch_positions(0.5, 0.5, 0.0)
    np.testing.assert_allclose(sa, [0, 0.5])
    np.testing.assert_allclose(notch_positions(0.02, 0.03, 0.1)[0], [0, 0.02])
    # gathered: the shorter side's notches every spacing from either end, the longer side's at the same fractions
    sa, sb = notch_positions(0.45, 0.30, 0.1, gathered=True)
    np.testing.assert_allclose(sb, [0, 0.1, 0.2, 0.3])
    np.testing.assert_allclose(sa, [0, 0.15, 0.3, 0.45])
    sa, sb = notch_positions(0.66, 0.44, 0.1, gathered=True)
    np.testing.assert_allclose(sb, [0, 0.1, 0.2, 0.24, 0.34, 0.44])
    np.testing.assert_allclose(sa, 1.5 * sb)


@pytest.mark.parametrize("gathered", [False, True])
def test_notch_positions_do_not_depend_on_the_seams_direction(gathered):
    """A seam measured from its other end (its mirror image, or the same seam listed the other way round) gets
    the same notches: the rule is symmetric by construction, whatever the lengths and spacing."""
    rng = np.random.default_rng(16)
    for _ in range(300):
        la, spacing = rng.uniform(0.0, 1.5), rng.choice([0.0, rng.uniform(0.005, 0.3)])
        lb = la * rng.uniform(0.6, 1.6) if gathered else la + rng.uniform(-0.01, 0.01)
        lb = max(lb, 0.0)
        sa, sb = notch_positions(la, lb, spacing, gathered)
        np.testing.assert_allclose(la - sa[::-1], sa, atol=1e-12)
        np.testing.assert_allclose(lb - sb[::-1], sb, atol=1e-12)
        # the sides swapped: each side keeps its notches
        ra, rb = notch_positions(lb, la, spacing, gathered)
        np.testing.assert_allclose(ra, sb, atol=1e-12)
        np.testing.assert_allclose(rb, sa, atol=1e-12)
        assert len(sa) == len(sb) >= 2 and np.all(np.diff(sa) >= 0)
        lmin = min(la, lb)
        if spacing > 0 and lmin > 0:
            ss = sa if la <= lb else sb
            # no stretch of the shorter side longer than 1.25 spacing nor, between interior notches or an end,
            # shorter than spacing / 4 (a seam shorter than that keeps only its ends)
            assert np.diff(ss).max() <= 1.25 * spacing + 1e-12 or len(ss) == 2 and lmin <= 1.25 * spacing
            assert len(ss) == 2 or np.diff(ss).min() >= 0.25 * spacing - 1e-12
            if not gathered:
                # matched from the nearer end: equal arc lengths on both sides, the middle at half of each
                half = len(sa) // 2
                np.testing.assert_allclose(sa[:half], sb[:half], atol=1e-12)
                np.testing.assert_allclose(la - sa[-half:], lb - sb[-half:], atol=1e-12)


def test_grain_rotation_keeps_lengths_and_points_up():
    pat = make_pattern(rotate_back_deg=37.0)
    back = build_pieces(pat)[1]
    np.testing.assert_allclose(back.rotation @ pat.panel("back").grain, [0, 1], atol=1e-12)
    loop = pat.panel("back").boundary[0]
    assert polyline_length(back.sew[0], True) == pytest.approx(polyline_length(pat.panel("back").uv[loop], True))
    g = back.grain
    assert abs(g[1, 0] - g[0, 0]) < 1e-12 and g[1, 1] > g[0, 1]
    assert len(back.arrows) == 2


def test_labels_carry_style_size_quantity_and_mirror():
    from export_synth import mirrored_pattern

    left, right = build_pieces(mirrored_pattern())
    assert left.label[0] == "mirror test" and "size: M" in left.label
    assert left.label[3] == "cut 1, mirrored by front_right" and right.label[3] == "cut 1, mirror of front_left"
    assert any("units: mm" in s for s in right.label)
    # a declared pair that is no mirror image (the tube's back is rotated and shaped apart from its front)
    pat = make_pattern()
    pat.panels[1].mirror_of = "front"
    front, back = build_pieces(pat)
    gap = back.mirror_gaps["front"]
    assert gap == front.mirror_gaps["back"] > 0.01
    assert front.label[3] == f"cut 1, not the mirror of back: {round(gap * 1000, 1):g} mm off"
    assert back.label[3] == f"cut 1, not the mirror of front: {round(gap * 1000, 1):g} mm off"


def test_fold_edge_gets_no_allowance_and_label():
    pat = make_pattern()
    front = pat.panel("front")
    front.fold = np.array([front.boundary[0][-1], front.boundary[0][0]])  # optional attribute
    p = build_pieces(pat)[0]
    assert p.fold and any("cut on fold" in s for s in p.label)
    assert np.isclose(p.edge_allowance[0][-1], 0.0)


def test_resolve_allowance_errors_and_materials():
    pat = make_pattern()
    assert resolve_allowance(0.015, pat)["default"] == 0.015
    pat.materials = {"export": {"allowance": {"hem": 0.03}}}
    assert resolve_allowance(None, pat)["hem"] == 0.03
    with pytest.raises(ExportError, match="nosuch"):
        resolve_allowance({"nosuch": 0.01}, pat)
    with pytest.raises(ExportError, match="hem"):
        resolve_allowance({"hem": -0.01}, pat)
    with pytest.raises(ExportError, match="default"):
        resolve_allowance({"default": float("nan")}, pat)


def test_build_pieces_is_deterministic():
    a = build_pieces(make_pattern())
    b = build_pieces(make_pattern())
    for p, q in zip(a, b):
        np.testing.assert_array_equal(p.cut[0], q.cut[0])
        assert p.label == q.label


def test_narrow_slit_is_refused_with_a_clear_error():
    corners = np.array(
        [[0, 0], [0.4, 0], [0.4, 0.1925], [0.2, 0.1925], [0.2, 0.2075], [0.4, 0.2075], [0.4, 0.4], [0, 0.4]]
    )
    pts = []
    for i in range(len(corners)):
        a, b = corners[i], corners[(i + 1) % len(corners)]
        n = max(2, int(np.linalg.norm(b - a) / 0.01))
        pts += [a + (b - a) * t for t in np.arange(n) / n]
    slit = np.array(pts)
    with pytest.raises(ExportError, match="lower the allowance"):
        cut_line(slit, np.full(len(slit), 0.01))
    cut = cut_line(slit, np.full(len(slit), 0.005))  # 1.5 cm slit, 2 x 5 mm allowance: fits
    assert points_in_polygon(slit[[0, 10, 40]], cut).all()


def test_piece_with_a_hole():
    # an annulus: outer radius 20 cm, hole of 8 cm (a neck opening cut into a cape)
    na, nr = 48, 5
    th = 2 * np.pi * np.arange(na) / na
    r = np.linspace(0.08, 0.2, nr)
    uv = np.array([[rr * np.cos(t), rr * np.sin(t)] for rr in r for t in th])
    faces = ring_grid_faces(nr, na)
    from core.pattern.types import Pattern, PatternPanel

    f = len(faces)
    panel = PatternPanel(
        "cape",
        "cape",
        uv,
        np.array(faces),
        np.arange(len(uv)),
        np.zeros((len(uv), 3)),
        np.array([0.0, 1.0]),
        np.ones(f),
        np.ones(f),
        np.ones(f),
        np.ones(f),
    )
    pat = Pattern("cape", {"size": "M"}, {"cape": "upper"}, [panel], [])
    piece = build_pieces(pat, allowance=0.01)[0]
    assert len(piece.sew) == 2 and len(piece.cut) == 2
    assert signed_area(piece.sew[0]) > 0 > signed_area(piece.sew[1])
    # the hole's cut line lies inside the hole, 1 cm in from its sew line
    d_hole = distance_to_polyline(0.5 * (piece.sew[1] + np.roll(piece.sew[1], -1, 0)), piece.cut[1])
    np.testing.assert_allclose(d_hole, 0.01, atol=1e-9)
    assert abs(signed_area(piece.cut[1])) < abs(signed_area(piece.sew[1]))
    assert abs(signed_area(piece.cut[0])) > abs(signed_area(piece.sew[0]))


def test_duplicate_boundary_vertex_on_a_seam_still_gets_notches():
    pat = make_pattern()
    front = pat.panel("front")
    seam = pat.seams[1]  # side_right runs up the front's right side
    front.uv[seam.verts_a[3]] = front.uv[seam.verts_a[2]]  # a zero-length seam edge
    p = build_pieces(pat)[0]
    notches = [n for n in p.notches if n.seam == seam.name]
    assert len(notches) == 7
    assert all(np.isfinite(n.segment).all() and abs(np.linalg.norm(n.normal) - 1) < 1e-9 for n in notches)


def test_label_stays_inside_narrow_pieces():
    from export_synth import _panel, grid_piece

    from core.export.pieces import CHAR_WIDTH
    from core.pattern.types import Pattern

    panels = []
    for k, w in enumerate((0.5, 0.12, 0.07)):
        uv, faces, loop, _ = grid_piece(5, 9, lambda s, t, w=w: ((s - 0.5) * w, t * 0.6))
        panels.append(_panel(f"strip{k}", uv, faces, loop, [0.0, 1.0]))
    pat = Pattern("strips", {"size": "M"}, {"shirt": "upper"}, panels, [])
    for p in build_pieces(pat):
        h = p.text_height
        tw, th = max(len(s) for s in p.label) * CHAR_WIDTH * h, len(p.label) * 1.5 * h
        x, y = p.label_at
        box = np.array([[x + a * tw, y - b * th] for a in np.linspace(0, 1, 5) for b in np.linspace(0, 1, 5)])
        assert points_in_polygon(box, p.sew[0]).all(), p.name
        assert 0.0025 <= h <= 0.008


def test_self_seam_closing_a_tube():
    from export_synth import _panel, grid_piece

    from core.pattern.types import Pattern, PatternSeam

    uv, faces, loop, sides = grid_piece(9, 7, lambda s, t: (s * 0.8, t * 0.45))
    panel = _panel("tube", uv, faces, loop, [0.0, 1.0], hems=[sides["bottom"]])
    seam = PatternSeam("back_seam", "tube", "tube", sides["left"][::-1], sides["right"])
    pat = Pattern("tube", {"size": "M"}, {"tube": "lower"}, [panel], [seam])
    p = build_pieces(pat, allowance={"back_seam": 0.015})[0]
    a = [n for n in p.notches if n.side == "a"]
    b = [n for n in p.notches if n.side == "b"]
    assert len(a) == len(b) == 6  # 0, 10, 20, 25, 35, 45 cm: every 10 cm from either end
    np.testing.assert_allclose([n.s for n in a], [n.s for n in b])
    np.testing.assert_allclose([n.point[1] for n in a], [n.point[1] for n in b])  # same heights
    assert all(n.normal[0] < 0 for n in a) and all(n.normal[0] > 0 for n in b)  # each points off its edge
    widths = sorted(set(np.round(p.edge_allowance[0], 6)))
    assert widths == [0.01, 0.015, 0.02]
