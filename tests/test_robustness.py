"""Robustness: a corpus of bad inputs through the API and the command line,
determinism, and dead reckoning over a folder with broken frames.

Every bad input must give a specific :class:`seahough.SeahoughError` subclass
(or the documented empty result) through the API, and through the installed
``seahough detect`` command exactly one ``seahough: error: ...`` line on
stderr naming the file (or parameter) and the problem, with exit status 2,
never a traceback. See docs/errors.md for the table this file checks.

A test that reproduces a bug is marked ``xfail(strict=True, reason="BUG: ...")``
until the bug is fixed (none are, today).

The command-line cases run in subprocesses, several at a time (they are
mostly interpreter start-up), under an address-space limit so that a
"decompression bomb" that does get decoded fails fast instead of swapping.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import re
import resource
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import cv2
import numpy as np
import pytest
from PIL import Image

from seahough import (Config, Detector, ImageReadError, ImageSizeError,
                      ImageValueError, ParameterError, Pattern, PatternError, SeahoughError,
                      estimate_motion, read_image, to_gray)
from seahough import sim as sim

from conftest import seahough_command

#: address-space limit of the command-line subprocesses (a seahough process
#: peaks at under 1 GiB of virtual memory; a decoded bomb needs far more)
AS_LIMIT = 4 << 30
#: a command that has not finished by then is taken as hung
HANG_S = 20.0
#: detections that, today, run for minutes (each takes well under a second once fixed)
_SLOW = {
    "angle 1e12": "Detector(Pattern.rectangle(40, 30), angle_range=(1e12, 1e12)).detect(img)",
    "local_window 1e6": "Detector(Pattern.rectangle(40, 30), "
                        "config=Config(local_window=10**6)).detect(img)",
    "scale 100-1000": "Detector(Pattern.rectangle(40, 30), scale_range=(100, 1000)).detect(img)",
}


# ------------------------------------------------------------------ helpers
def _env(**extra) -> dict:
    env = dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    env.update({k: str(v) for k, v in extra.items()})
    return env


def _limit_memory():  # pragma: no cover - runs in the child
    try:
        resource.setrlimit(resource.RLIMIT_AS, (AS_LIMIT, AS_LIMIT))
    except (ValueError, OSError):
        pass


class Run:
    """The outcome of one subprocess: ``rc`` is None when it timed out."""

    def __init__(self, argv, rc, out, err, seconds):
        self.argv, self.rc, self.stdout, self.stderr, self.seconds = argv, rc, out, err, seconds

    def __repr__(self):
        return (f"Run(rc={self.rc}, {self.seconds:.1f} s, argv={self.argv[1:]!r},\n"
                f"stdout={self.stdout[-800:]!r},\nstderr={self.stderr[-1500:]!r})")


def _run(argv, timeout=HANG_S, env=None, cwd=None) -> Run:
    t0 = time.perf_counter()
    try:
        p = subprocess.run(argv, capture_output=True, text=True, timeout=timeout,
                           env=env or _env(), cwd=cwd, preexec_fn=_limit_memory)
        return Run(argv, p.returncode, p.stdout, p.stderr, time.perf_counter() - t0)
    except subprocess.TimeoutExpired as e:
        out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        err = e.stderr.decode() if isinstance(e.stderr, bytes) else (e.stderr or "")
        return Run(argv, None, out, err, time.perf_counter() - t0)


def _cli(*args) -> list:
    return [str(seahough_command()), *map(str, args)]


def _py(code: str) -> list:
    return [sys.executable, "-c", code]


def assert_one_error_line(r: Run, *needles: str) -> str:
    """Exit 2, exactly one ``seahough: error:`` line on stderr holding the
    needles, no traceback, nothing on stdout."""
    assert r.rc is not None, f"hung (> {HANG_S:.0f} s): {r!r}"
    assert "Traceback" not in r.stderr, r
    assert r.rc == 2, r
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r
    assert lines[0].startswith("seahough: error: "), r
    for n in needles:
        assert n in lines[0], r
    assert r.stdout == "", r
    return lines[0]


# -------------------------------------------------------------------- corpus
def _scene() -> np.ndarray:
    """A bright 61x41 rectangle on a dark 160x120 background."""
    img = np.full((120, 160), 40, np.uint8)
    cv2.rectangle(img, (50, 40), (110, 80), 220, -1)
    return img


def _png_with_size(w: int, h: int) -> bytes:
    """A valid small PNG whose IHDR claims ``w`` x ``h`` (CRC fixed up)."""
    ok, buf = cv2.imencode(".png", _scene())
    data = bytearray(buf.tobytes())
    new = b"IHDR" + struct.pack(">II", w, h) + bytes(data[24:29])
    data[12:29] = new
    data[29:33] = struct.pack(">I", zlib.crc32(new) & 0xFFFFFFFF)
    return bytes(data)


def _jpeg_with_size(w: int, h: int) -> bytes:
    """A valid small JPEG whose SOF marker claims ``w`` x ``h``."""
    ok, buf = cv2.imencode(".jpg", _scene())
    data = bytearray(buf.tobytes())
    i = 2
    while not (data[i] == 0xFF and data[i + 1] in (0xC0, 0xC1, 0xC2)):
        i += 2 + struct.unpack(">H", data[i + 2:i + 4])[0]
    data[i + 5:i + 9] = struct.pack(">HH", h, w)
    return bytes(data)


def _noise(shape, seed=0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, shape).astype(np.uint8)


def _png_header_only(w: int, h: int, bit_depth: int, colour_type: int) -> bytes:
    """A PNG whose IHDR claims ``w`` x ``h`` of the given format, with a tiny IDAT."""
    chunks = b""
    for body in (b"IHDR" + struct.pack(">IIBBBBB", w, h, bit_depth, colour_type, 0, 0, 0),
                 b"IDAT" + zlib.compress(bytes(64)), b"IEND"):
        chunks += struct.pack(">I", len(body) - 4) + body
        chunks += struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
    return b"\x89PNG\r\n\x1a\n" + chunks


#: what a phone appends to a "motion photo" JPEG: an MP4 after the image's end marker
_MP4_TRAILER = struct.pack(">I", 24) + b"ftypmp42" + bytes(12) + bytes(range(256)) * 8


def _write_corpus(d: Path) -> None:
    scene = _scene()
    cv2.imwrite(str(d / "scene.png"), scene)
    cv2.imwrite(str(d / "pattern.png"), scene[30:90, 40:120])
    # unreadable files
    (d / "empty.png").write_bytes(b"")
    ok, jpg = cv2.imencode(".jpg", scene)
    (d / "truncated.jpg").write_bytes(jpg.tobytes()[: len(jpg) // 2])
    ok, png = cv2.imencode(".png", _noise((120, 160)))
    (d / "truncated.png").write_bytes(png.tobytes()[: len(png) // 2])
    (d / "text.png").write_text("this is a text file, not a PNG\n")
    (d / "folder.png").mkdir()
    (d / "zero.png").write_bytes(_png_with_size(0, 0))
    bad = bytearray(png.tobytes())                      # IDAT damaged, IEND intact
    bad[len(bad) // 2: len(bad) // 2 + 64] = bytes(64)
    (d / "corrupt.png").write_bytes(bytes(bad))
    ok, jn = cv2.imencode(".jpg", _noise((120, 160), 1))
    bad = bytearray(jn.tobytes())                       # entropy data zeroed, EOI intact
    bad[len(bad) // 2: len(bad) // 2 + 256] = bytes(256)
    (d / "corrupt.jpg").write_bytes(bytes(bad))
    # wrong sizes
    cv2.imwrite(str(d / "one.png"), np.zeros((1, 1), np.uint8))
    cv2.imwrite(str(d / "strip_wide.png"), np.zeros((1, 100000), np.uint8))
    cv2.imwrite(str(d / "strip_tall.png"), np.zeros((100000, 1), np.uint8))
    (d / "bomb.png").write_bytes(_png_with_size(100000, 100000))
    (d / "bomb.jpg").write_bytes(_jpeg_with_size(65000, 65000))
    # 198.8 Mpx of 16-bit colour: under the pixel limit, over the memory budget
    (d / "deep.png").write_bytes(_png_header_only(14000, 14200, 16, 2))
    # several frames or pages
    frames = [Image.fromarray(np.roll(scene, 4 * k, axis=1)) for k in range(12)]
    frames[0].save(d / "animated.gif", save_all=True, append_images=frames[1:], duration=80)
    frames[0].save(d / "pages.tiff", save_all=True, append_images=frames[1:3])
    # bad values
    f = scene.astype(np.float32)
    f[5, 5] = np.nan
    cv2.imwrite(str(d / "nan.tiff"), f)
    f[5, 5] = np.inf
    cv2.imwrite(str(d / "inf.tiff"), f)
    # images that must work
    cv2.imwrite(str(d / "u16.png"), scene.astype(np.uint16) * 257)
    cv2.imwrite(str(d / "u16_bgr.png"), cv2.cvtColor(scene, cv2.COLOR_GRAY2BGR).astype(np.uint16) * 257)
    cv2.imwrite(str(d / "f32.tiff"), scene.astype(np.float32) / 255.0)
    cv2.imwrite(str(d / "bgra.png"), cv2.cvtColor(scene, cv2.COLOR_GRAY2BGRA))
    (d / "trailer.png").write_bytes((d / "scene.png").read_bytes() + b"camera trailer" * 40)
    # stored turned a quarter to the left, shown upright (EXIF orientation 6): the scene
    Image.fromarray(np.rot90(scene)).save(d / "rotated.tiff", tiffinfo={274: 6})
    ok, jpg = cv2.imencode(".jpg", scene, [cv2.IMWRITE_JPEG_QUALITY, 95])
    (d / "scene.jpg").write_bytes(jpg.tobytes())
    (d / "motion.jpg").write_bytes(jpg.tobytes() + _MP4_TRAILER)
    # no edges
    cv2.imwrite(str(d / "black.png"), np.zeros((120, 160), np.uint8))
    cv2.imwrite(str(d / "grey16.png"), np.full((120, 160), 30000, np.uint16))
    ramp = np.tile(np.linspace(60, 120, 160, dtype=np.float32), (120, 1))
    cv2.imwrite(str(d / "ramp.png"), np.round(ramp).astype(np.uint8))
    cv2.imwrite(str(d / "flat_pattern.png"), np.full((40, 40), 90, np.uint8))
    # a pattern image larger than the scene
    big = np.full((300, 400), 40, np.uint8)
    cv2.rectangle(big, (60, 50), (340, 250), 220, -1)
    cv2.imwrite(str(d / "big_pattern.png"), big)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("corpus")
    _write_corpus(d)
    return d


# (case, file, API exception, words in the API message and in the CLI line)
BAD_FILES = [
    ("empty file", "empty.png", ImageReadError, "empty file"),
    ("truncated JPEG", "truncated.jpg", ImageReadError, "truncated JPEG"),
    ("truncated PNG", "truncated.png", ImageReadError, "truncated PNG"),
    ("text file named .png", "text.png", ImageReadError, "not an image"),
    ("folder named .png", "folder.png", ImageReadError, "is a folder"),
    ("PNG header 0x0", "zero.png", ImageReadError, "not a valid PNG"),
    ("PNG with damaged IDAT", "corrupt.png", ImageReadError, "corrupt PNG data"),
    ("JPEG with damaged data", "corrupt.jpg", ImageReadError, "corrupt"),
    ("1x1 image", "one.png", ImageSizeError, "too small"),
    ("100000x1 strip", "strip_wide.png", ImageSizeError, "too small"),
    ("1x100000 strip", "strip_tall.png", ImageSizeError, "too small"),
    ("PNG header bomb", "bomb.png", ImageSizeError, "over the limit"),
    ("JPEG header bomb", "bomb.jpg", ImageSizeError, "over the limit"),
    ("over the memory budget", "deep.png", ImageSizeError, "over the memory limit"),
    ("animated GIF", "animated.gif", ImageReadError, "animated image with 12 frames"),
    ("multi-page TIFF", "pages.tiff", ImageReadError, "multi-page image with 3 pages"),
    ("float TIFF with NaN", "nan.tiff", ImageValueError, "NaN"),
    ("float TIFF with inf", "inf.tiff", ImageValueError, "infinite"),
]

WORKS = ("scene.png", "u16.png", "u16_bgr.png", "f32.tiff", "bgra.png", "trailer.png",
         "rotated.tiff")
NO_EDGES = ("black.png", "grey16.png", "ramp.png")

_API_BUGS: dict = {}
_CLI_BUGS: dict = {}


def _params(cases, bugs):
    return [pytest.param(*c, id=c[0], marks=[bugs[c[0]]] if c[0] in bugs else [])
            for c in cases]


# (case, detect arguments after the command, words in the error line)
BAD_ARGS = [
    ("scale_range reversed", ["pattern.png", "scene.png", "--scale-range", 2, 1],
     ["--scale-range", "LOW must not exceed HIGH"]),
    ("scale_range negative", ["pattern.png", "scene.png", "--scale-range", -1, 2],
     ["--scale-range", "> 0"]),
    ("scale_range zero", ["pattern.png", "scene.png", "--scale-range", 0, 0], ["--scale-range"]),
    ("scale_range NaN", ["pattern.png", "scene.png", "--scale-range", "nan", 2],
     ["--scale-range", "finite"]),
    ("scale_range inf", ["pattern.png", "scene.png", "--scale-range", 1, "inf"],
     ["--scale-range", "finite"]),
    ("scale_range over 64x", ["pattern.png", "scene.png", "--scale-range", 0.01, 10],
     ["scale_range", "64"]),
    ("scale_range not a number", ["pattern.png", "scene.png", "--scale-range", "a", 2],
     ["--scale-range"]),
    ("angle_range reversed", ["pattern.png", "scene.png", "--angle-range", 10, 5],
     ["--angle-range", "LOW must not exceed HIGH"]),
    ("angle_range across 0", ["pattern.png", "scene.png", "--angle-range", 350, 10],
     ["--angle-range", "LOW must not exceed HIGH", "'350 370' or '-10 10'"]),
    ("angle_range NaN", ["pattern.png", "scene.png", "--angle-range", 0, "nan"],
     ["--angle-range", "finite"]),
    ("max_results 0", ["pattern.png", "scene.png", "--max-results", 0], ["--max-results"]),
    ("min_score 2", ["pattern.png", "scene.png", "--min-score", 2], ["--min-score"]),
    ("min_confidence -0.5", ["pattern.png", "scene.png", "--min-confidence", -0.5],
     ["--min-confidence"]),
    ("downscale 0", ["pattern.png", "scene.png", "--downscale", 0], ["--downscale"]),
    ("downscale 1.5", ["pattern.png", "scene.png", "--downscale", 1.5], ["--downscale"]),
    ("keypoints 0", ["pattern.png", "scene.png", "--keypoints", 0], ["--keypoints"]),
    ("rect:-3,4", ["rect:-3,4", "scene.png"], ["rect:-3,4", "width=-3.0", "at least 1 px"]),
    ("circle:abc", ["circle:abc", "scene.png"], ["circle:abc", "expected numbers"]),
    ("rect:nan,4", ["rect:nan,4", "scene.png"], ["rect:nan,4", "finite"]),
    ("rect:60", ["rect:60", "scene.png"], ["rect:60", "expected rect:W,H"]),
    ("rect:1,2,3", ["rect:1,2,3", "scene.png"], ["rect:1,2,3", "expected rect:W,H"]),
    ("circle:0", ["circle:0", "scene.png"], ["circle:0", "radius"]),
    ("ring:10,20", ["ring:10,20", "scene.png"], ["ring:10,20", "inner_radius"]),
    ("line:10,8", ["line:10,8", "scene.png"], ["line:10,8", "twice its width"]),
    ("ellipse:30", ["ellipse:30", "scene.png"], ["ellipse:30", "expected ellipse:RX,RY"]),
    ("ellipse:30,-2", ["ellipse:30,-2", "scene.png"], ["ellipse:30,-2", "ry"]),
    ("polygon:0,0,1,1", ["polygon:0,0,1,1", "scene.png"], ["polygon:0,0,1,1"]),
    ("collinear polygon", ["polygon:0,0,10,10,20,20", "scene.png"], ["no area"]),
    ("tiny rect (no edges)", ["rect:2,2", "scene.png"], ["rect:2,2", "too few edges"]),
    ("pattern without edges", ["flat_pattern.png", "scene.png"],
     ["flat_pattern.png", "too few edges"]),
    ("empty pattern file", ["empty.png", "scene.png"], ["pattern", "empty.png", "empty file"]),
    ("pattern is a text file", ["text.png", "scene.png"], ["pattern", "text.png"]),
    ("pattern header bomb", ["bomb.png", "scene.png"], ["pattern", "bomb.png", "over the limit"]),
    ("mask on a shape", ["rect:60,40", "scene.png", "--mask", "scene.png"], ["--mask"]),
    ("mask of another size", ["pattern.png", "scene.png", "--mask", "scene.png"],
     ["pattern.png", "mask"]),
    # found while writing these tests (each was a crash or a traceback)
    ("huge rect", ["rect:1000000,1000000", "scene.png"], ["rect:1000000,1000000"]),
    ("huge circle", ["circle:100000", "scene.png"], ["circle:100000"]),
    ("scale_range 1e6", ["pattern.png", "scene.png", "--scale-range", 1e6, 1e6],
     ["scale_range"]),
    ("scale_range 1e-300", ["pattern.png", "scene.png", "--scale-range", 1e-300, 1e-300],
     ["scale_range"]),
]

_ARG_BUGS: dict = {}

# The command-line cases. Most run through one driver process that calls
# seahough.cli.main -- what the `seahough` command runs -- once per case, with
# file descriptors 1 and 2 redirected, so that output written by C libraries
# (libpng, libjpeg) is caught too; this saves an interpreter start-up per case.
# Cases that must be seen from outside (a whole command line, a hang, a crash)
# run as `seahough ...` (the installed command) in their own process.
_DRIVER = r"""
import json, os, sys, tempfile, traceback
from seahough.cli import main
cases = json.load(open(sys.argv[1]))
results = {}
for key, argv in cases.items():
    outs = [tempfile.TemporaryFile(), tempfile.TemporaryFile()]
    sys.stdout.flush(); sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    os.dup2(outs[0].fileno(), 1); os.dup2(outs[1].fileno(), 2)
    try:
        try:
            main(argv)
            rc = 0
        except SystemExit as e:
            rc = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except BaseException:
            traceback.print_exc()
            rc = 1
        sys.stdout.flush(); sys.stderr.flush()
    finally:
        os.dup2(saved[0], 1); os.dup2(saved[1], 2)
        os.close(saved[0]); os.close(saved[1])
    text = []
    for f in outs:
        f.seek(0)
        text.append(f.read().decode("utf-8", "replace"))
        f.close()
    results[key] = [rc, text[0], text[1]]
