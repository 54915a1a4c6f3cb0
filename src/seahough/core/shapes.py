"""Shapes drawn as patterns: a polyline of strips (a gate frame, a chevron),
and the disc, ring and line of :meth:`~seahough.Pattern.circle` and
:meth:`~seahough.Pattern.line` (the rectangle and polygon are in
:mod:`.pattern`).

A strip ``width`` px wide runs along every segment of the polyline; the
segments meet in mitred corners (square for a right angle, bevelled when
the mitre would be longer than :data:`MITRE_LIMIT` widths, as SVG does) and
the two ends are cut square at the first and last points. The union of the
strips is drawn on a finer raster: traced, it gives the pattern's outline
(closed boundary polygons); averaged down, each pixel's level (30 to 230,
as the other shapes) by the area of it the strips cover.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from ..errors import ParameterError, PatternError

#: A corner's mitre longer than this many strip widths is bevelled (SVG's default).
MITRE_LIMIT = 4.0
#: The strips are traced on a raster this many times finer than the pattern's
#: pixels (fewer for a large shape: at most _MAX_FINE px a side).
_FINE = 8
_MAX_FINE = 8192


#: The sharpest turn of a polyline, degrees (a chevron's tip of 10 degrees):
#: beyond it the strips before and after lie on each other.
MAX_TURN = 170.0


def xy_pairs(points, what: str = "points={!r}") -> np.ndarray:
    """``points`` as an (n, 2) float array: (x, y) pairs, or an OpenCV
    contour's (n, 1, 2); else a ParameterError saying the shape it got (an
    archaeologist's contour was refused as "expected (x, y) pairs" with the
    whole array printed).

    >>> xy_pairs(np.zeros((5, 1, 2), np.int32)).shape
    (5, 2)
    >>> xy_pairs(np.zeros((2, 20)))
    Traceback (most recent call last):
    seahough.errors.ParameterError: points (an array of shape (2, 20)): expected (x, y) pairs, an (n, 2) array (or an OpenCV contour, (n, 1, 2))
    """
    bare = what.split("{")[0].rstrip("= ")       # (what without the value)
    if isinstance(points, np.ndarray):
        name = f"{bare} (an array of shape {points.shape})"
    else:
        name = what.format(points) if len(repr(points)) <= 80 else bare
    try:
        pts = np.asarray(points, float)
    except (TypeError, ValueError):
        raise ParameterError(f"{name}: expected (x, y) pairs of numbers") from None
    if pts.ndim == 3 and pts.shape[1:] == (1, 2):
        pts = pts.reshape(-1, 2)
    if pts.ndim != 2 or pts.shape[1] != 2:   # ((x, y, z) rows were re-paired)
        raise ParameterError(f"{name}: expected (x, y) pairs, an (n, 2) array (or an OpenCV "
                             "contour, (n, 1, 2))")
    return pts


def _points(points) -> np.ndarray:
    """The polyline's points as an (n, 2) float array, consecutive repeats
    dropped (a ParameterError naming ``points`` when there is no polyline)."""
    pts = xy_pairs(points)
    if not np.isfinite(pts).all():
        raise ParameterError("points: the polyline's coordinates must be finite")
    if pts.shape[0] >= 2:   # (points under half a pixel apart are one: jitter turns back)
        keep = [0]
        for i in range(1, pts.shape[0]):
            if np.hypot(*(pts[i] - pts[keep[-1]])) >= 0.5:
                keep.append(i)
        pts = pts[keep]
    if pts.shape[0] < 2:
        raise ParameterError("points: a polyline needs at least 2 distinct (x, y) points")
    d = np.diff(pts, axis=0)
    turn = np.degrees(np.abs(np.arctan2(d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0],
                                        (d[:-1] * d[1:]).sum(axis=1))))
    if (turn > MAX_TURN).any():
        i = int(np.argmax(turn > MAX_TURN)) + 1
        raise ParameterError(f"points: the polyline turns back on itself at point {i} "
                             f"({pts[i, 0]:g}, {pts[i, 1]:g}), by {turn[i - 1]:.0f} degrees (at "
                             f"most {MAX_TURN:g}: its two strips would lie on each other)")
    return pts


def vertices(points, min_size: float) -> np.ndarray:
    """A polygon's vertices as an (n, 2) array moved to (0, 0), checked: at
    least 3 finite (x, y) pairs ((x, y, z) rows were re-paired into another
    polygon), some area, ``min_size`` px across at its narrowest."""
    pts = xy_pairs(points, "polygon points {!r}")
    if pts.shape[0] < 3 or not np.isfinite(pts).all():
        raise ParameterError("polygon needs at least 3 finite (x, y) vertices")
    pts = pts - pts.min(axis=0)
    area = 0.5 * abs(np.sum(pts[:, 0] * np.roll(pts[:, 1], -1) - np.roll(pts[:, 0], -1) * pts[:, 1]))
    if area < 4.0:
        raise PatternError("polygon encloses (almost) no area")
    across = min(cv2.minAreaRect(pts.astype(np.float32))[1])  # its narrower side
    if across < min_size:
        raise ParameterError(f"polygon points: {across:.3g} px across at its narrowest: must "
                             f"be at least {min_size:g} px")
    return pts


def _lying_on_each_other(pts: np.ndarray, width: float):
    """The first two strips that are not neighbours and lie on each other
    (nearly parallel, under ``width`` apart, side by side for more than a
    width: a hairpin of two right angles), as ``(i, j)`` segment indices, or
    None. Strips that merely cross are allowed."""
    for i in range(len(pts) - 1):
        a0, a1 = pts[i], pts[i + 1]
        u = (a1 - a0) / np.hypot(*(a1 - a0))
        for j in range(i + 2, len(pts) - 1):
            b0, b1 = pts[j], pts[j + 1]
            v = (b1 - b0) / np.hypot(*(b1 - b0))
            if abs(u @ v) < math.cos(math.radians(30.0)):
                continue
            n = np.array([-u[1], u[0]])
            if max(abs((b0 - a0) @ n), abs((b1 - a0) @ n)) >= width:
                continue
            t = sorted(((b0 - a0) @ u, (b1 - a0) @ u))
            if min(t[1], np.hypot(*(a1 - a0))) - max(t[0], 0.0) > width:
                return i, j
    return None


def strip_polygons(points, width: float, mitre_limit: float = MITRE_LIMIT) -> list[np.ndarray]:
    """The polygons whose union is the strip: one rectangle per segment and
    one corner piece (mitre, or bevel beyond ``mitre_limit``) per turn.

    Examples
    --------
    A right-angled bend of a strip 2 px wide: two rectangles, and the square
    corner piece that fills the outside of the bend.

    >>> right, down, corner = strip_polygons([(0, 0), (10, 0), (10, 10)], 2)
    >>> right.tolist(), corner.tolist()
    ([[0.0, 1.0], [10.0, 1.0], [10.0, -1.0], [0.0, -1.0]], [[10.0, 0.0], [10.0, -1.0], [11.0, -1.0], [11.0, 0.0]])
    """
    pts = np.asarray(points, float)
    h = 0.5 * float(width)
    d = np.diff(pts, axis=0)
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    n = np.stack([-d[:, 1], d[:, 0]], 1)             # each segment's normal
    polys = [np.array([a + h * m, b + h * m, b - h * m, a - h * m])
             for a, b, m in zip(pts[:-1], pts[1:], n)]
    for i in range(1, len(pts) - 1):
        v, na, nb = pts[i], n[i - 1], n[i]
        turn = float(np.dot(d[i], na))                # > 0: turns towards +na
        if abs(turn) < 1e-12:
            continue                                  # straight on, or straight back
        s = -math.copysign(h, turn)                   # the outer side's offset
        c = float(np.dot(na, nb))
        corner = [v, v + s * na]
        if 1.0 + c > 1e-12 and math.sqrt(2.0 / (1.0 + c)) <= mitre_limit:
            corner.append(v + s * (na + nb) / (1.0 + c))   # the outer borders meet here
        corner.append(v + s * nb)
        polys.append(np.array(corner))
    return polys


def fineness(shape) -> int:
    """How many times finer than a canvas of ``shape`` its shapes are drawn
    (:data:`_FINE`, fewer for a large canvas)."""
    return max(1, min(_FINE, _MAX_FINE // max(shape)))


def _raster(polys, shape, fine: int) -> np.ndarray:
    """The union of ``polys`` (canvas pixels) on a uint8 raster ``fine``
    times finer than a canvas of ``shape`` (255 inside)."""
    h, w = shape
    raster = np.zeros((h * fine, w * fine), np.uint8)
    # canvas pixel i holds fine pixels fine * i ... fine * i + fine - 1, so x
    # is drawn at fine * (x + 0.5) - 0.5 (8 bits of sub-pixel), and a traced
    # fine pixel j is x = j / fine - 0.5: both borders of a strip within 1 / fine
    for p in polys:
        q = np.round(((np.asarray(p) + 0.5) * fine - 0.5) * 256).astype(np.int32)
        cv2.fillPoly(raster, [q.reshape(-1, 1, 2)], 255, lineType=cv2.LINE_8, shift=8)
    return raster


def _area(raster: np.ndarray, shape) -> np.ndarray:
    """A fine raster (:func:`_raster`) as the share of each canvas pixel it
    covers. cv2 fills both ends of every run (a span from 51.5 to 531.5: 52
    to 532): one fine pixel too many along each row and column, taken off
    their ends first."""
    raster = cv2.erode(raster, np.ones((2, 2), np.uint8), anchor=(0, 0),
                       borderType=cv2.BORDER_CONSTANT, borderValue=0)
    return cv2.resize(raster.astype(np.float32) / 255.0, (shape[1], shape[0]),
                      interpolation=cv2.INTER_AREA)


def coverage(polys, shape) -> np.ndarray:
    """The share of each pixel of a canvas of ``shape`` that the union of
    ``polys`` (canvas pixels: pixel i spans [i - 0.5, i + 0.5]) covers, 0-1
    (exact within 1 / :func:`fineness` px). cv2's anti-aliased fill widens a
    shape by about 0.7 px a side: a 60 px rectangle drawn so was found at
    scale 0.973 on a 60 px box.

    >>> c = coverage([np.array([(2, 0), (6, 0), (6, 3), (2, 3)], float)], (4, 9))
    >>> c[1].round(2).tolist(), round(float(c.sum()), 2)      # 4 x 3 px
    ([0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 0.5, 0.0, 0.0], 12.0)
    """
    return _area(_raster(polys, shape, fineness(shape)), shape)


def fill(img: np.ndarray, polys, value: float) -> None:
    """Paint ``value`` over the uint8 ``img`` by the area of each pixel that
    ``polys`` cover (:func:`coverage`), in place."""
    c = coverage(polys, img.shape)
    img[...] = np.round(img * (1.0 - c) + float(value) * c).astype(np.uint8)


def _draw(polys, shape, fine: int):
    """The union of ``polys`` (canvas pixels) drawn on a raster ``fine``
    times finer: its coverage of each canvas pixel (0-1, the exact area
    within 1 / fine px a side), and its outer boundaries and holes traced
    as polygons in canvas pixels."""
    raster = _raster(polys, shape, fine)
    cs, hier = cv2.findContours(raster, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    outer, holes = [], []
    for c, (_, _, _, parent) in zip(cs, hier[0] if hier is not None else []):
        c = cv2.approxPolyDP(c, 1.5, True).reshape(-1, 2)   # (straightens the steps)
        if len(c) < 3:
            continue
        (outer if parent < 0 else holes).append(c / fine - 0.5)
    return _area(raster, shape), outer, holes


def polyline(cls, points, width, *, polarity="bright", margin=6.0):
    """An open polyline of strips ``width`` px wide: a gate frame (two posts
    and a bar), a chevron, a bent bracket.

    Parameters
    ----------
    points : sequence of (x, y)
        The strips' centre line, at least 2 points (any units of pixels; only
        their shape matters).
    width : float
        The strips' width in pixels (at least 1).
    polarity : {"bright", "dark", "either"}
        ``"bright"``: bright strips on a darker background.
    margin : float
        Background pixels around the shape in the pattern image.

    Returns
    -------
    Pattern
        ``kind="polyline"``. Its edges are the strips' borders: both sides of
        every strip and the two square ends. Corners are mitred (square for a
        right angle; bevelled beyond a mitre :data:`MITRE_LIMIT` widths long).
        The origin (what ``Detection.x, y`` report) is the centre of the
        points' bounding box; ``polyline_points`` holds the centre line and
        ``polyline_width`` the width, in pattern-image pixels. The outline
        is the strips' boundary (closed polygons), drawn around the object.

    Examples
    --------
    >>> from seahough import Pattern
    >>> gate = Pattern.polyline([(0, 80), (0, 0), (60, 0), (60, 80)], 6)  # posts and bar
    >>> gate.kind, gate.image.shape, gate.origin
    ('polyline', (96, 79), (39.0, 49.0))
    >>> gate.polyline_points[0].tolist(), int(gate.image[49, 39]), int(gate.image[49, 9])
    ([9.0, 89.0], 30, 230)
    """
    from .pattern import _check_polarity, _check_positive

    pts = _points(points)
    _check_positive(width=width)
    W = float(width)
    both = _lying_on_each_other(pts, W)
    if both is not None:
        i, j = both
        raise ParameterError(f"points: the strips from point {i} and from point {j} lie on each "
                             f"other (nearly parallel, under width={W:g} apart)")
    if float(np.hypot(*np.diff(pts, axis=0).T).sum()) < 1.0:
        raise ParameterError("points: the polyline must be at least 1 px long")
    _check_polarity(polarity)
    polys = strip_polygons(pts, W)
    allv = np.vstack(polys)
    lo = allv.min(axis=0)
    w, h = allv.max(axis=0) - lo
    img, m = cls._canvas(w, h, margin)
    shift = m - lo
    polys = [p + shift for p in polys]
    cover, outer, holes = _draw(polys, img.shape, fineness(img.shape))
    # drawn by its area on each pixel, as every shape (:func:`coverage`)
    img = np.round(30.0 + 200.0 * cover).astype(np.uint8)
    pts = pts + shift
    origin = tuple(float(v) for v in 0.5 * (pts.min(axis=0) + pts.max(axis=0)))
    p = cls(img, None, origin, polarity=polarity, kind="polyline", outline=outer + holes,
            closed=True)
    p.polyline_points, p.polyline_width = pts, W
    return p


# ------------------------------------------- primitive shapes (Pattern.circle, .line)
def circle(cls, radius, inner_radius=None, *, polarity="bright", margin=6.0):
    """A filled disc, or a ring when ``inner_radius`` is given.

    A ring is not reported where its inner circle is not seen (a disc the
    size of its outer one matches 62 % of its points):
    ``Config(search=SearchTuning(hole_support=...))``, 0 to report it.
    """
    from .pattern import MIN_SHAPE_SIZE, _check_positive
    _check_positive(radius=radius)
    r = float(radius)
    holes = ()
    kind = "circle"
    if inner_radius is not None:
        _check_positive(inner_radius=inner_radius)
        if not float(inner_radius) < r:
            raise ParameterError(f"inner_radius={inner_radius!r} must be smaller than radius={r}")
        if r - float(inner_radius) < MIN_SHAPE_SIZE:
            raise ParameterError(f"inner_radius={inner_radius!r}: the ring (radius={r:g}) must "
                                 f"be at least {MIN_SHAPE_SIZE:g} px thick")
        kind = "ring"
    t = np.linspace(0, 2 * np.pi, max(32, int(2 * np.pi * r)), endpoint=False)
    outer = np.stack([r + r * np.cos(t), r + r * np.sin(t)], 1)
    if inner_radius is not None:
        ri = float(inner_radius)
        holes = (np.stack([r + ri * np.cos(t), r + ri * np.sin(t)], 1),)
    return cls._shape([outer], 2 * r, 2 * r, margin, polarity, kind, holes=holes)

def ellipse(cls, rx, ry, *, polarity="bright", margin=6.0):
    """A filled ellipse of semi-axes ``rx`` (along x) and ``ry`` (along y),
    px: an amphora or a pipe's end seen from above, a disc seen at a slant
    (a circle when they are equal: :meth:`circle`, searched at one rotation).
    It looks the same turned by 180 degrees: an angle range of 180 degrees
    covers it.

    >>> from seahough import Pattern
    >>> p = Pattern.ellipse(30, 50)
    >>> p.kind, p.image.shape, Pattern.ellipse(20, 20).kind
    ('ellipse', (113, 73), 'circle')
    """
    from .pattern import _check_positive
    _check_positive(rx=rx, ry=ry)
    a, b = float(rx), float(ry)
    if a == b:
        return circle(cls, a, polarity=polarity, margin=margin)
    t = np.linspace(0, 2 * np.pi, max(32, int(np.pi * (a + b))), endpoint=False)
    outer = np.stack([a + a * np.cos(t), b + b * np.sin(t)], 1)
    return cls._shape([outer], 2 * a, 2 * b, margin, polarity, "ellipse")


def line(cls, length, width, *, polarity="bright", margin=6.0):
    """A straight band ``width`` pixels wide: a rope, tether, cable or pipe.

    Only its two long borders are edges (its ends are not: a rope runs on
    out of the frame), so the position along the line stays undetermined
    and detections report the line's direction and offset instead.
    """
    from .pattern import _check_positive
    _check_positive(length=length, width=width)
    L, W = float(length), float(width)
    if L < 2 * W:
        raise ParameterError(f"line length={L} must be at least twice its width={W}")
    poly = [(0, 0), (L, 0), (L, W), (0, W)]
    img, m = cls._canvas(L, W, margin)
    edge_mask = np.zeros(img.shape, bool)
    x0, x1 = int(m + min(W, 4)), int(math.ceil(m + L - min(W, 4)))
    edge_mask[:, x0:x1 + 1] = True
    outline = [np.array([(0, 0), (L, 0)]), np.array([(0, W), (L, W)])]
    p = cls._shape([poly], L, W, margin, polarity, "line", outline=outline,
                   edge_mask=edge_mask, closed=False)
    p.line_length, p.line_width = L, W
    return p
