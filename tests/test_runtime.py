"""Nothing lost, nothing spliced, nothing swallowed (issue 18, the runtime
part): importing where nothing can be written, Ctrl-C inside a compiled
kernel, bins at their documented limits, and sub-pixel shapes."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import click
import cv2
import numpy as np
import pytest

import seahough
from seahough import Config, Detector, Pattern
from seahough.cli import cli, main
from seahough.errors import ParameterError

from conftest import NOBODY, as_unprivileged, seahough_command

SRC = Path(seahough.__file__).resolve().parent

_DETECT = """
import numpy as np, seahough
p = seahough.Pattern.rectangle(40, 24)
img = np.zeros((120, 160), np.uint8)
img[40:64, 60:100] = 200
d = seahough.Detector(p).detect(img)
assert d and abs(d[0].x - 79.5) < 1.5 and abs(d[0].y - 51.5) < 1.5, d
print("found at", round(d[0].x), round(d[0].y), "with", seahough.__file__)
"""


def _scene(seed: int = 0) -> np.ndarray:
    """640x480 seabed-like texture with a bright 120x80 rectangle at (200, 150)."""
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur((rng.random((480, 640)) * 60 + 40).astype(np.float32), (0, 0), 3)
    img[150:230, 200:320] += 120
    return np.clip(img, 0, 255).astype(np.uint8)


# ------------------------------------------------- 1. nothing writable at all
def _as_unprivileged(env: dict) -> list[str]:
    """The command prefix that runs a child as a user who can write nowhere
    but ``env["TMPDIR"]``; skips the test when this environment cannot."""
    prefix = as_unprivileged(env, [sys.executable, "-c", "import numpy, numba, cv2, click"])
    if prefix:
        os.chown(env["TMPDIR"], NOBODY, NOBODY)
    return prefix


@pytest.mark.slow
def test_import_and_detect_where_nothing_can_be_written(tmp_path):
    """A system or container install run by a service user: the package folder
    and HOME are read-only. The kernels are compiled into a private folder
    under the temporary folder, said once, with no traceback (before: the
    import failed with "cannot cache function ...: no locator available")."""
    site = tmp_path / "site"
    shutil.copytree(SRC, site / "seahough", ignore=shutil.ignore_patterns("__pycache__"))
    home = tmp_path / "home"
    home.mkdir()
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(home),
           "TMPDIR": str(tmp), "PYTHONPATH": str(site), "MPLBACKEND": "Agg",
           "LANG": "C.UTF-8"}
    for sub, dirs, files in os.walk(site):
        for f in files:
            os.chmod(os.path.join(sub, f), 0o444)
    read_only = [Path(sub) / x for sub, dirs, _ in os.walk(site) for x in dirs] + [site, home]
    for d in read_only:
        os.chmod(d, 0o555)
    try:
        prefix = _as_unprivileged(env)
        proc = subprocess.run(prefix + [sys.executable, "-c", _DETECT], env=env, cwd=str(tmp),
                              capture_output=True, text=True, timeout=300)
    finally:
        for d in read_only:
            os.chmod(d, 0o755)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    assert f"with {site / 'seahough'}" in proc.stdout, proc.stdout
    # said once, on one line of its own
    assert proc.stderr.count("KernelCacheWarning") == 1, proc.stderr
    note = next(line for line in proc.stderr.splitlines() if "KernelCacheWarning" in line)
    assert str(tmp) in note, note
    # and the compiled kernels are there for the next run
    assert list(tmp.glob("seahough-numba-*/**/*.nbi")), sorted(map(str, tmp.rglob("*")))


def test_cache_choice_keeps_a_working_location(monkeypatch, tmp_path):
    """Numba's own choice (here a NUMBA_CACHE_DIR the user set) is kept as it is."""
    import numba

    from seahough.core.kernels import _cache

    monkeypatch.setattr(_cache, "CACHE", _cache.CACHE)      # restored after
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "mine"))
    with _cache.kernel_cache() as where:
        assert Path(where).parent == tmp_path / "mine" and _cache.CACHE
        assert numba.config.CACHE_DIR == str(tmp_path / "mine")
    assert numba.config.CACHE_DIR == str(tmp_path / "mine")


