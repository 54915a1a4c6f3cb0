"""What in a frame is not the scene: a video's blank border (letterbox bars,
a uniform band) and burned-in captions (a timestamp or frame counter on a
flat box at an edge), found so that the search does not take their edges for
objects (:func:`find_blanks`), and filled from the picture beside them
(:func:`fill_blanks`). Positions are unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

def _grey(image: np.ndarray, colour: bool | None = None) -> np.ndarray:
    """A colour image's mean of its channels (numpy's mean over the last
    axis took 5 ms for a 640x480 photo), a grey one as it is; ``colour``:
    whether the last axis holds channels (None: when there are three axes)."""
    if not (image.ndim == 3 if colour is None else colour):
        return image
    c = image.astype(np.float32, copy=False)
    if c.shape[-1] != 3:                        # (one channel, grey and alpha...)
        return c[..., 0] if c.shape[-1] < 3 else c[..., :3].mean(axis=-1)
    return (c[..., 0] + c[..., 1] + c[..., 2]) * np.float32(1.0 / 3.0)


#: a frame's outermost line is blank (a video's letterbox bar, a camera's
#: black or grey band) when its levels vary by less than this standard
#: deviation (0-255 levels): the black bars of the RoboSub pool videos have
#: 0.5-1.0 (JPEG noise), a flat grey band 0; the darkest vignetted border
#: of the real sequences (the amphora wreck's corners) 6.7, textured sand
#: more. Only lines all flat count: a dark border with texture is content.
BLANK_STD = 2.0
#: at most this share of each side is taken for a blank border (a side
#: flat farther in: no border, the picture's own flat background)
BLANK_DEPTH = 0.25
#: ... and only when the picture beyond it departs from the band's level by
#: this many levels (within that quarter) all along the side, at least at
#: this share of its length: a drawn scene's flat background, level with
#: the band beside an object, is no border (the object stays as it is).
#: All 102 bordered RoboSub test frames pass; no tune photo has such a border.
BLANK_STEP = 10.0
BLANK_ALONG = 0.98
#: ... and this share of it within the first lines beyond the band (a bar's
#: edge is a step; the flat open water at the top of a pool photo fades,
#: and its objects break it over a fifth of the width)
BLANK_STEP_SHARE = 0.75
#: lines beyond a blank border left out too: the JPEG-smeared line between
#: bar and content (RoboSub: a column at 43 between 0 and 82)
BLANK_MARGIN = 2
#: ... and this many more in a colour image's copy: JPEG and video codecs
#: keep colour at half resolution (4:2:0), so a bar's edge smears further
#: into the picture's colour channels (RoboSub: red 11, 25, 59, 44, 0 over
#: the 4 columns before a bar where grey steps once; a user trial's colour
#: search found the bar's edge as a post)
CHROMA_MARGIN = 2


def blank_border(gray: np.ndarray) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1), end exclusive: the image without its blank border
    (flat lines at an edge: letterbox bars, a uniform band, beyond which the
    picture departs from their level all along the side, :data:`BLANK_STEP`) and
    :data:`BLANK_MARGIN` lines more on each side that has one; the whole
    image when it has none, or when they would leave less than half of it.

    Examples
    --------
    >>> img = np.random.default_rng(0).uniform(60, 200, (60, 80)).astype(np.float32)
    >>> img[:, :6] = 0                               # a letterbox bar
    >>> blank_border(img)
    (8, 0, 80, 60)
    """
    g = gray
    h, w = g.shape[:2]
    colour = g.ndim == 3

    def grey(a: np.ndarray) -> np.ndarray:      # (a colour image's lines only, not all of it)
        return _grey(a, colour)

    def flat_run(lines: np.ndarray) -> int:
        # lines: the side's outermost lines as rows, outermost first (most
        # images: the first alone decides); how many are flat (-1: all of them)
        if lines.shape[0] == 0 or grey(lines[0]).std() >= BLANK_STD:
            return 0
        flat = grey(lines).std(axis=1) < BLANK_STD
        return -1 if flat.all() else int(np.argmin(flat))

    def depth(lines: np.ndarray, n: int, lo: int, hi: int) -> int:
        # n: its flat_run; lo:hi: the part of the side between the bars of the sides
        # across it, where the picture begins (a picture framed on all four sides)
        if n <= 0:                    # (-1: a quarter of the side flat: a background)
            return 0
        framed = lo > 0 or hi < lines.shape[1]
        lines = grey(lines[:, lo:hi])
        if framed and lines[n].std() < BLANK_STD:   # (a flat object on a flat ground)
            return 0
        # a bar runs the whole side: beyond it, the picture departs from the band's
        # level all along (a drawn scene's flat background, level with the band, does
        # not where it passes beside an object)
        off = np.abs(lines[n:] - float(lines[n - 1].mean())) >= BLANK_STEP
        # ... and at once: a bar's edge is a step, open water fades from its level
        if (off.any(axis=0).mean() < BLANK_ALONG
                or off[:BLANK_MARGIN + 2].any(axis=0).mean() < BLANK_STEP_SHARE):
            return 0
        return n + BLANK_MARGIN

    ly, lx = int(h * BLANK_DEPTH), int(w * BLANK_DEPTH)
    sides = (g[:ly], g[h - ly:][::-1], np.swapaxes(g[:, :lx], 0, 1),
             np.swapaxes(g[:, w - lx:][:, ::-1], 0, 1))          # top, bottom, left, right
    runs = [flat_run(s) for s in sides]
    t, b, l, r = (max(n, 0) for n in runs)
    top, bottom, left, right = (depth(s, n, lo, hi) for s, n, (lo, hi) in zip(
        sides, runs, ((l, w - r), (l, w - r), (t, h - b), (t, h - b))))
    if not (top or bottom or left or right):
        return (0, 0, w, h)
    box = (left, top, w - right, h - bottom)
    if box[2] - box[0] < w // 2 or box[3] - box[1] < h // 2:
        return (0, 0, w, h)
    return box


