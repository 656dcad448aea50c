"""The drawing of each pattern piece, as a printed or plotted pattern shows it.

For every piece: the sew line (the piece boundary), the cut line (the sew
line offset outward by the allowance of each edge, :mod:`.allowance`),
notches on both sides of each seam at identical arc lengths
(:mod:`.notches`), the grain line with arrows (:mod:`core.geom.layout`) and
the piece label. :func:`core.geom.layout.layout_pieces` then places the
pieces on a sheet.

Every piece is drawn in its own frame: the pattern uv (metres) rotated so that
the grain (warp) points along +y, the way pieces are laid on fabric with the
selvage vertical. Rotation keeps lengths, so sew-line lengths are the
pattern's.
"""

from __future__ import annotations

import dataclasses
import re
import unicodedata
from dataclasses import dataclass, field
from typing import Dict, List, Mapping, Optional

import numpy as np

from ..geom.layout import grain_arrows, grain_line, grain_rotation
from ..geom.polygon import MITRE_LIMIT, ray_hit
from ..pattern.types import Pattern, PatternPanel
from ..progress import report
from .allowance import allowance_text, edge_allowances, fold_ids, piece_cut_lines, resolve_allowance
from .boundary import edge_table, piece_loops
from .darts import DartDrawing, bridge_darts, dart_drawing, piece_darts
from .mirror_check import MIRROR_TOL, declared_pairs, mirror_gap
from .notches import DEFAULT_NOTCH_SPACING, Notch, check_notch_spacing, piece_notches, slit
from .pleats import PleatDrawing, piece_pleats, pleat_notches

CHAR_WIDTH = 0.6  # Helvetica's mean advance is ~0.55 em: a safe width estimate per character
TEXT_MIN = 0.0025  # m, smallest label text
CUT_LINE = 3  # index of the label line that says how to cut the piece (:func:`_label`)


@dataclass
class PieceDrawing:
    """Everything drawn for one pattern piece, in the piece frame (metres, grain = +y).

    Attributes
    ----------
    name, garment : str.
    rotation : (2, 2) float, piece frame = ``rotation @ uv``.
    sew : list of (k, 2) closed loops, the sew line; ``sew[0]`` is the outline
        (counter-clockwise), the others are holes (clockwise).
    sew_ids : list of (k,) int, local vertex ids of ``sew``.
    cut : list of (m, 2) closed loops, the cut line (allowance included).
    edge_allowance : list of (k,) float, allowance of each sew edge (m).
    fold : list of (j, 2) polylines on the fold (layer "mirror line").
    notches : list of :class:`core.export.notches.Notch` (a dart's: one at each leg's mouth).
    grain : (2, 2) float, grain line end points (bottom, top).
    arrows : list of (3, 2) polylines, arrow heads at both grain ends.
    label : list of str, label lines (ASCII).
    label_at : (2,) float, top-left of the label block.
    text_height : float, m.
    quantity : int, how many to cut from this drawing: 1 for every pattern piece (a mirrored
        pair is two pieces); 2 for a pair's left piece printed once for both on a
        tiled PDF (:func:`core.export.print_set.print_set`).
    bbox : (2, 2) float, min and max corner of everything drawn.
    mirror_gaps : dict, for a piece of a declared pair (``mirror_of`` either way): the other piece's name ->
        how far (m) the right piece lies from the left one's mirror image (inf: their drawings differ in kind),
        :func:`core.export.mirror_check.mirror_gap`; the label and the tiled PDF's print set follow it.
    turn_points : (t, 2) float or None, the corners (AAMA turn points) the DXF marks; None: the vertices
        where the cut and sew lines turn by more than :data:`core.export.dxf.TURN_DEG` (a graded nest sets
        the sample size's corners on every size, :mod:`core.export.graded`).
    """

    name: str
    garment: str
    rotation: np.ndarray
    sew: List[np.ndarray]
    sew_ids: List[np.ndarray]
    cut: List[np.ndarray]
    edge_allowance: List[np.ndarray]
    fold: List[np.ndarray]
    notches: List[Notch]
    grain: np.ndarray
    arrows: List[np.ndarray]
    label: List[str]
    label_at: np.ndarray
    text_height: float
    quantity: int
    bbox: np.ndarray = field(default_factory=lambda: np.zeros((2, 2)))
    darts: List[DartDrawing] = field(default_factory=list)
    pleats: List[PleatDrawing] = field(default_factory=list)
    mirror_gaps: Dict[str, float] = field(default_factory=dict)
    turn_points: Optional[np.ndarray] = None


