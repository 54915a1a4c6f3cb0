"""Dead reckoning that never stalls silently (issue 13, point 5).

A pair that the keyframe, the full search and the previous frame cannot
measure gets a last, wider try (``wide``); a pair that still cannot be
measured is flagged with what happened (``no_match``, ``low_confidence``,
``little_overlap``, ``few_edges``) and its pose carries the last velocity on (``pose_assumed:
constant velocity since frame N``), never zero motion once a motion is known;
the mosaic leaves assumed poses out and says so; a resumed run stays exact.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

import seahough.motion.odometry as O
import seahough.motion.odometer as OM
from seahough import sim as S
from seahough.errors import ParameterError
from seahough.geometry import apply_matrix, compose, invert_matrix
from seahough.motion import run_odometry
from seahough.viz import plot_trajectory

from test_odometry import _csv_without_timing, _true_track, _write_frames

SHAPE = (240, 320)
H, W = SHAPE
CORNERS = np.array([[0.0, 0.0], [W - 1.0, 0.0], [0.0, H - 1.0], [W - 1.0, H - 1.0]])


# ----------------------------------------------------------------------------- helpers
def _line(n=12, seed=7):
    """A simulated straight line (procedural seabed, moderate water, 12 px a
    frame with a seeded jitter of speed and heading) and its truth."""
    return S.sequence(None, n_frames=n, frame_size=SHAPE, path="line", step=12.0, seed=seed,
                      source="procedural")


def _with_gap(frames, k, kind="unrelated"):
    """The frames with frame ``k`` replaced by an unrelated image."""
    frames = list(frames)
    if kind == "unrelated":
        frames[k] = S.seabed(SHAPE, seed=99)                # a frame of somewhere else
    else:
        frames[k] = np.random.default_rng(5).integers(0, 256, (H, W, 3), np.uint8)  # noise
    return frames


def _matrix(row):
    return np.asarray(row["matrix"], float).reshape(2, 3)


def _corner_error(est, truth) -> float:
    """Largest distance (px) between where two cumulative matrices put the frame's corners."""
    return float(np.max(np.hypot(*(apply_matrix(est, CORNERS) - apply_matrix(truth, CORNERS)).T)))


_SCENE = None


def _cut(x, y, angle=0.0):
    """A frame cut exactly from one large procedural seabed: its centre at
    scene pixel (x, y), turned ``angle`` degrees; returns the frame and its
    scene -> frame matrix (so the truth between any two frames is exact)."""
    global _SCENE
    if _SCENE is None:
        _SCENE = S.seabed((700, 1400), seed=5)
    c = np.array([(W - 1) / 2.0, (H - 1) / 2.0])
    a = math.radians(angle)
    rot = np.array([[math.cos(a), math.sin(a)], [-math.sin(a), math.cos(a)]])
    m = np.hstack([rot, (c - rot @ np.array([x, y], float))[:, None]])
    return cv2.warpAffine(_SCENE, m, (W, H), flags=cv2.INTER_LINEAR), m


def _cut_run(tmp_path, poses, **kw):
    """run_odometry over frames cut at ``poses``; the rows and each row's
    corner error against the exact truth."""
    frames, ms = zip(*(_cut(*p) for p in poses))
    res = run_odometry(list(frames), tmp_path, progress=False, mosaic=False, **kw)
    inv0 = invert_matrix(ms[0])
    errors = [_corner_error(_matrix(r), compose(m, inv0)) for r, m in zip(res.rows, ms)]
    return res, errors


