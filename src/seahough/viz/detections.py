"""The picture of what a search found: the image with each detection's
outline, origin and label, the list of labels or a "not found" note, and
the pattern, laid out so that nothing covers the image's axes."""

from __future__ import annotations

import math

import cv2
import numpy as np
from matplotlib import patheffects
from matplotlib.figure import Figure
from matplotlib.offsetbox import AnchoredOffsetbox, TextArea, VPacker

from ..config import Config
from ..core.lines import visible_segment
from ..errors import ParameterError
from ._figure import COLOURS, DPI, _OUTLINE, _TEXT_OUTLINE, _as_display, _det_label, _figure, \
    _finish, _items, _line_ends, _set_title, _show, _text_size
from ._inset import _pattern_beside, _pattern_inset

_IMAGE_BOX = 900        # longer side of an image drawn by plot_detections, px
_MARGINS = (75, 25, 45, 55)   # left, right, bottom, top margins around it, px
_MIN_WIDTH = 560
#: Smallest height of the image box: a strip shorter than this when drawn
#: (e.g. 900 x 60) has its notes (list, "not found", pattern) below it.
_MIN_BOX_HEIGHT = 240
_UNDER_AXIS = 48        # px below a drawn image taken by its x ticks and label


#: Longest side of an image drawn at its own size (``max_width=0``): a
#: larger one is shrunk to it (a figure's memory, 4 bytes a pixel; Agg's
#: limit is 65,536 px a side).
_MAX_NATIVE = 8192


def _check_max_width(max_width):
    """``max_width`` as :func:`plot_detections` uses it: None (the default
    size), or a whole number of px >= 0 (0 and ``"native"``: the image's own).

    >>> _check_max_width(None), _check_max_width("native"), _check_max_width(1600.0)
    (None, 0, 1600)
    >>> _check_max_width(-1)
    Traceback (most recent call last):
    ...
    seahough.errors.ParameterError: max_width=-1: must be a whole number of px >= 0 \
(0 or "native": the image's own width), or None
    """
    if max_width is None:
        return None
    if isinstance(max_width, str) and max_width.strip().lower() == "native":
        return 0
    try:
        v = float(max_width)
        ok = not isinstance(max_width, (bool, str)) and v >= 0 and v == int(v)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ParameterError(f"max_width={max_width!r}: must be a whole number of px >= 0 "
                             f'(0 or "native": the image\'s own width), or None')
    return int(v)


def _drawn_image(h: int, w: int, max_width) -> tuple[int, int]:
    """``(width, height)`` in px at which an ``h`` x ``w`` image is drawn:
    900 px on its longer side (``max_width`` None), else ``max_width`` px
    wide when it is wider (its own width when not, or for 0), at most
    :data:`_MAX_NATIVE` px on its longer side."""
    if max_width is None:
        s = _IMAGE_BOX / max(h, w)
    else:
        s = min(1.0, max_width / w) if max_width > 0 else 1.0
        s = min(s, _MAX_NATIVE / max(h, w))
    return max(1, round(w * s)), max(1, round(h * s))


def detections_size(shape, *, max_width=None) -> tuple[int, int]:
    """PNG size ``(width, height)`` in px that :func:`plot_detections` makes
    for an image of ``shape`` (height, width, ...).

    The image is drawn 900 px on its longer side (by default), or at most
    ``max_width`` px wide (shrunk to it, never enlarged; 0: at its own
    width, up to 8192 px on its longer side), plus margins for the axes and
    title (75 + 25 px across, 45 + 55 px down), at least 560 px wide and
    with at least 240 px for the image and what goes under a short strip.

    Parameters
    ----------
    shape : tuple of int
        The image's ``(height, width)`` or ``(height, width, channels)``.
    max_width : int or "native", optional
        As for :func:`plot_detections`.

    Returns
    -------
    (int, int)
        Width and height of the PNG in px.

    Raises
    ------
    ParameterError
        When ``max_width`` is not None, ``"native"`` or a whole number >= 0.

    Examples
    --------
    >>> from seahough.viz import detections_size
    >>> detections_size((480, 640)), detections_size((60, 900)), detections_size((400, 40))
    ((1000, 775), (1000, 340), (560, 1000))
    >>> detections_size((2160, 3840), max_width=0), detections_size((2160, 3840), max_width=1920)
    ((3940, 2260), (2020, 1180))
    """
    h, w = int(shape[0]), int(shape[1])
    iw, ih = _drawn_image(h, w, _check_max_width(max_width))
    left, right, bottom, top = _MARGINS
    return max(_MIN_WIDTH, iw + left + right), max(ih, _MIN_BOX_HEIGHT) + bottom + top


