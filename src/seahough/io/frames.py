"""Frame sequences: folders, videos and lists of images, in order, read by index.

>>> time_from_name("dive_20130701_134008.633.jpg")
1372686008.633
"""

from __future__ import annotations

import calendar
import os
import re
from pathlib import Path

import cv2
import numpy as np

from ..errors import ImageError, ParameterError
from .images import read_image

__all__ = ["list_frames", "time_from_name", "FrameReader", "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS"]

IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pgm", ".ppm", ".pnm",
                    ".webp", ".jp2")
VIDEO_EXTENSIONS = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".wmv", ".webm",
                    ".mts", ".ts", ".3gp")


def _natural_key(s: str):
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", s)]


_DATETIME = re.compile(r"(?<!\d)(\d{4})[-_]?(\d{2})[-_]?(\d{2})[T_\- ]?(\d{2})[-_:h]?(\d{2})"
                       r"[-_:m]?(\d{2})(?:[.,](\d+))?(?!\d)")
_EPOCH = re.compile(r"(?<!\d)(1\d{9})(?:[._](\d{1,9}))?(?!\d)"
                    r"|(?<!\d)(1\d{12}|1\d{15}|1\d{18})(?!\d)")
_CLOCK = re.compile(r"(?<!\d)(\d{2})[-_:h](\d{2})[-_:m](\d{2})(?:[.,](\d+))?(?!\d)")


def time_from_name(name: str) -> float | None:
    """Seconds from a timestamp in a file name, or None.

    Understood: date and time (``20130701_134008.633``, ``2013-07-01T13-40-08``;
    seconds since 1970, UTC), Unix time (``1372687208.633``, 13/16/19-digit
    milli/micro/nanoseconds), and a time of day (``00_00_21.000``,
    ``13-40-08``; seconds since midnight). A plain frame number is not a time.

    Examples
    --------
    >>> time_from_name("frame_00_00_21.500.jpg")
    21.5
    >>> time_from_name("1372687208.6337876.png")
    1372687208.6337876
    >>> time_from_name("frame_000123.png") is None
    True
    """
    stem = Path(name).name
    for ext in (*IMAGE_EXTENSIONS, *VIDEO_EXTENSIONS):
        if stem.lower().endswith(ext):
            stem = stem[: -len(ext)]
            break
    m = _DATETIME.search(stem)
    if m:
        y, mo, d, hh, mi, ss = (int(v) for v in m.groups()[:6])
        if 1970 <= y <= 2100 and 1 <= mo <= 12 and 1 <= d <= 31 and hh < 24 and mi < 60 and ss < 61:
            frac = float("0." + m.group(7)) if m.group(7) else 0.0
            return calendar.timegm((y, mo, d, hh, mi, ss, 0, 0, 0)) + frac
    m = _EPOCH.search(stem)
    if m:
        if m.group(1):
            return float(m.group(1) + ("." + m.group(2) if m.group(2) else ""))
        digits = m.group(3)
        return int(digits) / 10.0 ** (len(digits) - 10)
    m = _CLOCK.search(stem)
    if m:
        hh, mi, ss = (int(v) for v in m.groups()[:3])
        if hh < 24 and mi < 60 and ss < 61:
            frac = float("0." + m.group(4)) if m.group(4) else 0.0
            return hh * 3600.0 + mi * 60.0 + ss + frac
    return None


def _is_video(p: Path) -> bool:
    return p.suffix.lower() in VIDEO_EXTENSIONS


def _split_video_ref(s: str):
    """``("video.mp4", 12)`` for ``"video.mp4#12"``, else None."""
    m = re.match(r"^(.*)#(\d+)$", s)
    if m and _is_video(Path(m.group(1))):
        return m.group(1), int(m.group(2))
    return None


def _video_frames(path: Path) -> list[str]:
    cap = cv2.VideoCapture(os.fspath(path))
    if not cap.isOpened():
        raise ParameterError(f"{path}: cannot open the video")
    try:
        n = 0
        while cap.grab():
            n += 1
    finally:
        cap.release()
    if n == 0:
        raise ParameterError(f"{path}: the video holds no frame OpenCV can decode")
    return [f"{path}#{i}" for i in range(n)]


