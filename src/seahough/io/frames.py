"""Frame sequences: folders, videos and lists of images, in order, read by index.

>>> time_from_name("dive_20130701_134008.633.jpg")
1372686008.633

Nothing of a sequence is dropped without a word: every entry of a folder
whose name has an image extension is a frame (a broken link, a link loop or
a folder of that name is one that cannot be read), and a video lists every
frame its header counts, those the decoder cannot give included (see
:func:`list_frames`).
"""

from __future__ import annotations

import calendar
import errno
import logging
import os
import re
import stat
import zlib
from pathlib import Path

import cv2
import numpy as np

from ..config import MAX_MEMORY_MB
from ..errors import ImageError, ImageReadError, ImageValueError, ParameterError
from .images import read_image

__all__ = ["list_frames", "iter_frames", "time_from_name", "FrameReader", "printable",
           "IMAGE_EXTENSIONS", "VIDEO_EXTENSIONS"]

# FFmpeg prints what it thinks of damaged video data ("[mjpeg @ 0x...] bad vlc")
# on the process's stderr, where it would reach the user as stray lines: the
# frames it cannot decode are flagged in the results instead. OpenCV reads this
# setting when it first uses FFmpeg in the process (-8: AV_LOG_QUIET); a value
# the user set is kept. No file descriptor is touched.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

#: Frames that a video's header counts but the decoder cannot give are listed
#: too; a header claiming more than this many of them is refused as damaged.
MAX_MISSING_VIDEO_FRAMES = 1_000_000
_GIVE_UP_GRABS = 64        # failed grabs in a row taken for the end of a video
_SAMPLE = 4096             # bytes of each of the 3 blocks a file's fingerprint reads
_SAMPLE_ROWS = 16          # pixel rows a decoded frame's fingerprint reads
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u2028\u2029\ud800-\udfff]")


def printable(name) -> str:
    r"""``name`` with control characters (newlines, tabs, terminal escapes,
    undecodable bytes) escaped as Python writes them, for one-line output.

    Examples
    --------
    >>> print(printable("dive/frame\n7.png"))
    dive/frame\n7.png
    >>> printable("plain name.png")
    'plain name.png'
    """
    return _CONTROL.sub(lambda m: repr(m.group())[1:-1], str(name))


IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".jpe", ".jfif", ".tif", ".tiff", ".bmp", ".pgm",
                    ".ppm", ".pnm", ".webp", ".jp2")
VIDEO_EXTENSIONS = (".mp4", ".avi", ".mov", ".mkv", ".m4v", ".mpg", ".mpeg", ".wmv", ".webm",
                    ".mts", ".ts", ".3gp")
#: Pictures a folder may hold that are not read as frames (said so, not skipped silently).
OTHER_PICTURES = (".gif", ".heic", ".heif", ".avif", ".dng", ".cr2", ".cr3", ".nef", ".arw",
                  ".orf", ".rw2", ".raw", ".exr", ".hdr", ".jxl")
#: What a folder holds and is not read (subfolders, videos, other pictures), at WARNING level.
log = logging.getLogger("seahough.io")


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


def split_video_ref(s: str):
    """``("video.mp4", 12)`` for ``"video.mp4#12"``, else None (also for
    ``"video.mp4#012"``: a frame is named one way, :func:`video_ref_problem`)."""
    m = re.match(r"^(.*)#(0|[1-9]\d*)$", s)
    if m and _is_video(Path(m.group(1))):
        return m.group(1), int(m.group(2))
    return None


def video_ref_problem(s: str) -> str | None:
    """Why ``s``, an existing video's name and ``#`` something, names none of
    its frames (a user's ``dive.mp4#3-5`` was "no such file"); None when it
    is no such name.

    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     video = os.path.join(d, "dive.mp4")
    ...     open(video, "wb").close()
    ...     print(video_ref_problem(video + "#3-5").replace(d, "D"))
    ...     print(video_ref_problem(video + "#007").replace(d, "D"))
    ...     print(video_ref_problem(video + "#7"), video_ref_problem(d + "/x.mp4#1-2"))
    D/dive.mp4#3-5: '3-5' is no frame number (a video's frame is named D/dive.mp4#12, counted from 0; every frame: D/dive.mp4)
    D/dive.mp4#007: '007' is no frame number (a video's frame is named D/dive.mp4#7, counted from 0; every frame: D/dive.mp4)
    None None
    """
    video, sep, frame = s.rpartition("#")
    if not sep or not _is_video(Path(video)) or not Path(video).is_file() \
            or split_video_ref(s) is not None:
        return None
    example = str(int(frame)) if frame.isascii() and frame.isdigit() else "12"   # ("²")
    return (f"{s}: {frame!r} is no frame number (a video's frame is named {video}#{example}, "
            f"counted from 0; every frame: {video})")


