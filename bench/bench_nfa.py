"""Calibration of the number of false alarms (NFA) on object-free photos.

A detection's NFA promises: at ``max_nfa = e``, about ``e`` chance
detections per image searched. This script measures it: it searches
patterns that are not in the photos (markers on natural seabed, a cross and
a ring in pool photos) with no other filter (``min_score=0``,
``max_nfa=inf``), keeps every detection with its evidence (n, k, p, number
of tests: :mod:`seahough.core.nfa`), and counts, for each promised ``e``,
the detections per search with NFA <= e.

The split (by photo: no test photo is seen when tuning; each sequence is cut
in two so that both parts hold every kind of scene):

- tune: the even Sparus AUV frames, the first half of the AQUALOC wreck
  frames, the first Skerki and DTU frames (4 views each: as is, mirrored,
  turned by 90 degrees, rescaled by 0.75; DTU in 640x480 crops), simulated
  object-free scenes cut from those photos (seeds 0-299, the three water
  presets in turn) and on the procedural seabed (even seeds 0-598);
- test: the odd Sparus frames, the second half of the wreck, the second
  Skerki and DTU frames, the DTU starfish photo, simulated scenes cut from
  those (seeds 0-299), the procedural seabed (odd seeds), and the RoboSub
  pool photos (cross and ring only; reported apart: a pool holds real
  crosses and discs).

Besides whole-image marker searches, the same images are searched for a
rope (a line pattern, as ``find_curves`` seeds its search) and for markers in
a 200 x 200 px window (one at a known pose): searches that count far fewer
poses, so that the model is seen where the number of tests varies.

The constant in use, :data:`seahough.core.nfa.DEPENDENCE`, is the smallest
at which the NFA holds as a bound on the tune part. With ``--fit`` the
script also fits a *calibrated* model on the tune part's whole-image marker
searches: :data:`~seahough.core.nfa.DEPENDENCE` together with a *share* of the counted
poses taken as independent tries (log10; the product takes every pose, a
share of 0, never fewer than one try): of a grid of both, the
pair that puts the most of the (group, e) within the band 0.5e-2e, ties
broken by the squared log ratio of observed to promised (:func:`fit`); the
page shows both models on every kind of search, and at the defaults. Each
detection's NFA is recomputed at any pair from its stored evidence (the
binomial tail at each DEPENDENCE of :data:`DEPENDENCES`, with the share
and the search's counted poses). The test part is reported as
measured, by group, kind of search and pattern.

    python bench/bench_nfa.py --write         # ~10 min: collect, report, plot
    python bench/bench_nfa.py --quick         # smoke test (~20 s)
    python bench/bench_nfa.py --fit           # also fit a calibrated model on the tune part
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
import math
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import command, machine, seabed_split  # noqa: E402  (sets single-thread first)

import cv2  # noqa: E402
import numpy as np  # noqa: E402

import seahough  # noqa: E402
from seahough import sim as S  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402
from seahough.core import nfa as N  # noqa: E402
from seahough.core import ranking  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PROMISED = (0.01, 0.1, 1.0)
MARKER_PATTERNS = ("L", "cross", "board", "ring", "chevron")
#: Searches of other kinds on the same object-free images (search name ->
#: pattern, Detector arguments; a window: the 200 x 200 px around the image
#: centre): they count far fewer poses than a whole-image marker search
#: (10 ** 4.6 to 10 ** 7 against 10 ** 8.5 to 10 ** 9.7), so that the fit sees
#: the number of tests vary.
OTHER_SEARCHES = {
    "rope (line 96 x 8)": ("rope", dict(scale_range=(0.5, 1.5), angle_range=(0.0, 180.0))),
    "L in a window": ("L", dict(scale_range=(0.8, 1.25), angle_range=(-15.0, 15.0),
                                window=200)),
    "cross in a window, pose known": ("cross", dict(scale_range=(1.0, 1.0),
                                                    angle_range=(0.0, 0.0), window=200)),
}
NATURAL_SEARCHES = MARKER_PATTERNS + tuple(OTHER_SEARCHES)
POOL_PATTERNS = ("cross", "ring")


def kind(name: str) -> str:
    """The kind of a search, by its name: a whole-image marker search, or one
    of :data:`OTHER_SEARCHES`."""
    return "marker, whole image" if name in MARKER_PATTERNS else name


def detector(pats: dict, name: str, img: np.ndarray):
    """The unfiltered Detector of the search ``name`` on ``img``."""
    if name not in OTHER_SEARCHES:
        return seahough.Detector(pats[name], min_score=0.0, max_nfa=math.inf)
    key, kw = OTHER_SEARCHES[name]
    kw = dict(kw)
    half = kw.pop("window", None)
    if half is not None:
        h, w = img.shape[:2]
        half //= 2
        kw["search_region"] = (w // 2 - half, h // 2 - half, w // 2 + half, h // 2 + half)
    return seahough.Detector(pats[key], min_score=0.0, max_nfa=math.inf, **kw)


def patterns() -> dict:
    out = {}
    for name in ("L", "cross", "board"):
        img, mask = S.marker(name, 120)
        out[name] = seahough.Pattern.from_image(img, mask=mask)
    out["ring"] = seahough.Pattern.circle(40, 25)
    out["chevron"] = seahough.Pattern.polygon([(0, 0), (60, 40), (120, 0), (120, 25), (60, 65),
                                               (0, 25)])
    out["rope"] = seahough.Pattern.line(96, 8)   # (a find_curves seed of a rope 8 px wide)
    return out


def views(img: np.ndarray):
    """Four views of a photo: as is, mirrored, turned by 90 degrees, rescaled by 0.75."""
    yield "as is", img
    yield "mirrored", img[:, ::-1].copy()
    yield "turned", np.ascontiguousarray(np.rot90(img))
    yield "0.75", cv2.resize(img, None, fx=0.75, fy=0.75, interpolation=cv2.INTER_AREA)


def crops(img: np.ndarray, size=(480, 640), n=4):
    """Up to ``n`` non-overlapping crops of ``size`` (a large photo)."""
    h, w = img.shape[:2]
    ch, cw = size
    if h < ch or w < cw:
        yield img
        return
    k = 0
    for y in range(0, h - ch + 1, ch):
        for x in range(0, w - cw + 1, cw):
            if k < n:
                yield img[y:y + ch, x:x + cw]
                k += 1


def images(quick: bool):
    """(group, split, label, loader, pattern names) of every object-free image."""
    base = shared_data_dir()
    items = []
    n_sim = 6 if quick else 300
    for seed in range(2 * n_sim):
        water = S.water.PRESETS[(seed // 2) % 3]
        items.append(("sim procedural", "tune" if seed % 2 == 0 else "test",
                      f"seed {seed} {water}",
                      lambda s=seed, w=water: [S.negative_scene((480, 640), water=w, seed=s,
                                                                source="procedural")],
                      NATURAL_SEARCHES))
    if base is None:
        return items
    tune_real, test_real = seabed_split(base)
    if quick:
        tune_real, test_real = tune_real[:1], test_real[:1]

    def real(path):
        img = cv2.imread(str(path))
        return [v for c in crops(img) for _, v in views(c)]

    for split, photos in (("tune", tune_real), ("test", test_real)):
        for p in photos:
            items.append(("seabed photos", split, p.name, lambda p=p: real(p), NATURAL_SEARCHES))
        for seed in range(n_sim):
            water = S.water.PRESETS[seed % 3]
            src = photos[seed % len(photos)]
            items.append((f"sim on {split} photos", split, f"seed {seed} {water}",
                          lambda s=seed, w=water, src=src: [S.negative_scene(
                              (480, 640), water=w, seed=s, source=src)], NATURAL_SEARCHES))
    pool = pool_photos(base)
    for p in pool[:2] if quick else pool:
        items.append(("pool photos (RoboSub)", "test", p.name, lambda p=p: [cv2.imread(str(p))],
                      POOL_PATTERNS))
    return items


def pool_photos(base: Path) -> list:
    """The RoboSub pool photos (frames 100 and up: 0-99 are renders)."""
    pool = sorted((base / "objects" / "robosub_transdec" / "images").glob("*.jpg"),
                  key=lambda p: int(re.findall(r"\d+", p.name)[0]))
    return [p for p in pool if int(re.findall(r"\d+", p.name)[0]) >= 100]


def pool_split(quick: bool) -> str:
    """The false alarms of the pool photos at the Detector's defaults, told
    apart by where they lie: on a prop that others labelled in the photo
    (the box grown by half its size on every side: a ring on a round buoy,
    a cross on the torpedo board's holes; a look-alike that is there, not
    chance) or elsewhere. A markdown table; the counts stay those of the
    calibration (every detection is a false alarm: neither pattern is in
    the pool)."""
    from bench_robosub import parse_voc
    base = shared_data_dir()
    pats = patterns()
    photos = pool_photos(base)[:20] if quick else pool_photos(base)
    where: Counter = Counter()
    props: Counter = Counter()
    for p in photos:
        img = cv2.imread(str(p))
        xml = base / "objects" / "robosub_transdec" / "annotations" / (p.stem + ".xml")
        boxes = parse_voc(xml.read_text()) if xml.exists() else []
        for name in POOL_PATTERNS:
            for d in seahough.Detector(pats[name]).detect(img):
                on = [b for b in boxes if b.x0 - b.w / 2 <= d.x <= b.x1 + b.w / 2
                      and b.y0 - b.h / 2 <= d.y <= b.y1 + b.h / 2]
                where[name, bool(on)] += 1
                props.update((name, label) for label in {b.name for b in on})
    n = len(photos)
    lines = ["| pattern | searches | false alarms a search | on a labelled prop | elsewhere "
             "| the props they lie on |", "|---|---|---|---|---|---|"]
    for name in POOL_PATTERNS:
        on, off = where[name, True], where[name, False]
        labels = ", ".join(f"{lab} {k}" for (pn, lab), k in props.most_common()
                           if pn == name) or "-"
        lines.append(f"| {name} | {n} | {(on + off) / n:.3f} | {on / n:.3f} | {off / n:.3f} "
                     f"| {labels} |")
    on = sum(v for (_, lies_on), v in where.items() if lies_on)
    off = sum(v for (_, lies_on), v in where.items() if not lies_on)
    lines.append(f"| both | {2 * n} | {(on + off) / (2 * n):.3f} | {on / (2 * n):.3f} | "
                 f"{off / (2 * n):.3f} | |")
    return "\n".join(lines)


#: The DEPENDENCE values (pixels of edge) every detection's NFA is also
#: computed at (for --fit), besides the product's.
DEPENDENCES = (4.0, 8.0, 12.0, 14.0, 16.0, 18.0, 20.0, 24.0)
#: The shares of the fit's grid (log10 of the counted poses taken as tries;
#: applied to the stored rows).
SHARES = tuple(np.arange(-10.0, 0.01, 0.25).round(2))
#: The calibrated model the fit of bench_nfa found (16, -7.5), not adopted
#: (docs/nfa.md): shown beside the model in use when --fit is not given.
CALIBRATED = (16.0, -7.5)


def collect(quick: bool) -> dict:
    """Every detection's evidence on every object-free image: its NFA at
    each of :data:`DEPENDENCES`, and the search's counted poses (log10)."""
    pats = patterns()
    rows, searches = [], []
    judged = [0.0]
    judge = ranking.judge

    def timed_judge(ctx, c):
        t = time.perf_counter()
        judge(ctx, c)
        judged[0] += time.perf_counter() - t
        used, by = N.DEPENDENCE, {}
        try:
            for d in sorted({*DEPENDENCES, used}):   # (the product's, and the grid)
                N.DEPENDENCE = d
                judge(ctx, c)
                by[d] = c.evidence.log10_nfa
        finally:
            N.DEPENDENCE = used
        judge(ctx, c)
        c.by_dependence = by
        c.log_tests = ranking.search_tests(ctx)

    ranking.judge = timed_judge
    t_search = 0.0
    items = images(quick)
    t0 = time.time()
    try:
        for i, (group, split, label, load, names) in enumerate(items):
            for img in load():
                for name in names:
                    det = detector(pats, name, img)
                    j0 = judged[0]
                    t = time.perf_counter()
                    res = det.search(img)
                    dt = time.perf_counter() - t
                    # (the judge ran 2 + len(DEPENDENCES) times: its time counts once)
                    t_search += dt - (judged[0] - j0) * (1 + len({*DEPENDENCES, N.DEPENDENCE}))
                    searches.append((group, split, name))
                    judged_c = [c for c in res.candidates if c.evidence is not None]
                    for d in res.detections:
                        c = next(c for c in judged_c if c.full.score == d.score
                                 and c.evidence.nfa == d.nfa)
                        e = c.evidence
                        rows.append({"group": group, "split": split, "pattern": name,
                                     "label": label, "score": d.score,
                                     "confidence": d.confidence, "n": e.n, "k": e.k, "p": e.p,
                                     "log_tests": c.log_tests,
                                     "log10_nfa": {str(float(k)): v
                                                   for k, v in c.by_dependence.items()}})
            if i % 50 == 0:
                print(f"{i}/{len(items)} images, {time.time() - t0:.0f} s", flush=True)
    finally:
        ranking.judge = judge
    return {"rows": rows, "searches": searches, "judge_s": judged[0], "search_s": t_search}


