"""RoboSub props in real pools: buoys as discs, gate posts as lines, the gate as an open frame.

Data: ../shared/data/objects/robosub_transdec (390 frames with VOC boxes labelled by
others; frames 1-99 are simulator renders, reported apart). Split by blocks of frame
numbers (frames are numbered in recording order, neighbours are near-duplicates):

- tune part: frames 100-999 and 1401-1469 (every setting below was chosen here);
- test part: frames 1000-1400 and 1470-1499 (reported, never looked at while tuning).

Tasks, and when a detection matches a labelled box (one detection matches at most one
box, detections taken best first, each the free box it fits best; a detection matching
no free box of its task is a false detection, wherever it lies: on a prop labelled for
another task, on a look-alike nobody labelled, or on nothing):

- buoys (``buoy_red``, ``buoy_green``, ``buoy_yellow``) as discs: the disc's centre lies
  inside the box and its diameter is within a factor 1.5 of the box's width (its height
  when the box touches the left or right image border: a buoy cut by the frame);
- gate posts (each ``qual_gate`` box is one post; boxes under 2 px across are left out) as
  lines: the (infinite) line crosses the box's middle third, at one and at two thirds of
  its long side, within the box's width (plus 2 px), and its direction is within 10
  degrees of the box's long axis (or within the box diagonal's angle, when larger: a post
  tilted in its box);
- the whole gate as an open frame (two posts and the bar across their tops): the union of
  the two post boxes of a frame is the gate; a detection matches when the intersection
  over union of its bounding box with the gate's is at least 0.5. Frames with a single
  labelled post (the gate half out of view) are left out of this task.

Methods: seahough with the library's defaults for the pattern (the settings of the
issue: ``circle:16`` at scale 0.3-4, ``line:120,12`` at 60-120 degrees) and with settings
chosen on the tune part; OpenCV HoughCircles (HOUGH_GRADIENT, HOUGH_GRADIENT_ALT),
HoughLinesP with a rule grouping near-vertical segments into posts, GeneralizedHoughGuil
(the gate) and multi-scale matchTemplate (disc, post and gate templates), all in
bench/peers.py. Each method's main parameters are chosen on the tune part by a small
grid with one rule (the page says which). Times: CPU ms per photo, single-threaded
(bench/_common.py), after a warm-up; GeneralizedHoughGuil runs in a worker process and
reports its own time.

    python bench/bench_robosub.py --write          # everything, docs/robosub.md (~20 min)
    python bench/bench_robosub.py --quick          # 8 photos, a 1-setting grid
    python bench/bench_robosub.py --cache FILE     # keep/reuse raw detections between runs
"""

from __future__ import annotations

import argparse
import datetime
import math
import pickle
import sys
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
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

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "robosub.md"
PICTURE = ROOT / "docs" / "images" / "robosub_test.jpg"
SUBDIR = ("objects", "robosub_transdec")

SIM_LAST = 99                                   # frames 1-99: simulator renders
TUNE_BLOCKS = ((100, 999), (1401, 1469))
TEST_BLOCKS = ((1000, 1400), (1470, 1499))
SPLIT = ("tune part = frames 100-999 and 1401-1469; test part = frames 1000-1400 and "
         "1470-1499; frames 1-99 (simulator renders) apart")

SIZE_FACTOR = 1.5       # disc diameter within this factor of the buoy box's size
ANGLE_TOL = 10.0        # line direction within this of the post box's long axis (degrees)
SLACK_PX = 2.0          # a line may cross the middle third this far outside the box's width
MIN_BOX = 2.0           # post boxes narrower than this (px) are left out
GATE_IOU = 0.5          # gate: intersection over union of the bounding boxes
FA_BUDGET = 0.3         # tuning rule and target: false detections per image
TARGET_RECALL = 0.9
TARGET_MS = 30.0
TASKS = ("buoy", "post", "gate")
TASK_TITLE = {"buoy": "Buoys as discs", "post": "Gate posts as lines",
              "gate": "The gate as an open frame"}
PICTURE_FRAME = 1375

# the patterns (pattern pixels) and the search ranges of the tasks
BUOY_R = 16.0
BUOY_SCALE = (0.3, 4.0)                     # the issue's: diameters 9.6-128 px
POST_LEN, POST_W = 120.0, 12.0
POST_ANGLE = (60.0, 120.0)                  # the issue's: within 30 degrees of vertical
POST_SCALE = (0.5, 2.0)                     # seahough's default scale range
GATE_H, GATE_ASPECT, GATE_W = 100.0, 2.1, 6.0   # aspect: median of the tune part's gates
GATE_SCALE = (0.9, 3.0)                     # tune part gates: 112-282 px high
GATE_ANGLE = (-10.0, 10.0)
GUIL_TIMEOUT = 3.0                          # s per GeneralizedHoughGuil search (then: failed)
QUICK_FRAMES = (506, 1442, 1452, 1040, 1375, 1490, 1, 34)


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------
# data
# --------------------------------------------------------------------------

@dataclass(frozen=True)
class Box:
    """A labelled box, pixel coordinates as in the VOC file."""

    name: str
    x0: float
    y0: float
    x1: float
    y1: float

    @property
    def w(self) -> float:
        return self.x1 - self.x0

    @property
    def h(self) -> float:
        return self.y1 - self.y0

    @property
    def cx(self) -> float:
        return 0.5 * (self.x0 + self.x1)

    @property
    def cy(self) -> float:
        return 0.5 * (self.y0 + self.y1)


@dataclass
class Photo:
    number: int
    path: Path
    shape: tuple            # (h, w)
    boxes: list = field(default_factory=list)

    @property
    def part(self) -> str:
        return part_of(self.number)


def part_of(number: int) -> str:
    """"sim", "tune" or "test" (or "" outside every block) for a frame number."""
    if number <= SIM_LAST:
        return "sim"
    for name, blocks in (("tune", TUNE_BLOCKS), ("test", TEST_BLOCKS)):
        if any(a <= number <= b for a, b in blocks):
            return name
    return ""


def parse_voc(text: str) -> list:
    """The boxes of a VOC annotation."""
    out = []
    for obj in ET.fromstring(text).iter("object"):
        bb = obj.find("bndbox")
        v = [float(bb.find(k).text) for k in ("xmin", "ymin", "xmax", "ymax")]
        out.append(Box(obj.find("name").text.strip(), *v))
    return out