def _draw_line(ax, d, colour, gray, w, h):
    """Draw line detection ``d``: each stretch seen along the object (its
    ``stretches``, its ``segment``, or :func:`~.core.lines.visible_segment`) as
    its two borders closed at the ends, and return them, ``(k, 2, 2)``; or,
    when none is found, its borders across the image (None)."""
    borders = [np.asarray(o, float).reshape(-1, 2) for o in d.outline]
    borders = [o[0] for o in borders if len(o) >= 2]
    a = math.radians(d.line_angle)
    nv = np.array([math.sin(a), math.cos(a)])
    half = 0.5 * abs(float(np.dot(borders[0] - borders[1], nv))) if len(borders) >= 2 else 0.0
    # the search's, reported in its records too (looked for there, on the image
    # searched: not again here, or the picture could show what the JSON does not)
    seg = getattr(d, "segment", None)
    if not hasattr(d, "segment") and gray is not None:
        seg = visible_segment(gray, d, Config().min_gradient)
    if seg is None:
        # the rope's borders (the centre line without them) across the image
        for bx, by in borders or [np.array([d.x, d.y])]:
            e = _line_ends(bx, by, d.line_angle, w, h)
            if e is not None:
                ax.plot([e[0][0], e[1][0]], [e[0][1], e[1][1]], color=colour, lw=1.8,
                        path_effects=_OUTLINE)
        return None
    parts = np.asarray(getattr(d, "stretches", None) or [seg], float)   # (buried: gaps)
    for a0, a1 in parts:
        band = np.array([a0 - half * nv, a1 - half * nv, a1 + half * nv, a0 + half * nv, a0 - half * nv])
        ax.plot(band[:, 0], band[:, 1], color=colour, lw=1.8, path_effects=_OUTLINE)
    return parts


def _nearest_on(parts, x, y) -> tuple[float, float]:
    """The point of the segments ``parts`` (each its two ends) nearest ``(x, y)``."""
    qs = []
    for a, b in np.asarray(parts, float).reshape(-1, 2, 2):
        ab = b - a
        qs.append(a + float(np.clip(np.dot((x, y) - a, ab) / max(np.dot(ab, ab), 1e-12), 0, 1)) * ab)
    q = min(qs, key=lambda q: float(np.hypot(*(q - (x, y)))))
    return float(q[0]), float(q[1])


def _place_label(ax, text, x, y, colour, w, h):
    """A boxed label just above (x, y), or below it near the image's top
    edge, centred on x and moved in from a side it would reach past (a sonar
    crop's label ran off its right edge)."""
    dy = 10 if y < 0.08 * h else -10
    va = "bottom" if dy < 0 else "top"
    half = 0.5 * (_text_size(ax.figure, text, **_LIST_TEXT)[0] + _LIST_PAD) * w / ax.bbox.width
    xs = float(np.clip(x, min(half, 0.5 * w), max(w - half, 0.5 * w)) - 0.5)
    ys = float(np.clip(y, 0.02 * h, 0.98 * h))
    ax.annotate(text, (xs, ys), xytext=(0, -dy), textcoords="offset points", ha="center", va=va,
                color=colour, fontsize=10, fontweight="bold", annotation_clip=False,
                bbox=dict(boxstyle="round,pad=0.25", fc="black", ec=colour, alpha=0.72, lw=1))


#: an outline drawn smaller than this (display px across its narrowest
#: strip or side, see :func:`_outline_style`) gets thin lines
_THIN_BELOW = 12.0
_THIN_OUTLINE = [patheffects.Stroke(linewidth=2.4, foreground="black", alpha=0.6),
                 patheffects.Normal()]


