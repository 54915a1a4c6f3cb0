"""Colour edges (Config.colour): an object told from its surroundings by hue
alone is found in colour and not in grey; grey images are searched as before.

The scene: an orange rectangle on grey-green sand whose BGR levels OpenCV
turns into the same grey level (128), as an orange marker looks once the
water has taken most of its red's contrast away.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import Config, Detector, ParameterError, Pattern, PatternError
from seahough.core.preprocess import compute_gradients
from seahough.io.images import to_gray, to_image

SAND, ORANGE = (90, 140, 120), (40, 93, 230)     # BGR, both grey 128
COLOUR = Config(colour=True)


def _scene(noise=2.0, inside=ORANGE, outside=SAND, seed=0):
    """640x480 (searched at half size, finished at full resolution): a
    180 x 120 rectangle centred at (380, 220), turned by 30 degrees."""
    img = np.empty((480, 640, 3), np.uint8)
    img[:] = outside
    box = cv2.boxPoints(((380.0, 220.0), (180.0, 120.0), -30.0))
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], inside)
    if noise:
        rng = np.random.default_rng(seed)
        img = np.clip(img + rng.normal(0.0, noise, img.shape), 0, 255).astype(np.uint8)
    return img


def _pose(d):
    return d.x, d.y, d.scale, d.angle % 180.0


def _at_truth(d):
    x, y, s, a = _pose(d)
    return math.hypot(x - 380.0, y - 220.0) < 2.0 and abs(s - 3.0) < 0.1 and abs(a - 30.0) < 1.0


def test_the_scene_has_no_grey_edge():
    clean = _scene(noise=0.0)
    assert np.ptp(to_gray(clean)) == 0.0          # one grey level everywhere


def test_an_iso_luminant_object_is_found_in_colour_only():
    img = _scene()
    rect = Pattern.rectangle(60, 40)
    assert Detector(rect, (2.0, 4.0)).detect(img) == []
    found = Detector(rect, (2.0, 4.0), config=COLOUR).detect(img)
    assert found and _at_truth(found[0]), [_pose(d) for d in found]
    assert found[0].nfa < 1e-6


def test_a_colour_pattern_image_needs_colour_edges(tmp_path):
    # the pattern cut from a colour photo: the rectangle, unturned, on sand
    crop = np.empty((80, 110, 3), np.uint8)
    crop[:] = SAND
    crop[20:60, 25:85] = ORANGE
    with pytest.raises(PatternError, match="too few edges"):
        Pattern.from_image(crop, config=Config(colour=False))   # grey: no edges to find it by
    p = Pattern.from_image(crop, config=COLOUR)
    assert p.image.shape == (80, 110)             # the pattern image stays grey
    found = Detector(p, (2.0, 4.0), config=COLOUR).detect(_scene())
    assert found and _at_truth(found[0]), [_pose(d) for d in found]
    # a saved colour pattern keeps its colours: the same detections
    q = Pattern.load(p.save(tmp_path / "orange.npz"), config=COLOUR)
    again = Detector(q, (2.0, 4.0), config=COLOUR).detect(_scene())
    assert [d.to_dict() for d in again] == [d.to_dict() for d in found]


def test_colour_edge_polarity_bright_and_dark():
    # across the border into the orange, red (the channel that changes
    # most) rises: the rectangle is "bright"; with the colours swapped the
    # red falls into it and it is "dark"
    img, swapped = _scene(), _scene(inside=SAND, outside=ORANGE)
    cfg = dict(scale_range=(2.0, 4.0), config=COLOUR)
    bright = Pattern.rectangle(60, 40, polarity="bright")
    dark = Pattern.rectangle(60, 40, polarity="dark")
    either = Pattern.rectangle(60, 40, polarity="either")
    assert _at_truth(Detector(bright, **cfg).detect(img)[0])
    assert not any(_at_truth(d) for d in Detector(dark, **cfg).detect(img))
    assert _at_truth(Detector(dark, **cfg).detect(swapped)[0])
    assert not any(_at_truth(d) for d in Detector(bright, **cfg).detect(swapped))
    assert _at_truth(Detector(either, **cfg).detect(swapped)[0])


@pytest.mark.parametrize("make", [
    lambda g: np.dstack([g] * 3),                        # three equal channels
    lambda g: np.dstack([g, g, g, np.full_like(g, 255)]),  # ... and an alpha channel
])
def test_a_grey_image_in_colour_channels_is_searched_as_grey(make):
    g = cv2.cvtColor(_scene(noise=3.0, inside=(200, 200, 200), outside=(60, 60, 60)),
                     cv2.COLOR_BGR2GRAY)
    rect = Pattern.rectangle(60, 40)
    want = [d.to_dict() for d in Detector(rect, (2.0, 4.0)).detect(g)]
    assert want and _at_truth(Detector(rect, (2.0, 4.0)).detect(g)[0])
    for cfg in (Config(), COLOUR):
        assert [d.to_dict() for d in Detector(rect, (2.0, 4.0), config=cfg).detect(make(g))] == want
        assert [d.to_dict() for d in Detector(rect, (2.0, 4.0), config=cfg).detect(g)] == want


def test_di_zenzo_on_nearly_grey_channels_gives_the_grey_pose():
    # one level more in red than in blue and green: the colour path runs (the
    # channels differ), and the edges are those of the grey image
    g = cv2.cvtColor(_scene(noise=3.0, inside=(200, 200, 200), outside=(60, 60, 60)),
                     cv2.COLOR_BGR2GRAY)
    bgr = np.dstack([g, g, g + 1])
    assert to_image(bgr, colour=True).ndim == 3
    rect = Pattern.rectangle(60, 40)
    a = Detector(rect, (2.0, 4.0)).detect(g)[0]
    b = Detector(rect, (2.0, 4.0), config=COLOUR).detect(bgr)[0]
    assert math.hypot(a.x - b.x, a.y - b.y) < 0.05
    assert abs(a.scale / b.scale - 1) < 1e-3 and abs(a.angle - b.angle) < 0.05
    assert abs(a.score - b.score) < 0.02


def test_to_image_keeps_colour_only_when_asked_and_checks_as_to_gray():
    img = _scene()
    assert np.array_equal(to_image(img), to_gray(img))
    c = to_image(img, colour=True)
    assert c.dtype == np.float32 and c.shape == (480, 640, 3)
    np.testing.assert_array_equal(c, img.astype(np.float32))
    bgra = np.dstack([img, np.zeros(img.shape[:2], np.uint8)])
    np.testing.assert_array_equal(to_image(bgra, colour=True), c)       # alpha dropped
    np.testing.assert_array_equal(to_image(img.astype(np.uint16) * 257, colour=True), c)
    grey = to_gray(img)
    assert np.array_equal(to_image(grey, colour=True), grey)
    for bad in (np.zeros((10, 10, 2)), np.zeros((4, 4, 3)), np.full((9, 9, 3), np.nan)):
        with pytest.raises(seahough.SeahoughError) as e1:
            to_gray(bad, name="photo")
        with pytest.raises(type(e1.value)) as e2:
            to_image(bad, colour=True, name="photo")
        assert str(e1.value) == str(e2.value) and str(e2.value).startswith("photo: ")


def test_colour_gradients_point_one_way_along_a_whole_border():
    # an orange disc on sand: every border pixel's colour gradient points
    # inwards (red rises into the disc), whatever the border's direction
    img = np.empty((101, 101, 3), np.float32)
    img[:] = SAND
    cv2.circle(img, (50, 50), 30, ORANGE, -1)
    g = compute_gradients(img)
    yy, xx = np.mgrid[0:101, 0:101]
    r = np.hypot(xx - 50, yy - 50)
    on = (g.magnitude > 200) & (abs(r - 30) < 2)
    assert on.sum() > 150
    inward = -(g.gx * (xx - 50) + g.gy * (yy - 50)) / np.maximum(r, 1) / np.maximum(g.magnitude, 1)
    assert (inward[on] > 0.5).all()            # (a pixel staircase turns some by up to 45 deg)
    assert np.median(inward[on]) > 0.95
    # the grey image has (almost) no edge there at all
    grey = compute_gradients(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY))
    assert grey.magnitude[on].max() < 0.1 * g.magnitude[on].min()


def test_config_colour_must_be_a_bool_or_none():
    assert Config().colour is None and COLOUR.colour is True
    with pytest.raises(ParameterError, match=r"Config\.colour='x'"):
        Config(colour="x")
    with pytest.raises(ParameterError, match=r"Config\.colour"):
        Config().replace(colour=1)


def test_cli_colour_and_grey(tmp_path, capsys):
    import json

    from seahough.cli import main

    path = tmp_path / "iso.png"
    cv2.imwrite(str(path), _scene())

    def run(*args):
        with pytest.raises(SystemExit) as e:
            main(["detect", "rect:60,40", str(path), "--scale-range", "2", "4", "--json", "-q",
                  *args])
        return e.value.code, json.loads(capsys.readouterr().out)

    rc, rec = run("--grey")
    assert rc == 1 and rec["detections"] == []
    rc, rec = run("--colour")
    assert rc == 0
    d = rec["detections"][0]
    assert math.hypot(d["x"] - 380.0, d["y"] - 220.0) < 2.0


def _on_grey_texture(seed, chroma=30.0):
    """320x240: strong grey texture (every channel alike, spread 40 levels)
    and a flat 90 x 60 rectangle at (170, 120), turned by 30 degrees, as
    grey as the texture's mean, red 30 up and green down: its border is a
    colour step weaker than the texture's grey ones."""
    rng = np.random.default_rng(seed)
    t = cv2.GaussianBlur(rng.normal(0, 1, (240, 320)).astype(np.float32), (0, 0), 2.0)
    t = 120 + 40 * t / t.std()
    img = np.dstack([t, t, t])
    box = cv2.boxPoints(((170.0, 120.0), (90.0, 60.0), -30.0))
    inside = np.zeros((240, 320), np.uint8)
    cv2.fillPoly(inside, [np.round(box).astype(np.int32)], 1)
    img[inside > 0] = (120.0, 120.0 - chroma * 0.299 / 0.587, 120.0 + chroma)
    return np.clip(img, 0, 255).astype(np.uint8)


