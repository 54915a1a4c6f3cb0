"""Stage 7a: near symmetries of a pattern, and the turn its own details decide.

A marker board is a square frame with a few small cells inside: turned by a
quarter, its frame falls on itself and only the cells tell the turns apart.
The search finds the frame; which of the four turns it reports is decided
by the little the cells add to the score, and at a distance, in murky water,
the vote often picks a wrong one (on the coloured markers of
``bench/bench_colour.py``, a third of the boards were found at the right
place and scale but turned).

:func:`near_turns` finds the quarter and half turns about the pattern's
centre that map most of its edge points onto its own (a *near* symmetry:
at least :data:`NEAR` of them, and fewer than :data:`EXACT`: an exact
symmetry is the same answer, see
:meth:`~seahough.core.candidates.PoseComparison.equivalent`).
:func:`turn_pose` composes a pose with such a turn; the ranking
(:func:`seahough.core.ranking.rank`) refines each turned pose of a
candidate and keeps the one whose full-resolution score is highest: the
frame scores the same in every turn, so the details decide.
"""

from __future__ import annotations

import math

import numpy as np

from . import kernels as K
from .keypoints import find_edge_points
from .preprocess import compute_gradients
from .refine import Pose

#: Share of the pattern's points a turn must map onto its own points for a
#: near symmetry.
NEAR = 0.6
#: From this share on, the turn is an exact symmetry (the same answer; a drawn
#: rectangle turned by a half maps 97.9 % of its sampled points onto its edges).
EXACT = 0.95
#: The turns tried (degrees, counter-clockwise as displayed).
TURNS = (90.0, 180.0, 270.0)


def near_turns(vx, vy, vang, edges, index, origin=(0.0, 0.0), *, tol: float,
               radius: float = 1.5) -> tuple:
    """``((theta, cx, cy), ...)``: the turns of :data:`TURNS` (radians) about
    the centre (cx, cy) of the pattern's edges that put at least
    :data:`NEAR` and fewer than :data:`EXACT` of its points ``vx, vy, vang``
    (relative to ``origin``) within ``radius`` of one of its edge points
    (``edges``, :class:`~.keypoints.EdgePoints` of the pattern image, and
    their ``index`` map) of the same direction (within ``tol`` radians; of
    the same sign even for a pattern of either polarity: turned, a board's
    cells fall on cells of the other sign).
    The points are a sample, the edges all of them: the sample need not be
    symmetric itself. ``(cx, cy)``: the middle of the edges' bounding box,
    relative to ``origin``.

    Examples
    --------
    >>> from seahough.core.keypoints import find_edge_points
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((80, 80), np.float32); img[20:60, 20:60] = 200     # a square ...
    >>> def turns(img):
    ...     e = find_edge_points(compute_gradients(img), 20.0)
    ...     o = (39.5, 39.5)
    ...     return near_turns(e.x - o[0], e.y - o[1], e.angle, e, e.index_map(), o, tol=0.26)
    >>> turns(img)                                                     # exact: none
    ()
    >>> img[26:31, 26:40] = 0                                          # ... with a mark
    >>> [round(math.degrees(t[0])) for t in turns(img)]
    [90, 180, 270]
    """
    return tuple((theta, cx, cy) for share, theta, cx, cy in turn_shares(
        vx, vy, vang, edges, index, origin, tol=tol, radius=radius) if NEAR <= share < EXACT)


