"""What the commands share: the one-line error output, JSON, tables,
progress bars, range and number parsing, and pattern specs."""

from __future__ import annotations

import inspect
import json
import math
import re
import sys
from pathlib import Path

import click

from .._validate import _turn_hint, default_workers, number
from .._values import json_safe
from ..errors import ParameterError, SeahoughError, interrupted, without_name

PROG = "seahough"
SHAPES_HELP = ("rect:W,H | line:LENGTH,WIDTH | circle:R | circle:R,INNER (a ring) | "
               "ellipse:RX,RY | polygon:x1,y1,x2,y2,... | polyline:WIDTH:x1,y1,x2,y2,... | "
               "curve:WIDTH")
_SHAPE_POLARITY = {"same": "bright", "inverted": "dark", "bright": "bright", "dark": "dark",
                   "either": "either"}
_IMAGE_POLARITY = {"same": "same", "inverted": "inverted", "bright": "same", "dark": "inverted",
                   "either": "either"}


class _Fail(Exception):
    """A user error already worded for the one-line message."""


# --------------------------------------------------------------------------- output
def _json_default(o):
    import numpy as np   # (loaded by then: only results hold numpy values)

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
    """``obj`` as JSON, numpy values and paths included; a float that is not
    finite as null (JSON has no Infinity: readers refuse it).

    >>> import numpy as np
    >>> _dumps({"x": np.float32(0.5), "p": Path("a"), "max_nfa": float("inf")})
    '{"x": 0.5, "p": "a", "max_nfa": null}'
    """
    return json.dumps(json_safe(obj), default=_json_default, allow_nan=False, **kw)


def _err(msg: str) -> None:
    """One line on stderr: ``seahough: error: msg``."""
    msg = " ".join(str(msg).split())
    click.echo(f"{PROG}: error: {msg}", err=True)


#: The message of an exception without a leading copy of the file name.
_problem = without_name


_interrupted = interrupted   # (the name the CLI modules use)


class _Terminated(BaseException):
    """SIGTERM (``kill``, a batch system's time limit, ``docker stop``),
    raised where Ctrl-C would be: what Ctrl-C keeps is kept (the work's
    ``finally`` clauses run; a BaseException, not a KeyboardInterrupt, so
    that click does not take it for a Ctrl-C at a prompt)."""


def _say_kept(e: BaseException, said: str):
    """Raise the interruption ``e`` of a command again with what it kept
    (``said``): Ctrl-C as KeyboardInterrupt(said), SIGTERM as
    _Terminated(said) (also from inside a compiled kernel, a SystemError
    caused by either: a trial saw SIGTERM's message without the count that
    Ctrl-C gives); anything else as it is."""
    if isinstance(e, _Terminated) or (isinstance(e, SystemError) and _interrupted(e, _Terminated)):
        raise _Terminated(said) from None
    if isinstance(e, KeyboardInterrupt) or (isinstance(e, SystemError) and _interrupted(e)):
        raise KeyboardInterrupt(said) from None
    raise e


def _out_dir(out: str) -> Path:
    """The ``--out`` folder, created (a :class:`_Fail` when it cannot be)."""
    o = Path(out)
    try:
        o.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _Fail(f"--out {out}: cannot create the folder ({e.strerror or e})") from None
    return o


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
    """Aligned columns (numbers right-aligned, or all left with ``left``).

    >>> for line in _table([(1, "2.50", "a"), (10, "0.25", "")], ("#", "x", "flags")):
    ...     print(line)
       #     x  flags
       1  2.50  a
      10  0.25
    """
    cols = [header] + rows
    widths = [max(len(str(r[i])) for r in cols) for i in range(len(header))]
    out = []
    for r in cols:
        cells = [str(c) if i == len(header) - 1 else
                 (str(c).ljust(widths[i]) if left else str(c).rjust(widths[i]))
                 for i, c in enumerate(r)]
        out.append("  " + "  ".join(cells).rstrip())
    return out


# -------------------------------------------------------------------------- workers
def workers_option(what: str):
    """The ``--workers N`` option of a command (``what``: what runs at once);
    None (not given) means :func:`default_workers`, and N < 1 is refused
    with one line."""
    return click.option(
        "--workers", "-j", type=click.IntRange(min=1), default=None, metavar="N",
        help=f"{what} (default: all cores, {default_workers()} here; 1: one at a time).")


