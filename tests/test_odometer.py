"""Dead reckoning one frame at a time (seahough.Odometer): a camera's stream
on a vehicle's own computer. The same rows as run_odometry for the same
frames; dropped (None), duplicated and resized frames; a good frame right
after a bad one."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as S
from seahough.motion import run_odometry

from conftest import DATA
from test_odometry import SHAPE

H, W = SHAPE


def _line(n=8, seed=7):
    return S.sequence(None, n_frames=n, frame_size=SHAPE, path="line", step=12.0, seed=seed,
                      source="procedural")


def test_odometer_gives_run_odometrys_rows_frame_by_frame(tmp_path):
    frames, _ = _line()
    odo = seahough.Odometer(metres_per_pixel=0.004, fps=2.0)
    rows = [odo.push(f) for f in frames]
    ref = run_odometry(frames, tmp_path, metres_per_pixel=0.004, fps=2.0, progress=False,
                       mosaic=False).rows
    assert [r["status"] for r in rows] == [r["status"] for r in ref]
    assert rows[0]["status"] == "origin" and all(r["status"] == "measured" for r in rows[1:])
    for a, b in zip(rows, ref):
        assert set(a) == set(b)
        assert (a["ref"], a["method"], a["flags"], a["file"]) == (b["ref"], b["method"], b["flags"],
                                                                  b["file"])
        assert a["time"] == pytest.approx(b["time"]) and a["index"] == b["index"]
        np.testing.assert_allclose(a["matrix"], b["matrix"], atol=1e-3)   # (the CSV rounds)
        for k in ("x", "y", "x_m", "y_m", "heading", "confidence"):
            assert a[k] == pytest.approx(b[k], abs=1e-3), k
        assert a["frame_hash"] == b["frame_hash"] and a["settings_hash"] == b["settings_hash"]
    assert isinstance(rows[3]["x"], float) and len(rows[3]["pair_matrix"]) == 6
    # a given time comes first; reset starts a new track at frame 0
    assert odo.push(frames[0], time=12.5)["time"] == 12.5
    odo.reset()
    r = odo.push(frames[2], name="cam0.png")
    assert (r["index"], r["status"], r["file"], r["x"]) == (0, "origin", "cam0.png", rows[0]["x"])


def test_a_dropped_frame_is_an_unreadable_row_and_the_next_one_is_measured(tmp_path):
    """A user's trial: the camera driver gives None for a dropped frame. The
    Odometer and run_odometry take it as an unreadable frame (run_odometry
    refused the whole list: "unexpected item NoneType; expected paths")."""
    frames, _ = _line(6)
    given = frames[:3] + [None] + frames[4:]
    odo = seahough.Odometer()
    rows = [odo.push(f) for f in given]
    ref = run_odometry(given, tmp_path, progress=False, mosaic=False).rows
    for got in (rows, ref):
        assert got[3]["status"] == "unreadable" and got[3]["x"] is None
        assert got[3]["flags"] == "unreadable: no frame (None: a dropped frame)"
        assert got[4]["status"] == "measured" and got[4]["ref"] <= 2 and got[4]["flags"] == ""
    with pytest.raises(seahough.ParameterError, match=r"frames: item 1 \(int\) is not an image path"):
        run_odometry([frames[0], 5], tmp_path / "bad", progress=False)


def test_a_duplicated_frame_is_flagged_not_measured_as_zero_motion(tmp_path):
    """A user's trial: a camera driver handing the same buffer twice gave a
    measured zero motion at confidence 0.98 (halving the speed over it). Its
    motion is not known: the pose is assumed (constant velocity), flagged."""
    frames, _ = _line(7)
    given = frames[:4] + [frames[3].copy()] + frames[4:6]
    odo = seahough.Odometer()
    rows = [odo.push(f) for f in given]
    ref = run_odometry(given, tmp_path, progress=False, mosaic=False).rows
    for got in (rows, ref):
        dup = got[4]
        assert dup["status"] == "assumed", dup
        assert dup["flags"] == ("duplicate: the same pixels as frame 3; "
                                "pose_assumed: constant velocity since frame 3")
        assert dup["y"] != got[3]["y"]                       # carried on, not stopped
        assert [r["status"] for r in got[5:]] == ["measured", "measured"]
    # a frame only like the last one (not the same pixels) is measured
    near = frames[3].astype(np.int16)
    near[0, 0] += 1
    odo2 = seahough.Odometer()
    got = [odo2.push(f) for f in frames[:4] + [np.clip(near, 0, 255).astype(np.uint8)]]
    assert got[4]["status"] == "measured"


def test_a_frame_of_another_size_is_unreadable_until_reset():
    frames, _ = _line(4)
    odo = seahough.Odometer()
    odo.push(frames[0])
    big = np.zeros((H + 40, W + 40, 3), np.uint8)
    big[:H, :W] = frames[1]
    r = odo.push(big)
    assert r["status"] == "unreadable"
    assert r["flags"] == f"unreadable: size {W + 40}x{H + 40} differs from the first frame's {W}x{H}"
    assert odo.push(frames[2])["status"] == "measured"
    odo.reset()
    assert odo.push(big)["status"] == "origin"


def test_odometer_refuses_bad_settings_by_name():
    with pytest.raises(seahough.ParameterError, match="fps"):
        seahough.Odometer(fps=0)
    with pytest.raises(seahough.ParameterError, match="config must be a seahough.Config"):
        seahough.Odometer(config={})
    with pytest.raises(seahough.ParameterError, match="time"):
        seahough.Odometer().push(np.zeros((80, 80), np.uint8), time="noon")


@pytest.mark.parametrize("seed", [0, 3])
def test_a_good_frame_after_one_bad_frame_is_measured(tmp_path, seed):
    """A user's trial: frames cut from a real photo (the simulator's choice
    for these seeds: a murky Sparus frame), frame 6 replaced by a frame of
    somewhere else, and frame 7 was flagged too (4 of 10 seeds): its
    keyframe was 5 frames back and the last try (the last measured frame,
    frame 5, with twice the motion's ranges and shift, the vote alone) too
    wide to vote. After a gap the last measured frame gets a full search of
    its own, measured as estimate_motion measures a pair."""
    if DATA is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    frames, _ = S.sequence(None, n_frames=12, frame_size=SHAPE, path="line", step=12.0,
                           seed=seed, source="auto")
    frames = list(frames)
    frames[6] = S.seabed(SHAPE, seed=99)
    rows = run_odometry(frames, tmp_path, progress=False, mosaic=False).rows
    assert rows[6]["status"] == "assumed"
    assert [r["status"] for r in rows[7:]] == ["measured"] * 5, [r["flags"] for r in rows]
    assert rows[7]["ref"] == 5 and rows[7]["flags"] == "" and rows[7]["method"] == "recover"


def test_an_empty_config_is_refused_not_taken_for_the_default(tmp_path):
    """``config or DEFAULT`` took an empty dict (or any empty mapping) for
    "no config" and searched with the defaults without a word."""
    img = np.zeros((80, 80), np.uint8)
    calls = [lambda: seahough.Detector(seahough.Pattern.rectangle(20, 10), config={}),
             lambda: seahough.estimate_motion(img, img, config={}),
             lambda: seahough.Odometer(config={}),
             lambda: seahough.Odometer(tuning={}),
             lambda: run_odometry([img, img], tmp_path, config={}, progress=False)]
    for call in calls:
        with pytest.raises(seahough.ParameterError, match="must be a seahough"):
            call()


def _strict(text):
    """JSON as strict readers (jq, JavaScript) take it: no Infinity, no NaN."""
    import json

    def refuse(c):
        raise ValueError(f"not JSON: {c}")
    return json.loads(text, parse_constant=refuse)


def test_summary_and_cli_json_are_strict_json(tmp_path, capsys):
    """A user's trial: summary.json and `odometry --json` held
    ``"max_nfa": Infinity``, which jq and JavaScript refuse."""
    from seahough.cli import main

    frames, _ = _line(3)
    res = run_odometry(frames, tmp_path / "a", progress=False, mosaic=False)
    s = _strict(res.json_path.read_text())
    assert s["settings"]["tuning"]["max_nfa"] is None
    assert res.summary["settings"]["tuning"]["max_nfa"] == float("inf")   # (Python keeps it)
    folder = tmp_path / "frames"
    folder.mkdir()
    import cv2
    for k, f in enumerate(frames):
        cv2.imwrite(str(folder / f"f{k}.png"), f)
    with pytest.raises(SystemExit) as exit_:
        main(["odometry", str(folder), "--out", str(tmp_path / "b"), "--json", "-q"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert _strict(out)["summary"]["settings"]["tuning"]["max_nfa"] is None


def test_measure_motion_says_why_there_is_no_motion(caplog):
    """A user's trial: why estimate_motion returned None was only logged;
    a vehicle's fallback needs it as a value (measure_motion)."""
    import logging

    prev, cur, truth = S.frame_pair(seed=4, source="procedural")
    res = seahough.measure_motion(prev, cur)
    assert res and res.reason == "" and res.motion == seahough.estimate_motion(prev, cur)
    assert res.best == res.motion
    blank = np.full_like(prev, 90)
    for a, b, why in ((blank, cur, "the previous frame has no edges"),
                      (prev, blank, "the current frame has no edges")):
        r = seahough.measure_motion(a, b)
        assert not r and r.motion is None and r.best is None and r.reason.startswith(why)
    with caplog.at_level(logging.INFO, logger="seahough.motion"):
        declined = seahough.measure_motion(prev, cur, min_confidence=1.0)
        assert seahough.estimate_motion(prev, cur, min_confidence=1.0) is None
    assert declined.motion is None and declined.reason.startswith("confidence ")
    assert "under min_confidence 1" in declined.reason
    assert f"no motion: {declined.reason}" in caplog.text            # the same words
    assert abs(declined.best.angle - truth.angle) < 0.5 and declined.best.confidence < 1.0
    # a frame with a border: the best motion is in whole-frame pixels too
    from seahough.geometry import shift_origin

    framed = [np.pad(f, ((12, 0), (20, 0), (0, 0))) for f in (prev, cur)]
    r = seahough.measure_motion(*framed, min_confidence=1.0)
    np.testing.assert_allclose(r.best.matrix, shift_origin(declined.best.matrix, -20, -12),
                               atol=0.5)


def test_pushes_from_two_threads_are_taken_in_turn_and_the_frame_is_copied():
    """A user's trial: two threads pushing into one Odometer broke it
    ("'NoneType' object is not callable", two rows of index 1); and a
    float32 frame whose pixels were all kept (no border cropped) stayed the
    caller's buffer, which a camera driver refills: the keyframe changed
    under the Odometer (dy 0.0 where copies gave 10.7)."""
    import threading

    frames, _ = _line(9)
    odo = seahough.Odometer()
    rows, errors = [], []
    lock = threading.Lock()
    todo = list(frames)

    def worker():
        while True:
            with lock:
                if not todo:
                    return
                f = todo.pop(0)
            try:
                rows.append(odo.push(f))
            except Exception as e:     # pragma: no cover - the failure this test catches
                errors.append(e)
    threads = [threading.Thread(target=worker) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and sorted(r["index"] for r in rows) == list(range(9))
    # a refilled buffer
    # (66 px strips: frames so small keep every pixel, no border cropped, no copy made)
    grey = [np.ascontiguousarray(cv2.cvtColor(f, cv2.COLOR_BGR2GRAY)[80:146]).astype(np.float32)
            for f in frames[:4]]
    ref = seahough.Odometer()
    want = [ref.push(g.copy()) for g in grey]
    buf = np.empty_like(grey[0])
    odo = seahough.Odometer()
    got = []
    for g in grey:
        buf[...] = g
        got.append(odo.push(buf))
    import copy
    import pickle

    assert pickle.loads(pickle.dumps(odo))._next == odo._next == 4   # (the lock not pickled)
    assert copy.deepcopy(ref)._next == 4
    assert [r["dy"] for r in got[1:]] == pytest.approx([r["dy"] for r in want[1:]], abs=1e-6)
    with pytest.raises(seahough.ImageValueError, match="frame: expected a numpy array"):
        odo.push([[1, 2], [3, 4]])


def test_frames_of_two_videos_pushed_are_on_one_time_line(tmp_path):
    """A video analyst's trial: run_odometry puts a dive's videos on one time
    line, but Odometer.push of the second video's frames restarted at 0 (a
    velocity across the change went backwards in time)."""
    from conftest import moving_rectangle_video

    a = moving_rectangle_video(tmp_path / "a.mp4", 4)       # 5 fps: 0.8 s
    b = moving_rectangle_video(tmp_path / "b.mp4", 3, start=(140, 80))
    names = [f"{a}#{k}" for k in range(4)] + [f"{b}#{k}" for k in range(3)]
    odo = seahough.Odometer()
    times = [odo.push(n)["time"] for n in names]
    assert times == pytest.approx([0.0, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2])
    ref = run_odometry([a, b], tmp_path / "run", progress=False, mosaic=False).rows
    assert [r["time"] for r in ref] == pytest.approx(times)
    odo.reset()                      # a new track: its own time line
    assert odo.push(names[4])["time"] == pytest.approx(0.0)
    assert seahough.Odometer().push(names[5], time=7.0)["time"] == 7.0   # (given: kept)
