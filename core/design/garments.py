"""The garment templates' builders: each returns a design dict (the JSON format) that
:mod:`.templates` registers and ships. Templates are made of landmarks, traced lengths and
rings only, so they hold on any body model with the standard landmarks.

Construction (all mirrored left -> right):

- tops: neckline loop through the four neck landmarks (opening); hem ring
  (opening) a traced length below the front waist; armhole rings (seams) a
  little down the arm from the armpit, across the upper arm and over the
  shoulder tip (the plane follows the arm, so the A, T and P1 reference poses
  cut; the front/back halves are named by ring fractions, not axes); shoulder
  seams neck -> armhole top; side seams armhole bottom -> hem side; sleeves end in
  cuff rings (openings) a traced sleeve length from the armhole top, split
  front/back by a seam on top and one underneath. Pinned at the neckline.
- pants/shorts: waist ring (opening, pinned); centre front and centre back
  seams waist -> crotch along the midline (plane sections, from the waist ring's
  front and back midpoints, so they meet the ring on every size); side seams waist side -> leg hem; inseams crotch ->
  leg hem; leg hem rings (openings) across the leg at a traced length.
- skirt/dress: the skirt topology (``"skirt": true``): the hem is a loop of
  points on both legs, joined across the bridged inter-leg surface.
"""

from __future__ import annotations

import copy

from .materials import EPS_WEFT


def _design(name, description, garments, parameters, keypoints, lines=None, skirt=False, fabric="cotton"):
    d = {
        "format": "ease-design",
        "version": 1,
        "name": name,
        "description": description,
        "body": {"model": "anny", "shape": "M", "pose": "A"},
        "materials": {"fabric": fabric, "eps_weft": EPS_WEFT, "eps_warp": EPS_WEFT},
        "mirror": True,
        "skirt": skirt,
        "refine_edge_length": 0.01,
        "parameters": parameters,
        "keypoints": keypoints,
    }
    if lines:
        d["lines"] = lines
    d["garments"] = garments
    return d


# ---------------------------------------------------------------- upper body parts


