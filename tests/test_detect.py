"""Recognition on scenes with exact ground truth, and on real photos."""

from __future__ import annotations

import csv
import io
import json
import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as S
from seahough.geometry import apply_matrix, pose_to_matrix

from conftest import corner_error, data_path

SHAPE = (480, 640)


def _coverage(pattern: seahough.Pattern) -> np.ndarray:
    """The shape's own pixels (anti-aliased) of a primitive pattern image."""
    return np.clip((pattern.image.astype(np.float32) - 30.0) / 200.0, 0, 1)


def _scene(pattern_img, cover, seed, *, scale_range=(0.5, 2.0), hide=0.2, water="moderate",
           shape=SHAPE):
    """A seabed scene holding the pattern at a random pose, part of it hidden."""
    rng = np.random.default_rng(seed)
    bg = S.background(shape, seed=seed, source="procedural")
    x, y, s, a = S.random_pose(rng, shape, pattern_img.shape, scale_range, (0, 360), margin=4)
    mask = np.round(cover * 255).astype(np.uint8)
    scene, truth = S.paste_pattern(bg, pattern_img, mask, x=x, y=y, scale=s, angle=a,
                                   occlusion=hide, seed=seed)
    if water:
        scene = S.apply_water(scene, water, seed=seed)
    return scene, truth


PRIMITIVES = {
    "rectangle": (lambda: seahough.Pattern.rectangle(90, 50), True),
    "polygon": (lambda: seahough.Pattern.polygon([(0, 0), (90, 0), (90, 24), (34, 24), (34, 70), (0, 70)]), False),
    "circle": (lambda: seahough.Pattern.circle(36), None),
    "ring": (lambda: seahough.Pattern.circle(40, inner_radius=24), None),
}


@pytest.mark.parametrize("name", sorted(PRIMITIVES))
def test_primitive_found_at_random_pose_with_noise_blur_and_a_fifth_hidden(name):
    # random pose (scale 0.5-2, any angle), moderate water (blur, noise, snow,
    # haze), 20 % of the shape under silt. Silt can leave a visible part that
    # is itself a smaller copy of the shape, so the bar is 7 of 8, not all.
    # The pose is judged without the NFA (max_nfa=inf); at the default
    # max_nfa=1 one more may be declined: a small shape in dense texture is
    # weak evidence (seed 11: a 90 x 50 rectangle at scale 0.6, score 0.73,
    # NFA 1.7 in the 4-D search).
    make, symmetric = PRIMITIVES[name]
    pattern = make()
    det = seahough.Detector(pattern, scale_range=(0.5, 2.0), max_nfa=math.inf)
    default = seahough.Detector(pattern, scale_range=(0.5, 2.0))
    errors, kept = [], []
    for seed in range(8):
        scene, truth = _scene(pattern.image, _coverage(pattern), 10 + seed)
        found = det.detect(scene)
        kept.append(bool(default.detect(scene)))
        if not found:
            errors.append(float("inf"))
            continue
        d = found[0]
        if symmetric is None:  # a disc or ring has no rotation: compare centre and scale
            err = math.hypot(d.x - truth.x, d.y - truth.y) + abs(d.scale - truth.scale) * pattern.extent / 2
        else:
            err = corner_error(d.matrix, truth.matrix, pattern.image.shape, symmetric=symmetric)
        errors.append(err)
    assert sum(e <= 2.0 for e in errors) >= 7, errors
    assert np.median(errors) <= 1.0, errors
    assert sum(k and e <= 2.0 for k, e in zip(kept, errors)) >= 6, (kept, errors)


def test_a_disc_is_not_a_ring():
    # a disc matches a ring's outer circle, 62 % of its points (over min_score)
    # at an NFA far below 1: the ring's hole must be seen too (core/parts.py)
    ring = seahough.Pattern.circle(40, inner_radius=25)
    disc = seahough.Pattern.circle(40)
    off = seahough.Config(search=seahough.config.SearchTuning(hole_support=0.0))
    found = {"disc": 0, "ring": 0, "disc, unchecked": 0}
    for seed in range(4):
        for name, pat in (("disc", disc), ("ring", ring)):
            scene, truth = _scene(pat.image, _coverage(pat), 40 + seed, scale_range=(0.6, 1.4),
                                  hide=0.0)
            for key, cfg in ((name, None), (f"{name}, unchecked", off)):
                if key == "ring, unchecked":
                    continue
                dets = seahough.Detector(ring, scale_range=(0.5, 2.0), config=cfg).detect(scene)
                found[key] += any(math.hypot(d.x - truth.x, d.y - truth.y) < 3 for d in dets)
    assert found == {"disc": 0, "ring": 4, "disc, unchecked": 4}, found


def test_a_declined_candidate_says_why():
    # the disc's pose, declined for the ring's unseen hole, leaves its trace
    ring = seahough.Pattern.circle(40, inner_radius=25)
    disc = seahough.Pattern.circle(40)
    scene, truth = _scene(disc.image, _coverage(disc), 40, scale_range=(0.6, 1.4), hide=0.0)
    res = seahough.Detector(ring, scale_range=(0.5, 2.0)).search(scene)
    assert res.detections == []
    why = [c.declined for c in res.candidates
           if math.hypot(c.pose.tx - truth.x, c.pose.ty - truth.y) < 3]
    assert why and why[0].startswith("its hole is not in the image"), why
    # every candidate not reported says why; a detection says nothing
    scene, truth = _scene(ring.image, _coverage(ring), 41, scale_range=(0.6, 1.4), hide=0.0)
    res = seahough.Detector(ring, scale_range=(0.5, 2.0), max_results=1).search(scene)
    assert len(res.detections) == 1
    reported = [c for c in res.candidates if not c.declined]
    assert len(reported) == 1 and len(res.candidates) > 1
    assert abs(reported[0].full.score - res.detections[0].score) < 1e-9


def test_declined_reasons_of_two_alike_objects():
    # two equal boxes, one result asked for: the second is over max_results,
    # and the first's confidence (measured against the second) too low
    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.normal(100, 12, (240, 320)).astype(np.float32), (0, 0), 1.5)
    cv2.rectangle(img, (40, 60), (99, 99), 210, -1)
    cv2.rectangle(img, (200, 140), (259, 179), 210, -1)
    box = seahough.Pattern.rectangle(60, 40)
    res = seahough.Detector(box, scale_range=(0.8, 1.25), angle_range=(0, 0), max_results=1,
                            min_confidence=0.3).search(img)
    assert res.detections == []
    why = {"left" if c.pose.tx < 160 else "right": c.declined for c in res.candidates
           if c.score > 0.9}
    # (both judged: the one over max_results too, so that it counts as "more objects may be
    # there" only when chance does not explain it)
    assert [c.nfa < 1e-6 for c in res.candidates if c.score > 0.9] == [True, True]
    assert set(why) == {"left", "right"}, why
    first, second = sorted(why.values(), key=lambda w: not w.startswith("confidence"))
    assert first.startswith("confidence ") and "under min_confidence 0.3 (a look-alike" in first
    assert second == "max_results 1 reached by better candidates", second
    assert all(c.declined for c in res.candidates)
    # with two results asked for, both are reported and say nothing
    res = seahough.Detector(box, scale_range=(0.8, 1.25), angle_range=(0, 0),
                            max_results=2).search(img)
    assert len(res.detections) == 2
    assert sum(not c.declined for c in res.candidates) == 2


