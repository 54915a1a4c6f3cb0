"""Evidence for a frame pair that differs by a perspective change.

A camera that looks ahead and down (a pool robot, an ROV) and moves forward
sees the floor expand from a point near the horizon: near parts of the
frame move and grow more than far ones. Two such frames differ by a
homography of the floor's plane, not by a similarity, so the similarity
that the vote finds puts only a band of the frame within the match radius:
its score and its runner-up confidence fall under thresholds set on flat
scenes (issue 13: a forward-oblique camera over a tiled pool closed 1 loop
in 10). Over a tiled floor it is worse: a shift by a tile or two matches
almost as well as the true motion, so the vote hardly prefers the true
peak to its neighbours.

So the vote's best candidate poses are refitted as homographies: the
previous frame's strongest edge points are matched to the current frame's
edges (same direction, mapped by the homography's local Jacobian), and the
homography that brings them onto their edges is fitted (point-to-edge
distances, Gauss-Newton with Huber weights, shrinking match radii). The
true motion then explains most of the frame's edges in view, where a
similarity explained a band. The evidence is:

- ``agreement``: the share of the previous frame's edge points *in view*
  found again within the match radius (ranks the candidates: a look-alike
  that moves less keeps more of the frame in view, and on a tiled floor
  matched a larger share of *all* the points than the true motion);
- ``score``: the share of all of them found again (as :mod:`.parallax`
  counts; the caller's ``min_score`` judges it);
- ``nfa``: the a-contrario number of false alarms of that agreement
  (:mod:`seahough.core.nfa`), the search's poses times the freedom the
  homography adds (:data:`EXTRA_DOF` parameters, each moving the frame's
  corners over :data:`RADII` ``[0]`` working pixels either way, one
  value a pixel);
- ``confidence``: the agreement against the best of the other candidates
  that end more than ``SAME`` working pixels away at the frame's corners
  (the :data:`FULL` best refitted to the end, the others at the large radii
  only: their agreement, and so the runner-up, may be a little low).

The check confirms the vote's own answer or nothing: over a tiled floor the
true motion is not always among the candidates, and then a look-alike a
tile or two off fits best. The motion reported is the similarity that fits
the homography best over the part of the frame still in view (least squares
on a grid: what a trajectory needs, and how the benchmark's truth is
defined), with the homography itself beside it.
"""

from __future__ import annotations

import math

import numpy as np

from ..core import kernels as K
from ..core.keypoints import find_edge_points
from ..core.nfa import BORDER, MIN_LOG10_NFA, background, evidence, log10_tests
from ..core.preprocess import compute_gradients
from ..core.refine import Pose
from ..geometry import fit_similarity
from .parallax import (SAME, LocalCheck, _candidate_matrix, frame_points, full_matrix,
                       work_matrix)

__all__ = ["CANDIDATES", "RADII", "homography_icp", "similarity_of", "check_perspective",
           "judge_homography", "shared_agreement"]

#: Candidate poses of the search refined as homographies (the best by score).
CANDIDATES = 5
#: Candidates fitted to the end (the others: at the two largest radii only).
FULL = 2
#: Match radii of the homography fit, working pixels (ITERATIONS at each).
RADII = (6.0, 4.0, 2.5, 1.5)
#: Every how many points are matched while the radius exceeds 2 px.
STRIDE = 2
#: Iterations at each radius.
ITERATIONS = 5
#: The finish's working scale, times the search's ...
FINE = 2.0
#: ... its match radii (pixels of that scale) ...
FINE_RADII = (3.0, 2.0, 1.5)
#: ... the most edge points it fits (the strongest) ...
FINE_POINTS = 4000
#: ... and how far it may move the frame's corners (working pixels of the search).
FINISH_MOVE = 2.0
#: A candidate is ranked when its homography keeps at least this share of the
#: previous frame's points in view.
MIN_IN_VIEW = 0.25
#: Fewer points than this in view for every answer compared
#: (:func:`shared_agreement`): too few to tell them apart.
MIN_SHARED = 50
#: Parameters a homography has beyond a similarity (shear, aspect, perspective).
EXTRA_DOF = 4


