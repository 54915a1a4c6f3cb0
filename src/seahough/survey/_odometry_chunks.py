"""The chunks of a survey's dead reckoning: which frames each one holds, and
the task a worker runs on one.

A chunk is :data:`OVERLAP` frames longer than its share of the sequence: it
starts on the last frames of the one before, so that the two can be joined
on a frame measured in both (:mod:`._odometry_chain`). Each chunk is a
:func:`~seahough.run_odometry` run of its own (its own keyframes) in
``OUT/chunks/NNNNN/``: a run folder as any other, locked while written,
resumed when a run was cut short, kept when finished.
"""

from __future__ import annotations

import errno
import inspect
import json
import os
import time
from pathlib import Path

import numpy as np

from ..errors import ImageError, ParameterError, WriteError
from ..io.frames import FrameReader, split_video_ref
from ..io.images import to_gray
from ..motion.odometry import run_odometry
from ..motion.runfiles import LOCK_NAME, RunFolder, check_kept_row, run_settings, settings_hash
from ..motion.track import closing_enumerate, iter_odometry_csv

try:                                  # POSIX; elsewhere runs are not locked
    import fcntl
except ImportError:                   # pragma: no cover
    fcntl = None

__all__ = ["OVERLAP", "plan_chunks", "chunk_folder", "run_chunk"]

#: Frames two consecutive chunks share: one bad frame among them (unreadable,
#: or of somewhere else) still leaves a frame measured in both to join on.
OVERLAP = 3
#: How long a chunk's task waits for a run still writing its folder (a copy
#: of the task that the scheduler took for lost but that is still running).
LOCK_WAIT_S = 3600.0
#: A stand-in for a listed frame that is no longer a file (deleted since it
#: was listed, a broken link): run_odometry refuses a list naming a missing
#: file, where a run over the folder flags the frame; the stand-in is an
#: image that cannot be used (an empty one), so that the chunk flags it too
#: (the client writes the row's real reason).
_GONE = np.zeros((0, 0), np.uint8)


def plan_chunks(n: int, chunk_size: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of each chunk of a sequence of ``n`` frames:
    ``chunk_size`` consecutive frames, the first :data:`OVERLAP` of each
    shared with the chunk before.

    >>> plan_chunks(10, 6)
    [(0, 6), (3, 9), (6, 10)]
    >>> plan_chunks(4, 6)
    [(0, 4)]
    """
    step = chunk_size - OVERLAP
    out, a = [], 0
    while True:
        b = min(a + chunk_size, n)
        out.append((a, b))
        if b >= n:
            return out
        a += step


def chunk_folder(out: Path, k: int) -> Path:
    """``OUT/chunks/NNNNN``.

    >>> chunk_folder(Path("run"), 7).as_posix()
    'run/chunks/00007'
    """
    return Path(out) / "chunks" / f"{k:05d}"


def chunk_settings_hash(scale_range, angle_range, config, tuning) -> str:
    """The settings hash of a chunk's run: the survey's settings without
    metres per pixel (which changes no measurement: the survey computes the
    metric columns when it chains, and a new altitude reuses the chunks)."""
    return settings_hash(run_settings(scale_range, angle_range, None, config, tuning))


def _gone(item) -> bool:
    """Would a list holding ``item`` be refused by ``list_frames`` (a path
    that is no file any more, or a folder)?"""
    if not isinstance(item, str):
        return False
    p = Path(item)
    return p.is_dir() or (not p.exists() and split_video_ref(item) is None)


def _lock_held(folder: Path) -> bool:
    """Does a live process hold ``folder``'s run lock? (``flock`` locks die
    with their process: a killed worker's lock is free at once.)"""
    if fcntl is None:
        return False
    try:
        fd = os.open(folder / LOCK_NAME, os.O_RDWR)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as e:
        return e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES)
    finally:
        os.close(fd)
    return False


def _finished(folder: Path, items, digest: str, config) -> bool:
    """Did an earlier run finish this chunk: its summary written, every
    frame's row in its CSV, the same settings and the same frames (names
    and contents, as ``resume`` checks them)?"""
    summary = folder / "summary.json"
    if not summary.is_file() or not (folder / "odometry.csv").is_file():
        return False
    with RunFolder(folder) as run:
        rec = run.read_settings()
        if rec is None or rec.get("settings_hash") != digest:
            return False
        try:
            if json.loads(summary.read_text()).get("frames") != len(items):
                return False
        except (OSError, ValueError, AttributeError):
            return False
        reader = FrameReader(items, config.max_pixels, config.max_memory_mb)
        n = 0
        try:
            for pos, row in closing_enumerate(iter_odometry_csv(run.csv)):
                if pos >= len(items):
                    return False
                check_kept_row(run.csv, pos, row, reader, digest, rec.get("cwd"))
                n += 1
        except ParameterError:
            return False
        finally:
            reader.close()
        return n == len(items)