def test_a_detections_own_copy_is_no_look_alike():
    """A buoy with a highlight: the highlight and the whole buoy are two
    discs of one object (the second declined as "the same object"). That
    copy is the runner-up of neither detection: before, both buoys were
    flagged ambiguous at confidence 0, the second one's against the first
    buoy's outline (5 of 37 ambiguous buoys of the RoboSub tune part)."""
    img = np.full((240, 360), 60, np.uint8)
    cv2.circle(img, (100, 120), 32, 170, -1, lineType=cv2.LINE_AA)   # a buoy
    cv2.circle(img, (94, 112), 14, 240, -1, lineType=cv2.LINE_AA)    # its highlight
    cv2.circle(img, (260, 120), 20, 170, -1, lineType=cv2.LINE_AA)   # a second buoy,
    img[95:106, 235:290] = 60                                        # its top hidden
    rng = np.random.default_rng(0)
    img = np.clip(cv2.GaussianBlur(img, (0, 0), 1.0) + rng.normal(0, 6, img.shape), 0, 255)
    det = seahough.Detector(seahough.Pattern.circle(16), scale_range=(0.5, 2.5),
                            angle_range=(0, 360), max_results=5)
    res = det.search(img.astype(np.uint8))
    copies = [c for c in res.candidates if c.declined == "the same object as a better candidate"]
    assert copies and all(c.score > 0.9 for c in copies), res.candidates
    found = {"left" if d.x < 180 else "right": d for d in res.detections}
    assert set(found) == {"left", "right"}, res.detections
    for d in found.values():
        assert "ambiguous" not in d.flags and d.confidence > 0.3, d
    # the copy's score is above the second buoy's: it would have been its runner-up
    assert max(c.score for c in copies) > found["right"].score


def test_only_an_untwisted_copy_leaves_the_runner_up():
    """A copy declined as the same object is no rival when it is a disc or
    ring, or turned under 10 degrees; a pose at the same place turned
    further stays one (the turn of a shape is an ambiguity to see), and a
    camera frame's "same object" (a third of the frame) always does."""
    import types

    from seahough.core.ranking import _copy_of

    def cand(angle):
        pose = seahough.Similarity.from_pose(50.0, 50.0, 1.0, angle)
        return types.SimpleNamespace(full=types.SimpleNamespace(pose=pose))

    ctx = lambda p: types.SimpleNamespace(pattern=p)      # noqa: E731
    L = seahough.Pattern.polygon([(0, 0), (60, 0), (60, 15), (15, 15), (15, 50), (0, 50)])
    assert _copy_of(ctx(L), cand(4.0), cand(356.0))         # (8 degrees across 0)
    assert not _copy_of(ctx(L), cand(90.0), cand(0.0))
    assert _copy_of(ctx(seahough.Pattern.circle(16)), cand(90.0), cand(0.0))
    frame = seahough.Pattern.from_frame(S.frame_pair(seed=0, source="procedural")[0])
    assert not _copy_of(ctx(frame), cand(0.0), cand(0.0))


@pytest.mark.parametrize("name", S.MARKERS)
def test_image_pattern_markers_found_in_moderate_water(name):
    img, mask = S.marker(name, 120)
    det = seahough.Detector(seahough.Pattern.from_image(img, mask=mask), scale_range=(0.5, 2.0))
    ok = 0
    for seed in range(5):
        scene, _, truth = S.marker_scene(name, SHAPE, scale_range=(0.6, 1.6), occlusion=(0.0, 0.2),
                                         water="moderate", seed=200 + seed, source="procedural")
        found = det.detect(scene)
        if found and corner_error(found[0].matrix, truth.matrix, img.shape,
                                  symmetric=name == "rectangle") <= 2.0:
            ok += 1
            assert 0.5 <= found[0].score <= 1.0
    assert ok >= 4, f"{name}: {ok}/5 within 2 px"


def test_detection_fields_follow_the_api_conventions():
    pattern = seahough.Pattern.polygon([(0, 0), (90, 0), (90, 24), (34, 24), (34, 70), (0, 70)])
    scene, truth = _scene(pattern.image, _coverage(pattern), 3, hide=0.0, water=None)
    d = seahough.Detector(pattern).detect(scene)[0]
    assert d.matrix.shape == (2, 3)
    # x, y is where the pattern origin lands; matrix maps pattern pixels
    assert apply_matrix(d.matrix, [pattern.origin])[0] == pytest.approx([d.x, d.y], abs=1e-6)
    assert d.matrix == pytest.approx(pose_to_matrix(d.x, d.y, d.scale, d.angle, pattern.origin))
    assert abs((d.angle - truth.angle + 180) % 360 - 180) < 0.5
    assert d.scale == pytest.approx(truth.scale, rel=0.01)
    assert 0.0 <= d.confidence <= 1.0 and 0.9 <= d.score <= 1.0
    # the outline is the pattern outline placed by the matrix
    assert np.allclose(d.outline[0], apply_matrix(d.matrix, pattern.outline[0]))
    # the pattern's coverage warped by the matrix lands on the bright plate in the scene
    inside = cv2.warpAffine(_coverage(pattern), d.matrix, (SHAPE[1], SHAPE[0])) > 0.99
    grey = cv2.cvtColor(scene, cv2.COLOR_BGR2GRAY).astype(float)
    assert abs(grey[inside].mean() - 230) < 15


def test_results_compare_by_value():
    """``==`` of detections, motions and curves compares their values (a
    Python user's trial: equal detections raised numpy's "truth value of an
    array is ambiguous"); a SearchResult is equal only to itself."""
    from seahough.core.curves import Curve

    pattern = seahough.Pattern.rectangle(90, 50)
    scene = S.marker_scene("board", seed=1, source="procedural")[0]
    det = seahough.Detector(pattern, max_results=2)
    a, b = det.detect(scene), det.detect(scene)
    assert a and a == b and a[0] == b[0] and not (a[0] != b[0])
    moved = seahough.Detection(**{**a[0].__dict__, "matrix": a[0].matrix + 1.0})
    assert moved != a[0] and a[0] != "a detection"
    with pytest.raises(TypeError):
        hash(a[0])                               # (mutable: unhashable, as before)
    prev, cur, _ = S.frame_pair(seed=1, source="procedural")
    assert seahough.estimate_motion(prev, cur) == seahough.estimate_motion(prev, cur)
    c = Curve(np.array([[0.0, 1.0], [5.0, 1.0]]), 4.0, 0.8, float("nan"), 0.5)
    assert c == Curve(np.array([[0.0, 1.0], [5.0, 1.0]]), 4.0, 0.8, float("nan"), 0.5)
    r = det.search(scene)
    assert r == r and r != det.search(scene)    # (identity: it holds the planes and features)


def test_nothing_confident_found_where_the_pattern_is_absent():
    img, mask = S.marker("board", 120)
    det = seahough.Detector(seahough.Pattern.from_image(img, mask=mask))
    hits = 0
    for seed in range(8):
        scene = S.negative_scene(SHAPE, water="moderate", seed=300 + seed, source="procedural")
        hits += len(det.detect(scene))
    assert hits == 0


def test_several_instances_are_all_reported_best_first():
    pattern = seahough.Pattern.polygon([(0, 0), (80, 0), (80, 22), (30, 22), (30, 60), (0, 60)])
    bg = S.background(SHAPE, seed=4, source="procedural")
    mask = np.round(_coverage(pattern) * 255).astype(np.uint8)
    poses = [(150, 140, 0.8, 20), (450, 120, 1.2, 200), (320, 360, 1.0, 290)]
    scene = bg
    for x, y, s, a in poses:
        scene, _ = S.paste_pattern(scene, pattern.image, mask, x=x, y=y, scale=s, angle=a)
    found = seahough.Detector(pattern, max_results=5).detect(scene)
    assert len(found) == 3
    assert [d.score for d in found] == sorted((d.score for d in found), reverse=True)
    for x, y, s, a in poses:
        assert min(math.hypot(d.x - x, d.y - y) for d in found) < 1.5