def apply_homography(H, x, y):
    """``(u, v, w)``: points ``(x, y)`` mapped by the 3x3 ``H`` (``w``: the
    homogeneous divisor, positive in front of the camera)."""
    w = H[2, 0] * x + H[2, 1] * y + H[2, 2]
    return (H[0, 0] * x + H[0, 1] * y + H[0, 2]) / w, (H[1, 0] * x + H[1, 1] * y + H[1, 2]) / w, w


def map_points(H, x, y, angle):
    """Points and their gradient directions (radians, in [0, 2 pi)) mapped by
    ``H``: a gradient (normal to the edge) turns by the inverse transpose of
    the homography's Jacobian at the point.

    >>> H = np.array([[0.0, -1.0, 10.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # turned 90 deg
    >>> u, v, a = map_points(H, np.array([1.0]), np.array([0.0]), np.array([0.0]))
    >>> float(u[0]), float(v[0]), round(float(a[0]), 4)
    (10.0, 1.0, 1.5708)
    """
    u, v, w = apply_homography(H, x, y)
    j11, j12 = (H[0, 0] - u * H[2, 0]) / w, (H[0, 1] - u * H[2, 1]) / w
    j21, j22 = (H[1, 0] - v * H[2, 0]) / w, (H[1, 1] - v * H[2, 1]) / w
    c, s = np.cos(angle), np.sin(angle)
    nx, ny = j22 * c - j21 * s, -j12 * c + j11 * s    # (J^-T n, times det J)
    det = j11 * j22 - j12 * j21
    nx, ny = nx * np.sign(det), ny * np.sign(det)
    return u, v, np.mod(np.arctan2(ny, nx), 2 * math.pi)


def homography_icp(H0, points, edges, index, tol: float, radii=RADII,
                   iterations: int = ITERATIONS, score_radius: float = 1.5,
                   stride: int = STRIDE):
    """Fit a homography to the edge ``points`` (x, y, gradient angle) of one
    frame among the ``edges`` of another (``index``: their index map),
    starting from ``H0`` (3x3, or a 2x3 similarity). Returns ``(H, score,
    inside)``: the 3x3 homography (``H[2, 2] = 1``), the share of the points
    with a matching edge within ``score_radius`` at it, and the share it maps
    inside the image. Each step matches every
    point (every ``stride``-th while the radius exceeds 2 px) to the nearest
    edge point of compatible direction within the radius and solves the
    weighted least squares of the point-to-edge distances (along the edge's
    normal; Huber weights beyond half the radius, at least 1 px) for the 8
    parameters
    (:func:`seahough.core.kernels.homography_icp`).

    Examples
    --------
    A grid of squares seen under a perspective change is found from the
    identity:

    >>> import cv2
    >>> from seahough.core.keypoints import find_edge_points
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((160, 200), np.float32)
    >>> for y in range(20, 140, 30):
    ...     for x in range(20, 180, 40):
    ...         img[y:y + 14, x:x + 20 + y // 10] = 200
    >>> H = np.array([[1.02, 0.01, 2.0], [0.0, 1.03, 1.0], [0.0, 1e-4, 1.0]])
    >>> seen = cv2.warpPerspective(img, H, (200, 160))
    >>> prev = find_edge_points(compute_gradients(img), 20)
    >>> cur = find_edge_points(compute_gradients(seen), 20)
    >>> pts = prev.x.astype(float), prev.y.astype(float), prev.angle.astype(float)
    >>> fit, score, inside = homography_icp(np.eye(3), pts, cur, cur.index_map(),
    ...                                     math.radians(20))
    >>> score > 0.9, inside > 0.95, bool(np.abs(fit - H).max() < 0.01)
    (True, True, True)
    """
    H = np.asarray(H0, np.float64)
    if H.shape == (2, 3):
        H = np.vstack([H, [0.0, 0.0, 1.0]])
    px, py, pa = (np.ascontiguousarray(v, np.float64) for v in points)
    out, score, inside = K.homography_icp(px, py, pa, np.ascontiguousarray(H), edges.x,
                                          edges.y, edges.angle, edges.nx, edges.ny, index,
                                          np.asarray(radii, np.float64), int(iterations),
                                          float(tol), int(stride), float(score_radius))
    return out, float(score), float(inside)