with open(sys.argv[2], "w") as f:
    json.dump(results, f)
"""


def _cli_cases(d: Path):
    """``(driver, separate)``: detect argument lists run by the driver, and
    whole command lines (with their time limits) run on their own."""
    def arg(a):
        return str(d / a) if isinstance(a, str) and (d / a).exists() else str(a)

    drv = {}
    for name, fname, *_ in BAD_FILES:
        drv[f"file {name}"] = ["detect", arg("pattern.png"), arg(fname)]
    for name, args, _ in BAD_ARGS:
        drv[f"args {name}"] = ["detect", *map(arg, args)]
    sep = {}
    # parameters that make the search run for minutes (see the test): first, in the background
    sep["hang"] = (_py(_CHILD) + [json.dumps(_SLOW)], 15.0)
    # a pattern origin beyond float32 crashes the process
    sep["crash origin 1e39"] = (_py(
        "import numpy as np, seahough\n"
        "img = np.full((120, 160), 40, np.uint8); img[40:81, 50:111] = 220\n"
        "try:\n"
        "    p = seahough.Pattern.from_image(img, origin=(1e39, 0.0))\n"
        "    print('ok', seahough.Detector(p).detect(img))\n"
        "except seahough.SeahoughError as e:\n"
        "    print('refused', type(e).__name__, e)\n"), HANG_S)
    # every bad file of the corpus in one command: one line each, the good image still reported
    batch = [d / f for _, f, *_ in BAD_FILES]
    sep["batch"] = (_cli("detect", d / "pattern.png", d / "scene.png", *batch, "--json"), HANG_S)
    sep["works"] = (_cli("detect", d / "pattern.png", *[d / f for f in WORKS], "--json"), HANG_S)
    sep["trailer"] = (_cli("detect", d / "pattern.png", d / "scene.jpg", d / "motion.jpg",
                           "--json"), HANG_S)
    sep["no edges"] = (_cli("detect", d / "pattern.png", *[d / f for f in NO_EDGES], "--json"),
                       HANG_S)
    sep["larger"] = (_cli("detect", "rect:300,200", d / "scene.png", "--json",
                          "--scale-range", 0.9, 1.1), HANG_S)
    sep["larger image"] = (_cli("detect", d / "big_pattern.png", d / "scene.png", "--json",
                                "--scale-range", 0.9, 1.1), HANG_S)
    return drv, sep


class _CliRuns:
    def __init__(self, d: Path, tmp: Path):
        drv, sep = _cli_cases(d)
        self._pool = cf.ThreadPoolExecutor(max_workers=3)
        self._sep = {k: self._pool.submit(_run, argv, t) for k, (argv, t) in sep.items()}
        (tmp / "cases.json").write_text(json.dumps(drv))
        self._drv_cases = drv
        self._drv_argv = _py(_DRIVER) + [str(tmp / "cases.json"), str(tmp / "results.json")]
        self._drv = self._pool.submit(_run, self._drv_argv, 240.0)
        self._results = tmp / "results.json"
        self._parsed = None

    def __getitem__(self, key: str) -> Run:
        if key in self._sep:
            return self._sep[key].result()
        if self._parsed is None:
            r = self._drv.result()
            assert r.rc == 0 and self._results.is_file(), r
            self._parsed = json.loads(self._results.read_text())
        rc, out, err = self._parsed[key]
        return Run(["seahough", *self._drv_cases[key]], rc, out, err, 0.0)

    def close(self):
        self._pool.shutdown(wait=True, cancel_futures=True)


@pytest.fixture(scope="module")
def cli_runs(corpus, tmp_path_factory):
    """Start every command-line case now; each test waits for its own."""
    runs = _CliRuns(corpus, tmp_path_factory.mktemp("cli"))
    yield runs
    runs.close()


# ------------------------------------------------------- bad files: the API
@pytest.mark.parametrize("case, fname, exc, words", _params(BAD_FILES, _API_BUGS))
def test_bad_file_raises_a_specific_error_through_the_api(corpus, case, fname, exc, words):
    path = corpus / fname
    det = Detector(Pattern.rectangle(60, 40))
    with pytest.raises(exc) as info:
        det.detect(path)
    msg = str(info.value)
    assert words in msg and fname in msg, msg
    assert "\n" not in msg
    # the same through every entry point that takes a file
    with pytest.raises(exc):
        to_gray(path)
    with pytest.raises(exc):
        estimate_motion(corpus / "scene.png", path)
    with pytest.raises(exc):
        Pattern.from_image(path)


# ------------------------------------------------------- bad files: the CLI
@pytest.mark.parametrize("case, fname, exc, words", _params(BAD_FILES, _CLI_BUGS))
def test_bad_file_gives_one_error_line_and_exit_2(cli_runs, corpus, case, fname, exc, words):
    r = cli_runs[f"file {case}"]
    line = assert_one_error_line(r, str(corpus / fname), words)
    assert line.startswith(f"seahough: error: {corpus / fname}: "), line
    # (not "strip.png: image: 968x5 is too small": the array's own label after the name)
    assert f"{corpus / fname}: image: " not in line, line


def _assert_clean(line: str):
    for noise in ("[", "WARN", "DEBUG", ".cpp", "global ", "libpng", "OpenCV(", "\n"):
        assert noise not in line, (noise, line)


@pytest.mark.parametrize("fname, start", [
    ("zero.png", "not a valid PNG (its header claims 0x0 pixels)"),
    ("corrupt.png", "corrupt PNG data (broken PNG file (bad header checksum in b'IDAT'))"),
    ("truncated.png", "truncated PNG (the image data ends early)"),
    ("truncated.jpg", "truncated JPEG (the image data ends early)"),
    ("corrupt.jpg", "corrupt JPEG data (Corrupt JPEG data: 1223 extraneous bytes before marker "
                    "0xd9)"),
    ("text.png", "not an image OpenCV can decode"),
])
def test_decoder_failures_are_one_clean_phrase_and_nothing_on_stderr(corpus, capfd, fname,
                                                                    start):
    """Why a decoder failed is said in the message, not printed by the
    decoder: nothing reaches stderr (the decoders report to seahough)."""
    with pytest.raises(ImageReadError) as info:
        read_image(corpus / fname)
    msg = str(info.value)
    assert msg == f"{corpus / fname}: {start}", msg
    _assert_clean(msg)
    assert capfd.readouterr().err == ""


def test_zero_size_png_gives_a_clean_line(cli_runs, corpus):
    line = assert_one_error_line(cli_runs["file PNG header 0x0"], str(corpus / "zero.png"))
    assert line.startswith(f"seahough: error: {corpus / 'zero.png'}: not a valid PNG"), line
    _assert_clean(line)


def test_bad_files_among_a_good_one_each_get_their_own_line(cli_runs, corpus):
    r = cli_runs["batch"]
    assert r.rc == 2 and "Traceback" not in r.stderr, r
    bad = [(f, w) for _, f, _, w in BAD_FILES]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == len(bad), r
    for line, (f, words) in zip(lines, bad):
        assert line.startswith(f"seahough: error: {corpus / f}: ") and words in line, line
    recs = [json.loads(x) for x in r.stdout.splitlines()]
    good = [x for x in recs if "error" not in x]
    assert [Path(x["file"]).name for x in good] == ["scene.png"] and good[0]["found"]
    # each bad file has its record too, its reason as on stderr
    errs = [(Path(x["file"]).name, x["error"]) for x in recs if "error" in x]
    assert [f for f, _ in errs] == [f for f, _ in bad]
    for (f, why), line in zip(errs, lines):
        assert line == f"seahough: error: {corpus / f}: {why}"


# --------------------------------------------------- the pixel limit (bombs)
def test_pixel_limit_is_documented_and_shared():
    assert Config().max_pixels == 200_000_000
    for f in (read_image, to_gray):
        assert __import__("inspect").signature(f).parameters["max_pixels"].default == 200_000_000


@pytest.mark.parametrize("fname", ["bomb.png", "bomb.jpg"])
def test_header_bomb_is_refused_before_decoding(corpus, fname, monkeypatch):
    import seahough.io.images as io

    def no_decode(*a, **k):
        raise AssertionError("the bomb was handed to the decoder")

    monkeypatch.setattr(io.cv2, "imdecode", no_decode)
    t0 = time.perf_counter()
    with pytest.raises(ImageSizeError, match="refusing to decode"):
        to_gray(corpus / fname)
    with pytest.raises(ImageSizeError, match="Config.max_pixels"):
        Detector(Pattern.rectangle(60, 40)).detect(corpus / fname)
    assert time.perf_counter() - t0 < 2.0


def test_header_limit_boundary_and_config_limit(corpus):
    p = corpus / "scene.png"                              # 160 x 120 = 19200 px
    assert read_image(p, max_pixels=19200).shape == (120, 160)
    with pytest.raises(ImageSizeError, match="19200"):
        read_image(p, max_pixels=19199)
    det = Detector(Pattern.rectangle(60, 40), config=Config(max_pixels=19199))
    for img in (p, _scene()):
        with pytest.raises(ImageSizeError, match="over the limit of 19199"):
            det.detect(img)
    with pytest.raises(ImageSizeError, match="over the limit"):
        estimate_motion(p, p, config=Config(max_pixels=10000))


def test_huge_array_is_refused_without_copying_it():
    # a 40000 x 40000 view of one byte: refused on its shape, before any conversion
    view = np.broadcast_to(np.uint8(7), (40000, 40000))
    t0 = time.perf_counter()
    with pytest.raises(ImageSizeError, match="over the limit of 200000000"):
        to_gray(view)
    with pytest.raises(ImageSizeError):
        Detector(Pattern.rectangle(60, 40)).detect(view)
    assert time.perf_counter() - t0 < 1.0


# ------------------------------------------------ images that must work
def test_16bit_float_and_bgra_files_work_like_8bit(cli_runs, corpus):
    det = Detector(Pattern.from_image(corpus / "pattern.png"))
    ref = det.detect(corpus / "scene.png")
    assert ref
    for fname in WORKS[1:]:
        got = det.detect(corpus / fname)
        assert len(ref) == len(got), fname
        for a, b in zip(ref, got):
            assert (a.x, a.y, a.scale) == pytest.approx((b.x, b.y, b.scale), abs=1e-3), fname
    r = cli_runs["works"]
    assert r.rc == 0 and r.stderr == "", r
    recs = [json.loads(line) for line in r.stdout.splitlines()]
    assert [Path(x["file"]).name for x in recs] == list(WORKS)
    for rec in recs:
        assert rec["found"] and (rec["width"], rec["height"]) == (160, 120)
        assert rec["detections"][0]["x"] == pytest.approx(ref[0].x, abs=1e-3)


def test_jpeg_with_a_motion_photo_trailer_works_like_without(cli_runs, corpus):
    """Bytes after the JPEG's end marker (a phone's motion video) are not
    the image: the file is read as the JPEG alone, through API and command."""
    assert np.array_equal(read_image(corpus / "motion.jpg"), read_image(corpus / "scene.jpg"))
    r = cli_runs["trailer"]
    assert r.rc == 0 and r.stderr == "", r
    plain, motion = [json.loads(line) for line in r.stdout.splitlines()]
    assert plain["found"] and plain["detections"] == motion["detections"]


@pytest.mark.parametrize("conv", [
    lambda g: g.astype(np.uint16) * 257,
    lambda g: g.astype(np.float32),
    lambda g: g.astype(np.float64) / 255.0,
    lambda g: g.astype(np.int32),
    lambda g: cv2.cvtColor(g, cv2.COLOR_GRAY2BGR).astype(np.float32) / 255.0,
    lambda g: cv2.cvtColor(g, cv2.COLOR_GRAY2BGRA).astype(np.uint16) * 257,
    lambda g: g > 100,
], ids=["uint16", "float32", "float64 0-1", "int32", "BGR float 0-1", "BGRA uint16", "bool"])
def test_deep_and_float_arrays_work_in_detection_and_motion(conv):
    g = _scene()
    det = Detector(Pattern.rectangle(61, 41), scale_range=(0.8, 1.25))
    ref = det.detect(g)
    got = det.detect(conv(g))
    assert ref and got
    assert (got[0].x, got[0].y) == pytest.approx((ref[0].x, ref[0].y), abs=0.5)
    pat = Pattern.from_image(conv(g)[20:100, 30:130])
    assert Detector(pat).detect(conv(g))
    m = estimate_motion(conv(g), conv(g), scale_range=(1, 1), angle_range=(0, 0))
    assert m is not None and abs(m.dx) < 0.5 and abs(m.dy) < 0.5


# --------------------------------------------- no edges: a clear empty result
def test_image_without_edges_is_an_empty_result_and_exit_1(cli_runs, corpus):
    det = Detector(Pattern.from_image(corpus / "pattern.png"))
    for fname in NO_EDGES:
        res = det.search(corpus / fname)
        assert res.detections == [] and res.note == "no edges", fname
        assert res.planes is None and res.candidates == []
    r = cli_runs["no edges"]
    assert r.rc == 1 and r.stderr == "", r
    recs = [json.loads(line) for line in r.stdout.splitlines()]
    assert [Path(x["file"]).name for x in recs] == list(NO_EDGES)
    assert all(x["found"] is False and x["detections"] == [] for x in recs)


@pytest.mark.parametrize("img", [
    np.full((120, 160, 3), 128, np.uint8), np.full((120, 160), 0.5, np.float32),
    np.full((120, 160, 4), 65535, np.uint16), np.zeros((120, 160), bool),
    np.full((8, 8), 200, np.uint8), np.zeros((8, 5000), np.uint8),
], ids=["BGR grey", "float 0.5", "BGRA uint16 white", "bool false", "8x8", "8x5000"])
def test_uniform_arrays_of_any_kind_say_no_edges(img):
    for pat in (Pattern.rectangle(40, 30), Pattern.line(100, 6), Pattern.circle(10)):
        res = Detector(pat).search(img)
        assert res.detections == [] and res.note == "no edges"
    if img.shape[:2] == (120, 160):
        assert estimate_motion(_scene(), img) is None


def test_motion_from_a_frame_without_edges_is_unknown_not_an_error():
    # the previous frame becomes the pattern, and has no edges: no motion (None),
    # as for a current frame without edges (a loop over a dive goes on)
    assert estimate_motion(np.zeros((120, 160), np.uint8), _scene()) is None


def test_pattern_without_edges_is_refused(corpus):
    for src in (corpus / "flat_pattern.png", np.full((40, 40, 3), 90, np.uint8),
                np.zeros((40, 40), np.float64), np.full((16, 16), 65535, np.uint16)):
        with pytest.raises(PatternError, match="too few edges"):
            Pattern.from_image(src)
    with pytest.raises(PatternError, match="too few edges"):
        Pattern.rectangle(2, 2)
    with pytest.raises(PatternError, match="mask is empty"):
        Pattern.from_image(_scene(), mask=np.zeros((120, 160), np.uint8))


def test_pattern_larger_than_the_image_is_not_found_not_an_error(cli_runs, corpus):
    # documented: no error; nothing is found ([], exit 1), and a pattern that
    # cannot fit at any searched scale says so without voting
    for pat, sr, note in ((Pattern.rectangle(300, 200), (0.9, 1.1), ""),
                          (Pattern.from_image(corpus / "big_pattern.png"), (0.9, 1.1),
                           "pattern larger than the image")):
        res = Detector(pat, scale_range=sr).search(corpus / "scene.png")
        assert res.detections == [] and res.note == note
    for key in ("larger", "larger image"):
        r = cli_runs[key]
        assert r.rc == 1 and r.stderr == "", r
        assert json.loads(r.stdout)["found"] is False


# ---------------------------------------------------- parameters: the CLI
@pytest.mark.parametrize("case, args, words", _params(BAD_ARGS, _ARG_BUGS))
def test_bad_parameter_gives_one_error_line_and_exit_2(cli_runs, case, args, words):
    assert_one_error_line(cli_runs[f"args {case}"], *words)


def test_far_pattern_origin_does_not_crash(cli_runs):
    r = cli_runs["crash origin 1e39"]
    assert r.rc == 0 and r.stdout.split()[0] in ("ok", "refused"), r


# ---------------------------------------------------- parameters: the API
def test_a_rotation_range_across_north_says_how_to_give_it():
    """(350, 10), "about north": refused, with the two ways to say it."""
    with pytest.raises(ParameterError, match=re.escape("(350, 370) or (-10, 10)")):
        Detector(Pattern.rectangle(40, 30), angle_range=(350, 10))
    for kw in (dict(scale_range=(2, 1)), dict(angle_range=(10, 5))):   # (a plain swap: none)
        with pytest.raises(ParameterError) as info:
            Detector(Pattern.rectangle(40, 30), **kw)
        assert "turns" not in str(info.value)


@pytest.mark.parametrize("kw", [
    dict(scale_range=(-1, 2)), dict(scale_range=(1, float("inf"))), dict(scale_range=(0.01, 10)),
    dict(scale_range=None), dict(scale_range="ab"), dict(scale_range=(1,)),
    dict(scale_range=("a", 2)), dict(angle_range=(float("nan"), 0)),
    dict(angle_range=(0, float("inf"))), dict(angle_range=None), dict(angle_range=(0,)),
    dict(max_results=-1), dict(max_results=1.5), dict(max_results=True), dict(max_results="3"),
    dict(min_score=-0.1), dict(min_score=float("nan")), dict(min_score="0.5"), dict(min_score=2),
    dict(min_confidence=2), dict(min_confidence=float("nan")),
    dict(search_region=(0, 0, 10)), dict(search_region=(0, 0, float("nan"), 10)),
    dict(search_region="abcd"), dict(config="fast"),
], ids=repr)
def test_bad_detector_parameters_raise_parameter_error(kw):
    with pytest.raises(ParameterError) as info:
        Detector(Pattern.rectangle(40, 30), **kw)
    name = next(iter(kw))
    assert name in str(info.value) or name == "config"


@pytest.mark.parametrize("kw", [
    dict(downscale=-0.5), dict(downscale=float("nan")), dict(target_size=16),
    dict(target_size=320.0), dict(n_keypoints=-5), dict(n_pattern_points=4),
    dict(n_verify_points=0), dict(min_pattern_size=0), dict(min_pattern_size=float("nan")),
    dict(min_gradient=-1), dict(min_gradient=float("nan")), dict(local_window=2),
    dict(local_window=True), dict(segment_steps=0), dict(segment_steps=21),
    dict(segment_angle_tol=0), dict(segment_angle_tol=91), dict(max_segments=0),
    dict(voting="hough"), dict(translation_bin=0), dict(angle_bin=-1), dict(scale_step=0),
    dict(angle_tolerance=float("nan")), dict(match_radius=0), dict(n_candidates=0),
    dict(max_pixels=0), dict(max_pixels=1e9),
], ids=repr)
def test_bad_config_fields_raise_parameter_error_naming_the_field(kw):
    name = next(iter(kw))
    with pytest.raises(ParameterError, match=f"Config.{name}="):
        Config(**kw)
    with pytest.raises(ParameterError, match=name):
        Config().replace(**kw)


def test_unknown_config_field_is_a_parameter_error():
    with pytest.raises(ParameterError, match="no parameter 'n_points'"):
        Config().replace(n_points=3)
    with pytest.raises(TypeError):      # the constructor: a TypeError, as Python's own ...
        Config(n_points=3)
    with pytest.raises(ParameterError, match="Config has no parameter 'n_points'"):
        Config(n_points=3)                  # ... and a ParameterError naming it


@pytest.mark.parametrize("kw", [
    dict(downscale="0.5"), dict(min_pattern_size="a"), dict(min_gradient="a"),
    dict(segment_steps="a"), dict(segment_angle_tol="a"), dict(translation_bin="a"),
    dict(match_radius="a"),
], ids=repr)
def test_non_numeric_config_fields_raise_parameter_error(kw):
    with pytest.raises(ParameterError):
        Config(**kw)


@pytest.mark.parametrize("kw", [
    dict(max_shift=0), dict(max_shift=2), dict(max_shift=float("nan")),
    dict(scale_range=(1.2, 0.8)), dict(angle_range=(30, -30)), dict(min_score=1.5),
], ids=repr)
def test_bad_motion_parameters_raise_parameter_error(kw):
    with pytest.raises(ParameterError):
        estimate_motion(_scene(), _scene(), **kw)


@pytest.mark.parametrize("prev, cur, exc", [
    ((120, 160), (100, 160), ParameterError), ((120, 160), (120, 161), ParameterError),
    ((120, 160), (160, 120), ParameterError), ((120, 160, 3), (120, 150), ParameterError),
], ids=["fewer rows", "one more column", "turned", "BGR vs narrower grey"])
def test_motion_between_frames_of_different_sizes_is_refused(prev, cur, exc):
    rng = np.random.default_rng(0)
    a = cv2.resize(_scene(), (prev[1], prev[0]))
    if len(prev) == 3:
        a = cv2.cvtColor(a, cv2.COLOR_GRAY2BGR)
    b = cv2.resize(_scene(), (cur[1], cur[0])) + rng.integers(0, 3, cur[:2]).astype(np.uint8)
    with pytest.raises(exc, match="differ in size"):
        estimate_motion(a, b)


def test_motion_bad_frames_raise_image_errors(corpus):
    g = _scene()
    with pytest.raises(ImageValueError, match="current frame"):
        estimate_motion(g, np.full((120, 160), np.nan))
    with pytest.raises(ImageValueError, match="previous frame"):
        estimate_motion(np.zeros((120, 160, 2), np.uint8), g)
    with pytest.raises(ImageSizeError):
        estimate_motion(g[:4], g[:4])
    with pytest.raises(ImageReadError, match="no such file"):
        estimate_motion(g, corpus / "missing.png")


# ---------------------------------------------- bugs found through the API
def test_tiny_scale_range_is_refused_or_empty():
    try:
        found = Detector(Pattern.rectangle(40, 30), scale_range=(1e-300, 1e-299)).detect(_scene())
    except SeahoughError:
        return
    assert found == []


_HUGE = {
    "scale 1e6": "Detector(Pattern.rectangle(40, 30), scale_range=(1e6, 1e6)).detect(img)",
    "region 1e9": "Detector(Pattern.rectangle(40, 30), "
                  "search_region=(-1e9, -1e9, 1e9, 1e9)).detect(img)",
    "region 1e300": "Detector(Pattern.rectangle(40, 30), "
                    "search_region=(0, 0, 1e300, 1e300)).detect(img)",
    "translation_bin 1e-6": "Detector(Pattern.rectangle(40, 30), "
                            "config=Config(translation_bin=1e-6)).detect(img)",
    "angle_bin 1e-9": "Detector(Pattern.rectangle(40, 30), "
                      "config=Config(angle_bin=1e-9)).detect(img)",
    "scale_step 1e-9": "Detector(Pattern.rectangle(40, 30), "
                       "config=Config(scale_step=1e-9)).detect(img)",
    "polygon 1e9": "Pattern.polygon([(0, 0), (1e9, 0), (0, 1e9)])",
    "rectangle 1e6": "Pattern.rectangle(1e6, 1e6)",
}

_CHILD = """
import json, sys, numpy as np
from seahough import *
img = np.full((120, 160), 40, np.uint8); img[40:81, 50:111] = 220
for name, code in json.loads(sys.argv[1]).items():
    print('start', name, flush=True)
    try:
        eval(code)
        out = 'ok'
    except SeahoughError as e:
        out = 'refused'
    except Exception as e:
        out = f'{type(e).__name__}: {e}'
    print(json.dumps([name, out]), flush=True)
