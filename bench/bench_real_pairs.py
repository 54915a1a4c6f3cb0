"""Real frame pairs: seahough's motion against two agreeing feature fits.

Every consecutive pair of every real sequence of ../shared/data/sequences,
at native size and at half size (``cv2.resize``, INTER_AREA), gets a
*reference* motion from two independent feature fits, each ending in a
RANSAC similarity (``cv2.estimateAffinePartial2D``, bench/peers.py): SIFT
with a low contrast threshold (``cv2.SIFT_create(contrastThreshold=0.01)``,
ratio test), and AKAZE (``cv2.AKAZE_create()``, ratio test) where OpenCV has
it, else (OpenCV 5.0 dropped AKAZE from its main modules) KLT: corners
tracked by pyramidal Lucas-Kanade on high-passed frames, seeded by a coarse
template-matching shift (:func:`peers.klt_pair`). A pair has a reference
only where the two agree: the four frame corners mapped by the two matrices
lie within 0.5 % of the image diagonal of each other; the reference is then
the mean of the two matrices. Pairs without one are counted, not scored.

Methods, timed in CPU time, single-threaded (bench/_common.py), one call per
pair after a warm-up on the sequence's first pair: seahough
``estimate_motion(prev, cur)`` with its defaults, SIFT+RANSAC (default SIFT),
ORB+RANSAC, AKAZE+RANSAC or KLT+RANSAC (the second fit of the reference
itself: its errors are below 0.5 % of the diagonal by construction) and phase
correlation
(translation only). Error of an answer: the largest distance between the
frame's four corners mapped by the answer and by the reference.

Dead reckoning: ``seahough.run_odometry`` over each sequence at native size
(the frames decoded in memory, one worker, no mosaic, after a warm-up run), its steps (``pair_matrix``) against the reference
pairs, and the end point of its chained trajectory against the chain of
reference motions (SIFT-lowc standing in for a pair without a reference).

The same frames cropped by 1, 2 and 3 px at the top left (:data:`CROPS`):
seahough's pairs and dead reckoning measured again, their matrices brought
back to whole-frame pixels, against the same references. The pixel grid
moves against the scene and nothing else changes, so a figure that moves
between these runs owes that much to one grid: issue 14's checks are judged
on every run. (On the forward-oblique tiled pool they do move: a wrong step
taken in one grid is declined in the next.)

Split: tune part = sparus_auv_seabed and skerki_mud_pair (seen while
tuning), test part = the others; issue 13's targets are judged on the test
part only. Issue 14's check: no answer (or dead-reckoning step) off by more
than 3 % of the diagonal is accepted at NFA <= 1. Pairs without a reference
are not scored, but a seahough answer (or step) there that lies more than
3 % of the diagonal from both fits is listed as likely wrong.

    python bench/bench_real_pairs.py --write   # everything, docs/real_pairs.md (~3 min)
    python bench/bench_real_pairs.py --quick   # 2 pairs per sequence, half size, 1 px crop (~25 s)
"""

from __future__ import annotations

import argparse
import datetime
import inspect
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import (  # noqa: E402  (single thread first)
    command, machine, steady_allocator, write_page)

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import peers  # noqa: E402
import seahough  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.errors import SeahoughError  # noqa: E402
from seahough.geometry import (apply_matrix, compose, frame_centre, invert_matrix,  # noqa: E402
                               shift_origin)

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "real_pairs.md"
SEQUENCES = ("sparus_auv_seabed", "skerki_mud_pair", "aqualoc_amphorae_wreck",
             "dtu_seabed_pair", "subvo_pool_chain")
TUNE = ("sparus_auv_seabed", "skerki_mud_pair")
#: a forward-oblique camera (data README): the motion between its frames is a
#: perspective change, not a similarity (reported apart, for information only)
OBLIQUE = ("subvo_pool_chain",)
AGREE = 0.005      # the two reference fits agree within this share of the diagonal
GOOD = 0.01        # an answer "within 1 %"
WRONG = 0.03       # an answer "off by more than 3 %"
#: what the fits' spread column of the reference table says (the table's figures)
FITS_TEXT = [
    "The spread of similarity fits: the same SIFT-lowc matches fitted again by other robust "
    "criteria (RANSAC at 1, 2 and 5 px instead of the reference's 3 px, and least median of "
    "squares: bench/peers.py similarity_fits), the largest corner distance among the five "
    "matrices. Where the motion is not a similarity (3-D relief, a tilted or oblique camera) "
    "each criterion keeps other matches and the pair's \"similarity\" lands elsewhere: that "
    "column is how far it is defined by the frames, the SIFT-KLT gap how far two fits of one "
    "criterion (RANSAC at 3 px, refined on its inliers) agree. Issue 13's step target is judged "
    "against the second, as the issue states it; the first is shown beside it "
    "(\"fits\") so that a step error between the two reads as an error within the pair's own "
    "ambiguity, not as a miss of that size. It is not a target and no code was tuned on it.",
]
TARGET = 0.97      # issue 13: answer rate and share of answers within 1 %
QUICK_PAIRS = 2
#: seahough measured again on the frames cropped by this many pixels at the
#: top left (the pixel grid shifted against the scene by a pixel or two, the
#: frame as much smaller): a figure that moves with them owes something to one
#: grid, and would not be expected to hold on a new data set
CROPS = (1, 2, 3)
#: the second reference fit: AKAZE where OpenCV has it (not in OpenCV 5.0's main modules)
SECOND = "AKAZE" if hasattr(cv2, "AKAZE_create") else "KLT"
SECOND_METHOD = f"{SECOND}+RANSAC"
SECOND_NOTE = (
    "AKAZE: cv2.AKAZE_create() defaults, ratio test 0.75, brute-force Hamming matching."
    if SECOND == "AKAZE" else
    "AKAZE is not in this OpenCV (5.0 moved it out of the main modules), so the second fit is "
    "KLT: up to 2000 cv2.goodFeaturesToTrack corners of the high-passed frames (minus a "
    "sigma-8 px Gaussian blur: the lights' brightness gradients left out), tracked by "
    "cv2.calcOpticalFlowPyrLK (21x21, 3 levels) forwards and back (kept within 1 px), seeded by "
    "the best of a 3x3 grid of tiles template-matched at 192 px (bench/peers.py klt_pair).")