def similarity_of(H, shape, step: int = 8):
    """The similarity (2x3) that fits the homography ``H`` best over the
    pixels of a frame of ``shape`` (h, w) that it keeps in view (least
    squares on a grid of ``step`` pixels), and the RMS distance (pixels) of
    the homography from it there. None when under 10 grid points stay in
    view.

    >>> S, rms = similarity_of(np.array([[1.0, 0, 3], [0, 1, -2], [0, 0, 1]]), (64, 80))
    >>> S.round(6).tolist(), round(rms, 6)
    ([[1.0, -0.0, 3.0], [0.0, 1.0, -2.0]], 0.0)
    """
    h, w = shape[:2]
    v, u = np.mgrid[0:h:step, 0:w:step].astype(np.float64)
    u, v = u.ravel(), v.ravel()
    qu, qv, qw = apply_homography(np.asarray(H, float), u, v)
    inside = (qw > 0) & (qu >= 0) & (qu <= w - 1) & (qv >= 0) & (qv <= h - 1)
    if inside.sum() < 10:
        return None
    p = np.stack([u[inside], v[inside]], 1)
    q = np.stack([qu[inside], qv[inside]], 1)
    S = fit_similarity(p, q)
    res = q - (p @ S[:, :2].T + S[:, 2])
    return S, float(np.sqrt((res ** 2).sum(1).mean()))


def check_perspective(pattern, result, detection, region, scale_range, angle_range, config,
                      candidates: int = CANDIDATES, gray=None, frame=None
                      ) -> LocalCheck | None:
    """Confirm a frame pair's motion by the search's best candidates'
    evidence as homographies (the module's docstring).

    ``pattern`` is the previous frame (:meth:`~seahough.Pattern.from_frame`),
    ``result`` the :class:`~seahough.core.detector.SearchResult` of its
    search in the current frame within ``region`` and the ranges,
    ``detection`` its best detection (None: its best candidate stands in):
    the vote's answer. Each candidate is ranked by the share of its points
    in view that it matches (a look-alike that moves less keeps more of the
    frame in view, and would win on the share of all the points), among
    those that keep at least :data:`MIN_IN_VIEW` of them in view. Returns a
    :class:`~.parallax.LocalCheck` (its ``matrix`` the similarity that fits
    the homography over the frame, its ``parallax`` the RMS distance of the
    homography from it, full-resolution pixels; its ``score`` the share of
    all the points matched; its ``distinct`` not measured), or None when the
    search left no candidate, none could be fitted, the best is not the
    vote's answer, or the scale or rotation is known (a homography would
    free it). ``gray``: the current frame (grey, full resolution), for the
    homography's finish at :data:`FINE` times the working scale; ``frame``:
    the previous frame's :func:`~.parallax.frame_points` at the working
    scale, when already made.
    """
    feats = result.features
    if feats is None or not result.candidates:
        return None
    if scale_range[0] == scale_range[1] or angle_range[0] == angle_range[1]:
        return None
    fx, fy, factor = feats.gradients.fx, feats.gradients.fy, result.factor
    tol = math.radians(config.angle_tolerance)
    radius = max(1.25, config.match_radius * factor)
    grad, points = frame or frame_points(pattern, factor, config)
    ox, oy = pattern.origin
    owx, owy = (ox + 0.5) * fx - 0.5, (oy + 0.5) * fy - 0.5
    ph, pw = grad.magnitude.shape
    corners = np.array([[0, 0, 1], [pw - 1, 0, 1], [pw - 1, ph - 1, 1], [0, ph - 1, 1]], float)

    def at(m):
        q = corners @ m.T
        return q[:, :2] / q[:, 2:] if np.all(q[:, 2] > 0) else None

    def gap(a, b):
        return float(np.hypot(*(a - b).T).max())

    cands = sorted(result.candidates, key=lambda c: -c.work_score)[:candidates]
    starts = [_candidate_matrix(c.fit.pose, owx, owy) for c in cands]
    # the vote's answer: the candidate nearest the detection (the ranking may
    # finish another candidate than the best at the working scale)
    own = 0
    if detection is not None:
        d_at = at(np.vstack([work_matrix(detection.matrix, fx, fy)[:2], [0, 0, 1]]))
        own = int(np.argmin([gap(at(np.vstack([m, [0, 0, 1]])), d_at) for m in starts]))
    # every candidate fitted at the large radii on a subset of the points,
    # the best FULL of them to the end
    fits = []
    for k, m in enumerate(starts):
        H, score, inside = homography_icp(m, points, feats.edges, feats.index, tol,
                                          radii=RADII[:2], iterations=3, score_radius=radius,
                                          stride=2 * STRIDE)
        fits.append([score / max(inside, 1e-9), score, inside, H, k])
    fits.sort(key=lambda f: -f[0] if f[2] >= MIN_IN_VIEW else 1.0)
    for f in fits[:FULL]:
        H, score, inside = homography_icp(f[3], points, feats.edges, feats.index, tol,
                                          radii=RADII[1:], score_radius=radius)
        f[:4] = [score / max(inside, 1e-9), score, inside, H]
    fits = [f + [at(f[3])] for f in fits if f[2] >= MIN_IN_VIEW and f[1] > 0]
    fits = [f for f in fits if f[5] is not None]
    fits.sort(key=lambda f: -f[0])
    if not fits or fits[0][4] != own:
        # the check confirms the vote's own answer, never puts another in its
        # place: over a tiled floor the true motion is not always among the
        # candidates, and then a look-alike a tile or two off fits best
        return None
    agree, score, _, H, _, c_at = fits[0]
    runner = max((f[0] for f in fits[1:] if gap(f[5], c_at) > SAME), default=0.0)
    conf = float(np.clip((agree - runner) / max(1.0 - runner, 1e-9), 0.0, 1.0))
    return judge_homography(H, conf, score, pattern, result, region, scale_range, angle_range,
                            config, points, gray)


