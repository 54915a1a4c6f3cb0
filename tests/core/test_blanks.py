"""Burned-in captions (a video overlay's timestamp on a flat box at an edge):
found, filled, and not confused with the scene's own dark or light areas.
(The blank border's tests are in test_preprocess.py.)"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import seahough
from seahough.core import blanks as B
from seahough.core.blanks import Caption, caption_boxes, fill_blanks, find_blanks, no_data

from conftest import data_path


def _scene(h=240, w=320, seed=0):
    return np.random.default_rng(seed).uniform(60, 200, (h, w)).astype(np.float32)


def _caption(img, x, y, w=120, h=16, box=0.0, ink=235.0):
    """A flat box of level ``box`` at (x, y) with a line of round 'glyphs'
    (small discs) of level ``ink`` in it."""
    img[y:y + h, x:x + w] = box
    for cx in range(x + 8, x + w - 6, 14):
        cv2.circle(img, (cx, y + h // 2), 4, float(ink), -1, cv2.LINE_AA)
    return img


@pytest.mark.parametrize("where,side", [((0, 0), "top"), ((200, 0), "top"),
                                        ((0, 224), "bottom"), ((0, 100), "left"),
                                        ((200, 110), "right")])
def test_a_caption_at_any_edge_is_found_and_filled_from_beside_it(where, side):
    img = _caption(_scene(), *where)
    x, y = where
    caps = caption_boxes(img)
    assert caps == (Caption(side, max(x - 2, 0), max(y - 2, 0), min(x + 122, 320),
                            min(y + 18, 240)),)
    out = fill_blanks(img)
    c = caps[0]
    inside = out[c.y0:c.y1, c.x0:c.x1]
    # filled: the box's lines all repeat the picture's line beside it (no step, no text)
    if side in ("top", "bottom"):
        beside = img[c.y1, c.x0:c.x1] if side == "top" else img[c.y0 - 1, c.x0:c.x1]
        assert (inside == beside[None, :]).all()
    else:
        beside = img[c.y0:c.y1, c.x1] if side == "left" else img[c.y0:c.y1, c.x0 - 1]
        assert (inside == beside[:, None]).all()
    rest = np.ones(img.shape, bool)
    rest[c.y0:c.y1, c.x0:c.x1] = False
    assert (out[rest] == img[rest]).all()                     # the picture untouched
    assert (img == _caption(_scene(), *where)).all()          # (the input not changed)


def test_a_light_caption_with_dark_text_and_a_colour_frame():
    img = _caption(_scene(), 0, 0, box=245.0, ink=10.0)
    assert [c.side for c in caption_boxes(img)] == ["top"]
    colour = np.dstack([img, img * 0.9, img * 0.8]).astype(np.float32)
    colour[:16, :120] = (250, 250, 250)
    for cx in range(7, 114, 10):
        cv2.circle(colour, (cx, 8), 4, (0, 0, 0), 1, cv2.LINE_AA)
    blanks = find_blanks(colour)
    assert [c.side for c in blanks.captions] == ["top"]
    out = fill_blanks(colour, blanks)
    assert out.shape == colour.shape and float(out[:18, :122].min()) > 40


def test_a_caption_beside_a_letterbox_bar():
    """A timestamp box touching a video's black bar (the RoboSub frames): the
    bar is the border, the box a caption inside it; both filled."""
    img = _scene(360, 480)
    img[:, :6] = 0.7
    _caption(img, 6, 0, h=14)
    blanks = find_blanks(img)
    assert blanks.border == (8, 0, 480, 360)
    assert blanks.captions == (Caption("top", 8, 0, 128, 16),)
    out = fill_blanks(img, blanks)
    assert float(out[:16, :130].min()) > 40 and float(out[:, :8].min()) > 40


def test_what_is_not_a_caption():
    # a flat dark band at an edge with nothing in it (a shadow, a bar)
    img = _scene()
    img[:16, :120] = 0
    assert caption_boxes(img) == ()
    # a box with text away from every edge (a sign in the scene)
    assert caption_boxes(_caption(_scene(), 100, 100)) == ()
    # a dark area at an edge that is textured, not flat (rock in shadow)
    img = _caption(_scene(), 0, 0)
    img[:16, :120] += np.random.default_rng(3).uniform(0, 30, (16, 120)).astype(np.float32)
    assert caption_boxes(img) == ()
    # too tall for a line of text
    assert caption_boxes(_caption(_scene(), 0, 0, w=120, h=60)) == ()
    # a drawn scene: black ground, white shapes, one of them at an edge
    drawn = np.zeros((240, 320), np.float32)
    drawn[0:30, 40:200] = 255
    cv2.circle(drawn, (160, 140), 30, 255.0, -1)
    assert find_blanks(drawn).captions == ()
    assert fill_blanks(drawn) is drawn                        # (no copy)


@pytest.mark.parametrize("case", ["valid", "narrow", "tall", "large", "small", "away",
                                  "blob", "no text", "textured"])
def test_each_rule_of_a_caption(case):
    """A valid caption, then each of its rules broken alone: no caption."""
    img = _scene()
    box = dict(valid=(0, 0, 120, 16), narrow=(0, 0, 40, 16), tall=(0, 0, 100, 30),
               large=(0, 0, 280, 15), small=(0, 0, 15, 5), away=(5, 5, 120, 16))
    if case in box:
        x, y, w, h = box[case]
        _caption(img, x, y, w, h)
        if case == "small":
            img[2, 3:12:3] = 235.0                      # (its 'text')
    elif case == "blob":       # a flat dark half disc cut by the top edge, the scene beside it
        cv2.ellipse(img, (60, 0), (60, 16), 0, 0, 180, 0.0, -1)
    elif case == "no text":
        img[:16, :120] = 0.0
    else:
        _caption(img, 0, 0)
        img[:16, :120] += np.random.default_rng(3).uniform(0, 30, (16, 120)).astype(np.float32)
    assert bool(caption_boxes(img)) == (case == "valid")


def test_two_stacked_captions_are_filled_as_one():
    """A two-line overlay on two boxes a pixel apart: one box, filled from
    beyond both (a review found the first filled from the second)."""
    img = _caption(_caption(_scene(), 0, 0, 120, 14), 0, 15, 90, 14)
    (c,) = caption_boxes(img)
    assert (c.side, c.x0, c.y0, c.x1, c.y1) == ("top", 0, 0, 122, 31)
    out = fill_blanks(img)
    assert float(out[:31, :122].min()) > 40


@pytest.mark.parametrize("kind", ["uint8", "uint16 levels 0-255", "HxWx1", "HxWx4"])
def test_captions_in_other_arrays(kind):
    img = _caption(_scene(), 0, 0)
    arr = {"uint8": lambda: img.astype(np.uint8), "uint16 levels 0-255": lambda: img.astype(np.uint16),
           "HxWx1": lambda: img[:, :, None],
           "HxWx4": lambda: np.dstack([img, img, img, np.full_like(img, 255)])}[kind]()
    blanks = find_blanks(arr)
    assert [c.side for c in blanks.captions] == ["top"]
    out = fill_blanks(arr, blanks)
    assert out.shape == arr.shape and out.dtype == arr.dtype and float(out[:18, :122].min()) > 40


def _discs(img, n=3, r=9):
    """Bright discs (the searched objects) in the scene's lower half."""
    for i in range(n):
        cv2.circle(img, (60 + 90 * i, 170), r, 250.0, -1, cv2.LINE_AA)
    return img