# -------------------------------------------------------------------------- parsing
def _range_callback(positive: bool):
    """A click callback checking a ``LOW HIGH`` option (finite, LOW <= HIGH,
    and > 0 when ``positive``)."""
    def check(ctx, param, value):
        if value is None:
            return value
        lo, hi = value
        flag = f"{lo:g} {hi:g}"
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise click.BadParameter(f"{flag}: values must be finite")
        if lo > hi:
            hint = _turn_hint("angle", lo, hi, "'{} {}'") if not positive else ""
            raise click.BadParameter(f"{flag}: LOW must not exceed HIGH{hint}")
        if positive and lo <= 0:
            raise click.BadParameter(f"{flag}: scales must be > 0")
        return float(lo), float(hi)
    return check


def _max_nfa_callback(ctx, param, value):
    """A click callback checking ``--max-nfa``: a number > 0, ``inf`` for no
    limit (:func:`seahough._validate.check_max_nfa`).

    >>> _max_nfa_callback(None, None, float("inf")), _max_nfa_callback(None, None, 1e-3)
    (inf, 0.001)
    >>> _max_nfa_callback(None, None, 0.0)
    Traceback (most recent call last):
    click.exceptions.BadParameter: 0: must be > 0 (inf: no limit)
    """
    from .._validate import check_max_nfa
    from ..errors import ParameterError

    if value is None:
        return value
    try:
        return check_max_nfa(value)
    except ParameterError:
        raise click.BadParameter(f"{value:g}: must be > 0 (inf: no limit)") from None


def _numbers(text: str, spec: str) -> list[float]:
    """The comma-separated numbers of a shape spec.

    >>> _numbers("60, 40", "rect:60, 40")
    [60.0, 40.0]
    """
    try:
        vals = [float(v) for v in text.replace(" ", "").split(",") if v != ""]
    except ValueError:
        raise click.BadParameter(f"{spec!r}: expected numbers separated by commas "
                                 f"({SHAPES_HELP})", param_hint="PATTERN") from None
    if not all(math.isfinite(v) for v in vals):
        raise click.BadParameter(f"{spec!r}: numbers must be finite", param_hint="PATTERN")
    return vals


_SHAPE_COUNTS = {"rect": 2, "rectangle": 2, "line": 2, "circle": (1, 2), "ring": 2,
                 "ellipse": 2, "polygon": None, "poly": None, "polyline": None}
_SHAPE_USAGE = {"rect": "rect:W,H (e.g. rect:60,40)", "rectangle": "rect:W,H (e.g. rect:60,40)",
                "line": "line:LENGTH,WIDTH (e.g. line:200,8)",
                "circle": "circle:R or circle:R,INNER (e.g. circle:30)",
                "ring": "ring:R,INNER (e.g. ring:30,20)",
                "ellipse": "ellipse:RX,RY (semi-axes, e.g. ellipse:30,50)",
                "polygon": "polygon:x1,y1,x2,y2,x3,y3,...",
                "poly": "polygon:x1,y1,x2,y2,x3,y3,...",
                "polyline": "polyline:WIDTH:x1,y1,x2,y2,... (e.g. polyline:6:0,100,0,0,210,0,210,100)",
                "curve": "curve:WIDTH[,PIECE_LENGTH[,MIN_LENGTH]] (e.g. curve:8; a bright "
                         "rope, --polarity dark for a dark cable)"}


def bit_depth_option(f):
    """``--bit-depth N`` (``Config.bit_depth``), for detect and odometry."""
    return click.option("--bit-depth", type=click.IntRange(9, 16), default=None, metavar="N",
                        help="Significant bits of 16-bit images: a camera's 10- or 12-bit "
                        "samples in 16-bit files (read as 16-bit data they are 64 or 16 times "
                        "too dark to show edges). Default: 16.")(f)


