"""A simple landmark-based 6-panel long-sleeve shirt CutSpec on Anny (no tests here).

Keypoints that are not landmarks are found geometrically on the reference
body: the surface point closest to a point just outside the body in a given
direction (front/back centre, armhole midpoints, cuff ring around the arm).
"""

import numpy as np

from core.body.model import SurfacePoint
from core.body.surface import closest_surface_point
from core.design.spec import CutLine, CutSpec, GarmentSpec, PanelSpec


def surface_point(body, X, p):
    """SurfacePoint at the surface point of ``X`` closest to ``p`` (3,)."""
    return closest_surface_point(X, body.faces, p)


def ray_point(body, X, origin, direction):
    """SurfacePoint where the ray from ``origin`` (inside the body) along ``direction`` leaves it first."""
    import igl

    F = np.asarray(body.faces, dtype=np.int64)
    hit = igl.ray_mesh_intersect(np.asarray(origin, float), np.asarray(direction, float), X, F, first=True)
    if not hit:
        raise AssertionError(f"no surface hit from {origin} along {direction}")
    f, _, u, v = hit[0]
    b = np.clip(np.array([1 - u - v, u, v]), 0, None)
    return SurfacePoint(int(f), tuple(b / b.sum()))


def shirt_spec(body, X, joints=None, refine=0.01, garment="shirt"):
    """Long-sleeve shirt: front, back, and each sleeve front/back (6 panels)."""
    lm = body.landmarks
    F = np.asarray(body.faces)
    pos = {k: v.position(X, F) for k, v in lm.items()}
    g = garment

    def at(o, d):
        return ray_point(body, X, o, d)

    z_hem = pos["hip_left"][2]
    centre = np.array([0.0, 0.5 * (pos["waist_front"][1] + pos["waist_back"][1]), z_hem])
    hem_front = at(centre, [0, -1, 0])
    hem_back = at(centre, [0, 1, 0])
    lines = [
        CutLine(
            f"{g}.neck",
            [lm["neck_front"], lm["neck_left"], lm["neck_back"], lm["neck_right"]],
            closed=True,
            role="opening",
        ),
        CutLine(f"{g}.hem", [lm["hip_left"], hem_back, lm["hip_right"], hem_front], closed=True, role="opening"),
    ]
    panels = [PanelSpec(f"{g}.front", g, lm["navel"]), PanelSpec(f"{g}.back", g, lm["waist_back"])]
    jn = [n.lower() for n in body.joint_names]
    for side, S in (("left", "L"), ("right", "R")):
        sh, ap = pos[f"shoulder_{side}"], pos[f"armpit_{side}"]
        mid = 0.5 * (sh + ap)
        ah_front = at(mid, [0, -1, 0])
        ah_back = at(mid, [0, 1, 0])
        # the forearm axis from joints: elbow -> wrist (the A-pose arm is bent)
        js = joints[jn.index(f"upperarm01.{S.lower()}")]
        je = joints[jn.index(f"lowerarm01.{S.lower()}")]
        jw = joints[jn.index(f"wrist.{S.lower()}")]
        axis = (jw - je) / np.linalg.norm(jw - je)
        c = je + 0.75 * (jw - je)  # cuff a little above the wrist
        up = np.array([0.0, 0.0, 1.0])
        up = up - (up @ axis) * axis
        up /= np.linalg.norm(up)
        front = np.array([0.0, -1.0, 0.0])
        front = front - (front @ axis) * axis - (front @ up) * up
        front /= np.linalg.norm(front)
        cuff = [at(c, d) for d in (up, front, -up, -front)]
        armhole = [lm[f"shoulder_{side}"], ah_front, lm[f"armpit_{side}"], ah_back]
        lines += [
            CutLine(f"{g}.armhole_{side}", armhole, closed=True, role="seam"),
            CutLine(f"{g}.cuff_{side}", cuff, closed=True, role="opening"),
            CutLine(f"{g}.shoulder_{side}", [lm[f"neck_{side}"], lm[f"shoulder_{side}"]]),
            CutLine(f"{g}.side_{side}", [lm[f"armpit_{side}"], lm[f"waist_{side}"], lm[f"hip_{side}"]]),
            CutLine(f"{g}.sleeve_top_{side}", [lm[f"shoulder_{side}"], cuff[0]]),
            CutLine(f"{g}.sleeve_under_{side}", [lm[f"armpit_{side}"], cuff[2]]),
        ]
        m = js + 0.6 * (je - js)
        panels += [
            PanelSpec(f"{g}.sleeve_front_{side}", g, at(m, front), body_part="arm"),
            PanelSpec(f"{g}.sleeve_back_{side}", g, at(m, -front), body_part="arm"),
        ]
    return CutSpec(
        lines,
        panels,
        [GarmentSpec(g, "upper", pin_line=f"{g}.neck")],
        refine_edge_length=refine,
        body={"model": "anny", "shape": None, "pose": None},
    )
