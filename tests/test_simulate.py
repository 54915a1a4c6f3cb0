"""Tests of the synthetic scene generator: determinism, exact ground truth, water model."""

from __future__ import annotations

import math
import time

import cv2
import numpy as np
import pytest

from seahough import sim as S
from seahough.geometry import apply_matrix, compose, invert_matrix, matrix_to_pose, pose_to_matrix

SHAPE = (480, 640)


def _grey(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img


def _overlap_mask(matrix: np.ndarray, src_shape, dst_shape, erode: int = 5) -> np.ndarray:
    """Pixels of the destination that the warped source covers, eroded."""
    h, w = dst_shape[:2]
    ones = np.full(src_shape[:2], 255, np.uint8)
    m = cv2.warpAffine(ones, matrix, (w, h), flags=cv2.INTER_NEAREST)
    return cv2.erode(m, np.ones((erode, erode), np.uint8)) > 0


def _warp_error(src: np.ndarray, dst: np.ndarray, matrix: np.ndarray) -> float:
    """Mean absolute grey difference between warped ``src`` and ``dst`` where they overlap."""
    h, w = dst.shape[:2]
    warped = cv2.warpAffine(_grey(src), matrix, (w, h), flags=cv2.INTER_LINEAR)
    m = _overlap_mask(matrix, src.shape, dst.shape)
    assert m.sum() > 2000, "the views hardly overlap"
    return float(np.abs(warped.astype(float) - _grey(dst))[m].mean())


@pytest.fixture
def no_shared_data(monkeypatch):
    """Pretend ../shared/data is absent (a user's fresh checkout)."""
    import seahough.sim.backgrounds as backgrounds_module
    monkeypatch.setattr(backgrounds_module, "shared_data_dir", lambda: None)


# ----------------------------------------------------------------------------
# seabed and background
# ----------------------------------------------------------------------------

def test_seabed_deterministic_textured_and_fast():
    a, b, c = S.seabed(SHAPE, seed=0), S.seabed(SHAPE, seed=0), S.seabed(SHAPE, seed=1)
    assert a.shape == (480, 640, 3) and a.dtype == np.uint8
    np.testing.assert_array_equal(a, b)
    assert np.abs(a.astype(int) - c).mean() > 10
    edges = cv2.Canny(_grey(a), 50, 150)
    assert edges.mean() > 5  # plenty of edges
    t = min(_timed(lambda: S.seabed(SHAPE, seed=s)) for s in range(3))
    assert t < 0.25, f"seabed took {t * 1000:.0f} ms"


def _timed(f) -> float:
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def _long_lines(grey: np.ndarray, length: int = 50) -> int:
    edges = cv2.Canny(grey, 50, 150)
    lines = cv2.HoughLinesP(edges, 1, np.pi / 180, threshold=length // 2,
                            minLineLength=length, maxLineGap=2)
    return 0 if lines is None else len(lines)


def test_seabed_has_no_long_straight_lines():
    for seed in range(3):
        assert _long_lines(_grey(S.seabed(SHAPE, seed=seed))) <= 1
    # positive control: an axis-aligned rectangle marker is found by the same probe
    pattern, mask = S.marker("rectangle", 160)
    scene, _ = S.paste_pattern(S.seabed(SHAPE, seed=0), pattern, mask,
                               x=320, y=240, scale=1.0, angle=0.0)
    assert _long_lines(_grey(scene)) >= 2


def test_seabed_other_shapes():
    img = S.seabed((100, 37), seed=3)
    assert img.shape == (100, 37, 3)


def test_background_sources(tmp_path):
    proc = S.background(SHAPE, seed=4, source="procedural")
    np.testing.assert_array_equal(proc, S.seabed(SHAPE, seed=4))
    auto1, auto2 = S.background(SHAPE, seed=5), S.background(SHAPE, seed=5)
    np.testing.assert_array_equal(auto1, auto2)
    assert auto1.shape == (480, 640, 3) and auto1.dtype == np.uint8
    path = tmp_path / "photo.png"
    cv2.imwrite(str(path), S.seabed((300, 500), seed=9))
    from_file = S.background((120, 160), seed=0, source=str(path))
    assert from_file.shape == (120, 160, 3)
    missing = tmp_path / "nope.jpg"
    with pytest.raises(FileNotFoundError, match="nope.jpg"):
        S.background(SHAPE, seed=0, source=missing)


def test_background_falls_back_without_shared_data(no_shared_data):
    np.testing.assert_array_equal(S.background(SHAPE, seed=2), S.seabed(SHAPE, seed=2))


# ----------------------------------------------------------------------------
# water
# ----------------------------------------------------------------------------

def test_water_presets_and_invalid_name():
    for name in S.PRESETS:
        assert isinstance(S.Water.preset(name), S.Water)
    assert S.Water.preset("moderate") == S.Water()
    with pytest.raises(ValueError, match="clear"):
        S.Water.preset("murky")
    with pytest.raises(ValueError):
        S.Water(strobe=2.0)


def test_hard_water_has_less_contrast_than_clear():
    img = S.seabed(SHAPE, seed=1)
    clear = _grey(S.apply_water(img, "clear", seed=0)).astype(float)
    hard = _grey(S.apply_water(img, "hard", seed=0)).astype(float)
    assert hard.std() < 0.8 * clear.std()
    # local (edge) contrast too
    def hp(g):
        return (g - cv2.GaussianBlur(g, (0, 0), 3)).std()
    assert hp(hard) < hp(clear)


def test_red_is_attenuated_more_than_blue():
    w = S.Water.preset("moderate")
    t = w.transmission
    assert t[2] < t[1] and t[2] < t[0]
    white = np.full((64, 64, 3), 255, np.uint8)
    still = S.Water(attenuation=w.attenuation, distance=w.distance, backscatter=(0, 0, 0),
                    strobe=0, blur=0, noise=0, snow=0, jpeg_quality=None)
    out = S.apply_water(white, still)
    b, g, r = out.reshape(-1, 3).mean(axis=0)
    assert r < b - 30
    # the scene's contrast in the red channel drops most
    img = S.seabed(SHAPE, seed=2)
    out = S.apply_water(img, dataclass_replace(still, backscatter=(120, 120, 60)))
    ratio = out.reshape(-1, 3).std(axis=0) / img.reshape(-1, 3).std(axis=0)
    assert ratio[2] < ratio[0]


def dataclass_replace(obj, **kw):
    import dataclasses
    return dataclasses.replace(obj, **kw)


def test_apply_water_model_exact_without_degradations():
    img = S.seabed((60, 80), seed=0)
    w = S.Water(attenuation=(0.1, 0.2, 0.5), distance=2.0, backscatter=(100, 50, 20),
                strobe=0, blur=0, noise=0, snow=0, jpeg_quality=None)
    t = np.exp(-np.array([0.1, 0.2, 0.5]) * 2.0)
    expected = img * t + np.array([100, 50, 20]) * (1 - t)
    assert np.abs(S.apply_water(img, w).astype(float) - expected).max() <= 0.51


def test_apply_water_jpeg_grey_determinism_and_none():
    img = S.seabed((120, 160), seed=0)
    base = S.Water(strobe=0, blur=0, noise=0, snow=0, jpeg_quality=None)
    raw = S.apply_water(img, base)
    jpg = S.apply_water(img, dataclass_replace(base, jpeg_quality=40))
    assert jpg.shape == raw.shape and jpg.dtype == np.uint8
    assert 0 < np.abs(jpg.astype(int) - raw).mean() < 6
    grey = S.apply_water(_grey(img), "moderate", seed=1)
    assert grey.shape == (120, 160, 3)
    a, b = S.apply_water(img, "hard", seed=3), S.apply_water(img, "hard", seed=3)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, S.apply_water(img, "hard", seed=4))
    none = S.apply_water(img, None)
    np.testing.assert_array_equal(none, img)
    assert none is not img


