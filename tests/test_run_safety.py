"""Run safety of the dead reckoning (issue 18): nothing lost, nothing spliced,
nothing swallowed.

A damaged video keeps every frame in the table; ``--resume`` continues only
the run it belongs to (same settings, same frames); one run at a time writes
an output folder, and a new run leaves nothing of the previous one; a folder
that cannot be written is a ``WriteError``; links, loops and folders among
the frames get rows; frames too small to measure are refused; and names with
control characters cannot split the printed tables.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import stat
import struct
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

import seahough
from seahough import sim as S
from seahough.config import OdometryTuning
from seahough.errors import ImageSizeError, ParameterError, WriteError
from seahough.io.frames import FrameReader, list_frames
from seahough.motion import read_odometry_csv, run_odometry

from conftest import as_unprivileged, seahough_command
from test_odometry import _KILL_SCRIPT, _csv_without_timing as _rows, _write_frames

SRC = Path(__file__).resolve().parents[1] / "src"
SHAPE = (120, 160)


# ----------------------------------------------------------------------------- helpers
def _env() -> dict:
    env = dict(os.environ)
    env.setdefault("MPLBACKEND", "Agg")
    # (importing seahough set it in this process: the command must set it itself)
    env.pop("OPENCV_FFMPEG_LOGLEVEL", None)
    return env


def cli(*args, cwd=None, timeout=180):
    return subprocess.run([str(seahough_command()), *map(str, args)], cwd=cwd, env=_env(),
                          capture_output=True, text=True, timeout=timeout)


def one_error_line(proc, *needles):
    assert proc.returncode == 2, (proc.returncode, proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("seahough: error: "), proc.stderr
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


def _frames(n=8, seed=0):
    frames, _ = S.sequence(None, n_frames=n, frame_size=SHAPE, path="line", step=6.0, seed=seed,
                           source="procedural")
    return frames


def _write(frames, folder: Path):
    return _write_frames(frames, folder, prefix="f_")


# ------------------------------------------------------------- 1. damaged videos
def _avi(path: Path, frames, fps=10.0):
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, SHAPE[::-1])
    if not vw.isOpened():
        pytest.skip("OpenCV cannot write an MJPG video here")
    for f in frames:
        vw.write(f)
    vw.release()


def _video_chunks(data: bytes):
    """(offset, size) of each video chunk (``00dc``) of an AVI's ``movi`` list."""
    pos = data.index(b"movi") + 4
    out = []
    while pos + 8 <= len(data):
        cid, size = data[pos:pos + 4], struct.unpack("<I", data[pos + 4:pos + 8])[0]
        if cid == b"idx1" or not cid.isalnum():
            break
        if cid == b"00dc":
            out.append((pos, size))
        pos += 8 + size + (size & 1)
    return out


def _damage(data: bytes, how: str, k: int) -> bytes:
    """``cut``: the k-th frame's chunk claims 3 bytes (the decoder fails on
    it, the demuxer reads on); ``zero``: 20 kB zeroed from the k-th frame on
    (those frames are lost and the demuxer resynchronises after them)."""
    chunks = _video_chunks(data)
    assert len(chunks) > k + 10
    d = bytearray(data)
    pos = chunks[k][0]
    if how == "cut":
        d[pos + 4:pos + 8] = struct.pack("<I", 3)
    else:
        d[pos:pos + 20000] = bytes(20000)
    return bytes(d)