def _top_parts(sleeves: str = "long", hem: str = "hem", ease=None):
    """Parameters, keypoints, lines and panels of a top.

    sleeves : "long" | "short" | "none"; hem : name of the hem line (the
    teaser shares the waist line instead).
    """
    ease = ease or {}
    params = {
        "armhole_drop": {"value": 0.01, "kind": "length", "min": 0.005, "max": 0.05},
        "neck_drop_front": {"value": 0.03, "kind": "length", "min": 0.015, "max": 0.15},
        "neck_drop": {"value": 0.015, "kind": "length", "min": 0.01, "max": 0.06},
        # the neckline's side point: a placement from the neck towards the shoulder tip
        "neck_width": {"value": 0.15, "kind": "placement", "min": 0.05, "max": 0.6},
    }
    kps = {
        "armhole_under_left": {"trace": {"from": "armpit_left", "along": "arm_left", "length": "$armhole_drop"}},
        # the neckline sits below the neck landmarks (the head region starts there)
        "neckline_front": {"trace": {"from": "neck_front", "along": "torso_down", "length": "$neck_drop_front"}},
        "neckline_back": {"trace": {"from": "neck_back", "along": "torso_down", "length": "$neck_drop"}},
        # a point just below the elbow: the shoulder tip -> here is the upper arm's direction
        # (the elbow landmark lies on the back of the elbow; this one lies on the arm's axis
        # seen from above, so in the A-pose the armhole plane stays the sagittal one)
        "arm_axis_left": {"between": ["elbow_left", "wrist_left"], "t": 0.15},
        # the armhole's top: the shoulder tip (a vertex of the armhole ring, in every pose)
        "armhole_top_left": "shoulder_left",
        "neckline_side_left": {"between": ["neck_left", "shoulder_left"], "t": "$neck_width"},
        "chest_front": {"between": ["neck_front", "waist_front"], "t": 0.45},
        "chest_back": {"between": ["neck_back", "waist_back"], "t": 0.45},
    }
    lines = [
        {
            "name": "neckline",
            "points": ["neckline_front", "neckline_side_left", "neckline_back", "neckline_side_right"],
            "closed": True,
            "role": "opening",
        },
        # a set-in armhole: the section just outside the armpit, over the shoulder tip and
        # across the upper arm - the plane through both, turned least from the arm's axis.
        # It follows the arm in every reference pose (in the A-pose it is the sagittal
        # plane, normal x; a fixed x would slice a raised or forward arm lengthwise).
        {
            "name": "armhole_left",
            "ring": {
                "through": "armhole_under_left",
                "normal": ["shoulder_left", "arm_axis_left"],
                # front/back: fractions of the ring from the armpit
                # (in the A-pose its front- and backmost points)
                "contains": "armhole_top_left",
                "points": 12,
                "named": {"armhole_front_left": 0.81, "armhole_back_left": 0.29},
            },
            "role": "seam" if sleeves != "none" else "opening",
        },
        {"name": "shoulder_left", "points": ["neckline_side_left", "armhole_top_left"], "role": "seam"},
        {"name": "side_left", "points": ["armhole_under_left", "hem_side_left"], "role": "seam"},
    ]
    panels = [
        {"name": "front", "seed": "chest_front", "body_part": "torso", "ease": ease.get("front", {"value": 1.2})},
        {"name": "back", "seed": "chest_back", "body_part": "torso", "ease": ease.get("back", {"value": 1.2})},
    ]
    if sleeves != "none":
        # The declared ranges are the lengths that cut and flatten on the template's body
        # (tests/test_template_ranges.py sweeps them), with about 2 cm to spare for other sizes:
        if sleeves == "long":
            # A long sleeve ends by the wrist on every body: its cuff is placed at a share of the
            # way (along the arm) from the armhole's top to the wrist, 0.89 (0.52 m on the default
            # M, whose wrist is 0.583 m away; women's wrists are 0.508-0.517 m away, men's
            # 0.536-0.609). Its seams pass the elbow guide ring, so the cuff must lie past the
            # elbow: up to 0.35 m (0.6 of the way) the cuff ring crosses the sleeve seams.
            params["sleeve_end"] = {"value": 0.89, "kind": "placement", "min": 0.65, "max": 0.97}
            kps["cuff_level_left"] = {"between": ["armhole_top_left", "wrist_left"], "t": "$sleeve_end"}
            normal = ["elbow_left", "wrist_left"]
        else:
            # the cuff must lie below the armhole's underside (1 cm down the arm from the
            # armpit): up to 0.11 m (0.13 on XL) the cuff ring crosses the armhole ring; a short
            # sleeve's length is the same on every body (a traced length)
            params["sleeve_length"] = {"value": 0.2, "kind": "length", "min": 0.15, "max": 0.3}
            kps["cuff_level_left"] = {
                "trace": {"from": "armhole_top_left", "along": "arm_left", "length": "$sleeve_length"}
            }
            normal = ["shoulder_left", "elbow_left"]
        kps["sleeve_front_mid_left"] = {"between": ["armhole_front_left", "cuff_front_left"], "t": 0.5}
        kps["sleeve_back_mid_left"] = {"between": ["armhole_back_left", "cuff_back_left"], "t": 0.5}
        lines += [
            {
                "name": "cuff_left",
                "ring": {
                    "through": "cuff_level_left",
                    "normal": normal,
                    "points": 12,
                    "named": {
                        "cuff_top_left": "+z",
                        "cuff_under_left": "-z",
                        "cuff_front_left": "-y",
                        "cuff_back_left": "+y",
                    },
                },
                "role": "opening",
            },
            {"name": "sleeve_top_left", "points": ["armhole_top_left", "cuff_top_left"], "role": "seam"},
            {"name": "sleeve_under_left", "points": ["armhole_under_left", "cuff_under_left"], "role": "seam"},
        ]
        if sleeves == "long":
            # the forearm turns forward: the sleeve seams pass the elbow on its top and underside
            lines += [
                {
                    "name": "elbow_guide_left",
                    "ring": {
                        "through": "elbow_left",
                        "normal": ["shoulder_left", "elbow_left"],
                        "points": 8,
                        "named": {"elbow_top_left": "+z", "elbow_under_left": "-z"},
                    },
                    "role": "guide",
                }
            ]
            lines[-3]["points"] = ["armhole_top_left", "elbow_top_left", "cuff_top_left"]
            lines[-2]["points"] = ["armhole_under_left", "elbow_under_left", "cuff_under_left"]
        panels += [
            {
                "name": "sleeve_front_left",
                "seed": "sleeve_front_mid_left",
                "body_part": "arm",
                "ease": ease.get("sleeve_front_left", {"value": 1.2}),
            },
            {
                "name": "sleeve_back_left",
                "seed": "sleeve_back_mid_left",
                "body_part": "arm",
                "ease": ease.get("sleeve_back_left", {"value": 1.2}),
            },
        ]
    return params, kps, lines, panels


