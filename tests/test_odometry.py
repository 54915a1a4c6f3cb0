"""Photo dead reckoning over whole sequences (seahough.odometry)."""

from __future__ import annotations

import csv
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import simulate as S
from seahough.geometry import apply_matrix, compose, invert_matrix, matrix_to_pose
from seahough.odometry import list_frames, read_odometry_csv, run_odometry, time_from_name

from conftest import DATA, data_path

SRC = Path(__file__).resolve().parents[1] / "src"
SEQUENCES = ("sparus_auv_seabed", "aqualoc_amphorae_wreck", "subvo_pool_chain",
             "dtu_seabed_pair", "skerki_mud_pair")
SHAPE = (240, 320)


# ----------------------------------------------------------------------------- helpers
def _photo():
    """A real photo to cut frames from (an amphora wreck: object-rich, as
    photo dead reckoning needs), or None (the procedural seabed)."""
    if DATA is None:
        return None
    p = DATA / "sequences" / "aqualoc_amphorae_wreck" / "frame_000.png"
    return str(p) if p.exists() else None


def _sequence(path, n=20, seed=0, step=12.0):
    photo = _photo()
    return S.sequence(photo, n_frames=n, frame_size=SHAPE, path=path, step=step, seed=seed,
                      source="auto" if photo else "procedural")


def _true_track(mats, shape=SHAPE):
    h, w = shape
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
    heading = np.degrees(np.unwrap([-math.radians(matrix_to_pose(m)[3]) for m in mats]))
    return xy, heading


def _write_frames(frames, folder: Path, prefix="frame_"):
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, f in enumerate(frames):
        p = folder / f"{prefix}{i:03d}.png"
        cv2.imwrite(str(p), f)
        paths.append(str(p))
    return paths