METHODS = ("seahough", "SIFT+RANSAC", "ORB+RANSAC", SECOND_METHOD, "phase correlation")
_DEFAULTS = inspect.signature(seahough.estimate_motion).parameters
MIN_CONFIDENCE = _DEFAULTS["min_confidence"].default
MAX_NFA = _DEFAULTS["max_nfa"].default


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------
# geometry of the comparison
# --------------------------------------------------------------------------

def corner_error(a, b, shape) -> float:
    """Largest distance between the frame's 4 corners mapped by ``a`` and by
    ``b`` (2x3 matrices; ``inf`` when either is None or not finite)."""
    if a is None or b is None:
        return math.inf
    h, w = shape[:2]
    c = np.array([[0, 0], [w - 1, 0], [w - 1, h - 1], [0, h - 1]], float)
    d = apply_matrix(np.asarray(a, float), c) - apply_matrix(np.asarray(b, float), c)
    return float(np.max(np.hypot(d[:, 0], d[:, 1]))) if np.all(np.isfinite(d)) else math.inf


def diagonal(shape) -> float:
    return math.hypot(shape[1], shape[0])


def reference(sift, second, shape):
    """(matrix or None, why): the mean of the two fits where they agree within
    :data:`AGREE` of the diagonal."""
    if sift is None or second is None:
        missing = " and ".join(n for n, m in (("SIFT-lowc", sift), (SECOND, second)) if m is None)
        return None, f"no {missing} fit"
    d = corner_error(sift, second, shape)
    if d > AGREE * diagonal(shape):
        return None, f"disagree by {d:.1f} px ({100 * d / diagonal(shape):.2f} %)"
    return 0.5 * (np.asarray(sift, float) + np.asarray(second, float)), "agree"


def centre_in_first(cum, shape):
    """Where a frame's centre lies in frame-0 pixels, from its cumulative
    matrix (frame 0 -> that frame)."""
    return apply_matrix(invert_matrix(np.asarray(cum, float)), [frame_centre(shape)])[0]


# --------------------------------------------------------------------------
# measurement
# --------------------------------------------------------------------------

def _seahough(a, b):
    try:
        m = seahough.estimate_motion(a, b)
    except SeahoughError:
        return None
    return m


METHOD_FNS = {
    "seahough": _seahough,
    "SIFT+RANSAC": lambda a, b: peers.feature_pair("sift", a, b),
    "ORB+RANSAC": lambda a, b: peers.feature_pair("orb", a, b),
    SECOND_METHOD: peers.feature_pair_akaze if SECOND == "AKAZE" else peers.klt_pair,
    "phase correlation": peers.phase_correlation,
}


def cpu_timed(fn, *args):
    # OpenCV's RNG seeded before every call: FLANN's randomised k-d trees made the SIFT-lowc
    # fit of the Skerki pair move by about 1 px from one run to the next
    cv2.setRNGSeed(0)
    t = time.process_time()
    out = fn(*args)
    return out, 1000.0 * (time.process_time() - t)


def load(folder: Path, half: bool, limit=None):
    files = [Path(p) for p in seahough.list_frames(folder)]
    if limit is not None:
        files = files[:limit]
    frames = [cv2.imread(str(p), cv2.IMREAD_UNCHANGED) for p in files]
    if half:
        frames = [cv2.resize(f, (round(f.shape[1] / 2), round(f.shape[0] / 2)),
                             interpolation=cv2.INTER_AREA) for f in frames]
    return files, frames


def _sift_lowc(a, b):
    """(SIFT-lowc + RANSAC fit, its matched points)."""
    pts = peers.matched_points("sift-lowc", a, b)
    return peers._ransac(*pts), pts


