"""Start-up (issue 17): ``import seahough`` and ``seahough --help`` load
nothing heavy, a command's module is imported only when it runs, and the
wheel that ``pip install .`` builds carries the Numba kernels compiled, so
that the first ``seahough detect`` compiles nothing (read-only installs too)."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import types
import zipfile
from pathlib import Path

import click
import pytest

import seahough
import seahough.cli as cli_module
from seahough.cli import COMMANDS, cli, load_command, main

from conftest import DATA, NOBODY, as_unprivileged, seahough_command

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "cv2", "matplotlib", "dask", "distributed", "pyarrow")


_RUN = """
import json, sys
out, code = sys.argv[1], sys.argv[2]
try:
    exec(code)
finally:
    with open(out, "w") as f:
        json.dump(sorted(sys.modules), f)
"""


def _imported(code: str, tmp_path: Path) -> tuple[set[str], subprocess.CompletedProcess]:
    """The modules a child process running ``code`` has imported when it ends."""
    out = tmp_path / "modules.json"
    proc = subprocess.run([sys.executable, "-c", _RUN, str(out), code], capture_output=True,
                          text=True, timeout=120, env=dict(os.environ, COLUMNS="100"))
    return set(json.loads(out.read_text())), proc


def _command(*args: str) -> str:
    """The code of the ``seahough`` command (its entry point) run with ``args``."""
    return f"from seahough.cli import main\ntry:\n    main({list(args)!r})\nexcept SystemExit:\n    pass"


def _top(names: set[str]) -> set[str]:
    return {n.split(".")[0] for n in names}


# --------------------------------------------------------------- lazy imports
def test_import_seahough_loads_nothing_heavy(tmp_path):
    names, proc = _imported("import seahough", tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert not _top(names) & set(HEAVY), sorted(_top(names) & set(HEAVY))
    assert "seahough" in names


def test_help_lists_every_command_without_importing_one(tmp_path):
    names, proc = _imported(_command("--help"), tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert not _top(names) & set(HEAVY), sorted(_top(names) & set(HEAVY))
    assert not {f"seahough.cli.{c}" for c in COMMANDS} & names
    listed = proc.stdout.split("Commands:", 1)[1]
    for name, (short, _) in COMMANDS.items():
        assert re.search(rf"^\s+{name}\s+{re.escape(short)}$", listed, flags=re.M), proc.stdout


def test_detect_help_loads_no_pictures_nor_dask(tmp_path):
    names, proc = _imported(_command("detect", "--help"), tmp_path)
    assert proc.returncode == 0 and "PATTERN" in proc.stdout, proc.stderr[-2000:]
    assert not _top(names) & {"matplotlib", "dask", "distributed", "pyarrow"}
    assert "seahough.cli.detect" in names and "seahough.cli.odometry" not in names


def test_public_names_resolve_on_first_access():
    from seahough.core.detector import Detector
    from seahough.motion import estimate_motion

    assert seahough.Detector is Detector and seahough.estimate_motion is estimate_motion
    missing = [n for n in seahough.__all__ if not hasattr(seahough, n)]
    assert not missing
    assert set(seahough.__all__) - {"__version__"} == set(seahough._WHERE)
    assert set(seahough.__all__) <= set(dir(seahough))
    # (the module's own plumbing is not offered as API: a user's trial found it in dir())
    assert not {"TYPE_CHECKING", "annotations", "importlib"} & set(dir(seahough))
    ns: dict = {}
    exec("from seahough import *", ns)
    assert ns["Pattern"] is seahough.Pattern and ns["__version__"] == seahough.__version__
    # subpackages too, without importing them first; anything else is an AttributeError
    assert isinstance(seahough.geometry, types.ModuleType)
    with pytest.raises(AttributeError, match="no attribute 'Detektor'"):
        seahough.Detektor  # noqa: B018


def test_modules_reached_as_attributes_as_before_the_lazy_imports(tmp_path):
    # (scripts wrote seahough.io.frames.list_frames or seahough.core.detector.Detector
    # after a bare `import seahough`, which then imported them all)
    code = ("import seahough\n"
            "for path in ('io.frames', 'io.images', 'core.detector', 'core.kernels', "
            "'motion.odometry', 'geometry', 'viz'):\n"
            "    obj = seahough\n"
            "    for part in path.split('.'):\n"
            "        obj = getattr(obj, part)\n")
    _, proc = _imported(code, tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_a_public_name_is_never_a_submodule_name():
    # importing a submodule sets it as an attribute of the package: a public
    # name of the same spelling would be replaced by the module
    assert not set(seahough._WHERE) & set(seahough._SUBMODULES)
    assert not {p.stem for p in Path(seahough.__file__).parent.iterdir()} & set(seahough._WHERE)


# --------------------------------------------------------------- the command table
@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_command_table_says_what_the_command_says(name):
    if not (Path(cli_module.__file__).parent / f"{name}.py").exists():
        pytest.skip(f"seahough/cli/{name}.py is not there yet")
    cmd = load_command(name)
    assert cmd.name == name
    assert cmd.get_short_help_str(limit=1000) == COMMANDS[name][0]


def test_help_is_the_same_once_the_commands_are_loaded(capsys, monkeypatch):
    lazy = subprocess.run([str(seahough_command()), "--help"], capture_output=True, text=True,
                          timeout=60, env=dict(os.environ, COLUMNS="100"))
    assert lazy.returncode == 0 and "Commands:" in lazy.stdout, lazy.stderr
    monkeypatch.setenv("COLUMNS", "100")
    for name in COMMANDS:
        try:
            cli.get_command(None, name)
        except click.ClickException:
            pass                                       # (a command not written yet)
    with pytest.raises(SystemExit):
        main(["--help"])
    assert capsys.readouterr().out == lazy.stdout


def _fake_importlib(exc: BaseException):
    def import_module(name, package=None):
        raise exc
    return types.SimpleNamespace(import_module=import_module)


def test_a_missing_command_module_is_one_line(monkeypatch, capsys):
    monkeypatch.setitem(COMMANDS, "nosuch", ("Not there.", None))
    with pytest.raises(SystemExit) as e:
        main(["nosuch"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert err == ("seahough: error: nosuch: this installation has no such command "
                   "(no module seahough.cli.nosuch)\n"), err


def test_a_missing_dependency_of_a_command_is_one_line(monkeypatch, capsys):
    monkeypatch.setattr(cli, "commands", {})              # nothing loaded yet
    missing = ModuleNotFoundError("No module named 'dask'", name="dask")
    monkeypatch.setattr(cli_module, "importlib", _fake_importlib(missing))
    with pytest.raises(SystemExit) as e:
        main(["survey", "detect", "rect:9,5", "x.png", "--out", "o"])
    assert e.value.code == 2
    assert capsys.readouterr().err == ("seahough: error: survey: No module named 'dask' "
                                       "(pip install 'seahough[survey]')\n")


def test_ctrl_c_while_a_command_is_imported(monkeypatch, capsys):
    """The imports happen inside main (before: at ``import seahough.cli``,
    where a Ctrl-C in the first half second gave a traceback)."""
    monkeypatch.setattr(cli, "commands", {})
    monkeypatch.setattr(cli_module, "importlib", _fake_importlib(KeyboardInterrupt()))
    with pytest.raises(SystemExit) as e:
        main(["detect", "rect:9,5", "x.png"])
    assert e.value.code == 130
    assert capsys.readouterr().err == "\nseahough: error: interrupted\n"


# --------------------------------------------------------------- shipped cache
_TINY = """\
from numba import njit


