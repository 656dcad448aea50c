"""The fabric's own stretch limit: pd's strain limit (DrapeOptions.strain_limit) and the report's share past it."""

import numpy as np
import pytest

from core.drape import drape
from core.drape import textile as T
from core.drape.materials import get_material
from core.drape.mesh import build_cloth
from core.drape.output import report_dict
from core.drape.pd import ProjectiveStep
from core.drape.result import stretch_limit_report

#: a cotton sheet made soft in its grain: hanging 20 cm from its top edge it stretches 12.8 % at the clamp
#: (rho g H / k), far past cotton's 5 % max_stretch
SOFT = {"fabric": "cotton", "stretch_weft": 2.0, "stretch_warp": 2.0}


def _hanging(width=0.1, height=0.2, edge=0.02):
    """A sheet hanging from its pinned top edge, warp vertical (as :func:`core.drape.textile.hanging_sheet`),
    and a body out of its reach."""
    uv, faces = T.strip_mesh([-height, 0.0], width, edge)
    uv = np.column_stack([uv[:, 1], uv[:, 0]])
    faces = faces[:, [0, 2, 1]]
    pattern = T.sheet_pattern(uv, faces, 0.0, uv[:, 1] >= -1e-9, "cotton")
    pattern.panels[0].xyz = np.column_stack([uv[:, 0], np.zeros(len(uv)), uv[:, 1]])
    return pattern, T.box_body((-0.05, 0.5, -0.05), (0.05, 0.6, 0.05))


def _drape(material, limit, frames=40):
    pattern, (bv, bf) = _hanging()
    opts = {"solver": "pd", "substeps": 3, "tether_slack": None, "grow_frames": 0, "max_frames": frames}
    if limit is not None:
        opts["strain_limit"] = limit
    return drape(pattern, bv, bf, material=material, options=opts)


@pytest.fixture(scope="module")
def soft():
    return {limit: _drape(SOFT, limit) for limit in (0.0, 100.0)}


def test_strain_limit_holds_the_fabric_at_its_max_stretch(soft):
    # without the limit the soft sheet hangs 12 % stretched at its clamp; with it no grain ends much past
    # cotton's 5 %
    free, held = soft[0.0], soft[100.0]
    assert free.settled and held.settled
    limit = get_material("cotton").max_stretch
    assert free.face_strain_warp.max() > 2.0 * limit
    assert held.face_strain_warp.max() < limit + 0.005
    assert held.face_strain_weft.max() < limit + 0.005
    # the limit shortens only what is past it: the sheet's lower half, under the limit, still stretches
    assert np.median(held.face_strain_warp) > 0.02


def test_a_drape_within_the_limit_is_unchanged():
    # hanging cotton stretches 0.02 %: the limit's set stays empty and the drape is the same bits
    on, off = _drape("cotton", 100.0), _drape("cotton", 0.0)
    assert on.face_strain_warp.max() < 0.01
    assert np.array_equal(on.positions, off.positions)


def test_limit_gradient_is_the_energy_slope():
    # a sheet stretched 12 % along the warp: after a solve the limit's set holds its grains, and the
    # gradient (the kernel's plus the limit's) is the slope of the energy (with the penalty past the limit)
    uv, faces = T.strip_mesh([0.0, 0.04], 0.03, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < 1e-9, "cotton"))
    mat = get_material("cotton")
    mass = mat.density * cloth.mass_area
    pd = ProjectiveStep(cloth, mat, 1 / 60, mass, np.ones((len(cloth.faces), 2)), np.zeros(0), strain_limit=100.0)
    x = cloth.x0.copy()
    x[:, 1] *= 1.12
    y = x.copy()
    for _ in range(2):  # the first solve marks the grains past the limit, the next one limits them
        pd.solve(x.copy(), y, 1.0, 1, 1e-3, mass * 9.81)
    assert pd.limited > 0
    # the set's weights are in the factored matrix: M + sum w A^T A + the set's w_limit A^T A (free particles)
    rows, w, _ = pd._limit
    fi = pd.free_idx
    want = (pd.matrix + pd.D[rows].T @ pd.D[rows].multiply(w[:, None]))[fi][:, fi].toarray()
    assert np.allclose(pd._free_matrix.toarray(), want, rtol=1e-12, atol=1e-9 * np.abs(want).max())
    v = np.random.default_rng(5).normal(size=(len(fi), 3))
    assert np.allclose(want @ pd._back(v), v, atol=1e-8 * np.abs(v).max())  # and refactored
    rng = np.random.default_rng(3)
    x = x + rng.normal(scale=1e-5, size=x.shape)
    grad, _ = pd.local(x, y, 1.0)
    d = rng.normal(size=x.shape)
    d[~pd.free] = 0.0
    h = 1e-7
    slope = (pd.energy(x + h * d, y, 1.0) - pd.energy(x - h * d, y, 1.0)) / (2 * h)
    assert slope == pytest.approx(float(np.sum(grad * d)), rel=1e-4)
    # the limit's part is there: without it the same step's energy is lower
    off = ProjectiveStep(cloth, mat, 1 / 60, mass, np.ones((len(cloth.faces), 2)), np.zeros(0), strain_limit=0.0)
    assert off.energy(x, y, 1.0) < pd.energy(x, y, 1.0)


def test_report_gives_the_share_past_the_limit(soft):
    # per garment and per piece: the share of the fabric's area stretched past max_stretch along each grain,
    # and the largest stretch; in the drape report too
    r = soft[0.0]
    rep = r.stretch_limit
    assert rep["max_stretch_pct"] == pytest.approx(5.0)
    cloth = build_cloth(_hanging()[0])
    over = r.face_strain_warp > 0.05
    expect = 100.0 * cloth.rest_area[over].sum() / cloth.rest_area.sum()
    assert 0.0 < rep["all"]["warp_over_pct"] == pytest.approx(expect)
    assert rep["all"]["weft_over_pct"] == 0.0
    assert rep["all"]["warp_max_pct"] == pytest.approx(100.0 * r.face_strain_warp.max())
    garment = rep["garments"]["specimen"]
    assert garment["warp_over_pct"] == pytest.approx(expect)
    assert garment["pieces"]["specimen"]["warp_over_pct"] == pytest.approx(expect)
    assert report_dict(r, {"all": {"gap_mm": {}, "penetration_pct": 0.0, "seam_gap_mm": {}}})["stretch_limit"] == rep
    # held at the limit: little of the fabric is past it, and by little
    held = soft[100.0].stretch_limit["all"]
    assert held["warp_max_pct"] < 5.5


def test_report_per_piece():
    # two pieces of one garment: each piece's own share, the garment's the area-weighted whole
    uv, faces = T.strip_mesh([0.0, 0.04], 0.03, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < -1.0, "cotton"))
    t = len(cloth.faces)
    cloth.face_panel = (np.arange(t) >= t // 2).astype(int)
    cloth.panel_names = ["left", "right"]
    weft = np.where(np.arange(t) < t // 2, 0.08, 0.0)
    warp = np.full(t, 0.01)
    rep = stretch_limit_report(cloth, weft, warp, np.ones(t, bool), 0.05)
    pieces = rep["garments"]["specimen"]["pieces"]
    assert pieces["left"]["weft_over_pct"] == pytest.approx(100.0)
    assert pieces["right"]["weft_over_pct"] == 0.0
    area = cloth.rest_area
    assert rep["all"]["weft_over_pct"] == pytest.approx(100.0 * area[: t // 2].sum() / area.sum())
    assert rep["all"]["weft_max_pct"] == pytest.approx(8.0) and rep["all"]["warp_over_pct"] == 0.0
