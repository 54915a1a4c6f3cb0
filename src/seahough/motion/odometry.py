"""Photo dead reckoning over a whole dive: the camera's path from its frames.

Each frame is measured against a *keyframe* (an earlier frame kept as the
pattern while the two still overlap well), which drifts less than chaining
every consecutive pair. The motion of the last frames predicts where the
keyframe lies in the next one, so the search is narrowed to a small window of
position, rotation and scale around that prediction (the fast path); when
that fails, the full search against the keyframe, then against the previous
frame, takes over. A pair that still cannot be measured is flagged, never
silently invented.

>>> from seahough.odometry import run_odometry          # doctest: +SKIP
>>> result = run_odometry("dive/frames", "track", altitude=2.5, focal_px=800)  # doctest: +SKIP
>>> result.summary["path_length_m"]                      # doctest: +SKIP

Conventions
-----------
- Pixel (0, 0) is the centre of the top-left pixel, x right, y down.
- "Frame 0" is the first readable frame (the origin of the trajectory).
- A frame's cumulative matrix (CSV column ``matrix``) maps frame-0 pixels to
  that frame's pixels; a pair matrix (``pair_matrix``) maps the previous
  frame's pixels to the current frame's (as :attr:`seahough.Motion.matrix`).
- ``x, y``: where the frame's centre lies in frame-0 pixels (frame 0 itself
  is at its own centre); ``x_m, y_m``: metres from frame 0's centre along
  the same axes (``(x - x_0, y - y_0)`` times metres per pixel).
- ``heading``: degrees, 0 for frame 0, counter-clockwise as displayed
  (the direction of the frame's "up" in frame-0 pixels), unwrapped (a full
  loop ends near +-360); ``scale``: size of the ground in the frame relative
  to frame 0 (> 1: the camera is closer to the bottom than at frame 0).
"""

from __future__ import annotations

import calendar
import cmath
import csv
import dataclasses
import json
import math
import os
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from .._validate import number, pair
from ..core.accumulator import check_ranges
from ..config import Config
from ..core.detector import Detector
from ..errors import ImageError, ParameterError, SeahoughError
from ..core.features import extract_features
from ..geometry import angle_difference, apply_matrix, compose, invert_matrix, matrix_to_pose
from ..io.images import read_image, to_gray
from .pair import MOTION_CONFIG, content_box
from ..core.pattern import Pattern
from ..core.preprocess import choose_factor

__all__ = ["run_odometry", "list_frames", "read_odometry_csv", "time_from_name", "OdometryResult",
           "ODOMETRY_CONFIG", "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS"]

#: Search configuration used unless ``config`` is given: the motion
#: configuration with the pattern-point counts of the default Config (fewer
#: than estimate_motion's: a keyframe is searched many times, from a
#: prediction), and its seven accumulator peaks per full search (two in the
#: small prior window). Three peaks per full search
#: accepted tile-shifted look-alikes on the tiled pool sequence (40 px jumps
#: at confidence 0.28-0.32) that seven flag as low confidence.
ODOMETRY_CONFIG = MOTION_CONFIG.replace(n_pattern_points=128, n_verify_points=400)

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm", ".ppm", ".pnm",
                    ".webp", ".jp2")
VIDEO_EXTENSIONS = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".wmv", ".webm",
                    ".mts", ".ts", ".3gp")

# ---- tuning of the sequence logic (documented in run_odometry) ----
_MIN_CONFIDENCE = 0.2       # below: the pair is not measured ("low_confidence")
_MIN_RELATIVE = 0.4         # ... nor when its edges match less than this share as well as
                            # in the last measured frames (median of up to 5; a frame of
                            # somewhere else, a fish, a cloud of silt)
_MIN_SCORE = 0.2            # share of the keyframe's edges found again
_MIN_OVERLAP = 0.15         # share of the reference frame still in view
_REKEY_OVERLAP = 0.6        # next frame predicted to overlap the keyframe less: re-keyframe
_REKEY_MATCH = 0.6          # ... or its edges in view are found less than this share as
                            # often as in the first frame measured against it (looks changed)
_PRIOR_RADIUS = 0.05        # prior window half-size, share of the frame's longer side ...
_PRIOR_BINS = 3             # ... and at least this many translation bins
_PRIOR_ANGLE = 4.0          # prior rotation window, +- degrees
_PRIOR_SCALE = 1.03         # prior scale window, x/÷
_PRIOR_CANDIDATES = 2       # accumulator peaks examined in the prior window
_FULL_SHIFT = 0.5           # full search: +- this share of the frame around the last position
_MAX_SPAN = 3               # ... and the ranges widened for at most this many frames of gap
_DOUBTFUL = 0.35            # a keyframe measurement less confident than this is checked
                            # against the last measured frame (nearer in time) ...
_AGREE_PX = 2.0             # ... which replaces it when they differ by more than this many
                            # working px at the frame's corners (beyond the noise of a
                            # measurement) and it is more confident

_CSV_BASE = ["index", "file", "time", "x", "y", "heading", "scale", "confidence", "flags"]
_CSV_METRIC = ["x_m", "y_m"]
_CSV_MORE = ["dx", "dy", "rotation", "scale_change", "score", "overlap", "ref", "method",
             "status", "ms", "matrix", "pair_matrix"]

_IDENTITY = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


# ============================================================================ result
class OdometryResult:
    """What :func:`run_odometry` produced.

    Attributes
    ----------
    rows : list of dict
        One per frame, the CSV's columns with Python values (None = empty):
        ``index, file, time, x, y, heading, scale, confidence, flags``
        (``x_m, y_m`` when metric), and ``dx, dy, rotation, scale_change``
        (motion from the previous frame: shift of its centre in current-frame
        pixels, degrees counter-clockwise as displayed, size change),
        ``score, overlap`` (of the measurement), ``ref`` (index of the frame
        it was measured against), ``method`` (``"prior"``, ``"full"``,
        ``"previous"``: see :func:`run_odometry`'s notes), ``status``
        (``"origin"``, ``"measured"``, ``"assumed"``, ``"unreadable"``),
        ``ms``, ``matrix`` and
        ``pair_matrix`` (2x3 as 6 floats, row-major). The run does not keep
        the rows in memory (a survey of 100,000 photos would hold about
        250 MB of them): they are read from ``csv_path`` by
        :func:`read_odometry_csv` when first asked for, then kept.
    summary : dict
        The content of ``summary.json``.
    csv_path, json_path : Path
    mosaic_path, trajectory_path : Path or None
    """

    def __init__(self, rows, summary, csv_path, json_path, mosaic_path=None,
                 trajectory_path=None):
        self._rows = None if rows is None else list(rows)
        self.summary = summary
        self.csv_path = Path(csv_path)
        self.json_path = Path(json_path)
        self.mosaic_path = mosaic_path
        self.trajectory_path = trajectory_path

    @property
    def rows(self) -> list:
        if self._rows is None:
            self._rows = read_odometry_csv(self.csv_path)
        return self._rows

    def iter_rows(self):
        """The rows one at a time, from the CSV unless already loaded (for
        runs too long to hold every row)."""
        return iter(self._rows) if self._rows is not None else _iter_odometry_csv(self.csv_path)

    def __repr__(self):
        return (f"OdometryResult(frames={self.summary.get('frames')}, csv_path={self.csv_path!r}, "
                f"mosaic_path={self.mosaic_path!r}, trajectory_path={self.trajectory_path!r})")


