"""Survey sequences over a seabed in relief: views that differ by parallax.

A flat photo cut at two poses differs by a similarity; a real seabed does
not. Here a photo is draped over a smooth random height field (tens of
centimetres) and seen by a downward pinhole camera 1.5-3 m above it, moving
16-29 % of the frame between frames, with its strobe fixed to it: near bumps
are brighter, far hollows darker, and the light moves with the camera. The
water (:class:`~seahough.sim.Water`) absorbs along the light's path (twice
the camera-to-seabed distance) and adds its veiling light; blur, noise, snow
and JPEG follow as in :func:`~seahough.sim.apply_water`.

Ground truth is exact: every pixel of one frame is cast onto the seabed and
projected into the other (:meth:`ReliefTruth.flow`), and the similarity a
trajectory needs is the least-squares fit to that flow
(:meth:`ReliefTruth.similarity`); its residual is the parallax that no single
similarity explains.

Conventions: world X, Y on the mean seabed (metres), Z up; the seabed is at
height ``h(X, Y)`` (mean 0); the camera looks straight down from altitude
``A`` above the mean seabed, its image x axis at angle ``yaw`` from world X.
Occlusion is not modelled (the height field is smooth and seen from above).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import ParameterError
from ._util import ImageLike, Shape, _check_shape, _seed_of
from ._views import _as_photo
from .backgrounds import _source_photo
from .water import Water, WaterLike, _as_water, apply_water

__all__ = ["ReliefTruth", "relief_sequence"]

_ITERATIONS = 8          # fixed-point steps of the ray / height-field intersection


@dataclass
class ReliefTruth:
    """The camera path and the seabed of a :func:`relief_sequence`.

    Attributes
    ----------
    cameras : ndarray (n, 4)
        Per frame: X, Y (metres), altitude above the mean seabed (metres),
        yaw (radians).
    focal : float
        Focal length in pixels (principal point at the frame centre).
    shape : (int, int)
        Frame (height, width).
    heights : ndarray
        The height field (metres) on a grid of ``cell`` metres from
        ``origin`` (X, Y of cell (0, 0)).
    cell : float
    origin : (float, float)
    """

    cameras: np.ndarray
    focal: float
    shape: tuple[int, int]
    heights: np.ndarray
    cell: float
    origin: tuple[float, float]

    def _axes(self, i):
        X, Y, A, yaw = self.cameras[i]
        xc = np.array([math.cos(yaw), math.sin(yaw)])
        yc = np.array([math.sin(yaw), -math.cos(yaw)])
        return X, Y, A, xc, yc

    def height_at(self, X, Y) -> np.ndarray:
        """Seabed height (metres) at world points (bilinear on the grid)."""
        gx = ((np.asarray(X, np.float32) - self.origin[0]) / self.cell).astype(np.float32)
        gy = ((np.asarray(Y, np.float32) - self.origin[1]) / self.cell).astype(np.float32)
        shape, n = gx.shape, gx.size
        if gx.ndim != 2 or max(shape) >= 32767:   # (remap's maps: 2-D, sides < 32767)
            cols = 1024
            pad = -n % cols
            gx = np.concatenate([gx.ravel(), np.zeros(pad, np.float32)]).reshape(-1, cols)
            gy = np.concatenate([gy.ravel(), np.zeros(pad, np.float32)]).reshape(-1, cols)
        out = cv2.remap(self.heights, gx, gy, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        return out.ravel()[:n].reshape(shape)

    def ground(self, i: int, u, v):
        """World (X, Y, Z) of frame ``i``'s pixels (u, v), cast onto the seabed."""
        X0, Y0, A, xc, yc = self._axes(i)
        h, w = self.shape
        a = (np.asarray(u, np.float64) - (w - 1) / 2) / self.focal
        b = (np.asarray(v, np.float64) - (h - 1) / 2) / self.focal
        dx, dy = a * xc[0] + b * yc[0], a * xc[1] + b * yc[1]
        t = np.full(a.shape, A)
        for _ in range(_ITERATIONS):   # depth t along the axis: Z = A - t = h(X, Y)
            t = A - self.height_at(X0 + t * dx, Y0 + t * dy)
        return X0 + t * dx, Y0 + t * dy, A - t

    def project(self, j: int, X, Y, Z):
        """Frame ``j``'s pixel (u, v) of world points."""
        X0, Y0, A, xc, yc = self._axes(j)
        h, w = self.shape
        t = A - Z
        rx, ry = X - X0, Y - Y0
        u = self.focal * (rx * xc[0] + ry * xc[1]) / t + (w - 1) / 2
        v = self.focal * (rx * yc[0] + ry * yc[1]) / t + (h - 1) / 2
        return u, v

    def flow(self, i: int, j: int, step: int = 8):
        """True correspondences: frame ``i`` pixels on a ``step`` grid, and
        where they are in frame ``j`` (only those inside frame ``j``).
        Returns two (n, 2) arrays."""
        h, w = self.shape
        v, u = np.mgrid[0:h:step, 0:w:step].astype(np.float64)
        u, v = u.ravel(), v.ravel()
        uj, vj = self.project(j, *self.ground(i, u, v))
        inside = (uj >= 0) & (uj <= w - 1) & (vj >= 0) & (vj <= h - 1)
        return (np.stack([u[inside], v[inside]], 1), np.stack([uj[inside], vj[inside]], 1))

    def similarity(self, i: int, j: int) -> tuple[np.ndarray, float]:
        """The similarity (2x3, frame ``i`` pixel -> frame ``j`` pixel) that
        fits the true flow best (least squares over the overlap), and the RMS
        of what it leaves (the parallax, in pixels)."""
        p, q = self.flow(i, j)
        if len(p) < 10:
            raise ParameterError(f"frames {i} and {j} do not overlap")
        M = _fit_similarity(p, q)
        r = q - (p @ M[:, :2].T + M[:, 2])
        return M, float(np.sqrt((r ** 2).sum(1).mean()))


