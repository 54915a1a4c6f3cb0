"""The ``seahough`` command line: detect, odometry, simulate, demo.

Errors a user can cause (a missing or broken file, a bad parameter) print
one line ``seahough: error: ...`` on stderr and exit with status 2, never a
traceback. See ``seahough COMMAND --help``.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import sys
import time
from pathlib import Path

import click
import numpy as np

from .. import __version__
from ..config import Config
from ..core.detector import Detector
from ..errors import SeahoughError
from ..geometry import format_angle

PROG = "seahough"
SHAPES_HELP = ("rect:W,H | line:LENGTH,WIDTH | circle:R | circle:R,INNER (a ring) | "
               "polygon:x1,y1,x2,y2,...")
_SHAPE_POLARITY = {"same": "bright", "inverted": "dark", "bright": "bright", "dark": "dark",
                   "either": "either"}
_IMAGE_POLARITY = {"same": "same", "inverted": "inverted", "bright": "same", "dark": "inverted",
                   "either": "either"}
WATER_CHOICES = ("clear", "moderate", "hard", "none")
SIM_KINDS = ("marker", "rope", "pair", "sequence", "negative")
# the command's defaults are the library's, so that both give the same results
_DET = {k: v.default for k, v in inspect.signature(Detector.__init__).parameters.items()}
_CFG = Config()


class _Fail(Exception):
    """A user error already worded for the one-line message."""


# ------------------------------------------------------------------------ helpers
def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    if isinstance(o, (set, tuple)):
        return list(o)
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _dumps(obj, **kw) -> str:
    return json.dumps(obj, default=_json_default, allow_nan=True, **kw)


def _err(msg: str) -> None:
    """One line on stderr: ``seahough: error: msg``."""
    msg = " ".join(str(msg).split())
    click.echo(f"{PROG}: error: {msg}", err=True)


def _problem(exc: Exception, name: str) -> str:
    """The message of ``exc`` without a leading copy of the file name."""
    msg = str(exc)
    for prefix in (f"{name}: ", f"{Path(name)}: "):
        if msg.startswith(prefix):
            return msg[len(prefix):]
    return msg


def _range_callback(positive: bool):
    def check(ctx, param, value):
        if value is None:
            return value
        lo, hi = value
        flag = f"{lo:g} {hi:g}"
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise click.BadParameter(f"{flag}: values must be finite")
        if lo > hi:
            raise click.BadParameter(f"{flag}: LOW must not exceed HIGH")
        if positive and lo <= 0:
            raise click.BadParameter(f"{flag}: scales must be > 0")
        return float(lo), float(hi)
    return check


def _numbers(text: str, spec: str) -> list[float]:
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise click.BadParameter(f"{spec!r}: expected numbers separated by commas "
                                 f"({SHAPES_HELP})", param_hint="PATTERN") from None
    if not all(math.isfinite(v) for v in vals):
        raise click.BadParameter(f"{spec!r}: numbers must be finite", param_hint="PATTERN")
    return vals


def parse_pattern(spec: str, polarity: str | None = None, mask: str | None = None):
    """A :class:`~seahough.Pattern` from an image file or a shape spec.

    ``rect:W,H``, ``line:LENGTH,WIDTH``, ``circle:R``, ``circle:R,INNER``
    (a ring), ``polygon:x1,y1,x2,y2,...``; anything else is an image file.

    >>> parse_pattern("rect:60,40").kind
    'rectangle'
    """
    from ..core.pattern import Pattern

    kind, sep, rest = spec.partition(":")
    kind = kind.strip().lower()
    shapes = {"rect": 2, "rectangle": 2, "line": 2, "circle": (1, 2), "ring": 2,
              "polygon": None, "poly": None}
    if sep and kind in shapes and not Path(spec).is_file():
        pol = _SHAPE_POLARITY[polarity or "bright"]
        if mask is not None:
            raise click.BadParameter("--mask applies to image patterns, not shapes",
                                     param_hint="--mask")
        v = _numbers(rest, spec)
        want = shapes[kind]
        usage = {"rect": "rect:W,H (e.g. rect:60,40)", "rectangle": "rect:W,H (e.g. rect:60,40)",
                 "line": "line:LENGTH,WIDTH (e.g. line:200,8)",
                 "circle": "circle:R or circle:R,INNER (e.g. circle:30)",
                 "ring": "ring:R,INNER (e.g. ring:30,20)",
                 "polygon": "polygon:x1,y1,x2,y2,x3,y3,...",
                 "poly": "polygon:x1,y1,x2,y2,x3,y3,..."}[kind]
        ok = (len(v) in want) if isinstance(want, tuple) else (
            len(v) == want if want is not None else (len(v) >= 6 and len(v) % 2 == 0))
        if not ok:
            raise click.BadParameter(f"{spec!r}: expected {usage}", param_hint="PATTERN")
        try:
            if kind in ("rect", "rectangle"):
                return Pattern.rectangle(v[0], v[1], polarity=pol)
            if kind == "line":
                return Pattern.line(v[0], v[1], polarity=pol)
            if kind in ("circle", "ring"):
                return Pattern.circle(v[0], v[1] if len(v) > 1 else None, polarity=pol)
            return Pattern.polygon(np.reshape(v, (-1, 2)), polarity=pol)
        except SeahoughError as e:
            raise click.BadParameter(f"{spec!r}: {e}", param_hint="PATTERN") from None
    p = Path(spec)
    if not p.exists():
        if sep and len(kind) > 1:
            raise click.BadParameter(f"{spec!r} is neither an image file nor a shape "
                                     f"({SHAPES_HELP})", param_hint="PATTERN")
        raise _Fail(f"pattern {spec}: no such file")
    try:
        return Pattern.from_image(spec, mask=mask, polarity=_IMAGE_POLARITY[polarity or "same"])
    except SeahoughError as e:
        raise _Fail(f"pattern {spec}: {_problem(e, spec)}") from None


class _Output:
    """stdout lines that do not tear a progress bar on stderr."""

    def __init__(self, bar=None):
        self.bar = bar

    def __call__(self, line: str = "") -> None:
        if self.bar is not None:
            self.bar.write(line, file=sys.stdout)
        else:
            click.echo(line)
        sys.stdout.flush()

    def error(self, line: str) -> None:
        line = " ".join(line.split())
        if self.bar is not None:
            self.bar.write(f"{PROG}: error: {line}", file=sys.stderr)
        else:
            _err(line)


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def _progress(iterable, total, desc, enabled, unit="img"):
    """A tqdm bar on stderr, only when wanted and stderr is a terminal
    (``disable=None``), wiped when done (``leave=False``)."""
    if not enabled:
        return None
    from tqdm import tqdm
    return tqdm(iterable, total=total, desc=desc, unit=unit, file=sys.stderr, disable=None,
                leave=False, dynamic_ncols=True)


def _table(rows, header, left=False) -> list[str]:
    """Aligned columns (numbers right-aligned, or all left with ``left``)."""
    cols = [header] + rows
    widths = [max(len(str(r[i])) for r in cols) for i in range(len(header))]
    out = []
    for r in cols:
        cells = [str(c) if i == len(header) - 1 else
                 (str(c).ljust(widths[i]) if left else str(c).rjust(widths[i]))
                 for i, c in enumerate(r)]
        out.append("  " + "  ".join(cells).rstrip())
    return out


def _detection_lines(dets) -> list[str]:
    from ..core.detector import FLAG_ALONG_LINE

    if dets and dets[0].kind == "line":
        header = ("#", "line_angle", "offset", "x", "y", "width_scale", "score", "conf", "flags")
        rows = [(i + 1, format_angle(d.line_angle, 2, 180.0), f"{d.line_offset:.2f}",
                 f"{d.x:.2f}", f"{d.y:.2f}", f"{d.scale:.3f}", f"{d.score:.2f}",
                 f"{d.confidence:.2f}",
                 ",".join(f for f in d.flags if f != FLAG_ALONG_LINE))
                for i, d in enumerate(dets)]
    else:
        header = ("#", "x", "y", "scale", "angle", "score", "conf", "flags")
        rows = [(i + 1, f"{d.x:.2f}", f"{d.y:.2f}", f"{d.scale:.3f}", format_angle(d.angle, 2),
                 f"{d.score:.2f}", f"{d.confidence:.2f}", ",".join(d.flags))
                for i, d in enumerate(dets)]
    return _table(rows, header)


# --------------------------------------------------------------------------- group
@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, "--version", "-V", prog_name=PROG,
                      message="%(prog)s %(version)s")
def cli():
    """Find objects in underwater photos by the shape of their edges, and
    measure the camera's motion between photos (photo dead reckoning).

    \b
    Exit status: 0 success; 1 detect: the pattern was not found in some
    image, odometry: some frames are flagged; 2 bad input (missing or
    unreadable file, bad parameter), one line on stderr.
    Try `seahough demo` for a tour that needs no files.
    """


# -------------------------------------------------------------------------- detect
@cli.command(no_args_is_help=True)
@click.argument("pattern", metavar="PATTERN")
@click.argument("images", nargs=-1, required=True, metavar="IMAGE...")
@click.option("--scale-range", nargs=2, type=float, default=tuple(_DET["scale_range"]),
              show_default=True, metavar="LOW HIGH", callback=_range_callback(True),
              help="Sizes to search, relative to the pattern; LOW = HIGH: known size.")
@click.option("--angle-range", nargs=2, type=float, default=tuple(_DET["angle_range"]),
              show_default=True,
              metavar="LOW HIGH", callback=_range_callback(False),
              help="Rotations to search, degrees counter-clockwise; LOW = HIGH: known rotation.")
@click.option("--max-results", "-n", type=click.IntRange(min=1), default=_DET["max_results"],
              show_default=True,
              help="At most this many detections per image.")
@click.option("--min-score", type=click.FloatRange(0.0, 1.0), default=_DET["min_score"],
              show_default=True,
              help="Least share of the pattern's edges that must be found.")
@click.option("--min-confidence", type=click.FloatRange(0.0, 1.0),
              default=_DET["min_confidence"], show_default=True,
              help="Least distinctness of the accumulator peak.")
@click.option("--downscale", type=click.FloatRange(0.0, 1.0, min_open=True), default=None,
              help="Work on the image scaled by this factor (default: automatic).")
@click.option("--keypoints", type=click.IntRange(min=1), default=None,
              help=f"Number of most contrasted edge points kept (default {_CFG.n_keypoints}).")
@click.option("--equalize", is_flag=True, help="Local contrast equalisation (haze, uneven light).")
@click.option("--polarity", type=click.Choice(["same", "inverted", "either", "bright", "dark"]),
              default=None, help="Contrast of the object: as in the pattern image (same; for "
              "shapes: bright on dark), inverted (dark), or either.")
@click.option("--mask", type=click.Path(dir_okay=False), default=None,
              help="Image pattern only: mask of the object's pixels (non-zero).")
@click.option("--json", "as_json", is_flag=True,
              help="One JSON object per image and line (JSON Lines) instead of tables.")
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Write pictures per image here: <stem>_overlay.png (detections), "
              "<stem>_accumulator.png (the vote planes) and <stem>_edges.png (gradients, key "
              "points and segments).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar or notes; results only.")
def detect(pattern, images, scale_range, angle_range, max_results, min_score, min_confidence,
           downscale, keypoints, equalize, polarity, mask, as_json, out, quiet):
    """Find PATTERN in each IMAGE.

    \b
    PATTERN is an image file of the object (its centre is the origin) or
    a shape (pixels):
      rect:W,H           a filled rectangle (the paper's marker)
      line:LENGTH,WIDTH  a rope, cable or pipe: reports its angle and offset
      circle:R           a disc;  circle:R,INNER  a ring
      polygon:x1,y1,x2,y2,x3,y3,...

    \b
    Positions are pattern-origin pixels (x right, y down); angles degrees
    counter-clockwise as displayed, in [0, 360) (lines: [0, 180)). When the
    search could not run, the line says why, e.g. "not found (no edges)" or
    "not found (pattern larger than the image)"; the JSON "note" field holds
    the same ("" when the search ran). A progress bar is shown on stderr
    for several images when stderr is a terminal.

    \b
    Exit status: 0 the pattern was found in every image; 1 it was not found
    in some image; 2 bad input (the good images' results are still printed,
    each bad file gets one line on stderr).

    \b
    Example:
      seahough detect marker.png dive/*.jpg --scale-range 0.5 2 --json
    """
    from ..io.images import read_image

    cfg_kw = {}
    if downscale is not None:
        cfg_kw["downscale"] = downscale
    if keypoints is not None:
        cfg_kw["n_keypoints"] = keypoints
        cfg_kw["n_keypoints_2d"] = keypoints
    if equalize:
        cfg_kw["equalize"] = True
    cfg = Config(**cfg_kw)
    pat = parse_pattern(pattern, polarity, mask)
    detector = Detector(pat, scale_range, angle_range, config=cfg, max_results=max_results,
                        min_score=min_score, min_confidence=min_confidence)
    out_dir = None
    if out is not None:
        out_dir = Path(out)
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise _Fail(f"--out {out}: cannot create the folder ({e.strerror or e})") from None
    bar = _progress(images, len(images), "detect", len(images) > 1 and not quiet)
    say = _Output(bar)
    n_bad = n_missing = 0
    stems: dict[str, int] = {}
    for name in (bar if bar is not None else images):
        t0 = time.perf_counter()
        try:
            img = read_image(name, max_pixels=cfg.max_pixels)
            res = detector.search(img)
        except SeahoughError as e:
            say.error(f"{name}: {_problem(e, name)}")
            n_bad += 1
            continue
        ms = 1000.0 * (time.perf_counter() - t0)
        dets = res.detections
        # why the search could not run (SearchResult.note), e.g. " (no edges)"
        why = f" ({res.note})" if res.note else ""
        h, w = img.shape[:2]
        written = {}
        if out_dir is not None:
            from .. import viz as plot

            stem = Path(name).stem
            k = stems.get(stem, 0)
            stems[stem] = k + 1
            if k:
                stem = f"{stem}_{k + 1}"
            n = len(dets)
            head = f"{Path(name).name}: " + (f"not found{why}" if n == 0 else
                                             f"{n} detection{'s' if n > 1 else ''}")
            ov = out_dir / f"{stem}_overlay.png"
            ac = out_dir / f"{stem}_accumulator.png"
            ed = out_dir / f"{stem}_edges.png"
            plot.plot_detections(img, dets, ov, pattern=pat, title=head)
            plot.plot_accumulator(res.planes, dets, ac, title=f"{Path(name).name}: accumulator",
                                  note=res.note)
            plot.plot_edges(img, res.features, ed,
                            title=f"{Path(name).name}: what the detector sees")
            written = {"overlay": str(ov), "accumulator": str(ac), "edges": str(ed)}
        if not dets:
            n_missing += 1
        if as_json:
            rec = {"file": name, "width": int(w), "height": int(h), "found": bool(dets),
                   "note": res.note, "detections": [d.to_dict() for d in dets],
                   "time_ms": round(ms, 3)}
            rec.update(written)
            say(_dumps(rec))
        else:
            if dets:
                say(f"{name}  {w}x{h}  {len(dets)} found  ({ms:.0f} ms)")
                for line in _detection_lines(dets):
                    say(line)
            else:
                say(f"{name}  {w}x{h}  not found{why}  ({ms:.0f} ms)")
            if written and not quiet:
                say("  wrote " + ", ".join(written.values()))
    if bar is not None:
        bar.close()
    if n_bad:
        return 2
    return 1 if n_missing else 0


# ------------------------------------------------------------------------ odometry
def _path_length(rows) -> float:
    pts = np.array([[float(r.get("x", np.nan)), float(r.get("y", np.nan))] for r in rows], float)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0


def _odometry_rows(result):
    """The run's rows one at a time (a long survey's rows are not all loaded)."""
    it = getattr(result, "iter_rows", None)
    return it() if callable(it) else iter(result.rows)


def _odometry_summary(result, wall_s: float, unit: str) -> dict:
    s = dict(getattr(result, "summary", {}) or {})
    # the summary has the counts; the rows are read only where it lacks them
    n = s.get("frames")
    if not isinstance(n, int):
        n = sum(1 for _ in _odometry_rows(result))
    flagged = s.get("flagged_pairs")
    if not isinstance(flagged, int):
        flagged = sum(1 for r in _odometry_rows(result) if r.get("flags") and r.get("index", 0) > 0)
    dist = s.get("distance")
    if not isinstance(dist, (int, float)) or not math.isfinite(dist):
        dist = _path_length(list(_odometry_rows(result)))
    unit = s.get("unit", unit)
    per = None
    for key in ("time_per_frame_ms", "ms_per_frame"):
        if isinstance(s.get(key), (int, float)):
            per = float(s[key])
            break
    if per is None and isinstance(s.get("time_per_frame_s"), (int, float)):
        per = 1000.0 * float(s["time_per_frame_s"])
    if per is None:
        per = 1000.0 * wall_s / max(n, 1)
    return {"frames": n, "flagged_pairs": flagged, "distance": float(dist), "unit": unit,
            "time_per_frame_ms": per,
            "csv": _str_or_none(getattr(result, "csv_path", None)),
            "json": _str_or_none(getattr(result, "json_path", None)),
            "mosaic": _str_or_none(getattr(result, "mosaic_path", None)),
            "trajectory": _str_or_none(getattr(result, "trajectory_path", None)),
            "summary": s}


def _str_or_none(p):
    return None if p is None else str(p)


def _import_odometry():
    try:
        from ..motion.odometry import run_odometry
    except ImportError as e:
        if "odometry" not in str(e):
            raise
        raise _Fail("odometry is not available in this installation (seahough.odometry "
                    "is missing)") from None
    return run_odometry


@cli.command(no_args_is_help=True)
@click.argument("frames", nargs=-1, required=True, metavar="FRAMES...")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for the CSV/JSON track, the mosaic and the trajectory plot.")
@click.option("--metres-per-pixel", type=click.FloatRange(0.0, min_open=True), default=None,
              help="Ground size of a pixel, for positions in metres.")
@click.option("--altitude", type=click.FloatRange(0.0, min_open=True), default=None,
              help="Camera height above the bottom, metres (with --focal-px).")
@click.option("--focal-px", type=click.FloatRange(0.0, min_open=True), default=None,
              help="Focal length in pixels (with --altitude).")
@click.option("--scale-range", nargs=2, type=float, default=(0.9, 1.1), show_default=True,
              metavar="LOW HIGH", callback=_range_callback(True),
              help="Size change between frames (altitude change); LOW = HIGH: known.")
@click.option("--angle-range", nargs=2, type=float, default=(-20.0, 20.0), show_default=True,
              metavar="LOW HIGH", callback=_range_callback(False),
              help="Turn between frames, degrees; LOW = HIGH: known heading change.")
@click.option("--resume", is_flag=True, help="Continue a run interrupted in the same --out.")
@click.option("--no-mosaic", is_flag=True, help="Do not build the mosaic.")
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar (shown on stderr only when it is a terminal).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object.")
def odometry(frames, out, metres_per_pixel, altitude, focal_px, scale_range, angle_range,
             resume, no_mosaic, quiet, as_json):
    """Dead reckoning: the camera's path from overlapping frames.

    \b
    FRAMES is a folder of images (in the order of the timestamps in their
    names when every name has one, e.g. cam_20240210_134109.500.png, else in
    natural name order: f2 before f10), one or more video files (read frame
    by frame, one after the other), or image files in the order given. An earlier frame (a keyframe) is the pattern searched
    for in each frame; the accumulator peak is the motion. Positions are in pixels of the first
    frame, or metres with --metres-per-pixel, or --altitude and --focal-px.
    Writes odometry.csv, summary.json, trajectory.png and mosaic.png to --out.

    \b
    Exit status: 0 every pair of frames was measured; 1 some frames are
    flagged (unreadable, or their motion could not be measured: see the
    CSV's flags column); 2 bad input.

    \b
    Example:
      seahough odometry dive/frames --out track --altitude 2.5 --focal-px 800
    """
    if metres_per_pixel is not None and (altitude is not None or focal_px is not None):
        raise click.UsageError("give --metres-per-pixel or --altitude with --focal-px, not both")
    if (altitude is None) != (focal_px is None):
        raise click.UsageError("--altitude and --focal-px go together")
    for f in frames:
        if not Path(f).exists():
            raise _Fail(f"{f}: no such file or folder")
    run_odometry = _import_odometry()
    unit = "m" if (metres_per_pixel is not None or altitude is not None) else "px"
    t0 = time.perf_counter()
    result = run_odometry(list(frames), out, metres_per_pixel=metres_per_pixel,
                          altitude=altitude, focal_px=focal_px, scale_range=scale_range,
                          angle_range=angle_range, resume=resume,
                          progress=not quiet and _stderr_is_terminal(), mosaic=not no_mosaic)
    summ = _odometry_summary(result, time.perf_counter() - t0, unit)
    status = 1 if summ["flagged_pairs"] else 0
    if as_json:
        click.echo(_dumps(summ))
        return status
    click.echo(f"frames: {summ['frames']}   flagged pairs: {summ['flagged_pairs']}   "
               f"distance: {summ['distance']:.2f} {summ['unit']}   "
               f"time per frame: {summ['time_per_frame_ms']:.0f} ms")
    n_flagged = 0
    for r in _odometry_rows(result):
        if not r.get("flags"):
            continue
        n_flagged += 1
        if n_flagged <= 10:
            click.echo(f"  flagged: frame {r.get('index')} {r.get('file')}: {r.get('flags')}")
    if n_flagged > 10:
        click.echo(f"  ... and {n_flagged - 10} more (see the CSV's flags column)")
    files = [summ[k] for k in ("csv", "json", "trajectory", "mosaic") if summ[k]]
    if files:
        click.echo("wrote: " + ", ".join(files))
    return status


# ------------------------------------------------------------------------ simulate
def _water_arg(name: str):
    return None if name == "none" else name


def _truth_dict(truth) -> dict:
    import dataclasses

    d = {}
    for f in dataclasses.fields(truth):
        v = getattr(truth, f.name)
        if v is None:
            continue
        d[f.name] = np.asarray(v).tolist() if isinstance(v, np.ndarray) else (
            float(v) if isinstance(v, (float, np.floating)) else v)
    return d


def _imwrite(path: Path, image) -> None:
    import cv2

    if not cv2.imwrite(os.fspath(path), image):
        raise _Fail(f"{path}: cannot write the image")


def write_simulation(kind: str, out: Path, *, n: int | None = None, seed: int = 0,
                     water: str = "moderate", marker_name: str = "board",
                     size: tuple[int, int] | None = None, path: str = "line",
                     procedural: bool = False, progress: bool = False) -> dict:
    """Write simulated scenes of ``kind`` and their ``truth.json`` into ``out``.

    ``progress``: a progress bar on stderr (when it is a terminal) for more
    than one scene or frame. Returns the truth dictionary (also written as
    ``out/truth.json``).
    """
    out.mkdir(parents=True, exist_ok=True)
    wat = _water_arg(water)
    source = "procedural" if procedural else "auto"
    if size is None:
        size = (320, 240) if kind == "sequence" else (640, 480)
    w, h = size
    truth: dict = {"kind": kind, "seed": seed, "water": water, "width": w, "height": h,
                   "source": source, "convention": (
                       "pixels (x right, y down), (0, 0) = centre of the top-left pixel; "
                       "angles in degrees counter-clockwise as displayed; matrices are 2x3, "
                       "pattern (or previous-frame) pixel -> scene pixel")}
    count = n if n is not None else (10 if kind == "sequence" else 1)
    unit = "frame" if kind == "sequence" else ("pair" if kind == "pair" else "scene")
    bar = _progress(None, count, "simulate", progress and count > 1, unit=unit)
    try:
        _simulate_into(kind, out, truth, count, bar, seed=seed, wat=wat, source=source,
                       marker_name=marker_name, size=(w, h), path=path)
    finally:
        if bar is not None:
            bar.close()
    (out / "truth.json").write_text(_dumps(truth, indent=1) + "\n")
    return truth


def _simulate_into(kind, out: Path, truth: dict, count: int, bar, *, seed, wat, source,
                   marker_name, size, path) -> None:
    """The scenes of :func:`write_simulation`, written one by one (``bar``
    ticks per scene or frame written)."""
    from .. import sim
    from ..geometry import apply_matrix, compose, invert_matrix

    tick = (lambda: None) if bar is None else (lambda: bar.update(1))
    w, h = size
    if kind == "sequence":
        if bar is not None:
            bar.set_description("simulate (rendering)")
        frames, mats = sim.sequence(n_frames=count, frame_size=(h, w), path=path, water=wat,
                                    seed=seed, source=source)
        if bar is not None:
            bar.set_description("simulate")
        c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
        rows = []
        for i, (f, m) in enumerate(zip(frames, mats)):
            name = f"frame_{i:03d}.png"
            _imwrite(out / name, f)
            centre = apply_matrix(invert_matrix(m), [c])[0]
            row = {"file": name, "matrix_from_first": np.asarray(m).tolist(),
                   "centre_in_first": centre.tolist()}
            if i:
                row["motion_from_previous"] = compose(m, invert_matrix(mats[i - 1])).tolist()
            rows.append(row)
            tick()
        truth.update(path=path, frames=rows)
    else:
        scenes = []
        if kind == "marker":
            pat, mask = sim.marker(marker_name)
            _imwrite(out / "pattern.png", pat)
            _imwrite(out / "pattern_mask.png", mask)
            truth.update(marker=marker_name, pattern="pattern.png", pattern_mask="pattern_mask.png")
        for i in range(count):
            s = seed + i
            if kind == "marker":
                scene, _, tr = sim.marker_scene(marker_name, (h, w), water=wat, seed=s,
                                                source=source)
                name = f"marker_{i:03d}.png"
                _imwrite(out / name, scene)
                scenes.append({"file": name, "seed": s, **_truth_dict(tr)})
            elif kind == "negative":
                scene = sim.negative_scene((h, w), water=wat, seed=s, source=source)
                name = f"negative_{i:03d}.png"
                _imwrite(out / name, scene)
                scenes.append({"file": name, "seed": s, "marker": False})
            elif kind == "rope":
                width = 8.0
                scene, tr = sim.rope_scene((h, w), width=width, water=wat, seed=s, source=source)
                name = f"rope_{i:03d}.png"
                _imwrite(out / name, scene)
                scenes.append({"file": name, "seed": s, "width": width, **_truth_dict(tr)})
            elif kind == "pair":
                a, b, tr = sim.frame_pair(frame_size=(h, w), water=wat, seed=s, source=source)
                na, nb = f"pair_{i:03d}_a.png", f"pair_{i:03d}_b.png"
                _imwrite(out / na, a)
                _imwrite(out / nb, b)
                scenes.append({"previous": na, "current": nb, "seed": s, **_truth_dict(tr)})
            else:  # pragma: no cover - click restricts the choice
                raise _Fail(f"unknown kind {kind!r}")
            tick()
        truth["scenes"] = scenes


@cli.command(no_args_is_help=True)
@click.argument("kind", type=click.Choice(SIM_KINDS), metavar="KIND")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for the PNG scenes and truth.json.")
@click.option("--n", "-n", "count", type=click.IntRange(min=1, max=10000), default=None,
              help="Number of scenes (default 1), or of frames for a sequence (default 10).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True)
@click.option("--water", type=click.Choice(WATER_CHOICES), default="moderate", show_default=True,
              help="Water conditions (none: no degradation).")
@click.option("--marker", "marker_name", type=click.Choice(["board", "rectangle", "L", "cross"]),
              default="board", show_default=True, help="Marker drawn in marker scenes.")
@click.option("--size", nargs=2, type=click.IntRange(min=16, max=8192), default=None,
              metavar="W H", help="Scene size in px (default 640 480; sequence 320 240).")
@click.option("--path", "path_kind", type=click.Choice(["line", "turn", "loop"]), default="line",
              show_default=True, help="Camera path of a sequence.")
@click.option("--procedural", is_flag=True,
              help="Procedural seabed backgrounds only (default: real photos when the shared "
              "data folder is present).")
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar or hint; only the line saying what was written.")
def simulate(kind, out, count, seed, water, marker_name, size, path_kind, procedural, quiet):
    """Write synthetic underwater scenes with exact ground truth.

    \b
    KIND: marker    a seabed photo with a docking marker (plus pattern.png)
          rope      a rope across the frame
          pair      two overlapping camera frames (a known motion)
          sequence  frames along a camera path (for `seahough odometry`)
          negative  seabed photos with no marker
    truth.json holds the poses (matrix, x, y, scale, angle), rope angle and
    offset, or motions, so you can test your own settings. A progress bar
    is shown on stderr for several scenes when stderr is a terminal.
    """
    o = Path(out)
    try:
        o.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _Fail(f"--out {out}: cannot create the folder ({e.strerror or e})") from None
    truth = write_simulation(kind, o, n=count, seed=seed, water=water, marker_name=marker_name,
                             size=tuple(size) if size else None, path=path_kind,
                             procedural=procedural, progress=not quiet)
    n_files = len(truth.get("frames", truth.get("scenes", [])))
    what = "frames" if kind == "sequence" else ("pairs" if kind == "pair" else "scenes")
    click.echo(f"wrote {n_files} {what} and {o / 'truth.json'}")
    if quiet:
        return 0
    if kind == "marker":
        click.echo(f"try: {PROG} detect {o / 'pattern.png'} {o / 'marker_*.png'}")
    elif kind == "rope":
        click.echo(f"try: {PROG} detect line:200,8 {o / 'rope_*.png'} --angle-range 0 180")
    elif kind == "negative":
        click.echo(f"try: {PROG} detect rect:60,60 {o / 'negative_*.png'}  (expect exit status 1)")
    elif kind == "sequence":
        click.echo(f"try: {PROG} odometry {o} --out {o.parent / (o.name + '_odometry')}")
    return 0


# ---------------------------------------------------------------------------- demo
def _angle_err(a, b, period=360.0):
    return abs((a - b + period / 2) % period - period / 2)


@cli.command(short_help="A tour that needs no files: simulate, detect, dead-reckon.")
@click.option("--out", "-o", type=click.Path(file_okay=False), default="seahough-demo",
              show_default=True, help="Folder for the scenes and pictures.")
@click.option("--quiet", "-q", is_flag=True, help="No progress or file list; the table only.")
def demo(out, quiet):
    """A tour with no files and no network: simulate, detect, dead-reckon.

    Makes an underwater scene with a board marker, one with a rope and a
    short seabed sequence; finds the marker (from its clean image) and the
    rope (a line pattern), dead-reckons the sequence, writes every picture
    to --out and prints what was found against the truth.
    """
    from .. import viz as plot
    from .. import sim
    from ..geometry import apply_matrix, invert_matrix
    from ..core.pattern import Pattern

    o = Path(out)
    o.mkdir(parents=True, exist_ok=True)
    note = (lambda s: None) if quiet else (lambda s: click.echo(s, err=True))
    t_start = time.perf_counter()
    rows_out = []   # (what, found, truth, error)
    written = []

    # 1. the marker
    note("demo: marker scene ...")
    scene, pat_img, tr = sim.marker_scene("board", water="moderate", seed=11, source="procedural")
    _imwrite(o / "marker_scene.png", scene)
    _imwrite(o / "marker_pattern.png", pat_img)
    pat = Pattern.from_image(pat_img)
    res = Detector(pat, scale_range=(0.5, 2.0)).search(scene)
    d = res.detections[0] if res.detections else None
    plot.plot_detections(scene, res.detections, o / "marker_overlay.png", pattern=pat,
                         title="marker: Pattern.from_image(clean marker), scale 0.5-2, "
                         "any rotation")
    plot.plot_accumulator(res.planes, res.detections, o / "marker_accumulator.png",
                          title="marker: accumulator planes")
    plot.plot_edges(scene, res.features, o / "marker_edges.png", title="marker scene: edges")
    written += ["marker_scene.png", "marker_overlay.png", "marker_accumulator.png",
                "marker_edges.png"]
    ok = d is not None
    if ok:
        rows_out += [
            ("marker position", f"({d.x:.1f}, {d.y:.1f}) px", f"({tr.x:.1f}, {tr.y:.1f}) px",
             f"{math.hypot(d.x - tr.x, d.y - tr.y):.2f} px"),
            ("marker angle", f"{format_angle(d.angle)}°", f"{format_angle(tr.angle)}°",
             f"{_angle_err(d.angle, tr.angle):.2f}°"),
            ("marker scale", f"{d.scale:.3f}", f"{tr.scale:.3f}",
             f"{100 * abs(d.scale / tr.scale - 1):.2f} %"),
        ]
    else:
        rows_out.append(("marker", "NOT FOUND", f"({tr.x:.1f}, {tr.y:.1f}) px", "-"))

    # 2. the rope
    note("demo: rope scene ...")
    rope, rtr = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    _imwrite(o / "rope_scene.png", rope)
    lp = Pattern.line(200, 8)
    rres = Detector(lp, scale_range=(0.5, 2.0), angle_range=(0.0, 180.0),
                    max_results=1).search(rope)
    rd = rres.detections[0] if rres.detections else None
    plot.plot_detections(rope, rres.detections, o / "rope_overlay.png", pattern=lp,
                         title="rope: Pattern.line(200, 8), any direction")
    plot.plot_accumulator(rres.planes, rres.detections, o / "rope_accumulator.png",
                          title="rope: accumulator planes")
    written += ["rope_scene.png", "rope_overlay.png", "rope_accumulator.png"]
    if rd is not None:
        rows_out += [
            ("rope angle", f"{format_angle(rd.line_angle, 2, 180.0)}°",
             f"{format_angle(rtr.line_angle, 2, 180.0)}°",
             f"{_angle_err(rd.line_angle, rtr.line_angle, 180.0):.2f}°"),
            ("rope offset", f"{rd.line_offset:+.1f} px", f"{rtr.line_offset:+.1f} px",
             f"{abs(rd.line_offset - rtr.line_offset):.2f} px"),
        ]
    else:
        ok = False
        rows_out.append(("rope", "NOT FOUND", f"{format_angle(rtr.line_angle, 2, 180.0)}°", "-"))

    # 3. dead reckoning
    note("demo: seabed sequence and dead reckoning ...")
    frames, mats = sim.sequence(n_frames=8, frame_size=(240, 320), path="turn", step=24.0,
                                water="moderate", seed=3, source="procedural")
    seq_dir = o / "sequence"
    seq_dir.mkdir(exist_ok=True)
    for i, f in enumerate(frames):
        _imwrite(seq_dir / f"frame_{i:03d}.png", f)
    written.append("sequence/frame_000.png ... frame_007.png")
    c = np.array([(320 - 1) / 2.0, (240 - 1) / 2.0])
    true_xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
    try:
        run_odometry = _import_odometry()
    except _Fail as e:
        run_odometry = None
        rows_out.append(("odometry", "skipped", "-", str(e)))
    if run_odometry is not None:
        odo_dir = o / "odometry"
        result = run_odometry([str(seq_dir)], str(odo_dir), scale_range=(0.9, 1.1),
                              angle_range=(-20.0, 20.0),
                              progress=not quiet and _stderr_is_terminal(), mosaic=True)
        rows = list(result.rows)
        # x, y: where each frame's centre lies in frame-0 pixels, as the truth
        est = np.array([[np.nan if r.get("x") is None else float(r["x"]),
                         np.nan if r.get("y") is None else float(r["y"])] for r in rows], float)
        plot.plot_trajectory(rows, o / "trajectory.png", truth=true_xy,
                             title="dead reckoning over 8 simulated frames (grey band: truth)")
        written.append("trajectory.png")
        for name in ("mosaic_path", "trajectory_path", "csv_path"):
            p = getattr(result, name, None)
            if p:
                written.append(os.path.relpath(str(p), str(o)))
        length = float(np.hypot(*np.diff(true_xy, axis=0).T).sum())
        flagged = sum(1 for r in rows[1:] if r.get("flags"))
        end = est[-1] - est[0]
        true_end = true_xy[-1] - true_xy[0]
        if np.all(np.isfinite(end)):
            drift = 100 * float(np.hypot(*(end - true_end))) / max(length, 1e-9)
            err = f"drift {drift:.2f} % of {length:.0f} px"
        else:
            ok, err = False, "no position for the last frame"
        rows_out.append(("odometry end point", f"({end[0]:+.1f}, {end[1]:+.1f}) px",
                         f"({true_end[0]:+.1f}, {true_end[1]:+.1f}) px",
                         err + (f", {flagged} flagged" if flagged else "")))
    click.echo(f"{PROG} demo: found vs truth (simulated scenes, moderate water)")
    for line in _table(rows_out, ("what", "found", "truth", "error"), left=True):
        click.echo(line)
    if not quiet:
        click.echo(f"pictures in {o}: " + ", ".join(written))
    click.echo(f"done in {time.perf_counter() - t_start:.1f} s")
    return 0 if ok else 1


# ----------------------------------------------------------------------------- main
def main(argv=None) -> None:
    """Entry point of the ``seahough`` command (and ``python -m seahough``)."""
    try:
        rv = cli.main(args=argv, prog_name=PROG, standalone_mode=False)
    except click.exceptions.NoArgsIsHelpError as e:
        click.echo(e.ctx.get_help())
        rv = 0
    except click.ClickException as e:
        msg = e.format_message()
        ctx = getattr(e, "ctx", None)
        if isinstance(e, click.UsageError) and ctx is not None:
            msg += f" (see '{ctx.command_path} --help')"
        _err(msg)
        rv = e.exit_code
    except click.exceptions.Abort:
        _err("interrupted")
        rv = 130
    except KeyboardInterrupt:
        _err("interrupted")
        rv = 130
    except _Fail as e:
        _err(str(e))
        rv = 2
    except SeahoughError as e:
        _err(str(e))
        rv = 2
    except BrokenPipeError:
        # the reader went away (e.g. `| head`): stop quietly
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except OSError:
            pass
        rv = 141
    except OSError as e:
        where = f"{e.filename}: " if getattr(e, "filename", None) else ""
        _err(f"{where}{e.strerror or e}")
        rv = 2
    sys.exit(rv if isinstance(rv, int) else 0)


if __name__ == "__main__":  # pragma: no cover
    main()