def _hem_ring(through="hem_front"):
    return {
        "name": "hem",
        "ring": {
            "through": through,
            "normal": "z",
            "points": 16,
            "named": {"hem_side_left": "+x", "hem_side_right": "-x"},
        },
        "role": "opening",
    }


def _top(name, description, sleeves, hem_length=0.10, ease=None):
    params, kps, lines, panels = _top_parts(sleeves, ease=ease)
    # a traced length is > 0 (the format refuses 0): the hem is at least 5 mm below the waist
    params["hem_length"] = {"value": hem_length, "kind": "length", "min": 0.005, "max": 0.2}
    kps["hem_front"] = {"trace": {"from": "waist_front", "along": "torso_down", "length": "$hem_length"}}
    lines.insert(1, _hem_ring())
    garment = {
        "name": "shirt" if sleeves == "long" else "top",
        "kind": "upper",
        "pin": "neckline",
        "lines": lines,
        "panels": panels,
    }
    return _design(name, description, [garment], params, kps)


def shirt_long_sleeve():
    return _top("long-sleeve shirt", "Front, back, and each sleeve split front/back (6 panels); ease 1.2.", "long")


def top_short_sleeve():
    return _top("short-sleeve top", "Front, back and short sleeves split front/back; ease 1.2.", "short")


def top_sleeveless():
    return _top("sleeveless top", "Front and back; the armholes are openings; ease 1.2.", "none")


def jacket():
    d = _top(
        "jacket",
        "The long-sleeve shirt with one extra cut down the front centre: "
        "front_left / front_right open at the front; ease 1.3.",
        "long",
        ease={k: {"value": 1.3} for k in ("front", "back", "sleeve_front_left", "sleeve_back_left")},
    )
    g = d["garments"][0]
    g["name"] = "jacket"
    g["lines"].append(
        {
            "name": "center_front",
            "section": {"from": "neckline_front", "to": "hem_front", "normal": "x"},
            "role": "opening",
        }
    )
    front = next(p for p in g["panels"] if p["name"] == "front")
    front["name"] = "front_left"
    front["seed"] = "bust_left"
    return d


# ---------------------------------------------------------------- lower body