def test_marine_snow_adds_bright_specks():
    dark = np.full((200, 200, 3), 40, np.uint8)
    w = S.Water(attenuation=(0, 0, 0), distance=0, strobe=0, blur=0, noise=0,
                snow=2000, jpeg_quality=None)
    out = S.apply_water(dark, w, seed=0)
    assert (out.max(axis=2) > 100).sum() > 20
    assert np.median(out) == 40


# ----------------------------------------------------------------------------
# markers, poses, pasting
# ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", S.MARKERS)
def test_marker_images(name):
    img, mask = S.marker(name, size=120)
    assert img.dtype == np.uint8 and mask.dtype == np.uint8 and img.shape == mask.shape
    assert mask.min() == 0 and mask.max() == 255
    assert ((mask > 0) & (mask < 255)).mean() < 0.1  # anti-aliased border only
    assert 20 <= img.min() <= 40 and 230 <= img.max() <= 255
    ys, xs = np.nonzero(mask)
    assert max(xs.max() - xs.min() + 1, ys.max() - ys.min() + 1) in (119, 120, 121)
    assert xs.min() >= 3 and ys.min() >= 3
    assert xs.max() <= img.shape[1] - 4 and ys.max() <= img.shape[0] - 4
    # no rotational or mirror symmetry (except the plain rectangle's)
    bright = (img > 128).astype(np.uint8)
    if name != "rectangle":
        for k in (1, 2, 3):
            r = np.rot90(bright, k)
            if r.shape == bright.shape:
                assert not np.array_equal(r, bright)
        assert not np.array_equal(bright[:, ::-1], bright)
        assert not np.array_equal(bright[::-1], bright)
    else:
        h, w = np.ptp(ys) + 1, np.ptp(xs) + 1
        assert 1.5 < w / h < 1.7


