"""A small seabed patch found again in a large frame.

A square patch (64, 96 or 128 px) is cut from a photo; the photo is turned
by a random angle and rescaled by 0.9-1.1 about the patch's centre (the
camera came back turned and at another altitude), seen through clear or
moderate water (``seahough.sim.apply_water``), and the patch is searched for
in it: ``seahough.Detector(Pattern(patch), scale_range=(0.85, 1.15))``, full
turn, its defaults. (Positions whose patch has too few edges to be a pattern
are drawn again.) Found = the best detection's origin (the patch centre)
within 3 px of the truth; wrong = a detection farther off. Compared: the
same search without the key points added for small texture patterns
(``core.detector.TEXTURE_DENSITY = 0``: the search before issue 13, point 4),
and SIFT + ratio test + RANSAC (bench/peers.py ``FeatureLocator``).

Split by photo: tune part = the procedural seabed and
dtu_seabed_pair/scene1.png (TEXTURE_DENSITY was set on the procedural seabed); test part =
dtu_seabed_pair/scene2.png and aqualoc_amphorae_wreck/frame_040.png. Frames
are the photo at 1280 px wide and at its own size (1920x1080; the wreck
968x608 and 1280x804).

A second table: **medium patches at unknown scale** (64-128 px patches of
frames 384 and 640 px wide, a quarter to a third of the frame: a user's crop
of one photo searched in the next), searched with ``Detector(Pattern(patch))``
at its defaults (scale 0.5-2, full turn), the view turned and rescaled as
above. Compared: the rule before 2026-12-07, key points added only when the
default put fewer than 16 on the patch (``core.detector.MIN_ON_PATTERN =
16``; a 96 px patch of a 384x288 Sparus frame, 25 there, was missed in that
very frame), and SIFT. Its tune part adds the Sparus frames 0, 10 and 20
(sparus_auv_seabed) to the tune photos; its test part is the test photos'.

    python bench/bench_small_patch.py --write   # docs/small_patch.md (~5 min)
    python bench/bench_small_patch.py --quick   # a smoke run (~20 s)
"""

from __future__ import annotations

import math
import sys
import time
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import page_head, page_parser, publish  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import peers  # noqa: E402
import seahough  # noqa: E402
import seahough.core.detector as D  # noqa: E402
from seahough import sim  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.errors import PatternError  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "small_patch.md"
TUNE = ("procedural", "sequences/dtu_seabed_pair/scene1.png")
TEST = ("sequences/dtu_seabed_pair/scene2.png", "sequences/aqualoc_amphorae_wreck/frame_040.png")
SIDES = (64, 96, 128)
CASES = 8
GOOD_PX = 3.0
METHODS = ("seahough", "seahough, no added key points", "SIFT+RANSAC")


def photos(name: str):
    """The frames of a photo: 1280 px wide and its own size."""
    if name == "procedural":
        return [sim.seabed((720, 1280), seed=11), sim.seabed((1080, 1920), seed=12)]
    img = cv2.imread(str(shared_data_dir() / name), cv2.IMREAD_COLOR)
    h, w = img.shape[:2]
    small = cv2.resize(img, (1280, round(h * 1280 / w)),
                       interpolation=cv2.INTER_AREA if w > 1280 else cv2.INTER_CUBIC)
    return [small, img]


def _seahough(patch, scene, density, scale_range=(0.85, 1.15), min_on=None):
    old = D.TEXTURE_DENSITY, D.MIN_ON_PATTERN
    D.TEXTURE_DENSITY, D.MIN_ON_PATTERN = density, min_on
    try:
        d = seahough.Detector(seahough.Pattern(patch), scale_range=scale_range).detect(scene)
    finally:
        D.TEXTURE_DENSITY, D.MIN_ON_PATTERN = old
    return None if not d else (d[0].x, d[0].y)


def _sift(patch, scene):
    r = peers.FeatureLocator("sift", patch).locate(scene)
    if r.matrix is None:
        return None
    side = patch.shape[0]
    c = np.array([(side - 1) / 2.0, (side - 1) / 2.0])
    return tuple(r.matrix[:, :2] @ c + r.matrix[:, 2])