def fill_blank_border(image: np.ndarray, box=None) -> np.ndarray:
    """``image`` with its :func:`blank_border` replaced by its content's
    outermost lines repeated outwards, so that the step between a letterbox
    bar and the picture is no edge (a post, a line, a rope along the frame
    on every video frame); the same array when it has none. Positions are
    unchanged. ``box``: that border, already found (the grey and colour
    copies of one image filled alike).

    Examples
    --------
    >>> img = np.random.default_rng(0).uniform(60, 200, (60, 80)).astype(np.float32)
    >>> img[:, :6] = 0
    >>> out = fill_blank_border(img)
    >>> bool((out[:, :8] == out[:, 8:9]).all()), out.shape
    (True, (60, 80))
    """
    h, w = image.shape[:2]
    x0, y0, x1, y1 = blank_border(image) if box is None else box
    if (x0, y0, x1, y1) == (0, 0, w, h):
        return image
    return cv2.copyMakeBorder(image[y0:y1, x0:x1], y0, h - y1, x0, w - x1, cv2.BORDER_REPLICATE)


#: a burned-in caption's box: a connected region of flat levels, dark (at
#: most CAPTION_DARK) or light (at least CAPTION_LIGHT), CAPTION_FLAT of it
#: within CAPTION_LEVELS of its median (the RoboSub pool videos' timestamp
#: box: 0-5, JPEG noise; the glyphs' smeared edges are the rest), of at
#: least CAPTION_MIN_PIXELS, touching an edge of the picture (within
#: CAPTION_TOUCH px of it), wide (at least CAPTION_ASPECT times as wide as
#: high, a line of text), at most CAPTION_HEIGHT of the image high and
#: CAPTION_AREA of it in all, covering more than CAPTION_FILL of its bounding
#: box and, with the holes it encloses (its glyphs), at least CAPTION_SOLID
#: of it (a box, not a blob: sun glare at the surface, a disc cut by the
#: frame), with text in those holes: at least CAPTION_TEXT of the box at
#: least CAPTION_INK levels off the box's level. The RoboSub timestamp
#: boxes: solid 0.95-1.00, text 0.11-0.18 of the box.
CAPTION_DARK, CAPTION_LIGHT = 40.0, 215.0
CAPTION_LEVELS = 6.0
CAPTION_FLAT = 0.7
CAPTION_MIN_PIXELS = 100
CAPTION_TOUCH = 3
CAPTION_ASPECT = 3.0
CAPTION_HEIGHT = 0.1
CAPTION_AREA = 0.05
CAPTION_FILL = 0.5
CAPTION_SOLID = 0.9
CAPTION_TEXT = 0.03
CAPTION_INK = 120.0
#: the least height of such a box (CAPTION_MIN_PIXELS at CAPTION_ASPECT):
#: an edge is read further only where its outermost lines hold a run of
#: flat levels that long (left, right) or CAPTION_ASPECT times that (top,
#: bottom)
CAPTION_MIN_HEIGHT = int(np.sqrt(CAPTION_MIN_PIXELS / CAPTION_ASPECT))
#: lines around a caption filled too (JPEG smear of its edge)
CAPTION_MARGIN = 2


