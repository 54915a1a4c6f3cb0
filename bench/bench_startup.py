"""Start-up after ``pip install .`` (issue 17): a benchmark, not a test.

Makes a fresh venv in a temporary folder, installs this checkout into it as a
user does (``pip install <repo>``: not editable, so the wheel is built, and
its warm-up compiles the Numba kernels into it), then times, wall-clock, each
in a new process:

- ``seahough --help`` and ``python -c "import seahough"``;
- the first ``seahough detect rect:90,50 IMAGE`` after the install, and a
  second one;
- the same first call with the kernels' cache emptied: what an install
  without the warm-up costs (every kernel compiled on first use).

IMAGE is a real seabed photo of ``../shared/data`` when present (else a
simulated one). The cheap calls are repeated and their median kept; the
first calls are first calls, once each. Numba and OpenCV use their default
threads, as a user's command does.

    python bench/bench_startup.py                  # prints the Markdown table
    python bench/bench_startup.py --write          # and puts it in docs/speed.md ("Start-up")
    python bench/bench_startup.py --keep DIR       # keep the venv in DIR (e.g. to look at it)
"""

from __future__ import annotations

import argparse
import glob
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SECTION = "## Start-up"


def cpu() -> str:
    """CPU model and core count."""
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            model = next((line.split(":", 1)[1].strip() for line in f
                          if line.startswith("model name")), model)
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores"


def sources(dest: Path) -> Path:
    """The files a wheel is built from (without the checkout's build/ and caches)."""
    dest.mkdir(parents=True)
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE", "MANIFEST.in"):
        if (ROOT / name).exists():
            shutil.copy2(ROOT / name, dest / name)
    shutil.copytree(ROOT / "src", dest / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "*.nb[ic]"))
    return dest


def image(tmp: Path) -> tuple[Path, str]:
    """The photo to search, and how to name it in the report."""
    sys.path.insert(0, str(ROOT / "src"))
    from seahough._data import shared_data_dir

    data = shared_data_dir()
    if data is not None and (data / "seabed" / "dtu_starfish_murky.jpg").exists():
        return data / "seabed" / "dtu_starfish_murky.jpg", \
            "`../shared/data/seabed/dtu_starfish_murky.jpg` (640x480, a real seabed photo)"
    import cv2

    from seahough import sim

    path = tmp / "seabed.png"
    cv2.imwrite(str(path), sim.seabed((480, 640), seed=1))
    return path, "a simulated 640x480 seabed (../shared/data is absent)"


def timed(args: list[str], env: dict, cwd: Path) -> float:
    """Wall-clock seconds of one run of ``args`` (its exit status 0, or 1 for
    a detect that found nothing)."""
    t0 = time.perf_counter()
    proc = subprocess.run(args, env=env, cwd=cwd, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        sys.exit(f"{' '.join(args)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return dt


def measure(venv: Path, photo: Path, repeat: int) -> dict:
    py = venv / "bin" / "python"
    cmd = venv / "bin" / "seahough"
    work = venv.parent
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("NUMBA_", "OMP_", "OPENBLAS_", "MKL_", "PYTHONPATH"))}
    env.update(MPLBACKEND="Agg", PIP_DISABLE_PIP_VERSION_CHECK="1")
    out = {"load": os.getloadavg()[0] if hasattr(os, "getloadavg") else None}

    src = sources(work / "src")
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    t0 = time.perf_counter()
    proc = subprocess.run([str(py), "-m", "pip", "install", "--quiet", str(src)], env=env,
                          cwd=work, capture_output=True, text=True)
    out["install"] = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"pip install {src} failed:\n{proc.stderr[-3000:]}")
    out["versions"] = subprocess.run(
        [str(py), "-c", "import numba, numpy, cv2, platform; print(f'Python "
         "{platform.python_version()}, numpy {numpy.__version__}, numba {numba.__version__}, "
         "OpenCV {cv2.__version__}')"], capture_output=True, text=True, env=env).stdout.strip()
    site = subprocess.run([str(py), "-c", "import seahough, os; "
                           "print(os.path.dirname(seahough.__file__))"],
                          capture_output=True, text=True, env=env, check=True).stdout.strip()
    shipped = glob.glob(os.path.join(site, "core", "kernels", "__pycache__", "*.nb[ic]"))
    out["shipped"] = len([p for p in shipped if p.endswith(".nbi")])

    detect = [str(cmd), "detect", "rect:90,50", str(photo)]
    out["first"] = timed(detect, env, work)
    out["second"] = statistics.median(timed(detect, env, work) for _ in range(repeat))
    out["help"] = statistics.median(timed([str(cmd), "--help"], env, work)
                                    for _ in range(repeat))
    out["import"] = statistics.median(timed([str(py), "-c", "import seahough"], env, work)
                                      for _ in range(repeat))
    for p in glob.glob(os.path.join(site, "core", "kernels", "__pycache__", "*.nb[ic]")):
        os.remove(p)
    out["cold"] = timed(detect, env, work)
    return out


