"""The searches a dead-reckoning frame gets (:func:`~seahough.run_odometry`'s
steps ``prior``, ``full``, ``previous`` and ``wide``), on frames cropped to
their content box, each judged by the run's acceptance checks.

A pair that is not accepted comes back with the reason it failed:

- ``no_match``: no pose of the reference frame was found in the current
  one (no accumulator peak with enough of its edges, or its NFA over
  ``OdometryTuning.max_nfa`` when one is given; the reference has no
  edges to search for, or the prior window cut the true peak off);
- ``low_confidence``: a pose was found, but it is not distinct from its
  runner-up, or its edges in view match far worse than in the last
  measured frames (a frame of somewhere else, a fish, silt);
- ``little_overlap``: a pose was found, but too little of the reference is
  still in view to trust it;
- ``few_edges``: the reference frame or the current one has too few edges
  to be measured at all (open water, featureless sand, a frame too dark or
  washed out).

>>> sorted(REASONS)
['few_edges', 'little_overlap', 'low_confidence', 'no_match']
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import Config, OdometryTuning
from ..core.detector import MIN_SEGMENTS
from ..errors import SeahoughError
from ..geometry import (angle_difference, apply_matrix, frame_centre, matrix_to_pose,
                        overlap, shift_origin, wrap_angle)
from .pair import frame_factor, frame_features, measure_pair
from .repeats import nearest_copy
from .state import Frame

__all__ = ["Measure", "Searcher", "REASONS", "WIDEN"]

_SAME = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

#: Why a pair was not measured (the first word of a flagged row's ``flags``).
REASONS = ("no_match", "low_confidence", "little_overlap", "few_edges")
#: The last attempt before a pair is flagged (``wide``) searches this many
#: times the full search's shift region, and the per-frame ranges widened as
#: for this many times the frames of the gap.
WIDEN = 2


@dataclass
class Measure:
    """An accepted measurement of a pair (full-frame pixels)."""

    matrix: np.ndarray        # reference frame -> current frame
    confidence: float
    score: float
    overlap: float
    ref: int
    method: str
    nfa: float = float("nan")   # (judged only against OdometryTuning.max_nfa)
    #: the current frame's period (full px) when the step is known only up to
    #: it (a repeated texture: repeats.nearest_copy); 0.0 otherwise
    period: float = 0.0


class Searcher:
    """The kinds of search, on frames cropped to the content box
    (matrices in and out are in full-frame pixels)."""

    def __init__(self, box, scale_range, angle_range, cfg: Config, tuning: OdometryTuning):
        self.box = box
        self.tuning = tuning
        self.off = (float(box[0]), float(box[1]))
        shape = (box[3] - box[1], box[2] - box[0])
        self.shape = shape
        self.s_range = scale_range
        self.a_range = angle_range
        self.cfg = cfg
        # inside the small prior window one runner-up is enough to rate the peak
        self.prior_cfg = cfg.replace(n_candidates=min(cfg.n_candidates, tuning.prior_candidates))
        self.s_known = scale_range[0] == scale_range[1]
        self.a_known = angle_range[0] == angle_range[1]
        h, w = shape
        self.factor = frame_factor(shape, cfg, scale_range)
        step = (cfg.translation_bin or 6.0) / self.factor
        self.prior_radius = max(tuning.prior_radius * max(w, h), tuning.prior_bins * step)

    def crop(self, gray):
        x0, y0, x1, y1 = self.box
        return np.ascontiguousarray(gray[y0:y1, x0:x1])

    def features(self, gray):
        """Features of a cropped frame."""
        return frame_features(gray, self.cfg, self.s_range)

    def _run(self, pattern, gray, feats, s_range, a_range, region, cfg, rescue=True,
             adjacent=False):
        (s0, s1), (a0, a1) = s_range, a_range
        s_range = (max(s0, 1e-3), max(s1, s0, 1e-3))
        if s_range[1] / s_range[0] > 60:
            s_range = (s_range[0], s_range[0] * 60)
        # a search against an older keyframe gets neither the check of the
        # candidates (measure_pair's docstring) nor coarse to fine (motion/pyramid.py):
        # on the real tiled pool they measured 11 of 11 pairs, against 10, but 4
        # steps, their least-squares similarities composed with the vote's against a
        # keyframe, moved 35-60 px from the reference where they had been 10-31 px.
        # A frame searched directly without a prior gets both (``adjacent``:
        # measured as estimate_motion measures a pair; see measure())
        return measure_pair(pattern, gray, s_range, (a0, a1), region,
                            min_score=self.tuning.min_score,
                            min_confidence=self.tuning.min_confidence, config=cfg,
                            features=feats, rescue=rescue, perspective=adjacent,
                            coarse=adjacent, decline_repeats=False)

    def ranges_around(self, base, n: int, widen: int = 1):
        """Scale and angle ranges of the user's per-pair ranges, ``n`` frames
        on from the motion ``base`` (reference -> last measured frame); a
        range that is not a known quantity is widened as for ``widen`` times
        as many frames (at most ``max_span`` frames of gap count).

        >>> from seahough.config import ODOMETRY_CONFIG
        >>> s = Searcher((0, 0, 320, 240), (0.9, 1.1), (-20.0, 20.0), ODOMETRY_CONFIG,
        ...              OdometryTuning())
        >>> base = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
        >>> s.ranges_around(base, 1)
        ((0.9, 1.1), (-20.0, 20.0))
        >>> sr, ar = s.ranges_around(base, 1, widen=2)
        >>> [round(v, 2) for v in sr], ar
        ([0.81, 1.21], (-40.0, 40.0))
        >>> known = Searcher((0, 0, 320, 240), (1.0, 1.0), (5.0, 5.0), ODOMETRY_CONFIG,
        ...                  OdometryTuning())       # altitude and turn per frame known
        >>> known.ranges_around(base, 1, widen=2)   # stay known: one frame of them
        ((1.0, 1.0), (5.0, 5.0))
        """
        m = min(n, self.tuning.max_span) * widen   # known quantities go on exactly
        _, _, bs, ba = matrix_to_pose(base, frame_centre(self.shape))
        ba = wrap_angle(ba, low=-180.0)
        s0, s1 = self.s_range
        a0, a1 = self.a_range
        if self.s_known:
            sr = (bs * s0 ** n,) * 2
        else:
            sr = (bs * s0 ** m, bs * s1 ** m)
        if self.a_known:
            ar = (ba + a0 * n,) * 2
        else:
            lo, hi = ba + a0 * m, ba + a1 * m
            if hi - lo > 360:
                lo, hi = ba - 180.0, ba + 180.0
            ar = (lo, hi)
        return sr, ar

    def measure(self, ref: Frame, gray, feats, predicted, base, n: int, method: str,
                ref_rate: float | None = None, widen: int = 1, near=None):
        """Motion of ``ref`` into the current frame: ``(Measure, "")``, or
        ``(None, reason)`` (one of :data:`REASONS`).

        ``predicted``: the expected motion (prior window around it); else
        ``base`` (the motion to the last measured frame) and the user's
        ranges widened over ``n`` frames, the shift region and the ranges
        ``widen`` times the full search's. ``near``: the motion a search
        without a prior window still expects (the constant velocity's), by
        which a repeated texture's copy is chosen (default ``predicted``)."""
        pattern = ref.get_pattern(self.cfg)
        if pattern is None or len(feats.segments) < MIN_SEGMENTS:
            return None, "few_edges"
        h, w = self.shape
        c = frame_centre(self.shape)
        ox, oy = self.off
        if predicted is not None:
            predicted = shift_origin(predicted, ox, oy)
        near = predicted if near is None else shift_origin(near, ox, oy)
        if base is not None:
            base = shift_origin(base, ox, oy)
        t = self.tuning
        if predicted is not None:
            px, py, ps, pa = matrix_to_pose(predicted, c)
            pa = wrap_angle(pa, low=-180.0)
            r = self.prior_radius
            region = (px - r, py - r, px + r, py + r)
            sr = (ps,) * 2 if self.s_known else (ps / t.prior_scale, ps * t.prior_scale)
            if self.a_known:
                ar = (pa,) * 2
            else:
                ar = (pa - t.prior_angle, pa + t.prior_angle)
        else:
            bx, by = apply_matrix(base, [c])[0]
            sr, ar = self.ranges_around(base, n, widen)
            span = min(n, t.max_span) * widen
            mx, my = t.full_shift * w * span, t.full_shift * h * span
            region = (bx - mx, by - my, bx + mx, by + my)
        # a frame a frame or two apart searched directly, without a prior and
        # not through a keyframe (the first pair, the previous frame's try, the
        # last measured frame's after a one-frame gap, a wide try so near;
        # farther, the slow route costs each frame of a long gap): measured as
        # estimate_motion does, coarse to fine and the check of the candidates
        # when the vote cannot vouch for its answer. Over 40 rendered tiled floors
        # seen by a forward-oblique camera (bench/bench_oblique.py's dev part,
        # 10-frame runs) pairs measured 182 -> 354 of 360, steps within 2 % of the
        # diagonal 103 -> 322, off by more than 3 % 26 -> 20
        adjacent = (predicted is None and n <= 2 and base is not None
                    and np.allclose(base, _SAME))
        try:
            d = self._run(pattern, gray, feats, sr, ar, region,
                          self.prior_cfg if predicted is not None else self.cfg,
                          rescue=predicted is None, adjacent=adjacent)
        except SeahoughError:
            d = None
        if d is None or d.score < t.min_score or d.nfa > t.max_nfa:
            return None, "no_match"
        m = d.matrix
        ov = overlap(m, w, h)
        if d.confidence < t.min_confidence:
            return None, "low_confidence"
        if ov < t.min_overlap:
            return None, "little_overlap"
        if ref_rate is not None and d.score / max(ov, 1e-6) < t.min_relative * ref_rate:
            return None, "low_confidence"
        # a repeated texture (a net, a grating): the step is known up to its
        # period; around a prediction, the copy nearest it is taken
        d, period = nearest_copy(d, pattern, feats, self.prior_cfg if predicted is not None
                                 else self.cfg, t.min_confidence, near)
        if d is None:    # (the copy the prediction points at does not fit: no better)
            return None, "low_confidence"
        m = d.matrix
        if predicted is not None:
            # the refined pose must stay inside the prior window (else the
            # prior was wrong and the window cut the true peak off)
            x0, y0, x1, y1 = region
            slack = 0.25 * self.prior_radius
            dx, dy, _, da = d.pose(c)
            ang = angle_difference(da, pa)
            if not (x0 - slack <= dx <= x1 + slack and y0 - slack <= dy <= y1 + slack) or \
                    abs(ang) > t.prior_angle + 2.0:
                return None, "no_match"
        return Measure(shift_origin(m, -ox, -oy), float(d.confidence), float(d.score),
                       overlap(m, w, h), ref.index, method, float(d.nfa), period), ""
