"""Single scenes with exact ground truth: a marker on the seabed (and its
matched negative), a photo fragment, a pair of camera frames, a straight
rope and a curved one."""

from __future__ import annotations

import math
from pathlib import Path
from dataclasses import dataclass
from typing import Union

import cv2
import numpy as np

from ..errors import ParameterError
from ..geometry import apply_matrix, compose, invert_matrix, matrix_to_pose, pose_to_matrix
from ._util import (ImageLike, Shape, _centre, _check_range, _check_shape, _corners, _log_uniform,
                    _seed_of, _to_grey)
from ._views import _place_views, _render_view
from .backgrounds import background
from .markers import Truth, _pose_extent, marker, paste_pattern, random_pose
from .water import WaterLike, _water_per_frame, apply_water

__all__ = ["marker_scene", "negative_scene", "fragment_scene", "frame_pair", "rope_scene",
           "curved_rope_scene", "CurveTruth"]


def _occlusion_value(rng: np.random.Generator, occlusion) -> float:
    if np.ndim(occlusion) == 0:
        return float(occlusion)
    lo, hi = _check_range(occlusion, "occlusion")
    return float(rng.uniform(lo, hi)) if hi > lo else lo


def marker_scene(name: str = "board", shape: Shape = (480, 640), *,
                 scale_range: tuple[float, float] = (0.6, 1.6),
                 angle_range: tuple[float, float] = (0.0, 360.0),
                 occlusion: Union[float, tuple[float, float]] = (0.0, 0.2),
                 water: WaterLike = "moderate", seed: int = 0, size: int = 120,
                 source: Union[str, Path] = "auto") -> tuple[np.ndarray, np.ndarray, Truth]:
    """A seabed photo holding one docking marker at a random, known pose.

    Background (:func:`background`), pose (:func:`random_pose`, the whole
    marker inside the frame, 4 px margin), paste with silt occlusion
    (:func:`paste_pattern`), then water (:func:`apply_water`).
    :func:`negative_scene` with the same ``shape``, ``water``, ``seed`` and
    ``source`` gives the same background and water without the marker.

    Parameters
    ----------
    name : str
        One of :data:`MARKERS`.
    shape : (int, int)
        ``(height, width)`` of the scene.
    scale_range, angle_range : (float, float)
        Ranges of the marker's scale and angle (degrees).
    occlusion : float or (float, float)
        Hidden fraction, or a range to draw it from.
    water : Water, str or None
        Water conditions, preset name, or None for a clear scene.
    seed : int
        Seed of everything.
    size : int
        Marker size in pattern pixels (see :func:`marker`).
    source : str or path
        Background source (see :func:`background`).

    Returns
    -------
    scene : numpy.ndarray
        uint8 BGR scene.
    pattern : numpy.ndarray
        uint8 grey marker image (what a detector searches for).
    truth : Truth
        Pose of the marker (origin = pattern centre), corners, occluded.

    Examples
    --------
    >>> scene, pattern, truth = marker_scene("cross", (120, 160), seed=2, size=40,
    ...                                      source="procedural")
    >>> scene.shape, pattern.shape
    ((120, 160, 3), (48, 47))
    >>> 0.0 <= truth.occluded <= 0.2 and 0.6 <= truth.scale <= 1.6
    True
    """
    rng = np.random.default_rng(seed)
    bg_seed, water_seed, pose_seed, occ_seed = (_seed_of(rng) for _ in range(4))
    h, w = _check_shape(shape)
    pattern, mask = marker(name, size)
    bg = background((h, w), bg_seed, source)
    prng = np.random.default_rng(pose_seed)
    x, y, s, a = random_pose(prng, (h, w), pattern.shape, scale_range, angle_range, margin=4)
    occ = _occlusion_value(prng, occlusion)
    scene, truth = paste_pattern(bg, pattern, mask, x=x, y=y, scale=s, angle=a,
                                 occlusion=occ, seed=occ_seed)
    return apply_water(scene, water, water_seed), pattern, truth


