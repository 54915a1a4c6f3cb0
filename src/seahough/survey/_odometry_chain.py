"""Chaining a survey's chunks into one trajectory: the one serial step.

Each chunk's rows give poses relative to the chunk's own first frame. The
chunks are taken in order; each is joined to the trajectory so far on a
frame both measured (the last such frame of their shared frames), so that
the join adds no error of its own: the frame's pose in the trajectory and
in the chunk fix the chunk's place. A chunk's rows before the join frame
are left out (the trajectory has them), those after it are placed by it.

A join must never invent a pose. A shared frame is usable only when it is
measured (or the origin) in both runs and the chunk's poses after it do not
go back, through the chunk's own keyframes, to an *assumed* pose before it
(a pose assumed there would be in no row of the trajectory). When no shared
frame is usable, the chunk's first readable frame is measured directly
against the trajectory's last measured frame (as run_odometry does across a
gap); when that fails too, its pose is assumed and flagged as run_odometry
flags one: the last measured pose carried on by the last measured motion per
frame (``pose_assumed: constant velocity since frame N``; with no motion
measured yet, ``pose_assumed: zero motion since frame N``), and the rest of
the chunk follows from it. A pose the chunk itself assumed with zero motion
(its run had not measured any motion yet: a failure in its first frames) is
assumed again with the trajectory's velocity when it has one, and the
chunk's poses measured from it move with it, as a single run would have
placed them.

Memory holds one chunk's rows at a time (plus the rows of the chunk before
that are not written yet: those after its last join candidate).
"""

from __future__ import annotations

import copy
import csv
import math
import re
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ImageError, PatternError, SeahoughError
from ..geometry import compose, invert_matrix, matrix_power, nearest_similarity
from ..core.pattern import Pattern
from ..motion.pair import estimate_motion
from ..motion.track import iter_odometry_csv, pose_columns, row_to_csv

__all__ = ["shift_flags", "read_chunk", "Chain", "measure_across"]

POSED = ("origin", "measured")
_ZERO = "pose_assumed: zero motion since frame "
_SINCE = re.compile(r"((?:pose_assumed: (?:zero motion|constant velocity) since|"
                    r"after_gap: measured against|duplicate: the same pixels as) frame )(\d+)")
_IDENTITY = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_PAIR = ("dx", "dy", "rotation", "scale_change", "pair_matrix")
_MEASURE = ("confidence", "nfa", "score", "overlap")


def shift_flags(flags: str, start: int) -> str:
    """A chunk row's flags with the frame numbers it names made global.

    >>> shift_flags("no_match; pose_assumed: constant velocity since frame 7", 400)
    'no_match; pose_assumed: constant velocity since frame 407'
    >>> shift_flags("little_overlap; pose_assumed: zero motion since frame 0", 400)
    'little_overlap; pose_assumed: zero motion since frame 400'
    >>> shift_flags("unreadable: frame 7 cannot be decoded", 400)    # the video's own number
    'unreadable: frame 7 cannot be decoded'
    >>> shift_flags("after_gap: measured against frame 15, whose pose was assumed", 20)
    'after_gap: measured against frame 35, whose pose was assumed'
    >>> shift_flags("duplicate: the same pixels as frame 4; pose_assumed: constant velocity "
    ...             "since frame 4", 10)
    'duplicate: the same pixels as frame 14; pose_assumed: constant velocity since frame 14'
    """
    return _SINCE.sub(lambda m: m.group(1) + str(int(m.group(2)) + start), flags)


def _unreadable_reason(reader, i: int) -> str:
    """What run_odometry writes after ``unreadable: `` for frame ``i``."""
    try:
        reader.raw(i)
    except (ImageError, OSError) as e:
        msg = " ".join(str(e).split())
        return msg.replace(str(reader.items[i]) + ": ", "")
    return "no such file when it was measured"