def test_known_scale_and_rotation_is_the_fast_2d_case():
    pattern = seahough.Pattern.rectangle(70, 40)
    scene, truth = _scene(pattern.image, _coverage(pattern), 5, hide=0.1)
    det = seahough.Detector(pattern, scale_range=(truth.scale, truth.scale),
                            angle_range=(truth.angle, truth.angle))
    res = det.search(scene)
    d = res.detections[0]
    assert d.scale == pytest.approx(truth.scale) and d.angle == pytest.approx(truth.angle % 360)
    assert math.hypot(d.x - truth.x, d.y - truth.y) < 1.0
    assert res.planes.scale_angle.shape == (1, 1)
    # the 2-D case keeps Config.n_keypoints_2d key points; a search over scales the full N
    cfg = seahough.Config()
    assert len(res.features.keypoints) == cfg.n_keypoints_2d < cfg.n_keypoints
    full = seahough.Detector(pattern, scale_range=(0.5, 2.0)).search(scene)
    assert len(full.features.keypoints) == cfg.n_keypoints
    same = seahough.Detector(pattern, (truth.scale, truth.scale), (truth.angle, truth.angle),
                             config=cfg.replace(n_keypoints_2d=None)).search(scene)
    assert len(same.features.keypoints) == cfg.n_keypoints


@pytest.mark.parametrize("voting", ["oriented", "points", "segments"])
def test_every_voting_mode_finds_an_unscaled_marker(voting):
    # "segments" (equation 5 on short segments) measures scale poorly, so
    # all modes are compared at scale 1 where each must work
    pattern = seahough.Pattern.polygon([(0, 0), (90, 0), (90, 24), (34, 24), (34, 70), (0, 70)])
    scene, truth = _scene(pattern.image, _coverage(pattern), 8, scale_range=(1.0, 1.0), hide=0.0)
    det = seahough.Detector(pattern, scale_range=(0.8, 1.25), config=seahough.Config(voting=voting))
    d = det.detect(scene)[0]
    assert corner_error(d.matrix, truth.matrix, pattern.image.shape) < 2.0


def test_accumulator_planes_are_arrays_with_the_peak_at_the_object():
    pattern = seahough.Pattern.rectangle(80, 50)
    scene, truth = _scene(pattern.image, _coverage(pattern), 21, hide=0.0)
    res = seahough.Detector(pattern).search(scene)
    pl = res.planes
    assert pl.xy.shape == (pl.y.size, pl.x.size)
    assert pl.scale_angle.shape == (pl.scales.size, pl.angles.size)
    iy, ix = np.unravel_index(np.argmax(pl.xy), pl.xy.shape)
    assert math.hypot(pl.x[ix] - truth.x, pl.y[iy] - truth.y) < 12
    k, a = np.unravel_index(np.argmax(pl.scale_angle), pl.scale_angle.shape)
    assert abs(math.log(pl.scales[k] / truth.scale)) < 0.2
    assert abs((pl.angles[a] - truth.angle + 90) % 180 - 90) < 12  # symmetric rectangle


def test_rope_reports_direction_and_offset_not_a_made_up_point():
    scene, truth = S.rope_scene(SHAPE, width=10, water="moderate", seed=5, source="procedural")
    det = seahough.Detector(seahough.Pattern.line(200, 10), scale_range=(0.7, 1.4))
    d = det.detect(scene)[0]
    assert d.kind == "line" and "position_along_line_undetermined" in d.flags
    assert abs((d.line_angle - truth.line_angle + 90) % 180 - 90) < 1.0
    assert abs(abs(d.line_offset) - abs(truth.line_offset)) < 2.0
    # the reported point is on the rope, nearest the image centre
    assert math.hypot(d.x - truth.x, d.y - truth.y) < 3.0


def test_fragment_of_a_real_frame_found_in_a_rotated_rescaled_degraded_copy():
    path = data_path("sequences", "aqualoc_amphorae_wreck", "frame_040.png")
    photo = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    h, w = photo.shape
    patch = photo[220:400, 380:560].copy()   # 180x180 px of wreck and amphorae
    pattern = seahough.Pattern.from_image(patch)
    s, a = 0.8, 137.0
    centre = ((w - 1) / 2, (h - 1) / 2)
    m = cv2.getRotationMatrix2D(centre, a, s)   # OpenCV: positive = counter-clockwise
    m[:, 2] += [60, -20]
    copy = cv2.warpAffine(photo, m, (w, h), borderMode=cv2.BORDER_REFLECT)
    copy = S.apply_water(copy, "moderate", seed=3)
    truth = np.vstack([m, [0, 0, 1]]) @ np.vstack([pose_to_matrix(470 - 0.5 + 0.5, 310 - 0.5 + 0.5, 1, 0, (89.5, 89.5)), [0, 0, 1]])
    found = seahough.Detector(pattern, scale_range=(0.6, 1.5)).detect(copy)
    assert found
    assert corner_error(found[0].matrix, truth[:2], patch.shape) <= 2.0


@pytest.mark.parametrize("seed", [20000, 20020, 20033])
def test_clear_photo_patch_is_found_through_water_with_the_default_threshold(seed):
    # the patch is cut from the clear photo, the view comes through moderate
    # water: without Config.pattern_blur these true poses scored 0.43-0.45 at
    # full resolution, under the default min_score 0.5 (bench: fragment task).
    # Real photos: the procedural seabed's texture is too clean to show it.
    data_path("seabed")
    side = int(np.random.default_rng(seed).integers(120, 201))
    scene, patch, truth = S.fragment_scene(size=(side, side), scale_range=(0.75, 1.33),
                                           water="moderate", seed=seed)
    pattern = seahough.Pattern.from_image(patch)
    found = seahough.Detector(pattern, (0.7, 1.4)).detect(scene)
    assert found, "not found with the default min_score"
    assert corner_error(found[0].matrix, truth.matrix, patch.shape) <= 2.0
    sharp = seahough.Detector(pattern, (0.7, 1.4), config=seahough.Config(pattern_blur=0.0),
                              min_score=0.0).detect(scene)
    assert corner_error(sharp[0].matrix, truth.matrix, patch.shape) <= 2.0
    assert found[0].score > sharp[0].score + 0.05  # the blur is what lifts the score


def test_pose_refined_outside_the_searched_ranges_is_flagged():
    # a 100x60 plate at scale 1 and 30 degrees, searched just beside it:
    # refinement reaches the true pose, and says it lies outside the ranges
    img = np.full((240, 320), 40, np.uint8)
    box = cv2.boxPoints(((160.0, 120.0), (100.0, 60.0), -30.0))
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], 220)
    pattern = seahough.Pattern.rectangle(100, 60)
    flag = seahough.core.detector.FLAG_OUTSIDE_RANGE
    inside = seahough.Detector(pattern, scale_range=(0.5, 2.0)).detect(img)
    assert inside and flag not in inside[0].flags
    small = seahough.Detector(pattern, scale_range=(1.1, 1.5)).detect(img)
    assert small and abs(small[0].scale - 1.0) < 0.03 and flag in small[0].flags
    turned = seahough.Detector(pattern, scale_range=(1, 1), angle_range=(40, 60)).detect(img)
    assert turned and abs((turned[0].angle - 30 + 90) % 180 - 90) < 1 and flag in turned[0].flags
    assert flag not in seahough.Detector(pattern, (1, 1), (20, 40)).detect(img)[0].flags


