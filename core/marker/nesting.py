"""Markers: every piece of one or more sizes nested on a fabric of a given width.

A marker is the cutting-room layout of all pieces to cut from one length of
fabric. The pieces' cut lines (seam allowance included, from
:func:`core.export.pieces.build_pieces`) are nested by spyrrow, the sparrow /
jagua-rs irregular strip packer, run in its own process
(:mod:`core.marker.worker`) so that a cancel or Ctrl-C can stop it and
keep the best marker found so far. Each cut line is nested as a simpler
polygon that holds it (:func:`core.marker.outline.nest_outline`), so
the true cut lines of two nested pieces never meet.

Frame (metres): x runs along the fabric (the marker length, from 0), y
across it (0 at one selvage, ``width`` at the other). The grain (warp) of
every piece lies along x, parallel to the selvage: a piece's frame has the
grain along +y (:mod:`core.export.pieces`), so it is first turned by -90°
(:data:`GRAIN_TO_LENGTH`) and then only by 0° or 180° (two-way fabric), 0°
(one-way fabric: nap, pile, a directional print), each optionally with a
small tilt tolerance.

Efficiency is the pieces' cut area over the marker area (width x length).
A piece cut on a fold is unfolded (mirrored about its fold line): a marker is
cut from a single open ply.

Repeatability: the nester runs on ``threads`` worker threads (1 by default)
with the given seed. With one thread its search is a function of the seed,
so a marker whose search ends by itself before the time limit
(``stopped == "converged"``) is the same, byte for byte, on every run; a
search cut short by the time limit ends wherever the machine's speed took it.
More cores help in two ways, both within the same wall time: ``threads``
(the nester's own worker threads, one search) and ``tries`` (nesters side by
side with seeds ``seed``, ``seed + 1``, ..., the shortest marker kept); the
marker reports both, so its efficiency is always that of ``seconds`` on
``threads x tries`` cores.
"""

from __future__ import annotations

import json
import math
import os
import queue
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..errors import Cancelled, ExportError
from ..export.pieces import PieceDrawing, build_pieces
from ..export.pieces import size_label as pieces_size_label
from ..geom.polygon import signed_area
from ..pattern.types import Pattern
from ..progress import Progress, report
from .outline import nest_outline

GRAIN_TO_LENGTH = np.array([[0.0, 1.0], [-1.0, 0.0]])  # piece frame (grain +y) -> marker frame (grain +x)
MAX_TILT = 10.0  # degrees
MAX_WIDTH = 10.0  # m of fabric width: the widest rolls are ~3.2 m
MAX_SECONDS = 24 * 3600  # s of nesting
MAX_GARMENTS = 100  # garments of one size in one marker
MARGIN = 5.0  # s: a nest returns at most this long after its time budget
SPREADS = ("single", "pairs")  # one ply; two plies face to face
EXPLORATION_SHARE = 0.8  # of the budget exploring (sparrow's own split), the rest compressing
WORKER = Path(__file__).with_name("worker.py")
SPYRROW_PIN = "spyrrow==0.9.0"


@dataclass
class MarkerItem:
    """One piece of one size to nest, ``count`` times.

    Attributes
    ----------
    size : str, the size label (pattern folder or size name).
    piece : :class:`core.export.pieces.PieceDrawing` (piece frame, m).
    outline : (k, 2) float, m: the cut line in the piece frame, unfolded for a
        piece cut on a fold (counter-clockwise).
    mirror : (2,) point and (2,) unit direction of the fold line, or None.
    count : int, copies to nest (garments of this size x the label's quantity; face to face, see
        :func:`marker_items`).
    area : float, m², of ``outline``.
    garments : int, garments of this size the marker cuts (0: from ``count``).
    plies : int, 1 (single ply) or 2 (face to face: each copy cuts the piece and its mirror image).
    pair : str, face to face: the piece whose mirror image the second ply cuts (a declared pair's right),
        else "".
    """

    size: str
    piece: PieceDrawing
    outline: np.ndarray
    mirror: Optional[Tuple[np.ndarray, np.ndarray]]
    count: int
    area: float
    garments: int = 0
    plies: int = 1
    pair: str = ""


@dataclass
class Placement:
    """Where one copy of an item lies: marker point = ``rotation @ piece point + translation``.

    ``angle`` (degrees) is the nester's turn after :data:`GRAIN_TO_LENGTH`.
    """

    item: int
    angle: float
    rotation: np.ndarray
    translation: np.ndarray


