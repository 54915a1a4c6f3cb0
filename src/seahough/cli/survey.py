"""``seahough survey``: many photos on every core or a Dask cluster.

``survey detect`` takes the search options of ``seahough detect`` (the same
click options, taken from that command) and writes Parquet; ``survey
odometry`` takes those of ``seahough odometry`` and writes what it writes.
The work is :mod:`seahough.survey`'s.
"""

from __future__ import annotations

import csv
import importlib
import json
import os
import time
from pathlib import Path
from types import SimpleNamespace

import click

from ..io.frames import printable
from ._common import (_Fail, _dumps, _say_kept, _stderr_is_terminal, _Terminated, make_detector,
                      workers_option)

__all__ = ["survey"]

#: The options of ``seahough detect`` that ``survey detect`` takes too.
SEARCH_OPTIONS = ("scale_range", "angle_range", "max_results", "min_score", "min_confidence",
                  "max_nfa", "downscale", "keypoints", "equalize", "smooth", "ignore", "bit_depth",
                  "colour",
                  "polarity", "mask")
#: The options of ``seahough odometry`` that ``survey odometry`` takes too.
ODOMETRY_OPTIONS = ("metres_per_pixel", "altitude", "focal_px", "scale_range", "angle_range",
                    "no_mosaic", "equalize", "fps", "bit_depth")
#: Error rows listed after a survey (the rest: in images.parquet).
SHOW_ERRORS = 10


def _borrow(command: click.Command, names) -> list[click.Parameter]:
    """The parameters ``names`` of another command, the same objects."""
    params = {p.name: p for p in command.params}
    return [params[n] for n in names]


def _cluster_options(f):
    f = click.option("--scheduler", metavar="ADDRESS", default=None,
                     help="Use the running Dask scheduler at ADDRESS (tcp://host:8786) "
                     "instead of a local cluster; its workers must read the files at the "
                     "same paths.")(f)
    return workers_option("Worker processes of the local Dask cluster, one thread each; "
                          "ignored with --scheduler")(f)


@click.group(no_args_is_help=True)
def survey():
    """Thousands of photos on every core or a Dask cluster, into Parquet.

    \b
    A local cluster of --workers processes by default, or a running Dask
    cluster with --scheduler ADDRESS (see docs/scale.md for SLURM/PBS).
    Needs Dask: pip install 'seahough[survey]'.
    """


def _kept(out) -> str:
    """What an interrupted survey in ``out`` kept, in words ("" when unknown)."""
    import pyarrow.parquet as pq

    try:
        total = json.loads((Path(out) / "survey.json").read_text())["inputs"]["count"]
        done = sum(pq.read_metadata(p).num_rows
                   for p in (Path(out) / "parts").glob("images-*.parquet"))
    except (OSError, ValueError, KeyError, TypeError, ImportError):
        return ""
    return (f"{done} of {total} images searched and kept in {printable(out)}; the same "
            "command goes on with the others")


def _chunks_kept(out) -> str:
    """What an interrupted survey odometry in ``out`` kept, in words."""
    done = len(list((Path(out) / "chunks").glob("*/summary.json")))
    return (f"{done} chunk{'s' if done != 1 else ''} of frames measured and kept in "
            f"{printable(out)}; the same command goes on with the others")


def _errors(images_path: Path, limit: int) -> list[tuple[str, str]]:
    """The first ``limit`` error rows of images.parquet: (path, error)."""
    import pyarrow.parquet as pq

    t = pq.read_table(images_path, columns=["path", "error"],
                      filters=[("status", "=", "error")])
    return list(zip(t.column("path").to_pylist()[:limit], t.column("error").to_pylist()[:limit]))


@survey.command("detect", no_args_is_help=True)
@click.argument("pattern", metavar="PATTERN")
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for images.parquet, detections.parquet and survey.json.")
@_cluster_options
@click.option("--batch-size", type=click.IntRange(min=1), default=None, metavar="N",
              help="Images per task (default: up to 16).")
