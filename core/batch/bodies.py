"""The bodies of a batch: a measurement table, a seeded sample of Anny's phenotype space, or SMPL betas.

Each source gives a list of :class:`BodySource`, the description of one body
(not its vertices: a worker turns it into a body instance, so reading a table
of 10,000 rows costs nothing). Malformed input is refused here, before any
work starts, with one line naming the file, the row and the column; a body
that is well formed but cannot be built (a measurement the model cannot
reach) fails later as that item alone.

Sampling (:func:`sample_anny`): body ``i`` of seed ``S`` is drawn from its own
generator ``numpy.random.default_rng([S, i])``, so it does not depend on how
many bodies are drawn or in what order the workers take them. Each phenotype
is uniform on its range (Anny: gender, muscle, weight, height, proportions on
[0, 1]), except age, uniform on :data:`ADULT_AGE` (Anny's young-adult anchor,
25 years, to its old anchor, 90 years): the templates are adult garments;
cup size and firmness stay at Anny's average.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import List, Mapping, Optional

import numpy as np

from ..errors import BodyError

#: Anny's age range sampled (2/3 = 25 years, 1 = 90 years; see :mod:`core.body.anny`).
ADULT_AGE = (2.0 / 3.0, 1.0)

#: Column names of a measurement table read as the chart size (XS..XL, or women:M).
SIZE_COLUMNS = ("size",)

#: Columns that only name a row.
NAME_COLUMNS = ("name", "id", "label")

# The size chart of a row's ``size`` (core.body.sizes.CHART_NAMES); without it a bare size is
# of the design's own chart, as in ``ease transfer``.
CHART_COLUMNS = ("chart",)


class BodySourceError(BodyError):
    """A body table, sample request or betas file is malformed (names file, row and column)."""


@dataclass(frozen=True)
class BodySource:
    """One body of a batch, as given by the user.

    Attributes
    ----------
    label : str, the row's name or ``"row 3"`` / ``"sample 17"`` / ``"betas 4"``.
    kind : ``"size"`` (chart size name), ``"shape"`` (shape parameters of the
        model), ``"measurements"`` (chart measures in cm, fitted by
        :func:`core.body.sizes.fit_measurements` on the worker) or ``"tape"`` (tape measures in
        cm, and optionally gender, made-to-measure: :func:`core.body.made_to_measure.fit_tape`).
    value : the size name, or a dict parameter -> value, or measure -> cm.
    origin : where it came from (``"bodies.csv row 3"``), for error messages.
    """

    label: str
    kind: str
    value: object
    origin: str = ""

    def record(self) -> dict:
        """The JSON record of this body (it enters the item's content hash)."""
        value = dict(self.value) if isinstance(self.value, Mapping) else self.value
        return {"label": self.label, "kind": self.kind, "value": value}


def _number(text: str, where: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise BodySourceError(f"{where}: expected a number, got {text!r}") from None
    if not np.isfinite(v):
        raise BodySourceError(f"{where}: expected a finite number, got {text!r}")
    return v


def read_measurements(path) -> List[BodySource]:
    """Bodies from a CSV table: one row a body, a header naming the columns.

    Columns: ``height``, ``chest`` (or ``bust``), ``waist``, ``hip`` in cm (any
    subset the fit takes, see :data:`core.body.measure.MEASUREMENTS`), or
    ``size`` (a chart size: ``M`` of the design's chart, ``women:M``, or ``M`` with a
    ``chart`` column naming the chart; used as such where given), and optionally
    ``name``. Empty cells are "not given".

    A table with a column of the tape measures beyond those four (``neck``, ``underbust``,
    ``inseam``, ... :data:`core.body.tape.TAPE_MEASURES` and their aliases) or a ``gender``
    column (0 male .. 1 female) is a made-to-measure table: each of its rows is fitted as
    ``ease body --measurements`` fits a table (kind ``"tape"``, docs/measurements.md).

    Raises
    ------
    BodySourceError naming the file, row (1 = the first body) and column.
    """
    from ..body.made_to_measure import RANGES
    from ..body.measure import MEASUREMENTS
    from ..body.sizes import TARGET_RANGES, check_size
    from ..body.tape import ALIASES, TAPE_MEASURES

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise BodySourceError(f"{path}: cannot read the body table ({exc.strerror or exc})") from None
    rows = list(csv.reader(text.splitlines()))
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise BodySourceError(
            f"{path}: empty body table; expected a header row "
            f"({', '.join(MEASUREMENTS)}, bust, size, name) and one row per body"
        )
    header = [h.strip().lower() for h in rows[0]]
    tape_names = set(TAPE_MEASURES) | set(ALIASES) | {"gender"}
    allowed = set(MEASUREMENTS) | {"bust"} | set(SIZE_COLUMNS) | set(NAME_COLUMNS) | set(CHART_COLUMNS) | tape_names
    for j, h in enumerate(header):
        if h not in allowed:
            raise BodySourceError(
                f"{path}: header column {j + 1} {h!r} is not a measurement; allowed: "
                f"{', '.join(MEASUREMENTS)}, bust (cm), size, chart, name, or the tape measures "
                f"{', '.join(m for m in TAPE_MEASURES if m not in MEASUREMENTS)} (cm) and gender"
            )
    if "chest" in header and "bust" in header:
        raise BodySourceError(f"{path}: header has both 'chest' and 'bust' (the same girth); keep one")
    # a made-to-measure table: a tape measure the chart fit does not take, or gender
    tape = any(h in tape_names and h not in MEASUREMENTS + ("bust",) for h in header)
    canonical = {h: ALIASES.get(h, h) for h in header if h in tape_names}
    if tape and len({canonical[h] for h in header if h in canonical}) < len([h for h in header if h in canonical]):
        raise BodySourceError(f"{path}: header names one tape measure twice (a name and its alias); keep one")
    out = []
    for i, row in enumerate(rows[1:], start=1):
        if len(row) > len(header):
            raise BodySourceError(f"{path}: row {i} has {len(row)} cells, the header {len(header)}")
        cells = {h: (row[j].strip() if j < len(row) else "") for j, h in enumerate(header)}
        name = next((cells[c] for c in NAME_COLUMNS if cells.get(c)), "") or f"row {i}"
        origin = f"{path.name} row {i}"
        size = next((cells[c] for c in SIZE_COLUMNS if cells.get(c)), "")
        targets = {
            (canonical[h] if tape else "chest" if h == "bust" else h): _number(v, f"{path}: row {i}, column {h!r}")
            for h, v in cells.items()
            if v and (h in canonical if tape else h in MEASUREMENTS + ("bust",))
        }
        chart = next((cells[c] for c in CHART_COLUMNS if cells.get(c)), "") or None
        if chart and not size:
            raise BodySourceError(
                f"{path}: row {i}, column 'chart': a chart names the chart of a size; this row has no size"
            )
        if size:
            try:
                size = check_size(size, chart)  # "women:M" when the chart is named
            except BodyError as exc:
                raise BodySourceError(
                    f"{path}: row {i}, column {'size' if chart is None else 'size/chart'!r}: {exc}"
                ) from None
            if targets:
                raise BodySourceError(f"{path}: row {i}: give a size or measurements, not both")
            out.append(BodySource(name, "size", size, origin))
        elif tape and set(targets) - {"gender"}:
            for h, v in cells.items():  # each measure's plausible range, checked before the batch starts
                if v and h in canonical:
                    lo, hi = (0.0, 1.0) if h == "gender" else RANGES[canonical[h]]
                    if not lo <= targets[canonical[h]] <= hi:
                        unit = "" if h == "gender" else " cm"
                        raise BodySourceError(f"{path}: row {i}, column {h!r}: expected {lo:g}..{hi:g}{unit}, got {v}")
            out.append(BodySource(name, "tape", targets, origin))
        elif targets and not tape:
            for h, v in targets.items():  # the chart's range, checked here so the batch never starts
                lo, hi = TARGET_RANGES[h]
                if not lo <= v <= hi:
                    column = "bust" if h == "chest" and "bust" in header else h
                    raise BodySourceError(f"{path}: row {i}, column {column!r}: expected {lo:g}..{hi:g} cm, got {v:g}")
            out.append(BodySource(name, "measurements", targets, origin))
        else:
            raise BodySourceError(f"{path}: row {i}: no measurement and no size given")
    if not out:
        raise BodySourceError(f"{path}: the body table has a header but no body rows")
    return out


# Anny's parameters a sample holds at their default (see sample_anny).
HELD_AT_AVERAGE = ("cupsize", "firmness")


def sample_anny(n: int, seed: int = 0, parameters: Optional[Mapping[str, tuple]] = None) -> List[BodySource]:
    """``n`` Anny shapes, uniform on each phenotype's range (age on :data:`ADULT_AGE`;
    cup size and firmness at their average, :data:`HELD_AT_AVERAGE`).

    Parameters
    ----------
    n : number of bodies, >= 1
    seed : int >= 0; body ``i`` uses ``numpy.random.default_rng([seed, i])``
    parameters : the model's ``shape_parameters()`` ({name: (lo, hi, default)});
        default Anny's
    """
    if not isinstance(n, (int, np.integer)) or isinstance(n, bool) or n < 1:
        raise BodySourceError(f"--sample: expected a number of bodies >= 1, got {n!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise BodySourceError(f"--seed: expected an integer >= 0, got {seed!r}")
    if parameters is None:
        from ..body import load_body

        parameters = load_body("anny").shape_parameters()
    # The breast phenotypes stay at Anny's average: they became shape parameters after
    # datasets were made with this sampler, and a seed keeps giving the same bodies.
    names = sorted(k for k in parameters if k not in HELD_AT_AVERAGE)
    bounds = {k: (ADULT_AGE if k == "age" else parameters[k][:2]) for k in names}
    out = []
    for i in range(int(n)):
        rng = np.random.default_rng([int(seed), i])
        u = rng.random(len(names))
        shape = {k: round(float(bounds[k][0] + u[j] * (bounds[k][1] - bounds[k][0])), 6) for j, k in enumerate(names)}
        out.append(BodySource(f"sample {i}", "shape", shape, f"sample {i} of seed {seed}"))
    return out


def _betas_array(path: Path) -> np.ndarray:
    suffix = path.suffix.lower()
    try:
        if suffix == ".npy":
            return np.load(path, allow_pickle=False)
        if suffix == ".npz":
            with np.load(path, allow_pickle=False) as z:
                keys = list(z.keys())
                key = "betas" if "betas" in keys else (keys[0] if len(keys) == 1 else None)
                if key is None:
                    raise BodySourceError(
                        f"{path}: expected an array 'betas' (or a single array); found {', '.join(keys) or 'none'}"
                    )
                return z[key]
    except (OSError, ValueError) as exc:
        raise BodySourceError(f"{path}: cannot read the betas ({exc})") from None
    if suffix != ".csv":
        raise BodySourceError(f"{path}: betas must be .npy, .npz or .csv, got {suffix or 'no extension'!r}")
    try:
        rows = [r for r in csv.reader(path.read_text(encoding="utf-8-sig").splitlines()) if r]
    except OSError as exc:
        raise BodySourceError(f"{path}: cannot read the betas ({exc.strerror or exc})") from None
    if rows and rows[0] and not _is_number(rows[0][0]):
        rows = rows[1:]  # a header (beta0, beta1, ...)
    table = []
    for i, r in enumerate(rows, start=1):
        if len(r) != len(rows[0]):
            raise BodySourceError(f"{path}: row {i} has {len(r)} betas, row 1 has {len(rows[0])}")
        table.append([_number(c.strip(), f"{path}: row {i}, column {j + 1}") for j, c in enumerate(r)])
    return np.array(table, dtype=float).reshape(len(table), -1)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_betas(path, parameters: Mapping[str, tuple]) -> List[BodySource]:
    """SMPL shapes from a betas file: (N, B) in ``.npy``, ``.npz`` (array ``betas``) or CSV.

    Parameters
    ----------
    path : the file
    parameters : the SMPL model's ``shape_parameters()`` (``beta0`` ...): B may
        be at most the model's count (missing betas are 0), each value in range.
    """
    path = Path(path)
    betas = np.asarray(_betas_array(path))
    if betas.ndim == 1:
        betas = betas[None, :]
    if betas.ndim != 2 or betas.shape[0] == 0 or betas.shape[1] == 0:
        raise BodySourceError(f"{path}: expected betas of shape (N bodies, B), got {betas.shape}")
    if not np.issubdtype(betas.dtype, np.number):
        raise BodySourceError(f"{path}: betas must be numbers, got dtype {betas.dtype}")
    names = [f"beta{j}" for j in range(betas.shape[1])]
    missing = [n for n in names if n not in parameters]
    if missing:
        raise BodySourceError(
            f"{path}: {betas.shape[1]} betas per body but the model has "
            f"{sum(1 for k in parameters if k.startswith('beta'))}"
        )
    out = []
    for i, row in enumerate(betas, start=1):
        shape = {}
        for j, v in enumerate(row):
            lo, hi = parameters[names[j]][:2]
            if not (np.isfinite(v) and lo <= v <= hi):
                raise BodySourceError(
                    f"{path}: row {i}, column {j + 1} (beta{j}) = {v:g} is out of range [{lo:g}, {hi:g}]"
                )
            shape[names[j]] = float(v)
        out.append(BodySource(f"betas {i}", "shape", shape, f"{path.name} row {i}"))
    return out