# ---------------------------------------------------------------- a frame that cannot be measured
@pytest.mark.parametrize("kind", ["unrelated", "noise"])
def test_a_bad_frame_carries_the_last_velocity_on(tmp_path, kind):
    frames, mats = _line()
    xy, _ = _true_track(mats)
    res = run_odometry(_with_gap(frames, 6, kind), tmp_path / "gap", progress=False)
    rows = res.rows
    gap = rows[6]
    assert gap["status"] == "assumed" and gap["ref"] is None and gap["method"] == ""
    why, _, assumed = gap["flags"].partition("; ")
    assert why in ("no_match", "low_confidence")
    assert assumed == "pose_assumed: constant velocity since frame 5"
    # the pose is frame 5's carried on by the motion from 4 to 5 (the last velocity) ...
    vel = compose(_matrix(rows[5]), invert_matrix(_matrix(rows[4])))
    expected = compose(vel, _matrix(rows[5]))
    np.testing.assert_allclose(_matrix(gap), expected, atol=1e-9)
    step = math.hypot(rows[5]["x"] - rows[4]["x"], rows[5]["y"] - rows[4]["y"])
    assert 10.0 < step < 14.0                                  # (12 px a frame, jittered)
    moved = math.hypot(gap["x"] - rows[5]["x"], gap["y"] - rows[5]["y"])
    assert moved == pytest.approx(step, rel=0.01)              # not zero motion
    # ... which is near where the camera was: within 2 px of the truth, where
    # zero motion would be a whole step (about 12 px) off
    assert math.hypot(gap["x"] - xy[6][0], gap["y"] - xy[6][1]) < 2.0
    assert math.hypot(rows[5]["x"] - xy[6][0], rows[5]["y"] - xy[6][1]) > 9.0
    assert gap["dx"] is not None                              # its step is the velocity's
    # the next frame is measured again, and so is the rest
    assert all(r["status"] == "measured" for r in rows[7:])
    assert rows[7]["ref"] != 6                                 # not from the assumed pose
    # the summary and the mosaic say what was assumed and left out
    s = json.loads(res.json_path.read_text())
    assert s["assumed_poses"] == 1 and s["flagged_pairs"] == 1
    assert s["mosaic_left_out"] == 1 == res.summary["mosaic_left_out"]
    assert cv2.imread(str(res.mosaic_path)) is not None
    # the end point is as accurate as without the bad frame
    clean = run_odometry(frames, tmp_path / "clean", progress=False, mosaic=False)
    assert clean.summary["flagged_pairs"] == 0 and clean.summary["mosaic_left_out"] is None
    end = math.hypot(rows[-1]["x"] - xy[-1][0], rows[-1]["y"] - xy[-1][1])
    end_clean = math.hypot(clean.rows[-1]["x"] - xy[-1][0], clean.rows[-1]["y"] - xy[-1][1])
    assert end < 2.0 and end < end_clean + 0.5, (end, end_clean)


def test_assumed_poses_never_feed_the_velocity(tmp_path):
    # two bad frames in a row: both carried on by the velocity measured
    # before them (the first assumed pose does not become the second's
    # velocity), and the frame after them is measured across the gap
    frames, mats = _line(n=14, seed=3)
    frames = _with_gap(_with_gap(frames, 6), 7, "noise")
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    rows = res.rows
    vel = compose(_matrix(rows[5]), invert_matrix(_matrix(rows[4])))
    for k, n in ((6, 1), (7, 2)):
        assert rows[k]["status"] == "assumed"
        assert rows[k]["flags"].endswith("pose_assumed: constant velocity since frame 5")
        expected = compose(np.linalg.matrix_power(np.vstack([vel, [0, 0, 1]]), n)[:2],
                           _matrix(rows[5]))
        np.testing.assert_allclose(_matrix(rows[k]), expected, atol=1e-6)
    assert all(r["status"] == "measured" for r in rows[8:])
    xy, _ = _true_track(mats)
    assert math.hypot(rows[-1]["x"] - xy[-1][0], rows[-1]["y"] - xy[-1][1]) < 3.0


def test_with_no_motion_measured_yet_zero_motion_is_assumed(tmp_path):
    # the second frame unrelated: no velocity is known, the pose stays the
    # origin's, and the flag says so
    frames, _ = _line(n=6, seed=2)
    res = run_odometry(_with_gap(frames, 1), tmp_path, progress=False, mosaic=False)
    r = res.rows[1]
    assert r["status"] == "assumed"
    assert r["flags"].split("; ")[1] == "pose_assumed: zero motion since frame 0"
    assert (r["x"], r["y"], r["heading"]) == (res.rows[0]["x"], res.rows[0]["y"], 0.0)