@click.option("--retry-errors", is_flag=True,
              help="Search again the images that could not be read or searched before "
                   "(status error).")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object.")
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar (shown on stderr only when it is a terminal).")
def detect(pattern, inputs, out, workers, scheduler, batch_size, retry_errors, as_json, quiet,
           **search):
    """Find PATTERN in every image of INPUT... (a survey).

    \b
    INPUT is an image file, a folder (its images, in natural name order, or in the
    order of the timestamps in their names; not its subfolders, which a
    note names), or @LIST.txt: a file of paths,
    one a line (a shell cannot pass 100,000 names); a file or folder given
    here that does not exist is bad input (exit 2), one listed in @LIST.txt
    gets an error row. PATTERN and the search options are those of
    `seahough detect`, but for curve:WIDTH (found by `seahough detect`).

    \b
    Writes to --out:
      images.parquet      one row per image: index, path, status (found,
                          not found, error), n_detections, ms, width,
                          height, note, error
      detections.parquet  one row per detection: index, path, rank, x, y,
                          scale, angle, score, confidence, nfa (number
                          of false alarms), matrix (6 numbers, 2x3
                          row-major), votes, kind, line_angle,
                          line_offset, flags, pattern (its name, for
                          several patterns: NAME=SPEC+NAME=SPEC), segment
                          (a line's visible extent: x0 y0 x1 y1),
                          stretches (a line's stretches seen, each x0 y0
                          x1 y1), width (a line's band, px)
      survey.json         the settings, the inputs and the counts
    Results are saved in shards as they come (parts/): run the same
    command again to continue an interrupted survey (nothing is searched
    twice; a complete survey is not searched again), with more images
    after its own (a folder a dive is still adding to) to search those
    too, with --retry-errors to search its unreadable images again.
    Another survey in the same --out (other settings or images) is refused.

    \b
    Exit status: 0 every image was searched (found or not: see the counts);
    1 some images could not be read (rows with status "error", the first
    listed); 2 bad input (parameters, no images, --out, --scheduler); 130
    interrupted (Ctrl-C: the line says how many images were kept), 143
    terminated (SIGTERM): the images searched are kept, and the same
    command goes on where it stopped.

    \b
    Example:
      seahough survey detect marker.png dive/ @more.txt --out found --workers 8
    """
    from ..survey.detect import detect as run_survey

    if pattern.strip().lower().startswith("curve:") and not Path(pattern).is_file():
        raise click.BadParameter(f"{pattern!r}: curves are found by 'seahough detect', not "
                                 "by a survey", param_hint="PATTERN")
    detector = make_detector(pattern, **search)
    # a path typed on the command line that is not there is a typo, not a photo
    # that failed: nothing is started (paths in @LIST files get error rows)
    for item in inputs:
        if not item.startswith("@") and not Path(item).exists() and not os.path.islink(item):
            raise _Fail(f"{printable(item)}: no such file or folder")
    try:
        result = run_survey(detector, list(inputs), out, workers=workers,
                            scheduler=scheduler, batch_size=batch_size,
                            progress=not quiet and _stderr_is_terminal(),
                            retry_errors=retry_errors)
    except (KeyboardInterrupt, _Terminated, SystemError) as e:
        # (Ctrl-C inside a compiled kernel is a SystemError caused by it: what
        # was kept is said the same way; a trial saw a bare "interrupted")
        _say_kept(e, _kept(out))
    errors = _errors(result.images, SHOW_ERRORS) if result.errors else []
    summary = {"images": result.total, "found": result.found, "not_found": result.not_found,
               "errors": result.errors, "detections": result.n_detections,
               "searched_now": result.processed, "seconds": round(result.seconds, 3),
               "files": {"images": str(result.images), "detections": str(result.detections),
                         "manifest": str(result.manifest)}}
    status = 1 if result.errors else 0
    if as_json:
        summary["first_errors"] = [{"path": p, "error": e} for p, e in errors]
        click.echo(_dumps(summary))
        return status
    click.echo(f"images: {result.total}   found: {result.found}   not found: "
               f"{result.not_found}   errors: {result.errors}   detections: "
               f"{result.n_detections}")
    if result.processed:
        n = result.processed
        click.echo(f"searched {n} image{'s' if n != 1 else ''} in {result.seconds:.1f} s, "
                   f"cluster start included ({1000.0 * result.seconds / n:.1f} ms per image)")
    else:
        click.echo("nothing to search: the survey in this folder was complete"
                   + (" (--retry-errors searches its unreadable images again)"
                      if result.errors else ""))
    for p, e in errors:
        click.echo(f"  error: {printable(p)}: {printable(e)}")
    if result.errors > len(errors):
        click.echo(f"  ... and {result.errors - len(errors)} more (status \"error\" in "
                   "images.parquet)")
    click.echo(("wrote: " if result.processed else "results: ")
               + ", ".join(printable(p) for p in (result.images, result.detections,
                                                  result.manifest)))
    return status


