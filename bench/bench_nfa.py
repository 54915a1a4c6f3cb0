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

The one constant fitted on the tune part is :data:`seahough.core.nfa.DEPENDENCE`
(with ``--fit``: the smallest value at which the tune part never shows more
than twice the promised false alarms); the test part is reported as
measured, by group and by pattern.

    python bench/bench_nfa.py --write         # ~10 min: collect, report, plot
    python bench/bench_nfa.py --quick         # smoke test (~20 s)
    python bench/bench_nfa.py --fit           # also the fit of DEPENDENCE on the tune part
"""

from __future__ import annotations

import argparse
import json
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
POOL_PATTERNS = ("cross", "ring")


def patterns() -> dict:
    out = {}
    for name in ("L", "cross", "board"):
        img, mask = S.marker(name, 120)
        out[name] = seahough.Pattern.from_image(img, mask=mask)
    out["ring"] = seahough.Pattern.circle(40, 25)
    out["chevron"] = seahough.Pattern.polygon([(0, 0), (60, 40), (120, 0), (120, 25), (60, 65),
                                               (0, 25)])
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
                      MARKER_PATTERNS))
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
            items.append(("seabed photos", split, p.name, lambda p=p: real(p), MARKER_PATTERNS))
        for seed in range(n_sim):
            water = S.water.PRESETS[seed % 3]
            src = photos[seed % len(photos)]
            items.append((f"sim on {split} photos", split, f"seed {seed} {water}",
                          lambda s=seed, w=water, src=src: [S.negative_scene(
                              (480, 640), water=w, seed=s, source=src)], MARKER_PATTERNS))
    pool = sorted((base / "objects" / "robosub_transdec" / "images").glob("*.jpg"),
                  key=lambda p: int(re.findall(r"\d+", p.name)[0]))
    pool = [p for p in pool if int(re.findall(r"\d+", p.name)[0]) >= 100]  # (0-99: renders)
    for p in pool[:2] if quick else pool:
        items.append(("pool photos (RoboSub)", "test", p.name, lambda p=p: [cv2.imread(str(p))],
                      POOL_PATTERNS))
    return items


#: The DEPENDENCE values every detection's NFA is also computed at (for --fit).
DEPENDENCES = (1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0, 6.0, 8.0)


def collect(quick: bool) -> dict:
    """Every detection's evidence on every object-free image, with its NFA
    at each of :data:`DEPENDENCES`."""
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
            for d in DEPENDENCES:
                N.DEPENDENCE = d
                judge(ctx, c)
                by[d] = c.evidence.log10_nfa
        finally:
            N.DEPENDENCE = used
        judge(ctx, c)
        c.by_dependence = by

    ranking.judge = timed_judge
    t_search = 0.0
    items = images(quick)
    t0 = time.time()
    try:
        for i, (group, split, label, load, names) in enumerate(items):
            for img in load():
                for name in names:
                    det = seahough.Detector(pats[name], min_score=0.0, max_nfa=math.inf)
                    j0 = judged[0]
                    t = time.perf_counter()
                    res = det.search(img)
                    dt = time.perf_counter() - t
                    # (the judge ran 2 + len(DEPENDENCES) times: its time counts once)
                    t_search += dt - (judged[0] - j0) * (1 + len(DEPENDENCES))
                    searches.append((group, split, name))
                    judged_c = [c for c in res.candidates if c.evidence is not None]
                    for d in res.detections:
                        c = next(c for c in judged_c if c.full.score == d.score
                                 and c.evidence.nfa == d.nfa)
                        e = c.evidence
                        rows.append({"group": group, "split": split, "pattern": name,
                                     "label": label, "score": d.score,
                                     "confidence": d.confidence, "n": e.n, "k": e.k, "p": e.p,
                                     "log10_nfa": {str(float(k)): v
                                                   for k, v in c.by_dependence.items()}})
            if i % 50 == 0:
                print(f"{i}/{len(items)} images, {time.time() - t0:.0f} s", flush=True)
    finally:
        ranking.judge = judge
    return {"rows": rows, "searches": searches, "judge_s": judged[0], "search_s": t_search}


def log_nfa(rows, dependence: float) -> np.ndarray:
    return np.array([r["log10_nfa"][str(float(dependence))] for r in rows])


def counts(data, dependence: float, select) -> tuple[int, dict]:
    """(searches, {e: detections per search with NFA <= e}) over the selected group."""
    n = sum(1 for s in data["searches"] if select(s[0], s[1], s[2]))
    rows = [r for r in data["rows"] if select(r["group"], r["split"], r["pattern"])]
    lg = log_nfa(rows, dependence)
    return n, {e: float(np.sum(lg <= math.log10(e))) / max(n, 1) for e in PROMISED}


def fit(data) -> float:
    """The smallest DEPENDENCE (of :data:`DEPENDENCES`) at which the tune part
    never shows more than twice the promised false alarms, at every promised
    e: the NFA as a bound that holds (a-contrario's reading of it), as
    tight as the tune part allows."""
    for c in DEPENDENCES:
        n, obs = counts(data, c, lambda g, s, p: s == "tune")
        if all(obs[e] <= 2 * e for e in PROMISED):
            return float(c)
    return math.inf


def by_pattern(data, dependence: float) -> str:
    """Observed detections per search at each promised e, by pattern and split
    (the seabed photos and the scenes cut from them, pool photos apart)."""
    lines = ["| split | pattern | searches | " + " | ".join(f"e = {e:g}" for e in PROMISED) + " |",
             "|---|---|---|" + "---|" * len(PROMISED)]
    names = sorted({s[2] for s in data["searches"]})
    for sp in ("tune", "test"):
        for name in names:
            sel = (lambda g, s, p, sp=sp, name=name: s == sp and p == name
                   and not g.startswith("pool"))
            n, obs = counts(data, dependence, sel)
            if n:
                lines.append(f"| {sp} | {name} | {n} | "
                             + " | ".join(f"{obs[e]:.3f}" for e in PROMISED) + " |")
    return "\n".join(lines)


def at_defaults(data, dependence: float) -> str:
    """False alarms per search at the defaults (max_nfa=1 and min_score 0.5)
    against min_score 0.5 alone (before the NFA), by group. (Counted on the
    detections of the unfiltered search: the same candidates a default search
    ranks, filtered afterwards.)"""
    lines = ["| split | images | searches | min_score 0.5 alone (before) | max_nfa=1 and "
             "min_score 0.5 (defaults) | max_nfa=1 alone |", "|---|---|---|---|---|---|"]
    groups = sorted({(s[0], s[1]) for s in data["searches"]}, key=lambda t: (t[1] != "tune", t[0]))
    for g, sp in groups:
        n = sum(1 for s in data["searches"] if s[:2] == (g, sp))
        rows = [r for r in data["rows"] if (r["group"], r["split"]) == (g, sp)]
        lg = log_nfa(rows, dependence)
        sc = np.array([r["score"] for r in rows])
        before = float(np.sum(sc >= 0.5)) / n
        after = float(np.sum((sc >= 0.5) & (lg <= 0.0))) / n
        alone = float(np.sum(lg <= 0.0)) / n
        lines.append(f"| {sp} | {g} | {n} | {before:.3f} | {after:.3f} | {alone:.3f} |")
    return "\n".join(lines)


def report(data, quick: bool) -> str:
    c = N.DEPENDENCE
    groups = sorted({(s[0], s[1]) for s in data["searches"]}, key=lambda t: (t[1] != "tune", t[0]))
    lines = ["| split | images | patterns | searches | " + " | ".join(
        f"observed at e = {e:g} (band {0.5 * e:g}-{2 * e:g})" for e in PROMISED) + " |",
             "|---|---|---|---|" + "---|" * len(PROMISED)]
    pooled = {}
    for g, sp in groups:
        names = sorted({s[2] for s in data["searches"] if s[:2] == (g, sp)})
        n, obs = counts(data, c, lambda gg, ss, pp, g=g, sp=sp: (gg, ss) == (g, sp))
        cells = [f"{obs[e]:.3f}" + ("" if 0.5 * e <= obs[e] <= 2 * e else " (out)")
                 for e in PROMISED]
        lines.append(f"| {sp} | {g} | {', '.join(names)} | {n} | " + " | ".join(cells) + " |")
        pooled[(g, sp)] = obs
    return "\n".join(lines), pooled


def plot(data, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    es = np.logspace(-3, 1, 25)
    fig, ax = plt.subplots(figsize=(6, 5))
    groups = sorted({(s[0], s[1]) for s in data["searches"]})
    lg_all = log_nfa(data["rows"], N.DEPENDENCE)
    for g, sp in groups:
        n = sum(1 for s in data["searches"] if s[:2] == (g, sp))
        sel = np.array([(r["group"], r["split"]) == (g, sp) for r in data["rows"]], bool)
        obs = [np.sum(lg_all[sel] <= math.log10(e)) / n for e in es]
        ax.loglog(es, np.maximum(obs, 1e-4), "o-" if sp == "test" else "s--", ms=3,
                  label=f"{g} ({sp}, {n} searches)")
    ax.fill_between(es, 0.5 * es, 2 * es, color="0.85", label="band 0.5e-2e")
    ax.loglog(es, es, "k-", lw=1, label="promised")
    ax.set_xlabel("max_nfa = e (promised false alarms per search)")
    ax.set_ylabel("observed detections per search")
    ax.set_ylim(1e-4, 20)
    ax.legend(fontsize=7)
    ax.set_title("NFA calibration on object-free photos")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a few images only (smoke test)")
    ap.add_argument("--fit", action="store_true", help="fit DEPENDENCE on the tune part")
    ap.add_argument("--cache", type=Path, help="reuse (or write) the collected evidence here")
    ap.add_argument("--write", action="store_true", help="write docs/nfa_calibration.md and the plot")
    a = ap.parse_args(argv)
    if a.cache and a.cache.exists():
        data = json.loads(a.cache.read_text())
        data["searches"] = [tuple(s) for s in data["searches"]]
    else:
        data = collect(a.quick)
        if a.cache:
            a.cache.write_text(json.dumps(data))
    fitted = ""
    if a.fit:
        fitted = f"DEPENDENCE fitted on the tune part: {fit(data):g} (in use: {N.DEPENDENCE:g}).  \n"
        print(fitted)
    table, _ = report(data, a.quick)
    share = data["judge_s"] / max(data["search_s"], 1e-9)
    cmd = command() if a.cache is None else command().replace(str(a.cache), "EVIDENCE.json")
    text = (f"Command: `{cmd}` (the evidence is collected afresh when the cache file "
            f"is absent)  \nDate: {time.strftime('%Y-%m-%d')}  \nMachine: {machine()}  \n"
            f"{fitted}DEPENDENCE = {N.DEPENDENCE:g}, CELL = {N.CELL} px. Split: see "
            "the docstring of bench/bench_nfa.py and docs/nfa.md.\n\n"
            f"Detections per search with NFA <= e (min_score 0, no other filter):\n\n{table}\n\n"
            f"By pattern (seabed photos and the scenes cut from them):\n\n"
            f"{by_pattern(data, N.DEPENDENCE)}\n\n"
            f"False alarms per search at the defaults:\n\n{at_defaults(data, N.DEPENDENCE)}\n\n"
            f"Time spent on the NFA (background model and evidence of the candidates): "
            f"{100 * share:.1f} % of the search time ({data['search_s']:.0f} s of searches).\n")
    print(text)
    if a.write and not a.quick:
        plot(data, ROOT / "docs" / "images" / "nfa_calibration.png")
        (ROOT / "docs" / "nfa_calibration.md").write_text(
            "# NFA calibration (generated by bench/bench_nfa.py)\n\n" + text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
