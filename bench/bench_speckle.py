"""Chance answers on sonar-like speckle: does ``max_nfa = e`` hold there?

The a-contrario model (``seahough.core.nfa``, docs/nfa.md) was measured on
object-free photos and rendered seabed. Sonar images are made of speckle,
and side-scan speckle is streaked: blurred more along the track than across
it, so that chance edges run long in one direction. A user's trial on sonar
(2026-12-07) found lines, thin rectangles and curves reported on pure speckle
with NFA far under 1. This page counts them.

Scenes: object-free speckle (exponential noise, 256x256), blurred by a
Gaussian of sigma (sx, sy): isotropic (1.5, 1.5), streaked (3, 0.7) and
(6, 0.7), 30 seeds each. Searched as the README advises for sonar
(``Config(smooth=2)``), with the sonar user's patterns: ``line:100,6`` at any
angle, ``rect:150,8`` (a cylinder, a log), ``rect:60,40``, each with
``min_score=0`` and ``max_nfa=inf`` (every candidate kept, 5 at most an image)
and counted at NFA <= e; and ``curve:8`` (``find_curves``, its seeds' NFA).
The promise is at most about e chance answers an image at ``max_nfa = e``
(docs/nfa.md: within 0.5e-2e is the issue's band). Nothing was tuned on these
scenes; they are not part of bench/bench_nfa.py's calibration.

    python bench/bench_speckle.py --write   # docs/speckle.md (~2 min)
    python bench/bench_speckle.py --quick   # a smoke run (~10 s)
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import page_head, page_parser, publish  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import seahough  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "speckle.md"
BLURS = {"isotropic (1.5, 1.5)": (1.5, 1.5), "streaked (3, 0.7)": (3.0, 0.7),
         "streaked (6, 0.7)": (6.0, 0.7)}
SEEDS = 30
ES = (1.0, 0.1, 0.01, 1e-4)
SMOOTH = 2.0
TOP = 5


def speckle(seed: int, sx: float, sy: float, shape=(256, 256)) -> np.ndarray:
    """Object-free speckle: exponential noise blurred by (sx, sy), levels 0-255.

    >>> a = speckle(0, 3.0, 0.7)
    >>> a.shape, a.dtype.name, int(a.min()), int(a.max())
    ((256, 256), 'uint8', 0, 255)
    """
    a = np.random.default_rng(seed).exponential(1.0, shape).astype(np.float32)
    a = cv2.GaussianBlur(a, (0, 0), sigmaX=sx, sigmaY=sy)
    return cv2.normalize(a, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)


def searches():
    """name -> image -> the NFAs of its answers (every candidate kept, or the curves')."""
    cfg = seahough.Config(smooth=SMOOTH)
    kept = dict(config=cfg, max_nfa=math.inf, min_score=0.0, max_results=TOP)
    dets = {
        "line:100,6": seahough.Detector(seahough.Pattern.line(100, 6), scale_range=(0.5, 2.0),
                                        angle_range=(0, 180), **kept),
        "rect:150,8": seahough.Detector(seahough.Pattern.rectangle(150, 8), **kept),
        "rect:60,40": seahough.Detector(seahough.Pattern.rectangle(60, 40), **kept),
    }
    out = {name: (lambda img, d=d: [x.nfa for x in d.detect(img)]) for name, d in dets.items()}
    out["curve:8"] = lambda img: [c.nfa for c in seahough.find_curves(
        img, 8, config=cfg, max_curves=TOP, max_nfa=max(ES))]
    return out


def measure(seeds: int, blurs: dict) -> list:
    """One row per (blur, search): answers an image at NFA <= e, the smallest NFA."""
    rows = []
    run = searches()
    for blur, (sx, sy) in blurs.items():
        images = [speckle(s, sx, sy) for s in range(seeds)]
        for name, search in run.items():
            nfas = np.array([v for img in images for v in search(img)], float)
            rows.append(dict(blur=blur, search=name, images=seeds,
                             per_e={e: float((nfas <= e).sum()) / seeds for e in ES},
                             least=float(nfas.min()) if nfas.size else math.inf))
    return rows


def page(rows: list, seconds: float) -> str:
    def cell(v, e):   # (under the band is no breach of the promise: a bound)
        return f"{v:.2f}" + (" (over)" if v > 2 * e else "")
    lines = page_head("Chance answers on sonar-like speckle", seconds) + [
        __doc__.split("\n\n")[1].replace("\n", " "), "",
        __doc__.split("\n\n")[2].replace("\n", " "), "",
        "Answers an image at NFA <= e (over: more than 2e, more chance answers than "
        "promised; with 30 images a column under 1/30 cannot be told from 0):",
        "", "| speckle | search | images | " + " | ".join(f"e = {e:g}" for e in ES)
        + " | smallest NFA |", "|---" * (4 + len(ES)) + "|"]
    for r in rows:
        lines.append(f"| {r['blur']} | {r['search']} | {r['images']} | "
                     + " | ".join(cell(r["per_e"][e], e) for e in ES)
                     + f" | {r['least']:.2g} |")
    lines += ["", "Curves: `find_curves(max_nfa=1)`, so the e = 1 column counts every curve "
              "it reports; each curve's NFA is its seed's.", "",
              "## Reading", "",
              "The model counts one independent observation per `DEPENDENCE` (pi) pixels of "
              "edge a pattern lies along (docs/nfa.md). In streaked speckle the chance edges "
              "along the streaks run for tens of pixels, so that a line, a thin rectangle or a "
              "rope's seed laid along them agrees over its whole length far more often than "
              "independent observations would: the NFA of such an answer is too small, by "
              "orders of magnitude when the streaks are long, and `max_nfa` does not hold as a "
              "bound there. Isotropic speckle, like the object-free photos of "
              "docs/nfa_calibration.md, stays near the promise at e = 1 and over it at the "
              "strict end. Estimating the dependence from the image was tried on the chains of "
              "edge points (2026-12-07): the length of a direction's chains does not tell "
              "streaks from a pool photo's few long, real edges (the object's own), so nothing "
              "was changed. On sonar, read the NFA as a ranking, not as a count of false "
              "alarms, and confirm answers along the streaks' direction by eye.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    args = page_parser(__doc__, "speckle.md", "2 seeds, one streaked speckle").parse_args(argv)
    t0 = time.time()
    seeds, blurs = (2, {"streaked (3, 0.7)": BLURS["streaked (3, 0.7)"]}) if args.quick \
        else (SEEDS, BLURS)
    publish(page(measure(seeds, blurs), time.time() - t0), args, DOC)
    return 0


if __name__ == "__main__":
    sys.exit(main())
