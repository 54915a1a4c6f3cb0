"""A small texture patch in a large frame: the search takes enough of the
frame's key points for some to fall on the patch (Detector._n_keypoints)."""

import math

import cv2
import numpy as np

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
    # (a 120 px patch in a 640x480 view: about 28 of the 1,200 fall on it already)
    fragment = seahough.Detector(seahough.Pattern(sim.seabed((480, 640), seed=3)[:120, :120]),
                                 scale_range=(0.7, 1.4))
    assert fragment._n_keypoints((480, 640), 0.5) is None
    shape = seahough.Detector(seahough.Pattern.rectangle(40, 24), scale_range=(0.85, 1.15))
    assert shape._n_keypoints(frame, 0.25) is None
    assert seahough.Detector(seahough.Pattern.from_frame(patch))._n_keypoints(frame, 0.25) is None
    # a number of key points the user chose is kept (CLI --keypoints)
    mine = seahough.Detector(seahough.Pattern(patch), scale_range=(0.85, 1.15),
                             config=seahough.Config(n_keypoints=300))
    assert mine._n_keypoints(frame, 0.25) is None