def test_a_caption_s_digits_are_not_found_as_objects(monkeypatch):
    """Discs searched in a frame with a timestamp of round glyphs: no
    candidate lies in the caption (its glyphs took candidate slots before),
    and the scene's discs are found. Control: with the captions left in, the
    glyphs are candidates, so the test can fail."""
    img = cv2.GaussianBlur(_discs(_caption(_scene(seed=4) * 0.3 + 60, 0, 0, w=160, h=18)),
                           (0, 0), 0.7)
    det = seahough.Detector(seahough.Pattern.circle(5, polarity="either"),
                            scale_range=(0.6, 2.5), max_results=8)

    def in_caption(c):   # (a candidate that fits a glyph: the filled box's streaks fit none)
        return c.fit.pose.ty < 22 and c.fit.pose.tx < 165 and c.fit.score >= 0.6

    res = det.search(img)
    assert res.blanks is not None and [c.side for c in res.blanks.captions] == ["top"]
    assert not any(in_caption(c) for c in res.candidates)
    assert sorted(round(d.y) for d in res.detections) == [170, 170, 170]
    monkeypatch.setattr(B, "caption_boxes", lambda image, border=None: ())
    assert sum(in_caption(c) for c in det.search(img).candidates) >= 3


def test_real_video_captions():
    """The RoboSub pool videos' timestamp box (top left, beside the
    letterbox bar) is found; no caption in real photos that have none."""
    frame = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "1032.jpg")))
    blanks = find_blanks(frame.astype(np.float32))
    assert blanks.border == (6, 0, 485, 360)
    (c,) = blanks.captions                       # (x0: 6 or 7 by the JPEG decoder)
    assert (c.side, c.y0, c.x1, c.y1) == ("top", 0, 149, 19) and c.x0 in (6, 7)
    # (1385: sun glare at the surface, a flat light blob at the top edge beside water)
    for parts in (("objects", "robosub_transdec", "images", "1375.jpg"),
                  ("objects", "robosub_transdec", "images", "1385.jpg"),
                  ("sequences", "sparus_auv_seabed"), ("sequences", "aqualoc_amphorae_wreck")):
        p = data_path(*parts)
        files = [p] if p.is_file() else sorted(p.glob("*.png")) + sorted(p.glob("*.jpg"))
        for f in files[:6]:
            img = cv2.imread(str(f))
            assert caption_boxes(img.astype(np.float32)) == (), f