def load_photos(folder: Path) -> list:
    photos = []
    for img in sorted((folder / "images").glob("*.jpg"), key=lambda p: int(p.stem)):
        ann = folder / "annotations" / f"{img.stem}.xml"
        boxes = parse_voc(ann.read_text()) if ann.is_file() else []
        shape = cv2.imread(str(img), cv2.IMREAD_GRAYSCALE).shape
        photos.append(Photo(int(img.stem), img, tuple(shape), boxes))
    return photos


class Images:
    """Photos decoded (colour, BGR) when asked for: ``images[number]``."""

    def __init__(self, photos):
        self.paths = {p.number: p.path for p in photos}

    def __getitem__(self, number: int) -> np.ndarray:
        return cv2.imread(str(self.paths[number]), cv2.IMREAD_COLOR)


def truth(photo: Photo, task: str):
    """The labelled objects of a task in a photo; None: the photo is left out."""
    if task == "buoy":
        return [b for b in photo.boxes if b.name.startswith("buoy_")]
    posts = [b for b in photo.boxes if b.name == "qual_gate" and min(b.w, b.h) >= MIN_BOX]
    if task == "post":
        return posts
    gate = [b for b in photo.boxes if b.name == "qual_gate"]
    if len(gate) == 1:
        return None
    if len(gate) == 2:
        return [Box("gate", min(b.x0 for b in gate), min(b.y0 for b in gate),
                    max(b.x1 for b in gate), max(b.y1 for b in gate))]
    return []


# --------------------------------------------------------------------------
# detections and the matching rules
# --------------------------------------------------------------------------

@dataclass(frozen=True)
class Det:
    """One answer of a method: a disc (centre ``x, y``, ``size`` its diameter),
    a line (through ``x, y`` at ``angle`` degrees [0, 180), counter-clockwise
    as displayed) or a frame (``box``: x0, y0, x1, y1); ``strength`` the
    method's own measure (higher is better), ``nfa`` seahough's."""

    x: float
    y: float
    size: float = 0.0
    angle: float = 90.0
    box: tuple = ()
    strength: float = 0.0
    nfa: float = 0.0


def buoy_size(b: Box, shape) -> float:
    """A buoy box's size: its width, or its height when the box touches the
    left or right border (the buoy is cut by the frame)."""
    return b.h if (b.x0 <= 1.0 or b.x1 >= shape[1] - 2.0) else b.w


def disc_cost(d: Det, b: Box, shape):
    """None when the disc does not match the buoy box, else how far its centre
    lies from the box's (smaller is better)."""
    if not (b.x0 <= d.x <= b.x1 and b.y0 <= d.y <= b.y1):
        return None
    s = buoy_size(b, shape)
    if s <= 0 or not (s / SIZE_FACTOR <= d.size <= s * SIZE_FACTOR):
        return None
    return math.hypot(d.x - b.cx, d.y - b.cy)


def angle_diff(a: float, b: float) -> float:
    """Difference of two undirected line directions, degrees in [0, 90]."""
    d = abs(a - b) % 180.0
    return min(d, 180.0 - d)


def line_cross(d: Det, at: float, vertical: bool):
    """Where the line crosses height ``at`` (``vertical``: its x) or the
    column ``at`` (its y); None when it runs parallel to it."""
    t = math.radians(d.angle)
    c, s = math.cos(t), math.sin(t)        # direction (c, -s) in image pixels
    if vertical:
        return None if abs(s) < 1e-9 else d.x + (d.y - at) * c / s
    return None if abs(c) < 1e-9 else d.y - (at - d.x) * s / c


def line_cost(d: Det, b: Box, shape=None):
    """None when the line does not match the post box, else how far it passes
    from the box's centre."""
    vertical = b.h >= b.w
    long_, across = (b.h, b.w) if vertical else (b.w, b.h)
    tol = max(ANGLE_TOL, math.degrees(math.atan2(across, long_)))
    if angle_diff(d.angle, 90.0 if vertical else 0.0) > tol:
        return None
    lo, hi = (b.y0, b.y1) if vertical else (b.x0, b.x1)
    a0, a1 = (b.x0, b.x1) if vertical else (b.y0, b.y1)
    for f in (1.0 / 3.0, 2.0 / 3.0):
        v = line_cross(d, lo + f * (hi - lo), vertical)
        if v is None or not (a0 - SLACK_PX <= v <= a1 + SLACK_PX):
            return None
    mid = line_cross(d, 0.5 * (lo + hi), vertical)
    return abs(mid - 0.5 * (a0 + a1))


