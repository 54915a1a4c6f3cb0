"""Stage 3 on tiny hand-made images: segments traced along edges.

A segment starts at a key point and follows the edge ``steps`` pixels each
way: first along (-sin a, cos a), a being the key point's gradient angle
(its end is (x1, y1)), then the other way ((x2, y2)). Each step goes to the
strongest 8-neighbour ahead that is an edge point whose gradient direction
differs from the current point's by at most the tolerance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahough.core.keypoints import find_edge_points
from seahough.core.preprocess import compute_gradients
from seahough.core.segments import trace_segments

from .conftest import square_image


def _edges(img, floor=100.0):
    e = find_edge_points(compute_gradients(img), floor)
    return e, e.index_map()


def _vertical_step(h=12, w=12, col=6):
    img = np.zeros((h, w), np.float32)
    img[:, col:] = 100.0
    return img


def test_segment_along_a_straight_edge():
    # bright from column 6: edge points at pixel column 6, x = 5.5, rows
    # 1..10 (the outermost rows are never edge points), gradient angle 0, so
    # the first side runs down (+y) and the second up
    e, index = _edges(_vertical_step())
    kp = np.array([index[5, 6]], np.int32)
    s = trace_segments(e, kp, steps=2)
    assert len(s) == 1
    assert (s.x[0], s.y[0]) == (5.5, 5.0)
    assert (s.x1[0], s.y1[0]) == (5.5, 7.0)
    assert (s.x2[0], s.y2[0]) == (5.5, 3.0)
    assert s.length[0] == 4 and s.angle[0] == 0.0
    assert s.ids[0] == kp[0] and s.magnitude[0] == 1600.0
    s3 = trace_segments(e, kp, steps=3)
    assert (s3.y1[0], s3.y2[0], s3.length[0]) == (8.0, 2.0, 6)


def test_every_key_point_of_a_straight_edge_and_the_ends():
    # rows 1 and 10 can only go one way: 2 steps, still a segment; rows 2
    # and 9 get 3 (one step towards the end), the others 4
    e, index = _edges(_vertical_step())
    kp = index[1:11, 6].astype(np.int32)
    s = trace_segments(e, kp, steps=2)
    assert s.y.tolist() == list(range(1, 11))
    assert s.length.tolist() == [2, 3, 4, 4, 4, 4, 4, 4, 3, 2]
    assert s.y1.tolist() == [3, 4, 5, 6, 7, 8, 9, 10, 10, 10]
    assert s.y2.tolist() == [1, 1, 1, 2, 3, 4, 5, 6, 7, 8]
    assert np.all(s.x1 == 5.5) and np.all(s.x2 == 5.5) and np.all(s.angle == 0.0)
    # a horizontal edge (top of a square, gradient 90 degrees): the first
    # side runs to -x
    e, index = _edges(square_image())
    s = trace_segments(e, np.array([index[6, 10]], np.int32))
    assert (s.x1[0], s.y1[0], s.x2[0], s.y2[0]) == (8.0, 5.5, 12.0, 5.5)
    assert math.degrees(s.angle[0]) == pytest.approx(90.0, abs=0.01)


def test_a_corner_stops_the_segment_within_the_tolerance():
    # square_image(): the left side's points have angle 0, the corner point
    # (6, 6) 45 degrees, the top side's 90 (see test_keypoints)
    e, index = _edges(square_image())
    kp = lambda x, y: np.array([index[y, x]], np.int32)
    # from (6, 8): down to rows 9, 10; up to row 7, then the corner differs
    # by 45 > 30 degrees: 3 steps
    s = trace_segments(e, kp(6, 8), angle_tol_deg=30.0)
    assert (s.y1[0], s.y2[0], s.length[0], s.angle[0]) == (10.0, 7.0, 3, 0.0)
    # from (6, 7): 2 steps down, none up: still a segment
    s = trace_segments(e, kp(6, 7), angle_tol_deg=30.0)
    assert (s.y1[0], s.y2[0], s.length[0]) == (9.0, 7.0, 2)
    # the corner itself: both neighbours along the edge differ by 45
    assert len(trace_segments(e, kp(6, 6), angle_tol_deg=30.0)) == 0
    # a tolerance of 50 turns the corner: from (6, 8) up to (6, 7) and the
    # corner; the mean gradient (4 x angle 0 + 1 x 45) points at
    # atan(sin 45 / (4 + cos 45))
    s = trace_segments(e, kp(6, 8), angle_tol_deg=50.0)
    c = 6 - 3 / 46
    assert (s.x2[0], s.y2[0]) == pytest.approx((c, c), abs=1e-5)
    assert s.length[0] == 4
    want = math.atan2(math.sin(math.pi / 4), 4 + math.cos(math.pi / 4))
    assert s.angle[0] == pytest.approx(want, abs=1e-5)
    # from (6, 7) at 50: up onto the corner, then on along the top side to (7, 6)
    s = trace_segments(e, kp(6, 7), angle_tol_deg=50.0)
    assert (s.x2[0], s.y2[0], s.length[0]) == (7.0, 5.5, 4)


def test_a_speck_makes_no_segment():
    # one bright pixel: its four axis neighbours are edge points (1000) whose
    # gradients point at it, 90 degrees apart from one another
    img = np.zeros((11, 11), np.float32)
    img[5, 5] = 100.0
    e, index = _edges(img, 500.0)
    assert sorted(zip(e.ix.tolist(), e.iy.tolist())) == [(4, 5), (5, 4), (5, 6), (6, 5)]
    assert len(trace_segments(e, np.arange(len(e), dtype=np.int32))) == 0


def test_max_segments_keeps_the_most_contrasted():
    # two vertical steps: 0 -> 100 at column 4 (1600) and 100 -> 150 at
    # column 12 (800), 14 edge points each
    img = np.zeros((16, 16), np.float32)
    img[:, 4:] = 100.0
    img[:, 12:] = 150.0
    e, index = _edges(img)
    kp = np.arange(len(e), dtype=np.int32)
    assert len(trace_segments(e, kp)) == 28
    s = trace_segments(e, kp, max_segments=14)
    assert len(s) == 14 and np.all(s.x == 3.5) and np.all(s.magnitude == 1600.0)
    assert np.all(np.diff(s.ids) > 0)          # in key point order
    # Segments.take
    t = s.take(np.array([0, 2]))
    assert len(t) == 2 and t.y.tolist() == s.y[[0, 2]].tolist() and t.ids.tolist() == s.ids[[0, 2]].tolist()