@dataclass(frozen=True)
class Caption:
    """A burned-in caption's box (end exclusive, margin included) and the
    side of the picture it touches, from which it is filled."""

    side: str
    x0: int
    y0: int
    x1: int
    y1: int


@dataclass(frozen=True)
class Blanks:
    """What :func:`fill_blanks` fills: ``border`` the picture without its
    blank border (x0, y0, x1, y1, end exclusive; :func:`blank_border`), the
    burned-in ``captions`` inside it (:func:`caption_boxes`), the regions
    a user asked to leave out (``Config.ignore``, clipped to the image) and
    the ``no_data`` pixels beyond the picture (a sonar's fan: :func:`no_data`)."""

    border: tuple[int, int, int, int]
    captions: tuple[Caption, ...] = ()
    ignored: tuple[tuple[int, int, int, int], ...] = ()
    #: the pixels of a flat black area beyond the picture (:func:`no_data`), or None
    no_data: np.ndarray | None = field(default=None, repr=False, compare=False)


def caption_boxes(image: np.ndarray, border=None) -> tuple[Caption, ...]:
    """The burned-in captions of a frame (grey or colour, levels 0-255):
    flat dark or light boxes at an edge of the picture (``border``: its
    :func:`blank_border`, found when None) holding a line of text, as an
    ROV's video overlay prints its timestamp. A scene's own dark or light
    areas are not flat enough, not that wide at an edge, or hold no text.

    Examples
    --------
    >>> img = np.random.default_rng(0).uniform(60, 200, (160, 240)).astype(np.float32)
    >>> img[:14, :90] = 0                          # a black box in the top left corner ...
    >>> img[4:10, 5:85:6] = 230                    # ... with white text in it
    >>> caption_boxes(img)
    (Caption(side='top', x0=0, y0=0, x1=92, y1=16),)
    """
    h, w = image.shape[:2]
    x0, y0, x1, y1 = blank_border(image) if border is None else border
    t = CAPTION_TOUCH
    deep = min(t + int(CAPTION_HEIGHT * h) + 1, y1 - y0)
    # where a caption may lie: a band along the top or the bottom (most
    # overlays), or the rows beside a run of an edge's flat levels for one at
    # the left or right; each read only where the picture's outermost lines
    # hold such a run (a photo is read in these bands alone)
    edges = {"top": (x0, y0, x1, y0 + t + 1), "bottom": (x0, y1 - t - 1, x1, y1),
             "left": (x0, y0, x0 + t + 1, y1), "right": (x1 - t - 1, y0, x1, y1)}
    found = []
    for dark in (True, False):
        rows = []                                   # (first, end) rows to read
        for edge, (ex0, ey0, ex1, ey1) in edges.items():
            e = _grey(image[ey0:ey1, ex0:ex1])
            hit = (e <= CAPTION_DARK) if dark else (e >= CAPTION_LIGHT)
            along = hit.any(axis=0 if edge in ("top", "bottom") else 1)
            for a, b in _runs(along):
                if edge == "top" and b - a >= CAPTION_ASPECT * CAPTION_MIN_HEIGHT:
                    rows.append((y0, y0 + deep))
                elif edge == "bottom" and b - a >= CAPTION_ASPECT * CAPTION_MIN_HEIGHT:
                    rows.append((y1 - deep, y1))
                elif edge in ("left", "right") and CAPTION_MIN_HEIGHT <= b - a < deep:
                    rows.append((max(y0, ey0 + a - t - 1), min(y1, ey0 + b + t + 1)))
        for r0, r1 in _merged(rows):                # (each row read once)
            found += _captions_in(image, (x0, r0, x1, r1), (x0, y0, x1, y1), dark)
    return tuple(sorted(_joined(found, (x0, y0, x1, y1)), key=lambda c: (c.y0, c.x0)))


