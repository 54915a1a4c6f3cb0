"""Pictures of what seahough found, and of how it got there.

Every function draws on a fresh :class:`matplotlib.figure.Figure` made
without :mod:`matplotlib.pyplot` (so no GUI backend is needed and no global
figure state is left behind; PNGs are rendered by Agg), saves it as a PNG when
given ``path`` and returns the figure. The PNG sizes are fixed (see each
function) so that pictures line up in reports and tests.

>>> import numpy as np
>>> from seahough import plot
>>> fig = plot.plot_detections(np.zeros((48, 64), np.uint8), [])
>>> fig.get_size_inches() * fig.dpi
array([1000.,  775.])
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import cv2
import numpy as np
from matplotlib import patheffects
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure

from ..geometry import format_angle

__all__ = ["plot_detections", "plot_accumulator", "plot_edges", "plot_trajectory",
           "save_mosaic", "detections_size", "scale_angle_marker", "DPI"]

#: Resolution of every figure (pixels per inch); sizes below are in pixels.
DPI = 100
#: Strong colours for detections, best first; they stand out on blue-green water.
COLOURS = ("#ff2d2d", "#00e5ff", "#ffd60a", "#ff3df2", "#39ff5a", "#ff9500")
#: The true path in :func:`plot_trajectory` (a band under the estimate).
TRUTH_COLOUR = "#c4c4c4"
_OUTLINE = [patheffects.Stroke(linewidth=4.5, foreground="black", alpha=0.8), patheffects.Normal()]
_TEXT_OUTLINE = [patheffects.withStroke(linewidth=3, foreground="black")]
#: What the accumulator planes' heights are (see :func:`plot_accumulator`):
#: votes over the number of pattern points, pooled over 2 x 2 position bins,
#: so a peak is often above 1; not the 0-1 score of a detection.
_VOTES = "votes per pattern point (2x2 bins pooled: can exceed 1)"
_IMAGE_BOX = 900        # longer side of an image drawn by plot_detections, px
_MARGINS = (75, 25, 45, 55)   # left, right, bottom, top margins around it, px
_MIN_WIDTH = 560
#: Smallest height of the image box: a strip shorter than this when drawn
#: (e.g. 900 x 60) has its notes (list, "not found", pattern) below it.
_MIN_BOX_HEIGHT = 240
_UNDER_AXIS = 48        # px below a drawn image taken by its x ticks and label


# --------------------------------------------------------------------------- helpers
def _figure(width_px: int, height_px: int) -> Figure:
    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI)
    FigureCanvasAgg(fig)        # a renderer, to measure text while laying out
    return fig


def _text_size(fig: Figure, text: str, **props) -> tuple[float, float]:
    """``(width, height)`` in px of ``text`` drawn with ``props``."""
    t = fig.text(0, 0, text, **props)
    bb = t.get_window_extent(fig.canvas.get_renderer())
    t.remove()
    return bb.width, bb.height


def _finish(fig: Figure, path) -> Figure:
    if path is not None:
        p = Path(path)
        if p.parent and not p.parent.exists():
            p.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(os.fspath(p), dpi=DPI, format=p.suffix[1:].lower() or "png")
    return fig


def _as_display(image) -> tuple[np.ndarray, bool]:
    """``(array for imshow, is_colour)`` from a path or an OpenCV array."""
    from ..io.images import read_image, to_gray

    if isinstance(image, (str, os.PathLike)):
        image = read_image(image)
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[2] in (3, 4) and a.dtype == np.uint8:
        code = cv2.COLOR_BGRA2RGB if a.shape[2] == 4 else cv2.COLOR_BGR2RGB
        return cv2.cvtColor(a, code), True
    return to_gray(a, min_side=1), False


def _show(ax, image) -> tuple[int, int]:
    disp, colour = _as_display(image)
    h, w = disp.shape[:2]
    if colour:
        ax.imshow(disp, interpolation="antialiased")
    else:
        ax.imshow(disp, cmap="gray", vmin=0, vmax=255, interpolation="antialiased")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_ylim(h - 0.5, -0.5)
    ax.set_autoscale_on(False)
    return h, w


def detections_size(shape) -> tuple[int, int]:
    """PNG size ``(width, height)`` in px that :func:`plot_detections` makes
    for an image of ``shape`` (height, width, ...).

    The image is drawn 900 px on its longer side, plus margins for the axes
    and title (75 + 25 px across, 45 + 55 px down), at least 560 px wide and
    with at least 240 px for the image and what goes under a short strip.

    >>> detections_size((480, 640))
    (1000, 775)
    >>> detections_size((60, 900))
    (1000, 340)
    """
    h, w = int(shape[0]), int(shape[1])
    s = _IMAGE_BOX / max(h, w)
    iw, ih = max(1, round(w * s)), max(1, round(h * s))
    left, right, bottom, top = _MARGINS
    return max(_MIN_WIDTH, iw + left + right), max(ih, _MIN_BOX_HEIGHT) + bottom + top


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


def _det_label(d) -> str:
    """``"score 0.87 · conf 0.64 · s 1.23 · 45.0°"`` (angles wrapped after
    rounding: 359.98 is written 0.0)."""
    if getattr(d, "kind", "object") == "line" and d.line_angle is not None:
        return (f"score {d.score:.2f} · conf {d.confidence:.2f} · "
                f"line {format_angle(d.line_angle, 1, 180.0)}° · "
                f"offset {d.line_offset:+.1f} px")
    return (f"score {d.score:.2f} · conf {d.confidence:.2f} · s {d.scale:.2f} · "
            f"{format_angle(d.angle, 1)}°")


def _place_label(ax, text, x, y, colour, w, h, above=True):
    """A boxed label near (x, y), kept inside the image."""
    ha = "left" if x < 0.25 * w else ("right" if x > 0.75 * w else "center")
    dy = -10 if above else 10
    if above and y < 0.08 * h:
        dy, above = 10, False
    if not above and y > 0.92 * h:
        dy = -10
    va = "bottom" if dy < 0 else "top"
    xs = float(np.clip(x, 0.02 * w, 0.98 * w))
    ys = float(np.clip(y, 0.02 * h, 0.98 * h))
    ax.annotate(text, (xs, ys), xytext=(0, -dy), textcoords="offset points", ha=ha, va=va,
                color=colour, fontsize=10, fontweight="bold", annotation_clip=False,
                bbox=dict(boxstyle="round,pad=0.25", fc="black", ec=colour, alpha=0.72, lw=1))


def _free_corners(points, w, h) -> list:
    """Image corners (0 TL, 1 TR, 2 BR, 3 BL), farthest from ``points`` first."""
    corners = np.array([[0, 0], [w, 0], [w, h], [0, h]], float)
    p = np.asarray(points, float).reshape(-1, 2)
    if len(p) == 0:
        return [1, 0, 2, 3]
    d = np.hypot(corners[:, None, 0] - p[None, :, 0], corners[:, None, 1] - p[None, :, 1]).min(1)
    d = d / math.hypot(w, h) + np.array([0, 1e-6, 0, 0])  # ties: top right
    return [int(k) for k in np.argsort(-d, kind="stable")]


_LIST_TEXT = dict(fontsize=10, fontweight="bold")
_LIST_PAD = 16          # px around the text of a list box (pad, border, rounding)
_LIST_SEP = 3           # px between its lines


def _wrap_label(fig: Figure, text: str, max_w: float) -> str:
    """``text`` broken at its " · " separators into lines at most ``max_w``
    px wide (continuation lines indented); a part wider than that alone
    stays on its own line."""
    parts = text.split(" · ")
    lines = [parts[0]]
    for part in parts[1:]:
        trial = f"{lines[-1]} · {part}"
        if _text_size(fig, trial, **_LIST_TEXT)[0] <= max_w:
            lines[-1] = trial
        else:
            lines.append("   " + part)
    return "\n".join(lines)


def _list_size(fig: Figure, items) -> tuple[float, float]:
    """``(width, height)`` in px of the list box :func:`_label_list` draws."""
    sizes = [_text_size(fig, t, **_LIST_TEXT) for t, _ in items]
    return (max(sw for sw, _ in sizes) + _LIST_PAD,
            sum(sh for _, sh in sizes) + _LIST_SEP * (len(sizes) - 1) + _LIST_PAD)


def _label_list(ax, items, corner: int = 1, at=None):
    """A boxed list of coloured lines: in an image corner, or with its top
    left corner at ``at`` (figure fraction) when given."""
    from matplotlib.offsetbox import AnchoredOffsetbox, TextArea, VPacker

    rows = [TextArea(t, textprops=dict(color=c, **_LIST_TEXT)) for t, c in items]
    box = VPacker(children=rows, align="left", pad=0, sep=_LIST_SEP)
    if at is None:
        loc = {0: "upper left", 1: "upper right", 2: "lower right", 3: "lower left"}[corner]
        anchored = AnchoredOffsetbox(loc=loc, child=box, pad=0.4, borderpad=0.6, frameon=True)
    else:
        anchored = AnchoredOffsetbox(loc="upper left", child=box, pad=0.4, borderpad=0.0,
                                     frameon=True, bbox_to_anchor=at,
                                     bbox_transform=ax.figure.transFigure)
    anchored.patch.set_facecolor("black")
    anchored.patch.set_alpha(0.72)
    anchored.patch.set_edgecolor("white")
    anchored.patch.set_boxstyle("round,pad=0.2")
    ax.add_artist(anchored)
    return anchored


def _draw_pattern(ins, pattern):
    ins.imshow(pattern.image, cmap="gray", vmin=0, vmax=255)
    for o in getattr(pattern, "outline", []):
        o = np.asarray(o, float)
        closed = getattr(pattern, "closed", True) and len(o) > 2
        if closed:
            o = np.vstack([o, o[:1]])
        ins.plot(o[:, 0], o[:, 1], color=COLOURS[0], lw=1.5)
    ins.set_xticks([]); ins.set_yticks([])
    for s in ins.spines.values():
        s.set_color("white"); s.set_linewidth(1.5)
    ins.set_title("pattern", color="white", fontsize=9, pad=2,
                  path_effects=_TEXT_OUTLINE)
    return ins


def _pattern_inset(ax, pattern, corner: int):
    size = 0.2
    pos = {0: (0.015, 0.955 - size), 1: (0.985 - size, 0.955 - size),
           2: (0.985 - size, 0.015), 3: (0.015, 0.015)}[corner]
    ph, pw = pattern.image.shape
    aspect = pw / ph
    bw, bh = (size, size / aspect) if aspect >= 1 else (size * aspect, size)
    x0 = pos[0] + (size - bw if corner in (1, 2) else 0)
    y0 = pos[1] + (size - bh if corner in (0, 1) else 0)
    return _draw_pattern(ax.inset_axes([x0, y0, bw, bh]), pattern)


def _pattern_beside(fig: Figure, pattern, x0: float, y_top: float, max_w: float):
    """The pattern in a box of at most ``max_w`` (and 140) px, its top left at
    (``x0``, ``y_top``) figure px (room left above for its title)."""
    ph, pw = pattern.image.shape
    side = min(max_w, 140.0)
    bw, bh = (side, side * ph / pw) if pw >= ph else (side * pw / ph, side)
    fw, fh = fig.get_size_inches() * fig.dpi
    y0 = y_top - 16 - bh
    return _draw_pattern(fig.add_axes([x0 / fw, y0 / fh, bw / fw, bh / fh]), pattern)


def _image_px(shape_wh, box_wh) -> tuple[float, float]:
    """Size in px of an image of ``shape_wh`` (w, h) drawn in a box of
    ``box_wh`` px keeping its aspect."""
    (w, h), (bw, bh) = shape_wh, box_wh
    s = min(bw / w, bh / h)
    return w * s, h * s


def _short_strip(w, h, box_w, box_h) -> bool:
    """Is the drawn image so much shorter than its box that its notes go
    under it (see :data:`_MIN_BOX_HEIGHT`)?"""
    return box_h - _image_px((w, h), (box_w, box_h))[1] >= _UNDER_AXIS + 60


def _fits_beside_object(fig, text, w, h, box_w, box_h) -> bool:
    """Whether a single detection's boxed label fits across the drawn image
    (a short strip's labels go under it)."""
    if _short_strip(w, h, box_w, box_h):
        return False
    tw, _ = _text_size(fig, text, **_LIST_TEXT)
    return tw + _LIST_PAD <= 0.96 * _image_px((w, h), (box_w, box_h))[0]


def _notes(fig, ax, detections, pattern, corners, wh, box_wh):
    """The detection list, the "not found" note and the pattern inset.

    In an image corner when they fit there; next to an image too narrow
    for them (the image is then drawn on the left and they go in the space
    on its right); else with the lines wrapped to fit inside the image.
    """
    left, _, bottom, _ = _MARGINS
    fw, fh = fig.get_size_inches() * fig.dpi
    dw, dh = _image_px(wh, box_wh)
    n = len(detections)
    items = [((f"#{i + 1} " if n > 1 else "") + _det_label(d), COLOURS[i % len(COLOURS)])
             for i, d in enumerate(detections)]
    lw, lh = _list_size(fig, items) if items else (0.0, 0.0)
    nf_size = 30
    nf_w = _text_size(fig, "not found", fontsize=nf_size, fontweight="bold")[0] + 30
    if n == 1:
        inside = _fits_beside_object(fig, items[0][0], *wh, *box_wh)
    elif n > 1:
        inside = lw <= 0.94 * dw and lh <= 0.6 * dh
    else:
        inside = nf_w <= 0.9 * dw
    x_side = left + dw + 14                     # the image drawn on the left
    side_w = fw - x_side - 8
    top_px = bottom + box_wh[1] / 2 + dh / 2    # the image's top edge
    if _short_strip(*wh, *box_wh):
        # the box is taller than the image: the image at the top, the notes
        # under its x axis
        ax.set_anchor("N")
        _notes_below(fig, items, pattern, (left, bottom + box_wh[1] - dh - _UNDER_AXIS),
                     fw - left - 8, nf_size)
        return
    if not inside and side_w >= 120:
        ax.set_anchor("W")
        y = top_px
        if items:
            items = [(_wrap_label(fig, t, side_w - _LIST_PAD), c) for t, c in items]
            _label_list(ax, items, at=(x_side / fw, y / fh))
            y -= _list_size(fig, items)[1] + 12
        else:
            size = nf_size
            while size > 12 and _text_size(fig, "not found", fontsize=size,
                                           fontweight="bold")[0] + size > side_w:
                size -= 2
            pad = 0.4 * size * DPI / 72             # the box's padding, px
            fig.text((x_side + pad) / fw, (y - pad) / fh, "not found", ha="left", va="top",
                     fontsize=size,
                     fontweight="bold", color="white", path_effects=_TEXT_OUTLINE,
                     bbox=dict(boxstyle="round,pad=0.4", fc="#b00020", ec="white", alpha=0.8))
            y -= 2.3 * size * DPI / 72 + 12
        if pattern is not None:
            _pattern_beside(fig, pattern, x_side, y, side_w)
        return
    if n == 1 and not inside:
        # no room beside the image: the label wrapped, in a free corner
        items = [(_wrap_label(fig, items[0][0], 0.94 * dw - _LIST_PAD), items[0][1])]
        _label_list(ax, items, corners[0])
        corners = corners[1:]
    elif n > 1:
        if not inside:
            items = [(_wrap_label(fig, t, 0.94 * dw - _LIST_PAD), c) for t, c in items]
        _label_list(ax, items, corners[0])
        corners = corners[1:]
    elif n == 0:
        size = nf_size
        while size > 10 and _text_size(fig, "not found", fontsize=size,
                                       fontweight="bold")[0] + 30 > 0.9 * dw:
            size -= 2
        ax.text(0.5, 0.5, "not found", transform=ax.transAxes, ha="center", va="center",
                fontsize=size, fontweight="bold", color="white", path_effects=_TEXT_OUTLINE,
                bbox=dict(boxstyle="round,pad=0.4", fc="#b00020", ec="white", alpha=0.8))
    if pattern is not None:
        _pattern_inset(ax, pattern, corners[0])


def _notes_below(fig, items, pattern, top_left, width, nf_size):
    """The detection list (or "not found") and the pattern, side by side,
    their tops at ``top_left`` (figure px), within ``width`` px."""
    fw, fh = fig.get_size_inches() * fig.dpi
    x, y = top_left
    room = y - 8                                  # px down to the figure's bottom
    if items:
        items = [(_wrap_label(fig, t, width - _LIST_PAD - 150), c) for t, c in items]
        _label_list(fig.axes[0], items, at=(x / fw, y / fh))
        x += _list_size(fig, items)[0] + 14
    else:
        size = nf_size
        while size > 12 and 2.3 * size * DPI / 72 > room:
            size -= 2
        pad = 0.4 * size * DPI / 72
        fig.text((x + pad) / fw, (y - pad) / fh, "not found", ha="left", va="top",
                 fontsize=size, fontweight="bold", color="white", path_effects=_TEXT_OUTLINE,
                 bbox=dict(boxstyle="round,pad=0.4", fc="#b00020", ec="white", alpha=0.8))
        x += _text_size(fig, "not found", fontsize=size, fontweight="bold")[0] + 2 * pad + 14
    if pattern is not None:
        ph, pw = pattern.image.shape
        side = max(min(room - 16, width - (x - top_left[0])), 8.0)  # 16: the title above it
        _pattern_beside(fig, pattern, x, y, side if pw >= ph else side * pw / ph)


# ------------------------------------------------------------------------ detections
def plot_detections(image, detections, path=None, *, pattern=None, title=None) -> Figure:
    """The image with each detection's outline, origin and numbers.

    Parameters
    ----------
    image : ndarray or path
        The searched image: BGR/BGRA (shown in its colours) or grey.
    detections : list of Detection
        From :meth:`seahough.Detector.detect`; best first. Objects are drawn
        with their closed outline; lines (``kind == "line"``) across the
        whole image along ``line_angle`` through ``(x, y)``, with their two
        borders dashed. Each gets a label
        ``"score 0.87 · conf 0.64 · s 1.23 · 45.0°"`` (angles in [0, 360),
        lines' in [0, 180), wrapped after rounding): beside a single
        detection, or, for several, in a numbered list in the image corner
        farthest from them; an empty list writes "not found" across the
        image. When an image is too narrow for them (a tall strip), the
        image is drawn on the left and the labels (wrapped as needed), the
        note and the pattern go in the space on its right; under a short
        strip (drawn less than 240 px high, e.g. 900 x 60), they go below
        it: nothing spills onto the axes.
    path : str or Path, optional
        Where to save the PNG.
    pattern : Pattern, optional
        Shown as a small inset (with its outline) in the image corner
        farthest from the detections (or beside a narrow image).
    title : str, optional
        Default: how many detections were found.

    Returns
    -------
    matplotlib.figure.Figure
        :func:`detections_size` px (1000 x 775 for a 640 x 480 image).
    """
    disp, _ = _as_display(image)
    h, w = disp.shape[:2]
    fw, fh = detections_size((h, w))
    fig = _figure(fw, fh)
    left, right, bottom, top = _MARGINS
    iw, ih = fw - left - right, fh - bottom - top
    ax = fig.add_axes([left / fw, bottom / fh, iw / fw, ih / fh])
    _show(ax, image)
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    detections = list(detections or [])
    anchors = []
    for i, d in enumerate(detections):
        c = COLOURS[i % len(COLOURS)]
        if getattr(d, "kind", "object") == "line" and d.line_angle is not None:
            # the rope's two borders, extended across the image (the rope shows
            # between them); the centre line when the outline is missing
            borders = [np.asarray(o, float).reshape(-1, 2) for o in d.outline]
            borders = [o[0] for o in borders if len(o) >= 2] or [np.array([d.x, d.y])]
            for bx, by in borders:
                e = _line_ends(bx, by, d.line_angle, w, h)
                if e is not None:
                    ax.plot([e[0][0], e[1][0]], [e[0][1], e[1][1]], color=c, lw=1.8,
                            path_effects=_OUTLINE)
        else:
            for o in d.outline:
                o = np.asarray(o, float).reshape(-1, 2)
                if len(o) > 2:
                    o = np.vstack([o, o[:1]])
                ax.plot(o[:, 0], o[:, 1], color=c, lw=2.2, path_effects=_OUTLINE)
        ax.plot([d.x], [d.y], marker="+", ms=16, mew=2.5, color=c, path_effects=_OUTLINE)
        pts = np.vstack([np.asarray(o, float).reshape(-1, 2) for o in d.outline]) \
            if d.outline else np.array([[d.x, d.y]])
        anchors.append(pts if getattr(d, "kind", "object") != "line" else np.array([[d.x, d.y]]))
        if getattr(d, "kind", "object") == "line":
            lx, ly = d.x, d.y
        else:
            lx, ly = float(np.mean(pts[:, 0])), float(pts[:, 1].min())
        if len(detections) == 1:
            if _fits_beside_object(fig, _det_label(d), w, h, iw, ih):
                _place_label(ax, _det_label(d), lx, ly, c, w, h)
        else:
            _place_label(ax, f"#{i + 1}", lx, ly, c, w, h)
    corners = _free_corners(np.vstack(anchors) if anchors else np.empty((0, 2)), w, h)
    _notes(fig, ax, detections, pattern, corners, (w, h), (iw, ih))
    if title is None:
        n = len(detections)
        title = "pattern not found" if n == 0 else f"{n} detection{'s' if n > 1 else ''}"
    ax.set_title(title, fontsize=12, loc="left")
    return _finish(fig, path)


# ----------------------------------------------------------------------- accumulator
def _ring(ax, x, y, colour, ms=22):
    """A hollow circle around (x, y) that leaves the peak inside visible."""
    ax.plot([x], [y], "o", ms=ms, mfc="none", mec="black", mew=4.0, clip_on=False)
    ax.plot([x], [y], "o", ms=ms, mfc="none", mec=colour, mew=2.0, clip_on=False)


def _edges_from_centres(c, log=False, single_half=1.0):
    c = np.asarray(c, float)
    if log:
        c = np.log(c)
    if c.size == 1:
        e = np.array([c[0] - single_half, c[0] + single_half])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        e = np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])
    return np.exp(e) if log else e