def fit_spread(fits, shape) -> float:
    """Largest corner distance between any two of the matrices (px)."""
    fits = [f for f in fits if f is not None]
    return max((corner_error(f, g, shape) for i, f in enumerate(fits) for g in fits[i + 1:]),
               default=math.nan)


def measure_pairs(seq: str, size: str, frames) -> list[dict]:
    """One record per consecutive pair: the reference and every method's answer."""
    shape = frames[0].shape[:2]
    for fn in METHOD_FNS.values():       # warm-up: Numba, first-call allocations
        cpu_timed(fn, frames[0], frames[1])
    cpu_timed(peers.feature_pair, "sift-lowc", frames[0], frames[1])
    out = []
    for i in range(len(frames) - 1):
        a, b = frames[i], frames[i + 1]
        (sift, pts), sift_ms = cpu_timed(_sift_lowc, a, b)
        ans = {}
        for name, fn in METHOD_FNS.items():
            r, ms = cpu_timed(fn, a, b)
            ans[name] = dict(matrix=None if r is None else r.matrix, ms=ms)
            if name == "seahough" and r is not None:
                ans[name].update(nfa=float(r.nfa), confidence=float(r.confidence))
        ref, why = reference(sift.matrix, ans[SECOND_METHOD]["matrix"], shape)
        for v in ans.values():
            v["err"] = corner_error(v["matrix"], ref, shape) if ref is not None else math.nan
        out.append(dict(seq=seq, size=size, shape=shape, pair=i, ref=ref, why=why,
                        sift_lowc=sift.matrix, sift_lowc_ms=sift_ms, ans=ans,
                        ref_gap=corner_error(sift.matrix, ans[SECOND_METHOD]["matrix"], shape),
                        fit_spread=fit_spread([sift.matrix, *peers.similarity_fits(*pts)],
                                              shape)))
    return out


def cropped_pairs(frames, pairs: list[dict], crop: int) -> list[dict]:
    """The pair records again, seahough's answers measured on the frames
    cropped by ``crop`` pixels at the top left (brought back to whole-frame
    pixels; the references and the other methods' answers as they were)."""
    frames = [f[crop:, crop:] for f in frames]
    out = []
    for rec in pairs:
        i = rec["pair"]
        m, ms = cpu_timed(_seahough, frames[i], frames[i + 1])
        a = dict(matrix=None, ms=ms)
        if m is not None:
            a.update(matrix=shift_origin(m.matrix, -crop, -crop), nfa=float(m.nfa),
                     confidence=float(m.confidence))
        a["err"] = (corner_error(a["matrix"], rec["ref"], rec["shape"]) if rec["ref"] is not None
                    else math.nan)
        out.append(dict(rec, ans=dict(rec["ans"], seahough=a), crop=crop))
    return out


def dead_reckoning(seq: str, frames, pairs: list[dict], crop: int = 0) -> dict:
    """run_odometry over the frames (arrays), against the pair records;
    ``crop``: over the frames cropped by that many pixels at the top left
    (its matrices back in whole-frame pixels)."""
    shape = frames[0].shape[:2]
    frames = [f[crop:, crop:] for f in frames]
    with tempfile.TemporaryDirectory() as tmp:
        t = time.process_time()
        res = seahough.run_odometry(list(frames), tmp, progress=False, mosaic=False, workers=1)
        cpu = time.process_time() - t
        rows = list(res.iter_rows())
    diag = diagonal(shape)
    steps, stand_in, broken, far = [], [], [], []
    ref_cum = np.eye(2, 3)
    path = 0.0
    prev_c = centre_in_first(ref_cum, shape)
    for rec in pairs:
        i = rec["pair"]
        row = rows[i + 1] if i + 1 < len(rows) else None
        m = rec["ref"]
        if m is None:
            m = rec["sift_lowc"] if rec["sift_lowc"] is not None else rec["ans"][SECOND_METHOD][
                "matrix"]
            (stand_in if m is not None else broken).append(i)
        if m is not None and ref_cum is not None:
            ref_cum = compose(m, ref_cum)
            c = centre_in_first(ref_cum, shape)
            path += float(np.hypot(*(c - prev_c)))
            prev_c = c
        else:
            ref_cum = None
        if row is None or row["status"] != "measured":
            continue
        pm = shift_origin(np.asarray(row["pair_matrix"], float).reshape(2, 3), -crop, -crop)
        if rec["ref"] is None:
            d = [corner_error(pm, f, shape) for f in (rec["sift_lowc"],
                                                      rec["ans"][SECOND_METHOD]["matrix"])]
            if min(d) > WRONG * diagonal(shape):
                far.append(dict(pair=i, dist=[100 * v / diagonal(shape) for v in d],
                                nfa=row.get("nfa"), confidence=row.get("confidence")))
            continue
        err = corner_error(pm, rec["ref"], shape)
        steps.append(dict(pair=i, err=err, nfa=row.get("nfa"), confidence=row.get("confidence"),
                          method=row.get("method"), ref=row.get("ref")))
    status = [r["status"] for r in rows[1:]]
    gap = math.nan
    if ref_cum is not None and rows and rows[-1].get("matrix") is not None:
        est = centre_in_first(shift_origin(np.asarray(rows[-1]["matrix"], float).reshape(2, 3),
                                           -crop, -crop), shape)
        gap = float(np.hypot(*(est - centre_in_first(ref_cum, shape))))
    wrong = [s for s in steps if s["err"] > WRONG * diag]
    return dict(seq=seq, shape=shape, crop=crop, frames=len(frames), pairs=len(frames) - 1,
                measured=status.count("measured"), assumed=status.count("assumed"),
                flagged=sum(bool(r.get("flags")) for r in rows[1:]),
                steps=steps, wrong=wrong,
                wrong_nfa=[s for s in wrong if s["nfa"] is not None and s["nfa"] <= MAX_NFA],
                gap=gap, path=path, stand_in=stand_in, broken=broken, far=far,
                ms_frame=1000.0 * cpu / max(len(frames), 1))


