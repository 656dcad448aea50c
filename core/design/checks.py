"""Validation of design fields: every error names the JSON path of the field.

Field checks return the normalised value (``check_keypoint`` a keypoint dict,
``check_ease`` an ease field, ``check_number`` a float) or raise
:class:`core.errors.DesignError` whose ``path`` is the offending element
(``garments[0].panels[2].ease.value: expected a number in 0.8..4.0, got 7``).
The parser (:mod:`core.design.parser`) builds the design from them; the
design's own edits (:class:`core.design.types.Design`) re-validate with them.
Design-wide checks (names unique, seam names of the materials) come last.
"""

from __future__ import annotations

import json
import math
import re
from typing import Dict

from ..choices import SOLVER_CONFIGS  # noqa: F401  (re-exported)
from ..errors import DesignError

# Ease a design may ask for. The floor is the lowest ease that drapes: with every panel at
# a uniform 0.7 the long-sleeve shirt's drape diverges at frame 1 (0.5 to 0.7 solve into
# patterns but tear in the drape), at 0.8 every template drapes (cotton; the shirt also in
# denim, silk and jersey; 30-frame drapes, tests/test_template_ranges.py).
EASE_MIN, EASE_MAX = 0.8, 4.0
# refine_edge_length (m): finer than 5 mm the drape diverges at frame 1 (skirt at 4 mm,
# shirt at 3 mm, with the default 20 substeps per frame) and the pattern solve tears seams
# (dress_gradient 95 mm seam mismatch at 4 mm, skirt 43 mm at 2 mm).
REFINE_EDGE_MIN, REFINE_EDGE_MAX = 0.005, 0.1
GARMENT_KINDS = ("upper", "lower", "dress")
LINE_ROLES = ("seam", "opening", "guide")  # a guide line is not cut: it only names points
BODY_PARTS = ("torso", "arm", "leg")
TRACE_ALONG = ("arm_left", "arm_right", "leg_left", "leg_right", "torso_down", "torso_up")
PARAMETER_KINDS = ("placement", "length", "number")
AXES = ("x", "-x", "+x", "y", "-y", "+y", "z", "-z", "+z")
KEYPOINT_KINDS = ("landmark", "triangle", "between", "trace", "mirror_of")

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def fmt(value) -> str:
    try:
        s = json.dumps(value)
    except (TypeError, ValueError):
        s = repr(value)
    return s if len(s) <= 60 else s[:57] + "..."


def is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def expect_dict(path, obj, what="an object"):
    if not isinstance(obj, dict):
        raise DesignError(path, f"expected {what}, got {fmt(obj)}")
    return obj


def expect_keys(path, obj, allowed):
    extra = sorted(set(obj) - set(allowed))
    if extra:
        raise DesignError(
            f"{path}.{extra[0]}" if path else extra[0], f"unknown field; expected one of: {', '.join(sorted(allowed))}"
        )


def check_name(path, name):
    if not isinstance(name, str) or not _NAME.match(name):
        raise DesignError(path, f"expected a name of letters, digits and '_', got {fmt(name)}")


def check_number(path, x, lo=None, hi=None, lo_open=False, what=None):
    if not is_number(x) or not math.isfinite(x):
        rng = f" in {lo}..{hi}" if lo is not None and hi is not None else ""
        raise DesignError(path, f"expected {what or 'a finite number'}{rng}, got {fmt(x)}")
    if (lo is not None and (x < lo or (lo_open and x <= lo))) or (hi is not None and x > hi):
        if lo is not None and hi is not None:
            rng = f"in {lo}..{hi}"
        elif lo is not None:
            rng = f"> {lo}" if lo_open else f">= {lo}"
        else:
            rng = f"<= {hi}"
        raise DesignError(path, f"expected {what or 'a number'} {rng}, got {fmt(x)}")
    return float(x)


def check_parameter_value(path, kind, value, lo=None, hi=None):
    if kind == "placement":
        check_number(path, value, 0.0, 1.0, what="a placement")
    elif kind == "length":
        check_number(path, value, 0.0, 3.0, lo_open=True, what="a length in metres")
    else:
        check_number(path, value)
    if lo is not None and value < lo or hi is not None and value > hi:
        raise DesignError(path, f"expected a value in {lo}..{hi} (the parameter's range), got {fmt(value)}")


