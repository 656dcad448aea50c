"""core.cut.grain: warp per triangle along the body part's long axis."""

import numpy as np

from core.cut.grain import body_part_axis, warp_directions


def test_axes_from_joint_names_point_up_the_part():
    names = [
        "root",
        "neck01",
        "upperarm01.L",
        "wrist.L",
        "upperarm01.R",
        "wrist.R",
        "upperleg01.L",
        "foot.L",
        "upperleg01.R",
        "foot.R",
    ]
    J = np.array(
        [
            [0, 0, 0],
            [0, 0, 0.5],
            [0.2, 0, 0.45],
            [0.5, 0, 0.1],
            [-0.2, 0, 0.45],
            [-0.5, 0, 0.1],
            [0.1, 0, 0],
            [0.12, 0, -0.8],
            [-0.1, 0, 0],
            [-0.12, 0, -0.8],
        ],
        float,
    )
    np.testing.assert_allclose(body_part_axis("torso", "left", names, J), [0, 0, 1])
    arm = body_part_axis("arm", "left", names, J)
    np.testing.assert_allclose(arm, np.array([-0.3, 0, 0.35]) / np.hypot(0.3, 0.35))
    assert body_part_axis("arm", "right", names, J)[0] > 0  # right arm: mirror
    leg = body_part_axis("leg", "left", names, J)
    assert leg[2] > 0.99
    # SMPL-style names work too
    smpl = ["pelvis", "neck", "left_shoulder", "left_wrist"]
    Js = np.array([[0, 0, 0], [0, 0, 0.5], [0.2, 0, 0.4], [0.6, 0, 0.4]], float)
    np.testing.assert_allclose(body_part_axis("arm", "left", smpl, Js), [-1, 0, 0])
    # nothing known: vertical
    np.testing.assert_allclose(body_part_axis("leg", "left"), [0, 0, 1])


def test_warp_is_unit_tangent_projection():
    rng = np.random.RandomState(0)
    X = rng.normal(size=(30, 3))
    F = np.array([[i, i + 1, i + 2] for i in range(0, 27, 3)])
    axis = np.array([0.0, 0.0, 1.0])
    w = warp_directions(X, F, axis)
    n = np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), 1.0)
    np.testing.assert_allclose((w * n).sum(1), 0.0, atol=1e-12)
    assert np.all(w @ axis > 0)
    # a triangle facing along the axis gets a fixed tangent, still unit and in-plane
    Xh = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    wh = warp_directions(Xh, np.array([[0, 1, 2]]), axis)
    np.testing.assert_allclose(np.linalg.norm(wh), 1.0)
    assert abs(wh[0, 2]) < 1e-12


def test_axis_from_region_points():
    t = np.linspace(0, 1, 50)[:, None]
    rng = np.random.RandomState(2)
    d = np.array([0.6, 0.0, -0.8])
    P = t * d + 0.02 * rng.normal(size=(50, 3))
    a = body_part_axis("arm", "left", region_points=P)
    assert a[2] > 0 and abs(a @ d) > 0.98


def _quadruped():
    """The box horse of tests/test_body_obj.py (facing -Y, head up front), as vertices and triangles."""
    from test_body_obj import horse

    v, quads, owner = horse()
    F = np.array([t for q in quads for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))])
    return v, F, np.array(owner)


def test_quadruped_warp_runs_along_the_spine():
    """No skeleton, regions or landmarks: the warp on the barrel runs along the spine (Y), not
    around the barrel (the vertical it used to take), pointing to the head end."""
    v, F, owner = _quadruped()
    axis = body_part_axis("torso", "left", landmarks={}, faces=F, X=v)
    assert abs(axis[1]) > 0.95 and axis[1] < 0, axis  # along -Y, towards the head
    barrel = np.nonzero(np.isin(F, np.nonzero(owner == "torso")[0]).all(1))[0]
    w = warp_directions(v, F[barrel], axis)
    # side and back faces of the barrel: the warp lies along the spine
    sides = np.abs(np.cross(v[F[barrel, 1]] - v[F[barrel, 0]], v[F[barrel, 2]] - v[F[barrel, 0]]))[:, 1] < 1e-9
    assert sides.sum() >= 8 and np.all(np.abs(w[sides, 1]) > 0.999)


def test_standing_body_keeps_the_vertical():
    """A standing body (the horse stood up on its tail) keeps the vertical torso axis."""
    v, F, _ = _quadruped()
    standing = np.stack([v[:, 0], v[:, 2], -v[:, 1]], 1)
    np.testing.assert_allclose(body_part_axis("torso", "left", landmarks={}, faces=F, X=standing), [0, 0, 1])
