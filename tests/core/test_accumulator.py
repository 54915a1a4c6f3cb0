"""Stage 4 on hand-made pattern points and image segments: the accumulator's
bins, its votes, and where its peak lies.

The image segments are the pattern's points moved by a known pose (equation
1: q = t + rho R(phi) p, a gradient angle a becoming a - phi), so every
pattern point votes for the true cell; a cell counts each pattern point at
most once, weighted by its weight (here 1/4 each: a full match is 1.0).
``best_val`` sums 2x2 blocks of translation cells: block (row, col) covers
translations [tx0 + col * step, tx0 + (col + 2) * step) (and the same in y),
so one cell of votes makes four equal blocks, those that contain it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from seahough.config import Config
from seahough.core.accumulator import accumulate, check_ranges, edge_gap, make_bins, planes
from seahough.core.pattern import Pattern, PatternFeatures
from seahough.core.preprocess import compute_gradients
from seahough.core.segments import Segments
from seahough.errors import ParameterError

# four points 20 px from the origin, outward gradients, no symmetry under any
# rotation (their directions are 0, 90, 180 and 315 degrees), so only the
# true rotation lines all four up
_R = 20.0
_DIRS = np.radians([0.0, 90.0, 180.0, 315.0])


def _pattern(dirs=_DIRS, radius=_R) -> PatternFeatures:
    x = radius * np.cos(dirs)
    y = radius * np.sin(dirs)
    # the other end of each point's segment: 2 px along the edge
    x2, y2 = x - 2 * np.sin(dirs), y + 2 * np.cos(dirs)
    f = lambda a: np.asarray(a, np.float32)
    w = np.full(len(dirs), 1.0 / len(dirs), np.float32)
    return PatternFeatures(f(x), f(y), f(dirs), w, f(x2), f(y2), f(x), f(y), f(dirs))


def _moved(pf: PatternFeatures, tx, ty, rho=1.0, phi_deg=0.0, invert=False) -> Segments:
    """The pattern's points as image segments, moved by equation 1."""
    phi = math.radians(phi_deg)
    c, s = rho * math.cos(phi), rho * math.sin(phi)
    mx = lambda x, y: tx + c * x + s * y
    my = lambda x, y: ty - s * x + c * y
    x, y = pf.x.astype(float), pf.y.astype(float)
    ang = np.mod(pf.angle.astype(float) - phi + (math.pi if invert else 0.0), 2 * math.pi)
    f = lambda a: np.asarray(a, np.float32)
    n = len(x)
    return Segments(f(mx(x, y)), f(my(x, y)), f(ang), f(mx(x, y)), f(my(x, y)),
                    f(mx(pf.x2, pf.y2)), f(my(pf.x2, pf.y2)), np.full(n, 2, np.int32),
                    np.full(n, 100.0, np.float32), np.arange(n, dtype=np.int32))


def _blocks_holding(tx, ty, bins):
    """The (row, col) blocks of best_val whose 2x2 cells contain (tx, ty)."""
    cx = int(math.floor((tx - bins.tx0) / bins.step))
    cy = int(math.floor((ty - bins.ty0) / bins.step))
    return sorted((r, c) for r in (cy - 1, cy) for c in (cx - 1, cx))


def _peak_blocks(v):
    top = v.best_val.max()
    return top, sorted(map(tuple, np.argwhere(v.best_val == top).tolist()))


