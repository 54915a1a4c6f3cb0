"""Stage 2 on tiny hand-made inputs: edge points (non-maximum suppression),
the histogram threshold, the N strongest key points, the index map."""

from __future__ import annotations

import math

import numpy as np
import pytest

import cv2

from seahough.core import keypoints as KP
from seahough.core.kernels import band_gradients
from seahough.core.keypoints import (contrast_threshold, edge_points_near, edge_points_near_image,
                                     find_edge_points, local_contrast, select_keypoints)
from seahough.core.preprocess import compute_gradients

from .conftest import make_edges, square_image

# The bright square of square_image() covers pixels 6..13 (level 100), so
# its borders lie at 5.5 and 13.5. Along a straight side the step of 100
# gives 1600 on both pixels beside it (the outer and the inner one). The
# suppression keeps a pixel that is >= its neighbour before it and > the one
# after it (along +x / +y), so of the two equal pixels the later one stays:
# the left and top sides keep their inner pixel (6), the right and bottom
# sides their outer one (14); the parabola through (1600, 1600, 0) then puts
# each at the border, half a pixel off. At a corner pixel of the square the
# two sides' kernels give gx = gy = +-1300 (10 + 3 of the 16 weights see the
# square), 1300 sqrt 2 = 1838, the largest in its neighbourhood; along its
# diagonal it has 300 sqrt 2 outside and 0 inside, so the parabola's vertex
# is 0.5 * 300 / (300 - 2 * 1300) = 3/46 px outwards on each axis.
_C = 3.0 / 46.0
_SIDE = list(range(7, 13))


def _expected_square():
    """{(ix, iy): (x, y, angle_deg, magnitude)} of every edge point."""
    d = {}
    for k in _SIDE:
        d[(k, 6)] = (k, 5.5, 90.0, 1600.0)      # top: bright below
        d[(k, 14)] = (k, 13.5, 270.0, 1600.0)   # bottom
        d[(6, k)] = (5.5, k, 0.0, 1600.0)       # left: bright to the right
        d[(14, k)] = (13.5, k, 180.0, 1600.0)   # right
    m = 1300 * math.sqrt(2)
    d[(6, 6)] = (6 - _C, 6 - _C, 45.0, m)
    d[(13, 6)] = (13 + _C, 6 - _C, 135.0, m)
    d[(13, 13)] = (13 + _C, 13 + _C, 225.0, m)
    d[(6, 13)] = (6 - _C, 13 + _C, 315.0, m)
    return d


def test_edge_points_of_a_square():
    g = compute_gradients(square_image())
    e = find_edge_points(g, 100.0)
    want = _expected_square()
    got = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(e.ix, e.iy))}
    assert sorted(got) == sorted(want) and len(e) == 28
    for key, (x, y, ang, mag) in want.items():
        k = got[key]
        assert (e.x[k], e.y[k]) == pytest.approx((x, y), abs=1e-4), key
        # cv2.phase is accurate to about 0.3 degrees
        assert math.degrees(e.angle[k]) == pytest.approx(ang, abs=0.3), key
        assert e.magnitude[k] == pytest.approx(mag, rel=1e-6)
        # the exact unit gradient
        assert (e.nx[k], e.ny[k]) == pytest.approx(
            (math.cos(math.radians(ang)), math.sin(math.radians(ang))), abs=1e-6)
    assert e.shape == (20, 20)


def test_min_gradient_is_inclusive_and_leaves_the_corners():
    g = compute_gradients(square_image())
    assert len(find_edge_points(g, 1600.0)) == 28            # 1600 >= 1600
    corners = find_edge_points(g, 1600.5)                     # only 1838 remains
    assert sorted(zip(corners.ix.tolist(), corners.iy.tolist())) == [
        (6, 6), (6, 13), (13, 6), (13, 13)]
    assert len(find_edge_points(g, 1839.0)) == 0


