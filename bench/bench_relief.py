"""Rendered survey pairs over a seabed in relief, with exact truth.

The real sequences of ../shared/data are few and mostly flat. Here the
large real photos are draped over a smooth random height field
(``seahough.sim.relief_sequence``: standard deviation 5, 10, 15 or 20 cm,
bumps about 40 cm across) and seen by a downward camera 1.5-3 m above it
(1360x1024, 50 degrees across, like an AUV survey camera), moving 16-29 %
of its frame between frames, its strobe fixed to it, through clear, oceanic
or moderate water (sim.PRESETS; the coastal preset's murk over the light's
doubled path leaves almost no texture at 2-3 m). Each sequence has 4 frames (3 consecutive pairs); every
pair is measured at native size and at half size (``cv2.resize``,
INTER_AREA).

Truth: the similarity that fits the true per-pixel motion best (least
squares over the overlap, ``ReliefTruth.similarity``); what it leaves is the
parallax (RMS, reported). A pair is *scored* when that parallax is at most
0.5 % of the diagonal: there one similarity describes the pair as well as
two feature fits agree on the real pairs (bench_real_pairs.py), and an
answer within 1 % of the diagonal of it is right. Pairs with more parallax
are reported apart (answered; within 2 %).

Split by photo: tune part = dtu_seabed_pair/scene1.png and the procedural
seabed (seen while tuning); test part = dtu_seabed_pair/scene2.png (the
same reef a few metres on), aqualoc_amphorae_wreck/frame_040.png (a wreck,
grey) and seabed/dtu_starfish_murky.jpg; seeds are the same in both parts.
Methods and timing as bench_real_pairs.py (CPU time, single thread,
seahough ``estimate_motion`` at its defaults). Dead reckoning:
``run_odometry`` over each sequence at native size, its steps against the
truth.

    python bench/bench_relief.py --write   # docs/relief.md (~6 min)
    python bench/bench_relief.py --quick   # 2 sequences, half size (~20 s)
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import page_head, page_parser, publish  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import bench_real_pairs as R  # noqa: E402
import seahough  # noqa: E402
from seahough import sim  # noqa: E402
from seahough.geometry import compose, invert_matrix  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "relief.md"
TUNE = ("sequences/dtu_seabed_pair/scene1.png", "procedural")
TEST = ("sequences/dtu_seabed_pair/scene2.png", "sequences/aqualoc_amphorae_wreck/frame_040.png",
        "seabed/dtu_starfish_murky.jpg")
RELIEF = (0.05, 0.10, 0.15, 0.20)
WATERS = ("clear", "oceanic", "moderate")
SEEDS = 8
SCORED = 0.005     # parallax (RMS, share of the diagonal) of a scored pair


def half_matrix(m):
    """A full-size 2x3 matrix for frames halved (pixel centres kept)."""
    s = np.array([[0.5, 0.0, -0.25], [0.0, 0.5, -0.25], [0.0, 0.0, 1.0]])
    return (s @ np.vstack([m, [0, 0, 1]]) @ np.linalg.inv(s))[:2]


def render(photo: str, seed: int):
    src = photo if photo == "procedural" else str(shared_data_dir() / photo)
    return sim.relief_sequence(source=src, seed=seed, n_frames=4, relief=RELIEF[seed % 4],
                               water=WATERS[seed % 3])


def measure(photo: str, part: str, seed: int, sizes) -> list[dict]:
    frames, truth = render(photo, seed)
    out = []
    for size in sizes:
        fr = frames if size == "native" else [
            cv2.resize(f, (f.shape[1] // 2, f.shape[0] // 2), interpolation=cv2.INTER_AREA)
            for f in frames]
        shape = fr[0].shape[:2]
        for i in range(len(fr) - 1):
            m, parallax = truth.similarity(i, i + 1)
            if size == "half":
                m, parallax = half_matrix(m), parallax / 2
            ans = {}
            for name, fn in R.METHOD_FNS.items():
                r, ms = R.cpu_timed(fn, fr[i], fr[i + 1])
                mat = None if r is None else r.matrix
                ans[name] = dict(matrix=mat, ms=ms, err=R.corner_error(mat, m, shape))
                if name == "seahough" and r is not None:
                    ans[name].update(nfa=float(r.nfa), confidence=float(r.confidence),
                                     parallax=float(getattr(r, "parallax", float("nan"))))
            rel = parallax / R.diagonal(shape)
            out.append(dict(seq=f"{Path(photo).name} seed {seed}", photo=photo, part=part,
                            size=size, shape=shape, pair=i, parallax=parallax,
                            ref=m if rel <= SCORED else None, truth=m, ans=ans))
    return out


def dead_reckoning(photo: str, part: str, seed: int) -> dict:
    """run_odometry over the sequence at native size (frames in memory, no
    mosaic): pairs measured, and each measured step against the truth."""
    frames, truth = render(photo, seed)
    shape = frames[0].shape[:2]
    with tempfile.TemporaryDirectory() as tmp:
        t = time.process_time()
        rows = seahough.run_odometry(frames, tmp, mosaic=False, progress=False, workers=1).rows
        ms = 1000 * (time.process_time() - t) / len(frames)
    errs = []
    for a, b in zip(rows, rows[1:]):
        if b["status"] != "measured" or a["status"] not in ("origin", "measured"):
            continue
        step = compose(np.reshape(b["matrix"], (2, 3)), invert_matrix(np.reshape(a["matrix"],
                                                                                 (2, 3))))
        m, _ = truth.similarity(a["index"], b["index"])
        errs.append(R.corner_error(step, m, shape) / R.diagonal(shape))
    return dict(part=part, pairs=len(rows) - 1,
                measured=sum(r["status"] == "measured" for r in rows[1:]), errs=errs, ms=ms)


def strong_cells(recs, method):
    """Pairs with strong parallax: answered, within 2 % of the truth."""
    strong = [r for r in recs if r["ref"] is None]
    ans = [r for r in strong if r["ans"][method]["matrix"] is not None]
    good = [r for r in ans if r["ans"][method]["err"] <= 0.02 * R.diagonal(r["shape"])]
    return [str(len(strong)), R.pct(len(ans), len(strong)), R.pct(len(good), len(ans))]


def page(recs, runs, seconds: float, quick: bool) -> str:
    lines = page_head("Survey pairs over a seabed in relief (rendered, exact truth)", seconds)
    lines += ["Split by photo: tune part = " + ", ".join(TUNE) + "; test part = "
             + ", ".join(TEST) + ". Targets are judged on the test part only.", "",
             "How it is made and measured: bench/bench_relief.py's docstring. A pair is scored "
             f"when the parallax its best similarity leaves is at most {100 * SCORED:.1f} % of "
             "the diagonal (RMS); error = largest corner distance to that similarity.", ""]
    if quick:
        lines += ["**Quick run** (a smoke test, not a result).", ""]
    parts = ("test", "tune")
    lines += ["## Scored pairs (parallax at most 0.5 % of the diagonal)", ""]
    rows = []
    for method in R.METHODS:
        for part in parts:
            sub = [r for r in recs if r["part"] == part]
            rows.append([method, part] + R.stats_cells(R.stats(sub, method), method))
    lines += R.table(["method", "part"] + R.STATS_HEAD, rows) + [""]
    lines += ["## By size (test part)", ""]
    rows = []
    for size in ("native", "half"):
        for method in R.METHODS:
            sub = [r for r in recs if r["part"] == "test" and r["size"] == size]
            if sub:
                rows.append([size, method] + R.stats_cells(R.stats(sub, method), method))
    lines += R.table(["size", "method"] + R.STATS_HEAD, rows) + [""]
    lines += ["## Pairs with strong parallax (more than 0.5 % of the diagonal; not scored)", "",
              "The best similarity itself is off by the parallax there: an answer within 2 % "
              "of it is counted.", ""]
    rows = []
    for method in R.METHODS:
        for part in parts:
            sub = [r for r in recs if r["part"] == part]
            rows.append([method, part] + strong_cells(sub, method))
    lines += R.table(["method", "part", "pairs", "answered", "within 2 % (of answers)"], rows)
    lines += ["", "## Dead reckoning (run_odometry at its defaults, native size)", "",
              "Each sequence's 4 frames; a step is measured when its row's status is "
              "`measured` and the frame before it was measured too; error against the "
              "true similarity of the pair.", ""]
    rows = []
    for part in parts:
        sub = [r for r in runs if r["part"] == part]
        if sub:
            errs = [e for r in sub for e in r["errs"]]
            rows.append([part, str(len(sub)), R.pct(sum(r["measured"] for r in sub),
                                                     sum(r["pairs"] for r in sub)),
                         R.fnum(100 * float(np.median(errs)) if errs else math.nan),
                         R.pct(sum(e <= 0.01 for e in errs), len(errs)),
                         R.fnum(float(np.median([r["ms"] for r in sub])), 1)])
    lines += R.table(["part", "sequences", "pairs measured", "median step error % diag",
                      "steps within 1 %", "CPU ms a frame (median)"], rows)
    lines += ["", "## Parallax of the pairs", ""]
    rows = []
    for part in parts:
        for size in ("native", "half"):
            sub = [r for r in recs if r["part"] == part and r["size"] == size]
            if sub:
                par = [r["parallax"] for r in sub]
                rows.append([part, size, str(len(sub)), str(sum(r["ref"] is not None for r in sub)),
                             R.fnum(float(np.median(par)), 1), R.fnum(float(np.max(par)), 1)])
    lines += R.table(["part", "size", "pairs", "scored", "median parallax px (RMS)",
                      "largest px"], rows)
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = page_parser(__doc__, "relief.md", "a smoke run: 2 sequences, half size")
    ap.add_argument("--part", choices=("tune", "test", "both"), default="both",
                    help="render and measure only this part (tuning: --part tune)")
    args = ap.parse_args(argv)
    if shared_data_dir() is None:
        print("bench_relief: ../shared/data not found", file=sys.stderr)
        return 2
    t0 = time.time()
    recs, runs = [], []
    jobs = ([(TUNE[1], "tune", 0), (TEST[2], "test", 1)] if args.quick else
            [(p, "tune", s) for p in TUNE for s in range(SEEDS)]
            + [(p, "test", s) for p in TEST for s in range(SEEDS)])
    if args.part != "both":
        jobs = [j for j in jobs if j[1] == args.part]
    sizes = ("half",) if args.quick else ("native", "half")
    for photo, part, seed in jobs:
        t = time.time()
        recs += measure(photo, part, seed, sizes)
        runs.append(dead_reckoning(photo, part, seed))
        R.log(f"{photo} seed {seed}: {time.time() - t:.0f} s")
    text = page(recs, runs, time.time() - t0, args.quick)
    publish(text, args, DOC)
    return 0


if __name__ == "__main__":
    sys.exit(main())