def test_marker_invalid_name():
    with pytest.raises(ValueError, match="board"):
        S.marker("circle")


def test_random_pose_keeps_pattern_inside():
    rng = np.random.default_rng(0)
    for _ in range(50):
        x, y, s, a = S.random_pose(rng, SHAPE, (132, 132), (0.6, 1.6), (0, 360), margin=3)
        assert 0.6 <= s <= 1.6 and 0 <= a <= 360
        m = pose_to_matrix(x, y, s, a, ((132 - 1) / 2, (132 - 1) / 2))
        c = apply_matrix(m, [[0, 0], [131, 0], [131, 131], [0, 131]])
        assert c.min() >= 3 - 1e-9 and c[:, 0].max() <= 636 + 1e-9 and c[:, 1].max() <= 476 + 1e-9
    with pytest.raises(ValueError):
        S.random_pose(rng, (100, 100), (132, 132), (2.0, 3.0))


@pytest.mark.parametrize("name", S.MARKERS)
def test_paste_pattern_truth_reproduces_pixels(name):
    bg = S.seabed(SHAPE, seed=3)
    pattern, mask = S.marker(name)
    rng = np.random.default_rng(1)
    x, y, s, a = S.random_pose(rng, SHAPE, pattern.shape)
    scene, truth = S.paste_pattern(bg, pattern, mask, x=x, y=y, scale=s, angle=a)
    assert scene.shape == bg.shape
    warped = cv2.warpAffine(pattern, truth.matrix, (640, 480), flags=cv2.INTER_LINEAR)
    inner = cv2.erode(cv2.warpAffine(mask, truth.matrix, (640, 480), flags=cv2.INTER_NEAREST),
                      np.ones((5, 5), np.uint8)) > 0
    assert np.abs(warped.astype(float) - _grey(scene))[inner].mean() < 1.0
    outer = cv2.warpAffine(mask, truth.matrix, (640, 480)) == 0
    np.testing.assert_array_equal(scene[outer], bg[outer])
    # pose fields agree with the matrix (origin = pattern centre)
    origin = ((pattern.shape[1] - 1) / 2, (pattern.shape[0] - 1) / 2)
    px, py, ps, pa = matrix_to_pose(truth.matrix, origin)
    assert (px, py, ps) == pytest.approx((truth.x, truth.y, truth.scale))
    assert abs(S_angle_diff(pa, truth.angle)) < 1e-6
    h, w = pattern.shape
    np.testing.assert_allclose(
        truth.corners, apply_matrix(truth.matrix, [[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]]))
    assert truth.occluded == 0.0


def S_angle_diff(a, b):
    return (a - b + 180) % 360 - 180


