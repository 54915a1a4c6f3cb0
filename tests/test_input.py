"""Image input: every accepted form, and a specific error for every bad one."""

import cv2
import numpy as np
import pytest

import seahough
from seahough import (ImageReadError, ImageSizeError, ImageValueError, ParameterError,
                      PatternError, SeahoughError)
from seahough.io.images import to_gray


def _scene():
    img = np.full((120, 160), 40, np.uint8)
    cv2.rectangle(img, (50, 40), (110, 80), 220, -1)
    return img


@pytest.mark.parametrize("conv", [
    lambda g: g,
    lambda g: g[:, :, None],
    lambda g: cv2.cvtColor(g, cv2.COLOR_GRAY2BGR),
    lambda g: cv2.cvtColor(g, cv2.COLOR_GRAY2BGRA),
    lambda g: g.astype(np.uint16) * 257,
    lambda g: g.astype(np.float32) / 255.0,
    lambda g: g.astype(np.float64),
    lambda g: g.astype(np.int32),
])
def test_every_accepted_form_gives_the_same_grey_levels(conv):
    g = _scene()
    out = to_gray(conv(g))
    assert out.dtype == np.float32 and out.shape == g.shape
    assert np.abs(out - g).max() < 1.0


def test_bit_depth_reads_a_cameras_twelve_bits_in_sixteen_bit_arrays():
    """``bit_depth=12``: values up to 4095 are read as the 8-bit levels they
    stand for (by default, as 16-bit data: 16 times darker); beyond the
    stated depth, 255 (more than 1 % of them: refused); every frame alike, whatever its own largest value."""
    from seahough.io.images import to_bgr8

    g = _scene()
    twelve = g.astype(np.uint16) * 16
    assert np.abs(to_gray(twelve, bit_depth=12) - g).max() < 1.0
    assert to_gray(twelve).max() == pytest.approx(220 * 16 / 257.0)
    over = twelve.copy()
    over[0, 0] = 60000
    got = to_gray(over, bit_depth=12)
    assert got[0, 0] == 255.0 and np.array_equal(got[1:], to_gray(twelve, bit_depth=12)[1:])
    # more than 1 % beyond: not 12-bit data (read so, a mostly white frame): refused
    wide = g.astype(np.uint16) * 257
    with pytest.raises(ImageValueError, match=r"frame\.png: \d+ % of the values are beyond "
                                              r"bit_depth=12 \(0-4095\), up to 56540"):
        to_gray(wide, bit_depth=12, name="frame.png")
    assert np.abs(to_bgr8(twelve, 12)[..., 0].astype(float) - g).max() <= 1.0
    # (a dark 16-bit image is drawn dark, not taken for [0, 1] floats)
    assert to_bgr8(np.full((4, 4), 10, np.uint16)).max() == 0


def test_sixteen_bit_data_of_fewer_bits_is_said_once(monkeypatch):
    """A uint16 image whose values all fit in 12 (or 10) bits, read as 16-bit
    data, is too dark to show its edges: said once a process for each number
    of bits, with what to give (a sonar user's trial: a bare "not found")."""
    import warnings

    from seahough.errors import BitDepthWarning
    from seahough.io import levels

    monkeypatch.setattr(levels, "_SAID_BITS", set())
    g = _scene()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        to_gray(g.astype(np.uint16) * 16, name="a.png")             # 12 bits: said
        to_gray(g.astype(np.uint16) * 16, name="b.png")             # (once)
        to_gray(g.astype(np.uint16) * 4)                            # 10 bits: said
        to_gray(g.astype(np.uint16) * 16, bit_depth=12)             # its depth given
        to_gray(g.astype(np.uint16) * 257)                          # 16-bit data
        to_gray(np.zeros((40, 40), np.uint16))                      # black
        to_gray(g)                                                  # uint8
    said = [str(x.message) for x in w if issubclass(x.category, BitDepthWarning)]
    assert len(said) == 2 and len(w) == 2, [str(x.message) for x in w]
    assert said[0] == ("a.png: a 16-bit image whose values reach only 3520, read as 16-bit "
                       "data (levels up to 13.7 of 255: too dark to show most edges); a "
                       "camera's 10-14-bit samples (12 bits hold these)? give its bit depth: "
                       "Config(bit_depth=12), CLI --bit-depth 12 (a 12-bit camera: 12)")
    assert said[1].startswith("image: a 16-bit image whose values reach only 880") and \
        "Config(bit_depth=10)" in said[1]
    # 8-bit levels in a 16-bit array: no bit depth to give
    with pytest.warns(BitDepthWarning, match="8-bit data in a 16-bit file"):
        to_gray(g.astype(np.uint16))