def ignore_boxes(ctx, param, values) -> tuple:
    """``--ignore X0,Y0,X1,Y1`` (repeatable) as boxes, or a usage error that
    says what is wrong with which.

    >>> ignore_boxes(None, None, ("0,0,140,18", "345, 255, 492, 360"))
    ((0, 0, 140, 18), (345, 255, 492, 360))
    """
    from ..config import MAX_COORD, _boxes

    out = []
    for v in values or ():
        try:   # (the numbers judged as Config.ignore judges them: one rule)
            (box,) = _boxes("ignore", [[float(p) for p in str(v).split(",")]])
        except (ValueError, SeahoughError):
            raise click.BadParameter(f"{v!r}: must be X0,Y0,X1,Y1, four numbers (image pixels) "
                                     f"with 0 <= X0 < X1 <= {MAX_COORD:,} and "
                                     f"0 <= Y0 < Y1 <= {MAX_COORD:,}") from None
        out.append(box)
    return tuple(out)


def make_detector(pattern, scale_range, angle_range, max_results, min_score, min_confidence,
                  downscale, keypoints, equalize, polarity, mask, max_nfa=1.0, colour=None,
                  bit_depth=None, smooth=None, ignore=()):
    """The Detector that the search options of ``seahough detect`` (also
    taken by ``survey detect``) describe; PATTERN as :func:`parse_pattern`.

    >>> make_detector("rect:60,40", (0.5, 2), (0, 360), 5, 0.5, 0.0, None, None, False,
    ...               None, None, max_nfa=0.01).max_nfa
    0.01
    """
    from ..config import Config
    from ..core.detector import Detector

    cfg_kw = {}
    if downscale is not None:
        cfg_kw["downscale"] = downscale
    if keypoints is not None:
        cfg_kw["n_keypoints"] = keypoints
        cfg_kw["n_keypoints_2d"] = keypoints
    if equalize:
        cfg_kw["equalize"] = True
    if colour is not None:
        cfg_kw["colour"] = bool(colour)
    if colour and polarity is None:
        # (as a painted pattern is searched by default: a colour edge's sign is the
        # channel's that changes most across it, which depends on the ground; a
        # colour trial's orange cross, --colour alone: 0 of 12 found, 12 with either)
        polarity = "either"
    if bit_depth is not None:
        cfg_kw["bit_depth"] = int(bit_depth)
    if smooth:
        cfg_kw["smooth"] = float(smooth)
    if ignore:
        cfg_kw["ignore"] = tuple(ignore)
    config = Config(**cfg_kw)
    kind, sep, rest = pattern.partition(":")
    if sep and kind.strip().lower() == "curve" and not Path(pattern).is_file():
        pattern_options(pattern)   # (none: says so)
        from ..core.detector import Detector as _D

        defaults = {k: v.default for k, v in inspect.signature(_D.__init__).parameters.items()}
        unused = [name for name, given, default in (
            ("--scale-range", tuple(scale_range), tuple(defaults["scale_range"])),
            ("--angle-range", tuple(angle_range), tuple(defaults["angle_range"])),
            ("--min-score", min_score, defaults["min_score"]),
            ("--min-confidence", min_confidence, defaults["min_confidence"]),
            ("--mask", mask, None), ("--colour", bool(colour), False)) if given != default]
        if unused:
            raise click.BadParameter(f"{unused[0]} does not apply to curves (curve:WIDTH "
                                     "searches widths 0.5-1.5x WIDTH at any angle, grey)",
                                     param_hint=unused[0])
        if max_results > 100:
            raise click.BadParameter(f"{max_results}: at most 100 curves an image",
                                     param_hint="--max-results")
        return CurveSearch(*_curve_spec(pattern, rest), _SHAPE_POLARITY[polarity or "bright"],
                           config, max_results, max_nfa)
    given = dict(scale_range=scale_range, angle_range=angle_range, max_results=max_results,
                 min_score=min_score, min_confidence=min_confidence, max_nfa=max_nfa)
    named = parse_patterns(pattern)
    if named is None:
        spec, own = pattern_options(pattern)
        pat = parse_pattern(spec, own.pop("polarity", polarity), mask, config)
        return Detector(pat, config=config, **{**given, **own})
    if mask is not None:
        raise click.BadParameter("--mask applies to a single image pattern, not to several "
                                 "patterns", param_hint="--mask")
    pat = {}
    for name, spec in named:
        spec, own = pattern_options(spec)
        p = parse_pattern(spec, own.pop("polarity", polarity), None, config)
        if own:   # (its own ranges or thresholds: a Detector of its own)
            try:
                p = Detector(p, config=config, **{**given, **own})
            except SeahoughError as e:   # (which pattern's settings)
                raise click.BadParameter(f"{name}: {spec}@...: {e}",
                                         param_hint="PATTERN") from None
        pat[name] = p
    return Detector(pat, config=config, **given)


