"""Time of the pictures of one 4K detection (issue 17: <= 0.5 s for all three).

``seahough detect PATTERN IMAGE --out DIR`` draws three pictures per image
with :mod:`seahough.viz`: the overlay (:func:`~seahough.viz.plot_detections`),
the accumulator's planes (:func:`~seahough.viz.plot_accumulator`) and what
the detector saw (:func:`~seahough.viz.plot_edges`), each written as a PNG.
This times them, PNG written included, on one 4K photo with one detection:

- steady state: each picture drawn and written ``--repeat`` times in this
  process after a first call; the median CPU time of the process and the
  median wall time (larger when the machine is shared);
- the first call in a fresh process (wall): ``from seahough import viz``
  (matplotlib's import) and each picture's first call (fonts loaded, first
  text laid out), the search done before and not counted.

The photo: the largest real frame of ../shared/data (the DTU seabed pair,
1920x1080) resized to 3840x2160 (and 4000x3000) with the simulator's board
marker pasted in at a known pose, in moderate water; the procedural seabed
when the shared data is absent. Single thread (bench/_common.py).

    python bench/bench_pictures.py              # prints the table (~1 min)
    python bench/bench_pictures.py --write      # and puts it in docs/speed.md ("Pictures")
    python bench/bench_pictures.py --quick      # smoke test: 3840x2160, 2 repeats
    python bench/bench_pictures.py --pictures DIR   # keep the pictures to look at
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _common import command, machine  # noqa: E402  (single-thread setup first)

import cv2  # noqa: E402

from seahough import sim as S  # noqa: E402
from seahough._data import shared_data_dir  # noqa: E402

SPEED_MD = HERE.parent / "docs" / "speed.md"
SECTION = "## Pictures"
TARGET_S = 0.5
PICTURES = ("overlay", "accumulator", "edges")
SHAPES = ((2160, 3840), (3000, 4000))
MARKER_SIZE = 120           # px of the marker's pattern; pasted at scale 2.5-3
#: The same benchmark run on the pictures' code before issue 17 part 4 (same
#: machine, 2026-12-01, load average 4.7 on 2 cores: CPU times are the ones
#: to compare): steady-state CPU ms of overlay, accumulator, edges, and the
#: whole first call in a fresh process (wall ms).
BEFORE = {"3840x2160": (510, 166, 179, 1895), "4000x3000": (701, 181, 205, 2172)}


def photo_source() -> tuple[object, str]:
    """The background of the scenes and a line saying what it is."""
    root = shared_data_dir()
    if root is not None:
        p = root / "sequences" / "dtu_seabed_pair" / "scene1.png"
        if p.is_file():
            return str(p), (f"a real photo (`../shared/data/{p.relative_to(root)}`, "
                            "1920x1080, DTU seabed) resized")
    return "procedural", "the procedural seabed (../shared/data absent)"


def make_case(shape, source, folder: Path) -> dict:
    """A 4K scene with the board marker in it: the image and the pattern
    written to ``folder`` (for the fresh process), and the search's settings."""
    scene, pattern, truth = S.marker_scene("board", shape, scale_range=(2.5, 3.0),
                                           angle_range=(0, 360), occlusion=0.0,
                                           size=MARKER_SIZE, source=source, seed=7)
    img, mask = S.marker("board", MARKER_SIZE)
    name = f"{shape[1]}x{shape[0]}"
    cv2.imwrite(str(folder / f"{name}.png"), scene, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    cv2.imwrite(str(folder / "board.png"), img)
    cv2.imwrite(str(folder / "board_mask.png"), mask.astype("uint8") * 255)
    return {"name": name, "image": str(folder / f"{name}.png"), "scene": scene,
            "pattern": str(folder / "board.png"), "mask": str(folder / "board_mask.png"),
            "truth": (truth.x, truth.y)}


# The code run in this process (steady state) and in a fresh one (first call).
_SETUP = """
import cv2, numpy as np, seahough
cv2.setNumThreads(1)
img = cv2.imread({image!r}, cv2.IMREAD_COLOR)
pattern = seahough.Pattern.from_image(cv2.imread({pattern!r}, cv2.IMREAD_GRAYSCALE),
                                      mask=cv2.imread({mask!r}, cv2.IMREAD_GRAYSCALE) > 0)
res = seahough.Detector(pattern, scale_range=(2, 3.5), max_results=1).search(img)
"""
_FIRST = """
import json, time
t0 = time.perf_counter()
from seahough import viz
t1 = time.perf_counter()
viz.plot_detections(img, res.detections, {out!r} + "/overlay.png", pattern=pattern,
                    title="4K: 1 detection")
t2 = time.perf_counter()
viz.plot_accumulator(res.planes, res.detections, {out!r} + "/accumulator.png",
                     title="4K: accumulator", note=res.note)
t3 = time.perf_counter()
viz.plot_edges(img, res.features, {out!r} + "/edges.png", title="4K: what the detector sees")
t4 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "overlay": t2 - t1, "accumulator": t3 - t2,
                  "edges": t4 - t3, "found": len(res.detections)}}))
"""


def first_call(case: dict, out: str) -> dict:
    """Seconds of the first calls in a fresh Python process."""
    code = _SETUP.format(**case) + _FIRST.format(out=out)
    env = dict(os.environ, MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def steady(case: dict, out: str, repeat: int) -> tuple[dict, dict, int]:
    """Median CPU and wall seconds of each picture over ``repeat`` calls
    after a first one, and the number of detections."""
    ns: dict = {}
    exec(_SETUP.format(**case), ns)
    from seahough import viz

    img, res, pattern = ns["img"], ns["res"], ns["pattern"]
    calls = {
        "overlay": lambda: viz.plot_detections(img, res.detections, out + "/overlay.png",
                                               pattern=pattern, title="4K: 1 detection"),
        "accumulator": lambda: viz.plot_accumulator(res.planes, res.detections,
                                                    out + "/accumulator.png",
                                                    title="4K: accumulator", note=res.note),
        "edges": lambda: viz.plot_edges(img, res.features, out + "/edges.png",
                                        title="4K: what the detector sees"),
    }
    cpu, wall = {}, {}
    for name, call in calls.items():
        call()
        c, w = [], []
        for _ in range(repeat):
            t0, p0 = time.perf_counter(), time.process_time()
            call()
            c.append(time.process_time() - p0)
            w.append(time.perf_counter() - t0)
        cpu[name], wall[name] = statistics.median(c), statistics.median(w)
    return cpu, wall, len(res.detections)


def ms(s: float) -> str:
    return f"{1000 * s:.0f}"


def report(rows: list[dict], source_line: str, repeat: int, load: tuple) -> str:
    shared = max(load) > 1.2
    lines = [
        SECTION,
        "",
        f"Command: `{command()}`  ",
        f"Machine: {machine()}  ",
        f"Date: {time.strftime('%Y-%m-%d')}; load average (1 min) {load[0]:.1f} at the start, "
        f"{load[1]:.1f} at the end"
        + (" (the machine was shared: wall times are inflated, CPU times less so)"
           if shared else ""),
        "",
        f"The three pictures `seahough detect PATTERN IMAGE --out DIR` writes for one photo, "
        f"each PNG written included; the photo is {source_line} with the board marker "
        f"pasted in, one detection. Steady state: median of {repeat} calls after a first "
        "one, CPU time of the single-threaded process (wall beside it: larger when the "
        "machine is shared). First call: a fresh Python process, wall time, after the "
        "search; its total includes `from seahough import viz` (matplotlib's import).",
        "",
        "| photo | picture | steady ms (CPU) | steady ms (wall) | first call in a fresh "
        "process, ms (wall) |",
        "|---|---|---:|---:|---:|",
    ]
    for r in rows:
        for name in PICTURES:
            lines.append(f"| {r['name']} | {name} | {ms(r['cpu'][name])} | "
                         f"{ms(r['wall'][name])} | {ms(r['first'][name])} |")
        lines.append(f"| {r['name']} | import of `seahough.viz` | | | "
                     f"{ms(r['first']['import'])} |")
        tc, tw = sum(r["cpu"].values()), sum(r["wall"].values())
        tf = sum(r["first"][k] for k in (*PICTURES, "import"))
        lines.append(f"| {r['name']} | **all three** | **{ms(tc)}** | **{ms(tw)}** | "
                     f"**{ms(tf)}** |")
    verdicts = []
    for r in rows:
        tc, tw = sum(r["cpu"].values()), sum(r["wall"].values())
        verdict = ("met" if max(tc, tw) <= TARGET_S else
                   "met in CPU time" if tc <= TARGET_S else "not met")
        verdicts.append(f"{r['name']} {ms(tc)} ms CPU, {ms(tw)} ms wall: {verdict}")
    lines += ["", f"Target (issue 17): the three pictures of one 4K detection in <= "
              f"{1000 * TARGET_S:.0f} ms (steady state): " + "; ".join(verdicts) + "."]
    before = [r for r in rows if r["name"] in BEFORE]
    if before:
        lines += ["", "Before (the same benchmark on the earlier pictures' code, same machine, "
                  "2026-12-01): " + "; ".join(
                      f"{r['name']}: overlay {BEFORE[r['name']][0]}, accumulator "
                      f"{BEFORE[r['name']][1]}, edges {BEFORE[r['name']][2]} ms CPU (all three "
                      f"{sum(BEFORE[r['name']][:3])} ms), first call in a fresh process "
                      f"{BEFORE[r['name']][3]} ms" for r in before) + ".",
                  "",
                  "What changed (`seahough/viz/_figure.py`): the photo is shrunk to the size "
                  "it is drawn at (900 px wide) by OpenCV's area average before matplotlib "
                  "sees it, instead of being resampled by matplotlib, which first made a "
                  "masked RGBA copy of the whole 4K photo (about 0.35 s); the PNGs are "
                  "encoded by OpenCV as RGB at zlib level 1 with libpng's \"up\" row filter "
                  "instead of by Pillow as RGBA at level 6 (the overlay of a photo: 0.015 s "
                  "instead of 0.17 s, the file 3 % larger; a flat synthetic scene's up to "
                  "1.7 times larger). A large pattern image is shrunk to its inset the same "
                  "way. "
                  "What is left is matplotlib's own cost of axes, ticks and text (about "
                  "0.1 s per picture, whatever the photo's size); pictures of images "
                  "smaller than drawn are pixel for pixel what they were."]
    return "\n".join(lines)


def write_section(text: str, path: Path = SPEED_MD) -> None:
    """Put ``text`` (a ``## Pictures`` section) in ``path``: in place of the
    section there, else at the end; the rest of the file as it is now."""
    doc = path.read_text() if path.is_file() else ""
    m = re.search(rf"^{re.escape(SECTION)}[ \t]*$", doc, flags=re.M)
    if m is None:
        doc = doc.rstrip("\n") + ("\n\n" if doc.strip() else "") + text + "\n"
    else:
        nxt = re.search(r"^## ", doc[m.end():], flags=re.M)
        end = m.end() + nxt.start() if nxt else len(doc)
        tail = doc[end:]
        doc = doc[:m.start()] + text + ("\n\n" + tail if tail else "\n")
    path.write_text(doc)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=7, help="steady-state calls per picture")
    ap.add_argument("--quick", action="store_true", help="3840x2160 only, 2 repeats")
    ap.add_argument("--pictures", metavar="DIR",
                    help="leave the scenes and pictures in DIR/<W>x<H>/ (default: removed)")
    ap.add_argument("--write", action="store_true",
                    help=f"put the table in {SPEED_MD.relative_to(HERE.parent)} ({SECTION!r})")
    args = ap.parse_args(argv)
    repeat = 2 if args.quick else args.repeat
    shapes = SHAPES[:1] if args.quick else SHAPES
    source, source_line = photo_source()
    rows = []
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        for shape in shapes:
            folder = Path(args.pictures or tmp) / f"{shape[1]}x{shape[0]}"
            folder.mkdir(parents=True, exist_ok=True)
            case = make_case(shape, source, folder)
            first = first_call(case, str(folder))
            cpu, wall, found = steady(case, str(folder), repeat)
            if found != 1 or first["found"] != 1:
                print(f"warning: {case['name']}: {found} detection(s), not 1", file=sys.stderr)
            rows.append({"name": case["name"], "cpu": cpu, "wall": wall, "first": first})
            print(f"{case['name']}: steady {ms(sum(cpu.values()))} ms CPU, first call "
                  f"{ms(sum(first[k] for k in (*PICTURES, 'import')))} ms", file=sys.stderr)
    text = report(rows, source_line, repeat, (load0, os.getloadavg()[0]))
    print(text)
    if args.write:
        write_section(text)
        print(f"wrote the {SECTION!r} section of {SPEED_MD}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