def test_weighing_the_colours_finds_a_colour_border_in_grey_texture():
    def found(boost):
        det = Detector(Pattern.rectangle(60, 40), (1.0, 2.0),
                       config=Config(colour=True, colour_boost=boost))
        n = 0
        for seed in range(10):
            d = det.detect(_on_grey_texture(seed))
            n += bool(d) and math.hypot(d[0].x - 170, d[0].y - 120) < 2.0 \
                and abs(d[0].scale - 1.5) < 0.05 and abs(d[0].angle % 180 - 30) < 1.5
        return n
    assert Config(colour=True).colour_boost == 4.0
    weighed, plain = found(4.0), found(1.0)
    assert weighed >= 8 and plain <= 4, (weighed, plain)


@pytest.mark.parametrize("bad", [0.5, -1.0, float("nan"), 1000.0, "x"])
def test_config_colour_boost_is_checked(bad):
    with pytest.raises(ParameterError, match="colour_boost"):
        Config(colour=True, colour_boost=bad)


def test_a_painted_pattern_is_searched_in_colour_by_default():
    """Config.colour None (the default): a pattern painted in colour (an
    orange board on sand) is searched by its colour edges, and finds the
    iso-luminant board that a grey search cannot see; a grey pattern, a
    shape, and a crop of a dull seabed photo stay grey."""
    crop = np.empty((80, 110, 3), np.uint8)
    crop[:] = SAND
    crop[20:60, 25:85] = ORANGE
    p = Pattern.from_image(crop)                  # (painted: no Config needed for its edges)
    assert p.painted and p.in_colour() and not p.in_colour(Config(colour=False))
    det = Detector(p, (2.0, 4.0))
    assert det.config.colour is True
    found = det.detect(_scene())
    assert found and _at_truth(found[0]), [_pose(d) for d in found]
    # a grey board, a shape, a dull seabed crop: grey searches
    board = np.full((80, 110), 60, np.uint8)
    board[20:60, 25:85] = 200
    grey = Pattern.from_image(cv2.cvtColor(board, cv2.COLOR_GRAY2BGR))   # (three equal channels)
    rng = np.random.default_rng(0)
    seabed = np.clip(rng.normal(0, 12, (64, 64, 1)) + (95, 110, 105), 0, 255).astype(np.uint8)
    seabed = cv2.GaussianBlur(seabed, (0, 0), 1.5)
    for q in (grey, Pattern.rectangle(60, 40), Pattern.from_image(seabed)):
        assert not q.painted and Detector(q).config.colour is False
    assert Detector(Pattern.rectangle(60, 40), (2.0, 4.0)).detect(_scene()) == []