#: A pattern's own options in a PATTERN of several (``SPEC@key=value,...``).
PATTERN_OPTIONS = {"scale": "scale_range", "angle": "angle_range", "polarity": "polarity",
                   "n": "max_results", "min-score": "min_score",
                   "min-confidence": "min_confidence", "max-nfa": "max_nfa"}


def pattern_options(spec: str):
    """A pattern's SPEC and its own options, from ``SPEC@key=value,...``
    (``scale=LO:HI``, ``angle=LO:HI``, ``polarity=bright|dark|either``,
    ``n=N``, ``min-score=S``, ``min-confidence=C``, ``max-nfa=E``), as
    Detector keywords.

    >>> pattern_options("polyline:6:0,100,0,0,210,0,210,100@angle=-15:15,polarity=either")
    ('polyline:6:0,100,0,0,210,0,210,100', {'angle_range': (-15.0, 15.0), 'polarity': 'either'})
    >>> pattern_options("circle:16")
    ('circle:16', {})
    """
    if Path(spec).is_file() or "@" not in spec:
        return spec, {}
    spec, _, opts = spec.rpartition("@")
    if spec.strip().lower().startswith("curve:"):
        raise click.BadParameter(f"{spec}@{opts}: curve:WIDTH takes no @ settings (give "
                                 "--polarity, -n, --max-nfa)", param_hint="PATTERN")
    out = {}
    for item in opts.split(","):
        key, eq, value = (t.strip() for t in item.partition("="))
        if key not in PATTERN_OPTIONS or not eq or not value:
            raise click.BadParameter(
                f"{spec}@{opts}: expected @key=value,... with keys "
                + ", ".join(PATTERN_OPTIONS) + f" (got {item.strip()!r})", param_hint="PATTERN")
        name = PATTERN_OPTIONS[key]
        if name in out:
            raise click.BadParameter(f"{spec}@{opts}: {key} is given twice",
                                     param_hint="PATTERN")
        try:
            if name in ("scale_range", "angle_range"):
                lo, colon, hi = value.partition(":")
                if not colon:
                    raise ValueError
                out[name] = (float(lo), float(hi))
            elif name == "polarity":
                if value not in ("bright", "dark", "either"):
                    raise ValueError
                out[name] = value
            elif name == "max_results":
                out[name] = int(value)
            else:
                out[name] = float(value)
        except ValueError:
            form = {"scale_range": "LO:HI", "angle_range": "LO:HI",
                    "polarity": "bright, dark or either", "max_results": "a whole number"}
            raise click.BadParameter(f"{spec}@{opts}: {key}={value!r}: expected "
                                     f"{form.get(name, 'a number')}", param_hint="PATTERN") \
                from None
    return spec, out


def _curve_spec(spec: str, rest: str) -> tuple:
    """``(width, piece_length, min_length)`` of
    ``curve:WIDTH[,PIECE_LENGTH[,MIN_LENGTH]]`` (None: find_curves' default).

    >>> _curve_spec("curve:8", "8"), _curve_spec("curve:8,40,60", "8,40,60")
    ((8.0, None, None), (8.0, 40.0, 60.0))
    """
    from ..core.curves import _check

    v = _numbers(rest, spec)
    if not 1 <= len(v) <= 3:
        raise click.BadParameter(f"{spec!r}: expected curve:WIDTH[,PIECE_LENGTH[,MIN_LENGTH]] "
                                 "(px, e.g. curve:8 or curve:8,40,60)",
                                 param_hint="PATTERN")
    width, piece, least = (list(map(float, v)) + [None, None])[:3]
    try:
        _check(width, (0.5, 1.5), "bright", piece, 25.0, 1, None)
        if least is not None:
            number("min_length", least, lo=0.0)
    except ParameterError as e:
        raise click.BadParameter(f"{spec!r}: {e} (curve:WIDTH[,PIECE_LENGTH[,MIN_LENGTH]])",
                                 param_hint="PATTERN") from None
    return width, piece, least