def iou(a, b) -> float:
    """Intersection over union of two boxes (x0, y0, x1, y1)."""
    iw = min(a[2], b[2]) - max(a[0], b[0])
    ih = min(a[3], b[3]) - max(a[1], b[1])
    if iw <= 0 or ih <= 0:
        return 0.0
    inter = iw * ih
    return inter / ((a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter)


def frame_cost(d: Det, b: Box, shape=None):
    v = iou(d.box, (b.x0, b.y0, b.x1, b.y1))
    return -v if v >= GATE_IOU else None


COST = {"buoy": disc_cost, "post": line_cost, "gate": frame_cost}


def assign(dets, boxes, cost, shape=None, taken: list | None = None) -> list:
    """For each detection (best first): True when it matches a box not yet
    taken (it takes the one it fits best), False when it is a false one.
    ``taken`` (a list of False, one per box), when given, tells which boxes
    were matched."""
    taken = [False] * len(boxes) if taken is None else taken
    hits = []
    for d in dets:
        best = None
        for i, b in enumerate(boxes):
            if not taken[i]:
                c = cost(d, b, shape)
                if c is not None and (best is None or c < best[0]):
                    best = (c, i)
        if best is not None:
            taken[best[1]] = True
        hits.append(best is not None)
    return hits


def keep(dets, top: int, min_strength: float = -math.inf, max_nfa: float = math.inf) -> list:
    """A method's final answer from its raw list: the detections at least
    ``min_strength`` strong with an NFA of at most ``max_nfa``, ``top`` at most."""
    return [d for d in dets if d.strength >= min_strength and d.nfa <= max_nfa][:top]


def on_other_prop(task: str, d: Det, photo: Photo) -> bool:
    """Whether a (false) detection lies on a box labelled for another task or
    prop (for information only: it still counts as false): a disc's centre
    inside it, a line crossing its middle row, a frame overlapping it by an
    intersection over union of at least GATE_IOU."""
    for b in photo.boxes:
        if b.name.startswith("buoy_" if task == "buoy" else "qual_gate"):
            continue
        if task == "buoy" and b.x0 <= d.x <= b.x1 and b.y0 <= d.y <= b.y1:
            return True
        if task == "post":
            x = line_cross(d, b.cy, True)
            if x is not None and b.x0 <= x <= b.x1:
                return True
        if task == "gate" and iou(d.box, (b.x0, b.y0, b.x1, b.y1)) >= GATE_IOU:
            return True
    return False


def score(task: str, photos, found: dict, post: dict | None = None) -> dict:
    """Recall and false detections per image of a task over ``photos``,
    ``found[number]`` the raw detections, ``post`` the arguments of :func:`keep`;
    ``other``: how many of the false ones lie on another labelled prop."""
    n_img = n_obj = hit = false = other = 0
    for p in photos:
        objs = truth(p, task)
        if objs is None or p.number not in found:
            continue
        dets = found[p.number] if post is None else keep(found[p.number], **post)
        h = assign(dets, objs, COST[task], p.shape)
        n_img += 1
        n_obj += len(objs)
        hit += sum(h)
        false += len(h) - sum(h)
        other += sum(on_other_prop(task, d, p) for d, ok in zip(dets, h) if not ok)
    return dict(images=n_img, objects=n_obj, found=hit, false=false, other=other,
                recall=hit / n_obj if n_obj else math.nan,
                fa=false / n_img if n_img else math.nan)


# --------------------------------------------------------------------------
# methods
# --------------------------------------------------------------------------

def gate_points(aspect: float = GATE_ASPECT, h: float = GATE_H) -> list:
    """The gate's centre line: up the left post, along the bar, down the right post."""
    w = aspect * h
    return [(0.0, h), (0.0, 0.0), (w, 0.0), (w, h)]


def seahough_pattern(task: str, p: dict):
    pol = p.get("polarity", "bright")
    if task == "buoy":
        return seahough.Pattern.circle(p.get("r", BUOY_R), polarity=pol)
    if task == "post":
        return seahough.Pattern.line(p.get("length", POST_LEN), p.get("width", POST_W),
                                     polarity=pol)
    return seahough.Pattern.polyline(gate_points(p.get("aspect", GATE_ASPECT)),
                                     p.get("width", GATE_W), polarity=pol)


def seahough_ranges(task: str, p: dict):
    scale = {"buoy": BUOY_SCALE, "post": POST_SCALE, "gate": GATE_SCALE}[task]
    angle = {"buoy": (0.0, 360.0), "post": POST_ANGLE, "gate": GATE_ANGLE}[task]
    return tuple(p.get("scale", scale)), tuple(p.get("angle", angle))


def make_seahough(task: str, p: dict):
    """A runner: image -> detections, for seahough with settings ``p``
    (pattern: polarity, r / length / width / aspect; search: scale, angle,
    config; thresholds: top, min_score, max_nfa)."""
    pattern = seahough_pattern(task, p)
    scale, angle = seahough_ranges(task, p)
    cfg = seahough.Config(**dict(p.get("config", ())))
    det = seahough.Detector(pattern, scale_range=scale, angle_range=angle, config=cfg,
                            max_results=p.get("top", 5), min_score=p.get("min_score", 0.5),
                            max_nfa=p.get("max_nfa", 1.0))
    r0 = p.get("r", BUOY_R)

    def run(img):
        try:
            found = det.detect(img)
        except SeahoughError as e:
            log(f"seahough: {e}")
            return []
        out = []
        for d in found:
            if task == "buoy":
                out.append(Det(d.x, d.y, size=2.0 * r0 * d.scale, strength=d.score, nfa=d.nfa))
            elif task == "post":
                out.append(Det(d.x, d.y, angle=d.line_angle, strength=d.score, nfa=d.nfa))
            else:
                pts = np.vstack(d.outline)
                out.append(Det(d.x, d.y, box=(*pts.min(axis=0), *pts.max(axis=0)),
                               strength=d.score, nfa=d.nfa))
        return out
    return run


def geometric(lo: float, hi: float, step: float = 1.15) -> list:
    n = max(1, int(math.ceil(math.log(hi / lo) / math.log(step))))
    return [float(lo * (hi / lo) ** (i / n)) for i in range(n + 1)]


def post_template(length: float = POST_LEN, width: float = POST_W) -> np.ndarray:
    """A vertical bright band (no ends: a post runs on), background beside it."""
    h, w = int(round(length)), int(round(3 * width))
    t = np.full((h, w), 30, np.uint8)
    t[:, int(round(width)):int(round(2 * width))] = 230
    return t


def guil_template():
    """GeneralizedHoughGuil's gate template, its outline and its angle range.

    Guil searches angles in [0, 360] only (clockwise as displayed), so the
    default gate pattern's image is turned counter-clockwise by the lower
    end of :data:`GATE_ANGLE`'s span first (on a larger canvas, background
    level) and searched over ``(0, span)``: together -10..10 degrees about
    upright. Returns (template, outline points in template pixels, angle range).
    """
    pat = seahough_pattern("gate", {})
    img = pat.image
    h, w = img.shape
    a = -GATE_ANGLE[0]
    c, s = abs(math.cos(math.radians(a))), abs(math.sin(math.radians(a)))
    W, H = int(math.ceil(w * c + h * s)) + 2, int(math.ceil(w * s + h * c)) + 2
    R = cv2.getRotationMatrix2D(((w - 1) / 2.0, (h - 1) / 2.0), a, 1.0)
    R[:, 2] += [(W - w) / 2.0, (H - h) / 2.0]
    bg = int(np.median(img[0]))
    tpl = cv2.warpAffine(img, R, (W, H), flags=cv2.INTER_LINEAR, borderValue=bg)
    pts = np.vstack(pat.outline) @ R[:, :2].T + R[:, 2]
    return tpl, pts, (0.0, GATE_ANGLE[1] - GATE_ANGLE[0])


def make_peer(task: str, method: str, p: dict):
    """A runner for an OpenCV peer (bench/peers.py) with settings ``p``."""
    if method.startswith("HoughCircles"):
        kind = "alt" if method.endswith("ALT") else "gradient"
        rad = (int(BUOY_R * BUOY_SCALE[0]), int(math.ceil(BUOY_R * BUOY_SCALE[1])))

        def run(img):
            return [Det(x, y, size=2 * r, strength=-i) for i, (x, y, r) in enumerate(
                peers.hough_circles(img, kind, p["dp"], p["param1"], p["param2"], rad))]
        return run
    if method == "HoughLinesP":
        def run(img):
            return [Det(x, y, angle=a, strength=s) for a, x, y, s in peers.hough_posts(
                img, p["canny"], p["threshold"], p["min_length"], p["max_gap"],
                max_tilt=90.0 - POST_ANGLE[0])]
        return run
    if method == "matchTemplate":
        if task == "buoy":
            tpl, scales = seahough.Pattern.circle(BUOY_R).image, geometric(*BUOY_SCALE)
        elif task == "post":
            tpl, scales = post_template(), geometric(*POST_SCALE)
        else:
            pat = seahough_pattern("gate", {})
            tpl, scales = pat.image, geometric(*GATE_SCALE)
        th, tw = tpl.shape
        if task == "gate":   # the frame's extent about the template's centre, template px
            o = np.vstack(pat.outline) - [(tw - 1) / 2.0, (th - 1) / 2.0]
            lo, hi = o.min(axis=0), o.max(axis=0)

        def run(img):
            out = []
            for s, x, y, sc in peers.match_template_multiscale(
                    img, tpl, scales, polarity=p["polarity"], floor=0.3):
                if task == "buoy":
                    out.append(Det(x, y, size=2 * BUOY_R * sc, strength=s))
                elif task == "post":
                    out.append(Det(x, y, angle=90.0, strength=s))
                else:
                    out.append(Det(x, y, box=(x + sc * lo[0], y + sc * lo[1], x + sc * hi[0],
                                              y + sc * hi[1]), strength=s))
            return out
        return run
    if method == "GeneralizedHoughGuil":
        tpl, corners, span = guil_template()
        opts = {k: v for k, v in p.items() if k != "timeout"}
        ght = peers.GHTGuilOpts(timeout=p.get("timeout", GUIL_TIMEOUT), **opts)
        ght.set_template(tpl, None, GATE_SCALE, span)

        def run(img):
            r = ght.locate(img)
            run.seconds = r.seconds
            if r.matrix is None:
                return []
            q = corners @ r.matrix[:, :2].T + r.matrix[:, 2]
            c = q.mean(axis=0)
            return [Det(float(c[0]), float(c[1]), box=(*q.min(axis=0), *q.max(axis=0)),
                        strength=r.confidence)]
        run.seconds = None
        run.close = ght.close
        return run
    raise ValueError(method)


# --------------------------------------------------------------------------
# grids (tune part) and the rule that picks a setting
# --------------------------------------------------------------------------

TOPS = (1, 2, 3, 5)
NFAS = (1e-6, 1e-4, 1e-2, 1.0)
QUANTILES = (*range(0, 100, 10), 95, 98, 99)
# seahough grid runs, filtered after. At most 5 results: more is counting mode
# (more key points, every candidate finished), not what the tuned row reruns
# with (at most 5), so the grid would choose for a search it does not run.
PERMISSIVE = dict(top=max(TOPS), min_score=0.3, max_nfa=1e3)


def seahough_grid(task: str, quick: bool, colour: bool = False) -> list:
    """Search settings (each needs a run); thresholds are chosen after."""
    pols = ("either",) if quick else ("bright", "dark", "either")
    kps = (1200,) if quick else (1200, 2500)
    cfg = lambda kp: tuple(sorted({"n_keypoints": kp, **({"colour": True} if colour else {})}  # noqa: E731
                                  .items()))
    if task == "buoy":
        scales = (BUOY_SCALE,) if quick else (BUOY_SCALE, (0.3, 7.0))
        return [dict(polarity=q, scale=sc, config=cfg(kp)) for q in pols for kp in kps
                for sc in scales]
    if task == "post":
        widths = (12.0,) if quick else (6.0, 12.0, 20.0)
        return [dict(polarity=q, width=w, config=cfg(kp)) for q in pols for w in widths
                for kp in kps]
    widths = (6.0,) if quick else (4.0, 8.0, 14.0)
    aspects = (GATE_ASPECT,) if quick else (1.8, 2.1, 2.4)
    return [dict(polarity=q, width=w, aspect=a, config=cfg(1200)) for q in pols for w in widths
            for a in aspects]


def peer_grid(task: str, quick: bool) -> dict:
    """method -> list of run settings."""
    pol = ("either",) if quick else ("bright", "dark", "either")
    if task == "buoy":
        g = {"HoughCircles": [dict(dp=dp, param1=p1, param2=p2)
                              for dp in ((1.0,) if quick else (1.0, 1.5))
                              for p1 in ((100.0,) if quick else (50.0, 100.0, 150.0))
                              for p2 in ((30.0,) if quick else (15.0, 25.0, 35.0, 50.0))],
             "HoughCircles ALT": [dict(dp=1.5, param1=p1, param2=p2)
                                  for p1 in ((300.0,) if quick else (100.0, 200.0, 300.0))
                                  for p2 in ((0.9,) if quick else (0.5, 0.7, 0.8, 0.9))]}
    elif task == "post":
        g = {"HoughLinesP": [dict(canny=c, threshold=t, min_length=m, max_gap=gp)
                             for c in (((50, 150),) if quick else ((30, 90), (50, 150), (80, 240)))
                             for t in ((50,) if quick else (30, 60))
                             for m in ((40.0,) if quick else (40.0, 80.0))
                             for gp in ((10.0,) if quick else (5.0, 15.0))]}
    else:
        g = {"GeneralizedHoughGuil": [{}] if quick else [
            {}, dict(canny=(30, 90), angle_thresh=500, scale_thresh=20, pos_thresh=5)]}
    g["matchTemplate"] = [dict(polarity=q) for q in pol]
    return g


def posts_of(method: str, found: dict, quick: bool) -> list:
    """Thresholds to try on a run's raw detections (tune part)."""
    strengths = np.array([d.strength for ds in found.values() for d in ds], float)
    qs = sorted(set(np.percentile(strengths, QUANTILES).tolist())) if strengths.size else [0.0]
    qs = [-math.inf] + qs
    tops = (1, 3) if quick else TOPS
    if method.startswith("HoughCircles"):
        return [dict(top=t) for t in tops]
    if method == "GeneralizedHoughGuil":
        return [dict(top=1, min_strength=q) for q in qs]
    if method.startswith("seahough"):
        return [dict(top=t, min_strength=q, max_nfa=n) for t in tops for q in qs
                for n in ((1.0,) if quick else NFAS)]
    return [dict(top=t, min_strength=q) for t in tops for q in qs]


def choose(cands: list) -> dict:
    """The rule: of the settings with at most FA_BUDGET false detections per
    image on the tune part, the highest recall (then fewer false detections,
    then the faster); when none is within the budget, the fewest false
    detections (then the highest recall)."""
    ok = [c for c in cands if c["fa"] <= FA_BUDGET]
    if ok:
        return min(ok, key=lambda c: (-c["recall"], c["fa"], c["ms"]))
    return min(cands, key=lambda c: (c["fa"], -c["recall"], c["ms"]))


# --------------------------------------------------------------------------
# running
# --------------------------------------------------------------------------

class Runs:
    """Raw detections and CPU ms per (method key, photo number), optionally kept in a file."""

    def __init__(self, path=None):
        self.path = Path(path) if path else None
        self.data = {}
        if self.path and self.path.is_file():
            with open(self.path, "rb") as f:
                self.data = pickle.load(f)
        self.loaded = {k: set(v) for k, v in self.data.items()}
        self.reused = set()         # (key, number) read from the file and used
        self.searched = 0

    def save(self):
        if self.path:
            tmp = self.path.with_suffix(".tmp")
            with open(tmp, "wb") as f:
                pickle.dump(self.data, f)
            tmp.replace(self.path)

    def run(self, key: tuple, make, photos, images) -> dict:
        """{number: (detections, ms)} of the runner ``make()`` over ``photos``."""
        have = self.data.setdefault(key, {})
        todo = [p for p in photos if p.number not in have]
        self.reused |= {(key, p.number) for p in photos if p.number in self.loaded.get(key, ())}
        self.searched += len(todo)
        if todo:
            runner = make()
            for p in todo[:2]:                          # warm-up (Numba, first allocations)
                runner(images[p.number])
            for p in todo:
                img = images[p.number]
                t = time.process_time()
                dets = runner(img)
                ms = 1000.0 * (time.process_time() - t)
                if getattr(runner, "seconds", None) is not None:
                    ms = 1000.0 * runner.seconds       # a worker process: its own time
                have[p.number] = (dets, ms)
            if hasattr(runner, "close"):
                runner.close()
        return {p.number: have[p.number] for p in photos}


def key_of(task: str, method: str, p: dict) -> tuple:
    return (task, method, tuple(sorted((k, repr(v)) for k, v in p.items())))


def summarise(task: str, photos, got: dict, post: dict | None = None) -> dict:
    s = score(task, photos, {n: d for n, (d, _) in got.items()}, post)
    ms = [m for _, m in got.values()]
    s["ms"] = float(np.median(ms)) if ms else math.nan
    return s


def colour_config():
    """Config(colour=True) when this seahough has it, else None."""
    try:
        seahough.Config(colour=True)
    except (TypeError, SeahoughError):
        return None
    return ("colour", True)


def tune(task: str, runs: Runs, tune_photos, images, quick: bool) -> dict:
    """method -> the chosen setting, its tune-part numbers and the grid's size."""
    chosen = {}
    grids = {"seahough": seahough_grid(task, quick)}
    if colour_config() is not None:
        grids["seahough colour"] = seahough_grid(task, quick, colour=True)
    grids.update(peer_grid(task, quick))
    for method, grid in grids.items():
        cands = []
        t0 = time.perf_counter()
        for rp in grid:
            if method.startswith("seahough"):
                full = dict(rp, **PERMISSIVE)
                got = runs.run(key_of(task, "seahough", full),
                               lambda: make_seahough(task, full), tune_photos, images)
            else:
                got = runs.run(key_of(task, method, rp), lambda: make_peer(task, method, rp),
                               tune_photos, images)
            found = {n: d for n, (d, _) in got.items()}
            for post in posts_of(method, found, quick):
                s = summarise(task, tune_photos, got, post)
                cands.append(dict(s, run=rp, post=post))
        c = choose(cands)
        chosen[method] = dict(c, grid=len(cands), runs=len(grid))
        log(f"{task} {method}: {len(grid)} runs, {len(cands)} settings in "
            f"{time.perf_counter() - t0:.0f} s; chose {c['run']} {c['post']}: recall "
            f"{c['recall']:.2f}, FA {c['fa']:.2f}")
        runs.save()
    return chosen


def final_settings(task: str, chosen: dict) -> list:
    """(row name, method, run settings, post filter) of every row of a task's table."""
    rows = [("seahough (defaults)", "seahough", {}, None)]
    for method, name in (("seahough", "seahough (tuned)"),
                         ("seahough colour", "seahough (tuned, colour)")):
        if method in chosen:
            c = chosen[method]
            post = c["post"]
            ms = post["min_strength"]
            rows.append((name, "seahough", dict(c["run"], top=post["top"], max_nfa=post["max_nfa"],
                                                min_score=ms if math.isfinite(ms) else
                                                PERMISSIVE["min_score"]), None))
    for method, c in chosen.items():
        if not method.startswith("seahough"):
            rows.append((method, method, c["run"], c["post"]))
    return rows


def evaluate(task: str, rows, runs: Runs, photos, images) -> list:
    out = []
    for name, method, rp, post in rows:
        if method == "seahough":
            got = runs.run(key_of(task, method, rp), lambda: make_seahough(task, rp), photos,
                           images)
        else:
            got = runs.run(key_of(task, method, rp), lambda: make_peer(task, method, rp), photos,
                           images)
        res = {}
        for part in ("tune", "test", "sim"):
            ps = [p for p in photos if p.part == part]
            res[part] = summarise(task, ps, {p.number: got[p.number] for p in ps}, post)
        vga = [got[p.number][1] for p in photos if p.part == "tune" and p.shape == (480, 640)]
        res["ms640"] = float(np.median(vga)) if vga else math.nan
        res["by_block"] = blocks(task, [p for p in photos if p.part == "test"], got, post)
        out.append(dict(name=name, method=method, run=rp, post=post, res=res,
                        found={n: (keep(d, **post) if post else d) for n, (d, _) in got.items()}))
        runs.save()
        log(f"{task} {name}: test recall {res['test']['recall']:.2f}, FA {res['test']['fa']:.2f}, "
            f"{res['test']['ms']:.1f} ms")
    return out


def blocks(task: str, photos, got: dict, post) -> list:
    """Recall and false detections per run of consecutive frame numbers (gap <= 5)."""
    runs_, cur = [], []
    for p in sorted(photos, key=lambda p: p.number):
        if cur and p.number - cur[-1].number > 5:
            runs_.append(cur)
            cur = []
        cur.append(p)
    if cur:
        runs_.append(cur)
    out = []
    for r in runs_:
        s = score(task, r, {p.number: got[p.number][0] for p in r}, post)
        if s["objects"]:
            out.append(dict(s, first=r[0].number, last=r[-1].number,
                            size=f"{r[0].shape[1]}x{r[0].shape[0]}"))
    return out


# --------------------------------------------------------------------------
# report
# --------------------------------------------------------------------------

def table(head, rows) -> list:
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return out


def fnum(v, nd=2) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{nd}f}"