@njit(cache=True)
def plus_one(x):
    return x + 1
"""

_CALL_TINY = """
import sys
sys.path.insert(0, sys.argv[1])
import tiny
tiny.plus_one(1)
s = tiny.plus_one.stats
print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))
"""


def _run_tiny(pkg: Path, cache_dir: str | None) -> tuple[int, int]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    if cache_dir:
        env["NUMBA_CACHE_DIR"] = cache_dir
    proc = subprocess.run([sys.executable, "-c", _CALL_TINY, str(pkg)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    hits, misses = map(int, proc.stdout.split())
    return hits, misses


def test_seed_cache_copies_the_shipped_kernels_once(tmp_path):
    """What a read-only install does with the cache files of its wheel: they
    are copied into the folder Numba uses instead, and Numba loads them."""
    from numba.core.caching import UserProvidedCacheLocator

    from seahough.core.kernels._cache import seed_cache

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "tiny.py").write_text(_TINY)
    assert _run_tiny(pkg, None) == (0, 1)                # compiled, cached beside it ("shipped")
    assert list((pkg / "__pycache__").glob("tiny.plus_one-*.nbi"))
    root = tmp_path / "cache"
    where = root / UserProvidedCacheLocator.get_suitable_cache_subpath(str(pkg / "tiny.py"))
    where.mkdir(parents=True)
    assert seed_cache(str(where), str(pkg)) == 1
    assert seed_cache(str(where), str(pkg)) == 0         # once
    assert _run_tiny(pkg, str(root)) == (1, 0)           # loaded, not compiled
    # nothing shipped for a source that changed since: Numba compiles it as before
    (pkg / "tiny.py").write_text(_TINY + "\n# edited\n")
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    assert seed_cache(str(fresh), str(pkg)) == 0 and not list(fresh.iterdir())
    # the package's own __pycache__ is never seeded from itself
    assert seed_cache(str(pkg / "__pycache__"), str(pkg)) == 0


# --------------------------------------------------------------- the wheel
_DETECT_AND_ODOMETRY = """
import json, sys, tempfile
import seahough
from seahough.cli import main
from seahough._warmup import cache_stats
photo, frames = sys.argv[1], sys.argv[2:]
try:
    main(["detect", "rect:90,50", photo, "--quiet"])
