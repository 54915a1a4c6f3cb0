"""The pattern drawn beside a detection picture: a shape from its outline
(filled lightly and stroked, holes and open strips kept), an image pattern
as its image with its mask's outline."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import PathPatch
from matplotlib.path import Path as MplPath

from ._figure import COLOURS, _TEXT_OUTLINE, _imshow, _pattern_picture

#: Pattern kinds drawn from their outline (a shape), not from their image.
_SHAPE_KINDS = ("rectangle", "line", "polygon", "circle", "ring", "ellipse", "polyline")
#: Behind a shape: the grey of a shape pattern's background (30).
_SHAPE_BACK = "#1e1e1e"


def _area(o) -> float:
    """Signed area of polygon ``o`` (positive: counter-clockwise in x, y)."""
    return 0.5 * float(np.sum(o[:, 0] * np.roll(o[:, 1], -1) - np.roll(o[:, 0], -1) * o[:, 1]))


def _shape_path(pattern) -> MplPath:
    """The shape's area as one path: its outline's closed polygons, a
    polygon inside an odd number of others a hole (a ring's, a closed
    polyline's), turned against the rest (matplotlib fills non-zero
    winding); a line's band between its two borders.

    >>> from seahough import Pattern
    >>> outer, hole = _shape_path(Pattern.circle(20, 10)).to_polygons()   # a ring
    >>> bool(_area(outer) > 0), bool(_area(hole) < 0)
    (True, True)
    """
    polys = [np.asarray(o, float).reshape(-1, 2) for o in pattern.outline]
    if not pattern.closed:                   # a line: its two borders, ends open
        ends = [o[[0, -1]] for o in polys if len(o) >= 2]
        polys = [np.vstack([ends[0], ends[1][::-1]])] if len(ends) >= 2 else []
    polys = [o for o in polys if len(o) >= 3]
    verts, codes = [], []
    for i, o in enumerate(polys):
        depth = sum(MplPath(q).contains_point(o[0]) for j, q in enumerate(polys) if j != i)
        if (_area(o) > 0) == (depth % 2 == 1):
            o = o[::-1]
        verts += [*o, o[0]]
        codes += [MplPath.MOVETO] + [MplPath.LINETO] * (len(o) - 1) + [MplPath.CLOSEPOLY]
    return MplPath(np.array(verts).reshape(-1, 2), codes or None)


def _is_border(outline, w, h) -> bool:
    """Is ``outline`` only the pattern image's border (an image without a mask)?"""
    return len(outline) == 1 and len(outline[0]) == 4 and np.allclose(
        np.sort(outline[0], axis=0), [(0, 0), (0, 0), (w - 1, h - 1), (w - 1, h - 1)])


def _draw_pattern(ins, pattern, box_px):
    """The pattern in the axes ``ins`` (``box_px``, its size in px), titled,
    in pattern-image pixels, with a "+" on its origin: a shape (rectangle,
    line, polygon, circle, ring, polyline) drawn from its outline, filled
    lightly and stroked, so that a thin or open one reads at any size (its
    image shrunk to an inset can be a dark box); a line's two borders
    stroked, its ends open. A pattern made from an image shows the image
    (a larger one shrunk to the box first), with its mask's outline."""
    ph, pw = pattern.image.shape
    colour = COLOURS[0]
    if pattern.kind in _SHAPE_KINDS:
        ins.set_facecolor(_SHAPE_BACK)
        ins.add_patch(PathPatch(_shape_path(pattern), fc=(1, 1, 1, 0.45), ec="none"))
        lines = [np.asarray(o, float).reshape(-1, 2) for o in pattern.outline]
    else:
        picture, kw = _pattern_picture(pattern)
        _imshow(ins, picture, box_px, **kw)
        lines = [] if _is_border(pattern.outline, pw, ph) else \
            [np.asarray(o, float).reshape(-1, 2) for o in pattern.outline]
    for o in lines:
        if pattern.closed and len(o) > 2:
            o = np.vstack([o, o[:1]])
        ins.plot(o[:, 0], o[:, 1], color=colour, lw=1.6, solid_joinstyle="miter")
    ins.plot([pattern.origin[0]], [pattern.origin[1]], marker="+", ms=9, mew=1.6, color=colour)
    ins.set_xlim(-0.5, pw - 0.5)
    ins.set_ylim(ph - 0.5, -0.5)
    ins.set_aspect("equal")
    ins.set_xticks([]); ins.set_yticks([])
    for s in ins.spines.values():
        s.set_color("white"); s.set_linewidth(1.5)
    ins.set_title("pattern", color="white", fontsize=9, pad=2,
                  path_effects=_TEXT_OUTLINE)
    return ins


def _pattern_inset(ax, pattern, corner: int, ax_px):
    """The pattern in an inset of at most a fifth of ``ax`` (drawn ``ax_px``
    = (width, height) px) in an image corner (0 TL, 1 TR, 2 BR, 3 BL)."""
    size = 0.2
    pos = {0: (0.015, 0.955 - size), 1: (0.985 - size, 0.955 - size),
           2: (0.985 - size, 0.015), 3: (0.015, 0.015)}[corner]
    ph, pw = pattern.image.shape
    aspect = pw / ph
    bw, bh = (size, size / aspect) if aspect >= 1 else (size * aspect, size)
    x0 = pos[0] + (size - bw if corner in (1, 2) else 0)
    y0 = pos[1] + (size - bh if corner in (0, 1) else 0)
    return _draw_pattern(ax.inset_axes([x0, y0, bw, bh]), pattern,
                         (bw * ax_px[0], bh * ax_px[1]))


def _pattern_beside(fig: Figure, pattern, x0: float, y_top: float, max_w: float):
    """The pattern in a box of at most ``max_w`` (and 140) px, its top left at
    (``x0``, ``y_top``) figure px (room left above for its title)."""
    ph, pw = pattern.image.shape
    side = min(max_w, 140.0)
    bw, bh = (side, side * ph / pw) if pw >= ph else (side * pw / ph, side)
    fw, fh = fig.get_size_inches() * fig.dpi
    y0 = y_top - 16 - bh
    return _draw_pattern(fig.add_axes([x0 / fw, y0 / fh, bw / fw, bh / fh]), pattern, (bw, bh))
