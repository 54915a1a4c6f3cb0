"""The number of false alarms (issue #14) outside the core: Motion.nfa and
``max_nfa`` of estimate_motion, the ``nfa`` column of the dead reckoning's
CSV (a run, a resumed run of an older CSV, a survey's chained chunks), and
``--max-nfa`` / ``nfa`` of ``seahough detect`` and ``survey detect``."""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim
from seahough.config import MOTION_CONFIG
from seahough.core.pattern import Pattern
from seahough.errors import ParameterError
from seahough.motion import read_odometry_csv, run_odometry
from seahough.motion import pair as P

from conftest import write_frames

from test_cli import assert_one_error_line, run

SHAPE = (240, 320)
NFA_TEXT = re.compile(r"^\d\.\de[+-]\d\d$")          # as 3.2e-05


@pytest.fixture(scope="module")
def frame_pair():
    prev, cur, truth = sim.frame_pair(seed=4, source="procedural")
    return prev, cur, truth, seahough.estimate_motion(prev, cur)


def _float_or_none(s):
    return None if s == "" else float(s)


# ------------------------------------------------------------------- estimate_motion
def test_motion_carries_a_finite_nfa(frame_pair):
    prev, cur, truth, m = frame_pair
    assert m is not None and math.isfinite(m.nfa) and 0.0 < m.nfa <= 1.0
    d = m.to_dict()
    assert d["nfa"] == m.nfa
    json.dumps(d, allow_nan=False)                    # plain JSON
    # the field is the last one, with a default: positional construction still works
    old = seahough.Motion(m.matrix, m.dx, m.dy, m.angle, m.scale, m.confidence, m.score,
                          m.overlap)
    assert math.isnan(old.nfa) and old.to_dict()["nfa"] is None
    json.dumps(old.to_dict(), allow_nan=False)


def test_max_nfa_judges_the_best_motion(frame_pair):
    prev, cur, _, m = frame_pair
    same = seahough.estimate_motion(prev, cur, max_nfa=m.nfa)          # the limit itself
    assert same is not None and same.nfa == m.nfa
    np.testing.assert_array_equal(same.matrix, m.matrix)
    free = seahough.estimate_motion(prev, cur, max_nfa=math.inf)
    assert free is not None and free.nfa == m.nfa
    assert seahough.estimate_motion(prev, cur, max_nfa=m.nfa / 2) is None
    assert seahough.estimate_motion(prev, cur, max_nfa=1e-300 if m.nfa > 1e-300 else 1e-310) \
        is None
    # motion_from_pattern, on a frame without a border: no content-box shift
    pattern = Pattern.from_frame(prev, config=MOTION_CONFIG)
    direct = P.motion_from_pattern(pattern, cur)
    assert direct is not None and 0.0 < direct.nfa <= 1.0
    assert P.motion_from_pattern(pattern, cur, max_nfa=direct.nfa / 2) is None


@pytest.mark.parametrize("bad", [0, -1, "x", float("nan"), True, None])
def test_bad_max_nfa_is_refused_by_name(frame_pair, bad):
    prev, cur, _, _ = frame_pair
    with pytest.raises(ParameterError, match="max_nfa"):
        seahough.estimate_motion(prev, cur, max_nfa=bad)
    pattern = Pattern.from_frame(prev, config=MOTION_CONFIG)
    with pytest.raises(ParameterError, match="max_nfa"):
        P.motion_from_pattern(pattern, cur, max_nfa=bad)


def test_measure_pair_does_not_judge_the_nfa(frame_pair):
    """The dead reckoning's searches keep their own decisions: an answer at a
    high NFA (two unrelated frames) is still returned, with its NFA; only
    estimate_motion's max_nfa declines it."""
    prev, _, _, _ = frame_pair
    other = sim.negative_scene(prev.shape[:2], seed=77, source="procedural")
    pattern = Pattern.from_frame(seahough.to_gray(prev), config=MOTION_CONFIG)
    h, w = other.shape[:2]
    gray = seahough.to_gray(other)
    region = (0.0, 0.0, float(w), float(h))
    d = P.measure_pair(pattern, gray, (0.8, 1.25), (-30, 30), region, min_score=0.0,
                       min_confidence=0.0, config=MOTION_CONFIG)
    assert d is not None and math.isfinite(d.nfa) and d.nfa > 1.0
    assert P.motion_from_pattern(pattern, gray, max_shift=1.0, min_confidence=0.0,
                                 min_score=0.0) is None
    loose = P.motion_from_pattern(pattern, gray, max_shift=1.0, min_confidence=0.0,
                                  min_score=0.0, max_nfa=math.inf)
    assert loose is not None and loose.nfa > 1.0


# ----------------------------------------------------------------------- dead reckoning
def _sequence_files(folder: Path, n=6, seed=2, step=12.0):
    frames, _ = sim.sequence(n_frames=n, frame_size=SHAPE, path="line", step=step, seed=seed,
                             source="procedural")
    return write_frames(frames, folder)


