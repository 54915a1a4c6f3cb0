"""Memory stays flat over long runs (issue 6): a benchmark, not a test.

Part 1 runs marker detection and photo motion (estimate_motion) on thousands
of 640x480 frames -- a handful of simulated scenes and frame pairs, generated
once and cycled. Part 2 runs photo dead reckoning (run_odometry) over as many
640x480 frames on disk: a simulated closed loop of frames (written once as
PNG files) listed over and over, so the camera circles the same ground and
every pass of the loop ends with a jump back to its first frame (a full
search); the CSV, the keyframes, the summary and at the end the mosaic and
the trajectory plot all run as in a survey. Both report the process's
resident memory (RSS, from /proc and getrusage), the Python heap
(tracemalloc) and the number of live Python objects after the warm-up and
at checkpoints, with the frame rate. A leak, or state that grows with the
frame count, shows as RSS or traced memory growing with the frame count.

    python bench/bench_memory.py                       # 5000 frames each (~30-40 min)
    python bench/bench_memory.py --frames 500          # a quicker look
    python bench/bench_memory.py --frames 200 --odometry-only   # odometry part, ~1 min
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

import cv2  # noqa: E402

import seahough  # noqa: E402
import seahough.motion.odometer as odometer  # noqa: E402
import seahough.motion.odometry as odometry  # noqa: E402
from seahough import sim as S  # noqa: E402

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


class Probe:
    """Checkpoints of memory and speed (the rows of one table)."""

    def __init__(self, trace: bool):
        self.trace = trace
        self.rows = []
        self.last_t, self.last_i = time.perf_counter(), 0

    def checkpoint(self, i, label=None):
        gc.collect()
        now = time.perf_counter()
        cur, peak = tracemalloc.get_traced_memory() if tracemalloc.is_tracing() else (None, None)
        self.rows.append(dict(frames=i, label=label, rss=rss_now(), peak=rss_peak(), traced=cur,
                              traced_peak=peak, objects=len(gc.get_objects()),
                              fps=(i - self.last_i) / max(now - self.last_t, 1e-9)))
        self.last_t, self.last_i = time.perf_counter(), i

    def start_tracing(self):
        if self.trace:
            tracemalloc.start()
            tracemalloc.reset_peak()


def print_table(rows, first_is_base=True):
    mb = lambda v: "-" if v is None else f"{v / MiB:.1f}"  # noqa: E731
    print("| frames | RSS now (MiB) | peak RSS (MiB) | traced now (MiB) | traced peak (MiB) "
          "| live Python objects | frames/s |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for k, r in enumerate(rows):
        fps = "-" if (k == 0 and first_is_base) or r["label"] else format(r["fps"], ".2f")
        print(f"| {r['label'] or r['frames']} | {r['rss']:.1f} | {r['peak']:.1f} "
              f"| {mb(r['traced'])} | {mb(r['traced_peak'])} | {r['objects']} | {fps} |")


def growth_lines(rows, n):
    """RSS and heap growth between the checkpoints (``rows`` without labelled ones)."""
    base, end = rows[0], rows[-1]
    mb = lambda v: "-" if v is None else f"{v / MiB:.1f}"  # noqa: E731
    growth = end["rss"] - base["rss"]
    out = [f"RSS after warm-up {base['rss']:.1f} MiB, at frame {end['frames']} "
           f"{end['rss']:.1f} MiB: {growth:+.1f} MiB over {n} frames "
           f"({1000 * growth / max(n, 1):+.2f} MiB per 1000 frames); peak RSS {end['peak']:.1f} "
           f"MiB (after warm-up: {base['peak']:.1f})."]
    if len(rows) > 2:  # a step right after the baseline (allocator pools, tracing) is not a leak
        first = rows[1]
        late = end["rss"] - first["rss"]
        span = max(end["frames"] - first["frames"], 1)
        out.append(f"From frame {first['frames']} to {end['frames']}: {late:+.1f} MiB "
                   f"({1000 * late / span:+.2f} MiB per 1000 frames).")
        if first["traced"] is not None and end["traced"] is not None:
            heap = end["traced"] - first["traced"]
            out.append(f"Python heap (tracemalloc) from frame {first['frames']} to "
                       f"{end['frames']}: {heap / 1024:+.0f} KiB "
                       f"({heap / 1.024 / span:+.2f} KiB per 1000 frames).")
    if end["traced"] is not None:
        out.append(f"Python heap at frame {end['frames']} {mb(end['traced'])} MiB, peak "
                   f"{mb(end['traced_peak'])} MiB; live objects {base['objects']} -> "
                   f"{end['objects']}.")
    return out


def odometry_pass(args, tmp: Path) -> None:
    """Part 2: run_odometry over ``args.frames`` frames on disk, with checkpoints."""
    t0 = time.perf_counter()
    frames, _ = S.sequence(None, n_frames=args.loop, frame_size=SHAPE, path="loop", step=24.0,
                           seed=7, source=args.source)
    folder = tmp / "frames"
    folder.mkdir()
    files = []
    for i, f in enumerate(frames):
        q = folder / f"loop_{i:03d}.png"
        cv2.imwrite(str(q), f)
        files.append(str(q))
    del frames
    paths = [files[i % len(files)] for i in range(args.frames)]
    setup_s = time.perf_counter() - t0
    # warm-up (Numba compiles, first allocations) on a few frames, outside the measurement
    odometry.run_odometry(files[:4], tmp / "warm", progress=False, mosaic=False)

    probe = Probe(not args.no_tracemalloc)
    marks = _marks(args)
    advance = odometer.advance   # (the per-frame step's, motion/odometer.py)

    def advance_and_probe(st, row, tuning):    # called once per frame, after its row is written
        advance(st, row, tuning)
        i = row["index"] + 1
        if i == args.warmup:
            probe.checkpoint(i)
            probe.start_tracing()
        elif i in marks:
            probe.checkpoint(i)

    odometer.advance = advance_and_probe
    t = time.perf_counter()
    try:
        res = odometry.run_odometry(paths, tmp / "odometry", progress=False,
                                    mosaic=not args.no_mosaic)
    finally:
        odometer.advance = advance
    total_s = time.perf_counter() - t
    probe.checkpoint(args.frames, label="after mosaic and plot" if not args.no_mosaic
                     else "after plot")
    tracemalloc.stop()
    sm = res.summary          # (not res.rows: they would be read back from the CSV)
    n = args.frames - args.warmup
    loop_rows = [r for r in probe.rows if not r["label"]]
    print("\n## Photo dead reckoning (run_odometry)\n")
    print(f"{args.frames} frames of 640x480 on disk: a simulated closed loop of {args.loop} frames "
          f"(24 px/frame, {args.source} seabed, PNG; written in {setup_s:.1f} s) listed "
          f"{args.frames / args.loop:.0f} times over; one run_odometry call "
          f"({'with' if not args.no_mosaic else 'without'} the mosaic). Baseline after "
          f"{args.warmup} frames; Python allocations traced with tracemalloc: "
          f"{'yes' if probe.trace else 'no'}. The last row is taken after run_odometry has "
          "returned (mosaic and trajectory plot built from the CSV).\n")
    print_table(probe.rows)
    print()
    for line in growth_lines(loop_rows, n):
        print(line)
    after = probe.rows[-1]
    mb = lambda v: "-" if v is None else f"{v / MiB:.1f}"  # noqa: E731
    print(f"After the outputs: RSS {after['rss']:.1f} MiB, peak RSS {after['peak']:.1f} MiB, "
          f"Python heap {mb(after['traced'])} MiB (traced peak {mb(after['traced_peak'])} MiB).")
    methods = ", ".join(f"{k} {v}" for k, v in sorted(sm["methods"].items()))
    print(f"Run: {sm['frames']} frames, {sm['measured_pairs']} measured ({methods}), "
          f"{sm['flagged_pairs']} flagged, {sm['keyframes']} keyframes; "
          f"{args.frames / max(total_s, 1e-9):.1f} frames/s over the whole call "
          f"({total_s:.0f} s, outputs included; tracing slows it).")
    if res.mosaic_path is not None:
        m = cv2.imread(str(res.mosaic_path), cv2.IMREAD_UNCHANGED)
        print(f"Mosaic {m.shape[1]}x{m.shape[0]} px.")


def _marks(args):
    step = max(1, (args.frames - args.warmup) // max(args.checkpoints, 1))
    return sorted({args.warmup, *range(args.warmup + step, args.frames, step), args.frames})


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
    ap.add_argument("--no-motion", action="store_true", help="detection only (part 1)")
    ap.add_argument("--no-odometry", action="store_true", help="part 1 only")
    ap.add_argument("--odometry-only", action="store_true", help="part 2 only")
    ap.add_argument("--loop", type=int, default=48,
                    help="frames of the simulated loop that part 2 cycles (default 48)")
    ap.add_argument("--no-mosaic", action="store_true", help="part 2 without the mosaic")
    ap.add_argument("--no-tracemalloc", action="store_true",
                    help="do not trace Python allocations (tracing slows the run a little)")
    ap.add_argument("--source", default="procedural", choices=["procedural", "auto"],
                    help="seabed backgrounds: procedural (default) or real photos when present")
    args = ap.parse_args(argv)
    if args.frames <= args.warmup:
        ap.error("--frames must exceed --warmup")
    if args.no_odometry and args.odometry_only:
        ap.error("--no-odometry and --odometry-only exclude each other")
    if args.loop < 8:
        ap.error("--loop must be at least 8 frames")

    print("# seahough memory benchmark\n")
    print(f"Command: `{command()}`  \nMachine: {machine()}\n")
    if not args.odometry_only:
        detection_pass(args)
    if not args.no_odometry:
        import tempfile
        with tempfile.TemporaryDirectory() as tmp:
            odometry_pass(args, Path(tmp))
    return 0


def detection_pass(args) -> None:
    """Part 1: detection and estimate_motion, with checkpoints."""
    t0 = time.perf_counter()
    pattern, scenes, pairs = make_inputs(args.scenes, args.pairs, args.source)
    detector = seahough.Detector(pattern, scale_range=(0.5, 2.0), angle_range=(0.0, 360.0))
    setup_s = time.perf_counter() - t0
    do_motion = not args.no_motion

    marks = _marks(args)
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
    print("## Marker detection and estimate_motion\n")
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


if __name__ == "__main__":
    sys.exit(main())
