"""Survey frames over a seabed in relief (sim.relief_sequence) and the motion
measured where parallax spoils a single similarity (motion/parallax.py)."""

import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim
from seahough.errors import ParameterError
from seahough.motion import pair
from seahough.motion import parallax as P

from conftest import data_path


def _seq(**kw):
    args = dict(n_frames=3, frame_size=(120, 160), seed=2, source="procedural", water=None)
    args.update(kw)
    return sim.relief_sequence(**args)


def test_a_pixel_cast_onto_the_seabed_projects_back_onto_itself():
    _, truth = _seq(relief=0.2)
    u = np.array([0.0, 80.0, 159.0, 20.0])
    v = np.array([0.0, 60.0, 119.0, 100.0])
    X, Y, Z = truth.ground(1, u, v)
    bu, bv = truth.project(1, X, Y, Z)
    assert np.allclose(bu, u, atol=1e-6) and np.allclose(bv, v, atol=1e-6)
    # ... and lies on the seabed (the ray met the height field)
    assert np.allclose(Z, truth.height_at(X, Y), atol=2e-3)
    assert np.ptp(Z) > 0.02          # (not vacuous: the points are at different heights)


def test_a_flat_seabed_is_one_similarity_and_relief_adds_parallax():
    _, flat = _seq(relief=0.0)
    _, low = _seq(relief=0.05)
    _, high = _seq(relief=0.2)
    assert flat.similarity(0, 1)[1] < 1e-6
    assert 0.05 < low.similarity(0, 1)[1] < high.similarity(0, 1)[1]
    # the true flow of the flat pair is the similarity itself
    p, q = flat.flow(0, 1)
    m, _ = flat.similarity(0, 1)
    assert np.abs(p @ m[:, :2].T + m[:, 2] - q).max() < 1e-6


def test_the_camera_moves_a_share_of_its_frame_and_its_light_moves_with_it():
    frames, truth = _seq(n_frames=4, step=(0.2, 0.2), water="clear", frame_size=(240, 320))
    for i in range(3):
        m, _ = truth.similarity(i, i + 1)
        c = np.array([159.5, 119.5])
        shift = np.hypot(*(m[:, :2] @ c + m[:, 2] - c))
        assert 0.12 * 240 < shift < 0.3 * 320     # about a fifth of the frame
    assert frames[0].dtype == np.uint8 and frames[0].shape == (240, 320, 3)
    # the strobe on the camera: over a uniform flat seabed, the middle of every
    # frame is lit more than its corners (farther away, seen obliquely)
    grey = np.full((300, 400, 3), 150, np.uint8)
    lit, _ = _seq(image=grey, relief=0.0, n_frames=3, frame_size=(240, 320))
    for f in lit:
        g = f.mean(axis=2)
        centre = g[100:140, 140:180].mean()
        for corner in (g[:20, :20], g[:20, -20:], g[-20:, :20], g[-20:, -20:]):
            assert centre > corner.mean() + 5


@pytest.mark.parametrize("kw, word", [(dict(n_frames=1), "n_frames"),
                                      (dict(altitude=(2.0, 1.0)), "altitude"),
                                      (dict(step=(0.1, 0.9)), "step"),
                                      (dict(relief=0.6), "too rough"),
                                      (dict(correlation=0.0), "correlation")])
def test_bad_parameters_are_named(kw, word):
    with pytest.raises(ParameterError, match=word):
        _seq(**kw)


def test_parallax_that_spoils_the_similarity_is_measured_tile_by_tile(monkeypatch):
    # a survey camera (1360x1024) 1.5-3 m over a reef in relief (std 18 cm):
    # the best similarity leaves 0.8 % of the diagonal of parallax, the
    # similarity's own confidence falls under the threshold, and the check
    # tile by tile finds the motion (tune photo of bench/bench_relief.py)
    frames, truth = sim.relief_sequence(source=data_path("sequences", "dtu_seabed_pair",
                                                         "scene1.png"),
                                        n_frames=2, relief=0.18, seed=6, water="moderate")
    m_true, parallax = truth.similarity(0, 1)
    h, w = frames[0].shape[:2]
    diag = math.hypot(w, h)
    assert parallax > 0.006 * diag     # (strong relief: the test is not vacuous)
    m = seahough.estimate_motion(frames[0], frames[1])
    assert m is not None and m.confidence >= 0.15 and m.nfa < 1e-6
    assert m.parallax > 2.0 and m.homography is not None and m.homography.shape == (3, 3)
    corners = np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], float)
    err = np.hypot(*(corners @ m.matrix[:, :2].T + m.matrix[:, 2]
                     - (corners @ m_true[:, :2].T + m_true[:, 2])).T).max()
    assert err < 4 * parallax          # the true similarity itself is off by the parallax
    # without the check tile by tile, coarse to fine measures it (as a
    # homography, which absorbs part of the parallax); without either (nor the
    # check of the candidates), the pair is declined
    import seahough.motion.pair as pair
    monkeypatch.setattr(pair, "check_locally", lambda *a, **k: None)
    m = seahough.estimate_motion(frames[0], frames[1])
    assert m is not None and m.homography is not None and m.nfa < 1e-6
    err = np.hypot(*(corners @ m.matrix[:, :2].T + m.matrix[:, 2]
                     - (corners @ m_true[:, :2].T + m_true[:, 2])).T).max()
    assert err < 4 * parallax
    for check in ("coarse_to_fine", "check_perspective"):
        monkeypatch.setattr(pair, check, lambda *a, **k: None)
    assert seahough.estimate_motion(frames[0], frames[1]) is None