class CurveSearch:
    """``seahough detect curve:WIDTH``: :func:`~seahough.find_curves` in the
    shape of a Detector's search, for the detect command (its results'
    ``detections`` are :class:`~seahough.Curve` objects)."""

    parts: dict = {}
    pattern = None

    def __init__(self, width, piece_length, min_length, polarity, config, max_results, max_nfa):
        self.width, self.polarity, self.config = width, polarity, config
        self.piece_length, self.min_length = piece_length, min_length
        self.max_results, self.max_nfa = max_results, max_nfa

    def search(self, image, *, name: str | None = None):
        from types import SimpleNamespace

        from ..core.blanks import find_blanks
        from ..core.curves import find_curves
        from ..io.images import to_gray

        cfg = self.config
        # (decoded once here: what was left out, captions and --ignore, is said too)
        gray = to_gray(image, name=name or (str(image) if isinstance(image, (str, Path))
                                           else "image"),
                       max_pixels=cfg.max_pixels, max_memory_mb=cfg.max_memory_mb,
                       bit_depth=cfg.bit_depth)
        declined: list = []       # (why no curve: the seed candidates' reasons)
        curves = find_curves(gray, self.width, polarity=self.polarity, config=cfg,
                             piece_length=self.piece_length, min_length=self.min_length,
                             max_curves=self.max_results, max_nfa=self.max_nfa,
                             declined=declined)
        return SimpleNamespace(detections=curves, note="", planes=None, features=None,
                               blanks=find_blanks(gray, cfg.ignore), parts={},
                               candidates=declined)


def parse_patterns(spec: str):
    """Several patterns in one PATTERN argument: ``[NAME=]SPEC+[NAME=]SPEC...``
    as ``[(name, spec), ...]`` (a pattern without a name is named by its
    spec); None for one pattern (or an existing file whose name holds "+").

    >>> parse_patterns("gate=polyline:6:0,80,0,0,60,0,60,80+circle:16")
    [('gate', 'polyline:6:0,80,0,0,60,0,60,80'), ('circle:16', 'circle:16')]
    >>> parse_patterns("rect:60,40") is None
    True
    >>> parse_patterns("buoy=circle:16")
    [('buoy', 'circle:16')]
    >>> parse_patterns("circle:16@scale=0.3:2+gate=rect:90,60@angle=-15:15")
    [('circle:16', 'circle:16@scale=0.3:2'), ('gate', 'rect:90,60@angle=-15:15')]
    """
    if Path(spec).is_file():
        return None

    def naming(part):   # NAME=REST, or None and the part (an "=" after "@" is an option's)
        name, eq, rest = part.partition("=")
        if not eq or "@" in name or any(c in name for c in ":/\\.,"):
            return None, part
        return name, rest

    if "+" not in spec:   # one pattern: named only as NAME=SPEC with a plain name
        name, _ = naming(spec)
        if name is None or not name.strip():
            return None
    named = []
    for part in spec.split("+"):
        name, rest = naming(part)
        rest = rest.strip()
        name = pattern_options(rest)[0].strip() if name is None else name.strip()
        if not name or not rest:
            raise click.BadParameter(f"{spec!r}: expected [NAME=]SPEC+[NAME=]SPEC..., got an "
                                     f"empty part {part!r}", param_hint="PATTERN")
        if rest.lower().startswith("curve:"):
            raise click.BadParameter(f"{spec!r}: curve:WIDTH is searched alone, not with "
                                     "other patterns", param_hint="PATTERN")
        if name in dict(named):
            raise click.BadParameter(f"{spec!r}: the name {name!r} is given twice",
                                     param_hint="PATTERN")
        named.append((name, rest))
    return named


