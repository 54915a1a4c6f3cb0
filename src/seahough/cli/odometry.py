"""``seahough odometry``: dead reckoning over a sequence of frames."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import click
import numpy as np

from ..io.frames import printable, split_video_ref, video_ref_problem
from ._common import (_Fail, _dumps, _range_callback, _say_kept, _stderr_is_terminal, _Terminated,
                      bit_depth_option, workers_option)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _path_length(rows) -> float:
    """Length of the path through the rows' ``x, y`` (rows without a position,
    and assumed poses, skipped: the path joins the measured ones).

    >>> _path_length([{"x": 0, "y": 0}, {"x": None, "y": None}, {"x": 3, "y": 4},
    ...               {"x": 9, "y": 4, "status": "assumed"}, {"x": 3, "y": 4}])
    5.0
    """
    pts = np.array([[np.nan if r.get("x") is None or r.get("status") == "assumed"
                     else float(r["x"]),
                     np.nan if r.get("y") is None else float(r["y"])] for r in rows], float)
    pts = pts[np.all(np.isfinite(pts), axis=1)] if len(pts) else pts
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0


def _odometry_rows(result):
    """The run's rows one at a time (a long survey's rows are not all loaded)."""
    it = getattr(result, "iter_rows", None)
    return it() if callable(it) else iter(result.rows)


def _str_or_none(p):
    return None if p is None else str(p)


def _odometry_summary(result, wall_s: float, unit: str) -> dict:
    """What the command prints, from the run's summary (``path_length_m``
    when not None, else ``path_length_px``; ``mean_ms_per_frame``). The rows
    are read only where the summary lacks a count or the path length, and
    ``unit`` ("m" or "px", from the options) labels that length."""
    s = dict(getattr(result, "summary", {}) or {})
    n = s.get("frames")
    if not isinstance(n, int):
        n = sum(1 for _ in _odometry_rows(result))
    flagged = s.get("flagged_pairs")
    if not isinstance(flagged, int):
        flagged = sum(1 for r in _odometry_rows(result) if r.get("flags") and r.get("index", 0) > 0)
    if _number(s.get("path_length_m")):
        dist, unit = s["path_length_m"], "m"
    elif _number(s.get("path_length_px")):
        dist, unit = s["path_length_px"], "px"
    else:
        dist = _path_length(list(_odometry_rows(result)))
    per = s.get("mean_ms_per_frame")
    per = float(per) if _number(per) else 1000.0 * wall_s / max(n, 1)
    return {"frames": n, "flagged_pairs": flagged, "distance": float(dist), "unit": unit,
            "time_per_frame_ms": per,
            "csv": _str_or_none(getattr(result, "csv_path", None)),
            "json": _str_or_none(getattr(result, "json_path", None)),
            "mosaic": _str_or_none(getattr(result, "mosaic_path", None)),
            "trajectory": _str_or_none(getattr(result, "trajectory_path", None)),
            "summary": s}


def _finite(ctx, param, value):
    """A click callback refusing nan and inf (FloatRange lets them through)."""
    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"{value!r}: expected a finite number")
    return value


@click.command(no_args_is_help=True)
@click.argument("frames", nargs=-1, required=True, metavar="FRAMES...")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for the CSV/JSON track, the mosaic and the trajectory plot.")
@click.option("--metres-per-pixel", type=click.FloatRange(0.0, min_open=True), default=None,
              callback=_finite, help="Ground size of a pixel, for positions in metres.")
@click.option("--altitude", type=click.FloatRange(0.0, min_open=True), default=None,
              callback=_finite, help="Camera height above the bottom, metres (with --focal-px).")
@click.option("--focal-px", type=click.FloatRange(0.0, min_open=True), default=None,
              callback=_finite, help="Focal length in pixels (with --altitude).")
@click.option("--scale-range", nargs=2, type=float, default=(0.9, 1.1), show_default=True,
              metavar="LOW HIGH", callback=_range_callback(True),
              help="Size change between frames (altitude change); LOW = HIGH: known.")
@click.option("--angle-range", nargs=2, type=float, default=(-20.0, 20.0), show_default=True,
              metavar="LOW HIGH", callback=_range_callback(False),
              help="Turn between frames, degrees; LOW = HIGH: known heading change.")
@click.option("--resume", is_flag=True, help="Continue a run interrupted in the same --out "
              "(the same frames and settings only).")
@click.option("--no-mosaic", is_flag=True, help="Do not build the mosaic.")
@click.option("--equalize", is_flag=True,
              help="Local contrast equalisation of every frame (dark, hazy or unevenly lit "
              "frames flagged no_match or few_edges).")
@click.option("--fps", type=click.FloatRange(0.0, min_open=True), default=None, callback=_finite,
              help="Frame rate, for the time column of frames whose names carry no time: "
              "index / FPS, seconds since the first frame.")
@bit_depth_option
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar (shown on stderr only when it is a terminal).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object.")
@workers_option("Threads: the pairs are measured in turn while the coming frames are read and "
                "prepared ahead; the same results for any number")
def odometry(frames, out, metres_per_pixel, altitude, focal_px, scale_range, angle_range,
             resume, no_mosaic, equalize, fps, bit_depth, quiet, as_json, workers):
    """Dead reckoning: the camera's path from overlapping frames.

    \b
    FRAMES is a folder of images (in the order of the timestamps in their
    names when every name has one, e.g. cam_20240210_134109.500.png, else in
    natural name order: f2 before f10), one or more video files (read frame
    by frame, one after the other), or image files in the order given. An earlier frame (a keyframe) is the pattern searched
    for in each frame; the accumulator peak is the motion. Positions (x, y)
    are where each frame's centre lies in pixels of the first frame (frame 0
    at its own centre); x_m, y_m with --metres-per-pixel, or --altitude and
    --focal-px, are metres from frame 0's centre. Writes odometry.csv,
    run.json, summary.json, trajectory.png and mosaic.png to --out (a run's
    files replace an earlier run's there unless --resume; a run into an
    --out that another run is writing is refused).

    \b
    odometry.csv, a row a frame (more in docs/odometry.md):
      index, file      the frame's place in the run and its name
      time             seconds: from a time in its name (since 1970, UTC,
                       for a date and time; since midnight for a time of
                       day), a video's frame rate, or index / --fps; empty
                       when none
      x, y, x_m, y_m   its centre in frame 0's pixels; in metres from
                       frame 0's centre
      heading, scale   its turn since frame 0, degrees, counter-clockwise
                       as the frames are displayed (unwrapped; a compass,
                       seen from above, turns the other way), and its size
                       change since frame 0 (> 1: closer)
      confidence, nfa, score, overlap   the evidence of its step
      flags            why a step was not measured (below), or after_gap
                       (measured, against a frame whose pose was assumed),
                       or repeated_texture (measured up to the period of a
                       net or grating: the copy the velocity predicts);
                       empty otherwise
      dx, dy, rotation, scale_change    the scene's motion from the
                       previous frame (the camera moved the other way)
      ref, method, status, ms, matrix, pair_matrix   how it was measured,
                       CPU ms, frame 0 -> frame and previous -> frame
      frame_hash, settings_hash         what --resume checks

    \b
    Flags (the first word): no_match (the reference frame not found in
    this one: another place, blur, a dark frame: try --equalize),
    low_confidence (a pose no more likely than its runner-up),
    little_overlap (under 15 % of the reference in view), few_edges (too
    few edges: open water, bare sand, exposure: try --equalize),
    duplicate (the very pixels of the frame before: a camera driver's
    repeated buffer), unreadable: WHY (no pose at all). A flagged frame's
    pose is assumed, said as "pose_assumed: constant velocity since frame
    N" (or zero motion), drawn hollow and left out of the mosaic. Roll and
    pitch are not measured: a tilt of the camera shows as a sideways shift.

    \b
    Exit status: 0 every pair of frames was measured; 1 some frames are
    flagged (unreadable, their motion could not be measured, measured
    after such a gap or only up to a repeated texture's period: see the
    CSV's flags column); 2 bad input.

    \b
    Example:
      seahough odometry dive/frames --out track --altitude 2.5 --focal-px 800
    """
    check_inputs(frames, metres_per_pixel, altitude, focal_px)
    if fps is not None and not quiet:
        _say_video_rates(frames, fps)
    # looked up when the command runs (tests stand a stub in for the module)
    from ..motion.odometry import run_odometry

    unit = "m" if (metres_per_pixel is not None or altitude is not None) else "px"
    earlier = None if resume else _rows_in(out)
    if earlier and not quiet:   # (one forgotten --resume cost a long survey's run, unsaid)
        click.echo(f"seahough: note: replacing the run of {earlier} frame{'s' * (earlier != 1)} "
                   f"in {printable(str(out))} (--resume would go on with it)", err=True)
    t0 = time.perf_counter()
    try:
        result = run_odometry(list(frames), out, metres_per_pixel=metres_per_pixel,
                              altitude=altitude, focal_px=focal_px, scale_range=scale_range,
                              angle_range=angle_range, resume=resume,
                              progress=not quiet and _stderr_is_terminal(),
                              mosaic=not no_mosaic, workers=workers, fps=fps,
                              **_config(bit_depth, equalize))
    except (KeyboardInterrupt, _Terminated, SystemError) as e:
        # (Ctrl-C inside a compiled kernel is a SystemError caused by it: what
        # was kept is said the same way; a trial saw a bare "interrupted")
        _say_kept(e, _kept(out))
    return report(result, time.perf_counter() - t0, unit, as_json)


def _say_video_rates(frames, fps: float) -> None:
    """A note for each video whose frames keep their own rate over ``--fps``
    (a user's --fps 20 on a 5 fps video changed nothing, unsaid)."""
    from ..io.frames import VIDEO_EXTENSIONS, FrameReader

    videos = dict.fromkeys((split_video_ref(f) or (f,))[0] for f in frames)
    reader = FrameReader([], 1)     # (its header's rate, as the run's times take it)
    for v in videos:
        if Path(v).suffix.lower() in VIDEO_EXTENSIONS and Path(v).is_file():
            rate = reader._video_fps(v)
            if rate > 0:
                click.echo(f"seahough: note: --fps {fps:g} is for frames without a time: the "
                           f"frames of {printable(v)} take its own rate ({rate:g} fps)", err=True)


def _rows_in(out) -> int | None:
    """How many rows the ``odometry.csv`` in ``out`` holds (None: none there)."""
    try:
        with open(Path(out) / "odometry.csv", newline="") as f:
            return max(sum(1 for _ in f) - 1, 0)
    except OSError:
        return None


def _kept(out) -> str:
    """What an interrupted run in ``out`` kept, in words ("" when unknown)."""
    n = _rows_in(out)
    if n is None:
        return ""
    return (f"{n} frame{'s' * (n != 1)} kept in {printable(str(out))}/odometry.csv; the same "
            "command with --resume goes on from there")


def _config(bit_depth, equalize) -> dict:
    """``config=`` for a run of ``--bit-depth`` and ``--equalize`` (nothing:
    the run's default, so that runs made before resume as they were)."""
    if bit_depth is None and not equalize:
        return {}
    from ..config import ODOMETRY_CONFIG

    changes = {"bit_depth": int(bit_depth)} if bit_depth is not None else {}
    if equalize:
        changes["equalize"] = True
    return {"config": ODOMETRY_CONFIG.replace(**changes)}


def check_inputs(frames, metres_per_pixel, altitude, focal_px) -> None:
    """The checks of ``odometry`` (and ``survey odometry``) before any work:
    one way to give the ground scale, and frames that exist."""
    if metres_per_pixel is not None and (altitude is not None or focal_px is not None):
        raise click.UsageError("give --metres-per-pixel or --altitude with --focal-px, not both")
    if (altitude is None) != (focal_px is None):
        raise click.UsageError("--altitude and --focal-px go together")
    for f in frames:
        if not Path(f).exists() and not os.path.islink(f):   # (a broken link: flagged)
            ref = split_video_ref(f)      # (a video's frame: "dive.mp4#12")
            if ref is None or not Path(ref[0]).is_file():
                raise _Fail(printable(video_ref_problem(f) or f"{f}: no such file or folder"))


#: the end note that a run's scale changed (a camera looking ahead, an
#: altitude that changed), when its largest scale is this many times its
#: smallest
SCALE_NOTE = 1.4


def report(result, seconds: float, unit: str, as_json: bool) -> int:
    """Print a run's summary (one JSON object, or lines: the totals, the
    first 10 flagged frames, the files written); the exit status: 1 when
    frames are flagged, else 0."""
    summ = _odometry_summary(result, seconds, unit)
    status = 1 if summ["flagged_pairs"] else 0
    if summ["frames"] < 2:   # (stderr: the JSON on stdout stays one object)
        click.echo(f"note: {summ['frames']} frame: no motion to measure (dead reckoning "
                   "needs two frames or more)", err=True)
    if as_json:
        click.echo(_dumps(summ))
        return status
    click.echo(f"frames: {summ['frames']}   flagged frames: {summ['flagged_pairs']}   "
               f"distance: {summ['distance']:.2f} {summ['unit']}   "
               f"time per frame: {summ['time_per_frame_ms']:.0f} ms")
    flagged = [r for r in _odometry_rows(result) if r.get("flags")]
    n_flagged = len(flagged)
    n_sized = sum("differs from the first frame's" in str(r.get("flags")) for r in flagged)
    said = {printable(r.get("flags")) for r in flagged}
    if n_flagged > 2 and n_flagged == summ["frames"] and len(said) == 1:
        # (one reason for every frame, frames too small say: once, not once a frame)
        click.echo(f"  flagged: every frame ({n_flagged}): {said.pop()}")
        flagged = []
    for r in flagged[:10]:
        click.echo(f"  flagged: frame {r.get('index')} {printable(r.get('file'))}: "
                   f"{printable(r.get('flags'))}")
    if len(flagged) > 10:
        click.echo(f"  ... and {n_flagged - 10} more (see the CSV's flags column)")
    if n_sized and n_sized == summ["frames"] - 1:
        click.echo("  note: every frame after the first has another size than the first: "
                   "the first may be the odd one (leave it out)")
    gaps = summ["summary"].get("after_gap") or []
    if gaps:
        click.echo(f"  note: the track goes on after {len(gaps)} gap{'s' * (len(gaps) > 1)} "
                   f"(frames {', '.join(str(g) for g in gaps[:10])}"
                   f"{', ...' if len(gaps) > 10 else ''}): each step is measured, but the "
                   "positions from there on carry the assumed poses before it")
    seen = summ["summary"].get("scale_seen")
    if seen and seen["max"] / seen["min"] > SCALE_NOTE:
        click.echo(f"  note: the scene's scale changed {seen['max'] / seen['min']:.2f}x over the "
                   f"run (frame {seen['min_frame']}: {seen['min']:.2f}, frame "
                   f"{seen['max_frame']}: {seen['max']:.2f}): a camera that looks ahead, or a "
                   "large change of altitude; the track and its metres assume a camera that "
                   "looks down from a steady height")
    files = [summ[k] for k in ("csv", "json", "trajectory", "mosaic") if summ[k]]
    if files:
        click.echo("wrote: " + ", ".join(printable(f) for f in files))
    return status
