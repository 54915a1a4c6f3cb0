"""Near symmetries: a marker board's frame falls on itself turned by a
quarter; the ranking lets its cells decide the turn."""

import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim
from seahough.core import detector as detector_module
from seahough.core import ranking
from seahough.core import symmetry as Y
from seahough.core.refine import Pose


@pytest.mark.parametrize("name,turns", [("board", 3), ("L", 0), ("cross", 0), ("rectangle", 0)])
def test_only_the_board_has_near_turns(name, turns):
    img, mask = sim.marker(name, 120)
    p = seahough.Pattern.from_image(img, mask=mask)
    found = p.near_turns()
    assert len(found) == turns
    if turns:
        assert sorted(round(math.degrees(t[0])) for t in found) == [90, 180, 270]
        # about the board's centre (its origin: the image centre)
        assert all(abs(t[1]) < 1.0 and abs(t[2]) < 1.0 for t in found)
    # lines and frames are never turned
    assert seahough.Pattern.line(100, 8).near_turns() == ()
    assert seahough.Pattern.from_frame(sim.seabed((120, 160), seed=1)).near_turns() == ()


@pytest.mark.parametrize("polarity", ["inverted", "either"])
def test_near_turns_whatever_the_polarity_or_the_colour(polarity):
    img, mask = sim.marker("board", 120, colour=sim.PAINTS["orange"])
    p = seahough.Pattern.from_image(img, mask=mask, polarity=polarity)
    assert len(p.near_turns()) == 3
    assert len(p.near_turns(seahough.Config(colour=True))) == 3


def test_a_masked_crop_turns_about_its_masked_part():
    img, mask = sim.marker("board", 120)
    big = np.full((200, 260), 90, np.uint8)
    big[20:20 + img.shape[0], 100:100 + img.shape[1]] = img
    big[150:190, 10:60] = 200                       # something else, outside the mask
    m = np.zeros_like(big)
    m[20:20 + img.shape[0], 100:100 + img.shape[1]] = mask
    p = seahough.Pattern.from_image(big, mask=m)
    turns = p.near_turns()
    assert len(turns) == 3
    # about the board's centre, not the middle of the whole crop
    centre = (100 + (img.shape[1] - 1) / 2 - p.origin[0], 20 + (img.shape[0] - 1) / 2 - p.origin[1])
    assert all(math.hypot(t[1] - centre[0], t[2] - centre[1]) < 1.5 for t in turns)


@pytest.mark.parametrize("w,h", [(40, 40), (60, 30), (300, 300), (600, 600), (600, 300)])
def test_exact_symmetries_of_large_shapes_are_not_near(w, h):
    # (their sampled points are not symmetric themselves: the edges are)
    assert seahough.Pattern.rectangle(w, h).near_turns() == ()


def test_turn_pose_puts_the_turned_pattern_where_the_pose_put_the_pattern():
    rng = np.random.default_rng(0)
    vx, vy = rng.uniform(-30, 30, 50), rng.uniform(-20, 20, 50)
    pose = Pose.from_params(200.0, 150.0, 1.3, math.radians(25))
    for theta, cx, cy in ((math.pi / 2, 3.0, -2.0), (math.pi, 0.0, 0.0), (1.5 * math.pi, -4, 1)):
        c, s = math.cos(theta), math.sin(theta)
        rx, ry = cx + c * (vx - cx) + s * (vy - cy), cy - s * (vx - cx) + c * (vy - cy)
        a = Y.turn_pose(pose, theta, cx, cy).map(vx, vy)
        b = pose.map(rx, ry)
        np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize("shape", [(240, 320), (960, 1280)])
