"""The ``seahough`` command line, run as users run it: the installed
``seahough`` command (the console script beside the interpreter running the
tests), in a subprocess."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
import threading
import types
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as sim
from seahough._data import shared_data_dir

from conftest import moving_rectangle_video, seahough_command

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _env() -> dict:
    env = dict(os.environ)
    env.setdefault("MPLBACKEND", "Agg")
    return env


def run(*args, cwd=None, timeout=180):
    return subprocess.run([str(seahough_command()), *map(str, args)], cwd=cwd, env=_env(),
                          capture_output=True, text=True, timeout=timeout)


def run_on_terminal(*args, timeout=180):
    """Run the command with its stderr on a pseudo-terminal, as in an
    interactive shell (where progress bars are drawn): ``(returncode,
    stdout, what reached the terminal)``."""
    if os.name != "posix":
        pytest.skip("pseudo-terminals are POSIX only")
    import fcntl
    import struct
    import termios

    master, slave = os.openpty()
    # a size, as a terminal window has (tqdm draws nothing on 0 columns)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    chunks = []

    def drain():
        while True:
            try:
                data = os.read(master, 65536)
            except OSError:          # EIO: the child closed the terminal
                return
            if not data:
                return
            chunks.append(data)

    try:
        proc = subprocess.Popen([str(seahough_command()), *map(str, args)], env=_env(),
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
    finally:
        os.close(slave)
    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    try:
        out, _ = proc.communicate(timeout=timeout)
    finally:
        if proc.poll() is None:
            proc.kill()
        reader.join(10)
        os.close(master)
    return proc.returncode, out.decode(), b"".join(chunks).decode("utf-8", "replace")


def png_size(path: Path) -> tuple[int, int]:
    """``(width, height)`` of a PNG from its header, after checking that it
    is one and that it decodes to that size."""
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR", f"{path} is not a PNG"
    w, h = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    im = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert im is not None and im.shape[:2] == (h, w), path
    return w, h


def csv_without_timing(path: Path) -> list:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.pop("ms")
    return rows


def test_cli_tests_run_the_installed_command(tmp_path, monkeypatch):
    exe = seahough_command()
    assert exe.parent == Path(sys.executable).parent and os.access(exe, os.X_OK)
    proc = run("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"seahough {seahough.__version__}"
    # no command beside the interpreter: a clear failure, never python -m as a fallback
    monkeypatch.setattr(sys, "executable", str(tmp_path / "python"))
    with pytest.raises(pytest.fail.Exception, match="seahough command is not installed"):
        seahough_command()


def assert_one_error_line(proc, *needles):
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("seahough: error: ")
    assert "Traceback" not in proc.stderr
    for n in needles:
        assert n in lines[0], lines[0]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """A marker scene (known pose), its clean pattern, a matched negative, a fake PNG."""
    d = tmp_path_factory.mktemp("scenes")
    scene, pattern, truth = sim.marker_scene("board", seed=3, source="procedural")
    cv2.imwrite(str(d / "scene.png"), scene)
    cv2.imwrite(str(d / "pattern.png"), pattern)
    cv2.imwrite(str(d / "neg.png"), sim.negative_scene(seed=3, source="procedural"))
    (d / "notes.png").write_text("this is not an image\n")
    return d, truth


# ----------------------------------------------------------------------------- detect
def test_detect_csv_holds_what_json_holds(scenes, tmp_path):
    d, truth = scenes
    args = ("detect", d / "pattern.png", d / "scene.png", d / "neg.png", "-n", 2, "--quiet")
    proc = run(*args, "--csv")
    assert proc.returncode == 1, proc.stderr
    rows = list(csv.DictReader(io.StringIO(proc.stdout)))
    recs = [json.loads(line) for line in run(*args, "--json").stdout.splitlines()]
    found = [r for r in rows if r["file"].endswith("scene.png")]
    assert [r["rank"] for r in found] == [str(i + 1) for i in range(len(recs[0]["detections"]))]
    for r, det in zip(found, recs[0]["detections"]):
        assert r["found"] == "true" and r["width"] == "640" and r["kind"] == "object"
        for k in ("x", "y", "scale", "angle", "score", "confidence", "nfa"):
            assert float(r[k]) == pytest.approx(det[k]), k
        assert json.loads(r["flags"]) == det["flags"] and json.loads(r["matrix"]) == det["matrix"]
    assert abs(float(found[0]["x"]) - truth.x) < 2
    (neg,) = [r for r in rows if r["file"].endswith("neg.png")]   # one row, nothing found
    assert neg["found"] == "false" and neg["rank"] == "" and neg["x"] == ""
    # ... its best declined candidate's reason, as the JSON has it, and as the table the
    # option that would let it through (a user trial: the CSV dropped it); a detection: none
    assert neg["declined"].startswith((recs[1]["best_declined"] or {}).get("declined", "-"))
    assert neg["declined"].endswith(("(option --min-score)", "(option --max-nfa)",
                                     "(far under it: the pattern may not be in view)"))
    assert neg["declined"] and all(r["declined"] == "" for r in found)
    assert all(r["frame"] == "" for r in rows) and "frame" not in recs[0]   # (files: none)
    # a name with a line break, a comma and a quote stays one field
    odd = tmp_path / 'new\nline, "q".png'
    odd.write_bytes((d / "neg.png").read_bytes())
    proc = run("detect", d / "pattern.png", odd, "--csv", "-q")
    (r,) = list(csv.DictReader(io.StringIO(proc.stdout, newline="")))
    assert r["file"] == str(odd) and r["found"] == "false"
    assert_one_error_line(run(*args, "--csv", "--json"), "--json and --csv")
    # a rope: its line columns; a bad file: its line on stderr, the others' rows kept
    img, _ = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    cv2.imwrite(str(tmp_path / "rope.png"), img)
    proc = run("detect", "line:200,8", tmp_path / "rope.png", d / "notes.png", "--csv", "-n", 1,
               "--angle-range", 0, 180, "-q")
    assert proc.returncode == 2 and "notes.png" in proc.stderr
    r, bad = list(csv.DictReader(io.StringIO(proc.stdout)))
    assert r["kind"] == "line" and r["line_angle"] and r["line_offset"] and r["error"] == ""
    # ... with its visible extent, as the JSON's segment (the CSV had none)
    (seg,) = [d["segment"] for d in json.loads(run(
        "detect", "line:200,8", tmp_path / "rope.png", "--json", "-n", 1, "--angle-range", 0, 180,
        "-q").stdout)["detections"]]
    assert seg is not None and np.allclose(json.loads(r["segment"]), seg)
    assert all(x["segment"] == "" for x in found)    # (a shape: none)
    # ... and its own row (a sonar user's trial: a CSV or JSON Lines reader lost track of
    # it): the reason in "error", nothing else but the file
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0] == f"seahough: error: {d / 'notes.png'}: {bad['error']}"
    assert bad["file"] == str(d / "notes.png") and bad["error"]
    assert all(v == "" for k, v in bad.items() if k not in ("file", "error"))
    proc = run("detect", "line:200,8", tmp_path / "rope.png", d / "notes.png", "--json", "-n", 1,
               "--angle-range", 0, 180, "-q")
    assert proc.returncode == 2
    good, bad_rec = (json.loads(line) for line in proc.stdout.splitlines())
    assert good["found"] is True and "error" not in good
    assert bad_rec == {"file": str(d / "notes.png"), "found": None, "error": bad["error"],
                       "detections": []}


def test_detect_json_matches_python_api(scenes):
    d, truth = scenes
    proc = run("detect", d / "pattern.png", d / "scene.png", "--json",
               "--scale-range", 0.5, 2, "--angle-range", 0, 360)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert len(lines) == 1
    rec = json.loads(lines[0])
    assert rec["file"] == str(d / "scene.png")
    assert (rec["width"], rec["height"]) == (640, 480)
    assert rec["found"] is True and rec["time_ms"] > 0
    api = seahough.Detector(seahough.Pattern.from_image(d / "pattern.png"),
                            scale_range=(0.5, 2.0), angle_range=(0.0, 360.0)
                            ).detect(d / "scene.png")
    assert len(rec["detections"]) == len(api)
    for got, want in zip(rec["detections"], api):
        for k in ("x", "y", "scale", "angle", "score"):
            assert got[k] == pytest.approx(getattr(want, k), abs=1e-6)
        assert np.allclose(got["matrix"], want.matrix, atol=1e-6)
    best = rec["detections"][0]
    assert np.hypot(best["x"] - truth.x, best["y"] - truth.y) < 1.5
    assert abs((best["angle"] - truth.angle + 180) % 360 - 180) < 1.0
    assert best["scale"] == pytest.approx(truth.scale, rel=0.02)


def test_detect_human_table(scenes):
    d, truth = scenes
    proc = run("detect", d / "pattern.png", d / "scene.png")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith(str(d / "scene.png")) and "640x480" in lines[0]
    assert "1 found" in lines[0]
    assert lines[1].split() == ["#", "x", "y", "scale", "angle", "score", "conf", "nfa", "flags"]
    row = lines[2].split()
    assert row[0] == "1"
    x, y, scale, angle = map(float, row[1:5])
    assert np.hypot(x - truth.x, y - truth.y) < 1.5
    assert scale == pytest.approx(truth.scale, rel=0.02)
    assert proc.stderr == ""


def test_no_marker_exits_1(scenes):
    d, _ = scenes
    proc = run("detect", d / "pattern.png", d / "neg.png", "--json")
    assert proc.returncode == 1, proc.stderr
    rec = json.loads(proc.stdout)
    assert rec["found"] is False and rec["detections"] == []
    assert "Traceback" not in proc.stderr


@pytest.mark.parametrize("case", ["missing", "text_png", "scale_range", "shape_spec",
                                  "shape_numbers", "pattern_missing", "shape_bare"])
def test_bad_input_exits_2_with_one_line(scenes, case):
    d, _ = scenes
    args, needle = {
        "missing": (("detect", d / "pattern.png", d / "nosuch.png"), "nosuch.png"),
        "text_png": (("detect", d / "pattern.png", d / "notes.png"), "notes.png"),
        "scale_range": (("detect", d / "pattern.png", d / "scene.png", "--scale-range", 2, 1),
                        "--scale-range"),
        "shape_spec": (("detect", "hexagon:3", d / "scene.png"), "hexagon:3"),
        "shape_numbers": (("detect", "rect:60", d / "scene.png"), "rect:60"),
        "pattern_missing": (("detect", d / "nopattern.png", d / "scene.png"), "nopattern.png"),
        # a shape's name without its sizes (and no file of that name): the syntax is named
        "shape_bare": (("detect", "circle", d / "scene.png"), "needs its sizes: circle:R"),
    }[case]
    proc = run(*args)
    assert_one_error_line(proc, needle)
    assert proc.stdout == ""


def test_bad_image_among_good_ones(scenes):
    d, _ = scenes
    proc = run("detect", d / "pattern.png", d / "scene.png", d / "notes.png", d / "neg.png",
               "--json", "--quiet")
    assert proc.returncode == 2
    recs = [json.loads(line) for line in proc.stdout.strip().splitlines()]
    assert [Path(r["file"]).name for r in recs] == ["scene.png", "notes.png", "neg.png"]
    assert recs[0]["found"] and recs[2]["found"] is False
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"seahough: error: {d / 'notes.png'}: ")
    # the bad file's record: why, as on stderr (found: null, neither true nor false)
    assert recs[1] == {"file": str(d / "notes.png"), "found": None, "detections": [],
                       "error": err[0].split(f"{d / 'notes.png'}: ", 1)[1]}
    assert "Traceback" not in proc.stderr


def test_detect_a_picture_that_cannot_be_written_loses_no_result(scenes, tmp_path):
    """A folder in the way of one image's overlay: that image's results are
    still printed, the error is one line on stderr, the next images are
    searched and drawn, and the exit code is 2."""
    d, _ = scenes
    (tmp_path / "scene_overlay.png").mkdir()
    proc = run("detect", d / "pattern.png", d / "scene.png", d / "neg.png", "--out", tmp_path,
               "--json", "--quiet", "-j", "1")
    assert proc.returncode == 2
    recs = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [Path(r["file"]).name for r in recs] == ["scene.png", "neg.png"]
    assert recs[0]["found"] and "overlay" not in recs[0]
    assert "scene_overlay.png: cannot write the figure" in recs[0]["picture_error"]
    assert recs[1]["overlay"] == str(tmp_path / "neg_overlay.png") and "picture_error" not in recs[1]
    assert (tmp_path / "neg_edges.png").is_file()
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and "scene_overlay.png: cannot write the figure" in err[0]
    assert "Traceback" not in proc.stderr
    # the table form prints the found image's detections before the error
    proc = run("detect", d / "pattern.png", d / "scene.png", "--out", tmp_path, "--quiet")
    assert proc.returncode == 2 and "1 found" in proc.stdout


def test_bit_depth_option_reads_twelve_bit_files(tmp_path):
    """A pool photo and three survey frames saved as a 12-bit camera saves them
    (16-bit PNG, values up to 4095): found and measured with --bit-depth 12,
    too dark without (not found; odometry flags the pairs few_edges)."""
    data = shared_data_dir()
    if data is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    photo = data / "objects" / "robosub_transdec" / "images" / "1448.jpg"
    p = tmp_path / "b12.png"
    cv2.imwrite(str(p), cv2.imread(str(photo), cv2.IMREAD_GRAYSCALE).astype(np.uint16) * 16)
    proc = run("detect", "circle:16", p, p, "--json", "--out", tmp_path / "dark")
    assert proc.returncode == 1 and json.loads(proc.stdout.splitlines()[0])["found"] is False
    # why it is not found is said once, on one line, with the file and the option
    # (a sonar user's trial: "not found", and no hint)
    said = [line for line in proc.stderr.splitlines() if "a 16-bit image" in line]
    assert len(said) == 1 and str(p) in said[0] and "--bit-depth 12" in said[0], proc.stderr
    assert said[0].startswith("seahough: warning: ")      # (one line, not "seahough:0: ...")
    # ... and in each image's own record (a spreadsheet of the CSV showed "not found" alone)
    recs = [json.loads(line) for line in proc.stdout.splitlines()]
    assert all("reach only" in r["warning"] and "--bit-depth" in r["warning"] for r in recs)
    rows = list(csv.DictReader(io.StringIO(run("detect", "circle:16", p, "--csv").stdout)))
    assert rows and all("reach only" in r["warning"] for r in rows)
    eight = tmp_path / "b8.png"          # 8-bit data in a 16-bit file: no --bit-depth for it
    cv2.imwrite(str(eight), cv2.imread(str(photo), cv2.IMREAD_GRAYSCALE).astype(np.uint16))
    rec = json.loads(run("detect", "circle:16", eight, "--json").stdout)
    assert "8-bit data in a 16-bit file" in rec["warning"] and "--bit-depth" not in rec["warning"]
    proc = run("detect", "circle:16", p, "--json", "--bit-depth", "12", "--out", tmp_path / "pics")
    assert proc.returncode == 0 and len(json.loads(proc.stdout)["detections"]) == 3
    assert "a 16-bit image" not in proc.stderr and "warning" not in json.loads(proc.stdout)
    # the overlay draws the photo as the search read it, not 16 times too dark
    middle = [cv2.imread(str(tmp_path / d / "b12_overlay.png"), cv2.IMREAD_GRAYSCALE)
              for d in ("dark", "pics")]
    middle = [float(np.median(m[m.shape[0] // 3:2 * m.shape[0] // 3,
                                m.shape[1] // 3:2 * m.shape[1] // 3])) for m in middle]
    assert middle[1] > 60 and middle[0] < 20, middle
    assert_one_error_line(run("detect", "circle:16", p, "--bit-depth", "8"), "--bit-depth")
    # a pattern cut from such a file is read the same way
    crop = tmp_path / "crop12.png"
    cv2.imwrite(str(crop), cv2.imread(str(p), cv2.IMREAD_UNCHANGED)[150:330, 100:300])
    proc = run("detect", crop, p, "--json", "--bit-depth", "12", "--scale-range", "0.9", "1.1")
    assert proc.returncode == 0, proc.stderr
    best = json.loads(proc.stdout)["detections"][0]
    assert abs(best["x"] - 199.5) < 1.0 and abs(best["y"] - 239.5) < 1.0
    seq = tmp_path / "seq"
    seq.mkdir()
    for i in range(3):
        f = cv2.imread(str(data / "sequences" / "sparus_auv_seabed" / f"frame_{i:03d}.png"),
                       cv2.IMREAD_GRAYSCALE)
        cv2.imwrite(str(seq / f"f{i}.png"), f.astype(np.uint16) * 16)
    proc = run("odometry", seq, "--out", tmp_path / "o16", "--quiet", "--no-mosaic")
    assert proc.returncode == 1
    assert proc.stderr.count("a 16-bit image") == 1 and "--bit-depth 12" in proc.stderr
    assert f"{seq / 'f0.png'}: a 16-bit image" in proc.stderr    # (the frame named)
    with open(tmp_path / "o16" / "odometry.csv", newline="") as fh:
        assert [r["flags"].split(";")[0] for r in csv.DictReader(fh)][1:] == ["few_edges"] * 2
    proc = run("odometry", seq, "--out", tmp_path / "o12", "--quiet", "--bit-depth", "12")
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_accumulator_picture_of_several_patterns_shows_each_pattern(tmp_path, monkeypatch):
    """With several patterns, the accumulator picture shows each pattern's
    planes, one under the other, titled with its name (a trial found the
    post planes left out of a buoy-and-post search)."""
    from seahough import viz
    from seahough.cli import detect as D
    from seahough.cli._common import make_detector

    img, _ = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    det = make_detector("buoy=circle:16+rope=line:200,8", (0.5, 2.0), (0.0, 180.0), 1, 0.5,
                        0.0, None, None, False, None, None)
    res = det.search(img)
    assert [d.pattern for d in res.detections] == ["rope"]
    seen = []
    draw = viz.plot_accumulator
    monkeypatch.setattr(viz, "plot_accumulator",
                        lambda planes, dets, path, title, note, patterns=None, best=None:
                        seen.append((planes, title)) or draw(planes, dets, path, title=title,
                                                            note=note))
    written = {}
    D._pictures("rope.png", img, res, det, None, tmp_path / "rope",
                D.Drawing(kinds=("accumulator",)), written)
    assert [(p, t) for p, t in seen] == [
        (res.parts["buoy"].planes, "rope.png: accumulator of pattern buoy"),
        (res.parts["rope"].planes, "rope.png: accumulator of pattern rope")]
    both = cv2.imread(written["accumulator"])
    draw(res.parts["rope"].planes, res.detections, tmp_path / "one.png")
    single = cv2.imread(str(tmp_path / "one.png"))
    assert both.shape == (2 * single.shape[0], single.shape[1], 3)


def test_each_of_several_patterns_takes_its_own_settings(tmp_path):
    from seahough.cli._common import make_detector

    det = make_detector("gate=polyline:6:0,100,0,0,210,0,210,100@angle=-15:15,polarity=either"
                        "+buoy=circle:16@scale=0.3:3,n=2,max-nfa=0.1+path=rect:120,20",
                        (0.5, 2.0), (0.0, 360.0), 5, 0.5, 0.0, None, None, False, None, None)
    gate, buoy, path = (det.parts[k] for k in ("gate", "buoy", "path"))
    assert gate.angle_range == (345.0, 375.0) and gate.scale_range == (0.5, 2.0)  # (-15 to 15)
    assert gate.pattern.polarity == "either" and path.pattern.polarity == "bright"
    assert buoy.scale_range == (0.3, 3.0) and buoy.max_results == 2 and buoy.max_nfa == 0.1
    assert path.angle_range == (0.0, 360.0) and path.max_results == 5
    # one pattern may carry them too
    one = make_detector("circle:16@scale=0.3:3", (0.5, 2.0), (0.0, 360.0), 5, 0.5, 0.0, None,
                        None, False, None, None)
    assert one.scale_range == (0.3, 3.0) and not one.parts
    # in the command: found with them; a wrong option is one line
    img = np.full((240, 320), 90, np.uint8)
    cv2.circle(img, (100, 120), 8, 220, -1)      # a small buoy: half the pattern's radius
    cv2.imwrite(str(tmp_path / "pool.png"), img)
    proc = run("detect", "box=rect:60,40+buoy=circle:16@scale=0.3:3", tmp_path / "pool.png",
               "--json")
    assert proc.returncode == 0, proc.stderr
    (rec,) = [json.loads(line) for line in proc.stdout.splitlines()]
    d = rec["detections"][0]
    assert d["pattern"] == "buoy" and abs(d["scale"] - 0.5) < 0.05, d
    # a file name holding "@": the whole name names it
    cv2.imwrite(str(tmp_path / "box@2x.png"), img[100:140, 80:120])
    named = make_detector(f"{tmp_path / 'box@2x.png'}+circle:16", (0.5, 2.0), (0.0, 360.0), 5,
                          0.5, 0.0, None, None, False, None, None)
    assert list(named.parts) == [str(tmp_path / "box@2x.png"), "circle:16"]
    for bad, needle in (("buoy=circle16+box=rect:9,9", "a shape is NAME:SIZES: circle:R"),
                        ("buoy=circle:16@n=2,n=3+box=rect:9,9", "n is given twice"),
                        ("buoy=circle:16@scale=2:1+box=rect:9,9", "buoy: circle:16@...: scale"),
                        ("curve:8@n=2", "takes no @ settings"),
                        ("buoy=circle:16@scale=2", "scale='2': expected LO:HI"),
                        ("buoy=circle:16@size=2:3", "with keys scale, angle"),
                        ("buoy=circle:16@polarity=up", "bright, dark or either")):
        assert_one_error_line(run("detect", bad, tmp_path / "pool.png"), needle)


def test_detect_pictures_chooses_which_are_drawn(scenes, tmp_path):
    d, _ = scenes
    proc = run("detect", d / "pattern.png", d / "scene.png", "--out", tmp_path / "a",
               "--pictures", "overlay", "--json", "-q")
    assert proc.returncode == 0, proc.stderr
    rec = json.loads(proc.stdout)
    assert rec["overlay"] == str(tmp_path / "a" / "scene_overlay.png")
    assert "accumulator" not in rec and "edges" not in rec
    assert [p.name for p in (tmp_path / "a").iterdir()] == ["scene_overlay.png"]
    proc = run("detect", d / "pattern.png", d / "scene.png", "--out", tmp_path / "b",
               "--pictures", "edges,accumulator", "-q")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        "scene_accumulator.png", "scene_edges.png"]
    assert_one_error_line(run("detect", d / "pattern.png", d / "scene.png", "--out",
                              tmp_path / "c", "--pictures", "overlay,vote"), "--pictures")
    proc = run("detect", d / "pattern.png", d / "scene.png", "--pictures", "overlay")
    assert proc.returncode == 2 and "give --out DIR" in proc.stderr


def test_detect_out_writes_pngs(scenes, tmp_path):
    d, _ = scenes
    from seahough.viz import detections_size

    proc = run("detect", d / "pattern.png", d / "scene.png", d / "neg.png", "--out", tmp_path,
               "--json", "--quiet")
    assert proc.returncode == 1          # found in scene.png, not in neg.png
    recs = [json.loads(line) for line in proc.stdout.splitlines()]
    for rec, stem in zip(recs, ("scene", "neg")):
        assert rec["overlay"] == str(tmp_path / f"{stem}_overlay.png")
        assert rec["accumulator"] == str(tmp_path / f"{stem}_accumulator.png")
        assert rec["edges"] == str(tmp_path / f"{stem}_edges.png")
    # every image gets its three pictures, and nothing else is written
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"{stem}_{kind}.png" for stem in ("scene", "neg")
        for kind in ("overlay", "accumulator", "edges"))
    for stem in ("scene", "neg"):
        sizes = {kind: png_size(tmp_path / f"{stem}_{kind}.png")
                 for kind in ("overlay", "accumulator", "edges")}
        assert sizes == {"overlay": detections_size((480, 640)), "accumulator": (1300, 560),
                         "edges": (1300, 560)}
        for kind in sizes:
            assert cv2.imread(str(tmp_path / f"{stem}_{kind}.png")).std() > 10, (stem, kind)
        # the edges picture draws the segments (cyan) and key points (red)
        ed = cv2.imread(str(tmp_path / f"{stem}_edges.png"))
        cyan = (np.abs(ed.astype(int) - [255, 229, 0]).max(axis=2) < 40).sum()
        assert cyan > 200, stem
    # the table mode names the three files
    proc = run("detect", d / "pattern.png", d / "scene.png", "--out", tmp_path / "t")
    assert proc.returncode == 0, proc.stderr
    wrote = [ln for ln in proc.stdout.splitlines() if ln.strip().startswith("wrote ")]
    assert len(wrote) == 1 and str(tmp_path / "t" / "scene_edges.png") in wrote[0]
    assert "_edges.png" in run("detect", "--help").stdout.replace("\n", " ")


def test_not_found_says_why(tmp_path):
    """An image the search cannot run on says why (SearchResult.note), in
    the table and in the JSON record; the exit status stays 1."""
    cv2.imwrite(str(tmp_path / "black.png"), np.zeros((120, 160), np.uint8))
    cv2.imwrite(str(tmp_path / "grey.png"), np.full((120, 160, 3), 128, np.uint8))
    small = np.full((120, 160), 40, np.uint8)
    cv2.rectangle(small, (50, 40), (110, 80), 220, -1)
    cv2.imwrite(str(tmp_path / "small.png"), small)
    proc = run("detect", "rect:60,40", tmp_path / "black.png", tmp_path / "grey.png")
    assert proc.returncode == 1 and proc.stderr == "", proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 2
    for line, name in zip(lines, ("black.png", "grey.png")):
        assert line.startswith(str(tmp_path / name) + "  160x120  not found (no edges)  ("), line
    proc = run("detect", "rect:60,40", tmp_path / "black.png", "--json")
    assert proc.returncode == 1
    rec = json.loads(proc.stdout)
    assert rec["found"] is False and rec["detections"] == [] and rec["note"] == "no edges"
    # a pattern too large at every searched scale says so; a search that ran has no note
    proc = run("detect", "rect:600,400", tmp_path / "small.png", "--scale-range", 1, 1)
    assert proc.returncode == 1
    assert "  not found (pattern larger than the image)  (" in proc.stdout, proc.stdout
    proc = run("detect", "rect:60,40", tmp_path / "small.png", "--json")
    assert proc.returncode == 0
    assert json.loads(proc.stdout)["note"] == ""


def test_a_caption_is_listed_and_drawn(tmp_path):
    """A frame with a burned-in timestamp box: JSON "captions" lists its box
    (filled, not searched), the overlay is drawn; a frame without: []."""
    img = np.random.default_rng(0).uniform(60, 200, (240, 320)).astype(np.uint8)
    cv2.rectangle(img, (150, 100), (230, 150), 240, -1)
    plain = img.copy()
    img[:16, :120] = 0
    for cx in range(8, 114, 14):
        cv2.circle(img, (cx, 8), 4, 235, -1)
    cv2.imwrite(str(tmp_path / "cap.png"), img)
    cv2.imwrite(str(tmp_path / "plain.png"), plain)
    proc = run("detect", "rect:80,50", tmp_path / "cap.png", tmp_path / "plain.png", "--json",
               "-o", tmp_path / "out", "--pictures", "overlay")
    assert proc.returncode == 0, proc.stderr
    recs = [json.loads(line) for line in proc.stdout.splitlines()]
    assert [r["captions"] for r in recs] == [[[0, 0, 122, 18]], []]
    assert recs[0]["found"] and (tmp_path / "out" / "cap_overlay.png").is_file()
    assert "captions" in run("detect", "--help").stdout
    # --ignore: the region left out (clipped to the image), listed in the JSON
    proc = run("detect", "rect:80,50", tmp_path / "plain.png", "--json", "--ignore",
               "140,90,240,160", "--ignore", "300,200,400,300")
    rec = json.loads(proc.stdout)
    assert proc.returncode == 1 and rec["ignored"] == [[140, 90, 240, 160], [300, 200, 320, 240]]
    # a curve search says it too (a review found its JSON crashing on "parts")
    proc = run("detect", "curve:8", tmp_path / "plain.png", "--json", "--ignore", "0,0,50,50")
    assert json.loads(proc.stdout)["ignored"] == [[0, 0, 50, 50]], proc.stderr
    # a box clipped to 1 px (a review found a crash)
    proc = run("detect", "rect:80,50", tmp_path / "plain.png", "--ignore", "319,0,400,50")
    assert proc.returncode == 0, proc.stderr
    for bad in ("1,2,3", "5,0,2,10", "a,b,c,d", "0,0,inf,5"):
        proc = run("detect", "rect:80,50", tmp_path / "plain.png", "--ignore", bad)
        assert_one_error_line(proc, "--ignore", bad)


def test_several_patterns_say_which_found_nothing(tmp_path):
    """Several patterns, one of them not in the image: the table says
    "not found: NAME" with its best declined candidate (a user trial found
    it silent), JSON "not_found" lists it; the image was found (exit 0)."""
    img = np.full((200, 260), 80, np.uint8)
    cv2.rectangle(img, (70, 60), (190, 140), 170, -1)
    cv2.imwrite(str(tmp_path / "r.png"), img)
    proc = run("detect", "box=rect:120,80+disc=circle:20", tmp_path / "r.png")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert "  not found: disc" in lines
    after = lines[lines.index("  not found: disc") + 1]
    assert after.startswith("  best candidate, not reported: disc: x "), after
    rec = json.loads(run("detect", "box=rect:120,80+disc=circle:20", tmp_path / "r.png",
                         "--json").stdout)
    assert rec["found"] and rec["not_found"] == ["disc"]
    assert list(rec["best_declined_by_pattern"]) == ["disc"]
    assert rec["best_declined_by_pattern"]["disc"]["pattern"] == "disc"
    one = json.loads(run("detect", "rect:120,80", tmp_path / "r.png", "--json").stdout)
    assert "not_found" not in one and "best_declined_by_pattern" not in one
    # CSV: the detections, then a row for the pattern that found nothing, with why
    rows = list(csv.DictReader(io.StringIO(run("detect", "box=rect:120,80+disc=circle:20",
                                                 tmp_path / "r.png", "--csv").stdout)))
    assert [(r["found"], r["pattern"]) for r in rows] == [("true", "box"), ("false", "disc")]
    assert rows[1]["declined"] and rows[1]["x"] == "" and rows[1]["rank"] == ""
    # a detection's row has its outline's bounding box, as JSON has (an archaeologist's wish)
    assert json.loads(rows[0]["box"]) == pytest.approx(rec["detections"][0]["box"])
    assert rows[1]["box"] == "" and list(rows[0])[-3:] == ["box", "segment", "stretches"]


def test_angles_near_360_are_printed_wrapped():
    """The table prints the rounded angle in [0, 360) (lines: [0, 180))."""
    from seahough.cli.detect import _detection_lines
    from seahough.geometry import format_angle

    assert format_angle(359.998) == "0.00" and format_angle(359.994) == "359.99"
    assert format_angle(359.96, 1) == "0.0" and format_angle(0.004) == "0.00"
    assert format_angle(179.999, 2, 180.0) == "0.00" and format_angle(-0.001) == "0.00"
    assert format_angle(360.0) == "0.00" and format_angle(725.5, 1) == "5.5"
    obj = types.SimpleNamespace(kind="object", x=10.0, y=20.0, scale=1.0, angle=359.998,
                                score=0.9, confidence=0.8, flags=[], nfa=3.21e-05)
    row = _detection_lines([obj])[1].split()
    assert row[4] == "0.00" and row[7] == "3.2e-05", row
    line = types.SimpleNamespace(kind="line", x=10.0, y=20.0, scale=1.0, angle=359.998,
                                 line_angle=179.9991, line_offset=-3.0, score=0.9,
                                 confidence=0.8, flags=["position_along_line_undetermined"],
                                 nfa=float("nan"))
    row = _detection_lines([line])[1].split()
    assert row[1] == "0.00" and row[8] == "-", row


def test_shape_pattern_and_line(tmp_path):
    """Shape specs: a rectangle drawn with OpenCV, and a rope as a line."""
    img = np.full((240, 320), 40, np.uint8)
    box = cv2.boxPoints(((200.0, 110.0), (90.0, 50.0), -30.0))
    cv2.fillPoly(img, [np.round(box).astype(np.int32)], 220)
    cv2.imwrite(str(tmp_path / "box.png"), img)
    rope, rt = sim.rope_scene(seed=2, source="procedural")
    cv2.imwrite(str(tmp_path / "rope.png"), rope)
    proc = run("detect", "rect:90,50", tmp_path / "box.png", "--json", "--max-results", 1)
    assert proc.returncode == 0, proc.stderr
    det = json.loads(proc.stdout)["detections"][0]
    assert (det["x"], det["y"]) == (pytest.approx(200, abs=1.5), pytest.approx(110, abs=1.5))
    assert det["scale"] == pytest.approx(1.0, abs=0.05)
    proc = run("detect", "line:200,8", tmp_path / "rope.png", "--json", "--angle-range", 0, 180,
               "--max-results", 1)
    assert proc.returncode == 0, proc.stderr
    det = json.loads(proc.stdout)["detections"][0]
    assert det["kind"] == "line"
    assert abs((det["line_angle"] - rt.line_angle + 90) % 180 - 90) < 2.0
    assert det["line_offset"] == pytest.approx(rt.line_offset, abs=3.0)


def test_detect_real_photo_crop(tmp_path):
    root = shared_data_dir()
    if root is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    src = root / "objects" / "suim" / "w_r_147_image.jpg"
    if not src.exists():
        pytest.skip(f"{src} is not present")
    img = cv2.imread(str(src))
    h, w = img.shape[:2]
    # the photo turned by 25 degrees and magnified 1.15 about its centre; the
    # pattern is a crop of the original photo
    m = cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), 25.0, 1.15)
    cv2.imwrite(str(tmp_path / "turned.png"),
                cv2.warpAffine(img, m, (w, h), borderMode=cv2.BORDER_REFLECT))
    x0, y0, cw, ch = int(0.45 * w), int(0.4 * h), w // 4, h // 4
    cv2.imwrite(str(tmp_path / "crop.png"), img[y0:y0 + ch, x0:x0 + cw])
    tx, ty = m @ [x0 + (cw - 1) / 2, y0 + (ch - 1) / 2, 1.0]
    proc = run("detect", tmp_path / "crop.png", tmp_path / "turned.png", "--json",
               "--scale-range", 0.8, 1.25)
    assert proc.returncode == 0, proc.stderr
    det = json.loads(proc.stdout)["detections"][0]
    assert np.hypot(det["x"] - tx, det["y"] - ty) < 2.0
    assert det["angle"] == pytest.approx(25.0, abs=1.0)
    assert det["scale"] == pytest.approx(1.15, rel=0.02)


# ---------------------------------------------------------------------- other commands
def test_version_and_help():
    proc = run("--version")
    assert proc.returncode == 0 and seahough.__version__ in proc.stdout
    proc = run("detect", "--help")
    assert proc.returncode == 0
    assert "Exit status" in proc.stdout and "rect:W,H" in proc.stdout
    proc = run("frobnicate")
    assert_one_error_line(proc, "frobnicate")


@pytest.mark.parametrize("kind", ["marker", "rope", "pair", "sequence", "negative"])
def test_simulate_writes_scenes_and_truth(tmp_path, kind):
    n = 3 if kind == "sequence" else 2
    proc = run("simulate", kind, "--out", tmp_path, "--n", n, "--seed", 4, "--water", "clear",
               "--procedural", "--size", 160, 120)
    assert proc.returncode == 0, proc.stderr
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert truth["kind"] == kind and truth["seed"] == 4
    items = truth["frames"] if kind == "sequence" else truth["scenes"]
    assert len(items) == n
    files = [it[k] for it in items for k in ("file", "previous", "current") if k in it]
    for f in files:
        im = cv2.imread(str(tmp_path / f))
        assert im is not None and im.shape[:2] == (120, 160)
    if kind == "marker":
        assert cv2.imread(str(tmp_path / truth["pattern"])) is not None
        s = items[0]
        assert np.asarray(s["matrix"]).shape == (2, 3)
        # the truth is the simulator's
        _, _, t = sim.marker_scene("board", (120, 160), water="clear", seed=4, source="procedural")
        assert s["x"] == pytest.approx(t.x) and s["angle"] == pytest.approx(t.angle)
    if kind == "rope":
        assert {"line_angle", "line_offset"} <= set(items[0])
    if kind == "pair":
        assert np.asarray(items[0]["motion"]).shape == (2, 3)
        # the turn as estimate_motion reports it, in [-180, 180)
        m = seahough.estimate_motion(tmp_path / items[0]["previous"],
                                     tmp_path / items[0]["current"])
        assert -180 <= items[0]["angle"] < 180 and m.angle == pytest.approx(items[0]["angle"],
                                                                               abs=0.5)
    if kind == "sequence":
        assert np.allclose(items[0]["matrix_from_first"], [[1, 0, 0], [0, 1, 0]])
        assert "motion_from_previous" in items[1]


def test_write_simulation_is_the_library_behind_the_command(tmp_path):
    """`seahough simulate` writes what seahough.sim.files.write_simulation
    writes; the function raises seahough errors, which the command prints as
    one line (exit status 2)."""
    from seahough.errors import ParameterError, SeahoughError, WriteError
    from seahough.sim.files import write_simulation

    args = dict(n=2, seed=4, water="clear", size=(160, 120), procedural=True)
    truth = write_simulation("rope", tmp_path / "lib", **args)
    proc = run("simulate", "rope", "--out", tmp_path / "cmd", "--n", 2, "--seed", 4, "--water",
               "clear", "--procedural", "--size", 160, 120, "--quiet")
    assert proc.returncode == 0, proc.stderr
    text = (tmp_path / "cmd" / "truth.json").read_text()
    assert text == (tmp_path / "lib" / "truth.json").read_text() and json.loads(text) == truth
    for name in ("rope_000.png", "rope_001.png"):
        assert (tmp_path / "cmd" / name).read_bytes() == (tmp_path / "lib" / name).read_bytes()
    with pytest.raises(ParameterError, match="kind='blob'"):
        write_simulation("blob", tmp_path / "x")
    with pytest.raises(ParameterError, match="water='murky'"):
        write_simulation("marker", tmp_path / "x", water="murky")
    # a folder where a file should go
    (tmp_path / "blocked" / "marker_000.png").mkdir(parents=True)
    (tmp_path / "blocked2" / "truth.json").mkdir(parents=True)
    with pytest.raises(WriteError, match="marker_000.png: cannot write the image") as info:
        write_simulation("marker", tmp_path / "blocked", **args)
    assert isinstance(info.value, OSError) and isinstance(info.value, SeahoughError)
    with pytest.raises(WriteError, match="truth.json"):
        write_simulation("marker", tmp_path / "blocked2", **args)
    for sub, needle in (("blocked", "marker_000.png: cannot write the image"),
                        ("blocked2", "truth.json: ")):
        proc = run("simulate", "marker", "--out", tmp_path / sub, "--procedural", "--size", 160,
                   120)
        assert_one_error_line(proc, str(tmp_path / sub / needle))
        assert proc.stdout == ""


def test_odometry_command_calls_run_odometry(tmp_path, monkeypatch, capsys):
    """The command's wiring to seahough.motion.odometry.run_odometry (a stand-in here)."""
    from seahough import cli

    calls = {}

    def fake_run_odometry(frames, out_dir, **kw):
        calls.update(frames=frames, out_dir=out_dir, **kw)
        rows = [{"index": i, "file": f"f{i}.png", "time": float(i), "x": 3.0 * i, "y": 4.0 * i,
                 "heading": 0.0, "scale": 1.0, "confidence": 0.9,
                 "flags": ["lost"] if i == 2 else []} for i in range(4)]
        return types.SimpleNamespace(rows=rows, summary={}, csv_path=Path(out_dir) / "track.csv",
                                     json_path=None, mosaic_path=None, trajectory_path=None)

    fake = types.ModuleType("seahough.motion.odometry")
    fake.run_odometry = fake_run_odometry
    monkeypatch.setitem(sys.modules, "seahough.motion.odometry", fake)
    (tmp_path / "frames").mkdir()
    with pytest.raises(SystemExit) as ex:
        cli.main(["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "o"),
                  "--altitude", "2.5", "--focal-px", "800", "--scale-range", "0.95", "1.05",
                  "--no-mosaic", "--quiet", "--json"])
    assert ex.value.code == 1            # a flagged frame
    assert calls["frames"] == [str(tmp_path / "frames")]
    assert calls["altitude"] == 2.5 and calls["focal_px"] == 800
    assert calls["metres_per_pixel"] is None
    assert calls["scale_range"] == (0.95, 1.05) and calls["angle_range"] == (-20.0, 20.0)
    assert calls["mosaic"] is False and calls["progress"] is False and calls["resume"] is False
    summary = json.loads(capsys.readouterr().out)
    assert summary["frames"] == 4 and summary["flagged_pairs"] == 1
    assert summary["distance"] == pytest.approx(15.0) and summary["unit"] == "m"
    with pytest.raises(SystemExit) as ex:
        cli.main(["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "o"),
                  "--metres-per-pixel", "0.01", "--altitude", "2"])
    assert ex.value.code == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert calls["fps"] is None and "config" not in calls      # (the run's own defaults)
    # --fps and --equalize (a survey engineer's trial: no way to time frames whose names
    # carry no time; the cure the flags' table gives for dark frames was Python only)
    with pytest.raises(SystemExit):
        cli.main(["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "o"),
                  "--fps", "5", "--equalize", "--bit-depth", "12", "--quiet"])
    assert calls["fps"] == 5.0
    assert calls["config"].equalize is True and calls["config"].bit_depth == 12
    for bad in (["--fps", "0"], ["--fps", "nan"]):
        with pytest.raises(SystemExit) as ex:
            cli.main(["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "o"), *bad])
        assert ex.value.code == 2 and "--fps" in capsys.readouterr().err


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM"])
def test_ctrl_c_inside_a_kernel_still_says_what_odometry_kept(tmp_path, monkeypatch, capsys,
                                                              signal_name):
    """Ctrl-C that lands inside a compiled kernel surfaces as a SystemError
    caused by the KeyboardInterrupt: the command still says how many frames
    were kept and that --resume goes on (a trial saw a bare "interrupted").
    SIGTERM's own line is kept; a SystemError of another cause is a bug."""
    from seahough import cli
    from seahough.cli import _Terminated

    out = tmp_path / "o"

    def fake_run_odometry(frames, out_dir, **kw):
        Path(out_dir).mkdir()
        (Path(out_dir) / "odometry.csv").write_text("index,file\n0,a.png\n1,b.png\n2,c.png\n")
        try:
            raise KeyboardInterrupt() if signal_name == "SIGINT" else _Terminated()
        except BaseException as ki:
            raise SystemError("returned a result with an exception set") from ki

    fake = types.ModuleType("seahough.motion.odometry")
    fake.run_odometry = fake_run_odometry
    monkeypatch.setitem(sys.modules, "seahough.motion.odometry", fake)
    (tmp_path / "frames").mkdir()
    with pytest.raises(SystemExit) as ex:
        cli.main(["odometry", str(tmp_path / "frames"), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    if signal_name == "SIGINT":
        assert ex.value.code == 130
        assert err.strip() == (f"seahough: error: interrupted: 3 frames kept in {out}/"
                               "odometry.csv; the same command with --resume goes on from "
                               "there"), err
    else:
        assert ex.value.code == 143 and "terminated (SIGTERM)" in err and "--resume" in err
    fake.run_odometry = lambda *a, **k: (_ for _ in ()).throw(SystemError("a bug"))
    with pytest.raises(SystemError):
        cli.main(["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "p"),
                  "--quiet"])


@pytest.mark.parametrize("old_keys", [False, True])
def test_odometry_command_prints_the_canonical_summary_keys(tmp_path, monkeypatch, capsys,
                                                            old_keys):
    """distance: path_length_m when not None, else path_length_px; time per
    frame: mean_ms_per_frame; keys the summary once had for the command
    (distance, unit, ms_per_frame) are not read."""
    from seahough import cli

    summary = {"frames": 3, "flagged_pairs": 0, "path_length_px": 250.0, "path_length_m": 2.5,
               "mean_ms_per_frame": 12.0}
    if old_keys:
        summary.update(distance=999.0, unit="furlongs", ms_per_frame=999.0)

    def fake_run_odometry(frames, out_dir, **kw):
        rows = [{"index": i, "file": f"f{i}.png", "x": 0.0, "y": 0.0, "flags": []}
                for i in range(3)]
        return types.SimpleNamespace(rows=rows, summary=summary, csv_path=None, json_path=None,
                                     mosaic_path=None, trajectory_path=None)

    fake = types.ModuleType("seahough.motion.odometry")
    fake.run_odometry = fake_run_odometry
    monkeypatch.setitem(sys.modules, "seahough.motion.odometry", fake)
    (tmp_path / "frames").mkdir()
    argv = ["odometry", str(tmp_path / "frames"), "--out", str(tmp_path / "o"), "--quiet"]
    for path_length_m, want in ((2.5, "distance: 2.50 m"), (None, "distance: 250.00 px")):
        summary["path_length_m"] = path_length_m
        with pytest.raises(SystemExit) as ex:
            cli.main(argv)
        assert ex.value.code == 0
        assert capsys.readouterr().out.splitlines() == [
            f"frames: 3   flagged frames: 0   {want}   time per frame: 12 ms"]
    with pytest.raises(SystemExit):
        cli.main(argv + ["--json"])
    got = json.loads(capsys.readouterr().out)
    assert (got["distance"], got["unit"], got["time_per_frame_ms"]) == (250.0, "px", 12.0)


def test_odometry_on_simulated_sequence(tmp_path):
    proc = run("simulate", "sequence", "--out", tmp_path / "seq", "--n", 5, "--procedural",
               "--seed", 2)
    assert proc.returncode == 0, proc.stderr
    proc = run("odometry", tmp_path / "seq", "--out", tmp_path / "odo", "--quiet", "--json")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["frames"] == 5
    assert summary["csv"] and Path(summary["csv"]).exists()


def test_simulate_progress_bar_and_quiet(tmp_path):
    """Like detect: a progress bar on stderr only when it is a terminal and
    there are several scenes, and --quiet leaves stderr empty."""
    args = ("simulate", "marker", "--n", 3, "--procedural", "--size", 160, 120, "--seed", 1)
    rc, out, tty = run_on_terminal(*args, "--out", tmp_path / "a")
    assert rc == 0, tty
    assert "simulate: " in tty and "/3 [" in tty, tty            # the bar was drawn
    assert out.splitlines()[0] == f"wrote 3 scenes and {tmp_path / 'a' / 'truth.json'}"
    rc, out, tty = run_on_terminal(*args, "--out", tmp_path / "b", "--quiet")
    assert rc == 0 and tty == "", tty
    assert out.splitlines() == [f"wrote 3 scenes and {tmp_path / 'b' / 'truth.json'}"]
    proc = run(*args, "--out", tmp_path / "c")                  # stderr is a pipe: no bar
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    proc = run(*args, "--out", tmp_path / "d", "--quiet")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    # the same scenes, bar or not
    for sub in ("b", "c", "d"):
        assert (tmp_path / sub / "truth.json").read_text() == \
            (tmp_path / "a" / "truth.json").read_text()
    rc, out, tty = run_on_terminal("simulate", "sequence", "--n", 4, "--procedural",
                                   "--out", tmp_path / "s")
    assert rc == 0 and "/4 [" in tty, tty


def test_simulate_from_a_photo_of_ones_own(tmp_path):
    photo = tmp_path / "floor.png"
    cv2.imwrite(str(photo), sim.seabed((240, 320), seed=3))
    # a long turn over a small photo: the note says it is magnified, -q keeps it quiet
    args = ("simulate", "sequence", "--n", 60, "--path", "turn", "--size", 160, 120,
            "--photo", photo)
    proc = run(*args, "--out", tmp_path / "a")
    assert proc.returncode == 0, proc.stderr
    assert "note: the photo (320x240) is magnified" in proc.stderr, proc.stderr
    proc = run(*args, "--out", tmp_path / "b", "-q")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    truth = json.loads((tmp_path / "b" / "truth.json").read_text())
    assert truth["source"] == str(photo.resolve())
    # the views are of that photo: the first frame is where the simulator puts it
    frames, _ = sim.sequence(cv2.imread(str(photo)), n_frames=60, frame_size=(120, 160),
                             path="turn", water="moderate", seed=0)
    assert np.array_equal(cv2.imread(str(tmp_path / "b" / "frame_000.png")), frames[0])
    proc = run("simulate", "pair", "--out", tmp_path / "c", "--photo", photo, "-q")
    assert proc.returncode == 0, proc.stderr
    # a photo that cannot be read, or given with --procedural: one line, nothing written
    proc = run("simulate", "pair", "--out", tmp_path / "d", "--photo", tmp_path / "none.jpg")
    assert_one_error_line(proc, "none.jpg: no such file")
    proc = run("simulate", "pair", "--out", tmp_path / "e", "--photo", photo, "--procedural")
    assert_one_error_line(proc, "photo and procedural")
    # an option of another kind of scene is refused, not ignored
    assert_one_error_line(run("simulate", "marker", "--path", "turn", "--out", tmp_path / "g"),
                          "--path applies to sequence scenes, not marker")
    cv2.imwrite(str(tmp_path / "black.png"), np.zeros((240, 320), np.uint8))
    proc = run("simulate", "pair", "--out", tmp_path / "e", "--photo", tmp_path / "black.png")
    assert_one_error_line(proc, "black.png: a flat picture (grey levels 0-0)")
    assert not (tmp_path / "d").exists() and not (tmp_path / "e").exists()
    # a 12-bit camera's photo in a 16-bit file: stretched by its bits, not darkened by 257
    cv2.imwrite(str(tmp_path / "floor12.png"),
                (sim.seabed((240, 320), seed=3).astype(np.uint16) * 16))
    proc = run("simulate", "negative", "--out", tmp_path / "f", "--photo",
               tmp_path / "floor12.png", "--water", "none", "-q")
    assert proc.returncode == 0, proc.stderr
    assert cv2.imread(str(tmp_path / "f" / "negative_000.png")).mean() > 60


@pytest.fixture(scope="module")
def sequence_dir(tmp_path_factory):
    """A short simulated sequence, written by `seahough simulate`."""
    d = tmp_path_factory.mktemp("sequence") / "seq"
    proc = run("simulate", "sequence", "--out", d, "--n", 8, "--procedural", "--seed", 5,
               "--quiet")
    assert proc.returncode == 0, proc.stderr
    return d


def test_odometry_progress_bar_like_detect(sequence_dir, tmp_path):
    """On a terminal the bar is drawn, --quiet removes it; into a pipe or a
    log file it is not drawn (as detect's)."""
    args = ("odometry", sequence_dir, "--no-mosaic", "--json")
    rc, out, tty = run_on_terminal(*args, "--out", tmp_path / "a")
    assert rc == 0, tty
    assert "odometry" in tty and "/8 [" in tty, tty
    rc, out, tty = run_on_terminal(*args, "--out", tmp_path / "b", "--quiet")
    assert rc == 0 and tty == "", tty
    proc = run(*args, "--out", tmp_path / "c")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert json.loads(proc.stdout)["frames"] == 8


def test_odometry_resume_after_a_killed_run(sequence_dir, tmp_path):
    """--resume continues the CSV a killed run left (a header, a few rows
    and a row cut short) to the result of an uninterrupted run."""
    proc = run("odometry", sequence_dir, "--out", tmp_path / "full", "--quiet", "--no-mosaic",
               "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["summary"]["resumed_rows"] == 0
    lines = (tmp_path / "full" / "odometry.csv").read_text().splitlines(keepends=True)
    assert len(lines) == 9                                       # header + 8 frames
    killed = tmp_path / "killed"
    killed.mkdir()
    (killed / "odometry.csv").write_text("".join(lines[:4]) + lines[4][: len(lines[4]) // 2])
    proc = run("odometry", sequence_dir, "--out", killed, "--quiet", "--no-mosaic", "--json",
               "--resume")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["frames"] == 8
    assert summary["summary"]["resumed_rows"] == 3              # the cut row is measured again
    assert csv_without_timing(killed / "odometry.csv") == \
        csv_without_timing(tmp_path / "full" / "odometry.csv")


def test_odometry_says_when_it_replaces_an_earlier_run(sequence_dir, tmp_path):
    """Without --resume a run replaces the one in --out: said in one line
    (a forgotten flag cost an interrupted survey's rows, unsaid)."""
    killed = tmp_path / "o"
    killed.mkdir()
    full = tmp_path / "full"
    assert run("odometry", sequence_dir, "--out", full, "--quiet", "--no-mosaic").returncode == 0
    lines = (full / "odometry.csv").read_text().splitlines(keepends=True)
    (killed / "odometry.csv").write_text("".join(lines[:4]))          # 3 rows kept
    proc = run("odometry", sequence_dir, "--out", killed, "--no-mosaic")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == [f"seahough: note: replacing the run of 3 frames in "
                                        f"{killed} (--resume would go on with it)"], proc.stderr
    proc = run("odometry", sequence_dir, "--out", tmp_path / "new", "--no-mosaic")
    assert "replacing" not in proc.stderr                          # (nothing there before)


def test_demo_end_to_end(tmp_path):
    from seahough.viz import detections_size

    proc = run("demo", "--out", tmp_path / "demo", "--quiet", timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stderr == "", proc.stderr
    out = tmp_path / "demo"
    overlay = detections_size((480, 640))
    pattern_h, pattern_w = sim.marker("board")[0].shape[:2]
    want = {"marker_scene.png": (640, 480), "marker_pattern.png": (pattern_w, pattern_h),
            "marker_overlay.png": overlay, "marker_accumulator.png": (1300, 560),
            "marker_edges.png": (1300, 560), "rope_scene.png": (640, 480),
            "rope_overlay.png": overlay, "rope_accumulator.png": (1300, 560),
            **{f"sequence/frame_{i:03d}.png": (320, 240) for i in range(8)}}
    want.update({"trajectory.png": (900, 800), "odometry/trajectory.png": (900, 800),
                 "odometry/mosaic.png": None})
    # every picture the demo writes is checked: a new one must be added here
    written = sorted(p.relative_to(out).as_posix() for p in out.rglob("*.png"))
    assert written == sorted(want)
    for name, size in want.items():
        w, h = png_size(out / name)
        if size is None:                 # the mosaic: the frames' union, turned and shifted
            assert 320 <= w <= 4 * 320 and 240 <= h <= 4 * 240, (name, w, h)
        else:
            assert (w, h) == tuple(size), name
        im = cv2.imread(str(out / name))
        assert im.std() > 5, f"{name} is (almost) blank"
    assert "marker position" in proc.stdout and "rope offset" in proc.stdout
    assert "drift" in proc.stdout
    # without --quiet, the list of pictures names every file written (and the frames' range)
    proc = run("demo", "--out", tmp_path / "demo2", timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    listed = proc.stdout.split("pictures in ", 1)[1].split("\n", 1)[0].split(": ", 1)[1]
    listed = set(listed.split(", "))
    for name in want:
        if not name.startswith("sequence/"):
            assert name in listed, name


def test_detect_searches_a_painted_pattern_in_colour_unless_told_grey(tmp_path):
    """An orange board on sand of the same grey level: its pattern image is
    painted, so `seahough detect` finds it by its colour edges without
    --colour; --grey searches grey levels, where the board has no edge."""
    sand, orange = (90, 140, 120), (40, 93, 230)          # BGR, both grey 128
    pat = np.empty((80, 110, 3), np.uint8)
    pat[:] = sand
    pat[20:60, 25:85] = orange
    scene = np.empty((360, 480, 3), np.uint8)
    scene[:] = sand
    box = cv2.boxPoints(((250.0, 170.0), (120.0, 80.0), 20.0))    # the board at 2x, turned
    cv2.fillPoly(scene, [np.round(box).astype(np.int32)], orange)
    cv2.imwrite(str(tmp_path / "board.png"), pat)
    cv2.imwrite(str(tmp_path / "scene.png"), scene)
    args = ("detect", tmp_path / "board.png", tmp_path / "scene.png", "--json",
            "--scale-range", 1.5, 2.5)
    rec = json.loads(run(*args).stdout)
    assert rec["found"] is True
    best = rec["detections"][0]
    assert np.hypot(best["x"] - 250.0, best["y"] - 170.0) < 2.0 and abs(best["scale"] - 2) < 0.05
    grey = run(*args, "--grey")        # (in grey levels the pattern has no edge at all)
    assert grey.returncode == 2 and "too few edges" in grey.stderr, grey.stderr


def test_odometry_of_one_frame_says_there_is_nothing_to_measure(tmp_path):
    """One frame: the run writes its one row and says, on stderr, that
    there was no motion to measure (it used to finish silently)."""
    frames = tmp_path / "frames"
    frames.mkdir()
    img, _ = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    cv2.imwrite(str(frames / "f0.png"), img)
    proc = run("odometry", frames, "--out", tmp_path / "o", "--no-mosaic", "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["frames"] == 1
    assert "1 frame: no motion to measure" in proc.stderr


def test_odometry_says_when_the_first_frame_may_be_the_odd_one(tmp_path):
    frames, _ = sim.sequence(n_frames=4, frame_size=(240, 320), seed=1, source="procedural")
    cv2.imwrite(str(tmp_path / "f0.png"), cv2.resize(frames[0], (640, 480)))
    for i in range(1, 4):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), frames[i])
    proc = run("odometry", tmp_path, "--out", tmp_path / "out", "--no-mosaic", "-q")
    assert proc.returncode == 1
    assert "note: every frame after the first has another size than the first" in proc.stdout


def test_not_found_shows_the_best_candidate_and_why(tmp_path):
    """Nothing reported: the best candidate that was not is printed under the
    image's line with its pose, score and reason (JSON: best_declined), so
    that a user sees which setting stopped it; -q leaves the line out; a
    found image has best_declined null."""
    img = np.full((200, 260), 80, np.uint8)
    cv2.rectangle(img, (70, 60), (190, 140), 170, -1)
    cv2.imwrite(str(tmp_path / "r.png"), img)
    proc = run("detect", "rect:120,80", tmp_path / "r.png", "--min-score", 0.99)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 2 and "not found" in lines[0]
    assert lines[1].startswith("  best candidate, not reported: x "), lines[1]
    assert "under min_score 0.99" in lines[1] or "the least that could win" in lines[1], lines[1]
    assert lines[1].endswith("(option --min-score)"), lines[1]        # the setting, named
    rec = json.loads(run("detect", "rect:120,80", tmp_path / "r.png", "--min-score", 0.99,
                         "--json").stdout)
    best = rec["best_declined"]
    assert rec["found"] is False and best["declined"] and 0 < best["score"] < 0.99
    assert set(best) == {"pattern", "x", "y", "scale", "angle", "score", "nfa", "declined"}
    quiet = run("detect", "rect:120,80", tmp_path / "r.png", "--min-score", 0.99, "-q")
    assert len(quiet.stdout.splitlines()) == 1
    found = json.loads(run("detect", "rect:120,80", tmp_path / "r.png", "--json").stdout)
    assert found["found"] is True and found["best_declined"] is None
    # several patterns: the line names the candidate's pattern
    proc = run("detect", "a=rect:120,80@min-score=0.99+b=circle:30@min-score=0.99",
               tmp_path / "r.png")
    assert proc.returncode == 1
    # ... one line for each (a RoboSub trial saw only one of two patterns' reasons), whose
    # hint also names the pattern's own setting (the option sets every pattern's)
    lines = proc.stdout.splitlines()
    assert [ln[:34] for ln in lines[1:]] == ["  best candidate, not reported: a:",
                                             "  best candidate, not reported: b:"], lines
    assert lines[1].endswith("(option --min-score; for a alone: its @min-score=...)"), lines[1]
    rec = json.loads(run("detect", "a=rect:120,80@min-score=0.99+b=circle:30@min-score=0.99",
                         tmp_path / "r.png", "--json").stdout)
    assert rec["not_found"] == ["a", "b"] and set(rec["best_declined_by_pattern"]) == {"a", "b"}
    rows = list(csv.DictReader(io.StringIO(run(
        "detect", "a=rect:120,80@min-score=0.99+b=circle:30@min-score=0.99", tmp_path / "r.png",
        "--csv").stdout)))
    assert [(r["found"], r["pattern"]) for r in rows] == [("false", "a"), ("false", "b")]
    assert rows[0]["declined"].endswith("(option --min-score; for a alone: its @min-score=...)")
    # a scale outside the searched range names the option that sets it
    from types import SimpleNamespace as C
    from seahough.cli._records import _option_hint
    assert _option_hint(C(score=0.8, declined="scale 0.338 outside 0.4-2.5 (the searched "
                          "range and its slack)", pattern="")) == " (option --scale-range)"


def test_detect_takes_a_folder_for_its_images(tmp_path):
    img = np.full((120, 160), 60, np.uint8)
    cv2.rectangle(img, (50, 40), (110, 80), 200, -1)
    (tmp_path / "dive").mkdir()
    for name in ("f10.png", "f2.png"):
        cv2.imwrite(str(tmp_path / "dive" / name), img)
    (tmp_path / "dive" / "notes.txt").write_text("not an image")
    proc = run("detect", "rect:60,40", tmp_path / "dive", "--json")
    assert proc.returncode == 0, proc.stderr
    files = [Path(json.loads(line)["file"]).name for line in proc.stdout.splitlines()]
    assert files == ["f2.png", "f10.png"]
    (tmp_path / "empty").mkdir()
    proc = run("detect", "rect:60,40", tmp_path / "empty")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().endswith("in this folder") and "empty" in proc.stderr
    # a folder or video that cannot be listed: its problem line, the others' results
    (tmp_path / "broken.mp4").write_bytes(b"not a video")
    proc = run("detect", "rect:60,40", tmp_path / "empty", tmp_path / "broken.mp4",
               tmp_path / "dive" / "f2.png")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert [line.split(": ")[2] for line in proc.stderr.splitlines()] == [
        str(tmp_path / "empty"), str(tmp_path / "broken.mp4")]
    assert proc.stdout.startswith(str(tmp_path / "dive" / "f2.png") + "  160x120  1 found")


def test_detect_reads_a_video_frame_by_frame(tmp_path):
    """A video among the IMAGEs: each frame searched, named VIDEO#N, in
    order (also with several workers), its pictures VIDEO-STEM_0000N."""
    path = moving_rectangle_video(tmp_path / "dive.mp4", 4)
    for workers in (1, 2):
        proc = run("detect", "rect:60,40", path, "--json", "-n", 1, "--workers", workers)
        assert proc.returncode == 0, proc.stderr
        recs = [json.loads(line) for line in proc.stdout.splitlines()]
        assert [r["file"] for r in recs] == [f"{path}#{i}" for i in range(4)]
        assert [r["frame"] for r in recs] == [0, 1, 2, 3]
        xs = [r["detections"][0]["x"] for r in recs]
        assert np.allclose(np.diff(xs), 10.0, atol=1.0), xs
    rows = list(csv.DictReader(io.StringIO(run("detect", "rect:60,40", path, "--csv", "-n", 1,
                                               "-q").stdout)))
    assert [r["frame"] for r in rows] == ["0", "1", "2", "3"]
    proc = run("detect", "rect:60,40", path, "--out", tmp_path / "pics", "--pictures", "overlay")
    assert sorted(p.name for p in (tmp_path / "pics").iterdir()) == [
        f"dive_{i:05d}_overlay.png" for i in range(4)]


def test_a_video_frame_by_name_in_odometry_and_names_that_are_no_frame(tmp_path):
    """A video analyst's trial: ``odometry "dive.mp4#5" "dive.mp4#6"`` was "no
    such file or folder" (detect and run_odometry took them); "dive.mp4#3-5"
    and "#03" were "no such file" though the video is there; --fps beside a
    video changed nothing, unsaid."""
    path = moving_rectangle_video(tmp_path / "dive.mp4", 6)
    proc = run("odometry", f"{path}#2", f"{path}#3", f"{path}#4", "--out", tmp_path / "o",
               "--no-mosaic", "-q", "--fps", 20)
    assert proc.returncode in (0, 1), proc.stderr
    rows = list(csv.DictReader((tmp_path / "o" / "odometry.csv").open()))
    assert [r["file"] for r in rows] == [f"{path}#{k}" for k in (2, 3, 4)]
    assert [float(r["time"]) for r in rows] == [0.4, 0.6, 0.8]     # (its own 5 fps)
    assert proc.stderr == ""                                        # (-q: no note)
    proc = run("odometry", path, "--out", tmp_path / "o2", "--no-mosaic", "--fps", 20)
    assert f"note: --fps 20 is for frames without a time: the frames of {path} take its own " \
        "rate (5 fps)" in proc.stderr, proc.stderr
    for cmd in (["odometry", "--out", tmp_path / "o3"], ["detect", "rect:60,40"]):
        for bad, example in (("3-5", 12), ("03", 3), ("abc", 12)):
            proc = run(*cmd, f"{path}#{bad}", f"{path}#1")
            assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
            assert proc.stderr.strip() == (
                f"seahough: error: {path}#{bad}: '{bad}' is no frame number (a video's frame is "
                f"named {path}#{example}, counted from 0; every frame: {path})"), proc.stderr


def test_frames_too_small_for_motion_are_said_once(tmp_path):
    """A video analyst's trial: a video of 48x40 frames gave one "unreadable:
    too small" line a frame and wrote a run of nothing. A video says it once,
    before the run (its header gives the size), and writes nothing; a folder
    whose every frame is too small says it once too."""
    path = moving_rectangle_video(tmp_path / "tiny.mp4", 6, size=(48, 40), start=(2, 2), step=1)
    proc = run("odometry", path, "--out", tmp_path / "o")
    assert proc.returncode == 2 and not (tmp_path / "o").exists()
    assert proc.stderr.strip() == (f"seahough: error: {path}: its frames are 48x40, too small to "
                                   "measure motion (each side must be at least 64 px)"), proc.stderr
    with pytest.raises(seahough.ImageSizeError, match="tiny.mp4: its frames are 48x40"):
        seahough.run_odometry(path, tmp_path / "o", progress=False)
    folder = tmp_path / "small"
    folder.mkdir()
    for k in range(5):
        cv2.imwrite(str(folder / f"f{k}.png"), np.full((40, 50), 30 * k, np.uint8))
    proc = run("odometry", folder, "--out", tmp_path / "o2", "--no-mosaic")
    assert proc.returncode == 1, proc.stderr
    flagged = [line for line in proc.stdout.splitlines() if "flagged:" in line]
    assert flagged == ["  flagged: every frame (5): unreadable: frame: 50x40 is too small to "
                       "measure motion (each side must be at least 64 px)"], proc.stdout


def test_odometry_notes_a_scene_whose_scale_changes_much(tmp_path):
    """A camera that looks ahead (or an altitude that changes much) makes the
    scene's scale drift: a user's forward-looking pool video reached 1.8x
    with nothing said. The summary keeps the scales seen; the command notes
    a change over 1.4x; a steady survey gets no note."""
    rng = np.random.default_rng(8)
    big = cv2.GaussianBlur(rng.uniform(0, 255, (900, 1200)).astype(np.float32), (0, 0), 3)
    big = np.clip(128 + 4 * (big - big.mean()), 0, 255).astype(np.uint8)
    for name, zoom, step in (("zoom", 1.08, 0), ("steady", 1.0, 12)):
        d = tmp_path / name
        d.mkdir()
        for k in range(8):
            s = zoom ** k
            m = np.array([[s, 0, 160 - s * (600 + step * k)], [0, s, 120 - s * 450]])
            cv2.imwrite(str(d / f"f{k}.png"), cv2.warpAffine(big, m, (320, 240)))
        proc = run("odometry", d, "--out", tmp_path / f"o_{name}", "--no-mosaic", "--quiet")
        summary = json.loads((tmp_path / f"o_{name}" / "summary.json").read_text())
        seen = summary["scale_seen"]
        if name == "zoom":
            assert seen["max"] > 1.5 and seen["max_frame"] == 7, seen
            assert "note: the scene's scale changed" in proc.stdout, proc.stdout
        else:
            assert 0.97 < seen["min"] <= seen["max"] < 1.03, seen
            assert "scale changed" not in proc.stdout, proc.stdout


def test_quiet_detect_leaves_out_the_folder_notes(tmp_path):
    """-q prints the results only (a trial saw "note: FOLDER: not read: 1 video
    file" with -q); without it the note is said."""
    folder = tmp_path / "dive"
    folder.mkdir()
    img = np.full((120, 160), 40, np.uint8)
    img[40:80, 50:110] = 200
    cv2.imwrite(str(folder / "a.png"), img)
    (folder / "clip.mp4").write_bytes(b"")
    quiet = run("detect", "rect:60,40", folder, "-q")
    assert quiet.returncode == 0 and quiet.stderr == "", quiet.stderr
    loud = run("detect", "rect:60,40", folder)
    assert "not read: 1 video file (.mp4)" in loud.stderr, loud.stderr


def test_colour_choices_are_said_and_colour_searches_either_polarity(tmp_path, capsys):
    """A colour trial: an orange cross on a grey canvas (15 % of it coloured, a
    painted marker is 20 %) was searched by its grey edges without a word, its
    answers on a yellow L; --colour alone kept the image's polarity (0 of 12
    found, 12 with --polarity either); --polarity was ignored for a painted
    pattern without a word."""
    from seahough.cli import main
    from seahough.cli._common import make_detector

    canvas = np.full((160, 160, 3), 128, np.uint8)
    canvas[65:95, 40:120] = (0, 120, 255)          # an orange cross: 15 % of the canvas
    canvas[40:120, 65:95] = (0, 120, 255)
    cross = tmp_path / "cross.png"
    cv2.imwrite(str(cross), canvas)
    scene = tmp_path / "scene.png"
    cv2.imwrite(str(scene), np.full((240, 320, 3), 90, np.uint8))
    notes = lambda err: [ln for ln in err.splitlines() if ln.startswith("note:")]  # noqa: E731
    for extra, said in (([], 1), (["-q"], 0), (["--colour"], 0), (["--grey"], 0)):
        with pytest.raises(SystemExit):
            main(["detect", str(cross), str(scene), *extra])
        got = notes(capsys.readouterr().err)
        assert len(got) == said, (extra, got)
        if said:
            assert "searched by its grey edges: 15% of it is coloured" in got[0], got
    assert make_detector(str(cross), (0.5, 2), (0, 360), 5, 0.5, 0.0, None, None, False,
                         None, None, colour=True).pattern.polarity == "either"
    assert make_detector(str(cross), (0.5, 2), (0, 360), 5, 0.5, 0.0, None, None, False,
                         "same", None, colour=True).pattern.polarity == "bright"
    painted = tmp_path / "board.png"
    board = np.full((80, 120, 3), (0, 120, 255), np.uint8)
    board[20:60, 30:90] = 255
    cv2.imwrite(str(painted), board)
    with pytest.raises(SystemExit):
        main(["detect", str(painted), str(scene), "--polarity", "dark"])
    got = notes(capsys.readouterr().err)
    assert len(got) == 1 and "--polarity dark applies with --grey" in got[0], got


def test_the_edges_picture_says_when_the_edges_came_from_colour(tmp_path, monkeypatch, capsys):
    """A colour trial read the edges picture's grey working image as what was
    searched: its title says when the edges came from the colour channels."""
    from seahough import viz
    from seahough.cli import main

    titles = []
    monkeypatch.setattr(viz, "plot_edges", lambda img, feats, path, title: titles.append(title))
    board = np.full((80, 120, 3), (0, 120, 255), np.uint8)      # a painted board
    board[20:60, 30:90] = 255
    cv2.imwrite(str(tmp_path / "board.png"), board)
    scene = np.full((240, 320, 3), (90, 110, 60), np.uint8)
    scene[80:160, 100:220] = board
    cv2.imwrite(str(tmp_path / "scene.png"), scene)
    cv2.imwrite(str(tmp_path / "grey.png"), cv2.cvtColor(scene, cv2.COLOR_BGR2GRAY))
    for img in ("scene.png", "grey.png"):
        with pytest.raises(SystemExit):
            main(["detect", str(tmp_path / "board.png"), str(tmp_path / img), "-q",
                  "-o", str(tmp_path / "o"), "--pictures", "edges"])
    capsys.readouterr()
    assert titles[0].endswith("(edges from the colour channels; left, its grey levels)")
    assert titles[1] == "grey.png: what the detector sees"


def test_an_overlay_says_what_was_not_found_and_keeps_each_patterns_colour(tmp_path,
                                                                         monkeypatch):
    """A trial of the pictures: a not-found overlay said only "not found" (the
    table gave the best candidate and why); a multi-pattern overlay never named
    the patterns that found nothing; and a pattern's colour changed with the
    image (by rank when only one pattern was found in it: now by the search's
    pattern order, given to the picture)."""
    import seahough.viz as viz
    from seahough.cli import main

    img = np.full((240, 320), 60, np.uint8)
    cv2.circle(img, (100, 120), 20, 200, -1)
    cv2.circle(img, (220, 120), 20, 200, -1)
    p = tmp_path / "two.png"
    cv2.imwrite(str(p), img)
    seen = {}
    monkeypatch.setattr(viz, "plot_detections",
                        lambda image, dets, path, **kw: seen.setdefault(Path(path).parent.name, kw))
    for spec, out, more in (("buoy=circle:20+post=line:100,12", "a", []),
                            ("rect:60,60", "b", ["--min-score", "0.95"])):
        with pytest.raises(SystemExit):
            main(["detect", spec, str(p), "-q", "--pictures", "overlay",
                  "--out", str(tmp_path / out)] + more)
    assert seen["a"]["title"] == "two.png: 2 detections; not found: post", seen["a"]
    assert seen["a"]["patterns"] == ["buoy", "post"]
    assert seen["b"]["title"].startswith("two.png: not found; best candidate: score ")
    assert seen["b"]["title"].count("score") == 1 + seen["b"]["title"].count("min_score")
    assert seen["b"]["patterns"] is None
    from seahough.viz.detections import colours
    from types import SimpleNamespace as Det
    assert colours([Det(pattern="post")], ["buoy", "post"]) == colours(
        [Det(pattern="buoy"), Det(pattern="post")])[1:]


def test_an_ellipse_spec_finds_an_ellipse(tmp_path):
    img = np.full((240, 320), 70, np.uint8)
    cv2.ellipse(img, (150, 110), (45, 27), 0, 0, 360, 200, -1)
    cv2.imwrite(str(tmp_path / "e.png"), img)
    proc = run("detect", "ellipse:45,27", tmp_path / "e.png", "--json", "--scale-range", 0.9, 1.1,
               "--angle-range", 0, 180)
    assert proc.returncode == 0, proc.stderr
    d = json.loads(proc.stdout)["detections"][0]
    assert abs(d["x"] - 150) < 1.0 and abs(d["y"] - 110) < 1.0 and len(d["outline"][0]) > 30


def test_the_table_of_several_patterns_gives_a_lines_offset():
    """A pipeline engineer's trial: ``detect "pipe=line:300,30+joint=rect:60,34"``
    printed the pipe's x, y, scale and angle, not its offset (its CSV and
    JSON had it): the table of several patterns has an offset column when a
    line is among them."""
    from types import SimpleNamespace as D

    from seahough.cli._records import _detection_lines

    common = dict(x=10.0, y=20.0, scale=1.0, score=0.9, confidence=0.8, nfa=1e-9, flags=())
    pipe = D(kind="line", pattern="pipe", angle=30.0, line_angle=30.0, line_offset=-12.5,
             **common)
    joint = D(kind="object", pattern="joint", angle=45.0, line_angle=None, line_offset=None,
              **common)
    head, *rows = [line.split() for line in _detection_lines([pipe, joint]) if line.strip()]
    head = [h for h in head if set(h) != {"-"}]
    rows = [r for r in rows if set(r[0]) != {"-"}]
    col = head.index("offset")
    assert rows[0][col] in ("-12.50", "12.50") and rows[1][col] == "-", (head, rows)
    assert "offset" not in " ".join(_detection_lines([joint]))


def test_the_edges_picture_of_several_patterns_shows_each_patterns_features(tmp_path, monkeypatch):
    """With several patterns searched at different working scales, the edges
    picture shows each scale's key points, one under the other, naming its
    patterns (a trial debugged a post "not found" on the buoy's features: the
    picture named no pattern)."""
    from seahough import viz
    from seahough.cli import detect as D
    from seahough.cli._common import make_detector

    img, _ = sim.rope_scene(width=8, water="moderate", seed=5, source="procedural")
    det = make_detector("buoy=circle:6+rope=line:200,8+post=line:150,8", (0.5, 2.0),
                        (0.0, 180.0), 1, 0.5, 0.0, None, None, False, None, None)
    res = det.search(img)
    by = {n: r.features for n, r in res.parts.items()}
    assert by["buoy"] is not by["rope"] and by["rope"] is by["post"]   # (two scales)
    seen = []
    draw = viz.plot_edges
    monkeypatch.setattr(viz, "plot_edges", lambda image, feats, path, title=None:
                        seen.append((feats, title)) or draw(image, feats, path, title=title))
    written = {}
    D._pictures("rope.png", img, res, det, None, tmp_path / "rope",
                D.Drawing(kinds=("edges",)), written)
    assert [(f, t) for f, t in seen] == [
        (by["buoy"], "rope.png: what the detector sees; pattern buoy"),
        (by["rope"], "rope.png: what the detector sees; patterns rope, post")]
    assert cv2.imread(written["edges"]).shape == (2 * 560, 1300, 3)