def ascii_text(text: str) -> str:
    """7-bit ASCII rendering of a label (DXF AAMA and the PDF base fonts need it)."""
    s = unicodedata.normalize("NFKD", str(text)).encode("ascii", "ignore").decode("ascii")
    return "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in s)


def readable_name(label: str) -> str:
    """A body's label as a size name for files and labels: a generated label ``<kind> <number>`` (a batch's
    ``sample 17``, ``row 3``, ``betas 4``) as ``sample-0017``, any other (a table's ``name`` column) as written
    (ASCII); ``custom`` for an empty one."""
    m = re.fullmatch(r"\s*([A-Za-z]+)\s+(\d+)\s*", str(label))
    if m:
        return f"{m.group(1).lower()}-{int(m.group(2)):04d}"
    return ascii_text(label).strip() or "custom"


def size_label(pattern: Pattern) -> str:
    """The size a pattern is for, as every file names it (AAMA ``Size:`` / ``Sample Size:``, labels,
    ``export.json``): the body's chart size (``size``, or a ``shape`` given by name), else the body's ``name``
    (a batch's measured or sampled body, :func:`readable_name`), else ``custom`` for a body given only by
    its shape parameters, ``-`` without a body. Never the shape parameters themselves."""
    body = pattern.body or {}
    for key in ("size", "name", "shape"):
        value = body.get(key)
        if isinstance(value, str) and value.strip():
            return value.strip()
    return "custom" if body.get("shape") is not None else "-"


def body_summary(pattern: Pattern) -> dict:
    """The pattern's body in its own fields, for ``export.json``: ``size`` (:func:`size_label`), ``model``,
    ``pose`` (a preset's name), ``shape`` (the model's parameters, when given as such) and
    ``measurements_cm`` (where the body record carries them, e.g. a batch item's girths)."""
    body = pattern.body or {}
    out = {"size": size_label(pattern)}
    for key in ("name", "model", "pose"):
        if isinstance(body.get(key), str):
            out[key] = body[key]
    for key in ("shape", "measurements_cm"):
        if isinstance(body.get(key), dict):
            out[key] = {str(k): float(v) for k, v in sorted(body[key].items())}
    return out


def _room(sew: List[np.ndarray], y: np.ndarray, x: float, direction: float) -> float:
    """Smallest distance (m) from (x, y_k) along +-x to the sew line, over the rows y_k."""
    d = np.array([direction, 0.0])
    hits = []
    for yk in y:
        h = [t for t in (ray_hit(np.array([x, yk]), d, loop) for loop in sew) if t is not None]
        hits.append(min(h) if h else 0.0)
    return float(min(hits))


def _place_label(sew: List[np.ndarray], grain: np.ndarray, label: List[str], text_h: float):
    """Top-left corner and text height of the label, kept inside the sew line.

    Beside the grain line (1 cm to its right) where the piece is wide enough,
    else centred across it with smaller text (down to ``TEXT_MIN``).
    """
    gx = float(grain[0, 0])
    mid = 0.5 * float(grain[0, 1] + grain[1, 1])
    chars = max(len(s) for s in label)

    def rows(h):
        top = mid + 0.5 * len(label) * 1.5 * h
        return np.linspace(top, top - len(label) * 1.5 * h, 4)

    right = _room(sew, rows(text_h), gx + 0.01, 1.0)
    h = min(text_h, 0.9 * right / (CHAR_WIDTH * chars))
    if h >= 0.7 * text_h or h >= TEXT_MIN * 1.6:
        h = max(h, TEXT_MIN)
        return np.array([gx + 0.01, mid + 0.5 * len(label) * 1.5 * h]), float(h)
    left = _room(sew, rows(text_h), gx, -1.0)
    right = _room(sew, rows(text_h), gx, 1.0)
    h = float(np.clip(0.9 * (left + right) / (CHAR_WIDTH * chars), TEXT_MIN, text_h))
    width = CHAR_WIDTH * chars * h
    x0 = gx - left + 0.5 * max(left + right - width, 0.0)
    return np.array([x0, mid + 0.5 * len(label) * 1.5 * h]), h


