"""``survey detect``: one pattern in many photos, on a Dask cluster, into Parquet.

The client prepares a :class:`~seahough.Detector` (its pattern's features
computed for the first image's size) and sends it to the cluster once, as
the result of a task: each worker fetches it once and keeps it, and a
worker that dies and comes back gets it again (a scattered object would be
lost with the last worker holding it). The images go in batches of paths
(16 at most per task): workers read the images themselves, and send back
only their rows. The client writes the rows in shards (see
:mod:`._shards`): a rerun into the same folder searches only what is not
done yet, and never writes a row twice.

Statuses of an image: ``found`` (at least one detection), ``not found``,
``error`` (the file could not be read or searched: ``error`` says why, as
``seahough detect`` prints it; or its worker process died each time it
searched it, :data:`DIED`).
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import sys
import time
import warnings
import weakref
from dataclasses import dataclass
from pathlib import Path

from .._validate import number
from ..config import config_record
from ..core.detector import Detector
from ..core.pattern import Pattern
from ..core.candidates import best_declined
from ..errors import (BitDepthWarning, LevelsWarning, ParameterError, SeahoughError,
                      without_name)
from ._cluster import open_client
from ._inputs import expand_inputs
from ._shards import SurveyFolder, image_row

__all__ = ["detect", "SurveyResult", "detector_settings"]

#: A shard is written when this many images' rows are waiting ...
SHARD_IMAGES = 1024
#: ... or when the oldest waits for this long (seconds): what a killed run redoes.
SHARD_SECONDS = 30.0
#: Most images per task (fewer when there are too few for every worker).
MAX_BATCH = 16


@dataclass(frozen=True)
class SurveyResult:
    """What :func:`detect` wrote, and the counts.

    Attributes
    ----------
    images, detections, manifest : Path
        ``images.parquet``, ``detections.parquet`` and ``survey.json``.
    total, found, not_found, errors : int
        Images in the survey, and how many have each status.
    n_detections : int
        Rows of ``detections.parquet``.
    processed : int
        Images searched by this call (0: the survey was complete already).
    seconds : float
        Wall time of this call.
    """

    images: Path
    detections: Path
    manifest: Path
    total: int
    found: int
    not_found: int
    errors: int
    n_detections: int
    processed: int
    seconds: float


# ----------------------------------------------------------------- settings
def _pattern_digest(p: Pattern) -> str:
    """32 hex digits naming the pattern's content (image, mask, origin, ...)."""
    h = hashlib.blake2b(digest_size=16)
    gray = getattr(p, "_gray", p.image)
    for a in (gray, getattr(p, "_colour", None), p.mask, getattr(p, "_edge_mask", None),
              *p.outline):
        if a is not None:
            h.update(repr((a.shape, a.dtype.str)).encode())
            h.update(a.tobytes())
    h.update(repr((p.origin, p.polarity, p.kind, p.closed, getattr(p, "line_length", None),
                   getattr(p, "line_width", None))).encode())
    return h.hexdigest()


def detector_settings(detector: Detector) -> dict:
    """Everything that changes a survey's rows, as plain JSON values.

    >>> s = detector_settings(Detector(Pattern.rectangle(60, 40), (0.8, 1.2)))
    >>> s["scale_range"], s["pattern"]["kind"], len(s["pattern"]["digest"]), s["max_nfa"]
    ([0.8, 1.2], 'rectangle', 32, 1.0)
    >>> detector_settings(Detector(Pattern.rectangle(60, 40), max_nfa=math.inf))["max_nfa"]
    'inf'
    """
    if detector.parts:   # several patterns: each one's own settings
        return {"patterns": {name: detector_settings(d) for name, d in detector.parts.items()},
                "config": config_record(detector.config)}
    p = detector.pattern
    sr = detector.search_region
    return {"pattern": {"kind": p.kind, "size": list(p.image.shape[::-1]),
                        "origin": list(p.origin), "polarity": p.polarity,
                        "digest": _pattern_digest(p)},
            "scale_range": [float(v) for v in detector.scale_range],
            "angle_range": [float(v) for v in detector.angle_range],
            "max_results": detector.max_results, "min_score": detector.min_score,
            "min_confidence": detector.min_confidence,
            # (no limit as "inf": JSON has no infinity)
            "max_nfa": detector.max_nfa if math.isfinite(detector.max_nfa) else "inf",
            "search_region": None if sr is None else list(sr),
            "config": config_record(detector.config)}