def test_paste_pattern_grey_background_and_custom_origin():
    bg = np.full((200, 200), 90, np.uint8)
    pattern, mask = S.marker("L", 60)
    scene, truth = S.paste_pattern(bg, pattern, mask, x=100, y=100, scale=1.0, angle=90,
                                   origin=(0, 0))
    assert scene.ndim == 2
    np.testing.assert_allclose(apply_matrix(truth.matrix, [[0, 0]]), [[100, 100]])
    # +90 deg is counter-clockwise as displayed: the pattern's +x axis points up
    np.testing.assert_allclose(apply_matrix(truth.matrix, [[10, 0]]), [[100, 90]], atol=1e-9)
    # a board half outside the scene is half hidden
    board, bmask = S.marker("board", 100)
    _, truth = S.paste_pattern(bg, board, bmask, x=0.0, y=100, scale=1.0, angle=0)
    assert truth.occluded == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("name", ["board", "rectangle", "cross"])
def test_occlusion_fraction(name):
    bg = np.full((480, 640, 3), 100, np.uint8)  # flat: silt is then plain grey 100
    pattern, mask = S.marker(name)
    rng = np.random.default_rng(7)
    for occ in (0.05, 0.15, 0.25):
        x, y, s, a = S.random_pose(rng, SHAPE, pattern.shape)
        clean, _ = S.paste_pattern(bg, pattern, mask, x=x, y=y, scale=s, angle=a)
        scene, truth = S.paste_pattern(bg, pattern, mask, x=x, y=y, scale=s, angle=a,
                                       occlusion=occ, seed=int(occ * 100))
        assert abs(truth.occluded - occ) < 0.03
        m = cv2.warpAffine(mask, truth.matrix, (640, 480)) > 127
        marker_px = cv2.warpAffine(pattern, truth.matrix, (640, 480)).astype(float)
        # a pixel is hidden when it moved more than half-way to the silt colour
        hidden = np.abs(scene[:, :, 1] - marker_px) > 0.5 * np.abs(100 - marker_px)
        assert abs(hidden[m].mean() - occ) < 0.03
        # nothing changes far from the marker (silt may spill a little around it)
        k = 2 * int(0.4 * math.sqrt(m.sum()) + 6) + 1
        far = cv2.dilate(m.astype(np.uint8), np.ones((k, k), np.uint8)) == 0
        np.testing.assert_array_equal(scene[far], clean[far])


def test_occlusion_silt_looks_like_background():
    bg = S.seabed(SHAPE, seed=5)
    pattern, mask = S.marker("rectangle", 150)
    scene, truth = S.paste_pattern(bg, pattern, mask, x=320, y=240, scale=1.2, angle=20,
                                   occlusion=0.2, seed=1)
    assert abs(truth.occluded - 0.2) < 0.03
    m = cv2.warpAffine(mask, truth.matrix, (640, 480)) > 127
    g = _grey(scene).astype(float)
    hidden = m & (g < 200)  # marker is 242; silt has seabed tones
    assert hidden.sum() > 0.1 * m.sum()
    assert abs(g[hidden].mean() - _grey(bg)[m].mean()) < 40


# ----------------------------------------------------------------------------
# scenes
# ----------------------------------------------------------------------------

def test_marker_scene_determinism_and_truth():
    a = S.marker_scene("board", seed=11)
    b = S.marker_scene("board", seed=11)
    c = S.marker_scene("board", seed=12)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[2].matrix, b[2].matrix)
    assert not np.array_equal(a[0], c[0])
    scene, pattern, truth = a
    assert scene.shape == (480, 640, 3) and scene.dtype == np.uint8
    np.testing.assert_array_equal(pattern, S.marker("board")[0])
    assert truth.corners.min() >= 0
    assert truth.corners[:, 0].max() <= 639 and truth.corners[:, 1].max() <= 479
    assert 0.6 <= truth.scale <= 1.6 and 0 <= truth.occluded <= 0.23


