"""``seahough survey``: detection over many images on a Dask cluster, into Parquet.

One local cluster of 2 worker processes serves the module (passed as a
running scheduler); one test starts its own local cluster.
"""

from __future__ import annotations

import importlib
import json
import shutil
import os
import signal
import socket
import subprocess
import sys
import time
import types

import cv2
import numpy as np
import pytest

pytest.importorskip("distributed")
pq = pytest.importorskip("pyarrow.parquet")

import seahough  # noqa: E402
from seahough import sim  # noqa: E402
from seahough.cli import main  # noqa: E402
from seahough.errors import ParameterError, WriteError  # noqa: E402
from seahough.survey import detect as survey_detect  # noqa: E402
from seahough.survey._inputs import expand_inputs  # noqa: E402

# the module (the package's ``detect`` is the function)
SD = importlib.import_module("seahough.survey.detect")
CLUSTER = importlib.import_module("seahough.survey._cluster")
N = 8


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """N small simulated scenes with a marker, an unreadable file, and the pattern."""
    d = tmp_path_factory.mktemp("scenes")
    imgs = d / "imgs"
    imgs.mkdir()
    pattern = None
    for i in range(N):
        scene, pat, _ = sim.marker_scene(shape=(200, 260), seed=i, size=56, source="procedural")
        cv2.imwrite(str(imgs / f"s{i}.png"), scene)
        pattern = pat if pattern is None else pattern
    cv2.imwrite(str(d / "pattern.png"), pattern)
    (imgs / "z_bad.png").write_bytes(b"not a png")
    return d


@pytest.fixture(scope="module")
def cluster():
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as c:
        yield c


def _pattern(scenes):
    return seahough.Pattern.from_image(str(scenes / "pattern.png"))


def _rows(path):
    return pq.read_table(path).to_pylist()


def _shards():
    return importlib.import_module("seahough.survey._shards")


def _check_once(result, n):
    rows = _rows(result.images)
    assert [r["index"] for r in rows] == list(range(n))
    assert result.total == n == len(rows)
    return rows


@pytest.fixture(scope="module")
def first(scenes, cluster, tmp_path_factory):
    """One survey of the folder plus a missing file."""
    out = tmp_path_factory.mktemp("first") / "out"
    inputs = [str(scenes / "imgs"), str(scenes / "missing.jpg")]
    r = survey_detect(_pattern(scenes), inputs, out, scheduler=cluster.scheduler_address,
                      batch_size=2, progress=False)
    return r, inputs


def test_rows_once_and_as_detector_detect(scenes, first):
    r, inputs = first
    paths = expand_inputs(inputs)
    rows = _check_once(r, N + 2)
    assert [row["path"] for row in rows] == paths
    by_path = {row["path"]: row for row in rows}
    assert by_path[str(scenes / "missing.jpg")]["error"] == "no such file"
    bad = by_path[str(scenes / "imgs" / "z_bad.png")]
    assert bad["status"] == "error" and bad["error"] and bad["width"] is None
    assert (r.errors, r.found + r.not_found, r.processed) == (2, N, N + 2)
    # the same detections as a Detector in this process
    det = seahough.Detector(_pattern(scenes))
    got = _rows(r.detections)
    want = []
    for i, p in enumerate(paths[:N]):
        for rank, d in enumerate(det.detect(p), 1):
            want.append((i, rank, d))
        assert by_path[p]["n_detections"] == len(det.detect(p))
    assert len(got) == len(want) == r.n_detections and r.found >= N - 1
    for g, (i, rank, d) in zip(got, want):
        assert (g["index"], g["rank"], g["path"]) == (i, rank, paths[i])
        for k, v in d.to_dict().items():
            if k in ("box", "outline"):      # (the survey's table: the matrix gives them)
                continue
            if k == "matrix":
                np.testing.assert_allclose(g["matrix"], np.ravel(v), rtol=0, atol=1e-9)
            elif isinstance(v, float):
                assert g[k] == pytest.approx(v, abs=1e-9), k
            else:
                assert g[k] == v, k
    manifest = json.loads(r.manifest.read_text())
    assert manifest["state"] == "complete" and manifest["counts"]["errors"] == 2