def _outline_style(outline, px_per_px: float):
    """(points, line width, path effects) of one polyline of a detection's
    outline as drawn: closed, with the usual thick line and its black
    border; or, drawn narrower than :data:`_THIN_BELOW` px (a small disc, a
    gate's strips a few px wide), which that line would cover, a thin line;
    and a long thin strip as its centre line alone (its two borders would
    be one solid bar over it)."""
    o = np.asarray(outline, float).reshape(-1, 2)
    if len(o) < 3:
        return o, 2.2, _OUTLINE
    (cx, cy), (rw, rh), ang = cv2.minAreaRect(o.astype(np.float32))
    closed = np.vstack([o, o[:1]])
    narrow, long = sorted((rw, rh))
    if narrow * px_per_px >= _THIN_BELOW:
        return closed, 2.2, _OUTLINE
    if long < 3.0 * max(narrow, 1e-9) or cv2.contourArea(o.astype(np.float32)) < 0.8 * rw * rh:
        return closed, 1.2, _THIN_OUTLINE     # (compact, or not a straight strip: an L, a U)
    t = np.radians(ang + (0.0 if rw >= rh else 90.0))
    half = 0.5 * long * np.array([np.cos(t), np.sin(t)])
    return np.array([[cx, cy] - half, [cx, cy] + half]), 1.2, _THIN_OUTLINE


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


#: font size of the "not found" note in an image corner (points, at most)
_CORNER_NOTE = 20


def _notes(fig, ax, items, pattern, corners, wh, box_wh, listed: bool = False):
    """The detection list (``items``: each line's text and colour), the "not
    found" note and the pattern inset. One item is left to the caller, who
    draws it beside its object, when it fits there (``listed``: a list of
    one all the same: a curve's numbers are not drawn beside it).

    In an image corner when they fit there; next to an image too narrow
    for them (the image is then drawn on the left and they go in the space
    on its right); else with the lines wrapped to fit inside the image.
    """
    left, _, bottom, _ = _MARGINS
    fw, fh = fig.get_size_inches() * fig.dpi
    dw, dh = _image_px(wh, box_wh)
    n = len(items)
    many = n > 1 or (n == 1 and listed)
    lw, lh = _list_size(fig, items) if items else (0.0, 0.0)
    nf_size = 30
    nf_w = _text_size(fig, "not found", fontsize=nf_size, fontweight="bold")[0] + 30
    if n == 1 and not many:
        inside = _fits_beside_object(fig, items[0][0], *wh, *box_wh)
    elif many:
        inside = lw <= 0.94 * dw and lh <= 0.6 * dh
    else:
        inside = nf_w <= 0.9 * dw
    x_side = left + dw + 14                     # the image drawn on the left
    side_w = fw - x_side - 8
    top_px = bottom + box_wh[1] / 2 + dh / 2    # the image's top edge
    if _short_strip(*wh, *box_wh):
        # the box is taller than the image: the image at the top, the notes under its x axis
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
    if n == 1 and not many and not inside:
        # no room beside the image: the label wrapped, in a free corner
        items = [(_wrap_label(fig, items[0][0], 0.94 * dw - _LIST_PAD), items[0][1])]
        _label_list(ax, items, corners[0])
        corners = corners[1:]
    elif many:
        if not inside:
            items = [(_wrap_label(fig, t, 0.94 * dw - _LIST_PAD), c) for t, c in items]
        _label_list(ax, items, corners[0])
        corners = corners[1:]
    elif n == 0:
        # in a corner (the second free one: the top left of an image without
        # detections), not over the middle of the picture, where the object a
        # user looks for usually is
        size = _CORNER_NOTE
        while size > 10 and _text_size(fig, "not found", fontsize=size,
                                       fontweight="bold")[0] + 30 > 0.45 * dw:
            size -= 2
        x, y, ha, va = {0: (0.02, 0.98, "left", "top"), 1: (0.98, 0.98, "right", "top"),
                        2: (0.98, 0.02, "right", "bottom"),
                        3: (0.02, 0.02, "left", "bottom")}[corners[1]]
        ax.text(x, y, "not found", transform=ax.transAxes, ha=ha, va=va,
                fontsize=size, fontweight="bold", color="white", path_effects=_TEXT_OUTLINE,
                bbox=dict(boxstyle="round,pad=0.4", fc="#b00020", ec="white", alpha=0.8))
        corners = [corners[0], *corners[2:]]     # (the pattern where it goes when found)
    if pattern is not None:
        _pattern_inset(ax, pattern, corners[0], (dw, dh))