def test_each_pattern_of_a_detector_gets_its_own_edges():
    """A Detector of a painted pattern and a grey shape: each pattern is
    searched in the image it needs (the painted board in colour, the shape
    in grey), and finds what it finds searched alone: the iso-luminant board
    and a white rectangle elsewhere in the scene."""
    crop = np.empty((80, 110, 3), np.uint8)
    crop[:] = SAND
    crop[20:60, 25:85] = ORANGE
    pats = {"board": Pattern.from_image(crop), "rect": Pattern.rectangle(60, 40)}
    img = _scene(noise=0)
    box = cv2.boxPoints(((120.0, 400.0), (120.0, 80.0), 0.0))       # the rectangle at 2x
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], (235, 235, 235))
    many = Detector(pats, (1.5, 4.0))
    assert {k: d.config.colour for k, d in many.parts.items()} == {"board": True, "rect": False}
    assert many.config.colour is None               # (its patterns differ)
    got = many.detect(img)
    alone = {k: Detector(p, (1.5, 4.0)).detect(img) for k, p in pats.items()}
    key = lambda d: (round(d.x, 6), round(d.y, 6), round(d.scale, 6), round(d.score, 6))  # noqa: E731
    assert sorted(key(d) for d in got) == sorted(key(d) for v in alone.values() for d in v)
    assert any(_at_truth(d) for d in alone["board"]), [_pose(d) for d in alone["board"]]
    r = alone["rect"][0]
    assert math.hypot(r.x - 120, r.y - 400) < 2 and abs(r.scale - 2) < 0.05, _pose(r)
    # one set of features cannot serve a grey and a colour search
    with pytest.raises(ParameterError, match="features"):
        many.search(img, features=many.search(img).features)
    # shapes alone: the Detector's config is grey, as before Config.colour's None
    assert Detector({"a": Pattern.rectangle(60, 40), "b": Pattern.circle(20)}).config.colour is False