def _runs(flags: np.ndarray) -> list:
    """(start, end) of each run of True in a 1-D boolean array."""
    d = np.diff(np.r_[0, flags.astype(np.int8), 0])
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def _merged(spans: list) -> list:
    """Overlapping (start, end) spans joined, in order."""
    out: list = []
    for a, b in sorted(set(spans)):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def _side(x0: int, y0: int, x1: int, y1: int, border) -> str:
    """The edge of the picture ``border`` that a box (margins included)
    touches, the first of top, bottom, left, right; "" for none."""
    t = CAPTION_TOUCH - CAPTION_MARGIN           # (the box's own edge within CAPTION_TOUCH)
    bx0, by0, bx1, by1 = border
    return ("top" if y0 <= by0 + t else "bottom" if y1 >= by1 - t else
            "left" if x0 <= bx0 + t else "right" if x1 >= bx1 - t else "")


def _joined(caps: list, border) -> list:
    """Captions whose boxes (margins included) overlap, joined into one box,
    filled from the edge it touches: a two-line overlay's boxes are filled
    from beyond both, not one from the other."""
    boxes = _merged_boxes([(c.x0, c.y0, c.x1, c.y1) for c in caps], touching=False)
    return [Caption(_side(*b, border), *b) for b in boxes]


def _merged_boxes(boxes: list, touching: bool) -> list:
    """Boxes (x0, y0, x1, y1, end exclusive) that overlap (``touching``: or
    touch) joined into their bounding box, until none do."""
    boxes = list(dict.fromkeys(boxes))
    merged = True
    while merged:
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                a, b = boxes[i], boxes[j]
                over = ((a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3])
                        if touching else
                        (a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]))
                if over:
                    boxes[i] = (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]),
                                max(a[3], b[3]))
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    return boxes


def _captions_in(image: np.ndarray, region, border, dark: bool) -> list:
    """The captions of :func:`caption_boxes` (dark or light boxes) whose box
    lies in ``region`` (x0, y0, x1, y1) of the picture ``border``."""
    h, w = image.shape[:2]
    rx0, ry0, rx1, ry1 = region
    x0, y0, x1, y1 = border
    sub = _grey(image[ry0:ry1, rx0:rx1])
    mask = (sub <= CAPTION_DARK) if dark else (sub >= CAPTION_LIGHT)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=8)
    out = []
    m = CAPTION_MARGIN
    x_, y_, bw_, bh_, area_ = stats[1:].T.astype(np.int64)
    ok = ((area_ >= CAPTION_MIN_PIXELS) & (bw_ >= CAPTION_ASPECT * bh_)
          & (bh_ <= CAPTION_HEIGHT * h) & (bw_ * bh_ <= CAPTION_AREA * h * w)
          & (area_ > CAPTION_FILL * bw_ * bh_)
          & ~((y_ == 0) & (ry0 > y0)) & ~((y_ + bh_ == ry1) & (ry1 < y1)))  # (cut by a band)
    for i in np.flatnonzero(ok) + 1:
        x, y, bw, bh = (int(v) for v in stats[i, :4])
        box = sub[y:y + bh, x:x + bw]
        comp = labels[y:y + bh, x:x + bw] == i
        level = box[comp]
        mid = float(np.median(level))
        if np.mean(np.abs(level - mid) <= CAPTION_LEVELS) < CAPTION_FLAT:
            continue
        # the holes it encloses: what is not it and not reached from outside its box
        outside = np.pad(~comp, 1, constant_values=True).view(np.uint8)
        cv2.floodFill(outside, None, (0, 0), 2)
        holes = outside[1:-1, 1:-1] == 1
        if (comp | holes).mean() < CAPTION_SOLID:
            continue
        ink = ((box >= mid + CAPTION_INK) if dark else (box <= mid - CAPTION_INK)) & holes
        if ink.mean() < CAPTION_TEXT:
            continue
        x, y = x + rx0, y + ry0
        box = (max(x - m, x0), max(y - m, y0), min(x + bw + m, x1), min(y + bh + m, y1))
        side = _side(*box, border)
        if side:
            out.append(Caption(side, *box))
    return out