def _both_checks(monkeypatch):
    """Spy on estimate_motion's check tile by tile: each call's answer with the
    shortcut it was asked for, and without it."""
    seen = []

    def spy(*a, **k):
        seen.append((P.check_locally(*a, **k),
                     P.check_locally(*a, **{n: v for n, v in k.items() if n != "min_distinct"}),
                     k.get("min_distinct", 0.0)))
        return seen[-1][0]

    monkeypatch.setattr(pair, "check_locally", spy)
    return seen


def test_the_check_tile_by_tile_is_skipped_when_no_answer_could_be_distinct(monkeypatch):
    # the real tiled pool, frames 1 -> 2: whatever pose the check would
    # choose, the vote's runner-up is too near it (a tile's look-alike) to
    # rescue the pair; min_distinct says so before a tile is measured
    files = seahough.list_frames(data_path("sequences", "subvo_pool_chain"))
    frames = [cv2.imread(str(f)) for f in files[1:3]]
    seen = _both_checks(monkeypatch)
    seahough.estimate_motion(*frames)
    assert seen and seen[0][2] == pair.RESCUE_DISTINCT
    short, full, _ = seen[0]
    assert short is None and full is not None and full.distinct < pair.RESCUE_DISTINCT
    # a pose the vote found distinct is measured as without the shortcut, and
    # rescues its pair (the reef in relief of the test above)
    seen.clear()
    relief, _ = sim.relief_sequence(source=data_path("sequences", "dtu_seabed_pair",
                                                     "scene1.png"),
                                    n_frames=2, relief=0.18, seed=6, water="moderate")
    assert seahough.estimate_motion(*relief) is not None
    short, full, _ = seen[0]
    assert full.distinct >= pair.RESCUE_DISTINCT
    assert np.array_equal(short.matrix, full.matrix) and short.score == full.score


def test_unrelated_frames_are_not_made_a_match_by_the_tiles_freedom():
    # two different seabeds: the tiles may shift, and the number of false
    # alarms pays for it
    from seahough.core.keypoints import find_edge_points
    from seahough.core.nfa import background
    from seahough.core.preprocess import compute_gradients

    a = sim.relief_sequence(n_frames=2, frame_size=(480, 640), seed=1, source="procedural",
                            water="clear")[0][0]
    b = sim.relief_sequence(n_frames=2, frame_size=(480, 640), seed=5, source="procedural",
                            water="clear")[0][1]
    assert seahough.estimate_motion(a, b) is None
    edges = [find_edge_points(compute_gradients(seahough.to_gray(f), 0.5), 20) for f in (a, b)]
    idx = edges[1].index_map()
    bg = background(edges[1], 1.25, math.radians(20), None, idx)
    for shift in ([[1, 0, 0], [0, 1, 0]], [[1, 0, 12], [0, 1, -7]]):
        ev = P.local_evidence(P.strongest(edges[0]), edges[1], idx, shift, bg, 7.0,
                              tol=math.radians(20), match_radius=1.25)
        assert ev.tiles >= 12 and ev.nfa > 1.0 and ev.score < 0.3, (ev.score, ev.nfa)


def test_a_survey_measures_its_chunk_links_tile_by_tile_too():
    # survey odometry's links between chunks go through estimate_motion with
    # the run's own threshold, so a pair in relief is rescued there as in
    # run_odometry (it asked for min_confidence=0 and judged itself: never)
    from seahough.config import OdometryTuning
    from seahough.motion.pair import MOTION_CONFIG
    from seahough.survey._odometry_chain import measure_across

    frames, truth = sim.relief_sequence(source=data_path("sequences", "dtu_seabed_pair",
                                                         "scene1.png"),
                                        n_frames=2, relief=0.18, seed=6, water="moderate")

    class Reader:
        def raw(self, i):
            return frames[i]

    # (min_score 0: the similarity's detection is kept, at its low confidence)
    mo, why = measure_across(Reader(), 0, 1, (0.8, 1.25), (-30.0, 30.0), MOTION_CONFIG,
                             OdometryTuning(min_score=0.0))
    assert why == "" and mo is not None and mo.parallax > 2.0, why


