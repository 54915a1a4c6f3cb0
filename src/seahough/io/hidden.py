"""Transparent pixels of a searched image: no data, not scene.

An orthomosaic tile, a photo turned and pasted on a transparent canvas, a
frame with its housing masked out: their transparent pixels (alpha 0) hold
whatever the writer left there (black, most often), and the step from the
picture to that is the strongest edge of the image (a user trial: a
rectangle found three times along a tile's border at NFA 1e-29 to 1e-42, a
starfish "found" where the image was fully transparent). They are filled
smoothly from the picture around them before a search (:func:`fill_hidden`),
as a letterbox border is (:mod:`seahough.core.blanks`); positions are
unchanged.
"""

from __future__ import annotations

import cv2
import numpy as np


def fill_hidden(image: np.ndarray) -> np.ndarray:
    """``image`` (HxW, HxWx3 or HxWx4 levels, as a search reads them) as
    the search sees it: a BGRA image whose alpha is 0 somewhere (and not
    everywhere) comes back as float32 BGR with its pixels of less than full
    alpha (the transparent ones, and the blend at their border) filled from the
    visible ones around them by a push-pull pyramid (each coarser level the
    weighted mean of the visible pixels below it, spread back where nothing
    was visible), which leaves no step at the border of the picture; the
    visible pixels are unchanged. Anything else: the same array.

    Examples
    --------
    >>> bgra = np.zeros((60, 80, 4), np.uint8)
    >>> bgra[10:50, 20:60] = (90, 120, 150, 255)     # a flat picture on a transparent canvas
    >>> out = fill_hidden(bgra)
    >>> out.shape, out.dtype.name, float(np.abs(out - (90, 120, 150)).max()) < 0.01
    ((60, 80, 3), 'float32', True)
    >>> opaque = bgra[10:50, 20:60]                 # nothing transparent: as it is
    >>> fill_hidden(opaque) is opaque, fill_hidden(bgra[..., :3]) is not None
    (True, True)
    """
    if image.ndim != 3 or image.shape[2] != 4:
        return image
    alpha = image[:, :, 3]
    if not (alpha == 0).any():
        return image
    # (and the partly transparent pixels around them: a picture turned onto a transparent
    # canvas blends its outermost pixels with the canvas's black, a dark outline)
    hidden = alpha < alpha.max()
    if hidden.all() or not hidden.any():
        return image
    bgr = np.ascontiguousarray(image[:, :, :3], np.float32)
    seen = (~hidden).astype(np.float32)
    # down: the weighted sums and weights of every level (pyrDown's mean of each)
    sums, weights = [bgr * seen[:, :, None]], [seen]
    while min(weights[-1].shape) > 2 and weights[-1].min() == 0.0:
        sums.append(cv2.pyrDown(sums[-1]))
        weights.append(cv2.pyrDown(weights[-1]))
    w = weights[-1][:, :, None]      # (what the coarsest level did not see: the mean)
    value = np.where(w > 0, sums[-1] / np.maximum(w, 1e-12), bgr[~hidden].mean(axis=0))
    # up: each level's own mean where it saw enough, the coarser fill where it saw less
    for s, wt in zip(sums[-2::-1], weights[-2::-1]):
        up = cv2.pyrUp(value, dstsize=(wt.shape[1], wt.shape[0]))
        wt = np.minimum(wt, 1.0)[:, :, None]
        value = np.where(wt > 0, s / np.maximum(wt, 1e-12), 0.0) * wt + up * (1.0 - wt)
    out = bgr.copy()
    out[hidden] = value.astype(np.float32)[hidden]
    return out
