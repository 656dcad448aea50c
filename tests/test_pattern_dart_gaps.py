"""The solver's gap step between a dart's legs (core.pattern.optimizer.dart_gaps, issue 30), on a small system."""

import numpy as np
import pytest
import scipy.sparse as sp

from core.pattern.optimizer import dart_gaps as D
from core.pattern.optimizer.factor import SymmetricFactor
from core.pattern.optimizer.seams import SeamSide


def _sides(n_pairs=5, length=0.1):
    """The two sides of a dart of ``n_pairs`` + 1 vertices each (apex shared), ids 0..n_pairs-1 (a), n_pairs..
    (b), apex last: (sides, pairs, darts) for dart_legs."""
    k = n_pairs
    a = np.r_[np.arange(k), 2 * k]
    b = np.r_[np.arange(k, 2 * k), 2 * k]
    rest = np.full(k, length / k)
    return [SeamSide(0, a, rest, np.zeros(k, int)), SeamSide(0, b, rest, np.zeros(k, int))], [(0, 1)], [0]


def _legs(n_pairs=5, length=0.1):
    """The legs of :func:`_sides` and the number of unknowns."""
    return D.dart_legs(*_sides(n_pairs, length)), 2 * n_pairs + 1


def _positions(k, width):
    """A dart along +y towards the apex at (0, 0.1): leg a on the left (x < 0), b on the right, ``width`` (k,)
    the signed gap a - b across the dart at each pair (negative: crossed)."""
    y = np.linspace(0.0, 0.1, k + 1)[:-1]
    U = np.zeros((2 * k + 1, 2))
    U[:k] = np.c_[-0.5 * width, y]
    U[k : 2 * k] = np.c_[0.5 * width, y]
    U[2 * k] = (0.0, 0.1)
    return U


def _base(n):
    """An SPD system matrix on n unknowns: a chain Laplacian plus a diagonal."""
    L = sp.diags([-np.ones(n - 1), 2.0 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]) + sp.eye(n)
    return SymmetricFactor(L.tocsc())


def test_the_legs_and_their_bound():
    legs, n = _legs()
    assert legs.a.tolist() == [0, 1, 2, 3, 4] and legs.b.tolist() == [5, 6, 7, 8, 9]
    assert legs.next_a[-1] == legs.next_b[-1] == 10  # the apex ends the last pair's axis
    # the bound: MIN_OPENING times the distance to the apex along the legs
    assert legs.min_gap == pytest.approx(D.MIN_OPENING * np.array([0.1, 0.08, 0.06, 0.04, 0.02]))


def test_legs_apart_are_left_as_they_are():
    legs, n = _legs()
    U = _positions(5, np.full(5, 0.01))  # 1 cm apart everywhere: above the bound
    assert D.GapCorrection(legs).correct(_base(n), U) is U
    # a gap measured on the leg a's side of the dart: positive here
    assert np.all(D.leg_gaps(legs, U) > 0)


def test_crossed_legs_are_pushed_to_their_bound():
    legs, n = _legs()
    width = np.array([0.01, 0.004, -0.003, -0.002, 0.0005])  # crossed in the middle
    U = _positions(5, width)
    fixed = D.GapCorrection(legs).correct(_base(n), U)
    gap = D.leg_gaps(legs, fixed)
    short = width < legs.min_gap
    # the short pairs reach their bound within the correction's stiffness (w = 100 x the mean diagonal)
    assert np.all(gap[short] >= 0.95 * legs.min_gap[short]), (gap, legs.min_gap)
    assert np.all(gap > 0)
    # along the dart nothing is pushed: the legs' mean y positions stay put within a tenth of a mm
    assert np.abs(fixed[:10, 1] - U[:10, 1]).max() < 1e-4
    assert np.all(np.isfinite(fixed))


def test_no_darts_no_legs():
    legs = D.dart_legs([], [], [])
    assert len(legs.a) == 0
    U = np.zeros((3, 2))
    assert D.GapCorrection(legs).correct(_base(3), U) is U


def test_a_deep_crossing_opens_at_most_a_legs_edge_an_iteration():
    legs, n = _legs()
    assert legs.edge == pytest.approx(0.02)
    width = np.array([-0.05, -0.05, -0.04, -0.02, -0.01])  # crossed by up to 5 cm
    U = _positions(5, width)
    gap = D.leg_gaps(legs, D.GapCorrection(legs).correct(_base(n), U))
    raised = gap - width
    assert np.all(raised > 0) and np.all(raised <= D.STEP_CAP * legs.edge * 1.001)


def test_legs_the_step_closes_again_go_back_to_their_bound():
    """The cap counts from the previous iterate's gap: legs apart there that the global step crosses by 5 cm
    are put back near their bound in one correction (capped from the step's gap alone, they opened by half a
    leg's edge an iteration and the next step closed them again: the four-dart blouse in P1)."""
    legs, n = _legs()
    width = np.array([-0.05, -0.05, -0.04, -0.02, -0.01])
    U, before = _positions(5, width), _positions(5, np.full(5, 0.01))
    gap = D.leg_gaps(legs, D.GapCorrection(legs).correct(_base(n), U, before))
    # opened by 1-5 cm to within the correction's stiffness of the bound (a 5 cm push: 86-91 % of it)
    assert np.all(gap >= 0.8 * legs.min_gap), (gap, legs.min_gap)
    # a deep crossing in the previous iterate too still opens by at most the cap
    gap = D.leg_gaps(legs, D.GapCorrection(legs).correct(_base(n), U, _positions(5, width)))
    assert np.all(gap - width > 0) and np.all(gap - width <= D.STEP_CAP * legs.edge * 1.001)