#: A flat black area joined to the picture's edge is no data when its levels
#: are at most this (0-255: JPEG's black is 0-3) ...
NO_DATA_LEVEL = 4.0
#: ... it holds this share of the picture, at least and at most (a drawn
#: shape's black canvas holds more: 83-94 %, and the segmentation masks of
#: ../shared/data 63-98 %; the fan of a forward-looking sonar about 40 %) ...
NO_DATA_SHARE = (0.02, 0.6)
#: ... the picture steps up from it by BLANK_STEP levels 3-5 px beyond it along
#: this share of its border (the dark water of the amphora wreck's corner
#: fades: 0-4 % of its border; a sonar's fan: 95-100 %) ...
NO_DATA_STEP = 0.75
#: ... and this share of the rest is texture (5x5 standard deviation of at
#: least 2 levels: a label mask's flat classes 2-3 %, a hazy pool 10 %,
#: sonar speckle and photos 50-100 %). Its pixels and NO_DATA_GROW px
#: beyond them (JPEG's smear of the step) are filled, as transparent ones
#: are (:func:`seahough.io.hidden.fill_hidden`).
NO_DATA_TEXTURE = 0.5
NO_DATA_GROW = 3
#: ... and it lies along the image's edge for at least this share of its
#: border with the picture (what lies beyond a picture: a fan's outside
#: 1.0, a turned photo's black corners over 1; a black cable or a shadow
#: running off the edge, which a reviewer saw filled: 0.03 and 0.14; a black
#: half-disc cut by the edge 0.64).
NO_DATA_CONTACT = 0.8


def no_data(gray: np.ndarray, border=None) -> np.ndarray | None:
    """The pixels of a flat black area beyond the picture (a boolean mask,
    or None): the outside of a forward-looking sonar's fan, a photo turned
    on a black canvas (a user trial: both sides of a sonar's fan "found" as
    lines at NFA 1e-12, the fan empty). ``gray``: levels 0-255; ``border``:
    its :func:`blank_border` (found when None), outside which it looks.

    >>> rng = np.random.default_rng(0)
    >>> img = rng.uniform(40, 200, (120, 160)).astype(np.float32)
    >>> yy, xx = np.mgrid[:120, :160]
    >>> img[np.abs(xx - 80) > 0.8 * (120 - yy)] = 0        # black beside a fan (apex down)
    >>> mask = no_data(img)
    >>> bool(mask[115, 5]), bool(mask[5, 80]), bool(mask[110, 80]), round(float(mask.mean()), 2)
    (True, False, False, 0.43)
    >>> no_data(np.zeros((120, 160), np.float32)) is None  # (all black: no picture)
    True
    """
    x0, y0, x1, y1 = blank_border(gray) if border is None else border
    p = _grey(gray)[y0:y1, x0:x1].astype(np.float32, copy=False)
    h, w = p.shape[:2]
    if h < 16 or w < 16 or min(p[0].min(), p[-1].min(), p[:, 0].min(),
                                p[:, -1].min()) > NO_DATA_LEVEL:
        return None      # (most frames: nothing black at the edge, nothing more to do)
    # (dark and flat: its 5x5 all at most NO_DATA_LEVEL; a 5x5 maximum, not the
    # standard deviation of every pixel: 18 ms a 968x608 photo with dark corners)
    dark = (cv2.dilate(p, np.ones((5, 5), np.uint8)) <= NO_DATA_LEVEL).view(np.uint8)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(dark, connectivity=4)
    contact = np.bincount(np.concatenate([lab[0], lab[-1], lab[:, 0], lab[:, -1]]), minlength=n)
    rim = (dark > 0) & (cv2.erode(dark, np.ones((3, 3), np.uint8),
                                  borderType=cv2.BORDER_REPLICATE) == 0)
    rim[[0, -1], :] = False
    rim[:, [0, -1]] = False
    keep = (stats[:, cv2.CC_STAT_AREA] >= NO_DATA_SHARE[0] * h * w) & (contact > 0) & (
        contact >= NO_DATA_CONTACT * np.bincount(lab[rim], minlength=n))
    keep[0] = False
    mask = keep[lab]
    if not mask.any() or mask.mean() > NO_DATA_SHARE[1]:
        return None
    grow = lambda r: cv2.dilate(mask.view(np.uint8), np.ones((2 * r + 1,) * 2, np.uint8)) > 0
    grown = grow(NO_DATA_GROW)
    ring = grow(NO_DATA_GROW + 2) & ~grow(2)   # (3-5 px beyond: the flat test's 5x5 left 2)
    ring[[0, -1], :] = False
    ring[:, [0, -1]] = False
    if not ring.any() or np.mean(p[ring] >= NO_DATA_LEVEL + BLANK_STEP) < NO_DATA_STEP:
        return None
    m = cv2.blur(p, (5, 5))       # (the rest's texture, last: the rarest test to reach)
    sd = np.sqrt(np.maximum(cv2.blur(p * p, (5, 5)) - m * m, 0.0))
    if np.mean(sd[~grown] >= 2.0) < NO_DATA_TEXTURE:
        return None
    out = np.zeros(gray.shape[:2], bool)
    out[y0:y1, x0:x1] = grown
    return out


