"""Photo dead reckoning one frame at a time: :class:`Odometer`, for a
camera's stream (a vehicle's own computer), and the steps every frame of
:func:`~seahough.run_odometry` goes through.

A frame is given, its row comes back: where the camera is, how it got
there, and flags when a step could not be measured. Nothing grows with the
frames: the Odometer keeps the few frames the next one may be measured
against (the keyframe, the last frame, the last measured one), not the
rows. :func:`~seahough.run_odometry` runs the same steps over a whole
sequence (a folder, a video, a list), writing each row to ``odometry.csv``,
so the two give the same rows for the same frames.

>>> from seahough import sim
>>> frames, truth = sim.sequence(n_frames=4, seed=2, source="procedural")
>>> odo = Odometer()
>>> rows = [odo.push(f) for f in frames]
>>> [r["status"] for r in rows]
['origin', 'measured', 'measured', 'measured']
>>> rows[1]["flags"], len(rows[1]["pair_matrix"])
('', 6)
"""

from __future__ import annotations

import os
import threading
import time as _time

import numpy as np

from .._validate import number, pair
from ..config import ODOMETRY_CONFIG, Config, OdometryTuning
from ..core.accumulator import check_ranges
from ..core.detector import MIN_SEGMENTS
from ..errors import ImageValueError, ParameterError, interrupted
from ..geometry import apply_matrix, compose, invert_matrix, matrix_power, nearest_similarity
from ..io.frames import FrameReader, split_video_ref
from .framing import content_box
from .prefetch import Prefetch, Prepared, read_frame
from .runfiles import run_settings, settings_hash
from .searcher import WIDEN, Searcher as _Searcher
from .state import Frame, State, advance, ref_cum
from .track import CSV_BASE, CSV_CHECK, CSV_METRIC, CSV_MORE, pose_columns, \
    resolve_metres_per_pixel

__all__ = ["Odometer"]

#: The policy a run follows unless given one.
TUNING = OdometryTuning()

