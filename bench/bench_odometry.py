"""Speed of photo dead reckoning (seahough.motion.odometry), single thread.

Milliseconds per frame pair measured with the prior (the last motion narrows
the search to a small window: the usual case), and per frame over a whole
run (keyframe patterns, full-search fallbacks and reading included), on
simulated 640x480 sequences (cut from a real photo from ../shared/data, or
the procedural seabed when absent) and on the real sequences (also rescaled
to 640 px wide). Numba compile time is excluded: a warm-up run comes first.
Frames are decoded into memory before the timed runs (file reading is
reported separately, "from files").

Times are CPU times of the (single-threaded) process, so that other programs
on a shared machine do not inflate them; wall-clock times are printed beside.
The runs use ``workers=1``: with more, the coming frames' features are
computed ahead in other threads, so a pair's time would leave them out while
the process's CPU time counts them (from 2026-12-02 to 2026-12-06 this script
ran with the default, all cores).
"ms/pair with prior" is the measurement of one frame against its keyframe on
the fast path (features of the frame, the windowed search and, on the first
pair after a keyframe change, building the keyframe's pattern); "ms/frame
whole run" divides the whole run (fallbacks, CSV, everything but the mosaic
and the plot) by the number of frames.

    python bench/bench_odometry.py            # full run (~1 min)
    python bench/bench_odometry.py --quick    # smoke test (~15 s)
    python bench/bench_odometry.py --sizes    # drift of a turn at 320x240 and 640x480 (~2 min)
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine  # noqa: E402  (sets single-thread first)

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from seahough import sim as S  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.geometry import apply_matrix, invert_matrix  # noqa: E402
import seahough.motion.odometer as odometer  # noqa: E402
from seahough import OdometryTuning, list_frames, run_odometry  # noqa: E402

TARGET_MS = 30.0


def _photo():
    d = shared_data_dir()
    if d is None:
        return None
    p = d / "sequences" / "dtu_seabed_pair" / "scene1.png"
    return str(p) if p.exists() else None


_TIMES: dict = {}


def _timed_measure(orig):
    """Wrap the per-frame measurement to record its CPU and wall time."""
    def wrapper(row, i, *a, **kw):
        c, w = time.process_time(), time.perf_counter()
        out = orig(row, i, *a, **kw)
        _TIMES[i] = (1000.0 * (time.process_time() - c), 1000.0 * (time.perf_counter() - w))
        return out
    return wrapper


# (the per-frame step lives in motion/odometer.py, which run_odometry calls)
odometer._measure_frame = _timed_measure(odometer._measure_frame)


def _run(frames, tmp):
    _TIMES.clear()
    c, t = time.process_time(), time.perf_counter()
    res = run_odometry(frames, tmp, progress=False, mosaic=False, workers=1)
    return res, time.process_time() - c, time.perf_counter() - t


def _stats(res, cpu, wall, n):
    rows = res.rows[1:]
    prior = [_TIMES[r["index"]] for r in rows if r["method"] == "prior" and r["index"] in _TIMES]
    pc = [p[0] for p in prior]
    pw = [p[1] for p in prior]
    # pairs on the prior whose keyframe was already in use for the previous frame (its
    # pattern built): the others build the new keyframe's pattern first
    kept = [_TIMES[r["index"]][0] for q, r in zip(res.rows, rows)
            if r["method"] == "prior" and r["index"] in _TIMES and r["ref"] == q.get("ref")]
    return {
        "frames": n,
        "prior_share": len(prior) / max(len(rows), 1),
        "prior_median": float(np.median(pc)) if pc else math.nan,
        "prior_p90": float(np.percentile(pc, 90)) if pc else math.nan,
        "prior_new_key": len(pc) - len(kept),
        "prior_p90_kept": float(np.percentile(kept, 90)) if kept else math.nan,
        "prior_wall": float(np.median(pw)) if pw else math.nan,
        "mean_all": 1000.0 * cpu / max(n, 1),
        "mean_wall": 1000.0 * wall / max(n, 1),
        "flagged": res.summary["flagged_pairs"],
        "keyframes": res.summary["keyframes"],
    }


def _drift(res, mats, shape):
    h, w = shape
    c = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
    xy = np.array([apply_matrix(invert_matrix(m), [c])[0] for m in mats])
    est = np.array([[r["x"], r["y"]] for r in res.rows])
    length = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    return 100.0 * float(np.hypot(*(est[-1] - xy[-1]))) / length


def _load(folder, width=None):
    out = []
    for p in list_frames(folder):
        img = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
        if width and img.shape[1] != width:
            h = int(round(img.shape[0] * width / img.shape[1]))
            img = cv2.resize(img, (width, h), interpolation=cv2.INTER_AREA if width < img.shape[1]
                             else cv2.INTER_CUBIC)
        out.append(img)
    return out


def drift_by_size(n=60, seeds=(0, 1)):
    """Drift of a simulated turn of ``n`` frames at 320x240 and 640x480, at
    the default keyframe policy and re-keyed on every frame: rows
    ``(size, seed, policy, drift %, heading error deg, keyframes)``."""
    photo = _photo()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for h, w in ((240, 320), (480, 640)):
            for seed in seeds:
                frames, mats = S.sequence(photo, n_frames=n, frame_size=(h, w), path="turn",
                                          seed=seed, source="auto" if photo else "procedural")
                true_heading = math.degrees(math.atan2(mats[-1][1][0], mats[-1][0][0]))
                for policy, tuning in (("default", None),
                                       ("every frame", OdometryTuning(rekey_overlap=0.999))):
                    res = run_odometry(frames, Path(tmp) / f"{w}{seed}{policy}", progress=False,
                                       mosaic=False, workers=1,
                                       **({"tuning": tuning} if tuning else {}))
                    err = abs((res.rows[-1]["heading"] - true_heading + 180.0) % 360.0 - 180.0)
                    rows.append((f"{w}x{h}", seed, policy, _drift(res, mats, (h, w)), err,
                                 res.summary["keyframes"]))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer and shorter sequences")
    ap.add_argument("--sizes", action="store_true",
                    help="only the drift of a 60-frame simulated turn at 320x240 and 640x480, "
                    "with the default keyframes and re-keyed on every frame (~2 min)")
    args = ap.parse_args(argv)
    if args.sizes:
        print(f"command: `{command()}`  ")
        print(f"machine: {machine()}\n")
        print("| frame | seed | keyframes policy | end drift | heading error | keyframes |")
        print("| --- | ---: | --- | ---: | ---: | ---: |")
        for size, seed, policy, drift, err, keys in drift_by_size():
            print(f"| {size} | {seed} | {policy} | {drift:.2f} % | {err:.2f} deg | {keys} |")
        return
    n = 12 if args.quick else 30
    photo = _photo()
    source = "a real photo (dtu_seabed_pair/scene1.png)" if photo else "the procedural seabed"
    table = []
    with tempfile.TemporaryDirectory() as tmp:
        # warm-up: Numba compiles (or loads its cache) here, not in the timed runs
        fr, _ = S.sequence(photo, n_frames=4, frame_size=(480, 640), step=24.0, seed=99,
                           source="auto" if photo else "procedural")
        run_odometry(fr, Path(tmp) / "warm", progress=False, mosaic=False, workers=1)

        for path in ("line", "turn", "loop") if not args.quick else ("line",):
            frames, mats = S.sequence(photo, n_frames=n, frame_size=(480, 640), path=path,
                                      step=24.0, seed=1, source="auto" if photo else "procedural")
            res, cpu, wall = _run(frames, Path(tmp) / path)
            st = _stats(res, cpu, wall, n)
            st["drift"] = _drift(res, mats, (480, 640))
            table.append((f"simulated {path}, 24 px/frame", "640x480", st))

        data = shared_data_dir()
        if data is not None:
            real = [("sparus_auv_seabed", None), ("sparus_auv_seabed", 640),
                    ("aqualoc_amphorae_wreck", 640), ("aqualoc_amphorae_wreck", None)]
            if not args.quick:
                real += [("subvo_pool_chain", 640), ("subvo_pool_chain", None)]
            for name, width in real:
                folder = data / "sequences" / name
                if not folder.is_dir():
                    continue
                frames = _load(folder, width)
                res, cpu, wall = _run(frames, Path(tmp) / f"{name}{width}")
                st = _stats(res, cpu, wall, len(frames))
                st["drift"] = math.nan
                size = f"{frames[0].shape[1]}x{frames[0].shape[0]}"
                label = name + (" (rescaled)" if width else "")
                table.append((label, size, st))
            # end to end from the files (decoding included), native size
            folder = data / "sequences" / "sparus_auv_seabed"
            if folder.is_dir():
                res, cpu, wall = _run(folder, Path(tmp) / "files")
                st = _stats(res, cpu, wall, len(res.rows))
                st["drift"] = math.nan
                table.append(("sparus_auv_seabed, from files", "384x288", st))

    print(f"command: `{command()}`  ")
    print(f"machine: {machine()}  ")
    print(f"simulated frames cut from {source}, moderate water; target <= {TARGET_MS:.0f} ms "
          "per 640x480 pair with the prior\n")
    print("| sequence | frame | frames | pairs on the prior | CPU ms/pair with prior "
          "(median, p90) [wall median] | CPU ms/frame whole run [wall] | keyframes | flagged "
          "| end drift |")
    print("| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for label, size, st in table:
        drift = "-" if math.isnan(st["drift"]) else f"{st['drift']:.2f} %"
        print(f"| {label} | {size} | {st['frames']} | {100 * st['prior_share']:.0f} % | "
              f"{st['prior_median']:.1f}, {st['prior_p90']:.1f} [{st['prior_wall']:.1f}] | "
              f"{st['mean_all']:.1f} [{st['mean_wall']:.1f}] | "
              f"{st['keyframes']} | {st['flagged']} | {drift} |")
    rows = [(label, st) for label, size, st in table if size == "640x480"]
    if rows:
        med = [st["prior_median"] for _, st in rows]
        verdict = "meets" if max(med) <= TARGET_MS else "misses"
        print(f"\n640x480 with the prior, against the {TARGET_MS:.0f} ms target: median "
              f"{min(med):.1f}-{max(med):.1f} CPU ms per pair ({verdict} it in every row"
              + ("" if verdict == "meets" else
                 f": misses in {sum(m > TARGET_MS for m in med)} of {len(med)}") + ").")
        late = [(label, st) for label, st in rows if st["prior_p90"] > TARGET_MS]
        per_row = "; ".join(
            f"{label} {st['prior_p90']:.1f} ms "
            f"({'misses' if st['prior_p90'] > TARGET_MS else 'meets'}; "
            f"{st['prior_p90_kept']:.1f} ms without the {st['prior_new_key']} pairs that first "
            "build a new keyframe's pattern)" for label, st in rows)
        print(f"90th percentile per row: {per_row}. "
              + (f"At the 90th percentile the target is missed in {len(late)} of {len(rows)} "
                 "rows." if late else "The 90th percentile meets the target in every row."))

if __name__ == "__main__":
    main()
