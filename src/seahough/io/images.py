"""Image input and output: a path or an array in, a finite float32 grey image
out; arrays and figures written to files, with errors that name the file.

Decoders
--------
No decoder may write to the process's stderr, and nothing here touches the
process's file descriptors (other threads' output is never caught):

- JPEG: libjpeg-turbo through ``simplejpeg``, whose warnings ("Corrupt JPEG
  data: ...", "Premature end of JPEG file") come back as exceptions;
- PNG: Pillow reads the header; OpenCV decodes the chunks that make the pixels
  (no metadata for libpng to warn about, its log silenced); a damaged one is
  described by Pillow's chunk check;
- anything else: OpenCV, with OpenCV's own log silenced while it decodes.

Pillow reads every header first: the size, the number of frames or pages, the
EXIF orientation and what decoding would cost in memory are known, and
checked, before a pixel is decoded.
"""

from __future__ import annotations

import contextlib
import io
import os
from pathlib import Path

import cv2
import numpy as np
import simplejpeg
from PIL import Image

from .._validate import number
from ..config import MAX_MEMORY_MB
from ..errors import ImageReadError, ImageSizeError, ImageValueError, ParameterError, WriteError
from ._decoders import (_Header, _decode_jpeg, _decode_png, _opencv_decode, _pillow_problem,
                        _quiet_opencv)
from .hidden import fill_hidden, hidden_pixels
from .levels import DIM_UNIT, OVERSHOOT, _unit_levels, say_bits, say_levels  # noqa: F401

#: The smallest side, in pixels, an image must have to hold any edge.
MIN_SIDE = 8
#: Default memory budget (MB) of reading and searching one image file.
#: Bytes per image pixel that a search's working arrays take beyond the grey
#: image, with the default downscaling (measured: docs/errors.md, "Images").
_SEARCH_BYTES = 4
#: EXIF orientations (the tag's values) and how to show the stored pixels.
_SHOW = {
    2: lambda a: a[:, ::-1],
    3: lambda a: a[::-1, ::-1],
    4: lambda a: a[::-1],
    5: lambda a: a.swapaxes(0, 1),
    6: lambda a: np.rot90(a, -1),
    7: lambda a: a[::-1, ::-1].swapaxes(0, 1),
    8: lambda a: np.rot90(a, 1),
}
#: ... and back (6 and 8 undo each other; the others undo themselves).
_UNSHOW = {**_SHOW, 6: _SHOW[8], 8: _SHOW[6]}
#: Pillow modes as OpenCV decodes them: (channels, bytes per sample).
_LAYOUT = {"1": (1, 1), "L": (1, 1), "P": (3, 1), "PA": (4, 1), "LA": (4, 1), "La": (4, 1),
           "RGB": (3, 1), "RGBA": (4, 1), "RGBa": (4, 1), "RGBX": (4, 1), "CMYK": (3, 1),
           "YCbCr": (3, 1), "LAB": (3, 1), "HSV": (3, 1), "I": (1, 4), "F": (1, 4)}
#: formats whose frames are an animation or pages (a phone's MPO is one photo)
_MULTI = {"GIF": "animated", "PNG": "animated", "WEBP": "animated", "AVIF": "animated",
          "TIFF": "multi-page"}
_JPEG = b"\xff\xd8\xff"
_PNG = b"\x89PNG\r\n\x1a\n"


def _probe(data: bytes) -> _Header | None:
    """The header of ``data``, or None when neither Pillow nor (for a JPEG)
    libjpeg-turbo recognises it. A PNG's orientation is read after decoding
    (Pillow would decode it to find an eXIf chunk after the image data)."""
    Image.MAX_IMAGE_PIXELS = None  # our own limits apply, below
    try:
        im = Image.open(io.BytesIO(data))
        w, h = im.size
    except Exception:
        if data[:3] != _JPEG:
            return None
        try:
            h, w, space, _ = simplejpeg.decode_jpeg_header(data)
        except ValueError:
            return None
        return _Header(w, h, channels=1 if space == "Gray" else 3, format="JPEG")
    mode = im.mode
    try:
        args = im.tile[0][3]
        raw = args[0] if isinstance(args, tuple) else args
    except (IndexError, TypeError):
        raw = ""
    raw = raw if isinstance(raw, str) else ""
    if mode.startswith("I;16"):
        c, b = 1, 2
    else:
        c, b = _LAYOUT.get(mode, (4, 4))
        if "16" in raw:
            b = 2
        if mode == "P" and "transparency" in im.info:
            c = 4
    head = _Header(w, h, c, b, floating=mode == "F" or raw.endswith("F"),
                   format=im.format or "", image=im)
    try:
        head.frames = int(getattr(im, "n_frames", 1))
        if head.format != "PNG":
            head.orientation = int(im.getexif().get(0x0112, 1))
    except Exception:  # damaged metadata: decode the pixels as stored
        pass
    return head


