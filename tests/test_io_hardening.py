"""Reading and writing image files without losing, splicing or swallowing anything
(issue 18): other threads' stderr, trailers after the image, damaged JPEG data,
EXIF orientation, animations, the memory budget, and writes on a full disk.

Each test here failed before the fix it covers, except four that guard the
new decoders against the old ones' answers: nothing printed for bad files,
the corruptions libjpeg flags, and PNGs and JPEGs of every kind read as
OpenCV reads them.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image, ImageOps

from seahough import ImageReadError, ImageSizeError, ParameterError, WriteError, read_image, to_gray

from conftest import data_path

REAL_JPEG = ("seabed", "dtu_starfish_murky.jpg")


def _scene(h=120, w=160) -> np.ndarray:
    img = np.full((h, w), 40, np.uint8)
    cv2.rectangle(img, (w // 3, h // 3), (w // 3 + 60, h // 3 + 40), 220, -1)
    return img


def _noise(shape, seed=0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, shape).astype(np.uint8)


def _encode(ext, img, *params) -> bytes:
    ok, buf = cv2.imencode(ext, img, list(params))
    assert ok
    return buf.tobytes()


def _entropy_span(data: bytes) -> tuple[int, int]:
    """(first byte after the SOS header, index of the EOI marker) of a baseline JPEG."""
    i = 2
    while True:
        assert data[i] == 0xFF, i
        marker = data[i + 1]
        length = struct.unpack(">H", data[i + 2:i + 4])[0]
        if marker == 0xDA:
            return i + 2 + length, data.rindex(b"\xff\xd9")
        i += 2 + length


def _bad_files(d: Path) -> list[Path]:
    """Files whose decoders have something to say: damaged, truncated at many
    places, 0x0, not an image; and good ones among them."""
    jpg = _encode(".jpg", _noise((120, 160, 3), 1))
    png = _encode(".png", _noise((120, 160), 2))
    files = {"good.jpg": jpg, "good.png": png}
    for k, cut in enumerate((5, 40, 200, len(jpg) // 2, len(jpg) - 2)):
        files[f"cut{k}.jpg"] = jpg[:cut]
    for k, cut in enumerate((10, 30, 60, len(png) // 2, len(png) - 6)):
        files[f"cut{k}.png"] = png[:cut]
    bad = bytearray(jpg)
    bad[len(bad) // 2: len(bad) // 2 + 256] = bytes(256)
    files["zeroed.jpg"] = bytes(bad)
    bad = bytearray(png)
    bad[len(bad) // 2: len(bad) // 2 + 64] = bytes(64)
    files["zeroed.png"] = bytes(bad)
    zero = bytearray(png)
    ihdr = b"IHDR" + struct.pack(">II", 0, 0) + bytes(zero[24:29])
    zero[12:29] = ihdr
    zero[29:33] = struct.pack(">I", zlib.crc32(ihdr) & 0xFFFFFFFF)
    files["zero.png"] = bytes(zero)
    files["text.png"] = b"not an image\n"
    files["cut.tiff"] = _encode(".tiff", _noise((120, 160), 3))[:500]
    files["cut.webp"] = _encode(".webp", _noise((120, 160, 3), 4))[:300]
    out = []
    for name, data in files.items():
        (d / name).write_bytes(data)
        out.append(d / name)
    return out


# ------------------------------------------------- 1: other threads' stderr
_STDERR_CHILD = r"""
import os, sys, threading, time
from pathlib import Path
import seahough
files = [Path(p) for p in sys.argv[1:]]
done = threading.Event()
reads = [0]

def reader():
    while not done.is_set() or reads[0] < 3 * len(files):
        for f in files:
            try:
                seahough.read_image(f)
            except seahough.SeahoughError:
                pass
            reads[0] += 1

def talker():
    for i in range(200):
        if i % 2:
            os.write(2, f"line {i}\n".encode())
        else:
            sys.stderr.write(f"line {i}\n")
            sys.stderr.flush()
        time.sleep(0.001)
    done.set()

threads = [threading.Thread(target=reader), threading.Thread(target=talker)]
for t in threads:
    t.start()
for t in threads:
    t.join()