def not_mirror_note(other: str, gap: float) -> str:
    """What a piece of a declared pair says when it is not ``other``'s mirror image, ``gap`` m off (inf: its
    drawing differs in kind): ``not the mirror of <other>: N mm off`` (or ``: differs``)."""
    why = f"{round(gap * 1000, 1):g} mm off" if np.isfinite(gap) else "differs"
    return f"not the mirror of {other}: {why}"


def _cut_line(
    quantity: int, folded: bool, panel: PatternPanel, pattern: Pattern, gaps: Optional[Dict[str, float]] = None
) -> str:
    """The label's line ``CUT_LINE``: ``cut N`` and notes: on a fold; for a declared pair, ``mirror of X`` /
    ``mirrored by X`` where ``gaps`` (other piece -> m) has it within ``MIRROR_TOL`` of X's mirror image, else
    :func:`not_mirror_note` (no ``gaps``: the declaration is taken as it stands)."""
    notes = ["cut on fold"] if folded else []
    gaps = gaps or {}
    twins = [p.name for p in pattern.panels if p.mirror_of == panel.name]
    pairs = ([(panel.mirror_of, "mirror of")] if panel.mirror_of else []) + [(t, "mirrored by") for t in twins]
    same = [(other, how) for other, how in pairs if gaps.get(other, 0.0) <= MIRROR_TOL]
    for how in ("mirror of", "mirrored by"):
        names = [other for other, h in same if h == how]
        if names:
            notes.append(f"{how} {', '.join(names)}")
    notes += [not_mirror_note(other, gaps[other]) for other, _ in pairs if gaps.get(other, 0.0) > MIRROR_TOL]
    return ascii_text(f"cut {quantity}" + "".join(f", {n}" for n in notes))


def _label(pattern: Pattern, panel: PatternPanel, quantity: int, folded: bool, edge_w: List[np.ndarray]) -> List[str]:
    """The label lines of a piece: style, piece, size, how to cut it (line ``CUT_LINE``), units and allowance."""
    size = size_label(pattern)
    return [
        ascii_text(pattern.style or "pattern"),
        ascii_text(
            f"piece: {panel.name}"
            + (f" ({panel.garment})" if panel.garment and not panel.name.startswith(panel.garment) else "")
        ),
        ascii_text(f"size: {size}"),
        _cut_line(quantity, folded, panel, pattern),
        ascii_text(f"units: mm, {allowance_text(edge_w)}"),
    ]