def memory_needed(width: int, height: int, *, channels: int = 1, sample_bytes: int = 1,
                  floating: bool = False, file_bytes: int = 0) -> int:
    """Bytes that reading a ``width`` x ``height`` image file and searching
    it take at their peak, beyond the program itself.

    The model, per pixel: the decoded array (``channels`` x ``sample_bytes``),
    plus the largest of a second copy of it (a decoder's buffer, or turning
    it as the EXIF orientation says), :func:`to_gray`'s conversion (a float32
    copy of deep or float colours, or an 8-bit grey one, a NaN mask, and the
    float32 grey image), and the grey image with a search's working arrays
    (measured; they are small at the default downscaling); and twice the
    file's size (its bytes, and a copy some decoders make). It bounds the
    measured peaks in docs/errors.md.

    Examples
    --------
    >>> memory_needed(1000, 1000)                          # 8-bit grey: 9 bytes a pixel
    9000000
    >>> memory_needed(1000, 1000, channels=3, sample_bytes=2) // 1000000
    22
    """
    decoded = channels * sample_bytes
    convert = (4 * channels if sample_bytes > 1 or floating else 1) if channels > 1 else 0
    convert += channels if floating else 0
    per_px = decoded + max(decoded, convert + 4, 4 + _SEARCH_BYTES)
    return int(width) * int(height) * per_px + 2 * int(file_bytes)


def _check_header(p: Path, head: _Header, size: int, max_pixels: int,
                  max_memory_mb: float) -> None:
    """Refuse, before decoding: too many pixels, several frames, too much memory."""
    w, h = head.width, head.height
    if w * h > max_pixels:
        raise ImageSizeError(
            f"{p}: header claims {w}x{h} = {w * h} pixels, over the limit of "
            f"{max_pixels} (Config.max_pixels); refusing to decode")
    kind = _MULTI.get(head.format)
    if kind and head.frames > 1:
        what = "frames" if kind == "animated" else "pages"
        raise ImageReadError(f"{p}: {kind} image with {head.frames} {what}: extract the "
                             f"{what[:-1]} to search (only single images are read)")
    need = memory_needed(w, h, channels=head.channels, sample_bytes=head.sample_bytes,
                         floating=head.floating, file_bytes=size)
    if need > max_memory_mb * 2 ** 20:
        depth = f"{8 * head.sample_bytes}-bit {'float' if head.floating else 'integer'}"
        raise ImageSizeError(
            f"{p}: {w}x{h} pixels of {head.channels} channel(s), {depth}, need about "
            f"{-(-need // 2 ** 20)} MB to read and search, over the memory limit of "
            f"{max_memory_mb:g} MB; refusing to decode (raise Config.max_memory_mb, or read_image's max_memory_mb, to allow it)")