def rate(s: dict) -> str:
    if not s["objects"]:
        return "-"
    return f"{100 * s['recall']:.0f} % ({s['found']}/{s['objects']})"


def fa(s: dict) -> str:
    return f"{fnum(s['fa'])} ({s['false']}/{s['images']})" if s["images"] else "-"


def describe(method: str, rp: dict, post) -> str:
    """The settings of a row, in words."""
    parts = []
    for k, v in rp.items():
        if k == "config":
            parts.append("Config(" + ", ".join(f"{a}={b!r}" for a, b in v) + ")")
        elif k == "max_nfa":
            parts.append(f"max_nfa={v:g}")
        elif k == "min_score":
            parts.append(f"min_score={v:.2f}")
        elif k == "top":
            parts.append(f"max_results={v}")
        else:
            parts.append(f"{k}={v}")
    if post:
        if "top" in post:
            parts.append(f"best {post['top']}")
        if math.isfinite(post.get("min_strength", -math.inf)):
            parts.append(f"strength >= {post['min_strength']:.3g}")
    return ", ".join(parts) if parts else "defaults"


def default_text(task: str) -> str:
    if task == "buoy":
        return (f"Pattern.circle({BUOY_R:g}), scale_range={BUOY_SCALE}, any angle; "
                "Detector defaults (max_results=5, min_score=0.5, max_nfa=1)")
    if task == "post":
        return (f"Pattern.line({POST_LEN:g}, {POST_W:g}), scale_range={POST_SCALE}, "
                f"angle_range={POST_ANGLE}; Detector defaults")
    return (f"Pattern.polyline({[tuple(round(v) for v in q) for q in gate_points()]}, "
            f"{GATE_W:g}), scale_range={GATE_SCALE}, angle_range={GATE_ANGLE}; Detector defaults")


