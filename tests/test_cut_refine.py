"""core.cut.refine: conforming red-green refinement to a target edge length."""

import numpy as np
import scipy.sparse as sp
from cut_synth import triangle_areas
from test_cut_split import grid

from core.cut.refine import SPLIT_RATIO, refine


def test_refine_edge_length_area_and_embedding():
    X, F = grid(3, size=0.1)
    X = X + np.random.RandomState(1).uniform(-0.003, 0.003, X.shape) * [1, 1, 0]
    labels = np.arange(len(F)) % 2
    W = sp.identity(len(X), format="csr")
    line = np.array([0, 1, 2, 3])  # along the bottom edge
    h = 0.01
    X2, F2, L2, W2, (line2,) = refine(X, F, labels, W, [line], h)
    e = np.linalg.norm(X2[F2] - X2[np.roll(F2, -1, 1)], axis=2)
    assert e.max() <= SPLIT_RATIO * h
    # h is the target mean edge: the mean lands between 0.75 h and h
    assert 0.75 * h <= e.mean() <= h
    np.testing.assert_allclose(triangle_areas(X2, F2).sum(), triangle_areas(X, F).sum(), rtol=1e-12)
    # labels are carried: per label the area is unchanged
    for k in (0, 1):
        np.testing.assert_allclose(triangle_areas(X2, F2[L2 == k]).sum(), triangle_areas(X, F[labels == k]).sum())
    # new vertices are linear combinations of the original ones
    np.testing.assert_allclose(W2 @ X, X2, atol=1e-15)
    np.testing.assert_allclose(np.asarray(W2.sum(1)).ravel(), 1.0)
    # conforming: every interior edge has two faces, orientation kept (+z)
    key = F2.reshape(-1) * len(X2) + np.roll(F2, -1, 1).reshape(-1)
    assert len(np.unique(key)) == len(key)
    n = np.cross(X2[F2[:, 1]] - X2[F2[:, 0]], X2[F2[:, 2]] - X2[F2[:, 0]])
    assert (n[:, 2] > 0).all()
    # the line gets the midpoints of its edges, in order, and stays straight
    assert line2[0] == 0 and line2[-1] == 3
    np.testing.assert_allclose(X2[line2, 1], X2[line2, 1].mean(), atol=0.003)
    assert np.all(np.diff(X2[line2, 0]) > 0)
    for a, b in zip(line2[:-1], line2[1:]):
        assert np.any(
            np.all(np.sort(np.stack([F2, np.roll(F2, -1, 1)], 2), axis=2).reshape(-1, 2) == sorted((a, b)), axis=1)
        )


def test_refine_noop_when_short_enough():
    X, F = grid(2, size=0.01)
    W = sp.identity(len(X), format="csr")
    X2, F2, L2, W2, _ = refine(X, F, np.zeros(len(F), int), W, [], 0.1)
    np.testing.assert_array_equal(F2, F)
    assert W2.shape == W.shape


def test_delaunay_flips_fix_bad_triangles_and_keep_fixed_edges():
    from core.cut.refine import delaunay_flips

    # a strip of skinny triangles: two rows of points, triangulated with long diagonals
    xs = np.linspace(0, 1, 11)
    X = np.concatenate(
        [np.stack([xs, np.zeros(11), np.zeros(11)], 1), np.stack([xs + 0.3, np.full(11, 0.1), np.zeros(11)], 1)]
    )
    F = []
    for i in range(10):
        F += [[i, i + 1, 11 + i], [i + 1, 12 + i, 11 + i]]
    F = np.array(F)
    # a deliberately bad triangulation of one quad
    n = len(X)
    labels = np.zeros(len(F), int)
    fixed = np.array([0 * n + 1])
    F2 = delaunay_flips(X, F, labels, fixed)
    assert F2.shape == F.shape
    np.testing.assert_allclose(triangle_areas(X, F2).sum(), triangle_areas(X, F).sum())

    def min_angle(F):
        P = X[F]
        ang = []
        for k in range(3):
            u, v = P[:, (k + 1) % 3] - P[:, k], P[:, (k + 2) % 3] - P[:, k]
            ang.append(np.arccos((u * v).sum(1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)))
        return np.min(ang)

    assert min_angle(F2) > min_angle(F)
    n2 = np.cross(X[F2[:, 1]] - X[F2[:, 0]], X[F2[:, 2]] - X[F2[:, 0]])
    assert (n2[:, 2] > 0).all()
    # the fixed edge 0-1 is still there
    E = np.sort(np.stack([F2, np.roll(F2, -1, 1)], 2).reshape(-1, 2), axis=1)
    assert np.any(np.all(E == [0, 1], axis=1))
    # different labels: nothing flips across them
    F3 = delaunay_flips(X, F, np.arange(len(F)), np.zeros(0, np.int64))
    np.testing.assert_array_equal(F3, F)


def test_later_flip_rounds_retest_only_what_can_change():
    """Rounds after the first test only edges next to a flipped face or held back last
    round: the same flips as testing every edge again, over several rounds."""
    from core.cut.refine import delaunay_flips

    rng = np.random.RandomState(3)
    X, F = grid(12, size=0.2)
    X = X + rng.uniform(-0.006, 0.006, X.shape) * [1, 1, 0]
    X[:, 2] = 0.002 * np.sin(20 * X[:, 0])  # gently curved
    labels = (X[F].mean(1)[:, 0] > 0.1).astype(int)  # two panels
    W = sp.identity(len(X), format="csr")
    X2, F2, L2, _, _ = refine(X, F, labels, W, [], 0.01)
    flips = [delaunay_flips(X2, F2, L2, np.zeros(0, np.int64), max_rounds=r) for r in range(1, 5)]
    for r in range(1, 5):
        np.testing.assert_array_equal(
            flips[r - 1], delaunay_flips(X2, F2, L2, np.zeros(0, np.int64), max_rounds=r, _retest_all=True)
        )
    assert (flips[0] != F2).any(axis=1).sum() > 20
    assert (flips[1] != flips[0]).any(axis=1).sum() > 0  # round 2 still flips something


def test_flip_rounds_match_full_retesting_on_jittered_grids():
    from core.cut.refine import delaunay_flips

    flipped_late = 0
    for seed in range(20):
        rng = np.random.RandomState(seed)
        n = rng.randint(4, 14)
        X, F = grid(n, size=0.2)
        X = X + rng.uniform(-0.45, 0.45, X.shape) * (0.2 / n) * [1, 1, 0]
        labels = (rng.uniform(size=len(F)) < 0.1).astype(int)
        fixed = np.zeros(0, np.int64)
        one = delaunay_flips(X, F, labels, fixed, max_rounds=1)
        for r in (2, 3):
            got = delaunay_flips(X, F, labels, fixed, max_rounds=r)
            np.testing.assert_array_equal(got, delaunay_flips(X, F, labels, fixed, max_rounds=r, _retest_all=True))
        flipped_late += int((got != one).any(axis=1).sum())
    assert flipped_late > 50
