"""The mosaic of a dive: frames placed by their measured poses on one canvas."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from ..errors import ImageError
from ..geometry import apply_matrix, compose, frame_centre, invert_matrix
from ..io.frames import FrameReader
from ..io.images import to_bgr8, write_image
from .track import iter_odometry_csv


def _posed(csv_path, counts: dict | None = None):
    """(index, inverse cumulative matrix) of the frames with a measured pose, from the CSV.

    Frames whose pose is only assumed (a gap) are left out: their place is a
    guess (counted in ``counts["left_out"]`` when given)."""
    for r in iter_odometry_csv(csv_path):
        if r.get("matrix") is None:
            continue
        if r["status"] in ("origin", "measured"):
            yield r["index"], invert_matrix(np.asarray(r["matrix"]).reshape(2, 3))
        elif counts is not None:
            counts["left_out"] += 1


def build_mosaic(csv_path, reader: FrameReader, shape, path: Path, max_side: int = 4000, *,
                 counts: dict | None = None, bit_depth: int | None = None):
    """Frames placed by the trajectory on one canvas (frame-0 pixels).

    Each canvas pixel comes from the frame that saw it nearest to that
    frame's centre (sharp, no double images, little vignetting seam).
    Memory does not grow with the number of frames: the canvas is at most
    ``max_side`` pixels on its longer side (frames are shrunk to fit), the
    poses are read from the CSV twice (extent, then placing) and the frames
    one at a time.

    Only measured poses (and the origin) are placed: a frame whose pose is
    assumed (status ``assumed``: the motion of its pair could not be
    measured) is never stacked on the others. ``counts``, when given, gets
    ``"left_out"``: how many frames with a pose are not in the mosaic (their
    pose assumed, or the frame unreadable when the mosaic is built).

    Returns the mosaic's path, or None when no frame has a measured pose.
    """
    if counts is not None:
        counts["left_out"] = 0
    h, w = shape
    corners = np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]])
    x0 = y0 = math.inf
    x1 = y1 = -math.inf
    for _, inv in _posed(csv_path, counts):
        q = apply_matrix(inv, corners)
        x0, y0 = min(x0, q[:, 0].min()), min(y0, q[:, 1].min())
        x1, y1 = max(x1, q[:, 0].max()), max(y1, q[:, 1].max())
    if not math.isfinite(x0):
        return None
    span = max(x1 - x0, y1 - y0, 1.0)
    f = min(1.0, max_side / span)
    cw = int(math.ceil((x1 - x0) * f)) + 1
    ch = int(math.ceil((y1 - y0) * f)) + 1
    place = np.array([[f, 0, -x0 * f - 0.5 * (1 - f)], [0, f, -y0 * f - 0.5 * (1 - f)]])
    canvas = np.zeros((ch, cw, 3), np.uint8)
    best = np.full((ch, cw), np.inf, np.float32)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    c = frame_centre(shape)
    dist = (((xx - c[0]) / w) ** 2 + ((yy - c[1]) / h) ** 2).astype(np.float32) + 1.0  # >= 1
    for index, inv in _posed(csv_path):
        try:
            img = to_bgr8(reader.raw(index), bit_depth)
        except (ImageError, OSError):
            img = None
        if img is None or img.shape[:2] != (h, w):
            if counts is not None:
                counts["left_out"] += 1
            continue
        m = compose(place, inv)
        fp = apply_matrix(m, corners)
        bx0 = max(int(math.floor(fp[:, 0].min())) - 1, 0)
        by0 = max(int(math.floor(fp[:, 1].min())) - 1, 0)
        bx1 = min(int(math.ceil(fp[:, 0].max())) + 2, cw)
        by1 = min(int(math.ceil(fp[:, 1].max())) + 2, ch)
        if bx1 <= bx0 or by1 <= by0:
            continue
        mm = m.copy()
        mm[:, 2] -= (bx0, by0)
        size = (bx1 - bx0, by1 - by0)
        interp = cv2.INTER_AREA if f < 0.999 else cv2.INTER_LINEAR
        warped = cv2.warpAffine(img, mm, size, flags=cv2.INTER_LINEAR if f >= 0.5 else interp,
                                borderMode=cv2.BORDER_CONSTANT)
        d = cv2.warpAffine(dist, mm, size, flags=cv2.INTER_NEAREST,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
        # 0 outside the frame; stay a pixel away from its border
        valid = cv2.erode((d > 0).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
        sub_best = best[by0:by1, bx0:bx1]
        take = valid & (d < sub_best)
        canvas[by0:by1, bx0:bx1][take] = warped[take]
        sub_best[take] = d[take]
    path.parent.mkdir(parents=True, exist_ok=True)
    write_image(path, canvas, what="the mosaic")
    return path