"""


@pytest.fixture(scope="module")
def huge_runs():
    """Each case of _HUGE in one memory-limited child: {case: outcome}."""
    r = _run(_py(_CHILD) + [json.dumps(_HUGE)], timeout=120)
    assert r.rc == 0, r
    return dict(json.loads(line) for line in r.stdout.splitlines() if line.startswith("["))


@pytest.mark.parametrize("case", list(_HUGE))
def test_parameters_that_would_need_huge_arrays_are_refused(huge_runs, case):
    assert huge_runs[case] in ("ok", "refused"), (_HUGE[case], huge_runs[case])


def test_far_out_parameters_do_not_hang(cli_runs):
    r = cli_runs["hang"]
    assert r.rc == 0, r
    assert all(json.loads(x)[1] in ("ok", "refused") for x in r.stdout.splitlines()
               if x.startswith("[")), r


def test_float64_beyond_float32_range_is_refused_or_finite():
    a = _scene().astype(np.float64) * 1e300
    try:
        g = to_gray(a)
    except ImageValueError:
        return
    assert np.isfinite(g).all()


def test_detection_angle_stays_below_360():
    found = Detector(Pattern.rectangle(60, 40), angle_range=(-1e-14, -1e-14)).detect(_scene())
    assert found and all(0.0 <= d.angle < 360.0 for d in found)


@pytest.mark.parametrize("shape", [(8, 17), (11, 40), (30, 9)])
def test_motion_on_frames_of_8_to_11_px(shape):
    a = _noise(shape, 3)
    try:
        m = estimate_motion(a, a)
    except ImageSizeError as e:
        assert "pattern" not in str(e), e
        return
    assert m is None or np.isfinite(m.matrix).all()


def test_non_numeric_max_shift_is_a_parameter_error():
    with pytest.raises(ParameterError):
        estimate_motion(_scene(), _scene(), max_shift="half")


@pytest.mark.parametrize("v", [5.0, float("nan"), -1.0])
def test_motion_min_confidence_is_validated(v):
    with pytest.raises(ParameterError):
        estimate_motion(_scene(), _scene(), min_confidence=v)


def test_numpy_scalars_are_accepted_as_thresholds():
    Detector(Pattern.rectangle(40, 30), min_score=np.float32(0.5),
             min_confidence=np.float32(0.1))


def test_range_with_three_values_is_refused():
    with pytest.raises(ParameterError):
        Detector(Pattern.rectangle(40, 30), scale_range=(1, 2, 3))


# ----------------------------------------------------- same input, same output
def _as_json(obj):
    """``obj`` as the CLI's JSON gives it back (floats round-trip exactly)."""
    return json.loads(json.dumps(obj, default=lambda o: o.tolist()))


