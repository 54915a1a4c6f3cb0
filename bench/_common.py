"""Shared helpers of the benchmark scripts: single-thread setup, machine line."""

from __future__ import annotations

import ctypes
import os
import platform
import sys

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
            f"numba {numba.__version__}, OpenCV {cv2.__version__}")


def command() -> str:
    return "python " + " ".join([os.path.relpath(sys.argv[0])] + sys.argv[1:])


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
        libc = ctypes.CDLL("libc.so.6")
        M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
        ok = libc.mallopt(M_MMAP_THRESHOLD, 1 << 30) == 1 and libc.mallopt(
            M_TRIM_THRESHOLD, 1 << 30) == 1
    except (OSError, AttributeError):
        ok = False
    if ok:
        return ("glibc allocator thresholds fixed (mallopt M_MMAP_THRESHOLD and "
                "M_TRIM_THRESHOLD 1 GiB: freed arrays are reused, as in the steady state of a "
                "long run, whatever ran before)")
    return "allocator at its defaults (not glibc: times may depend on what ran before)"
