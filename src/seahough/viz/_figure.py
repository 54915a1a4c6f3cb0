"""What every picture shares: the resolution, the colours, making and saving
a figure, measuring text and showing an image; and where a line crosses
the image and which part of it the image shows.

Speed (a 4K photo, issue 17): an image larger than it is drawn is shrunk to
its drawn size by OpenCV (an area average) before matplotlib sees it, rather
than resampled by matplotlib (which first makes a masked RGBA copy of the
whole 4K photo: 0.35 s of the overlay's 0.6 s); PNGs are encoded by OpenCV
as RGB at zlib level 1 with one row filter rather than by Pillow as RGBA at
level 6: files of about the same size, ten times faster (0.015 s instead of
0.17 s for a photo's overlay).

Thread safety: figures are :class:`~matplotlib.figure.Figure` objects with
their own Agg canvas, never :mod:`matplotlib.pyplot` and its current-figure
state, and nothing here is shared between calls, so pictures can be drawn
from several threads at once (matplotlib renders one figure at a time, under
a lock in ``Figure.draw``: safe, not faster)."""

from __future__ import annotations

import io
import math
import os
from pathlib import Path

import cv2
import numpy as np
from matplotlib import patheffects
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..core.ranking import FLAG_ALONG_LINE
from ..errors import ParameterError, WriteError
from ..geometry import format_angle, format_line
from ..io.images import read_image, to_bgr8, to_gray, write_bytes

#: Resolution of every figure (pixels per inch); sizes are given in pixels.
DPI = 100
#: How the PNGs are encoded (OpenCV's ``imencode`` flags): zlib level 1,
#: the fastest (level 6 makes a photo's PNG about 10 % smaller in five times
#: the time), and each row stored as its difference from the row above
#: (libpng's "up" filter: half the time of trying every filter on each row,
#: files 0-3 % larger; OpenCV >= 4.12 knows the flag, older ones use their default).
_PNG_FLAGS = [cv2.IMWRITE_PNG_COMPRESSION, 1] + (
    [cv2.IMWRITE_PNG_FILTER, cv2.IMWRITE_PNG_FILTER_UP] if hasattr(cv2, "IMWRITE_PNG_FILTER")
    else [])
#: Strong colours for detections, best first; they stand out on blue-green water.
COLOURS = ("#ff2d2d", "#00e5ff", "#ffd60a", "#ff3df2", "#39ff5a", "#ff9500")
#: The true path in :func:`~seahough.viz.plot_trajectory` (a band under the estimate).
TRUTH_COLOUR = "#c4c4c4"
#: A black border around lines and markers drawn over an image.
_OUTLINE = [patheffects.Stroke(linewidth=4.5, foreground="black", alpha=0.8), patheffects.Normal()]
#: A black border around text drawn over an image or a plane.
_TEXT_OUTLINE = [patheffects.withStroke(linewidth=3, foreground="black")]


def _items(name: str, items, kind: str, attrs: tuple, source: str) -> list:
    """``items`` as a list, each with the attributes ``attrs`` of a ``kind``
    (a ParameterError naming ``name`` and what gives them, not an
    AttributeError deep in the drawing)."""
    try:
        out = list(items or [])
    except TypeError:   # (a SearchResult: its .detections)
        raise ParameterError(f"{name}: expected a list of {kind} objects ({source}), got "
                             f"{type(items).__name__}") from None
    bad = next((v for v in out if not all(hasattr(v, a) for a in attrs)), None)
    if bad is not None:
        raise ParameterError(f"{name}: expected {kind} objects ({source}), got "
                             f"{type(bad).__name__} {bad!r:.40}")
    return out


def _figure(width_px: int, height_px: int) -> Figure:
    """A ``width_px`` x ``height_px`` figure with an Agg canvas (no pyplot),
    so that text can be measured while laying it out."""
    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _set_title(fig: Figure, ax, title: str) -> None:
    """``ax``'s title on the left, broken into lines that fit the figure
    (a not-found picture's title says why, and ran off its right edge: a
    user read "...under min_len"): two lines at 12 pt, else up to three at
    10 pt, the last cut with an ellipsis beyond that."""
    x0 = ax.get_position().x0 * fig.bbox.width
    room = fig.bbox.width - x0 - 8.0
    for size, most in ((12, 2), (10, 3)):
        lines = [""]
        for word in title.split(" "):
            trial = f"{lines[-1]} {word}" if lines[-1] else word
            if lines[-1] and _text_size(fig, trial, fontsize=size)[0] > room:
                lines.append(word)
            else:
                lines[-1] = trial
        if len(lines) <= most:
            break
    cut = len(lines) > most
    lines = lines[:most]
    for k, line in enumerate(lines):   # (a line still too wide: one long word, a path)
        end = " ..." if cut and k == len(lines) - 1 else ""
        if end or _text_size(fig, line, fontsize=size)[0] > room:
            while len(line) > 1 and _text_size(fig, line + (end or " ..."),
                                               fontsize=size)[0] > room:
                line = line[:-1]
            lines[k] = line + (end or " ...")
    ax.set_title("\n".join(lines), fontsize=size, loc="left")