def target_rows(results: dict) -> list:
    rows = []
    for task in ("buoy", "post"):
        res = {r["name"]: r["res"] for r in results[task]}
        for name in ("seahough (defaults)", "seahough (tuned)"):
            t = res[name]["test"]
            met = lambda ok: "met" if ok else "**missed**"  # noqa: E731
            ms = res[name]["ms640"]
            rows += [[TASK_TITLE[task], name, "recall", rate(t), ">= 90 %",
                      met(t["recall"] >= TARGET_RECALL)],
                     [TASK_TITLE[task], name, "false detections / image", fa(t), "<= 0.3",
                      met(t["fa"] <= FA_BUDGET)],
                     [TASK_TITLE[task], name, "CPU ms, 640x480 photo (median)", fnum(ms, 1),
                      "< 30", met(ms < TARGET_MS)]]
    return rows


def report(photos, results: dict, chosen: dict, args, seconds: float, allocator: str,
           runs: Runs | None = None) -> str:
    cached = ""
    if runs is not None and runs.reused:
        n = len(runs.reused)
        cached = (f" {n} of {n + runs.searched} searches (their detections "
                  f"and times) were read from the cache file of an earlier run (--cache).")
    L = ["# RoboSub props in real pools: buoys, gate posts, the gate", "",
         f"Command: `{command()}`  ", f"Date: {datetime.date.today().isoformat()}  ",
         f"Machine: {machine()}  ",
         "Single-threaded (cv2.setNumThreads(1), NUMBA_NUM_THREADS=1); CPU ms of one call per "
         "photo (the JPEG decoded before), after a warm-up on two photos; GeneralizedHoughGuil "
         f"runs in a worker process and its own time is given; {allocator}. Whole run: "
         f"{seconds / 60:.0f} min." + (" **Quick run: 8 photos, a 1-setting grid.**"
                                      if args.quick else "") + cached, "",
         "Data: ../shared/data/objects/robosub_transdec (MIT licence; beaverauv/"
         "robosub_transdec_dataset: photos by Montana State Univ. RoboCatz and AVBotz), "
         "boxes labelled by others. How it is measured: bench/bench_robosub.py.", "",
         f"**Split** (blocks of frame numbers; frames are numbered in recording order and "
         f"neighbours are near-duplicates): {SPLIT}. Every setting was chosen on the tune part; "
         "the targets are judged on the test part.", ""]
    rows = []
    for part in ("tune", "test", "sim"):
        ps = [p for p in photos if p.part == part]
        sizes = sorted({f"{p.shape[1]}x{p.shape[0]}" for p in ps})
        n = {t: sum(len(truth(p, t) or []) for p in ps) for t in TASKS}
        left = sum(truth(p, "gate") is None for p in ps)
        rows.append([part, len(ps), ", ".join(sizes), n["buoy"], n["post"], n["gate"], left])
    dropped = sum(1 for p in photos for b in p.boxes
                  if b.name == "qual_gate" and min(b.w, b.h) < MIN_BOX)
    L += table(["part", "photos", "sizes", "buoys", "gate posts", "whole gates",
                "photos with one post (left out of the gate task)"], rows)
    L += ["", f"Post boxes under {MIN_BOX:g} px across, left out: {dropped}.", ""]

    L += ["## Targets (issue 15, test part)", "",
          "Recall and false detections on the test part; time on the tune part's 640x480 "
          "photos (the test part has none: its photos are 492x360 and 640x360; times on them "
          "are in the tables below).", "",
          *table(["task", "seahough", "check", "measured", "target", "result"],
                 target_rows(results)), "",
          "Test part, recall at false detections per image:", "", *summary(results), ""]

    L += ["## Matching rules", "",
          "One detection matches at most one labelled box: a method's detections are taken "
          "best first, each takes the free box it fits best (nearest centre; the gate: highest "
          "overlap). A detection that matches no free box of its task is a **false "
          "detection**, wherever it lies: on another labelled prop (the channel's posts look "
          "like gate posts), on a prop nobody labelled (some visible buoys are not labelled, "
          "e.g. in frames 1199-1202 and 1444-1451), or on nothing. Recall = matched boxes / "
          "labelled boxes; false detections per image = false detections / photos of the part.",
          "",
          f"- **Buoys** (`buoy_red`, `buoy_green`, `buoy_yellow`, any colour) as discs: the "
          f"disc's centre lies inside the box, and its diameter is within a factor "
          f"{SIZE_FACTOR:g} of the box's width (its height when the box touches the left or "
          "right border of the photo: the buoy is cut by the frame). The width, not the "
          "height: a buoy's box also holds its bottom fitting.",
          f"- **Gate posts** (each `qual_gate` box is one post) as lines: the line (seahough "
          "reports a line's direction and offset, not where along it the post lies; every "
          "method's answer is taken as an infinite line) crosses the box's middle third, at "
          f"one and at two thirds of its height, within the box's width (plus {SLACK_PX:g} px), "
          f"and its direction is within {ANGLE_TOL:g} degrees of vertical (or within the "
          "angle of the box's diagonal, when larger: a post tilted in its box).",
          f"- **The gate** (two posts and the bar across their tops, as in every photo of "
          "it: the posts hang from a bar; the channel is the U-shaped prop) as an open frame: "
          "the union of a photo's two post boxes is the gate; a detection matches when its "
          f"bounding box overlaps it with an intersection over union of at least {GATE_IOU:g}. "
          "A photo with one labelled post (the gate half out of view) is left out of this task.",
          ""]

    for task in TASKS:
        L += [f"## {TASK_TITLE[task]}", "",
              f"seahough (defaults): {default_text(task)}. Tuned rows and peers: the settings "
              "chosen on the tune part (next section). ms: median CPU ms per photo"
              + (f" (GeneralizedHoughGuil: {1000 * GUIL_TIMEOUT:.0f} ms is its cap, reached "
                 "when a search was stopped; the cap is wall-clock time, so on a shared machine "
                 "how many searches are stopped, and with them its numbers and the setting the "
                 "tune part picks, change from run to run)" if task == "gate" else "") + ".", ""]
        rows = []
        for r in results[task]:
            res = r["res"]
            rows.append([r["name"], describe(r["method"], r["run"], r["post"]),
                         rate(res["test"]), fa(res["test"]), res["test"]["other"],
                         fnum(res["test"]["ms"], 1),
                         fnum(res["ms640"], 1), rate(res["tune"]), fnum(res["tune"]["fa"]),
                         rate(res["sim"]), fnum(res["sim"]["fa"])])
        L += table(["method", "settings", "test recall", "test false / image",
                    "of which on other props", "test ms",
                    "ms 640x480", "tune recall", "tune false / image", "simulator recall",
                    "simulator false / image"], rows)
        L += ["", "Test part by block of consecutive frames (found/labelled, false detections):",
              ""]
        names = [r["name"] for r in results[task]]
        blocks_ = results[task][0]["res"]["by_block"]
        rows = []
        for i, b in enumerate(blocks_):
            cells = [f"{b['first']}-{b['last']}", b["size"], b["images"]]
            for r in results[task]:
                bb = r["res"]["by_block"][i]
                cells.append(f"{bb['found']}/{bb['objects']}, {bb['false']}")
            rows.append(cells)
        L += table(["frames", "size", "photos", *names], rows) + [""]
        L += by_size(task, [p for p in photos if p.part == "test"], results[task])

    L += ["## How the settings were chosen (tune part only)", "",
          f"Rule, for every method alike: of the settings with at most {FA_BUDGET:g} false "
          "detections per image on the tune part, the one with the highest recall (ties: fewer "
          "false detections, then the faster); when none is within that budget, the one with the "
          "fewest false detections. Thresholds on a method's own strength (seahough: score; "
          "HoughLinesP: the posts' total segment length; matchTemplate: the correlation; "
          "GeneralizedHoughGuil: its votes) were tried at the 0-90th percentiles of the "
          "strengths the method gave on the tune part, with none at all; the number of "
          f"detections kept at {', '.join(map(str, TOPS))}; seahough's max_nfa at "
          f"{', '.join(f'{v:g}' for v in NFAS)}. seahough's grid runs searched with "
          f"max_results={PERMISSIVE['top']}, min_score={PERMISSIVE['min_score']} and "
          f"max_nfa={PERMISSIVE['max_nfa']:g} and were filtered after; the tuned row is a "
          "new run with the chosen thresholds.", ""]
    rows = []
    for task in TASKS:
        for method, c in chosen[task].items():
            rows.append([TASK_TITLE[task], method, grid_text(task, method), c["runs"], c["grid"],
                         describe(method, c["run"], c["post"]), rate(c), fnum(c["fa"])])
    L += table(["task", "method", "grid", "runs", "settings tried", "chosen", "tune recall",
                "tune false / image"], rows) + [""]
    L += ["## Picture", "",
          f"Test frame {PICTURE_FRAME}, seahough (tuned) for each task: labelled boxes in white, "
          "matched detections in green, false ones in red (buoys: the found disc; posts: the "
          "found line, drawn across the photo since its position along the line is not "
          "measured; the gate: the found frame's bounding box).", "",
          f"![RoboSub test frame]({PICTURE.relative_to(DOC.parent).as_posix()})", ""]
    return "\n".join(L)


