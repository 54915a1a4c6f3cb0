"""All cores on one machine: the kernels release the GIL, searches run from
several threads at once with the results of one thread, ``detect --workers``
and ``run_odometry(workers=...)`` give the results of one worker."""

from __future__ import annotations

import csv
import json
from concurrent.futures import ThreadPoolExecutor

import cv2
import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

import seahough
from seahough import sim
from seahough.cli import main
from seahough.core.kernels import _common, edges, matching, voting
from seahough.errors import ParameterError
from seahough.io.frames import FrameReader
from seahough.motion.odometry import run_odometry
from seahough.motion.prefetch import Prefetch, overlapped


def _dispatchers():
    for mod in (edges, voting, matching, _common):
        for name, obj in vars(mod).items():
            if isinstance(obj, CPUDispatcher) and obj.__module__ == mod.__name__:
                yield f"{mod.__name__}.{name}", obj


def test_every_kernel_releases_the_gil():
    found = dict(_dispatchers())
    assert {"vote", "icp", "edge_points"} <= {k.rsplit(".", 1)[1] for k in found}
    holding = [name for name, d in found.items() if not d.targetoptions.get("nogil")]
    assert holding == []


def _same_detections(a, b) -> bool:
    return [d.to_dict() for d in a] == [d.to_dict() for d in b] and all(
        np.array_equal(x.matrix, y.matrix) for x, y in zip(a, b))


def test_searches_from_four_threads_give_the_serial_results():
    scenes = [sim.marker_scene("board", seed=s, source="procedural")[0] for s in range(4)]
    detector = seahough.Detector(seahough.Pattern.rectangle(90, 60))
    pairs = [sim.frame_pair(seed=s, source="procedural")[:2] for s in range(4)]

    def work(k):
        return detector.detect(scenes[k % 4]), seahough.estimate_motion(*pairs[k % 4])

    serial = [work(k) for k in range(4)]
    with ThreadPoolExecutor(4) as pool:
        threaded = list(pool.map(work, range(12)))
    for k, (dets, motion) in enumerate(threaded):
        want_dets, want_motion = serial[k % 4]
        assert want_dets and _same_detections(dets, want_dets)
        assert (motion is None) == (want_motion is None)
        if motion is not None:
            assert motion.to_dict() == want_motion.to_dict()


# ------------------------------------------------------------------------- detect
@pytest.fixture(scope="module")
def images(tmp_path_factory):
    d = tmp_path_factory.mktemp("workers")
    names = []
    for s in range(5):
        p = d / f"scene{s}.png"
        cv2.imwrite(str(p), sim.marker_scene("board", seed=s, source="procedural")[0])
        names.append(p)
    cv2.imwrite(str(d / "black.png"), np.zeros((120, 160), np.uint8))
    (d / "notes.png").write_text("not an image\n")
    # a bad file, a search that cannot run, and two files of one stem among the good ones
    sub = d / "again"
    sub.mkdir()
    cv2.imwrite(str(sub / "scene0.png"), sim.negative_scene(seed=1, source="procedural"))
    return [names[0], d / "notes.png", names[1], d / "black.png", names[2], sub / "scene0.png",
            names[3], names[4]]


def _detect(capsys, *args):
    with pytest.raises(SystemExit) as e:
        main(["detect", *map(str, args)])
    out, err = capsys.readouterr()
    return e.value.code, out, err


def _records(out: str) -> list:
    recs = [json.loads(line) for line in out.splitlines()]
    for r in recs:
        r.pop("time_ms", None)     # (a bad file's record has none)
    return recs


def test_detect_workers_prints_the_one_worker_results_in_order(images, capsys, tmp_path):
    one = _detect(capsys, "rect:90,60", *images, "--json", "--workers", 1,
                  "--out", tmp_path / "one")
    three = _detect(capsys, "rect:90,60", *images, "--json", "--workers", 3,
                    "--out", tmp_path / "three")
    assert one[0] == three[0] == 2                      # the bad file
    assert one[2] == three[2] and one[2].count("\n") == 1 and "notes.png" in one[2]
    recs1, recs3 = _records(one[1]), _records(three[1])
    assert [r["file"] for r in recs3] == [str(p) for p in images]   # (the bad one: its error)
    assert [r["file"] for r in recs3 if "error" in r] == [str(p) for p in images
                                                          if p.name == "notes.png"]
    assert [r for r in recs1 if "error" in r] == [r for r in recs3 if "error" in r]
    recs1, recs3 = ([r for r in recs if "error" not in r] for recs in (recs1, recs3))
    for r in recs1 + recs3:            # the pictures' paths differ by the folder only
        for k in ("overlay", "accumulator", "edges"):
            r[k] = r[k].split("/")[-1]
    assert recs1 == recs3
    assert [r["note"] for r in recs3][2] == "no edges"
    assert {r["overlay"] for r in recs3} >= {"scene0_overlay.png", "scene0_2_overlay.png"}
    # the pictures, drawn in worker threads, are those of one worker
    pngs = sorted(p.name for p in (tmp_path / "one").iterdir())
    assert pngs == sorted(p.name for p in (tmp_path / "three").iterdir()) and len(pngs) == 21
    for name in pngs:
        a = cv2.imread(str(tmp_path / "one" / name))
        b = cv2.imread(str(tmp_path / "three" / name))
        assert a.shape == b.shape and np.array_equal(a, b), name


