"""Body contact that follows the surface, and the textile tests (core.drape.textile, SPEC item 11)."""

import numpy as np
import pytest

from core.drape import DrapeSolver
from core.drape import textile as T
from core.drape.materials import get_material
from core.drape.mesh import build_cloth


def _ledge_drape(edge=0.01, frames=60):
    """A cotton strip clamped on a box whose top ends in a 90 degree edge at x = 0; 6 cm hang past it."""
    uv, faces = T.strip_mesh([-0.03, 0.0, 0.06], 0.03, edge)
    pattern = T.sheet_pattern(uv, faces, 0.00303, uv[:, 0] <= -0.02, "cotton")
    cloth = build_cloth(pattern)
    body = T.box_body((-0.2, -0.1, -0.1), (0.0, 0.1, 0.0))
    solver = DrapeSolver(cloth, *body, "cotton", {"max_frames": frames})
    state = solver.state()
    for _ in range(frames):
        solver.step(state)
    return uv, cloth, state.x.numpy().astype(float)


def test_cloth_falls_off_a_convex_edge():
    # contact against the extended plane of the nearest triangle held the strip flat on an invisible
    # shelf up to the 3 cm search distance past the edge; the closest point on the mesh lets it fall
    uv, cloth, x = _ledge_drape()
    past = cloth.particle_of[np.nonzero(uv[:, 0] >= 0.02 - 1e-9)[0]]
    # 2 cm and more past the edge, within the old shelf's reach: well below the top face
    assert x[past, 2].max() < -0.005
    tip = cloth.particle_of[np.nonzero(uv[:, 0] >= 0.06 - 1e-9)[0]]
    assert x[tip, 2].mean() < -0.03
    # and nothing went through the box: above its top or outside its side face
    assert np.all((x[:, 2] > -1e-3) | (x[:, 0] > -1e-3))


def test_contact_plane_turns_round_the_edge():
    # a particle beside and above the edge: its plane is through the edge, facing it (45 degrees)
    from core.drape import kernels as K
    from core.geom.queries import warp_mesh

    wp = K.wp
    v, f = T.box_body((-0.2, -0.1, -0.1), (0.0, 0.1, 0.0))
    mesh = warp_mesh(v, f, device="cpu")
    pts = np.array([[0.01, 0.0, 0.01], [-0.05, 0.0, 0.002], [0.004, 0.0, -0.05]])
    n = len(pts)
    point, normal, hit = (
        wp.zeros(n, dtype=wp.vec3, device="cpu"),
        wp.zeros(n, dtype=wp.vec3, device="cpu"),
        wp.zeros(n, dtype=int, device="cpu"),
    )
    wp.launch(
        K.closest_contact,
        n,
        inputs=[
            wp.array(pts, dtype=wp.vec3, device="cpu"),
            wp.ones(n, dtype=float, device="cpu"),
            mesh.id,
            0.03,
            1e-4,
            point,
            normal,
            hit,
        ],
        device="cpu",
    )
    nrm, pt = normal.numpy(), point.numpy()
    assert hit.numpy().tolist() == [1, 1, 1]
    assert np.allclose(pt[0], [0.0, 0.0, 0.0], atol=1e-6)
    assert np.allclose(nrm[0], [np.sqrt(0.5), 0.0, np.sqrt(0.5)], atol=1e-5)
    assert np.allclose(nrm[1], [0.0, 0.0, 1.0], atol=1e-5)  # over the top face: its normal
    assert np.allclose(nrm[2], [1.0, 0.0, 0.0], atol=1e-5)  # beside the side face: its normal


def test_shadow_area_and_nodes():
    uv, faces = T.disc_mesh(0.15, 0.01, 0.09, seed=1)
    # the rasterised disc (1 mm cells) is the disc's area within the polygon's chord error
    assert T.shadow_area(uv, faces) == pytest.approx(np.pi * 0.15**2, rel=0.01)
    # a rim with 7 bumps of 1 cm: 7 nodes; a circle: none
    th = np.linspace(-np.pi, np.pi, 400, endpoint=False)
    r = 0.12 + 0.01 * np.cos(7 * th + 0.3)
    assert T.count_nodes(np.column_stack([r * np.cos(th), r * np.sin(th)]))[0] == 7
    assert T.count_nodes(0.12 * np.column_stack([np.cos(th), np.sin(th)]))[0] == 0