SIZE_BINS = {"buoy": (0, 20, 40, 80, math.inf), "post": (0, 120, 160, 240, math.inf),
             "gate": (0, 150, 200, math.inf)}


def by_size(task: str, photos, rows) -> list:
    """Test-part recall of every method by the labelled object's size (buoys:
    the size of the disc rule; posts and gates: the box's height)."""
    edges = SIZE_BINS[task]
    size = (lambda b, p: buoy_size(b, p.shape)) if task == "buoy" else (lambda b, p: b.h)
    counts = {r["name"]: [[0, 0] for _ in edges[1:]] for r in rows}
    for p in photos:
        objs = truth(p, task)
        if not objs:
            continue
        for r in rows:
            taken = [False] * len(objs)
            assign(r["found"].get(p.number, []), objs, COST[task], p.shape, taken)
            for b, t in zip(objs, taken):
                k = next(i for i in range(len(edges) - 1) if edges[i] <= size(b, p) < edges[i + 1])
                counts[r["name"]][k][0] += t
                counts[r["name"]][k][1] += 1
    what = "size (px)" if task == "buoy" else "height (px)"
    head = [f"{edges[i]:g}-{edges[i + 1]:g}" if math.isfinite(edges[i + 1]) else f">= {edges[i]:g}"
            for i in range(len(edges) - 1)]
    out = [f"Test part recall by the labelled object's {what} (found/labelled):", ""]
    out += table(["method", *head], [[name, *(f"{a}/{n}" for a, n in c)]
                                     for name, c in counts.items()])
    return out + [""]


