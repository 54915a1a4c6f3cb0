"""Real frame pairs made worse: motion blur, sensor noise, JPEG, underexposure.

What a vehicle's camera does to its frames and nobody here controls: a long
exposure while the vehicle moves (motion blur, in another direction in each
frame of a pair), a dark scene's sensor noise, strong JPEG compression on a
thin telemetry link, an underexposed frame (a quarter of the light). Every
consecutive pair of every real sequence of ../shared/data/sequences at native
size, with the reference motion of bench/bench_real_pairs.py (SIFT with a low
contrast threshold and a second fit, agreeing within 0.5 % of the diagonal;
measured on the frames as they are), is degraded and measured again by
seahough ``estimate_motion`` (its defaults), SIFT+RANSAC and ORB+RANSAC
(bench/peers.py).

Reported per degradation and method: pairs answered, answers within 1 % of
the diagonal, answers off by more than 3 % (confident and wrong), median CPU
ms. The split of bench_real_pairs.py (tune part: Sparus and Skerki) is kept
in the tables; nothing here is tuned (the degradations are fixed below).

    python bench/bench_degraded_pairs.py --write   # docs/degraded_pairs.md (~4 min)
    python bench/bench_degraded_pairs.py --quick   # Sparus, 4 pairs
"""

from __future__ import annotations

import argparse
import datetime
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine, publish, steady_allocator  # noqa: E402  (single thread first)

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import bench_real_pairs as R  # noqa: E402
import peers  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "degraded_pairs.md"

METHODS = {
    "seahough": R._seahough,
    "SIFT+RANSAC": lambda a, b: peers.feature_pair("sift", a, b),
    "ORB+RANSAC": lambda a, b: peers.feature_pair("orb", a, b),
}


def motion_blur(img: np.ndarray, length: int, angle: float) -> np.ndarray:
    """A straight blur of ``length`` px at ``angle`` degrees (a camera moving
    during the exposure)."""
    k = np.zeros((length, length), np.float32)
    k[length // 2, :] = 1.0
    m = cv2.getRotationMatrix2D(((length - 1) / 2.0, (length - 1) / 2.0), angle, 1.0)
    k = cv2.warpAffine(k, m, (length, length))
    k /= k.sum()
    return np.clip(cv2.filter2D(img.astype(np.float32), -1, k), 0, 255).astype(np.uint8)


def noise(img: np.ndarray, sigma: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.clip(img.astype(np.float32) + rng.normal(0.0, sigma, img.shape), 0,
                   255).astype(np.uint8)


def jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, quality])
    return cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)


def dark(img: np.ndarray, gain: float, seed: int) -> np.ndarray:
    """A quarter of the light: levels times ``gain`` (truncated to whole
    levels), then the sensor's noise (sigma 2 levels)."""
    return noise((img.astype(np.float32) * gain).astype(np.uint8), 2.0, seed)


def streak(f: np.ndarray, share: float) -> int:
    """A blur length: ``share`` of the frame's width, odd, at least 3 px."""
    return max(3, int(round(share * f.shape[1])) | 1)


#: name -> f(frame, index of the frame, which of the pair: 0 or 1). Blur as a
#: share of the frame's width: an AUV at 1 m/s, 2 m up, a 10 ms exposure moves
#: about 1 % of a 1360 px frame's width during it; "a turn": the streak's
#: direction differs by 60 degrees between the two frames of a pair.
DEGRADATIONS = {
    "as recorded": lambda f, i, k: f,
    "motion blur 1 % of the width": lambda f, i, k: motion_blur(f, streak(f, 0.01),
                                                                 20.0 + 10.0 * k),
    "motion blur 2 %": lambda f, i, k: motion_blur(f, streak(f, 0.02), 20.0 + 10.0 * k),
    "motion blur 2 %, a turn": lambda f, i, k: motion_blur(f, streak(f, 0.02), 20.0 + 60.0 * k),
    "noise sigma 12": lambda f, i, k: noise(f, 12.0, 2 * i + k),
    "JPEG quality 15": lambda f, i, k: jpeg(f, 15),
    "underexposed x0.25": lambda f, i, k: dark(f, 0.25, 2 * i + k),
    "blur 1 % + noise 12": lambda f, i, k: noise(motion_blur(f, streak(f, 0.01), 20.0 + 10.0 * k),
                                                 12.0, 2 * i + k),
}