def test_disc_mesh_has_the_clamp_ring():
    uv, faces = T.disc_mesh(0.15, 0.01, 0.09)
    r = np.hypot(uv[:, 0], uv[:, 1])
    assert np.sum(np.isclose(r, 0.09)) >= 50 and np.isclose(r.max(), 0.15)
    e = uv[faces[:, [1, 2, 0]]] - uv[faces]
    lengths = np.linalg.norm(e, axis=2)
    assert 0.007 < np.median(lengths) < 0.013


def test_disc_mesh_resolves_the_clamp_band():
    # the clamp's boundary layer (cotton: sqrt(B / T) = 9.9 mm, T the hanging annulus's weight per length of
    # the clamp's edge) is meshed at half its width out to twice it, at any edge; past it the edge's rings
    mat = get_material("cotton")
    tension = mat.density * 9.81 * np.pi * (0.15**2 - 0.09**2) / (2 * np.pi * 0.09)
    assert T.clamp_layer(mat) == pytest.approx(np.sqrt(mat.bending / tension), rel=1e-12)
    assert 0.009 < T.clamp_layer(mat) < 0.011
    width, step = T.clamp_band(mat)
    assert width == pytest.approx(2 * T.clamp_layer(mat)) and step == pytest.approx(0.5 * T.clamp_layer(mat))
    uv, faces = T.disc_mesh(0.15, 0.01, 0.09, 0, width, step)
    r = np.hypot(uv[:, 0], uv[:, 1])
    rings = np.unique(np.round(r, 9))
    band = rings[(rings > 0.09) & (rings <= 0.09 + width + 1e-9)]
    assert np.all(np.diff(np.concatenate([[0.09], band])) <= step + 1e-9) and len(band) >= 4
    outside = rings[rings > 0.09 + width + 1e-9]
    assert np.all(np.diff(outside) > step) and np.isclose(r.max(), 0.15)
    assert np.sum(np.isclose(r, 0.09)) >= 50  # the clamp ring kept
    # the band's triangles are about its spacing; without a band the disc is the plain one
    mid = uv[faces].mean(axis=1)
    in_band = (np.hypot(mid[:, 0], mid[:, 1]) > 0.091) & (np.hypot(mid[:, 0], mid[:, 1]) < 0.09 + width - 0.002)
    lengths = np.linalg.norm(uv[faces[:, [1, 2, 0]]] - uv[faces], axis=2)
    assert np.median(lengths[in_band]) < 1.3 * step
    plain = T.disc_mesh(0.15, 0.01, 0.09, 0)
    assert all(np.array_equal(a, b) for a, b in zip(plain, T.disc_mesh(0.15, 0.01, 0.09, 0, 0.0, None)))


@pytest.fixture(scope="module")
def cusick_cotton():
    return T.cusick("cotton", edge=0.01, max_frames=300)


def test_cusick_settles_by_energy_and_displacement(cusick_cotton):
    r = cusick_cotton
    assert r["settled"]
    assert r["energy"] < T.SETTLE_ENERGY and r["move_mm"] < T.SETTLE_MOVE * 1e3
    # the clamp holds the centre; the annulus hangs: the shadow lies between the support and the flat disc
    assert 0.0 < r["dc_pct"] < 100.0
    x = r["positions"]
    assert x[:, 2].min() < -0.02
    assert r["nodes"] >= 3


def test_settle_stops_only_when_still():
    # a drape cut off early is not settled, and says so
    r = T.cusick("cotton", edge=0.015, max_frames=5)
    assert not r["settled"] and r["frames"] == 5
    assert r["energy"] > T.SETTLE_ENERGY or r["move_mm"] > T.SETTLE_MOVE * 1e3


