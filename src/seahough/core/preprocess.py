"""Stage 1: scale the frame down and compute Scharr gradients (paper, section II)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..config import Config
from .blanks import Blanks, fill_blanks, find_blanks


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
    metric : ndarray or None
        A colour image's channel weighting (3x3, :func:`colour_metric`)
        that the gradients were measured with; None: the channels as they
        are (and every grey image).
    """

    image: np.ndarray
    gx: np.ndarray
    gy: np.ndarray
    magnitude: np.ndarray
    fx: float
    fy: float
    full_shape: tuple[int, int]
    metric: np.ndarray | None = None

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


#: A band pattern (a rope, a post: ``Pattern.line``) searched in an image
#: brought far down keeps this many working pixels across at its smallest
#: searched scale (``Detector.working_factor`` says when): its two borders
#: merge below it (a 690 x 33 px post in a 4000 px photo, brought to 320 px:
#: 1.3 px across, "0 edge segments", exit 2).
MIN_BAND_PX = 3.0


def choose_factor(shape: tuple[int, int], config: Config,
                  pattern_extent: float | None = None, min_scale: float = 1.0,
                  band_width: float | None = None) -> float:
    """The downscale factor for an image of ``shape`` (height, width[, channels]).

    ``config.downscale`` wins when set. Otherwise the longest side is brought
    to ``config.target_size``, but never so far that a pattern of
    ``pattern_extent`` full-resolution pixels, seen at ``min_scale``, would
    span fewer than ``config.min_pattern_size`` working pixels, nor a band
    ``band_width`` across (a line pattern's) fewer than :data:`MIN_BAND_PX`.

    Examples
    --------
    >>> choose_factor((480, 640), Config())
    0.5
    >>> round(choose_factor((2250, 4000), Config(), 690, 0.5, band_width=33), 3)
    0.182
    """
    if config.downscale is not None:
        return float(config.downscale)
    f = min(1.0, config.target_size / max(shape[:2]))
    if pattern_extent:
        need = config.min_pattern_size / max(pattern_extent * min_scale, 1e-6)
        f = min(1.0, max(f, need))
    if band_width:
        f = min(1.0, max(f, MIN_BAND_PX / max(band_width * min_scale, 1e-6)))
    return float(f)


def factor_hint(shape, factor: float, config: Config, min_scale: float) -> str:
    """What to add to a pattern's "too few edges" at a search's working
    scale ``factor``: why that scale, and what to do ("" at full size or a
    scale the user set). A user trial: a 115 px crop searched at scale 6-12
    in a 6000 px photo, "too few edges at scale 0.05", and the pattern was
    fine.

    >>> factor_hint((4500, 6000), 320 / 6000, Config(), 6.0).split(":")[0]
    '; the 6000x4500 image is searched at scale 0.05 (its longer side brought to 320 px'
    """
    if factor >= 0.999 or config.downscale is not None:
        return ""
    h, w = shape[:2]
    why = (f"its longer side brought to {config.target_size} px: Config.target_size"
           if abs(factor * max(h, w) - config.target_size) < 1.0 else
           "the scale that keeps the pattern large enough at the smallest searched scale")
    return (f"; the {w}x{h} image is searched at scale {factor:.2f} ({why}), and the pattern "
            "with it: give the "
            f"pattern at about its size in the image (the scale range starts at {min_scale:g}), "
            "or set a larger working scale (Config.downscale, CLI --downscale)")


def prepare_image(image: np.ndarray, config: Config, blanks: Blanks | None = None) -> np.ndarray:
    """A searched image as the search sees it: what is not the scene filled
    (:func:`~.blanks.fill_blanks`: a letterbox border, burned-in captions,
    the regions of ``Config.ignore``; ``blanks``: those already found) and,
    with ``Config.smooth``, blurred by that Gaussian sigma (speckle, grain).
    Positions are unchanged.

    >>> img = np.zeros((40, 60), np.float32); img[:, 30:] = 200
    >>> out = prepare_image(img, Config(smooth=2.0))
    >>> float(out[20, 29]) > 0 and float(out[20, 30]) < 200
    True
    """
    image = fill_blanks(image, find_blanks(image, config.ignore) if blanks is None else blanks)
    if config.smooth > 0:
        image = cv2.GaussianBlur(np.ascontiguousarray(image, np.float32), (0, 0), config.smooth,
                                 borderType=cv2.BORDER_REPLICATE)
    return image


