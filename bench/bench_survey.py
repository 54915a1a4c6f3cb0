"""Survey throughput, overhead and memory (``seahough.survey.detect`` on Dask).

Real photos from ../shared/data (the RoboSub pool photos, mostly 640x480; the
simulator's renders left out) are symlinked under distinct names in a
temporary folder outside the repository, cycled to the counts asked for, and
surveyed for ``rect:90,50`` (scale 0.5-2, any rotation: the defaults of
``seahough detect``). Measured:

1. a bare loop of ``Detector.detect(path)`` in this process (reading
   included), the reference cost per image;
2. the survey with 1 and with 2 workers on its local cluster of processes
   (``open_client``), started and warmed up (every worker has searched one
   photo) before the clock starts, its start-up reported apart: throughput,
   speed-up, and the overhead per image over (1);
3. the resident memory (RSS) of each worker and of the client, sampled over
   a long survey: flat means nothing accumulates per image;
4. the cost of one 12 MP photo (a real photo enlarged to 4000x3000, JPEG),
   bare, for the projection in docs/scale.md.

Every process runs one thread (NUMBA/OpenCV threads 1; the workers inherit
it). The photos are read from the page cache after the first pass: disk or
network file-system speed is not measured.

    python bench/bench_survey.py                  # 1,000 and 10,000 photos (~6 min)
    python bench/bench_survey.py --quick          # 120 and 600 photos (~1 min)
    python bench/bench_survey.py --write          # also fill the figures in docs/scale.md
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (sets single-thread first)

import cv2  # noqa: E402
import psutil  # noqa: E402  (a dependency of distributed)

import seahough  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.survey._cluster import open_client  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "scale.md"
BEGIN, END = "<!-- bench_survey:begin -->", "<!-- bench_survey:end -->"
MiB = 1024.0 * 1024.0


def real_photos() -> list[Path]:
    data = shared_data_dir()
    folder = None if data is None else data / "objects" / "robosub_transdec" / "images"
    if folder is None or not folder.is_dir():
        sys.exit("bench_survey: the real photos (../shared/data/objects/robosub_transdec) "
                 "are not here")
    # names 0-99 are the simulator's renders
    return sorted((p for p in folder.glob("*.jpg") if p.stem.isdigit() and int(p.stem) >= 100),
                  key=lambda p: int(p.stem))


def link_photos(src: list[Path], n: int, folder: Path) -> list[str]:
    """``n`` distinct names in ``folder``, symlinks to ``src`` cycled."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for i in range(n):
        q = folder / f"photo_{i:06d}.jpg"
        if not q.exists():
            os.symlink(src[i % len(src)], q)
        out.append(str(q))
    return out


def bare_loop(detector, paths) -> float:
    """Seconds of ``detector.detect`` over ``paths`` in this process."""
    t = time.perf_counter()
    for p in paths:
        detector.detect(p)
    return time.perf_counter() - t


def warm(detector, path):
    """Run on every worker before the clock starts: Numba's kernels loaded."""
    detector.detect(path)


def worker_rss(client) -> dict:
    return client.run(lambda: psutil.Process().memory_info().rss)


def survey_run(detector, paths, out: Path, address: str, batch_size, on_batch=None):
    from seahough import survey

    t = time.perf_counter()
    r = survey.detect(detector, paths, out, scheduler=address, batch_size=batch_size,
                      progress=False, on_batch=on_batch)
    return r, time.perf_counter() - t


def worker_ms(result) -> list[float]:
    import pyarrow.parquet as pq

    return pq.read_table(result.images, columns=["ms"]).column("ms").to_pylist()


