"""Published size charts (women's and men's, EN 13402-3) and their fits on Anny.

A chart names sizes and gives, per size, the body measurements (cm) a garment
of that size is made for; :func:`core.body.sizes.size_shape` turns a chart size
into a shape of the body model (the stored fit below for Anny, a fit made once
per process for other models). The current chart (:data:`core.body.sizes.SIZE_CHART`,
Anny's own bodies around the reference shape) stays the default; these are
``"women"`` and ``"men"``, named ``women:M`` on the command line.

Sources, exactly what was used (the standard's text itself is paywalled and was
not read):

- EN 13402-3:2004/2005 "Size designation of clothes - Part 3: Measurements and
  intervals" (CEN). Its women's bust-girth series, 74 to 102 cm in steps of 4 cm
  and 107 to 131 cm in steps of 6 cm, as the CRAN package *Anthropometry*
  documents it (``bustSizesStandard``, https://search.r-project.org/CRAN/refmans/
  Anthropometry/html/bustSizesStandard.html, citing "European Committee for
  Standardization. Size designation of clothes. Part 3: Measurements and
  intervals (2005)"). Summaries of EN 13402 (e.g. the "Garment Size Guide" at
  techallusa.blogspot.com, 2014) state that the women's bust, waist and hip
  intervals step by 4 cm (5 cm hip / 6 cm bust and waist for large sizes), the
  men's chest and waist by 4 cm, and quote the standard's example designation
  88-72-96 (bust-waist-hip).
- The EN 13402-3 letter codes (XS..XL) as bands of those girths, as two public
  transcriptions of the standard's letter-code table give them: women's bust
  XS 74-82, S 82-90, M 90-98, L 98-107, XL 107-119; men's chest S 86-94,
  M 94-102, L 102-110, XL 110-118. The girths of a size here are the band
  midpoints the same transcriptions list (women's waist 62/70/78/86.5/97, hip
  86/94/102/110.5/120; men's waist 70/78/86/94/102), which equal the
  standard's example 88-72-96 moved by its 4 cm steps (waist = bust - 16,
  hip = bust + 8 up to bust 102).
- Height is not part of the letter-code table (EN 13402 treats it as a
  separate dimension) and no verifiable EN height table was found; every size
  of a chart is held at one height, 176 cm (Anny's female reference body is
  176.9 cm), so a chart size changes girths, not stature, as the default chart does.
- Men's hip girth has no letter-code column (men's bottoms are sized by waist):
  the men's sizes have no hip target, and the fit holds the hip near the
  starting body's (see :func:`core.body.sizes.fit_measurements`).

Sizes Anny cannot reach within 1 cm are left out rather than fitted badly:
women's XS (78/62/86 cm) needs a slimmer bust than Anny's lightest adult woman
up to ~50 years (age <= 0.8: best bust +1.5 cm even at age 0.9; only a ~90-year-old
body reaches it), women's XL (113/97/120 cm) more girth than Anny's heaviest
(weight 1: best 109.8/99.7/119.2 cm), men's XS (82/70 cm) a slimmer male than
Anny's lightest (best 84.7 cm chest, 77.0 cm waist). The women's fits may also move
Anny's ``cupsize`` (0 .. 1 moves a women's M bust 89.8 .. 103.4 cm, waist and hip
still), which does not bring these sizes in reach either: at 176 cm the XS bust stays
at 81.9 cm with the smallest cup (the rib cage, not the breast, sets it), and XL's
23 cm drop from hip to waist is beyond Anny's heaviest women (best with cupsize 0.8:
112.6/98.2/116.8 cm). The stored S, M and L fits keep the average cup (0.5).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Mapping, Tuple

CHART_HEIGHT_CM = 176.0

# Adult ages only (Anny: 2/3 = young adult ~25 years, 0.8 ~ 50 years): a size fit may use
# age (girth distribution shifts with it) but never turns the body into a teenager or a 90-year-old.
ADULT_AGE = (0.67, 0.8)


@dataclass(frozen=True)
class SizeChart:
    """A size chart: sizes -> target measurements, and how they are fitted on a body model.

    Attributes
    ----------
    name : the chart's name (``"women"``).
    title : one line naming the chart and its source.
    sizes : size name -> {height, chest, waist[, hip]} in cm, in size order.
    start : shape parameters the fit starts from and does not move (the gender phenotype).
    parameters : shape parameters the fit moves (where the model has them).
    bounds : parameter -> (lo, hi) narrowing its range during the fit.
    fitted : model name -> size -> shape parameters, stored fits (re-fitted by the tests).
    """
    name: str
    title: str
    sizes: Mapping[str, Mapping[str, float]]
    start: Mapping[str, float] = field(default_factory=dict)
    parameters: Tuple[str, ...] = ()
    bounds: Mapping[str, Tuple[float, float]] = field(default_factory=dict)
    fitted: Mapping[str, Mapping[str, Mapping[str, float]]] = field(default_factory=dict)


def _women(bust, waist, hip):
    return {"height": CHART_HEIGHT_CM, "chest": bust, "waist": waist, "hip": hip}


def _men(chest, waist):
    return {"height": CHART_HEIGHT_CM, "chest": chest, "waist": waist}


FIT_PARAMETERS = ("height", "weight", "muscle", "proportions", "age")

WOMEN = SizeChart(
    name="women",
    title="women's EN 13402-3 letter codes S-L (bust/waist/hip band midpoints), height 176 cm",
    sizes={"S": _women(86.0, 70.0, 94.0), "M": _women(94.0, 78.0, 102.0), "L": _women(102.0, 86.5, 110.5)},
    start={"gender": 1.0}, parameters=FIT_PARAMETERS + ("cupsize",), bounds={"age": ADULT_AGE},
    fitted={"anny": {
        "S": {"gender": 1.0, "age": 0.701, "muscle": 0.7032, "weight": 0.0523, "height": 0.5031, "proportions": 0.9899},
        "M": {"gender": 1.0, "age": 0.67, "muscle": 0.43, "weight": 0.7422, "height": 0.4863, "proportions": 0.3837},
        "L": {"gender": 1.0, "age": 0.7069, "muscle": 0.316, "weight": 1.0, "height": 0.48, "proportions": 0.0},
    }},
)

MEN = SizeChart(
    name="men",
    title="men's EN 13402-3 letter codes S-XL (chest/waist band midpoints), height 176 cm",
    sizes={"S": _men(90.0, 78.0), "M": _men(98.0, 86.0), "L": _men(106.0, 94.0), "XL": _men(114.0, 102.0)},
    start={"gender": 0.0}, parameters=FIT_PARAMETERS, bounds={"age": ADULT_AGE},
    fitted={"anny": {
        "S": {"gender": 0.0, "age": 0.7254, "muscle": 0.6163, "weight": 0.0, "height": 0.3654, "proportions": 1.0},
        "M": {"gender": 0.0, "age": 0.738, "muscle": 0.4262, "weight": 0.5776, "height": 0.3663, "proportions": 0.6421},
        "L": {"gender": 0.0, "age": 0.67, "muscle": 0.023, "weight": 0.5013, "height": 0.3581, "proportions": 0.0},
        "XL": {"gender": 0.0, "age": 0.67, "muscle": 0.0519, "weight": 0.6552, "height": 0.3561, "proportions": 0.0},
    }},
)

PUBLISHED: Dict[str, SizeChart] = {c.name: c for c in (WOMEN, MEN)}
