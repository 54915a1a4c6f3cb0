"""Image input: a path or an array in, a finite float32 grey image out."""

from __future__ import annotations

import os
import re
import sys
import tempfile
import threading
from pathlib import Path

import cv2
import numpy as np

from ..errors import ImageReadError, ImageSizeError, ImageValueError, WriteError

#: The smallest side, in pixels, an image must have to hold any edge.
MIN_SIDE = 8


def _check_header(path: Path, max_pixels: int) -> None:
    """Refuse a file whose header claims more than ``max_pixels`` pixels."""
    try:
        from PIL import Image
    except ImportError:  # pragma: no cover - pillow is a dependency
        return
    Image.MAX_IMAGE_PIXELS = None  # we apply our own limit below
    try:
        with Image.open(path) as im:
            w, h = im.size
    except Exception:
        return  # not a format Pillow knows; OpenCV decides below
    if w * h > max_pixels:
        raise ImageSizeError(
            f"{path}: header claims {w}x{h} = {w * h} pixels, over the limit of "
            f"{max_pixels} (Config.max_pixels); refusing to decode")


def _check_complete(path: Path, data: bytes) -> None:
    """Refuse truncated JPEG and PNG files (decoders would fill in grey)."""
    tail = data.rstrip(b"\x00")[-16:]
    if data[:3] == b"\xff\xd8\xff" and not tail.endswith(b"\xff\xd9"):
        raise ImageReadError(f"{path}: truncated JPEG (no end-of-image marker)")
    if data[:8] == b"\x89PNG\r\n\x1a\n" and b"IEND" not in tail:
        raise ImageReadError(f"{path}: truncated PNG (no IEND chunk)")


class _DecoderMessages:
    """Catch what the C decoders (libjpeg, libpng) print on stderr.

    They report damaged data there, not to OpenCV: a JPEG with corrupt
    entropy-coded data decodes "successfully" into garbage and a warning.
    File descriptor 2 is pointed at a temporary file while decoding (one
    decode at a time), and the text is kept in ``text`` instead of reaching
    the user's terminal as stray lines.
    """

    _lock = threading.Lock()

    def __enter__(self):
        self.text = ""
        self._saved = None
        self._lock.acquire()
        try:
            sys.stderr.flush()
            self._tmp = tempfile.TemporaryFile()
            self._saved = os.dup(2)
            os.dup2(self._tmp.fileno(), 2)
        except (OSError, ValueError, AttributeError):  # no usable fd 2: decode as is
            self._saved = None
        return self

    def __exit__(self, *exc):
        try:
            if self._saved is not None:
                os.dup2(self._saved, 2)
                os.close(self._saved)
                self._tmp.seek(0)
                self.text = self._tmp.read(4096).decode("utf-8", "replace")
                self._tmp.close()
        finally:
            self._lock.release()
        return False


#: OpenCV's log prefix, e.g. ``[ WARN:0@0.518] global grfmt_png.cpp:793 read_from_io``
_CV_LOG = re.compile(r"^\[\s*(?P<level>[A-Z]+)[^\]]*\]\s*(?:global\s+)?"
                     r"(?:[\w./\\-]+\.(?:cpp|hpp|cc|c|h):\d+\s+[\w:~<>]+\s*)?")
#: OpenCV's exception text inside a log line (source path, line, error code)
_CV_ERROR = re.compile(r"[\s:]*OpenCV\([\d.]+\)\s.*$")
#: a function name leading a log message, e.g. ``imdecode_('.png'): ``
_CV_FUNC = re.compile(r"^[A-Za-z_]\w*\([^)]*\)\s*:\s*")
_LIB_PREFIX = re.compile(r"^(?:lib(?P<lib>png|jpeg|tiff|webp)\s+(?:warning|error)\s*:\s*|"
                         r"OpenCV\([\d.]+\)\s*)", re.IGNORECASE)


def _first_line(text: str) -> str:
    """The first message the decoders printed, as a clean phrase: without
    OpenCV's log prefix (level, time, source file and line) or the library's
    ``libpng warning:``, e.g. ``PNG: image width is zero in IHDR``; debug
    and info log lines are skipped.

    >>> _first_line("[ WARN:0@0.518] global grfmt_png.cpp:793 read_from_io "
    ...             "libpng warning: Image width is zero in IHDR\\n")
    'PNG: image width is zero in IHDR'
    """
    for line in text.splitlines():
        line = line.strip()
        m = _CV_LOG.match(line)
        if m:
            if m.group("level") in ("INFO", "DEBUG", "VERBOSE", "TRACE"):
                continue
            line = _CV_FUNC.sub("", _CV_ERROR.sub("", line[m.end():]))
        lib = None
        m = _LIB_PREFIX.match(line)
        while m:
            lib = lib or m.group("lib")
            line = line[m.end():].strip()
            m = _LIB_PREFIX.match(line)
        line = " ".join(line.split()).rstrip(".:")
        if not line:
            continue
        if lib:
            line = f"{lib.upper()}: {line[:1].lower()}{line[1:]}"
        return line[:160]
    return ""