def _key(dets) -> str:
    return repr([d.to_dict() for d in dets])


@pytest.fixture(scope="module")
def marker(tmp_path_factory):
    d = tmp_path_factory.mktemp("marker")
    scene, pattern, _ = sim.marker_scene("board", seed=3, source="procedural")
    cv2.imwrite(str(d / "scene.png"), scene)
    cv2.imwrite(str(d / "pattern.png"), pattern)
    a, b, _ = sim.frame_pair(frame_size=(240, 320), seed=4, source="procedural")
    cv2.imwrite(str(d / "a.png"), a)
    cv2.imwrite(str(d / "b.png"), b)
    return d


_MOTION_CODE = (
    "import json, sys, seahough\n"
    "m = seahough.estimate_motion(sys.argv[1], sys.argv[2])\n"
    "print(json.dumps(None if m is None else m.to_dict()))\n")


@pytest.fixture(scope="module")
def twin_runs(marker):
    """Detection and motion, each in two fresh interpreters with different
    hash seeds (set and dict-of-str order) and thread settings."""
    d = marker
    jobs = {}
    for i, (seed, threads) in enumerate((("0", "1"), ("4242", "2"))):
        env = _env(PYTHONHASHSEED=seed, OMP_NUM_THREADS=threads, NUMBA_NUM_THREADS=threads)
        jobs[("detect", i)] = (_cli("detect", d / "pattern.png", d / "scene.png", "--json"), env)
        jobs[("motion", i)] = (_py(_MOTION_CODE) + [str(d / "a.png"), str(d / "b.png")], env)
    with cf.ThreadPoolExecutor(max_workers=4) as pool:
        futs = {k: pool.submit(_run, argv, 120, env) for k, (argv, env) in jobs.items()}
        return {k: f.result() for k, f in futs.items()}