@pytest.mark.parametrize("how", ["cut", "zero"])
def test_a_damaged_video_keeps_every_frame_in_the_csv(tmp_path, how):
    # 59 frames, damaged in the middle: every frame index the container holds
    # has its row, the frames that cannot be read are flagged, the command
    # says the run is not complete (exit 1), and FFmpeg prints nothing
    good = tmp_path / "good.avi"
    _avi(good, _frames(59, seed=3))
    if len(_video_chunks(good.read_bytes())) != 59:
        pytest.skip("this OpenCV writes AVI files of another layout")
    bad = tmp_path / "bad.avi"
    bad.write_bytes(_damage(good.read_bytes(), how, 29))
    assert len(list_frames(bad)) == 59
    proc = cli("odometry", bad, "--out", tmp_path / "o", "--quiet", "--no-mosaic")
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    assert proc.stderr == ""
    assert proc.stdout.startswith("frames: 59 ")
    rows = read_odometry_csv(tmp_path / "o" / "odometry.csv")
    assert [r["index"] for r in rows] == list(range(59))
    assert [r["file"] for r in rows] == [f"{bad}#{i}" for i in range(59)]
    lost = [r for r in rows if r["status"] == "unreadable"]
    assert lost and all(r["flags"].startswith("unreadable: ") and r["x"] is None for r in lost)
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["frames"] == 59 and summary["unreadable_frames"] == len(lost)


def test_a_video_reader_reads_past_a_bad_frame(tmp_path):
    good = tmp_path / "good.avi"
    frames = _frames(40, seed=4)
    _avi(good, frames)
    bad = tmp_path / "bad.avi"
    bad.write_bytes(_damage(good.read_bytes(), "cut", 20))
    items = list_frames(bad)
    reader = FrameReader(items, 10 ** 8)
    got = []
    for i in range(len(items)):
        try:
            got.append(reader.raw(i))
        except seahough.ImageError as e:
            assert "bad.avi" in str(e) and "frame 20" in str(e)
            got.append(None)
    reader.close()
    assert len(got) == 40 and got[20] is None
    # the frames after the damage are where they were written
    for i in (19, 21, 39):
        assert np.abs(got[i].astype(float) - frames[i]).mean() < 6.0, i