# ---------------------------------------------------------------- bins
def test_make_bins_derived_from_the_pattern_size():
    pf = _pattern()
    assert pf.radius == pytest.approx(20.0, abs=1e-5)
    b = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, 40.0, 30.0), Config())
    # translation bin 0.17 * rms radius * mid scale (1): 3.4 px (within 2..6)
    assert b.step == pytest.approx(3.4, abs=1e-5)
    # kappa = 1.6 * 3.4 / 20 = 0.272 rad: rotation bin capped at 10 degrees
    # -> 36 slices centred at 5, 15, ..., 355, half width 5 degrees
    np.testing.assert_allclose(np.degrees(b.angles), np.arange(5.0, 360.0, 10.0), atol=1e-5)
    assert math.degrees(b.angle_half) == pytest.approx(5.0)
    # log-scale step capped at 0.15: ln(1.25 / 0.8) = 0.446 needs 3 bins of
    # 0.1488 = (2/3) ln 1.25, centred at 0.8 * 1.25^(1/3), 0.8 * 1.25, 0.8 * 1.25^(5/3)
    np.testing.assert_allclose(b.scales, 0.8 * 1.25 ** (np.array([1, 3, 5]) / 3), rtol=1e-9)
    assert b.log_step == pytest.approx(2 / 3 * math.log(1.25))
    # cells cover the region from its corner: ceil(40 / 3.4) + 1, ceil(30 / 3.4) + 1
    assert (b.tx0, b.ty0, b.nx, b.ny) == (0.0, 0.0, 13, 10)
    assert (b.mode, b.scale_known, b.angle_known) == (0, False, False)     # oriented


def test_make_bins_for_known_quantities_and_limits():
    pf = _pattern()
    # scale and rotation known: the paper's 2-D case, 1 px bins, one slice
    # of +-angle_tolerance, point voting
    b = make_bins(pf, (1.0, 1.0), (30.0, 30.0), (5.0, 6.0, 15.0, 16.0), Config())
    assert b.step == 1.0 and (b.nx, b.ny) == (11, 11) and (b.tx0, b.ty0) == (5.0, 6.0)
    assert b.scales.tolist() == [1.0] and np.degrees(b.angles).tolist() == pytest.approx([30.0])
    assert math.degrees(b.angle_half) == pytest.approx(15.0)
    assert (b.mode, b.scale_known, b.angle_known) == (1, True, True)
    # a small pattern (radius 5): step clipped up to 2 px, bins capped
    small = make_bins(_pattern(radius=5.0), (0.8, 1.25), (0.0, 90.0), (0, 0, 10, 10), Config())
    assert small.step == 2.0 and small.angles.size == 9 and small.scales.size == 3
    # a large one (radius 100): step clipped down to 6 px; kappa = 0.096 rad
    # (5.5 degrees): 66 slices over 360 degrees and ceil(0.446 / 0.096) = 5 scales
    big = make_bins(_pattern(radius=100.0), (0.8, 1.25), (0.0, 360.0), (0, 0, 10, 10), Config())
    assert big.step == 6.0 and big.angles.size == 66 and big.scales.size == 5
    # the config's explicit bins win
    cfg = Config(translation_bin=2.5, angle_bin=20.0, scale_step=0.2)
    b = make_bins(pf, (0.8, 1.25), (-30.0, 30.0), (0, 0, 10, 10), cfg)
    assert b.step == 2.5 and (b.nx, b.ny) == (5, 5)
    np.testing.assert_allclose(np.degrees(b.angles), [340.0, 360.0, 380.0], atol=1e-6)
    assert b.scales.size == 3                 # ceil(0.446 / 0.2)


def test_check_ranges():
    assert check_ranges((0.5, 2), (-30, 30)) == ((0.5, 2.0), (330.0, 390.0))
    assert check_ranges((1, 1), (0, 720)) == ((1.0, 1.0), (0.0, 360.0))     # a full turn
    assert check_ranges((1, 1), (360, 370)) == ((1.0, 1.0), (0.0, 10.0))
    assert check_ranges((1, 1), (-360, -350)) == ((1.0, 1.0), (0.0, 10.0))
    assert check_ranges((0.01, 0.64), (720.5, 721)) == ((0.01, 0.64), (0.5, 1.0))


