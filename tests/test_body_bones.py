"""core.body.lbs.bone_tails: the bones of a rig drawn from joint positions (the add-on's Add Rig)."""

import numpy as np
import pytest

from core.body.lbs import bone_tails
from core.errors import BodyError


def test_bone_tails_follow_the_limb_and_stub_the_ends():
    # root, spine up, two arms from the spine (one with a hand), a twist joint on the elbow
    heads = np.array(
        [[0, 0, 1.0], [0, 0, 1.4], [0.3, 0, 1.4], [-0.3, 0, 1.4], [0.6, 0, 1.4], [0.6, 0, 1.401], [0.3, 0.0, 1.1]]
    )
    parents = np.array([-1, 0, 1, 1, 2, 4, 2])
    t = bone_tails(heads, parents)
    assert t.shape == heads.shape
    assert np.allclose(t[0], heads[1]) and np.allclose(t[1], heads[2])  # toward the first child
    assert np.allclose(t[2], heads[4])  # the first child, not the later one (6)
    assert np.allclose(t[3], heads[3] + [-0.03, 0, 0])  # an end: along its parent's bone (1 -> 3)
    # 4's only child (5) is 1 mm away: too close to aim at, so 4 is an end along 2 -> 4
    assert np.allclose(t[4], heads[4] + [0.03, 0, 0])
    assert np.allclose(t[5], heads[5] + [0, 0, 0.03])  # along 4 -> 5 (straight up)
    assert np.allclose(t[6], heads[6] + [0, 0, -0.03])  # along 2 -> 6 (down)
    # a lone root, and a joint on its parent: stub up +z; the stub length is a parameter
    assert np.allclose(bone_tails([[1, 2, 3.0]], [-1], stub=0.1), [[1, 2, 3.1]])
    assert np.allclose(bone_tails([[0, 0, 0.0], [0, 0, 0.0]], [-1, 0])[1], [0, 0, 0.03])
    assert np.all(np.linalg.norm(t - heads, axis=1) > 0.005)  # every bone has a length


def test_bone_tails_checks_its_arrays():
    with pytest.raises(BodyError, match="heads has shape"):
        bone_tails(np.zeros((2, 3)), [-1, 0, 1])
    with pytest.raises(BodyError, match="parent"):
        bone_tails(np.zeros((2, 3)), [-1, 1])
