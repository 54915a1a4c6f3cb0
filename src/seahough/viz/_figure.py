"""What every picture shares: the resolution, the colours, making and saving
a figure, measuring text and showing an image."""

from __future__ import annotations

import io
import os
from pathlib import Path

import cv2
import numpy as np
from matplotlib import patheffects
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ..errors import WriteError
from ..io.images import read_image, to_bgr8, to_gray, write_bytes

#: Resolution of every figure (pixels per inch); sizes are given in pixels.
DPI = 100
#: Strong colours for detections, best first; they stand out on blue-green water.
COLOURS = ("#ff2d2d", "#00e5ff", "#ffd60a", "#ff3df2", "#39ff5a", "#ff9500")
#: The true path in :func:`~seahough.viz.plot_trajectory` (a band under the estimate).
TRUTH_COLOUR = "#c4c4c4"
#: A black border around lines and markers drawn over an image.
_OUTLINE = [patheffects.Stroke(linewidth=4.5, foreground="black", alpha=0.8), patheffects.Normal()]
#: A black border around text drawn over an image or a plane.
_TEXT_OUTLINE = [patheffects.withStroke(linewidth=3, foreground="black")]


def _figure(width_px: int, height_px: int) -> Figure:
    """A ``width_px`` x ``height_px`` figure with an Agg canvas (no pyplot),
    so that text can be measured while laying it out."""
    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _text_size(fig: Figure, text: str, **props) -> tuple[float, float]:
    """``(width, height)`` in px of ``text`` drawn with ``props``."""
    t = fig.text(0, 0, text, **props)
    bb = t.get_window_extent(fig.canvas.get_renderer())
    t.remove()
    return bb.width, bb.height


def _finish(fig: Figure, path) -> Figure:
    """Save ``fig`` at ``path`` (its folder made as needed; the format from
    the extension, PNG without one) unless ``path`` is None; return it.
    Rendered in memory, then written by :func:`~seahough.io.images.write_bytes`:
    a :class:`~seahough.errors.WriteError` naming the file when it cannot be."""
    if path is not None:
        p = Path(path)
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise WriteError(f"{p}: cannot write the figure ({e.strerror or e})") from None
        buf = io.BytesIO()
        fig.savefig(buf, dpi=DPI, format=p.suffix[1:].lower() or "png")
        write_bytes(p, buf.getbuffer(), what="the figure")
    return fig


def _as_display(image) -> tuple[np.ndarray, bool]:
    """``(array for imshow, is_colour)`` from a path or an OpenCV array:
    8-bit BGR or BGRA as RGB, anything else as grey levels (0-255)."""
    if isinstance(image, (str, os.PathLike)):
        image = read_image(image)
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[2] in (3, 4) and a.dtype == np.uint8:
        return cv2.cvtColor(to_bgr8(a), cv2.COLOR_BGR2RGB), True
    return to_gray(a, min_side=1), False


def _show(ax, disp: np.ndarray, colour: bool) -> None:
    """Draw an image from :func:`_as_display` filling ``ax``, pixel centres
    at integer coordinates."""
    h, w = disp.shape[:2]
    if colour:
        ax.imshow(disp, interpolation="antialiased")
    else:
        ax.imshow(disp, cmap="gray", vmin=0, vmax=255, interpolation="antialiased")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_autoscale_on(False)