def turn_shares(vx, vy, vang, edges, index, origin=(0.0, 0.0), *, tol: float,
                radius: float = 1.5) -> tuple:
    """``((share, theta, cx, cy), ...)`` for each turn of :data:`TURNS`: the
    share of the points it maps onto the pattern's edges (:func:`near_turns`
    says how); ``()`` for fewer than 8 points or edges."""
    vx, vy, vang = (np.asarray(v, np.float64) for v in (vx, vy, vang))
    if vx.size < 8 or len(edges) < 8:
        return ()
    ox, oy = float(origin[0]), float(origin[1])
    cx = 0.5 * (float(edges.x.min()) + float(edges.x.max())) - ox
    cy = 0.5 * (float(edges.y.min()) + float(edges.y.max())) - oy
    out = []
    for deg in TURNS:
        theta = math.radians(deg)
        q = turn_pose(Pose(1.0, 0.0, ox, oy), theta, cx, cy)   # turned, in image pixels
        ids, _ = K.match_points(vx, vy, vang, q.a, q.b, q.tx, q.ty, edges.x, edges.y,
                                edges.angle, index, float(radius), float(tol), False)
        out.append((float(np.mean(ids >= 0)), theta, cx, cy))
    return tuple(out)


def pattern_turn_shares(pattern, config) -> tuple:
    """:func:`turn_shares` of a :class:`~.pattern.Pattern` with ``config``
    (cached on it; none for frames and lines): its sampled points against
    all the edges they were taken from."""
    if pattern.is_frame or pattern.is_line:
        return ()

    def shares():
        f = pattern.features(1.0, config)
        e = find_edge_points(compute_gradients(np.asarray(pattern._prepared(config), np.float32),
                                               1.0, config.equalize), config.min_gradient)
        if pattern._edge_mask is not None and len(e):
            e = e.take(pattern._edge_mask[e.iy, e.ix])
        return turn_shares(f.vx, f.vy, f.vangle, e, e.index_map(), pattern.origin,
                           tol=math.radians(config.angle_tolerance))
    key = ("turn shares",) + pattern._features_key(1.0, config) + (config.angle_tolerance,)
    return pattern._cache.get_or_compute(key, shares)


def symmetry_turn(shares) -> float:
    """The least turn (degrees: 90 or 180) that maps the pattern onto itself
    exactly (at least :data:`EXACT` of its points, :func:`turn_shares`'
    ``shares``), or 360 when none does: its angle is known up to that turn.

    >>> symmetry_turn(((0.2, math.pi / 2, 0, 0), (0.98, math.pi, 0, 0), (0.2, 1.5 * math.pi, 0, 0)))
    180.0
    >>> symmetry_turn(()), symmetry_turn(((0.97, math.pi / 2, 0, 0), (0.99, math.pi, 0, 0)))
    (360.0, 90.0)
    """
    turns = [math.degrees(theta) for share, theta, _, _ in shares if share >= EXACT]
    return float(round(min(turns))) if turns else 360.0


def turn_pose(pose: Pose, theta: float, cx: float, cy: float) -> Pose:
    """``pose`` composed with a turn of the pattern by ``theta`` about (cx,
    cy) (pattern coordinates): the pose that puts the turned pattern where
    ``pose`` puts the pattern.

    Examples
    --------
    >>> p = Pose.from_params(100.0, 50.0, 2.0, 0.3)
    >>> q = turn_pose(p, math.pi / 2, 0.0, 0.0)
    >>> round(q.scale, 6), round(q.angle - p.angle, 6)          # (degrees)
    (2.0, 90.0)
    >>> x, y = turn_pose(p, math.pi, 10.0, 0.0).map(np.array([20.0]), np.array([0.0]))
    >>> x0, y0 = p.map(np.array([0.0]), np.array([0.0]))       # 20 turned about 10 is 0
    >>> bool(np.allclose([x[0], y[0]], [x0[0], y0[0]]))
    True
    """
    c, s = math.cos(theta), math.sin(theta)
    a, b = pose.a * c - pose.b * s, pose.a * s + pose.b * c
    # where the turn puts the pattern's origin: (cx, cy) - Rot (cx, cy)
    u = cx - (c * cx + s * cy)
    w = cy - (-s * cx + c * cy)
    return Pose(a, b, pose.tx + pose.a * u + pose.b * w, pose.ty - pose.b * u + pose.a * w)
