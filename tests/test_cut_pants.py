"""Four-panel pants on Anny: four cut lines meet at the crotch keypoint (no skirt topology)."""

import numpy as np
from cut_anny_shirt import ray_point

from core.cut.engine import cut_surface
from core.design.spec import CutLine, CutSpec, GarmentSpec, PanelSpec
from core.geom.polyline import polyline_length


def pants_spec(body, X, J):
    lm = body.landmarks
    jn = body.joint_names
    lines = [
        CutLine(
            "pants.waist",
            [lm["waist_front"], lm["waist_left"], lm["waist_back"], lm["waist_right"]],
            closed=True,
            role="opening",
        ),
        CutLine("pants.center_front", [lm["waist_front"], lm["crotch"]]),
        CutLine("pants.center_back", [lm["waist_back"], lm["crotch"]]),
    ]
    panels = []
    for side, S, out in (("left", "L", 1.0), ("right", "R", -1.0)):
        knee, ankle = J[jn.index(f"lowerleg01.{S}")], J[jn.index(f"foot.{S}")]
        c = knee + 0.6 * (ankle - knee)  # hem at mid-shin
        o, f, i, b = (ray_point(body, X, c, d) for d in ([out, 0, 0], [0, -1, 0], [-out, 0, 0], [0, 1, 0]))
        lines += [
            CutLine(f"pants.hem_{side}", [o, f, i, b], closed=True, role="opening"),
            CutLine(f"pants.outseam_{side}", [lm[f"waist_{side}"], o]),
            CutLine(f"pants.inseam_{side}", [lm["crotch"], i]),
        ]
        thigh = J[jn.index(f"upperleg01.{S}")] + 0.4 * (knee - J[jn.index(f"upperleg01.{S}")])
        panels += [
            PanelSpec(f"pants.front_{side}", "pants", ray_point(body, X, thigh, [0, -1, 0]), body_part="leg"),
            PanelSpec(f"pants.back_{side}", "pants", ray_point(body, X, thigh, [0, 1, 0]), body_part="leg"),
        ]
    return CutSpec(lines, panels, [GarmentSpec("pants", "lower", pin_line="pants.waist")], refine_edge_length=0.01)


def test_pants(anny, anny_reference):
    body, (X, J) = anny, anny_reference
    cut = cut_surface(body, X, pants_spec(body, X, J))
    G = cut.positions(X)
    assert len(cut.panels) == 4
    for p in cut.panels:
        assert len(p.boundary) == 1, p.name
    pairs = {(s.name.split("#")[0], frozenset((s.panel_a, s.panel_b))) for s in cut.seams}
    assert ("pants.center_front", frozenset(("pants.front_left", "pants.front_right"))) in pairs
    assert ("pants.center_back", frozenset(("pants.back_left", "pants.back_right"))) in pairs
    assert ("pants.inseam_left", frozenset(("pants.front_left", "pants.back_left"))) in pairs
    assert ("pants.outseam_right", frozenset(("pants.front_right", "pants.back_right"))) in pairs
    for s in cut.seams:
        a, b = cut.panel(s.panel_a), cut.panel(s.panel_b)
        np.testing.assert_array_equal(a.vertex_ids[s.verts_a], b.vertex_ids[s.verts_b])
    # the four panels meet at the crotch vertex
    crotch = body.landmarks["crotch"].position(X, body.faces)
    for p in cut.panels:
        assert np.linalg.norm(G[p.vertex_ids] - crotch, axis=1).min() < 1e-9
    # grain along the leg
    for p in cut.panels:
        assert np.median(p.warp_dir[:, 2]) > 0.9
    # left/right mirror: same seam lengths
    L = {s.name: polyline_length(cut.panel_positions(cut.panel(s.panel_a), X)[s.verts_a]) for s in cut.seams}
    np.testing.assert_allclose(L["pants.inseam_left"], L["pants.inseam_right"], rtol=0.02)