def test_a_painted_pattern_in_a_grey_image_is_searched_by_its_grey_edges():
    """A grey image has no colour to see: a painted pattern (an orange board
    on a dark canvas) is then searched by its grey edges, exactly as with
    ``Config(colour=False)``. In a colour image it is searched by its colour
    edges, either polarity: the board is orange on grey in the pattern image
    (red rises most across its border) and orange on blue in the scene (blue
    falls most), so a colour edge's sign says nothing of the object."""
    orange = (0, 120, 255)                                           # grey 147
    pat = np.full((80, 110, 3), 30, np.uint8)
    pat[20:60, 25:85] = orange
    scene = np.full((480, 640, 3), (200, 150, 60), np.uint8)         # a blue ground, grey 129
    box = cv2.boxPoints(((380.0, 220.0), (180.0, 120.0), -30.0))
    cv2.fillPoly(scene, [np.round(box).astype(np.int32)], orange)
    grey = cv2.cvtColor(scene, cv2.COLOR_BGR2GRAY)
    p = Pattern.from_image(pat)                                      # (polarity: as painted)
    auto = Detector(p, (2.0, 4.0)).detect(grey)
    plain = Detector(p, (2.0, 4.0), config=Config(colour=False)).detect(grey)
    assert auto and _at_truth(auto[0]), [_pose(d) for d in auto]
    assert [(_pose(d), d.score, d.nfa) for d in auto] == [(_pose(d), d.score, d.nfa) for d in plain]
    det = Detector(p, (2.0, 4.0))
    assert det.pattern.polarity == "either" and p.polarity == "bright"   # (the user's kept)
    found = det.detect(scene)
    assert found and _at_truth(found[0]), [_pose(d) for d in found]
    assert Detector(p, (2.0, 4.0), config=COLOUR).detect(scene) == []    # (the sign asked for)


def test_painted_takes_the_mask_and_its_thresholds():
    from seahough.core.pattern_io import PAINTED_CHROMA, PAINTED_SHARE, painted
    img = np.full((10, 10, 3), 100.0, np.float32)
    n = int(round(PAINTED_SHARE * 100))
    flat = img.reshape(-1, 3)
    flat[:n] = (100.0, 100.0, 100.0 + PAINTED_CHROMA)              # a fifth just saturated enough
    assert painted(img, None)
    flat[0, 2] -= 1.0                                                 # one pixel fewer
    assert not painted(img, None)
    mask = np.zeros((10, 10), bool)
    mask.reshape(-1)[:n] = True                                       # the mask on the paint
    assert painted(img, mask) is True
    assert painted(img, ~mask) is False                               # ... and on the ground


def test_a_pattern_in_colour_only_is_not_found_in_a_grey_image():
    """The orange board on sand of its grey level has no grey edge: in a grey
    image (with edges of its own) the default search says "not found" and
    why, rather than failing on the pattern; alone and as one pattern of a
    Detector of several."""
    crop = np.empty((80, 110, 3), np.uint8)
    crop[:] = SAND
    crop[20:60, 25:85] = ORANGE
    grey = cv2.cvtColor(_scene(), cv2.COLOR_BGR2GRAY)
    cv2.rectangle(grey, (10, 10), (100, 80), 255, -1)             # (something to see)
    res = Detector(Pattern.from_image(crop), (2.0, 4.0)).search(grey)
    assert res.detections == [] and "colour only" in res.note and "too few edges" in res.note
    many = Detector({"board": Pattern.from_image(crop), "rect": Pattern.rectangle(60, 40)},
                    (1.0, 4.0)).search(grey)
    assert many.parts["board"].detections == [] and "colour only" in many.parts["board"].note
    assert many.parts["rect"].detections                            # (the white block)