def _odometry_result(paths: dict):
    """What ``seahough odometry`` prints its summary from, for the files of
    a survey's dead reckoning."""
    summary = {}
    if paths.get("summary"):
        try:
            summary = json.loads(Path(paths["summary"]).read_text())
        except (OSError, ValueError):
            summary = {}

    def iter_rows():
        if not paths.get("csv"):
            return
        with open(paths["csv"], newline="") as f:
            for row in csv.DictReader(f):
                try:
                    row["index"] = int(row.get("index", 0))
                except ValueError:
                    pass
                for k in ("x", "y"):
                    try:
                        row[k] = float(row[k]) if row.get(k) not in (None, "") else None
                    except ValueError:
                        row[k] = None
                yield row

    return SimpleNamespace(summary=summary, iter_rows=iter_rows, csv_path=paths.get("csv"),
                           json_path=paths.get("summary"), mosaic_path=paths.get("mosaic"),
                           trajectory_path=paths.get("trajectory"))


@survey.command("odometry", no_args_is_help=True)
@click.argument("frames", nargs=-1, required=True, metavar="FRAMES...")
@click.option("--out", "-o", required=True, type=click.Path(file_okay=False),
              help="Folder for the CSV/JSON track, the mosaic and the trajectory plot.")
@_cluster_options
@click.option("--chunk-size", type=click.IntRange(min=6), default=200, show_default=True,
              metavar="N", help="Frames per chunk measured in parallel (each with its own "
              "keyframes), chained after.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as one JSON object.")
@click.option("--quiet", "-q", is_flag=True,
              help="No progress bar (shown on stderr only when it is a terminal).")
def odometry(frames, out, workers, scheduler, chunk_size, as_json, quiet, **opts):
    """Dead reckoning over a long sequence, pairs measured in parallel.

    \b
    FRAMES and the options are those of `seahough odometry`; the pairs of
    frames are measured in chunks on the cluster, the chunks chained after
    (the one serial step). Writes the same files: odometry.csv, run.json,
    summary.json, trajectory.png, mosaic.png.

    \b
    Exit status: 0 every pair was measured; 1 some frames are flagged;
    2 bad input; 130 interrupted (Ctrl-C), 143 terminated (SIGTERM): the
    chunks done are kept, and the same command goes on where it stopped.
    """
    from .odometry import _config, check_inputs, report

    mpp, altitude, focal_px = opts["metres_per_pixel"], opts["altitude"], opts["focal_px"]
    check_inputs(frames, mpp, altitude, focal_px)
    # looked up when the command runs (tests stand a stub in for it)
    run = importlib.import_module("seahough.survey.odometry").odometry
    t0 = time.perf_counter()
    try:
        paths = run(list(frames), out, workers=workers, scheduler=scheduler,
                    chunk_size=chunk_size, metres_per_pixel=mpp, altitude=altitude,
                    focal_px=focal_px, scale_range=opts["scale_range"],
                    angle_range=opts["angle_range"], mosaic=not opts["no_mosaic"],
                    progress=not quiet and _stderr_is_terminal(), fps=opts["fps"],
                    **_config(opts["bit_depth"], opts["equalize"]))
    except (KeyboardInterrupt, _Terminated, SystemError) as e:
        # (as survey detect says what it kept: a trial saw a bare "interrupted")
        _say_kept(e, _chunks_kept(out))
    unit = "m" if (mpp is not None or altitude is not None) else "px"
    return report(_odometry_result(paths), time.perf_counter() - t0, unit, as_json)


def _attach() -> None:
    """Give the subcommands the options they take from ``detect`` and
    ``odometry`` (after their own arguments, before their own options)."""
    detect.params[3:3] = _borrow(importlib.import_module(f"{__package__}.detect").detect,
                                 SEARCH_OPTIONS)
    odometry.params[2:2] = _borrow(importlib.import_module(f"{__package__}.odometry").odometry,
                                   ODOMETRY_OPTIONS)


_attach()
