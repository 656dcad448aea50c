"""OBJ templates as body models, on a generated quadruped made of boxes."""

import json

import numpy as np
import pytest

from core.body.obj_model import load_obj_body, read_obj
from core.errors import BodyError

QUAD_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def box(lo, hi):
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    return corners, QUAD_FACES


def horse(up="z"):
    """A box horse facing -Y: torso, four legs, neck+head. Returns (verts, quads, part per vertex)."""
    parts = {
        "torso": ((-0.25, -0.8, 0.9), (0.25, 0.8, 1.4)),
        "leg_fl": ((0.1, -0.75, 0.0), (0.22, -0.6, 0.9)),
        "leg_fr": ((-0.22, -0.75, 0.0), (-0.1, -0.6, 0.9)),
        "leg_bl": ((0.1, 0.6, 0.0), (0.22, 0.75, 0.9)),
        "leg_br": ((-0.22, 0.6, 0.0), (-0.1, 0.75, 0.9)),
        "head": ((-0.1, -1.2, 1.3), (0.1, -0.8, 1.9)),
    }
    verts, quads, owner = [], [], []
    for name, (lo, hi) in parts.items():
        c, f = box(lo, hi)
        base = len(verts)
        verts.extend(c.tolist())
        quads.extend([tuple(base + i for i in q) for q in f])
        owner.extend([name] * len(c))
    v = np.array(verts)
    if up == "y":  # export as Y up, facing +Z: (x, y, z)_ours -> (x, z, -y)
        v = np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)
    return v, quads, owner


def write_obj(path, v, quads):
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += ["f " + " ".join(f"{i + 1}/{i + 1}" for i in q) for q in quads]
    path.write_text("# box horse\n" + "\n".join(lines) + "\n")


@pytest.fixture
def horse_files(tmp_path):
    v, quads, owner = horse()
    write_obj(tmp_path / "horse.obj", v, quads)
    V = len(v)
    owner = np.array(owner)
    # Blend shape "belly": torso bottom drops 10 cm. "long_neck": head up 20 cm.
    belly = np.zeros((V, 3))
    belly[(owner == "torso") & (v[:, 2] < 1.0), 2] = -0.1
    neck = np.zeros((V, 3))
    neck[owner == "head", 2] = 0.2
    joints = np.array([[0, 0, 1.15], [0.16, -0.68, 0.9], [-0.16, -0.68, 0.9], [0.16, 0.68, 0.9], [-0.16, 0.68, 0.9]])
    parents = np.array([-1, 0, 0, 0, 0])
    weights = np.zeros((V, 5))
    for j, part in enumerate(["torso", "leg_fl", "leg_fr", "leg_bl", "leg_br"]):
        weights[owner == part, j] = 1.0
    weights[owner == "head", 0] = 1.0
    np.savez(
        tmp_path / "horse_shapes.npz",
        names=np.array(["belly", "long_neck"]),
        deltas=np.stack([belly, neck]),
        ranges=np.array([[0, 1], [-1, 1.0]]),
    )
    np.savez(
        tmp_path / "horse_rig.npz",
        names=np.array(["belly"]),
        deltas=belly[None],
        weights=weights,
        joints=joints,
        parents=parents,
        joint_names=np.array(["root", "fl", "fr", "bl", "br"]),
    )
    (tmp_path / "horse_marks.json").write_text(
        json.dumps(
            {
                "landmarks": {"withers": 5, "nose": {"triangle": 50, "bary": [0.2, 0.3, 0.5]}},
                "regions": {"head": list(range(40, 48)), "hooves": [0, 8, 16, 24]},
            }
        )
    )
    return tmp_path, v, owner


def test_read_obj_triangulates_quads(horse_files):
    path, v, _ = horse_files
    verts, faces = read_obj(path / "horse.obj")
    np.testing.assert_allclose(verts, v, atol=1e-6)
    assert faces.shape == (6 * 6 * 2, 3)


def test_blend_shapes_are_linear_and_ranged(horse_files):
    path, v, owner = horse_files
    body = load_obj_body(path / "horse.obj", blendshapes=path / "horse_shapes.npz")
    assert body.shape_parameters() == {"belly": (0.0, 1.0, 0.0), "long_neck": (-1.0, 1.0, 0.0)}
    base = body.vertices()
    np.testing.assert_allclose(base, v, atol=1e-6)
    half = body.vertices({"belly": 0.5, "long_neck": -0.5})
    assert half[owner == "head", 2] == pytest.approx(v[owner == "head", 2] - 0.1, abs=1e-6)
    assert half[:, 2].min() == pytest.approx(0.0, abs=1e-6)  # hooves stay on the ground
    low = (owner == "torso") & (v[:, 2] < 1.0)
    np.testing.assert_allclose(half[low, 2], v[low, 2] - 0.05, atol=1e-6)
    with pytest.raises(BodyError, match=r"belly=2 is out of range \[0, 1\]"):
        body.vertices({"belly": 2})
    with pytest.raises(BodyError, match="shape.tail: unknown shape parameter; allowed: belly, long_neck"):
        body.vertices({"tail": 0.1})
    with pytest.raises(BodyError, match="needs a skeleton"):
        body.vertices(None, "P1")
    np.testing.assert_allclose(body.vertices(None, "A"), base)