def run(quick: bool) -> list[dict]:
    data = shared_data_dir()
    out = []
    seqs = R.SEQUENCES[:1] if quick else R.SEQUENCES
    for seq in seqs:
        folder = data / "sequences" / seq
        if not folder.is_dir():
            continue
        _, frames = R.load(folder, False, 5 if quick else None)
        recs = [r for r in R.measure_pairs(seq, "native", frames) if r["ref"] is not None]
        diag = R.diagonal(frames[0].shape)
        for deg, fn in DEGRADATIONS.items():
            pairs = [(r, fn(frames[r["pair"]], r["pair"], 0), fn(frames[r["pair"] + 1],
                                                                  r["pair"] + 1, 1))
                     for r in recs]
            for name, method in METHODS.items():
                R.cpu_timed(method, pairs[0][1], pairs[0][2])      # warm-up
                for r, a, b in pairs:
                    m, ms = R.cpu_timed(method, a, b)
                    mat = None if m is None else m.matrix
                    err = 100.0 * R.corner_error(mat, r["ref"], frames[0].shape) / diag
                    out.append(dict(seq=seq, part=R.part_of(seq), deg=deg, method=name,
                                    answered=mat is not None, err=err, ms=ms))
            R.log(f"{seq}: {deg} done")
    return out


def table(rows: list[dict], part: str | None) -> list[str]:
    lines = ["| degradation | method | pairs | answered | within 1 % (of answers) | off > 3 % "
             "| median CPU ms |", "|---|---|---|---|---|---|---|"]
    for deg in DEGRADATIONS:
        for name in METHODS:
            sel = [r for r in rows if r["deg"] == deg and r["method"] == name
                   and (part is None or r["part"] == part)]
            if not sel:
                continue
            ans = [r for r in sel if r["answered"]]
            ok = sum(r["err"] <= 1.0 for r in ans)
            bad = sum(r["err"] > 3.0 for r in ans)
            bold = "**" if name == "seahough" else ""
            lines.append(f"| {deg} | {bold}{name}{bold} | {len(sel)} | {len(ans)} | "
                         f"{ok}/{len(ans)} | {bad} | {np.median([r['ms'] for r in sel]):.1f} |")
    return lines


def by_sequence(rows: list[dict]) -> list[str]:
    seqs = list(dict.fromkeys(r["seq"] for r in rows))
    lines = ["| degradation | method | " + " | ".join(seqs) + " |",
             "|---|---|" + "---|" * len(seqs)]
    for deg in DEGRADATIONS:
        for name in METHODS:
            cells = []
            for s in seqs:
                sel = [r for r in rows if r["deg"] == deg and r["method"] == name
                       and r["seq"] == s]
                ok = sum(r["answered"] and r["err"] <= 1.0 for r in sel)
                cells.append(f"{ok}/{len(sel)}")
            lines.append(f"| {deg} | {name} | " + " | ".join(cells) + " |")
    return lines


def _tally(rows, deg, method, part=None, seq=None):
    sel = [r for r in rows if r["deg"] == deg and r["method"] == method
           and (part is None or r["part"] == part) and (seq is None or r["seq"] == seq)]
    ans = [r for r in sel if r["answered"]]
    return dict(n=len(sel), answered=len(ans), ok=sum(r["err"] <= 1.0 for r in ans),
                bad=sum(r["err"] > 3.0 for r in ans),
                ms=float(np.median([r["ms"] for r in sel])) if sel else math.nan)