@dataclass
class Marker:
    """A nested marker (metres) and how it was found.

    Attributes
    ----------
    width, length : float, m: fabric width and marker length (to the farthest cut line).
    items : the nested :class:`MarkerItem` list.
    placements : one :class:`Placement` per cut copy.
    efficiency : float in [0, 1], pieces' cut area / (width x length).
    seconds : float, wall seconds spent nesting.
    seed, threads : the nester's seed and worker threads.
    orientations : the allowed turns (degrees) after the grain turn.
    stopped : ``"converged"``, ``"time limit"`` or ``"interrupted"``.
    history : list of (seconds, efficiency), each improvement as it came.
    tries : nesters run side by side (seeds ``seed`` ...), ``best_seed`` the one whose marker this is.
    """

    width: float
    length: float
    items: List[MarkerItem]
    placements: List[Placement]
    efficiency: float
    seconds: float
    seed: int
    threads: int
    orientations: List[float]
    stopped: str
    history: List[Tuple[float, float]] = field(default_factory=list)
    tries: int = 1
    best_seed: int = 0


def orientations(one_way: bool = False, tilt: float = 0.0) -> List[float]:
    """The allowed turns (degrees): 0 and 180 (0 only for a one-way fabric), each ± ``tilt``."""
    tilt = float(tilt)
    if not (0.0 <= tilt <= MAX_TILT):
        raise ExportError(f"tilt: expected 0 to {MAX_TILT:g} degrees off the grain, got {tilt:g}")
    base = [0.0] if one_way else [0.0, 180.0]
    out = []
    for b in base:
        out += [b] if tilt == 0 else [b - tilt, b, b + tilt]
    return out


def _cores() -> int:
    return max(int(os.cpu_count() or 1), 1)


def default_split(threads: Optional[int] = None, tries: Optional[int] = None) -> Tuple[int, int]:
    """(threads, tries) by default: one nester with a worker thread a core (sparrow's workers search side by side
    from their own random streams and share the best solution: measured on the teaser XS-XL, 150 cm, 60 s on 2
    cores, one nester of 2 threads 77.7 % against 76.2 % for 2 one-thread nesters, seeds 0 and 1); a given
    ``threads`` takes as many tries as the cores hold (:func:`default_tries`), a given ``tries`` the cores' share
    of threads each."""
    if threads is None and tries is None:
        return _cores(), 1
    if tries is None:
        return threads, default_tries(threads)
    if threads is None:
        try:
            share = _cores() // max(int(tries), 1)
        except (TypeError, ValueError, OverflowError):  # check_options names the bad value
            share = 1
        return max(share, 1), tries
    return threads, tries


