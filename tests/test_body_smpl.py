"""SMPL loader, restricted unpickler and skinning, on SMPL-format files made here."""

import pickle
import sys
import textwrap

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial.transform import Rotation
from smpl_synth import stick_smpl, tube_model

from core.body.lbs import forward_kinematics, rodrigues, skin
from core.body.smpl import SMPL_TO_OURS, load_smpl
from core.body.unpickle import safe_load
from core.errors import BodyError

C = SMPL_TO_OURS


def reference_lbs(m, betas, aa_smpl):
    """Straightforward SMPL in SMPL's own frame, vertex by vertex, with scipy rotations."""
    v = m["v_template"] + np.einsum("vck,k->vc", m["shapedirs"], betas)
    jr = m["J_regressor"].toarray() if sp.issparse(m["J_regressor"]) else m["J_regressor"]
    joints = jr @ v
    R = Rotation.from_rotvec(aa_smpl).as_matrix()
    feat = np.concatenate([(R[j] - np.eye(3)).ravel() for j in range(1, len(R))])
    v = v + np.einsum("vck,k->vc", m["posedirs"], feat)
    parents = m["kintree_table"][0].astype(np.int64)
    parents[0] = -1
    world = []
    for j in range(len(R)):
        T = np.eye(4)
        T[:3, :3] = R[j]
        T[:3, 3] = joints[j] - (joints[parents[j]] if j else 0)
        world.append(T if j == 0 else world[parents[j]] @ T)
    out = np.zeros_like(v)
    for i in range(len(v)):
        acc = np.zeros(3)
        for j in range(len(R)):
            p = world[j] @ np.append(v[i] - joints[j], 1.0)
            acc += m["weights"][i, j] * p[:3]
        out[i] = acc
    return out


def test_rodrigues_matches_scipy():
    aa = np.random.default_rng(1).normal(size=(10, 3))
    aa[0] = 0.0
    np.testing.assert_allclose(rodrigues(aa), Rotation.from_rotvec(aa).as_matrix(), atol=1e-12)


def test_npz_load_and_lbs_against_reference(tmp_path):
    m = tube_model()
    path = tmp_path / "toy.npz"
    np.savez(path, **m)
    body = load_smpl(path)
    assert body.n_vertices == len(m["v_template"]) and body.faces.shape == (len(m["f"]), 3)
    assert list(body.shape_parameters()) == ["beta0", "beta1", "beta2"]
    # Frame: SMPL's +Y (up) becomes our +Z, SMPL's +Z (front) our -Y.
    rest = body.vertices({"beta0": 0.0}, {"joint1": np.zeros(3)})
    np.testing.assert_allclose(rest, m["v_template"] @ C.T, atol=1e-12)
    betas = np.array([0.5, -1.0, 2.0])
    aa_ours = np.random.default_rng(2).normal(scale=0.5, size=(4, 3))
    pose = {f"joint{j}": aa_ours[j] for j in range(4)}
    got = body.vertices({f"beta{i}": b for i, b in enumerate(betas)}, pose)
    aa_smpl = aa_ours @ C  # the same rotations seen in SMPL's frame: C^T a
    expected = reference_lbs(m, betas, aa_smpl) @ C.T
    np.testing.assert_allclose(got, expected, atol=1e-10)
    joints = body.joints({f"beta{i}": b for i, b in enumerate(betas)}, pose)
    assert joints.shape == (4, 3)


def test_skin_identity_is_rest():
    v = np.random.default_rng(3).normal(size=(20, 3))
    w = np.full((20, 2), 0.5)
    _, G = forward_kinematics(np.stack([np.eye(3)] * 2), np.array([[0, 0, 0], [0, 0, 1.0]]), np.array([-1, 0]))
    np.testing.assert_allclose(skin(v, w, G), v, atol=1e-14)


def test_bad_shape_and_pose_are_named(tmp_path):
    np.savez(tmp_path / "toy.npz", **tube_model())
    body = load_smpl(tmp_path / "toy.npz")
    with pytest.raises(BodyError, match="beta7.*allowed: beta0"):
        body.vertices({"beta7": 1.0})
    with pytest.raises(BodyError, match=r"out of range \[-5, 5\]"):
        body.vertices({"beta0": 9.0})
    with pytest.raises(BodyError, match="pose.elbow: unknown joint"):
        body.vertices(None, {"elbow": np.zeros(3)})
    with pytest.raises(BodyError, match="allowed: A, T, P1, P2, P3"):
        body.vertices(None, "Q")
    with pytest.raises(BodyError, match="landmarks are not known"):
        body.landmark_position("navel", body.vertices())