def read_image(path: str | os.PathLike, *, max_pixels: int = 200_000_000,
               max_memory_mb: float = MAX_MEMORY_MB, orientation: str = "exif") -> np.ndarray:
    """Read an image file as OpenCV's ``IMREAD_UNCHANGED`` gives it (any
    depth; grey, BGR or BGRA), turned as the photo is shown.

    Parameters
    ----------
    path : str or PathLike
        The file: JPEG, PNG, TIFF, WebP, BMP, a single-frame GIF, or any
        other format OpenCV reads. Bytes after the image (a phone's motion
        video after a JPEG, a camera's trailer) are ignored. Also a video's
        frame as :func:`~seahough.list_frames` names it, ``"dive.mp4#12"``
        (decoded from the video's start: :func:`~seahough.iter_frames`
        reads them all in order); or a NumPy ``.npy`` file of an image's
        array (a float sonar tile: its levels as :func:`to_gray` reads them).
    max_pixels : int
        Files whose header claims more pixels are refused before decoding.
    max_memory_mb : float
        Files that would need more memory (MB) to read and search, by
        :func:`memory_needed`, are refused before decoding.
    orientation : {"exif", "stored"}
        ``"exif"``: turned and flipped as the EXIF Orientation tag says, as
        phones, cameras and viewers show the photo (positions found in it are
        in those pixels). ``"stored"``: the pixels as stored in the file.

    Raises
    ------
    ImageReadError
        Missing, unreadable, truncated, damaged, not an image, or an
        animation or several pages.
    ImageSizeError
        Empty, or larger than ``max_pixels`` or ``max_memory_mb`` allow.
    ParameterError
        ``orientation`` or ``max_memory_mb`` out of range.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_image(os.path.join(d, "a.jpg"), np.zeros((30, 40, 3), np.uint8))
    ...     read_image(os.path.join(d, "a.jpg")).shape
    (30, 40, 3)
    """
    if orientation not in ("exif", "stored"):
        raise ParameterError(f"orientation={orientation!r}: must be 'exif' or 'stored'")
    number("max_memory_mb", max_memory_mb, lo=0.0, lo_open=True)
    p = Path(path)
    if not p.exists():
        from .frames import FrameReader, printable, split_video_ref, video_ref_problem

        ref = split_video_ref(str(path))
        if ref is not None and Path(ref[0]).is_file():
            # a video's frame, as seahough.list_frames names it (decoded from the
            # start: iter_frames reads a video's frames in order)
            reader = FrameReader([str(path)], max_pixels, max_memory_mb)
            try:
                return reader.raw(0)
            finally:
                reader.close()
        if os.path.islink(p):   # (the folder shows it: say why it cannot be read)
            raise ImageReadError(f"{p}: broken symbolic link (to "
                                 f"{printable(os.readlink(p))})")
        raise ImageReadError(video_ref_problem(str(path)) or f"{p}: no such file")
    if p.is_dir():
        raise ImageReadError(f"{p}: is a folder, not an image")
    if p.suffix.lower() == ".npy":
        return _read_npy(p, max_pixels, max_memory_mb)
    from .frames import VIDEO_EXTENSIONS
    if p.suffix.lower() in VIDEO_EXTENSIONS:   # (not read whole: a dive's video is gigabytes)
        raise ImageReadError(f"{p}: a video, not an image: one of its frames is {p}#12 (from "
                             "0); all of them: seahough.iter_frames, or list it among frames")
    try:
        data = p.read_bytes()
    except OSError as e:
        raise ImageReadError(f"{p}: cannot read ({e.strerror or e})") from None
    if not data:
        raise ImageReadError(f"{p}: empty file")
    head = _probe(data)
    if head is not None:
        _check_header(p, head, len(data), max_pixels, max_memory_mb)
    turned = 1  # the orientation the decoder has already applied
    if data[:3] == _JPEG:
        img = _decode_jpeg(p, data)
    elif data[:8] == _PNG:
        img, shown = _decode_png(p, data, head)
        head.orientation = shown
    else:
        img = _opencv_decode(data)
        if img is None:
            why = _pillow_problem(head)
            raise ImageReadError(f"{p}: not an image OpenCV can decode"
                                 + (f" ({why})" if why else ""))
        if head is not None and head.format == "TIFF" and _opencv_turns_tiff():
            turned = head.orientation
    if img.size == 0:
        raise ImageSizeError(f"{p}: image has no pixels")
    want = head.orientation if head is not None and orientation == "exif" else 1
    if want != turned:
        if turned in _UNSHOW:
            img = _UNSHOW[turned](img)
        if want in _SHOW:
            img = _SHOW[want](img)
        img = np.ascontiguousarray(img)
    return img


_tiff_turned: list = []


