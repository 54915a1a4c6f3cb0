"""Stage 4: voting into the 4-D accumulator over (dx, dy, scale, rotation).

The accumulator is never held whole: each rotation slice (scale x dy x dx)
is filled in cache and reduced at once into its two 2-D projections, the
planes the paper shows (its Fig. 4): where (dx-dy) and what size and which
way (scale-rotation).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import kernels as K
from ..config import Config
from .._validate import pair
from ..errors import ParameterError
from .pattern import PatternFeatures
from .segments import Segments

_MODES = {"oriented": K.MODE_ORIENTED, "points": K.MODE_POINTS, "segments": K.MODE_SEGMENTS}
N_ANGLE_BINS = 64


@dataclass
class Bins:
    """The accumulator's grid. Translations are in working pixels."""

    scales: np.ndarray        # scale bin centres
    angles: np.ndarray        # rotation slice centres, radians
    angle_half: float         # half width of a rotation slice (or the tolerance)
    log_scale0: float
    log_step: float
    tx0: float                # translation of the dx-dy grid's origin
    ty0: float
    step: float               # translation bin size
    nx: int
    ny: int
    mode: int
    scale_known: bool
    angle_known: bool
    config: Config | None = None  # what the bins were made from (for messages)


@dataclass
class AccumulatorPlanes:
    """The accumulator's 2-D projections, for peaks and pictures.

    Attributes
    ----------
    xy : ndarray (ny, nx)
        For each translation, the highest cell over scale and rotation (the
        dx-dy plane: where). Heights count the pattern's voting points that
        support the cell (1.0 = every point, once), over 2x2 translation bins.
    xy_scale, xy_angle : ndarray (ny, nx)
        The scale and rotation (degrees) of that highest cell (computed on
        first use).
    scale_angle : ndarray (n_scales, n_angles)
        For each scale and rotation, the highest cell over translation.
    scales, angles : ndarray
        Bin centres of ``scale_angle`` (angles in degrees).
    x, y : ndarray
        Full-resolution image coordinates of the ``xy`` columns and rows.
    pattern : str
        Which pattern voted, in a search of several named patterns (``""``
        for a Detector of one pattern).
    """

    def __init__(self, xy, best_k, best_d, scale_angle, scales, angles_deg, x, y):
        self.xy = xy
        self._k, self._d = best_k, best_d
        self.scale_angle = scale_angle
        self.scales = scales
        self.angles = angles_deg
        self.x = x
        self.y = y
        self.pattern = ""    # whose planes, in a search of several named patterns

    @functools.cached_property
    def xy_scale(self) -> np.ndarray:
        return self.scales[self._k].astype(np.float32)

    @functools.cached_property
    def xy_angle(self) -> np.ndarray:
        return self.angles[self._d].astype(np.float32)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(left, right, bottom, top) for ``matplotlib.pyplot.imshow``."""
        dx = self.x[1] - self.x[0] if self.x.size > 1 else 1.0
        dy = self.y[1] - self.y[0] if self.y.size > 1 else 1.0
        return (self.x[0] - dx / 2, self.x[-1] + dx / 2, self.y[-1] + dy / 2, self.y[0] - dy / 2)


#: Scales outside this range are refused (a pattern 100x smaller or larger
#: than its image is a mistake, and would size the accumulator without bound).
SCALE_LIMITS = (0.01, 100.0)


#: The most cells one rotation slice of the accumulator may hold: the slice
#: and its vote stamps take 8 bytes a cell (2.5e8 cells: 2 GB). Default bins
#: over a 640x480 region: at most 2.2e6.
MAX_SLICE_CELLS = 2.5e8
#: The most cells of the whole accumulator (each slice is cleared and reduced
#: once) per REFERENCE_AREA working px^2 of searched region: 3.8e9 cells took
#: 6.2-8.4 s (1.6-2.2 ns a cell, one core of a 2-core AMD EPYC). Default bins
#: over a 640x480 region: at most 1.8e8 (a 64x scale range and a large pattern).
MAX_CELLS = 4e9
REFERENCE_AREA = 640.0 * 480.0
#: The most votes of one search: pattern points x image segments x (scales,
#: or 1 in segment voting, + rotation slices / 64 for the direction bins each
#: slice looks at). 9.8e8 took 10.2 s, 2.3e8 1.5 s (6-12 ns a vote). Default
#: counts: at most 4.3e7 (256 pattern points, 1200 segments, 139 scales).
MAX_VOTES = 8e8
#: The most pattern points x rotation slices: the vote kernel tags each cell
#: with the last (slice, pattern point) that voted in it, in a float32 beside
#: the cell's height (exact up to 2**24).
MAX_POINT_SLICES = 2 ** 24


def check_ranges(scale_range, angle_range):
    """Validated ``(scale_range, angle_range)``; raises ParameterError.

    Scales must lie in :data:`SCALE_LIMITS` and span at most 64x. The angle
    range is moved by whole turns so that it starts in [0, 360) (so
    ``(-30, 30)`` becomes ``(330, 390)``), and a span over 360 degrees is
    taken as a full turn.

    Examples
    --------
    >>> check_ranges((0.5, 2), (-30, 30))
    ((0.5, 2.0), (330.0, 390.0))
    """
    s = pair("scale_range", scale_range)
    lo, hi = SCALE_LIMITS
    if not (lo <= s[0] and s[1] <= hi):
        raise ParameterError(f"scale_range={scale_range!r}: scales must be in [{lo:g}, {hi:g}]")
    if s[1] / s[0] > 64:
        raise ParameterError(f"scale_range={scale_range!r}: spans more than 64x; split the search")
    a0, a1 = pair("angle_range", angle_range)
    span = min(a1 - a0, 360.0)
    a0 = math.fmod(a0, 360.0)
    if a0 < 0:
        a0 += 360.0
    if a0 >= 360.0:
        a0 = 0.0
    return s, (a0, a0 + span)


def edge_gap(pf: PatternFeatures, either: bool = False, n: int = 64) -> float:
    """Median distance, across its edge, from a pattern point to the nearest
    parallel edge of the pattern that it could be taken for (working px at
    scale 1; inf when most points have none): the same direction of
    gradient, or either direction when the pattern's polarity is
    ``"either"``. The width of a marker board's rings (``either``) or of
    two of them, a shape's opposite side (``either``) or nothing.

    Examples
    --------
    >>> from seahough.core.pattern import Pattern
    >>> bar = Pattern.rectangle(60, 40, polarity="either").features(1.0)
    >>> round(edge_gap(bar, either=True))   # its height
    40
    >>> edge_gap(Pattern.rectangle(60, 40).features(1.0))   # no side is another's look-alike
    inf
    """
    x, y, a = (np.asarray(v, np.float64) for v in (pf.vx, pf.vy, pf.vangle))
    if x.size < 4:
        return math.inf
    q = np.unique(np.linspace(0, x.size - 1, min(n, x.size)).astype(int))
    nx, ny = np.cos(a[q])[:, None], np.sin(a[q])[:, None]
    dx, dy = x[None, :] - x[q][:, None], y[None, :] - y[q][:, None]
    across = np.abs(dx * nx + dy * ny)                # along the query's normal
    beside = np.abs(dx * ny - dy * nx)                # along its edge
    da = a[None, :] - a[q][:, None]
    cos20 = math.cos(math.radians(20.0))
    parallel = (np.abs(np.cos(da)) > cos20) if either else (np.cos(da) > cos20)
    other = parallel & (across > 1.5) & (beside <= max(2.0, 2.0 * pf.spacing))
    gap = np.where(other, across, np.inf).min(axis=1)
    return float(np.median(gap))


def make_bins(pf: PatternFeatures, scale_range, angle_range, region, config: Config,
              gap: float | None = None) -> Bins:
    """Bin sizes from the pattern's size, the ranges and the config.

    ``region`` is (x0, y0, x1, y1) in working pixels: where the pattern
    origin may lie. A ParameterError refuses an accumulator over the limits
    (:data:`MAX_SLICE_CELLS`, :data:`MAX_CELLS`), naming what to change.
    ``gap``: the :func:`edge_gap` of a pattern drawn with borders (a shape,
    a marker; not a texture, not a line): its translation bin is at most
    half of it at the middle scale, so that a marker board's pose and the
    pose one ring off fall in different cells; at least 2 px and half the
    derived bin (a thin stroke's cells would otherwise multiply), and the
    rotation and scale bins stay those of the derived one.
    """
    (s0, s1), (a0, a1) = check_ranges(scale_range, angle_range)
    r = max(pf.radius, 2.0)
    s_mid = math.sqrt(s0 * s1)
    scale_known = s1 / s0 < 1.0 + 1e-9
    angle_known = (a1 - a0) < 1e-9
    if config.translation_bin:
        step = float(config.translation_bin)
    elif scale_known and angle_known:
        step = 1.0
    else:
        step = float(np.clip(0.17 * r * s_mid, 2.0, 6.0))
    # rotation and scale steps that move the pattern's points about one bin
    kappa = 1.6 * step / (r * s_mid)
    if gap is not None and not config.translation_bin and not (scale_known and angle_known):
        step = max(2.0, 0.5 * step, min(step, 0.5 * gap * s_mid))
    if angle_known:
        angles = np.array([math.radians(a0)])
        half = math.radians(config.angle_tolerance)
    else:
        ab = math.radians(config.angle_bin) if config.angle_bin else float(np.clip(kappa, math.radians(2.5), math.radians(10.0)))
        span = math.radians(min(a1 - a0, 360.0))
        n = max(1, int(math.ceil(span / ab - 1e-9)))
        w = span / n
        angles = math.radians(a0) + (np.arange(n) + 0.5) * w
        half = 0.5 * w
    if scale_known:
        scales = np.array([s0])
        log0, lstep = math.log(s0), 1.0
    else:
        ls = config.scale_step or float(np.clip(kappa, 0.03, 0.15))
        span = math.log(s1 / s0)
        n = max(1, int(math.ceil(span / ls - 1e-9)))
        lstep = span / n
        log0 = math.log(s0) + 0.5 * lstep
        scales = np.exp(log0 + np.arange(n) * lstep)
    x0, y0, x1, y1 = region
    nx = max(int(math.ceil((x1 - x0) / step)) + 1, 2)
    ny = max(int(math.ceil((y1 - y0) / step)) + 1, 2)
    mode = _MODES[config.voting]
    if angle_known:
        mode = K.MODE_POINTS  # a known rotation is used as given
    bins = Bins(scales, angles, half, log0, lstep, float(x0), float(y0), step, nx, ny, mode,
                scale_known, angle_known, config)
    _check_size(bins, (x1 - x0) * (y1 - y0), config)
    return bins


def _bin_fields(bins: Bins, config: Config, names) -> str:
    """``"Config.translation_bin (derived: 3.4 px), Config.angle_bin (0.1) or
    ..."``: the fields ``names`` of ``config`` with their values, or the
    value ``bins`` derived for a field left None."""
    used = {"translation_bin": f"{bins.step:.3g} px", "angle_bin":
            f"{math.degrees(2 * bins.angle_half):.3g} degrees", "scale_step": f"{bins.log_step:.3g}"}
    out = []
    for n in names:
        v = getattr(config, n)
        out.append(f"Config.{n} ({v:g})" if v is not None else f"Config.{n} (derived: {used[n]})")
    return ", ".join(out[:-1]) + " or " + out[-1] if len(out) > 1 else out[0]


def _check_size(bins: Bins, area: float, config: Config) -> None:
    """Refuse an accumulator too large to hold or to sweep.

    Parameters
    ----------
    bins : Bins
        The grid.
    area : float
        Area of the searched region, working px^2.
    config : Config
        What the bins were made from (named in the message).

    Raises
    ------
    ParameterError
        Over :data:`MAX_SLICE_CELLS` cells a rotation slice, or over
        :data:`MAX_CELLS` cells in all per :data:`REFERENCE_AREA` of region;
        the message names the bins to coarsen and the ranges to narrow.
    """
    ns, na = bins.scales.size, bins.angles.size
    per_slice = float(bins.nx) * bins.ny * ns
    cells = per_slice * na
    limit = MAX_CELLS * max(1.0, area / REFERENCE_AREA)
    over, names = [], ["translation_bin", "scale_step"]
    if per_slice > MAX_SLICE_CELLS:
        over.append(f"{MAX_SLICE_CELLS:.2g} cells a slice")
    if cells > limit:
        over.append(f"{limit:.2g} cells in all")
        names.insert(1, "angle_bin")
    if not over:
        return
    raise ParameterError(
        f"an accumulator of {cells:.2g} cells ({bins.nx} x {bins.ny} translations x {ns} scales "
        f"x {na} rotations; {per_slice:.2g} cells, {per_slice * 8 / 1e9:.3g} GB, a rotation "
        f"slice) is over the limit of {' and '.join(over)}: coarsen "
        f"{_bin_fields(bins, config, names)}, or narrow scale_range, angle_range or "
        "search_region (or search a smaller image: Config.downscale)")


def _check_votes(n_points: int, n_segments: int, bins: Bins) -> None:
    """Refuse a vote that would take too long (over :data:`MAX_VOTES`), or
    whose (rotation slice, pattern point) tags the kernel could not tell
    apart (over :data:`MAX_POINT_SLICES`).

    Parameters
    ----------
    n_points, n_segments : int
        Pattern points (counting both polarities) and image segments.
    bins : Bins
        The grid: each pair votes once per scale (once in segment voting),
        and each rotation slice looks at the segments of its direction bins.

    Raises
    ------
    ParameterError
        Over :data:`MAX_VOTES` or :data:`MAX_POINT_SLICES`; the message names
        the counts to lower.
    """
    config = bins.config or Config()
    ns, na = bins.scales.size, bins.angles.size
    votes = float(n_points) * n_segments * (
        (1 if bins.mode == K.MODE_SEGMENTS else ns) + na / N_ANGLE_BINS)
    if float(n_points) * na > MAX_POINT_SLICES:
        raise ParameterError(
            f"voting {n_points} pattern points over {na} rotations is over the limit of "
            f"{MAX_POINT_SLICES:.3g} (pattern points x rotations): lower Config.n_pattern_points "
            f"({config.n_pattern_points}) or coarsen {_bin_fields(bins, config, ('angle_bin',))}")
    if votes > MAX_VOTES:
        raise ParameterError(
            f"voting {n_points} pattern points x {n_segments} image segments over {ns} scales "
            f"and {na} rotations ({votes:.2g} votes) is over the limit of {MAX_VOTES:.2g}: "
            f"lower Config.n_pattern_points ({config.n_pattern_points}) or Config.n_keypoints "
            f"({config.n_keypoints}), coarsen {_bin_fields(bins, config, ('scale_step',))}, "
            "or narrow scale_range")


class Votes(NamedTuple):
    """The accumulator, reduced as it was filled (see :func:`accumulate`)."""

    best_val: np.ndarray      # (ny, nx): the highest cell over scale and rotation
    best_k: np.ndarray        # its scale bin
    best_d: np.ndarray        # its rotation slice
    scale_angle: np.ndarray   # (n_scales, n_angles): the highest cell over translation


def accumulate(pf: PatternFeatures, seg: Segments, bins: Bins, either: bool = False) -> Votes:
    """Vote every pattern point / image segment pair into the accumulator of
    ``bins``; returns its reductions as :class:`Votes`. A ParameterError
    refuses, before voting, more than :data:`MAX_VOTES` votes.

    Examples
    --------
    A pattern searched for in its own image: the peak is at the pattern's
    origin (to within a bin), at scale 1 and rotation 0.

    >>> from seahough.core.pattern import Pattern
    >>> from seahough.core.features import extract_features
    >>> from seahough.config import Config
    >>> p = Pattern.rectangle(60, 40)
    >>> pf, cfg = p.features(1.0), Config()
    >>> feats = extract_features(p.image.astype(np.float32), 1.0, cfg)
    >>> h, w = p.image.shape
    >>> bins = make_bins(pf, (0.8, 1.25), (0.0, 360.0), (0.0, 0.0, w - 1.0, h - 1.0), cfg)
    >>> v = accumulate(pf, feats.segments, bins)
    >>> y, x = np.unravel_index(np.argmax(v.best_val), v.best_val.shape)
    >>> tx, ty = bins.tx0 + (x + 1) * bins.step, bins.ty0 + (y + 1) * bins.step
    >>> bool(abs(tx - p.origin[0]) <= bins.step and abs(ty - p.origin[1]) <= bins.step)
    True
    >>> k = int(v.best_k[y, x])
    >>> round(float(bins.scales[k]), 1)
    1.0
    """
    px, py, pa, pw, p2x, p2y = pf.x, pf.y, pf.angle, pf.weight, pf.x2, pf.y2
    if either:  # each pattern point may appear with its gradient reversed
        px, py, p2x, p2y = (np.concatenate([v, v]) for v in (px, py, p2x, p2y))
        pa = np.concatenate([pa, (pa + np.float32(math.pi)) % np.float32(2 * math.pi)])
        pw = np.concatenate([pw, pw])
    _check_votes(px.size, len(seg), bins)
    abin = 2 * math.pi / N_ANGLE_BINS
    b = np.minimum((seg.angle / abin).astype(np.int64), N_ANGLE_BINS - 1)
    order = np.argsort(b, kind="stable")
    qstart = np.zeros(N_ANGLE_BINS + 1, np.int64)
    np.cumsum(np.bincount(b, minlength=N_ANGLE_BINS), out=qstart[1:])
    c = lambda a: np.ascontiguousarray(a[order], np.float32)
    nxr, nyr = bins.nx, bins.ny
    best_val = np.zeros((nyr - 1, nxr - 1), np.float32)
    best_k = np.zeros((nyr - 1, nxr - 1), np.int32)
    best_d = np.zeros((nyr - 1, nxr - 1), np.int32)
    proj = np.zeros((bins.scales.size, bins.angles.size), np.float32)
    f = lambda a: np.ascontiguousarray(a, np.float32)
    K.vote(f(px), f(py), f(pa), f(pw), f(p2x), f(p2y),
           c(seg.x), c(seg.y), c(seg.angle), c(seg.x2), c(seg.y2), qstart, N_ANGLE_BINS,
           bins.angles.astype(np.float64), float(bins.angle_half), bins.scales.astype(np.float64),
           float(bins.log_scale0), float(bins.log_step), int(bins.mode),
           float(bins.tx0), float(bins.ty0), float(bins.step), int(nxr), int(nyr),
           best_val, best_k, best_d, proj)
    return Votes(best_val, best_k, best_d, proj)


def planes(votes: Votes, bins: Bins, gradients) -> AccumulatorPlanes:
    """The accumulator's planes in full-resolution image coordinates
    (``gradients``: the searched image's :class:`~.preprocess.Gradients`)."""
    cols = bins.tx0 + (np.arange(votes.best_val.shape[1]) + 1) * bins.step
    rows = bins.ty0 + (np.arange(votes.best_val.shape[0]) + 1) * bins.step
    xs, ys = gradients.to_full(cols, rows)
    return AccumulatorPlanes(votes.best_val, votes.best_k, votes.best_d, votes.scale_angle,
                             bins.scales.copy(), np.degrees(bins.angles) % 360.0,
                             np.asarray(xs, float), np.asarray(ys, float))
