"""Repeated textures: the look-alikes of a motion one period of the texture away.

A tiled floor, a grating, a net: a frame that repeats itself by a shift
``v`` gives the previous frame placed ``v`` away from the true motion nearly
the score of the true one, and the vote keeps one peak per neighbourhood, so
a search can report one of the copies as unique (a simulated tiled floor:
8 of 16 pairs answered 88-245 px off at confidence 0.19-0.79). The periods
are read from the current frame's own gradient magnitude (the highest peaks
of its autocorrelation away from the origin), the answer's pose is moved by
each, and the best score found there is a runner-up the confidence must
count (:func:`repeat_confidence`). Where a copy fits as well, the frames'
grey levels, blurred past the repeated lines, choose among the copies
(:func:`look_shift`), or the answer is declined (:func:`resolve`; the
measurement of a pair from scratch, :func:`~.pair.measure_pair`, calls it).
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from ..config import Config
from ..core.features import Features
from ..core.candidates import icp_subset
from ..core.pattern import Pattern
from ..core.refine import Pose, refine
from .parallax import work_matrix

#: Periods are looked for up to this share of the frame's width and height.
MAX_LAG = 0.25
#: ... and from this many working pixels (the autocorrelation's own central
#: peak is about an edge's width).
MIN_LAG = 4
#: An autocorrelation peak at least this high (1: the frame is the same
#: shifted) is a period worth testing.
MIN_PERIODIC = 0.25
#: A gradient magnitude of at least twice this many pixels a side is searched
#: for periods at half its resolution (from 1.5 MIN_LAG px on).
HALF_FROM = 96
#: How many periods (each tested both ways) at most.
N_PERIODS = 4
#: Of the autocorrelation's peaks, those at least this share of the highest
#: are periods (the shortest first).
PEAK_SHARE = 0.7


def _spectrum(a: np.ndarray, shape) -> np.ndarray:
    """The DFT of ``a`` (float32) zero-padded to at least twice ``shape``
    (no wrap-around for shifts under it), as ``cv2.dft`` gives it."""
    h, w = shape
    pad = np.zeros((cv2.getOptimalDFTSize(2 * h), cv2.getOptimalDFTSize(2 * w)), np.float32)
    pad[:a.shape[0], :a.shape[1]] = a
    return cv2.dft(pad, flags=cv2.DFT_COMPLEX_OUTPUT)


def _correlate(fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """``c[t] = sum_x a(x + t) b(x)`` from the spectra of ``a`` and ``b``
    (:func:`_spectrum`), shifts modulo the padded size."""
    return cv2.idft(cv2.mulSpectrums(fa, fb, 0, conjB=True),
                    flags=cv2.DFT_REAL_OUTPUT | cv2.DFT_SCALE)


#: The gradient magnitude is clipped at this quantile before its periods are
#: read (:func:`periods`).
CLIP = 0.9


def periods(magnitude: np.ndarray, n: int = N_PERIODS, min_lag: float = MIN_LAG) -> np.ndarray:
    """The shifts (dx, dy), working pixels, by which the image ``magnitude``
    (a gradient magnitude) most resembles itself: the highest local maxima
    of its normalised autocorrelation between ``min_lag`` and
    :data:`MAX_LAG` of the image, at least :data:`MIN_PERIODIC`, one of
    each pair ``v, -v``; an (m, 2) array, m <= n (0 rows: no period).

    Examples
    --------
    >>> img = np.zeros((96, 128), np.float32)
    >>> img[::12, ::16] = 1.0                      # a dot every 16 px across, 12 down
    >>> sorted(tuple(int(c) for c in v) for v in periods(img, 2))
    [(0, 12), (16, 0)]
    """
    m = np.asarray(magnitude, np.float32)
    # clipped at its CLIP quantile: the specks of marine snow and the noise of
    # hard water are the strongest gradients of a frame, and their spikes
    # drowned a tiled floor's periods (none found in 5 hard-water pairs)
    # (of the non-zero values: a sparse image keeps its own)
    nz = m[m > 0]
    m = np.minimum(m, np.float32(np.quantile(nz, CLIP))) if nz.size else m
    if min(m.shape) >= 2 * HALF_FROM:   # at half resolution (a quarter of the time), once
        half = cv2.resize(m, (m.shape[1] // 2, m.shape[0] // 2), interpolation=cv2.INTER_AREA)
        return 2.0 * _periods(half, n, 0.75 * min_lag)   # (6 px: a 16 px tile at 0.5)
    return _periods(m, n, min_lag)


def _periods(m: np.ndarray, n: int, min_lag: float) -> np.ndarray:
    """:func:`periods` of a float32 image at its own resolution."""
    h, w = m.shape
    spec = _spectrum(m - np.float32(m.mean()), (h, w))
    ac = _correlate(spec, spec)
    if not ac[0, 0] > 0:
        return np.zeros((0, 2))
    ly, lx = max(1, int(MAX_LAG * h)), max(1, int(MAX_LAG * w))
    # lags -ly..ly, -lx..lx, each divided by the overlap it is summed over
    ys = np.r_[np.arange(0, ly + 1), np.arange(-ly, 0)]
    xs = np.r_[np.arange(0, lx + 1), np.arange(-lx, 0)]
    win = ac[np.ix_(ys % ac.shape[0], xs % ac.shape[1])].astype(np.float64)
    overlap = np.outer(h - np.abs(ys), w - np.abs(xs)) / float(h * w)
    # (float32 throughout: a peak compared with its own value rounded would be lost)
    win = np.fft.fftshift(win / overlap / ac[0, 0]).astype(np.float32)
    dy, dx = np.mgrid[-ly:ly + 1, -lx:lx + 1]
    near = np.hypot(dx, dy) < min_lag
    # (not on the window's border: still rising there, not a peak)
    inner = (np.abs(dy) < ly) & (np.abs(dx) < lx)
    peak = (win >= cv2.dilate(win, np.ones((3, 3), np.uint8))) & ~near & inner
    peak &= win >= MIN_PERIODIC
    # one of v, -v (the autocorrelation is symmetric): dy > 0, or dy == 0 and dx > 0
    peak &= (dy > 0) | ((dy == 0) & (dx > 0))
    iy, ix = np.nonzero(peak)
    if not iy.size:
        return np.zeros((0, 2))
    # a lattice repeats at every sum of its periods, as high: the shortest of
    # the peaks near the highest are the periods themselves
    v = win[iy, ix]
    keep = v >= PEAK_SHARE * v.max()
    iy, ix = iy[keep], ix[keep]
    order = np.argsort(np.hypot(dx[iy, ix], dy[iy, ix]), kind="stable")[:n]
    return np.stack([dx[iy[order], ix[order]], dy[iy[order], ix[order]]], 1).astype(float)


def in_view(fit) -> float:
    """A fit's score over the share of the points it keeps in view (at
    most 1: points just outside the image may match edges inside it)."""
    return min(1.0, fit.score / max(fit.inside, 0.05))


#: A copy whose fit on the refinement's subset of points (a third of the
#: time of a fit on all) lies this far under the score that could lower the
#: answer's confidence is not fitted on all (:func:`repeat_confidence`).
SCREEN_MARGIN = 0.15


def repeat_confidence(pattern: Pattern, features: Features, factor: float, pose: Pose,
                      config: Config, keep: float = 1.0
                      ) -> tuple[float, float, np.ndarray] | None:
    """(best score, the confidence it leaves, the periods) of the
    working-scale ``pose`` against itself moved by each period of the
    current frame (:func:`periods` of ``features``' gradient magnitude) and
    refitted (scale and rotation kept): ``copy_confidence(score, r)`` with ``r``
    the best score of the moved poses, scores of the points in view
    (:func:`in_view`), on all the pattern's scoring points (on the
    refinement's subset, a third of the time, one tiled floor's copy fitted
    less well than the answer and a pair was answered a tile off). None:
    the frame has no period.

    ``keep``: the confidence the answer has; a copy that could not bring
    the confidence under it (its fit on the subset :data:`SCREEN_MARGIN`
    under the score that would) is only fitted on the subset, which then
    stands for its score (the same answers on the 106 real pairs, whose
    frames have periods of their own: 8 copies a pair on the amphora wreck;
    about 2 ms less of a 50 ms real pair, 10 ms of a tiled floor's).
    """
    shifts = getattr(features, "_periods", None)   # (once a frame: several searches ask)
    if shifts is None:
        shifts = features._periods = periods(features.gradients.magnitude)
    if not len(shifts):
        return None
    pf = pattern.features(factor, config)
    vx, vy, va = pf.vx, pf.vy, pf.vangle
    tol = math.radians(config.angle_tolerance)
    score_r = max(1.25, config.match_radius * factor)

    sub = icp_subset(pf, config.search.icp_points, frame=True)
    sx, sy, sa = (np.ascontiguousarray(v[sub]) for v in (vx, vy, va))

    def fit(p, x=vx, y=vy, a=va):   # (the share of the points in view: a shift moves some out)
        f = refine(p, x, y, a, features.edges, features.index,
                   radii=(2.0, 1.25), iterations=4, angle_tol=tol, either=pattern.either,
                   fix_scale=True, fix_angle=True, score_radius=score_r)
        return in_view(f)

    best = fit(pose)
    # the copies' score under which the confidence stays at least ``keep``
    harmless = min((best - keep) / (1.0 - keep), best - keep * COPY_FLOOR) if keep < 1.0 else -1.0
    r = 0.0
    for dx, dy in shifts:
        for s in (1.0, -1.0):
            q = Pose(pose.a, pose.b, pose.tx + s * dx, pose.ty + s * dy)
            v = fit(q, sx, sy, sa) if harmless > SCREEN_MARGIN else 1.0
            r = max(r, v if v < harmless - SCREEN_MARGIN else fit(q))
    return best, copy_confidence(best, r), shifts


#: :func:`copy_confidence` divides by at least this share left unexplained.
COPY_FLOOR = 0.1


def copy_confidence(best: float, copy: float) -> float:
    """The answer's confidence against its best copy, as
    :func:`~seahough.core.detection.confidence` (of what the copy leaves
    unexplained, the share the answer explains), over at least
    :data:`COPY_FLOOR`: an answer that fits a perfect net entirely (1.0)
    had a confidence of 1 against a copy a mesh cell off at 0.997.

    >>> copy_confidence(1.0, 0.997) < 0.05, copy_confidence(1.0, 0.88), round(copy_confidence(0.6, 0.5), 2)
    (True, 1.0, 0.2)
    """
    return float(np.clip((best - copy) / max(1.0 - copy, COPY_FLOOR), 0.0, 1.0))



#: A frame's appearance picks the copy (:func:`resolve`) by at least this
#: margin of normalised correlation, ``(best - runner-up) / (1 - runner-up)``,
#: or the answer keeps the confidence its edges leave it.
MIN_LOOK_MARGIN = 0.05
#: ... and only at a correlation of at least this (the right copy of a tiled
#: floor correlated at 0.99, the wrong ones' best under 0.9).
MIN_LOOK = 0.8
#: A copy the grey levels chose must fit the edges at least this share as
#: well as the answer (a copy one period away fits them alike).
MIN_COPY = 0.9
#: ... and only when no other shift correlates at this much or more: the
#: grey levels of a one-shade net correlate alike a mesh cell away (the
#: runner-up at 0.80-0.96, against 0.25-0.32 on a tiled floor of two shades
#: and 0.33-0.49 on a net over a shaded bottom), and a net moved by 1, 3 or
#: 5 cells was answered "not moved" at confidence 1 (a net-pen trial).
MAX_LOOK_RIVAL = 0.7
#: The grey levels are compared over shifts up to this share of the frame.
LOOK_LAG = 0.5
#: The grey levels are compared blurred by this share of the shortest period.
LOOK_BLUR = 0.5


def _bands(image: np.ndarray, sigma: float) -> np.ndarray:
    """``image`` blurred by ``sigma``, less its blur by 4 ``sigma`` (the
    light's slow fall-off, which moves with the camera, taken out)."""
    a = np.asarray(image, np.float32)
    return cv2.GaussianBlur(a, (0, 0), sigma) - cv2.GaussianBlur(a, (0, 0), 4.0 * sigma)


def look_shift(prev: np.ndarray, cur: np.ndarray, work: np.ndarray, lag: int):
    """Where the working image ``prev``, placed on ``cur`` by ``work`` (3x3,
    :func:`~.parallax.work_matrix`), looks most like it: ``(dx, dy, best, runner_up)``, the shift
    (working px, within ``lag``) of the highest normalised correlation of
    the two over their overlap (each shift its own overlap: Padfield's
    masked correlation, by FFT, at half the resolution: the images are
    blurred), that correlation, and the highest local maximum at least
    :data:`MIN_LAG` px from it. None when no shift keeps enough overlap.
    """
    h, w = cur.shape
    warped = cv2.warpPerspective(prev.astype(np.float32), work, (w, h), flags=cv2.INTER_LINEAR)
    inside = cv2.warpPerspective(np.ones(prev.shape, np.float32), work, (w, h),
                                 flags=cv2.INTER_NEAREST)
    half = lambda a: cv2.resize(a, (max(1, w // 2), max(1, h // 2)),  # noqa: E731
                                interpolation=cv2.INTER_AREA)
    f, mv, mm = half(np.asarray(cur, np.float32)), half(warped), (half(inside) > 0.99)
    mm = mm.astype(np.float32)
    f = f - np.float32(f.mean())          # (centred: the sums below lose fewer digits)
    mv = (mv - np.float32(mv[mm > 0].mean() if mm.any() else 0.0)) * mm
    shape = f.shape
    F = lambda a: _spectrum(a.astype(np.float32), shape)  # noqa: E731
    # the moving image shifted by t onto the fixed one (the fixed one whole)
    Ff, Fff, Fmf = F(f), F(f * f), F(np.ones(shape, np.float32))
    Fm, Fmm, Fmask = F(mv), F(mv * mv), F(mm)
    n = _correlate(Fmf, Fmask)
    sf, sm = _correlate(Ff, Fmask), _correlate(Fmf, Fm)
    sff, smm, sfm = _correlate(Fff, Fmask), _correlate(Fmf, Fmm), _correlate(Ff, Fm)
    L = max(1, lag // 2)
    ys = np.r_[np.arange(0, L + 1), np.arange(-L, 0)] % n.shape[0]
    xs = np.r_[np.arange(0, L + 1), np.arange(-L, 0)] % n.shape[1]
    pick = lambda a: np.fft.fftshift(a[np.ix_(ys, xs)].astype(np.float64))  # noqa: E731
    n, sf, sm, sff, smm, sfm = (pick(a) for a in (n, sf, sm, sff, smm, sfm))
    if not mm.any():
        return None
    nn = np.maximum(n, 1.0)
    vf, vm = sff - sf * sf / nn, smm - sm * sm / nn
    # enough overlap, and texture in it on both sides (a flat overlap's
    # correlation is noise over nothing: it blew up past 1)
    enough = (n >= 0.3 * float(mm.sum())) & (vf > 1e-6 * max(float(vf.max()), 1e-12)) \
        & (vm > 1e-6 * max(float(vm.max()), 1e-12))
    if not enough.any():
        return None
    ncc = np.where(enough, (sfm - sf * sm / nn) / np.sqrt(np.maximum(vf * vm, 1e-30)), -1.0)
    ncc = np.clip(ncc, -1.0, 1.0).astype(np.float32)
    by, bx = np.unravel_index(int(np.argmax(ncc)), ncc.shape)
    best = float(ncc[by, bx])
    yy, xx = np.mgrid[:ncc.shape[0], :ncc.shape[1]]
    peak = (ncc >= cv2.dilate(ncc, np.ones((3, 3), np.uint8))) & enough
    peak &= np.hypot(yy - by, xx - bx) >= MIN_LAG / 2.0
    second = float(ncc[peak].max()) if peak.any() else -1.0
    return 2.0 * (bx - L), 2.0 * (by - L), best, second


def declined_copy(m, got, decline: bool):
    """``m`` with the confidence its edges leave it among its copies
    (``got``: :func:`repeat_confidence`'s), and a note saying why; ``m``
    itself when not ``decline``."""
    if not decline:
        return m
    dx, dy = got[2][0]
    return replace(m, confidence=got[1], note=(
        f"a repeated texture: the answer moved by its period ({math.hypot(dx, dy):.0f} "
        "working px) fits the edges about as well, and the grey levels do not choose"))


def _work_pose(m, pattern: Pattern, features: Features) -> Pose:
    """The working-scale pose of the previous frame's origin under ``m``."""
    g = features.gradients
    mat = np.asarray(m.matrix, float)[:2]
    x, y = g.to_work(*(mat[:, :2] @ list(pattern.origin) + mat[:, 2]))
    return Pose(float(mat[0, 0]), float(mat[0, 1]), float(x), float(y))


def resolve(m, res, pattern: Pattern, config: Config, decline: bool = True, region=None):
    """A pair's answer ``m`` (a :class:`~.pair.PairMeasure`) over a repeated
    texture: when the current frame has periods and the answer moved by one
    of them fits its edges about as well (:func:`repeat_confidence`), the
    frames' grey levels, correlated over shifts, choose the copy (tiles of
    different shades, stains; :func:`_choose`). When they do not, the
    answer's confidence is what its edges leave it (``decline``; else ``m``
    stands). ``m`` as it is otherwise.
    """
    feats = res.features if res is not None else None
    if m is None or feats is None:
        return m
    pose = _work_pose(m, pattern, feats)
    got = repeat_confidence(pattern, feats, res.factor, pose, config, keep=m.confidence)
    if got is None or got[1] >= m.confidence:
        return m
    chosen = _choose(m, got, pose, pattern, feats, res.factor, config, region)
    return chosen if chosen is not None else declined_copy(m, got, decline)


def _choose(m, got, pose: Pose, pattern: Pattern, feats: Features, factor: float,
            config: Config, region=None):
    """The copy of ``m`` the frames' grey levels choose (``got``:
    :func:`repeat_confidence`'s), or None when they do not. Correlated over
    shifts, blurred past the repeated lines, they must prefer one shift by
    :data:`MIN_LOOK_MARGIN` with no rival at :data:`MAX_LOOK_RIVAL`; the
    answer is moved there and refitted, its confidence the correlation's
    margin over its next peak. A copy whose origin falls outside ``region``
    (x0, y0, x1, y1, full-resolution px: the search's) is not one the search
    looked for."""
    g = feats.gradients
    mat = np.asarray(m.matrix, float)[:2]
    ox, oy = pattern.origin
    prev = cv2.resize(pattern.image, None, fx=g.fx, fy=g.fy, interpolation=cv2.INTER_AREA)
    # blurred over half the shortest period: the repeated lines (grout) fade,
    # the coarser shading that tells the copies apart stays
    period = float(np.hypot(*got[2][0]))      # (the shortest: they are sorted so)
    prev, cur = (_bands(a, max(1.0, LOOK_BLUR * period)) for a in (prev, g.image))
    lag = int(LOOK_LAG * min(g.image.shape))
    # (the homography where the pair has one: a camera that looks ahead)
    hom = getattr(m, "homography", None)
    look = look_shift(prev, cur, work_matrix(mat if hom is None else hom, g.fx, g.fy), lag)
    if look is None:
        return None
    dx, dy, best, second = look
    margin = float(np.clip((best - second) / max(1e-9, 1.0 - second), 0.0, 1.0))
    if margin < MIN_LOOK_MARGIN or second >= MAX_LOOK_RIVAL:
        return None
    # grey levels that stay with the camera (a strobe's fall-off, a lens's
    # shading) correlate as well with the frames not moved at all: they tell
    # nothing of the scene (a one-shade net in the simulator's water: copies
    # 1-3 mesh cells off "chosen" at a rival of 0.40). (Nor can they confirm
    # a motion under a period: the frames not moved are as alike.)
    still = look_shift(prev, cur, np.eye(3), 4)
    if still is not None and still[2] >= best - MIN_LOOK_MARGIN:
        return None
    # the edges' copy: copies lie a period apart (a smaller shift is the blurred
    # grey levels' own imprecision, or a camera's perspective). The grey levels
    # confirm it, however well they correlate (two frames of a camera that looks
    # ahead correlate at 0.75-0.79, their next peak at 0.33); another copy needs
    # MIN_LOOK
    if math.hypot(dx, dy) < 0.5 * period:
        return replace(m, confidence=max(got[1], min(m.confidence, margin)))
    if best < MIN_LOOK:
        return None
    moved = _refit_copy(m, pattern, feats, factor, config, pose, dx, dy,
                        MIN_COPY * got[0], fixed=False)
    if moved is None:    # not a copy the edges agree with
        return None
    fx, fy = moved.matrix[:, :2] @ [ox, oy] + moved.matrix[:, 2]
    if region is not None and not (region[0] <= fx <= region[2] and region[1] <= fy <= region[3]):
        return None
    if hom is not None:   # (the homography moved as the origin was, full-resolution px)
        x0, y0 = mat @ [ox, oy, 1.0]
        d = np.array([[1.0, 0.0, fx - x0], [0.0, 1.0, fy - y0], [0.0, 0.0, 1.0]])
        hom = d @ np.asarray(hom, float)
    return replace(moved, confidence=margin, homography=hom)


def _refit_copy(m, pattern: Pattern, features: Features, factor: float, config: Config,
                pose: Pose, dx: float, dy: float, least: float, fixed: bool = True,
                radii=(2.0, 1.5, 1.25)):
    """``m`` moved by ``(dx, dy)`` working px and refitted (its scale and
    turn kept when ``fixed``), or None when that copy fits the edges under
    ``least`` (:func:`in_view`)."""
    pf = pattern.features(factor, config)
    fit = refine(Pose(pose.a, pose.b, pose.tx + dx, pose.ty + dy), pf.vx, pf.vy, pf.vangle,
                 features.edges, features.index, radii=radii, iterations=6,
                 angle_tol=math.radians(config.angle_tolerance), either=pattern.either,
                 fix_scale=fixed, fix_angle=fixed,
                 score_radius=max(1.25, config.match_radius * factor))
    if in_view(fit) < least:
        return None
    q, (ox, oy) = fit.pose, pattern.origin
    fx, fy = (float(v) for v in features.gradients.to_full(q.tx, q.ty))
    full = np.array([[q.a, q.b, 0.0], [-q.b, q.a, 0.0]])
    full[:, 2] = [fx, fy] - full[:, :2] @ [ox, oy]
    return replace(m, matrix=full, score=fit.score)


def nearest_copy(m, pattern: Pattern, features: Features, config: Config,
                 min_confidence: float, near=None):
    """For the dead reckoning: ``(m, period)``, with ``period`` the current
    frame's shortest period in full-resolution px when the answer ``m`` (a
    :class:`~.pair.PairMeasure`) moved by a period fits its edges about as
    well (:func:`repeat_confidence` leaves it under ``min_confidence``) and
    the grey levels do not tell the copies apart (:func:`_choose`; when they
    do, their copy, and 0.0): the step is known only up to the texture's
    period. Else ``(m, 0.0)``. Then, with ``near`` (the predicted 2x3
    motion), the copy nearest the prediction is returned in its place: the
    answer's turn and scale moved to the prediction's place and refitted,
    from a capture radius of 0.4 period down (a net 23 px a frame,
    predicted at +46 px, was answered +6, a mesh cell off, at the vote's
    say: a net-pen trial). A copy there that fits the edges under
    :data:`MIN_COPY` of the answer: ``(None, period)``, not measured.
    """
    g = features.gradients
    pose = _work_pose(m, pattern, features)
    got = repeat_confidence(pattern, features, g.factor, pose, config, keep=m.confidence)
    if got is None or got[1] >= min_confidence:
        return m, 0.0
    chosen = _choose(m, got, pose, pattern, features, g.factor, config)
    if chosen is not None:    # (the grey levels tell the copies apart: measured)
        return chosen, 0.0
    v = np.asarray(got[2], float)
    period = float(np.hypot(v[0, 0] / g.fx, v[0, 1] / g.fy))
    if near is None:
        return m, period
    q = _work_pose(replace(m, matrix=np.asarray(near, float)[:2]), pattern, features)
    dx, dy = q.tx - pose.tx, q.ty - pose.ty
    pw = float(np.hypot(*v[0]))     # (working px)
    if math.hypot(dx, dy) < 0.25 * pw:   # (the answer is the copy the prediction is nearest)
        return m, period
    moved = _refit_copy(m, pattern, features, g.factor, config, pose, dx, dy, MIN_COPY * got[0],
                        radii=(0.4 * pw, 0.25 * pw, 2.0, 1.5, 1.25))
    return moved, period