def find_blanks(image: np.ndarray, ignore=()) -> Blanks:
    """The :class:`Blanks` of a frame (grey or colour, levels 0-255 as a
    search sees them: an image in other units, 16-bit levels or floats in
    0-1, is to be scaled to them first, :func:`seahough.io.images.to_gray`).

    >>> img = np.random.default_rng(0).uniform(60, 200, (60, 80)).astype(np.float32)
    >>> img[:, :6] = 0
    >>> find_blanks(img, ignore=[(20, 10, 40, 30), (40, 10, 50, 20)])
    Blanks(border=(8, 0, 80, 60), captions=(), ignored=((20, 10, 50, 30),))
    """
    if image.ndim == 3 and image.shape[2] in (3, 4):
        # (a colour frame's blanks are its grey copy's, as when it is searched in
        # grey: the mean of its channels left a letterbox bar's fade column in,
        # a "post" in a user trial's colour search)
        code = cv2.COLOR_BGR2GRAY if image.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
        image = cv2.cvtColor(np.ascontiguousarray(image, np.float32), code)
    border = blank_border(image)
    h, w = image.shape[:2]
    boxes = [b for b in ((max(x0, 0), max(y0, 0), min(x1, w), min(y1, h))
                         for x0, y0, x1, y1 in ignore) if b[0] < b[2] and b[1] < b[3]]
    # (regions that overlap or touch as one: each is filled from the lines around
    # it, which must not lie in another still to be filled)
    return Blanks(border, caption_boxes(image, border),
                  tuple(_merged_boxes(boxes, touching=True)), no_data(image, border))


def fill_blanks(image: np.ndarray, blanks: Blanks | None = None) -> np.ndarray:
    """``image`` with its :class:`Blanks` (found when None) filled from the
    picture beside them: a caption's box from the line just beyond it,
    repeated towards the edge it touches, then the blank border
    (:func:`fill_blank_border`). The same array when there is nothing to
    fill; else a copy.

    >>> img = np.random.default_rng(0).uniform(60, 200, (160, 240)).astype(np.float32)
    >>> img[:14, :90] = 0
    >>> img[4:10, 5:85:6] = 230
    >>> out = fill_blanks(img)
    >>> bool((out[:16, :92] == out[16, :92]).all()), bool((out[16:] == img[16:]).all())
    (True, True)
    """
    blanks = find_blanks(image) if blanks is None else blanks
    if blanks.ignored or blanks.captions or blanks.no_data is not None:
        image = image.copy()
    if blanks.no_data is not None:   # (first: the captions and regions are filled beside it)
        from ..io.hidden import fill_hidden

        image = fill_hidden(image.astype(np.float32, copy=False), blanks.no_data)
    bx0, by0, bx1, by1 = blanks.border
    # the regions to leave out first, within the picture (the bars are filled
    # after, from it): a caption beside one is then filled from its fill
    inner = image[by0:by1, bx0:bx1]
    for x0, y0, x1, y1 in blanks.ignored:
        x0, y0, x1, y1 = max(x0, bx0), max(y0, by0), min(x1, bx1), min(y1, by1)
        if x0 < x1 and y0 < y1:
            _fill_box(inner, (x0 - bx0, y0 - by0, x1 - bx0, y1 - by0))
    if blanks.captions:
        m = CHROMA_MARGIN if image.ndim == 3 else 0     # (a colour copy: its smear too)
        for c in blanks.captions:
            c = Caption(c.side, max(c.x0 - m, bx0), max(c.y0 - m, by0), min(c.x1 + m, bx1),
                        min(c.y1 + m, by1))
            if c.side == "top" and c.y1 < by1:
                image[by0:c.y1, c.x0:c.x1] = image[c.y1:c.y1 + 1, c.x0:c.x1]
            elif c.side == "bottom" and c.y0 > by0:
                image[c.y0:by1, c.x0:c.x1] = image[c.y0 - 1:c.y0, c.x0:c.x1]
            elif c.side == "left" and c.x1 < bx1:
                image[c.y0:c.y1, bx0:c.x1] = image[c.y0:c.y1, c.x1:c.x1 + 1]
            elif c.side == "right" and c.x0 > bx0:
                image[c.y0:c.y1, c.x0:bx1] = image[c.y0:c.y1, c.x0 - 1:c.x0]
    border = blanks.border
    if image.ndim == 3 and border != (0, 0) + image.shape[1::-1]:
        h, w = image.shape[:2]
        x0, y0, x1, y1 = border
        c = CHROMA_MARGIN
        border = (x0 + c if x0 else 0, y0 + c if y0 else 0, x1 - c if x1 < w else w,
                  y1 - c if y1 < h else h)
    return fill_blank_border(image, border)