def read_chunk(folder, result: dict, reader, shape) -> list:
    """A chunk's rows with global values: ``index``, ``file`` (the name of
    the survey's frame: an array frame is numbered globally), ``ref`` and the
    frame numbers in ``flags``; ``_cum`` the chunk's cumulative matrix.

    A chunk whose first readable frame is not of the survey's size (that of
    its first readable frame) gets its frames flagged as a run flags a frame
    of another size: as unreadable, without a pose.
    """
    start = result["start"]
    gone = set(result.get("gone") or ())
    odd = result.get("odd") or {}
    other = result.get("shape") is not None and shape is not None and \
        tuple(result["shape"]) != tuple(shape)
    rows = []
    for r in iter_odometry_csv(folder / "odometry.csv"):
        local = r["index"]
        g = local + start
        r["index"] = g
        r["file"] = reader.name(g)
        r["time"] = reader.time(g)   # (a chunk's own reader numbers its frames from 0)
        r["_resumed"] = local < result.get("resumed_rows", 0)
        if r["ref"] is not None:
            r["ref"] += start
        r["flags"] = shift_flags(r["flags"], start)
        if local in gone:
            r["flags"] = "unreadable: " + _unreadable_reason(reader, g)
            r["frame_hash"] = reader.fingerprint(g)
        elif local in odd and shape is not None:     # (as a run flags a frame of another size)
            h, w = odd[local]
            r["flags"] = (f"unreadable: size {w}x{h} differs from the first frame's "
                          f"{shape[1]}x{shape[0]}")
            r["frame_hash"] = reader.fingerprint(g)
        if other and r["status"] != "unreadable":
            h, w = result["shape"]
            r.update({k: None for k in ("x", "y", "heading", "scale", "matrix", "ref",
                                        *_PAIR, *_MEASURE)})
            r.update(status="unreadable", method="",
                     flags=f"unreadable: size {w}x{h} differs from the first frame's "
                           f"{shape[1]}x{shape[0]}")
        r["_cum"] = None if r["matrix"] is None else np.asarray(r["matrix"], float).reshape(2, 3)
        rows.append(r)
    return rows


def _links(rows):
    """For each posed row: the row its pose was made from (``ref`` when
    measured, the last posed row when assumed, None for the origin), and its
    anchor: the last assumption (or the origin) on that path."""
    parent, anchor = {}, {}
    last = None
    for r in rows:
        i, status = r["index"], r["status"]
        if status == "unreadable":
            continue
        if status == "origin":
            parent[i], anchor[i] = None, i
        elif status == "assumed":
            parent[i], anchor[i] = last, i
        else:
            parent[i] = r["ref"]
            anchor[i] = anchor.get(r["ref"], i)
        last = i
    return parent, anchor


def _unjoined(rows, j: int, parent, anchor) -> set:
    """Posed rows after ``j`` whose pose, relative to ``j``'s, goes through an
    assumed pose at or before ``j`` that ``j``'s does not: placed by ``j``
    they would carry an assumption that no row of the trajectory shows.

    >>> rows = [{"index": 0, "status": "origin", "ref": None},
    ...         {"index": 1, "status": "assumed", "ref": None},
    ...         {"index": 2, "status": "measured", "ref": 0},
    ...         {"index": 3, "status": "measured", "ref": 1}]
    >>> parent, anchor = _links(rows)
    >>> sorted(_unjoined(rows, 2, parent, anchor))      # 3 was measured from 1 (assumed)
    [3]
    >>> sorted(_unjoined(rows, 1, parent, anchor))      # 2 goes back to 0, before 1
    [2]
    """
    bad, base = set(), {}
    for r in rows:
        f = r["index"]
        if f <= j or f not in parent:
            continue
        p = parent[f]
        b = p if p is None or p <= j else base.get(p)
        base[f] = b
        if b is None or anchor.get(b) != anchor[j]:
            bad.add(f)
    return bad


@dataclass
class _Cursor:
    """The trajectory as it stands after a row: its last posed row
    (index, global matrix, heading), last measured row, the row itself, and
    the last measured motion per frame (between two measured poses with no
    assumed one between them: an assumed pose never feeds it).

    >>> c = _Cursor()
    >>> for i, x in enumerate((0.0, -5.0, -10.0)):
    ...     c.update({"index": i, "status": "measured" if i else "origin", "heading": 0.0,
    ...               "_G": np.array([[1.0, 0.0, x], [0.0, 1.0, 0.0]])})
    >>> (np.round(c.vel, 6) + 0.0).tolist()
    [[1.0, 0.0, -5.0], [0.0, 1.0, 0.0]]
    """

    pose: tuple | None = None       # (index, G, heading)
    measured: tuple | None = None   # (index, G)
    prev: tuple | None = None       # (index, G or None)
    vel: np.ndarray | None = None   # motion per frame (frame-to-frame matrix)
    pose_measured: bool = False     # is ``pose`` a measured one (or the origin)?

    def update(self, r):
        g = r.get("_G")
        self.prev = (r["index"], g)
        if g is None:
            return
        measured = r["status"] in POSED
        if r["status"] == "origin":
            self.vel = None
        elif measured and self.pose is not None and self.pose_measured:
            self.vel = matrix_power(compose(g, invert_matrix(self.pose[1])),
                                    1.0 / max(r["index"] - self.pose[0], 1))
        self.pose = (r["index"], g, r["heading"])
        self.pose_measured = measured
        if measured:
            self.measured = (r["index"], g)


