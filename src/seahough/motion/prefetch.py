"""The coming frames of a dead-reckoning run, prepared ahead in worker threads.

The chain of pairs is sequential (each frame is measured against a keyframe
chosen from the previous results), but what a frame needs before its
searches does not depend on them: reading and decoding it, its grey
conversion, the crop to the content box and its features. :class:`Prefetch`
does that for the next frames in ``workers - 1`` threads (the run's own
thread measures the pairs), at most ``2 * workers`` frames ahead, so memory
stays bounded. The compiled kernels release the GIL, as do OpenCV's decoders
and filters, so the threads run on other cores. Every frame is prepared by
the same functions whichever thread runs them, so the rows are identical to
a run with one worker (which prepares each frame when it comes, in its own
thread, as before).

>>> import numpy as np
>>> from seahough.io.frames import FrameReader
>>> frames = [np.full((80, 80), v, np.uint8) for v in (10, 20, 30)]
>>> with Prefetch(FrameReader(frames, 10 ** 6), 0, max_pixels=10 ** 6,
...               max_memory_mb=100, workers=2) as ahead:
...     [int(ahead.get(i).gray[0, 0]) for i in range(3)]
[10, 20, 30]
"""

from __future__ import annotations

import threading
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..core.features import Features
from ..errors import ImageError
from ..io.frames import FrameReader
from ..io.images import to_gray
from .framing import check_motion_size

__all__ = ["Prefetch", "Prepared", "overlapped"]


@dataclass
class Prepared:
    """A frame read and prepared for measuring.

    ``error`` says why it is unreadable (its pixels are then None);
    ``gray`` is the whole grey frame until it is cropped, then the crop to
    ``box`` (the content box it was cropped to), with its ``features``
    when they were asked for (see :meth:`Prefetch.use`).
    """

    index: int
    frame_hash: str
    shape: tuple | None = None
    gray: np.ndarray | None = None
    error: str | None = None
    box: tuple | None = None
    features: Features | None = None


def read_frame(reader: FrameReader, i: int, max_pixels: int, max_memory_mb: float,
               bit_depth: int | None = None) -> Prepared:
    """Frame ``i`` read, its fingerprint (``--resume``) and grey image, or
    why it cannot be measured (unreadable, too small)."""
    frame_hash = None
    try:
        raw = reader.raw(i)
        frame_hash = reader.fingerprint(i, raw)
        gray = to_gray(raw, max_pixels=max_pixels, max_memory_mb=max_memory_mb,
                       bit_depth=bit_depth,   # (a warning about it names the file)
                       name="image" if reader.is_array(i) else str(reader.items[i]))
        del raw
        check_motion_size(gray.shape, "frame")
    except (ImageError, OSError) as e:
        if frame_hash is None:
            frame_hash = reader.fingerprint(i)
        msg = " ".join(str(e).split())
        if not reader.is_array(i):
            msg = msg.replace(str(reader.items[i]) + ": ", "")
        return Prepared(i, frame_hash, error=msg)
    return Prepared(i, frame_hash, gray.shape, gray)


