"""Synthetic underwater scenes with exact ground truth.

Tests, benchmarks and the demo use this module to make photos in which the
answer is known exactly: a docking marker pasted at a known pose, a patch of
a photo seen again rotated and rescaled, two camera frames related by a known
similarity motion, a rope crossing the frame, a whole camera path.

Scenes are built from a background (a real seabed photo from the shared data
folder when it is there, else a procedural seabed), then degraded by water.

Image-formation model
---------------------
:func:`apply_water` turns a clear scene radiance ``J`` (what the camera
would see in air) into an underwater photo ``I``, per colour channel ``c``::

    t_c = exp(-attenuation_c * distance)          transmission
    I_c = J_c * t_c + B_c * (1 - t_c)             direct light + backscatter
    I   = I * (1 - strobe * (r / R)^2)            strobe / vignetting falloff
    I   = gaussian_blur(I, blur)                  forward scatter, defocus
    I   = I + N(0, noise^2)                       sensor noise
    I   = screen(I, marine-snow specks)           bright particles near the lens
    I   = jpeg(I, jpeg_quality)                   compression

Red is attenuated most, then green, then blue, so distant scenes turn
blue-green and lose contrast; ``r`` is the distance to the strobe centre and
``R`` the distance from that centre to the farthest image corner.

Geometry conventions are those of :mod:`seahough.geometry` (equation 1):
a 2x3 matrix maps pattern-image (or previous-frame) pixel coordinates to
scene (current-frame) pixel coordinates, exactly as ``cv2.warpAffine(src, M,
(w, h))`` takes it; pixel ``(0, 0)`` is the centre of the top-left pixel; x
right, y down; angles in degrees, positive = counter-clockwise as displayed.
Everything is deterministic given ``seed`` (``numpy.random.default_rng``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence, Union

import cv2
import numpy as np

from .._data import shared_data_dir
from ..errors import ImageReadError, ParameterError
from ..geometry import (apply_matrix, compose, invert_matrix, matrix_to_pose, pose_to_matrix,
                       rotation)

__all__ = [
    "MARKERS",
    "PRESETS",
    "Water",
    "Truth",
    "apply_water",
    "seabed",
    "background",
    "marker",
    "random_pose",
    "paste_pattern",
    "marker_scene",
    "negative_scene",
    "fragment_scene",
    "frame_pair",
    "rope_scene",
    "sequence",
]

MARKERS: tuple[str, ...] = ("board", "rectangle", "L", "cross")
"""Names accepted by :func:`marker`."""

PRESETS: tuple[str, ...] = ("clear", "moderate", "hard")
"""Names accepted by :meth:`Water.preset`."""

# Folders of the shared data that ``source="auto"`` never picks: the pool's
# tiles are long straight lines and clean rectangles, i.e. marker look-alikes.
_EXCLUDED_AUTO = ("subvo_pool_chain",)

Shape = tuple[int, int]
ImageLike = Union[np.ndarray, str, Path]
WaterLike = Union["Water", str, None]


class _ImageFileNotFound(ImageReadError, FileNotFoundError):
    """An image file that cannot be read (both ImageReadError and FileNotFoundError)."""


# ----------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------

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
    img = _to_uint8(np.asarray(img))
    if img.ndim == 2:
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    if img.ndim == 3 and img.shape[2] == 1:
        return cv2.cvtColor(img[:, :, 0], cv2.COLOR_GRAY2BGR)
    if img.ndim == 3 and img.shape[2] == 4:
        return cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
    if img.ndim == 3 and img.shape[2] == 3:
        return img
    raise ParameterError(f"expected a grey or BGR image, got an array of shape {img.shape}")


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


# ----------------------------------------------------------------------------
# procedural seabed
# ----------------------------------------------------------------------------

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


def _upsample(field: np.ndarray, shape: Shape) -> np.ndarray:
    """Bilinear upsampling of a low-resolution field to ``shape`` (pixel-centre aligned)."""
    h, w = shape
    return cv2.resize(field, (w, h), interpolation=cv2.INTER_LINEAR)


def _blob_polygons(rng: np.random.Generator, cx: np.ndarray, cy: np.ndarray, r: np.ndarray,
                   rough: float = 0.22, n: int = 48) -> np.ndarray:
    """Irregular closed outlines (pebbles, rocks), (N, n, 2) fixed-point (3 bits) int32."""
    k = len(r)
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)[None, :]
    rad = np.ones((k, n))
    for harm in range(2, 6):
        amp = rough / harm * rng.standard_normal((k, 1))
        rad += amp * np.cos(harm * t + rng.uniform(0, 2 * math.pi, (k, 1)))
    rad = np.clip(rad, 0.45, 1.6) * r[:, None]
    aspect = rng.uniform(0.55, 1.0, (k, 1))
    phi = rng.uniform(0, math.pi, (k, 1))
    px, py = rad * np.cos(t), aspect * rad * np.sin(t)
    c, s = np.cos(phi), np.sin(phi)
    x = cx[:, None] + c * px - s * py
    y = cy[:, None] + s * px + c * py
    return np.round(np.stack([x, y], axis=2) * 8).astype(np.int32)


def seabed(shape: Shape = (480, 640), seed: int = 0) -> np.ndarray:
    """Procedural seabed photo: rippled sand, pebbles, rocks and algae.

    Multi-scale texture (grain, ripples, stones from 1 to ~50 px, rock rims
    lit from one side, soft cast shadows, dark algae patches) gives plenty of
    short curved edges but no long straight lines nor rectangles, so it holds
    nothing that looks like a docking marker. Feature sizes are in pixels,
    independent of ``shape``: a larger seabed shows a larger area.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` in pixels.
    seed : int
        Seed of ``numpy.random.default_rng``; same seed, same image.

    Returns
    -------
    numpy.ndarray
        ``(height, width, 3)`` uint8 BGR image (the clear scene, before water).
    """
    h, w = _check_shape(shape)
    rng = np.random.default_rng(seed)
    area = h * w / (480.0 * 640.0)
    q = 4  # low-frequency fields are made at 1/q resolution
    lh, lw = max(2, -(-h // q)), max(2, -(-w // q))

    # --- low-frequency fields at 1/4 resolution ----------------------------
    lum_low = 0.10 * _noise(rng, (lh, lw), 110 / q) + 0.06 * _noise(rng, (lh, lw), 28 / q)
    phi = rng.uniform(0, math.pi)
    lam = rng.uniform(20, 38)
    yy, xx = np.mgrid[0:lh, 0:lw].astype(np.float32)
    # low-res pixel j covers full-res pixels [q j, q j + q): its centre is q j + (q - 1) / 2
    xs, ys = xx * q + (q - 1) / 2.0, yy * q + (q - 1) / 2.0
    phase_low = ((xs * math.cos(phi) + ys * math.sin(phi)) * np.float32(2 * math.pi / lam)
                 + 2.8 * _noise(rng, (lh, lw), 130 / q) + 0.9 * _noise(rng, (lh, lw), 40 / q))
    amp_low = np.clip(0.55 + 0.5 * _noise(rng, (lh, lw), 160 / q), 0.0, 1.0) * np.float32(0.075)
    algae_low = _noise(rng, (lh, lw), 95 / q) + 0.45 * _noise(rng, (lh, lw), 30 / q)
    lum_l, phase, amp, algae_field = (
        cv2.resize(f.astype(np.float32), (lw * q, lh * q), interpolation=cv2.INTER_LINEAR)[:h, :w]
        for f in (lum_low, phase_low, amp_low, algae_low))

    # --- sand: colour, brightness, grain, ripples ---------------------------
    sand_choices = np.array([[150, 178, 196], [140, 156, 166], [118, 160, 186],
                             [128, 146, 150]], dtype=np.float32)
    base = sand_choices[rng.integers(len(sand_choices))] * np.float32(rng.uniform(0.85, 1.1))
    n6, n2, n1 = _noise(rng, (h, w), 6), _noise(rng, (h, w), 2), _fast_normal(rng, (h, w))
    grain = 0.05 * n6 + 0.035 * n2 + 0.05 * n1
    ripple = np.sin(phase)
    ripple += 0.35 * np.sin(2 * phase + 1.0)
    lum = 1.0 + lum_l + grain + amp * ripple

    # --- stones: power-law sizes, drawn big first --------------------------
    n_stones = int(rng.poisson(260 * area))
    u = rng.uniform(0, 1, n_stones)
    rmin, rmax = 1.5, 48.0
    radii = np.sort(rmin / (1 - u * (1 - rmin / rmax)))[::-1]  # density ~ r^-2
    cxs = rng.uniform(-radii, w + radii)
    cys = rng.uniform(-radii, h + radii)
    grey_v = rng.uniform(55, 200, n_stones)
    palette = np.array([[1.0, 1.0, 1.0], [0.86, 0.95, 1.06], [0.92, 0.98, 1.02],
                        [0.97, 1.02, 0.98], [0.80, 0.90, 1.08]])
    tints = palette[rng.integers(len(palette), size=n_stones)]
    tints = tints * (1.0 + 0.03 * rng.standard_normal((n_stones, 3)))
    cols = np.clip(grey_v[:, None] * tints, 0, 255)
    hvs = np.clip(60 + 3.5 * radii, 60, 255)
    big = radii >= 3.0
    polys = _blob_polygons(rng, cxs[big], cys[big], radii[big])
    stone = np.zeros((h, w, 4), np.uint8)   # B, G, R, alpha
    height = np.zeros((h, w), np.uint8)
    pi = 0
    for i in range(n_stones):
        colour = (float(cols[i, 0]), float(cols[i, 1]), float(cols[i, 2]), 255.0)
        if big[i]:
            pts = [polys[pi]]
            pi += 1
            cv2.fillPoly(stone, pts, colour, cv2.LINE_AA, 3)
            cv2.fillPoly(height, pts, float(hvs[i]), cv2.LINE_AA, 3)
        else:
            c8 = (int(round(cxs[i] * 8)), int(round(cys[i] * 8)))
            rr = int(round(radii[i] * 8))
            cv2.circle(stone, c8, rr, colour, -1, cv2.LINE_AA, 3)
            cv2.circle(height, c8, rr, float(hvs[i]), -1, cv2.LINE_AA, 3)
    a = stone[:, :, 3].astype(np.float32) * np.float32(1.0 / 255.0)
    # soft cast shadow of the stones on the sand (light from the upper left)
    sh = np.zeros_like(a)
    sh[3:, 3:] = a[:-3, :-3]
    sh = cv2.GaussianBlur(sh, (0, 0), 3.0)
    lum *= 1.0 - 0.38 * sh * (1.0 - a)
    stone_tex = 1.0 + 0.12 * n2 + 0.08 * n6 + 0.04 * n1
    # rim lighting and rounded tops from the stones' height map
    dome = cv2.distanceTransform((stone[:, :, 3] > 127).astype(np.uint8), cv2.DIST_L2, 3)
    hmap = height.astype(np.float32) + 6.0 * np.sqrt(np.minimum(dome, 30.0))
    hb = cv2.GaussianBlur(hmap, (0, 0), 1.6)
    gx = cv2.Sobel(hb, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(hb, cv2.CV_32F, 0, 1, ksize=3)
    shade = np.clip(1.0 - 0.0022 * (gx + gy), 0.55, 1.45)

    # --- algae: dark, fuzzy patches ---------------------------------------
    thr = rng.uniform(1.2, 1.6)
    fuzz = np.clip(0.6 + 0.3 * n2 + 0.25 * n6, 0.0, 1.0)
    alg = np.clip((algae_field - thr) * 2.5, 0.0, 1.0) * fuzz * np.float32(0.85)
    algae_cols = np.array([[38, 70, 48], [34, 56, 72], [52, 74, 60]], dtype=np.float32)
    acol = algae_cols[rng.integers(len(algae_cols))]

    # --- compose: sand * (1 - a) + stone * a, shading, algae ---------------
    ws = (1.0 - a) * lum
    wt = a * stone_tex
    keep = (1.0 - alg) * shade
    planes = []
    for c in range(3):  # planar arithmetic: much faster than (h, w, 3) broadcasting
        plane = stone[:, :, c].astype(np.float32)
        plane *= wt
        plane += ws * base[c]
        plane *= keep
        plane += alg * acol[c]
        planes.append(_to_uint8(plane))
    return cv2.GaussianBlur(cv2.merge(planes), (0, 0), 0.6)


# ----------------------------------------------------------------------------
# real photos
# ----------------------------------------------------------------------------

@functools.lru_cache(maxsize=8)
def _real_photo_groups(root: str) -> tuple[tuple[str, ...], ...]:
    """Image files of the shared data, grouped by folder (sequences' and seabed/)."""
    base = Path(root)
    groups = []
    folders = sorted(p for p in (base / "sequences").glob("*") if p.is_dir())
    folders.append(base / "seabed")
    for folder in folders:
        if folder.name in _EXCLUDED_AUTO or not folder.is_dir():
            continue
        files = sorted(str(p) for p in folder.iterdir()
                       if p.suffix.lower() in (".png", ".jpg", ".jpeg"))
        if files:
            groups.append(tuple(files))
    return tuple(groups)


@functools.lru_cache(maxsize=24)
def _load_cached(path: str) -> np.ndarray:
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        err = _ImageFileNotFound(f"cannot read image file: {path}")
        err.filename = path
        raise err
    img.setflags(write=False)
    return img


def _load_image(path: Union[str, Path]) -> np.ndarray:
    """BGR uint8 image of a file (read-only, cached); FileNotFoundError naming the path."""
    return _load_cached(str(Path(path)))


def _random_real_photo(rng: np.random.Generator) -> np.ndarray | None:
    root = shared_data_dir()
    if root is None:
        return None
    groups = _real_photo_groups(str(root))
    if not groups:
        return None
    group = groups[int(rng.integers(len(groups)))]
    return _load_image(group[int(rng.integers(len(group)))])


def _source_photo(rng: np.random.Generator, source) -> np.ndarray | None:
    """The photo for ``source`` ("auto", "procedural", path or array), None = procedural."""
    if isinstance(source, np.ndarray):
        return _to_bgr(source)
    if isinstance(source, str) and source == "procedural":
        return None
    if isinstance(source, str) and source == "auto":
        return _random_real_photo(rng)
    if isinstance(source, (str, Path)):
        return _load_image(source)
    raise ParameterError(f"source must be 'auto', 'procedural', a path or an image, "
                         f"got {source!r}")


def background(shape: Shape = (480, 640), seed: int = 0,
               source: Union[str, Path] = "auto") -> np.ndarray:
    """A seabed background: a random real photo crop, or the procedural seabed.

    Parameters
    ----------
    shape : (int, int)
        ``(height, width)`` of the result.
    seed : int
        Chooses the photo, the crop and its flips (or the procedural seabed).
    source : {"auto", "procedural"} or path
        ``"auto"``: a photo of the shared data folder (a frame of one of the
        sequences, or ``seabed/*``; the tiled pool sequence is left out since
        tiles look like markers), picked at random, randomly cropped to the
        aspect of ``shape``, flipped and resized; :func:`seabed` when the
        shared data is absent. ``"procedural"``: always :func:`seabed`. A path:
        that file, cropped and resized the same way.

    Returns
    -------
    numpy.ndarray
        ``(height, width, 3)`` uint8 BGR image.

    Raises
    ------
    FileNotFoundError
        ``source`` is a path that cannot be read as an image.
    """
    h, w = _check_shape(shape)
    rng = np.random.default_rng(seed)
    photo = _source_photo(rng, source)
    if photo is None:
        return seabed((h, w), seed)
    ph, pw = photo.shape[:2]
    ar = w / h
    if pw / ph > ar:
        ch, cw = ph, ph * ar
    else:
        ch, cw = pw / ar, pw
    f = rng.uniform(0.6, 1.0)
    ch, cw = max(2, int(ch * f)), max(2, int(cw * f))
    y0 = int(rng.integers(0, ph - ch + 1))
    x0 = int(rng.integers(0, pw - cw + 1))
    crop = photo[y0:y0 + ch, x0:x0 + cw]
    interp = cv2.INTER_AREA if cw > w else cv2.INTER_LINEAR
    out = cv2.resize(crop, (w, h), interpolation=interp)
    if rng.uniform() < 0.5:
        out = out[:, ::-1]
    if rng.uniform() < 0.5:
        out = out[::-1]
    return np.ascontiguousarray(out)


# ----------------------------------------------------------------------------
# water
# ----------------------------------------------------------------------------

@dataclass
class Water:
    """Water and camera degradations (see the module docstring for the model).

    Attributes
    ----------
    attenuation : (float, float, float)
        Attenuation coefficients per metre for the B, G, R channels (red
        fades first).
    distance : float
        Camera-to-scene distance in metres; transmission is
        ``t = exp(-attenuation * distance)``.
    backscatter : (float, float, float)
        Colour of the veiling light (B, G, R, 0-255), reached where ``t -> 0``.
    strobe : float
        0-1 strength of the radial light falloff: 1 - strobe at the farthest
        corner from the strobe centre.
    strobe_centre : (float, float) or None
        Centre of the light as fractions of (width, height); None = random
        (seeded) near the middle.
    blur : float
        Gaussian blur sigma in pixels (forward scatter, defocus).
    noise : float
        Sensor noise sigma in grey levels (independent per pixel and channel;
        near-gaussian: a sum of three uniform draws, for speed).
    snow : float
        Marine-snow specks per megapixel (bright gaussian dots 1-4 px).
    jpeg_quality : int or None
        JPEG round-trip quality 1-100, or None for no compression.

    The defaults are the ``"moderate"`` preset; derive variants with
    ``dataclasses.replace(Water.preset("hard"), jpeg_quality=None)``.
    """

    attenuation: tuple[float, float, float] = (0.10, 0.07, 0.42)
    distance: float = 2.5
    backscatter: tuple[float, float, float] = (135.0, 128.0, 55.0)
    strobe: float = 0.35
    strobe_centre: tuple[float, float] | None = None
    blur: float = 0.9
    noise: float = 3.5
    snow: float = 150.0
    jpeg_quality: int | None = 85

    def __post_init__(self) -> None:
        att = tuple(float(v) for v in self.attenuation)
        bs = tuple(float(v) for v in self.backscatter)
        if len(att) != 3 or min(att) < 0:
            raise ParameterError("attenuation must be 3 non-negative numbers, "
                                 f"got {self.attenuation!r}")
        if len(bs) != 3 or min(bs) < 0 or max(bs) > 255:
            raise ParameterError("backscatter must be 3 numbers in 0-255, "
                                 f"got {self.backscatter!r}")
        if self.distance < 0:
            raise ParameterError(f"distance must be >= 0, got {self.distance!r}")
        if not 0.0 <= self.strobe <= 1.0:
            raise ParameterError(f"strobe must be in [0, 1], got {self.strobe!r}")
        if self.blur < 0 or self.noise < 0 or self.snow < 0:
            raise ParameterError("blur, noise and snow must be >= 0")
        if self.jpeg_quality is not None and not 1 <= int(self.jpeg_quality) <= 100:
            raise ParameterError(f"jpeg_quality must be None or 1-100, got {self.jpeg_quality!r}")
        object.__setattr__(self, "attenuation", att)
        object.__setattr__(self, "backscatter", bs)
        if self.strobe_centre is not None:
            object.__setattr__(self, "strobe_centre",
                               tuple(float(v) for v in self.strobe_centre))

    @classmethod
    def preset(cls, name: str) -> "Water":
        """One of the named conditions ``"clear"``, ``"moderate"``, ``"hard"``.

        ``"clear"``: a few metres of clear water, slight blue cast.
        ``"moderate"``: typical survey water, red mostly gone, edges still crisp.
        ``"hard"``: murky green water at distance, strong falloff, noise,
        marine snow and JPEG artefacts; objects still recognisable.

        Raises
        ------
        ValueError
            (a :class:`~seahough.errors.ParameterError`) for any other name.
        """
        key = str(name).lower()
        if key == "clear":
            return cls(attenuation=(0.05, 0.04, 0.25), distance=1.5,
                       backscatter=(160.0, 135.0, 70.0), strobe=0.15, blur=0.4,
                       noise=1.5, snow=20.0, jpeg_quality=None)
        if key == "moderate":
            return cls()
        if key == "hard":
            return cls(attenuation=(0.16, 0.12, 0.55), distance=5.5,
                       backscatter=(112.0, 128.0, 72.0), strobe=0.55, blur=1.6,
                       noise=7.0, snow=600.0, jpeg_quality=60)
        raise ParameterError(f"unknown water preset {name!r}; valid names: "
                             + ", ".join(repr(p) for p in PRESETS))

    @property
    def transmission(self) -> np.ndarray:
        """Per-channel transmission ``exp(-attenuation * distance)`` (B, G, R)."""
        return np.exp(-np.asarray(self.attenuation) * self.distance)

    def apply(self, image: np.ndarray, seed: int = 0) -> np.ndarray:
        """Same as :func:`apply_water` ``(image, self, seed)``."""
        return apply_water(image, self, seed)


def _as_water(water: WaterLike) -> Water | None:
    if water is None or isinstance(water, Water):
        return water
    if isinstance(water, str):
        return Water.preset(water)
    raise ParameterError(f"water must be a Water, a preset name {PRESETS} or None, got {water!r}")


def _add_snow(rng: np.random.Generator, out: np.ndarray, count: int) -> None:
    """Screen-blend ``count`` bright gaussian specks (about 1-4 px) into ``out`` in place."""
    h, w = out.shape[:2]
    sig = rng.uniform(0.45, 1.6, count)      # visible size about 1-4 px
    amp = rng.uniform(50, 190, count) / 255.0
    cxs, cys = rng.uniform(0, w - 1, count), rng.uniform(0, h - 1, count)
    for sigma, a, cx, cy in zip(sig, amp, cxs, cys):
        rad = int(math.ceil(3 * sigma))
        x0, x1 = max(0, int(cx) - rad), min(w, int(cx) + rad + 2)
        y0, y1 = max(0, int(cy) - rad), min(h, int(cy) + rad + 2)
        gx = np.exp(-0.5 * ((np.arange(x0, x1) - cx) / sigma) ** 2)
        gy = np.exp(-0.5 * ((np.arange(y0, y1) - cy) / sigma) ** 2)
        keep = (1.0 - a * np.outer(gy, gx)).astype(np.float32)[:, :, None]
        roi = np.clip(out[y0:y1, x0:x1], 0.0, 255.0)
        out[y0:y1, x0:x1] = 255.0 - (255.0 - roi) * keep


def apply_water(image: np.ndarray, water: WaterLike = "moderate", seed: int = 0) -> np.ndarray:
    """Degrade a clear image as if seen through water (module docstring model).

    Parameters
    ----------
    image : numpy.ndarray
        Grey or BGR uint8 image (grey is converted to BGR).
    water : Water, str or None
        Conditions, a preset name, or None for no change (a BGR copy).
    seed : int
        Seeds the noise, snow and (when ``strobe_centre`` is None) the strobe
        centre.

    Returns
    -------
    numpy.ndarray
        uint8 BGR image of the same height and width.
    """
    bgr = _to_bgr(image)
    wat = _as_water(water)
    if wat is None:
        return bgr.copy()
    rng = np.random.default_rng(seed)
    h, w = bgr.shape[:2]
    t = wat.transmission
    bs = np.asarray(wat.backscatter)
    # per-channel affine I = J t + B (1 - t), as one cv2.transform
    m = np.zeros((3, 4), np.float32)
    m[[0, 1, 2], [0, 1, 2]] = t
    m[:, 3] = bs * (1.0 - t)
    out = cv2.transform(bgr.astype(np.float32), m)
    centre = wat.strobe_centre
    if centre is None:
        centre = tuple(rng.uniform(0.35, 0.65, 2))
    if wat.strobe > 0:
        cx, cy = float(centre[0]) * (w - 1), float(centre[1]) * (h - 1)
        rmax2 = max(cx, w - 1 - cx) ** 2 + max(cy, h - 1 - cy) ** 2
        dx2 = ((np.arange(w, dtype=np.float32) - cx) ** 2)[None, :]
        dy2 = ((np.arange(h, dtype=np.float32) - cy) ** 2)[:, None]
        fall = 1.0 - np.float32(wat.strobe) * np.minimum((dx2 + dy2) / np.float32(max(rmax2, 1.0)),
                                                           np.float32(1.0))
        out = cv2.multiply(out, cv2.merge([fall, fall, fall]))
    if wat.blur > 0.05:
        out = cv2.GaussianBlur(out, (0, 0), wat.blur)
    if wat.noise > 0:
        out = cv2.scaleAdd(_fast_normal(rng, out.shape), float(wat.noise), out)
    if wat.snow > 0:
        count = int(rng.poisson(wat.snow * h * w / 1e6))
        if count:
            _add_snow(rng, out, count)
    out8 = _to_uint8(out)
    if wat.jpeg_quality is not None:
        ok, buf = cv2.imencode(".jpg", out8, [cv2.IMWRITE_JPEG_QUALITY, int(wat.jpeg_quality)])
        if ok:
            out8 = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out8


# ----------------------------------------------------------------------------
# markers
# ----------------------------------------------------------------------------

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


def marker(name: str = "board", size: int = 120) -> tuple[np.ndarray, np.ndarray]:
    """A flat docking marker on its own canvas.

    Bright (242) shapes on a dark (30) canvas, anti-aliased, with a margin of
    ``max(4, size // 20)`` px on every side:

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

    Returns
    -------
    image : numpy.ndarray
        uint8 grey canvas.
    mask : numpy.ndarray
        uint8 coverage of the marker: 255 inside, 0 outside, anti-aliased
        (intermediate) along its border.
    """
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
    image = _to_uint8(_DARK + (_BRIGHT - _DARK) * cover)
    if name == "board":
        mask_cover = render([(0.0, 0.0, sw, sh)])
    else:
        mask_cover = cover
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


# ----------------------------------------------------------------------------
# marker scenes
# ----------------------------------------------------------------------------

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
    :func:`negative_scene` with the same arguments gives the same background
    and water without the marker.

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

    Returns
    -------
    numpy.ndarray
        uint8 BGR scene.
    """
    rng = np.random.default_rng(seed)
    bg_seed, water_seed = _seed_of(rng), _seed_of(rng)
    bg = background(_check_shape(shape), bg_seed, source)
    return apply_water(bg, water, water_seed)


# ----------------------------------------------------------------------------
# views cut from one large photo (fragments, frame pairs, sequences)
# ----------------------------------------------------------------------------

def _render_view(photo: np.ndarray, F: np.ndarray, shape: Shape) -> np.ndarray:
    """The view of ``photo`` through ``F`` (photo pixel -> view pixel), anti-aliased."""
    h, w = shape
    ph, pw = photo.shape[:2]
    pts = apply_matrix(invert_matrix(F), _corners((h, w)))
    x0 = max(0, int(math.floor(pts[:, 0].min())) - 4)
    y0 = max(0, int(math.floor(pts[:, 1].min())) - 4)
    x1 = min(pw, int(math.ceil(pts[:, 0].max())) + 5)
    y1 = min(ph, int(math.ceil(pts[:, 1].max())) + 5)
    roi = photo[y0:y1, x0:x1]
    mag = math.sqrt(abs(np.linalg.det(np.asarray(F)[:, :2])))
    if mag < 0.9:
        roi = cv2.GaussianBlur(roi, (0, 0), 0.45 * math.sqrt(1.0 / mag ** 2 - 1.0))
    Fr = compose(F, np.array([[1.0, 0.0, x0], [0.0, 1.0, y0]]))
    # views lie inside the photo: a black border here would reveal a bug
    return cv2.warpAffine(roi, Fr, (w, h), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def _as_photo(image) -> np.ndarray | None:
    if image is None:
        return None
    if isinstance(image, (str, Path)):
        return _load_image(image)
    return _to_bgr(np.asarray(image))


def _place_views(rng: np.random.Generator, image, source, views: list[tuple[np.ndarray, Shape]],
                 orient: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Fit views given in 'virtual photo' units into a photo.

    ``views`` are (G, shape): G maps virtual-photo coordinates to view pixels.
    A real photo is magnified by the smallest factor u >= 1 that holds every
    view, and shifted at random: virtual = u * photo - t. Without a photo, a
    procedural seabed just large enough is made, its axes turned by
    ``orient`` degrees (equation-1 convention) to keep it small.
    Returns (photo, P) with P the 2x3 matrix photo pixel -> virtual
    coordinates, so that the view matrices are ``compose(G, P)``.
    """
    pts = np.vstack([apply_matrix(invert_matrix(G), _corners(s)) for G, s in views])
    photo = _as_photo(image)
    if photo is None:
        photo = _source_photo(rng, source)
    if photo is None:
        rot = rotation(orient)
        q = pts @ rot.T
        lo, hi = q.min(axis=0), q.max(axis=0)
        size = (int(math.ceil(hi[1] - lo[1])) + 5, int(math.ceil(hi[0] - lo[0])) + 5)
        photo = seabed(size, _seed_of(rng))
        b = 2.0 - lo  # photo = rot @ virtual + b
        P = np.hstack([rot.T, (-rot.T @ b)[:, None]])
        return photo, P
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    bw, bh = hi - lo
    ph, pw = photo.shape[:2]
    u = max(1.0, bw / (pw - 1.0), bh / (ph - 1.0))
    if u > 1.0:
        u *= 1.0 + 1e-6
    # virtual = u * photo - t: the box [lo, hi] must lie in [-t, u * (size - 1) - t]
    tx_lo, tx_hi = -lo[0], u * (pw - 1) - hi[0]
    ty_lo, ty_hi = -lo[1], u * (ph - 1) - hi[1]
    tx = rng.uniform(tx_lo, max(tx_lo, tx_hi))
    ty = rng.uniform(ty_lo, max(ty_lo, ty_hi))
    if u == 1.0:  # integer offsets keep axis-aligned crops exact
        if math.ceil(tx_lo - 1e-9) <= math.floor(tx_hi + 1e-9):
            tx = min(max(round(tx), math.ceil(tx_lo - 1e-9)), math.floor(tx_hi + 1e-9))
        if math.ceil(ty_lo - 1e-9) <= math.floor(ty_hi + 1e-9):
            ty = min(max(round(ty), math.ceil(ty_lo - 1e-9)), math.floor(ty_hi + 1e-9))
    P = np.array([[u, 0.0, -tx], [0.0, u, -ty]])
    return photo, P


def _water_per_frame(rng: np.random.Generator, water: WaterLike, n: int) -> list[Water | None]:
    """One Water per frame; a random strobe centre is fixed to the camera, with jitter."""
    wat = _as_water(water)
    if wat is None:
        return [None] * n
    if wat.strobe_centre is not None or wat.strobe == 0:
        return [wat] * n
    base = rng.uniform(0.4, 0.6, 2)
    return [dataclasses.replace(wat, strobe_centre=tuple(np.clip(base + rng.normal(0, 0.03, 2),
                                                                 0.0, 1.0)))
            for _ in range(n)]


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
    cover = np.clip(half + 0.5 - np.abs(s), 0.0, 1.0)
    u = np.clip(s / max(half, 0.5), -1.0, 1.0)
    profile = np.sqrt(1.0 - 0.75 * u * u)  # round rope: darker at its sides
    period = max(3.0, 1.4 * float(width))
    strands = 0.86 + 0.14 * np.cos(np.float32(2 * math.pi / period) * (t + 0.9 * s))
    tone = (np.array([200.0, 232.0, 246.0]) * rng.uniform(0.95, 1.03)).astype(np.float32)
    # a faint shadow beside the rope (light from the upper left)
    shadow = 1.0 - 0.25 * np.exp(-((s - 0.9 * width) / max(width, 1.0)) ** 2)
    pix = bg[ys, xs].astype(np.float32) * (shadow * (1.0 - cover))[:, None]
    pix += (profile * strands * cover)[:, None] * tone
    img = bg.copy()
    img[ys, xs] = np.clip(np.rint(pix), 0, 255).astype(np.uint8)
    scene = apply_water(img, water, water_seed)
    px, py = cx + off * float(n[0]), cy + off * float(n[1])
    truth = Truth(x=px, y=py, line_angle=a, line_offset=off)
    return scene, truth


_PATHS = ("line", "turn", "loop")


def sequence(image: ImageLike | None = None, *, n_frames: int = 20,
             frame_size: Shape = (240, 320), path: str = "line", step: float = 12.0,
             water: WaterLike = "moderate", seed: int = 0,
             source: Union[str, Path] = "auto") -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Frames along a known camera path over one photo (dead-reckoning truth).

    The camera flies at constant altitude, moving ``step`` frame pixels per
    frame towards the top of its frame (its forward direction), with a small
    seeded jitter of speed and heading. Paths:

    - ``"line"``: straight ahead;
    - ``"turn"``: a steady turn of 90 degrees over the sequence;
    - ``"loop"``: a full circle, back near the start.

    The initial heading is random. Small photos are magnified as needed so
    that every frame lies inside the photo.

    Parameters
    ----------
    image : ndarray, path or None
        The photo; None = a random real photo (``source``), else a procedural
        seabed just large enough.
    n_frames : int
        Number of frames (>= 2).
    frame_size : (int, int)
        ``(height, width)`` of the frames.
    path : {"line", "turn", "loop"}
        Camera path.
    step : float
        Forward motion per frame in frame pixels.
    water : Water, str or None
        Degradation of each frame (own noise/snow per frame).
    seed : int
        Seed of everything.
    source : str or path
        Where the photo comes from when ``image`` is None.

    Returns
    -------
    frames : list of numpy.ndarray
        uint8 BGR frames.
    matrices : list of numpy.ndarray
        2x3 matrices, frame-0 pixel -> frame-i pixel (the first is the
        identity); frame i-1 -> frame i is
        ``compose(matrices[i], invert_matrix(matrices[i-1]))``.

    Raises
    ------
    ParameterError
        Unknown path, or a step so large that consecutive frames overlap by
        less than 60 %.
    """
    if path not in _PATHS:
        raise ParameterError(f"unknown path {path!r}; valid: " + ", ".join(repr(p) for p in _PATHS))
    n = int(n_frames)
    if n < 2:
        raise ParameterError(f"n_frames must be >= 2, got {n_frames!r}")
    if step < 0:
        raise ParameterError(f"step must be >= 0, got {step!r}")
    rng = np.random.default_rng(seed)
    h, w = _check_shape(frame_size, "frame_size")
    c = _centre((h, w))
    yaw = {"line": 0.0, "turn": 90.0 / max(1, n - 1), "loop": 360.0 / n}[path]
    # camera i: virtual -> frame i is G_i = pose_to_matrix(c, 1, heading_i, origin=C_i)
    heading0 = heading = float(rng.uniform(0, 360))
    pos = np.zeros(2)
    G = []
    for i in range(n):
        Gi = pose_to_matrix(c[0], c[1], 1.0, heading, tuple(pos))
        G.append(Gi)
        ds = step * (1.0 + 0.08 * rng.standard_normal())
        # forward = frame up: the virtual point that appears ds px above the centre
        ahead = apply_matrix(invert_matrix(Gi), [[c[0], c[1] - ds]])[0]
        pos = ahead
        heading += yaw + 0.6 * rng.standard_normal()
    rel = [compose(G[i], invert_matrix(G[i - 1])) for i in range(1, n)]
    overlap = min(_overlap(r, (h, w)) for r in rel)
    if overlap < 0.6:
        raise ParameterError(f"consecutive frames overlap by only {overlap:.0%} (< 60 %); "
                             f"use a smaller step")
    photo, P = _place_views(rng, image, source, [(Gi, (h, w)) for Gi in G], orient=heading0)
    waters = _water_per_frame(rng, water, n)
    frames = []
    for Gi, wat in zip(G, waters):
        f = _render_view(photo, compose(Gi, P), (h, w))
        frames.append(apply_water(f, wat, _seed_of(rng)))
    inv0 = invert_matrix(G[0])
    mats = [compose(Gi, inv0) for Gi in G]
    mats[0] = np.hstack([np.eye(2), np.zeros((2, 1))])
    return frames, mats


def _overlap(M: np.ndarray, shape: Shape) -> float:
    """Fraction of a frame still seen in the next one (sampled on a grid)."""
    h, w = shape
    ys, xs = np.mgrid[0:h:max(1, h // 24), 0:w:max(1, w // 32)]
    p = apply_matrix(M, np.stack([xs.ravel(), ys.ravel()], axis=1))
    inside = (p[:, 0] >= 0) & (p[:, 0] <= w - 1) & (p[:, 1] >= 0) & (p[:, 1] <= h - 1)
    return float(inside.mean())
