"""Coarse to fine: a frame pair voted where a repeated texture blurs away,
refined as a homography where its detail is.

Over a tiled floor seen by a camera that looks ahead (a pool robot), the
search at the working scale (320 px) fails twice: the tiles' grid gives the
vote as many near-equal peaks as there are tile shifts, and the perspective
change spreads the true motion's votes over neighbouring cells, so that the
true peak is often not among the candidates at all (issue 13: the real
tiled pool sequence, 1 loop closed in 10). At a coarse scale (the frame's
long side :data:`COARSE_SIZE` px) the tiles average away and what is left
is what does not repeat (a rope, bricks, the pool's wall, the light), and
the perspective change is a pixel or two: the vote's peak there is the
motion, a few coarse pixels off.

So the previous frame is searched for in the current one at the coarse
scale; its answer is refitted as a homography at that scale
(:func:`~seahough.motion.perspective.homography_icp`, radii
:data:`COARSE_RADII`), then at every doubling of the scale up to the
search's working scale (radii :data:`STEP_RADII`: each level starts
within a pixel or two of its answer, less than a tile, so it cannot slide
to a look-alike a tile off), then finished at twice the working scale
(:func:`~seahough.motion.perspective.judge_homography`). The evidence is
measured at the working scale, as for the other checks: ``score``, the
share of the previous frame's edge points found again; ``nfa``, their
agreement against chance, the working-scale search's poses times the
homography's extra freedom; ``confidence``: the coarse vote's (how much it
preferred its answer to the runner-up), which the caller's
``min_confidence`` judges.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.detector import Detector
from ..core.keypoints import find_edge_points
from ..core.pattern import Pattern
from ..core.preprocess import compute_gradients, scale_image
from ..errors import ImageSizeError, PatternError
from ..geometry import corner_gap
from .parallax import LocalCheck, frame_points, full_matrix, work_matrix
from .perspective import FINE_POINTS, MIN_IN_VIEW, homography_icp, judge_homography

__all__ = ["COARSE_SIZE", "COARSE_POINTS", "COARSE_RADII", "STEP_RADII", "AGREE", "CoarseVote",
           "coarse_vote", "ladder", "refine_up", "coarse_to_fine"]

#: The coarse scale: the frame's long side, pixels.
COARSE_SIZE = 80
#: Pattern points voted at the coarse scale (about every edge point of an
#: 80 px frame), and points checked.
COARSE_POINTS = (512, 1200)
#: Match radii of the homography fit at the coarse scale (coarse pixels) ...
COARSE_RADII = (2.0, 1.5, 1.0)
#: ... and at each finer level (pixels of that level).
STEP_RADII = (2.0, 1.5)
#: A vote's answer agrees with the coarse one when the frame's corners lie
#: within this many coarse pixels (a tile of the real pool is 2-3 of them
#: near the bottom of the frame; the perspective change a similarity leaves
#: out, about 1).
AGREE = 2.0


def coarse_to_fine(pattern, gray, scale_range, angle_range, region, config, result,
                   frame=None) -> LocalCheck | None:
    """A frame pair's motion voted at the coarse scale and refined up to the
    working scale of ``result`` (the module's docstring).

    ``pattern`` is the previous frame (:meth:`~seahough.Pattern.from_frame`),
    ``gray`` the current frame (grey, full resolution), ``result`` the
    :class:`~seahough.core.detector.SearchResult` of the pattern's search in
    it within ``region`` and the ranges, ``frame`` the previous frame's
    :func:`~.parallax.frame_points` at the working scale when already made.
    Returns a :class:`~.parallax.LocalCheck` (its ``matrix`` the similarity
    that fits the homography best over the frame, its ``parallax`` the RMS
    distance of the homography from it, full-resolution pixels), or None:
    the working scale is not finer than the coarse one, the scale or the
    rotation is known (a homography would free it), the coarse search found
    nothing, a level's fit failed (:func:`ladder`: nothing matched, under
    :data:`~.perspective.MIN_IN_VIEW` of the points left in view, or a
    corner behind the camera), or the homography keeps too little of the
    frame in view to fit a similarity to it.

    Examples
    --------
    Two views of a tiled floor seen by a camera tilted 40 degrees forward, the
    second a step further on: the search at the working scale finds nothing
    it can tell from its look-alikes; coarse to fine finds the motion within
    a pixel at the frame's corners.

    >>> import numpy as np
    >>> from seahough import Pattern, sim, to_gray
    >>> from seahough.config import MOTION_CONFIG
    >>> from seahough.core.detector import Detector
    >>> frames, truth = sim.relief_sequence(
    ...     n_frames=2, frame_size=(360, 640), seed=0, source="tiles", tilt=40.0,
    ...     forward=True, strobe=False, relief=0.01, altitude=(1.0, 2.0),
    ...     step=(0.06, 0.15), turn=2.0, water=None)
    >>> prev, cur = to_gray(frames[0]), to_gray(frames[1])
    >>> pattern = Pattern.from_frame(prev, config=MOTION_CONFIG)
    >>> region = (0, 0, 640, 360)         # where the previous frame's centre may go
    >>> res = Detector(pattern, (0.8, 1.25), (-30, 30), config=MOTION_CONFIG,
    ...                search_region=region).search(cur)
    >>> res.detections
    []
    >>> check = coarse_to_fine(pattern, cur, (0.8, 1.25), (-30, 30), region, MOTION_CONFIG, res)
    >>> corners = np.array([[0, 0, 1], [639, 0, 1], [639, 359, 1], [0, 359, 1]], float)
    >>> err = corners @ (check.matrix - truth.similarity(0, 1)[0]).T
    >>> bool(np.hypot(*err.T).max() < 1.0), bool(check.nfa < 1e-100), check.homography.shape
    (True, True, (3, 3))
    """
    vote = coarse_vote(pattern, gray, scale_range, angle_range, region, config, result)
    if vote is None:
        return None
    return refine_up(vote, pattern, gray, scale_range, angle_range, region, config, result, frame)


@dataclass
class CoarseVote:
    """The coarse search's answer (:func:`coarse_vote`)."""

    matrix: np.ndarray     # 3x3, previous -> current full-resolution pixels (a similarity)
    confidence: float      # the coarse vote's: its answer against its runner-up
    factor: float          # the coarse scale (coarse pixels a full-resolution pixel)

    def agrees(self, matrix, shape, within: float = AGREE) -> bool:
        """Whether a 2x3 similarity puts the frame's corners within
        ``within`` coarse pixels of this answer."""
        return bool(corner_gap(self.matrix, matrix, shape) * self.factor <= within)