_IDENTITY = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: After a gap of at most this many frames since the last measured one (one
#: or two frames assumed), that frame gets a full search of its own
#: (``recover``); a longer gap costs every frame of it the searches it has
#: (about 0.2 s more a frame at 320x240 when every frame got it).
RECOVER_SPAN = 3


class Odometer:
    """Photo dead reckoning of frames given one at a time (a camera's stream).

    Each :meth:`push` measures a frame against the frames before it, as
    :func:`~seahough.run_odometry` measures a sequence (the same steps,
    keyframes and prior; its notes say how), and returns the frame's row.
    No file is written and no row is kept: memory stays bounded over
    hours of frames.

    Parameters
    ----------
    scale_range, angle_range : (float, float)
        Size change and turn (degrees) possible between consecutive
        frames, as for :func:`~seahough.run_odometry` (narrower than
        :func:`~seahough.estimate_motion`'s, which are for any pair: a
        stream's consecutive frames differ by little, and a larger jump is
        still measured by the run's wide try).
    metres_per_pixel, altitude, focal_px : float, optional
        The ground size of a frame-0 pixel, or the altitude (m) and focal
        length (px) of a down-looking camera: adds ``x_m, y_m`` to the rows.
    config : seahough.Config, optional
        Search tuning (default :data:`~seahough.config.ODOMETRY_CONFIG`).
    tuning : seahough.OdometryTuning, optional
        The keyframe, prior and fallback policy.
    fps : float, optional
        Frame rate: a row's ``time`` is ``index / fps`` unless :meth:`push`
        is given one.

    Examples
    --------
    See the module's. A frame the camera driver could not give (None), or
    one that cannot be read, gets an ``unreadable`` row and the next one is
    measured across the gap; a frame of another size than the first is
    unreadable too, until :meth:`reset` starts a new track.
    """

    def __init__(self, scale_range=(0.9, 1.1), angle_range=(-20.0, 20.0), *,
                 metres_per_pixel=None, altitude=None, focal_px=None, config=None,
                 tuning: OdometryTuning | None = None, fps: float | None = None):
        cfg = ODOMETRY_CONFIG if config is None else config
        if not isinstance(cfg, Config):
            raise ParameterError("config must be a seahough.Config")
        tuning = TUNING if tuning is None else tuning
        if not isinstance(tuning, OdometryTuning):
            raise ParameterError("tuning must be a seahough.OdometryTuning")
        self.scale_range, _ = check_ranges(scale_range, (0.0, 0.0))
        self.angle_range = pair("angle_range", angle_range)  # kept as given: a window around 0
        self.fps = None if fps is None else number("fps", fps, lo=0.0, lo_open=True)
        self.mpp = resolve_metres_per_pixel(metres_per_pixel, altitude, focal_px)
        self.config, self.tuning = cfg, tuning
        self.settings = run_settings(self.scale_range, self.angle_range, self.mpp, cfg, tuning)
        if self.fps is not None:  # (only when given: runs made before resume as they were)
            self.settings["fps"] = float(self.fps)
        self.digest = settings_hash(self.settings)
        self.columns = CSV_BASE + (CSV_METRIC if self.mpp else []) + CSV_MORE + CSV_CHECK
        #: how a frame the state needs and does not hold is read again (a
        #: resumed run's keyframe): index -> grey image
        self.fetch = None
        self._lock = threading.RLock()
        self.reset()

    def __getstate__(self):       # (a lock is not pickled: a copy gets its own)
        state = dict(self.__dict__)
        state.pop("_lock", None)
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._lock = threading.RLock()

    def reset(self) -> None:
        """Start a new track: the next frame is frame 0 of it (after a change
        of camera, of resolution, or a jump to another place)."""
        with self._lock:
            self.st = State()
            self.searcher: _Searcher | None = None
            self.frames: dict = {}   # index -> Frame: those the next one may be measured against
            self.hashes: dict = {}   # index -> frame_hash of those
            self._next = 0
            self._video = None       # (path, last frame) of the last video frame pushed ...
            self._video_t0 = 0.0     # ... and when that video began on the track's time line

    def push(self, frame, *, time: float | None = None, name: str | None = None) -> dict:
        """Measure the next frame; returns its row.

        Parameters
        ----------
        frame : array or path, or None
            The frame (grey, BGR/BGRA, 8 or 16 bits, float), or its file.
            None: a frame the camera could not give (a dropped frame).
        time : float, optional
            Its time (s); else its file's (a time in its name, or a video
            frame's, ``"dive.mp4#12"``: the frames of several videos pushed
            one video after the other are on one time line, as in
            :func:`~seahough.run_odometry`); else ``index / fps`` when the
            Odometer has ``fps``.
        name : str, optional
            The row's ``file`` (default ``frame_NNNNN``, or the path).

        Returns
        -------
        dict
            The columns of :attr:`OdometryResult.rows <seahough.motion.track.OdometryResult>`,
            unrounded: ``index, file, time``; the pose ``x, y, heading, scale``
            (``x_m, y_m`` with a ground size), ``matrix`` (frame 0 -> this
            frame, 6 numbers, row-major 2x3); its evidence ``confidence,
            nfa, score, overlap``; ``flags`` ("" when the step was measured;
            the first word says why not: ``no_match``, ``low_confidence``,
            ``little_overlap``, ``few_edges``, ``duplicate``, ``unreadable``;
            ``after_gap`` on a measured step); the step from the previous
            frame ``dx, dy, rotation, scale_change, pair_matrix``; how it
            was measured ``ref, method, ms``; ``status``: ``"origin"``,
            ``"measured"``, ``"assumed"`` (a pose carried on: not measured)
            or ``"unreadable"`` (no pose); ``frame_hash, settings_hash``
            (what a resumed file run checks).

        Raises
        ------
        ImageValueError
            ``frame`` is neither an array, a path nor None.

        Notes
        -----
        One push at a time: pushes from several threads are taken in turn
        (a lock), in the order they get it.
        """
        if frame is not None and not isinstance(frame, (np.ndarray, str, os.PathLike)):
            raise ImageValueError(f"frame: expected a numpy array, a file path or None, got "
                                  f"{type(frame).__name__}")
        with self._lock:
            return self._push(frame, time, name)

    def _video_start(self, reader: FrameReader, name: str) -> float:
        """When the video of frame ``name`` began on the track's time line:
        a video after another starts where that one ends (its frame count
        over its rate; a second video's times started at 0 again, and a
        velocity across the change was wrong)."""
        path, k = split_video_ref(name)
        run = getattr(self, "_video", None)   # (an Odometer pickled before it had one: none)
        self._video_t0 = getattr(self, "_video_t0", 0.0)
        if run is not None and run[0] != path:
            self._video_t0 += reader._video_length(*run)
            run = None
        self._video = (path, k if run is None else max(run[1], k))
        return self._video_t0

    def _push(self, frame, time, name) -> dict:
        i = self._next
        t0 = _time.perf_counter()
        cfg = self.config
        reader = FrameReader([frame], cfg.max_pixels, cfg.max_memory_mb)
        if frame is None:
            prep = Prepared(i, "", error="no frame (None: a dropped frame)")
        else:
            prep = read_frame(reader, 0, cfg.max_pixels, cfg.max_memory_mb, cfg.bit_depth)
            prep.index = i
            if prep.gray is not None and isinstance(frame, np.ndarray) \
                    and np.may_share_memory(prep.gray, frame):
                # (a camera driver refills its buffer: the keyframe must be our own)
                prep.gray = prep.gray.copy()
        label = f"frame_{i:05d}" if reader.is_array(0) else reader.name(0)
        if time is not None:
            time = number("time", time)
        else:   # (as run_odometry: a time in the file's name, else index / fps)
            time = reader.time(0)
            if time is not None and reader.is_video(0):
                time += self._video_start(reader, str(frame))
            if time is None and self.fps is not None:
                time = i / self.fps
        try:
            row = self.step(i, prep, label if name is None else str(name), time, t0)
        except SystemError as e:   # (Ctrl-C inside a compiled kernel)
            if interrupted(e):
                raise KeyboardInterrupt from e
            raise
        self._next += 1
        return {k: _plain(row.get(k)) for k in self.columns}

    # ------------------------------------------------------------- the steps
    def load(self, i: int | None) -> Frame | None:
        """Frame ``i`` of the state (kept, or read again by :attr:`fetch`)."""
        if i is None:
            return None
        if i not in self.frames:
            self.frames[i] = Frame(i, self.searcher.crop(self.fetch(i)))
        return self.frames[i]

    def step(self, i: int, prep: Prepared, name: str, time: float | None, t0: float) -> dict:
        """Frame ``i`` (read, or why not: ``prep``) measured; its row (with
        ``_cum``, the cumulative matrix), the state advanced."""
        st = self.st
        row = {"index": i, "file": name, "time": time, "x": None,
               "y": None, "heading": None, "scale": None, "confidence": None, "nfa": None,
               "flags": "", "dx": None, "dy": None, "rotation": None, "scale_change": None,
               "score": None, "overlap": None, "ref": None, "method": "", "status": "",
               "matrix": None, "pair_matrix": None, "_cum": None,
               "frame_hash": prep.frame_hash, "settings_hash": self.digest}
        gray = prep.gray
        if prep.error is None and st.shape is not None and prep.shape != st.shape:
            prep.error = (f"size {prep.shape[1]}x{prep.shape[0]} differs from the first "
                          f"frame's {st.shape[1]}x{st.shape[0]}")
        if prep.error is not None:
            row["status"] = "unreadable"
            row["flags"] = f"unreadable: {prep.error}"
            gray = None
        if gray is not None:
            if st.shape is None:
                st.shape, st.box = gray.shape, content_box(gray)
                self.searcher = _Searcher(st.box, self.scale_range, self.angle_range,
                                          self.config, self.tuning)
            gray = Prefetch.finish(prep, self.searcher, st.key is not None).gray
            if st.key is None:
                row["status"] = "origin"
                row["_cum"] = _IDENTITY.copy()
            elif self._duplicate(prep, gray):
                _assume(row, st, f"duplicate: the same pixels as frame {st.prev}")
            else:
                _measure_frame(row, i, gray, prep.features, st, self.searcher, self.load)
            self.frames[i] = self.frames.get(i) or Frame(i, gray)
            self.hashes[i] = prep.frame_hash
        _finish_row(row, st, self.mpp)
        row["ms"] = 1000.0 * (_time.perf_counter() - t0)
        advance(st, row, self.tuning)
        if row["status"] != "unreadable":
            st.heading = row["heading"]
        # keep only the frames the next one may be measured against
        for k in list(self.frames):
            if k not in (st.key, st.prev, st.meas):
                del self.frames[k]
                self.hashes.pop(k, None)
        return row

    def _duplicate(self, prep: Prepared, gray) -> bool:
        """The same pixels as the last frame with a pose (a camera driver
        handing the same buffer twice): its motion is not zero, it is not
        known. (Fingerprints first: the pixels are compared only when they
        agree. A frame without edges, open water or a black frame, is not
        one: it is measured, and flagged ``few_edges``.)"""
        if prep.features is not None and len(prep.features.segments) < MIN_SEGMENTS:
            return False
        last = self.frames.get(self.st.prev)
        if last is None or not prep.frame_hash or self.hashes.get(last.index) != prep.frame_hash:
            return False
        return last.gray.shape == gray.shape and np.array_equal(last.gray, gray)


def _plain(v):
    """A row's value as Python gives it (numpy scalars to float/int)."""
    if isinstance(v, np.generic):
        return v.item()
    return v


def _measure_frame(row, i, gray, feats, st: State, searcher: _Searcher, load):
    """Steps 1-4 of run_odometry's notes; fills ``row`` (status, matrix...)."""
    key = load(st.key)
    ref_rate = float(np.median(st.rates)) if len(st.rates) >= 2 else None
    reasons = []
    res = None
    n = i - st.meas
    # the constant velocity's motion from a reference frame: it chooses among a
    # repeated texture's copies in every search (repeats.nearest_copy)
    pred_cum = compose(matrix_power(st.vel, n), st.meas_cum) if st.vel is not None else None
    near = lambda ref: (None if pred_cum is None  # noqa: E731
                        else compose(pred_cum, invert_matrix(ref_cum(st, ref))))
    if pred_cum is not None:
        res, why = searcher.measure(key, gray, feats, near(st.key), None, n, "prior", ref_rate)
        reasons.append(why)
    if res is None:
        base = compose(st.meas_cum, invert_matrix(st.key_cum))
        res, why = searcher.measure(key, gray, feats, None, base, n, "full", ref_rate,
                                    near=near(st.key))
        reasons.append(why)
    if res is None and st.prev != st.meas and st.meas != st.key and n <= RECOVER_SPAN:
        # after a short gap (the last poses assumed: a bad frame, a fish), the
        # last measured frame's full search too, as estimate_motion measures a
        # pair: nearer than the keyframe, and the wide try against it searches
        # for twice the motion (a good frame after one bad frame was flagged
        # no_match: its keyframe 5 frames back, the wide try too wide to vote)
        res, why = searcher.measure(load(st.meas), gray, feats, None, _IDENTITY, n, "recover",
                                    ref_rate, near=near(st.meas))
        reasons.append(why)
    if res is None and st.prev is not None and st.prev != st.key:
        prev = load(st.prev)
        res, why = searcher.measure(prev, gray, feats, None, _IDENTITY, i - st.prev, "previous",
                                    ref_rate, near=near(st.prev))
        reasons.append(why)
    if res is None:
        # the last attempt: the last measured frame, a wider shift region and wider ranges
        res, why = searcher.measure(load(st.meas), gray, feats, None, _IDENTITY, n, "wide",
                                    ref_rate, widen=WIDEN, near=near(st.meas))
        reasons.append(why)
    if res is None:
        _assume(row, st, "low_confidence" if "low_confidence" in reasons else (
            "little_overlap" if "little_overlap" in reasons else (
                "few_edges" if all(r == "few_edges" for r in reasons) else "no_match")))
        return
    if _doubtful(res, st, searcher.tuning):
        res = _checked(res, i, gray, feats, st, searcher, load, ref_rate, near(st.meas))
    row["status"] = "measured"
    row["_cum"] = compose(res.matrix, ref_cum(st, res.ref))
    flags = []
    if res.ref == st.prev and st.prev != st.meas:
        # (its step is measured; its place rests on the guess of the frame before)
        flags.append(f"after_gap: measured against frame {res.ref}, whose pose was assumed")
    if getattr(res, "period", 0.0) > 0.0:   # (a net, a grating: repeats.nearest_copy)
        flags.append(f"repeated_texture: the step is known up to the texture's period "
                     f"({res.period:.0f} px); " + (
                         "the copy nearest the constant-velocity prediction was taken"
                         if pred_cum is not None else "the vote's copy (no velocity known yet)"))
    row["flags"] = "; ".join(flags)
    row["ref"] = res.ref
    row["method"] = res.method
    row["confidence"] = res.confidence
    row["nfa"] = res.nfa
    row["score"] = res.score
    row["overlap"] = res.overlap


def _assume(row, st: State, why: str) -> None:
    """A pair that could not be measured: the last measured pose carried on
    by the last measured velocity (zero motion when none is known yet),
    flagged with ``why`` and the assumption."""
    n = row["index"] - st.meas
    row["status"] = "assumed"
    if st.vel is not None:
        row["_cum"] = compose(matrix_power(st.vel, n), st.meas_cum)
        how = "constant velocity"
    else:
        row["_cum"] = st.meas_cum.copy()
        how = "zero motion"
    row["flags"] = f"{why}; pose_assumed: {how} since frame {st.meas}"


def _doubtful(res, st: State, tuning) -> bool:
    """Whether a measurement against the keyframe (two or more frames back)
    is checked by :func:`_checked`: less confident than ``tuning.doubtful``,
    or found by a search other than the prior's (the motion left the
    prediction, or there was none: the keyframe's best peak out there may
    be a look-alike, a tile or a ripple one period on).

    The check of every full search, not only of the second one running off
    the prior: on the real tiled pool (frames cropped by 3 px) a full
    search right after a measurement on the prior went a tile off, 7 % of
    the diagonal at confidence 0.59, where the adjacent frame's own search
    was right.

    >>> from seahough import OdometryTuning
    >>> from seahough.motion.searcher import Measure
    >>> st = State(key=3, meas=5)
    >>> full = Measure(np.eye(2, 3), 0.6, 0.5, 0.8, ref=3, method="full")
    >>> _doubtful(full, st, OdometryTuning())          # off the prior
    True
    >>> prior = Measure(np.eye(2, 3), 0.6, 0.5, 0.8, ref=3, method="prior")
    >>> _doubtful(prior, st, OdometryTuning()), _doubtful(
    ...     Measure(np.eye(2, 3), 0.3, 0.5, 0.8, ref=3, method="prior"), st, OdometryTuning())
    (False, True)
    >>> _doubtful(full, State(key=5, meas=5), OdometryTuning())   # the keyframe is the last frame
    False
    """
    if res.ref != st.key or st.meas is None or st.meas == st.key:
        return False
    return res.confidence < tuning.doubtful or res.method != "prior"


def _checked(res, i, gray, feats, st: State, searcher: _Searcher, load, ref_rate, near=None):
    """A doubtful keyframe measurement against the last measured frame: an
    old keyframe's peak can be a look-alike (a tile, a ripple one period on)
    that the nearer frame does not share, and an old keyframe of a scene in
    relief is off by more than its confidence says. Doubtful:
    :func:`_doubtful` (the run is where the prior does not hold: a camera
    that looks ahead, a tiled floor, a turn; a run on the prior is not
    checked above ``OdometryTuning.doubtful``). When the two disagree, the
    nearer frame's measurement replaces it if that frame is the adjacent
    one (the pair with the most overlap and the least change of view,
    measured as estimate_motion measures a pair), else only if it is more
    confident.

    Chosen on the dev part of bench/bench_oblique.py (40 rendered tiled
    floors seen by a forward-oblique camera, seeds 200-239, 10-frame runs):
    of 14 keyframe measurements two or more frames back, 8 were look-alikes
    9-24 % of the diagonal off at confidence 0.26-0.82; the adjacent
    frame's measurement was within 2 % in 6 of those, and within 2 % (and
    nearer the truth) in all 6 right ones. Steps off by more than 3 %
    20 -> 14 of 354, within 2 % 322 -> 329. Checking every keyframe
    measurement did the same there but quadrupled a downward survey's prior
    pairs (10 -> 43 ms at 640x480); checking also those on the prior after
    one search off it made the amphora wreck's pairs on the prior 2x slower
    at the median."""
    # a full search: in the small prior window a look-alike has only one
    # runner-up to be measured against (on the tiled pool it confirmed itself)
    n = i - st.meas
    check, _ = searcher.measure(load(st.meas), gray, feats, None, _IDENTITY, n, "previous",
                                ref_rate, near=near)
    if check is None or (n > 1 and check.confidence <= res.confidence):
        return res
    implied = compose(res.matrix, compose(st.key_cum, invert_matrix(st.meas_cum)))
    h, w = st.shape
    grid = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
    gap = float(np.max(np.hypot(*(apply_matrix(implied, grid) - apply_matrix(check.matrix, grid)).T)))
    return check if gap > searcher.tuning.agree_px / searcher.factor else res


def _finish_row(row, st: State, mpp):
    """Pose columns from the cumulative matrix, and the motion from the previous frame."""
    cum = row["_cum"]
    if cum is None:
        return
    cum = nearest_similarity(cum)
    row["_cum"] = cum
    prev = (st.last_pose_cum if st.last_pose is not None and st.last_pose == row["index"] - 1
            else None)
    row.update(pose_columns(cum, st.shape, st.heading if st.last_pose is not None else 0.0, mpp,
                            prev))