def _pants_parts(length_value, length_range, ease=None, name="pants", to_ankle=False):
    """``to_ankle``: the leg's length is a share of the way (along the leg) from the waist's side
    to the ankle (``leg_end``), so full-length legs end by the ankle on every body; else a
    length in metres from the waist's side (``leg_length``), the same on every body."""
    ease = ease or {}
    kind, key = ("placement", "leg_end") if to_ankle else ("length", "leg_length")
    params = {key: {"value": length_value, "kind": kind, "min": length_range[0], "max": length_range[1]}}
    hem = (
        {"between": ["waist_side_left", "ankle_left"], "t": "$leg_end"}
        if to_ankle
        else {"trace": {"from": "waist_side_left", "along": "leg_left", "length": "$leg_length"}}
    )
    kps = {
        "leg_hem_out_left": hem,
        "thigh_front_left": {"between": ["waist_front", "leg_hem_front_left"], "t": 0.45},
        "thigh_back_left": {"between": ["waist_back", "leg_hem_back_left"], "t": 0.45},
    }
    lines = [
        # centre seams follow the midline (a geodesic there is not unique in the concave crotch)
        {"name": "center_front", "section": {"from": "waist_front", "to": "crotch", "normal": "x"}, "role": "seam"},
        # ... from the waist ring's back midpoint (half way round from waist_front), not the
        # waist_back landmark: on other sizes that landmark is a little off the ring's height
        {"name": "center_back", "section": {"from": "waist_back_mid", "to": "crotch", "normal": "x"}, "role": "seam"},
        {"name": "side_left", "points": ["waist_side_left", "leg_hem_out_left"], "role": "seam"},
        {
            "name": "leg_hem_left",
            "ring": {
                "through": "leg_hem_out_left",
                "normal": "z",
                "points": 12,
                "named": {"leg_hem_in_left": "-x", "leg_hem_front_left": "-y", "leg_hem_back_left": "+y"},
            },
            "role": "opening",
        },
        {"name": "inseam_left", "points": ["crotch", "leg_hem_in_left"], "role": "seam"},
    ]
    panels = [
        {
            "name": "front_left",
            "seed": "thigh_front_left",
            "body_part": "leg",
            "ease": ease.get("front_left", {"value": 1.2}),
        },
        {
            "name": "back_left",
            "seed": "thigh_back_left",
            "body_part": "leg",
            "ease": ease.get("back_left", {"value": 1.2}),
        },
    ]
    return params, kps, lines, panels


def _waist_ring(name="waist", role="opening"):
    return {
        "name": name,
        "ring": {
            "through": "waist_front",
            "normal": "z",
            "points": 16,
            "named": {"waist_side_left": "+x", "waist_side_right": "-x", "waist_back_mid": 0.5},
        },
        "role": role,
    }


def _lower(name, description, length_value, length_range, garment_name, to_ankle=False):
    params, kps, lines, panels = _pants_parts(length_value, length_range, to_ankle=to_ankle)
    lines.insert(0, _waist_ring())
    g = {"name": garment_name, "kind": "lower", "pin": "waist", "lines": lines, "panels": panels}
    return _design(name, description, [g], params, kps)


def pants():
    # the hem at 0.9 of the way from the waist's side to the ankle (0.98 m on the default M, whose
    # ankle is 1.083 m away; women's ankles are 0.947-0.988 m away, men's 0.963-1.058)
    return _lower("pants", "Four panels (front/back, left/right); ease 1.2.", 0.9, (0.46, 0.97), "pants", to_ankle=True)


def shorts():
    # the leg hem ring must lie below the crotch: up to 0.27 m down the side (0.26 on XS and
    # XL) it runs round the buttocks and crosses the centre back seam
    return _lower(
        "shorts", "Four panels (front/back, left/right), legs ending mid-thigh; ease 1.2.", 0.42, (0.3, 0.6), "shorts"
    )


