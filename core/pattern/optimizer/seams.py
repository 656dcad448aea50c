"""The seam system of the optimizer: seam topology, the seam plan, the seam terms.

- :func:`seam_layout`: every seam side's vertices and edges stacked over all
  seams (:class:`SeamLayout`), so the seam terms are a few array operations.
- :func:`plan_seams`: which seams are sewn gathered (:class:`SeamPlan`, a
  value passed into each solve).
- :func:`seam_matrix` and :func:`seam_rhs`: the seam terms' part of the fixed
  system matrix and of each iteration's right-hand side.

Seam terms integrate over a band one mean edge length ``h`` wide along the
seam (an edge of length ``l_i`` stands for the area ``l_i h``) with residuals
relative to ``h``::

    lambda_len      sum_i l_i/(h A) |e_i - Lbar_i d_i|^2   (length: edge e_i towards the mean length Lbar_i
                                                             of both sides along its current direction d_i)
    lambda_straight sum_i l_i/(h A) |D2 u_i - S_i|^2        (straightness: second differences towards S_i)
    lambda_curve    sum_i l_i/(h A) |D2 u_i - C_i|^2        (matched curvature with the other side)

Gathered seams have the length and matched-curvature terms off (the paper's
switch for gathered designs, per seam).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np
import scipy.sparse as sp

from ...cut.types import seam_names
from ...design.naming import mirrored_name, swap_side
from ...errors import PatternError
from ..config import SolverConfig, gather_threshold
from .dart_gaps import DartLegs, dart_legs


def seam_is_gathered(seam: str, gathered: Sequence[str]) -> bool:
    """Whether the cut seam ``seam`` (``garment.line`` or ``garment.line#k``) is named by ``gathered``.

    An entry names the seam itself, its line (``shirt.armhole_left``) or the
    line in any garment (``armhole_left``), as export allowances do
    (:func:`core.cut.types.seam_names`); ``"*"`` names every seam.
    """
    return "*" in gathered or any(n in gathered for n in seam_names(seam))


def design_gathered(materials: Optional[Mapping]) -> tuple:
    """The design's own gathered seams (``materials.gathered``: true for all, or seam line names; a
    ``*_left`` line brings its mirror, as everywhere in a mirrored design)."""
    g = (materials or {}).get("gathered")
    if g is True:
        return ("*",)
    if not g:
        return ()
    names = [str(x) for x in g]
    return tuple(names + [m for m in (mirrored_name(n.partition("#")[0]) for n in names) if m])


@dataclass(frozen=True)
class SeamSide:
    """One side of a seam: ``seam`` (index in the cut), ``gids`` (k,) global unknown ids along the
    polyline, ``rest_lengths`` (k-1,) its edges' lengths in the initial flattening (metres),
    ``edge_face`` (k-1,) the global index of each edge's triangle."""

    seam: int
    gids: np.ndarray
    rest_lengths: np.ndarray
    edge_face: np.ndarray


@dataclass(frozen=True)
class SeamLayout:
    """All seam sides stacked (built once per solver by :func:`seam_layout`).

    Edges (one per seam-side edge, ``E``): ``edge_start``/``edge_end`` (global
    ids of the ends), ``edge_partner`` (index of the sewn edge on the other
    side), ``edge_rest`` (initial lengths, metres), ``edge_face`` (the edge's
    triangle). Vertices (``V``): ``vertex_ids``, ``vertex_partner`` (the sewn
    vertex on the other side), ``vertex_side``, ``side_vertex_count`` (per
    side), for the per-side rigid fit of the matched-curvature term. Second
    differences (rows ``R``: interior vertices of sides with >= 3 vertices):
    ``second_diff`` (sparse (R, n), None when R = 0), ``row_band`` (band
    weights ``l/(h A)``), ``row_partner``, ``row_smooth`` (rows with both
    neighbours on a side with >= 3 rows), ``row_straight`` (1 on sides with >= 3
    rows: they get the straightness term), ``row_side``. ``band`` is
    ``1/(h A)``, ``h`` the mean edge length and ``A`` the total area.
    """

    sides: List[SeamSide]
    pairs: List[Tuple[int, int]]
    edge_start: np.ndarray
    edge_end: np.ndarray
    edge_partner: np.ndarray
    edge_rest: np.ndarray
    edge_face: np.ndarray
    vertex_ids: np.ndarray
    vertex_partner: np.ndarray
    vertex_side: np.ndarray
    side_vertex_count: np.ndarray
    second_diff: Optional[sp.csr_matrix]
    second_diff_T: Optional[sp.csr_matrix]
    row_band: np.ndarray
    row_partner: np.ndarray
    row_smooth: np.ndarray
    row_straight: np.ndarray
    row_side: np.ndarray
    mean_edge: float
    total_area: float
    edge_weight: Optional[np.ndarray] = None
    mouth_a: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    mouth_b: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    mouth_width: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mouth_apex: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    #: every dart's matched leg vertices (:mod:`core.pattern.optimizer.dart_gaps`: the legs kept apart)
    legs: Optional[DartLegs] = None
    #: what :func:`seam_rhs` derives from the layout on first use (its indices, the last solve's weights)
    cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)


