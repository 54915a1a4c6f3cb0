"""geometry.Similarity, overlap and wrap_angle on hand-computable cases.

A similarity is the 2x3 matrix [[a, b, tx], [-b, a, ty]] (equation 1 with
a = scale cos(angle), b = scale sin(angle)); as 3x3 matrices with a last row
[0, 0, 1], composing is the matrix product and inverting the matrix inverse.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahough.geometry import Similarity, angle_difference, overlap, wrap360, wrap_angle

# a, b, tx, ty: all exact in binary, so that round trips are exact
S1 = Similarity(1.5, 0.5, 10.0, -4.0)
S2 = Similarity(0.0, 2.0, 3.0, 7.25)            # scale 2, turned 90 degrees
PURE_SHIFT = Similarity(1.0, 0.0, 3.0, -2.0)


def _m3(s: Similarity) -> np.ndarray:
    return np.vstack([s.matrix, [0.0, 0.0, 1.0]])


def test_matrix_round_trips():
    for s in (S1, S2, PURE_SHIFT, Similarity.identity()):
        m = s.matrix
        np.testing.assert_array_equal(m, [[s.a, s.b, s.tx], [-s.b, s.a, s.ty]])
        assert Similarity.from_matrix(m) == s
        np.testing.assert_array_equal(Similarity.from_matrix(m).matrix, m)
    # a matrix that is not a similarity: the nearest one averages the two
    # diagonal entries and the two off-diagonal ones
    assert Similarity.from_matrix([[1.0, 0.25, 5.0], [0.0, 2.0, 6.0]]) == Similarity(
        1.5, 0.125, 5.0, 6.0)


def test_reading_and_mapping():
    assert S2.scale == 2.0 and S2.angle == 90.0
    # (1, 0) -> (tx + a, ty - b): to the right goes up on screen at +90
    assert S2.map(1.0, 0.0) == (3.0, 5.25)
    np.testing.assert_array_equal(S1.apply([[0, 0], [2, 4]]), [[10.0, -4.0], [15.0, 1.0]])
    assert Similarity(-1.0, 0.0, 0, 0).angle == 180.0
    assert Similarity(1.0, -1e-20, 0, 0).angle == 0.0          # not 360
    assert Similarity(0.0, -3.0, 0, 0).angle == 270.0
    # from_pose puts the origin at (x, y): to_pose reads it back
    s = Similarity.from_pose(100.0, 50.0, 2.0, 90.0, origin=(10.0, 10.0))
    assert s.to_pose((10.0, 10.0)) == pytest.approx((100.0, 50.0, 2.0, 90.0))
    np.testing.assert_allclose(s.apply([[11.0, 10.0]]), [[100.0, 48.0]], atol=1e-12)


def test_compose_inverse_and_power_against_matrix_products():
    np.testing.assert_allclose(S2.compose(S1).matrix, (_m3(S2) @ _m3(S1))[:2], atol=1e-12)
    np.testing.assert_allclose(S1.compose(S2).matrix, (_m3(S1) @ _m3(S2))[:2], atol=1e-12)
    np.testing.assert_allclose(S1.inverse().matrix, np.linalg.inv(_m3(S1))[:2], atol=1e-12)
    np.testing.assert_allclose(S2.inverse().matrix, np.linalg.inv(_m3(S2))[:2], atol=1e-12)
    np.testing.assert_allclose(S1.compose(S1.inverse()).matrix, np.eye(3)[:2], atol=1e-12)
    # whole powers are repeated products, 0 the identity, -1 the inverse
    m = _m3(S1)
    np.testing.assert_allclose(S1.power(2).matrix, (m @ m)[:2], atol=1e-12)
    np.testing.assert_allclose(S1.power(3).matrix, (m @ m @ m)[:2], atol=1e-10)
    np.testing.assert_allclose(S1.power(0).matrix, np.eye(3)[:2], atol=1e-12)
    np.testing.assert_allclose(S1.power(-1).matrix, np.linalg.inv(m)[:2], atol=1e-12)
    assert S1.power(1) is S1
    # a root: twice the half is the whole; the half of 2 at 90 is sqrt 2 at 45
    half = S2.power(0.5)
    assert (half.scale, half.angle) == pytest.approx((math.sqrt(2), 45.0))
    np.testing.assert_allclose(half.compose(half).matrix, S2.matrix, atol=1e-12)
    # a pure translation: t times the shift
    np.testing.assert_allclose(PURE_SHIFT.power(2.5).matrix, [[1, 0, 7.5], [0, 1, -5.0]],
                               atol=1e-12)


def test_shifted_is_the_same_transform_about_another_origin():
    # T(-o) S T(o), with T(o) the shift by +o
    o = (4.0, -6.0)
    t = lambda dx, dy: np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])
    want = t(-o[0], -o[1]) @ _m3(S1) @ t(*o)
    np.testing.assert_allclose(S1.shifted(*o).matrix, want[:2], atol=1e-12)
    # by hand: S1 maps (4, -6) to (10 + 6 - 3, -4 - 2 - 9) = (13, -15)
    assert S1.shifted(*o) == Similarity(1.5, 0.5, 9.0, -9.0)
    # the rotation about the centre of a 5x5 frame, seen from its corner
    half_turn = Similarity(-1.0, 0.0, 0.0, 0.0).shifted(-2.0, -2.0)
    assert half_turn == Similarity(-1.0, 0.0, 4.0, 4.0)


@pytest.mark.parametrize("s, want", [
    (Similarity.identity(), 1.0),
    (Similarity(1.0, 0.0, 1e-9, -1e-9), 1.0),         # a hair off is the same frame
    (Similarity(1.0, 0.0, 2.0, 0.0), 3 / 5),          # [-0.5, 4.5] moved 2 right
    (Similarity(1.0, 0.0, 2.0, -1.0), 3 / 5 * 4 / 5),  # and 1 up
    (Similarity(2.0, 0.0, 0.0, 0.0), 1 / 2 * 1 / 2),   # [-1, 9] of [-0.5, 4.5] on each axis
    (Similarity(-1.0, 0.0, 4.0, 4.0), 1.0),           # half a turn about the centre
    (Similarity(1.0, 0.0, 5.0, 0.0), 0.0),            # moved off the frame
    (Similarity(0.0, 1.0, 0.0, 4.0), 1.0),            # a quarter turn of a square
    (Similarity(1.0, 0.0, 0.3, 0.0), 1 - 0.3 / 5),    # exact, not counted on a grid
])
def test_overlap_of_a_5_by_5_frame(s, want):
    # a frame covers -0.5 .. 4.5: the share of it mapped inside, exactly (a
    # grid of samples on the border pixels gave 0.918 for the same frame
    # moved 1e-9 px: a new user's trial)
    assert overlap(s.matrix, 5, 5) == pytest.approx(want, abs=1e-9)
    assert s.overlap(5, 5) == pytest.approx(want, abs=1e-9)


def test_overlap_of_half_a_frame():
    assert overlap([[1, 0, 32], [0, 1, 0]], 64, 48) == 0.5
    assert overlap([[1, 0, 32], [0, 1, 0]], 65, 48) == pytest.approx(33 / 65)


@pytest.mark.parametrize("angle, kw, want", [
    (-1e-20, {}, 0.0),            # x % 360 would give 360.0
    (-1e-14, {}, 0.0),            # 360 - 1e-14 rounds to 360.0
    (360.0, {}, 0.0),
    (720.0, {}, 0.0),
    (-360.0, {}, 0.0),
    (359.5, {}, 359.5),
    (-90.0, {}, 270.0),
    (370.0, {}, 10.0),
    (180.0, {"low": -180.0}, -180.0),        # the signed form: [-180, 180)
    (-180.0, {"low": -180.0}, -180.0),
    (190.0, {"low": -180.0}, -170.0),
    (-1e-20, {"low": -180.0}, 0.0),
    (179.999, {"low": -180.0}, 179.999),
    (200.0, {"period": 180.0}, 20.0),        # a line's direction: [0, 180)
    (180.0, {"period": 180.0}, 0.0),
    (-1e-20, {"period": 180.0}, 0.0),        # not 180
    (-90.0, {"period": 180.0}, 90.0),
    (100.0, {"period": 180.0, "low": -90.0}, -80.0),
])
def test_wrap_angle(angle, kw, want):
    got = wrap_angle(angle, **kw)
    assert got == pytest.approx(want, abs=1e-9)
    low, period = kw.get("low", 0.0), kw.get("period", 360.0)
    assert low <= got < low + period


def test_wrap_angle_tiny_negatives_stay_in_range():
    for eps in (1e-300, 1e-20, 1e-15, 1e-14, 1e-13, 1e-12):
        for low, period in ((0.0, 360.0), (-180.0, 360.0), (0.0, 180.0)):
            got = wrap_angle(low - eps, period, low)      # just below the interval
            assert low <= got < low + period, (eps, low, period, got)
    assert wrap360(-1e-20) == 0.0 and wrap360(725.0) == 5.0
    assert angle_difference(350.0, 10.0) == -20.0 and angle_difference(10.0, 170.0, 180.0) == 20.0