except SystemExit as e:
    assert e.code in (0, 1), e.code
with tempfile.TemporaryDirectory() as out:
    seahough.run_odometry(frames, out, progress=False, mosaic=False)
stats = cache_stats()
print(json.dumps({"file": seahough.__file__, "stats": stats}))
"""


def _sources(dest: Path) -> Path:
    """The files a wheel is built from, copied (no build/ or caches of the checkout)."""
    dest.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE", "MANIFEST.in"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    shutil.copytree(ROOT / "src", dest / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "*.nb[ic]"))
    return dest


def _build_wheel(src: Path, out: Path) -> Path:
    """``pip wheel`` of ``src``: in this environment when its setuptools can
    build the project, else in pip's isolated build environment (skipped when
    that cannot be made: no package index)."""
    import setuptools

    isolate = int(setuptools.__version__.split(".")[0]) < 77
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(out), str(src)]
    if not isolate:
        cmd.insert(4, "--no-build-isolation")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                          env={k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")})
    if proc.returncode != 0 and isolate and re.search(
            r"No matching distribution|Could not find a version|NewConnectionError|"
            r"Network is unreachable", proc.stdout + proc.stderr):
        pytest.skip("cannot make pip's isolated build environment here (no package index), "
                    "and this environment's setuptools is older than 77")
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-3000:]
    assert "kernels were not compiled" not in proc.stdout + proc.stderr
    return next(out.glob("seahough-*.whl"))


def _inputs(tmp: Path) -> tuple[str, list[str]]:
    """A photo (the real seabed one when present) and four frames."""
    import cv2

    from seahough import sim

    photo = DATA / "seabed" / "dtu_starfish_murky.jpg" if DATA else None
    if photo is None or not photo.exists():
        photo = tmp / "scene.png"
        cv2.imwrite(str(photo), sim.seabed((480, 640), seed=1))
    frames, _ = sim.sequence(n_frames=4, frame_size=(288, 384), seed=5, source="procedural")
    paths = []
    for i, f in enumerate(frames):
        paths.append(str(tmp / f"frame_{i}.png"))
        cv2.imwrite(paths[-1], f)
    return str(photo), paths


def _compiled(proc: subprocess.CompletedProcess) -> tuple[str, dict]:
    import json

    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return out["file"], {k: v for k, v in out["stats"].items() if v[1]}


@pytest.mark.slow
def test_the_wheel_carries_the_compiled_kernels(tmp_path):
    """``pip install .`` builds this wheel: installed (here into a target
    folder), its first detect and odometry load every kernel from the cache,
    and so does a read-only copy run by a user who can write only in TMPDIR.
    (About 30-60 s: a wheel build, whose warm-up compiles every kernel.)"""
    wheel = _build_wheel(_sources(tmp_path / "src"), tmp_path / "dist")
    names = zipfile.ZipFile(wheel).namelist()
    cached = [n for n in names if n.startswith("seahough/core/kernels/__pycache__/")]
    for module in ("edges", "voting", "matching"):
        assert any(re.search(rf"/{module}\.\w+-\d+\.py\d+\.nbi$", n) for n in cached), cached
        assert any(re.search(rf"/{module}\.\w+-\d+\.py\d+\.\d+\.nbc$", n) for n in cached)
    assert not [n for n in names if n.endswith(".pyc")]

    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--no-compile", "--target", str(site), str(wheel)], check=True, timeout=300)
    photo, frames = _inputs(tmp_path)
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(PYTHONPATH=str(site), MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, "-c", _DETECT_AND_ODOMETRY, photo, *frames], env=env,
                          cwd=str(tmp_path), capture_output=True, text=True, timeout=300)
    where, compiled = _compiled(proc)
    assert where.startswith(str(site)) and not compiled, compiled

    # read-only, HOME read-only: the shipped files are copied to the private folder
    ro = tmp_path / "ro"
    shutil.copytree(site, ro)
    home, tmp = tmp_path / "home", tmp_path / "tmp"
    home.mkdir()
    tmp.mkdir()
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(home),
           "TMPDIR": str(tmp), "PYTHONPATH": str(ro), "MPLBACKEND": "Agg", "LANG": "C.UTF-8"}
    for f in [photo, *frames]:
        os.chmod(f, 0o644)
    dirs = [Path(d) for d, _, _ in os.walk(ro)] + [home]
    for d, _, files in os.walk(ro):
        for f in files:
            os.chmod(os.path.join(d, f), 0o444)
    for d in dirs:
        os.chmod(d, 0o555)
    try:
        prefix = as_unprivileged(env, [sys.executable, "-c", "import numpy, numba, cv2"])
        if prefix:
            os.chown(tmp, NOBODY, NOBODY)
            os.chmod(tmp_path, 0o755)
        proc = subprocess.run(prefix + [sys.executable, "-c", _DETECT_AND_ODOMETRY, photo,
                                        *frames], env=env, cwd=str(tmp), capture_output=True,
                              text=True, timeout=300)
    finally:
        for d in dirs:
            os.chmod(d, 0o755)
    where, compiled = _compiled(proc)
    assert where.startswith(str(ro)) and not compiled, (compiled, proc.stderr[-2000:])
    assert proc.stderr.count("KernelCacheWarning") == 1, proc.stderr
    assert list(tmp.glob("seahough-numba-*/*/*.nbi"))


def test_editable_and_source_builds_skip_the_warm_up(monkeypatch, tmp_path):
    """``pip install -e .`` compiles on first use, as before: setup.py's step
    runs only for a wheel, and a failed warm-up is one warning, not a failed
    build."""
    text = (ROOT / "setup.py").read_text().replace("\nsetup(", "\n_not_run = dict(")
    module = types.ModuleType("seahough_setup")       # setup.py without its setup() call
    exec(compile(text, str(ROOT / "setup.py"), "exec"), module.__dict__)
    Cmd = module.BuildPyWithKernels

    calls = []
    monkeypatch.setattr(Cmd, "warm_up", lambda self: calls.append(self))
    from setuptools import Distribution
    from setuptools.command.build_py import build_py
    monkeypatch.setattr(build_py, "run", lambda self: None)

    cmd = Cmd(Distribution())
    cmd.editable_mode = True
    cmd.run()
    assert calls == []
    cmd.editable_mode = False
    cmd.run()
    assert calls == [cmd]

    # a warm-up that fails: a warning, the build goes on
    monkeypatch.undo()
    monkeypatch.setattr(module.subprocess, "run", lambda *a, **k: subprocess.CompletedProcess(
        a, 1, "", "Traceback ...\nImportError: numba is broken\n"))
    warned = []
    cmd = Cmd(Distribution())
    cmd.build_lib = str(tmp_path)
    monkeypatch.setattr(cmd, "warn", warned.append)
    cmd.warm_up()
    assert len(warned) == 1 and "ImportError: numba is broken" in warned[0], warned

