"""The materials of a design: fabric, stretch tolerances, gathered seams, seam allowances, notches.

:class:`Materials` is the one owner of their defaults; every stage that needs
one (the pattern solver's gather threshold and tolerances, the export's seam
allowance and notch spacing, the add-on's panels) reads it from here. A
design keeps its materials as the plain dict of its file (``design.materials``,
the defaults of ``fabric``, ``eps_weft`` and ``eps_warp`` filled in by the
parser); :meth:`Materials.from_dict` / :meth:`Materials.of` give the typed view
with every default applied, and :meth:`Materials.edit` makes the validated
edits the add-on's panels make.

Fields of the ``materials`` object (metres):

``fabric``        preset name, one of :data:`FABRICS` (default ``"cotton"``)
``eps_weft``      weft stretch tolerance >= 1 (default 1.1: 10 % stretch)
``eps_warp``      warp stretch tolerance >= 1 (default: ``eps_weft``)
``gathered``      true (every seam) or a list of seam line names sewn gathered, not flat
``gather_above``  gather any seam whose sides' ease demands differ by more than this
                  fraction (default 0.2); null: never
``export``        ``{"allowance": m | {"default", "hem", "fold", seam line: m},
                  "notch_spacing": m}``: seam allowance 0..0.1 m (default 1 cm,
                  hems 2 cm, folds 0) and notch spacing (default 10 cm)
``color``         the fabric's colour in renders: ``"#rrggbb"`` or ``[r, g, b]`` in 0..1
                  (sRGB), or ``{garment: colour}``; default: the fabric preset's
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Dict, Mapping, Optional, Tuple, Union

from ..errors import DesignError
from .checks import check_name, check_number, expect_dict, expect_keys, fmt, is_number
from .naming import mirrored_name

FABRIC = "cotton"
# The fabric presets a design may name; their physical values are the drape's
# (core.drape.materials.PRESETS, one per name here).
FABRICS = ("cotton", "jersey", "denim", "silk", "wool")
EPS_WEFT = 1.1  # weft stretch tolerance: 10 % stretch
GATHER_ABOVE = 0.2  # gather a seam whose sides' ease demands differ by more than 20 %
ALLOWANCE = 0.01  # m, seam allowance
HEM = 0.02  # m, hem allowance
FOLD = 0.0  # m, a fold has no allowance
NOTCH_SPACING = 0.10  # m between notches along a seam
EXPORT_ALLOWANCE_KEYS = ("default", "hem", "fold")

_KEEP = object()


@dataclass(frozen=True)
class Materials:
    """The materials of a design with every default applied (read-only view).

    Attributes
    ----------
    fabric : str, the fabric preset.
    eps_weft, eps_warp : float >= 1, stretch tolerances (1.1 = 10 % stretch).
    gathered : bool or tuple of seam line names, seams sewn gathered.
    gather_above : float or None, ease-demand difference above which a seam is gathered.
    allowances : dict ``{"default", "hem", "fold", seam line: m}``, seam allowances (m).
    notch_spacing : float, m between notches along a seam (0: seam ends only).
    """

    fabric: str = FABRIC
    eps_weft: float = EPS_WEFT
    eps_warp: float = EPS_WEFT
    gathered: Union[bool, Tuple[str, ...]] = False
    gather_above: Optional[float] = GATHER_ABOVE
    allowances: Dict[str, float] = field(default_factory=lambda: {"default": ALLOWANCE, "hem": HEM, "fold": FOLD})
    notch_spacing: float = NOTCH_SPACING

    @classmethod
    def from_dict(cls, materials: Optional[Mapping]) -> "Materials":
        """The typed view of a materials dict (a design's, a cut's or a pattern's); None: all defaults."""
        m = dict(materials or {})
        eps_weft = float(m.get("eps_weft", EPS_WEFT))
        gathered = m.get("gathered", False)
        export = m.get("export") or {}
        widths = {"default": ALLOWANCE, "hem": HEM, "fold": FOLD}
        widths.update(_widths(export.get("allowance")))
        return cls(
            fabric=str(m.get("fabric", FABRIC)),
            eps_weft=eps_weft,
            eps_warp=float(m.get("eps_warp", eps_weft)),
            gathered=gathered if isinstance(gathered, bool) else tuple(gathered),
            gather_above=m.get("gather_above", GATHER_ABOVE),
            allowances=widths,
            notch_spacing=float(export.get("notch_spacing", NOTCH_SPACING)),
        )

    @classmethod
    def of(cls, design) -> "Materials":
        """The materials of a :class:`core.design.types.Design` (or anything with a ``materials`` dict)."""
        return cls.from_dict(design.materials)

    @staticmethod
    def edit(
        materials: Optional[Mapping],
        *,
        allowance=_KEEP,
        hem=_KEEP,
        notch_spacing=_KEEP,
        gather_above=_KEEP,
        eps_weft=_KEEP,
        eps_warp=_KEEP,
        fabric=_KEEP,
    ) -> dict:
        """The materials dict ``materials`` with the given fields changed, validated.

        Parameters
        ----------
        materials : dict, the design's materials (``design.materials``).
        allowance, hem : float, m, the default seam and hem allowance.
        notch_spacing : float, m.
        gather_above : float or None (never gather).
        eps_weft, eps_warp : float >= 1.
        fabric : str.

        The export settings (``allowance``, ``hem``, ``notch_spacing``) are one
        group, as the add-on's Export panel shows them: when any one given
        differs from what the design does now (its value or the default), all
        of them given are written into ``materials.export`` (per-seam widths
        are kept); when none differs, nothing is written. The other fields
        are written only when they differ, so an edit that changes nothing
        returns a dict equal to ``materials``.

        Returns
        -------
        dict, a new materials dict (``materials`` is not changed).

        Raises
        ------
        DesignError naming the field (``materials.export.notch_spacing``, ...)
        of an invalid value.
        """
        out = copy.deepcopy(dict(materials or {}))
        now = Materials.from_dict(out)
        exp = copy.deepcopy(out.get("export") or {})
        old = _widths(exp.get("allowance"))
        given = {k: v for k, v in (("default", allowance), ("hem", hem)) if v is not _KEEP}
        if any(now.allowances[k] != v for k, v in given.items()) or (
            notch_spacing is not _KEEP and notch_spacing != now.notch_spacing
        ):
            if given:
                exp["allowance"] = dict(old, **given)
            if notch_spacing is not _KEEP:
                exp["notch_spacing"] = notch_spacing
            out["export"] = exp
        for key, value in (
            ("gather_above", gather_above),
            ("eps_weft", eps_weft),
            ("eps_warp", eps_warp),
            ("fabric", fabric),
        ):
            if value is not _KEEP and value != getattr(now, key):
                out[key] = value
        return parse_materials("materials", out)


def _widths(allowance) -> Dict[str, float]:
    """A file's ``export.allowance`` (absent, one width, or per seam) as a dict of widths."""
    if allowance is None:
        return {}
    return dict(allowance) if isinstance(allowance, Mapping) else {"default": float(allowance)}


def parse_materials(path: str, obj) -> dict:
    """Validate a ``materials`` object; the result has ``fabric``, ``eps_weft`` and ``eps_warp`` filled in
    (their defaults when absent) and the optional fields as given."""
    expect_dict(path, obj, "materials {fabric, eps_weft, eps_warp, export, gathered, gather_above, color}")
    expect_keys(path, obj, ("fabric", "eps_weft", "eps_warp", "export", "gathered", "gather_above", "color"))
    fabric = obj.get("fabric", FABRIC)
    if not isinstance(fabric, str) or fabric.strip().lower() not in FABRICS:
        raise DesignError(f"{path}.fabric", f"expected a fabric preset ({', '.join(FABRICS)}), got {fmt(fabric)}")
    out = {"fabric": fabric}
    out["eps_weft"] = check_number(f"{path}.eps_weft", obj.get("eps_weft", EPS_WEFT), 1.0, 4.0, what="a tolerance")
    # the warp tolerance follows the weft's unless the design sets its own
    out["eps_warp"] = check_number(
        f"{path}.eps_warp", obj.get("eps_warp", out["eps_weft"]), 1.0, 4.0, what="a tolerance"
    )
    if "export" in obj:
        out["export"] = _parse_export(f"{path}.export", obj["export"])
    if "gathered" in obj:
        g = obj["gathered"]
        if isinstance(g, bool):
            out["gathered"] = g
        elif isinstance(g, list) and all(isinstance(x, str) for x in g):
            for k, x in enumerate(g):
                for part in x.partition("#")[0].split("."):
                    check_name(f"{path}.gathered[{k}]", part)
            out["gathered"] = list(g)
        else:
            raise DesignError(f"{path}.gathered", f"expected true, false or a list of seam line names, got {fmt(g)}")
    if "gather_above" in obj:
        a = obj["gather_above"]
        out["gather_above"] = (
            None
            if a is None
            else check_number(
                f"{path}.gather_above",
                a,
                0.01,
                10.0,
                what="a fraction (0.25: gather a seam whose sides' ease demands differ by more than 25 %) or null",
            )
        )
    if "color" in obj:
        c = obj["color"]
        if isinstance(c, dict):
            for k, v in c.items():
                check_name(f"{path}.color.{k}", k)
                _check_color(f"{path}.color.{k}", v)
            out["color"] = dict(c)
        else:
            out["color"] = _check_color(f"{path}.color", c)
    return out


def _check_color(path: str, value):
    """A render colour: ``"#rrggbb"`` or ``[r, g, b]`` in 0..1 (sRGB)."""
    if (
        isinstance(value, str)
        and len(value) == 7
        and value[0] == "#"
        and all(ch in "0123456789abcdefABCDEF" for ch in value[1:])
    ):
        return value
    if isinstance(value, list) and len(value) == 3 and all(is_number(x) and 0.0 <= x <= 1.0 for x in value):
        return list(value)
    raise DesignError(path, f'expected a colour "#rrggbb" or [r, g, b] in 0..1, got {fmt(value)}')


def _parse_export(path, obj):
    """``materials.export``: seam allowance (m, a number or per seam) and notch spacing (m)."""
    expect_dict(path, obj, "an object {allowance, notch_spacing}")
    expect_keys(path, obj, ("allowance", "notch_spacing"))
    out = {}
    if "allowance" in obj:
        a = obj["allowance"]
        if is_number(a):
            out["allowance"] = check_number(f"{path}.allowance", a, 0.0, 0.1, what="a seam allowance in metres")
        else:
            expect_dict(f"{path}.allowance", a, 'a width in metres or {"default", "hem", "fold", <seam line>: m}')
            widths = {}
            for k, v in a.items():
                if k not in EXPORT_ALLOWANCE_KEYS:
                    for part in str(k).partition("#")[0].split("."):
                        check_name(f"{path}.allowance.{k}", part)
                widths[k] = check_number(f"{path}.allowance.{k}", v, 0.0, 0.1, what="a seam allowance in metres")
            out["allowance"] = widths
    if "notch_spacing" in obj:
        out["notch_spacing"] = check_number(
            f"{path}.notch_spacing",
            obj["notch_spacing"],
            0.0,
            1.0,
            what="a notch spacing in metres (0: seam ends only)",
        )
    return out


def seam_line_names(design) -> set:
    """Every name a seam line answers to: its own, its mirror's, and both as ``garment.line``."""
    seams = set()
    for gname, lines in [(None, design.lines)] + [(g.name, g.lines) for g in design.garments]:
        for line in lines:
            if line.role != "seam":
                continue
            m = mirrored_name(line.name) if design.mirror else None
            for n in (line.name, m):
                if n:
                    seams.add(n)
                    if gname:
                        seams.add(f"{gname}.{n}")
    return seams


def check_seam_names(design) -> None:
    """Per-seam allowance keys of ``materials.export`` and the ``materials.gathered`` list must name seam
    lines (or their mirrors)."""
    allowance = (design.materials.get("export") or {}).get("allowance")
    gathered = design.materials.get("gathered")
    if not isinstance(allowance, dict) and not isinstance(gathered, list):
        return
    seams = seam_line_names(design)
    for k, name in enumerate(gathered if isinstance(gathered, list) else []):
        if name.partition("#")[0] not in seams:
            raise DesignError(
                f"materials.gathered[{k}]",
                f"{name!r} is not a seam line of the design; expected one of: "
                f"{', '.join(sorted(seams)) or '(no seam lines)'}",
            )
    for k in allowance if isinstance(allowance, dict) else {}:
        if k in EXPORT_ALLOWANCE_KEYS or k.partition("#")[0] in seams:
            continue
        raise DesignError(
            f"materials.export.allowance.{k}",
            f"not a seam line of the design; expected 'default', 'hem', 'fold' or one of: "
            f"{', '.join(sorted(seams)) or '(no seam lines)'}",
        )
