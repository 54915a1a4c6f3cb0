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
height ``h(X, Y)`` (mean 0); the camera is at altitude ``A`` above the mean
seabed, its image x axis horizontal at angle ``yaw`` from world X; it looks
straight down, or tilted forward by ``tilt`` degrees (its optical axis
leaning towards the top of the image: a forward-oblique camera, as on an ROV
or a pool robot, whose frames differ by a perspective change even over a
flat floor). Occlusion is not modelled (the height field is smooth and seen
from above).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import ParameterError
from ..geometry import fit_similarity
from ._util import ImageLike, Shape, _check_shape, _seed_of
from ._views import _as_photo
from .backgrounds import _source_photo, tiled_floor
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
    tilt : float
        The camera's forward tilt from straight down, degrees (0: downward).
    """

    cameras: np.ndarray
    focal: float
    shape: tuple[int, int]
    heights: np.ndarray
    cell: float
    origin: tuple[float, float]
    tilt: float = 0.0

    def _axes(self, i):
        """Camera ``i``'s centre and its horizontal x and y axes (2-vectors)."""
        X, Y, A, yaw = self.cameras[i]
        xc = np.array([math.cos(yaw), math.sin(yaw)])
        yc = np.array([math.sin(yaw), -math.cos(yaw)])
        return X, Y, A, xc, yc

    def _basis(self, i):
        """Camera ``i``'s image x, image y and optical axes in the world (3-vectors):
        the downward camera's, turned forward by :attr:`tilt` about its x axis."""
        _, _, _, xc, yc = self._axes(i)
        t = math.radians(self.tilt)
        ex = np.array([xc[0], xc[1], 0.0])
        ey = np.array([yc[0], yc[1], 0.0])
        ez = np.array([0.0, 0.0, -1.0])
        return ex, math.cos(t) * ey + math.sin(t) * ez, math.cos(t) * ez - math.sin(t) * ey

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
        X0, Y0, A, _, _ = self._axes(i)
        ex, ey, ez = self._basis(i)
        h, w = self.shape
        a = (np.asarray(u, np.float64) - (w - 1) / 2) / self.focal
        b = (np.asarray(v, np.float64) - (h - 1) / 2) / self.focal
        # the ray of depth t (along the optical axis) reaches t (a ex + b ey + ez)
        dx, dy = a * ex[0] + b * ey[0] + ez[0], a * ex[1] + b * ey[1] + ez[1]
        down = -(b * ey[2] + ez[2])   # metres of descent per unit of depth (> 0)
        t = A / down
        for _ in range(_ITERATIONS):   # Z = A - t down = h(X, Y)
            t = (A - self.height_at(X0 + t * dx, Y0 + t * dy)) / down
        return X0 + t * dx, Y0 + t * dy, A - t * down

    def project(self, j: int, X, Y, Z):
        """Frame ``j``'s pixel (u, v) of world points."""
        X0, Y0, A, _, _ = self._axes(j)
        ex, ey, ez = self._basis(j)
        h, w = self.shape
        rx, ry, rz = X - X0, Y - Y0, Z - A
        t = rx * ez[0] + ry * ez[1] + rz * ez[2]
        u = self.focal * (rx * ex[0] + ry * ex[1] + rz * ex[2]) / t + (w - 1) / 2
        v = self.focal * (rx * ey[0] + ry * ey[1] + rz * ey[2]) / t + (h - 1) / 2
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
        M = fit_similarity(p, q)
        r = q - (p @ M[:, :2].T + M[:, 2])
        return M, float(np.sqrt((r ** 2).sum(1).mean()))


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
                    water: WaterLike = "moderate", seed: int = 0, source="auto",
                    tilt: float = 0.0, forward: bool = False, strobe: bool = True):
    """Frames of a camera flying over a photo draped on relief.

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
        Where the photo comes from when ``image`` is None; ``"tiles"``: a
        pool floor (:func:`~seahough.sim.tiled_floor`, tiles 2.5-5 cm),
        drawn at the ground's resolution.
    tilt : float
        The camera's forward tilt from straight down, degrees (0-60; the top
        of the frame must still see the floor within 80 degrees of straight
        down).
    forward : bool
        Move towards the top of the frame (where a tilted camera looks),
        instead of in a random direction.
    strobe : bool
        Light from a strobe on the camera (falling off with the square of
        the distance); False: daylight from straight above (a pool).

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
    focal = (w / 2) / math.tan(math.radians(fov) / 2)
    top = math.degrees(math.atan((h - 1) / 2 / focal))   # the top row's angle off the axis
    if not (0.0 <= tilt <= 60.0 and tilt + top <= 80.0):
        raise ParameterError(f"tilt must be 0-60 degrees with the top of the frame within 80 "
                             f"degrees of straight down ({top:.0f} above the axis here), got "
                             f"{tilt!r}")
    rng = np.random.default_rng(seed)
    cos_t = math.cos(math.radians(tilt))
    # the path: heading and yaw wander; each step a share of the frame's extent
    alt = float(rng.uniform(a0, a1))
    heading = float(rng.uniform(0, 2 * math.pi))
    if forward:   # (the image's top, -y, points to yaw + 90 degrees in the world)
        yaw = heading - 0.5 * math.pi
    else:
        yaw = heading + float(rng.uniform(-math.pi, math.pi))
    cams = []
    X = Y = 0.0
    for k in range(n):
        cams.append((X, Y, alt, yaw))
        rel = heading - yaw       # the motion's direction in the frame
        extent = abs(math.cos(rel)) * w + abs(math.sin(rel)) * h
        # (the ground a pixel spans at the frame's centre: farther when tilted)
        d = float(rng.uniform(s0, s1)) * extent * alt / (focal * cos_t ** 2)
        X, Y = X + d * math.cos(heading), Y + d * math.sin(heading)
        dturn = math.radians(float(rng.normal(0, turn)))
        heading += dturn
        yaw += dturn
        alt = float(np.clip(alt * (1 + rng.normal(0, 0.03)), a0 * 0.9, a1 * 1.1))
    cams = np.array(cams)
    # the ground seen: footprint corners of every frame, with a margin
    if tilt == 0.0:
        half = np.hypot(w, h) / 2 / focal * (cams[:, 2].max() + 3 * relief)
        lo = cams[:, :2].min(0) - half * 1.05
        hi = cams[:, :2].max(0) + half * 1.05
    else:   # the corners cast onto the floor 3 relief deep
        flat = ReliefTruth(cams, focal, (h, w), np.full((2, 2), -3 * relief, np.float32),
                           1e6, (-5e5, -5e5), float(tilt))
        u = np.array([0.0, w - 1, 0.0, w - 1]) + np.array([-1, 1, -1, 1]) * 0.05 * w
        v = np.array([0.0, 0.0, h - 1, h - 1]) + np.array([-1, -1, 1, 1]) * 0.05 * h
        xy = np.concatenate([np.stack(flat.ground(i, u, v)[:2], 1) for i in range(n)])
        lo, hi = xy.min(0), xy.max(0)
    extent = hi - lo
    cell = 0.01
    heights = _height_field(rng, extent, cell, relief, correlation)
    truth = ReliefTruth(cams, focal, (h, w), heights, cell, (float(lo[0]), float(lo[1])),
                        float(tilt))
    photo = _as_photo(image)
    if photo is None and isinstance(source, str) and source == "tiles":
        tile_m = float(rng.uniform(0.025, 0.05))   # (10 photo pixels a tile)
        mpp = tile_m / 10.0
        photo = tiled_floor((int(math.ceil(extent[1] / mpp)), int(math.ceil(extent[0] / mpp))),
                            _seed_of(rng), tile=10.0)
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
    frames = [_render(truth, i, photo, lo, metres_per_px, wat, rng, strobe) for i in range(n)]
    return frames, truth


def _render(truth: ReliefTruth, i: int, photo, lo, mpp, wat: Water | None, rng,
            strobe: bool = True):
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
    if strobe:
        lx = ((X0 - X) * xc[0] + (Y0 - Y) * xc[1]) / r
        ly = ((X0 - X) * yc[0] + (Y0 - Y) * yc[1]) / r
        lz = (A - Z) / r
    else:   # daylight from above: no fall-off
        lx, ly, lz = 0.0, 0.0, 1.0
    lambert = np.clip((nx * lx + ny * ly + lz) / np.sqrt(nx ** 2 + ny ** 2 + 1), 0.05, 1.0)
    light = (lambert * (A / r) ** 2 if strobe else lambert).astype(np.float32)
    if wat is not None:
        att = np.asarray(wat.attenuation, np.float32)
        bs = np.asarray(wat.backscatter, np.float32)
        t = np.exp(-att[None, None, :] * (2 * r)[:, :, None])
        img = img * light[:, :, None] * t + bs * (1 - np.exp(-att[None, None, :] * r[:, :, None]))
        rest = dataclasses.replace(wat, attenuation=(0.0, 0.0, 0.0), distance=0.0, strobe=0.0)
        return apply_water(np.clip(img, 0, 255).astype(np.uint8), rest, _seed_of(rng))
    return np.clip(img * light[:, :, None], 0, 255).astype(np.uint8)
