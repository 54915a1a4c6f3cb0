"""Shared helpers of the benchmark scripts: single-thread setup, machine line,
the seabed photos' tune/test split, writing a page."""

from __future__ import annotations

import ctypes
import os
import platform
import sys
from pathlib import Path

for _v in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import cv2  # noqa: E402

cv2.setNumThreads(1)


def machine() -> str:
    """One line describing this machine and the software."""
    import numba
    import numpy
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return (f"{cpu}, {os.cpu_count()} cores (benchmarks run single-threaded), "
            f"Python {platform.python_version()}, numpy {numpy.__version__}, "
            f"numba {numba.__version__}, OpenCV {cv2.__version__}; "
            f"speed reference: {reference_ms():.2f} ms (bench/_common.py reference_ms: compare "
            "pages' times by it, machines of one name differ)")


def reference_ms(repeat: int = 50) -> float:
    """Median ms of a fixed piece of work on this machine, now: OpenCV's
    Gaussian blur, Scharr derivatives and their magnitude on a 640x480 float
    image (OpenCV and numpy only, so that it does not move with seahough).
    Shared machines of one name have run 1-4 times slower from day to day:
    in this unit, a page's times compare with another's."""
    import time

    import numpy
    img = numpy.random.default_rng(0).uniform(0, 255, (480, 640)).astype(numpy.float32)
    times = []
    for _ in range(repeat + 1):
        t = time.perf_counter()
        g = cv2.GaussianBlur(img, (0, 0), 2.0)
        gx = cv2.Scharr(g, cv2.CV_32F, 1, 0)
        gy = cv2.Scharr(g, cv2.CV_32F, 0, 1)
        numpy.sqrt(gx * gx + gy * gy)
        times.append(1000.0 * (time.perf_counter() - t))
    return float(numpy.median(times[1:]))


def _shown(arg: str) -> str:
    """A command-line argument as a page shows it: an absolute path (or
    ``--opt=/path``) outside the working folder by its file name alone, so
    that no machine's paths land in the repository."""
    opt, eq, value = arg.partition("=") if arg.startswith("--") else ("", "", arg)
    if not os.path.isabs(value):
        return arg
    rel = os.path.relpath(value)
    value = rel if not rel.startswith("..") else os.path.basename(value.rstrip("/\\"))
    return f"{opt}{eq}{value}"


def command() -> str:
    """The command that made a page, as run (paths as :func:`_shown` shows them).

    >>> away = os.path.join(os.path.abspath(os.sep), "elsewhere")   # (a folder outside this one)
    >>> sys.argv = ["bench/x.py", "--cache", os.path.join(away, "rs.cache"),
    ...             "--out=" + os.path.join(away, "r.md"), "--n", "4"]
    >>> command()
    'python bench/x.py --cache rs.cache --out=r.md --n 4'
    >>> sys.argv = [os.path.join(os.path.dirname(os.path.abspath(__file__)), "x.py"), "--write"]
    >>> command()                        # (a bench script run from another folder: as from here)
    'python bench/x.py --write'
    """
    script = os.path.abspath(sys.argv[0])
    here = os.path.dirname(os.path.abspath(__file__))    # (the bench folder)
    shown = (os.path.join("bench", os.path.relpath(script, here)) if
             os.path.dirname(script) == here else os.path.relpath(sys.argv[0]))
    return "python " + " ".join([shown] + [_shown(a) for a in sys.argv[1:]])


def steady_allocator() -> str:
    """Keep freed large arrays for reuse (glibc's ``mallopt``), and say so.

    With glibc's defaults an array above its mmap threshold is mapped afresh
    and faulted in page by page each time it is made, and the threshold moves
    with what the process freed before: a method's time then depends on what
    ran before it. On the 384x288 Sparus frames SIFT+RANSAC took 49-51 ms a
    pair in a fresh process, 22-24 ms after the larger sequences and 24-25 ms
    with the thresholds fixed (seahough 23-24, 22 and 20-22 ms; 2026-12-01,
    this machine). Fixed, every method is timed in the steady state of a long
    run. Returns a line for the report.
    """
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):
        return "allocator at its defaults (not glibc: times may depend on what ran before)"
    M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
    # (man mallopt gives 32 MiB as the mmap threshold's upper limit on 64-bit;
    # glibc 2.36 takes 1 GiB, which keeps even SIFT's 2x-upsampled 1080p
    # pyramid levels (33 MB) on the heap)
    mmap = next((v for v in (1 << 30, 32 << 20) if mallopt(M_MMAP_THRESHOLD, v) == 1), None)
    trim = mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1
    if mmap is None and not trim:
        return "allocator at its defaults (mallopt refused the thresholds)"
    return (f"glibc allocator thresholds fixed (mallopt M_MMAP_THRESHOLD "
            f"{'unchanged' if mmap is None else f'{mmap >> 20} MiB'}, M_TRIM_THRESHOLD "
            f"{'unchanged' if not trim else '1024 MiB'}: freed arrays are reused, as in the "
            "steady state of a long run, whatever ran before)")


def seabed_split(base):
    """(tune, test) real seabed photos of the shared data folder ``base``
    (bench_nfa.py, bench_colour.py): each sequence cut in two, so that both
    parts hold every kind of scene (a first split by sequence tuned on the
    quiet Sparus and Skerki frames alone, and the wreck and sand of the test
    part then showed 15 times the promised false alarms: docs/nfa.md)."""
    seq = Path(base) / "sequences"
    sparus = sorted((seq / "sparus_auv_seabed").glob("*.png"))
    aqualoc = sorted((seq / "aqualoc_amphorae_wreck").glob("*.png"))
    skerki = sorted((seq / "skerki_mud_pair").glob("*.png"))
    dtu = sorted((seq / "dtu_seabed_pair").glob("*.png"))
    tune = sparus[0::2] + aqualoc[: len(aqualoc) // 2] + skerki[:1] + dtu[:1]
    test = (sparus[1::2] + aqualoc[len(aqualoc) // 2:] + skerki[1:] + dtu[1:]
            + sorted((Path(base) / "seabed").glob("*.jpg")))
    return tune, test


def write_page(text: str, out) -> None:
    """Write a benchmark's markdown page to ``out`` (folders made), and say so on stderr."""
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    Path(out).write_text(text + "\n")
    print(f"written to {out}", file=sys.stderr, flush=True)


def publish(text: str, args, doc) -> None:
    """Print a benchmark's page, and write it to ``args.out``, or to ``doc``
    with ``args.write``."""
    print(text)
    out = args.out or (doc if args.write else None)
    if out:
        write_page(text, out)


def page_head(title: str, seconds: float) -> list[str]:
    """A page's first lines: title, command, date, machine, threads and run time."""
    import datetime
    return [f"# {title}", "", f"Command: `{command()}`  ",
            f"Date: {datetime.date.today().isoformat()}  ", f"Machine: {machine()}  ",
            f"Single-threaded; {steady_allocator()} Whole run: {seconds:.0f} s.", ""]


def page_parser(doc: str, page: str, quick: str):
    """The arguments every page-writing benchmark takes: ``--write`` (to
    ``docs/<page>``), ``--quick`` (``quick`` says what it runs), ``--out``."""
    import argparse
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--write", action="store_true", help=f"write docs/{page}")
    ap.add_argument("--quick", action="store_true", help=quick)
    ap.add_argument("--out", type=Path, help="write the page here")
    return ap