@pytest.mark.parametrize("scale_range, angle_range, match", [
    ((0.001, 1.0), (0, 10), r"scale_range=\(0\.001, 1\.0\): scales must be in \[0\.01, 100\]"),
    ((1.0, 101.0), (0, 10), "scale_range.*scales must be in"),
    ((0.5, 40.0), (0, 10), "scale_range.*more than 64x"),
    ((2.0, 1.0), (0, 10), "scale_range.*low must be <= high"),
    ((1.0,), (0, 10), "scale_range.*got 1 values"),
    ("ab", (0, 10), "scale_range.*pair"),
    ((1.0, float("nan")), (0, 10), r"scale_range\[1\]=nan: must be finite"),
    ((1.0, 1.0), (10, 0), "angle_range.*low must be <= high"),
    ((1.0, 1.0), None, "angle_range=None"),
    ((1.0, 1.0), (0, True), r"angle_range\[1\]=True: must be a number"),
])
def test_check_ranges_errors_name_the_parameter(scale_range, angle_range, match):
    with pytest.raises(ParameterError, match=match):
        check_ranges(scale_range, angle_range)


# ---------------------------------------------------------------- votes
def test_known_scale_and_rotation_shift_peaks_at_the_shift():
    pf = _pattern()
    tx, ty = 30.3, 27.6
    seg = _moved(pf, tx, ty)
    # a stray image segment elsewhere: one pattern point pairs with it
    extra = _moved(pf, 5.0, 40.0).take(np.array([0]))
    seg = Segments(*(np.concatenate([getattr(seg, f), getattr(extra, f)])
                     for f in Segments.__dataclass_fields__))
    b = make_bins(pf, (1.0, 1.0), (0.0, 0.0), (20.0, 20.0, 40.0, 35.0), Config())
    v = accumulate(pf, seg, b)
    assert v.best_val.shape == (b.ny - 1, b.nx - 1) == (15, 20)
    top, where = _peak_blocks(v)
    assert top == 1.0
    # cell (10, 7) from (20, 20): blocks (6..7, 9..10)
    assert where == _blocks_holding(tx, ty, b) == [(6, 9), (6, 10), (7, 9), (7, 10)]
    # every other block holds at most the stray point and one of the true ones
    rest = v.best_val.copy()
    for r, c in where:
        rest[r, c] = 0
    assert rest.max() <= 0.5
    assert v.scale_angle.tolist() == [[1.0]]


@pytest.mark.parametrize("voting", ["oriented", "points", "segments"])
@pytest.mark.parametrize("k, phi_deg", [(1, 35.0), (2, 125.0), (0, 305.0)])
def test_scale_and_rotation_peak_at_their_bins(voting, k, phi_deg):
    # the bins of test_make_bins_derived_from_the_pattern_size (step 3.4,
    # slices of 10 degrees, scales 0.8 * 1.25^((1 + 2k) / 3)); the pose puts
    # the origin in the middle of cell (10, 7) and uses a scale and a
    # rotation at bin centres (slice d is centred on 5 + 10 d degrees)
    pf = _pattern()
    cfg = Config(voting=voting)
    b = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0), cfg)
    rho = 0.8 * 1.25 ** ((1 + 2 * k) / 3)
    d = int(phi_deg // 10)
    tx, ty = 10.5 * 3.4, 7.5 * 3.4
    v = accumulate(pf, _moved(pf, tx, ty, rho, phi_deg), b)
    top, where = _peak_blocks(v)
    assert top == pytest.approx(1.0, abs=1e-6)
    assert where == _blocks_holding(tx, ty, b) == [(6, 9), (6, 10), (7, 9), (7, 10)]
    assert {int(v.best_k[r, c]) for r, c in where} == {k}
    assert {int(v.best_d[r, c]) for r, c in where} == {d}
    # the scale-rotation plane: its one full cell is (k, d)
    assert v.scale_angle.shape == (3, 36)
    assert np.argwhere(v.scale_angle >= top - 1e-6).tolist() == [[k, d]]


def test_inverted_contrast_needs_either():
    pf = _pattern()
    b = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0), Config())
    tx, ty = 10.5 * 3.4, 7.5 * 3.4
    seg = _moved(pf, tx, ty, 1.0, 35.0, invert=True)   # every gradient reversed
    blocks = tuple(np.array(_blocks_holding(tx, ty, b)).T)
    # as it is, no pattern point agrees with its own reversed edge there
    assert accumulate(pf, seg, b).best_val[blocks].max() < 0.5
    # with either polarity, the reversed copies of all four points do
    v = accumulate(pf, seg, b, either=True)
    top, where = _peak_blocks(v)
    assert top == 1.0 and where == _blocks_holding(tx, ty, b)


