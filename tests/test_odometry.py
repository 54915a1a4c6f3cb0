"""Photo dead reckoning over whole sequences (seahough.motion.odometry)."""

from __future__ import annotations

import csv
import functools
import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as S
from seahough.geometry import apply_matrix, compose, invert_matrix, matrix_to_pose
from seahough.io.frames import list_frames, time_from_name
from seahough.motion import read_odometry_csv, run_odometry

from conftest import DATA, data_path, write_frames

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


def _sequence(path, n=20, seed=0, step=12.0, source=None):
    """Frames along a camera path over the real photo when it is there, else
    the procedural seabed; ``source="procedural"``: that seabed everywhere."""
    photo = None if source == "procedural" else _photo()
    return S.sequence(photo, n_frames=n, frame_size=SHAPE, path=path, step=step, seed=seed,
                      source="auto" if photo else "procedural")


def _true_track(mats, shape=SHAPE):
    h, w = shape
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
    heading = np.degrees(np.unwrap([-math.radians(matrix_to_pose(m)[3]) for m in mats]))
    return xy, heading


def _write_frames(frames, folder: Path, prefix="frame_"):
    return write_frames(frames, folder, prefix)


def _hp(gray, sigma=2.0):
    """High-pass (the image minus its Gaussian blur): fine texture, not
    brightness or vignetting, so a correlation of two views depends on
    their registration to a pixel or two."""
    g = np.asarray(gray, np.float32)
    return g - cv2.GaussianBlur(g, (0, 0), sigma)


def _find_subpixel(image, patch):
    """Top-left of ``patch`` in ``image`` (normalised correlation, peak refined
    to a fraction of a pixel by a parabola through its neighbours)."""
    r = cv2.matchTemplate(image, patch, cv2.TM_CCOEFF_NORMED)
    _, _, _, (px, py) = cv2.minMaxLoc(r)

    def refine(a, b, c):
        d = a - 2 * b + c
        return 0.0 if d >= 0 else 0.5 * (a - c) / d

    fx = refine(*r[py, px - 1: px + 2]) if 0 < px < r.shape[1] - 1 else 0.0
    fy = refine(*r[py - 1: py + 2, px]) if 0 < py < r.shape[0] - 1 else 0.0
    return px + fx, py + fy


_OFFSETS = ((0.0, 0.0), (3.0, 0.0), (-3.0, 0.0), (0.0, 3.0), (0.0, -3.0))