@dataclass(frozen=True)
class SeamPlan:
    """Which seams a solve sews gathered: ``gathered`` (sorted cut seam names), ``demand`` (seam name ->
    ease demand ratio, longer side / shorter side - 1), and per seam edge / second-difference row
    ``sewn_edges`` (E,) and ``sewn_rows`` (R,): 1.0 where the seam is sewn flat, 0.0 where gathered."""

    gathered: Tuple[str, ...]
    demand: Dict[str, float]
    sewn_edges: np.ndarray
    sewn_rows: np.ndarray


def _side_edges(name: str, pd, v: np.ndarray, table) -> np.ndarray:
    """Global face index of each edge of the polyline ``v`` (panel-local ids) in panel ``pd``."""
    keys, order = table
    nf = len(pd.faces)
    ef = np.zeros(len(v) - 1, int)
    found = np.zeros(len(v) - 1, bool)
    for x, y in ((v[:-1], v[1:]), (v[1:], v[:-1])):
        q = x * pd.n + y
        pos = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
        hit = (keys[pos] == q) & ~found
        ef[hit] = pd.face_offset + order[pos[hit]] % nf
        found |= hit
    if not np.all(found):
        i = int(np.argmin(found))
        raise PatternError(
            f"seam {name!r}: vertices {(int(v[i]), int(v[i + 1]))} of panel {pd.name!r} are not joined by an edge"
        )
    return ef


#: the seam-length weight on a dart's legs, times the seams' (20 oscillates): the legs of a dart sew to
#: equal length within 0.1 mm (a seam's sides meet within ~0.3 mm at weight 1)
DART_LENGTH_WEIGHT = 10.0
#: the weight of a dart's intake term (the mouth's width), times the seam-length weight, per unit area
DART_INTAKE_WEIGHT = 0.3


def seam_layout(cut, panels, uv0: np.ndarray, n: int, mean_edge: float, total_area: float) -> SeamLayout:
    """Stack the seams of ``cut`` over the solver's panels (``_PanelData``) and initial flattening ``uv0`` (n, 2)."""
    by_name = {pd.name: pd for pd in panels}
    sides: List[SeamSide] = []
    pairs = []
    edge_tables = {}
    for si, s in enumerate(cut.seams):
        pair = []
        for pname, verts in ((s.panel_a, s.verts_a), (s.panel_b, s.verts_b)):
            pd = by_name[pname]
            v = np.asarray(verts, int)
            if pname not in edge_tables:
                # directed half-edges (i -> j) of the panel, sorted by key i * n + j
                F = pd.faces
                keys = np.concatenate([F[:, c] * pd.n + F[:, (c + 1) % 3] for c in range(3)])
                order = np.argsort(keys, kind="stable")
                edge_tables[pname] = (keys[order], order)
            ef = _side_edges(s.name, pd, v, edge_tables[pname])
            g = v + pd.offset
            sides.append(SeamSide(si, g, np.linalg.norm(np.diff(uv0[g], axis=0), axis=1), ef))
            pair.append(len(sides) - 1)
        pairs.append(tuple(pair))
    layout = _stack(sides, pairs, n, mean_edge, total_area)
    darts = [si for si, s in enumerate(cut.seams) if s.kind == "dart"]
    if not darts:
        return layout
    from dataclasses import replace

    is_dart = np.repeat([cut.seams[sd.seam].kind == "dart" for sd in sides], [len(sd.gids) - 1 for sd in sides])
    # only darts with a set intake get the mouth term ("auto" ones open as the flattening opens them)
    darts_set = [
        si for si in darts if (getattr(cut, "darts", {}) or {}).get(cut.seams[si].name, {}).get("intake") is not None
    ]
    set_w = [cut.darts[cut.seams[si].name]["intake"] for si in darts_set]
    return replace(
        layout,
        edge_weight=np.where(is_dart, DART_LENGTH_WEIGHT, 1.0),
        mouth_a=np.array([sides[pairs[si][0]].gids[0] for si in darts_set], int),
        mouth_b=np.array([sides[pairs[si][1]].gids[0] for si in darts_set], int),
        mouth_apex=np.array([sides[pairs[si][0]].gids[-1] for si in darts_set], int),
        mouth_width=np.array([float(w) for w in set_w], float),
        legs=dart_legs(sides, pairs, darts, [(cut.seams[si].panel_a, cut.seams[si].name) for si in darts]),
    )


