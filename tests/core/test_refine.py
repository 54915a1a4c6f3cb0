"""Stage 6 on synthetic point sets: matching and ICP refinement of a pose.

The pattern is 16 edge points on the outline of a 24 x 16 rectangle centred
on its origin, 4 px apart, with outward gradients. The image's edge points
are the same points moved by a known similarity (equation 1:
x'' = tx + a x' + b y', y'' = ty - b x' + a y'). With a = 1.25, b = 0.5 and
quarter-pixel translations every moved point is a multiple of 1/4, exact in
float32, and the gradient angles turn by -phi, phi = atan2(b, a). The
moved points are 4 * |(a, b)| = 5.4 px apart, so a start a pixel or two off
matches every point to its own image point, and the least squares of
exact matches give back the pose exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahough.core.refine import Pose, match, refine

from .conftest import make_edges


def _rectangle_points():
    pts = [(x, -8.0, 270.0) for x in (-8, -4, 0, 4, 8)]       # top: gradient up (-y)
    pts += [(x, 8.0, 90.0) for x in (-8, -4, 0, 4, 8)]        # bottom
    pts += [(-12.0, y, 180.0) for y in (-4, 0, 4)]            # left
    pts += [(12.0, y, 0.0) for y in (-4, 0, 4)]               # right
    p = np.array(pts, float)
    return (p[:, 0].astype(np.float32), p[:, 1].astype(np.float32),
            np.radians(p[:, 2]).astype(np.float32))


VX, VY, VANG = _rectangle_points()
TRUE = Pose(1.25, 0.5, 40.5, 30.25)
SHAPE = (64, 80)


def _image(pose=TRUE, keep=None, shape=SHAPE, turn_deg=0.0):
    """Image edge points: the pattern points moved by ``pose`` (only the
    indices ``keep``), their gradients turned with it (plus ``turn_deg``)."""
    x, y = pose.map(VX, VY)
    ang = VANG.astype(float) - math.atan2(pose.b, pose.a) + math.radians(turn_deg)
    keep = np.arange(len(VX)) if keep is None else np.asarray(keep)
    e = make_edges(x[keep], y[keep], ang[keep], shape)
    return e, e.index_map()


def _start(pose, dscale=1.0, dangle_deg=0.0, dx=0.0, dy=0.0):
    return Pose.from_params(pose.tx + dx, pose.ty + dy, pose.scale * dscale,
                            math.atan2(pose.b, pose.a) + math.radians(dangle_deg))


def _close(p: Pose, q: Pose, tol=1e-6):
    return (p.a, p.b, p.tx, p.ty) == pytest.approx((q.a, q.b, q.tx, q.ty), abs=tol)


def test_pose_conventions():
    p = Pose.from_params(3.0, 4.0, 2.0, math.radians(90.0))
    assert (p.a, p.b) == pytest.approx((0.0, 2.0), abs=1e-12)
    assert p.scale == pytest.approx(2.0) and p.angle == pytest.approx(90.0)
    # (1, 0) -> (3 + 0, 4 - 2): a positive angle turns counter-clockwise as displayed
    assert tuple(map(float, p.map(1.0, 0.0))) == pytest.approx((3.0, 2.0))
    assert Pose(1.0, -1e-20, 0, 0).angle == 0.0      # never 360
    assert TRUE.scale == pytest.approx(math.sqrt(1.8125))


def test_match_finds_each_points_own_edge():
    e, index = _image()
    ids, dist = match(TRUE, VX, VY, VANG, e, index, 1.5, math.radians(15), False)
    np.testing.assert_array_equal(ids, np.arange(16))
    np.testing.assert_array_equal(dist, np.zeros(16))
    # 0.6 px to the right: still each its own, 0.6 px away
    off = Pose(TRUE.a, TRUE.b, TRUE.tx + 0.6, TRUE.ty)
    ids, dist = match(off, VX, VY, VANG, e, index, 1.0, math.radians(15), False)
    np.testing.assert_array_equal(ids, np.arange(16))
    np.testing.assert_allclose(dist, 0.6, atol=1e-6)
    # ... but not within 0.5 px
    ids, dist = match(off, VX, VY, VANG, e, index, 0.5, math.radians(15), False)
    assert np.all(ids == -1) and np.all(np.isinf(dist))


def test_match_direction_tolerance_and_polarity():
    e, index = _image(turn_deg=25.0)          # every image gradient 25 degrees off
    ids, _ = match(TRUE, VX, VY, VANG, e, index, 1.5, math.radians(20), False)
    assert np.all(ids == -1)
    ids, _ = match(TRUE, VX, VY, VANG, e, index, 1.5, math.radians(30), False)
    np.testing.assert_array_equal(ids, np.arange(16))
    e, index = _image(turn_deg=180.0)         # inverted contrast
    ids, _ = match(TRUE, VX, VY, VANG, e, index, 1.5, math.radians(15), False)
    assert np.all(ids == -1)
    ids, _ = match(TRUE, VX, VY, VANG, e, index, 1.5, math.radians(15), True)
    np.testing.assert_array_equal(ids, np.arange(16))


@pytest.mark.parametrize("dscale, dangle, dx, dy", [
    (1.0, 0.0, 1.0, -1.0),          # a pixel off each way
    (1.01, 1.0, 1.0, -1.0),         # and 1 % and 1 degree
    (0.99, -1.5, -1.5, 0.5),
])
def test_refine_recovers_the_true_pose(dscale, dangle, dx, dy):
    e, index = _image()
    fit = refine(_start(TRUE, dscale, dangle, dx, dy), VX, VY, VANG, e, index)
    assert _close(fit.pose, TRUE)
    assert fit.score == 1.0 and fit.matched == 16 and fit.inside == 1.0
    assert fit.rms == pytest.approx(0.0, abs=1e-5)


def test_fix_scale_and_fix_angle_keep_those_values():
    e, index = _image()
    # the true scale kept, the rest found
    fit = refine(_start(TRUE, 1.0, 1.0, 1.0, -1.0), VX, VY, VANG, e, index, fix_scale=True)
    assert _close(fit.pose, TRUE)
    # a wrong scale is kept as given (and then the pose cannot be the truth)
    start = _start(TRUE, 1.02, 0.5, 0.5, 0.5)
    fit = refine(start, VX, VY, VANG, e, index, fix_scale=True)
    assert fit.pose.scale == pytest.approx(start.scale, abs=1e-12)
    assert fit.pose.angle == pytest.approx(TRUE.angle, abs=0.2)
    # the true angle kept, the rest found
    fit = refine(_start(TRUE, 1.01, 0.0, -1.0, 1.0), VX, VY, VANG, e, index, fix_angle=True)
    assert _close(fit.pose, TRUE)
    # a wrong angle is kept as given
    start = _start(TRUE, 1.0, 1.5, 0.5, 0.5)
    fit = refine(start, VX, VY, VANG, e, index, fix_angle=True)
    assert fit.pose.angle == pytest.approx(start.angle, abs=1e-9)
    assert fit.pose.scale == pytest.approx(TRUE.scale, abs=0.01)
    # both: a and b exactly as given, the translation found
    start = _start(TRUE, 1.0, 0.0, 1.5, -1.0)
    fit = refine(start, VX, VY, VANG, e, index, fix_scale=True, fix_angle=True)
    assert (fit.pose.a, fit.pose.b) == (start.a, start.b)
    assert _close(fit.pose, TRUE)


def test_score_counts_the_matched_share():
    # 12 of the 16 points have an image edge (the left and right sides'
    # middle points and two of the top's are missing): 0.75
    keep = [i for i in range(16) if i not in (1, 3, 11, 14)]
    e, index = _image(keep=keep)
    fit = refine(_start(TRUE, 1.0, 0.5, 1.0, 0.5), VX, VY, VANG, e, index)
    assert _close(fit.pose, TRUE)
    assert (fit.score, fit.matched, fit.inside) == (0.75, 12, 1.0)


def test_score_of_three_points_of_four():
    # 4 pattern points, 3 in the image: 0.75. With fewer than 6 matches the
    # ICP does not move the pose; the score is still measured
    sel = np.array([0, 5, 10, 13])
    vx, vy, va = VX[sel], VY[sel], VANG[sel]
    e, index = _image(keep=[0, 5, 10])
    start = Pose(TRUE.a, TRUE.b, TRUE.tx + 0.3, TRUE.ty)
    fit = refine(start, vx, vy, va, e, index)
    assert fit.pose == start
    assert (fit.score, fit.matched) == (0.75, 3)
    assert fit.rms == pytest.approx(0.3, abs=1e-6)     # each 0.3 px off


def test_inside_share_and_score_at_the_image_border():
    # a pure shift by (20, 30) into an image 30 px wide: the right side
    # (x' = 12 -> x'' = 32 > 29) falls outside, 13 of 16 points stay inside,
    # and only those have edges
    shift = Pose(1.0, 0.0, 20.0, 30.0)
    x, _ = shift.map(VX, VY)
    keep = np.flatnonzero(x <= 29)
    assert keep.size == 13
    e, index = _image(shift, keep=keep, shape=(64, 30))
    fit = refine(Pose(1.0, 0.0, 21.0, 29.5), VX, VY, VANG, e, index)
    assert _close(fit.pose, shift)
    assert (fit.score, fit.matched, fit.inside) == (13 / 16, 13, 13 / 16)


def test_shift_votes_peak_at_the_shift_that_puts_the_points_on_their_edges():
    from seahough.core import kernels as K
    e, index = _image()
    start = Pose(TRUE.a, TRUE.b, TRUE.tx - 3.0, TRUE.ty + 2.0)
    v = K.shift_votes(VX, VY, VANG, start.a, start.b, start.tx, start.ty, e.x, e.y, e.angle,
                      index, 5, math.radians(15), False)
    assert v.shape == (11, 11)
    iy, ix = np.unravel_index(int(np.argmax(v)), v.shape)
    assert (ix - 5, iy - 5) == (3, -2) and v[iy, ix] == len(VX)   # every point, once
    # a wrong polarity agrees with nothing, unless either polarity is asked for
    flipped = make_edges(e.x, e.y, e.angle + math.pi, SHAPE)
    args = (VX, VY, VANG, start.a, start.b, start.tx, start.ty, flipped.x, flipped.y,
            flipped.angle, flipped.index_map(), 5, math.radians(15))
    assert K.shift_votes(*args, False).max() == 0
    assert K.shift_votes(*args, True).max() == len(VX)


def test_the_local_vote_moves_a_pose_a_scale_step_and_a_few_pixels_off_onto_the_shape(monkeypatch):
    # ranking._shifted on a real search's context: a clean rectangle, and a
    # start a few pixels off (the box-summed vote's argmax puts it back), and
    # one also RESCALE smaller (the rescaled vote wins); a known scale never
    # tries another
    import cv2

    from seahough import Detector, Pattern
    from seahough.core import detector as D
    from seahough.core import ranking
    img = np.full((240, 320), 60, np.uint8)
    cv2.rectangle(img, (130, 100), (189, 139), 200, -1)   # 60 x 40, centre (159.5, 119.5)
    seen = {}
    real_rank = D.rank

    def spy(ctx, cands, gray, min_confidence):
        seen["ctx"] = ctx
        return real_rank(ctx, cands, gray, min_confidence)
    monkeypatch.setattr(D, "rank", spy)
    for scales in ((0.7, 1.4), (1.0, 1.0)):
        (d,) = Detector(Pattern.rectangle(60, 40), scales, (-10, 10)).detect(img)
        ctx = seen["ctx"]
        f = ctx.factor
        truth = Pose.from_params(d.x * f, d.y * f, d.scale, math.radians(d.angle))
        sub = ranking._subset(ctx)
        starts = [(Pose(truth.a, truth.b, truth.tx + 3.0, truth.ty - 2.0), 1.0)]
        if not ctx.scale_known:
            m = 1.0 / ranking.RESCALE
            starts.append((Pose(truth.a * m, truth.b * m, truth.tx - 2.0, truth.ty + 1.0), m))
        for start, _ in starts:
            moved = ranking._shifted(ctx, start, 6, sub)
            assert abs(moved.scale / truth.scale - 1) < 0.01, (scales, start, moved)
            assert math.hypot(moved.tx - truth.tx, moved.ty - truth.ty) <= 1.0, (scales, moved)
        if ctx.scale_known:   # (a scale the caller did not search is never tried)
            start = Pose(truth.a / ranking.RESCALE, truth.b / ranking.RESCALE, truth.tx, truth.ty)
            assert ranking._shifted(ctx, start, 6, sub).scale == pytest.approx(start.scale)
