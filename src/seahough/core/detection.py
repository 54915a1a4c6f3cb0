"""A detection: one instance of a pattern found in an image, its flags, and
how distinct it is from the best other candidate (its confidence). Made by
the ranking stage (:mod:`.ranking`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._values import ValueEquality

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
#: Flag when the scale or rotation lies at an end of the searched ranges
#: (within 3 % or 1 degree): the object may be larger, smaller or turned
#: further than searched, and only a part of it matched; widen the range
#: to see.
FLAG_RANGE_EDGE = "at_search_range_edge"
#: Flags when the pattern looks the same turned by a half (a rectangle, an
#: ellipse) or a quarter turn (a square): its angle is known up to that turn
#: (a controller reading 179.5 then 0.5 degrees for a half turn of 1 degree
#: should read them modulo 180). Not for discs and rings (any turn), nor
#: when the searched angle range is narrower than the turn (it rules it out).
FLAG_HALF_TURN = "same_turned_180"
FLAG_QUARTER_TURN = "same_turned_90"
#: Flag when a painted pattern searched in colour (``Config.colour`` None)
#: found nothing and its grey edges found this: its NFA (and its search's
#: candidates') counts both searches.
FLAG_GREY = "found_in_grey"


@dataclass(eq=False)
class Detection(ValueEquality):
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
        Height of the accumulator peak: votes per voting point of the
        pattern, pooled over neighbouring bins (not a share: a clear peak is
        often above 1, while ``score`` is at most 1).
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
    nfa : float
        Number of false alarms: how many poses this good the search would
        be expected to find per image by chance, in an image like this one
        holding no such object (:mod:`seahough.core.nfa`). The smaller, the
        stronger the evidence; the Detector accepts ``nfa <= max_nfa``.
        It tells an answer from chance, not from other real structure: a
        part of a larger frame, a similar prop or a tile one period on is
        not chance and can have a tiny NFA; ``confidence`` and the flag
        ``ambiguous`` are what see those (docs/nfa.md).
    pattern : str
        Which pattern this is, for a Detector of several named patterns
        (``""`` for a Detector of one pattern).
    segment : ndarray (2, 2) or None
        A line's visible extent, ``[[x0, y0], [x1, y1]]``: from the first
        stretch where the image shows both of its borders to the last
        (:mod:`.lines`; ``box`` in ``to_dict`` is the band's there), or None.
    stretches : list of ndarray (2, 2)
        A line's stretches seen, in order along it (one, or more where
        stretches of it are hidden: a pipe buried in places); their lengths
        add up to its visible length.
    """

    x: float
    y: float
    scale: float
    angle: float
    score: float
    confidence: float
    matrix: np.ndarray
    outline: list = field(default_factory=list, repr=False)   # (polylines: long)
    votes: float = 0.0
    kind: str = "object"
    line_angle: float | None = None
    line_offset: float | None = None
    flags: tuple = ()
    nfa: float = float("nan")
    pattern: str = ""
    segment: np.ndarray | None = field(default=None, repr=False)
    stretches: list = field(default_factory=list, repr=False)

    def to_dict(self) -> dict:
        """Plain-Python form for JSON; with an outline, ``box``: its bounding box
        ``[x0, y0, x1, y1]`` in image pixels (a line's: its band's along its
        ``segment``, when it has one), and ``outline``: its polylines; a
        line's ``width``, its band's in image pixels (the pattern's times its
        scale).

        >>> d = Detection(1.0, 2.0, 1.0, 0.0, 0.9, 0.8, np.eye(2, 3))
        >>> sorted(d.to_dict())[:4]
        ['angle', 'confidence', 'flags', 'kind']
        >>> d.outline = [np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 2.0]])]
        >>> d.to_dict()["box"]
        [0.0, 0.0, 4.0, 2.0]
        """
        d = {"x": self.x, "y": self.y, "scale": self.scale, "angle": self.angle,
             "score": self.score, "confidence": self.confidence,
             "matrix": np.asarray(self.matrix).tolist(), "votes": self.votes,
             "kind": self.kind, "flags": list(self.flags),
             "nfa": self.nfa if math.isfinite(self.nfa) else None, "pattern": self.pattern}
        seg = None if self.segment is None else np.asarray(self.segment, float)
        pts = np.vstack(self.outline) if self.outline else None
        width = n = None
        if self.kind == "line":
            if self.line_angle is not None:
                a = math.radians(self.line_angle)
                n = np.array([math.sin(a), math.cos(a)])
            width = None if pts is None or n is None else float(np.ptp(pts @ n))   # (px)
            d.update(line_angle=self.line_angle, line_offset=self.line_offset, width=width,
                     segment=None if seg is None else seg.round(3).tolist(),
                     stretches=[np.asarray(st, float).round(3).tolist() for st in self.stretches])
        if self.outline:
            if seg is not None and width is not None:   # (the band there: the outline's
                # length is the pattern's)
                pts = np.vstack([seg - width / 2 * n, seg + width / 2 * n])
            d["box"] = [float(v) for v in (*pts.min(axis=0), *pts.max(axis=0))]
            d["outline"] = [np.asarray(o, float).round(3).tolist() for o in self.outline]
        return d


def confidence(score: float, runner_up: float) -> float:
    """How distinct a find is from the best other candidate: of the pattern
    that the runner-up leaves unexplained, the share the find explains.

    Examples
    --------
    >>> round(confidence(1.0, 0.88), 2), round(confidence(0.55, 0.5), 2)
    (1.0, 0.1)

    A runner-up as good is no distinction, whatever the scores (scores over
    the points in view may pass 1: a copy of a net fitting at 1.008 left an
    answer at 1.009 a confidence of 1; over 1, the share of the score).

    >>> round(confidence(1.009, 1.008), 3), confidence(1.0, 1.0), confidence(0.5, 0.6)
    (0.001, 0.0, 0.0)
    """
    if not score > runner_up:
        return 0.0
    if runner_up >= 1.0:
        return 0.0 if score - runner_up < 1e-9 else float(min(1.0, (score - runner_up) / score))
    return float(np.clip((score - runner_up) / max(1.0 - runner_up, 1e-9), 0.0, 1.0))