def test_bending_iterations_converge_the_cantilever():
    # one XPBD pass a substep under-delivers the bending where its compliance is not large against the
    # mass term (a 5 mm strip droops 49 degrees at 2.5 cm); iterated with the multiplier accumulated it
    # converges (36.3 degrees at 4 passes, 35.5 at 8). Shirting at 0.05 gf cm^2/cm, the cotton preset's
    # bending before its Cusick calibration: at the preset's 0.10 the passes converge more slowly
    # (24.1 degrees at 4, 20.6 at 8)
    from core.drape import DrapeOptions
    from core.drape.materials import get_material

    shirting = get_material("cotton", {"bending": 5.0e-6})
    angle = {
        it: T.tip_angle(shirting, 0.025, 0.005, DrapeOptions(solver="xpbd", iterations=it), 300)[0] for it in (1, 4, 8)
    }
    assert angle[1] > angle[4] + 8.0
    assert abs(angle[4] - angle[8]) < 2.0


def test_a_swinging_strip_stays_out_of_the_platform(monkeypatch):
    # jersey's 12 cm overhang at 2.5 mm falls and swings its tip toward the platform's side at about 1 m/s
    # (4 cm a frame with pd's 2 substeps): the contact search runs again whenever a particle may have come
    # from beyond its search distance (before, once a frame: with the released strip's onset iterations the
    # tip passed 7 mm into the platform and the contact tore the strip, 330 % strain)
    seen = []
    real = DrapeSolver.step

    def step(self, state, before_substep=None):
        real(self, state, before_substep)
        seen.append(state.x.numpy().copy())

    monkeypatch.setattr(DrapeSolver, "step", step)
    angle, st = T.tip_angle(get_material("jersey"), 0.12, 0.0025, T.DrapeOptions.coerce({"solver": "pd"}), 300)
    assert st.settled and angle > 80.0
    x = np.concatenate(seen)
    inside = (x[:, 0] < -1e-3) & (x[:, 2] < -1e-3) & (x[:, 2] > -0.099)  # the platform: x < 0, -0.1 < z < 0
    assert not inside.any()


def test_cantilever_orders_the_fabrics():
    # the bisection brackets the 41.5 degree overhang; denim (stiff, heavy) has a longer bending length
    # than silk (the presets' own (G/W)^(1/3): 2.48 and 1.30 cm; XPBD's one pass delivers less of the
    # stiffer bending: 1.27 and 0.96 cm here; pd gives 2.38 and 1.30 cm, but its silk strip droops
    # 26 degrees at a 0.4 cm overhang, more than at 1.85 cm)
    xpbd = {"solver": "xpbd"}
    denim = T.cantilever("denim", edge=0.005, options=xpbd, bisections=3)
    silk = T.cantilever("silk", edge=0.005, options=xpbd, bisections=3)
    for r in (denim, silk):
        assert np.isfinite(r["bending_length_cm"]) and 0.2 < r["bending_length_cm"] < 6.0
        angles = sorted((q["overhang_cm"], q["angle_deg"]) for q in r["runs"])
        assert all(a0 <= a1 for (_, a0), (_, a1) in zip(angles[:-1], angles[1:]))  # longer droops more
    assert denim["bending_length_cm"] > 1.2 * silk["bending_length_cm"]
    assert T.cantilever_expected("denim") == pytest.approx(2.48, abs=0.01)


# ----------------------------------------------------------------------------- the solvers (issue 35)


def test_solver_option_is_checked():
    from core.drape import DrapeOptions
    from core.errors import DrapeError

    with pytest.raises(DrapeError, match="drape option solver = 'style3d'"):
        DrapeOptions.coerce({"solver": "style3d"})
    # iterations left out: the solver's own default
    assert [DrapeOptions(solver=s).iterations for s in ("xpbd", "vbd", "newton")] == [1, 2, 30]
    assert DrapeOptions(solver="newton", iterations=4).iterations == 4