def coarse_vote(pattern, gray, scale_range, angle_range, region, config, result
                ) -> CoarseVote | None:
    """The previous frame searched for in the current one at the coarse scale
    (:func:`coarse_to_fine`'s first step). None: ``result`` (the search at
    the working scale) has no features, the scale or the rotation is known,
    the frame is too small to be coarser than that search, or nothing was
    found."""
    if result.features is None:
        return None
    if scale_range[0] == scale_range[1] or angle_range[0] == angle_range[1]:
        return None
    h, w = gray.shape[:2]
    if min(1.0, COARSE_SIZE / max(h, w)) >= result.factor * 0.99:
        return None   # (a frame too small to be searched coarser than it was)
    coarse = config.replace(target_size=COARSE_SIZE, downscale=None,
                            n_pattern_points=COARSE_POINTS[0], n_verify_points=COARSE_POINTS[1])
    # (searched in both frames brought to twice the coarse size: the search's
    # own finish at "full resolution" then costs what the coarse search does)
    small = min(1.0, 2.0 * COARSE_SIZE / max(h, w))
    prev, fx, fy = scale_image(pattern.grey_levels(), small)
    cur, _, _ = scale_image(gray, small)
    x0, y0, x1, y1 = region
    region_small = ((x0 + 0.5) * fx - 0.5, (y0 + 0.5) * fy - 0.5,
                    (x1 + 0.5) * fx - 0.5, (y1 + 0.5) * fy - 0.5)
    ox, oy = pattern.origin
    try:
        ps = Pattern.from_frame(prev, ((ox + 0.5) * fx - 0.5, (oy + 0.5) * fy - 0.5),
                                config=coarse)
        det = Detector(ps, scale_range, angle_range, config=coarse, max_results=1,
                       min_score=0.0, min_confidence=0.0, max_nfa=math.inf,
                       search_region=region_small)
        res = det.search(cur)
    except (PatternError, ImageSizeError):   # (no edges left at that size, or a strip)
        return None
    if not res.detections or res.factor * small >= result.factor * 0.99:
        return None
    d = res.detections[0]
    Hf = full_matrix(np.vstack([np.asarray(d.matrix, float), [0.0, 0.0, 1.0]]), fx, fy)
    return CoarseVote(Hf / Hf[2, 2], float(d.confidence), res.factor * small)


