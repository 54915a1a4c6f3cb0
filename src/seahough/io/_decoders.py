"""Decoding image files without a word on stderr: JPEG through libjpeg-turbo
(``simplejpeg``, its warnings as exceptions), PNG checked by Pillow and decoded
by OpenCV from the chunks that make the pixels, anything else by OpenCV with
its log silenced (:mod:`seahough.io.images` says which decoder reads what).
"""

from __future__ import annotations

import contextlib
import io
import threading
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import simplejpeg
from PIL import Image

from ..errors import ImageReadError


@dataclass
class _Header:
    """What Pillow (or, for JPEG, libjpeg-turbo) reads from a file's header."""

    width: int
    height: int
    channels: int = 3
    sample_bytes: int = 1
    floating: bool = False
    frames: int = 1
    format: str = ""
    orientation: int = 1
    image: Image.Image | None = None


_quiet_lock = threading.Lock()
_quiet_users = 0
_quiet_saved = None


@contextlib.contextmanager
def _quiet_opencv():
    """OpenCV's own log silenced while any thread decodes or encodes through
    it ("can't read header" lines would reach stderr beside our message); its
    level is restored when the last one finishes. Process-wide, as OpenCV's
    log level is, but never at the level of file descriptors."""
    global _quiet_users, _quiet_saved
    with _quiet_lock:
        if _quiet_users == 0:
            _quiet_saved = cv2.utils.logging.getLogLevel()
            cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
        _quiet_users += 1
    try:
        yield
    finally:
        with _quiet_lock:
            _quiet_users -= 1
            if _quiet_users == 0:
                cv2.utils.logging.setLogLevel(_quiet_saved)


def _opencv_decode(data: bytes):
    with _quiet_opencv():
        try:
            return cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED)
        except cv2.error:
            return None


def _pillow_problem(head: _Header | None) -> str:
    """Why Pillow cannot decode the image (for a message), or '': asked only
    of its decoders that print nothing (its libtiff prints on stderr)."""
    if head is None or head.image is None or head.format not in ("BMP", "GIF", "PPM", "WEBP"):
        return ""
    try:
        head.image.load()
    except Exception as e:
        return " ".join(str(e).split())[:160]
    return ""


def _tj(e: Exception) -> str:
    """libjpeg-turbo's message, without the TurboJPEG function it came through."""
    text = " ".join(str(e).split())
    return text.split("(): ", 1)[1] if text.startswith("tj") and "(): " in text else text


def _decode_jpeg(p: Path, data: bytes) -> np.ndarray:
    """A JPEG as OpenCV decodes it (grey, or BGR), refusing what libjpeg-turbo
    reports as damaged: its warnings are exceptions here, not stderr lines."""
    try:
        space = simplejpeg.decode_jpeg_header(data)[2]
    except ValueError as e:
        return _jpeg_by_opencv(p, data, _tj(e))
    target = {"Gray": "GRAY", "CMYK": "CMYK", "YCCK": "CMYK"}.get(space, "BGR")
    try:
        img = simplejpeg.decode_jpeg(data, target, strict=True)
    except ValueError as e:
        img = _jpeg_warned(p, data, target, _tj(e))
    if target == "CMYK":  # sound; OpenCV turns CMYK into BGR its own way: keep its colours
        return _jpeg_by_opencv(p, data, "CMYK")
    return img.reshape(img.shape[:2]) if img.shape[2] == 1 else img


#: libjpeg warnings about a header oddity that leaves the pixels sound
_JPEG_HARMLESS = ("Invalid SOS parameters", "Warning: unknown JFIF", "Unknown Adobe color")


def _jpeg_warned(p: Path, data: bytes, target: str, first: str) -> np.ndarray:
    """The JPEG whose strict decoding stopped at ``first``: decoded past a
    harmless warning, else refused (truncated, or damaged data)."""
    if first.startswith("Premature end of JPEG file"):
        raise ImageReadError(f"{p}: truncated JPEG (the image data ends early)")
    if first.startswith(_JPEG_HARMLESS):
        try:
            return simplejpeg.decode_jpeg(data, target, strict=False)
        except ValueError:
            pass
    raise ImageReadError(f"{p}: corrupt JPEG data ({first})")