# ===================================================================== frame lists
def _natural_key(s: str):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


_DATETIME = re.compile(r"(?<!\d)(\d{4})[-_]?(\d{2})[-_]?(\d{2})[T_\- ]?(\d{2})[-_:h]?(\d{2})"
                       r"[-_:m]?(\d{2})(?:[.,](\d+))?(?!\d)")
_EPOCH = re.compile(r"(?<!\d)(1\d{9})(?:[._](\d{1,9}))?(?!\d)"
                    r"|(?<!\d)(1\d{12}|1\d{15}|1\d{18})(?!\d)")
_CLOCK = re.compile(r"(?<!\d)(\d{2})[-_:h](\d{2})[-_:m](\d{2})(?:[.,](\d+))?(?!\d)")


def time_from_name(name: str) -> float | None:
    """Seconds from a timestamp in a file name, or None.

    Understood: date and time (``20130701_134008.633``, ``2013-07-01T13-40-08``;
    seconds since 1970, UTC), Unix time (``1372687208.633``, 13/16/19-digit
    milli/micro/nanoseconds), and a time of day (``00_00_21.000``,
    ``13-40-08``; seconds since midnight). A plain frame number is not a time.

    Examples
    --------
    >>> time_from_name("frame_00_00_21.500.jpg")
    21.5
    >>> time_from_name("1372687208.6337876.png")
    1372687208.6337876
    >>> time_from_name("frame_000123.png") is None
    True
    """
    stem = Path(name).name
    for ext in (*IMAGE_EXTENSIONS, *VIDEO_EXTENSIONS):
        if stem.lower().endswith(ext):
            stem = stem[: -len(ext)]
            break
    m = _DATETIME.search(stem)
    if m:
        y, mo, d, hh, mi, ss = (int(v) for v in m.groups()[:6])
        if 1970 <= y <= 2100 and 1 <= mo <= 12 and 1 <= d <= 31 and hh < 24 and mi < 60 and ss < 61:
            frac = float("0." + m.group(7)) if m.group(7) else 0.0
            return calendar.timegm((y, mo, d, hh, mi, ss, 0, 0, 0)) + frac
    m = _EPOCH.search(stem)
    if m:
        if m.group(1):
            return float(m.group(1) + ("." + m.group(2) if m.group(2) else ""))
        digits = m.group(3)
        return int(digits) / 10.0 ** (len(digits) - 10)
    m = _CLOCK.search(stem)
    if m:
        hh, mi, ss = (int(v) for v in m.groups()[:3])
        if hh < 24 and mi < 60 and ss < 61:
            frac = float("0." + m.group(4)) if m.group(4) else 0.0
            return hh * 3600.0 + mi * 60.0 + ss + frac
    return None


def _is_video(p: Path) -> bool:
    return p.suffix.lower() in VIDEO_EXTENSIONS


def _split_video_ref(s: str):
    """``("video.mp4", 12)`` for ``"video.mp4#12"``, else None."""
    m = re.match(r"^(.*)#(\d+)$", s)
    if m and _is_video(Path(m.group(1))):
        return m.group(1), int(m.group(2))
    return None


def _video_frames(path: Path) -> list[str]:
    cap = cv2.VideoCapture(os.fspath(path))
    if not cap.isOpened():
        raise ParameterError(f"{path}: cannot open the video")
    try:
        n = 0
        while cap.grab():
            n += 1
    finally:
        cap.release()
    if n == 0:
        raise ParameterError(f"{path}: the video holds no frame OpenCV can decode")
    return [f"{path}#{i}" for i in range(n)]


def list_frames(frames) -> list:
    """The frames of ``frames`` in order, as a list.

    Parameters
    ----------
    frames : path, or list of paths (or arrays)
        A folder (its images, sorted by the timestamp in their names when
        every name carries one, else in natural name order: ``f2`` before
        ``f10``), a video file (one entry ``"video.mp4#<i>"`` per frame),
        or a list of image paths kept in the given order. A list of one
        folder is read as that folder; each video in a list is replaced
        by its frames, in place (several videos: one after the other, in
        the order given). Arrays in a list are taken as frames as they are.

    Raises
    ------
    ParameterError
        No such file or folder, an empty folder, an unreadable video.
    """
    if isinstance(frames, np.ndarray):
        raise ParameterError("frames: give a folder, a video or a list of image paths "
                             "(a single array is not a sequence)")
    if isinstance(frames, (str, os.PathLike)):
        items = [frames]
    else:
        try:
            items = list(frames)
        except TypeError:
            raise ParameterError(f"frames={frames!r}: expected a folder, a video or a "
                                 "list of image paths") from None
    if len(items) == 1 and isinstance(items[0], (str, os.PathLike)):
        p = Path(items[0])
        if p.is_dir():
            files = [f for f in p.iterdir() if f.is_file() and not f.name.startswith(".")
                     and f.suffix.lower() in IMAGE_EXTENSIONS]
            if not files:
                raise ParameterError(f"{p}: no image files ({', '.join(IMAGE_EXTENSIONS)}) "
                                     "in this folder")
            times = [time_from_name(f.name) for f in files]
            if all(t is not None for t in times):
                order = sorted(range(len(files)),
                               key=lambda i: (times[i], _natural_key(files[i].name)))
            else:
                order = sorted(range(len(files)), key=lambda i: _natural_key(files[i].name))
            return [str(files[i]) for i in order]
        if p.is_file() and _is_video(p):
            return _video_frames(p)
    out = []
    for it in items:
        if isinstance(it, np.ndarray):
            out.append(it)
        elif isinstance(it, (str, os.PathLike)):
            s = os.fspath(it)
            if Path(s).is_dir():
                raise ParameterError(f"{s}: a folder inside a list of frames; give the "
                                     "folder alone")
            if not Path(s).exists() and _split_video_ref(s) is None:
                raise ParameterError(f"{s}: no such file")
            if _is_video(Path(s)) and Path(s).is_file():
                out.extend(_video_frames(Path(s)))   # each video of a list: its frames
            else:
                out.append(s)
        else:
            raise ParameterError(f"frames: unexpected item {type(it).__name__}; expected paths")
    if not out:
        raise ParameterError("frames: the list is empty")
    return out