def _csv(path):
    with open(path, newline="") as f:
        r = csv.DictReader(f)
        return r.fieldnames, list(r)


def test_odometry_csv_has_the_nfa_of_each_measured_pair(tmp_path, monkeypatch):
    # the run's searches do not judge the NFA (its decisions stay its own)
    seen = []
    real = P.Detector

    def spy(*a, **k):
        seen.append(k.get("max_nfa"))
        return real(*a, **k)

    monkeypatch.setattr(P, "Detector", spy)
    paths = _sequence_files(tmp_path / "f")
    res = run_odometry(paths, tmp_path / "out", progress=False, mosaic=False, workers=1)
    assert seen and all(v == math.inf for v in seen)
    header, rows = _csv(res.csv_path)
    assert header.index("nfa") == header.index("confidence") + 1
    measured = [r for r in rows if r["status"] == "measured"]
    assert len(measured) == len(paths) - 1
    for r in rows:
        if r["status"] == "measured":
            assert 0.0 < float(r["nfa"]) and math.isfinite(float(r["nfa"]))
        else:
            assert r["nfa"] == "" and r["confidence"] == ""
    back = list(res.iter_rows())
    assert [r["nfa"] for r in back] == [_float_or_none(r["nfa"]) for r in rows]
    assert back[0]["nfa"] is None and all(isinstance(r["nfa"], float) for r in back[1:])