def negative_scene(shape: Shape = (480, 640), water: WaterLike = "moderate", seed: int = 0,
                   source: Union[str, Path] = "auto") -> np.ndarray:
    """A seabed photo with no marker: background + water.

    Same background and water draws as :func:`marker_scene` with the same
    ``seed``, ``shape`` and ``source`` (a matched negative).

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` of the scene.
    water : Water, str or None
        Water conditions, preset name, or None for a clear scene.
    seed : int
        Seed of everything.
    source : str or path
        Background source (see :func:`background`).

    Returns
    -------
    numpy.ndarray
        uint8 BGR scene.

    Examples
    --------
    >>> negative_scene((120, 160), seed=2, source="procedural").shape
    (120, 160, 3)
    >>> clear = negative_scene((120, 160), water=None, seed=2, source="procedural")
    >>> scene, _, _ = marker_scene(shape=(120, 160), water=None, seed=2, source="procedural")
    >>> 0.0 < float((scene != clear).any(axis=2).mean()) < 0.5  # only the marker differs
    True
    """
    rng = np.random.default_rng(seed)
    bg_seed, water_seed = _seed_of(rng), _seed_of(rng)
    bg = background(_check_shape(shape), bg_seed, source)
    return apply_water(bg, water, water_seed)


def fragment_scene(image: ImageLike | None = None, *, size: Shape = (160, 160),
                   shape: Shape = (480, 640),
                   scale_range: tuple[float, float] = (0.75, 1.33),
                   angle_range: tuple[float, float] = (0.0, 360.0),
                   water: WaterLike = "moderate", seed: int = 0,
                   source: Union[str, Path] = "auto") -> tuple[np.ndarray, np.ndarray, Truth]:
    """A textured patch of a photo, and a rotated, rescaled, degraded view holding it.

    The scene is a camera view of the photo at scale ``rho`` and angle
    ``phi`` (the patch appears at that pose); the patch is an axis-aligned
    cut of the clear photo, chosen as the most textured (highest mean
    gradient magnitude) of 32 random candidates that fit inside the scene.
    Small photos are magnified as needed so that the scene has no border.

    Parameters
    ----------
    image : ndarray, path or None
        The photo; None = a random real photo (``source``), or a procedural
        seabed.
    size : (int, int)
        ``(height, width)`` of the patch.
    shape : (int, int)
        ``(height, width)`` of the scene.
    scale_range, angle_range : (float, float)
        Ranges of the patch's scale (log-uniform) and angle in the scene.
    water : Water, str or None
        Degradation of the scene (the patch stays clear).
    seed : int
        Seed of everything.
    source : str or path
        Where the photo comes from when ``image`` is None (see :func:`background`).

    Returns
    -------
    scene : numpy.ndarray
        uint8 BGR scene.
    patch : numpy.ndarray
        uint8 grey patch (the pattern).
    truth : Truth
        ``matrix`` patch pixel -> scene pixel, pose of the patch centre,
        ``corners``, ``occluded=0``.

    Examples
    --------
    >>> scene, patch, truth = fragment_scene(size=(32, 32), shape=(96, 128), seed=1,
    ...                                      source="procedural")
    >>> scene.shape, patch.shape, truth.occluded
    ((96, 128, 3), (32, 32), 0.0)
    >>> 0.75 <= truth.scale <= 1.33
    True
    """
    rng = np.random.default_rng(seed)
    h, w = _check_shape(shape)
    ph, pw = _check_shape(size, "size")
    lo, hi = _check_range(scale_range, "scale_range", positive=True)
    alo, ahi = _check_range(angle_range, "angle_range")
    rho = _log_uniform(rng, lo, hi)
    phi = float(rng.uniform(alo, ahi)) if ahi > alo else alo
    sc = _centre((h, w))
    # scene: virtual v -> rho R (v) + scene centre
    G_scene = pose_to_matrix(sc[0], sc[1], rho, phi, (0.0, 0.0))
    ex0, ex1, ey0, ey1 = _pose_extent((ph, pw), _centre((ph, pw)), rho, phi)
    if ex1 - ex0 > w - 5 or ey1 - ey0 > h - 5:
        raise ParameterError(f"a {pw}x{ph} patch at scale {rho:.2f} does not fit in a "
                             f"{w}x{h} scene")
    photo, P = _place_views(rng, image, source, [(G_scene, (h, w))], orient=phi)
    F_scene = compose(G_scene, P)
    inv_G = invert_matrix(G_scene)
    # texture score on the photo at native resolution
    grey = cv2.cvtColor(photo, cv2.COLOR_BGR2GRAY)
    grey = cv2.GaussianBlur(grey, (0, 0), 1.0)
    gm = np.abs(cv2.Sobel(grey, cv2.CV_32F, 1, 0)) + np.abs(cv2.Sobel(grey, cv2.CV_32F, 0, 1))
    integ = cv2.integral(gm, sdepth=cv2.CV_64F)
    inv_P = invert_matrix(P)
    best, best_score = None, -1.0
    for _ in range(32):
        scx = rng.uniform(2 - ex0, w - 3 - ex1)
        scy = rng.uniform(2 - ey0, h - 3 - ey1)
        vc = apply_matrix(inv_G, [[scx, scy]])[0]
        o = np.round(vc - np.array(_centre((ph, pw))))
        pc = apply_matrix(inv_P, _corners((ph, pw)) + o)  # patch corners in the photo
        xa, ya = int(max(0, math.floor(pc[:, 0].min()))), int(max(0, math.floor(pc[:, 1].min())))
        xb = int(min(gm.shape[1], math.ceil(pc[:, 0].max()) + 1))
        yb = int(min(gm.shape[0], math.ceil(pc[:, 1].max()) + 1))
        if xb <= xa or yb <= ya:
            continue
        s = ((integ[yb, xb] - integ[ya, xb] - integ[yb, xa] + integ[ya, xa])
             / ((xb - xa) * (yb - ya)))
        # the rounded patch must still lie inside the scene
        cs = apply_matrix(G_scene, _corners((ph, pw)) + o)
        if cs.min() < 1 or cs[:, 0].max() > w - 2 or cs[:, 1].max() > h - 2:
            continue
        if s > best_score:
            best, best_score = o, s
    if best is None:
        raise ParameterError("could not place the patch inside the scene")
    T_patch = np.array([[1.0, 0.0, -best[0]], [0.0, 1.0, -best[1]]])  # virtual -> patch
    F_patch = compose(T_patch, P)
    patch = _to_grey(_render_view(photo, F_patch, (ph, pw)))
    scene = _render_view(photo, F_scene, (h, w))
    water_seed = _seed_of(rng)
    scene = apply_water(scene, water, water_seed)
    M = compose(G_scene, invert_matrix(T_patch))
    x, y, s, a = matrix_to_pose(M, _centre((ph, pw)))
    truth = Truth(matrix=M, x=x, y=y, scale=s, angle=a,
                  corners=apply_matrix(M, _corners((ph, pw))), occluded=0.0)
    return scene, patch, truth