def _origin_shape(folder: Path, items, config):
    """(h, w) of the chunk's first readable frame (its origin), or None."""
    reader = FrameReader(items, config.max_pixels, config.max_memory_mb)
    try:
        for row in iter_odometry_csv(folder / "odometry.csv"):
            if row["status"] != "unreadable":
                return to_gray(reader.raw(row["index"]), max_pixels=config.max_pixels,
                               max_memory_mb=config.max_memory_mb,
                               bit_depth=config.bit_depth).shape
    except (ImageError, OSError):
        return None
    finally:
        reader.close()
    return None


def _run(items, folder: Path, options: dict) -> dict:
    """run_odometry on the chunk, continuing a run cut short when it is
    this one (else measured again)."""
    kw = dict(options, progress=False, mosaic=False)
    if "workers" in inspect.signature(run_odometry).parameters:
        kw["workers"] = 1           # one thread a Dask worker: the cluster has the cores
    try:
        return run_odometry(items, folder, resume=True, **kw).summary
    except ParameterError:          # another run's rows (settings, frames): measure anew
        return run_odometry(items, folder, resume=False, **kw).summary


def first_shape(reader: FrameReader, config) -> tuple | None:
    """(h, w) of the first readable frame of ``reader``, or None: the size
    every frame of a run must have."""
    return next((sh for sh in (_shape_of(reader, i, config) for i in range(len(reader.items)))
                 if sh is not None), None)


def _odd_start(items: list, gone: list, shape, config) -> dict:
    """The frames at the start of a chunk, before its first readable frame
    of the survey's ``shape``, that are readable but of another size:
    ``{position: (h, w)}``. (The chunk's run would take the first of them as
    its origin and flag every frame of the survey's size.)"""
    odd: dict = {}
    if shape is None:
        return odd
    reader = FrameReader(items, config.max_pixels, config.max_memory_mb)
    try:
        for i in range(len(items)):
            if i in gone:
                continue
            got = _shape_of(reader, i, config)
            if got == tuple(shape):
                break
            if got is not None:
                odd[i] = got
    finally:
        reader.close()
    return odd


def _shape_of(reader: FrameReader, i: int, config):
    """(h, w) of frame ``i``, or None when it cannot be read."""
    try:
        return tuple(to_gray(reader.raw(i), max_pixels=config.max_pixels,
                             max_memory_mb=config.max_memory_mb,
                             bit_depth=config.bit_depth).shape)
    except (ImageError, OSError):
        return None


def run_chunk(k: int, start: int, items: list, folder: str, options: dict,
              shape=None) -> dict:
    """The task of chunk ``k`` (frames ``start...``), on a worker.

    ``options``: ``scale_range, angle_range, config, tuning`` of
    run_odometry. A chunk finished by an earlier run is kept as it is; one
    cut short (its worker killed) is resumed. Returns what the client needs
    to chain it: ``chunk``, ``start``, ``folder``, ``state`` ("kept",
    "measured"), ``resumed_rows`` (rows not measured by this task),
    ``shape`` (of its first readable frame, or None) and ``gone`` (frames
    no longer files, by position in the chunk), ``odd`` (frames before the
    chunk's first frame of the survey's ``shape`` that are of another size:
    set aside, as a run flags them, so that the chunk's origin has the
    survey's size).
    """
    folder = Path(folder)
    cfg = options["config"]
    gone = [i for i, it in enumerate(items) if _gone(it)]
    items = [_GONE if i in gone else it for i, it in enumerate(items)]
    odd = _odd_start(items, gone, shape, cfg)
    items = [_GONE if i in odd else it for i, it in enumerate(items)]
    digest = chunk_settings_hash(options["scale_range"], options["angle_range"], cfg,
                                 options["tuning"])
    deadline = time.monotonic() + LOCK_WAIT_S
    while True:
        try:
            if _finished(folder, items, digest, cfg):
                state, resumed = "kept", len(items)
            else:
                state = "measured"
                resumed = int(_run(items, folder, options).get("resumed_rows") or 0)
            break
        except WriteError:
            # another copy of this task still writing the folder: wait for it
            if not _lock_held(folder) or time.monotonic() > deadline:
                raise
            time.sleep(0.5)
    return {"chunk": k, "start": start, "folder": str(folder), "state": state,
            "resumed_rows": resumed, "n": len(items), "shape": _origin_shape(folder, items, cfg),
            "gone": gone, "odd": odd}