def shared_agreement(homographies, points, edges, index, radius: float, tol: float,
                     min_points: int = MIN_SHARED) -> list | None:
    """For each of several working-scale ``homographies`` (3x3) of the same
    frame pair, the share of the previous frame's ``points`` (x, y, gradient
    angle) that find a compatible edge among ``edges`` within ``radius``,
    counted over the points that every one of them keeps in view (3 px from
    the border, and in front of the camera): like with like, where a point
    one answer maps out of view neither counts for it nor against the other.
    None when fewer than ``min_points`` are in view for all.

    >>> from seahough.core.keypoints import find_edge_points
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((120, 160), np.float32)
    >>> img[30:90, 40:120] = 200
    >>> e = find_edge_points(compute_gradients(img), 20)
    >>> pts = e.x.astype(float), e.y.astype(float), e.angle.astype(float)
    >>> off = np.array([[1.0, 0, 6], [0, 1, 0], [0, 0, 1]])   # 6 px right: only the top and bottom
    >>> right, wrong = shared_agreement([np.eye(3), off], pts, e, e.index_map(), 1.5, 0.35)
    >>> right, round(wrong, 2)
    (1.0, 0.53)
    """
    px, py, pa = (np.asarray(v, np.float64) for v in points)
    h, w = index.shape
    Hs = [np.asarray(H, np.float64) for H in homographies]
    mapped = [map_points(H, px, py, pa) for H in Hs]
    common = np.ones(px.size, bool)
    for H, (u, v, _) in zip(Hs, mapped):
        common &= (u >= BORDER) & (u <= w - 1 - BORDER) & (v >= BORDER) & (v <= h - 1 - BORDER)
        common &= H[2, 0] * px + H[2, 1] * py + H[2, 2] > 0   # (in front of the camera)
    if int(common.sum()) < min_points:
        return None
    out = []
    for u, v, a in mapped:
        ids, _ = K.match_points(*(np.ascontiguousarray(t[common]) for t in (u, v, a)), 1.0, 0.0,
                                0.0, 0.0, edges.x, edges.y, edges.angle, index, float(radius),
                                float(tol), False)
        out.append(float((ids >= 0).mean()))
    return out