def scale_image(gray: np.ndarray, factor: float) -> tuple[np.ndarray, float, float]:
    """Downscale with area averaging (a grey or a colour image, every
    channel alike); returns (image, fx, fy)."""
    h, w = gray.shape[:2]
    if factor >= 0.999:
        return gray, 1.0, 1.0
    nw, nh = max(int(round(w * factor)), 1), max(int(round(h * factor)), 1)
    small = cv2.resize(gray, (nw, nh), interpolation=cv2.INTER_AREA)
    return small, nw / w, nh / h


def compute_gradients(gray: np.ndarray, factor: float = 1.0, equalize: bool = False,
                      metric=None) -> Gradients:
    """Scale ``gray`` by ``factor`` and take its Scharr gradients.

    A colour image (HxWx3, BGR) gets the Di Zenzo colour gradient: per
    channel Scharr derivatives ``gx_c, gy_c``, their structure tensor
    averaged over the channels, ``(sum gx_c^2, sum gx_c gy_c, sum gy_c^2) / 3``,
    whose largest eigenvalue is the squared magnitude and whose eigenvector
    is the direction: the direction across which the colour changes most.
    Averaged (not summed), so that three equal channels give the grey
    image's magnitude, and a step in one channel alone gives
    ``1 / sqrt(3)`` of that channel's (``Config.min_gradient`` keeps its
    unit). The eigenvector has no sign: the gradient points the way the
    channel that changes most along it increases, i.e. the sign of
    ``sum_c d_c |d_c|`` where ``d_c`` is channel c's derivative along the
    eigenvector (a zero sum: +). That is the grey gradient's sign whenever
    the channels agree, and the same along the whole border between two
    colours (the ratios of the ``d_c`` are those of the colours'
    differences), so "bright" and "dark" polarities mean "the dominant
    channel rises" and "falls" across a colour edge. ``gx, gy`` are the
    magnitude times that signed direction, so the later stages are those of
    a grey image; ``Gradients.image`` is the working image made grey.

    Parameters
    ----------
    gray : ndarray
        float32 grey image (HxW), or BGR image (HxWx3), levels 0-255.
    factor : float
        Downscale factor in (0, 1].
    equalize : bool
        Apply CLAHE before the gradients (uneven light, haze); each channel
        of a colour image.
    metric : None, float or ndarray
        How a colour image's channels are weighed (grey images: ignored).
        None: as they are. A number ``b > 1``: by this image's own gradient
        statistics, every colour direction's gain at most ``b``
        (:func:`colour_metric`). A 3x3 array: that weighting (one measured
        before, e.g. on the working image, for its full-resolution edges).
        The magnitude and direction are those of the weighted channels; the
        sign rule above stays that of the channels as they are, so that
        "bright" and "dark" keep their meaning. ``Gradients.metric`` holds
        the weighting used. What the weighting adds over the channels as
        they are is smoothed by :data:`CHROMA_SIGMA` full-resolution pixels
        (a camera's colour is coarser than its brightness).

    Examples
    --------
    >>> img = np.zeros((40, 40), np.float32); img[:, 20:] = 100
    >>> g = compute_gradients(img)
    >>> float(g.magnitude[20, 19]), float(g.magnitude[20, 5])
    (1600.0, 0.0)

    The same step in three equal channels: the same magnitude and direction.

    >>> c = compute_gradients(np.dstack([img] * 3))
    >>> float(c.magnitude[20, 19]), float(c.gx[20, 19]), float(c.gy[20, 19]), c.image.shape
    (1600.0, 1600.0, 0.0, (40, 40))

    Green to red at the same grey level: no grey edge, a colour edge, its
    sign that of red (which changes most, rising to the right).

    >>> bgr = np.zeros((40, 40, 3), np.float32)
    >>> bgr[:, :20] = (0, 100, 0); bgr[:, 20:] = (0, 0, 100 * 0.587 / 0.299)
    >>> grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    >>> round(float(compute_gradients(grey).magnitude[20, 19]))
    0
    >>> c = compute_gradients(bgr)
    >>> round(float(c.magnitude[20, 19])), round(float(c.gx[20, 19])), float(c.gy[20, 19])
    (2035, 2035, 0.0)
    """
    small, fx, fy = scale_image(gray, factor)
    if small.ndim == 3:
        return _colour_gradients(small, fx, fy, gray.shape[:2], equalize, metric)
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


