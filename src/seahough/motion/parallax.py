"""Evidence for a frame pair that tolerates parallax (a seabed in relief).

The vote finds the motion between two frames as one similarity. On a flat
seabed every edge point of the previous frame then lies within the match
radius (1.5 px) of its edge in the current one. On a seabed in relief it
does not: a rock nearer the camera moves more than the sand around it, and
a similarity leaves tens of pixels of parallax at native resolution, so the
share of edge points it explains, and the runner-up confidence made from
it, fall under any threshold set on flat scenes (issue 13).

So a pair's evidence is measured locally: the previous frame is cut into
:data:`GRID` x :data:`GRID` tiles, and each tile's edge points may shift
by up to :data:`RADIUS` working pixels from the similarity (point-to-edge
ICP, translation only, starting at the similarity). The evidence is then:

- ``score``: the share of the previous frame's edge points found again
  (within the match radius) after their tile's shift (of all of them: a
  look-alike that keeps less of the frame in view explains less);
- ``nfa``: the a-contrario number of false alarms of that agreement
  (:mod:`seahough.core.nfa`): the binomial tail of the pooled agreement of
  the tiles, times the poses the search tried, times, for every tile, the
  shifts it could take (one per working pixel of a disc of :data:`RADIUS`):
  the freedom given to the tiles is paid for;
- ``parallax``: how far the tiles' shifts stray from the similarity
  fitted to them (median, working pixels);
- a homography fitted to the tiles' shifts (a plane seen from two places:
  the forward-oblique camera over a pool floor).

The runner-up's evidence is measured the same way, so that confidence
compares like with like.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..core import kernels as K
from ..core.keypoints import EdgePoints, find_edge_points
from ..core.nfa import (MIN_CHANCE, MIN_LOG10_NFA, Background, background, evidence,
                        log10_binom_tail, log10_tests)
from ..core.preprocess import compute_gradients
from ..core.refine import Pose

__all__ = ["GRID", "RADIUS", "LocalEvidence", "local_evidence", "check_locally", "LocalCheck",
           "work_matrix",
           "full_matrix"]

#: Tiles a side: each tile of the previous frame takes its own shift.
GRID = 4
#: Largest shift of a tile from the similarity, working pixels (24 px of a
#: 1360 px frame searched at 320 px: the parallax of a 0.3 m bump seen 2 m
#: below a camera that moved a fifth of its frame).
RADIUS = 6.0
#: Most edge points checked (the strongest).
MAX_POINTS = 2000
#: A tile with fewer points in view is left out.
MIN_TILE_POINTS = 20
#: Two poses whose frame corners lie this close (working pixels) are one
#: answer: the runner-up of the confidence is farther than that.
SAME = 2.0
#: Another candidate replaces the search's answer when its score is higher
#: by this much (near-equal scores are look-alikes: the confidence says so).
SWITCH = 0.1
#: Candidate poses of the search measured besides its best detection.
CANDIDATES = 4
#: A homography is fitted to at least this many tiles (4 fit any exactly).
MIN_HOMOGRAPHY_TILES = 6
#: Match radius of the score (working pixels), as the search's.
SCORE_RADIUS = 1.5


@dataclass
class LocalEvidence:
    """The evidence of a frame pair's motion, each tile shifted on its own
    (working-scale pixels)."""

    score: float               # share of the edge points found again after the tile shifts
                               # (of all the previous frame's points: in view or not)
    log10_nfa: float
    tiles: int                 # tiles in view
    parallax: float            # median distance of the tile shifts from `similarity`
    similarity: np.ndarray     # 2x3, fitted to the tiles' shifts
    homography: np.ndarray | None   # 3x3, fitted to them (None: under 4 tiles)

    @property
    def nfa(self) -> float:
        return float(10.0 ** self.log10_nfa)


def _scaling(fx: float, fy: float) -> np.ndarray:
    """Full-resolution pixel -> working pixel (pixel centres kept)."""
    return np.array([[fx, 0.0, 0.5 * fx - 0.5], [0.0, fy, 0.5 * fy - 0.5], [0.0, 0.0, 1.0]])


def work_matrix(matrix, fx: float, fy: float) -> np.ndarray:
    """A full-resolution 2x3 (or 3x3) matrix in working pixels (3x3).

    >>> m = np.array([[1.0, 0.0, 8.0], [0.0, 1.0, -4.0]])
    >>> work_matrix(m, 0.25, 0.25)[:2].round(3).tolist()
    [[1.0, 0.0, 2.0], [0.0, 1.0, -1.0]]
    """
    m = np.asarray(matrix, np.float64)
    if m.shape == (2, 3):
        m = np.vstack([m, [0.0, 0.0, 1.0]])
    s = _scaling(fx, fy)
    return s @ m @ np.linalg.inv(s)


def full_matrix(matrix, fx: float, fy: float) -> np.ndarray:
    """The inverse of :func:`work_matrix` (3x3 in, 3x3 out).

    >>> m = np.array([[1.0, 0.0, 8.0], [0.0, 1.0, -4.0]])
    >>> bool(np.allclose(full_matrix(work_matrix(m, 0.3, 0.3), 0.3, 0.3)[:2], m))
    True
    """
    s = _scaling(fx, fy)
    return np.linalg.inv(s) @ np.asarray(matrix, np.float64) @ s


def strongest(edges: EdgePoints, count: int = MAX_POINTS):
    """The ``count`` strongest edge points: (x, y, angle) float64 arrays,
    strongest first (equal strengths in the edges' order).

    >>> from seahough.core.keypoints import EdgePoints
    >>> e = EdgePoints(*(np.arange(5.0),) * 2, np.zeros(5), np.array([1.0, 3, 2, 3, 0]),
    ...                np.ones(5), np.zeros(5), (4, 6))
    >>> strongest(e, 3)[0].tolist()
    [1.0, 3.0, 2.0]
    """
    mag = edges.magnitude
    n = mag.size
    if count >= n:
        order = np.argsort(-mag, kind="stable")
    else:   # (the strongest picked first: a frame has 10-100x more edge points)
        thr = np.partition(mag, n - count)[n - count]
        keep = np.flatnonzero(mag > thr)
        keep = np.sort(np.concatenate([keep, np.flatnonzero(mag == thr)[: count - keep.size]]))
        order = keep[np.argsort(-mag[keep], kind="stable")]
    return (edges.x[order].astype(np.float64), edges.y[order].astype(np.float64),
            edges.angle[order].astype(np.float64))


def frame_points(pattern, factor: float, config, count: int = MAX_POINTS):
    """The previous frame's gradients at working scale ``factor`` and its
    ``count`` :func:`strongest` edge points (x, y, angle)."""
    # (the pattern's own levels: 8 bits are downscaled as they are, not copied
    # to float at full resolution; a frame pattern is grey)
    grad = compute_gradients(pattern.grey_levels(), factor, config.equalize)
    return grad, strongest(find_edge_points(grad, config.min_gradient), count)


def _fit_similarity(c, q, weight, known=None, keep=(False, False)):
    """Weighted least-squares similarity c -> q (2x3), None when degenerate.
    ``keep`` = (scale, rotation): those of the 2x3 matrix ``known`` are kept
    (the rest is fitted)."""
    w = weight / weight.sum()
    mc, mq = (c * w[:, None]).sum(0), (q * w[:, None]).sum(0)
    a, b = c - mc, q - mq
    sxx = (w * (a ** 2).sum(1)).sum()
    if sxx <= 1e-9 and not all(keep):
        return None
    cc = (w * (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])).sum() / max(sxx, 1e-9)
    ss = (w * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])).sum() / max(sxx, 1e-9)
    if any(keep):
        k = np.asarray(known, float)
        turn = math.atan2(k[1, 0], k[0, 0]) if keep[1] else math.atan2(ss, cc)
        if keep[0]:
            scale = math.hypot(k[0, 0], k[1, 0])
        elif keep[1]:    # (the least-squares scale along the known rotation)
            scale = cc * math.cos(turn) + ss * math.sin(turn)
        else:
            scale = math.hypot(cc, ss)
        cc, ss = scale * math.cos(turn), scale * math.sin(turn)
    r = np.array([[cc, -ss], [ss, cc]])
    return np.hstack([r, (mq - r @ mc)[:, None]])


def local_evidence(points, edges: EdgePoints, index: np.ndarray, matrix, bg: Background,
                   log_tests: float, *, tol: float, grid: int = GRID,
                   radius: float = RADIUS, match_radius: float = SCORE_RADIUS,
                   keep=(False, False)) -> LocalEvidence | None:
    """The :class:`LocalEvidence` of the motion ``matrix`` (2x3 or 3x3,
    previous-frame working pixel -> current-frame working pixel) of the
    previous frame's edge ``points`` (x, y, angle: :func:`strongest`) among
    the current frame's ``edges`` (``index``: their index map; ``bg``: its
    background model; ``log_tests``: log10 of the poses the search tried).
    ``keep`` = (scale, rotation): those known quantities of ``matrix`` are
    kept by the similarity fitted to the tiles. None when fewer than 2
    tiles are in view.

    (Two neighbouring tiles that shift apart may both count the same edge
    points of the current frame near their common border: a few per cent of
    a tile's points at most, left in the count.)

    Examples
    --------
    A frame and a copy moved by 5 px: each tile is found in place.

    >>> from seahough.core.keypoints import find_edge_points
    >>> from seahough.core.preprocess import compute_gradients
    >>> from seahough.core.nfa import background
    >>> from seahough.sim import seabed
    >>> g = seabed((240, 320), seed=2)[:, :, 1].astype(np.float32)
    >>> prev = find_edge_points(compute_gradients(g[:, :300]), 20)
    >>> cur = find_edge_points(compute_gradients(g[:, 5:305]), 20)
    >>> idx = cur.index_map()
    >>> bg = background(cur, 1.5, math.radians(20), None, idx)
    >>> ev = local_evidence(strongest(prev), cur, idx, [[1, 0, -5], [0, 1, 0]], bg, 5.0,
    ...                     tol=math.radians(20))
    >>> ev.score > 0.8, ev.tiles, ev.nfa < 1e-50, ev.parallax < 0.5
    (True, 16, True, True)
    """
    m = np.asarray(matrix, np.float64)[:2]
    px, py, pa = points
    n_all = px.size
    h, w = index.shape
    # the points that land in the current frame at this motion (1 px inside)
    qx = m[0, 0] * px + m[0, 1] * py + m[0, 2]
    qy = m[1, 0] * px + m[1, 1] * py + m[1, 2]
    inside = (qx >= 1) & (qy >= 1) & (qx <= w - 2) & (qy <= h - 2)
    px, py, pa = px[inside], py[inside], pa[inside]
    if px.size < 2 * MIN_TILE_POINTS:
        return None
    x0, y0, x1, y1 = px.min(), py.min(), px.max() + 1e-6, py.max() + 1e-6
    tile = (np.minimum(((px - x0) / (x1 - x0) * grid).astype(np.int64), grid - 1) * grid
            + np.minimum(((py - y0) / (y1 - y0) * grid).astype(np.int64), grid - 1))
    a, b = float(m[0, 0]), float(m[0, 1])
    tx, ty = float(m[0, 2]), float(m[1, 2])
    radii = np.array([radius, 3.0, match_radius])
    centres, shifted, weights = [], [], []
    matched = 0
    n_obs = k_obs = 0
    p_sum = 0.0
    for t in range(grid * grid):
        sel = tile == t
        n = int(sel.sum())
        if n < MIN_TILE_POINTS:
            continue
        sx, sy, sa = px[sel], py[sel], pa[sel]
        r = K.icp(sx, sy, sa, a, b, tx, ty, edges.x, edges.y, edges.angle, edges.nx, edges.ny,
                  index, radii, 3, float(tol), False, True, True, 0.02, match_radius, 1e-3)
        ttx, tty = float(r[2]), float(r[3])
        if not (math.isfinite(ttx) and math.isfinite(tty)) or math.hypot(ttx - tx, tty - ty) > radius:
            ttx, tty = tx, ty           # (drifted away: the tile stays at the similarity)
            r = K.icp(sx, sy, sa, a, b, tx, ty, edges.x, edges.y, edges.angle, edges.nx,
                      edges.ny, index, radii[-1:], 0, float(tol), False, True, True, 0.02,
                      match_radius, 1e-3)
        ev = evidence(Pose(a, b, ttx, tty), sx, sy, sa, edges, index, bg, 0.0, tol=tol,
                      either=False)
        n_obs += ev.n_obs
        k_obs += ev.k_obs
        p_sum += ev.p * ev.n_obs
        matched += int(r[5])
        cx, cy = float(sx.mean()), float(sy.mean())
        centres.append((cx, cy))
        shifted.append((ttx + a * cx + b * cy, tty - b * cx + a * cy))
        weights.append(max(float(r[5]), 1.0))
    if len(centres) < 2:
        return None
    c = np.array(centres)
    q = np.array(shifted)
    wgt = np.array(weights)
    known = keep
    keep = np.ones(len(c), bool)
    sim = m
    for _ in range(3):   # (a tile that found the wrong edges leaves the fit)
        fit = _fit_similarity(c[keep], q[keep], wgt[keep], m, known)
        if fit is None:
            break
        sim = fit
        res = np.hypot(*(q - (c @ sim[:, :2].T + sim[:, 2])).T)
        keep = res <= 3.0 * float(np.median(res)) + 1.0
        if keep.sum() < 2:
            break
    res = np.hypot(*(q - (c @ sim[:, :2].T + sim[:, 2])).T)
    hom = None
    if keep.sum() >= MIN_HOMOGRAPHY_TILES:   # (the tiles the similarity kept; 4 fit exactly)
        hom, _ = cv2.findHomography(c[keep].astype(np.float64), q[keep].astype(np.float64), 0)
        if hom is not None and not (np.all(np.isfinite(hom)) and abs(hom[2, 2]) > 1e-9):
            hom = None
    tail = (log10_binom_tail(k_obs, n_obs, max(p_sum / n_obs, MIN_CHANCE)) if n_obs
            else 0.0)
    tests = log_tests + len(c) * math.log10(max(math.pi * radius * radius, 1.0))
    return LocalEvidence(matched / max(n_all, 1), max(tests + tail, MIN_LOG10_NFA), len(c),
                         float(np.median(res)), sim, hom)


@dataclass
class LocalCheck:
    """What :func:`check_locally` found: the motion it chose and its evidence."""

    matrix: np.ndarray          # 2x3, previous -> current full-resolution pixels
    confidence: float
    score: float
    nfa: float
    parallax: float             # full-resolution pixels
    homography: np.ndarray | None
    distinct: float = 0.0       # 1 - runner-up / answer, of the vote's own scores


def _candidate_matrix(pose, owx: float, owy: float) -> np.ndarray:
    """A candidate's working pose (pattern points relative to the origin at
    working pixel ``(owx, owy)``) as a 2x3 working-pixel matrix."""
    a, b = pose.a, pose.b
    return np.array([[a, b, pose.tx - a * owx - b * owy], [-b, a, pose.ty + b * owx - a * owy]])


def check_locally(pattern, result, detection, region, scale_range, angle_range, config,
                  candidates: int = CANDIDATES, frame=None,
                  min_distinct: float = 0.0) -> LocalCheck | None:
    """Choose a frame pair's motion by its evidence measured tile by tile.

    ``pattern`` is the previous frame (:meth:`~seahough.Pattern.from_frame`),
    ``result`` the :class:`~seahough.core.detector.SearchResult` of its
    search in the current frame within ``region`` (current-frame pixels) and
    the ranges, ``detection`` its best detection (None: none passed the
    search's thresholds; its best candidate stands in). The detection and the
    ``candidates`` best other candidate poses are measured tile by tile; the
    one with the highest score is the motion (a look-alike of a repeated
    texture, or a pose that a similarity favours only because parallax
    spoils the right one, loses here). Its confidence rates it against the
    best of the others that lie more than :data:`SAME` working pixels away
    at the frame's corners (nearer ones are the same answer), and never
    above how distinct the vote found it (``distinct``: ``1 - runner-up /
    answer`` of their working-scale scores). The matrix is the similarity
    fitted to the chosen pose's tile shifts; ``parallax`` is measured
    against it. None when too little of the frame is in view to cut it
    into tiles. ``frame``: the previous frame's :func:`frame_points` at
    the search's working scale, when already made. ``min_distinct``: None
    as well, without measuring a tile, when no pose that could be chosen is
    that distinct in the vote (a caller that would discard such an answer).
    """
    feats = result.features
    if feats is None:
        return None
    fx, fy, factor = feats.gradients.fx, feats.gradients.fy, result.factor
    tol = math.radians(config.angle_tolerance)
    radius = max(1.25, config.match_radius * factor)   # (the search's evidence radius)
    grad, points = frame or frame_points(pattern, factor, config)
    bg = background(feats.edges, radius, tol, None, feats.index)
    x0, y0, x1, y1 = region
    fh, fw = feats.gradients.full_shape[:2]
    area = max(min(x1, fw) - max(x0, 0), 1.0) * max(min(y1, fh) - max(y0, 0), 1.0) * fx * fy
    tests = log10_tests(area, pattern.features(factor, config).radius, scale_range, angle_range)
    ox, oy = pattern.origin
    owx, owy = (ox + 0.5) * fx - 0.5, (oy + 0.5) * fy - 0.5
    # the detection (finished at full resolution), then the other candidates
    ph, pw = grad.magnitude.shape
    corners = np.array([[0, 0, 1], [pw - 1, 0, 1], [pw - 1, ph - 1, 1], [0, ph - 1, 1]], float)
    cands = sorted(result.candidates, key=lambda c: -c.work_score)
    cand_m = [_candidate_matrix(c.fit.pose, owx, owy) for c in cands]
    cand_at = [corners @ m.T for m in cand_m]
    poses = cand_m[:candidates]
    if detection is not None:
        poses = [work_matrix(detection.matrix, fx, fy)[:2]] + poses
    if not poses:
        return None
    at = [corners @ m.T for m in poses]
    known = (scale_range[0] == scale_range[1], angle_range[0] == angle_range[1])

    def gap(a, b):
        return float(np.hypot(*(a - b).T).max())

    def distinct_at(a):
        # how distinct the vote found the pose at corners ``a``: 1 - runner-up / own
        gaps = [gap(c, a) for c in cand_at]
        own = cands[int(np.argmin(gaps))].work_score
        rival = max((c.work_score for c, g in zip(cands, gaps) if g > SAME), default=0.0)
        return float(np.clip(1.0 - rival / max(own, 1e-9), 0.0, 1.0))

    if min_distinct > 0 and (not cands or max(map(distinct_at, at)) < min_distinct):
        return None

    # the tiles may not shift as far as the nearest rival peak of the vote: a
    # repeated texture's look-alikes (pool tiles) lie a period apart
    near = min((g for g in (gap(a, at[0]) for a in cand_at) if g > SAME), default=np.inf)
    reach = float(np.clip(0.5 * near, 1.5, RADIUS))
    found = [local_evidence(points, feats.edges, feats.index, m, bg, tests, tol=tol,
                            radius=reach, match_radius=radius, keep=known) for m in poses]
    if found[0] is None:
        return None
    # the search's answer stands unless another pose explains clearly more
    best = max((i for i, e in enumerate(found) if e is not None), key=lambda i: found[i].score)
    if found[best].score < found[0].score + SWITCH:
        best = 0
    ev = found[best]

    runner = max((e.score for i, e in enumerate(found) if e is not None
                  and gap(at[i], at[best]) > SAME), default=0.0)
    conf = float(np.clip((ev.score - runner) / max(1.0 - runner, 1e-9), 0.0, 1.0))
    # ... and as distinct in the vote: a repeated texture's look-alikes (tiles)
    # each fit well tile by tile, and not every one of them is a candidate
    distinct = 0.0
    if cands:
        distinct = distinct_at(at[best])
        conf = min(conf, distinct)
    # the motion: the similarity that fits the chosen pose's tiles' shifts
    # (the parts of the frame say where it is; a finish at full resolution
    # with a 1.5 px radius fits the part that the similarity suits best)
    m_full = full_matrix(np.vstack([ev.similarity, [0.0, 0.0, 1.0]]), fx, fy)[:2]
    hom = None
    if ev.homography is not None:
        hom = full_matrix(ev.homography, fx, fy)
        hom = hom / hom[2, 2]
    return LocalCheck(np.asarray(m_full, float)[:2], conf, ev.score, ev.nfa,
                      float(ev.parallax / math.sqrt(fx * fy)), hom, distinct)