def test_mask_limits_the_points_but_not_the_comparison():
    g = compute_gradients(square_image())
    mask = np.zeros((20, 20), np.uint8)
    mask[9, :] = 1
    e = find_edge_points(g, 100.0, mask)
    assert sorted(zip(e.ix.tolist(), e.iy.tolist())) == [(6, 9), (14, 9)]
    # pixel (5, 9) has 1600 too, but its neighbour (6, 9), outside the mask,
    # wins the tie: nothing is kept
    only = np.zeros((20, 20), np.uint8)
    only[9, 5] = 1
    assert len(find_edge_points(g, 100.0, only)) == 0


def test_edge_points_near_a_point():
    g = compute_gradients(square_image())
    # radius 1: a 3x3 square around (6, 9), i.e. rows 8..10 of the left side
    e = edge_points_near(g, [6.0], [9.0], 1.0, 100.0)
    assert sorted(zip(e.ix.tolist(), e.iy.tolist())) == [(6, 8), (6, 9), (6, 10)]
    # radius 1.5 rounds up to 2: rows 7..11; a mask keeps rows 10 and 11
    mask = np.zeros((20, 20), bool)
    mask[10:, :] = True
    e = edge_points_near(g, [6.2], [8.6], 1.5, 100.0, mask)
    assert sorted(zip(e.ix.tolist(), e.iy.tolist())) == [(6, 10), (6, 11)]
    # points outside the image select nothing
    assert len(edge_points_near(g, [-5.0], [40.0], 2.0, 100.0)) == 0


def test_band_gradients_are_opencvs_where_asked_and_zero_elsewhere():
    # integer grey levels (every photo's): the same numbers as cv2.Scharr with
    # replicated borders and numpy's magnitude, the image's borders included
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (37, 53)).astype(np.float32)
    need = (rng.uniform(size=img.shape) < 0.3).astype(np.uint8)
    need[0, :] = need[-1, :] = need[:, 0] = need[:, -1] = 1
    gx, gy, mag = band_gradients(img, need)
    g = compute_gradients(img)
    on = need > 0
    for mine, theirs in ((gx, g.gx), (gy, g.gy), (mag, g.magnitude)):
        assert np.array_equal(mine[on], theirs[on])
        assert not mine[~on].any()


@pytest.mark.parametrize("levels", ["integer", "fractional"])
def test_edges_in_a_band_are_those_of_the_whole_images_gradients(monkeypatch, levels):
    # the full-resolution finish of a frame: few points in a large image, so
    # its gradients are taken in the band only; the same points as from the
    # whole image's gradients (positions within float rounding on fractional levels)
    rng = np.random.default_rng(5)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (300, 420)).astype(np.float32), (0, 0), 1.5)
    if levels == "integer":
        img = np.rint(img)
    px, py = rng.uniform(0, 419, 40), rng.uniform(0, 299, 40)
    calls = []
    monkeypatch.setattr(KP.K, "band_gradients",
                        lambda *a: calls.append(1) or band_gradients(*a))
    banded = edge_points_near_image(img, px, py, 2.0, 5.0)
    assert calls, "the band path was not taken"
    whole = edge_points_near(compute_gradients(img), px, py, 2.0, 5.0)
    key = lambda e: np.lexsort((e.ix, e.iy))
    a, b = key(banded), key(whole)
    assert len(banded) == len(whole) > 100
    assert np.array_equal(banded.ix[a], whole.ix[b]) and np.array_equal(banded.iy[a], whole.iy[b])
    for name in ("x", "y", "angle", "magnitude"):
        u, v = getattr(banded, name)[a], getattr(whole, name)[b]
        if levels == "integer":
            assert np.array_equal(u, v), name
        else:
            assert np.allclose(u, v, rtol=1e-5, atol=1e-4), name


def test_index_map():
    g = compute_gradients(square_image())
    e = find_edge_points(g, 100.0)
    m = e.index_map()
    assert m.shape == (20, 20) and m.dtype == np.int32
    assert (m >= 0).sum() == 28
    np.testing.assert_array_equal(m[e.iy, e.ix], np.arange(28))
    # hand-made points, and only some of them
    h = make_edges([1.2, 3.0, 0.4], [0.0, 2.4, 1.6], [0, 0, 0], (3, 4))
    np.testing.assert_array_equal(h.index_map(), [[-1, 0, -1, -1],
                                                  [-1, -1, -1, -1],
                                                  [2, -1, -1, 1]])
    np.testing.assert_array_equal(h.index_map(np.array([1])), [[-1, -1, -1, -1],
                                                               [-1, -1, -1, -1],
                                                               [-1, -1, -1, 1]])