def frame_pair(image: ImageLike | None = None, *, frame_size: Shape = (480, 640),
               shift: tuple[float, float] | None = None, angle: float | None = None,
               scale: float | None = None, max_shift: float = 0.4,
               angle_range: tuple[float, float] = (-20.0, 20.0),
               scale_range: tuple[float, float] = (0.9, 1.1),
               water: WaterLike = "moderate", seed: int = 0,
               source: Union[str, Path] = "auto") -> tuple[np.ndarray, np.ndarray, Truth]:
    """Two overlapping camera frames cut from one photo with a known motion.

    The motion maps previous-frame pixels to current-frame pixels::

        M = pose_to_matrix(cx + dx, cy + dy, scale, angle, origin=(cx, cy))

    with ``(cx, cy)`` the frame centre: the content at the centre of the
    previous frame appears at ``(cx + dx, cy + dy)`` in the current one,
    turned by ``angle`` (counter-clockwise as displayed) and magnified by
    ``scale`` (> 1: the camera came down). The previous frame is an
    axis-aligned cut; both frames lie entirely inside the photo (small photos
    are magnified as needed), and each gets its own water draw (noise, snow,
    strobe jitter; the strobe stays roughly fixed to the camera).

    Parameters
    ----------
    image : ndarray, path or None
        The photo; None = a random real photo (``source``), else a procedural
        seabed just large enough.
    frame_size : (int, int)
        ``(height, width)`` of the frames.
    shift : (float, float) or None
        ``(dx, dy)`` in pixels; None = uniform in
        ``[-max_shift * width, max_shift * width] x [-max_shift * height, ...]``.
    angle, scale : float or None
        Rotation (degrees) and scale change; None = drawn from
        ``angle_range`` (uniform) and ``scale_range`` (log-uniform).
    max_shift : float
        Largest random shift as a fraction of the frame size.
    water : Water, str or None
        Degradation of each frame.
    seed : int
        Seed of everything.
    source : str or path
        Where the photo comes from when ``image`` is None.

    Returns
    -------
    prev, cur : numpy.ndarray
        uint8 BGR frames.
    truth : Truth
        ``motion`` (= ``matrix``), ``x``, ``y``, ``scale``, ``angle`` (of the
        previous frame's centre, angle in [0, 360)), ``corners`` (the previous
        frame's corners in the current frame).

    Examples
    --------
    >>> prev, cur, truth = frame_pair(frame_size=(96, 128), shift=(10, -5), angle=5.0,
    ...                               scale=1.0, seed=0, source="procedural")
    >>> prev.shape, cur.shape
    ((96, 128, 3), (96, 128, 3))
    >>> [round(v, 3) for v in (truth.x - 63.5, truth.y - 47.5, truth.scale, truth.angle)]
    [10.0, -5.0, 1.0, 5.0]
    """
    rng = np.random.default_rng(seed)
    h, w = _check_shape(frame_size, "frame_size")
    if shift is None:
        if not 0 <= max_shift < 1:
            raise ParameterError(f"max_shift must be in [0, 1), got {max_shift!r}")
        dx = float(rng.uniform(-max_shift, max_shift) * w)
        dy = float(rng.uniform(-max_shift, max_shift) * h)
    else:
        dx, dy = (float(v) for v in shift)
    if angle is None:
        alo, ahi = _check_range(angle_range, "angle_range")
        angle = float(rng.uniform(alo, ahi))
    if scale is None:
        slo, shi = _check_range(scale_range, "scale_range", positive=True)
        scale = _log_uniform(rng, slo, shi)
    if scale <= 0:
        raise ParameterError(f"scale must be positive, got {scale!r}")
    c = _centre((h, w))
    M = pose_to_matrix(c[0] + dx, c[1] + dy, float(scale), float(angle), c)
    G_prev = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    G_cur = M.copy()
    photo, P = _place_views(rng, image, source, [(G_prev, (h, w)), (G_cur, (h, w))])
    prev = _render_view(photo, compose(G_prev, P), (h, w))
    cur = _render_view(photo, compose(G_cur, P), (h, w))
    w_prev, w_cur = _water_per_frame(rng, water, 2)
    s1, s2 = _seed_of(rng), _seed_of(rng)
    prev, cur = apply_water(prev, w_prev, s1), apply_water(cur, w_cur, s2)
    x, y, s, a = matrix_to_pose(M, c)
    truth = Truth(matrix=M, x=x, y=y, scale=s, angle=a,
                  corners=apply_matrix(M, _corners((h, w))), motion=M.copy())
    return prev, cur, truth