def teaser_shirt_pants():
    """The paper's teaser: a shirt and pants, each panel with its own ease."""
    shirt_ease = {
        "front": {"value": 1.15},
        "back": {"value": 1.3},
        "sleeve_front_left": {"value": 1.45},
        "sleeve_back_left": {"value": 1.6},
    }
    params, kps, lines, panels = _top_parts("long", ease=shirt_ease)
    # The shirt ends at the waist, where the pants begin: one shared line.
    for l in lines:
        if l["name"] == "side_left":
            l["points"] = ["armhole_under_left", "waist_side_left"]
    shirt = {"name": "shirt", "kind": "upper", "pin": "neckline", "lines": lines, "panels": panels}
    pparams, pkps, plines, ppanels = _pants_parts(
        0.9, (0.46, 0.97), ease={"front_left": {"value": 1.1}, "back_left": {"value": 1.25}}, to_ankle=True
    )
    params.update(pparams)
    kps.update(pkps)
    pants_g = {"name": "pants", "kind": "lower", "pin": "waist", "lines": plines, "panels": ppanels}
    return _design(
        "teaser shirt + pants",
        "The paper's teaser: long-sleeve shirt and pants sharing the waist line, a different uniform ease per panel.",
        [shirt, pants_g],
        params,
        kps,
        lines=[_waist_ring()],
    )


# ---------------------------------------------------------------- skirt topology

# The skirt length's minimum: the hem's thigh rings must lie below the crotch, one round each
# leg; up to 0.27 m down the side (0.26 on XS and XL) one ring runs round both legs and the
# hem's front points on the two legs coincide.
SKIRT_LENGTH_MIN = 0.3


def _skirt_hem_parts(length_value, length_range):
    params = {"skirt_length": {"value": length_value, "kind": "length", "min": length_range[0], "max": length_range[1]}}
    kps = {
        "hem_out_left": {"trace": {"from": "waist_side_left", "along": "leg_left", "length": "$skirt_length"}},
    }
    lines = [
        {
            "name": "thigh_left",
            "ring": {
                "through": "hem_out_left",
                "normal": "z",
                "points": 8,
                "named": {
                    "hem_front_left": "-y",
                    "hem_back_left": "+y",
                },
            },
            "role": "guide",
        },
    ]
    return params, kps, lines


def _skirt_lines(top_point_front="waist_front"):
    """Side seams and the hem loop across both legs (on the skirt topology)."""
    hem = {
        "name": "hem",
        "points": [
            "hem_out_left",
            "hem_front_left",
            "hem_front_right",
            "hem_out_right",
            "hem_back_right",
            "hem_back_left",
        ],
        "closed": True,
        "role": "opening",
    }
    side = {"name": "side_left", "points": ["waist_side_left", "hem_out_left"], "role": "seam"}
    return [hem, side]


#: the skirt's back waist darts: the mouth this fraction of the way along the waist from the centre back
#: to the side, sewn to the seat point (``seat_left``; apex offset 0)
SKIRT_BACK_DART_PLACE = 0.4


def _skirt_back_darts(kps):
    """The skirt's back waist darts (``*_right`` mirrored), their mouth keypoint added to ``kps``.

    Without them the back is the skirt's compliance miss: a flat piece cannot follow the seat's
    dome from the waist, so the solve leaves the waist loose (+3.8 % weft) and the seat tight
    (-5.7 %), 2.23 % mean on M against the front's 1.10 %. A dart from the waist to the seat point
    takes that curvature, as a pattern maker's back darts do: the closed skirt reads 0.84-1.17 %
    from XS to XL (1.20-1.84 % without), darts of about 80 mm at the waist (``"auto"``: as wide as
    the flattening opens them). Ended 20 mm short of the seat point the XL read 1.24 %; mouths at
    0.3 / 0.35 of the way 1.20 / 1.18 % (0.4: 1.17); two darts a side (0.3 and 0.6) 1.21 %."""
    kps["back_dart_top_left"] = {"between": ["waist_back_mid", "waist_side_left"], "t": SKIRT_BACK_DART_PLACE}
    return [
        {
            "name": "back_dart_left",
            "line": "waist",
            "apex": "seat_left",
            "at": "back_dart_top_left",
            "intake": "auto",
            "apex_offset": 0.0,
        }
    ]


