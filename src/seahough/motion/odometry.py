"""Photo dead reckoning over a whole dive: the camera's path from its frames.

Each frame is measured against a *keyframe* (an earlier frame kept as the
pattern while the two still overlap well), which drifts less than chaining
every consecutive pair. The motion of the last frames predicts where the
keyframe lies in the next one, so the search is narrowed to a small window of
position, rotation and scale around that prediction (the fast path); when
that fails, the full search against the keyframe, then against the previous
frame, then a wider search against the last measured frame take over. A
pair that still cannot be measured is flagged with what happened, and its
pose is assumed, as it says: the last measured pose carried on by the last
velocity, never passed off as measured (nor stacked in the mosaic).

A dive of 6 simulated frames (a folder, a video or a list of paths work alike):

>>> import tempfile
>>> from seahough import sim
>>> frames, truth = sim.sequence(n_frames=6, seed=2, source="procedural")
>>> with tempfile.TemporaryDirectory() as out:
...     result = run_odometry(frames, out, metres_per_pixel=0.004, progress=False,
...                           mosaic=False)
>>> result.summary["measured_pairs"], round(result.summary["path_length_m"], 2)
(5, 0.23)

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

import csv
import json
import os
import sys
import time

import numpy as np

from .._validate import check_workers
from ..config import ODOMETRY_CONFIG, OdometryTuning
from ..errors import ParameterError, SeahoughError, WriteError, interrupted
from .._values import json_safe
from ..io.frames import FrameReader, list_frames
from ..io.images import to_gray
from .mosaic import build_mosaic
from .odometer import TUNING, Odometer  # noqa: F401  (TUNING: the default policy, as before)
from .prefetch import Prefetch, overlapped
from .state import advance
from .framing import check_video_sizes, content_box
from .searcher import Searcher as _Searcher
from .runfiles import (RunFolder, check_kept_row, check_kind, open_track, write_output,
                       write_row)
from .track import (OdometryResult, Totals, closing_enumerate, plot_track, summarise,
                    iter_odometry_csv, metric_position, row_to_csv)

__all__ = ["run_odometry", "ODOMETRY_CONFIG", "OdometryTuning"]



def run_odometry(frames, out_dir, *, metres_per_pixel=None, altitude=None, focal_px=None,
                 scale_range=(0.9, 1.1), angle_range=(-20.0, 20.0), resume=False,
                 progress=True, mosaic=True, config=None,
                 tuning: OdometryTuning | None = None, workers: int | None = None,
                 fps: float | None = None) -> OdometryResult:
    """Dead reckoning over a sequence of down-looking frames.

    Parameters
    ----------
    frames : folder, video file, or list of image paths (or of videos) or of arrays
        See :func:`seahough.io.frames.list_frames` (frames of any size, depth and colour; all
        must have the first readable frame's size; None in a list: a dropped frame, an
        ``unreadable`` row). A generator is read to its end before the run starts
        (its arrays held in memory): a live camera's frames, which never end, go to
        :class:`~seahough.Odometer` one at a time.
    out_dir : path
        Created if needed; receives ``odometry.csv`` (written and flushed
        row by row), ``run.json`` (the settings), then ``summary.json``,
        ``mosaic.png`` and ``trajectory.png`` when the run ends (those of an
        earlier run are removed when it starts). One run at a time: the
        folder is locked while a run writes it.
    metres_per_pixel : float, optional
        Ground size of a frame-0 pixel; or give ``altitude`` (m) and
        ``focal_px`` (focal length in pixels) of a down-looking camera:
        metres per pixel = altitude / focal_px. Adds ``x_m, y_m``. Giving
        ``metres_per_pixel`` with ``altitude`` or ``focal_px`` is refused
        (ParameterError).
    scale_range, angle_range : (float, float)
        Size change and turn (degrees, counter-clockwise as displayed)
        possible between consecutive frames; a range of one value is a known
        quantity (``(1, 1), (0, 0)``: constant altitude and heading). The
        vote searches these ranges; a pair measured as a homography (below)
        may end outside them.
    resume : bool
        Continue from an ``odometry.csv`` already in ``out_dir``: frames
        measured there are kept, the state (poses, keyframe, velocity) is
        rebuilt from them, and the result is the same as an uninterrupted
        run. Only the same run is continued: the same settings (ranges,
        metres per pixel, config, tuning), and the same frames (names
        compared as full paths, contents by fingerprint), else a
        ParameterError naming what differs. Without it, an existing CSV is
        overwritten (not a read-only one: WriteError).
    progress : bool
        A tqdm progress bar on stderr (shown only when stderr is a terminal).
    mosaic : bool
        Build ``mosaic.png`` (needs the frames read a second time; at most
        4000 px on its longer side, the frames shrunk to fit). Frames whose
        pose is assumed are left out of it (their place is a guess): the
        summary's ``mosaic_left_out`` counts the frames with a pose that are
        not in it (None when no mosaic was built).
    config : seahough.Config, optional
        Search tuning (default :data:`~seahough.config.ODOMETRY_CONFIG`).
    tuning : seahough.OdometryTuning, optional
        The keyframe, prior and fallback policy (the numbers of the notes
        below are its defaults).
    workers : int, optional
        Threads (default: all cores): the pairs are measured in turn while the
        coming frames are read and given their features ahead (:mod:`.prefetch`);
        the same rows for any number (1: all in the calling thread, as before).
    fps : float, optional
        Frame rate, for the ``time`` column of frames whose names carry no
        time (and of arrays): ``index / fps``, seconds since the first frame.
        A time in a frame's name, or a video's own frame rate, comes first.

    Returns
    -------
    OdometryResult
        Memory does not grow with the number of frames: each row goes to
        the CSV when finished, the summary is counted as they go, and the
        result's ``rows`` are read back from the CSV when first asked for.

    Raises
    ------
    ParameterError
        Bad parameters; ``resume`` of another run.
    WriteError
        ``out_dir`` cannot be created or written, another run is writing
        it, or its CSV is read-only.

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
    2b. ``recover``: after a gap of one or two frames whose poses were
       assumed (a bad frame, a fish), against the last measured frame, with
       the ranges widened over the gap.
    3. ``previous``: against the previous readable frame (when it is not
       the keyframe), full search; it then becomes the keyframe.
    4. ``wide``: the last try before the pair is flagged: against the last
       measured frame, with twice the full search's shift region (+-a whole
       frame) and the ranges widened as for twice the frames (``scale_range``
       squared, ``angle_range`` doubled; known quantities stay known); it
       then becomes the keyframe. A sudden jump, turn or change of altitude
       beyond the per-frame ranges is measured here, not flagged.

    A search of a frame one or two frames away, directly, without a prior and
    not through a keyframe (the first pair, 2. while the keyframe is the
    previous frame, 2b. after one frame assumed, 3., 4.) is measured as
    :func:`~seahough.estimate_motion` measures a pair: coarse to fine and a
    check of the candidates as homographies when the vote cannot vouch for
    its answer (a repeated texture, a camera that looks ahead), so that its
    turn may lie outside ``angle_range`` (a 30-degree turn under the default
    +-20 is measured by 3.).

    A keyframe measurement of confidence below 0.35 (an old keyframe, or a
    look-alike of it: a tile or a ripple one period on), or one found by the
    full search (2.: the motion left the prediction, or there was none),
    two or more frames back, is checked by a full search
    against the last measured frame, nearer in time; that one replaces it
    when the two differ by more than 2 working pixels at the frame's corners
    (more than a measurement's noise: an aging keyframe of a scene in relief
    drifts too) and it is the adjacent frame, or more confident. It is then
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
    not be measured or a frame that could not be read; docs/odometry.md):

    - ``unreadable: <reason>``: corrupt, truncated, wrong size, too small
      to measure (a side under 64 px), gone since the run started, a broken
      link or a folder in a folder of frames, a video frame the decoder
      cannot give; the row has no pose, the state is kept and the next
      readable frame is measured against the keyframe across the gap. (A
      path of a *list* of frames that is not there, a broken link or a
      folder, is refused before the run starts: ParameterError.)
    - ``duplicate: the same pixels as frame N``: the frame is frame N over
      again (a camera driver handing the same buffer twice): not measured
      (its motion is not known), its pose assumed as below.
    - ``no_match`` (no pose of the reference frame was found in this one),
      ``low_confidence`` (one was found, but not distinct from its
      runner-up, or matching far worse than the last frames did),
      ``little_overlap`` (one was found, but too little of the reference is
      in view), ``few_edges`` (every attempt had a frame with too few edges
      to be measured: open water, featureless sand, a frame too dark or
      washed out): no step measured the pair (the reason of the best
      attempt).
      The frame's pose is *assumed*: the last measured pose carried on by
      the last measured motion per frame, flagged ``pose_assumed: constant
      velocity since frame N`` (N: the last measured frame); before any
      motion was measured (the second frame), the last measured pose,
      flagged ``pose_assumed: zero motion since frame N``. An assumed pose
      never feeds the motion per frame; it is in the CSV (status
      ``assumed``), the plot (a hollow marker) and the summary
      (``assumed_poses``), but not in the mosaic (``mosaic_left_out``).
      The next frame is searched against the keyframe and against this
      frame, so the trajectory goes on from the next good pair.
    - ``after_gap: measured against frame N, whose pose was assumed``: a
      frame measured (its step, ``pair_matrix``, is) against a frame whose
      pose was assumed: its place on the track, and every later one's,
      carries that guess (the summary's ``after_gap`` lists these frames).
    - ``repeated_texture: the step is known up to the texture's period (P
      px); the copy nearest the constant-velocity prediction was taken``: a
      frame of a net, a grating, a one-shade tiled floor, whose step moved
      by a whole period fits its edges as well (``motion/repeats.py``): of
      the copies, the one the last velocity predicts (before any velocity
      is known: the vote's, said so). Right while the velocity changes by
      less than half a period a frame; the flag says it is not measured
      otherwise.
    """
    t_start = time.perf_counter()
    odo = Odometer(scale_range, angle_range, metres_per_pixel=metres_per_pixel,
                   altitude=altitude, focal_px=focal_px, config=config, tuning=tuning, fps=fps)
    workers = check_workers(workers)
    _not_the_frames_folder(frames, out_dir)
    items = list_frames(frames)
    check_video_sizes(items)
    cfg = odo.config
    reader = FrameReader(items, cfg.max_pixels, cfg.max_memory_mb, fps=odo.fps)
    with RunFolder(out_dir) as run:
        check_kind(run.path, "odometry")
        try:
            return _run(run, reader, items, odo, resume, progress, mosaic, t_start,
                        (metres_per_pixel, altitude, focal_px, _source(frames)), workers)
        except SystemError as e:   # (Ctrl-C inside a compiled kernel)
            if interrupted(e):
                raise KeyboardInterrupt from e
            raise
        finally:
            reader.close()


def _not_the_frames_folder(frames, out_dir) -> None:
    """A ParameterError when ``out_dir`` is the frames' folder: the run's
    pictures (mosaic.png, trajectory.png) would be frames of the next run
    over it (a user trial: its second run flagged them unreadable, and
    --resume was refused for good as "frame 10 changed")."""
    folder = frames[0] if isinstance(frames, (list, tuple)) and len(frames) == 1 else frames
    if isinstance(folder, (str, os.PathLike)) and os.path.isdir(folder) and os.path.exists(
            out_dir) and os.path.samefile(folder, out_dir):
        raise ParameterError(f"out_dir {os.fspath(out_dir)!r} is the frames' folder: the run's "
                             "pictures would be read as frames by the next run; give another "
                             "folder (e.g. a subfolder)")


def _source(frames) -> str | None:
    """The frames' source for the summary: a folder's or a video's path as
    given (a list: None, its first frame is named)."""
    if isinstance(frames, (str, os.PathLike)):
        return str(frames)
    return None


def _run(run: RunFolder, reader: FrameReader, items, odo: Odometer, resume, progress, mosaic,
         t_start, given, workers):
    """run_odometry in its locked output folder."""
    out, csv_path, json_path = run.path, run.csv, run.json
    run.check_writable(csv_path)
    cfg, tuning, mpp, settings, digest, columns = (odo.config, odo.tuning, odo.mpp, odo.settings,
                                                   odo.digest, odo.columns)
    scale_range, angle_range = odo.scale_range, odo.angle_range

    # Rows are not kept in memory (a long survey would grow without bound): each one
    # is written to the CSV as it is finished, the summary is counted as they go
    # by, and the mosaic and the plot read the CSV back.
    st = odo.st
    totals = Totals()
    ahead = None
    # (a frame the state needs and the Odometer does not hold: a resumed run's)
    odo.fetch = lambda i: to_gray((reader if ahead is None else ahead).raw(i),
                                  max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb,
                                  bit_depth=cfg.bit_depth)

    # ---- resume: check that the rows kept are this run's (settings, frames) and
    # rebuild the state from them, rewriting them (drops a cut-off line) into a new
    # file, read and written one row at a time
    n_resumed = 0
    kept_hashes: dict = {}     # (the frames the state refers to: a duplicate is told by them)
    if resume and csv_path.exists():
        old_cwd = run.check_settings(settings, digest)
        part = csv_path.with_name(csv_path.name + ".part")
        try:
            with open(part, "w", newline="") as fnew:
                writer = csv.DictWriter(fnew, fieldnames=columns, extrasaction="ignore")
                writer.writeheader()
                old = iter_odometry_csv(csv_path)
                for pos, r in closing_enumerate(old):
                    if pos >= len(items):
                        n_old = pos + 1 + sum(1 for _ in old)
                        raise ParameterError(f"{csv_path} holds {n_old} frames, more than the "
                                             f"{len(items)} given: not the same sequence")
                    check_kept_row(csv_path, pos, r, reader, digest, old_cwd)
                    r["_cum"] = (None if r["matrix"] is None
                                 else np.asarray(r["matrix"], float).reshape(2, 3))
                    if r["status"] != "unreadable" and st.shape is None:
                        g0 = to_gray(reader.raw(r["index"]), max_pixels=cfg.max_pixels,
                                     max_memory_mb=cfg.max_memory_mb, bit_depth=cfg.bit_depth)
                        st.shape, st.box = g0.shape, content_box(g0)
                    if mpp:
                        r["x_m"], r["y_m"] = metric_position(r, st.shape, mpp)
                    else:
                        r.pop("x_m", None)
                        r.pop("y_m", None)
                    advance(st, r, tuning)
                    if r["status"] != "unreadable":
                        st.heading = r["heading"]
                        kept_hashes[r["index"]] = r.get("frame_hash") or ""
                        kept_hashes = {k: h for k, h in kept_hashes.items()
                                       if k in (st.key, st.prev, st.meas)}
                    writer.writerow(row_to_csv(r, columns))
                    totals.add(r)
                    n_resumed += 1
            os.replace(part, csv_path)
        except BaseException as e:
            part.unlink(missing_ok=True)
            if isinstance(e, OSError) and not isinstance(e, SeahoughError):
                raise WriteError(f"{csv_path}: cannot rewrite it to resume "
                                 f"({e.strerror or e})") from None
            raise
        if run.read_settings() is None:
            run.write_settings(settings, digest)
        run.clear_outputs()
        fcsv = open_track(csv_path, "a")
    else:
        run.clear_outputs()
        run.write_settings(settings, digest)
        fcsv = open_track(csv_path, "w")
    writer = csv.DictWriter(fcsv, fieldnames=columns, extrasaction="ignore")
    if fcsv.tell() == 0:                    # a new file: the header first
        write_row(fcsv, csv_path, writer.writeheader)

    if st.shape is not None:
        odo.searcher = _Searcher(st.box, scale_range, angle_range, cfg, tuning)
        for k in (st.key, st.prev, st.meas):
            odo.load(k)
        odo.hashes = {k: h for k, h in kept_hashes.items() if k in odo.frames}

    bar = None
    if progress:
        from tqdm import tqdm
        # like the CLI's bars: only on a terminal (disable=None), wiped when done
        bar = tqdm(total=len(items), initial=n_resumed, file=sys.stderr, unit="frame",
                   desc="odometry", dynamic_ncols=True, disable=None, leave=False)
    ahead = Prefetch(reader, n_resumed, max_pixels=cfg.max_pixels,
                     max_memory_mb=cfg.max_memory_mb, workers=workers, bit_depth=cfg.bit_depth)
    if odo.searcher is not None:
        ahead.use(odo.searcher, st.shape)
    try:
        for i in range(n_resumed, len(items)):
            t0 = time.perf_counter()
            row = odo.step(i, ahead.get(i), reader.name(i), reader.time(i), t0)
            if ahead.searcher is None and odo.searcher is not None:
                ahead.use(odo.searcher, st.shape)
            write_row(fcsv, csv_path, lambda: writer.writerow(row_to_csv(row, columns)))
            totals.add(row)
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(f"flagged {totals.flagged}", refresh=False)
    finally:
        ahead.close()
        fcsv.close()
        if bar is not None:
            bar.close()
    odo.reset()

    # ---- outputs (from the CSV, one row at a time; the two pictures at once)
    placed: dict = {}
    def draw_mosaic():
        if not (mosaic and st.shape is not None):
            return None
        return write_output(out / "mosaic.png", lambda: build_mosaic(
            csv_path, reader, st.shape, out / "mosaic.png", counts=placed,
            bit_depth=cfg.bit_depth))

    def draw_track():
        return write_output(out / "trajectory.png", lambda: plot_track(
            csv_path, out / "trajectory.png", bool(mpp)))

    mosaic_path, trajectory_path = overlapped((draw_mosaic, draw_track), workers)
    reader.close()
    summary = summarise(totals, items, mpp, scale_range, angle_range, cfg, tuning, n_resumed,
                        time.perf_counter() - t_start, *given)
    summary["mosaic_left_out"] = placed.get("left_out")
    summary["outputs"] = {"csv": str(csv_path), "json": str(json_path),
                          "mosaic": None if mosaic_path is None else str(mosaic_path),
                          "trajectory": str(trajectory_path)}

    def write_summary():
        with open(json_path, "w") as f:
            json.dump(json_safe(summary), f, indent=2)
            f.write("\n")

    write_output(json_path, write_summary)
    return OdometryResult(None, summary, csv_path, json_path, mosaic_path, trajectory_path)