def param_or_number(path, x, params, kind, lo=None, hi=None, lo_open=False, what=None):
    """A number, or ``"$name"`` naming a parameter of a compatible kind."""
    if isinstance(x, str):
        if not x.startswith("$"):
            raise DesignError(path, f'expected a number or "$parameter", got {fmt(x)}')
        name = x[1:]
        if name not in params:
            raise DesignError(path, f"unknown parameter {name!r}; parameters: {', '.join(params) or 'none'}")
        p = params[name]
        if kind and p.kind not in (kind, "number"):
            raise DesignError(path, f"parameter {name!r} is a {p.kind}, expected a {kind}")
        return x
    return check_number(path, x, lo, hi, lo_open=lo_open, what=what)


def parameter_value(x, params: Dict[str, object]) -> float:
    """The number a validated ``number | "$param"`` field stands for (``params``: name -> :class:`.types.Parameter`)."""
    if isinstance(x, str):
        return float(params[x[1:]].value)
    return float(x)


def keypoint_ref(path, x, params, allow_inline=True):
    """A keypoint reference: a name, or (when allowed) an inline keypoint."""
    if isinstance(x, str):
        check_name(path, x)
        return x
    if allow_inline and isinstance(x, dict):
        return check_keypoint(path, x, params)
    raise DesignError(path, f"expected a keypoint name{' or a keypoint object' if allow_inline else ''}, got {fmt(x)}")


def check_keypoint(path, obj, params):
    if isinstance(obj, str):
        return {"landmark": obj}
    expect_dict(path, obj, "a keypoint object {landmark | triangle+bary | between+t | trace}")
    kinds = [k for k in KEYPOINT_KINDS if k in obj]
    if len(kinds) != 1:
        raise DesignError(path, f"expected exactly one of {', '.join(KEYPOINT_KINDS)}, got {fmt(sorted(obj))}")
    kind = kinds[0]
    if kind == "landmark":
        expect_keys(path, obj, ("landmark",))
        check_name(f"{path}.landmark", obj["landmark"])
        return {"landmark": obj["landmark"]}
    if kind == "triangle":
        expect_keys(path, obj, ("triangle", "bary"))
        tri = obj["triangle"]
        if not isinstance(tri, int) or isinstance(tri, bool) or tri < 0:
            raise DesignError(f"{path}.triangle", f"expected a triangle index >= 0, got {fmt(tri)}")
        bary = obj.get("bary")
        if not isinstance(bary, (list, tuple)) or len(bary) != 3:
            raise DesignError(f"{path}.bary", f"expected 3 barycentric weights, got {fmt(bary)}")
        b = [
            check_number(f"{path}.bary[{i}]", v, -1e-6, 1 + 1e-6, what="a barycentric weight")
            for i, v in enumerate(bary)
        ]
        if abs(sum(b) - 1.0) > 1e-4:
            raise DesignError(f"{path}.bary", f"expected weights summing to 1, got sum {sum(b):.6f}")
        return {"triangle": int(tri), "bary": b}
    if kind == "between":
        expect_keys(path, obj, ("between", "t"))
        pair = obj["between"]
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise DesignError(f"{path}.between", f"expected [keypoint_a, keypoint_b], got {fmt(pair)}")
        refs = [keypoint_ref(f"{path}.between[{i}]", r, params) for i, r in enumerate(pair)]
        if "t" not in obj:
            raise DesignError(f"{path}.t", 'missing; expected a placement 0..1 or "$parameter"')
        t = param_or_number(f"{path}.t", obj["t"], params, "placement", 0.0, 1.0, what="a placement")
        return {"between": refs, "t": t}
    if kind == "mirror_of":
        # the mirror image (through the body's symmetry map) of another keypoint
        expect_keys(path, obj, ("mirror_of",))
        return {"mirror_of": keypoint_ref(f"{path}.mirror_of", obj["mirror_of"], params)}
    # trace
    expect_keys(path, obj, ("trace",))
    tr = expect_dict(f"{path}.trace", obj["trace"], "{from, along, length}")
    expect_keys(f"{path}.trace", tr, ("from", "along", "length"))
    for k in ("from", "along", "length"):
        if k not in tr:
            raise DesignError(f"{path}.trace.{k}", "missing")
    start = keypoint_ref(f"{path}.trace.from", tr["from"], params)
    if tr["along"] not in TRACE_ALONG:
        raise DesignError(f"{path}.trace.along", f"expected one of {', '.join(TRACE_ALONG)}, got {fmt(tr['along'])}")
    length = param_or_number(
        f"{path}.trace.length", tr["length"], params, "length", 0.0, 3.0, lo_open=True, what="a length in metres"
    )
    return {"trace": {"from": start, "along": tr["along"], "length": length}}