def test_detect_is_bit_identical_when_repeated_in_one_process(marker):
    d = marker
    pat = Pattern.from_image(d / "pattern.png")
    det = Detector(pat)
    first = det.search(d / "scene.png")
    assert first.detections
    det.detect(d / "a.png")                       # another image in between
    again = det.search(d / "scene.png")
    fresh = Detector(Pattern.from_image(d / "pattern.png")).search(d / "scene.png")
    for other in (again, fresh):
        assert _key(other.detections) == _key(first.detections)
        assert other.planes.xy.tobytes() == first.planes.xy.tobytes()
        assert other.planes.scale_angle.tobytes() == first.planes.scale_angle.tobytes()


def test_motion_is_bit_identical_when_repeated_in_one_process(marker):
    d = marker
    runs = [estimate_motion(d / "a.png", d / "b.png") for _ in range(2)]
    runs.append(estimate_motion(cv2.imread(str(d / "a.png"), cv2.IMREAD_UNCHANGED),
                                cv2.imread(str(d / "b.png"), cv2.IMREAD_UNCHANGED)))
    assert runs[0] is not None
    assert len({repr(m.to_dict()) for m in runs}) == 1


def test_detect_and_motion_are_bit_identical_across_processes(marker, twin_runs):
    d = marker
    recs = []
    for i in range(2):
        r = twin_runs[("detect", i)]
        assert r.rc == 0 and r.stderr == "", r
        rec = json.loads(r.stdout)
        rec.pop("time_ms")
        recs.append(rec)
    assert recs[0] == recs[1]
    api = Detector(Pattern.from_image(d / "pattern.png")).detect(d / "scene.png")
    assert recs[0]["detections"] == _as_json([x.to_dict() for x in api])
    motions = []
    for i in range(2):
        r = twin_runs[("motion", i)]
        assert r.rc == 0, r
        motions.append(json.loads(r.stdout))
    assert motions[0] is not None and motions[0] == motions[1]
    here = estimate_motion(d / "a.png", d / "b.png")
    assert motions[0] == _as_json(here.to_dict())


