"""Docking markers, and pasting a pattern into a scene at a known pose with
silt occlusion; :class:`Truth`, the ground truth of every synthetic scene."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from ..errors import ParameterError
from ..geometry import apply_matrix, pose_to_matrix
from ._util import (Shape, _centre, _check_range, _check_shape, _corners, _log_uniform, _noise,
                    _to_bgr, _to_grey, _to_uint8)

__all__ = ["MARKERS", "Truth", "marker", "random_pose", "paste_pattern"]

MARKERS: tuple[str, ...] = ("board", "rectangle", "L", "cross")
"""Names accepted by :func:`marker`."""

_DARK, _BRIGHT = 30.0, 242.0
_SS = 4  # supersampling factor for anti-aliased marker drawing

# board: 9x9 cells; dark border (cells 0, 8), bright frame (1, 7), dark gap
# (2, 6), and this asymmetric set of bright cells in the inner 3x3 block
_BOARD_CELLS = ((0, 0), (0, 1), (1, 2), (2, 0))


def _marker_rects(name: str, size: float) -> tuple[list[tuple[float, float, float, float]],
                                                   tuple[float, float]]:
    """Bright rectangles (x0, y0, x1, y1) of a marker, in shape units, and its (w, h)."""
    s = float(size)
    if name == "board":
        c = s / 9.0
        rects = [(c, c, 8 * c, 2 * c), (c, 7 * c, 8 * c, 8 * c),
                 (c, 2 * c, 2 * c, 7 * c), (7 * c, 2 * c, 8 * c, 7 * c)]
        for r, q in _BOARD_CELLS:
            rects.append(((3 + q) * c, (3 + r) * c, (4 + q) * c, (4 + r) * c))
        return rects, (s, s)
    if name == "rectangle":
        return [(0.0, 0.0, s, s / 1.6)], (s, s / 1.6)
    if name == "L":
        t = 0.3 * s
        return [(0.0, 0.0, t, s), (t, s - t, 0.68 * s, s)], (0.68 * s, s)
    if name == "cross":
        t = 0.22 * s
        up, left, right = 0.3 * s, 0.25 * s, 0.5 * s
        cx = left + t / 2.0
        cy = up + t / 2.0
        return [(cx - t / 2, 0.0, cx + t / 2, s),
                (0.0, cy - t / 2, cx + t / 2 + right, cy + t / 2)], (cx + t / 2 + right, s)
    raise ParameterError(f"unknown marker {name!r}; valid names: "
                         + ", ".join(repr(m) for m in MARKERS))


def _paint(value, name: str) -> np.ndarray:
    """A BGR paint: 3 numbers in 0-255, as a float32 array."""
    try:
        bgr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        bgr = np.zeros(0)
    if bgr.size != 3 or not np.all(np.isfinite(bgr)) or bgr.min() < 0 or bgr.max() > 255:
        raise ParameterError(f"{name} must be a (B, G, R) colour, 3 numbers in 0-255, "
                             f"got {value!r}")
    return bgr.astype(np.float32)


def marker(name: str = "board", size: int = 120, *, colour=None,
           dark=(30, 30, 30)) -> tuple[np.ndarray, np.ndarray]:
    """A flat docking marker on its own canvas.

    Bright (242) shapes on a dark (30) canvas, anti-aliased, with a margin of
    ``max(4, size // 20)`` px on every side. With ``colour``, a BGR image
    painted so that the colour is always at the marker's outline: the shapes
    in ``colour`` on a ``dark`` canvas; the board's panel in ``colour``, its
    frame and cells (bright in the grey board) and the canvas in ``dark``.

    - ``"board"``: an ArUco-like square tag: a dark panel with a bright square
      frame and four bright inner cells in an arrangement with no rotational
      or mirror symmetry; the mask is the whole panel square.
    - ``"rectangle"``: a plain bright rectangle, 1.6:1 (the paper's marker),
      landscape.
    - ``"L"``: an L with unequal arms (1.0 and 0.68 of ``size``, 0.3 thick).
    - ``"cross"``: a plus sign with four unequal arms (no symmetry).

    For all but the board the mask is the bright shape itself.

    Parameters
    ----------
    name : str
        One of :data:`MARKERS`.
    size : int
        Longest side of the shape in pixels (>= 16).
    colour : (B, G, R) or None
        Paint (0-255 each) where the marker meets its surroundings: the
        shapes, the board's panel; None = the grey marker.
    dark : (B, G, R)
        Paint of the canvas (and of the board's frame and cells) when
        ``colour`` is given.

    Returns
    -------
    image : numpy.ndarray
        uint8 grey canvas, or BGR with ``colour``.
    mask : numpy.ndarray
        uint8 coverage of the marker: 255 inside, 0 outside, anti-aliased
        (intermediate) along its border.

    Examples
    --------
    >>> image, mask = marker("L", 40)
    >>> image.shape, mask.shape
    ((48, 36), (48, 36))
    >>> int(image.min()), int(image.max()), int(mask.max())
    (30, 242, 255)
    >>> orange, mask2 = marker("L", 40, colour=(0, 120, 255))
    >>> orange.shape, orange[24, 8].tolist(), orange[0, 0].tolist(), bool((mask2 == mask).all())
    ((48, 36, 3), [0, 120, 255], [30, 30, 30], True)
    """
    paint = None if colour is None else _paint(colour, "colour")
    canvas = _paint(dark, "dark")
    if int(size) < 16:
        raise ParameterError(f"marker size must be >= 16 px, got {size!r}")
    size = int(size)
    rects, (sw, sh) = _marker_rects(name, size)
    m = max(4, size // 20)
    w, h = int(math.ceil(sw)) + 2 * m, int(math.ceil(sh)) + 2 * m
    ox, oy = (w - sw) / 2.0, (h - sh) / 2.0  # centre the shape on the canvas

    def render(rect_list) -> np.ndarray:
        big = np.zeros((h * _SS, w * _SS), np.uint8)
        for x0, y0, x1, y1 in rect_list:
            # in edge units (canvas pixel i spans [i, i + 1]) the shape spans
            # [ox, ox + sw]: its centre is the canvas centre ((w-1)/2 in pixels)
            a = (int(round((ox + x0) * _SS)), int(round((oy + y0) * _SS)))
            b = (int(round((ox + x1) * _SS)) - 1, int(round((oy + y1) * _SS)) - 1)
            cv2.rectangle(big, a, b, 255, -1)
        return cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0

    cover = render(rects)
    if name == "board":
        mask_cover = render([(0.0, 0.0, sw, sh)])
    else:
        mask_cover = cover
    if paint is None:
        image = _to_uint8(_DARK + (_BRIGHT - _DARK) * cover)
    else:
        # the paint is where the marker meets the seabed: the shapes, or the
        # board's panel around its (then dark) frame and cells
        painted = np.clip(mask_cover - cover, 0.0, 1.0) if name == "board" else cover
        c3 = painted[:, :, None]
        image = _to_uint8(canvas * (1.0 - c3) + paint * c3)
    # anti-aliased like the image, so a paste has its edge exactly where the
    # pattern's is (a binary mask would leave a dark rim inside the border)
    mask = _to_uint8(255.0 * mask_cover)
    return image, mask


# ----------------------------------------------------------------------------
# ground truth and pasting
# ----------------------------------------------------------------------------

@dataclass(eq=False)
class Truth:
    """Ground truth of a synthetic scene; fields that do not apply are None.

    Attributes
    ----------
    matrix : numpy.ndarray or None
        2x3 float matrix, pattern-image pixel -> scene pixel (for pairs: the
        same as ``motion``).
    x, y, scale, angle : float or None
        Pose of the pattern origin (equation 1); ``angle`` in degrees, [0, 360).
    corners : numpy.ndarray or None
        (4, 2) float: the pattern canvas corners (0,0), (w-1,0), (w-1,h-1),
        (0,h-1) mapped into the scene.
    occluded : float or None
        Fraction of the pattern's mask area hidden (by silt, or outside the
        frame).
    line_angle : float or None
        Rope direction in degrees, [0, 180), counter-clockwise from +x as
        displayed (see :func:`rope_scene`).
    line_offset : float or None
        Signed distance in px from the image centre to the rope's centre line
        (see :func:`rope_scene`).
    motion : numpy.ndarray or None
        2x3 matrix, previous-frame pixel -> current-frame pixel.

    Examples
    --------
    >>> t = Truth(x=12.0, y=5.0, scale=1.5, angle=30.0)
    >>> t.x, t.angle, t.line_angle
    (12.0, 30.0, None)
    """

    matrix: np.ndarray | None = None
    x: float | None = None
    y: float | None = None
    scale: float | None = None
    angle: float | None = None
    corners: np.ndarray | None = None
    occluded: float | None = None
    line_angle: float | None = None
    line_offset: float | None = None
    motion: np.ndarray | None = None


def _object_colour(pattern: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The object's own colour under a soft mask's border.

    Where the mask is partial, an anti-aliased pattern image holds a mix of
    the object and its canvas; pasting that through the same soft mask would
    count the canvas twice (a dark or bright rim). Replace those pixels by the
    mean of their fully covered neighbours, so the mask alone does the
    anti-aliasing.
    """
    full = (mask >= 255).astype(np.float32)
    part = (mask > 0) & (mask < 255)
    if not part.any() or not full.any():
        return pattern
    out = pattern.astype(np.float32).copy()
    p = out if out.ndim == 3 else out[:, :, None]
    for k in (3, 5, 9):
        wsum = cv2.blur(full, (k, k))
        vals = [cv2.blur(p[:, :, c] * full, (k, k)) for c in range(p.shape[2])]
        ok = part & (wsum > 0)
        for c in range(p.shape[2]):
            p[:, :, c][ok] = vals[c][ok] / wsum[ok]
        part = part & ~ok
        if not part.any():
            break
    return _to_uint8(out)


def _blend(under: np.ndarray, over: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """``under * (1 - alpha) + over * alpha`` for grey or multi-channel float32 images."""
    alpha = np.ascontiguousarray(alpha, dtype=np.float32)
    under = np.ascontiguousarray(under, dtype=np.float32)
    over = np.ascontiguousarray(over, dtype=np.float32)
    # cv2.blendLinear divides by (w1 + w2 + 1e-5): relative error 1e-5
    return cv2.blendLinear(under, over, 1.0 - alpha, alpha)


def _pose_extent(pattern_shape: Shape, origin, scale: float, angle: float
                 ) -> tuple[float, float, float, float]:
    """(xmin, xmax, ymin, ymax) of the warped canvas corners relative to (x, y)."""
    m = pose_to_matrix(0.0, 0.0, scale, angle, origin)
    c = apply_matrix(m, _corners(pattern_shape))
    return c[:, 0].min(), c[:, 0].max(), c[:, 1].min(), c[:, 1].max()


def random_pose(rng: np.random.Generator, scene_shape: Shape, pattern_shape: Sequence[int],
                scale_range: tuple[float, float] = (0.6, 1.6),
                angle_range: tuple[float, float] = (0.0, 360.0),
                margin: float = 0.0, origin: tuple[float, float] | None = None
                ) -> tuple[float, float, float, float]:
    """A random pose that keeps the whole warped pattern inside the scene.

    The scale is drawn log-uniformly in ``scale_range``, the angle uniformly in
    ``angle_range``, then ``(x, y)`` uniformly among positions where all four
    canvas corners land at least ``margin`` px inside the scene.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness.
    scene_shape, pattern_shape : sequence of int
        ``(height, width, ...)`` of the scene and of the pattern image.
    scale_range, angle_range : (float, float)
        Ranges of the scale and of the angle (degrees).
    margin : float
        Minimum distance in px between the warped canvas and the scene border.
    origin : (float, float) or None
        Pattern origin in pattern pixels; None = the pattern centre.

    Returns
    -------
    (x, y, scale, angle) : tuple of float
        Pose of the pattern origin; ``angle`` as drawn (not wrapped).

    Raises
    ------
    ParameterError
        When the pattern cannot fit at any drawn scale/angle.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x, y, scale, angle = random_pose(rng, (120, 160), (40, 40), margin=4)
    >>> 0.6 <= scale <= 1.6 and 0.0 <= angle <= 360.0
    True
    """
    sh, sw = _check_shape(scene_shape, "scene_shape")
    ph, pw = (int(v) for v in tuple(pattern_shape)[:2])
    lo, hi = _check_range(scale_range, "scale_range", positive=True)
    alo, ahi = _check_range(angle_range, "angle_range")
    org = _centre((ph, pw)) if origin is None else tuple(float(v) for v in origin)
    for _ in range(200):
        scale = _log_uniform(rng, lo, hi)
        angle = float(rng.uniform(alo, ahi)) if ahi > alo else alo
        x0, x1, y0, y1 = _pose_extent((ph, pw), org, scale, angle)
        xa, xb = margin - x0, sw - 1 - margin - x1
        ya, yb = margin - y0, sh - 1 - margin - y1
        if xa <= xb and ya <= yb:
            return float(rng.uniform(xa, xb)), float(rng.uniform(ya, yb)), scale, angle
    raise ParameterError(f"a {pw}x{ph} pattern at scale {scale_range} does not fit in a "
                         f"{sw}x{sh} scene with margin {margin}")


def _occluder(rng: np.random.Generator, mask_w: np.ndarray, target: float, size_px: float
              ) -> tuple[np.ndarray, tuple[int, int, int, int]]:
    """Silt blobs hiding ``target`` of the (soft) area of ``mask_w``.

    Returns the float32 alpha of the blobs over a region of interest and
    that region ``(y0, y1, x0, x1)``.
    """
    h, w = mask_w.shape
    inside = mask_w > 0.5
    ys, xs = np.nonzero(inside)
    if target <= 0 or len(xs) == 0:
        return np.zeros((0, 0), np.float32), (0, 0, 0, 0)
    pad = int(0.35 * size_px) + 4
    x0, x1 = max(0, xs.min() - pad), min(w, xs.max() + pad + 1)
    y0, y1 = max(0, ys.min() - pad), min(h, ys.max() + pad + 1)
    rh, rw = y1 - y0, x1 - x0
    roi_in = inside[y0:y1, x0:x1]
    cell = max(6.0, size_px / 3.5)
    field = _noise(rng, (rh, rw), cell) + 0.3 * _noise(rng, (rh, rw), max(3.0, cell / 4))
    # silt drifts in from one side: a ramp along a random direction
    d = rng.uniform(0, 2 * math.pi)
    yy, xx = np.mgrid[0:rh, 0:rw].astype(np.float32)
    cxm, cym = xs.mean() - x0, ys.mean() - y0
    ramp = ((xx - cxm) * math.cos(d) + (yy - cym) * math.sin(d)) / max(size_px, 1.0)
    field = field + 2.2 * ramp
    # keep blobs near the marker
    dist = cv2.distanceTransform((~roi_in).astype(np.uint8), cv2.DIST_L2, 3)
    field = field - (dist / max(0.1 * size_px, 2.0)) ** 2
    vals = field[roi_in]
    wts = mask_w[y0:y1, x0:x1]
    wsum = max(float(wts.sum()), 1e-6)
    # the blur below rounds the blobs: bisect the threshold so that the soft
    # coverage of the marker matches the target
    lo_t, hi_t = float(vals.min()) - 1e-3, float(vals.max())
    thr = float(np.quantile(vals, 1.0 - target))
    soft = None
    for _ in range(24):
        soft = cv2.GaussianBlur((field > thr).astype(np.float32), (0, 0), 1.0)
        got = float((soft * wts).sum() / wsum)
        if abs(got - target) < 0.002:
            break
        if got > target:
            lo_t = thr
        else:
            hi_t = thr
        thr = 0.5 * (lo_t + hi_t)
    return soft, (y0, y1, x0, x1)


def paste_pattern(background: np.ndarray, pattern: np.ndarray, mask: np.ndarray | None = None,
                  *, x: float, y: float, scale: float, angle: float,
                  occlusion: float = 0.0, seed: int = 0,
                  origin: tuple[float, float] | None = None) -> tuple[np.ndarray, Truth]:
    """Paste a pattern into a copy of a background at a known pose.

    The pattern is warped with ``cv2.warpAffine`` (bilinear) by
    ``pose_to_matrix(x, y, scale, angle, origin)`` and blended through its
    mask warped as float (anti-aliased edges). Then ``occlusion`` of the
    marker's area is hidden under silt: soft irregular blobs, drifting in
    from one side, filled with the background's own texture taken from a
    nearby offset.

    Parameters
    ----------
    background : numpy.ndarray
        Grey or BGR uint8 scene; the result has the same layout.
    pattern : numpy.ndarray
        Grey or BGR uint8 pattern image.
    mask : numpy.ndarray or None
        uint8 mask of the pattern's pixels (non-zero = pattern); None = the
        whole canvas.
    x, y, scale, angle : float
        Pose of the pattern origin (equation 1; degrees).
    occlusion : float
        Fraction (0-0.5) of the marker's area to hide.
    seed : int
        Seeds the silt blobs.
    origin : (float, float) or None
        Pattern origin in pattern pixels; None = ((w-1)/2, (h-1)/2).

    Returns
    -------
    scene : numpy.ndarray
        The composited image.
    truth : Truth
        ``matrix``, ``x``, ``y``, ``scale``, ``angle`` (wrapped to [0, 360)),
        ``corners`` and ``occluded``: the hidden fraction of the full mask
        area (silt-covered, plus any part falling outside the scene).

    Examples
    --------
    >>> pattern, mask = marker("rectangle", 32)
    >>> bg = np.full((100, 120), 90, np.uint8)
    >>> scene, truth = paste_pattern(bg, pattern, mask, x=60, y=50, scale=1.5, angle=30)
    >>> scene.shape, int(scene[50, 60]), int(scene[0, 0])
    ((100, 120), 242, 90)
    >>> round(truth.scale, 2), round(truth.angle, 1), round(truth.occluded, 3)
    (1.5, 30.0, 0.0)
    >>> _, silted = paste_pattern(bg, pattern, mask, x=60, y=50, scale=1.5, angle=30,
    ...                           occlusion=0.3, seed=1)
    >>> round(silted.occluded, 2)
    0.3
    """
    bg = _to_uint8(np.asarray(background))
    if bg.ndim not in (2, 3):
        raise ParameterError(f"background must be a grey or BGR image, got shape {bg.shape}")
    if not 0.0 <= float(occlusion) <= 0.5:
        raise ParameterError(f"occlusion must be in [0, 0.5], got {occlusion!r}")
    if scale <= 0:
        raise ParameterError(f"scale must be positive, got {scale!r}")
    colour = bg.ndim == 3
    if colour:
        bg = _to_bgr(bg)
        pat = _to_bgr(pattern)
    else:
        pat = _to_grey(pattern)
    ph, pw = pat.shape[:2]
    if mask is None:
        mk = np.full((ph, pw), 255, np.uint8)
    else:
        mk = np.asarray(mask)
        if mk.shape[:2] != (ph, pw):
            raise ParameterError(f"mask shape {mk.shape} does not match the pattern's {pat.shape}")
        mk = mk.reshape(ph, pw, -1)[:, :, 0].astype(np.uint8)
        pat = _object_colour(pat, mk)
    org = _centre((ph, pw)) if origin is None else (float(origin[0]), float(origin[1]))
    M = pose_to_matrix(x, y, scale, angle, org)
    h, w = bg.shape[:2]
    warped = cv2.warpAffine(pat, M, (w, h), flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REPLICATE).astype(np.float32)
    a = cv2.warpAffine(mk.astype(np.float32) * (1.0 / 255.0), M, (w, h),
                       flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    out = _blend(bg.astype(np.float32), warped, a)

    corners = apply_matrix(M, _corners((ph, pw)))
    in_frame = float(a.sum())
    if (corners.min() >= -0.5 and corners[:, 0].max() <= w - 0.5
            and corners[:, 1].max() <= h - 0.5):
        full_area, outside = in_frame, 0.0
    else:  # part of the pattern falls outside the scene: measure it on a padded canvas
        lo = np.floor(np.minimum(corners.min(axis=0), 0.0)) - 2
        hi = np.ceil(np.maximum(corners.max(axis=0), [w - 1, h - 1])) + 2
        Mp = M.copy()
        Mp[:, 2] -= lo
        size = (int(hi[0] - lo[0]) + 1, int(hi[1] - lo[1]) + 1)
        full_area = float(cv2.warpAffine(mk.astype(np.float32) * (1.0 / 255.0), Mp, size,
                                         flags=cv2.INTER_LINEAR).sum())
        outside = max(0.0, full_area - in_frame)
    covered = 0.0
    if occlusion > 0 and in_frame > 0:
        rng = np.random.default_rng(seed)
        target_px = occlusion * full_area - outside
        target = min(max(target_px / in_frame, 0.0), 0.95)
        alpha, (y0, y1, x0, x1) = _occluder(rng, a, target, math.sqrt(full_area))
        if y1 > y0 and x1 > x0:
            # silt texture: the background seen at a nearby offset, a bit blurred
            off = rng.uniform(0.6, 1.0) * math.sqrt(full_area) * 1.1
            d = rng.uniform(0, 2 * math.pi)
            T = np.array([[1.0, 0.0, -x0 + off * math.cos(d)],
                          [0.0, 1.0, -y0 + off * math.sin(d)]])
            tex = cv2.warpAffine(bg, T, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_REFLECT_101).astype(np.float32)
            tex = cv2.GaussianBlur(tex, (0, 0), 0.8) * np.float32(rng.uniform(0.92, 1.05))
            out[y0:y1, x0:x1] = _blend(out[y0:y1, x0:x1], tex, alpha)
            covered = float((alpha * a[y0:y1, x0:x1]).sum())
    occluded = 0.0 if full_area <= 0 else min(1.0, (outside + covered) / full_area)
    truth = Truth(matrix=M, x=float(x), y=float(y), scale=float(scale),
                  angle=float(angle) % 360.0, corners=corners,
                  occluded=float(occluded))
    return _to_uint8(out), truth
