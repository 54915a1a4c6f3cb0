"""``seahough detect``: find a pattern in images."""

from __future__ import annotations

import inspect
import logging
import os
import time
from collections import deque
from contextlib import closing
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import NamedTuple

import click

from ..config import Config
from ..core.detector import FLAG_GREY, Detector
from ..core.candidates import best_declined
from ..errors import SeahoughError
from ..io.frames import (IMAGE_EXTENSIONS, VIDEO_EXTENSIONS, FrameReader, list_frames, printable,
                         split_video_ref)
from ._common import (CurveSearch, _Output, _dumps, _max_nfa_callback, _out_dir, _problem,
                      _progress, _range_callback, bit_depth_option, default_workers,
                      ignore_boxes, make_detector, workers_option)
from ._records import (CSV_COLUMNS, _best_declined_dict, _best_declined_line, _captions,
                       _csv_line, _csv_rows, _detection_lines, _frame, _ignored, error_row,
                       bits_warning, patterns_not_found, picture_title)

# the command's defaults are the library's, so that both give the same results
_DET = {k: v.default for k, v in inspect.signature(Detector.__init__).parameters.items()}
_CFG = Config()


def _expand_inputs(images) -> tuple[list[str], dict]:
    """IMAGE arguments with each folder replaced by its images, in name
    order (not its subfolders), and each video by its frames
    (``"dive.mp4#<k>"``; :func:`~seahough.io.frames.list_frames`); and the
    SeahoughError of each folder or video that could not be listed, by name
    (it stays in the list: one problem line, the run goes on)."""
    out, bad = [], {}
    for name in images:
        suffix = Path(name).suffix.lower()
        if (suffix in VIDEO_EXTENSIONS and os.path.isfile(name)) or (
                suffix not in IMAGE_EXTENSIONS and os.path.isdir(name)):
            try:
                out.extend(str(f) for f in list_frames(name))
                continue
            except SeahoughError as e:
                bad[name] = e
        out.append(name)
    return out, bad


def _picture_stem(name: str, out_dir, stems: dict) -> str | None:
    """The pictures' file stem of image ``name`` (``<stem>_2`` for the second
    image of that stem, and so on, counted in ``stems``); None without
    ``--out``."""
    if out_dir is None:
        return None
    ref = split_video_ref(name)
    stem = f"{Path(ref[0]).stem}_{ref[1]:05d}" if ref else Path(name).stem
    k = stems.get(stem, 0)
    stems[stem] = k + 1
    return f"{stem}_{k + 1}" if k else stem


def _max_width_callback(ctx, param, value):
    """A click callback checking ``--max-width``: a whole number of px >= 0,
    or ``native`` (0: the photo's own width); None when not given.

    >>> _max_width_callback(None, None, "1920"), _max_width_callback(None, None, "native")
    (1920, 0)
    >>> _max_width_callback(None, None, "-5")
    Traceback (most recent call last):
    click.exceptions.BadParameter: '-5': expected a whole number of px >= 0, or native
    """
    if value is None:
        return None
    text = value.strip().lower()
    if text == "native":
        return 0
    try:
        n = int(text)
    except ValueError:
        n = -1
    if n < 0:
        raise click.BadParameter(f"{value!r}: expected a whole number of px >= 0, or native")
    return n


