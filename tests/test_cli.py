"""The ``seahough`` command line, run as users run it: in a subprocess."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import types
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import simulate as sim
from seahough._data import shared_data_dir

SRC = Path(__file__).resolve().parents[1] / "src"
HAS_ODOMETRY = importlib.util.find_spec("seahough.odometry") is not None


def run(*args, cwd=None, timeout=180):
    env = dict(os.environ)
    extra = [env["PYTHONPATH"]] if env.get("PYTHONPATH") else []
    env["PYTHONPATH"] = os.pathsep.join([str(SRC)] + extra)
    env.setdefault("MPLBACKEND", "Agg")
    return subprocess.run([sys.executable, "-m", "seahough", *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


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
    assert lines[1].split() == ["#", "x", "y", "scale", "angle", "score", "conf", "flags"]
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
                                  "shape_numbers", "pattern_missing"])
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
    assert [Path(r["file"]).name for r in recs] == ["scene.png", "neg.png"]
    assert recs[0]["found"] and not recs[1]["found"]
    err = proc.stderr.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"seahough: error: {d / 'notes.png'}: ")
    assert "Traceback" not in proc.stderr


def test_detect_out_writes_pngs(scenes, tmp_path):
    d, _ = scenes
    from seahough.plot import detections_size

    proc = run("detect", d / "pattern.png", d / "scene.png", d / "neg.png", "--out", tmp_path,
               "--json", "--quiet")
    assert proc.returncode == 1          # found in scene.png, not in neg.png
    recs = [json.loads(line) for line in proc.stdout.splitlines()]
    assert recs[0]["overlay"] == str(tmp_path / "scene_overlay.png")
    for stem in ("scene", "neg"):
        ov = cv2.imread(str(tmp_path / f"{stem}_overlay.png"))
        ac = cv2.imread(str(tmp_path / f"{stem}_accumulator.png"))
        assert ov is not None and ac is not None
        assert (ov.shape[1], ov.shape[0]) == detections_size((480, 640))
        assert ac.shape[:2] == (560, 1300)
        assert ov.std() > 10 and ac.std() > 10


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
    if kind == "sequence":
        assert np.allclose(items[0]["matrix_from_first"], [[1, 0, 0], [0, 1, 0]])
        assert "motion_from_previous" in items[1]


def test_odometry_command_calls_run_odometry(tmp_path, monkeypatch, capsys):
    """The command's wiring to seahough.odometry.run_odometry (a stand-in here)."""
    from seahough import cli

    calls = {}

    def fake_run_odometry(frames, out_dir, **kw):
        calls.update(frames=frames, out_dir=out_dir, **kw)
        rows = [{"index": i, "file": f"f{i}.png", "time": float(i), "x": 3.0 * i, "y": 4.0 * i,
                 "heading": 0.0, "scale": 1.0, "confidence": 0.9,
                 "flags": ["lost"] if i == 2 else []} for i in range(4)]
        return types.SimpleNamespace(rows=rows, summary={}, csv_path=Path(out_dir) / "track.csv",
                                     json_path=None, mosaic_path=None, trajectory_path=None)

    fake = types.ModuleType("seahough.odometry")
    fake.run_odometry = fake_run_odometry
    monkeypatch.setitem(sys.modules, "seahough.odometry", fake)
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


@pytest.mark.skipif(not HAS_ODOMETRY, reason="seahough.odometry is not there yet")
def test_odometry_on_simulated_sequence(tmp_path):
    proc = run("simulate", "sequence", "--out", tmp_path / "seq", "--n", 5, "--procedural",
               "--seed", 2)
    assert proc.returncode == 0, proc.stderr
    proc = run("odometry", tmp_path / "seq", "--out", tmp_path / "odo", "--quiet", "--json")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["frames"] == 5
    assert summary["csv"] and Path(summary["csv"]).exists()


def test_demo_end_to_end(tmp_path):
    proc = run("demo", "--out", tmp_path / "demo", "--quiet", timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Traceback" not in proc.stderr
    out = tmp_path / "demo"
    for name in ("marker_scene.png", "marker_overlay.png", "marker_accumulator.png",
                 "marker_edges.png", "rope_overlay.png", "rope_accumulator.png",
                 "sequence/frame_000.png", "sequence/frame_007.png"):
        assert cv2.imread(str(out / name)) is not None, name
    assert "marker position" in proc.stdout and "rope offset" in proc.stdout
    if HAS_ODOMETRY:
        assert cv2.imread(str(out / "trajectory.png")) is not None
        assert "drift" in proc.stdout