def build_piece(
    pattern: Pattern,
    panel: PatternPanel,
    widths: Dict[str, float],
    notch_spacing: float = DEFAULT_NOTCH_SPACING,
    mitre_limit: float = MITRE_LIMIT,
    warnings: Optional[List[str]] = None,
    grade_from: Optional[Mapping[str, float]] = None,
) -> PieceDrawing:
    """The drawing of one piece: sew and cut lines, notches, grain line, label.

    Parameters
    ----------
    pattern : the pattern (seams, style, body size).
    panel : the piece.
    widths : from :func:`core.export.allowance.resolve_allowance`.
    notch_spacing : float, m between interior notches along a seam (0: ends only).
    mitre_limit : float, see :func:`core.geom.polygon.offset_loop`.
    warnings : list or None; when given, a cut line that does not fit is drawn
        anyway and the problem appended here (see :func:`core.export.allowance.cut_line`).
    grade_from : seam name -> length (m) to grade the notches from (a graded nest's sample size,
        :func:`core.export.notches.piece_notches`), or None.
    """
    rot = grain_rotation(panel.grain)
    xy = np.asarray(panel.uv, float) @ rot.T
    loops = piece_loops(panel)
    darts = piece_darts(pattern, panel)
    if darts:
        loops = bridge_darts(loops, darts)
    table = edge_table(loops)
    edge_w = edge_allowances(pattern, panel, widths, loops, table)
    mouths = _bridge_allowance(loops, table, darts, edge_w)
    fold = fold_ids(panel)
    folds = [] if fold is None else [xy[fold]]
    sew = [xy[b] for b in loops]
    cut = piece_cut_lines(panel.name, sew, edge_w, mitre_limit, warnings)
    notches = piece_notches(pattern, panel, xy, loops, table, edge_w, cut, notch_spacing, grade_from)
    drawn = [dart_drawing(panel, s, xy) for s in darts]
    notches += _mouth_notches(darts, mouths, xy, loops, cut, edge_w)
    notches += pleat_notches(pattern, panel, xy, loops, cut, edge_w)
    # xy is already in the grain frame: the grain is +y there
    start, end = grain_line(xy, np.asarray(panel.faces, int), loops, np.array([0.0, 1.0]))
    grain, arrows = np.stack([start, end]), grain_arrows(start, end)

    quantity = 1
    label = _label(pattern, panel, quantity, bool(folds), edge_w)
    piece = PieceDrawing(
        name=panel.name,
        garment=panel.garment,
        rotation=rot,
        sew=sew,
        sew_ids=loops,
        cut=cut,
        edge_allowance=edge_w,
        fold=folds,
        notches=notches,
        grain=grain,
        arrows=arrows,
        label=label,
        label_at=np.zeros(2),
        text_height=0.0,
        quantity=quantity,
        darts=drawn,
        pleats=piece_pleats(pattern, panel, xy),
    )
    _set_label(piece, label)
    return piece


def _set_label(piece: PieceDrawing, label: List[str]) -> None:
    """Give ``piece`` the label lines ``label``: text height from the piece's size, placed inside the sew line
    (:func:`_place_label`), and the bounding box of the cut lines and the label."""
    lo = np.min([c.min(0) for c in piece.cut], axis=0)
    hi = np.max([c.max(0) for c in piece.cut], axis=0)
    text_h = float(np.clip(min(hi - lo) / (len(label) * 3.0), 0.003, 0.008))
    label_at, text_h = _place_label(piece.sew, piece.grain, label, text_h)
    tw = max(len(s) for s in label) * CHAR_WIDTH * text_h
    th = len(label) * 1.5 * text_h
    lo = np.minimum(lo, [label_at[0], label_at[1] - th])
    hi = np.maximum(hi, [label_at[0] + tw, label_at[1]])
    piece.label, piece.label_at, piece.text_height, piece.bbox = label, label_at, text_h, np.stack([lo, hi])


def relabel(piece: PieceDrawing, how: List[str], quantity: int) -> PieceDrawing:
    """A copy of ``piece`` to cut ``quantity`` times, its label's cut line (``cut 1, ...``) replaced by the lines
    ``how``.

    The label is placed again (a wider label may need smaller text) and the
    bounding box follows; lines, notches and grain are the piece's own.
    """
    out = dataclasses.replace(piece, quantity=int(quantity))
    label = list(piece.label)
    label[CUT_LINE : CUT_LINE + 1] = [ascii_text(h) for h in how]
    _set_label(out, label)
    return out


def _bridge_allowance(loops, table, darts, edge_w) -> list:
    """Give each dart's bridge (the sew edge across its mouth) the allowance of the edge
    before it (the hem or seam the dart opens on); ``(loop, edge)`` of each bridge, per dart."""
    out = []
    for s in darts:
        key = (int(s.verts_a[0]), int(s.verts_b[0]))
        if key not in table:
            out.append(None)
            continue
        li, ei = table[key]
        edge_w[li][ei] = edge_w[li][(ei - 1) % len(loops[li])]
        out.append((li, ei))
    return out


