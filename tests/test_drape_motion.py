"""The drape carried through a body's motion (core.drape.animate): the garment follows a moving
body without tunnelling, pinned vertices ride on it, pose in-betweens keep the limbs' length."""

from __future__ import annotations

import json

import numpy as np
import pytest
from drape_synth import revolution_body, tube_skirt

from core.body.instance import body_instance, instance_shape
from core.drape import DrapeSolver
from core.drape import textile as T
from core.drape.animate import drape_motion, pose_frames
from core.drape.mesh import build_cloth
from core.errors import DrapeError
from core.geom.frame import to_y_up


@pytest.fixture(scope="module")
def body():
    return revolution_body(48, 60)


def _centroid(result, k):
    return result.positions[k][result.used].mean(axis=0)


def test_skirt_follows_a_fast_moving_body(body):
    """5 cm a frame (1.5 m/s) for 10 frames, then still for a second: the skirt comes along,
    nothing passes through the body at any frame, none of it is left behind."""
    bv, bf = body
    frames = [bv + [0.05 * k, 0.0, 0.0] for k in range(11)] + [bv + [0.5, 0.0, 0.0]] * 30
    r = drape_motion(tube_skirt(), frames, bf, options={"max_frames": 60})
    assert r.positions.shape[0] == len(frames) and np.all(np.isfinite(r.positions))
    assert r.penetration.max() <= 0.005, r.penetration
    # none of it left behind: at every frame each vertex is within a hand of the body's axis
    for k, f in enumerate(frames):
        axis = f[:, :2].mean(axis=0)
        far = np.linalg.norm(r.positions[k][r.used][:, :2] - axis, axis=1).max()
        assert far < 0.35, (k, far)
    # the body still again, the skirt hangs as it did, 0.5 m on
    shift = _centroid(r, len(frames) - 1) - _centroid(r, 0)
    assert shift == pytest.approx([0.5, 0.0, 0.0], abs=0.01)
    ext = [np.ptp(r.positions[k][r.used][:, 0]) for k in (0, len(frames) - 1)]
    assert ext[1] == pytest.approx(ext[0], abs=0.01)
    assert len(r.frame_seconds) == len(frames) - 1 and r.settled


def test_a_body_jumping_20_cm_in_one_frame_keeps_the_skirt(body):
    """A frame that moves the body further than a simulation frame may (MAX_MOVE) is simulated as
    several: the skirt is carried, not torn or left inside."""
    from core.drape.animate import MAX_MOVE

    bv, bf = body
    assert 0.2 > 2 * MAX_MOVE
    r = drape_motion(tube_skirt(), [bv, bv + [0.2, 0.0, 0.0], bv + [0.2, 0.0, 0.0]], bf, options={"max_frames": 60})
    assert r.penetration.max() <= 0.005, r.penetration
    # carried 20 cm across, neither thrown up nor overshooting (one 20 cm jump throws it up ~6 cm)
    assert _centroid(r, 2) - _centroid(r, 0) == pytest.approx([0.2, 0.0, 0.0], abs=0.02)
    assert r.stretch.max() < 0.15


def test_a_still_body_keeps_the_settled_drape(body, tmp_path):
    bv, bf = body
    r = drape_motion(tube_skirt(), [bv] * 4, bf, options={"max_frames": 60})
    assert np.abs(r.positions[-1] - r.positions[0]).max() < 0.005
    # its files: Y-up by default, up="z" the core frame; the OBJ's faces on the used vertices
    from core.drape.animate import write_motion

    for up, frame in (("y", to_y_up), ("z", np.asarray)):
        write_motion(tmp_path / up, r, [bv] * 4, bf, ["A", "A"], 2, up=up)
        k, n = _pc2(tmp_path / up / "garment_motion.pc2")
        assert n == int(r.used.sum()) and np.allclose(k, frame(r.positions[:, r.used]), atol=1e-6)
        kb, _ = _pc2(tmp_path / up / "body_motion.pc2")
        assert np.allclose(kb[0], frame(bv), atol=1e-6)
        lines = (tmp_path / up / "garment_motion.obj").read_text().splitlines()
        assert f"+{up.upper()} up" in lines[1]
        v = np.array([ln.split()[1:] for ln in lines if ln.startswith("v ")], float)
        f = np.array([ln.split()[1:] for ln in lines if ln.startswith("f ")], int) - 1
        assert np.allclose(v, k[0], atol=1e-6) and f.min() == 0 and f.max() == len(v) - 1
        assert np.allclose(v[f], frame(r.positions[0][r.faces]), atol=1e-6)


