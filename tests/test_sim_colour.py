"""Coloured markers seen through water (seahough.sim.colour): deterministic
scenes, red fading with distance, the truth of the pasted marker, grey-matched
paint."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np
import pytest

from seahough import sim as S
from seahough.errors import ParameterError
from seahough.geometry import apply_matrix

from conftest import data_path

SHAPE = (160, 200)
KW = dict(size=48, source="procedural")
#: water without noise, strobe, snow, blur or compression: only attenuation and veiling light
STILL = dataclasses.replace(S.Water.preset("moderate"), strobe=0.0, blur=0.0, noise=0.0,
                            snow=0.0, jpeg_quality=None)


def _inside_points(name: str, truth, size: int = 48, erode: int = 5) -> np.ndarray:
    """Scene pixel positions (rounded) well inside the marker's shape."""
    _, mask = S.marker(name, size)
    core = cv2.erode((mask == 255).astype(np.uint8), np.ones((erode, erode), np.uint8))
    ys, xs = np.nonzero(core)
    pts = apply_matrix(truth.matrix, np.stack([xs, ys], axis=1).astype(float))
    return np.round(pts).astype(int)


def _mean_inside(scene, name, truth) -> np.ndarray:
    pts = _inside_points(name, truth)
    return scene[pts[:, 1], pts[:, 0]].reshape(-1, 3).astype(float).mean(axis=0)


def test_scenes_are_deterministic_by_seed():
    a = S.colour_marker_scene("L", SHAPE, paint="orange", grey_match=True, seed=5, **KW)
    b = S.colour_marker_scene("L", SHAPE, paint="orange", grey_match=True, seed=5, **KW)
    c = S.colour_marker_scene("L", SHAPE, paint="orange", grey_match=True, seed=6, **KW)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(a[2].matrix, b[2].matrix)
    assert not np.array_equal(a[0], c[0])
    assert a[0].shape == SHAPE + (3,) and a[0].dtype == np.uint8 and a[1].ndim == 3


def test_truth_is_where_the_painted_marker_is():
    paint = (40, 200, 90)
    for name in S.MARKERS:
        scene, pattern, truth = S.colour_marker_scene(name, SHAPE, paint=paint, water=None,
                                                      occlusion=0.0, seed=11, **KW)
        # the same pose as the grey marker scene of that seed
        _, _, grey_truth = S.marker_scene(name, SHAPE, water=None, occlusion=0.0, seed=11, **KW)
        np.testing.assert_allclose(truth.matrix, grey_truth.matrix)
        # the pattern's paint where the truth puts its shape
        _, mask = S.marker(name, 48)
        warped = cv2.warpAffine(pattern, truth.matrix, SHAPE[::-1], flags=cv2.INTER_LINEAR)
        inside = cv2.warpAffine((mask == 255).astype(np.uint8), truth.matrix, SHAPE[::-1],
                                flags=cv2.INTER_NEAREST)
        inside = cv2.erode(inside, np.ones((3, 3), np.uint8)) > 0
        diff = np.abs(scene.astype(int) - warped.astype(int))[inside]
        assert inside.sum() > 100 and np.percentile(diff, 99) <= 2, name
        if name != "board":
            assert np.abs(_mean_inside(scene, name, truth) - paint).max() < 1.5, name


