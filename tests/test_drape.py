"""The XPBD drape on a body of revolution with a two-panel tube skirt (core.drape)."""

import numpy as np
import pytest
from drape_synth import HIP_RADIUS, radius, revolution_body, tube_skirt

from core.drape import DrapeOptions, DrapeSolver, drape
from core.drape.materials import get_material
from core.drape.mesh import build_cloth, rest_edges
from core.drape.schedule import check_divergence, growth_per_substep, initial_growth, run, settle_speed
from core.errors import DrapeError
from core.metrics.drape import penetration, seam_side_distance


@pytest.fixture(scope="module")
def body():
    return revolution_body(48, 60)


@pytest.fixture(scope="module")
def skirt():
    return tube_skirt(1.2)


@pytest.fixture(scope="module")
def draped(body, skirt):
    return drape(skirt, *body)


def test_hangs_without_penetrating(body, draped):
    share, sd = penetration(draped.positions, *body)
    assert share == 0.0
    assert sd.min() > -0.002
    # analytic check on the body of revolution: every particle outside the surface
    x = draped.positions
    clearance = np.hypot(x[:, 0], x[:, 1]) - radius(x[:, 2])
    assert clearance.min() > -0.002
    assert draped.settled and draped.settle_reason == "settled"


def test_relaxes_from_skintight_to_pattern_size(draped):
    # the 1.2-ease skirt starts on the hips and billows out to about 1.2 x the hip radius
    x = draped.positions
    hem = x[:, 2] < 0.7
    r_hem = np.hypot(x[hem, 0], x[hem, 1]).mean()
    assert 1.08 * HIP_RADIUS < r_hem < 1.25 * HIP_RADIUS
    start = np.hypot(draped.start_positions[:, 0], draped.start_positions[:, 1])
    assert np.allclose(start, HIP_RADIUS, atol=1e-6)


def test_keeps_pattern_rest_lengths(skirt, draped):
    cloth = build_cloth(skirt)
    x = draped.positions[np.argsort(cloth.particle_of)]  # particle order
    edges, rest = rest_edges(cloth.faces, cloth.rest_inv)
    ratio = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1) / rest
    # the waistband is pinned at the skintight size (1/1.2 of its pattern width) and
    # gathers the fabric just below it: judge the fabric 5 cm and more below the pins
    below = (cloth.tether_length[edges] >= 0.05).all(axis=1)
    dev = np.abs(ratio[below] - 1.0)
    assert below.sum() > len(edges) / 2
    assert dev.mean() < 0.02
    assert np.percentile(dev, 95) < 0.02
    assert dev.max() < 0.08  # a single edge at a fold


def test_closes_its_seams(skirt, draped):
    sides = seam_side_distance(skirt, draped.positions)
    assert set(sides) == {"side_left", "side_right"}
    assert max(sides.values()) < 1e-3


def test_unwelded_seam_is_sewn(body):
    # give the front panel's seam columns their own ids: the seams must still close
    p = tube_skirt(1.2, n_rows=6, n_cols=6)
    front = p.panel("front")
    n = int(max(q.vertex_ids.max() for q in p.panels)) + 1
    for s in p.seams:
        side = s.verts_b if s.panel_b == "front" else s.verts_a
        front.vertex_ids[side] = n + np.arange(len(side))
        n += len(side)
    p.pins = {"skirt": np.concatenate([p.panel("back").vertex_ids[:7], front.vertex_ids[:7]])}
    r = drape(p, *body, options={"max_frames": 30})
    assert max(seam_side_distance(p, r.positions).values()) < 1e-3
    assert r.positions.shape == (n, 3)


def test_two_cpu_runs_are_identical(body, skirt, draped):
    again = drape(skirt, *body)
    assert again.frames == draped.frames
    assert np.array_equal(again.positions, draped.positions)


def test_result_layout(skirt, draped):
    n = int(max(p.vertex_ids.max() for p in skirt.panels)) + 1
    assert draped.positions.shape == (n, 3)
    assert draped.faces.shape == (sum(len(p.faces) for p in skirt.panels), 3)
    assert draped.strain_weft.shape == (n,) and draped.strain_warp.shape == (n,)
    assert set(draped.timings) == {"prepare", "compile", "simulate", "total"}
    assert draped.garment_names == ["skirt"]
    assert draped.material["name"] == "cotton"  # from the pattern's materials.fabric
    assert not draped.self_collision  # optional, off by default
    # settling is only declared once the fabric has grown to its pattern size
    assert draped.frames > draped.options["grow_frames"] + draped.options["settle_frames"] - 1