def _mouth_notches(darts, mouths, xy, loops, cut, edge_w) -> List[Notch]:
    """A notch at each leg's mouth of every dart (side ``a`` and ``b``, at arc length 0)."""
    out = []
    for s, at in zip(darts, mouths):
        if at is None:
            continue
        li, ei = at
        b = loops[li]
        d = xy[b[(ei + 1) % len(b)]] - xy[b[ei]]
        nrm = np.array([d[1], -d[0]]) / max(np.linalg.norm(d), 1e-300)
        for side, v in (("a", s.verts_a[0]), ("b", s.verts_b[0])):
            q = xy[int(v)]
            out.append(
                Notch(seam=s.name, side=side, s=0.0, point=q, normal=nrm, segment=slit(q, nrm, cut[li], edge_w[li][ei]))
            )
    return out


def resolve_notch_spacing(notch_spacing, pattern: Pattern) -> float:
    """The caller's notch spacing (m), else the design's (``materials.export.notch_spacing``), else 10 cm;
    checked by :func:`core.export.notches.check_notch_spacing` (ExportError naming the option or the field)."""
    if notch_spacing is not None:
        return check_notch_spacing(notch_spacing)
    value = ((pattern.materials or {}).get("export") or {}).get("notch_spacing", DEFAULT_NOTCH_SPACING)
    return check_notch_spacing(value, "pattern.json materials.export.notch_spacing")


def build_pieces(
    pattern: Pattern,
    allowance=None,
    notch_spacing: Optional[float] = None,
    progress=None,
    warnings: Optional[List[str]] = None,
    grade_from: Optional[Mapping[str, float]] = None,
) -> List[PieceDrawing]:
    """:func:`build_piece` for every piece of a validated pattern, in pattern order.

    Parameters
    ----------
    pattern : the pattern.
    allowance : see :func:`core.export.allowance.resolve_allowance`.
    notch_spacing : m between notches, None: the design's
        (``materials["export"]["notch_spacing"]``) or 10 cm.
    progress : ``progress(fraction, message)`` callback.
    warnings : None raises on a cut line that does not fit; a list collects
        the problems instead (lenient export).
    grade_from : see :func:`build_piece`.
    """
    from ..pattern.pleats import open_pattern

    pattern = open_pattern(pattern)  # pleats: the pieces are cut with their pleats' cloth
    widths = resolve_allowance(allowance, pattern)
    notch_spacing = resolve_notch_spacing(notch_spacing, pattern)
    out = []
    for i, panel in enumerate(pattern.panels):
        report(progress, i / max(len(pattern.panels), 1), f"piece {panel.name}")
        out.append(build_piece(pattern, panel, widths, notch_spacing, warnings=warnings, grade_from=grade_from))
    _check_pairs(pattern, out)
    return out


def _check_pairs(pattern: Pattern, pieces: List[PieceDrawing]) -> None:
    """Measure every declared pair (``mirror_of``) as the tiled PDF does (:func:`core.export.mirror_check.mirror_gap`),
    keep the figure on both pieces (``mirror_gaps``) and let their labels say whether each is the other's mirror
    image: a pair whose sides differ (ease painted on one side) must not send the cutter to flip one piece's paper
    for the other in any file."""
    for j, k in declared_pairs(pattern, pieces):
        gap = mirror_gap(pieces[j], pieces[k])
        pieces[j].mirror_gaps[pieces[k].name] = pieces[k].mirror_gaps[pieces[j].name] = gap
    for k, piece in enumerate(pieces):
        if piece.mirror_gaps:
            label = list(piece.label)
            label[CUT_LINE] = _cut_line(piece.quantity, bool(piece.fold), pattern.panels[k], pattern, piece.mirror_gaps)
            if label != piece.label:
                _set_label(piece, label)