def skirt():
    params, kps, guides = _skirt_hem_parts(0.45, (SKIRT_LENGTH_MIN, 0.7))
    kps["skirt_front_mid"] = {"between": ["waist_front", "crotch"], "t": 0.5}
    kps["skirt_back_mid"] = {"between": ["waist_back", "crotch"], "t": 0.5}
    lines = [_waist_ring()] + _skirt_lines() + guides
    g = {
        "name": "skirt",
        "kind": "lower",
        "pin": "waist",
        "lines": lines,
        "panels": [
            {"name": "front", "seed": "skirt_front_mid", "body_part": "torso", "ease": {"value": 1.3}},
            {
                "name": "back",
                "seed": "skirt_back_mid",
                "body_part": "torso",
                "ease": {"value": 1.3},
                "darts": _skirt_back_darts(kps),
            },
        ],
    }
    return _design(
        "skirt",
        "A two-panel skirt on the skirt topology, a waist dart either side of the back to the seat; ease 1.3.",
        [g],
        params,
        kps,
        skirt=True,
    )


def _dress(name, description, ease, length_range=(SKIRT_LENGTH_MIN, 0.8)):
    params, kps, lines, panels = _top_parts("none")
    sparams, skps, guides = _skirt_hem_parts(0.55, length_range)
    params.update(sparams)
    kps.update(skps)
    kps["skirt_front_mid"] = {"between": ["waist_front", "crotch"], "t": 0.5}
    kps["skirt_back_mid"] = {"between": ["waist_back", "crotch"], "t": 0.5}
    for l in lines:
        if l["name"] == "side_left":
            l["points"] = ["armhole_under_left", "waist_side_left"]
    skirt_lines = _skirt_lines()
    skirt_lines[1]["name"] = "skirt_side_left"
    lines = lines + [_waist_ring(role="seam")] + skirt_lines + guides
    panels = [
        {"name": "bodice_front", "seed": "chest_front", "body_part": "torso", "ease": ease["bodice_front"]},
        {"name": "bodice_back", "seed": "chest_back", "body_part": "torso", "ease": ease["bodice_back"]},
        {"name": "skirt_front", "seed": "skirt_front_mid", "body_part": "torso", "ease": ease["skirt_front"]},
        {"name": "skirt_back", "seed": "skirt_back_mid", "body_part": "torso", "ease": ease["skirt_back"]},
    ]
    g = {"name": "dress", "kind": "dress", "pin": "waist", "lines": lines, "panels": panels}
    return _design(name, description, [g], params, kps, skirt=True)


def dress():
    return _dress(
        "dress",
        "Sleeveless dress: bodice and skirt, front and back, joined by a waist seam "
        "(pinned); skirt topology; ease 1.15 bodice, 1.4 skirt.",
        {
            "bodice_front": {"value": 1.15},
            "bodice_back": {"value": 1.15},
            "skirt_front": {"value": 1.4},
            "skirt_back": {"value": 1.4},
        },
        # longer, the pattern solve tears the uniform-ease skirt at its left side
        # seam (seam mismatch 12 mm at 0.71 m, 131 mm at 0.75; 2 mm at 0.70)
        length_range=(SKIRT_LENGTH_MIN, 0.7),
    )


def dress_gradient():
    """The paper's simple dress with ease rising linearly from top to hem."""
    grad = {"from": 1.0, "to": 1.8, "axis": "-z", "over": "garment"}
    return _dress(
        "dress with linear ease",
        "The paper's non-uniform dress: ease rising linearly from 1.0 at the neckline to 1.8 at the hem.",
        {k: copy.deepcopy(grad) for k in ("bodice_front", "bodice_back", "skirt_front", "skirt_back")},
        # shorter, the steeper ease ramp with a deep front neckline tears the pattern's
        # seams (mismatch 7 to 17 mm at 0.32 to 0.34 m, neck_drop_front 0.146; 2.4 at 0.36)
        length_range=(0.36, 0.8),
    )


