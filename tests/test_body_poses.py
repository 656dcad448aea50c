"""Pose presets and arbitrary joint rotations of the default body, checked geometrically."""

import numpy as np
import pytest

from core.body import POSE_PRESETS
from core.body.lbs import rodrigues
from core.body.poses import rotation_between
from core.errors import BodyError


@pytest.fixture(scope="module")
def body(anny):
    return anny


def _joints(body, pose, shape=None):
    return {n: p for n, p in zip(body.joint_names, body.joints(shape, pose))}


def _angle(a, b):
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    return np.degrees(np.arccos(np.clip(a @ b, -1.0, 1.0)))


def _torso_down(J):
    """Unit vector down the torso axis (neck base -> pelvis)."""
    d = J["root"] - J["neck01"]
    return d / np.linalg.norm(d)


def _upper_arm(J, s):
    return J["lowerarm01" + s] - J["upperarm01" + s]


def _thigh(J, s):
    return J["lowerleg01" + s] - J["upperleg01" + s]


def _shin(J, s):
    return J["foot" + s] - J["lowerleg01" + s]


def test_rotation_between():
    rng = np.random.default_rng(0)
    for _ in range(20):
        a, b = rng.normal(size=3), rng.normal(size=3)
        R = rotation_between(a, b)
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.allclose(R @ (a / np.linalg.norm(a)), b / np.linalg.norm(b), atol=1e-12)
    a = np.array([0.0, 0.0, 1.0])
    assert np.allclose(rotation_between(a, -a) @ a, -a)


def test_a_pose_is_reference(body):
    J = _joints(body, "A")
    assert np.array_equal(body.vertices(None, "A"), body.vertices())
    for s in (".L", ".R"):
        # Arms about 45 degrees below horizontal: 45 degrees from the torso's down axis.
        assert 35 < _angle(_upper_arm(J, s), _torso_down(J)) < 55
        # Legs slightly apart.
        assert 2 < _angle(_thigh(J, s), _torso_down(J)) < 12
    assert J["foot.L"][0] - J["foot.R"][0] > J["upperleg01.L"][0] - J["upperleg01.R"][0]


def test_t_pose_arms_horizontal(body):
    J = _joints(body, "T")
    for s, sx in ((".L", 1), (".R", -1)):
        assert abs(_angle(_upper_arm(J, s), _torso_down(J)) - 90) < 3
        assert _upper_arm(J, s)[0] * sx > 0


def test_p1_arms_forward_legs_spread(body):
    J = _joints(body, "P1")
    down = _torso_down(J)
    for s, sx in ((".L", 1), (".R", -1)):
        arm = _upper_arm(J, s)
        assert abs(_angle(arm, down) - 90) < 3  # shoulder flexion 90
        assert _angle(arm, [0, -1, 0]) < 5  # pointing forward
        spread = _thigh(J, s)
        assert 15 < _angle(spread, down) < 25 and spread[0] * sx > 0


def test_p2_arms_up_scissored_legs(body):
    J = _joints(body, "P2")
    down = _torso_down(J)
    for s in (".L", ".R"):
        assert abs(_angle(_upper_arm(J, s), down) - 160) < 3

    def sagittal(v):  # hip flexion angle in the sagittal plane, + forward
        return np.degrees(np.arctan2(-v[1], -v[2]))

    assert abs(sagittal(_thigh(J, ".L")) - 30) < 3  # left hip flexed
    assert abs(sagittal(_thigh(J, ".R")) + 30) < 3  # right hip extended


def test_p3_sitting_elbows_bent(body):
    J = _joints(body, "P3")
    down = _torso_down(J)
    for s in (".L", ".R"):
        hip = _angle(-down, _thigh(J, s))  # trunk vs thigh: 90 when seated
        knee = _angle(-_thigh(J, s), _shin(J, s))  # thigh vs shin: 90 when seated
        elbow = _angle(-_upper_arm(J, s), J["wrist" + s] - J["lowerarm01" + s])
        assert abs(hip - 90) < 8, hip
        assert abs(knee - 90) < 5, knee
        assert abs(elbow - 90) < 5, elbow
        forearm = J["wrist" + s] - J["lowerarm01" + s]
        assert _angle(forearm, [0, -1, 0]) < 5  # forearms in front
        assert _angle(_upper_arm(J, s), down) < 15  # upper arms down along the torso