def test_growth_starts_from_the_skintight_stretch(body, skirt):
    # after one frame of the 20-frame growth the 1.2-ease skirt is still near its skintight size;
    # without growth it has already sprung off the body
    grown = drape(skirt, *body, options={"max_frames": 1, "min_frames": 1})
    at_once = drape(skirt, *body, options={"max_frames": 1, "min_frames": 1, "grow_frames": 0})
    r = lambda res: np.hypot(res.positions[:, 0], res.positions[:, 1]).mean()  # noqa: E731
    assert r(grown) < r(at_once)
    assert r(grown) < 1.03 * HIP_RADIUS


def _sheets(n=10, size=0.2, drop=0.03):
    """Two flat square sheets 1 m beside the body: the lower one pinned, the upper one ``drop`` above it."""
    from core.pattern.types import Pattern, PatternPanel

    g = np.linspace(0.0, size, n + 1)
    u, v = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    faces = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            faces += [[a, a + n + 1, a + 1], [a + 1, a + n + 1, a + n + 2]]
    faces = np.asarray(faces)
    panels = []
    for k, (name, z) in enumerate((("lower", 0.5), ("upper", 0.5 + drop))):
        xyz = np.column_stack([1.0 + u, v, np.full(len(u), z)])
        panels.append(
            PatternPanel(
                name=name,
                garment="sheets",
                uv=np.column_stack([u, v]),
                faces=faces,
                vertex_ids=k * len(u) + np.arange(len(u)),
                xyz=xyz,
                grain=np.array([0.0, 1.0]),
                target_weft=np.ones(len(faces)),
                target_warp=np.ones(len(faces)),
                achieved_weft=np.ones(len(faces)),
                achieved_warp=np.ones(len(faces)),
            )
        )
    return Pattern(
        style="sheets",
        body={"model": "revolution"},
        garments={"sheets": "sheets"},
        panels=panels,
        seams=[],
        pins={"sheets": np.arange(len(u))},
        materials={"fabric": "cotton"},
    )


def test_self_collision_stacks_layers(body):
    # the upper sheet falls onto the pinned lower one: with self-collision it rests on it about
    # two particle radii up, without it falls through
    p = _sheets()
    opts = {"max_frames": 20, "tether_slack": None}
    on = drape(p, *body, options={**opts, "self_collision": True})
    assert on.self_collision and on.self_radius == pytest.approx(0.4 * 0.02)
    upper = p.panel("upper").vertex_ids
    z_on = on.positions[upper, 2] - 0.5
    assert z_on.min() > 0.8 * 2 * on.self_radius
    assert z_on.max() < 1.2 * 2 * on.self_radius
    off = drape(p, *body, options=opts)
    assert not off.self_collision
    assert off.positions[upper, 2].max() < 0.5 - 0.05
    again = drape(p, *body, options={**opts, "self_collision": True})
    assert np.array_equal(again.positions, on.positions)  # still bitwise repeatable


def test_self_collision_holds_at_many_iterations(body):
    # pd's self-collision penalty is not in the step's matrix: where no halved step lowers G the solve
    # stops there (before, iterating on from a raised G diverged at 80 iterations a substep)
    p = _sheets()
    r = drape(p, *body, options={"max_frames": 20, "tether_slack": None, "self_collision": True, "iterations": 80})
    z = r.positions[p.panel("upper").vertex_ids, 2] - 0.5
    assert z.min() > 0.8 * 2 * r.self_radius and z.max() < 1.2 * 2 * r.self_radius


def test_woven_cotton_barely_stretches_jersey_gives(body):
    # a heavy load (5 g) without tethers: the warp carries the skirt's weight (pd, the default, at its
    # own substeps: 5 at 5 g; XPBD needed 80 to deliver the stiffness)
    p = tube_skirt(1.0, n_rows=8, n_cols=8)
    opts = {"gravity": 50.0, "tether_slack": None, "max_frames": 20}
    cotton = drape(p, *body, material="cotton", options=opts)
    jersey = drape(p, *body, material="jersey", options=opts)
    assert np.abs(cotton.face_strain_warp).mean() < 0.05
    assert jersey.face_strain_warp.mean() > cotton.face_strain_warp.mean() + 0.004
    assert get_material("cotton").max_stretch <= 0.05 < get_material("jersey").max_stretch


