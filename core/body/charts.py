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
  M 94-102, L 102-110, XL 110-118 (men's XS, 82/70 cm, is the band below S by the
  same 8 cm chest and waist steps). The girths of a size here are the band
  midpoints the same transcriptions list (women's waist 62/70/78/86.5/97, hip
  86/94/102/110.5/120; men's waist 70/78/86/94/102), which equal the
  standard's example 88-72-96 moved by its 4 cm steps (waist = bust - 16,
  hip = bust + 8 up to bust 102).
- Height is not part of the letter-code table (EN 13402 treats it as a separate
  dimension; no EN height table was found). The heights come from German size
  tables, which give one per size.
  Women's: 168 cm for every size. The German women's "Normalgrößen" hold one body
  height for a whole series (168 cm; "Kurzgrößen" 160, "Langgrößen" 176 cm), as
  style-engineers.com, "Größentabellen: Damengrößen & Sondergrößen für Frauen"
  (August 2012, http://www.style-engineers.com/2012/08/groessentabellen-damengroessen-
  sondergroessen-fuer-frauen/) states; the Hohenstein institute, which publishes the
  German body-measurement tables, gives the same 1.68 m for women's size 38 (interview
  with Rose-Marie Riedl, jetzt.de, "Vermiss mich! Warum Jungs oft keine passenden
  Kleider finden", https://jetzt.de/interview/vermiss-mich-warum-jungs-oft-keine-
  passenden-kleider-finden-411500); Universal-Lexikon (2012, "Konfektionsgrößen")
  also puts normal figures at 168 cm (its short and long series, 162 and 174 cm, differ).
  Men's: height grows with the size (:data:`MEN_HEIGHT_BY_CHEST`), from the table of
  German men's sizes 42-64 at https://gist.github.com/rixx/c54f8b52dbe5d84fe42a3289d253e80b
  (height 166, 168, 170 ... 188 cm; chest 80, 86, 90, 94 ... 126 cm; waist 70, 74,
  78 ... 114 cm; it names a source the stored copy does not show). Its sizes 46, 50,
  54 and 58 have exactly the chest/waist of the chart's S, M, L and XL (90/78 ...
  114/102 cm), so S..XL take its heights 170, 174, 178 and 182 cm; XS (chest 82 cm)
  takes 166.7 cm, interpolated between sizes 42 (80 cm, 166) and 44 (86 cm, 168). A
  second published table (FWF clothing sizes, https://cdn.shopify.com/s/files/1/1668/
  0297/files/FWF_Clothing_Sizes.pdf: men's 44-64 at 168, 171, 174, 177, 180, 182 ...
  cm for chest 88, 92, 96, 100, 104, 108 ... cm) puts the same chests 0.5-3 cm taller.
- Men's hip girth has no letter-code column (men's bottoms are sized by waist):
  the men's sizes have no hip target, and the fit holds the hip near the
  starting body's (see :func:`core.body.sizes.fit_measurements`).

Every size of both charts is fitted within 1 cm of each target and of its height, the girths
measured as a tailor measures (:mod:`core.body.tape`, ISO 8559-1: bust at the bust points, natural
waist, hip at the buttocks): the stored fits below are made by :func:`core.body.sizes.chart_tape_fit`
(phenotypes, the local change of each girth given and the thigh's, the thighs kept apart). The
history below (:func:`core.body.sizes.chart_fit`, :data:`RESTARTS`) is that of the earlier fits by
the chart measures of :mod:`core.body.measure`, which other body models are still fitted by. The women's fits may move Anny's ``cupsize`` (0 .. 1 moves a women's M bust
89.8 .. 103.4 cm, waist and hip still) where the average cup (0.5) cannot reach a size
(the chart's ``assist``): XS needs the smallest cup (0), L the largest (1); S and M keep
0.5 (with the cup free from the start, the least-squares fit drifts: M ended at cup 0.65,
weight 0.71, a body whose bust is harder to fit than the average-cup M at weight 0.79). At 168 cm women's XS is in reach (at 176 cm its bust stayed >= 81.9 cm); Anny's
``firmness`` is not fitted: it moves the XS bust by < 0.1 cm and brings no size in reach.

Women's XL (113/97/120 cm) and the plus sizes are beyond Anny's phenotypes: their best fit
(every restart, cupsize 1, weight 0.83, muscle 0, age 0.8) was 112.0/99.4/116.5 cm at
168.9 cm, XL's 23 cm drop from hip to waist beyond Anny's heavy women (17.2 cm there):
Anny's weight widens the waist about twice as fast as the hip (weight 0.6 -> 0.83: waist
+14.9, hip +8.0 cm). They are fitted with Anny's local changes (MakeHuman's
``measure-bust-circ``, ``measure-waist-circ`` and ``measure-hips-circ`` modifiers, the chart's
``local``) moving too, last, where the phenotypes miss: XL lands with bust +0.06, waist
-0.10, hips +0.28 of their -1 .. 1 ranges.