@pytest.mark.parametrize("key", ["posedirs", "kintree_table", "f"])
def test_missing_key_is_named(tmp_path, key):
    m = tube_model()
    del m[key]
    np.savez(tmp_path / "m.npz", **m)
    with pytest.raises(BodyError, match=f"missing key '{key}'"):
        load_smpl(tmp_path / "m.npz")
    with open(tmp_path / "m.pkl", "wb") as f:
        pickle.dump(m, f, protocol=2)
    with pytest.raises(BodyError, match=f"missing key '{key}'"):
        load_smpl(tmp_path / "m.pkl")


def test_wrong_shape_is_named(tmp_path):
    m = tube_model()
    m["posedirs"] = m["posedirs"][:, :, :5]
    np.savez(tmp_path / "m.npz", **m)
    with pytest.raises(BodyError, match="'posedirs' has shape"):
        load_smpl(tmp_path / "m.npz")


@pytest.fixture
def fake_chumpy(tmp_path, monkeypatch):
    """A stand-in ``chumpy`` package, as SMPL's py2-era files reference."""
    pkg = tmp_path / "fakemods" / "chumpy"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("from .ch import Ch\n")
    (pkg / "ch.py").write_text(
        textwrap.dedent("""
        class Ch(object):
            def __init__(self, x):
                self.x = x
                self._dirty_vars = set()

        class ChReduced(Ch):
            def __reduce__(self):
                return (ChReduced, (self.x,))
    """)
    )
    monkeypatch.syspath_prepend(str(tmp_path / "fakemods"))
    yield
    for name in [n for n in sys.modules if n == "chumpy" or n.startswith("chumpy.")]:
        del sys.modules[name]


def test_pkl_with_chumpy_and_sparse(tmp_path, fake_chumpy):
    import chumpy

    m = tube_model(seed=5)
    pk = dict(m)
    pk["shapedirs"] = chumpy.Ch(m["shapedirs"])
    pk["v_template"] = chumpy.Ch(m["v_template"])
    pk["posedirs"] = chumpy.Ch(m["posedirs"])
    pk["weights"] = chumpy.ch.ChReduced(m["weights"])
    pk["J_regressor"] = sp.csc_matrix(m["J_regressor"])
    pk["bs_style"] = "lbs"
    path = tmp_path / "model.pkl"
    with open(path, "wb") as f:
        pickle.dump(pk, f, protocol=2)
    body = load_smpl(path)
    np.savez(tmp_path / "model.npz", **m)
    ref = load_smpl(tmp_path / "model.npz")
    pose = {"joint2": np.array([0.3, -0.2, 0.1])}
    np.testing.assert_allclose(body.vertices({"beta1": 1.5}, pose), ref.vertices({"beta1": 1.5}, pose), atol=1e-12)
    for protocol in (0, 1, 4, 5):  # 0/1 (py2 defaults) go through copy_reg._reconstructor
        with open(path, "wb") as f:
            pickle.dump(pk, f, protocol=protocol)
        np.testing.assert_allclose(load_smpl(path).vertices(), ref.vertices(), atol=1e-12)


class _SystemPayload:
    def __init__(self, cmd):
        self.cmd = cmd

    def __reduce__(self):
        import os

        return (os.system, (self.cmd,))


class _EvalPayload:
    def __reduce__(self):
        return (eval, ("open('/nonexistent/x', 'w')",))


def test_os_system_payload_is_refused_and_never_runs(tmp_path):
    marker = tmp_path / "pwned"
    m = tube_model()
    m["v_template"] = _SystemPayload(f"touch {marker}")
    path = tmp_path / "evil.pkl"
    with open(path, "wb") as f:
        pickle.dump(m, f, protocol=2)
    with pytest.raises(BodyError, match=r"refused.*(posix|os|nt)\.system"):
        load_smpl(path)
    assert not marker.exists()


def test_other_callables_are_refused(tmp_path):
    with pytest.raises(BodyError, match=r"_?_?builtins?_?_?\.eval"):
        safe_load(pickle.dumps({"f": _EvalPayload()}, protocol=2))
    import subprocess

    class Sub:
        def __reduce__(self):
            return (subprocess.call, (["true"],))

    with pytest.raises(BodyError, match=r"subprocess\.call"):
        safe_load(pickle.dumps(Sub(), protocol=4))
    with pytest.raises(BodyError, match="not a readable model pickle"):
        safe_load(b"\x80\x02garbage")