# ------------------------------------- dead reckoning over broken frames
def _broken_sequence(folder: Path):
    """12 frames of a straight track with, in the middle, frames that cannot
    be used (and the first frame unreadable): ``{index: expected flag words}``."""
    frames, mats = sim.sequence(n_frames=12, frame_size=(240, 320), path="line", step=12.0,
                                seed=6, source="procedural")
    folder.mkdir()
    for i, f in enumerate(frames):
        cv2.imwrite(str(folder / f"frame_{i:03d}.png"), f)
    (folder / "frame_000.png").write_bytes(b"")
    (folder / "frame_004.png").write_text("not an image")
    cv2.imwrite(str(folder / "frame_005.png"), np.zeros((1, 1), np.uint8))
    (folder / "frame_006.png").unlink()
    nan = frames[6].astype(np.float32)
    nan[10, 10] = np.nan
    cv2.imwrite(str(folder / "frame_006.tiff"), nan)
    cv2.imwrite(str(folder / "frame_007.png"), frames[7][:200, :300])
    cv2.imwrite(str(folder / "frame_009.png"), np.full((240, 320), 90, np.uint8))
    unreadable = {0: "empty file", 4: "not an image", 5: "too small", 6: "NaN",
                  7: "differs from the first frame"}
    return frames, unreadable