def log_nfa(rows, dependence: float | None = None, share: float = 0.0) -> np.ndarray:
    """The rows' log10 NFA at ``dependence`` (default: the product's) with
    ``10 ** share`` of the counted poses taken as independent tries, never
    fewer than one (``share`` 0: every pose, as the product counts)."""
    d = N.DEPENDENCE if dependence is None else dependence
    raw = np.array([r["log10_nfa"][str(float(d))] for r in rows])
    tests = np.array([r["log_tests"] for r in rows])
    return np.maximum(raw - tests + np.maximum(tests + share, 0.0), N.MIN_LOG10_NFA)


def counts(data, select, dependence=None, share=0.0) -> tuple[int, dict]:
    """(searches, {e: detections per search with NFA <= e}) over the selected group."""
    n = sum(1 for s in data["searches"] if select(s[0], s[1], s[2]))
    rows = [r for r in data["rows"] if select(r["group"], r["split"], r["pattern"])]
    lg = log_nfa(rows, dependence, share)
    return n, {e: float(np.sum(lg <= math.log10(e))) / max(n, 1) for e in PROMISED}


def in_band(obs: float, e: float) -> bool:
    return 0.5 * e <= obs <= 2 * e


def fit(data, kinds=("marker, whole image",)) -> tuple[float, float]:
    """(DEPENDENCE, share) of the grid that puts the most of the
    tune part's (group, e) of the searches of ``kinds`` within the band
    0.5e-2e, ties broken by the sum of squared log ratios of observed to
    promised (pool photos left out; they are in the test part anyway). By
    default the whole-image marker searches: what the calibration was first
    asked of."""
    tune = [c for c in cells(data, natural_only=True) if c[0] == "tune" and c[2] in kinds]
    best = None
    for d in DEPENDENCES:
        for sh in SHARES:
            inside, loss = 0, 0.0
            for cell in tune:
                _, obs = counts(data, in_cell(cell), d, sh)
                for e in PROMISED:
                    inside += in_band(obs[e], e)
                    loss += math.log(max(obs[e], 1e-4) / e) ** 2
            key = (-inside, loss)
            if best is None or key < best[0]:
                best = (key, d, float(sh))
    return best[1], best[2]