def test_a_candidate_found_turned_comes_back_to_the_right_turn(monkeypatch, shape):
    """Every candidate the search ranks is handed over turned by a quarter
    (the frame fits, the cells do not): the ranking turns it back, at full
    resolution and below it (a large image searched at a smaller scale)."""
    img, mask = sim.marker("board", 120)
    pattern = seahough.Pattern.from_image(img, mask=mask)
    scene = np.full(shape, 70, np.uint8)
    truth = (shape[1] / 2 + 10.5, shape[0] / 2 - 7.5, 1.3 if shape[0] > 500 else 1.0, 35.0)
    m = seahough.geometry.pose_to_matrix(*truth, pattern.origin)
    warped = cv2.warpAffine(img, m, (shape[1], shape[0]), flags=cv2.INTER_LINEAR)
    inside = cv2.warpAffine(np.where(mask > 0, 255, 0).astype(np.uint8), m, (shape[1], shape[0]))
    scene = np.where(inside > 127, warped, scene).astype(np.uint8)
    real = ranking.rank
    turns = pattern.near_turns()

    def turned_rank(ctx, cands, gray, min_confidence):
        for c in cands:
            (theta, cx, cy), = [t for t in turns if abs(math.degrees(t[0]) - 90) < 1]
            q = Y.turn_pose(c.fit.pose, theta, cx * ctx.factor, cy * ctx.factor)
            c.fit = ranking.Fit(q, c.fit.score, c.fit.matched, c.fit.rms, c.fit.inside)
        return real(ctx, cands, gray, min_confidence)

    monkeypatch.setattr(detector_module, "rank", turned_rank)
    d = seahough.Detector(pattern, (0.8, 1.6)).detect(scene)[0]
    assert math.hypot(d.x - truth[0], d.y - truth[1]) < 1.5
    assert abs((d.angle - truth[3] + 180) % 360 - 180) < 1.5
    # (not vacuous: without the turns the quarter turn handed over stays)
    turns = pattern.near_turns()
    monkeypatch.setattr(seahough.Pattern, "near_turns", lambda self, config=None: ())
    d = seahough.Detector(pattern, (0.8, 1.6)).detect(scene)[0]
    assert abs((d.angle - truth[3] + 180) % 360 - 180) > 80


def _boards(n=16):
    """Hard board scenes (coastal and moderate water, 3 m): the cells are faint."""
    img, mask = sim.marker("board", 120, colour=sim.PAINTS["orange"])
    det = seahough.Detector(seahough.Pattern.from_image(img, mask=mask, polarity="either"),
                            (0.5, 2.0), (0.0, 360.0), config=seahough.Config(colour=True))
    for seed in range(n):
        scene, _, truth = sim.colour_marker_scene("board", paint="orange", distance=3.0,
                                                  water=("coastal", "moderate")[seed % 2],
                                                  seed=7000 + seed, source="procedural")
        yield det, scene, truth


def _right(found, truth) -> bool:
    if not found:
        return False
    d = found[0]
    da = abs((d.angle - truth.angle + 180.0) % 360.0 - 180.0)
    return math.hypot(d.x - truth.x, d.y - truth.y) <= 3.0 and da <= 5.0


def test_the_cells_decide_the_turn_of_a_board(monkeypatch):
    """On faint boards the vote often picks a turned frame; trying the turns
    finds more of them at the right angle, and never fewer."""
    with_turns = [_right(det.detect(scene), truth) for det, scene, truth in _boards()]
    monkeypatch.setattr(seahough.Pattern, "near_turns", lambda self, config=None: ())
    without = [_right(det.detect(scene), truth) for det, scene, truth in _boards()]
    assert sum(with_turns) > sum(without)
    assert sum(w and not t for w, t in zip(without, with_turns)) <= 1


def test_a_known_angle_is_never_turned(monkeypatch):
    calls = []
    real = ranking.turn_pose
    monkeypatch.setattr(ranking, "turn_pose", lambda *a: calls.append(a) or real(*a))
    img, mask = sim.marker("board", 120)
    pattern = seahough.Pattern.from_image(img, mask=mask)
    scene, _, truth = sim.marker_scene("board", seed=3)
    found = seahough.Detector(pattern, (truth.scale, truth.scale),
                              (truth.angle, truth.angle)).detect(scene)
    assert found and calls == []
    seahough.Detector(pattern).detect(scene)          # (any angle: the turns are tried)
    assert calls