def list_frames(frames) -> list:
    """The frames of ``frames`` in order, as a list.

    Parameters
    ----------
    frames : path, or list of paths (or arrays)
        A folder (its images, sorted by the timestamp in their names when
        every name carries one, else in natural name order: ``f2`` before
        ``f10``), a video file (one entry ``"video.mp4#<i>"`` per frame),
        or a list of image paths kept in the given order. A list of one
        folder is read as that folder; each video in a list is replaced
        by its frames, in place (several videos: one after the other, in
        the order given). Arrays in a list are taken as frames as they are.

    Raises
    ------
    ParameterError
        No such file or folder, an empty folder, an unreadable video.
    """
    if isinstance(frames, np.ndarray):
        raise ParameterError("frames: give a folder, a video or a list of image paths "
                             "(a single array is not a sequence)")
    if isinstance(frames, (str, os.PathLike)):
        items = [frames]
    else:
        try:
            items = list(frames)
        except TypeError:
            raise ParameterError(f"frames={frames!r}: expected a folder, a video or a "
                                 "list of image paths") from None
    if len(items) == 1 and isinstance(items[0], (str, os.PathLike)):
        p = Path(items[0])
        if p.is_dir():
            files = [f for f in p.iterdir() if f.is_file() and not f.name.startswith(".")
                     and f.suffix.lower() in IMAGE_EXTENSIONS]
            if not files:
                raise ParameterError(f"{p}: no image files ({', '.join(IMAGE_EXTENSIONS)}) "
                                     "in this folder")
            times = [time_from_name(f.name) for f in files]
            if all(t is not None for t in times):
                order = sorted(range(len(files)),
                               key=lambda i: (times[i], _natural_key(files[i].name)))
            else:
                order = sorted(range(len(files)), key=lambda i: _natural_key(files[i].name))
            return [str(files[i]) for i in order]
        if p.is_file() and _is_video(p):
            return _video_frames(p)
    out = []
    for it in items:
        if isinstance(it, np.ndarray):
            out.append(it)
        elif isinstance(it, (str, os.PathLike)):
            s = os.fspath(it)
            if Path(s).is_dir():
                raise ParameterError(f"{s}: a folder inside a list of frames; give the "
                                     "folder alone")
            if not Path(s).exists() and _split_video_ref(s) is None:
                raise ParameterError(f"{s}: no such file")
            if _is_video(Path(s)) and Path(s).is_file():
                out.extend(_video_frames(Path(s)))   # each video of a list: its frames
            else:
                out.append(s)
        else:
            raise ParameterError(f"frames: unexpected item {type(it).__name__}; expected paths")
    if not out:
        raise ParameterError("frames: the list is empty")
    return out


class FrameReader:
    """Reads the listed frames by index (videos sequentially, reopened when
    asked for an earlier frame)."""

    def __init__(self, items: list, max_pixels: int):
        self.items = items
        self.max_pixels = max_pixels
        self._cap = None
        self._cap_path = None
        self._cap_next = 0
        self._fps = {}

    def name(self, i: int) -> str:
        it = self.items[i]
        return f"frame_{i:05d}" if isinstance(it, np.ndarray) else str(it)

    def time(self, i: int) -> float | None:
        it = self.items[i]
        if isinstance(it, np.ndarray):
            return None
        ref = _split_video_ref(str(it))
        if ref is not None:
            fps = self._video_fps(ref[0])
            return ref[1] / fps if fps > 0 else None
        return time_from_name(str(it))

    def _video_fps(self, path: str) -> float:
        if path not in self._fps:
            cap = cv2.VideoCapture(path)
            self._fps[path] = float(cap.get(cv2.CAP_PROP_FPS) or 0.0) if cap.isOpened() else 0.0
            cap.release()
        return self._fps[path]

    def raw(self, i: int) -> np.ndarray:
        """The frame as stored (any depth/channels); raises ImageError."""
        it = self.items[i]
        if isinstance(it, np.ndarray):
            return it
        ref = _split_video_ref(str(it))
        if ref is None:
            return read_image(it, max_pixels=self.max_pixels)
        path, k = ref
        if self._cap is None or self._cap_path != path or k < self._cap_next:
            self.close()
            self._cap = cv2.VideoCapture(path)
            self._cap_path, self._cap_next = path, 0
            if not self._cap.isOpened():
                raise ImageError(f"{path}: cannot open the video")
        while self._cap_next < k:
            if not self._cap.grab():
                raise ImageError(f"{path}: frame {k} is past the end of the video")
            self._cap_next += 1
        ok, img = self._cap.read()
        self._cap_next += 1
        if not ok or img is None:
            raise ImageError(f"{path}: cannot decode frame {k}")
        return img

    def close(self):
        if self._cap is not None:
            self._cap.release()
        self._cap = None
