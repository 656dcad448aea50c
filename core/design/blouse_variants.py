"""Variants of the fitted blouse template with more darts than it ships with.

:func:`blouse_waist_darts` adds the tailor's front waist dart (from the hem up towards the bust
point), a shoulder dart towards the bust point and, optionally, a back waist dart (from the hem
towards the shoulder blade) to :func:`core.design.templates.blouse_fitted`. It is not a shipped
template (see its docs and docs/darts.md, "Limits": the darts pay only on a converged solve).
"""
from __future__ import annotations

from .templates import blouse_fitted

#: m, the waist and shoulder darts' set intakes of :func:`blouse_waist_darts` (held by the solver's
#: soft intake term; ``"auto"`` ones cross on one side: the flattening shares the bust's wedge
#: between converging darts arbitrarily, see docs/darts.md)
WAIST_DART_INTAKE = 0.02
SHOULDER_DART_INTAKE = 0.02


def blouse_waist_darts(waist=WAIST_DART_INTAKE, shoulder=SHOULDER_DART_INTAKE, back=None, apex_offset=0.02):
    """The fitted blouse with the tailor's front waist dart (from the hem up towards the bust
    point), a shoulder dart towards the bust point and, with ``back`` (m), a back waist dart from
    the hem towards the shoulder blade, beside the side-seam bust darts; ``*_right`` mirrored.

    Not a shipped template: the darts pay only on a converged solve. Measured on women:M
    (ease 1.1 / 1.3; weft %, warp %, shear p95 deg, bust region %): at the solver's default 20
    iterations 1.81 / 1.22, 8.5, 6.8 / 7.6, 5.8 / 3.9 and 1 collapsed triangle at 1.3 (the bust
    darts alone: 1.49 / 1.48, 7.0, 4.7 / 5.1, 5.1 / 5.2); at 200 iterations 0.54 / 0.55, 8.8 / 9.0,
    5.9 / 6.4, 2.3 / 2.5; at 200 iterations with warp slack 0 (ease 1.1) 0.58, 2.98, 7.1, 2.6
    (docs/darts.md, "Limits"). Intakes in m (None: leave the dart out), ``apex_offset`` m for
    the front darts.
    """
    d = blouse_fitted()
    d["description"] = ("Women's sleeveless fitted blouse (women's chart, size M) with bust, waist and shoulder "
                        "darts towards the bust points" + (" and back waist darts towards the shoulder blades"
                                                           if back else "") + ".")
    g = d["garments"][0]
    front = next(p for p in g["panels"] if p["name"] == "front")
    front["darts"][0]["apex_offset"] = apex_offset
    extra = (("waist_dart_left", "hem", waist), ("shoulder_dart_left", "shoulder_left", shoulder))
    front["darts"] += [{"name": n, "line": line, "apex": "bust_left", "intake": w, "apex_offset": apex_offset}
                       for n, line, w in extra if w]
    if back:
        rear = next(p for p in g["panels"] if p["name"] == "back")
        rear["darts"] = [{"name": "back_waist_dart_left", "line": "hem", "apex": "shoulder_blade_left",
                          "intake": back, "apex_offset": 0.03}]
    return d

