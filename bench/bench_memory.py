"""Memory stays flat over long runs (issue 6): a benchmark, not a test.

Runs marker detection and photo motion (estimate_motion) on thousands of
640x480 frames -- a handful of simulated scenes and frame pairs, generated
once and cycled -- and reports the process's resident memory (RSS, from
/proc and getrusage), the Python heap (tracemalloc) and the number of live
Python objects after the warm-up and at checkpoints, with the frame rate.
A leak shows as RSS or traced memory growing with the frame count.

    python bench/bench_memory.py                 # 5000 frames (~15-25 min)
    python bench/bench_memory.py --frames 500    # a quicker look
"""

from __future__ import annotations

import argparse
import gc
import os
import resource
import sys
import time
import tracemalloc
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402

import numpy as np  # noqa: E402

import seahough  # noqa: E402
from seahough import simulate as S  # noqa: E402

SHAPE = (480, 640)
MiB = 1024.0 * 1024.0


def rss_now() -> float:
    """Resident set size now, MiB (Linux /proc; the peak elsewhere)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        return pages * os.sysconf("SC_PAGE_SIZE") / MiB
    except (OSError, ValueError, IndexError):
        return rss_peak()


def rss_peak() -> float:
    """Peak resident set size so far, MiB (getrusage: KiB on Linux, bytes on macOS)."""
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / MiB if sys.platform == "darwin" else r / 1024.0


def make_inputs(n_scenes: int, n_pairs: int, source: str):
    img, mask = S.marker("board", 120)
    pattern = seahough.Pattern.from_image(img, mask=mask)
    scenes = [S.marker_scene("board", SHAPE, seed=100 + i, source=source)[0]
              for i in range(n_scenes)]
    pairs = [S.frame_pair(frame_size=SHAPE, seed=200 + i, source=source)[:2]
             for i in range(n_pairs)]
    return pattern, scenes, pairs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=5000, help="frames to process (default 5000)")
    ap.add_argument("--warmup", type=int, default=100,
                    help="frames before the baseline is taken (default 100)")
    ap.add_argument("--checkpoints", type=int, default=5,
                    help="rows between the baseline and the end (default 5)")
    ap.add_argument("--scenes", type=int, default=4, help="distinct marker scenes (default 4)")
    ap.add_argument("--pairs", type=int, default=3, help="distinct frame pairs (default 3)")
    ap.add_argument("--no-motion", action="store_true", help="detection only")
    ap.add_argument("--no-tracemalloc", action="store_true",
                    help="do not trace Python allocations (tracing slows the run a little)")
    ap.add_argument("--source", default="procedural", choices=["procedural", "auto"],
                    help="seabed backgrounds: procedural (default) or real photos when present")
    args = ap.parse_args(argv)
    if args.frames <= args.warmup:
        ap.error("--frames must exceed --warmup")

    t0 = time.perf_counter()
    pattern, scenes, pairs = make_inputs(args.scenes, args.pairs, args.source)
    detector = seahough.Detector(pattern, scale_range=(0.5, 2.0), angle_range=(0.0, 360.0))
    setup_s = time.perf_counter() - t0
    do_motion = not args.no_motion

    step = max(1, (args.frames - args.warmup) // max(args.checkpoints, 1))
    marks = sorted({args.warmup, *range(args.warmup + step, args.frames, step), args.frames})
    rows = []
    found = measured = 0
    t_det = t_mot = 0.0
    last_t, last_i = time.perf_counter(), 0
    trace = not args.no_tracemalloc

    def checkpoint(i):
        nonlocal last_t, last_i
        gc.collect()
        now = time.perf_counter()
        cur, peak = tracemalloc.get_traced_memory() if tracemalloc.is_tracing() else (None, None)
        rows.append(dict(frames=i, rss=rss_now(), peak=rss_peak(), traced=cur, traced_peak=peak,
                         objects=len(gc.get_objects()),
                         fps=(i - last_i) / max(now - last_t, 1e-9)))
        last_t, last_i = time.perf_counter(), i

    for i in range(1, args.frames + 1):
        scene = scenes[i % len(scenes)]
        t = time.perf_counter()
        found += bool(detector.detect(scene))
        t_det += time.perf_counter() - t
        if do_motion:
            a, b = pairs[i % len(pairs)]
            t = time.perf_counter()
            measured += seahough.estimate_motion(a, b) is not None
            t_mot += time.perf_counter() - t
        if i == args.warmup:
            checkpoint(i)
            if trace:
                tracemalloc.start()
                tracemalloc.reset_peak()
            # rates after the warm-up only
            t_det = t_mot = 0.0
        elif i in marks:
            checkpoint(i)
    tracemalloc.stop()

    n = args.frames - args.warmup
    base, end = rows[0], rows[-1]
    mb = lambda v: "-" if v is None else f"{v / MiB:.1f}"
    print("# seahough memory benchmark\n")
    print(f"Command: `{command()}`  \nMachine: {machine()}\n")
    print(f"{args.frames} frames of 640x480: each one a marker detection "
          f"(board marker, scale 0.5-2, any rotation; {len(scenes)} simulated scenes cycled)"
          + (f" and an estimate_motion between two frames ({len(pairs)} simulated pairs cycled)"
             if do_motion else "")
          + f". Baseline after {args.warmup} warm-up frames; inputs made in {setup_s:.1f} s; "
          f"Python allocations traced with tracemalloc: {'yes' if trace else 'no'}.\n")
    print("| frames | RSS now (MiB) | peak RSS (MiB) | traced now (MiB) | traced peak (MiB) "
          "| live Python objects | frames/s |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['frames']} | {r['rss']:.1f} | {r['peak']:.1f} | {mb(r['traced'])} "
              f"| {mb(r['traced_peak'])} | {r['objects']} | "
              f"{'-' if r is base else format(r['fps'], '.2f')} |")
    growth = end["rss"] - base["rss"]
    print(f"\nRSS after warm-up {base['rss']:.1f} MiB, at the end {end['rss']:.1f} MiB: "
          f"{growth:+.1f} MiB over {n} frames ({1000 * growth / n:+.2f} MiB per 1000 frames); "
          f"peak RSS {end['peak']:.1f} MiB (after warm-up: {base['peak']:.1f}).")
    if len(rows) > 2:  # a step right after the baseline (allocator pools, tracing) is not a leak
        first = rows[1]
        late = end["rss"] - first["rss"]
        print(f"From frame {first['frames']} to {end['frames']}: {late:+.1f} MiB "
              f"({1000 * late / max(end['frames'] - first['frames'], 1):+.2f} MiB per 1000 frames).")
    if trace:
        print(f"Python heap (tracemalloc) at the end {mb(end['traced'])} MiB, peak "
              f"{mb(end['traced_peak'])} MiB; live objects {base['objects']} -> {end['objects']}.")
    rate = f"detection {1000 * t_det / n:.1f} ms/frame"
    if do_motion:
        rate += f", estimate_motion {1000 * t_mot / n:.1f} ms/pair"
    total = n / max(t_det + t_mot, 1e-9)
    print(f"Speed after warm-up: {total:.2f} frames/s ({rate}); marker found in "
          f"{100 * found / args.frames:.0f} % of frames"
          + (f", motion measured in {100 * measured / args.frames:.0f} % of pairs." if do_motion
             else "."))
    return 0


if __name__ == "__main__":
    sys.exit(main())