def _video_frames(path: Path) -> list[str]:
    """One entry per frame of the video: as many as the decoder gives, and at
    least as many as its header counts (a damaged stretch is read past; the
    frames it loses are listed too, and are unreadable when read)."""
    cap = cv2.VideoCapture(os.fspath(path))
    if not cap.isOpened():
        raise ParameterError(f"{path}: cannot open the video")
    try:
        expected = max(int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0), 0)
        n = good = failed = 0
        while failed < _GIVE_UP_GRABS:
            if cap.grab():
                # the frames the decoder could not give before this one keep their places
                n, good, failed = n + failed + 1, good + 1, 0
            else:
                failed += 1
    finally:
        cap.release()
    if good == 0:
        raise ParameterError(f"{path}: the video holds no frame OpenCV can decode")
    n = max(n, expected)
    if n - good > MAX_MISSING_VIDEO_FRAMES:
        raise ParameterError(f"{path}: the header counts {expected} frames but only {good} "
                             "decode: a damaged header?")
    return [f"{path}#{i}" for i in range(n)]


def _say_midnight(folder, names: list, times: list) -> None:
    """A note when frames named by their time of day (no date) jump by
    over 12 hours: a dive across midnight, whose frames after it sort first
    (a trial: the track turned back on itself, every frame "measured")."""
    if len(times) < 2 or max(times) >= 86400.0 + 1.0:   # (dates or Unix times: not this)
        return
    gaps = np.diff(times)
    k = int(np.argmax(gaps))
    if gaps[k] > 43200.0:
        log.warning("note: %s: the frames' times of day jump by %.1f h between %s and %s: a "
                    "dive across midnight? They are taken in order of time of day; name them "
                    "with their date, or give them as a list in their order", printable(folder),
                    gaps[k] / 3600.0, names[k], names[k + 1])


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

    Every entry of a folder whose name ends with an image extension is a
    frame, whatever it is: a broken link, a link loop, a folder or a FIFO so
    named cannot be read and gets an ``unreadable`` row in a dead-reckoning
    run (names starting with ``.`` are left out). What a folder holds that
    may have been meant as frames and is not read (its subfolders: a folder
    is not searched inside; videos; pictures of other formats, such as
    ``.gif``) is named in a note, logged at WARNING level on the
    ``"seahough.io"`` logger (printed on stderr unless logging is set up
    otherwise). A video's frames are as
    many as its header counts (``CAP_PROP_FRAME_COUNT``), or as the decoder
    gives if more: frames the decoder cannot give (damaged data) keep their
    place and cannot be read, so that a damaged video never looks complete.

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
            with os.scandir(p) as it:
                entries = [(e, os.path.splitext(e.name)[1].lower()) for e in it
                           if not e.name.startswith(".")]
            files = [Path(e.path) for e, ext in entries if ext in IMAGE_EXTENSIONS]
            left = _not_read([(e, ext) for e, ext in entries if ext not in IMAGE_EXTENSIONS])
            if not files:
                raise ParameterError(f"{printable(p)}: no image files "
                                     f"({', '.join(IMAGE_EXTENSIONS)}) in this folder"
                                     + (f"; not read: {left}" if left else ""))
            if left:
                log.warning("note: %s: not read: %s", printable(p), left)
            times = [time_from_name(f.name) for f in files]
            if all(t is not None for t in times):
                order = sorted(range(len(files)),
                               key=lambda i: (times[i], _natural_key(files[i].name)))
                _say_midnight(p, [files[i].name for i in order], [times[i] for i in order])
            else:
                order = sorted(range(len(files)), key=lambda i: _natural_key(files[i].name))
            return [str(files[i]) for i in order]
        if p.is_file() and _is_video(p):
            return _video_frames(p)
    out = []
    for it in items:
        if isinstance(it, np.ndarray) or it is None:   # (None: a frame the camera dropped)
            out.append(it)
        elif isinstance(it, (str, os.PathLike)):
            s = os.fspath(it)
            if Path(s).is_dir():
                raise ParameterError(f"{s}: a folder inside a list of frames; give the "
                                     "folder alone")
            # (a broken link is listed, not a typo: its frame is flagged as unreadable)
            if not Path(s).exists() and not os.path.islink(s) and split_video_ref(s) is None:
                raise ParameterError(video_ref_problem(s) or f"{s}: no such file")
            if _is_video(Path(s)) and Path(s).is_file():
                out.extend(_video_frames(Path(s)))   # each video of a list: its frames
            else:
                out.append(s)
        else:
            raise ParameterError(f"frames: item {len(out)} ({type(it).__name__}) is not an image "
                                 "path, an array or None (a dropped frame)")
    if not out:
        raise ParameterError("frames: the list is empty")
    return out