def _length_weight(layout: SeamLayout, config: SolverConfig, plan: SeamPlan) -> np.ndarray:
    """(E,) the seam-length term's weight of every seam edge (dart legs weigh more)."""
    c = config.weights.seam_length * layout.edge_rest / (layout.mean_edge * layout.total_area) * plan.sewn_edges
    return c if layout.edge_weight is None else c * layout.edge_weight


def _intake_weight(layout: SeamLayout, config: SolverConfig) -> float:
    return DART_INTAKE_WEIGHT * config.weights.seam_length / layout.total_area


def _stack(sides: List[SeamSide], pairs, n: int, h: float, total_area: float) -> SeamLayout:
    other = {}
    for ka, kb in pairs:
        other[ka], other[kb] = kb, ka
    e_start = np.cumsum([0] + [len(sd.gids) - 1 for sd in sides])
    v_start = np.cumsum([0] + [len(sd.gids) for sd in sides])
    cat = lambda parts, dtype: np.concatenate(parts) if sides else np.zeros(0, dtype)
    edges = dict(
        edge_start=cat([sd.gids[:-1] for sd in sides], int),
        edge_end=cat([sd.gids[1:] for sd in sides], int),
        edge_rest=cat([sd.rest_lengths for sd in sides], float),
        edge_face=cat([sd.edge_face for sd in sides], int),
        edge_partner=cat([e_start[other[k]] + np.arange(len(sd.gids) - 1) for k, sd in enumerate(sides)], int),
        vertex_ids=cat([sd.gids for sd in sides], int),
        vertex_partner=cat([v_start[other[k]] + np.arange(len(sd.gids)) for k, sd in enumerate(sides)], int),
        vertex_side=cat([np.full(len(sd.gids), k) for k, sd in enumerate(sides)], int),
        side_vertex_count=np.array([len(sd.gids) for sd in sides], float),
    )
    prev, mid, nxt, band, partner, smooth, straight = [], [], [], [], [], [], []
    r_start = np.cumsum([0] + [max(len(sd.gids) - 2, 0) for sd in sides])
    for k, sd in enumerate(sides):
        g, m = sd.gids, len(sd.gids) - 2
        if m < 1:
            continue
        prev.append(g[:-2]), mid.append(g[1:-1]), nxt.append(g[2:])
        band.append(0.5 * (sd.rest_lengths[:-1] + sd.rest_lengths[1:]) / (h * total_area))
        partner.append(r_start[other[k]] + np.arange(m))
        sm = np.zeros(m, bool)
        if m >= 3:
            sm[1:-1] = True
        smooth.append(sm)
        straight.append(np.full(m, m >= 3))
    nr = int(r_start[-1]) if len(r_start) else 0
    rows = dict(
        second_diff=None,
        second_diff_T=None,
        row_band=np.zeros(0),
        row_partner=np.zeros(0, int),
        row_smooth=np.zeros(0, bool),
        row_straight=np.zeros(0, bool),
        row_side=np.zeros(0, int),
    )
    if nr:
        prev, mid, nxt = np.concatenate(prev), np.concatenate(mid), np.concatenate(nxt)
        r = np.arange(nr)
        D = sp.csr_matrix(
            (np.tile([1.0, -2.0, 1.0], nr), (np.repeat(r, 3), np.stack([prev, mid, nxt], axis=1).ravel())),
            shape=(nr, n),
        )
        rows = dict(
            second_diff=D,
            second_diff_T=D.T.tocsr(),
            row_band=np.concatenate(band),
            row_partner=np.concatenate(partner),
            row_smooth=np.concatenate(smooth),
            row_straight=np.concatenate(straight),
            row_side=np.repeat(np.arange(len(sides)), [max(len(sd.gids) - 2, 0) for sd in sides]),
        )
    return SeamLayout(sides=sides, pairs=list(pairs), mean_edge=h, total_area=total_area, **edges, **rows)