@pytest.mark.parametrize("friction", [False, True])
def test_pd_carries_the_cloth_a_body_slides_under(friction, monkeypatch):
    """pd: a sheet resting on a box that slides along under it, 1 cm a frame for 10 frames, rides on
    it (its held particles keep their velocity relative to the body, as on a still body their own)
    and stops with it, on the box at its offset; with Coulomb friction in the solve too (pd.FRICTION:
    anchored where the body carried the substep's start). (Before, pd's contact penalty held the sheet
    where it was in the world: the box slid out from under it.)"""
    monkeypatch.setattr("core.drape.pd.FRICTION", friction)
    uv, faces = T.strip_mesh([0.0, 0.06], 0.06, 0.01)
    cloth = build_cloth(T.sheet_pattern(uv - [0.03, 0.0], faces, 0.0, np.zeros(len(uv), bool), "cotton"))
    bv, bf = T.box_body([-0.2, -0.2, -0.1], [0.2, 0.2, -0.003])
    solver = DrapeSolver(cloth, bv, bf, "cotton", {"solver": "pd"})
    state = solver.state()
    n = solver.options.substeps

    def frames(count, at):
        for k in range(count):
            solver.step(state, before_substep=lambda i, k=k: solver.move_body(bv + [at(k + (i + 1) / n), 0.0, 0.0]))
        return state.x.numpy().astype(float)

    x0 = frames(3, lambda t: 0.0)
    moved = frames(10, lambda t: 0.01 * t)
    held = frames(5, lambda t: 0.1)
    assert (moved - x0).mean(axis=0) == pytest.approx([0.1, 0.0, 0.0], abs=2e-3)
    assert np.abs(held - moved).max() < 1e-3  # stopped with the body
    assert np.abs(held[:, 2] - x0[:, 2]).max() < 1e-4  # on the box, at its offset


def test_moved_body_must_keep_its_vertices(body):
    bv, bf = body
    solver = DrapeSolver(build_cloth(tube_skirt()), bv, bf)
    with pytest.raises(DrapeError, match="vertices"):
        solver.move_body(bv[:-1])
    with pytest.raises(DrapeError, match="vertex count"):
        drape_motion(tube_skirt(), [bv, bv[:-1]], bf)


def test_pose_in_betweens_keep_the_limbs(anny):
    """A -> P1 -> P3 with in-betweens: the poses' frames are the model's own instances, and an
    arm's length (fingertip to shoulder) holds through the in-betweens from A to P1 (a linear
    blend of the vertices would shorten it half-way)."""
    frames = pose_frames(anny, "M", ["A", "P1", "P3"], between=3)
    assert len(frames) == 9
    for k, pose in ((0, "A"), (4, "P1"), (8, "P3")):
        assert np.allclose(frames[k], body_instance(anny, "M", pose))
    tip = int(np.argmax(frames[0][:, 0]))  # the left fingertip in A
    head = anny.joints(instance_shape(anny, "M"))[list(anny.joint_names).index("upperarm01.L")]
    shoulder = int(np.argmin(np.linalg.norm(frames[0] - head, axis=1)))  # the skin at the shoulder joint
    # A -> P1 turns the shoulder only (P3 then bends the elbow): the arm keeps its length
    arm = np.array([np.linalg.norm(f[tip] - f[shoulder]) for f in frames[:5]])
    assert arm.max() - arm.min() < 0.01 * arm[0], arm
    # a linear blend of A and P1 half-way would be shorter: the in-betweens are rotations
    lin = 0.5 * (frames[0] + frames[4])
    assert np.linalg.norm(lin[tip] - lin[shoulder]) < arm[2] - 0.02
    steps = [np.linalg.norm(frames[k + 1][tip] - frames[k][tip]) for k in range(4)]
    assert max(steps) < 2.0 * min(steps)  # even steps from A to P1
    with pytest.raises(DrapeError):
        pose_frames(anny, "M", ["A"], between=3)