def test_polarity_bright_dark_or_either():
    # a dark plate on bright sand: found by polarity "dark" and "either", while
    # "bright" (a bright plate expected) does not find it
    pattern_img = seahough.Pattern.polygon([(0, 0), (90, 0), (90, 24), (34, 24), (34, 70), (0, 70)]).image
    bg = np.full((SHAPE[0], SHAPE[1], 3), 200, np.uint8)
    noise = np.random.default_rng(0).normal(0, 4, bg.shape)
    mask = np.round(np.clip((pattern_img.astype(np.float32) - 30) / 200, 0, 1) * 255).astype(np.uint8)
    dark_plate = np.full_like(pattern_img, 40)
    scene, truth = S.paste_pattern(np.clip(bg + noise, 0, 255).astype(np.uint8), dark_plate, mask,
                                   x=300, y=220, scale=1.2, angle=35)
    poly = [(0, 0), (90, 0), (90, 24), (34, 24), (34, 70), (0, 70)]
    for polarity, expect in (("dark", True), ("either", True), ("bright", False)):
        found = seahough.Detector(seahough.Pattern.polygon(poly, polarity=polarity)).detect(scene)
        hit = bool(found) and math.hypot(found[0].x - 300, found[0].y - 220) < 1.0 \
            and abs((found[0].angle - 35 + 180) % 360 - 180) < 0.5
        assert hit == expect, (polarity, found[:1])
    # an image pattern taken from a bright plate finds the dark one when inverted
    found = seahough.Detector(seahough.Pattern.from_image(pattern_img, polarity="inverted")).detect(scene)
    assert found and math.hypot(found[0].x - 300, found[0].y - 220) < 1.0


def test_a_second_post_is_refined_not_lost_behind_the_first():
    """A long post puts a ridge of accumulator peaks along itself; the second
    gate post of RoboSub frame 538 (x ~ 226) used to get no candidate at all."""
    img = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "538.jpg")))
    det = seahough.Detector(seahough.Pattern.line(120, 12, polarity="either"), (0.5, 2.0),
                            (60.0, 120.0), max_nfa=math.inf, min_score=0.0)
    r = det.search(img)
    xs = [c.fit.pose.tx / r.factor for c in r.candidates]
    assert any(abs(x - 70) < 15 for x in xs) and any(abs(x - 226) < 25 for x in xs), xs
    found = [d.x for d in r.detections]
    assert any(abs(x - 70) < 10 for x in found) and any(abs(x - 226) < 10 for x in found)


def test_drawn_shapes_are_found_at_their_own_size():
    """Shapes are drawn by the area of each pixel they cover: a 60 x 40 box
    is found at scale 1 (cv2's anti-aliased fill drew the pattern 1.4 px too
    wide: 0.973), a disc of radius 16 by circle(16) at 1 (0.95 before)."""
    img = np.full((300, 400), 30, np.uint8)
    img[100:140, 150:210] = 230                     # 60 x 40 px, centre (179.5, 119.5)
    d = seahough.Detector(seahough.Pattern.rectangle(60, 40), (0.5, 2.0)).detect(img)[0]
    assert d.scale == pytest.approx(1.0, abs=0.005)
    assert (d.x, d.y) == (pytest.approx(179.5, abs=0.15), pytest.approx(119.5, abs=0.15))
    # a disc of radius 16 centred on pixel (200, 150), by area (8 x 8 samples a pixel)
    fine = np.zeros((300 * 8, 400 * 8), np.float32)
    cv2.circle(fine, (200 * 8 + 4, 150 * 8 + 4), 16 * 8, 1.0, -1)
    cover = cv2.resize(fine, (400, 300), interpolation=cv2.INTER_AREA)
    img = np.round(30 + 200 * cover).astype(np.uint8)
    d = seahough.Detector(seahough.Pattern.circle(16), (0.5, 2.0)).detect(img)[0]
    assert d.scale == pytest.approx(1.0, abs=0.01)


def test_more_results_asked_than_candidates_are_found():
    # 12 discs, 10 asked for: the search refined Config.n_candidates (7) and found 7
    rng = np.random.default_rng(1)
    img = cv2.GaussianBlur(rng.normal(100, 10, (480, 640)).astype(np.float32), (0, 0), 1.2)
    for y in (100, 240, 380):
        for x in (100, 240, 380, 520):
            cv2.circle(img, (x, y), 20, 220, -1)
    disc = seahough.Pattern.circle(20)
    for n, want in ((5, 5), (10, 10), (15, 12)):
        dets = seahough.Detector(disc, scale_range=(0.5, 2), max_results=n).detect(img)
        assert len(dets) == want, (n, len(dets))
        assert all(abs(d.scale - 1) < 0.05 for d in dets)


def _letterboxed(seed=3):
    """A 492x360 video frame of a murky pool: soft texture, a bright post
    12 px wide at x = 250, black bars 6 px wide at both sides (JPEG noise)."""
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur(rng.uniform(0, 255, (360, 492)).astype(np.float32), (0, 0), 4)
    img = 70 + (img - img.mean()) * 3.0
    img[100:300, 244:256] += 90
    img[:, :6] = rng.uniform(0, 2, (360, 6))
    img[:, -6:] = rng.uniform(0, 2, (360, 6))
    return np.clip(img, 0, 255).astype(np.uint8)


def test_letterbox_bars_of_a_video_frame_are_no_lines():
    """The step from a black letterbox bar to the picture is a long straight
    edge on every frame of such a video: no post, line or rope is reported
    there (the image's blank border is filled from its content), and the
    post in the picture is still found where it is."""
    img = _letterboxed()
    det = seahough.Detector(seahough.Pattern.line(120, 12), (0.5, 2.0), (60.0, 120.0))
    found = det.detect(img)
    assert found and abs(found[0].x - 250) < 3
    assert all(12 < d.x < 480 for d in found), [(d.x, d.y, d.nfa) for d in found]
    # several patterns at once: the same
    both = seahough.Detector({"post": det, "disc": seahough.Detector(seahough.Pattern.circle(16))})
    assert all(12 < d.x < 480 for d in both.detect(img) if d.pattern == "post")


def test_letterbox_bars_of_real_pool_video_are_no_gate_posts():
    """RoboSub pool frames with black side bars (6 px): searched for gate
    posts as lines, no detection lies on a bar's edge (each frame had one or
    two there, at NFA down to 5e-10)."""
    det = seahough.Detector(seahough.Pattern.line(120, 12), (0.5, 2.0), (60.0, 120.0))
    for n in (1024, 1026, 1030, 1033):
        img = cv2.imread(str(data_path("objects", "robosub_transdec", "images", f"{n}.jpg")))
        w = img.shape[1]
        for d in det.detect(img):
            assert 15 < d.x < w - 15, (n, d.x, d.y, d.nfa)



def _buoy_box(n, label="buoy_green"):
    import re

    xml = data_path("objects", "robosub_transdec", "annotations", f"{n}.xml").read_text()
    for obj in re.findall(r"<object>(.*?)</object>", xml):
        if f"<name>{label}</name>" in obj:
            return [int(re.search(f"<{k}>(\\d+)</{k}>", obj).group(1))
                    for k in ("xmin", "ymin", "xmax", "ymax")]
    return None


