"""Transparent pixels of a searched image: no data, not scene.

An orthomosaic tile, a photo turned and pasted on a transparent canvas, a
frame with its housing masked out: their transparent pixels (alpha 0) hold
whatever the writer left there (black, most often), and the step from the
picture to that is the strongest edge of the image (a user trial: a
rectangle found three times along a tile's border at NFA 1e-29 to 1e-42, a
starfish "found" where the image was fully transparent). They are filled
smoothly from the picture around them before a search (:func:`fill_hidden`),
as a letterbox border is (:mod:`seahough.core.blanks`); positions are
unchanged. A pattern image's transparent pixels are not filled: they are
its mask, and its outline is the step to them (``Pattern.from_image``).
"""

from __future__ import annotations

import cv2
import numpy as np

#: Partly transparent pixels this many pixels from a transparent one are
#: filled too: a picture turned onto a transparent canvas blends its
#: outermost pixels with the canvas's black (a dark outline, an edge)
BLEND_RING = 2


def hidden_pixels(alpha: np.ndarray | None) -> np.ndarray | None:
    """The pixels to fill of an image of alpha channel ``alpha`` (None:
    none): the transparent ones (alpha 0), and those less than fully opaque
    within :data:`BLEND_RING` px of them; None when there are none, or when
    every pixel is transparent (nothing to fill from).

    >>> a = np.full((5, 8), 255, np.uint8); a[:, :2] = 0; a[:, 2] = 120; a[0, 6] = 200
    >>> hidden_pixels(a)[0].astype(int).tolist()       # (the 200 far from them: kept)
    [1, 1, 1, 0, 0, 0, 0, 0]
    >>> hidden_pixels(np.full((5, 8), 255, np.uint8)) is None
    True
    """
    if alpha is None or alpha.min() > 0:     # (the quickest look over a large opaque image)
        return None
    zero = alpha == 0
    if zero.all():
        return None
    k = 2 * BLEND_RING + 1
    near = cv2.dilate(zero.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
    return zero | (near & (alpha < alpha.max()))


def fill_hidden(levels: np.ndarray, hidden: np.ndarray | None) -> np.ndarray:
    """``levels`` (HxW or HxWxC float32, as a search reads them) with the
    pixels of ``hidden`` (:func:`hidden_pixels`; None: the same array)
    filled from the others by a push-pull pyramid (each coarser level the
    mean of the visible pixels below it, spread back where none was seen),
    which leaves no step at the border of the picture; the visible pixels
    are unchanged (filled in place when ``levels`` is writeable).

    Examples
    --------
    >>> img = np.zeros((60, 80), np.float32); img[10:50, 20:60] = 150   # a flat picture...
    >>> hidden = np.ones((60, 80), bool); hidden[10:50, 20:60] = False  # ... on no data
    >>> out = fill_hidden(img.copy(), hidden)
    >>> float(np.abs(out - 150).max()) < 0.01                # no step left
    True
    >>> fill_hidden(img, None) is img
    True
    """
    if hidden is None:
        return levels
    out = levels if levels.flags.writeable else levels.copy()
    seen = (~hidden).astype(np.float32)
    if out.ndim == 3:
        seen = seen[:, :, None]
    # down: each level's weighted sums and weights (pyrDown: means of 5x5 blocks)
    sums, weights = [cv2.pyrDown(out * seen)], [cv2.pyrDown(seen)]
    while min(weights[-1].shape[:2]) > 2 and weights[-1].min() == 0.0:
        sums.append(cv2.pyrDown(sums[-1]))
        weights.append(cv2.pyrDown(weights[-1]))
    shape = lambda a: a if a.ndim == out.ndim else a[:, :, None]   # (pyrDown drops a 1-axis)
    w = shape(weights[-1])          # (what the coarsest level did not see: the mean)
    value = np.where(w > 0, shape(sums[-1]) / np.maximum(w, 1e-12), out[~hidden].mean(axis=0))
    # up: each level's own mean where it saw enough, the coarser fill where it saw less
    for s, wt in zip(sums[-2::-1], weights[-2::-1]):
        up = shape(cv2.pyrUp(value, dstsize=(wt.shape[1], wt.shape[0])))
        wt = np.minimum(shape(wt), 1.0)
        value = shape(s) + up * (1.0 - wt)
    up = cv2.pyrUp(value, dstsize=(out.shape[1], out.shape[0]))
    out[hidden] = shape(up)[hidden]
    return out
