"""Water and camera degradations of a clear scene.

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
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Union

import cv2
import numpy as np

from ..errors import ParameterError
from ._util import _fast_normal, _to_bgr, _to_uint8

__all__ = ["PRESETS", "Water", "apply_water"]

PRESETS: tuple[str, ...] = ("clear", "moderate", "hard", "oceanic", "coastal")
"""Names accepted by :meth:`Water.preset`: three conditions of one greenish
water (``"clear"`` to ``"hard"``), and two water types that differ in colour
(``"oceanic"``: blue, ``"coastal"``: green, where blue fades too)."""


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

    Examples
    --------
    >>> import dataclasses
    >>> murky = dataclasses.replace(Water.preset("hard"), jpeg_quality=None, snow=0.0)
    >>> murky.distance, murky.jpeg_quality
    (5.5, None)
    >>> murky.apply(np.full((40, 60, 3), 200, np.uint8), seed=0).shape
    (40, 60, 3)
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
        """One of the named conditions of :data:`PRESETS`.

        ``"clear"``: a few metres of clear water, slight blue cast.
        ``"moderate"``: typical survey water, red mostly gone, edges still crisp.
        ``"hard"``: murky green water at distance, strong falloff, noise,
        marine snow and JPEG artefacts; objects still recognisable.
        ``"oceanic"``: open-ocean blue water (about Jerlov's type I-II): blue
        and green carry far, red fades within metres; blue veiling light.
        ``"coastal"``: green coastal water (about Jerlov's coastal types 3-5):
        dissolved matter absorbs blue as well as red, so only green carries;
        green veiling light, more scatter than ``"moderate"``.

        The coefficients are chosen by hand to give those looks, not fitted
        to measurements. Every preset attenuates red most, so a red or orange
        object loses its colour with distance (see :mod:`seahough.sim.colour`).

        Parameters
        ----------
        name : str
            One of :data:`PRESETS` (case does not matter).

        Returns
        -------
        Water
            The conditions of that preset.

        Raises
        ------
        ValueError
            (a :class:`~seahough.errors.ParameterError`) for any other name.

        Examples
        --------
        >>> Water.preset("hard").jpeg_quality
        60
        >>> Water.preset("Moderate") == Water()
        True
        >>> [round(float(t), 2) for t in Water.preset("coastal").transmission]  # B, G, R
        [0.47, 0.67, 0.3]
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
        if key == "oceanic":
            return cls(attenuation=(0.05, 0.08, 0.45), distance=3.0,
                       backscatter=(150.0, 105.0, 35.0), strobe=0.3, blur=0.6,
                       noise=2.5, snow=80.0, jpeg_quality=90)
        if key == "coastal":
            return cls(attenuation=(0.38, 0.20, 0.60), distance=2.0,
                       backscatter=(85.0, 130.0, 70.0), strobe=0.4, blur=1.1,
                       noise=4.0, snow=250.0, jpeg_quality=80)
        raise ParameterError(f"unknown water preset {name!r}; valid names: "
                             + ", ".join(repr(p) for p in PRESETS))

    def at(self, distance: float) -> "Water":
        """The same water with the camera ``distance`` metres from the scene.

        Parameters
        ----------
        distance : float
            Camera-to-scene distance in metres (>= 0).

        Returns
        -------
        Water
            A copy; only ``distance`` differs.

        Examples
        --------
        >>> near, far = Water().at(1.0), Water().at(4.0)
        >>> bool(far.transmission[2] < near.transmission[2])  # red fades with distance
        True
        >>> Water().at(-1)
        Traceback (most recent call last):
        ...
        seahough.errors.ParameterError: distance must be >= 0, got -1.0
        """
        try:
            d = float(distance)
        except (TypeError, ValueError):
            raise ParameterError(f"distance must be a number, got {distance!r}") from None
        if not math.isfinite(d):
            raise ParameterError(f"distance must be finite, got {distance!r}")
        return dataclasses.replace(self, distance=d)

    @property
    def transmission(self) -> np.ndarray:
        """Per-channel transmission ``exp(-attenuation * distance)`` (B, G, R).

        Examples
        --------
        >>> [round(float(t), 3) for t in Water.preset("clear").transmission]
        [0.928, 0.942, 0.687]
        """
        return np.exp(-np.asarray(self.attenuation) * self.distance)

    def apply(self, image: np.ndarray, seed: int = 0) -> np.ndarray:
        """Same as :func:`apply_water` ``(image, self, seed)`` (parameters and result there).

        Examples
        --------
        >>> Water.preset("clear").apply(np.zeros((30, 40), np.uint8), seed=1).shape
        (30, 40, 3)
        """
        return apply_water(image, self, seed)


WaterLike = Union[Water, str, None]


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

    Examples
    --------
    >>> clear = np.full((40, 60, 3), 200, np.uint8)
    >>> out = apply_water(clear, "moderate", seed=0)
    >>> out.shape, str(out.dtype)
    ((40, 60, 3), 'uint8')
    >>> int(out[:, :, 2].mean()) < int(out[:, :, 0].mean())  # red fades first
    True
    >>> bool((apply_water(clear, None) == clear).all())
    True
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
