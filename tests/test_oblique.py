"""A forward-oblique camera over a pool floor (sim.relief_sequence with tilt,
sim.tiled_floor) and the motion measured as a homography
(motion/perspective.py)."""

import math

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim
from seahough.core import kernels as K
from seahough.core.keypoints import find_edge_points
from seahough.core.preprocess import compute_gradients
from seahough.errors import ParameterError
from seahough.motion import pair as PAIR
from seahough.motion import perspective as PP


def _seq(**kw):
    args = dict(n_frames=3, frame_size=(120, 160), seed=2, source="procedural", water=None,
                tilt=40.0, forward=True)
    args.update(kw)
    return sim.relief_sequence(**args)


def _corner_error(a, b, shape):
    h, w = shape[:2]
    c = np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], float)
    return float(np.hypot(*((c @ a[:, :2].T + a[:, 2]) - (c @ b[:, :2].T + b[:, 2])).T).max())


# ----------------------------------------------------------------------------
# the simulator
# ----------------------------------------------------------------------------

def test_a_tiled_floor_is_a_lattice_of_its_period():
    img = sim.tiled_floor((200, 240), seed=3, tile=16)
    assert img.shape == (200, 240, 3) and img.dtype == np.uint8
    assert (img == sim.tiled_floor((200, 240), seed=3, tile=16)).all()
    assert not (img == sim.tiled_floor((200, 240), seed=4, tile=16)).all()
    # the grout lines repeat every tile: the autocorrelation of a row's
    # brightness peaks near the period
    g = img.mean(axis=2)
    row = g[100] - g[100].mean()
    ac = np.correlate(row, row, "full")[row.size - 1:]
    assert 14 <= int(np.argmax(ac[8:40])) + 8 <= 18
    with pytest.raises(ParameterError, match="tile"):
        sim.tiled_floor((50, 50), tile=3)


def test_a_tilted_camera_casts_and_projects_back_onto_itself():
    _, truth = _seq(relief=0.1)
    assert truth.tilt == 40.0
    u = np.array([0.0, 80.0, 159.0, 20.0])
    v = np.array([0.0, 60.0, 119.0, 100.0])
    X, Y, Z = truth.ground(1, u, v)
    bu, bv = truth.project(1, X, Y, Z)
    assert np.allclose(bu, u, atol=1e-6) and np.allclose(bv, v, atol=1e-6)
    assert np.allclose(Z, truth.height_at(X, Y), atol=2e-3)
    # the top of the frame sees farther than the bottom
    X0, Y0, A, _, _ = truth._axes(1)
    far = np.hypot(X[0] - X0, Y[0] - Y0)
    near = np.hypot(X[2] - X0, Y[2] - Y0)
    assert far > 2 * near


def test_a_flat_floor_seen_obliquely_is_a_homography_not_a_similarity():
    _, truth = _seq(relief=0.0, frame_size=(240, 320))
    p, q = truth.flow(0, 1)
    m, rms = truth.similarity(0, 1)
    assert rms > 1.0                          # a similarity leaves the perspective out
    H, _ = cv2.findHomography(p, q, 0)
    hp = cv2.perspectiveTransform(p[None], H)[0]
    assert np.abs(hp - q).max() < 0.05        # ... a homography does not
    # moving forward (towards the top of the frame): the floor comes down
    # the frame and grows
    c = np.array([159.5, 119.5])
    assert (m[:, :2] @ c + m[:, 2] - c)[1] > 5
    assert math.hypot(m[0, 0], m[1, 0]) > 1.0


def test_tilt_zero_renders_what_the_downward_camera_did():
    a, ta = sim.relief_sequence(n_frames=2, frame_size=(96, 128), seed=1, source="procedural",
                                water=None)
    b, tb = sim.relief_sequence(n_frames=2, frame_size=(96, 128), seed=1, source="procedural",
                                water=None, tilt=0.0)
    assert all((x == y).all() for x, y in zip(a, b))
    assert np.array_equal(ta.similarity(0, 1)[0], tb.similarity(0, 1)[0])


def test_daylight_has_no_fall_off_and_the_tiles_source_is_a_pool():
    frames, _ = _seq(source="tiles", strobe=False, frame_size=(240, 320), relief=0.0)
    g = frames[0].mean(axis=2)
    # the farther top of the frame is as bright as the bottom (no strobe)
    assert abs(g[:60].mean() - g[-60:].mean()) < 0.25 * g.mean()


@pytest.mark.parametrize("kw", [dict(tilt=-5.0), dict(tilt=61.0),
                                dict(tilt=60.0, frame_size=(400, 160))])
def test_a_tilt_that_sees_the_horizon_is_refused(kw):
    with pytest.raises(ParameterError, match="tilt"):
        _seq(**kw)


# ----------------------------------------------------------------------------
# the homography fit
# ----------------------------------------------------------------------------

def _grid_image():
    img = np.zeros((200, 260), np.float32)
    rng = np.random.default_rng(0)
    for _ in range(40):
        x, y = rng.integers(10, 230), rng.integers(10, 170)
        img[y:y + rng.integers(8, 25), x:x + rng.integers(8, 25)] = rng.uniform(80, 250)
    return img


def _points(img):
    e = find_edge_points(compute_gradients(img), 20)
    return e, (e.x.astype(float), e.y.astype(float), e.angle.astype(float))