def refine_up(vote: CoarseVote, pattern, gray, scale_range, angle_range, region, config,
              result, frame=None) -> LocalCheck | None:
    """The coarse answer refitted as a homography at the coarse scale, then at
    each doubling up to the working scale of ``result``, and judged there
    (:func:`coarse_to_fine`'s second step; None: a level's fit failed)."""
    fit = ladder(vote, pattern, gray, config, result, frame)
    if fit is None:
        return None
    H, score, points = fit
    return judge_homography(H, vote.confidence, score, pattern, result, region, scale_range,
                            angle_range, config, points, gray)


def ladder(vote: CoarseVote, pattern, gray, config, result, frame=None):
    """``vote``'s answer refitted as a homography from its scale up to the
    working scale of ``result`` (:func:`coarse_to_fine`): ``(H, score,
    points)``, the working-scale homography, the share of the previous
    frame's ``points`` (its strongest edge points at the working scale) it
    matches there; None when a level's fit matched nothing, kept under
    :data:`~.perspective.MIN_IN_VIEW` of the points in view, or put a
    corner behind the camera. An answer at the working scale itself is
    refitted there only."""
    feats, top = result.features, result.factor
    tol = math.radians(config.angle_tolerance)
    Hf = vote.matrix
    levels = [min(vote.factor, top)]
    while levels[-1] * 2 < top * 0.99:
        levels.append(levels[-1] * 2)
    if levels[-1] < top * 0.99:
        levels.append(top)
    levels[-1] = top
    for k, factor in enumerate(levels):
        radii = COARSE_RADII if k == 0 else STEP_RADII
        if factor == top:   # (the search's own features)
            grad, edges, index = feats.gradients, feats.edges, feats.index
            points = (frame or frame_points(pattern, factor, config))[1]
        else:
            points = frame_points(pattern, factor, config, FINE_POINTS)[1]
            grad = compute_gradients(gray, factor, config.equalize)
            edges = find_edge_points(grad, config.min_gradient)
            index = edges.index_map()
        H, score, inside = homography_icp(work_matrix(Hf, grad.fx, grad.fy), points, edges,
                                          index, tol, radii=radii,
                                          score_radius=max(1.25, config.match_radius * factor))
        if score <= 0 or inside < MIN_IN_VIEW or not _in_front(H, grad.magnitude.shape):
            return None
        Hf = full_matrix(H, grad.fx, grad.fy)
        Hf = Hf / Hf[2, 2]
    return H, score, points


def _in_front(H, shape) -> bool:
    """Whether the homography keeps the frame's corners in front of the camera."""
    h, w = shape[:2]
    c = np.array([[0, 0, 1], [w - 1, 0, 1], [w - 1, h - 1, 1], [0, h - 1, 1]], float)
    return bool(np.all(c @ np.asarray(H)[2] > 0))