def iter_frames(frames, *, max_pixels: int = 200_000_000, max_memory_mb: float = MAX_MEMORY_MB):
    """``(name, image)`` for each frame of ``frames`` in order, decoded one
    at a time: a folder, a video or a list, as :func:`list_frames` takes
    them (a video's frames named ``"dive.mp4#<k>"``; the video is read
    through once first, to count them). A frame that cannot be read comes
    as ``(name, None)``, its reason logged at WARNING level on the
    ``"seahough.io"`` logger, and the frames after it are read on. What
    :func:`list_frames` refuses (no such folder, a video that cannot be
    opened) raises here, at the call.

    Examples
    --------
    >>> import tempfile, cv2
    >>> with tempfile.TemporaryDirectory() as d:
    ...     path = os.path.join(d, "dive.avi")
    ...     w = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 5, (64, 48))
    ...     for k in range(3):
    ...         _ = w.write(np.full((48, 64, 3), 40 * k, np.uint8))
    ...     w.release()
    ...     [(os.path.basename(n), img.shape) for n, img in iter_frames(path)]
    [('dive.avi#0', (48, 64, 3)), ('dive.avi#1', (48, 64, 3)), ('dive.avi#2', (48, 64, 3))]
    """
    items = list_frames(frames)
    return _frames_of(FrameReader(items, max_pixels, max_memory_mb))


def _frames_of(reader: FrameReader):
    """:func:`iter_frames`' generator over the reader's items."""
    try:
        for i in range(len(reader.items)):
            try:
                image = reader.raw(i)
            except ImageError as e:
                log.warning("%s", printable(str(e)))
                image = None
            yield reader.name(i), image
    finally:
        reader.close()


def _not_read(entries) -> str:
    """What of a folder's entries that are not images (``(os.DirEntry,
    lower-case extension)`` pairs) may have been meant as frames, said in
    words: subfolders holding images (not searched), videos and other
    picture formats; "" when none (other files, a navigation log or notes,
    and folders without images are no frames and go unsaid)."""
    def is_dir(e) -> bool:
        try:
            return e.is_dir()    # (from the listing itself on most file systems: no stat)
        except OSError:
            return False

    def has_images(path) -> bool:
        try:
            with os.scandir(path) as it:
                return any(os.path.splitext(f.name)[1].lower() in IMAGE_EXTENSIONS
                           and not f.name.startswith(".") for f in it)
        except OSError:
            return False

    subs = [e for e, _ in entries if is_dir(e)]
    named = {e.name for e in subs}
    dirs = sorted(e.name for e in subs[:1000] if has_images(e.path))   # (a bounded look)
    kinds = []
    if dirs:
        kinds.append(f"{len(dirs)} subfolder{'s' * (len(dirs) > 1)} of images, e.g. "
                     f"{printable(dirs[0])} (a folder is not searched inside)")
    # .ts: a video when it is a transport stream (not TypeScript; a bounded look)
    ts = {e.name for e, ext in entries if ext == ".ts" and e.name not in named}
    ts_video = ts if len(ts) > 1000 else {e.name for e, _ in entries
                                          if e.name in ts and _transport_stream(e)}
    for what, exts in (("video", VIDEO_EXTENSIONS), ("other picture", OTHER_PICTURES)):
        got = [ext for e, ext in entries if ext in exts and e.name not in named
               and (ext != ".ts" or e.name in ts_video)]
        if got:
            kinds.append(f"{len(got)} {what} file{'s' * (len(got) > 1)} "
                         f"({', '.join(sorted(set(got)))})")
    return "; ".join(kinds)


