"""A dead-reckoning track on disk: ``odometry.csv`` rows, the run's summary
counts, and what :func:`~seahough.run_odometry` returns.

Rows are written to the CSV as each frame is finished and read back one at
a time, so that a survey's length never sets the memory it needs.
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .._validate import number
from ..errors import ParameterError
from ..geometry import (angle_difference, apply_matrix, compose, frame_centre, invert_matrix,
                        matrix_to_pose, wrap_angle)

__all__ = ["OdometryResult", "read_odometry_csv", "iter_odometry_csv", "CSV_BASE", "CSV_METRIC",
           "CSV_MORE", "CSV_CHECK"]

CSV_BASE = ["index", "file", "time", "x", "y", "heading", "scale", "confidence", "nfa", "flags"]
CSV_METRIC = ["x_m", "y_m"]
CSV_MORE = ["dx", "dy", "rotation", "scale_change", "score", "overlap", "ref", "method",
             "status", "ms", "matrix", "pair_matrix"]
#: What ``--resume`` checks a row against: the frame's content fingerprint
#: (:meth:`seahough.io.frames.FrameReader.fingerprint`) and the hash of the
#: settings the run was made with (:func:`seahough.motion.runfiles.run_settings`).
CSV_CHECK = ["frame_hash", "settings_hash"]


class OdometryResult:
    """What :func:`~seahough.run_odometry` produced.

    Attributes
    ----------
    rows : list of dict
        One per frame, the CSV's columns with Python values (None = empty):
        ``index, file, time, x, y, heading, scale, confidence, nfa, flags``
        (``x_m, y_m`` when metric; ``nfa``: the measurement's number of
        false alarms, :attr:`seahough.Motion.nfa`, reported only: the run
        does not judge pairs by it; None for a pair not measured, and in
        rows of a CSV written before the column existed), and ``dx, dy,
        rotation, scale_change`` (motion from the previous frame: shift of
        its centre in current-frame pixels, degrees counter-clockwise as
        displayed, size change),
        ``score, overlap`` (of the measurement), ``ref`` (index of the frame
        it was measured against), ``method`` (``"prior"``, ``"full"``,
        ``"recover"``, ``"previous"``, ``"wide"``: see :func:`run_odometry`'s notes), ``status``
        (``"origin"``, ``"measured"``, ``"assumed"``: a pose carried on from
        the last measured one, see the ``flags``; ``"unreadable"``),
        ``ms``, ``matrix`` and
        ``pair_matrix`` (2x3 as 6 floats, row-major), ``frame_hash`` and
        ``settings_hash`` (what ``resume`` checks: the frame's content and
        the run's settings, as short strings). The run does not keep
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
        return iter(self._rows) if self._rows is not None else iter_odometry_csv(self.csv_path)

    def __repr__(self):
        return (f"OdometryResult(frames={self.summary.get('frames')}, csv_path={self.csv_path!r}, "
                f"mosaic_path={self.mosaic_path!r}, trajectory_path={self.trajectory_path!r})")


def matrix_text(m) -> str:
    """A 2x3 matrix as the CSV writes it: 6 numbers, row-major, exact (repr).

    >>> parse_matrix(matrix_text([[1, 0, 2.5], [0, 1, -1]])).tolist()
    [[1.0, 0.0, 2.5], [0.0, 1.0, -1.0]]
    """
    return " ".join(repr(float(v)) for v in np.asarray(m, float).ravel())


def parse_matrix(s) -> np.ndarray | None:
    """The 2x3 matrix of a CSV cell (None for an empty one); ValueError otherwise."""
    if s is None or s == "":
        return None
    v = [float(t) for t in str(s).split()]
    if len(v) != 6:
        raise ValueError(f"expected 6 numbers, got {len(v)}")
    return np.array(v, float).reshape(2, 3)


def _fmt(v, digits=None) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        if not math.isfinite(v):
            return ""
        v = float(v)        # a numpy float's repr is "np.float64(...)"
        return repr(v) if digits is None else f"{v:.{digits}f}"
    return str(v)


def row_to_csv(row: dict, columns) -> dict:
    out = {}
    for k in columns:
        v = row.get(k)
        if k in ("matrix", "pair_matrix"):
            out[k] = "" if v is None else matrix_text(np.asarray(v).reshape(2, 3))
        elif k == "ms":
            out[k] = _fmt(v, 2)
        else:
            out[k] = _fmt(v)
    return out


_FLOAT_COLS = ("time", "x", "y", "x_m", "y_m", "heading", "scale", "confidence", "nfa", "dx",
               "dy", "rotation", "scale_change", "score", "overlap", "ms")
#: Columns a CSV of an earlier seahough may lack: read back as None (empty).
_NEWER_COLS = ("nfa",)


def read_odometry_csv(path) -> list:
    """Rows of an ``odometry.csv`` with Python values (as :attr:`OdometryResult.rows`).

    A last line cut short (the run was killed while writing it) is dropped.
    """
    return list(iter_odometry_csv(path))


def iter_odometry_csv(path):
    """The rows of :func:`read_odometry_csv` one at a time (the file is not read whole)."""
    with open(path, newline="") as f:
        def complete_lines():
            # only the file's last line can be a row cut short (no line end): a
            # line before it may end inside a quoted name holding "\r" or "\n"
            last = None
            for line in f:
                if last is not None:
                    yield last
                last = line
            if last is not None and last.endswith("\n"):
                yield last

        records = csv.DictReader(complete_lines())
        while True:
            try:
                rec = next(records)
            except StopIteration:
                return
            except csv.Error:
                return      # a quoted field cut short, a NUL byte: stop here
            try:
                row = {"index": int(rec["index"]), "file": rec["file"]}
                for k in _FLOAT_COLS:
                    if k in rec:
                        row[k] = float(rec[k]) if rec[k] not in ("", None) else None
                    elif k in _NEWER_COLS:
                        row[k] = None
                row["flags"] = rec.get("flags") or ""
                row["ref"] = int(rec["ref"]) if rec.get("ref") else None
                row["method"] = rec.get("method") or ""
                row["status"] = rec["status"]
                if row["status"] not in ("origin", "measured", "assumed", "unreadable"):
                    raise ValueError(row["status"])
                m = parse_matrix(rec.get("matrix"))
                row["matrix"] = None if m is None else m.ravel().tolist()
                pm = parse_matrix(rec.get("pair_matrix"))
                row["pair_matrix"] = None if pm is None else pm.ravel().tolist()
                if row["status"] != "unreadable" and m is None:
                    raise ValueError("no matrix")
                for k in CSV_CHECK:             # None: a CSV of a seahough without them
                    row[k] = rec.get(k)
            except (KeyError, ValueError, TypeError, AttributeError):
                return  # a truncated or foreign line: stop here
            yield row


def closing_enumerate(gen):
    """enumerate(gen), closing the generator (its file) however the loop ends."""
    try:
        yield from enumerate(gen)
    finally:
        gen.close()


def pose_fields(cum, shape, heading_prev):
    """x, y, heading (unwrapped near ``heading_prev``), scale of a cumulative matrix."""
    inv = invert_matrix(cum)
    x, y = apply_matrix(inv, [frame_centre(shape)])[0]
    up = inv[:, :2] @ np.array([0.0, -1.0])
    hd = math.degrees(math.atan2(-up[0], -up[1]))
    hd = heading_prev + angle_difference(hd, heading_prev)
    _, _, s, _ = matrix_to_pose(cum)
    return float(x), float(y), float(hd), float(s)


def metric_position(row, shape, mpp):
    """(x_m, y_m): metres from the first frame's centre."""
    if row.get("x") is None or shape is None:
        return None, None
    c = frame_centre(shape)
    return float((row["x"] - c[0]) * mpp), float((row["y"] - c[1]) * mpp)


def pose_columns(cum, shape, heading_prev: float, mpp=None, prev_cum=None) -> dict:
    """The columns of a row that follow from its cumulative matrix ``cum``
    (frame-0 pixels -> frame pixels): ``matrix, x, y, heading`` (unwrapped
    near ``heading_prev``), ``scale``; ``x_m, y_m`` when ``mpp`` (metres per
    pixel) is given; and, when ``prev_cum`` (the previous frame's) is given,
    the motion from the previous frame: ``dx, dy, rotation, scale_change,
    pair_matrix``. (A run computes them as each frame is finished; a survey
    recomputes them once its chunks are chained.)

    >>> c = pose_columns([[1, 0, -10], [0, 1, 0]], (240, 320), 0.0, mpp=0.01,
    ...                  prev_cum=[[1, 0, 0], [0, 1, 0]])
    >>> c["x"], c["y"], c["heading"], c["scale"], round(c["x_m"], 6), c["dx"], c["dy"]
    (169.5, 119.5, 0.0, 1.0, 0.1, -10.0, 0.0)
    """
    cum = np.asarray(cum, float).reshape(2, 3)
    x, y, hd, s = pose_fields(cum, shape, heading_prev)
    out = {"matrix": cum.ravel().tolist(), "x": x, "y": y, "heading": hd, "scale": s}
    if mpp:
        out["x_m"], out["y_m"] = metric_position(out, shape, mpp)
    if prev_cum is not None:
        pm = compose(cum, invert_matrix(np.asarray(prev_cum, float).reshape(2, 3)))
        c = frame_centre(shape)
        px, py, ps, pa = matrix_to_pose(pm, c)
        out.update(dx=float(px - c[0]), dy=float(py - c[1]),
                   rotation=wrap_angle(pa, low=-180.0), scale_change=float(ps),
                   pair_matrix=pm.ravel().tolist())
    return out


class Totals:
    """The summary's counts, updated row by row (the rows themselves are not kept)."""

    def __init__(self):
        self.frames = self.measured = self.flagged = self.unreadable = self.assumed = 0
        self.methods: dict = {}
        self.refs: set = set()
        self.length = 0.0
        self.last_xy = None
        self.end = None
        self.ms_sum, self.ms_n = 0.0, 0
        self.after_gap: list = []
        #: the smallest and largest scale of the measured poses (the first
        #: one's: 1), and the frames where they were
        self.scales = None

    def add(self, r):
        self.frames += 1
        if str(r.get("flags") or "").startswith("after_gap"):
            self.after_gap.append(r["index"])
        self.measured += r["status"] == "measured"
        self.flagged += bool(r.get("flags"))
        self.unreadable += r["status"] == "unreadable"
        self.assumed += r["status"] == "assumed"
        if r.get("method"):
            self.methods[r["method"]] = self.methods.get(r["method"], 0) + 1
        if r.get("ref") is not None:
            self.refs.add(r["ref"])
        if r.get("x") is not None:
            # the path joins the measured poses (an assumed one, carried on
            # from the last measured, would add motion that did not happen)
            if r["status"] != "assumed":
                sc = r.get("scale")
                if sc is not None and math.isfinite(sc) and sc > 0:
                    seen = self.scales or [(sc, r["index"])] * 2
                    self.scales = [min(seen[0], (sc, r["index"])), max(seen[1], (sc, r["index"]))]
                if self.last_xy is not None:
                    self.length += math.hypot(r["x"] - self.last_xy[0], r["y"] - self.last_xy[1])
                self.last_xy = (r["x"], r["y"])
            self.end = {"index": r["index"], "status": r["status"], "x": r["x"], "y": r["y"],
                        "heading": r["heading"], "scale": r["scale"], "x_m": r.get("x_m"),
                        "y_m": r.get("y_m")}
        if r.get("ms") is not None:
            self.ms_sum += r["ms"]
            self.ms_n += 1


def plot_track(csv_path, path: Path, metric: bool):
    """The trajectory picture; only the columns drawn are read back from the CSV."""
    from ..viz import plot_trajectory

    plot_rows = [{"x": r.get("x"), "y": r.get("y"), "x_m": r.get("x_m"), "y_m": r.get("y_m"),
                  "heading": r.get("heading"), "flags": r.get("flags"),
                  "status": r.get("status")}
                 for r in iter_odometry_csv(csv_path)]
    plot_trajectory(plot_rows, path, unit="m" if metric else "px")
    return path


#: The most metres a pixel may cover: a photo 1,000 px wide over 10 km of seabed.
MAX_METRES_PER_PIXEL = 10.0


def resolve_metres_per_pixel(metres_per_pixel, altitude, focal_px):
    def pos(name, v):
        return number(name, v, lo=0.0, lo_open=True)

    def sane(mpp, how):   # (a user's altitude in mm gave 53.6 km for 4 s of survey)
        if not (math.isfinite(mpp) and 0.0 < mpp <= MAX_METRES_PER_PIXEL):
            raise ParameterError(f"{how} = {mpp:.3g} m a pixel: must be over 0 and at most "
                                 f"{MAX_METRES_PER_PIXEL:g} (an altitude in millimetres, or a "
                                 "focal length in mm rather than pixels?)")
        return mpp

    if metres_per_pixel is not None:
        if altitude is not None or focal_px is not None:
            given = ", ".join(n for n, v in (("altitude", altitude), ("focal_px", focal_px))
                              if v is not None)
            raise ParameterError(f"give metres_per_pixel, or altitude with focal_px, not both "
                                 f"(got metres_per_pixel={metres_per_pixel!r} and {given})")
        return sane(pos("metres_per_pixel", metres_per_pixel), "metres_per_pixel")
    if altitude is None and focal_px is None:
        return None
    if altitude is None or focal_px is None:
        raise ParameterError("altitude and focal_px go together (metres per pixel = "
                             "altitude / focal_px for a down-looking camera)")
    return sane(pos("altitude", altitude) / pos("focal_px", focal_px), "altitude / focal_px")


def summarise(t: Totals, items, mpp, scale_range, angle_range, cfg, tuning, n_resumed, wall_s,
             metres_per_pixel, altitude, focal_px, source=None) -> dict:
    """The run's summary.json (``source``: the frames as the run was given
    them, when a folder or a video: its path; else the first frame's)."""
    length = t.length
    mean_ms = t.ms_sum / t.ms_n if t.ms_n else None
    src = items[0] if len(items) and not isinstance(items[0], np.ndarray) else "arrays"
    if source is not None:
        src = source
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
        "after_gap": list(t.after_gap),
        "scale_seen": None if t.scales is None else {
            "min": t.scales[0][0], "min_frame": t.scales[0][1],
            "max": t.scales[1][0], "max_frame": t.scales[1][1]},
        "mean_ms_per_frame": mean_ms,
        "resumed_rows": n_resumed,
        "wall_s": wall_s,
        "settings": {
            "source": str(src) if not isinstance(src, str) else src,
            "metres_per_pixel": mpp, "given_metres_per_pixel": metres_per_pixel,
            "altitude": altitude, "focal_px": focal_px,
            "scale_range": list(scale_range), "angle_range": list(angle_range),
            "tuning": asdict(tuning),
            "config": asdict(cfg),
        },
    }
    return s