MEDIUM_TUNE = TUNE + tuple(f"sequences/sparus_auv_seabed/frame_{k:03d}.png" for k in (0, 10, 20))
MEDIUM_METHODS = ("seahough", "seahough, key points added under 16 (before)", "SIFT+RANSAC")


def medium_photos(name: str):
    """The frames of a photo for the medium patches: 640 and 384 px wide
    (a Sparus frame: its own 384x288)."""
    if name == "procedural":
        return [sim.seabed((480, 640), seed=21), sim.seabed((288, 384), seed=22)]
    img = cv2.imread(str(shared_data_dir() / name), cv2.IMREAD_COLOR)
    h, w = img.shape[:2]
    if w <= 384:
        return [img]
    return [cv2.resize(img, (wide, round(h * wide / w)), interpolation=cv2.INTER_AREA)
            for wide in (640, 384)]


def cases(name: str, part: str, n: int, sides, frames=photos, margin: float = 1.0):
    """Patches ``margin`` sides or more from the frame's border (too large a
    patch for the frame is skipped), each with a turned and rescaled view."""
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    for frame in frames(name):
        h, w = frame.shape[:2]
        for side in sides:
            if min(h, w) <= (1 + 2 * margin) * side:
                continue
            for k in range(n):
                for _ in range(50):   # (a patch with no edges to find is not a case)
                    x = int(rng.uniform(margin * side, w - (1 + margin) * side))
                    y = int(rng.uniform(margin * side, h - (1 + margin) * side))
                    try:
                        seahough.Pattern(frame[y:y + side, x:x + side])
                        break
                    except PatternError:
                        continue
                c = (x + (side - 1) / 2.0, y + (side - 1) / 2.0)
                m = cv2.getRotationMatrix2D(c, float(rng.uniform(-180, 180)),
                                            float(rng.uniform(0.9, 1.1)))
                scene = cv2.warpAffine(frame, m, (w, h), flags=cv2.INTER_LINEAR,
                                       borderMode=cv2.BORDER_REFLECT)
                water = ("clear", "moderate")[k % 2]
                scene = sim.apply_water(scene, water, seed=int(rng.integers(1 << 30)))
                yield dict(photo=name, part=part, frame=f"{w}x{h}", side=side, water=water,
                           truth=c), frame[y:y + side, x:x + side], scene


def _timed(case, fns: dict) -> dict:
    """Each method of ``fns`` (name -> call giving the patch centre or None)
    run on the case: answered, error to the truth, CPU ms."""
    out = {}
    for name, fn in fns.items():
        t = time.process_time()
        r = fn()
        ms = 1000 * (time.process_time() - t)
        err = math.inf if r is None else math.hypot(r[0] - case["truth"][0],
                                                     r[1] - case["truth"][1])
        out[name] = dict(answered=r is not None, err=err, ms=ms)
    return dict(case, res=out)


def measure(case, patch, scene) -> dict:
    return _timed(case, {
        "seahough": lambda: _seahough(patch, scene, D.TEXTURE_DENSITY),
        "seahough, no added key points": lambda: _seahough(patch, scene, 0.0),
        "SIFT+RANSAC": lambda: _sift(patch, scene)})


def measure_medium(case, patch, scene) -> dict:
    return _timed(case, {
        "seahough": lambda: _seahough(patch, scene, D.TEXTURE_DENSITY, (0.5, 2.0)),
        MEDIUM_METHODS[1]: lambda: _seahough(patch, scene, D.TEXTURE_DENSITY, (0.5, 2.0), 16),
        "SIFT+RANSAC": lambda: _sift(patch, scene)})


def _cells(recs, method):
    n = len(recs)
    found = sum(r["res"][method]["err"] <= GOOD_PX for r in recs)
    wrong = sum(r["res"][method]["answered"] and r["res"][method]["err"] > GOOD_PX for r in recs)
    ms = float(np.median([r["res"][method]["ms"] for r in recs])) if recs else math.nan
    return [f"{found}/{n} ({100 * found / max(n, 1):.0f} %)", str(wrong), f"{ms:.0f}"]


