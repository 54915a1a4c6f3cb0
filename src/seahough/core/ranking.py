"""Stage 7: candidates -> detections.

The promising candidates are refined once more on the full-resolution image,
ranked, reduced to distinct objects, and rated against the best other
candidate (the runner-up): that is their confidence. The result is a list of
:class:`~.detection.Detection`, best first.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from . import kernels as K
from ..geometry import angle_difference, apply_matrix, line_parameters, pose_to_matrix, wrap_angle
from .candidates import Candidate, SearchContext, icp_subset
from .detection import (FLAG_ALONG_LINE, FLAG_AMBIGUOUS, FLAG_GREY, FLAG_HALF_TURN,  # noqa: F401
                        FLAG_OUTSIDE_RANGE, FLAG_PARTIAL, FLAG_QUARTER_TURN, FLAG_RANGE_EDGE,
                        Detection, confidence)
from .features import Features
from .lines import visible_stretches
from .keypoints import edge_points_near_image
from .nfa import CELL, background, evidence, search_tests
from .parts import hole_labels, unseen_hole
from .refine import Fit, Pose, match, refine
from .symmetry import pattern_turn_shares, symmetry_turn, turn_pose

#: A candidate's pose may move this share of the pattern's size to a shift
#: more of its points agree on (:func:`_alternatives`).
CAPTURE = 0.1
#: ... and its size change by this factor (:func:`_shifted`).
RESCALE = 1.12
#: A polyline's candidate is also fitted at sizes this step apart, up to
#: this many steps larger and smaller (:func:`_rescaled`; 12 drawn gates, 3
#: ranges: 24 -> 35 of 36 within 3 px; at most 5 % more time on RoboSub photos).
POLYLINE_RESIZE = (0.02, 6)


# ------------------------------------------------------------ full resolution
def _full_pose(pose: Pose, features: Features) -> Pose:
    tx, ty = features.gradients.to_full(pose.tx, pose.ty)
    return Pose(pose.a, pose.b, float(tx), float(ty))


def _full_radius(factor: float) -> float:
    """First match radius of the full-resolution refinement (px): one working pixel."""
    return max(1.0 / factor, 2.0)


def _full_edges(ctx: SearchContext, gray, todo, alternatives):
    """Full-resolution edges near each candidate's pattern points, in a
    box around them: one box around all candidates when that is cheaper
    than one box each (``alternatives``: per candidate, other working-scale
    fits whose points are gathered too, :func:`_alternatives`). Returns
    ``(box, edges, index)`` per candidate.

    Edges farther from the pattern's points than the refinement's match
    radius plus the distance it may move the pose could never be matched:
    they are left out (finding them cost as much as the rest of the finish).
    """
    cfg, factor = ctx.config, ctx.factor
    vx, vy, _ = ctx.pattern.finish_points(factor, cfg)
    if vx.size < cfg.search.min_finish_points:  # (no edges at full resolution)
        return [None] * len(todo)
    H, W = gray.shape[:2]  # (a colour image: HxWx3)
    pts = []
    for c, alts in zip(todo, alternatives):
        poses = [c.fit.pose] + [a.pose for a in alts]
        mapped = [_full_pose(q, ctx.features).map(vx, vy) for q in poses]
        pts.append((np.concatenate([m[0] for m in mapped]),
                    np.concatenate([m[1] for m in mapped])))
    band_r = int(math.ceil(_full_radius(factor) + cfg.search.band_slack))
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
        # (a strip of rows at a time: a large frame's gradients are 200 MB)
        e = edge_points_near_image(gray[y0:y1, x0:x1],
                                   np.concatenate([pts[i][0] for i in members]) - x0,
                                   np.concatenate([pts[i][1] for i in members]) - y0, band_r,
                                   cfg.min_gradient, None, cfg.equalize,
                                   metric=ctx.features.gradients.metric)
        for i in members:
            out[i] = (box, e, e.index_map())
    return out


def _full_res(ctx: SearchContext, fit: Fit, gray, where=None) -> Fit:
    """Refine a working-resolution fit on the full-resolution image."""
    cfg, p, factor = ctx.config, ctx.pattern, ctx.factor
    pose = _full_pose(fit.pose, ctx.features)
    vx, vy, vang = p.finish_points(factor, cfg)
    tol = math.radians(cfg.angle_tolerance)
    if factor < 0.999:
        if where is None:  # (a box too small to hold edges, or no finishing points)
            return Fit(pose, fit.score, fit.matched, fit.rms, fit.inside)
        (x0, y0, x1, y1), edges, index = where
        H, W = gray.shape[:2]  # (a colour image: HxWx3)
        local = Pose(pose.a, pose.b, pose.tx - x0, pose.ty - y0)
        f = refine(local, vx, vy, vang, edges, index,
                   radii=(_full_radius(factor), 1.5) if cfg.refine else (), iterations=3,
                   angle_tol=tol, either=p.either, fix_scale=ctx.scale_known,
                   fix_angle=ctx.angle_known, score_radius=cfg.match_radius)
        q = f.pose
        # the share inside the image is measured on the whole image, not the crop
        mx, my = Pose(q.a, q.b, q.tx + x0, q.ty + y0).map(vx, vy)
        inside = float(np.mean((mx >= 0) & (my >= 0) & (mx <= W - 1) & (my <= H - 1)))
        return Fit(Pose(q.a, q.b, q.tx + x0, q.ty + y0), f.score, f.matched, f.rms, inside)
    feats = ctx.features
    return refine(pose, vx, vy, vang, feats.edges, feats.index,
                  radii=(1.0,) if cfg.refine else (), angle_tol=tol, either=p.either,
                  fix_scale=ctx.scale_known, fix_angle=ctx.angle_known,
                  score_radius=cfg.match_radius)


def _capture(ctx: SearchContext) -> int:
    """How far (working px) :func:`_alternatives` looks for a better shift:
    :data:`CAPTURE` of the pattern's size at the searched scales, from 2 px
    to ``Config.search.max_radius``."""
    size = CAPTURE * ctx.pattern.extent * math.sqrt(ctx.scale_range[0] * ctx.scale_range[1])
    return int(np.clip(round(size * ctx.factor), 2, max(2, int(ctx.config.search.max_radius))))


def _subset(ctx: SearchContext):
    """The pattern points the candidates' refinement iterates on
    (``Config.search.icp_points`` of them: :func:`.candidates.icp_subset`)."""
    pf = ctx.pf
    sub = icp_subset(pf, ctx.config.search.icp_points, ctx.pattern.is_frame)
    return tuple(np.ascontiguousarray(v[sub]) for v in (pf.vx, pf.vy, pf.vangle))


def _shifted(ctx: SearchContext, pose: Pose, radius: int, points, rescale=True) -> Pose:
    """``pose`` moved by the shift most of the pattern's ``points`` (vx, vy,
    vangle) agree on, within ``radius`` working px (:func:`~.kernels.shift_votes`, smoothed
    over 3 x 3 px), at its scale or (``rescale``) :data:`RESCALE` times larger or smaller
    (a board of nested rings found a ring off); ``pose`` itself when no
    other does better."""
    e = ctx.features.edges
    vx, vy, vang = points
    tol = math.radians(ctx.config.angle_tolerance)
    best, at = -1.0, pose
    scales = (1.0,) if ctx.scale_known or not rescale else (1.0, RESCALE, 1.0 / RESCALE)
    for m in scales:
        q = Pose(pose.a * m, pose.b * m, pose.tx, pose.ty)
        if m != 1.0 and (not ctx.compare.pose_ok(q)
                         or ctx.compare.outside_ranges(q.scale, q.angle)):
            continue   # (a size the caller did not search is not tried)
        v = K.shift_votes(vx, vy, vang, float(q.a), float(q.b), float(q.tx),
                          float(q.ty), e.x, e.y, e.angle, ctx.features.index, int(radius), tol,
                          ctx.pattern.either)
        v = cv2.boxFilter(v, -1, (3, 3), normalize=False, borderType=cv2.BORDER_CONSTANT)
        iy, ix = np.unravel_index(int(np.argmax(v)), v.shape)
        if m == 1.0:
            best = float(v[radius, radius])
        if v[iy, ix] > best:
            best = float(v[iy, ix])
            at = Pose(q.a, q.b, q.tx + float(ix - radius), q.ty + float(iy - radius))
    return at


def _alternatives(ctx: SearchContext, c: Candidate, turns) -> list:
    """Other working-scale fits of a candidate: its own pose and the pose
    turned by each near symmetry of the pattern (:mod:`.symmetry`; a turn
    the caller did not search is not tried), each first moved by the shift
    most of its points agree on (:func:`_shifted`), then refined. The
    candidates' refinement captures within a pixel or two of where it
    starts, and a pose a few pixels off can be a local optimum that no
    refinement leaves: a rectangle with one end on a seabed edge and the
    other off its own, a board's frame found with its cells a few pixels
    off (a clean box turned by 30 degrees: a pixel off, its first
    refinement stopped there). The turned fits, and the candidate's own when
    it fits better, are returned; :func:`_best_full` judges them at full
    resolution."""
    pf, feats, cfg, f = ctx.pf, ctx.features, ctx.config, ctx.factor
    p = ctx.pattern
    s0, s1 = ctx.scale_range
    # (a line's pose slides along it, a frame's candidates are measured by
    # the motion's own checks, motion/pair.py; Config.refine False: the turns
    # are scored where they fall)
    starts = [] if p.is_line or p.is_frame or not cfg.refine else [c.fit.pose]
    for theta, cx, cy in turns:
        start = turn_pose(c.fit.pose, theta, cx * f, cy * f)
        if not ctx.compare.outside_ranges(math.sqrt(s0 * s1), start.angle):
            starts.append(start)
    radius = _capture(ctx)
    sub = _subset(ctx)
    # (refined on the subset, scored with all the points, as the candidates
    # are: candidates.find_candidates)
    kw = dict(angle_tol=math.radians(cfg.angle_tolerance), either=p.either,
              fix_scale=ctx.scale_known, fix_angle=ctx.angle_known,
              score_radius=max(1.25, cfg.match_radius * f))
    out = []
    for start in starts:
        own = start is c.fit.pose
        moved = start
        if cfg.refine:
            moved = _shifted(ctx, start, radius, sub)
            moved = refine(moved, *sub, feats.edges, feats.index, radii=(2.0, 1.5, 1.25),
                           iterations=3, **kw).pose
        work = refine(moved, pf.vx, pf.vy, pf.vangle, feats.edges, feats.index, radii=(), **kw)
        if not ctx.compare.pose_ok(work.pose):
            continue
        if not own or work.score > c.work_score:
            out.append(work)
    if p.kind == "polyline" and cfg.refine and not ctx.scale_known:
        out += _rescaled(ctx, c, radius, sub, kw)
    return out


def _rescaled(ctx: SearchContext, c: Candidate, radius: int, sub, kw) -> list:
    """A polyline's fits at other sizes (:data:`POLYLINE_RESIZE`; each moved
    by the shift its points agree on, as far as the size change moves its
    ends, and refined at that size) that fit better than the candidate. An
    open shape's size is held by few points (its strips' ends, a gate's far
    post): a drawn gate found 7 % too large, one post and the bar on it, was
    32 px off at a score of 0.77 (1.00 at its size); an L 8 px off."""
    pf, feats, p, q0 = ctx.pf, ctx.features, ctx.pattern, c.fit.pose
    step, n = POLYLINE_RESIZE
    most = max(8, 4 * int(ctx.config.search.max_radius))   # (a bound on the shift's cost)
    fixed = dict(kw, fix_scale=True)
    out = []
    for k in range(1, n + 1):
        for m in (1.0 + step * k, 1.0 / (1.0 + step * k)):
            q = Pose(q0.a * m, q0.b * m, q0.tx, q0.ty)
            if ctx.compare.outside_ranges(q.scale, q.angle):
                continue
            reach = abs(1.0 - m) * 0.5 * p.extent * q0.scale * ctx.factor   # (working px)
            r = min(max(radius, int(math.ceil(reach)) + 2), most)
            moved = _shifted(ctx, q, r, sub, rescale=False)
            moved = refine(moved, *sub, feats.edges, feats.index, radii=(2.0, 1.5, 1.25),
                           iterations=3, **fixed).pose
            work = refine(moved, pf.vx, pf.vy, pf.vangle, feats.edges, feats.index, radii=(),
                          **kw)
            if ctx.compare.pose_ok(work.pose) and work.score > c.work_score:
                out.append(work)
    return out


def _best_full(ctx: SearchContext, c: Candidate, alts, gray, where) -> None:
    """Replace the candidate's pose by an alternative (:func:`_alternatives`)
    that scores higher at full resolution (the part a turn maps onto itself
    scores alike, so the pattern's other details decide)."""
    best = None
    for work in alts:
        full = _full_res(ctx, work, gray, where)
        if full.score > (c.full.score if best is None else best[1].score):
            best = (work, full)
    if best is not None:   # (counting judged the pose it had; a twin's is the runner-up's test)
        c.fit, c.work_score, c.full, c.evidence = best[0], best[0].score, best[1], None
        if ctx.counting:
            judge(ctx, c)


# ------------------------------------------------------------------- ranking
#: The least share in view of a pose judged over its points in view
#: (:func:`seen_score`): one mostly outside is judged over all its points (a
#: 500 x 300 box's corner, 33 % in view, was a box at 0.44 of a 100 x 80 one).
SEEN_FLOOR = 0.5


def seen_score(ctx: SearchContext, fit: Fit) -> float:
    """A fit's score over the pattern points in view, ``score / inside``,
    for an object partly outside the image but at least :data:`SEEN_FLOOR`
    in view; its score otherwise, and for a frame's or a line's pattern
    (an overlap, a line's extent, measured their own way). Candidates are
    ranked, and min_score judged, by it: a marker 40 % outside scored 0.50
    (its outside points unmatched), a smaller copy turned 90 degrees in
    its seen part 0.71 and was reported (a docking trial: 6 of 12 cut
    rectangles). The chance of the points in view is the NFA's (over
    those only)."""
    if not SEEN_FLOOR <= fit.inside < 0.98 or ctx.pattern.is_frame or ctx.pattern.is_line:
        return fit.score
    return min(1.0, fit.score / fit.inside)


def rank(ctx: SearchContext, cands: list, gray: np.ndarray, min_confidence: float) -> list:
    """Refine the promising candidates at full resolution, rank them by
    that score, keep the distinct ones and rate their confidence.
    ``gray`` is the full-resolution working image: grey, or BGR when the
    search is in colour (``Config.colour``).

    Returns the detections, best first (``[]``: not found). Each candidate
    not reported says why in :attr:`~.candidates.Candidate.declined`.
    """
    cmp = ctx.compare
    best = max((c.work_score for c in cands), default=0.0)
    # only those that could win; counting (many results asked for), every one that could
    # pass min_score: a half-buried object is not judged against a clean one elsewhere
    share = 0.0 if ctx.counting else 0.6
    pre = max(0.85 * ctx.min_score, share * best)
    seen = {id(c): seen_score(ctx, c.fit) for c in cands}   # (the working scale's)
    todo = sorted((c for c in cands if seen[id(c)] >= pre), key=lambda c: -seen[id(c)])
    if ctx.counting:   # (those chance explains, judged at the working scale, go last:
        for c in todo:  # a sonar tile's speckle took every place from the rubble)
            judge(ctx, c)
        todo.sort(key=lambda c: c.evidence.nfa > ctx.max_nfa)
    todo = todo[: ctx.max_results + 2]
    for c in cands:
        c.placed = _full_pose(c.fit.pose, ctx.features)
        if seen[id(c)] < pre:   # (which bound: a user could not tell what to change)
            bound = ("0.85 x min_score" if 0.85 * ctx.min_score >= share * best
                     else "0.6 x the best candidate's")
            c.declined = (f"score {c.work_score:.3g} (coarse, before the full-resolution "
                          f"finish) under {pre:.3g} ({bound}), the least that could win")
        elif not any(c is t for t in todo):   # (counting: judged; chance's are cut first)
            c.declined = (f"NFA {c.evidence.nfa:.3g} over max_nfa {ctx.max_nfa:.3g} (coarse)"
                          if c.evidence is not None and c.evidence.nfa > ctx.max_nfa else
                          f"score {c.work_score:.3g} (coarse): {ctx.max_results + 2} "
                          "better ones were finished (max_results + 2)")
    turns = () if ctx.angle_known else ctx.pattern.near_turns(ctx.config)
    alts = [_alternatives(ctx, c, turns) for c in todo]
    wheres = (_full_edges(ctx, gray, todo, alts) if todo and ctx.factor < 0.999
              else [None] * len(todo))
    for c, alt, where in zip(todo, alts, wheres):
        c.full = _full_res(ctx, c.fit, gray, where)
        _best_full(ctx, c, alt, gray, where)
    # rank by both scores: the working scale's is smoother (less pixel
    # noise, JPEG, snow), the full resolution's sharper
    todo.sort(key=lambda c: -(seen_score(ctx, c.full) + seen_score(ctx, c.fit)))
    accepted: list[Candidate] = []
    # (a disc for a ring, a copy of a detection: no rival of either)
    other_object: list[Candidate] = []
    s0, s1 = ctx.scale_range
    for c in todo:
        if seen_score(ctx, c.full) < ctx.min_score:   # (its NFA too when over: a user lowered
            judge(ctx, c)                  # one, then met the other, on a sonar tile)
            view = seen_score(ctx, c.full)
            view = f" ({view:.3g} of its points in view)" if view != c.full.score else ""
            c.declined = f"score {c.full.score:.3g}{view} under min_score {ctx.min_score:.3g}" + (
                f"; NFA {c.nfa:.3g} over max_nfa {ctx.max_nfa:.3g} too" if c.nfa > ctx.max_nfa
                else "")
            continue
        if not cmp.pose_ok(c.full.pose):
            q = c.full.pose
            c.declined = (f"scale {q.scale:.3g} outside {0.8 * s0:.3g}-{1.25 * s1:.3g} (the "
                          "searched range and its slack)" if all(map(math.isfinite, (
                              q.scale, q.tx, q.ty))) else "its refinement diverged (no finite pose)")
            continue
        twin = next((a for a in accepted if cmp.same(c.full.pose, a.full.pose, 1.0)), None)
        if twin is not None:
            c.declined = "the same object as a better candidate"
            if _copy_of(ctx, c, twin):
                other_object.append(c)
            continue
        judge(ctx, c)  # (those that could be accepted, or left out by max_results: a little)
        if c.evidence.nfa > ctx.max_nfa:
            c.declined = f"NFA {c.evidence.nfa:.3g} over max_nfa {ctx.max_nfa:.3g}"
            continue
        if len(accepted) >= ctx.max_results:   # (chance explains none: more may be there)
            c.declined = f"max_results {ctx.max_results} reached by better candidates"
            continue
        if ctx.pattern.is_line and ctx.line_extent and _line_unseen(ctx, c, gray):
            c.declined = ("no stretch of it where both of its borders are seen (one edge, or "
                          "texture, along the band)")
            other_object.append(c)   # (no rival: not the object's kind)
            continue
        if _unseen_hole(ctx, c):
            c.declined = (f"its hole is not in the image (hole support under "
                          f"{ctx.config.search.hole_support:.3g} of the whole's)")
            other_object.append(c)
            continue
        accepted.append(c)
    # runner-up: the best candidate that is not (nearly) the same pose as a detection
    # (for a line: not the same line, found at another point along it)
    if ctx.pattern.is_line:
        same = lambda c, a: cmp.same(c.fit.pose, a.fit.pose, ctx.factor)
    else:
        same = lambda c, a: cmp.close(c.fit.pose, a.fit.pose) or cmp.equivalent(c.fit.pose, a.fit.pose)
    # (counting, one chance explains is no rival: speckle made sonar rubble ambiguous)
    chance = lambda c: ctx.counting and c.evidence is not None and c.evidence.nfa > ctx.max_nfa
    others = [c.work_score for c in cands if not chance(c)
              and not any(c is a or same(c, a) for a in accepted + other_object)]
    runner_up = max(others, default=0.0)
    dets = []
    for c in accepted:
        own = seen_score(ctx, c.fit)    # (a look-alike's own score: raw, as before)
        conf = confidence(own, runner_up)
        if conf < min_confidence:
            c.declined = (f"confidence {conf:.3g} under min_confidence {min_confidence:.3g} "
                          f"(a look-alike scores {runner_up:.3g} to its {own:.3g}, "
                          "coarse)")
            continue
        dets.append(to_detection(ctx, c, conf, gray))
    a0, a1 = ctx.angle_range
    for c in cands:   # (a declined pose in the slack past the ranges says so, as a
        q = c.pose    # detection's flag does: 0.446 of 0.5-2 read as searched, a trial)
        said = c.declined.startswith(("scale ", "the same object")) or "range searched" in c.declined
        if (c.declined and not said and all(map(math.isfinite, (q.scale, q.angle)))
                and ctx.compare.outside_ranges(q.scale, q.angle)):
            c.declined += (f"; its scale {q.scale:.3g} is outside the range searched "
                           f"({s0:.3g}-{s1:.3g})" if not s0 / 1.02 <= q.scale <= s1 * 1.02 else
                           f"; its angle {wrap_angle(q.angle):.1f} is outside the range "
                           f"searched ({a0:g}-{a1:g})")
    dets.sort(key=lambda d: -d.score)
    return dets


def _line_unseen(ctx: SearchContext, c: Candidate, gray) -> bool:
    """Whether line candidate ``c`` has no visible extent (:func:`.lines.visible_stretches`):
    no stretch where both borders of its band are edges. Such bands were 47 of 126
    false gate posts of RoboSub's tune part at the defaults (2 of 28 right ones). A
    band too thin to tell its borders apart (under 2 px) is not judged so."""
    to_detection(ctx, c, 1.0, gray)
    return c.stretches is not None and len(c.stretches) == 0


def _copy_of(ctx: SearchContext, c: Candidate, twin: Candidate) -> bool:
    """Whether ``c``, declined as the same object as the detection ``twin``,
    is a copy of it and no rival (left out of the runner-up): a disc or a
    ring at any turn (a smaller disc inside a buoy), another pattern turned
    by under 10 degrees. Not a camera frame's: its "same object" spans a
    third of the frame (a tiled floor's tile one period off is a rival), nor
    a pose turned further (the turn of a square is the ambiguity to see)."""
    p = ctx.pattern
    return not p.is_frame and (p.kind in ("circle", "ring") or abs(
        angle_difference(c.full.pose.angle, twin.full.pose.angle)) < 10.0)


def judge(ctx: SearchContext, c: Candidate) -> None:
    """Set a candidate's a-contrario :class:`~.nfa.Evidence` (at its working-
    scale pose), against a background model of the image around it."""
    pf, feats, cfg = ctx.pf, ctx.features, ctx.config
    tol = math.radians(cfg.angle_tolerance)
    radius = max(1.25, cfg.match_radius * ctx.factor)
    mx, my = c.fit.pose.map(pf.vx, pf.vy)
    m = 2 * CELL
    box = (math.floor(mx.min()) - m, math.floor(my.min()) - m,
           math.ceil(mx.max()) + m + 1, math.ceil(my.max()) + m + 1)
    bg = background(feats.edges, radius, tol, box, feats.index)
    c.evidence = evidence(c.fit.pose, pf.vx, pf.vy, pf.vangle, feats.edges, feats.index,
                          bg, search_tests(ctx), tol=tol, either=ctx.pattern.either,
                          spacing=pf.spacing)


def _unseen_hole(ctx: SearchContext, c: Candidate) -> bool:
    """Whether the candidate's pattern has a hole its image lacks (a disc
    found for a ring: :mod:`.parts`)."""
    p, pf, cfg = ctx.pattern, ctx.pf, ctx.config
    share = cfg.search.hole_support
    if share <= 0.0 or p.is_frame or p.is_line or len(p.outline) < 2:
        return False
    key = ("holes",) + p._features_key(ctx.factor, cfg)   # (once per pattern and scale)
    labels = p._cache.get_or_compute(
        key, lambda: hole_labels(p.outline, p.origin, pf.vx, pf.vy, ctx.factor))
    if labels is None:
        return False
    ids, _ = match(c.fit.pose, pf.vx, pf.vy, pf.vangle, ctx.features.edges, ctx.features.index,
                   max(1.25, cfg.match_radius * ctx.factor), math.radians(cfg.angle_tolerance),
                   p.either)
    return unseen_hole(labels, ids >= 0, share)


def to_detection(ctx: SearchContext, c: Candidate, conf: float, gray) -> Detection:
    """The :class:`Detection` of a finished candidate (``gray``: the image
    searched at full resolution), with its flags."""
    p = ctx.pattern
    pose = c.full.pose
    x, y, s, a = pose.tx, pose.ty, pose.scale, pose.angle
    kind, la, lo = "object", None, None
    if p.is_line:
        # any point of the line is as good: report the one nearest the centre
        kind = "line"
        la, lo, x, y = line_parameters(x, y, a, gray.shape)
    m = pose_to_matrix(x, y, s, a, p.origin)
    outline = [apply_matrix(m, o) for o in p.outline]
    flags = []
    if c.full.inside < 0.98:
        flags.append(FLAG_PARTIAL)
    if conf < 0.2:
        flags.append(FLAG_AMBIGUOUS)
    flags += [FLAG_ALONG_LINE] if p.is_line else []
    span = ctx.angle_range[1] - ctx.angle_range[0]    # (a narrower range rules the turn out)
    if p.kind not in ("circle", "ring") and span >= 90.0:   # (a disc: no angle to tell)
        turn = symmetry_turn(pattern_turn_shares(p, ctx.config))
        flags += {90.0: [FLAG_QUARTER_TURN], 180.0: [FLAG_HALF_TURN]}.get(turn, []) \
            if span >= turn else []
    if ctx.compare.outside_ranges(s, a):
        flags.append(FLAG_OUTSIDE_RANGE)
    elif ctx.compare.at_range_edge(s, a):
        flags.append(FLAG_RANGE_EDGE)
    det = Detection(float(x), float(y), float(s), float(a), float(c.full.score), conf,
                    m, outline, c.votes, kind, la, lo, tuple(flags), c.evidence.nfa)
    if p.is_line:   # (in a colour search's BGR image, its grey copy's; once)
        if not c.looked:   # (None: not measurable, a band under 2 px)
            c.stretches, c.looked = visible_stretches(
                gray if gray.ndim == 2 else cv2.cvtColor(np.ascontiguousarray(gray),
                                                         cv2.COLOR_BGR2GRAY), det,
                ctx.config.min_gradient), True
        st = c.stretches or []
        det.stretches, det.segment = st, (np.array([st[0][0], st[-1][1]]) if st else None)
    return det
