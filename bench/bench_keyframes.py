"""Dead reckoning's keyframes: step error against drift (run_odometry's ``rekey_overlap``).

A frame measured against a keyframe two or more frames back gets its step
(``pair_matrix``: previous -> current frame) as the difference of two
keyframe measurements. Taking every frame as the keyframe measures each
pair directly. This script runs ``run_odometry`` both ways
(``OdometryTuning()`` and ``OdometryTuning(rekey_overlap=REKEY)``, with
which every frame becomes the keyframe of the next) and reports:

- on the real sequences at native size (../shared/data/sequences): the
  median step error against the references of bench/bench_real_pairs.py
  (two agreeing feature fits; % of the diagonal), with the part of that
  page's split each sequence belongs to;
- on simulated sequences with exact truth (frames of 640x480 cut from the
  DTU photo sequences/dtu_seabed_pair/scene1.png, moderate water, paths
  line, turn and loop, seeds 1-3, 30 frames): the median step error and the
  end drift (% of the distance flown).

Nothing is tuned here: both settings exist; the page says what each costs.

    python bench/bench_keyframes.py            # (~5 min: the references' feature fits)
    python bench/bench_keyframes.py --quick    # Sparus and one simulated run
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (single thread first)

import numpy as np  # noqa: E402

import bench_real_pairs as R  # noqa: E402
from seahough import run_odometry, sim as S  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.config import OdometryTuning  # noqa: E402
from seahough.geometry import apply_matrix, compose, invert_matrix  # noqa: E402

#: With this rekey_overlap every frame becomes the keyframe of the next (any motion
#: puts some of the next frame outside the keyframe: overlap() < 1).
REKEY = 1.0
REAL = ("sparus_auv_seabed", "aqualoc_amphorae_wreck", "subvo_pool_chain")
SETTINGS = (("default (keyframes)", OdometryTuning()),
            (f"rekey_overlap={REKEY} (every frame)", OdometryTuning(rekey_overlap=REKEY)))


def corner_pct(a, b, shape) -> float:
    return 100.0 * R.corner_error(a, b, shape) / R.diagonal(shape)


def real_steps(seq: str, tuning, frames, pairs) -> list[float]:
    """Step errors (% of the diagonal) of a run over the frames."""
    shape = frames[0].shape[:2]
    with tempfile.TemporaryDirectory() as tmp:
        rows = run_odometry(list(frames), tmp, progress=False, mosaic=False, workers=1,
                            tuning=tuning).rows
    out = []
    for rec in pairs:
        row = rows[rec["pair"] + 1]
        if rec["ref"] is None or row["status"] != "measured":
            continue
        pm = np.asarray(row["pair_matrix"], float).reshape(2, 3)
        out.append(corner_pct(pm, rec["ref"], shape))
    return out


def simulated(tuning, runs) -> tuple[list[float], list[float]]:
    """(step errors % of the diagonal, end drifts % of the distance) over the runs."""
    photo = shared_data_dir() / "sequences" / "dtu_seabed_pair" / "scene1.png"
    shape = (480, 640)
    steps, drifts = [], []
    for path, seed in runs:
        frames, mats = S.sequence(str(photo), n_frames=30, frame_size=shape, path=path,
                                  step=24.0, seed=seed, water="moderate")
        with tempfile.TemporaryDirectory() as tmp:
            rows = run_odometry(frames, tmp, progress=False, mosaic=False, workers=1,
                                tuning=tuning).rows
        for i in range(1, len(rows)):
            if rows[i]["status"] == "measured":
                truth = compose(mats[i], invert_matrix(mats[i - 1]))
                pm = np.asarray(rows[i]["pair_matrix"], float).reshape(2, 3)
                steps.append(corner_pct(pm, truth, shape))
        c = np.array([(shape[1] - 1) / 2.0, (shape[0] - 1) / 2.0])
        xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
        length = float(np.hypot(*np.diff(xy, axis=0).T).sum())
        end = np.array([rows[-1]["x"], rows[-1]["y"]], float)
        drifts.append(100.0 * float(np.hypot(*(end - xy[-1]))) / length)
    return steps, drifts


def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="Sparus and one simulated run")
    ap.add_argument("--out", default=None, help="also write the table to this file")
    args = ap.parse_args(argv)
    data = shared_data_dir()
    if data is None or not (data / "sequences").is_dir():
        sys.exit("no data: ../shared/data/sequences is missing")
    seqs = REAL[:1] if args.quick else REAL
    runs = [("line", 1)] if args.quick else [(p, s) for p in ("line", "turn", "loop")
                                             for s in (1, 2, 3)]
    lines = [f"Command: `{command()}`. Machine: {machine()}.", "",
             "| data | part | " + " | ".join(n for n, _ in SETTINGS) + " |",
             "|---|---|" + "---|" * len(SETTINGS)]
    for seq in seqs:
        _, frames = R.load(data / "sequences" / seq, False)
        pairs = R.measure_pairs(seq, "native", frames)
        cells = []
        for _, tuning in SETTINGS:
            e = real_steps(seq, tuning, frames, pairs)
            cells.append(f"median step {np.median(e):.3f} % (mean {np.mean(e):.3f}, "
                         f"{len(e)} steps)")
        pair_err = [100 * r["ans"]["seahough"]["err"] / R.diagonal(r["shape"]) for r in pairs
                    if r["ref"] is not None and math.isfinite(r["ans"]["seahough"]["err"])]
        lines.append(f"| {seq}, native (estimate_motion per pair: median "
                     f"{np.median(pair_err):.3f} %) | {R.part_of(seq)} | " + " | ".join(cells) + " |")
    cells = []
    for _, tuning in SETTINGS:
        st, dr = simulated(tuning, runs)
        cells.append(f"median step {np.median(st):.3f} %, end drift mean {np.mean(dr):.3f} % "
                     f"(max {max(dr):.2f})")
    lines.append(f"| simulated, {len(runs)} runs of 30 frames (truth) | - | " + " | ".join(cells)
                 + " |")
    text = "\n".join(lines)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return text


if __name__ == "__main__":
    main()