def check_axis(path, x, params):
    if isinstance(x, str):
        if x not in AXES:
            raise DesignError(path, f"expected an axis ({', '.join(AXES)}) or [keypoint_a, keypoint_b], got {fmt(x)}")
        return x
    if isinstance(x, (list, tuple)) and len(x) == 2:
        return [keypoint_ref(f"{path}[{i}]", r, params) for i, r in enumerate(x)]
    raise DesignError(path, f"expected an axis ({', '.join(AXES)}) or [keypoint_a, keypoint_b], got {fmt(x)}")


def check_ring(path, ring, params):
    expect_dict(path, ring, "a ring {through, normal, points, named}")
    expect_keys(path, ring, ("through", "normal", "points", "named", "offset", "contains"))
    if "through" not in ring:
        raise DesignError(f"{path}.through", "missing; expected a keypoint the ring passes through")
    out = {"through": keypoint_ref(f"{path}.through", ring["through"], params)}
    if "normal" not in ring:
        raise DesignError(f"{path}.normal", "missing; expected an axis or [keypoint_a, keypoint_b]")
    out["normal"] = check_axis(f"{path}.normal", ring["normal"], params)
    if "contains" in ring:
        out["contains"] = keypoint_ref(f"{path}.contains", ring["contains"], params)
    n = ring.get("points", 12)
    if not isinstance(n, int) or isinstance(n, bool) or not 4 <= n <= 64:
        raise DesignError(f"{path}.points", f"expected an integer in 4..64, got {fmt(n)}")
    out["points"] = n
    out["offset"] = param_or_number(
        f"{path}.offset", ring.get("offset", 0.0), params, "length", -0.2, 0.2, what="an offset in metres"
    )
    named = ring.get("named", {})
    expect_dict(f"{path}.named", named, "an object name -> fraction 0..1 or axis")
    out_named = {}
    for k, v in named.items():
        check_name(f"{path}.named.{k}", k)
        if isinstance(v, str):
            if v not in AXES:
                raise DesignError(
                    f"{path}.named.{k}", f"expected a fraction 0..1 or an axis ({', '.join(AXES)}), got {fmt(v)}"
                )
            out_named[k] = v
        else:
            out_named[k] = check_number(f"{path}.named.{k}", v, 0.0, 1.0, what="a fraction of the ring")
    out["named"] = out_named
    return out


def check_section(path, sec, params):
    expect_dict(path, sec, "a section {from, to, normal, spacing}")
    expect_keys(path, sec, ("from", "to", "normal", "spacing"))
    for k in ("from", "to", "normal"):
        if k not in sec:
            raise DesignError(f"{path}.{k}", "missing")
    out = {
        "from": keypoint_ref(f"{path}.from", sec["from"], params),
        "to": keypoint_ref(f"{path}.to", sec["to"], params),
        "normal": check_axis(f"{path}.normal", sec["normal"], params),
    }
    out["spacing"] = check_number(
        f"{path}.spacing", sec.get("spacing", 0.03), 0.005, 0.2, what="a point spacing in metres"
    )
    return out


def _ease_value(path, x):
    return check_number(path, x, EASE_MIN, EASE_MAX, what="a number")