def test_cache_falls_back_to_a_private_temp_folder_then_to_none(monkeypatch, tmp_path):
    import numba

    from seahough.core.kernels import _cache

    monkeypatch.setattr(_cache, "CACHE", _cache.CACHE)      # restored after
    monkeypatch.setattr(numba.config, "CACHE_DIR", "")
    monkeypatch.setattr(_cache.tempfile, "gettempdir", lambda: str(tmp_path))
    # no locator of Numba's own works (read-only install, HOME read-only) ...
    real = _cache.cache_path
    monkeypatch.setattr(_cache, "cache_path", lambda: real() if numba.config.CACHE_DIR else None)
    with pytest.warns(_cache.KernelCacheWarning, match="caching the compiled kernels in") as rec:
        with _cache.kernel_cache() as where:
            root = Path(numba.config.CACHE_DIR)
            assert Path(where).parent == root and root.parent == tmp_path and _cache.CACHE
            assert (root.stat().st_mode & 0o777) == 0o700
    assert len(rec) == 1 and str(tmp_path) in str(rec[0].message)
    assert numba.config.CACHE_DIR == ""            # restored for other libraries
    # ... and no temporary folder either: no cache, said once
    monkeypatch.setattr(_cache, "cache_path", lambda: None)
    with pytest.warns(_cache.KernelCacheWarning, match="compiled anew") as rec:
        with _cache.kernel_cache() as where:
            assert where is None and not _cache.CACHE
    assert len(rec) == 1 and numba.config.CACHE_DIR == ""


@pytest.mark.skipif(os.name != "posix", reason="ownership and modes are POSIX")
def test_private_folder_must_be_ours_and_closed(tmp_path):
    from seahough.core.kernels import _cache

    d = _cache.private_dir(str(tmp_path))
    assert d is not None and Path(d).parent == tmp_path
    assert _cache.private_dir(str(tmp_path)) == d                  # found again
    os.chmod(d, 0o777)                                              # opened to others
    assert _cache.private_dir(str(tmp_path)) is None
    os.chmod(d, 0o700)
    if os.geteuid() == 0:                                           # someone else's
        os.chown(d, NOBODY, NOBODY)
        assert _cache.private_dir(str(tmp_path)) is None
    shutil.rmtree(d)
    Path(d).symlink_to(tmp_path)                                    # a planted link
    assert _cache.private_dir(str(tmp_path)) is None
    assert _cache.private_dir(str(tmp_path / "missing" / "deeper")) is None


# ------------------------------------------------- 2. Ctrl-C in compiled code
@pytest.fixture
def raising_command(monkeypatch):
    """A command ``boom`` that raises the exception it is given."""
    box = {}

    @click.command("boom")
    def boom():
        raise box["exc"]

    monkeypatch.setitem(cli.commands, "boom", boom)
    return box


def _numba_style_interrupt() -> SystemError:
    """What a SIGINT during a compiled kernel gives: the KeyboardInterrupt
    raised inside ``_numba_unpickle`` while the results are boxed, then a
    SystemError for each boxed value, each caused by the one before."""
    exc = KeyboardInterrupt()
    for _ in range(3):
        try:
            raise SystemError("CPUDispatcher(<function edge_points>) returned a result "
                              "with an exception set") from exc
        except SystemError as e:
            exc = e
    return exc


def test_main_reports_an_interrupt_inside_compiled_code_as_interrupted(raising_command, capsys):
    implicit = SystemError("returned a result with an exception set")
    implicit.__context__ = KeyboardInterrupt()
    for exc in (_numba_style_interrupt(), implicit, KeyboardInterrupt()):
        raising_command["exc"] = exc
        with pytest.raises(SystemExit) as e:
            main(["boom"])
        assert e.value.code == 130
        # as for any Ctrl-C: click ends the line of the ^C, then one line
        assert capsys.readouterr().err == "\nseahough: error: interrupted\n"
    # any other SystemError is a bug, and stays one
    raising_command["exc"] = SystemError("a bug")
    with pytest.raises(SystemError, match="a bug"):
        main(["boom"])


def test_main_reports_sigterm_as_terminated_also_inside_compiled_code(raising_command, capsys,
                                                                     monkeypatch):
    """SIGTERM is raised as the CLI's own _Terminated (where Ctrl-C would be),
    inside a compiled kernel wrapped in SystemErrors as a Ctrl-C is there:
    one line, status 143, no traceback; an ignored SIGTERM stays ignored."""
    import signal

    from seahough.cli import _Terminated, _catch_signals

    inside = _Terminated()
    for _ in range(2):
        try:
            raise SystemError("returned a result with an exception set") from inside
        except SystemError as e:
            inside = e
    for exc in (_Terminated(), inside):
        raising_command["exc"] = exc
        with pytest.raises(SystemExit) as e:
            main(["boom"])
        assert e.value.code == 143
        err = capsys.readouterr().err
        assert err.startswith("seahough: error: terminated (SIGTERM)") and err.count("\n") == 1
    old = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        got = _catch_signals()
        assert signal.SIGTERM not in got and signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGTERM, old)
        for sig, handler in got.items():
            signal.signal(sig, handler)