class _Reader:
    """Reads the listed frames by index (videos sequentially, reopened when
    asked for an earlier frame)."""

    def __init__(self, items: list, max_pixels: int):
        self.items = items
        self.max_pixels = max_pixels
        self._cap = None
        self._cap_path = None
        self._cap_next = 0
        self._fps = {}

    def name(self, i: int) -> str:
        it = self.items[i]
        return f"frame_{i:05d}" if isinstance(it, np.ndarray) else str(it)

    def time(self, i: int) -> float | None:
        it = self.items[i]
        if isinstance(it, np.ndarray):
            return None
        ref = _split_video_ref(str(it))
        if ref is not None:
            fps = self._video_fps(ref[0])
            return ref[1] / fps if fps > 0 else None
        return time_from_name(str(it))

    def _video_fps(self, path: str) -> float:
        if path not in self._fps:
            cap = cv2.VideoCapture(path)
            self._fps[path] = float(cap.get(cv2.CAP_PROP_FPS) or 0.0) if cap.isOpened() else 0.0
            cap.release()
        return self._fps[path]

    def raw(self, i: int) -> np.ndarray:
        """The frame as stored (any depth/channels); raises ImageError."""
        it = self.items[i]
        if isinstance(it, np.ndarray):
            return it
        ref = _split_video_ref(str(it))
        if ref is None:
            return read_image(it, max_pixels=self.max_pixels)
        path, k = ref
        if self._cap is None or self._cap_path != path or k < self._cap_next:
            self.close()
            self._cap = cv2.VideoCapture(path)
            self._cap_path, self._cap_next = path, 0
            if not self._cap.isOpened():
                raise ImageError(f"{path}: cannot open the video")
        while self._cap_next < k:
            if not self._cap.grab():
                raise ImageError(f"{path}: frame {k} is past the end of the video")
            self._cap_next += 1
        ok, img = self._cap.read()
        self._cap_next += 1
        if not ok or img is None:
            raise ImageError(f"{path}: cannot decode frame {k}")
        return img

    def close(self):
        if self._cap is not None:
            self._cap.release()
        self._cap = None


# ================================================================ similarity maths
def _to_c(m) -> tuple[complex, complex]:
    """A 2x3 similarity as ``z -> a z + b`` on ``z = x + i y``."""
    m = np.asarray(m, float)
    return complex(m[0, 0], m[1, 0]), complex(m[0, 2], m[1, 2])


def _from_c(a: complex, b: complex) -> np.ndarray:
    return np.array([[a.real, -a.imag, b.real], [a.imag, a.real, b.imag]])


def _power(m, t: float) -> np.ndarray:
    """The similarity ``m`` applied ``t`` times (any real ``t``: roots too)."""
    a, b = _to_c(m)
    if t == 1:
        return _from_c(a, b)
    at = cmath.exp(t * cmath.log(a)) if a != 0 else 0j
    if abs(a - 1) < 1e-12:
        bt = b * t
    else:
        bt = b * (1 - at) / (1 - a)
    return _from_c(at, bt)


def _similar(m) -> np.ndarray:
    """The nearest similarity to a 2x3 matrix (kills rounding asymmetry)."""
    m = np.asarray(m, float)
    a, b = 0.5 * (m[0, 0] + m[1, 1]), 0.5 * (m[1, 0] - m[0, 1])
    return np.array([[a, -b, m[0, 2]], [b, a, m[1, 2]]])


def _overlap(m, w: int, h: int, n: int = 24) -> float:
    """Share of a frame that ``m`` maps inside an equally sized frame."""
    xs, ys = np.meshgrid(np.linspace(0, w - 1, n), np.linspace(0, h - 1, n))
    p = apply_matrix(m, np.stack([xs.ravel(), ys.ravel()], 1))
    return float(np.mean((p[:, 0] >= 0) & (p[:, 1] >= 0) & (p[:, 0] <= w - 1) & (p[:, 1] <= h - 1)))


def _shift(m, ox: float, oy: float) -> np.ndarray:
    """``m`` seen in coordinates shifted by (ox, oy): T(-o) m T(o)."""
    m = np.array(m, float)
    t = m[:, :2] @ np.array([ox, oy]) + m[:, 2] - np.array([ox, oy])
    return np.hstack([m[:, :2], t[:, None]])


def _mat_str(m) -> str:
    return " ".join(repr(float(v)) for v in np.asarray(m, float).ravel())


def _mat_parse(s) -> np.ndarray | None:
    if s is None or s == "":
        return None
    v = [float(t) for t in str(s).split()]
    if len(v) != 6:
        raise ValueError(f"expected 6 numbers, got {len(v)}")
    return np.array(v, float).reshape(2, 3)


# ============================================================================ state
@dataclass
class _State:
    """Everything the next frame needs, rebuilt from the rows alone (resume)."""

    shape: tuple | None = None          # (h, w) of the first readable frame
    box: tuple | None = None            # its content box (see motion.content_box)
    key: int | None = None              # keyframe index and its cumulative matrix
    key_cum: np.ndarray | None = None
    key_rate: float | None = None       # score / overlap of the first frame measured on it
    prev: int | None = None             # last readable frame with a pose
    prev_cum: np.ndarray | None = None
    meas: int | None = None             # last measured frame (for the prediction)
    meas_cum: np.ndarray | None = None
    vel: np.ndarray | None = None       # motion per frame (frame-to-frame matrix)
    last_pose: int | None = None        # last row with a pose, and whether measured
    last_pose_cum: np.ndarray | None = None
    last_pose_measured: bool = False
    heading: float = 0.0                # unwrapped heading of the last pose
    rates: list = field(default_factory=list)   # score/overlap of the last measurements


def _centre(shape) -> np.ndarray:
    h, w = shape
    return np.array([(w - 1) / 2.0, (h - 1) / 2.0])


def _advance(st: _State, row: dict) -> None:
    """Update the state with one finished row (the same in a run and a resume)."""
    status = row["status"]
    i = row["index"]
    if status == "unreadable":
        return
    cum = row["_cum"]
    if status == "origin":
        st.key = st.prev = st.meas = st.last_pose = i
        st.key_cum = st.prev_cum = st.meas_cum = st.last_pose_cum = cum
        st.key_rate = None
        st.rates = []
        st.vel = None
        st.last_pose_measured = True
        return
    if status == "assumed":
        st.rates = []   # after a failure, no reference quality (a new scene is allowed)
        st.prev, st.prev_cum = i, cum
        st.last_pose, st.last_pose_cum, st.last_pose_measured = i, cum, False
        return
    # measured
    ref = row["ref"]
    ref_cum = _ref_cum(st, ref)
    if st.last_pose_measured and st.last_pose is not None:
        st.vel = _power(compose(cum, invert_matrix(st.last_pose_cum)), 1.0 / (i - st.last_pose))
    else:
        st.vel = _power(compose(cum, invert_matrix(ref_cum)), 1.0 / max(i - ref, 1))
    if ref != st.key:
        st.key, st.key_cum, st.key_rate = ref, ref_cum, None
    rate = row["score"] / max(row["overlap"], 1e-6)
    st.rates = (st.rates + [rate])[-5:]
    if st.key_rate is None:
        st.key_rate = rate
    h, w = st.shape
    nxt = compose(st.vel, cum)
    faded = rate < _REKEY_MATCH * st.key_rate
    if faded or _overlap(compose(nxt, invert_matrix(st.key_cum)), w, h) < _REKEY_OVERLAP:
        st.key, st.key_cum, st.key_rate = i, cum, None
    st.prev, st.prev_cum = i, cum
    st.meas, st.meas_cum = i, cum
    st.last_pose, st.last_pose_cum, st.last_pose_measured = i, cum, True


