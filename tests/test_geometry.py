import math
import re

import numpy as np
import pytest

import seahough
from seahough.geometry import (apply_matrix, compose, invert_matrix, matrix_to_pose,
                               pose_to_matrix, solve_segment_pair)


def _eq1(p, dx, dy, rho, phi_deg):
    c, s = math.cos(math.radians(phi_deg)), math.sin(math.radians(phi_deg))
    return (dx + rho * (c * p[0] + s * p[1]), dy + rho * (-s * p[0] + c * p[1]))


def test_equation5_round_trip_recovers_random_poses(rng):
    for _ in range(200):
        dx, dy = rng.uniform(-500, 500, 2)
        rho = rng.uniform(0.2, 5)
        phi = rng.uniform(0, 360)
        p1, p2 = rng.uniform(-100, 100, (2, 2))
        q1, q2 = _eq1(p1, dx, dy, rho, phi), _eq1(p2, dx, dy, rho, phi)
        got = solve_segment_pair(p1, p2, q1, q2)
        assert got[0] == pytest.approx(dx, abs=1e-6)
        assert got[1] == pytest.approx(dy, abs=1e-6)
        assert got[2] == pytest.approx(rho, rel=1e-9)
        assert abs((got[3] - phi + 180) % 360 - 180) < 1e-6


def test_paper_sign_of_equation5_would_flip_the_pose():
    # as printed (denominator -A^2-B^2) the scale-rotation vector changes sign:
    # rho cos/sin come out negated, i.e. the angle is off by 180 degrees
    p1, p2 = (0.0, 0.0), (10.0, 0.0)
    q1, q2 = _eq1(p1, 5, 7, 2.0, 30.0), _eq1(p2, 5, 7, 2.0, 30.0)
    dx, dy, rho, phi = solve_segment_pair(p1, p2, q1, q2)
    assert phi == pytest.approx(30.0)
    a, b = p1[0] - p2[0], p1[1] - p2[1]
    c, d = q1[0] - q2[0], q1[1] - q2[1]
    printed = np.array([[a, b], [b, -a]]) @ [c, d] / (-a * a - b * b)
    assert math.degrees(math.atan2(printed[1], printed[0])) % 360 == pytest.approx(210.0)


def test_positive_angle_turns_counter_clockwise_as_displayed():
    m = pose_to_matrix(0, 0, 1.0, 90.0)
    # a point to the right of the origin goes up (y decreases) on screen
    assert apply_matrix(m, [[1, 0]])[0] == pytest.approx([0, -1])


def test_matrix_pose_round_trip_and_warpaffine_convention(rng):
    import cv2
    img = np.zeros((21, 31), np.float32)
    img[10, 20] = 1.0  # a dot at pattern pixel (20, 10)
    m = pose_to_matrix(50.0, 40.0, 1.0, 0.0, origin=(15.0, 10.0))
    out = cv2.warpAffine(img, m, (100, 80))
    y, x = np.unravel_index(np.argmax(out), out.shape)
    assert (x, y) == (55, 40)
    for _ in range(20):
        x, y, s, a = rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(0.3, 3), rng.uniform(0, 360)
        o = tuple(rng.uniform(0, 40, 2))
        got = matrix_to_pose(pose_to_matrix(x, y, s, a, o), o)
        assert got[:3] == pytest.approx((x, y, s))
        assert abs((got[3] - a + 180) % 360 - 180) < 1e-9
    m2 = pose_to_matrix(3, 4, 1.5, 20)
    assert compose(invert_matrix(m2), m2) == pytest.approx(np.array([[1, 0, 0], [0, 1, 0]]))


def test_degenerate_segment_is_refused():
    with pytest.raises(ValueError):
        solve_segment_pair((1, 1), (1, 1), (0, 0), (1, 0))


def test_bad_arguments_of_similarity_are_parameter_errors():
    """A Python user's trial: an array where a Similarity was expected, a
    Parquet table's flat matrix, a 2x2 matrix, a zero scale's inverse and
    3-column points raised AttributeError, IndexError, ZeroDivisionError
    and ValueError from inside the package."""
    from seahough.geometry import Similarity

    s = Similarity.from_pose(10.0, 5.0, 2.0, 30.0)
    assert s.compose(s.matrix) == s.compose(s)                      # a 2x3 matrix: taken
    assert Similarity.from_matrix(s.matrix.ravel().tolist()) == Similarity.from_matrix(s.matrix)
    assert Similarity.from_matrix(np.vstack([s.matrix, [0, 0, 1]])) == Similarity.from_matrix(
        s.matrix)
    for call, words in ((lambda: Similarity.from_matrix(np.eye(2)), "shape (2, 2)"),
                        (lambda: Similarity.from_matrix(np.eye(3) * 2), "shape (3, 3)"),
                        (lambda: Similarity.from_columns([1, 2]), "shape (2,)"),
                        (lambda: Similarity(0.0, 0.0, 1.0, 1.0).inverse(), "scale 0"),
                        (lambda: s.apply([[1.0, 2.0, 3.0]]), "shape (1, 3)"),
                        (lambda: s.compose("s"), "got str")):
        with pytest.raises(seahough.ParameterError, match=re.escape(words)):
            call()
    # (as before: no points, and OpenCV's (N, 1, 2) contours)
    assert s.apply([]).shape == (0, 2)
    contour = np.array([[[1.0, 2.0]], [[3.0, 4.0]]])
    assert np.array_equal(s.apply(contour), s.apply(contour[:, 0]))
