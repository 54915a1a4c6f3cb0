"""A small texture patch in a large frame: the search takes enough of the
frame's key points for some to fall on the patch (Detector._n_keypoints)."""

import math

import cv2
import numpy as np
import pytest

import seahough
import seahough.core.detector as D
from seahough import sim


def _cases(n=10):
    big = sim.seabed((720, 1280), seed=11)
    rng = np.random.default_rng(5)
    for k in range(n):
        side = 96
        x, y = int(rng.uniform(side, 1280 - 2 * side)), int(rng.uniform(side, 720 - 2 * side))
        c = (x + side / 2 - 0.5, y + side / 2 - 0.5)
        m = cv2.getRotationMatrix2D(c, float(rng.uniform(-180, 180)), float(rng.uniform(0.9, 1.1)))
        scene = sim.apply_water(cv2.warpAffine(big, m, (1280, 720), borderMode=cv2.BORDER_REFLECT),
                                "clear", seed=k)
        yield big[y:y + side, x:x + side], scene, c


def _found(monkeypatch, density):
    monkeypatch.setattr(D, "TEXTURE_DENSITY", density)
    hits = 0
    for patch, scene, c in _cases():
        d = seahough.Detector(seahough.Pattern(patch), scale_range=(0.85, 1.15)).detect(scene)
        hits += bool(d) and math.hypot(d[0].x - c[0], d[0].y - c[1]) < 3
    return hits


def test_a_96_px_patch_in_a_1280_px_frame_is_found(monkeypatch):
    # 12 of the frame's 1,200 most contrasted edge points fell on such a patch:
    # found 3 times in 10; with key points for a quarter of its 256 voting points
    # (half of the 128 it had then) on its area, 9
    assert _found(monkeypatch, D.TEXTURE_DENSITY) >= 8
    assert _found(monkeypatch, 0.0) <= 4


def test_only_small_texture_patterns_take_more_key_points():
    frame = (720, 1280)
    patch = sim.seabed((480, 640), seed=3)[:96, :96]
    small = seahough.Detector(seahough.Pattern(patch), scale_range=(0.85, 1.15))
    n = small._n_keypoints(frame, 0.25)
    assert small.config.n_keypoints < n <= D.MAX_KEYPOINTS
    # a patch covering a large share of the image, a shape, a frame: the default
    large = seahough.Detector(seahough.Pattern(sim.seabed((480, 640), seed=3)[:300, :400]),
                              scale_range=(0.85, 1.15))
    assert large._n_keypoints(frame, 0.25) is None
    # a 96 px patch of a 384x288 frame at the default scales (a user's crop
    # searched in the next frame): 25 of the 1,200 fell on it at scale 0.5, and
    # it was missed in its own frame; now a quarter of its 256 voting points
    medium = seahough.Detector(seahough.Pattern(sim.seabed((288, 384), seed=3)[:96, :96]))
    n = medium._n_keypoints((288, 384), 320 / 384)
    share = 96 * 96 * 0.5 ** 2 / (288 * 384)
    assert n * share == pytest.approx(D.TEXTURE_DENSITY * medium.config.n_pattern_points, rel=0.01)
    # (a 300 x 400 patch of a 1280x720 frame: 112 fall on it already)
    shape = seahough.Detector(seahough.Pattern.rectangle(40, 24), scale_range=(0.85, 1.15))
    assert shape._n_keypoints(frame, 0.25) is None
    assert seahough.Detector(seahough.Pattern.from_frame(patch))._n_keypoints(frame, 0.25) is None
    # a number of key points the user chose is kept (CLI --keypoints)
    mine = seahough.Detector(seahough.Pattern(patch), scale_range=(0.85, 1.15),
                             config=seahough.Config(n_keypoints=300))
    assert mine._n_keypoints(frame, 0.25) is None


def test_a_users_crop_is_found_in_the_frame_it_came_from():
    """A new user's first try (96 px of a real 384x288 Sparus frame, searched
    at the defaults in that very frame): "not found" while 25 key points fell
    on it; with a quarter of its voting points there, found where it was cut."""
    from conftest import data_path

    frame = cv2.imread(str(data_path("sequences", "sparus_auv_seabed", "frame_005.png")))
    found = seahough.Detector(seahough.Pattern.from_image(frame[100:196, 150:246])).detect(frame)
    assert found, "not found in its own frame"
    assert math.hypot(found[0].x - 197.5, found[0].y - 147.5) < 1.0
    assert found[0].scale == pytest.approx(1.0, abs=0.01)