def test_every_detection_field_has_a_column():
    from seahough.core.ranking import Detection
    from seahough.survey._shards import DETECTIONS_SCHEMA

    d = Detection(1.0, 2.0, 1.0, 0.0, 0.9, 0.8, np.eye(2, 3), kind="line", line_angle=3.0,
                  line_offset=1.0)
    assert set(d.to_dict()) <= set(DETECTIONS_SCHEMA.names)


def test_rerun_redoes_nothing(scenes, first, monkeypatch):
    r, inputs = first
    before = {p: p.stat().st_mtime_ns for p in (r.images, r.detections)}

    def no_cluster(*a, **k):
        raise AssertionError("a complete survey started a cluster")

    monkeypatch.setattr(SD, "open_client", no_cluster)
    again = survey_detect(_pattern(scenes), inputs, r.images.parent, progress=False)
    assert again.processed == 0 and again.total == r.total and again.found == r.found
    assert {p: p.stat().st_mtime_ns for p in before} == before


def test_mismatched_rerun_refused(scenes, first):
    r, inputs = first
    with pytest.raises(ParameterError, match=r"other settings: scale_range \[0\.5, 2\.0\] "
                                             r"\(now \[0\.8, 1\.2\]\)"):
        survey_detect(_pattern(scenes), inputs, r.images.parent, scale_range=(0.8, 1.2))
    with pytest.raises(ParameterError, match="other images: 10 images \\(now 10\\); first "
                                             "difference: image 9"):
        survey_detect(_pattern(scenes), inputs[:1] + [str(scenes / "other.jpg")],
                      r.images.parent)
    with pytest.raises(ParameterError, match="other settings: pattern"):
        survey_detect(seahough.Pattern.rectangle(40, 30), inputs, r.images.parent)


