"""Frame sequences along a known camera path over one photo."""

from __future__ import annotations

from pathlib import Path
from typing import Union

import numpy as np

from ..errors import ParameterError
from ..geometry import apply_matrix, compose, invert_matrix, pose_to_matrix
from ._util import ImageLike, Shape, _centre, _check_shape, _seed_of
from ._views import _place_views, _render_view
from .water import WaterLike, _water_per_frame, apply_water

__all__ = ["sequence"]

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

    Examples
    --------
    >>> frames, mats = sequence(n_frames=3, frame_size=(48, 64), step=6.0, seed=0,
    ...                         source="procedural")
    >>> len(frames), frames[0].shape, mats[0].tolist()
    (3, (48, 64, 3), [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
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
    overlap = min(_overlap_on_pixel_grid(r, (h, w)) for r in rel)
    if overlap < 0.6:
        raise ParameterError(f"consecutive frames overlap by only {overlap:.0%} (< 60 %) at "
                             f"{w}x{h} px and step={step:g} px: give larger frames (--size) "
                             "or a smaller step")
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


# Not geometry.overlap: its n x n linspace grid would change which sequences pass the 60 % check.
def _overlap_on_pixel_grid(M: np.ndarray, shape: Shape) -> float:
    """Fraction of a frame still seen in the next one (sampled every h//24, w//32 pixels)."""
    h, w = shape
    ys, xs = np.mgrid[0:h:max(1, h // 24), 0:w:max(1, w // 32)]
    p = apply_matrix(M, np.stack([xs.ravel(), ys.ravel()], axis=1))
    inside = (p[:, 0] >= 0) & (p[:, 0] <= w - 1) & (p[:, 1] >= 0) & (p[:, 1] <= h - 1)
    return float(inside.mean())