def cells(data, natural_only=False) -> list:
    """The (split, group, kind) of the searches, tune first."""
    out = sorted({(s[1], s[0], kind(s[2])) for s in data["searches"]
                  if not (natural_only and s[0].startswith("pool"))},
                 key=lambda t: (t[0] != "tune", t[2] != "marker, whole image", t[2], t[1]))
    return out


def in_cell(cell):
    sp, g, k = cell
    return lambda gg, ss, pp: (ss, gg, kind(pp)) == (sp, g, k)


def by_pattern(data) -> str:
    """Observed detections per search at each promised e, by search and split
    (the seabed photos and the scenes cut from them, pool photos apart)."""
    lines = ["| split | search | searches | " + " | ".join(f"e = {e:g}" for e in PROMISED) + " |",
             "|---|---|---|" + "---|" * len(PROMISED)]
    names = [n for n in NATURAL_SEARCHES if any(s[2] == n for s in data["searches"])]
    for sp in ("tune", "test"):
        for name in names:
            sel = (lambda g, s, p, sp=sp, name=name: s == sp and p == name
                   and g in ("seabed photos", f"sim on {sp} photos"))
            n, obs = counts(data, sel)
            if n:
                lines.append(f"| {sp} | {name} | {n} | "
                             + " | ".join(f"{obs[e]:.3f}" for e in PROMISED) + " |")
    return "\n".join(lines)


