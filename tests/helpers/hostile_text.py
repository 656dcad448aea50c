"""Hostile design files and option strings (no tests here): encodings, nesting, numbers, names.

:func:`design_cases` gives ``(name, bytes)`` design files: crafted ones (latin-1,
UTF-16/32, nesting, huge or non-finite numbers, reversed ranges, unknown
fabrics, models, shape parameters and joints, huge pose angles) and seeded
mutations of every template, element by element (:func:`json_mutation`) and
byte by byte (:func:`mutate`).
"""

import copy
import json

from hostile_cut_folders import json_mutation
from hostile_models import mutate


def templates():
    from core.design.templates import TEMPLATES, template_path

    return {name: json.loads(template_path(name).read_text(encoding="utf-8")) for name in TEMPLATES}


def _edit(obj, path, value):
    obj = copy.deepcopy(obj)
    o = obj
    for k in path[:-1]:
        o = o.setdefault(k, {}) if isinstance(k, str) else o[k]
    o[path[-1]] = value
    return obj


def _deep(n):
    return "[" * n + "]" * n


CRAFTED_EDITS = {
    # name: (JSON path, value, text expected in the refusal)
    "fabric_unknown": (("materials", "fabric"), "velvet", "materials.fabric"),
    "fabric_number": (("materials", "fabric"), 3, "materials.fabric"),
    "model_unknown": (("body", "model"), "smplx", "body.model"),
    "model_fbx": (("body", "model"), "body.fbx", "body.model"),
    "shape_unknown_param": (("body", "shape"), {"heigth": 0.5}, "body.shape.heigth"),
    "shape_out_of_range": (("body", "shape"), {"height": 1e9}, "body.shape.height"),
    "shape_nan": (("body", "shape"), {"height": float("nan")}, "body.shape.height"),
    "pose_unknown_joint": (("body", "pose"), {"elbow": [0, 0, 1]}, "body.pose.elbow"),
    "pose_huge_angle": (("body", "pose"), {"root": [1e9, 0, 0]}, "body.pose.root[0]"),
    "pose_degrees": (("body", "pose"), {"root": [90, 0, 0]}, "body.pose.root[0]"),
    "pose_long_axis": (("body", "pose"), {"root": [6, 6, 0]}, "body.pose.root"),
    "pose_two_numbers": (("body", "pose"), {"root": [0, 1]}, "body.pose.root"),
    "refine_tiny": (("refine_edge_length",), 1e-9, "refine_edge_length"),
    "parameter_reversed": (
        ("parameters", "p_rev"),
        {"value": 0.5, "kind": "placement", "min": 0.7, "max": 0.2},
        "parameters.p_rev.min",
    ),
    "name_huge_int": (("name",), 10**100, "name"),
    "version_float": (("version",), 1.5, "version"),
}


def crafted_designs():
    """``{name: (bytes, expected text)}``: each must be refused, naming the field (or the file)."""
    base = templates()["skirt"]
    text = json.dumps(base)
    out = {}
    for name, (path, value, expect) in CRAFTED_EDITS.items():
        out[name] = (json.dumps(_edit(base, path, value)).encode(), expect)
    accented = json.dumps(_edit(base, ("description",), "jupe \u00e9vas\u00e9e"), ensure_ascii=False)
    for enc in ("latin-1", "cp1252", "utf-16", "utf-16-le", "utf-16-be", "utf-32"):
        out[f"encoding_{enc}"] = (accented.encode(enc), "UTF")
    for where, n in (("description", 100), ("parameters", 1000), ("garments", 100000)):
        t = text.replace(f'"{where}": ', f'"{where}": {_deep(n)[:n]}0{_deep(n)[n:]}, "x_{where}": ', 1)
        out[f"nested_{where}_{n}"] = (t.encode(), "nested" if n > 64 else where)
    out["integer_5000_digits"] = (text.replace('"version": 1', '"version": ' + "9" * 5000, 1).encode(), "JSON")
    out["nan_literal"] = (text.replace('"version": 1', '"version": NaN', 1).encode(), "version")
    out["overflow_literal"] = (text.replace('"version": 1', '"version": 1e999', 1).encode(), "version")
    out["not_json"] = (b"\x00\x01garbage", "JSON")
    out["empty"] = (b"", "JSON")
    out["top_level_list"] = (json.dumps([base]).encode(), "a design object")
    return out


def design_cases():
    """Every design case as ``(kind, key)``: crafted, element mutations and byte mutations per template."""
    names = sorted(templates())
    cases = [("crafted", n) for n in crafted_designs()]
    cases += [("element", f"{t}@{s}") for t in names for s in range(40)]
    cases += [("bytes", f"{t}@{s}") for t in names for s in range(20)]
    return cases


_TEMPLATES = {}


def design_bytes(case) -> bytes:
    kind, key = case
    if kind == "crafted":
        return crafted_designs()[key][0]
    if not _TEMPLATES:
        _TEMPLATES.update(templates())
    name, seed = key.split("@")
    obj = _TEMPLATES[name]
    if kind == "element":
        return json.dumps(json_mutation(obj, int(seed)), ensure_ascii=False).encode("utf-8", "surrogateescape")
    return mutate(json.dumps(obj, indent=1).encode(), int(seed))


# --measure / --shape strings: (text, refused?)
ASSIGNMENTS = [
    ("chest=96,chest=100", True),
    ("chest=96,bust=100", True),
    ("chest=1e9", True),
    ("chest=nan", True),
    ("chest=inf", True),
    ("chest=-96", True),
    ("=96", True),
    ("chest", True),
    ("chest=", True),
    ("chest=96,,waist=80", False),
    (" chest = 96 ", False),
    ("neck=40", True),
    ("chest=9" + "9" * 400, True),
    ("chest=96,waist=80,hip=100,height=175", False),
    (",", True),
    ("chest=0x60", True),
]