def test_planes_in_full_resolution_coordinates():
    pf = _pattern()
    b = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0), Config())
    v = accumulate(pf, _moved(pf, 35.7, 25.5, 1.0, 35.0), b)
    # a working image at half scale: working x -> full (x + 0.5) / 0.5 - 0.5
    g = compute_gradients(np.zeros((120, 160), np.float32), 0.5)
    p = planes(v, b, g)
    # block (r, c) is centred on tx0 + (c + 1) * step
    assert p.x[9] == pytest.approx((10 * 3.4 + 0.5) * 2 - 0.5)
    assert p.y[6] == pytest.approx((7 * 3.4 + 0.5) * 2 - 0.5)
    assert p.xy is v.best_val and p.xy_scale[7, 10] == pytest.approx(1.0)
    assert p.xy_angle[7, 10] == pytest.approx(35.0, abs=1e-4)
    assert p.angles.tolist() == pytest.approx(list(np.arange(5.0, 360.0, 10.0)))


# ---------------------------------------------------------------- size limits
def test_accumulator_over_its_limits_is_refused_naming_the_bins():
    from seahough.core import accumulator as A

    pf = _pattern()
    region = (0.0, 0.0, 639.0, 479.0)                 # a 640x480 working image
    # the finest documented bins: 2560 x 1920 translations x 1387 scales per
    # slice (6.8e9 cells, 54 GB) and 3600 slices
    fine = Config(translation_bin=0.25, angle_bin=0.1, scale_step=0.001)
    with pytest.raises(ParameterError) as e:
        make_bins(pf, (0.5, 2.0), (0.0, 360.0), region, fine)
    msg = str(e.value)
    assert msg.startswith("an accumulator of 2.4e+13 cells (2557 x 1917 translations x 1387 "
                          "scales x 3600 rotations; 6.8e+09 cells, 54.4 GB, a rotation slice) "
                          "is over the limit of 2.5e+08 cells a slice and 4e+09 cells in all: "
                          "coarsen Config.translation_bin (0.25), Config.angle_bin (0.1) or "
                          "Config.scale_step (0.001), or narrow scale_range"), msg
    # only the time: the fields not set are named with the bins derived for them
    with pytest.raises(ParameterError, match=r"^an accumulator of 1\.3e\+11 cells .* over the "
                       r"limit of 4e\+09 cells in all: coarsen Config\.translation_bin \(derived: "
                       r"3\.4 px\), Config\.angle_bin \(0\.1\) or Config\.scale_step \(0\.001\)"):
        make_bins(pf, (0.5, 2.0), (0.0, 360.0), region, Config(angle_bin=0.1, scale_step=0.001))
    # ... which a narrower search brings back under the limit
    assert make_bins(pf, (0.9, 1.1), (0.0, 10.0), region,
                     Config(angle_bin=0.1, scale_step=0.001)).angles.size == 100
    # the limit on all cells grows with the searched area (so that default
    # bins search any image), the one on a slice does not
    big = (0.0, 0.0, 16000.0, 12000.0)
    b = make_bins(pf, (0.5, 2.0), (0.0, 360.0), big, Config())
    cells = b.nx * b.ny * b.scales.size * b.angles.size
    assert cells > A.MAX_CELLS and b.nx * b.ny * b.scales.size < A.MAX_SLICE_CELLS
    with pytest.raises(ParameterError, match="cells a slice: coarsen Config.translation_bin"):
        make_bins(pf, (0.5, 2.0), (0.0, 360.0), (0.0, 0.0, 40000.0, 30000.0), Config())