def grid_text(task: str, method: str) -> str:
    if method.startswith("seahough"):
        cfg = "Config(colour=True), " if method.endswith("colour") else ""
        if task == "buoy":
            return (f"{cfg}polarity bright/dark/either x n_keypoints 1200/2500 x scale "
                    f"{BUOY_SCALE[0]:g}-{BUOY_SCALE[1]:g}/0.3-7")
        if task == "post":
            return f"{cfg}polarity bright/dark/either x width 6/12/20 x n_keypoints 1200/2500"
        return f"{cfg}polarity bright/dark/either x width 4/8/14 x aspect 1.8/2.1/2.4"
    if method == "HoughCircles":
        return "dp 1/1.5 x param1 50/100/150 x param2 15/25/35/50; radius 4-64, medianBlur 5"
    if method == "HoughCircles ALT":
        return "dp 1.5, param1 100/200/300 x param2 0.5/0.7/0.8/0.9; radius 4-64, medianBlur 5"
    if method == "HoughLinesP":
        return ("Canny 30/90, 50/150, 80/240 x threshold 30/60 x minLineLength 40/80 x "
                "maxLineGap 5/15; within 30 degrees of vertical, borders grouped within 30 px")
    if method == "GeneralizedHoughGuil":
        return ("GHTGuil's settings (Canny 60/180, AngleThresh 1500, ScaleThresh 50, PosThresh 10) "
                "or Canny 30/90 with 500/20/5; the default gate pattern's image as template, "
                "scale 0.9-3, angle -10..10; half resolution, "
                f"{GUIL_TIMEOUT:g} s cap (bench/peers.py GHTGuilOpts)")
    return ("polarity bright/dark/either (TM_CCOEFF_NORMED at 320 px wide, scales x1.15 over "
            "the seahough range)")