def test_newton_energy_gradient_matches_finite_differences():
    # the line search and the residual stop trust grad G: check it against G on a bent, stretched sheet
    from core.drape.newton import NewtonStep

    uv, faces = T.strip_mesh([0.0, 0.04], 0.03, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < -1.0, "cotton"))
    rng = np.random.default_rng(3)
    x = cloth.x0 + rng.normal(scale=5e-4, size=cloth.x0.shape)
    y = x + rng.normal(scale=1e-4, size=x.shape)
    mass = 0.13 * cloth.mass_area
    n = cloth.n_particles
    ps = NewtonStep(cloth, get_material("cotton"), 1 / 90, mass, np.full((len(cloth.faces), 2), 1.01), np.zeros(0))
    ps.set_contact(np.zeros((n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1)), np.ones(n, int), 0.0003)
    e, g = ps.energy(x, y, 0.5)
    h = 1e-7
    for i, k in [(0, 0), (5, 2), (n - 1, 1), (n // 2, 2)]:
        xp, xm = x.copy(), x.copy()
        xp[i, k] += h
        xm[i, k] -= h
        fd = (ps.energy(xp, y, 0.5, gradient=False)[0] - ps.energy(xm, y, 0.5, gradient=False)[0]) / (2 * h)
        assert fd == pytest.approx(g[i, k], rel=1e-4, abs=1e-9 * np.abs(g).max())


def test_newton_buckling_caps_the_compressive_stress():
    # sub-element buckling (the default): a grain spring compressed past the element's Euler load pi^2 B /
    # h^2 pushes back with that stress and no more; its gradient still matches G (finite differences)
    from core.drape.newton import NewtonStep, buckling_stress

    uv, faces = T.strip_mesh([0.0, 0.04], 0.03, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < -1.0, "silk"))
    silk, n = get_material("silk"), cloth.n_particles
    mass = silk.density * cloth.mass_area
    start = np.ones((len(cloth.faces), 2))
    steps = {b: NewtonStep(cloth, silk, 1 / 90, mass, start, np.zeros(0), buckling=b) for b in (False, True)}
    assert np.all(np.isfinite(NewtonStep(cloth, silk, 1 / 90, mass, start, np.zeros(0)).cap_a))  # on by default
    y = cloth.x0.copy()
    squeeze = cloth.x0 * np.array([0.9, 1.0, 1.0])  # 10 % along x: past every element's buckling strain
    sigma = buckling_stress(silk.bending, cloth.rest_area)
    assert np.all(0.1 * silk.stretch_weft > sigma)
    e_free, g_free = steps[False].energy(squeeze, y, 1.0)
    e_cap, g_cap = steps[True].energy(squeeze, y, 1.0)
    assert e_cap < 0.1 * e_free and np.abs(g_cap).max() < 0.1 * np.abs(g_free).max()
    # the capped energy grows linearly past the cap: the force on the strip's end is the stress times
    # the width it carries (the end column's share), whatever the squeeze
    end = np.nonzero(uv[:, 0] >= 0.04 - 1e-9)[0]
    more = cloth.x0 * np.array([0.8, 1.0, 1.0])
    _, g_more = steps[True].energy(more, y, 1.0)
    inertia = steps[True].inertia[:, None]
    elastic_cap, elastic_more = g_cap - inertia * (squeeze - y), g_more - inertia * (more - y)
    assert elastic_more[end, 0].sum() == pytest.approx(elastic_cap[end, 0].sum(), rel=1e-6)
    assert -elastic_cap[end, 0].sum() == pytest.approx(sigma.mean() * 0.03, rel=0.05)  # 3 cm wide
    rng = np.random.default_rng(5)
    x = squeeze + rng.normal(scale=2e-4, size=squeeze.shape)
    e, g = steps[True].energy(x, y, 1.0)
    h = 1e-7
    for i, k in [(0, 0), (n // 2, 1), (n - 1, 2)]:
        xp, xm = x.copy(), x.copy()
        xp[i, k] += h
        xm[i, k] -= h
        fd = (steps[True].energy(xp, y, 1.0, False)[0] - steps[True].energy(xm, y, 1.0, False)[0]) / (2 * h)
        assert fd == pytest.approx(g[i, k], rel=1e-4, abs=1e-9 * np.abs(g).max())


def test_clamped_hinge_carries_the_free_side_alone():
    # a hinge between a clamped triangle and a free one stands for the free side's curvature only: its
    # weight is |e|^2 / A_free, twice an interior hinge's on the strip's regular cells; the others keep
    # mesh.py's |e|^2 / (A_a + A_b)
    from core.drape.newton import clamped_bend_weight

    uv, faces = T.strip_mesh([-0.02, 0.0, 0.04], 0.02, 0.005)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] <= 1e-9, "cotton"))
    w0, w = np.asarray(cloth.bend_weight), clamped_bend_weight(cloth)
    b = cloth.bends.reshape(-1, 4)
    pos = cloth.x0[b]
    on_line = np.all(np.abs(pos[:, 2:, 0]) < 1e-9, axis=1)  # the hinge edge lies on the clamp line x = 0
    assert on_line.sum() == 4  # the 2 cm wide strip's four 5 mm cross edges
    assert np.allclose(w[on_line], 2.0 * w0[on_line])
    assert np.allclose(w[~on_line], w0[~on_line])