def _notes_below(fig, items, pattern, top_left, width, nf_size):
    """The detection list (or "not found") and the pattern, side by side,
    their tops at ``top_left`` (figure px), within ``width`` px.

    A short strip leaves at least 97 px under its axis (see
    :func:`_short_strip`), room for the note at ``nf_size`` (2.3 lines of 30
    points: 96 px)."""
    fw, fh = fig.get_size_inches() * fig.dpi
    x, y = top_left
    room = y - 8                                  # px down to the figure's bottom
    if items:
        items = [(_wrap_label(fig, t, width - _LIST_PAD - 150), c) for t, c in items]
        _label_list(fig.axes[0], items, at=(x / fw, y / fh))
        x += _list_size(fig, items)[0] + 14
    else:
        pad = 0.4 * nf_size * DPI / 72
        fig.text((x + pad) / fw, (y - pad) / fh, "not found", ha="left", va="top",
                 fontsize=nf_size, fontweight="bold", color="white", path_effects=_TEXT_OUTLINE,
                 bbox=dict(boxstyle="round,pad=0.4", fc="#b00020", ec="white", alpha=0.8))
        x += _text_size(fig, "not found", fontsize=nf_size, fontweight="bold")[0] + 2 * pad + 14
    if pattern is not None:
        ph, pw = pattern.image.shape
        side = max(min(room - 16, width - (x - top_left[0])), 8.0)  # 16: the title above it
        _pattern_beside(fig, pattern, x, y, side if pw >= ph else side * pw / ph)


def colours(detections, patterns=None) -> list:
    """Each detection's colour: by its pattern's when they name several (in
    the order the patterns first appear), or when ``patterns`` (the names of
    a search's patterns) gives the order: the same colour for a pattern in
    every image, even one where it alone was found; else by its rank.

    >>> from types import SimpleNamespace as D
    >>> colours([D(pattern="gate"), D(pattern="buoy"), D(pattern="gate")]) == [
    ...     COLOURS[0], COLOURS[1], COLOURS[0]]
    True
    >>> colours([D(pattern="buoy"), D(pattern="buoy")], ["gate", "buoy"]) == [COLOURS[1]] * 2
    True
    """
    names = list(patterns or ())
    names += [n for n in dict.fromkeys(getattr(d, "pattern", "") for d in detections)
              if n not in names]
    if len(names) > 1:
        return [COLOURS[names.index(getattr(d, "pattern", "")) % len(COLOURS)]
                for d in detections]
    return [COLOURS[i % len(COLOURS)] for i in range(len(detections))]


def _cross_size(ax, d, is_line: bool, wh, box_wh) -> float:
    """The origin's "+" in points: 16, or less on an object drawn smaller
    than it (a small buoy's circle must show around it); ``wh`` the image's
    size, ``box_wh`` the box it is drawn in (px)."""
    if is_line or not d.outline:
        return 16.0
    pts = np.vstack([np.asarray(o, float).reshape(-1, 2) for o in d.outline])
    extent = float(min(np.ptp(pts[:, 0]), np.ptp(pts[:, 1])))
    px_per_unit = _image_px(wh, box_wh)[0] / max(wh[0], 1)
    return float(np.clip(0.6 * extent * px_per_unit * 72.0 / ax.figure.dpi, 6.0, 16.0))