def _search_one(name: str, stem: str | None, detector: Detector, pat, out_dir,
                draw=None, image=None):
    """Read and search one image, and write its pictures (``stem`` given):
    ``(result, (h, w), ms, written, failed)``, or the SeahoughError that
    stopped reading or searching it. ``failed``: the WriteError of a picture
    that could not be written (the result stands; the pictures after it are
    not drawn). ``image``: the image already read (a video's frame, decoded in
    order by :func:`_run_jobs`), or the SeahoughError of reading it. Runs in a
    worker thread: the kernels release the GIL, and the pictures are drawn on
    their own Agg figures."""
    from ..io.images import read_image, say_bits

    cfg = detector.config
    t0 = time.perf_counter()
    if isinstance(image, SeahoughError):
        return image
    try:
        img = image if image is not None else read_image(
            name, max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb)
        bits = ""
        if img.dtype.name == "uint16" and cfg.bit_depth is None:   # (said with its file's name)
            top = int(img.max(initial=0))
            say_bits(top, name)
            bits = bits_warning(top)       # (and in its record)
        res = detector.search(img, name=name)   # (its warnings name the file)
        res.warning = bits
    except SeahoughError as e:
        return e
    ms = 1000.0 * (time.perf_counter() - t0)
    written: dict = {}
    failed = None
    if stem is not None:
        try:
            _pictures(name, img, res, detector, pat, out_dir / stem, draw or Drawing(),
                      written)
        except SeahoughError as e:
            failed = e
    return res, img.shape[:2], ms, written, failed


def _paint_notes(detector, colour, polarity=None) -> list:
    """A note for each colour image pattern with some paint, too little to
    be searched by its colour edges by default (a colour trial: an orange
    cross on a grey canvas, 14 % of it, was searched in grey and its
    answers sat on a yellow L, with nothing said). ``colour``: the user's
    --colour/--grey (None: not given, the pattern decides)."""
    from ..core.pattern_io import PAINTED_SHARE, paint_share

    out = []
    for name, d in (detector.parts.items() if detector.parts else [("", detector)]):
        p = getattr(d, "pattern", None)
        if (p is not None and p.painted and colour is None and polarity not in (None, "either")
                and p.has_long_borders(d.config)):     # (a photo's crop: its own polarity)
            out.append(f"note: {name or 'the pattern'}: painted, searched by its colour edges "
                       f"at either polarity (--polarity {polarity} applies with --grey, or "
                       "with --colour)")
        if p is None or colour is not None or p.painted:
            continue
        share = paint_share(p._colour, p.mask)
        if share >= 0.25 * PAINTED_SHARE:
            out.append(f"note: {name or 'the pattern'}: searched by its grey edges: "
                       f"{int(100 * share)}% "
                       f"of it is coloured, under the {PAINTED_SHARE:.0%} of a painted marker "
                       "(--colour --polarity either: by its colour edges; a tighter crop or "
                       "--mask: the marker alone)")
    return out


#: The pictures ``detect --out`` can draw for an image.
PICTURES = ("overlay", "accumulator", "edges")


class Drawing(NamedTuple):
    """How ``detect --out`` draws: ``--max-width`` and ``--pictures``."""

    max_width: int | None = None
    kinds: tuple = PICTURES


def _pictures_callback(ctx, param, value):
    """``--pictures``: a comma list of :data:`PICTURES` (all when not given).

    >>> _pictures_callback(None, None, "overlay, edges")
    ('overlay', 'edges')
    """
    if value is None:
        return PICTURES
    kinds = tuple(k.strip().lower() for k in value.split(",") if k.strip())
    bad = [k for k in kinds if k not in PICTURES]
    if bad or not kinds:
        raise click.BadParameter(f"{value!r}: expected a comma list of "
                                 + ", ".join(PICTURES))
    return tuple(dict.fromkeys(kinds))


