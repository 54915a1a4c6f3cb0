"""A line detection's visible extent: where along the found line the
object's two borders are both seen as edges (:func:`visible_segment`), so
that a pipe's or a rope's ends are reported and drawn where the image shows
them (the position along a line is otherwise undetermined: its pattern's
length is no measure of the object's).
"""

from __future__ import annotations

import math

import cv2
import numpy as np


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
#: the line's normal (tan 25 = 0.47) ...
_BAND_TOL = 1.5
_ACROSS_RATIO = 1.0 / math.tan(math.radians(25.0))
#: ... and at least this many times the strip's noise (the robust standard
#: deviation of its gradients along the line; 3 cut a simulated rope on a
#: seabed's texture short, 4 lost it)
_NOISE_SIGMAS = 2.0
#: Stretches seen closer than this many widths apart (or 5 % of the line's
#: length in the image) are one: a longer hidden stretch parts them.
_GAP_WIDTHS = 4.0


def _line_extent(gray: np.ndarray, d, half: float, min_gradient: float):
    """The stretches along line detection ``d`` where the object is seen:
    ``[(t0, t1), ...]`` in order, px along its direction from ``(d.x, d.y)``
    (``[]``: none is seen; None: it cannot be measured).

    The grey image is sampled in a strip along the line (1 px along, 0.5 px
    across); a place along it holds the object when both of its borders
    (``half`` px each side of the centre line, within 1.5 px) have an edge
    there: a gradient across the line of at least ``min_gradient`` (Scharr
    units: 32 per grey level per px) and :data:`_NOISE_SIGMAS` times the
    strip's noise, within 25 degrees of the normal, of the sign most of that
    border's edges have (a bright rope has opposite signs on its two sides).
    The stretch with the most more such places than not (Kadane's) is seen;
    inside it, a stretch longer than the gap (:data:`_GAP_WIDTHS` widths, or
    5 % of the line's length in the image) where under half the places
    within two widths hold it is hidden and parts it (a pipe seen over 330
    px, buried over 300 and seen again was one stretch across the burial:
    more of it lay beyond than the burial was long); beyond a gap from it,
    another stretch of its own at least a gap (or 5 % of the line) long is
    seen too. A part shorter than two widths (or 3 % of the line) does not
    count; the first must cover a tenth of the line's length. None when
    the extent cannot be measured (the line misses the image, its band has
    no rows), ``[]`` when it was and nothing is seen.

    Examples
    --------
    >>> import types
    >>> img = np.full((100, 200), 40, np.float32)
    >>> img[48:53, 30:120] = 220                         # a rope 5 px wide, x 30-119
    >>> d = types.SimpleNamespace(x=99.5, y=50.0, line_angle=0.0)
    >>> [[round(float(v)) for v in st] for st in _line_extent(img, d, 2.5, 48.0)]
    [[-70, 20]]
    >>> img[48:53, 60:90] = 40                           # 30 px of it buried
    >>> [[round(float(v)) for v in st] for st in _line_extent(img, d, 2.5, 48.0)]
    [[-70, -40], [-10, 20]]
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
    # over the image's noise too: the strongest of a border's rows in speckle or
    # grain (sd 2 levels) passed 1.5 levels/px anywhere (a reviewer's rope of 140 px
    # came out 180-300 px long); measured along the line (a straight border has no
    # gradient along it; a shaded rope has across it, inside)
    along = g_t[:, 1:-1]
    noise = 1.4826 * float(np.median(np.abs(along - np.median(along)))) if along.size else 0.0
    thr = max(min_gradient / 32.0, _NOISE_SIGMAS * noise)
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
            return []
        sign = 1.0 if (gs[edge] > 0).sum() >= (gs[edge] < 0).sum() else -1.0
        hit &= edge & (gs * sign > 0)
    length, width = ts[1] - ts[0], 2.0 * half
    gap = max(_GAP_WIDTHS * width, 0.05 * length)
    win = max(3, int(round(2.0 * width)) | 1)         # (odd)
    seen = cv2.blur(hit.astype(np.float32)[None, :], (win, 1),
                    borderType=cv2.BORDER_CONSTANT)[0] >= 0.5
    out, todo, main = [], [(0, t.size)], None
    while todo:     # the stretch with most more places seen than not, then beyond its gaps
        lo, hi = todo.pop()
        if hi - lo < 1 or not hit[lo:hi].any():
            continue
        i0, i1 = (lo + i for i in _best_run(np.where(hit[lo:hi], 1.0, -1.0)))
        if main is not None and t[i1] - t[i0] < max(gap, 0.05 * length):
            continue        # (beyond a gap: a stretch of its own, longer than chance's)
        main = main or (float(t[i0]), float(t[i1]))
        # a hidden stretch longer than the gap inside it parts it (it was crossed when
        # more of the object lay beyond it than it was long)
        cuts = [(a, b) for a, b in _runs(~seen[i0:i1 + 1]) if t[b] - t[a] >= gap]
        bounds = [i0] + [i0 + v for a, b in cuts for v in (a, b)] + [i1]
        for a, b in zip(bounds[::2], bounds[1::2]):
            j0, j1 = (a + i for i in _best_run(np.where(hit[a:b + 1], 1.0, -1.0)))
            t0, t1 = max(float(t[j0]), ts[0]), min(float(t[j1]), ts[1])   # (in the image)
            if hit[j0] and t1 - t0 >= max(2.0 * width, 0.03 * length):
                out.append((t0, t1))
        todo += [(lo, max(lo, i0 - int(gap))), (min(hi, i1 + int(gap) + 1), hi)]
    # (the stretch of most places seen must cover a tenth of the line on its own: chance
    # stretches beyond gaps added up past it along a single straight edge)
    if main is None or not out or main[1] - main[0] < 0.1 * length:
        return []
    return sorted(out)


def _runs(v: np.ndarray) -> list:
    """``[(i0, i1), ...]``: the first and last index of each run of True in ``v``.

    >>> _runs(np.array([0, 1, 1, 0, 0, 1, 0, 1], bool))
    [(1, 2), (5, 5), (7, 7)]
    """
    x = np.diff(np.concatenate(([0], v.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(x == 1).tolist(), (np.flatnonzero(x == -1) - 1).tolist()))


def _best_run(v: np.ndarray) -> tuple[int, int]:
    """``(i0, i1)``: the first and last index of the stretch of ``v`` of the
    largest sum (Kadane's; the first of equal ones).

    >>> _best_run(np.array([-1, 1, 1, -1, 1, 1, 1, -1, -1, -1, 1.0]))
    (1, 6)
    """
    best, b0, b1, run, r0 = -np.inf, 0, 0, 0.0, 0
    for i, x in enumerate(v.tolist()):
        if run <= 0.0:
            run, r0 = x, i
        else:
            run += x
        if run > best:
            best, b0, b1 = run, r0, i
    return b0, b1


def visible_stretches(gray: np.ndarray, d, min_gradient: float) -> list:
    """The stretches of line detection ``d`` (its ``x, y, line_angle`` and
    ``outline``, the band's two borders) that grey image ``gray`` shows: each
    ``[[x0, y0], [x1, y1]]`` on the centre line, image pixels, in order along
    it; ``[]`` when none is seen, None when that cannot be measured (a band
    under 2 px wide: its two borders are not told apart; :func:`_line_extent`).

    >>> import types
    >>> img = np.full((100, 200), 40, np.float32)
    >>> img[48:53, 30:120] = 220                         # a rope 5 px wide, x 30-119
    >>> img[48:53, 60:90] = 40                           # 30 px of it buried
    >>> borders = [np.array([[0.0, 47.5], [199.0, 47.5]]), np.array([[0.0, 52.5], [199.0, 52.5]])]
    >>> d = types.SimpleNamespace(x=99.5, y=50.0, line_angle=0.0, outline=borders)
    >>> [st.round(1).tolist() for st in visible_stretches(img, d, 48.0)]
    [[[29.5, 50.0], [59.5, 50.0]], [[89.5, 50.0], [119.5, 50.0]]]
    """
    borders = [np.asarray(o, float).reshape(-1, 2) for o in d.outline]
    borders = [o[0] for o in borders if len(o) >= 2]
    if len(borders) < 2 or d.line_angle is None:
        return None
    a = math.radians(d.line_angle)
    dv, nv = np.array([math.cos(a), -math.sin(a)]), np.array([math.sin(a), math.cos(a)])
    half = 0.5 * abs(float(np.dot(borders[0] - borders[1], nv)))
    ext = _line_extent(gray, d, half, min_gradient) if half >= 1.0 else None
    if ext is None:
        return None
    p = np.array([d.x, d.y])
    return [np.array([p + t0 * dv, p + t1 * dv]) for t0, t1 in ext]


def visible_segment(gray: np.ndarray, d, min_gradient: float):
    """The visible extent of line detection ``d``: from the first stretch
    :func:`visible_stretches` finds to the last, ``[[x0, y0], [x1, y1]]``,
    or None when there is none.

    >>> import types
    >>> img = np.full((100, 200), 40, np.float32)
    >>> img[48:53, 30:120] = 220                         # a rope 5 px wide, x 30-119
    >>> borders = [np.array([[0.0, 47.5], [199.0, 47.5]]), np.array([[0.0, 52.5], [199.0, 52.5]])]
    >>> d = types.SimpleNamespace(x=99.5, y=50.0, line_angle=0.0, outline=borders)
    >>> visible_segment(img, d, 48.0).round(1).tolist()
    [[29.5, 50.0], [119.5, 50.0]]
    """
    st = visible_stretches(gray, d, min_gradient)
    return np.array([st[0][0], st[-1][1]]) if st else None   # (none, or not measured)