def test_a_colour_search_does_not_take_a_letterbox_bar_for_a_post():
    """Searched in colour, a video frame's bars are filled as in grey (the
    border found on its grey copy) and further into its colour channels,
    where the codec smears the bar's edge (a user trial found the bar of
    RoboSub frame 1026 as a post, in colour only)."""
    frame = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "1026.jpg")))
    for colour in (False, True):
        det = seahough.Detector(seahough.Pattern.line(55, 3), scale_range=(0.6, 1.6),
                                angle_range=(80, 100), max_results=4,
                                config=seahough.Config(colour=colour))
        res = det.search(frame)
        assert res.blanks.border == (7, 0, 485, 360)
        assert not [d for d in res.detections if d.x < 12 or d.x > 480], colour


def test_an_ignored_region_is_filled_smoothly_and_its_object_not_found():
    """Config.ignore: a region filled from the picture around it (a Coons
    patch of the smoothed lines around it: no step at its sides, no streaks
    across it), so an object under it is not found, and one beside it is."""
    img = np.tile(np.linspace(60, 160, 260, dtype=np.float32), (200, 1))
    img += np.linspace(0, 30, 200, dtype=np.float32)[:, None]
    smooth = img.copy()
    cv2.rectangle(img, (40, 60), (100, 100), 230.0, -1)     # under the region
    cv2.rectangle(img, (160, 60), (220, 100), 230.0, -1)    # beside it
    region = (30, 50, 112, 112)
    blanks = find_blanks(img, [region, (250, 190, 400, 300)])
    assert blanks.ignored == (region, (250, 190, 260, 200))  # (clipped to the image)
    out = fill_blanks(img, blanks)
    x0, y0, x1, y1 = region
    assert float(np.abs(out[y0:y1, x0:x1] - smooth[y0:y1, x0:x1]).max()) < 3.0
    assert (out[:, 120:250] == img[:, 120:250]).all()
    det = seahough.Detector(seahough.Pattern.rectangle(60, 40), max_results=3)
    plain = det.detect(img)
    assert sorted(round(d.x) for d in plain) == [70, 190]
    ignored = seahough.Detector(seahough.Pattern.rectangle(60, 40), max_results=3,
                                config=seahough.Config(ignore=[region])).search(img)
    assert [round(d.x) for d in ignored.detections] == [190]
    assert ignored.blanks.ignored == (region,)


def test_a_picture_in_picture_inset_left_out_is_no_post():
    """A RoboSub frame's picture-in-picture inset: its straight left border
    is found as a post (a user trial); with the inset left out
    (Config.ignore), it is not, and nothing else comes in its place."""
    frame = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "1040.jpg")))
    pattern = seahough.Pattern.line(55, 3)

    def posts(**cfg):
        det = seahough.Detector(pattern, angle_range=(60, 120), config=seahough.Config(**cfg))
        return [(round(d.x), round(d.y)) for d in det.detect(frame)]

    assert any(335 <= x <= 350 for x, _ in posts())
    assert posts(ignore=[(340, 255, 492, 360)]) == []


@pytest.mark.parametrize("box", [(250, 150, 300, 200), (0, 0, 60, 40), (0, 80, 40, 120),
                                 (100, 0, 160, 30), (299, 0, 300, 50), (10, 10, 11, 11)])
def test_an_ignored_region_at_an_edge_or_a_corner_leaves_no_step(box):
    """A region at the image's edge or corner (an inset, the vehicle's skid),
    1 px ones too: filled with no step at its sides (a review found 10-65
    levels at the sides of boxes touching an edge, and a crash at 1 px)."""
    yy, xx = np.mgrid[0:200, 0:300].astype(np.float32)
    smooth = 60 + 0.3 * xx + 0.2 * yy + 10 * np.sin(xx / 40)
    img = smooth.copy()
    x0, y0, x1, y1 = box
    img[y0:y1, x0:x1] = 0
    out = fill_blanks(img, find_blanks(img, [box]))
    steps = max(float(np.abs(np.diff(out, axis=a)).max()) for a in (0, 1))
    assert steps < 3.5, steps
    assert (out[y0:y1, x0:x1] > 40).all()