# --------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------

def pct(k: int, n: int) -> str:
    return f"{k}/{n} ({100.0 * k / n:.0f} %)" if n else f"{k}/0"


def fnum(v, nd=2) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{nd}f}"


def stats(recs: list[dict], method: str) -> dict:
    scored = [r for r in recs if r["ref"] is not None]
    ans = [r for r in scored if r["ans"][method]["matrix"] is not None]
    errs = [r["ans"][method]["err"] for r in ans]
    rel = [r["ans"][method]["err"] / diagonal(r["shape"]) for r in ans]
    wrong = [r for r, e in zip(ans, rel) if e > WRONG]
    out = dict(pairs=len(recs), scored=len(scored), answered=len(ans),
               good=sum(e <= GOOD for e in rel), wrong=len(wrong),
               median_px=float(np.median(errs)) if errs else math.nan,
               median_rel=float(np.median(rel)) if rel else math.nan,
               ms=float(np.median([r["ans"][method]["ms"] for r in recs])) if recs else math.nan)
    if method == "seahough":
        out["wrong_nfa"] = sum(r["ans"][method]["nfa"] <= MAX_NFA for r in wrong)
        out["wrong_conf"] = sum(r["ans"][method]["confidence"] >= MIN_CONFIDENCE for r in wrong)
    return out


def stats_cells(s: dict, method: str) -> list[str]:
    wrong = str(s["wrong"])
    if method == "seahough":
        wrong += f" (NFA <= {MAX_NFA:g}: {s['wrong_nfa']})"
    return [str(s["scored"]), pct(s["answered"], s["scored"]), pct(s["good"], s["answered"]),
            wrong, fnum(s["median_px"]), fnum(100 * s["median_rel"]), fnum(s["ms"], 1)]


STATS_HEAD = ["pairs with a reference", "answered", "within 1 % (of answers)", "off > 3 %",
              "median error px", "median error % diag", "median CPU ms"]


def table(head, rows) -> list[str]:
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


def unscored_distances(r: dict) -> dict:
    """seahough's answer to a pair without a reference: its distance to each
    fit, in % of the diagonal."""
    m, dg = r["ans"]["seahough"]["matrix"], diagonal(r["shape"])
    return {"SIFT-lowc": 100 * corner_error(m, r["sift_lowc"], r["shape"]) / dg,
            SECOND: 100 * corner_error(m, r["ans"][SECOND_METHOD]["matrix"], r["shape"]) / dg}


def far_from_both(r: dict) -> bool:
    """A seahough answer to a pair without a reference more than 3 % of the
    diagonal from both fits (likely wrong, though not scored)."""
    return (r["ref"] is None and r["ans"]["seahough"]["matrix"] is not None
            and min(unscored_distances(r).values()) > 100 * WRONG)


def part_of(seq: str) -> str:
    return "tune" if seq in TUNE else "test"


def _crop_section(recs, odo, shifted) -> list[str]:
    """The runs on cropped frames beside the main one (crop 0)."""
    test_seqs = [s for s in SEQUENCES if s not in TUNE]
    rows = []
    for c, (r, d) in [(0, (recs, odo)), *shifted.items()]:
        t = stats([x for x in r if part_of(x["seq"]) == "test"], "seahough")
        a = stats(r, "seahough")
        gaps = {o["seq"]: o["gap"] for o in d}
        rows.append([c, pct(t["answered"], t["scored"]), pct(t["good"], t["answered"]),
                     f"{a['wrong']} (NFA <= {MAX_NFA:g}: {a['wrong_nfa']})",
                     pct(sum(o["measured"] for o in d), sum(o["pairs"] for o in d)),
                     f"{sum(len(o['wrong']) for o in d)} (NFA <= {MAX_NFA:g}: "
                     f"{sum(len(o['wrong_nfa']) for o in d)})",
                     " / ".join(fnum(gaps.get(q, math.nan), 1) for q in test_seqs)])
    return ["## The same frames cropped by a few pixels", "",
            "seahough measured again on every pair and dead-reckoned again over every sequence, "
            f"the frames cropped by {' or '.join(str(c) for c in shifted)} px at the top left "
            "(crop 0: the run above): the "
            "pixel grid shifted against the scene, nothing else changed. Answers brought back to "
            "whole-frame pixels, against the same references. A figure that moves between these "
            "rows owes that much to one grid: read the spread, not one row.", "",
            *table(["crop px", "test: answered", "test: within 1 % (of answers)",
                    "all: answers off > 3 %", "dead reckoning: pairs measured",
                    "steps off > 3 %", "end-point gap px, " + " / ".join(test_seqs)], rows), "",
            *_crop_misses(shifted)]