def report(r: dict, image_name: str, repeat: int) -> str:
    load = "" if r["load"] is None else f"; load average {r['load']:.1f} when it started"
    lines = [
        SECTION, "",
        f"Command: `{' '.join(['python', 'bench/bench_startup.py'] + sys.argv[1:])}`  ",
        f"Machine: {cpu()}, {r['versions']}{load} (wall-clock times: larger when the "
        "machine is shared)  ",
        f"Date: {time.strftime('%Y-%m-%d')}; image: {image_name}", "",
        f"A fresh venv, `pip install <checkout>` (not editable; {r['install']:.0f} s, the wheel "
        f"built with its kernels compiled: {r['shipped']} kernels cached), then each command in "
        f"a new process; Numba and OpenCV at their default threads. Medians of {repeat} runs, "
        "except the first calls (once each).", "",
        "| command | wall (s) |", "|---|---|",
        f"| `seahough --help` | {r['help']:.2f} |",
        f"| `python -c \"import seahough\"` | {r['import']:.2f} |",
        f"| first `seahough detect rect:90,50 IMAGE` after the install | {r['first']:.2f} |",
        f"| second call | {r['second']:.2f} |",
        f"| first call with the kernels' cache emptied (an install without the warm-up) "
        f"| {r['cold']:.2f} |",
        "",
        f"Target (issue 17): the first call after the install <= 3 s "
        f"({'met' if r['first'] <= 3 else 'not met'}), a second one <= 1 s "
        f"({'met' if r['second'] <= 1 else 'not met'}). The first call loads the kernels "
        "compiled when the wheel was built (`setup.py` runs `seahough/_warmup.py`); without "
        "them it compiles every kernel it calls (last row).",
        "",
    ]
    return "\n".join(lines)


def write(section: str, path: Path) -> None:
    """Put ``section`` in ``path`` in place of its "Start-up" section (or at
    the end), leaving the other sections as they are."""
    text = path.read_text() if path.exists() else ""
    if SECTION + "\n" in text:
        head, _, rest = text.partition(SECTION + "\n")
        nxt = rest.find("\n## ")
        tail = rest[nxt + 1:] if nxt >= 0 else ""
        text = head + section + ("\n" + tail if tail else "")
    else:
        text = text.rstrip("\n") + ("\n\n" if text else "") + section
    path.write_text(text)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs of the cheap calls (median)")
    ap.add_argument("--keep", metavar="DIR", help="make the venv there and keep it")
    ap.add_argument("--write", action="store_true", help="update docs/speed.md")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="seahough-startup-") as tmp:
        base = Path(args.keep) if args.keep else Path(tmp)
        if args.keep:
            if base.exists():
                sys.exit(f"--keep {base}: already exists")
            base.mkdir(parents=True)
        photo, name = image(Path(tmp))
        result = measure(base / "venv", photo, max(1, args.repeat))
    section = report(result, name, max(1, args.repeat))
    print(section)
    if args.write:
        write(section, ROOT / "docs" / "speed.md")


if __name__ == "__main__":
    main()