@pytest.mark.parametrize("shape", [None, {"weight": 0.95, "height": 0.2}, {"gender": 0.0, "age": 0.9}])
def test_presets_hold_for_other_shapes(body, shape):
    J = _joints(body, "T", shape)
    assert abs(_angle(_upper_arm(J, ".L"), _torso_down(J)) - 90) < 3
    J = _joints(body, "P3", shape)
    assert abs(_angle(-_thigh(J, ".L"), _shin(J, ".L")) - 90) < 5


def test_posing_keeps_rigid_parts(body):
    """Edges whose two vertices hang rigidly on one bone keep their length in every pose."""
    W = body.data.weights
    rigid = W.max(axis=1) > 0.9999
    bone = W.argmax(axis=1)
    F = body.faces
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e = e[rigid[e[:, 0]] & rigid[e[:, 1]] & (bone[e[:, 0]] == bone[e[:, 1]])]
    assert e.shape[0] > 1000
    rest = body.vertices()
    L0 = np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)
    for pose in POSE_PRESETS:
        v = body.vertices(None, pose)
        L = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
        assert np.abs(L - L0).max() < 1e-9, pose
    # The body moves, though: presets are not the rest pose.
    assert np.abs(body.vertices(None, "P3") - rest).max() > 0.3


def test_arbitrary_rotation_turns_the_child_about_the_joint(body):
    J0 = _joints(body, None)
    aa = np.array([0.0, 0.0, 1.2])
    J = _joints(body, {"lowerarm01.L": aa})
    R = rodrigues(aa)
    assert np.allclose(J["lowerarm01.L"], J0["lowerarm01.L"], atol=1e-12)
    assert np.allclose(J["wrist.L"] - J["lowerarm01.L"], R @ (J0["wrist.L"] - J0["lowerarm01.L"]), atol=1e-9)
    assert np.allclose(J["wrist.R"], J0["wrist.R"], atol=1e-12)


def test_rotation_on_top_of_preset(body):
    J = _joints(body, {"preset": "T", "upperleg01.L": [np.pi / 2, 0.0, 0.0]})
    # A quarter turn about +X swings the left thigh from down to +Y (backwards) ...
    assert _angle(_thigh(J, ".L"), [0, 1, 0]) < 8
    # ... and the preset still holds.
    assert abs(_angle(_upper_arm(J, ".L"), _torso_down(J)) - 90) < 3


def test_shoulder_girdle_shares_arm_raise(body):
    J0, J = _joints(body, "A"), _joints(body, "P2")
    # Raising the arms lifts the shoulder joint a little (scapula/clavicle), not the neck.
    assert 0.005 < J["upperarm01.L"][2] - J0["upperarm01.L"][2] < 0.08
    assert np.allclose(J["neck01"], J0["neck01"])


def test_bad_pose_names_list_allowed(body):
    with pytest.raises(BodyError, match="P3"):
        body.vertices(None, "sitting")
    with pytest.raises(BodyError, match="lowerarm01.L"):
        body.vertices(None, {"elbow_left": [0, 0, 1]})
    with pytest.raises(BodyError, match="axis-angle"):
        body.vertices(None, {"lowerarm01.L": [0, 1]})
    with pytest.raises(BodyError, match="preset"):
        body.vertices(None, 42)


def test_rotation_axes_are_reference_axes_carried_by_the_parent(body):
    """The convention of core.body.model: G_bone = G_parent @ R(aa), axes of the reference
    pose's world frame - not the bone's own local frame (which differs: Anny's forearm
    bones are not aligned with the world axes)."""
    J0 = _joints(body, None)
    a1, a2 = np.array([0.3, -0.5, 0.4]), np.array([0.0, 0.7, -0.2])
    J = _joints(body, {"upperarm02.L": a1, "lowerarm01.L": a2})
    R1, R2 = rodrigues(a1), rodrigues(a2)
    np.testing.assert_allclose(
        J["lowerarm01.L"] - J["upperarm02.L"], R1 @ (J0["lowerarm01.L"] - J0["upperarm02.L"]), atol=1e-9
    )
    np.testing.assert_allclose(
        J["wrist.L"] - J["lowerarm01.L"], R1 @ R2 @ (J0["wrist.L"] - J0["lowerarm01.L"]), atol=1e-9
    )
    # the bone's local frame is not the world frame, so the two conventions differ here
    U = body.data.reference_orientations[body.joint_names.index("lowerarm01.L")]
    assert np.abs(U - np.eye(3)).max() > 0.1
    J_local = R1 @ U.T @ R2 @ U @ (J0["wrist.L"] - J0["lowerarm01.L"])
    assert np.linalg.norm(J_local - (J["wrist.L"] - J["lowerarm01.L"])) > 0.01