# ---------------------------------------------------------------- 2. resume and --out
def test_resume_with_other_settings_is_refused_naming_them(tmp_path):
    paths = _write(_frames(8), tmp_path / "frames")
    out = tmp_path / "out"
    run_odometry(paths[:4], out, progress=False, mosaic=False)
    before = (out / "odometry.csv").read_bytes()
    for kw, needle in (({"scale_range": (0.8, 1.2)}, "scale_range"),
                       ({"angle_range": (-10, 10)}, "angle_range"),
                       ({"metres_per_pixel": 0.01}, "metres_per_pixel"),
                       ({"tuning": OdometryTuning(min_confidence=0.3)}, "tuning.min_confidence"),
                       ({"config": seahough.config.ODOMETRY_CONFIG.replace(n_keypoints=300)},
                        "config.n_keypoints")):
        with pytest.raises(ParameterError, match=needle) as e:
            run_odometry(paths, out, resume=True, progress=False, mosaic=False, **kw)
        assert "\n" not in str(e.value)
        assert (out / "odometry.csv").read_bytes() == before        # nothing spliced
    proc = cli("odometry", *paths, "--out", out, "--resume", "--scale-range", 0.8, 1.2,
               "--quiet", "--no-mosaic")
    one_error_line(proc, "scale_range")
    # the same settings continue the run, to the result of an uninterrupted one
    full = run_odometry(paths, tmp_path / "full", progress=False, mosaic=False)
    res = run_odometry(paths, out, resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == 4
    assert _rows(res.csv_path) == _rows(full.csv_path)


def test_resume_refuses_a_csv_without_the_checks(tmp_path):
    # a CSV of a seahough that wrote no frame or settings hashes cannot be checked
    paths = _write(_frames(5), tmp_path / "frames")
    out = tmp_path / "out"
    run_odometry(paths[:3], out, progress=False, mosaic=False)
    with open(out / "odometry.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    keep = [k for k in rows[0] if k not in ("frame_hash", "settings_hash")]
    with open(out / "odometry.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keep, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    (out / "run.json").unlink()
    with pytest.raises(ParameterError, match="older seahough.*without --resume"):
        run_odometry(paths, out, resume=True, progress=False, mosaic=False)


def test_resume_refuses_frames_that_changed_under_the_same_names(tmp_path):
    folder = tmp_path / "frames"
    _write(_frames(8, seed=0), folder)
    out = tmp_path / "out"
    run_odometry(list_frames(folder)[:5], out, progress=False, mosaic=False)
    shutil.rmtree(folder)
    _write(_frames(8, seed=1), folder)                     # another dive, the same names
    with pytest.raises(ParameterError, match="f_000.png.*changed") as e:
        run_odometry(folder, out, resume=True, progress=False, mosaic=False)
    assert "\n" not in str(e.value)
    # arrays too: their pixels are compared
    a, b = _frames(6, seed=0), _frames(6, seed=1)
    run_odometry(a[:3], tmp_path / "arrays", progress=False, mosaic=False)
    with pytest.raises(ParameterError, match="frame_00000.*changed"):
        run_odometry(b, tmp_path / "arrays", resume=True, progress=False, mosaic=False)
    res = run_odometry(a, tmp_path / "arrays", resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == 3 and res.summary["frames"] == 6


def test_resume_takes_the_same_frames_by_another_path(tmp_path, monkeypatch):
    _write(_frames(8), tmp_path / "frames")
    monkeypatch.chdir(tmp_path)
    rel = list_frames("frames")
    assert not os.path.isabs(rel[0])
    full = run_odometry(rel, "full", progress=False, mosaic=False)
    run_odometry(rel[:4], "out", progress=False, mosaic=False)
    absolute = [str(tmp_path / p) for p in rel]
    res = run_odometry(absolute, tmp_path / "out", resume=True, progress=False, mosaic=False)
    assert res.summary["resumed_rows"] == 4
    got, want = _rows(res.csv_path), _rows(full.csv_path)
    for r in got + want:
        r["file"] = os.path.abspath(r["file"])
    assert got == want
    # a relative path from elsewhere names the same files too
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    again = run_odometry([os.path.join("..", p) for p in rel], tmp_path / "out", resume=True,
                         progress=False, mosaic=False)
    assert again.summary["resumed_rows"] == 8


def test_one_run_at_a_time_writes_an_output_folder(tmp_path):
    folder = tmp_path / "frames"
    _write(_frames(12), folder)
    out = tmp_path / "out"
    env = dict(_env(), PYTHONPATH=os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]))
    # (a run slowed to 0.3 s a frame, to be caught while it runs)
    proc = subprocess.Popen([sys.executable, "-c", _KILL_SCRIPT, str(folder), str(out), "0.3"],
                            env=env)
    try:
        deadline = time.time() + 120
        csv_path = out / "odometry.csv"
        while time.time() < deadline and proc.poll() is None:
            if csv_path.exists() and len(csv_path.read_text().splitlines()) >= 3:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the first run ended too soon"
        with pytest.raises(WriteError, match="another seahough run") as e:
            run_odometry(folder, out, progress=False, mosaic=False)
        assert str(out) in str(e.value)
        with pytest.raises(WriteError, match="another seahough run"):
            run_odometry(folder, out, resume=True, progress=False, mosaic=False)
        one_error_line(cli("odometry", folder, "--out", out, "--quiet"), str(out), "another")
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
    # a killed run holds nothing: the folder is free again, and --resume finishes it
    res = run_odometry(folder, out, resume=True, progress=False, mosaic=False)
    full = run_odometry(folder, tmp_path / "full", progress=False, mosaic=False)
    assert 1 <= res.summary["resumed_rows"] < 12
    assert _rows(res.csv_path) == _rows(full.csv_path)


def test_a_new_run_leaves_nothing_of_the_previous_one(tmp_path, monkeypatch):
    paths = _write(_frames(6), tmp_path / "frames")
    out = tmp_path / "out"
    run_odometry(paths, out, progress=False)
    olds = [out / n for n in ("summary.json", "mosaic.png", "trajectory.png")]
    assert all(p.is_file() for p in olds)
    raw = FrameReader.raw

    def dies_at_3(self, i):
        if i == 3:
            raise KeyboardInterrupt
        return raw(self, i)

    monkeypatch.setattr(FrameReader, "raw", dies_at_3)
    with pytest.raises(KeyboardInterrupt):
        run_odometry(paths, out, progress=False)
    assert [p.name for p in olds if p.exists()] == []
    assert len(read_odometry_csv(out / "odometry.csv")) == 3   # only the new run's rows
    monkeypatch.setattr(FrameReader, "raw", raw)
    # (and a run without a mosaic leaves no mosaic of an earlier run beside its track)
    run_odometry(paths, out, progress=False)
    res = run_odometry(paths, out, progress=False, mosaic=False)
    assert res.mosaic_path is None and not (out / "mosaic.png").exists()


# ------------------------------------------------------------------- 3. bad --out
def test_an_out_dir_that_cannot_be_a_folder_is_a_write_error(tmp_path):
    paths = _write(_frames(3), tmp_path / "frames")
    blocker = tmp_path / "blocker"
    blocker.write_text("a file")
    for out in (blocker, blocker / "sub"):
        with pytest.raises(WriteError, match=str(out)):
            run_odometry(paths, out, progress=False, mosaic=False)
    one_error_line(cli("odometry", *paths, "--out", blocker / "sub", "--quiet"), "blocker")


def test_an_out_dir_without_permission_is_a_write_error(tmp_path, monkeypatch):
    paths = _write(_frames(3), tmp_path / "frames")
    real_mkdir = Path.mkdir

    def denied(self, *a, **kw):
        if self.name == "locked":
            raise PermissionError(13, "Permission denied", str(self))
        return real_mkdir(self, *a, **kw)

    monkeypatch.setattr(Path, "mkdir", denied)
    with pytest.raises(WriteError, match="locked.*permission denied"):
        run_odometry(paths, tmp_path / "locked", progress=False, mosaic=False)


def test_an_out_dir_without_permission_for_another_user(tmp_path):
    # the same as a user whom the permission bits stop (root is not stopped)
    prefix = as_unprivileged(probe=[str(seahough_command()), "--version"])
    base = Path(os.path.realpath("/tmp")) / f"seahough-perm-{os.getpid()}"
    base.mkdir(mode=0o755)
    try:
        paths = _write(_frames(3), base / "frames")
        for p in [base / "frames", *paths]:
            os.chmod(p, 0o755 if Path(p).is_dir() else 0o644)
        (base / "ro").mkdir(mode=0o555)
        (base / "cache").mkdir(mode=0o777)       # the user's own Numba cache (no fallback note)
        os.chmod(base / "cache", 0o777)
        env = dict(_env(), NUMBA_CACHE_DIR=str(base / "cache"))
        proc = subprocess.run(prefix + [str(seahough_command()), "odometry", *paths, "--out",
                                        str(base / "ro" / "out"), "--quiet"],
                              capture_output=True, text=True, timeout=180, env=env)
        one_error_line(proc, str(base / "ro" / "out"))
    finally:
        shutil.rmtree(base, ignore_errors=True)


def test_resume_refuses_a_read_only_csv(tmp_path):
    paths = _write(_frames(5), tmp_path / "frames")
    out = tmp_path / "out"
    run_odometry(paths[:3], out, progress=False, mosaic=False)
    csv_path = out / "odometry.csv"
    before = csv_path.read_bytes()
    os.chmod(csv_path, 0o444)
    try:
        with pytest.raises(WriteError, match="odometry.csv.*read-only"):
            run_odometry(paths, out, resume=True, progress=False, mosaic=False)
        with pytest.raises(WriteError, match="read-only"):
            run_odometry(paths, out, progress=False, mosaic=False)     # nor replaced by a new run
        one_error_line(cli("odometry", *paths, "--out", out, "--resume", "--quiet"), "read-only")
        assert csv_path.read_bytes() == before
        assert stat.S_IMODE(csv_path.stat().st_mode) == 0o444
    finally:
        os.chmod(csv_path, 0o644)


# ----------------------------------------------------- 4. what a frame folder holds
def test_links_loops_and_folders_among_the_frames_get_flagged_rows(tmp_path):
    folder = tmp_path / "frames"
    _write(_frames(9), folder)
    (folder / "f_002.png").unlink()
    (folder / "f_002.png").symlink_to(tmp_path / "gone.png")          # dangling
    (folder / "f_004.png").unlink()
    (folder / "f_005.png").unlink()
    (folder / "f_004.png").symlink_to(folder / "f_005.png")           # a loop
    (folder / "f_005.png").symlink_to(folder / "f_004.png")
    (folder / "f_007.png").unlink()
    (folder / "f_007.png").mkdir()                                    # a folder
    (folder / ".hidden.png").write_bytes(b"")                         # hidden: not a frame
    res = run_odometry(folder, tmp_path / "out", progress=False, mosaic=False)
    rows = res.rows
    assert [Path(r["file"]).name for r in rows] == [f"f_{i:03d}.png" for i in range(9)]
    want = {2: "broken symbolic link", 4: "symbolic link loop", 5: "symbolic link loop",
            7: "is a folder"}
    for i, words in want.items():
        assert rows[i]["status"] == "unreadable" and rows[i]["flags"].startswith("unreadable: ")
        assert words in rows[i]["flags"], rows[i]["flags"]
    assert all(rows[i]["status"] in ("origin", "measured") for i in (0, 1, 3, 6, 8))
    assert res.summary["unreadable_frames"] == 4



def test_a_broken_link_in_a_list_of_frames_or_images_is_named_and_flagged(tmp_path):
    """A user trial: a broken link named on the command line (a shell glob
    over the frames' folder) refused the whole odometry run as "no such file
    or folder", and detect called it "no such file", though the folder
    shows it; a folder's broken link was a flagged row. Now a listed one is
    flagged the same way, and named for what it is."""
    folder = tmp_path / "frames"
    _write(_frames(4), folder)
    (folder / "f_002.png").unlink()
    (folder / "f_002.png").symlink_to(tmp_path / "gone.png")
    paths = sorted(folder.iterdir())
    proc = cli("odometry", *paths, "--out", tmp_path / "out", "-q")
    assert proc.returncode == 1, proc.stderr            # (a frame flagged, the run done)
    rows = list(csv.DictReader(open(tmp_path / "out" / "odometry.csv")))
    assert rows[2]["status"] == "unreadable" and "broken symbolic link" in rows[2]["flags"]
    assert all(rows[i]["status"] in ("origin", "measured") for i in (0, 1, 3))
    with pytest.raises(seahough.ImageReadError, match=r"f_002.png: broken symbolic link \(to "):
        seahough.read_image(folder / "f_002.png")
    proc = cli("detect", "circle:10", folder / "f_002.png")
    assert proc.returncode == 2 and "broken symbolic link" in proc.stderr, proc.stderr
    # a path that is not there at all is still a typo: nothing is started
    proc = cli("odometry", *paths, folder / "f_009.png", "--out", tmp_path / "out2", "-q")
    assert proc.returncode == 2 and "no such file" in proc.stderr

# ------------------------------------------------------------ 5. frames too small
def test_frames_too_small_to_measure_are_refused():
    from seahough.motion.pair import MIN_MOTION_SIDE

    g = cv2.cvtColor(S.seabed((400, 500), seed=0), cv2.COLOR_BGR2GRAY)
    for h, w in ((8, 320), (MIN_MOTION_SIDE - 1, 400), (300, 40)):
        a = g[100:100 + h, 50:50 + w]
        with pytest.raises(ImageSizeError, match=f"{w}x{h}.*at least {MIN_MOTION_SIDE} px"):
            seahough.estimate_motion(a, a)
    a = g[100:100 + MIN_MOTION_SIDE, 50:450]
    m = seahough.estimate_motion(a, a)
    assert m is not None and abs(m.dx) < 0.5 and abs(m.dy) < 0.5


def test_odometry_flags_frames_too_small_to_measure(tmp_path):
    frames, _ = S.sequence(None, n_frames=5, frame_size=(8, 320), step=2.0, seed=0,
                           source="procedural")
    res = run_odometry(frames, tmp_path, progress=False, mosaic=False)
    assert [r["status"] for r in res.rows] == ["unreadable"] * 5
    assert all("too small" in r["flags"] and "320x8" in r["flags"] for r in res.rows)
    assert res.summary["measured_pairs"] == 0 and res.summary["flagged_pairs"] == 5


# ------------------------------------------------ 6. control characters in names
def test_a_newline_in_a_file_name_does_not_split_the_detect_table(tmp_path):
    scene, pattern, _ = S.marker_scene("board", seed=3, source="procedural")
    odd = tmp_path / "two\nlines\r\x1b[31m.png"
    cv2.imwrite(str(tmp_path / "plain.png"), scene)
    os.rename(tmp_path / "plain.png", odd)
    cv2.imwrite(str(tmp_path / "pattern.png"), pattern)
    bad = tmp_path / "bad\n.png"
    bad.write_text("not an image")
    proc = cli("detect", tmp_path / "pattern.png", odd, bad, "--scale-range", 0.5, 2)
    assert proc.returncode == 2
    lines = proc.stdout.splitlines()
    assert lines[0].startswith(str(tmp_path / "two\\nlines\\r\\x1b[31m.png") + "  ")
    assert len(lines) == 3 and lines[1].lstrip().startswith("#")       # the name, the table
    err = proc.stderr.splitlines()
    assert len(err) == 1 and "bad\\n.png" in err[0]
    assert "\x1b" not in proc.stdout + proc.stderr


def test_odometry_csv_with_control_characters_in_names_stays_parseable(tmp_path):
    folder = tmp_path / "frames"
    paths = _write(_frames(5), folder)
    names = []
    for i, (p, odd) in enumerate(zip(paths, ["a\nb", "c\rd", "e\r\nf", "g,h\"i", "j\tk"])):
        q = folder / f"f_{i:03d}_{odd}.png"
        os.rename(p, q)
        names.append(str(q))
    res = run_odometry(names, tmp_path / "out", progress=False, mosaic=False)
    rows = read_odometry_csv(res.csv_path)
    assert [r["file"] for r in rows] == names
    assert [r["status"] for r in rows] == ["origin"] + ["measured"] * 4
    with open(res.csv_path, newline="") as f:
        assert [r["file"] for r in csv.DictReader(f)] == names
    # a resume reads them back too
    again = run_odometry(names, tmp_path / "out", resume=True, progress=False, mosaic=False)
    assert again.summary["resumed_rows"] == 5
    proc = cli("odometry", *names, "--out", tmp_path / "cli", "--no-mosaic", "--quiet")
    assert proc.returncode == 0 and len(proc.stdout.splitlines()) == 2, proc.stdout


def _lock_again(path, q):
    from seahough.errors import WriteError
    from seahough.motion.runfiles import RunFolder
    try:
        RunFolder(path)
        q.put("locked")
    except WriteError as e:
        q.put(str(e))


def test_a_worker_that_starts_the_run_again_is_told_about_the_main_guard(tmp_path):
    """A script without ``if __name__ == "__main__":`` runs its survey again in
    each worker process (they import it): the worker found the folder held
    by "another seahough run (process N)", N being its own parent. It is told
    what to do instead."""
    import multiprocessing

    from seahough.motion.runfiles import RunFolder

    held = RunFolder(tmp_path / "out")
    try:
        ctx = multiprocessing.get_context("spawn")
        q = ctx.Queue()
        p = ctx.Process(target=_lock_again, args=(str(tmp_path / "out"), q))
        p.start()
        msg = q.get(timeout=60)
        p.join(timeout=60)
    finally:
        held.release()
    assert "put the script's code under `if __name__ == \"__main__\":`" in msg, msg
