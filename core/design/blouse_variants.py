"""The fitted blouse with other darts than :func:`core.design.garments.blouse_fitted` ships with.

The ``blouse_fitted`` template has bust darts from the side seams and front waist darts from the
hem, both towards the bust points. :func:`blouse_waist_darts` sets the waist darts' intake (or
leaves them out), adds a shoulder dart towards the bust point and, optionally, a neckline dart
towards the bust point and a back waist dart (from the hem towards the shoulder blade); it is a
study, not a template (the shoulder darts pay only on a converged solve, docs/darts.md, "Limits").
:func:`blouse_four_darts`, the four-dart blouse, is the shipped template ``blouse_four_darts``:
it names the solver configuration it is made for (``"solver": "fitted"``).
"""

from __future__ import annotations

from .garments import BLOUSE_WAIST_DART_INTAKE, blouse_fitted

#: m, the waist and shoulder darts' set intakes of :func:`blouse_waist_darts` (held by the solver's
#: soft intake term; ``"auto"`` ones cross on one side: the flattening shares the bust's wedge
#: between converging darts arbitrarily, see docs/darts.md)
WAIST_DART_INTAKE = BLOUSE_WAIST_DART_INTAKE
SHOULDER_DART_INTAKE = 0.02
#: m, the neckline darts' intake of :func:`blouse_four_darts`, and the front darts' apex offset there:
#: four darts sharing the bust's wedge, each ending 5 mm from the bust point (2 mm leaves a sliver
#: at the apex that flips), are the blouse's best frontier (benchmarks/results/pattern.md, women's wear)
NECK_DART_INTAKE = 0.0075
FOUR_DART_APEX_OFFSET = 0.005
#: m, where the neckline dart of :func:`blouse_four_darts` stops short of the bust point: it meets the
#: shoulder dart at a narrow angle, and on the tape-fitted women's L, XXL and 3XL their lines crossed
#: at 5 mm ("cut lines ... cross"); at 7.5 mm every women's size cuts (men's XXL then loses the dart's
#: line: a women's blouse there is refused), and women:M's figures move by under 0.01 point
#: (compliance 0.61 %, warp 3.20 -> 3.21 %, bust region 1.31 %)
NECK_DART_APEX_OFFSET = 0.0075


def blouse_waist_darts(waist=WAIST_DART_INTAKE, shoulder=SHOULDER_DART_INTAKE, back=None, apex_offset=0.02, neck=None):
    """The fitted blouse with its front waist dart (from the hem up towards the bust point) at
    intake ``waist``, a shoulder dart towards the bust point, with ``neck`` (m) a neckline dart
    towards the bust point and, with ``back`` (m), a back waist dart from the hem towards the
    shoulder blade, beside the side-seam bust darts; ``*_right`` mirrored.

    Not a shipped template: the shoulder darts pay only on a converged solve (figures on women:M
    in benchmarks/results/pattern.md, "Women's wear", the "waist + shoulder darts" rows, and
    docs/darts.md, "Limits"). Intakes in m (None: leave the dart out), ``apex_offset`` m for the
    front darts.
    """
    d = blouse_fitted()
    d["description"] = (
        "Women's sleeveless fitted blouse (women's chart, size M) with bust, waist, shoulder"
        + (" and neckline" if neck else "")
        + " darts towards the bust points"
        + (" and back waist darts towards the shoulder blades" if back else "")
        + "."
    )
    g = d["garments"][0]
    front = next(p for p in g["panels"] if p["name"] == "front")
    # the template's own darts: the bust dart, and its waist dart (set here, or left out)
    bust = next(x for x in front["darts"] if x["name"] == "bust_dart_left")
    bust["apex_offset"] = apex_offset
    front["darts"] = [bust]
    extra = (
        ("waist_dart_left", "hem", waist),
        ("shoulder_dart_left", "shoulder_left", shoulder),
        ("neck_dart_left", "neckline", neck),
    )
    front["darts"] += [
        {"name": n, "line": line, "apex": "bust_left", "intake": w, "apex_offset": apex_offset}
        for n, line, w in extra
        if w
    ]
    if back:
        rear = next(p for p in g["panels"] if p["name"] == "back")
        rear["darts"] = [
            {
                "name": "back_waist_dart_left",
                "line": "hem",
                "apex": "shoulder_blade_left",
                "intake": back,
                "apex_offset": 0.03,
            }
        ]
    return d


def blouse_four_darts():
    """Template ``blouse_four_darts``: the fitted blouse with four darts towards each bust point (side
    seam, hem, shoulder and neckline), each ending :data:`FOUR_DART_APEX_OFFSET` from the bust point
    (the neckline dart :data:`NECK_DART_APEX_OFFSET`),
    solved with the ``fitted`` configuration it names (``"solver"``; converged, the warp lengths
    nearly kept): issue 14's blouse targets on women:M (figures in benchmarks/results/pattern.md,
    women's wear). At the default 20 iterations its seams part by up to 4.7 mm at the ends of its
    parameter ranges; with ``fitted`` by under 1.5 mm. The shoulder and neckline darts arrive at a
    narrow angle: the cut turns the neckline dart's point along the 5 mm circle so a ring of
    triangles stays between the tips (:mod:`core.design.dart_tips`; without it the solve at 5 mm
    edges flips)."""
    d = blouse_waist_darts(neck=NECK_DART_INTAKE, apex_offset=FOUR_DART_APEX_OFFSET)
    front = next(p for p in d["garments"][0]["panels"] if p["name"] == "front")
    next(x for x in front["darts"] if x["name"] == "neck_dart_left")["apex_offset"] = NECK_DART_APEX_OFFSET
    d["name"] = "four-dart blouse"
    d["description"] = (
        "Women's sleeveless fitted blouse (women's chart, size M) with four darts towards each "
        "bust point: from the side seam, the hem, the shoulder and the neckline, ending 5 mm "
        "from the point (the neckline dart 7.5 mm); ease 1.1; solved with the fitted configuration (converged, the warp "
        "lengths kept)."
    )
    d["solver"] = "fitted"
    # graded up to a bigger cup, the darts are drafted again on it (docs/darts.md, "Graded to L")
    d["transfer_solver"] = "cup"
    return d