def _opencv_turns_tiff() -> bool:
    """Whether OpenCV's TIFF decoder applies the Orientation tag itself
    (OpenCV 5's does, even for IMREAD_UNCHANGED): asked once, of a 2x1 TIFF
    turned upside down."""
    if not _tiff_turned:
        buf = io.BytesIO()
        Image.fromarray(np.array([[0, 255]], np.uint8)).save(buf, "TIFF", tiffinfo={274: 3})
        img = _opencv_decode(buf.getvalue())
        _tiff_turned.append(img is not None and int(img[0, 0]) == 255)
    return _tiff_turned[0]


def _read_npy(p: Path, max_pixels: int, max_memory_mb: float) -> np.ndarray:
    """A NumPy ``.npy`` file's array as an image (HxW, HxWx3 or HxWx4; its
    levels are read as :func:`to_gray` reads an array's): a sonar's float
    backscatter saved by a script. Its shape and size are checked before it
    is read."""
    try:
        a = np.load(p, mmap_mode="r", allow_pickle=False)
    except (OSError, ValueError) as e:
        raise ImageReadError(f"{p}: not a NumPy array file ({e})") from None
    if not isinstance(a, np.ndarray):        # (an .npz archive so named)
        a.close()
        raise ImageReadError(f"{p}: a NumPy archive of several arrays (.npz), not one array")
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (1, 3, 4)):
        raise ImageReadError(f"{p}: a NumPy array of shape {a.shape}, not an image (HxW, "
                             "HxWx3 or HxWx4)")
    if a.shape[0] * a.shape[1] > max_pixels:
        raise ImageSizeError(f"{p}: {a.shape[1]}x{a.shape[0]} pixels is over the limit of "
                             f"{max_pixels}")
    need = memory_needed(a.shape[1], a.shape[0], channels=a.shape[2] if a.ndim == 3 else 1,
                         sample_bytes=a.dtype.itemsize, floating=a.dtype.kind == "f",
                         file_bytes=a.nbytes)
    if need > max_memory_mb * 2 ** 20:
        raise ImageSizeError(f"{p}: a {a.shape} {a.dtype} array needs about "
                             f"{need / 2 ** 20:.0f} MB to read and search, over the memory limit "
                             f"of {max_memory_mb:g} MB (raise Config.max_memory_mb to allow it)")
    return np.array(a[:, :, 0] if a.ndim == 3 and a.shape[2] == 1 else a)


def to_gray(image, *, name: str = "image", max_pixels: int = 200_000_000,
            min_side: int = MIN_SIDE, max_memory_mb: float = MAX_MEMORY_MB,
            orientation: str = "exif", bit_depth: int | None = None) -> np.ndarray:
    """A path or array as a float32 grey image with grey levels in [0, 255].

    Accepts grey (HxW or HxWx1), BGR or BGRA arrays of dtype uint8, uint16,
    other integers, bool or float. uint16 is divided by 257 (``bit_depth``:
    by ``(2**bit_depth - 1) / 255``, a camera's fewer bits in 16-bit files,
    then clipped to 255); floats in [0, 1] are multiplied by 255 (so are a
    0-1 image's few values pushed a little over 1 or under 0, saturated:
    :data:`~.levels.OVERSHOOT`); other floats are levels 0-255 as they are (a
    :class:`~seahough.errors.LevelsWarning` when they look like another
    scale: under -0.5, over 1024, a float64 image at most 10); a BGRA image's
    transparent pixels are filled (:func:`~seahough.io.hidden.fill_hidden`). A path is
    read by :func:`read_image` (with ``max_pixels``, ``max_memory_mb``, ``orientation``).
    An array that is already such an image (C-contiguous HxW float32, levels
    0-255, not read as 0-1) is not copied: the result is a read-only view of it
    (a 12 MP frame's copy is 46 MB). Copy it to write into it.

    Examples
    --------
    >>> to_gray(np.full((10, 12, 3), 255, np.uint8)).shape
    (10, 12)
    >>> g = np.full((10, 12), 80.0, np.float32)
    >>> v = to_gray(g)
    >>> bool(np.shares_memory(v, g)), v.flags.writeable
    (True, False)
    """
    a = _levels(image, name, max_pixels, min_side, max_memory_mb, orientation, bit_depth)
    return fill_hidden(_grey(a), hidden_pixels(a[:, :, 3] if a.shape[2:] == (4,) else None))


