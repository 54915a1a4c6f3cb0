"""Shared fixtures: where the real data is, and small synthetic helpers."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from seahough._data import shared_data_dir

DATA = shared_data_dir()


def data_path(*parts: str) -> Path:
    """A file of ../shared/data, or skip the test when the folder is absent."""
    if DATA is None:
        pytest.skip("real data (../shared/data) is not present beside this checkout")
    p = DATA.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"{p} is not present")
    return p


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def corner_error(matrix_found, matrix_true, shape, symmetric: bool = False) -> float:
    """Largest distance between the pattern image's corners mapped by both.

    ``symmetric``: the pattern looks the same turned by 180 degrees (a plain
    rectangle), so the corners are compared as a set."""
    from seahough.geometry import apply_matrix
    h, w = shape[:2]
    c = np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], float)
    f, t = apply_matrix(matrix_found, c), apply_matrix(matrix_true, c)
    if symmetric:
        d = np.hypot(f[:, None, 0] - t[None, :, 0], f[:, None, 1] - t[None, :, 1])
        return float(d.min(axis=0).max())
    return float(np.max(np.hypot(*(f - t).T)))


#: The uid and gid of user ``nobody`` (Debian, and most Linux systems).
NOBODY = 65534


def as_unprivileged(env: dict | None = None, probe: list | None = None) -> list:
    """The command prefix that runs a child process as user ``nobody``, who
    can write only where anyone may (a test's permission bits then stop it,
    as they stop a service user; they do not stop root). It keeps only the
    capability to read files (CAP_DAC_READ_SEARCH), so the interpreter and
    the venv are readable wherever they live (e.g. under /root). ``[]`` when
    the tests already run as a normal user; the test is skipped, with the
    reason, when this environment cannot switch user."""
    import shutil
    import subprocess
    if os.name != "posix":
        pytest.skip("user switching is POSIX only")
    if os.geteuid() != 0:
        return []            # a normal user is stopped by the permission bits already
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("running as root without setpriv: cannot drop to user nobody")
    prefix = [setpriv, f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups",
              "--inh-caps=+dac_read_search", "--ambient-caps=+dac_read_search"]
    check = subprocess.run(prefix + (probe or [sys.executable, "-c", "import numpy, numba, cv2"]),
                           env=env, capture_output=True, text=True, timeout=120)
    if check.returncode != 0:
        pytest.skip("this environment cannot run the interpreter as user nobody "
                    f"({check.stderr.strip().splitlines()[-1:] or check.returncode})")
    return prefix


def seahough_command() -> Path:
    """The installed ``seahough`` console script beside ``sys.executable``.

    The tests run what users run (the entry point of the installed package),
    never ``python -m seahough`` from the source tree: a missing command is a
    failure, not a reason to fall back."""
    exe = Path(sys.executable).parent / ("seahough.exe" if os.name == "nt" else "seahough")
    if not exe.is_file():
        pytest.fail(f"the seahough command is not installed beside {sys.executable} (no {exe}): "
                    "install the package into this environment (pip install -e .)",
                    pytrace=False)
    return exe


def write_frames(frames, folder: Path, prefix: str = "f_") -> list:
    """Frames written as ``<prefix>000.png``, ``<prefix>001.png``... into
    ``folder`` (made if needed); their paths as strings, in order."""
    import cv2
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, f in enumerate(frames):
        p = folder / f"{prefix}{i:03d}.png"
        cv2.imwrite(str(p), f)
        paths.append(str(p))
    return paths


def run_bench_code(code: str, timeout: float = 300) -> str:
    """Run ``code`` in a fresh interpreter with bench/ and src/ on the path
    (bench code sets single-thread limits at import: not in the test
    process); its stdout (a non-zero exit fails the test with its stderr)."""
    import subprocess
    root = Path(__file__).resolve().parents[1]
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(root / "src"), str(root / "bench"),
                                         env.get("PYTHONPATH", "")])
    proc = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True,
                          text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return proc.stdout


def moving_rectangle_video(path, n: int, size=(320, 240), start=(100, 80), step: int = 10,
                           fourcc: str = "mp4v"):
    """A video of ``n`` frames: a light 60x40 rectangle on grey, its top left at
    ``start`` and moving right by ``step`` px a frame; returns ``path``."""
    w, h = size
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), 5, (w, h))
    for k in range(n):
        f = np.full((h, w, 3), 60, np.uint8)
        x, y = start[0] + step * k, start[1]
        cv2.rectangle(f, (x, y), (x + 60, y + 40), (200, 200, 200), -1)
        writer.write(f)
    writer.release()
    return path