def test_the_correction_solves_the_matrix_it_is_given():
    """A stiffened matrix (the collapse guard's) is factorised with the legs' term in place of the last one:
    the correction of a guarded step follows its stiffness (on the solver's own matrix it stretched the
    guarded triangles: the four-dart blouse on women:XL diverged)."""
    legs, n = _legs()
    gaps = D.GapCorrection(legs)
    U = _positions(5, np.array([0.01, 0.004, -0.003, -0.002, 0.0005]))
    soft = _base(n)
    held = np.r_[np.full(5, 50.0), np.zeros(n - 5)]  # leg a's vertices stiffened
    stiff = SymmetricFactor((soft.matrix + sp.diags(held)).tocsc())
    moved = lambda V: np.abs(V - U).max(axis=1)
    a = gaps.correct(soft, U)
    b = gaps.correct(stiff, U)
    assert gaps._held[0] is stiff.matrix
    # the stiffened leg moves less, the other one more
    assert moved(b)[:5].max() < 0.5 * moved(a)[:5].max() and moved(b)[5:10].max() > moved(a)[5:10].max()
    # a factorisation refactorised in place (the same object, a new matrix) is factorised again
    again = soft.with_values(soft.matrix.data, reuse=stiff)
    assert again is stiff and np.allclose(gaps.correct(again, U), a)


def test_crossed_legs_are_told_from_legs_apart():
    """GapCorrection.crossed: the solver's check for the extra rounds (issue 30): an edge of one leg touching
    or crossing one of the other leg, the two edges that meet at the apex left out."""
    legs, n = _legs()
    gaps = D.GapCorrection(legs)
    assert not gaps.crossed(_positions(5, np.full(5, 0.02)))  # apart; they meet at the apex only
    assert gaps.crossed(_positions(5, np.array([0.02, 0.02, -0.01, 0.02, 0.02])))  # crossed in the middle
    U = _positions(5, np.full(5, 0.02))
    U[3] = (0.02, 0.07)  # leg a's fourth vertex hooked over to leg b's side: its edge meets leg b
    assert gaps.crossed(U)
    assert not D.GapCorrection(D.dart_legs([], [], [])).crossed(np.zeros((3, 2)))


def test_a_solve_refactorises_its_own_corrected_matrix_in_place():
    """A solve's holder keeps one corrected factorisation, refactorised in place for each new matrix of the
    same pattern (the collapse guard's renewals): the same corrections as a factorisation made anew, and one
    factorisation from scratch per pattern and per solve instead of one per matrix (review of issue 30)."""
    legs, n = _legs()
    U = _positions(5, np.array([0.01, 0.004, -0.003, -0.002, 0.0005]))
    soft = _base(n)
    gaps = D.GapCorrection(legs)
    holder = {}
    outs = []
    for k in range(4):
        held = np.r_[np.full(5, 10.0 * k), np.zeros(n - 5)]
        base = soft.with_values((soft.matrix + sp.diags(held)).tocsc().data) if k else soft
        outs.append(gaps.correct(base, U, holder=holder))
        # the same bits as a correction that factorises this matrix from scratch
        assert np.array_equal(outs[-1], D.GapCorrection(legs).correct(base, U))
        assert holder["held"][0] is base.matrix
    assert gaps.factorised == 2  # the pattern's kept one, then the solve's own (refactorised twice)
    # the stiffer leg a moves less each time: the values followed the matrix
    moved = [np.abs(V - U)[:5].max() for V in outs]
    assert moved == sorted(moved, reverse=True)
    # a second solve (its own holder) reuses the pattern's analysis: one factorisation of its own
    gaps.correct(soft.with_values(soft.matrix.data * 2.0), U, holder={})
    assert gaps.factorised == 3


def test_legs_not_sewn_equal_are_named():
    """unequal_legs: the darts whose legs differ by more than 0.1 mm (issue 30), named by piece and dart, the
    largest first; a dart within the tolerance is not named."""
    legs, n = _legs()
    assert D.LEGS_REFUSED == pytest.approx(1e-4)
    U = _positions(5, np.full(5, 0.02))
    assert D.unequal_legs(legs, U) == []
    named = D.dart_legs(*_sides(), names=[("skirt.back", "skirt.back_dart")])
    assert named.names == (("skirt.back", "skirt.back_dart"),)
    for shift, over in ((0.00009, False), (0.0003, True)):
        V = U.copy()
        V[0, 1] -= shift  # leg a's first vertex pulled away from the apex along the dart: leg a longer
        found = D.unequal_legs(named, V)
        assert bool(found) is over, found
        if over:
            (panel, dart, d), *_ = found
            assert (panel, dart) == ("skirt.back", "skirt.back_dart") and d == pytest.approx(shift, rel=1e-3)
    # without names a dart is numbered
    V = U.copy()
    V[0, 1] -= 0.001
    assert D.unequal_legs(legs, V)[0][:2] == ("", "dart 1")