def test_default_bins_stay_far_under_the_limits():
    """Every pattern size, scale span and angle range with the default bins,
    over a 640x480 working region: at most a fifteenth of each limit (the
    most: a scale range of 1.56-100 and a large pattern, 144 x 139 bins)."""
    from seahough.config import MOTION_CONFIG
    from seahough.core import accumulator as A

    most = np.zeros(3)
    for r in np.geomspace(2.0, 2000.0, 40):
        pf = _pattern(radius=float(r))
        for sr in ((1, 1), (0.9, 1.1), (0.5, 2.0), (0.1, 6.4), (1.5625, 100.0), (0.01, 0.64)):
            for ar in ((0, 0), (-25, 25), (0, 180), (0, 360)):
                b = make_bins(pf, sr, ar, (0.0, 0.0, 639.0, 479.0), Config())
                ns, na, nt = b.scales.size, b.angles.size, b.nx * b.ny
                votes = MOTION_CONFIG.n_pattern_points * Config().n_keypoints * (ns + na / 64)
                most = np.maximum(most, [nt * ns, nt * ns * na, votes])
    assert (most * 15 < [A.MAX_SLICE_CELLS, A.MAX_CELLS, A.MAX_VOTES]).all(), most


def test_too_many_votes_are_refused_naming_the_counts():
    # 4 pattern points x 1000 segments x (139 scales + 36 / 64): 5.6e5 votes;
    # refused when the limit is lower than that
    from seahough.core import accumulator as A

    pf = _pattern()
    b = make_bins(pf, (0.5, 2.0), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0),
                  Config(scale_step=0.01, n_pattern_points=500))
    seg = _moved(pf, 30.0, 20.0)
    many = seg.take(np.arange(1000) % len(seg))
    accumulate(pf, many, b)                           # under the limit
    old, A.MAX_VOTES = A.MAX_VOTES, 5e5
    try:
        with pytest.raises(ParameterError, match=r"^voting 4 pattern points x 1000 image segments "
                           r"over 139 scales and 36 rotations \(5\.6e\+05 votes\) is over the "
                           r"limit of 5e\+05: lower "
                           r"Config\.n_pattern_points \(500\) or Config\.n_keypoints \(1200\), "
                           r"coarsen Config\.scale_step \(0\.01\), or narrow scale_range"):
            accumulate(pf, many, b)
        # each pattern point counts twice with either polarity
        A.MAX_VOTES = 1e6
        accumulate(pf, many, b)
        with pytest.raises(ParameterError, match="^voting 8 pattern points"):
            accumulate(pf, many, b, either=True)
    finally:
        A.MAX_VOTES = old


@pytest.mark.parametrize("voting", ["oriented", "points", "segments"])
def test_a_pattern_point_counts_once_per_cell(voting):
    # every image segment given three times: each pair votes three times into
    # the same cells, and a cell still counts each pattern point once (its
    # height, the share of the pattern's weight, never passes 1); the pattern
    # itself is found whole
    pf = _pattern()
    cfg = Config(voting=voting)
    b = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0), cfg)
    seg = _moved(pf, 30.0, 20.0)
    once = accumulate(pf, seg, b)
    thrice = accumulate(pf, seg.take(np.arange(3 * len(seg)) % len(seg)), b)
    assert np.array_equal(once.best_val, thrice.best_val)
    assert once.best_val.max() == pytest.approx(1.0, abs=1e-5)
    assert np.array_equal(once.scale_angle, thrice.scale_angle)