def test_latin1_py2_pickle_with_bytes_strings():
    # A py2 str holding a non-ASCII byte (SHORT_BINSTRING) decodes as latin1.
    data = b"\x80\x02}q\x00U\x04name\x55\x02\xe9eq\x01s."
    assert safe_load(data) == {"name": "\xe9e"}


def test_pose_presets_on_smpl_skeleton(tmp_path):
    np.savez(tmp_path / "stick.npz", **stick_smpl())
    body = load_smpl(tmp_path / "stick.npz")
    assert body.joint_names[16] == "left_shoulder"
    idx = {n: i for i, n in enumerate(body.joint_names)}
    vt = body.vertices(None, "T")
    va = body.vertices()  # reference A-pose
    sh, wr = idx["left_shoulder"], idx["left_wrist"]
    # T: arm horizontal along +X (body's left); A: ~45 deg below horizontal.
    d = vt[wr] - vt[sh]
    assert d[0] > 0.5 and abs(d[2]) < 1e-9
    d = va[wr] - va[sh]
    assert np.degrees(np.arctan2(-d[2], d[0])) == pytest.approx(45, abs=1)
    dr = va[idx["right_wrist"]] - va[idx["right_shoulder"]]
    assert np.degrees(np.arctan2(-dr[2], -dr[0])) == pytest.approx(45, abs=1)
    # P1: arms forward (-Y); P2: arms up; P3: knees in front of hips, forearm forward.
    p1 = body.vertices(None, "P1")
    assert (p1[wr] - p1[sh])[1] < -0.5
    p2 = body.vertices(None, "P2")
    assert (p2[wr] - p2[sh])[2] > 0.45
    assert p2[idx["left_knee"]][1] < -0.1 and p2[idx["right_knee"]][1] > 0.1  # scissored
    p3 = body.vertices(None, "P3")
    assert p3[idx["left_knee"]][1] < -0.3 and abs(p3[idx["left_knee"]][2] - p3[idx["left_hip"]][2]) < 0.02
    assert p3[idx["left_ankle"]][2] < p3[idx["left_knee"]][2] - 0.3  # shin hangs down
    assert (p3[wr] - p3[idx["left_elbow"]])[1] < -0.2
    # Mirror map pairs left and right joints.
    assert body.symmetry[idx["left_knee"]] == idx["right_knee"]
    # Custom rotation applies on top of the A-pose.
    bent = body.vertices(None, {"left_elbow": np.array([0, 0, -np.pi / 2])})
    assert (bent[wr] - bent[idx["left_elbow"]])[1] < -0.15  # about world Z: the forearm swings forward


def test_smpl_topology_gets_all_landmarks(tmp_path):
    """A 6890-vertex SMPL-layout model (points scattered around the bones) gets every
    required landmark from the stated vertex ids and rules, left ones on the left."""
    from core.body.model import REQUIRED_LANDMARKS, REQUIRED_REGIONS

    m = stick_smpl()
    joints = m["v_template"]
    parents = m["kintree_table"][0].astype(np.int64)
    parents[0] = -1
    rng = np.random.default_rng(7)
    V = 6890
    bone = rng.integers(1, 24, size=V)
    t = rng.random(V)[:, None]
    a = rng.random(V) * 2 * np.pi
    radius = np.where(np.isin(bone, [3, 6, 9]), 0.14, 0.05)[:, None]
    ring = np.stack([np.cos(a), np.zeros(V), np.sin(a)], 1) * radius  # around SMPL's Y (up)
    v = joints[parents[bone]] * (1 - t) + joints[bone] * t + ring
    v[:24] = joints  # the regressor picks these
    weights = np.zeros((V, 24))
    weights[np.arange(V), parents[bone]] = 1.0
    weights[:24] = np.eye(24)
    faces = np.array([[i, i + 1, i + 2] for i in range(0, V - 2)])
    np.savez(
        tmp_path / "smpl6890.npz",
        v_template=v,
        f=faces,
        weights=weights,
        kintree_table=m["kintree_table"],
        J_regressor=np.eye(24, V),
        shapedirs=np.zeros((V, 3, 10)),
        posedirs=np.zeros((V, 3, 207)),
    )
    body = load_smpl(tmp_path / "smpl6890.npz")
    assert set(REQUIRED_LANDMARKS) <= set(body.landmarks)
    assert set(REQUIRED_REGIONS) <= set(body.regions)
    verts = body.vertices()
    from core.body.smpl import SMPL_VERTEX_IDS

    for name in REQUIRED_LANDMARKS:
        p = body.landmark_position(name, verts)
        if name in SMPL_VERTEX_IDS or name == "ankle_right":
            continue  # literature ids: random points on this synthetic mesh
        if name.endswith("_left"):
            assert p[0] > 0, name
        if name.endswith("_right"):
            assert p[0] < 0, name
    for name, vid in SMPL_VERTEX_IDS.items():
        if name in body.landmarks:
            np.testing.assert_allclose(body.landmark_position(name, verts), verts[vid])
    knee = body.landmark_position("knee_left", verts)
    assert knee[1] < body.joints()[4][1]  # on the front of the knee