def _text_size(fig: Figure, text: str, **props) -> tuple[float, float]:
    """``(width, height)`` in px of ``text`` drawn with ``props``."""
    t = fig.text(0, 0, text, **props)
    bb = t.get_window_extent(fig.canvas.get_renderer())
    t.remove()
    return bb.width, bb.height


def _png_bytes(fig: Figure, path) -> np.ndarray:
    """``fig`` rendered by its Agg canvas (as ``savefig`` does at the
    figure's dpi) and encoded as an RGB PNG with :data:`_PNG_FLAGS` (the
    figures are opaque); ``path`` only names the file in an error."""
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    ok, buf = cv2.imencode(".png", cv2.cvtColor(rgba, cv2.COLOR_RGBA2BGR), _PNG_FLAGS)
    if not ok:                                         # (not seen: an 8-bit BGR array)
        raise WriteError(f"{path}: cannot write the figure (PNG encoding failed)")
    return buf


def stack_figures(figs, path) -> None:
    """Figures drawn one under the other in one PNG at ``path`` (white
    where one is narrower than the widest): e.g. the accumulator of each
    pattern of a search of several. A :class:`~seahough.errors.WriteError`
    naming the file when it cannot be written."""
    from ..io.images import write_image

    parts = []
    for fig in figs:
        fig.canvas.draw()
        parts.append(cv2.cvtColor(np.asarray(fig.canvas.buffer_rgba()), cv2.COLOR_RGBA2BGR))
    width = max(a.shape[1] for a in parts)
    rows = [cv2.copyMakeBorder(a, 0, 0, 0, width - a.shape[1], cv2.BORDER_CONSTANT,
                               value=(255, 255, 255)) for a in parts]
    write_image(path, np.vstack(rows), what="the figure")


def _finish(fig: Figure, path) -> Figure:
    """Save ``fig`` at ``path`` (its folder made as needed; the format from
    the extension, PNG without one) unless ``path`` is None; return it.
    Rendered in memory (a PNG by :func:`_png_bytes`, other formats by
    ``savefig``), then written by :func:`~seahough.io.images.write_bytes`:
    a :class:`~seahough.errors.WriteError` naming the file when it cannot be."""
    if path is not None:
        p = Path(path)
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise WriteError(f"{p}: cannot write the figure ({e.strerror or e})") from None
        fmt = p.suffix[1:].lower() or "png"
        if fmt == "png" and fig.dpi == DPI:
            data = _png_bytes(fig, p)
        else:
            buf = io.BytesIO()
            fig.savefig(buf, dpi=DPI, format=fmt)
            data = buf.getbuffer()
        write_bytes(p, data, what="the figure")
    return fig


def _as_display(image, bit_depth: int | None = None) -> tuple[np.ndarray, bool]:
    """``(array for imshow, is_colour)`` from a path or an OpenCV array:
    8-bit BGR or BGRA as RGB, anything else as grey levels (0-255); a uint16
    one of ``bit_depth`` bits (:attr:`seahough.Config.bit_depth`) as the
    search reads it."""
    if isinstance(image, (str, os.PathLike)):
        image = read_image(image)
    a = np.asarray(image)
    if a.dtype == np.uint16 and bit_depth is not None:
        a = to_bgr8(a, bit_depth) if a.ndim == 3 else to_gray(a, min_side=1,
                                                              bit_depth=bit_depth)
    if a.ndim == 3 and a.shape[2] in (3, 4) and a.dtype == np.uint8:
        return cv2.cvtColor(to_bgr8(a), cv2.COLOR_BGR2RGB), True
    return to_gray(a, min_side=1), False


def _drawn_size(shape, box_wh) -> tuple[int, int]:
    """``(width, height)`` in whole px of an image of ``shape`` (height,
    width, ...) drawn as large as fits in a box of ``box_wh`` px, keeping its
    aspect (as ``imshow`` with ``aspect="equal"`` draws it)."""
    h, w = shape[:2]
    s = min(box_wh[0] / w, box_wh[1] / h)
    return max(1, round(w * s)), max(1, round(h * s))