def at_defaults(data, calibrated) -> str:
    """False alarms per search at the defaults (max_nfa=1 and min_score 0.5)
    with the model in use and with the ``calibrated`` one, against min_score
    0.5 alone (before the NFA), by group and kind of search. (Counted on the
    detections of the unfiltered search: the same candidates a default search
    ranks, filtered afterwards.)"""
    lines = ["| split | images | search | searches | min_score 0.5 alone (no NFA) | defaults "
             f"(max_nfa=1 and min_score 0.5) | defaults with the calibrated model "
             f"(DEPENDENCE {calibrated[0]:g}, share of tries 10^{calibrated[1]:g}) | "
             "max_nfa=1 alone | max_nfa=1 alone, calibrated model |",
             "|---|---|---|---|---|---|---|---|---|"]
    for cell in cells(data):
        sel = in_cell(cell)
        n = sum(1 for s in data["searches"] if sel(*s))
        rows = [r for r in data["rows"] if sel(r["group"], r["split"], r["pattern"])]
        lg, cal = log_nfa(rows), log_nfa(rows, *calibrated)
        sc = np.array([r["score"] for r in rows])
        alone = float(np.sum(sc >= 0.5)) / n
        now = float(np.sum((sc >= 0.5) & (lg <= 0.0))) / n
        then = float(np.sum((sc >= 0.5) & (cal <= 0.0))) / n
        sp, g, k = cell
        lines.append(f"| {sp} | {g} | {k} | {n} | {alone:.3f} | {now:.3f} | {then:.3f} | "
                     f"{float(np.sum(lg <= 0.0)) / n:.3f} | {float(np.sum(cal <= 0.0)) / n:.3f} |")
    return "\n".join(lines)