#: the women's body of the women's templates: size M of the women's chart (core.body.charts: Anny at
#: gender phenotype 1.0 fitted to EN 13402-3)
WOMEN_BODY = {"model": "anny", "chart": "women", "shape": "M", "pose": "A"}


#: m, the fitted blouse's front waist darts' intake at the hem (a tailor's 2 cm; ``"auto"`` ones share the
#: bust's wedge with the bust darts arbitrarily and cross on one side, docs/darts.md)
BLOUSE_WAIST_DART_INTAKE = 0.02


def blouse_fitted():
    """Women's sleeveless fitted blouse: the sleeveless top on a women's body, hem just below the
    waist, ease 1.1, with a bust dart from each side seam and a waist dart from the hem, both
    towards the bust point (:mod:`core.design.darts`; ``*_right`` mirrored).

    The waist darts against the bust darts alone, women:M at ease 1.1 (weft %, warp %, shear
    p95 deg): 1.50 / 6.25 / 4.2 against 1.49 / 6.52 / 4.7; at 1.3 1.47 / 6.40 / 4.5 against
    1.48 / 6.70 / 5.1 (benchmarks/results/pattern.md, women's wear).
    """
    d = _top(
        "fitted blouse",
        "Women's sleeveless fitted blouse (women's chart, size M): front and back, hem just "
        "below the waist, bust darts from the side seams and waist darts from the hem towards "
        "the bust points; ease 1.1.",
        "none",
    )
    d["body"] = copy.deepcopy(WOMEN_BODY)
    d["parameters"]["hem_length"]["value"] = 0.01
    g = d["garments"][0]
    g["name"] = "blouse"
    for p in g["panels"]:
        p["ease"] = {"value": 1.1}
    front = next(p for p in g["panels"] if p["name"] == "front")
    front["darts"] = [
        {"name": "bust_dart_left", "line": "side_left", "apex": "bust_left", "intake": "auto", "apex_offset": 0.025},
        {
            "name": "waist_dart_left",
            "line": "hem",
            "apex": "bust_left",
            "intake": BLOUSE_WAIST_DART_INTAKE,
            "apex_offset": 0.02,
        },
    ]
    return d


def skirt_darted():
    """Women's fitted skirt: the two-panel skirt on a women's body, ease 1.1, with a waist dart
    on each side of the back, 13 cm long, pointing down at the seat; ``*_right`` mirrored. (Front
    darts towards the stomach open by less than 4 mm on this body, or cross: the front's side
    seams take its shaping, so the template has none.)"""
    d = skirt()
    d["name"] = "darted skirt"
    d["description"] = (
        "Women's fitted skirt (women's chart, size M): front and back on the skirt topology, "
        "waist darts towards the stomach and the seat; ease 1.1."
    )
    d["body"] = copy.deepcopy(WOMEN_BODY)
    d["parameters"]["back_dart_length"] = {"value": 0.13, "kind": "length", "min": 0.07, "max": 0.18}
    d["parameters"]["back_dart_place"] = {"value": 0.5, "kind": "placement", "min": 0.2, "max": 0.8}
    d["keypoints"]["back_dart_top_left"] = {"between": ["waist_back", "waist_side_left"], "t": "$back_dart_place"}
    d["keypoints"]["back_dart_apex_left"] = {
        "trace": {"from": "back_dart_top_left", "along": "torso_down", "length": "$back_dart_length"}
    }
    for p in d["garments"][0]["panels"]:
        p["ease"] = {"value": 1.1}
        if p["name"] == "back":
            p["darts"] = [
                {
                    "name": "back_dart_left",
                    "line": "waist",
                    "apex": "back_dart_apex_left",
                    "at": "back_dart_top_left",
                    "intake": "auto",
                    "apex_offset": 0.01,
                }
            ]
    return d