def test_frames_without_edges_are_flagged_few_edges_not_no_match(tmp_path):
    """Open water before the seabed comes into view (flat frames), then a blank
    frame in the middle: the pairs that cannot be measured say why (few_edges);
    a frame of somewhere else, which has edges, is not few_edges."""
    frames, _ = _line(n=8, seed=2)
    flat = np.full_like(frames[0], 90)
    frames = [flat, flat] + list(frames[:3]) + [flat] + list(frames[3:5]) + [
        S.seabed(SHAPE, seed=99)]                          # a frame of somewhere else
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    why = [r["flags"].split("; ")[0] if r["flags"] else "" for r in res.rows]
    assert why[1] == why[2] == "few_edges"      # the first keyframe is open water
    # the seabed: measured, from frame 2 on, whose place (the origin's) is a guess
    assert why[3] == "after_gap: measured against frame 2, whose pose was assumed"
    assert why[4] == ""
    assert why[5] == "few_edges"                # a blank frame
    assert why[6] == why[7] == "", why
    assert why[8] in ("no_match", "low_confidence"), why   # edges, but not these


def test_a_surveys_folder_is_not_mixed_with_a_dead_reckoning(tmp_path):
    """run_odometry into a folder of survey detect's results is refused, and
    nothing of it is written there."""
    from seahough.errors import ParameterError

    frames, _ = _line(n=3)
    (tmp_path / "survey.json").write_text("{}")
    with pytest.raises(ParameterError, match="holds the results of a survey detect"):
        run_odometry(frames, tmp_path, progress=False, mosaic=False)
    assert not (tmp_path / "odometry.csv").exists()


def test_the_trajectory_picture_marks_assumed_poses(tmp_path):
    frames, _ = _line()
    res = run_odometry(_with_gap(frames, 6), tmp_path, progress=False, mosaic=False)
    fig = plot_trajectory(res.rows)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert "pose assumed (1)" in labels
    assert not any(lab.startswith("flagged") for lab in labels)  # (not drawn twice)
    # a hollow marker, at the assumed position
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "pose assumed (1)")
    assert line.get_markerfacecolor() == "none"      # (hollow: the start shows through)
    assert (line.get_xdata()[0], line.get_ydata()[0]) == (res.rows[6]["x"], res.rows[6]["y"])
    # the title splits its flagged frames as the legend does (a video analyst read "2
    # flagged" over "flagged (1)" and "pose assumed (1)")
    n = sum(1 for r in res.rows if r["flags"])
    title = fig.axes[0].get_title()
    assert title.endswith(f"{n} flagged (1 pose assumed)"), (title, n)


# ---------------------------------------------------------------- the wide last try
def test_a_jump_beyond_the_full_search_is_measured_by_the_wide_try(tmp_path, monkeypatch):
    # 12 px a frame along x, then a jump of 190 px: more than the full
    # search's +-half a frame (160 px), within the wide try's whole frame
    poses = [(400 + 12 * k, 350) for k in range(6)] + [(650 + 12 * k, 350) for k in range(4)]
    res, errors = _cut_run(tmp_path / "a", poses)
    r = res.rows[6]
    assert (r["status"], r["method"], r["ref"], r["flags"]) == ("measured", "wide", 5, "")
    assert r["confidence"] >= 0.2 and r["overlap"] >= 0.15     # the usual checks held
    assert r["dx"] == pytest.approx(-190.0, abs=0.5)           # content moved left
    assert max(errors) < 0.5, errors                           # the whole track is exact
    assert res.summary["flagged_pairs"] == 0 and res.summary["methods"]["wide"] == 1
    # without the wider region (twice -> once the full search's) the pair is
    # flagged; the next frame is then measured against the last measured one
    # (frame 5: after a gap its own full search), not against the assumed
    # frame 6 (an after_gap guess, before 2026-12-07), and the track is exact
    monkeypatch.setattr(OM, "WIDEN", 1)
    res1, errors1 = _cut_run(tmp_path / "b", poses)
    assert res1.rows[6]["status"] == "assumed" and res1.summary["flagged_pairs"] == 1
    r7 = res1.rows[7]
    assert (r7["status"], r7["method"], r7["ref"], r7["flags"]) == ("measured", "recover", 5, "")
    assert max(e for k, e in enumerate(errors1) if k != 6) < 0.5, errors1