def test_absurd_time_step_is_refused(body, skirt):
    with pytest.raises(DrapeError, match="time step"):
        drape(skirt, *body, options={"fps": 0.5, "substeps": 1})


def test_absurd_stiffness_is_refused(body, skirt):
    with pytest.raises(DrapeError, match="stretch_weft"):
        drape(skirt, *body, material={"fabric": "cotton", "stretch_weft": 1e12})
    with pytest.raises(DrapeError, match="shear"):
        drape(skirt, *body, material={"fabric": "cotton", "shear": -1.0})


def test_divergence_detector_names_frame_and_cause():
    opts = DrapeOptions()
    mat = get_material("cotton")
    x = np.zeros((4, 3))
    v = np.zeros((4, 3))
    check_divergence(3, x, v, opts, mat, 1e-3)  # a still state passes
    with pytest.raises(DrapeError, match="frame 7.*NaN"):
        check_divergence(7, np.array([[np.nan, 0, 0]]), v[:1], opts, mat, 1e-3)
    with pytest.raises(DrapeError, match="frame 8.*bounding box"):
        check_divergence(8, np.array([[0, 0, 0], [100.0, 0, 0]]), v[:2], opts, mat, 1e-3)
    with pytest.raises(DrapeError, match="frame 9.*kinetic energy"):
        check_divergence(9, x, np.full((4, 3), 100.0), opts, mat, 1e-3)


def test_stretch_blowup_is_divergence(skirt):
    cloth = build_cloth(skirt)
    torn = cloth.x0 * np.array([1.0, 1.0, 5.0])  # stretched 5x along the warp
    with pytest.raises(DrapeError, match="frame 2.*stretched beyond"):
        check_divergence(2, torn, np.zeros_like(torn), DrapeOptions(), get_material("cotton"), 1e-3, cloth)


def test_bad_inputs(body, skirt):
    with pytest.raises(DrapeError, match="unknown drape option"):
        drape(skirt, *body, options={"frams": 3})
    with pytest.raises(DrapeError, match="substeps"):
        drape(skirt, *body, options={"substeps": 0})
    with pytest.raises(DrapeError, match="body vertices"):
        drape(skirt, np.zeros((3, 2)), body[1])
    with pytest.raises(DrapeError, match="device"):
        drape(skirt, *body, options={"device": "cuda:7"})
    with pytest.raises(DrapeError, match="unknown material"):
        drape(skirt, *body, material="tweed-ish")
    with pytest.raises(DrapeError, match="self_collision"):
        drape(skirt, *body, options={"self_collision": "yes"})
    with pytest.raises(DrapeError, match="grow_frames"):
        drape(skirt, *body, options={"grow_frames": -1})


def test_solver_steps_reproduce_drape(body, skirt, draped):
    # the solver and its schedule, driven by hand, give the drape bitwise; a second state
    # on the same solver starts afresh (the solver keeps nothing a step changes)
    solver = DrapeSolver(build_cloth(skirt), *body, get_material("cotton"))
    first = solver.state()
    settling = run(solver, first)
    assert settling.frames == draped.frames and settling.settled and settling.reason == "settled"
    assert np.array_equal(settling.speeds, draped.speed_history)
    second = solver.state()
    for _ in range(draped.frames):
        solver.step(second)
    assert second.frames == draped.frames and second.substeps == draped.frames * solver.options.substeps
    assert np.array_equal(second.x.numpy(), first.x.numpy())
    assert solver.options.solver == "pd" and solver.options.substeps == 2  # the default: cotton's 2 substeps
    assert solver.dt == pytest.approx(1.0 / (30.0 * 2))


def test_solver_validates_at_the_door(body, skirt):
    cloth = build_cloth(skirt)
    with pytest.raises(DrapeError, match="substeps"):
        DrapeSolver(cloth, *body, options={"substeps": 0})
    with pytest.raises(DrapeError, match="body faces"):
        DrapeSolver(cloth, body[0], body[1][:, :2])
    with pytest.raises(DrapeError, match="time step"):
        DrapeSolver(cloth, *body, options={"fps": 0.5, "substeps": 1})