def _display_angles(angles_deg):
    """Rotation bin centres made increasing (wrap-around removed) and centred
    on the searched range, e.g. -17.5..17.5 rather than 342.5..17.5."""
    a = np.degrees(np.unwrap(np.radians(np.asarray(angles_deg, float))))
    if a.size and np.mean(a) > 180.0 + 1e-9:
        a = a - 360.0
    return a


def _rotation_edges(planes) -> np.ndarray:
    """Bin edges of the scale-rotation plane's rotation axis, as displayed."""
    return _edges_from_centres(_display_angles(planes.angles), single_half=2.5)


def scale_angle_marker(planes, scale, angle) -> tuple[float, float]:
    """``(rotation, scale)`` at which a detection is marked on the
    scale-rotation plane: the centre of the cell it refers to.

    That is the cell the refined ``scale`` and ``angle`` (degrees) fall in,
    or, when a neighbouring cell across the nearer border (in rotation, in
    scale, or both) holds more votes, that one: the refinement moves a pose
    by up to a cell from its accumulator peak. The rotation axis of a full
    turn wraps around, so a detection at 359.998 from a peak in the first
    cell is marked there, at the plane's left edge, not half outside its
    right edge. On a partial span an angle outside it goes to the nearer
    end. The rotation returned is in displayed degrees (the plane's x axis,
    e.g. -17.5..17.5 for a search of -20..20) and is a cell centre, so a
    marker is never cut by the plane's border.

    Parameters
    ----------
    planes : AccumulatorPlanes
    scale, angle : float
        The detection's refined scale and rotation (degrees).

    Returns
    -------
    (float, float)
    """
    centres = _display_angles(planes.angles)
    edges = _rotation_edges(planes)
    lo, hi = float(edges[0]), float(edges[-1])
    n = centres.size
    full = n > 1 and hi - lo >= 360.0 - 1e-6
    a = lo + (float(angle) - lo) % 360.0                 # in [lo, lo + 360)
    if not full and a > hi and (a - hi) > (lo - (a - 360.0)):
        a -= 360.0                                       # nearer the low end
    j0 = int(np.clip(np.searchsorted(edges, a, side="right") - 1, 0, n - 1))
    dj = -1 if a < centres[j0] else 1                    # towards the nearer border
    log_s = np.log(np.asarray(planes.scales, float))
    ls = math.log(max(float(scale), 1e-9))
    k0 = int(np.argmin(np.abs(log_s - ls)))
    dk = -1 if ls < log_s[k0] else 1
    sa = np.asarray(planes.scale_angle, float)
    best, cell = -np.inf, (k0, j0)
    for k, j in ((k0, j0), (k0, j0 + dj), (k0 + dk, j0), (k0 + dk, j0 + dj)):
        if full:
            j %= n                                       # own cell first: it wins ties
        if 0 <= k < log_s.size and 0 <= j < n and sa[k, j] > best:
            best, cell = sa[k, j], (k, j)
    k, j = cell
    return float(centres[j]), float(planes.scales[k])