def _mosaic_placement(mosaic, frames, rows):
    """Is every frame in the mosaic where the trajectory puts it?

    The mosaic takes each pixel from the frame that saw it nearest to that
    frame's centre (seahough.motion.mosaic.build_mosaic), so each frame has a cell of the
    mosaic that should hold its own pixels: the cells are computed from the
    trajectory (the rows' ``matrix``). Frame 0 is located in the mosaic (the
    canvas origin); then each frame is compared with the mosaic over its
    cell, sampled where the trajectory places it and 3 px beside (4
    directions, frame-0 pixels). Returns, per frame, (coverage: share of the
    cell the mosaic filled, [high-pass normalised correlation at each of
    _OFFSETS]). Correctly placed: the cell filled and the correlation peaks
    at offset (0, 0); a frame left out or put elsewhere leaves its cell
    black or holding other content; a frame 3 px off correlates better 3 px
    beside."""
    gm = cv2.cvtColor(mosaic, cv2.COLOR_BGR2GRAY)
    g0 = cv2.cvtColor(frames[0], cv2.COLOR_BGR2GRAY)
    h, w = g0.shape
    x, y = _find_subpixel(gm, g0[h // 4: 3 * h // 4, w // 4: 3 * w // 4])
    gmf = gm.astype(np.float32)
    yy, xx = np.mgrid[0:h, 0:w]
    pix = np.stack([xx.ravel(), yy.ravel()], 1).astype(float)
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    mats = [np.asarray(r["matrix"]).reshape(2, 3) for r in rows]

    def centre_distance(p):     # as the mosaic's, infinite outside the frame
        d = ((p[:, 0] - c[0]) / w) ** 2 + ((p[:, 1] - c[1]) / h) ** 2
        d[(p[:, 0] < 0) | (p[:, 1] < 0) | (p[:, 0] > w - 1) | (p[:, 1] > h - 1)] = np.inf
        return d

    out = []
    for i, f in enumerate(frames):
        to_0 = invert_matrix(mats[i])                       # frame i px -> frame-0 px
        others = np.full(len(pix), np.inf)
        for j, m in enumerate(mats):
            if j != i:
                others = np.minimum(others, centre_distance(apply_matrix(compose(m, to_0), pix)))
        cell = (centre_distance(pix) < others).reshape(h, w).astype(np.uint8)
        cell = cv2.erode(cell, np.ones((5, 5), np.uint8)) > 0
        assert cell.sum() > 2000, "each frame of the test sequence must own a part of the mosaic"
        hf = _hp(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY))
        coverage, nccs = None, []
        for dx, dy in _OFFSETS:
            to_canvas = np.array([[1.0, 0.0, x - w // 4 + dx], [0.0, 1.0, y - h // 4 + dy]])
            back = cv2.warpAffine(gmf, compose(to_canvas, to_0), (w, h),
                                  flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderValue=0.0)
            filled = cell & (back > 0)
            if coverage is None:
                coverage = float(filled.sum() / cell.sum())
            if filled.sum() < 500:
                nccs.append(0.0)
                continue
            a, b = hf[filled], _hp(back)[filled]
            a, b = a - a.mean(), b - b.mean()
            nccs.append(float((a * b).sum() / math.sqrt((a * a).sum() * (b * b).sum())))
        out.append((coverage, nccs))
    return out


def _mosaic_is_registered(placement):
    """Every frame's cell filled, and its correlation there clear and highest
    where the trajectory puts it (not 3 px beside)."""
    return all(cov > 0.9 and n[0] > 0.25 and n[0] > max(n[1:]) + 0.05
               for cov, n in placement)


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


def test_a_high_rekey_overlap_measures_every_pair_directly(tmp_path):
    """docs/odometry.md: with ``rekey_overlap=1.0`` each frame is the next one's
    keyframe, so every step is a direct pair measurement; by default frames are
    measured against keyframes two or more frames back."""
    from seahough.config import OdometryTuning
    frames, mats = _sequence("line", seed=0)
    default = run_odometry(frames, tmp_path / "a", progress=False, mosaic=False).rows
    direct = run_odometry(frames, tmp_path / "b", progress=False, mosaic=False,
                          tuning=OdometryTuning(rekey_overlap=1.0)).rows
    assert any(r["ref"] < r["index"] - 1 for r in default[1:])
    assert all(r["status"] == "measured" and r["ref"] == r["index"] - 1 for r in direct[1:])
    c = [[(SHAPE[1] - 1) / 2.0, (SHAPE[0] - 1) / 2.0]]
    for r in direct[1:]:
        pair = np.asarray(r["pair_matrix"]).reshape(2, 3)
        truth = compose(mats[r["index"]], invert_matrix(mats[r["index"] - 1]))
        assert np.hypot(*(apply_matrix(pair, c) - apply_matrix(truth, c))[0]) < 1.5


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
    assert header[:12] == ["index", "file", "time", "x", "y", "heading", "scale", "confidence",
                           "nfa", "flags", "x_m", "y_m"]
    summary = json.loads(Path(res.json_path).read_text())
    assert summary["frames"] == 10 and summary["measured_pairs"] == 9
    assert summary["flagged_pairs"] == 0
    assert summary["path_length_m"] == pytest.approx(summary["path_length_px"] * mpp)
    end_x_m = (res.rows[-1]["x"] - res.rows[0]["x"]) * mpp
    assert summary["end_point"]["x_m"] == pytest.approx(end_x_m)
    assert res.rows[0]["x_m"] == 0.0 and res.rows[0]["y_m"] == 0.0
    assert summary["settings"]["metres_per_pixel"] == pytest.approx(mpp)
    assert summary["mean_ms_per_frame"] > 0
    # the CSV read back holds the same metric columns (plain numbers)
    back = read_odometry_csv(res.csv_path)
    assert len(back) == 10 and back[-1]["x_m"] == pytest.approx(summary["end_point"]["x_m"])
    # the mosaic: every frame where the trajectory places it (relative to frame
    # 0), sharp: its fine texture matches the frame's there (a frame misplaced by
    # 3 px, or left at frame 0's place, or mirrored, fails: see _mosaic_placement)
    mosaic = cv2.imread(str(res.mosaic_path))
    assert mosaic is not None and min(mosaic.shape[:2]) >= SHAPE[0]
    placement = _mosaic_placement(mosaic, frames, res.rows)
    assert _mosaic_is_registered(placement), placement


def test_metres_per_pixel_needs_both_altitude_and_focal(tmp_path):
    frames, _ = _sequence("line", n=3)
    with pytest.raises(seahough.ParameterError, match="altitude and focal_px"):
        run_odometry(frames, tmp_path, altitude=2.0, progress=False)
    with pytest.raises(seahough.ParameterError, match="scale_range"):
        run_odometry(frames, tmp_path, scale_range=(1.1, 0.9), progress=False)
    # metres_per_pixel and altitude/focal_px are two ways of saying one thing:
    # both given is refused (as the CLI does), naming both, not one silently preferred
    for extra in ({"altitude": 2.0, "focal_px": 400.0}, {"altitude": 2.0}, {"focal_px": 400.0}):
        with pytest.raises(seahough.ParameterError) as e:
            run_odometry(frames, tmp_path / "both", metres_per_pixel=0.004, progress=False,
                         **extra)
        assert "metres_per_pixel" in str(e.value) and "altitude" in str(e.value)
        assert "not both" in str(e.value)
    assert not (tmp_path / "both" / "odometry.csv").exists()    # refused before any work
    # units that cannot be (an altitude in mm: 53.6 km for 4 s of survey; a ratio of 0)
    for kw in ({"altitude": 2500.0, "focal_px": 8.0}, {"metres_per_pixel": 1e9},
               {"altitude": 1e-300, "focal_px": 1e300}):
        with pytest.raises(seahough.ParameterError, match="m a pixel: must be over 0 and at "
                                                          "most 10 \\(an altitude in millimetres"):
            run_odometry(frames, tmp_path / "units", progress=False, **kw)


def test_the_frames_folder_is_not_the_output_folder(tmp_path):
    """--out set to the frames' folder: the next run read mosaic.png and
    trajectory.png as frames (unreadable), and --resume was refused for
    good; now refused at once. A subfolder is fine."""
    frames, _ = _sequence("line", n=3)
    write_frames(frames, tmp_path / "dive")
    for given in (tmp_path / "dive", str(tmp_path / "dive"), [tmp_path / "dive"]):
        with pytest.raises(seahough.ParameterError, match="is the frames' folder"):
            run_odometry(given, tmp_path / "dive", progress=False, mosaic=False)
    assert sorted(p.name for p in (tmp_path / "dive").iterdir()) == [
        "f_000.png", "f_001.png", "f_002.png"]                  # (nothing written there)
    r = run_odometry(tmp_path / "dive", tmp_path / "dive" / "run", progress=False, mosaic=False)
    assert len(r.rows) == 3


def test_metres_per_pixel_scales_the_track(tmp_path):
    frames, mats = _sequence("turn", n=8, seed=11)
    mpp = 0.0037
    res = run_odometry(frames, tmp_path / "m", metres_per_pixel=mpp, progress=False,
                       mosaic=False)
    px = run_odometry(frames, tmp_path / "px", progress=False, mosaic=False)
    x0, y0 = res.rows[0]["x"], res.rows[0]["y"]
    assert (res.rows[0]["x_m"], res.rows[0]["y_m"]) == (0.0, 0.0)
    for r, q in zip(res.rows, px.rows):
        assert (r["x"], r["y"]) == (q["x"], q["y"])           # the pixels do not change
        assert r["x_m"] == pytest.approx((r["x"] - x0) * mpp, abs=1e-12)
        assert r["y_m"] == pytest.approx((r["y"] - y0) * mpp, abs=1e-12)
        assert "x_m" not in q
    assert res.summary["settings"]["metres_per_pixel"] == mpp
    assert res.summary["path_length_m"] == pytest.approx(px.summary["path_length_px"] * mpp)
    assert px.summary["path_length_m"] is None            # no scale given: pixels only
    # the end point in metres against the truth (the camera moved ~90 px, ~0.33 m)
    xy, _ = _true_track(mats)
    true_end = (xy[-1] - xy[0]) * mpp
    end = np.array([res.rows[-1]["x_m"], res.rows[-1]["y_m"]])
    assert np.hypot(*true_end) > 0.25
    assert np.hypot(*(end - true_end)) < 3.0 * mpp
    with open(res.csv_path, newline="") as f:
        assert next(csv.reader(f))[10:12] == ["x_m", "y_m"]


def test_frame_order_and_timestamps(tmp_path):
    for name in ("f10.png", "f2.png", "f1.png"):
        cv2.imwrite(str(tmp_path / name), np.zeros((16, 16), np.uint8))
    assert [Path(p).name for p in list_frames(tmp_path)] == ["f1.png", "f2.png", "f10.png"]
    assert [Path(p).name for p in list_frames([str(tmp_path)])] == ["f1.png", "f2.png", "f10.png"]
    # names whose order (camA, camB, camC) disagrees with their times: sorted by time
    ts = tmp_path / "ts"
    ts.mkdir()
    names = ("camB_20240210_134109.000.png", "camA_20240210_134117.500.png",
             "camC_20240210_134100.000.png")
    for name in names:
        cv2.imwrite(str(ts / name), np.zeros((16, 16), np.uint8))
    assert sorted(names) != [names[2], names[0], names[1]]        # (the test is not blind)
    assert [Path(p).name for p in list_frames(ts)] == [names[2], names[0], names[1]]
    # one name without a time: natural name order for the whole folder
    cv2.imwrite(str(ts / "camD.png"), np.zeros((16, 16), np.uint8))
    assert [Path(p).name for p in list_frames(ts)] == sorted(names) + ["camD.png"]
    assert time_from_name("frame_00_00_21.000.jpg") == 21.0
    assert time_from_name("1372687208.6337876.png") == pytest.approx(1372687208.6337876)
    assert time_from_name("frame_000123.png") is None
    with pytest.raises(seahough.ParameterError):
        list_frames(tmp_path / "missing")


def test_fps_times_frames_whose_names_carry_none(tmp_path):
    """``fps``: the time column of frames without a time in their names (a
    survey engineer's trial could not fuse a Sparus run with navigation); a
    name's own time comes first; recorded for --resume only when given."""
    frames, _ = _sequence("line", n=3, source="procedural")
    folder = tmp_path / "f"
    _write_frames(frames, folder)
    (folder / "frame_002.png").rename(folder / "frame_002_00_00_21.500.png")   # (a time of day)
    res = run_odometry(folder, tmp_path / "o", progress=False, mosaic=False, fps=4)
    assert [r["time"] for r in res.rows] == [0.0, 0.25, 21.5]
    assert json.loads((tmp_path / "o" / "run.json").read_text())["settings"]["fps"] == 4.0
    assert res.summary["settings"]["source"] == str(folder)   # (the folder, not a frame)
    res = run_odometry(list(frames), tmp_path / "a", progress=False, mosaic=False)
    assert [r["time"] for r in res.rows] == [None] * 3                   # (none: as before)
    assert "fps" not in json.loads((tmp_path / "a" / "run.json").read_text())["settings"]
    assert res.summary["settings"]["source"] == "arrays"
    for bad in (0, -1, float("nan"), "5"):
        with pytest.raises(seahough.ParameterError, match="fps"):
            run_odometry(folder, tmp_path / "b", progress=False, fps=bad)


def test_frames_named_by_time_of_day_across_midnight_are_said(tmp_path, caplog):
    """Times of day without a date: a dive across midnight sorts its frames
    after it first (a trial: the track turned back, every frame "measured");
    a note says so, and a dive within one day gets none."""
    for name in ("f_23_59_59.000.png", "f_23_59_59.500.png", "f_00_00_00.000.png",
                 "f_00_00_00.500.png"):
        cv2.imwrite(str(tmp_path / name), np.zeros((16, 16), np.uint8))
    with caplog.at_level("WARNING", logger="seahough.io"):
        names = [Path(p).name for p in list_frames(tmp_path)]
    assert names[0] == "f_00_00_00.000.png"                 # (the order of the day, as said)
    [note] = [r.getMessage() for r in caplog.records]
    assert "jump by 24.0 h between f_00_00_00.500.png and f_23_59_59.000.png" in note
    assert "a dive across midnight?" in note
    caplog.clear()
    (tmp_path / "f_00_00_00.000.png").unlink()
    (tmp_path / "f_00_00_00.500.png").unlink()
    with caplog.at_level("WARNING", logger="seahough.io"):
        list_frames(tmp_path)
    assert not caplog.records


def test_a_folder_says_what_it_does_not_read(tmp_path, caplog):
    # subfolders (not searched inside), videos and picture formats it cannot
    # read were left out without a word; a navigation log is no frame
    for name in ("f1.png", "f2.png"):
        cv2.imwrite(str(tmp_path / name), np.zeros((16, 16), np.uint8))
    # (.jpe and .jfif are JPEG names OpenCV reads: they were read when named, skipped in a
    # folder without a word, a user trial)
    for name in ("f3.jpe", "f4.JFIF"):
        (tmp_path / name).write_bytes(cv2.imencode(".jpg", np.zeros((16, 16), np.uint8))[1])
    for name in ("dive2", "dive3", "empty"):
        (tmp_path / name).mkdir()
    for name in ("dive2", "dive3"):
        cv2.imwrite(str(tmp_path / name / "g.png"), np.zeros((16, 16), np.uint8))
    for name in ("clip.mp4", "a.gif", "b.GIF", "nav.csv", ".hidden.gif"):
        (tmp_path / name).write_bytes(b"x")
    # a .ts file is a video when it is an MPEG transport stream, not TypeScript
    (tmp_path / "cam.ts").write_bytes(2 * (b"\x47\x40\x00\x10" + bytes(184)))
    (tmp_path / "logger.ts").write_text("export const x = 1;\n")
    (tmp_path / "Greeter.ts").write_text("G" + "x" * 300)   # ("G" is 0x47: one byte is not enough)
    if hasattr(os, "mkfifo"):
        os.mkfifo(tmp_path / "live.ts")   # (a capture's named pipe: never opened, it would block)
    with caplog.at_level("WARNING", logger="seahough.io"):
        assert [Path(p).name for p in list_frames(tmp_path)] == ["f1.png", "f2.png", "f3.jpe",
                                                                 "f4.JFIF"]
    (msg,) = [r.getMessage() for r in caplog.records]
    assert msg.startswith(f"note: {tmp_path}: not read: 2 subfolders of images, e.g. dive2 "
                          "(a folder is not searched inside)"), msg
    assert "2 video files (.mp4, .ts)" in msg, msg
    assert "2 other picture files (.gif)" in msg and "nav.csv" not in msg, msg
    # a folder with only subfolders: the error says where the images may be
    top = tmp_path / "empty"
    (top / "cam0").mkdir()
    (top / "cam1").mkdir()
    cv2.imwrite(str(top / "cam0" / "a.png"), np.zeros((16, 16), np.uint8))
    with pytest.raises(seahough.ParameterError, match=r"no image files .*; not read: 1 "
                                                      r"subfolder of images, e\.g\. cam0"):
        list_frames(top)
    # nothing to say: no note
    caplog.clear()
    with caplog.at_level("WARNING", logger="seahough.io"):
        list_frames([str(tmp_path / "f1.png"), str(tmp_path / "f2.png")])
    assert not caplog.records


def test_video_file_and_grey_16bit_frames(tmp_path):
    # One sequence whether ../shared/data is there or not: this tests reading
    # videos and 16-bit frames, so its frames must not change with the data.
    # (With seed 4 on the procedural seabed the MJPG-compressed first pair was
    # measured wrong, confidence 0.11, and flagged, where the PNG frames give
    # 0.88: a detector weakness reported apart, not what this test is about.)
    frames, mats = _sequence("line", n=8, seed=0, source="procedural")
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
    # several videos in one list: each one's frames in turn, in the order given
    video2 = tmp_path / "dive2.avi"
    vw = cv2.VideoWriter(str(video2), cv2.VideoWriter_fourcc(*"MJPG"), 5.0, SHAPE[::-1])
    for f in frames[:3]:
        vw.write(f)
    vw.release()
    both = list_frames([str(video2), str(video)])
    assert both == [f"{video2}#{i}" for i in range(3)] + [f"{video}#{i}" for i in range(8)]
    two = run_odometry([str(video), str(video2)], tmp_path / "v2", progress=False, mosaic=False)
    assert [r["file"] for r in two.rows] == [f"{video}#{i}" for i in range(8)] + [
        f"{video2}#{i}" for i in range(3)]
    assert all(r["status"] != "unreadable" for r in two.rows)
    assert two.rows[7]["x"] == pytest.approx(res.rows[7]["x"])   # the first video as alone
    # one time line: the second video's frames come after the first's 8 (at 5 fps), not
    # at 0 again (a user's velocities from the time column were wrong)
    assert [r["time"] for r in two.rows] == pytest.approx([0.2 * i for i in range(11)])
    # each video as long as its frame count, whichever of its frames are listed; a video
    # listed again comes after the one before it (a reviewer's finds)
    from seahough.io.frames import FrameReader
    r = FrameReader([f"{video}#0", f"{video}#2", f"{video2}#1", f"{video}#1"], 10 ** 7)
    assert [r.time(i) for i in range(4)] == pytest.approx([0.0, 0.4, 1.6 + 0.2, 2.2 + 0.2])
    bad = tmp_path / "broken.avi"
    bad.write_bytes(b"not a video")
    with pytest.raises(seahough.ParameterError, match="broken.avi: (cannot open|.*no frame)"):
        list_frames([str(video), str(bad)])
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
    assert r["flags"].split(";")[0] in ("low_confidence", "no_match")
    # the last velocity carried on across the gap (and said so), then measured again
    assert r["flags"].endswith("; pose_assumed: constant velocity since frame 5")
    step = math.hypot(res.rows[5]["x"] - res.rows[4]["x"], res.rows[5]["y"] - res.rows[4]["y"])
    assert math.hypot(r["x"] - res.rows[5]["x"], r["y"] - res.rows[5]["y"]) == \
        pytest.approx(step, rel=0.01)
    assert all(q["status"] == "measured" for q in res.rows[7:])
    xy, _ = _true_track(mats)
    est = np.array([[q["x"], q["y"]] for q in res.rows])
    assert np.hypot(*(est[-1] - xy[-1])) < 3.0   # frame 7 was measured against the keyframe


def _errors(res, mats, keep):
    """Distance (px) of each row's position from the truth of the frame it shows."""
    xy, _ = _true_track(mats)
    return [math.hypot(r["x"] - xy[k][0], r["y"] - xy[k][1]) for r, k in zip(res.rows, keep)]


def test_a_jump_the_prior_cannot_explain_falls_back_to_the_full_search(tmp_path):
    # frames 6-8 of a 12 px/frame line dropped: a 48 px step where the prior
    # (the last motion, +-5 % of the frame around it) expects 12 px
    frames, mats = _sequence("line", n=16, seed=0)
    keep = [0, 1, 2, 3, 4, 5, 9, 10, 11, 12, 13, 14]
    res = run_odometry([frames[k] for k in keep], tmp_path, progress=False, mosaic=False)
    methods = [r["method"] for r in res.rows]
    assert methods[2:6] == ["prior"] * 4            # the prior at work before the jump
    assert methods[6] == "full"                     # the jump: the full search, on the keyframe
    assert res.rows[6]["ref"] == 0 and res.rows[6]["status"] == "measured"
    assert methods[-3:] == ["prior"] * 3            # and the prior again once it has the motion
    assert res.summary["flagged_pairs"] == 0
    assert max(_errors(res, mats, keep)) < 2.0      # the track stays on the truth


def test_after_a_scene_change_the_previous_frame_takes_over(tmp_path):
    # the camera is suddenly somewhere else (scene B): B's first frame cannot be
    # measured against the keyframe (scene A) and is flagged; B's second frame
    # cannot be either, but it can against the previous frame (B's first), which
    # then becomes the keyframe, and the track goes on with B's motion. (A jump
    # the keyframe can no longer see but the previous frame can also takes this
    # path, but only in a narrow band of overlaps that depends on the search's
    # tuning: the keyframe is kept while the next frame overlaps it by 60 %.)
    a, _ = _sequence("line", n=6, seed=0)
    b, mats_b = S.sequence(None, n_frames=5, frame_size=SHAPE, path="line", step=12.0,
                           seed=21, source="procedural")
    res = run_odometry(list(a) + list(b), tmp_path, progress=False, mosaic=False)
    rows = res.rows
    assert [r["status"] for r in rows[:6]] == ["origin"] + ["measured"] * 5
    assert rows[6]["status"] == "assumed" and "pose_assumed" in rows[6]["flags"]
    assert (rows[7]["status"], rows[7]["method"], rows[7]["ref"]) == ("measured", "previous", 6)
    assert rows[8]["ref"] == 6                      # B's first frame: the keyframe now
    assert all(r["status"] == "measured" for r in rows[8:])
    assert res.summary["methods"]["previous"] == 1 and res.summary["flagged_pairs"] == 2
    assert rows[7]["flags"].startswith("after_gap: ") and res.summary["after_gap"] == [7]
    # B's motion, from its first frame (where the track was left), matches its truth
    for k in range(1, 5):
        est = compose(np.asarray(rows[6 + k]["matrix"]).reshape(2, 3),
                      invert_matrix(np.asarray(rows[6]["matrix"]).reshape(2, 3)))
        c = [[(SHAPE[1] - 1) / 2.0, (SHAPE[0] - 1) / 2.0]]
        assert np.hypot(*(apply_matrix(est, c) - apply_matrix(mats_b[k], c))[0]) < 1.5


def _banded_frames(folder: Path, jumps):
    """Frames of a scene whose only texture is a band of rows (elsewhere a smooth
    gradient, no edges): frame 0 at the top, then two unreadable frames (so the
    search covers 3 frames of motion), then one frame per ``jumps`` (rows down).
    Frame 0's edges all lie in its rows 195-240: a frame ``j`` rows down sees
    them in its top 240 - j rows."""
    h, w = SHAPE
    yy, xx = np.mgrid[0:h + 300, 0:w].astype(np.float32)
    scene = 90 + 0.25 * xx + 0.08 * yy
    tex = S.seabed((h + 300, w), seed=3)
    tex = cv2.cvtColor(tex, cv2.COLOR_BGR2GRAY) if tex.ndim == 3 else tex
    scene[195:240] = tex[195:240]
    scene = np.clip(scene, 0, 255).astype(np.uint8)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, j in enumerate([0, None, None, *jumps]):
        p = folder / f"f{i}.png"
        if j is None:
            p.write_bytes(b"lost")
        else:
            cv2.imwrite(str(p), scene[j:j + h])
        paths.append(str(p))
    return paths


@pytest.mark.parametrize("jump, measured", [(190, True), (205, False)])
def test_too_little_overlap_is_flagged(tmp_path, jump, measured):
    # the same edges seen in 50 rows of the frame (21 %): measured; in 35 rows
    # (15 % of the frame, 13 % once cropped): found, confidently, but refused
    paths = _banded_frames(tmp_path / "f", [jump])
    res = run_odometry(paths, tmp_path / "o", progress=False, mosaic=False)
    r = res.rows[3]
    if measured:
        assert (r["status"], r["method"], r["flags"]) == ("measured", "full", "")
        assert r["overlap"] < 0.25
        assert r["y"] - res.rows[0]["y"] == pytest.approx(jump, abs=1.0)
    else:
        assert r["status"] == "assumed"
        assert r["flags"] == "little_overlap; pose_assumed: zero motion since frame 0"
        assert (r["x"], r["y"]) == (res.rows[0]["x"], res.rows[0]["y"])
        assert res.summary["assumed_poses"] == 1


def test_a_long_run_keeps_no_state_per_frame(tmp_path, monkeypatch):
    # a survey of 100,000 photos must not hold 100,000 rows: count the live
    # (garbage-collected) Python objects as the run goes, with a loop of frames
    # on disk listed over and over (the camera circles the same ground)
    import gc
    import seahough.motion.odometer as OM
    frames, _ = _sequence("loop", n=24, seed=12)
    paths = _write_frames(frames, tmp_path / "loop")
    seq = [paths[i % len(paths)] for i in range(150)]
    counts = {}
    advance = OM.advance

    def counting(st, row, tuning):
        advance(st, row, tuning)
        if row["index"] in (49, 149):
            gc.collect()
            counts[row["index"]] = len(gc.get_objects())

    monkeypatch.setattr(OM, "advance", counting)
    res = run_odometry(seq, tmp_path / "o", progress=False, mosaic=True)
    # (a row kept per frame was 3 objects: the dict and its two matrix lists)
    assert counts[149] - counts[49] < 30, counts
    assert res.summary["frames"] == 150 and res.summary["measured_pairs"] >= 140
    # the rows are still there when asked for: read back from the CSV
    assert res.rows == read_odometry_csv(res.csv_path) and len(res.rows) == 150
    assert res.summary["end_point"]["x"] == res.rows[-1]["x"]
    assert cv2.imread(str(res.mosaic_path)) is not None


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
import seahough.motion.odometry as O
from seahough.io.frames import FrameReader
raw = FrameReader.raw
delay = float(sys.argv[3]) if len(sys.argv) > 3 else 0.15
def slow(self, i):
    time.sleep(delay)
    return raw(self, i)
FrameReader.raw = slow
O.run_odometry(sys.argv[1], sys.argv[2], progress=False, mosaic=False)
"""


def _stopped_mid_run(tmp_path, script, sig, name):
    """A run of ``script`` over 14 frames, sent ``sig`` once 5 rows are
    written: ``(proc, stderr, frames folder, out, the uninterrupted run)``."""
    frames, _ = _sequence("line", n=14, seed=9)
    folder = tmp_path / "frames"
    _write_frames(frames, folder)
    full = run_odometry(folder, tmp_path / "full", progress=False, mosaic=False)
    out = tmp_path / name
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
    # (SIGINT at its default: a suite started in the background inherits it ignored)
    proc = subprocess.Popen([sys.executable, "-c", script, str(folder), str(out)], env=env,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    csv_path = out / "odometry.csv"
    err = ""
    try:
        deadline = time.time() + 60
        while time.time() < deadline:
            if csv_path.exists() and len(csv_path.read_text().splitlines()) >= 6:
                break
            if proc.poll() is not None:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the run ended before it could be stopped"
        os.kill(proc.pid, sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    return proc, err, folder, out, full


def _resumes_to(folder, out, full):
    done = read_odometry_csv(out / "odometry.csv")
    assert 5 <= len(done) < 14                                # stopped mid-run, rows kept
    res = run_odometry(folder, out, resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == len(done)
    assert _csv_without_timing(res.csv_path) == _csv_without_timing(full.csv_path)


def test_killed_run_resumes_to_the_same_result(tmp_path):
    _, _, folder, out, full = _stopped_mid_run(tmp_path, _KILL_SCRIPT, signal.SIGKILL, "killed")
    _resumes_to(folder, out, full)


_TERM_SCRIPT = """
import sys, time
from seahough.io.frames import FrameReader
raw = FrameReader.raw
def slow(self, i):
    time.sleep(0.15)
    return raw(self, i)
FrameReader.raw = slow
from seahough.cli import main
main(["odometry", sys.argv[1], "--out", sys.argv[2], "--no-mosaic", "--quiet", "-j", "1"])
"""


def test_sigterm_stops_the_command_like_ctrl_c_and_the_run_resumes(tmp_path):
    """``kill`` (SIGTERM: a batch system's time limit, ``docker stop``) stops
    ``seahough odometry`` as Ctrl-C does: one line, exit 143, the rows done are
    kept, and --resume finishes the run as an uninterrupted one."""
    proc, err, folder, out, full = _stopped_mid_run(tmp_path, _TERM_SCRIPT, signal.SIGTERM,
                                                    "term")
    assert proc.returncode == 143, err
    assert err.count("\n") == 1 and "terminated (SIGTERM)" in err and "Traceback" not in err
    # (what was kept, as Ctrl-C says it: a trial saw SIGTERM's line without the count)
    assert re.search(r"terminated \(SIGTERM\): \d+ frames? kept in .*odometry\.csv; the same "
                     r"command with --resume goes on from there", err), err
    _resumes_to(folder, out, full)


def test_ctrl_c_says_what_was_kept_and_how_to_go_on(tmp_path):
    proc, err, folder, out, full = _stopped_mid_run(tmp_path, _TERM_SCRIPT, signal.SIGINT,
                                                    "int")
    assert proc.returncode == 130, err
    (line,) = [ln for ln in err.splitlines() if ln]
    n = len(read_odometry_csv(out / "odometry.csv"))
    assert line == (f"seahough: error: interrupted: {n} frames kept in {out}/odometry.csv; "
                    "the same command with --resume goes on from there"), line
    _resumes_to(folder, out, full)


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


def _quat_matrix(x, y, z, w):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _sparus_poses(folder: Path, reading="world->camera"):
    """Times, rotations world -> camera and camera centres of the distinct poses.

    The CSV (``source world, target camera``, MANIFEST.tsv: "world->camera")
    holds the world -> camera transform, ``p_cam = R p_world + t``, quaternion
    x, y, z, w; the camera centre is ``C = -R^T t``. World z points down (C_z
    = +13.9 m, the depth) and the camera frame is the optical one: x right in
    the image, y down, z towards the seabed. (``reading="camera-in-world"``:
    the same numbers read as the camera's pose in the world, ``C = t`` and R
    camera -> world, for the test that this wrong reading fails.) The CSV
    repeats each pose at 10 Hz until the next one (~every 0.35 s): only the
    changes are kept."""
    rows = list(csv.DictReader(open(folder / "camera_poses_sparus_snippet.csv", newline="")))
    keys = []
    for r in rows:
        v = tuple(float(r[k]) for k in ("x", "y", "z", "qx", "qy", "qz", "qw"))
        if not keys or keys[-1][1] != v:
            keys.append((float(r["ts"]), v))
    ts = np.array([k[0] for k in keys])
    t = np.array([k[1][:3] for k in keys])
    rot = [_quat_matrix(*k[1][3:]) for k in keys]
    if reading == "world->camera":
        return ts, rot, np.array([-r.T @ v for r, v in zip(rot, t)])
    return ts, [r.T for r in rot], t


def _rotation_at(ts, rots, t):
    """Rotation at time ``t``: turned from the pose before towards the next one
    in proportion to the time (clamped to the span)."""
    t = min(max(t, ts[0]), ts[-1])
    j = min(int(np.searchsorted(ts, t, side="right")) - 1, len(ts) - 2)
    a = (t - ts[j]) / (ts[j + 1] - ts[j])
    rv, _ = cv2.Rodrigues(rots[j + 1] @ rots[j].T)
    step, _ = cv2.Rodrigues(rv * a)
    return step @ rots[j]


def _sparus_comparison(rows, folder: Path, reading="world->camera", axes="optical",
                       window=15):
    """The Sparus odometry against its poses: heading change, and direction
    of travel over ``window``-pair windows (15 pairs = 3 s).

    Frame i was taken at the video start (sparus_time_offset.yaml) + i /
    4.9988 s (MANIFEST.tsv). Direction of travel: where frame k+window's
    centre lies in frame k's pixels (from the odometry's matrices) against
    the camera's displacement in camera k's axes, R_k (C_k+window - C_k),
    whose (x, y) are image (right, down) for the optical camera frame
    (``axes="body"``: x = image up, y = image left, the vehicle convention
    an earlier version of this test assumed). Windows start and end inside
    the pose span. Returns the heading change of both over the whole run
    (degrees counter-clockwise as displayed), the signed direction
    differences (odometry - poses), their circular mean (one fixed offset)
    and the largest deviation from it."""
    offset = float((folder / "sparus_time_offset.yaml").read_text().split(":", 1)[1])
    ts, rots, centres = _sparus_poses(folder, reading)
    n = len(rows)
    tf = offset + np.arange(n) / 4.9988
    rf = [_rotation_at(ts, rots, t) for t in tf]
    cf = np.stack([np.interp(tf, ts, centres[:, k]) for k in range(3)], 1)

    def image(v):   # camera-frame vector -> image (x right, y down)
        return np.array([v[0], v[1]]) if axes == "optical" else np.array([-v[1], -v[0]])

    def angle(v):
        return math.degrees(math.atan2(v[1], v[0]))

    def wrap(a):
        return (a + 180.0) % 360.0 - 180.0

    # camera n-1's x axis seen in camera 0's image; on screen (y down) a turn
    # counter-clockwise is a negative atan2
    x_last = image(rf[0] @ rf[-1].T @ np.array([1.0, 0.0, 0.0]))
    turn_poses = -wrap(angle(x_last) - angle(image(np.array([1.0, 0.0, 0.0]))))
    mats = [np.asarray(r["matrix"]).reshape(2, 3) for r in rows]
    h, w = cv2.imread(rows[0]["file"], cv2.IMREAD_GRAYSCALE).shape
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    inside = (tf >= ts[0]) & (tf <= ts[-1])
    diffs = []
    for k in range(n - window):
        if not (inside[k] and inside[k + window]):
            continue
        seen = apply_matrix(compose(mats[k], invert_matrix(mats[k + window])), [c])[0] - c
        moved = image(rf[k] @ (cf[k + window] - cf[k]))
        diffs.append(wrap(angle(seen) - angle(moved)))
    d = np.radians(diffs)
    fixed = math.degrees(math.atan2(np.sin(d).mean(), np.cos(d).mean()))
    return {"turn_poses": turn_poses, "turn": rows[-1]["heading"] - rows[0]["heading"],
            "diffs": diffs, "offset": fixed,
            "spread": max(abs(wrap(x - fixed)) for x in diffs)}


def _sparus_agrees(cmp) -> bool:
    """The heading change within 5 degrees, and the direction of travel off by
    one fixed angle (20-40 degrees: this data's yaw offset between the pose
    'camera' frame and the image axes) give or take 6 degrees in every 3 s
    window."""
    return (abs(cmp["turn"] - cmp["turn_poses"]) < 5.0 and cmp["spread"] < 6.0
            and 20.0 < cmp["offset"] < 40.0)


def test_sparus_agrees_with_its_camera_poses(real_runs):
    folder = data_path("sequences", "sparus_auv_seabed")
    res = real_runs("sparus_auv_seabed")
    cmp = _sparus_comparison(res.rows, folder)
    # the poses: a steady turn of ~23 degrees counter-clockwise in the image
    # (-23 about the downward optical axis); the camera centre a smooth track
    assert cmp["turn_poses"] == pytest.approx(22.9, abs=1.0)
    ts, _, centres = _sparus_poses(folder)
    speeds = np.hypot(*np.diff(centres[:, :2], axis=0).T) / np.diff(ts)
    assert centres[0, 2] == pytest.approx(13.94, abs=0.05) and speeds.max() < 0.25
    # the odometry: the same turn (measured ~25.5), and its direction of travel
    # off by one fixed angle (~+30) within ~2.5 degrees over the six 3 s windows
    assert len(cmp["diffs"]) == 6
    assert _sparus_agrees(cmp), cmp
    # the test is not blind: the other readings of the same numbers fail it
    # (camera-in-world with optical axes: the turn is -23; with the vehicle's
    # axes, as this test once assumed: the turn agrees but the direction wanders
    # by ~30 degrees, since t = -R C swings with every tilt of the camera)
    for reading, axes in (("camera-in-world", "optical"), ("camera-in-world", "body"),
                          ("world->camera", "body")):
        wrong = _sparus_comparison(res.rows, folder, reading, axes)
        assert not _sparus_agrees(wrong), (reading, axes, wrong)


def _step_disagreements(tmp_path, sequence, limit=10.0, config=None):
    """Frames of a real sequence whose dead-reckoned step (frame i -> i+1)
    differs by more than ``limit`` px at the corners from estimate_motion on
    the same pair (where that is confident), and how many pairs were compared."""
    folder = data_path("sequences", sequence)
    files = [str(p) for p in list_frames(folder)]
    kw = {} if config is None else {"config": config}
    rows = run_odometry(files, tmp_path, mosaic=False, progress=False, **kw).rows
    shape = seahough.to_gray(files[0]).shape
    h, w = shape
    grid = np.array([[x, y] for x in np.linspace(0, w - 1, 5) for y in np.linspace(0, h - 1, 5)])
    bad, compared = [], 0
    for a, b in zip(rows, rows[1:]):
        if b["status"] != "measured" or a["status"] not in ("origin", "measured"):
            continue
        m = seahough.estimate_motion(files[a["index"]], files[b["index"]])
        if m is None or m.confidence < 0.2 or m.homography is not None:
            continue  # no reference (below 0.2 a detection is flagged ambiguous: on this
            # pool estimate_motion once answered a 37 px jump at 0.17 between two frames
            # that every other pair says moved a few px; a pair it measured as a
            # homography, coarse to fine, reports the homography's least-squares
            # similarity over the frame: on the pool's perspective change 15-33 px
            # from the vote's, which the dead reckoning reports against an older
            # keyframe; its searches of the adjacent frame are measured the same way)
        step = compose(np.reshape(b["matrix"], (2, 3)), invert_matrix(np.reshape(a["matrix"], (2, 3))))
        err = float(np.max(np.hypot(*(apply_matrix(step, grid) - apply_matrix(m.matrix, grid)).T)))
        compared += 1
        if err > limit:
            bad.append((b["index"], round(err, 1), b["method"], b["confidence"]))
    return bad, compared


@functools.lru_cache(maxsize=4)
def _sift_features(path):
    """SIFT key points and descriptors of an image file (each frame of a
    sequence is in two pairs: computed once)."""
    return cv2.SIFT_create().detectAndCompute(cv2.imread(path, cv2.IMREAD_GRAYSCALE), None)


def _sift_similarity(a, b):
    """SIFT + ratio test + RANSAC similarity from image file ``a`` to ``b``
    (an independent reference), and its number of inliers."""
    (ka, da), (kb, db) = _sift_features(a), _sift_features(b)
    # FLANN k-d trees (a brute-force matcher took 5 s a pool pair, FLANN 0.5 s), their
    # randomness seeded
    cv2.setRNGSeed(0)
    flann = cv2.FlannBasedMatcher(dict(algorithm=1, trees=5), dict(checks=50))
    good = [p for p, q in flann.knnMatch(da, db, k=2) if p.distance < 0.75 * q.distance]
    src = np.float32([ka[m.queryIdx].pt for m in good])
    dst = np.float32([kb[m.trainIdx].pt for m in good])
    m, inliers = cv2.estimateAffinePartial2D(src, dst, method=cv2.RANSAC,
                                             ransacReprojThreshold=3.0)
    return m, int(inliers.sum())


def test_every_pool_step_agrees_with_an_independent_feature_fit(tmp_path):
    # the tiled pool (a forward-oblique camera): no step may be a tile-shifted
    # look-alike (37-40 px) or a keyframe answer a few frames back that drifted
    # off. Every measured step against SIFT+RANSAC on the same pair (600+
    # inliers on each): within 2 % of the diagonal (29 px). Until a confident
    # vote over a repeated texture was checked at the coarse scale
    # (pair.REPEATED, 2026-12-06), two steps on the prior against keyframe 4
    # were 50-60 px off; now at most 27 px (steps 4 and 5, 23 and 27 px: the
    # mosaic's small tiles, one apart, remain), the others 2-13 px. (Not
    # against estimate_motion's vote: on this pool it is itself 25-30 px from
    # SIFT on three pairs, confident look-alikes of the small tiles.)
    files = [str(p) for p in list_frames(data_path("sequences", "subvo_pool_chain"))]
    rows = run_odometry(files, tmp_path, mosaic=False, progress=False, workers=1).rows
    h, w = seahough.to_gray(files[0]).shape
    grid = np.array([[x, y] for x in np.linspace(0, w - 1, 5) for y in np.linspace(0, h - 1, 5)])
    errors = []
    for a, b in zip(rows, rows[1:]):
        assert b["status"] == "measured", b
        step = compose(np.reshape(b["matrix"], (2, 3)), invert_matrix(np.reshape(a["matrix"], (2, 3))))
        ref, inliers = _sift_similarity(files[a["index"]], files[b["index"]])
        assert inliers >= 600
        errors.append(float(np.max(np.hypot(*(apply_matrix(step, grid) - apply_matrix(ref, grid)).T))))
    assert max(errors) < 0.02 * math.hypot(w, h), [round(e, 1) for e in errors]


def test_an_aging_keyframe_of_a_scene_in_relief_gives_way_to_the_nearer_frame(tmp_path):
    # the amphora wreck (3-D relief): a keyframe three frames back measured
    # frame 17 14 px off at the corners (confidence 0.29) where the adjacent
    # frame (0.73) agrees with estimate_motion; the doubtful-keyframe check let
    # it stand while its threshold was two translation bins (36 px here)
    bad, compared = _step_disagreements(tmp_path, "aqualoc_amphorae_wreck", limit=10.0)
    assert bad == [] and compared >= 15, (bad, compared)


def test_a_full_search_off_the_prior_is_checked_against_the_adjacent_frame(tmp_path):
    # The real tiled pool cropped by 3 px (the pixel grid moved, nothing else):
    # the prior failed at frame 8, and the full search against keyframe 5,
    # right after a step measured on the prior, went a tile off (6.8 % of the
    # diagonal at confidence 0.59, NFA 7e-98). Every full search's answer is
    # now checked against the adjacent frame, which was right: each step
    # agrees with estimate_motion on its own pair.
    from seahough.geometry import corner_gap
    files = list_frames(data_path("sequences", "subvo_pool_chain"))
    frames = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE)[3:, 3:] for f in files]
    rows = run_odometry(frames, tmp_path / "run", progress=False, mosaic=False, workers=1).rows
    diag = math.hypot(*frames[0].shape)
    row = rows[8]
    assert row["status"] == "measured" and row["ref"] == 7, row
    step = np.asarray(row["pair_matrix"], float).reshape(2, 3)
    pair = seahough.estimate_motion(frames[7], frames[8])
    assert corner_gap(step, pair.matrix, frames[0].shape) < 0.01 * diag


def test_an_nfa_limit_is_a_choice_of_the_dead_reckoning(tmp_path):
    # frames enlarged into a blur (a small photo over a long turn): some pairs
    # are measured at an NFA over 1. Reported, not judged by default (there
    # they were as often right as wrong); OdometryTuning(max_nfa=1) flags them
    photo = S.seabed((72, 108), seed=1)
    frames, _ = S.sequence(photo, n_frames=30, frame_size=(180, 240), path="turn", step=9,
                           seed=0)
    runs = {}
    for mx in (math.inf, 1.0):
        rows = run_odometry(frames, tmp_path / str(mx), progress=False, mosaic=False, workers=1,
                            tuning=seahough.OdometryTuning(max_nfa=mx)).rows[1:]
        runs[mx] = rows
    weak = [r["index"] for r in runs[math.inf] if r["status"] == "measured" and r["nfa"] > 1.0]
    assert weak and not any(r["flags"] for r in runs[math.inf]), weak
    strict = {r["index"]: r for r in runs[1.0]}
    assert all(r["nfa"] <= 1.0 for r in strict.values() if r["status"] == "measured")
    assert any(strict[i]["status"] == "assumed" for i in weak), weak


@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_a_net_is_followed_by_its_velocity_and_says_so(tmp_path, jitter):
    """A 40 px mesh crossed at 23 px a frame: a step moved by a mesh cell
    fits the edges as well. A net-pen trial's track went back and forth,
    320 px off, nothing flagged, exit 0. Each such step is now the copy
    nearest the constant velocity's prediction, flagged ``repeated_texture``;
    a perfect mesh's first step (no velocity yet) is the vote's copy, and
    says so (its track is then off by a cell a frame: flagged throughout)."""
    frames, mats = S.sequence(S.net((1200, 1600), mesh=40, seed=2, jitter=jitter,
                                    holes=0.005 * (jitter > 0)),
                              n_frames=8, frame_size=(240, 320), path="line", step=23.0, seed=2)
    rows = run_odometry(frames, tmp_path, progress=False, mosaic=False, workers=1).rows
    flagged = [r["flags"] for r in rows[1:]]
    assert all(f.startswith("repeated_texture: the step is known up to the texture's period")
               for f in flagged[1:]), flagged
    xy, _ = _true_track(mats, (240, 320))
    est = np.array([[r["x"], r["y"]] for r in rows])
    if jitter:    # (the first step, the vote's, was right: the rest follow)
        assert np.hypot(*(est - xy).T).max() < 3.0
    else:
        assert "the vote's copy (no velocity known yet)" in flagged[0]
