"""Stage 5: accumulator peaks -> candidate poses, refined and scored at the
working scale.

The peaks of the dx-dy plane are seeds; each is looked at cheaply (a single
matching pass at its cell's scale and the neighbouring ones), the most
promising are refined by ICP (:mod:`.refine`), and the distinct refined
poses are the candidates that :mod:`.ranking` finishes at full resolution.
:class:`PoseComparison` says when two poses are the same answer.

Everything a search shares lives on a :class:`SearchContext` made afresh for
each search, so one :class:`~seahough.Detector` can serve several threads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from . import kernels as K
from ..config import Config
from .accumulator import Bins, Votes
from .features import Features
from .nfa import Evidence
from .pattern import Pattern, PatternFeatures
from .refine import Fit, Pose, refine


@dataclass
class Candidate:
    """A refined pose at the working scale, and later at full resolution.

    ``pose`` and ``score`` are the full-resolution finish's when the
    candidate got one, else the working scale's (a :class:`~.refine.Pose`:
    ``tx, ty`` the pattern origin's place in full-resolution image pixels,
    ``scale``, ``angle`` in degrees). ``nfa``: its number of false alarms,
    when it was judged (inf otherwise). ``declined``: why it was not
    reported, with its figures ("" for a detection). ``pattern``: the name
    of its pattern in a Detector of several.
    """

    fit: Fit                  # working-scale pose and score
    votes: float              # height of its accumulator peak
    work_score: float         # score at the working scale
    full: Fit | None = None   # the full-resolution finish (ranking)
    evidence: Evidence | None = None  # its number of false alarms (ranking)
    #: why :func:`~.ranking.rank` did not report it, with its figures (e.g.
    #: "NFA 3.2 over max_nfa 1"); "" for a detection
    declined: str = ""
    pattern: str = ""
    #: the working-scale pose in full-resolution pixels (ranking)
    placed: Pose | None = field(default=None, repr=False)
    #: a line's stretches seen, once ranking looked (``looked``; None: not measurable,
    #: :func:`.lines.visible_stretches`)
    stretches: list | None = field(default=None, repr=False)
    looked: bool = field(default=False, repr=False)

    @property
    def pose(self) -> Pose:
        """Its pose in full-resolution image pixels (the finish's, or the
        working scale's brought to full resolution)."""
        if self.full is not None:
            return self.full.pose
        return self.placed if self.placed is not None else self.fit.pose

    @property
    def score(self) -> float:
        return self.full.score if self.full is not None else self.work_score

    @property
    def nfa(self) -> float:
        return self.evidence.nfa if self.evidence is not None else math.inf


@dataclass(frozen=True)
class Seed:
    """An accumulator cell worth refining."""

    look: float               # score of its best first look (a single matching pass)
    votes: float              # height of its cell
    tx: float                 # the cell's translation (working px)
    ty: float
    scale_bins: tuple         # scale bins to start from, the best-looking first
    angle: float              # the cell's rotation (radians)
    is_peak: bool             # a local maximum (else a neighbour of one)


class PoseComparison:
    """Which poses are the same answer, for one pattern at one working scale.

    Parameters
    ----------
    pattern : Pattern
    pf : PatternFeatures
        The pattern's points at the search's working scale.
    step : float
        The accumulator's translation bin (working px).
    scale_range, angle_range : (float, float)
        The searched ranges (as validated by :func:`.accumulator.check_ranges`).
    tuning_overlap : float
        ``Config.search.overlap``.

    Examples
    --------
    >>> p = Pattern.rectangle(60, 40)
    >>> cmp = PoseComparison(p, p.features(1.0), 3.0, (0.5, 2.0), (0.0, 360.0), 0.3)
    >>> a = Pose.from_params(100.0, 80.0, 1.0, 0.0)
    >>> cmp.close(a, Pose.from_params(100.5, 80.0, 1.0, 0.0))
    True
    >>> cmp.equivalent(a, Pose.from_params(100.0, 80.0, 1.0, math.pi))  # turned by 180 deg
    True
    >>> cmp.same(a, Pose.from_params(160.0, 80.0, 1.0, 0.0), 1.0)
    False
    """

    def __init__(self, pattern: Pattern, pf: PatternFeatures, step: float, scale_range,
                 angle_range, tuning_overlap: float):
        self.pattern = pattern
        self.scale_range = scale_range
        self.angle_range = angle_range
        self.overlap = tuning_overlap
        self.points = np.stack([pf.vx, pf.vy], 1).astype(float)
        self.probe = self.points[:: max(1, pf.vx.size // 64)]
        self.centre = tuple(float(v) for v in self.points.mean(axis=0))
        hull = cv2.convexHull(np.vstack(pattern.outline).astype(np.float32)).reshape(-1, 2)
        self.footprint = hull.astype(float) - np.asarray(pattern.origin)  # pattern px, from origin
        self.close_px = max(2.0 * step, 3.0)

    def pose_ok(self, pose: Pose) -> bool:
        """A finite pose whose scale is not far outside the searched range."""
        s0, s1 = self.scale_range
        return 0.8 * s0 <= pose.scale <= 1.25 * s1 and math.isfinite(pose.tx) and math.isfinite(pose.ty)

    def outside_ranges(self, scale: float, angle: float) -> bool:
        """Is a refined pose outside the searched ranges (with a little slack)?"""
        s0, s1 = self.scale_range
        if not s0 / 1.02 <= scale <= s1 * 1.02:
            return True
        a0, a1 = self.angle_range
        period = 180.0 if self.pattern.is_line else 360.0
        if a1 - a0 >= period:
            return False
        d = (angle - a0) % period  # how far past the range's start
        return (a1 - a0) + 1.0 < d < period - 1.0

    def at_range_edge(self, scale: float, angle: float) -> bool:
        """Is a pose within the searched ranges' slack of one of their ends
        (scale within 3 %, angle within 1 degree; a range too narrow to
        have ends, under 1.5x or 2 degrees, e.g. a known scale, has none)? The object may then be
        larger, smaller or turned further than searched, and only a part
        of it fitted (a box 3 times the pattern, searched up to 2: a
        corner-hugging copy at 1.95)."""
        s0, s1 = self.scale_range
        if s1 >= 1.5 * s0 and (scale <= s0 * 1.03 or scale >= s1 / 1.03):
            return True
        a0, a1 = self.angle_range
        period = 180.0 if self.pattern.is_line else 360.0
        if not 2.0 <= a1 - a0 < period:
            return False
        d = (angle - a0) % period  # how far past the range's start
        return d <= 1.0 or abs(d - (a1 - a0)) <= 1.0 or d >= period - 1.0

    def same(self, a: Pose, b: Pose, factor: float) -> bool:
        """Do two poses describe the same object (or the same line)?"""
        p = self.pattern
        if p.is_line:
            ta, tb = math.radians(a.angle), math.radians(b.angle)
            if abs(((math.degrees(ta - tb) + 90) % 180) - 90) > 10:
                return False
            n = np.array([math.sin(ta), math.cos(ta)])
            d = abs(n @ np.array([a.tx - b.tx, a.ty - b.ty]))
            return d < max(p.line_width * factor * max(a.scale, b.scale), 2.0)
        r = 0.35 * p.extent * factor * min(a.scale, b.scale)
        if math.hypot(a.tx - b.tx, a.ty - b.ty) < r:
            return True
        # overlapping footprints: a smaller copy in a self-similar shape's
        # corner, or a turned copy sharing some of its edges
        fa, fb = self.placed(a, factor), self.placed(b, factor)
        inter, _ = cv2.intersectConvexConvex(fa, fb)
        smaller = min(cv2.contourArea(fa), cv2.contourArea(fb))
        return smaller > 0 and inter > self.overlap * smaller

    def placed(self, pose: Pose, factor: float) -> np.ndarray:
        """The pattern's convex footprint placed at ``pose``."""
        fp = self.footprint * factor
        qx, qy = pose.map(fp[:, 0], fp[:, 1])
        return np.stack([qx, qy], 1).astype(np.float32)

    def centre_gap(self, a: Pose, b: Pose) -> float:
        """Distance between the pattern points' centre placed by ``a`` and by ``b``."""
        cx, cy = self.centre
        dx = (a.tx - b.tx) + (a.a - b.a) * cx + (a.b - b.b) * cy
        dy = (a.ty - b.ty) - (a.b - b.b) * cx + (a.a - b.a) * cy
        return math.hypot(dx, dy)

    def close(self, a: Pose, b: Pose) -> bool:
        """Practically the same pose: the pattern's points move less than
        ~2 working pixels between the two."""
        if self.centre_gap(a, b) >= self.close_px:
            return False
        pts = self.probe
        ax, ay = a.map(pts[:, 0], pts[:, 1])
        bx, by = b.map(pts[:, 0], pts[:, 1])
        return float(np.max(np.hypot(ax - bx, ay - by))) < self.close_px

    def equivalent(self, a: Pose, b: Pose) -> bool:
        """The same answer in another guise: the pattern's edge points placed
        by ``a`` and by ``b`` coincide as sets (a symmetric shape turned onto
        itself, e.g. a rectangle by 180 degrees)."""
        # a camera frame has no symmetry, and its points cover it so densely
        # that any nearby pose would pass the test below
        if self.pattern.is_frame:
            return False
        # point sets that coincide have (nearly) the same centre: a cheap test first
        if self.centre_gap(a, b) > 3.0 * self.close_px:
            return False
        ax, ay = a.map(self.probe[:, 0], self.probe[:, 1])
        bx, by = b.map(self.points[:, 0], self.points[:, 1])
        d = np.sqrt(((ax[:, None] - bx[None, :]) ** 2 + (ay[:, None] - by[None, :]) ** 2).min(axis=1))
        # the 90th percentile (as np.percentile interpolates it), by partition: faster
        n = d.size
        pos = 0.9 * (n - 1)
        lo = int(pos)
        hi = min(lo + 1, n - 1)
        part = np.partition(d, (lo, hi))
        q90 = part[lo] + (pos - lo) * (part[hi] - part[lo])
        return float(q90) < self.close_px


@dataclass
class SearchContext:
    """What the stages of one search share (made afresh for each search)."""

    pattern: Pattern
    pf: PatternFeatures
    features: Features
    bins: Bins
    factor: float
    config: Config
    scale_range: tuple
    angle_range: tuple
    max_results: int
    min_score: float
    compare: PoseComparison
    max_nfa: float = math.inf
    #: the rotations the caller asked for, when the search tried fewer (a disc
    #: is searched at one): the number of false alarms still counts them
    asked_angles: tuple | None = None
    #: how many searches of the image this one completes (a painted pattern's
    #: grey search after an empty colour one: 2): the number of tests counts them
    searches: int = 1
    #: many results asked for, to count objects (``Detector(max_results > 5)``):
    #: every candidate that could pass min_score is finished (ranking)
    counting: bool = False
    #: a line is reported only with a visible extent (ranking); not a curve's pieces
    line_extent: bool = True

    @property
    def n_candidates(self) -> int:
        """How many candidates the search refines: ``Config.n_candidates``,
        or ``max_results + 2`` when more results than that are asked for
        (12 discs in view, 10 asked for: 7 refined gave 7). Each costs its
        refinement: 50 asked for on a 640x480 photo, about 3x the time."""
        n = self.config.n_candidates
        return n if self.max_results <= n else self.max_results + 2

    @property
    def scale_known(self) -> bool:
        return self.scale_range[0] == self.scale_range[1]

    @property
    def angle_known(self) -> bool:
        return self.angle_range[0] == self.angle_range[1]


def peaks(best_val: np.ndarray, radius: int, n: int):
    """``(ys, xs, heights)`` of the local maxima of the dx-dy plane, highest
    first, at most ``4 n``.

    Examples
    --------
    >>> plane = np.zeros((5, 6), np.float32); plane[1, 4] = 2.0; plane[3, 1] = 1.0
    >>> ys, xs, v = peaks(plane, 1, 1)
    >>> [(int(y), int(x), float(h)) for y, x, h in zip(ys, xs, v)]
    [(1, 4, 2.0), (3, 1, 1.0)]
    """
    ys, xs = K.local_maxima(best_val, int(radius))
    v = best_val[ys, xs]
    order = np.argsort(-v, kind="stable")[: 4 * n]
    return ys[order], xs[order], v[order]


def _one_peak_per_line(ctx: SearchContext, votes: Votes, ys, xs, vs):
    """The peaks of a line pattern, each on a line of its own: a long rope or
    post puts a ridge of peaks along itself (its position along the line is
    undetermined), which would take every candidate. The peaks are put in
    the order they are refined in: the two highest, then the highest of each
    other line (direction within 5 degrees, within one translation bin), then
    the rest, so that a second rope or post is refined too."""
    bins = ctx.bins
    if len(ys) < 2:
        return ys, xs, vs
    tx = bins.tx0 + (xs + 1) * bins.step
    ty = bins.ty0 + (ys + 1) * bins.step
    a = np.asarray(bins.angles)[votes.best_d[ys, xs]]
    near = bins.step   # (a pose half a width across, on one border, is another seed)
    tol = math.radians(5.0)
    # same[i][j]: peak i lies on the line of peak j (direction within tol; its
    # distance to that line, of direction (cos a, -sin a), within a bin)
    da = np.abs((a[:, None] - a[None, :] + 0.5 * math.pi) % math.pi - 0.5 * math.pi)
    off = np.abs((tx[:, None] - tx[None, :]) * -np.sin(a)[None, :]
                 - (ty[:, None] - ty[None, :]) * np.cos(a)[None, :])
    same = (da <= tol) & (off <= near)
    covered = np.zeros(len(ys), bool)   # on the line of a peak kept so far
    keep: list[int] = []
    for i in range(len(ys)):           # greedy, highest first
        if not covered[i]:
            keep.append(i)
            covered |= same[:, i]
    # the two highest first (as for any pattern: refinement may need the
    # second seed on the best line), then one per other line, then the rest
    kept = np.asarray([i for i in keep if i > 1], int)
    order = np.concatenate([[0, 1], kept, np.setdiff1d(np.arange(2, len(ys)), kept)])
    k = order.astype(int)
    return ys[k], xs[k], vs[k]


def _seed_cells(ctx: SearchContext, votes: Votes):
    """The accumulator cells to refine: ``(y, x, height, is_peak)``."""
    cfg, p, bins, tune = ctx.config, ctx.pattern, ctx.bins, ctx.config.search
    best_val, best_k, best_d = votes.best_val, votes.best_k, votes.best_d
    s0 = ctx.scale_range[0]
    if p.is_line:
        radius = max(1, int(round(0.5 * p.line_width * s0 * ctx.factor / bins.step)))
    else:
        radius = int(np.clip(round(0.25 * p.extent * s0 * ctx.factor / bins.step), 1,
                             tune.peak_radius))
    if p.is_line:   # (many maxima lie along one line: look further down the list)
        ys, xs, vs = _one_peak_per_line(ctx, votes, *peaks(best_val, radius, 8 * ctx.n_candidates))
    else:
        ys, xs, vs = peaks(best_val, radius, ctx.n_candidates)
    known = bins.scale_known and bins.angle_known
    n_peaks = ctx.max_results + 1 if known else ctx.n_candidates + 4
    cells = []
    ny, nx = best_val.shape
    for i, (yy, xx, v) in enumerate(list(zip(ys, xs, vs))[:n_peaks]):
        if known and v < 0.25 * vs[0]:
            break  # a sharp 2-D accumulator: far lower peaks cannot reach min_score
        cells.append((yy, xx, v, True))
        if known or i >= tune.neighbour_seeds:  # (one scale, one rotation: nothing beside)
            continue
        # a self-similar shape (L, rectangle) puts a smaller copy in its
        # own corner: the true cell may sit next to the peak, below it.
        # Counting, two such cells: the clutter that 2,400 key points bring
        # lifts a larger, turned pose over an object's own cell (an amphora
        # in a wreck photo, found with -n 5, was lost with -n 10 and 15)
        y0, y1, x0, x1 = max(yy - 2, 0), min(yy + 3, ny), max(xx - 2, 0), min(xx + 3, nx)
        win = best_val[y0:y1, x0:x1]
        taken = [(yy, xx)]
        for j in np.argsort(-win, axis=None)[1:]:
            wy, wx = divmod(int(j), win.shape[1])
            cy, cx = y0 + wy, x0 + wx
            if win[wy, wx] < 0.6 * v:
                break
            if all(abs(int(best_k[cy, cx]) - int(best_k[ty, tx])) >= 2
                   or abs(int(best_d[cy, cx]) - int(best_d[ty, tx])) >= 2 for ty, tx in taken):
                cells.append((cy, cx, float(win[wy, wx]), False))
                taken.append((cy, cx))
                if len(taken) > (2 if ctx.counting else 1):
                    break
    return cells


def seeds(ctx: SearchContext, votes: Votes, look_points, look_radius: float) -> list:
    """The :class:`Seed` of each cell worth refining, in the order they are
    refined: the strongest peaks first (a big pattern's coarse pose can look
    poor), then the others by how well they look."""
    p, bins, feats = ctx.pattern, ctx.bins, ctx.features
    sx, sy, sa = look_points
    tol = math.radians(ctx.config.angle_tolerance)
    known = bins.scale_known and bins.angle_known
    out = []
    for yy, xx, v, is_peak in _seed_cells(ctx, votes):
        tx = bins.tx0 + (xx + 1) * bins.step
        ty = bins.ty0 + (yy + 1) * bins.step
        k0 = int(votes.best_k[yy, xx])
        angle = float(bins.angles[votes.best_d[yy, xx]])
        if known:  # one scale: nothing to choose, refinement will judge it
            out.append(Seed(float(v), float(v), tx, ty, (k0,), angle, is_peak))
            continue
        by_k = []
        for k in sorted(range(max(k0 - 1, 0), min(k0 + 2, bins.scales.size)), key=lambda k: abs(k - k0)):
            pose = Pose.from_params(tx, ty, float(bins.scales[k]), angle)
            by_k.append((refine(pose, sx, sy, sa, feats.edges, feats.index, radii=(),
                                angle_tol=tol, either=p.either, score_radius=look_radius).score, k))
        by_k.sort(key=lambda t: -t[0])
        # the look only orders the seeds: a poor first look can still refine
        # to the object when nothing better claims the refinement budget
        out.append(Seed(by_k[0][0], float(v), tx, ty, tuple(k for _, k in by_k), angle, is_peak))
    top = [i for i, s in enumerate(out) if s.is_peak][: ctx.config.search.top_votes]
    return [out[i] for i in top] + sorted((s for i, s in enumerate(out) if i not in top),
                                          key=lambda s: -s.look)


def icp_subset(pf: PatternFeatures, k: int, frame: bool = False) -> np.ndarray:
    """Indices of ``k`` of the pattern's points (all when fewer), spread
    around it: evenly spaced in the order of their direction from the
    origin (then every other one is still spread around it). The points'
    own order is not spatial: a drawn shape's alternates between its sides,
    and every other index of a rectangle's 198 points left out its whole
    left side, so the refinement could not fix its width (a clean box
    turned by 30 degrees stopped a pixel off, score 0.83). A frame's points
    (``frame``) keep their own order, strongest first, every n-th of them:
    no side of a frame is left out that way, and the motion benchmarks were
    measured so.

    >>> from seahough.core.pattern import Pattern
    >>> pf = Pattern.rectangle(60, 40).features(1.0)
    >>> sub = icp_subset(pf, 100)
    >>> for half in (sub, sub[::2]):   # (the short ICPs take every other one)
    ...     sides = np.round(np.degrees(pf.vangle[half]) / 90) % 4
    ...     print(sorted(set(sides.astype(int).tolist())))
    [0, 1, 2, 3]
    [0, 1, 2, 3]
    """
    n = pf.vx.size
    k = min(int(k), n)
    spread = np.unique(np.linspace(0, n - 1, k).astype(int))
    if frame:
        return spread
    order = np.argsort(np.arctan2(pf.vy, pf.vx), kind="stable")
    return order[spread]   # (in that order: every other one is still spread around)


def find_candidates(ctx: SearchContext, votes: Votes) -> list:
    """Refine the accumulator's most promising cells into distinct candidate
    poses at the working scale, best first (at most ``ctx.n_candidates``; when
    counting, every seed's)."""
    cfg, p, bins, pf, feats = ctx.config, ctx.pattern, ctx.bins, ctx.pf, ctx.features
    tune = cfg.search
    cmp = ctx.compare
    tol = math.radians(cfg.angle_tolerance)
    # iterate on a subset of the points; score with all of them at the end
    sub = icp_subset(pf, tune.icp_points, p.is_frame)
    sx, sy, sa = (np.ascontiguousarray(v[sub]) for v in (pf.vx, pf.vy, pf.vangle))
    # the short ICPs that pick a scale seed use half of them, but a big
    # pattern (a whole frame) needs them all
    msub = sub[:: 2] if pf.radius < 40 else sub
    mx, my, ma = (np.ascontiguousarray(v[msub]) for v in (pf.vx, pf.vy, pf.vangle))
    score_r = max(1.25, cfg.match_radius * ctx.factor)
    r0 = float(np.clip(1.5 * bins.step, 2.0, tune.max_radius))
    radii = (r0, max(0.6 * r0, 1.5), 1.25)
    # screen every peak with cheap single matching passes, at the cell's
    # best scale and its neighbours: the cell's best scale can be a bin or
    # two off (a smaller copy fitting part of the object)
    todo = seeds(ctx, votes, (sx, sy, sa), min(r0, tune.look_radius))
    known = bins.scale_known and bins.angle_known
    edges, index = feats.edges, feats.index

    def icp(start, px, py, pa, rad, iterations, fix_scale, fix_angle):
        return refine(start, px, py, pa, edges, index, radii=rad, iterations=iterations,
                      angle_tol=tol, either=p.either, fix_scale=fix_scale, fix_angle=fix_angle,
                      score_radius=score_r)

    def score(pose):  # all the points, no refinement
        return refine(pose, pf.vx, pf.vy, pf.vangle, edges, index, radii=(), angle_tol=tol,
                      either=p.either, score_radius=score_r)

    out: list[Candidate] = []
    # a whole frame's other candidates are mostly chance matches of its
    # texture, there to measure the runner-up: one that fits far worse than
    # the best so far after its first short ICP is scored there (tune.screen)
    screen = p.is_frame and not known
    # counting: every seed is refined and kept (the seeds of a weak object
    # come late, after the clutter's have taken the places; ranking judges them)
    for rank, sd in enumerate(todo):
        if len(out) >= ctx.n_candidates and not ctx.counting:
            break
        ks, v, tx, ty, angle = sd.scale_bins, sd.votes, sd.tx, sd.ty, sd.angle
        lead = tune.screen * max((c.work_score for c in out), default=0.0)
        start = Pose.from_params(tx, ty, float(bins.scales[ks[0]]), angle)
        if rank < tune.full_treatment and cfg.refine and len(ks) > 1:
            # scale and position trade off along a corner: a short ICP from
            # each scale seed, then the full one from the best of them
            best = -1.0
            for k in ks:
                pose = Pose.from_params(tx, ty, float(bins.scales[k]), angle)
                f = icp(pose, mx, my, ma, radii[:2], 3, bins.scale_known, bins.angle_known)
                if f.score > best:
                    best, start = f.score, f.pose
                if screen and best < lead:
                    break
            if screen and best < lead:
                fit = score(start)
                if cmp.pose_ok(fit.pose) and not any(cmp.close(fit.pose, c.fit.pose) for c in out):
                    out.append(Candidate(fit, v, fit.score))
                continue
        if known:  # only the translation moves: refine on the subset, score with all
            fit = icp(start, sx, sy, sa, radii if cfg.refine else (), tune.icp_iterations,
                      True, True)
            fit = score(fit.pose)
        else:
            starts = [start]
            if not (rank < tune.full_treatment and len(ks) > 1) and len(ks) > 1:
                starts.append(Pose.from_params(tx, ty, float(bins.scales[ks[1]]), angle))
            fit = None
            for st in starts:  # the second-best scale only when the first is not good
                f = icp(st, sx, sy, sa, radii if cfg.refine else (), tune.icp_iterations,
                        bins.scale_known, bins.angle_known)
                if fit is None or f.score > fit.score:
                    fit = f
                if fit.score >= tune.good_fit:
                    break
            if not cmp.pose_ok(fit.pose):
                continue
            fit = score(fit.pose)
        # two peaks may converge on one pose; distinct poses all stay
        # candidates (object-level suppression comes after ranking)
        if any(cmp.close(fit.pose, c.fit.pose) for c in out):
            continue
        out.append(Candidate(fit, v, fit.score))
    out.sort(key=lambda c: -c.work_score)
    return out if ctx.counting else out[: ctx.n_candidates]


def best_declined(res):
    """The best-scoring candidate of a search that was not reported (not
    merely a repeat of a better one), or None: what a user tunes by."""
    cands = [c for c in getattr(res, "candidates", None) or ()
             if c.declined and not c.declined.startswith("the same object")]
    # (a candidate finished at full resolution before one cut at the coarse scale:
    # their scores are not measured alike)
    return max(cands, key=lambda c: (c.full is not None, c.score)) if cands else None