def test_resume_of_a_csv_without_the_nfa_column(tmp_path):
    # a run of an earlier seahough (no nfa column) is continued, not refused
    paths = _sequence_files(tmp_path / "f")
    out = tmp_path / "out"
    run_odometry(paths[:3], out, progress=False, mosaic=False, workers=1)
    header, rows = _csv(out / "odometry.csv")
    old = [k for k in header if k != "nfa"]
    with open(out / "odometry.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=old, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    assert all(r["nfa"] is None for r in read_odometry_csv(out / "odometry.csv"))
    res = run_odometry(paths, out, resume=True, progress=False, mosaic=False, workers=1)
    assert res.summary["resumed_rows"] == 3
    header, rows = _csv(res.csv_path)
    assert "nfa" in header and len(rows) == len(paths)
    assert [r["nfa"] for r in rows[:3]] == ["", "", ""]          # not measured here: unknown
    assert all(float(r["nfa"]) > 0 for r in rows[3:])
    assert [r["status"] for r in rows] == ["origin"] + ["measured"] * (len(paths) - 1)


def test_a_join_measured_across_reports_its_nfa(tmp_path, monkeypatch):
    # the survey's chaining measures a pair across a gap with estimate_motion:
    # without a limit on the NFA (as the run's own pairs), and reports it
    from seahough.config import ODOMETRY_CONFIG, OdometryTuning
    from seahough.io.frames import FrameReader
    from seahough.survey import _odometry_chain as C

    seen = []
    real = C.estimate_motion

    def spy(*a, **k):
        seen.append(k.get("max_nfa"))
        return real(*a, **k)

    monkeypatch.setattr(C, "estimate_motion", spy)
    paths = _sequence_files(tmp_path / "f", n=3)
    reader = FrameReader(paths, ODOMETRY_CONFIG.max_pixels)
    mo, why = C.measure_across(reader, 0, 2, (0.9, 1.1), (-20.0, 20.0), ODOMETRY_CONFIG,
                               OdometryTuning())
    reader.close()
    assert seen == [math.inf]
    assert why == "" and mo is not None and 0.0 < mo.nfa <= 1.0
    assert "nfa" in C._MEASURE
    # a blank earlier frame: few_edges (estimate_motion answers None for it)
    cv2.imwrite(str(paths[0]), np.zeros((240, 320), np.uint8))
    reader = FrameReader(paths, ODOMETRY_CONFIG.max_pixels)
    mo, why = C.measure_across(reader, 0, 2, (0.9, 1.1), (-20.0, 20.0), ODOMETRY_CONFIG,
                               OdometryTuning())
    reader.close()
    assert (mo, why) == (None, "few_edges")


# ------------------------------------------------------------------------------- CLI
@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    d = tmp_path_factory.mktemp("scene")
    img, pattern, truth = sim.marker_scene("board", seed=3, source="procedural")
    cv2.imwrite(str(d / "scene.png"), img)
    cv2.imwrite(str(d / "pattern.png"), pattern)
    return d


@pytest.mark.parametrize("value", ["0", "-1", "nan", "x"])
def test_cli_detect_refuses_a_bad_max_nfa(scene, value):
    proc = run("detect", scene / "pattern.png", scene / "scene.png", f"--max-nfa={value}")
    assert_one_error_line(proc, "--max-nfa")
    assert proc.stdout == ""


def test_cli_detect_json_and_table_have_the_nfa(scene):
    args = ("detect", scene / "pattern.png", scene / "scene.png", "--scale-range", 0.5, 2)
    proc = run(*args, "--json")
    assert proc.returncode == 0, proc.stderr
    rec = json.loads(proc.stdout, parse_constant=lambda c: pytest.fail(f"JSON has {c}"))
    best = rec["detections"][0]
    assert isinstance(best["nfa"], float) and 0.0 < best["nfa"] <= 1.0
    # --max-nfa reaches the Detector: below the best's NFA, the best is gone
    proc = run(*args, "--json", "--max-nfa", best["nfa"] / 2)
    left = json.loads(proc.stdout)["detections"]
    assert all(d["nfa"] <= best["nfa"] / 2 for d in left)        # (the best among none)
    assert proc.returncode == (0 if left else 1)
    proc = run(*args, "--max-nfa", "inf")
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    header = lines[1].split()
    assert header == ["#", "x", "y", "scale", "angle", "score", "conf", "nfa", "flags"]
    row = lines[2].split()
    assert NFA_TEXT.match(row[7]), row
    assert float(row[7]) == pytest.approx(best["nfa"], rel=0.06)


def test_cli_survey_detect_takes_max_nfa(scene, tmp_path):
    from seahough.cli.survey import detect as survey_cmd

    assert "max_nfa" in {p.name for p in survey_cmd.params}
    proc = run("survey", "detect", scene / "pattern.png", scene / "scene.png",
               "--out", tmp_path / "out", "--max-nfa", "0")
    assert_one_error_line(proc, "--max-nfa")
    assert not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- survey
@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    pytest.importorskip("pyarrow.parquet")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as c:
        yield c


def test_survey_detect_parquet_has_the_nfa(scene, cluster, tmp_path):
    import pyarrow.parquet as pq

    out = tmp_path / "out"
    proc = run("survey", "detect", scene / "pattern.png", scene / "scene.png", "--out", out,
               "--scale-range", 0.5, 2, "--max-nfa", 0.5, "--scheduler",
               cluster.scheduler_address, "--quiet")
    assert proc.returncode == 0, proc.stderr
    manifest = json.loads((out / "survey.json").read_text())
    assert manifest["settings"]["max_nfa"] == 0.5
    rows = pq.read_table(out / "detections.parquet").to_pylist()
    want = seahough.Detector(seahough.Pattern.from_image(scene / "pattern.png"), (0.5, 2.0),
                             max_nfa=0.5).detect(scene / "scene.png")
    assert rows and len(rows) == len(want)
    for r, d in zip(rows, want):
        assert r["nfa"] == pytest.approx(d.nfa, rel=1e-9) and r["nfa"] <= 0.5
    # other max_nfa, other survey: refused, naming it
    from seahough.survey import detect as survey_detect

    with pytest.raises(ParameterError, match=r"other settings: max_nfa 0\.5 \(now 1\.0\)"):
        survey_detect(seahough.Pattern.from_image(scene / "pattern.png"),
                      [str(scene / "scene.png")], out, scale_range=(0.5, 2.0),
                      progress=False)


def test_survey_of_an_earlier_seahough_is_not_continued(scene, tmp_path):
    # a manifest without max_nfa (its detections without nfa): never mixed with new ones
    pytest.importorskip("pyarrow.parquet")
    from seahough.survey import detect as survey_detect

    out = tmp_path / "out"
    out.mkdir()
    (out / "survey.json").write_text(json.dumps({
        "format": 1, "command": "survey detect", "settings_hash": "0" * 16,
        "settings": {"scale_range": [0.5, 2.0]}, "inputs": {"count": 1, "hash": ""},
        "state": "complete", "counts": None, "files": {}}))
    with pytest.raises(ParameterError, match="another seahough.*give another output folder"):
        survey_detect(seahough.Pattern.from_image(scene / "pattern.png"),
                      [str(scene / "scene.png")], out, progress=False)


def test_survey_odometry_chains_the_nfa(cluster, tmp_path):
    # two chunks whose shared frames are lost: the join is measured across the
    # gap; every measured row (chunk rows and the join) has its NFA
    from seahough.survey.odometry import odometry as survey_odometry

    paths = _sequence_files(tmp_path / "f", n=14, seed=5, step=10.0)
    for i in (5, 6, 7):
        Path(paths[i]).write_bytes(b"not an image")
    got = survey_odometry(paths, tmp_path / "s", scheduler=cluster.scheduler_address,
                          chunk_size=8, progress=False, mosaic=False)
    header, rows = _csv(got["csv"])
    assert header.index("nfa") == header.index("confidence") + 1
    summary = json.loads(got["summary"].read_text())
    assert summary["survey"]["joins"]["measured"] == 1
    assert rows[8]["status"] == "measured" and rows[8]["method"] == "previous"
    for r in rows:
        if r["status"] == "measured":
            assert float(r["nfa"]) > 0, r
        else:
            assert r["nfa"] == "", r