def test_errors_retried_and_more_images_added(scenes, cluster, tmp_path, capsys):
    # a photo still being copied when the survey read it, then more photos
    imgs = scenes / "imgs"
    late = tmp_path / "late.png"
    inputs = [str(imgs / "s0.png"), str(imgs / "s1.png"), str(late)]
    out = tmp_path / "out"
    kw = dict(scheduler=cluster.scheduler_address, progress=False)
    r = survey_detect(_pattern(scenes), inputs, out, **kw)
    assert (r.total, r.errors, r.processed) == (3, 1, 3)
    shutil.copy(imgs / "s2.png", late)
    r = survey_detect(_pattern(scenes), inputs, out, **kw)     # (a plain rerun: as it was)
    assert (r.errors, r.processed) == (1, 0)
    # a retry stopped while it rewrites a shard: the survey says it is running
    # again, and its two files (which would hold the error) are gone
    shards = _shards()
    real_write = shards.SurveyFolder._write

    def stop_at(name):
        def write(self, path, table):
            if path.name.startswith(name):
                raise KeyboardInterrupt
            return real_write(self, path, table)
        return write

    shards.SurveyFolder._write = stop_at("images-")
    try:
        with pytest.raises(KeyboardInterrupt):
            survey_detect(_pattern(scenes), inputs, out, retry_errors=True, **kw)
    finally:
        shards.SurveyFolder._write = real_write
    assert json.loads((out / "survey.json").read_text())["state"] == "stopped"
    assert not (out / "images.parquet").exists()
    r = survey_detect(_pattern(scenes), inputs, out, retry_errors=True, **kw)
    assert (r.total, r.errors, r.processed, r.found) == (3, 0, 1, 3)
    manifest = json.loads(r.manifest.read_text())
    assert manifest["state"] == "complete" and "stopped" not in manifest
    rows = _check_once(r, 3)
    assert rows[2]["status"] == "found" and rows[2]["error"] is None
    # more images after the survey's own: only they are searched
    more = inputs + [str(imgs / "s3.png"), str(imgs / "s4.png")]
    r = survey_detect(_pattern(scenes), more, out, **kw)
    assert (r.total, r.processed, r.errors) == (5, 2, 0)
    assert [row["path"] for row in _check_once(r, 5)] == more
    manifest = json.loads(r.manifest.read_text())
    assert manifest["state"] == "complete" and manifest["inputs"]["count"] == 5
    # fewer, or others in their place, are another survey
    with pytest.raises(ParameterError, match="other images: 5 images \\(now 4\\)"):
        survey_detect(_pattern(scenes), more[:4], out, **kw)
    # a growth stopped between the manifest and the input list: the next run goes on
    old_list = pq.read_table(out / "parts" / "inputs.parquet")
    grown = more + [str(imgs / "s5.png")]
    shards.SurveyFolder._write = stop_at("inputs.parquet")
    try:
        with pytest.raises(KeyboardInterrupt):
            survey_detect(_pattern(scenes), grown, out, **kw)
    finally:
        shards.SurveyFolder._write = real_write
    assert pq.read_table(out / "parts" / "inputs.parquet").equals(old_list)
    assert not (out / "images.parquet").exists()     # (no stale complete results)
    r = survey_detect(_pattern(scenes), grown, out, **kw)
    assert (r.total, r.processed) == (6, 1)
    assert pq.read_table(out / "parts" / "inputs.parquet").num_rows == 6
    # from the command line
    imgs_dir = tmp_path / "dive"
    imgs_dir.mkdir()
    for i in (5, 6):
        shutil.copy(imgs / f"s{i}.png", imgs_dir / f"s{i}.png")
    code, outp, err = _cli(capsys, "detect", scenes / "pattern.png", *grown, imgs_dir / "s5.png",
                           "--out", out, "--scheduler", cluster.scheduler_address,
                           "--retry-errors", "--quiet")
    assert code == 0, err
    assert "images: 7   found: 7" in outp and "searched 1 image " in outp