def summary(results: dict) -> list:
    """One line per task: every row's test-part recall and false detections per image."""
    out = []
    for task in TASKS:
        cells = [f"{r['name']} {100 * r['res']['test']['recall']:.0f} % at "
                 f"{r['res']['test']['fa']:.2f}" for r in results[task]]
        out.append(f"- **{TASK_TITLE[task]}**: " + "; ".join(cells) + ".")
    return out


# --------------------------------------------------------------------------
# picture
# --------------------------------------------------------------------------

def draw(photo: Photo, results: dict, path: Path) -> None:
    img = cv2.imread(str(photo.path), cv2.IMREAD_COLOR)
    for b in photo.boxes:
        if b.name.startswith("buoy_") or b.name == "qual_gate":
            cv2.rectangle(img, (round(b.x0), round(b.y0)), (round(b.x1), round(b.y1)),
                          (255, 255, 255), 1, cv2.LINE_AA)
    h, w = photo.shape
    for task in TASKS:
        row = next(r for r in results[task] if r["name"] == "seahough (tuned)")
        dets = row["found"].get(photo.number, [])
        objs = truth(photo, task) or []
        for d, hit in zip(dets, assign(dets, objs, COST[task], photo.shape)):
            col = (60, 220, 60) if hit else (40, 40, 230)
            if task == "buoy":
                cv2.circle(img, (round(d.x), round(d.y)), round(d.size / 2), col, 2, cv2.LINE_AA)
            elif task == "post":
                x0, x1 = line_cross(d, 0.0, True), line_cross(d, h - 1.0, True)
                if x0 is not None:
                    cv2.line(img, (round(x0), 0), (round(x1), h - 1), col, 1, cv2.LINE_AA)
            else:
                x0, y0, x1, y1 = (round(v) for v in d.box)
                cv2.rectangle(img, (x0, y0), (x1, y1), col, 2, cv2.LINE_AA)
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), img, [cv2.IMWRITE_JPEG_QUALITY, 88])


# --------------------------------------------------------------------------
# main
# --------------------------------------------------------------------------

def main(argv=None) -> str:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n", 1)[1])
    ap.add_argument("--quick", action="store_true",
                    help="8 photos and a 1-setting grid (a smoke test)")
    ap.add_argument("--write", action="store_true",
                    help=f"write {DOC.relative_to(ROOT)} and {PICTURE.relative_to(ROOT)}")
    ap.add_argument("--out", default=None, help="write the report here instead")
    ap.add_argument("--cache", default=None,
                    help="keep raw detections in this file and reuse them (delete it when "
                         "seahough or the peers change)")
    args = ap.parse_args(argv)
    if args.quick and args.write:
        ap.error(f"--quick with --write would replace {DOC.relative_to(ROOT)} by a smoke test")
    data = shared_data_dir()
    folder = None if data is None else data.joinpath(*SUBDIR)
    if folder is None or not (folder / "images").is_dir():
        print("Skipped: the real data (../shared/data/objects/robosub_transdec) is not present.")
        return ""
    allocator = steady_allocator()
    t0 = time.perf_counter()
    photos = [p for p in load_photos(folder) if p.part]
    if args.quick:
        photos = [p for p in photos if p.number in QUICK_FRAMES]
    images = Images(photos)
    runs = Runs(args.cache)
    tune_photos = [p for p in photos if p.part == "tune"]
    chosen, results = {}, {}
    for task in TASKS:
        chosen[task] = tune(task, runs, tune_photos, images, args.quick)
        results[task] = evaluate(task, final_settings(task, chosen[task]), runs, photos, images)
    text = report(photos, results, chosen, args, time.perf_counter() - t0, allocator, runs)
    print(text)
    out = args.out or (str(DOC) if args.write else None)
    if out:
        write_page(text, out)
    pic = [p for p in photos if p.number == PICTURE_FRAME]
    if args.write and pic:
        draw(pic[0], results, PICTURE)
        log(f"picture: {PICTURE}")
    return text


if __name__ == "__main__":
    main()
