"""Small helpers shared by the simulator's modules: argument checks, seeds,
image conversions, frame corners and centres, smooth noise."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Union

import cv2
import numpy as np

from ..errors import ParameterError
from ..io.images import to_bgr8

Shape = tuple[int, int]
ImageLike = Union[np.ndarray, str, Path]


def _check_shape(shape, name: str = "shape") -> Shape:
    try:
        h, w = (int(v) for v in tuple(shape)[:2])
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be (height, width), got {shape!r}") from None
    if h < 8 or w < 8:
        raise ParameterError(f"{name} must be at least 8x8 pixels, got {shape!r}")
    return h, w


def _check_range(rng_values, name: str, positive: bool = False) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in rng_values)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a (low, high) pair, got {rng_values!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
        raise ParameterError(f"{name} must be a finite (low, high) pair with low <= high, "
                             f"got {rng_values!r}")
    if positive and lo <= 0:
        raise ParameterError(f"{name} must be positive, got {rng_values!r}")
    return lo, hi


def _seed_of(rng: np.random.Generator) -> int:
    return int(rng.integers(0, 2**31 - 1))


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    if lo == hi:
        return float(lo)
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _to_uint8(img: np.ndarray) -> np.ndarray:
    """Round and saturate to uint8 (fast path for float32 images of <= 4 channels)."""
    if img.dtype == np.uint8:
        return img
    if img.dtype == np.float32 and (img.ndim == 2 or (img.ndim == 3 and img.shape[2] <= 4)):
        return cv2.convertScaleAbs(cv2.max(img, 0.0))
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def _fast_normal(rng: np.random.Generator, shape) -> np.ndarray:
    """Approximately standard-normal float32 noise (sum of 3 uniform bytes), fast."""
    n = int(np.prod(shape))
    b = np.frombuffer(rng.bytes(3 * n), np.uint8).reshape(3, n)
    out = b[0].astype(np.float32)
    out += b[1]
    out += b[2]
    out -= np.float32(382.5)
    out *= np.float32(1.0 / 128.0)
    return out.reshape(shape)


def _to_bgr(img: np.ndarray) -> np.ndarray:
    """BGR uint8: the simulator's own rounding (:func:`_to_uint8`), then :func:`to_bgr8`."""
    return to_bgr8(_to_uint8(np.asarray(img)))


def _to_grey(img: np.ndarray) -> np.ndarray:
    img = _to_uint8(np.asarray(img))
    if img.ndim == 2:
        return img
    return cv2.cvtColor(_to_bgr(img), cv2.COLOR_BGR2GRAY)


def _corners(shape: Shape) -> np.ndarray:
    h, w = shape
    return np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], dtype=float)


def _centre(shape: Shape) -> tuple[float, float]:
    h, w = shape
    return (w - 1) / 2.0, (h - 1) / 2.0


def _noise(rng: np.random.Generator, shape: Shape, cell: float) -> np.ndarray:
    """Smooth random field of unit standard deviation with features ~``cell`` px."""
    h, w = shape
    if cell <= 1.0:
        return rng.standard_normal((h, w), dtype=np.float32)
    gh, gw = int(h / cell) + 3, int(w / cell) + 3
    grid = rng.standard_normal((gh, gw), dtype=np.float32)
    # grid node (i, j) lands at pixel (j * cell - ox, i * cell - oy)
    ox, oy = rng.uniform(cell, 2 * cell, 2)
    m = np.array([[cell, 0.0, -ox], [0.0, cell, -oy]])
    out = cv2.warpAffine(grid, m, (w, h), flags=cv2.INTER_CUBIC,
                         borderMode=cv2.BORDER_REFLECT_101)
    s = float(out[::3, ::3].std())
    return out * np.float32(1.0 / s) if s > 1e-6 else out
