"""Curved ropes: ``find_curves`` follows a bent band and reports its centre
line as a polyline.

The arcs here are drawn independently of the simulator: a band of exact
width around a circle, its cover anti-aliased over one pixel, grey levels
60 (seabed) and 200 (rope), gaussian noise; the distance from a found point
to the true centre line is then ``| |p - centre| - radius |``. The simulator's
curved and straight ropes (twisted, shaded, in water) are used as well.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as S
from seahough.core import curves as C
from seahough.errors import ParameterError

ARC = dict(centre=(160.0, 460.0), radius=300.0)    # crosses a 320x240 image


def arc_image(shape=(240, 320), centre=ARC["centre"], radius=ARC["radius"], width=8.0,
              fg=200.0, bg=60.0, noise=6.0, seed=0, gap=None):
    """A band ``width`` px wide along a circle; ``gap``: (a0, a1) degrees
    (measured from straight up, clockwise as displayed) where it is hidden."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    r = np.hypot(xx - centre[0], yy - centre[1])
    cover = np.clip(width / 2 + 0.5 - np.abs(r - radius), 0.0, 1.0)
    if gap is not None:
        ang = np.degrees(np.arctan2(xx - centre[0], centre[1] - yy))
        cover[(ang > gap[0]) & (ang < gap[1])] = 0.0
    img = bg + (fg - bg) * cover + np.random.default_rng(seed).normal(0.0, noise, shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def off_arc(points, centre=ARC["centre"], radius=ARC["radius"]):
    p = np.asarray(points, float)
    return np.abs(np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) - radius)


def along(poly, step=1.0):
    """Points every ``step`` px along a polyline."""
    out = []
    for a, b in zip(poly[:-1], poly[1:]):
        n = max(int(math.ceil(np.hypot(*(b - a)) / step)), 1)
        out.append(a + (np.arange(n) / n)[:, None] * (b - a))
    return np.vstack(out + [poly[-1:]])


def covered(truth_points, poly, tol=3.0):
    """Share of ``truth_points`` within ``tol`` px of the polyline."""
    q = along(poly, 0.5)
    d = np.hypot(truth_points[:, None, 0] - q[None, :, 0], truth_points[:, None, 1] - q[None, :, 1])
    return float((d.min(axis=1) <= tol).mean())


def test_a_drawn_arc_is_followed_along_its_centre_line():
    img = arc_image()
    curves = seahough.find_curves(img, 8)
    assert len(curves) == 1
    c = curves[0]
    d = off_arc(along(c.points))
    assert np.mean(d <= 2.0) >= 0.95 and d.max() < 3.0
    assert off_arc(c.points).max() < 1.5              # the points themselves
    # the whole visible arc is covered (it leaves the image at both sides)
    t = np.radians(np.linspace(-40, 40, 801))
    truth = np.stack([160 + 300 * np.sin(t), 460 - 300 * np.cos(t)], 1)
    truth = truth[(truth[:, 0] >= 0) & (truth[:, 0] <= 319) & (truth[:, 1] <= 239)]
    assert covered(truth, c.points) > 0.9
    assert c.flags == (C.FLAG_LEAVES_IMAGE,)
    assert abs(c.width - 8.0) < 1.0
    assert c.nfa <= 1.0 and 0.0 <= c.score <= 1.0 and c.pieces >= 5
    assert len(c.piece_nfa) == len(c.points)


def test_a_dark_cable_needs_its_polarity():
    img = arc_image(fg=40.0, bg=170.0)
    for polarity in ("dark", "either"):
        c = seahough.find_curves(img, 8, polarity=polarity)[0]
        assert off_arc(c.points).max() < 1.5 and c.length > 300
    # searched as a bright rope it is not there: nothing (not the "bright band"
    # beside it, whose two borders are the cable's and the seabed's: unbalanced)
    assert seahough.find_curves(img, 8, polarity="bright") == []