def test_marker_scene_without_water_matches_pattern_and_negative():
    scene, pattern, truth = S.marker_scene("cross", water=None, occlusion=0.0, seed=3,
                                           source="procedural")
    _, mask = S.marker("cross")
    assert _warp_error_in_mask(pattern, mask, scene, truth.matrix) < 1.0
    neg = S.negative_scene(SHAPE, water=None, seed=3, source="procedural")
    region = cv2.warpAffine(mask, truth.matrix, (640, 480)) > 0
    region = cv2.dilate(region.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    np.testing.assert_array_equal(scene[~region], neg[~region])
    assert not np.array_equal(scene[region], neg[region])


def _warp_error_in_mask(pattern, mask, scene, matrix) -> float:
    h, w = scene.shape[:2]
    warped = cv2.warpAffine(pattern, matrix, (w, h), flags=cv2.INTER_LINEAR)
    inner = cv2.erode(cv2.warpAffine(mask, matrix, (w, h), flags=cv2.INTER_NEAREST),
                      np.ones((5, 5), np.uint8)) > 0
    return float(np.abs(warped.astype(float) - _grey(scene))[inner].mean())


def test_negative_scene_is_deterministic():
    np.testing.assert_array_equal(S.negative_scene(seed=1), S.negative_scene(seed=1))
    assert S.negative_scene(seed=1).shape == (480, 640, 3)


@pytest.mark.parametrize("source", ["auto", "procedural"])
def test_fragment_scene_truth(source):
    scene, patch, truth = S.fragment_scene(water=None, seed=2, source=source)
    assert patch.shape == (160, 160) and scene.shape == (480, 640, 3)
    assert 0.75 <= truth.scale <= 1.33
    assert truth.corners.min() >= 0 and truth.corners[:, 0].max() <= 639
    assert _warp_error(patch, scene, truth.matrix) < 3.0
    # the truth is informative: a 3 px error in the pose gives a clearly larger error
    off = truth.matrix.copy()
    off[:, 2] += 3
    assert _warp_error(patch, scene, off) > 2 * _warp_error(patch, scene, truth.matrix)
    # a textured patch
    gm = np.abs(cv2.Sobel(patch, cv2.CV_32F, 1, 0)) + np.abs(cv2.Sobel(patch, cv2.CV_32F, 0, 1))
    assert gm.mean() > 4
    again = S.fragment_scene(water=None, seed=2, source=source)
    np.testing.assert_array_equal(again[0], scene)


def test_fragment_scene_from_given_image():
    photo = S.seabed((300, 400), seed=8)  # small: magnified as needed
    scene, patch, truth = S.fragment_scene(photo, size=(100, 120), water="moderate", seed=0)
    assert patch.shape == (100, 120)
    assert scene.shape == (480, 640, 3)


@pytest.mark.parametrize("source", ["auto", "procedural"])
def test_frame_pair_motion_is_exact(source):
    prev, cur, truth = S.frame_pair(water=None, seed=4, source=source)
    assert prev.shape == cur.shape == (480, 640, 3)
    np.testing.assert_array_equal(truth.motion, truth.matrix)
    assert _warp_error(prev, cur, truth.motion) < 3.0
    off = truth.motion.copy()
    off[:, 2] += 3
    assert _warp_error(prev, cur, off) > 2 * max(_warp_error(prev, cur, truth.motion), 0.5)


@pytest.mark.parametrize("photo_shape", [(1200, 1600), (300, 400), (700, 500)])
def test_views_lie_inside_the_photo(photo_shape):
    # views of a flat photo show no dark border anywhere (sampling outside is black)
    photo = np.full(photo_shape + (3,), 200, np.uint8)
    for seed in range(3):
        prev, cur, _ = S.frame_pair(photo, water=None, seed=seed)
        scene, patch, _ = S.fragment_scene(photo, water=None, seed=seed)
        frames, _ = S.sequence(photo, n_frames=6, path="loop", water=None, seed=seed)
        for view in [prev, cur, scene, patch, *frames]:
            assert view.min() >= 190


def test_a_photo_magnified_into_a_blur_is_said_so(caplog):
    # a long turn over a small photo: every frame an enlarged blur, without a word
    photo = np.full((240, 320, 3), 200, np.uint8)
    with caplog.at_level("WARNING", logger="seahough.sim"):
        S.sequence(photo, n_frames=4, frame_size=(48, 64), step=6.0, water=None, seed=0)
    assert not caplog.records                    # (magnified 1x: nothing to say)
    with caplog.at_level("WARNING", logger="seahough.sim"):
        S.sequence(photo, n_frames=60, frame_size=(120, 160), path="turn", water=None, seed=0)
    (msg,) = [r.getMessage() for r in caplog.records]
    assert msg.startswith("note: the photo (320x240) is magnified ") and "blurred" in msg, msg
    u = float(msg.split("magnified ")[1].split("x")[0])
    assert u > S._views.MAGNIFY_NOTE


def test_frame_pair_given_motion_and_water():
    prev, cur, truth = S.frame_pair(frame_size=(240, 320), shift=(30, -20), angle=10,
                                    scale=1.05, water="moderate", seed=1)
    cx, cy = 159.5, 119.5
    x, y, s, a = matrix_to_pose(truth.motion, (cx, cy))
    assert (x, y, s, a) == pytest.approx((cx + 30, cy - 20, 1.05, 10.0))
    assert (truth.x, truth.y) == pytest.approx((cx + 30, cy - 20))
    # each frame has its own water draw, yet they still agree well
    err = _warp_error(prev, cur, truth.motion)
    assert 0.5 < err < 15


def test_frame_pair_random_components_within_ranges():
    for seed in range(4):
        _, _, t = S.frame_pair(frame_size=(120, 160), water=None, seed=seed)
        assert 0.9 <= t.scale <= 1.1
        assert abs(S_angle_diff(t.angle, 0)) <= 20
        assert abs(t.x - 79.5) <= 0.4 * 160 + 1e-9 and abs(t.y - 59.5) <= 0.4 * 120 + 1e-9


def test_rope_scene_centre_line_is_bright():
    for seed in range(3):
        scene, truth = S.rope_scene(water=None, seed=seed, source="procedural")
        assert 0 <= truth.line_angle < 180
        a = math.radians(truth.line_angle)
        d = np.array([math.cos(a), -math.sin(a)])
        n = np.array([math.sin(a), math.cos(a)])
        c = np.array([319.5, 239.5])
        np.testing.assert_allclose([truth.x, truth.y], c + truth.line_offset * n)
        ts = np.arange(-500, 500, 2.0)
        on = c + truth.line_offset * n + ts[:, None] * d
        keep = (on[:, 0] >= 0) & (on[:, 0] <= 639) & (on[:, 1] >= 0) & (on[:, 1] <= 479)
        assert keep.sum() > 100  # crosses the frame
        g = _grey(scene).astype(float)
        vals = g[np.round(on[keep, 1]).astype(int), np.round(on[keep, 0]).astype(int)]
        assert vals.min() > 140 and vals.mean() > 170
        # a parallel line 3 rope widths away is not the rope
        away = on[keep] + 24 * n
        ok = (away[:, 0] >= 0) & (away[:, 0] <= 639) & (away[:, 1] >= 0) & (away[:, 1] <= 479)
        far = g[np.round(away[ok, 1]).astype(int), np.round(away[ok, 0]).astype(int)]
        assert far.mean() < vals.mean() - 30


def test_rope_scene_sign_convention():
    # horizontal rope below the centre: positive offset
    scene, truth = S.rope_scene(angle=0.0, offset=100.0, water=None, seed=0, source="procedural")
    assert (truth.x, truth.y) == pytest.approx((319.5, 339.5))
    assert _grey(scene)[339, 50:600].mean() > 170
    # vertical rope right of the centre: positive offset
    scene, truth = S.rope_scene(angle=90.0, offset=50.0, water=None, seed=0, source="procedural")
    assert (truth.x, truth.y) == pytest.approx((369.5, 239.5))
    assert _grey(scene)[20:460, 369:371].mean() > 170
    scene, truth = S.rope_scene(angle=200.0, offset=0.0, water="hard", seed=0)
    assert truth.line_angle == pytest.approx(20.0)


@pytest.mark.parametrize("path", ["line", "turn", "loop"])
def test_sequence_matrices_are_consistent(path):
    frames, mats = S.sequence(n_frames=8, path=path, water=None, seed=3)
    assert len(frames) == len(mats) == 8
    np.testing.assert_allclose(mats[0], [[1, 0, 0], [0, 1, 0]])
    for i in range(1, len(frames)):
        rel = compose(mats[i], invert_matrix(mats[i - 1]))
        assert _overlap_mask(rel, frames[0].shape, frames[0].shape, erode=1).mean() >= 0.6
        assert _warp_error(frames[i - 1], frames[i], rel) < 3.0
    # and directly from frame 0 to frame 2
    assert _warp_error(frames[0], frames[2], mats[2]) < 3.0


def test_sequence_paths_and_errors():
    _, line = S.sequence(n_frames=6, path="line", step=10, water=None, seed=0,
                         source="procedural")
    _, turn = S.sequence(n_frames=6, path="turn", step=10, water=None, seed=0,
                         source="procedural")
    assert S_angle_diff(matrix_to_pose(line[-1])[3], 0) == pytest.approx(0, abs=4)
    assert abs(S_angle_diff(matrix_to_pose(turn[-1])[3], 0)) > 60
    # forward motion: the content of frame 0 moves about 5 * 10 px (down the frame)
    x0 = apply_matrix(line[-1], [[159.5, 119.5]])[0]
    assert 35 < np.hypot(*(x0 - [159.5, 119.5])) < 65
    with pytest.raises(ValueError):
        S.sequence(path="zigzag")
    with pytest.raises(ValueError):
        S.sequence(n_frames=3, step=200)


def test_sequence_determinism_and_water():
    a, ma = S.sequence(n_frames=4, seed=5)
    b, mb = S.sequence(n_frames=4, seed=5)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)
    for x, y in zip(ma, mb):
        np.testing.assert_array_equal(x, y)
    assert a[0].shape == (240, 320, 3)