def test_a_painted_crop_of_a_video_frame_is_searched_in_grey_when_colour_finds_nothing():
    """A green buoy cut from a RoboSub pool frame (a circle for its mask) is
    painted (saturated), so it is searched by its colour edges; in the next
    frames those do not show it (the video's colour is coarser than its
    grey) and a user trial found it in 1 of 27 frames. Its grey edges do:
    found in its labelled box, flagged found_in_grey, at twice the grey
    search's NFA (two searches); never when colour is asked for."""
    frame = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "1040.jpg")))
    mask = np.zeros((69, 53), np.uint8)
    cv2.circle(mask, (26, 26), 24, 255, -1)
    pattern = seahough.Pattern.from_image(frame[176:245, 270:323], mask=mask)
    assert pattern.painted
    auto = seahough.Detector(pattern, (0.3, 2.0))
    grey = seahough.Detector(pattern, (0.3, 2.0), config=seahough.Config(colour=False))
    for n in (1044, 1046, 1047):
        path = data_path("objects", "robosub_transdec", "images", f"{n}.jpg")
        img = cv2.imread(str(path))
        res = auto.search(str(path))                 # (a path: decoded once for both)
        x0, y0, x1, y1 = _buoy_box(n)
        best = res.detections[0]
        assert x0 <= best.x <= x1 and y0 <= best.y <= y1, (n, best.x, best.y)
        assert "found_in_grey" in best.flags
        twin = grey.detect(img)[0]
        assert (twin.x, twin.y) == (best.x, best.y) and math.isclose(best.nfa, 2 * twin.nfa)
        # its candidate says the same NFA (both searches counted there too)
        [c] = [c for c in res.candidates if not c.declined and c.pose.tx == best.x]
        assert math.isclose(c.nfa, best.nfa)
    # max_nfa is judged on the doubled NFA: under twice the grey NFA, declined, and
    # the reason names it
    tight = seahough.Detector(pattern, (0.3, 2.0), max_nfa=1.5 * twin.nfa)
    res = tight.search(img)
    assert res.detections == []
    assert any(c.declined.startswith("NFA") and math.isclose(c.nfa, 2 * twin.nfa)
               for c in res.candidates), [(c.nfa, c.declined) for c in res.candidates]


def test_a_painted_crop_of_a_photo_is_searched_at_its_own_polarity():
    """A crop of a RoboSub pool frame is painted (the water's green), so it
    is searched by its colour edges; a marker painted on some ground is
    searched at either polarity (its ground is not the scene's), but a
    photo's crop brings its ground along. A team's crop of the gate, at
    either polarity, was not found in the frame it was cut from: a wrong
    pose at 0.55, unflagged, at every range tried; at its own, score 0.95."""
    frame = cv2.imread(str(data_path("objects", "robosub_transdec", "images", "1380.jpg")))
    pattern = seahough.Pattern.from_image(frame[50:295, 55:525])
    assert pattern.painted and not pattern.has_long_borders(seahough.Config(colour=True))
    for scales, angles in (((0.4, 1.5), (-15, 15)), ((0.9, 1.1), (-5, 5))):
        det = seahough.Detector(pattern, scales, angles)
        assert det.pattern.polarity == "bright"
        [best] = det.detect(frame)[:1]
        assert math.hypot(best.x - 289.5, best.y - 172.0) < 1.5 and best.score > 0.9
    # a painted marker (long borders) is still searched at either polarity
    img, mask = S.marker("cross", 120, colour=S.PAINTS["orange"])
    marker = seahough.Pattern.from_image(img, mask=mask)
    assert marker.painted and seahough.Detector(marker).pattern.polarity == "either"


def test_transparent_pixels_of_a_searched_image_are_no_data(tmp_path):
    """A photo turned 12 degrees onto a transparent canvas (an orthomosaic
    tile): its border against the canvas was found as a rectangle three
    times (NFA down to 1e-42, a user trial), and what lay under transparent
    pixels was searched. They are filled from the picture (and the blend
    at its border, a dark outline): no edge there; the picture's own
    objects are found where they are."""
    rng = np.random.default_rng(5)
    photo = cv2.GaussianBlur(rng.uniform(60, 190, (300, 400, 3)), (0, 0), 2).astype(np.uint8)
    cv2.circle(photo, (120, 200), 18, (230, 230, 230), -1)
    m = cv2.getRotationMatrix2D((200, 150), 12, 1.0)
    m[:, 2] += (150, 100)
    tile = cv2.warpAffine(cv2.cvtColor(photo, cv2.COLOR_BGR2BGRA), m, (700, 500),
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0))
    cv2.imwrite(str(tmp_path / "tile.png"), tile)
    rect = seahough.Detector(seahough.Pattern.rectangle(400, 300), (0.9, 1.1))
    assert rect.detect(str(tmp_path / "tile.png")) == []
    assert rect.detect(tile[..., :3]) != []            # (the same pixels, alpha dropped)
    found = seahough.Detector(seahough.Pattern.circle(18), (0.9, 1.1)).detect(tile)
    x, y = m @ (120, 200, 1)
    assert found and math.hypot(found[0].x - x, found[0].y - y) < 1.0
    # the canvas and the dark blend at the picture's border are gone from what is searched
    from seahough.io.images import to_gray, to_image
    lo = float(cv2.cvtColor(photo, cv2.COLOR_BGR2GRAY).min())
    assert float(to_gray(tile).min()) > lo - 3 and float(to_image(tile, True).min()) > 0
    # a cut-out pattern is not filled: the step to its transparent pixels is its outline
    # (a flat star on a transparent canvas had no edges left, a reviewer's find)
    star = np.zeros((120, 120, 4), np.uint8)
    pts = np.array([(60 + (50 if k % 2 == 0 else 20) * math.cos(math.pi * k / 5 - math.pi / 2),
                     60 + (50 if k % 2 == 0 else 20) * math.sin(math.pi * k / 5 - math.pi / 2))
                    for k in range(10)], np.int32)
    cv2.fillPoly(star, [pts], (150, 150, 150, 255))
    scene = np.full((300, 400, 3), 60, np.uint8)
    cv2.fillPoly(scene, [pts + (140, 90)], (150, 150, 150))
    found = seahough.Detector(seahough.Pattern.from_image(star), (0.9, 1.1), (-10, 10)).detect(scene)
    assert found and math.hypot(found[0].x - 200, found[0].y - 150) < 1.5


def test_a_detections_record_holds_its_outline_and_box():
    """JSON consumers (a RoboSub team) got no box or outline: they worked
    them out from the matrix. to_dict (and so --json) gives both."""
    img = np.full((200, 260), 70, np.uint8)
    cv2.rectangle(img, (60, 50), (179, 129), 190, -1)        # 120 x 80, centre (119.5, 89.5)
    d = seahough.Detector(seahough.Pattern.rectangle(120, 80), (0.9, 1.1), (0, 10)).detect(img)[0]
    rec = d.to_dict()
    assert rec["box"] == pytest.approx([59.5, 49.5, 179.5, 129.5], abs=1.0)
    assert len(rec["outline"]) == 1 and len(rec["outline"][0]) == 4
    json.dumps(rec, allow_nan=False)


def test_a_candidate_chance_explains_is_no_more_objects_hint():
    """An archaeologist's trial: an amphora (an ellipse, 60 x 100) in a wreck
    frame with max_results=1 said "2 more candidates over --min-score left
    out by --max-results: more objects may be there"; with 2, both were
    declined by their NFA (67 and 6680). A candidate left out by
    max_results is now judged first: only those chance does not explain are
    counted."""
    t = np.linspace(0, 2 * math.pi, 20, endpoint=False)
    ellipse = list(zip(30 + 30 * np.sin(t), 50 + 50 * np.cos(t)))
    det = seahough.Detector(seahough.Pattern.polygon(ellipse, polarity="dark"), (0.6, 1.6),
                            max_results=1, min_score=0.35)
    res = det.search(str(data_path("sequences", "aqualoc_amphorae_wreck", "frame_060.png")))
    assert len(res.detections) == 1
    for c in res.candidates:
        if c.declined.startswith("max_results"):
            assert c.evidence.nfa <= 1.0, c.evidence.nfa
    assert all(c.evidence.nfa > 1 for c in res.candidates if c.declined.startswith("NFA"))