def parse_pattern(spec: str, polarity: str | None = None, mask: str | None = None,
                  config=None):
    """A :class:`~seahough.Pattern` from an image file or a shape spec.

    ``rect:W,H``, ``line:LENGTH,WIDTH``, ``circle:R``, ``circle:R,INNER``
    (a ring), ``polygon:x1,y1,x2,y2,...``, ``polyline:WIDTH:x1,y1,x2,y2,...``
    (open strips WIDTH px wide along the points); anything else is an image
    file.

    >>> parse_pattern("rect:60,40").kind
    'rectangle'
    >>> parse_pattern("polyline:6:0,80,0,0,60,0,60,80").polyline_width   # a gate
    6.0
    """
    from ..core.pattern import Pattern

    kind, sep, rest = spec.partition(":")
    kind = kind.strip().lower()
    if sep and kind in _SHAPE_COUNTS and not Path(spec).is_file():
        pol = _SHAPE_POLARITY[polarity or "bright"]
        if mask is not None:
            raise click.BadParameter("--mask applies to image patterns, not shapes",
                                     param_hint="--mask")
        if kind == "polyline":   # the width, then the points
            width, sep2, rest = rest.partition(":")
            w = _numbers(width, spec)
            v = w + _numbers(rest, spec)
            ok = bool(sep2) and len(w) == 1 and len(v) >= 5 and len(v) % 2 == 1
            if bool(sep2) and len(w) == 1 and not ok:   # (the width given: say what the points lack)
                n = len(v) - 1
                raise click.BadParameter(
                    f"{spec!r}: points: {n} coordinates, " + (
                        "an odd count (x, y pairs expected)" if n % 2 else
                        "a polyline needs at least 2 (x, y) points") +
                    f" ({_SHAPE_USAGE[kind]})", param_hint="PATTERN")
        else:
            v = _numbers(rest, spec)
            want = _SHAPE_COUNTS[kind]
            ok = (len(v) in want) if isinstance(want, tuple) else (
                len(v) == want if want is not None else (len(v) >= 6 and len(v) % 2 == 0))
        if not ok:
            raise click.BadParameter(f"{spec!r}: expected {_SHAPE_USAGE[kind]}",
                                     param_hint="PATTERN")
        try:
            if kind in ("rect", "rectangle"):
                return Pattern.rectangle(v[0], v[1], polarity=pol)
            if kind == "line":
                return Pattern.line(v[0], v[1], polarity=pol)
            if kind in ("circle", "ring"):
                return Pattern.circle(v[0], v[1] if len(v) > 1 else None, polarity=pol)
            if kind == "ellipse":
                return Pattern.ellipse(v[0], v[1], polarity=pol)
            if kind == "polyline":
                return Pattern.polyline([v[i:i + 2] for i in range(1, len(v), 2)], v[0],
                                        polarity=pol)
            return Pattern.polygon([v[i:i + 2] for i in range(0, len(v), 2)], polarity=pol)
        except SeahoughError as e:
            raise click.BadParameter(f"{spec!r}: {e}", param_hint="PATTERN") from None
    p = Path(spec)
    if not p.exists():
        if sep and len(kind) > 1:
            raise click.BadParameter(f"{spec!r} is neither an image file nor a shape "
                                     f"({SHAPES_HELP})", param_hint="PATTERN")
        hint = (f" (a shape needs its sizes: {_SHAPE_USAGE[spec.lower()]})"
                if spec.lower() in _SHAPE_USAGE else "")
        # a shape's name run into its sizes ("circle16"): its colon left out
        shape = re.match(r"^([a-z]+)[\d.,]", spec.lower())
        if not hint and shape and shape.group(1) in _SHAPE_USAGE:
            hint = f" (a shape is NAME:SIZES: {_SHAPE_USAGE[shape.group(1)]})"
        raise _Fail(f"pattern {spec}: no such file{hint}")
    if p.suffix.lower() == ".npz":   # (a pattern Pattern.save wrote: made once, used here)
        if mask is not None or polarity is not None:
            raise _Fail(f"pattern {spec}: a saved pattern keeps its own "
                        f"{'mask' if mask is not None else 'polarity'} (give none)")
        try:
            return Pattern.load(spec, config=config)
        except SeahoughError as e:
            raise _Fail(f"pattern {spec}: {_problem(e, spec)}") from None
    try:
        return Pattern.from_image(spec, mask=mask, polarity=_IMAGE_POLARITY.get(polarity),
                                  config=config)
    except SeahoughError as e:
        raise _Fail(f"pattern {spec}: {_problem(e, spec)}") from None