def _csv_without_timing(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.pop("ms")
    return rows


# ---------------------------------------------------------------- synthetic accuracy
@pytest.mark.parametrize("path, seed", [("line", 0), ("turn", 1), ("loop", 2)])
def test_synthetic_path_drift_under_one_percent(tmp_path, path, seed):
    frames, mats = _sequence(path, seed=seed)
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    xy, heading = _true_track(mats)
    est = np.array([[r["x"], r["y"]] for r in res.rows])
    travelled = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    drift = float(np.hypot(*(est[-1] - xy[-1])))
    assert travelled > 200
    assert drift < 0.01 * travelled, f"{path}: end-point drift {drift:.2f} px of {travelled:.0f} px"
    assert abs(res.rows[-1]["heading"] - heading[-1]) < 1.0
    assert res.summary["flagged_pairs"] == 0
    # the prior did the work, the keyframes were kept over several frames
    assert res.summary["methods"].get("prior", 0) >= len(frames) - 4
    assert res.summary["keyframes"] <= len(frames) // 3
    # each pair's own motion is reported, and it matches the truth
    r = res.rows[5]
    pair = np.asarray(r["pair_matrix"]).reshape(2, 3)
    true_pair = compose(mats[5], invert_matrix(mats[4]))
    c = [[(SHAPE[1] - 1) / 2.0, (SHAPE[0] - 1) / 2.0]]
    assert np.hypot(*(apply_matrix(pair, c) - apply_matrix(true_pair, c))[0]) < 1.5
    assert r["dx"] == pytest.approx(apply_matrix(pair, c)[0][0] - c[0][0])


def test_known_heading_and_altitude_keep_them_fixed(tmp_path):
    frames, mats = S.sequence(_photo(), n_frames=8, frame_size=SHAPE, path="line", step=12.0,
                              seed=5, source="auto" if _photo() else "procedural")
    res = run_odometry(frames, tmp_path, scale_range=(1, 1), angle_range=(0, 0),
                       progress=False, mosaic=False)
    assert all(r["scale"] == pytest.approx(1.0) for r in res.rows)
    assert all(r["heading"] == pytest.approx(0.0, abs=1e-9) for r in res.rows)
    xy, _ = _true_track(mats)
    est = np.array([[r["x"], r["y"]] for r in res.rows])
    # the true heading wanders by ~0.6 deg a frame: a fixed one still tracks closely
    assert np.hypot(*(est[-1] - xy[-1])) < 4.0


# ------------------------------------------------------------------------- outputs
def test_outputs_metric_and_mosaic(tmp_path):
    frames, mats = _sequence("turn", n=10, seed=3)
    res = run_odometry(frames, tmp_path / "out", altitude=2.0, focal_px=400.0, progress=False)
    mpp = 2.0 / 400.0
    for p in (res.csv_path, res.json_path, res.mosaic_path, res.trajectory_path):
        assert Path(p).is_file() and Path(p).stat().st_size > 0
    with open(res.csv_path, newline="") as f:
        header = next(csv.reader(f))
    assert header[:11] == ["index", "file", "time", "x", "y", "heading", "scale", "confidence",
                           "flags", "x_m", "y_m"]
    summary = json.loads(Path(res.json_path).read_text())
    assert summary["frames"] == 10 and summary["measured_pairs"] == 9
    assert summary["flagged_pairs"] == 0
    assert summary["path_length_m"] == pytest.approx(summary["path_length_px"] * mpp)
    end_x_m = (res.rows[-1]["x"] - res.rows[0]["x"]) * mpp
    assert summary["end_point"]["x_m"] == pytest.approx(end_x_m)
    assert res.rows[0]["x_m"] == 0.0 and res.rows[0]["y_m"] == 0.0
    assert summary["settings"]["metres_per_pixel"] == pytest.approx(mpp)
    assert summary["mean_ms_per_frame"] > 0
    # the mosaic: every frame placed where the trajectory says, so it holds the
    # frames' content: frame 0 is found at its place, sharp (not a blend)
    mosaic = cv2.imread(str(res.mosaic_path))
    assert mosaic is not None and min(mosaic.shape[:2]) >= SHAPE[0]
    g0 = cv2.cvtColor(frames[0], cv2.COLOR_BGR2GRAY)
    gm = cv2.cvtColor(mosaic, cv2.COLOR_BGR2GRAY)
    patch = g0[80:160, 100:220]
    score = cv2.matchTemplate(gm, patch, cv2.TM_CCOEFF_NORMED).max()
    assert score > 0.9


def test_metres_per_pixel_needs_both_altitude_and_focal(tmp_path):
    frames, _ = _sequence("line", n=3)
    with pytest.raises(seahough.ParameterError, match="altitude and focal_px"):
        run_odometry(frames, tmp_path, altitude=2.0, progress=False)
    with pytest.raises(seahough.ParameterError, match="scale_range"):
        run_odometry(frames, tmp_path, scale_range=(1.1, 0.9), progress=False)


def test_frame_order_and_timestamps(tmp_path):
    for name in ("f10.png", "f2.png", "f1.png"):
        cv2.imwrite(str(tmp_path / name), np.zeros((16, 16), np.uint8))
    assert [Path(p).name for p in list_frames(tmp_path)] == ["f1.png", "f2.png", "f10.png"]
    assert [Path(p).name for p in list_frames([str(tmp_path)])] == ["f1.png", "f2.png", "f10.png"]
    ts = tmp_path / "ts"
    ts.mkdir()
    for name in ("cam_20240210_134117.500.png", "cam_20240210_134109.000.png",
                 "cam_20240210_134200.000.png"):
        cv2.imwrite(str(ts / name), np.zeros((16, 16), np.uint8))
    assert [Path(p).name[4:19] for p in list_frames(ts)] == [
        "20240210_134109", "20240210_134117", "20240210_134200"]
    assert time_from_name("frame_00_00_21.000.jpg") == 21.0
    assert time_from_name("1372687208.6337876.png") == pytest.approx(1372687208.6337876)
    assert time_from_name("frame_000123.png") is None
    with pytest.raises(seahough.ParameterError):
        list_frames(tmp_path / "missing")


def test_video_file_and_grey_16bit_frames(tmp_path):
    frames, mats = _sequence("line", n=8, seed=4)
    video = tmp_path / "dive.avi"
    vw = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 5.0, SHAPE[::-1])
    if not vw.isOpened():
        pytest.skip("OpenCV cannot write an MJPG video here")
    for f in frames:
        vw.write(f)
    vw.release()
    assert len(list_frames(video)) == 8
    res = run_odometry([str(video)], tmp_path / "v", progress=False, mosaic=False)
    assert [r["file"] for r in res.rows][:2] == [f"{video}#0", f"{video}#1"]
    assert res.rows[1]["time"] == pytest.approx(0.2)
    assert res.summary["flagged_pairs"] == 0
    xy, _ = _true_track(mats)
    est = np.array([[r["x"], r["y"]] for r in res.rows])
    assert np.hypot(*(est[-1] - xy[-1])) < 3.0
    # the same frames as 16-bit grey PNG files
    d = tmp_path / "grey16"
    d.mkdir()
    for i, f in enumerate(frames):
        g = cv2.cvtColor(f, cv2.COLOR_BGR2GRAY).astype(np.uint16) * 257
        cv2.imwrite(str(d / f"g_{i}.png"), g)
    res16 = run_odometry(d, tmp_path / "g", progress=False)
    est16 = np.array([[r["x"], r["y"]] for r in res16.rows])
    assert np.hypot(*(est16[-1] - xy[-1])) < 3.0
    assert cv2.imread(str(res16.mosaic_path)) is not None