def to_image(image, colour: bool = False, *, name: str = "image",
             max_pixels: int = 200_000_000, min_side: int = MIN_SIDE,
             max_memory_mb: float = MAX_MEMORY_MB, orientation: str = "exif",
             bit_depth: int | None = None) -> np.ndarray:
    """A path or array as the working image of a search: grey, or BGR when
    ``colour`` is True and the image has colour (``Config.colour``).

    The same checks, limits, messages and levels as :func:`to_gray` (which
    this is when ``colour`` is False). With ``colour``, a BGR or BGRA image
    comes back as HxWx3 float32 BGR levels in [0, 255] (transparent pixels filled); a
    grey one, or one whose three channels are equal everywhere (no colour to
    see), comes back as :func:`to_gray` makes it, so that its search is the
    grey search, bit for bit.

    Examples
    --------
    >>> bgr = np.zeros((10, 12, 3), np.uint8); bgr[..., 2] = 200   # red
    >>> to_image(bgr).shape, to_image(bgr, colour=True).shape
    ((10, 12), (10, 12, 3))
    >>> to_image(np.full((10, 12, 3), 9, np.uint8), colour=True).shape   # no colour in it
    (10, 12)
    """
    a = _levels(image, name, max_pixels, min_side, max_memory_mb, orientation, bit_depth)
    hidden = hidden_pixels(a[:, :, 3] if a.shape[2:] == (4,) else None)
    if not colour or a.ndim == 2:
        return fill_hidden(_grey(a), hidden)
    a = a[:, :, :3]
    if np.array_equal(a[:, :, 0], a[:, :, 1]) and np.array_equal(a[:, :, 0], a[:, :, 2]):
        return fill_hidden(_grey(a), hidden)
    return fill_hidden(np.ascontiguousarray(a, dtype=np.float32), hidden)   # (BGRA: a copy)


def _levels(image, label, max_pixels, min_side, max_memory_mb, orientation,
            bit_depth=None) -> np.ndarray:
    """:func:`to_gray`'s checks and levels, before the colours are mixed:
    HxW, HxWx3 or HxWx4, uint8 or float32 in [0, 255]."""
    if isinstance(image, (str, os.PathLike)):
        label = str(image)
        image = read_image(image, max_pixels=max_pixels, max_memory_mb=max_memory_mb,
                           orientation=orientation)
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
        lo, hi = float(a.min(initial=0)), float(a.max(initial=0))
        unit = _unit_levels(a, lo, hi)
        if not unit:
            # (float32 is also what the package hands itself: a dark 8-bit frame
            # converted once is no "dim float image" of the user's)
            say_levels(lo, hi, label, dim=a.dtype != np.float32)
        elif 0.0 < hi < DIM_UNIT or hi > OVERSHOOT:
            say_levels(lo, hi, label, unit=True)
        if not unit and a.dtype == np.float32 and a.flags.c_contiguous and a.ndim == 2:
            # already the levels a search works on (a frame cropped and checked
            # before): no copy (a 12 MP frame's is 46 MB), a read-only view
            a = a.view()
            a.flags.writeable = False
            return a
        a = a.astype(np.float32)  # a copy: scaled in place (no second copy)
        if unit:
            a *= 255.0
            if hi > 1.0 or lo < 0.0:   # (a 0-1 image's overshoot: saturated, as 1 and 0 are)
                np.clip(a, 0.0, 255.0, out=a)
    elif a.dtype == np.uint16:
        most = None if bit_depth is None else 2 ** int(bit_depth) - 1
        if most is not None and int(a.max(initial=0)) > most:
            # a few hot pixels are clipped; more than 1 % beyond the stated
            # depth: wider samples (read so, the frame would be mostly white)
            over = np.count_nonzero(a > most)
            if over > 0.01 * a.size:
                raise ImageValueError(
                    f"{label}: {100.0 * over / a.size:.0f} % of the values are beyond "
                    f"bit_depth={int(bit_depth)} (0-{most}), up to {int(a.max())}: these "
                    f"are wider samples; give their bit depth, or none for 16-bit data")
        elif most is None:
            say_bits(int(a.max(initial=0)), label)
        a = a.astype(np.float32)
        a /= uint16_divisor(bit_depth)
        if most is not None:     # (values beyond the stated depth)
            np.minimum(a, 255.0, out=a)
    elif a.dtype != np.uint8:
        a = a.astype(np.float32)
    return a