def test_interrupted_run_continues(scenes, cluster, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(SD, "SHARD_IMAGES", 2)
    inputs = [str(scenes / "imgs" / f"s{i % N}.png") for i in range(12)]
    out = tmp_path / "out"
    seen = []

    def stop(done, total):
        seen.append(done)
        if len(seen) == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        survey_detect(_pattern(scenes), inputs, out, scheduler=cluster.scheduler_address,
                      batch_size=1, progress=False, on_batch=stop)
    assert not (out / "images.parquet").exists()
    kept = sum(pq.read_table(p).num_rows for p in (out / "parts").glob("images-*.parquet"))
    assert kept == 5
    # survey.json says the run stopped (it said "running" with no run left)
    manifest = json.loads((out / "survey.json").read_text())
    assert manifest["state"] == "stopped"
    assert manifest["stopped"]["why"] == "interrupted" and manifest["stopped"]["images_done"] == 5
    # the command line says what was kept, in its one line
    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(SD, "detect", interrupted)
    code, _, err = _cli(capsys, "detect", scenes / "pattern.png", *inputs, "--out", out)
    assert code == 130 and err == (f"\nseahough: error: interrupted: 5 of 12 images searched "
                                   f"and kept in {out}; the same command goes on with the "
                                   "others\n"), err
    monkeypatch.undo()
    monkeypatch.setattr(SD, "SHARD_IMAGES", 2)
    # what a killed client leaves: a half-written shard and a shard without its mark
    (out / "parts" / "images-000099.parquet.tmp").write_bytes(b"half")
    (out / "parts" / "detections-000098.parquet").write_bytes(b"orphan")
    r = survey_detect(_pattern(scenes), inputs, out, scheduler=cluster.scheduler_address,
                      batch_size=1, progress=False)
    assert r.processed == 12 - 5
    rows = _check_once(r, 12)
    assert [row["path"] for row in rows] == inputs
    assert not list((out / "parts").glob("*.tmp"))
    assert not (out / "parts" / "detections-000098.parquet").exists()
    # each detection once: as many as the images' counts say
    assert r.n_detections == sum(row["n_detections"] for row in rows)


def test_killed_worker(scenes, cluster, first, tmp_path):
    import distributed

    inputs = [str(scenes / "imgs" / f"s{i % N}.png") for i in range(40)]
    with distributed.Client(cluster.scheduler_address) as client:
        pids = client.run(os.getpid)
        killed = []

        def kill(done, total):
            if not killed:
                pid = sorted(pids.values())[0]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        r = survey_detect(_pattern(scenes), inputs, tmp_path / "out",
                          scheduler=cluster.scheduler_address, batch_size=1, progress=False,
                          on_batch=kill)
        # the nanny has started a new worker process in place of the killed one
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                now = client.run(os.getpid)
            except OSError:                     # (the dead worker, not yet removed)
                now = {}
            if len(now) == 2 and killed and killed[0] not in now.values():
                break
            time.sleep(0.2)
        else:
            pytest.fail(f"no new worker in place of the killed one: {now}, killed {killed}")
    rows = _check_once(r, 40)
    assert all(row["status"] != "error" for row in rows)
    # the same results as the survey that lost no worker
    ref = {row["path"]: row["n_detections"] for row in _rows(first[0].images)}
    assert [row["n_detections"] for row in rows] == [ref[p] for p in inputs]
    ref_d = {}
    for d in _rows(first[0].detections):
        ref_d.setdefault(d["path"], []).append((d["x"], d["y"], d["score"]))
    got_d = {}
    for d in _rows(r.detections):
        got_d.setdefault(d["index"], []).append((d["x"], d["y"], d["score"]))
    assert all(got_d.get(i, []) == ref_d.get(p, []) for i, p in enumerate(inputs))


def _poison(dask_worker=None):
    """On a worker: reading an image named poison* kills the process."""
    import seahough.io.images as images

    read = images.read_image

    def read_or_die(path, **kw):
        if os.path.basename(path).startswith("poison"):
            os._exit(1)
        return read(path, **kw)

    images.read_image = read_or_die


def test_an_image_that_kills_its_worker_is_an_error_row(scenes, tmp_path):
    import dask
    import distributed

    poison = tmp_path / "poison.png"
    poison.write_bytes((scenes / "imgs" / "s0.png").read_bytes())
    inputs = [str(scenes / "imgs" / "s1.png"), str(poison), str(scenes / "imgs" / "s2.png"),
              str(scenes / "imgs" / "s3.png")]
    # a task is given up at its first dead worker; one task at a time on a
    # worker, so that the death hits that task only
    with dask.config.set({"distributed.scheduler.allowed-failures": 0,
                          "distributed.scheduler.worker-saturation": 1.0}):
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=":0", silence_logs=50) as c:
            with distributed.Client(c) as client:
                client.register_worker_callbacks(setup=_poison)
                r = survey_detect(_pattern(scenes), inputs, tmp_path / "out",
                                  scheduler=c.scheduler_address, batch_size=4, progress=False)
    rows = _check_once(r, 4)
    assert [row["status"] for row in rows] == ["found", "error", "found", "found"]
    assert rows[1]["error"] == SD.DIED


def test_local_cluster_by_default(scenes, tmp_path):
    r = survey_detect(_pattern(scenes), [str(scenes / "imgs" / "s0.png")], tmp_path / "o",
                      workers=1, progress=False)
    assert (r.total, r.found, r.processed) == (1, 1, 1)