def plan_seams(
    cut,
    layout: SeamLayout,
    uv0: np.ndarray,
    K: np.ndarray,
    c_weft: np.ndarray,
    c_warp: np.ndarray,
    config: SolverConfig,
) -> SeamPlan:
    """Decide which seams are gathered, from the ease demands of the targets ``diag(c) K``.

    A side's demand is the seam's length under its own triangles' targets
    (each seam edge of the initial flattening ``uv0`` mapped by ``diag(c_t) K_t``).
    Gathered: the seams named by the configuration or the design
    (``materials.gathered``), and the seams of every line where any seam's
    demand ratio (longer side / shorter side - 1) is above the gathering
    threshold (:func:`core.pattern.config.gather_threshold`), so an armhole is
    gathered all round or not at all.

    Parameters
    ----------
    K : (f, 2, 2) float, intrinsic offsets on the reference body.
    c_weft, c_warp : (f,) float, the target scales.
    """
    T = np.stack([c_weft, c_warp], axis=1)[:, :, None] * K
    e0 = uv0[layout.edge_end] - uv0[layout.edge_start]
    Te = T[layout.edge_face]
    edge = np.hypot(Te[:, 0, 0] * e0[:, 0] + Te[:, 0, 1] * e0[:, 1], Te[:, 1, 0] * e0[:, 0] + Te[:, 1, 1] * e0[:, 1])
    start = np.cumsum([0] + [len(sd.gids) - 1 for sd in layout.sides])
    side_len = np.add.reduceat(edge, start[:-1]) if len(edge) else np.zeros(0)
    demand = {}
    for si, (ka, kb) in enumerate(layout.pairs):
        la, lb = float(side_len[ka]), float(side_len[kb])
        demand[cut.seams[si].name] = max(la, lb) / max(min(la, lb), 1e-300) - 1.0
    above = gather_threshold(config, cut.materials)
    auto = ()
    if above is not None:
        lines = {n.split("#", 1)[0] for n, r in demand.items() if r > above}
        # a line and its mirror gather together: their demands differ only by the flattening's
        # asymmetry (the cut is symmetric to 0.1 mm), not by the design
        lines |= {swap_side(n) for n in lines}
        auto = tuple(n for n in demand if n.split("#", 1)[0] in lines)
    explicit = tuple(config.seams.gathered) + design_gathered(cut.materials)
    named = [s.name for s in cut.seams if seam_is_gathered(s.name, explicit)]
    # a dart's legs always sew to equal length
    darts = {s.name for s in cut.seams if s.kind == "dart"}
    gathered = tuple(sorted((set(named) | set(auto)) - darts))
    side_gathered = np.array([seam_is_gathered(cut.seams[sd.seam].name, gathered) for sd in layout.sides], bool)
    return SeamPlan(
        gathered=gathered,
        demand=demand,
        sewn_edges=np.repeat(~side_gathered, [len(sd.gids) - 1 for sd in layout.sides]).astype(float),
        sewn_rows=np.repeat(~side_gathered, [max(len(sd.gids) - 2, 0) for sd in layout.sides]).astype(float),
    )