def _jpeg_by_opencv(p: Path, data: bytes, why: str) -> np.ndarray:
    """A JPEG decoded by OpenCV's libjpeg (silent on fatal errors): a CMYK
    one (already found sound), or one using what TurboJPEG lacks (12-bit,
    lossless, unusual sampling); any other fatal error is refused as is."""
    lacks = ("Unsupported JPEG", "subsampling", "not supported", "omitted at compile time")
    if why != "CMYK" and not any(w in why for w in lacks):
        raise ImageReadError(f"{p}: not a JPEG that can be decoded ({why})")
    img = _opencv_decode(data)
    if img is None:
        raise ImageReadError(f"{p}: not a JPEG that can be decoded ({why})")
    return img


def _png_image_chunks(data: bytes) -> tuple[bytes, bytes | None]:
    """The PNG with only the chunks that make its pixels (no metadata for
    libpng to warn about), and the content of its eXIf chunk (or None)."""
    out, i, exif = [data[:8]], 8, None
    while i + 8 <= len(data):
        kind = data[i + 4:i + 8]
        end = i + 12 + int.from_bytes(data[i:i + 4], "big")
        if kind in (b"IHDR", b"PLTE", b"tRNS", b"IDAT", b"IEND"):
            out.append(data[i:end])
        elif kind == b"eXIf":
            exif = data[i + 8:end - 4]
        if kind == b"IEND":
            break
        i = end
    return b"".join(out), exif


def _png_not_read(p: Path, data: bytes, head: _Header | None, err: Exception | None) -> str:
    """The message for a PNG that Pillow cannot read: truncated, damaged, or no PNG."""
    if head is None:  # Pillow did not take it as a PNG at all: say why, from the header
        if len(data) < 33 or data[12:16] != b"IHDR":
            return f"{p}: truncated PNG (the file ends in its header)" if len(data) < 33 \
                else f"{p}: not a valid PNG (no IHDR chunk first)"
        w, h = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
        if w == 0 or h == 0:
            return f"{p}: not a valid PNG (its header claims {w}x{h} pixels)"
        return f"{p}: not a valid PNG (a header Pillow cannot read)"
    why = " ".join(str(err).split()) if err is not None else "its image data cannot be decoded"
    try:  # Pillow's chunk check names the damaged chunk
        Image.open(io.BytesIO(data)).verify()
    except Exception as v:
        why = " ".join(str(v).split()) or why
    if "truncated" in why.lower():
        return f"{p}: truncated PNG (the image data ends early)"
    return f"{p}: corrupt PNG data ({why[:160]})"


def _decode_png(p: Path, data: bytes, head: _Header | None) -> tuple[np.ndarray, int]:
    """A PNG as OpenCV decodes it (grey, BGR or BGRA, 8 or 16 bits) and its
    EXIF orientation. Pillow has read its header and checks every chunk
    (CRCs, the end of the file); OpenCV (libpng, faster than Pillow's own
    decoder) then decodes only the chunks that make the pixels, with its log
    silenced, so libpng has nothing to say on stderr. (A deflate stream
    damaged under an intact CRC, which takes deliberate work, would still get
    one libpng line through.)"""
    if head is None or head.format != "PNG":
        raise ImageReadError(_png_not_read(p, data, None, None))
    if head.image is not None:
        head.image.close()
        head.image = None
    try:  # every chunk's CRC and the end of the file, before libpng sees them: it
        # prints its errors (truncation, damaged chunks) on stderr itself
        Image.open(io.BytesIO(data)).verify()
    except Exception as e:
        raise ImageReadError(_png_not_read(p, data, head, e)) from None
    chunks, exif = _png_image_chunks(data)
    img = _opencv_decode(chunks)
    if img is None:
        raise ImageReadError(_png_not_read(p, data, head, None))
    orientation = 1
    if exif is not None:
        try:
            tags = Image.Exif()
            tags.load(exif)
            orientation = int(tags.get(0x0112, 1))
        except Exception:  # damaged metadata: the pixels as stored
            pass
    return img, orientation