def measure_across(reader, p: int, q: int, scale_range, angle_range, config, tuning):
    """Frame ``p``'s motion into frame ``q`` (a full search with the per-frame
    ranges widened over the gap, as run_odometry's), judged by the run's
    thresholds (not by its number of false alarms, which run_odometry only
    reports): ``(Motion, "")`` or ``(None, reason)``."""
    n = q - p
    m = min(n, tuning.max_span)
    (s0, s1), (a0, a1) = scale_range, angle_range
    sr = (s0 ** n,) * 2 if s0 == s1 else (s0 ** m, s1 ** m)
    ar = (a0 * n,) * 2 if a0 == a1 else (a0 * m, a1 * m)
    if ar[1] - ar[0] > 360:
        ar = (-180.0, 180.0)
    # (the run's own confidence threshold: a pair the similarity cannot vouch
    # for is then measured tile by tile, as run_odometry's full searches are)
    kw = dict(max_shift=min(1.5, tuning.full_shift * m), min_score=tuning.min_score,
              max_nfa=math.inf, config=config)
    try:
        mo = estimate_motion(reader.raw(p), reader.raw(q), sr, ar,
                             min_confidence=tuning.min_confidence, **kw)
        if mo is None:   # why: no edges, nothing found, or nothing distinct enough
            try:   # (the earlier frame's edges: a join's pattern, built once more)
                Pattern.from_frame(reader.raw(p), config=config)
            except PatternError:
                return None, "few_edges"
            loose = estimate_motion(reader.raw(p), reader.raw(q), sr, ar, min_confidence=0.0,
                                    **kw)
            return None, "no_match" if loose is None else "low_confidence"
    except (SeahoughError, OSError):
        return None, "no_match"
    if mo.overlap < tuning.min_overlap:
        return None, "little_overlap"
    return mo, ""