The women's plus range (XXL, 3XL, 4XL: bust 119, 125, 131 cm) continues EN 13402-3's
women's bust-girth series beyond XL's 113 cm (107 to 131 cm in steps of 6 cm, the
*Anthropometry* ``bustSizesStandard`` above) with the large-size intervals the summaries state
(waist 6 cm, hip 5 cm a size): 119/103/125, 125/109/130, 131/115/135 cm. The girths are the
standard's; the letter names beyond XL are this chart's (the transcriptions of the letter-code
table that were read stop at XL). Men's XXL (122/110 cm, 186 cm) is the next 8 cm chest and
waist band after XL, and equals German men's size 62 (chest 122, waist 110, height 186 cm) of the
rixx table above, whose sizes 60-64 extend :data:`MEN_HEIGHT_BY_CHEST`; Anny's phenotypes reach it.

The women's 3XL and 4XL were refitted so that every template solves on them (docs/bodies.md):
their thighs had been 1.8 mm apart (the pants' back legs collapsed in the crease under 3XL's
crotch) and 4XL's bust had come from the cup (0.75), which pulled the tops' side seams 3.4-6.4 mm
apart. 3XL: ``chart_tape_fit`` from the women's start, its thigh penalty aimed at 1 cm, without the
underbust local (0.97 cm apart, cup 0.5; refitted with the underbust and 0.7 cm the four-dart
blouse's solve diverged on it). 4XL: ``chart_tape_fit`` as it is
(:data:`core.body.sizes.CHART_THIGH_GAP_CM`, the underbust local) from the earlier 4XL with its cup
at 0.5 (0.68 cm apart, underbust +0.48); refitted from itself it stays. Refitted from itself, 3XL
(its chest 0.56 and height 0.72 cm off, outside the fit's 0.3 cm stop) moves to another body within
1 cm; both land within 1 cm from their phenotypes alone (tests/test_body_charts.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Mapping, Tuple

import numpy as np

# Body height (cm) of the women's sizes: the German women's "Normalgrößen" hold one height
# for every girth (see the module docstring).
WOMEN_HEIGHT_CM = 168.0

# Men's body height (cm) by chest girth (cm), the German men's normal sizes 42..58 (see the
# module docstring); a chart size between two rows takes the height linearly interpolated.
MEN_HEIGHT_BY_CHEST = (
    (80.0, 166.0),
    (86.0, 168.0),
    (90.0, 170.0),
    (94.0, 172.0),
    (98.0, 174.0),
    (102.0, 176.0),
    (106.0, 178.0),
    (110.0, 180.0),
    (114.0, 182.0),
    (118.0, 184.0),
    (122.0, 186.0),
    (126.0, 188.0),
)

# Adult ages only (Anny: 2/3 = young adult ~25 years, 0.8 ~ 50 years): a size fit may use
# age (girth distribution shifts with it) but never turns the body into a teenager or a 90-year-old.
ADULT_AGE = (0.67, 0.8)

# Where a chart fit starts again when its first fit misses: the centres of the cells of Anny's
# piecewise-linear muscle, weight and proportions blends (anchors 0, 0.5, 1). A local fit from the
# average body stays on its side of a kink: from muscle 0.5 the men's XS fit ends at muscle 1
# (chest 83.2, waist 74.5 cm) and the women's XS at muscle 0.8 (bust 79.3 cm), both of which land
# from a start in the low-muscle, low-weight cells.
RESTARTS = tuple(
    {"muscle": m, "weight": w, "proportions": p} for m in (0.25, 0.75) for w in (0.25, 0.75) for p in (0.25, 0.75)
)


@dataclass(frozen=True)
class SizeChart:
    """A size chart: sizes -> target measurements, and how they are fitted on a body model.

    Attributes
    ----------
    name : the chart's name (``"women"``).
    title : one line naming the chart and its source.
    sizes : size name -> {height, chest, waist[, hip]} in cm, in size order.
    start : shape parameters the fit starts from (the gender phenotype, which it does not move).
    parameters : shape parameters the fit moves (where the model has them).
    bounds : parameter -> (lo, hi) narrowing its range during the fit.
    fitted : model name -> size -> shape parameters, stored fits (re-fitted by the tests).
    restarts : partial start shapes a fit that misses is made again from, in order
        (:func:`core.body.sizes.chart_fit`).
    assist : shape parameters held at the start (the model's average) unless the fit
        without them misses from every restart (the women's ``cupsize``: a size the
        average cup reaches keeps it, so the chart's bodies differ by the girths the
        chart gives, not by a cup the least-squares fit drifted to).
    local : the model's local changes (Anny's ``measure-*-circ``) that move too, last, where
        the phenotypes (with ``assist``) miss from every restart: the sizes beyond the reach of
        Anny's phenotypes (the women's XL and up, the men's XXL).
    """

    name: str
    title: str
    sizes: Mapping[str, Mapping[str, float]]
    start: Mapping[str, float] = field(default_factory=dict)
    parameters: Tuple[str, ...] = ()
    bounds: Mapping[str, Tuple[float, float]] = field(default_factory=dict)
    fitted: Mapping[str, Mapping[str, Mapping[str, float]]] = field(default_factory=dict)
    restarts: Tuple[Mapping[str, float], ...] = ()
    assist: Tuple[str, ...] = ()
    local: Tuple[str, ...] = ()


def _women(bust, waist, hip):
    return {"height": WOMEN_HEIGHT_CM, "chest": bust, "waist": waist, "hip": hip}


def _men(chest, waist):
    return {"height": round(float(np.interp(chest, *zip(*MEN_HEIGHT_BY_CHEST))), 1), "chest": chest, "waist": waist}


FIT_PARAMETERS = ("height", "weight", "muscle", "proportions", "age")

# Anny's local changes a chart size beyond the phenotypes' reach moves (also those of
# core.body.sizes.LOCAL_OF_GIRTH): bust, waist, hip girths; the men's chart, without a hip target,
# the first two.
LOCAL_GIRTHS = ("measure-bust-circ-incr", "measure-waist-circ-incr", "measure-hips-circ-incr")

WOMEN = SizeChart(
    name="women",
    title="women's EN 13402-3 letter codes XS-XL (bust/waist/hip band midpoints) and its bust series to 131 cm "
    "(XXL-4XL), height 168 cm (DOB normal sizes)",
    sizes={
        "XS": _women(78.0, 62.0, 86.0),
        "S": _women(86.0, 70.0, 94.0),
        "M": _women(94.0, 78.0, 102.0),
        "L": _women(102.0, 86.5, 110.5),
        "XL": _women(113.0, 97.0, 120.0),
        "XXL": _women(119.0, 103.0, 125.0),
        "3XL": _women(125.0, 109.0, 130.0),
        "4XL": _women(131.0, 115.0, 135.0),
    },
    start={"gender": 1.0},
    parameters=FIT_PARAMETERS,
    bounds={"age": ADULT_AGE},
    restarts=RESTARTS,
    assist=("cupsize",),
    local=LOCAL_GIRTHS,
    fitted={
        "anny": {
            "XS": {
                "gender": 1.0,
                "age": 0.7681,
                "muscle": 0.3887,
                "weight": 0.0,
                "height": 0.422,
                "proportions": 0.5152,
                "cupsize": 0.0,
            },
            "S": {
                "gender": 1.0,
                "age": 0.68,
                "muscle": 0.608,
                "weight": 0.3843,
                "height": 0.4252,
                "proportions": 0.8556,
                "cupsize": 0.5,
                "measure-bust-circ-incr": -0.0009,
                "measure-waist-circ-incr": 0.0204,
                "measure-hips-circ-incr": -0.0038,
            },
            "M": {
                "gender": 1.0,
                "age": 0.67,
                "muscle": 0.3385,
                "weight": 0.7858,
                "height": 0.4121,
                "proportions": 0.3558,
                "cupsize": 0.5,
                "measure-thigh-circ-incr": -0.0003,
                "measure-bust-circ-incr": -0.0189,
                "measure-waist-circ-incr": 0.072,
                "measure-hips-circ-incr": -0.0833,
            },
            "L": {
                "gender": 1.0,
                "age": 0.7464,
                "muscle": 0.0014,
                "weight": 0.6581,
                "height": 0.4347,
                "proportions": 1.0,
                "cupsize": 1.0,
                "measure-thigh-circ-incr": -0.0003,
                "measure-bust-circ-incr": -0.1252,
                "measure-waist-circ-incr": 0.2034,
                "measure-hips-circ-incr": -0.1362,
            },
            "XL": {
                "gender": 1.0,
                "age": 0.7251,
                "muscle": 0.0,
                "weight": 0.8666,
                "height": 0.4218,
                "proportions": 0.8054,
                "cupsize": 1.0,
                "measure-bust-circ-incr": -0.0434,
                "measure-waist-circ-incr": 0.0265,
                "measure-hips-circ-incr": 0.0153,
            },
            "XXL": {
                "gender": 1.0,
                "age": 0.7799,
                "muscle": 0.0,
                "weight": 0.9189,
                "height": 0.4208,
                "proportions": 0.9492,
                "cupsize": 1.0,
                "measure-bust-circ-incr": 0.2005,
                "measure-waist-circ-incr": 0.2109,
                "measure-hips-circ-incr": 0.09,
                "measure-thigh-circ-incr": -0.1916,
            },
            "3XL": {
                "gender": 1.0,
                "age": 0.8,
                "muscle": 0.0351,
                "weight": 0.9949,
                "height": 0.4068,
                "proportions": 1.0,
                "cupsize": 0.5,
                "measure-thigh-circ-incr": -0.6107,
                "measure-bust-circ-incr": 1.0,
                "measure-waist-circ-incr": 0.4567,
                "measure-hips-circ-incr": 0.3807,
            },
            "4XL": {
                "gender": 1.0,
                "age": 0.8,
                "muscle": 0.0,
                "weight": 1.0,
                "height": 0.4009,
                "proportions": 1.0,
                "cupsize": 0.5,
                "measure-bust-circ-incr": 0.964,
                "measure-waist-circ-incr": 0.4,
                "measure-hips-circ-incr": 0.606,
                "measure-thigh-circ-incr": -0.5099,
                "measure-underbust-circ-incr": 0.4782,
            },
        }
    },
)

MEN = SizeChart(
    name="men",
    title="men's EN 13402-3 letter codes XS-XXL (chest/waist band midpoints), height 167-186 cm (German normal sizes)",
    sizes={
        "XS": _men(82.0, 70.0),
        "S": _men(90.0, 78.0),
        "M": _men(98.0, 86.0),
        "L": _men(106.0, 94.0),
        "XL": _men(114.0, 102.0),
        "XXL": _men(122.0, 110.0),
    },
    start={"gender": 0.0},
    parameters=FIT_PARAMETERS,
    bounds={"age": ADULT_AGE},
    restarts=RESTARTS,
    local=LOCAL_GIRTHS[:2],
    fitted={
        "anny": {
            "XS": {
                "gender": 0.0,
                "age": 0.8,
                "muscle": 0.0362,
                "weight": 0.1444,
                "height": 0.2805,
                "proportions": 1.0,
                "cupsize": 0.5,
            },
            "S": {
                "gender": 0.0,
                "age": 0.7978,
                "muscle": 0.5184,
                "weight": 0.0305,
                "height": 0.3157,
                "proportions": 0.9949,
                "cupsize": 0.5,
                "measure-bust-circ-incr": -0.0045,
                "measure-waist-circ-incr": -0.0101,
            },
            "M": {
                "gender": 0.0,
                "age": 0.7615,
                "muscle": 0.4299,
                "weight": 0.6038,
                "height": 0.3502,
                "proportions": 0.6007,
                "cupsize": 0.5,
            },
            "L": {
                "gender": 0.0,
                "age": 0.6701,
                "muscle": 0.0,
                "weight": 0.5088,
                "height": 0.3763,
                "proportions": 0.086,
                "cupsize": 0.5,
                "measure-bust-circ-incr": -0.0095,
                "measure-waist-circ-incr": 0.0067,
            },
            "XL": {
                "gender": 0.0,
                "age": 0.6716,
                "muscle": 0.3469,
                "weight": 1.0,
                "height": 0.4134,
                "proportions": 0.3762,
                "cupsize": 0.5,
                "measure-bust-circ-incr": -0.009,
                "measure-waist-circ-incr": 0.009,
            },
            "XXL": {
                "gender": 0.0,
                "age": 0.6745,
                "muscle": 0.0227,
                "weight": 0.753,
                "height": 0.4473,
                "proportions": 0.077,
                "cupsize": 0.5,
                "measure-bust-circ-incr": 0.0003,
                "measure-waist-circ-incr": 0.0476,
            },
        }
    },
)

PUBLISHED: Dict[str, SizeChart] = {c.name: c for c in (WOMEN, MEN)}