def test_pose_from_bone_rotations_round_trips_the_model_poses(anny):
    """A rig's bones turned as the model turns its joints in P3 (world rotations: each joint's
    carried by its parent's) give back P3: the same body, to rounding; a root move carries
    the body as a whole, and posed_frames poses JSON poses as the model does."""
    from core.drape.animate import pose_from_bone_rotations, posed_frames

    names, parents = list(anny.joint_names), np.asarray(anny.data.parents)
    D = anny.pose_rotations("P3", instance_shape(anny, "M"))
    G = np.empty_like(D)
    for j, p in enumerate(parents):  # parents come before their children
        G[j] = D[j] if p < 0 else G[p] @ D[j]
    pose = pose_from_bone_rotations(names, parents, G)
    assert "lowerleg01.L" in pose and "head" not in pose  # turned joints only
    want = body_instance(anny, "M", "P3")
    got = posed_frames(anny, "M", [pose, "A"], root_moves=[[0.0, 0.0, 0.0], [0.1, 0.0, -0.02]])
    assert np.abs(got[0] - want).max() < 1e-9
    assert np.abs(got[1] - body_instance(anny, "M", "A") - [0.1, 0.0, -0.02]).max() < 1e-12
    with pytest.raises(DrapeError, match="bone rotations"):
        pose_from_bone_rotations(names, parents, G[:-1])


def test_ease_drape_animation_on_the_default_body(tmp_path, anny):
    """The real body through the CLI: a top draped in A, carried to P1 (arms forward, a JSON pose from
    a file) over 4 frames;
    no frame lets more than 0.5 % of the garment through the body, the top stays on the torso, the
    files say so and the point caches hold the frames."""
    from core import workflows
    from core.cli import main
    from core.design import load_design
    from core.design.templates import template_path
    from core.pattern.io import save_pattern

    prep = workflows.prepare(load_design(template_path("top_sleeveless")))
    save_pattern(workflows.reference(prep).pattern, tmp_path / "pattern")
    out = tmp_path / "motion"
    # the poses from a file: a preset, then P1 with the left elbow bent a little more (a JSON pose)
    p1 = {"preset": "P1", "lowerarm01.L": [0.0, 0.0, 0.3]}
    (tmp_path / "poses.json").write_text(json.dumps(["A", p1]))
    argv = ["drape", str(tmp_path / "pattern"), "--out", str(out), "--between", "2", "--frames", "40", "--quiet"]
    assert main(argv + ["--animation", str(tmp_path / "poses.json")]) == 0
    rep = json.loads((out / "motion_report.json").read_text())
    assert rep["poses"] == ["A", p1] and rep["frames"] == 4 and len(rep["stretch_p95_pct"]) == 4
    assert rep["worst_penetration_pct"] <= 0.5 and len(rep["frame_seconds"]) == 3
    z = np.load(out / "motion.npz")
    pos, used = z["positions"], z["used"]
    assert pos.shape[0] == 4 and np.all(np.isfinite(pos))
    assert abs(pos[-1][used][:, 2].mean() - pos[0][used][:, 2].mean()) < 0.03
    assert np.abs(z["body_vertices"][-1] - body_instance(anny, "M", p1)).max() < 1e-5
    assert np.abs(z["body_vertices"][-1] - body_instance(anny, "M", "P1")).max() > 0.01  # the elbow too
    k, v = _pc2(out / "garment_motion.pc2")
    assert k.shape == (4, int(used.sum()), 3) and v == int(used.sum())
    # the caches and OBJs are Y-up by default, (x, z, -y) of motion.npz's core frame
    assert np.array_equal(k, to_y_up(pos[:, used]).astype(np.float32))
    head = (out / "garment_motion.obj").read_text().splitlines()[:3]
    assert "+Y up" in head[1] and head[2] == "o garment_motion"
    # a joint the body lacks is refused before the drape, naming the file's entry
    (tmp_path / "bad.json").write_text(json.dumps(["A", {"elbow": [0.0, 0.0, 1.0]}]))
    assert main(argv + ["--animation", str(tmp_path / "bad.json")]) == 2


