"""What ``seahough detect`` prints for an image: its table lines, the best
candidate it did not report, and its CSV rows."""

from __future__ import annotations

import csv
import io
import json
import math
import re
from pathlib import Path

from ..core.detector import FLAG_ALONG_LINE
from ..geometry import format_angle, format_line
from ..io.frames import split_video_ref
from ._common import _table


def _nfa_text(nfa) -> str:
    """A number of false alarms as the table prints it (``-``: not known).

    >>> _nfa_text(3.2e-05), _nfa_text(0.5), _nfa_text(float("nan"))
    ('3.2e-05', '5.0e-01', '-')
    """
    return f"{nfa:.1e}" if math.isfinite(nfa) else "-"


def _xy(p) -> str:
    """A point as the table writes it (no "-0.0" for -5.6e-17).

    >>> _xy((-5.6e-17, 240.94))
    '0.0,240.9'
    """
    return ",".join(f"{round(float(v), 1) + 0.0:.1f}" for v in p[:2])


def _curve_lines(curves) -> list[str]:
    header = ("#", "length", "width", "from", "to", "points", "score", "conf", "nfa", "flags")
    rows = [(i + 1, f"{c.length:.1f}", f"{c.width:.2f}", _xy(c.points[0]), _xy(c.points[-1]),
             len(c.points), f"{c.score:.2f}",
             f"{c.confidence:.2f}", _nfa_text(c.nfa), ",".join(c.flags))
            for i, c in enumerate(curves)]
    return _table(rows, header)


def _line_cells(d) -> tuple[str, str]:
    """A line detection's direction and offset as the table shows them
    (:func:`~seahough.geometry.format_line`: the offset's sign follows the
    direction written)."""
    angle, offset = format_line(d.line_angle, d.line_offset, 2)
    return angle, f"{offset:.2f}"


def _detection_lines(dets) -> list[str]:
    if dets and getattr(dets[0], "kind", None) == "curve":
        return _curve_lines(dets)
    if any(getattr(d, "pattern", "") for d in dets):   # several patterns: one table
        # (a line's offset too, when there is one: a pipe's was left out, a user trial)
        lines = any(d.kind == "line" for d in dets)
        header = ("#", "pattern", "x", "y", "scale", "angle", *(("offset",) * lines), "score",
                  "conf", "nfa", "flags")
        rows = [(i + 1, d.pattern, f"{d.x:.2f}", f"{d.y:.2f}", f"{d.scale:.3f}",
                 *(_line_cells(d) if d.kind == "line" else
                   (format_angle(d.angle, 2), "-")[: 1 + lines]),
                 f"{d.score:.2f}", f"{d.confidence:.2f}", _nfa_text(d.nfa),
                 ",".join(f for f in d.flags if f != FLAG_ALONG_LINE))
                for i, d in enumerate(dets)]
        return _table(rows, header)
    if dets and dets[0].kind == "line":
        header = ("#", "line_angle", "offset", "x", "y", "width_scale", "score", "conf", "nfa",
                  "flags")
        rows = [(i + 1, *_line_cells(d),
                 f"{d.x:.2f}", f"{d.y:.2f}", f"{d.scale:.3f}", f"{d.score:.2f}",
                 f"{d.confidence:.2f}", _nfa_text(d.nfa),
                 ",".join(f for f in d.flags if f != FLAG_ALONG_LINE))
                for i, d in enumerate(dets)]
    else:
        header = ("#", "x", "y", "scale", "angle", "score", "conf", "nfa", "flags")
        rows = [(i + 1, f"{d.x:.2f}", f"{d.y:.2f}", f"{d.scale:.3f}", format_angle(d.angle, 2),
                 f"{d.score:.2f}", f"{d.confidence:.2f}", _nfa_text(d.nfa), ",".join(d.flags))
                for i, d in enumerate(dets)]
    return _table(rows, header)


def patterns_not_found(res) -> list:
    """Several patterns searched: the names of those with no detection in
    the image ([] for one pattern: its "not found" is the image's)."""
    return [name for name, part in (getattr(res, "parts", None) or {}).items()
            if not part.detections]


def _ignored(res) -> list:
    """The regions of ``--ignore`` left out of a search (clipped to the
    image), as JSON: each ``[x0, y0, x1, y1]``; [] for none."""
    b = getattr(res, "blanks", None)
    return [list(box) for box in b.ignored] if b is not None else []