def test_newton_cantilever_converges_in_the_mesh():
    # the clamp's hinge weighted for the free side alone: the cotton strip (3.46 cm overhang) droops
    # 34.9 / 35.3 degrees at 10 / 5 mm edges; with |e|^2 / (A_a + A_b) there it drooped 46.0 / 41.3
    # (and 38.8 at 2.5 mm): the clamp hinge turned twice what its moment asks, a first-order error
    from core.drape import DrapeOptions

    opts = DrapeOptions.coerce({"solver": "newton", "substeps": 3})
    cotton = get_material("cotton")
    angle = {h: T.tip_angle(cotton, 0.0346, h, opts, 200)[0] for h in (0.01, 0.005)}
    assert abs(angle[0.01] - angle[0.005]) < 1.5
    assert 30.0 < angle[0.005] < 40.0


def test_newton_step_ends_no_higher_than_its_start():
    # a solve cut off at one iteration from a guess far up the potential (stiff springs stretched)
    # ends no higher in G than the substep's start x_n: it starts from x_n where G is lower there
    from core.drape.newton import NewtonStep

    uv, faces = T.strip_mesh([0.0, 0.1], 0.1, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv, faces, 0.0, uv[:, 0] < 1e-9, "cotton"))
    cotton = get_material("cotton")
    mass = cotton.density * cloth.mass_area
    step = NewtonStep(cloth, cotton, 1 / 90, mass, np.ones((len(cloth.faces), 2)), np.zeros(0))
    x_n = cloth.x0.copy()
    y = x_n - np.array([0.0, 0.0, 9.81 / 90**2])
    guess = x_n + np.random.default_rng(2).normal(scale=2e-3, size=x_n.shape) * step.free[:, None]
    g_start = step.energy(x_n, y, 1.0, False)[0]
    assert step.energy(guess, y, 1.0, False)[0] > 10 * g_start
    weight = mass * 9.81
    cut = guess.copy()
    step.solve(cut, y, 1.0, 1, 1e-9, weight, previous=x_n)
    assert step.energy(cut, y, 1.0, False)[0] <= g_start


def test_newton_holds_the_fabric_stiffness():
    # a 30 x 50 cm cotton sheet hanging from its top edge, no tethers, 2 cm mesh: in equilibrium the warp
    # tension at the clamp is rho g H per width, the largest warp strain rho g H / k_warp = 0.021 %. One XPBD
    # pass a substep stretched it 3.5 % (p95) here, 25 % on a 1 cm mesh (issue 35): its stiffness came
    # from the step; the newton solver's factored global solve delivers the preset's
    r = T.hanging_sheet("cotton", edge=0.02, options={"solver": "newton", "substeps": 3}, max_frames=40)
    assert r["settled"]
    assert r["warp_max_pct"] == pytest.approx(r["expected_pct"], rel=0.15)
    assert 0.0 < r["warp_p95_pct"] < 1.0


@pytest.fixture(scope="module")
def cusick_newton():
    # the plain coarse disc (no clamp band, textile.clamp_band): an equilibrium to check, not a drape figure
    solver, state, uv = T.cusick_setup("cotton", edge=0.025, options={"solver": "newton", "substeps": 3}, band=False)
    st = T.settle(solver, state, 150)
    return solver, state, st


def test_newton_settles_in_the_fabric_equilibrium(cusick_newton):
    # the settled disc is a static equilibrium of the preset's own energy: on every particle off the
    # support the elastic force balances the weight (before, XPBD's settled shape balanced its
    # step-dependent effective stiffness instead)
    solver, state, st = cusick_newton
    assert st.settled
    assert solver.residual(state) < 0.05
    x = state.x.numpy()
    assert x[:, 2].min() < -0.03  # the annulus hangs
    # one solve a substep; at the end each met the residual tolerance before the iteration limit (the
    # released disc's first frames take onset_factor x the iterations: DrapeOptions.onset_frames)
    its = np.asarray(solver._newton_iterations)
    onset = 3 * solver.onset
    assert len(its) == 3 * st.frames and its[onset:].max() <= 30 and its[-3:].max() < 30
    assert its[:onset].max() <= 30 * solver.options.onset_factor