def seam_matrix(layout: SeamLayout, config: SolverConfig, plan: SeamPlan, L: sp.csr_matrix) -> sp.csr_matrix:
    """``L`` (n, n) plus the seam terms' part of the fixed system matrix (length, then shape)."""
    w = config.weights
    n = L.shape[0]
    if layout.sides and w.seam_length > 0:
        c = _length_weight(layout, config, plan)
        E0, E1 = layout.edge_start, layout.edge_end
        L = (
            L
            + sp.coo_matrix(
                (np.concatenate([c, c, -c, -c]), (np.concatenate([E0, E1, E0, E1]), np.concatenate([E0, E1, E1, E0]))),
                shape=(n, n),
            ).tocsr()
        )
    if len(layout.mouth_a) and w.seam_length > 0:
        # a set dart intake: |u_a - u_b - width d|^2 at each mouth
        c = np.full(len(layout.mouth_a), _intake_weight(layout, config))
        A, B = layout.mouth_a, layout.mouth_b
        L = (
            L
            + sp.coo_matrix(
                (np.concatenate([c, c, -c, -c]), (np.concatenate([A, B, A, B]), np.concatenate([A, B, B, A]))),
                shape=(n, n),
            ).tocsr()
        )
    if layout.sides and w.seam_straight + w.seam_curve > 0 and layout.second_diff is not None:
        lam = w.seam_straight + w.seam_curve * plan.sewn_rows
        L = L + layout.second_diff_T @ sp.diags(lam * layout.row_band) @ layout.second_diff
    return L


def seam_rhs(
    layout: SeamLayout, U: np.ndarray, config: SolverConfig, plan: SeamPlan, integral: np.ndarray
) -> np.ndarray:
    """Right-hand side (n, 2) of the seam terms at the current iterate ``U`` (n, 2).

    ``integral`` (E,): the length term's integral action of this solve,
    updated in place (zeros at the first iteration).

    - length: edge ``e_i`` towards ``Lbar_i d_i``, ``d_i`` its current direction
      (the paper's linearisation on the current tangent), ``Lbar_i`` the mean
      of the two sides' current lengths plus the integral of the remaining
      mismatch, so both sides end equally long (0.1 % instead of the ~1 % a
      proximal pull leaves);
    - straightness: second differences towards 0 (``"zero"``) or the mean of
      their neighbours (``"smooth"``: damps oscillations, keeps curves);
    - matched curvature: towards the mean of this side's second difference
      and the other side's, rotated by the best rigid fit of the two polylines.

    Only the ``m`` seam vertices are summed into (:func:`_rhs_index`), on flat arrays, each entry by
    the same floating-point operations in the same order as a sum over all ``n`` per coordinate.
    """
    w, s = config.weights, config.seams
    n = len(U)
    rhs = np.zeros((n, 2))
    if not layout.sides:
        return rhs
    ix = _rhs_index(layout)
    c_len, ws2, wc2 = _rhs_weights(layout, config, plan)
    Uf = U.reshape(-1)
    m = len(ix.vids)
    if w.seam_length > 0:
        cur = (Uf.take(ix.end_xy) - Uf.take(ix.start_xy)).reshape(2, -1)  # coordinate-major
        cur_len = np.sqrt(cur[0] ** 2 + cur[1] ** 2)
        Eo = layout.edge_partner
        lbar = 0.5 * (cur_len + cur_len[Eo])
        if s.length_integral > 0:
            # integral action: what the proximal pull leaves of the mismatch is
            # accumulated into this side's target until both sides agree
            integral -= s.length_integral * 0.5 * (cur_len - cur_len[Eo])
            # bounded: where the design itself makes the sides differ (weft ease on a
            # sleeve cap sewn to a warp-wise armhole) the seam gives way, not the cloth
            cap = s.length_integral_cap * lbar
            np.clip(integral, -cap, cap, out=integral)
            lbar = lbar + integral
        # (c Lbar) times the direction. Bin d m + v sums coordinate d of the edges at v in edge order, as a
        # bincount per coordinate does; a sum from +0.0 is never -0.0, so adding it to zeros changes nothing
        tgt = (c_len * lbar) * (cur / np.maximum(cur_len, 1e-300))
        part = np.bincount(ix.end_bins, tgt.ravel(), minlength=2 * m) - np.bincount(
            ix.start_bins, tgt.ravel(), minlength=2 * m
        )
    else:
        part = np.zeros(2 * m)
    part = part.reshape(2, m).T  # (m, 2), a view
    if len(layout.mouth_a) and w.seam_length > 0:
        tgt = _intake_weight(layout, config) * _mouth_targets(layout, U)
        np.add.at(part, ix.mouth_a, tgt)
        np.add.at(part, ix.mouth_b, -tgt)
    if layout.second_diff is not None and (ws2 is not None or wc2 is not None):
        d2 = (layout.second_diff @ U).ravel()  # (2R,), row-major
        # each row's terms, flat; the zero they were added to is left out: it changes no non-zero, and a
        # zero's sign cannot reach the product below (its sums start at +0.0)
        acc = None
        if ws2 is not None:
            # damp oscillations only: towards the neighbours' mean second difference
            sm = d2.copy()
            sm[ix.smooth] = 0.5 * (d2.take(ix.smooth_prev) + d2.take(ix.smooth_next))
            acc = ws2 * sm
        if wc2 is not None:
            mean = 0.5 * (d2 + _fitted_partner(layout, Uf, d2, ix))
            acc = wc2 * mean if acc is None else acc + wc2 * mean
        part = (ix.second_diff_T @ acc.reshape(-1, 2)) + part  # x + y is y + x
    rhs.reshape(-1)[ix.vids_xy] = part.ravel()
    return rhs