def _pictures(name: str, img, res, detector: Detector, pat, base: Path, draw: Drawing,
              written: dict) -> None:
    """Draw one image's pictures (``draw.kinds``) at ``base``_overlay.png,
    _accumulator.png and _edges.png (curves: the overlay only), adding each
    file written to ``written``."""
    from .. import viz as plot

    max_width, kinds = draw

    dets = res.detections
    head, near = picture_title(name, res, isinstance(detector, CurveSearch))
    names = list(getattr(detector, "parts", None) or {}) or None
    ov = Path(f"{base}_overlay.png")
    if isinstance(detector, CurveSearch):    # curves: the overlay only
        if "overlay" in kinds:
            plot.plot_curves(img, dets, ov, title=head, max_width=max_width,
                             bit_depth=detector.config.bit_depth, best=near)
            written["overlay"] = str(ov)
        return
    if "overlay" in kinds:
        plot.plot_detections(img, dets, ov, pattern=pat, title=head, max_width=max_width,
                             bit_depth=detector.config.bit_depth, blanks=res.blanks,
                             patterns=names)
        written["overlay"] = str(ov)
    acc_title = f"{Path(name).name}: accumulator"
    # (a colour search's edges come from the channels, its working image is grey:
    # a colour trial read the left panel as what was searched)
    searcher = detector.parts[dets[0].pattern if dets else next(iter(detector.parts))] \
        if detector.parts else detector
    in_colour = (img.ndim == 3 and bool(searcher.config.colour)
                 and not any(FLAG_GREY in d.flags for d in dets))
    from ..viz._figure import stack_figures

    if "accumulator" in kinds:
        ac = Path(f"{base}_accumulator.png")
        if detector.parts and res.parts:
            # each pattern's planes, one under the other (its detections numbered in
            # the whole list)
            stack_figures([plot.plot_accumulator(r.planes, dets, None, note=r.note,
                                                 title=f"{acc_title} of pattern {n}",
                                                 patterns=names, best=best_declined(r))
                           for n, r in res.parts.items()], ac)
        else:
            plot.plot_accumulator(res.planes, dets, ac, title=acc_title, note=res.note,
                                  best=near)
        written["accumulator"] = str(ac)
    if "edges" in kinds:
        ed = Path(f"{base}_edges.png")
        how = " (edges from the colour channels; left, its grey levels)" if in_colour else ""
        head = f"{Path(name).name}: what the detector sees{how}"
        seen = {}   # (several patterns: each working scale's features, one under the other,
        for n, r in (res.parts or {}).items():    # naming its patterns: a trial debugged a
            if r.features is not None:            # post's search on the buoy's)
                seen.setdefault(id(r.features), (r.features, []))[1].append(n)
        figs = [plot.plot_edges(img, f, None, title=f"{head}; pattern{'s' * (len(ns) > 1)} "
                                f"{', '.join(ns)}") for f, ns in seen.values()]
        stack_figures(figs, ed) if figs else plot.plot_edges(img, res.features, ed, title=head)
        written["edges"] = str(ed)


def _run_jobs(jobs, detector: Detector, pat, out_dir, workers: int, draw=None, bad=None):
    """``(name, outcome of _search_one)`` for each ``(name, stem)`` of
    ``jobs``, in their order: one at a time with one worker, else ``workers``
    threads with at most twice as many images in flight (read, searched or
    done but not yet printed), so that memory stays bounded. ``bad``: the
    error of each input that could not be listed, reported as its outcome."""
    cfg = detector.config
    bad = bad or {}
    videos = FrameReader([], cfg.max_pixels, cfg.max_memory_mb)

    def decoded(name):
        # a video's frame decoded here, in the order of the frames (the reader
        # goes on from the last one); a file is read by its worker
        if name in bad:
            return bad[name]
        if split_video_ref(name) is None:
            return None
        videos.items = [name]
        try:
            return videos.raw(0)
        except SeahoughError as e:
            return e

    try:
        if workers <= 1:
            for name, stem in jobs:
                yield name, _search_one(name, stem, detector, pat, out_dir, draw, decoded(name))
            return
        pool = ThreadPoolExecutor(workers, thread_name_prefix="seahough-detect")
        pending: deque = deque()
        todo = iter(jobs)
        try:
            for name, stem in todo:
                pending.append((name, pool.submit(_search_one, name, stem, detector, pat,
                                                  out_dir, draw, decoded(name))))
                if len(pending) >= 2 * workers:
                    break
            while pending:
                name, fut = pending.popleft()
                done = fut.result()
                nxt = next(todo, None)
                if nxt is not None:
                    pending.append((nxt[0], pool.submit(_search_one, *nxt, detector, pat,
                                                        out_dir, draw, decoded(nxt[0]))))
                yield name, done
        finally:
            # (an error, Ctrl-C or a closed pipe: what has not started is dropped)
            pool.shutdown(wait=True, cancel_futures=True)
    finally:
        videos.close()


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
              help="At most this many detections per image. A detection's confidence is "
              "measured against the best candidate left out: with more objects in view than "
              "this, the ones reported are measured against the others and may come out "
              "ambiguous (ask for as many as there may be; to count many objects, e.g. 60 "
              "tags, ask for a few more than there may be: over 5, each result gets its own "
              "240 key points, unless --keypoints is given).")