def rope_scene(shape: Shape = (480, 640), *, width: float = 8, angle: float | None = None,
               offset: float | None = None, water: WaterLike = "moderate", seed: int = 0,
               source: Union[str, Path] = "auto") -> tuple[np.ndarray, Truth]:
    """A bright twisted rope lying straight across the whole frame.

    Line convention (the detector must report the same): with ``a`` =
    ``line_angle`` in degrees, ``c = ((w-1)/2, (h-1)/2)`` the image centre,

    - direction ``d = (cos a, -sin a)`` (counter-clockwise from +x as
      displayed, y down), ``a`` in [0, 180);
    - unit normal ``n = (sin a, cos a)``;
    - ``line_offset = n . (p - c)`` for every point ``p`` on the centre line.

    So the centre line is ``{c + line_offset * n + t * d}``. For a horizontal
    rope (a = 0) ``n = (0, 1)``: positive offset = below the centre. For a
    vertical rope (a = 90) ``n = (1, 0)``: positive = right of the centre.
    In OpenCV's ``HoughLines`` terms, ``theta = radians(90 - a)`` and
    ``rho = line_offset + n . c`` (for a > 90, theta is negative: add pi
    and negate rho).

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` of the scene.
    width : float
        Rope diameter in pixels.
    angle, offset : float or None
        The line; None = uniform in [0, 180) and in
        ``[-0.35, 0.35] * min(height, width)``.
    water : Water, str or None
        Degradation.
    seed : int
        Seed of everything.
    source : str or path
        Background source (see :func:`background`).

    Returns
    -------
    scene : numpy.ndarray
        uint8 BGR scene.
    truth : Truth
        ``line_angle``, ``line_offset`` and ``x``, ``y`` = the point of the
        centre line nearest the image centre.

    Examples
    --------
    >>> scene, truth = rope_scene((96, 128), angle=30.0, offset=-10.0, seed=0,
    ...                           source="procedural")
    >>> scene.shape, truth.line_angle, truth.line_offset
    ((96, 128, 3), 30.0, -10.0)
    >>> round(truth.x, 2), round(truth.y, 2)
    (58.5, 38.84)
    """
    rng = np.random.default_rng(seed)
    h, w = _check_shape(shape)
    if width <= 0:
        raise ParameterError(f"width must be positive, got {width!r}")
    bg_seed, water_seed = _seed_of(rng), _seed_of(rng)
    a = float(rng.uniform(0, 180)) if angle is None else float(angle) % 180.0
    off = (float(rng.uniform(-0.35, 0.35) * min(h, w)) if offset is None else float(offset))
    bg = background((h, w), bg_seed, source)
    ar = math.radians(a)
    d = np.array([math.cos(ar), -math.sin(ar)], np.float32)
    n = np.array([math.sin(ar), math.cos(ar)], np.float32)
    cx, cy = _centre((h, w))
    xx = (np.arange(w, dtype=np.float32) - cx)[None, :]
    yy = (np.arange(h, dtype=np.float32) - cy)[:, None]
    s_full = xx * n[0] + yy * n[1] - np.float32(off)   # across, px from the centre line
    half = 0.5 * float(width)
    # only the band of the rope and its shadow changes
    ys, xs = np.nonzero((s_full > -half - 1.0) & (s_full < 3.5 * float(width) + 2.0))
    s = s_full[ys, xs]
    t = (xs - np.float32(cx)) * d[0] + (ys - np.float32(cy)) * d[1]  # along the rope
    tone = (np.array([200.0, 232.0, 246.0]) * rng.uniform(0.95, 1.03)).astype(np.float32)
    scene = apply_water(_paint_rope(bg, ys, xs, s, t, width, tone), water, water_seed)
    px, py = cx + off * float(n[0]), cy + off * float(n[1])
    truth = Truth(x=px, y=py, line_angle=a, line_offset=off)
    return scene, truth