def _rhs_index(layout: SeamLayout) -> SimpleNamespace:
    """:func:`seam_rhs`'s indices into flat arrays on ``layout``, built on first use and kept on the layout.

    ``vids`` (m,) the seam vertices (sorted global ids), ``vids_xy`` (2m,) their entries in a flat
    (n, 2) array; ``start_xy``/``end_xy`` (2E,) the edge ends' entries, coordinate-major, and
    ``start_bins``/``end_bins`` (2E,) their bins ``d m + v`` (``v`` local); ``mouth_a``/``mouth_b``
    local; ``second_diff_T`` (m, R) the layout's rows of the seam vertices (entries in the layout's
    order). In flat (R, 2) second differences: ``smooth`` the smoothed entries, ``smooth_prev``/
    ``smooth_next`` their neighbours', ``row_partner`` (2R,) the other side's entries, ``row_turned``
    the same swapped (``d_1, d_0``) with ``turn_sign`` (-1, 1), ``row_side`` each entry's side. The
    rigid fit: ``vertex_xy`` (2V,) the sides' vertices' entries and ``side_bins2`` their bins
    ``2 side + d``, ``count2`` (2k,) the sides' vertex counts; for ``H[side, i, j]`` ``h_q``/``h_p``
    (4V,) the entries ``(v, i)`` of the partner and ``(v, j)`` of the vertex, ``side_bins4`` the bins
    ``4 side + 2 i + j``.
    """
    ix = layout.cache.get("rhs_index")
    if ix is not None:
        return ix
    D = layout.second_diff
    vids = np.unique(
        np.concatenate(
            [layout.edge_start, layout.edge_end, layout.mouth_a, layout.mouth_b]
            + ([D.indices] if D is not None else [])
        )
    )
    m, k = len(vids), len(layout.sides)
    local = lambda g: np.searchsorted(vids, g)
    xy = lambda i: (2 * i[:, None] + np.arange(2)).ravel()  # row-major entries (i, 0), (i, 1)
    major = lambda i, step: np.concatenate([i, i + step])  # coordinate-major
    partner_side = np.zeros(k, int)
    for a, b in layout.pairs:
        partner_side[a], partner_side[b] = b, a
    if not np.array_equal(layout.side_vertex_count, layout.side_vertex_count[partner_side]):
        raise PatternError("a seam's two sides have different vertex counts; they pair one to one")
    smooth, rp = np.flatnonzero(layout.row_smooth), layout.row_partner
    V, vp, side, ij = len(layout.vertex_ids), layout.vertex_partner, layout.vertex_side, np.arange(4)
    ix = SimpleNamespace(
        vids=vids,
        vids_xy=xy(vids),
        start_xy=major(2 * layout.edge_start, 1),
        end_xy=major(2 * layout.edge_end, 1),
        start_bins=major(local(layout.edge_start), m),
        end_bins=major(local(layout.edge_end), m),
        mouth_a=local(layout.mouth_a),
        mouth_b=local(layout.mouth_b),
        second_diff_T=None if D is None else layout.second_diff_T[vids],
        smooth=xy(smooth),
        smooth_prev=xy(smooth - 1),
        smooth_next=xy(smooth + 1),
        row_partner=xy(rp),
        row_turned=xy(rp)[np.arange(2 * len(rp)) ^ 1],
        turn_sign=np.tile([-1.0, 1.0], len(rp)),
        row_side=np.repeat(layout.row_side, 2),
        vertex_xy=xy(layout.vertex_ids),
        side_bins2=xy(side),
        count2=np.repeat(layout.side_vertex_count, 2),
        side_bins4=(4 * side[:, None] + ij).ravel(),
        h_q=2 * np.repeat(vp, 4) + np.tile(ij // 2, V),
        h_p=2 * np.repeat(np.arange(V), 4) + np.tile(ij % 2, V),
    )
    layout.cache["rhs_index"] = ix
    return ix


def _rhs_weights(layout: SeamLayout, config: SolverConfig, plan: SeamPlan):
    """:func:`seam_rhs`'s weights: the length term's (E,) (:func:`_length_weight`), the smoothing
    straightness term's and the matched curvature's per flat (R, 2) entry (2R,), None where a term is
    off; kept on the layout for the last plan and weights (a solve's do not change between iterations)."""
    w, s = config.weights, config.seams
    key = (w.seam_length, w.seam_straight, w.seam_curve, s.straight_target)
    got = layout.cache.get("rhs_weights")
    if got is not None and got[0] is plan and got[1] == key:
        return got[2]
    rows = layout.second_diff is not None
    out = (
        _length_weight(layout, config, plan) if w.seam_length > 0 else None,
        np.repeat(w.seam_straight * layout.row_band * layout.row_straight, 2)
        if rows and w.seam_straight > 0 and s.straight_target == "smooth"
        else None,
        np.repeat(w.seam_curve * layout.row_band * plan.sewn_rows, 2) if rows and w.seam_curve > 0 else None,
    )
    layout.cache["rhs_weights"] = (plan, key, out)
    return out


def _mouth_targets(layout: SeamLayout, U: np.ndarray) -> np.ndarray:
    """(M, 2) the target of each set-intake dart's mouth gap ``u_a - u_b``: its component across
    the dart (the normal of mouth -> apex on leg ``a``'s side, the open side of a counter-clockwise
    piece) set to the intake, so a crossed dart is pulled open; the component along the dart kept."""
    a, b = U[layout.mouth_a], U[layout.mouth_b]
    gap = a - b
    axis = U[layout.mouth_apex] - 0.5 * (a + b)
    across = np.stack([-axis[:, 1], axis[:, 0]], axis=1) / np.maximum(np.linalg.norm(axis, axis=1), 1e-300)[:, None]
    now = np.sum(gap * across, axis=1)
    return gap + (layout.mouth_width - now)[:, None] * across


def _fitted_partner(layout: SeamLayout, Uf: np.ndarray, d2: np.ndarray, ix: SimpleNamespace) -> np.ndarray:
    """The other side's second differences, flat (2R,), turned by the best rigid fit of the two seam
    polylines (per side, vectorised Kabsch); ``Uf`` and ``d2`` the iterate and second differences, flat."""
    k = len(layout.sides)
    # per-side means (bin 2 side + d sums in vertex order); the partners' means are the other side's:
    # its vertices pair with this side's in order
    P = Uf.take(ix.vertex_xy)
    Pc = P - (np.bincount(ix.side_bins2, P, minlength=2 * k) / ix.count2).take(ix.side_bins2)
    # H = Qc^T Pc per side (Qc the partners' Pc); rotation = polar(H^T)
    H = np.bincount(ix.side_bins4, Pc.take(ix.h_q) * Pc.take(ix.h_p), minlength=4 * k).reshape(k, 4)
    th = np.arctan2(H[:, 1] - H[:, 2], H[:, 0] + H[:, 3])
    # (c d_0 - s d_1, s d_0 + c d_1) as c (d_0, d_1) + s (-d_1, d_0): s (-d_1) is -(s d_1), a sum's terms commute
    return np.cos(th).take(ix.row_side) * d2.take(ix.row_partner) + np.sin(th).take(ix.row_side) * (
        d2.take(ix.row_turned) * ix.turn_sign
    )