print(reads[0])
"""


def test_reading_files_keeps_every_line_other_threads_write_to_stderr(tmp_path):
    files = _bad_files(tmp_path)
    # (-W ignore: Pillow's Python warnings about a damaged TIFF header are
    # the user's to filter; this is about what reaches file descriptor 2)
    p = subprocess.run([sys.executable, "-W", "ignore", "-c", _STDERR_CHILD, *map(str, files)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    assert int(p.stdout) >= 3 * len(files)
    lines = p.stderr.splitlines()
    # every line arrives, once, whole; and the decoders add none of their own
    assert sorted(lines) == sorted(f"line {i}" for i in range(200)), p.stderr[-2000:]


@pytest.mark.filterwarnings("ignore:Corrupt EXIF data:UserWarning")  # Pillow, on cut.tiff
def test_reading_bad_files_prints_nothing(tmp_path, capfd):
    for f in _bad_files(tmp_path):
        try:
            read_image(f)
        except ImageReadError as e:
            assert str(e).startswith(f"{f}: ") and "\n" not in str(e), e
    out, err = capfd.readouterr()
    assert out == "" and err == "", err


# ------------------------------------------------- 2: trailers, corruption
def test_jpeg_and_png_with_bytes_after_the_end_marker_read_as_without(tmp_path):
    mp4 = struct.pack(">I", 24) + b"ftypmp42" + bytes(12) + _noise(5000, 9).tobytes()
    cases = {
        ".jpg": _encode(".jpg", _noise((120, 160, 3), 5)),
        ".png": _encode(".png", _noise((120, 160, 3), 6)),
    }
    for ext, data in cases.items():
        plain = tmp_path / f"plain{ext}"
        plain.write_bytes(data)
        ref = read_image(plain)
        for k, trailer in enumerate((mp4, bytes(64), b"\xff\xd8\xff\xe0 another image?")):
            p = tmp_path / f"trailer{k}{ext}"
            p.write_bytes(data + trailer)
            got = read_image(p)
            assert got.shape == ref.shape and np.array_equal(got, ref), (p, trailer[:12])


def _libjpeg_flags(datas) -> list[str]:
    """What OpenCV's libjpeg prints on stderr for each JPEG, decoded alone in
    a child process (the decoder's own verdict, independent of seahough)."""
    code = r"""
import os, sys, tempfile, json, numpy as np, cv2
out = []
for path in sys.argv[1:]:
    tmp = tempfile.TemporaryFile()
    saved = os.dup(2)
    os.dup2(tmp.fileno(), 2)
    cv2.imdecode(np.fromfile(path, np.uint8), cv2.IMREAD_UNCHANGED)
    os.dup2(saved, 2)
    tmp.seek(0)
    out.append(tmp.read().decode("utf-8", "replace").strip())
print(json.dumps(out))
"""
    p = subprocess.run([sys.executable, "-c", code, *map(str, datas)], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_every_corruption_the_jpeg_decoder_flags_is_an_error(tmp_path):
    data = data_path(*REAL_JPEG).read_bytes()
    start, eoi = _entropy_span(data)
    rng = np.random.default_rng(18)
    paths = []
    for k in range(40):
        b = bytearray(data)
        pos = int(rng.integers(start, eoi))
        if k % 2 == 0:                                     # flip one bit
            b[pos] ^= 1 << int(rng.integers(0, 8))
        else:                                              # overwrite a run of bytes
            n = min(int(rng.integers(1, 64)), eoi - pos)
            b[pos:pos + n] = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
        p = tmp_path / f"c{k:02d}.jpg"
        p.write_bytes(bytes(b))
        paths.append(p)
    flags = _libjpeg_flags(paths)
    caught = 0
    for p, flag in zip(paths, flags):
        if flag:
            with pytest.raises(ImageReadError) as info:
                read_image(p)
            assert str(info.value).startswith(f"{p}: corrupt JPEG data ("), (flag, info.value)
            caught += 1
        else:  # nothing the decoder can tell: read as OpenCV reads it
            ref = cv2.imdecode(np.fromfile(p, np.uint8), cv2.IMREAD_UNCHANGED)
            assert np.array_equal(read_image(p), ref), p
    print(f"corruptions flagged by libjpeg and refused: {caught} of 40")
    assert caught >= 20


# ------------------------------------------- the decoders give what OpenCV gives
def _pngs(d: Path) -> list[Path]:
    rng = np.random.default_rng(1)
    g = rng.integers(0, 256, (20, 24), np.uint8)
    rgb = rng.integers(0, 256, (20, 24, 3), np.uint8)
    rgba = rng.integers(0, 256, (20, 24, 4), np.uint8)
    pil = {
        "g1": (Image.fromarray(g > 128), {}),
        "g8": (Image.fromarray(g), {}),
        "g8_interlaced": (Image.fromarray(g), {}),
        "p4": (Image.fromarray(g).convert("P"), dict(bits=4)),
        "la8": (Image.fromarray(np.dstack([g, g[::-1]]), "LA"), {}),
        "rgb8": (Image.fromarray(rgb), {}),
        "rgba8": (Image.fromarray(rgba), {}),
        "p": (Image.fromarray(rgb).quantize(16), {}),
        "p_trns": (Image.fromarray(rgb).quantize(16), dict(transparency=3)),
        "g8_trns": (Image.fromarray(g), dict(transparency=17)),
        "rgb8_trns": (Image.fromarray(rgb), dict(transparency=(1, 2, 3))),
        "g16": (Image.fromarray(g.astype(np.uint16) * 257), {}),
    }
    out = []
    for name, (im, kw) in pil.items():
        im.save(d / f"{name}.png", **kw)
        out.append(d / f"{name}.png")
    cv2.imwrite(str(d / "g8_interlaced.png"), g)  # (OpenCV writes no interlaced PNG)
    for name, a in (("rgb16", rgb.astype(np.uint16) * 250), ("rgba16", rgba.astype(np.uint16) * 250),
                    ("la16", cv2.cvtColor(g, cv2.COLOR_GRAY2BGRA).astype(np.uint16) * 257)):
        cv2.imwrite(str(d / f"{name}.png"), a)
        out.append(d / f"{name}.png")
    # a 16-bit colour PNG with metadata chunks (libpng would have its say on a bad iCCP)
    data = (d / "rgb16.png").read_bytes()
    body = b"iTXt" + b"Comment\x00\x05\x07\x00\x00bad compression flag"
    chunk = struct.pack(">I", len(body) - 4) + body + struct.pack(">I", zlib.crc32(body))
    (d / "rgb16_meta.png").write_bytes(data[:33] + chunk + data[33:])
    out.append(d / "rgb16_meta.png")
    return out


def test_pngs_of_every_kind_read_as_opencv_reads_them(tmp_path, capfd):
    for p in _pngs(tmp_path):
        capfd.readouterr()
        got = read_image(p)
        assert capfd.readouterr().err == "", p
        ref = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
        assert got.dtype == ref.dtype and got.shape == ref.shape, (p.name, got.shape, ref.shape)
        assert np.array_equal(got, ref), p.name
        assert got.flags.writeable and got.flags.c_contiguous, p.name


def test_jpegs_of_every_kind_read_as_opencv_reads_them(tmp_path):
    rgb = _noise((48, 64, 3), 3)
    kinds = {"grey": (Image.fromarray(rgb[:, :, 0]), {}), "colour": (Image.fromarray(rgb), {}),
             "progressive": (Image.fromarray(rgb), dict(progressive=True)),
             "444": (Image.fromarray(rgb), dict(subsampling=0)),
             "cmyk": (Image.fromarray(rgb).convert("CMYK"), {})}
    for name, (im, kw) in kinds.items():
        p = tmp_path / f"{name}.jpg"
        im.save(p, quality=90, **kw)
        assert np.array_equal(read_image(p), cv2.imread(str(p), cv2.IMREAD_UNCHANGED)), name


# ------------------------------------------------------ 3: EXIF orientation
def _oriented_jpeg(path: Path, rgb: np.ndarray, orientation: int, fmt="JPEG") -> None:
    exif = Image.Exif()
    exif[0x0112] = orientation
    kw = dict(quality=95) if fmt == "JPEG" else {}
    Image.fromarray(rgb).save(path, fmt, exif=exif, **kw)


def _asymmetric_rgb() -> np.ndarray:
    a = np.zeros((40, 60, 3), np.uint8)
    a[2:10, 2:20] = (255, 0, 0)        # a red bar in the top-left corner
    a[30:38, 50:58] = (0, 255, 0)      # a green square near the bottom-right
    return a


def test_exif_orientation_6_gives_the_photo_as_displayed(tmp_path):
    p = tmp_path / "phone.jpg"
    _oriented_jpeg(p, _asymmetric_rgb(), 6)
    shown = np.asarray(ImageOps.exif_transpose(Image.open(p)))[:, :, ::-1]
    img = read_image(p)
    assert img.shape == (60, 40, 3)
    assert np.abs(img.astype(int) - shown).max() <= 2
    # the red bar, top-left when stored, is top-right as displayed (turned 90 degrees clockwise)
    assert img[2:20, 30:38, 2].mean() > 200 and img[2:20, 2:10, 2].mean() < 50
    assert to_gray(p).shape == (60, 40)
    # OpenCV's IMREAD_COLOR shows it the same way
    assert np.abs(img.astype(int) - cv2.imread(str(p), cv2.IMREAD_COLOR)).max() <= 2
    stored = read_image(p, orientation="stored")
    assert stored.shape == (40, 60, 3)
    assert np.array_equal(stored, cv2.imread(str(p), cv2.IMREAD_UNCHANGED))
    with pytest.raises(ParameterError, match="orientation"):
        read_image(p, orientation="sideways")


@pytest.mark.parametrize("fmt", ["PNG", "TIFF", "WEBP"])
@pytest.mark.parametrize("orientation", range(1, 9))
def test_every_orientation_of_lossless_files_matches_pillow(tmp_path, fmt, orientation):
    rgb = _asymmetric_rgb()
    p = tmp_path / f"o.{fmt.lower()}"
    if fmt == "TIFF":
        Image.fromarray(rgb).save(p, fmt, tiffinfo={274: orientation})
    else:
        kw = dict(lossless=True) if fmt == "WEBP" else {}
        exif = Image.Exif()
        exif[0x0112] = orientation
        Image.fromarray(rgb).save(p, fmt, exif=exif, **kw)
    shown = np.ascontiguousarray(np.asarray(ImageOps.exif_transpose(Image.open(p)))[:, :, ::-1])
    assert np.array_equal(read_image(p), shown)
    assert np.array_equal(read_image(p, orientation="stored"), rgb[:, :, ::-1])


# ------------------------------------------------- 4: animations, pages
def test_animated_gif_and_multipage_tiff_are_refused(tmp_path):
    frames = [Image.fromarray(_scene()).rotate(5 * k) for k in range(12)]
    gif = tmp_path / "anim.gif"
    frames[0].save(gif, save_all=True, append_images=frames[1:], duration=80, loop=0)
    with pytest.raises(ImageReadError) as info:
        read_image(gif)
    assert str(info.value).startswith(f"{gif}: animated image with 12 frames"), info.value
    tif = tmp_path / "pages.tiff"
    frames[0].save(tif, save_all=True, append_images=frames[1:3])
    with pytest.raises(ImageReadError, match=r"multi-page image with 3 pages"):
        read_image(tif)
    apng = tmp_path / "anim.png"
    frames[0].save(apng, save_all=True, append_images=frames[1:4])
    with pytest.raises(ImageReadError, match=r"animated image with 4 frames"):
        read_image(apng)
    one = tmp_path / "one.gif"
    frames[0].save(one)
    assert read_image(one).shape[:2] == (120, 160)


# ------------------------------------------------------ 5: memory budget
def _png_header_only(w: int, h: int, bit_depth: int, colour_type: int) -> bytes:
    """A PNG whose IHDR claims w x h (and the given format), with a tiny IDAT."""
    ihdr = b"IHDR" + struct.pack(">IIBBBBB", w, h, bit_depth, colour_type, 0, 0, 0)
    idat = b"IDAT" + zlib.compress(b"\x00" * 64)
    chunks = b""
    for body in (ihdr, idat, b"IEND"):
        chunks += struct.pack(">I", len(body) - 4) + body
        chunks += struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
    return b"\x89PNG\r\n\x1a\n" + chunks


def test_image_needing_more_memory_than_the_budget_is_refused_before_decoding(
        tmp_path, monkeypatch):
    import seahough.io.images as io_images

    p = tmp_path / "deep.png"
    p.write_bytes(_png_header_only(14000, 14000, 16, 2))   # 196 Mpx, 16-bit colour
    seen = []
    monkeypatch.setattr(io_images.cv2, "imdecode", lambda *a: seen.append(a))
    monkeypatch.setattr(io_images.Image.Image, "load", lambda *a: seen.append(a))
    with pytest.raises(ImageSizeError) as info:
        read_image(p)
    msg = str(info.value)
    assert msg.startswith(f"{p}: ") and "14000x14000" in msg and "max_memory_mb" in msg, msg
    assert "over the memory limit of 4096 MB" in msg, msg
    assert not seen
    monkeypatch.undo()
    # with a larger budget it is decoded (and found broken: the header lies)
    with pytest.raises(ImageReadError):
        read_image(p, max_memory_mb=1_000_000)


def test_memory_limit_boundary_and_parameter(tmp_path):
    p = tmp_path / "g.png"
    cv2.imwrite(str(p), _noise((1000, 1000), 7))
    from seahough.io.images import memory_needed
    need = memory_needed(1000, 1000, channels=1, sample_bytes=1, file_bytes=p.stat().st_size)
    assert 5_000_000 < need < 20_000_000
    mb = need / 2 ** 20
    assert read_image(p, max_memory_mb=mb).shape == (1000, 1000)
    with pytest.raises(ImageSizeError, match="memory limit"):
        read_image(p, max_memory_mb=mb * 0.99)
    with pytest.raises(ImageSizeError, match="memory limit"):
        to_gray(p, max_memory_mb=mb * 0.99)
    for bad in (0, -1, float("nan"), "lots"):
        with pytest.raises(ParameterError, match="max_memory_mb"):
            read_image(p, max_memory_mb=bad)


def test_memory_model_bounds_what_reading_allocates(tmp_path):
    """The arrays numpy and OpenCV allocate while reading and converting stay
    under the model's figure (Pillow's own buffers are not traced; the
    measured peaks of whole runs are in docs/errors.md)."""
    import tracemalloc

    from seahough.io.images import memory_needed
    cases = [(_noise((600, 800, 3), 1).astype(np.uint16) * 257, ".png", 3, 2),
             (_noise((600, 800), 2), ".png", 1, 1),
             (_noise((600, 800, 3), 3), ".png", 3, 1),
             (_noise((600, 800), 4).astype(np.float32), ".tiff", 1, 4)]
    for arr, ext, c, b in cases:
        p = tmp_path / f"m{c}{b}{ext}"
        cv2.imwrite(str(p), arr)
        tracemalloc.start()
        try:
            to_gray(p)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        model = memory_needed(800, 600, channels=c, sample_bytes=b, floating=ext == ".tiff",
                              file_bytes=p.stat().st_size)
        assert peak <= model, (p.name, peak, model)


# ---------------------------------------------------------------- 6: writing
def test_write_image_on_a_full_disk_names_the_file_and_prints_nothing(capfd):
    from seahough.io.images import write_image
    with pytest.raises(WriteError) as info:
        write_image("/dev/full", _noise((200, 200), 1))
    msg = str(info.value)
    assert msg.startswith("/dev/full: cannot write the image (") and "No space left" in msg, msg
    out, err = capfd.readouterr()
    assert out == "" and err == "", err


def test_figures_and_mosaics_on_a_full_disk_raise_write_errors(tmp_path, capfd):
    from seahough import sim
    from seahough.io.frames import FrameReader
    from seahough.motion.mosaic import build_mosaic
    from seahough.motion.odometry import run_odometry
    from seahough.viz import plot_detections

    with pytest.raises(WriteError, match=r"^/dev/full: cannot write the figure \("):
        plot_detections(_scene(), [], path="/dev/full")
    frames, _ = sim.sequence(n_frames=3, frame_size=(120, 160), path="line", step=6.0, seed=2,
                             source="procedural")
    res = run_odometry(frames, tmp_path / "run", progress=False, mosaic=False)
    with pytest.raises(WriteError, match=r"^/dev/full: cannot write the mosaic \("):
        build_mosaic(tmp_path / "run" / "odometry.csv", FrameReader(list(frames), 10 ** 8),
                     frames[0].shape[:2], Path("/dev/full"))
    assert res.rows
    out, err = capfd.readouterr()
    assert err == "", err


_FSIZE_CHILD = r"""
import resource, signal, sys, numpy as np
from seahough.io.images import write_image
from seahough import WriteError
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))
try:
    write_image(sys.argv[1], np.random.default_rng(0).integers(0, 256, (200, 200), np.uint8))
except WriteError as e:
    print(e)
"""


def test_a_write_cut_short_leaves_no_partial_file(tmp_path):
    p = tmp_path / "big.png"
    r = subprocess.run([sys.executable, "-c", _FSIZE_CHILD, str(p)], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert r.stdout.startswith(f"{p}: cannot write the image ("), r.stdout
    assert not p.exists()


def test_write_image_errors_name_the_file(tmp_path, capfd):
    from seahough.io.images import write_image
    with pytest.raises(WriteError, match="no.such.folder"):
        write_image(tmp_path / "no.such.folder" / "a.png", _scene())
    with pytest.raises(WriteError, match=r"a\.xyz: cannot write the image"):
        write_image(tmp_path / "a.xyz", _scene())
    write_image(tmp_path / "noext", _scene())                  # no extension: PNG
    assert (tmp_path / "noext").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    write_image(tmp_path / "ok.png", _scene())
    assert np.array_equal(read_image(tmp_path / "ok.png"), _scene())
    assert capfd.readouterr().err == ""
