"""What the unmatched detections of bench_robosub.py lie on: pictures to look at.

A detection that matches no labelled box counts as false in
bench/bench_robosub.py, wherever it lies; the labels (by others) leave some
objects out. This script draws, for one task and one row of that benchmark
(default: buoys, seahough at its defaults, test part), a crop around each
unmatched detection: the detection in red (a disc, or a line through the
crop), the labelled boxes in green, the tile's number at its top left; 16
tiles a sheet. ``items.json`` lists each tile's photo, position, size,
score and NFA, so that a person can say what each one lies on
(docs/robosub_labels.md is such a look).

It reads the detections that bench_robosub.py kept in its cache file (run
it first with ``--cache FILE``); nothing is searched here.

    python bench/bench_robosub.py --write --cache rs.cache
    python bench/robosub_unmatched.py --cache rs.cache --out DIR [--task buoy]
"""

from __future__ import annotations

import argparse
import json
import pickle
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_robosub as br  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from seahough._data import shared_data_dir  # noqa: E402

TILE = 160
PER_SHEET = 16


def load_runs(path: Path) -> dict:
    """bench_robosub.py's cache (pickled as its ``__main__``)."""
    main = sys.modules["__main__"]
    for name in ("Det", "Box"):
        if not hasattr(main, name):
            setattr(main, name, getattr(br, name))
    with open(path, "rb") as f:
        return pickle.load(f)


def unmatched(task: str, runs: dict, part: str = "test") -> list:
    """(photo, detection) of each detection of the defaults row that matches
    no labelled box of the task, in photo order."""
    photos = br.load_photos(shared_data_dir().joinpath(*br.SUBDIR))
    got = runs.get(br.key_of(task, "seahough", {}))
    if got is None:
        sys.exit(f"the cache holds no run of seahough's defaults for {task!r}")
    out = []
    for p in photos:
        objs = br.truth(p, task)
        if p.part != part or objs is None or p.number not in got:
            continue
        dets, _ = got[p.number]
        for d, hit in zip(dets, br.assign(dets, objs, br.COST[task], p.shape)):
            if not hit:
                out.append((p, d))
    return out


def tile(p, d, number: int) -> np.ndarray:
    """A crop around one detection, drawn as the module docstring says."""
    img = cv2.imread(str(p.path))
    half = max(1.5 * d.size, 24.0) if d.size else 48.0
    k = TILE / (2.0 * half)
    m = cv2.getAffineTransform(np.float32([[d.x - half, d.y - half], [d.x + half, d.y - half],
                                           [d.x - half, d.y + half]]),
                               np.float32([[0, 0], [TILE, 0], [0, TILE]]))
    out = cv2.warpAffine(img, m, (TILE, TILE), flags=cv2.INTER_CUBIC,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=(40, 40, 40))
    for b in p.boxes:
        a = (int((b.x0 - d.x + half) * k), int((b.y0 - d.y + half) * k))
        z = (int((b.x1 - d.x + half) * k), int((b.y1 - d.y + half) * k))
        cv2.rectangle(out, a, z, (0, 255, 0), 1)
    c = TILE // 2
    if d.size:
        cv2.circle(out, (c, c), max(int(0.5 * d.size * k), 1), (0, 0, 255), 1)
    else:
        t = np.radians(d.angle)
        dx, dy = np.cos(t) * TILE, -np.sin(t) * TILE
        cv2.line(out, (int(c - dx), int(c - dy)), (int(c + dx), int(c + dy)), (0, 0, 255), 1)
    cv2.putText(out, str(number), (4, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 2)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", required=True, type=Path, help="bench_robosub.py's --cache file")
    ap.add_argument("--out", required=True, type=Path, help="folder for the sheets")
    ap.add_argument("--task", default="buoy", choices=("buoy", "post"))
    a = ap.parse_args()
    items = unmatched(a.task, load_runs(a.cache))
    a.out.mkdir(parents=True, exist_ok=True)
    tiles = [tile(p, d, i) for i, (p, d) in enumerate(items)]
    blank = np.zeros((TILE, TILE, 3), np.uint8)
    for s in range(0, len(tiles), PER_SHEET):
        sheet = tiles[s:s + PER_SHEET] + [blank] * (PER_SHEET - len(tiles[s:s + PER_SHEET]))
        rows = [np.hstack(sheet[r:r + 4]) for r in range(0, PER_SHEET, 4)]
        cv2.imwrite(str(a.out / f"{a.task}_unmatched_{s // PER_SHEET}.png"), np.vstack(rows))
    meta = [dict(tile=i, photo=p.number, x=round(d.x, 1), y=round(d.y, 1),
                 diameter=round(d.size, 1) if d.size else None,
                 angle=None if d.size else round(d.angle, 1),
                 score=round(d.strength, 3), nfa=float(d.nfa)) for i, (p, d) in enumerate(items)]
    (a.out / "items.json").write_text(json.dumps(meta, indent=1))
    print(f"{len(items)} unmatched {a.task} detections of seahough's defaults (test part): "
          f"{(len(tiles) + PER_SHEET - 1) // PER_SHEET} sheets in {a.out}")


if __name__ == "__main__":
    main()