def test_counting_many_objects_finds_them_and_says_when_the_list_was_cut(tmp_path):
    """A scientist's trial: 40 rings drawn on a real seabed photo, searched with
    max_results 50: 1,200 key points left the fainter ones without any (about
    half found, each at confidence 1, no flag). A search for more than 5
    results takes 240 key points for each. And with fewer results asked for
    than objects there, the result says how many candidates were left out."""
    from seahough import Config, Detector, Pattern

    photo = cv2.imread(str(data_path("sequences/dtu_seabed_pair/scene1.png")))
    img = cv2.resize(photo, (640, 480), interpolation=cv2.INTER_AREA)
    rng = np.random.default_rng(3)
    pts = []
    while len(pts) < 40:
        x, y, r = rng.uniform(25, 615), rng.uniform(25, 455), rng.uniform(12, 20)
        if all(math.hypot(x - a, y - b) > 1.3 * (r + c) for a, b, c in pts):
            pts.append((x, y, r))
    for x, y, r in pts:
        level = int(rng.uniform(150, 230))
        cv2.circle(img, (round(16 * x), round(16 * y)), round(16 * r), (level,) * 3, -1,
                   cv2.LINE_AA, 4)
        hole = cv2.resize(photo, (640, 480), interpolation=cv2.INTER_AREA)   # (the seabed shows)
        m = np.zeros(img.shape[:2], np.uint8)
        cv2.circle(m, (round(16 * x), round(16 * y)), round(16 * 0.6 * r), 255, -1, cv2.LINE_AA, 4)
        img[m > 127] = hole[m > 127]
    ring = Pattern.circle(15, inner_radius=9)

    def found(det):
        res = det.search(img)
        hit = {i for d in res.detections for i, (x, y, r) in enumerate(pts)
               if math.hypot(d.x - x, d.y - y) < 0.5 * r}
        return res, len(hit), len(res.detections) - len(hit)

    res, hits, false = found(Detector(ring, (0.6, 1.6), max_results=50))
    assert hits >= 36 and false == 0, (hits, false)
    assert res.left_out == 0
    few, hits_few, _ = found(Detector(ring, (0.6, 1.6), max_results=50,
                                      config=Config(n_keypoints=1201)))   # (~ as before)
    assert hits_few < hits - 5, (hits_few, hits)
    cut, _, _ = found(Detector(ring, (0.6, 1.6), max_results=10))
    assert len(cut.detections) == 10 and cut.left_out >= 1


def test_a_thick_line_in_a_large_photo_is_searched_where_its_band_has_edges():
    """A trial of the pictures: a 690 x 33 px post in a 4000 x 2250 photo
    (``line:690,33``) failed, "0 edge segments at scale 0.08": brought to
    320 px the band was 1.3 px across at the smallest scale searched, its two
    borders merged. It is searched where the band keeps 3 px."""
    rng = np.random.default_rng(1)
    img = cv2.GaussianBlur(rng.normal(90, 12, (2250, 4000)).astype(np.float32), (0, 0), 3)
    img[700:1500, 1900:1933] += 90           # a post 33 px wide, 800 px long
    det = seahough.Detector(seahough.Pattern.line(690, 33), max_results=1)
    res = det.search(np.clip(img, 0, 255).astype(np.uint8))
    assert res.factor > 0.15 and len(res.detections) == 1, res.factor
    d = res.detections[0]
    assert abs(d.line_angle - 90.0) < 2.0 and abs(d.x - 1916) < 4, (d.x, d.line_angle)
    # a band that keeps its edges at the usual scale is searched there, as before
    assert seahough.Detector(seahough.Pattern.line(120, 12)).working_factor((480, 640)) == 0.5
    # a thicker band, with edges at scale 1 but 1.6 px at the smallest scale, in an
    # image brought down 12 times: 3 px at the smallest scale too (a review)
    assert seahough.Detector(seahough.Pattern.line(690, 40)).working_factor(
        (2250, 4000)) == pytest.approx(3.0 / (40 * 0.5))


def test_key_points_for_many_results_also_at_a_known_scale():
    """A search for many results takes 240 key points for each, also at a
    known scale and rotation (tags of one size: the paper's 2-D case, which
    keeps Config.n_keypoints_2d otherwise); a Config's own count is kept."""
    disc = seahough.Pattern.circle(15)
    n = lambda det: det._n_keypoints((480, 640), 0.5)   # noqa: E731
    assert n(seahough.Detector(disc, (1, 1))) == seahough.Config().n_keypoints_2d
    assert n(seahough.Detector(disc, (1, 1), max_results=40)) == 240 * 40
    assert n(seahough.Detector(disc, (0.5, 2), max_results=40)) == 240 * 40
    assert n(seahough.Detector(disc, (0.5, 2), max_results=200)) == 20_000
    assert n(seahough.Detector(disc, (0.5, 2), max_results=40,
                               config=seahough.Config(n_keypoints=1500))) is None
    assert n(seahough.Detector(disc, (1, 1), max_results=40,
                               config=seahough.Config(n_keypoints_2d=300))) == 300


def test_counting_does_not_judge_a_half_buried_object_against_a_clean_one():
    """A scientist's trial: a half-buried disc (55 % in view) was found alone,
    and declined beside a clean disc elsewhere in the image ("under 0.6 x the
    best candidate's, the least that could win"). With many results asked
    for, every candidate that could pass min_score is finished."""
    photo = cv2.imread(str(data_path("sequences/dtu_seabed_pair/scene1.png")))
    bg = cv2.resize(photo, (640, 480), interpolation=cv2.INTER_AREA)
    found = 0
    for x, y in ((320, 240), (450, 300), (250, 380), (500, 100)):
        img = bg.copy()
        cv2.circle(img, (x, y), 15, (230,) * 3, -1, cv2.LINE_AA)
        y0 = round(y - 15 + 2 * 15 * 0.55)
        img[y0:y + 18, x - 18:x + 19] = bg[y0:y + 18, x - 18:x + 19]     # buried below
        cv2.circle(img, (150, 120), 15, (230,) * 3, -1, cv2.LINE_AA)    # a clean disc
        det = seahough.Detector(seahough.Pattern.circle(15), max_results=10, min_score=0.3,
                                max_nfa=1e3)
        found += any(abs(d.x - x) < 6 and abs(d.y - y) < 6 for d in det.detect(img))
    assert found >= 3, found


def test_counting_keeps_an_object_found_when_fewer_results_are_asked_for():
    """An archaeologist's trial: an amphora (a 20-sided ellipse, 60 x 100 px)
    in a wreck photo was found with ``max_results`` 5, lost with 10 and 15
    (the clutter of the extra key points lifted a larger, turned pose over its
    own accumulator cell, and the clutter's seeds took every candidate place),
    and found again with 20. Asking for more results never loses it."""
    photo = str(data_path("sequences/aqualoc_amphorae_wreck/frame_060.png"))
    t = np.radians(np.arange(20) * 18.0)
    amphora = seahough.Pattern.polygon(np.c_[np.round(30 + 30 * np.cos(t)),
                                             np.round(50 + 50 * np.sin(t))], polarity="dark")
    for n in (5, 10, 15, 20):
        det = seahough.Detector(amphora, (0.6, 1.6), max_results=n, min_score=0.35)
        assert any(math.hypot(d.x - 216, d.y - 427) < 5 for d in det.detect(photo)), n


def test_counting_does_not_give_fewer_detections_for_more_results():
    """Small dark ellipses (rubble) in a side-scan tile: once counting refined
    every seed, a sonar analyst saw 4 detections with ``-n 5`` and 2 with
    ``-n 6``: speckle candidates that chance explains (high score, NFA in the
    hundreds) took every place of the full-resolution finish. Counting,
    those go last."""
    tile = str(data_path("sonar/sdvd_sidescan/example_rubble.jpg"))
    rubble = seahough.Pattern.ellipse(8, 5, polarity="dark")
    before = None
    for n in (5, 6, 7, 8):
        det = seahough.Detector(rubble, max_results=n, config=seahough.Config(smooth=1.5))
        dets = det.detect(tile)
        found = [(d.x, d.y) for d in dets]
        if before is not None:
            assert all(any(math.hypot(x - u, y - v) < 3 for u, v in found)
                       for x, y in before), (n, before, found)
        before = found
    assert len(before) >= 4
    # and a candidate that chance explains is no rival: with every seed refined, the
    # speckle's made every stone ambiguous (confidence 0), a reviewer's find
    assert sum(d.confidence > 0.5 for d in dets) >= 4, [d.confidence for d in dets]


