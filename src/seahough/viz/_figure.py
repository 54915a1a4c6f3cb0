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

from ..core.lines import _BAND_TOL, _line_ends, _line_extent  # noqa: F401  (their home was here)
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