class Chain:
    """The trajectory, built chunk by chunk (:meth:`add`), rows written in
    order as soon as no later chunk can replace them (:meth:`finish` writes
    the rest).

    Parameters
    ----------
    write : callable
        Called with each finished row (global values; ``row_to_csv`` writes it).
    shape : (h, w)
        Size of the survey's frames.
    mpp : float or None
        Metres per pixel (adds ``x_m, y_m``).
    measure : callable
        ``measure(p, q) -> (Motion or None, reason)``: a pair across a join
        (:func:`measure_across`).
    """

    def __init__(self, write, shape, mpp, measure):
        self.write = write
        self.shape = shape
        self.mpp = mpp
        self.measure = measure
        self.pending: list = []
        self.written = _Cursor()
        self.next_index = 0
        self.joins = {"exact": 0, "measured": 0, "assumed": 0, "none": 0}

    def add(self, rows: list) -> None:
        """Join the next chunk's rows (from :func:`read_chunk`) to the trajectory."""
        if not rows:
            return
        a = rows[0]["index"]
        p0 = self.pending[0]["index"] if self.pending else self.next_index
        pend = {r["index"]: r for r in self.pending}
        new = {r["index"]: r for r in rows}
        parent, anchor = _links(rows)
        lo = max(a, p0)
        join = None
        for j in range(max(pend, default=lo - 1), lo - 1, -1):     # the last usable one
            if j in pend and pend[j]["status"] in POSED and new[j]["status"] in POSED \
                    and not _unjoined(rows, j, parent, anchor):
                join = j
                break
        if join is not None:
            keep = [r for r in self.pending if r["index"] <= join]
            tail = [r for r in rows if r["index"] > join]
            x = compose(invert_matrix(new[join]["_cum"]), pend[join]["_G"])
            q, bad = None, set()
            self.joins["exact"] += 1
        else:
            q = next((r["index"] for r in rows if r["index"] >= lo and r["_cum"] is not None),
                     None)
            last = max(pend, default=p0 - 1)
            if q is None:                    # nothing posed in the chunk: nothing to join
                keep = list(self.pending)
                tail = [r for r in rows if r["index"] > last]
                self.joins["none"] += 1
            else:
                keep = [r for r in self.pending if r["index"] < q]
                tail = [r for r in rows if r["index"] > last or r["index"] >= q]
            bad = set() if q is None else _unjoined(rows, q, parent, anchor)
            x = None
        cursor = copy.copy(self.written)
        for r in keep:
            cursor.update(r)
            self.write(r)
        self.written = copy.copy(cursor)
        if q is not None:
            x = self._join(new[q], cursor)
        out = []
        rewritten_prev = False
        # a pose the chunk assumed with zero motion (before it had measured any
        # motion) is assumed again here with the trajectory's velocity, and the
        # chunk's poses made from it follow: {index: global correction}
        moved: dict = {}
        last_measured = None                           # (the chunk's, as its run saw it)
        for r in tail:
            i = r["index"]
            status = r["status"]
            rewritten = i == q
            if r["_cum"] is None:
                r["_G"] = None
            elif i == q:
                pass                                   # placed by _join
            elif i in bad:
                self._assume(r, cursor, "no_match")
                rewritten = True
            else:
                g = nearest_similarity(compose(r["_cum"], x))
                if status == "assumed" and _ZERO in r["flags"] and cursor.vel is not None:
                    self._assume(r, cursor, r["flags"].split(";")[0])
                    moved[i] = compose(invert_matrix(g), r["_G"])
                    rewritten = True
                else:
                    c = moved.get(r["ref"] if status == "measured" else
                                  last_measured if status == "assumed" else None)
                    if c is not None:
                        g = nearest_similarity(compose(g, c))
                        moved[i] = c
                        rewritten = True
                    r["_G"] = g
            if status in POSED:
                last_measured = i
            if r["_G"] is not None:
                prev = cursor.prev[1] if cursor.prev is not None and \
                    cursor.prev[0] == i - 1 else None
                heading = cursor.pose[2] if cursor.pose is not None else 0.0
                cols = pose_columns(r["_G"], self.shape, heading, self.mpp,
                                    prev if (rewritten or rewritten_prev) else None)
                if (rewritten or rewritten_prev) and prev is None:
                    r.update({k: None for k in _PAIR})
                r.update(cols)
            rewritten_prev = rewritten
            cursor.update(r)
            out.append(r)
        self.pending = out
        self.next_index = max(self.next_index, (out[-1]["index"] + 1) if out else 0)

    def _join(self, row, cursor: _Cursor) -> np.ndarray:
        """Place the chunk's frame ``row`` (its first usable one) after the
        trajectory's last frames: the origin when there is none, else
        measured against the last measured frame, else assumed; returns the
        chunk -> trajectory matrix."""
        t0 = time.perf_counter()
        row.update({k: None for k in (*_PAIR, *_MEASURE, "ref")}, method="", flags="")
        if cursor.pose is None:
            row["_G"] = _IDENTITY.copy()
            row["status"] = "origin"
            return invert_matrix(row["_cum"])
        else:
            p, g_p = cursor.measured
            mo, why = self.measure(p, row["index"])
            if mo is not None:
                row["_G"] = nearest_similarity(compose(mo.matrix, g_p))
                row.update(status="measured", ref=p, method="previous",
                           confidence=float(mo.confidence), nfa=float(mo.nfa),
                           score=float(mo.score), overlap=float(mo.overlap))
                self.joins["measured"] += 1
            else:
                self._assume(row, cursor, why)
                self.joins["assumed"] += 1
        row["ms"] = (row.get("ms") or 0.0) + 1000.0 * (time.perf_counter() - t0)
        return compose(invert_matrix(row["_cum"]), row["_G"])

    @staticmethod
    def _assume(row, cursor: _Cursor, why: str) -> None:
        """The row gets the trajectory's last measured pose carried on by the
        last measured motion per frame (zero motion when none is known),
        flagged as run_odometry flags it."""
        p, g = cursor.measured if cursor.measured is not None else cursor.pose[:2]
        if cursor.vel is not None:
            g = nearest_similarity(compose(matrix_power(cursor.vel, row["index"] - p), g))
            how = "constant velocity"
        else:
            g = g.copy()
            how = "zero motion"
        row.update({k: None for k in (*_PAIR, *_MEASURE, "ref")}, method="",
                   status="assumed", _G=g, flags=f"{why}; pose_assumed: {how} since frame {p}")

    def finish(self) -> None:
        """Write the rows still held."""
        for r in self.pending:
            self.write(r)
        self.pending = []


def csv_writer(f, columns, digest, totals):
    """``write(row)`` for :class:`Chain`: the row as a CSV line (its
    ``settings_hash`` that of the survey's settings), counted in ``totals``."""
    writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
    writer.writeheader()

    def write(row):
        row["settings_hash"] = digest
        writer.writerow(row_to_csv(row, columns))
        totals.add(row)

    return write