@pytest.mark.parametrize("H", [
    np.array([[1.0, 0.0, 3.0], [0.0, 1.0, -2.0], [0.0, 0.0, 1.0]]),         # a shift
    np.array([[1.03, -0.02, 1.0], [0.01, 0.99, 2.0], [2e-5, 1.5e-4, 1.0]]),  # perspective
])
def test_the_homography_fit_finds_a_known_homography(H):
    img = _grid_image()
    seen = cv2.warpPerspective(img, H, (260, 200))
    _, pts = _points(img)
    cur, _ = _points(seen)
    fit, score = PP.homography_icp(np.eye(3), pts, cur, cur.index_map(), math.radians(20))
    assert score > 0.85
    c = np.array([[0, 0], [259, 0], [259, 199], [0, 199]], float)
    got = cv2.perspectiveTransform(c[None], fit)[0]
    want = cv2.perspectiveTransform(c[None], H)[0]
    assert np.abs(got - want).max() < 0.3
    # the kernel and its wrapper agree
    raw, s2 = K.homography_icp(*pts, np.eye(3), cur.x, cur.y, cur.angle, cur.nx, cur.ny,
                               cur.index_map(), np.array(PP.RADII), PP.ITERATIONS,
                               math.radians(20), PP.STRIDE, 1.5)
    assert np.allclose(raw, fit) and s2 == score


def test_a_fit_from_far_off_does_not_claim_the_match():
    img = _grid_image()
    seen = cv2.warpPerspective(img, np.eye(3), (260, 200))
    _, pts = _points(img)
    cur, _ = _points(seen)
    start = np.array([[1.0, 0, 40.0], [0, 1.0, 30.0], [0, 0, 1.0]])    # far beyond the radii
    _, score = PP.homography_icp(start, pts, cur, cur.index_map(), math.radians(20))
    assert score < 0.3


def test_map_points_turns_gradients_with_the_homography():
    # a similarity turning by 30 degrees turns gradients by 30 degrees
    t = math.radians(30)
    H = np.array([[math.cos(t), -math.sin(t), 5.0], [math.sin(t), math.cos(t), 1.0], [0, 0, 1]])
    _, _, a = PP.map_points(H, np.array([3.0, 10.0]), np.array([4.0, -2.0]),
                            np.array([0.0, 1.0]))
    assert np.allclose(a, [t, 1.0 + t])


def test_similarity_of_a_homography_is_its_least_squares_fit():
    S, rms = PP.similarity_of(np.array([[2.0, 0, 10], [0, 2.0, 0], [0, 0, 1.0]]), (100, 120))
    assert np.allclose(S, [[2.0, 0, 10], [0, 2.0, 0]]) and rms < 1e-9
    H = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 4e-4, 1.0]])
    S, rms = PP.similarity_of(H, (100, 120))
    assert rms > 0.1                       # perspective: no similarity fits exactly
    assert PP.similarity_of(np.array([[1.0, 0, 1e4], [0, 1, 0], [0, 0, 1]]), (100, 120)) is None


# ----------------------------------------------------------------------------
# the motion of an oblique pair
# ----------------------------------------------------------------------------

@pytest.fixture(scope="module")
def pool_pair():
    # the tune part's tiled floor of bench/bench_oblique.py, seed 4, frames 1 -> 2: the
    # similarity alone is declined (confidence 0.14); as homographies the
    # true motion explains 0.77 of the frame's edges, its look-alikes 0.2
    import importlib.util
    import pathlib
    path = pathlib.Path(__file__).resolve().parent.parent / "bench" / "bench_oblique.py"
    spec = importlib.util.spec_from_file_location("bench_oblique", path)
    B = importlib.util.module_from_spec(spec)
    import sys
    sys.path.insert(0, str(path.parent))
    try:
        spec.loader.exec_module(B)
        frames, truth = B.render("tiles", 4)
    finally:
        sys.path.remove(str(path.parent))
    return frames[1], frames[2], truth.similarity(1, 2)[0]


def test_an_oblique_pool_pair_is_measured_as_a_homography(pool_pair, monkeypatch):
    a, b, want = pool_pair
    d = math.hypot(*a.shape[:2])
    seen = {}
    real = PAIR.check_perspective

    def spy(*args, **kw):
        seen["check"] = real(*args, **kw)
        return seen["check"]

    monkeypatch.setattr(PAIR, "check_perspective", spy)
    m = seahough.estimate_motion(a, b)
    assert m is not None and seen.get("check") is not None
    assert _corner_error(m.matrix, want, a.shape) < 0.01 * d
    assert m.confidence >= 0.15 and m.nfa < 1e-6
    assert m.homography is not None and m.parallax > 1.0   # (the perspective it measured)
    # without the check, the pair is declined
    monkeypatch.setattr(PAIR, "check_perspective", lambda *a, **k: None)
    assert seahough.estimate_motion(a, b) is None


def test_a_confident_similarity_is_not_refitted(monkeypatch):
    frames, _ = sim.relief_sequence(n_frames=2, frame_size=(240, 320), seed=3, relief=0.0,
                                    source="procedural", water=None)
    monkeypatch.setattr(PAIR, "check_perspective",
                        lambda *a, **k: pytest.fail("a confident pair was refitted"))
    assert seahough.estimate_motion(frames[0], frames[1]) is not None