def _fit_similarity(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Least-squares similarity p -> q (Umeyama, no reflection)."""
    mp, mq = p.mean(0), q.mean(0)
    a, b = p - mp, q - mq
    s_xx = (a ** 2).sum()
    c = (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]).sum() / s_xx
    s = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum() / s_xx
    R = np.array([[c, -s], [s, c]])
    return np.hstack([R, (mq - R @ mp)[:, None]])


def _height_field(rng, extent, cell, relief, corr):
    """A smooth random height field (std ``relief`` m, correlation ``corr`` m)."""
    nx, ny = (int(math.ceil(e / cell)) + 1 for e in extent)
    noise = rng.standard_normal((ny, nx)).astype(np.float32)
    hf = cv2.GaussianBlur(noise, (0, 0), corr / cell, borderType=cv2.BORDER_REFLECT)
    hf -= hf.mean()
    return (hf * (relief / max(float(hf.std()), 1e-9))).astype(np.float32)


def relief_sequence(image: ImageLike | None = None, *, n_frames: int = 6,
                    frame_size: Shape = (1024, 1360), altitude=(1.5, 3.0),
                    relief: float = 0.15, correlation: float = 0.4,
                    step=(0.16, 0.29), turn: float = 4.0, fov: float = 50.0,
                    water: WaterLike = "moderate", seed: int = 0, source="auto"):
    """Frames of a downward camera flying over a photo draped on relief.

    Parameters
    ----------
    image : ndarray, path or None
        The seabed photo; None = a random real photo (``source``), else a
        procedural seabed.
    n_frames : int
        Number of frames (>= 2).
    frame_size : (int, int)
        ``(height, width)``.
    altitude : (float, float)
        The range of the camera's altitude above the mean seabed, metres
        (drawn once, then wandering by a few per cent a frame).
    relief : float
        Standard deviation of the seabed height, metres (0: flat).
    correlation : float
        Size of the bumps (Gaussian correlation length), metres.
    step : (float, float)
        Range of the motion between consecutive frames, as a share of the
        frame's extent along the motion.
    turn : float
        Standard deviation of the heading change a frame, degrees.
    fov : float
        Horizontal field of view, degrees.
    water : Water, str or None
        The water; its ``distance`` is replaced by the true light path.
    seed : int
    source : str or path
        Where the photo comes from when ``image`` is None.

    Returns
    -------
    frames : list of ndarray
        uint8 BGR frames.
    truth : ReliefTruth

    Examples
    --------
    >>> frames, truth = relief_sequence(n_frames=2, frame_size=(96, 128), seed=1,
    ...                                 source="procedural", water=None)
    >>> len(frames), frames[0].shape
    (2, (96, 128, 3))
    >>> M, parallax = truth.similarity(0, 1)
    >>> bool(parallax > 0.05)            # relief: no similarity fits exactly
    True
    >>> _, flat = relief_sequence(n_frames=2, frame_size=(96, 128), seed=1, relief=0.0,
    ...                           source="procedural", water=None)
    >>> bool(flat.similarity(0, 1)[1] < 1e-6)
    True
    """
    n = int(n_frames)
    if n < 2:
        raise ParameterError(f"n_frames must be >= 2, got {n_frames!r}")
    h, w = _check_shape(frame_size, "frame_size")
    a0, a1 = (float(v) for v in altitude)
    s0, s1 = (float(v) for v in step)
    if not 0 < a0 <= a1:
        raise ParameterError(f"altitude must be a range of positive metres, got {altitude!r}")
    if not 0 <= s0 <= s1 < 0.8:
        raise ParameterError(f"step must be a range within [0, 0.8), got {step!r}")
    if relief < 0 or correlation <= 0:
        raise ParameterError("relief must be >= 0 and correlation > 0")
    if relief > 0.25 * a0:
        raise ParameterError(f"relief {relief} m is too rough for an altitude of {a0} m")
    rng = np.random.default_rng(seed)
    focal = (w / 2) / math.tan(math.radians(fov) / 2)
    # the path: heading and yaw wander; each step a share of the frame's extent
    alt = float(rng.uniform(a0, a1))
    heading = float(rng.uniform(0, 2 * math.pi))
    yaw = heading + float(rng.uniform(-math.pi, math.pi))
    cams = []
    X = Y = 0.0
    for k in range(n):
        cams.append((X, Y, alt, yaw))
        rel = heading - yaw       # the motion's direction in the frame
        extent = abs(math.cos(rel)) * w + abs(math.sin(rel)) * h
        d = float(rng.uniform(s0, s1)) * extent * alt / focal
        X, Y = X + d * math.cos(heading), Y + d * math.sin(heading)
        dturn = math.radians(float(rng.normal(0, turn)))
        heading += dturn
        yaw += dturn
        alt = float(np.clip(alt * (1 + rng.normal(0, 0.03)), a0 * 0.9, a1 * 1.1))
    cams = np.array(cams)
    # the ground seen: footprint corners of every frame, with a margin
    half = np.hypot(w, h) / 2 / focal * (cams[:, 2].max() + 3 * relief)
    lo = cams[:, :2].min(0) - half * 1.05
    hi = cams[:, :2].max(0) + half * 1.05
    extent = hi - lo
    cell = 0.01
    heights = _height_field(rng, extent, cell, relief, correlation)
    truth = ReliefTruth(cams, focal, (h, w), heights, cell, (float(lo[0]), float(lo[1])))
    photo = _as_photo(image)
    if photo is None:
        photo = _source_photo(rng, source)
    if photo is None:
        from .backgrounds import seabed
        photo = seabed((max(h, 480), max(w, 640)), seed=_seed_of(rng))
    if photo.ndim == 2:
        photo = cv2.cvtColor(photo, cv2.COLOR_GRAY2BGR)
    ph, pw = photo.shape[:2]
    metres_per_px = max(extent[0] / pw, extent[1] / ph)   # the photo covers the ground
    wat = _as_water(water)
    frames = [_render(truth, i, photo, lo, metres_per_px, wat, rng) for i in range(n)]
    return frames, truth


def _render(truth: ReliefTruth, i: int, photo, lo, mpp, wat: Water | None, rng):
    h, w = truth.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    X, Y, Z = truth.ground(i, u, v)
    mx = ((X - lo[0]) / mpp).astype(np.float32)
    my = ((Y - lo[1]) / mpp).astype(np.float32)
    img = cv2.remap(photo, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    img = img.astype(np.float32)
    X0, Y0, A, xc, yc = truth._axes(i)
    # strobe on the camera: inverse square of the distance, Lambert on the slope
    r = np.sqrt((X - X0) ** 2 + (Y - Y0) ** 2 + (A - Z) ** 2).astype(np.float32)
    gy, gx = np.gradient(truth.height_at(X, Y).astype(np.float32))
    # (slopes per pixel -> per metre: a pixel spans about r / focal metres)
    per_m = truth.focal / np.maximum(r, 1e-3)
    nx, ny = -gx * per_m, -gy * per_m
    # the light's direction along the frame's axes (the slopes are along them)
    lx = ((X0 - X) * xc[0] + (Y0 - Y) * xc[1]) / r
    ly = ((X0 - X) * yc[0] + (Y0 - Y) * yc[1]) / r
    lz = (A - Z) / r
    lambert = np.clip((nx * lx + ny * ly + lz) / np.sqrt(nx ** 2 + ny ** 2 + 1), 0.05, 1.0)
    light = (lambert * (A / r) ** 2).astype(np.float32)
    if wat is not None:
        att = np.asarray(wat.attenuation, np.float32)
        bs = np.asarray(wat.backscatter, np.float32)
        t = np.exp(-att[None, None, :] * (2 * r)[:, :, None])
        img = img * light[:, :, None] * t + bs * (1 - np.exp(-att[None, None, :] * r[:, :, None]))
        rest = dataclasses.replace(wat, attenuation=(0.0, 0.0, 0.0), distance=0.0, strobe=0.0)
        return apply_water(np.clip(img, 0, 255).astype(np.uint8), rest, _seed_of(rng))
    return np.clip(img * light[:, :, None], 0, 255).astype(np.uint8)