@click.option("--min-score", type=click.FloatRange(0.0, 1.0), default=_DET["min_score"],
              show_default=True,
              help="Least share of the pattern's edges that must be found.")
@click.option("--min-confidence", type=click.FloatRange(0.0, 1.0),
              default=_DET["min_confidence"], show_default=True,
              help="Least distinctness of the accumulator peak.")
@click.option("--max-nfa", type=float, default=_DET["max_nfa"], show_default=True,
              metavar="FLOAT", callback=_max_nfa_callback,
              help="Most false alarms: a detection's NFA (how many this good chance would "
              "give per image) must be at most this; > 0, smaller is stricter, inf: no limit.")
@click.option("--downscale", type=click.FloatRange(0.0, 1.0, min_open=True), default=None,
              help="Work on the image scaled by this factor (default: automatic).")
@click.option("--keypoints", type=click.IntRange(min=1), default=None,
              help=f"Number of most contrasted edge points kept (default {_CFG.n_keypoints}; "
              "without it, a pattern cut from a photo that is a small share of the image, a "
              "seabed patch, gets as many more as put enough on its area, and a search for "
              "more than 5 results 240 for each: slower).")
@click.option("--equalize", is_flag=True, help="Local contrast equalisation (haze, uneven light).")
@click.option("--smooth", type=click.FloatRange(0.0, 100.0), default=None, metavar="SIGMA",
              help="Blur each image by this Gaussian sigma (px) before its edges are found: "
              "speckle of sonar images, grain, marine snow (an image pattern gets it too). "
              "Default: none.")
@click.option("--ignore", "ignore", multiple=True, metavar="X0,Y0,X1,Y1", callback=ignore_boxes,
              help="A region not to search, image pixels (end exclusive; repeatable): the "
              "vehicle's own parts in view, a fixed overlay, a picture-in-picture inset. It is "
              "filled from the picture around it (an object under it is not found).")
@bit_depth_option
@click.option("--colour/--grey", "colour", default=None,
              help="Edges from every colour channel of a colour image (an object that differs "
                   "from its ground by hue more than by brightness), or from its grey levels "
                   "(default: colour when the pattern image is painted in colour, an orange or "
                   "a green marker; grey otherwise). In colour a pattern is searched at either "
                   "polarity: with --colour, unless --polarity says otherwise; a painted "
                   "pattern searched in colour by default always (its --polarity applies with "
                   "--grey or --colour).")
@click.option("--polarity", type=click.Choice(["same", "inverted", "either", "bright", "dark"]),
              default=None, help="Contrast of the object: as in the pattern image (same; for "
              "shapes: bright on dark; bright is the same), inverted (dark on bright; dark is "
              "the same), or either.")
@click.option("--mask", type=click.Path(dir_okay=False), default=None,
              help="Image pattern only: mask of the object's pixels (non-zero).")
@click.option("--json", "as_json", is_flag=True,
              help="One JSON object per image and line (JSON Lines) instead of tables.")
@click.option("--csv", "as_csv", is_flag=True,
              help="CSV instead of tables: a header, then a row per detection (an image with "
              "none: one row, found false, and in its column declined why the best "
              "candidate was not reported, and the option that would let it through; several "
              "patterns: such a row for each that found nothing, naming it in pattern); "
              "lists (flags, matrix, points, box) as JSON text; a "
              "video's frames: its number in frame (JSON too).")