def test_a_unit_float_image_pushed_over_one_is_still_read_as_one(monkeypatch):
    """A 0-1 float frame that colour correction pushed a little over 1 (a
    Python user's trial: one pixel at 1.02 turned a detection into "no
    edges"): scaled by 255, its values over 1 saturated; float images of
    another scale are said once each (LevelsWarning), and read as before."""
    import warnings

    from seahough.errors import LevelsWarning
    from seahough.io import levels
    from seahough.io.images import to_bgr8

    monkeypatch.setattr(levels, "_SAID_LEVELS", set())
    g = _scene().astype(np.float32)
    unit = g / 255.0
    over = unit.copy()
    over[0, :3] = 1.02
    assert np.array_equal(to_gray(over)[1:], to_gray(unit)[1:])
    assert to_gray(over)[0, 0] == 255.0
    assert np.array_equal(to_bgr8(over)[1:], to_bgr8(unit)[1:])
    box = seahough.Pattern.rectangle(60, 40)
    assert seahough.Detector(box).detect(over) and seahough.Detector(box).detect(unit)
    # more than 5 % over 1, or a value over 2: levels 0-255 as they are (and said)
    many = unit * 1.25                    # (the bright rectangle: 28 % of the pixels)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        assert to_gray(many.astype(np.float64), name="a.tif").max() == pytest.approx(
            1.25 * 220 / 255)
        to_gray(unit.astype(np.float64) * 3.0)        # (dim again: said once)
        to_gray(many)                                 # (float32: the package's own levels)
        seahough.estimate_motion(_scene() // 100, _scene() // 100)   # (a dark 8-bit pair)
        to_gray(unit * 2 - 1)                         # -1..1
        to_gray(g * 1000)                             # far over 255
        to_gray(g)                                    # levels 0-255: nothing to say
        to_gray(unit)                                 # 0-1: nothing to say
    said = [str(x.message) for x in w if issubclass(x.category, LevelsWarning)]
    assert len(w) == len(said) == 3, [str(x.message) for x in w]
    assert said[0].startswith("a.tif: a float image read as levels 0-255, values only up to "
                              "1.08 of 255: too dark")
    assert "values down to -0.686" in said[1] and "values up to 2.2e+05" in said[2]
    # a frame already in levels is still not copied
    assert np.shares_memory(to_gray(g), g)
    # a dip under 0 as well (saturated at 0); but whole numbers over 1 are a dark 8-bit
    # frame's levels, however few: converting twice changes nothing (a review found the
    # package's own float copy of a dark frame read as 0-1 the second time)
    dip = unit.copy()
    dip[0, :3] = -0.01
    assert to_gray(dip)[0, 0] == 0.0 and np.array_equal(to_gray(dip)[1:], to_gray(unit)[1:])
    dark = np.zeros((60, 80), np.uint8)
    dark[0, :3], dark[10:30, 10:40] = 2, 1
    assert to_gray(to_gray(dark)).max() == 2.0


def test_bit_depth_lets_twelve_bit_frames_be_measured():
    """Real frames saved as a 12-bit camera saves them: read as 16-bit data
    the previous frame has too few edges to be searched for (no motion);
    with ``Config(bit_depth=12)`` the motion is the 8-bit frames'."""
    import seahough
    from seahough.config import MOTION_CONFIG

    from seahough._data import shared_data_dir
    d = shared_data_dir()
    if d is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    seq = d / "sequences" / "sparus_auv_seabed"
    a, b = (cv2.imread(str(seq / f"frame_{i:03d}.png"), cv2.IMREAD_GRAYSCALE) for i in (0, 1))
    a12, b12 = a.astype(np.uint16) * 16, b.astype(np.uint16) * 16
    assert seahough.estimate_motion(a12, b12) is None
    want = seahough.estimate_motion(a, b)
    got = seahough.estimate_motion(a12, b12, config=MOTION_CONFIG.replace(bit_depth=12))
    assert np.abs(got.matrix - want.matrix).max() < 0.05


def test_paths_are_read(tmp_path):
    p = tmp_path / "scene.png"
    cv2.imwrite(str(p), _scene())
    assert np.array_equal(to_gray(p), _scene().astype(np.float32))
    assert np.array_equal(to_gray(str(p)), _scene().astype(np.float32))


@pytest.mark.parametrize("bad, err, words", [
    (np.zeros((0, 0), np.uint8), ImageSizeError, "empty"),
    (np.zeros((1, 1), np.uint8), ImageSizeError, "too small"),
    (np.zeros((1, 100000), np.uint8), ImageSizeError, "too small"),
    (np.full((20, 20), np.nan, np.float32), ImageValueError, "NaN"),
    (np.full((20, 20), np.inf), ImageValueError, "NaN or infinite"),
    (np.zeros((20, 20, 2), np.uint8), ImageValueError, "shape"),
    (np.zeros((20, 20), np.complex64), ImageValueError, "dtype"),
    ([[1, 2], [3, 4]], ImageValueError, "numpy array"),
])
def test_bad_arrays_raise_specific_errors(bad, err, words):
    with pytest.raises(err, match=words):
        to_gray(bad)


def test_bad_files_raise_read_errors_naming_the_file(tmp_path):
    missing = tmp_path / "nope.png"
    with pytest.raises(ImageReadError, match="nope.png: no such file"):
        to_gray(missing)
    empty = tmp_path / "empty.jpg"
    empty.write_bytes(b"")
    with pytest.raises(ImageReadError, match="empty file"):
        to_gray(empty)
    text = tmp_path / "text.png"
    text.write_text("not an image at all")
    with pytest.raises(ImageReadError, match="text.png"):
        to_gray(text)
    ok, buf = cv2.imencode(".jpg", _scene())
    trunc = tmp_path / "trunc.jpg"
    trunc.write_bytes(buf.tobytes()[: len(buf) // 2])
    with pytest.raises(ImageReadError, match="truncated JPEG"):
        to_gray(trunc)


def test_header_claiming_huge_dimensions_is_refused_before_decoding(tmp_path):
    # a valid small PNG whose IHDR says 100000 x 100000
    import struct
    import zlib
    ok, buf = cv2.imencode(".png", _scene())
    data = bytearray(buf.tobytes())
    ihdr = data[12:29]
    new = b"IHDR" + struct.pack(">II", 100000, 100000) + bytes(ihdr[12:17])
    data[12:29] = new
    data[29:33] = struct.pack(">I", zlib.crc32(new) & 0xFFFFFFFF)
    bomb = tmp_path / "bomb.png"
    bomb.write_bytes(bytes(data))
    with pytest.raises(ImageSizeError, match="over the limit"):
        to_gray(bomb, max_pixels=50_000_000)


def test_errors_are_one_hierarchy_and_builtin_compatible():
    for e in (ImageReadError, ImageSizeError, ImageValueError, ParameterError, PatternError):
        assert issubclass(e, SeahoughError) and issubclass(e, ValueError)
    assert issubclass(ImageReadError, OSError)


def test_uniform_image_is_a_clear_empty_result_not_an_error():
    det = seahough.Detector(seahough.Pattern.rectangle(40, 30))
    res = det.search(np.zeros((120, 160), np.uint8))
    assert res.detections == [] and res.note == "no edges"
    assert det.detect(np.full((120, 160), 200, np.uint8)) == []


def test_pattern_without_edges_is_refused():
    with pytest.raises(PatternError, match="too few edges"):
        seahough.Pattern.from_image(np.full((40, 40), 90, np.uint8))


def test_a_pattern_lost_at_a_large_images_working_scale_says_why():
    """A user trial: a 115 px crop searched at scale 6-12 in a 6000 px photo
    was refused as having "too few edges at scale 0.05", and the pattern was
    fine: the image was brought down to 320 px, and the pattern with it. The
    error says so, and what to do; at full size nothing is added."""
    img = np.full((2000, 3000), 90, np.uint8)
    cv2.rectangle(img, (1000, 800), (1240, 960), 200, -1)
    with pytest.raises(PatternError, match=r"too few edges .*; the 3000x2000 image is searched at "
                       r"scale 0\.11 .*Config\.target_size.*scale range starts at 5.*--downscale"):
        seahough.Detector(seahough.Pattern.rectangle(40, 28), (5, 8)).detect(img)
    from seahough.core.preprocess import factor_hint
    assert factor_hint((2000, 3000), 1.0, seahough.Config(), 5) == ""
    assert factor_hint((2000, 3000), 0.2, seahough.Config(downscale=0.2), 5) == ""


@pytest.mark.parametrize("kw", [
    dict(scale_range=(2.0, 1.0)), dict(scale_range=(0, 2)), dict(scale_range=(0.5, float("nan"))),
    dict(angle_range=(10, 5)), dict(angle_range="any"), dict(max_results=0),
    dict(min_score=1.5), dict(search_region=(10, 10, 5, 50)),
])
def test_contradictory_or_out_of_range_parameters_raise_parameter_error(kw):
    with pytest.raises(ParameterError):
        seahough.Detector(seahough.Pattern.rectangle(40, 30), **kw)


@pytest.mark.parametrize("kw", [dict(downscale=0), dict(downscale=1.5), dict(n_keypoints=0),
                                dict(voting="magic"), dict(angle_tolerance=0)])
def test_bad_config_raises_parameter_error_naming_the_field(kw):
    name = next(iter(kw))
    with pytest.raises(ParameterError, match=name):
        seahough.Config(**kw)


@pytest.mark.parametrize("make", [
    lambda: seahough.Pattern.rectangle(-3, 10), lambda: seahough.Pattern.circle(0),
    lambda: seahough.Pattern.circle(10, inner_radius=12), lambda: seahough.Pattern.line(10, 8),
    lambda: seahough.Pattern.polygon([(0, 0), (1, 1)]),
    lambda: seahough.Pattern.rectangle(40, 30, polarity="purple"),
])
def test_bad_shape_parameters_raise(make):
    with pytest.raises((ParameterError, PatternError)):
        make()


def test_a_video_frame_by_its_name_and_every_frame_in_order(tmp_path, caplog):
    """A video's frames as list_frames names them ("dive.avi#2") are images
    for read_image and a Detector; iter_frames gives each frame of a video,
    folder or list in order, an unreadable one as (name, None) with its
    reason logged, and goes on (a user trial found "dive.mp4#3: no such
    file" in Python, where the command line read the video)."""
    import logging

    from conftest import moving_rectangle_video

    path = moving_rectangle_video(tmp_path / "dive.avi", 3, (160, 120), (40, 40), fourcc="MJPG")
    names = seahough.list_frames(path)
    assert [n.split("/")[-1] for n in map(str, names)] == ["dive.avi#0", "dive.avi#1", "dive.avi#2"]
    third = seahough.read_image(names[2])
    assert third.shape == (120, 160, 3)
    found = seahough.Detector(seahough.Pattern.rectangle(60, 40), max_results=1).detect(names[2])
    assert abs(found[0].x - 90) < 1.5 and abs(found[0].y - 60) < 1.5
    frames = list(seahough.iter_frames(path))
    assert [str(n) for n, _ in frames] == [str(n) for n in names]
    assert np.array_equal(frames[2][1], third)
    with pytest.raises(seahough.ImageReadError, match="'x' is no frame number .*dive.avi#12"):
        seahough.read_image(tmp_path / "dive.avi#x")
    with pytest.raises(seahough.ImageReadError, match="no such file"):
        seahough.read_image(tmp_path / "other.avi#1")
    # a folder that is not there: at the call, not at the first frame
    with pytest.raises(seahough.ParameterError, match="no such"):
        seahough.iter_frames(tmp_path / "nowhere")
    # a frame past the end: said so, without decoding on to it
    with pytest.raises(seahough.ImageReadError, match="past the end of the video"):
        seahough.read_image(f"{path}#999999999")
    # a list with a damaged file: its name and None, the reason logged, the rest read
    good, bad = tmp_path / "a.png", tmp_path / "bad.png"
    cv2.imwrite(str(good), frames[0][1])
    bad.write_bytes(b"\x89PNG not really")
    with caplog.at_level(logging.WARNING, logger="seahough.io"):
        got = list(seahough.iter_frames([str(good), str(bad), str(good)]))
    assert [img is None for _, img in got] == [False, True, False]
    assert "bad.png" in caplog.text


def test_a_unit_float_frame_with_a_hot_pixel_is_still_read_as_one(monkeypatch):
    """A docking engineer's trial: one pixel at 3.0 (a glint, a hot pixel) in a
    0-1 float frame made the whole frame levels 0-3 of 255: the marker "not
    found", without a word for float32. Most values between 0 and 1, at most
    5 % over: read as 0-1, those saturated, said once; a dark 8-bit frame in
    float (whole levels 0, 1 and a few bright) is still levels 0-255."""
    import warnings

    from seahough.errors import LevelsWarning
    from seahough.io import levels

    monkeypatch.setattr(levels, "_SAID_LEVELS", set())
    unit = _scene().astype(np.float32) / 255.0
    hot = unit.copy()
    hot[0, 0], hot[5, 7] = 3.0, 40.0
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        g = to_gray(hot, name="f.png")
        to_gray(hot)                                   # (said once)
    assert np.array_equal(g[1:, 8:], to_gray(unit)[1:, 8:]) and g[0, 0] == g[5, 7] == 255.0
    said = [str(x.message) for x in w if issubclass(x.category, LevelsWarning)]
    assert said == ["f.png: a 0-1 float image with a few values far over 1 (up to 40: hot "
                    "pixels, a glint?), read as 0-1 (those saturate, as 1 does)"], said
    box = seahough.Pattern.rectangle(60, 40)
    assert seahough.Detector(box).detect(hot)
    dark = np.zeros((100, 120), np.float32)
    dark[40:60, 40:80], dark[0, :4] = 1.0, 3.0          # (8-bit levels 0, 1 and 3)
    assert to_gray(dark).max() == 3.0
    # a review: a 0-1 sonar fan whose outside is exactly 0 (most of the frame) with a
    # hot pixel was still levels 0-3; a dark 16-bit frame with a bright rope, read
    # once to levels under 1 of 255, was read as 0-1 the second time (the package
    # reads its own float32 images again: find_curves)
    rng = np.random.default_rng(0)
    fan = np.zeros((240, 320), np.float32)
    fan[:, 100:220] = rng.uniform(0.1, 0.9, (240, 120))
    fan[5, 150] = 3.0
    assert to_gray(fan).max() == 255.0
    raw = rng.normal(120, 20, (240, 320)).clip(0, 65535).astype(np.uint16)
    raw[115:122, :] = 6000
    once = to_gray(raw)
    assert np.median(once) < 1.0 and np.array_equal(to_gray(once), once)


def test_a_dim_unit_float_image_is_said_with_its_file_name(tmp_path, monkeypatch, capsys):
    """A sonar user's trial: linear backscatter as float32 0-0.05 (levels up to
    12.8 of 255) was "not found" without a word, where a dark 16-bit file is
    said (BitDepthWarning); and the CLI's float warnings named "image", not
    the file. A 0-1 image reaching only under 16 of 255 levels is said once,
    with its file's name and what to do."""
    import warnings

    from seahough.errors import LevelsWarning
    from seahough.io import levels

    monkeypatch.setattr(levels, "_SAID_LEVELS", set())
    unit = _scene().astype(np.float32) / 255.0
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        to_gray(unit)                                  # 0-1, bright enough: nothing
        to_gray(unit * 0.05, name="backscatter.tif")   # dim: said
        to_gray(unit * 0.04)                           # (once)
        to_gray(np.zeros((40, 40), np.float32))        # black: nothing to stretch
    said = [str(x.message) for x in w]
    assert said == ["backscatter.tif: a 0-1 float image whose values reach only 0.0431 (levels "
                    "up to 11 of 255: too dark to show most edges); stretch it to 0-1 (numpy: "
                    "image / image.max())"], said
    assert all(issubclass(x.category, LevelsWarning) for x in w)
    # the CLI names the file the warning is about
    from seahough.cli import main
    monkeypatch.setattr(levels, "_SAID_LEVELS", set())
    path = tmp_path / "db.tif"
    assert cv2.imwrite(str(path), (_scene().astype(np.float32) - 255.0) / 10.0)
    with pytest.raises(SystemExit):
        main(["detect", "circle:10", str(path)])
    err = capsys.readouterr().err
    assert f"warning: {path}: a float image read as levels 0-255, values down to" in err, err


def test_a_warning_from_the_prompt_or_python_c_is_no_crash():
    """A sonar user's trial: every seahough warning raised ImportError
    ("'__main__' is not a built-in module") from ``python -c``, a script on
    stdin and the interactive prompt: the warning's line was looked up
    through __main__'s loader, which has no source to give."""
    import subprocess
    import sys

    code = ("import numpy as np, seahough; seahough.Detector(seahough.Pattern.circle(8))"
            ".detect(np.linspace(0, 3000, 64 * 64).reshape(64, 64).astype(np.uint16))")
    for args, stdin in (([sys.executable, "-c", code], None), ([sys.executable, "-"], code)):
        r = subprocess.run(args, input=stdin, capture_output=True, text=True, timeout=300)
        assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr[-2000:]
        assert "BitDepthWarning" in r.stderr, r.stderr[-2000:]


def test_a_numpy_file_is_an_image_and_a_video_is_said_to_be_one(tmp_path):
    """A sonar analyst's trial: a float tile saved with np.save was "not an
    image OpenCV can decode", and so was a whole video given to
    Detector.detect (read whole first: a dive's video is gigabytes)."""
    tile = (_scene().astype(np.float32) / 255.0)
    np.save(tmp_path / "tile.npy", tile)
    assert np.array_equal(seahough.read_image(tmp_path / "tile.npy"), tile)
    np.save(tmp_path / "one.npy", tile[:, :, None])                  # HxWx1: grey
    assert seahough.read_image(tmp_path / "one.npy").shape == tile.shape
    box = seahough.Pattern.rectangle(60, 40)
    assert seahough.Detector(box).detect(str(tmp_path / "tile.npy"))
    np.save(tmp_path / "cube.npy", np.zeros((3, 4, 5, 6)))
    with pytest.raises(ImageReadError, match=r"cube.npy: a NumPy array of shape \(3, 4, 5, 6\)"):
        seahough.read_image(tmp_path / "cube.npy")
    with pytest.raises(seahough.ImageSizeError, match="over the limit of 100"):
        seahough.read_image(tmp_path / "tile.npy", max_pixels=100)
    # its size before it is read (a reviewer's 3.2 GB float64 file was read whole), and
    # an .npz archive so named is no array (it raised AttributeError)
    np.save(tmp_path / "big.npy", np.zeros((1000, 1000, 4)))
    with pytest.raises(seahough.ImageSizeError, match=r"big.npy: a \(1000, 1000, 4\) float64 "
                       r"array needs about \d+ MB to read and search, over the memory limit of 10 MB"):
        seahough.read_image(tmp_path / "big.npy", max_memory_mb=10)
    np.savez(tmp_path / "two.npz", a=tile, b=tile)
    (tmp_path / "two.npz").rename(tmp_path / "two.npy")
    with pytest.raises(ImageReadError, match=r"two.npy: a NumPy archive of several arrays"):
        seahough.read_image(tmp_path / "two.npy")
    (tmp_path / "text.npy").write_text("not numpy")
    with pytest.raises(ImageReadError, match="text.npy: not a NumPy array file"):
        seahough.read_image(tmp_path / "text.npy")
    (tmp_path / "dive.mp4").write_bytes(b"\0" * 64)
    with pytest.raises(ImageReadError, match=r"dive.mp4: a video, not an image: one of its "
                       r"frames is .*dive.mp4#12 \(from 0\); all of them: seahough.iter_frames"):
        seahough.Detector(box).detect(str(tmp_path / "dive.mp4"))


def test_a_frame_name_with_a_digit_that_is_not_ascii_is_said_to_be_no_frame(tmp_path):
    """'²'.isdigit() is True and int('²') fails: "dive.avi#²" raised ValueError
    (a reviewer's find) instead of naming what is wrong."""
    from seahough.io.frames import video_ref_problem

    (tmp_path / "dive.avi").write_bytes(b"\0" * 16)
    assert "'²' is no frame number" in video_ref_problem(f"{tmp_path / 'dive.avi'}#²")
