"""Projective dynamics' sub-element buckling (core.drape.pd, issue 35; off by default, ``BUCKLING``):
NewtonStep's capped grain springs as a projection, and the Cusick drape it gives."""

import numpy as np
import pytest

from core.drape import textile as T
from core.drape.materials import TARGETS, get_material
from core.drape.mesh import build_cloth
from core.drape.newton import NewtonStep
from core.drape.pd import ProjectiveStep


def _steps(buckling):
    uv, faces = T.strip_mesh([0.0, 0.04], 0.03, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < -1.0, "cotton"))
    mat = get_material("cotton")
    args = (cloth, mat, 1 / 60, mat.density * cloth.mass_area, np.ones((len(cloth.faces), 2)), np.zeros(0))
    return cloth, ProjectiveStep(*args, buckling=buckling), NewtonStep(*args)


def test_buckled_grain_springs_are_newtons():
    # a flat sheet, weft compressed 2 % (40x cotton's buckling strain at 1 cm, 0.043 %), warp stretched 0.5 %:
    # no shear, no bend, so the energy is the grain springs' alone, and pd's is NewtonStep's exactly, the
    # compressed springs' force held at the element's Euler load
    cloth, pd, nt = _steps(True)
    assert pd.buckling and 0.0 < nt.cap_a.max() < 0.02
    x = cloth.x0.copy()
    x[:, 0] *= 0.98
    x[:, 1] *= 1.005
    elastic, energy = pd.local(x, x, 1.0)
    e_nt, g_nt = nt.energy(x, x, 1.0)
    assert energy == pytest.approx(e_nt, rel=1e-9)
    assert np.allclose(elastic, g_nt, rtol=1e-7, atol=1e-9 * np.abs(g_nt).max())
    # without the cap pd holds the compressed weft at its full stiffness: far more energy and force
    _, soft, _ = _steps(False)
    elastic_stiff, energy_stiff = soft.local(x, x, 1.0)
    assert energy_stiff > 5.0 * energy
    assert np.abs(elastic_stiff[:, 0]).max() > 5.0 * np.abs(elastic[:, 0]).max()  # along the weft


def test_buckled_projection_lowers_the_step():
    # the capped spring is min over t <= rest of w / 2 (l - t)^2 + w c (rest - t): the local step's target
    # minimises it, so each local-global iteration still lowers G and the solve reaches the implicit step
    cloth, pd, _ = _steps(True)
    rng = np.random.default_rng(3)
    y = cloth.x0 * np.array([0.97, 1.0, 1.0]) + rng.normal(scale=3e-4, size=cloth.x0.shape)
    x = y.copy()
    energies = []
    for _ in range(6):
        energies.append(pd.energy(x, y, 1.0))
        pd.solve(x, y, 1.0, 1, 0.0, np.ones(cloth.n_particles))
    assert np.all(np.diff(energies) <= 1e-12 * abs(energies[0]))
    assert energies[-1] < energies[0]


def test_pd_silk_drapes_in_its_range_with_the_cap(monkeypatch):
    # silk (1.5e-6 N m, calibrated with NewtonStep's cap) on the plain 10 mm disc: with the cap 31.2 % with 8
    # nodes (33.1 % with Anderson's iterations); without it (pd's default, BUCKLING off) pd's hoops locked and
    # read 44.8 % there (Anderson), above silk's 20-40 %
    import core.drape.pd as P

    monkeypatch.setattr(P, "BUCKLING", True)
    r = T.cusick("silk", edge=0.01, options={"solver": "pd"}, band=False)  # the plain disc those figures read
    assert r["settled"]
    assert 20.0 <= r["dc_pct"] <= 40.0
    assert 5 <= r["nodes"] <= 10


def test_cusick_specimens_average_their_seeds():
    # the figure of k specimens is the mean of the seeds' runs (each its own mesh turn, so its own folds)
    opts = {"solver": "pd"}
    r = T.cusick_specimens("cotton", edge=0.03, options=opts, max_frames=3, specimens=2, band=False)
    one = [T.cusick("cotton", edge=0.03, options=opts, max_frames=3, seed=s, band=False) for s in (0, 1)]
    assert r["specimens"] == 2 and [x["seed"] for x in r["runs"]] == [0, 1]
    assert [x["dc_pct"] for x in r["runs"]] == [x["dc_pct"] for x in one]
    assert r["dc_pct"] == pytest.approx(np.mean([x["dc_pct"] for x in one]), rel=1e-12)
    assert r["dc_min"] <= r["dc_pct"] <= r["dc_max"] and not r["settled"]
    with pytest.raises(ValueError, match="specimens"):
        T.cusick_specimens("cotton", edge=0.03, specimens=0)


@pytest.mark.slow
@pytest.mark.parametrize("fabric", ["cotton", "wool"])
def test_pd_cusick_converges_in_the_mesh_and_the_iterations(fabric):
    # issue 35's reading: the mean of 4 specimens moves by at most 3 points from the 10 mm disc (with its
    # clamp band) to the 5 mm one and from the default iterations to 4x them, inside the fabric's range with
    # 5-10 nodes. The released disc takes 8x the iterations in its first 5 frames (DrapeOptions.onset_frames,
    # where its fold count is picked): without them wool read 55.0 % with 4 nodes and moved +7.4 points at
    # 4x (8 specimens, fabric.md of session 6). Minutes a fabric: --full only
    lo, hi = TARGETS[fabric]["dc_pct"]
    base = {"solver": "pd"}
    ten = T.cusick_specimens(fabric, edge=0.01, options=base)
    five = T.cusick_specimens(fabric, edge=0.005, options=base)
    more = T.cusick_specimens(fabric, edge=0.01, options={**base, "iterations": 4 * 10})
    for r in (ten, five, more):
        assert r["settled"] and lo <= r["dc_pct"] <= hi and 5 <= r["nodes"] <= 10, (r["dc_pct"], r["nodes"])
    assert abs(five["dc_pct"] - ten["dc_pct"]) <= 3.0
    assert abs(more["dc_pct"] - ten["dc_pct"]) <= 3.0