def _paint_rope(bg: np.ndarray, ys, xs, s, t, width: float, tone, keep=None) -> np.ndarray:
    """``bg`` with a twisted rope painted at pixels ``(ys, xs)``, ``s`` px across its
    centre line (positive: its normal's side, where its faint shadow falls), ``t`` px
    along it; ``tone`` its BGR colour, ``keep`` (0-1) how much shows (0: buried)."""
    half = 0.5 * float(width)
    cover = np.clip(half + 0.5 - np.abs(s), 0.0, 1.0)
    if keep is not None:
        cover = cover * keep
    u = np.clip(s / max(half, 0.5), -1.0, 1.0)
    profile = np.sqrt(1.0 - 0.75 * u * u)  # round rope: darker at its sides
    period = max(3.0, 1.4 * float(width))
    strands = 0.86 + 0.14 * np.cos(np.float32(2 * math.pi / period) * (t + 0.9 * s))
    # a faint shadow beside the rope (light from the upper left)
    dim = 0.25 if keep is None else 0.25 * keep
    shadow = 1.0 - dim * np.exp(-((s - 0.9 * width) / max(width, 1.0)) ** 2)
    pix = bg[ys, xs].astype(np.float32) * (shadow * (1.0 - cover))[:, None]
    pix += (profile * strands * cover)[:, None] * tone
    img = bg.copy()
    img[ys, xs] = np.clip(np.rint(pix), 0, 255).astype(np.uint8)
    return img


@dataclass
class CurveTruth:
    """Ground truth of :func:`curved_rope_scene`: ``points`` (N, 2), the
    rope's centre line (x, y), a point a pixel along its whole drawn length
    (it may run out of the frame); ``visible`` (N,), inside the frame and
    not buried; ``width`` px; ``radius``, the smallest radius of curvature
    of the visible rope, px (``inf``: straight); ``polarity``."""

    points: np.ndarray
    visible: np.ndarray
    width: float
    radius: float
    polarity: str

    @property
    def length(self) -> float:
        """Visible length of the rope, px."""
        return float(np.count_nonzero(self.visible))