def test_everything_works_without_shared_data(no_shared_data):
    scene, pattern, truth = S.marker_scene("L", seed=0)
    assert scene.shape == (480, 640, 3)
    np.testing.assert_array_equal(
        S.marker_scene("L", seed=0, water=None, occlusion=0)[0],
        S.marker_scene("L", seed=0, water=None, occlusion=0, source="procedural")[0])
    prev, cur, t = S.frame_pair(water=None, seed=0)
    assert _warp_error(prev, cur, t.motion) < 3.0
    scene, patch, t = S.fragment_scene(water=None, seed=0)
    assert _warp_error(patch, scene, t.matrix) < 3.0
    frames, mats = S.sequence(n_frames=3, water=None, seed=0)
    assert len(frames) == 3
    scene, t = S.rope_scene(seed=0)
    assert scene.shape == (480, 640, 3)


def test_scene_functions_are_fast():
    S.marker_scene(seed=0)  # warm the photo cache
    S.frame_pair(seed=0)
    for f in (lambda: S.marker_scene(seed=1), lambda: S.frame_pair(seed=1),
              lambda: S.rope_scene(seed=1), lambda: S.fragment_scene(seed=1)):
        assert min(_timed(f) for _ in range(2)) < 0.5


# ----------------------------------------------------------------------------
# curved rope
# ----------------------------------------------------------------------------
def _normals(points: np.ndarray) -> np.ndarray:
    d = np.gradient(points, axis=0)
    d /= np.hypot(*d.T)[:, None]
    return np.stack([-d[:, 1], d[:, 0]], 1)


