"""``seahough detect``: find a pattern in images."""

from __future__ import annotations

import inspect
import time
from pathlib import Path

import click

from ..config import Config
from ..core.detector import FLAG_ALONG_LINE, Detector
from ..errors import SeahoughError
from ..geometry import format_angle
from ..io.frames import printable
from ._common import (_Output, _dumps, _out_dir, _problem, _progress, _range_callback, _table,
                      parse_pattern)

# the command's defaults are the library's, so that both give the same results
_DET = {k: v.default for k, v in inspect.signature(Detector.__init__).parameters.items()}
_CFG = Config()


def _detection_lines(dets) -> list[str]:
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


@click.command(no_args_is_help=True)
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
    out_dir = _out_dir(out) if out is not None else None
    bar = _progress(images, len(images), "detect", len(images) > 1 and not quiet)
    say = _Output(bar)
    n_bad = n_missing = 0
    stems: dict[str, int] = {}
    for name in (bar if bar is not None else images):
        t0 = time.perf_counter()
        try:
            img = read_image(name, max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb)
            res = detector.search(img)
        except SeahoughError as e:
            say.error(f"{printable(name)}: {printable(_problem(e, name))}")
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
            # (a name's control characters escaped: a newline must not split the table)
            if dets:
                say(f"{printable(name)}  {w}x{h}  {len(dets)} found  ({ms:.0f} ms)")
                for line in _detection_lines(dets):
                    say(line)
            else:
                say(f"{printable(name)}  {w}x{h}  not found{why}  ({ms:.0f} ms)")
            if written and not quiet:
                say("  wrote " + ", ".join(printable(v) for v in written.values()))
    if bar is not None:
        bar.close()
    if n_bad:
        return 2
    return 1 if n_missing else 0