def test_bad_inputs(scenes, tmp_path):
    p = _pattern(scenes)
    with pytest.raises(ParameterError, match="no input images"):
        survey_detect(p, [], tmp_path / "a")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ParameterError, match="no image files"):
        survey_detect(p, [str(tmp_path / "empty")], tmp_path / "a")
    with pytest.raises(ParameterError, match="no such list file"):
        survey_detect(p, ["@" + str(tmp_path / "nolist.txt")], tmp_path / "a")
    with pytest.raises(ParameterError, match="a video"):
        survey_detect(p, [str(tmp_path / "dive.mp4")], tmp_path / "a")
    with pytest.raises(ParameterError, match="max_results"):
        survey_detect(seahough.Detector(p), [str(scenes / "imgs")], tmp_path / "a",
                      max_results=2)
    with pytest.raises(ParameterError, match="batch_size"):
        survey_detect(p, [str(scenes / "imgs")], tmp_path / "a", batch_size=0)
    with pytest.raises(ParameterError, match="workers"):
        survey_detect(p, [str(scenes / "imgs")], tmp_path / "w", workers=0)
    (tmp_path / "file").write_text("x")
    with pytest.raises(WriteError, match="cannot create the output folder"):
        survey_detect(p, [str(scenes / "imgs")], tmp_path / "file" / "out")
    assert not (tmp_path / "a").exists()


def test_inputs_lists_and_folders(scenes, tmp_path, monkeypatch):
    monkeypatch.chdir(scenes)
    lst = tmp_path / "list.txt"
    lst.write_text("imgs/s3.png\n\n  \nimgs\r\nimgs/nothere.jpg\n")
    got = expand_inputs(["imgs/s1.png", "@" + str(lst)])
    folder = [f"imgs/s{i}.png" for i in range(N)] + ["imgs/z_bad.png"]
    assert got == ["imgs/s1.png", "imgs/s3.png", *folder, "imgs/nothere.jpg"]


# ----------------------------------------------------------------------- CLI
def _cli(capsys, *args):
    with pytest.raises(SystemExit) as e:
        main(["survey", *map(str, args)])
    out, err = capsys.readouterr()
    return e.value.code, out, err


def test_cli_detect(scenes, cluster, tmp_path, capsys):
    pat = scenes / "pattern.png"
    code, out, err = _cli(capsys, "detect", pat, scenes / "imgs" / "s1.png",
                          scenes / "imgs" / "s2.png", "--out", tmp_path / "o", "--scheduler",
                          cluster.scheduler_address, "--quiet")
    assert code == 0, err
    assert "images: 2   found: 2   not found: 0   errors: 0" in out
    code, out, err = _cli(capsys, "detect", pat, scenes / "imgs", "--out", tmp_path / "b",
                          "--scheduler", cluster.scheduler_address, "--json")
    assert code == 1                            # z_bad.png could not be read
    s = json.loads(out)
    assert (s["images"], s["errors"], s["first_errors"][0]["path"]) == (
        N + 1, 1, str(scenes / "imgs" / "z_bad.png"))
    # rerun: nothing searched; other settings: one line, exit 2
    code, out, err = _cli(capsys, "detect", pat, scenes / "imgs", "--out", tmp_path / "b")
    assert code == 1 and "nothing to search" in out
    assert "\nresults: " in out and "wrote:" not in out      # (nothing was written)
    code, out, err = _cli(capsys, "detect", pat, scenes / "imgs", "--out", tmp_path / "b",
                          "--min-score", "0.6")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("seahough: error: ") and "min_score 0.5 (now 0.6)" in err