def test_too_many_point_slices_are_refused():
    # the vote kernel's tags (slice x pattern point) are exact float32 integers
    # only up to 2**24: over its limit the search is refused, naming what to lower
    from seahough.core import accumulator as A

    pf = _pattern()
    b = make_bins(pf, (0.5, 2.0), (0.0, 360.0), (0.0, 0.0, 68.0, 51.0), Config())
    seg = _moved(pf, 30.0, 20.0)
    assert A.MAX_POINT_SLICES == 2 ** 24
    old, A.MAX_POINT_SLICES = A.MAX_POINT_SLICES, 4 * b.angles.size
    try:
        accumulate(pf, seg, b)                        # 4 points: at the limit
        with pytest.raises(ParameterError, match=rf"^voting 8 pattern points over "
                           rf"{b.angles.size} rotations is over the limit of .*: lower "
                           rf"Config\.n_pattern_points \({Config().n_pattern_points}\) or "
                           r"coarsen Config\.angle_bin"):
            accumulate(pf, seg, b, either=True)
    finally:
        A.MAX_POINT_SLICES = old


# ------------------------------------------ nested outlines (a marker board's rings)
def _nested_squares(sides=(120, 92, 64), size=140):
    """Concentric squares, bright / dark alternately: rings 14 px wide."""
    import cv2
    img = np.zeros((size, size), np.uint8)
    for i, side in enumerate(sides):
        a, b = (size - side) // 2, (size + side) // 2
        cv2.rectangle(img, (a, a), (b - 1, b - 1), 220 if i % 2 == 0 else 30, -1)
    return img


def test_edge_gap_is_the_width_of_a_ring_or_of_a_shape():
    rings = Pattern.from_image(_nested_squares(), polarity="either")
    assert edge_gap(rings.features(1.0), either=True) == pytest.approx(14.0, abs=1.5)
    assert edge_gap(rings.features(0.5), either=True) == pytest.approx(7.0, abs=1.0)
    # the same direction of gradient only (a "bright" pattern): no ring is its
    # neighbour's look-alike; the nearest are two rings on, or across the squares
    bright = Pattern.from_image(_nested_squares(), polarity="bright")
    assert edge_gap(bright.features(1.0)) >= 27.0
    bar = Pattern.rectangle(120, 40, polarity="either").features(1.0)
    assert edge_gap(bar, either=True) == pytest.approx(40.0, abs=2.0)
    assert edge_gap(Pattern.rectangle(120, 40).features(1.0)) == math.inf


@pytest.mark.parametrize("scale_range", [(0.5, 2.0), (1.0, 4.0)])
def test_nested_outlines_get_translation_bins_of_half_a_ring(scale_range):
    cfg = Config()
    pf = Pattern.from_image(_nested_squares(), polarity="either").features(0.5, cfg)
    gap = edge_gap(pf, either=True)
    s_mid = math.sqrt(scale_range[0] * scale_range[1])
    region = (0.0, 0.0, 319.0, 239.0)
    plain = make_bins(pf, scale_range, (0.0, 360.0), region, cfg)
    nested = make_bins(pf, scale_range, (0.0, 360.0), region, cfg, gap)
    assert nested.step == pytest.approx(max(2.0, 0.5 * plain.step,
                                            min(plain.step, 0.5 * gap * s_mid)))
    if s_mid == 1.0:   # the derived bin (4.6 px) spans most of a ring (7 px): halved
        assert nested.step < plain.step
    else:              # rings of 14 px at the middle scale: the derived bin (6 px) holds
        assert nested.step == plain.step
    # only the translation bin: rotation and scale bins stay the derived ones
    np.testing.assert_array_equal(nested.angles, plain.angles)
    np.testing.assert_array_equal(nested.scales, plain.scales)
    # a plain shape's opposite side is far: its bins stay as derived
    rect = Pattern.rectangle(120, 80, polarity="either").features(0.5, cfg)
    assert make_bins(rect, scale_range, (0.0, 360.0), region, cfg,
                     edge_gap(rect, either=True)).step == \
        make_bins(rect, scale_range, (0.0, 360.0), region, cfg).step
    # a thin stroke: at most half the derived bin finer (its cells would multiply)
    assert make_bins(pf, scale_range, (0.0, 360.0), region, cfg, 1.0).step == \
        pytest.approx(max(2.0, 0.5 * plain.step))
    # a bin given by the caller is kept
    fixed = cfg.replace(translation_bin=5.0)
    assert make_bins(pf, scale_range, (0.0, 360.0), region, fixed, gap).step == 5.0