def check_ease(path, obj, params) -> dict:
    """Validate an ease field. Every value must be finite and in EASE_MIN..EASE_MAX (0.8..4.0)."""
    if is_number(obj):
        return {"value": _ease_value(path, obj)}
    expect_dict(path, obj, "an ease field {value} | {from, to, between|axis} | {per_triangle}")
    if "value" in obj:
        expect_keys(path, obj, ("value",))
        return {"value": _ease_value(f"{path}.value", obj["value"])}
    if "per_triangle" in obj:
        expect_keys(path, obj, ("per_triangle",))
        pt = expect_dict(f"{path}.per_triangle", obj["per_triangle"], "{triangles, values, default}")
        expect_keys(f"{path}.per_triangle", pt, ("triangles", "values", "default"))
        vals = pt.get("values")
        if not isinstance(vals, list) or not vals:
            raise DesignError(
                f"{path}.per_triangle.values", f"expected a non-empty list of ease values, got {fmt(vals)}"
            )
        out_vals = [_ease_value(f"{path}.per_triangle.values[{i}]", v) for i, v in enumerate(vals)]
        out = {"values": out_vals}
        if "triangles" in pt:
            tris = pt["triangles"]
            if not isinstance(tris, list) or len(tris) != len(vals):
                raise DesignError(
                    f"{path}.per_triangle.triangles",
                    f"expected a list of {len(vals)} body triangle ids (one per value), got {fmt(tris)}",
                )
            for i, t in enumerate(tris):
                if not isinstance(t, int) or isinstance(t, bool) or t < 0:
                    raise DesignError(
                        f"{path}.per_triangle.triangles[{i}]", f"expected a triangle index >= 0, got {fmt(t)}"
                    )
            out["triangles"] = [int(t) for t in tris]
        out["default"] = _ease_value(f"{path}.per_triangle.default", pt.get("default", 1.0))
        return {"per_triangle": out}
    if "from" in obj or "to" in obj:
        expect_keys(path, obj, ("from", "to", "between", "axis", "over"))
        for k in ("from", "to"):
            if k not in obj:
                raise DesignError(f"{path}.{k}", "missing; a gradient needs from and to")
        out = {"from": _ease_value(f"{path}.from", obj["from"]), "to": _ease_value(f"{path}.to", obj["to"])}
        if ("between" in obj) == ("axis" in obj):
            raise DesignError(path, "a gradient needs exactly one of between [keypoint_a, keypoint_b] or axis")
        if "between" in obj:
            pair = obj["between"]
            if not isinstance(pair, list) or len(pair) != 2:
                raise DesignError(f"{path}.between", f"expected [keypoint_a, keypoint_b], got {fmt(pair)}")
            out["between"] = [keypoint_ref(f"{path}.between[{i}]", r, params) for i, r in enumerate(pair)]
        else:
            if obj["axis"] not in AXES:
                raise DesignError(f"{path}.axis", f"expected one of {', '.join(AXES)}, got {fmt(obj['axis'])}")
            out["axis"] = obj["axis"]
            over = obj.get("over", "panel")
            if over not in ("panel", "garment"):
                raise DesignError(f"{path}.over", f'expected "panel" or "garment", got {fmt(over)}')
            if over != "panel":
                out["over"] = over
        return out
    raise DesignError(
        path, f"expected an ease field {{value}} | {{from, to, between|axis}} | {{per_triangle}}, got {fmt(obj)}"
    )


def check_names_unique(design) -> None:
    """Ring-named points must not shadow keypoints or each other."""
    seen = dict.fromkeys(design.keypoints, "keypoints")
    groups = [("lines", design.lines)] + [(f"garments[{gi}].lines", g.lines) for gi, g in enumerate(design.garments)]
    for prefix, lines in groups:
        for li, line in enumerate(lines):
            if line.ring is None:
                continue
            for k in line.ring["named"]:
                if k in seen:
                    raise DesignError(f"{prefix}[{li}].ring.named.{k}", f"name {k!r} is already defined ({seen[k]})")
                seen[k] = f"{prefix}[{li}]"