@pytest.mark.parametrize("args, message", [
    (["@{tmp}/nolist.txt"], "no such list file"),
    (["{tmp}/empty"], "no image files"),
    (["{imgs}", "--scale-range", "2", "1"], "LOW must not exceed HIGH"),
    (["{imgs}", "--workers", "0"], "--workers"),
    (["{imgs}", "--out", "{tmp}/f/o"], "cannot create the output folder"),
    # a typo on the command line: nothing started, nothing written
    (["{imgs}", "{tmp}/nosuchdir"], "nosuchdir: no such file or folder"),
    # a dead reckoning's folder: not mixed with a survey
    (["{imgs}", "--out", "{tmp}/odo"], "holds the results of an odometry (odometry.csv)"),
])
def test_cli_bad_input_one_line(scenes, tmp_path, capsys, args, message):
    (tmp_path / "empty").mkdir()
    (tmp_path / "f").write_text("x")
    (tmp_path / "odo").mkdir()
    (tmp_path / "odo" / "odometry.csv").write_text("index\n")
    args = [a.format(tmp=tmp_path, imgs=scenes / "imgs") for a in args]
    if "--out" not in args:
        args += ["--out", str(tmp_path / "o")]
    code, out, err = _cli(capsys, "detect", scenes / "pattern.png", *args)
    assert code == 2 and err.count("\n") == 1 and message in err, err
    if "nosuchdir" in message:
        assert not (tmp_path / "o").exists()


def test_cli_scheduler_nothing_listens(scenes, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(CLUSTER, "CONNECT_TIMEOUT", "1s")
    with socket.socket() as s:                 # a free port: nothing listens there
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    code, out, err = _cli(capsys, "detect", scenes / "pattern.png", scenes / "imgs", "--out",
                          tmp_path / "o", "--scheduler", f"tcp://127.0.0.1:{port}")
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"seahough: error: scheduler tcp://127.0.0.1:{port}: cannot connect")
    # a trial: the failed run left survey.json and its inputs, and the corrected
    # command (another pattern, a local cluster) was refused as "other settings"
    assert not (tmp_path / "o" / "survey.json").exists()
    assert not (tmp_path / "o" / "parts").exists()
    code, out, err = _cli(capsys, "detect", "rect:90,50", scenes / "imgs", "--out",
                          tmp_path / "o", "--workers", "1")
    assert code in (0, 1) and "other settings" not in err, err


def test_cli_odometry_wiring(tmp_path, capsys, monkeypatch):
    frames = tmp_path / "frames"
    frames.mkdir()
    calls = []

    def fake(frames_, out, **kw):
        calls.append((frames_, out, kw))
        out = tmp_path / "run"
        out.mkdir(exist_ok=True)
        (out / "summary.json").write_text(json.dumps(
            {"frames": 3, "flagged_pairs": 1, "path_length_m": 1.5, "mean_ms_per_frame": 20.0}))
        (out / "odometry.csv").write_text("index,file,x,y,flags\n0,a.png,0,0,\n"
                                          "1,b.png,1,0,\n2,c.png,,,unreadable\n")
        return {"csv": str(out / "odometry.csv"), "summary": str(out / "summary.json"),
                "trajectory": None, "mosaic": None}

    monkeypatch.setitem(sys.modules, "seahough.survey.odometry",
                        types.SimpleNamespace(odometry=fake))
    code, out, err = _cli(capsys, "odometry", frames, "--out", tmp_path / "run", "-j", "3",
                          "--chunk-size", "50", "--altitude", "2", "--focal-px", "800",
                          "--no-mosaic", "--quiet")
    assert code == 1, err
    (f, o, kw) = calls[0]
    assert f == [str(frames)] and o == str(tmp_path / "run")
    assert kw == {"workers": 3, "scheduler": None, "chunk_size": 50, "metres_per_pixel": None,
                  "altitude": 2.0, "focal_px": 800.0, "scale_range": (0.9, 1.1),
                  "angle_range": (-20.0, 20.0), "mosaic": False, "progress": False,
                  "fps": None}
    assert "frames: 3   flagged frames: 1   distance: 1.50 m" in out
    assert "flagged: frame 2 c.png: unreadable" in out
    code, out, err = _cli(capsys, "odometry", frames, "--out", tmp_path / "r", "--altitude", "2")
    assert code == 2 and "--altitude and --focal-px go together" in err
    # --equalize, as seahough odometry takes it (a review: the help promised its options)
    _cli(capsys, "odometry", frames, "--out", tmp_path / "run", "--equalize", "--quiet")
    assert calls[-1][2]["config"].equalize is True


