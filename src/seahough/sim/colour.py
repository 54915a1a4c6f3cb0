"""Coloured markers on the seabed, seen through water whose red fades with
distance: the scenes of the colour benchmark (``bench/bench_colour.py``).

A marker painted in a colour (:data:`PAINTS`, or any BGR) is pasted on a
seabed photo and the whole scene goes through the water model
(:mod:`seahough.sim.water`): every preset attenuates red most, so an orange
marker turns brown, then grey-green, with distance, as the sand around it
does. With ``grey_match`` the paint is made as light or as dark as the
seabed around the marker *as the camera sees it through that water*: its
grey level then equals the sand's, and its border has almost no grey
gradient while its colour still differs (the hard case of issue 15).
:func:`border_contrast` measures what is left at the border, in grey and in
colour.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Union

import cv2
import numpy as np

from ..errors import ParameterError
from ..geometry import pose_to_matrix
from ._util import Shape, _centre, _check_range, _check_shape, _seed_of
from .backgrounds import background
from .markers import Truth, _paint, marker, paste_pattern, random_pose
from .water import WaterLike, _as_water, apply_water

__all__ = ["PAINTS", "GREY_WEIGHTS", "BorderContrast", "matched_paint", "colour_marker_scene",
           "border_contrast"]

PAINTS: dict[str, tuple[int, int, int]] = {
    "orange": (0, 120, 255),
    "red": (40, 30, 200),
    "yellow": (30, 210, 235),
    "green": (60, 170, 50),
}
"""Named marker paints, BGR (0-255): what a team paints a docking marker with."""

GREY_WEIGHTS: tuple[float, float, float] = (0.114, 0.587, 0.299)
"""The weights of B, G, R in a grey level (OpenCV's ``COLOR_BGR2GRAY``)."""

#: Width in px of the seabed band around the marker that a grey match reads.
_SURROUND_BAND = 8


def _as_paint(paint, name: str = "paint") -> np.ndarray:
    if isinstance(paint, str):
        try:
            return _paint(PAINTS[paint.lower()], name)
        except KeyError:
            raise ParameterError(f"unknown {name} {paint!r}; valid names: "
                                 + ", ".join(repr(p) for p in PAINTS)
                                 + ", or a (B, G, R) colour") from None
    return _paint(paint, name)


def matched_paint(paint, surround, water: WaterLike = None) -> np.ndarray:
    """The shade of ``paint`` whose grey level through ``water`` equals the surround's.

    The water model turns a colour ``J`` into ``J_c t_c + B_c (1 - t_c)`` per
    channel (transmission ``t``, veiling light ``B``), so two colours have
    the same grey level under water when ``sum_c w_c t_c (P_c - S_c) = 0``
    (``w``: :data:`GREY_WEIGHTS`); the veiling light, the strobe falloff and
    the noise act on both alike. The paint is scaled by one factor (its hue
    kept) to meet that, channels saturating at 255 (then the others carry
    on); when even white-saturated paint stays darker, the brightest shade
    is returned.

    Parameters
    ----------
    paint : str or (B, G, R)
        A name of :data:`PAINTS` or a colour (0-255); not black.
    surround : (B, G, R)
        Colour of the seabed around the marker, before the water.
    water : Water, str or None
        The water it is seen through (None: in air, ``t = 1``).

    Returns
    -------
    numpy.ndarray
        float32 (B, G, R), 0-255.

    Examples
    --------
    >>> p = matched_paint("orange", (80, 90, 100), "moderate")
    >>> [round(float(v)) for v in p]
    [0, 87, 184]
    >>> from seahough.sim import Water
    >>> t = Water().transmission
    >>> print(f"{np.dot(GREY_WEIGHTS, t * p):.2f} {np.dot(GREY_WEIGHTS, t * [80, 90, 100]):.2f}")
    61.91 61.91
    >>> [round(float(v)) for v in matched_paint("orange", (120, 140, 150), "moderate")]
    [0, 139, 255]
    """
    p = _as_paint(paint)
    s = _paint(surround, "surround")
    wat = _as_water(water)
    t = np.ones(3) if wat is None else wat.transmission
    wt = np.asarray(GREY_WEIGHTS) * t
    if not (p > 0).any():
        raise ParameterError("paint must not be black: no shade of it can match a grey level")
    target = float(np.dot(wt, s))

    def grey(k: float) -> float:
        return float(np.dot(wt, np.minimum(k * p, 255.0)))

    hi = 255.0 / float(p[p > 0].min())   # every channel saturated beyond this
    if grey(hi) <= target:
        return np.minimum(hi * p, 255.0).astype(np.float32)
    lo = 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if grey(mid) < target:
            lo = mid
        else:
            hi = mid
    return np.minimum(0.5 * (lo + hi) * p, 255.0).astype(np.float32)


def _warped_mask(mask: np.ndarray, matrix: np.ndarray, shape: Shape) -> np.ndarray:
    h, w = shape
    return cv2.warpAffine(mask.astype(np.float32) * (1.0 / 255.0), np.asarray(matrix, float),
                          (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                          borderValue=0) > 0.5


def colour_marker_scene(name: str = "cross", shape: Shape = (480, 640), *,
                        paint="orange", dark=(30, 30, 30), grey_match: bool = False,
                        water: WaterLike = "moderate", distance: float | None = None,
                        scale_range: tuple[float, float] = (0.6, 1.6),
                        angle_range: tuple[float, float] = (0.0, 360.0),
                        occlusion: Union[float, tuple[float, float]] = (0.0, 0.2),
                        seed: int = 0, size: int = 120, source: Union[str, Path] = "auto"
                        ) -> tuple[np.ndarray, np.ndarray, Truth]:
    """A seabed photo holding one marker painted in a colour, seen through water.

    As :func:`~seahough.sim.marker_scene` (same seed, same background,
    pose, silt and water draws: the truth is the same), but the marker is
    painted (:func:`~seahough.sim.marker` with ``colour``) and the water's
    distance can be set: the marker's colour goes through the water model
    with the rest of the scene, so its red fades with ``distance``.

    Parameters
    ----------
    name : str
        One of :data:`~seahough.sim.MARKERS`.
    shape : (int, int)
        ``(height, width)`` of the scene.
    paint : str or (B, G, R)
        Colour of the marker where it meets the seabed (the shapes; the
        board's panel): a name of :data:`PAINTS` or BGR 0-255.
    dark : (B, G, R)
        Colour of the board's frame and cells (and of the pattern image's
        canvas).
    grey_match : bool
        Scale the paint by :func:`matched_paint`, so that through this water
        its grey level equals the mean of the seabed in an 8 px band around
        the marker: the hard case, visible in colour only.
    water : Water, str or None
        Water conditions or a preset name (:data:`~seahough.sim.PRESETS`);
        None: a clear scene.
    distance : float or None
        Camera-to-scene distance in metres (:meth:`Water.at`); None: the
        water's own. Needs a water.
    scale_range, angle_range : (float, float)
        Ranges of the marker's scale and angle (degrees).
    occlusion : float or (float, float)
        Hidden fraction, or a range to draw it from.
    seed : int
        Seed of everything.
    size : int
        Marker size in pattern pixels.
    source : str or path
        Background source (see :func:`~seahough.sim.background`).

    Returns
    -------
    scene : numpy.ndarray
        uint8 BGR scene.
    pattern : numpy.ndarray
        uint8 BGR marker image as painted (in air): what a user searches for;
        its mask is ``marker(name, size)[1]``.
    truth : Truth
        Pose of the marker (origin = pattern centre), corners, occluded.

    Examples
    --------
    >>> from seahough import sim
    >>> scene, pattern, truth = colour_marker_scene("cross", (120, 160), paint="orange",
    ...                                             seed=2, size=40, source="procedural")
    >>> scene.shape, pattern.shape
    ((120, 160, 3), (48, 47, 3))
    >>> _, _, grey_truth = sim.marker_scene("cross", (120, 160), seed=2, size=40,
    ...                                     source="procedural")
    >>> bool(np.allclose(truth.matrix, grey_truth.matrix))  # the same pose
    True
    """
    rng = np.random.default_rng(seed)
    bg_seed, water_seed, pose_seed, occ_seed = (_seed_of(rng) for _ in range(4))
    h, w = _check_shape(shape)
    grey_pattern, mask = marker(name, size)
    colour = _as_paint(paint)
    panel = _paint(dark, "dark")
    wat = _as_water(water)
    if distance is not None:
        if wat is None:
            raise ParameterError("distance needs a water (water=None is a clear scene)")
        wat = wat.at(distance)
    bg = background((h, w), bg_seed, source)
    prng = np.random.default_rng(pose_seed)
    x, y, s, a = random_pose(prng, (h, w), grey_pattern.shape, scale_range, angle_range,
                             margin=4)
    if np.ndim(occlusion) == 0:
        occ = float(occlusion)
    else:
        lo, hi = _check_range(occlusion, "occlusion")
        occ = float(prng.uniform(lo, hi)) if hi > lo else lo
    if grey_match:
        inside = _warped_mask(mask, pose_to_matrix(x, y, s, a, _centre(mask.shape)), (h, w))
        k = 2 * _SURROUND_BAND + 1
        ring = cv2.dilate(inside.astype(np.uint8), np.ones((k, k), np.uint8)) > 0
        ring &= ~inside
        colour = matched_paint(colour, bg[ring].reshape(-1, 3).mean(axis=0), wat)
    pattern, _ = marker(name, size, colour=colour, dark=panel)
    scene, truth = paste_pattern(bg, pattern, mask, x=x, y=y, scale=s, angle=a,
                                 occlusion=occ, seed=occ_seed)
    return apply_water(scene, wat, water_seed), pattern, truth


@dataclass(frozen=True)
class BorderContrast:
    """What is left of a marker's border in a scene (see :func:`border_contrast`).

    Attributes
    ----------
    grey : float
        Median absolute grey-level step across the outline (levels 0-255).
    colour : float
        Median length of the BGR step across the outline (levels 0-255;
        at least ``grey`` up to the weights: a grey step is a weighted mean
        of the channels' steps).
    """

    grey: float
    colour: float


def border_contrast(scene: np.ndarray, mask: np.ndarray, truth: Truth,
                    band: int = 3) -> BorderContrast:
    """The grey and colour steps across a pasted marker's outline.

    The marker's mask is placed by ``truth.matrix``; at every outline pixel
    the means of a ``band``-px strip inside and of one outside (the pixel
    next to the outline left out: it is mixed), within a ``(2 band + 3)``
    square window, are compared. The medians over the outline are returned:
    a border with no grey gradient has ``grey`` near the noise's level.

    Parameters
    ----------
    scene : numpy.ndarray
        uint8 BGR scene (grey is taken as BGR with equal channels).
    mask : numpy.ndarray
        uint8 mask of the marker image (non-zero inside).
    truth : Truth
        The scene's truth (its ``matrix``).
    band : int
        Width in px of the strips either side (>= 1).

    Returns
    -------
    BorderContrast

    Examples
    --------
    >>> _, mask = marker("cross", 40)
    >>> kw = dict(paint="orange", seed=3, size=40, source="procedural")
    >>> plain, _, truth = colour_marker_scene("cross", (120, 160), **kw)
    >>> hard, _, _ = colour_marker_scene("cross", (120, 160), grey_match=True, **kw)
    >>> c_plain, c_hard = border_contrast(plain, mask, truth), border_contrast(hard, mask, truth)
    >>> c_hard.grey < 0.5 * c_plain.grey, c_hard.colour > 2 * c_hard.grey
    (True, True)
    """
    if int(band) < 1:
        raise ParameterError(f"band must be >= 1, got {band!r}")
    band = int(band)
    img = np.asarray(scene)
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
    img = img.astype(np.float32)
    h, w = img.shape[:2]
    inside = _warped_mask(np.asarray(mask), truth.matrix, (h, w)).astype(np.uint8)
    din = cv2.distanceTransform(inside, cv2.DIST_L2, 3)
    dout = cv2.distanceTransform(1 - inside, cv2.DIST_L2, 3)
    inner = ((din > 1.5) & (din <= band + 1.5)).astype(np.float32)
    outer = ((dout > 1.5) & (dout <= band + 1.5)).astype(np.float32)
    outline = (inside > 0) & (din <= 1.0)
    k = (2 * band + 3, 2 * band + 3)

    cnt_in = cv2.boxFilter(inner, -1, k, normalize=False)
    cnt_out = cv2.boxFilter(outer, -1, k, normalize=False)
    ok = outline & (cnt_in > 0) & (cnt_out > 0)
    if not ok.any():
        return BorderContrast(math.nan, math.nan)
    steps = []
    for c in range(3):
        plane = img[:, :, c]
        s_in = cv2.boxFilter(plane * inner, -1, k, normalize=False)
        s_out = cv2.boxFilter(plane * outer, -1, k, normalize=False)
        steps.append(s_in[ok] / cnt_in[ok] - s_out[ok] / cnt_out[ok])
    d = np.stack(steps, axis=1)
    grey = np.abs(d @ np.asarray(GREY_WEIGHTS, np.float32))
    return BorderContrast(float(np.median(grey)), float(np.median(np.linalg.norm(d, axis=1))))