def medium_table(recs) -> list:
    """The medium patches' table: by part, frame width and patch size, then totals."""
    lines = ["", "## Medium patches at unknown scale", "",
             "64-128 px patches of frames 640 and 384 px wide, `Detector(Pattern(patch))` at "
             "its defaults (scale 0.5-2, any rotation); the view turned and rescaled by 0.9-1.1. "
             "Tune part: " + ", ".join(MEDIUM_TUNE) + "; test part: " + ", ".join(TEST) + ".",
             "", "| part | frame width | patch px | method | found | wrong | median CPU ms |",
             "|---|---|---|---|---|---|---|"]
    for part in ("test", "tune"):
        for wide in ("640", "384"):
            for side in SIDES:
                sub = [r for r in recs if r["part"] == part and r["side"] == side
                       and r["frame"].startswith(wide + "x")]
                for method in MEDIUM_METHODS if sub else ():
                    lines.append("| " + " | ".join([part, wide, str(side), method]
                                                   + _cells(sub, method)) + " |")
    lines += ["", "| part | method | found | wrong | median CPU ms |", "|---|---|---|---|---|"]
    for part in ("test", "tune"):
        sub = [r for r in recs if r["part"] == part]
        for method in MEDIUM_METHODS if sub else ():
            lines.append("| " + " | ".join([part, method] + _cells(sub, method)) + " |")
    return lines


def page(recs, seconds: float, quick: bool, medium=()) -> str:
    lines = page_head("A small seabed patch in a large frame", seconds)
    lines += ["Split by photo: tune part = " + ", ".join(TUNE) + "; test part = "
             + ", ".join(TEST) + ". How the cases are made: bench/bench_small_patch.py's "
             f"docstring. Found = within {GOOD_PX:g} px of the true patch centre; wrong = an "
             "answer farther off.", ""]
    if quick:
        lines += ["**Quick run** (a smoke test, not a result).", ""]
    head = ["part", "frame width", "patch px", "method", "found", "wrong", "median CPU ms"]
    rows = []
    for part in ("test", "tune"):
        for wide in ("1280", "native"):
            for side in SIDES:
                sub = [r for r in recs if r["part"] == part and r["side"] == side
                       and (r["frame"].startswith("1280x") == (wide == "1280"))]
                if not sub:
                    continue
                for method in METHODS:
                    rows.append([part, wide, str(side), method] + _cells(sub, method))
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    lines += ["", "## Totals", "", "| part | method | found | wrong | median CPU ms |",
              "|---|---|---|---|---|"]
    for part in ("test", "tune"):
        sub = [r for r in recs if r["part"] == part]
        for method in METHODS:
            if sub:
                lines.append("| " + " | ".join([part, method] + _cells(sub, method)) + " |")
    if medium:
        lines += medium_table(medium)
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = page_parser(__doc__, "small_patch.md", "a smoke run")
    args = ap.parse_args(argv)
    if shared_data_dir() is None:
        print("bench_small_patch: ../shared/data not found", file=sys.stderr)
        return 2
    t0 = time.time()
    n, sides = (1, (96,)) if args.quick else (CASES, SIDES)
    jobs = [(p, "tune") for p in TUNE] + [(p, "test") for p in TEST]
    if args.quick:
        jobs = [jobs[0], jobs[2]]
    recs = [measure(c, patch, scene)
            for p, part in jobs for c, patch, scene in cases(p, part, n, sides)]
    mjobs = [(p, "tune") for p in MEDIUM_TUNE] + [(p, "test") for p in TEST]
    if args.quick:
        mjobs = [mjobs[2], mjobs[-1]]
    medium = [measure_medium(c, patch, scene) for p, part in mjobs
              for c, patch, scene in cases(p, part, 1 if args.quick else 4, sides,
                                           medium_photos, 0.5)]
    text = page(recs, time.time() - t0, args.quick, medium)
    publish(text, args, DOC)
    return 0


if __name__ == "__main__":
    sys.exit(main())