@pytest.mark.parametrize("blocked", ["pyarrow", "distributed"])
@pytest.mark.parametrize("command", ["detect", "odometry"])
def test_without_the_survey_extra_the_commands_say_what_to_install(tmp_path, blocked, command):
    # (a real missing package, as on an install without the extra: a None in
    # sys.modules makes its import fail)
    args = (["survey", "detect", "rect:9,5", str(tmp_path), "--out", str(tmp_path / "o")]
            if command == "detect" else ["survey", "odometry", str(tmp_path), "--out",
                                         str(tmp_path / "o")])
    code = (f"import sys; sys.modules[{blocked!r}] = None\n"
            "from seahough.cli import main\n"
            f"main({args!r})\n")
    (tmp_path / "a.png").write_bytes(b"")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("seahough: error: "), proc.stderr
    assert "pip install 'seahough[survey]'" in lines[0]


def test_a_cluster_that_goes_away_is_one_error_and_the_rows_are_kept(scenes, cluster, tmp_path):
    """Cancelled tasks (a restarted scheduler, a lost connection): a SeahoughError
    naming the folder, the rows received so far in a shard, and a rerun completes."""
    import distributed

    inputs = [str(scenes / "imgs" / f"s{i % N}.png") for i in range(12)]

    def cancel_rest(done, total):
        if done == 1:
            cl = distributed.default_client()
            cl.cancel([distributed.Future(k, cl) for k in list(cl.futures)])

    out = tmp_path / "out"
    with pytest.raises(seahough.SeahoughError, match="the cluster went away.*run again"):
        survey_detect(_pattern(scenes), inputs, out, scheduler=cluster.scheduler_address,
                      batch_size=1, progress=False, on_batch=cancel_rest)
    assert list((out / "parts").glob("images-*.parquet")), "the rows received were not kept"
    r = survey_detect(_pattern(scenes), inputs, out, scheduler=cluster.scheduler_address,
                      batch_size=1, progress=False)
    _check_once(r, 12)


def test_a_new_survey_keeps_other_files_in_a_parts_folder(scenes, cluster, tmp_path):
    out = tmp_path / "out"
    (out / "parts").mkdir(parents=True)
    (out / "parts" / "notes.txt").write_text("mine")
    (out / "parts" / "images-000007.parquet").write_bytes(b"an old survey's shard")
    r = survey_detect(_pattern(scenes), [str(scenes / "imgs" / "s0.png")], out,
                      scheduler=cluster.scheduler_address, progress=False)
    _check_once(r, 1)
    assert (out / "parts" / "notes.txt").read_text() == "mine"


def test_a_workers_first_image_is_timed_without_the_warm_up(scenes, monkeypatch):
    # a process's first search loads the compiled kernels (~300 ms): searched
    # once untimed before, so that the first image's ms is its own
    det = seahough.Detector(seahough.Pattern.from_image(cv2.imread(str(scenes / "pattern.png"))))
    calls = []
    real = seahough.Detector.search
    monkeypatch.setattr(seahough.Detector, "search",
                        lambda self, img, **kw: calls.append(img.shape) or real(self, img, **kw))
    paths = [(i, str(scenes / "imgs" / f"s{i}.png")) for i in range(3)]
    rows, _ = SD.search_batch(paths, det)
    assert len(calls) == 4 and [r[2] for r in rows] == ["found"] * 3
    rows, _ = SD.search_batch(paths[:2], det)            # the same worker's next batch
    assert len(calls) == 6
    # an unreadable first image: its row says so as before, and the next one warms up
    other = seahough.Detector(seahough.Pattern.rectangle(40, 30))
    calls.clear()
    rows, _ = SD.search_batch([(9, str(scenes / "imgs" / "z_bad.png")), paths[0]], other)
    assert rows[0][2] == "error" and "z_bad.png" not in rows[0][8] and rows[0][8]
    assert rows[1][2] in ("found", "not found") and len(calls) == 2 and other in SD._WARM