def _fit(a: np.ndarray, box_wh) -> np.ndarray:
    """``a`` shrunk by an area average to the size it is drawn at in a box of
    ``box_wh`` px (see :func:`_drawn_size`), or ``a`` itself when it is not
    larger than that: what the PNG shows of it, without a 4K array for
    matplotlib to resample.

    Examples
    --------
    >>> _fit(np.zeros((2160, 3840, 3), np.uint8), (900, 675)).shape
    (506, 900, 3)
    >>> _fit(np.zeros((240, 320), np.uint8), (900, 675)).shape
    (240, 320)
    """
    h, w = a.shape[:2]
    dw, dh = _drawn_size(a.shape, box_wh)
    if dw >= w and dh >= h:
        return a
    k = min(w // dw, h // dh)
    if k >= 2:      # whole blocks of k x k first: OpenCV's fast path, half the time
        a = cv2.resize(a, (w // k, h // k), interpolation=cv2.INTER_AREA)
    return cv2.resize(a, (min(dw, w), min(dh, h)), interpolation=cv2.INTER_AREA)


def _imshow(ax, a: np.ndarray, box_wh=None, *, extent=None, **kw):
    """``ax.imshow(a, **kw)`` with pixel centres at integer coordinates of
    ``a`` (or spanning ``extent``, (left, right, bottom, top) in data
    coordinates, e.g. a working image drawn in full-resolution pixels); when
    ``box_wh`` (the axes' box in px) is given, ``a`` larger than drawn there
    is shrunk first (:func:`_fit`) and shown pixel for pixel, as is one drawn
    at its own size (e.g. ``plot_detections(max_width=0)``)."""
    h, w = a.shape[:2]
    if box_wh is not None:
        small = _fit(a, box_wh)
        if small is not a or _drawn_size(a.shape, box_wh) == (w, h):
            a = small
            kw["interpolation"] = "none"      # pixel for pixel: no resampling
    if extent is None:
        extent = (-0.5, w - 0.5, h - 0.5, -0.5)
    return ax.imshow(a, extent=extent, **kw)


def _pattern_picture(pattern) -> tuple[np.ndarray, dict]:
    """A pattern made from an image as :func:`_imshow` draws it, and how:
    a colour one in its colours (RGB), a grey one in grey levels."""
    bgr = getattr(pattern, "_colour", None)
    if bgr is not None:
        return np.clip(np.asarray(bgr, np.float32)[:, :, 2::-1], 0, 255).astype(np.uint8), {}
    return pattern.image, {"cmap": "gray", "vmin": 0, "vmax": 255}


def _show(ax, disp: np.ndarray, colour: bool, box_wh=None) -> None:
    """Draw an image from :func:`_as_display` filling ``ax`` (a box of
    ``box_wh`` px: see :func:`_imshow`), pixel centres at integer
    coordinates."""
    h, w = disp.shape[:2]
    if colour:
        _imshow(ax, disp, box_wh, interpolation="antialiased")
    else:
        _imshow(ax, disp, box_wh, cmap="gray", vmin=0, vmax=255, interpolation="antialiased")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_autoscale_on(False)


def _line_ends(x, y, angle_deg, w, h):
    """The two ends of the line through (x, y) at ``angle_deg`` (counter-
    clockwise as displayed) clipped to the image, or None when it misses."""
    t = math.radians(angle_deg)
    d = np.array([math.cos(t), -math.sin(t)])
    L = 2.0 * math.hypot(w, h) + abs(x) + abs(y)
    p1 = (int(round((x - L * d[0]) * 64)), int(round((y - L * d[1]) * 64)))
    p2 = (int(round((x + L * d[0]) * 64)), int(round((y + L * d[1]) * 64)))
    ok, a, b = cv2.clipLine((0, 0, int(w * 64), int(h * 64)), p1, p2)
    if not ok:
        return None
    return (a[0] / 64 - 0.5, a[1] / 64 - 0.5), (b[0] / 64 - 0.5, b[1] / 64 - 0.5)


#: Where a line detection's visible extent is looked for: its borders'
#: edges within this many px across, their gradient within 25 degrees of
#: the line's normal (tan 25 = 0.47), and gaps along it of at most this
#: share of the image's diagonal.
_BAND_TOL = 1.5
_ACROSS_RATIO = 1.0 / math.tan(math.radians(25.0))
_MAX_GAP = 0.05


def _line_extent(gray: np.ndarray, d, half: float, min_gradient: float):
    """``(t0, t1)``: the visible extent of line detection ``d`` along its
    direction, px from ``(d.x, d.y)``, or None when none is found.

    The grey image is sampled in a strip along the line (1 px along, 0.5 px
    across); a place along it holds the object when both of its borders
    (``half`` px each side of the centre line, within 1.5 px) have an edge
    there: a gradient across the line of at least ``min_gradient`` (Scharr
    units: 32 per grey level per px), within 25 degrees of the normal, of
    the sign most of that border's edges have (a bright rope has opposite
    signs on its two sides). The longest run of such places without gaps
    over 5 % of the image's diagonal gives the ends; one shorter than a
    tenth of the line's length in the image does not count.

    Examples
    --------
    >>> import types
    >>> img = np.full((100, 200), 40, np.float32)
    >>> img[48:53, 30:120] = 220                         # a rope 5 px wide, x 30-119
    >>> d = types.SimpleNamespace(x=99.5, y=50.0, line_angle=0.0)
    >>> [round(float(v)) for v in _line_extent(img, d, 2.5, 48.0)]
    [-70, 20]
    """
    h, w = gray.shape
    ends = _line_ends(d.x, d.y, d.line_angle, w, h)
    if ends is None:
        return None
    a = math.radians(d.line_angle)
    dx, dy = math.cos(a), -math.sin(a)
    nx, ny = math.sin(a), math.cos(a)
    ts = sorted((e[0] - d.x) * dx + (e[1] - d.y) * dy for e in ends)
    t = np.arange(math.floor(ts[0]), math.ceil(ts[1]) + 1, dtype=np.float32)
    reach = half + _BAND_TOL + 1.0
    s = np.arange(-reach, reach + 0.25, 0.5, dtype=np.float32)
    mx = (d.x + t[None, :] * dx + s[:, None] * nx).astype(np.float32)
    my = (d.y + t[None, :] * dy + s[:, None] * ny).astype(np.float32)
    strip = cv2.remap(np.ascontiguousarray(gray, np.float32), mx, my, cv2.INTER_LINEAR,
                      borderMode=cv2.BORDER_REPLICATE)
    strip = cv2.blur(strip, (3, 1))                   # strands, noise: 3 px along
    g_s = np.zeros_like(strip)                        # grey levels per px, across
    g_s[1:-1] = strip[2:] - strip[:-2]                # (rows 0.5 px apart)
    g_t = np.zeros_like(strip)                        # and along
    g_t[:, 1:-1] = 0.5 * (strip[:, 2:] - strip[:, :-2])
    thr = min_gradient / 32.0
    hit = np.ones(t.size, bool)
    for side in (-half, half):
        rows = np.flatnonzero(np.abs(s - side) <= _BAND_TOL)
        rows = rows[(rows > 0) & (rows < s.size - 1)]
        if rows.size == 0:
            return None
        gs, gt = g_s[rows], g_t[rows]
        best = np.abs(gs).argmax(axis=0)
        col = np.arange(t.size)
        gs, gt = gs[best, col], gt[best, col]
        edge = (np.abs(gs) >= thr) & (np.abs(gs) >= _ACROSS_RATIO * np.abs(gt))
        if not edge.any():
            return None
        sign = 1.0 if (gs[edge] > 0).sum() >= (gs[edge] < 0).sum() else -1.0
        hit &= edge & (gs * sign > 0)
    idx = np.flatnonzero(hit)
    if idx.size == 0:
        return None
    cuts = np.flatnonzero(np.diff(t[idx]) > _MAX_GAP * math.hypot(w, h))
    starts, stops = np.r_[0, cuts + 1], np.r_[cuts, idx.size - 1]
    k = int(np.argmax(t[idx[stops]] - t[idx[starts]]))
    t0, t1 = float(t[idx[starts[k]]]), float(t[idx[stops[k]]])
    if t1 - t0 < 0.1 * (ts[1] - ts[0]):
        return None
    return t0, t1


def _det_label(d) -> str:
    """``"score 0.87 · conf 0.64 · s 1.23 · 45.0° · nfa 3e-10 · ambiguous"``
    (angles wrapped after rounding: 359.98 is written 0.0; the NFA and the
    flags, but a line's ever-present one, as a table gives them:
    a colour trial's wrong answer, flagged ambiguous, looked like a good one
    on the picture), after the pattern's name for a search of several."""
    name = getattr(d, "pattern", "")
    if name:
        return f"{name} · " + _det_label(type(d)(**{**d.__dict__, "pattern": ""}))
    if d.kind == "line" and d.line_angle is not None:
        angle, offset = format_line(d.line_angle, d.line_offset, 1)
        head = (f"score {d.score:.2f} · conf {d.confidence:.2f} · "
                f"line {angle}° · offset {offset:+.1f} px")
    else:
        head = (f"score {d.score:.2f} · conf {d.confidence:.2f} · s {d.scale:.2f} · "
                f"{format_angle(d.angle, 1)}°")
    nfa = getattr(d, "nfa", math.nan)
    flags = [f for f in getattr(d, "flags", ()) if f != FLAG_ALONG_LINE]
    return head + (f" · nfa {nfa:.0e}" if math.isfinite(nfa) else "") + "".join(
        f" · {f}" for f in flags)
