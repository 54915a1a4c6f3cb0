"""What a frame pair's measurement gives: :class:`Motion`, and
:class:`MotionResult` (the answer, or why there is none, and the best motion
found even when it was declined)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._values import ValueEquality

__all__ = ["Motion", "MotionResult"]


@dataclass(eq=False)
class Motion(ValueEquality):
    """Motion of the image content from the previous frame to the current one.

    Attributes
    ----------
    matrix : ndarray (2, 3)
        Previous-frame pixel (x, y) -> current-frame pixel (x, y).
    dx, dy : float
        Shift of the previous frame's centre, in current-frame pixels.
    angle : float
        Rotation in degrees (counter-clockwise as displayed), in [-180, 180).
    scale : float
        Size change (> 1: the camera came closer).
    confidence : float
        How distinct the accumulator peak was (0-1).
    score : float
        Share of the previous frame's edge points (inside the overlap) found
        again.
    overlap : float
        Share of the previous frame that is still in view.
    nfa : float
        Number of false alarms of the measurement (:attr:`seahough.Detection.nfa`):
        how many motions this well supported a search of this pair would
        find by chance; the smaller, the stronger the evidence (NaN: not
        known).
    parallax : float
        How far parts of the frame stray from the similarity (pixels): the
        seabed's relief seen from two places, or a camera that looks
        obliquely (NaN: not measured). Measured tile by tile, the median
        distance of the tiles' shifts; refitted as a homography, the RMS
        distance of the homography from the similarity over the frame.
    homography : ndarray (3, 3) or None
        Previous-frame pixel -> current-frame pixel as a homography fitted
        to the parts of the frame (a plane seen from two places; None: not
        measured).
    note : str
        Why its confidence was lowered, when it was (e.g. a look-alike of a
        repeated texture); "" otherwise.

    When the similarity alone was not confident enough and the pair was
    measured tile by tile (:mod:`seahough.motion.parallax`: a seabed in
    relief), ``confidence``, ``score`` and ``nfa`` are those of that
    measurement, with each part of the frame allowed a small shift of its
    own, and ``parallax`` is how far the parts stray from the similarity
    fitted to them. When the vote hardly preferred its answer (a tiled
    floor, a camera that looks ahead) and the pair was measured again as a
    homography, coarse to fine (:mod:`seahough.motion.pyramid`) or from the
    vote's candidates (:mod:`seahough.motion.perspective`), they are those
    of the homography (the confidence: that of the coarse vote, or of the
    candidates' homographies), the matrix is the similarity that fits it
    best over the frame, and ``homography`` is it.
    """

    matrix: np.ndarray
    dx: float
    dy: float
    angle: float
    scale: float
    confidence: float
    score: float
    overlap: float
    nfa: float = float("nan")
    parallax: float = float("nan")
    homography: np.ndarray | None = None
    note: str = ""              # why its confidence was lowered, when it was

    def to_dict(self) -> dict:
        """Plain-Python form for JSON (``nfa`` None when not known).

        >>> m = Motion(np.eye(2, 3), 1.0, 0.0, 0.0, 1.0, 0.9, 0.8, 0.95)
        >>> m.to_dict()["nfa"], Motion(np.eye(2, 3), 0, 0, 0, 1, 1, 1, 1, 1e-12).to_dict()["nfa"]
        (None, 1e-12)
        """
        return {"matrix": np.asarray(self.matrix).tolist(), "dx": self.dx, "dy": self.dy,
                "angle": self.angle, "scale": self.scale, "confidence": self.confidence,
                "score": self.score, "overlap": self.overlap,
                "nfa": float(self.nfa) if math.isfinite(self.nfa) else None,
                "parallax": float(self.parallax) if math.isfinite(self.parallax) else None,
                "homography": (None if self.homography is None
                               else np.asarray(self.homography).tolist()),
                "note": self.note}


@dataclass(eq=False)
class MotionResult:
    """What :func:`~seahough.motion.measure_motion` found in a frame pair.

    Attributes
    ----------
    motion : Motion or None
        The answer, as :func:`~seahough.estimate_motion` gives it: None when
        the motion cannot be told.
    reason : str
        Why ``motion`` is None ("" when there is one): a frame without edges
        (blank, dark, featureless), no pose of the previous frame found in
        the current one, or which of ``min_confidence``, ``min_score``,
        ``max_nfa`` the best motion missed, with its figures. A vehicle's
        fallback can act on it (e.g. hold the last velocity, or slow down).
    best : Motion or None
        The best motion the search found, also when it was declined (its
        ``confidence``, ``score``, ``nfa`` say how weak it was; do not use it
        as a measurement); None when nothing was found.
    """

    motion: Motion | None
    reason: str = ""
    best: Motion | None = None

    def __bool__(self) -> bool:
        return self.motion is not None
