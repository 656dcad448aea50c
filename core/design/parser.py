"""The EASE design file (``"format": "ease-design", "version": 1``): JSON -> :mod:`core.design.types`, and back.

A design is plain JSON. Loading validates every element
(:mod:`core.design.checks`, the materials by :mod:`core.design.materials`) and raises
:class:`core.errors.DesignError` whose ``path`` is the JSON path of the
offending element (``garments[0].panels[2].ease.value: expected a number in
0.8..4.0, got 7``). Everything that depends on a body (landmark names, whether
a length fits on a limb) is checked when the design is resolved
(:func:`core.design.resolve.resolve`), with the same kind of path.

Fields (metres, the body frame of :mod:`core`: +Z up, body faces -Y, +X = body's left)

=====================  ==========================================================
``format``, ``version``  ``"ease-design"``, ``1``
``name``               non-empty string; ``description`` optional
``body``               ``{"model": "anny", "shape": "XS".."XL" | {param: value},
                       "pose": "A" | "T" | "P1".."P3" | {joint: [rx, ry, rz]}}``:
                       the reference instance the design is made on
``materials``          ``{"fabric", "eps_weft", "eps_warp", "gathered", "gather_above",
                       "export": {"allowance", "notch_spacing"}}``: fabric, stretch
                       tolerances, gathered seams, seam allowance and notch
                       spacing; fields and defaults in :mod:`core.design.materials`
``mirror``             true: every ``*_left`` keypoint / line / panel gets its
                       ``*_right`` counterpart through the body's symmetry map
``skirt``              true: cut on the skirt topology (dresses, skirts)
``refine_edge_length`` target *mean* edge length of the cut panels (m, 0.005..0.1,
                       default 0.01; finer does not drape): every edge longer than 1.5x it is split
                       (:mod:`core.cut.refine`); null keeps the body's resolution
``solver``             optional: the solver configuration the design is made for
                       (``"improved"`` | ``"paper"`` | ``"stretch"`` | ``"fitted"`` | ``"lengths"``); the
                       pattern is solved with it unless the user chooses one
                       (``--config``, the add-on's Solver); absent: ``"improved"``
``transfer_solver``    optional: ``"target"`` makes each transfer to another size flatten and
                       factorise on that size's body, ``"reference"`` (absent: the
                       configuration's) reuses the reference body's (docs/darts.md, "A solver
                       made on the target body"); ``"cup"`` the target's, every dart re-derived,
                       where the size's cups are bigger than the design's, else the reference's
                       (docs/darts.md, "Graded to L"); ``ease transfer --transfer-solver`` overrides it
``parameters``         ``{name: number | {"value", "kind": "placement" (0..1) |
                       "length" (m) | "number", "min", "max"}}``; used as
                       ``"$name"`` wherever a number is expected
``keypoints``          ``{name: keypoint}``; a keypoint is a landmark name,
                       ``{"landmark"}``, ``{"triangle", "bary"}`` (template surface
                       point), ``{"between": [a, b], "t"}`` (fraction t along the
                       geodesic a -> b) or ``{"trace": {"from", "along": "arm_left" |
                       "arm_right" | "leg_left" | "leg_right" | "torso_down" |
                       "torso_up", "length"}}`` (geodesic length down a body part)
                       or ``{"mirror_of": keypoint}`` (its mirror image)
``lines``              lines shared by all garments (e.g. the waist of shirt+pants)
``garments``           ``[{"name", "kind": "upper" | "lower" | "dress", "pin": line
                       name, "lines": [...], "panels": [...]}]``
line                   ``{"name", "role": "seam" | "opening" | "guide"}`` plus one of
                       ``"points": [keypoint, ...], "closed"`` (joined by geodesics);
                       ``"ring": {"through", "normal": axis | [a, b], "contains",
                       "points", "named": {name: fraction | axis}}`` (closed plane
                       section; ``contains``, optional: a second keypoint the
                       plane is tilted to hold, the normal turned least; names
                       points on itself: the extreme along an axis, or the
                       point at a fraction of its length); ``"section": {"from",
                       "to", "normal", "spacing"}`` (plane section between two
                       keypoints, e.g. a centre seam on the midline). A ``guide``
                       line is not cut; it only names points.
panel                  ``{"name", "seed": keypoint inside it, "body_part": "torso" |
                       "arm" | "leg", "ease": field, "darts": [dart, ...]}``
dart                   ``"auto"`` | ``{"auto": {"max_count", "max_intake"}}`` (placed by
                       :mod:`core.cut.auto_darts`) or a list of
                       ``{"name", "line": seam or hem line of the mouth, "apex": keypoint,
                       "intake": m | "auto", "apex_offset": m, "at": keypoint}``
                       (see :mod:`core.design.darts`)
ease field             ``{"value"}`` | ``{"from", "to", "between": [a, b]}`` |
                       ``{"from", "to", "axis", "over": "panel" | "garment"}`` |
                       ``{"per_triangle": {"triangles",
                       "values", "default"}}`` (body template triangles) -- every
                       value finite and in 0.8..4.0 (see :mod:`core.design.ease`)
=====================  ==========================================================

Keypoint references are strings: the name of a design keypoint, of a point
named on a ring line, of a generated ``*_right`` mirror, or of a body landmark.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Dict, Union

from ..body.model import POSE_PRESETS
from ..choices import TRANSFER_SOLVERS
from ..errors import BodyError, DesignError
from .checks import (
    BODY_PARTS,
    GARMENT_KINDS,
    LINE_ROLES,
    PARAMETER_KINDS,
    REFINE_EDGE_MAX,
    REFINE_EDGE_MIN,
    SOLVER_CONFIGS,
    check_ease,
    check_keypoint,
    check_name,
    check_names_unique,
    check_number,
    check_parameter_value,
    check_ring,
    check_section,
    expect_dict,
    expect_keys,
    fmt,
    is_number,
    keypoint_ref,
)
from .darts import parse_auto, parse_darts
from .materials import check_seam_names, parse_materials
from .pleats import parse_pleats
from .types import FORMAT, VERSION, Design, Garment, Line, Panel, Parameter


def _parse_line(path, obj, params) -> Line:
    expect_dict(path, obj, "a line {name, points | ring | section, closed, role}")
    expect_keys(path, obj, ("name", "points", "closed", "role", "ring", "section"))
    if "name" not in obj:
        raise DesignError(f"{path}.name", "missing")
    check_name(f"{path}.name", obj["name"])
    role = obj.get("role", "seam")
    if role not in LINE_ROLES:
        raise DesignError(f"{path}.role", f"expected one of {', '.join(LINE_ROLES)}, got {fmt(role)}")
    if sum(k in obj for k in ("ring", "points", "section")) != 1:
        raise DesignError(
            path,
            "expected exactly one of points (a keypoint list), ring (a closed plane "
            "section) or section (a plane section between two keypoints)",
        )
    if "section" in obj:
        if obj.get("closed", False) is not False:
            raise DesignError(f"{path}.closed", "a section is always open")
        return Line(obj["name"], [], False, role, None, check_section(f"{path}.section", obj["section"], params))
    if "ring" in obj:
        if obj.get("closed", True) is not True:
            raise DesignError(f"{path}.closed", "a ring is always closed")
        return Line(obj["name"], [], True, role, check_ring(f"{path}.ring", obj["ring"], params))
    closed = obj.get("closed", False)
    if not isinstance(closed, bool):
        raise DesignError(f"{path}.closed", f"expected true or false, got {fmt(closed)}")
    pts = obj["points"]
    need = 3 if closed else 2
    if not isinstance(pts, list) or len(pts) < need:
        raise DesignError(
            f"{path}.points",
            f"expected a list of at least {need} keypoints{' (a closed line)' if closed else ''}, got {fmt(pts)}",
        )
    refs = [keypoint_ref(f"{path}.points[{i}]", r, params) for i, r in enumerate(pts)]
    return Line(obj["name"], refs, closed, role, None)


def _parse_panel(path, obj, params) -> Panel:
    expect_dict(path, obj, "a panel {name, seed, body_part, ease, darts}")
    expect_keys(path, obj, ("name", "seed", "body_part", "ease", "darts", "pleats"))
    for k in ("name", "seed"):
        if k not in obj:
            raise DesignError(f"{path}.{k}", "missing")
    check_name(f"{path}.name", obj["name"])
    seed = keypoint_ref(f"{path}.seed", obj["seed"], params)
    part = obj.get("body_part", "torso")
    if part not in BODY_PARTS:
        raise DesignError(f"{path}.body_part", f"expected one of {', '.join(BODY_PARTS)}, got {fmt(part)}")
    try:
        ease = check_ease(f"{path}.ease", obj.get("ease", {"value": 1.0}), params)
    except DesignError as exc:
        # name the panel, not only its JSON path
        raise DesignError(exc.path, f"panel {obj['name']!r}: {exc.message}") from None
    auto = parse_auto(f"{path}.darts", obj["darts"]) if "darts" in obj else None
    darts = parse_darts(f"{path}.darts", obj["darts"], params) if "darts" in obj and auto is None else []
    pleats = parse_pleats(f"{path}.pleats", obj["pleats"], params) if "pleats" in obj else []
    return Panel(obj["name"], seed, part, ease, darts, auto, pleats)


def _named_list(path, raw, what, parse, required=False):
    """Parse a list of named elements (lines, panels, garments) with ``parse(path, item)``;
    their names must be unique."""
    if not isinstance(raw, list) or (required and not raw):
        raise DesignError(path, f"expected a {'non-empty ' if required else ''}list of {what}s, got {fmt(raw)}")
    out = []
    for i, item in enumerate(raw):
        x = parse(f"{path}[{i}]", item)
        if any(y.name == x.name for y in out):
            raise DesignError(f"{path}[{i}].name", f"duplicate {what} name {x.name!r}")
        out.append(x)
    return out


def _parse_garment(path, obj, params, shared_lines) -> Garment:
    expect_dict(path, obj, "a garment {name, kind, pin, lines, panels}")
    expect_keys(path, obj, ("name", "kind", "pin", "lines", "panels"))
    if "name" not in obj:
        raise DesignError(f"{path}.name", "missing")
    check_name(f"{path}.name", obj["name"])
    kind = obj.get("kind")
    if kind not in GARMENT_KINDS:
        raise DesignError(f"{path}.kind", f"expected one of {', '.join(GARMENT_KINDS)}, got {fmt(kind)}")
    lines = _named_list(f"{path}.lines", obj.get("lines", []), "line", lambda p, x: _parse_line(p, x, params))
    panels = _named_list(
        f"{path}.panels", obj.get("panels"), "panel", lambda p, x: _parse_panel(p, x, params), required=True
    )
    pin = obj.get("pin")
    if pin is not None:
        names = [l.name for l in lines] + [l.name for l in shared_lines]
        if not isinstance(pin, str) or pin not in names:
            raise DesignError(
                f"{path}.pin",
                f"expected the name of one of the garment's (or shared) lines "
                f"({', '.join(names) or 'none'}), got {fmt(pin)}",
            )
    return Garment(obj["name"], kind, pin, lines, panels)


def _check_on_model(path, model, shape, pose):
    """The shape parameters and pose joints of a design's body, checked against the model where its
    names are known without loading it (the built-in Anny); a file model is checked when it is loaded."""
    from ..body.anny import anny_names
    from ..body.model import check_axis_angle, check_shape

    names = anny_names() if model.lower() == "anny" else None
    if names is None:
        return
    params, joints = names
    for k, v in shape.items() if isinstance(shape, dict) else ():
        try:
            check_shape(params, {k: v}, model)
        except BodyError as exc:
            raise DesignError(f"{path}.shape.{k}", str(exc).split(": ", 2)[-1]) from None
    for k, v in pose.items() if isinstance(pose, dict) else ():
        try:
            check_axis_angle(v, k, joints)
        except BodyError as exc:
            raise DesignError(f"{path}.pose.{k}", str(exc).split(": ", 1)[-1]) from None


def _parse_body(path, obj):
    from ..body.model import POSE_ANGLE_MAX
    from ..body.registry import BUILTIN, MODEL_SUFFIXES
    from ..body.sizes import CHART_NAMES, chart_sizes, check_chart, check_size

    expect_dict(path, obj, "a body {model, chart, shape, pose} (an OBJ model also landmarks, blendshapes, up)")
    expect_keys(path, obj, ("model", "chart", "shape", "measurements", "pose", "landmarks", "blendshapes", "up"))
    model = obj.get("model", "anny")
    if not isinstance(model, str) or not (model.lower() in BUILTIN or model.lower().endswith(MODEL_SUFFIXES)):
        raise DesignError(
            f"{path}.model",
            f"expected {', '.join(BUILTIN)} or a path to a body model file "
            f"({', '.join(MODEL_SUFFIXES)}), got {fmt(model)}",
        )
    is_obj = model.lower().endswith(".obj")
    extra = {}
    # An OBJ template's own files: its landmarks (which a chart size and the keypoints need), blend
    # shapes (its shape parameters) and up axis; paths relative to the design file.
    for key, suffix in (("landmarks", ".json"), ("blendshapes", ".npz")):
        if key in obj:
            v = obj[key]
            if not is_obj:
                raise DesignError(
                    f"{path}.{key}",
                    f"only an OBJ template (body.model *.obj) takes a {key} file; the model is {fmt(model)}",
                )
            if not isinstance(v, str) or not v.lower().endswith(suffix):
                raise DesignError(f"{path}.{key}", f"expected a path to a {suffix} file, got {fmt(v)}")
            extra[key] = v
    if "up" in obj:
        if not is_obj or obj["up"] not in ("z", "y"):
            raise DesignError(
                f"{path}.up", f"expected 'z' or 'y' (the up axis of an OBJ template), got {fmt(obj['up'])}"
            )
        extra["up"] = obj["up"]
    chart = obj.get("chart")
    if chart is not None:
        if not isinstance(chart, str) or chart.strip().lower() not in CHART_NAMES:
            raise DesignError(f"{path}.chart", f"expected a size chart ({', '.join(CHART_NAMES)}), got {fmt(chart)}")
        chart = check_chart(chart).name
    # An OBJ template is a body of its own: its reference shape unless a shape is named (a chart
    # size needs its landmarks); the parametric models default to size M.
    shape = obj.get("shape", None if is_obj else "M")
    if "measurements" in obj:  # made-to-measure: the shape fitted to a table of tape measures
        if "shape" in obj or model.lower() != "anny":
            raise DesignError(
                f"{path}.measurements",
                "a table of tape measures fits Anny's shape: give it without body.shape, on model anny",
            )
        if not isinstance(obj["measurements"], dict):
            raise DesignError(
                f"{path}.measurements", f"expected an object measure -> cm, got {fmt(obj['measurements'])}"
            )
        from ..body.made_to_measure import measured_shape

        try:
            shape = measured_shape(obj["measurements"], f"{path}.measurements")
        except BodyError as exc:  # "body.measurements[.name]: what" -> that path and what
            where, _, what = str(exc).partition(": ")
            raise DesignError(
                where if where.startswith(f"{path}.measurements") else f"{path}.measurements", what or str(exc)
            ) from None
    if isinstance(shape, dict):
        for k, v in shape.items():
            check_number(f"{path}.shape.{k}", v)
        shape = {k: float(v) for k, v in shape.items()}
    elif isinstance(shape, str):
        try:
            shape = check_size(shape, chart)  # "M" of the chart, stored as "women:M"
        except BodyError:
            raise DesignError(
                f"{path}.shape",
                f"expected a size of chart {chart or 'default'} "
                f"({', '.join(chart_sizes(chart))}) or an object of shape "
                f"parameters, got {fmt(shape)}",
            ) from None
    elif shape is not None:
        raise DesignError(
            f"{path}.shape",
            f"expected a size ({', '.join(chart_sizes(chart))}) or an object of shape parameters, got {fmt(shape)}",
        )
    pose = obj.get("pose", "A")
    if isinstance(pose, str):
        if pose not in POSE_PRESETS:
            raise DesignError(
                f"{path}.pose",
                f"expected a pose preset ({', '.join(POSE_PRESETS)}) or an object joint -> [rx, ry, rz], got {fmt(pose)}",
            )
    elif isinstance(pose, dict):
        for k, v in pose.items():
            if not isinstance(v, list) or len(v) != 3:
                raise DesignError(f"{path}.pose.{k}", f"expected an axis-angle [rx, ry, rz] in radians, got {fmt(v)}")
            for i, x in enumerate(v):
                check_number(f"{path}.pose.{k}[{i}]", x, -POSE_ANGLE_MAX, POSE_ANGLE_MAX, what="an angle in radians")
        pose = {k: [float(x) for x in v] for k, v in pose.items()}
    elif pose is not None:
        raise DesignError(
            f"{path}.pose",
            f"expected a pose preset ({', '.join(POSE_PRESETS)}) or an object joint -> [rx, ry, rz], got {fmt(pose)}",
        )
    _check_on_model(path, model, shape, pose)
    return {"model": model, **({"chart": chart} if chart else {}), "shape": shape, "pose": pose, **extra}


def _parse_parameters(path, obj) -> Dict[str, Parameter]:
    expect_dict(path, obj, "an object name -> number | {value, kind, min, max}")
    out = {}
    for name, v in obj.items():
        p = f"{path}.{name}"
        check_name(p, name)
        if is_number(v):
            v = {"value": v}
        expect_dict(p, v, "a number or {value, kind, min, max}")
        expect_keys(p, v, ("value", "kind", "min", "max"))
        kind = v.get("kind", "number")
        if kind not in PARAMETER_KINDS:
            raise DesignError(f"{p}.kind", f"expected one of {', '.join(PARAMETER_KINDS)}, got {fmt(kind)}")
        lo = check_number(f"{p}.min", v["min"]) if "min" in v else None
        hi = check_number(f"{p}.max", v["max"]) if "max" in v else None
        if lo is not None and hi is not None and lo > hi:
            raise DesignError(
                f"{p}.min",
                f"min {fmt(v['min'])} is above max {fmt(v['max'])}: the parameter's "
                "range is reversed (min must be <= max)",
            )
        if "value" not in v:
            raise DesignError(f"{p}.value", "missing")
        check_parameter_value(f"{p}.value", kind, v["value"], lo, hi)
        out[name] = Parameter(name, float(v["value"]), kind, lo, hi)
    return out


def parse_design(obj: dict) -> Design:
    """Validate a design object (parsed JSON) and build a :class:`Design`."""
    expect_dict("", obj, "a design object")
    top = (
        "format",
        "version",
        "name",
        "description",
        "body",
        "materials",
        "mirror",
        "skirt",
        "refine_edge_length",
        "solver",
        "transfer_solver",
        "parameters",
        "keypoints",
        "lines",
        "garments",
    )
    expect_keys("", obj, top)
    if obj.get("format") != FORMAT:
        raise DesignError("format", f"expected {FORMAT!r}, got {fmt(obj.get('format'))}")
    if obj.get("version") != VERSION:
        raise DesignError(
            "version",
            f"expected {VERSION} (this version of EASE reads design version {VERSION}), got {fmt(obj.get('version'))}",
        )
    name = obj.get("name")
    if not isinstance(name, str) or not name.strip():
        raise DesignError("name", f"expected a non-empty string, got {fmt(name)}")
    desc = obj.get("description", "")
    if not isinstance(desc, str):
        raise DesignError("description", f"expected a string, got {fmt(desc)}")
    body = _parse_body("body", obj.get("body", {}))
    materials = parse_materials("materials", obj.get("materials", {}))
    for k in ("mirror", "skirt"):
        if not isinstance(obj.get(k, False), bool):
            raise DesignError(k, f"expected true or false, got {fmt(obj.get(k))}")
    rel = obj.get("refine_edge_length", 0.01)
    if rel is not None:
        rel = check_number(
            "refine_edge_length",
            rel,
            REFINE_EDGE_MIN,
            REFINE_EDGE_MAX,
            what="an edge length in metres (or null; finer meshes do not drape)",
        )
    solver = obj.get("solver")
    if solver is not None and solver not in SOLVER_CONFIGS:
        raise DesignError(
            "solver", f"expected a solver configuration ({', '.join(SOLVER_CONFIGS)}) or null, got {fmt(solver)}"
        )
    transfer_solver = obj.get("transfer_solver")
    if transfer_solver is not None and transfer_solver not in TRANSFER_SOLVERS:
        raise DesignError(
            "transfer_solver",
            f"expected {' or '.join(repr(t) for t in TRANSFER_SOLVERS)} or null, got {fmt(transfer_solver)}",
        )
    params = _parse_parameters("parameters", obj.get("parameters", {}))
    kps_raw = expect_dict("keypoints", obj.get("keypoints", {}), "an object name -> keypoint")
    keypoints = {}
    for k, v in kps_raw.items():
        check_name(f"keypoints.{k}", k)
        keypoints[k] = check_keypoint(f"keypoints.{k}", v, params)
    shared = _named_list("lines", obj.get("lines", []), "line", lambda p, x: _parse_line(p, x, params))
    garments = _named_list(
        "garments", obj.get("garments"), "garment", lambda p, x: _parse_garment(p, x, params, shared), required=True
    )
    skirt = bool(obj.get("skirt", False))
    design = Design(
        name=name,
        body=body,
        materials=materials,
        parameters=params,
        keypoints=keypoints,
        lines=shared,
        garments=garments,
        mirror=bool(obj.get("mirror", False)),
        skirt=skirt,
        refine_edge_length=rel,
        description=desc,
        solver=solver,
        transfer_solver=transfer_solver,
    )
    check_names_unique(design)
    check_seam_names(design)
    return design


# A design with per-triangle ease over a dense body is a few MB; JSON nests about 8 deep.
MAX_DESIGN_BYTES = 64 << 20
MAX_DEPTH = 64


def check_depth(obj, limit: int = MAX_DEPTH) -> None:
    """Refuse JSON nested deeper than ``limit`` (lists and objects), naming the first element too deep."""
    stack = [(obj, "", 0)]
    while stack:
        value, path, depth = stack.pop()
        if depth > limit:
            raise DesignError(
                path, f"nested more than {limit} levels deep; a design is a few levels of objects and lists"
            )
        if isinstance(value, dict):
            stack.extend((v, f"{path}.{k}" if path else str(k), depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value))


def _design_text(p: Path) -> str:
    try:
        if p.stat().st_size > MAX_DESIGN_BYTES:
            raise DesignError("", f"{p}: over {MAX_DESIGN_BYTES >> 20} MiB; not a design file")
        data = p.read_bytes()
    except OSError as exc:
        raise DesignError("", f"{p}: cannot read ({exc.strerror})") from None
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise DesignError("", f"{p}: UTF-16 text; save the design as UTF-8")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise DesignError(
            "",
            f"{p}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}, "
            "e.g. latin-1); save the design as UTF-8",
        ) from None


def _names_file(text: str) -> bool:
    """Whether ``text`` is the path of an existing file (False for JSON text too long to be a path)."""
    try:
        return "\n" not in text and Path(text).is_file()
    except (OSError, ValueError):
        return False


def load_design(source: Union[str, Path, dict, Design]) -> Design:
    """Load and validate a design from a path, a JSON string, a dict or a Design.

    Raises
    ------
    DesignError : naming the JSON path of the first invalid element (or the
        file: not UTF-8, not JSON, nested more than :data:`MAX_DEPTH` deep,
        over :data:`MAX_DESIGN_BYTES`).
    """
    if isinstance(source, Design):
        return source
    if isinstance(source, dict):
        check_depth(source)
        return parse_design(copy.deepcopy(source))
    if isinstance(source, str) and source.lstrip().startswith("{") and not _names_file(source):
        # JSON text; a path is a path, even one starting with "{" ("{summer} skirt.json")
        text = source
        where = "<string>"
        if "\n" not in source and '"' not in source:  # no JSON text has neither: a file name, name it
            raise DesignError("", f"design file not found: {source}")
    else:
        p = Path(source)
        if not p.is_file():
            raise DesignError("", f"design file not found: {p}")
        text = _design_text(p)
        where = str(p)
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DesignError("", f"{where}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except RecursionError:
        raise DesignError("", f"{where}: nested more than {MAX_DEPTH} levels deep") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise DesignError("", f"{where}: not valid JSON ({str(exc)[:80]})") from None
    try:
        check_depth(obj)
        design = parse_design(obj)
    except DesignError as exc:
        if where != "<string>":  # name the file too; path and message stay as they are
            exc.args = (f"{where}: {exc}",)
        raise
    if where != "<string>":
        # an OBJ template's files are named relative to the design file, for every caller
        from ..body.registry import resolve_body_files

        design.body.update(resolve_body_files(design.body, p.parent))
    return design


def save_design(design: Design, path: Union[str, Path]) -> Path:
    """Write ``design`` as JSON atomically (validated again first)."""
    from ..fileio import write_json

    obj = design.to_json()
    parse_design(copy.deepcopy(obj))
    return write_json(path, obj, indent=1)
