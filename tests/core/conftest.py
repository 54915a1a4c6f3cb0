"""Helpers shared by the core stage tests: hand-made edge points and images."""

from __future__ import annotations

import numpy as np

from seahough.core.keypoints import EdgePoints


def make_edges(x, y, angle, shape, magnitude=None) -> EdgePoints:
    """EdgePoints at the given sub-pixel positions (working px) and gradient
    angles (radians), each in the pixel it rounds to."""
    x = np.asarray(x, np.float32)
    y = np.asarray(y, np.float32)
    angle = np.mod(np.asarray(angle, np.float64), 2 * np.pi).astype(np.float32)
    mag = (np.full(x.shape, 100.0, np.float32) if magnitude is None
           else np.asarray(magnitude, np.float32))
    ix = np.rint(x).astype(np.int32)
    iy = np.rint(y).astype(np.int32)
    return EdgePoints(x, y, angle, mag, ix, iy, tuple(shape))


def square_image(size=20, lo=6, hi=14, level=100.0) -> np.ndarray:
    """A ``size`` x ``size`` float32 image, 0 but for a bright square of
    ``level`` on pixels [lo, hi) in both axes."""
    img = np.zeros((size, size), np.float32)
    img[lo:hi, lo:hi] = level
    return img