class Prefetch:
    """Frames ``start, start + 1, ...`` of ``reader``, prepared ahead.

    Parameters
    ----------
    reader : FrameReader
        The run's frames. Frames of a video are read one after the other,
        in order (its decoder is sequential); files and arrays at once.
    start : int
        The first frame asked for; :meth:`get` is then called with each
        index in turn.
    max_pixels, max_memory_mb
        The limits of :func:`~seahough.to_gray` (``Config``'s).
    workers : int
        1: each frame is prepared when asked for, in the caller's thread;
        more: ``workers - 1`` threads prepare the coming frames, at most
        ``2 * workers`` ahead.
    """

    def __init__(self, reader: FrameReader, start: int, *, max_pixels: int,
                 max_memory_mb: float, workers: int = 1, bit_depth: int | None = None):
        self.reader = reader
        self.limits = (max_pixels, max_memory_mb, bit_depth)
        self.searcher = None
        self.shape = None
        self._next = start                 # the next index to submit
        self._n = len(reader.items)
        self._ahead = 2 * workers
        self._pool = (ThreadPoolExecutor(max(workers - 1, 1), thread_name_prefix="seahough-frames")
                      if workers > 1 else None)
        self._pending: deque[Future] = deque()
        # video frames: read one at a time, in order (a lock, and a turn)
        self._turn = threading.Condition()
        self._video_done = 0
        self._video_pos: dict[int, int] = {}
        if self._pool is not None:
            k = 0
            for i in range(start, self._n):
                if reader.is_video(i):
                    self._video_pos[i] = k
                    k += 1

    def use(self, searcher, shape) -> None:
        """Crop the frames of ``shape`` (the first readable frame's: the
        others are flagged by the caller) to ``searcher.box`` and compute
        their features (``searcher.features``) from now on; known once the
        first readable frame is (frames prepared before are finished in
        :meth:`finish`)."""
        self.searcher = searcher
        self.shape = tuple(shape)

    def raw(self, i: int) -> np.ndarray:
        """Frame ``i`` as stored, read in the caller's thread (resume: the
        frames the state refers to), never at the same time as a video
        frame ahead."""
        with self._turn:
            return self.reader.raw(i)

    def _prepare(self, i: int, searcher) -> Prepared:
        pos = self._video_pos.get(i)   # (only with threads)
        if pos is None:
            prep = read_frame(self.reader, i, *self.limits)
        else:
            with self._turn:
                self._turn.wait_for(lambda: self._video_done >= pos)
                try:
                    prep = read_frame(self.reader, i, *self.limits)
                finally:
                    self._video_done += 1
                    self._turn.notify_all()
        if searcher is not None and prep.gray is not None and tuple(prep.shape) == self.shape:
            self.finish(prep, searcher, features=True)
        return prep

    @staticmethod
    def finish(prep: Prepared, searcher, features: bool) -> Prepared:
        """Crop ``prep`` to ``searcher.box`` (if not yet) and compute its
        features (with ``features``, if not yet). Returns ``prep``."""
        if prep.gray is None:
            return prep
        if prep.box != searcher.box:
            prep.gray = searcher.crop(prep.gray)
            prep.box = searcher.box
        if features and prep.features is None:
            prep.features = searcher.features(prep.gray)
        return prep

    def _submit(self) -> None:
        while self._next < self._n and len(self._pending) < self._ahead:
            self._pending.append(self._pool.submit(self._prepare, self._next, self.searcher))
            self._next += 1

    def get(self, i: int) -> Prepared:
        """Frame ``i`` (the next index in turn): read, grey, and cropped and
        with its features once :meth:`use` was called. Errors other than an
        unreadable frame are raised here, as when not prefetched."""
        if self._pool is None:
            self._next = i + 1
            return self._prepare(i, None)
        if not self._pending:
            self._next = i
        self._submit()
        prep = self._pending.popleft().result()
        if prep.index != i:  # pragma: no cover - a caller's bug
            raise RuntimeError(f"frame {i} asked for, frame {prep.index} prepared")
        self._submit()
        return prep

    def close(self) -> None:
        """Stop the threads (what has not started is dropped)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pending.clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def overlapped(tasks, workers: int) -> list:
    """The results of the functions ``tasks`` (no arguments), in their
    order: run at once in threads when ``workers`` > 1 (e.g. the mosaic
    and the trajectory of a run), else one after the other. The first
    error, in their order, is raised once all are done.

    >>> overlapped((lambda: 1, lambda: 2), workers=2)
    [1, 2]
    """
    if workers <= 1 or len(tasks) <= 1:
        return [t() for t in tasks]
    with ThreadPoolExecutor(min(workers, len(tasks)),
                            thread_name_prefix="seahough-outputs") as pool:
        futures = [pool.submit(t) for t in tasks]
    return [f.result() for f in futures]