def _captions(res) -> list:
    """The burned-in captions filled before a search, as JSON: each
    ``[x0, y0, x1, y1]`` (end exclusive, image pixels); [] for none."""
    b = getattr(res, "blanks", None)
    return [[c.x0, c.y0, c.x1, c.y1] for c in b.captions] if b is not None else []


def _best_declined_dict(c) -> dict | None:
    if c is None:
        return None
    q = c.pose
    return {"pattern": c.pattern, "x": float(q.tx), "y": float(q.ty), "scale": float(q.scale),
            "angle": float(q.angle), "score": float(c.score),
            "nfa": float(c.nfa) if math.isfinite(c.nfa) else None, "declined": c.declined}


#: the option that sets what a declined candidate fell short of, by the
#: words of its reason (a user trial: the reason never named the option)
_OPTION_OF = (("min_score", "--min-score"), ("max_nfa", "--max-nfa"),
              ("max_results", "--max-results"), ("min_confidence", "--min-confidence"),
              ("min_length", "curve:WIDTH,PIECE_LENGTH,MIN_LENGTH"),
              ("the searched range", "--scale-range"))
#: ... and its form for one pattern of several (``NAME=SPEC@key=value``)
_OWN_OPTION = {"--min-score": "min-score", "--max-nfa": "max-nfa", "--max-results": "n",
               "--min-confidence": "min-confidence", "--scale-range": "scale"}


def _option_hint(c) -> str:
    """The option that would let ``c`` through, named after its reason; not
    for a score far under its bound (under half of it: nothing like the
    pattern may be there, and a lower --min-score then --max-nfa reported
    wrong poses, a user trial), which says so instead.

    >>> from types import SimpleNamespace as C
    >>> _option_hint(C(score=0.45, declined="score 0.45 under min_score 0.5"))
    ' (option --min-score)'
    >>> _option_hint(C(score=0.2, declined="score 0.2 (coarse) under 0.425 (0.85 x min_score)"))
    ' (far under it: the pattern may not be in view)'
    >>> _option_hint(C(score=0.6, declined="NFA 3 over max_nfa 1", pattern="buoy"))
    ' (option --max-nfa; for buoy alone: its @max-nfa=...)'
    >>> _option_hint(C(score=0.44, declined="score 0.44 under min_score 0.5; NFA 154 over "
    ...                "max_nfa 1 too"))
    ' (options --min-score and --max-nfa)'
    """
    options = [o for words, o in _OPTION_OF if words in c.declined]   # (both: "...; NFA ...")
    option = options[0] if options else None
    bound = re.search(r"under (\d+(?:\.\d+)?(?:e[-+]?\d+)?)", c.declined)
    if option == "--min-score" and bound and c.score < 0.5 * float(bound.group(1)):
        return " (far under it: the pattern may not be in view)"
    name = getattr(c, "pattern", "")
    said = " and ".join(options)
    if option in _OWN_OPTION and name:    # (one of several: the option sets them all)
        own = " and ".join(f"@{_OWN_OPTION[o]}=..." for o in options if o in _OWN_OPTION)
        return f" (option{'s' * (len(options) > 1)} {said}; for {name} alone: its {own})"
    return f" (option{'s' * (len(options) > 1)} {said})" if option else ""


def _best_declined_line(c) -> str:
    q = c.pose
    name = f"{c.pattern}: " if c.pattern else ""
    nfa = f", nfa {_nfa_text(c.nfa)}" if math.isfinite(c.nfa) else ""
    hint = _option_hint(c)
    return (f"  best candidate, not reported: {name}x {q.tx:.1f}, y {q.ty:.1f}, scale "
            f"{q.scale:.3f}, angle {format_angle(q.angle, 1)}, score {c.score:.2f}{nfa}: "
            f"{c.declined}{hint}")


#: The columns of ``detect --csv``: the image's, then a detection's (a
#: shape's, a line's or a curve's: those that do not apply are empty);
#: ``error`` is filled only in the one row of an image that could not be
#: read or searched (every other field but ``file`` and ``frame`` empty);
#: ``segment``, a line's visible extent ``[[x1, y1], [x2, y2]]``, and
#: ``stretches``, the stretches of it seen (the JSON's), came last so that the
#: columns before them kept their places.
CSV_COLUMNS = ("file", "width", "height", "found", "note", "time_ms", "rank", "pattern", "kind",
               "x", "y", "scale", "angle", "score", "confidence", "nfa", "flags", "line_angle",
               "line_offset", "width_px", "length", "votes", "matrix", "points", "declined",
               "frame", "error", "warning", "box", "segment", "stretches")