#: Gaussian sigma, in full-resolution pixels, of what :func:`colour_metric`'s
#: weighting adds to a colour image's derivatives (its gain over 1, along the
#: colour directions): JPEG and most cameras sample colour every second pixel
#: (4:2:0, a Bayer mosaic), so colour detail finer than that is their noise and
#: block edges, which a gain of up to ``Config.colour_boost`` would raise to the
#: texture's strength (a rectangle found on the block grid inside its own
#: paint). Chosen on the tune parts (bench_colour.py, bench_robosub.py): 1 px
#: found 3 more of 576 coloured markers and 10 % more buoys in colour at
#: unchanged settings; 2 px lost thin gate posts (their two borders merge).
CHROMA_SIGMA = 1.0


def colour_metric(gxc: np.ndarray, gyc: np.ndarray, boost: float) -> np.ndarray | None:
    """The channel weighting of a colour image measured in its own units.

    ``gxc``, ``gyc``: the image's per-channel derivatives (HxWx3). Returns
    the symmetric 3x3 matrix ``W = V diag(g) V^T``, where ``V, lam`` are the
    eigenvectors and eigenvalues of the channels' gradient covariance (the
    mean of ``d d^T`` over the pixels and both derivatives) and
    ``g_i = sqrt(lam_max / max(lam_i, lam_max / boost^2))``: the direction in
    colour space along which the image changes most (on a seabed, mostly
    brightness: its texture) keeps its units, the others are amplified to
    the same spread, by at most ``boost``. An edge that changes colour where
    the texture does not (a painted marker whose grey level the water has
    made the sand's) then weighs as much as the texture's strongest. None
    when ``boost <= 1`` or the image has no gradient.

    Examples
    --------
    Grey texture and one step from green to red: the texture's direction
    (grey) keeps its gain of 1, the colour directions get the largest.

    >>> rng = np.random.default_rng(0)
    >>> t = rng.normal(0, 20, (60, 60)).astype(np.float32)
    >>> img = np.dstack([t, t, t]) + 100
    >>> img[:, 30:, 1] -= 30; img[:, 30:, 2] += 30
    >>> gx = cv2.Scharr(img, cv2.CV_32F, 1, 0); gy = cv2.Scharr(img, cv2.CV_32F, 0, 1)
    >>> W = colour_metric(gx, gy, 4.0)
    >>> grey = np.ones(3) / np.sqrt(3)
    >>> round(float(grey @ W @ grey), 2), round(float(np.linalg.eigvalsh(W).max()), 2)
    (1.0, 4.0)
    """
    if boost <= 1.0:
        return None
    # (every other row and column: the statistics of a whole image, at a
    # quarter of the cost; summed in float64, the same bits on every machine)
    dx = gxc[::2, ::2, :3].reshape(-1, 3).astype(np.float64)
    dy = gyc[::2, ::2, :3].reshape(-1, 3).astype(np.float64)
    cov = (dx.T @ dx + dy.T @ dy) / max(2 * dx.shape[0], 1)
    if not np.isfinite(cov).all():
        return None
    lam, vec = np.linalg.eigh(cov)
    top = float(lam.max())
    if not top > 0.0:
        return None
    gain = np.sqrt(top / np.maximum(lam, top / (boost * boost)))
    return ((vec * gain) @ vec.T).astype(np.float32)