def test_local_evidence_pays_for_each_tiles_shift():
    from seahough.core.keypoints import find_edge_points
    from seahough.core.nfa import background
    from seahough.core.preprocess import compute_gradients

    g = sim.seabed((240, 320), seed=2)[:, :, 1].astype(np.float32)
    prev = find_edge_points(compute_gradients(g[:, :300]), 20)
    cur = find_edge_points(compute_gradients(g[:, 5:305]), 20)
    idx = cur.index_map()
    bg = background(cur, 1.5, math.radians(20), None, idx)
    pts = P.strongest(prev, 160)     # (few points: tails above the floor of 1e-300)
    shift = [[1, 0, -5], [0, 1, 0]]
    ev = P.local_evidence(pts, cur, idx, shift, bg, 5.0, tol=math.radians(20), grid=2)
    still = P.local_evidence(pts, cur, idx, shift, bg, 5.0, tol=math.radians(20), grid=2,
                             radius=1.5)
    assert ev.tiles == 4 and -300 < ev.log10_nfa < -5
    # the same agreement; the freedom of the tiles to shift 6 px costs
    # log10(pi 36) - log10(pi 1.5^2) orders of magnitude more each
    assert ev.score == pytest.approx(still.score, abs=0.02)
    extra = ev.tiles * (math.log10(math.pi * 36) - math.log10(math.pi * 1.5 ** 2))
    assert ev.log10_nfa - still.log10_nfa == pytest.approx(extra, abs=3.0)
    # a pose 3 px off is found again by the tiles, and the parallax it leaves is small
    off = P.local_evidence(P.strongest(prev), cur, idx, [[1, 0, -2], [0, 1, 0]], bg, 5.0,
                           tol=math.radians(20))
    assert off.score > 0.8 and off.parallax < 0.5
    assert np.allclose(off.similarity[:, 2], [-5, 0], atol=0.3)


# ------------------------------------------------------------ large frames' memory
def test_a_checked_float_frame_is_not_copied_again():
    g = np.full((80, 100), 120.0, np.float32)
    out = seahough.to_gray(g)
    assert np.shares_memory(out, g) and not out.flags.writeable
    assert g.flags.writeable                      # (the caller's array is untouched)
    unit = np.full((80, 100), 0.5, np.float32)    # [0, 1] levels are scaled: a copy
    assert not np.shares_memory(seahough.to_gray(unit), unit)


def test_an_8_bit_frame_pattern_keeps_its_levels_once():
    frame = sim.seabed((240, 320), seed=3)[:, :, 1]
    p = seahough.Pattern.from_frame(frame)
    assert p.__dict__["_gray_f"] is None and p.image.dtype == np.uint8
    assert np.array_equal(p._gray, frame.astype(np.float32))
    fractional = seahough.Pattern.from_frame(frame.astype(np.float32) + 0.25)
    assert fractional.__dict__["_gray_f"] is not None     # (levels 8 bits cannot hold)


def test_a_large_pair_holds_few_copies_of_its_frames():
    # the numpy memory estimate_motion allocates at its peak, in frames of
    # float32 (deterministic: tracemalloc counts numpy's allocations). It held
    # 12 frames' worth for a 12 MP pair before the full-resolution edges were
    # taken by strips and the frames' float copies dropped; about 3 now
    import tracemalloc
    big = sim.seabed((1700, 2300), seed=4)
    a, b = big[:1500, :2000], big[150:1650, 250:2250]
    seahough.estimate_motion(a[::8, ::8], b[::8, ::8])
    tracemalloc.start()
    try:
        m = seahough.estimate_motion(a, b)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert m is not None and abs(m.dx + 250) < 1.5 and abs(m.dy + 150) < 1.5
    assert peak < 5 * 1500 * 2000 * 4, peak / 2 ** 20


def test_the_homography_is_measured_when_asked():
    # a flat seabed seen from two places: the similarity answers as without
    # the option, and the homography asked for fits the true motion too
    frames, truth = sim.relief_sequence(n_frames=2, frame_size=(480, 640), relief=0.0,
                                        seed=3, source="procedural", water="clear")
    plain = seahough.estimate_motion(frames[0], frames[1])
    asked = seahough.estimate_motion(frames[0], frames[1], homography=True)
    assert plain is not None and plain.homography is None and math.isnan(plain.parallax)
    assert asked is not None and asked.homography.shape == (3, 3)
    np.testing.assert_allclose(asked.matrix, plain.matrix)      # the same answer
    assert asked.confidence == plain.confidence and asked.parallax < 1.0
    p, q = truth.flow(0, 1, step=32)
    hp = asked.homography @ np.vstack([p.T, np.ones(len(p))])
    err = np.hypot(*(hp[:2] / hp[2] - q.T)).max()
    assert err < 2.0, err                      # a flat seabed: one homography
    assert asked.to_dict()["homography"] is not None