@pytest.mark.parametrize("polarity", ["bright", "dark"])
def test_curved_rope_scene_truth_is_the_centre_line(polarity):
    scene, truth = S.curved_rope_scene(width=10, bend=40, polarity=polarity, water=None,
                                       seed=2, source="procedural")
    assert scene.shape == (480, 640, 3) and truth.width == 10.0
    assert truth.polarity == polarity and truth.visible.sum() > 200
    g = _grey(scene).astype(float)
    pts = truth.points[truth.visible][2:-2]           # (an end is cut across its point)
    nrm = _normals(truth.points)[truth.visible][2:-2]

    def grey_at(q):
        ok = (q[:, 0] >= 0) & (q[:, 0] <= 639) & (q[:, 1] >= 0) & (q[:, 1] <= 479)
        q = np.round(q[ok]).astype(int)
        return g[q[:, 1], q[:, 0]]
    on, beside = grey_at(pts), grey_at(pts + 3.0 * truth.width * nrm)
    if polarity == "bright":
        assert on.min() > 140 and on.mean() > beside.mean() + 40
    else:
        assert on.max() < 80 and on.mean() < beside.mean() - 40
    # the points are a pixel apart along the rope, the curve smooth
    steps = np.hypot(*np.diff(truth.points, axis=0).T)
    np.testing.assert_allclose(steps, 1.0, atol=0.01)
    # the rope's border is half a width from the line: across it, on the
    # side away from its faint shadow (the normal (-d[1], d[0]) points to
    # the shadow), the grey level changes between 0.35 and 0.7 width, and
    # hardly beyond (the round rope also darkens towards its sides)
    prof = [grey_at(pts - k * truth.width * nrm).mean() for k in (0.35, 0.7, 1.05)]
    assert abs(prof[0] - prof[1]) > 15 and abs(prof[0] - prof[1]) > 5 * abs(prof[1] - prof[2])