# ====================================================================== the search
@dataclass
class _Measure:
    matrix: np.ndarray        # reference frame -> current frame
    confidence: float
    score: float
    overlap: float
    ref: int
    method: str


@dataclass
class _Frame:
    """A readable frame kept in memory: its grey image and, once needed, its
    pattern (built once, reused while it is the keyframe)."""

    index: int
    gray: np.ndarray
    pattern: Pattern | None = None
    failed: bool = False

    def get_pattern(self, config: Config):
        if self.pattern is None and not self.failed:
            try:
                self.pattern = Pattern.from_frame(self.gray, config=config)
            except SeahoughError:
                self.failed = True
        return self.pattern


class _Searcher:
    """The three kinds of search, on frames cropped to the content box
    (matrices in and out are in full-frame pixels)."""

    def __init__(self, box, scale_range, angle_range, cfg: Config):
        self.box = box
        self.off = (float(box[0]), float(box[1]))
        shape = (box[3] - box[1], box[2] - box[0])
        self.shape = shape
        self.s_range = scale_range
        self.a_range = angle_range
        self.cfg = cfg
        # inside the small prior window one runner-up is enough to rate the peak
        self.prior_cfg = cfg.replace(n_candidates=min(cfg.n_candidates, _PRIOR_CANDIDATES))
        self.s_known = scale_range[0] == scale_range[1]
        self.a_known = angle_range[0] == angle_range[1]
        h, w = shape
        self.factor = choose_factor(shape, cfg, math.hypot(w, h), min(scale_range[0], 1.0))
        step = (cfg.translation_bin or 6.0) / self.factor
        self.prior_radius = max(_PRIOR_RADIUS * max(w, h), _PRIOR_BINS * step)

    def crop(self, gray):
        x0, y0, x1, y1 = self.box
        return np.ascontiguousarray(gray[y0:y1, x0:x1])

    def features(self, gray):
        """Features of a cropped frame."""
        return extract_features(gray, self.factor, self.cfg)

    def _run(self, pattern, gray, feats, s_range, a_range, region, cfg):
        (s0, s1), (a0, a1) = s_range, a_range
        s_range = (max(s0, 1e-3), max(s1, s0, 1e-3))
        if s_range[1] / s_range[0] > 60:
            s_range = (s_range[0], s_range[0] * 60)
        det = Detector(pattern, s_range, (a0, a1), config=cfg, max_results=1,
                       min_score=_MIN_SCORE, min_confidence=0.0, search_region=region)
        res = det.search(gray, features=feats)
        return res.detections[0] if res.detections else None

    def _ranges_around(self, base, n: int):
        """Scale and angle ranges of the user's per-pair ranges, ``n`` frames
        on from the motion ``base`` (reference -> last measured frame)."""
        m = min(n, _MAX_SPAN)      # known quantities go on exactly, ranges widen at most m
        _, _, bs, ba = matrix_to_pose(base, _centre(self.shape))
        ba = (ba + 180.0) % 360.0 - 180.0
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

    def measure(self, ref: _Frame, gray, feats, predicted, base, n: int, method: str,
                ref_rate: float | None = None):
        """Motion of ``ref`` into the current frame, or (None, reason).

        ``predicted``: the expected motion (prior window around it); else
        ``base`` (the motion to the last measured frame) and the user's
        ranges widened over ``n`` frames."""
        pattern = ref.get_pattern(self.cfg)
        if pattern is None:
            return None, "no_motion"
        h, w = self.shape
        c = _centre(self.shape)
        ox, oy = self.off
        if predicted is not None:
            predicted = _shift(predicted, ox, oy)
        if base is not None:
            base = _shift(base, ox, oy)
        if predicted is not None:
            px, py, ps, pa = matrix_to_pose(predicted, c)
            pa = (pa + 180.0) % 360.0 - 180.0
            r = self.prior_radius
            region = (px - r, py - r, px + r, py + r)
            sr = (ps,) * 2 if self.s_known else (ps / _PRIOR_SCALE, ps * _PRIOR_SCALE)
            if self.a_known:
                ar = (pa,) * 2
            else:
                ar = (pa - _PRIOR_ANGLE, pa + _PRIOR_ANGLE)
        else:
            bx, by = apply_matrix(base, [c])[0]
            sr, ar = self._ranges_around(base, n)
            span = min(n, _MAX_SPAN)
            mx, my = _FULL_SHIFT * w * span, _FULL_SHIFT * h * span
            region = (bx - mx, by - my, bx + mx, by + my)
        try:
            d = self._run(pattern, gray, feats, sr, ar, region,
                          self.prior_cfg if predicted is not None else self.cfg)
        except SeahoughError:
            d = None
        if d is None:
            return None, "no_motion"
        m = _similar(d.matrix)
        ov = _overlap(m, w, h)
        if d.confidence < _MIN_CONFIDENCE:
            return None, "low_confidence"
        if ov < _MIN_OVERLAP:
            return None, "little_overlap"
        if ref_rate is not None and d.score / max(ov, 1e-6) < _MIN_RELATIVE * ref_rate:
            return None, "low_confidence"
        if predicted is not None:
            # the refined pose must stay inside the prior window (else the
            # prior was wrong and the window cut the true peak off)
            x0, y0, x1, y1 = region
            slack = 0.25 * self.prior_radius
            ang = angle_difference(d.angle, pa)
            if not (x0 - slack <= d.x <= x1 + slack and y0 - slack <= d.y <= y1 + slack) or \
                    abs(ang) > _PRIOR_ANGLE + 2.0:
                return None, "no_motion"
        return _Measure(_shift(m, -ox, -oy), float(d.confidence), float(d.score), ov, ref.index,
                        method), ""


# ====================================================================== CSV & rows
def _fmt(v, digits=None) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        if not math.isfinite(v):
            return ""
        v = float(v)        # a numpy float's repr is "np.float64(...)"
        return repr(v) if digits is None else f"{v:.{digits}f}"
    return str(v)


def _row_to_csv(row: dict, columns) -> dict:
    out = {}
    for k in columns:
        v = row.get(k)
        if k in ("matrix", "pair_matrix"):
            out[k] = "" if v is None else _mat_str(np.asarray(v).reshape(2, 3))
        elif k in ("x", "y", "x_m", "y_m", "heading", "scale", "dx", "dy", "rotation",
                   "scale_change", "confidence", "score", "overlap", "time"):
            out[k] = _fmt(v)
        elif k == "ms":
            out[k] = _fmt(v, 2)
        else:
            out[k] = _fmt(v)
    return out


_FLOAT_COLS = ("time", "x", "y", "x_m", "y_m", "heading", "scale", "confidence", "dx", "dy",
               "rotation", "scale_change", "score", "overlap", "ms")