def _as_detector(pattern, options: dict) -> Detector:
    given = {k: v for k, v in options.items() if v is not None}
    if isinstance(pattern, Detector):
        if given:
            raise ParameterError(f"{', '.join(sorted(given))}: give the search options to the "
                                 "Detector, or a Pattern with them, not both")
        return pattern
    if not isinstance(pattern, Pattern):
        raise ParameterError(f"pattern must be a seahough.Pattern or Detector, got "
                             f"{type(pattern).__name__}")
    return Detector(pattern, **given)


def _prepare(detector: Detector, path: str) -> None:
    """Compute the pattern's features on the client for the size of the
    image at ``path`` (read from its header; nothing when it cannot be), so
    that workers receive them ready; a pattern that cannot be searched at
    that size fails here, once, rather than in every image."""
    try:
        from PIL import Image

        with Image.open(path) as im:
            w, h = im.size
    except Exception:           # unreadable: its row will say why
        return
    for d in (detector.parts or {"": detector}).values():
        cfg = d.config    # (each pattern's: its colour is its own)
        factor = d.working_factor((h, w))
        d.pattern.features(factor, cfg)
        d.pattern.finish_points(factor, cfg)


# ------------------------------------------------------------------ workers
def _message(exc: BaseException, path: str) -> str:
    """What went wrong, without a leading copy of the file name (as
    ``seahough detect`` prints it after the name)."""
    if isinstance(exc, SeahoughError):
        return without_name(exc, path)
    return f"{type(exc).__name__}: {exc}"


def _hold(detector: Detector) -> Detector:
    """The task whose result is the Detector each worker fetches once."""
    return detector


#: The Detectors this process has searched with: its first search loads the
#: compiled kernels (about 300 ms), which is no image's time.
_WARM: "weakref.WeakSet[Detector]" = weakref.WeakSet()


def _warm_up(detector: Detector, path: str) -> None:
    """Search the image at ``path`` once, untimed and its answer dropped, so
    that the first image's ``ms`` is its own. An image that cannot be read
    or searched warms nothing: the next one is tried (the timed search
    after says what went wrong). The cost: one more search of one image per
    worker process and Detector (a worker receives the Detector once)."""
    from ..io.images import read_image

    cfg = detector.config
    try:
        detector.search(read_image(path, max_pixels=cfg.max_pixels,
                                   max_memory_mb=cfg.max_memory_mb), name=path)
    except Exception:  # noqa: BLE001 - (the timed search says it)
        return
    _WARM.add(detector)


def _one_line_warnings() -> None:
    """On a worker: seahough's warnings about an input (each names its file)
    one line each, as ``seahough detect`` says them (they came out in
    Python's form, from Dask's source line); others as Python shows them.
    Process-wide, once (a worker's threads share it)."""
    if getattr(warnings.showwarning, "_seahough", False):
        return
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, (BitDepthWarning, LevelsWarning)):
            print(f"seahough: warning: {' '.join(str(message).split())}", file=sys.stderr,
                  flush=True)
        else:
            shown(message, category, filename, lineno, file, line)
    show._seahough = True
    warnings.showwarning = show


def search_batch(batch: list, detector: Detector) -> tuple[list, list]:
    """Search the images of ``batch`` (``(index, path)`` pairs), on a worker.

    Returns the rows of images.parquet (without the path: the client adds
    it) and of detections.parquet (likewise), small enough to send back.
    An image that cannot be read or searched is an ``error`` row.
    """
    from ..io.images import read_image

    cfg = detector.config
    rows, dets = [], []
    _one_line_warnings()
    for index, path in batch:
        if detector not in _WARM:
            _warm_up(detector, path)
        t0 = time.perf_counter()
        try:
            img = read_image(path, max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb)
            res = detector.search(img, name=path)
        except Exception as e:  # noqa: BLE001 - one image must not stop a survey
            ms = 1000.0 * (time.perf_counter() - t0)
            rows.append(image_row(index, None, "error", 0, ms, error=_message(e, path)))
            continue
        ms = 1000.0 * (time.perf_counter() - t0)
        h, w = img.shape[:2]
        found = res.detections
        rows.append(image_row(index, None, "found" if found else "not found", len(found), ms,
                              int(w), int(h), res.note, left_out=res.left_out,
                              best=None if found or res.note else best_declined(res)))
        for rank, d in enumerate(found, 1):
            m = [float(v) for v in d.matrix.ravel()]
            nfa = float(d.nfa) if math.isfinite(d.nfa) else None
            dets.append((index, None, rank, d.x, d.y, d.scale, d.angle, d.score, d.confidence,
                         nfa, m, float(d.votes), d.kind, d.line_angle, d.line_offset,
                         list(d.flags), d.pattern,
                         None if d.segment is None else [float(v) for v in d.segment.ravel()],
                         *(([[float(v) for v in st.ravel()] for st in d.stretches],
                             d.to_dict().get("width")) if d.kind == "line" else (None, None))))
    return rows, dets