def _short_band(polarity="bright"):
    """A straight band 8 px wide and 81 px long: a piece of rope, shorter than
    the two pieces (96 px) a curve must be by default."""
    img = np.full((200, 260), 60, np.uint8)
    cv2.line(img, (90, 120), (160, 90), 200, 8, lineType=cv2.LINE_AA)
    img = np.clip(img + np.random.default_rng(0).normal(0, 6, img.shape), 0, 255)
    img = img.astype(np.uint8)
    return img if polarity == "bright" else 255 - img


def test_no_curve_says_why_and_what_to_change():
    """A user whose rope is not found learns why (a sonar user's trial: the
    table, JSON and CSV said nothing): ``declined`` receives the seed
    candidates, best first, each with its reason."""
    why = []
    assert seahough.find_curves(_short_band(), 8, declined=why) == []
    assert why and why[0].declined == ("the rope followed from this line is 81 px long, "
                                       "under min_length 96"), why[0]
    assert seahough.find_curves(_short_band(), 8, min_length=60)     # what to change
    # a dark band searched as a bright rope: a line, but no rope across it
    why = []
    assert seahough.find_curves(_short_band("dark"), 8, declined=why) == []
    assert why[0].declined.startswith("a line, but no rope across it: one border of a "
                                      "bright band 4-12 px wide"), why[0]
    assert "--polarity" in why[0].declined
    # a line whose NFA, counted over both seed searches, is over max_nfa
    why = []
    assert seahough.find_curves(_short_band(), 8, max_nfa=1e-30, declined=why) == []
    assert why and all(c.declined for c in why)
    assert any("over max_nfa 1e-30" in c.declined for c in why), [c.declined for c in why]
    # a curve found: nothing declined is said
    why = []
    assert seahough.find_curves(arc_image(), 8, declined=why) and why == []


def test_a_seed_declined_for_its_nfa_over_both_searches_says_that_nfa():
    """A sonar user's trial read "nfa 5.1e-01: NFA 1.01 (the line's, counted
    over the 2 seed searches) over max_nfa 1": two NFAs, one under the limit
    it was said to exceed. The candidate carries the NFA its reason counts."""
    import math
    from types import SimpleNamespace

    from seahough.core.candidates import Candidate
    from seahough.core.curves import _declined_seeds
    from seahough.core.nfa import Evidence

    c = Candidate(None, 10.0, 0.82, evidence=Evidence(40, 33, 0.1, math.log10(0.505)))
    res = SimpleNamespace(candidates=[c], detections=[SimpleNamespace(score=0.82, nfa=c.nfa)])
    why = "NFA 1.01 over max_nfa 1 (the line's, counted over the 2 seed searches)"
    out = _declined_seeds(res, {0: why}, 2)
    assert len(out) == 1 and out[0].declined == why and out[0].nfa == pytest.approx(1.01)
    assert c.nfa == pytest.approx(0.505)                    # (the search's own: unchanged)
    assert _declined_seeds(res, {0: why})[0].nfa == pytest.approx(0.505)   # one search


def test_dark_cables_searched_as_bright_ropes_give_nothing():
    """Simulated dark cables in water (seeds no benchmark uses): each is found
    at its own polarity; at the default (bright) none gives a curve (6 of 15
    gave one beside the cable before the seed had to show a balanced profile)."""
    for seed in range(200, 215):
        img, _ = S.curved_rope_scene(width=8, bend=30, polarity="dark", seed=seed)
        assert seahough.find_curves(img, 8) == [], seed
        assert seahough.find_curves(img, 8, polarity="dark"), seed


def test_a_tight_bend_is_followed():
    # radius 120 px = 20 rope widths: the arc turns by about 180 degrees in view
    centre = (160.0, 260.0)
    img = arc_image(centre=centre, radius=120.0, width=6.0)
    c = seahough.find_curves(img, 6)[0]
    assert off_arc(along(c.points), centre, 120.0).max() < 2.0
    assert c.length > 300


def test_a_buried_stretch_is_bridged_and_flagged():
    img = arc_image(gap=(-8.0, 4.0))                 # 63 px of the arc hidden
    c = seahough.find_curves(img, 8)[0]
    assert C.FLAG_GAP in c.flags
    assert c.length > 300
    assert off_arc(along(c.points)).max() < 2.0        # across the gap too
    bridged = [math.isnan(v) for v in c.piece_nfa[1:-1]]
    assert any(bridged)


