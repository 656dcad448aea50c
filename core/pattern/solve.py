"""The ease-driven local-global pattern optimizer (paper: "Parameterization -- Optimizing Ease").

Unknowns: the 2D positions of every panel vertex (seam vertices are
duplicated, one copy per panel), stacked over all panels; one sparse
least-squares system couples them.

Everything is expressed on the panel's initial flattening ``U0`` (LSCM,
area-matched, grain along +y). Per triangle ``t`` its gradient operator
``G_t`` (3x2, :func:`init.gradient_operators`) gives

- the 2D Jacobian of the current pattern w.r.t. the initial one,
  ``M_t = U_t^T G_t`` (2x2); its columns are ``sigma_2D`` of the paper (the 2D
  weft and warp offsets of a unit step from the centroid, barycentric offsets
  ``G_t[:, 0]`` and ``G_t[:, 1]`` fixed at the initialisation);
- the 3D offsets ``sigma_3D = X_t^T G_t`` (3x2) on any body instance ``X``;
  their intrinsic 2D coordinates ``K_t`` (2x2, the warp offset along the
  second axis) carry the triangle's metric.

Targets, with ``c = |sigma*_2D| / |sigma_3D|`` (paper Eqs. ref-scale,
transfer-scale, adapt-scale, material-scale) and ``D_t = diag(c_weft, c_warp)``:

- improved (``stretch_frame="pattern"``): ``T_t = D_t K_t``. The scales act
  along the pattern's own axes, so any rotation ``R`` of the body frame keeps
  them: ``M = D R K`` gives the 2D->3D map ``J = Q R^T D^-1`` (SPEC weft
  scale exactly ``c_weft``, no shear). The regulariser's rest shapes are
  ``D_t R_t K_t``.
- paper, literal (``stretch_frame="initial"``): ``T_t = K_t D_t``, the 2D
  offsets of the initial barycentric steps scaled by ``c``. A locally rotated
  rest shape ``R T`` then carries its stretch off the weft (at rho = 2 a 5
  degree rotation costs 1 % compliance and 7 degrees of shear): compliance and
  shear grow with rho.

Energy, every term normalised to be dimensionless and independent of the mesh
resolution and the garment size: a relative strain squared, integrated over
area and divided by the garment's total area ``A``. Seam terms integrate over
a band one mean edge length ``h`` wide along the seam (an edge of length
``l_i`` stands for the area ``l_i h``) with residuals relative to ``h``, so a
seam residual of one edge length weighs like a strain of 1 over that band,
and tiny edges (slivers at seam ends) do not stiffen the system::

    E = lambda_ease sum_t a_t |(M_t - T_t) W|^2            (E_weft + E_warp, axes fixed:
                                                             weft along x, warp along y)
      + lambda_reg  sum_t a_t |(M_t - D_t R_t K_t) W|^2   (ARAP, R_t from the local step)
      + lambda_len  sum_i l_i/(h A) |e_i - Lbar_i d_i|^2  (seam length, linearised)
      + lambda_straight sum_i l_i/(h A) |D2 u_i - S_i|^2  (seam straightness)
      + lambda_curve sum_i l_i/(h A) |D2 u_i - C_i|^2     (matched seam curvature)

with ``a_t = area_t / A`` (at least ``sliver_weight`` times the mean, so
slivers do not fold for free), ``W = diag(1, warp_weight)``. The regulariser's
rest shape is the isometric ``R_t K_t`` in the paper-default configuration
(taken literally the regulariser then fights the ease term: compliance
20-40 %) and the pre-stretched ``D_t R_t K_t`` in the improved one (no
competition: both terms agree on the target shape, the regulariser only adds
rotation freedom against curvature). ``warp_slack`` > 0 also lets the local
step scale the rest shape's warp row freely within ``1 +- slack`` (curvature
then goes into warp length rather than weft and shear), and ``warp_row_weight``
< 1 makes the local step fit each rotation to the current weft first.

Seam terms keep the system matrix fixed by targeting whole vectors:

- E_len: edge ``e_i`` towards ``Lbar_i d_i``, ``d_i`` its current direction
  (the paper's linearisation on the current tangent), ``Lbar_i`` the mean of
  the two sides' current lengths plus an integral action (``len_integral``)
  that accumulates the remaining mismatch, so both sides end equally long
  (0.1 % instead of the ~1 % a proximal pull leaves);
- E_straight: second differences towards 0 (paper) or, improved, towards the
  mean of their neighbours (damps oscillations, keeps crotch and armhole
  curves: towards 0 they are pulled straight and panels fold);
- E_curv: towards the mean of this side's second difference and the other
  side's, rotated by the best rigid fit of the two seam polylines.

Gathered seams (``SolverConfig.gathered``, the design's ``materials.gathered``,
and every seam whose two sides' ease demands differ by more than
``gather_above``) have E_len and E_curv off: the paper's switch for gathered
designs, per seam. A set-in sleeve at ease 2 wants about 40 % more cap than
the armhole has (the sleeve's weft runs along it, the bodice's warp does);
sewn flat, the difference goes into shear on both sides.

Thus the matrix never changes (factorised once per solver, configuration and
seam plan, reused by the reference, transfer and adaptation solves, which keep
the reference solve's seam plan); only the right-hand side does. One soft pin
per panel fixes the translation gauge; rotation is fixed by the ease term's axes and the grain re-alignment (area-weighted vote)
after every iteration. No triangle ever flips: the rigid part of each step is
removed per panel, then the vertices of triangles that would flip (or lose
more than half their area) step back locally (:meth:`PatternSolver._safeguard`)
from the previous, flip-free iterate.

Optional feedback (``feedback``, ``feedback_warp``) moves the weft/warp
targets by the achieved/target ratio each iteration: compliance bought with
shear (the "stretch" configuration, and adaptation solves).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Dict, List, Optional, Sequence

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from ..errors import PatternError
from ..progress import Progress, report
from ..metrics.pattern import signed_areas_2d, scales, areas_3d
from . import init as _init
from .types import Pattern, PatternPanel, PatternSeam


@dataclass(frozen=True)
class SolverConfig:
    """Weights and options of the optimizer (see module docstring for the normalisation).

    ``reg_rest``: ``"isometric"`` (paper: ARAP towards the body triangle) or
    ``"prestretch"`` (ARAP towards the triangle pre-stretched by the targets).
    ``warp_weight``: relative weight of the warp column in the ease and
    regulariser terms (< 1 lets warp give way to the weft target).
    ``seam_length``: False switches E_len off
    (gathered designs). ``adapt_margin``: pose demands are raised by this
    fraction before the tolerance applies, so that the optimizer's own
    compliance error (~1-2 %) does not leave triangles just above the
    tolerance (the paper's Eq. material-scale aims exactly at the tolerance;
    ``paper()`` sets 0). ``feedback``: gain of a per-iteration correction of
    the weft targets by the ratio target / achieved scale (SPEC rho-hat), so
    that curvature error moves out of the weft into warp and shear (0 = off,
    the paper); ``feedback_warp`` the same for the warp targets;
    ``adapt_feedback`` the weft and warp feedback used by adaptation solves
    (pose demands are local, hence incompatible in 2D without shear); there
    it aims at the poses' demands along the pattern's current weft and warp.
    ``sliver_weight``: every triangle weighs at least this fraction of the
    mean triangle weight (set when the solver is built).
    ``len_integral``: gain of the integral action on seam-edge length
    mismatch (0 = the paper's proximal linearisation only).
    ``straight_target``: ``"zero"`` (paper: second differences of seams
    towards 0, which also straightens seams that must be curved -- crotch,
    armholes) or ``"smooth"`` (towards the mean of the neighbouring second
    differences of the current seam: only oscillations are damped).
    ``stretch_frame``: ``"pattern"`` (targets ``diag(c) K``: the scales act
    along the pattern's weft/warp after the local rotation) or ``"initial"``
    (the paper literally: ``K diag(c)``, the initial flattening's barycentric
    offsets scaled). ``warp_slack``: the local step may scale the rest
    shape's warp by a factor within ``[1/(1+slack), 1+slack]`` (0 = off).
    ``warp_row_weight``: weight of the pattern's warp (v) row against the
    weft (u) row when the local step fits each triangle's rotation (< 1: the
    rest shape is turned to match the current weft first, so curvature goes
    into warp length and shear rather than weft). The global step is not
    reweighted: one factorisation serves both coordinates.
    ``gathered``: seams (cut seam names, seam lines, or lines in every
    garment; ``"*"`` for all) sewn gathered: their length and matched-
    curvature terms are off, the longer side is gathered into the shorter
    (the paper's switch for gathered designs, per seam). The design adds its
    own (``materials.gathered``). ``gather_above``: a seam whose two sides'
    ease demands (the targets' lengths along it) differ by more than this
    fraction is gathered too (a set-in sleeve at ease 2 wants about 40 % more
    cap than the armhole has; sewn flat that goes into shear); None never
    gathers on its own. The design may override it (``materials.gather_above``).
    ``adapt_iterations``, ``adapt_bound``: adaptation solves run at least
    this many iterations, and their feedback may raise a target up to this
    factor (the poses' local demands are far from uniform).
    """
    lambda_ease: float = 0.1
    lambda_reg: float = 1.0
    lambda_len: float = 15.0
    lambda_straight: float = 0.1
    lambda_curve: float = 0.1
    iterations: int = 20
    reg_rest: str = "prestretch"
    warp_weight: float = 1.0
    seam_length: bool = True
    realign_grain: bool = True
    adapt_margin: float = 0.06
    feedback: float = 0.06
    straight_target: str = "smooth"
    len_direction: str = "current"
    len_target: str = "current"
    len_integral: float = 1.0
    len_integral_cap: float = 1.0
    adapt_feedback: float = 0.5
    sliver_weight: float = 0.5
    feedback_warp: float = 0.0
    stretch_frame: str = "pattern"
    warp_slack: float = 0.12
    warp_row_weight: float = 0.5
    adapt_iterations: int = 40
    adapt_bound: float = 2.0
    gathered: tuple = ()
    gather_above: Optional[float] = 0.2


    @classmethod
    def paper(cls, **kw) -> "SolverConfig":
        """The paper's weights taken literally (isometric ARAP regulariser)."""
        return replace(cls(reg_rest="isometric", adapt_margin=0.0, gather_above=None, feedback=0.0, straight_target="zero", len_target="current",
                           stretch_frame="initial", warp_slack=0.0, warp_row_weight=1.0, lambda_len=100.0, lambda_straight=5.0, lambda_curve=10.0, len_integral=0.0,
                           adapt_feedback=0.0), **kw)

    @classmethod
    def improved(cls, **kw) -> "SolverConfig":
        """Our default: pre-stretched ARAP rest shape, lighter seam-shape terms, free warp length within 12 %,
        light weft feedback (gain 0.06), seams gathered where their sides' demands differ by > 20 %."""
        return replace(cls(), **kw)

    @classmethod
    def stretch(cls, **kw) -> "SolverConfig":
        """Improved, with a stronger weft target feedback (gain 0.15), warp slack 0.1 and both rows weighted
        alike: compliance bought with shear and local warp length."""
        return replace(cls(feedback=0.15, warp_slack=0.1, warp_row_weight=1.0), **kw)

    @classmethod
    def named(cls, name: str, **kw) -> "SolverConfig":
        table = {"paper": cls.paper, "improved": cls.improved, "stretch": cls.stretch}
        if name not in table:
            raise PatternError(f"solver configuration: expected one of {', '.join(table)}, got {name!r}")
        return table[name](**kw)

    def check(self) -> None:
        for k in ("lambda_ease", "lambda_reg", "lambda_len", "lambda_straight", "lambda_curve", "warp_weight",
                  "adapt_margin", "warp_row_weight", "adapt_bound"):
            v = getattr(self, k)
            if not np.isfinite(v) or v < 0:
                raise PatternError(f"solver configuration {k}: expected a finite value >= 0, got {v}")
        if self.lambda_ease + self.lambda_reg <= 0:
            raise PatternError("solver configuration: lambda_ease + lambda_reg must be > 0")
        if self.warp_weight <= 0:
            raise PatternError("solver configuration warp_weight: expected > 0")
        if self.warp_row_weight <= 0:
            raise PatternError("solver configuration warp_row_weight: expected > 0")
        if self.adapt_bound < 1:
            raise PatternError(f"solver configuration adapt_bound: expected >= 1, got {self.adapt_bound}")
        if int(self.iterations) < 1:
            raise PatternError(f"solver configuration iterations: expected >= 1, got {self.iterations}")
        if self.straight_target not in ("zero", "smooth"):
            raise PatternError(f"solver configuration straight_target: expected 'zero' or 'smooth', got {self.straight_target!r}")
        if self.stretch_frame not in ("pattern", "initial"):
            raise PatternError(f"solver configuration stretch_frame: expected 'pattern' or 'initial', got {self.stretch_frame!r}")
        if not np.isfinite(self.warp_slack) or self.warp_slack < 0:
            raise PatternError(f"solver configuration warp_slack: expected a finite value >= 0, got {self.warp_slack}")
        if self.gather_above is not None and (not np.isfinite(self.gather_above) or self.gather_above <= 0):
            raise PatternError(f"solver configuration gather_above: expected a fraction > 0 or None, got {self.gather_above}")
        if isinstance(self.gathered, str) or not all(isinstance(g, str) for g in self.gathered):
            raise PatternError(f"solver configuration gathered: expected a tuple of seam names, got {self.gathered!r}")
        if self.reg_rest not in ("isometric", "prestretch"):
            raise PatternError(f"solver configuration reg_rest: expected 'isometric' or 'prestretch', got {self.reg_rest!r}")


# ----------------------------------------------------------------------------- validation

def _design_gathered(materials: dict) -> tuple:
    """The design's own gathered seams (``materials.gathered``: true for all, or seam line names; a
    ``*_left`` line brings its mirror, as everywhere in a mirrored design)."""
    from ..design.mirror import mirrored_name
    g = (materials or {}).get("gathered")
    if g is True:
        return ("*",)
    if not g:
        return ()
    names = [str(x) for x in g]
    return tuple(names + [m for m in (mirrored_name(n.partition("#")[0]) for n in names) if m])


def seam_is_gathered(seam: str, gathered: Sequence[str]) -> bool:
    """Whether the cut seam ``seam`` (``garment.line`` or ``garment.line#k``) is named by ``gathered``.

    An entry names the seam itself, its line (``shirt.armhole_left``) or the
    line in any garment (``armhole_left``), as export allowances do
    (:func:`core.cut.types.seam_names`); ``"*"`` names every seam.
    """
    from ..cut.types import seam_names
    return "*" in gathered or any(n in gathered for n in seam_names(seam))


def validate_cut(cut) -> None:
    """Raise :class:`PatternError` naming the first invalid element of a GarmentCut."""
    if not cut.panels:
        raise PatternError("cut has no panels")
    N = cut.n_vertices
    names = set()
    for p in cut.panels:
        if p.name in names:
            raise PatternError(f"panel {p.name!r}: duplicate name")
        names.add(p.name)
        F = np.asarray(p.faces)
        vids = np.asarray(p.vertex_ids)
        if F.ndim != 2 or F.shape[0] == 0 or F.shape[1] != 3:
            raise PatternError(f"panel {p.name!r}: empty panel (faces must be a non-empty (f, 3) array, got shape {F.shape})")
        if vids.ndim != 1 or vids.size < 3:
            raise PatternError(f"panel {p.name!r}: vertex_ids must list >= 3 vertices")
        if F.min() < 0 or F.max() >= vids.size:
            raise PatternError(f"panel {p.name!r}: faces index outside [0, {vids.size})")
        if vids.min() < 0 or vids.max() >= N:
            raise PatternError(f"panel {p.name!r}: vertex_ids outside the embedding's {N} rows")
        ease = np.asarray(p.ease, float)
        if ease.shape != (F.shape[0],):
            raise PatternError(f"panel {p.name!r}: ease must have one value per triangle ({F.shape[0]}), got shape {ease.shape}")
        bad = ~np.isfinite(ease) | (ease <= 0)
        if np.any(bad):
            t = int(np.argmax(bad))
            raise PatternError(f"panel {p.name!r}: ease of triangle {t} is {ease[t]}; expected a finite weft scale > 0")
        wd = np.asarray(p.warp_dir, float)
        if wd.shape != (F.shape[0], 3) or not np.all(np.isfinite(wd)):
            raise PatternError(f"panel {p.name!r}: warp_dir must be a finite (f, 3) array, got shape {wd.shape}")
    for s in cut.seams:
        for side in ("panel_a", "panel_b"):
            if getattr(s, side) not in names:
                raise PatternError(f"seam {s.name!r}: {side} {getattr(s, side)!r} is not a panel of the cut")
        va, vb = np.asarray(s.verts_a), np.asarray(s.verts_b)
        if va.ndim != 1 or va.shape != vb.shape or va.size < 2:
            raise PatternError(f"seam {s.name!r}: verts_a and verts_b must be equally long polylines of >= 2 "
                               f"vertices, got {va.shape} and {vb.shape}")
        for side, v in (("a", va), ("b", vb)):
            n = len(cut.panel(getattr(s, f"panel_{side}")).vertex_ids)
            if v.min() < 0 or v.max() >= n:
                raise PatternError(f"seam {s.name!r}: verts_{side} outside [0, {n})")


def _check_eps(name: str, eps: float) -> float:
    eps = float(eps)
    if not np.isfinite(eps) or eps < 1.0:
        raise PatternError(f"{name}: a stretch tolerance must be >= 1 (1.1 = 10 % stretch), got {eps}")
    return eps


# ----------------------------------------------------------------------------- geometry helpers

def intrinsic_offsets(X_t: np.ndarray, G: np.ndarray) -> tuple:
    """3D weft/warp offsets and their intrinsic 2D coordinates.

    Parameters
    ----------
    X_t : (f, 3, 3) triangle vertex positions on a body instance.
    G : (f, 3, 2) gradient operators of the initial flattening.

    Returns
    -------
    K : (f, 2, 2) columns: the weft and warp offsets in an orthonormal tangent
        frame whose second axis is the warp offset (lower-triangular).
    len_weft, len_warp : (f,) lengths |sigma_3D| (metres per unit 2D step).
    """
    S = _jac(X_t, G)  # (f, 3, 2)
    sw, sg = S[:, :, 0], S[:, :, 1]
    lw = np.linalg.norm(sw, axis=1)
    lg = np.linalg.norm(sg, axis=1)
    safe = np.where(lg > 0, lg, 1.0)
    along = np.sum(sw * sg, axis=1) / safe
    across = np.linalg.norm(np.cross(sw, sg), axis=1) / safe
    K = np.zeros((len(G), 2, 2))
    K[:, 0, 0] = across
    K[:, 1, 0] = along
    K[:, 1, 1] = lg
    return K, lw, lg


def _jac(Ut: np.ndarray, G: np.ndarray) -> np.ndarray:
    """``M[t] = Ut[t]^T G[t]`` for Ut (f, 3, d), G (f, 3, 2) -> (f, d, 2) (explicit sums: fast)."""
    return (Ut[:, 0, :, None] * G[:, 0, None, :] + Ut[:, 1, :, None] * G[:, 1, None, :]
            + Ut[:, 2, :, None] * G[:, 2, None, :])


def _turn(P: np.ndarray, c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Rows of ``P`` (n, 2) turned counter-clockwise by per-row angles with cosines ``c`` and sines ``s``."""
    out = np.empty_like(P)
    out[:, 0] = c * P[:, 0] - s * P[:, 1]
    out[:, 1] = s * P[:, 0] + c * P[:, 1]
    return out


def _components(A: np.ndarray) -> list:
    """A (f, 2, 2) as 4 contiguous (f,) arrays a00, a01, a10, a11."""
    return [np.ascontiguousarray(A[:, i, j]) for i in range(2) for j in range(2)]


def _achieved(M: list, Kc: list):
    """SPEC rho-hat weft and warp (f,) of pattern Jacobians ``M`` on a body with intrinsic offsets ``Kc``.

    ``J = Q K M^-1`` (Q orthonormal): ``|J w| = |K M^-1 e_x|``, ``|J g| = |K M^-1 e_y|``.
    """
    det = M[0] * M[3] - M[1] * M[2]
    wx, wy = M[3], -M[2]        # det * M^-1 e_x
    gx, gy = -M[1], M[0]        # det * M^-1 e_y
    with np.errstate(divide="ignore", invalid="ignore"):
        rw = np.abs(det) / np.hypot(Kc[0] * wx + Kc[1] * wy, Kc[2] * wx + Kc[3] * wy)
        rg = np.abs(det) / np.hypot(Kc[0] * gx + Kc[1] * gy, Kc[2] * gx + Kc[3] * gy)
    return rw, rg


# ----------------------------------------------------------------------------- solver

@dataclass
class _PanelData:
    name: str
    offset: int
    n: int
    faces: np.ndarray      # local
    gfaces: np.ndarray     # global unknown ids
    vertex_ids: np.ndarray
    warp_dir: np.ndarray
    ease: np.ndarray
    uv0: np.ndarray
    G: np.ndarray
    area0: np.ndarray      # initial 2D areas (= 3D areas up to LSCM distortion)
    face_offset: int = 0


@dataclass
class _SeamSide:
    seam: int
    gids: np.ndarray       # global unknown ids along the polyline
    l0: np.ndarray         # initial 2D edge lengths (k-1,)
    edge_face: np.ndarray  # (k-1,) global face index of each edge's triangle
    edge_local: np.ndarray  # (k-1, 2) which corners (0..2) of that face the edge runs from/to


@dataclass
class SolveResult:
    """The outcome of one solve: per panel ``uv`` and per-triangle targets."""
    uv: Dict[str, np.ndarray]
    target_weft: Dict[str, np.ndarray]
    target_warp: Dict[str, np.ndarray]
    xyz: Dict[str, np.ndarray]
    seconds: float
    iterations: int
    backtracks: int
    energy: List[float] = field(default_factory=list)
    gathered: tuple = ()


class PatternSolver:
    """Local-global ease optimizer over all panels of a cut, factorised once.

    Parameters
    ----------
    cut : GarmentCut
    body_vertices : (V, 3) the reference body instance the cut was made on.
    config : SolverConfig (default :meth:`SolverConfig.improved`).
    """

    def __init__(self, cut, body_vertices: np.ndarray, config: Optional[SolverConfig] = None,
                 progress: Optional[Progress] = None):
        validate_cut(cut)
        self.cut = cut
        self.config = config or SolverConfig.improved()
        self.config.check()
        t0 = time.perf_counter()
        self.ref_positions = self._positions(body_vertices, "reference body")
        self.panels: List[_PanelData] = []
        offset = 0
        face_offset = 0
        flat = []
        for k, p in enumerate(cut.panels):
            report(progress, 0.8 * k / len(cut.panels), f"flattening panel {p.name}")
            xyz = self.ref_positions[np.asarray(p.vertex_ids, int)]
            F = np.asarray(p.faces, np.int64)
            if np.all(areas_3d(xyz, F) <= 0):
                raise PatternError(f"panel {p.name!r}: all triangles are degenerate on the reference body")
            fl = _init.flatten_panel(xyz, F, np.asarray(p.warp_dir, float))
            flat.append(fl)
            self.panels.append(_PanelData(p.name, offset, len(p.vertex_ids), F, F + offset,
                                          np.asarray(p.vertex_ids, int), np.asarray(p.warp_dir, float),
                                          np.asarray(p.ease, float), fl["uv"], fl["G"], fl["area"], face_offset))
            offset += len(p.vertex_ids)
            face_offset += len(F)
        self.n = offset
        self.gfaces = np.concatenate([pd.gfaces for pd in self.panels])
        self.G = np.concatenate([pd.G for pd in self.panels])
        self.a = np.concatenate([pd.area0 for pd in self.panels])
        self._area_floor = 1e-6 * np.abs(self.a)
        self._Fcols = tuple(np.ascontiguousarray(self.gfaces[:, c]) for c in range(3))
        nf = len(self.gfaces)
        # vertex -> incident faces, for the flip safeguard's local re-checks
        self._vf = sp.csr_matrix((np.ones(3 * nf), (self.gfaces.ravel(), np.repeat(np.arange(nf), 3))),
                                 shape=(self.n, nf))
        self.face_panel = np.concatenate([np.full(len(pd.faces), k) for k, pd in enumerate(self.panels)])
        # the 3D warp pulled back to the initial flattening (a material direction: the pattern's
        # own Jacobian carries it, whatever body the pattern is solved on) and its vote weight
        self._warp0 = np.concatenate([fl["warp"] for fl in flat])
        self._warp_w = np.concatenate([fl["warp_weight"] for fl in flat])
        self.total_area = float(self.a.sum())
        self.a = self.a / self.total_area
        # slivers (cut boundaries meet the body mesh at grazing angles) would weigh almost
        # nothing and fold freely: give every triangle at least a fraction of the mean weight
        self.a = np.maximum(self.a, self.config.sliver_weight * float(np.mean(self.a)))
        self.uv0 = np.concatenate([pd.uv0 for pd in self.panels])
        el = np.linalg.norm(self.uv0[self.gfaces[:, [1, 2, 0]]] - self.uv0[self.gfaces], axis=2)
        self.h = float(np.mean(el))
        # panels are contiguous blocks of vertices and of faces: per-panel sums are reduceat's
        self._voff = np.array([pd.offset for pd in self.panels])
        self._vcount = np.array([pd.n for pd in self.panels], float)
        self._foff = np.array([pd.face_offset for pd in self.panels])
        self._fcount = np.array([len(pd.faces) for pd in self.panels])
        counts = np.array([pd.n for pd in self.panels])
        self._vrep = lambda x: np.repeat(x, counts, axis=0)
        self._build_seams()
        # scatter of per-triangle corner contributions into the unknowns
        f = len(self.gfaces)
        rows = np.repeat(np.arange(f), 3)
        cols = self.gfaces.ravel()
        # gradient operators as sparse (f, n) matrices: (Gx @ U)[t] = M_t[:, 0], (Gy @ U)[t] = M_t[:, 1]
        self._Gx = sp.csr_matrix((self.G[:, :, 0].ravel(), (rows, cols)), shape=(f, self.n))
        self._Gy = sp.csr_matrix((self.G[:, :, 1].ravel(), (rows, cols)), shape=(f, self.n))
        self._GxT = self._Gx.T.tocsr()
        self._GyT = self._Gy.T.tocsr()
        self._factor = None
        self._factor_key = None
        self._planned = False
        self.seam_demand: Dict[str, float] = {}
        self.timings = {"init": time.perf_counter() - t0}
        report(progress, 1.0, "flattened")

    # ------------------------------------------------------------------ setup
    def _positions(self, body_vertices, what) -> np.ndarray:
        X = np.asarray(body_vertices, float)
        if X.ndim != 2 or X.shape[1] != 3 or not np.all(np.isfinite(X)):
            raise PatternError(f"{what}: expected finite body vertices (V, 3), got shape {X.shape}")
        if X.shape[0] != self.cut.embedding.shape[1]:
            raise PatternError(f"{what}: has {X.shape[0]} vertices, the cut's embedding expects "
                               f"{self.cut.embedding.shape[1]}")
        return self.cut.positions(X)

    def _build_seams(self) -> None:
        by_name = {pd.name: pd for pd in self.panels}
        self.sides: List[_SeamSide] = []
        self.seam_pairs = []
        edge_tables = {}
        for si, s in enumerate(self.cut.seams):
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
                keys, order = edge_tables[pname]
                nf = len(pd.faces)
                ef, el = np.zeros(len(v) - 1, int), np.zeros((len(v) - 1, 2), int)
                found = np.zeros(len(v) - 1, bool)
                for fwd, (x, y) in ((True, (v[:-1], v[1:])), (False, (v[1:], v[:-1]))):
                    q = x * pd.n + y
                    pos = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
                    hit = (keys[pos] == q) & ~found
                    h = order[pos[hit]]
                    fi, c = h % nf, h // nf
                    ef[hit] = pd.face_offset + fi
                    el[hit] = np.stack([c, (c + 1) % 3], axis=1) if fwd else np.stack([(c + 1) % 3, c], axis=1)
                    found |= hit
                if not np.all(found):
                    i = int(np.argmin(found))
                    raise PatternError(f"seam {s.name!r}: vertices {(int(v[i]), int(v[i + 1]))} of panel {pname!r} "
                                       "are not joined by an edge")
                g = v + pd.offset
                l0 = np.linalg.norm(np.diff(self.uv0[g], axis=0), axis=1)
                self.sides.append(_SeamSide(si, g, l0, ef, el))
                pair.append(len(self.sides) - 1)
            self.seam_pairs.append(tuple(pair))
        self._stack_seams()

    def _stack_seams(self) -> None:
        """All seam sides concatenated, so that the seam right-hand side is a few array operations.

        Edges: ``_E0``/``_E1`` (global ids of each seam edge's ends), ``_Eo``
        (index of the sewn edge on the other side), ``_El0`` (initial
        lengths), ``_Ef`` (the edge's triangle). Second differences: one
        sparse ``_Dall`` (rows: interior seam vertices of sides with >= 3
        vertices), ``_Ro`` (the sewn row on the other side), ``_Rcc`` (band
        weights), ``_Rsmooth`` (rows that have both neighbours on a side with
        >= 3 rows), ``_Rend`` (rows whose side has >= 3 rows: they get the
        straightness term). Vertices: ``_Vg``, ``_Vo``, ``_Vside`` for the
        per-side rigid fit of the matched-curvature term.
        """
        sides = self.sides
        other = {}
        for ka, kb in self.seam_pairs:
            other[ka], other[kb] = kb, ka
        e_start = np.cumsum([0] + [len(sd.gids) - 1 for sd in sides])
        v_start = np.cumsum([0] + [len(sd.gids) for sd in sides])
        self._E0 = np.concatenate([sd.gids[:-1] for sd in sides]) if sides else np.zeros(0, int)
        self._E1 = np.concatenate([sd.gids[1:] for sd in sides]) if sides else np.zeros(0, int)
        self._El0 = np.concatenate([sd.l0 for sd in sides]) if sides else np.zeros(0)
        self._Ef = np.concatenate([sd.edge_face for sd in sides]) if sides else np.zeros(0, int)
        self._Eo = np.concatenate([e_start[other[k]] + np.arange(len(sd.gids) - 1) for k, sd in enumerate(sides)]) \
            if sides else np.zeros(0, int)
        self._Vg = np.concatenate([sd.gids for sd in sides]) if sides else np.zeros(0, int)
        self._Vo = np.concatenate([v_start[other[k]] + np.arange(len(sd.gids)) for k, sd in enumerate(sides)]) \
            if sides else np.zeros(0, int)
        self._Vside = np.concatenate([np.full(len(sd.gids), k) for k, sd in enumerate(sides)]) if sides else np.zeros(0, int)
        self._Vcount = np.array([len(sd.gids) for sd in sides], float)
        rows, prev, mid, nxt, cc, ro, smooth, straight = [], [], [], [], [], [], [], []
        r_start = np.cumsum([0] + [max(len(sd.gids) - 2, 0) for sd in sides])
        for k, sd in enumerate(sides):
            g, m = sd.gids, len(sd.gids) - 2
            if m < 1:
                continue
            prev.append(g[:-2]), mid.append(g[1:-1]), nxt.append(g[2:])
            cc.append(0.5 * (sd.l0[:-1] + sd.l0[1:]) / (self.h * self.total_area))
            ro.append(r_start[other[k]] + np.arange(m))
            sm = np.zeros(m, bool)
            if m >= 3:
                sm[1:-1] = True
            smooth.append(sm)
            straight.append(np.full(m, m >= 3))
        nr = int(r_start[-1]) if len(r_start) else 0
        if nr:
            prev, mid, nxt = np.concatenate(prev), np.concatenate(mid), np.concatenate(nxt)
            r = np.arange(nr)
            self._Dall = sp.csr_matrix((np.tile([1.0, -2.0, 1.0], nr),
                                        (np.repeat(r, 3), np.stack([prev, mid, nxt], axis=1).ravel())),
                                       shape=(nr, self.n))
            self._DallT = self._Dall.T.tocsr()
            self._Rcc, self._Ro = np.concatenate(cc), np.concatenate(ro)
            self._Rsmooth, self._Rstraight = np.concatenate(smooth), np.concatenate(straight)
            self._Rside = np.repeat(np.arange(len(sides)), [max(len(sd.gids) - 2, 0) for sd in sides])
        else:
            self._Dall = None

    def _sewn_edges(self):
        """Per seam edge and per seam second-difference row: 1.0 where the seam is sewn flat, 0.0 on
        gathered seams (:attr:`gathered`: their length and matched-curvature terms are off)."""
        key = self.gathered
        if getattr(self, "_gathered_key", None) != key:
            gathered = np.array([seam_is_gathered(self.cut.seams[sd.seam].name, key) for sd in self.sides], bool)
            self._sewn = (np.repeat(~gathered, [len(sd.gids) - 1 for sd in self.sides]).astype(float),
                          np.repeat(~gathered, [max(len(sd.gids) - 2, 0) for sd in self.sides]).astype(float))
            self._gathered_key = key
        return self._sewn

    def _matrix(self) -> sp.csc_matrix:
        """The fixed system matrix (both pattern coordinates): ease + regulariser (one operator), seam
        length, seam shape, and the gauge pins (stored in ``self._pin``, (n, 2))."""
        cfg = self.config
        W2 = np.array([1.0, cfg.warp_weight ** 2])
        w = (cfg.lambda_ease + cfg.lambda_reg) * self.a
        L = (self._GxT @ sp.diags(w * W2[0]) @ self._Gx + self._GyT @ sp.diags(w * W2[1]) @ self._Gy).tocsr()
        if self.sides and cfg.seam_length and cfg.lambda_len > 0:
            c = cfg.lambda_len * self._El0 / (self.h * self.total_area) * self._sewn_edges()[0]
            E0, E1 = self._E0, self._E1
            L = L + sp.coo_matrix((np.concatenate([c, c, -c, -c]),
                                   (np.concatenate([E0, E1, E0, E1]), np.concatenate([E0, E1, E1, E0]))),
                                  shape=(self.n, self.n)).tocsr()
        lam = cfg.lambda_straight + cfg.lambda_curve
        if self.sides and lam > 0 and self._Dall is not None:
            lam = cfg.lambda_straight + cfg.lambda_curve * self._sewn_edges()[1]
            L = L + self._DallT @ sp.diags(lam * self._Rcc) @ self._Dall
        # translation gauge: one soft pin per panel, tiny against the diagonal
        d = L.diagonal()
        pin = np.zeros(self.n)
        pin[self._voff] = 1e-6 * np.add.reduceat(d, self._voff) / self._vcount
        self._pin = np.stack([pin, pin], axis=1)
        return (L + sp.diags(pin)).tocsc()

    def _solver(self):
        """Back-substitution ``rhs (n, 2) -> U (n, 2)`` with the factorised matrix, built once per configuration."""
        cfg = self.config
        key = (cfg.lambda_ease, cfg.lambda_reg, cfg.lambda_len, cfg.lambda_straight, cfg.lambda_curve,
               cfg.warp_weight, cfg.seam_length, self.gathered)
        if self._factor is None or self._factor_key != key:
            t0 = time.perf_counter()
            # symmetric positive definite: a symmetric minimum-degree ordering on A + A^T keeps the
            # factors ~40 % sparser than the default column ordering (faster factor and solves)
            A = self._matrix()
            self._factor = splu(A, permc_spec="MMD_AT_PLUS_A", options={"SymmetricMode": True}).solve
            self._factor_key = key
            self.timings["factorise"] = time.perf_counter() - t0
            self.n_factorisations = getattr(self, "n_factorisations", 0) + 1
        return self._factor

    # ------------------------------------------------------------------ seam plan
    @property
    def gathered(self) -> tuple:
        """Names of the cut seams sewn gathered in the next solve (sorted)."""
        explicit = tuple(self.config.gathered) + _design_gathered(self.cut.materials)
        names = [s.name for s in self.cut.seams if seam_is_gathered(s.name, explicit)]
        return tuple(sorted(set(names) | set(getattr(self, "_auto_gathered", ()))))

    def plan_seams(self, K: np.ndarray, c_weft: np.ndarray, c_warp: np.ndarray) -> Dict[str, float]:
        """Decide which seams are gathered from the ease demands of ``diag(c) K`` (config ``gather_above``).

        A side's demand is the seam's length under its own triangles' targets
        (each seam edge of the initial flattening mapped by ``diag(c_t) K_t``).
        Returns seam name -> demand ratio (longer side / shorter side - 1);
        seams of a line are gathered together when any of them is above the
        threshold, so an armhole is gathered all round or not at all.
        """
        T = np.stack([c_weft, c_warp], axis=1)[:, :, None] * K
        e0 = self.uv0[self._E1] - self.uv0[self._E0]
        Te = T[self._Ef]
        edge = np.hypot(Te[:, 0, 0] * e0[:, 0] + Te[:, 0, 1] * e0[:, 1], Te[:, 1, 0] * e0[:, 0] + Te[:, 1, 1] * e0[:, 1])
        start = np.cumsum([0] + [len(sd.gids) - 1 for sd in self.sides])
        side_len = np.add.reduceat(edge, start[:-1]) if len(edge) else np.zeros(0)
        demand = {}
        for si, (ka, kb) in enumerate(self.seam_pairs):
            la, lb = float(side_len[ka]), float(side_len[kb])
            demand[self.cut.seams[si].name] = max(la, lb) / max(min(la, lb), 1e-300) - 1.0
        above = self.cut.materials.get("gather_above", self.config.gather_above)
        auto = ()
        if above is not None:
            lines = {n.split("#", 1)[0] for n, r in demand.items() if r > float(above)}
            auto = tuple(n for n in demand if n.split("#", 1)[0] in lines)
        self._auto_gathered = auto
        self._planned = True
        self.seam_demand = demand
        return demand

    def _plan_from_design(self, K_ref: Optional[np.ndarray] = None) -> None:
        """Transfer and adaptation keep the reference solve's seam plan; without one, plan it from the
        design's ease on the reference body (intrinsic offsets ``K_ref`` when the caller has them)."""
        if not self._planned:
            if K_ref is None:
                K_ref = self._offsets(self.ref_positions)[0]
            ease = np.concatenate([pd.ease for pd in self.panels])
            self.plan_seams(K_ref, ease, np.ones_like(ease))

    # ------------------------------------------------------------------ targets
    def _offsets(self, positions: np.ndarray):
        X = np.concatenate([positions[pd.vertex_ids][pd.faces] for pd in self.panels])
        return intrinsic_offsets(X, self.G)

    def targets_reference(self, positions: Optional[np.ndarray] = None, ease=None):
        """Targets of Eq. ref-scale (or transfer-scale on other ``positions``): c = (rho_weft, 1).

        ``ease``: optional override of the cut's weft ease, a scalar or one
        value per triangle of all panels in order (benchmarks sweep it).
        """
        K, lw, lg = self._offsets(self.ref_positions if positions is None else positions)
        if ease is None:
            ease = np.concatenate([pd.ease for pd in self.panels])
        else:
            ease = np.broadcast_to(np.asarray(ease, float), (len(self.gfaces),)).copy()
            if not np.all(np.isfinite(ease) & (ease > 0)):
                raise PatternError("ease override: expected finite weft scales > 0")
        if positions is None:
            self.plan_seams(K, ease, np.ones_like(ease))
        else:
            self._plan_from_design()
        return K, ease.copy(), np.ones_like(ease)

    def targets_adapt(self, pose_positions: Sequence[np.ndarray], eps_weft: float, eps_warp: float):
        """Targets of Eq. material-scale: per direction max(rho sigma_ref, max_i sigma_i / eps)."""
        eps_weft = _check_eps("eps_weft", eps_weft)
        eps_warp = _check_eps("eps_warp", eps_warp)
        K, lw, lg = self._offsets(self.ref_positions)
        self._plan_from_design(K)
        ease = np.concatenate([pd.ease for pd in self.panels])
        want_w = ease * lw
        want_g = 1.0 * lg
        m = 1.0 + self.config.adapt_margin
        for P in pose_positions:
            _, lwi, lgi = self._offsets(P)
            want_w = np.maximum(want_w, m * lwi / eps_weft)
            want_g = np.maximum(want_g, m * lgi / eps_warp)
        with np.errstate(divide="ignore", invalid="ignore"):
            cw = np.where(lw > 0, want_w / lw, ease)
            cg = np.where(lg > 0, want_g / lg, 1.0)
        return K, cw, cg

    def pose_demands(self, pose_positions: Sequence[np.ndarray], eps_weft: float, eps_warp: float) -> dict:
        """What adaptation solves feed back on (see :meth:`solve`): the poses' intrinsic offsets and tolerances."""
        return {"offsets": [_components(self._offsets(P)[0]) for P in pose_positions],
                "ease_weft": np.concatenate([pd.ease for pd in self.panels]), "ease_warp": np.ones(len(self.gfaces)),
                "eps_weft": _check_eps("eps_weft", eps_weft), "eps_warp": _check_eps("eps_warp", eps_warp),
                "margin": 1.0 + self.config.adapt_margin}

    # ------------------------------------------------------------------ iterations
    def solve(self, K: np.ndarray, c_weft: np.ndarray, c_warp: np.ndarray, start: Optional[np.ndarray] = None,
              positions: Optional[np.ndarray] = None, progress: Optional[Progress] = None,
              poses: Optional[dict] = None) -> SolveResult:
        """Run the local-global iterations towards targets ``diag(c_weft, c_warp) K`` (module docstring).

        Per iteration: the local step (closed-form rotations, all triangles at
        once), one right-hand side, one back-substitution of the factorised
        matrix for both coordinates, the per-panel rigid fit, the flip
        safeguard and the grain re-alignment; the Jacobians of the next
        iterate are carried through the re-alignment's rotation, so only two
        sparse products per iteration touch the triangles.

        ``poses`` (adaptation, from :meth:`pose_demands`): the feedback then
        aims, per triangle, at the larger of the design ease and what every
        pose demands along the pattern's *current* weft/warp directions
        (Eq. material-scale evaluated where the metric measures it), so the
        local rotations of the solve cannot turn a demand off the weft.
        """
        cfg = self.config
        t0 = time.perf_counter()
        lu = self._solver()
        W2 = np.array([1.0, cfg.warp_weight ** 2])
        U = self._scaled_start(c_weft, c_warp) if start is None else start.copy()
        pos = self.ref_positions if positions is None else positions
        nf = len(self.gfaces)
        corr_w = np.ones(nf)
        corr_g = np.ones(nf)
        energies = []
        backtracks = 0
        n_it = int(cfg.iterations) if poses is None else max(int(cfg.iterations), int(cfg.adapt_iterations))
        hi = 1.25 if poses is None else cfg.adapt_bound
        step = 0.03 if poses is None else 0.06
        tg = self._target_parts(K, c_weft, c_warp)
        Kc = _components(K)
        aw = (self.a * W2[0], self.a * W2[1])
        M = self._jac4(U)
        s_cur = None
        local_state = {}
        for it in range(n_it):
            report(progress, it / n_it, f"optimizing pattern: iteration {it + 1}/{n_it}")
            if (cfg.feedback > 0 or cfg.feedback_warp > 0) and it >= 2:
                # move the targets by the achieved/target ratio: the linear solve then
                # lands on the wanted rho-hat wherever curvature allows it
                rw, rg = _achieved(M, Kc)
                goal_w, goal_g = c_weft, c_warp
                if poses is not None:
                    goal_w, goal_g = poses["ease_weft"].copy(), poses["ease_warp"].copy()
                    for Kp in poses["offsets"]:
                        # stretch of the pose along the current weft/warp: rho-hat on the reference
                        # over rho-hat on the pose
                        pw, pg = _achieved(M, Kp)
                        with np.errstate(divide="ignore", invalid="ignore"):
                            goal_w = np.fmax(goal_w, poses["margin"] * rw / pw / poses["eps_weft"])
                            goal_g = np.fmax(goal_g, poses["margin"] * rg / pg / poses["eps_warp"])
                ok = np.isfinite(rw) & np.isfinite(rg) & (rw > 0) & (rg > 0) & np.isfinite(goal_w) & np.isfinite(goal_g)
                if cfg.feedback > 0:
                    corr_w[ok] *= np.clip((goal_w[ok] / rw[ok]) ** cfg.feedback, 1 - step, 1 + step)
                if cfg.feedback_warp > 0:
                    corr_g[ok] *= np.clip((goal_g[ok] / rg[ok]) ** cfg.feedback_warp, 1 - step, 1 + step)
                np.clip(corr_w, 0.8, hi, out=corr_w)
                np.clip(corr_g, 0.8, hi, out=corr_g)
                tg = self._target_parts(K, c_weft * corr_w, c_warp * corr_g)
            RT, Te = self._local_step(M, tg, W2, state=local_state)
            energies.append(float(np.sum(self.a * sum(W2[k % 2] * (M[k] - RT[k]) ** 2 for k in range(4)))))
            # B = lambda_ease T + lambda_reg R T: one right-hand side for both terms (same weights)
            B = [cfg.lambda_ease * Te[k] + cfg.lambda_reg * RT[k] for k in range(4)]
            rhs = np.empty((self.n, 2))
            rhs[:, 0] = self._GxT @ (aw[0] * B[0]) + self._GyT @ (aw[1] * B[1])
            rhs[:, 1] = self._GxT @ (aw[0] * B[2]) + self._GyT @ (aw[1] * B[3])
            RTs = None
            if cfg.len_target != "current" or cfg.len_direction != "current":
                Dt, Kt = tg["seam"]
                _, RTs = self._local_step(M, {"T": tg["T"], "reg": (Dt, Kt)}, W2, slack=False)
                RTs = np.stack(RTs, axis=1).reshape(-1, 2, 2)
            rhs += self._seam_rhs(U, RTs, reset=(it == 0))
            rhs += self._pin * U
            U_new = lu(rhs)
            # the step's rigid part per panel carries no strain: remove it so that the flip
            # safeguard only ever pulls back the local part of the step
            U_new = self._rigid_align(U_new, U)
            U, nb, s_cur = self._safeguard(U, U_new, s_cur)
            backtracks += nb
            M = self._jac4(U)
            if cfg.realign_grain:
                U, M = self._realign(U, M)
        report(progress, 1.0, "pattern optimized")
        out_uv, tw, tgw, xyz = {}, {}, {}, {}
        fb = 0
        for pd in self.panels:
            out_uv[pd.name] = U[pd.offset:pd.offset + pd.n].copy()
            tw[pd.name] = np.asarray(c_weft[fb:fb + len(pd.faces)], float).copy()
            tgw[pd.name] = np.asarray(c_warp[fb:fb + len(pd.faces)], float).copy()
            xyz[pd.name] = pos[pd.vertex_ids]
            fb += len(pd.faces)
        return SolveResult(out_uv, tw, tgw, xyz, time.perf_counter() - t0, n_it, backtracks, energies, self.gathered)

    def _jac4(self, U: np.ndarray) -> list:
        """Jacobians of ``U`` w.r.t. the initial flattening as 4 contiguous (f,) arrays m00, m01, m10, m11.

        ``m_ij``: derivative of pattern coordinate ``i`` (u, v) along initial axis ``j`` (x, y).
        """
        u, v = np.ascontiguousarray(U[:, 0]), np.ascontiguousarray(U[:, 1])
        return [self._Gx @ u, self._Gy @ u, self._Gx @ v, self._Gy @ v]

    def _local_step(self, M: list, tg: dict, W2: np.ndarray, slack: bool = True, state: Optional[dict] = None):
        """Rest shapes ``D R K'`` of the regulariser (best 2x2 rotations, all triangles at once) and the ease target.

        ``M``: the current Jacobians (:meth:`_jac4`). With ``warp_slack`` the
        rest shape's warp row is also scaled by the best factor ``s`` within
        ``[1/(1+slack), 1+slack]`` (free warp stretch), and so is the ease
        target; ``s`` alternates with ``R`` across iterations (kept in ``state``).
        Returns (RT, T) as component lists (m00, m01, m10, m11).

        The rotation minimises ``|Omega^1/2 (M - D R K') W^1/2|^2`` (``Omega =
        diag(1, warp_row_weight)``): ``f(theta) = -2 (x cos + y sin) + p cos 2theta
        + q sin 2theta + const`` with ``x``, ``y`` the trace and skew parts of
        ``A = D Omega M W K'^T`` and ``p``, ``q`` from ``Delta = (d0^2 - omega d1^2) / 2``
        and ``C = K' W K'^T``. The polar angle of ``A`` is exact when ``Delta`` or
        the anisotropy of ``C`` vanishes; one Newton step refines it otherwise.
        """
        cfg = self.config
        D, Kr = tg["reg"]
        if "_k" not in tg:
            k = _components(Kr)
            tg["_k"] = (k, W2[0] * k[0] ** 2 + W2[1] * k[1] ** 2 - W2[0] * k[2] ** 2 - W2[1] * k[3] ** 2,
                        W2[0] * k[0] * k[2] + W2[1] * k[1] * k[3], np.ascontiguousarray(D[:, 0]),
                        np.ascontiguousarray(D[:, 1]), _components(tg["T"]))
        k, Cdiff, C01, d0, d1, T = tg["_k"]
        free = slack and cfg.warp_slack > 0
        state = {} if state is None else state
        sw = state.get("sw") if free else None
        dw = d1 if sw is None else d1 * sw
        om = cfg.warp_row_weight
        m0, m1, m2, m3 = W2[0] * M[0], W2[1] * M[1], W2[0] * M[2], W2[1] * M[3]
        x = d0 * (m0 * k[0] + m1 * k[1]) + om * dw * (m2 * k[2] + m3 * k[3])
        y = om * dw * (m2 * k[0] + m3 * k[1]) - d0 * (m0 * k[2] + m1 * k[3])
        r = np.hypot(x, y)
        ok = r > 0
        rs = np.where(ok, r, 1.0)
        c, sn = np.where(ok, x / rs, 1.0), np.where(ok, y / rs, 0.0)
        delta = 0.5 * (d0 * d0 - om * dw * dw)
        if np.any(delta != 0):
            p, q = delta * Cdiff, -2.0 * delta * C01
            c2, s2 = c * c - sn * sn, 2.0 * c * sn
            g1 = 2.0 * (x * sn - y * c) - 2.0 * p * s2 + 2.0 * q * c2
            g2 = 2.0 * r - 4.0 * p * c2 - 4.0 * q * s2
            step = np.where(g2 > 0, -g1 / np.where(g2 > 0, g2, 1.0), 0.0)
            nrm = np.sqrt(1.0 + step * step)
            c, sn = (c - sn * step) / nrm, (sn + c * step) / nrm
        rk = [c * k[0] - sn * k[2], c * k[1] - sn * k[3], sn * k[0] + c * k[2], sn * k[1] + c * k[3]]
        if free:
            lo, hi = 1.0 / (1.0 + cfg.warp_slack), 1.0 + cfg.warp_slack
            p0, p1 = d1 * rk[2], d1 * rk[3]
            sw = np.clip((m2 * p0 + m3 * p1) / np.maximum(W2[0] * p0 * p0 + W2[1] * p1 * p1, 1e-300), lo, hi)
            state["sw"] = sw
            RT = [d0 * rk[0], d0 * rk[1], d1 * sw * rk[2], d1 * sw * rk[3]]
            se = np.clip((m2 * T[2] + m3 * T[3]) / np.maximum(W2[0] * T[2] ** 2 + W2[1] * T[3] ** 2, 1e-300), lo, hi)
            return RT, [T[0], T[1], T[2] * se, T[3] * se]
        return [d0 * rk[0], d0 * rk[1], d1 * rk[2], d1 * rk[3]], T

    def _target_parts(self, K: np.ndarray, c_weft: np.ndarray, c_warp: np.ndarray) -> dict:
        """Ease target ``T`` (f, 2, 2) and the rest shapes ``D R K'`` of the regulariser and seam prediction.

        ``stretch_frame == "pattern"`` (improved): ``T = diag(c) K``, the
        scales act along the pattern's weft/warp axes after the rotation
        (``J = Q R^T diag(1/c)``: exact weft scale and no shear for any local
        rotation ``R``). ``"initial"`` (paper, literal): ``T = K diag(c)``,
        the scales act on the initial flattening's barycentric offsets, so a
        local rotation of a stretched triangle turns its stretch off the weft
        (shear and compliance error that grow with rho).
        Returns ``{"T": T, "reg": (D, K'), "seam": (D, K')}``: rest shapes ``diag(D) R K'``.
        """
        c = np.stack([c_weft, c_warp], axis=1)
        one = np.ones_like(c)
        if self.config.stretch_frame == "pattern":
            T = c[:, :, None] * K
            stretched = (c, K)
        else:
            T = K * c[:, None, :]
            stretched = (one, T)
        reg = stretched if self.config.reg_rest == "prestretch" else (one, K)
        return {"T": T, "reg": reg, "seam": stretched}

    def _seam_rhs(self, U: np.ndarray, RT: Optional[np.ndarray], reset: bool = False) -> np.ndarray:
        """Right-hand side (n, 2) of the seam terms at the current iterate ``U``.

        ``RT``: the per-triangle rest shapes ``R_t T_t`` of this iteration,
        needed only by the predicted-length variants (``len_target`` or
        ``len_direction`` ``"predicted"``).
        """
        cfg = self.config
        rhs = np.zeros((self.n, 2))
        if not self.sides:
            return rhs
        if not hasattr(self, "_len_int") or reset:
            self._len_int = np.zeros(len(self._E0))
        cur = U[self._E1] - U[self._E0]
        cur_len = np.sqrt(cur[:, 0] ** 2 + cur[:, 1] ** 2)
        if cfg.seam_length and cfg.lambda_len > 0:
            pred = None
            if cfg.len_target != "current" or cfg.len_direction != "current":
                # ARAP prediction of every seam edge: R_t T_t (u0_j - u0_i) of the edge's triangle
                e0 = self.uv0[self._E1] - self.uv0[self._E0]
                pred = np.sum(RT[self._Ef] * e0[:, None, :], axis=2)
            if cfg.len_target == "current":
                lbar = 0.5 * (cur_len + cur_len[self._Eo])
            else:
                pl = np.linalg.norm(pred, axis=1)
                lbar = 0.5 * (pl + pl[self._Eo])
            if cfg.len_integral > 0:
                # integral action: what the proximal pull leaves of the mismatch is
                # accumulated into this side's target until both sides agree
                self._len_int -= cfg.len_integral * 0.5 * (cur_len - cur_len[self._Eo])
                # bounded: where the design itself makes the sides differ (weft ease on a
                # sleeve cap sewn to a warp-wise armhole) the seam gives way, not the cloth
                cap = cfg.len_integral_cap * lbar
                np.clip(self._len_int, -cap, cap, out=self._len_int)
                lbar = lbar + self._len_int
            if cfg.len_direction == "current":
                dirn = cur / np.maximum(cur_len, 1e-300)[:, None]
            else:
                dirn = pred / np.maximum(np.linalg.norm(pred, axis=1), 1e-300)[:, None]
            c = cfg.lambda_len * self._El0 / (self.h * self.total_area) * self._sewn_edges()[0]
            tgt = (c * lbar)[:, None] * dirn
            n = self.n
            for d in range(2):
                rhs[:, d] += np.bincount(self._E1, tgt[:, d], minlength=n) - np.bincount(self._E0, tgt[:, d], minlength=n)
        if self._Dall is None:
            return rhs
        d2 = self._Dall @ U
        acc = np.zeros_like(d2)
        if cfg.lambda_straight > 0 and cfg.straight_target == "smooth":
            # damp oscillations only: towards the neighbours' mean second difference
            sm = d2.copy()
            i = np.flatnonzero(self._Rsmooth)
            sm[i] = 0.5 * (d2[i - 1] + d2[i + 1])
            acc += (cfg.lambda_straight * self._Rcc * self._Rstraight)[:, None] * sm
        if cfg.lambda_curve > 0:
            # towards the mean of both sides' second differences, the other side's turned by the
            # best rigid fit of the two polylines (per side, vectorised Kabsch)
            k = len(self.sides)
            P = U[self._Vg]
            Q = P[self._Vo]
            cnt = self._Vcount
            Pm = np.stack([np.bincount(self._Vside, P[:, d], minlength=k) for d in range(2)], axis=1) / cnt[:, None]
            Qm = np.stack([np.bincount(self._Vside, Q[:, d], minlength=k) for d in range(2)], axis=1) / cnt[:, None]
            Pc, Qc = P - Pm[self._Vside], Q - Qm[self._Vside]
            # H = Qc^T Pc per side; rotation = polar(H^T)
            h = {(i, j): np.bincount(self._Vside, Qc[:, i] * Pc[:, j], minlength=k) for i in range(2) for j in range(2)}
            th = np.arctan2(h[(0, 1)] - h[(1, 0)], h[(0, 0)] + h[(1, 1)])
            c_, s_ = np.cos(th)[self._Rside], np.sin(th)[self._Rside]
            do = d2[self._Ro]
            rot = np.stack([c_ * do[:, 0] - s_ * do[:, 1], s_ * do[:, 0] + c_ * do[:, 1]], axis=1)
            acc += (cfg.lambda_curve * self._Rcc * self._sewn_edges()[1])[:, None] * (0.5 * (d2 + rot))
        rhs += self._DallT @ acc
        return rhs

    def _rigid_align(self, U_new: np.ndarray, U_old: np.ndarray) -> np.ndarray:
        """``U_new`` moved rigidly per panel onto ``U_old`` (area-free Kabsch, all panels at once)."""
        off, cnt = self._voff, self._vcount[:, None]
        co, cn = np.add.reduceat(U_old, off) / cnt, np.add.reduceat(U_new, off) / cnt
        rep = self._vrep
        Pc, Qc = U_old - rep(co), U_new - rep(cn)
        h = np.add.reduceat(Qc[:, [0, 0, 1, 1]] * Pc[:, [0, 1, 0, 1]], off)   # H = Qc^T Pc per panel
        th = np.arctan2(h[:, 1] - h[:, 2], h[:, 0] + h[:, 3])
        return _turn(Qc, rep(np.cos(th)), rep(np.sin(th))) + rep(co)

    def _areas(self, U: np.ndarray, faces: Optional[np.ndarray] = None) -> np.ndarray:
        """Signed 2D areas of all triangles (or of ``faces``), as :func:`signed_areas_2d`, on cached columns."""
        F0, F1, F2 = self._Fcols if faces is None else (c[faces] for c in self._Fcols)
        u, v = U[:, 0], U[:, 1]
        u0, v0 = u[F0], v[F0]
        ax, ay = u[F1] - u0, v[F1] - v0
        bx, by = u[F2] - u0, v[F2] - v0
        return 0.5 * (ax * by - ay * bx)

    def _safeguard(self, U_old: np.ndarray, U_new: np.ndarray, s_old: Optional[np.ndarray] = None):
        """Keep the step flip-free: vertices of triangles that would flip step back locally.

        Every vertex starts with the full step; the step of the vertices of
        each triangle that would flip (or lose more than half its area when
        already near-degenerate) is halved, and only the triangles around the
        moved vertices are checked again. As a vertex's step goes to 0 it
        returns to the previous, flip-free iterate, so this terminates; a
        panel not fixed in 40 rounds takes a uniformly shortened step instead
        (or keeps its previous iterate).
        ``s_old``: the signed areas of ``U_old`` when known (they survive
        rigid motions, so each iteration passes on its own).
        Returns (U, number of halvings, signed areas of U).
        """
        F = self.gfaces
        if s_old is None:
            s_old = self._areas(U_old)
        floor = np.minimum(self._area_floor, 0.5 * s_old)
        alpha = np.ones(self.n)
        U = U_new.copy()
        halvings = 0
        faces = None
        D = U_new - U_old
        for _ in range(40):
            if faces is None:
                s_all = self._areas(U)
                bad = np.flatnonzero(s_all <= floor)
                if bad.size == 0:
                    return U, halvings, s_all
            else:
                s = self._areas(U, faces)
                bad = faces[s <= floor[faces]]
                if bad.size == 0:
                    return U, halvings, None
            # largest common step fraction t of the bad triangle's vertices (their current
            # fractions scaled by t) keeping its area above the floor: a quadratic in t
            Fb = F[bad]
            P0 = U_old[Fb]
            Dd = alpha[Fb][:, :, None] * D[Fb]
            e1, e2 = P0[:, 1] - P0[:, 0], P0[:, 2] - P0[:, 0]
            f1, f2 = Dd[:, 1] - Dd[:, 0], Dd[:, 2] - Dd[:, 0]
            cr = lambda a, b: a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
            a0 = 0.5 * cr(e1, e2) - floor[bad]
            a1 = 0.5 * (cr(e1, f2) + cr(f1, e2))
            a2 = 0.5 * cr(f1, f2)
            t = np.full(len(bad), 0.5)
            ts = np.linspace(0.0, 1.0, 33)[1:]
            # first sample where the area would reach the floor; step back one sample (robust, vectorised)
            vals = a0[:, None] + a1[:, None] * ts[None, :] + a2[:, None] * ts[None, :] ** 2
            hit = np.argmax(vals <= 0, axis=1)
            has = np.any(vals <= 0, axis=1)
            t[has] = np.where(hit[has] > 0, ts[np.maximum(hit[has] - 1, 0)], 0.0) * 0.9
            verts_t = np.repeat(t, 3)
            vids = Fb.ravel()
            scale = np.ones(self.n)
            np.minimum.at(scale, vids, np.maximum(verts_t, 0.0))
            verts = np.unique(vids)
            # never stall: every vertex of a bad triangle at least halves its step
            alpha[verts] *= np.minimum(scale[verts], 0.5)
            halvings += 1
            U[verts] = U_old[verts] + alpha[verts, None] * D[verts]
            faces = np.unique(self._vf[verts].indices)
        s = signed_areas_2d(U, F)
        for pd in self.panels:
            sl = slice(pd.offset, pd.offset + pd.n)
            fs = slice(pd.face_offset, pd.face_offset + len(pd.faces))
            if not np.any(s[fs] <= floor[fs]):
                continue
            # fall back to a uniform step of the whole panel towards the locally shortened one
            beta, Ul = 0.5, U[sl].copy()
            U[sl] = U_old[sl]
            for _ in range(30):
                cand = U_old[sl] + beta * (Ul - U_old[sl])
                halvings += 1
                if np.all(signed_areas_2d(cand, pd.faces) > floor[fs]):
                    U[sl] = cand
                    break
                beta *= 0.5
        return U, halvings, None

    def _scaled_start(self, c_weft: np.ndarray, c_warp: np.ndarray) -> np.ndarray:
        """The initial flattening stretched by each panel's area-weighted mean targets.

        A flip-free affine image of a flip-free flattening, already close to a
        uniform-ease solution: the first global steps stay small, so the flip
        safeguard rarely has to act even at rho = 2.
        """
        U = self.uv0.copy()
        for pd in self.panels:
            fs = slice(pd.face_offset, pd.face_offset + len(pd.faces))
            w = np.abs(pd.area0)
            sx = float(np.sum(w * c_weft[fs]) / np.sum(w))
            sy = float(np.sum(w * c_warp[fs]) / np.sum(w))
            sl = slice(pd.offset, pd.offset + pd.n)
            c = U[sl].mean(axis=0)
            U[sl] = (U[sl] - c) * np.array([sx, sy]) + c
        return U

    def _realign(self, U: np.ndarray, M: list):
        """Rotate every panel about its centroid so its area-weighted grain vote is +y.

        ``M``: the Jacobians of ``U`` (:meth:`_jac4`); returns the rotated
        ``U`` and its Jacobians (the same rotation applied to the rows).
        """
        wx, wy = self._warp0[:, 0], self._warp0[:, 1]
        ix, iy = M[0] * wx + M[1] * wy, M[2] * wx + M[3] * wy  # current 2D image of the warp
        nrm = np.hypot(ix, iy)
        w = np.where(nrm > 0, self._warp_w, 0.0) / np.maximum(nrm, 1e-300)
        vx = np.add.reduceat(w * ix, self._foff)
        vy = np.add.reduceat(w * iy, self._foff)
        theta = -np.where((vx == 0) & (vy == 0), 0.0, np.arctan2(-vx, vy))
        c, sn = np.cos(theta), np.sin(theta)
        rep = self._vrep
        ctr = rep(np.add.reduceat(U, self._voff) / self._vcount[:, None])
        U = _turn(U - ctr, rep(c), rep(sn)) + ctr
        ct, st = np.repeat(c, self._fcount), np.repeat(sn, self._fcount)
        M = [ct * M[0] - st * M[2], ct * M[1] - st * M[3], st * M[0] + ct * M[2], st * M[1] + ct * M[3]]
        return U, M


# ----------------------------------------------------------------------------- patterns

def _layout(uv: Dict[str, np.ndarray], order: Sequence[str], gap: float = 0.05) -> Dict[str, np.ndarray]:
    """Translate the pieces into one row (left to right, bottoms aligned), gap in metres."""
    out, x = {}, 0.0
    for name in order:
        p = uv[name]
        lo, hi = p.min(axis=0), p.max(axis=0)
        out[name] = p - lo + np.array([x, 0.0])
        x += (hi - lo)[0] + gap
    return out


def build_pattern(cut, result: SolveResult, style: str = "", body: Optional[dict] = None,
                  mode: str = "reference", materials: Optional[dict] = None) -> Pattern:
    """Assemble a :class:`Pattern` from a solve; checks it has no flipped triangle."""
    order = [p.name for p in cut.panels]
    uv = _layout(result.uv, order)
    panels = []
    for p in cut.panels:
        xyz = result.xyz[p.name]
        grain = np.array([0.0, 1.0])
        rw, rg, _ = scales(uv[p.name], xyz, p.faces, grain)
        s = signed_areas_2d(uv[p.name], p.faces)
        if np.any(s <= 0):
            raise PatternError(f"panel {p.name!r}: {int(np.sum(s <= 0))} flipped triangles in the optimized pattern")
        panels.append(PatternPanel(
            name=p.name, garment=p.garment, uv=uv[p.name], faces=np.asarray(p.faces, int),
            vertex_ids=np.asarray(p.vertex_ids, int), xyz=np.asarray(xyz, float), grain=grain,
            target_weft=result.target_weft[p.name], target_warp=result.target_warp[p.name],
            achieved_weft=rw, achieved_warp=rg,
            boundary=[np.asarray(b, int) for b in (p.boundary or _init.boundary_loops(p.faces))],
            hems=[np.asarray(h, int) for h in cut.hems.get(p.name, [])], mirror_of=p.mirror_of))
    seams = [PatternSeam(s.name, s.panel_a, s.panel_b, np.asarray(s.verts_a, int), np.asarray(s.verts_b, int),
                         gathered=s.name in result.gathered)
             for s in cut.seams]
    body = dict(body if body is not None else cut.body)
    return Pattern(style=style, body=body, garments=dict(cut.garments), panels=panels, seams=seams,
                   pins={g: np.asarray(v, int) for g, v in cut.pins.items()},
                   materials=dict(materials if materials is not None else cut.materials), mode=mode,
                   report={"optimize_seconds": result.seconds, "iterations": result.iterations,
                           "backtracks": result.backtracks, "gathered_seams": list(result.gathered)})


def solve_pattern(cut, body_vertices, config: Optional[SolverConfig] = None, style: str = "",
                  progress: Optional[Progress] = None, solver: Optional[PatternSolver] = None) -> Pattern:
    """Reference pattern (paper Eq. ref-scale) of ``cut`` on the body instance it was cut on."""
    from ..progress import sub
    solver = solver or PatternSolver(cut, body_vertices, config, progress=sub(progress, 0.0, 0.3))
    K, cw, cg = solver.targets_reference()
    res = solver.solve(K, cw, cg, progress=sub(progress, 0.3, 1.0))
    pat = build_pattern(cut, res, style=style, mode="reference")
    pat.report["init_seconds"] = solver.timings.get("init", 0.0)
    return pat


def transfer_pattern(cut, ref_vertices, target_vertices, config: Optional[SolverConfig] = None,
                     style: str = "", body: Optional[dict] = None, progress: Optional[Progress] = None,
                     solver: Optional[PatternSolver] = None, start: Optional[Pattern] = None) -> Pattern:
    """Shape transfer (paper Eq. transfer-scale): the ease field kept on the target body.

    The reference flattening and factorisation are reused; the solve starts
    from the reference pattern when ``start`` is given.
    """
    from ..progress import sub
    solver = solver or PatternSolver(cut, ref_vertices, config, progress=sub(progress, 0.0, 0.3))
    tgt = solver._positions(target_vertices, "target body")
    K, cw, cg = solver.targets_reference(tgt)
    U0 = _start_from(solver, start)
    res = solver.solve(K, cw, cg, start=U0, positions=tgt, progress=sub(progress, 0.3, 1.0))
    return build_pattern(cut, res, style=style, body=body, mode="transfer")


def adapt_pattern(cut, ref_vertices, pose_vertices: Sequence[np.ndarray], eps_weft: float = 1.1,
                  eps_warp: Optional[float] = None, config: Optional[SolverConfig] = None, style: str = "",
                  body: Optional[dict] = None, progress: Optional[Progress] = None,
                  solver: Optional[PatternSolver] = None, start: Optional[Pattern] = None) -> Pattern:
    """Pose adaptation (paper Eqs. adapt-scale, material-scale) for one or more target poses.

    The pattern is solved for the reference body with targets raised to what
    every pose demands, divided by the stretch tolerances ``eps_weft`` and
    ``eps_warp`` (default: ``eps_weft``), each >= 1.
    """
    from ..progress import sub
    eps_weft = _check_eps("eps_weft", eps_weft)
    eps_warp = _check_eps("eps_warp", eps_weft if eps_warp is None else eps_warp)
    if not len(pose_vertices):
        raise PatternError("adaptation needs at least one target pose")
    solver = solver or PatternSolver(cut, ref_vertices, config, progress=sub(progress, 0.0, 0.3))
    poses = [solver._positions(P, f"pose {i + 1}") for i, P in enumerate(pose_vertices)]
    K, cw, cg = solver.targets_adapt(poses, eps_weft, eps_warp)
    cfg = solver.config
    if cfg.adapt_feedback > 0:
        # feedback only moves right-hand sides: the factorisation is kept
        solver.config = replace(cfg, feedback=max(cfg.feedback, cfg.adapt_feedback),
                                feedback_warp=max(cfg.feedback_warp, cfg.adapt_feedback))
    try:
        res = solver.solve(K, cw, cg, start=_start_from(solver, start), progress=sub(progress, 0.3, 1.0),
                           poses=solver.pose_demands(poses, eps_weft, eps_warp) if cfg.adapt_feedback > 0 else None)
    finally:
        solver.config = cfg
    mats = dict(cut.materials)
    mats.update({"eps_weft": eps_weft, "eps_warp": eps_warp})
    return build_pattern(cut, res, style=style, body=body, mode="adapt", materials=mats)


def _start_from(solver: PatternSolver, start: Optional[Pattern]) -> Optional[np.ndarray]:
    if start is None:
        return None
    U = np.concatenate([start.panel(pd.name).uv for pd in solver.panels])
    # the start is flip-free (every reported pattern is); re-centre each piece on its initial position
    out = U.copy()
    for pd in solver.panels:
        sl = slice(pd.offset, pd.offset + pd.n)
        out[sl] = U[sl] - U[sl].mean(axis=0) + solver.uv0[sl].mean(axis=0)
    return out