# ---------------------------------------------------------------- threshold
def test_contrast_threshold_on_a_known_histogram():
    # values 1, 1, 2, 2, 2, 3, 3, 3, 3, 4 in 4 bins over [0, 4]: bin = value,
    # 4 clipped into the top bin: counts [0, 2, 3, 5]; from the top 5, 8, 10.
    v = np.array([1, 1, 2, 2, 2, 3, 3, 3, 3, 4], np.float32)
    assert contrast_threshold(v, 4, bins=4) == 3.0      # the top bin (5 >= 4)
    assert contrast_threshold(v, 5, bins=4) == 3.0      # exactly 5
    assert contrast_threshold(v, 6, bins=4) == 2.0      # needs the next bin: 8
    assert contrast_threshold(v, 9, bins=4) == 1.0      # 10
    # 0..99 in 10 bins of 9.9: the top bin holds 90..99 (10 values)
    assert contrast_threshold(np.arange(100, dtype=np.float32), 10, bins=10) == pytest.approx(89.1)
    # no more values than asked for: all of them
    assert contrast_threshold(v, 10) == 1.0
    assert contrast_threshold(np.empty(0, np.float32), 3) == 0.0
    # all zero: the threshold is 0 (every point kept)
    assert contrast_threshold(np.zeros(20, np.float32), 5, bins=4) == 0.0


def _line_of_points(values):
    n = len(values)
    return make_edges(np.arange(n), np.zeros(n), np.zeros(n), (1, n), magnitude=values)


def test_select_keypoints_picks_the_n_strongest():
    e = _line_of_points([5, 1, 9, 3, 7, 2, 8])
    np.testing.assert_array_equal(select_keypoints(e, 3), [2, 4, 6])    # 9, 7, 8
    np.testing.assert_array_equal(select_keypoints(e, 1), [2])
    np.testing.assert_array_equal(select_keypoints(e, 7), np.arange(7))
    np.testing.assert_array_equal(select_keypoints(e, 50), np.arange(7))
    # ``strength`` ranks instead of the magnitude: 9 (id 1) and 8 (id 5)
    s = np.array([5, 9, 1, 7, 3, 8, 4], np.float32)
    np.testing.assert_array_equal(select_keypoints(e, 2, s), [1, 5])
    assert select_keypoints(_line_of_points([]), 5).size == 0


def test_select_keypoints_cuts_ties_at_the_threshold_bin():
    # 1024 bins over [0, 4]: the four 3s share bin 768 and the 4 is in the
    # top bin; counted from the top, 4 points are first reached at bin 768
    # (threshold 3.0), which holds 5 points: the cut leaves 4, the 4 among them
    e = _line_of_points([1, 1, 2, 2, 2, 3, 3, 3, 3, 4])
    assert contrast_threshold(e.magnitude, 4) == 3.0
    ids = select_keypoints(e, 4)
    assert len(ids) == 4 and 9 in ids and set(ids.tolist()) <= {5, 6, 7, 8, 9}
    assert np.all(np.diff(ids) > 0)       # sorted ids


def test_local_contrast_divides_by_the_mean_around_plus_the_image_mean():
    # a 3x3 magnitude image, 9 in the middle: a 3x3 box mean is 1 there, and
    # the image mean (the floor) is 1 too. Reflected borders: the window of
    # the corner (0, 0) holds the middle once as well.
    mag = np.zeros((3, 3), np.float32)
    mag[1, 1] = 9.0
    e = make_edges([1.0, 0.0], [1.0, 0.0], [0.0, 0.0], (3, 3), magnitude=[9.0, 3.0])
    np.testing.assert_allclose(local_contrast(e, mag, 3), [4.5, 1.5], rtol=1e-6)
    np.testing.assert_allclose(local_contrast(e, mag, 31), [4.5, 1.5], rtol=1e-6)  # capped at 3
    # a uniform gradient of 10: any point of magnitude m has m / (10 + 10)
    flat = np.full((5, 5), 10.0, np.float32)
    e = make_edges([2.0, 4.0], [2.0, 0.0], [0.0, 0.0], (5, 5), magnitude=[10.0, 30.0])
    np.testing.assert_allclose(local_contrast(e, flat, 3), [0.5, 1.5], rtol=1e-6)