def read_image(path: str | os.PathLike, *, max_pixels: int = 200_000_000) -> np.ndarray:
    """Read an image file as OpenCV does (any depth, grey/BGR/BGRA).

    Raises
    ------
    ImageReadError
        Missing, unreadable, truncated or not an image.
    ImageSizeError
        Empty, or larger than ``max_pixels``.
    """
    p = Path(path)
    if not p.exists():
        raise ImageReadError(f"{p}: no such file")
    if p.is_dir():
        raise ImageReadError(f"{p}: is a folder, not an image")
    try:
        data = p.read_bytes()
    except OSError as e:
        raise ImageReadError(f"{p}: cannot read ({e.strerror or e})") from None
    if not data:
        raise ImageReadError(f"{p}: empty file")
    _check_header(p, max_pixels)
    _check_complete(p, data)
    with _DecoderMessages() as messages:
        img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
    if img is None:
        why = _first_line(messages.text)
        raise ImageReadError(f"{p}: not an image OpenCV can decode" + (f" ({why})" if why else ""))
    if "Corrupt JPEG data" in messages.text or "Premature end of JPEG" in messages.text:
        raise ImageReadError(f"{p}: corrupt JPEG data ({_first_line(messages.text)})")
    if img.size == 0:
        raise ImageSizeError(f"{p}: image has no pixels")
    return img


def to_gray(image, *, name: str = "image", max_pixels: int = 200_000_000,
            min_side: int = MIN_SIDE) -> np.ndarray:
    """A path or array as a float32 grey image with grey levels in [0, 255].

    Accepts grey (HxW or HxWx1), BGR or BGRA arrays of dtype uint8, uint16,
    other integers, bool or float. uint16 is divided by 257; floats whose
    maximum is at most 1 are taken as [0, 1] and multiplied by 255.

    Examples
    --------
    >>> to_gray(np.full((10, 12, 3), 255, np.uint8)).shape
    (10, 12)
    """
    label = name
    if isinstance(image, (str, os.PathLike)):
        label = str(image)
        image = read_image(image, max_pixels=max_pixels)
    if not isinstance(image, np.ndarray):
        raise ImageValueError(f"{label}: expected a numpy array or a file path, "
                              f"got {type(image).__name__}")
    a = image
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (3, 4)):
        raise ImageValueError(f"{label}: expected HxW, HxWx3 or HxWx4, got shape {a.shape}")
    if a.size == 0:
        raise ImageSizeError(f"{label}: image is empty (shape {a.shape})")
    h, w = a.shape[:2]
    if h * w > max_pixels:
        raise ImageSizeError(f"{label}: {w}x{h} pixels is over the limit of {max_pixels}")
    if min(h, w) < min_side:
        raise ImageSizeError(f"{label}: {w}x{h} is too small (each side must be at "
                             f"least {min_side} px)")
    if a.dtype == bool:
        a = a.astype(np.uint8) * 255
    if a.dtype.kind == "c" or a.dtype.kind not in "uif":
        raise ImageValueError(f"{label}: unsupported dtype {a.dtype}")
    if a.dtype.kind == "f":
        if not np.isfinite(a).all():
            raise ImageValueError(f"{label}: contains NaN or infinite values")
        if a.dtype.itemsize > 4 and np.abs(a).max(initial=0) > np.finfo(np.float32).max:
            raise ImageValueError(f"{label}: values beyond +-3.4e38 (float32 range)")
        a = a.astype(np.float32)
        if a.max(initial=0) <= 1.0 and a.min(initial=0) >= 0.0:
            a = a * 255.0
    elif a.dtype == np.uint16:
        a = a.astype(np.float32) / 257.0
    elif a.dtype != np.uint8:
        a = a.astype(np.float32)
    if a.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if a.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        a = cv2.cvtColor(np.ascontiguousarray(a), code)
    return np.ascontiguousarray(a, dtype=np.float32)


def to_bgr8(image) -> np.ndarray:
    """An image array as 8-bit BGR, for writing and drawing.

    Grey (HxW or HxWx1), BGR and BGRA arrays are accepted. uint8 is kept
    as it is; uint16 is divided by 257; floats whose maximum is at most 1 are
    taken as [0, 1] and multiplied by 255, other floats and integers are
    clipped to [0, 255] (NaN becomes 0).

    Examples
    --------
    >>> to_bgr8(np.full((2, 3), 0.5)).shape, to_bgr8(np.full((2, 3), 0.5))[0, 0]
    ((2, 3, 3), array([127, 127, 127], dtype=uint8))
    >>> int(to_bgr8(np.full((2, 2), 65535, np.uint16))[0, 0, 0])
    255
    """
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (3, 4)):
        raise ImageValueError(f"expected a grey, BGR or BGRA image, got an array of shape {a.shape}")
    if a.dtype == np.uint16:
        a = a.astype(np.float32) / 257.0
    if a.dtype != np.uint8:
        a = a.astype(np.float32)
        if a.size and np.nanmax(a) <= 1.0:
            a = a * 255.0
        a = np.clip(np.nan_to_num(a), 0, 255).astype(np.uint8)
    if a.ndim == 2:
        return cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    if a.shape[2] == 4:
        return cv2.cvtColor(a, cv2.COLOR_BGRA2BGR)
    return a


def write_image(path, image) -> None:
    """Write an image array to ``path`` (the format from its extension, as
    ``cv2.imwrite``); raises :class:`~seahough.errors.WriteError` naming the
    file when it cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_image(os.path.join(d, "a.png"), np.zeros((4, 5), np.uint8))
    ...     read_image(os.path.join(d, "a.png")).shape
    (4, 5)
    """
    try:
        ok = cv2.imwrite(os.fspath(path), image)
    except cv2.error:
        ok = False
    if not ok:
        raise WriteError(f"{path}: cannot write the image")