def test_detect_workers_table_and_exit_status(images, capsys):
    good = [p for p in images if p.name.startswith("scene")]
    one = _detect(capsys, "rect:90,60", *good, "--workers", 1)
    two = _detect(capsys, "rect:90,60", *good, "--workers", 2)
    strip = lambda out: [line.rsplit("(", 1)[0] if "ms)" in line else line  # noqa: E731
                         for line in out.splitlines()]
    assert one[0] == two[0] and one[0] in (0, 1)
    assert strip(one[1]) == strip(two[1])


@pytest.mark.parametrize("value", ["0", "-2", "many"])
def test_detect_workers_must_be_positive(images, capsys, value):
    code, out, err = _detect(capsys, "rect:90,60", images[0], "--workers", value)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("seahough: error:") and "--workers" in err


# ----------------------------------------------------------------------- odometry
def _rows(path) -> list:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.pop("ms")
    return rows


def test_odometry_rows_identical_for_one_and_two_workers(tmp_path):
    frames, _ = sim.sequence(n_frames=10, seed=3, path="turn", source="procedural")
    frames = list(frames)
    frames[4] = np.zeros((20, 20), np.uint8)            # too small: an unreadable row
    runs = {w: run_odometry(frames, tmp_path / f"w{w}", progress=False, mosaic=w == 2,
                            workers=w) for w in (1, 2, 3)}
    rows = {w: _rows(r.csv_path) for w, r in runs.items()}
    assert len(rows[1]) == 10 and rows[1][4]["status"] == "unreadable"
    assert sum(r["status"] == "measured" for r in rows[1]) >= 7
    assert rows[1] == rows[2] == rows[3]
    assert runs[2].mosaic_path is not None and runs[2].mosaic_path.exists()
    with pytest.raises(ParameterError, match="workers"):
        run_odometry(frames, tmp_path / "w0", progress=False, workers=0)


def test_odometry_frame_smaller_than_the_first_frames_border_with_workers(tmp_path):
    """A later frame of another size, smaller than the first frame's content
    box offset: flagged as with one worker (the threads ahead once cropped it
    to nothing and raised cv2.error)."""
    rng = np.random.default_rng(0)

    def texture(h, w):
        noise = (rng.random((h, w)) * 255).astype(np.float32)
        return cv2.GaussianBlur(noise, (0, 0), 2).astype(np.uint8)

    first = texture(720, 960)
    first[:70] = 0                                    # a dark band: the content box starts at 72
    frames = ([np.roll(first, 4 * k, axis=1) for k in range(5)] + [texture(66, 320)]
              + [np.roll(first, 4 * k, axis=1) for k in range(5, 7)])
    rows = {w: _rows(run_odometry(frames, tmp_path / f"w{w}", progress=False, mosaic=False,
                                  workers=w).csv_path) for w in (1, 2)}
    assert rows[1][5]["status"] == "unreadable" and "differs" in rows[1][5]["flags"]
    assert rows[1] == rows[2]


def test_odometry_cli_workers(tmp_path, capsys):
    frames, _ = sim.sequence(n_frames=5, seed=1, source="procedural")
    d = tmp_path / "frames"
    d.mkdir()
    for k, f in enumerate(frames):
        cv2.imwrite(str(d / f"f{k}.png"), f)
    for w in (1, 2):
        with pytest.raises(SystemExit) as e:
            main(["odometry", str(d), "--out", str(tmp_path / f"o{w}"), "--no-mosaic",
                  "--workers", str(w), "-q"])
        assert e.value.code == 0
    capsys.readouterr()
    assert _rows(tmp_path / "o1" / "odometry.csv") == _rows(tmp_path / "o2" / "odometry.csv")
    with pytest.raises(SystemExit) as e:
        main(["odometry", str(d), "--out", str(tmp_path / "o0"), "--workers", "0"])
    _, err = capsys.readouterr()
    assert e.value.code == 2 and err.count("\n") == 1 and "--workers" in err


def test_prefetch_reads_a_video_in_order_from_several_threads(tmp_path, monkeypatch):
    frames, _ = sim.sequence(n_frames=9, seed=2, source="procedural")
    video = tmp_path / "dive.avi"
    vw = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 5.0,
                         frames[0].shape[1::-1])
    if not vw.isOpened():
        pytest.skip("OpenCV cannot write an MJPG video here")
    for f in frames:
        vw.write(f)
    vw.release()
    items = [f"{video}#{k}" for k in range(9)] + [str(tmp_path / "missing.png")]
    limits = {"max_pixels": 10 ** 7, "max_memory_mb": 500}
    with Prefetch(FrameReader(items, 10 ** 7), 0, workers=1, **limits) as one:
        want = [one.get(i) for i in range(len(items))]
    reader = FrameReader(items, 10 ** 7)
    opened = []
    real = cv2.VideoCapture

    def capture(*args):              # (the video is opened once: read in order)
        opened.append(args)
        return real(*args)

    monkeypatch.setattr(cv2, "VideoCapture", capture)
    with Prefetch(reader, 0, workers=4, **limits) as ahead:
        got = [ahead.get(i) for i in range(len(items))]
    assert [g.index for g in got] == list(range(len(items)))
    for g, w in zip(got, want):
        assert g.frame_hash == w.frame_hash and g.error == w.error
        assert (g.gray is None and w.gray is None) or np.array_equal(g.gray, w.gray)
    assert got[-1].error is not None and "no such file" in got[-1].error.lower()
    assert len(opened) == 1


def test_overlapped_raises_the_first_error_in_order():
    def fail(msg):
        def f():
            raise ValueError(msg)
        return f

    with pytest.raises(ValueError, match="first"):
        overlapped((fail("first"), fail("second")), workers=2)
    assert overlapped((lambda: 1,), workers=4) == [1]