def test_the_detector_takes_the_gap_of_drawn_patterns_only():
    from seahough import Detector
    rings = Pattern.from_image(_nested_squares(), polarity="either")
    assert Detector(rings)._edge_gap(rings.features(0.5), 0.5) == pytest.approx(7.0, abs=1.0)
    # ... also when its search ranks key points by contrast alone
    d0 = Detector(rings, config=Config(chain_length=0.0))
    assert d0._edge_gap(rings.features(0.5), 0.5) == pytest.approx(7.0, abs=1.0)
    line = Pattern.line(96, 8)
    assert Detector(line)._edge_gap(line.features(0.5), 0.5) is None
    rng = np.random.default_rng(3)
    import cv2
    texture = cv2.GaussianBlur(rng.uniform(0, 255, (120, 120)).astype(np.float32), (0, 0), 1.5)
    patch = Pattern.from_image(np.clip(texture, 0, 255).astype(np.uint8))
    for cfg in (Config(), Config(chain_length=0.0)):
        assert Detector(patch, config=cfg)._edge_gap(patch.features(0.5, cfg), 0.5) is None


def test_a_marker_board_is_not_taken_one_ring_off(monkeypatch):
    # scenes where the board's derived bins (translation bin 4.6 working px,
    # its rings 6.8 wide) answered the pose one ring off; half-ring bins find it
    # (the ranking's local vote over shifts, ranking._shifted, since finds them
    # with the old bins too: it is left out here, the bins are what is tested;
    # since the refinement's points cover every side, candidates.icp_subset,
    # the old bins find 2 of the 4). With 128 voting points, as then: with the
    # 256 of 2026-12-06 the old bins find these 4 boards, the half-ring bins 3
    # (the bins stay half a ring: on the coloured markers' tune part, boards
    # searched in colour were found 142 of 144 times with either count)
    from seahough import Detector, Pattern, sim as S
    from seahough.core import ranking
    monkeypatch.setattr(ranking, "_shifted", lambda ctx, pose, radius, points: pose)

    def at_truth(found, t):   # (bench_colour's success rule)
        d = found[0] if found else None
        return d is not None and math.hypot(d.x - t.x, d.y - t.y) <= 3.0 \
            and abs(d.scale / t.scale - 1) <= 0.05 \
            and abs((d.angle - t.angle + 180.0) % 360.0 - 180.0) <= 3.0
    img, mask = S.marker("board", 120, colour=S.PAINTS["orange"])
    pat = Pattern.from_image(img, mask=mask, polarity="either")
    cfg = Config(colour=True, n_pattern_points=128)
    old_bin = float(np.clip(0.17 * pat.features(0.5, cfg).radius, 2.0, 6.0))
    now = Detector(pat, (0.5, 2.0), config=cfg)
    before = Detector(pat, (0.5, 2.0), config=cfg.replace(translation_bin=old_bin))
    default = Detector(pat, (0.5, 2.0), config=Config(colour=True))
    found = {"now": 0, "before": 0, "256": 0}
    for seed in (13, 19, 20, 28):
        scene, _, truth = S.colour_marker_scene("board", (480, 640), paint="orange",
                                                grey_match=seed % 2 == 1, water="moderate",
                                                distance=2.0, seed=seed, size=120,
                                                source="procedural")
        for name, det in (("now", now), ("before", before), ("256", default)):
            found[name] += at_truth(det.detect(scene), truth)
    assert found["now"] >= 3 and found["before"] < found["now"], found
    # at the default 256 voting points the half-ring bins find 3 of the 4 (and
    # the old bins 4: the finer bins no longer show their gain on these scenes)
    assert found["256"] >= 3, found