def error_row(name: str, problem: str) -> str:
    """The CSV line of an image that could not be read or searched.

    >>> error_row("a.png", "truncated PNG").split(",")[-7:]
    ['', '', 'truncated PNG', '', '', '', '']
    """
    return _csv_row(file=name, frame=_frame(name), error=problem)


def _csv_row(**values) -> str:
    """A CSV line of :data:`CSV_COLUMNS` from its values by column ("" for
    the others; lists and dicts as JSON text)."""
    cell = lambda v: "" if v is None else (json.dumps(v, separators=(",", ":"))
                                           if isinstance(v, (list, tuple, dict)) else v)
    return _csv_line([cell(values.get(col)) for col in CSV_COLUMNS])


def bits_warning(top: int) -> str:
    """A record's words for a 16-bit image whose values reach only ``top``
    (:func:`seahough.io.images.say_bits` says it once a run, at length, on
    stderr; a spreadsheet of the table showed a 12-bit camera's photos as
    "not found"); "" for 16-bit data.

    >>> bits_warning(220)
    '16-bit values reach only 220: 8-bit data in a 16-bit file? (convert it to 8-bit)'
    >>> bits_warning(4095).endswith("12-bit samples? (--bit-depth)"), bits_warning(60000)
    (True, '')
    """
    if not 0 < top < 4096:
        return ""
    return f"16-bit values reach only {top}: " + (
        "8-bit data in a 16-bit file? (convert it to 8-bit)" if top < 256 else
        f"a camera's {max(top.bit_length(), 10)}-bit samples? (--bit-depth)")


def _frame(name: str):
    """A video frame's number (``"dive.mp4#12"``: 12), else ""."""
    ref = split_video_ref(name)
    return "" if ref is None else ref[1]


def _csv_line(values) -> str:
    """One CSV row without its line end (a field holding a line break quoted)."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\r\n").writerow(values)
    return buf.getvalue()[:-2]


def _csv_rows(name, w, h, note, ms, dets, nears=(), warning=""):
    """The CSV lines of one image (:data:`CSV_COLUMNS`): a row per detection,
    then a row (found false) per pattern that found nothing, with its best
    declined candidate's pattern and why it was not reported (and the option
    that would let it through) in ``declined``; ``nears``: ``(pattern name,
    that candidate or None)`` pairs. An image without detections has one
    such row at least. ``warning``: about the image's values (every row)."""
    head = dict(file=name, width=int(w), height=int(h), note=note, time_ms=round(ms, 3),
                frame=_frame(name), warning=warning)
    out = []
    for rank, d in enumerate(dets, 1):
        rec = {k: v for k, v in d.to_dict().items() if k not in ("outline", "declined")}
        rec["width_px"] = rec.pop("width", None)   # (a curve's or a line's, not the image's)
        out.append(_csv_row(**{**rec, **head}, found="true", rank=rank))
    for who, near in nears if dets else (list(nears) or [("", None)]):
        why = near.declined + _option_hint(near) if near is not None else ""
        out.append(_csv_row(**head, found="false", pattern=who, declined=why))
    return out


def picture_title(name: str, res, curves: bool = False) -> tuple:
    """``(title, near)``: an overlay's title for the search ``res`` of the
    image ``name`` (what was found, which patterns found nothing, and the
    best candidate not reported, with why), and that candidate (None when
    something was found). ``curves``: a curve search's."""
    from ..core.candidates import best_declined

    dets = res.detections
    n = len(dets)
    near = best_declined(res) if n == 0 and not res.note else None
    if curves:
        head = f"{Path(name).name}: " + (f"{n} curve{'s' if n > 1 else ''}" if n
                                         else "no curve found")
        if near is not None:
            head += f"; best line: score {near.score:.2f}, {near.declined}"
        return head, near
    why = f" ({res.note})" if res.note else ""
    head = f"{Path(name).name}: " + (f"not found{why}" if n == 0 else
                                     f"{n} detection{'s' if n > 1 else ''}")
    missing = patterns_not_found(res)
    if n and missing:    # (several patterns: say which found nothing, as the table does)
        head += f"; not found: {', '.join(missing)}"
    if near is not None:  # (what came closest, and why it was not reported)
        who = f"{near.pattern}, " if getattr(near, "pattern", "") else ""
        # (its score once: a reason of "score ..." says it, a user trial read it twice)
        score = "" if near.declined.startswith("score") else f"score {near.score:.2f}, "
        head += f"; best candidate: {who}{score}{near.declined}"
    return head, near