def uint16_divisor(bit_depth: int | None = None) -> float:
    """What a uint16 image is divided by to give levels 0-255: 257 (16-bit
    data), or ``(2**bit_depth - 1) / 255`` for a camera's ``bit_depth``-bit
    samples in 16-bit files (:attr:`seahough.Config.bit_depth`).

    >>> uint16_divisor(), uint16_divisor(12) * 255
    (257.0, 4095.0)
    """
    return 257.0 if bit_depth is None else (2.0 ** int(bit_depth) - 1.0) / 255.0


def _grey(a: np.ndarray) -> np.ndarray:
    """:func:`_levels`' image as float32 grey (OpenCV's BGR weights)."""
    if a.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if a.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        a = cv2.cvtColor(np.ascontiguousarray(a), code)
    return np.ascontiguousarray(a, dtype=np.float32)


def to_bgr8(image, bit_depth: int | None = None) -> np.ndarray:
    """An image array as 8-bit BGR, for writing and drawing.

    Grey (HxW or HxWx1), BGR and BGRA arrays are accepted. uint8 is kept
    as it is; uint16 is divided by 257 (or as ``bit_depth``-bit data,
    :func:`uint16_divisor`); floats read as 0-1 levels (as :func:`to_gray`
    reads them) are multiplied by 255, other floats and integers are
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
        # (straight to 8 bits: a dark 16-bit image is not taken for [0, 1] floats)
        a = np.minimum(a.astype(np.float32) / uint16_divisor(bit_depth), 255.0).astype(np.uint8)
    if a.dtype != np.uint8:
        a = a.astype(np.float32)
        if a.size and _unit_levels(a, float(np.nanmin(a)), float(np.nanmax(a))):
            a = a * 255.0
        a = np.clip(np.nan_to_num(a), 0, 255).astype(np.uint8)
    if a.ndim == 2:
        return cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    if a.shape[2] == 4:
        return cv2.cvtColor(a, cv2.COLOR_BGRA2BGR)
    return a


def write_bytes(path, data, *, what: str = "the file") -> None:
    """Write ``data`` to ``path`` (created or replaced); a
    :class:`~seahough.errors.WriteError` naming the file and the system's
    reason when it cannot be written (no folder, no permission, a full disk).
    A file cut short by a failing write is removed, not left half-written.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_bytes(os.path.join(d, "a.txt"), b"abc")
    ...     try:
    ...         write_bytes(os.path.join(d, "no", "b.txt"), b"abc", what="the note")
    ...     except WriteError as e:
    ...         print(str(e).replace(d, "DIR"))
    DIR/no/b.txt: cannot write the note (No such file or directory)
    """
    opened = False
    try:
        with open(path, "wb") as f:
            opened = True
            f.write(data)
    except OSError as e:
        if opened and os.path.isfile(path):  # a regular file we began: not left cut short
            with contextlib.suppress(OSError):
                os.remove(path)
        raise WriteError(f"{path}: cannot write {what} ({e.strerror or e})") from None


def write_image(path, image, *, what: str = "the image") -> None:
    """Write an image array to ``path``, encoded by OpenCV in the format of
    its extension (PNG without one), with :func:`write_bytes`: a
    :class:`~seahough.errors.WriteError` naming the file when it cannot be
    encoded or written, and nothing printed by the encoders.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_image(os.path.join(d, "a.png"), np.zeros((4, 5), np.uint8))
    ...     read_image(os.path.join(d, "a.png")).shape
    (4, 5)
    """
    ext = os.path.splitext(os.fspath(path))[1].lower() or ".png"
    try:
        with _quiet_opencv():
            ok, buf = cv2.imencode(ext, image)
    except cv2.error:
        ok = False
    if not ok:
        a = np.asarray(image)
        raise WriteError(f"{path}: cannot write {what} (OpenCV cannot encode an array of "
                         f"shape {a.shape} and dtype {a.dtype} as {ext})")
    write_bytes(path, buf, what=what)