def test_an_interruption_sent_twice_does_not_interrupt_the_saving():
    """``timeout -s INT`` signals the command, then its process group: the
    command got SIGINT twice, and the second interrupted the first one's
    saving (a survey's shard left as a .tmp, its images searched again; or
    the cluster's shutdown hung). A repeat within _REPEAT_S is ignored: the
    ``finally`` clause runs to its end."""
    import os
    import signal

    from seahough.cli import _Terminated, _catch_signals

    # (a job started in the background, as `nohup ... &` starts a CI run,
    # inherits SIGINT ignored, which _catch_signals rightly keeps ignored)
    caller = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _interrupted_twice(_catch_signals, _Terminated)
    finally:
        signal.signal(signal.SIGINT, caller)


def _interrupted_twice(_catch_signals, _Terminated):
    import os
    import signal

    for first, second, kind in ((signal.SIGINT, signal.SIGINT, KeyboardInterrupt),
                                (signal.SIGTERM, signal.SIGINT, _Terminated)):
        old = _catch_signals()
        saved = []
        try:
            with pytest.raises(kind):
                try:
                    os.kill(os.getpid(), first)
                    time.sleep(1.0)                 # (the handler raises before this ends)
                finally:
                    os.kill(os.getpid(), second)    # the same interruption, again
                    time.sleep(0.05)
                    saved.append(True)              # the saving went on to its end
            assert saved == [True]
        finally:
            for sig, handler in old.items():
                signal.signal(sig, handler)


def test_ctrl_c_during_detection_is_one_line_and_status_130(tmp_path):
    """SIGINT at 14 moments of a detection run, 0.05-1.5 s after its first
    image (some land inside the compiled kernels: before, 2 of 19 such
    trials ended in a SystemError traceback; about 15 s, two at a time)."""
    img = tmp_path / "noise.png"
    rng = np.random.default_rng(0)
    noise = cv2.GaussianBlur((rng.random((480, 640)) * 255).astype(np.float32), (0, 0), 2)
    cv2.imwrite(str(img), cv2.normalize(noise, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8))
    args = [str(seahough_command()), "detect", "rect:40,24", *[str(img)] * 300, "--quiet"]
    env = dict(os.environ, PYTHONUNBUFFERED="1", MPLBACKEND="Agg")

    def trial(delay):
        # (Ctrl-C at its default in the command: a job started in the background by a
        # non-interactive shell, as a CI runner may start this suite, ignores SIGINT,
        # and a Python started with SIGINT ignored keeps ignoring it)
        p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=env, preexec_fn=lambda: signal.signal(signal.SIGINT,
                                                                       signal.SIG_DFL))
        try:
            p.stdout.readline()            # one image done: the kernels are running
            time.sleep(delay)
            p.send_signal(signal.SIGINT)
            _, err = p.communicate(timeout=60)
        finally:
            if p.poll() is None:
                p.kill()
        return delay, p.returncode, err

    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(trial, np.linspace(0.05, 1.5, 14)))
    for delay, rc, err in results:
        assert "Traceback" not in err, f"SIGINT {delay:.2f} s after the first image:\n{err}"
        assert rc == 130 and err == "\nseahough: error: interrupted\n", (delay, rc, err)


# ------------------------------------------------- 3. bins at their limits
@pytest.mark.parametrize("bins, fields", [
    (dict(translation_bin=0.25, angle_bin=0.1, scale_step=0.001),
     ("Config.translation_bin (0.25)", "Config.angle_bin (0.1)", "Config.scale_step (0.001)")),
    (dict(angle_bin=0.1, scale_step=0.001), ("Config.angle_bin (0.1)", "Config.scale_step (0.001)")),
])
def test_finest_bins_are_refused_at_once_naming_the_fields(bins, fields):
    """Before: a MemoryError traceback after 21 s, and 76 s of voting."""
    img = _scene()
    det = Detector(Pattern.rectangle(120, 80), config=Config(**bins))
    t0 = time.perf_counter()
    with pytest.raises(ParameterError) as e:
        det.detect(img)
    assert time.perf_counter() - t0 < 1.0
    msg = str(e.value)
    assert "over the limit" in msg and "scale_range" in msg, msg
    for f in fields:
        assert f in msg, msg


def test_defaults_and_documented_coarse_bins_still_search():
    img = _scene()
    for cfg in (Config(), Config(voting="points"), Config(voting="segments"),
                Config(translation_bin=2.0, angle_bin=2.0, scale_step=0.02)):
        found = Detector(Pattern.rectangle(120, 80), config=cfg).detect(img)
        assert found and abs(found[0].x - 259.5) < 2 and abs(found[0].y - 189.5) < 2, (cfg, found)


# ------------------------------------------------- 4. sub-pixel shapes
def test_sub_pixel_shape_on_the_command_line(tmp_path):
    img = tmp_path / "scene.png"
    cv2.imwrite(str(img), _scene())
    proc = subprocess.run([str(seahough_command()), "detect", "rect:1e-9,50", str(img)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, (proc.stdout, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("seahough: error: ") and "width=1e-09" in lines[0], lines[0]
    assert "at least 1 px" in lines[0], lines[0]
    assert proc.stdout == ""