def _crop_misses(shifted) -> list[str]:
    """The answers and steps off by more than 3 % in the cropped runs."""
    rows = []
    for c, (r, d) in shifted.items():
        rows += [[c, x["seq"], x["size"], "pair", f"{x['pair']}-{x['pair'] + 1}",
                  fnum(100 * x["ans"]["seahough"]["err"] / diagonal(x["shape"])),
                  f"{x['ans']['seahough']['nfa']:.3g}", fnum(x["ans"]["seahough"]["confidence"]),
                  "-", "-"]
                 for x in r if x["ans"]["seahough"]["matrix"] is not None
                 and x["ans"]["seahough"]["err"] > WRONG * diagonal(x["shape"])]
        rows += [[c, o["seq"], "native", "step", f"{s['pair']}-{s['pair'] + 1}",
                  fnum(100 * s["err"] / diagonal(o["shape"])),
                  "-" if s["nfa"] is None else f"{s['nfa']:.3g}", fnum(s["confidence"]),
                  s["method"], s["ref"]] for o in d for s in o["wrong"]]
    if not rows:
        return []
    return ["Off by more than 3 % in the cropped runs:", "",
            *table(["crop px", "sequence", "size", "answer or step", "frames", "error % diag",
                    "NFA", "confidence", "method", "ref"], rows), ""]


