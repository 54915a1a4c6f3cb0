"""Stage 6b: the a-contrario decision, the number of false alarms (NFA).

A candidate pose puts ``n`` pattern points on the image, and ``k`` of them
find an image edge point of compatible direction within the match radius.
How surprising is that? In an image holding no object (the *background
model*), a point placed at random finds such an edge point with a
probability ``p`` that depends on where it lies: bare sand offers few
edges, textured seabed many. The chance that at least ``k`` of ``n`` points
agree is the tail of a binomial; the search tried many poses (positions x
scales x rotations), and the expected number of poses that agree that well
by chance is::

    NFA = N_tests * P[Binomial(n, p) >= k]

An answer with NFA <= 1 is one false alarm per image at most, on average
(Desolneux, Moisan and Morel, *From Gestalt Theory to Image Analysis*,
2008; Grompone von Gioi et al., LSD, IPOL 2012): a bound, which on
object-free seabed photos holds several times loose (``docs/nfa.md`` says
why it is not made a count: a calibrated model was measured and not
adopted).

``p`` comes from the searched image itself (:class:`Background`): the
share of the pixel positions near each place, per direction, that lie
within the match radius of an edge point of that direction, measured over
cells of :data:`CELL` working pixels and smoothed over 3 x 3 cells.
Agreement counts image edge points, each once however many pattern points
fall on it (``n`` and ``k`` in the same unit: :func:`evidence`).
Neighbouring points along an edge do not agree independently (an edge that
lies along the pattern's for one pixel does so for several): one
observation is counted per :data:`DEPENDENCE` pixels of edge at most, a
length measured on object-free real photos (``bench/bench_nfa.py``,
``docs/nfa.md``). Everything is computed in log10 to keep tiny tails.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import kernels as K

#: Side of a background cell, working pixels (the model is smoothed over
#: 3 x 3 cells, a window of 24 px: a local density, not the image's).
CELL = 8
#: The model samples every STRIDE-th pixel centre in x and y (an unbiased
#: estimate of each cell's share, at a quarter of the cost).
STRIDE = 2
#: Length of edge, in pixels, over which agreement is one observation (see
#: the module docstring): pattern points closer than that along an edge
#: share one, points farther apart (a frame's points, spread several pixels
#: apart) are each one. Measured on the tuning part of bench/bench_nfa.py
#: as 4 edge points (the smallest value at which the NFA holds as a bound);
#: a thinned edge has |cos a| + |sin a| of them a pixel, 4 / pi on average
#: over directions, so 4 edge points are pi pixels on average (a conversion,
#: not measured again: on object-free photos the NFA alone then let more
#: chance answers through, docs/nfa.md, thirteenth session). Counted in
#: pixels, the same edge turned is the same evidence (counted in edge
#: points, a box turned by 45 degrees had 1.4 times the observations of the
#: upright one: NFA 1e-78 against 1e-49).
DEPENDENCE = math.pi
#: Pattern points within this many working pixels of the image's border
#: are not counted: the border holds the camera's own straight edges (dark
#: lines that sensors and video decoders leave, a vignetted rim), which a
#: shape's straight side fits along its whole length (an L-shaped marker
#: "found" in the corner of 20 of the 22 Sparus frames).
BORDER = 3.0
#: The chance of a match is never taken below this: the model samples
#: every STRIDE-th position, and an isolated edge point's disc can hold
#: none of them (half a sample of the 3 x 3 cells around).
MIN_CHANCE = 0.5 / (9 * (CELL // STRIDE) ** 2)
#: log10 NFA never goes below this (the float stays representable).
MIN_LOG10_NFA = -300.0


@dataclass
class Background:
    """Where chance matches are likely in one image.

    ``cover[cy, cx, b]``: for cell (cx, cy) and direction ``b`` (the centre
    of the ``b``-th of ``nbins`` equal bins of [0, 2 pi)), the share of the
    positions of the 3 x 3 cells around that lie within the match radius of
    an edge point whose direction is within the tolerance of ``b``: the
    chance that a point placed there at random, wanting that direction,
    finds a match. Between bin centres it is interpolated.
    """

    cover: np.ndarray     # (gy, gx, nbins) float64
    cell: int
    radius: float
    origin: tuple = (0, 0)  # the top-left pixel (x, y) of cell (0, 0)


def n_direction_bins(tol: float) -> int:
    """Directions of the background model for a tolerance of ``tol``
    radians: about one tolerance apart (24 for 15 degrees), so that the
    chance varies little between two of them.

    >>> n_direction_bins(math.radians(15))
    24
    """
    return int(np.clip(round(2 * math.pi / max(tol, 1e-6)), 8, 32))


def background(edges, radius: float, tol: float, box=None, index=None) -> Background:
    """The background model of an image's edge points
    (:class:`~.keypoints.EdgePoints`) for a match ``radius`` (px) and
    direction tolerance ``tol`` (radians), over ``box`` (x0, y0, x1, y1,
    end exclusive; default: the whole image). Points outside the box take
    the model of its nearest cell. ``index`` is the edge points' index map
    (made when not given).

    Examples
    --------
    >>> from seahough.core.keypoints import find_edge_points
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((64, 64), np.float32); img[:, 32:] = 200
    >>> bg = background(find_edge_points(compute_gradients(img), 50), 1.5, math.radians(15))
    >>> bg.cover.shape
    (8, 8, 24)
    >>> float(bg.cover[:, 0].max()), float(bg.cover[:, 4, 0].max()) > 0.1   # (the edge: direction 0)
    (0.0, True)
    """
    h, w = edges.shape
    x0, y0, x1, y1 = (0, 0, w, h) if box is None else box
    x0, y0 = max(int(x0), 0), max(int(y0), 0)
    x1, y1 = max(min(int(x1), w), x0 + 1), max(min(int(y1), h), y0 + 1)
    nb = n_direction_bins(tol)
    if index is None:
        index = edges.index_map()
    cover = K.chance_coverage(edges.x, edges.y, edges.angle, index, x0, y0, y1 - y0, x1 - x0,
                              float(radius), float(tol), nb, CELL, STRIDE)
    return Background(cover, CELL, float(radius), (x0, y0))


def chance(bg: Background, x, y, direction, either: bool) -> np.ndarray:
    """Probability that a point at (x, y) wanting an edge of ``direction``
    (radians) finds one within the background's radius and tolerance by
    chance (``either``: of that direction or the opposite one; their sum,
    an upper bound).

    Examples
    --------
    >>> cover = np.zeros((2, 2, 24)); cover[..., 0], cover[..., 1] = 0.1, 0.3
    >>> bg = Background(cover, 8, 1.5)
    >>> half = math.pi / 24                                  # the centre of bin 0
    >>> [round(float(v), 3) for v in chance(bg, np.array([3.0, 3.0]), np.array([3.0, 3.0]),
    ...                                     np.array([half, 2 * half]), False)]
    [0.1, 0.2]
    """
    gy, gx, nb = bg.cover.shape
    cx = np.clip(((np.asarray(x) - bg.origin[0]) // bg.cell).astype(np.int64), 0, gx - 1)
    cy = np.clip(((np.asarray(y) - bg.origin[1]) // bg.cell).astype(np.int64), 0, gy - 1)
    cover = bg.cover[cy, cx]                  # (n, nb)
    rows = np.arange(cover.shape[0])

    def at(phi):  # linear between the two nearest bin centres
        u = np.asarray(phi, np.float64) * (nb / (2 * math.pi)) - 0.5
        j = np.floor(u)
        f = u - j
        j0 = j.astype(np.int64) % nb
        return (1.0 - f) * cover[rows, j0] + f * cover[rows, (j0 + 1) % nb]

    d = np.asarray(direction, np.float64)
    p = at(d)
    if either:
        p = np.minimum(1.0, p + at(d + math.pi))
    return p


def log10_binom_tail(k: float, n: float, p: float) -> float:
    """log10 P[Binomial(n, p) >= k], exact, in log space (n and k rounded
    to whole numbers).

    Examples
    --------
    >>> round(10 ** log10_binom_tail(1, 2, 0.5), 6)
    0.75
    >>> log10_binom_tail(0, 10, 0.3)
    0.0
    >>> round(log10_binom_tail(100, 100, 0.1), 6)
    -100.0
    """
    n = int(round(n))
    k = int(round(k))
    if k <= 0:
        return 0.0
    if k > n or p <= 0.0:
        return MIN_LOG10_NFA
    if p >= 1.0:
        return 0.0
    # the terms from j = k on, each from the one before (one lgamma in all)
    j = np.arange(k, n, dtype=np.float64)
    first = (math.lgamma(n + 1) - math.lgamma(k + 1) - math.lgamma(n - k + 1)
             + k * math.log(p) + (n - k) * math.log1p(-p))
    steps = np.log((n - j) / (j + 1)) + (math.log(p) - math.log1p(-p))
    terms = first + np.concatenate(([0.0], np.cumsum(steps)))
    top = terms.max()
    return float((top + math.log(np.exp(terms - top).sum())) / math.log(10.0))


def log10_tests(region_area: float, radius: float, scale_range, angle_range,
                period: float = 360.0, line_span: float | None = None,
                line_width: float = 0.0, line_length: float = 0.0) -> float:
    """log10 of the number of distinct poses a search tries: positions
    (working pixels of the region where the origin may lie) x rotations x
    scales, each step moving the pattern's points by about a pixel
    (``radius``: the pattern's radius in working pixels at scale 1). For a
    line (``line_span``: the region's diagonal) the positions along it are
    one answer: its distinct positions are its offsets across it (times the
    places along it of a pattern ``line_length`` long, shorter than the
    region), and its distinct scales those that move its borders
    (``line_width`` apart) by a pixel.

    Examples
    --------
    >>> round(log10_tests(100 * 100, 20.0, (1, 1), (0, 0)), 3)   # the 2-D case
    4.0
    >>> log10_tests(100 * 100, 20.0, (0.5, 2.0), (0, 360)) > 7
    True
    """
    s0, s1 = float(scale_range[0]), float(scale_range[1])
    a0, a1 = float(angle_range[0]), float(angle_range[1])
    r = max(float(radius), 1.0)
    n_angle = max(1.0, math.radians(min(a1 - a0, period)) * r * s1)
    n_scale = max(1.0, (r if line_span is None else 0.5 * line_width) * (s1 - s0))
    positions = region_area if line_span is None else (
        line_span * max(1.0, line_span / max(line_length * s0, 1.0)))
    return math.log10(max(positions, 1.0)) + math.log10(n_angle) + math.log10(n_scale)


@dataclass
class Evidence:
    """The a-contrario counts of one pose."""

    n: int          # image edge points the pattern's edges cover, inside the image
    k: int          # of those, the ones that agree (found an edge point)
    p: float        # mean chance of a match at those points
    log10_nfa: float
    n_obs: int = 0  # independent observations (one per DEPENDENCE px of edge at most)
    k_obs: int = 0  # of those, the ones that agree

    @property
    def nfa(self) -> float:
        return float(10.0 ** self.log10_nfa)


def evidence(pose, vx, vy, vang, edges, index, bg: Background, log_tests: float, *,
             tol: float, either: bool, spacing: float = 1.0) -> Evidence:
    """The :class:`Evidence` of a pose (working pixels) of the pattern points
    ``vx, vy, vang`` (``spacing``: their median distance to the nearest
    other, at scale 1) against an image's edge points.

    ``n`` counts the image edge points the pattern's edges would cover at
    this pose: a thinned edge is 4-connected, with ``|cos a| + |sin a|``
    points a pixel of its length (``a``: its direction), and pattern points
    closer than that share one; ``k`` the same count over the points that
    found a match: the edge points that agree, each once however many
    pattern points fall on it (at most ``n``). The binomial is taken over independent observations: one
    per :data:`DEPENDENCE` pixels of edge at most, ``k`` in proportion.
    """
    ids, _ = K.match_points(vx, vy, vang, float(pose.a), float(pose.b), float(pose.tx),
                            float(pose.ty), edges.x, edges.y, edges.angle, index,
                            float(bg.radius), float(tol), bool(either))
    h, w = index.shape
    step = spacing * math.hypot(pose.a, pose.b)  # between neighbouring points, image px
    n_eff, m_eff, k, p = K.evidence_counts(
        vx, vy, vang, float(pose.a), float(pose.b), float(pose.tx), float(pose.ty), ids,
        bg.cover, int(bg.origin[0]), int(bg.origin[1]), int(bg.cell), int(h), int(w),
        float(BORDER), bool(either), float(step), float(DEPENDENCE))
    n = int(round(n_eff))
    if n == 0 or m_eff < 0.5:
        return Evidence(n, 0, 0.0, log_tests)
    k_eff = min(float(k), n_eff)
    k = int(round(k_eff))
    # independent observations: one per DEPENDENCE pixels of edge at most
    n_obs = int(round(m_eff))
    k_obs = min(int(round(k_eff * m_eff / n_eff)), n_obs)
    tail = log10_binom_tail(k_obs, n_obs, max(p, MIN_CHANCE))
    return Evidence(n, k, p, max(log_tests + tail, MIN_LOG10_NFA), n_obs, k_obs)


def search_tests(ctx) -> float:
    """log10 of the distinct poses the search (a
    :class:`~.candidates.SearchContext`) could have answered with
    (:func:`log10_tests` over its accumulator's region and ranges)."""
    pf, b = ctx.pf, ctx.bins
    area = (b.nx - 1) * (b.ny - 1) * b.step * b.step
    period = 180.0 if ctx.pattern.is_line else 360.0
    span = math.hypot((b.nx - 1) * b.step, (b.ny - 1) * b.step) if ctx.pattern.is_line else None
    line = ctx.pattern.is_line
    width = ctx.pattern.line_width * ctx.factor if line else 0.0
    length = ctx.pattern.line_length * ctx.factor if line else 0.0
    # (a disc searched at one rotation counts a whole turn, whatever range was
    # asked, Detector._counted_angles: the calibration of docs/nfa.md was
    # fitted so; counting one, false alarms of discs and rings on real photos
    # rose from 0.14 to 0.24 a search, with the bound model of the seventh session)
    angles = ctx.asked_angles or ctx.angle_range
    return (log10_tests(area, pf.radius, ctx.scale_range, angles, period, span, width, length)
            + math.log10(ctx.searches))