def _colour_gradients(small: np.ndarray, fx: float, fy: float, full_shape,
                      equalize: bool, metric=None) -> Gradients:
    """:func:`compute_gradients` of a working BGR image (see there)."""
    if equalize:
        clahe = cv2.createCLAHE(clipLimit=2.0, tileGridSize=(8, 8))
        small = np.dstack([clahe.apply(np.clip(small[:, :, i], 0, 255).astype(np.uint8))
                           for i in range(3)])
    small = np.ascontiguousarray(small[:, :, :3], dtype=np.float32)   # (BGRA: no alpha)
    gxc = cv2.Scharr(small, cv2.CV_32F, 1, 0, borderType=cv2.BORDER_REPLICATE)
    gyc = cv2.Scharr(small, cv2.CV_32F, 0, 1, borderType=cv2.BORDER_REPLICATE)
    if metric is not None:
        metric = (colour_metric(gxc, gyc, float(metric)) if np.ndim(metric) == 0
                  else np.asarray(metric, np.float32).reshape(3, 3))
    # the sign (below) is taken from the channels as they are; the tensor
    # from the weighted ones
    if metric is None:
        wxc, wyc = gxc, gyc
    else:   # the channels as they are, plus what the weighting adds, smoothed
        sigma = CHROMA_SIGMA * min(fx, fy)
        extra = metric - np.eye(3, dtype=np.float32)
        wxc, wyc = cv2.transform(gxc, extra), cv2.transform(gyc, extra)
        if sigma >= 0.3:   # (below, a kernel of weights ~(0, 1, 0))
            wxc = cv2.GaussianBlur(wxc, (0, 0), sigma, borderType=cv2.BORDER_REPLICATE)
            wyc = cv2.GaussianBlur(wyc, (0, 0), sigma, borderType=cv2.BORDER_REPLICATE)
        wxc += gxc
        wyc += gyc
    bx, gx_, rx = wxc[:, :, 0], wxc[:, :, 1], wxc[:, :, 2]
    by, gy_, ry = wyc[:, :, 0], wyc[:, :, 1], wyc[:, :, 2]
    # (float32 numpy, in place where it can be: a third of the time of a plain
    # version with arctan2; still about 2 ms at 320x240, against 0.1 for grey)
    third = np.float32(1.0 / 3.0)
    a = bx * bx; a += gx_ * gx_; a += rx * rx; a *= third     # the structure tensor
    b = bx * by; b += gx_ * gy_; b += rx * ry; b *= third     # [[a, b], [b, c]]
    c = by * by; c += gy_ * gy_; c += ry * ry; c *= third
    half = a - c
    half *= np.float32(0.5)
    r = half * half
    r += b * b
    np.sqrt(r, out=r)
    mag = a
    mag += c
    mag *= np.float32(0.5)
    mag += r                                   # the largest eigenvalue
    np.sqrt(np.maximum(mag, 0, out=mag), out=mag)
    # its eigenvector (ux, uy): (half + r, b) or (b, r - half), whichever is
    # the longer (both are, unless one is zero)
    up = half >= 0
    ux, uy = np.where(up, half + r, b), np.where(up, b, r - half)
    norm = np.hypot(ux, uy)
    norm[norm == 0] = 1.0
    ux /= norm
    uy /= norm
    # polarity: the sign of sum_c d_c |d_c|, d_c channel c's derivative along it
    total = np.zeros_like(mag)
    for i in range(3):
        cx, cy = gxc[:, :, i], gyc[:, :, i]
        d = cx * ux
        d += cy * uy
        d *= np.abs(d)
        total += d
    mag_s = np.where(total < 0, -mag, mag)
    gx = np.ascontiguousarray(mag_s * ux, dtype=np.float32)
    gy = np.ascontiguousarray(mag_s * uy, dtype=np.float32)
    grey = cv2.cvtColor(small, cv2.COLOR_BGR2GRAY)
    return Gradients(grey, gx, gy, mag, fx, fy, tuple(full_shape), metric)