def test_smplx_layout_body_part(tmp_path):
    """SMPL-X files: 55 joints, shape and expression directions stored together (10 + 10)."""
    m = tube_model(J=55, n_betas=20)
    np.savez(tmp_path / "SMPLX_TOY.npz", **m)
    body = load_smpl(tmp_path / "SMPLX_TOY.npz")
    assert len(body.shape_parameters()) == 10  # expression directions are not shape
    assert body.joint_names[22] == "jaw" and body.joint_names[-1] == "right_thumb3"
    # The A-pose (SMPL joint names known) seen in SMPL's frame, for the reference.
    R = body.rotations({"jaw": np.zeros(3)})
    aa_smpl = Rotation.from_matrix(np.einsum("ba,jbc,cd->jad", C, R, C)).as_rotvec()
    assert np.count_nonzero(np.abs(aa_smpl).sum(1) > 0.01) == 4  # shoulders and hips
    np.testing.assert_allclose(
        body.vertices({"beta9": 1.0}, {"jaw": np.zeros(3)}),
        reference_lbs({**m, "shapedirs": m["shapedirs"][:, :, :10]}, np.eye(10)[9], aa_smpl) @ C.T,
        atol=1e-10,
    )


def test_pose_dict_axes_are_reference_axes_carried_by_the_parent(tmp_path):
    """Same convention as Anny (core.body.model): on top of the A-pose, about the
    reference pose's world axes, carried by the parent's rotation - although SMPL's
    shoulder is already rotated (45 deg) in the A-pose."""
    from core.body.lbs import rodrigues

    np.savez(tmp_path / "stick.npz", **stick_smpl())
    body = load_smpl(tmp_path / "stick.npz")
    idx = {n: i for i, n in enumerate(body.joint_names)}
    sh, el, wr = idx["left_shoulder"], idx["left_elbow"], idx["left_wrist"]
    J0 = body.joints()
    a1, a2 = np.array([0.2, 0.4, -0.3]), np.array([0.0, 0.0, -np.pi / 2])
    J = body.joints(None, {"left_elbow": a2})
    np.testing.assert_allclose(J[wr] - J[el], rodrigues(a2) @ (J0[wr] - J0[el]), atol=1e-9)
    J = body.joints(None, {"left_shoulder": a1, "left_elbow": a2})
    np.testing.assert_allclose(J[el] - J[sh], rodrigues(a1) @ (J0[el] - J0[sh]), atol=1e-9)
    np.testing.assert_allclose(J[wr] - J[el], rodrigues(a1) @ rodrigues(a2) @ (J0[wr] - J0[el]), atol=1e-9)
    # a preset under "preset", extra rotations on top of it
    # (the axes are carried by the parent: T turns the shoulder by G = -45 deg about Y from A)
    JT = body.joints(None, "T")
    G = rodrigues(np.array([0.0, -np.pi / 4, 0.0]))
    np.testing.assert_allclose(JT[wr] - JT[el], G @ (J0[wr] - J0[el]), atol=1e-9)
    J = body.joints(None, {"preset": "T", "left_elbow": a2})
    np.testing.assert_allclose(J[wr] - J[el], G @ rodrigues(a2) @ (J0[wr] - J0[el]), atol=1e-9)
    with pytest.raises(BodyError, match="P3"):
        body.joints(None, {"preset": "sitting"})
