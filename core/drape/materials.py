"""Fabric presets for the drape, in physical units.

Membrane stiffnesses are per unit width (N/m: force per metre of fabric edge
for a strain of 1), bending stiffness is a moment per unit width per unit
curvature (N*m), density is areal (kg/m^2). The values sit in the ranges
Kawabata-type measurements give for each fabric; what matters for the drape is
their order: woven cotton barely stretches (< 5 % under its own weight and
handling loads), jersey knit stretches easily across the courses (weft).

Bending is the KES-FB2 bending rigidity B, given in the textile literature in
gf*cm^2/cm: 1 gf*cm^2/cm = 9.80665e-3 N * 1e-4 m^2 / 1e-2 m = 9.80665e-5 N*m
(:data:`GF_CM2_PER_CM`). Sources: Kawabata, S., "The Standardization and
Analysis of Hand Evaluation", 2nd ed., Textile Machinery Society of Japan,
Osaka, 1980 (the KES-F instruments and the unit); Hu, J. and Chan, Y.-F.,
"Effect of fabric mechanical properties on drape", Textile Research Journal
68(1) (1998) 57-64 (KES-F bending and shear against the Cusick drape
coefficient of woven fabrics). The cotton and denim values were calibrated on
the Cusick test with the ``newton`` solver (``docs/drape.md``): cotton
0.05 -> 0.10 gf*cm^2/cm moved its drape coefficient from 52 % to 67 % (10 mm
mesh), denim 0.20 -> 0.61 from 57 % to 77 % (before the solver's clamped hinges and
sub-element buckling; with them cotton reads 66.0 % and denim 81.2 %). The per-fabric KES ranges quoted
beside each preset are the usual orders of magnitude for the class; their
tables were not re-checked against the sources in the session that set them.

With ``solver="pd"`` (the default: Anderson iterations; the Cusick disc's clamp band, the mean of 8
specimens, the released disc's 5 onset frames at 8x the iterations, ``DrapeOptions.onset_frames``;
``benchmarks/results/fabric.md``, seventh session) the presets land in their ranges without a
recalibration: cotton 71.5 % at 10 mm / 72.4 % at 5 mm / 72.2 % at 4x the iterations (8 nodes, bending
length 1.83-1.84 cm), denim 83.6 / 83.4 / 81.6 %, wool 63.1 / 63.6 / 62.8 %, silk 35.6 / 38.0 / 36.0 %, all
with 6-8 nodes and within 2.4 points; cotton solved to 1e-4 of the weight (400 iterations) reads 71.2-71.6
% with 8 nodes. Without the onset frames (sixth session) wool read 55.0 % with 4 nodes, 62.5 % at 4x: its
fold count followed the iteration count (``benchmarks/results/drape_pd.md``, session 8 p1). So the bending values stay those set above.

A design selects a preset by name (``materials.fabric``, one of
:data:`core.design.materials.FABRICS`, checked when the design loads), the CLI with
``--material``. Unknown names raise :class:`core.errors.DrapeError`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Mapping, Optional, Union

import numpy as np

from ..design.materials import FABRICS
from ..errors import DrapeError

#: N*m per gf*cm^2/cm (the KES-FB2 bending rigidity unit)
GF_CM2_PER_CM = 9.80665e-5


@dataclass(frozen=True)
class Material:
    """Cloth material for the XPBD drape.

    Attributes
    ----------
    name : str
    density : float, areal density in kg/m^2.
    stretch_weft, stretch_warp : float, membrane stiffness along the weft and
        the warp (grain line) in N/m.
    shear : float, in-plane shear stiffness in N/m.
    bending : float, bending stiffness in N*m.
    friction : float, Coulomb friction coefficient against the body.
    thickness : float, collision offset from the body surface in metres.
    max_stretch : float, the stretch (fraction) the fabric takes in wear: the drape report's
        ``stretch_limit`` gives the share of the fabric stretched beyond it, and pd's strain limit
        (``DrapeOptions.strain_limit``, off by default) holds the fabric there.
    """

    name: str
    density: float
    stretch_weft: float
    stretch_warp: float
    shear: float
    bending: float
    friction: float
    thickness: float
    max_stretch: float

    def to_json(self) -> dict:
        return asdict(self)


PRESETS = {
    # Shirting poplin: stiff in both grains, warp a little stiffer than weft.
    # Bending 1.0e-5 N*m: B = 0.10 gf*cm^2/cm (KES-FB2; shirting cottons read about 0.05-0.15): the Cusick test
    # with the newton solver gives DC 66.0 % (8 nodes) at 10 mm, 71.0 % (8) at 5 mm, the cantilever 1.88 cm
    # (targets 60-76 %, 5-10 nodes, 1.5-2.5 cm); 0.05 gave 52.2 % and 1.35 cm (before the clamped hinges).
    "cotton": Material(
        "cotton",
        density=0.13,
        stretch_weft=2.0e3,
        stretch_warp=3.0e3,
        shear=30.0,
        bending=1.0e-5,
        friction=0.4,
        thickness=0.003,
        max_stretch=0.05,
    ),
    # Single jersey knit: stretchy across the courses (weft), firmer along the wales.
    "jersey": Material(
        "jersey",
        density=0.18,
        stretch_weft=60.0,
        stretch_warp=200.0,
        shear=15.0,
        bending=5.0e-7,
        friction=0.5,
        thickness=0.003,
        max_stretch=0.4,
    ),
    # Heavy twill: stiff and heavy, bends little. 6.0e-5 N*m: B = 0.61 gf*cm^2/cm (KES-FB2; denims read about
    # 0.3-1.5): the Cusick test with the newton solver gives DC 81.2 % (7 nodes) at 10 mm, 80.9 % (6) at
    # 5 mm (target 70-90 %, 5-10 nodes); 0.20 gave 56.7 % (before the clamped hinges).
    "denim": Material(
        "denim",
        density=0.40,
        stretch_weft=4.0e3,
        stretch_warp=6.0e3,
        shear=80.0,
        bending=6.0e-5,
        friction=0.5,
        thickness=0.004,
        max_stretch=0.03,
    ),
    # Worsted wool suiting / flannel: heavier than shirting, softer in the grain, bends about as much.
    # Bending 1.5e-5 N*m: B = 0.15 gf*cm^2/cm, shear 35 N/m: G = 0.62 gf/(cm*deg) (1 gf/(cm*deg) =
    # 56.2 N/m per radian), 250 g/m^2: KES-F values of the men's-suiting class (Kawabata and Niwa 1989,
    # below; worsted suitings and flannels read about B 0.08-0.20, G 0.4-1.0, W 200-300 g/m^2; not
    # re-checked against the tables in the session that set them). The Cusick test with the newton
    # solver (sub-element buckling, clamped hinges) gives DC 59.4 % (9 nodes) at 10 mm, 58.5 % (9) at 4x the
    # iterations, 62.7 % (8) at 5 mm (target 55-65 %, issue 35); 1.7e-5 gave 61.1 % (8 nodes) at 10 mm,
    # 61.9 % (8) at 4x the iterations, but 65.7 % at 5 mm, above the range.
    "wool": Material(
        "wool",
        density=0.25,
        stretch_weft=1.5e3,
        stretch_warp=2.0e3,
        shear=35.0,
        bending=1.5e-5,
        friction=0.5,
        thickness=0.003,
        max_stretch=0.06,
    ),
    # Light silk charmeuse / habutai: light (70 g/m^2), slippery, floppy, stretchy in the grain for a woven.
    # Bending 1.5e-6 N*m: B = 0.015 gf*cm^2/cm (KES-FB2), a bending length (B/W)^1/3 of 1.29 cm: in the
    # lower half of the range quoted for silk weaves, about 0.01-0.04 gf*cm^2/cm (an order of magnitude,
    # not checked against a table). Source looked at: Matsudaira, M., "Characteristics of mechanical
    # properties and handles of silk filament weaves", Kanazawa University repository (AN00044160,
    # vol. 37, p. 139): KES-FB of silk against other filament weaves, silk "very soft in compression
    # and stretchy", its shear stiffness "extremely small" at small strain; only its abstract could be
    # read, so the membrane (800 / 1200 N/m) and shear (5 N/m) stay the soft values set before.
    # The preset's earlier 2e-7 N*m (0.002 gf*cm^2/cm) lay far below that. With the newton solver
    # (sub-element buckling, clamped hinges) the Cusick test on the 10 mm disc gives DC 31.5 % (8
    # nodes; target 20-40 %, 5-10 nodes); 1.0e-6 gave 26.5 % (10 nodes), 27.9 % (11 nodes) at 4x the
    # iterations, 27.5 % (8) at 5 mm; 2.0e-6 39.0 % (10). Without the cap, 2e-7 read 50.4 / 48.3 %
    # (10 / 5 mm).
    "silk": Material(
        "silk",
        density=0.07,
        stretch_weft=800.0,
        stretch_warp=1.2e3,
        shear=5.0,
        bending=1.5e-6,
        friction=0.2,
        thickness=0.002,
        max_stretch=0.08,
    ),
}

DEFAULT = "cotton"

#: What the textile tests should give for each preset (``ease bench --only fabric``,
#: :mod:`core.drape.textile`): Cusick drape coefficient (%) and nodes (BS 5058 / ISO 9073-9;
#: method: Cusick, G. E., "The measurement of fabric drape", J. Textile Inst. 59 (1968) 253-260),
#: cantilever bending length (cm; ASTM D1388; Peirce, F. T., "The handle of cloth as a measurable
#: quantity", J. Textile Inst. 21 (1930) T377-T416: flexural rigidity G = W c^3). The ranges are
#: those issue 35 gives (cotton 60-76 %, measured there 68.4 %; silk 20-40 %; denim 70-90 %;
#: woven fabrics 5-10 nodes; cotton shirting 1.5-2.5 cm); the per-fabric survey they come from
#: is not cited in the issue and was not checked in this session. Wool: about 55-65 % (issue 35;
#: KES-F values of suitings: Kawabata, S. and Niwa, M., "Fabric performance in clothing and
#: clothing manufacture", J. Textile Inst. 80(1) (1989) 19-50; drape of wool fabrics: Jeong, Y. J.
#: and Phillips, D. G., "A study of fabric-drape behaviour with image analysis. Part II", J.
#: Textile Inst. 89(1) (1998) 70-79; neither re-checked in the session that set the preset).
#: Jersey: no target yet (the issue asks for a published knit measurement; none was found in the
#: stored pages searched, three times: the stored copies of Sanad 2013, Pan et al. 2019, Gider 2004,
#: Jeong and Phillips 1998, Kuijpers 2017, Eryuruk and Kalaoglu 2016 (IJCST 28(4), 12 elastane
#: single jerseys, drape measured) and Bajaj 2024 (silk/viscose knits) hold only their opening pages,
#: no DC table). The one single-jersey figure seen, DC 18-31 % at 96.8-208.8 g/m^2, is second-hand,
#: from a 25 cm specimen (not Cusick's 30 cm) in an uncited note on GitHub: not usable as a target.
TARGETS = {
    "cotton": {"dc_pct": (60.0, 76.0), "nodes": (5, 10), "bending_length_cm": (1.5, 2.5)},
    "silk": {"dc_pct": (20.0, 40.0), "nodes": (5, 10)},
    "denim": {"dc_pct": (70.0, 90.0), "nodes": (5, 10)},
    "wool": {"dc_pct": (55.0, 65.0), "nodes": (5, 10)},
    "jersey": {},
}

_POSITIVE = ("density", "stretch_weft", "stretch_warp", "shear", "thickness")
# Upper bounds far beyond any textile: above them the input is a unit mistake.
_LIMITS = {
    "density": 10.0,
    "stretch_weft": 1.0e6,
    "stretch_warp": 1.0e6,
    "shear": 1.0e6,
    "bending": 1.0,
    "friction": 5.0,
    "thickness": 0.05,
}


def names() -> list:
    """Names of the presets (the design's :data:`~core.design.materials.FABRICS`)."""
    return sorted(FABRICS)


def validate(material: Material) -> Material:
    """Check every field is finite and in its physical range.

    Raises
    ------
    DrapeError naming the material field and the expected range.
    """
    for key, hi in _LIMITS.items():
        value = getattr(material, key)
        if not np.isfinite(value):
            raise DrapeError(f"material {material.name!r}: {key} = {value} is not a finite number")
        lo_ok = value > 0 if key in _POSITIVE else value >= 0
        if not lo_ok or value > hi:
            lo = "> 0" if key in _POSITIVE else ">= 0"
            raise DrapeError(
                f"material {material.name!r}: {key} = {value:g} is outside the physical range ({lo} and <= {hi:g})"
            )
    return material


def get_material(spec: Union[None, str, Material, Mapping] = None, overrides: Optional[Mapping] = None) -> Material:
    """Resolve a material: a preset name, a :class:`Material`, or a dict.

    Parameters
    ----------
    spec : None (the default preset), a preset name, a Material, or a mapping
        with ``"fabric"`` (preset name) and/or any Material field to override.
    overrides : optional mapping of Material fields to override.

    Returns
    -------
    Material, validated.
    """
    if spec is None:
        mat = PRESETS[DEFAULT]
    elif isinstance(spec, Material):
        mat = spec
    elif isinstance(spec, str):
        key = spec.strip().lower()
        if key not in PRESETS:
            raise DrapeError(f"unknown material {spec!r}; presets: {', '.join(names())}")
        mat = PRESETS[key]
    elif isinstance(spec, Mapping):
        spec = dict(spec)
        base = spec.pop("fabric", None) or spec.pop("name", None)
        mat = get_material(base)
        overrides = {**spec, **(overrides or {})}
    else:
        raise DrapeError(f"material must be a preset name, a Material or a dict, not {type(spec).__name__}")
    if overrides:
        fields = set(Material.__dataclass_fields__)
        unknown = sorted(set(overrides) - fields)
        if unknown:
            raise DrapeError(f"unknown material field(s) {', '.join(unknown)}; fields: {', '.join(sorted(fields))}")
        try:
            mat = replace(mat, **{k: (str(v) if k == "name" else float(v)) for k, v in overrides.items()})
        except (TypeError, ValueError) as exc:
            raise DrapeError(f"material override: {exc}") from None
    return validate(mat)