def test_two_ropes_and_max_curves():
    two = np.maximum(arc_image(), arc_image(centre=(160.0, -220.0), seed=1))
    curves = seahough.find_curves(two, 8)
    assert len(curves) == 2
    near = sorted(min(off_arc(c.points).max(), off_arc(c.points, (160.0, -220.0)).max())
                  for c in curves)
    assert near[-1] < 1.5
    which = {int(off_arc(c.points).max() > 3.0) for c in curves}
    assert which == {0, 1}                            # one of each
    assert len(seahough.find_curves(two, 8, max_curves=1)) == 1


def test_ends_inside_the_image_and_at_its_border():
    img = np.full((100, 160), 50, np.uint8)
    img[47:54, 30:120] = 200                           # 7 px wide, x 30-119
    c = seahough.find_curves(img, 7, piece_length=40)[0]
    xs = sorted(c.points[[0, -1], 0])
    assert abs(xs[0] - 30) < 4 and abs(xs[1] - 119) < 4 and c.flags == ()
    np.testing.assert_allclose(c.points[:, 1], 50.0, atol=0.5)
    img[47:54, 30:] = 200                              # now it runs out on the right
    c = seahough.find_curves(img, 7, piece_length=40)[0]
    assert max(c.points[:, 0]) > 158 and c.flags == (C.FLAG_LEAVES_IMAGE,)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_straight_rope_still_works(seed):
    scene, truth = S.rope_scene(width=8, seed=seed, source="procedural")
    c = seahough.find_curves(scene, 8)[0]
    a = math.radians(truth.line_angle)
    n = np.array([math.sin(a), math.cos(a)])
    assert np.abs((along(c.points) - [truth.x, truth.y]) @ n).max() < 2.0
    assert c.length > 350 and C.FLAG_LEAVES_IMAGE in c.flags


def test_a_simulated_curved_rope_in_water():
    scene, truth = S.curved_rope_scene(width=8, bend=30, form="arc", water="moderate", seed=3,
                                       source="procedural")
    c = seahough.find_curves(scene, 8)[0]
    q = along(c.points)
    d = np.hypot(q[:, None, 0] - truth.points[None, :, 0],
                 q[:, None, 1] - truth.points[None, :, 1]).min(axis=1)
    assert np.mean(d <= 2.0) >= 0.9
    # (0.69 of this rope since the refinement iterates on points taken around
    # the pattern, candidates.icp_subset: 0.7 before; over the benchmark's
    # test ropes the coverage went 85 -> 86 %, docs/curves.md)
    assert covered(truth.points[truth.visible][::4], c.points) > 0.65


@pytest.mark.parametrize("seed", [0, 3])
def test_an_image_without_a_rope_gives_nothing(seed):
    scene = S.negative_scene(water="moderate", seed=seed, source="procedural")
    assert seahough.find_curves(scene, 8) == []
    assert seahough.find_curves(np.full((120, 160), 90, np.uint8), 6) == []