#: Gaussian sigma (px) along the lines around an ignored region before they
#: are spread across it: a side's texture copied unsmoothed across a region
#: a hundred pixels deep ran as long straight streaks, "posts" to a line search
#: (found in a test on a RoboSub frame's picture-in-picture inset)
FILL_SMOOTH = 4.0


def _fill_box(image: np.ndarray, box) -> None:
    """Fill ``box`` (x0, y0, x1, y1) of ``image`` in place from the lines
    around it, smoothly: a Coons patch (the blend across from the columns at
    its left and right, plus the blend down from the rows above and below
    it, less the blend of its corners, the ends of those lines), so that no
    side of it is a step. A side at the image's edge is the straight blend
    of its two corners (a corner with neither line beside it: the mean of
    its neighbours); nothing around it at all: the box's own median, flat."""
    x0, y0, x1, y1 = box
    h, w = image.shape[:2]
    n, m = x1 - x0, y1 - y0
    f = image.astype(np.float32, copy=False)
    extra = image.shape[2:]                        # () grey, (C,) colour

    def line(a):   # a side's line, smoothed along it: its texture would run across as streaks
        a = np.ascontiguousarray(a, np.float32).reshape(1, a.shape[0], -1)
        out = cv2.GaussianBlur(a, (0, 0), sigmaX=FILL_SMOOTH, sigmaY=0.01,
                               borderType=cv2.BORDER_REPLICATE)
        return out.reshape((a.shape[1],) + extra)

    left = line(f[y0:y1, x0 - 1]) if x0 > 0 else None
    right = line(f[y0:y1, x1]) if x1 < w else None
    top = line(f[y0 - 1, x0:x1]) if y0 > 0 else None
    bottom = line(f[y1, x0:x1]) if y1 < h else None
    if left is None and right is None and top is None and bottom is None:
        image[y0:y1, x0:x1] = np.median(f[y0:y1, x0:x1].reshape((-1,) + extra),
                                        axis=0).astype(image.dtype)
        return

    def mean(*vals):
        vals = [v for v in vals if v is not None]
        return sum(vals) / len(vals) if vals else None

    cs = [mean(None if top is None else top[0], None if left is None else left[0]),
          mean(None if top is None else top[-1], None if right is None else right[0]),
          mean(None if bottom is None else bottom[0], None if left is None else left[-1]),
          mean(None if bottom is None else bottom[-1], None if right is None else right[-1])]
    for k, (a, b) in enumerate(((1, 2), (0, 3), (0, 3), (1, 2))):   # (a corner of the image)
        if cs[k] is None:
            cs[k] = mean(cs[a], cs[b])
    known = [c for c in cs if c is not None]
    c00, c10, c01, c11 = (c if c is not None else mean(*known) for c in cs)
    u = ((np.arange(n, dtype=np.float32) + 1) / (n + 1)).reshape((1, n) + (1,) * len(extra))
    v = ((np.arange(m, dtype=np.float32) + 1) / (m + 1)).reshape((m, 1) + (1,) * len(extra))
    uu, vv = u[0], v[:, 0]
    top = (1 - uu) * c00 + uu * c10 if top is None else top
    bottom = (1 - uu) * c01 + uu * c11 if bottom is None else bottom
    left = (1 - vv) * c00 + vv * c01 if left is None else left
    right = (1 - vv) * c10 + vv * c11 if right is None else right
    patch = ((1 - u) * left[:, None] + u * right[:, None] + (1 - v) * top[None, :]
             + v * bottom[None, :]
             - ((1 - u) * (1 - v) * c00 + u * (1 - v) * c10 + (1 - u) * v * c01 + u * v * c11))
    if np.issubdtype(image.dtype, np.integer):
        info = np.iinfo(image.dtype)
        patch = np.clip(np.rint(patch), info.min, info.max)
    image[y0:y1, x0:x1] = patch.astype(image.dtype)
