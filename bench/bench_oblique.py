"""Forward-oblique camera pairs over a tiled pool floor or a seabed (rendered, exact truth).

A camera that looks ahead and down (a pool robot, an ROV) and moves forward
sees the floor expand from a point near the horizon: its frames differ by a
perspective change, not a similarity, even over a flat floor. Over a tiled
pool every tile looks like the next, so a shift by a tile or two matches
almost as well as the true motion. The real example, the shared data's
``subvo_pool_chain``, is in the test part of bench_real_pairs.py; here the
same kind of sequence is rendered with exact truth
(``seahough.sim.relief_sequence`` with ``tilt`` and ``forward``): 1280x720
frames, 50 degrees across, tilted 30-50 degrees from straight down, 1-2 m
above the floor, moving forward 6-15 % of the frame a step, turning by about
2 degrees; a procedural pool floor (``sim.tiled_floor``: tiles of 2.5-5 cm,
a chain, bricks, silt stains; daylight from above, 1 cm of relief) or a
real seabed photo draped on 5-10 cm of relief (strobe on the camera);
clear, oceanic or moderate water.

Truth: the similarity that fits the true per-pixel motion best
(``ReliefTruth.similarity``, least squares over the overlap); what it leaves
is the perspective and parallax (RMS, reported: about 1 % of the diagonal).
An answer is *right* within 2 % of the diagonal of it (corners), *wrong*
beyond 5 %. That truth is one definition of "the" similarity of a
perspective change: a feature fit with RANSAC fits the similarity of the
band where most of its matches agree, which lies 0.5-4.5 % of the diagonal
from it even on the exact true flow (a reviewer's check), and the homography
check reports the least-squares fit itself. So the page also gives each
method's *excess flow RMS*: the RMS distance of its answer from the true
motion over the overlap, less the best similarity's (the parallax), which
does not favour either definition. Each sequence has 4 frames: 3 consecutive pairs and 2 pairs one
frame apart; a loop (frames k, k+1, k+2) is *closed* when its three pairs
are answered, and *consistent* when (k+1 -> k+2) o (k -> k+1) agrees with
k -> k+2 within 2 % of the diagonal. Dead reckoning: ``run_odometry`` over
each sequence's 4 frames at its defaults, its steps (``pair_matrix``)
against the best similarity of each consecutive pair; and over 10 frames of
each tiled floor (the same floor, camera and motion), where keyframes a few
frames back, their checks and look-alikes a tile on meet.

Split: tune part = the tiled floors of seeds 0-5 and dtu_seabed_pair/scene1.png
(seeds 0-1); test part = the tiled floors of seeds 100-105,
aqualoc_amphorae_wreck/frame_040.png and dtu_seabed_pair/scene2.png (seeds
0-1). A dev part (``--part dev``: the tiled floors of seeds 200-239, never
in a page of docs/) is for developing the motion search on repeated
textures without looking at the test part: the comparison of answers over
the points both keep in view, and ``MARGINAL`` 0.4, were chosen on it
(docs/method.md). Methods and timing as bench_real_pairs.py (CPU time, single thread;
seahough ``estimate_motion`` at its defaults), and seahough with its
homography checks switched off ("similarity only": as before them; the
vote's candidates refitted as homographies, motion/perspective.py, and the
pair measured coarse to fine, motion/pyramid.py).

    python bench/bench_oblique.py --write   # docs/oblique.md (~5 min)
    python bench/bench_oblique.py --quick   # 2 sequences at 640x360 (~15 s)
    python bench/bench_oblique.py --part tune --out oblique_tune.md   # (a page outside docs/)
    python bench/bench_oblique.py --part dev --out oblique_dev.md     # 40 floors (~10 min)
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import page_head, page_parser, publish  # noqa: E402

import numpy as np  # noqa: E402

import bench_real_pairs as R  # noqa: E402
import seahough  # noqa: E402
import seahough.motion.pair as P  # noqa: E402
from seahough import sim  # noqa: E402
from seahough.geometry import compose  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "oblique.md"
SCENE1 = "sequences/dtu_seabed_pair/scene1.png"
TUNE = [("tiles", s) for s in range(6)] + [(SCENE1, s) for s in range(2)]
DEV = [("tiles", s) for s in range(200, 240)]
TEST = ([("tiles", s) for s in range(100, 106)]
        + [(p, s) for p in ("sequences/aqualoc_amphorae_wreck/frame_040.png",
                            "sequences/dtu_seabed_pair/scene2.png") for s in range(2)])
WATERS = ("clear", "oceanic", "moderate")
PAIRS = ((0, 1), (1, 2), (2, 3), (0, 2), (1, 3))
LOOPS = ((0, 1, 2), (1, 2, 3))
RIGHT = 0.02       # an answer within this share of the diagonal of the best similarity
WRONG = 0.05       # ... and wrong beyond this
CONSISTENT = 0.02  # a loop's inconsistency within this share of the diagonal
TARGET_LOOPS = 0.9 # issue 13: the tiled pool closes at least 9 loops in 10
PARTS = ("test", "tune", "dev")   # (in a page's order)
LONG = 10          # frames of the longer dead-reckoning runs over the tiled floors


BEFORE = "seahough, similarity only"


def _similarity_only(a, b):
    """seahough as it was before the homography checks (motion/perspective.py,
    motion/pyramid.py): both switched off, for the comparison in the same run."""
    real = P.check_perspective, P.coarse_to_fine, P.MARGINAL, P.REPEATED
    P.check_perspective = P.coarse_to_fine = lambda *args, **kw: None
    P.MARGINAL = 0.0     # (nor a marginal answer voted again at the coarse scale,
    P.REPEATED = math.inf  # nor one over a repeated texture)
    try:
        return R.METHOD_FNS["seahough"](a, b)
    finally:
        P.check_perspective, P.coarse_to_fine, P.MARGINAL, P.REPEATED = real


METHOD_FNS = {**R.METHOD_FNS, BEFORE: _similarity_only}
METHODS = R.METHODS[:1] + (BEFORE,) + R.METHODS[1:]


def render(source: str, seed: int, size=(720, 1280), n_frames: int = 4):
    rng = np.random.default_rng(1000 + seed)
    tiles = source == "tiles"
    src = source if tiles else str(shared_data_dir() / source)
    return sim.relief_sequence(
        source=src, seed=seed, n_frames=n_frames, frame_size=size,
        tilt=float(rng.uniform(30, 50)), forward=True, strobe=not tiles,
        relief=0.01 if tiles else float(rng.uniform(0.05, 0.10)), altitude=(1.0, 2.0),
        step=(0.06, 0.15), turn=2.0, water=WATERS[seed % 3])


def label(source: str) -> str:
    return "tiled floor" if source == "tiles" else Path(source).name


def measure(source: str, part: str, seed: int, size=(720, 1280)) -> dict:
    frames, truth = render(source, seed, size)
    shape = frames[0].shape[:2]
    pairs = {}
    for i, j in PAIRS:
        m, parallax = truth.similarity(i, j)
        fp, fq = truth.flow(i, j, step=16)
        ans = {}
        for name, fn in METHOD_FNS.items():
            r, ms = R.cpu_timed(fn, frames[i], frames[j])
            mat = None if r is None or r.matrix is None else np.asarray(r.matrix, float)
            flow = (math.inf if mat is None else
                    float(np.sqrt(((fp @ mat[:, :2].T + mat[:, 2] - fq) ** 2).sum(1).mean())))
            ans[name] = dict(matrix=mat, ms=ms, err=R.corner_error(mat, m, shape),
                             flow=flow - parallax)
            if name.startswith("seahough") and r is not None:
                ans[name].update(nfa=float(r.nfa), confidence=float(r.confidence))
        pairs[(i, j)] = dict(truth=m, parallax=parallax, ans=ans)
    return dict(source=source, kind=label(source), seed=seed, part=part, shape=shape,
                tilt=truth.tilt, pairs=pairs, odometry=dead_reckoning(frames, truth))


def dead_reckoning(frames, truth) -> dict:
    """``run_odometry`` over the sequence (frames in memory, no mosaic, its
    defaults): the consecutive pairs it measured, and each step (a measured
    row's ``pair_matrix``: previous -> current frame) against the best
    similarity of the true motion, as a share of the diagonal, with its NFA."""
    with tempfile.TemporaryDirectory() as tmp:
        t = time.process_time()
        rows = seahough.run_odometry(frames, tmp, mosaic=False, progress=False, workers=1).rows
        ms = 1000 * (time.process_time() - t) / len(frames)
    shape = frames[0].shape[:2]
    steps = []
    for a, b in zip(rows, rows[1:]):   # (a step from an assumed pose is not measured)
        if (b["status"] != "measured" or a["status"] not in ("origin", "measured")
                or b.get("pair_matrix") is None):
            continue
        m, _ = truth.similarity(a["index"], b["index"])
        step = np.reshape(np.asarray(b["pair_matrix"], float), (2, 3))
        steps.append((R.corner_error(step, m, shape) / R.diagonal(shape), float(b["nfa"])))
    return dict(pairs=len(rows) - 1, measured=sum(r["status"] == "measured" for r in rows[1:]),
                steps=steps, ms=ms)


def long_run(seed: int, part: str, size=(720, 1280), n_frames: int = LONG) -> dict:
    """The dead reckoning over a longer run of a tiled floor (the same floor,
    camera and motion as the 4-frame sequence of that seed, ``n_frames``
    frames): where keyframes, their checks and look-alikes a tile on meet."""
    frames, truth = render("tiles", seed, size, n_frames)
    return dict(part=part, kind=f"tiled floor, {n_frames} frames", seed=seed,
                odometry=dead_reckoning(frames, truth))


def odometry_rows(recs) -> list:
    """Per part and floor: pairs measured, the steps' median error, within
    RIGHT, off by more than WRONG (and of those, at NFA <= 1), CPU ms a frame."""
    rows = []
    for part in PARTS:
        for kind in sorted({r["kind"] for r in recs if r["part"] == part}):
            sub = [r["odometry"] for r in recs if r["part"] == part and r["kind"] == kind]
            errs = [e for o in sub for e, _ in o["steps"]]
            off = [(e, nfa) for o in sub for e, nfa in o["steps"] if e > WRONG]
            rows.append([part, kind, R.pct(sum(o["measured"] for o in sub),
                                           sum(o["pairs"] for o in sub)),
                         R.fnum(100 * float(np.median(errs)) if errs else math.nan),
                         R.pct(sum(e <= RIGHT for e in errs), len(errs)),
                         f"{len(off)} (NFA <= {R.MAX_NFA:g}: "
                         f"{sum(nfa <= R.MAX_NFA for _, nfa in off)})",
                         R.fnum(float(np.median([o["ms"] for o in sub])), 1)])
    return rows


def loop_cells(recs, method):
    closed = consistent = n = 0
    for rec in recs:
        d = R.diagonal(rec["shape"])
        for a, b, c in LOOPS:
            n += 1
            m1, m2, m13 = (rec["pairs"][k]["ans"][method]["matrix"]
                           for k in ((a, b), (b, c), (a, c)))
            if m1 is None or m2 is None or m13 is None:
                continue
            closed += 1
            consistent += R.corner_error(compose(m2, m1), m13, rec["shape"]) <= CONSISTENT * d
    return n, closed, consistent


def pair_cells(recs, method):
    rows = [(rec, p) for rec in recs for p in rec["pairs"].values()]
    ans = [(rec, p) for rec, p in rows if p["ans"][method]["matrix"] is not None]
    rel = [p["ans"][method]["err"] / R.diagonal(rec["shape"]) for rec, p in ans]
    wrong = [(rec, p) for (rec, p), e in zip(ans, rel) if e > WRONG]
    cells = [str(len(rows)), R.pct(len(ans), len(rows)), R.pct(sum(e <= RIGHT for e in rel),
                                                                  len(ans))]
    w = str(len(wrong))
    if method.startswith("seahough"):
        w += f" (NFA <= {R.MAX_NFA:g}: {sum(p['ans'][method]['nfa'] <= R.MAX_NFA for _, p in wrong)})"
    n, closed, consistent = loop_cells(recs, method)
    flow = [p["ans"][method]["flow"] / R.diagonal(rec["shape"]) for rec, p in ans]
    return cells + [w, R.fnum(100 * float(np.median(rel)) if rel else math.nan),
                    R.fnum(100 * float(np.median(flow)) if flow else math.nan),
                    R.pct(closed, n), R.pct(consistent, n),
                    R.fnum(float(np.median([p["ans"][method]["ms"] for _, p in rows])), 1)]


HEAD = ["pairs", "answered", "within 2 % (of answers)", "off > 5 %", "median error % diag",
        "median excess flow RMS % diag", "loops closed", "loops consistent (2 %)", "median CPU ms"]


def page(recs, seconds: float, quick: bool, long_recs=()) -> str:
    lines = page_head("Forward-oblique camera pairs (rendered, exact truth)", seconds)
    lines += ["Split: tune part = " + ", ".join(sorted({label(s) for s, _ in TUNE}))
              + " (tiled floors: seeds 0-5); test part = "
              + ", ".join(sorted({label(s) for s, _ in TEST}))
              + " (tiled floors: seeds 100-105). Targets are judged on the test part only.", "",
              "How it is made and measured: bench/bench_oblique.py's docstring. Error = largest "
              "corner distance to the similarity that fits the true motion best; right within "
              f"{100 * RIGHT:.0f} %, wrong beyond {100 * WRONG:.0f} % of the diagonal. That "
              "similarity is the least-squares fit over the overlap, which the homography check "
              "reports and RANSAC fits (the similarity of a band) do not: the excess flow RMS "
              "(the answer's RMS distance from the true motion over the overlap, less the best "
              "similarity's) compares the methods without that bias.", ""]
    if quick:
        lines += ["**Quick run** (a smoke test, not a result).", ""]
    test_tiles = [r for r in recs if r["part"] == "test" and r["source"] == "tiles"]
    if test_tiles:
        n, closed, consistent = loop_cells(test_tiles, "seahough")
        ok = consistent >= TARGET_LOOPS * n
        lines += ["## Target (test part, tiled floors)", "",
                  f"Loops closed and consistent by seahough: {consistent}/{n} "
                  f"(target at least {100 * TARGET_LOOPS:.0f} %, as issue 13 asks of the real "
                  f"tiled pool): **{'met' if ok else 'missed'}**.", ""]
    for part in PARTS:
        sub = [r for r in recs if r["part"] == part]
        if not sub:
            continue
        lines += [f"## {part.capitalize()} part", ""]
        rows = []
        for kind in sorted({r["kind"] for r in sub}):
            for method in METHODS:
                rows.append([kind, method] + pair_cells([r for r in sub if r["kind"] == kind],
                                                        method))
        lines += R.table(["floor", "method"] + HEAD, rows) + [""]
    lines += ["## Dead reckoning (run_odometry at its defaults, native size)", "",
              "Each sequence's 4 frames; a step is a measured row's pair_matrix (previous -> "
              "current frame; the previous frame measured too), its error against the best similarity of the true motion of the "
              "pair. The dead reckoning measures most steps against a keyframe a few frames "
              "back: for a camera that looks ahead, similarities of different overlaps do not "
              "compose, so its steps can differ from the pairs measured one by one (above).", ""]
    lines += R.table(["part", "floor", "pairs measured", "median step error % diag",
                      f"steps within {100 * RIGHT:.0f} %", f"steps off > {100 * WRONG:.0f} %",
                      "CPU ms a frame (median)"], odometry_rows(recs)) + [""]
    if long_recs:
        n = long_recs[0]["odometry"]["pairs"] + 1
        lines += [f"## Longer runs over the tiled floors ({n} frames)", "",
                  f"The dead reckoning over {n} frames of each tiled floor (the same seeds, "
                  "floor, camera and motion as above): keyframes a few frames back, their checks "
                  "against the last measured frame, and look-alikes a tile on meet here. Columns "
                  "as above.", ""]
        lines += R.table(["part", "floor", "pairs measured", "median step error % diag",
                          f"steps within {100 * RIGHT:.0f} %",
                          f"steps off > {100 * WRONG:.0f} %", "CPU ms a frame (median)"],
                         odometry_rows(long_recs)) + [""]
    lines += ["## The pairs", "",
              "Perspective and parallax the best similarity leaves (RMS px), and seahough's "
              "answer (error % of the diagonal, confidence, NFA; '-' = declined).", ""]
    rows = []
    for r in recs:
        for (i, j), p in r["pairs"].items():
            a = p["ans"]["seahough"]
            got = ("-" if a["matrix"] is None else
                   f"{100 * a['err'] / R.diagonal(r['shape']):.2f} % ({a['confidence']:.2f}, "
                   f"{a['nfa']:.1e})")
            rows.append([r["part"], f"{r['kind']} seed {r['seed']}", f"{r['tilt']:.0f}",
                         f"{i}-{j}", R.fnum(p["parallax"], 1), got])
    lines += R.table(["part", "sequence", "tilt deg", "pair", "parallax px", "seahough"], rows)
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = page_parser(__doc__, "oblique.md", "a smoke run: 2 sequences at 640x360")
    ap.add_argument("--part", choices=("tune", "test", "both", "dev"), default="both",
                    help="render and measure only this part (tuning: --part tune; dev: the "
                         "development floors, seeds 200-239, alone)")
    args = ap.parse_args(argv)
    if shared_data_dir() is None:
        print("bench_oblique: ../shared/data not found", file=sys.stderr)
        return 2
    t0 = time.time()
    if args.part == "dev":
        if args.write:
            print("bench_oblique: the dev part is not a page of docs/ (use --out)",
                  file=sys.stderr)
            return 2
        jobs = [(s, "dev") for s in DEV]
    else:
        jobs = ([(s, "tune") for s in TUNE] if args.part != "test" else []) + \
               ([(s, "test") for s in TEST] if args.part != "tune" else [])
    if args.quick:   # the first sequence of each part
        jobs = [j for k, j in enumerate(jobs) if k == 0 or jobs[k - 1][1] != j[1]]
    recs, long_recs = [], []
    size = (360, 640) if args.quick else (720, 1280)
    for (source, seed), part in jobs:
        t = time.time()
        recs.append(measure(source, part, seed, size))
        if source == "tiles":
            long_recs.append(long_run(seed, part, size, 5 if args.quick else LONG))
        R.log(f"{label(source)} seed {seed}: {time.time() - t:.0f} s")
    publish(page(recs, time.time() - t0, args.quick, long_recs), args, DOC)
    return 0


if __name__ == "__main__":
    sys.exit(main())
