"""Views cut from one large photo (fragments, frame pairs, sequences): fitting
camera views into a photo, and rendering them."""

from __future__ import annotations

import logging
import math
from pathlib import Path

import cv2
import numpy as np

from ..geometry import apply_matrix, compose, invert_matrix, rotation
from ._util import Shape, _corners, _seed_of, _to_bgr
from .backgrounds import _load_image, _source_photo, seabed

#: A photo magnified more than this to hold the views is said so (WARNING on
#: the ``"seahough.sim"`` logger): its frames are an enlarged blur, with fewer
#: edges than any camera would see (``seahough simulate sequence --n 300 --path
#: turn``: a 576 px photo magnified 6.5x; 98 of 300 frames not measurable by
#: the dead reckoning).
MAGNIFY_NOTE = 2.0
log = logging.getLogger("seahough.sim")


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
    if u > MAGNIFY_NOTE:
        log.warning("note: the photo (%dx%d) is magnified %.1fx to hold every view (they "
                    "span %dx%d view pixels): the views are blurred by as much; give a larger "
                    "photo (`seahough simulate --photo`, or the image or source argument), "
                    "fewer, smaller or nearer views, or a procedural seabed", pw, ph, u,
                    math.ceil(bw), math.ceil(bh))
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