def _place_peak_labels(ax, marks, ring_px=22):
    """``#k`` labels beside markers, moved up or down so that none covers
    another (markers of detections at the same place coincide).

    ``marks``: ``(text, x, y, colour)`` in data coordinates, best first.
    Returns the annotations."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    ax.apply_aspect()
    x0, x1 = sorted(ax.get_xlim())
    placed, out = [], []
    step = 15.0                                  # points between stacked labels
    for text, px, py, colour in marks:
        right = (px - x0) > 0.8 * (x1 - x0)
        dx = -14 if right else 14
        ann = ax.annotate(text, (px, py), xytext=(dx, 12), textcoords="offset points",
                          color=colour, fontsize=11, fontweight="bold",
                          ha="right" if right else "left", path_effects=_TEXT_OUTLINE,
                          annotation_clip=False)
        for k in range(1, 4 * len(marks) + 2):
            bb = ann.get_window_extent(renderer).expanded(1.0, 1.1)
            if not any(bb.overlaps(o) for o in placed):
                break
            # 12 + 15, 12 - 15 - ring, 12 + 30, ...: above first, then below the ring
            j = (k + 1) // 2
            dy = 12 + j * step if k % 2 else 12 - j * step - ring_px
            ann.set_position((dx, dy))
        placed.append(ann.get_window_extent(renderer))
        out.append(ann)
    return out


def plot_accumulator(planes, detections=(), path=None, *, title=None, note=None) -> Figure:
    """The accumulator's two planes, as in the paper's Fig. 4.

    Left, *where*: the dx-dy plane (``planes.xy``): for each position of the
    pattern origin (image px), the highest vote over scale and rotation.
    Right, *what size and which way*: the scale-rotation plane
    (``planes.scale_angle``): for each scale and rotation, the highest vote
    over position. Heights (the colour bars) are votes per pattern point:
    the pattern's voting points that support a cell (each counts once per
    translation bin) over their number, summed over a 2 x 2 block of
    translation bins. 1.0 is as many votes as the pattern has points; the
    pooling (and, with polarity ``"either"``, both contrasts voting) lets a
    cell reach 4 (8), and a clear peak is often 1.5-3. They are not a
    detection's ``score``, the share (0-1) of the pattern's edges found at
    the refined pose. Detections are circled and numbered in both (labels
    of markers at the same place are stacked); with none, the highest cell
    is marked (a rejected peak). In the scale-rotation plane a detection's
    ring sits on the centre of the cell its peak comes from (see
    :func:`scale_angle_marker`): the refined pose may lie up to a cell away.

    Parameters
    ----------
    planes : AccumulatorPlanes or None
        ``SearchResult.planes`` from :meth:`seahough.Detector.search`; None
        (the search stopped before voting) draws a note instead.
    detections : list of Detection
    path : str or Path, optional
        Where to save the PNG.
    title : str, optional
        A line above both panels.
    note : str, optional
        Why there are no planes (``SearchResult.note``), for that note;
        default: the image has no edges.

    Returns
    -------
    matplotlib.figure.Figure
        1300 x 560 px.
    """
    fig = _figure(1300, 560)
    detections = list(detections or [])
    if title:
        fig.suptitle(title, fontsize=12, x=0.01, ha="left")
    if planes is None:
        ax = fig.add_axes([0, 0, 1, 1])
        ax.axis("off")
        why = note if note and note != "no edges" else \
            "the image has (almost) no edges to vote"
        ax.text(0.5, 0.5, f"no accumulator: {why}", ha="center", va="center", fontsize=16)
        return _finish(fig, path)
    top = 0.86 if title else 0.9
    ax1 = fig.add_axes([0.06, 0.1, 0.36, top - 0.1])
    cax1 = fig.add_axes([0.425, 0.1, 0.012, top - 0.1])
    ax2 = fig.add_axes([0.56, 0.1, 0.36, top - 0.1])
    cax2 = fig.add_axes([0.925, 0.1, 0.012, top - 0.1])
    xy = np.asarray(planes.xy, float)
    vmax = float(xy.max()) if xy.size and xy.max() > 0 else 1.0
    im = ax1.imshow(xy, extent=planes.extent, cmap="inferno", vmin=0, vmax=vmax,
                    interpolation="nearest", aspect="equal")
    cb = fig.colorbar(im, cax=cax1)
    cb.set_label(_VOTES)
    ax1.set_xlabel("x of pattern origin in the image (px)")
    ax1.set_ylabel("y of pattern origin in the image (px)")
    ax1.set_title("where: dx-dy plane (best over scale, rotation)", fontsize=11)

    sa = np.asarray(planes.scale_angle, float)
    ang = _display_angles(planes.angles)
    a_edges = _rotation_edges(planes)
    s_edges = _edges_from_centres(planes.scales, log=True, single_half=0.03)
    smax = float(sa.max()) if sa.size and sa.max() > 0 else 1.0
    mesh = ax2.pcolormesh(a_edges, s_edges, sa, cmap="inferno", vmin=0, vmax=smax, shading="flat")
    cb2 = fig.colorbar(mesh, cax=cax2)
    cb2.set_label(_VOTES)
    ax2.set_xlabel("rotation (degrees, counter-clockwise)")
    ax2.set_ylabel("scale (size relative to the pattern)")
    ax2.set_title("what size, which way: scale-rotation plane (best over position)", fontsize=11)
    ax2.set_xlim(a_edges[0], a_edges[-1])
    ax2.set_ylim(s_edges[0], s_edges[-1])

    marks1, marks2 = [], []
    for i, d in enumerate(detections):
        c = COLOURS[i % len(COLOURS)]
        a, sc = scale_angle_marker(planes, d.scale, d.angle)
        for ax, marks, px, py in ((ax1, marks1, d.x, d.y), (ax2, marks2, a, sc)):
            _ring(ax, px, py, c)
            marks.append((f"#{i + 1}", px, py, c))
    _place_peak_labels(ax1, marks1)
    _place_peak_labels(ax2, marks2)
    if not detections and xy.size and xy.max() > 0:
        r, c = np.unravel_index(int(np.argmax(xy)), xy.shape)
        ax1.plot([planes.x[c]], [planes.y[r]], "x", ms=14, mew=2.5, color="white")
        ax1.annotate("highest peak (rejected)", (planes.x[c], planes.y[r]), xytext=(10, 8),
                     textcoords="offset points", color="white", fontsize=10,
                     path_effects=_TEXT_OUTLINE)
        k, j = np.unravel_index(int(np.argmax(sa)), sa.shape)
        ax2.plot([ang[j]], [planes.scales[k]], "x", ms=14, mew=2.5, color="white", clip_on=False)
    return _finish(fig, path)


# ----------------------------------------------------------------------------- edges
def plot_edges(image, features, path=None, *, title=None) -> Figure:
    """What the detector saw: the working image, and its gradient magnitude
    with the chosen key points and the edge segments traced from them
    (the paper's Figs. 1-3), in working-image pixels. For tuning
    ``Config.n_keypoints``, ``min_gradient``, ``downscale`` and ``equalize``.

    Parameters
    ----------
    image : ndarray or path
        The photo the features were computed from (not read again: the
        working image is in ``features``).
    features : Features
        ``SearchResult.features`` (or :func:`seahough.core.features.extract_features`).
    path : str or Path, optional
        Where to save the PNG.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        1300 x 560 px.
    """
    if features is None:
        raise ValueError("plot_edges needs the search's features (SearchResult.features)")
    g = features.gradients
    mag = np.asarray(g.magnitude, float)
    h, w = mag.shape
    fig = _figure(1300, 560)
    top = 0.86
    ax1 = fig.add_axes([0.05, 0.1, 0.40, top - 0.1])
    ax2 = fig.add_axes([0.52, 0.1, 0.40, top - 0.1])
    cax = fig.add_axes([0.93, 0.1, 0.012, top - 0.1])
    ax1.imshow(g.image, cmap="gray", vmin=0, vmax=255)
    ax1.set_title(f"working image ({w} x {h} px, factor {g.factor:.2f})", fontsize=11)
    vmax = float(np.percentile(mag, 99.5)) if mag.size else 1.0
    # a flat image: a plain 0-1 scale rather than a 1e-6 one
    im = ax2.imshow(mag, cmap="gray", vmin=0, vmax=vmax if vmax >= 1.0 else 1.0)
    cb = fig.colorbar(im, cax=cax)
    cb.set_label("Scharr gradient magnitude (clipped at 99.5 %)")
    seg = features.segments
    n_seg = len(seg)
    if n_seg:
        lines = np.stack([np.stack([seg.x1, seg.y1], 1), np.stack([seg.x2, seg.y2], 1)], 1)
        ax2.add_collection(LineCollection(lines, colors="#00e5ff", linewidths=2.4, zorder=3,
                                          label=f"segments ({n_seg})"))
    kp = np.asarray(features.keypoints)
    if kp.size:
        ax2.scatter(features.edges.x[kp], features.edges.y[kp], s=3, c="#ff2d2d", lw=0,
                    label=f"key points ({kp.size})", zorder=4)
    for ax in (ax1, ax2):
        ax.set_xlim(-0.5, w - 0.5)
        ax.set_ylim(h - 0.5, -0.5)
        ax.set_xlabel("x (working px)")
        ax.set_ylabel("y (working px)")
    ax2.set_title(f"gradient magnitude, key points, segments ({len(features.edges)} edge points)",
                  fontsize=11)
    if n_seg or kp.size:
        leg = ax2.legend(loc="upper right", fontsize=9, framealpha=0.8, markerscale=3)
        leg.get_frame().set_facecolor("white")
    if title:
        fig.suptitle(title, fontsize=12, x=0.01, ha="left")
    return _finish(fig, path)


# ------------------------------------------------------------------------ trajectory
def _rows_of(rows_or_result):
    rows = getattr(rows_or_result, "rows", rows_or_result)
    return list(rows or [])


def _num(v):
    try:
        f = float(v)
    except (TypeError, ValueError):
        return math.nan
    return f


def plot_trajectory(rows_or_result, path=None, *, unit="px", truth=None, title=None) -> Figure:
    """The dead-reckoned path seen from above.

    Parameters
    ----------
    rows_or_result : OdometryResult or list of dict
        Rows with ``x``, ``y`` (position), ``heading`` (degrees) and
        ``flags``; ``x`` right and ``y`` down as in the first frame (so the
        path looks like the mosaic).
    path : str or Path, optional
        Where to save the PNG.
    unit : str
        Unit of ``x``, ``y`` for the axis labels (``"px"``, ``"m"``).
    truth : (N, 2) array, optional
        The true positions: a wide light grey band with a ring at each
        position, under the estimate (the estimate shows inside the band
        where both agree, and the band beside it where they do not).
    title : str, optional

    Notes
    -----
    The start is a green circle, the end a black square; frames with flags
    (a pair whose motion could not be measured or is doubtful) are red
    crosses; a few arrows show the heading (0 = up in the first frame,
    counter-clockwise positive as displayed).

    Returns
    -------
    matplotlib.figure.Figure
        900 x 800 px.
    """
    rows = _rows_of(rows_or_result)
    fig = _figure(900, 800)
    ax = fig.add_axes([0.1, 0.08, 0.86, 0.84])
    xs = np.array([_num(r.get("x")) for r in rows], float)
    ys = np.array([_num(r.get("y")) for r in rows], float)
    ok = np.isfinite(xs) & np.isfinite(ys)
    dist = float(np.nansum(np.hypot(np.diff(xs[ok]), np.diff(ys[ok])))) if ok.sum() > 1 else 0.0
    flagged = np.array([bool(r.get("flags")) for r in rows], bool)
    if truth is not None:
        t = np.asarray(truth, float).reshape(-1, 2)
        # under the estimate, wide and light, a ring at each true position: the
        # thin estimate shows inside it where both agree, beside it where not
        ax.plot(t[:, 0], t[:, 1], "-", color=TRUTH_COLOUR, lw=9, alpha=0.85,
                solid_capstyle="round", solid_joinstyle="round", zorder=1.5)
        ax.plot(t[:, 0], t[:, 1], "o", ms=9, mfc="none", mec="#5a5a5a", mew=1.2, zorder=1.6)
        ax.plot([], [], "-o", color=TRUTH_COLOUR, lw=6, ms=9, mfc="none", mec="#5a5a5a",
                label="truth")
    if ok.any():
        ax.plot(xs[ok], ys[ok], "-", color="#1f5fbf", lw=2.2, label="dead reckoning")
        ax.plot(xs[ok], ys[ok], ".", color="#1f5fbf", ms=6)
        i0 = int(np.flatnonzero(ok)[0]); i1 = int(np.flatnonzero(ok)[-1])
        ax.plot(xs[i0], ys[i0], "o", ms=12, color="#1aa442", mec="black", label="start", zorder=4)
        ax.plot(xs[i1], ys[i1], "s", ms=11, color="black", label="end", zorder=4)
        bad = flagged & ok
        if bad.any():
            ax.plot(xs[bad], ys[bad], "x", ms=11, mew=2.5, color="#e0001b",
                    label=f"flagged ({int(bad.sum())})", zorder=5)
        hd = np.array([_num(r.get("heading")) for r in rows], float)
        sel = np.flatnonzero(ok & np.isfinite(hd))
        if sel.size:
            sel = sel[:: max(1, int(math.ceil(sel.size / 12)))]
            span = max(np.ptp(xs[ok]), np.ptp(ys[ok]), 1e-9)
            L = 0.06 * span
            t = np.radians(hd[sel])
            # heading 0 = up (-y); positive turns counter-clockwise as displayed
            ax.quiver(xs[sel], ys[sel], -np.sin(t) * L, -np.cos(t) * L, angles="xy",
                      scale_units="xy", scale=1, color="#ff9500", width=0.004, zorder=3,
                      label="heading")
    else:
        ax.text(0.5, 0.5, "no positions", transform=ax.transAxes, ha="center", va="center",
                fontsize=20)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.grid(True, alpha=0.3)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit}, down as in the first frame)")
    if title is None:
        title = (f"dead-reckoned path: {len(rows)} frames, {dist:.1f} {unit} travelled, "
                 f"{int(flagged.sum())} flagged")
    ax.set_title(title, fontsize=12)
    if ok.any():
        ax.legend(loc="best", fontsize=9, framealpha=0.85)
    return _finish(fig, path)


# ---------------------------------------------------------------------------- mosaic
def save_mosaic(image, path) -> Path:
    """Write a mosaic (or any OpenCV image) to ``path`` (PNG, JPEG... by
    extension), creating the folder; returns the path.

    Raises
    ------
    OSError
        When OpenCV cannot write the file.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = np.clip(a, 0, 255).astype(np.uint8)
    if not cv2.imwrite(os.fspath(p), a):
        raise OSError(f"{p}: cannot write the image (unknown extension or unwritable folder)")
    return p