def _image_figure(image, max_width, bit_depth=None):
    """The figure of an image drawn as :func:`plot_detections` draws it:
    ``(fig, ax, disp, colour, (w, h), (iw, ih))``, ``(iw, ih)`` the image
    box in px."""
    max_width = _check_max_width(max_width)
    disp, colour = _as_display(image, bit_depth)
    h, w = disp.shape[:2]
    fw, fh = detections_size((h, w), max_width=max_width)
    fig = _figure(fw, fh)
    left, right, bottom, top = _MARGINS
    iw, ih = fw - left - right, fh - bottom - top
    ax = fig.add_axes([left / fw, bottom / fh, iw / fw, ih / fh])
    _show(ax, disp, colour, (iw, ih))
    return fig, ax, disp, colour, (w, h), (iw, ih)


def _draw_blank(ax, box, side: str, text: str) -> None:
    """A region the search left out (a caption's box, a region of ``Config.
    ignore``: x0, y0, x1, y1), dashed, with ``text`` beside it on the
    picture's side (``side``: the image edge it touches, or "")."""
    x0, y0, x1, y1 = (v - 0.5 for v in box)
    ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.85", lw=1.2, ls=(0, (4, 3)),
            path_effects=_THIN_OUTLINE)
    # beside the box, on the picture's side (on it, neither could be read: a user trial)
    my = 0.5 * (y0 + y1)
    x, y, ha, va = {"top": (x0, y1 + 1, "left", "top"), "bottom": (x0, y0 - 1, "left", "bottom"),
                    "left": (x1 + 1, my, "left", "center"),
                    "right": (x0 - 1, my, "right", "center")}.get(side, (x0, y1 + 1, "left",
                                                                          "top"))
    ax.text(x, y, text, color="0.95", fontsize=7, ha=ha, va=va, clip_on=True,
            path_effects=_THIN_OUTLINE)