def test_y_up_template_is_converted(horse_files, tmp_path):
    vy, quads, _ = horse("y")
    write_obj(tmp_path / "horse_y.obj", vy, quads)
    body = load_obj_body(tmp_path / "horse_y.obj", up="y")
    ref = load_obj_body(horse_files[0] / "horse.obj")
    np.testing.assert_allclose(body.vertices(), ref.vertices(), atol=1e-6)
    with pytest.raises(BodyError, match="allowed: z, y"):
        load_obj_body(tmp_path / "horse_y.obj", up="x")


def test_landmarks_regions_and_symmetry(horse_files):
    path, v, _ = horse_files
    body = load_obj_body(path / "horse.obj", landmarks=path / "horse_marks.json")
    verts = body.vertices()
    np.testing.assert_allclose(body.landmark_position("withers", verts), v[5])
    tri = body.faces[50]
    np.testing.assert_allclose(body.landmark_position("nose", verts), [0.2, 0.3, 0.5] @ v[tri])
    assert list(body.regions["hooves"]) == [0, 8, 16, 24]
    with pytest.raises(BodyError, match="landmark 'navel' is not defined.*known: nose, withers"):
        body.landmark_position("navel", verts)
    # Left front leg mirrors the right front leg.
    mirrored = verts[body.symmetry] * [-1, 1, 1]
    np.testing.assert_allclose(mirrored, verts, atol=1e-9)


def test_skeleton_poses_the_legs(horse_files):
    path, v, owner = horse_files
    body = load_obj_body(path / "horse.obj", blendshapes=path / "horse_rig.npz")
    assert body.joint_names == ["root", "fl", "fr", "bl", "br"]
    # Swing the front-left leg forward 90 deg about X: its hoof comes up to the hip height, in front.
    posed = body.vertices(None, {"fl": np.array([-np.pi / 2, 0, 0])})
    leg = owner == "leg_fl"
    assert posed[leg, 2].min() > 0.75 and posed[leg, 1].min() < -1.4
    np.testing.assert_allclose(posed[~leg], v[~leg], atol=1e-12)
    assert body.joints(None, {"fl": np.zeros(3)}).shape == (5, 3)
    with pytest.raises(BodyError, match="pose.tail: unknown joint.*root, fl"):
        body.vertices(None, {"tail": np.zeros(3)})


def test_bad_inputs_are_named(horse_files, tmp_path):
    path, v, _ = horse_files
    np.savez(tmp_path / "bad.npz", names=np.array(["a"]), deltas=np.zeros((1, 5, 3)))
    with pytest.raises(BodyError, match=r"'deltas' has shape \(1, 5, 3\), expected \(K, 48, 3\)"):
        load_obj_body(path / "horse.obj", blendshapes=tmp_path / "bad.npz")
    np.savez(tmp_path / "nodeltas.npz", names=np.array(["a"]))
    with pytest.raises(BodyError, match="missing key 'deltas'"):
        load_obj_body(path / "horse.obj", blendshapes=tmp_path / "nodeltas.npz")
    (tmp_path / "m.json").write_text(json.dumps({"x": 999}))
    with pytest.raises(BodyError, match=r"landmark 'x': vertex 999 out of range \[0, 48\)"):
        load_obj_body(path / "horse.obj", landmarks=tmp_path / "m.json")
    (tmp_path / "broken.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    with pytest.raises(BodyError, match="broken.obj:3: face refers to a vertex"):
        load_obj_body(tmp_path / "broken.obj")


def test_pose_axes_are_reference_axes_carried_by_the_parent(horse_files):
    """core.body.model's convention on a template's skeleton: G_leg = G_root @ R(aa)."""
    from core.body.lbs import rodrigues

    path, v, owner = horse_files
    body = load_obj_body(path / "horse.obj", blendshapes=path / "horse_rig.npz")
    J0 = body.joints()
    a1, a2 = np.array([0.0, 0.0, 0.3]), np.array([-0.6, 0.2, 0.0])
    posed = body.vertices(None, {"root": a1, "fl": a2})
    J = body.joints(None, {"root": a1, "fl": a2})
    leg = owner == "leg_fl"
    np.testing.assert_allclose(posed[leg] - J[1], (v[leg] - J0[1]) @ (rodrigues(a1) @ rodrigues(a2)).T, atol=1e-9)