@pytest.mark.parametrize("noise", [0.0, 2.0, 6.0, 10.0])
def test_a_lines_visible_extent_holds_in_noise(noise):
    """A rope 140 px long (x 60-200) on a flat ground: its segment, reported
    data since the overlay's extent became ``Detection.segment``, stretched
    to 180-300 px in grain of 2-10 levels (a reviewer's find: chance edges
    passed the threshold, and gaps of 5 % of the diagonal were crossed)."""
    for seed in (0, 1, 2):
        rng = np.random.default_rng(seed)
        img = np.full((240, 320), 90, np.float32)
        img[116:125, 60:201] = 200
        img = np.clip(img + rng.normal(0, noise, img.shape), 0, 255).astype(np.uint8)
        det = seahough.Detector(seahough.Pattern.line(100, 9), angle_range=(0, 180),
                                max_results=1).detect(img)
        assert det and det[0].segment is not None, (noise, seed)
        x0, x1 = sorted(det[0].segment[:, 0])
        assert abs(x0 - 60) < 4 and abs(x1 - 200) < 4, (noise, seed, x0, x1)


def test_a_candidate_under_min_score_says_its_nfa_fails_too():
    """A sonar user followed "score 0.441 under min_score 0.5 (option
    --min-score)", lowered it, and met "NFA 154 over max_nfa 1": a candidate
    under min_score says its NFA too when that is over max_nfa, and the hint
    names both options."""
    from seahough.cli._records import _option_hint

    img = cv2.GaussianBlur(np.random.default_rng(0).uniform(0, 255, (200, 260)).astype(
        np.uint8), (0, 0), 1.5)
    res = seahough.Detector(seahough.Pattern.rectangle(40, 30), min_score=0.6).search(img)
    under = [c for c in res.candidates if "under min_score 0.6" in c.declined]
    assert under and res.detections == []
    for c in under:
        assert f"; NFA {c.nfa:.3g} over max_nfa 1 too" in c.declined, c.declined
    assert _option_hint(under[0]) == " (options --min-score and --max-nfa)"


def test_counting_judges_a_candidate_again_when_its_finish_turned_it(monkeypatch):
    """Counting judges every candidate before the full-resolution finish;
    a finish that takes a turned alternative (an L of strips) changes its
    pose, and a twin declined after it kept the old pose's NFA, which the
    runner-up test reads (a reviewer's suspicion: 7 of 401 candidates of
    ten such scenes). Each candidate's judgement is its own pose's."""
    from seahough.core import ranking

    judged, turned = {}, []
    judge, best_full = ranking.judge, ranking._best_full

    def recording_judge(ctx, c):
        judge(ctx, c)
        judged[id(c)] = c.fit.pose

    def recording_best_full(ctx, c, *args):
        before = c.fit.pose
        best_full(ctx, c, *args)
        turned.append(c.fit.pose is not before)

    monkeypatch.setattr(ranking, "judge", recording_judge)
    monkeypatch.setattr(ranking, "_best_full", recording_best_full)
    stale = 0
    for seed in (0, 2, 4):
        rng = np.random.default_rng(seed)
        img = S.negative_scene(seed=seed, source="procedural").copy()
        for _ in range(6):
            x, y = rng.uniform(60, img.shape[1] - 60), rng.uniform(60, img.shape[0] - 60)
            box = cv2.boxPoints(((x, y), (60, 40), rng.uniform(0, 180))).astype(np.int32)
            cv2.fillPoly(img, [box], int(rng.uniform(150, 230)))
        judged.clear()
        res = seahough.Detector(seahough.Pattern.polyline([(0, 0), (60, 0), (60, 40)], 6),
                                (0.8, 1.25), max_results=10).search(img)
        stale += sum(judged[id(c)] is not c.fit.pose for c in res.candidates if id(c) in judged)
    assert any(turned) and stale == 0, (sum(turned), stale)


def test_a_line_band_without_a_visible_stretch_is_not_reported():
    """A pipeline engineer's trial: line detections whose band has no stretch
    where both of its borders are seen (``segment`` None) were reported
    (frames without a pipe, a dark pipe searched as bright: a band beside
    it). A single straight edge was "a bright line" at NFA 0.04. Such a band
    is declined and says why; a rope is still found, with its extent."""
    rng = np.random.default_rng(1)
    img = np.full((240, 320), 70, np.float32)
    img[:, 170:] = 150
    img = np.clip(cv2.GaussianBlur(img, (0, 0), 1.0) + rng.normal(0, 3, img.shape), 0, 255)
    res = seahough.Detector(seahough.Pattern.line(120, 12), angle_range=(60, 120)).search(
        img.astype(np.uint8))
    assert res.detections == []
    assert any(c.declined.startswith("no stretch of it where both of its borders are seen")
               for c in res.candidates), [c.declined for c in res.candidates]
    img[:, 170:] = 70
    img[:, 150:163] = 160                       # a rope 13 px wide, the whole height
    (d,) = seahough.Detector(seahough.Pattern.line(120, 12), angle_range=(60, 120),
                             max_results=1).detect(img.astype(np.uint8))
    assert d.segment is not None and abs(d.x - 156) < 1.5


def test_a_pipe_buried_in_the_middle_gives_its_two_stretches_seen(tmp_path):
    """A pipeline engineer's trial: a pipe seen over 0-330 px, buried over 300
    px and seen again came out as one stretch (the left one, or at other
    ranges one across the buried gap): a burial survey's very question. Its
    stretches seen are reported (API, JSON, CSV), its segment spans them,
    and the overlay draws each."""
    from seahough import viz as plot

    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.normal(100, 12, (500, 900)).astype(np.float32), (0, 0), 2)
    img[240:262, :300] += 70
    img[240:262, 600:] += 70
    img = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    for scales in ((0.5, 2.0), (0.8, 1.25)):
        (d,) = seahough.Detector(seahough.Pattern.line(300, 22), scales, (0, 180),
                                 max_results=1).detect(img)
        ends = [sorted(st[:, 0]) for st in d.stretches]
        assert len(ends) == 2, (scales, ends)
        assert all(abs(a - u) < 4 and abs(b - v) < 4
                   for (a, b), (u, v) in zip(ends, [(-0.5, 299.5), (599.5, 899.5)])), ends
        assert sorted(d.segment[:, 0]) == pytest.approx([ends[0][0], ends[1][1]])
    rec = d.to_dict()
    assert np.allclose(rec["stretches"], [st.tolist() for st in d.stretches], atol=1e-3)
    assert abs(rec["width"] - 22) < 3        # (its band's width, px: the CSV's was empty)
    fig = plot.plot_detections(img, [d])
    bands = [ln for ln in fig.axes[0].lines if len(ln.get_xydata()) == 5]
    assert len(bands) == 2
    cv2.imwrite(str(tmp_path / "pipe.png"), img)
    from test_cli import run
    proc = run("detect", "line:300,22", tmp_path / "pipe.png", "--csv", "-q", "-n", 1,
               "--angle-range", 0, 180)
    (row,) = list(csv.DictReader(io.StringIO(proc.stdout)))
    assert len(json.loads(row["stretches"])) == 2 and abs(float(row["width_px"]) - 22) < 3