def twelve_mp(src: Path, folder: Path, detector, repeat: int) -> float:
    """Seconds of one bare detection of a 4000x3000 JPEG (median of ``repeat``)."""
    img = cv2.resize(cv2.imread(str(src)), (4000, 3000), interpolation=cv2.INTER_CUBIC)
    path = folder / "twelve_mp.jpg"
    cv2.imwrite(str(path), img, [cv2.IMWRITE_JPEG_QUALITY, 92])
    detector.detect(str(path))
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        detector.detect(str(path))
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="120 and 600 photos")
    ap.add_argument("--photos", type=int, default=None, help="photos of the throughput runs "
                    "(default 1000)")
    ap.add_argument("--memory-photos", type=int, default=None,
                    help="photos of the memory run (default 10000)")
    ap.add_argument("--workers", type=int, default=2, help="workers of the scaling and memory "
                    "runs (default 2)")
    ap.add_argument("--batch-size", type=int, default=None, help="images per task (default: "
                    "the survey's)")
    ap.add_argument("--write", action="store_true", help="write the figures into docs/scale.md")
    args = ap.parse_args()
    n1 = args.photos or (120 if args.quick else 1000)
    n2 = args.memory_photos or (600 if args.quick else 10000)
    src = real_photos()
    pattern = seahough.Pattern.rectangle(90, 50)
    detector = seahough.Detector(pattern)
    lines = []
    say = lines.append
    with tempfile.TemporaryDirectory(prefix="seahough-bench-survey-") as tmp:
        tmp = Path(tmp)
        paths = link_photos(src, max(n1, n2), tmp / "photos")
        # warm-up: Numba's kernels loaded, the photos in the page cache
        bare_loop(detector, paths[:min(len(src), max(n1, n2))])
        bare_before = bare_loop(detector, paths[:n1])
        runs = {}
        for w in sorted({1, args.workers}):
            t = time.perf_counter()
            with open_client(w) as client:        # the survey's own local cluster
                start_s = time.perf_counter() - t
                client.run(warm, detector, paths[0])
                r, wall = survey_run(detector, paths[:n1], tmp / f"run{w}",
                                     client.scheduler.address, args.batch_size)
            assert r.total == n1 and r.processed == n1
            runs[w] = dict(start=start_s, wall=wall, ms=worker_ms(r), found=r.found)
        # the bare loop again after the survey runs: the two bracket the machine's drift
        # (on this shared 2-core machine one loop's speed varies by 10-20 % across minutes)
        bare_after = bare_loop(detector, paths[:n1])
        bare = 0.5 * (bare_before + bare_after)
        bare_ms = 1000.0 * bare / n1
        # the overhead, measured as drift allows: rounds of a bare loop then a survey of
        # the same photos on one worker, back to back; the median of the rounds' ratios
        ratios = []
        with open_client(1) as client:
            client.run(warm, detector, paths[0])
            for k in range(1 if args.quick else 3):
                b = bare_loop(detector, paths[:n1])
                _, s_wall = survey_run(detector, paths[:n1], tmp / f"over{k}",
                                       client.scheduler.address, args.batch_size)
                ratios.append(s_wall / b)
        # memory over a long survey
        samples = []
        with open_client(args.workers) as client:
            client.run(warm, detector, paths[0])
            marks = sorted({max(1, round(n2 * k / 10)) for k in range(1, 11)})

            def sample(done, total):
                while marks and done >= marks[0]:
                    marks.pop(0)
                    rss = worker_rss(client)
                    samples.append((done, [rss[k] / MiB for k in sorted(rss)],
                                    psutil.Process().memory_info().rss / MiB))

            samples.append((0, [v / MiB for _, v in sorted(worker_rss(client).items())],
                            psutil.Process().memory_info().rss / MiB))
            rm, wall_m = survey_run(detector, paths[:n2], tmp / "memory",
                                    client.scheduler.address, args.batch_size, sample)
        t12 = twelve_mp(src[0], tmp, detector, 2 if args.quick else 5)

    one, many = runs[1], runs[args.workers]
    w = args.workers
    speedup = one["wall"] / many["wall"]
    over = statistics.median(ratios) - 1.0
    worker_med = statistics.median(one["ms"])
    say(f"Machine: {machine()}  ")
    say(f"Command: `{command()}`  ")
    say(f"Date: {time.strftime('%Y-%m-%d', time.gmtime())}; real photos (RoboSub pool, "
        f"mostly 640x480 JPEG) symlinked under distinct names and cycled; pattern rect:90,50, "
        "scale 0.5-2, any rotation; one thread per process.\n")
    say("| measurement | value |")
    say("|---|---:|")
    say(f"| bare `Detector.detect` loop, {n1} photos, one process (mean of a loop before and "
        f"one after the survey runs: {1000 * bare_before / n1:.1f}, {1000 * bare_after / n1:.1f}) "
        f"| {bare_ms:.1f} ms/image |")
    say(f"| survey, 1 worker, {n1} photos | {1000 * one['wall'] / n1:.1f} ms/image "
        f"({n1 / one['wall']:.1f} images/s) |")
    say(f"| survey, {w} workers, {n1} photos | {1000 * many['wall'] / n1:.1f} ms/image "
        f"({n1 / many['wall']:.1f} images/s) |")
    say(f"| speed-up, {w} workers over 1 (target >= 1.7 for 2) | x{speedup:.2f} |")
    say(f"| overhead of the survey (1 worker) over the bare loop (target <= 10 %), median of "
        f"{len(ratios)} back-to-back rounds (bare loop, then the survey; rounds: "
        f"{', '.join(f'{100 * (r - 1):+.0f} %' for r in ratios)}) | {100 * over:+.1f} % |")
    say(f"| per-image cost on the worker (read + search, median / mean) | {worker_med:.1f} / "
        f"{statistics.fmean(one['ms']):.1f} ms |")
    say(f"| local cluster start-up (not in the figures above), 1 / {w} workers | "
        f"{one['start']:.1f} / {many['start']:.1f} s |")
    say(f"| one 12 MP photo (4000x3000 JPEG), bare detect, decode included | "
        f"{1000 * t12:.0f} ms |")
    say("")
    say(f"Memory (RSS, MiB) over a survey of {n2} photos with {w} workers "
        f"({n2 / wall_m:.1f} images/s):\n")
    say("| images done | " + " | ".join(f"worker {k + 1}" for k in range(w)) + " | client |")
    say("|---:|" + "---:|" * (w + 1))
    for done, ws, c in samples:
        cells = [f"{v:.0f}" for v in ws] + ["-"] * (w - len(ws))
        say(f"| {done} | " + " | ".join(cells) + f" | {c:.0f} |")
    first = samples[1] if len(samples) > 2 else samples[0]
    last = samples[-1]
    growth = [b - a for a, b in zip(first[1], last[1])]
    say("")
    say(f"Worker RSS from {first[0]} to {last[0]} images: "
        + ", ".join(f"{g:+.1f} MiB" for g in growth) + ".")
    # the projection
    cores, n_photos = 128, 100_000
    eff = speedup / w
    secs = n_photos * t12 / (cores * eff)
    span = f"{secs / 3600.0:.1f} h" if secs >= 7200 else f"{secs / 60.0:.0f} min"
    say("")
    say(f"Projection: {n_photos:,} photos of 12 MP on {cores} cores = {n_photos:,} x "
        f"{t12:.2f} s / ({cores} x {eff:.2f} parallel efficiency, measured here from 1 to {w} "
        f"workers) = **{span}** of wall time, if the file system delivers "
        f"{cores * eff / t12:.0f} photos/s (about {cores * eff / t12 * 4:.0f} MB/s of 4 MB "
        "JPEGs).")
    text = "\n".join(lines)
    print(text)
    if args.write:
        doc = DOC.read_text()
        if BEGIN not in doc or END not in doc:
            sys.exit(f"bench_survey: {DOC} has no {BEGIN} ... {END} block to fill")
        new = re.sub(re.escape(BEGIN) + ".*?" + re.escape(END),
                     lambda m: f"{BEGIN}\n{text}\n{END}", doc, flags=re.S)
        DOC.write_text(new)
        print(f"\n(wrote the figures into {DOC.relative_to(ROOT)})")


if __name__ == "__main__":
    main()