# --- key points on long borders (Config.chain_length) -------------------------

def _box_on_texture(seed=0):
    """A 120 x 80 box (grey step 40) on strong fine texture (specks of +-90)."""
    import cv2

    rng = np.random.default_rng(seed)
    img = np.full((240, 320), 100.0, np.float32)
    specks = rng.random((240, 320)) < 0.04
    img[specks] += rng.choice([-90.0, 90.0], specks.sum())
    img = cv2.GaussianBlur(img, (0, 0), 0.7)
    img[80:160, 100:220] += 40.0
    border = np.zeros(img.shape, bool)
    border[78:83, 98:223] = border[157:162, 98:223] = True
    border[78:162, 98:103] = border[78:162, 217:222] = True
    return img, border


def test_chain_lengths_join_one_border_and_break_at_turns():
    from seahough.core import kernels as K
    from seahough.core.keypoints import CHAIN_TOLERANCE, find_edge_points
    from seahough.core.preprocess import compute_gradients
    import math

    img = np.zeros((40, 80), np.float32)
    img[:, 40:] = 100          # one straight border, 40 px long
    img[5:7, 5:7] = 100        # a speck
    e = find_edge_points(compute_gradients(img), 20)
    c = K.chain_lengths(e.ix, e.iy, e.angle, e.index_map(), math.radians(CHAIN_TOLERANCE))
    on_border = np.abs(e.x - 39.5) < 1.5
    assert c[on_border].min() >= 38                # the whole border is one chain
    assert c[e.x < 20].max() <= 8                  # the speck's edges stay short
    # directions that differ by more than the tolerance are not joined
    c0 = K.chain_lengths(e.ix, e.iy, e.angle, e.index_map(), math.radians(0.001))
    assert c0[on_border].max() >= 38               # a straight border: one direction
    rng = np.random.default_rng(1)
    turned = (e.angle + rng.uniform(0.7, 1.0, len(e)).astype(np.float32)
              * np.where(np.arange(len(e)) % 2, 1, -1).astype(np.float32)) % np.float32(2 * np.pi)
    c1 = K.chain_lengths(e.ix, e.iy, turned.astype(np.float32), e.index_map(),
                         math.radians(CHAIN_TOLERANCE))
    assert c1[on_border].max() <= 3                # every other point turned by 40-57 deg


def test_chain_weighting_moves_key_points_from_texture_to_the_border():
    import seahough
    from seahough.core.features import extract_features

    shares = {}
    for chain in (0.0, 8.0):
        vals = []
        for seed in range(3):
            img, border = _box_on_texture(seed)
            f = extract_features(img, 1.0, seahough.Config(chain_length=chain, n_keypoints=300))
            kp = f.keypoints
            vals.append(border[f.edges.iy[kp], f.edges.ix[kp]].mean())
        shares[chain] = float(np.mean(vals))
    assert shares[8.0] > shares[0.0] + 0.1, shares


def test_long_borders_decide_the_weighting():
    import seahough
    from seahough import sim

    P = seahough.Pattern
    assert P.rectangle(60, 40).has_long_borders() and P.circle(10).has_long_borders()
    img, mask = sim.marker("cross", 120)
    assert P.from_image(img).has_long_borders()
    texture = np.random.default_rng(0).uniform(0, 255, (120, 120)).astype(np.uint8)
    tex = P.from_image(texture)
    assert not tex.has_long_borders()
    frame = P.from_frame(np.random.default_rng(1).uniform(0, 255, (120, 160)).astype(np.uint8))
    assert not frame.has_long_borders()
    # a search for texture ranks the image's key points by contrast alone
    assert seahough.Detector(tex)._features_config().chain_length == 0.0
    assert seahough.Detector(P.rectangle(60, 40))._features_config().chain_length == 8.0
    with pytest.raises(seahough.ParameterError, match="chain_length"):
        seahough.Config(chain_length=-1)