# ------------------------------------------------------------------- client
def _batch_size(n: int, workers: int, given) -> int:
    """Images per task: at most :data:`MAX_BATCH`, and few enough that every
    worker has about 8 tasks.

    >>> _batch_size(1000, 2, None), _batch_size(20, 2, None), _batch_size(5, 2, 3)
    (16, 2, 3)
    """
    if given is not None:
        return int(number("batch_size", given, lo=1, integer=True))
    return max(1, min(MAX_BATCH, math.ceil(n / (8 * max(workers, 1)))))


class _Pending:
    """Rows received and not yet in a shard."""

    def __init__(self, folder: SurveyFolder, paths: list[str]):
        self.folder, self.paths = folder, paths
        self.rows: list = []
        self.dets: list = []
        self.since = time.monotonic()

    def add(self, rows, dets) -> None:
        if not self.rows:
            self.since = time.monotonic()
        self.rows += [(r[0], self.paths[r[0]], *r[2:]) for r in rows]
        self.dets += [(d[0], self.paths[d[0]], *d[2:]) for d in dets]

    def due(self) -> bool:
        return (len(self.rows) >= SHARD_IMAGES
                or (self.rows and time.monotonic() - self.since >= SHARD_SECONDS))

    def flush(self) -> None:
        if self.rows:
            self.folder.write_part(self.rows, self.dets)
            self.rows, self.dets = [], []


def _progress_bar(total: int, initial: int, enabled: bool):
    """A tqdm bar on stderr when it is a terminal (and ``enabled``)."""
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc="survey", unit="img", file=sys.stderr,
                disable=None, leave=False, dynamic_ncols=True)


#: The row of an image whose worker process died each time it was searched.
DIED = ("the worker process died each time it searched this image (out of memory, or a "
        "crash in a library)")


def _run(client, detector, paths, todo, folder, batch_size, progress, on_batch) -> int:
    """Search the images ``todo`` on the cluster; rows into shards as they
    come. Returns how many were searched (all, unless interrupted).

    A batch whose workers died each time Dask ran it (``KilledWorker``:
    an image that exhausts memory or crashes a library) is run again one
    image a task; an image that still kills its worker is run alone once
    more (a dying worker also fails the task queued beside it), then gets
    an ``error`` row, and the survey goes on.
    """
    from distributed import KilledWorker, as_completed
    from distributed.client import FutureCancelledError

    # (worker threads: every thread takes a batch; scheduler_info() lists at
    # most 5 workers in some distributed releases, dask/distributed#9045)
    n_workers = sum(client.nthreads().values())
    size = _batch_size(len(todo), n_workers, batch_size)
    batches = [[(i, os.path.abspath(paths[i])) for i in todo[k:k + size]]
               for k in range(0, len(todo), size)]
    held = client.submit(_hold, detector, pure=False)
    pending = _Pending(folder, paths)
    total, done = len(paths), len(paths) - len(todo)
    bar = _progress_bar(total, done, progress)
    searched = 0
    retried: set = set()          # images run alone a second time after a dead worker

    def lost(why) -> SeahoughError:
        return SeahoughError(f"{folder.path}: the cluster went away ({why}); the "
                             f"{done + searched} images done are kept: run again to continue")

    try:
        futures = client.map(search_batch, batches, detector=held, pure=False)
        batch_of = {f.key: b for f, b in zip(futures, batches)}
        # (results fetched one by one, not with_results=True: its background
        # gathers can lose one and leave the loop waiting for ever,
        # dask/distributed#7331; seen here on a 10,000-photo survey)
        results = as_completed(futures, loop=client.loop)
        del futures, batches
        for fut in results:
            batch = batch_of.pop(fut.key)
            try:
                if fut.status == "cancelled":
                    raise lost("its tasks were cancelled: scheduler restarted or unreachable")
                if fut.status == "error":
                    exc = fut.exception()
                    if not isinstance(exc, KilledWorker):
                        raise SeahoughError(
                            f"{batch[0][1]}: the search failed on a worker "
                            f"({type(exc).__name__}: {exc}); is the same seahough installed "
                            "there? The images done are kept: run again to continue") from exc
                    # a batch: its images one a task; an image alone: once more (a
                    # worker dying took the task queued beside it too), then DIED
                    if len(batch) > 1 or batch[0][0] not in retried:
                        retried.update(item[0] for item in batch if len(batch) == 1)
                        for item in batch:
                            f = client.submit(search_batch, [item], detector=held, pure=False)
                            batch_of[f.key] = [item]
                            results.add(f)
                        continue
                    res = ([image_row(batch[0][0], None, "error", error=DIED)], [])
                else:
                    res = fut.result()
            except (FutureCancelledError, OSError) as e:   # (CommClosedError is an OSError)
                raise lost(f"{type(e).__name__}: {e}") from None
            rows, dets = res
            pending.add(rows, dets)
            searched += len(rows)
            if pending.due():
                pending.flush()
            if bar is not None:
                bar.update(len(rows))
            if on_batch is not None:
                on_batch(done + searched, total)
    finally:
        # what came before an error or an interruption is kept
        pending.flush()
        if bar is not None:
            bar.close()
    return searched