def test_a_pattern_the_same_turned_by_a_half_says_its_angle_is_known_up_to_it():
    """A docking engineer's trial: a rectangle marker turned by 179.5 and
    180.5 degrees read 179.5 and 0.5, confidence 1, no flag: a controller
    would command a U-turn. Its detections say the angle is known up to a
    half turn (a square's: a quarter); an L's, a disc's say nothing."""
    from seahough.core.detection import FLAG_HALF_TURN, FLAG_QUARTER_TURN

    img, mask = S.marker("rectangle", 120)
    bg = np.full((480, 640, 3), 90, np.uint8)
    angles = []
    for turn in (179.5, 180.5):
        scene, _ = S.paste_pattern(bg, img, mask, x=320, y=240, scale=1.0, angle=turn, seed=1)
        (d,) = seahough.Detector(seahough.Pattern.from_image(img, mask=mask), (0.7, 1.3),
                                 max_results=1).detect(scene)
        assert FLAG_HALF_TURN in d.flags and d.confidence > 0.5, d.flags
        angles.append(d.angle)
    assert abs(((angles[1] - angles[0] + 90.0) % 180.0) - 90.0) < 2.0, angles   # (modulo 180)
    square, disc = np.zeros((200, 200), np.uint8), np.zeros((200, 200), np.uint8)
    cv2.rectangle(square, (70, 70), (130, 130), 200, -1)
    cv2.circle(disc, (100, 100), 30, 200, -1)
    cases = ((seahough.Pattern.rectangle(60, 60), square, FLAG_QUARTER_TURN),
             (seahough.Pattern.circle(30), disc, None),
             (seahough.Pattern.from_image(*S.marker("L", 120)), None, None))
    for pattern, scene, flag in cases:
        if scene is None:
            scene, _ = S.paste_pattern(bg, *S.marker("L", 120), x=320, y=240, scale=1.0,
                                       angle=30.0, seed=1)
        found = seahough.Detector(pattern, max_results=1, min_score=0.3).detect(scene)
        assert found, pattern.kind
        turned = {f for f in found[0].flags if f.startswith("same_turned")}
        assert turned == ({flag} if flag else set()), (pattern.kind, found[0].flags)
    # an angle range narrower than the turn rules it out: no flag (a review)
    (d,) = seahough.Detector(seahough.Pattern.rectangle(60, 60), angle_range=(-15, 15),
                             max_results=1).detect(square)
    assert not any(f.startswith("same_turned") for f in d.flags), d.flags


def test_the_line_rules_hold_for_thin_lines_equal_stretches_and_edges_beside(tmp_path):
    """A review of the rule that a line is reported only where both borders
    of its band are seen: a band under 2 px cannot tell its borders apart and
    was always declined (a 2 px cable, found before at score 0.88); of two
    equal stretches at the ends of a buried pipe one was left out; a single
    edge declined as no line still counted as the pipe's runner-up (its
    confidence 0.75 -> 0.5); the overlay's "+" lay in the buried gap."""
    from seahough import viz as plot

    rng = np.random.default_rng(5)
    img = np.clip(rng.normal(90, 3, (240, 320)), 0, 255).astype(np.float32)
    img[119:121, :] = 170                                   # a 2 px cable
    (d,) = seahough.Detector(seahough.Pattern.line(150, 1.5), (1.0, 1.0), (0.0, 180.0),
                             max_results=1).detect(img.astype(np.uint8))
    assert abs(d.y - 119.5) < 1.0 and d.segment is None and d.stretches == []
    pipe = cv2.GaussianBlur(rng.normal(100, 12, (500, 900)).astype(np.float32), (0, 0), 2)
    pipe[240:262, :150] += 70
    pipe[240:262, 750:] += 70
    pipe = np.clip(pipe + rng.normal(0, 2, pipe.shape), 0, 255).astype(np.uint8)
    for im in (pipe, pipe[:, ::-1]):
        (d,) = seahough.Detector(seahough.Pattern.line(300, 22), (0.8, 1.25), (0.0, 180.0),
                                 max_results=1).detect(np.ascontiguousarray(im))
        ends = sorted(sorted(st[:, 0].tolist()) for st in d.stretches)
        assert len(ends) == 2 and ends[0][1] < 160 and ends[1][0] > 740, ends
    fig = plot.plot_detections(pipe, [d])
    (cross,) = [ln for ln in fig.axes[0].lines if ln.get_marker() == "+"]
    x = float(cross.get_data()[0][0])
    assert x < 160 or x > 740, x                            # (on a stretch seen)
    # a pipe and a straight step edge beside it: the edge is no line, and no rival
    rng = np.random.default_rng(5)
    scene = np.full((300, 400), 80, np.float32)
    scene[60:74, 40:150] = 170                              # a pipe, 14 px, 110 px seen
    scene[200:, :] = 150                                    # a step edge at y 200
    scene = np.clip(scene + rng.normal(0, 2, scene.shape), 0, 255).astype(np.uint8)
    res = seahough.Detector(seahough.Pattern.line(150, 14), (0.8, 1.25), (0.0, 180.0),
                            max_results=3).search(scene)
    assert len(res.detections) == 1 and abs(res.detections[0].y - 66.5) < 1.5
    assert res.detections[0].confidence > 0.65, [(c.work_score, c.declined)
                                                 for c in res.candidates]   # (0.46 before)


def test_a_declined_pose_outside_the_ranges_searched_says_so():
    # a 500 x 300 box searched at 0.5-2 in a 160 x 120 photo: its best
    # candidates sat at scale 0.44 (the slack past the range), their reason
    # only "score ... under ...": a new user read them as searched
    img = np.full((120, 160), 40, np.uint8)
    img[20:100, 30:130] = 200
    res = seahough.Detector(seahough.Pattern.rectangle(500, 300)).search(img)
    assert not res.detections and res.candidates
    for c in res.candidates:
        outside = not 0.5 / 1.02 <= c.pose.scale <= 2.0 * 1.02
        assert ("its scale" in c.declined and "outside the range searched (0.5-2)"
                in c.declined) == outside, (c.pose.scale, c.declined)
    assert any("outside the range searched" in c.declined for c in res.candidates)


def test_a_marker_cut_by_the_frame_edge_is_found_where_it_is():
    """A rectangle marker 20-45 % outside the frame: its true pose scores
    its points outside as unmatched (0.5-0.6), a smaller copy turned 90
    degrees in its seen part 0.67, and the copy was reported (a docking
    trial: 6 of 12 cut rectangles). Candidates are ranked, and min_score
    judged, over the points in view (the NFA is over those already)."""
    pat_img, mask = S.marker("rectangle", 120)
    pat = seahough.Pattern.from_image(pat_img, mask=mask)
    o = np.vstack(pat.outline)
    rng = np.random.default_rng(3)
    right = 0
    for k in range(8):
        cut, s, a = rng.uniform(0.25, 0.45), rng.uniform(0.8, 1.5), rng.uniform(0, 360)
        r = 60 * s
        x, y = ((-r + 2 * r * (1 - cut), rng.uniform(140, 340)) if k % 2 else
                (rng.uniform(160, 480), 480 + r - 2 * r * (1 - cut)))
        scene, t = S.paste_pattern(S.seabed((480, 640), seed=k), pat_img, mask, x=x, y=y,
                                   scale=s, angle=a, seed=k)
        res = seahough.Detector(pat).search(scene)
        if not res.detections:
            continue
        d = res.detections[0]
        P, Q = apply_matrix(t.matrix, o), apply_matrix(d.matrix, o)
        err = np.sqrt(((P[:, None] - Q[None]) ** 2).sum(-1)).min(1).max()   # (either turn)
        assert err < 4, (k, cut, s, a, d.scale, d.angle, d.score, err)
        assert "partly_outside_image" in d.flags
        right += 1
    assert right >= 7