def test_pattern_is_the_marker_as_painted():
    _, pattern, _ = S.colour_marker_scene("cross", SHAPE, paint="yellow", seed=2, **KW)
    img, mask = S.marker("cross", 48, colour=S.PAINTS["yellow"])
    np.testing.assert_array_equal(pattern, img)
    assert pattern.shape[:2] == mask.shape
    # the paint is at the outline: the board's panel is painted, its frame is dark
    board, bmask = S.marker("board", 90, colour=(0, 120, 255), dark=(20, 20, 20))
    m, c = 4, 10                                   # margin max(4, 90 // 20); cell 90 / 9
    mid = m + 45
    assert board[mid, m + c // 2].tolist() == [0, 120, 255]        # border ring (cell 0)
    assert board[mid, m + c + c // 2].tolist() == [20, 20, 20]     # frame (cell 1)
    assert board[1, 1].tolist() == [20, 20, 20] and bmask[mid, m + 2] == 255


def test_red_fades_more_than_blue_with_distance():
    means = {}
    for d in (0.5, 2.0, 4.0):
        scene, _, truth = S.colour_marker_scene("rectangle", SHAPE, paint=(200, 200, 200),
                                                water=STILL, distance=d, occlusion=0.0,
                                                seed=3, **KW)
        means[d] = _mean_inside(scene, "rectangle", truth)
    red = [means[d][2] for d in (0.5, 2.0, 4.0)]
    blue = [means[d][0] for d in (0.5, 2.0, 4.0)]
    assert red[0] > red[1] > red[2]                      # red fades with distance ...
    assert red[0] - red[2] > 2 * abs(blue[0] - blue[2])  # ... much more than blue
    # exactly the water model: J t + B (1 - t)
    for d in (0.5, 4.0):
        t = STILL.at(d).transmission
        expect = 200 * t + np.asarray(STILL.backscatter) * (1 - t)
        np.testing.assert_allclose(means[d], expect, atol=1.0)


def test_water_types():
    assert {"oceanic", "coastal", "moderate"} <= set(S.PRESETS)
    oceanic, coastal = S.Water.preset("oceanic"), S.Water.preset("coastal")
    for w in (oceanic, coastal, S.Water.preset("moderate")):
        a = w.attenuation
        assert a[2] > a[1] and a[2] > a[0]               # red fades first in every water
    assert oceanic.attenuation[0] < oceanic.attenuation[1]   # blue water: blue carries farthest
    assert coastal.attenuation[1] < coastal.attenuation[0]   # green water: green carries farthest
    assert S.Water().at(4.0).distance == 4.0 and S.Water().at(4.0).attenuation == S.Water().attenuation


def test_grey_matched_paint_has_the_seabeds_grey_level():
    p = S.matched_paint("orange", (90, 120, 110), "coastal")
    t = S.Water.preset("coastal").transmission
    w = np.array([0.114, 0.587, 0.299])
    assert np.dot(w, t * p) == pytest.approx(np.dot(w, t * np.array([90, 120, 110])), abs=1e-3)
    # same hue: a scaled orange
    orange = np.array(S.PAINTS["orange"], float)
    np.testing.assert_allclose(p / p.max(), orange / orange.max(), atol=1e-6)
    # a surround brighter than any shade of red: the brightest red
    np.testing.assert_allclose(S.matched_paint((0, 0, 100), (250, 250, 250)), (0, 0, 255))


def test_grey_match_leaves_no_grey_step_but_a_colour_one():
    _, mask = S.marker("L", 48)
    greys, colours, plain = [], [], []
    for paint in ("red", "yellow"):
        for seed in range(6):
            kw = dict(paint=paint, water=STILL, distance=2.0, occlusion=0.0, seed=seed, **KW)
            hard, _, truth = S.colour_marker_scene("L", SHAPE, grey_match=True, **kw)
            easy, _, _ = S.colour_marker_scene("L", SHAPE, **kw)
            c = S.border_contrast(hard, mask, truth)
            greys.append(c.grey)
            colours.append(c.colour)
            plain.append(S.border_contrast(easy, mask, truth).grey)
            # the marker's grey level is the mean of the seabed band around it
            g = cv2.cvtColor(hard, cv2.COLOR_BGR2GRAY).astype(float)
            inside = cv2.warpAffine(mask, truth.matrix, SHAPE[::-1]) > 127
            ring = cv2.dilate(inside.astype(np.uint8), np.ones((17, 17), np.uint8)) > 0
            ring &= ~cv2.dilate(inside.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
            pts = _inside_points("L", truth)
            assert g[pts[:, 1], pts[:, 0]].mean() == pytest.approx(g[ring].mean(), abs=2.0)
    # what is left is the seabed's own texture against a flat paint
    assert np.median(greys) < 0.4 * np.median(plain)
    assert np.median(colours) > 4 * np.median(greys)


def test_border_contrast_of_a_known_step():
    scene = np.full((100, 120, 3), 100, np.uint8)
    _, mask = S.marker("rectangle", 40)
    bgr = S.marker("rectangle", 40, colour=(100, 160, 100))[0]
    scene, truth = S.paste_pattern(scene, bgr, mask, x=60, y=50, scale=1.0, angle=0.0)
    c = S.border_contrast(scene, mask, truth)
    assert c.grey == pytest.approx(0.587 * 60, abs=1.0)
    assert c.colour == pytest.approx(60, abs=1.5)


def test_colour_scene_on_a_real_photo():
    photo = data_path("seabed", "dtu_starfish_murky.jpg")
    scene, pattern, truth = S.colour_marker_scene("board", (240, 320), paint="red",
                                                  grey_match=True, water="oceanic",
                                                  distance=1.0, seed=4, size=60, source=photo)
    assert scene.shape == (240, 320, 3) and pattern.shape[2] == 3
    assert np.all((truth.corners >= 0) & (truth.corners <= [319, 239]))


def test_bad_arguments_name_the_parameter():
    with pytest.raises(ParameterError, match="paint"):
        S.colour_marker_scene("L", SHAPE, paint="mauve", **KW)
    with pytest.raises(ParameterError, match="paint"):
        S.colour_marker_scene("L", SHAPE, paint=(0, 300, 0), **KW)
    with pytest.raises(ParameterError, match="distance"):
        S.colour_marker_scene("L", SHAPE, water=None, distance=2.0, **KW)
    with pytest.raises(ParameterError, match="distance"):
        S.Water().at(float("nan"))
    with pytest.raises(ParameterError, match="black"):
        S.matched_paint((0, 0, 0), (100, 100, 100))
    with pytest.raises(ParameterError, match="colour"):
        S.marker("cross", 40, colour=(1, 2))
    with pytest.raises(ParameterError, match="band"):
        S.border_contrast(np.zeros((50, 50, 3), np.uint8), S.marker("L", 20)[1],
                          S.Truth(matrix=np.eye(2, 3)), band=0)
