"""All cores on one machine: ``seahough detect`` and ``seahough odometry`` on
real data, one worker against several (``--workers N``).

Each command is run as a user runs it (the installed ``seahough`` in a
subprocess, start-up included), after one warm-up run (the compiled kernels
cached). Wall time is the fastest of the repeats; CPU time is the child's
user + system time of that run (all its threads). With one worker everything
runs in one thread; with N, ``detect`` searches N images at once in threads
and ``odometry`` measures the pairs in turn while the coming frames are read
and given their features in the other threads (identical results: see
``tests/test_workers.py``). OpenCV's own threads are limited to one
(``OMP_NUM_THREADS=1``, as in the other benchmarks) in every run.

Data (from ../shared/data): the RoboSub photos (``objects/robosub_transdec``,
mostly 640x480) searched for ``rect:90,50``, and the real sequences of
``sequences/`` for the dead reckoning (with its mosaic and plot); they are
short (12-22 frames), so a longer one is rendered by the simulator too: 120
frames of 640x480 over the procedural seabed (``seahough.sim.sequence``,
seed 3, 24 px a frame), written as PNG to a temporary folder.

    python bench/bench_cores.py              # full run (~3-4 min on 2 cores)
    python bench/bench_cores.py --quick      # smoke test (~40 s)
    python bench/bench_cores.py --workers 4  # compare 1 worker with 4
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (sets single-thread first)

from seahough._data import shared_data_dir  # noqa: E402

SEQUENCES = ("aqualoc_amphorae_wreck", "sparus_auv_seabed", "subvo_pool_chain")


def _seahough() -> str:
    exe = Path(sys.executable).with_name("seahough")
    return str(exe) if exe.exists() else (shutil.which("seahough") or "seahough")


def timed(args: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds (user + system, all threads) of one run of ``args``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 1):
        raise SystemExit(f"{' '.join(args)} failed ({proc.returncode}): {proc.stderr.strip()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def best_of(args: list[str], repeats: int) -> tuple[float, float]:
    """The fastest of ``repeats`` runs (wall, and that run's CPU time)."""
    return min(timed(args) for _ in range(repeats))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true",
                    help="40 photos, one sequence, one run each")
    ap.add_argument("--workers", type=int, default=2, help="workers to compare with one")
    ap.add_argument("--photos", type=int, default=None, help="photos searched (default 200)")
    opts = ap.parse_args()
    data = shared_data_dir()
    if data is None:
        raise SystemExit("../shared/data is absent: this benchmark needs its real photos")
    n_photos = opts.photos or (40 if opts.quick else 200)
    repeats = 1 if opts.quick else 3
    photos = sorted((data / "objects" / "robosub_transdec" / "images").glob("*.jpg"))[:n_photos]
    sequences = SEQUENCES[:1] if opts.quick else SEQUENCES
    exe = _seahough()

    print("# All cores on one machine: --workers 1 against --workers", opts.workers)
    print()
    print(f"Command: `{command()}`  ")
    print(f"Machine: {machine().replace(' (benchmarks run single-threaded)', '')}; "
          f"{len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else '?'} "
          "cores usable by this process")
    print()
    print(f"Fastest of {repeats} run(s) after a warm-up; CPU time = user + system of that run, "
          "all threads. Start-up of the command included.")
    print()
    print("| command | data | workers | wall (s) | CPU (s) | speed-up (wall) |")
    print("|---|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        jobs = [("seahough detect rect:90,50 PHOTOS --json",
                 f"{len(photos)} RoboSub photos",
                 lambda w: [exe, "detect", "rect:90,50", *map(str, photos), "--json", "-q",
                            "--workers", str(w)])]
        for name in sequences:
            folder = data / "sequences" / name
            n = sum(1 for p in folder.iterdir() if p.suffix.lower() in (".png", ".jpg"))
            jobs.append((f"seahough odometry {name} --out OUT", f"{n} frames",
                         lambda w, folder=folder: [exe, "odometry", str(folder), "--out",
                                                   str(Path(tmp) / f"o{w}"), "-q",
                                                   "--workers", str(w)]))
        if not opts.quick:
            import cv2

            from seahough import sim

            frames, _ = sim.sequence(n_frames=120, seed=3, source="procedural",
                                     frame_size=(480, 640), step=24.0)
            seq = Path(tmp) / "simulated"
            seq.mkdir()
            for i, f in enumerate(frames):
                cv2.imwrite(str(seq / f"f{i:04d}.png"), f)
            jobs.append(("seahough odometry SIMULATED --out OUT",
                         "120 simulated 640x480 frames",
                         lambda w: [exe, "odometry", str(seq), "--out", str(Path(tmp) / f"s{w}"),
                                    "-q", "--workers", str(w)]))
        for label, what, make in jobs:
            timed(make(1))                                   # warm-up
            base = None
            for w in (1, opts.workers):
                wall, cpu = best_of(make(w), repeats)
                base = base or wall
                print(f"| `{label}` | {what} | {w} | {wall:.2f} | {cpu:.2f} | "
                      f"{base / wall:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