def read_odometry_csv(path) -> list:
    """Rows of an ``odometry.csv`` with Python values (as :attr:`OdometryResult.rows`).

    A last line cut short (the run was killed while writing it) is dropped.
    """
    return list(_iter_odometry_csv(path))


def _iter_odometry_csv(path):
    """The rows of :func:`read_odometry_csv` one at a time (the file is not read whole)."""
    with open(path, newline="") as f:
        def complete_lines():
            for line in f:
                if not line.endswith("\n"):
                    return          # the last row was cut short
                yield line

        for rec in csv.DictReader(complete_lines()):
            try:
                row = {"index": int(rec["index"]), "file": rec["file"]}
                for k in _FLOAT_COLS:
                    if k in rec:
                        row[k] = float(rec[k]) if rec[k] not in ("", None) else None
                row["flags"] = rec.get("flags") or ""
                row["ref"] = int(rec["ref"]) if rec.get("ref") else None
                row["method"] = rec.get("method") or ""
                row["status"] = rec["status"]
                if row["status"] not in ("origin", "measured", "assumed", "unreadable"):
                    raise ValueError(row["status"])
                m = _mat_parse(rec.get("matrix"))
                row["matrix"] = None if m is None else m.ravel().tolist()
                pm = _mat_parse(rec.get("pair_matrix"))
                row["pair_matrix"] = None if pm is None else pm.ravel().tolist()
                if row["status"] != "unreadable" and m is None:
                    raise ValueError("no matrix")
            except (KeyError, ValueError, TypeError, AttributeError):
                return  # a truncated or foreign line: stop here
            yield row


def _closing_enumerate(gen):
    """enumerate(gen), closing the generator (its file) however the loop ends."""
    try:
        yield from enumerate(gen)
    finally:
        gen.close()


def _pose_fields(cum, shape, heading_prev):
    """x, y, heading (unwrapped near ``heading_prev``), scale of a cumulative matrix."""
    inv = invert_matrix(cum)
    x, y = apply_matrix(inv, [_centre(shape)])[0]
    up = inv[:, :2] @ np.array([0.0, -1.0])
    hd = math.degrees(math.atan2(-up[0], -up[1]))
    hd = heading_prev + angle_difference(hd, heading_prev)
    _, _, s, _ = matrix_to_pose(cum)
    return float(x), float(y), float(hd), float(s)


# ===================================================================== the mosaic
def _as_bgr8(img: np.ndarray) -> np.ndarray:
    a = np.asarray(img)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.dtype == np.uint16:
        a = (a.astype(np.float32) / 257.0)
    if a.dtype != np.uint8:
        a = a.astype(np.float32)
        if a.size and np.nanmax(a) <= 1.0:
            a = a * 255.0
        a = np.clip(np.nan_to_num(a), 0, 255).astype(np.uint8)
    if a.ndim == 2:
        a = cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    elif a.shape[2] == 4:
        a = cv2.cvtColor(a, cv2.COLOR_BGRA2BGR)
    return a


def _posed(csv_path):
    """(index, inverse cumulative matrix) of the frames with a measured pose, from the CSV.

    Frames whose pose is only assumed (a gap) are left out: their place is a guess."""
    for r in _iter_odometry_csv(csv_path):
        if r.get("matrix") is not None and r["status"] in ("origin", "measured"):
            yield r["index"], invert_matrix(np.asarray(r["matrix"]).reshape(2, 3))


