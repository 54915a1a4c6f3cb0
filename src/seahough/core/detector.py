"""Stages 5-7: peaks of the accumulator, refined poses, detections."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from . import kernels as K
from .accumulator import AccumulatorPlanes, Bins, accumulate, check_ranges, make_bins
from ..config import Config
from .._validate import number
from ..errors import ParameterError
from .features import Features, extract_features
from ..geometry import apply_matrix, pose_to_matrix
from ..io.images import to_gray
from .keypoints import edge_points_near
from .pattern import Pattern
from .preprocess import choose_factor, compute_gradients
from .refine import Fit, Pose, refine

#: Flag on line detections: the position along the line is not measured.
FLAG_ALONG_LINE = "position_along_line_undetermined"
#: Flag when the detection lies partly outside the image.
FLAG_PARTIAL = "partly_outside_image"
#: Flag when a close runner-up makes the detection doubtful.
FLAG_AMBIGUOUS = "ambiguous"
#: Flag when refinement took the scale or rotation outside the searched
#: ranges (by more than 2 % or 1 degree): the object may be there at a size
#: or turn that was not asked for.
FLAG_OUTSIDE_RANGE = "outside_search_range"


@dataclass
class Detection:
    """One instance of the pattern found in an image.

    Attributes
    ----------
    x, y : float
        Where the pattern origin lies, in full-resolution image pixels.
    scale : float
        Size in the image relative to the pattern (equation 1's rho).
    angle : float
        Rotation in degrees [0, 360), counter-clockwise as displayed (phi).
    score : float
        Share of the pattern's edge points found in the image at this pose
        (0-1), after refinement.
    confidence : float
        How distinct this find is: ``(score - r) / (1 - r)``, where ``r`` is
        the score of the best other candidate that is not one of the returned
        detections (the share of what the runner-up leaves unexplained that
        this find explains; 0: no better than the clutter, 1: unique). Both
        scores are measured at the working scale.
    matrix : ndarray (2, 3)
        Pattern-image pixel (x, y) -> image pixel (x, y); the matrix
        ``cv2.warpAffine(pattern.image, matrix, (w, h))`` takes.
    outline : list of ndarray
        The pattern's outline polylines in image pixels.
    votes : float
        Height of the accumulator peak (share of the voting points).
    kind : str
        ``"object"``, or ``"line"`` for line patterns.
    line_angle, line_offset : float or None
        For lines: direction in degrees [0, 180) (counter-clockwise from +x as
        displayed) and the signed distance in pixels from the image centre
        ``((w-1)/2, (h-1)/2)`` to the line, positive when the line lies on
        the side of the normal ``(sin a, cos a)`` (i.e. below the centre for a
        horizontal line). ``x, y`` is then the point of the line nearest the
        image centre.
    flags : tuple of str
        Warnings about this result (see the ``FLAG_*`` constants).
    """

    x: float
    y: float
    scale: float
    angle: float
    score: float
    confidence: float
    matrix: np.ndarray
    outline: list = field(default_factory=list)
    votes: float = 0.0
    kind: str = "object"
    line_angle: float | None = None
    line_offset: float | None = None
    flags: tuple = ()

    def to_dict(self) -> dict:
        """Plain-Python form for JSON."""
        d = {"x": self.x, "y": self.y, "scale": self.scale, "angle": self.angle,
             "score": self.score, "confidence": self.confidence,
             "matrix": np.asarray(self.matrix).tolist(), "votes": self.votes,
             "kind": self.kind, "flags": list(self.flags)}
        if self.kind == "line":
            d["line_angle"] = self.line_angle
            d["line_offset"] = self.line_offset
        return d


#: Why a search ended early with no detections ("" when it ran to the end).
SEARCH_NOTES = ("", "no edges", "pattern larger than the image",
                "search_region is outside the image")


@dataclass
class SearchResult:
    """Everything one search produced: the detections and how it got there.

    ``note`` says why a search stopped before voting (its detections are
    then empty): one of :data:`SEARCH_NOTES`. ``planes`` and ``features``
    may then be None.
    """

    detections: list
    planes: AccumulatorPlanes | None
    features: Features | None
    factor: float
    candidates: list
    timings: dict
    note: str = ""


@dataclass
class _Candidate:
    fit: Fit
    votes: float
    work_score: float
    full: Fit | None = None


def confidence(score: float, runner_up: float) -> float:
    """How distinct a find is from the best other candidate: of the pattern
    that the runner-up leaves unexplained, the share the find explains.

    Examples
    --------
    >>> round(confidence(1.0, 0.88), 2), round(confidence(0.55, 0.5), 2)
    (1.0, 0.1)
    """
    return float(np.clip((score - runner_up) / max(1.0 - runner_up, 1e-9), 0.0, 1.0))


def line_parameters(x: float, y: float, angle_deg: float, shape) -> tuple[float, float, float, float]:
    """(line_angle, line_offset, foot_x, foot_y) of the line through (x, y) at
    ``angle_deg``, relative to the centre of an image of ``shape``."""
    h, w = shape[:2]
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0
    a = angle_deg % 180.0
    t = math.radians(a)
    n = np.array([math.sin(t), math.cos(t)])    # normal
    off = float(n @ (np.array([x, y]) - [cx, cy]))
    fx, fy = cx + off * n[0], cy + off * n[1]
    return a, off, float(fx), float(fy)


class Detector:
    """Find a pattern at unknown position, scale and rotation.

    Create it once per pattern and search range, then call :meth:`detect`
    on as many images as needed.

    Parameters
    ----------
    pattern : Pattern
        What to look for.
    scale_range : (float, float)
        Smallest and largest size relative to the pattern. Equal values mean
        a known scale.
    angle_range : (float, float)
        Rotations to search, degrees (counter-clockwise as displayed). Equal
        values mean a known rotation; the default is any rotation.
    config : Config, optional
        Tuning of every stage.
    max_results : int
        At most this many detections.
    min_score : float
        A detection must have at least this share of the pattern's edges.
    min_confidence : float
        ... and at least this confidence.
    search_region : (x0, y0, x1, y1), optional
        Where the pattern origin may lie, in full-resolution image pixels.
        Default: the image, plus a margin of a tenth of the pattern's size.

    Examples
    --------
    >>> import numpy as np, cv2
    >>> img = np.full((240, 320), 40, np.uint8)
    >>> box = cv2.boxPoints(((200.0, 110.0), (90.0, 50.0), -30.0))
    >>> _ = cv2.fillPoly(img, [np.round(box).astype(np.int32)], 220)
    >>> found = Detector(Pattern.rectangle(60, 100)).detect(img)
    >>> d = found[0]
    >>> round(d.x), round(d.y), round(d.scale, 1)
    (200, 110, 0.9)
    """

    def __init__(self, pattern: Pattern, scale_range=(0.5, 2.0), angle_range=(0.0, 360.0), *,
                 config: Config | None = None, max_results: int = 5, min_score: float = 0.5,
                 min_confidence: float = 0.0, search_region=None):
        if not isinstance(pattern, Pattern):
            raise ParameterError(f"pattern must be a seahough.Pattern, got {type(pattern).__name__}")
        self.pattern = pattern
        (self.scale_range, self.angle_range) = check_ranges(scale_range, angle_range)
        self.config = config or Config()
        if not isinstance(self.config, Config):
            raise ParameterError("config must be a seahough.Config")
        self.max_results = int(number("max_results", max_results, lo=1, integer=True))
        self.min_score = number("min_score", min_score, lo=0.0, hi=1.0)
        self.min_confidence = number("min_confidence", min_confidence, lo=0.0, hi=1.0)
        if search_region is not None:
            try:
                sr = tuple(float(v) for v in search_region)
            except (TypeError, ValueError):
                sr = ()
            if len(sr) != 4 or not all(map(math.isfinite, sr)) or sr[2] <= sr[0] or sr[3] <= sr[1]:
                raise ParameterError(f"search_region={search_region!r}: expected (x0, y0, x1, y1) "
                                     "with x1 > x0 and y1 > y0")
            search_region = sr
        self.search_region = search_region

    # ------------------------------------------------------------------ public
    def detect(self, image) -> list:
        """Detections of the pattern in ``image`` (path or array), best first.

        An empty list means the pattern was not found.
        """
        return self.search(image).detections

    def search(self, image, features: Features | None = None) -> SearchResult:
        """Like :meth:`detect`, also returning the accumulator planes, all
        scored candidates and the stage timings.

        ``features`` may pass the image's already computed features (from a
        previous search at the same working scale), e.g. in dead reckoning.
        """
        cfg = self.config
        t0 = time.perf_counter()
        timings = {}
        gray = to_gray(image, max_pixels=cfg.max_pixels)
        p = self.pattern
        s0, s1 = self.scale_range
        # a pattern that cannot fit the image at any searched scale is not there;
        # larger scales than that are not searched (they would only size the
        # accumulator)
        fit = 2.0 * math.hypot(*gray.shape) / p.extent
        s1 = min(s1, max(fit, s0))
        factor = features.gradients.factor if features is not None else choose_factor(
            gray.shape, cfg, p.extent, s0)
        if features is None:
            known = (self.scale_range[0] == self.scale_range[1]
                     and self.angle_range[0] == self.angle_range[1])
            n_kp = cfg.n_keypoints_2d if known and cfg.n_keypoints_2d is not None else None
            features = extract_features(gray, factor, cfg, n_keypoints=n_kp)
        t1 = time.perf_counter()
        timings["features"] = t1 - t0
        if len(features.segments) < 4:
            return SearchResult([], None, features, factor, [], timings, note="no edges")
        if s0 > fit:
            return SearchResult([], None, features, factor, [], timings,
                                note="pattern larger than the image")
        pf = p.features(factor, cfg)
        g = features.gradients
        h, w = features.shape
        if self.search_region is not None:
            # the origin cannot lie farther out than the pattern reaches
            m = p.reach * s1 * factor + 2.0
            x0, y0 = g.to_work(self.search_region[0], self.search_region[1])
            x1, y1 = g.to_work(self.search_region[2], self.search_region[3])
            x0, y0 = max(x0, -m), max(y0, -m)
            x1, y1 = min(x1, w - 1 + m), min(y1, h - 1 + m)
            if x1 <= x0 or y1 <= y0:
                return SearchResult([], None, features, factor, [], timings,
                                    note="search_region is outside the image")
        else:
            m = 0.1 * p.extent * s1 * factor
            x0, y0, x1, y1 = -m, -m, w - 1 + m, h - 1 + m
        region = (float(x0), float(y0), float(x1), float(y1))
        bins = make_bins(pf, (s0, s1), self.angle_range, region, cfg)
        best_val, best_k, best_d, proj = accumulate(pf, features.segments, bins, p.either)
        t2 = time.perf_counter()
        timings["voting"] = t2 - t1
        planes = self._planes(bins, best_val, best_k, best_d, proj, g)
        self._points = np.stack([pf.vx, pf.vy], 1).astype(float)
        self._probe = self._points[:: max(1, pf.vx.size // 64)]
        self._centre = tuple(float(v) for v in self._points.mean(axis=0))
        hull = cv2.convexHull(np.vstack(p.outline).astype(np.float32)).reshape(-1, 2)
        self._footprint = hull.astype(float) - np.asarray(p.origin)  # pattern px, from origin
        self._close_px = max(2.0 * bins.step, 3.0)
        cands = self._candidates(pf, features, bins, best_val, best_k, best_d, factor)
        t3 = time.perf_counter()
        timings["peaks_refine"] = t3 - t2
        dets = self._finish(cands, gray, features, factor)
        timings["full_resolution"] = time.perf_counter() - t3
        timings["total"] = time.perf_counter() - t0
        return SearchResult(dets, planes, features, factor, cands, timings)

    # ----------------------------------------------------------------- helpers
    def _planes(self, bins: Bins, best_val, best_k, best_d, proj, g) -> AccumulatorPlanes:
        cols = bins.tx0 + (np.arange(best_val.shape[1]) + 1) * bins.step
        rows = bins.ty0 + (np.arange(best_val.shape[0]) + 1) * bins.step
        xs, ys = g.to_full(cols, rows)
        return AccumulatorPlanes(best_val, best_k, best_d, proj, bins.scales.copy(),
                                 np.degrees(bins.angles) % 360.0,
                                 np.asarray(xs, float), np.asarray(ys, float))

    def _peaks(self, best_val, radius: int, n: int):
        """Local maxima of the dx-dy plane, highest first."""
        ys, xs = K.local_maxima(best_val, int(radius))
        v = best_val[ys, xs]
        order = np.argsort(-v, kind="stable")[: 4 * n]
        return ys[order], xs[order], v[order]

    _peak_radius = 1
    _overlap = 0.3
    _good_fit = 0.7
    _full_treatment = 4
    _icp_points = 100
    _icp_iterations = 4
    _max_radius = 6.0
    _look_radius = 3.0
    _top_votes = 3
    _neighbour_seeds = 6
    #: A whole frame's candidate whose first short ICP (from its best-looking
    #: scale) scores below this share of the best candidate so far is scored
    #: there and not refined further. Only the scale seeds are screened: a
    #: tile-shifted look-alike on the pool (refined: 0.51 against 0.78) was
    #: found only from its second scale, so candidates that start from two
    #: scales try both (screening those too raised that pair's confidence by
    #: 0.16). See docs/method.md.
    _screen = 0.5

    def _candidates(self, pf, features: Features, bins: Bins, best_val, best_k, best_d, factor):
        cfg = self.config
        p = self.pattern
        s0 = self.scale_range[0]
        if p.is_line:
            radius = max(1, int(round(0.5 * p.line_width * s0 * factor / bins.step)))
        else:
            radius = int(np.clip(round(0.25 * p.extent * s0 * factor / bins.step), 1, self._peak_radius))
        ys, xs, vs = self._peaks(best_val, radius, cfg.n_candidates)
        tol = math.radians(cfg.angle_tolerance)
        # iterate on a subset of the points; score with all of them at the end
        sub = np.unique(np.linspace(0, pf.vx.size - 1, min(self._icp_points, pf.vx.size)).astype(int))
        sx, sy, sa = (np.ascontiguousarray(v[sub]) for v in (pf.vx, pf.vy, pf.vangle))
        # the short ICPs that pick a scale seed use half of them, but a big
        # pattern (a whole frame) needs them all
        msub = sub[:: 2] if pf.radius < 40 else sub
        mx, my, ma = (np.ascontiguousarray(v[msub]) for v in (pf.vx, pf.vy, pf.vangle))
        score_r = max(1.25, cfg.match_radius * factor)
        r0 = float(np.clip(1.5 * bins.step, 2.0, self._max_radius))
        radii = (r0, max(0.6 * r0, 1.5), 1.25)
        look_r = min(r0, self._look_radius)
        # screen every peak with cheap single matching passes, at the cell's
        # best scale and its neighbours: the cell's best scale can be a bin or
        # two off (a smaller copy fitting part of the object)
        looks = []
        seeds = []
        ny, nx = best_val.shape
        known = bins.scale_known and bins.angle_known
        n_peaks = self.max_results + 1 if known else cfg.n_candidates + 4
        for i, (yy, xx, v) in enumerate(list(zip(ys, xs, vs))[:n_peaks]):
            if known and v < 0.25 * vs[0]:
                break  # a sharp 2-D accumulator: far lower peaks cannot reach min_score
            seeds.append((yy, xx, v, True))
            if known or i >= self._neighbour_seeds:  # (one scale, one rotation: nothing beside)
                continue
            # a self-similar shape (L, rectangle) puts a smaller copy in its
            # own corner: the true cell may sit next to the peak, below it
            y0, y1, x0, x1 = max(yy - 2, 0), min(yy + 3, ny), max(xx - 2, 0), min(xx + 3, nx)
            win = best_val[y0:y1, x0:x1]
            for j in np.argsort(-win, axis=None)[1:]:
                wy, wx = divmod(int(j), win.shape[1])
                cy, cx = y0 + wy, x0 + wx
                dk = abs(int(best_k[cy, cx]) - int(best_k[yy, xx]))
                dd = abs(int(best_d[cy, cx]) - int(best_d[yy, xx]))
                if dk >= 2 or dd >= 2:
                    if win[wy, wx] >= 0.6 * v:
                        seeds.append((cy, cx, float(win[wy, wx]), False))
                    break
        for yy, xx, v, is_peak in seeds:
            tx = bins.tx0 + (xx + 1) * bins.step
            ty = bins.ty0 + (yy + 1) * bins.step
            k0 = int(best_k[yy, xx])
            angle = float(bins.angles[best_d[yy, xx]])
            if known:  # one scale: nothing to choose, refinement will judge it
                looks.append((float(v), float(v), tx, ty, [k0], angle, is_peak))
                continue
            by_k = []
            for k in sorted(range(max(k0 - 1, 0), min(k0 + 2, bins.scales.size)), key=lambda k: abs(k - k0)):
                pose = Pose.from_params(tx, ty, float(bins.scales[k]), angle)
                by_k.append((refine(pose, sx, sy, sa, features.edges, features.index, radii=(),
                                    angle_tol=tol, either=p.either, score_radius=look_r).score, k))
            by_k.sort(key=lambda t: -t[0])
            # the look only orders the seeds: a poor first look can still refine
            # to the object when nothing better claims the refinement budget
            looks.append((by_k[0][0], float(v), tx, ty, [k for _, k in by_k], angle, is_peak))
        # the strongest accumulator peaks are always refined first, whatever
        # their first look (a big pattern's coarse pose can look poor), then
        # the others by how well they look
        top = [i for i, t in enumerate(looks) if t[6]][: self._top_votes]
        looks = [looks[i] for i in top] + sorted(
            (t for i, t in enumerate(looks) if i not in top), key=lambda t: -t[0])
        out = []
        # a whole frame's other candidates are mostly chance matches of its
        # texture, there to measure the runner-up: one that fits far worse than
        # the best so far after its first short ICP is scored there (_screen)
        screen = p.kind == "frame" and not known
        for rank, (_, v, tx, ty, ks, angle, _) in enumerate(looks):
            if len(out) >= cfg.n_candidates:
                break
            lead = self._screen * max((c.work_score for c in out), default=0.0)
            start = Pose.from_params(tx, ty, float(bins.scales[ks[0]]), angle)
            if rank < self._full_treatment and cfg.refine and len(ks) > 1:
                # scale and position trade off along a corner: a short ICP from
                # each scale seed, then the full one from the best of them
                best = -1.0
                for k in ks:
                    pose = Pose.from_params(tx, ty, float(bins.scales[k]), angle)
                    f = refine(pose, mx, my, ma, features.edges, features.index,
                               radii=radii[:2], iterations=3, angle_tol=tol, either=p.either,
                               fix_scale=bins.scale_known, fix_angle=bins.angle_known,
                               score_radius=score_r)
                    if f.score > best:
                        best, start = f.score, f.pose
                    if screen and best < lead:
                        break
                if screen and best < lead:
                    fit = refine(start, pf.vx, pf.vy, pf.vangle, features.edges, features.index,
                                 radii=(), angle_tol=tol, either=p.either, score_radius=score_r)
                    if self._pose_ok(fit.pose) and not any(self._close(fit.pose, c.fit.pose)
                                                           for c in out):
                        out.append(_Candidate(fit, v, fit.score))
                    continue
            if known:  # only the translation moves: refine on the subset, score with all
                fit = refine(start, sx, sy, sa, features.edges, features.index,
                             radii=radii if cfg.refine else (), angle_tol=tol, either=p.either,
                             fix_scale=True, fix_angle=True, score_radius=score_r,
                             iterations=self._icp_iterations)
                fit = refine(fit.pose, pf.vx, pf.vy, pf.vangle, features.edges, features.index,
                             radii=(), angle_tol=tol, either=p.either, score_radius=score_r)
            else:
                starts = [start]
                if not (rank < self._full_treatment and len(ks) > 1) and len(ks) > 1:
                    starts.append(Pose.from_params(tx, ty, float(bins.scales[ks[1]]), angle))
                fit = None
                for st in starts:  # the second-best scale only when the first is not good
                    f = refine(st, sx, sy, sa, features.edges, features.index,
                               radii=radii if cfg.refine else (), angle_tol=tol, either=p.either,
                               fix_scale=bins.scale_known, fix_angle=bins.angle_known,
                               score_radius=score_r, iterations=self._icp_iterations)
                    if fit is None or f.score > fit.score:
                        fit = f
                    if fit.score >= self._good_fit:
                        break
                if not self._pose_ok(fit.pose):
                    continue
                fit = refine(fit.pose, pf.vx, pf.vy, pf.vangle, features.edges, features.index,
                             radii=(), angle_tol=tol, either=p.either, score_radius=score_r)
            # two peaks may converge on one pose; distinct poses all stay
            # candidates (object-level suppression comes after ranking)
            if any(self._close(fit.pose, c.fit.pose) for c in out):
                continue
            out.append(_Candidate(fit, v, fit.score))
        out.sort(key=lambda c: -c.work_score)
        return out

    def _outside_ranges(self, scale: float, angle: float) -> bool:
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

    def _pose_ok(self, pose: Pose) -> bool:
        s0, s1 = self.scale_range
        return 0.8 * s0 <= pose.scale <= 1.25 * s1 and math.isfinite(pose.tx) and math.isfinite(pose.ty)

    def _same(self, a: Pose, b: Pose, factor: float) -> bool:
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
        fa, fb = self._placed(a, factor), self._placed(b, factor)
        inter, _ = cv2.intersectConvexConvex(fa, fb)
        smaller = min(cv2.contourArea(fa), cv2.contourArea(fb))
        return smaller > 0 and inter > self._overlap * smaller

    def _placed(self, pose: Pose, factor: float) -> np.ndarray:
        """The pattern's convex footprint placed at ``pose``."""
        fp = self._footprint * factor
        qx, qy = pose.map(fp[:, 0], fp[:, 1])
        return np.stack([qx, qy], 1).astype(np.float32)

    def _centre_gap(self, a: Pose, b: Pose) -> float:
        """Distance between the pattern points' centre placed by ``a`` and by ``b``."""
        cx, cy = self._centre
        dx = (a.tx - b.tx) + (a.a - b.a) * cx + (a.b - b.b) * cy
        dy = (a.ty - b.ty) - (a.b - b.b) * cx + (a.a - b.a) * cy
        return math.hypot(dx, dy)

    def _close(self, a: Pose, b: Pose) -> bool:
        """Practically the same pose: the pattern's points move less than
        ~2 working pixels between the two."""
        if self._centre_gap(a, b) >= self._close_px:
            return False
        pts = self._probe
        ax, ay = a.map(pts[:, 0], pts[:, 1])
        bx, by = b.map(pts[:, 0], pts[:, 1])
        return float(np.max(np.hypot(ax - bx, ay - by))) < self._close_px

    def _equivalent(self, a: Pose, b: Pose) -> bool:
        """The same answer in another guise: the pattern's edge points placed
        by ``a`` and by ``b`` coincide as sets (a symmetric shape turned onto
        itself, e.g. a rectangle by 180 degrees)."""
        # a camera frame has no symmetry, and its points cover it so densely
        # that any nearby pose would pass the test below
        if self.pattern.kind == "frame":
            return False
        # point sets that coincide have (nearly) the same centre: a cheap test first
        if self._centre_gap(a, b) > 3.0 * self._close_px:
            return False
        ax, ay = a.map(self._probe[:, 0], self._probe[:, 1])
        bx, by = b.map(self._points[:, 0], self._points[:, 1])
        d = np.sqrt(((ax[:, None] - bx[None, :]) ** 2 + (ay[:, None] - by[None, :]) ** 2).min(axis=1))
        # the 90th percentile (as np.percentile interpolates it), by partition: faster
        n = d.size
        pos = 0.9 * (n - 1)
        lo = int(pos)
        hi = min(lo + 1, n - 1)
        part = np.partition(d, (lo, hi))
        q90 = part[lo] + (pos - lo) * (part[hi] - part[lo])
        return float(q90) < self._close_px

    def _full_pose(self, fit: Fit, features: Features) -> Pose:
        tx, ty = features.gradients.to_full(fit.pose.tx, fit.pose.ty)
        return Pose(fit.pose.a, fit.pose.b, float(tx), float(ty))

    #: Fewer full-resolution finishing points than this: the working-scale
    #: pose is the answer (a frame too faint or blurred at full resolution).
    _min_finish_points = 8

    #: Pose change the full-resolution refinement is allowed beyond its
    #: first match radius (px) when its edges are limited to a band.
    _band_slack = 2.0

    @staticmethod
    def _full_radius(factor: float) -> float:
        """First match radius of the full-resolution refinement (px): one
        working pixel."""
        return max(1.0 / factor, 2.0)

    def _full_edges(self, gray, todo, features: Features, factor: float):
        """Full-resolution edges near each candidate's pattern points, in a
        box around them: one box around all candidates when that is cheaper
        than one box each. Returns ``(box, edges, index)`` per candidate.

        Edges farther from the pattern's points than the refinement's match
        radius plus the distance it may move the pose could never be matched:
        they are left out (finding them cost as much as the rest of the finish).
        """
        vx, vy, _ = self.pattern.finish_points(factor, self.config)
        if vx.size < self._min_finish_points:  # (no edges at full resolution)
            return [None] * len(todo)
        H, W = gray.shape
        pts = [self._full_pose(c.fit, features).map(vx, vy) for c in todo]
        band_r = int(math.ceil(self._full_radius(factor) + self._band_slack))
        m = band_r + 4
        boxes = [(int(max(0, math.floor(mx.min()) - m)), int(max(0, math.floor(my.min()) - m)),
                  int(min(W, math.ceil(mx.max()) + m + 1)), int(min(H, math.ceil(my.max()) + m + 1)))
                 for mx, my in pts]
        area = lambda b: max(b[2] - b[0], 0) * max(b[3] - b[1], 0)
        union = (min(b[0] for b in boxes), min(b[1] for b in boxes),
                 max(b[2] for b in boxes), max(b[3] for b in boxes))
        if sum(area(b) for b in boxes) >= area(union):
            groups = [(union, list(range(len(todo))))]
        else:
            groups = [(b, [i]) for i, b in enumerate(boxes)]
        out = [None] * len(todo)
        for box, members in groups:
            x0, y0, x1, y1 = box
            if x1 - x0 < 8 or y1 - y0 < 8:
                continue
            grad = compute_gradients(np.ascontiguousarray(gray[y0:y1, x0:x1]), 1.0,
                                     self.config.equalize)
            e = edge_points_near(grad, np.concatenate([pts[i][0] for i in members]) - x0,
                                 np.concatenate([pts[i][1] for i in members]) - y0, band_r,
                                 self.config.min_gradient)
            for i in members:
                out[i] = (box, e, e.index_map())
        return out

    def _full_res(self, fit: Fit, gray, features: Features, factor: float, where=None) -> Fit:
        """Refine a working-resolution fit on the full-resolution image."""
        cfg = self.config
        p = self.pattern
        pose = self._full_pose(fit, features)
        vx, vy, vang = p.finish_points(factor, cfg)
        if factor < 0.999:
            if where is None:  # (a box too small to hold edges, or no finishing points)
                return Fit(pose, fit.score, fit.matched, fit.rms, fit.inside)
            (x0, y0, x1, y1), edges, index = where
            H, W = gray.shape
            local = Pose(pose.a, pose.b, pose.tx - x0, pose.ty - y0)
            f = refine(local, vx, vy, vang, edges, index,
                       radii=(self._full_radius(factor), 1.5) if cfg.refine else (), iterations=3,
                       angle_tol=math.radians(cfg.angle_tolerance), either=p.either,
                       fix_scale=self.scale_range[0] == self.scale_range[1],
                       fix_angle=self.angle_range[0] == self.angle_range[1],
                       score_radius=cfg.match_radius)
            q = f.pose
            # the share inside the image is measured on the whole image, not the crop
            mx, my = Pose(q.a, q.b, q.tx + x0, q.ty + y0).map(vx, vy)
            inside = float(np.mean((mx >= 0) & (my >= 0) & (mx <= W - 1) & (my <= H - 1)))
            return Fit(Pose(q.a, q.b, q.tx + x0, q.ty + y0), f.score, f.matched, f.rms, inside)
        return refine(pose, vx, vy, vang, features.edges, features.index,
                      radii=(1.0,) if cfg.refine else (), angle_tol=math.radians(cfg.angle_tolerance),
                      either=p.either, fix_scale=self.scale_range[0] == self.scale_range[1],
                      fix_angle=self.angle_range[0] == self.angle_range[1],
                      score_radius=cfg.match_radius)

    def _finish(self, cands, gray, features: Features, factor: float) -> list:
        """Refine the promising candidates at full resolution, rank them by
        that score, keep the distinct ones and rate their confidence."""
        best = max((c.work_score for c in cands), default=0.0)
        pre = max(0.85 * self.min_score, 0.6 * best)  # only those that could win
        todo = [c for c in cands if c.work_score >= pre][: self.max_results + 2]
        wheres = self._full_edges(gray, todo, features, factor) if todo and factor < 0.999 else [None] * len(todo)
        for c, where in zip(todo, wheres):
            c.full = self._full_res(c.fit, gray, features, factor, where)
        # rank by both scores: the working scale's is smoother (less pixel
        # noise, JPEG, snow), the full resolution's sharper
        todo.sort(key=lambda c: -(c.full.score + c.work_score))
        accepted: list[_Candidate] = []
        for c in todo:
            if len(accepted) >= self.max_results:
                break
            if c.full.score < self.min_score or not self._pose_ok(c.full.pose):
                continue
            if any(self._same(c.full.pose, a.full.pose, 1.0) for a in accepted):
                continue
            accepted.append(c)
        # runner-up: the best candidate that is not (nearly) the same pose as a detection
        # (for a line: not the same line, found at another point along it)
        same = (lambda c, a: self._same(c.fit.pose, a.fit.pose, factor)) if self.pattern.is_line \
            else (lambda c, a: self._close(c.fit.pose, a.fit.pose)
                  or self._equivalent(c.fit.pose, a.fit.pose))
        others = [c.work_score for c in cands if not any(c is a or same(c, a) for a in accepted)]
        runner_up = max(others, default=0.0)
        dets = []
        for c in accepted:
            conf = confidence(c.work_score, runner_up)
            if conf < self.min_confidence:
                continue
            dets.append(self._detection(c, conf, gray.shape))
        dets.sort(key=lambda d: -d.score)
        return dets

    def _detection(self, c: _Candidate, confidence: float, shape) -> Detection:
        p = self.pattern
        pose = c.full.pose
        x, y, s, a = pose.tx, pose.ty, pose.scale, pose.angle
        kind, la, lo = "object", None, None
        if p.is_line:
            # any point of the line is as good: report the one nearest the centre
            kind = "line"
            la, lo, x, y = line_parameters(x, y, a, shape)
        m = pose_to_matrix(x, y, s, a, p.origin)
        outline = [apply_matrix(m, o) for o in p.outline]
        flags = []
        if c.full.inside < 0.98:
            flags.append(FLAG_PARTIAL)
        if confidence < 0.2:
            flags.append(FLAG_AMBIGUOUS)
        if p.is_line:
            flags.append(FLAG_ALONG_LINE)
        if self._outside_ranges(s, a):
            flags.append(FLAG_OUTSIDE_RANGE)
        return Detection(float(x), float(y), float(s), float(a), float(c.full.score), confidence,
                         m, outline, c.votes, kind, la, lo, tuple(flags))