def report(recs: list[dict], odo: list[dict], args, seconds: float, allocator: str,
           shifted: dict | None = None) -> str:
    sizes = ["half"] if args.quick else ["native", "half"]
    test = [r for r in recs if part_of(r["seq"]) == "test"]
    L = ["# Real frame pairs: seahough against two agreeing feature fits", "",
         f"Command: `{command()}`  ", f"Date: {datetime.date.today().isoformat()}  ",
         f"Machine: {machine()}  ",
         f"Single-threaded (cv2.setNumThreads(1), NUMBA_NUM_THREADS=1), CPU times of one call per "
         f"pair after a warm-up on the sequence's first pair; {allocator}. Whole run: "
         f"{seconds:.0f} s." + (" **Quick run: 2 pairs per sequence, half size only.**"
                                if args.quick else ""), "",
         f"Split: tune part = {', '.join(TUNE)} (seen while tuning); test part = "
         f"{', '.join(s for s in SEQUENCES if s not in TUNE)}. Targets are judged on the test "
         "part only, pooling both sizes (each pair at each size is one case).", "",
         "How it is measured: bench/bench_real_pairs.py's docstring. Reference = mean of "
         f"SIFT-lowc+RANSAC and {SECOND_METHOD} where their frame corners agree within 0.5 % of "
         "the diagonal; error = largest corner distance to it. " + SECOND_NOTE + " "
         f"{SECOND_METHOD} is half of the reference: its errors are below 0.5 % of the diagonal "
         "by construction.", ""]

    # targets (issue 13, test part) and the NFA check (issue 14, everything)
    s = stats(test, "seahough")
    wrong_conf = s["wrong_conf"]
    rate = s["answered"] / s["scored"] if s["scored"] else math.nan
    good = s["good"] / s["answered"] if s["answered"] else math.nan
    met = lambda ok: "met" if ok else "**missed**"  # noqa: E731
    all_s = stats(recs, "seahough")
    odo_wrong_nfa = sum(len(o["wrong_nfa"]) for o in odo)
    shifted = shifted or {}
    crop_names = ", ".join(str(c) for c in shifted)
    crop_wrong = [(stats(r, "seahough")["wrong_nfa"], sum(len(o["wrong_nfa"]) for o in d))
                  for r, d in shifted.values()]
    # issue 13's time: a pair from scratch no slower than ORB+RANSAC in the same run
    # (at native size: the large frames the target names; a quick run has half size only)
    at = sizes[0]
    speed = []
    for seq in SEQUENCES:
        g = [r for r in test if r["seq"] == seq and r["size"] == at]
        if g:
            speed.append((seq, stats(g, "seahough")["ms"], stats(g, "ORB+RANSAC")["ms"]))
    # issue 13's dead reckoning: every real sequence measured; the steps' median error no
    # larger than the spread of the two fits (their median gap on the pairs both agree on)
    odo_rate = [(o["seq"], o["measured"], o["pairs"]) for o in odo]
    spread = []
    for o in odo:
        if part_of(o["seq"]) != "test" or not o["steps"]:
            continue
        d = diagonal(o["shape"])
        g = [r["ref_gap"] / d for r in recs if r["seq"] == o["seq"] and r["size"] == at
             and r["ref"] is not None]
        f = [r["fit_spread"] / d for r in recs if r["seq"] == o["seq"] and r["size"] == at
             and r["ref"] is not None]
        spread.append((o["seq"], 100 * float(np.median([t["err"] / d for t in o["steps"]])),
                       100 * float(np.median(g)) if g else math.nan,
                       100 * float(np.nanmedian(f)) if f else math.nan))
    L += ["## Targets", "",
          *table(["check", "part", "measured", "target", "result"], [
              ["estimate_motion answers", "test", pct(s["answered"], s["scored"]),
               ">= 97 % of pairs with a reference", met(rate >= TARGET)],
              ["answers within 1 % of the diagonal", "test", pct(s["good"], s["answered"]),
               ">= 97 % of answers", met(good >= TARGET)],
              [f"answers off > 3 % with confidence >= {MIN_CONFIDENCE:g}", "test",
               str(wrong_conf), "none", met(wrong_conf == 0)],
              [f"answers off > 3 % at NFA <= {MAX_NFA:g} (issue 14)", "all",
               str(all_s["wrong_nfa"]), "none", met(all_s["wrong_nfa"] == 0)],
              ["dead reckoning: consecutive pairs measured", "all",
               "; ".join(f"{q} {k}/{n}" for q, k, n in odo_rate), ">= 97 % of every sequence",
               met(bool(odo_rate) and all(k >= TARGET * n for _, k, n in odo_rate))],
              [f"dead reckoning: median step error / median SIFT-{SECOND} gap, % of the "
               f"diagonal, {at} size", "test",
               "; ".join(f"{q} {fnum(a, 2)} / {fnum(b, 3)} (fits: {fnum(c, 2)})"
                         for q, a, b, c in spread),
               "no larger, every sequence",
               met(bool(spread) and all(a <= b for _, a, b, _ in spread))],
              [f"dead-reckoning steps off > 3 % at NFA <= {MAX_NFA:g} (issue 14)", "all",
               str(odo_wrong_nfa), "none", met(odo_wrong_nfa == 0)],
              *([[f"the same two checks on the frames cropped by {crop_names} px "
                  "(answers; steps)", "all",
                  " / ".join(f"{a}; {b}" for a, b in crop_wrong), "none in each",
                  met(not any(a or b for a, b in crop_wrong))]] if shifted else []),
              [f"median CPU ms a pair from scratch, {at} size: seahough / ORB+RANSAC", "test",
               "; ".join(f"{q} {fnum(a, 1)} / {fnum(b, 1)}" for q, a, b in speed),
               "no slower than ORB+RANSAC, every sequence",
               met(bool(speed) and all(a <= b for _, a, b in speed))]]), ""]
    down = stats([r for r in test if r["seq"] not in OBLIQUE], "seahough")
    misses = []
    for seq in SEQUENCES:
        for size in sizes:
            g = [r for r in test if r["seq"] == seq and r["size"] == size and r["ref"] is not None]
            a = [r for r in g if r["ans"]["seahough"]["matrix"] is not None]
            off = sum(r["ans"]["seahough"]["err"] > GOOD * diagonal(r["shape"]) for r in a)
            if len(a) < len(g) or off:
                misses.append(f"{seq} {size}: {len(g) - len(a)} of {len(g)} declined, {off} of "
                              f"{len(a)} answers off by more than 1 %")
    L += ["Where the test part falls short: " + ("; ".join(misses) if misses else "nowhere") + ". "
          f"For information, the test part without the forward-oblique {', '.join(OBLIQUE)} "
          "(a camera looking ahead over a floor of small tiles: its motion is a perspective change, "
          "and the tiles make look-alikes a tile off): answered "
          f"{pct(down['answered'], down['scored'])}, within 1 % {pct(down['good'], down['answered'])}.",
          ""]
    far = [r for r in recs if far_from_both(r)]
    L += ["Not scored (pairs without a reference): " + (
        f"{len(far)} seahough answer(s) lie more than 3 % of the diagonal from both fits: "
        + "; ".join(f"{r['seq']} {r['size']} pair {r['pair']}-{r['pair'] + 1} (NFA "
                    f"{r['ans']['seahough']['nfa']:.2g}, confidence "
                    f"{r['ans']['seahough']['confidence']:.2f})" for r in far)
        + " (listed under Reference motions)." if far else
        "no seahough answer lies more than 3 % of the diagonal from both fits."), ""]

    if shifted:
        L += _crop_section(recs, odo, shifted)

    # references
    rows = []
    for seq in SEQUENCES:
        for size in sizes:
            g = [r for r in recs if r["seq"] == seq and r["size"] == size]
            if not g:
                continue
            dis = [r for r in g if r["why"].startswith("disagree")]
            miss = [r for r in g if r["why"].startswith("no ")]
            agree = [r["ref_gap"] / diagonal(r["shape"]) for r in g if r["ref"] is not None]
            fits = [r["fit_spread"] / diagonal(r["shape"]) for r in g if r["ref"] is not None]
            sh = g[0]["shape"]
            rows.append([seq, f"{size} {sh[1]}x{sh[0]}", len(g), pct(len(g) - len(dis) - len(miss),
                         len(g)), len(dis), len(miss),
                         fnum(100 * float(np.median(agree)) if agree else math.nan, 3),
                         fnum(100 * float(np.nanmedian(fits)) if fits else math.nan, 2),
                         fnum(float(np.median([r["sift_lowc_ms"] for r in g])), 0)])
    L += ["## Reference motions", "",
          *table(["sequence", "size", "pairs", "with a reference", f"SIFT-lowc and {SECOND} disagree",
                  "a fit missing", f"median SIFT-{SECOND} gap % diag",
                  "median spread of similarity fits to the SIFT-lowc matches % diag",
                  "SIFT-lowc CPU ms"], rows), "", *FITS_TEXT, ""]
    noref = [r for r in recs if r["ref"] is None]
    if noref:
        L += ["Pairs without a reference (not scored; seahough's answer shown with its distance "
              "to each fit, in % of the diagonal; **far from both**: more than 3 % from "
              "each):", ""]
        for r in noref:
            a = r["ans"]["seahough"]
            if a["matrix"] is None:
                sh = "declined"
            else:
                d = unscored_distances(r)
                far = " **far from both**" if far_from_both(r) else ""
                sh = (f"answered (confidence {a['confidence']:.2f}, NFA {a['nfa']:.2g}; "
                      + ", ".join(f"{fnum(v, 1)} % from {n}" for n, v in d.items()) + f"){far}")
            L.append(f"- {r['seq']} {r['size']}, pair {r['pair']}-{r['pair'] + 1}: {r['why']}; "
                     f"seahough {sh}")
        L.append("")

    # methods by part
    rows = []
    for m in METHODS:
        for part, g in (("test", test), ("tune", [r for r in recs if part_of(r["seq"]) == "tune"]),
                        ("all", recs)):
            rows.append([m, part, *stats_cells(stats(g, m), m)])
    L += ["## Methods", "", "Answered = a matrix returned (seahough: not None, i.e. confidence "
          f">= {MIN_CONFIDENCE:g}, score >= 0.15 and NFA <= {MAX_NFA:g}, its defaults; feature "
          "methods: a RANSAC model; phase correlation always answers). Off > 3 % = answered and off "
          "by more than 3 % of the diagonal (confident and wrong). Median error over the answers; "
          "median CPU ms over every pair.", "",
          *table(["method", "part", *STATS_HEAD], rows), ""]

    rows = []
    for seq in SEQUENCES:
        for size in sizes:
            g = [r for r in recs if r["seq"] == seq and r["size"] == size]
            if g:
                sh = g[0]["shape"]
                rows += [[seq, f"{size} {sh[1]}x{sh[0]}", m, *stats_cells(stats(g, m), m)]
                         for m in METHODS]
    L += ["## By sequence and size", "", *table(["sequence", "size", "method", *STATS_HEAD], rows),
          ""]

    bad = [r for r in recs if r["ref"] is not None and r["ans"]["seahough"]["matrix"] is not None
           and r["ans"]["seahough"]["err"] > GOOD * diagonal(r["shape"])]
    L += ["## seahough answers off by more than 1 % of the diagonal", "",
          "Every answer off by more than 1 %; those off by more than 3 % (confident and wrong) "
          "are marked.", ""]
    if bad:
        L += table(["sequence", "size", "pair", "error px", "error % diag", "> 3 %", "NFA",
                    "confidence"],
                   [[r["seq"], r["size"], f"{r['pair']}-{r['pair'] + 1}",
                     fnum(r["ans"]["seahough"]["err"], 1),
                     fnum(100 * r["ans"]["seahough"]["err"] / diagonal(r["shape"])),
                     "**yes**" if r["ans"]["seahough"]["err"] > WRONG * diagonal(r["shape"])
                     else "no",
                     f"{r['ans']['seahough']['nfa']:.3g}",
                     fnum(r["ans"]["seahough"]["confidence"])] for r in bad])
    else:
        L.append("None.")
    L.append("")

    # dead reckoning
    rows = []
    for o in odo:
        diag = diagonal(o["shape"])
        errs = [s["err"] for s in o["steps"]]
        chain = "references" if not (o["stand_in"] or o["broken"]) else (
            "; ".join(x for x in (
                f"SIFT-lowc for pair(s) {', '.join(str(i) for i in o['stand_in'])}"
                if o["stand_in"] else "",
                f"no fit for pair(s) {', '.join(str(i) for i in o['broken'])}"
                if o["broken"] else "") if x))
        rows.append([o["seq"], f"{o['shape'][1]}x{o['shape'][0]}", o["frames"],
                     pct(o["measured"], o["pairs"]), o["assumed"], len(o["steps"]),
                     fnum(float(np.median(errs)) if errs else math.nan),
                     f"{len(o['wrong'])} (NFA <= {MAX_NFA:g}: {len(o['wrong_nfa'])})",
                     fnum(o["gap"], 1), fnum(100 * o["gap"] / diag),
                     fnum(100 * o["gap"] / o["path"] if o["path"] > 0 else math.nan, 1),
                     chain, fnum(o["ms_frame"], 0)])
    L += ["## Dead reckoning (run_odometry)", "",
          "run_odometry(frames, out, progress=False, mosaic=False, workers=1) with its defaults "
          f"({'half size, first 3 frames' if args.quick else 'native size, whole sequence'}). "
          "Step = a measured row's pair_matrix (previous -> current frame) against the pair's "
          "reference; end-point gap = distance, in frame-0 pixels, between the last frame's centre "
          "on seahough's trajectory and on the chain of reference motions.", "",
          *table(["sequence", "size", "frames", "pairs measured", "assumed", "steps with a "
                  "reference", "median step error px", "steps off > 3 %", "end-point gap px",
                  "gap % diag", "gap % of path", "reference chain", "CPU ms/frame"], rows), ""]
    far = [(o, s) for o in odo for s in o["far"]]
    L += ["Not scored (steps on pairs without a reference): " + (
        "; ".join(f"{o['seq']} step {s['pair']}-{s['pair'] + 1} lies "
                  f"{fnum(s['dist'][0], 1)} % / {fnum(s['dist'][1], 1)} % of the diagonal from "
                  f"SIFT-lowc / {SECOND} (NFA "
                  + ("-" if s["nfa"] is None else f"{s['nfa']:.2g}")
                  + f", confidence {fnum(s['confidence'])})" for o, s in far) + "."
        if far else "no measured step lies more than 3 % of the diagonal from both fits."), ""]
    wrong_steps = [(o, s) for o in odo for s in o["wrong"]]
    if wrong_steps:
        L += ["Dead-reckoning steps off by more than 3 %:", "",
              *table(["sequence", "pair", "error % diag", "NFA", "confidence", "method", "ref"],
                     [[o["seq"], f"{s['pair']}-{s['pair'] + 1}",
                       fnum(100 * s["err"] / diagonal(o["shape"])),
                       "-" if s["nfa"] is None else f"{s['nfa']:.3g}", fnum(s["confidence"]),
                       s["method"], s["ref"]] for o, s in wrong_steps]), ""]
    return "\n".join(L)


