"""core.body.instance: one body instance from (model, size name or shape dict, pose)."""

import numpy as np

from core.body.instance import body_instance, instance_pose, instance_shape, spec_instance
from core.body.sizes import size_shape


def test_reference_pose_has_one_spelling(anny, anny_reference):
    assert instance_pose("A") is None and instance_pose(None) is None and instance_pose("T") == "T"
    ref = body_instance(anny)
    assert body_instance(anny, None, "A").tobytes() == ref.tobytes()
    assert body_instance(anny, {}, None).tobytes() == ref.tobytes()
    assert ref.tobytes() == np.asarray(anny_reference[0], dtype=np.float64).tobytes()


def test_size_names_and_json_poses(anny):
    assert instance_shape(anny, "L") == size_shape(anny, "L") and instance_shape(anny, None) is None
    pose = {"lowerarm01.L": [0.0, 0.0, 0.5]}
    got = body_instance(anny, "L", pose)
    want = anny.vertices(size_shape(anny, "L"), {"lowerarm01.L": np.array([0.0, 0.0, 0.5])})
    assert got.dtype == np.float64 and got.tobytes() == np.asarray(want, np.float64).tobytes()


def test_spec_instance(anny):
    V, F = spec_instance({"model": "anny", "shape": "M", "pose": "T"}, anny)
    assert V.tobytes() == body_instance(anny, "M", "T").tobytes() and F.dtype == np.int64
    assert F.shape == np.asarray(anny.faces).shape