def _build_mosaic(csv_path, reader: _Reader, shape, path: Path, max_side: int = 4000):
    """Frames placed by the trajectory on one canvas (frame-0 pixels).

    Each canvas pixel comes from the frame that saw it nearest to that
    frame's centre (sharp, no double images, little vignetting seam).
    Memory does not grow with the number of frames: the canvas is at most
    ``max_side`` pixels on its longer side (frames are shrunk to fit), the
    poses are read from the CSV twice (extent, then placing) and the frames
    one at a time."""
    h, w = shape
    corners = np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]])
    x0 = y0 = math.inf
    x1 = y1 = -math.inf
    for _, inv in _posed(csv_path):
        q = apply_matrix(inv, corners)
        x0, y0 = min(x0, q[:, 0].min()), min(y0, q[:, 1].min())
        x1, y1 = max(x1, q[:, 0].max()), max(y1, q[:, 1].max())
    if not math.isfinite(x0):
        return None
    span = max(x1 - x0, y1 - y0, 1.0)
    f = min(1.0, max_side / span)
    cw = int(math.ceil((x1 - x0) * f)) + 1
    ch = int(math.ceil((y1 - y0) * f)) + 1
    place = np.array([[f, 0, -x0 * f - 0.5 * (1 - f)], [0, f, -y0 * f - 0.5 * (1 - f)]])
    canvas = np.zeros((ch, cw, 3), np.uint8)
    best = np.full((ch, cw), np.inf, np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    c = _centre(shape)
    dist = (((xx - c[0]) / w) ** 2 + ((yy - c[1]) / h) ** 2).astype(np.float32) + 1.0  # >= 1
    for index, inv in _posed(csv_path):
        try:
            img = _as_bgr8(reader.raw(index))
        except (ImageError, OSError):
            continue
        if img.shape[:2] != (h, w):
            continue
        m = compose(place, inv)
        fp = apply_matrix(m, corners)
        bx0 = max(int(math.floor(fp[:, 0].min())) - 1, 0)
        by0 = max(int(math.floor(fp[:, 1].min())) - 1, 0)
        bx1 = min(int(math.ceil(fp[:, 0].max())) + 2, cw)
        by1 = min(int(math.ceil(fp[:, 1].max())) + 2, ch)
        if bx1 <= bx0 or by1 <= by0:
            continue
        mm = m.copy()
        mm[:, 2] -= (bx0, by0)
        size = (bx1 - bx0, by1 - by0)
        interp = cv2.INTER_AREA if f < 0.999 else cv2.INTER_LINEAR
        warped = cv2.warpAffine(img, mm, size, flags=cv2.INTER_LINEAR if f >= 0.5 else interp,
                                borderMode=cv2.BORDER_CONSTANT)
        d = cv2.warpAffine(dist, mm, size, flags=cv2.INTER_NEAREST,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        # 0 outside the frame; stay a pixel away from its border
        valid = cv2.erode((d > 0).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        sub_best = best[by0:by1, bx0:bx1]
        take = valid & (d < sub_best)
        canvas[by0:by1, bx0:bx1][take] = warped[take]
        sub_best[take] = d[take]
    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(os.fspath(path), canvas):
        raise OSError(f"{path}: cannot write the mosaic")
    return path


def _plot_trajectory(csv_path, path: Path, metric: bool):
    """The trajectory picture: seahough.plot when available, else a minimal one.

    Only the columns drawn are read back from the CSV (x, y, heading, flags)."""
    kx, ky = ("x_m", "y_m") if metric else ("x", "y")
    plot_rows = [{"x": r.get(kx), "y": r.get(ky), "heading": r.get("heading"),
                  "flags": r.get("flags")} for r in _iter_odometry_csv(csv_path)]
    unit = "m" if metric else "px"
    try:
        from ..viz import plot_trajectory
    except ImportError:
        plot_trajectory = None
    if plot_trajectory is not None:
        plot_trajectory(plot_rows, path, unit=unit)
        return path
    from matplotlib.figure import Figure  # pragma: no cover - fallback
    fig = Figure(figsize=(8, 7), dpi=100)
    ax = fig.add_subplot(111)
    xs = [r["x"] if r.get("x") is not None else np.nan for r in plot_rows]
    ys = [r["y"] if r.get("y") is not None else np.nan for r in plot_rows]
    ax.plot(xs, ys, "-o", ms=3)
    bad = [(x, y) for x, y, r in zip(xs, ys, plot_rows) if r.get("flags")]
    if bad:
        ax.plot(*zip(*bad), "rx", ms=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.invert_yaxis()
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    fig.savefig(os.fspath(path))
    return path


# ===================================================================== main entry
def _metres_per_pixel(metres_per_pixel, altitude, focal_px):
    def pos(name, v):
        return number(name, v, lo=0.0, lo_open=True)

    if metres_per_pixel is not None:
        if altitude is not None or focal_px is not None:
            given = ", ".join(n for n, v in (("altitude", altitude), ("focal_px", focal_px))
                              if v is not None)
            raise ParameterError(f"give metres_per_pixel, or altitude with focal_px, not both "
                                 f"(got metres_per_pixel={metres_per_pixel!r} and {given})")
        return pos("metres_per_pixel", metres_per_pixel)
    if altitude is None and focal_px is None:
        return None
    if altitude is None or focal_px is None:
        raise ParameterError("altitude and focal_px go together (metres per pixel = "
                             "altitude / focal_px for a down-looking camera)")
    return pos("altitude", altitude) / pos("focal_px", focal_px)


def run_odometry(frames, out_dir, *, metres_per_pixel=None, altitude=None, focal_px=None,
                 scale_range=(0.9, 1.1), angle_range=(-20.0, 20.0), resume=False,
                 progress=True, mosaic=True, config=None) -> OdometryResult:
    """Dead reckoning over a sequence of down-looking frames.

    Parameters
    ----------
    frames : folder, video file or list of image paths (or of videos)
        See :func:`list_frames` (frames of any size, depth and colour; all
        must have the first readable frame's size).
    out_dir : path
        Created if needed; receives ``odometry.csv`` (written and flushed
        row by row), ``summary.json``, ``mosaic.png`` and ``trajectory.png``.
    metres_per_pixel : float, optional
        Ground size of a frame-0 pixel; or give ``altitude`` (m) and
        ``focal_px`` (focal length in pixels) of a down-looking camera:
        metres per pixel = altitude / focal_px. Adds ``x_m, y_m``. Giving
        ``metres_per_pixel`` with ``altitude`` or ``focal_px`` is refused
        (ParameterError).
    scale_range, angle_range : (float, float)
        Size change and turn (degrees, counter-clockwise as displayed)
        possible between consecutive frames; a range of one value is a known
        quantity (``(1, 1), (0, 0)``: constant altitude and heading).
    resume : bool
        Continue from an ``odometry.csv`` already in ``out_dir``: frames
        measured there are kept, the state (poses, keyframe, velocity) is
        rebuilt from them, and the result is the same as an uninterrupted
        run. Without it, an existing CSV is overwritten.
    progress : bool
        A tqdm progress bar on stderr (shown only when stderr is a terminal).
    mosaic : bool
        Build ``mosaic.png`` (needs the frames read a second time; at most
        4000 px on its longer side, the frames shrunk to fit).
    config : seahough.Config, optional
        Search tuning (default :data:`ODOMETRY_CONFIG`).

    Returns
    -------
    OdometryResult
        Memory does not grow with the number of frames: each row goes to
        the CSV when finished, the summary is counted as they go, and the
        result's ``rows`` are read back from the CSV when first asked for.

    Notes
    -----
    How a frame is measured (columns ``ref`` and ``method``):

    Frames are cropped to their content (a dark or flat border, as video
    decoders leave, plus 2 px: its static edges would vote for "no motion").

    1. ``prior``: against the keyframe, in a small window around the pose
       predicted by the last measured motion (constant velocity): +-5 % of
       the frame's longer side (at least 3 accumulator bins), +-4 degrees,
       x/÷1.03 in size, two accumulator peaks. The refined pose must stay in
       the window.
    2. ``full``: against the keyframe, with the whole ``scale_range`` /
       ``angle_range`` around the last measured motion and +-half a frame.
    3. ``previous``: against the previous readable frame (when it is not
       the keyframe), full search; it then becomes the keyframe.

    A keyframe measurement of confidence below 0.35 (an old keyframe, or a
    look-alike of it: a tile or a ripple one period on) is checked by a full
    search against the last measured frame, nearer in time; that one
    replaces it when the two differ by more than 2 working pixels at the
    frame's corners (more than a measurement's noise: an aging keyframe of
    a scene in relief drifts too) and it is more confident. It is then
    reported as method ``previous``, with ``ref`` the frame it was measured
    against (the last measured one, which is the previous frame unless
    frames in between were assumed).

    Each must be confident (>= 0.2), find >= 20 % of the reference's edges,
    keep >= 15 % overlap, and match the edges in view at least 0.4 times as
    well as the last measured frames did (an unrelated frame, a fish, silt).
    The current frame becomes the keyframe when the next frame is predicted
    to overlap the keyframe by less than 60 %, or when the keyframe's edges
    match less than 0.6 times as well as at its first measurement (the
    scene's look changed). Flags (a frame with flags is a pair that could
    not be measured or a frame that could not be read):

    - ``unreadable: <reason>``: missing, corrupt, truncated, wrong size;
      the row has no pose, the state is kept and the next readable frame is
      measured against the keyframe across the gap.
    - ``no_motion`` / ``low_confidence`` / ``little_overlap``: no step
      found the motion (reason of the best attempt); the frame gets the
      last known pose, flagged ``pose_assumed: zero motion since frame N``
      (the pose across the gap is unknown: zero motion is assumed, never
      anything else); the next frame is searched against the keyframe and
      against this frame, so the trajectory goes on from the next good pair.
    """
    t_start = time.perf_counter()
    cfg = config or ODOMETRY_CONFIG
    if not isinstance(cfg, Config):
        raise ParameterError("config must be a seahough.Config")
    scale_range, _ = check_ranges(scale_range, (0.0, 0.0))
    angle_range = pair("angle_range", angle_range)  # kept as given: a window around 0
    mpp = _metres_per_pixel(metres_per_pixel, altitude, focal_px)
    items = list_frames(frames)
    reader = _Reader(items, cfg.max_pixels)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / "odometry.csv"
    json_path = out / "summary.json"
    columns = _CSV_BASE + (_CSV_METRIC if mpp else []) + _CSV_MORE

    # Rows are not kept in memory (a long survey would grow without bound): each one
    # is written to the CSV as it is finished, the summary is counted as they go
    # by, and the mosaic and the plot read the CSV back.
    st = _State()
    totals = _Totals()
    frames_mem: dict = {}
    searcher = None

    def load(i):
        if i is None:
            return None
        if i not in frames_mem:
            gray_i = to_gray(reader.raw(i), max_pixels=cfg.max_pixels)
            frames_mem[i] = _Frame(i, searcher.crop(gray_i))
        return frames_mem[i]

    # ---- resume: rebuild the state from the rows kept, rewriting them (drops a
    # cut-off line) into a new file, read and written one row at a time
    n_resumed = 0
    if resume and csv_path.exists():
        part = csv_path.with_name(csv_path.name + ".part")
        try:
            with open(part, "w", newline="") as fnew:
                writer = csv.DictWriter(fnew, fieldnames=columns, extrasaction="ignore")
                writer.writeheader()
                old = _iter_odometry_csv(csv_path)
                for pos, r in _closing_enumerate(old):
                    if pos >= len(items):
                        n_old = pos + 1 + sum(1 for _ in old)
                        raise ParameterError(f"{csv_path} holds {n_old} frames, more than the "
                                             f"{len(items)} given: not the same sequence")
                    if r["index"] != pos or r["file"] != reader.name(pos):
                        raise ParameterError(f"{csv_path}: row {pos} is frame {r['index']} "
                                             f"{r['file']!r}, but frame {pos} here is "
                                             f"{reader.name(pos)!r}: not the same sequence "
                                             "(run without resume)")
                    r["_cum"] = (None if r["matrix"] is None
                                 else np.asarray(r["matrix"], float).reshape(2, 3))
                    if r["status"] != "unreadable" and st.shape is None:
                        g0 = to_gray(reader.raw(r["index"]), max_pixels=cfg.max_pixels)
                        st.shape, st.box = g0.shape, content_box(g0)
                    if mpp:
                        r["x_m"], r["y_m"] = _metric(r, st.shape, mpp)
                    else:
                        r.pop("x_m", None)
                        r.pop("y_m", None)
                    _advance(st, r)
                    if r["status"] != "unreadable":
                        st.heading = r["heading"]
                    writer.writerow(_row_to_csv(r, columns))
                    totals.add(r)
                    n_resumed += 1
        except BaseException:
            part.unlink(missing_ok=True)
            raise
        os.replace(part, csv_path)
        fcsv = open(csv_path, "a", newline="")
    else:
        fcsv = open(csv_path, "w", newline="")
        csv.DictWriter(fcsv, fieldnames=columns).writeheader()
    writer = csv.DictWriter(fcsv, fieldnames=columns, extrasaction="ignore")
    fcsv.flush()

    if st.shape is not None:
        searcher = _Searcher(st.box, scale_range, angle_range, cfg)
        load(st.key)
        load(st.prev)

    bar = None
    if progress:
        from tqdm import tqdm
        # like the CLI's bars: only on a terminal (disable=None), wiped when done
        bar = tqdm(total=len(items), initial=n_resumed, file=sys.stderr, unit="frame",
                   desc="odometry", dynamic_ncols=True, disable=None, leave=False)
    try:
        for i in range(n_resumed, len(items)):
            t0 = time.perf_counter()
            row = {"index": i, "file": reader.name(i), "time": reader.time(i), "x": None,
                   "y": None, "heading": None, "scale": None, "confidence": None, "flags": "",
                   "dx": None, "dy": None, "rotation": None, "scale_change": None,
                   "score": None, "overlap": None, "ref": None, "method": "", "status": "",
                   "matrix": None, "pair_matrix": None, "_cum": None}
            gray = None
            try:
                gray = to_gray(reader.raw(i), max_pixels=cfg.max_pixels)
                if st.shape is not None and gray.shape != st.shape:
                    raise ImageError(f"size {gray.shape[1]}x{gray.shape[0]} differs from the "
                                     f"first frame's {st.shape[1]}x{st.shape[0]}")
            except (ImageError, OSError) as e:
                msg = " ".join(str(e).split())
                if not isinstance(items[i], np.ndarray):
                    msg = msg.replace(str(items[i]) + ": ", "")
                row["status"] = "unreadable"
                row["flags"] = f"unreadable: {msg}"
                gray = None
            if gray is not None:
                if st.shape is None:
                    st.shape, st.box = gray.shape, content_box(gray)
                    searcher = _Searcher(st.box, scale_range, angle_range, cfg)
                gray = searcher.crop(gray)
                if st.key is None:
                    row["status"] = "origin"
                    row["_cum"] = _IDENTITY.copy()
                else:
                    _measure_frame(row, i, gray, st, searcher, load)
                frames_mem[i] = frames_mem.get(i) or _Frame(i, gray)
            _finish_row(row, st, mpp)
            row["ms"] = 1000.0 * (time.perf_counter() - t0)
            _advance(st, row)
            if row["status"] != "unreadable":
                st.heading = row["heading"]
            # keep only the frames the next one may be measured against
            for k in list(frames_mem):
                if k not in (st.key, st.prev, st.meas):
                    del frames_mem[k]
            writer.writerow(_row_to_csv(row, columns))
            fcsv.flush()
            totals.add(row)
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(f"flagged {totals.flagged}", refresh=False)
    finally:
        fcsv.close()
        if bar is not None:
            bar.close()
    frames_mem.clear()

    # ---- outputs (from the CSV, one row at a time)
    mosaic_path = None
    if mosaic and st.shape is not None:
        mosaic_path = _build_mosaic(csv_path, reader, st.shape, out / "mosaic.png")
    reader.close()
    trajectory_path = _plot_trajectory(csv_path, out / "trajectory.png", bool(mpp))
    summary = _summary(totals, items, mpp, scale_range, angle_range, cfg, n_resumed,
                       time.perf_counter() - t_start, metres_per_pixel, altitude, focal_px)
    summary["outputs"] = {"csv": str(csv_path), "json": str(json_path),
                          "mosaic": None if mosaic_path is None else str(mosaic_path),
                          "trajectory": str(trajectory_path)}
    with open(json_path, "w") as f:
        json.dump(summary, f, indent=2)
        f.write("\n")
    return OdometryResult(None, summary, csv_path, json_path, mosaic_path, trajectory_path)


def _measure_frame(row, i, gray, st: _State, searcher: _Searcher, load):
    """Steps 1-3 of run_odometry's notes; fills ``row`` (status, matrix...)."""
    feats = searcher.features(gray)
    key = load(st.key)
    ref_rate = float(np.median(st.rates)) if len(st.rates) >= 2 else None
    reasons = []
    res = None
    n = i - st.meas
    if st.vel is not None:
        pred_cum = compose(_power(st.vel, n), st.meas_cum)
        predicted = compose(pred_cum, invert_matrix(st.key_cum))
        res, why = searcher.measure(key, gray, feats, predicted, None, n, "prior", ref_rate)
        reasons.append(why)
    if res is None:
        base = compose(st.meas_cum, invert_matrix(st.key_cum))
        res, why = searcher.measure(key, gray, feats, None, base, n, "full", ref_rate)
        reasons.append(why)
    if res is None and st.prev is not None and st.prev != st.key:
        prev = load(st.prev)
        res, why = searcher.measure(prev, gray, feats, None, _IDENTITY, i - st.prev, "previous",
                                    ref_rate)
        reasons.append(why)
    if res is None:
        row["status"] = "assumed"
        row["_cum"] = st.last_pose_cum.copy()
        why = "low_confidence" if "low_confidence" in reasons else (
            "little_overlap" if "little_overlap" in reasons else "no_motion")
        row["flags"] = f"{why}; pose_assumed: zero motion since frame {st.meas}"
        return
    if (res.ref == st.key and res.confidence < _DOUBTFUL and st.meas is not None
            and st.meas != st.key):
        res = _checked(res, i, gray, feats, st, searcher, load, ref_rate)
    row["status"] = "measured"
    row["_cum"] = compose(res.matrix, _ref_cum(st, res.ref))
    row["ref"] = res.ref
    row["method"] = res.method
    row["confidence"] = res.confidence
    row["score"] = res.score
    row["overlap"] = res.overlap


def _ref_cum(st: _State, ref: int) -> np.ndarray:
    """The cumulative matrix of a reference frame (the keyframe, the last
    measured frame or the previous frame)."""
    if ref == st.key:
        return st.key_cum
    return st.meas_cum if ref == st.meas else st.prev_cum


def _checked(res, i, gray, feats, st: _State, searcher: _Searcher, load, ref_rate):
    """A doubtful keyframe measurement against the last measured frame: an
    old keyframe's peak can be a look-alike (a tile, a ripple one period on)
    that the nearer frame does not share, and an old keyframe of a scene in
    relief is off by more than its confidence says. The nearer frame's
    measurement replaces it when the two disagree and it is more confident."""
    # a full search: in the small prior window a look-alike has only one
    # runner-up to be measured against (on the tiled pool it confirmed itself)
    n = i - st.meas
    check, _ = searcher.measure(load(st.meas), gray, feats, None, _IDENTITY, n, "previous",
                                ref_rate)
    if check is None or check.confidence <= res.confidence:
        return res
    implied = compose(res.matrix, compose(st.key_cum, invert_matrix(st.meas_cum)))
    h, w = st.shape
    grid = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
    gap = float(np.max(np.hypot(*(apply_matrix(implied, grid) - apply_matrix(check.matrix, grid)).T)))
    return check if gap > _AGREE_PX / searcher.factor else res


def _metric(row, shape, mpp):
    """(x_m, y_m): metres from the first frame's centre."""
    if row.get("x") is None or shape is None:
        return None, None
    c = _centre(shape)
    return float((row["x"] - c[0]) * mpp), float((row["y"] - c[1]) * mpp)


def _finish_row(row, st: _State, mpp):
    """Pose columns from the cumulative matrix, and the motion from the previous frame."""
    cum = row["_cum"]
    if cum is None:
        return
    cum = _similar(cum)
    row["_cum"] = cum
    row["matrix"] = cum.ravel().tolist()
    x, y, hd, s = _pose_fields(cum, st.shape, st.heading if st.last_pose is not None else 0.0)
    row.update(x=x, y=y, heading=hd, scale=s)
    if mpp:
        row["x_m"], row["y_m"] = _metric(row, st.shape, mpp)
    if st.last_pose is not None and st.last_pose == row["index"] - 1:
        pm = compose(cum, invert_matrix(st.last_pose_cum))
        c = _centre(st.shape)
        px, py, ps, pa = matrix_to_pose(pm, c)
        row.update(dx=float(px - c[0]), dy=float(py - c[1]),
                   rotation=float((pa + 180.0) % 360.0 - 180.0), scale_change=float(ps),
                   pair_matrix=pm.ravel().tolist())


class _Totals:
    """The summary's counts, updated row by row (the rows themselves are not kept)."""

    def __init__(self):
        self.frames = self.measured = self.flagged = self.unreadable = self.assumed = 0
        self.methods: dict = {}
        self.refs: set = set()
        self.length = 0.0
        self.last_xy = None
        self.end = None
        self.ms_sum, self.ms_n = 0.0, 0

    def add(self, r):
        self.frames += 1
        self.measured += r["status"] == "measured"
        self.flagged += bool(r.get("flags"))
        self.unreadable += r["status"] == "unreadable"
        self.assumed += r["status"] == "assumed"
        if r.get("method"):
            self.methods[r["method"]] = self.methods.get(r["method"], 0) + 1
        if r.get("ref") is not None:
            self.refs.add(r["ref"])
        if r.get("x") is not None:
            if self.last_xy is not None:
                self.length += math.hypot(r["x"] - self.last_xy[0], r["y"] - self.last_xy[1])
            self.last_xy = (r["x"], r["y"])
            self.end = {"index": r["index"], "x": r["x"], "y": r["y"],
                        "heading": r["heading"], "scale": r["scale"], "x_m": r.get("x_m"),
                        "y_m": r.get("y_m")}
        if r.get("ms") is not None:
            self.ms_sum += r["ms"]
            self.ms_n += 1


def _summary(t: _Totals, items, mpp, scale_range, angle_range, cfg, n_resumed, wall_s,
             metres_per_pixel, altitude, focal_px) -> dict:
    length = t.length
    mean_ms = t.ms_sum / t.ms_n if t.ms_n else None
    src = items[0] if len(items) and not isinstance(items[0], np.ndarray) else "arrays"
    s = {
        "frames": t.frames,
        "measured_pairs": t.measured,
        "flagged_pairs": t.flagged,
        "unreadable_frames": t.unreadable,
        "assumed_poses": t.assumed,
        "methods": dict(t.methods),
        "keyframes": len(t.refs),
        "path_length_px": length,
        "path_length_m": length * mpp if mpp else None,
        "end_point": t.end,
        "mean_ms_per_frame": mean_ms,
        "resumed_rows": n_resumed,
        "wall_s": wall_s,
        # the keys the CLI looks for
        "distance": length * mpp if mpp else length,
        "unit": "m" if mpp else "px",
        "ms_per_frame": mean_ms,
        "settings": {
            "source": str(src) if not isinstance(src, str) else src,
            "metres_per_pixel": mpp, "given_metres_per_pixel": metres_per_pixel,
            "altitude": altitude, "focal_px": focal_px,
            "scale_range": list(scale_range), "angle_range": list(angle_range),
            "min_confidence": _MIN_CONFIDENCE, "min_score": _MIN_SCORE,
            "min_relative_match": _MIN_RELATIVE,
            "min_overlap": _MIN_OVERLAP, "rekey_overlap": _REKEY_OVERLAP,
            "rekey_match": _REKEY_MATCH,
            "doubtful_keyframe_check": {"below_confidence": _DOUBTFUL,
                                        "agree_working_px": _AGREE_PX},
            "prior_window": {"radius_share": _PRIOR_RADIUS, "min_bins": _PRIOR_BINS,
                             "angle_deg": _PRIOR_ANGLE, "scale": _PRIOR_SCALE},
            "config": dataclasses.asdict(cfg),
        },
    }
    return s