def detect(pattern, images, out, *, workers: int | None = None, scheduler: str | None = None,
           scale_range=None, angle_range=None, config=None, max_results=None, min_score=None,
           min_confidence=None, max_nfa=None, search_region=None, batch_size: int | None = None,
           progress: bool = True, on_batch=None, retry_errors: bool = False) -> SurveyResult:
    """Find ``pattern`` in every image of ``images``, on a Dask cluster; the
    results in ``out/images.parquet`` and ``out/detections.parquet``.

    Parameters
    ----------
    pattern : Pattern or Detector
        What to look for; a Detector carries its search options.
    images : path or list of paths
        Image files, folders (their images) and ``@LIST`` files (one path a
        line); see :func:`~seahough.survey._inputs.expand_inputs`.
    out : path
        The output folder. A rerun with the same settings and images
        searches only the images not done yet (none when complete); with
        the same images and more after them (a folder a dive is still
        adding to), those too; with other settings or images it is refused.
    workers : int, optional
        Worker processes of the local cluster (default: all cores).
    scheduler : str, optional
        Address of a running Dask scheduler to use instead (``workers`` is
        then ignored); its workers must read the images at the same paths.
    scale_range, angle_range, config, max_results, min_score, min_confidence, max_nfa, search_region
        The search options of :class:`~seahough.Detector` (its defaults
        when not given).
    batch_size : int, optional
        Images per task (default: at most 16, fewer for short surveys).
    progress : bool
        A progress bar on stderr when it is a terminal.
    on_batch : callable, optional
        Called as ``on_batch(done, total)`` (images) after each batch's
        rows arrive; an exception it raises stops the survey, the rows
        received so far kept.
    retry_errors : bool
        Search again the images of a rerun that could not be read or
        searched before (status ``error``: a file system that was away, a
        file still being copied).

    Returns
    -------
    SurveyResult

    Raises
    ------
    ParameterError
        Bad options, no images, ``out`` holding another survey, Dask
        missing, or no scheduler at ``scheduler``.
    PatternError
        The pattern cannot be searched at the first image's size.
    WriteError
        ``out`` cannot be written, or another run is writing it.

    Examples
    --------
    Run it from a script's ``if __name__ == "__main__":`` block (the local
    cluster starts processes)::

        import seahough
        from seahough import survey

        if __name__ == "__main__":
            r = survey.detect(seahough.Pattern.rectangle(90, 50), ["dive/"], "found",
                              scale_range=(0.5, 2.0))
            print(r.found, "of", r.total, "images:", r.images)
    """
    t0 = time.perf_counter()
    detector = _as_detector(pattern, {
        "scale_range": scale_range, "angle_range": angle_range, "config": config,
        "max_results": max_results, "min_score": min_score, "min_confidence": min_confidence,
        "max_nfa": max_nfa, "search_region": search_region})
    paths = expand_inputs(images)
    settings = detector_settings(detector)
    if batch_size is not None:
        _batch_size(1, 1, batch_size)
    _prepare(detector, os.path.abspath(paths[0]))
    searched = 0
    with SurveyFolder(out) as folder:
        new = not folder.manifest.exists()
        done = folder.start(settings, paths)
        if folder.moved:    # (the rows' paths as the survey's list has them)
            paths = [os.path.abspath(p) for p in paths]
        if retry_errors and folder.forget_errors():
            done = folder.done()
        todo = [i for i in range(len(paths)) if i not in done]
        if todo:
            with contextlib.ExitStack() as stack:
                try:
                    client = stack.enter_context(open_client(workers, scheduler))
                except BaseException:
                    if new:   # (a bad --scheduler must not leave a survey that refuses the fix)
                        folder.discard_new()
                    raise
                searched = _run(client, detector, paths, todo, folder, batch_size, progress,
                                on_batch)
        counts = folder.finish()
    return SurveyResult(folder.images, folder.detections, folder.manifest, counts["images"],
                        counts["found"], counts["not_found"], counts["errors"],
                        counts["detections"], searched, time.perf_counter() - t0)