def test_growth_schedule():
    opts = DrapeOptions(grow_frames=20, substeps=10)
    assert initial_growth(opts) == 0.0 and growth_per_substep(opts) == pytest.approx(1.0 / 200)
    at_once = DrapeOptions(grow_frames=0)
    assert initial_growth(at_once) == 1.0 and growth_per_substep(at_once) is None


def test_settle_speed_leaves_out_the_fastest():
    v = np.zeros((100, 3))
    v[:, 0] = 0.01
    v[0, 0] = 10.0  # one particle chattering in an armpit
    assert settle_speed(v, 0.0) > 0.5
    assert settle_speed(v, 0.02) == pytest.approx(0.01)
    assert settle_speed(np.zeros((0, 3)), 0.02) == 0.0


def test_options_name_the_field_and_unit():
    with pytest.raises(DrapeError, match="settle_trim"):
        DrapeOptions.coerce({"settle_trim": 0.7})
    with pytest.raises(DrapeError, match="thickness"):
        DrapeOptions.coerce({"thickness": -0.001})
    with pytest.raises(DrapeError, match="fps"):
        DrapeOptions.coerce({"fps": float("inf")})
    with pytest.raises(DrapeError, match="DrapeOptions or a dict"):
        DrapeOptions.coerce(3)
    doc = DrapeOptions.__doc__
    for unit in ("m/s", "1/s", "m/s^2", "frames", "substeps"):
        assert unit in doc


def _tube(kind: str):
    """The tube skirt as a garment of ``kind`` (its waistband pinned either way)."""
    p = tube_skirt(1.2, n_rows=6, n_cols=6)
    p.garments = {"skirt": kind}
    return p


def test_an_upper_garments_pins_let_go_once_grown(body):
    # the hips are a cylinder over a narrower leg column: nothing holds a loose tube there but its pins.
    # As an upper garment its pinned band lets go after the growth and the tube slides down; as a lower
    # garment (or with hold_pins) the band stays where it was pinned
    opts = {"max_frames": 30, "min_frames": 30, "grow_frames": 5}
    top = _tube("upper")
    cloth = build_cloth(top)
    band = cloth.pinned.copy()
    assert band.any() and np.array_equal(cloth.pin_lets_go, band)
    assert not build_cloth(_tube("lower")).pin_lets_go.any()
    start = cloth.x0[band, 2].mean()
    z = {}
    for name, pattern, extra in (
        ("upper", top, {}),
        ("upper held", top, {"hold_pins": True}),
        ("lower", _tube("lower"), {}),
    ):
        solver = DrapeSolver(build_cloth(pattern), *body, options={**opts, **extra})
        state = solver.state()
        run(solver, state)
        assert state.released == (name == "upper")
        assert np.array_equal(state.free, solver.free | (band & state.released))
        z[name] = state.x.numpy()[band, 2].mean()
        # a later state starts held again: letting go is the state's, not the solver's
        again = solver.state()
        assert not again.released and np.array_equal(again.free, solver.free)
        assert np.array_equal(again.w.numpy() > 0, solver.free)
    assert z["upper"] < start - 0.02
    assert abs(z["upper held"] - start) < 1e-6 and abs(z["lower"] - start) < 1e-6


def test_letting_go_recomputes_the_tethers():
    cloth = build_cloth(_tube("upper"))
    assert (cloth.tether_anchor >= 0).any()
    free = cloth.let_go()
    assert not free.pinned.any() and not free.pin_lets_go.any()
    assert (free.tether_anchor == -1).all() and (free.tether_length == 0).all()
    # the rest of the cloth is the same
    assert np.array_equal(free.faces, cloth.faces) and np.array_equal(free.x0, cloth.x0)


def test_the_let_go_cloth_keeps_the_drapes_options(body):
    # pd steps the let-go cloth with its own factored matrix: built with the same strain limit and friction
    solver = DrapeSolver(
        build_cloth(_tube("upper")), *body, options={"max_frames": 2, "grow_frames": 1, "strain_limit": 30.0}
    )
    state = solver.state()
    solver.step(state)
    solver.step(state)
    assert state.released
    held, let_go = solver._implicit, solver._released[2]
    assert let_go is not held and let_go.limit_weight == held.limit_weight == 30.0
    assert let_go.friction == held.friction
    assert let_go.free.all() and not held.free.all()
