"""The drape carried through a body's motion (core.drape.animate): the garment follows a moving
body without tunnelling, pinned vertices ride on it, pose in-betweens keep the limbs' length."""
from __future__ import annotations

import numpy as np
import pytest
from drape_synth import revolution_body, tube_skirt

from core.body.instance import body_instance, instance_shape
from core.drape import DrapeSolver
from core.drape.animate import drape_motion, pose_frames
from core.drape.mesh import build_cloth
from core.errors import DrapeError


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


def test_a_still_body_keeps_the_settled_drape(body):
    bv, bf = body
    r = drape_motion(tube_skirt(), [bv] * 4, bf, options={"max_frames": 60})
    assert np.abs(r.positions[-1] - r.positions[0]).max() < 0.005


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
    tip = int(np.argmax(frames[0][:, 0]))                          # the left fingertip in A
    head = anny.joints(instance_shape(anny, "M"))[list(anny.joint_names).index("upperarm01.L")]
    shoulder = int(np.argmin(np.linalg.norm(frames[0] - head, axis=1)))   # the skin at the shoulder joint
    # A -> P1 turns the shoulder only (P3 then bends the elbow): the arm keeps its length
    arm = np.array([np.linalg.norm(f[tip] - f[shoulder]) for f in frames[:5]])
    assert arm.max() - arm.min() < 0.01 * arm[0], arm
    # a linear blend of A and P1 half-way would be shorter: the in-betweens are rotations
    lin = 0.5 * (frames[0] + frames[4])
    assert np.linalg.norm(lin[tip] - lin[shoulder]) < arm[2] - 0.02
    steps = [np.linalg.norm(frames[k + 1][tip] - frames[k][tip]) for k in range(4)]
    assert max(steps) < 2.0 * min(steps)                            # even steps from A to P1
    with pytest.raises(DrapeError):
        pose_frames(anny, "M", ["A"], between=3)


def test_top_through_a_to_p1_on_the_default_body(anny):
    """The real body: a top draped in A, carried to P1 (arms forward) over 4 frames; no frame
    lets more than 0.5 % of the garment through the body, and the top stays on the torso."""
    from core import workflows
    from core.body.instance import spec_instance
    from core.design import load_design
    from core.design.templates import template_path
    prep = workflows.prepare(load_design(template_path("top_sleeveless")))
    pattern = workflows.reference(prep).pattern
    _, faces = spec_instance(pattern.body)
    frames = pose_frames(prep.body, pattern.body.get("shape"), ["A", "P1"], between=3)
    r = drape_motion(pattern, frames, faces, options={"max_frames": 40})
    assert np.all(np.isfinite(r.positions)) and r.penetration.max() <= 0.005, r.penetration
    z = [r.positions[k][r.used][:, 2].mean() for k in (0, len(frames) - 1)]
    assert abs(z[1] - z[0]) < 0.03, z