def plot_detections(image, detections, path=None, *, pattern=None, title=None,
                    max_width=None, bit_depth=None, blanks=None, patterns=None) -> Figure:
    """The image with each detection's outline, origin and numbers.

    Parameters
    ----------
    image : ndarray or path
        The searched image: BGR/BGRA (shown in its colours) or grey; one
        larger than drawn (900 px on its longer side) is shrunk to that size
        by an area average before it is drawn.
    detections : list of Detection
        From :meth:`seahough.Detector.detect`; best first. Objects are drawn
        with their closed outline; lines (``kind == "line"``) as the
        segment along the object that the image shows (both borders of the
        band, edges across ``line_angle`` through ``(x, y)``, closed at the
        ends where the visible part stops), or as their two borders across
        the whole image when that cannot be found; a line's "+" is put on
        the drawn segment, at the point of the line nearest its ``(x, y)``
        (a line's position along itself is not measured: its ``x, y`` may
        lie beyond the visible part, where the accumulator picture rings
        it). Each gets a label
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
        Shown as a small inset in the image corner farthest from the
        detections (or beside a narrow image), with a "+" on its origin: a
        shape pattern drawn from its outline (filled lightly, stroked), one
        made from an image as that image (with its mask's outline).
    title : str, optional
        Default: how many detections were found.
    max_width : int or "native", optional
        Draw the image at most this many px wide: a wider one is shrunk to
        it, a narrower one drawn at its own size; 0 or ``"native"``: at its
        own width (pixel for pixel, up to 8192 px on its longer side), e.g.
        to look closely at a 4K photo. Default (None): 900 px on its longer
        side, whatever its size.
    bit_depth : int, optional
        A uint16 image's significant bits, as the search read it
        (:attr:`seahough.Config.bit_depth`: a 12-bit camera's frames are
        otherwise drawn 16 times too dark).
    blanks : Blanks, optional
        What the search filled before it looked (``SearchResult.blanks``):
        each burned-in caption's box and each region of ``Config.ignore`` is
        drawn dashed, "caption, not searched" or "ignored, not searched" (an
        object under it could not be found); no data beyond the picture too.
    patterns : list of str, optional
        The names of a search's patterns (``list(detector.parts)``): each
        pattern's colour then stays the same in every image.

    Returns
    -------
    matplotlib.figure.Figure
        :func:`detections_size` px (1000 x 775 for a 640 x 480 image).

    Raises
    ------
    ParameterError
        When ``max_width`` is not None, ``"native"`` or a whole number >= 0.

    Examples
    --------
    >>> import numpy as np, seahough
    >>> from seahough.viz import plot_detections
    >>> img = np.full((120, 160), 40, np.uint8)
    >>> img[40:70, 50:100] = 220                      # a bright 50 x 30 box
    >>> pattern = seahough.Pattern.rectangle(50, 30)
    >>> found = seahough.Detector(pattern, max_results=1).detect(img)
    >>> fig = plot_detections(img, found, pattern=pattern)   # path=...: also a PNG
    >>> tuple(int(v) for v in fig.get_size_inches() * fig.dpi)
    (1000, 775)
    """
    detections = _items("detections", detections, "Detection", ("x", "y", "kind", "outline"),
                        "from Detector.detect")
    fig, ax, disp, colour, (w, h), (iw, ih) = _image_figure(image, max_width, bit_depth)
    gray = None
    if any(d.kind == "line" for d in detections):
        gray = cv2.cvtColor(disp, cv2.COLOR_RGB2GRAY) if colour else disp
    ax.set_xlabel("x (px)")
    ax.set_ylabel("y (px)")
    anchors = []
    left_out = [] if blanks is None else (
        [((c.x0, c.y0, c.x1, c.y1), c.side, "caption, not searched") for c in blanks.captions]
        + [(b, "bottom" if b[3] >= h else "top" if b[1] <= 0 else "right" if b[2] >= w else
            "left" if b[0] <= 0 else "", "ignored, not searched") for b in blanks.ignored])
    for box, side, text in left_out:
        _draw_blank(ax, box, side, text)     # (and kept free of the labels, as an object is)
        anchors.append(np.array([box[:2], box[2:]], float))
    if getattr(blanks, "no_data", None) is not None:   # (black beyond a sonar's fan: filled)
        ax.contour(blanks.no_data.view(np.uint8), [0.5], colors="0.85", linestyles="dashed")
    for i, (d, c) in enumerate(zip(detections, colours(detections, patterns))):
        is_line = d.kind == "line"
        seg = None
        if is_line and d.line_angle is not None:
            seg = _draw_line(ax, d, c, gray, w, h)
        else:
            for o in d.outline:
                o, lw, effects = _outline_style(o, iw / w)
                ax.plot(o[:, 0], o[:, 1], color=c, lw=lw, path_effects=effects)
        # (a line's "+" on the segment the image shows, nearest its reported point:
        # that point, the line's nearest the image centre, may lie in open water)
        cx, cy = _nearest_on(seg, d.x, d.y) if seg is not None else (d.x, d.y)
        ax.plot([cx], [cy], marker="+", ms=_cross_size(ax, d, is_line, (w, h), (iw, ih)),
                mew=2.5, color=c, path_effects=_OUTLINE)
        if seg is not None:                 # its label on the segment, nearest the centre
            anchors.append(seg.reshape(-1, 2))
            lx, ly = _nearest_on(seg, d.x, d.y)
        elif is_line:                       # at the point nearest the centre
            anchors.append(np.array([[d.x, d.y]]))
            lx, ly = d.x, d.y
        else:                               # above the outline's top, centred on it
            pts = np.vstack([np.asarray(o, float).reshape(-1, 2) for o in d.outline]) \
                if d.outline else np.array([[d.x, d.y]])
            anchors.append(pts)
            lx, ly = float(np.mean(pts[:, 0])), float(pts[:, 1].min())
        if len(detections) == 1:
            if _fits_beside_object(fig, _det_label(d), w, h, iw, ih):
                _place_label(ax, _det_label(d), lx, ly, c, w, h)
        else:
            _place_label(ax, f"#{i + 1}", lx, ly, c, w, h)
    corners = _free_corners(np.vstack(anchors) if anchors else np.empty((0, 2)), w, h)
    n = len(detections)
    items = [((f"#{i + 1} " if n > 1 else "") + _det_label(d), c)
             for i, (d, c) in enumerate(zip(detections, colours(detections, patterns)))]
    _notes(fig, ax, items, pattern, corners, (w, h), (iw, ih))
    if title is None:
        n = len(detections)
        title = "pattern not found" if n == 0 else f"{n} detection{'s' if n > 1 else ''}"
    _set_title(fig, ax, title)
    return _finish(fig, path)