def _curve_path(rng: np.random.Generator, h: int, w: int, bend: float, form: str):
    """``(points, theta, kappa)`` of a smooth centre line through the middle
    of an ``h`` x ``w`` frame, 0.25 px steps, turning at most 90 degrees each
    way from its middle (a strong arc ends inside the frame, not in a loop)."""
    diag, step, k_max = math.hypot(h, w), 0.25, math.radians(bend) / 100.0
    x0, y0 = rng.uniform(0.3, 0.7) * (w - 1), rng.uniform(0.3, 0.7) * (h - 1)
    th0, sign = float(rng.uniform(0.0, 2.0 * math.pi)), float(rng.choice([-1.0, 1.0]))
    s = np.arange(0.0, 1.2 * diag, step)
    if form == "arc":
        kappa = lambda u: np.full_like(u, sign * k_max)
    else:  # a wave: the curvature swings from one side to the other
        period, phase = float(rng.uniform(0.8, 1.6)) * diag, float(rng.uniform(0.0, 2 * math.pi))
        kappa = lambda u: k_max * np.sin(2.0 * math.pi * u / period + phase)
    cum = lambda v: np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]))])  # trapezes
    halves = []
    for sg in (1.0, -1.0):
        k = kappa(sg * s)
        th = th0 + sg * step * cum(k)
        n = int(np.searchsorted(np.abs(th - th0) > math.pi / 2, True))
        th, k = th[:n], k[:n]
        halves.append((x0 + sg * step * cum(np.cos(th)), y0 - sg * step * cum(np.sin(th)), th, k))
    join = lambda j: np.r_[halves[1][j][::-1], halves[0][j][1:]]   # backwards, then on
    return np.stack([join(0), join(1)], 1), join(2), join(3)