@click.option("--out", "-o", type=click.Path(file_okay=False), default=None,
              help="Write pictures per image here: <stem>_overlay.png (detections), "
              "<stem>_accumulator.png (the vote planes; each pattern's when several) and "
              "<stem>_edges.png (gradients, key points and segments).")
@click.option("--max-width", type=str, default=None, metavar="PX|native",
              callback=_max_width_callback,
              help="With --out: draw each photo at most PX px wide on its overlay (a wider "
              "one is shrunk to it); 0 or native: at its own width, pixel for pixel "
              "(default: 900 px on its longer side).")
@click.option("--pictures", "pictures", type=str, default=None, metavar="KINDS",
              callback=_pictures_callback,
              help="With --out: which pictures, a comma list of overlay, accumulator, edges "
              "(default: all three; the overlay alone takes less than half their time; "
              "curve:WIDTH draws the overlay only).")
@click.option("--quiet", "-q", is_flag=True, help="No progress bar or notes; results only (warnings about an input, e.g. "
              "its bit depth, are still said).")
@workers_option("Images searched at once, in threads; results are printed in the order given")
def detect(pattern, images, scale_range, angle_range, max_results, min_score, min_confidence,
           max_nfa, downscale, keypoints, equalize, smooth, ignore, bit_depth, colour, polarity,
           mask, as_json,
           as_csv, out, max_width, pictures, quiet, workers):
    """Find PATTERN in each IMAGE.

    \b
    PATTERN is an image file of the object (its centre is the origin), a
    pattern file written by Pattern.save (.npz), or a shape (pixels):
      rect:W,H           a filled rectangle (the paper's marker)
      line:LENGTH,WIDTH  a rope, cable or pipe: reports its angle and offset
      circle:R           a disc;  circle:R,INNER (or ring:R,INNER)  a ring
      polygon:x1,y1,x2,y2,x3,y3,...
      polyline:WIDTH:x1,y1,x2,y2,...  open strips WIDTH wide along the
                         points, e.g. a gate: polyline:6:0,100,0,0,210,0,210,100
      curve:WIDTH        a rope or cable that bends, WIDTH px wide: each
                         found as the polyline of its centre line (searched
                         alone: not one of several patterns);
                         curve:WIDTH,PIECE_LENGTH,MIN_LENGTH: the straight
                         piece followed along it (default 4 x WIDTH, at
                         least 48) and the shortest curve reported (px;
                         default two pieces)
    Several patterns at once: NAME=SPEC+NAME=SPEC... (e.g.
    "buoy=circle:16+post=line:120,12"); each detection names its pattern,
    the strongest evidence (lowest nfa) first; -n is per pattern. A
    pattern's own settings follow its SPEC after @ (the options' values
    for the others): scale=LO:HI, angle=LO:HI, polarity=bright|dark|either,
    n=N, min-score=S, min-confidence=C, max-nfa=E, e.g.
    "gate=polyline:6:0,100,0,0,210,0,210,100@angle=-15:15,polarity=either
    +buoy=circle:16@scale=0.3:3".

    \b
    Positions are pattern-origin pixels (x right, y down); angles degrees
    counter-clockwise as displayed, in [0, 360) (lines: [0, 180)). When the
    search could not run, the line says why, e.g. "not found (no edges)" or
    "not found (pattern larger than the image)"; the JSON "note" field holds
    the same ("" when the search ran). When nothing is reported, the best
    candidate that was not is printed below, with why (e.g. "score 0.34
    under min_score 0.5", "NFA 3.2 over max_nfa 1"): the setting it would
    take (JSON "best_declined"; -q leaves it out of the table). When
    --max-results cut the list (candidates over --min-score left out: more
    objects may be there), a line under the table says how many (JSON
    "left_out"). "nfa" is
    a detection's number of false alarms: how many detections this good
    chance alone would give in an image without the object (1e-5: one in
    100,000 such images); only those of at most --max-nfa are reported. A
    video's burned-in caption (a timestamp on a flat box at an edge) is not
    searched: JSON "captions" lists each box [x0, y0, x1, y1], the overlay
    draws it dashed. With several patterns, those that found nothing in an
    image are named under its table ("not found: NAME", with their best
    candidate; JSON "not_found"); the image counts as found when one did.
    An image that cannot be read or searched: one line on stderr, and its
    own record, {"file": ..., "found": null, "error": WHY} (CSV: a row whose
    "error" column says why). A progress bar is shown on stderr for several images
    when stderr is a terminal.

    \b
    Images are searched --workers at a time (default: all cores), each
    with the same results as alone; the results are printed in the order
    of the IMAGE arguments.

    \b
    Exit status: 0 the pattern was found in every image (several patterns:
    at least one of them in every image; each detection names its pattern);
    1 nothing was found in some image; 2 bad input or a picture that could
    not be written (the good images' results are still printed, each
    problem gets one line on stderr).

    \b
    An IMAGE that is a folder stands for its images, in name order (by
    the time in their names when each has one; not its subfolders), and a
    video for its frames, each named VIDEO#N (N from 0) in the results and
    VIDEO-STEM_0000N in the pictures.

    \b
    Example:
      seahough detect marker.png dive/*.jpg --scale-range 0.5 2 --json
    """
    detector = make_detector(pattern, scale_range, angle_range, max_results, min_score,
                             min_confidence, downscale, keypoints, equalize, polarity, mask,
                             max_nfa=max_nfa, colour=colour, bit_depth=bit_depth, smooth=smooth,
                             ignore=ignore)
    if max_width is not None and out is None:
        raise click.UsageError("--max-width sizes the pictures of --out: give --out DIR")
    if pictures != PICTURES and out is None:
        raise click.UsageError("--pictures chooses the pictures of --out: give --out DIR")
    if max_width is not None and "overlay" not in pictures:
        raise click.UsageError("--max-width sizes the overlay, and --pictures leaves it out")
    if as_json and as_csv:
        raise click.UsageError("--json and --csv: give one of them")
    if isinstance(detector, CurveSearch) and out is not None and "overlay" not in pictures:
        raise click.UsageError("--pictures: curves have the overlay only")
    pat = None if detector.parts else detector.pattern   # (the inset: one pattern only)
    if not quiet:
        for line in _paint_notes(detector, colour, polarity):
            click.echo(line, err=True)
    notes = logging.getLogger("seahough.io")
    level = notes.level
    if quiet:   # ("note: FOLDER: not read: ...": a note; -q prints results only)
        notes.setLevel(logging.ERROR)
    try:
        images, unlisted = _expand_inputs(images)
    finally:
        notes.setLevel(level)
    out_dir = _out_dir(out) if out is not None else None
    workers = min(workers or default_workers(), len(images))
    bar = _progress(None, len(images), "detect", len(images) > 1 and not quiet)
    say = _Output(bar)
    stems: dict[str, int] = {}
    jobs = [(name, _picture_stem(name, out_dir, stems)) for name in images]
    with closing(_run_jobs(jobs, detector, pat, out_dir, workers,
                           Drawing(max_width, pictures), unlisted)) as outcomes:
        n_bad, n_missing = _report(outcomes, bar, say, "json" if as_json else
                                   "csv" if as_csv else "table", quiet)
    if bar is not None:
        bar.close()
    if n_bad:
        return 2
    return 1 if n_missing else 0