def test_curved_rope_scene_bend_and_form():
    _, straight = S.curved_rope_scene(bend=0, water=None, seed=1, source="procedural")
    p = straight.points - straight.points.mean(axis=0)
    assert np.linalg.svd(p, compute_uv=False)[1] < 1e-6 * len(p)   # on one line
    assert straight.radius == math.inf
    _, arc = S.curved_rope_scene(bend=60, form="arc", water=None, seed=1, source="procedural")
    assert arc.radius == pytest.approx(100 / math.radians(60), rel=1e-3)
    # an arc: every point at that radius from one centre (three points fix it)
    a, b, c = arc.points[[0, len(arc.points) // 2, -1]]
    m = np.array([b - a, c - a])
    centre = np.linalg.solve(2 * m, [b @ b - a @ a, c @ c - a @ a])
    np.testing.assert_allclose(np.hypot(*(arc.points - centre).T), arc.radius, rtol=2e-3)
    # it turns at most 90 degrees each way: no loop
    assert np.hypot(*(arc.points[0] - arc.points[-1])) > 1.9 * arc.radius
    _, wave = S.curved_rope_scene(bend=30, form="wave", water=None, seed=4, source="procedural")
    assert wave.radius >= 100 / math.radians(30) - 1e-6


def test_curved_rope_scene_buried_stretch_is_hidden():
    clear, t0 = S.curved_rope_scene(width=8, bend=20, water=None, seed=5, source="procedural")
    scene, t1 = S.curved_rope_scene(width=8, bend=20, buried=0.2, water=None, seed=5,
                                    source="procedural")
    np.testing.assert_array_equal(t0.points, t1.points)
    hidden = (t0.visible & ~t1.visible)
    assert abs(hidden.sum() / t0.visible.sum() - 0.2) < 0.05 and t1.length < t0.length
    q = np.round(t1.points[hidden]).astype(int)
    g0, g1 = _grey(clear).astype(float), _grey(scene).astype(float)
    assert g1[q[:, 1], q[:, 0]].mean() < g0[q[:, 1], q[:, 0]].mean() - 60   # no rope there
    shown = np.round(t1.points[t1.visible]).astype(int)
    np.testing.assert_array_equal(g1[shown[:, 1], shown[:, 0]] > 140,
                                  g0[shown[:, 1], shown[:, 0]] > 140)


def test_curved_rope_scene_deterministic_and_checked():
    a, ta = S.curved_rope_scene(seed=7)
    b, tb = S.curved_rope_scene(seed=7)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(ta.points, tb.points)
    assert not np.array_equal(a, S.curved_rope_scene(seed=8)[0])
    for kwargs, name in ((dict(width=0), "width"), (dict(bend=-5), "bend"),
                         (dict(form="zigzag"), "form"), (dict(polarity="red"), "polarity"),
                         (dict(buried=0.9), "buried")):
        with pytest.raises(ValueError, match=name):
            S.curved_rope_scene(**kwargs)
