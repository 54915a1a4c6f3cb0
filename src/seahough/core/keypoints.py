"""Stage 2: edge points, and the N most contrasted of them (the key points)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from . import kernels as K
from .preprocess import Gradients, compute_gradients


@dataclass
class EdgePoints:
    """Edge pixels after non-maximum suppression across the edge.

    ``x``, ``y`` are sub-pixel positions (working pixels), ``angle`` the
    gradient direction in radians [0, 2 pi), ``magnitude`` its strength,
    ``ix``, ``iy`` the pixel each point belongs to, ``shape`` the image's;
    ``nx``, ``ny`` the exact unit gradient (``angle``, from ``cv2.phase``,
    agrees with it to about 0.3 degrees; computed from ``angle`` when not
    given).
    """

    x: np.ndarray
    y: np.ndarray
    angle: np.ndarray
    magnitude: np.ndarray
    ix: np.ndarray
    iy: np.ndarray
    shape: tuple[int, int]
    index: np.ndarray | None = field(default=None, repr=False)
    nx: np.ndarray | None = field(default=None, repr=False)
    ny: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.nx is None or self.ny is None:
            self.nx = np.cos(self.angle).astype(np.float32)
            self.ny = np.sin(self.angle).astype(np.float32)

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def take(self, keep: np.ndarray) -> "EdgePoints":
        """The points where ``keep`` (bool or ids) holds, without an index map."""
        return EdgePoints(*(a[keep] for a in (self.x, self.y, self.angle, self.magnitude,
                                              self.ix, self.iy)), self.shape, None,
                          self.nx[keep], self.ny[keep])

    def index_map(self, ids: np.ndarray | None = None) -> np.ndarray:
        """int32 image holding each edge point's id at its pixel, -1 elsewhere.

        With ``ids``, only those points are entered. (Without, the map that
        :func:`find_edge_points` made along the way, when there is one: do
        not write into it.)"""
        if ids is None and self.index is not None:
            return self.index
        m = np.full(self.shape, -1, np.int32)
        if ids is None:
            ids = np.arange(len(self), dtype=np.int32)
        m[self.iy[ids], self.ix[ids]] = ids
        return m


_NO_MASK = np.zeros((0, 0), np.uint8)


def find_edge_points(grad: Gradients, min_gradient: float,
                     mask: np.ndarray | None = None, row0: int = 0) -> EdgePoints:
    """Thin edges to one pixel (non-maximum suppression) with sub-pixel positions.

    ``mask`` (the gradients' shape, non-zero where wanted) limits the points
    to some pixels; the suppression still compares with every neighbour.
    ``row0``: the gradients are rows of a larger image from this row on: the
    points' ``y`` are that image's (``iy`` and the index map stay these
    rows').

    Examples
    --------
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((30, 30), np.float32); img[:, 15:] = 200
    >>> e = find_edge_points(compute_gradients(img), 50)
    >>> bool(np.allclose(e.x, 14.5, atol=0.01)), len(e)   # every row but the first and last
    (True, 28)
    """
    mask = _NO_MASK if mask is None else np.ascontiguousarray(mask, np.uint8)
    x, y, m, ix, iy, index, nx, ny = K.edge_points(grad.magnitude, grad.gx, grad.gy,
                                                   np.float32(min_gradient), mask, int(row0))
    # the direction, [0, 2 pi), at the points only (about 0.3 deg accurate;
    # the same numbers as cv2.phase of the whole image: at least 16 values,
    # which OpenCV's vector code takes; fewer go through its scalar code,
    # a few ulp apart)
    n = ix.size
    gxp, gyp = np.zeros(max(n, 16), np.float32), np.zeros(max(n, 16), np.float32)
    gxp[:n], gyp[:n] = grad.gx[iy, ix], grad.gy[iy, ix]
    a = cv2.phase(gxp, gyp).reshape(-1)[:n].copy()
    a[a >= np.float32(2 * np.pi)] = 0.0
    return EdgePoints(x, y, a, m, ix, iy, grad.magnitude.shape, index, nx, ny)


def edge_points_near(grad: Gradients, x, y, radius: float, min_gradient: float,
                     mask: np.ndarray | None = None, row0: int = 0) -> EdgePoints:
    """The edge points (:func:`find_edge_points`) in a band around the points
    ``(x, y)`` (pixels of ``grad``): a square of side ``2 ceil(radius) + 1``
    around each, and only where ``mask`` (bool, optional) is set.

    Examples
    --------
    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((30, 60), np.float32); img[:, 15:] = 200; img[:, 45:] = 0
    >>> e = edge_points_near(compute_gradients(img), [14.0], [10.0], 2, 50)
    >>> sorted(set(e.ix.tolist())), len(e)   # rows 8-12, the maximum's pixel
    ([15], 5)
    """
    band = _band(grad.magnitude.shape, x, y, radius, mask)
    return find_edge_points(grad, min_gradient, band, row0)


def _band(shape, x, y, radius: float, mask=None) -> np.ndarray:
    """uint8 image of ``shape``: 1 within a square of side ``2 ceil(radius) + 1``
    around each point ``(x, y)`` and where ``mask`` (optional) is set."""
    h, w = shape
    band = np.zeros((h, w), np.uint8)
    ix = np.rint(np.asarray(x, float)).astype(np.int64)
    iy = np.rint(np.asarray(y, float)).astype(np.int64)
    ok = (ix >= 0) & (iy >= 0) & (ix < w) & (iy < h)
    band[iy[ok], ix[ok]] = 1
    k = 2 * int(math.ceil(radius)) + 1
    band = cv2.dilate(band, np.ones((k, k), np.uint8))
    if mask is not None:
        band &= np.asarray(mask, bool).astype(np.uint8)
    return band


#: Rows of a strip of :func:`edge_points_near_image` (and the rows around
#: each that its gradients and thinning look at).
STRIP_ROWS = 256
_STRIP_MARGIN = 3


def edge_points_near_image(gray: np.ndarray, x, y, radius: float, min_gradient: float,
                           mask: np.ndarray | None = None, equalize: bool = False,
                           rows: int = STRIP_ROWS, metric: np.ndarray | None = None) -> EdgePoints:
    """:func:`edge_points_near` on the full-resolution gradients of ``gray``
    (float32 grey or BGR), computed a strip of ``rows`` rows at a time: the
    same points, without holding a large image's gradients at once (a 12 MP
    frame's are 200 MB). A grey strip whose band is a small part of it has
    its gradients taken in the band only (:data:`BAND_SHARE`;
    :func:`~seahough.core.kernels.band_gradients`: the same numbers as
    OpenCV's on integer grey levels, within float rounding on others). With
    ``equalize`` (CLAHE, not local to a strip) the whole image's gradients
    are taken. ``metric``: a colour image's channel weighting
    (:func:`.preprocess.colour_metric`), the same for every strip.

    Examples
    --------
    >>> from seahough.core.preprocess import compute_gradients
    >>> rng = np.random.default_rng(0)
    >>> img = cv2.GaussianBlur(rng.uniform(0, 255, (100, 80)).astype(np.float32), (0, 0), 2)
    >>> px, py = rng.uniform(0, 79, 300), rng.uniform(0, 99, 300)
    >>> def pixels(e):    # (the points by pixel, and their positions)
    ...     o = np.lexsort((e.ix, e.iy))
    ...     return e.ix[o], e.iy[o], e.x[o], e.y[o]
    >>> for levels in (np.rint(img), img):     # integer grey levels, fractional ones
    ...     for r in (2, 6.75):   # (a band wider than the strips' margin of 3 rows too)
    ...         a = pixels(edge_points_near(compute_gradients(levels), px[::10], py[::10], r, 5))
    ...         b = pixels(edge_points_near_image(levels, px[::10], py[::10], r, 5, rows=16))
    ...         print(a[0].size > 50, all(np.array_equal(u, v) for u, v in zip(a[:2], b[:2])),
    ...               all(np.array_equal(u, v) for u, v in zip(a[2:], b[2:])),
    ...               max(float(np.abs(u - v).max()) for u, v in zip(a[2:], b[2:])) < 1e-4)
    True True True True
    True True True True
    True True False True
    True True True True
    """
    h, w = gray.shape[:2]
    if equalize or h <= rows + 2 * _STRIP_MARGIN:
        if not equalize:
            return _edges_near(gray, x, y, radius, min_gradient, mask, 0, metric)
        return edge_points_near(compute_gradients(gray, 1.0, equalize, metric), x, y, radius,
                                min_gradient, mask)
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    reach = int(math.ceil(radius)) + 1
    # the rows a strip's points may reach (their bands), and the rows around
    # those that the gradients and the thinning look at
    margin = max(_STRIP_MARGIN, reach + 2)
    parts = []
    for y0 in range(0, h, rows):
        y1 = min(h, y0 + rows)
        near = (y >= y0 - reach) & (y < y1 + reach)
        if not near.any():
            continue
        s0, s1 = max(0, y0 - margin), min(h, y1 + margin)
        sub = None if mask is None else np.asarray(mask)[s0:s1]
        e = _edges_near(gray[s0:s1], x[near], y[near] - s0, radius, min_gradient, sub, s0,
                        metric)
        core = (e.iy >= y0 - s0) & (e.iy < y1 - s0)
        e = e.take(core)
        parts.append((e, s0))
    if not parts:
        z = np.zeros(0, np.float32)
        zi = np.zeros(0, np.int32)
        return EdgePoints(z, z, z, z, zi, zi, (h, w))
    cat = lambda name: np.concatenate([getattr(e, name) for e, _ in parts])
    # (y is already the image's: row0)
    return EdgePoints(cat("x"), cat("y"),
                      cat("angle"), cat("magnitude"), cat("ix"),
                      np.concatenate([e.iy + s0 for e, s0 in parts]).astype(parts[0][0].iy.dtype),
                      (h, w), None, cat("nx"), cat("ny"))


#: Above this share of an image in the band, its gradients are taken whole
#: (OpenCV's vectorised filters), else in the band only (:func:`_edges_near`).
BAND_SHARE = 0.25


def _edges_near(gray, x, y, radius, min_gradient, mask, row0, metric) -> EdgePoints:
    """:func:`edge_points_near` of the full-resolution gradients of ``gray``
    (a strip from ``row0``): a grey image's taken in the band only when it
    is a small part of the image."""
    band = _band(gray.shape[:2], x, y, radius, mask)
    if gray.ndim == 2:
        need = cv2.dilate(band, np.ones((3, 3), np.uint8))
        if cv2.countNonZero(need) <= BAND_SHARE * need.size:
            img = np.ascontiguousarray(gray, np.float32)
            gx, gy, mag = K.band_gradients(img, need)
            grad = Gradients(img, gx, gy, mag, 1.0, 1.0, img.shape)
            return find_edge_points(grad, min_gradient, band, row0)
    grad = compute_gradients(np.ascontiguousarray(gray), 1.0, False, metric)
    return find_edge_points(grad, min_gradient, band, row0)


def contrast_threshold(magnitude: np.ndarray, n: int, bins: int = 1024) -> float:
    """The paper's threshold: add up the histogram of gradient magnitudes from
    the top until ``n`` points are reached; returns that bin's lower edge.

    Examples
    --------
    >>> contrast_threshold(np.arange(100, dtype=np.float32), 10) <= 90
    True
    """
    if magnitude.size <= n:
        return float(magnitude.min()) if magnitude.size else 0.0
    hi = float(magnitude.max())
    hi = hi if hi > 0 else 1.0
    # the histogram over [0, hi] in ``bins`` bins (np.bincount: 3x np.histogram's speed)
    q = np.minimum((magnitude * np.float32(bins / hi)).astype(np.int32), bins - 1)
    hist = np.bincount(np.maximum(q, 0), minlength=bins)
    from_top = np.cumsum(hist[::-1])
    k = int(np.searchsorted(from_top, n))
    return (bins - 1 - min(k, bins - 1)) * hi / bins


def local_contrast(edges: EdgePoints, magnitude: np.ndarray, window: int) -> np.ndarray:
    """Each edge point's gradient over the mean gradient around it.

    Examples
    --------
    A faint edge (a step of 10 grey levels) far from a strong one (190):
    by raw gradient it weighs 5 % of the strong edge, by local contrast 25 %.

    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((40, 80), np.float32); img[:, 10:] = 10; img[:, 60:] = 200
    >>> g = compute_gradients(img)
    >>> e = find_edge_points(g, 20)
    >>> c = local_contrast(e, g.magnitude, 15)
    >>> faint, strong = e.x < 30, e.x > 30
    >>> round(float(e.magnitude[faint].mean() / e.magnitude[strong].mean()), 2)
    0.05
    >>> round(float(c[faint].mean() / c[strong].mean()), 2)
    0.25
    """
    k = min(int(window), max(magnitude.shape)) | 1  # wider windows only cost time
    mean = cv2.blur(magnitude, (k, k), borderType=cv2.BORDER_REFLECT)
    floor = np.float32(max(cv2.mean(magnitude)[0], 1e-3))
    return edges.magnitude / (mean[edges.iy, edges.ix] + floor)


#: Edge points whose directions differ by at most this (degrees) are one chain.
CHAIN_TOLERANCE = 30.0


def chain_weight(edges: EdgePoints, length: float, index: np.ndarray,
                 strength: np.ndarray) -> np.ndarray:
    """``strength`` times ``min(1, L / length)``, L the number of edge points
    of each point's chain (neighbours along an edge whose directions differ
    by at most :data:`CHAIN_TOLERANCE`): points on long borders keep their
    rank, texture's short bits lose theirs.

    Examples
    --------
    A long straight border and a speck of texture, equally contrasted:

    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((40, 60), np.float32); img[:, 30:] = 100; img[5:7, 5:7] = 100
    >>> e = find_edge_points(compute_gradients(img), 20)
    >>> w = chain_weight(e, 12.0, e.index_map(), np.ones(len(e), np.float32))
    >>> float(w[e.x > 20].min()), bool(w[e.x < 20].max() < 1)
    (1.0, True)
    """
    chains = K.chain_lengths(edges.ix, edges.iy, edges.angle, index,
                             math.radians(CHAIN_TOLERANCE))
    return strength * np.minimum(np.float32(1.0), chains.astype(np.float32) / np.float32(length))


def chain_share(edges: EdgePoints, length: float, index: np.ndarray | None = None) -> float:
    """The share of edge points whose chain (see :func:`chain_weight`) holds
    at least ``length`` points: near 1 for a shape's borders, lower for
    texture.

    >>> from seahough.core.preprocess import compute_gradients
    >>> img = np.zeros((40, 60), np.float32); img[8:32, 10:50] = 100   # a box
    >>> round(chain_share(find_edge_points(compute_gradients(img), 20), 8), 2)
    0.97
    >>> noise = np.random.default_rng(0).uniform(0, 100, (40, 60)).astype(np.float32)
    >>> chain_share(find_edge_points(compute_gradients(noise), 20), 8) < 0.5
    True
    """
    if len(edges) == 0:
        return 0.0
    idx = edges.index_map() if index is None else index
    chains = K.chain_lengths(edges.ix, edges.iy, edges.angle, idx, math.radians(CHAIN_TOLERANCE))
    return float(np.mean(chains >= length))


def select_keypoints(edges: EdgePoints, n: int, strength: np.ndarray | None = None) -> np.ndarray:
    """Ids of the ``n`` most contrasted edge points (histogram threshold).

    ``strength`` ranks the points (default: their gradient magnitude). Ties
    at the threshold bin are cut so that at most ``n`` remain.
    """
    if len(edges) == 0:
        return np.empty(0, np.int32)
    v = edges.magnitude if strength is None else strength
    thr = contrast_threshold(v, n)
    ids = np.flatnonzero(v >= thr).astype(np.int32)
    if ids.size > n:
        keep = np.argpartition(-v[ids], n - 1)[:n]
        ids = np.sort(ids[keep])
    return ids


def spread_points(x, y, order, count):
    """The indices (sorted) of ``count`` of the edge points ``x, y`` spread
    evenly over the edges, the strongest first (``order``: their indices,
    strongest first); all of them when there are no more."""
    n = x.shape[0]
    if n <= count:
        return np.asarray(order, np.int64)
    x = np.ascontiguousarray(x, np.float64)
    y = np.ascontiguousarray(y, np.float64)
    # the spacing that leaves about `count` points: edges are lines, so about
    # n / count pixels; bisect within a bracket around that
    guess = n / count
    lo, hi = 0.25 * guess, 2.0 * guess
    best = None
    for _ in range(7):  # bisection on the spacing
        d = 0.5 * (lo + hi)
        # (the greedy pass stops at `count`: the same first points, found sooner)
        kept = K.spread_points(x, y, order, d, count)
        if kept.size >= count:
            best, lo = kept, d
        else:
            hi = d
    if best is None:
        best = K.spread_points(x, y, order, lo, count)
    return np.sort(best[:count])