def test_odometry_flags_every_kind_of_broken_frame_and_goes_on(tmp_path):
    from seahough.motion.odometry import run_odometry

    frames, unreadable = _broken_sequence(tmp_path / "frames")
    res = run_odometry(tmp_path / "frames", tmp_path / "out", progress=False, mosaic=False)
    rows = res.rows
    assert len(rows) == 12
    for i, words in unreadable.items():
        assert rows[i]["status"] == "unreadable", rows[i]
        assert rows[i]["flags"].startswith("unreadable: ") and words in rows[i]["flags"]
        assert rows[i]["x"] is None and rows[i]["matrix"] is None
    assert rows[1]["status"] == "origin"                       # first readable frame
    assert rows[9]["status"] == "assumed" and "pose_assumed" in rows[9]["flags"]
    for i in (2, 3, 8, 10, 11):                                # measured across the gaps
        assert rows[i]["status"] == "measured", rows[i]
        assert all(np.isfinite([rows[i]["x"], rows[i]["y"]]))
    assert res.summary["unreadable_frames"] == 5
    # the track still follows the camera (12 px per frame, straight on)
    clean = run_odometry(frames[1:], tmp_path / "clean", progress=False, mosaic=False)
    end = np.array([rows[-1]["x"], rows[-1]["y"]])
    ref = np.array([clean.rows[-1]["x"], clean.rows[-1]["y"]])
    assert np.hypot(*(end - ref)) < 10.0


def test_odometry_command_over_broken_frames_exits_1_without_traceback(tmp_path):
    _broken_sequence(tmp_path / "frames")
    r = _run(_cli("odometry", tmp_path / "frames", "--out", tmp_path / "out", "--quiet",
                  "--no-mosaic", "--json"), timeout=180)
    assert r.rc == 1 and "Traceback" not in r.stderr and r.stderr == "", r
    summ = json.loads(r.stdout)
    assert summ["frames"] == 12 and summ["flagged_pairs"] == 6
    assert (tmp_path / "out" / "odometry.csv").is_file()