def test_a_workers_warning_names_the_file_on_one_line(tmp_path, capsys, monkeypatch):
    """A trial: a 12-bit PNG in a survey gave Python's form of the warning, from
    Dask's source line, with "image" for the file; seahough detect names it."""
    import seahough.io.levels as L
    from seahough.survey.detect import search_batch

    import warnings

    monkeypatch.setattr(L, "_SAID_BITS", set())        # (said once a process)
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)   # (restored after)
    img = np.zeros((120, 160), np.uint16)
    img[30:90, 40:120] = 4000
    p = tmp_path / "c12.png"
    cv2.imwrite(str(p), img)
    rows, _ = search_batch([(0, str(p))], seahough.Detector(seahough.Pattern.rectangle(60, 40)))
    err = capsys.readouterr().err
    assert rows[0][2] in ("found", "not found")
    assert err.startswith(f"seahough: warning: {p}: a 16-bit image whose values reach only "
                          "4000"), err
    assert err.count("\n") == 1


def test_images_say_what_was_left_out_and_why_nothing_was_found(cluster, tmp_path):
    """images.parquet: ``left_out`` (more objects than max_results) and, for an
    image where nothing was found, the best candidate and why it was declined
    (a survey manager's question over thousands of photos: found nothing,
    or found something not good enough?)."""
    rng = np.random.default_rng(3)
    many = np.full((240, 320), 60, np.uint8)
    for x, y in ((60, 60), (200, 60), (60, 170), (200, 170)):
        cv2.rectangle(many, (x, y), (x + 60, y + 40), 200, -1)
    bare = cv2.GaussianBlur(rng.uniform(0, 255, (240, 320)).astype(np.uint8), (0, 0), 2)
    paths = [str(tmp_path / "many.png"), str(tmp_path / "bare.png")]
    cv2.imwrite(paths[0], many)
    cv2.imwrite(paths[1], bare)
    det = seahough.Detector(seahough.Pattern.rectangle(60, 40), (0.8, 1.25), max_results=1)
    r = survey_detect(det, paths, tmp_path / "out", scheduler=cluster.scheduler_address,
                      progress=False)
    rows = _check_once(r, 2)
    assert rows[0]["status"] == "found" and rows[0]["left_out"] >= 2, rows[0]
    assert rows[0]["left_out"] == det.search(many).left_out
    assert rows[0]["best_score"] is None and rows[0]["declined"] is None
    assert rows[1]["status"] == "not found" and rows[1]["left_out"] == 0
    # the same candidate, score and reason as the search in this process
    from seahough.core.candidates import best_declined
    best = best_declined(det.search(bare))
    assert best is not None
    assert rows[1]["best_score"] == pytest.approx(best.score)
    assert rows[1]["declined"] == best.declined and rows[1]["declined"]


def test_a_run_stopped_by_an_error_says_which(tmp_path):
    """survey.json after an error: state stopped, the error itself (not its
    class alone), and the images done as the shards hold them."""
    shards = _shards()
    with pytest.raises(RuntimeError):
        with shards.SurveyFolder(tmp_path / "o") as f:
            f.start({"a": 1}, ["x.png", "y.png", "z.png"])
            f.write_part([shards.image_row(0, "x.png", "not found"),
                          shards.image_row(1, "y.png", "not found")], [])
            raise RuntimeError("the disk went away")
    rec = json.loads((tmp_path / "o" / "survey.json").read_text())
    assert rec["state"] == "stopped"
    assert rec["stopped"]["why"] == "stopped by an error: RuntimeError: the disk went away"
    assert rec["stopped"]["images_done"] == 2
