"""What cutting a dead reckoning into chunks costs: `survey odometry` against one run.

Every real sequence of ../shared/data/sequences with more than two frames is
dead-reckoned once by ``seahough.run_odometry`` (one run, one worker) and by
``seahough.survey.odometry`` in chunks of 6, 8, 10 and 12 frames (a local
Dask cluster of one worker). Each chunk starts from its own first frame,
without the last chunk's velocity or keyframe, so the chained trajectory
differs from the single run's by what other keyframes change; the figure is
the distance between the last frame's centre on the two trajectories, in
frame-0 pixels (docs/scale.md quotes it). Nothing is tuned here.

    python bench/bench_survey_joins.py           # ~2 min
    python bench/bench_survey_joins.py --quick   # one sequence, chunks of 8 (~30 s)
"""

from __future__ import annotations

import csv
import math
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (single thread first)

import seahough  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402

CHUNKS = (6, 8, 10, 12)


def last_centre(csv_path) -> tuple[float, float]:
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    return float(rows[-1]["x"]), float(rows[-1]["y"])


def main() -> None:
    import argparse

    import distributed

    from seahough import survey

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one sequence, chunks of 8")
    quick = ap.parse_args().quick
    chunks = (8,) if quick else CHUNKS
    root = shared_data_dir() / "sequences"
    if not root.is_dir():
        sys.exit(f"no data: {root} is missing")
    print(f"Command: `{command()}`  \nMachine: {machine()}\n")
    print("| sequence | frames | " + " | ".join(f"chunks of {c}" for c in chunks) + " |")
    print("|---|---|" + "---|" * len(chunks))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as cluster:
        folders = sorted(p for p in root.iterdir() if p.is_dir())
        for folder in [f for f in folders if f.name == "sparus_auv_seabed"] if quick else folders:
            frames = seahough.list_frames(folder)
            if len(frames) < 3:
                continue
            with tempfile.TemporaryDirectory() as tmp:
                one = seahough.run_odometry(frames, Path(tmp) / "one", progress=False,
                                            mosaic=False, workers=1)
                x0, y0 = last_centre(one.csv_path)
                gaps = []
                for c in chunks:
                    out = Path(tmp) / f"chunks{c}"
                    survey.odometry(frames, out, scheduler=cluster.scheduler_address,
                                    chunk_size=c, mosaic=False, progress=False)
                    x, y = last_centre(out / "odometry.csv")
                    gaps.append(f"{math.hypot(x - x0, y - y0):.1f} px")
            print(f"| {folder.name} | {len(frames)} | " + " | ".join(gaps) + " |", flush=True)


if __name__ == "__main__":
    main()