def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n", 1)[1])
    ap.add_argument("--quick", action="store_true",
                    help=f"{QUICK_PAIRS} pairs per sequence, half size only, a 1 px crop (smoke test)")
    ap.add_argument("--write", action="store_true", help=f"write the report to {DOC.relative_to(ROOT)}")
    ap.add_argument("--out", default=None, help="write the report here instead")
    args = ap.parse_args(argv)
    if args.quick and args.write:
        ap.error(f"--quick with --write would replace {DOC.relative_to(ROOT)} by a smoke test")
    data = shared_data_dir()
    if data is None or not (data / "sequences").is_dir():
        print("Skipped: the real data (../shared/data/sequences) is not present.")
        return ""
    allocator = steady_allocator()
    t0 = time.perf_counter()
    recs, odo = [], []
    crops = CROPS[:1] if args.quick else CROPS
    shifted = {c: ([], []) for c in crops}     # crop -> (pair records, dead reckonings)
    limit = QUICK_PAIRS + 1 if args.quick else None
    warm = True
    for seq in SEQUENCES:
        folder = data / "sequences" / seq
        if not folder.is_dir():
            log(f"{seq}: absent, left out")
            continue
        for size in (("half",) if args.quick else ("native", "half")):
            _, frames = load(folder, size == "half", limit)
            if len(frames) < 2:
                continue
            t = time.perf_counter()
            got = measure_pairs(seq, size, frames)
            recs += got
            log(f"{seq} {size}: {len(got)} pairs in {time.perf_counter() - t:.0f} s")
            for c in crops:
                shifted[c][0].extend(cropped_pairs(frames, got, c))
            if size == ("half" if args.quick else "native"):
                if warm:    # Numba compiles the dead reckoning's kernels here, not in a timed run
                    with tempfile.TemporaryDirectory() as tmp:
                        seahough.run_odometry(frames[:2], tmp, progress=False, mosaic=False,
                                              workers=1)
                    warm = False
                t = time.perf_counter()
                odo.append(dead_reckoning(seq, frames, got))
                log(f"{seq} {size}: dead reckoning in {time.perf_counter() - t:.0f} s")
                for c in crops:
                    shifted[c][1].append(dead_reckoning(seq, frames, got, c))
    text = report(recs, odo, args, time.perf_counter() - t0, allocator, shifted)
    print(text)
    out = args.out or (str(DOC) if args.write else None)
    if out:
        write_page(text, out)
    return text


if __name__ == "__main__":
    main()