def test_the_image_features_are_computed_once(monkeypatch):
    from seahough.core import detector
    calls = []
    real = detector.extract_features
    monkeypatch.setattr(detector, "extract_features",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    c = seahough.find_curves(arc_image(), 8)[0]
    assert c.steps > 5 and len(calls) == 1


@pytest.mark.parametrize("kwargs, name", [
    (dict(width=0), "width"), (dict(width=-3), "width"), (dict(width="8"), "width"),
    (dict(width=float("nan")), "width"),
    (dict(width_range=(1.5, 0.5)), "width_range"), (dict(width_range=(0.1, 1.0)), "width_range"),
    (dict(width_range=3), "width_range"),
    (dict(polarity="green"), "polarity"),
    (dict(piece_length=10), "piece_length"),           # under twice the width
    (dict(min_length=-1), "min_length"),
    (dict(max_turn=0), "max_turn"), (dict(max_turn=120), "max_turn"),
    (dict(max_curves=0), "max_curves"), (dict(max_curves=1.5), "max_curves"),
    (dict(config="fast"), "config"),
    (dict(max_nfa=0), "max_nfa"), (dict(max_nfa=-1), "max_nfa"),
    (dict(declined=5), "declined"), (dict(declined=()), "declined"),
])
def test_bad_parameters_name_themselves(kwargs, name):
    args = dict(width=8)
    args.update(kwargs)
    width = args.pop("width")
    with pytest.raises(ParameterError, match=name):
        seahough.find_curves(np.zeros((60, 80), np.uint8), width, **args)


def test_curve_to_dict_round_trips_through_json():
    c = seahough.find_curves(arc_image(gap=(-8.0, 4.0)), 8)[0]
    d = json.loads(json.dumps(c.to_dict(), allow_nan=False))
    assert d["kind"] == "curve" and d["flags"] == list(c.flags)
    np.testing.assert_allclose(d["points"], c.points)
    assert d["length"] == pytest.approx(c.length) and d["width"] == pytest.approx(c.width)
    assert d["nfa"] == pytest.approx(c.nfa) and d["pieces"] == c.pieces
    assert None in d["piece_nfa"]                       # the ends, the bridged gap
    assert [v is None for v in d["piece_nfa"]] == [math.isnan(v) for v in c.piece_nfa]
    back = seahough.Curve(np.array(d["points"]), d["width"], d["score"], d["nfa"],
                          d["confidence"], tuple(d["flags"]), d["pieces"], d["steps"])
    assert back.length == pytest.approx(c.length)


def test_public_names():
    assert seahough.find_curves is C.find_curves and seahough.Curve is C.Curve
    assert {"find_curves", "Curve"} <= set(seahough.__all__)


def test_a_pipe_in_speckled_sonar_is_found_once_the_speckle_is_smoothed():
    """A soft pipeline across a forward-looking sonar crop (real data):
    speckle makes edges of its own and nothing is found; with
    Config(smooth=3) the pipe is, along its length (a user trial found the
    CLI had no way to smooth)."""
    import cv2

    from conftest import data_path

    img = cv2.imread(str(data_path("sonar", "nksid_fls", "soft_pipeline_img_62.jpg")), 0)
    assert seahough.find_curves(img, 10) == []
    [c] = seahough.find_curves(img, 10, config=seahough.Config(smooth=3.0))
    assert c.length > 150 and 8 < c.width < 13
    # its ends: the pipe runs from the lower right (140, 220) up to the left edge
    ends = sorted([tuple(c.points[0]), tuple(c.points[-1])])
    assert ends[0][0] < 15 and 60 < ends[0][1] < 110, ends
    assert ends[1][0] > 125 and ends[1][1] > 200, ends


def test_a_curve_that_leaves_the_image_ends_on_its_border():
    """Two ropes crossing the frame (a user trial): one's end was reported
    at y -4.7, outside the image, and another's start at x -5.6e-17,
    printed "-0.0"."""
    rng = np.random.default_rng(6)
    tex = cv2.GaussianBlur(rng.normal(0, 1, (480, 640)).astype(np.float32), (0, 0), 4)
    img = 90 + 25 * tex / tex.std() + rng.normal(0, 6, (480, 640))
    x = np.linspace(-20, 660, 400)
    p1 = np.stack([x, 240 + 60 * np.sin(2 * np.pi * x / 500)], 1)
    p2 = np.stack([np.linspace(150, 500, 400) + 30 * np.sin(np.linspace(0, 3, 400)),
                   np.linspace(-20, 500, 400)], 1)
    for p in (p1, p2):
        m = np.zeros((480, 640), np.uint8)
        cv2.polylines(m, [np.round(p * 16).astype(np.int32)], False, 255, 8, cv2.LINE_AA, shift=4)
        a = m.astype(np.float32) / 255
        img = img * (1 - a) + 200 * a
    curves = seahough.find_curves(np.clip(img, 0, 255).astype(np.uint8), 8)
    assert len(curves) == 2
    for c in curves:
        assert "leaves_image" in c.flags
        assert c.points.min() >= 0.0 and (c.points.max(axis=0) <= (639.0, 479.0)).all(), c.points