@pytest.mark.parametrize("turn, method", [(30.0, "previous"), (34.0, "wide")])
def test_a_sudden_turn_beyond_the_angle_range_is_measured(tmp_path, monkeypatch, turn, method):
    # a turn in one frame outside angle_range (-20, 20). 30 degrees: the previous
    # frame's try, a search of the adjacent frame without a prior, is measured as
    # estimate_motion measures a pair (coarse to fine when the vote cannot vouch
    # for its answer), and gets it exactly (before 2026-12-06 only the wide try
    # did). 34 degrees: beyond what that try reaches from the range's edge,
    # inside the wide try's (-40, 40); with the wide try's ranges not widened
    # (WIDEN 1) the frame is flagged
    poses = [(400 + 12 * k, 350) for k in range(6)] + [(472 + 12 * k, 350, turn)
                                                        for k in range(4)]
    res, errors = _cut_run(tmp_path / "a", poses)
    r = res.rows[6]
    assert (r["status"], r["method"], r["ref"]) == ("measured", method, 5), r
    assert abs(r["rotation"]) == pytest.approx(turn, abs=0.3)
    assert max(errors) < 0.5, errors
    if method == "wide":
        monkeypatch.setattr(OM, "WIDEN", 1)
        res1, _ = _cut_run(tmp_path / "b", poses)
        assert res1.rows[6]["status"] == "assumed"