def _report(outcomes, bar, say, form: str, quiet: bool) -> tuple[int, int]:
    """Print each image's outcome as it comes, in the order of the images
    (``form``: "table", "json" or "csv"); returns how many files were bad
    and how many images had no detection."""
    n_bad = n_missing = 0
    if form == "csv":
        say(_csv_line(CSV_COLUMNS))
    for name, done in outcomes:
        if bar is not None:
            bar.update(1)
        if isinstance(done, SeahoughError):
            problem = _problem(done, name)
            say.error(f"{printable(name)}: {printable(problem)}")
            # (and in the records: a JSON Lines or CSV reader keeps track of every image)
            if form == "json":
                # ("detections": [] too: pandas.json_normalize(recs, "detections") took
                # every record to have it, a user trial)
                rec = {"file": name, "found": None, "error": problem, "detections": []}
                if split_video_ref(name) is not None:
                    rec["frame"] = _frame(name)
                say(_dumps(rec))
            elif form == "csv":
                say(error_row(name, problem))
            n_bad += 1
            continue
        res, (h, w), ms, written, failed = done
        dets = res.detections
        # why the search could not run (SearchResult.note), e.g. " (no edges)"
        why = f" ({res.note})" if res.note else ""
        if not dets:
            n_missing += 1
        if form == "csv":
            parts = getattr(res, "parts", None)   # (several: each one not found)
            nears = ([(p, best_declined(res.parts[p])) for p in patterns_not_found(res)]
                     if parts else [] if dets else [("", best_declined(res))])
            for line in _csv_rows(name, w, h, res.note, ms, dets, nears,
                                  getattr(res, "warning", "")):
                say(line)
            if failed is not None:
                say.error(printable(str(failed)))
                n_bad += 1
            continue
        if form == "json":
            rec = {"file": name, "width": int(w), "height": int(h), "found": bool(dets),
                   "note": res.note, "detections": [d.to_dict() for d in dets],
                   "best_declined": None if dets else _best_declined_dict(best_declined(res)),
                   "captions": _captions(res), "ignored": _ignored(res),
                   "left_out": getattr(res, "left_out", 0), "time_ms": round(ms, 3)}
            if getattr(res, "warning", ""):       # (about the image's values: 12-bit data...)
                rec["warning"] = res.warning
            if getattr(res, "parts", None):       # (a curve search's result has none)
                rec["not_found"] = patterns_not_found(res)
                # (each of those: its best candidate and why not; best_declined: the best)
                rec["best_declined_by_pattern"] = {
                    pname: _best_declined_dict(best_declined(res.parts[pname]))
                    for pname in rec["not_found"]}
            if split_video_ref(name) is not None:
                rec["frame"] = _frame(name)
            rec.update(written)
            if failed is not None:
                rec["picture_error"] = str(failed)
            say(_dumps(rec))
        else:
            # (a name's control characters escaped: a newline must not split the table)
            if dets:
                say(f"{printable(name)}  {w}x{h}  {len(dets)} found  ({ms:.0f} ms)")
                for line in _detection_lines(dets):
                    say(line)
                more = getattr(res, "left_out", 0)     # (a curve search's result has none)
                if more and not quiet:
                    say(f"  {more} more candidate{'s' if more > 1 else ''} over --min-score "
                        "left out by --max-results (-n): more objects may be there")
                missing = patterns_not_found(res)
                if missing:     # (several patterns: those that found nothing, and why)
                    say(printable("  not found: " + ", ".join(missing)))
                    for pname in missing if not quiet else ():
                        near = best_declined(res.parts[pname])
                        if near is not None:
                            say(printable(_best_declined_line(near)))
            else:
                say(f"{printable(name)}  {w}x{h}  not found{why}  ({ms:.0f} ms)")
                # (several patterns: each one's best candidate, as when one is found)
                parts = getattr(res, "parts", None) or {"": res}
                for near in (best_declined(part) for part in parts.values()):
                    if near is not None and not quiet:
                        say(printable(_best_declined_line(near)))
            if written and not quiet:
                say("  wrote " + ", ".join(printable(v) for v in written.values()))
        if failed is not None:
            # (the image's results are printed above; its pictures stop here, the run goes on)
            say.error(printable(str(failed)))
            n_bad += 1
    return n_bad, n_missing