def report(data, model=None) -> str:
    """Detections per search at each promised e, by group and kind of search
    (``model``: (DEPENDENCE, share); default: the product's)."""
    model = model or (None, 0.0)
    lines = ["| split | images | search | searches | log10 poses counted | " + " | ".join(
        f"observed at e = {e:g} (band {0.5 * e:g}-{2 * e:g})" for e in PROMISED) + " |",
             "|---|---|---|---|---|" + "---|" * len(PROMISED)]
    for cell in cells(data):
        sel = in_cell(cell)
        n, obs = counts(data, sel, *model)
        tests = [r["log_tests"] for r in data["rows"] if sel(r["group"], r["split"], r["pattern"])]
        span = f"{min(tests):.1f}-{max(tests):.1f}" if tests else "-"
        out = [f"{obs[e]:.3f}" + ("" if in_band(obs[e], e) else " (out)") for e in PROMISED]
        sp, g, k = cell
        lines.append(f"| {sp} | {g} | {k} | {n} | {span} | " + " | ".join(out) + " |")
    return "\n".join(lines)


def plot(data, path: Path, calibrated) -> None:
    """Observed against promised, with the model in use and with the
    calibrated one: whole-image marker searches by group and part; the other
    kinds of search on the natural test images, pooled."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    es = np.logspace(-3, 1, 25)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), sharey=True)
    curves = [(f"{g} ({sp})", in_cell((sp, g, k)), "o-" if sp == "test" else "s--")
              for sp, g, k in cells(data) if k == "marker, whole image"]
    for k in OTHER_SEARCHES:
        curves.append((f"{k} (test, natural images)",
                       lambda g, s, p, k=k: s == "test" and p == k and not g.startswith("pool"),
                       "^:"))
    models = ((None, 0.0), calibrated)
    titles = (f"in use: DEPENDENCE {N.DEPENDENCE:g}, every pose a try (a bound)",
              f"calibrated, not adopted: DEPENDENCE {calibrated[0]:g}, "
              f"share 10^{calibrated[1]:g}")
    for ax, model, title in zip(axes, models, titles):
        lg_all = log_nfa(data["rows"], *model)
        for label, sel, style in curves:
            n = sum(1 for s in data["searches"] if sel(*s))
            if not n:
                continue
            mask = np.array([sel(r["group"], r["split"], r["pattern"]) for r in data["rows"]],
                            bool)
            obs = [np.sum(lg_all[mask] <= math.log10(e)) / n for e in es]
            ax.loglog(es, np.maximum(obs, 1e-4), style, ms=3, label=f"{label}, {n} searches")
        ax.fill_between(es, 0.5 * es, 2 * es, color="0.85", label="band 0.5e-2e")
        ax.loglog(es, es, "k-", lw=1, label="promised")
        ax.set_xlabel("max_nfa = e (promised false alarms per search)")
        ax.set_ylim(1e-4, 20)
        ax.set_title(title, fontsize=9)
    axes[0].set_ylabel("observed detections per search")
    axes[1].legend(fontsize=6, loc="lower right")
    fig.suptitle("NFA calibration on object-free photos")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a few images only (smoke test)")
    ap.add_argument("--fit", action="store_true", help="fit DEPENDENCE and a share of tries on the tune part (a calibrated model)")
    ap.add_argument("--cache", type=Path, help="reuse (or write) the collected evidence here")
    ap.add_argument("--write", action="store_true", help="write docs/nfa_calibration.md and the plot")
    ap.add_argument("--pool-split", action="store_true",
                    help="only the pool photos' false alarms at the defaults, on labelled props "
                         "and elsewhere (a table, ~3 min)")
    a = ap.parse_args(argv)
    if a.pool_split:
        if shared_data_dir() is None:
            print("bench_nfa: ../shared/data not found", file=sys.stderr)
            return 2
        print(f"Command: `{command()}`  \nDate: {time.strftime('%Y-%m-%d')}  \n"
              f"Machine: {machine()}\n\n{pool_split(a.quick)}")
        return 0
    if a.cache and a.cache.exists():
        data = json.loads(a.cache.read_text())
        data["searches"] = [tuple(s) for s in data["searches"]]
    else:
        data = collect(a.quick)
        if a.cache:
            a.cache.write_text(json.dumps(data))
    calibrated, fitted = CALIBRATED, ""
    if a.fit:
        calibrated = fit(data)
        fitted = (f"Fitted on the tune part's whole-image marker searches: DEPENDENCE "
                  f"{calibrated[0]:g}, share of tries 10^{calibrated[1]:g}.  \n")
        print(fitted)
    share = data["judge_s"] / max(data["search_s"], 1e-9)
    cmd = command() if a.cache is None else command().replace(str(a.cache), "EVIDENCE.json")
    cal = f"DEPENDENCE {calibrated[0]:g}, share of tries 10^{calibrated[1]:g}"
    text = (f"Command: `{cmd}` (the evidence is collected afresh when the cache file "
            f"is absent)  \nDate: {time.strftime('%Y-%m-%d')}  \nMachine: {machine()}  \n"
            f"{fitted}In use: DEPENDENCE = {N.DEPENDENCE:g}, every counted pose a try, "
            f"CELL = {N.CELL} px. Split: see "
            "the docstring of bench/bench_nfa.py and docs/nfa.md.\n\n"
            f"Detections per search with NFA <= e (min_score 0, no other filter), the model "
            f"in use:\n\n{report(data)}\n\n"
            f"The same with the calibrated model ({cal}; not adopted, docs/nfa.md):\n\n"
            f"{report(data, calibrated)}\n\n"
            f"By search (seabed photos and the scenes cut from them), the model in use:\n\n"
            f"{by_pattern(data)}\n\n"
            f"False alarms per search at the defaults:\n\n{at_defaults(data, calibrated)}\n\n"
            f"Time spent on the NFA (background model and evidence of the candidates): "
            f"{100 * share:.1f} % of the search time ({data['search_s']:.0f} s of searches).\n")
    print(text)
    if a.write and not a.quick:
        plot(data, ROOT / "docs" / "images" / "nfa_calibration.png", calibrated)
        (ROOT / "docs" / "nfa_calibration.md").write_text(
            "# NFA calibration (generated by bench/bench_nfa.py)\n\n" + text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