def findings(rows: list[dict]) -> str:
    """The page's reading of its tables (numbers from the rows)."""
    turn = "motion blur 2 %, a turn"
    mild = [d for d in DEGRADATIONS if d not in ("as recorded", turn)]
    t = {d: _tally(rows, d, "seahough", "test") for d in DEGRADATIONS}
    n = t["as recorded"]["n"]
    oks = [t[d]["ok"] for d in mild]
    bad = sum(t[d]["bad"] for d in DEGRADATIONS)
    under = {m: _tally(rows, "underexposed x0.25", m, seq="sparus_auv_seabed")
             for m in METHODS}
    tt = {m: _tally(rows, turn, m, "test") for m in METHODS}
    sp = {d: _tally(rows, d, "seahough", seq="sparus_auv_seabed")
          for d in ("as recorded", "noise sigma 12", "blur 1 % + noise 12")}
    pool = [_tally(rows, turn, m, seq="subvo_pool_chain") for m in METHODS]
    worst = min(DEGRADATIONS, key=lambda d: t[d]["ok"] / max(t[d]["answered"], 1))
    how = ("is seahough's weakest case" if worst == turn else
           f"(its weakest case here is {worst!r})")
    return f"""## What it shows

- Blur along the vehicle's track (1-2 % of the width, the streak turning 10 degrees between
  the frames), noise, JPEG at quality 15 and a quarter of the light: on the test part
  seahough answers {min(t[d]['answered'] for d in mild)}-{n} of {n} pairs, {min(oks)}-{max(oks)}
  within 1 %; {bad} answers off by more than 3 % over every degradation. On the underexposed
  Sparus frames (tune part) SIFT answers {under['SIFT+RANSAC']['answered']} of
  {under['SIFT+RANSAC']['n']} and ORB {under['ORB+RANSAC']['answered']} (too few corners in a
  quarter of the light), seahough {under['seahough']['answered']}.
- **Blur whose streak turns between the frames** (2 % of the width, 60 degrees apart: a
  vehicle yawing during the exposures) {how}: {tt['seahough']['ok']} of
  its {tt['seahough']['answered']} test answers within 1 % (SIFT {tt['SIFT+RANSAC']['ok']} of
  {tt['SIFT+RANSAC']['answered']}, ORB {tt['ORB+RANSAC']['ok']} of
  {tt['ORB+RANSAC']['answered']}), {tt['seahough']['bad']} off by more than 3 %. Edges across
  each frame's streak are smeared away, and different edges survive in the two frames: the
  similarity fitted to what is left is then off by more than 1 %. The tiled pool with 27 px
  streaks,
  within 1 %: {', '.join(f"{m} {c['ok']} of {c['n']}" for m, c in zip(METHODS, pool))}.
- Time: noise makes seahough slower on small frames (Sparus, 384x288: median
  {sp['noise sigma 12']['ms']:.0f} ms a pair against {sp['as recorded']['ms']:.0f};
  {sp['blur 1 % + noise 12']['ms']:.0f} ms with blur and noise), where the working scale
  averages little of the noise away and the vote is less sure of itself (more candidates
  checked, coarse to fine on some pairs).

"""


def report(rows: list[dict], seconds: float, allocator: str) -> str:
    head = f"""# Real frame pairs made worse: blur, noise, JPEG, underexposure

Command: `{command()}`  
Date: {datetime.date.today()}  
Machine: {machine()}; {allocator}  
Run time: {seconds / 60:.1f} min. CPU time per pair, single-threaded.

How it is measured: the docstring of `bench/bench_degraded_pairs.py`. Each real pair with
a reference ([real_pairs.md](real_pairs.md): two agreeing feature fits on the frames as
recorded) is degraded and measured again; an answer is within 1 % when the frame's corners
lie within 1 % of the diagonal of the reference's, off > 3 % when farther than 3 %
(answered and wrong). Motion blur is a straight streak of 1 or 2 % of the frame's width
(odd, at least 3 px: Sparus 5 and 9 px, the wreck 11 and 19, the pool 13 and 27), at 20
degrees in the first frame of a pair and 30 in the second (80 in "a turn"); the noise is
Gaussian (sigma in grey levels of 255);
underexposed: a quarter of the light, then the sensor's noise (sigma 2) and 8-bit levels.
Nothing was tuned on these frames; the split is that of real_pairs.md (tune part: Sparus,
Skerki).

## Test part

"""
    parts = [head.replace("## Test part\n\n", findings(rows) + "## Test part\n\n"),
             "\n".join(table(rows, "test")), "\n\n## Tune part\n\n",
             "\n".join(table(rows, "tune")), "\n\n## Within 1 % by sequence (both parts)\n\n",
             "\n".join(by_sequence(rows)), "\n"]
    return "".join(parts)


def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="Sparus, 4 pairs (smoke test)")
    ap.add_argument("--write", action="store_true",
                    help=f"write the report to {DOC.relative_to(ROOT)}")
    ap.add_argument("--out", default=None, help="write the report here instead")
    args = ap.parse_args(argv)
    if args.quick and args.write:
        ap.error("--quick with --write would replace the page by a smoke test")
    if shared_data_dir() is None or not (shared_data_dir() / "sequences").is_dir():
        sys.exit("no data: ../shared/data/sequences is missing")
    allocator, t0 = steady_allocator(), time.perf_counter()
    text = report(run(args.quick), time.perf_counter() - t0, allocator)
    publish(text, args, str(DOC))
    return text


if __name__ == "__main__":
    main()