def test_ignored_regions_beside_a_bar_each_other_and_the_whole_image():
    """Regions that overlap are one (each was filled from the other's lines);
    one reaching into a letterbox bar is filled from the picture, not the
    bar; one over the whole image leaves it flat (nothing to search), as the
    overlay and the JSON say."""
    img = _scene(240, 320)
    img[:, :8] = 0.5                                             # a letterbox bar
    blanks = find_blanks(img, [(0, 100, 60, 140), (50, 120, 90, 180)])
    assert blanks.border == (10, 0, 320, 240) and blanks.ignored == ((0, 100, 90, 180),)
    out = fill_blanks(img, blanks)
    assert float(out[100:180, 10:90].min()) > 40                 # (not from the bar's 0.5)
    flat = fill_blanks(img, find_blanks(img, [(0, 0, 320, 240)]))
    assert float(flat.min()) == float(flat.max())
    res = seahough.Detector(seahough.Pattern.rectangle(60, 40),
                            config=seahough.Config(ignore=[(0, 0, 320, 240)])).search(img)
    assert res.detections == [] and res.note == "no edges"


def _sonar_fan(pipe: bool, seed: int = 0) -> np.ndarray:
    """A forward-looking sonar's picture: speckle in a fan (110 degrees, ranges
    40-310 px), black beyond it; ``pipe``: a bright band across the fan."""
    rng = np.random.default_rng(seed)
    h, w = 320, 480
    img = cv2.GaussianBlur(rng.rayleigh(40, (h, w)).astype(np.float32), (0, 0), 1.2)
    if pipe:
        cv2.line(img, (150, 250), (330, 120), 200.0, 9, cv2.LINE_AA)
    yy, xx = np.mgrid[:h, :w]
    r = np.hypot(xx - 240, yy - 330)
    a = np.degrees(np.arctan2(xx - 240, 330 - yy))
    img[(r > 310) | (r < 40) | (np.abs(a) > 55)] = 0
    return np.clip(img, 0, 255).astype(np.uint8)


def test_the_black_beyond_a_sonar_fan_is_no_data():
    """A sonar analyst's trial: the straight sides of a forward-looking
    sonar's fan were "found" as lines (NFA 1e-12) in a fan with nothing in
    it. The flat black area joined to the picture's edge is filled from the
    fan before the search (as transparent pixels are); a pipe in the fan is
    still found, and a drawn shape's black canvas, a label mask's classes
    or a photo's dark water that fades are left as they are."""
    line = seahough.Detector(seahough.Pattern.line(120, 8), angle_range=(0, 180))
    assert line.detect(_sonar_fan(False)) == []
    found = line.detect(_sonar_fan(True))
    assert len(found) == 1 and abs(found[0].x - 252) < 6 and abs(found[0].y - 177) < 6
    blanks = find_blanks(_sonar_fan(False).astype(np.float32))
    assert blanks.no_data is not None and 0.3 < blanks.no_data.mean() < 0.5
    # a white box on a black canvas (94 % black), one beside a grey bar at the
    # edge: drawn pictures, not data beyond a picture
    canvas = np.zeros((240, 320), np.float32)
    cv2.rectangle(canvas, (100, 80), (180, 140), 200, -1)
    assert no_data(canvas) is None
    cv2.rectangle(canvas, (0, 100), (150, 239), 150, -1)
    assert no_data(canvas) is None
    # a black cable or a shadow running off the edge is scene (a reviewer saw the cable
    # filled, and no longer found); a photo turned on a black canvas has no data beyond it
    img = cv2.GaussianBlur(np.random.default_rng(0).uniform(60, 200, (240, 320)).astype(
        np.float32), (0, 0), 1)
    cable, shadow = img.copy(), img.copy()
    cv2.line(cable, (0, 60), (319, 180), 0, 12)
    shadow[100:140, 200:320] = 0
    disc = img.copy()                               # a black half-disc cut by the edge
    cv2.circle(disc, (160, 239), 50, 0, -1)
    assert no_data(cable) is None and no_data(shadow) is None and no_data(disc) is None
    assert seahough.Detector(seahough.Pattern.line(150, 12, polarity="dark"),
                             max_results=2).detect(cable)
    turned = cv2.warpAffine(img, cv2.getRotationMatrix2D((160, 120), 25, 0.8), (320, 240))
    assert 0.3 < no_data(turned).mean() < 0.45
    # the dark water in the amphora wreck's corner fades into the picture: kept
    photo = cv2.imread(str(data_path("sequences/aqualoc_amphorae_wreck/frame_060.png")), 0)
    assert no_data(photo.astype(np.float32)) is None
