"""``seahough survey odometry``: dead reckoning over a long sequence, its
pairs measured in parallel chunks on a Dask cluster, chained after.

The frames are listed once and cut into chunks of ``chunk_size``
consecutive frames, each sharing its first frames with the chunk before
(:data:`~seahough.survey._odometry_chunks.OVERLAP`). Each chunk is a
:func:`~seahough.run_odometry` run of its own on a worker (its own
keyframes) in ``OUT/chunks/NNNNN/``; once all are done the client chains
them, in order, into one trajectory (:mod:`._odometry_chain`): the same
``odometry.csv``, ``summary.json``, ``trajectory.png`` and ``mosaic.png`` as
``run_odometry`` writes.

A rerun with the same ``OUT`` keeps every chunk an earlier run finished
(same settings, same frames) and continues those cut short; a worker killed
mid-chunk has its chunk run again elsewhere, resumed from the rows it wrote
(its folder lock dies with it). Only the chaining is serial: a fraction of
a millisecond a frame (see ``docs/scale.md``).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from .._validate import number, pair
from ..config import ODOMETRY_CONFIG, Config, OdometryTuning
from ..core.accumulator import check_ranges
from ..errors import ParameterError, SeahoughError, WriteError
from .._values import json_safe
from ..io.frames import FrameReader, _pixels_fingerprint, list_frames, split_video_ref
from ..motion.mosaic import build_mosaic
from ..motion.runfiles import (RunFolder, check_kind, format_change, run_settings, settings_changes,
                               settings_hash, write_output)
from ..motion.track import (CSV_BASE, CSV_CHECK, CSV_METRIC, CSV_MORE, Totals, plot_track,
                            resolve_metres_per_pixel, summarise)
from ._cluster import open_client
from ._odometry_chain import Chain, csv_writer, measure_across, read_chunk
from ._odometry_chunks import OVERLAP, chunk_folder, first_shape, plan_chunks, run_chunk

__all__ = ["odometry"]


def _check_chunk_size(chunk_size) -> int:
    lo = 2 * OVERLAP
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) \
            or chunk_size < lo:
        raise ParameterError(f"chunk_size must be an integer of at least {lo} (frames a chunk; "
                             f"{OVERLAP} of them shared with the next), got {chunk_size!r}")
    return int(chunk_size)


def _for_workers(item):
    """A frame as a worker is given it: paths made absolute (a worker's
    working folder may be another), arrays as they are."""
    return os.path.abspath(item) if isinstance(item, str) else item


def frames_digest(items, n: int | None = None) -> str:
    """16 hex digits naming the first ``n`` frames (all by default): files by
    their real paths (as a chunk's resume compares them), arrays by their
    pixels' fingerprint.

    >>> frames_digest(["a.png", "b.png"], 1) == frames_digest(["a.png", "c.png"], 1)
    True
    >>> frames_digest(["a.png", "b.png"]) == frames_digest(["a.png", "c.png"])
    False
    """
    h = hashlib.blake2b(digest_size=8)
    for it in items[:n]:
        if it is None or isinstance(it, np.ndarray):
            key = "none" if it is None else _pixels_fingerprint(it)
        else:
            video = split_video_ref(str(it))
            key = (os.path.realpath(os.fspath(it)) if video is None
                   else f"{os.path.realpath(video[0])}#{video[1]}")
        h.update(key.encode("utf-8", "surrogateescape") + b"\0")
    return h.hexdigest()


def _check_same_survey(run: RunFolder, settings: dict, items=None) -> None:
    """ParameterError when ``run``'s folder holds a survey made with other
    settings (a new metres per pixel is allowed: chunks are in pixels), or
    of other frames (frames added after the survey's are allowed: a dive
    still recording)."""
    old = run.read_settings()
    if old is None:
        return
    was = old.get("inputs")
    if items is not None and isinstance(was, dict) and isinstance(was.get("count"), int):
        n = was["count"]
        if len(items) < n or frames_digest(items, n) != was.get("hash"):
            raise ParameterError(f"{run.path}: holds a survey of other frames ({n} frames, not "
                                 f"the first of the {len(items)} given). Use another --out, "
                                 "or remove the folder to start over")
    why = format_change(old["settings"], settings)
    if why:
        raise ParameterError(f"{run.path}: holds a survey that {why.removeprefix('the run ')}. "
                             "Use another --out, or remove the folder to start over")
    changes = [c for c in settings_changes(old["settings"], settings)
               if not c.startswith("metres_per_pixel ")]
    if changes:
        more = f"; and {len(changes) - 4} more" if len(changes) > 4 else ""
        raise ParameterError(f"{run.path}: holds a survey made with other settings: "
                             f"{'; '.join(changes[:4])}{more}. Use another --out, or remove "
                             "the folder to start over")


def _measure_chunks(client, plan, items, out: Path, options: dict, progress: bool,
                    shape) -> list:
    """Every chunk's task on the cluster; their results, in chunk order."""
    from distributed import KilledWorker, as_completed
    from distributed.client import FutureCancelledError

    futures = [client.submit(run_chunk, k, a, [_for_workers(it) for it in items[a:b]],
                             str(chunk_folder(out, k)), options, shape, pure=False)
               for k, (a, b) in enumerate(plan)]
    chunk_of = {f.key: k for k, f in enumerate(futures)}
    bar = None
    if progress:
        from tqdm import tqdm
        # like the CLI's bars: only on a terminal (disable=None), wiped when done
        bar = tqdm(total=plan[-1][1], file=sys.stderr, unit="frame", desc="survey odometry",
                   dynamic_ncols=True, disable=None, leave=False)
    results = [None] * len(plan)
    try:
        # (on its client's loop: another client in the process must not matter)
        for fut in as_completed(futures, loop=client.loop):
            k = chunk_of[fut.key]
            try:
                res = fut.result()
            except KilledWorker:
                a, b = plan[k]
                raise SeahoughError(
                    f"{chunk_folder(out, k)}: chunk {k} (frames {a}-{b - 1}) killed every worker "
                    "that measured it (out of memory?); the chunks finished are kept: run "
                    "again to continue") from None
            except (FutureCancelledError, OSError) as e:   # (CommClosedError is an OSError)
                if isinstance(e, SeahoughError):
                    raise
                raise SeahoughError(
                    f"{out}: the cluster went away ({type(e).__name__}: {e}); the chunks "
                    "finished are kept: run again to continue") from None
            except SeahoughError:
                raise
            except Exception as e:
                raise SeahoughError(
                    f"{chunk_folder(out, k)}: chunk {k} failed on a worker ({type(e).__name__}: "
                    f"{e}); is the same seahough installed there? The chunks finished are "
                    "kept: run again to continue") from e
            results[res["chunk"]] = res
            if bar is not None:
                bar.update(res["n"] - (OVERLAP if res["chunk"] else 0))
    finally:
        if bar is not None:
            bar.close()
        client.cancel([f for f in futures if not f.done()])
    return results


def odometry(frames, out, *, workers=None, scheduler=None, chunk_size=200,
             metres_per_pixel=None, altitude=None, focal_px=None, scale_range=(0.9, 1.1),
             angle_range=(-20.0, 20.0), config=None, tuning=None, mosaic=True,
             progress=True, fps=None) -> dict:
    """Dead reckoning over a sequence, measured in parallel chunks on Dask.

    Parameters
    ----------
    frames : folder, video file or list of image paths (or arrays)
        As :func:`~seahough.run_odometry` takes them
        (:func:`seahough.io.frames.list_frames`), listed once here.
    out : path
        The output folder (locked while a survey writes it): ``odometry.csv``,
        ``run.json``, ``summary.json``, ``trajectory.png``, ``mosaic.png``,
        and ``chunks/NNNNN/`` (each chunk's own run). On a cluster of several
        machines it must be a folder every worker can write, at the same path
        (a shared file system), and so must the frames be readable.
    workers : int, optional
        Worker processes of the local cluster (default: all cores).
    scheduler : str, optional
        Address of a running Dask scheduler instead (``workers`` ignored).
    chunk_size : int
        Frames a chunk (at least 6; 3 are shared with the next chunk). Each
        chunk starts its own keyframes: longer chunks, fewer joins.
    metres_per_pixel, altitude, focal_px, scale_range, angle_range, config, tuning
        As :func:`~seahough.run_odometry`'s.
    mosaic : bool
        Build ``mosaic.png`` (on the client, after the chaining: every frame
        read once more).
    progress : bool
        A progress bar on stderr while the chunks are measured (only on a
        terminal).
    fps : float, optional
        As :func:`~seahough.run_odometry` takes it: the time of frames whose
        names carry none, ``index / fps``.

    Returns
    -------
    dict of str to pathlib.Path
        ``"csv"``, ``"summary"``, ``"trajectory"``, and ``"mosaic"`` when one
        was built.

    Raises
    ------
    ParameterError
        Bad parameters, no frames, Dask missing, no scheduler at ``scheduler``.
    WriteError
        ``out`` cannot be written, or another run is writing it.

    Notes
    -----
    The rows have ``run_odometry``'s columns and meanings, with global frame
    numbers (``index``, ``ref``, ``... since frame N``), and
    positions, headings and matrices in the first frame's pixels; each
    frame's row is written once. A chunk's poses are placed by the last
    frame it shares with the chunk before that both measured (their joins
    add no error; the chunks' own keyframes make the poses differ from a
    single run by about a pixel). When no shared frame was measured in both
    (e.g. all unreadable), the chunk's first frame is measured against the
    last measured frame before it; failing that, its pose is assumed (the
    last measured pose carried on by the last measured motion per frame) and
    flagged ``pose_assumed: constant velocity since frame N`` (``zero
    motion`` when no motion was measured yet), never passed off as
    measured; assumed poses are left out of the mosaic (``mosaic_left_out``
    in the summary).
    ``summary.json`` also says how the chunks went (``survey``: chunks kept
    from an earlier run, measured, resumed from the rows of a run cut short,
    and the joins of each kind).

    Examples
    --------
    30 simulated frames in 3 chunks, on a local cluster of one worker:

    >>> import json, tempfile
    >>> from seahough import sim
    >>> frames, truth = sim.sequence(n_frames=30, seed=2, source="procedural")
    >>> with tempfile.TemporaryDirectory() as out:
    ...     paths = odometry(frames, out, workers=1, chunk_size=12, mosaic=False,
    ...                      progress=False)
    ...     summary = json.loads(paths["summary"].read_text())
    >>> sorted(paths)
    ['csv', 'summary', 'trajectory']
    >>> summary["frames"], summary["flagged_pairs"], summary["survey"]["joins"]["exact"]
    (30, 0, 2)
    """
    t_start = time.perf_counter()
    cfg = ODOMETRY_CONFIG if config is None else config
    if not isinstance(cfg, Config):
        raise ParameterError("config must be a seahough.Config")
    tuning = OdometryTuning() if tuning is None else tuning
    if not isinstance(tuning, OdometryTuning):
        raise ParameterError("tuning must be a seahough.OdometryTuning")
    scale_range, _ = check_ranges(scale_range, (0.0, 0.0))
    angle_range = pair("angle_range", angle_range)
    mpp = resolve_metres_per_pixel(metres_per_pixel, altitude, focal_px)
    chunk_size = _check_chunk_size(chunk_size)
    if fps is not None:
        fps = number("fps", fps, lo=0.0, lo_open=True)
    items = list_frames(frames)
    settings = run_settings(scale_range, angle_range, mpp, cfg, tuning)
    if fps is not None:       # (as run_odometry records it: only when given)
        settings["fps"] = float(fps)
    digest = settings_hash(settings)
    columns = CSV_BASE + (CSV_METRIC if mpp else []) + CSV_MORE + CSV_CHECK
    plan = plan_chunks(len(items), chunk_size)
    options = {"scale_range": tuple(scale_range), "angle_range": tuple(angle_range),
               "config": cfg, "tuning": tuning}
    out_abs = Path(os.path.abspath(out))
    with RunFolder(out) as run:
        check_kind(run.path, "odometry")
        run.check_writable(run.csv)
        _check_same_survey(run, settings, items)   # (before anything of it is removed)
        new = run.read_settings() is None
        run.clear_outputs()
        try:
            run.csv.unlink(missing_ok=True)       # an earlier survey's: made again below
        except OSError as e:
            raise WriteError(f"{run.csv}: cannot replace it ({e.strerror or e})") from None
        # (the frames a survey holds are recorded once measured: an extension
        # that fails, or is cut short, must not refuse the survey's own command)
        was = (run.read_settings() or {}).get("inputs")
        run.write_settings(settings, digest, {"inputs": was} if was else None)
        reader = FrameReader(items, cfg.max_pixels, cfg.max_memory_mb)
        try:
            shape = first_shape(reader, cfg)
        finally:
            reader.close()
        with contextlib.ExitStack() as stack:
            try:
                client = stack.enter_context(open_client(workers, scheduler))
            except BaseException:
                if new:   # (a bad --scheduler must not leave a survey that refuses the fix)
                    run.sidecar.unlink(missing_ok=True)
                raise
            results = _measure_chunks(client, plan, items, out_abs, options, progress, shape)
        run.write_settings(settings, digest,
                           {"inputs": {"count": len(items), "hash": frames_digest(items)}})
        # (the chunks' rows get their times here, by their frames' global numbers)
        reader = FrameReader(items, cfg.max_pixels, cfg.max_memory_mb, fps=fps)
        try:
            return _chain_and_write(run, reader, items, results, columns, digest, mpp,
                                    scale_range, angle_range, cfg, tuning, mosaic, t_start,
                                    (metres_per_pixel, altitude, focal_px), chunk_size)
        finally:
            reader.close()


def chain_chunks(results, reader, path: Path, columns, digest, mpp, measure):
    """The serial step: the chunks (their task's results, in order) chained
    into the CSV ``path`` (written to ``path.part``, renamed when whole).

    Returns the summary's :class:`~seahough.motion.track.Totals`, the
    joins made (:attr:`Chain.joins`) and the rows taken from chunks kept or
    resumed from an earlier run.
    """
    shape = next((tuple(r["shape"]) for r in results if r["shape"] is not None), None)
    totals = Totals()
    kept = {"rows": 0}
    part = path.with_name(path.name + ".part")
    try:
        with open(part, "w", newline="") as f:
            write_csv = csv_writer(f, columns, digest, totals)

            def write(row):
                kept["rows"] += bool(row.get("_resumed"))
                write_csv(row)

            chain = Chain(write, shape, mpp, measure)
            for res in results:
                chain.add(read_chunk(Path(res["folder"]), res, reader, shape))
            chain.finish()
        os.replace(part, path)
    except OSError as e:
        part.unlink(missing_ok=True)
        raise WriteError(f"{path}: cannot write the track ({e.strerror or e})") from None
    return totals, chain.joins, kept["rows"]


def _chain_and_write(run: RunFolder, reader, items, results, columns, digest, mpp,
                     scale_range, angle_range, cfg, tuning, mosaic, t_start, given,
                     chunk_size) -> dict:
    """The chunks chained into ``odometry.csv``, then the summary and pictures."""
    shape = next((tuple(r["shape"]) for r in results if r["shape"] is not None), None)
    t_chain = time.perf_counter()
    totals, joins, kept_rows = chain_chunks(
        results, reader, run.csv, columns, digest, mpp,
        lambda p, q: measure_across(reader, p, q, scale_range, angle_range, cfg, tuning))
    chain_s = time.perf_counter() - t_chain

    out = run.path
    paths = {"csv": run.csv}
    placed: dict = {}
    if mosaic and shape is not None:
        made = write_output(out / "mosaic.png", lambda: build_mosaic(
            run.csv, reader, shape, out / "mosaic.png", counts=placed,
            bit_depth=cfg.bit_depth))
        if made is not None:
            paths["mosaic"] = Path(made)
    paths["trajectory"] = Path(write_output(out / "trajectory.png", lambda: plot_track(
        run.csv, out / "trajectory.png", bool(mpp))))
    summary = summarise(totals, items, mpp, scale_range, angle_range, cfg, tuning, kept_rows,
                        time.perf_counter() - t_start, *given)
    summary["mosaic_left_out"] = placed.get("left_out")
    states = [r["state"] for r in results]
    summary["survey"] = {"chunks": len(results), "chunk_size": chunk_size, "overlap": OVERLAP,
                         "kept": states.count("kept"), "measured": states.count("measured"),
                         "resumed": sum(r["state"] == "measured" and r["resumed_rows"] > 0
                                        for r in results),
                         "joins": dict(joins), "chain_s": chain_s}
    summary["outputs"] = {"csv": str(run.csv), "json": str(run.json),
                          "mosaic": str(paths["mosaic"]) if "mosaic" in paths else None,
                          "trajectory": str(paths["trajectory"])}

    def write_summary():
        with open(run.json, "w") as fj:
            json.dump(json_safe(summary), fj, indent=2)
            fj.write("\n")

    write_output(run.json, write_summary)
    paths["summary"] = run.json
    return paths
