"""The part of a frame that motion is measured on: frames too small to
measure, and the dark or flat border that cameras and video decoders leave
at the edges (static edges there would vote for "no motion")."""

from __future__ import annotations

import cv2
import numpy as np

from ..errors import ImageSizeError

__all__ = ["MIN_MOTION_SIDE", "check_motion_size", "check_video_sizes", "content_box"]

#: The smallest side, in pixels, of a frame whose motion is measured. Thinner
#: frames were measured wrong with full confidence: strips of 8-48 rows cut
#: from the real sequences and the procedural seabed, identical or shifted by
#: a few pixels, gave 7-10 wrong answers in 624 (corners off by 2-140 px, at
#: confidence up to 1.0); from 56 rows on, and for squares from 32 px on, no
#: answer was wrong at a confidence over 0.3 (the few wrong ones, at 0.15-0.26,
#: are as rare as in full-size frames). 64 keeps a step of margin.
MIN_MOTION_SIDE = 64


def check_motion_size(shape, label: str = "frames") -> None:
    """An ImageSizeError when a frame of ``shape`` is too small to measure
    motion in (a side under :data:`MIN_MOTION_SIDE`).

    >>> check_motion_size((64, 320))
    >>> try:
    ...     check_motion_size((8, 320))
    ... except ImageSizeError as e:
    ...     print(e)
    frames: 320x8 is too small to measure motion (each side must be at least 64 px)
    """
    h, w = shape[:2]
    if min(h, w) < MIN_MOTION_SIDE:
        raise ImageSizeError(f"{label}: {w}x{h} is too small to measure motion (each side must "
                             f"be at least {MIN_MOTION_SIDE} px)")


def check_video_sizes(items) -> None:
    """An ImageSizeError naming the first video among ``items`` (frame
    names, ``"dive.mp4#12"`` for a video's) whose frames, as its header
    gives their size, are too small to measure motion in: said once before
    a run, not once a frame (a user's trial: a video of 48x40 frames gave
    a flagged line for each and wrote a run of nothing). Other items, and
    a video whose header gives no size, are left to the run.

    >>> import tempfile, os
    >>> with tempfile.TemporaryDirectory() as d:
    ...     name = os.path.join(d, "tiny.avi")
    ...     vw = cv2.VideoWriter(name, cv2.VideoWriter_fourcc(*"MJPG"), 10, (48, 40))
    ...     for _ in range(3):
    ...         _ = vw.write(np.full((40, 48, 3), 90, np.uint8))
    ...     vw.release()
    ...     try:
    ...         check_video_sizes([name + "#0", name + "#1"])
    ...     except ImageSizeError as e:
    ...         print(str(e).replace(name, "tiny.avi"))
    tiny.avi: its frames are 48x40, too small to measure motion (each side must be at least 64 px)
    """
    from ..io.frames import split_video_ref

    seen = set()
    for it in items:
        ref = None if isinstance(it, np.ndarray) or it is None else split_video_ref(str(it))
        if ref is None or ref[0] in seen:
            continue
        seen.add(ref[0])
        cap = cv2.VideoCapture(ref[0])
        w, h = (int(cap.get(p) or 0) for p in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT))
        cap.release()
        if 0 < min(w, h) < MIN_MOTION_SIDE:
            raise ImageSizeError(f"{ref[0]}: its frames are {w}x{h}, too small to measure motion "
                                 f"(each side must be at least {MIN_MOTION_SIDE} px)")


def content_box(gray: np.ndarray, margin: int = 2) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1), end exclusive: the frame without its dark or flat
    border (black lines that video decoders and cameras leave at the edges)
    and ``margin`` pixels more. Static edges there would vote for "no
    motion" in every pair."""
    h, w = gray.shape
    # (every third pixel: as good a level, a tenth of the time)
    interior = gray[h // 4: 3 * h // 4: 3, w // 4: 3 * w // 4: 3]
    level = float(np.median(interior))

    def depth(lines: np.ndarray) -> int:
        # lines: the side's outermost lines as rows, outermost first: how
        # many of them in a row are dark or flat (most frames: not the first;
        # else the rest at once, each row reduced as a line of its own)
        for k0, k1 in ((0, 1), (1, lines.shape[0])):
            part = np.ascontiguousarray(lines[k0:k1])
            bad = (part.mean(axis=1) < 0.5 * level) | (part.std(axis=1) < 1.0)
            if not bad.all():
                return k0 + int(np.argmin(bad))
        return int(lines.shape[0])

    lim_y, lim_x = max(h // 10, 1), max(w // 10, 1)
    top = depth(gray[:lim_y])
    bottom = depth(gray[h - lim_y:][::-1])
    left = depth(gray[:, :lim_x].T)
    right = depth(gray[:, w - lim_x:][:, ::-1].T)
    box = (left + margin, top + margin, w - right - margin, h - bottom - margin)
    small = max(w // 2, MIN_MOTION_SIDE), max(h // 2, MIN_MOTION_SIDE)
    if box[2] - box[0] < small[0] or box[3] - box[1] < small[1]:
        return (0, 0, w, h)  # (also frames too small to lose a margin)
    return box