def curved_rope_scene(shape: Shape = (480, 640), *, width: float = 8, bend: float = 20.0,
                      form: str = "random", polarity: str = "bright", buried: float = 0.0,
                      water: WaterLike = "moderate", seed: int = 0,
                      source: Union[str, Path] = "auto") -> tuple[np.ndarray, CurveTruth]:
    """A twisted rope lying in a smooth curve across the frame.

    The centre line passes through a random point of the frame's middle
    (0.3-0.7 of each side) in a random direction; its curvature is constant
    (``form="arc"``) or swings from one side to the other (``"wave"``, an
    S), at most ``bend`` degrees of turn per 100 px (radius of curvature
    ``100 / radians(bend)`` px: 286 px at 20, 95 px at 60). It turns at most
    90 degrees each way from that point (a strong arc ends inside the frame
    instead of closing a loop). The rope is drawn as :func:`rope_scene`
    draws it: round, twisted, a faint shadow on the side of its normal
    ``(-d_y, d_x)``, ``d`` its direction along ``points``.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` of the scene.
    width : float
        Rope diameter in pixels.
    bend : float
        Largest turn of its direction, degrees per 100 px (0: straight).
    form : {"random", "arc", "wave"}
        Shape of the curve (``"random"``: one of the two).
    polarity : {"bright", "dark"}
        A pale rope, or a dark cable.
    buried : float
        Share (0-0.6) of its visible length hidden under silt, in one gap
        (two when over 0.15) away from its ends.
    water, seed, source
        As for :func:`rope_scene`.

    Returns
    -------
    (scene, truth) : (numpy.ndarray, CurveTruth)
        uint8 BGR scene; the centre line and where it shows.

    Examples
    --------
    >>> scene, truth = curved_rope_scene((96, 128), width=6, bend=40, water=None, seed=1,
    ...                                  source="procedural")
    >>> scene.shape, truth.points.shape[1], truth.width, round(truth.radius)
    ((96, 128, 3), 2, 6.0, 143)
    >>> x, y = np.round(truth.points[truth.visible][10]).astype(int)
    >>> int(scene[y, x].mean()) > 150                   # bright on the centre line
    True
    """
    rng = np.random.default_rng(seed)
    h, w = _check_shape(shape)
    width, bend = float(width), float(bend)
    for ok, name, value, want in (
            (1.0 <= width <= 0.25 * min(h, w), "width", width, "1 px to a quarter of the shape"),
            (0.0 <= bend <= 180.0, "bend", bend, "0-180 degrees per 100 px"),
            (form in ("random", "arc", "wave"), "form", form, "random, arc or wave"),
            (polarity in ("bright", "dark"), "polarity", polarity, "bright or dark"),
            (0.0 <= float(buried) <= 0.6, "buried", buried, "0-0.6")):
        if not ok:  # (NaN fails the comparisons too)
            raise ParameterError(f"{name}={value!r}: must be {want}")
    bg_seed, water_seed, path_seed = _seed_of(rng), _seed_of(rng), _seed_of(rng)
    prng = np.random.default_rng(path_seed)
    form = form if form != "random" else ("arc" if prng.uniform() < 0.5 else "wave")
    fine, theta, kappa = _curve_path(prng, h, w, bend, form)
    # the centre line, one point a pixel, and where it shows
    pts, th, kp = fine[::4], theta[::4], kappa[::4]
    inside = (pts[:, 0] >= 0) & (pts[:, 0] <= w - 1) & (pts[:, 1] >= 0) & (pts[:, 1] <= h - 1)
    arc = np.arange(len(pts), dtype=np.float64)
    keep_t, idx = np.ones(len(pts)), np.flatnonzero(inside)
    if buried > 0 and idx.size > 8:
        n_gaps = 2 if buried > 0.15 else 1
        gap = float(buried) * idx.size / n_gaps
        lo = idx[0] + 0.1 * idx.size
        hi = max(idx[-1] - 0.1 * idx.size - gap, lo)
        starts = np.sort(prng.uniform(lo, hi, n_gaps))
        if n_gaps == 2 and starts[1] < starts[0] + gap + width:
            starts[1] = min(starts[0] + gap + width, hi)
        for a in starts:  # soft ends, a rope width long
            ramp = np.clip(np.minimum(arc - a, a + gap - arc) / width + 0.5, 0.0, 1.0)
            keep_t = np.minimum(keep_t, 1.0 - ramp)
    visible = inside & (keep_t > 0.5)
    bg = background((h, w), bg_seed, source)
    tone = np.array([200.0, 232.0, 246.0] if polarity == "bright" else [34.0, 38.0, 40.0])
    tone = (tone * rng.uniform(0.95, 1.03)).astype(np.float32)
    ip = np.round(pts).astype(np.int64)
    ok = (ip[:, 0] >= 0) & (ip[:, 0] < w) & (ip[:, 1] >= 0) & (ip[:, 1] < h)
    # pixels near the line: their nearest centre-line point (labels of a distance
    # transform, 1.. in row-major order of the seeds), then along and across it
    seeds, owner = np.full((h, w), 255, np.uint8), np.zeros((h, w), np.int64)
    seeds[ip[ok, 1], ip[ok, 0]], owner[ip[ok, 1], ip[ok, 0]] = 0, np.flatnonzero(ok)
    dist, lab = cv2.distanceTransformWithLabels(seeds, cv2.DIST_L2, 5,
                                                labelType=cv2.DIST_LABEL_PIXEL)
    ys, xs = np.nonzero(dist <= 3.5 * width + 4.5)
    i = owner[seeds == 0][lab[ys, xs] - 1]
    p = np.stack([xs, ys], 1).astype(np.float64)
    for _ in range(2):                          # to the foot of the perpendicular
        d = np.stack([np.cos(th[i]), -np.sin(th[i])], 1)
        ta = arc[i] + np.einsum("ij,ij->i", p - pts[i], d)
        i = np.clip(np.round(ta), 0, len(pts) - 1).astype(np.int64)
    n = np.stack([np.sin(th[i]), np.cos(th[i])], 1)
    d = np.stack([np.cos(th[i]), -np.sin(th[i])], 1)
    off = np.einsum("ij,ij->i", p - pts[i], d)
    s = (np.einsum("ij,ij->i", p - pts[i], n) + 0.5 * kp[i] * off * off).astype(np.float32)
    ta = arc[i] + off
    ends = np.clip(np.minimum(ta, arc[-1] - ta) + 0.5, 0.0, 1.0)
    keep = (np.interp(ta, arc, keep_t) * ends).astype(np.float32)
    img = _paint_rope(bg, ys, xs, s, ta.astype(np.float32), width, tone, keep)
    scene = apply_water(img, water, water_seed)
    vis_k = np.abs(kp[visible])
    radius = float(1.0 / vis_k.max()) if vis_k.size and vis_k.max() > 1e-9 else math.inf
    return scene, CurveTruth(points=pts.copy(), visible=visible, width=width, radius=radius,
                             polarity=polarity)