# ---------------------------------------------------------------- resume stays exact
@pytest.mark.parametrize("cut", [6, 7])
def test_resume_across_an_assumed_pose_is_exact(tmp_path, cut):
    # cut just before the assumed frame, and just after it: the resumed
    # state (velocity, last measured frame) is rebuilt from the rows alone
    frames, _ = _line(n=12, seed=7)
    paths = _write_frames(_with_gap(frames, 6), tmp_path / "frames")
    full = run_odometry(paths, tmp_path / "full", progress=False, mosaic=False)
    assert full.rows[6]["status"] == "assumed"
    run_odometry(paths[:cut], tmp_path / "resumed", progress=False, mosaic=False)
    res = run_odometry(paths, tmp_path / "resumed", resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == cut
    assert _csv_without_timing(res.csv_path) == _csv_without_timing(full.csv_path)


def test_a_run_of_an_earlier_format_is_not_continued(tmp_path):
    # a run folder written when an assumed pose meant zero motion (run format 1)
    frames, _ = _line(n=6, seed=2)
    paths = _write_frames(frames, tmp_path / "frames")
    out = tmp_path / "out"
    run_odometry(paths[:3], out, progress=False, mosaic=False)
    rec = json.loads((out / "run.json").read_text())
    rec["settings"]["format"] = 1
    (out / "run.json").write_text(json.dumps(rec))
    before = (out / "odometry.csv").read_bytes()
    with pytest.raises(ParameterError, match=r"earlier seahough \(run format 1, now 3.*zero "
                                             r"motion.*without --resume") as e:
        run_odometry(paths, out, resume=True, progress=False, mosaic=False)
    assert "\n" not in str(e.value)
    assert (out / "odometry.csv").read_bytes() == before          # nothing spliced
    res = run_odometry(paths, out, progress=False, mosaic=False)    # a new run: fine
    assert res.summary["frames"] == 6 and res.summary["resumed_rows"] == 0


# ---------------------------------------------------------------- a survey's chaining
def _chunk_row(i, status, cum, ref=None, flags=""):
    return {"index": i, "file": f"f{i}", "status": status, "ref": ref, "flags": flags,
            "method": "previous" if status == "measured" else "", "heading": None,
            "_cum": None if cum is None else np.asarray(cum, float), "confidence": None,
            "nfa": None, "score": None, "overlap": None}


def _shift(x, y=0.0):
    """Frame-0 pixels -> the pixels of a frame whose content moved by (x, y)."""
    return np.array([[1.0, 0.0, x], [0.0, 1.0, y]])


def test_the_chain_assumes_a_chunks_zero_motion_pose_again_with_the_trajectorys_velocity():
    # chunk A: 0-3 measured (10 px a frame), 4 assumed (its run's velocity), 5
    # unreadable. Chunk B starts at 3: 4 assumed with zero motion (B had measured
    # nothing yet), 6 measured from 4, 7 from 6. The join is frame 3 (the last
    # frame measured in both), so B's rows follow it: 4 is assumed again with the
    # trajectory's velocity (as a single run would have), and 6, 7 move with it.
    from seahough.survey._odometry_chain import Chain

    a = [_chunk_row(0, "origin", _shift(0)), _chunk_row(1, "measured", _shift(-10), 0),
         _chunk_row(2, "measured", _shift(-20), 1), _chunk_row(3, "measured", _shift(-30), 2),
         _chunk_row(4, "assumed", _shift(-40),
                    flags="no_match; pose_assumed: constant velocity since frame 3"),
         _chunk_row(5, "unreadable", None, flags="unreadable: corrupt")]
    b = [_chunk_row(3, "origin", _shift(0)),
         _chunk_row(4, "assumed", _shift(0),
                    flags="low_confidence; pose_assumed: zero motion since frame 3"),
         _chunk_row(5, "unreadable", None, flags="unreadable: corrupt"),
         _chunk_row(6, "measured", _shift(-7, 2), 4), _chunk_row(7, "measured", _shift(-14, 4), 6)]
    out = []
    chain = Chain(out.append, SHAPE, None, lambda p, q: (None, "no_match"))
    chain.add(a)
    chain.add(b)
    chain.finish()
    rows = {r["index"]: r for r in out}
    assert sorted(rows) == list(range(8)) and chain.joins["exact"] == 1
    r4 = rows[4]
    assert r4["status"] == "assumed"
    assert r4["flags"] == "low_confidence; pose_assumed: constant velocity since frame 3"
    np.testing.assert_allclose(r4["_G"], _shift(-40), atol=1e-9)   # 3's pose + 10 px
    assert r4["dx"] == pytest.approx(-10.0)
    # B's measured motion from 4 is kept: 6 and 7 placed from 4's new pose
    np.testing.assert_allclose(rows[6]["_G"], _shift(-47, 2), atol=1e-9)
    np.testing.assert_allclose(rows[7]["_G"], _shift(-54, 4), atol=1e-9)
    assert rows[7]["dx"] == pytest.approx(-7.0) and rows[7]["dy"] == pytest.approx(2.0)
    assert rows[6]["dx"] is None                  # (its previous frame, 5, has no pose)


def test_a_survey_folder_of_an_earlier_format_is_refused_not_spliced(tmp_path):
    # (the survey's check runs before any chunk is measured: no cluster needed)
    from seahough.config import ODOMETRY_CONFIG, OdometryTuning
    from seahough.motion.runfiles import RunFolder, run_settings, settings_hash
    from seahough.survey.odometry import _check_same_survey

    settings = run_settings((0.9, 1.1), (-20.0, 20.0), None, ODOMETRY_CONFIG, OdometryTuning())
    old = dict(settings, format=1)
    with RunFolder(tmp_path / "s") as run:
        run.write_settings(old, settings_hash(old))
        with pytest.raises(ParameterError, match=r"holds a survey that was made by an earlier "
                                                 r"seahough \(run format 1, now 3.*another --out"):
            _check_same_survey(run, settings)
        run.write_settings(settings, settings_hash(settings))
        _check_same_survey(run, settings)                          # the same survey: fine


def test_a_frame_measured_against_an_assumed_one_says_so(tmp_path):
    # a new scene from frame 5 on: frame 5 is no match (assumed), frame 6 is
    # measured against it: its step is right, but its place on the track
    # rests on frame 5's guess, and so does every later one's (a new user
    # kept the "measured" rows and got positions 160 px off, unflagged)
    a, _ = _line(n=5, seed=3)
    b, _ = _line(n=4, seed=11)
    frames = list(a) + [cv2.flip(f, 1) for f in b]    # (another place: the second line mirrored)
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    rows = res.rows
    assert rows[5]["status"] == "assumed"
    assert rows[6]["status"] == "measured" and rows[6]["ref"] == 5
    assert rows[6]["flags"] == "after_gap: measured against frame 5, whose pose was assumed"
    assert res.summary["after_gap"] == [6]
    assert res.summary["end_point"]["status"] == "measured"
    assert all(not r["flags"] for r in rows[7:])