def _transport_stream(entry: os.DirEntry) -> bool:
    """Whether a ``.ts`` file is an MPEG transport stream (a video: its
    188-byte packets start with the sync byte 0x47, "G"), not TypeScript
    source. Only a regular file is opened (a named pipe would block)."""
    try:
        if not entry.is_file():   # (a regular file, or a link to one)
            return False
        with open(entry.path, "rb") as f:
            head = f.read(189)
    except OSError:
        return False
    return len(head) == 189 and head[:1] == head[188:189] == b"\x47"


def _entry(path: str) -> os.stat_result:
    """The file's status; an ImageReadError saying why an entry is no image
    file (a broken link, a link loop, a folder, a FIFO...)."""
    try:
        st = os.stat(path)
    except OSError as e:
        if os.path.islink(path):
            if e.errno == errno.ELOOP:
                raise ImageReadError(f"{path}: symbolic link loop") from None
            raise ImageReadError(f"{path}: broken symbolic link (to "
                                 f"{printable(os.readlink(path))})") from None
        if isinstance(e, FileNotFoundError):
            raise ImageReadError(f"{path}: no such file") from None
        raise ImageReadError(f"{path}: cannot read ({e.strerror or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ImageReadError(f"{path}: is a folder, not an image")
    if not stat.S_ISREG(st.st_mode):
        raise ImageReadError(f"{path}: not a regular file (a FIFO, socket or device)")
    return st


def _pixels_fingerprint(a) -> str:
    """``p`` and a CRC-32 of the array's shape, dtype and 16 rows spread over it."""
    try:
        a = np.asarray(a)
        crc = zlib.crc32(repr((a.shape, a.dtype.str)).encode())
        if a.ndim and a.shape[0]:
            for r in np.unique(np.linspace(0, a.shape[0] - 1, _SAMPLE_ROWS).astype(int)):
                crc = zlib.crc32(np.ascontiguousarray(a[r]), crc)
    except (TypeError, ValueError):    # not an array of numbers: nothing to compare
        return ""
    return f"p{crc:08x}"


def _file_fingerprint(path: str) -> str:
    """The size and a CRC-32 of 3 blocks of 4 kB (start, middle, end) of a
    file; "" when it is no readable regular file."""
    try:
        size = _entry(path).st_size
        with open(path, "rb") as f:
            if size <= 3 * _SAMPLE:
                crc = zlib.crc32(f.read())
            else:
                crc = zlib.crc32(f.read(_SAMPLE))
                f.seek(size // 2 - _SAMPLE // 2)
                crc = zlib.crc32(f.read(_SAMPLE), crc)
                f.seek(size - _SAMPLE)
                crc = zlib.crc32(f.read(_SAMPLE), crc)
    except (OSError, ImageError):
        return ""
    return f"s{size:x}-{crc:08x}"


class FrameReader:
    """Reads the listed frames by index (videos sequentially, reopened when
    asked for an earlier frame; a frame the decoder cannot give is an
    ImageError, and the frames after it are read on)."""

    def __init__(self, items: list, max_pixels: int, max_memory_mb: float = MAX_MEMORY_MB,
                 fps: float | None = None):
        self.items = items
        self.max_pixels = max_pixels
        self.max_memory_mb = max_memory_mb
        self.fps = fps   # (frames without a time of their own: index / fps)
        self._cap = None
        self._cap_path = None
        self._cap_next = 0
        self._fps = {}
        self._starts = None

    def name(self, i: int) -> str:
        it = self.items[i]
        return f"frame_{i:05d}" if it is None or isinstance(it, np.ndarray) else str(it)

    def is_array(self, i: int) -> bool:
        """Is frame ``i`` an array given as it is (not read from a file; or
        None, a dropped frame)?"""
        return self.items[i] is None or isinstance(self.items[i], np.ndarray)

    def is_video(self, i: int) -> bool:
        """Is frame ``i`` a frame of a video (``"video.mp4#<k>"``)?"""
        it = self.items[i]
        return not isinstance(it, np.ndarray) and split_video_ref(str(it)) is not None

    def time(self, i: int) -> float | None:
        """Frame ``i``'s time, seconds: from its name (:func:`time_from_name`),
        or a video's frame rate (seconds since the start of the first video
        listed: several videos make one time line); else ``i / fps`` when
        the reader was given one (seconds since the first frame); else None.

        >>> r = FrameReader(["a.png", "cam_00_00_21.500.png", np.zeros((8, 8))], 100, fps=4)
        >>> r.time(0), r.time(1), r.time(2), FrameReader(["a.png"], 100).time(0)
        (0.0, 21.5, 0.5, None)
        """
        it = self.items[i]
        t = None
        if not isinstance(it, np.ndarray):
            ref = split_video_ref(str(it))
            if ref is not None:
                fps = self._video_fps(ref[0])
                t = self._video_start(i) + ref[1] / fps if fps > 0 else None
            else:
                t = time_from_name(str(it))
        if t is None and self.fps:
            t = i / float(self.fps)
        return t

    def _video_start(self, i: int) -> float:
        """Seconds before the first frame of the video frame ``i`` belongs to:
        the length of the videos listed before it, each as long as its frame
        count (one time line over a dive's several files: a second video's
        times started at 0 again, and a velocity from them was wrong; a video
        listed again starts after the one before it too)."""
        if self._starts is None:
            self._starts, t, run, last = [], 0.0, None, -1
            for it in self.items:
                ref = None if isinstance(it, np.ndarray) or it is None \
                    else split_video_ref(str(it))
                if ref is not None and run is not None and ref[0] != run:   # (the next video)
                    t += self._video_length(run, last)
                if ref is not None:
                    run, last = ref[0], ref[1] if ref[0] != run else max(last, ref[1])
                self._starts.append(t)
        return self._starts[i]

    def _video_length(self, path: str, last: int) -> float:
        """Video ``path``'s length, seconds: its frame count (at least its
        last frame listed, ``last``, + 1) over its rate; 0 without a rate."""
        fps, count = self._video_info(path)
        return max(count, last + 1) / fps if fps > 0 else 0.0

    def _video_fps(self, path: str) -> float:
        return self._video_info(path)[0]

    def _video_info(self, path: str) -> tuple[float, int]:
        """Video ``path``'s frame rate and frame count, as its header gives
        them (0 when it does not); read once."""
        if path not in self._fps:
            cap = cv2.VideoCapture(path)
            self._fps[path] = (float(cap.get(cv2.CAP_PROP_FPS) or 0.0),
                               int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)) \
                if cap.isOpened() else (0.0, 0)
            cap.release()
        return self._fps[path]

    def fingerprint(self, i: int, image=None) -> str:
        """What frame ``i`` holds, in a few characters, to tell a frame from
        another of the same name (``--resume``): for a file, its size and a
        CRC-32 of 12 kB of it (start, middle, end; a few tens of
        microseconds, the frame not decoded); for an array, or a video frame
        given decoded as ``image``, a CRC-32 of 16 rows of its pixels. ""
        when there is nothing to read.

        >>> reader = FrameReader([np.zeros((8, 8)), np.ones((8, 8))], 10 ** 6)
        >>> reader.fingerprint(0) == reader.fingerprint(1), len(reader.fingerprint(0))
        (False, 9)
        """
        it = self.items[i]
        if it is None:
            return ""
        if isinstance(it, np.ndarray):
            return _pixels_fingerprint(it)
        if split_video_ref(str(it)) is not None:
            return "" if image is None else _pixels_fingerprint(image)
        return _file_fingerprint(os.fspath(it))

    def raw(self, i: int) -> np.ndarray:
        """The frame as stored (any depth/channels); raises ImageError."""
        it = self.items[i]
        if isinstance(it, np.ndarray):
            return it
        if it is None:
            raise ImageValueError("no frame (None: a dropped frame)")
        ref = split_video_ref(str(it))
        if ref is None:
            _entry(os.fspath(it))
            return read_image(it, max_pixels=self.max_pixels, max_memory_mb=self.max_memory_mb)
        path, k = ref
        if self._cap is None or self._cap_path != path or k < self._cap_next:
            self.close()
            self._cap = cv2.VideoCapture(path)
            self._cap_path, self._cap_next = path, 0
            if not self._cap.isOpened():
                raise ImageReadError(f"{path}: cannot open the video")
        failed = 0
        while self._cap_next < k:
            # a frame that cannot be decoded still takes its place; many in a row:
            # the video has ended
            failed = 0 if self._cap.grab() else failed + 1
            self._cap_next += 1
            if failed >= _GIVE_UP_GRABS:
                end = self._cap_next - failed
                self.close()
                raise ImageReadError(f"{printable(str(it))}: past the end of the video (its "
                                     f"frames end before frame {end})")
        ok, img = self._cap.read()
        self._cap_next += 1
        if not ok or img is None:
            raise ImageReadError(f"{it}: frame {k} cannot be decoded (damaged or missing "
                                 "data)")
        return img

    def close(self):
        if self._cap is not None:
            self._cap.release()
        self._cap = None