def test_vbd_runs_and_repeats():
    # Vertex Block Descent: finite, falling, and bitwise repeatable on the CPU (colour-ordered Gauss-Seidel)
    runs = []
    for _ in range(2):
        solver, state, _ = T.cusick_setup("cotton", edge=0.025, options={"solver": "vbd", "substeps": 10}, band=False)
        for _ in range(15):
            solver.step(state)
        runs.append(state.x.numpy().copy())
    assert np.all(np.isfinite(runs[0]))
    assert runs[0][:, 2].min() < -0.02
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.slow
def test_newton_cotton_cusick_meets_the_published_range_at_any_iteration_count():
    # the calibrated cotton preset (bending 0.10 gf cm^2/cm) on the 10 mm disc: inside the published
    # 60-76 % with 5-10 nodes, and the same drape (within +-3 points) at 4x the iterations (66.0 % with 8
    # nodes and 67.1 % with 9, sub-element buckling and clamped hinges). Minutes: --full only
    runs = [
        T.cusick("cotton", edge=0.01, options={"solver": "newton", "substeps": 3, "iterations": it}, max_frames=200)
        for it in (30, 120)
    ]
    for r in runs:
        assert r["settled"]
        assert 60.0 <= r["dc_pct"] <= 76.0 and 5 <= r["nodes"] <= 10
    assert abs(runs[0]["dc_pct"] - runs[1]["dc_pct"]) <= 3.0


@pytest.mark.slow
def test_newton_wool_and_silk_meet_their_ranges():
    # wool (worsted suiting) and silk on the 10 mm disc: inside the 55-65 % and 20-40 % issue 35 gives,
    # with 5-10 nodes. Silk read 49.9 % (6 nodes) before the sub-element buckling cap: a grain spring
    # resisting compression as it resists tension locked the hoops the mesh could not fold
    # (docs/drape.md). Minutes: --full only
    opts = {"solver": "newton", "substeps": 3}
    for name, (lo, hi) in (("wool", (55.0, 65.0)), ("silk", (20.0, 40.0))):
        r = T.cusick(name, edge=0.01, options=opts, max_frames=200)
        assert r["settled"] and lo <= r["dc_pct"] <= hi and 5 <= r["nodes"] <= 10, (name, r["dc_pct"], r["nodes"])


def test_a_stiff_hinge_turns_at_most_its_reach_a_pass():
    # two 1 mm triangles of cotton, folded 1.5 rad off their flat rest: against their tiny masses the
    # hinge is as good as rigid, and one full Gauss-Seidel step turned it all the way at once (the
    # knife-pleated skirt at 5 mm tore at frame 1); a pass turns it by at most BEND_REACH, and the
    # passes with their multiplier still reach the rest angle
    from core.drape import kernels as K
    from core.drape.mesh import dihedral_angles

    wp = K.wp
    fold = 1.5
    x = np.array([[5e-4, 1e-3 * np.cos(fold), 1e-3 * np.sin(fold)], [5e-4, -1e-3, 0.0], [0, 0, 0], [1e-3, 0, 0]])
    bend = np.array([[0, 1, 2, 3]])
    start = dihedral_angles(x, bend)[0]
    assert abs(start) == pytest.approx(fold, abs=1e-6)
    xs = wp.array(x, dtype=wp.vec3, device="cpu")
    lam = wp.zeros(1, dtype=float, device="cpu")
    args = [wp.full(4, 5e7, dtype=float, device="cpu"), wp.array(bend.astype(np.int32), dtype=int, device="cpu")]
    args += [wp.ones(1, dtype=float, device="cpu"), wp.zeros(1, dtype=float, device="cpu"), 1.0e-5, 600.0**2, 0, lam]
    angles = []
    for _ in range(12):
        wp.launch(K.solve_bending, 1, inputs=[xs, *args], device="cpu")
        angles.append(dihedral_angles(xs.numpy().astype(float), bend)[0])
    assert abs(start) - abs(angles[0]) == pytest.approx(K.BEND_REACH, abs=0.1)
    assert abs(angles[-1]) < 0.01
