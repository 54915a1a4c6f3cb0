"""Stage 1: scale the frame down and compute Scharr gradients (paper, section II)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..config import Config


@dataclass
class Gradients:
    """Scharr gradients of the working (downscaled) image.

    Attributes
    ----------
    image : ndarray
        The working grey image, float32.
    gx, gy, magnitude : ndarray
        Scharr derivatives and their magnitude (float32, same shape).
    fx, fy : float
        Working pixels per full-resolution pixel, along x and y.
    full_shape : tuple
        (height, width) of the full-resolution image.
    """

    image: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    magnitude: np.ndarray
    fx: float
    fy: float
    full_shape: tuple[int, int]

    @property
    def factor(self) -> float:
        """The mean scale factor (working / full)."""
        return 0.5 * (self.fx + self.fy)

    def to_full(self, x, y):
        """Working-image pixel coordinates to full-resolution ones."""
        return ((np.asarray(x) + 0.5) / self.fx - 0.5, (np.asarray(y) + 0.5) / self.fy - 0.5)

    def to_work(self, x, y):
        """Full-resolution pixel coordinates to working-image ones."""
        return ((np.asarray(x) + 0.5) * self.fx - 0.5, (np.asarray(y) + 0.5) * self.fy - 0.5)


def choose_factor(shape: tuple[int, int], config: Config,
                  pattern_extent: float | None = None, min_scale: float = 1.0) -> float:
    """The downscale factor for an image of ``shape`` (height, width).

    ``config.downscale`` wins when set. Otherwise the longest side is brought
    to ``config.target_size``, but never so far that a pattern of
    ``pattern_extent`` full-resolution pixels, seen at ``min_scale``, would
    span fewer than ``config.min_pattern_size`` working pixels.

    Examples
    --------
    >>> choose_factor((480, 640), Config())
    0.5
    """
    if config.downscale is not None:
        return float(config.downscale)
    f = min(1.0, config.target_size / max(shape))
    if pattern_extent:
        need = config.min_pattern_size / max(pattern_extent * min_scale, 1e-6)
        f = min(1.0, max(f, need))
    return float(f)


def scale_image(gray: np.ndarray, factor: float) -> tuple[np.ndarray, float, float]:
    """Downscale with area averaging; returns (image, fx, fy)."""
    h, w = gray.shape
    if factor >= 0.999:
        return gray, 1.0, 1.0
    nw, nh = max(int(round(w * factor)), 1), max(int(round(h * factor)), 1)
    small = cv2.resize(gray, (nw, nh), interpolation=cv2.INTER_AREA)
    return small, nw / w, nh / h


def compute_gradients(gray: np.ndarray, factor: float = 1.0, equalize: bool = False) -> Gradients:
    """Scale ``gray`` by ``factor`` and take its Scharr gradients.

    Parameters
    ----------
    gray : ndarray
        float32 grey image, levels 0-255.
    factor : float
        Downscale factor in (0, 1].
    equalize : bool
        Apply CLAHE before the gradients (uneven light, haze).

    Examples
    --------
    >>> img = np.zeros((40, 40), np.float32); img[:, 20:] = 100
    >>> g = compute_gradients(img)
    >>> float(g.magnitude[20, 19]), float(g.magnitude[20, 5])
    (1600.0, 0.0)
    """
    small, fx, fy = scale_image(gray, factor)
    if equalize:
        clahe = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8))
        small = clahe.apply(np.clip(small, 0, 255).astype(np.uint8)).astype(np.float32)
    small = np.ascontiguousarray(small, dtype=np.float32)
    gx = cv2.Scharr(small, cv2.CV_32F, 1, 0, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.Scharr(small, cv2.CV_32F, 0, 1, borderType=cv2.BORDER_REPLICATE)
    # numpy, not cv2.magnitude: OpenCV's result depends on the arrays' memory
    # alignment in the last bits, which made runs differ from process to process
    mag = gx * gx
    mag += gy * gy
    np.sqrt(mag, out=mag)  # (in place: the same numbers, fewer temporaries)
    return Gradients(small, gx, gy, mag, fx, fy, gray.shape)