def test_a_box_is_fitted_to_its_edges_whatever_its_turn():
    """A clean box turned by 30 or 45 degrees is fitted to its edges. The
    refinement iterates on 100 of the pattern's points; taken every other
    index (the points alternate between the sides), they left out the left
    side of Pattern.rectangle(60, 40), and the fit stopped a pixel off
    (score 0.79-0.83, NFA 1e-45 at 30 degrees against 1e-64 upright)."""
    from seahough.core import candidates

    def box(angle):
        img = np.full((240, 320), 40, np.uint8)
        pts = cv2.boxPoints(((160.0, 120.0), (90.0, 60.0), -angle))
        cv2.fillPoly(img, [np.round(pts).astype(np.int32)], 220)
        return img
    det = seahough.Detector(seahough.Pattern.rectangle(60, 40))
    for angle in (30.0, 45.0):
        d = det.detect(box(angle))[0]
        assert d.score >= 0.95 and math.hypot(d.x - 160.0, d.y - 120.0) < 0.5, (angle, d)
    # (the every-other-index subset that failed here fits these boxes too since
    # the shapes are drawn by area, 2026-12-06: what it guards is the subset's
    # spread over the sides, checked in test_icp_subset_spreads_over_the_sides)


#: Scenes of the coloured-marker benchmark's tune part (bench/bench_colour.py)
#: that were answered 4-12 px off (the boards also turned and a ring off in
#: scale) while their true pose scored 0.85-0.95: (marker, paint, water,
#: distance, seed, photo).
_OFF = (("board", "orange", "oceanic", 1.0, 2, "aqualoc_amphorae_wreck/frame_012.png"),
        ("board", "orange", "coastal", 2.0, 30, "sparus_auv_seabed/frame_006.png"),
        ("board", "green", "coastal", 3.0, 140, "aqualoc_amphorae_wreck/frame_012.png"),
        ("rectangle", "orange", "oceanic", 2.0, 150, "aqualoc_amphorae_wreck/frame_016.png"),
        ("rectangle", "yellow", "oceanic", 3.0, 225, "aqualoc_amphorae_wreck/frame_000.png"))


def test_a_pose_a_few_pixels_off_is_moved_onto_the_marker(monkeypatch):
    """The local vote over shifts (and a ring's scale) brings these back;
    without it at most 2 are found (within 3 px, 5 % in scale, 3 degrees). With
    128 voting points, as when these cases were collected: with the 256 of
    2026-12-06, 3 of the 5 are found without it too."""
    from seahough._data import shared_data_dir
    base = shared_data_dir()
    if base is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")

    def found(marker, paint, water, dist, seed, photo, points=128):
        img, mask = sim.marker(marker, 120, colour=sim.PAINTS[paint])
        det = seahough.Detector(seahough.Pattern.from_image(img, mask=mask, polarity="either"),
                                (0.5, 2.0),
                                config=seahough.Config(colour=True, n_pattern_points=points))
        scene, _, t = sim.colour_marker_scene(marker, (480, 640), paint=paint, water=water,
                                              distance=dist, seed=seed, size=120,
                                              source=base / "sequences" / photo)
        d = det.detect(scene)
        period = 180.0 if marker == "rectangle" else 360.0
        return bool(d) and math.hypot(d[0].x - t.x, d[0].y - t.y) <= 3.0 \
            and abs(d[0].scale / t.scale - 1) <= 0.05 \
            and abs((d[0].angle - t.angle + period / 2) % period - period / 2) <= 3.0
    assert sum(found(*case) for case in _OFF) >= 4
    with_vote_256 = sum(found(*case, points=256) for case in _OFF)
    monkeypatch.setattr(ranking, "_shifted", lambda ctx, pose, radius, points: pose)
    # (2 since the colour edges' weighting is smoothed, CHROMA_SIGMA: 0 before)
    assert sum(found(*case) for case in _OFF) <= 2
    # the default's 256 voting points: found with the vote, and 3-4 without it
    assert with_vote_256 >= 4
    assert sum(found(*case, points=256) for case in _OFF) in (3, 4)


def test_icp_subset_spreads_over_the_sides():
    """The refinement's subset of a rectangle's points covers its four sides
    about evenly (every other index left out its whole left side)."""
    from seahough.core import candidates

    pf = seahough.Pattern.rectangle(60, 40).features(1.0)
    sub = candidates.icp_subset(pf, 100)
    x, y = pf.vx[sub], pf.vy[sub]
    sides = [(x < -28).sum(), (x > 28).sum(), (y < -18).sum(), (y > 18).sum()]
    assert len(sub) <= 100 and min(sides) >= 0.12 * len(sub), sides