# ----------------------------------------------------- gaps: corrupt and unrelated
def _frames_for_gap_tests(tmp_path):
    """Frames on disk: Sparus when present (real), else a simulated line."""
    if DATA is not None and (DATA / "sequences" / "sparus_auv_seabed").is_dir():
        src = sorted((DATA / "sequences" / "sparus_auv_seabed").glob("frame_*.png"))
        d = tmp_path / "frames"
        d.mkdir()
        out = []
        for p in src:
            q = d / p.name
            q.write_bytes(p.read_bytes())
            out.append(str(q))
        return out
    frames, _ = _sequence("line", n=16, seed=6)
    return _write_frames(frames, tmp_path / "frames")


def test_corrupt_frame_is_flagged_and_the_run_goes_on(tmp_path):
    paths = _frames_for_gap_tests(tmp_path)
    clean = run_odometry(paths, tmp_path / "clean", progress=False, mosaic=False)
    k = len(paths) // 2
    data = Path(paths[k]).read_bytes()
    Path(paths[k]).write_bytes(data[: len(data) // 2])       # truncated PNG
    res = run_odometry(paths, tmp_path / "cut", progress=False)
    bad = res.rows[k]
    assert bad["status"] == "unreadable" and bad["flags"].startswith("unreadable: ")
    assert "truncated" in bad["flags"]
    assert bad["x"] is None                                   # no invented pose
    assert res.rows[k + 1]["status"] == "measured"            # measured across the gap
    assert res.summary["flagged_pairs"] == 1 and res.summary["unreadable_frames"] == 1
    # the track after the gap agrees with the uncorrupted run
    a = np.array([res.rows[-1]["x"], res.rows[-1]["y"]])
    b = np.array([clean.rows[-1]["x"], clean.rows[-1]["y"]])
    assert np.hypot(*(a - b)) < 3.0
    assert Path(res.mosaic_path).is_file()


def test_unrelated_frame_is_flagged_not_invented(tmp_path):
    frames, mats = _sequence("line", n=12, seed=7)
    frames = list(frames)
    frames[6] = S.seabed(SHAPE, seed=99)   # a frame of somewhere else
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    r = res.rows[6]
    assert r["status"] == "assumed"
    assert "pose_assumed" in r["flags"]
    assert "low_confidence" in r["flags"] or "no_motion" in r["flags"]
    # zero motion assumed across the gap (and said so), then measured again
    assert (r["x"], r["y"]) == (res.rows[5]["x"], res.rows[5]["y"])
    assert all(q["status"] == "measured" for q in res.rows[7:])
    xy, _ = _true_track(mats)
    est = np.array([[q["x"], q["y"]] for q in res.rows])
    assert np.hypot(*(est[-1] - xy[-1])) < 3.0   # frame 7 was measured against the keyframe


# --------------------------------------------------------------------------- resume
def test_resume_gives_the_same_result(tmp_path):
    frames, _ = _sequence("turn", n=16, seed=8)
    paths = _write_frames(frames, tmp_path / "frames")
    Path(paths[4]).write_bytes(b"not an image")               # state across a gap too
    full = run_odometry(paths, tmp_path / "full", progress=False, mosaic=False)
    run_odometry(paths[:9], tmp_path / "resumed", progress=False, mosaic=False)
    res = run_odometry(paths, tmp_path / "resumed", resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == 9
    assert _csv_without_timing(res.csv_path) == _csv_without_timing(full.csv_path)
    # resuming a finished run measures nothing new
    again = run_odometry(paths, tmp_path / "resumed", resume=True, progress=False, mosaic=False)
    assert again.summary["resumed_rows"] == 16
    assert _csv_without_timing(again.csv_path) == _csv_without_timing(full.csv_path)
    # a CSV of another sequence is refused
    with pytest.raises(seahough.ParameterError, match="not the same sequence"):
        run_odometry(paths[::-1], tmp_path / "resumed", resume=True, progress=False)


_KILL_SCRIPT = """
import sys, time
import seahough.odometry as O
raw = O._Reader.raw
def slow(self, i):
    time.sleep(0.15)
    return raw(self, i)
O._Reader.raw = slow
O.run_odometry(sys.argv[1], sys.argv[2], progress=False, mosaic=False)
"""


def test_killed_run_resumes_to_the_same_result(tmp_path):
    frames, _ = _sequence("line", n=14, seed=9)
    folder = tmp_path / "frames"
    _write_frames(frames, folder)
    full = run_odometry(folder, tmp_path / "full", progress=False, mosaic=False)
    out = tmp_path / "killed"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-c", _KILL_SCRIPT, str(folder), str(out)], env=env)
    csv_path = out / "odometry.csv"
    try:
        deadline = time.time() + 60
        while time.time() < deadline:
            if csv_path.exists() and len(csv_path.read_text().splitlines()) >= 6:
                break
            if proc.poll() is not None:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the run ended before it could be killed"
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    done = read_odometry_csv(csv_path)
    assert 5 <= len(done) < 14                                # killed mid-run, rows kept
    res = run_odometry(folder, out, resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == len(done)
    assert _csv_without_timing(res.csv_path) == _csv_without_timing(full.csv_path)


# ---------------------------------------------------------------- real sequences
@pytest.fixture(scope="module")
def real_runs(tmp_path_factory):
    cache = {}

    def get(name):
        if name not in cache:
            folder = data_path("sequences", name)
            out = tmp_path_factory.mktemp(name)
            cache[name] = run_odometry(folder, out, progress=False)
        return cache[name]

    return get


@pytest.mark.parametrize("name", SEQUENCES)
def test_real_sequence_end_to_end(real_runs, name):
    res = real_runs(name)
    n = len(list_frames(data_path("sequences", name)))
    assert len(res.rows) == n == res.summary["frames"]
    for p in (res.csv_path, res.json_path, res.mosaic_path, res.trajectory_path):
        assert Path(p).is_file() and Path(p).stat().st_size > 0
    assert len(read_odometry_csv(res.csv_path)) == n
    assert cv2.imread(str(res.mosaic_path)) is not None
    # every frame either has a measured pose or says why not
    for r in res.rows[1:]:
        assert r["status"] == "measured" or r["flags"], r
    if name in ("sparus_auv_seabed", "aqualoc_amphorae_wreck", "dtu_seabed_pair"):
        assert res.summary["flagged_pairs"] == 0
    if name == "subvo_pool_chain":
        # names carry the time of day: sorted and timed by it
        assert res.rows[1]["time"] - res.rows[0]["time"] == pytest.approx(1.0)


def _sparus_truth(folder: Path, n_frames: int):
    """Heading change (deg, counter-clockwise as displayed) and travel direction
    (unit vector in frame-0 pixels) from the pose CSV, at the frames' times.

    The poses follow ROS conventions: world x east, y north, z up (z = -13.8 m
    is the depth); the camera frame is the vehicle's x forward (= up in the
    image), y left (= left in the image), z up (out of the image). Frame i was
    taken at offset + i / 4.9988 s (MANIFEST.tsv); the poses change every
    ~0.35 s and are interpolated linearly between changes.
    """
    offset = float((folder / "sparus_time_offset.yaml").read_text().split(":", 1)[1])
    with open(folder / "camera_poses_sparus_snippet.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["ts"]) for r in rows])
    p = np.array([[float(r[k]) for k in ("x", "y")] for r in rows])
    q = np.array([[float(r[k]) for k in ("qx", "qy", "qz", "qw")] for r in rows])
    change = [0] + [i for i in range(1, len(rows))
                    if not (np.allclose(p[i], p[i - 1]) and np.allclose(q[i], q[i - 1]))]
    x, y, z, w = q[change].T
    yaw = np.unwrap(np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))
    ft = offset + np.array([0, n_frames - 1]) / 4.9988
    yaw_f = np.interp(ft, t[change], yaw)
    px = np.interp(ft, t[change], p[change, 0])
    py = np.interp(ft, t[change], p[change, 1])
    d = np.array([px[1] - px[0], py[1] - py[0]])
    fwd = d @ [math.cos(yaw_f[0]), math.sin(yaw_f[0])]
    left = d @ [-math.sin(yaw_f[0]), math.cos(yaw_f[0])]
    direction = np.array([-left, -fwd]) / math.hypot(fwd, left)   # image x right, y down
    return math.degrees(yaw_f[1] - yaw_f[0]), direction


def test_sparus_agrees_with_its_camera_poses(real_runs):
    folder = data_path("sequences", "sparus_auv_seabed")
    res = real_runs("sparus_auv_seabed")
    turn, direction = _sparus_truth(folder, len(res.rows))
    measured_turn = res.rows[-1]["heading"] - res.rows[0]["heading"]
    # the vehicle turned left by ~23 degrees; we see 20-30 (the poses are a
    # navigation estimate, updated every 0.35 s)
    assert turn == pytest.approx(23.1, abs=1.0)
    assert measured_turn == pytest.approx(turn, rel=0.25)
    d = np.array([res.rows[-1]["x"] - res.rows[0]["x"], res.rows[-1]["y"] - res.rows[0]["y"]])
    cosang = float(d @ direction / np.linalg.norm(d))
    assert math.degrees(math.acos(min(1.0, cosang))) < 20.0
