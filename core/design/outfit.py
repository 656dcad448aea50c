"""Outfits: garments worn one over another, listed inner first (:func:`load_outfit`).

An outfit file is JSON::

    {"format": "ease-outfit", "version": 1, "name": "shirt tucked in trousers",
     "body": {...},                     # optional: every layer's design is cut on this body
     "layers": [{"design": "shirt_long_sleeve", "tucked": true},
                {"design": "pants.json"}]}

``design`` is a shipped template's name or a design file (relative to the outfit file). The
layers are in wearing order, inner first: each garment drapes over the ones before it. ``tucked``
says how an upper garment meets a lower one: ``true`` (tucked in) puts it under a lower garment
listed after it; an upper garment listed over a lower one is worn over it. An upper garment listed
before a lower garment without ``"tucked": true``, or a tucked one with no lower garment after it,
is refused (the order and the flag must agree). Bad values are refused with the JSON path.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional, Union

from ..errors import DesignError

#: The most layers an outfit may hold.
MAX_LAYERS = 6
_KEYS = {"format", "version", "name", "description", "body", "layers"}
_LAYER_KEYS = {"design", "tucked", "name"}


@dataclass
class Layer:
    """One garment of an outfit: its design (loaded, on the outfit's body), name and tuck."""

    name: str
    design: object  # core.design.Design
    source: str
    tucked: bool = False

    @property
    def kinds(self) -> List[str]:
        return [g.kind for g in self.design.garments]


@dataclass
class Outfit:
    """Garments in wearing order (``layers[0]`` innermost) on one body."""

    name: str
    body: dict
    layers: List[Layer] = field(default_factory=list)

    def to_json(self) -> dict:
        return {
            "format": "ease-outfit",
            "version": 1,
            "name": self.name,
            "body": self.body,
            "layers": [{"name": ly.name, "design": ly.source, "tucked": ly.tucked} for ly in self.layers],
        }


def _fail(path: str, msg: str, where: str = ""):
    raise DesignError(path, f"{where}: {msg}" if where else msg)


def _read(source) -> tuple:
    if isinstance(source, dict):
        return source, None, ""
    p = Path(source)
    if not p.is_file():
        raise DesignError("", f"outfit file not found: {p}")
    try:
        text = p.read_bytes().decode("utf-8")
        return json.loads(text), p.parent, str(p)
    except UnicodeDecodeError:
        raise DesignError("", f"{p}: not UTF-8 text; save the outfit as UTF-8") from None
    except json.JSONDecodeError as exc:
        raise DesignError("", f"{p}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None


def _design_source(value, base: Optional[Path], path: str):
    from .templates import list_templates, template_path

    if not isinstance(value, str) or not value.strip():
        _fail(path, f"expected a template name or a design file, got {value!r}")
    if value in list_templates():
        return template_path(value)
    p = Path(value)
    if not p.is_absolute() and base is not None:
        p = base / p
    if not p.is_file():
        _fail(path, f"no such design file or template: {value!r} (templates: {', '.join(list_templates())})")
    return p


def _load_layer(i: int, raw, base, body) -> Layer:
    from .parser import load_design

    path = f"layers[{i}]"
    if not isinstance(raw, dict):
        _fail(path, f'expected an object {{"design", "tucked"}}, got {type(raw).__name__}')
    extra = sorted(set(raw) - _LAYER_KEYS)
    if extra:
        _fail(f"{path}.{extra[0]}", f"unknown key; a layer has {', '.join(sorted(_LAYER_KEYS))}")
    if "design" not in raw:
        _fail(f"{path}.design", "missing: a template name or a design file")
    src = _design_source(raw["design"], base, f"{path}.design")
    tucked = raw.get("tucked", False)
    if not isinstance(tucked, bool):
        _fail(f"{path}.tucked", f"expected true or false, got {tucked!r}")
    try:
        design = load_design(src)
        if body is not None:
            data = design.to_json()
            data["body"] = body
            design = load_design(data)
    except DesignError as exc:
        raise DesignError(f"{path}.design", str(exc)) from None
    name = raw.get("name", design.name)
    if not isinstance(name, str) or not name.strip():
        _fail(f"{path}.name", f"expected a non-empty string, got {name!r}")
    return Layer(name=name, design=design, source=str(raw["design"]), tucked=tucked)


def _check_order(layers: List[Layer]) -> None:
    names = [ly.name for ly in layers]
    for i, ly in enumerate(layers):
        if names.index(ly.name) != i:
            _fail(f"layers[{i}].name", f"{ly.name!r} is already layers[{names.index(ly.name)}]'s name")
        lower_after = any("lower" in later.kinds for later in layers[i + 1 :])
        if ly.tucked and "upper" not in ly.kinds:
            _fail(f"layers[{i}].tucked", f"only an upper garment is tucked in; {ly.name!r} is {'/'.join(ly.kinds)}")
        if ly.tucked and not lower_after:
            _fail(f"layers[{i}].tucked", "a tucked garment needs a lower garment (trousers, skirt) in a later layer")
        if "upper" in ly.kinds and lower_after and not ly.tucked:
            _fail(
                f"layers[{i}].tucked",
                f'{ly.name!r} is under a lower garment listed after it: set "tucked": true, '
                "or list it after the lower garment to wear it over",
            )


def load_outfit(source: Union[str, Path, dict]) -> Outfit:
    """Load and check an outfit (a path or a dict); DesignError names the JSON path of what is wrong."""
    data, base, where = _read(source)
    try:
        if not isinstance(data, dict):
            _fail("", f"expected a JSON object, got {type(data).__name__}")
        extra = sorted(set(data) - _KEYS)
        if extra:
            _fail(extra[0], f"unknown key; an outfit has {', '.join(sorted(_KEYS))}")
        if data.get("format") != "ease-outfit":
            _fail("format", f'expected "ease-outfit", got {data.get("format")!r}')
        if data.get("version") != 1:
            _fail("version", f"expected 1, got {data.get('version')!r}")
        layers = data.get("layers")
        if not isinstance(layers, list) or not 1 <= len(layers) <= MAX_LAYERS:
            _fail("layers", f"expected a list of 1..{MAX_LAYERS} layers (inner first), got {layers!r:.60}")
        body = data.get("body")
        if body is not None and not isinstance(body, dict):
            _fail("body", f"expected a body object (as in a design), got {body!r:.60}")
        loaded = [_load_layer(i, raw, base, body) for i, raw in enumerate(layers)]
        first = loaded[0].design.body
        for i, ly in enumerate(loaded[1:], 1):
            if ly.design.body != first:
                _fail(
                    f"layers[{i}].design",
                    f'its body {ly.design.body} differs from layers[0]\'s {first}; give the outfit a "body"',
                )
        _check_order(loaded)
        name = data.get("name", " + ".join(ly.name for ly in loaded))
        if not isinstance(name, str) or not name.strip():
            _fail("name", f"expected a non-empty string, got {name!r}")
    except DesignError as exc:
        if where:
            exc.args = (f"{where}: {exc}",)
        raise
    return Outfit(name=name, body=dict(first), layers=loaded)
