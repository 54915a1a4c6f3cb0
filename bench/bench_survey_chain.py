"""The one serial step of `seahough survey odometry`: chaining the chunks.

Synthetic chunk CSVs (run_odometry's columns; a camera turning slowly, 12 px
a frame, a keyframe every 5 frames) for N frames in chunks of 200 are
chained by seahough.survey.odometry.chain_chunks exactly as a survey does
(read each chunk's CSV, join, recompute the global columns, write
odometry.csv). Single thread; the chunk files are in the page cache.

    python bench/bench_survey_chain.py [N]        # default 100000
"""
import csv
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (single-thread setup first)

import numpy as np  # noqa: E402

from seahough.geometry import compose  # noqa: E402
from seahough.io.frames import FrameReader  # noqa: E402
from seahough.motion.runfiles import run_settings, settings_hash  # noqa: E402
from seahough.motion.track import (CSV_BASE, CSV_CHECK, CSV_MORE, pose_columns, row_to_csv)  # noqa: E402
from seahough.config import ODOMETRY_CONFIG, OdometryTuning  # noqa: E402
from seahough.survey._odometry_chunks import plan_chunks, chunk_folder  # noqa: E402
from seahough.survey.odometry import chain_chunks  # noqa: E402

SHAPE = (480, 640)


def motion(i):
    a = math.radians(0.3)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 12.0 + 0.01 * (i % 7)]])


def write_chunk(folder: Path, start: int, n: int, columns, digest):
    folder.mkdir(parents=True, exist_ok=True)
    cum = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    key, prev_cum = 0, None
    with open(folder / "odometry.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        w.writeheader()
        heading = 0.0
        for i in range(n):
            row = {"index": i, "file": f"/survey/frames/img_{start + i:06d}.jpg",
                   "frame_hash": "s1a3a1-a1ee6c46", "settings_hash": digest, "flags": "",
                   "ms": 14.2}
            if i == 0:
                row["status"] = "origin"
            else:
                cum = compose(motion(start + i), prev_cum)
                row.update(status="measured", ref=key, method="prior", confidence=0.7,
                           score=0.5, overlap=0.8)
            row.update(pose_columns(cum, SHAPE, heading, None, prev_cum))
            heading = row["heading"]
            if i % 5 == 4:
                key = i
            prev_cum = cum
            w.writerow(row_to_csv(row, columns))


def main(n=100_000, chunk_size=200):
    columns = CSV_BASE + CSV_MORE + CSV_CHECK
    digest = settings_hash(run_settings((0.9, 1.1), (-20, 20), None, ODOMETRY_CONFIG,
                                        OdometryTuning()))
    plan = plan_chunks(n, chunk_size)
    with tempfile.TemporaryDirectory() as d:
        out = Path(d)
        results = []
        for k, (a, b) in enumerate(plan):
            folder = chunk_folder(out, k)
            write_chunk(folder, a, b - a, columns, digest)
            results.append({"chunk": k, "start": a, "folder": str(folder), "state": "measured",
                            "resumed_rows": 0, "n": b - a, "shape": SHAPE, "gone": []})
        items = [f"/survey/frames/img_{i:06d}.jpg" for i in range(n)]
        reader = FrameReader(items, 10 ** 9)
        t = time.perf_counter()
        cpu = time.process_time()
        totals, joins, _ = chain_chunks(results, reader, out / "odometry.csv", columns, digest,
                                        None, None)
        wall, cpu = time.perf_counter() - t, time.process_time() - cpu
        assert totals.frames == n and joins["exact"] == len(plan) - 1, (totals.frames, joins)
    print(f"machine: {machine()}; single thread\ncommand: {command()}")
    print(f"chained {n} frames in {len(plan)} chunks of {chunk_size}: {wall:.1f} s wall, "
          f"{cpu:.1f} s CPU = {1000 * wall / n:.3f} ms a frame "
          f"({wall * 100_000 / n:.0f} s for 100,000 frames)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 100_000)