def test_ease_drape_animation_refuses_a_bad_pose_file(tmp_path, capsys):
    from core.cli import main

    path = tmp_path / "poses.json"
    for text, words in (
        (json.dumps(["A", "Q9"]), "poses.json[1]: 'Q9' is not a pose"),
        (json.dumps(["A", {"preset": "Q9"}]), "poses.json[1]: 'Q9' is not a pose"),
        (json.dumps(["A", 3]), "poses.json[1]: expected a preset name"),
        (json.dumps({"A": 1}), "must hold a list of two poses or more"),
        ("[", "is not JSON"),
    ):
        path.write_text(text)
        argv = ["drape", str(tmp_path / "no_such_pattern"), "--out", str(tmp_path / "o"), "--animation", str(path)]
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert words in err and "--animation" in err and err.count("\n") == 1, err


def test_ease_drape_animation_adapts_the_pattern_to_the_motion(tmp_path, capsys):
    """``--adapt DESIGN``: the design's reference pattern adapted to the motion's poses (P1) within
    its stretch tolerances, then draped through A -> P1; the report names the pattern and gives
    the adaptation's residual stretch before and after, and each frame's stretch."""
    from core import workflows
    from core.cli import main
    from core.design import load_design
    from core.design.templates import template_path
    from core.pattern.io import load_pattern, save_pattern

    design = template_path("top_sleeveless")
    prep = workflows.prepare(load_design(design))
    save_pattern(workflows.reference(prep).pattern, tmp_path / "pattern")
    out = tmp_path / "motion"
    argv = ["drape", str(tmp_path / "pattern"), "--out", str(out), "--animation", "A,P1", "--between", "1"]
    assert main(argv + ["--frames", "40", "--adapt", str(design), "--quiet"]) == 0
    rep = json.loads((out / "motion_report.json").read_text())
    assert rep["pattern"] == "pattern adapted to P1" and rep["frames"] == 3
    stretch = rep["adaptation_residual_stretch_pct"]["P1"]["top"]
    assert stretch["after"] < stretch["before"]  # the adapted pattern stretches less in P1
    assert len(rep["stretch_p95_pct"]) == 3 and rep["worst_penetration_pct"] <= 0.5
    adapted = load_pattern(out / "pattern.json")
    assert adapted.mode == "adapt" and adapted.report["poses"] == ["P1"]
    # the pattern of another design is refused, naming the flag
    assert main(argv + ["--adapt", str(template_path("skirt")), "--quiet"]) == 2
    assert "--adapt: PATTERN_DIR is a pattern of the design" in capsys.readouterr().err


def _pc2(path):
    """(frames (K, V, 3) float32, V) of a Point Cache 2 file, read from its documented layout."""
    import struct

    raw = path.read_bytes()
    sig, version, n, start, rate, k = struct.unpack("<12siiffi", raw[:32])
    assert sig == b"POINTCACHE2\0" and version == 1 and (start, rate) == (1.0, 1.0)
    assert len(raw) == 32 + k * n * 12
    return np.frombuffer(raw[32:], dtype="<f4").reshape(k, n, 3), n


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--animation", "A,Q9"], "--animation: 'Q9' is not a pose"),
        (["--animation", "A"], "--animation: name two poses"),
        (["--animation", "A,P1", "--between", "-1"], "--between"),
        (["--adapt", "design.json"], "--adapt: adapts the pattern to the poses of --animation"),
        (["--animation", "A,P1", "--adapt", "no_such_design.json"], "--adapt: no design file"),
        (["--animation", "no_such_poses.json"], "--animation: cannot read no_such_poses.json"),
    ],
)
def test_ease_drape_animation_refuses_bad_flags_first(tmp_path, capsys, argv, words):
    from core.cli import main

    assert main(["drape", str(tmp_path / "no_such_pattern"), "--out", str(tmp_path / "o"), *argv]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1, err