def judge_homography(H, confidence, score, pattern, result, region, scale_range, angle_range,
                     config, points, gray=None) -> LocalCheck | None:
    """A working-scale homography ``H`` (3x3) of a frame pair searched as
    ``result``, as a :class:`~.parallax.LocalCheck` with the ``confidence``
    and ``score`` given: its matrix the similarity that fits the homography
    best over the frame (None when too little of the frame stays in view),
    its homography in full-resolution pixels (finished at :data:`FINE` times
    the working scale when ``gray``, the current frame, is given), and the
    number of false alarms of the agreement of the previous frame's
    ``points`` (at the working scale) at ``H``: the search's poses times the
    freedom the homography adds (:data:`EXTRA_DOF`)."""
    feats, factor = result.features, result.factor
    fx, fy = feats.gradients.fx, feats.gradients.fy
    tol = math.radians(config.angle_tolerance)
    radius = max(1.25, config.match_radius * factor)
    # the evidence: the points mapped by the homography, at the identity pose
    px, py, pa = points
    u, v, a = map_points(H, px, py, pa)
    bg = background(feats.edges, radius, tol, None, feats.index)
    x0, y0, x1, y1 = region
    fh, fw = feats.gradients.full_shape[:2]
    area = max(min(x1, fw) - max(x0, 0), 1.0) * max(min(y1, fh) - max(y0, 0), 1.0) * fx * fy
    tests = (log10_tests(area, pattern.features(factor, config).radius, scale_range,
                         angle_range) + EXTRA_DOF * math.log10(2 * RADII[0] + 1))
    ev = evidence(Pose(1.0, 0.0, 0.0, 0.0), u, v, a, feats.edges, feats.index, bg, tests, tol=tol,
                  either=False)
    Hf = full_matrix(H, fx, fy)
    Hf = Hf / Hf[2, 2]
    if gray is not None and FINE > 1 and factor < 1:
        Hf = _finish(Hf, pattern, gray, min(1.0, FINE * factor), config, tol,
                     max_move=FINISH_MOVE / factor)
    sim = similarity_of(Hf, feats.gradients.full_shape)
    if sim is None:
        return None
    S, rms = sim
    return LocalCheck(S, confidence, score, float(10.0 ** max(ev.log10_nfa, MIN_LOG10_NFA)), rms,
                      Hf)


def _finish(Hf, pattern, gray, factor, config, tol, max_move):
    """The full-resolution homography ``Hf`` refined at working scale
    ``factor`` (both frames' edges at that scale; :data:`FINE_RADII`); ``Hf``
    itself when the fit fails, matches fewer points in view, or moves the
    frame's corners more than ``max_move`` full-resolution pixels."""
    _, pts = frame_points(pattern, factor, config, FINE_POINTS)
    grad = compute_gradients(gray, factor, config.equalize)
    edges = find_edge_points(grad, config.min_gradient)
    fx, fy = grad.fx, grad.fy
    start = work_matrix(Hf, fx, fy)
    index = edges.index_map()
    _, s0, i0 = homography_icp(start, pts, edges, index, tol, radii=FINE_RADII[-1:],
                               iterations=0)
    H, score, inside = homography_icp(start, pts, edges, index, tol, radii=FINE_RADII)
    out = full_matrix(H, fx, fy)
    out = out / out[2, 2]
    h, w = gray.shape[:2]
    c = np.array([[0, 0, 1], [w - 1, 0, 1], [w - 1, h - 1, 1], [0, h - 1, 1]], float)
    a, b = c @ out.T, c @ Hf.T
    if (score <= 0 or score / max(inside, 1e-9) < s0 / max(i0, 1e-9) or np.any(a[:, 2] <= 0)
            or np.hypot(*(a[:, :2] / a[:, 2:] - b[:, :2] / b[:, 2:]).T).max() > max_move):
        return Hf
    return out