def default_tries(threads: int = 1) -> int:
    """Nesters side by side by default: as many as the machine's cores hold ``threads`` each (at least 1)."""
    try:
        threads = max(int(threads), 1)
    except (TypeError, ValueError):
        threads = 1
    return max(_cores() // threads, 1)


def check_options(width: float, seconds: int = 60, seed: int = 0, threads: int = 1, tries: int = 1, prefix: str = ""):
    """``(width, seconds, seed, threads, tries)`` checked, before any work: ExportError naming the option
    (``prefix`` + name, e.g. ``--`` for the CLI) otherwise.

    Ranges: width (m) in (0, :data:`MAX_WIDTH`]; seconds 1 to :data:`MAX_SECONDS`; seed 0 to 2**32 - 1
    (the nester's); threads and tries 1 to the machine's cores each, ``threads x tries`` at most the cores
    too (a nester thread or try per core: more only share them).
    """

    def num(name, value, kind):
        try:
            v = kind(value)
        except (TypeError, ValueError, OverflowError):
            raise ExportError(f"{prefix}{name}: expected a number, got {value!r}") from None
        if kind is int and (isinstance(value, bool) or v != value):
            raise ExportError(f"{prefix}{name}: expected a whole number, got {value!r}")
        return v

    width, seconds, seed = num("width", width, float), num("seconds", seconds, int), num("seed", seed, int)
    threads, tries = num("threads", threads, int), num("tries", tries, int)
    if not (math.isfinite(width) and 0 < width <= MAX_WIDTH):
        raise ExportError(
            f"{prefix}width: expected a fabric width in mm in (0, {MAX_WIDTH * 1000:g}], got {width * 1000:g}"
        )
    if not 1 <= seconds <= MAX_SECONDS:
        raise ExportError(f"{prefix}seconds: expected a time budget of 1 to {MAX_SECONDS} s, got {seconds}")
    if not 0 <= seed < 2**32:
        raise ExportError(f"{prefix}seed: expected 0 to {2**32 - 1}, got {seed}")
    cores = _cores()
    for name, v in (("threads", threads), ("tries", tries)):
        if not 1 <= v <= cores:
            raise ExportError(f"{prefix}{name}: expected 1 to {cores} (this machine's cores), got {v}")
    if threads * tries > cores:
        raise ExportError(
            f"{prefix}threads x {prefix}tries: expected at most {cores} (this machine's cores), got {threads} x {tries}"
        )
    return width, seconds, seed, threads, tries


def parse_quantities(text: str, field: str = "sizes") -> Dict[str, int]:
    """``"XS:1,M:2,L:1"`` (or ``"XS,M"``: one each) as {size: garments}, in the order given."""
    out: Dict[str, int] = {}
    for part in str(text).split(","):
        part = part.strip()
        if not part:
            continue
        name, _, count = part.partition(":")
        name = name.strip()
        try:
            n = int(count) if count.strip() else 1
        except ValueError:
            n = 0
        if not name or not 1 <= n <= MAX_GARMENTS or name in out:
            raise ExportError(
                f"{field}: expected SIZE:GARMENTS pairs such as XS:1,M:2 (each size once, "
                f"1 to {MAX_GARMENTS} garments), got {part!r}"
            )
        out[name] = n
    if not out:
        raise ExportError(f"{field}: expected SIZE:GARMENTS pairs such as XS:1,M:2, got {text!r}")
    return out


def size_label(pattern: Pattern, folder=None) -> str:
    """The size a pattern is for (:func:`core.export.pieces.size_label`: its chart size, else its body's
    name), else the folder name."""
    size = pieces_size_label(pattern)
    if size in ("-", "custom") and folder is not None:
        return Path(folder).name
    return size


def _rot(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def _fold_line(piece: PieceDrawing) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    if not piece.fold:
        return None
    f = np.asarray(piece.fold[0], float)
    d = f[-1] - f[0]
    return f[0], d / max(np.linalg.norm(d), 1e-12)


def reflect(points: np.ndarray, line: Tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """(k, 2) points mirrored about the line (point, unit direction)."""
    p0, d = line
    q = np.asarray(points, float) - p0
    along = q @ d
    return p0 + 2.0 * along[:, None] * d - q


def unfold(loop: np.ndarray, line: Tuple[np.ndarray, np.ndarray], tol: float = 1e-5) -> np.ndarray:
    """The whole outline of a piece cut on a fold: the half and its mirror image.

    Parameters
    ----------
    loop : (k, 2) float, m, counter-clockwise cut line of the half piece; the
        fold edge (no allowance) is a run of vertices on ``line``.
    line : fold line (point, unit direction).
    tol : m, distance within which a vertex counts as on the fold.

    Raises
    ------
    ExportError when no run of the cut line lies on the fold (an allowance on the fold).
    """
    p0, d = line
    q = loop - p0
    off = np.abs(q[:, 0] * d[1] - q[:, 1] * d[0]) > tol
    if off.all() or not off.any():
        raise ExportError("a piece cut on a fold needs its cut line along the fold (no allowance on the fold)")
    n = len(loop)
    # start at the last fold vertex before an off-fold run: A, c1..ck, B with A and B on the fold
    start = next(i for i in range(n) if not off[i] and off[(i + 1) % n])
    order = [(start + k) % n for k in range(n)]
    chain = [order[0]]
    for i in order[1:]:
        chain.append(i)
        if not off[i]:
            break
    half = loop[chain]
    return np.vstack([half, reflect(half[-2:0:-1], line)])


def _face_to_face(pattern: Pattern, pieces: Sequence[PieceDrawing], garments: int):
    """{piece index: (copies to nest, the pair's right piece or "")} of a face-to-face lay (two plies, one the
    other's mirror image): one piece of each mirrored pair, ``garments`` times (the second ply cuts the other);
    a piece that is its own mirror image across its grain, ``ceil(garments / 2)`` times (each copy cuts two).
    ExportError for a pair that is not mirrored, or a piece of neither kind (the second ply would cut it
    mirrored)."""
    from ..export.fold_half import fold_axis
    from ..export.mirror_check import MIRROR_TOL, declared_pairs

    out, right = {}, set()
    for j, k in declared_pairs(pattern, pieces):
        gap = pieces[j].mirror_gaps.get(pieces[k].name, math.inf)
        if gap > MIRROR_TOL:
            raise ExportError(
                f"spread pairs: {pieces[j].name} and {pieces[k].name} are not mirror images "
                f"({'differ' if not math.isfinite(gap) else f'{gap * 1000:.1f} mm off'}); "
                f"expected a mirrored pair, or spread single"
            )
        out[j], right = (garments, pieces[k].name), right | {k}
    for i, piece in enumerate(pieces):
        if i in out or i in right:
            continue
        if piece.fold or fold_axis(piece, MIRROR_TOL) is not None:
            out[i] = (-(-garments // 2), "")
        else:
            raise ExportError(
                f"spread pairs: piece {piece.name} is neither one of a mirrored pair nor its own "
                f"mirror image: the second ply would cut it mirrored; expected spread single"
            )
    return out


def marker_items(
    patterns: Sequence[Tuple[str, Pattern, int]],
    allowance=None,
    notch_spacing: Optional[float] = None,
    spread: str = "single",
) -> List[MarkerItem]:
    """The pieces to nest: every piece of every pattern, as many times as garments and labels ask.

    Parameters
    ----------
    patterns : (size label, pattern, garments) triples; ``garments`` >= 1 copies
        of the whole pattern (each piece ``garments x`` its label's quantity;
        mirrored pieces are pieces of their own in a pattern, drawn mirrored).
    allowance, notch_spacing : see :func:`core.export.pieces.build_pieces`.
    spread : ``"single"`` (one ply, every piece nested) or ``"pairs"`` (two plies face to face, as cutting
        rooms lay mirrored pieces: one piece of each mirrored pair, the second ply cutting its mirror image;
        a piece that is its own mirror image half as often, each copy cutting two; see :func:`_face_to_face`).
    """
    if spread not in SPREADS:
        raise ExportError(f"spread: expected {' or '.join(SPREADS)}, got {spread!r}")
    items = []
    for size, pattern, garments in patterns:
        if not 1 <= int(garments) <= MAX_GARMENTS:
            raise ExportError(f"size {size}: expected 1 to {MAX_GARMENTS} garments, got {garments}")
        pieces = build_pieces(pattern, allowance, notch_spacing)
        lay = _face_to_face(pattern, pieces, int(garments)) if spread == "pairs" else None
        for i, piece in enumerate(pieces):
            if lay is not None and i not in lay:
                continue
            line = _fold_line(piece)
            outline = piece.cut[0] if line is None else unfold(piece.cut[0], line)
            count, pair = lay[i] if lay is not None else (int(garments), "")
            items.append(
                MarkerItem(
                    size=str(size),
                    piece=piece,
                    outline=outline,
                    mirror=line,
                    count=count * int(piece.quantity),
                    area=float(signed_area(outline)),
                    garments=int(garments),
                    plies=2 if lay is not None else 1,
                    pair=pair,
                )
            )
    if not items:
        raise ExportError("marker: no pieces to nest")
    return items


def _check_fits(items: Sequence[MarkerItem], shapes: Sequence[np.ndarray], width: float, turns: Sequence[float]):
    for it, shape in zip(items, shapes):
        across = min(float(np.ptp((shape @ _rot(a).T)[:, 1])) for a in turns)
        if across > width:
            true = min(float(np.ptp((it.outline @ GRAIN_TO_LENGTH.T @ _rot(a).T)[:, 1])) for a in turns)
            raise ExportError(
                f"piece {it.piece.name} (size {it.size}) is {true * 1000:.0f} mm across the grain: "
                f"expected a fabric wider than that, got --width {width * 1000:.0f} mm"
            )


def _child_env() -> Dict[str, str]:
    # the worker imports spyrrow from wherever this process found it (venv, Blender's modules)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([p for p in sys.path if p] + [env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _read_lines(stream, out: "queue.Queue", tag: int) -> None:
    for line in stream:
        out.put((tag, line))
    out.put((tag, None))


def phase_seconds(seconds: int) -> Tuple[int, int]:
    """(exploration, compression) seconds of a nester's budget: :data:`EXPLORATION_SHARE` of it exploring
    (at least 1 s), the rest compressing the best marker found."""
    seconds = int(seconds)
    explore = min(seconds, max(1, int(round(EXPLORATION_SHARE * seconds))))
    return explore, seconds - explore


def nest(
    items: Sequence[MarkerItem],
    width: float,
    seconds: int = 60,
    seed: int = 0,
    one_way: bool = False,
    tilt: float = 0.0,
    threads: int = 1,
    tries: int = 1,
    progress: Optional[Progress] = None,
    early_stop: bool = False,
) -> Marker:
    """Nest the items on a fabric ``width`` m wide; the shortest marker found in ``seconds``.

    Parameters
    ----------
    items : from :func:`marker_items`.
    width : float, m, usable fabric width (selvage to selvage).
    seconds : int >= 1, the nester's time budget (it may end sooner when it converges).
    seed : int, the nester's random seed (tries use ``seed``, ``seed + 1``, ...).
    one_way, tilt : allowed turns, see :func:`orientations`.
    threads : int >= 1, worker threads of each nester (more than 1 is faster, not repeatable).
    tries : int >= 1, nesters run side by side in the same ``seconds``, each with its own
        seed and ``threads`` threads (``threads x tries`` cores in all); the shortest marker wins.
    progress : ``progress(fraction, message)`` with the live efficiency; raising
        :class:`core.errors.Cancelled` stops and discards the run.
    early_stop : let the nester end its search when it stops improving (spyrrow's early termination): a search
        that ends so before the time limit is repeatable with one thread; off (the default) it uses the whole
        budget, which finds shorter markers (teaser XS-XL, 150 cm, 60 s, one thread: 76.1-76.3 % against
        75.9 %).

    The budget is a promise: the nesters are stopped :data:`MARGIN` seconds after ``seconds`` at the latest
    (from the call, the outlines' preparation included), keeping the best marker so far; with none yet it
    is an error saying so.

    Returns
    -------
    :class:`Marker`. Ctrl-C (KeyboardInterrupt) stops the search and returns the
    best marker so far (``stopped == "interrupted"``), or re-raises when there is none yet.
    """
    t0 = time.monotonic()
    width, seconds, seed, threads, tries = check_options(width, seconds, seed, threads, tries)
    turns = orientations(one_way, tilt)
    shapes = [nest_outline(it.outline) @ GRAIN_TO_LENGTH.T for it in items]
    _check_fits(items, shapes, width, turns)
    explore, compress = phase_seconds(seconds)
    request = {
        "strip": width * 1000.0,
        "exploration": explore,
        "compression": compress,
        "threads": threads,
        "early_termination": bool(early_stop),
        "items": [
            {"shape": np.round(s * 1000.0, 4).tolist(), "demand": it.count, "orientations": turns}
            for it, s in zip(items, shapes)
        ],
    }
    area = sum(it.area * it.count for it in items)
    report(progress, 0.0, f"nesting {sum(it.count for it in items)} pieces on {width * 1000:.0f} mm fabric")
    best, history, stopped = run_nesters(
        request, seconds, seed, tries, lambda length: area / (width * length / 1000.0), t0, progress
    )
    return _marker(items, best, width, time.monotonic() - t0, seed, threads, turns, stopped, history, tries)


def run_nesters(
    request: dict,
    seconds: int,
    seed: int = 0,
    tries: int = 1,
    efficiency=None,
    t0: Optional[float] = None,
    progress: Optional[Progress] = None,
) -> Tuple[dict, list, str]:
    """Run ``tries`` nester processes (:mod:`.worker`) on ``request`` side by side, seeds ``seed``,
    ``seed + 1``, ...; the shortest solution any of them reports within ``seconds`` + :data:`MARGIN`
    (counted from ``t0``, default now).

    ``request``: the worker's JSON (``strip`` height, ``items`` with ``shape``, ``demand`` and
    ``orientations``, ``exploration`` and ``compression`` seconds, ``threads``, ``early_termination``).
    ``efficiency(length)``: the fraction shown on the progress line and kept in the history.

    Returns (best: the worker's message with ``length`` and ``placed`` and the ``seed`` that found it,
    history: (seconds, efficiency) per improvement, stopped: ``"converged"``, ``"time limit"`` or
    ``"interrupted"`` (Ctrl-C with a solution in hand)). ExportError without any solution.
    """
    t0 = time.monotonic() if t0 is None else t0
    pieces = sum(int(it["demand"]) for it in request["items"])
    deadline = t0 + seconds + MARGIN
    lines: "queue.Queue" = queue.Queue()
    procs = []
    best, history, running, ends = None, [], tries, []
    try:
        for k in range(tries):
            proc = subprocess.Popen(
                [sys.executable, str(WORKER)],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env=_child_env(),
            )
            procs.append(proc)
            proc.stdin.write(json.dumps(dict(request, seed=seed + k)))
            proc.stdin.close()
            threading.Thread(target=_read_lines, args=(proc.stdout, lines, k), daemon=True).start()
        while running:
            if time.monotonic() > deadline:  # the budget is a promise: stop the nesters, keep the best
                ends.append("time limit")
                break
            try:
                k, line = lines.get(timeout=0.2)
            except queue.Empty:
                k, line = -1, ""
            if line is None:
                running -= 1
                continue
            msg = json.loads(line) if line.strip() else {}
            elapsed = time.monotonic() - t0
            if msg.get("done"):
                ends.append("converged" if elapsed < seconds - 0.5 else "time limit")
            elif "placed" in msg and (best is None or msg["length"] < best["length"]):
                best = dict(msg, seed=seed + k)
                history.append((round(elapsed, 2), efficiency(msg["length"]) if efficiency else None))
            eff = (
                f"efficiency {history[-1][1] * 100:.1f} %, length {best['length'] / 1000:.3f} m"
                if best and efficiency
                else ("no marker yet" if best is None else f"length {best['length']:g}")
            )
            report(progress, min(elapsed / seconds, 0.99), f"nesting {pieces} pieces: {eff}")
        stopped = "converged" if ends and all(e == "converged" for e in ends) else "time limit"
    except KeyboardInterrupt:
        if best is None:
            raise
        stopped = "interrupted"
    except Cancelled:
        raise
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
            proc.wait()
    if best is None:
        errs = [(p.returncode, p.stderr.read().strip() if p.stderr else "") for p in procs]
        code, err = next((e for e in errs if e[0] == 3), errs[-1] if errs else (None, ""))
        if code == 3:
            raise ExportError(f"the marker needs the spyrrow package: pip install {SPYRROW_PIN} ({err})")
        if time.monotonic() > deadline:
            raise ExportError(
                f"the nester found no marker of {pieces} pieces within the time budget "
                f"({seconds} s + {MARGIN:g} s); give it more seconds or fewer garments"
            )
        raise ExportError(f"the nester found no marker (exit {code}): {err.splitlines()[-1] if err else ''}")
    return best, history, stopped


def nest_polygons(
    shapes: Sequence[np.ndarray],
    demands: Sequence[int],
    strip: float,
    seconds: int,
    seed: int = 0,
    threads: int = 1,
    tries: int = 1,
    orientations: Sequence[float] = (0.0, 180.0),
    early_stop: bool = False,
) -> dict:
    """Plain polygons (any unit) nested on a strip ``strip`` high by the marker's own nester settings
    (:func:`phase_seconds`, early termination, tries): a published strip-packing instance run through
    the same wrapper as a marker (the calibration of ``ease bench --only marker``).

    Returns {``length``, ``efficiency`` (the shapes' area over strip x length), ``stopped``, ``seconds``,
    ``best_seed``}.
    """
    t0 = time.monotonic()
    explore, compress = phase_seconds(seconds)
    shapes = [np.asarray(sh, float) for sh in shapes]
    area = sum(abs(float(signed_area(sh))) * int(d) for sh, d in zip(shapes, demands))
    request = {
        "strip": float(strip),
        "exploration": explore,
        "compression": compress,
        "threads": int(threads),
        "early_termination": bool(early_stop),
        "items": [
            {"shape": sh.tolist(), "demand": int(d), "orientations": list(orientations)}
            for sh, d in zip(shapes, demands)
        ],
    }
    best, _, stopped = run_nesters(request, seconds, seed, tries, t0=t0)
    return {
        "length": float(best["length"]),
        "efficiency": area / (float(strip) * float(best["length"])),
        "stopped": stopped,
        "seconds": time.monotonic() - t0,
        "best_seed": int(best["seed"]),
    }


def _marker(items, best, width, seconds, seed, threads, turns, stopped, history, tries=1) -> Marker:
    placements = []
    for k, angle, tx, ty in best["placed"]:
        rotation = _rot(angle) @ GRAIN_TO_LENGTH
        placements.append(
            Placement(item=int(k), angle=float(angle), rotation=rotation, translation=np.array([tx, ty]) / 1000.0)
        )
    # sorted by item then position: the files list copies in a fixed order
    placements.sort(key=lambda p: (p.item, round(float(p.translation[0]), 6), round(float(p.translation[1]), 6)))
    length = max(float((items[p.item].outline @ p.rotation.T + p.translation)[:, 0].max()) for p in placements)
    area = sum(items[p.item].area for p in placements)
    return Marker(
        width=width,
        length=length,
        items=list(items),
        placements=placements,
        efficiency=area / (width * length),
        seconds=seconds,
        seed=seed,
        threads=threads,
        orientations=list(turns),
        stopped=stopped,
        history=history,
        tries=tries,
        best_seed=int(best.get("seed", seed)),
    )


def placed_outline(marker: Marker, placement: Placement) -> np.ndarray:
    """(k, 2) m: the cut line of one placed copy, in the marker frame."""
    return marker.items[placement.item].outline @ placement.rotation.T + placement.translation


def marker_report(marker: Marker, title: str = "marker") -> dict:
    """What ``marker.json`` holds: length, efficiency, fabric per garment and per size, time, seed, placements.

    Fabric per size is the marker length shared out by the sizes' cut area;
    per garment, that share over the size's garment count.
    """
    area = sum(marker.items[p.item].area for p in marker.placements)
    sizes: Dict[str, dict] = {}
    for it in marker.items:
        s = sizes.setdefault(it.size, {"garments": 0, "pieces": 0, "area_m2": 0.0})
        s["pieces"] += it.count * it.plies
        s["area_m2"] += it.area * it.count
    for it in marker.items:
        sizes[it.size]["garments"] = max(
            sizes[it.size]["garments"], it.garments or it.count // max(it.piece.quantity, 1)
        )
    for s in sizes.values():
        share = marker.length * s["area_m2"] / area
        s.update(
            fabric_m=round(share, 4),
            fabric_per_garment_m=round(share / max(s["garments"], 1), 4),
            area_m2=round(s["area_m2"], 5),
        )
    garments = sum(s["garments"] for s in sizes.values())
    return {
        "title": title,
        "unit": "mm",
        "width_mm": round(marker.width * 1000, 2),
        "length_mm": round(marker.length * 1000, 2),
        "efficiency_pct": round(marker.efficiency * 100, 3),
        "pieces_area_m2": round(area, 5),
        "marker_area_m2": round(marker.width * marker.length, 5),
        "garments": garments,
        "fabric_per_garment_m": round(marker.length / max(garments, 1), 4),
        "sizes": sizes,
        "pieces": len(marker.placements),
        "orientations_deg": marker.orientations,
        "allowance_mm": {
            it.piece.name: sorted({round(float(w) * 1000, 2) for e in it.piece.edge_allowance for w in e})
            for it in marker.items
        },
        "grain": "along the marker length (x), parallel to the selvage",
        "spread": "pairs" if any(it.plies == 2 for it in marker.items) else "single",
        "plies": max(it.plies for it in marker.items),
        "face_to_face": {f"{it.size}/{it.piece.name}": it.pair or "itself" for it in marker.items if it.plies == 2},
        "seed": marker.seed,
        "threads": marker.threads,
        "tries": marker.tries,
        "best_seed": marker.best_seed,
        "stopped": marker.stopped,
        "placements": [
            {
                "size": marker.items[p.item].size,
                "piece": marker.items[p.item].piece.name,
                "angle_deg": round(p.angle, 4),
                "translation_mm": np.round(p.translation * 1000, 3).tolist(),
            }
            for p in marker.placements
        ],
    }


__all__ = [
    "MarkerItem",
    "Placement",
    "Marker",
    "marker_items",
    "nest",
    "orientations",
    "parse_quantities",
    "check_options",
    "default_tries",
    "SPREADS",
    "phase_seconds",
    "size_label",
    "MARGIN",
    "unfold",
    "reflect",
    "MAX_WIDTH",
    "MAX_SECONDS",
    "MAX_GARMENTS",
    "nest_outline",
    "placed_outline",
    "marker_report",
    "SPYRROW_PIN",
]
