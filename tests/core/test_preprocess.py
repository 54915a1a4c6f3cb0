"""Stage 1 on tiny hand-made images: working scale and Scharr gradients.

OpenCV's Scharr x kernel is [[-3, 0, 3], [-10, 0, 10], [-3, 0, 3]] (applied
as a correlation: right minus left), y the same transposed (below minus
above); their weights sum to 16 per side, so a step of 1 grey level gives 16
(Config.min_gradient's unit). Borders are replicated.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from seahough.config import Config
from seahough.core.blanks import blank_border, caption_boxes, fill_blank_border, fill_blanks, find_blanks
from seahough.core.preprocess import (choose_factor, colour_metric, compute_gradients,
                                      scale_image)


def _direction(g, y, x):
    """Gradient direction at a pixel, degrees in [0, 360), y down."""
    return math.degrees(math.atan2(float(g.gy[y, x]), float(g.gx[y, x]))) % 360.0


# ---------------------------------------------------------------- gradients
def test_vertical_step_of_one_level_gives_16_on_the_two_pixels_beside_it():
    img = np.zeros((8, 8), np.float32)
    img[:, 4:] = 1.0
    g = compute_gradients(img)
    # columns 3 (last dark) and 4 (first bright) see 0 on one side, 1 on the other
    expected = np.zeros((8, 8), np.float32)
    expected[:, 3:5] = 16.0
    np.testing.assert_array_equal(g.magnitude, expected)
    np.testing.assert_array_equal(g.gx, expected)            # brighter to the right: +x
    np.testing.assert_array_equal(g.gy, np.zeros((8, 8)))    # rows all alike (borders too)
    assert _direction(g, 5, 3) == 0.0


@pytest.mark.parametrize("flip, axis, want_deg", [
    (False, "y", 90.0),     # bright below: the gradient points down (+y)
    (True, "x", 180.0),     # bright on the left: points to -x
    (True, "y", 270.0),     # bright above: points up (-y)
])
def test_step_direction_follows_the_brighter_side(flip, axis, want_deg):
    img = np.zeros((8, 8), np.float32)
    if axis == "x":
        img[:, :4] = 50.0 if flip else 0.0
        img[:, 4:] = 0.0 if flip else 50.0
    else:
        img[:4, :] = 50.0 if flip else 0.0
        img[4:, :] = 0.0 if flip else 50.0
    g = compute_gradients(img)
    y, x = (5, 3) if axis == "x" else (3, 5)
    assert g.magnitude[y, x] == 16 * 50
    assert _direction(g, y, x) == want_deg


def test_ramp_interior_border_and_corner():
    # f(x, y) = 2x + 3y: inside, each side differs by 2 * 2 (x) or 2 * 3 (y)
    # levels: gx = 16 * 4 = 64, gy = 16 * 6 = 96. On the replicated border a
    # side sees the same pixel, so the difference halves: gx = 32 at x = 0.
    yy, xx = np.mgrid[0:6, 0:7].astype(np.float32)
    g = compute_gradients(2 * xx + 3 * yy)
    assert g.gx[3, 3] == 64.0 and g.gy[3, 3] == 96.0
    assert g.magnitude[3, 3] == pytest.approx(math.hypot(64, 96), rel=1e-6)
    assert _direction(g, 3, 3) == pytest.approx(math.degrees(math.atan2(3, 2)), abs=1e-4)
    assert g.gx[3, 0] == 32.0 and g.gx[3, 6] == 32.0
    assert g.gy[0, 3] == 48.0 and g.gy[5, 3] == 48.0
    assert (g.gx[0, 0], g.gy[0, 0]) == (32.0, 48.0)


def test_diagonal_step_points_at_45_degrees():
    # img = 1 where x + y >= 8. At (4, 4) (on it) and (3, 4) (just off it)
    # each side of either kernel holds one 0 and two 1s weighted 10 and 3,
    # or the mirror image: gx = gy = 13. One pixel further (2, 4): only the
    # corner weight 3 differs.
    yy, xx = np.mgrid[0:10, 0:10]
    img = (xx + yy >= 8).astype(np.float32)
    g = compute_gradients(img)
    for x, y in ((4, 4), (3, 4), (5, 3)):
        assert (g.gx[y, x], g.gy[y, x]) == (13.0, 13.0)
        assert _direction(g, y, x) == pytest.approx(45.0, abs=1e-6)
    assert (g.gx[4, 2], g.gy[4, 2]) == (3.0, 3.0)
    assert g.magnitude[4, 6] == 0.0


def test_gradients_of_a_downscaled_step_and_the_coordinate_maps():
    # 8x8, bright from column 4, halved: 2x2 blocks average to a 4x4 image
    # bright from column 2, whose step (height 100) gives 1600 at columns 1, 2
    img = np.zeros((8, 8), np.float32)
    img[:, 4:] = 100.0
    g = compute_gradients(img, 0.5)
    assert g.image.shape == (4, 4) and (g.fx, g.fy) == (0.5, 0.5) and g.factor == 0.5
    assert g.full_shape == (8, 8)
    np.testing.assert_array_equal(g.magnitude[:, 1:3], np.full((4, 2), 1600.0))
    assert g.magnitude[:, [0, 3]].max() == 0.0
    # working pixel 0 covers full pixels 0 and 1: its centre is at 0.5
    assert g.to_full(0.0, 0.0) == (0.5, 0.5)
    assert g.to_full(1.5, 3.0) == (3.5, 6.5)    # the step, between columns 3 and 4
    assert g.to_work(3.5, 6.5) == (1.5, 3.0)


# ---------------------------------------------------------------- scale
def test_scale_image_averages_blocks_and_reports_factors_per_axis():
    g = np.arange(24, dtype=np.float32).reshape(4, 6)
    small, fx, fy = scale_image(g, 0.5)
    # the mean of each 2x2 block: (a + a+1 + a+6 + a+7) / 4 = a + 3.5
    np.testing.assert_allclose(small, [[3.5, 5.5, 7.5], [15.5, 17.5, 19.5]], atol=1e-5)
    assert (fx, fy) == (0.5, 0.5)
    # 5x3 at 0.5: round(2.5) = 2 columns, round(1.5) = 2 rows (half to even),
    # so the factors actually applied differ from 0.5 and per axis
    small, fx, fy = scale_image(np.zeros((3, 5), np.float32), 0.5)
    assert small.shape == (2, 2) and (fx, fy) == (2 / 5, 2 / 3)
    # never below one pixel
    small, fx, fy = scale_image(np.zeros((1, 3), np.float32), 0.1)
    assert small.shape == (1, 1) and (fx, fy) == (1 / 3, 1.0)


def test_scale_image_at_full_size_is_the_same_array():
    g = np.ones((3, 3), np.float32)
    small, fx, fy = scale_image(g, 0.9995)    # >= 0.999: not resampled
    assert small is g and (fx, fy) == (1.0, 1.0)


@pytest.mark.parametrize("shape, kw, want", [
    ((480, 640), {}, 0.5),                 # longest side 640 -> 320
    ((640, 480), {}, 0.5),                 # portrait: the same
    ((240, 320), {}, 1.0),                 # already the target size
    ((100, 200), {}, 1.0),                 # never enlarged
    ((1000, 4000), {}, 0.08),              # 320 / 4000
    # a 40 px pattern must keep 24 working px: 24 / 40 = 0.6 > 0.5
    ((480, 640), {"pattern_extent": 40.0}, 0.6),
    # ... and at scale 0.5 it spans 20 px: 24 / 20 = 1.2, capped at 1
    ((480, 640), {"pattern_extent": 40.0, "min_scale": 0.5}, 1.0),
    # a large pattern does not change the target scale: 24 / 200 < 0.5
    ((480, 640), {"pattern_extent": 200.0}, 0.5),
])
def test_choose_factor(shape, kw, want):
    assert choose_factor(shape, Config(), **kw) == pytest.approx(want, abs=1e-12)


def test_choose_factor_settings_of_the_config():
    assert choose_factor((480, 640), Config(downscale=0.3), pattern_extent=40.0) == 0.3
    assert choose_factor((480, 640), Config(target_size=160)) == 0.25
    assert choose_factor((480, 640), Config(min_pattern_size=48), pattern_extent=40.0) == 1.0


# ---------------------------------------------------------------- colour
def test_colour_gradient_of_a_step_in_one_channel_is_its_own_over_root_3():
    # red alone steps by 30: its Scharr derivative 16 * 30 = 480, averaged
    # over three channels in the tensor: 480 / sqrt(3); pointing to the red
    bgr = np.zeros((8, 8, 3), np.float32)
    bgr[:, 4:, 2] = 30.0
    g = compute_gradients(bgr)
    assert g.magnitude[5, 3] == pytest.approx(480 / math.sqrt(3), rel=1e-6)
    assert g.magnitude[5, 0] == 0.0
    assert _direction(g, 5, 3) == pytest.approx(0.0, abs=1e-4)
    bgr = bgr[:, ::-1].copy()                   # red on the left: points to -x
    assert _direction(compute_gradients(bgr), 5, 4) == pytest.approx(180.0, abs=1e-4)


def test_colour_gradient_takes_the_direction_of_most_change_and_its_sign():
    # blue rises by 10 to the right, red by 40 downwards: the colour changes
    # most along y, whose derivative (red's) is positive: 90 degrees; the
    # grey image would mix both (0.114 * 10 along x, 0.299 * 40 along y)
    yy, xx = np.mgrid[0:9, 0:9].astype(np.float32)
    bgr = np.dstack([10 * (xx >= 4), np.zeros_like(xx), 40 * (yy >= 4)]).astype(np.float32)
    g = compute_gradients(bgr)
    assert _direction(g, 3, 3) == pytest.approx(90.0, abs=1e-3)
    # the largest eigenvalue of the tensor [[160^2, 0], [0, 640^2]] / 3
    assert g.magnitude[3, 3] == pytest.approx(640 / math.sqrt(3), rel=1e-6)
    flipped = compute_gradients(bgr[::-1].copy())
    assert _direction(flipped, 5, 3) == pytest.approx(270.0, abs=1e-3)


@pytest.mark.parametrize("factor, equalize", [(1.0, False), (0.5, False), (1.0, True), (0.5, True)])
def test_three_equal_channels_give_the_grey_gradients(factor, equalize):
    rng = np.random.default_rng(5)
    grey = cv2.GaussianBlur(rng.uniform(0, 255, (40, 60)).astype(np.float32), (0, 0), 2.0)
    g = compute_gradients(grey, factor, equalize)
    c = compute_gradients(np.dstack([grey] * 3), factor, equalize)
    assert c.image.shape == g.image.shape and c.full_shape == (40, 60) == g.full_shape
    assert (c.fx, c.fy) == (g.fx, g.fy)
    np.testing.assert_allclose(c.image, g.image, atol=1e-3)
    np.testing.assert_allclose(c.magnitude, g.magnitude, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(c.gx, g.gx, rtol=1e-4, atol=1e-2)
    np.testing.assert_allclose(c.gy, g.gy, rtol=1e-4, atol=1e-2)


# ------------------------------------------------- colour weighting (Config.colour_boost)
def _textured_with_a_colour_step(seed=0):
    """Grey texture (spread 20 levels, every channel alike) and, right of
    x = 30, red 30 up and green 30 down: a step the texture does not make."""
    rng = np.random.default_rng(seed)
    t = rng.normal(0, 20, (60, 60)).astype(np.float32)
    img = np.dstack([t, t, t]) + 100
    img[:, 30:, 1] -= 30
    img[:, 30:, 2] += 30
    return img


def test_colour_metric_keeps_the_texture_direction_and_amplifies_the_others():
    img = _textured_with_a_colour_step()
    gx = cv2.Scharr(img, cv2.CV_32F, 1, 0)
    gy = cv2.Scharr(img, cv2.CV_32F, 0, 1)
    w = colour_metric(gx, gy, 4.0)
    grey = np.ones(3) / math.sqrt(3)
    assert w.shape == (3, 3) and np.allclose(w, w.T, atol=1e-6)
    assert float(grey @ w @ grey) == pytest.approx(1.0, abs=0.02)     # texture: its units
    gains = np.linalg.eigvalsh(w.astype(np.float64))
    assert gains.max() == pytest.approx(4.0, rel=1e-4)                  # capped
    assert gains.min() == pytest.approx(1.0, abs=0.02)
    assert colour_metric(gx, gy, 1.0) is None                           # 1: off
    assert colour_metric(np.zeros_like(gx), np.zeros_like(gy), 4.0) is None   # flat image


def test_weighed_colours_raise_a_colour_step_over_the_texture_and_keep_its_sign():
    img = _textured_with_a_colour_step()
    plain = compute_gradients(img)
    weighed = compute_gradients(img, metric=4.0)
    assert plain.metric is None and weighed.metric.shape == (3, 3)
    step = (slice(5, 55), slice(29, 31))
    texture = (slice(5, 55), slice(5, 25))
    ratio = lambda g: float(np.median(g.magnitude[step]) / np.median(g.magnitude[texture]))
    assert ratio(weighed) > 2.0 * ratio(plain)
    # a given metric is used as it is (the full-resolution strips take the working one's)
    again = compute_gradients(img, metric=weighed.metric)
    np.testing.assert_array_equal(again.magnitude, weighed.magnitude)
    np.testing.assert_array_equal(again.metric, weighed.metric)
    # BGRA: the alpha channel is not a colour
    bgra = np.dstack([img, np.full(img.shape[:2], 255, np.float32)])
    np.testing.assert_array_equal(compute_gradients(bgra, metric=4.0).magnitude,
                                  weighed.magnitude)
    # grey images: no weighting
    assert compute_gradients(img[:, :, 0], metric=4.0).metric is None


def test_weighed_colours_keep_the_sign_of_the_channels_as_they_are():
    # blue 14 down, green and red 12 up across x = 30, on grey texture: as
    # they are, the channels that rise win (sum d |d| > 0: the gradient points
    # +x); weighed, the colour part of the step (blue against the others) is
    # amplified and blue would win. The sign stays that of the channels.
    rng = np.random.default_rng(1)
    t = rng.normal(0, 20, (60, 60)).astype(np.float32)
    t[:, 24:36] = 0.0                       # (flat about the step)
    img = np.dstack([t, t, t]) + 100
    img[:, 30:] += np.array([-14.0, 12.0, 12.0], np.float32)
    step = (slice(5, 55), slice(29, 31))
    for metric in (None, 4.0):
        g = compute_gradients(img, metric=metric)
        assert np.mean(g.gx[step] > 0) > 0.95, metric
    # (what a sign taken from the weighed channels would say: blue falls most)
    w = compute_gradients(img, metric=4.0).metric
    d = w @ np.array([-14.0, 12.0, 12.0])
    assert float(np.sum(d * np.abs(d))) < 0


def _textured(h=120, w=160, seed=0):
    return np.random.default_rng(seed).uniform(40, 220, (h, w)).astype(np.float32)


@pytest.mark.parametrize("side", ["left", "right", "top", "bottom"])
def test_a_letterbox_bar_on_any_side_is_a_blank_border(side):
    img = _textured()
    noise = np.random.default_rng(1).uniform(0, 2.5, img.shape).astype(np.float32)  # JPEG-like
    sl = {"left": np.s_[:, :7], "right": np.s_[:, -7:], "top": np.s_[:9], "bottom": np.s_[-9:]}
    img[sl[side]] = noise[sl[side]]
    want = {"left": (9, 0, 160, 120), "right": (0, 0, 151, 120), "top": (0, 11, 160, 120),
            "bottom": (0, 0, 160, 109)}
    assert blank_border(img) == want[side]
    out = fill_blank_border(img)
    x0, y0, x1, y1 = want[side]
    assert out.shape == img.shape
    assert (out[y0:y1, x0:x1] == img[y0:y1, x0:x1]).all()        # the content untouched
    edge = {"left": out[:, :x0] == out[:, x0:x0 + 1], "right": out[:, x1:] == out[:, x1 - 1:x1],
            "top": out[:y0] == out[y0:y0 + 1], "bottom": out[y1:] == out[y1 - 1:y1]}
    assert edge[side].all()                                      # its lines repeated outwards


def test_what_is_not_a_blank_border():
    img = _textured()
    assert blank_border(img) == (0, 0, 160, 120)
    assert fill_blank_border(img) is img                         # (no copy)
    # a dark border with texture (vignetting) is content
    dark = img.copy()
    dark[:, :20] *= 0.05
    assert blank_border(dark) == (0, 0, 160, 120)
    # a flat grey band is blank; colour images are judged on their mean
    band = np.dstack([img, img, img])
    band[:24] = (40, 45, 42)
    assert blank_border(band) == (0, 26, 160, 120)
    # more than half the image blank: no border taken (a frame mostly empty)
    most = img.copy()
    most[:, :42] = 0
    most[:, -42:] = 0
    assert blank_border(most) == (0, 0, 160, 120)
    flat = np.full((120, 160), 90, np.float32)
    assert blank_border(flat) == (0, 0, 160, 120)


def test_a_drawn_scene_s_flat_background_is_no_border():
    """A flat background level with the picture beside it (a drawn scene, a
    rectangle near its edge) is the scene's: nothing filled, the object's
    edge near the frame stays where it is."""
    img = np.full((120, 160), 60, np.float32)
    img[12:50, 30:90] = 200                       # 12 rows from the top
    assert blank_border(img) == (0, 0, 160, 120)
    assert fill_blank_border(img) is img


def test_a_large_object_on_a_flat_ground_and_open_water_are_no_border():
    """Flat lines at an edge that are the scene's own: a drawn object wider
    than half the image (its edges in the outer quarter) on a flat ground
    (a review found all four of its edges filled away), and the flat open
    water at the top of a pool photo, fading downwards, broken by a board's
    top edge (a RoboSub photo: 41 rows of it were taken for a band)."""
    img = np.full((120, 160), 60, np.float32)
    img[12:100, 20:150] = 200
    assert blank_border(img) == (0, 0, 160, 120)
    water = np.repeat(np.linspace(168, 20, 240, dtype=np.float32)[:, None], 320, axis=1)
    water[40:80, 200:260] = 90                      # a board near the top
    water[120:] += np.random.default_rng(2).uniform(-20, 20, (120, 320)).astype(np.float32)
    assert blank_border(water)[1] == 0


def test_a_picture_framed_on_all_four_sides_has_that_border():
    """A photo padded with black on every side (a user trial: a frame saved
    inside a larger canvas): each side's bar reaches the others, so the step
    into the picture runs only between them; the whole image was kept, and
    a rectangle search locked onto the photo's edge (score 0.72)."""
    rng = np.random.default_rng(3)
    photo = cv2.GaussianBlur(rng.uniform(40, 200, (240, 320)), (0, 0), 1.5).astype(np.float32)
    framed = cv2.copyMakeBorder(photo, 30, 30, 40, 40, cv2.BORDER_CONSTANT, value=0)
    assert blank_border(framed) == (42, 32, 358, 268)
    two = cv2.copyMakeBorder(photo, 30, 0, 40, 0, cv2.BORDER_CONSTANT, value=0)  # top, left
    assert blank_border(two) == (42, 32, 360, 270)

